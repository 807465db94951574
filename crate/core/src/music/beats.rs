//! Beat tracking by dynamic programming (Ellis 2007, "Beat tracking by dynamic programming"):
//! the beat sequence maximises the onset strength at the beats minus a penalty for each
//! inter-beat interval that departs from the global period,
//! `C(t) = O(t) + max_{τ ∈ [t−2P, t−P/2]} ( C(τ) − α · ln((t−τ)/P)² )`,
//! then backtracks from the last strong cumulative-score peak and trims weak beats at both ends
//! (silence before the music starts, a reverb tail after it ends).
//!
//! With a tempo that changes ([`track_beats_varying`]), `P` becomes the local period `P(t)` at
//! the later beat (from [`super::tempo::local_periods`]), so the penalty follows the tempo
//! instead of pulling every interval back to one global period.

use crate::fmath;

/// Gaussian smoothing of the onset curve (σ in frames), so a beat need not hit the exact onset
/// frame to collect it.
fn smooth(onset: &[f32], sigma: f32) -> Vec<f32> {
    let radius = (3.0 * sigma).ceil() as isize;
    let kernel: Vec<f32> = (-radius..=radius).map(|i| fmath::exp(-0.5 * (i as f32 / sigma).powi(2))).collect();
    let n = onset.len() as isize;
    (0..n)
        .map(|t| {
            kernel
                .iter()
                .enumerate()
                .map(|(k, w)| {
                    let i = t + k as isize - radius;
                    if (0..n).contains(&i) {
                        w * onset[i as usize]
                    } else {
                        0.0
                    }
                })
                .sum()
        })
        .collect()
}

/// Tracks beats through `onset` (frames) at a period of `period_frames`; `tightness` is α.
/// Returns beat frames in increasing order (empty when the curve is too short or flat).
pub fn track_beats(onset: &[f32], period_frames: f32, tightness: f32) -> Vec<usize> {
    track(onset, period_frames, None, tightness)
}

/// [`track_beats`] with a period per frame (`periods_frames.len() == onset.len()`): a beat at
/// frame `t` is expected `periods_frames[t]` after the one before. Empty when the lengths
/// differ or a period is not finite and ≥ 2 frames.
pub fn track_beats_varying(onset: &[f32], periods_frames: &[f32], tightness: f32) -> Vec<usize> {
    if periods_frames.len() != onset.len() || periods_frames.iter().any(|p| !(p.is_finite() && *p >= 2.0)) {
        return Vec::new();
    }
    let mut sorted = periods_frames.to_vec();
    sorted.sort_by(f32::total_cmp);
    let Some(&median) = sorted.get(sorted.len() / 2) else {
        return Vec::new();
    };
    track(onset, median, Some(periods_frames), tightness)
}

/// The dynamic programme: `period_frames` sets the smoothing and, without `periods`, the
/// expected interval; `periods` (one per frame) overrides the expected interval.
#[allow(clippy::needless_range_loop)] // `tau` indexes the step length as well as the arrays.
fn track(onset: &[f32], period_frames: f32, periods: Option<&[f32]>, tightness: f32) -> Vec<usize> {
    let n = onset.len();
    if n < 2 || !(period_frames.is_finite() && period_frames >= 2.0) {
        return Vec::new();
    }
    let local = smooth(onset, (period_frames / 16.0).max(1.0));
    let (shortest, longest) = periods.map_or((period_frames, period_frames), |p| {
        (p.iter().copied().fold(f32::INFINITY, f32::min), p.iter().copied().fold(0.0f32, f32::max))
    });
    let min_step = (shortest / 2.0).round().max(1.0) as usize;
    let max_step = (longest * 2.0).round().max(min_step as f32 + 1.0) as usize;
    // Transition penalty per step length, precomputed for the steady case.
    let penalty: Vec<f32> = (0..=max_step)
        .map(|d| if d == 0 { f32::INFINITY } else { tightness * fmath::ln(d as f32 / period_frames).powi(2) })
        .collect();
    let mut cumulative = vec![0.0f32; n];
    let mut back: Vec<Option<usize>> = vec![None; n];
    for t in 0..n {
        let mut best = f32::NEG_INFINITY;
        let mut arg = None;
        // This frame's expected interval and the steps it allows.
        let (p_t, lo_step, hi_step) = match periods {
            Some(p) => (p[t], (p[t] / 2.0).round().max(1.0) as usize, (p[t] * 2.0).round() as usize),
            None => (period_frames, min_step, max_step),
        };
        if t >= lo_step {
            let lo = t.saturating_sub(hi_step);
            for tau in lo..=t - lo_step {
                let d = t - tau;
                let cost = if periods.is_some() { tightness * fmath::ln(d as f32 / p_t).powi(2) } else { penalty[d] };
                let s = cumulative[tau] - cost;
                if s > best {
                    best = s;
                    arg = Some(tau);
                }
            }
        }
        // A sequence may start anywhere: never worse than starting here.
        if best > 0.0 {
            cumulative[t] = local[t] + best;
            back[t] = arg;
        } else {
            cumulative[t] = local[t];
        }
    }
    // The last beat: the last local maximum of the cumulative score that is at least half the
    // median of such maxima (librosa's rule, which keeps the tail from winning by length alone).
    let maxima: Vec<usize> = (1..n.saturating_sub(1))
        .filter(|&t| cumulative[t] > cumulative[t - 1] && cumulative[t] >= cumulative[t + 1])
        .collect();
    let mut values: Vec<f32> = maxima.iter().map(|&t| cumulative[t]).collect();
    values.sort_by(f32::total_cmp);
    let Some(&median) = values.get(values.len() / 2) else {
        return Vec::new();
    };
    let Some(&last) = maxima.iter().rev().find(|&&t| cumulative[t] >= 0.5 * median) else {
        return Vec::new();
    };
    let mut beats = vec![last];
    let mut t = last;
    while let Some(prev) = back[t] {
        beats.push(prev);
        t = prev;
    }
    beats.reverse();
    trim_weak_ends(&mut beats, &local);
    beats
}

