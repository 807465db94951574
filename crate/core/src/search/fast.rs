//! The fast exact search: the engine of `dp.rs` with partial paths dropped as soon as a lower
//! bound proves they cannot end at distance ≤ τ, where τ is the threshold or, lower, a proven
//! upper bound of the k-th result's distance. The ideas are the UCR Suite's (cheap-to-tight
//! lower bounds, envelope bounds, early abandoning against the current k-th best, flat
//! arrays, O(query) memory per column), re-derived for the slope-constrained steps and the
//! per-end normalisation of spec §C.
//!
//! It runs in two passes once τ is finite: `filter.rs` first computes one value per cell (the
//! least `Σ w(d − τ)` into it, pruned with the bounds below), which marks every end that can
//! have a match within τ and lowers τ from real paths; then the front DP of `dp.rs` runs, pruned
//! at the final τ, only on the windows (`maxSpan` columns) before the marked ends. An end is
//! reported only from a window that holds every admissible start of it, so its least distance
//! and start are the whole clip's.
//!
//! # Why it returns exactly what the plain DP returns
//!
//! *The test.* A path's distance is ≤ τ exactly when `Σ w·(d − τ) ≤ 0` over its frame pairs
//! (its weights add up to `I + span`). Split every step's weight into one unit per row it
//! enters and one per column it enters (diagonal `2·d(i, j)`: row i and column j; through
//! (i, j−1): `2·d(i, j−1)` gives row i and column j−1, `d(i, j)` column j; through (i−1, j):
//! rows i−1 and i and column j). A partial path at (i, j) from start s with cost c has used
//! weight `i + j − s + 2`; the rest of any completion enters each later row once and each
//! column up to its end once, so it adds at least `Σ_{i' > i} (r_{i'} − τ) + Σ_{j < j'' ≤ e}
//! (c_{j''} − τ)`, where `r_{i'}` bounds `d(i', ·)` over the columns the path can still reach
//! and `c_{j''}` bounds `d(·, j'')` over every query frame. The end is at most `j + maxSpan − 1`,
//! so the last sum is at least `Σ_{j < j'' < j + maxSpan} min(0, c_{j''} − τ)`. A partial path
//! whose `c − τ·(i + j − s + 2)` plus both bounds is above 0 (less a relative rounding margin
//! of 1e-4) is dropped. Every partial path of a match with distance ≤ τ passes; a dropped path
//! that dominated another (starting no later, costing no more) has the smaller test value, so
//! the other is dropped too. Hence every end whose least distance is ≤ τ gets exactly the plain
//! DP's least distance and start; other ends get nothing or a value above τ (filtered out).
//!
//! *The bounds (LB_Keogh-style envelopes; with no fixed band the envelope of a side is its
//! bounding box):* for a joint, `‖p − q‖ ≥ dist(p, box)` for any box holding q. Column bounds
//! are box-to-box distances between 16-frame chunks of the clip and 8-frame chunks of the
//! query (the nearest query chunk); row bounds the nearest clip chunk among those a block of
//! columns can reach. A frame distance is summed four joints at a time and abandoned once it
//! exceeds the largest value any incoming path could survive with (the partial sum is itself a
//! lower bound); an abandoned distance is recomputed in full if a compound step needs it.
//! Both passes also use the *coupled* bound of `coupled.rs` where paths get past their first
//! row: the same steps run backwards over box lower bounds of 8-frame library chunks, which
//! bounds the rest of a path from each cell and not row by row, so one path has to serve every
//! query frame (on a novel query this cut the cells needing a frame distance from about half
//! to a few percent). Each bound is a lower bound, so the test keeps the larger of them.
//! (The UCR Suite also reorders the query by variance; here the joints are summed in one fixed
//! order, extremities first, because the sum must be bit-for-bit the plain DP's.)
//!
//! *τ, the k-th best bound.* Results are taken best first and a result only knocks out ends
//! whose span overlaps it. Call two ends *far* when they lie in different clips or at least
//! `2·maxSpan − 1` frames apart in one clip: no span of at most `maxSpan` frames can touch
//! both. Given k far ends with distances ≤ τ', each is either taken or knocked out by a better
//! taken result, and no taken result knocks out two of them, so at least k results have
//! distance ≤ τ': the k-th result's distance is ≤ τ'. So τ starts at the threshold (or a bound
//! from probing the places with the lowest bounds: any path found there is a real one), drops
//! after each block of columns to the k-th distance of a far set picked best first from the
//! ends found so far, and the ends with distance ≤ the final τ are found exactly — every end
//! the selection of the first k results looks at. When fewer than k results come back, τ never
//! dropped below the threshold, so every end within the threshold was evaluated.

