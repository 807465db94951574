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
//! returns a minimum-cost path (ties broken towards lower segment indices). Repeats further
//! apart than one bar but within `repeat_window` bars (default 4: an A B A B alternation) are
//! not a sum over edges. They are charged in the same pass along each node's chosen path: when
//! a node's best predecessor path already used the same segment 2..=window bars earlier, the
//! node pays `repeat_penalty` (the usual path-dependent extension of Viterbi; it steers away
//! from repeats at no extra cost but is not guaranteed optimal for that term). The reported
//! cost is the full objective, window included. With `repeat_window` ≤ 1 the result is exactly
//! optimal.
//!
//! Speed: the M × M edge costs depend only on the library and are computed once per library
//! (cached by [`super::SegmentLibrary::transition_table`]) over structure-of-arrays copies of
//! the segment ends, in cache-sized blocks, so the inner loop vectorises; they are stored
//! column by column (all predecessors of one segment contiguous). In each open layer a column
//! first tries only its [`TOP_K`] cheapest edges and the previous layer's [`LOW_L`] cheapest
//! nodes, and accepts their best when it is provably optimal: any other predecessor costs at
//! least (the cheapest node outside that set) + (the cheapest edge outside that list).
//! Otherwise the whole column is reduced with a vectorised minimum. Either way the result is
//! exact.

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

/// The M × M edge costs C(a, b) (repetition penalty included), stored column by column (all
/// predecessors `a` of one `b` are contiguous), with each column's minimum.
#[derive(Clone, Debug, PartialEq)]
pub struct TransitionTable {
    m: usize,
    /// `costs[b * m + a]` = C(a, b).
    costs: Vec<f32>,
    col_min: Vec<f32>,
    /// `rows[a * m + b]` = C(a, b): the same costs row by row, for the fast path.
    rows: Vec<f32>,
    /// Per column, the [`TOP_K`] cheapest predecessors in increasing cost (then index).
    top: Vec<u32>,
    /// Their costs, alongside.
    top_cost: Vec<f32>,
    /// Per column, the cheapest cost outside its top list (a lower bound for the rest).
    rest_min: Vec<f32>,
    repeat_penalty: f32,
}

/// Predecessors kept per column for the fast path of the filling.
pub const TOP_K: usize = 96;
/// Cheapest nodes of the previous layer tried by every column on the fast path.
pub const LOW_L: usize = 96;

fn transpose(m: usize, costs: &[f32]) -> Vec<f32> {
    let mut t = vec![0.0f32; m * m];
    const TILE: usize = 64;
    for b0 in (0..m).step_by(TILE) {
        for a0 in (0..m).step_by(TILE) {
            for b in b0..(b0 + TILE).min(m) {
                for a in a0..(a0 + TILE).min(m) {
                    t[a * m + b] = costs[b * m + a];
                }
            }
        }
    }
    t
}

fn top_lists(m: usize, costs: &[f32]) -> (Vec<u32>, Vec<f32>) {
    let k = TOP_K.min(m);
    let mut top = Vec::with_capacity(m * k);
    let mut rest = Vec::with_capacity(m);
    let mut idx: Vec<u32> = Vec::with_capacity(m);
    for col in costs.chunks_exact(m.max(1)) {
        idx.clear();
        idx.extend(0..m as u32);
        let by = |x: &u32, y: &u32| col[*x as usize].total_cmp(&col[*y as usize]).then(x.cmp(y));
        if k < m {
            idx.select_nth_unstable_by(k, by);
            rest.push(col[idx[k] as usize]);
            // The rest's minimum is the k-th order statistic after selection.
            let r = idx[k..].iter().map(|&a| col[a as usize]).fold(f32::INFINITY, f32::min);
            if let Some(last) = rest.last_mut() {
                *last = r;
            }
        } else {
            rest.push(f32::INFINITY);
        }
        let head = &mut idx[..k];
        head.sort_by(by);
        top.extend_from_slice(head);
    }
    (top, rest)
}

