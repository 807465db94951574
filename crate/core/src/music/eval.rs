//! The beat-tracking F-measure (as in mir_eval's `beat.f_measure`, without its default trimming
//! of the first 5 s): estimated and reference event times are paired one-to-one when within a
//! tolerance (±70 ms is the MIREX convention), greedily by closeness;
//! `F = 2·P·R / (P + R)` with precision `P = hits / estimated` and recall `R = hits / reference`.

/// F-measure of `estimated` against `reference` event times (seconds) with `tolerance_secs`.
/// 0 when either list is empty (1 when both are).
pub fn f_measure(estimated: &[f32], reference: &[f32], tolerance_secs: f32) -> f32 {
    if estimated.is_empty() && reference.is_empty() {
        return 1.0;
    }
    if estimated.is_empty() || reference.is_empty() {
        return 0.0;
    }
    // Candidate pairs within tolerance, closest first; each event used once. Exact maximum
    // matching is not needed when events are further apart than twice the tolerance, which beats
    // (>= 200 ms apart at 300 BPM) are.
    let mut pairs: Vec<(f32, usize, usize)> = Vec::new();
    for (i, &e) in estimated.iter().enumerate() {
        for (j, &r) in reference.iter().enumerate() {
            let d = (e - r).abs();
            if d <= tolerance_secs {
                pairs.push((d, i, j));
            }
        }
    }
    pairs.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)).then(a.2.cmp(&b.2)));
    let mut used_e = vec![false; estimated.len()];
    let mut used_r = vec![false; reference.len()];
    let mut hits = 0usize;
    for (_, i, j) in pairs {
        if !used_e[i] && !used_r[j] {
            used_e[i] = true;
            used_r[j] = true;
            hits += 1;
        }
    }
    if hits == 0 {
        return 0.0;
    }
    let p = hits as f32 / estimated.len() as f32;
    let r = hits as f32 / reference.len() as f32;
    2.0 * p * r / (p + r)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn counts_hits_within_tolerance_once() {
        let reference = [1.0f32, 2.0, 3.0, 4.0];
        assert_eq!(f_measure(&reference, &reference, 0.07), 1.0);
        // Two hits (0.98, 3.0); 1.05 cannot pair with 1.0 a second time; 2.2 is 200 ms off.
        let est = [0.98f32, 1.05, 2.2, 3.0];
        let f = f_measure(&est, &reference, 0.07);
        assert!((f - 0.5).abs() < 1e-6, "{f}");
        assert_eq!(f_measure(&[], &reference, 0.07), 0.0);
        assert_eq!(f_measure(&[], &[], 0.07), 1.0);
    }
}
