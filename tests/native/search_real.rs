//! Search by example on real mocap (issue 3 acceptance): invariance to speed, facing, position,
//! body size and noise; the body-parts finding of seed 002 §4.3; and
//! exactness of the fast search against the reference DP on real clips. (The salsa partner
//! report is a benchmark, `bench/salsa_partners.rs`: no claim rests on it.)

#[path = "search_common.rs"]
mod common;

use std::sync::OnceLock;

use common::{reference_search, Rng};
use glam::{Quat, Vec3};
use odori_core::canon::humanoid::{canonical_positions, Canon, CANON_COUNT};
use odori_core::canon::normalize::Origin;
use odori_core::search::{no_progress, search, BodyPreset, ClipFeatures, FeatureIndex, MotionFeatures, SearchParams, FRAME_FLOATS};

struct Real {
    index: FeatureIndex,
    /// Canonical world positions per indexed clip (same order as `index.clips`).
    positions: Vec<Vec<Vec3>>,
}

fn real() -> &'static Real {
    static REAL: OnceLock<Real> = OnceLock::new();
    REAL.get_or_init(|| {
        let mut index = FeatureIndex::new();
        let mut positions = Vec::new();
        for (rel, clip, map, status) in common::real_clips() {
            if index.add_clip(rel, &clip, &map, &status).is_ok() {
                positions.push(canonical_positions(&index.resampled(&clip), &map));
            }
        }
        assert!(index.clips.len() >= 10, "expected the CMU salsa, Indian and martial clips to be searchable: {:?}", index.skipped);
        Real { index, positions }
    })
}

/// Cuts `out_frames` frames from `src` (frames × 21 positions) starting at `start`, played with
/// a speed that varies smoothly between 0.8× and 1.25×; then turns, shifts, scales and noises
/// the result. Returns the positions and the source frames covered.
fn transformed_query(rng: &mut Rng, src: &[Vec3], start: usize, out_frames: usize) -> (Vec<Vec3>, f32) {
    let src_frames = src.len() / CANON_COUNT;
    let (lo, hi) = (0.8f32.ln(), 1.25f32.ln());
    let (omega, phase) = (rng.range(0.02, 0.08), rng.range(0.0, 6.28));
    let yaw = rng.range(-std::f32::consts::PI, std::f32::consts::PI);
    let rot = Quat::from_rotation_y(yaw);
    let shift = Vec3::new(rng.range(-3.0, 3.0), 0.0, rng.range(-3.0, 3.0));
    let scale = rng.range(0.85, 1.15);
    let mut out = Vec::with_capacity(out_frames * CANON_COUNT);
    let mut x = start as f32;
    for k in 0..out_frames {
        let (f0, a) = (x.floor() as usize, x.fract());
        let f0 = f0.min(src_frames - 1);
        let f1 = (f0 + 1).min(src_frames - 1);
        for j in 0..CANON_COUNT {
            let p = src[f0 * CANON_COUNT + j].lerp(src[f1 * CANON_COUNT + j], a);
            let noise = Vec3::new(rng.normal(), rng.normal(), rng.normal()) * 0.005;
            out.push(rot * (p * scale) + shift + noise);
        }
        let speed = (lo + (hi - lo) * (0.5 + 0.5 * (omega * k as f32 + phase).sin())).exp();
        x += speed;
    }
    (out, x - start as f32)
}

/// Top-1 hit rate of transformed queries for a preset.
fn hit_rate(preset: BodyPreset, queries: &[(usize, usize, ClipFeatures)]) -> (usize, usize) {
    let r = real();
    let params = SearchParams { max_results: 1, ..SearchParams::preset(preset) };
    let mut hits = 0;
    for (clip, start, q) in queries {
        let out = search(&r.index, q, &params, &mut no_progress()).expect("search");
        let tol = (0.25 * r.index.clips[*clip].fps).round() as usize;
        match out.matches.first() {
            Some(m) if m.clip_index == *clip && m.start_frame.abs_diff(*start) <= tol => hits += 1,
            m => println!(
                "  miss ({preset:?}): cut at {} frame {start} ({} frames); best {:?}",
                r.index.clips[*clip].name,
                q.frame_count(),
                m.map(|m| (&m.clip_name, m.start_frame, m.end_frame, m.distance))
            ),
        }
    }
    (hits, queries.len())
}

#[test]
fn invariance_to_speed_facing_position_size_and_noise() {
    let r = real();
    let mut rng = Rng(0x1_2025_0003);
    let mut queries = Vec::new();
    // Every real clip in turn (four queries each where it is long enough), not a random pick.
    let mut tries = 0;
    while tries < 8 * r.index.clips.len() && queries.len() < 4 * r.index.clips.len() {
        let clip = tries % r.index.clips.len();
        tries += 1;
        let c = &r.index.clips[clip];
        let fps = c.fps;
        let out_frames = (rng.range(2.0, 4.0) * fps) as usize;
        // Source frames needed at the slowest (1.25×) speed, plus a margin.
        let need = (out_frames as f32 * 1.25) as usize + 2;
        if c.frame_count() <= need + 1 {
            continue;
        }
        let start = rng.usize(c.frame_count() - need);
        let (pos, _) = transformed_query(&mut rng, &r.positions[clip], start, out_frames);
        queries.push((clip, start, ClipFeatures::new("query", fps, MotionFeatures::from_positions(&pos))));
    }
    let mut rates = Vec::new();
    for preset in [BodyPreset::WholeBody, BodyPreset::FeetOnly, BodyPreset::Arms] {
        let (hits, n) = hit_rate(preset, &queries);
        println!("invariance, {preset:?}: top-1 hit {hits}/{n} = {:.1}%", 100.0 * hits as f32 / n as f32);
        rates.push((preset, hits as f32 / n as f32));
    }
    // Issue 16's goals: 95 % top-1 for the whole body, 90 % for feet only and arms.
    let clips_used: std::collections::BTreeSet<usize> = queries.iter().map(|q| q.0).collect();
    println!("invariance: {} queries from {} of {} clips", queries.len(), clips_used.len(), r.index.clips.len());
    for (preset, rate) in rates {
        let goal = if preset == BodyPreset::WholeBody { 0.95 } else { 0.9 };
        assert!(rate >= goal, "{preset:?}: top-1 hit rate {:.1}% is below the {:.0}% goal", 100.0 * rate, 100.0 * goal);
    }
}

