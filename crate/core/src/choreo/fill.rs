//! Filling the open bars (spec §G): a shortest path through a layered graph, one layer per
//! bar, one node per segment in an open bar and the single pinned segment in a pinned bar.
//!
//! The edge cost from segment A to segment B is C = 1 / S with S = S_pose + S_move exactly as
//! spec §G, over the 20 canonical links with weights β_l (summing to 1):
//! - S_pose = Σ β_l · h(v_l(i_A)) · h(v_l(j_B)),
//! - S_move = Σ β_l · g[h(v_l(j_B) − v_l(i_A)) · h(v̇_l(i_A))] + Σ β_l · g[h(v_l(j_B) − v_l(i_A)) · h(v̇_l(j_B))],
//!
//! with i_A the last frame A plays, j_B the first frame of B, link vectors from the normalised
//! body (spec §B), h normalisation to unit length and g[x] = max(x, 0). Where the spec leaves
//! it open: S is floored at 0.02 (so C ≤ 50), and a link that does not move across the join
//! (|v_l(j_B) − v_l(i_A)| < 1e-5) continues perfectly, g = 1 on both sides.
//!
//! The product adds two terms: a music term `music_weight · |bar intensity − segment
//! intensity|` per open bar, and a repetition penalty `repeat_penalty` on an edge whose two
//! segments share frames of the same clip (the same segment twice in a row included). Both
//! keep the objective a sum over edges and nodes, so the dynamic programme below is exact: it
//! returns a minimum-cost path (ties broken towards lower segment indices).
//!
//! Speed: the M × M edge costs depend only on the library and are computed once per library
//! (cached by [`super::SegmentLibrary::transition_table`]). Each open layer then relaxes rows in
//! increasing order of the previous layer's cost and stops as soon as no remaining row can
//! improve any column (prev[a] ≥ max_b (best[b] − min_a' C(a', b))), which is exact.

use serde::{Deserialize, Serialize};
use thiserror::Error;

use super::segment::{SegmentLibrary, LINK_COUNT};

/// Floor on S, so C = 1/S stays finite.
pub const MIN_S: f32 = 0.02;

/// Per-link weights β_l, summing to 1: limbs' end links weigh a little more than the spine.
pub fn link_weights() -> [f32; LINK_COUNT] {
    let mut w = [1.0f32; LINK_COUNT];
    // Forearm→hand and lower leg→foot links carry the visible motion.
    for l in [6, 7, 10, 11, 13, 14, 17, 18] {
        w[l] = 1.5;
    }
    let sum: f32 = w.iter().sum();
    w.map(|x| x / sum)
}

/// The M × M edge costs C(a, b) (repetition penalty included), row-major by `a`.
#[derive(Clone, Debug, PartialEq)]
pub struct TransitionTable {
    m: usize,
    costs: Vec<f32>,
    col_min: Vec<f32>,
    repeat_penalty: f32,
}

impl TransitionTable {
    /// A table from given costs (row-major, `m * m`); for tests and other libraries. Non-finite
    /// or negative costs are clamped to `0..=1e6`.
    pub fn from_costs(m: usize, mut costs: Vec<f32>) -> TransitionTable {
        costs.resize(m * m, 1e6);
        for c in costs.iter_mut() {
            *c = if c.is_finite() { c.clamp(0.0, 1e6) } else { 1e6 };
        }
        let col_min = column_minima(m, &costs);
        TransitionTable { m, costs, col_min, repeat_penalty: 0.0 }
    }

