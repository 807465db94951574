//! The fast exact search: the same DP as `dp.rs`, but cells that cannot lie on the path of a
//! reportable match are never computed. The ideas are the UCR suite's (cheap lower bounds,
//! envelope bounds, early abandoning against the current k-th best, flat arrays, O(query)
//! memory per column), re-derived for subsequence DP with step weights 1/2/1 and the
//! path-weight normalisation of spec §C.
//!
//! # Why it returns exactly what the plain DP returns
//!
//! *Setting cells to +∞ is harmless when they are irrelevant.* Call a cell relevant if it lies on
//! the chosen path of a candidate the final answer could contain (span within the bounds,
//! distance ≤ the final bound τ). The DP is a plain min-cost path problem (no constraint
//! inside it), so removing cells or edges can only raise the values of the other cells. Along a
//! relevant path, by induction from its start, every cell keeps its value: its chosen
//! predecessor is relevant too (a path's prefix is that predecessor's chosen path) and keeps its
//! value, so the minimum is reached again; a predecessor earlier in tie order was strictly worse
//! in the plain DP and can only be worse now, so the same one is chosen and the start pointer is
//! the same. Hence every relevant candidate is found with the same start, end and distance.
//!
//! *The bound.* A path from cell (i, j) with start G to an end (I−1, j') (0-based rows) enters
//! every later row once (vertical or diagonal step) and every later column once (horizontal or
//! diagonal step); a diagonal step costs 2d = d for its row + d for its column, so the rest of
//! the path costs at least `Σ_{i'>i} r_{i'} + Σ_{j<j''≤j'} c_{j''}` where `r_{i'}` is any lower
//! bound of `d(i', x)` over the columns x the path can still reach and `c_{j''}` any lower bound
//! of `d(y, j'')` over all rows y. The match is reported only if
//! `g_final ≤ τ·(I + j' − G + 1)`, so it needs
//! `g(i, j) + Σ_{i'>i} r_{i'} − τ·(I + j − G + 1) + Σ_{j<j''≤j'} (c_{j''} − τ) ≤ 0`
//! for some j' ≤ G + maxSpan − 1; the last sum is at least `F(j) = Σ_{j<j''<j+maxSpan}
//! min(0, c_{j''} − τ)`. A cell (or one incoming edge of it) failing this test for every j' is
//! irrelevant and becomes +∞ (dropped). So is every cell whose span `j − G + 1` already exceeds
//! `maxSpan` (no reportable end can follow).
//!
//! *The lower bounds (LB_Keogh-style envelopes; no warping band exists here, so the envelope of
//! a side is its bounding box):* for a joint, `‖p − q‖ ≥ dist(p, box)` for any box containing q.
//! `c_j = Σ_k w_k dist(target_k(j), box of query joint k over all query frames)` bounds column j
//! from below; `r_i = Σ_k w_k dist(query_k(i), box of target joint k over the columns the block's
//! paths can reach)` bounds row i from below. Both need only boxes, never a frame pair.
//!
//! *Early abandoning:* a cell's frame distance is summed joint by joint (in the same order as
//! the plain DP, so a completed sum is bit-for-bit the same) and abandoned once it exceeds the
//! largest value any incoming edge could survive with (LB_Kim-like: the partial sum of a few
//! joints is itself a lower bound of the distance).
//!
//! *The k-th best bound:* τ starts at the threshold and, after each block of columns, drops to
//! the distance of the k-th match the best-first non-overlapping selection takes from the
//! candidates found so far. τ only decreases, so every candidate with distance ≤ the final τ is
//! found. The selection of a candidate depends only on better candidates, so if the candidates
//! ≤ final τ already yield k matches, they are exactly the plain DP's first k. If not (a later,
//! better candidate knocked earlier ones out by overlapping them), the scan is repeated with τ
//! fixed at the threshold, which is the plain DP's own rule. Float sums in the bounds get a
//! relative margin of 1e-4 so rounding never prunes a reportable cell.

use std::ops::ControlFlow;

use super::features::{FeatureIndex, FRAME_FLOATS};
use super::results::{finish, select, Candidate, SearchOutcome, SearchStats};
use super::{frame_distance_abandon, Prepared, SearchError, SearchProgress};

/// Frames per precomputed target box.
const CHUNK: usize = 16;
/// Frames per query box.
const QCHUNK: usize = 8;
/// Columns per block: the row bounds and τ are refreshed per block.
const BLOCK: usize = 128;
const NONE: usize = usize::MAX;

pub(crate) fn run(
    index: &FeatureIndex,
    prep: &Prepared,
    progress: &mut dyn FnMut(SearchProgress) -> ControlFlow<()>,
) -> Result<SearchOutcome, SearchError> {
    let (mut pool, mut stats, tau) = scan(index, prep, true, progress)?;
    let mut selected = select(&mut pool, prep.max_results);
    if selected.len() < prep.max_results && tau < prep.threshold {
        let (mut pool2, stats2, _) = scan(index, prep, false, progress)?;
        selected = select(&mut pool2, prep.max_results);
        stats.distances_computed += stats2.distances_computed;
        stats.rescanned = true;
    }
    Ok(finish(index, prep, &selected, stats))
}

