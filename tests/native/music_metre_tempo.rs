//! Issue #15, the grid: metre detection (3/4 vs 4/4) and beats that follow a changing tempo,
//! on variants of the demo song whose true grid is exact by construction (a waltz, tempo ramps
//! up and down), each against a control (the analysis held to 4 beats per bar, or to one
//! steady period), plus the 4/4 demo song, which must stay in 4.

#[path = "music_audio.rs"]
mod music_audio;

use music_audio::*;
use odori_core::music::demo_song::{demo_song_with, DemoSong, DemoSongOptions};
use odori_core::music::{analyze, envelope, f_measure, AnalysisOptions, SongGrid};

const TOLERANCE_SECS: f32 = 0.07;

fn render(beats_per_bar: u32, bpm: f32, end_bpm: f32) -> DemoSong {
    demo_song_with(22050.0, &DemoSongOptions { beats_per_bar, bpm, end_bpm }).expect("render")
}

fn analyse(song: &DemoSong, options: &AnalysisOptions) -> SongGrid {
    let env = envelope(&[&song.samples], song.sample_rate_hz).expect("envelope");
    analyze(&env, options).expect("analysis")
}

/// (beat F, downbeat F) of a grid against the song's true grid.
fn scores(g: &SongGrid, song: &DemoSong) -> (f32, f32) {
    (
        f_measure(&g.beat_times_secs, &song.beat_times_secs(), TOLERANCE_SECS),
        f_measure(&g.downbeat_times_secs, &song.downbeat_times_secs(), TOLERANCE_SECS),
    )
}

/// The largest error, relative, of the tempo the found beats imply (60 / interval) against the
/// true tempo at the nearest true beat, over the middle 80 % of the song (the median of every
/// 5 intervals, so one misplaced beat does not decide it).
fn worst_local_tempo_error(g: &SongGrid, song: &DemoSong) -> f32 {
    let truth = song.beat_times_secs();
    let tempi = song.tempo_at_beats_bpm();
    let b = &g.beat_times_secs;
    let (lo, hi) = (b.len() / 10, b.len() * 9 / 10);
    let mut worst = 0.0f32;
    for i in lo..hi.saturating_sub(5) {
        let mut intervals: Vec<f32> = (i..i + 5).map(|k| b[k + 1] - b[k]).collect();
        intervals.sort_by(f32::total_cmp);
        let found = 60.0 / intervals[2];
        let k = truth.partition_point(|&t| t < b[i + 2]).min(tempi.len() - 1);
        worst = worst.max((found / tempi[k] - 1.0).abs());
    }
    worst
}

#[test]
fn a_waltz_is_found_in_three() {
    for bpm in [96.0f32, 150.0] {
        let song = render(3, bpm, bpm);
        let g = analyse(&song, &AnalysisOptions::default());
        let (beat_f, downbeat_f) = scores(&g, &song);
        // Control: the same analysis told 4 beats per bar (what every song got before).
        let four = analyse(&song, &AnalysisOptions { beats_per_bar: 4, ..Default::default() });
        let (_, four_downbeat_f) = scores(&four, &song);
        println!(
            "waltz {bpm} BPM: metre {} (true 3), {:.2} BPM, beat F {beat_f:.3}, downbeat F {downbeat_f:.3} (held to 4: {four_downbeat_f:.3})",
            g.beats_per_bar, g.bpm
        );
        assert_eq!(g.beats_per_bar, 3, "{bpm} BPM waltz");
        assert!(beat_f >= 0.95, "{bpm}: beat F {beat_f}");
        assert!(downbeat_f >= 0.9, "{bpm}: downbeat F {downbeat_f}");
        assert!(downbeat_f > four_downbeat_f + 0.3, "{bpm}: 3 beats per bar must beat the 4/4 control");
        // The person can still correct the metre.
        let corrected = g.with_beats_per_bar(4).expect("correct to 4");
        assert_eq!(corrected.beats_per_bar, 4);
        // The same beats; any beat added completes the last bar of 4 (a bar keeps all its beats).
        let n = g.beat_times_secs.len();
        assert_eq!(corrected.beat_times_secs[..n], g.beat_times_secs[..]);
        let last = corrected.bars.last().expect("bars");
        assert!(corrected.beat_times_secs.len() - n < 4 && corrected.beat_times_secs[n..].iter().all(|&t| t > last.start_secs && t < last.end_secs));
    }
}