    /// Spec §G's costs between every pair of the library's segments, plus `repeat_penalty` on
    /// pairs that share clip frames.
    pub fn from_library(lib: &SegmentLibrary, repeat_penalty: f32) -> TransitionTable {
        let m = lib.len();
        let beta = link_weights();
        // Flat SoA copies of the join features.
        let ends = &lib.ends;
        let unit = |v: glam::Vec3| v.normalize_or_zero();
        let end_u: Vec<[glam::Vec3; LINK_COUNT]> = ends.iter().map(|e| e.end.map(unit)).collect();
        let start_u: Vec<[glam::Vec3; LINK_COUNT]> = ends.iter().map(|e| e.start.map(unit)).collect();
        let end_vu: Vec<[glam::Vec3; LINK_COUNT]> = ends.iter().map(|e| e.end_velocity.map(unit)).collect();
        let start_vu: Vec<[glam::Vec3; LINK_COUNT]> = ends.iter().map(|e| e.start_velocity.map(unit)).collect();
        let mut costs = vec![0.0f32; m * m];
        for a in 0..m {
            let ea = &ends[a];
            let row = &mut costs[a * m..(a + 1) * m];
            for (b, slot) in row.iter_mut().enumerate() {
                let eb = &ends[b];
                let mut s = 0.0f32;
                for l in 0..LINK_COUNT {
                    let pose = end_u[a][l].dot(start_u[b][l]);
                    let d = eb.start[l] - ea.end[l];
                    let len = d.length();
                    let mv = if len < 1e-5 {
                        2.0
                    } else {
                        let dn = d / len;
                        dn.dot(end_vu[a][l]).max(0.0) + dn.dot(start_vu[b][l]).max(0.0)
                    };
                    s += beta[l] * (pose + mv);
                }
                *slot = 1.0 / s.max(MIN_S);
            }
        }
        for (a, ov) in lib.overlaps.iter().enumerate() {
            for &b in ov {
                if b < m {
                    costs[a * m + b] += repeat_penalty;
                }
            }
        }
        let col_min = column_minima(m, &costs);
        TransitionTable { m, costs, col_min, repeat_penalty }
    }

    /// Number of segments.
    pub fn len(&self) -> usize {
        self.m
    }

    pub fn is_empty(&self) -> bool {
        self.m == 0
    }

    /// C(a, b); infinite when out of range.
    pub fn cost(&self, a: usize, b: usize) -> f32 {
        if a < self.m && b < self.m {
            self.costs[a * self.m + b]
        } else {
            f32::INFINITY
        }
    }

    pub fn repeat_penalty(&self) -> f32 {
        self.repeat_penalty
    }

    fn row(&self, a: usize) -> &[f32] {
        &self.costs[a * self.m..(a + 1) * self.m]
    }
}

fn column_minima(m: usize, costs: &[f32]) -> Vec<f32> {
    let mut col = vec![f32::INFINITY; m];
    for row in costs.chunks_exact(m.max(1)) {
        for (c, v) in col.iter_mut().zip(row) {
            *c = c.min(*v);
        }
    }
    col
}

/// One bar of the filling problem.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "camelCase")]
pub enum Layer {
    /// A pinned bar: this segment, fixed.
    Fixed { segment: usize },
    /// An open bar with the music's intensity there (0..1).
    Open { intensity: f32 },
}

/// Weights of the product's extra terms.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "camelCase", default)]
pub struct FillWeights {
    /// Weight of |bar intensity − segment intensity| per open bar (0 = the paper's method).
    pub music_weight: f32,
    /// Added to an edge between segments sharing frames of one clip.
    pub repeat_penalty: f32,
}

impl Default for FillWeights {
    fn default() -> Self {
        Self { music_weight: 1.0, repeat_penalty: 3.0 }
    }
}

#[derive(Debug, Error, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "camelCase")]
pub enum FillError {
    #[error("the segment library is empty: add the built-in moves or a humanoid clip first")]
    EmptyLibrary,
    #[error("bar {bar} is pinned to segment {segment}, but the library has only {segments} segments")]
    UnknownSegment { bar: usize, segment: usize, segments: usize },
    #[error("segment intensities: {given} given for {segments} segments")]
    IntensityCount { given: usize, segments: usize },
}

