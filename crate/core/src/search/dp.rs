//! The DP of spec §C over one clip, column by column: the symmetric slope-constrained step
//! pattern of Sakoe and Chiba (P = 1) with, in every cell, the *Pareto front* of the partial
//! paths that reach it — pairs (cost, start) such that no other partial path into the cell
//! starts no later and costs no more.
//!
//! Why a front and not one value per cell: a match's distance is its cost divided by its total
//! step weight `I + span`, and the span depends on the start. Two partial paths into the same
//! cell share every completion, so the one starting earlier (larger normaliser) at no greater
//! cost is at least as good for every end; nothing else can be dropped without losing the
//! least distance of some end. At the last query frame the front therefore holds, for each
//! end, the least-distance path over every start (ties to the earlier start) — the per-end
//! rule of spec §C, exactly. On real motion the fronts hold one to a few entries.
//!
//! Steps (0-based rows i, columns j), with the costs added in exactly this form everywhere
//! (tests and path reconstruction too), so every code path gets the same bits:
//! * start at (0, s): `2·d(0, s)` (the start cell weighs 2, so every path's step weights add up
//!   to `I + span`);
//! * diagonal from (i−1, j−1): `+ 2·d(i, j)`;
//! * from (i−1, j−2) through (i, j−1): `+ (2·d(i, j−1) + d(i, j))`;
//! * from (i−2, j−1) through (i−1, j): `+ (2·d(i−1, j) + d(i, j))`.
//!
//! The same engine serves the plain search (nothing pruned: the benchmark baseline) and the
//! fast one, which passes a [`Prune`] test that drops a partial path only when a lower bound
//! proves it cannot end at distance ≤ τ (see `fast.rs`).

use std::ops::ControlFlow;

use super::features::FeatureIndex;
use super::results::{finish, select_matches, Candidate, SearchOutcome, SearchStats};
use super::{Prepared, SearchError, SearchProgress, LANE_FLOATS};

/// Columns between progress reports of the plain search.
pub(crate) const PROGRESS_COLUMNS: usize = 4096;

/// Not yet computed (a frame distance is never NaN: features are finite).
const UNSET: f32 = f32::NAN;

/// The fronts of one column, for the rows `lo .. lo + off.len() − 1`.
#[derive(Default)]
struct Col {
    lo: usize,
    off: Vec<u32>,
    ent: Vec<(f32, u32)>,
}

impl Col {
    #[inline]
    fn front(&self, i: usize) -> &[(f32, u32)] {
        if i < self.lo || i + 1 - self.lo >= self.off.len() {
            return &[];
        }
        let k = i - self.lo;
        &self.ent[self.off[k] as usize..self.off[k + 1] as usize]
    }
    fn clear(&mut self) {
        self.lo = 0;
        self.off.clear();
        self.ent.clear();
    }
    /// Rows `lo..hi` may hold entries (`hi` exclusive); (0, 0) when empty.
    fn range(&self) -> (usize, usize) {
        if self.ent.is_empty() {
            (0, 0)
        } else {
            (self.lo, self.lo + self.off.len() - 1)
        }
    }
}

/// What the fast search's pruning needs to know in one column: drop a partial path with cost
/// `c` from start `s` at row `i` when `c − τ·(i + j − s + 2) + rest[i] + cols > margin(c)`,
/// where `rest[i]` bounds `Σ (d − τ)` over the row units still to come and `cols` over the
/// column units (see `fast.rs` for why that is a lower bound).
pub(crate) struct Prune<'a> {
    pub tau: f32,
    pub rest: &'a [f32],
    pub cols: f32,
    /// The coupled bound of the rest of a path (`coupled.rs`), where it covers the column.
    pub cell: Option<&'a super::coupled::Coupled>,
}

impl Prune<'_> {
    /// The test value (≤ 0 keeps) minus the rounding margin, for a path of cost `c` from `s`
    /// at (i, j).
    #[inline]
    fn excess(&self, c: f32, s: usize, i: usize, j: usize) -> f32 {
        let w = (i + j + 2 - s) as f32;
        let mut r = self.rest[i] + self.cols;
        if let Some(cb) = self.cell.filter(|cb| cb.covers(j)) {
            r = r.max(cb.at(i, j));
        }
        let v = c - self.tau * w + r;
        // Relative margin so rounding in the bound sums never drops a reportable path.
        v - (1e-4 * (c + self.tau * w) + 1e-6)
    }
}