use std::ops::ControlFlow;

use super::coupled::{Coupled, FineDists};
use super::dp::{Engine, Prune};
use super::filter::{Bound, Filter, Mark};
use super::features::FeatureIndex;
use super::lanes::{box_box, push_box, BOX_FLOATS};
use super::results::{finish, order, select_matches, Candidate, SearchOutcome, SearchStats};
use super::{Prepared, SearchError, SearchProgress, LANE_FLOATS};

/// Frames per precomputed target box.
const CHUNK: usize = super::features::BOX_CHUNK_FRAMES;
/// Frames per query box.
const QCHUNK: usize = 8;
/// Columns per block: the row bounds and τ are refreshed per block.
const BLOCK: usize = 64;
/// Most results for which the search first probes the most promising places for a bound.
const PROBE_MAX_RESULTS: usize = 32;

pub(crate) fn run(
    index: &FeatureIndex,
    prep: &Prepared,
    progress: &mut dyn FnMut(SearchProgress) -> ControlFlow<()>,
) -> Result<SearchOutcome, SearchError> {
    let mut built = Prebuilt::new(index, prep);
    let (seed, probed) = seed(index, prep, &mut built);
    run_seeded(index, prep, &mut built, seed, probed, progress)
}

/// What a search builds from the query and the library before it prunes: the row and column
/// bounds' tables and the coupled tables' box distances (filled as tables are built). Valid
/// for one query, weights and origin on one index; [`super::SearchCache`] keeps it from a
/// part's probe for the bounded search that follows on the same worker.
pub(crate) struct Prebuilt {
    bounds: Bounds,
    fine: FineDists,
}

impl Prebuilt {
    pub(crate) fn new(index: &FeatureIndex, prep: &Prepared) -> Prebuilt {
        Prebuilt { bounds: Bounds::new(index, prep), fine: FineDists::new(prep, index.clips.len()) }
    }

    /// Heap bytes held.
    pub(crate) fn heap_bytes(&self) -> usize {
        4 * self.bounds.clips.iter().map(|c| c.dist.capacity() + c.lbc.capacity()).sum::<usize>() + self.fine.heap_bytes()
    }
}

/// The probe's bound for [`run`]: the k-th member of its far set, or +∞ (no probe for many
/// results, or fewer than k far ends found).
fn seed(index: &FeatureIndex, prep: &Prepared, built: &mut Prebuilt) -> (f32, u64) {
    if prep.max_results > PROBE_MAX_RESULTS {
        return (f32::INFINITY, 0);
    }
    let (set, probed) = probe(index, prep, &built.bounds, &mut built.fine, 2);
    (if set.len() == prep.max_results { set[prep.max_results - 1] } else { f32::INFINITY }, probed)
}

/// The exact search over the whole library with τ starting at the lower of the threshold and
/// `seed` (a proven upper bound of the k-th result's distance, or +∞).
fn run_seeded(
    index: &FeatureIndex,
    prep: &Prepared,
    built: &mut Prebuilt,
    seed: f32,
    probed: u64,
    progress: &mut dyn FnMut(SearchProgress) -> ControlFlow<()>,
) -> Result<SearchOutcome, SearchError> {
    let all: Vec<(usize, usize, usize)> =
        index.clips.iter().enumerate().map(|(ci, c)| (ci, 0, c.frame_count())).filter(|s| s.2 >= prep.min_span).collect();
    let shared = SharedTau::new(prep.threshold.min(seed));
    let (mut pool, mut stats) = run_part(index, prep, &built.bounds, &mut built.fine, &all, seed, &shared, progress)?;
    stats.distances_computed += probed;
    let within = pool.len() as u64;
    let selected = select_matches(index, prep, &mut pool);
    Ok(finish(index, prep, selected, stats, within))
}

