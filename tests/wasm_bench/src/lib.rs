//! wasm timing of the choreography core (issue 5's benchmark), outside the workspace: a raw
//! `cdylib` with no bindings, timed from Node by `run.mjs`. Build (this machine has no
//! rustup wasm32 std; see ../shared/guides/TOOLCHAIN.md) from this directory:
//!
//! ```text
//! RUSTC=/usr/bin/rustc RUSTDOC=/usr/bin/rustdoc RUSTC_BOOTSTRAP=1 CARGO_UNSTABLE_BUILD_STD=std,panic_abort \
//! CARGO_TARGET_WASM32_UNKNOWN_UNKNOWN_LINKER=wasm-ld-19 CARGO_TARGET_DIR=/tmp/choreo_wasm_bench/target \
//! /usr/bin/cargo build --release --target wasm32-unknown-unknown
//! WASM=/tmp/choreo_wasm_bench/target/wasm32-unknown-unknown/release/choreo_wasm_bench.wasm node run.mjs
//! ```
//! (add `RUSTFLAGS="-C target-feature=+simd128"` and another target dir for the SIMD build).
//! The ≥ 2,000-segment library is the built-in one plus every built-in move concatenated into
//! one 420-bar clip cut at every count (no file access in wasm).

use std::cell::RefCell;
use std::sync::Arc;
use odori_core::choreo::*;
use odori_core::clip::{Clip, TranslationTrack};
use odori_core::humanoid::HumanoidMap;

thread_local! {
    static LIB: RefCell<Option<SegmentLibrary>> = RefCell::new(None);
    static TABLE: RefCell<Option<Arc<TransitionTable>>> = RefCell::new(None);
}

#[no_mangle]
pub extern "C" fn build_builtin() -> u32 {
    SegmentLibrary::builtin().len() as u32
}

/// Built-in + every built-in move concatenated into one long clip cut at every count.
#[no_mangle]
pub extern "C" fn setup() -> u32 {
    let mut lib = SegmentLibrary::builtin();
    let clips = odori_core::library::builtin_clips();
    let sk = clips[0].skeleton.clone();
    let mut rot = Vec::new();
    let mut tr = Vec::new();
    for c in &clips {
        let n = c.frame_count() - 1;
        rot.extend_from_slice(&c.rotations[..n * sk.len()]);
        tr.extend_from_slice(&c.translations[0].values[..n]);
    }
    let long = Clip { name: "all".into(), source: "built-in".into(), fps: 30.0, skeleton: sk.clone(), rotations: rot, translations: vec![TranslationTrack { joint: 0, values: tr }] };
    let map = HumanoidMap::from_skeleton(&sk);
    lib.add_clip(&long, &map, &odori_core::HumanoidStatus::Complete, &SegmentOptions { tempo_bpm: Some(120.0), first_beat_secs: Some(0.0), hop_counts: 1 }).unwrap();
    let m = lib.len() as u32;
    LIB.with(|l| *l.borrow_mut() = Some(lib));
    m
}

#[no_mangle]
pub extern "C" fn table() -> u32 {
    LIB.with(|l| {
        let lib = l.borrow();
        let lib = lib.as_ref().unwrap();
        let t = lib.transition_table(3.0);
        let n = t.len() as u32;
        TABLE.with(|x| *x.borrow_mut() = Some(t));
        n
    })
}

#[no_mangle]
pub extern "C" fn fill90() -> f32 {
    fill90_with(FillWeights { repeat_window: 1, ..FillWeights::default() })
}

#[no_mangle]
pub extern "C" fn fill90_default() -> f32 {
    fill90_with(FillWeights::default())
}

fn fill90_with(w: FillWeights) -> f32 {
    LIB.with(|l| {
        let lib = l.borrow();
        let lib = lib.as_ref().unwrap();
        let t = TABLE.with(|x| x.borrow().clone().unwrap());
        let m = t.len();
        let inten: Vec<f32> = lib.segments().iter().map(|s| s.intensity01).collect();
        let layers: Vec<Layer> = (0..92)
            .map(|i| match i {
                0 => Layer::Fixed { segment: 17 },
                91 => Layer::Fixed { segment: 1234 % m },
                _ => Layer::Open { intensity: 0.5 + 0.45 * (i as f32 / 7.0).sin() },
            })
            .collect();
        fill(&t, &layers, &inten, &w).unwrap().1
    })
}
