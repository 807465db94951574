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
    let undocumented: Vec<String> = core_sources().into_iter().filter(|(_, text)| !text.trim_start().starts_with("//!")).map(|(name, _)| name).collect();
    assert!(undocumented.is_empty(), "core source files without a `//!` module doc: {undocumented:?}");
}

/// The std float methods `crate::fmath` stands for: in a native build they call the platform's
/// C library, whose last bits differ from the libm port the wasm build's std uses.
const STD_TRANSCENDENTALS: [&str; 15] = ["sin", "cos", "sin_cos", "tan", "asin", "acos", "atan", "atan2", "exp", "exp2", "ln", "log2", "log10", "powf", "tanh"];

#[test]
fn the_core_calls_libm_for_its_transcendentals_not_std() {
    // Code, not comments or strings' prose: a `.sin(` after `//` on its line is skipped.
    let mut found = Vec::new();
    for (name, text) in core_sources() {
        if name == "fmath.rs" {
            continue;
        }
        for (n, line) in text.lines().enumerate() {
            let code = line.split("//").next().unwrap_or("");
            for f in STD_TRANSCENDENTALS {
                if code.contains(&format!(".{f}(")) {
                    found.push(format!("{name}:{}: .{f}(", n + 1));
                }
            }
        }
    }
    assert!(found.is_empty(), "std transcendental methods in the core (call crate::fmath's, the same libm in every build): {found:?}");
}

#[test]
fn glam_computes_with_libm_as_the_core_does() {
    // glam's `libm` feature (native builds only: the core's Cargo.toml): a rotation's sine and cosine are libm's
    // bits, even where the platform's C library's differ (the case this test needs to be able
    // to fail, so it counts them too).
    let (mut differ_from_std, mut checked) = (0, 0);
    for k in 0..20_000 {
        let half = 0.000_37 + k as f32 * 0.000_731;
        let q = glam::Quat::from_rotation_y(2.0 * half);
        let (s, c) = odori_core::fmath::sin_cos(half);
        assert_eq!((q.y.to_bits(), q.w.to_bits()), (s.to_bits(), c.to_bits()), "glam's rotation by {} is not libm's sine and cosine", 2.0 * half);
        differ_from_std += usize::from(half.sin() != s || half.cos() != c);
        checked += 1;
    }
    assert!(differ_from_std > 0, "over {checked} angles, std's sine and cosine never differed from libm's: this test cannot tell them apart here");
    println!("std's sine or cosine differ from libm's at {differ_from_std} of {checked} angles; glam's rotations follow libm at all");
}
