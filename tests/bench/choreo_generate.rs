//! Generate on 90 bars with ≥ 2,000 segments (issue 26's speed goal: under 300 ms in wasm),
//! natively: the library of the wasm bench (`odori_tests::builtin_medley_library`: the built-in
//! moves plus a medley of every built-in move, danced one after another and cut at every count)
//! and its 90 bars (`odori_tests::bench_bars`), every stage at the default settings
//! (`odori_tests::generate_all`), as `tests/wasm_bench/run.sh` times it in wasm (`generate90`).
//! The first call builds the library's transition table for the song's metre (cached, as in the
//! app); the figure is the best of the calls after it. Then the second library (a medley of every
//! other built-in move) and a library of real files (`../shared/data`: the person's files and
//! the two VMD dances, each cut at every count), each with where its time goes; on the real
//! files the default alternated with every refill measured whole (`windowed_measures` off; best
//! of 3 each; whether the dance is the same is printed), one measure as played of the default's
//! dance profiled by part (`MEASURES=n`: n more, then stop), the default alternated with session
//! 24's measures (best of 5 each) and against its controls in the same run (session 24's
//! measures: every held round posed anew, session 20's measures, session 19's fills, session
//! 18's fills, session 15's measures, every held frame posed, session 16's default, the old
//! pipeline's settings, windowed refills, every refill measured whole), with the default's and
//! session 16's dances measured as played; then the same call with each later stage off in
//! turn, and the fill alone, so the figures say where the time goes. The medleys' dances need no
//! refill (stages 4b and 5 measure once and stop), so the controls run on the real files, where
//! the later stages work.
//! Prints figures; asserts only that the calls agree (session 20's measures, session 19's and 18's fills, quick measures, every
//! held frame posed and the default: the same dance).
//! `cargo bench -p odori-tests --bench choreo_generate` (`GENERATE_ONLY=1`: not the stages off
//! one at a time nor the built-in library). Needs `../shared/data` (fails naming it when absent).

use std::sync::OnceLock;
use std::time::Instant;