/// The DP engine for one clip segment: three columns of fronts and two of frame distances.
pub(crate) struct Engine {
    rows: usize,
    c2: Col,
    c1: Col,
    c0: Col,
    d_prev: Vec<f32>,
    d_cur: Vec<f32>,
    tmp: Vec<(f32, u32)>,
    /// Column the segment started at (no path starts before it).
    from: usize,
    /// Frame distances started.
    pub distances: u64,
}

impl Engine {
    pub(crate) fn new(rows: usize) -> Engine {
        Engine {
            rows,
            c2: Col::default(),
            c1: Col::default(),
            c0: Col::default(),
            d_prev: vec![UNSET; rows],
            d_cur: vec![UNSET; rows],
            tmp: Vec::new(),
            from: 0,
            distances: 0,
        }
    }

    /// Starts a new segment at column `from`: no partial path carries over.
    pub(crate) fn reset(&mut self, from: usize) {
        self.c2.clear();
        self.c1.clear();
        self.c0.clear();
        self.d_prev.fill(UNSET);
        self.d_cur.fill(UNSET);
        self.from = from;
    }

    /// Computes column `j` (the next after the previous call, or `from` after a reset). With
    /// `prune`, partial paths proven useless are dropped. Returns the least distance at end `j`
    /// with its start and cost, if any path reaches the last query frame there.
    #[inline]
    pub(crate) fn column(&mut self, prep: &Prepared, target: &[f32], j: usize, prune: Option<&Prune>) -> Option<(f32, usize, f32)> {
        let rows = self.rows;
        let t = &target[j * LANE_FLOATS..(j + 1) * LANE_FLOATS];
        std::mem::swap(&mut self.c2, &mut self.c1);
        std::mem::swap(&mut self.c1, &mut self.c0);
        std::mem::swap(&mut self.d_prev, &mut self.d_cur);
        self.c0.clear();
        self.d_cur.fill(UNSET);
        let has1 = j > self.from;
        let has2 = j > self.from + 1;
        // Rows that can receive a path: row 0 (a new start) and those next to a live front.
        let (l1, h1) = if has1 { self.c1.range() } else { (0, 0) };
        let (l2, h2) = if has2 { self.c2.range() } else { (0, 0) };
        let mut lo = usize::MAX;
        let mut hi = 0usize;
        if h1 > l1 {
            lo = lo.min(l1 + 1);
            hi = hi.max(h1 + 2);
        }
        if h2 > l2 {
            lo = lo.min(l2 + 1);
            hi = hi.max(h2 + 1);
        }
        let hi = hi.min(rows);
        // Row 0: a new start (cost 2·d(0, j)). Its distance is never an intermediate of a
        // compound step, so it may be abandoned early.
        self.c0.lo = 0;
        self.c0.off.push(0);
        {
            let limit = match prune {
                Some(p) => (-(p.excess(0.0, j, 0, j))) / 2.0,
                None => f32::INFINITY,
            };
            if limit >= 0.0 {
                self.distances += 1;
                let d = prep.d_abandon(0, t, limit);
                if d <= limit {
                    let c = 2.0 * d;
                    if prune.is_none_or(|p| p.excess(c, j, 0, j) <= 0.0) {
                        self.c0.ent.push((c, j as u32));
                    }
                }
            }
        }
        self.c0.off.push(self.c0.ent.len() as u32);
        if lo >= hi {
            return if rows == 1 { self.end_of(j) } else { None };
        }
        // Rows 1..lo are empty.
        for _ in 1..lo {
            self.c0.off.push(self.c0.ent.len() as u32);
        }
        for i in lo.max(1)..hi {
            let diag = if has1 { self.c1.front(i - 1) } else { &[] };
            let hor = if has2 { self.c2.front(i - 1) } else { &[] };
            let ver = if has1 && i >= 2 { self.c1.front(i - 2) } else { &[] };
            if diag.is_empty() && hor.is_empty() && ver.is_empty() {
                self.c0.off.push(self.c0.ent.len() as u32);
                continue;
            }
            // Intermediate distances of the compound steps (exact; computed on demand).
            let dh = if hor.is_empty() { 0.0 } else { exact(&mut self.d_prev[i], &mut self.distances, || prep.d(i, &target[(j - 1) * LANE_FLOATS..j * LANE_FLOATS])) };
            let dv = if ver.is_empty() { 0.0 } else { exact(&mut self.d_cur[i - 1], &mut self.distances, || prep.d(i - 1, t)) };
            // The largest d(i, j) with which some path survives (early abandoning).
            let limit = match prune {
                None => f32::INFINITY,
                Some(p) => {
                    let mut m = f32::NEG_INFINITY;
                    for &(c, s) in diag {
                        m = m.max(-p.excess(c, s as usize, i, j) / 2.0);
                    }
                    for &(c, s) in hor {
                        m = m.max(-p.excess(c + 2.0 * dh, s as usize, i, j));
                    }
                    for &(c, s) in ver {
                        m = m.max(-p.excess(c + 2.0 * dv, s as usize, i, j));
                    }
                    m
                }
            };
            if limit < 0.0 {
                self.c0.off.push(self.c0.ent.len() as u32);
                continue;
            }
            self.distances += 1;
            let d = prep.d_abandon(i, t, limit);
            // An abandoned distance is stored negated: only a lower bound, recomputed if a
            // compound step needs it exactly.
            self.d_cur[i] = if d <= limit { d } else { -d };
            if d > limit {
                self.c0.off.push(self.c0.ent.len() as u32);
                continue;
            }
            // Merge the three fronts (each sorted by start) by start, the cheapest first on
            // equal starts, keeping an entry only if it is cheaper than every entry starting
            // no later (the Pareto front).
            let (mut a, mut b, mut v) = (0usize, 0usize, 0usize);
            let mut best = f32::INFINITY;
            loop {
                let sa = diag.get(a).map_or(u32::MAX, |e| e.1);
                let sb = hor.get(b).map_or(u32::MAX, |e| e.1);
                let sv = ver.get(v).map_or(u32::MAX, |e| e.1);
                let s = sa.min(sb).min(sv);
                if s == u32::MAX {
                    break;
                }
                let mut c = f32::INFINITY;
                if sa == s {
                    c = c.min(diag[a].0 + 2.0 * d);
                    a += 1;
                }
                if sb == s {
                    c = c.min(hor[b].0 + (2.0 * dh + d));
                    b += 1;
                }
                if sv == s {
                    c = c.min(ver[v].0 + (2.0 * dv + d));
                    v += 1;
                }
                if c < best {
                    best = c;
                    if prune.is_none_or(|p| p.excess(c, s as usize, i, j) <= 0.0) {
                        self.tmp.push((c, s));
                    }
                }
            }
            hull(&mut self.tmp, prune.map_or(f32::INFINITY, |p| p.tau), &mut self.c0.ent);
            self.c0.off.push(self.c0.ent.len() as u32);
        }
        if hi == rows {
            self.end_of(j)
        } else {
            None
        }
    }

