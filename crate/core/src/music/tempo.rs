//! Global tempo from the onset curve: the autocorrelation of onset strength, read as a comb
//! over the first four multiples of each candidate beat period (so a tempo is supported by its
//! bars as well as its beats), weighted by a log-normal tempo prior. The comb and the prior
//! together settle half/double ambiguities: a doubled tempo gains its half-beat lag but loses
//! the prior, a halved tempo loses its own beat lag.
//!
//! Local tempo ([`local_periods`]): the same comb on windows of a few seconds, restricted to
//! tempi near the global one (so the metrical level cannot jump), and a Viterbi path through
//! the windows that charges each change of tempo (so one noisy window cannot pull the path
//! away). A piece whose path (but for its 10 % extremes) stays within [`STEADY_SPREAD`] of one tempo is
//! taken to be steady.

use crate::fmath;
use serde::{Deserialize, Serialize};

/// One tempo hypothesis and its score.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "camelCase")]
pub struct TempoCandidate {
    pub bpm: f32,
    /// Comb score times prior (comparable only within one song).
    pub score: f32,
}

/// The settings of tempo estimation.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TempoSettings {
    pub min_bpm: f32,
    pub max_bpm: f32,
    /// Centre of the log-normal prior, BPM.
    pub prior_bpm: f32,
    /// Standard deviation of the prior, octaves.
    pub prior_octaves: f32,
    /// For a short clip taken to be a loop: its length, seconds, and beats per bar. Tempos at
    /// which the clip holds a whole number of bars are then preferred (a loop repeats bar-wise),
    /// others keep a quarter of their score.
    pub loop_bars: Option<(f32, u32)>,
}

/// How well a tempo fits a loop of `duration_secs`: 1 for a whole number (≥ 1) of bars, falling
/// to 0.25 a tenth of a bar away.
fn loop_fit(bpm: f32, duration_secs: f32, beats_per_bar: u32) -> f32 {
    let bars = duration_secs * bpm / 60.0 / beats_per_bar.max(1) as f32;
    let d = (bars - bars.round().max(1.0)).abs();
    0.25 + 0.75 * fmath::exp(-0.5 * (d / 0.05).powi(2))
}

/// Unbiased, normalised autocorrelation of the mean-removed curve for lags `0..=max_lag`.
pub(crate) fn autocorrelation(x: &[f32], max_lag: usize) -> Vec<f32> {
    let n = x.len();
    if n == 0 {
        return Vec::new();
    }
    let mean = x.iter().map(|&v| f64::from(v)).sum::<f64>() / n as f64;
    let centred: Vec<f64> = x.iter().map(|&v| f64::from(v) - mean).collect();
    let max_lag = max_lag.min(n - 1);
    let mut r = Vec::with_capacity(max_lag + 1);
    for lag in 0..=max_lag {
        let s: f64 = centred[..n - lag].iter().zip(&centred[lag..]).map(|(a, b)| a * b).sum();
        r.push(s / (n - lag) as f64);
    }
    let r0 = r.first().copied().unwrap_or(0.0);
    if r0 <= 0.0 {
        return vec![0.0; r.len()];
    }
    r.iter().map(|v| (v / r0) as f32).collect()
}

/// Linear interpolation of `r` at a fractional lag (0 outside).
fn at(r: &[f32], lag: f32) -> f32 {
    if lag < 0.0 {
        return 0.0;
    }
    let i = lag.floor() as usize;
    let f = lag - i as f32;
    match (r.get(i), r.get(i + 1)) {
        (Some(&a), Some(&b)) => a + (b - a) * f,
        (Some(&a), None) => a * (1.0 - f),
        _ => 0.0,
    }
}

/// Maximum of `r` within ±`tol` frames of `lag` (timing jitter of human playing).
fn peak_near(r: &[f32], lag: f32, tol: f32) -> f32 {
    let steps = 4;
    (0..=2 * steps)
        .map(|s| at(r, lag - tol + tol * s as f32 / steps as f32))
        .fold(f32::NEG_INFINITY, f32::max)
}

