//! `xtask test-native`: the native tests, one test binary per core.
//!
//! `cargo test` runs its test binaries one after another. Many of ours hold a single long
//! real-data test, so on this machine kind one core sat idle for most of the native step. This
//! runs the binaries `cargo test --no-run` builds, as many at once as there are cores, the
//! longest first (the times of the last run, kept in `target/native-test-times.json`; on a fresh
//! checkout the ones known to be long), each in its package's folder as cargo would, and then the
//! doc tests through cargo. It prints a line per binary, a failing binary's whole output, and
//! exits 1 naming what failed.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::{Arc, Mutex};
use std::time::Instant;

/// One test binary cargo built.
#[derive(Debug, Clone, PartialEq)]
pub struct TestBinary {
    /// The target's name with its kind (`odori-core (lib)`, `choreo_fill`).
    pub name: String,
    pub executable: PathBuf,
    /// The package's folder: cargo runs a test binary there.
    pub dir: PathBuf,
}

/// The test binaries in the JSON lines of `cargo test --no-run --message-format=json`.
pub fn parse_artifacts(json_lines: &str) -> Vec<TestBinary> {
    let mut out = Vec::new();
    for line in json_lines.lines() {
        let Ok(v) = serde_json::from_str::<serde_json::Value>(line) else { continue };
        if v["reason"] != "compiler-artifact" || v["profile"]["test"] != true {
            continue;
        }
        let Some(exe) = v["executable"].as_str() else { continue };
        let Some(manifest) = v["manifest_path"].as_str() else { continue };
        let target = v["target"]["name"].as_str().unwrap_or("?");
        let kinds: Vec<&str> = v["target"]["kind"].as_array().map(|k| k.iter().filter_map(|s| s.as_str()).collect()).unwrap_or_default();
        let name = if kinds.iter().any(|k| *k == "test") { target.to_string() } else { format!("{target} ({})", kinds.join(",")) };
        let dir = Path::new(manifest).parent().map(Path::to_path_buf).unwrap_or_default();
        out.push(TestBinary { name, executable: PathBuf::from(exe), dir });
    }
    out.dedup_by(|a, b| a.executable == b.executable);
    out
}

/// What one binary's `test result:` lines say: (passed, failed, ignored), summed.
pub fn count_results(output: &str) -> (u32, u32, u32) {
    let mut sum = (0, 0, 0);
    for line in output.lines().filter(|l| l.starts_with("test result:")) {
        let num = |word: &str| -> u32 {
            line.split(';')
                .filter_map(|part| {
                    let mut it = part.trim().trim_start_matches("test result:").trim().trim_start_matches("ok.").trim_start_matches("FAILED.").trim().split_whitespace();
                    let n: u32 = it.next()?.parse().ok()?;
                    (it.next()? == word).then_some(n)
                })
                .sum()
        };
        sum.0 += num("passed");
        sum.1 += num("failed");
        sum.2 += num("ignored");
    }
    sum
}

/// Binaries known to be long on this machine kind, longest first, for a checkout with no
/// recorded times (CI's clean clone). Measured 2026-12-03: choreo_blended_cost 202 s,
/// choreo_feedback 136, choreo_preference_test 69, claims_search 50, project_roundtrip 37,
/// choreo_my_moves 34, choreo_takes 33, choreo_join_cost 31, choreo_join_points 20, the core's
/// unit tests 19, search_exact 16; the other 51 under 13 s each.
const KNOWN_LONG: &[&str] = &[
    "choreo_blended_cost",
    "choreo_feedback",
    "choreo_preference_test",
    "claims_search",
    "project_roundtrip",
    "choreo_my_moves",
    "choreo_takes",
    "choreo_join_cost",
    "choreo_join_points",
    "odori_core (lib)",
    "search_exact",
];

