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
//! *But the pruned scan can also report what the full DP never does:* where the full DP's best
//! path into an end was removed (too long, or too costly to be reported), the next best path to
//! that end may be reportable. So a candidate is checked before the selection takes it
//! (`is_genuine`: the plain DP rerun on a window long enough that no path from before it can be
//! cheaper, compared bit for bit). Candidates the selection skips for overlap need no check.
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
//! *Early abandoning:* a cell's frame distance is summed four joints at a time (in the same
//! order as the plain DP, so a completed sum is bit-for-bit the same) and abandoned once it
//! exceeds the
//! largest value any incoming edge could survive with (LB_Kim-like: the partial sum of a few
//! joints is itself a lower bound of the distance).
//!
//! *The k-th best bound:* τ starts at the threshold, or lower at a guess from probing the few
//! places with the lowest bounds first (`probe`), and after each block of columns drops to
//! the distance of the k-th candidate a best-first selection takes from the candidates found
//! so far (by their forward spans: an estimate). τ only decreases, so every candidate with
//! distance ≤ the final τ is found. The final selection of a candidate (checked, its start
//! re-chosen, see `results::select_matches`) depends only on better candidates, so if the
//! candidates ≤ final τ already yield k matches, they are exactly the plain DP's first k. If
//! not (a later, better candidate knocked earlier ones out by overlapping them, re-chosen
//! starts overlapped where forward spans did not, the guess was too low, or a candidate failed
//! its check), the scan is repeated with τ fixed a quarter higher, which finds every candidate
//! up to that bound and is judged the same way; failing that, with τ fixed at the threshold,
//! the plain DP's own rule (with no threshold, the plain DP's scan itself). And where pruning
//! does not pay (after an eighth of the library more than 90 % of the cells were computed), the
//! search switches to the plain DP, whose answer is the definition. Float sums in the
//! bounds get a relative margin of 1e-4 so rounding never prunes a reportable cell.

use std::ops::ControlFlow;

use super::features::FeatureIndex;
use super::lanes::{box_box, point_box, push_box, BOX_FLOATS};
use super::results::{finish, refine, select, select_matches, Candidate, SearchOutcome, SearchStats};
use super::{Prepared, SearchError, SearchProgress, LANE_FLOATS};

/// Frames per precomputed target box.
const CHUNK: usize = super::features::BOX_CHUNK_FRAMES;
/// Frames per query box.
const QCHUNK: usize = 8;
/// Columns per block: the row bounds and τ are refreshed per block.
const BLOCK: usize = 32;
/// Most results for which the search first probes the most promising places for a bound.
const PROBE_MAX_RESULTS: usize = 16;
const NONE: usize = usize::MAX;

pub(crate) fn run(
    index: &FeatureIndex,
    prep: &Prepared,
    progress: &mut dyn FnMut(SearchProgress) -> ControlFlow<()>,
) -> Result<SearchOutcome, SearchError> {
    let bounds = Bounds::new(index, prep);
    let (seed, probed) = if prep.max_results > PROBE_MAX_RESULTS { (f32::INFINITY, 0) } else { probe(index, prep, &bounds) };
    let all: Vec<(usize, usize, usize)> =
        index.clips.iter().enumerate().map(|(ci, c)| (ci, 0, c.frame_count())).filter(|s| s.2 >= prep.min_span).collect();
    let (mut pool, mut stats, tau, gave_up) = scan(index, prep, &bounds, &all, seed, true, true, progress)?;
    if gave_up {
        let (selected, plain) = super::dp::selection(index, prep, progress)?;
        stats.distances_computed += probed + plain.distances_computed;
        stats.rescanned = true;
        return Ok(finish(index, selected, stats));
    }
    stats.distances_computed += probed;
    let mut st = super::dp::Columns::new(prep.query_frames);
    let mut checked = 0u64;
    let mut take = |c: &Candidate| {
        let (ok, cells) = is_genuine(index, prep, c, &mut st);
        checked += cells;
        if !ok {
            return None;
        }
        checked += (prep.query_frames * prep.max_span.min(c.end + 1)) as u64;
        refine(index, prep, c)
    };
    let mut selected = select_matches(&mut pool, prep.max_results, &mut take);
    // Too few matches at or below τ (see the module docs): scan again with a fixed, higher
    // bound — first a quarter above τ, then the threshold itself (the plain DP's own rule).
    // Without a threshold that last scan prunes nothing, so it is the plain DP's scan, whose
    // candidates need no check.
    let mut bound = tau;
    while selected.len() < prep.max_results && bound < prep.threshold {
        bound = if stats.rescanned { prep.threshold } else { (bound * 1.25).min(prep.threshold) };
        stats.rescanned = true;
        if bound.is_finite() {
            let (mut pool2, stats2, _, _) = scan(index, prep, &bounds, &all, bound, false, false, progress)?;
            stats.distances_computed += stats2.distances_computed;
            selected = select_matches(&mut pool2, prep.max_results, &mut take);
        } else {
            let (plain, stats2) = super::dp::selection(index, prep, progress)?;
            stats.distances_computed += stats2.distances_computed;
            selected = plain;
        }
    }
    stats.distances_computed += checked;
    Ok(finish(index, selected, stats))
}

