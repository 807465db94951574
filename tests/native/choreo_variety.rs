//! Variety (issue 26, `generate::variety_stage`) on real songs: with the built-in library alone,
//! on every song in ../shared/data/music, the drum take in ../shared/data/beats and demo pieces
//! (4/4 at 100 and 140 BPM and a 90 → 130 ramp; 3/4 at 150, 108 and 84 BPM), with the core's own
//! grid, Generate's dance has no step or arm pattern in more than a third of the bars and
//! distinct moves in at least 0.7 of them (4/4), no single move in more than a third of the bars
//! (3/4); a song of fewer than 3 bars has no such goal. The control, the same pipeline with the
//! stage off (`GenerateOptions::follow_variety`), breaks them (one arm pattern held 88–100 % of
//! the bars of every piece before the stage). The figures are printed by
//! `tests/bench/choreo_person.rs`.
//!
//! Ignored until it passes (issue 26 item 2 is unfinished): with the stage as it is, every 4/4
//! piece but the drum take still breaks a goal (2026-11-29; the figures it prints).

#[path = "music_audio.rs"]
mod music_audio;

use std::collections::BTreeMap;
use odori_core::choreo::{GenerateOptions, SegmentLibrary};
use odori_core::music::{analyze, AnalysisOptions};

/// The songs: every song in ../shared/data/music, the drum take, six demo pieces.
fn songs() -> Vec<(String, odori_core::music::RmsEnvelope)> {
    let demos = [(4u32, 100.0f32, 100.0f32), (4, 140.0, 140.0), (4, 90.0, 130.0), (3, 150.0, 150.0), (3, 108.0, 108.0), (3, 84.0, 84.0)];
    odori_tests::acceptance_songs(&music_audio::ACCEPTANCE_TRACKS, music_audio::decode_envelope, &demos)
}

/// The largest number of bars one key holds.
fn most<K: Ord>(keys: impl Iterator<Item = K>) -> usize {
    let mut m: BTreeMap<K, usize> = BTreeMap::new();
    for k in keys {
        *m.entry(k).or_default() += 1;
    }
    m.into_values().max().unwrap_or(0)
}

/// What breaks the variety goals in `chosen` (empty: none).
fn faults(lib: &SegmentLibrary, chosen: &[usize], beats_per_bar: usize) -> Vec<String> {
    let n = chosen.len();
    if n < 3 {
        return Vec::new();
    }
    let info: Vec<_> = chosen.iter().map(|&s| lib.segments()[s].builtin.expect("built-in")).collect();
    let third = n as f32 / 3.0 + 1e-4;
    let (step, arms, mv) = (most(info.iter().map(|m| m.step.name())), most(info.iter().map(|m| m.arms.name())), most(chosen.iter()));
    let mut distinct = chosen.to_vec();
    distinct.sort_unstable();
    distinct.dedup();
    let mut out = Vec::new();
    if mv as f32 > third {
        out.push(format!("one move in {mv} of {n} bars"));
    }
    if beats_per_bar == 4 {
        if step as f32 > third {
            out.push(format!("one step in {step} of {n} bars"));
        }
        if arms as f32 > third {
            out.push(format!("one arm pattern in {arms} of {n} bars"));
        }
        if (distinct.len() as f32) < 0.7 * n as f32 - 1e-4 {
            out.push(format!("{} distinct moves in {n} bars", distinct.len()));
        }
    }
    out
}

#[test]
#[ignore = "issue 26 item 2 unfinished: the variety stage does not yet keep these goals (see GenerateOptions::follow_variety)"]
fn no_step_arm_pattern_or_move_dominates_a_built_in_dance() {
    let lib = SegmentLibrary::builtin();
    let (mut failures, mut control_faults, mut pieces) = (Vec::new(), 0usize, 0usize);
    for (label, env) in songs() {
        let grid = analyze(&env, &AnalysisOptions::default()).unwrap_or_else(|e| panic!("{label}: {e}"));
        let dance = |options: &GenerateOptions| {
            let mut doc = odori_tests::Dance::new(grid.bars.clone());
            doc.generate_with(&lib, options).unwrap_or_else(|e| panic!("{label}: {e}"));
            doc.segments().into_iter().map(|s| s.expect("every bar filled")).collect::<Vec<usize>>()
        };
        let with = faults(&lib, &dance(&GenerateOptions { follow_variety: true, ..GenerateOptions::default() }), grid.beats_per_bar as usize);
        let without = faults(&lib, &dance(&GenerateOptions { follow_variety: false, ..GenerateOptions::default() }), grid.beats_per_bar as usize);
        println!("{label} ({} bars in {}): with the stage {with:?}; without {without:?}", grid.bars.len(), grid.beats_per_bar);
        if !with.is_empty() {
            failures.push(format!("{label}: {}", with.join(", ")));
        }
        pieces += usize::from(grid.bars.len() >= 3);
        control_faults += usize::from(!without.is_empty());
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
    // The control breaks the goals where the stage keeps them: the test can fail.
    assert!(control_faults * 2 >= pieces, "without the stage only {control_faults} of {pieces} pieces break the goals");
}
