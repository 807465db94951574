//! A clip's count tempo (spec §E revised): one that its motion supports across the whole clip.
//! Two recordings of the same dance to the same music — the CMU salsa partners salsa_01/16 and
//! salsa_10/25 in ../shared/data — must be cut at tempos within 3 % of each other. Every other
//! real dance clip (salsa, Indian, modern, martial) is cut too and its tempo printed, so a
//! change that helps the pairs and breaks the rest shows; each must lie in the counting range
//! 60..=150 per minute and hold at least one 4-count segment.
//!
//! Ignored for now: it fails on salsa_10/25 (79.5 vs 124.1), the open acceptance item; run it
//! with `--ignored` to see every clip's tempo. What was found: the whole-body joint speed of
//! salsa_01, salsa_16 and salsa_25 has no periodicity at all between 3 and 130 frames (its
//! autocorrelation, slow trend removed, falls steadily from lag 3), so `detect_beats` finds no
//! peak and falls back to 15 frames, and the parabolic refinement on that slope moves it to
//! 15.5 or 14.5 frames: their 116.1 and 124.1 are the fallback, not a detection (so are the many
//! 116.1 / 124.1 tempos of the modern-dance clips), and salsa_01/16 "agree" by falling back
//! alike. Only salsa_10 has a peak (23 frames, 79.5 per minute). Two rules were tried and
//! dropped: a comb of the autocorrelation over 8 s choosing among the range (all supports are
//! at noise level on these clips) and a kinetic-beat grid scored against its half-count shift
//! (free over the range it wanders: salsa_01/16 at 82 vs 63.5).

use odori_core::choreo::{SegmentLibrary, SegmentOptions};
use odori_core::import::import_bytes;
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
#[ignore = "open (issue #15): salsa_10/salsa_25 are cut at 79.5 and 124.1 counts per minute; run with --ignored"]
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