/// Whether the full DP's path ending at the candidate's end is the one the pruned scan found.
///
/// Pruning removes only paths that cannot be reported, and keeps every reportable path exactly;
/// but where the full DP's best path P* into an end was removed, the pruned scan may report the
/// next best path P' to that end, which the full DP never reports. Which P* can that be?
/// * P* with span ≤ maxSpan and distance ≤ τ: never removed (each of its cells passes every
///   test, by induction along it), so the scan found it: P' = P*.
/// * P* with span ≤ maxSpan and distance > τ: it costs no more than P' but has a larger
///   distance, so it is shorter and starts after P' does.
/// * P* with span > maxSpan: it covers columns `end − maxSpan ..= end`, so it costs at least the
///   sum of their column bounds; if that sum exceeds P''s cost, P* cannot exist.
/// So the plain DP is rerun fresh from P''s start (or, when the last case cannot be ruled out,
/// from far enough back that the column bounds of any earlier start exceed P''s cost) to the
/// end: a path starting there or later gets exactly the full scan's operations, so P' is
/// genuine exactly when this rerun returns P''s value and start. Returns the verdict and the
/// cells computed.
fn is_genuine(index: &FeatureIndex, prep: &Prepared, c: &Candidate, st: &mut super::dp::Columns) -> (bool, u64) {
    let clip = &index.clips[c.clip];
    let target = clip.lanes(prep.origin);
    let all_boxes = clip.chunk_boxes(prep.origin);
    // Column bound of a chunk: the nearest query frame to the chunk's joint boxes (tighter than
    // the scan's chunk-to-chunk bound, and computed only for the chunks a check walks over).
    let chunk_bound = |t: usize| -> f32 {
        let Some(ch) = all_boxes.get(t * BOX_FLOATS..(t + 1) * BOX_FLOATS) else { return 0.0 };
        (0..prep.query_frames).map(|i| point_box(prep.ql(i), ch, &prep.groups)).fold(f32::INFINITY, f32::min)
    };
    let mut cells = 0u64;
    // Margin: a lower-bound sum must clear the cost despite rounding.
    let limit = c.cost * (1.0 + 1e-4) + 1e-6;
    let mut from = c.start;
    if c.end >= prep.max_span {
        // Walk back from the end until the bounds exceed the cost; if that happens within the
        // last maxSpan + 1 columns no over-long path can be cheaper.
        let mut j = c.end;
        let mut sum = 0.0f32;
        let mut cur_chunk = usize::MAX;
        let mut cur = 0.0f32;
        loop {
            if j / CHUNK != cur_chunk {
                cur_chunk = j / CHUNK;
                cur = chunk_bound(cur_chunk);
                // A chunk bound costs about as much as one DP column.
                cells += prep.query_frames as u64;
            }
            sum += cur;
            if sum > limit && j + prep.max_span >= c.end {
                // Columns end − maxSpan ..= end already exceed it: no over-long path can be
                // cheaper, only P''s own window matters.
                break;
            }
            if sum > limit && j < c.start {
                from = j;
                break;
            }
            if j == 0 {
                from = 0;
                break;
            }
            j -= 1;
        }
    }
    let (g, start) = super::dp::end_cell(prep, target, from, c.end, st);
    cells += ((c.end + 1 - from) * prep.query_frames) as u64;
    (g == c.cost && start == c.start, cells)
}

