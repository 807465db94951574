//! The RMS input of song analysis: the exact, frame-wise, banded RMS envelope the browser host
//! computes with WebAudio (spec §D: "the host passes an RMS envelope to the core"), and a Rust
//! implementation of the same definition used by native tests and as a wasm fallback.
//!
//! # The definition the host reproduces
//!
//! Given decoded PCM at sample rate `fs` (Hz, any rate ≥ 8000; the `AudioBuffer`'s own rate):
//!
//! 1. **Mono mixdown**: `m[i] = mean over channels c of x_c[i]`. For one or two channels this is
//!    exactly WebAudio's "speakers" down-mix to one channel (`0.5·(L+R)` for stereo), which a node
//!    with `channelCount = 1, channelCountMode = "explicit"` performs.
//! 2. **Bands**: each band of [`STANDARD_BANDS`] is `m` passed through a cascade of identical
//!    `BiquadFilterNode`s (`type`, `frequency`, `Q` as listed; `detune = 0`, `gain` unused), with
//!    the coefficients of the Web Audio API spec (RBJ cookbook; lowpass/highpass `Q` in dB,
//!    bandpass `Q` linear), zero initial state, normalised by `a0`. Band 0 is the unfiltered mono
//!    signal.
//! 3. **Frames**: hop `H = max(1, round(fs / 100))` samples (441 at 44.1 kHz, 480 at 48 kHz),
//!    `hop_secs = H / fs`. The frame count is `N = ceil(len / H)` (0 for empty input). Frame `n`
//!    is centred on sample `n·H` (time `n·hop_secs`) and covers the `2H` samples
//!    `[n·H − H, n·H + H)`; samples outside `[0, len)` count as zero (a rectangular window with
//!    zero padding). `rms[n] = sqrt( Σ y[i]² / (2H) )` over those samples: the divisor is always
//!    `2H`, also at the edges.
//!
//! The result is an [`RmsEnvelope`]: `hop_secs` and one `Vec<f32>` of `N` values per band, in the
//! order of [`STANDARD_BANDS`]. Analysis also accepts other band sets (see
//! [`crate::music::analyze`]), but the browser and native paths agree only with these.
//!
//! For more than two channels the mean differs from WebAudio's 5.1 down-mix; the difference is
//! a level change per channel, which the analysis (log-compressed, relative to each band's own
//! level) barely sees.
//!
//! # Reference host code
//!
//! A JavaScript twin of [`envelope`] (all four bands rendered at once in an
//! `OfflineAudioContext` at the buffer's own rate, then framed in JavaScript):
//!
//! ```js
//! const BANDS = [
//!   null,                                                         // 0 full: the mono mix
//!   { type: "lowpass",  frequency: 150,  Q: -3.0103, stages: 2 }, // 1 low
//!   { type: "bandpass", frequency: 800,  Q: 0.7,     stages: 1 }, // 2 mid
//!   { type: "highpass", frequency: 4000, Q: -3.0103, stages: 2 }, // 3 high
//! ];
//! async function rmsEnvelope(buffer /* AudioBuffer */) {
//!   const fs = buffer.sampleRate, len = buffer.length;
//!   const ctx = new OfflineAudioContext({ numberOfChannels: BANDS.length, length: len, sampleRate: fs });
//!   ctx.destination.channelInterpretation = "discrete";
//!   const src = new AudioBufferSourceNode(ctx, { buffer });
//!   const mono = new GainNode(ctx, { channelCount: 1, channelCountMode: "explicit", channelInterpretation: "speakers" });
//!   const merge = new ChannelMergerNode(ctx, { numberOfInputs: BANDS.length });
//!   src.connect(mono);
//!   BANDS.forEach((b, i) => {
//!     let node = mono;
//!     for (let s = 0; b && s < b.stages; s++) {
//!       const f = new BiquadFilterNode(ctx, { type: b.type, frequency: b.frequency, Q: b.Q });
//!       node.connect(f);
//!       node = f;
//!     }
//!     node.connect(merge, 0, i);
//!   });
//!   merge.connect(ctx.destination);
//!   src.start(0);
//!   const out = await ctx.startRendering();
//!   const H = Math.max(1, Math.round(fs * 0.01)), N = Math.ceil(len / H);
//!   const bands = BANDS.map((_, i) => {
//!     const y = out.getChannelData(i), rms = new Float32Array(N);
//!     let prev = 0; // energy of the previous hop-long block
//!     for (let n = 0; n < N; n++) {
//!       let e = 0;
//!       for (let k = n * H, end = Math.min(len, k + H); k < end; k++) e += y[k] * y[k];
//!       rms[n] = Math.sqrt((prev + e) / (2 * H));
//!       prev = e;
//!     }
//!     return rms;
//!   });
//!   return { hopSecs: H / fs, bands };
//! }
//! ```

