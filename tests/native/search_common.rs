//! Shared by the search tests and the benchmark: a seeded RNG, the real-data library, a
//! left/right mirror of features, and a plain reference DP written independently of the
//! core's (spec §C, from the text).
#![allow(dead_code)]

use odori_core::import::{import_bytes, ImportOptions};
use odori_core::search::{ClipFeatures, FeatureIndex, MotionFeatures, SearchParams, DISTANCE_ORDER, FRAME_FLOATS};

/// SplitMix64: small, seeded, deterministic.
pub struct Rng(pub u64);

impl Rng {
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    /// Uniform in [0, 1).
    pub fn f32(&mut self) -> f32 {
        (self.next_u64() >> 40) as f32 / (1u64 << 24) as f32
    }
    pub fn range(&mut self, lo: f32, hi: f32) -> f32 {
        lo + (hi - lo) * self.f32()
    }
    pub fn usize(&mut self, n: usize) -> usize {
        (self.next_u64() % n as u64) as usize
    }
    /// Roughly normal (sum of uniforms).
    pub fn normal(&mut self) -> f32 {
        (0..6).map(|_| self.f32()).sum::<f32>() - 3.0
    }
}

/// Every real BVH clip, as (relative path, clip, map, humanoid status).
pub fn real_clips() -> Vec<(String, odori_core::Clip, odori_core::HumanoidMap, odori_core::HumanoidStatus)> {
    odori_tests::all_bvh()
        .into_iter()
        .map(|rel| {
            let opts = ImportOptions { fps_override: odori_tests::fps_override_for(&rel), ..Default::default() };
            let imp = import_bytes(&rel, &odori_tests::read(&rel), &opts).unwrap_or_else(|e| panic!("{rel}: {e}"));
            let clip = imp.clips.into_iter().next().unwrap_or_else(|| panic!("{rel}: no clip"));
            (rel, clip, imp.humanoid, imp.status)
        })
        .collect()
}

/// The library of all real clips; clips the importer judges not humanoid are skipped by the
/// index (listed in `skipped` with the reason).
pub fn real_index() -> FeatureIndex {
    let mut index = FeatureIndex::new();
    for (rel, clip, map, status) in real_clips() {
        let _ = index.add_clip(rel, &clip, &map, &status);
    }
    index
}

/// A reference match: (clip, start, end inclusive, distance).
pub type RefMatch = (usize, usize, usize, f32);

/// Spec §C from the text: g(i,j) = min{g(i−1,j)+d, g(i−1,j−1)+2d, g(i,j−1)+d} (first wins ties),
/// g(1,j) = d(1,j), G carried along; score g/(I + span) with span in [ceil(I·lo), floor(I·hi)];
/// candidates best first; each taken one's start re-chosen for its end by brute force (a DP
/// from every admissible start up to its own on its own, the one with the least score wins,
/// ties to the later start); kept if it overlaps no kept match; the kept ones sorted by their
/// scores.
/// Full matrices, nothing clever.
pub fn reference_search(index: &FeatureIndex, query: &ClipFeatures, params: &SearchParams) -> Vec<RefMatch> {
    let q = &query.features(params.origin).data;
    let rows = q.len() / FRAME_FLOATS;
    let min_span = ((rows as f32 * params.min_span_ratio).ceil() as usize).max(1);
    let max_span = ((rows as f32 * params.max_span_ratio).floor() as usize).max(min_span);
    let threshold = params.threshold.unwrap_or(f32::INFINITY);
    let d = |a: &[f32], b: &[f32]| -> f32 { ref_distance(params, a, b) };
    let mut cands: Vec<RefMatch> = Vec::new();
    for (ci, clip) in index.clips.iter().enumerate() {
        let t = &clip.features(params.origin).data;
        let cols = t.len() / FRAME_FLOATS;
        let mut g = vec![vec![0f32; cols]; rows];
        let mut gs = vec![vec![0usize; cols]; rows];
        for j in 0..cols {
            let tj = &t[j * FRAME_FLOATS..(j + 1) * FRAME_FLOATS];
            for i in 0..rows {
                let dd = d(&q[i * FRAME_FLOATS..(i + 1) * FRAME_FLOATS], tj);
                if i == 0 {
                    g[0][j] = dd;
                    gs[0][j] = j;
                    continue;
                }
                let mut best = (g[i - 1][j] + dd, gs[i - 1][j]);
                if j > 0 {
                    for cand in [(g[i - 1][j - 1] + 2.0 * dd, gs[i - 1][j - 1]), (g[i][j - 1] + dd, gs[i][j - 1])] {
                        if cand.0 < best.0 {
                            best = cand;
                        }
                    }
                }
                g[i][j] = best.0;
                gs[i][j] = best.1;
            }
            let start = gs[rows - 1][j];
            let span = j - start + 1;
            let score = g[rows - 1][j] / (rows + span) as f32;
            if span >= min_span && span <= max_span && score <= threshold {
                cands.push((ci, start, j, score));
            }
        }
    }
    cands.sort_by(|a, b| a.3.total_cmp(&b.3).then(a.0.cmp(&b.0)).then(a.2.cmp(&b.2)));
    let mut out: Vec<RefMatch> = Vec::new();
    for c in cands {
        if out.len() >= params.max_results {
            break;
        }
        let t = &index.clips[c.0].features(params.origin).data;
        let m = best_start(params, q, t, c, min_span, max_span);
        if out.iter().all(|o| o.0 != m.0 || m.2 < o.1 || m.1 > o.2) {
            out.push(m);
        }
    }
    out.sort_by(|a, b| a.3.total_cmp(&b.3).then(a.0.cmp(&b.0)).then(a.2.cmp(&b.2)));
    out
}