    /// The least distance at end `j` over the last row's front (ties to the earlier start).
    fn end_of(&self, j: usize) -> Option<(f32, usize, f32)> {
        let rows = self.rows;
        let mut best: Option<(f32, usize, f32)> = None;
        for &(c, s) in self.c0.front(rows - 1) {
            let score = c / (rows + j + 1 - s as usize) as f32;
            if best.is_none_or(|b| score < b.0) {
                best = Some((score, s as usize, c));
            }
        }
        best
    }
}

/// Keeps, of a cell's Pareto front (`front`, by start ascending: cost falls as the start gets
/// later), only the entries that can be the best for some completion, appending them to `out`
/// (by start ascending) and clearing `front`.
///
/// Every entry of a cell shares the same completions: remaining weight w ≥ 0 and cost r ≥ 0.
/// With W the weight used so far, an entry's final distance is `(c + r) / (W + w)`, the slope
/// from (−w, −r) to the point (W, c); the least slope from a point below and left of every
/// entry is reached on the lower convex hull of the points, so an entry strictly above the
/// hull is never the best (a relative margin keeps near-collinear ones, so rounding never
/// drops a tie). And with τ finite, of two entries the earlier-starting one (A) is useless
/// when `(c_A − c_B) / (W_A − W_B) > τ`: A's distance is a weighted mean of B's and that
/// slope, so it is worse than B's or above τ; on the hull these slopes grow with W, so the
/// hull is cut at the first edge steeper than τ.
fn hull(front: &mut Vec<(f32, u32)>, tau: f32, out: &mut Vec<(f32, u32)>) {
    if front.len() <= 1 {
        out.append(front);
        return;
    }
    // Points by W ascending = start descending: x = −start, y = cost (both rising).
    let base = out.len();
    for &(c, s) in front.iter().rev() {
        let (x, y) = (-(s as f64), c as f64);
        if let Some(&(c1, s1)) = out.get(base..).and_then(|o| o.last()) {
            // The τ rule against the last kept (later-starting) entry, with a margin.
            let (x1, y1) = (-(s1 as f64), c1 as f64);
            if (y - y1) > (tau as f64) * (x - x1) * (1.0 + 1e-4) + 1e-6 {
                continue;
            }
        }
        while out.len() >= base + 2 {
            let (c2, s2) = out[out.len() - 1];
            let (c1, s1) = out[out.len() - 2];
            let (x1, y1, x2, y2) = (-(s1 as f64), c1 as f64, -(s2 as f64), c2 as f64);
            // Is point 2 strictly above the chord from 1 to the new point?
            let above = (y2 - y1) * (x - x1) - (y - y1) * (x2 - x1);
            if above > 1e-5 * (y.abs() + 1e-6) * (x - x1) {
                out.pop();
            } else {
                break;
            }
        }
        out.push((c, s));
    }
    out[base..].reverse();
    front.clear();
}

