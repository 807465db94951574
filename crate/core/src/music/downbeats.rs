//! Downbeats (the bar phase): which of every `beats_per_bar` beats starts a bar. Two accents of
//! popular music decide it, both measured at the beats from the band onsets:
//! - the **kick**: the low band's onset strength is highest on the one (low-band emphasis);
//! - the **backbeat**: in even metres the snare lands on the beats between (2 and 4 in 4/4);
//!   a beat's "snare-ness" is its mid-band onset minus its low-band onset, and the phase whose
//!   off-numbered beats carry snare and whose numbered beats do not wins.
//!
//! The backbeat alone cannot tell beat 1 from beat 3; the kick settles it. Music without drums
//! falls back to the low band (bass notes and chord changes). The user corrects the rest
//! (spec §D).

/// Weight of the backbeat term relative to the kick term.
const BACKBEAT_WEIGHT: f32 = 1.0;

/// Maximum of `x` over `[centre − radius, centre + radius]`.
fn max_around(x: &[f32], centre: usize, radius: usize) -> f32 {
    let lo = centre.saturating_sub(radius);
    let hi = (centre + radius + 1).min(x.len());
    x.get(lo..hi).map_or(0.0, |s| s.iter().copied().fold(0.0, f32::max))
}

/// Divides by the mean and caps at [`ACCENT_CAP`] (leaves an all-zero series alone): one
/// outlier beat (the song's very first frame, a crash) must not decide the phase of every bar.
fn normalise_mean(x: &mut [f32]) {
    let mean = x.iter().sum::<f32>() / x.len().max(1) as f32;
    if mean > 1e-9 {
        x.iter_mut().for_each(|v| *v = (*v / mean).min(ACCENT_CAP));
    }
}

/// The largest accent a single beat may carry, in multiples of the song's mean.
const ACCENT_CAP: f32 = 3.0;

/// Mean of `x[k]` over beats `k ≡ phase (mod bpb)`, for each phase.
fn phase_means(x: &[f32], bpb: usize) -> Vec<f32> {
    let mut sums = vec![0.0f32; bpb];
    let mut counts = vec![0usize; bpb];
    for (k, v) in x.iter().enumerate() {
        sums[k % bpb] += v;
        counts[k % bpb] += 1;
    }
    sums.iter().zip(&counts).map(|(s, &c)| if c > 0 { s / c as f32 } else { 0.0 }).collect()
}

/// The bar phase of a beat sequence: the index (`0..beats_per_bar`) of the first downbeat in
/// `beat_frames`, and the margin of the winning phase's score over the runner-up (a confidence;
/// 0 when two phases tie). `low_onset` and `mid_onset` are the low and mid bands' onset curves
/// (the same curve twice when only one band exists).
pub fn bar_phase(
    beat_frames: &[usize],
    low_onset: &[f32],
    mid_onset: &[f32],
    period_frames: f32,
    beats_per_bar: usize,
) -> (usize, f32) {
    let bpb = beats_per_bar.max(1);
    if beat_frames.is_empty() || bpb == 1 {
        return (0, 0.0);
    }
    let radius = (period_frames / 8.0).round().max(1.0) as usize;
    let mut low: Vec<f32> = beat_frames.iter().map(|&b| max_around(low_onset, b, radius)).collect();
    let mut mid: Vec<f32> = beat_frames.iter().map(|&b| max_around(mid_onset, b, radius)).collect();
    normalise_mean(&mut low);
    normalise_mean(&mut mid);
    let snare: Vec<f32> = mid.iter().zip(&low).map(|(m, l)| m - l).collect();
    let low_means = phase_means(&low, bpb);
    let snare_means = phase_means(&snare, bpb);
    let low_total: f32 = low_means.iter().sum();
    let scores: Vec<f32> = (0..bpb)
        .map(|phase| {
            let kick = low_means[phase] - (low_total - low_means[phase]) / (bpb - 1) as f32;
            let backbeat = if bpb.is_multiple_of(2) {
                let (mut odd, mut even) = (0.0, 0.0);
                for j in 0..bpb {
                    let v = snare_means[(phase + j) % bpb];
                    if !j.is_multiple_of(2) {
                        odd += v;
                    } else {
                        even += v;
                    }
                }
                (odd - even) / (bpb / 2) as f32
            } else {
                0.0
            };
            kick + BACKBEAT_WEIGHT * backbeat
        })
        .collect();
    let mut order: Vec<usize> = (0..bpb).collect();
    order.sort_by(|&a, &b| scores[b].total_cmp(&scores[a]).then(a.cmp(&b)));
    let best = order[0];
    let margin = order.get(1).map_or(0.0, |&second| scores[best] - scores[second]);
    (best, margin)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_accented_beat_is_the_downbeat() {
        let beats: Vec<usize> = (0..16).map(|k| 10 + 50 * k).collect();
        let mut low = vec![0.0f32; 900];
        let mut mid = vec![0.0f32; 900];
        for (k, &b) in beats.iter().enumerate() {
            // Bars start at beat index 1: kick on 1 (strong) and 3, snare on 2 and 4.
            match k % 4 {
                1 => low[b] = 2.0,
                3 => low[b] = 1.2,
                _ => mid[b] = 1.5,
            }
        }
        let (phase, margin) = bar_phase(&beats, &low, &mid, 50.0, 4);
        assert_eq!(phase, 1);
        assert!(margin > 0.3);
        // Without a snare, the kick alone decides.
        let (phase, _) = bar_phase(&beats, &low, &vec![0.0; 900], 50.0, 4);
        assert_eq!(phase, 1);
    }
}
