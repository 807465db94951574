//! The fuzz corpus replayed on the stable toolchain (issue #14): every file in
//! `fuzz/corpus/<target>/` — the seeds `fuzz/make_seeds.py` writes and the inputs libFuzzer
//! kept, crashes it found included once fixed — goes through the same entry points as the
//! libFuzzer targets (`fuzz/entries.rs`). A panic here is a regression of a fixed crash. This
//! runs in every `cargo test`; the coverage-guided runs are `./dev fuzz` (and a short one in
//! `./dev test` when the nightly toolchain and cargo-fuzz are there).

#[path = "../../fuzz/entries.rs"]
mod entries;

use std::path::PathBuf;

fn corpus(target: &str) -> Vec<(PathBuf, Vec<u8>)> {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../fuzz/corpus").join(target);
    let mut files: Vec<PathBuf> = std::fs::read_dir(&dir)
        .unwrap_or_else(|e| panic!("{}: {e} (the fuzz corpus is part of the repository)", dir.display()))
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.is_file())
        .collect();
    files.sort();
    assert!(!files.is_empty(), "{}: no seeds", dir.display());
    files.into_iter().map(|p| (p.clone(), std::fs::read(&p).unwrap())).collect()
}

fn replay(target: &str, entry: fn(&[u8])) {
    let files = corpus(target);
    for (path, bytes) in &files {
        if let Err(e) = std::panic::catch_unwind(|| entry(bytes)) {
            panic!("{target}: {} panics: {:?}", path.display(), e.downcast_ref::<String>().map(String::as_str).or(e.downcast_ref::<&str>().copied()));
        }
    }
    println!("{target}: {} inputs replayed", files.len());
}

#[test]
fn import_bvh_corpus() {
    replay("import_bvh", entries::import_bvh);
}

#[test]
fn import_gltf_corpus() {
    replay("import_gltf", entries::import_gltf);
}

#[test]
fn music_envelope_corpus() {
    replay("music_envelope", entries::music_envelope);
}

#[test]
fn text_parse_corpus() {
    replay("text_parse", entries::text_parse);
}

#[test]
fn project_open_corpus() {
    replay("project_open", entries::project_open);
    // The reviewed golden project seeds the fuzzer in place (tests/fuzz.sh); it opens.
    let golden = std::fs::read(PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("golden/project_v1.odori")).expect("tests/golden/project_v1.odori");
    assert!(odori_core::project::file::open(&golden).is_ok(), "the golden project no longer opens");
    entries::project_open(&golden);
}


#[test]
fn import_vmd_corpus() {
    replay("import_vmd", entries::import_vmd);
}

#[test]
fn import_pmx_corpus() {
    replay("import_pmx", entries::import_pmx);
}

#[test]
fn import_files_corpus() {
    replay("import_files", entries::import_files);
}