/// Bounding box (min xyz, max xyz) of each weighted joint over frames, `joints.len() * 6`.
fn boxes(data: &[f32], joints: &[(usize, f32)], out: &mut Vec<f32>) {
    out.clear();
    out.resize(joints.len() * 6, 0.0);
    for b in out.chunks_exact_mut(6) {
        b[..3].fill(f32::INFINITY);
        b[3..].fill(f32::NEG_INFINITY);
    }
    for f in data.chunks_exact(FRAME_FLOATS) {
        for (b, &(k, _)) in out.chunks_exact_mut(6).zip(joints) {
            for a in 0..3 {
                b[a] = b[a].min(f[k + a]);
                b[3 + a] = b[3 + a].max(f[k + a]);
            }
        }
    }
}

/// `Σ_k w_k dist(box a_k, box b_k)`: a lower bound of the frame distance between any frame
/// inside boxes `a` and any frame inside boxes `b`.
#[inline]
fn box_box(a: &[f32], b: &[f32], joints: &[(usize, f32)]) -> f32 {
    let mut s = 0.0f32;
    for ((x, y), &(_, w)) in a.chunks_exact(6).zip(b.chunks_exact(6)).zip(joints) {
        let mut e = 0.0f32;
        for k in 0..3 {
            let o = (x[k] - y[3 + k]).max(y[k] - x[3 + k]).max(0.0);
            e += o * o;
        }
        s += w * e.sqrt();
    }
    s
}

type ScanResult = (Vec<Candidate>, SearchStats, f32);