use crate::fmath;
use serde::{Deserialize, Serialize};

use super::MusicError;

/// The target hop of the envelope, seconds: the real hop is `round(fs · HOP_TARGET_SECS)`
/// samples.
pub const HOP_TARGET_SECS: f64 = 0.01;

/// The shortest hop [`RmsEnvelope::validate`] accepts, seconds (finer hops only cost time).
pub const MIN_HOP_SECS: f32 = 0.005;
/// The longest hop [`RmsEnvelope::validate`] accepts, seconds (coarser hops blur beats).
pub const MAX_HOP_SECS: f32 = 0.05;

/// The lowest sample rate the envelope accepts, Hz.
pub const MIN_SAMPLE_RATE_HZ: f32 = 8000.0;

/// The filter type of one band, as WebAudio's `BiquadFilterNode.type` (or no filter).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "camelCase")]
pub enum BandKind {
    /// The mono signal itself, no filter node.
    Full,
    /// `type = "lowpass"`: `q` is in dB, as WebAudio defines it for this type.
    Lowpass,
    /// `type = "bandpass"`: `q` is linear (centre frequency / bandwidth).
    Bandpass,
    /// `type = "highpass"`: `q` is in dB.
    Highpass,
}

/// One band of the envelope: a cascade of `stages` identical biquads. Serialize-only: the host
/// reads the product's bands, it does not define new ones.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
#[serde(rename_all = "camelCase")]
pub struct BandSpec {
    /// A short name for UIs and logs.
    pub name: &'static str,
    pub kind: BandKind,
    /// `BiquadFilterNode.frequency.value`, Hz (ignored for [`BandKind::Full`]).
    pub frequency_hz: f32,
    /// `BiquadFilterNode.Q.value` in WebAudio's own units for the type (dB for lowpass and
    /// highpass, linear for bandpass).
    pub q: f32,
    /// How many identical filter nodes are chained (0 for [`BandKind::Full`]).
    pub stages: u32,
}

/// `20·log10(1/√2)`: WebAudio's lowpass/highpass `Q` for a Butterworth (maximally flat) stage.
pub const BUTTERWORTH_Q_DB: f32 = -3.010_3;

/// The product's bands, in the order of [`RmsEnvelope::bands`]: full, low (kick, bass), mid
/// (snare body, voices, chords), high (hats, snare noise, attacks).
pub const STANDARD_BANDS: [BandSpec; 4] = [
    BandSpec { name: "full", kind: BandKind::Full, frequency_hz: 0.0, q: 0.0, stages: 0 },
    BandSpec { name: "low", kind: BandKind::Lowpass, frequency_hz: 150.0, q: BUTTERWORTH_Q_DB, stages: 2 },
    BandSpec { name: "mid", kind: BandKind::Bandpass, frequency_hz: 800.0, q: 0.7, stages: 1 },
    BandSpec { name: "high", kind: BandKind::Highpass, frequency_hz: 4000.0, q: BUTTERWORTH_Q_DB, stages: 2 },
];

/// Index of the full-band (loudness) envelope in [`STANDARD_BANDS`].
pub const BAND_FULL: usize = 0;
/// Index of the low band in [`STANDARD_BANDS`] (downbeat emphasis: kick, bass).
pub const BAND_LOW: usize = 1;
/// Index of the mid band in [`STANDARD_BANDS`] (downbeat phase: the snare's backbeat).
pub const BAND_MID: usize = 2;

/// The frame-wise RMS envelope of a song: what the host passes to the core.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "camelCase")]
pub struct RmsEnvelope {
    /// Seconds between frames (`H / fs`, about 0.01). Frame `n` is centred on `n · hop_secs`.
    pub hop_secs: f32,
    /// One RMS series per band, all the same length, linear amplitude (full scale = 1).
    pub bands: Vec<Vec<f32>>,
}

impl RmsEnvelope {
    /// Frames per band (0 when there is no band).
    pub fn frame_count(&self) -> usize {
        self.bands.first().map_or(0, Vec::len)
    }

