//! Bad input to the search: clear typed errors with the offending values, never a panic; and
//! progress reports with cancel.

use std::ops::ControlFlow;

use odori_core::canon::builtin::demo_clip;
use odori_core::canon::humanoid::HumanoidMap;
use odori_core::import::{import_bytes, ImportOptions};
use odori_core::canon::normalize::Origin;
use odori_core::search::{
    no_progress, search, search_plain, search_threads, BodyPreset, ClipFeatures, FeatureIndex, MotionFeatures, SearchError, SearchParams, FRAME_FLOATS,
};

fn demo_index() -> FeatureIndex {
    let clip = demo_clip();
    let map = HumanoidMap::from_skeleton(&clip.skeleton);
    let status = map.status(&clip.skeleton, Some(&clip));
    let mut index = FeatureIndex::new();
    index.add_clip("demo", &clip, &map, &status).expect("the built-in demo clip is humanoid");
    index
}

/// Runs both searches and checks they fail alike.
fn both(index: &FeatureIndex, q: &ClipFeatures, p: &SearchParams) -> SearchError {
    let a = search(index, q, p, &mut no_progress()).expect_err("fast search should fail");
    let b = search_plain(index, q, p, &mut no_progress()).expect_err("plain search should fail");
    assert_eq!(a.to_string(), b.to_string());
    a
}

#[test]
fn empty_query() {
    let index = demo_index();
    let q = ClipFeatures::new("empty", 60.0, MotionFeatures { origin: Origin::Hips, data: vec![] });
    let e = both(&index, &q, &SearchParams::default());
    assert_eq!(e, SearchError::EmptyQuery);
    assert!(e.to_string().contains("empty"), "{e}");
    // An empty range picked on a timeline.
    let e = index.query_range(0, 10, 10).expect_err("empty range");
    assert!(matches!(e, SearchError::BadRange { start_frame: 10, end_frame: 10, .. }), "{e:?}");
    let e = index.query_range(3, 0, 10).expect_err("no such clip");
    assert_eq!(e, SearchError::UnknownClip { clip_index: 3, clip_count: 1 });
}

#[test]
fn query_longer_than_every_clip() {
    let index = demo_index();
    let longest = index.clips[0].frame_count();
    // Its shortest admissible match spans about half the query (⌈(I−1)/2⌉ + 1 frames): a query
    // of 2·longest frames needs longest + 1; one of 2·longest − 1 frames still fits.
    let data = index.clips[0].features(Origin::Hips).data.repeat(3);
    let q = ClipFeatures::new("long", 60.0, MotionFeatures { origin: Origin::Hips, data: data[..2 * longest * FRAME_FLOATS].to_vec() });
    let e = both(&index, &q, &SearchParams::default());
    assert_eq!(e, SearchError::QueryTooLong { query_frames: 2 * longest, min_span_frames: longest + 1, longest_frames: longest });
    let msg = e.to_string();
    assert!(msg.contains(&(2 * longest).to_string()) && msg.contains(&longest.to_string()), "{msg}");
    let q = ClipFeatures::new("twice", 60.0, MotionFeatures { origin: Origin::Hips, data: data[..(2 * longest - 1) * FRAME_FLOATS].to_vec() });
    let out = search(&index, &q, &SearchParams::default(), &mut no_progress()).expect("a query twice the clip's length still has admissible matches");
    assert!(!out.matches.is_empty());
}

#[test]
fn all_weights_zero_and_bad_parameters() {
    let index = demo_index();
    let q = index.query_range(0, 0, 20).expect("range");
    let mut p = SearchParams::default();
    p.weights = [0.0; 21];
    let e = both(&index, &q, &p);
    assert_eq!(e, SearchError::AllWeightsZero);
    assert!(e.to_string().contains("zero"), "{e}");
    let mut p = SearchParams::default();
    p.weights[3] = f32::NAN;
    assert!(matches!(both(&index, &q, &p), SearchError::BadWeight { joint: "neck", .. }));
    let mut p = SearchParams::default();
    p.weights[0] = -1.0;
    assert!(matches!(both(&index, &q, &p), SearchError::BadWeight { joint: "hips", value } if value == -1.0));
    let p = SearchParams { max_results: 0, ..SearchParams::default() };
    assert!(matches!(both(&index, &q, &p), SearchError::BadParam { name: "maxResults", .. }));
    let p = SearchParams { threshold: Some(f32::NAN), ..SearchParams::default() };
    assert!(matches!(both(&index, &q, &p), SearchError::BadParam { name: "threshold", .. }));
}

