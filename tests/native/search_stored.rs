//! The stored search index (issue #16, build item 3) on the real clips: index → bytes → index
//! gives the same search results (presets, weights, thresholds, queries from the library and
//! from outside it, fast search and plain DP); a library that changed is caught by its content
//! key and the index rebuilt; damaged or other-version bytes are refused with a typed error.

#[path = "search_common.rs"]
mod common;

use std::cell::Cell;

use common::Rng;
use odori_core::search::{
    clip_key, decode_index, encode_index, library_key, no_progress, open_or_build, search,
    search_plain, BodyPreset, ClipFeatures, FeatureIndex, Opened, SearchParams, StoredClip,
    StoredIndex, StoredIndexError, STORED_INDEX_VERSION,
};
use odori_core::{Clip, HumanoidMap, HumanoidStatus};

type Real = Vec<(String, Clip, HumanoidMap, HumanoidStatus)>;

/// Builds the index of `clips` as the app does: ids 100, 101, … and each clip's content key.
fn build(clips: &Real) -> StoredIndex {
    let mut index = FeatureIndex::new();
    let mut stored = Vec::new();
    for (n, (rel, clip, map, status)) in clips.iter().enumerate() {
        if index.add_clip(rel.clone(), clip, map, status).is_ok() {
            stored.push(StoredClip {
                id: 100 + n as u32,
                key: clip_key(rel, clip),
            });
        }
    }
    StoredIndex {
        index,
        clips: stored,
    }
}

fn key_of(clips: &Real, index_fps: f32) -> u128 {
    // The key is computed from the library alone (no index built): every humanoid clip's key.
    library_key(
        index_fps,
        clips
            .iter()
            .filter(|c| !matches!(c.3, HumanoidStatus::NotHumanoid { .. }) && c.1.frame_count() > 0)
            .map(|(rel, clip, ..)| clip_key(rel, clip)),
    )
}

#[test]
fn stored_index_gives_the_same_results() {
    let clips = common::real_clips();
    let built = build(&clips);
    let bytes = encode_index(&built.index, &built.clips);
    let back = decode_index(&bytes).expect("the stored index reads back");
    assert_eq!(back.clips, built.clips, "ids and keys kept");
    assert_eq!(
        back.index.skipped, built.index.skipped,
        "skipped clips kept"
    );
    assert_eq!(
        back.library_key(),
        key_of(&clips, built.index.fps),
        "the library key is computable from the clips alone"
    );
    let frames = built.index.total_frames();
    println!(
        "{} clips, {} frames ({:.1} min at {} fps): {} bytes stored, {:.1} MB per hour of motion",
        built.index.clips.len(),
        frames,
        frames as f32 / built.index.fps / 60.0,
        built.index.fps,
        bytes.len(),
        bytes.len() as f64 / (frames as f64 / built.index.fps as f64 / 3600.0) / 1e6
    );

    // A query from outside the library: a stretch of a clip left out of a second index.
    let mut rng = Rng(0x5eed_0016);
    let presets = [
        BodyPreset::WholeBody,
        BodyPreset::FeetOnly,
        BodyPreset::Arms,
        BodyPreset::LowerBody,
    ];
    let mut compared = 0;
    for round in 0..12 {
        let mut params = SearchParams::preset(presets[round % presets.len()]);
        params.max_results = [1, 5, 10][round % 3];
        if round % 4 == 3 {
            // Random weights on every joint.
            for w in params.weights.iter_mut() {
                *w = rng.range(0.0, 2.0);
            }
        }
        let c = rng.usize(built.index.clips.len());
        let n = built.index.clips[c].frame_count();
        let len = 30 + rng.usize(90).min(n.saturating_sub(31));
        let start = rng.usize(n - len);
        let query: ClipFeatures = built
            .index
            .query_range(c, start, start + len)
            .expect("query range");
        let first = search(&built.index, &query, &params, &mut no_progress()).expect("search");
        if round % 2 == 1 {
            // A threshold between the best and the last distance, so it cuts.
            let d = &first.matches;
            params.threshold = Some((d[0].distance + d[d.len() - 1].distance) / 2.0 + 1e-6);
        }
        let want = search(&built.index, &query, &params, &mut no_progress()).expect("search");
        let got = search(&back.index, &query, &params, &mut no_progress())
            .expect("search the reopened index");
        assert_eq!(
            got, want,
            "round {round}: the reopened index answers differently ({params:?})"
        );
        if round < 3 {
            let plain =
                search_plain(&back.index, &query, &params, &mut no_progress()).expect("plain");
            assert_eq!(
                plain.matches, want.matches,
                "round {round}: the plain DP on the reopened index differs"
            );
        }
        assert!(!want.matches.is_empty());
        compared += 1;
    }
    assert_eq!(compared, 12);
}

#[test]
fn a_changed_library_is_detected_and_rebuilt() {
    let clips = common::real_clips();
    let first = build(&clips);
    let stored = encode_index(&first.index, &first.clips);
    let fps = FeatureIndex::new().fps;

    // The same library: the stored index is used and nothing is built.
    let built = Cell::new(false);
    let (same, how) = open_or_build(Some(&stored), key_of(&clips, fps), || {
        built.set(true);
        Ok::<_, ()>(build(&clips))
    })
    .unwrap();
    assert_eq!(how, Opened::Stored);
    assert!(!built.get(), "an up-to-date index was rebuilt");
    assert_eq!(same.library_key(), key_of(&clips, fps));

    // One rotation of one clip changed by a thousandth of a radian: another library.
    let mut changed = clips.clone();
    let k = changed.len() / 2;
    changed[k].1.rotations[10] *= glam::Quat::from_rotation_x(1e-3);
    let key = key_of(&changed, fps);
    assert_ne!(key, key_of(&clips, fps));
    let (fresh, how) = open_or_build(Some(&stored), key, || Ok::<_, ()>(build(&changed))).unwrap();
    match how {
        Opened::Rebuilt { why } => assert!(why.starts_with("stale"), "{why}"),
        Opened::Stored => panic!("a stale index was used"),
    }
    assert_eq!(fresh.library_key(), key);
    // A clip removed, and two clips swapped: other libraries too.
    let mut fewer = clips.clone();
    fewer.remove(0);
    assert_ne!(key_of(&fewer, fps), key_of(&clips, fps));
    let mut swapped = clips.clone();
    swapped.swap(0, 1);
    assert_ne!(key_of(&swapped, fps), key_of(&clips, fps));

    // Damaged bytes are rebuilt too, saying why; another version is a typed error.
    let mut damaged = stored.clone();
    let at = damaged.len() / 3;
    damaged[at] ^= 1;
    let (_, how) = open_or_build(Some(&damaged), key_of(&clips, fps), || {
        Ok::<_, ()>(build(&clips))
    })
    .unwrap();
    assert!(
        matches!(&how, Opened::Rebuilt { why } if why.contains("corrupt")),
        "{how:?}"
    );
    let mut other = stored.clone();
    other[8..12].copy_from_slice(&(STORED_INDEX_VERSION + 1).to_le_bytes());
    assert_eq!(
        decode_index(&other).unwrap_err(),
        StoredIndexError::Version {
            found: STORED_INDEX_VERSION + 1,
            expected: STORED_INDEX_VERSION
        }
    );
    assert!(matches!(
        decode_index(&stored[..stored.len() - 3]),
        Err(StoredIndexError::Checksum { .. } | StoredIndexError::Truncated { .. })
    ));
}
