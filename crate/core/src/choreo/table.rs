//! The transition table of spec §G: C(a, b) = 1 / S(a, b) for every ordered pair of library
//! segments, S = S_pose + S_move over the 20 canonical links with weights β_l (summing to 1):
//! - S_pose = Σ β_l · h(v_l(i_A)) · h(v_l(j_B)),
//! - S_move = Σ β_l · g[h(v_l(j_B) − v_l(i_A)) · h(v̇_l(i_A))] + Σ β_l · g[h(v_l(j_B) − v_l(i_A)) · h(v̇_l(j_B))],
//!
//! with i_A the last frame A plays, j_B the first frame of B, link vectors from the normalised
//! body (spec §B), h normalisation to unit length and g[x] = max(x, 0). Where the spec leaves
//! it open: S is floored at [`MIN_S`] (so C ≤ 50), and a link that does not move across the
//! join (|v_l(j_B) − v_l(i_A)| < 1e-5) continues perfectly, g = 1 on both sides. The product
//! adds `repeat_penalty` to an edge whose two segments share frames of the same clip, and an
//! end-effector gap term, [`END_GAP_WEIGHT`] × Σ over hands and feet of the distance between
//! where each is at the end of A and at the start of B (normalised body), which S, a sum of
//! per-link cosines, barely sees (see [`END_GAP_WEIGHT`]).
//!
//! Speed. The costs need one square root and one division per link and pair (the jump
//! direction h(v_l(j_B) − v_l(i_A)) cannot be factored), so the work is M² · 20 of those;
//! everything else is arranged around that loop: every segment's end-of-segment link data is
//! copied once into flat, link-major `f32` arrays with h(·) and β_l already applied (β_l ≥ 0,
//! so β·g[x] = g[β·x]), and the loop over predecessors runs over them in cache-sized blocks
//! with no branch, so it vectorises (SSE natively, `simd128` in the web build). The table is
//! built by a [`TableBuilder`] in slices of columns, so a host can spread it over frames and
//! show progress; the same builder run to the end is [`TransitionTable::from_library`].
//!
//! Layout. Costs are stored column by column (all predecessors of one segment contiguous) and
//! row by row (for the filling's fast path), with each column's [`TOP_K`] cheapest
//! predecessors and a lower bound on the rest.

use super::segment::{JoinEnds, SegmentLibrary, LINKS, LINK_COUNT};