#[test]
fn four_four_stays_in_four() {
    for bpm in [100.0f32, 120.0, 140.0] {
        let song = render(4, bpm, bpm);
        let g = analyse(&song, &AnalysisOptions::default());
        let (beat_f, downbeat_f) = scores(&g, &song);
        println!("4/4 {bpm} BPM: metre {}, {:.2} BPM, beat F {beat_f:.3}, downbeat F {downbeat_f:.3}", g.beats_per_bar, g.bpm);
        assert_eq!(g.beats_per_bar, 4, "{bpm} BPM 4/4");
        assert!(beat_f >= 0.95 && downbeat_f >= 0.9, "{bpm}: beat F {beat_f}, downbeat F {downbeat_f}");
    }
}

#[test]
fn beats_follow_a_tempo_ramp() {
    for (bpb, from, to) in [(4u32, 100.0f32, 140.0f32), (4, 135.0, 105.0), (3, 150.0, 120.0)] {
        let song = render(bpb, from, to);
        let g = analyse(&song, &AnalysisOptions::default());
        let (beat_f, downbeat_f) = scores(&g, &song);
        let error = worst_local_tempo_error(&g, &song);
        // Control: one steady period for the whole song.
        let steady = analyse(&song, &AnalysisOptions { follow_tempo: false, ..Default::default() });
        let (steady_beat_f, steady_downbeat_f) = scores(&steady, &song);
        println!(
            "ramp {from}->{to} BPM in {bpb}: metre {}, beat F {beat_f:.3}, downbeat F {downbeat_f:.3}, worst local tempo error {:.1} % \
             (steady control: beat F {steady_beat_f:.3}, downbeat F {steady_downbeat_f:.3})",
            g.beats_per_bar,
            error * 100.0
        );
        assert_eq!(g.beats_per_bar, bpb, "{from}->{to}: metre");
        assert!(beat_f >= 0.95, "{from}->{to}: beat F {beat_f}");
        assert!(downbeat_f >= 0.9, "{from}->{to}: downbeat F {downbeat_f}");
        assert!(error <= 0.03, "{from}->{to}: local tempo off by {error}");
        assert!(beat_f > steady_beat_f, "{from}->{to}: following the tempo must beat the steady control");
    }
}

#[test]
fn real_recordings_keep_their_grids() {
    // The drum take (4/4, steady 138 BPM): the brief's goals, and the detection must not move it.
    let audio = decode_data(DRUMS);
    let env = audio.envelope().expect("envelope");
    let g = analyze(&env, &AnalysisOptions::default()).expect("analysis");
    let (beats, downbeats) = read_beats(DRUMS_BEATS);
    let beat_f = f_measure(&g.beat_times_secs, &beats, TOLERANCE_SECS);
    let downbeat_f = f_measure(&g.downbeat_times_secs, &downbeats, TOLERANCE_SECS);
    println!("drums: metre {}, {:.2} BPM, beat F {beat_f:.3}, downbeat F {downbeat_f:.3}", g.beats_per_bar, g.bpm);
    assert_eq!(g.beats_per_bar, 4);
    assert!(beat_f >= 0.95 && downbeat_f >= 0.90, "drums: beat F {beat_f}, downbeat F {downbeat_f}");
    // The songs: metre found, and how far following the tempo moved the beats from one steady
    // period (the share of beats within 70 ms of the steady tracker's).
    for rel in FULL_TRACKS.iter().chain([&TRUMPET]) {
        let env = decode_data(rel).envelope().expect("envelope");
        let g = analyze(&env, &AnalysisOptions::default()).unwrap_or_else(|e| panic!("{rel}: {e}"));
        let steady = analyze(&env, &AnalysisOptions { follow_tempo: false, ..Default::default() }).expect("steady");
        let agree = f_measure(&g.beat_times_secs, &steady.beat_times_secs, TOLERANCE_SECS);
        println!("{rel}: metre {}, {:.2} BPM, {} bars; agreement with one steady period F {agree:.3}", g.beats_per_bar, g.bpm, g.bars.len());
        assert!((3..=4).contains(&g.beats_per_bar), "{rel}: metre {}", g.beats_per_bar);
    }
}
