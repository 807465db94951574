//! Issue #14, song: a nudge is a phase correction (more than a bar is refused, with the value),
//! a tempo needs four taps, and a song without a clear beat says so (`clearBeat: false`) instead
//! of presenting a confident grid. The clarity rule (a z-score ≥ 5 against the song's own
//! onsets shuffled in time) is checked on noise of several colours and seeds, synthetic pulse
//! tracks at several tempi, the demo song and every real recording in ../shared/data, and its
//! figures printed.

#[path = "music_audio.rs"]
mod music_audio;

use music_audio::*;
use odori_core::music::{analyze, demo_song, rms, AnalysisOptions, GridCorrection, MusicError, SongGrid};

fn corrected(g: &SongGrid, c: GridCorrection) -> Result<SongGrid, MusicError> {
    g.corrected(&c)
}

fn demo_grid() -> SongGrid {
    let d = demo_song(22050.0).unwrap();
    analyze(&rms::envelope(&[&d.samples], d.sample_rate_hz).unwrap(), &AnalysisOptions::default()).unwrap()
}

#[test]
fn a_nudge_of_more_than_a_bar_is_refused_and_the_grid_kept() {
    let tracked = demo_grid();
    let typed = corrected(&tracked, GridCorrection { bpm: Some(120.0), ..Default::default() }).unwrap();
    for (kind, g) in [("tracked", &tracked), ("typed", &typed)] {
        let bar = 60.0 * g.beats_per_bar as f32 / g.bpm;
        for nudge in [-5000.0f32, 5000.0, -(bar + 0.1), 1e9] {
            let e = corrected(g, GridCorrection { nudge_secs: Some(nudge), ..Default::default() }).unwrap_err();
            assert!(matches!(e, MusicError::NudgeTooFar { .. }), "{kind} {nudge}: {e:?}");
            let msg = e.to_string();
            assert!(msg.contains(&nudge.to_string()) && !msg.contains("finite"), "{kind}: {msg}");
        }
        // Control: nudges within a bar move the grid and keep it whole.
        for nudge in [0.01f32, -0.05, bar * 0.9] {
            let n = corrected(g, GridCorrection { nudge_secs: Some(nudge), ..Default::default() }).unwrap();
            assert!(n.bars.len() + 1 >= g.bars.len(), "{kind} {nudge}: {} of {} bars", n.bars.len(), g.bars.len());
        }
    }
}

#[test]
fn two_taps_are_not_a_tempo() {
    let g = demo_grid();
    for taps in [vec![0.0f32, 0.5], vec![0.0, 0.5, 1.0]] {
        let e = corrected(&g, GridCorrection { tap_times_secs: Some(taps.clone()), ..Default::default() }).unwrap_err();
        assert!(matches!(e, MusicError::TooFewTaps { min: 4, .. }), "{taps:?}: {e:?}");
    }
    let four = corrected(&g, GridCorrection { tap_times_secs: Some(vec![0.0, 0.5, 1.0, 1.5]), ..Default::default() }).unwrap();
    assert!((four.bpm - 120.0).abs() < 0.01);
}

/// `secs` of noise at 22.05 kHz: white, or integrated ("brown", leaky) for a low-heavy colour.
fn noise(seed: u64, secs: f32, brown: bool) -> Vec<f32> {
    let mut x = seed.max(1);
    let mut acc = 0.0f32;
    (0..(secs * 22050.0) as usize)
        .map(|_| {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            let w = ((x >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0) as f32;
            if brown {
                acc = acc * 0.995 + w * 0.1;
                acc
            } else {
                w * 0.3
            }
        })
        .collect()
}

/// A click track: decaying noise bursts on every beat at `bpm` over quiet noise.
fn clicks(bpm: f32, secs: f32) -> Vec<f32> {
    let bed = noise(7, secs, false);
    let period = 60.0 / bpm;
    bed.iter()
        .enumerate()
        .map(|(i, &n)| {
            let t = i as f32 / 22050.0;
            let since = t % period;
            n * (0.05 + 2.0 * (-since / 0.03).exp())
        })
        .collect()
}

fn grid_of(samples: &[f32]) -> SongGrid {
    analyze(&rms::envelope(&[samples], 22050.0).unwrap(), &AnalysisOptions::default()).unwrap()
}

#[test]
fn noise_has_no_clear_beat_and_music_has_one() {
    let mut rows = Vec::new();
    for seed in [1u64, 2, 3, 42] {
        for brown in [false, true] {
            let g = grid_of(&noise(seed, 30.0, brown));
            rows.push((format!("{} noise seed {seed}", if brown { "brown" } else { "white" }), g.bpm, g.beat_clarity.unwrap(), g.clear_beat));
            assert!(!g.clear_beat, "noise seed {seed} brown {brown}: clarity {:?} at {} BPM", g.beat_clarity, g.bpm);
        }
    }
    for bpm in [72.0f32, 100.0, 128.0, 174.0] {
        let g = grid_of(&clicks(bpm, 30.0));
        rows.push((format!("click track {bpm} BPM"), g.bpm, g.beat_clarity.unwrap(), g.clear_beat));
        assert!(g.clear_beat, "clicks at {bpm}: clarity {:?}", g.beat_clarity);
    }
    let g = demo_grid();
    rows.push(("demo song".into(), g.bpm, g.beat_clarity.unwrap(), g.clear_beat));
    assert!(g.clear_beat, "demo song: {:?}", g.beat_clarity);
    // A typed grid is not a guess.
    assert!(corrected(&g, GridCorrection { bpm: Some(90.0), ..Default::default() }).unwrap().clear_beat);
    for (name, bpm, z, clear) in rows {
        println!("{name:>24}: {bpm:6.1} BPM, clarity z {z:6.1}, clear beat {clear}");
    }
}

#[test]
fn real_recordings_with_a_beat_keep_it() {
    // Real data: every recording in ../shared/data with a steady beat must stay "clear"; the
    // solo trumpet (free time) is printed, not asserted.
    for rel in std::iter::once(DRUMS).chain(FULL_TRACKS).chain(std::iter::once(TRUMPET)) {
        let audio = decode_data(rel);
        let g = analyze(&audio.envelope().unwrap(), &AnalysisOptions::default()).unwrap();
        println!("{rel}: {:.1} BPM, clarity z {:.1}, clear beat {}", g.bpm, g.beat_clarity.unwrap(), g.clear_beat);
        if rel != TRUMPET {
            assert!(g.clear_beat, "{rel}: clarity {:?}", g.beat_clarity);
        }
    }
}