#[test]
fn legs_from_one_motion_arms_from_another() {
    let r = real();
    let find = |name: &str| r.index.clips.iter().position(|c| c.name.contains(name)).unwrap_or_else(|| panic!("{name} not indexed"));
    let (legs_clip, arms_clip) = (find("salsa_02"), find("indian_04"));
    let len = 180;
    let (legs_at, arms_at) = (900, 600);
    let legs = r.index.clips[legs_clip].features(Origin::Hips);
    let arms = r.index.clips[arms_clip].features(Origin::Hips);
    let lower = BodyPreset::LowerBody.joints();
    let mut data = Vec::with_capacity(len * FRAME_FLOATS);
    for f in 0..len {
        let (l, a) = (legs.frame(legs_at + f), arms.frame(arms_at + f));
        for c in Canon::ALL {
            let src = if lower.contains(&c) { l } else { a };
            data.extend_from_slice(&src[c.index() * 3..c.index() * 3 + 3]);
        }
    }
    let query = ClipFeatures::new("legs of salsa_02, arms of indian_04", 60.0, MotionFeatures { origin: Origin::Hips, data });
    let is_legs_source = |m: &odori_core::search::SearchMatch| m.clip_index == legs_clip && m.start_frame.abs_diff(legs_at) <= 15;
    let feet = search(&r.index, &query, &SearchParams::preset(BodyPreset::FeetOnly), &mut no_progress()).expect("search");
    let whole = search(&r.index, &query, &SearchParams::preset(BodyPreset::WholeBody), &mut no_progress()).expect("search");
    let show = |o: &odori_core::search::SearchOutcome| {
        o.matches.iter().take(3).map(|m| format!("{} {}..={} d={:.3}", m.clip_name, m.start_frame, m.end_frame, m.distance)).collect::<Vec<_>>()
    };
    println!("body parts, feet only: {:?}", show(&feet));
    println!("body parts, whole body: {:?}", show(&whole));
    assert!(feet.matches.first().is_some_and(is_legs_source), "feet only should rank the leg source first: {:?}", show(&feet));
    // Seed 002 §4.3: over the whole body the foot motion is lost among the rest. Under the
    // revised §C rule the leg source still ranks first by a small margin (1.17 vs 1.22 here),
    // so what is checked is that it does not stand out: the arms' source ranks beside it in
    // the top 3, and the leg source is far from the near-zero distance feet only gives it.
    let is_arms_source = |m: &odori_core::search::SearchMatch| m.clip_index == arms_clip && m.start_frame.abs_diff(arms_at) <= 15;
    assert!(whole.matches.iter().take(3).any(is_arms_source), "whole body should see the arms' source too: {:?}", show(&whole));
    let feet_d = feet.matches.first().map_or(f32::INFINITY, |m| m.distance);
    let whole_legs = whole.matches.iter().find(|m| is_legs_source(m)).map_or(f32::INFINITY, |m| m.distance);
    assert!(feet_d < 0.1 * whole_legs.max(1e-3), "feet only {feet_d} should find the leg source far closer than the whole body {whole_legs}");
}

#[test]
fn fast_equals_reference_on_real_clips() {
    let r = real();
    // A small library of real clips (the reference keeps whole matrices) and queries cut from
    // them, transformed, with several presets.
    let mut lib = FeatureIndex::new();
    for c in r.index.clips.iter().take(4) {
        lib.add_features(c.slice(0, c.frame_count().min(1500)).expect("slice"));
    }
    let mut rng = Rng(77);
    for round in 0..8 {
        let clip = round % lib.clips.len();
        let src = &r.positions[clip];
        let start = 100 + rng.usize(1000);
        let frames = 60 + rng.usize(60);
        let (pos, _) = transformed_query(&mut rng, src, start, frames);
        let q = ClipFeatures::new("q", 60.0, MotionFeatures::from_positions(&pos));
        let preset = [BodyPreset::WholeBody, BodyPreset::FeetOnly, BodyPreset::Arms, BodyPreset::LeftArm][round % 4];
        let mut params = SearchParams { max_results: [1, 5, 20][round % 3], ..SearchParams::preset(preset) };
        if round % 2 == 1 {
            params.threshold = Some(0.5);
        }
        let want = reference_search(&lib, &q, &params);
        let got = search(&lib, &q, &params, &mut no_progress()).expect("search");
        let g: Vec<_> = got.matches.iter().map(|m| (m.clip_index, m.start_frame, m.end_frame)).collect();
        let w: Vec<_> = want.iter().map(|m| (m.0, m.1, m.2)).collect();
        assert_eq!(g, w, "round {round} {preset:?}");
        for (m, x) in got.matches.iter().zip(&want) {
            assert!((m.distance - x.3).abs() <= 1e-5 * x.3.max(1.0), "round {round}: {} vs {}", m.distance, x.3);
        }
    }
}
