//! Variety (issue 26 item 2, `choreo::variety`, `GenerateOptions::variety_weight`) on real
//! songs: with the built-in library alone, on every song in ../shared/data/music, the drum take
//! in ../shared/data/beats and demo pieces (4/4 at 100 and 140 BPM and a 90 → 130 ramp; 3/4 at
//! 150, 108 and 84 BPM), with the core's own grid. The control is the same pipeline with the term
//! off (`variety_weight: 0`), which holds one arm pattern in 88–100 % of the bars of every 4/4
//! piece.
//!
//! Asserted (`the_variety_term_meets_the_issue_goals_on_the_beat`), on every piece of 3 bars or
//! more, issue 26's goals: in 4/4 no step and no arm pattern in more than a third of the bars and
//! distinct moves ≥ 0.7 × bars; in 3/4 and 4/4 no move in more than a third; and every beat goal
//! of spec §J the control meets is still met (BAS-music ≥ random moves' + 0.05, ≥ half-shifted +
//! 0.10, kinetic beats per count in 0.8–1.2 or 0.4–0.6, join jump ≤ 1.5) — but for the known
//! misses listed below. The control breaks the step or arm limit on every 4/4 piece (so the test
//! can fail).
//!
//! What the goals took (2026-11-29): the window of 3 bars alone left the top arm pattern in
//! 41–50 % of the bars (an A B A B alternation of arm patterns pays only the decayed charge two
//! bars back, less than the rough joins of moving on), and higher weights lost the beat. The
//! term now also counts over the whole dance so far ([`odori_core::choreo::variety`]): a step or
//! arm pattern that would hold more than a third of the bars so far, or a move used before when
//! more than 0.3 of the bars so far already repeat one, is charged twice the weight.
//! `ODORI_VARIETY_WEIGHT=x` tries another weight (the assertions stay): at 0.2 and 0.35 every
//! share goal held as well (with the beat term ×2).

#[path = "music_audio.rs"]
mod music_audio;

use std::collections::BTreeMap;
use odori_core::bars::Bar;
use odori_core::choreo::generate::VARIETY_WEIGHT_DEFAULT;
use odori_core::choreo::{GenerateOptions, SegmentLibrary};
use odori_core::music::{analyze, AnalysisOptions};
use odori_tests::{random_moves_bas, RANDOM_MOVES_SEED};

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

/// How much of a dance (`chosen`, every bar) one kind holds: top step, top arm pattern, top move,
/// distinct moves, bars.
#[derive(Debug, Clone, Copy)]
struct Shares {
    step: usize,
    arms: usize,
    mv: usize,
    distinct: usize,
    n: usize,
}

fn shares(lib: &SegmentLibrary, chosen: &[usize]) -> Shares {
    let info: Vec<_> = chosen.iter().map(|&s| lib.segments()[s].builtin.expect("built-in")).collect();
    let mut distinct = chosen.to_vec();
    distinct.sort_unstable();
    distinct.dedup();
    Shares { step: most(info.iter().map(|m| m.step.name())), arms: most(info.iter().map(|m| m.arms.name())), mv: most(chosen.iter()), distinct: distinct.len(), n: chosen.len() }
}

/// Each piece: (label, beats per bar, the dance with the term and without, their shares and beat goals).
struct Piece {
    label: String,
    bpb: usize,
    on: (Shares, [bool; 4], String),
    off: (Shares, [bool; 4], String),
}

fn pieces(w: f32) -> Vec<Piece> {
    let lib = SegmentLibrary::builtin();
    let mut out = Vec::new();
    for (label, env) in songs() {
        let grid = analyze(&env, &AnalysisOptions::default()).unwrap_or_else(|e| panic!("{label}: {e}"));
        let (bars, beats) = (grid.bars.clone(), grid.beat_times_secs.clone());
        let dance = |options: &GenerateOptions| {
            let mut doc = odori_tests::Dance::new(bars.clone());
            doc.generate_with(&lib, options).unwrap_or_else(|e| panic!("{label}: {e}"));
            doc.segments().into_iter().map(|s| s.expect("every bar filled")).collect::<Vec<usize>>()
        };
        let (on, off) = (dance(&GenerateOptions { variety_weight: w, ..GenerateOptions::default() }), dance(&GenerateOptions { variety_weight: 0.0, ..GenerateOptions::default() }));
        let random = random_moves_bas(&lib, &bars, &beats, RANDOM_MOVES_SEED);
        let ((g_on, said_on), (g_off, said_off)) = (beat_goals(&lib, &bars, &beats, &on, random), beat_goals(&lib, &bars, &beats, &off, random));
        let piece = Piece { label, bpb: grid.beats_per_bar as usize, on: (shares(&lib, &on), g_on, said_on), off: (shares(&lib, &off), g_off, said_off) };
        println!("{} (in {}), weight {w}: with the term {:?}, {}; without {:?}, {}", piece.label, piece.bpb, piece.on.0, piece.on.2, piece.off.0, piece.off.2);
        out.push(piece);
    }
    out
}

