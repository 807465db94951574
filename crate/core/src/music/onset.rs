//! Onset strength from the banded RMS envelope: how much louder each frame is than the one
//! before, band by band, on a log scale, half-wave rectified and summed. Beats sit on strong
//! onsets; the low band's own onset curve is kept for downbeat (bar-phase) estimation.

use crate::fmath;
use super::rms::RmsEnvelope;

/// Log compression: `ln(1 + LOG_GAIN · rms / ref)`, about a 60 dB usable range per band.
const LOG_GAIN: f32 = 1000.0;

/// Onset curves of one song, one value per envelope frame.
#[derive(Clone, Debug, PartialEq)]
pub struct Onsets {
    /// Summed onset strength over the onset bands, divided by its standard deviation.
    pub total: Vec<f32>,
    /// Onset strength of the low band (or of the only band), same scale as `total`'s parts.
    pub low: Vec<f32>,
    /// Onset strength of the mid band (or of the only band), same scale.
    pub mid: Vec<f32>,
}

/// The log-compressed band, relative to its 99.5th percentile (robust to a single click).
fn log_band(band: &[f32]) -> Option<Vec<f32>> {
    let mut sorted: Vec<f32> = band.to_vec();
    sorted.sort_by(f32::total_cmp);
    let idx = ((sorted.len() as f32 - 1.0) * 0.995) as usize;
    let reference = sorted.get(idx).copied().unwrap_or(0.0);
    if reference <= 1e-9 {
        return None;
    }
    Some(band.iter().map(|&v| fmath::ln(1.0 + LOG_GAIN * v / reference)).collect())
}

/// Half-wave rectified first difference, with silence before the first frame.
fn rectified_flux(log: &[f32]) -> Vec<f32> {
    let mut prev = 0.0f32;
    log.iter()
        .map(|&v| {
            let d = (v - prev).max(0.0);
            prev = v;
            d
        })
        .collect()
}

/// Onset strength of an envelope. `onset_bands` are the band indices summed into `total`;
/// `low_band` is the band whose flux feeds downbeat estimation. Bands that are silent throughout
/// contribute nothing. The result has the envelope's frame count.
pub fn onset_strength(envelope: &RmsEnvelope, onset_bands: &[usize], low_band: usize, mid_band: usize) -> Onsets {
    let frames = envelope.frame_count();
    let mut total = vec![0.0f32; frames];
    for &b in onset_bands {
        if let Some(flux) = envelope.bands.get(b).and_then(|band| log_band(band)).map(|l| rectified_flux(&l)) {
            total.iter_mut().zip(&flux).for_each(|(t, f)| *t += f);
        }
    }
    let band_flux = |b: usize| {
        envelope.bands.get(b).and_then(|band| log_band(band)).map(|l| rectified_flux(&l)).unwrap_or_else(|| vec![0.0; frames])
    };
    let (low, mid) = (band_flux(low_band), band_flux(mid_band));
    let sd = std_dev(&total);
    if sd > 1e-9 {
        total.iter_mut().for_each(|t| *t /= sd);
    }
    Onsets { total, low, mid }
}

/// Population standard deviation (0 for fewer than two values).
pub(crate) fn std_dev(x: &[f32]) -> f32 {
    if x.len() < 2 {
        return 0.0;
    }
    let n = x.len() as f64;
    let mean = x.iter().map(|&v| f64::from(v)).sum::<f64>() / n;
    let var = x.iter().map(|&v| (f64::from(v) - mean).powi(2)).sum::<f64>() / n;
    var.sqrt() as f32
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn onsets_peak_where_the_level_jumps() {
        let mut band = vec![0.01f32; 300];
        for start in [50usize, 150, 250] {
            for v in &mut band[start..start + 10] {
                *v = 0.5;
            }
        }
        let env = RmsEnvelope { hop_secs: 0.01, bands: vec![band] };
        let o = onset_strength(&env, &[0], 0, 0);
        let peak = |lo: usize, hi: usize| (lo..hi).max_by(|&a, &b| o.total[a].total_cmp(&o.total[b])).unwrap();
        assert_eq!(peak(40, 100), 50);
        assert_eq!(peak(140, 200), 150);
        // Decays are not onsets.
        assert_eq!(o.total[60], 0.0);
    }

    #[test]
    fn silent_band_gives_zero_onsets() {
        let env = RmsEnvelope { hop_secs: 0.01, bands: vec![vec![0.0; 100]] };
        let o = onset_strength(&env, &[0], 0, 0);
        assert!(o.total.iter().chain(&o.low).all(|&v| v == 0.0));
    }
}