/// A frame distance needed exactly: the cached value, or computed now (an abandoned one is
/// stored negated).
#[inline]
fn exact(slot: &mut f32, count: &mut u64, f: impl FnOnce() -> f32) -> f32 {
    if slot.is_nan() || *slot < 0.0 {
        *count += 1;
        *slot = f();
    }
    *slot
}

pub(crate) fn run(
    index: &FeatureIndex,
    prep: &Prepared,
    progress: &mut dyn FnMut(SearchProgress) -> ControlFlow<()>,
) -> Result<SearchOutcome, SearchError> {
    let (mut pool, stats) = candidates(index, prep, progress)?;
    let within = pool.len() as u64;
    let selected = select_matches(index, prep, &mut pool);
    Ok(finish(index, prep, selected, stats, within))
}

/// Every end of every clip with its least distance (within the threshold): every cell computed.
pub(crate) fn candidates(
    index: &FeatureIndex,
    prep: &Prepared,
    progress: &mut dyn FnMut(SearchProgress) -> ControlFlow<()>,
) -> Result<(Vec<Candidate>, SearchStats), SearchError> {
    let total = index.total_frames();
    let mut done = 0usize;
    let mut pool = Vec::new();
    let rows = prep.query_frames;
    let mut eng = Engine::new(rows);
    let mut stats = SearchStats { frames_searched: total, cells_total: (total as u64) * rows as u64, ..Default::default() };
    for (ci, clip) in index.clips.iter().enumerate() {
        let target = clip.lanes(prep.origin);
        let cols = target.len() / LANE_FLOATS;
        eng.reset(0);
        for j in 0..cols {
            if j % PROGRESS_COLUMNS == 0 {
                let p = SearchProgress { frames_done: done + j, frames_total: total, candidates: pool.len() };
                if progress(p).is_break() {
                    return Err(SearchError::Cancelled { frames_done: done + j, frames_total: total });
                }
            }
            if let Some((score, start, cost)) = eng.column(prep, target, j, None) {
                if score <= prep.threshold {
                    pool.push(Candidate { clip: ci, start, end: j, score, cost });
                }
            }
        }
        done += cols;
    }
    stats.distances_computed = eng.distances;
    Ok((pool, stats))
}