/// Milliseconds since the first reading (the clock the core's profile borrows).
fn clock_ms() -> f64 {
    static START: OnceLock<Instant> = OnceLock::new();
    START.get_or_init(Instant::now).elapsed().as_secs_f64() * 1e3
}

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
    // Where the time goes, per stage: the fills (shortest paths and free-skate passes) against
    // the renders and measures (odori_core::choreo::profile, with this clock).
    let ((), profile) = odori_core::choreo::profile::profiled(clock_ms, || {
        odori_tests::generate_all(&lib, &bars);
    });
    for line in odori_tests::profile_lines(&profile) {
        println!("native:   {line}");
    }
    // A second library (the built-in moves plus a medley of every other built-in clip, cut at
    // every count), so the figure is not of one library alone: its time, best of 3, and profile.
    let other = odori_tests::every_other_medley_library();
    let (other_first, other_cost) = odori_tests::generate_all(&other, &bars);
    let mut other_best = f64::MAX;
    for _ in 0..3 {
        let t = Instant::now();
        let again = odori_tests::generate_all(&other, &bars);
        other_best = other_best.min(t.elapsed().as_secs_f64() * 1e3);
        assert_eq!(again, (other_first.clone(), other_cost), "Generate is deterministic");
    }
    println!("native: Generate 90 bars from the second library ({} segments: built-in + medley of every other clip): {other_best:.0} ms (best of 3), objective {other_cost:.3}", other.len());
    let ((), profile) = odori_core::choreo::profile::profiled(clock_ms, || {
        odori_tests::generate_all(&other, &bars);
    });
    for line in odori_tests::profile_lines(&profile) {
        println!("native:   {line}");
    }
    // A third library, from real files (../shared/data): the person's files (every humanoid
    // dance clip in ../shared/data/mocap and RobotExpressive's Dance) and the two VMD dances of
    // ../shared/data/mmd/motion, each cut at every count: moves recorded by people, at their own
    // tempi, where the medleys above are the built-in moves danced at the song's tempo (a dance
    // from them can play the medley's bars in a row, joined as recorded).
    let real = odori_tests::real_files_library();
    let (real_first, real_cost) = odori_tests::generate_all(&real, &bars);
    let mut real_best = f64::MAX;
    for _ in 0..3 {
        let t = Instant::now();
        let again = odori_tests::generate_all(&real, &bars);
        real_best = real_best.min(t.elapsed().as_secs_f64() * 1e3);
        assert_eq!(again, (real_first.clone(), real_cost), "Generate is deterministic");
    }
    println!("native: Generate 90 bars from real files ({} segments: built-in + every count of the person's files and the two VMD dances): {real_best:.0} ms (best of 3), objective {real_cost:.3}", real.len());
    let ((), profile) = odori_core::choreo::profile::profiled(clock_ms, || {
        odori_tests::generate_all(&real, &bars);
    });
    for line in odori_tests::profile_lines(&profile) {
        println!("native:   {line}");
    }
    // Measures near a refill's changes (GenerateOptions::windowed_measures, the default) against
    // every measure of the whole dance (the control) on the real files: best of 3 each,
    // alternated.
    let whole_measures = odori_core::choreo::GenerateOptions { windowed_measures: false, ..odori_core::choreo::GenerateOptions::default() };
    let (mut near_ms, mut whole_ms) = (f64::MAX, f64::MAX);
    let mut whole_dance = None;
    for _ in 0..3 {
        let t = Instant::now();
        odori_tests::generate_all(&real, &bars);
        near_ms = near_ms.min(t.elapsed().as_secs_f64() * 1e3);
        let t = Instant::now();
        let (states, r) = odori_core::choreo::generate_states(&real, &bars, &[], odori_core::choreo::FillWeights::default(), &whole_measures).expect("generate");
        whole_ms = whole_ms.min(t.elapsed().as_secs_f64() * 1e3);
        whole_dance = Some((states.iter().map(odori_core::choreo::BarState::segment).collect::<Vec<_>>(), r.cost));
    }
    let (whole_path, whole_cost) = whole_dance.expect("timed");
    let differ = whole_path.iter().zip(&real_first).filter(|(a, b)| a != b).count();
    println!(
        "native: Generate 90 bars from real files, every measure of the whole dance (windowed_measures off, the control): {whole_ms:.0} ms, objective {whole_cost:.3} (best of 3), against the default's {near_ms:.0} ms in the same run: {:.2}x the default's time, {}",
        whole_ms / near_ms,
        if differ == 0 { "the same dance".to_string() } else { format!("dances differ in {differ} bars") }
    );
    drop(other);
    // The measure and the controls below on the real files, where the later stages work (on the
    // medleys a dance needs no refill: stages 4b and 5 measure once and stop).
    drop(lib);
    let lib = real;
    // One measure as played of the default's dance (what the order stage and stage 5 take 8
    // of a Generate), profiled by part: best of 5, then where its time goes. `MEASURES=n`: n
    // more of them and nothing else (for `perf record`).
    let path: Vec<usize> = {
        let (states, _) = odori_core::choreo::generate_states(&lib, &bars, &[], odori_core::choreo::FillWeights::default(), &odori_core::choreo::GenerateOptions::default()).expect("generate");
        states.iter().map(|b| b.segment().expect("every bar filled")).collect()
    };
    let mut best_measure = f64::MAX;
    for _ in 0..5 {
        let t = Instant::now();
        let f = odori_core::choreo::played_figures(&lib, &bars, &path);
        best_measure = best_measure.min(t.elapsed().as_secs_f64() * 1e3);
        assert!(f.is_some(), "the default's dance is measured");
    }
    let ((), profile) = odori_core::choreo::profile::profiled(clock_ms, || {
        odori_core::choreo::played_figures(&lib, &bars, &path);
    });
    println!("native: one measure as played of the default's dance: {best_measure:.1} ms (best of 5); by part, one call:");
    for line in odori_tests::profile_lines(&profile) {
        println!("native:   {line}");
    }
    if let Some(n) = std::env::var("MEASURES").ok().and_then(|v| v.parse::<usize>().ok()) {
        for _ in 0..n {
            odori_core::choreo::played_figures(&lib, &bars, &path);
        }
        return;
    }
    // The default against the controls in the same run, best of 3 each: session 15's measures
    // (GenerateOptions::quick_measures off), session 16's default (one join barred a refill,
    // GenerateOptions::join_bans_at_once off), the old pipeline (67f699e's
    // settings: measured unheld, no order stage) and windowed refills
    // (GenerateOptions::windowed_refills): times, objectives, whether the dance is the same.
    let d = odori_core::choreo::GenerateOptions::default;
    let run = |o: &odori_core::choreo::GenerateOptions| {
        let (states, r) = odori_core::choreo::generate_states(&lib, &bars, &[], odori_core::choreo::FillWeights::default(), o).expect("generate");
        (states.iter().map(odori_core::choreo::BarState::segment).collect::<Vec<_>>(), r.cost)
    };
    let control = odori_core::choreo::GenerateOptions { quick_measures: false, ..d() };
    let s16 = odori_core::choreo::GenerateOptions { join_bans_at_once: false, ..d() };
    let s17 = odori_core::choreo::GenerateOptions { pose_read_frames_only: false, top_lists_stop_at_rest: false, columns_scanned_by_chunks: false, ..d() };
    let s18 = odori_core::choreo::GenerateOptions { top_lists_stop_at_rest: false, columns_scanned_by_chunks: false, ..d() };
    let s19 = odori_core::choreo::GenerateOptions { columns_scanned_by_chunks: false, ..d() };
    let s20 = odori_core::choreo::GenerateOptions { free_pass_legs_only: false, ..d() };
    let s24 = odori_core::choreo::GenerateOptions { rounds_copy_same_frames: false, ..d() };
    let ((), profile) = odori_core::choreo::profile::profiled(clock_ms, || {
        run(&s24);
    });
    println!("native:   the same, session 24's measures (every held round posed anew: rounds_copy_same_frames off, today's main, the control):");
    for line in odori_tests::profile_lines(&profile) {
        println!("native:   {line}");
    }
    let ((), profile) = odori_core::choreo::profile::profiled(clock_ms, || {
        run(&s16);
    });
    println!("native:   the same, session 16's default (one join barred a refill, join_bans_at_once off, the control):");
    for line in odori_tests::profile_lines(&profile) {
        println!("native:   {line}");
    }
    println!("native: load average {}", std::fs::read_to_string("/proc/loadavg").unwrap_or_default().split_whitespace().take(3).collect::<Vec<_>>().join(" "));
    let variants = [
        ("the default (join bans at once, quick measures)", d()),
        ("session 24's measures (every held round posed anew; today's main, the control)", s24),
        ("session 20's work (the free pass posing every joint; control)", s20),
        ("session 19's work (whole columns scanned entry by entry; control)", s19),
        ("session 18's work (top lists stopped by the cheapest node; control)", s18),
        ("session 15's measures (control)", control),
        ("every held frame posed, session 18's fills (control)", s17),
        ("session 16's default (one join barred a refill, control)", s16),
        ("old pipeline (67f699e's settings)", odori_core::choreo::GenerateOptions { measure_played: false, follow_order: false, ..d() }),
        ("windowed refills", odori_core::choreo::GenerateOptions { windowed_refills: true, ..d() }),
        ("every measure of the whole dance (windowed_measures off; control)", odori_core::choreo::GenerateOptions { windowed_measures: false, ..d() }),
    ];
    let mut timed: Vec<(f64, (Vec<Option<usize>>, f32))> = Vec::new();
    for (_, o) in &variants {
        let mut best = (f64::MAX, (Vec::new(), 0.0));
        for _ in 0..3 {
            let t = Instant::now();
            let r = run(o);
            best = (best.0.min(t.elapsed().as_secs_f64() * 1e3), r);
        }
        timed.push(best);
    }
    // This session's lever against its control, alternated (the block above times each variant's
    // three calls together, and the first in it has run slow under load): best of 5 each.
    let (mut with, mut without) = (f64::MAX, f64::MAX);
    for _ in 0..5 {
        for (o, best) in [(d(), &mut with), (s24, &mut without)] {
            let t = Instant::now();
            let r = run(&o);
            *best = best.min(t.elapsed().as_secs_f64() * 1e3);
            assert_eq!(r, timed[0].1, "the rounds copying their same frames keep the dance");
        }
    }
    println!("native: Generate 90 bars alternated, best of 5 each: the default {with:.0} ms, session 24's measures (the control) {without:.0} ms: {:.2}x the default's time", without / with);
    for (k, ((label, _), (ms, (dance, c)))) in variants.iter().zip(&timed).enumerate() {
        let differ = dance.iter().zip(&timed[0].1 .0).filter(|(a, b)| a != b).count();
        let against = if k == 0 {
            String::new()
        } else {
            format!(": {:.2}x the default's time, {}", ms / timed[0].0, if differ == 0 { "the same dance".to_string() } else { format!("dances differ in {differ} bars") })
        };
        println!("native: Generate 90 bars, {label}: {ms:.0} ms, objective {c:.3} (best of 3){against}");
    }
    assert_eq!(timed[1].1, timed[0].1, "the rounds copying their same frames keep the dance");
    assert_eq!(timed[2].1, timed[0].1, "the free pass posing its legs alone keeps the dance");
    assert_eq!(timed[3].1, timed[0].1, "whole columns scanned by chunks keep the dance");
    assert_eq!(timed[4].1, timed[0].1, "top lists stopped at the rest keep the dance");
    assert_eq!(timed[5].1, timed[0].1, "quick measures keep the dance");
    assert_eq!(timed[6].1, timed[0].1, "posing only the frames read keeps the dance");
    // What each dance is worth, as played (the figures stage 5 and the preference order
    // follow): the default's against session 16's, the control.
    for (k, label) in [(0, "the default"), (7, "session 16's default (control)")] {
        let path: Vec<usize> = timed[k].1 .0.iter().map(|s| s.expect("every bar filled")).collect();
        let imported = path.iter().filter(|&&s| lib.segments()[s].builtin.is_none()).count();
        match odori_core::choreo::played_figures(&lib, &bars, &path) {
            Some(f) => println!(
                "native:   {label} as played: worst join {:.3} (bar {:?}; {} joins over 1.5), foot skate {:.2} cm/s (goal {:.2}), kinetic beats a count {:.3}, BAS-music {:.3}, {imported} of {} bars imported",
                f.whole.join_jump_max,
                f.whole.worst_join_bar,
                f.bars.iter().filter(|b| b.join_jump.is_some_and(|j| j > 1.5)).count(),
                f.whole.foot_skate_cm_per_s,
                odori_core::choreo::skate_goal_cm_per_s(&lib, &path),
                f.whole.kinetic_per_count,
                f.bas_music,
                path.len()
            ),
            None => println!("native:   {label}: not measured"),
        }
    }
    if std::env::var("GENERATE_ONLY").is_ok_and(|v| v == "1") {
        return;
    }
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
    stage("stage 2 off (beat rate)", odori_core::choreo::GenerateOptions { follow_beat_rate: false, ..d() });
    stage("stage 3 off (free skate)", odori_core::choreo::GenerateOptions { free_skate_slack: 0.0, ..d() });
    stage("stage 4 off (skate)", odori_core::choreo::GenerateOptions { follow_skate: false, ..d() });
    stage("stage 4b off (preference order)", odori_core::choreo::GenerateOptions { follow_order: false, ..d() });
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
