//! The song's grid (beats, downbeats, bars with intensity) and its corrections. Every
//! correction is a pure function from a grid to a new grid: cheap (no re-analysis, linear in
//! the number of beats and loudness frames), so the UI can re-derive bars while the user drags.
//!
//! Two kinds of grid exist: a *tracked* grid (beats where the analysis heard them, with the
//! player's micro-timing) and a *regular* grid (metronomic beats at a BPM over the whole song),
//! which is what a typed or tapped BPM produces. Shifting or re-barring keeps the kind.

use serde::{Deserialize, Serialize};

use super::MusicError;
use crate::bars::Bar;

/// The slowest tempo a grid may have, BPM.
pub const MIN_GRID_BPM: f32 = 20.0;
/// The fastest tempo a grid may have, BPM.
pub const MAX_GRID_BPM: f32 = 400.0;
/// The longest song a regular grid may span, seconds (twice the analysis limit).
pub const MAX_GRID_SECS: f32 = 2.0 * super::MAX_ANALYSIS_SECS;
/// The most beats a bar may have.
pub const MAX_BEATS_PER_BAR: u32 = 16;

/// The song's loudness over time: the full-band RMS envelope divided by its maximum (0..=1).
/// Bars take their intensity from it, and the UI can draw it as the waveform view.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "camelCase")]
pub struct LoudnessCurve {
    /// Seconds between values; value `n` is at `n · hop_secs`.
    pub hop_secs: f32,
    pub values: Vec<f32>,
}

impl LoudnessCurve {
    /// The full-band RMS scaled by its maximum (all zeros stay zeros).
    pub fn from_rms(hop_secs: f32, rms: &[f32]) -> Self {
        let peak = rms.iter().copied().fold(0.0f32, f32::max);
        let values = if peak > 0.0 { rms.iter().map(|v| v / peak).collect() } else { rms.to_vec() };
        Self { hop_secs, values }
    }

    /// Mean value over frames centred in `[start_secs, end_secs)`; the nearest frame's value
    /// when the span holds none.
    pub fn mean_over(&self, start_secs: f32, end_secs: f32) -> f32 {
        if self.values.is_empty() || self.hop_secs <= 0.0 {
            return 0.0;
        }
        let last = self.values.len() - 1;
        let lo = ((start_secs / self.hop_secs).ceil().max(0.0) as usize).min(last);
        let hi = ((end_secs / self.hop_secs).ceil().max(0.0) as usize).min(self.values.len());
        match self.values.get(lo..hi) {
            Some(s) if !s.is_empty() => s.iter().sum::<f32>() / s.len() as f32,
            _ => self.values[lo],
        }
    }
}

/// The song's beat grid: what analysis produces and what the user corrects.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "camelCase")]
pub struct SongGrid {
    /// Length of the analysed audio, seconds.
    pub duration_secs: f32,
    /// Tempo, beats per minute (for a tracked grid: the least-squares slope of the beats).
    pub bpm: f32,
    /// Beats per bar (4 unless corrected).
    pub beats_per_bar: u32,
    /// Beat times, seconds, increasing, all in `[0, duration_secs)`.
    pub beat_times_secs: Vec<f32>,
    /// Index in `beat_times_secs` of the first downbeat (`< beats_per_bar`); beats before it are
    /// a pickup that belongs to no bar.
    pub first_downbeat_index: usize,
    /// Time of the first downbeat, seconds.
    pub first_downbeat_secs: f32,
    /// Every downbeat: `beat_times_secs[first_downbeat_index + k · beats_per_bar]`.
    pub downbeat_times_secs: Vec<f32>,
    /// One bar per downbeat. A bar ends at the next downbeat; the last one ends `beats_per_bar`
    /// beats later at the period of the song's last beats, clipped to the song's end (dropped
    /// when less than half of it remains), and `beat_times_secs` holds every beat of it.
    pub bars: Vec<Bar>,
    /// True for a metronomic grid made from a typed or tapped BPM; false for tracked beats.
    pub regular: bool,
    /// The loudness curve bars take their intensity from.
    pub loudness: LoudnessCurve,
    /// For an analysed grid: how clearly the song beats at this tempo ([`super::tempo::pulse_clarity`],
    /// a z-score against the same song's onsets shuffled in time). `None` for a typed or tapped
    /// grid.
    #[serde(default)]
    pub beat_clarity: Option<f32>,
    /// False when the analysis found no clear beat (`beat_clarity` below
    /// [`super::tempo::MIN_CLEAR_BEAT_Z`]): the grid is a guess, and the person is told to
    /// type or tap the tempo. True for typed or tapped grids.
    #[serde(default = "yes")]
    pub clear_beat: bool,
}

