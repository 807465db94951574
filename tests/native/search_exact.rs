//! Exactness: the fast search returns the same matches and distances as a plain reference DP
//! (written in the test from spec §C) and as the core's own plain DP, on random motion and on
//! real clips.

#[path = "search_common.rs"]
mod common;

use common::{reference_search, Rng};
use odori_core::humanoid::CANON_COUNT;
use odori_core::normalize::Origin;
use odori_core::search::{
    no_progress, search, search_plain, BodyPreset, ClipFeatures, FeatureIndex, MotionFeatures, SearchOutcome, SearchParams, FRAME_FLOATS,
};

/// Smooth random motion: each coordinate a sum of three sinusoids plus a slow random walk.
fn random_motion(rng: &mut Rng, frames: usize) -> Vec<f32> {
    let mut data = vec![0f32; frames * FRAME_FLOATS];
    for c in 0..FRAME_FLOATS {
        let waves: Vec<(f32, f32, f32)> = (0..3).map(|_| (rng.range(0.02, 0.4), rng.range(0.0, 6.28), rng.range(0.02, 0.3))).collect();
        let mut walk = 0.0f32;
        for f in 0..frames {
            walk += 0.01 * rng.normal();
            data[f * FRAME_FLOATS + c] = waves.iter().map(|(w, p, a)| a * (w * f as f32 + p).sin()).sum::<f32>() + walk;
        }
    }
    data
}

fn features(name: &str, data: Vec<f32>) -> ClipFeatures {
    ClipFeatures::new(name, 60.0, MotionFeatures { origin: Origin::Hips, data })
}

/// A query cut from `src` at `start`, time-warped by a random speed in [0.8, 1.25] and noised.
fn warped_query(rng: &mut Rng, src: &[f32], start: usize, frames: usize) -> Vec<f32> {
    let speed = rng.range(0.8, 1.25);
    let src_frames = src.len() / FRAME_FLOATS;
    let mut out = Vec::with_capacity(frames * FRAME_FLOATS);
    for f in 0..frames {
        let x = (start as f32 + f as f32 * speed).min((src_frames - 1) as f32);
        let (f0, a) = (x.floor() as usize, x.fract());
        let f1 = (f0 + 1).min(src_frames - 1);
        for c in 0..FRAME_FLOATS {
            let v = src[f0 * FRAME_FLOATS + c] * (1.0 - a) + src[f1 * FRAME_FLOATS + c] * a;
            out.push(v + 0.02 * rng.normal());
        }
    }
    out
}

fn assert_same(what: &str, fast: &SearchOutcome, reference: &[common::RefMatch], (query, index, params): (&ClipFeatures, &FeatureIndex, &SearchParams)) {
    let got: Vec<(usize, usize, usize)> = fast.matches.iter().map(|m| (m.clip_index, m.start_frame, m.end_frame)).collect();
    let want: Vec<(usize, usize, usize)> = reference.iter().map(|r| (r.0, r.1, r.2)).collect();
    assert_eq!(got, want, "{what}: matches differ");
    for (m, r) in fast.matches.iter().zip(reference) {
        assert!((m.distance - r.3).abs() <= 1e-5 * r.3.abs().max(1.0), "{what}: distance {} vs reference {}", m.distance, r.3);
        // The warping path runs from (0, start) to (last, end) in unit steps.
        let first = m.path.first().copied().unwrap_or([9, 9]);
        let last = m.path.last().copied().unwrap_or([9, 9]);
        assert_eq!(first, [0, m.start_frame as u32], "{what}: path start");
        assert_eq!(last[1], m.end_frame as u32, "{what}: path end");
        for w in m.path.windows(2) {
            let (di, dj) = (w[1][0] - w[0][0], w[1][1] - w[0][1]);
            assert!(di <= 1 && dj <= 1 && di + dj >= 1, "{what}: bad step {w:?}");
        }
        // The path's own cost (step weights 1/2/1) is the match's cost and distance.
        {
            let (q, t) = (&query.features(params.origin).data, &index.clips[m.clip_index].features(params.origin).data);
            let d = |p: [u32; 2]| {
                let (i, j) = (p[0] as usize, p[1] as usize);
                common::ref_distance(params, &q[i * FRAME_FLOATS..(i + 1) * FRAME_FLOATS], &t[j * FRAME_FLOATS..(j + 1) * FRAME_FLOATS])
            };
            let mut cost = d(m.path[0]);
            for w in m.path.windows(2) {
                let diag = w[1][0] != w[0][0] && w[1][1] != w[0][1];
                cost += if diag { 2.0 } else { 1.0 } * d(w[1]);
            }
            assert_eq!(last[0] as usize + 1, q.len() / FRAME_FLOATS, "{what}: path ends on the last query frame");
            assert!((cost - m.cost).abs() <= 1e-4 * m.cost.max(1.0), "{what}: path cost {cost} vs match cost {}", m.cost);
            let norm = cost / (q.len() / FRAME_FLOATS + m.length_frames) as f32;
            assert!((norm - m.distance).abs() <= 1e-4 * m.distance.max(1.0), "{what}: path distance {norm} vs {}", m.distance);
        }
    }
}

