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
//! per-link cosines, barely sees (see [`END_GAP_WEIGHT`]). Since session 14 (issue 26) C may
//! also hold what the viewer sees after the blend ([`JumpTerm`]): [`BLENDED_JUMP_WEIGHT`] ×
//! max(0, J − [`BLENDED_JUMP_FREE`]), J the §J join jump predicted after the inertialized join
//! ([`blended_join_jump`], sampled at [`TABLE_BLEND_SAMPLES`] points of the decay), which ranks
//! the measured jumps at Spearman ρ 0.6 where C alone ranks them at 0.17. The default is
//! [`JumpTerm::OFF`], the cost before it, until the term stops costing the person's dances foot
//! skate ([`JumpTerm::MEASURED`]); a table extended block by block keeps its term.
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
//! Which pairs. A bar of n beats takes only n-count segments ([`super::fill::Tempi::bar_counts`]),
//! so a dance only ever joins a segment of bar t − 1's metre to one of bar t's. A table is
//! built for a [`TableScope`]: blocks of pairs by (predecessor counts, successor counts), the
//! (n, n) block for each metre two bars in a row have, and a cross block (p, n) only where a
//! bar of p is followed by one of n (a corrected bar, a metre change). A 4/4 song builds the
//! 4-count block alone; a bar whose metre no segment has (it takes any) needs every pair, one
//! block of all segments (main's all-pairs table, [`TransitionTable::from_library`], kept for
//! it and for comparisons). Cross blocks rather than costs computed per join in the filling:
//! a cross join needs every pair of the two metres all the same (the filling relaxes every
//! predecessor of every successor), a Generate runs the filling several times (its ladders
//! and join repairs) and a person Generates again and again, so the block is built once, in
//! the same slices with the same progress as the others, and cached with them. Costs are
//! the same formula and the same floating-point operations in any block, so a block holds
//! bit for bit what the all-pairs table holds; a pair outside the built blocks (a pinned
//! segment of another metre) is computed when asked ([`TransitionTable::cost`]), the same value.
//!
//! Layout. Each block's costs are stored column by column (all predecessors of one segment
//! contiguous); a within-metre block also row by row (for the filling's fast path), with each
//! column's [`TOP_K`] cheapest predecessors and a lower bound on the rest.

use std::collections::BTreeSet;
use std::sync::Arc;

use super::jump::{blend_jumps, blend_sides, BLEND_FLOATS};
pub use super::jump::{blended_join_jump, blended_join_jump_at, JumpTerm, BLENDED_JUMP_FREE, BLENDED_JUMP_WEIGHT, TABLE_BLEND_SAMPLES};
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

/// Which ordered pairs of segments a [`TransitionTable`] holds, as blocks by metre: the
/// (p, n) block holds C(a, b) for every segment a of p counts and b of n counts
/// ([`super::Segment::counts`]). A dance joins bar t − 1 to bar t, and a bar of n beats takes
/// only n-count segments, so a song needs the (n, n) block of each metre that two of its
/// bars in a row have, and a cross block (p, n) only where a bar of p is followed by one of
/// n (a corrected bar, a metre change): a 4/4 song needs the 4-count block alone. A bar whose
/// metre no segment has takes segments of every metre; its song needs every pair, as one
/// block ([`TableScope::all_pairs`]).
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct TableScope {
    all_pairs: bool,
    joins: BTreeSet<(usize, usize)>,
}

impl TableScope {
    /// Every ordered pair of segments, whatever their counts (one block).
    pub fn all_pairs() -> TableScope {
        TableScope { all_pairs: true, joins: BTreeSet::new() }
    }

    /// No pair at all (no bars, or one: nothing to join).
    pub fn none() -> TableScope {
        TableScope::default()
    }

    /// The joins between consecutive bars of these counts ([`super::bar_counts`]: 0 for a bar
    /// that takes segments of any metre, which needs every pair).
    pub fn for_bar_counts(counts: &[usize]) -> TableScope {
        if counts.contains(&0) {
            return TableScope::all_pairs();
        }
        TableScope { all_pairs: false, joins: counts.windows(2).map(|w| (w[0], w[1])).collect() }
    }

    /// The within-metre blocks of these metres (each (n, n)), no cross block.
    pub fn for_metres(metres: &[usize]) -> TableScope {
        TableScope { all_pairs: false, joins: metres.iter().map(|&n| (n, n)).collect() }
    }

    /// This scope with the (p, n) block too.
    pub fn with_join(mut self, p: usize, n: usize) -> TableScope {
        if !self.all_pairs {
            self.joins.insert((p, n));
        }
        self
    }

    pub fn is_all_pairs(&self) -> bool {
        self.all_pairs
    }