fn top_costs(m: usize, costs: &[f32], top: &[u32]) -> Vec<f32> {
    let k = TOP_K.min(m);
    top.iter().enumerate().map(|(i, &a)| costs[(i / k.max(1)) * m + a as usize]).collect()
}

impl TransitionTable {
    /// A table from given costs (row-major by `a`: `costs[a * m + b]` = C(a, b)); for tests and
    /// other libraries. Non-finite or negative costs are clamped to `0..=1e6`.
    pub fn from_costs(m: usize, mut costs: Vec<f32>) -> TransitionTable {
        costs.resize(m * m, 1e6);
        let mut t = vec![0.0f32; m * m];
        for a in 0..m {
            for b in 0..m {
                let c = costs[a * m + b];
                t[b * m + a] = if c.is_finite() { c.clamp(0.0, 1e6) } else { 1e6 };
            }
        }
        let col_min = column_minima(m, &t);
        let (top, rest_min) = top_lists(m, &t);
        let top_cost = top_costs(m, &t, &top);
        let rows = transpose(m, &t);
        TransitionTable { m, costs: t, col_min, rows, top, top_cost, rest_min, repeat_penalty: 0.0 }
    }

    /// Spec §G's costs between every pair of the library's segments, plus `repeat_penalty` on
    /// pairs that share clip frames.
    pub fn from_library(lib: &SegmentLibrary, repeat_penalty: f32) -> TransitionTable {
        match Self::from_library_with_progress(lib, repeat_penalty, &mut |_| true) {
            Some(t) => t,
            None => TransitionTable::from_costs(0, Vec::new()),
        }
    }