fn yes() -> bool {
    true
}

/// A user's correction of the grid, as the UI sends it; fields left out keep their value.
/// Applied in this order: tempo (`bpm`, else `tap_times_secs`), then `beats_per_bar`, then
/// `first_downbeat_secs`, then `nudge_secs`.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "camelCase", default)]
pub struct GridCorrection {
    /// A typed tempo: the grid becomes regular at this BPM, keeping the first downbeat.
    pub bpm: Option<f32>,
    /// Tap-tempo times, seconds (any clock): their tempo is used as `bpm`.
    pub tap_times_secs: Option<Vec<f32>>,
    pub beats_per_bar: Option<u32>,
    /// Where a bar should start: the beat nearest to it becomes a downbeat and the whole grid
    /// moves by the remaining offset.
    pub first_downbeat_secs: Option<f32>,
    /// Moves every beat by this many seconds (positive = later).
    pub nudge_secs: Option<f32>,
}

fn check_bpm(bpm: f32) -> Result<(), MusicError> {
    if bpm.is_finite() && (MIN_GRID_BPM..=MAX_GRID_BPM).contains(&bpm) {
        Ok(())
    } else {
        Err(MusicError::BpmOutOfRange { bpm, min_bpm: MIN_GRID_BPM, max_bpm: MAX_GRID_BPM })
    }
}

fn check_beats_per_bar(beats_per_bar: u32) -> Result<(), MusicError> {
    if (1..=MAX_BEATS_PER_BAR).contains(&beats_per_bar) {
        Ok(())
    } else {
        Err(MusicError::BadBeatsPerBar { beats_per_bar, max: MAX_BEATS_PER_BAR })
    }
}

/// Fewest taps that make a tempo: two taps are one interval, which says nothing about whether
/// the person kept time; four give three intervals whose median rejects one stray tap.
pub const MIN_TAPS: usize = 4;

fn check_time(what: &'static str, time_secs: f32) -> Result<(), MusicError> {
    if time_secs.is_finite() {
        Ok(())
    } else {
        Err(MusicError::BadTime { what, time_secs })
    }
}

/// The tempo of tap-tempo taps: taps are numbered by the median interval (so a missed tap
/// counts as two intervals), then the BPM is 60 over the least-squares slope of time against
/// tap number. Needs at least [`MIN_TAPS`] increasing, finite taps.
pub fn bpm_from_taps(tap_times_secs: &[f32]) -> Result<f32, MusicError> {
    if tap_times_secs.len() < MIN_TAPS {
        return Err(MusicError::TooFewTaps { taps: tap_times_secs.len(), min: MIN_TAPS });
    }
    for (index, w) in tap_times_secs.windows(2).enumerate() {
        if !(w[0].is_finite() && w[1].is_finite() && w[1] > w[0]) {
            return Err(MusicError::TapsNotIncreasing { index: index + 1, time_secs: w[1] });
        }
    }
    let mut intervals: Vec<f64> = tap_times_secs.windows(2).map(|w| f64::from(w[1] - w[0])).collect();
    intervals.sort_by(f64::total_cmp);
    let median = intervals[intervals.len() / 2];
    let t0 = f64::from(tap_times_secs[0]);
    let points: Vec<(f64, f64)> =
        tap_times_secs.iter().map(|&t| (((f64::from(t) - t0) / median).round(), f64::from(t) - t0)).collect();
    let n = points.len() as f64;
    let mx = points.iter().map(|p| p.0).sum::<f64>() / n;
    let my = points.iter().map(|p| p.1).sum::<f64>() / n;
    let sxx: f64 = points.iter().map(|p| (p.0 - mx).powi(2)).sum();
    let sxy: f64 = points.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
    let period = if sxx > 0.0 { sxy / sxx } else { median };
    let bpm = (60.0 / period) as f32;
    check_bpm(bpm)?;
    Ok(bpm)
}