/// Scores every tempo from `min_bpm` to `max_bpm` in 0.5 % steps and returns the candidates at
/// local maxima, best first. `fps` is the onset curve's frame rate.
pub fn tempo_candidates(onset: &[f32], fps: f32, settings: &TempoSettings) -> Vec<TempoCandidate> {
    let min_bpm = settings.min_bpm.max(1.0);
    let max_bpm = settings.max_bpm.max(min_bpm * 1.01);
    let longest_period = 60.0 * fps / min_bpm;
    let max_lag = (4.0 * longest_period).ceil() as usize + 2;
    let r = autocorrelation(onset, max_lag.min(onset.len().saturating_sub(1) * 2 / 3));
    if r.len() < 3 {
        return Vec::new();
    }
    let mut scores = Vec::new();
    let mut bpm = min_bpm;
    while bpm <= max_bpm {
        let period = 60.0 * fps / bpm;
        let tol = (period * 0.02).max(0.5);
        let comb: f32 = (1..=4)
            .map(|k| {
                let lag = period * k as f32;
                if lag < r.len() as f32 - 1.0 {
                    peak_near(&r, lag, tol).max(0.0) / (k as f32).sqrt()
                } else {
                    0.0
                }
            })
            .sum();
        let octaves = fmath::log2(bpm / settings.prior_bpm) / settings.prior_octaves.max(0.05);
        let mut prior = fmath::exp(-0.5 * octaves * octaves);
        if let Some((duration_secs, beats_per_bar)) = settings.loop_bars {
            prior *= loop_fit(bpm, duration_secs, beats_per_bar);
        }
        scores.push(TempoCandidate { bpm, score: comb * prior });
        bpm *= 1.005;
    }
    let mut peaks: Vec<TempoCandidate> = (0..scores.len())
        .filter(|&i| {
            let s = scores[i].score;
            let left = i.checked_sub(1).map_or(f32::NEG_INFINITY, |j| scores[j].score);
            let right = scores.get(i + 1).map_or(f32::NEG_INFINITY, |c| c.score);
            s > 0.0 && s >= left && s > right
        })
        .map(|i| scores[i])
        .collect();
    peaks.sort_by(|a, b| b.score.total_cmp(&a.score));
    peaks
}

/// Seconds of onset curve in one local-tempo window (about four bars at 120 BPM: enough lags
/// for a comb over a beat and its multiples).
const LOCAL_WINDOW_SECS: f32 = 8.0;
/// Seconds between local-tempo windows.
const LOCAL_HOP_SECS: f32 = 1.0;
/// Local tempi considered: the global tempo times `1/LOCAL_RANGE ..= LOCAL_RANGE`.
const LOCAL_RANGE: f32 = 1.35;
/// Step between local tempo bins (1 %).
const LOCAL_STEP: f32 = 1.01;
/// Viterbi cost of changing tempo between windows, per squared bin step (scores are normalised
/// to 1 per window): a drift of one bin per window costs a little, a jump of ten bins costs
/// more than any one window can gain.
const LOCAL_JUMP_COST: f32 = 0.02;
/// A local-tempo path whose 10th- and 90th-percentile tempi are within this ratio is steady
/// (a song that changes tempo by less keeps one period; the tracker absorbs a few per cent).
pub const STEADY_SPREAD: f32 = 1.08;

/// Local tempo bins around `centre_bpm`: `1/LOCAL_RANGE ..= LOCAL_RANGE` times it in 1 % steps.
fn local_bins(centre_bpm: f32) -> Vec<f32> {
    let mut bins = Vec::new();
    let mut bpm = centre_bpm / LOCAL_RANGE;
    while bpm <= centre_bpm * LOCAL_RANGE {
        bins.push(bpm);
        bpm *= LOCAL_STEP;
    }
    bins
}

