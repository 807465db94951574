//! Song analysis (spec §D): from the banded RMS envelope the host computes with WebAudio
//! ([`rms`]) to tempo, beats, downbeats and bars with intensity ([`SongGrid`]), plus the grid
//! corrections the user makes ([`grid`]), the song's sections ([`mod@sections`]), the product's own demo song ([`mod@demo_song`]) and the
//! beat-tracking evaluation measure ([`eval`]).
//!
//! The pipeline of [`analyze`]: onset strength per band (log RMS flux, [`onset`]) → global tempo
//! (autocorrelation comb over beat and bar lags with a log-normal prior around 120 BPM, and a
//! whole-bars preference for short loops, [`tempo`]) → beats by dynamic programming (Ellis 2007,
//! [`beats`], following a changing tempo through a local-tempo path when the tempo is not
//! steady, [`tempo::local_periods`]) → bar phase from the kick (low band) and backbeat (mid band) accents
//! ([`downbeats`]), with the metre (3 or 4 beats per bar) found from how the beat accents repeat
//! unless the caller fixes it → bars whose intensity is the mean full-band RMS scaled to the song's range.
//! All steps are deterministic and linear (or linear times the beat period) in the number of
//! frames: a 3-minute song takes a few tens of milliseconds natively.

pub mod beats;
pub mod demo_song;
pub mod downbeats;
pub mod eval;
pub mod grid;
pub mod onset;
pub mod rms;
pub mod sections;
pub mod tempo;

use serde::{Deserialize, Serialize};
use thiserror::Error;

pub use demo_song::{demo_song, DemoSong};
pub use eval::f_measure;
pub use grid::{bpm_from_taps, GridCorrection, LoudnessCurve, SongGrid};
pub use rms::{envelope, RmsEnvelope, STANDARD_BANDS};
pub use sections::{sections, Section, SectionError, SectionOptions, Sections};

/// The shortest audio [`analyze`] accepts, seconds (a few bars at slow tempi are needed to see
/// a tempo; shorter clips get a grid from [`SongGrid::regular`]).
pub const MIN_ANALYSIS_SECS: f32 = 3.0;
/// The longest audio [`analyze`] accepts, seconds (two hours).
pub const MAX_ANALYSIS_SECS: f32 = 7200.0;
/// Audio no longer than this, seconds, is taken to be a loop: tempos at which it holds a whole
/// number of bars are preferred (see [`tempo::TempoSettings::loop_bars`]).
pub const LOOP_MAX_SECS: f32 = 12.0;
/// With at least this many tracked beats the reported tempo is their least-squares slope;
/// with fewer, the tempo estimator's own value.
const MIN_BEATS_FOR_SLOPE: usize = 8;
/// Full-band RMS below this everywhere (−80 dBFS) counts as silence.
pub const SILENCE_RMS: f32 = 1e-4;

