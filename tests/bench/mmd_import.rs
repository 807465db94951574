//! Import time of an MMD dance posed with IK: WAVEFILE (wavefile_v2.vmd, 2,810 frames) on
//! 初音ミク Ver2 (140 bones, 7 IK chains) and on the built-in standard skeleton, files to Clip.
//! Prints figures (best of 5); the wasm goal for WAVEFILE on miku is < 150 ms.

#[path = "../mmd_read.rs"]
mod mmd_read;

use std::time::Instant;

use odori_core::mmd::{standard_rig, MmdClipOptions, MmdRig};
use odori_tests::read;

fn best_ms(mut f: impl FnMut()) -> f64 {
    (0..5)
        .map(|_| {
            let t = Instant::now();
            f();
            t.elapsed().as_secs_f64() * 1e3
        })
        .fold(f64::INFINITY, f64::min)
}

fn main() {
    let pmd = read("mmd/miku_v2/miku_v2.pmd");
    let vmd = read("mmd/motion/wavefile_v2.vmd");
    let mut frames = 0;
    let miku = best_ms(|| {
        let (name, bones, iks) = mmd_read::read_pmd(&pmd).expect("pmd");
        let rig = MmdRig::from_pmd_records(name, &bones, &iks).expect("rig");
        let motion = mmd_read::read_vmd(&vmd).expect("vmd");
        let clip = rig.motion_to_clip(&motion, &MmdClipOptions::default()).expect("clip");
        frames = clip.frame_count();
    });
    let motion = mmd_read::read_vmd(&vmd).expect("vmd");
    let rig = standard_rig();
    let standard = best_ms(|| {
        rig.motion_to_clip(&motion, &MmdClipOptions::default()).expect("clip");
    });
    println!("mmd_import: WAVEFILE ({frames} frames) on miku_v2, files → IK-solved clip: {miku:.1} ms (native, best of 5)");
    println!("mmd_import: WAVEFILE on the standard skeleton, motion → clip: {standard:.1} ms");
}