/// The tempo of a beat sequence: 60 over the least-squares slope of time against beat number.
pub(crate) fn bpm_of_beats(beat_times_secs: &[f32]) -> Option<f32> {
    if beat_times_secs.len() < 2 {
        return None;
    }
    let n = beat_times_secs.len() as f64;
    let mx = (n - 1.0) / 2.0;
    let my = beat_times_secs.iter().map(|&t| f64::from(t)).sum::<f64>() / n;
    let (mut sxx, mut sxy) = (0.0, 0.0);
    for (i, &t) in beat_times_secs.iter().enumerate() {
        sxx += (i as f64 - mx).powi(2);
        sxy += (i as f64 - mx) * (f64::from(t) - my);
    }
    (sxy > 0.0).then(|| (60.0 * sxx / sxy) as f32)
}

impl SongGrid {
    /// The beat period at the end of `beats`, seconds: the mean of the last `bpb` intervals (the
    /// last bar's tempo, which a tempo-following tracker may have moved from the song's mean);
    /// `60 / bpm` with fewer than two beats.
    fn closing_period_secs(beats: &[f32], bpb: usize, bpm: f32) -> f32 {
        let n = beats.len();
        if n < 2 {
            return 60.0 / bpm;
        }
        let k = bpb.min(n - 1);
        (beats[n - 1] - beats[n - 1 - k]) / k as f32
    }

    /// Assembles a grid from beats and a bar phase, deriving downbeats and bars. `bpm` is the
    /// tempo used to extend the last bar when fewer than two beats are known.
    pub(crate) fn assemble(
        duration_secs: f32,
        bpm: f32,
        beats_per_bar: u32,
        beat_times_secs: Vec<f32>,
        first_downbeat_index: usize,
        regular: bool,
        loudness: LoudnessCurve,
    ) -> Self {
        let bpb = beats_per_bar.max(1) as usize;
        let first = first_downbeat_index % bpb;
        let mut beat_times_secs = beat_times_secs;
        let downbeats: Vec<f32> = beat_times_secs.iter().skip(first).step_by(bpb).copied().collect();
        let mut bars = Vec::with_capacity(downbeats.len());
        for (k, &start_secs) in downbeats.iter().enumerate() {
            let next = beat_times_secs.get(first + (k + 1) * bpb).copied();
            let end_secs = match next {
                Some(end) => end,
                // The last downbeat: the beats stop inside its bar (the song ends, or a held
                // note or a fade gives the tracker nothing to follow).
                None => {
                    let period_secs = Self::closing_period_secs(&beat_times_secs, bpb, bpm);
                    let bar_secs = bpb as f32 * period_secs;
                    if duration_secs - start_secs < 0.5 * bar_secs {
                        continue;
                    }
                    let end_secs = (start_secs + bar_secs).min(duration_secs);
                    // The bar keeps all its beats, at the period the last ones had: the dance
                    // puts a count on each of them, and the §J measures score every beat of
                    // every bar (without them a one-bar song counted 2 beats in a bar of 4).
                    let downbeat_index = first + k * bpb;
                    for i in (beat_times_secs.len() - downbeat_index)..bpb {
                        let t = start_secs + i as f32 * period_secs;
                        if t >= end_secs - 1e-4 || t >= duration_secs {
                            break;
                        }
                        beat_times_secs.push(t);
                    }
                    end_secs
                }
            };
            bars.push(Bar { index: bars.len(), start_secs, end_secs, intensity: loudness.mean_over(start_secs, end_secs), beats: bpb as u32 });
        }
        // Intensity: mean loudness scaled to the song's range (spec §D): the quietest bar is 0,
        // the loudest 1; all bars equal -> 0.5.
        let lo = bars.iter().map(|b| b.intensity).fold(f32::INFINITY, f32::min);
        let hi = bars.iter().map(|b| b.intensity).fold(f32::NEG_INFINITY, f32::max);
        for b in &mut bars {
            b.intensity = if hi - lo > 1e-9 { ((b.intensity - lo) / (hi - lo)).clamp(0.0, 1.0) } else { 0.5 };
        }
        Self {
            duration_secs,
            bpm,
            beats_per_bar: bpb as u32,
            first_downbeat_secs: downbeats.first().copied().unwrap_or(0.0),
            beat_times_secs,
            first_downbeat_index: first,
            downbeat_times_secs: downbeats,
            bars,
            regular,
            loudness,
            beat_clarity: None,
            clear_beat: true,
        }
    }