/// Floor on S, so C = 1/S stays finite.
pub const MIN_S: f32 = 0.02;
/// The product's end-effector gap term, added to C(a, b): this weight times the summed
/// distance (body heights, in the normalised body of spec §B: hips origin, facing removed)
/// between where each hand and foot is at the end of A and at the start of B. Why: S compares
/// each link's direction by its cosine, which hardly moves for the 20–40° per link that add up
/// along an arm to a hand half a metre away, and the renderer's join must then carry the hand
/// that far in a few frames (the largest join jumps of §J measured on mocap joins were hands
/// moving 0.3–0.7 m across the join at ordinary C). At 1 per body height, a hand 0.3 body
/// heights off costs 0.3: the spread between a good and a middling C.
pub const END_GAP_WEIGHT: f32 = 1.0;
/// The end effectors of [`END_GAP_WEIGHT`]: hands and feet (canonical indices).
const END_EFFECTORS: [usize; 4] = [8, 12, 15, 19];
/// Floats per segment of the end-effector positions (xyz of each).
const GAP_FLOATS: usize = 3 * END_EFFECTORS.len();
/// Predecessors kept per column for the fast path of the filling.
pub const TOP_K: usize = 96;
/// |v_l(j_B) − v_l(i_A)|² below which a link counts as not moving across the join.
const STILL_LEN2: f32 = 1e-10;

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
/// predecessors `a` of one `b` are contiguous) and row by row, with each column's cheapest
/// predecessors.
#[derive(Clone, Debug, PartialEq)]
pub struct TransitionTable {
    pub(crate) m: usize,
    /// `costs[b * m + a]` = C(a, b).
    pub(crate) costs: Vec<f32>,
    /// `rows[a * m + b]` = C(a, b): the same costs row by row, for the fast path.
    pub(crate) rows: Vec<f32>,
    /// Per column, the [`TOP_K`] cheapest predecessors in increasing cost (then index).
    pub(crate) top: Vec<u32>,
    /// Their costs, alongside.
    pub(crate) top_cost: Vec<f32>,
    /// Per column, the cheapest cost outside its top list (a lower bound for the rest).
    pub(crate) rest_min: Vec<f32>,
    /// Segments that may fill an open bar (`false`: kept only for the bars that already hold
    /// them, see [`SegmentLibrary::recut_clip`]).
    pub(crate) available: Vec<bool>,
    repeat_penalty: f32,
    /// The library revision the table was built from (0 for tables built from given costs).
    revision: u64,
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
        let mut b = TableBuilder::empty(m, t, vec![true; m], 0.0, 0);
        b.next_col = m;
        while !b.step(usize::MAX).is_done() {}
        b.finish().unwrap_or_else(|| unreachable_empty(m))
    }

    /// Spec §G's costs between every pair of the library's segments, plus `repeat_penalty` on
    /// pairs that share clip frames.
    pub fn from_library(lib: &SegmentLibrary, repeat_penalty: f32) -> TransitionTable {
        let mut b = TableBuilder::new(lib, repeat_penalty);
        while !b.step(usize::MAX).is_done() {}
        b.finish().unwrap_or_else(|| unreachable_empty(lib.len()))
    }

    /// [`TransitionTable::from_library`] reporting progress (0..1) after each slice of
    /// columns; the callback returns `false` to cancel (then `None`).
    pub fn from_library_with_progress(lib: &SegmentLibrary, repeat_penalty: f32, progress: &mut dyn FnMut(f32) -> bool) -> Option<TransitionTable> {
        let mut b = TableBuilder::new(lib, repeat_penalty);
        loop {
            let p = b.step(SLICE_COLUMNS);
            if !progress(p.fraction()) {
                return None;
            }
            if p.is_done() {
                return b.finish();
            }
        }
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

    /// The library revision this table was built from.
    pub fn revision(&self) -> u64 {
        self.revision
    }

    /// Whether segment `s` may fill an open bar.
    pub fn is_available(&self, s: usize) -> bool {
        self.available.get(s).copied().unwrap_or(false)
    }

    /// All C(·, b), indexed by the predecessor.
    pub(crate) fn column(&self, b: usize) -> &[f32] {
        &self.costs[b * self.m..(b + 1) * self.m]
    }
}

/// A finished builder always yields a table; this keeps the constructors total without a panic.
fn unreachable_empty(m: usize) -> TransitionTable {
    debug_assert!(m == 0, "a finished table builder gave no table");
    TransitionTable {
        m: 0,
        costs: Vec::new(),
        rows: Vec::new(),
        top: Vec::new(),
        top_cost: Vec::new(),
        rest_min: Vec::new(),
        available: Vec::new(),
        repeat_penalty: 0.0,
        revision: 0,
    }
}

/// Columns per progress report of [`TransitionTable::from_library_with_progress`].
const SLICE_COLUMNS: usize = 256;
/// Predecessors per block of the pair loop: their link data (9 floats × 20 links each) stays
/// in cache while a slice of columns is filled.
const BLOCK: usize = 256;
/// Floats per link and predecessor: end link (3), β·h(end link) (3), β·h(end velocity) (3).
const A_FLOATS: usize = 9;

/// How far a [`TableBuilder`] has got.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TableProgress {
    /// Units of work done and in all (a pair column counts [`PAIR_UNITS`], a column's top
    /// list and its row of the transposed copy one each).
    pub done: usize,
    pub total: usize,
}

/// Work of one pair column relative to sorting out one column's top list.
pub const PAIR_UNITS: usize = 8;

impl TableProgress {
    pub fn fraction(&self) -> f32 {
        if self.total == 0 {
            1.0
        } else {
            self.done as f32 / self.total as f32
        }
    }

    pub fn is_done(&self) -> bool {
        self.done >= self.total
    }
}