/// Window starts (frames) and the comb score (over `combs` multiples of the beat) of each bin
/// in each window; `None` when the curve is shorter than two windows.
fn window_scores(onset: &[f32], fps: f32, bins: &[f32], combs: usize) -> Option<(Vec<usize>, Vec<Vec<f32>>)> {
    let window = (LOCAL_WINDOW_SECS * fps).round() as usize;
    let hop = (LOCAL_HOP_SECS * fps).round().max(1.0) as usize;
    let slowest = bins.iter().copied().fold(f32::INFINITY, f32::min);
    if onset.len() < 2 * window || !(slowest.is_finite() && slowest > 0.0) {
        return None;
    }
    let longest = 60.0 * fps / slowest;
    let max_lag = ((combs as f32 * longest).ceil() as usize + 2).min(window - 1);
    let starts: Vec<usize> = (0..=(onset.len() - window) / hop).map(|i| i * hop).collect();
    let scores = starts
        .iter()
        .map(|&a| {
            let r = autocorrelation(&onset[a..a + window], max_lag);
            bins.iter()
                .map(|&bpm| {
                    let period = 60.0 * fps / bpm;
                    let tol = (period * 0.02).max(0.5);
                    (1..=combs)
                        .map(|k| {
                            let lag = period * k as f32;
                            if lag < r.len() as f32 - 1.0 {
                                peak_near(&r, lag, tol).max(0.0) / (k as f32).sqrt()
                            } else {
                                0.0
                            }
                        })
                        .sum()
                })
                .collect()
        })
        .collect();
    Some((starts, scores))
}

/// The metrical level of a changing tempo: of `global_bpm`, its half and its double (those
/// within the settings' range), the one whose windows, each judged by the global estimator's
/// comb (beat and bar lags) times its prior at its own best local tempo, score highest in sum.
/// Over a whole song a tempo ramp smears the long bar lags more than the short ones, which can
/// make the song-wide comb prefer the double tempo; within a window the tempo is nearly steady.
pub fn local_level(onset: &[f32], fps: f32, global_bpm: f32, settings: &TempoSettings) -> f32 {
    let prior = |bpm: f32| {
        let octaves = fmath::log2(bpm / settings.prior_bpm) / settings.prior_octaves.max(0.05);
        fmath::exp(-0.5 * octaves * octaves)
    };
    let mut best = (global_bpm, f32::NEG_INFINITY);
    for level in [global_bpm, global_bpm / 2.0, global_bpm * 2.0] {
        if !(settings.min_bpm..=settings.max_bpm).contains(&level) {
            continue;
        }
        let bins = local_bins(level);
        let Some((_, scores)) = window_scores(onset, fps, &bins, 4) else {
            return global_bpm;
        };
        let total: f32 = scores
            .iter()
            .map(|row| row.iter().zip(&bins).map(|(s, &b)| s * prior(b)).fold(0.0f32, f32::max))
            .sum();
        if total > best.1 {
            best = (level, total);
        }
    }
    best.0
}