    /// [`TransitionTable::from_library`] reporting progress (0..1) after each block of
    /// predecessors; the callback returns `false` to cancel (then `None`).
    pub fn from_library_with_progress(lib: &SegmentLibrary, repeat_penalty: f32, progress: &mut dyn FnMut(f32) -> bool) -> Option<TransitionTable> {
        let m = lib.len();
        let beta = link_weights();
        let ends = &lib.ends;
        // Structure-of-arrays copies of every segment's end (the `a` side), link-major, so the
        // inner loop over `a` is contiguous and vectorises.
        let soa = |f: &dyn Fn(&super::segment::JoinEnds, usize) -> glam::Vec3| -> [Vec<f32>; 3] {
            let mut out = [vec![0.0f32; LINK_COUNT * m], vec![0.0f32; LINK_COUNT * m], vec![0.0f32; LINK_COUNT * m]];
            for (a, e) in ends.iter().enumerate() {
                for l in 0..LINK_COUNT {
                    let v = f(e, l);
                    out[0][l * m + a] = v.x;
                    out[1][l * m + a] = v.y;
                    out[2][l * m + a] = v.z;
                }
            }
            out
        };
        let end = soa(&|e, l| e.end[l]);
        let end_u = soa(&|e, l| e.end[l].normalize_or_zero());
        let end_vu = soa(&|e, l| e.end_velocity[l].normalize_or_zero());
        let mut costs = vec![0.0f32; m * m];
        // Blocks of predecessors small enough that their link data stays in cache while every
        // successor column is filled.
        const BLOCK: usize = 256;
        let mut acc = [0.0f32; BLOCK];
        for a0 in (0..m).step_by(BLOCK) {
            let n = BLOCK.min(m - a0);
            for (b, eb) in ends.iter().enumerate() {
                let acc = &mut acc[..n];
                acc.iter_mut().for_each(|x| *x = 0.0);
                for l in 0..LINK_COUNT {
                    let s = eb.start[l];
                    let su = s.normalize_or_zero();
                    let wu = eb.start_velocity[l].normalize_or_zero();
                    let bl = beta[l];
                    let r = l * m + a0..l * m + a0 + n;
                    let (ex, ey, ez) = (&end[0][r.clone()], &end[1][r.clone()], &end[2][r.clone()]);
                    let (ux, uy, uz) = (&end_u[0][r.clone()], &end_u[1][r.clone()], &end_u[2][r.clone()]);
                    let (vx, vy, vz) = (&end_vu[0][r.clone()], &end_vu[1][r.clone()], &end_vu[2][r]);
                    for a in 0..n {
                        let pose = ux[a] * su.x + uy[a] * su.y + uz[a] * su.z;
                        let (dx, dy, dz) = (s.x - ex[a], s.y - ey[a], s.z - ez[a]);
                        let len2 = dx * dx + dy * dy + dz * dz;
                        let dv = dx * vx[a] + dy * vy[a] + dz * vz[a];
                        let dw = dx * wu.x + dy * wu.y + dz * wu.z;
                        let moving = (dv.max(0.0) + dw.max(0.0)) / len2.max(1e-10).sqrt();
                        // A link that does not move across the join continues perfectly (g = 1
                        // twice).
                        let mv = if len2 < 1e-10 { 2.0 } else { moving };
                        acc[a] += bl * (pose + mv);
                    }
                }
                for (slot, s) in costs[b * m + a0..b * m + a0 + n].iter_mut().zip(acc.iter()) {
                    *slot = 1.0 / s.max(MIN_S);
                }
            }
            if !progress((a0 + n) as f32 / m as f32) {
                return None;
            }
        }
        for (a, ov) in lib.overlaps.iter().enumerate() {
            for &b in ov {
                if b < m {
                    costs[b * m + a] += repeat_penalty;
                }
            }
        }
        let col_min = column_minima(m, &costs);
        let (top, rest_min) = top_lists(m, &costs);
        let top_cost = top_costs(m, &costs, &top);
        let rows = transpose(m, &costs);
        Some(TransitionTable { m, costs, col_min, rows, top, top_cost, rest_min, repeat_penalty })
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
            self.costs[b * self.m + a]
        } else {
            f32::INFINITY
        }
    }

    pub fn repeat_penalty(&self) -> f32 {
        self.repeat_penalty
    }

    /// All C(·, b), indexed by the predecessor.
    fn column(&self, b: usize) -> &[f32] {
        &self.costs[b * self.m..(b + 1) * self.m]
    }
}

fn column_minima(m: usize, costs: &[f32]) -> Vec<f32> {
    costs.chunks_exact(m.max(1)).map(|col| col.iter().cloned().fold(f32::INFINITY, f32::min)).collect()
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
    /// Added to an edge between segments sharing frames of one clip, and to an open bar that
    /// repeats a segment used within `repeat_window` bars before it.
    pub repeat_penalty: f32,
    /// Bars within which a repeated segment counts as "too soon" (1: only the bar right
    /// before, which the exact search handles; larger windows are charged along the chosen
    /// paths, see the module documentation).
    pub repeat_window: usize,
}