/// Lower-bound tables of one clip: `dist[t * nq + q]` is the box-to-box bound between target
/// chunk t and query chunk q; `lbc[t]` the column bound of every column of chunk t (its
/// nearest query chunk).
struct ClipBounds {
    dist: Vec<f32>,
    lbc: Vec<f32>,
}

impl ClipBounds {
    /// `rq[q]` = the smallest bound between query chunk q and the target chunks covering
    /// columns `from..to`.
    fn row_bounds(&self, nq: usize, from: usize, to: usize, rq: &mut [f32]) {
        rq.fill(f32::INFINITY);
        for t in (from / CHUNK)..to.div_ceil(CHUNK) {
            for (r, d) in rq.iter_mut().zip(&self.dist[t * nq..(t + 1) * nq]) {
                *r = r.min(*d);
            }
        }
    }
}

/// The query's chunk boxes and every clip's bound tables, built once per search.
struct Bounds {
    nq: usize,
    clips: Vec<ClipBounds>,
}

impl Bounds {
    fn new(index: &FeatureIndex, prep: &Prepared) -> Bounds {
        let groups = &prep.groups;
        let mut qboxes: Vec<f32> = Vec::new();
        for ch in prep.query_lanes.chunks(QCHUNK * LANE_FLOATS) {
            push_box(ch, &mut qboxes);
        }
        let nq = prep.query_frames.div_ceil(QCHUNK);
        let clips = index
            .clips
            .iter()
            .map(|clip| {
                let all = clip.chunk_boxes(prep.origin);
                let mut dist = Vec::with_capacity(all.len() / BOX_FLOATS * nq);
                let mut lbc = Vec::with_capacity(all.len() / BOX_FLOATS);
                for ch in all.chunks_exact(BOX_FLOATS) {
                    let mut best = f32::INFINITY;
                    for q in qboxes.chunks_exact(BOX_FLOATS) {
                        let d = box_box(q, ch, groups);
                        dist.push(d);
                        best = best.min(d);
                    }
                    lbc.push(best);
                }
                ClipBounds { dist, lbc }
            })
            .collect();
        Bounds { nq, clips }
    }
}

/// A first bound for the k-th best distance when there is no threshold: the plain DP run on the
/// few places whose row bounds are lowest (each with `maxSpan` columns of run-up), and the
/// k-th of the best-first selection among what it finds. It is only a guess (those local runs
/// start fresh, so their paths may differ from the full scan's): the scan's final check keeps
/// the answer exact whatever it is.
fn probe(index: &FeatureIndex, prep: &Prepared, bounds: &Bounds) -> (f32, u64) {
    let k = prep.max_results;
    let nq = bounds.nq;
    let mut rq = vec![0f32; nq];
    let mut places: Vec<(f32, usize, usize)> = Vec::new();
    for (ci, clip) in index.clips.iter().enumerate() {
        let cols = clip.frame_count();
        if cols < prep.min_span {
            continue;
        }
        for b0 in (0..cols).step_by(BLOCK) {
            let wend = (b0 + BLOCK + prep.max_span - 1).min(cols);
            bounds.clips[ci].row_bounds(nq, b0, wend, &mut rq);
            let total: f32 = (0..prep.query_frames).map(|i| rq[i / QCHUNK]).sum();
            places.push((total, ci, b0));
        }
    }
    places.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)).then(a.2.cmp(&b.2)));
    let mut picked: Vec<(usize, usize)> = Vec::new();
    let mut segments = Vec::new();
    for &(_, ci, b0) in &places {
        if picked.len() >= k {
            break;
        }
        if picked.iter().any(|&(c, b)| c == ci && b.abs_diff(b0) < BLOCK + 2 * prep.max_span) {
            continue;
        }
        picked.push((ci, b0));
        let cols = index.clips[ci].frame_count();
        // The place's bound covers paths through its block and on for up to maxSpan columns;
        // most good matches are about as long as the query.
        let q = prep.query_frames;
        segments.push((ci, b0.saturating_sub(q / 2), (b0 + BLOCK + 2 * q).min(cols)));
    }
    // The fast scan itself, on those places only, lowering its bound as it goes.
    let Ok((mut pool, stats, _, _)) = scan(index, prep, bounds, &segments, f32::INFINITY, true, false, &mut |_| ControlFlow::Continue(())) else {
        return (f32::INFINITY, 0);
    };
    let sel = select(&mut pool, k);
    (sel.get(k - 1).map_or(f32::INFINITY, |c| c.score), stats.distances_computed)
}

