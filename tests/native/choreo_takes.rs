//! Another take (issue 26, `GenerateOptions::take`) on real songs: on every song in
//! ../shared/data/music, the drum take in ../shared/data/beats and two demo pieces no setting
//! was tuned on (4/4 at 100 BPM, 3/4 at 126 BPM), with the core's own grid and the built-in
//! library, five takes of Generate (take 0 is `Project::generate`'s dance):
//! - every pair differs in at least half the bars, by more than a built-in move's side (take 1
//!   was every move of take 0 led by the other side on Sugar Plum and the 100 and 126 BPM demos,
//!   and so were takes 2 and 3 of the 100 BPM demo, until 2026-11-30);
//! - each take's objective (`GenerateReport::cost`, the same objective for every take, its
//!   variety term included) is within 10 % of the best take's;
//! - each take meets the beat goals of issue 26 (spec §J): BAS-music ≥ random moves' + 0.05
//!   (`odori_tests::random_moves_bas`) and ≥ the same dance on the half-shifted beats + 0.10,
//!   kinetic beats per count in 0.8–1.2 or 0.4–0.6;
//! - each take's joins within 1.5 as played (spec §J's join jump, `odori_tests::dance_quality_of`),
//!   take 0's included but for a piece listed where Generate's own dance misses it
//!   ([`KNOWN_TAKE_0_JOINS`]).
//! A song of fewer than 3 bars (the trumpet loop's one bar) is printed, not asserted: one bar has
//! no five dances of comparable cost (no other move is within 10 % of the best one), and its one
//! move is scored against random single moves. The figures are also printed by
//! `tests/bench/choreo_person.rs`.

#[path = "music_audio.rs"]
mod music_audio;

use odori_core::choreo::{GenerateOptions, SegmentLibrary};
use odori_core::music::{analyze, AnalysisOptions};
use odori_tests::{dance_quality_of as quality, random_moves_bas, RANDOM_MOVES_SEED_TAKES};

/// The songs: every song in ../shared/data/music, the drum take, two demo pieces.
fn songs() -> Vec<(String, odori_core::music::RmsEnvelope)> {
    odori_tests::acceptance_songs(&music_audio::ACCEPTANCE_TRACKS, music_audio::decode_envelope, &[(4, 100.0, 100.0), (3, 126.0, 126.0)])
}

/// Pieces whose takes miss a beat goal, listed with the rate alone (other goals asserted). None since
/// session 26. Before: Let's Go Fishin', kinetic beats per count 1.44–1.51 on
/// every take, take 0 (Generate's own dance) at 1.44 (2026-11-30; over random moves by +0.075 to
/// +0.123, so only the rate misses). Why: its bars run at 88.5 counts a minute, where the
/// built-in moves (made at 120) turn more often than once a count (at that rate their median is
/// 1.27 kinetic beats a count, 74 of 420 in the band); take 0's moves predict 1.20 but the dance
/// measures 1.44, and stage 2's beat-rate ladder finds no dance in the band, so take 0 misses
/// and the takes keep what take 0 met. Not the joins (session 20): each bar's move followed by
/// itself turns 1.43 a count there (the dance 1.438; a hard cut 1.41), a third of its kinetic
/// beats half a count off (the moves keyed on the half count turn on the "and" when played
/// slowly); the prediction mirrors each move at its ends and misses a turn at the bar line.
/// Built-in moves held on the counts met every goal here on all five takes but moved Vibe Ace's
/// joins past 1.5 (take 0 or 3), so were not kept then; session 26 added them (48: side touch,
/// slow grapevine, slow box, sway × presses, open and close) with stage 5's wider reach on:
/// Let's Go Fishin' turns 1.16–1.18 a count on all five takes, BAS-music 0.841–0.878 against
/// random 0.763, joins ≤ 0.96; Vibe Ace's takes join at 1.18–1.49. Tried in session 19 (not kept):
/// stage 2 aiming each move's predicted rate at 1 less the offset the first measure showed
/// (+0.235 a count) brings take 0 into the band (1.16 at the ladder's weight 0.45) but at
/// BAS-music 0.716 against random moves' 0.753 (take 1: 1.14, 0.732): the moves slow enough
/// there do not land on the counts, a rate traded for the beat alignment
/// (`docs/benchmarks-notes-choreo.md`, sessions 19 and 20). The ceiling for this listed miss is 1.6 (a
/// rate of 1.6 or more fails), its other beat goals are asserted, and a piece listed here whose
/// takes all meet the goals fails (unlist it).
const KNOWN_UNDER_MARGIN: &[&str] = &[];

/// Pieces whose take 0 (Generate's own dance, tested in `choreo_variety`) joins over 1.5, with
/// the ceiling of that listed miss. None since session 19: Vibe Ace's take 0 joined at 1.59
/// (stage 5's refills barring every rough join at once reached 1.43 but slid past the skate goal
/// the dance met, and the plain skate weights 0.1–0.4 moved no bar beside the variety term's ×3
/// beat term); with those weights scaled beside the fill's beat term
/// (`GenerateOptions::skate_beside_beat_term`, on) it joins at 1.47. A piece listed here whose
/// take 0 joins within 1.5 fails (unlist it).
const KNOWN_TAKE_0_JOINS: &[(&str, f32)] = &[];

