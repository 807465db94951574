//! Report (issue 17: a report-only test moved to a benchmark, because no claim rests on it): does
//! a stretch of one salsa dancer find the *partner's* same stretch (CMU subject 60/61 pairs, who
//! danced together)? For each 3-s query every 5 s of one partner's clip, the top 3 of the whole
//! real library without the query's own clip is checked for the other partner's clip starting
//! within 0.25 s / 1 s of the query's time; also with the query mirrored, and with feet only. Next
//! to each hit count it prints the count expected by chance (three starts placed at random over
//! the admissible starts), so the figure reads against a control. Measured so far: the partner's
//! same stretch is not found above chance — leader and follower do complementary, not equal,
//! steps — which is why this is a report and not a test.
//! Run: `cargo bench -p odori-tests --bench salsa_partners`.

#[path = "../native/search_common.rs"]
mod common;

use common::mirrored;
use odori_core::canon::normalize::Origin;
use odori_core::search::{no_progress, search, BodyPreset, ClipFeatures, FeatureIndex, SearchParams};

fn main() {
    let real = common::real_index();
    assert!(real.clips.len() >= 10, "expected the CMU salsa, Indian and martial clips of ../shared/data/mocap to be searchable: {:?}", real.skipped);
    let find = |name: &str| real.clips.iter().position(|c| c.name.contains(name)).unwrap_or_else(|| panic!("{name} not indexed (is ../shared/data/mocap there?)"));
    let pairs = [("salsa_01", "salsa_16"), ("salsa_16", "salsa_01"), ("salsa_10", "salsa_25"), ("salsa_25", "salsa_10")];
    let variants: [(&str, BodyPreset, u8); 3] = [
        ("whole body", BodyPreset::WholeBody, 0),
        ("whole body, query mirrored left/right and front/back", BodyPreset::WholeBody, 2),
        ("feet only", BodyPreset::FeetOnly, 0),
    ];
    const TOLS: [f32; 2] = [0.25, 1.0];
    // (hits within each tolerance, chance within each tolerance, queries)
    let mut totals = vec![([0usize; 2], [0f64; 2], 0usize); variants.len()];
    let mut alone = ([0usize; 2], [0f64; 2], 0usize);
    // Chance that one of `k` starts drawn at random over `starts` admissible starts of the
    // partner's clip lies within `tol` seconds of the query's start.
    let chance = |k: usize, starts: usize, tol: f32, fps: f32, in_library_frames: usize, partner_frames: usize| -> f64 {
        let window = (2.0 * tol * fps + 1.0) as f64;
        let p_one = (window / starts.max(1) as f64).min(1.0) * (partner_frames as f64 / in_library_frames.max(1) as f64);
        1.0 - (1.0 - p_one).powi(k as i32)
    };
    for (from, to) in pairs {
        let (a, b) = (find(from), find(to));
        let mut lib = FeatureIndex::new();
        let mut b_in_lib = 0;
        for (k, c) in real.clips.iter().enumerate() {
            if k != a {
                if k == b {
                    b_in_lib = lib.clips.len();
                }
                lib.add_features(c.clone());
            }
        }
        let src = &real.clips[a];
        let fps = src.fps;
        let len = (3.0 * fps) as usize;
        let step = (5.0 * fps) as usize;
        let partner_frames = real.clips[b].frame_count();
        let lib_frames = lib.total_frames();
        let mut partner_only = FeatureIndex::new();
        partner_only.add_features(real.clips[b].clone());
        let params3 = SearchParams { max_results: 3, ..SearchParams::preset(BodyPreset::WholeBody) };
        let mut start = 0;
        while start + len <= src.frame_count().min(partner_frames) {
            let q = src.slice(start, start + len).expect("slice");
            let out = search(&partner_only, &q, &params3, &mut no_progress()).expect("search");
            for (t, tol) in TOLS.iter().enumerate() {
                alone.0[t] += out.matches.iter().any(|m| m.start_frame.abs_diff(start) as f32 <= tol * fps) as usize;
                alone.1[t] += chance(3, partner_frames - len / 2, *tol, fps, partner_frames, partner_frames);
            }
            alone.2 += 1;
            start += step;
        }
        for (vi, (_, preset, mirror)) in variants.iter().enumerate() {
            let params = SearchParams { max_results: 3, ..SearchParams::preset(*preset) };
            let mut start = 0;
            while start + len <= src.frame_count().min(partner_frames) {
                let q = src.slice(start, start + len).expect("slice");
                let q = match mirror {
                    0 => q,
                    m => ClipFeatures::new("mirrored", fps, mirrored(q.features(Origin::Hips), *m == 2)),
                };
                let out = search(&lib, &q, &params, &mut no_progress()).expect("search");
                for (t, tol) in TOLS.iter().enumerate() {
                    totals[vi].0[t] += out.matches.iter().any(|m| m.clip_index == b_in_lib && m.start_frame.abs_diff(start) as f32 <= tol * fps) as usize;
                    totals[vi].1[t] += chance(3, partner_frames - len / 2, *tol, fps, lib_frames, partner_frames);
                }
                totals[vi].2 += 1;
                start += step;
            }
        }
    }
    let line = |name: &str, (hits, chance, n): &([usize; 2], [f64; 2], usize)| {
        println!(
            "salsa partners, {name}: partner's same stretch in top 3: {}/{n} within 0.25 s (chance {:.1}), {}/{n} within 1 s (chance {:.1})",
            hits[0], chance[0], hits[1], chance[1]
        );
    };
    line("whole body, library = the partner's clip only", &alone);
    for ((name, _, _), t) in variants.iter().zip(&totals) {
        line(name, t);
    }
}