    /// A metronomic grid over `[0, duration_secs)`: beats every `60 / bpm` seconds with a
    /// downbeat at `first_downbeat_secs` (any time; earlier beats are added back to 0). This is
    /// also the manual fallback when analysis fails (e.g. a clip too short to analyse).
    pub fn regular(
        duration_secs: f32,
        bpm: f32,
        first_downbeat_secs: f32,
        beats_per_bar: u32,
        loudness: LoudnessCurve,
    ) -> Result<Self, MusicError> {
        check_bpm(bpm)?;
        check_beats_per_bar(beats_per_bar)?;
        if !(duration_secs.is_finite() && duration_secs > 0.0 && duration_secs <= MAX_GRID_SECS) {
            return Err(MusicError::BadTime { what: "song duration", time_secs: duration_secs });
        }
        // Any downbeat within a song length of the song is meaningful; further out is a bug.
        if !(first_downbeat_secs.is_finite() && first_downbeat_secs.abs() <= duration_secs + 60.0) {
            return Err(MusicError::BadTime { what: "first downbeat", time_secs: first_downbeat_secs });
        }
        let period = 60.0 / f64::from(bpm);
        let anchor = f64::from(first_downbeat_secs);
        // Index (relative to the anchor) of the first beat at or after 0.
        let k0 = (-anchor / period).ceil() as i64;
        let k1 = ((f64::from(duration_secs) - anchor) / period).ceil() as i64;
        let beats: Vec<f32> = (k0..k1).map(|k| (anchor + k as f64 * period) as f32).filter(|&t| t >= 0.0 && t < duration_secs).collect();
        let first = (-(k0 % i64::from(beats_per_bar))).rem_euclid(i64::from(beats_per_bar)) as usize;
        Ok(Self::assemble(duration_secs, bpm, beats_per_bar, beats, first, true, loudness))
    }

    /// The manual grid for a song analysis could not handle (too short, no pulse): a regular
    /// grid over the envelope's length, with bar intensity from its band 0 (full-band RMS).
    pub fn manual(
        envelope: &super::RmsEnvelope,
        bpm: f32,
        first_downbeat_secs: f32,
        beats_per_bar: u32,
    ) -> Result<Self, MusicError> {
        let full = envelope.bands.first().map_or(&[][..], Vec::as_slice);
        let loudness = LoudnessCurve::from_rms(envelope.hop_secs, full);
        Self::regular(envelope.duration_secs(), bpm, first_downbeat_secs, beats_per_bar, loudness)
    }

    /// Re-derives downbeats and bars after the beats or bar settings changed.
    fn rebuilt(&self, beats: Vec<f32>, first_downbeat_index: usize, beats_per_bar: u32) -> Self {
        Self::assemble(self.duration_secs, self.bpm, beats_per_bar, beats, first_downbeat_index, self.regular, self.loudness.clone())
    }

    /// A regular grid at `bpm` that keeps the current first downbeat.
    pub fn with_bpm(&self, bpm: f32) -> Result<Self, MusicError> {
        Self::regular(self.duration_secs, bpm, self.first_downbeat_secs, self.beats_per_bar, self.loudness.clone())
    }

    /// [`SongGrid::with_bpm`] at the tempo of tap-tempo taps ([`bpm_from_taps`]).
    pub fn with_tap_tempo(&self, tap_times_secs: &[f32]) -> Result<Self, MusicError> {
        self.with_bpm(bpm_from_taps(tap_times_secs)?)
    }