/// Round 1 of a search over a library split into parts that hold different clips (the web
/// app's workers, see [`super::search_probe`]): this part's probe far set, best first, and the
/// work done (none for more than [`PROBE_MAX_RESULTS`] results: the search then starts
/// unbounded, as [`run`] does).
pub(crate) fn probe_part(index: &FeatureIndex, prep: &Prepared, built: &mut Prebuilt) -> (Vec<f32>, u64) {
    if prep.max_results > PROBE_MAX_RESULTS {
        return (Vec::new(), 0);
    }
    // One round: the parts' lists are joined before any τ is used (the union's k-th smallest
    // is never above one part's own k-th), and the search's first pass lowers τ from real
    // paths anyway. On the hour of real motion split in two (tests/bench/search.rs) the second
    // round took about half of a part's probe time; without it the joined bound rose by 0 %
    // (source in the library) and 3.5 % (novel query) for top 10, and the busiest part's CPU
    // time fell from 60.0 to 47.9 ms and from 74.8 to 73.3 ms.
    probe(index, prep, &built.bounds, &mut built.fine, 1)
}

/// Round 2 (see [`super::search_bounded`]): [`run`] with the probe replaced by `bound`.
pub(crate) fn run_bounded(
    index: &FeatureIndex,
    prep: &Prepared,
    built: &mut Prebuilt,
    bound: f32,
    progress: &mut dyn FnMut(SearchProgress) -> ControlFlow<()>,
) -> Result<SearchOutcome, SearchError> {
    run_seeded(index, prep, built, bound, 0, progress)
}

/// [`run`] on `threads` threads: the library's ends are cut into `threads` runs of about equal
/// length (a long clip may be cut too; each piece then starts `maxSpan − 1` columns early, so
/// it holds every admissible start of its ends), each run searched on its own thread with the
/// same probe seed, and the pools joined before the one selection. Exact for the same reasons
/// as [`run`]: every part's τ is a proven upper bound of the whole library's k-th result (a far
/// set inside a part is a far set of the library), so the parts share it — each lowers a
/// common τ and reads it before every block — and every end within the final τ of its part is
/// in the joined pool with its least distance and start. Ends are reported by one part only.
#[cfg(not(target_arch = "wasm32"))]
pub(crate) fn run_threads(
    index: &FeatureIndex,
    prep: &Prepared,
    threads: usize,
    progress: &mut dyn FnMut(SearchProgress) -> ControlFlow<()>,
) -> Result<SearchOutcome, SearchError> {
    use std::sync::atomic::{AtomicBool, Ordering};
    let mut built = Prebuilt::new(index, prep);
    let (seed, probed) = seed(index, prep, &mut built);
    let (bounds, fine) = (&built.bounds, &mut built.fine);
    let parts = split(index, prep, threads.max(1));
    let shared = SharedTau::new(prep.threshold.min(seed));
    let cancel = AtomicBool::new(false);
    // Where the calling thread's progress last stood (scaled), for the cancel error.
    let reached = std::cell::Cell::new(0usize);
    let total = index.total_frames();
    let (first, rest) = parts.split_first().expect("split gives at least one part");
    let first_total: usize = first.iter().map(|s| s.2 - s.1).sum::<usize>().max(1);
    let results: Vec<Result<(Vec<Candidate>, SearchStats), SearchError>> = std::thread::scope(|scope| {
        let handles: Vec<_> = rest
            .iter()
            .map(|segments| {
                let (shared, cancel) = (&shared, &cancel);
                scope.spawn(move || {
                    let mut stop = |_: SearchProgress| if cancel.load(Ordering::Relaxed) { ControlFlow::Break(()) } else { ControlFlow::Continue(()) };
                    // Each thread keeps its own box distances (filled where its tables are).
                    run_part(index, prep, bounds, &mut FineDists::new(prep, index.clips.len()), segments, seed, shared, &mut stop)
                })
            })
            .collect();
        // This thread searches the first part and reports progress for all (scaled from its own).
        let mut mine = |p: SearchProgress| {
            let scaled = SearchProgress { frames_done: (p.frames_done.min(first_total) * total) / first_total, frames_total: total, candidates: p.candidates };
            reached.set(scaled.frames_done);
            let r = progress(scaled);
            if r.is_break() {
                cancel.store(true, Ordering::Relaxed);
            }
            r
        };
        let mut out = vec![run_part(index, prep, bounds, fine, first, seed, &shared, &mut mine)];
        out.extend(handles.into_iter().map(|h| h.join().expect("search thread panicked")));
        out
    });
    let mut pool = Vec::new();
    let mut stats = SearchStats { frames_searched: total, cells_total: total as u64 * prep.query_frames as u64, distances_computed: probed };
    for r in results {
        let (p, s) = match r {
            Err(SearchError::Cancelled { .. }) => return Err(SearchError::Cancelled { frames_done: reached.get(), frames_total: total }),
            other => other?,
        };
        pool.extend(p);
        stats.distances_computed += s.distances_computed;
    }
    let within = pool.len() as u64;
    let selected = select_matches(index, prep, &mut pool);
    Ok(finish(index, prep, selected, stats, within))
}

