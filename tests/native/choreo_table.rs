//! The transition table built only for the joins a song's bars make (blocks by metre, spec §G's
//! C unchanged) against the all-pairs table, on a real library (the built-in moves and every
//! clip of ../shared/data/mocap, cut into 4- and 3-count segments): the same costs pair by pair
//! (bit for bit, cross-metre joins included) and the same dance from a whole Generate (same
//! choices, same cost) on real songs from ../shared/data/music and the drum take, a piece in
//! 3/4, one whose metre changes, and one with a bar corrected to 3 beats and a pinned bar.

use odori_core::bars::Bar;
use odori_core::choreo::{bar_counts, bars_from_tempo, generate_states, BarState, FillWeights, GenerateOptions, SegmentLibrary, SegmentOptions, TableScope, TransitionTable};
use odori_core::import::import_bytes;
use odori_core::music::{analyze, AnalysisOptions};
use odori_core::ImportOptions;
use odori_tests::{all_bvh, fps_override_for, read};

#[path = "music_audio.rs"]
mod music_audio;

/// The built-in moves and every real mocap clip, cut at the default options (4- and 3-count);
/// made once for the tests of this file.
fn real_library() -> SegmentLibrary {
    static LIB: std::sync::OnceLock<SegmentLibrary> = std::sync::OnceLock::new();
    LIB.get_or_init(make_real_library).clone()
}

fn make_real_library() -> SegmentLibrary {
    let mut lib = SegmentLibrary::builtin();
    for rel in all_bvh() {
        let opts = ImportOptions { fps_override: fps_override_for(&rel), ..Default::default() };
        let imp = import_bytes(&rel, &read(&rel), &opts).expect("import");
        for clip in &imp.clips {
            let _ = lib.add_clip(clip, &imp.humanoid, &imp.status, &SegmentOptions::default());
        }
    }
    lib
}

/// The song's bars from the core's analysis of a real recording.
fn song_bars(rel: &str) -> Vec<Bar> {
    let audio = music_audio::decode_data(rel);
    let env = audio.envelope().unwrap_or_else(|e| panic!("{rel}: {e}"));
    analyze(&env, &AnalysisOptions::default()).unwrap_or_else(|e| panic!("{rel}: {e}")).bars
}

/// Bars of `n` beats after `before` (indices and times continued).
fn continue_bars(before: &[Bar], secs: f32, bpm: f32, n: usize) -> Vec<Bar> {
    let start = before.last().map_or(0.0, |b| b.end_secs);
    let mut bars = before.to_vec();
    let more = bars_from_tempo(secs, bpm, n, 0.0, |a, b| 0.5 + 0.4 * ((a + b) * 0.37).sin()).expect("bars");
    for mut b in more {
        b.index = bars.len();
        b.start_secs += start;
        b.end_secs += start;
        bars.push(b);
    }
    bars
}

/// The pieces: real songs and the drum take as analysed, and made ones in 3/4, with a metre
/// change, and with a bar corrected to 3 beats.
fn pieces() -> Vec<(String, Vec<Bar>)> {
    let mut out = Vec::new();
    let dir = odori_tests::data_dir().join("music");
    let mut songs: Vec<String> = std::fs::read_dir(&dir)
        .unwrap_or_else(|e| panic!("cannot list {} (../shared/data is needed): {e}", dir.display()))
        .flatten()
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .filter(|n| n.ends_with(".ogg"))
        .collect();
    songs.sort();
    assert!(!songs.is_empty(), "no songs in {}", dir.display());
    for s in songs {
        let rel = format!("music/{s}");
        out.push((rel.clone(), song_bars(&rel)));
    }
    out.push(("drum take".into(), song_bars(music_audio::DRUMS)));
    out.push(("made, 3/4 at 108 BPM".into(), continue_bars(&[], 60.0, 108.0, 3)));
    let change = continue_bars(&continue_bars(&[], 30.0, 120.0, 4), 30.0, 120.0, 3);
    out.push(("made, 4/4 then 3/4".into(), continue_bars(&change, 16.0, 120.0, 4)));
    let mut corrected = continue_bars(&[], 60.0, 126.0, 4);
    corrected[7].beats = 3;
    corrected[8].beats = 3;
    corrected[20].beats = 3;
    out.push(("made, 4/4 with bars corrected to 3".into(), corrected));
    out
}