    /// Its blocks by (predecessor counts, successor counts) (none listed for all pairs).
    pub fn joins(&self) -> impl Iterator<Item = (usize, usize)> + '_ {
        self.joins.iter().copied()
    }

    /// Whether a table of this scope holds every pair one of `other` holds.
    pub fn covers(&self, other: &TableScope) -> bool {
        self.all_pairs || (!other.all_pairs && other.joins.is_subset(&self.joins))
    }

    /// The pairs of both.
    pub fn union(&self, other: &TableScope) -> TableScope {
        if self.all_pairs || other.all_pairs {
            return TableScope::all_pairs();
        }
        TableScope { all_pairs: false, joins: self.joins.union(&other.joins).copied().collect() }
    }
}

impl std::fmt::Display for TableScope {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        if self.all_pairs {
            return write!(f, "all pairs");
        }
        let parts: Vec<String> = self.joins.iter().map(|(p, n)| if p == n { format!("{p}") } else { format!("{p}→{n}") }).collect();
        if parts.is_empty() {
            write!(f, "none")
        } else {
            write!(f, "{}", parts.join(" + "))
        }
    }
}

/// The costs from one group of segments (a metre's, or all) to one group: `costs[lb * from.len() + la]`
/// = C(from[la], to[lb]), a column per successor. A within-group block (`from == to`) also
/// keeps the costs row by row (for the filling's fast path) and each column's [`TOP_K`]
/// cheapest predecessors and a lower bound on the rest.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Block {
    /// Its predecessors' and successors' library indices, ascending.
    pub(crate) from: Vec<u32>,
    pub(crate) to: Vec<u32>,
    pub(crate) costs: Arc<[f32]>,
    /// `rows[la * to.len() + lb]` = the same costs row by row (within-group blocks only).
    pub(crate) rows: Vec<f32>,
    /// Per column, the [`TOP_K`] cheapest predecessors (local indices) in increasing cost
    /// (then index), within-group blocks only.
    pub(crate) top: Vec<u32>,
    /// Their costs, alongside.
    pub(crate) top_cost: Vec<f32>,
    /// Per column, the cheapest cost outside its top list (a lower bound for the rest).
    pub(crate) rest_min: Vec<f32>,
    /// Per column, its cheapest cost from each chunk of predecessors
    /// ([`super::scan::chunk_mins`], within-group blocks only): the bounds of its chunked scan.
    pub(crate) chunk_min: Vec<f32>,
}

impl Block {
    /// All C(·, to[lb]), indexed by the predecessor's local index.
    pub(crate) fn column(&self, lb: usize) -> &[f32] {
        let n = self.from.len();
        &self.costs[lb * n..(lb + 1) * n]
    }
}

/// Every segment's end-of-segment link data, packed for the pair loop (see the module docs),
/// and the clip-frame overlaps: what any pair's cost is computed from.
#[derive(Clone, Debug, PartialEq)]
struct Ends {
    m: usize,
    /// Predecessor side, `[l][A_FLOATS][m]`: end link xyz, β·h(end) xyz, β·h(end velocity) xyz.
    a_side: Vec<f32>,
    /// Successor side, `[b][l][10]`: start link xyz, β·h(start) xyz, β·h(start velocity) xyz, 2β.
    b_side: Vec<f32>,
    /// Predecessor end-effector positions at their end, `[GAP_FLOATS][m]`.
    a_gap: Vec<f32>,
    /// Successor end-effector positions at their start, `[b][GAP_FLOATS]`.
    b_gap: Vec<f32>,
    /// Predecessor blend data P ([`blend_sides`]), `[BLEND_FLOATS][m]`, their largest end
    /// acceleration squared and their sharpness, `[m]` each.
    a_blend: Vec<f32>,
    a_peak2: Vec<f32>,
    sharp: Vec<f32>,
    /// Successor blend data Q, `[b][BLEND_FLOATS]`.
    b_blend: Vec<f32>,
    overlaps: Vec<Vec<usize>>,
}

/// The predecessor side of a block's segments ([`Ends::gather`]).
#[derive(Clone, Debug, Default)]
struct Gathered {
    a_side: Vec<f32>,
    a_gap: Vec<f32>,
    a_blend: Vec<f32>,
    a_peak2: Vec<f32>,
    a_sharp: Vec<f32>,
}

impl Ends {
    fn from_library(lib: &SegmentLibrary) -> Ends {
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
        let mut a_blend = vec![0.0f32; BLEND_FLOATS * m];
        let mut b_blend = vec![0.0f32; m * BLEND_FLOATS];
        let mut a_peak2 = vec![0.0f32; m];
        for (s, e) in ends.iter().enumerate() {
            let (p, q, peak2) = blend_sides(e);
            for (r, x) in p.into_iter().enumerate() {
                a_blend[r * m + s] = x;
            }
            b_blend[s * BLEND_FLOATS..(s + 1) * BLEND_FLOATS].copy_from_slice(&q);
            a_peak2[s] = peak2;
        }
        let sharp = ends.iter().map(|e| e.sharpness).collect();
        Ends { m, a_side, b_side, a_gap, b_gap, a_blend, a_peak2, sharp, b_blend, overlaps: lib.overlaps.clone() }
    }

