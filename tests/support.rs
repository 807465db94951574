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