#[test]
fn five_takes_differ_in_half_the_bars_at_comparable_cost_on_the_beat_with_smooth_joins() {
    let failures = five_takes();
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// A bar's move as the eye tells moves apart: a built-in move without its side, else the segment.
fn move_of(lib: &SegmentLibrary, s: Option<usize>) -> (Option<usize>, Option<odori_core::library::MoveInfo>) {
    match s.and_then(|s| lib.segments()[s].builtin) {
        Some(m) => (None, Some(odori_core::library::MoveInfo { mirrored: false, ..m })),
        None => (s, None),
    }
}

/// Five takes of every song: what breaks the differ, cost, beat and join goals.
fn five_takes() -> Vec<String> {
    let lib = SegmentLibrary::builtin();
    let mut failures = Vec::new();
    for (label, env) in songs() {
        let grid = analyze(&env, &AnalysisOptions::default()).unwrap_or_else(|e| panic!("{label}: {e}"));
        let (bars, beats) = (grid.bars.clone(), grid.beat_times_secs.clone());
        let random = random_moves_bas(&lib, &bars, &beats, RANDOM_MOVES_SEED_TAKES);
        let mut takes: Vec<(Vec<Option<usize>>, f32)> = Vec::new();
        // Whether a listed miss still occurs on this piece (a list that says more than is true
        // fails: the test then asserts what was fixed).
        let (mut rate_missed, mut take_0_join_missed) = (false, false);
        for take in 0..5 {
            let mut doc = odori_tests::Dance::new(bars.clone());
            let report = doc.generate_with(&lib, &GenerateOptions { take, ..GenerateOptions::default() }).unwrap_or_else(|e| panic!("{label} take {take}: {e}"));
            let chosen = doc.segments();
            if take == 0 {
                let mut plain = odori_tests::Dance::new(bars.clone());
                plain.generate(&lib).expect("generate");
                assert_eq!(plain.segments(), chosen, "{label}: take 0 is Generate's dance");
            }
            let q = quality(&lib, &bars, &beats, &chosen);
            let rate = q.beats.kinetic_beats_per_sec / q.beats.music_beats_per_sec.max(1e-6);
            let (over_random, over_shifted) = (q.beats.bas_music - random, q.beats.bas_music - q.beats.bas_music_shifted);
            println!("{label} take {take}: cost {:.3}, BAS-music {:.3} (random {random:.3}, shifted {:.3}), kinetic/song beats {rate:.2}, join max {:.2}", report.cost, q.beats.bas_music, q.beats.bas_music_shifted, q.join_jump_max);
            let goals = [over_random >= 0.05, over_shifted >= 0.10, (0.8..=1.2).contains(&rate) || (0.4..=0.6).contains(&rate)];
            // A known miss (KNOWN_UNDER_MARGIN): the rate alone, under 1.6. Printed; any other
            // piece, or any other goal missed, fails.
            let known = KNOWN_UNDER_MARGIN.iter().any(|k| label.contains(k)) && goals[0] && goals[1] && rate < 1.6;
            if bars.len() >= 3 && goals.contains(&false) && known {
                rate_missed = true;
                println!("  KNOWN MISS {label} take {take}: BAS-music − random {over_random:+.3} (goal +0.05), kinetic/song beats {rate:.2}");
            } else if bars.len() >= 3 && goals.contains(&false) {
                failures.push(format!("{label} take {take}: BAS-music − random {over_random:+.3}, − shifted {over_shifted:+.3}, kinetic/song beats {rate:.2}"));
            }
            let known_join = take == 0 && KNOWN_TAKE_0_JOINS.iter().any(|&(k, ceiling)| label.contains(k) && q.join_jump_max < ceiling);
            if bars.len() >= 3 && q.join_jump_max > 1.5 && known_join {
                take_0_join_missed = true;
                println!("  KNOWN MISS {label} take 0: join max {:.2} (goal 1.5; Generate's own dance)", q.join_jump_max);
            } else if bars.len() >= 3 && q.join_jump_max > 1.5 {
                failures.push(format!("{label} take {take}: join max {:.2} over 1.5", q.join_jump_max));
            }
            takes.push((chosen, report.cost));
        }
        if KNOWN_UNDER_MARGIN.iter().any(|k| label.contains(k)) && !rate_missed {
            failures.push(format!("{label}: listed in KNOWN_UNDER_MARGIN, but every take meets the beat goals: unlist it"));
        }
        if KNOWN_TAKE_0_JOINS.iter().any(|&(k, _)| label.contains(k)) && !take_0_join_missed {
            failures.push(format!("{label}: listed in KNOWN_TAKE_0_JOINS, but take 0 joins within 1.5: unlist it"));
        }
        let best = takes.iter().map(|t| t.1).fold(f32::INFINITY, f32::min);
        for (k, (a, cost)) in takes.iter().enumerate() {
            if bars.len() >= 3 && *cost > best * 1.1 + 1e-4 {
                failures.push(format!("{label} take {k}: objective {cost:.3} more than 10 % above the best take's {best:.3}"));
            }
            for (j, (b, _)) in takes.iter().enumerate().take(k) {
                // A bar differs when its move does by more than its side (a built-in move led by
                // the other side, mirrored, is the same move to the eye).
                let differ = a.iter().zip(b).filter(|(x, y)| move_of(&lib, **x) != move_of(&lib, **y)).count();
                if bars.len() >= 3 && 2 * differ < bars.len() {
                    failures.push(format!("{label}: takes {j} and {k} differ in {differ} of {} bars", bars.len()));
                }
            }
        }
    }
    failures
}