#[test]
fn non_humanoid_clip_is_skipped_with_its_reason() {
    let fox = import_bytes("Fox.glb", &odori_tests::read("gltf/Fox.glb"), &ImportOptions::default()).expect("Fox imports");
    assert!(!fox.status.is_humanoid());
    let clip = fox.clips.first().expect("Fox has clips");
    // A library of the Fox only: refused, then nothing to search.
    let mut only_fox = FeatureIndex::new();
    let e = only_fox.add_clip("Fox.glb", clip, &fox.humanoid, &fox.status).expect_err("the Fox is not humanoid");
    assert!(matches!(&e, SearchError::NotHumanoid { clip, reason } if clip == "Fox.glb" && !reason.is_empty()), "{e:?}");
    assert!(e.to_string().contains("Fox.glb"), "{e}");
    assert_eq!(only_fox.skipped.len(), 1);
    let demo = demo_index();
    let q = demo.query_range(0, 0, 20).expect("range");
    let e = both(&only_fox, &q, &SearchParams::default());
    assert_eq!(e, SearchError::EmptyLibrary { skipped: 1 });
    // Fox and a humanoid: the search runs and reports the skipped clip.
    let mut lib = demo_index();
    assert!(lib.add_clip("Fox.glb", clip, &fox.humanoid, &fox.status).is_err());
    let out = search(&lib, &q, &SearchParams::default(), &mut no_progress()).expect("search runs");
    assert_eq!(out.skipped.len(), 1);
    assert_eq!(out.skipped[0].name, "Fox.glb");
    assert!(out.matches.first().is_some_and(|m| m.clip_name == "demo" && m.start_frame == 0 && m.distance < 1e-6), "{:?}", out.matches.first());
}

#[test]
fn progress_is_reported_and_cancel_stops_the_search() {
    // A library long enough for several progress chunks.
    let demo = demo_index();
    let base = &demo.clips[0].features(Origin::Hips).data;
    let mut data = Vec::new();
    while data.len() < 40_000 * FRAME_FLOATS {
        data.extend_from_slice(base);
    }
    let mut lib = FeatureIndex::new();
    lib.add_features(ClipFeatures::new("long", 60.0, MotionFeatures { origin: Origin::Hips, data }));
    let q = demo.query_range(0, 0, 30).expect("range");
    let p = SearchParams::preset(BodyPreset::WholeBody);
    for mode in ["fast", "plain", "threads"] {
        let mut seen = Vec::new();
        let mut calls = 0;
        let mut cb = |s: odori_core::search::SearchProgress| {
            seen.push(s.frames_done);
            calls += 1;
            if calls == 3 {
                ControlFlow::Break(())
            } else {
                ControlFlow::Continue(())
            }
        };
        let r = match mode {
            "plain" => search_plain(&lib, &q, &p, &mut cb),
            // Cancelling the calling thread's progress stops every thread.
            "threads" => search_threads(&lib, &q, &p, 2, &mut cb),
            _ => search(&lib, &q, &p, &mut cb),
        };
        match r {
            Err(SearchError::Cancelled { frames_done, frames_total }) => {
                assert!(frames_done > 0 && frames_done < frames_total, "{mode}: {frames_done}/{frames_total}");
            }
            other => panic!("{mode}: expected a cancel, got {other:?}"),
        }
        assert!(seen.windows(2).all(|w| w[0] <= w[1]), "progress goes forward: {seen:?}");
    }
}