fn random_params(rng: &mut Rng, round: usize) -> SearchParams {
    let preset = BodyPreset::ALL[round % BodyPreset::ALL.len()];
    let mut p = SearchParams::preset(preset);
    p.max_results = [1, 3, 10, 40][rng.usize(4)];
    if round % 5 == 4 {
        // Random per-joint weights, some zero.
        for w in p.weights.iter_mut() {
            *w = if rng.f32() < 0.3 { 0.0 } else { rng.range(0.1, 3.0) };
        }
        p.weights[rng.usize(CANON_COUNT)] = 1.0;
    }
    if round % 3 == 1 {
        p.min_span_ratio = rng.range(0.3, 1.0);
        p.max_span_ratio = rng.range(1.0, 3.0);
    }
    if round % 7 == 2 {
        // Tight span bounds: many best paths are cut, which is where a pruned scan could
        // report a path the full DP never chose.
        p.min_span_ratio = 0.9;
        p.max_span_ratio = 1.1;
    }
    p
}

#[test]
fn fast_equals_reference_on_random_motion() {
    let mut rng = Rng(0x5EED_0003);
    let mut clips: Vec<Vec<f32>> = (0..4).map(|k| random_motion(&mut rng, 250 + 120 * k)).collect();
    // Repetitive motion, like a dance's repeated step: one 40-frame phrase played over and over
    // at varying speeds. Many near-equal paths compete here, and many best paths are too long
    // or too short to report, which is where a pruned scan is most likely to go wrong.
    for _ in 0..2 {
        let phrase = random_motion(&mut rng, 40);
        let mut data = Vec::new();
        for _ in 0..12 {
            let frames = 30 + rng.usize(20);
            data.extend(warped_query(&mut rng, &phrase, 0, frames));
        }
        clips.push(data);
    }
    let mut index = FeatureIndex::new();
    for (k, c) in clips.iter().enumerate() {
        index.add_features(features(&format!("random{k}"), c.clone()));
    }
    let mut rescans = 0;
    for round in 0..80 {
        let rows = 12 + rng.usize(30);
        let src = rng.usize(clips.len());
        let data = if round % 4 == 3 {
            random_motion(&mut rng, rows) // unrelated motion
        } else {
            let start = rng.usize(clips[src].len() / FRAME_FLOATS - 2 * rows);
            warped_query(&mut rng, &clips[src], start, rows)
        };
        let query = features("query", data);
        let mut params = random_params(&mut rng, round);
        let reference_all = reference_search(&index, &query, &params);
        if round % 2 == 1 {
            // A threshold between the best distances, so it bites.
            if let Some(r) = reference_all.get(reference_all.len() / 2) {
                params.threshold = Some(r.3);
            }
        }
        let reference = reference_search(&index, &query, &params);
        let fast = search(&index, &query, &params, &mut no_progress()).unwrap();
        let plain = search_plain(&index, &query, &params, &mut no_progress()).unwrap();
        let what = format!("round {round} ({rows} frames, {params:?})");
        assert_same(&format!("fast, {what}"), &fast, &reference, (&query, &index, &params));
        assert_same(&format!("plain, {what}"), &plain, &reference, (&query, &index, &params));
        if round % 4 != 3 {
            assert!(!reference.is_empty(), "{what}: a query cut from the library should match");
        }
        rescans += fast.stats.rescanned as usize;
    }
    println!("random exactness: 80 rounds, {rescans} rescans");
}