/// The library's ends cut into `parts` runs of about equal length, as filter segments
/// (clip, first column, end column): a piece that starts inside a clip starts `maxSpan − 1`
/// columns before its first end, and every cut lies at least `maxSpan` columns into the clip,
/// so the piece's first column is past 0 (the passes report an end of a segment that starts
/// past 0 only when all its admissible starts lie inside: exactly the piece's own ends).
#[cfg(not(target_arch = "wasm32"))]
fn split(index: &FeatureIndex, prep: &Prepared, parts: usize) -> Vec<Vec<(usize, usize, usize)>> {
    let clips: Vec<(usize, usize)> = index.clips.iter().enumerate().map(|(ci, c)| (ci, c.frame_count())).filter(|c| c.1 >= prep.min_span).collect();
    let total: usize = clips.iter().map(|c| c.1).sum();
    let share = total.div_ceil(parts).max(1);
    let mut out: Vec<Vec<(usize, usize, usize)>> = vec![Vec::new()];
    let mut room = share;
    for (ci, cols) in clips {
        let mut at = 0usize;
        while at < cols {
            let mut to = (at + room).min(cols);
            if to < cols {
                // The next piece's first end must lie at least maxSpan columns in, and no
                // piece shorter than maxSpan is left at the clip's end.
                to = to.max(prep.max_span);
                if cols.saturating_sub(to) < prep.max_span {
                    to = cols;
                }
            }
            let from = if at == 0 { 0 } else { at + 1 - prep.max_span };
            out.last_mut().expect("one part").push((ci, from, to));
            room = room.saturating_sub(to - at);
            at = to;
            if room == 0 && out.len() < parts {
                out.push(Vec::new());
                room = share;
            }
        }
    }
    out.retain(|p| !p.is_empty());
    if out.is_empty() {
        out.push(Vec::new());
    }
    out
}

/// The best τ found so far by any part of a search (see [`run_threads`]): distances are ≥ 0, so
/// their f32 bits order like the values.
struct SharedTau(std::sync::atomic::AtomicU32);

impl SharedTau {
    fn new(tau: f32) -> SharedTau {
        SharedTau(std::sync::atomic::AtomicU32::new(tau.max(0.0).to_bits()))
    }
    fn get(&self) -> f32 {
        f32::from_bits(self.0.load(std::sync::atomic::Ordering::Relaxed))
    }
    fn lower(&self, tau: f32) {
        self.0.fetch_min(tau.max(0.0).to_bits(), std::sync::atomic::Ordering::Relaxed);
    }
}