/// Builds a [`TransitionTable`] in slices: [`TableBuilder::step`] does up to a given number
/// of columns and says how far it got; [`TableBuilder::finish`] hands over the table. It owns
/// copies of what it needs, so the library may be read (not changed) meanwhile; a table built
/// from an older revision of the library is refused by [`SegmentLibrary::install_table`].
#[derive(Clone, Debug)]
pub struct TableBuilder {
    m: usize,
    /// Predecessor side, `[l][A_FLOATS][m]`: end link xyz, β·h(end) xyz, β·h(end velocity) xyz.
    a_side: Vec<f32>,
    /// Successor side, `[b][l][10]`: start link xyz, β·h(start) xyz, β·h(start velocity) xyz, 2β.
    b_side: Vec<f32>,
    /// Predecessor end-effector positions at their end, `[GAP_FLOATS][m]`.
    a_gap: Vec<f32>,
    /// Successor end-effector positions at their start, `[b][GAP_FLOATS]`.
    b_gap: Vec<f32>,
    overlaps: Vec<Vec<usize>>,
    costs: Vec<f32>,
    available: Vec<bool>,
    repeat_penalty: f32,
    revision: u64,
    /// Next column of pair costs to compute.
    next_col: usize,
    /// Next column whose top list is to be sorted out.
    next_top: usize,
    /// Next block of rows of the transposed copy.
    next_row: usize,
    top: Vec<u32>,
    top_cost: Vec<f32>,
    rest_min: Vec<f32>,
    rows: Vec<f32>,
    scratch: Vec<f32>,
}

/// The unit vector, or zero for a (near-)zero vector (h of the spec).
fn unit(v: glam::Vec3) -> glam::Vec3 {
    v.normalize_or_zero()
}

impl TableBuilder {
    /// A builder for the library's table with the given repetition penalty.
    pub fn new(lib: &SegmentLibrary, repeat_penalty: f32) -> TableBuilder {
        let m = lib.len();
        let beta = link_weights();
        let ends: &[JoinEnds] = &lib.ends;
        let mut a_side = vec![0.0f32; LINK_COUNT * A_FLOATS * m];
        let mut b_side = vec![0.0f32; m * LINK_COUNT * 10];
        for (s, e) in ends.iter().enumerate() {
            for l in 0..LINK_COUNT {
                let bl = beta[l];
                let (end, end_u, end_v) = (e.end[l], unit(e.end[l]) * bl, unit(e.end_velocity[l]) * bl);
                let base = l * A_FLOATS * m;
                for (k, x) in [end.x, end.y, end.z, end_u.x, end_u.y, end_u.z, end_v.x, end_v.y, end_v.z].into_iter().enumerate() {
                    a_side[base + k * m + s] = x;
                }
                // h(start) carries no β: β is already in h(end) of the dot product.
                let (start, start_u, start_w) = (e.start[l], unit(e.start[l]), unit(e.start_velocity[l]) * bl);
                let o = (s * LINK_COUNT + l) * 10;
                b_side[o..o + 10].copy_from_slice(&[start.x, start.y, start.z, start_u.x, start_u.y, start_u.z, start_w.x, start_w.y, start_w.z, 2.0 * bl]);
            }
        }
        // End-effector positions from the link vectors: each joint is its parent plus the link.
        let mut a_gap = vec![0.0f32; GAP_FLOATS * m];
        let mut b_gap = vec![0.0f32; m * GAP_FLOATS];
        for (s, e) in ends.iter().enumerate() {
            for (k, &joint) in END_EFFECTORS.iter().enumerate() {
                let (mut at_end, mut at_start) = (glam::Vec3::ZERO, glam::Vec3::ZERO);
                let mut j = joint;
                while let Some(l) = LINKS.iter().position(|&(_, c)| c == j) {
                    at_end += e.end[l];
                    at_start += e.start[l];
                    j = LINKS[l].0;
                }
                for (c, (x, y)) in [(at_end.x, at_start.x), (at_end.y, at_start.y), (at_end.z, at_start.z)].into_iter().enumerate() {
                    a_gap[(3 * k + c) * m + s] = x;
                    b_gap[s * GAP_FLOATS + 3 * k + c] = y;
                }
            }
        }
        let available = lib.segments().iter().map(|s| !s.retired).collect();
        let mut b = TableBuilder::empty(m, vec![0.0f32; m * m], available, repeat_penalty, lib.revision());
        b.a_side = a_side;
        b.b_side = b_side;
        b.a_gap = a_gap;
        b.b_gap = b_gap;
        b.overlaps = lib.overlaps.clone();
        b
    }