/// (candidates, work, final τ, whether the scan gave up because pruning did not pay).
type ScanResult = (Vec<Candidate>, SearchStats, f32, bool);

/// A scan allowed to give up does so once it has covered an eighth of the library and computed
/// more than this share of those cells: pruning is not paying for its bookkeeping, and the
/// plain DP's tighter loop is faster.
const GIVE_UP_SHARE: f64 = 0.9;

fn scan(
    index: &FeatureIndex,
    prep: &Prepared,
    bounds: &Bounds,
    segments: &[(usize, usize, usize)],
    seed: f32,
    lower: bool,
    may_give_up: bool,
    progress: &mut dyn FnMut(SearchProgress) -> ControlFlow<()>,
) -> Result<ScanResult, SearchError> {
    let rows = prep.query_frames;
    let total: usize = segments.iter().map(|s| s.2 - s.1).sum();
    let mut stats = SearchStats { frames_searched: total, cells_total: total as u64 * rows as u64, ..Default::default() };
    let nq = bounds.nq;
    let mut rq = vec![0f32; nq];
    let mut tau = prep.threshold.min(seed);
    let mut pool: Vec<Candidate> = Vec::new();
    let mut pool_seen = 0usize;
    let mut done = 0usize;

    let mut pg = vec![f32::INFINITY; rows];
    let mut ps = vec![0usize; rows];
    let mut cg = vec![f32::INFINITY; rows];
    let mut cs = vec![0usize; rows];
    let mut rrest = vec![0f32; rows];
    let mut fneg: Vec<f32> = Vec::new();

    for &(ci, from, to) in segments {
        let target = index.clips[ci].lanes(prep.origin);
        let cols = target.len() / LANE_FLOATS;
        let cb = &bounds.clips[ci];
        let (mut plo, mut phi) = (NONE, NONE);
        for b0 in (from..to).step_by(BLOCK) {
            let p = SearchProgress { frames_done: done + b0 - from, frames_total: total, candidates: pool.len() };
            if progress(p).is_break() {
                return Err(SearchError::Cancelled { frames_done: done + b0 - from, frames_total: total });
            }
            let b1 = (b0 + BLOCK).min(to);
            let prune = tau.is_finite();
            // Budget with a margin against rounding in the bound sums.
            let tp = tau * (1.0 + 1e-4) + 1e-6;
            let wend = (b0 + BLOCK + prep.max_span - 1).min(cols);
            if prune {
                // Row bounds r_i: the nearest target chunk box, over the columns this block's
                // paths can reach (a path through column j of the block ends by
                // G + maxSpan − 1 ≤ j + maxSpan − 1), to the box of the query chunk holding row i.
                cb.row_bounds(nq, b0, wend, &mut rq);
                let mut acc = 0.0f32;
                for i in (0..rows).rev() {
                    rrest[i] = acc;
                    acc += rq[i / QCHUNK];
                }
                fneg.clear();
                fneg.push(0.0);
                let mut acc = 0.0f32;
                for j in b0..wend {
                    acc += (cb.lbc[j / CHUNK] - tau).min(0.0);
                    fneg.push(acc);
                }
            }
            for j in b0..b1 {
                let t = &target[j * LANE_FLOATS..(j + 1) * LANE_FLOATS];
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
                        let d = prep.d_abandon(0, t, dmax);
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
                        let d = prep.d_abandon(i, t, dmax);
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
            let covered = done + b1 - from;
            if may_give_up && covered * 8 >= total && stats.distances_computed as f64 > GIVE_UP_SHARE * (covered * rows) as f64 {
                return Ok((pool, stats, tau, true));
            }
        }
        done += to - from;
    }
    pool.retain(|c| c.score <= tau);
    Ok((pool, stats, tau, false))
}
