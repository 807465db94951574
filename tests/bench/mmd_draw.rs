//! Time for an MMD model to be ready to draw (issue 28 item 2, step 7): the files imported
//! (`mmd::files::import_files`: PMX/PMD parsed, textures resolved) and made a character
//! (`mmd::mesh::model_character`: skin, parts, TGA/BMP decoded and re-encoded as PNG), for
//! Gene (PMX, 28,646 vertices, PNG textures), miku_v2 (PMD, BMP) and the low-poly miku (TGA).
//! Prints figures (best of 5, native); the goal for Gene in wasm is < 300 ms (wasm runs this kind
//! of code about 1.5–2× slower than native here: see the README's wasm figures).

use odori_core::mmd::files::{import_files, MmdFilesOptions};
use odori_core::mmd::mesh::model_character;
use odori_tests::data_folder;

/// Best of 5, ms.
fn best_ms(f: impl FnMut()) -> f64 {
    odori_tests::best_ms(5, f)
}

fn main() {
    for (label, dir, model) in [("Gene_light.pmx", "mmd/gene", "Gene_light.pmx"), ("miku_v2.pmd", "mmd/miku_v2", "miku_v2.pmd"), ("low_poly/miku.pmd", "mmd/low_poly", "miku.pmd")] {
        let files = data_folder(dir, |n| !n.starts_with("motion/") && (!(n.ends_with(".pmd") || n.ends_with(".pmx")) || n == model));
        let mut info = String::new();
        let import = best_ms(|| {
            let r = import_files(&files, &[], &MmdFilesOptions::default());
            assert!(r.problems.is_empty(), "{:?}", r.problems);
        });
        let r = import_files(&files, &[], &MmdFilesOptions::default());
        let m = &r.models[0];
        let make = best_ms(|| {
            let c = model_character(&m.file, &m.model, &m.textures, &m.missing_textures, &files).expect("character");
            info = format!("{} vertices, {} parts, {} textures", m.model.vertices.len(), c.character.mesh.parts.len(), c.character.mesh.textures.len());
        });
        println!("mmd_draw: {label} ({info}): import {import:.1} ms + character {make:.1} ms = {:.1} ms ready to draw (native, best of 5)", import + make);
    }
}