/// A minimum-cost choice of one segment per layer. `segment_intensity[s]` is segment `s`'s
/// intensity in 0..1. Returns the chosen segment per layer (pinned layers keep theirs) and the
/// path's cost.
pub fn fill(table: &TransitionTable, layers: &[Layer], segment_intensity: &[f32], weights: &FillWeights) -> Result<(Vec<usize>, f32), FillError> {
    let m = table.len();
    if m == 0 {
        return Err(FillError::EmptyLibrary);
    }
    if segment_intensity.len() != m {
        return Err(FillError::IntensityCount { given: segment_intensity.len(), segments: m });
    }
    for (bar, l) in layers.iter().enumerate() {
        if let Layer::Fixed { segment } = *l {
            if segment >= m {
                return Err(FillError::UnknownSegment { bar, segment, segments: m });
            }
        }
    }
    if layers.is_empty() {
        return Ok((Vec::new(), 0.0));
    }
    let music = |intensity: f32, b: usize| weights.music_weight * (intensity - segment_intensity[b]).abs();
    // Node costs of the current layer: either one fixed node or all m.
    enum Nodes {
        One(usize, f32),
        All(Vec<f32>),
    }
    let mut back: Vec<Vec<u32>> = Vec::with_capacity(layers.len());
    let mut cur = match layers[0] {
        Layer::Fixed { segment } => Nodes::One(segment, 0.0),
        Layer::Open { intensity } => Nodes::All((0..m).map(|b| music(intensity, b)).collect()),
    };
    back.push(Vec::new());
    let mut order: Vec<u32> = Vec::with_capacity(m);
    for layer in &layers[1..] {
        match (*layer, &cur) {
            (Layer::Fixed { segment }, Nodes::One(a, c)) => {
                let v = c + table.cost(*a, segment);
                back.push(vec![*a as u32]);
                cur = Nodes::One(segment, v);
            }
            (Layer::Fixed { segment }, Nodes::All(prev)) => {
                let mut best = (f32::INFINITY, 0usize);
                for (a, p) in prev.iter().enumerate() {
                    let v = p + table.cost(a, segment);
                    if v < best.0 {
                        best = (v, a);
                    }
                }
                back.push(vec![best.1 as u32]);
                cur = Nodes::One(segment, best.0);
            }
            (Layer::Open { intensity }, Nodes::One(a, c)) => {
                let row = table.row(*a);
                let next: Vec<f32> = (0..m).map(|b| c + row[b] + music(intensity, b)).collect();
                back.push(vec![*a as u32; m]);
                cur = Nodes::All(next);
            }
            (Layer::Open { intensity }, Nodes::All(prev)) => {
                let mut best = vec![f32::INFINITY; m];
                let mut arg = vec![0u32; m];
                order.clear();
                order.extend(0..m as u32);
                order.sort_by(|&x, &y| prev[x as usize].total_cmp(&prev[y as usize]).then(x.cmp(&y)));
                let mut threshold = f32::INFINITY;
                for (k, &a) in order.iter().enumerate() {
                    let pa = prev[a as usize];
                    if pa >= threshold {
                        break;
                    }
                    let row = table.row(a as usize);
                    for b in 0..m {
                        let v = pa + row[b];
                        // Rows come in increasing prev order, so `<` keeps the first (lowest
                        // prev, then lowest index) of equal costs; ties across rows with equal
                        // prev resolve to the lower index because `order` is sorted by index.
                        let better = v < best[b];
                        best[b] = if better { v } else { best[b] };
                        arg[b] = if better { a } else { arg[b] };
                    }
                    if k % 8 == 7 {
                        threshold = best.iter().zip(&table.col_min).map(|(b, c)| b - c).fold(f32::MIN, f32::max);
                    }
                }
                for (b, v) in best.iter_mut().enumerate() {
                    *v += music(intensity, b);
                }
                back.push(arg);
                cur = Nodes::All(best);
            }
        }
    }
    // Backtrack.
    let n = layers.len();
    let mut path = vec![0usize; n];
    let (mut node, total) = match &cur {
        Nodes::One(s, c) => (*s, *c),
        Nodes::All(v) => {
            let mut best = (f32::INFINITY, 0usize);
            for (b, c) in v.iter().enumerate() {
                if *c < best.0 {
                    best = (*c, b);
                }
            }
            (best.1, best.0)
        }
    };
    for t in (0..n).rev() {
        path[t] = match layers[t] {
            Layer::Fixed { segment } => segment,
            Layer::Open { .. } => node,
        };
        if t > 0 {
            let bt = &back[t];
            node = if bt.len() == 1 { bt[0] as usize } else { bt.get(path[t]).copied().unwrap_or(0) as usize };
        }
    }
    Ok((path, total))
}

/// The objective [`fill`] minimises, for any path (for checks and reports).
pub fn path_cost(table: &TransitionTable, layers: &[Layer], segment_intensity: &[f32], weights: &FillWeights, path: &[usize]) -> f32 {
    let mut c = 0.0;
    for (t, l) in layers.iter().enumerate() {
        let Some(&s) = path.get(t) else { return f32::INFINITY };
        if let Layer::Open { intensity } = l {
            c += weights.music_weight * (intensity - segment_intensity.get(s).copied().unwrap_or(f32::INFINITY)).abs();
        }
        if t > 0 {
            c += table.cost(path[t - 1], s);
        }
    }
    c
}