/// The exact search over `segments` (see [`split`]), τ starting at the lower of the threshold
/// and `seed` and shared through `shared`: the ends of the segments whose least distance is
/// within the final τ, with the work done.
#[allow(clippy::too_many_arguments)]
fn run_part(
    index: &FeatureIndex,
    prep: &Prepared,
    bounds: &Bounds,
    fine: &mut FineDists,
    all: &[(usize, usize, usize)],
    seed: f32,
    shared: &SharedTau,
    progress: &mut dyn FnMut(SearchProgress) -> ControlFlow<()>,
) -> Result<(Vec<Candidate>, SearchStats), SearchError> {
    let tau0 = prep.threshold.min(seed);
    if tau0.is_finite() {
        // Two passes: the one-value filter finds the ends that can be within τ (and lowers τ),
        // then the exact front DP runs on those ends' windows only.
        let (marks, tau, filtered) = filter_pass(index, prep, bounds, fine, all, tau0, shared, progress)?;
        // Sums were formed with τ values up to τ0: their rounding scales with it.
        let margin = filter_margin(prep, tau0);
        let wmin = (prep.query_frames + prep.min_span) as f32;
        let mut segments: Vec<(usize, usize, usize)> = Vec::new();
        for &(ci, m) in &marks {
            // The value was summed with a τ no lower than the final one; every path into the
            // end weighs at least I + minSpan, so this is a lower bound under the final τ.
            if m.value + (m.tau - tau) * wmin > margin {
                continue;
            }
            let from = (m.end + 1).saturating_sub(prep.max_span);
            match segments.last_mut() {
                Some(last) if last.0 == ci && from <= last.2 => last.2 = last.2.max(m.end + 1),
                _ => segments.push((ci, from, m.end + 1)),
            }
        }
        let total = index.total_frames();
        let mut pass2 = |p: SearchProgress| progress(SearchProgress { frames_done: total, frames_total: total, candidates: p.candidates });
        let (pool, exact, _) = scan(index, prep, bounds, fine, &segments, tau, false, true, shared, &mut pass2)?;
        let stats = SearchStats { distances_computed: filtered.distances_computed + exact.distances_computed, ..filtered };
        Ok((pool, stats))
    } else {
        let (pool, stats, _) = scan(index, prep, bounds, fine, all, seed, true, true, shared, progress)?;
        Ok((pool, stats))
    }
}

/// Rounding margin of the one-value pass whose τ started at `tau`: for any path that ends
/// within τ, every sum the test forms is at most about `4·τ·(I + maxSpan)` in magnitude, and
/// f32 sums of a few hundred terms stay well within 1e-4 of that.
fn filter_margin(prep: &Prepared, tau: f32) -> f32 {
    1e-4 * 4.0 * tau * (prep.query_frames + prep.max_span) as f32 + 1e-6
}

/// Row bounds (`rest[i]`: Σ over the rows after i of their bound less τ) and the running sums
/// of the column bounds' negative parts (`fneg`) for the block starting at `b0`, whose paths
/// reach no column at or after `wend`.
#[allow(clippy::too_many_arguments)]
fn block_bounds(cb: &ClipBounds, nq: usize, tau: f32, b0: usize, wend: usize, rq: &mut [f32], rest: &mut [f32], fneg: &mut Vec<f32>) {
    cb.row_bounds(nq, b0, wend, rq);
    let mut acc = 0.0f32;
    for i in (0..rest.len()).rev() {
        rest[i] = acc;
        acc += rq[i / QCHUNK] - tau;
    }
    fneg.clear();
    fneg.push(0.0);
    let mut acc = 0.0f32;
    for j in b0..wend {
        acc += (cb.lbc[j / CHUNK] - tau).min(0.0);
        fneg.push(acc);
    }
}

/// The marks of the one-value pass (`filter.rs`) over `segments` (whole clips), τ starting at
/// `tau0` and lowered after each block to the far-set bound of the real paths found.
type FilterResult = (Vec<(usize, Mark)>, f32, SearchStats);

