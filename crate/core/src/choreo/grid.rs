//! Bars from a stated tempo: the grid a choreography can be made on before (or without) the
//! song analysis, e.g. for a song whose tempo the person knows.

use serde::{Deserialize, Serialize};
use thiserror::Error;

use crate::bars::Bar;

#[derive(Debug, Error, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "camelCase")]
pub enum GridError {
    #[error("tempo {bpm} BPM is outside {min}..={max}", min = super::MIN_MOVE_BPM, max = super::MAX_MOVE_BPM)]
    BadTempo { bpm: f32 },
    #[error("the song is {duration_secs:.2} s long after the first downbeat at {first_downbeat_secs:.2} s, shorter than one bar of {bar_secs:.2} s: there is no bar to dance")]
    ShorterThanABar { duration_secs: f32, first_downbeat_secs: f32, bar_secs: f32 },
    #[error("beats per bar must be 1..=16, got {beats_per_bar}")]
    BadBeatsPerBar { beats_per_bar: usize },
}

/// Whole bars of `beats_per_bar` beats at `bpm` from `first_downbeat_secs` to the end of a song
/// of `duration_secs`. `intensity(start, end)` gives each bar's music intensity (0..1).
pub fn bars_from_tempo(
    duration_secs: f32,
    bpm: f32,
    beats_per_bar: usize,
    first_downbeat_secs: f32,
    intensity: impl Fn(f32, f32) -> f32,
) -> Result<Vec<Bar>, GridError> {
    if !(super::MIN_MOVE_BPM..=super::MAX_MOVE_BPM).contains(&bpm) {
        return Err(GridError::BadTempo { bpm });
    }
    if !(1..=16).contains(&beats_per_bar) {
        return Err(GridError::BadBeatsPerBar { beats_per_bar });
    }
    let bar_secs = beats_per_bar as f32 * 60.0 / bpm;
    let first = first_downbeat_secs.max(0.0);
    let count = if duration_secs.is_finite() { ((duration_secs - first) / bar_secs + 1e-4).floor() } else { 0.0 };
    if count < 1.0 {
        return Err(GridError::ShorterThanABar { duration_secs, first_downbeat_secs: first, bar_secs });
    }
    Ok((0..count as usize)
        .map(|i| {
            // Each bar ends where the next starts, to the bit (`start + bar_secs` could end a bar
            // an ulp past the next one's start, and that bar's window then held the next bar's
            // first count).
            let start_secs = first + i as f32 * bar_secs;
            let end_secs = first + (i + 1) as f32 * bar_secs;
            Bar { index: i, start_secs, end_secs, intensity: intensity(start_secs, end_secs).clamp(0.0, 1.0), beats: beats_per_bar as u32 }
        })
        .collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn whole_bars_only() {
        let bars = bars_from_tempo(10.0, 120.0, 4, 0.5, |_, _| 0.5).unwrap();
        assert_eq!(bars.len(), 4);
        assert!((bars[3].end_secs - 8.5).abs() < 1e-5);
        assert!(matches!(bars_from_tempo(1.5, 120.0, 4, 0.0, |_, _| 0.5), Err(GridError::ShorterThanABar { .. })));
    }

    #[test]
    fn each_bar_ends_where_the_next_starts_to_the_bit() {
        // Over tempi and first downbeats where `start + bar_secs` (the rule before) ends some
        // bar an ulp off the next bar's start: the control counts them, so the test can fail.
        let (mut checked, mut off_before) = (0, 0);
        for tenth_bpm in (600..=2000).step_by(7) {
            let bpm = tenth_bpm as f32 / 10.0;
            for first in [0.0f32, 0.137, 0.5, 1.03] {
                let bars = bars_from_tempo(300.0, bpm, 4, first, |_, _| 0.5).unwrap();
                let bar_secs = 4.0 * 60.0 / bpm;
                for w in bars.windows(2) {
                    assert_eq!(w[0].end_secs.to_bits(), w[1].start_secs.to_bits(), "{bpm} BPM from {first} s, bar {}", w[0].index);
                    off_before += usize::from((w[0].start_secs + bar_secs).to_bits() != w[1].start_secs.to_bits());
                    checked += 1;
                }
            }
        }
        assert!(off_before > 100, "the rule before ended only {off_before} of {checked} bars off the next start: the test would not catch it");
    }
}