    /// The same beats and first downbeat, with `beats_per_bar` beats in a bar.
    pub fn with_beats_per_bar(&self, beats_per_bar: u32) -> Result<Self, MusicError> {
        check_beats_per_bar(beats_per_bar)?;
        Ok(self.rebuilt(self.beat_times_secs.clone(), self.first_downbeat_index, beats_per_bar))
    }

    /// Moves every beat by `delta_secs`. A tracked grid loses beats that leave the song; a
    /// regular grid is regenerated so it still covers the whole song.
    pub fn nudged(&self, delta_secs: f32) -> Result<Self, MusicError> {
        check_time("nudge", delta_secs)?;
        if self.regular {
            return Self::regular(
                self.duration_secs,
                self.bpm,
                self.first_downbeat_secs + delta_secs,
                self.beats_per_bar,
                self.loudness.clone(),
            );
        }
        let dropped = self.beat_times_secs.iter().take_while(|&&t| t + delta_secs < 0.0).count();
        let beats: Vec<f32> =
            self.beat_times_secs.iter().map(|&t| t + delta_secs).filter(|&t| t >= 0.0 && t < self.duration_secs).collect();
        let first = (self.first_downbeat_index as i64 - dropped as i64).rem_euclid(i64::from(self.beats_per_bar.max(1)));
        Ok(self.rebuilt(beats, first as usize, self.beats_per_bar))
    }

    /// Makes a bar start at `time_secs`: the beat nearest to it becomes a downbeat and the whole
    /// grid moves by the remaining offset (so dropping it on a beat only changes the bar phase,
    /// and dropping it between beats also shifts the beats).
    pub fn with_first_downbeat(&self, time_secs: f32) -> Result<Self, MusicError> {
        check_time("first downbeat", time_secs)?;
        let Some((nearest, &beat)) =
            self.beat_times_secs.iter().enumerate().min_by(|a, b| (a.1 - time_secs).abs().total_cmp(&(b.1 - time_secs).abs()))
        else {
            return Self::regular(self.duration_secs, self.bpm, time_secs, self.beats_per_bar, self.loudness.clone());
        };
        let phased = self.rebuilt(self.beat_times_secs.clone(), nearest, self.beats_per_bar);
        phased.nudged(time_secs - beat)
    }

