//! Beat tracking by dynamic programming (Ellis 2007, "Beat tracking by dynamic programming"):
//! the beat sequence maximises the onset strength at the beats minus a penalty for each
//! inter-beat interval that departs from the global period,
//! `C(t) = O(t) + max_{τ ∈ [t−2P, t−P/2]} ( C(τ) − α · ln((t−τ)/P)² )`,
//! then backtracks from the last strong cumulative-score peak and trims weak beats at both ends
//! (silence before the music starts, a reverb tail after it ends).

/// Gaussian smoothing of the onset curve (σ in frames), so a beat need not hit the exact onset
/// frame to collect it.
fn smooth(onset: &[f32], sigma: f32) -> Vec<f32> {
    let radius = (3.0 * sigma).ceil() as isize;
    let kernel: Vec<f32> = (-radius..=radius).map(|i| (-0.5 * (i as f32 / sigma).powi(2)).exp()).collect();
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
    let n = onset.len();
    if n < 2 || !(period_frames.is_finite() && period_frames >= 2.0) {
        return Vec::new();
    }
    let local = smooth(onset, (period_frames / 16.0).max(1.0));
    let min_step = (period_frames / 2.0).round().max(1.0) as usize;
    let max_step = (period_frames * 2.0).round().max(min_step as f32 + 1.0) as usize;
    // Transition penalty per step length, precomputed.
    let penalty: Vec<f32> = (0..=max_step)
        .map(|d| if d == 0 { f32::INFINITY } else { tightness * (d as f32 / period_frames).ln().powi(2) })
        .collect();
    let mut cumulative = vec![0.0f32; n];
    let mut back: Vec<Option<usize>> = vec![None; n];
    for t in 0..n {
        let mut best = f32::NEG_INFINITY;
        let mut arg = None;
        if t >= min_step {
            let lo = t.saturating_sub(max_step);
            for tau in lo..=t - min_step {
                let s = cumulative[tau] - penalty[t - tau];
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
    fn flat_or_tiny_input_gives_no_beats_and_no_panic() {
        assert!(track_beats(&[], 50.0, 100.0).is_empty());
        assert!(track_beats(&[0.0; 10], 50.0, 100.0).is_empty());
        assert!(track_beats(&[1.0; 500], f32::NAN, 100.0).is_empty());
    }
}