/// The order to start them in: longest recorded time first, then the known long ones, then the rest
/// by name.
pub fn order(mut bins: Vec<TestBinary>, times: &BTreeMap<String, f64>) -> Vec<TestBinary> {
    let key = |b: &TestBinary| -> (i64, usize, String) {
        let recorded = times.get(&b.name).map(|t| -(t * 1000.0) as i64).unwrap_or(0);
        let known = KNOWN_LONG.iter().position(|k| *k == b.name).unwrap_or(KNOWN_LONG.len());
        (recorded, known, b.name.clone())
    };
    bins.sort_by_key(key);
    bins
}

struct Done {
    name: String,
    ok: bool,
    secs: f64,
    counts: (u32, u32, u32),
    output: String,
}

pub fn run(root: &Path, extra_args: &[String]) {
    let started = Instant::now();
    let times_path = root.join("target/native-test-times.json");
    let times: BTreeMap<String, f64> = std::fs::read(&times_path).ok().and_then(|b| serde_json::from_slice(&b).ok()).unwrap_or_default();

    let build = Command::new("cargo").current_dir(root).args(["test", "--no-run", "--quiet", "--message-format=json"]).args(extra_args).output();
    let build = match build {
        Ok(o) => o,
        Err(e) => super::fail(format!("cannot run cargo test --no-run: {e}")),
    };
    if !build.status.success() {
        eprint!("{}", String::from_utf8_lossy(&build.stderr));
        super::fail("the native tests did not compile (above)");
    }
    let bins = order(parse_artifacts(&String::from_utf8_lossy(&build.stdout)), &times);
    if bins.is_empty() {
        super::fail("cargo test --no-run listed no test binary");
    }
    let workers = std::thread::available_parallelism().map(|n| n.get()).unwrap_or(1).min(bins.len());
    println!("native tests: {} binaries, {workers} at a time, longest first", bins.len());

    let queue = Arc::new(Mutex::new(bins.into_iter().collect::<std::collections::VecDeque<_>>()));
    let (tx, rx) = std::sync::mpsc::channel::<Done>();
    let handles: Vec<_> = (0..workers)
        .map(|_| {
            let (queue, tx) = (queue.clone(), tx.clone());
            std::thread::spawn(move || loop {
                let Some(bin) = queue.lock().unwrap().pop_front() else { break };
                let t = Instant::now();
                let out = Command::new(&bin.executable).current_dir(&bin.dir).arg("--quiet").output();
                let (ok, output) = match out {
                    Ok(o) => (o.status.success(), format!("{}{}", String::from_utf8_lossy(&o.stdout), String::from_utf8_lossy(&o.stderr))),
                    Err(e) => (false, format!("cannot run {}: {e}", bin.executable.display())),
                };
                let counts = count_results(&output);
                let _ = tx.send(Done { name: bin.name, ok, secs: t.elapsed().as_secs_f64(), counts, output });
            })
        })
        .collect();
    drop(tx);

    let mut failed = Vec::new();
    let mut new_times = BTreeMap::new();
    let (mut passed, mut failed_tests, mut ignored) = (0, 0, 0);
    for d in rx {
        println!("  {} {:<28} {:>4} passed {:>7.1} s{}", if d.ok { "ok  " } else { "FAIL" }, d.name, d.counts.0, d.secs, if d.counts.2 > 0 { format!(" ({} ignored)", d.counts.2) } else { String::new() });
        passed += d.counts.0;
        failed_tests += d.counts.1;
        ignored += d.counts.2;
        new_times.insert(d.name.clone(), d.secs);
        if !d.ok {
            println!("---- {} output ----\n{}\n---- end of {} ----", d.name, d.output.trim_end(), d.name);
            failed.push(d.name);
        }
    }
    for h in handles {
        let _ = h.join();
    }
    if let Ok(json) = serde_json::to_vec_pretty(&new_times) {
        let _ = std::fs::write(&times_path, json);
    }

    println!("native tests: doc tests (cargo test --doc)");
    let doc = Command::new("cargo").current_dir(root).args(["test", "--doc", "--quiet"]).args(extra_args).output();
    match doc {
        Ok(o) => {
            let text = format!("{}{}", String::from_utf8_lossy(&o.stdout), String::from_utf8_lossy(&o.stderr));
            let c = count_results(&text);
            passed += c.0;
            failed_tests += c.1;
            ignored += c.2;
            if !o.status.success() {
                println!("{text}");
                failed.push("doc tests".into());
            }
        }
        Err(e) => {
            println!("cannot run cargo test --doc: {e}");
            failed.push("doc tests".into());
        }
    }
    println!("native tests: {passed} passed, {failed_tests} failed, {ignored} ignored, in {:.0} s", started.elapsed().as_secs_f64());
    if !failed.is_empty() {
        super::fail(format!("native tests failed in: {}", failed.join(", ")));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn artifacts_keep_test_binaries_only() {
        let lines = [
            r#"{"reason":"compiler-artifact","manifest_path":"/r/tests/Cargo.toml","target":{"name":"choreo_fill","kind":["test"]},"profile":{"test":true},"executable":"/r/target/debug/deps/choreo_fill-1"}"#,
            r#"{"reason":"compiler-artifact","manifest_path":"/r/crate/core/Cargo.toml","target":{"name":"odori_core","kind":["lib"]},"profile":{"test":true},"executable":"/r/target/debug/deps/odori_core-2"}"#,
            r#"{"reason":"compiler-artifact","manifest_path":"/r/crate/core/Cargo.toml","target":{"name":"odori_core","kind":["lib"]},"profile":{"test":false},"executable":null}"#,
            r#"{"reason":"compiler-artifact","manifest_path":"/r/tests/Cargo.toml","target":{"name":"music_beats","kind":["example"]},"profile":{"test":false},"executable":"/r/target/debug/examples/music_beats"}"#,
            r#"{"reason":"build-finished","success":true}"#,
            "not json",
        ]
        .join("\n");
        let bins = parse_artifacts(&lines);
        assert_eq!(bins.len(), 2, "{bins:?}");
        assert_eq!(bins[0].name, "choreo_fill");
        assert_eq!(bins[0].dir, PathBuf::from("/r/tests"));
        assert_eq!(bins[1].name, "odori_core (lib)");
        assert_eq!(bins[1].executable, PathBuf::from("/r/target/debug/deps/odori_core-2"));
    }

    #[test]
    fn results_are_summed_over_lines() {
        let out = "running 3 tests\n...\ntest result: ok. 3 passed; 0 failed; 1 ignored; 0 measured; 0 filtered out; finished in 0.1s\n\
                   test result: FAILED. 2 passed; 1 failed; 0 ignored; 0 measured; 0 filtered out; finished in 2s\n";
        assert_eq!(count_results(out), (5, 1, 1));
        assert_eq!(count_results("no summary here"), (0, 0, 0));
    }

    #[test]
    fn recorded_times_then_known_long_then_names() {
        let b = |n: &str| TestBinary { name: n.into(), executable: PathBuf::from(n), dir: PathBuf::new() };
        let bins = vec![b("a_short"), b("choreo_feedback"), b("z_recorded"), b("choreo_blended_cost")];
        let fresh = order(bins.clone(), &BTreeMap::new());
        let names: Vec<_> = fresh.iter().map(|b| b.name.as_str()).collect();
        assert_eq!(names, ["choreo_blended_cost", "choreo_feedback", "a_short", "z_recorded"]);
        let times = BTreeMap::from([("z_recorded".to_string(), 500.0), ("choreo_blended_cost".to_string(), 10.0)]);
        let names: Vec<_> = order(bins, &times).iter().map(|b| b.name.clone()).collect();
        assert_eq!(names, ["z_recorded", "choreo_blended_cost", "choreo_feedback", "a_short"]);
    }
}