    /// Applies a [`GridCorrection`] (see its docs for the order).
    pub fn corrected(&self, correction: &GridCorrection) -> Result<Self, MusicError> {
        let mut grid = match (correction.bpm, &correction.tap_times_secs) {
            (Some(bpm), _) => self.with_bpm(bpm)?,
            (None, Some(taps)) => self.with_tap_tempo(taps)?,
            (None, None) => self.clone(),
        };
        if let Some(n) = correction.beats_per_bar {
            grid = grid.with_beats_per_bar(n)?;
        }
        if let Some(t) = correction.first_downbeat_secs {
            grid = grid.with_first_downbeat(t)?;
        }
        if let Some(d) = correction.nudge_secs {
            // A nudge corrects the grid's phase: within a bar every phase is reachable, so a
            // larger one is a mistake (it would push the grid out of the song and empty it).
            check_time("nudge", d)?;
            let bar_secs = 60.0 * grid.beats_per_bar as f32 / grid.bpm;
            if d.abs() > bar_secs {
                return Err(MusicError::NudgeTooFar { nudge_secs: d, max_secs: bar_secs });
            }
            grid = grid.nudged(d)?;
        }
        Ok(grid)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn flat(duration_secs: f32) -> LoudnessCurve {
        LoudnessCurve { hop_secs: 0.01, values: vec![0.5; (duration_secs * 100.0) as usize] }
    }

    #[test]
    fn regular_grid_covers_the_song_with_the_downbeat_where_asked() {
        let g = SongGrid::regular(10.0, 120.0, 1.25, 4, flat(10.0)).unwrap();
        assert_eq!(g.beat_times_secs.first().copied(), Some(0.25));
        assert!(g.beat_times_secs.iter().all(|&t| (0.0..10.0).contains(&t)));
        assert!((g.first_downbeat_secs - 1.25).abs() < 1e-5);
        assert_eq!(g.first_downbeat_index, 2);
        for w in g.bars.windows(2) {
            assert!((w[0].end_secs - w[1].start_secs).abs() < 1e-5);
            assert!((w[0].duration_secs() - 2.0).abs() < 1e-4);
        }
        // Bars: 1.25, 3.25, 5.25, 7.25 and 9.25 is dropped (less than half a bar left).
        assert_eq!(g.bars.len(), 4);
    }

    #[test]
    fn tap_tempo_survives_jitter_and_a_missed_tap() {
        let taps = [0.0f32, 0.51, 0.99, 1.5, 2.52, 3.0];
        let bpm = bpm_from_taps(&taps).unwrap();
        assert!((bpm - 120.0).abs() < 2.0, "{bpm}");
        assert!(matches!(bpm_from_taps(&[1.0]), Err(MusicError::TooFewTaps { taps: 1, .. })));
        assert!(matches!(bpm_from_taps(&[1.0, 0.5, 2.0, 3.0]), Err(MusicError::TapsNotIncreasing { index: 1, .. })));
        assert!(matches!(bpm_from_taps(&[0.0, 10.0, 20.0, 30.0]), Err(MusicError::BpmOutOfRange { .. })));
    }

    #[test]
    fn first_downbeat_snaps_to_a_beat_or_shifts_the_grid() {
        let g = SongGrid::regular(20.0, 120.0, 0.0, 4, flat(20.0)).unwrap();
        let snapped = g.with_first_downbeat(1.02).unwrap();
        assert!((snapped.first_downbeat_secs - 1.02).abs() < 1e-4, "{}", snapped.first_downbeat_secs);
        assert_eq!(snapped.first_downbeat_index, 2);
        let shifted = g.with_first_downbeat(0.25).unwrap();
        assert!((shifted.beat_times_secs[0] - 0.25).abs() < 1e-5);
        assert_eq!(shifted.first_downbeat_index, 0);
        // A tracked grid keeps its beats and changes only the phase when dropped on a beat.
        let tracked = SongGrid { regular: false, ..g.clone() };
        let t = tracked.with_first_downbeat(1.5).unwrap();
        assert_eq!(t.beat_times_secs, tracked.beat_times_secs);
        assert_eq!(t.first_downbeat_index, 3);
    }

    #[test]
    fn corrections_compose_and_reject_bad_values() {
        let g = SongGrid::regular(30.0, 100.0, 0.3, 4, flat(30.0)).unwrap();
        let c = GridCorrection { bpm: Some(150.0), beats_per_bar: Some(3), ..Default::default() };
        let h = g.corrected(&c).unwrap();
        assert_eq!(h.bpm, 150.0);
        assert_eq!(h.beats_per_bar, 3);
        assert!((h.bars[0].duration_secs() - 1.2).abs() < 1e-4);
        assert!((h.first_downbeat_secs - 0.3).abs() < 1e-5);
        assert!(g.with_bpm(f32::NAN).is_err());
        assert!(g.with_beats_per_bar(0).is_err());
        assert!(g.nudged(f32::INFINITY).is_err());
        assert!(SongGrid::regular(30.0, 100.0, 1e30, 4, flat(30.0)).is_err());
        assert!(SongGrid::regular(1e30, 100.0, 0.0, 4, flat(30.0)).is_err());
        // Far nudges leave a tracked grid empty rather than failing or hanging.
        let far = SongGrid { regular: false, ..g.clone() }.nudged(1e9).unwrap();
        assert!(far.beat_times_secs.is_empty() && far.bars.is_empty());
        // Typing a BPM then restores a grid over the whole song.
        assert_eq!(far.with_bpm(120.0).unwrap().beat_times_secs.len(), 60);
        let tracked = SongGrid { regular: false, ..g.clone() };
        let n = tracked.nudged(-0.5).unwrap();
        // The first beat falls off the start; the rest move; the room the nudge leaves at the
        // end goes to the last bar's beats (a bar keeps all its beats).
        let moved: Vec<f32> = g.beat_times_secs[1..].iter().map(|t| t - 0.5).collect();
        assert!(n.beat_times_secs.len() >= moved.len());
        assert!(moved.iter().zip(&n.beat_times_secs).all(|(a, b)| (a - b).abs() < 1e-4));
        let last_bar = n.bars.last().unwrap();
        assert!(n.beat_times_secs[moved.len()..].iter().all(|&t| t >= last_bar.start_secs && t < last_bar.end_secs));
        assert!((n.first_downbeat_secs - tracked.downbeat_times_secs[1] + 0.5).abs() < 1e-5);
    }

    #[test]
    fn the_last_bar_keeps_its_beats_when_the_tracker_stops_inside_it() {
        // Tracked beats every 0.6 s that stop at 3.0 s, in a song of 5 s: the bar from the
        // downbeat at 2.4 s runs four beats of 0.6 s to 4.8 s and holds beats at 3.6 and 4.2 s
        // that the tracker did not give (a held note at the end of a solo).
        let beats: Vec<f32> = (0..6).map(|i| 0.6 * i as f32).collect();
        let g = SongGrid::assemble(5.0, 90.0, 4, beats.clone(), 0, false, flat(5.0));
        assert_eq!(g.bars.len(), 2);
        let last = g.bars[1];
        assert!((last.start_secs - 2.4).abs() < 1e-5 && (last.end_secs - 4.8).abs() < 1e-4, "{last:?}");
        assert_eq!(g.beat_times_secs.len(), 8, "{:?}", g.beat_times_secs);
        assert!((g.beat_times_secs[6] - 3.6).abs() < 1e-4 && (g.beat_times_secs[7] - 4.2).abs() < 1e-4);
        // At the period of the last beats (0.6 s), not the song's mean tempo (90 BPM: 0.67 s).
        // Rebuilding the grid (any correction) adds nothing more.
        let again = g.with_beats_per_bar(4).unwrap();
        assert_eq!(again.beat_times_secs, g.beat_times_secs);
        assert_eq!(again.bars, g.bars);
        // Clipped to the song: a 4.5 s song keeps the bar to its end and no beat past it.
        let short = SongGrid::assemble(4.5, 90.0, 4, beats, 0, false, flat(4.5));
        assert!((short.bars[1].end_secs - 4.5).abs() < 1e-5);
        assert!(short.beat_times_secs.iter().all(|&t| t < 4.5) && short.beat_times_secs.len() == 8);
    }

    #[test]
    fn json_field_names_are_the_javascript_contract() {
        let g = SongGrid::regular(4.0, 120.0, 0.0, 4, flat(4.0)).unwrap();
        let v = serde_json::to_value(&g).unwrap();
        for key in [
            "durationSecs",
            "bpm",
            "beatsPerBar",
            "beatTimesSecs",
            "firstDownbeatIndex",
            "firstDownbeatSecs",
            "beatClarity",
            "clearBeat",
            "downbeatTimesSecs",
            "bars",
            "regular",
            "loudness",
        ] {
            assert!(v.get(key).is_some(), "{key}");
        }
        assert!(v["bars"][0].get("startSecs").is_some() && v["loudness"].get("hopSecs").is_some());
        // A correction from JavaScript may leave out any field.
        let c: GridCorrection = serde_json::from_str(r#"{"tapTimesSecs":[0,0.5,1.0,1.5],"nudgeSecs":null}"#).unwrap();
        assert_eq!(c.tap_times_secs, Some(vec![0.0, 0.5, 1.0, 1.5]));
        assert_eq!(c.bpm, None);
        assert_eq!(g.corrected(&c).unwrap().bpm, 120.0);
    }

    #[test]
    fn bar_intensity_spans_the_song_range() {
        let mut loud = flat(16.0);
        for v in &mut loud.values[800..] {
            *v = 1.0;
        }
        for v in &mut loud.values[..400] {
            *v = 0.1;
        }
        let g = SongGrid::regular(16.0, 120.0, 0.0, 4, loud).unwrap();
        let i: Vec<f32> = g.bars.iter().map(|b| b.intensity).collect();
        assert_eq!(i.len(), 8);
        assert_eq!(i[0], 0.0);
        assert_eq!(i[7], 1.0);
        assert!(i[2] > 0.3 && i[2] < 0.6, "{i:?}");
    }
}
