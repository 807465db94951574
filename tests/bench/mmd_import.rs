//! Import time of MMD files through `mmd::files::import_files` (what `Library.importFiles` and
//! the MMD dialog run): WAVEFILE (wavefile_v2.vmd, 2,810 frames) with the 初音ミク Ver2 folder
//! (140 bones, 7 IK chains: its IK solved), WAVEFILE alone on the built-in standard skeleton (the
//! project-source path), and the Gene folder (PMX, 28,646 vertices, 13 textures). The control:
//! the same posing with every CCD iteration run, as three.js does (`MmdRig::with_full_ccd`).
//! Prints figures (best of 5); the wasm goals are WAVEFILE < 150 ms, Gene < 300 ms
//! (`tests/bench/mmd-wasm.mjs` times the same in wasm).

use odori_core::import::{mmd_model, vmd};
use odori_core::mmd::files::{import_files, MmdFilesOptions, STANDARD_RIG};
use odori_core::mmd::{MmdClipOptions, MmdMotion, MmdRig};
use odori_tests::{data_folder, read};

/// Best of 5, ms.
fn best_ms(f: impl FnMut()) -> f64 {
    odori_tests::best_ms(5, f)
}

/// A data folder's files as a dropped folder gives them: named under the folder's own name.
fn folder(rel: &str, keep: impl Fn(&str) -> bool) -> Vec<(String, Vec<u8>)> {
    let top = rel.rsplit('/').next().unwrap_or(rel);
    data_folder(rel, keep).into_iter().map(|(name, bytes)| (format!("{top}/{name}"), bytes)).collect()
}

fn main() {
    let wave = read("mmd/motion/wavefile_v2.vmd");
    let mut set = folder("mmd/miku_v2", |_| true);
    set.push(("wavefile_v2.vmd".into(), wave.clone()));
    let mut frames = 0;
    let on_miku = best_ms(|| {
        let r = import_files(&set, &[], &MmdFilesOptions::default());
        assert!(r.problems.is_empty(), "{:?}", r.problems);
        frames = r.motions[0].clip.frame_count();
    });
    let pmd = read("mmd/miku_v2/miku_v2.pmd");
    let model = mmd_model::read_model("miku_v2.pmd", &pmd).expect("pmd");
    let motion = MmdMotion::from_vmd(&vmd::read("wavefile_v2.vmd", &wave).expect("vmd"));
    let rig = MmdRig::from_model(&model).expect("rig");
    let posed = best_ms(|| {
        rig.motion_to_clip(&motion, &MmdClipOptions::default()).expect("clip");
    });
    let full = rig.clone().with_full_ccd();
    let posed_full = best_ms(|| {
        full.motion_to_clip(&motion, &MmdClipOptions::default()).expect("clip");
    });
    let alone = vec![("wavefile_v2.vmd".to_string(), wave.clone())];
    let on_standard = best_ms(|| {
        let r = import_files(&alone, &[], &MmdFilesOptions { model: Some(STANDARD_RIG.into()), ..Default::default() });
        assert!(r.problems.is_empty(), "{:?}", r.problems);
    });
    let gene = folder("mmd/gene", |n| !n.starts_with("motion/") && !n.ends_with(".pmd"));
    let mut vertices = 0;
    let gene_ms = best_ms(|| {
        let r = import_files(&gene, &[], &MmdFilesOptions::default());
        vertices = r.models.iter().map(|m| m.model.vertices.len()).sum();
    });
    println!("mmd_import: WAVEFILE ({frames} frames) + miku_v2 folder, import_files → IK-solved clip: {on_miku:.1} ms (native, best of 5)");
    println!("mmd_import:   of which posing (keys → grants, IK → clip): {posed:.1} ms; the control, every CCD iteration (three.js's rule): {posed_full:.1} ms");
    println!("mmd_import: WAVEFILE alone on the standard skeleton (the project-source path), import_files: {on_standard:.1} ms");
    println!("mmd_import: Gene folder ({vertices} vertices, {} files), import_files: {gene_ms:.1} ms", gene.len());
}