    /// The predecessor side of the segments `from`, packed as [`Ends::a_side`],
    /// [`Ends::a_gap`] and [`Ends::a_blend`] with `from.len()` in place of m, and their
    /// [`Ends::a_peak2`] and [`Ends::sharp`].
    fn gather(&self, from: &[u32]) -> Gathered {
        let (m, n) = (self.m, from.len());
        let mut a_side = vec![0.0f32; LINK_COUNT * A_FLOATS * n];
        for row in 0..LINK_COUNT * A_FLOATS {
            let (src, dst) = (&self.a_side[row * m..(row + 1) * m], &mut a_side[row * n..(row + 1) * n]);
            for (d, &a) in dst.iter_mut().zip(from) {
                *d = src[a as usize];
            }
        }
        let mut a_gap = vec![0.0f32; GAP_FLOATS * n];
        for row in 0..GAP_FLOATS {
            let (src, dst) = (&self.a_gap[row * m..(row + 1) * m], &mut a_gap[row * n..(row + 1) * n]);
            for (d, &a) in dst.iter_mut().zip(from) {
                *d = src[a as usize];
            }
        }
        let mut a_blend = vec![0.0f32; BLEND_FLOATS * n];
        for row in 0..BLEND_FLOATS {
            let (src, dst) = (&self.a_blend[row * m..(row + 1) * m], &mut a_blend[row * n..(row + 1) * n]);
            for (d, &a) in dst.iter_mut().zip(from) {
                *d = src[a as usize];
            }
        }
        let a_peak2 = from.iter().map(|&a| self.a_peak2[a as usize]).collect();
        let a_sharp = from.iter().map(|&a| self.sharp[a as usize]).collect();
        Gathered { a_side, a_gap, a_blend, a_peak2, a_sharp }
    }

    /// C(a, b) of one pair, by the very operations of the block loop (so bit for bit the
    /// cost a block holds), repetition penalty and blended-jump term included.
    fn pair_cost(&self, a: usize, b: usize, repeat_penalty: f32, term: JumpTerm) -> f32 {
        let m = self.m;
        if a >= m || b >= m {
            return f32::INFINITY;
        }
        let mut acc = [0.0f32; 1];
        for l in 0..LINK_COUNT {
            let o = (b * LINK_COUNT + l) * 10;
            let Ok(bs) = <&[f32; 10]>::try_from(&self.b_side[o..o + 10]) else { continue };
            let base = l * A_FLOATS * m + a;
            let col = |k: usize| &self.a_side[base + k * m..base + k * m + 1];
            link_pairs(&mut acc, bs, [col(0), col(1), col(2), col(3), col(4), col(5), col(6), col(7), col(8)]);
        }
        let s = acc[0];
        let mut c = [1.0 / if s > MIN_S { s } else { MIN_S }];
        end_gaps(&mut c, &self.b_gap[b * GAP_FLOATS..(b + 1) * GAP_FLOATS], |k| &self.a_gap[k * m + a..k * m + a + 1]);
        if term.weight > 0.0 {
            let mut peak = [0.0f32; 1];
            let bq = &self.b_blend[b * BLEND_FLOATS..(b + 1) * BLEND_FLOATS];
            blend_jumps(&mut c, &mut peak, bq, self.sharp[b], |r| &self.a_blend[r * m + a..r * m + a + 1], &self.a_peak2[a..a + 1], &self.sharp[a..a + 1], term);
        }
        let mut c = c[0];
        for &x in &self.overlaps[a] {
            if x == b {
                c += repeat_penalty;
            }
        }
        c
    }
}

