//! The fast search's first pass: one value per cell instead of a front, to find which ends can
//! have a match within τ at all, before the exact front DP of `dp.rs` runs on those ends alone.
//!
//! For a fixed τ a path's distance is ≤ τ exactly when `Σ w·(d − τ) ≤ 0` over its frame pairs
//! (its step weights add up to `I + span`), and the least of that sum over every path into a
//! cell obeys the ordinary one-value recurrence with the steps of spec §C — no fronts: no
//! merging, no hull, about the cost of one frame distance per cell. A cell whose value plus
//! the lower bound of the rest (`rest` and `cols`, as in `fast.rs`) is above 0 is dropped, and
//! a frame distance is abandoned once no incoming value can survive it. When τ falls during the
//! pass the stored values are left as they are: each was summed with a τ no lower than the
//! current one, so it stays a lower bound of the least sum under the current τ, which is all
//! the dropping test needs. An end is *marked* when its value is ≤ 0 (less a rounding margin):
//! every end whose least distance is ≤ τ is marked; a marked end may still be above τ (the
//! exact pass decides). Alongside the value each cell carries one real path (its cost and
//! start), so every marked end also gives a real distance — an upper bound that lowers τ.

use super::{Prepared, LANE_FLOATS};

/// Per-row state of one column: lower bound of the least `Σ w(d − τ)`, and the cost and start
/// of one real path into the cell (an upper bound for distances).
#[derive(Default)]
struct Col {
    v: Vec<f32>,
    c: Vec<f32>,
    s: Vec<u32>,
    /// Live rows `lo..hi` (empty when `lo >= hi`).
    lo: usize,
    hi: usize,
}

impl Col {
    fn new(rows: usize) -> Col {
        Col { v: vec![f32::INFINITY; rows], c: vec![0.0; rows], s: vec![0; rows], lo: 0, hi: 0 }
    }
    /// Value at row `i` (+∞ when not live).
    #[inline]
    fn at(&self, i: usize) -> f32 {
        if i >= self.lo && i < self.hi {
            self.v[i]
        } else {
            f32::INFINITY
        }
    }
    fn kill(&mut self) {
        for x in &mut self.v[self.lo..self.hi] {
            *x = f32::INFINITY;
        }
        self.lo = 0;
        self.hi = 0;
    }
}

/// What the first pass found at an end: the value (a lower bound of the least `Σ w(d − τ)`
/// with the τ of the time), that τ, and one real path (cost, start).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Mark {
    pub end: usize,
    pub value: f32,
    pub tau: f32,
    pub cost: f32,
    pub start: usize,
}

/// The lower bounds of the rest of a path, for one block of columns (see [`Filter::column`]).
pub(crate) struct Bound<'a> {
    pub margin: f32,
    pub rest: &'a [f32],
    pub fneg: &'a [f32],
    pub base: usize,
    pub last: usize,
    /// The coupled bound of the rest of a path (see `coupled.rs`), when one covers the column.
    pub cell: Option<&'a super::coupled::Coupled>,
}

/// The one-value DP over one clip segment.
pub(crate) struct Filter {
    rows: usize,
    c0: Col,
    c1: Col,
    c2: Col,
    d_prev: Vec<f32>,
    d_cur: Vec<f32>,
    from: usize,
    /// Frame distances started.
    pub distances: u64,
    /// Set when a cell past the first row is kept (the caller clears it): only then is the
    /// coupled bound worth its box distances (where the row bounds already stop every path at
    /// its first row, they settle the stretch alone).
    pub busy: bool,
}

/// Not yet computed (features are finite, so no distance is NaN).
const UNSET: f32 = f32::NAN;

impl Filter {
    pub(crate) fn new(rows: usize) -> Filter {
        Filter { rows, c0: Col::new(rows), c1: Col::new(rows), c2: Col::new(rows), d_prev: vec![UNSET; rows], d_cur: vec![UNSET; rows], from: 0, distances: 0, busy: false }
    }

    /// Starts a new segment at column `from`.
    pub(crate) fn reset(&mut self, from: usize) {
        self.c0.kill();
        self.c1.kill();
        self.c2.kill();
        self.d_prev.fill(UNSET);
        self.d_cur.fill(UNSET);
        self.from = from;
    }