/// Drops beats at either end whose smoothed onset is below [`TRIM_FRACTION`] of the median
/// over all beats: silence before the music and a reverb tail after it hold no onsets, while
/// the median (unlike a mean or an RMS) ignores the few loudest hits, so quieter real beats at
/// the edges survive.
fn trim_weak_ends(beats: &mut Vec<usize>, local: &[f32]) {
    if beats.is_empty() {
        return;
    }
    let value = |b: usize| local.get(b).copied().unwrap_or(0.0);
    let mut values: Vec<f32> = beats.iter().map(|&b| value(b)).collect();
    values.sort_by(f32::total_cmp);
    let threshold = TRIM_FRACTION * values[values.len() / 2];
    let first = beats.iter().position(|&b| value(b) >= threshold).unwrap_or(beats.len());
    let last = beats.iter().rposition(|&b| value(b) >= threshold).map_or(0, |i| i + 1);
    if first >= last {
        beats.clear();
    } else {
        beats.truncate(last);
        beats.drain(..first);
    }
}

/// See [`trim_weak_ends`].
const TRIM_FRACTION: f32 = 0.2;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn follows_a_jittered_pulse_and_skips_silence() {
        // 50-frame period with ±2-frame jitter, silent for the first 100 and last 200 frames.
        let mut x = vec![0.0f32; 1300];
        let jitter = [0i32, 2, -1, -2, 1, 0, 2, -2];
        let mut expected = Vec::new();
        for k in 0..20 {
            let t = (100 + 50 * k as i32 + jitter[k % 8]) as usize;
            x[t] = 3.0;
            expected.push(t);
        }
        let beats = track_beats(&x, 50.0, 100.0);
        assert_eq!(beats.len(), expected.len(), "{beats:?}");
        for (b, e) in beats.iter().zip(&expected) {
            assert!((*b as i32 - *e as i32).abs() <= 1, "{beats:?}");
        }
    }

    #[test]
    fn a_varying_period_follows_an_accelerating_pulse() {
        // Intervals shrink from 60 to 40 frames; the steady tracker at the mean period loses
        // beats, the varying one keeps every beat within a frame.
        let mut x = vec![0.0f32; 2400];
        let mut expected = Vec::new();
        let mut t = 100.0f32;
        let mut periods = vec![0.0f32; 2400];
        while t < 2200.0 {
            let p = 60.0 - 20.0 * (t - 100.0) / 2100.0;
            expected.push(t.round() as usize);
            x[t.round() as usize] = 3.0;
            t += p;
        }
        for (f, p) in periods.iter_mut().enumerate() {
            *p = (60.0 - 20.0 * (f as f32 - 100.0) / 2100.0).clamp(40.0, 60.0);
        }
        let beats = track_beats_varying(&x, &periods, 1000.0);
        assert_eq!(beats.len(), expected.len(), "{beats:?}");
        assert!(beats.iter().zip(&expected).all(|(b, e)| b.abs_diff(*e) <= 1), "{beats:?}");
        assert!(track_beats_varying(&x, &periods[..10], 1000.0).is_empty());
    }

    #[test]
    fn flat_or_tiny_input_gives_no_beats_and_no_panic() {
        assert!(track_beats(&[], 50.0, 100.0).is_empty());
        assert!(track_beats(&[0.0; 10], 50.0, 100.0).is_empty());
        assert!(track_beats(&[1.0; 500], f32::NAN, 100.0).is_empty());
    }
}