    /// The song's length as the envelope sees it: `frame_count · hop_secs`.
    pub fn duration_secs(&self) -> f32 {
        self.frame_count() as f32 * self.hop_secs
    }

    /// Checks shape and values: at least one band, equal lengths, a hop within
    /// [`MIN_HOP_SECS`]..=[`MAX_HOP_SECS`], finite non-negative values.
    pub fn validate(&self) -> Result<(), MusicError> {
        if !(self.hop_secs.is_finite() && (MIN_HOP_SECS..=MAX_HOP_SECS).contains(&self.hop_secs)) {
            return Err(MusicError::BadHop { hop_secs: self.hop_secs });
        }
        let frames = self.frame_count();
        if self.bands.is_empty() || frames == 0 {
            return Err(MusicError::Empty);
        }
        for (band, values) in self.bands.iter().enumerate() {
            if values.len() != frames {
                return Err(MusicError::RaggedBands { band, frames: values.len(), expected: frames });
            }
            if let Some(frame) = values.iter().position(|v| !v.is_finite() || *v < 0.0) {
                return Err(MusicError::BadValue { band, frame, value: values[frame] });
            }
        }
        Ok(())
    }
}

/// Biquad coefficients normalised by `a0`: `y = b0 x + b1 x1 + b2 x2 − a1 y1 − a2 y2`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BiquadCoefficients {
    pub b0: f64,
    pub b1: f64,
    pub b2: f64,
    pub a1: f64,
    pub a2: f64,
}

impl BiquadCoefficients {
    /// The Web Audio API's `BiquadFilterNode` coefficients for `kind` at `frequency_hz` and `q`
    /// (WebAudio units), sample rate `sample_rate_hz`. The frequency is clamped to
    /// `[0, fs/2]` as WebAudio clamps its computed frequency. `None` for [`BandKind::Full`].
    pub fn webaudio(kind: BandKind, frequency_hz: f32, q: f32, sample_rate_hz: f32) -> Option<Self> {
        let fs = f64::from(sample_rate_hz);
        let f0 = f64::from(frequency_hz).clamp(0.0, fs / 2.0);
        let w0 = 2.0 * std::f64::consts::PI * f0 / fs;
        let (sin_w0, cos_w0) = fmath::sin_cos(w0);
        let q = f64::from(q);
        let (b0, b1, b2, a0, a1, a2) = match kind {
            BandKind::Full => return None,
            BandKind::Lowpass => {
                let alpha = sin_w0 / (2.0 * fmath::powf(10f64, q / 20.0));
                let b = (1.0 - cos_w0) / 2.0;
                (b, 1.0 - cos_w0, b, 1.0 + alpha, -2.0 * cos_w0, 1.0 - alpha)
            }
            BandKind::Highpass => {
                let alpha = sin_w0 / (2.0 * fmath::powf(10f64, q / 20.0));
                let b = (1.0 + cos_w0) / 2.0;
                (b, -(1.0 + cos_w0), b, 1.0 + alpha, -2.0 * cos_w0, 1.0 - alpha)
            }
            BandKind::Bandpass => {
                let alpha = sin_w0 / (2.0 * q.max(1e-4));
                (alpha, 0.0, -alpha, 1.0 + alpha, -2.0 * cos_w0, 1.0 - alpha)
            }
        };
        Some(Self { b0: b0 / a0, b1: b1 / a0, b2: b2 / a0, a1: a1 / a0, a2: a2 / a0 })
    }

    /// Filters `signal` in place from zero state (direct form I, double-precision state, as
    /// browsers implement `BiquadFilterNode`).
    pub fn filter_in_place(&self, signal: &mut [f32]) {
        let (mut x1, mut x2, mut y1, mut y2) = (0.0f64, 0.0f64, 0.0f64, 0.0f64);
        for s in signal.iter_mut() {
            let x = f64::from(*s);
            let y = self.b0 * x + self.b1 * x1 + self.b2 * x2 - self.a1 * y1 - self.a2 * y2;
            x2 = x1;
            x1 = x;
            y2 = y1;
            y1 = y;
            *s = y as f32;
        }
    }
}

/// The hop in samples for a sample rate: `max(1, round(fs · 0.01))`.
pub fn hop_samples(sample_rate_hz: f32) -> usize {
    ((f64::from(sample_rate_hz) * HOP_TARGET_SECS).round() as usize).max(1)
}