/// The frame distance of spec §C, summed as the core sums it: joints in `DISTANCE_ORDER`,
/// four at a time, each four as `(a + c) + (b + d)`, the fours in order.
pub fn ref_distance(params: &SearchParams, a: &[f32], b: &[f32]) -> f32 {
    let mut s = 0.0f32;
    for four in DISTANCE_ORDER.chunks(4) {
        let mut r = [0f32; 4];
        for (l, c) in four.iter().enumerate() {
            let w = params.weights[c.index()];
            let k = c.index() * 3;
            let e = ((a[k] - b[k]).powi(2) + (a[k + 1] - b[k + 1]).powi(2) + (a[k + 2] - b[k + 2]).powi(2)).sqrt();
            r[l] = w * e;
        }
        s += (r[0] + r[2]) + (r[1] + r[3]);
    }
    s
}

/// For candidate `(clip, start, end, _)`: the forward DP run from each admissible start
/// `s ≤ start` alone (row 0 entered only at column s), the one with the least `g / (I + span)`.
fn best_start(params: &SearchParams, q: &[f32], t: &[f32], cand: RefMatch, min_span: usize, max_span: usize) -> RefMatch {
    let (clip, latest, end) = (cand.0, cand.1, cand.2);
    let rows = q.len() / FRAME_FLOATS;
    let lo = (end + 1).saturating_sub(max_span);
    let dm: Vec<Vec<f32>> = (0..rows)
        .map(|i| (lo..=end).map(|j| ref_distance(params, &q[i * FRAME_FLOATS..(i + 1) * FRAME_FLOATS], &t[j * FRAME_FLOATS..(j + 1) * FRAME_FLOATS])).collect())
        .collect();
    let mut best: RefMatch = (clip, end, end, f32::INFINITY);
    for s in (lo..=end).rev() {
        let span = end + 1 - s;
        if span < min_span || span > max_span || s > latest {
            continue;
        }
        let (c0, n) = (s - lo, end + 1 - s);
        let mut g = vec![vec![f32::INFINITY; n]; rows];
        for c in 0..n {
            for i in 0..rows {
                let dd = dm[i][c0 + c];
                g[i][c] = if i == 0 {
                    if c == 0 { dd } else { f32::INFINITY }
                } else {
                    let mut v = g[i - 1][c] + dd;
                    if c > 0 {
                        v = v.min(g[i - 1][c - 1] + 2.0 * dd).min(g[i][c - 1] + dd);
                    }
                    v
                };
            }
        }
        let score = g[rows - 1][n - 1] / (rows + span) as f32;
        if score < best.3 {
            best = (clip, s, end, score);
        }
    }
    best
}

/// Left/right mirror of normalised hip-origin features: swap the sides, negate the lateral axis
/// (+Z is the hips' right → left direction after normalisation); `flip_forward` also negates x.
pub fn mirrored(f: &MotionFeatures, flip_forward: bool) -> MotionFeatures {
    use odori_core::humanoid::Canon::*;
    let pairs = [
        (LeftShoulder, RightShoulder),
        (LeftUpperArm, RightUpperArm),
        (LeftForearm, RightForearm),
        (LeftHand, RightHand),
        (LeftUpperLeg, RightUpperLeg),
        (LeftLowerLeg, RightLowerLeg),
        (LeftFoot, RightFoot),
        (LeftToe, RightToe),
    ];
    let mut data = f.data.clone();
    for fr in data.chunks_exact_mut(FRAME_FLOATS) {
        for (a, b) in pairs {
            for k in 0..3 {
                fr.swap(a.index() * 3 + k, b.index() * 3 + k);
            }
        }
        for p in fr.chunks_exact_mut(3) {
            p[2] = -p[2];
            if flip_forward {
                p[0] = -p[0];
            }
        }
    }
    MotionFeatures { origin: f.origin, data }
}