/// The ordered pairs of spec §G's edge costs C(a, b) (repetition penalty included) that a
/// [`TableScope`] asks for, in [`Block`]s by metre; [`TransitionTable::cost`] answers any
/// pair (one outside the built blocks is computed then, bit for bit as a block would hold it).
#[derive(Clone, Debug, PartialEq)]
pub struct TransitionTable {
    pub(crate) m: usize,
    scope: TableScope,
    /// The counts of each group of segments (one group of every segment for all pairs: empty).
    metres: Vec<usize>,
    /// Per segment, its group and its index within it.
    group: Vec<u8>,
    local: Vec<u32>,
    /// `blocks[g * groups + h]`: the costs from group g to group h, when built.
    blocks: Vec<Option<Arc<Block>>>,
    /// The costs of the one block of an all-pairs table (shared with it), `flat[b * m + a]`.
    flat: Option<Arc<[f32]>>,
    ends: Option<Arc<Ends>>,
    /// Segments that may fill an open bar (`false`: kept only for the bars that already hold
    /// them, see [`SegmentLibrary::recut_clip`]).
    pub(crate) available: Vec<bool>,
    repeat_penalty: f32,
    /// The predicted blended jump's term in its costs ([`JumpTerm`]; [`JumpTerm::OFF`]: the
    /// cost before it).
    jump_term: JumpTerm,
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
        let mut b = TableBuilder::with_groups(m, Layout::one_group(m), None, TableScope::all_pairs(), vec![true; m], (0.0, JumpTerm::OFF), 0, None);
        if let Some(job) = b.jobs.first_mut() {
            job.costs = t;
            job.next_col = m;
        }
        while !b.step(usize::MAX).is_done() {}
        b.finish().unwrap_or_else(|| unreachable_empty(m))
    }

    /// Spec §G's costs between every pair of the library's segments, plus `repeat_penalty` on
    /// pairs that share clip frames (one block, whatever the segments' counts).
    pub fn from_library(lib: &SegmentLibrary, repeat_penalty: f32) -> TransitionTable {
        TransitionTable::for_scope(lib, repeat_penalty, &TableScope::all_pairs())
    }

    /// The blocks of `scope` only ([`TableScope`]).
    pub fn for_scope(lib: &SegmentLibrary, repeat_penalty: f32, scope: &TableScope) -> TransitionTable {
        TransitionTable::for_scope_with_term(lib, repeat_penalty, scope, JumpTerm::default())
    }

    /// [`TransitionTable::for_scope`] with the predicted blended jump's term `term`
    /// ([`JumpTerm::OFF`]: the cost before session 14, §G's C and the end gaps alone; for
    /// comparisons).
    pub fn for_scope_with_term(lib: &SegmentLibrary, repeat_penalty: f32, scope: &TableScope, term: JumpTerm) -> TransitionTable {
        let mut b = TableBuilder::for_scope_with_term(lib, repeat_penalty, scope, None, term);
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

    /// The pairs it holds.
    pub fn scope(&self) -> &TableScope {
        &self.scope
    }

    /// Cost values stored (all blocks), e.g. to compare scopes.
    pub fn stored_pairs(&self) -> usize {
        self.blocks.iter().flatten().map(|b| b.costs.len()).sum()
    }

    /// C(a, b); infinite when out of range. A pair outside the built blocks is computed here
    /// (the same value a block would hold).
    #[inline]
    pub fn cost(&self, a: usize, b: usize) -> f32 {
        if a >= self.m || b >= self.m {
            return f32::INFINITY;
        }
        // One block of all segments (all pairs): indexed as it is, through a slice held here
        // (the loops that call this for every pair then run as fast as over a plain array).
        if let Some(flat) = &self.flat {
            return flat[b * self.m + a];
        }
        let (g, h) = (self.group[a] as usize, self.group[b] as usize);
        if let Some(block) = self.block(g, h) {
            return block.costs[self.local[b] as usize * block.from.len() + self.local[a] as usize];
        }
        match &self.ends {
            Some(e) => e.pair_cost(a, b, self.repeat_penalty, self.jump_term),
            None => f32::INFINITY,
        }
    }

    pub fn repeat_penalty(&self) -> f32 {
        self.repeat_penalty
    }

    /// The predicted blended jump's term in its costs ([`JumpTerm`]).
    pub fn jump_term(&self) -> JumpTerm {
        self.jump_term
    }

    /// The library revision this table was built from.
    pub fn revision(&self) -> u64 {
        self.revision
    }

    /// Whether segment `s` may fill an open bar.
    pub fn is_available(&self, s: usize) -> bool {
        self.available.get(s).copied().unwrap_or(false)
    }

    /// The counts of each group of segments (empty: one group of all, an all-pairs table).
    pub(crate) fn metres(&self) -> &[usize] {
        &self.metres
    }

    /// Segment `s`'s group.
    pub(crate) fn group_of(&self, s: usize) -> usize {
        self.group.get(s).map_or(0, |&g| g as usize)
    }

    /// The block from group `g` to group `h`, when built.
    pub(crate) fn block(&self, g: usize, h: usize) -> Option<&Block> {
        let groups = self.metres.len().max(1);
        if g >= groups || h >= groups {
            return None;
        }
        self.blocks.get(g * groups + h).and_then(|b| b.as_deref())
    }
}