/// Frame-wise RMS of one signal with hop `hop` (see the module docs: frame `n` covers
/// `[n·hop − hop, n·hop + hop)`, zero-padded, divisor `2·hop`).
pub fn frame_rms(signal: &[f32], hop: usize) -> Vec<f32> {
    let hop = hop.max(1);
    // Energy of each hop-long block [m·hop, (m+1)·hop), in f64; frame n is blocks n−1 and n.
    let blocks: Vec<f64> =
        signal.chunks(hop).map(|c| c.iter().map(|&s| f64::from(s) * f64::from(s)).sum::<f64>()).collect();
    let denom = (2 * hop) as f64;
    let mut prev = 0.0f64;
    blocks
        .iter()
        .map(|&b| {
            let v = ((prev + b) / denom).sqrt() as f32;
            prev = b;
            v
        })
        .collect()
}

/// The mono mixdown: the mean of the channels, sample by sample (channels of unequal length
/// are an error).
pub fn mono_mixdown(channels: &[&[f32]]) -> Result<Vec<f32>, MusicError> {
    let Some(first) = channels.first() else {
        return Err(MusicError::Empty);
    };
    let len = first.len();
    if let Some((channel, c)) = channels.iter().enumerate().find(|(_, c)| c.len() != len) {
        return Err(MusicError::RaggedChannels { channel, samples: c.len(), expected: len });
    }
    let scale = 1.0 / channels.len() as f32;
    let mut out = vec![0.0f32; len];
    for c in channels {
        for (o, &s) in out.iter_mut().zip(c.iter()) {
            *o += s;
        }
    }
    if channels.len() > 1 {
        out.iter_mut().for_each(|o| *o *= scale);
    }
    Ok(out)
}

/// Computes the envelope of decoded PCM exactly as the module docs define it, with the given
/// bands (use [`STANDARD_BANDS`] to match the browser host). `channels` are the planar channel
/// buffers (e.g. `AudioBuffer.getChannelData(c)`), all the same length.
pub fn envelope_with_bands(
    channels: &[&[f32]],
    sample_rate_hz: f32,
    bands: &[BandSpec],
) -> Result<RmsEnvelope, MusicError> {
    if !(sample_rate_hz.is_finite() && sample_rate_hz >= MIN_SAMPLE_RATE_HZ) {
        return Err(MusicError::BadSampleRate { sample_rate_hz, min_hz: MIN_SAMPLE_RATE_HZ });
    }
    let mono = mono_mixdown(channels)?;
    if mono.is_empty() {
        return Err(MusicError::Empty);
    }
    if let Some(sample) = mono.iter().position(|s| !s.is_finite()) {
        return Err(MusicError::NonFiniteSample { sample });
    }
    let hop = hop_samples(sample_rate_hz);
    let mut out = Vec::with_capacity(bands.len());
    let mut scratch = Vec::new();
    for band in bands {
        match BiquadCoefficients::webaudio(band.kind, band.frequency_hz, band.q, sample_rate_hz) {
            None => out.push(frame_rms(&mono, hop)),
            Some(coeffs) => {
                scratch.clear();
                scratch.extend_from_slice(&mono);
                for _ in 0..band.stages.max(1) {
                    coeffs.filter_in_place(&mut scratch);
                }
                out.push(frame_rms(&scratch, hop));
            }
        }
    }
    Ok(RmsEnvelope { hop_secs: (hop as f64 / f64::from(sample_rate_hz)) as f32, bands: out })
}

/// What a host needs to compute the envelope itself (the browser's WebAudio graph): the
/// bands, the hop rule and the lowest sample rate. The host asks for it instead of restating
/// the constants, so a change here reaches the page and the native path together.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
#[serde(rename_all = "camelCase")]
pub struct EnvelopeDefinition {
    /// The bands in envelope order ([`STANDARD_BANDS`]).
    pub bands: &'static [BandSpec],
    /// The hop is `max(1, round(fs · hop_target_secs))` samples ([`hop_samples`]).
    pub hop_target_secs: f64,
    /// The lowest sample rate [`envelope`] accepts, Hz.
    pub min_sample_rate_hz: f32,
}

/// The envelope's definition as [`envelope`] computes it: what the browser host builds its
/// filters and frames from.
pub fn envelope_definition() -> EnvelopeDefinition {
    EnvelopeDefinition { bands: &STANDARD_BANDS, hop_target_secs: HOP_TARGET_SECS, min_sample_rate_hz: MIN_SAMPLE_RATE_HZ }
}

