//! Choreography benchmarks (native, release): building the built-in library, building the
//! segment library from ~30 minutes of mocap, the transition table, filling 90 open bars from
//! ≥ 2,000 segments (against a plain full min-plus DP measured in the same run), a feedback
//! round and rendering. Prints figures; asserts nothing about time.

use std::time::Instant;

use odori_core::choreo::{fill_with_stats, FeedbackSession, FillWeights, Layer, RenderOptions, SegmentLibrary, SegmentOptions, TableScope, TransitionTable};
use odori_core::import::import_bytes;
use odori_core::ImportOptions;
use odori_tests::{all_bvh, fps_override_for, read};

fn ms(t: Instant) -> f64 {
    t.elapsed().as_secs_f64() * 1e3
}

/// The plain layered DP (every edge relaxed), as the baseline.
fn plain_fill(table: &TransitionTable, layers: &[Layer], inten: &[f32], w: &FillWeights) -> f32 {
    let m = table.len();
    let music = |i: f32, b: usize| w.music_weight * (i - inten[b]).abs();
    let mut cur: Vec<f32> = match layers[0] {
        Layer::Open { intensity } => (0..m).map(|b| music(intensity, b)).collect(),
        Layer::Fixed { segment } => (0..m).map(|b| if b == segment { 0.0 } else { f32::INFINITY }).collect(),
    };
    let mut back: Vec<Vec<u32>> = Vec::new();
    for l in &layers[1..] {
        let mut next = vec![f32::INFINITY; m];
        let mut arg = vec![0u32; m];
        // Column by column: C(·, b) is contiguous in the table.
        for (b, slot) in next.iter_mut().enumerate() {
            for (a, &pa) in cur.iter().enumerate() {
                let v = pa + table.cost(a, b);
                if v < *slot {
                    *slot = v;
                    arg[b] = a as u32;
                }
            }
        }
        match *l {
            Layer::Open { intensity } => next.iter_mut().enumerate().for_each(|(b, v)| *v += music(intensity, b)),
            Layer::Fixed { segment } => next.iter_mut().enumerate().for_each(|(b, v)| {
                if b != segment {
                    *v = f32::INFINITY
                }
            }),
        }
        back.push(arg);
        cur = next;
    }
    cur.iter().cloned().fold(f32::INFINITY, f32::min)
}

