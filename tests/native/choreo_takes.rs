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

use odori_core::bars::Bar;
use odori_core::choreo::quality::{dance_quality, DanceQuality};
use odori_core::choreo::{bar_counts, GenerateOptions, RenderOptions, SegmentLibrary};
use odori_core::music::demo_song::{demo_song_with, DemoSongOptions};
use odori_core::music::{analyze, envelope, AnalysisOptions, RmsEnvelope};

fn songs() -> Vec<(String, RmsEnvelope)> {
    let mut out: Vec<(String, RmsEnvelope)> = music_audio::FULL_TRACKS
        .iter()
        .chain([&music_audio::TRUMPET, &music_audio::DRUMS])
        .map(|rel| (rel.to_string(), music_audio::decode_data(rel).envelope().unwrap_or_else(|e| panic!("{rel}: {e}"))))
        .collect();
    for (bpb, bpm) in [(4u32, 100.0f32), (3, 126.0)] {
        let song = demo_song_with(22050.0, &DemoSongOptions { beats_per_bar: bpb, bpm, end_bpm: bpm }).expect("demo song");
        out.push((format!("demo in {bpb}, {bpm} BPM"), envelope(&[&song.samples], 22050.0).expect("envelope")));
    }
    out
}

fn quality(lib: &SegmentLibrary, bars: &[Bar], beats: &[f32], choices: &[Option<usize>]) -> DanceQuality {
    let clip = odori_core::choreo::render(lib, bars, choices, &RenderOptions::default());
    dance_quality(&clip, bars, beats).expect("dance quality")
}

/// BAS-music of random dances on the same bars (each bar's own count; a fixed generator).
fn random_bas(lib: &SegmentLibrary, bars: &[Bar], beats: &[f32]) -> f32 {
    let live: Vec<Vec<usize>> = bar_counts(lib, bars).iter().map(|&n| lib.segments().iter().filter(|s| !s.retired && (n == 0 || s.counts() == n)).map(|s| s.index).collect()).collect();
    let draws = 5usize.max(100usize.div_ceil(bars.len().max(1)));
    let mut x = 0x9E37_79B9_7F4A_7C15u64;
    let mut sum = 0.0;
    for _ in 0..draws {
        let ch: Vec<Option<usize>> = (0..bars.len())
            .map(|b| {
                x = x.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
                Some(live[b][(x >> 33) as usize % live[b].len()])
            })
            .collect();
        sum += quality(lib, bars, beats, &ch).beats.bas_music;
    }
    sum / draws as f32
}

#[test]
fn five_takes_differ_in_half_the_bars_at_comparable_cost_on_the_beat() {
    let lib = SegmentLibrary::builtin();
    let mut failures = Vec::new();
    for (label, env) in songs() {
        let grid = analyze(&env, &AnalysisOptions::default()).unwrap_or_else(|e| panic!("{label}: {e}"));
        let (bars, beats) = (grid.bars.clone(), grid.beat_times_secs.clone());
        let random = random_bas(&lib, &bars, &beats);
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