/// [`envelope_with_bands`] with [`STANDARD_BANDS`]: the native twin of the browser host.
pub fn envelope(channels: &[&[f32]], sample_rate_hz: f32) -> Result<RmsEnvelope, MusicError> {
    envelope_with_bands(channels, sample_rate_hz, &STANDARD_BANDS)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sine(freq: f32, fs: f32, secs: f32) -> Vec<f32> {
        (0..(fs * secs) as usize).map(|i| fmath::sin(2.0 * std::f32::consts::PI * freq * i as f32 / fs)).collect()
    }

    #[test]
    fn frame_layout_is_centred_and_zero_padded() {
        // hop 2, window 4: frame 0 covers [-2, 2) -> samples 0,1 only, divisor 4.
        let x = [1.0f32, 1.0, 1.0, 1.0, 1.0];
        let r = frame_rms(&x, 2);
        assert_eq!(r.len(), 3);
        assert!((r[0] - (2.0f32 / 4.0).sqrt()).abs() < 1e-6);
        assert!((r[1] - 1.0).abs() < 1e-6);
        // frame 2 covers [2, 6) -> samples 2,3,4.
        assert!((r[2] - (3.0f32 / 4.0).sqrt()).abs() < 1e-6);
    }

    #[test]
    fn sine_rms_is_one_over_root_two_and_hop_follows_rate() {
        for fs in [22050.0f32, 44100.0, 48000.0] {
            let e = envelope(&[&sine(440.0, fs, 1.0)], fs).unwrap();
            assert_eq!(e.bands.len(), 4);
            assert!((e.hop_secs - 0.01).abs() < 1e-4, "hop {}", e.hop_secs);
            let mid = e.bands[0][50];
            assert!((mid - std::f32::consts::FRAC_1_SQRT_2).abs() < 0.01, "{mid}");
        }
    }

    #[test]
    fn bands_separate_low_and_high() {
        let fs = 44100.0;
        let low = envelope(&[&sine(60.0, fs, 1.0)], fs).unwrap();
        let high = envelope(&[&sine(8000.0, fs, 1.0)], fs).unwrap();
        let at = |e: &RmsEnvelope, b: usize| e.bands[b][60];
        assert!(at(&low, BAND_LOW) > 0.6 && at(&low, 3) < 0.01, "low: {:?}", low.bands.iter().map(|b| b[60]).collect::<Vec<_>>());
        assert!(at(&high, 3) > 0.6 && at(&high, BAND_LOW) < 0.01);
        // The bandpass peaks at its centre frequency with unit gain.
        let mid = envelope(&[&sine(800.0, fs, 1.0)], fs).unwrap();
        assert!((at(&mid, 2) - std::f32::consts::FRAC_1_SQRT_2).abs() < 0.02);
    }

    #[test]
    fn lowpass_q_is_in_db() {
        // At the cutoff a WebAudio lowpass has gain 10^(Q/20): 0 dB Q -> unit gain.
        let fs = 48000.0;
        let c = BiquadCoefficients::webaudio(BandKind::Lowpass, 1000.0, 0.0, fs).unwrap();
        let mut x = sine(1000.0, fs, 0.5);
        c.filter_in_place(&mut x);
        let r = frame_rms(&x, 480);
        assert!((r[30] - std::f32::consts::FRAC_1_SQRT_2).abs() < 0.01, "{}", r[30]);
    }

    #[test]
    fn stereo_mixdown_is_the_mean() {
        let l = [1.0f32, 0.0];
        let r = [0.0f32, 1.0];
        assert_eq!(mono_mixdown(&[&l, &r]).unwrap(), vec![0.5, 0.5]);
        assert!(matches!(mono_mixdown(&[&l, &r[..1]]), Err(MusicError::RaggedChannels { channel: 1, .. })));
    }

    #[test]
    fn bad_pcm_is_a_typed_error() {
        assert!(matches!(envelope(&[], 44100.0), Err(MusicError::Empty)));
        assert!(matches!(envelope(&[&[]], 44100.0), Err(MusicError::Empty)));
        assert!(matches!(envelope(&[&[0.0; 10]], 100.0), Err(MusicError::BadSampleRate { .. })));
        assert!(matches!(envelope(&[&[0.0, f32::NAN]], 44100.0), Err(MusicError::NonFiniteSample { sample: 1 })));
    }
}
