//! Generate on 90 bars with ≥ 2,000 segments (issue 26's speed goal: under 300 ms in wasm),
//! natively: the library of the wasm bench (`odori_tests::builtin_medley_library`: the built-in
//! moves plus a medley of every built-in move cut at every count) and its 90 bars
//! (`odori_tests::bench_bars`), every stage at the default settings (`odori_tests::generate_all`),
//! as `tests/wasm_bench/run.sh` times it in wasm (`generate90`). The first call builds the
//! library's transition table for the song's metre (cached, as in the app); the figure is the best
//! of the calls after it; then the same call with each later stage off in turn, and the fill
//! alone, so the figures say where the time goes. Prints figures; asserts only that the calls
//! agree.
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
    // Where the time goes: the same call with one stage off at a time, and stage 1 alone (the
    // fill: every later stage off), best of 3 each.
    let stage = |label: &str, o: odori_core::choreo::GenerateOptions| {
        let mut best = f64::MAX;
        let mut cost = 0.0;
        for _ in 0..3 {
            let t = Instant::now();
            let (_, r) = odori_core::choreo::generate_states(&lib, &bars, &[], odori_core::choreo::FillWeights::default(), &o).expect("generate");
            best = best.min(t.elapsed().as_secs_f64() * 1e3);
            cost = r.cost;
        }
        println!("native:   {label}: {best:.0} ms (best of 3), objective {cost:.3}");
    };
    let d = odori_core::choreo::GenerateOptions::default;
    stage("stage 2 off (beat rate)", odori_core::choreo::GenerateOptions { follow_beat_rate: false, ..d() });
    stage("stage 3 off (free skate)", odori_core::choreo::GenerateOptions { free_skate_slack: 0.0, ..d() });
    stage("stage 4 off (skate)", odori_core::choreo::GenerateOptions { follow_skate: false, ..d() });
    stage("stage 5 off (join repair)", odori_core::choreo::GenerateOptions { follow_joins: false, ..d() });
    stage("stage 1 alone (the fill)", odori_core::choreo::GenerateOptions { follow_beat_rate: false, free_skate_slack: 0.0, follow_skate: false, follow_joins: false, ..d() });
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
