//! Time for an MMD model to be ready to draw (issue 28 item 2, step 7): the files imported
//! (`mmd::files::import_files`: PMX/PMD parsed, textures resolved) and made a character
//! (`mmd::mesh::model_character`: skin, parts, TGA/BMP decoded and re-encoded as PNG), for
//! Gene (PMX, 28,646 vertices, PNG textures), miku_v2 (PMD, BMP) and the low-poly miku (TGA).
//! Prints figures (best of 5, native); the goal for Gene in wasm is < 300 ms (wasm runs this kind
//! of code about 1.5–2× slower than native here: see the README's wasm figures).

use std::time::Instant;

use odori_core::mmd::files::{import_files, MmdFilesOptions};
use odori_core::mmd::mesh::model_character;
use odori_tests::data_dir;

fn best_ms(mut f: impl FnMut()) -> f64 {
    (0..5)
        .map(|_| {
            let t = Instant::now();
            f();
            t.elapsed().as_secs_f64() * 1e3
        })
        .fold(f64::INFINITY, f64::min)
}

fn files_under(rel: &str, keep: impl Fn(&str) -> bool) -> Vec<(String, Vec<u8>)> {
    let mut out = Vec::new();
    let mut stack = vec![data_dir().join(rel)];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap_or_else(|e| panic!("{}: {e}", d.display())).flatten() {
            let p = e.path();
            if p.is_dir() {
                stack.push(p);
            } else {
                let name = p.strip_prefix(data_dir().join(rel)).map(|r| r.to_string_lossy().replace('\\', "/")).unwrap_or_default();
                if keep(&name) {
                    out.push((name, std::fs::read(&p).expect("read")));
                }
            }
        }
    }
    out
}

fn main() {
    for (label, dir, model) in [("Gene_light.pmx", "mmd/gene", "Gene_light.pmx"), ("miku_v2.pmd", "mmd/miku_v2", "miku_v2.pmd"), ("low_poly/miku.pmd", "mmd/low_poly", "miku.pmd")] {
        let files = files_under(dir, |n| !n.starts_with("motion/") && (!(n.ends_with(".pmd") || n.ends_with(".pmx")) || n == model));
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