    fn empty(m: usize, costs: Vec<f32>, available: Vec<bool>, repeat_penalty: f32, revision: u64) -> TableBuilder {
        TableBuilder {
            m,
            a_side: Vec::new(),
            b_side: Vec::new(),
            a_gap: Vec::new(),
            b_gap: Vec::new(),
            overlaps: Vec::new(),
            costs,
            available,
            repeat_penalty,
            revision,
            next_col: 0,
            next_top: 0,
            next_row: 0,
            top: Vec::new(),
            top_cost: Vec::new(),
            rest_min: Vec::new(),
            rows: Vec::new(),
            scratch: Vec::new(),
        }
    }

    /// The library revision it is building for.
    pub fn revision(&self) -> u64 {
        self.revision
    }

    pub fn repeat_penalty(&self) -> f32 {
        self.repeat_penalty
    }

    /// How far it has got.
    pub fn progress(&self) -> TableProgress {
        let m = self.m;
        TableProgress {
            done: self.next_col * PAIR_UNITS + self.next_top + self.next_row.min(m),
            total: m * (PAIR_UNITS + 2),
        }
    }

    /// Does up to `columns` columns of work (pair costs first, then top lists, then the
    /// transposed copy, each counted in columns) and reports progress.
    pub fn step(&mut self, columns: usize) -> TableProgress {
        let m = self.m;
        let mut budget = columns.max(1);
        if self.next_col < m {
            let end = self.next_col.saturating_add(budget).min(m);
            self.pair_columns(self.next_col, end);
            budget -= end - self.next_col;
            self.next_col = end;
            if self.next_col == m {
                self.add_repeat_penalty();
            }
        }
        if budget > 0 && self.next_col == m && self.next_top < m {
            let end = self.next_top.saturating_add(budget).min(m);
            self.top_lists(self.next_top, end);
            budget -= end - self.next_top;
            self.next_top = end;
        }
        if budget > 0 && self.next_top == m && self.next_row < m {
            if self.rows.is_empty() {
                self.rows = vec![0.0f32; m * m];
            }
            // Whole tiles of rows.
            let end = self.next_row.saturating_add(budget.max(TILE)).min(m);
            transpose_rows(m, &self.costs, &mut self.rows, self.next_row, end);
            self.next_row = end;
        }
        self.progress()
    }

    /// The finished table (`None` before the last step).
    pub fn finish(self) -> Option<TransitionTable> {
        if !self.progress().is_done() {
            return None;
        }
        let TableBuilder { m, costs, rows, top, top_cost, rest_min, available, repeat_penalty, revision, .. } = self;
        Some(TransitionTable { m, costs, rows, top, top_cost, rest_min, available, repeat_penalty, revision })
    }

    /// Pair costs of columns `b0..b1`, blocked over predecessors.
    fn pair_columns(&mut self, b0: usize, b1: usize) {
        let m = self.m;
        let mut acc = [0.0f32; BLOCK];
        for a0 in (0..m).step_by(BLOCK) {
            let n = BLOCK.min(m - a0);
            for b in b0..b1 {
                let acc = &mut acc[..n];
                acc.fill(0.0);
                for l in 0..LINK_COUNT {
                    let o = (b * LINK_COUNT + l) * 10;
                    let bs: &[f32; 10] = match self.b_side[o..o + 10].try_into() {
                        Ok(x) => x,
                        Err(_) => continue,
                    };
                    let base = l * A_FLOATS * m + a0;
                    let col = |k: usize| &self.a_side[base + k * m..base + k * m + n];
                    link_pairs(acc, bs, [col(0), col(1), col(2), col(3), col(4), col(5), col(6), col(7), col(8)]);
                }
                for (slot, s) in self.costs[b * m + a0..b * m + a0 + n].iter_mut().zip(acc.iter()) {
                    *slot = 1.0 / if *s > MIN_S { *s } else { MIN_S };
                }
                if let Some(bg) = self.b_gap.get(b * GAP_FLOATS..(b + 1) * GAP_FLOATS) {
                    if self.a_gap.len() == GAP_FLOATS * m {
                        let col = |k: usize| &self.a_gap[k * m + a0..k * m + a0 + n];
                        end_gaps(&mut self.costs[b * m + a0..b * m + a0 + n], bg, col);
                    }
                }
            }
        }
    }

    fn add_repeat_penalty(&mut self) {
        let m = self.m;
        for (a, ov) in self.overlaps.iter().enumerate() {
            for &b in ov {
                if b < m && a < m {
                    self.costs[b * m + a] += self.repeat_penalty;
                }
            }
        }
    }