fn scan(
    index: &FeatureIndex,
    prep: &Prepared,
    lower: bool,
    progress: &mut dyn FnMut(SearchProgress) -> ControlFlow<()>,
) -> Result<ScanResult, SearchError> {
    let rows = prep.query_frames;
    let joints = &prep.joints;
    let nj = joints.len();
    let total = index.total_frames();
    let mut stats = SearchStats { frames_searched: total, cells_total: total as u64 * rows as u64, ..Default::default() };
    // Boxes of the query per QCHUNK frames.
    let mut qboxes: Vec<f32> = Vec::new();
    let mut tmp = Vec::new();
    for ch in prep.query.chunks(QCHUNK * FRAME_FLOATS) {
        boxes(ch, joints, &mut tmp);
        qboxes.extend_from_slice(&tmp);
    }
    let nq = rows.div_ceil(QCHUNK);
    let mut rq = vec![0f32; nq];
    let mut tau = prep.threshold;
    let mut pool: Vec<Candidate> = Vec::new();
    let mut pool_seen = 0usize;
    let mut done = 0usize;

    let mut pg = vec![f32::INFINITY; rows];
    let mut ps = vec![0usize; rows];
    let mut cg = vec![f32::INFINITY; rows];
    let mut cs = vec![0usize; rows];
    let mut rrest = vec![0f32; rows];
    let mut lbc: Vec<f32> = Vec::new();
    let mut chunk_boxes: Vec<f32> = Vec::new();
    let mut fneg: Vec<f32> = Vec::new();

    for (ci, clip) in index.clips.iter().enumerate() {
        let target = &clip.features(prep.origin).data;
        let cols = target.len() / FRAME_FLOATS;
        if cols < prep.min_span {
            done += cols;
            continue;
        }
        // Target boxes per chunk, and the column bounds c_j: for the columns of a chunk, the
        // nearest query box to the chunk's box.
        chunk_boxes.clear();
        lbc.clear();
        for ch in target.chunks(CHUNK * FRAME_FLOATS) {
            boxes(ch, joints, &mut tmp);
            chunk_boxes.extend_from_slice(&tmp);
            let c = qboxes.chunks_exact(nj * 6).map(|q| box_box(q, &tmp, joints)).fold(f32::INFINITY, f32::min);
            lbc.extend(std::iter::repeat_n(c, ch.len() / FRAME_FLOATS));
        }
        let (mut plo, mut phi) = (NONE, NONE);
        for b0 in (0..cols).step_by(BLOCK) {
            let p = SearchProgress { frames_done: done + b0, frames_total: total, candidates: pool.len() };
            if progress(p).is_break() {
                return Err(SearchError::Cancelled { frames_done: done + b0, frames_total: total });
            }
            let b1 = (b0 + BLOCK).min(cols);
            let prune = tau.is_finite();
            // Budget with a margin against rounding in the bound sums.
            let tp = tau * (1.0 + 1e-4) + 1e-6;
            let wend = (b0 + BLOCK + prep.max_span - 1).min(cols);
            if prune {
                // Row bounds r_i: the nearest target chunk box, over the columns this block's
                // paths can reach (a path through column j of the block ends by
                // G + maxSpan − 1 ≤ j + maxSpan − 1), to the box of the query chunk holding row i.
                rq.fill(f32::INFINITY);
                for c in (b0 / CHUNK)..wend.div_ceil(CHUNK) {
                    let tb = &chunk_boxes[c * nj * 6..(c + 1) * nj * 6];
                    for (r, qb) in rq.iter_mut().zip(qboxes.chunks_exact(nj * 6)) {
                        *r = r.min(box_box(qb, tb, joints));
                    }
                }
                let mut acc = 0.0f32;
                for i in (0..rows).rev() {
                    rrest[i] = acc;
                    acc += rq[i / QCHUNK];
                }
                fneg.clear();
                fneg.push(0.0);
                let mut acc = 0.0f32;
                for &c in &lbc[b0..wend] {
                    acc += (c - tau).min(0.0);
                    fneg.push(acc);
                }
            }
            for j in b0..b1 {
                let t = &target[j * FRAME_FLOATS..(j + 1) * FRAME_FLOATS];
                // F(j) = Σ_{j < j'' < j + maxSpan} min(0, c_j'' − τ) (≤ 0).
                let f_j = if prune {
                    let hi = (j + prep.max_span - 1).min(cols - 1);
                    fneg[hi + 1 - b0] - fneg[j + 1 - b0]
                } else {
                    0.0
                };
                let (mut clo, mut chi) = (NONE, NONE);
                // Row 0: a new start, g = d(0, j), G = j, span 1.
                {
                    let dmax = if prune { tp * (rows + 1) as f32 - rrest[0] - f_j } else { f32::INFINITY };
                    if dmax >= 0.0 {
                        stats.distances_computed += 1;
                        let d = frame_distance_abandon(prep.q(0), t, joints, dmax);
                        if d <= dmax {
                            cg[0] = d;
                            cs[0] = j;
                            clo = 0;
                            chi = 0;
                        }
                    }
                }
                let prev_any = plo != NONE;
                let mut i = 1;
                while i < rows {
                    let up = clo != NONE && chi == i - 1;
                    let diag_ok = prev_any && i - 1 >= plo && i - 1 <= phi;
                    let hor_ok = prev_any && i >= plo && i <= phi;
                    if !up && !diag_ok && !hor_ok {
                        if prev_any && i < plo {
                            if clo != NONE {
                                cg[i..plo].fill(f32::INFINITY);
                            }
                            i = plo;
                            continue;
                        }
                        break;
                    }
                    // Incoming edges in tie order: vertical, diagonal, horizontal.
                    let mut opts = [(0f32, 0usize, 0f32, 0f32); 3];
                    let mut n = 0;
                    let base = if prune { rrest[i] + f_j } else { 0.0 };
                    let mut dmax = f32::NEG_INFINITY;
                    let mut push = |v: f32, s: usize, w: f32| {
                        if v.is_finite() && j + 1 - s <= prep.max_span {
                            let slack = if prune { (tp * (rows + j + 1 - s) as f32 - base - v) / w } else { f32::INFINITY };
                            opts[n] = (v, s, w, slack);
                            n += 1;
                            dmax = dmax.max(slack);
                        }
                    };
                    if up {
                        push(cg[i - 1], cs[i - 1], 1.0);
                    }
                    if diag_ok {
                        push(pg[i - 1], ps[i - 1], 2.0);
                    }
                    if hor_ok {
                        push(pg[i], ps[i], 1.0);
                    }
                    let mut live = false;
                    if n > 0 && dmax >= 0.0 {
                        stats.distances_computed += 1;
                        let d = frame_distance_abandon(prep.q(i), t, joints, dmax);
                        if d <= dmax {
                            let mut best = f32::INFINITY;
                            let mut start = 0;
                            for &(v, s, w, slack) in &opts[..n] {
                                if d <= slack {
                                    let val = v + w * d;
                                    if val < best {
                                        best = val;
                                        start = s;
                                    }
                                }
                            }
                            if best.is_finite() {
                                cg[i] = best;
                                cs[i] = start;
                                live = true;
                                if clo == NONE {
                                    clo = i;
                                }
                                chi = i;
                            }
                        }
                    }
                    if !live && clo != NONE {
                        cg[i] = f32::INFINITY;
                    }
                    i += 1;
                }
                if chi == rows - 1 {
                    let (g, start) = (cg[rows - 1], cs[rows - 1]);
                    let span = j + 1 - start;
                    if span >= prep.min_span && span <= prep.max_span {
                        let score = g / (rows + span) as f32;
                        if score <= tau {
                            pool.push(Candidate { clip: ci, start, end: j, score, cost: g });
                        }
                    }
                }
                std::mem::swap(&mut pg, &mut cg);
                std::mem::swap(&mut ps, &mut cs);
                plo = clo;
                phi = chi;
            }
            if lower && pool.len() > pool_seen && pool.len() >= prep.max_results {
                let sel = select(&mut pool, prep.max_results);
                if let Some(kth) = sel.get(prep.max_results - 1) {
                    if kth.score < tau {
                        tau = kth.score;
                        pool.retain(|c| c.score <= tau);
                    }
                }
                pool_seen = pool.len();
            }
        }
        done += cols;
    }
    pool.retain(|c| c.score <= tau);
    Ok((pool, stats, tau))
}
