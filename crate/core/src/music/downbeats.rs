//! Downbeats (the bar phase): which of every `beats_per_bar` beats starts a bar. Each beat gets
//! an accent, the low band's onset strength at the beat (kick drum and bass notes land on the
//! one) plus a smaller share of the overall onset strength; the phase whose beats carry the most
//! accent wins. With low-band emphasis this follows the accent pattern of most popular music;
//! the user corrects it when it does not (spec §D).

/// Weight of the overall onset relative to the low band's in a beat's accent.
const TOTAL_WEIGHT: f32 = 0.5;

/// Maximum of `x` over `[centre − radius, centre + radius]`.
fn max_around(x: &[f32], centre: usize, radius: usize) -> f32 {
    let lo = centre.saturating_sub(radius);
    let hi = (centre + radius + 1).min(x.len());
    x.get(lo..hi).map_or(0.0, |s| s.iter().copied().fold(0.0, f32::max))
}

/// Divides by the mean (leaves an all-zero series alone).
fn normalise_mean(x: &mut [f32]) {
    let mean = x.iter().sum::<f32>() / x.len().max(1) as f32;
    if mean > 1e-9 {
        x.iter_mut().for_each(|v| *v /= mean);
    }
}

/// The bar phase of a beat sequence: the index (`0..beats_per_bar`) of the first downbeat in
/// `beat_frames`, and the winning phase's share of the summed phase scores (a confidence,
/// `1 / beats_per_bar` when every phase looks the same).
pub fn bar_phase(
    beat_frames: &[usize],
    total_onset: &[f32],
    low_onset: &[f32],
    period_frames: f32,
    beats_per_bar: usize,
) -> (usize, f32) {
    let bpb = beats_per_bar.max(1);
    if beat_frames.is_empty() || bpb == 1 {
        return (0, 1.0);
    }
    let radius = (period_frames / 8.0).round().max(1.0) as usize;
    let mut low: Vec<f32> = beat_frames.iter().map(|&b| max_around(low_onset, b, radius)).collect();
    let mut total: Vec<f32> = beat_frames.iter().map(|&b| max_around(total_onset, b, radius)).collect();
    normalise_mean(&mut low);
    normalise_mean(&mut total);
    let mut sums = vec![0.0f32; bpb];
    let mut counts = vec![0usize; bpb];
    for (k, (l, t)) in low.iter().zip(&total).enumerate() {
        sums[k % bpb] += l + TOTAL_WEIGHT * t;
        counts[k % bpb] += 1;
    }
    let scores: Vec<f32> = sums.iter().zip(&counts).map(|(s, &c)| if c > 0 { s / c as f32 } else { 0.0 }).collect();
    let (phase, best) = scores
        .iter()
        .enumerate()
        .fold((0, f32::NEG_INFINITY), |acc, (i, &s)| if s > acc.1 { (i, s) } else { acc });
    let sum: f32 = scores.iter().sum();
    let confidence = if sum > 0.0 { best / sum } else { 1.0 / bpb as f32 };
    (phase, confidence)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_accented_beat_is_the_downbeat() {
        let beats: Vec<usize> = (0..16).map(|k| 10 + 50 * k).collect();
        let mut low = vec![0.0f32; 900];
        let mut total = vec![0.0f32; 900];
        for (k, &b) in beats.iter().enumerate() {
            total[b] = 1.0;
            // Kick on beats 2 and 4 of a bar that starts at beat index 1.
            if k % 4 == 1 {
                low[b] = 2.0;
            }
            if k % 4 == 3 {
                low[b] = 1.0;
            }
        }
        let (phase, confidence) = bar_phase(&beats, &total, &low, 50.0, 4);
        assert_eq!(phase, 1);
        assert!(confidence > 0.3);
    }
}
