//! Issue 27's house rules that the code alone can keep, checked on every run: no core source
//! file over 1,200 lines (a module that grows past it is split by concept, not trimmed), and every
//! core source file opens with a `//!` module doc saying what it is. (That the core depends on no
//! web crate is `xtask check-core-deps`, the first step of `./dev test`.)

use std::path::{Path, PathBuf};

/// The longest a core source file may be (issue 27's acceptance).
const MAX_LINES: usize = 1_200;

fn core_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../crate/core")
}

fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    let mut entries: Vec<_> = std::fs::read_dir(dir).unwrap_or_else(|e| panic!("{}: {e}", dir.display())).filter_map(Result::ok).map(|e| e.path()).collect();
    entries.sort();
    for p in entries {
        if p.is_dir() {
            rust_files(&p, out);
        } else if p.extension().is_some_and(|x| x == "rs") {
            out.push(p);
        }
    }
}

fn core_sources() -> Vec<(String, String)> {
    let src = core_dir().join("src");
    let mut files = Vec::new();
    rust_files(&src, &mut files);
    assert!(files.len() > 50, "expected the core's sources under {}, found {}", src.display(), files.len());
    files.iter().map(|p| (p.strip_prefix(&src).unwrap_or(p).display().to_string(), std::fs::read_to_string(p).unwrap_or_else(|e| panic!("{}: {e}", p.display())))).collect()
}

#[test]
fn no_core_source_file_is_over_1200_lines() {
    let long: Vec<String> = core_sources().iter().filter(|(_, text)| text.lines().count() > MAX_LINES).map(|(name, text)| format!("{name}: {} lines", text.lines().count())).collect();
    assert!(long.is_empty(), "core source files over {MAX_LINES} lines (split them by concept): {long:?}");
}

#[test]
fn every_core_source_file_says_what_it_is() {
    let sources = core_sources();
    let undocumented: Vec<&String> = sources.iter().filter(|(_, text)| !text.trim_start().starts_with("//!")).map(|(name, _)| name).collect();
    assert!(undocumented.is_empty(), "core source files without a `//!` module doc: {undocumented:?}");
}
