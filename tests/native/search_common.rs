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

/// Brute force, from the text of spec §C: for every start s of every clip, the DP run from
/// (0, s) alone with the symmetric slope-constrained steps (P = 1) — start cell 2·d, diagonal
/// + 2·d(i, j), through (i, j−1): + (2·d(i, j−1) + d(i, j)), through (i−1, j): + (2·d(i−1, j) +
/// d(i, j)) — gives the least cost C(s, e) of every (s, e) pair on its own; an end's match is
/// the start with the least C(s, e) / (I + span) (ties to the earlier start); ends are taken
/// best first by (distance, clip, end), each unless it shares more than half of the shorter
/// span with one already taken in its clip, up to maxResults and within the threshold.
/// Full matrices, nothing clever.
pub fn reference_search(index: &FeatureIndex, query: &ClipFeatures, params: &SearchParams) -> Vec<RefMatch> {
    let mut ends = reference_ends(index, query, params);
    let threshold = params.threshold.unwrap_or(f32::INFINITY);
    ends.retain(|e| e.3 <= threshold);
    ends.sort_by(|a, b| a.3.total_cmp(&b.3).then(a.0.cmp(&b.0)).then(a.2.cmp(&b.2)));
    let mut out: Vec<RefMatch> = Vec::new();
    for c in ends {
        if out.len() >= params.max_results {
            break;
        }
        if out.iter().all(|o| !ref_conflict(o, &c)) {
            out.push(c);
        }
    }
    out
}

/// Whether two spans of one clip share more than half of the shorter one's frames.
pub fn ref_conflict(a: &RefMatch, b: &RefMatch) -> bool {
    if a.0 != b.0 {
        return false;
    }
    let shared = (a.2.min(b.2) + 1).saturating_sub(a.1.max(b.1));
    let shorter = (a.2 - a.1 + 1).min(b.2 - b.1 + 1);
    2 * shared > shorter
}

/// Every end of every clip with its match (least distance over every start), by brute force.
pub fn reference_ends(index: &FeatureIndex, query: &ClipFeatures, params: &SearchParams) -> Vec<RefMatch> {
    let q = &query.features(params.origin).data;
    let rows = q.len() / FRAME_FLOATS;
    let max_span = 2 * (rows - 1) + 1;
    let mut out = Vec::new();
    for (ci, clip) in index.clips.iter().enumerate() {
        let t = &clip.features(params.origin).data;
        let cols = t.len() / FRAME_FLOATS;
        let mut best: Vec<Option<(f32, usize, f32)>> = vec![None; cols];
        // Every frame distance once (the starts share them).
        let dm: Vec<Vec<f32>> = (0..rows)
            .map(|i| (0..cols).map(|j| ref_distance(params, &q[i * FRAME_FLOATS..(i + 1) * FRAME_FLOATS], &t[j * FRAME_FLOATS..(j + 1) * FRAME_FLOATS])).collect())
            .collect();
        for s in 0..cols {
            let n = max_span.min(cols - s);
            let d: Vec<&[f32]> = dm.iter().map(|row| &row[s..s + n]).collect();
            let mut g = vec![vec![f32::INFINITY; n]; rows];
            g[0][0] = 2.0 * d[0][0];
            for k in 0..n {
                for i in 1..rows {
                    let mut v = f32::INFINITY;
                    if k >= 1 {
                        v = v.min(g[i - 1][k - 1] + 2.0 * d[i][k]);
                    }
                    if k >= 2 {
                        v = v.min(g[i - 1][k - 2] + (2.0 * d[i][k - 1] + d[i][k]));
                    }
                    if k >= 1 && i >= 2 {
                        v = v.min(g[i - 2][k - 1] + (2.0 * d[i - 1][k] + d[i][k]));
                    }
                    g[i][k] = v;
                }
            }
            for k in 0..n {
                let c = g[rows - 1][k];
                if !c.is_finite() {
                    continue;
                }
                let score = c / (rows + k + 1) as f32;
                let e = s + k;
                // Starts are visited in increasing order: strict < keeps the earlier on ties.
                if best[e].is_none_or(|b| score < b.0) {
                    best[e] = Some((score, s, c));
                }
            }
        }
        for (e, b) in best.iter().enumerate() {
            if let Some((score, s, _)) = b {
                out.push((ci, *s, e, *score));
            }
        }
    }
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

/// Left/right mirror of normalised hip-origin features: swap the sides, negate the lateral axis
/// (+Z is the hips' right → left direction after normalisation); `flip_forward` also negates x.
pub fn mirrored(f: &MotionFeatures, flip_forward: bool) -> MotionFeatures {
    use odori_core::canon::humanoid::Canon::*;
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