#[allow(clippy::too_many_arguments)]
fn filter_pass(
    index: &FeatureIndex,
    prep: &Prepared,
    bounds: &Bounds,
    fine: &mut FineDists,
    segments: &[(usize, usize, usize)],
    tau0: f32,
    shared: &SharedTau,
    progress: &mut dyn FnMut(SearchProgress) -> ControlFlow<()>,
) -> Result<FilterResult, SearchError> {
    let rows = prep.query_frames;
    let total: usize = segments.iter().map(|s| s.2 - s.1).sum();
    let mut stats = SearchStats { frames_searched: total, cells_total: total as u64 * rows as u64, ..Default::default() };
    let nq = bounds.nq;
    let mut rq = vec![0f32; nq];
    let mut rest = vec![0f32; rows];
    let mut fneg: Vec<f32> = Vec::new();
    let mut tau = tau0;
    let mut marks: Vec<(usize, Mark)> = Vec::new();
    let mut upper: Vec<Candidate> = Vec::new();
    let mut upper_seen = 0usize;
    let mut done = 0usize;
    let mut filter = Filter::new(rows);
    filter.busy = true;
    let mut coupled = Coupled::default();
    let boxes0 = fine.boxes;
    for &(ci, from, to) in segments {
        let target = index.clips[ci].lanes(prep.origin);
        let cols = target.len() / LANE_FLOATS;
        let cb = &bounds.clips[ci];
        filter.reset(from);
        // The coupled bound's table, rebuilt every `SPAN` columns at the τ of the time, where
        // paths get past their first row (`busy` carries over from the previous clip, so a
        // library of many short clips does not pay a table per clip once τ is low).
        let mut table_to = from;
        for b0 in (from..to).step_by(BLOCK) {
            let p = SearchProgress { frames_done: done + b0 - from, frames_total: total, candidates: marks.len() };
            if progress(p).is_break() {
                return Err(SearchError::Cancelled { frames_done: done + b0 - from, frames_total: total });
            }
            let b1 = (b0 + BLOCK).min(to);
            let wend = (b0 + BLOCK + prep.max_span - 1).min(cols);
            // Another part of the search may have lowered τ (see `run_threads`).
            let theirs = shared.get();
            if theirs < tau {
                tau = theirs;
                upper.retain(|c| c.score <= tau);
            }
            block_bounds(cb, nq, tau, b0, wend, &mut rq, &mut rest, &mut fneg);
            if b0 >= table_to && filter.busy {
                coupled.build(prep, fine, ci, index.clips[ci].fine_boxes(prep.origin), b0, to, tau);
                table_to = coupled.valid_to;
            }
            filter.busy = false;
            let cell = (b0 < table_to && coupled.covers(b0)).then_some(&coupled);
            // Stored values may have been summed with any τ since τ0: the margin scales with it.
            let margin = filter_margin(prep, tau0);
            for j in b0..b1 {
                let last = (j + prep.max_span - 1).min(cols - 1);
                let bound = Bound { margin, rest: &rest, fneg: &fneg, base: b0, last, cell };
                if let Some(m) = filter.column(prep, target, j, tau, &bound) {
                    let score = m.cost / (rows + m.end + 1 - m.start) as f32;
                    // A real path: its distance bounds its end's from above, wherever it lies.
                    upper.push(Candidate { clip: ci, start: m.start, end: m.end, score, cost: m.cost });
                    // Only a segment that holds every admissible start of an end marks it
                    // (a piece of a split clip starts maxSpan − 1 columns before its ends).
                    if from == 0 || m.end + 1 >= from + prep.max_span {
                        marks.push((ci, m));
                    }
                }
            }
            if upper.len() > upper_seen && upper.len() >= prep.max_results {
                if let Some(kth) = far_bound(&mut upper, prep.max_results, prep.max_span) {
                    if kth < tau {
                        tau = kth;
                        upper.retain(|c| c.score <= tau);
                        shared.lower(tau);
                    }
                }
                upper_seen = upper.len();
            }
        }
        done += to - from;
    }
    // A box distance costs about one frame distance: counted with them.
    stats.distances_computed = filter.distances + (fine.boxes - boxes0);
    Ok((marks, tau, stats))
}

/// The k-th distance of a far set (see the module docs) picked best first from `pool`, if it
/// has k members: an upper bound of the k-th result's distance.
fn far_bound(pool: &mut [Candidate], k: usize, max_span: usize) -> Option<f32> {
    let set = far_set(pool, k, max_span);
    (set.len() == k).then(|| set[k - 1])
}