impl Default for FillWeights {
    fn default() -> Self {
        Self { music_weight: 1.0, repeat_penalty: 3.0, repeat_window: 4 }
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

/// min over `a` of `prev[a] + col[a]` and the first `a` reaching it.
fn column_min(prev: &[f32], col: &[f32]) -> (f32, usize) {
    let n = prev.len().min(col.len());
    let (prev, col) = (&prev[..n], &col[..n]);
    let mut lanes = [f32::INFINITY; 8];
    let split = n - n % 8;
    for (p8, c8) in prev[..split].chunks_exact(8).zip(col[..split].chunks_exact(8)) {
        for i in 0..8 {
            let v = p8[i] + c8[i];
            lanes[i] = if v < lanes[i] { v } else { lanes[i] };
        }
    }
    let mut min = lanes.iter().cloned().fold(f32::INFINITY, f32::min);
    for a in split..n {
        let v = prev[a] + col[a];
        if v < min {
            min = v;
        }
    }
    let at = (0..n).find(|&a| prev[a] + col[a] == min).unwrap_or(0);
    (min, at)
}

/// Whether segment `b` in layer `t`, reached from node `pred` of layer `t - 1`, repeats a
/// segment of that node's best path 2..=`window` layers back.
fn repeats_on_path(back: &[Vec<u32>], t: usize, pred: usize, b: usize, window: usize) -> bool {
    let (mut node, mut layer) = (pred, t.saturating_sub(1));
    for _ in 2..=window {
        if layer == 0 {
            return false;
        }
        let Some(bt) = back.get(layer) else { return false };
        node = if bt.len() == 1 { bt[0] as usize } else { bt.get(node).copied().unwrap_or(0) as usize };
        layer -= 1;
        if node == b {
            return true;
        }
    }
    false
}

/// Whether bar `t` of a path repeats a segment used 2..=`window` bars before it.
fn repeats_too_soon(path: &[usize], t: usize, window: usize) -> bool {
    (2..=window).any(|d| t >= d && path[t - d] == path[t])
}

/// How much work a filling did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "camelCase")]
pub struct FillStats {
    /// Columns (open-bar nodes after an open bar) relaxed.
    pub open_columns: usize,
    /// Of those, columns whose top-[`TOP_K`] list could not prove the optimum and were scanned.
    pub full_scans: usize,
    /// Nodes charged for repeating a segment of their path within the window.
    pub window_charges: usize,
}

/// A minimum-cost choice of one segment per layer. `segment_intensity[s]` is segment `s`'s
/// intensity in 0..1. Returns the chosen segment per layer (pinned layers keep theirs) and the
/// path's cost.
pub fn fill(table: &TransitionTable, layers: &[Layer], segment_intensity: &[f32], weights: &FillWeights) -> Result<(Vec<usize>, f32), FillError> {
    fill_with_stats(table, layers, segment_intensity, weights).map(|(p, c, _)| (p, c))
}

/// [`fill`], also saying how much work it took.
pub fn fill_with_stats(table: &TransitionTable, layers: &[Layer], segment_intensity: &[f32], weights: &FillWeights) -> Result<(Vec<usize>, f32, FillStats), FillError> {
    let mut stats = FillStats::default();
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
        return Ok((Vec::new(), 0.0, stats));
    }
    let window = if weights.repeat_penalty > 0.0 { weights.repeat_window } else { 0 };
    let music = |intensity: f32, b: usize| weights.music_weight * (intensity - segment_intensity[b]).abs();
    // Node costs of the current layer: either one fixed node or all m.
    enum Nodes {
        One(usize, f32),
        All(Vec<f32>),
    }
    let mut back: Vec<Vec<u32>> = Vec::with_capacity(layers.len());
    let mut low: Vec<u32> = Vec::with_capacity(m);
    let mut cur = match layers[0] {
        Layer::Fixed { segment } => Nodes::One(segment, 0.0),
        Layer::Open { intensity } => {
            Nodes::All((0..m).map(|b| music(intensity, b)).collect())
        }
    };
    back.push(Vec::new());
    for (t, layer) in layers.iter().enumerate().skip(1) {
        match (*layer, &cur) {
            (Layer::Fixed { segment }, Nodes::One(a, c)) => {
                let v = c + table.cost(*a, segment);
                back.push(vec![*a as u32]);
                cur = Nodes::One(segment, v);
            }
            (Layer::Fixed { segment }, Nodes::All(prev)) => {
                let col = table.column(segment);
                let mut best = (f32::INFINITY, 0usize);
                for (a, (p, c)) in prev.iter().zip(col).enumerate() {
                    let v = p + c;
                    if v < best.0 {
                        best = (v, a);
                    }
                }
                back.push(vec![best.1 as u32]);
                cur = Nodes::One(segment, best.0);
            }
            (Layer::Open { intensity }, Nodes::One(a, c)) => {
                let mut next: Vec<f32> = (0..m).map(|b| c + table.cost(*a, b) + music(intensity, b)).collect();
                for (b, v) in next.iter_mut().enumerate() {
                    if repeats_on_path(&back, t, *a, b, window) {
                        *v += weights.repeat_penalty;
                        stats.window_charges += 1;
                    }
                }
                back.push(vec![*a as u32; m]);
                cur = Nodes::All(next);
            }
            (Layer::Open { intensity }, Nodes::All(prev)) => {
                // The previous layer's LOW_L cheapest nodes, and the cheapest cost outside them.
                low.clear();
                low.extend(0..m as u32);
                let l = LOW_L.min(m);
                let prev_rest = if l < m {
                    low.select_nth_unstable_by(l, |x, y| prev[*x as usize].total_cmp(&prev[*y as usize]).then(x.cmp(y)));
                    let r = low[l..].iter().map(|&a| prev[a as usize]).fold(f32::INFINITY, f32::min);
                    low.truncate(l);
                    r
                } else {
                    f32::INFINITY
                };
                let k = TOP_K.min(m);
                // The cheapest nodes' rows, streamed (vectorised).
                let mut next = vec![f32::INFINITY; m];
                let mut arg = vec![0u32; m];
                low.sort_unstable();
                for &a in low.iter() {
                    let pa = prev[a as usize];
                    let row = &table.rows[a as usize * m..(a as usize + 1) * m];
                    for ((n, g), &c) in next.iter_mut().zip(arg.iter_mut()).zip(row) {
                        let v = pa + c;
                        let better = v < *n;
                        *n = if better { v } else { *n };
                        *g = if better { a } else { *g };
                    }
                }
                for b in 0..m {
                    let (mut best, mut best_a) = (next[b], arg[b]);
                    // Then the column's cheapest edges. Any other predecessor costs at least
                    // prev_rest + rest_min[b], so the best found is exact when no worse.
                    let (ti, tc) = (&table.top[b * k..(b + 1) * k], &table.top_cost[b * k..(b + 1) * k]);
                    for (&a, &c) in ti.iter().zip(tc) {
                        let v = prev[a as usize] + c;
                        if v < best || (v == best && a < best_a) {
                            best = v;
                            best_a = a;
                        }
                    }
                    if best > prev_rest + table.rest_min[b] {
                        // Not provable from the list: the whole column, contiguous (vectorised
                        // minimum, then the first predecessor reaching it).
                        let (min, at) = column_min(prev, table.column(b));
                        best = min;
                        best_a = at as u32;
                        stats.full_scans += 1;
                    }
                    next[b] = best + music(intensity, b);
                    arg[b] = best_a;
                }
                stats.open_columns += m;
                for (b, v) in next.iter_mut().enumerate() {
                    if repeats_on_path(&back, t, arg[b] as usize, b, window) {
                        *v += weights.repeat_penalty;
                        stats.window_charges += 1;
                    }
                }
                back.push(arg);
                cur = Nodes::All(next);
            }
        }
    }
    // Backtrack.
    let n = layers.len();
    let mut path = vec![0usize; n];
    // The last layer's best node (its cost is recomputed below with the full objective).
    let mut node = match &cur {
        Nodes::One(s, _) => *s,
        Nodes::All(v) => {
            let mut best = (f32::INFINITY, 0usize);
            for (b, c) in v.iter().enumerate() {
                if *c < best.0 {
                    best = (*c, b);
                }
            }
            best.1
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
    let cost = path_cost(table, layers, segment_intensity, weights, &path);
    Ok((path, cost, stats))
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
        if weights.repeat_window > 1 && matches!(l, Layer::Open { .. }) && repeats_too_soon(path, t, weights.repeat_window) {
            c += weights.repeat_penalty;
        }
    }
    c
}