/// The weight under test: the product's default, or `ODORI_VARIETY_WEIGHT`.
fn weight() -> f32 {
    std::env::var("ODORI_VARIETY_WEIGHT").ok().and_then(|v| v.parse().ok()).unwrap_or(VARIETY_WEIGHT_DEFAULT)
}

/// Which beat goals of spec §J a dance meets: over random moves, over the half-shifted beats,
/// the beat rate, the joins.
fn beat_goals(lib: &SegmentLibrary, bars: &[Bar], beats: &[f32], chosen: &[usize], random: f32) -> ([bool; 4], String) {
    let choices: Vec<Option<usize>> = chosen.iter().map(|&s| Some(s)).collect();
    let q = odori_tests::dance_quality_of(lib, bars, beats, &choices);
    let rate = q.beats.kinetic_beats_per_sec / q.beats.music_beats_per_sec.max(1e-6);
    let goals = [q.beats.bas_music >= random + 0.05, q.beats.bas_music >= q.beats.bas_music_shifted + 0.10, (0.8..=1.2).contains(&rate) || (0.4..=0.6).contains(&rate), q.join_jump_max <= 1.5];
    (goals, format!("BAS-music {:.3} (random {random:.3}, shifted {:.3}), beat rate {rate:.2}, join max {:.2}", q.beats.bas_music, q.beats.bas_music_shifted, q.join_jump_max))
}

/// Pieces where the term loses a beat goal the control meets. None since session 19: Vibe Ace
/// joined at 1.59 with the term (the control 1.47; listed since 2026-11-29) until stage 5's skate
/// weights were scaled beside the fill's beat term (`GenerateOptions::skate_beside_beat_term`):
/// 1.47 now. At the default weight, a piece listed here that meets its goal (or whose control
/// misses it) fails: unlist it.
const KNOWN_LOST_GOALS: &[(&str, usize)] = &[];

#[test]
fn the_variety_term_meets_the_issue_goals_on_the_beat() {
    let w = weight();
    let mut failures = Vec::new();
    let names = ["BAS-music ≥ random + 0.05", "BAS-music ≥ shifted + 0.10", "beat rate in 0.8–1.2 or 0.4–0.6", "join jump ≤ 1.5"];
    let (mut control_faults, mut counted) = (0, 0);
    for p in pieces(w) {
        let (on, off) = (p.on.0, p.off.0);
        // A listed miss the dance now meets fails (at the default weight, the one the list is
        // of): the list says only what is true.
        for &(_, g) in KNOWN_LOST_GOALS.iter().filter(|(k, _)| w == VARIETY_WEIGHT_DEFAULT && p.label.contains(k)) {
            if p.on.1[g] || !p.off.1[g] {
                failures.push(format!("{}: listed in KNOWN_LOST_GOALS for '{}', which it no longer loses ({}; without the term {}): unlist it", p.label, names[g], p.on.2, p.off.2));
            }
        }
        for g in 0..4 {
            if p.off.1[g] && !p.on.1[g] {
                let known = KNOWN_LOST_GOALS.iter().any(|&(k, kg)| p.label.contains(k) && kg == g);
                let what = format!("{}: the term lost '{}': {} (without it {})", p.label, names[g], p.on.2, p.off.2);
                if known {
                    println!("  KNOWN MISS {what}");
                } else {
                    failures.push(what);
                }
            }
        }
        if on.n < 3 {
            continue;
        }
        let third = on.n as f32 / 3.0 + 1e-4;
        if on.mv as f32 > third {
            failures.push(format!("{}: one move in {} of {} bars", p.label, on.mv, on.n));
        }
        if p.bpb == 4 {
            counted += 1;
            control_faults += usize::from(off.step as f32 > third || off.arms as f32 > third);
            if on.step as f32 > third {
                failures.push(format!("{}: one step in {} of {} bars", p.label, on.step, on.n));
            }
            if on.arms as f32 > third {
                failures.push(format!("{}: one arm pattern in {} of {} bars (without the term {})", p.label, on.arms, on.n, off.arms));
            }
            if (on.distinct as f32) < 0.7 * on.n as f32 - 1e-4 {
                failures.push(format!("{}: {} distinct moves in {} bars (without the term {})", p.label, on.distinct, on.n, off.distinct));
            }
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
    // The control breaks what the term keeps: the test can fail.
    assert!(control_faults == counted && counted > 0, "without the term only {control_faults} of {counted} pieces in 4/4 break the step or arm limit");
}
