//! Another take (issue 26, `GenerateOptions::take`) on real songs: on every song in
//! ../shared/data/music, the drum take in ../shared/data/beats and two demo pieces no setting
//! was tuned on (4/4 at 100 BPM, 3/4 at 126 BPM), with the core's own grid and the built-in
//! library, five takes of Generate differ pairwise in at least half the bars, each take's
//! objective (`GenerateReport::cost`, the same objective for every take) is within
//! 10 % of the best take's (these two on songs of 3 bars or more: on the trumpet loop's one bar,
//! no other move is within 10 % of take 0's shortest path, and take 0's stages raise its cost
//! above take 4's, 0.095 against 0.062), and each take meets every beat goal of spec §J that take 0 meets:
//! BAS-music ≥ random moves' + 0.05 (mean of at least 5 random dances on the same bars, 100 bars
//! in all) and ≥ the same dance on the half-shifted beats + 0.10, kinetic beats per count in
//! 0.75–1.25 or 0.375–0.625 (with the built-in library alone, take 0 misses some on the one-bar
//! trumpet loop and on the piece in 3, which no built-in move is made for). Take 0 is
//! `Project::generate`'s dance. The figures are printed by `tests/bench/choreo_person.rs`.

#[path = "music_audio.rs"]
mod music_audio;

use odori_core::choreo::{GenerateOptions, SegmentLibrary};
use odori_core::music::{analyze, AnalysisOptions};
use odori_tests::{dance_quality_of as quality, random_moves_bas, RANDOM_MOVES_SEED_TAKES};

/// The songs: every song in ../shared/data/music, the drum take, two demo pieces.
fn songs() -> Vec<(String, odori_core::music::RmsEnvelope)> {
    odori_tests::acceptance_songs(&music_audio::ACCEPTANCE_TRACKS, music_audio::decode_envelope, &[(4, 100.0, 100.0), (3, 126.0, 126.0)])
}

#[test]
fn five_takes_differ_in_half_the_bars_at_comparable_cost_on_the_beat() {
    let lib = SegmentLibrary::builtin();
    let mut failures = Vec::new();
    for (label, env) in songs() {
        let grid = analyze(&env, &AnalysisOptions::default()).unwrap_or_else(|e| panic!("{label}: {e}"));
        let (bars, beats) = (grid.bars.clone(), grid.beat_times_secs.clone());
        let random = random_moves_bas(&lib, &bars, &beats, RANDOM_MOVES_SEED_TAKES);
        let mut takes: Vec<(Vec<Option<usize>>, f32)> = Vec::new();
        let mut goals0 = [false; 3];
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
            println!("{label} take {take}: cost {:.3}, BAS-music {:.3} (random {random:.3}, shifted {:.3}), kinetic/song beats {rate:.2}", report.cost, q.beats.bas_music, q.beats.bas_music_shifted);
            let goals = [over_random >= 0.05, over_shifted >= 0.10, (0.75..=1.25).contains(&rate) || (0.375..=0.625).contains(&rate)];
            if take == 0 {
                goals0 = goals;
            }
            if (0..3).any(|g| goals0[g] && !goals[g]) {
                failures.push(format!("{label} take {take}: BAS-music − random {over_random:+.3}, − shifted {over_shifted:+.3}, kinetic/song beats {rate:.2}"));
            }
            takes.push((chosen, report.cost));
        }
        let best = takes.iter().map(|t| t.1).fold(f32::INFINITY, f32::min);
        for (k, (a, cost)) in takes.iter().enumerate() {
            if bars.len() >= 3 && *cost > best * 1.1 + 1e-4 {
                failures.push(format!("{label} take {k}: objective {cost:.3} more than 10 % above the best take's {best:.3}"));
            }
            for (j, (b, _)) in takes.iter().enumerate().take(k) {
                let differ = a.iter().zip(b).filter(|(x, y)| x != y).count();
                if bars.len() >= 3 && 2 * differ < bars.len() {
                    failures.push(format!("{label}: takes {j} and {k} differ in {differ} of {} bars", bars.len()));
                }
            }
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}