fn main() {
    // 1. Built-in library.
    let mut best = f64::MAX;
    for _ in 0..5 {
        let t = Instant::now();
        let lib = SegmentLibrary::builtin();
        best = best.min(ms(t));
        assert!(lib.len() >= 200);
    }
    let builtin = SegmentLibrary::builtin();
    println!("built-in library: {} segments, built in {best:.1} ms (best of 5)", builtin.len());

    // 2. ~30 minutes of mocap: every real BVH clip, 4 times over (7.4 min each pass).
    let t = Instant::now();
    let mut imported = Vec::new();
    for rel in all_bvh() {
        let opts = ImportOptions { fps_override: fps_override_for(&rel), ..Default::default() };
        imported.push(import_bytes(&rel, &read(&rel), &opts).expect("import"));
    }
    let parse_ms = ms(t);
    let mut lib = SegmentLibrary::builtin();
    let mut secs = 0.0;
    let t = Instant::now();
    let mut refused = 0;
    while secs < 30.0 * 60.0 {
        let before = secs;
        for imp in &imported {
            for c in &imp.clips {
                match lib.add_clip(c, &imp.humanoid, &imp.status, &SegmentOptions { hop_counts: 1, ..Default::default() }) {
                    Ok(_) => secs += c.duration_secs(),
                    Err(_) => refused += 1,
                }
            }
        }
        if secs == before {
            break;
        }
    }
    let build_ms = ms(t);
    println!(
        "segment library from {:.1} min of humanoid mocap (hop 1 count; {} non-humanoid clip loads refused): {} segments in {build_ms:.0} ms \
         (retarget + beats + W + eigen signatures; BVH parsing of one pass {parse_ms:.0} ms more)",
        secs / 60.0,
        refused,
        lib.len() - builtin.len()
    );
    let m = lib.len();
    assert!(m >= 2000, "only {m} segments");

    // 3. Transition table: in one go (cached), and its phases through the slicing builder.
    let t = Instant::now();
    let table = lib.transition_table(FillWeights::default().repeat_penalty);
    println!("transition table: {m} x {m} spec §G costs in {:.0} ms (once per library, cached)", ms(t));
    let mut builder = lib.table_builder(FillWeights::default().repeat_penalty);
    let t = Instant::now();
    builder.step(m);
    let pairs_ms = ms(t);
    let t = Instant::now();
    builder.step(m);
    let top_ms = ms(t);
    let t = Instant::now();
    let p = builder.step(m);
    let rows_ms = ms(t);
    assert!(p.is_done());
    assert!(builder.finish().as_ref() == Some(&*table), "sliced build differs");
    println!("  phases: pair costs {pairs_ms:.0} ms ({:.2} ns per link and pair), top-{} lists {top_ms:.0} ms, row-major copy {rows_ms:.0} ms",
        pairs_ms * 1e6 / (m * m * 20) as f64, odori_core::choreo::fill::TOP_K);

    // The table by metre (what a song's bars need, TableScope) against the all-pairs table
    // above, in the same run: each metre set built from nothing, best of 3.
    let penalty = FillWeights::default().repeat_penalty;
    let time_scope = |scope: &TableScope| {
        let mut best = f64::MAX;
        let mut stored = 0;
        for _ in 0..3 {
            let t = Instant::now();
            let tb = TransitionTable::for_scope(&lib, penalty, scope);
            best = best.min(ms(t));
            stored = tb.stored_pairs();
        }
        (best, stored)
    };
    let (all_ms, all_stored) = time_scope(&TableScope::all_pairs());
    let (n3, n4) = (lib.segments().iter().filter(|s| s.counts() == 3).count(), lib.segments().iter().filter(|s| s.counts() == 4).count());
    println!("transition table by metre ({n4} segments in 4 counts, {n3} in 3); all pairs (main's table): {all_ms:.0} ms, {all_stored} costs (best of 3)");
    for (what, scope) in [
        ("a 4/4 song", TableScope::for_metres(&[4])),
        ("a 3/4 song", TableScope::for_metres(&[3])),
        ("a 4/4 song with one bar corrected to 3", TableScope::for_metres(&[4]).with_join(4, 3).with_join(3, 4)),
        ("a song in 4/4 and 3/4 with a change each way", TableScope::for_metres(&[3, 4]).with_join(4, 3).with_join(3, 4)),
    ] {
        let (t, stored) = time_scope(&scope);
        println!("  {what} ({scope}): {t:.0} ms, {stored} costs; all pairs / this: {:.2}x time, {:.2}x memory", all_ms / t, all_stored as f64 / stored.max(1) as f64);
    }

    // The same ≥ 2,000-segment library the wasm bench times (tests/wasm_bench), for a direct
    // comparison.
    let medley = odori_tests::builtin_medley_library();
    let mut best = f64::MAX;
    for _ in 0..3 {
        let t = Instant::now();
        let t2 = TransitionTable::from_library(&medley, 3.0);
        best = best.min(ms(t));
        assert_eq!(t2.len(), medley.len());
    }
    println!("transition table of the wasm bench's library (built-in + medley): {0} x {0} in {best:.0} ms (best of 3)", medley.len());

    // 4. Fill 90 open bars.
    let inten: Vec<f32> = lib.segments().iter().map(|s| s.intensity01).collect();
    let layers = odori_tests::bench_layers(m);
    // The exact objective (repeat window 1) against the plain DP; then the default (window 4,
    // its repeats charged along the chosen paths).
    let w = FillWeights { repeat_window: 1, ..FillWeights::default() };
    let mut fast = f64::MAX;
    let mut cost = 0.0;
    let mut stats = Default::default();
    for _ in 0..5 {
        let t = Instant::now();
        let (_, c, st) = fill_with_stats(&table, &layers, &inten, &w).unwrap();
        fast = fast.min(ms(t));
        cost = c;
        stats = st;
    }
    let t = Instant::now();
    let plain = plain_fill(&table, &layers, &inten, &w);
    let plain_ms = ms(t);
    assert!((plain - cost).abs() < 1e-3 * cost.abs().max(1.0), "pruned {cost} vs plain {plain}");
    println!(
        "fill: 90 open bars (+2 pinned) from {m} segments in {fast:.1} ms (best of 5); plain full DP {plain_ms:.1} ms in the same run: {:.1}x faster; same cost {cost:.3}",
        plain_ms / fast
    );
    let stats: odori_core::choreo::FillStats = stats;
    println!(
        "  columns relaxed {}, proved optimal from their top-{} edges + the 96 cheapest nodes {:.1}%, scanned in full {}",
        stats.open_columns,
        odori_core::choreo::fill::TOP_K,
        100.0 * (stats.open_columns - stats.full_scans) as f64 / stats.open_columns.max(1) as f64,
        stats.full_scans
    );

    let wd = FillWeights::default();
    let mut with_repairs = f64::MAX;
    let mut st = Default::default();
    for _ in 0..3 {
        let t = Instant::now();
        let (_, _, s) = fill_with_stats(&table, &layers, &inten, &wd).unwrap();
        with_repairs = with_repairs.min(ms(t));
        st = s;
    }
    let st: odori_core::choreo::FillStats = st;
    println!(
        "fill with the default repeat window of {} bars: {with_repairs:.1} ms (best of 3), {} nodes charged for a repeat",
        wd.repeat_window, st.window_charges
    );

    // 5. A feedback round and a Search.
    let t = Instant::now();
    let mut s = FeedbackSession::new();
    let r = s.next_round(&lib, 0.6, 0.3, 6).to_vec();
    let first = ms(t);
    let t = Instant::now();
    s.search(&lib, &r[..2], 0.6, 0.3, 6);
    println!("feedback: first round of 6 from {m} segments {first:.1} ms; a Search round {:.1} ms", ms(t));

    // 6. Generate over 90 bars: with main's all-pairs table cached, and with the table by
    // metre (built by the first Generate on a copy of the library without a table, then
    // cached), in 4/4 and 3/4; the dances must be the same.
    for (beats, bpm) in [(4usize, 120.0f32), (3, 90.0)] {
        let bars = odori_core::choreo::bars_from_tempo(181.0, bpm, beats, 0.0, |_, _| 0.5).unwrap();
        // A copy shares the cached all-pairs table (built in 3.).
        let with_all = lib.clone();
        assert!(with_all.cached_table(penalty).is_some_and(|t| t.scope().is_all_pairs()));
        type States = Vec<odori_core::choreo::BarState>;
        let generate = |lib: &SegmentLibrary| -> States {
            odori_core::choreo::generate_states(lib, &bars, &[], odori_core::choreo::FillWeights::default(), &odori_core::choreo::GenerateOptions::default()).unwrap().0
        };
        // Best of two Generates (each checked by `check`), ms.
        let best_of_two = |lib: &SegmentLibrary, check: &dyn Fn(&States)| {
            (0..2)
                .map(|_| {
                    let t = Instant::now();
                    let d = generate(lib);
                    let took = ms(t);
                    check(&d);
                    took
                })
                .fold(f64::MAX, f64::min)
        };
        let all_gen = best_of_two(&with_all, &|_| {});
        let scoped = lib.clone();
        scoped.drop_table();
        let t = Instant::now();
        let first = generate(&scoped);
        let first_ms = ms(t);
        let built = scoped.cached_table(penalty).expect("cached");
        let cached_gen = best_of_two(&scoped, &|d| assert_eq!(d, &first));
        assert_eq!(generate(&with_all), first, "the table by metre changed the dance");
        println!(
            "generate_states over {} bars in {beats}/4: all-pairs table cached {all_gen:.0} ms; table by metre ({}) cached {cached_gen:.0} ms ({:.2}x faster), \
             first Generate building it {first_ms:.0} ms (against all-pairs build + Generate {:.0} ms: {:.2}x); same dance",
            bars.len(),
            built.scope(),
            all_gen / cached_gen,
            all_ms + all_gen,
            (all_ms + all_gen) / first_ms
        );
    }

    // 7. Render 90 bars.
    let bars = odori_core::choreo::bars_from_tempo(181.0, 120.0, 4, 0.0, |_, _| 0.5).unwrap();
    let (states, _) = odori_core::choreo::generate_states(&lib, &bars, &[], odori_core::choreo::FillWeights::default(), &odori_core::choreo::GenerateOptions::default()).unwrap();
    let t = Instant::now();
    let clip = odori_core::choreo::render_states(&lib, &bars, &states, &RenderOptions::default());
    println!("render of {} bars at 60 fps ({} frames) {:.1} ms", bars.len(), clip.frame_count(), ms(t));
}
