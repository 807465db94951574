//! The coupled lower bound of the fast search's first pass: for a stretch of library columns,
//! a lower bound `B(i, j)` of `Σ w·(d − τ)` over the rest of *any* admissible path from cell
//! (i, j) to the last query frame, found by running the §C step pattern backwards over a
//! matrix of cheap lower bounds `L(i, j) ≤ d(i, j)` instead of the frame distances.
//!
//! Why: the row bounds of `fast.rs` (LB_Keogh-style: each later query frame's nearest library
//! chunk within reach, summed) let every row pick its own best column, so for a query unlike
//! anything in the library they stay far below the truth and almost nothing is pruned (about
//! half the cells needed a frame distance). Coupling the rows by the steps themselves — one
//! path has to serve every row, moving right by one or two columns per row — gives a bound
//! that, on the real hour of motion, leaves a few percent of the cells to compute.
//!
//! `L(i, j)` is the distance between the joint boxes of the [`QFINE`]-frame query chunk
//! holding query frame i and the aligned [`FINE`]-frame library chunk holding library frame j
//! (the clip's boxes are made once, when the index is built: `ClipFeatures::fine_boxes`) (`box_box`, a lower bound of the frame distance between any two frames inside them),
//! shrunk by a relative 1e-5 so f32 rounding in the box arithmetic never lifts it above the
//! real distance. The backward DP uses exactly the forward step pattern: from
//! (i, j) the path enters (i+1, j+1) with weight 2 and then stops there, or goes on to
//! (i+1, j+2) or (i+2, j+1) with weight 1. Every real completion is one of those paths, and
//! each of its terms `w·(d − τ)` is at least `w·(L − τ)`, so `B ≤` its `Σ w·(d − τ)`. For a
//! lower τ' the completions' sums only grow (`Σ w·(d − τ') = Σ w·(d − τ) + (τ − τ')·W`), so
//! a table built at τ stays a lower bound when the search's τ falls. The table's own f32
//! rounding is covered by the slack the user subtracts ([`Coupled::at`]).

use super::lanes::{box_box, push_box, BOX_FLOATS};
use super::{Prepared, LANE_FLOATS};

/// Library frames per box of the bound (smaller: tighter bound, more box distances).
pub(crate) const FINE: usize = 8;
/// Query frames per box of the bound.
pub(crate) const QFINE: usize = 2;
/// Columns a table covers (it is computed over `2·(I − 1)` more, where the paths of its
/// columns may still run).
pub(crate) const SPAN: usize = 2048;

/// One table: `B` for the columns `b0 .. b0 + SPAN` of a clip (row-major, `w` columns).
#[derive(Default)]
pub(crate) struct Coupled {
    pub b0: usize,
    /// End (exclusive) of the columns whose values are valid.
    pub valid_to: usize,
    w: usize,
    table: Vec<f32>,
    lrow: Vec<f32>,
    /// Rounding slack scale `2τ(I + maxSpan)` of the table's τ.
    scale: f32,
}

/// Most box distances a [`FineDists`] keeps (16 MB of f32): an hour of motion at 60 fps and a
/// 120-frame query needs 27,000 chunks × 60 query boxes = 1.6 M; past the cap the distances of
/// further clips are computed per table, as before the cache.
const KEEP_MAX_FLOATS: usize = 4 << 20;

/// The box distances `L` of the coupled tables (before τ is subtracted, already shrunk), per
/// clip, [`FINE`]-frame chunk and query box, computed on first use and kept for the query.
///
/// Why one set serves every table of a query: a table at τ reads `L − τ`, and `L` depends on
/// the query, the weights, the origin and the clip, never on τ or on the stretch — so tables
/// built at a later, lower τ (the next `SPAN` of a clip, the exact pass over the marked ends
/// after the one-value pass, the bounded search after the probe on the same worker) and
/// overlapping tables (each reaches `2·(I − 1)` columns past its valid ones) reuse the same
/// numbers, bit for bit. The table's DP itself is redone at each τ: a table built at the
/// lower τ is the tighter one, and it costs a few additions per cell where a box distance
/// costs about a frame distance.
#[derive(Default)]
pub(crate) struct FineDists {
    /// The query's boxes ([`QFINE`] frames each).
    qboxes: Vec<f32>,
    /// Per clip: `chunks × query boxes` distances (empty until first used, or when past the cap).
    clips: Vec<Vec<f32>>,
    /// Per clip: which chunks' distances are in `clips`.
    done: Vec<Vec<bool>>,
    kept: usize,
    scratch: Vec<f32>,
    /// Box distances computed (work counter).
    pub boxes: u64,
}