    /// The [`TOP_K`] cheapest predecessors (by cost, then index) of columns `b0..b1`, and the
    /// cheapest cost outside them.
    fn top_lists(&mut self, b0: usize, b1: usize) {
        let m = self.m;
        let k = TOP_K.min(m);
        for b in b0..b1 {
            let col = &self.costs[b * m..(b + 1) * m];
            let start = self.top.len();
            if k < m {
                // The k-th and (k+1)-th smallest costs: the list holds every cost below the
                // k-th and, of those equal to it, the lowest indices; the rest start at the
                // (k+1)-th.
                self.scratch.clear();
                self.scratch.extend_from_slice(col);
                let (head, kth1, _) = self.scratch.select_nth_unstable_by(k, f32::total_cmp);
                let rest = *kth1;
                let kth = head.iter().copied().fold(f32::NEG_INFINITY, f32::max);
                let below = head.iter().filter(|&&c| c < kth).count();
                let mut ties = k - below;
                for (a, &c) in col.iter().enumerate() {
                    if c < kth {
                        self.top.push(a as u32);
                    } else if c == kth && ties > 0 {
                        self.top.push(a as u32);
                        ties -= 1;
                    }
                }
                self.rest_min.push(rest);
            } else {
                self.top.extend(0..m as u32);
                self.rest_min.push(f32::INFINITY);
            }
            let list = &mut self.top[start..];
            list.sort_by(|x, y| col[*x as usize].total_cmp(&col[*y as usize]).then(x.cmp(y)));
            self.top_cost.extend(list.iter().map(|&a| col[a as usize]));
        }
    }
}

/// Accumulates β_l · (S_pose + S_move) of one link for one successor and a block of
/// predecessors. `b` = the successor's start link xyz, h(start) xyz, β·h(start velocity) xyz
/// and 2β; `a` = the predecessors' end link x, y, z, β·h(end) x, y, z, β·h(end velocity) x, y, z.
#[inline(always)]
fn link_pairs(acc: &mut [f32], b: &[f32; 10], a: [&[f32]; A_FLOATS]) {
    let n = acc.len();
    let [ex, ey, ez, ux, uy, uz, vx, vy, vz] = a;
    let (ex, ey, ez, ux, uy, uz, vx, vy, vz) = (&ex[..n], &ey[..n], &ez[..n], &ux[..n], &uy[..n], &uz[..n], &vx[..n], &vy[..n], &vz[..n]);
    let [sx, sy, sz, px, py, pz, wx, wy, wz, still] = *b;
    for i in 0..n {
        let (dx, dy, dz) = (sx - ex[i], sy - ey[i], sz - ez[i]);
        let len2 = dx * dx + dy * dy + dz * dz;
        let pose = ux[i] * px + uy[i] * py + uz[i] * pz;
        let dv = dx * vx[i] + dy * vy[i] + dz * vz[i];
        let dw = dx * wx + dy * wy + dz * wz;
        // g[x] = max(x, 0), written as a select so it maps onto one SIMD instruction.
        let g = (if dv > 0.0 { dv } else { 0.0 }) + (if dw > 0.0 { dw } else { 0.0 });
        let moving = g / (if len2 > STILL_LEN2 { len2 } else { STILL_LEN2 }).sqrt();
        acc[i] += pose + if len2 < STILL_LEN2 { still } else { moving };
    }
}

/// Adds [`END_GAP_WEIGHT`] × the summed end-effector distance to each cost of a block of
/// predecessors (`a(k)`: coordinate k of their end positions; `b`: the successor's start).
fn end_gaps<'a>(costs: &mut [f32], b: &[f32], a: impl Fn(usize) -> &'a [f32]) {
    let n = costs.len();
    for e in 0..END_EFFECTORS.len() {
        let (ax, ay, az) = (&a(3 * e)[..n], &a(3 * e + 1)[..n], &a(3 * e + 2)[..n]);
        let (bx, by, bz) = (b[3 * e], b[3 * e + 1], b[3 * e + 2]);
        for i in 0..n {
            let (dx, dy, dz) = (bx - ax[i], by - ay[i], bz - az[i]);
            costs[i] += END_GAP_WEIGHT * (dx * dx + dy * dy + dz * dz).sqrt();
        }
    }
}

/// Tile edge of the blocked transpose.
const TILE: usize = 64;

