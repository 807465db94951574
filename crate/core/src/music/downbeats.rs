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
//!
//! The metre ([`detect_metre`]): how many beats a bar holds, 3 or 4. The accents at the beats
//! (low band, mid band, all bands) repeat with the bar, so each accent series, read beat by
//! beat, correlates with itself at a lag of one bar and its double: a waltz at lags 3 and 6,
//! 4/4 (and 2/4) at 4 and 8, while each correlates poorly at the other's lags. 4 wins ties and
//! short songs; the person corrects the rest (beats per bar is a grid correction).

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

/// The metres [`detect_metre`] chooses between, most likely first.
pub const METRES: [usize; 2] = [4, 3];
/// Fewest beats for a metre decision (four bars of 4): below it, 4.
const MIN_BEATS_FOR_METRE: usize = 16;
/// How much better (in summed correlation) 3 must score than 4 to win: 4/4 is the default of
/// popular and dance music, so ambiguity keeps it.
const METRE_MARGIN: f32 = 0.1;

/// Autocorrelation (normalised, mean removed) of a series at `lag` (0 when undefined).
fn lag_correlation(x: &[f32], lag: usize) -> f32 {
    if x.len() <= lag + 2 {
        return 0.0;
    }
    let mean = x.iter().sum::<f32>() / x.len() as f32;
    let var = x.iter().map(|v| (v - mean).powi(2)).sum::<f32>() / x.len() as f32;
    if var <= 1e-12 {
        return 0.0;
    }
    let cov = x[lag..].iter().zip(x).map(|(a, b)| (a - mean) * (b - mean)).sum::<f32>() / (x.len() - lag) as f32;
    cov / var
}

/// The beats per bar (one of [`METRES`]) of a beat sequence and the score of each metre (the
/// sum over accent series of their correlation at one and two bars), in the order of
/// [`METRES`]. `accents` are onset curves (e.g. low band, mid band, total) read at the beats.
pub fn detect_metre(beat_frames: &[usize], accents: &[&[f32]], period_frames: f32) -> (usize, [f32; 2]) {
    if beat_frames.len() < MIN_BEATS_FOR_METRE {
        return (METRES[0], [0.0; 2]);
    }
    let radius = (period_frames / 8.0).round().max(1.0) as usize;
    let series: Vec<Vec<f32>> = accents
        .iter()
        .map(|curve| {
            let mut x: Vec<f32> = beat_frames.iter().map(|&b| max_around(curve, b, radius)).collect();
            normalise_mean(&mut x);
            x
        })
        .collect();
    let mut scores = [0.0f32; 2];
    for (score, &m) in scores.iter_mut().zip(&METRES) {
        *score = series.iter().map(|x| lag_correlation(x, m) + lag_correlation(x, 2 * m)).sum();
    }
    let metre = if scores[1] > scores[0] + METRE_MARGIN { METRES[1] } else { METRES[0] };
    (metre, scores)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Accent curves for `beats` beats 50 frames apart with the pattern `low`/`mid` per beat of
    /// the bar.
    fn accents(beats: usize, low_pattern: &[f32], mid_pattern: &[f32]) -> (Vec<usize>, Vec<f32>, Vec<f32>) {
        let frames: Vec<usize> = (0..beats).map(|k| 10 + 50 * k).collect();
        let mut low = vec![0.0f32; 50 * beats + 20];
        let mut mid = low.clone();
        for (k, &b) in frames.iter().enumerate() {
            low[b] = low_pattern[k % low_pattern.len()];
            mid[b] = mid_pattern[k % mid_pattern.len()];
        }
        (frames, low, mid)
    }

    #[test]
    fn metre_is_three_for_a_waltz_and_four_for_rock_or_a_march() {
        // Waltz: kick on one, snare on two and three.
        let (f, low, mid) = accents(48, &[2.0, 0.2, 0.2], &[0.2, 1.0, 1.0]);
        assert_eq!(detect_metre(&f, &[&low, &mid], 50.0).0, 3);
        // Rock: kick on one and three, snare on two and four.
        let (f, low, mid) = accents(48, &[2.0, 0.2, 1.2, 0.2], &[0.2, 1.0, 0.2, 1.0]);
        assert_eq!(detect_metre(&f, &[&low, &mid], 50.0).0, 4);
        // A march in 2/4 reads as 4 (its bars pair up), never 3.
        let (f, low, mid) = accents(48, &[2.0, 0.5], &[0.2, 1.0]);
        assert_eq!(detect_metre(&f, &[&low, &mid], 50.0).0, 4);
        // No accents, or too few beats: 4.
        let (f, low, mid) = accents(48, &[1.0], &[1.0]);
        assert_eq!(detect_metre(&f, &[&low, &mid], 50.0).0, 4);
        let (f, low, mid) = accents(9, &[2.0, 0.2, 0.2], &[0.2, 1.0, 1.0]);
        assert_eq!(detect_metre(&f, &[&low, &mid], 50.0).0, 4);
    }

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