#[test]
fn tables_by_metre_give_main_s_costs_and_dances() {
    let lib = real_library();
    let counts: std::collections::BTreeSet<usize> = lib.segments().iter().map(|s| s.counts()).collect();
    assert!(counts.contains(&3) && counts.contains(&4), "the library should hold 3- and 4-count segments: {counts:?}");
    let penalty = FillWeights::default().repeat_penalty;
    let full = TransitionTable::from_library(&lib, penalty);
    let m = lib.len();
    println!("library: {m} segments ({} in 3 counts)", lib.segments().iter().filter(|s| s.counts() == 3).count());

    // Pair by pair: every block of a table with all four metre pairs, and pairs computed
    // outside the blocks (a table of the 4-count block only), bit for bit.
    let both = TableScope::for_metres(&[3, 4]).with_join(3, 4).with_join(4, 3);
    let blocks = TransitionTable::for_scope(&lib, penalty, &both);
    let four = TransitionTable::for_scope(&lib, penalty, &TableScope::for_metres(&[4]));
    assert!(four.stored_pairs() < full.stored_pairs());
    let mut checked = 0;
    for a in (0..m).step_by(3) {
        for b in (0..m).step_by(7) {
            assert_eq!(blocks.cost(a, b).to_bits(), full.cost(a, b).to_bits(), "C({a}, {b})");
            assert_eq!(four.cost(a, b).to_bits(), full.cost(a, b).to_bits(), "C({a}, {b}) outside the 4-count block");
            checked += 1;
        }
    }
    println!("{checked} pairs: same costs bit for bit");

    // Whole Generates: a copy of the library with the all-pairs table installed (main's), and
    // one that builds only what the song needs.
    for (name, bars) in pieces() {
        let with_full = lib.clone();
        assert!(with_full.install_table(full.clone()), "the all-pairs table is this library's");
        let scoped = lib.clone();
        let mut pinned = vec![BarState::Empty; bars.len()];
        if name.contains("corrected") {
            // A pinned bar in 3 among the corrected ones.
            let three = (0..m).find(|&s| lib.segments()[s].counts() == 3 && !lib.segments()[s].retired).expect("a 3-count segment");
            pinned[8] = BarState::Pinned { segment: three };
        }
        let generate = |lib: &SegmentLibrary| generate_states(lib, &bars, &pinned, FillWeights::default(), &GenerateOptions::default());
        let (a, ra) = generate(&with_full).expect("generate (all pairs)");
        let (b, rb) = generate(&scoped).expect("generate (by metre)");
        let used = scoped.cached_table(penalty).expect("a table cached");
        let need = TableScope::for_bar_counts(&bar_counts(&lib, &bars));
        println!(
            "{name}: {} bars, metres {:?}, table {} ({} of {} costs stored); cost {:.4} vs {:.4}",
            bars.len(),
            bar_counts(&lib, &bars).iter().collect::<std::collections::BTreeSet<_>>(),
            used.scope(),
            used.stored_pairs(),
            full.stored_pairs(),
            rb.cost,
            ra.cost
        );
        assert!(used.scope().covers(&need) && !used.scope().is_all_pairs() || need.is_all_pairs(), "{name}: built {} for {need}", used.scope());
        assert_eq!(a, b, "{name}: the dances differ");
        assert_eq!((ra.filled, ra.pinned, ra.cost.to_bits()), (rb.filled, rb.pinned, rb.cost.to_bits()), "{name}: the reports differ");
        assert!(b.iter().any(|s| matches!(s, BarState::Generated { .. })), "{name}: nothing generated");
    }
}

