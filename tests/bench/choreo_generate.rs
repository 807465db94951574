//! Generate on 90 bars with ≥ 2,000 segments (issue 26's speed goal: under 300 ms in wasm),
//! natively: the library of the wasm bench (`odori_tests::builtin_medley_library`: the built-in
//! moves plus a medley of every built-in move cut at every count) and its 90 bars
//! (`odori_tests::bench_bars`), every stage at the default settings (`odori_tests::generate_all`),
//! as `tests/wasm_bench/run.sh` times it in wasm (`generate90`). The first call builds the
//! library's transition table for the song's metre (cached, as in the app); the figure is the best
//! of the calls after it. Prints figures; asserts only that the calls agree.
//! `cargo bench -p odori-tests --bench choreo_generate`.

use std::time::Instant;

fn main() {
    let t = Instant::now();
    let lib = odori_tests::builtin_medley_library();
    let bars = odori_tests::bench_bars();
    println!("library of {} segments (built-in + medley) built in {:.0} ms; {} bars", lib.len(), t.elapsed().as_secs_f64() * 1e3, bars.len());
    let t = Instant::now();
    let (first, cost) = odori_tests::generate_all(&lib, &bars);
    let first_ms = t.elapsed().as_secs_f64() * 1e3;
    let mut best = f64::MAX;
    for _ in 0..5 {
        let t = Instant::now();
        let (again, c) = odori_tests::generate_all(&lib, &bars);
        best = best.min(t.elapsed().as_secs_f64() * 1e3);
        assert_eq!((again, c), (first.clone(), cost), "Generate is deterministic");
    }
    println!("native: Generate 90 bars from {} segments (every stage, default settings): {best:.0} ms (best of 5; first call with the table {first_ms:.0} ms), objective {cost:.3}", lib.len());
    // The built-in library alone, where the variety term is on (off while a library holds
    // imported moves, as the medley is).
    let builtin = odori_core::choreo::SegmentLibrary::builtin();
    let t = Instant::now();
    let (_, cost) = odori_tests::generate_all(&builtin, &bars);
    let first_ms = t.elapsed().as_secs_f64() * 1e3;
    let mut best = f64::MAX;
    for _ in 0..5 {
        let t = Instant::now();
        odori_tests::generate_all(&builtin, &bars);
        best = best.min(t.elapsed().as_secs_f64() * 1e3);
    }
    println!("native: Generate 90 bars from the built-in library alone ({} segments, variety term on): {best:.0} ms (best of 5; first call with the table {first_ms:.0} ms), objective {cost:.3}", builtin.len());
}