impl FineDists {
    /// Distances for `clips` clips of the query of `prep`.
    pub(crate) fn new(prep: &Prepared, clips: usize) -> FineDists {
        let mut qboxes = Vec::new();
        for ch in prep.query_lanes.chunks(QFINE * LANE_FLOATS) {
            push_box(ch, &mut qboxes);
        }
        FineDists { qboxes, clips: vec![Vec::new(); clips], done: vec![Vec::new(); clips], ..FineDists::default() }
    }

    /// Heap bytes held.
    pub(crate) fn heap_bytes(&self) -> usize {
        4 * (self.qboxes.capacity() + self.kept + self.scratch.capacity()) + self.done.iter().map(Vec::capacity).sum::<usize>()
    }

    /// `L` between every query box and chunk `t` of clip `ci` (`boxes`: the clip's
    /// [`FINE`]-frame boxes).
    fn chunk(&mut self, prep: &Prepared, ci: usize, boxes: &[f32], t: usize) -> &[f32] {
        let nqf = self.qboxes.len() / BOX_FLOATS;
        let chunks = boxes.len() / BOX_FLOATS;
        if self.clips[ci].is_empty() && self.kept + chunks * nqf <= KEEP_MAX_FLOATS {
            self.clips[ci] = vec![0.0; chunks * nqf];
            self.done[ci] = vec![false; chunks];
            self.kept += chunks * nqf;
        }
        let keep = !self.clips[ci].is_empty();
        if keep && self.done[ci][t] {
            return &self.clips[ci][t * nqf..(t + 1) * nqf];
        }
        let bx = &boxes[t * BOX_FLOATS..(t + 1) * BOX_FLOATS];
        let out = if keep { &mut self.clips[ci][t * nqf..(t + 1) * nqf] } else {
            self.scratch.resize(nqf, 0.0);
            &mut self.scratch[..]
        };
        for (o, qb) in out.iter_mut().zip(self.qboxes.chunks_exact(BOX_FLOATS)) {
            *o = box_box(qb, bx, &prep.groups) * (1.0 - 1e-5);
        }
        self.boxes += nqf as u64;
        if keep {
            self.done[ci][t] = true;
            &self.clips[ci][t * nqf..(t + 1) * nqf]
        } else {
            &self.scratch[..nqf]
        }
    }
}

impl Coupled {
    /// Builds the table at τ for columns `b0 ..` of a clip (`boxes`: its [`FINE`]-frame boxes,
    /// `ClipFeatures::fine_boxes`) for paths that end before column `to` (the end of the
    /// stretch the caller searches: no later end is ever reported from it, so leaving those
    /// completions out keeps the bound valid). A column's box is that of the aligned
    /// [`FINE`]-frame chunk holding it, whatever `b0` is: a box holding more frames than the
    /// columns a table needs only lowers `L`, so the bound stays a lower bound.
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn build(&mut self, prep: &Prepared, dists: &mut FineDists, ci: usize, boxes: &[f32], b0: usize, to: usize, tau: f32) {
        let rows = prep.query_frames;
        let hi = to.min(b0 + SPAN + 2 * (rows - 1));
        let w = hi - b0;
        self.b0 = b0;
        self.w = w;
        self.valid_to = to.min(b0 + SPAN);
        self.scale = 2.0 * tau * (rows + prep.max_span) as f32;
        // L − τ, row-major.
        self.lrow.clear();
        self.lrow.resize(rows * w, 0.0);
        for t in (b0 / FINE)..hi.div_ceil(FINE) {
            let (c0, c1) = ((t * FINE).max(b0), ((t + 1) * FINE).min(hi));
            for (q, l) in dists.chunk(prep, ci, boxes, t).iter().enumerate() {
                let e = l - tau;
                for i in q * QFINE..((q + 1) * QFINE).min(rows) {
                    self.lrow[i * w + (c0 - b0)..i * w + (c1 - b0)].fill(e);
                }
            }
        }
        // The backward DP: B(I − 1, ·) = 0 (a path may end at any column); columns past `hi`
        // are out of reach of the valid columns' paths (or past the clip), so +∞ there.
        self.table.clear();
        self.table.resize(rows * w, f32::INFINITY);
        self.table[(rows - 1) * w..].fill(0.0);
        for i in (0..rows.saturating_sub(1)).rev() {
            let (head, tail) = self.table.split_at_mut((i + 1) * w);
            let out = &mut head[i * w..];
            let next = &tail[..w];
            let e1 = &self.lrow[(i + 1) * w..(i + 2) * w];
            if w < 2 {
                continue;
            }
            if i + 2 < rows {
                let next2 = &tail[w..2 * w];
                let e2 = &self.lrow[(i + 2) * w..(i + 3) * w];
                for k in 0..w - 2 {
                    let m = next[k + 1].min(next[k + 2] + e1[k + 2]).min(next2[k + 1] + e2[k + 1]);
                    out[k] = 2.0 * e1[k + 1] + m;
                }
                let k = w - 2;
                out[k] = 2.0 * e1[k + 1] + next[k + 1].min(next2[k + 1] + e2[k + 1]);
            } else {
                for k in 0..w - 2 {
                    let m = next[k + 1].min(next[k + 2] + e1[k + 2]);
                    out[k] = 2.0 * e1[k + 1] + m;
                }
                let k = w - 2;
                out[k] = 2.0 * e1[k + 1] + next[k + 1];
            }
        }
    }