/// Everything that can go wrong in song analysis, with the offending values.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum MusicError {
    #[error("no audio: the envelope or PCM is empty")]
    Empty,
    #[error("envelope hop {hop_secs} s is outside 0.005..=0.05 s")]
    BadHop { hop_secs: f32 },
    #[error("envelope band {band} has {frames} frames, band 0 has {expected}")]
    RaggedBands { band: usize, frames: usize, expected: usize },
    #[error("envelope band {band} frame {frame} holds {value}, not a finite RMS value >= 0")]
    BadValue { band: usize, frame: usize, value: f32 },
    #[error("channel {channel} has {samples} samples, channel 0 has {expected}")]
    RaggedChannels { channel: usize, samples: usize, expected: usize },
    #[error("sample rate {sample_rate_hz} Hz is not supported (minimum {min_hz} Hz)")]
    BadSampleRate { sample_rate_hz: f32, min_hz: f32 },
    #[error("sample {sample} of the mono mix is not a finite number")]
    NonFiniteSample { sample: usize },
    #[error("the song is {duration_secs:.2} s long; analysis needs at least {min_secs} s (set the grid by hand instead)")]
    TooShort { duration_secs: f32, min_secs: f32 },
    #[error("the song is {duration_secs:.0} s long; analysis takes at most {max_secs} s")]
    TooLong { duration_secs: f32, max_secs: f32 },
    #[error("the song is silent (loudest RMS {peak_rms:e}, threshold {threshold:e})")]
    Silent { peak_rms: f32, threshold: f32 },
    #[error("no steady beat found in the song (set the tempo by hand or by tapping)")]
    NoPulse,
    #[error("tempo {bpm} BPM is outside {min_bpm}..={max_bpm}")]
    BpmOutOfRange { bpm: f32, min_bpm: f32, max_bpm: f32 },
    #[error("{beats_per_bar} beats per bar: must be 1..={max}")]
    BadBeatsPerBar { beats_per_bar: u32, max: u32 },
    #[error("{what} time {time_secs} s is not a finite number")]
    BadTime { what: &'static str, time_secs: f32 },
    #[error("a nudge of {nudge_secs} s is more than a bar ({max_secs:.3} s): nudge by less than a bar, or set the first downbeat or the tempo")]
    NudgeTooFar { nudge_secs: f32, max_secs: f32 },
    #[error("tap tempo needs at least {min} taps, got {taps}")]
    TooFewTaps { taps: usize, min: usize },
    #[error("tap {index} at {time_secs} s is not later than the tap before it")]
    TapsNotIncreasing { index: usize, time_secs: f32 },
    #[error("analysis option {what} = {value} is invalid")]
    BadOption { what: &'static str, value: f32 },
}

/// Settings of [`analyze`]. The defaults suit popular music and dance.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "camelCase", default)]
pub struct AnalysisOptions {
    /// Beats per bar of the result; 0 (the default) detects it (3 or 4, 4 when unsure,
    /// [`downbeats::detect_metre`]).
    pub beats_per_bar: u32,
    /// Slowest tempo considered, BPM.
    pub min_bpm: f32,
    /// Fastest tempo considered, BPM.
    pub max_bpm: f32,
    /// Most likely tempo a priori (centre of a log-normal prior), BPM.
    pub prior_bpm: f32,
    /// Width of the prior, octaves (standard deviation of log2 tempo).
    pub prior_octaves: f32,
    /// How strongly beats keep to the period (Ellis's α; higher = steadier).
    pub tightness: f32,
    /// Let the beat period follow a changing tempo (default true); false keeps one period for
    /// the whole song.
    pub follow_tempo: bool,
}

impl Default for AnalysisOptions {
    fn default() -> Self {
        Self { beats_per_bar: 0, min_bpm: 50.0, max_bpm: 220.0, prior_bpm: 120.0, prior_octaves: 0.9, tightness: 1000.0, follow_tempo: true }
    }
}

impl AnalysisOptions {
    fn validate(&self) -> Result<(), MusicError> {
        let bad = |what, value: f32| Err(MusicError::BadOption { what, value });
        // 0 asks for detection.
        if self.beats_per_bar > grid::MAX_BEATS_PER_BAR {
            return Err(MusicError::BadBeatsPerBar { beats_per_bar: self.beats_per_bar, max: grid::MAX_BEATS_PER_BAR });
        }
        if !(self.min_bpm.is_finite() && self.min_bpm >= grid::MIN_GRID_BPM) {
            return bad("minBpm", self.min_bpm);
        }
        if !(self.max_bpm.is_finite() && self.max_bpm <= grid::MAX_GRID_BPM && self.max_bpm > self.min_bpm) {
            return bad("maxBpm", self.max_bpm);
        }
        if !(self.prior_bpm.is_finite() && self.prior_bpm > 0.0) {
            return bad("priorBpm", self.prior_bpm);
        }
        if !(self.prior_octaves.is_finite() && self.prior_octaves > 0.0) {
            return bad("priorOctaves", self.prior_octaves);
        }
        if !(self.tightness.is_finite() && self.tightness >= 0.0) {
            return bad("tightness", self.tightness);
        }
        Ok(())
    }
}

/// Analyses a song's RMS envelope into a beat grid with bars (spec §D).
///
/// Band use: with several bands (the host's [`STANDARD_BANDS`]), band 0 is the loudness used
/// for silence detection and bar intensity, bands 1.. feed onset strength, and bands 1 (low)
/// and 2 (mid) the downbeat accents. With a single band, it serves every purpose.
///
/// Clips no longer than [`LOOP_MAX_SECS`] are treated as loops (a whole number of bars long).
///
/// Errors: a malformed envelope ([`RmsEnvelope::validate`]), bad options, audio shorter than
/// [`MIN_ANALYSIS_SECS`] or longer than [`MAX_ANALYSIS_SECS`], silence, or no steady pulse.
pub fn analyze(envelope: &RmsEnvelope, options: &AnalysisOptions) -> Result<SongGrid, MusicError> {
    envelope.validate()?;
    options.validate()?;
    let duration_secs = envelope.duration_secs();
    if duration_secs < MIN_ANALYSIS_SECS {
        return Err(MusicError::TooShort { duration_secs, min_secs: MIN_ANALYSIS_SECS });
    }
    if duration_secs > MAX_ANALYSIS_SECS {
        return Err(MusicError::TooLong { duration_secs, max_secs: MAX_ANALYSIS_SECS });
    }
    let full = &envelope.bands[rms::BAND_FULL];
    let peak_rms = full.iter().copied().fold(0.0f32, f32::max);
    if peak_rms < SILENCE_RMS {
        return Err(MusicError::Silent { peak_rms, threshold: SILENCE_RMS });
    }
    let band_count = envelope.bands.len();
    let (onset_bands, low_band, mid_band): (Vec<usize>, usize, usize) = if band_count >= 2 {
        ((1..band_count).collect(), rms::BAND_LOW, rms::BAND_MID.min(band_count - 1))
    } else {
        (vec![0], 0, 0)
    };
    let onsets = onset::onset_strength(envelope, &onset_bands, low_band, mid_band);
    let fps = 1.0 / envelope.hop_secs;
    let settings = tempo::TempoSettings {
        min_bpm: options.min_bpm,
        max_bpm: options.max_bpm,
        prior_bpm: options.prior_bpm,
        prior_octaves: options.prior_octaves,
        // A loop of unknown metre is judged in 4 (the common case; 3 is found afterwards).
        loop_bars: (duration_secs <= LOOP_MAX_SECS).then_some((duration_secs, if options.beats_per_bar == 0 { 4 } else { options.beats_per_bar })),
    };
    let candidates = tempo::tempo_candidates(&onsets.total, fps, &settings);
    let first = candidates.first().ok_or(MusicError::NoPulse)?;
    // A changing tempo: first the metrical level judged window by window (a ramp can make the
    // song-wide comb prefer the double tempo), then the local periods at that level.
    let (level_bpm, local) = if options.follow_tempo && tempo::local_periods(&onsets.total, fps, first.bpm).is_some() {
        let level_bpm = tempo::local_level(&onsets.total, fps, first.bpm, &settings);
        (level_bpm, tempo::local_periods(&onsets.total, fps, level_bpm))
    } else {
        (first.bpm, None)
    };
    let period_frames = match &local {
        Some(periods) => periods.iter().sum::<f32>() / periods.len() as f32,
        None => 60.0 * fps / level_bpm,
    };
    let beat_frames = match &local {
        Some(periods) => beats::track_beats_varying(&onsets.total, periods, options.tightness),
        None => beats::track_beats(&onsets.total, period_frames, options.tightness),
    };
    if beat_frames.len() < 2 {
        return Err(MusicError::NoPulse);
    }
    let beats_per_bar = match options.beats_per_bar {
        0 => downbeats::detect_metre(&beat_frames, &[&onsets.low, &onsets.mid, &onsets.total], period_frames).0 as u32,
        n => n,
    };
    let (phase, _confidence) =
        downbeats::bar_phase(&beat_frames, &onsets.low, &onsets.mid, period_frames, beats_per_bar as usize);
    let beat_times_secs: Vec<f32> = beat_frames.iter().map(|&f| f as f32 * envelope.hop_secs).collect();
    // The tracked beats measure the tempo more finely than the 0.5 % comb steps, once there are
    // enough of them to average out the player's timing.
    let bpm = if beat_times_secs.len() >= MIN_BEATS_FOR_SLOPE {
        grid::bpm_of_beats(&beat_times_secs).unwrap_or(level_bpm)
    } else {
        level_bpm
    }
    .clamp(grid::MIN_GRID_BPM, grid::MAX_GRID_BPM);
    let mut grid = SongGrid::assemble(
        duration_secs,
        bpm,
        beats_per_bar,
        beat_times_secs,
        phase,
        false,
        LoudnessCurve::from_rms(envelope.hop_secs, full),
    );
    // Clamp with a notice: the grid is still given (the person may tap over it), marked as a
    // guess when the song shows no clear beat at its tempo (noise, free-time playing).
    let clarity = tempo::pulse_clarity(&onsets.total, period_frames);
    grid.beat_clarity = Some(clarity);
    grid.clear_beat = clarity >= tempo::MIN_CLEAR_BEAT_Z;
    Ok(grid)
}

#[cfg(test)]
#[allow(clippy::needless_range_loop)]
mod tests {
    use super::*;

    /// A synthetic envelope: a kick-like low-band burst on every beat, louder on the one, and a
    /// hat-like high-band burst on every eighth.
    fn pulse_envelope(bpm: f32, secs: f32) -> RmsEnvelope {
        pulse_envelope_in(bpm, secs, 4)
    }

    /// [`pulse_envelope`] with `beats_per_bar` beats between accents.
    fn pulse_envelope_in(bpm: f32, secs: f32, beats_per_bar: usize) -> RmsEnvelope {
        let hop = 0.01f32;
        let frames = (secs / hop) as usize;
        let beat = 60.0 / bpm;
        let mut bands = vec![vec![0.001f32; frames]; 4];
        for n in 0..frames {
            let t = n as f32 * hop;
            let phase_beats = t / beat;
            let in_beat = (phase_beats.fract()) * beat;
            let in_eighth = (phase_beats * 2.0).fract() * beat / 2.0;
            let accent = if (phase_beats as usize).is_multiple_of(beats_per_bar) { 1.0 } else { 0.5 };
            bands[1][n] += accent * crate::fmath::exp(-in_beat / 0.08);
            bands[3][n] += 0.2 * crate::fmath::exp(-in_eighth / 0.03);
            bands[2][n] += 0.1;
            bands[0][n] = bands[1][n] + bands[2][n] + bands[3][n];
        }
        RmsEnvelope { hop_secs: hop, bands }
    }

    #[test]
    fn analysis_finds_tempo_beats_and_downbeats_of_a_clean_pulse() {
        for bpm in [96.0f32, 120.0, 138.0] {
            let g = analyze(&pulse_envelope(bpm, 30.0), &AnalysisOptions::default()).unwrap();
            assert!((g.bpm / bpm - 1.0).abs() < 0.01, "{bpm}: {}", g.bpm);
            let bar = 240.0 / bpm;
            let off = (g.first_downbeat_secs / bar).fract();
            assert!(!(0.02..0.98).contains(&off), "{bpm}: first downbeat {}", g.first_downbeat_secs);
            assert!(g.bars.len() as f32 >= 30.0 / bar - 2.0);
        }
    }

    #[test]
    fn bad_envelopes_are_typed_errors() {
        let o = AnalysisOptions::default();
        let ok = pulse_envelope(120.0, 10.0);
        assert_eq!(analyze(&RmsEnvelope::default(), &o), Err(MusicError::BadHop { hop_secs: 0.0 }));
        assert_eq!(analyze(&RmsEnvelope { hop_secs: 0.01, bands: vec![] }, &o), Err(MusicError::Empty));
        let mut nan = ok.clone();
        nan.bands[2][7] = f32::NAN;
        assert!(matches!(analyze(&nan, &o), Err(MusicError::BadValue { band: 2, frame: 7, .. })));
        let mut ragged = ok.clone();
        ragged.bands[3].pop();
        assert!(matches!(analyze(&ragged, &o), Err(MusicError::RaggedBands { band: 3, .. })));
        let silent = RmsEnvelope { hop_secs: 0.01, bands: vec![vec![0.0; 1000]; 4] };
        assert!(matches!(analyze(&silent, &o), Err(MusicError::Silent { .. })));
        let short = RmsEnvelope { hop_secs: 0.01, bands: ok.bands.iter().map(|b| b[..200].to_vec()).collect() };
        assert!(matches!(analyze(&short, &o), Err(MusicError::TooShort { .. })));
        let fine = RmsEnvelope { hop_secs: 1e-6, bands: ok.bands.clone() };
        assert!(matches!(analyze(&fine, &o), Err(MusicError::BadHop { .. })));
        assert!(matches!(
            analyze(&ok, &AnalysisOptions { max_bpm: 10.0, ..o }),
            Err(MusicError::BadOption { what: "maxBpm", .. })
        ));
    }

    #[test]
    fn three_beats_per_bar_follow_the_accent() {
        // A waltz at 150 BPM whose accents fall on beats 0, 3, 6, …: with the pulse starting
        // 0.3 s late, the first downbeat is the first accented beat.
        let mut e = pulse_envelope_in(150.0, 24.0, 3);
        for band in &mut e.bands {
            band.splice(0..0, std::iter::repeat_n(0.001, 30));
        }
        let o = AnalysisOptions { beats_per_bar: 3, ..AnalysisOptions::default() };
        let g = analyze(&e, &o).unwrap();
        assert_eq!(g.beats_per_bar, 3);
        let bar = 3.0 * 60.0 / 150.0;
        let off = ((g.first_downbeat_secs - 0.3) / bar).rem_euclid(1.0);
        assert!(!(0.02..0.98).contains(&off), "first downbeat {}", g.first_downbeat_secs);
        assert!((g.bars[0].duration_secs() - bar).abs() < 0.03);
        // Left to itself, the analysis finds the 3; a 4/4 pulse stays in 4.
        assert_eq!(analyze(&e, &AnalysisOptions::default()).unwrap().beats_per_bar, 3);
        assert_eq!(analyze(&pulse_envelope(120.0, 24.0), &AnalysisOptions::default()).unwrap().beats_per_bar, 4);
    }

    #[test]
    fn analysis_is_deterministic() {
        let e = pulse_envelope(128.0, 20.0);
        let o = AnalysisOptions::default();
        assert_eq!(analyze(&e, &o).unwrap(), analyze(&e, &o).unwrap());
    }

    #[test]
    fn a_single_band_envelope_works() {
        let e = pulse_envelope(120.0, 20.0);
        let single = RmsEnvelope { hop_secs: e.hop_secs, bands: vec![e.bands[0].clone()] };
        let g = analyze(&single, &AnalysisOptions::default()).unwrap();
        assert!((g.bpm - 120.0).abs() < 1.5, "{}", g.bpm);
    }
}