/// Rows `r0..r1` of the row-major copy (`rows[a * m + b]` = `costs[b * m + a]`).
fn transpose_rows(m: usize, costs: &[f32], rows: &mut [f32], r0: usize, r1: usize) {
    for a0 in (r0..r1).step_by(TILE) {
        let a1 = (a0 + TILE).min(r1);
        for b0 in (0..m).step_by(TILE) {
            for b in b0..(b0 + TILE).min(m) {
                for a in a0..a1 {
                    rows[a * m + b] = costs[b * m + a];
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    /// Spec §G (and the product's end-effector gap) written out per pair with vector
    /// operations, independently of the flat loop.
    fn reference_cost(e_a: &JoinEnds, e_b: &JoinEnds) -> f32 {
        let beta = link_weights();
        let h = |v: Vec3| v.normalize_or_zero();
        let g = |x: f32| x.max(0.0);
        let mut s_pose = 0.0;
        let mut s_move = 0.0;
        for l in 0..LINK_COUNT {
            let (va, vb) = (e_a.end[l], e_b.start[l]);
            s_pose += beta[l] * h(va).dot(h(vb));
            let d = vb - va;
            if d.length_squared() < STILL_LEN2 {
                s_move += beta[l] * 2.0;
            } else {
                s_move += beta[l] * g(h(d).dot(h(e_a.end_velocity[l])));
                s_move += beta[l] * g(h(d).dot(h(e_b.start_velocity[l])));
            }
        }
        // The product's end-effector gap: each hand and foot placed by walking its chain of
        // links out from the hips (joint paths written out here, not taken from the builder).
        let chains: [&[usize]; 4] = [&[1, 2, 5, 6, 7, 8], &[1, 2, 9, 10, 11, 12], &[13, 14, 15], &[17, 18, 19]];
        let link_to = |c: usize| LINKS.iter().position(|&(_, child)| child == c).unwrap();
        let gap: f32 = chains
            .iter()
            .map(|chain| {
                let end: Vec3 = chain.iter().map(|&c| e_a.end[link_to(c)]).sum();
                let start: Vec3 = chain.iter().map(|&c| e_b.start[link_to(c)]).sum();
                (start - end).length()
            })
            .sum();
        1.0 / (s_pose + s_move).max(MIN_S) + END_GAP_WEIGHT * gap
    }

    #[test]
    fn costs_follow_the_spec_formula_pair_by_pair() {
        let lib = SegmentLibrary::builtin();
        let t = TransitionTable::from_library(&lib, 0.0);
        let m = lib.len();
        let mut worst = 0.0f32;
        for a in (0..m).step_by(7) {
            for b in (0..m).step_by(5) {
                let r = reference_cost(&lib.ends[a], &lib.ends[b]);
                let c = t.cost(a, b);
                worst = worst.max((c - r).abs() / r);
            }
        }
        assert!(worst < 1e-4, "largest relative difference from the spec formula {worst}");
    }

    #[test]
    fn slices_give_the_same_table_as_one_go() {
        let lib = SegmentLibrary::builtin();
        let whole = TransitionTable::from_library(&lib, 2.0);
        let mut b = TableBuilder::new(&lib, 2.0);
        let mut fractions = Vec::new();
        loop {
            let p = b.step(37);
            fractions.push(p.fraction());
            if p.is_done() {
                break;
            }
        }
        assert!(fractions.windows(2).all(|w| w[0] < w[1]), "{fractions:?}");
        assert!(fractions.len() > 10);
        assert_eq!(b.finish().unwrap(), whole);
    }

    #[test]
    fn top_lists_hold_the_cheapest_predecessors_ties_by_index() {
        // Column costs with many ties around the k-th.
        let m = 300;
        let costs: Vec<f32> = (0..m * m).map(|i| ((i * 7919) % 13) as f32).collect();
        let t = TransitionTable::from_costs(m, costs);
        for b in [0, 1, 150, 299] {
            let mut order: Vec<u32> = (0..m as u32).collect();
            order.sort_by(|x, y| t.cost(*x as usize, b).total_cmp(&t.cost(*y as usize, b)).then(x.cmp(y)));
            assert_eq!(&t.top[b * TOP_K..(b + 1) * TOP_K], &order[..TOP_K], "column {b}");
            assert_eq!(t.rest_min[b], t.cost(order[TOP_K] as usize, b));
        }
    }
}