#[test]
fn the_cache_builds_the_blocks_new_bars_bring_in_and_refuses_other_tables() {
    let mut lib = real_library();
    let penalty = FillWeights::default().repeat_penalty;
    let m = lib.len();
    let (m3, m4) = (lib.segments().iter().filter(|s| s.counts() == 3).count(), lib.segments().iter().filter(|s| s.counts() == 4).count());
    let four = continue_bars(&[], 40.0, 120.0, 4);
    let scope4 = TableScope::for_bar_counts(&bar_counts(&lib, &four));
    assert_eq!(scope4, TableScope::for_metres(&[4]));

    // A 4/4 song: the 4-count block alone, in slices whose progress only grows.
    let mut b = lib.table_builder_for(penalty, &scope4);
    let mut fractions = Vec::new();
    while !b.step(64).is_done() {
        fractions.push(b.progress().fraction());
    }
    assert!(fractions.len() > 5 && fractions.windows(2).all(|w| w[0] < w[1]), "{fractions:?}");
    let t4 = b.finish().expect("table");
    assert_eq!(t4.stored_pairs(), m4 * m4);
    assert!(lib.install_table_for(t4.clone(), &scope4));
    assert!(lib.cached_table_for(penalty, &scope4).is_some());

    // New bars with a metre change: only the blocks missing are built (less work than all of
    // them), and the table holds the 4-count block too.
    let change = continue_bars(&continue_bars(&[], 20.0, 120.0, 4), 20.0, 120.0, 3);
    let scope = TableScope::for_bar_counts(&bar_counts(&lib, &change));
    assert_eq!(scope, TableScope::for_metres(&[3, 4]).with_join(4, 3));
    assert!(lib.cached_table_for(penalty, &scope).is_none(), "the 4-count table does not cover a 3/4 bar");
    // A table lacking the new blocks is refused for these bars.
    assert!(!lib.install_table_for(t4.clone(), &scope));
    let b = lib.table_builder_for(penalty, &scope);
    let all_new = odori_core::choreo::TableBuilder::for_scope(&lib, penalty, &scope, None);
    assert!(b.progress().total < all_new.progress().total, "the 4-count block is not built again");
    let mut b = b;
    while !b.step(256).is_done() {}
    let t = b.finish().expect("table");
    assert_eq!(t.stored_pairs(), m4 * m4 + m3 * m3 + m4 * m3);
    assert!(lib.install_table_for(t, &scope));
    let cached = lib.cached_table_for(penalty, &scope).expect("cached");
    // Its costs are the all-pairs table's on the blocks (bit for bit).
    let full = TransitionTable::from_library(&lib, penalty);
    for a in (0..m).step_by(11) {
        for b in (0..m).step_by(13) {
            assert_eq!(cached.cost(a, b).to_bits(), full.cost(a, b).to_bits());
        }
    }
    // Generate reads the cached table as it is (nothing more to build).
    generate_states(&lib, &change, &[], FillWeights::default(), &GenerateOptions::default()).expect("generate");
    assert!(std::sync::Arc::ptr_eq(&cached, &lib.cached_table(penalty).expect("still cached")));

    // A library change drops the table, and a table built before it is refused.
    let stale = lib.table_builder_for(penalty, &scope);
    let rel = all_bvh().into_iter().next().expect("a mocap clip");
    let imp = import_bytes(&rel, &read(&rel), &ImportOptions { fps_override: fps_override_for(&rel), ..Default::default() }).expect("import");
    lib.add_clip(&imp.clips[0], &imp.humanoid, &imp.status, &SegmentOptions::default()).expect("add");
    assert!(lib.cached_table(penalty).is_none(), "a library change drops the table");
    let mut stale = stale;
    while !stale.step(usize::MAX).is_done() {}
    assert!(!lib.install_table_for(stale.finish().expect("table"), &scope), "a table of another revision is refused");
    // And one of another library with the same segments count is refused too.
    let other = real_library();
    let t_other = TransitionTable::for_scope(&other, penalty, &scope);
    assert!(!lib.install_table(t_other));
}