    /// Column `j`. A value `v` at row i is kept when `v + rest[i] + cols(i) ≤ margin`, where
    /// `cols(i)` bounds the columns still to come: a path at row i has `R = I − 1 − i` rows left
    /// and so enters at most `2R` more columns (and none past `bound.last`), each adding at
    /// least `min(0, c − τ)`; `bound.fneg[k]` is the running sum of those from column
    /// `bound.base` (`fneg[0] = 0` before it). Returns the end's mark when row I−1 is kept.
    #[inline]
    // Row i indexes three columns' arrays, the cached distances and the bounds at once.
    #[allow(clippy::needless_range_loop)]
    pub(crate) fn column(&mut self, prep: &Prepared, target: &[f32], j: usize, tau: f32, bound: &Bound) -> Option<Mark> {
        let rows = self.rows;
        let t = &target[j * LANE_FLOATS..(j + 1) * LANE_FLOATS];
        std::mem::swap(&mut self.c2, &mut self.c1);
        std::mem::swap(&mut self.c1, &mut self.c0);
        std::mem::swap(&mut self.d_prev, &mut self.d_cur);
        self.c0.kill();
        // Only the rows touched two columns ago need clearing (the rest are still unset).
        self.d_cur.fill(UNSET);
        if j == self.from {
            self.c1.kill();
        }
        if j <= self.from + 1 {
            self.c2.kill();
        }
        let (c0, c1, c2) = (&mut self.c0, &self.c1, &self.c2);
        let rest = bound.rest;
        let here = bound.fneg[j + 1 - bound.base];
        // margin − cols(i): the budget of row i before its row bound.
        let budget = |i: usize| -> f32 {
            let last = (j + 2 * (rows - 1 - i)).min(bound.last);
            let cols = if last > j { bound.fneg[last + 1 - bound.base] - here } else { 0.0 };
            bound.margin - cols
        };
        // margin − the bound of the rest of a path at row i: the larger of the row and column
        // bounds and the coupled one.
        let cell = bound.cell.filter(|c| c.covers(j));
        let room = |i: usize| -> f32 {
            let r = budget(i) - rest[i];
            match cell {
                Some(c) => r.min(bound.margin - c.at(i, j)),
                None => r,
            }
        };
        let mut lo = usize::MAX;
        let mut hi = 0usize;
        // Row 0: a new start, value 2(d − τ).
        {
            let limit = tau + room(0) / 2.0;
            if limit >= 0.0 {
                self.distances += 1;
                let d = prep.d_abandon(0, t, limit);
                self.d_cur[0] = if d <= limit { d } else { -d };
                if d <= limit {
                    c0.v[0] = 2.0 * (d - tau);
                    c0.c[0] = 2.0 * d;
                    c0.s[0] = j as u32;
                    lo = 0;
                    hi = 1;
                }
            }
        }
        // Rows next to a live cell of the previous two columns.
        let (mut r_lo, mut r_hi) = (usize::MAX, 0usize);
        if c1.hi > c1.lo {
            r_lo = c1.lo + 1;
            r_hi = c1.hi + 2;
        }
        if c2.hi > c2.lo {
            r_lo = r_lo.min(c2.lo + 1);
            r_hi = r_hi.max(c2.hi + 1);
        }
        let r_lo = r_lo.max(1);
        let r_hi = r_hi.min(rows);
        for i in r_lo..r_hi {
            let b = room(i);
            let va = c1.at(i - 1);
            let mut vh = c2.at(i - 1);
            let mut vv = if i >= 2 { c1.at(i - 2) } else { f32::INFINITY };
            if va == f32::INFINITY && vh == f32::INFINITY && vv == f32::INFINITY {
                continue;
            }
            // Compound steps: their middle distance must be exact; a cached abandoned value
            // (stored negated) is a lower bound, enough to rule the step out cheaply.
            let mut dh = 0.0f32;
            if vh != f32::INFINITY {
                let cached = self.d_prev[i];
                if cached < 0.0 && vh + 2.0 * (-cached - tau) - tau > b {
                    vh = f32::INFINITY;
                } else {
                    if cached.is_nan() || cached < 0.0 {
                        self.distances += 1;
                        self.d_prev[i] = prep.d(i, &target[(j - 1) * LANE_FLOATS..j * LANE_FLOATS]);
                    }
                    dh = self.d_prev[i];
                    vh += 2.0 * (dh - tau);
                }
            }
            let mut dv = 0.0f32;
            if vv != f32::INFINITY {
                let cached = self.d_cur[i - 1];
                if cached < 0.0 && vv + 2.0 * (-cached - tau) - tau > b {
                    vv = f32::INFINITY;
                } else {
                    if cached.is_nan() || cached < 0.0 {
                        self.distances += 1;
                        self.d_cur[i - 1] = prep.d(i - 1, t);
                    }
                    dv = self.d_cur[i - 1];
                    vv += 2.0 * (dv - tau);
                }
            }
            // The largest d(i, j) with which some incoming value survives.
            let limit = (tau + (b - va) / 2.0).max(tau + b - vh).max(tau + b - vv);
            if limit.is_nan() || limit < 0.0 {
                continue;
            }
            self.distances += 1;
            let d = prep.d_abandon(i, t, limit);
            self.d_cur[i] = if d <= limit { d } else { -d };
            if d > limit {
                continue;
            }
            let ea = va + 2.0 * (d - tau);
            let eh = vh + (d - tau);
            let ev = vv + (d - tau);
            let (v, c, s) = if ea <= eh && ea <= ev {
                (ea, c1.c[i - 1] + 2.0 * d, c1.s[i - 1])
            } else if eh <= ev {
                (eh, c2.c[i - 1] + (2.0 * dh + d), c2.s[i - 1])
            } else {
                (ev, c1.c[i - 2] + (2.0 * dv + d), c1.s[i - 2])
            };
            if v > b {
                continue;
            }
            c0.v[i] = v;
            c0.c[i] = c;
            c0.s[i] = s;
            lo = lo.min(i);
            hi = i + 1;
        }
        if lo < hi {
            c0.lo = lo;
            c0.hi = hi;
            self.busy |= hi > 1;
        }
        (c0.hi == rows && c0.v[rows - 1] <= bound.margin)
            .then(|| Mark { end: j, value: c0.v[rows - 1], tau, cost: c0.c[rows - 1], start: c0.s[rows - 1] as usize })
    }
}