/// The distances of a far set picked best first from `pool` (at most k of them, best first):
/// each end is taken unless it is near one taken before.
fn far_set(pool: &mut [Candidate], k: usize, max_span: usize) -> Vec<f32> {
    pool.sort_by(order);
    let gap = 2 * max_span - 1;
    let mut picked: Vec<(usize, usize)> = Vec::new();
    let mut set = Vec::new();
    for c in pool.iter() {
        if set.len() == k {
            break;
        }
        if picked.iter().all(|&(clip, end)| clip != c.clip || end.abs_diff(c.end) >= gap) {
            picked.push((c.clip, c.end));
            set.push(c.score);
        }
    }
    set
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

/// A first τ when there is no threshold or it is loose: real paths found on the few places
/// whose row bounds are lowest (each with `maxSpan` columns of run-up), and the far set of
/// their distances picked best first (real paths, so each bounds its end's least distance from
/// above; its k-th member, if it has k, bounds the k-th result's, see the module docs).
/// Returns that far set's distances, best first (at most k), and the work done, after
/// `rounds` (1 or 2) rounds.
///
/// The paths come from the one-value DP of `filter.rs`, which at a fixed λ finds into every end
/// the path of least `Σ w·(d − λ)` (and carries its cost and start) — about the cost of one
/// frame distance per cell, where the front DP costs several. Twice, as in Dinkelbach's method
/// for least ratios: at λ = 0 (the cheapest paths, nothing pruned: every value is ≥ 0), then at
/// the far-set bound of those; a path of least `Σ w·(d − λ)` with λ at or above the least
/// distance has a distance no higher than λ, so the second round tightens the bound. Only paths
/// with `Σ w·(d − λ) ≤ 0` can do that, so the second round drops the others with the bounds of
/// the search itself (row bounds and the coupled table, built at λ over the probed stretch) —
/// pruning there can only lose paths, never make one up, so whatever is found stays real.
fn probe(index: &FeatureIndex, prep: &Prepared, bounds: &Bounds, fine: &mut FineDists, rounds: usize) -> (Vec<f32>, u64) {
    let boxes0 = fine.boxes;
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
    let gap = 2 * prep.max_span + BLOCK;
    let mut picked: Vec<(usize, usize)> = Vec::new();
    let mut segments = Vec::new();
    for &(_, ci, b0) in &places {
        if picked.len() >= k {
            break;
        }
        if picked.iter().any(|&(c, b)| c == ci && b.abs_diff(b0) < gap) {
            continue;
        }
        picked.push((ci, b0));
        let cols = index.clips[ci].frame_count();
        segments.push((ci, b0.saturating_sub(prep.max_span), (b0 + BLOCK + prep.max_span).min(cols)));
    }
    let rows = prep.query_frames;
    let mut filter = Filter::new(rows);
    let mut rest = vec![0f32; rows];
    let mut fneg: Vec<f32> = Vec::new();
    let mut coupled = Coupled::default();
    let mut pool: Vec<Candidate> = Vec::new();
    let mut set: Vec<f32> = Vec::new();
    for round in 0..rounds {
        // λ: 0, then the worst member of the first round's far set (its k-th when it has k).
        let lambda = if round == 0 { 0.0 } else { set.last().copied().unwrap_or(f32::INFINITY) };
        if !lambda.is_finite() {
            break;
        }
        for &(ci, from, to) in &segments {
            let target = index.clips[ci].lanes(prep.origin);
            let margin = if round == 0 {
                // Nothing pruned: an infinite margin, zero bounds.
                rest.fill(0.0);
                fneg.clear();
                fneg.resize(to + 1 - from, 0.0);
                f32::INFINITY
            } else {
                // The stretch's paths stay inside `from..to`.
                block_bounds(&bounds.clips[ci], nq, lambda, from, to, &mut rq, &mut rest, &mut fneg);
                coupled.build(prep, fine, ci, index.clips[ci].fine_boxes(prep.origin), from, to, lambda);
                filter_margin(prep, lambda)
            };
            let cell = (round > 0).then_some(&coupled);
            filter.reset(from);
            for j in from..to {
                let bound = Bound { margin, rest: &rest, fneg: &fneg, base: from, last: (j + prep.max_span - 1).min(to - 1), cell };
                if let Some(m) = filter.column(prep, target, j, lambda, &bound) {
                    let score = m.cost / (rows + m.end + 1 - m.start) as f32;
                    pool.push(Candidate { clip: ci, start: m.start, end: m.end, score, cost: m.cost });
                }
            }
        }
        set = far_set(&mut pool, k, prep.max_span);
    }
    (set, filter.distances + (fine.boxes - boxes0))
}

/// (ends with their least distance ≤ the final τ, work, final τ).
type ScanResult = (Vec<Candidate>, SearchStats, f32);

/// The pruned DP over `segments` (clip, first column, end column), τ starting at the lower of
/// the threshold and `seed`, lowered after each block when `lower`. With `exact`, only ends
/// whose every admissible start lies in the segment are kept (their least distance is then the
/// whole clip's); without, every end found is kept (a real path: an upper bound, for τ).
#[allow(clippy::too_many_arguments)]
fn scan(
    index: &FeatureIndex,
    prep: &Prepared,
    bounds: &Bounds,
    fine: &mut FineDists,
    segments: &[(usize, usize, usize)],
    seed: f32,
    lower: bool,
    exact: bool,
    shared: &SharedTau,
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
    let mut eng = Engine::new(rows);
    let mut rest = vec![0f32; rows];
    let mut fneg: Vec<f32> = Vec::new();
    let mut coupled = Coupled::default();
    let boxes0 = fine.boxes;

    for &(ci, from, to) in segments {
        let target = index.clips[ci].lanes(prep.origin);
        let cols = target.len() / LANE_FLOATS;
        let cb = &bounds.clips[ci];
        eng.reset(from);
        let mut table_to = from;
        for b0 in (from..to).step_by(BLOCK) {
            let p = SearchProgress { frames_done: done + b0 - from, frames_total: total, candidates: pool.len() };
            if progress(p).is_break() {
                return Err(SearchError::Cancelled { frames_done: done + b0 - from, frames_total: total });
            }
            let b1 = (b0 + BLOCK).min(to);
            // Another part of the search may have lowered τ (see `run_threads`).
            tau = tau.min(shared.get());
            let prune = tau.is_finite();
            let wend = (b0 + BLOCK + prep.max_span - 1).min(cols);
            if prune {
                // Row bounds: the nearest clip chunk, over the columns this block's paths can
                // reach (an end is at most maxSpan − 1 columns after any column of its path).
                block_bounds(cb, nq, tau, b0, wend, &mut rq, &mut rest, &mut fneg);
                if b0 >= table_to {
                    coupled.build(prep, fine, ci, index.clips[ci].fine_boxes(prep.origin), b0, to, tau);
                    table_to = coupled.valid_to;
                }
            }
            for j in b0..b1 {
                let found = if prune {
                    let hi = (j + prep.max_span - 1).min(cols - 1);
                    let cols_bound = if hi > j { fneg[hi + 1 - b0] - fneg[j + 1 - b0] } else { 0.0 };
                    eng.column(prep, target, j, Some(&Prune { tau, rest: &rest, cols: cols_bound, cell: (table_to > from).then_some(&coupled) }))
                } else {
                    eng.column(prep, target, j, None)
                };
                if let Some((score, start, cost)) = found {
                    if score <= tau && (!exact || from == 0 || j + 1 >= from + prep.max_span) {
                        pool.push(Candidate { clip: ci, start, end: j, score, cost });
                    }
                }
            }
            if lower && pool.len() > pool_seen && pool.len() >= prep.max_results {
                if let Some(kth) = far_bound(&mut pool, prep.max_results, prep.max_span) {
                    if kth < tau {
                        tau = kth;
                        pool.retain(|c| c.score <= tau);
                        shared.lower(tau);
                    }
                }
                pool_seen = pool.len();
            }
        }
        done += to - from;
    }
    pool.retain(|c| c.score <= tau);
    stats.distances_computed = eng.distances + (fine.boxes - boxes0);
    Ok((pool, stats, tau))
}