/// The beat period in frames at every frame of `onset`, following a changing tempo around
/// `global_bpm`; `None` when the tempo is steady (within [`STEADY_SPREAD`]) or the curve is
/// shorter than two windows, so steady music keeps the single global period.
pub fn local_periods(onset: &[f32], fps: f32, global_bpm: f32) -> Option<Vec<f32>> {
    if !(global_bpm.is_finite() && global_bpm > 0.0) {
        return None;
    }
    let window = (LOCAL_WINDOW_SECS * fps).round() as usize;
    let bins = local_bins(global_bpm);
    let (starts, mut scores) = window_scores(onset, fps, &bins, 3)?;
    // Normalised to each window's best, so loud and quiet passages weigh alike.
    for row in &mut scores {
        let best = row.iter().copied().fold(0.0f32, f32::max);
        if best > 0.0 {
            row.iter_mut().for_each(|v| *v /= best);
        }
    }
    // Viterbi: the path of bins maximising score minus the cost of its changes.
    let nb = bins.len();
    let mut total = scores[0].clone();
    let mut back = vec![vec![0usize; nb]; scores.len()];
    for w in 1..scores.len() {
        let mut next = vec![0.0f32; nb];
        for j in 0..nb {
            let (mut best, mut arg) = (f32::NEG_INFINITY, j);
            for (i, &v) in total.iter().enumerate() {
                let d = i.abs_diff(j) as f32;
                let s = v - LOCAL_JUMP_COST * d * d;
                if s > best {
                    best = s;
                    arg = i;
                }
            }
            next[j] = best + scores[w][j];
            back[w][j] = arg;
        }
        total = next;
    }
    let mut j = (0..nb).max_by(|&a, &b| total[a].total_cmp(&total[b]))?;
    let mut path = vec![0usize; scores.len()];
    for w in (0..scores.len()).rev() {
        path[w] = j;
        j = back[w][j];
    }
    let tempi: Vec<f32> = path.iter().map(|&j| bins[j]).collect();
    // The spread between the 10th and 90th percentile of the path: a passage of a few seconds
    // where the path wanders (a fill, a held chord) does not make a steady song unsteady.
    let mut sorted = tempi.clone();
    sorted.sort_by(f32::total_cmp);
    let (lo, hi) = (sorted[sorted.len() / 10], sorted[sorted.len() * 9 / 10]);
    if hi / lo <= STEADY_SPREAD {
        return None;
    }
    // Period per frame: linear between window centres, held beyond the first and last.
    let centres: Vec<f32> = starts.iter().map(|&a| a as f32 + window as f32 / 2.0).collect();
    let periods: Vec<f32> = tempi.iter().map(|&bpm| 60.0 * fps / bpm).collect();
    Some(
        (0..onset.len())
            .map(|t| {
                let t = t as f32;
                let k = centres.partition_point(|&c| c <= t);
                if k == 0 {
                    periods[0]
                } else if k == centres.len() {
                    periods[k - 1]
                } else {
                    let f = (t - centres[k - 1]) / (centres[k] - centres[k - 1]);
                    periods[k - 1] + f * (periods[k] - periods[k - 1])
                }
            })
            .collect(),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    fn pulses(period: f32, frames: usize, accent_every: usize) -> Vec<f32> {
        let mut x = vec![0.0f32; frames];
        let mut k = 0usize;
        let mut t = 0.0f32;
        while (t as usize) < frames {
            x[t as usize] = if k.is_multiple_of(accent_every) { 2.0 } else { 1.0 };
            t += period;
            k += 1;
        }
        x
    }

    fn settings() -> TempoSettings {
        TempoSettings { min_bpm: 40.0, max_bpm: 240.0, prior_bpm: 120.0, prior_octaves: 1.0, loop_bars: None }
    }

    #[test]
    fn finds_the_pulse_rate() {
        for bpm in [80.0f32, 100.0, 128.0, 150.0] {
            let x = pulses(6000.0 / bpm, 3000, 4);
            let c = tempo_candidates(&x, 100.0, &settings());
            assert!((c[0].bpm / bpm - 1.0).abs() < 0.02, "{bpm}: {:?}", &c[..3]);
        }
    }

    /// Pulses whose tempo ramps linearly per beat from `from_bpm` to `to_bpm` over `beats`.
    fn ramp(from_bpm: f32, to_bpm: f32, beats: usize, fps: f32) -> (Vec<f32>, Vec<f32>) {
        let mut t = 1.0f32;
        let mut times = Vec::new();
        for k in 0..beats {
            times.push(t);
            t += 60.0 / (from_bpm + (to_bpm - from_bpm) * k as f32 / (beats - 1) as f32);
        }
        let mut x = vec![0.0f32; ((t + 1.0) * fps) as usize];
        for (k, &b) in times.iter().enumerate() {
            x[(b * fps).round() as usize] = if k % 4 == 0 { 2.0 } else { 1.0 };
        }
        (x, times)
    }

    #[test]
    fn local_tempo_follows_a_ramp_and_stays_silent_on_a_steady_pulse() {
        let fps = 100.0;
        let (x, times) = ramp(100.0, 140.0, 160, fps);
        let global = tempo_candidates(&x, fps, &settings())[0].bpm;
        let periods = local_periods(&x, fps, global).expect("a ramp is not steady");
        // Mid-song (away from the held ends), the local tempo is within 3 % of the true one.
        for k in (20..140).step_by(10) {
            let true_bpm = 60.0 / (times[k + 1] - times[k]);
            let frame = (times[k] * fps) as usize;
            let found = 60.0 * fps / periods[frame];
            assert!((found / true_bpm - 1.0).abs() < 0.03, "beat {k}: {found} vs {true_bpm}");
        }
        let steady = pulses(50.0, 6000, 4);
        assert!(local_periods(&steady, fps, 120.0).is_none());
    }

    #[test]
    fn a_loop_prefers_tempos_with_whole_bars() {
        assert!((loop_fit(90.0, 5.3333, 4) - 1.0).abs() < 1e-3);
        assert!((loop_fit(180.0, 5.3333, 4) - 1.0).abs() < 1e-3);
        assert!(loop_fit(103.0, 5.3333, 4) < 0.3);
        // Less than a bar never fits.
        assert!(loop_fit(20.0, 5.3333, 4) < 0.3);
    }

    #[test]
    fn autocorrelation_is_one_at_zero_and_flat_for_constant() {
        let r = autocorrelation(&[1.0, 0.0, 1.0, 0.0, 1.0, 0.0], 3);
        assert!((r[0] - 1.0).abs() < 1e-6 && r[2] > 0.9 && r[1] < -0.9);
        assert!(autocorrelation(&[2.0; 10], 3).iter().all(|&v| v == 0.0));
    }
}

/// Smallest [`pulse_clarity`] taken as a clear beat: five standard deviations above what the
/// same onsets give with their timing shuffled. Chosen as a conventional significance level,
/// not fitted to any song.
pub const MIN_CLEAR_BEAT_Z: f32 = 5.0;

/// The comb of [`tempo_candidates`] at one period, from the integer lags it needs only.
fn comb_at(centred: &[f64], r0: f64, period: f32) -> f32 {
    let n = centred.len();
    let tol = (period * 0.02).max(0.5);
    (1..=4)
        .map(|k| {
            let lag = period * k as f32;
            let (lo, hi) = ((lag - tol).floor().max(1.0) as usize, (lag + tol).ceil() as usize);
            if hi + 2 >= n {
                return 0.0;
            }
            let best = (lo..=hi)
                .map(|l| centred[..n - l].iter().zip(&centred[l..]).map(|(a, b)| a * b).sum::<f64>() / (n - l) as f64 / r0)
                .fold(f64::NEG_INFINITY, f64::max);
            best.max(0.0) as f32 / (k as f32).sqrt()
        })
        .sum()
}

/// How clearly an onset curve pulses at `period_frames`: the comb score of the curve against
/// the comb scores of [`CLARITY_SURROGATES`] copies with their frames shuffled (same values,
/// no timing), as a z-score. A song with a beat scores far above its shuffles; noise, whose
/// best tempo is only the largest of many chance peaks, does not. Deterministic (a fixed
/// shuffle seed).
pub fn pulse_clarity(onset: &[f32], period_frames: f32) -> f32 {
    let n = onset.len();
    if n < 8 || !(period_frames.is_finite() && period_frames >= 1.0) {
        return 0.0;
    }
    let mean = onset.iter().map(|&v| f64::from(v)).sum::<f64>() / n as f64;
    let mut centred: Vec<f64> = onset.iter().map(|&v| f64::from(v) - mean).collect();
    let r0 = centred.iter().map(|v| v * v).sum::<f64>() / n as f64;
    if r0 <= 0.0 {
        return 0.0;
    }
    let score = comb_at(&centred, r0, period_frames);
    let mut state = 0x9E37_79B9_7F4A_7C15u64;
    let mut next = move || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        state
    };
    let nulls: Vec<f32> = (0..CLARITY_SURROGATES)
        .map(|_| {
            for i in (1..n).rev() {
                let j = (next() % (i as u64 + 1)) as usize;
                centred.swap(i, j);
            }
            comb_at(&centred, r0, period_frames)
        })
        .collect();
    let m = nulls.iter().sum::<f32>() / nulls.len() as f32;
    let sd = (nulls.iter().map(|v| (v - m).powi(2)).sum::<f32>() / (nulls.len() - 1) as f32).sqrt();
    (score - m) / sd.max(1e-6)
}

/// Shuffled copies [`pulse_clarity`] compares against.
pub const CLARITY_SURROGATES: usize = 16;
