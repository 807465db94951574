//! Import time of an MMD dance posed with IK: WAVEFILE (wavefile_v2.vmd, 2,810 frames) on
//! 初音ミク Ver2 (140 bones, 7 IK chains) and on the built-in standard skeleton, files to Clip.
//! Prints figures (best of 5); the wasm goal for WAVEFILE on miku is < 150 ms.

use std::time::Instant;

use odori_core::import::{mmd_model, vmd};
use odori_core::mmd::{standard_rig, vmd_to_clip, MmdClipOptions, MmdMotion, MmdRig};
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
    let wave = read("mmd/motion/wavefile_v2.vmd");
    let mut frames = 0;
    let all = best_ms(|| {
        let model = mmd_model::read_model("miku_v2.pmd", &pmd).expect("pmd");
        let v = vmd::read("wavefile_v2.vmd", &wave).expect("vmd");
        frames = vmd_to_clip("wavefile_v2.vmd", &v, &[model]).expect("clip").0.frame_count();
    });
    let model = mmd_model::read_model("miku_v2.pmd", &pmd).expect("pmd");
    let motion = MmdMotion::from_vmd(&vmd::read("wavefile_v2.vmd", &wave).expect("vmd"));
    let rig = MmdRig::from_model(&model).expect("rig");
    let posed = best_ms(|| {
        rig.motion_to_clip(&motion, &MmdClipOptions::default()).expect("clip");
    });
    let standard = standard_rig();
    let on_standard = best_ms(|| {
        standard.motion_to_clip(&motion, &MmdClipOptions::default()).expect("clip");
    });
    println!("mmd_import: WAVEFILE ({frames} frames) on miku_v2, files → IK-solved clip: {all:.1} ms (native, best of 5)");
    println!("mmd_import:   of which posing (keys → grants, IK → clip): {posed:.1} ms");
    println!("mmd_import: WAVEFILE on the standard skeleton, motion → clip: {on_standard:.1} ms");
}