    /// Whether column `j` has a valid value in this table.
    #[inline]
    pub(crate) fn covers(&self, j: usize) -> bool {
        j >= self.b0 && j < self.valid_to
    }

    /// `B(i, j)` less its rounding slack (+∞ when no admissible completion exists: the caller
    /// drops the cell). Only for columns [`Coupled::covers`].
    #[inline]
    pub(crate) fn at(&self, i: usize, j: usize) -> f32 {
        let b = self.table[i * self.w + (j - self.b0)];
        if b == f32::INFINITY {
            return b;
        }
        b - 1e-4 * (b.abs() + self.scale) - 1e-6
    }
}

#[cfg(test)]
mod tests {
    // The bound's soundness is checked end to end by the exactness tests (fast = plain = brute
    // force); here, that the table is below the true least completion on random data.
    use super::*;
    use crate::search::features::FRAME_FLOATS;
    use crate::search::lanes::{distance, to_lanes, weighted_groups};
    use crate::search::Prepared;

    #[test]
    fn table_is_below_the_least_completion() {
        let mut x = 0x51_7cc1_b727_220au64;
        let mut next = || {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            (x >> 40) as f32 / (1u64 << 24) as f32 - 0.5
        };
        let rows = 9;
        let cols = 60;
        let q = to_lanes(&(0..rows * FRAME_FLOATS).map(|_| next()).collect::<Vec<_>>());
        let t = to_lanes(&(0..cols * FRAME_FLOATS).map(|_| next() * 0.7).collect::<Vec<_>>());
        let groups = weighted_groups(&[1.0; crate::canon::humanoid::CANON_COUNT]);
        let prep = Prepared {
            query_frames: rows,
            min_span: 5,
            max_span: 17,
            threshold: f32::INFINITY,
            max_results: 1,
            origin: crate::canon::normalize::Origin::Hips,
            groups: groups.clone(),
            query_lanes: &q,
        };
        let tau = 6.0;
        let d = |i: usize, j: usize| distance(&q[i * LANE_FLOATS..], &t[j * LANE_FLOATS..], &groups) - tau;
        // Exact least completion, backwards, in f64.
        let mut best = vec![vec![f64::INFINITY; cols]; rows];
        best[rows - 1].fill(0.0);
        for i in (0..rows - 1).rev() {
            for j in 0..cols {
                if j + 1 >= cols {
                    continue;
                }
                let e1 = d(i + 1, j + 1) as f64;
                let mut m = best[i + 1][j + 1];
                if j + 2 < cols {
                    m = m.min(best[i + 1][j + 2] + d(i + 1, j + 2) as f64);
                }
                if i + 2 < rows {
                    m = m.min(best[i + 2][j + 1] + d(i + 2, j + 1) as f64);
                }
                best[i][j] = 2.0 * e1 + m;
            }
        }
        let mut c = Coupled::default();
        let mut dists = FineDists::new(&prep, 1);
        c.build(&prep, &mut dists, 0, &crate::search::lanes::chunk_boxes(&t, FINE), 0, cols, tau);
        let mut finite = 0;
        for i in 0..rows {
            for j in 0..cols {
                assert!(c.covers(j));
                let b = c.at(i, j) as f64;
                assert!(b <= best[i][j] + 1e-9, "B({i}, {j}) = {b} above the least completion {}", best[i][j]);
                finite += b.is_finite() as usize;
            }
        }
        assert!(finite > rows * cols / 2, "the bound is finite where paths exist");
    }
}
