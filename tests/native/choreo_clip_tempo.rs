//! A clip's count tempo (spec §E revised): one that its motion supports across the whole clip.
//! Two recordings of the same dance to the same music — the CMU salsa partners salsa_01/16 and
//! salsa_10/25 in ../shared/data — must be cut at tempos within 3 % of each other. Every other
//! real dance clip (salsa, Indian, modern, martial) is cut too and its tempo printed, so a
//! change that helps the pairs and breaks the rest shows; each must lie in the counting range
//! 60..=150 per minute and hold at least one 4-count segment.
//!
//! The tempo is the period that the speed curves of the feet, whole body, hands and hips
//! support together at 1, 2 and 4 counts (`clip_count_period`). Before it, the whole-body speed
//! alone gave 116.1 / 116.1 and 79.5 / 124.1 (three of the four takes had no periodicity there:
//! a fallback, not a detection). What this test does not show, printed as a diagnostic: on
//! halves and thirds of the takes, salsa_01/16 still agree within about 4 %, but salsa_10/25
//! do not (salsa_25's feet quicken to a period near 19 frames in its second half while
//! salsa_10's stay near 21–22), so the 10/25 agreement on the whole take has little margin.

use odori_core::choreo::segment::clip_count_period;
use odori_core::choreo::{SegmentLibrary, SegmentOptions, LIBRARY_FPS};
use odori_core::import::import_bytes;
use odori_core::canon::retarget::to_canonical;
use odori_core::ImportOptions;
use odori_tests::{all_bvh, fps_override_for, read};

/// Every real BVH cut at its detected tempo: (file, counts per minute).
fn cut_tempos() -> Vec<(String, f32)> {
    let mut out = Vec::new();
    for rel in all_bvh() {
        let opts = ImportOptions { fps_override: fps_override_for(&rel), ..Default::default() };
        let imp = import_bytes(&rel, &read(&rel), &opts).unwrap_or_else(|e| panic!("{rel}: {e}"));
        for clip in &imp.clips {
            let mut lib = SegmentLibrary::new();
            let summary = lib.add_clip(clip, &imp.humanoid, &imp.status, &SegmentOptions::default()).unwrap_or_else(|e| panic!("{rel}: {e}"));
            assert!(summary.segments >= 1, "{rel}: no segment");
            out.push((rel.clone(), summary.tempo_bpm));
        }
    }
    out
}

#[test]
fn salsa_partners_get_the_same_tempo_and_every_clip_a_counting_tempo() {
    let tempos = cut_tempos();
    for (rel, bpm) in &tempos {
        println!("  {rel}: {bpm:.1} counts/min");
    }
    for (rel, bpm) in &tempos {
        assert!((60.0..=150.5).contains(bpm), "{rel}: {bpm:.1} counts per minute is outside 60..=150");
    }
    let of = |name: &str| tempos.iter().find(|(r, _)| r.contains(name)).map(|(_, b)| *b).unwrap_or_else(|| panic!("{name} is missing from ../shared/data/mocap/cmu-salsa"));
    for (a, b) in [("salsa_01", "salsa_16"), ("salsa_10", "salsa_25")] {
        let (ta, tb) = (of(a), of(b));
        let ratio = ta.max(tb) / ta.min(tb);
        println!("  partners {a}/{b}: {ta:.1} vs {tb:.1} counts/min (ratio {ratio:.3})");
        assert!(ratio <= 1.03, "partners {a} and {b} cut at {ta:.1} and {tb:.1} counts per minute: more than 3 % apart");
    }
}


/// Not asserted (see the module note): each partner take's tempo on excerpts (halves, middle
/// half, first and last two thirds), so how far the agreement holds is printed with every run.
#[test]
fn partner_tempos_on_excerpts_are_printed() {
    for (a, b) in [("salsa_01", "salsa_16"), ("salsa_10", "salsa_25")] {
        let tempos = |name: &str| -> Vec<f32> {
            let rel = format!("mocap/cmu-salsa/{name}.bvh");
            let opts = ImportOptions { fps_override: fps_override_for(&rel), ..Default::default() };
            let imp = import_bytes(&rel, &read(&rel), &opts).unwrap_or_else(|e| panic!("{rel}: {e}"));
            let canon = to_canonical(&imp.clips[0], &imp.humanoid, LIBRARY_FPS);
            let n = canon.frame_count();
            [(0, n / 2), (n / 2, n), (n / 4, 3 * n / 4), (0, 2 * n / 3), (n / 3, n)]
                .iter()
                .map(|&(s, e)| clip_count_period(&canon.slice(s, e, "excerpt")).map_or(f32::NAN, |(p, _)| LIBRARY_FPS * 60.0 / p))
                .collect()
        };
        let (ta, tb) = (tempos(a), tempos(b));
        let ratios: Vec<String> = ta.iter().zip(&tb).map(|(x, y)| format!("{x:.1}/{y:.1} ({:.3})", x.max(*y) / x.min(*y))).collect();
        println!("  {a}/{b} excerpts (first half, second half, middle half, first 2/3, last 2/3): {}", ratios.join(", "));
        assert!(ta.iter().chain(&tb).all(|t| t.is_nan() || (60.0..=150.5).contains(t)), "an excerpt tempo is outside 60..=150");
    }
}