/// A finished builder always yields a table; this keeps the constructors total without a panic.
fn unreachable_empty(m: usize) -> TransitionTable {
    debug_assert!(m == 0, "a finished table builder gave no table");
    TransitionTable {
        m: 0,
        scope: TableScope::all_pairs(),
        metres: Vec::new(),
        group: Vec::new(),
        local: Vec::new(),
        blocks: Vec::new(),
        flat: None,
        ends: None,
        available: Vec::new(),
        repeat_penalty: 0.0,
        jump_term: JumpTerm::OFF,
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
    /// Units of work done and in all (a pair counts [`PAIR_UNITS`]; sorting it into a top
    /// list and copying it into the row-major copy one each).
    pub done: usize,
    pub total: usize,
}

/// Work of one pair cost relative to sorting it into its column's top list.
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

/// How a table groups the segments: per segment its group and index in it, per group its
/// counts (none: one group of all) and members.
#[derive(Clone, Debug)]
struct Layout {
    metres: Vec<usize>,
    group: Vec<u8>,
    local: Vec<u32>,
    members: Vec<Vec<u32>>,
}

impl Layout {
    fn one_group(m: usize) -> Layout {
        Layout { metres: Vec::new(), group: vec![0; m], local: (0..m as u32).collect(), members: vec![(0..m as u32).collect()] }
    }

    /// Groups by counts ([`super::Segment::counts`]), ascending.
    fn by_counts(lib: &SegmentLibrary) -> Layout {
        let counts: Vec<usize> = lib.segments().iter().map(|s| s.counts()).collect();
        let metres: Vec<usize> = counts.iter().copied().collect::<BTreeSet<_>>().into_iter().collect();
        let mut members = vec![Vec::new(); metres.len()];
        let (mut group, mut local) = (Vec::with_capacity(counts.len()), Vec::with_capacity(counts.len()));
        for (s, n) in counts.iter().enumerate() {
            let g = metres.binary_search(n).unwrap_or(0);
            group.push(g as u8);
            local.push(members[g].len() as u32);
            members[g].push(s as u32);
        }
        Layout { metres, group, local, members }
    }
}

/// The library's metres as a table groups them (for [`SegmentLibrary::install_table`]).
pub(crate) fn library_metres(lib: &SegmentLibrary) -> Vec<usize> {
    lib.segments().iter().map(|s| s.counts()).collect::<BTreeSet<_>>().into_iter().collect()
}

/// One block to build: pair costs first, then (within a group) top lists, then the
/// row-major copy.
#[derive(Clone, Debug)]
struct Job {
    g: usize,
    h: usize,
    diag: bool,
    ends: Option<Arc<Ends>>,
    from: Vec<u32>,
    to: Vec<u32>,
    /// The predecessors' link and blend data, packed as [`Ends`] over `from`.
    a: Gathered,
    costs: Vec<f32>,
    next_col: usize,
    next_top: usize,
    next_row: usize,
    top: Vec<u32>,
    top_cost: Vec<f32>,
    rest_min: Vec<f32>,
    chunk_min: Vec<f32>,
    rows: Vec<f32>,
    scratch: Vec<f32>,
}

impl Job {
    fn units(&self) -> (usize, usize) {
        let (nf, nt) = (self.from.len(), self.to.len());
        let total = nt * nf * PAIR_UNITS + if self.diag { 2 * nt * nf } else { 0 };
        let done = self.next_col * nf * PAIR_UNITS + if self.diag { self.next_top * nf + self.next_row.min(nf) * nt } else { 0 };
        (done, total)
    }

    fn is_done(&self) -> bool {
        let (d, t) = self.units();
        d >= t
    }

    fn into_block(self) -> Block {
        let Job { from, to, costs, rows, top, top_cost, rest_min, chunk_min, .. } = self;
        Block { from, to, costs: costs.into(), rows, top, top_cost, rest_min, chunk_min }
    }
}

/// Builds a [`TransitionTable`] in slices: [`TableBuilder::step`] does up to a given number
/// of columns and says how far it got; [`TableBuilder::finish`] hands over the table. It owns
/// copies of what it needs, so the library may be read (not changed) meanwhile; a table built
/// from an older revision of the library is refused by [`SegmentLibrary::install_table`].
#[derive(Clone, Debug)]
pub struct TableBuilder {
    m: usize,
    scope: TableScope,
    layout: Layout,
    /// Blocks already built (carried over from an earlier table of the same library).
    blocks: Vec<Option<Arc<Block>>>,
    ends: Option<Arc<Ends>>,
    jobs: Vec<Job>,
    /// The first job not finished.
    job: usize,
    available: Vec<bool>,
    repeat_penalty: f32,
    jump_term: JumpTerm,
    revision: u64,
}

/// The unit vector, or zero for a (near-)zero vector (h of the spec).
fn unit(v: glam::Vec3) -> glam::Vec3 {
    v.normalize_or_zero()
}

impl TableBuilder {
    /// A builder for the library's all-pairs table with the given repetition penalty.
    pub fn new(lib: &SegmentLibrary, repeat_penalty: f32) -> TableBuilder {
        TableBuilder::for_scope(lib, repeat_penalty, &TableScope::all_pairs(), None)
    }

    /// A builder of the blocks of `scope` ([`TableScope`]), taking over the blocks `earlier`
    /// already holds when it was built from this library (same revision and penalty): only the
    /// missing blocks are built, and the table holds both.
    pub fn for_scope(lib: &SegmentLibrary, repeat_penalty: f32, scope: &TableScope, earlier: Option<&TransitionTable>) -> TableBuilder {
        // Blocks added to an earlier table are costed as its own are.
        let term = earlier.map_or_else(JumpTerm::default, |t| t.jump_term);
        TableBuilder::for_scope_with_term(lib, repeat_penalty, scope, earlier, term)
    }

    /// [`TableBuilder::for_scope`] with the predicted blended jump's term `term`
    /// ([`JumpTerm::OFF`]: the cost before session 14); `earlier` is taken over only when it
    /// has the same term.
    pub fn for_scope_with_term(lib: &SegmentLibrary, repeat_penalty: f32, scope: &TableScope, earlier: Option<&TransitionTable>, term: JumpTerm) -> TableBuilder {
        let m = lib.len();
        let jump_term = term.clamped();
        let available = lib.segments().iter().map(|s| !s.retired).collect();
        let ends = Some(Arc::new(Ends::from_library(lib)));
        let (layout, earlier) = if scope.is_all_pairs() {
            (Layout::one_group(m), None)
        } else {
            let layout = Layout::by_counts(lib);
            let earlier = earlier.filter(|t| t.revision == lib.revision() && t.m == m && t.repeat_penalty == repeat_penalty && t.jump_term == jump_term && !t.scope.is_all_pairs() && t.metres == layout.metres);
            (layout, earlier)
        };
        TableBuilder::with_groups(m, layout, earlier, scope.clone(), available, (repeat_penalty, jump_term), lib.revision(), ends)
    }

    #[allow(clippy::too_many_arguments)]
    fn with_groups(m: usize, layout: Layout, earlier: Option<&TransitionTable>, scope: TableScope, available: Vec<bool>, (repeat_penalty, jump_term): (f32, JumpTerm), revision: u64, ends: Option<Arc<Ends>>) -> TableBuilder {
        let groups = layout.members.len().max(1);
        let blocks: Vec<Option<Arc<Block>>> = match earlier {
            Some(t) if t.blocks.len() == groups * groups => t.blocks.clone(),
            _ => vec![None; groups * groups],
        };
        let scope = match earlier {
            Some(t) => scope.union(&t.scope),
            None => scope,
        };
        // The blocks to build, by group pair.
        let wanted: Vec<(usize, usize)> = if scope.is_all_pairs() {
            vec![(0, 0)]
        } else {
            scope.joins().filter_map(|(p, n)| Some((layout.metres.binary_search(&p).ok()?, layout.metres.binary_search(&n).ok()?))).collect()
        };
        let mut jobs = Vec::new();
        for (g, h) in wanted {
            if blocks[g * groups + h].is_some() {
                continue;
            }
            let (from, to) = match (layout.members.get(g), layout.members.get(h)) {
                (Some(f), Some(t)) => (f.clone(), t.clone()),
                _ => (Vec::new(), Vec::new()),
            };
            let a = ends.as_ref().map_or_else(Gathered::default, |e| e.gather(&from));
            let costs = vec![0.0f32; from.len() * to.len()];
            jobs.push(Job {
                g,
                h,
                diag: g == h,
                ends: ends.clone(),
                from,
                to,
                a,
                costs,
                next_col: 0,
                next_top: 0,
                next_row: 0,
                top: Vec::new(),
                top_cost: Vec::new(),
                rest_min: Vec::new(),
                chunk_min: Vec::new(),
                rows: Vec::new(),
                scratch: Vec::new(),
            });
        }
        TableBuilder { m, scope, layout, blocks, ends, jobs, job: 0, available, repeat_penalty, jump_term, revision }
    }

    /// The library revision it is building for.
    pub fn revision(&self) -> u64 {
        self.revision
    }

    pub fn repeat_penalty(&self) -> f32 {
        self.repeat_penalty
    }

    /// The pairs its table will hold.
    pub fn scope(&self) -> &TableScope {
        &self.scope
    }

    /// How far it has got (over the blocks it builds; none: done).
    pub fn progress(&self) -> TableProgress {
        let (mut done, mut total) = (0, 0);
        for j in &self.jobs {
            let (d, t) = j.units();
            done += d;
            total += t;
        }
        TableProgress { done, total }
    }

    /// Does up to `columns` columns of work on the block being built (pair costs first, then
    /// top lists, then the transposed copy, each counted in columns) and reports progress.
    pub fn step(&mut self, columns: usize) -> TableProgress {
        while self.job < self.jobs.len() && self.jobs[self.job].is_done() {
            self.job += 1;
        }
        let (overlaps, group, local) = (self.ends.as_ref().map(|e| &e.overlaps), &self.layout.group, &self.layout.local);
        if let Some(job) = self.jobs.get_mut(self.job) {
            job.step(columns, (self.repeat_penalty, self.jump_term), overlaps.map(|o| (o.as_slice(), group.as_slice(), local.as_slice())));
        }
        self.progress()
    }

    /// The finished table (`None` before the last step).
    pub fn finish(self) -> Option<TransitionTable> {
        if !self.progress().is_done() {
            return None;
        }
        let TableBuilder { m, scope, layout, mut blocks, ends, jobs, available, repeat_penalty, jump_term, revision, .. } = self;
        let groups = layout.members.len().max(1);
        for j in jobs {
            let at = j.g * groups + j.h;
            if let Some(slot) = blocks.get_mut(at) {
                *slot = Some(Arc::new(j.into_block()));
            }
        }
        let Layout { metres, group, local, .. } = layout;
        let flat = match blocks.as_slice() {
            [Some(b)] if metres.is_empty() && b.costs.len() == m * m => Some(b.costs.clone()),
            _ => None,
        };
        Some(TransitionTable { m, scope, metres, group, local, blocks, flat, ends, available, repeat_penalty, jump_term, revision })
    }
}

impl Job {
    /// Up to `columns` columns of work. `overlaps`: the library's overlaps and the segments'
    /// groups and local indices (for the repetition penalty).
    fn step(&mut self, columns: usize, (repeat_penalty, jump_term): (f32, JumpTerm), overlaps: Option<(&[Vec<usize>], &[u8], &[u32])>) {
        let (nf, nt) = (self.from.len(), self.to.len());
        let mut budget = columns.max(1);
        if self.next_col < nt {
            let end = self.next_col.saturating_add(budget).min(nt);
            self.pair_columns(self.next_col, end, jump_term);
            budget -= end - self.next_col;
            self.next_col = end;
            if self.next_col == nt {
                if let Some((ov, group, local)) = overlaps {
                    self.add_repeat_penalty(repeat_penalty, ov, group, local);
                }
            }
        }
        if !self.diag {
            return;
        }
        if budget > 0 && self.next_col == nt && self.next_top < nt {
            let end = self.next_top.saturating_add(budget).min(nt);
            self.top_lists(self.next_top, end);
            budget -= end - self.next_top;
            self.next_top = end;
        }
        if budget > 0 && self.next_top == nt && self.next_row < nf {
            if self.rows.is_empty() {
                self.rows = vec![0.0f32; nf * nt];
            }
            // Whole tiles of rows.
            let end = self.next_row.saturating_add(budget.max(TILE)).min(nf);
            transpose_rows(nf, &self.costs, &mut self.rows, self.next_row, end);
            self.next_row = end;
        }
    }

    /// Pair costs of columns `b0..b1`, blocked over predecessors.
    fn pair_columns(&mut self, b0: usize, b1: usize, term: JumpTerm) {
        let m = self.from.len();
        let Some(ends) = self.ends.clone() else { return };
        let a = &self.a;
        if a.a_side.len() != LINK_COUNT * A_FLOATS * m {
            return;
        }
        let blend = term.weight > 0.0 && a.a_blend.len() == BLEND_FLOATS * m && a.a_peak2.len() == m && a.a_sharp.len() == m;
        let (mut acc, mut peak) = ([0.0f32; BLOCK], [0.0f32; BLOCK]);
        for a0 in (0..m).step_by(BLOCK) {
            let n = BLOCK.min(m - a0);
            for lb in b0..b1 {
                let b = self.to[lb] as usize;
                let acc = &mut acc[..n];
                acc.fill(0.0);
                for l in 0..LINK_COUNT {
                    let o = (b * LINK_COUNT + l) * 10;
                    let bs: &[f32; 10] = match ends.b_side.get(o..o + 10).and_then(|x| x.try_into().ok()) {
                        Some(x) => x,
                        None => continue,
                    };
                    let base = l * A_FLOATS * m + a0;
                    let col = |k: usize| &a.a_side[base + k * m..base + k * m + n];
                    link_pairs(acc, bs, [col(0), col(1), col(2), col(3), col(4), col(5), col(6), col(7), col(8)]);
                }
                for (slot, s) in self.costs[lb * m + a0..lb * m + a0 + n].iter_mut().zip(acc.iter()) {
                    *slot = 1.0 / if *s > MIN_S { *s } else { MIN_S };
                }
                if let Some(bg) = ends.b_gap.get(b * GAP_FLOATS..(b + 1) * GAP_FLOATS) {
                    if a.a_gap.len() == GAP_FLOATS * m {
                        let col = |k: usize| &a.a_gap[k * m + a0..k * m + a0 + n];
                        end_gaps(&mut self.costs[lb * m + a0..lb * m + a0 + n], bg, col);
                    }
                }
                if let (true, Some(bq), Some(&b_sharp)) = (blend, ends.b_blend.get(b * BLEND_FLOATS..(b + 1) * BLEND_FLOATS), ends.sharp.get(b)) {
                    let col = |r: usize| &a.a_blend[r * m + a0..r * m + a0 + n];
                    blend_jumps(&mut self.costs[lb * m + a0..lb * m + a0 + n], &mut peak, bq, b_sharp, col, &a.a_peak2[a0..a0 + n], &a.a_sharp[a0..a0 + n], term);
                }
            }
        }
    }

    fn add_repeat_penalty(&mut self, repeat_penalty: f32, overlaps: &[Vec<usize>], group: &[u8], local: &[u32]) {
        let (nf, nt) = (self.from.len(), self.to.len());
        for (la, &a) in self.from.iter().enumerate() {
            let Some(ov) = overlaps.get(a as usize) else { continue };
            for &b in ov {
                if group.get(b).is_some_and(|&g| g as usize == self.h) {
                    let lb = local[b] as usize;
                    if lb < nt && la < nf {
                        self.costs[lb * nf + la] += repeat_penalty;
                    }
                }
            }
        }
    }

    /// The [`TOP_K`] cheapest predecessors (by cost, then index) of columns `b0..b1`, and the
    /// cheapest cost outside them.
    fn top_lists(&mut self, b0: usize, b1: usize) {
        let m = self.from.len();
        let k = TOP_K.min(m);
        for b in b0..b1 {
            let col = &self.costs[b * m..(b + 1) * m];
            super::scan::chunk_mins(col, &mut self.chunk_min);
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
    use super::super::jump::blend_span_frames;

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
        1.0 / (s_pose + s_move).max(MIN_S) + END_GAP_WEIGHT * gap + BLENDED_JUMP_WEIGHT * (reference_jump(e_a, e_b) - BLENDED_JUMP_FREE).max(0.0)
    }

    /// The predicted blended jump as the table samples it, written out joint by joint with the
    /// render's quintic (not through the P − Q split of [`blend_sides`]).
    fn reference_jump(e_a: &JoinEnds, e_b: &JoinEnds) -> f32 {
        let span = blend_span_frames();
        let mut peak = 0.0f32;
        for (&[xa, va, aa], &[xb, vb, ab]) in e_a.end_joint.iter().zip(&e_b.start_joint) {
            let (x0, v0, a0) = (xa + va + 0.5 * aa - xb, va - vb, aa - ab);
            peak = peak.max(aa.length());
            for k in TABLE_BLEND_SAMPLES {
                let t = span * k as f32 / 10.0;
                peak = peak.max((ab + crate::choreo::render::quintic_offset_accel(x0, v0, a0, span, t)).length());
            }
        }
        peak / (0.5 * (e_a.sharpness + e_b.sharpness)).max(1e-6)
    }

    #[test]
    fn the_tables_blended_term_samples_the_predicted_jump() {
        // The table's term (its cost less the cost at weight 0) against the ten-sample
        // prediction of `blended_join_jump`: never above it (its samples are a subset), and
        // close to it (printed); the control, the cost at weight 0, holds no such term.
        let lib = SegmentLibrary::builtin();
        let scope = TableScope::all_pairs();
        let all = JumpTerm { weight: 1.0, free: 0.0 };
        let (with, without) = (TransitionTable::for_scope_with_term(&lib, 0.0, &scope, all), TransitionTable::for_scope_with_term(&lib, 0.0, &scope, JumpTerm::OFF));
        assert_eq!(TransitionTable::for_scope(&lib, 0.0, &TableScope::none()).jump_term(), JumpTerm::OFF);
        assert_eq!(without.jump_term(), JumpTerm::OFF);
        let m = lib.len();
        let (mut worst_over, mut ratios) = (0.0f32, Vec::new());
        for a in (0..m).step_by(3) {
            for b in (0..m).step_by(7) {
                let full = blended_join_jump(&lib, a, b).unwrap();
                let term = with.cost(a, b) - without.cost(a, b);
                worst_over = worst_over.max((term - full) / full.max(1e-3));
                ratios.push(term / full.max(1e-3));
            }
        }
        ratios.sort_by(f32::total_cmp);
        let (p5, median) = (ratios[ratios.len() / 20], ratios[ratios.len() / 2]);
        println!("{} pairs: the table's term over the ten-sample prediction: 5th percentile {p5:.3}, median {median:.3}, most over {worst_over:.2e}", ratios.len());
        assert!(worst_over < 1e-3, "the table's term exceeds the prediction by {worst_over}");
        assert!(p5 > 0.8 && median > 0.95, "the table's term falls short of the prediction: 5th percentile {p5}, median {median}");
    }

    #[test]
    fn costs_follow_the_spec_formula_pair_by_pair() {
        let lib = SegmentLibrary::builtin();
        let t = TransitionTable::for_scope_with_term(&lib, 0.0, &TableScope::all_pairs(), JumpTerm::MEASURED);
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
            let block = t.block(0, 0).unwrap();
            assert_eq!(&block.top[b * TOP_K..(b + 1) * TOP_K], &order[..TOP_K], "column {b}");
            assert_eq!(block.rest_min[b], t.cost(order[TOP_K] as usize, b));
        }
    }
}
