//! Helpers shared by the integration tests: where the real data lives, and reading it.

use std::path::PathBuf;

/// `../shared/data` relative to the repository root. Panics with a clear message when it is
/// absent: real-data tests must not pass silently without their data.
pub fn data_dir() -> PathBuf {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("..");
    let dir = std::env::var_os("ODORI_DATA").map(PathBuf::from).unwrap_or_else(|| root.join("../shared/data"));
    if !dir.is_dir() {
        panic!(
            "real-data test: {} is missing. These tests read the shared real data (mocap, glTF, music) \
             that sits beside the repository as ../shared/data; set ODORI_DATA to point elsewhere.",
            dir.display()
        );
    }
    dir
}

/// Reads a file under the data directory.
pub fn read(rel: &str) -> Vec<u8> {
    let p = data_dir().join(rel);
    std::fs::read(&p).unwrap_or_else(|e| panic!("cannot read {}: {e}", p.display()))
}

/// Every BVH file under `mocap/`, sorted, as paths relative to the data directory.
pub fn all_bvh() -> Vec<String> {
    let base = data_dir();
    let mut out = Vec::new();
    let mut stack = vec![base.join("mocap")];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap_or_else(|e| panic!("cannot list {}: {e}", d.display())).flatten() {
            let p = e.path();
            if p.is_dir() {
                stack.push(p);
            } else if p.extension().is_some_and(|x| x == "bvh") {
                out.push(p.strip_prefix(&base).unwrap().to_string_lossy().replace('\\', "/"));
            }
        }
    }
    out.sort();
    out
}

/// The frame rate a real file should be played at: the CMU salsa headers say 120 fps but the
/// recordings are 60 fps (see ../shared/data/mocap/SOURCE-cmu-acrnn.txt).
pub fn fps_override_for(rel: &str) -> Option<f32> {
    rel.contains("cmu-salsa").then_some(60.0)
}

/// The ≥ 2,000-segment library the choreography benches time both natively and in wasm
/// (tests/bench/choreo.rs, tests/wasm_bench), built without file access: the built-in moves
/// plus every built-in move concatenated into one 420-bar clip, cut at every count at its
/// stated 120 counts per minute.
pub fn builtin_medley_library() -> odori_core::choreo::SegmentLibrary {
    use odori_core::choreo::{SegmentLibrary, SegmentOptions};
    use odori_core::clip::{Clip, TranslationTrack};
    let mut lib = SegmentLibrary::builtin();
    let clips = odori_core::library::builtin_clips();
    let sk = clips[0].skeleton.clone();
    let (mut rotations, mut root) = (Vec::new(), Vec::new());
    for c in &clips {
        let n = c.frame_count() - 1;
        rotations.extend_from_slice(&c.rotations[..n * sk.len()]);
        root.extend_from_slice(&c.translations[0].values[..n]);
    }
    let medley = Clip {
        name: "medley".into(),
        source: "built-in".into(),
        fps: 30.0,
        skeleton: sk.clone(),
        rotations,
        translations: vec![TranslationTrack { joint: 0, values: root }],
    };
    let map = odori_core::humanoid::HumanoidMap::from_skeleton(&sk);
    let opts = SegmentOptions { tempo_bpm: Some(odori_core::library::BUILTIN_BPM), first_beat_secs: Some(0.0), hop_counts: 1 };
    lib.add_clip(&medley, &map, &odori_core::HumanoidStatus::Complete, &opts).expect("the medley of built-in moves cuts into segments");
    lib
}

/// The filling problem both choreography benches time (native and wasm): 90 open bars whose
/// music intensity swells and falls, between two pinned bars, over `segments` segments.
pub fn bench_layers(segments: usize) -> Vec<odori_core::choreo::Layer> {
    use odori_core::choreo::Layer;
    (0..92)
        .map(|i| match i {
            0 => Layer::Fixed { segment: 17 % segments.max(1) },
            91 => Layer::Fixed { segment: 1234 % segments.max(1) },
            _ => Layer::Open { intensity: 0.5 + 0.45 * (i as f32 / 7.0).sin() },
        })
        .collect()
}
