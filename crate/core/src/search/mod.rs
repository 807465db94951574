//! Search by example (spec §B–C, seed 002): find where in the library a motion like the query
//! happens, by subsequence DP matching over normalised canonical joint positions.
//!
//! The rule is spec §C (revised): frame distance `d(i, j) = Σ_k w_k ‖p_k(i) − q_k(j)‖`; a match
//! is a warping path from (first query frame, s) to (last query frame, e) made of the symmetric
//! slope-constrained steps of Sakoe and Chiba (P = 1) — diagonal with weight 2·d, or one row and
//! two columns (or two rows and one column) through the middle cell with 2·d(middle) + d — from a
//! start cell of weight 2, so every path's step weights add up to `I + span` and its span
//! `e − s + 1` lies in `[⌈(I−1)/2⌉ + 1, 2I − 1]` by construction. Its distance is its cost
//! divided by `I + span` (the weighted mean frame distance along it). For each end the match is
//! the admissible path of least distance over every start (ties to the earlier start). Results
//! are ends best first — by (distance, clip, end) — each kept unless its span shares more than
//! half of the shorter span's frames with a result already kept in the same clip, up to
//! `maxResults`, and within the threshold if one is set. So fewer than `maxResults` come back
//! only when every other admissible end is over the threshold or overlaps a shown match
//! ([`Shortfall`] says which).
//!
//! [`search`] is the fast exact search (lower bounds, early abandoning, a k-th-best bound, see
//! `fast.rs`); [`search_plain`] computes every cell (the benchmark baseline). Both return the
//! same results, and the tests check both against brute force (every start evaluated alone).

mod coupled;
mod dp;
mod fast;
mod filter;
mod features;
mod lanes;
mod presets;
mod results;
mod stored;

use std::ops::ControlFlow;

use serde::{Deserialize, Serialize};
use thiserror::Error;

use crate::canon::humanoid::{Canon, CANON_COUNT};
use crate::canon::normalize::Origin;

pub use features::{ClipFeatures, FeatureIndex, JointCurve, MotionFeatures, SkippedClip, DEFAULT_INDEX_FPS, FRAME_FLOATS};
pub use presets::BodyPreset;
pub use results::{SearchMatch, SearchOutcome, SearchStats, Shortfall};
pub use stored::{clip_key, decode_index, encode_index, library_key, open_or_build, positions_key, Opened, StoredClip, StoredIndex, StoredIndexError, STORED_INDEX_VERSION};

/// Order in which a frame distance sums its joints: extremities first, so that early
/// abandoning (which stops summing once the partial sum is too large) stops soon. The joints
/// are summed four at a time in this order (see `lanes.rs`), the same way in both searches, so
/// their distances are bit-for-bit the same.
pub const DISTANCE_ORDER: [Canon; CANON_COUNT] = {
    use Canon::*;
    [
        LeftHand, RightHand, LeftFoot, RightFoot, LeftToe, RightToe, LeftForearm, RightForearm, LeftLowerLeg, RightLowerLeg, Head,
        LeftUpperArm, RightUpperArm, Neck, LeftUpperLeg, RightUpperLeg, LeftShoulder, RightShoulder, Chest, Spine, Hips,
    ]
};

/// Everything that can go wrong in a search, with the offending values.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum SearchError {
    #[error("the query is empty: pick at least one frame")]
    EmptyQuery,
    #[error("the query is {query_frames} frames long: its shortest admissible match ({min_span_frames} frames, half its length) is longer than every clip in the library (the longest has {longest_frames} frames)")]
    QueryTooLong { query_frames: usize, min_span_frames: usize, longest_frames: usize },
    #[error("all joint weights are zero: choose a body part or give at least one joint a weight above 0")]
    AllWeightsZero,
    #[error("joint weight for {joint} is {value}: weights must be finite and not negative")]
    BadWeight { joint: &'static str, value: f32 },
    #[error("bad search parameter {name} = {value}: {why}")]
    BadParam { name: &'static str, value: f32, why: &'static str },
    #[error("clip \"{clip}\" cannot be searched: {reason}")]
    NotHumanoid { clip: String, reason: String },
    #[error("the library has no searchable clips ({skipped} offered clips were skipped)")]
    EmptyLibrary { skipped: usize },
    #[error("clip index {clip_index} is out of range: the library has {clip_count} clips")]
    UnknownClip { clip_index: usize, clip_count: usize },
    #[error("frames {start_frame}..{end_frame} are not a non-empty range inside clip \"{clip}\" ({frames} frames)")]
    BadRange { clip: String, start_frame: usize, end_frame: usize, frames: usize },
    #[error("search cancelled after {frames_done} of {frames_total} library frames")]
    Cancelled { frames_done: usize, frames_total: usize },
}

/// What to search for and how strictly.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "camelCase")]
pub struct SearchParams {
    /// Weight per canonical joint, in [`Canon::ALL`] order (`hips, spine, …, rightToe`);
    /// finite, ≥ 0, not all zero. A preset sets 1 on its joints and 0 elsewhere.
    pub weights: [f32; CANON_COUNT],
    /// Normalisation origin: hips, or shoulders for arm-only searches (spec §B.1).
    pub origin: Origin,
    /// Largest distance (weighted mean frame distance along the path) a match may have;
    /// `None` = no threshold, only `maxResults` limits.
    pub threshold: Option<f32>,
    /// Most matches to return (≥ 1).
    pub max_results: usize,
}

impl Default for SearchParams {
    fn default() -> Self {
        SearchParams::preset(BodyPreset::WholeBody)
    }
}

impl SearchParams {
    /// Parameters for a preset, with threshold none, 10 results.
    pub fn preset(preset: BodyPreset) -> SearchParams {
        SearchParams {
            weights: preset.weights(),
            origin: preset.origin(),
            threshold: None,
            max_results: 10,
        }
    }

    /// Checks the parameters.
    pub fn validate(&self) -> Result<(), SearchError> {
        for (c, &w) in Canon::ALL.iter().zip(&self.weights) {
            if !w.is_finite() || w < 0.0 {
                return Err(SearchError::BadWeight { joint: c.name(), value: w });
            }
        }
        if self.weights.iter().all(|&w| w == 0.0) {
            return Err(SearchError::AllWeightsZero);
        }
        if let Some(t) = self.threshold {
            if t.is_nan() || t < 0.0 {
                return Err(SearchError::BadParam { name: "threshold", value: t, why: "must be a number ≥ 0 (or none)" });
            }
        }
        if self.max_results == 0 {
            return Err(SearchError::BadParam { name: "maxResults", value: 0.0, why: "must be at least 1" });
        }
        Ok(())
    }

    /// Shortest and longest span (frames) of an admissible match of a `query_frames`-frame
    /// query: the steps advance one row for one or two columns, or two rows for one column.
    pub fn span_bounds(query_frames: usize) -> (usize, usize) {
        let r = query_frames.saturating_sub(1);
        (r.div_ceil(2) + 1, 2 * r + 1)
    }
}

/// Where a running search is, passed to the progress callback between chunks of work.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "camelCase")]
pub struct SearchProgress {
    /// Library frames (DP columns) done so far.
    pub frames_done: usize,
    /// Library frames in total.
    pub frames_total: usize,
    /// Match ends found so far within the current bound (before overlap removal).
    pub candidates: usize,
}

/// The query and parameters reduced to what the DP loops read.
pub(crate) struct Prepared<'q> {
    pub query_frames: usize,
    pub min_span: usize,
    pub max_span: usize,
    /// `threshold`, or +∞.
    pub threshold: f32,
    pub max_results: usize,
    pub origin: Origin,
    /// The weighted joint groups of the lane layout.
    pub groups: Vec<(usize, [f32; lanes::LANES])>,
    /// Query frames in the lane layout.
    pub query_lanes: &'q [f32],
}

impl<'q> Prepared<'q> {
    fn new(index: &FeatureIndex, query: &'q ClipFeatures, params: &SearchParams) -> Result<Prepared<'q>, SearchError> {
        params.validate()?;
        let query_frames = query.frame_count();
        if query_frames == 0 {
            return Err(SearchError::EmptyQuery);
        }
        if index.clips.is_empty() {
            return Err(SearchError::EmptyLibrary { skipped: index.skipped.len() });
        }
        let longest = index.clips.iter().map(ClipFeatures::frame_count).max().unwrap_or(0);
        let (min_span, max_span) = SearchParams::span_bounds(query_frames);
        if min_span > longest {
            return Err(SearchError::QueryTooLong { query_frames, min_span_frames: min_span, longest_frames: longest });
        }
        Ok(Prepared {
            groups: lanes::weighted_groups(&params.weights),
            query_lanes: query.lanes(params.origin),
            query_frames,
            min_span,
            max_span,
            threshold: params.threshold.unwrap_or(f32::INFINITY),
            max_results: params.max_results,
            origin: params.origin,
        })
    }

    /// Query frame `i` in the lane layout.
    #[inline]
    pub fn ql(&self, i: usize) -> &[f32] {
        &self.query_lanes[i * LANE_FLOATS..(i + 1) * LANE_FLOATS]
    }

    /// Frame distance between query frame `i` and a lane-layout library frame.
    #[inline]
    pub fn d(&self, i: usize, t: &[f32]) -> f32 {
        lanes::distance(self.ql(i), t, &self.groups)
    }

    /// [`Prepared::d`], abandoned once above `limit` (see [`lanes::distance_abandon`]).
    #[inline]
    pub fn d_abandon(&self, i: usize, t: &[f32], limit: f32) -> f32 {
        lanes::distance_abandon(self.ql(i), t, &self.groups, limit)
    }
}

pub(crate) use lanes::LANE_FLOATS;

/// The fast exact search over every clip of the library. `progress` is called between chunks
/// of work; returning `ControlFlow::Break(())` cancels the search ([`SearchError::Cancelled`]).
pub fn search(
    index: &FeatureIndex,
    query: &ClipFeatures,
    params: &SearchParams,
    progress: &mut dyn FnMut(SearchProgress) -> ControlFlow<()>,
) -> Result<SearchOutcome, SearchError> {
    let prep = Prepared::new(index, query, params)?;
    fast::run(index, &prep, progress)
}

/// [`search`] on `threads` threads (native builds; the web app gets its parallelism from Web
/// Workers that each hold part of the library instead): the library's ends are cut into
/// `threads` runs of about equal length — a long clip too — searched at once, sharing the k-th
/// best bound, and joined before the one selection. Same results as [`search`], bit for bit;
/// `progress` is called from the calling thread only (its part's progress, scaled to the
/// whole), and cancelling it stops every thread.
#[cfg(not(target_arch = "wasm32"))]
pub fn search_threads(
    index: &FeatureIndex,
    query: &ClipFeatures,
    params: &SearchParams,
    threads: usize,
    progress: &mut dyn FnMut(SearchProgress) -> ControlFlow<()>,
) -> Result<SearchOutcome, SearchError> {
    let prep = Prepared::new(index, query, params)?;
    fast::run_threads(index, &prep, threads, progress)
}

/// Round 1 of an exact search over a library split into parts that each hold whole clips (the
/// web app's Web Workers, which share no memory): the distances of real admissible paths this
/// part's probe found, as a far set picked best first (at most `maxResults` of them, best
/// first; none when more than 32 results are asked for, where the search starts unbounded).
/// Give every part's list to [`joined_bound`], and its answer to [`search_bounded`] in every
/// part: each part then prunes with the whole library's bound instead of its own (an idle part
/// whose own best matches are poor would otherwise do most of the work of the search).
pub fn search_probe(index: &FeatureIndex, query: &ClipFeatures, params: &SearchParams) -> Result<SearchProbe, SearchError> {
    search_probe_cached(index, query, params, &mut SearchCache::default())
}

/// [`search_probe`] keeping what it builds from the query in `cache`, for the
/// [`search_bounded_cached`] that follows with the same query on the same index (the web app's
/// worker): the bound tables and the coupled bound's box distances are then not built again.
/// Same results as [`search_probe`].
pub fn search_probe_cached(index: &FeatureIndex, query: &ClipFeatures, params: &SearchParams, cache: &mut SearchCache) -> Result<SearchProbe, SearchError> {
    let prep = Prepared::new(index, query, params)?;
    let (distances, work) = fast::probe_part(index, &prep, cache.get(index, &prep));
    Ok(SearchProbe { distances, distances_computed: work })
}

/// What the fast search builds from one query before it prunes — the row and column bounds'
/// tables (box distances between the query's 8-frame chunks and every clip's 16-frame chunks)
/// and the coupled bound's box distances (2-frame query chunks against 8-frame clip chunks,
/// filled where tables are built) — kept between calls by [`search_probe_cached`] and
/// [`search_bounded_cached`].
///
/// Keyed by the query's features (bit for bit), the weights and the origin (all these numbers
/// depend on, and nothing else: not the threshold, `maxResults` or any τ), and the index's clip
/// and frame counts; another query replaces what is kept. It belongs to one index: call
/// [`SearchCache::clear`] when clips are added or removed. Memory: the bound tables (about 0.9
/// MB per hour of motion, 60 fps, 120-frame query) and at most 16 MB of box distances (an hour
/// needs about 6.5 MB; past the cap they are computed per table).
#[derive(Default)]
pub struct SearchCache {
    key: Option<CacheKey>,
    built: Option<fast::Prebuilt>,
}

#[derive(PartialEq)]
struct CacheKey {
    query_bits: Vec<u32>,
    group_bits: Vec<(usize, [u32; lanes::LANES])>,
    origin: Origin,
    clips: usize,
    frames: usize,
}

impl SearchCache {
    /// Drops what is kept.
    pub fn clear(&mut self) {
        *self = SearchCache::default();
    }

    /// Heap bytes held (0 when empty).
    pub fn heap_bytes(&self) -> usize {
        self.built.as_ref().map_or(0, fast::Prebuilt::heap_bytes) + self.key.as_ref().map_or(0, |k| 4 * k.query_bits.capacity())
    }

    /// The prebuilt tables for this query, built now unless kept from the last call with it.
    fn get(&mut self, index: &FeatureIndex, prep: &Prepared) -> &mut fast::Prebuilt {
        let key = CacheKey {
            query_bits: prep.query_lanes.iter().map(|v| v.to_bits()).collect(),
            group_bits: prep.groups.iter().map(|(g, w)| (*g, w.map(f32::to_bits))).collect(),
            origin: prep.origin,
            clips: index.clips.len(),
            frames: index.total_frames(),
        };
        if self.key.as_ref() != Some(&key) || self.built.is_none() {
            // Dropped before the new one is built: at most one query's tables are held.
            self.built = None;
            self.built = Some(fast::Prebuilt::new(index, prep));
            self.key = Some(key);
        }
        self.built.as_mut().expect("built above")
    }
}

/// What [`search_probe`] found in one part.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "camelCase")]
pub struct SearchProbe {
    /// Distances of real admissible paths whose ends are pairwise far (in different clips, or
    /// at least `2·maxSpan − 1` frames apart: no span of an admissible match touches two of
    /// them), best first, at most `maxResults`.
    pub distances: Vec<f32>,
    /// Work counter: frame and box distances the probe computed.
    pub distances_computed: u64,
}

/// The bound round 2 starts from: the `max_results`-th smallest distance over every part's
/// [`SearchProbe::distances`], or +∞ when they hold fewer together.
///
/// Why it bounds the whole library's k-th result's distance from above (k = `max_results`):
/// ends in one part's list are pairwise far by construction, and ends in different parts lie
/// in different clips (a part holds whole clips), so they are far too; the k smallest of the
/// union are then k pairwise far ends of real paths, each with distance ≤ the bound. Results
/// are taken best first and a taken result knocks out only ends whose span overlaps its own,
/// so no result knocks out two far ends; each of the k is either taken or knocked out by a
/// better taken result, so at least k results have distance ≤ the bound.
pub fn joined_bound(parts: &[&[f32]], max_results: usize) -> f32 {
    let mut all: Vec<f32> = parts.iter().flat_map(|p| p.iter().copied()).filter(|d| !d.is_nan()).collect();
    all.sort_by(f32::total_cmp);
    match max_results.checked_sub(1).and_then(|k| all.get(k)) {
        Some(&d) => d,
        None => f32::INFINITY,
    }
}

/// Round 2 of a split search (see [`search_probe`]): [`search`] over this part's clips with τ
/// starting at the lower of the threshold and `bound` (from [`joined_bound`]; +∞ is allowed)
/// instead of this part's own probe.
///
/// Merging the parts' answers best first — by distance, then clip in library order, then end —
/// and keeping the first `maxResults` gives exactly [`search`] over the whole library: `bound`
/// is at least the library's k-th result's distance, and so is every lower τ the part proves
/// on the way (a far set inside a part is a far set of the library); the part returns every
/// result of its clips within its final τ with the whole library's distance and start, and a
/// result's fate in the selection depends only on better ends of its own clip, which are all
/// within that τ too. So every one of the library's k results is in its part's answer, in the
/// same order. A part's `shortfall` counts are its clips' exact counts only when its τ never
/// fell below the threshold — always the case when the merged answer is short, since a finite
/// bound below the threshold proves k results exist.
pub fn search_bounded(
    index: &FeatureIndex,
    query: &ClipFeatures,
    params: &SearchParams,
    bound: f32,
    progress: &mut dyn FnMut(SearchProgress) -> ControlFlow<()>,
) -> Result<SearchOutcome, SearchError> {
    search_bounded_cached(index, query, params, bound, &mut SearchCache::default(), progress)
}

/// [`search_bounded`] reusing (or keeping) in `cache` what [`search_probe_cached`] built for
/// the same query on this index. Same results as [`search_bounded`].
pub fn search_bounded_cached(
    index: &FeatureIndex,
    query: &ClipFeatures,
    params: &SearchParams,
    bound: f32,
    cache: &mut SearchCache,
    progress: &mut dyn FnMut(SearchProgress) -> ControlFlow<()>,
) -> Result<SearchOutcome, SearchError> {
    if bound.is_nan() || bound < 0.0 {
        return Err(SearchError::BadParam { name: "bound", value: bound, why: "must be a distance ≥ 0 (or +∞)" });
    }
    let prep = Prepared::new(index, query, params)?;
    fast::run_bounded(index, &prep, cache.get(index, &prep), bound, progress)
}

/// Joins the parts' round-2 answers ([`search_bounded`] in every part) into the whole
/// library's answer: the matches best first — by distance, then clip in library order, then
/// end frame — cut to `max_results`; the parts' work counters summed, their skipped clips
/// listed together; a shortfall (only when the merged answer is short, and then every part's
/// counts are exact: see [`search_bounded`]) with the parts' counts summed.
///
/// Each match's `clip_index` must already be its clip's place in the whole library (a part's
/// own index maps through the clips it holds): the merged answer is then [`search`] over the
/// whole library, match for match. Why that is exact: matches only knock each other out within
/// one clip, and a part holds whole clips, so each part's best-first list is the library's list
/// restricted to its clips.
pub fn merge_parts(parts: Vec<SearchOutcome>, max_results: usize) -> SearchOutcome {
    let mut stats = SearchStats::default();
    let mut skipped = Vec::new();
    let (mut admissible_ends, mut ends_within_threshold, mut threshold) = (0u64, 0u64, None);
    let mut matches = Vec::new();
    for part in parts {
        stats.frames_searched += part.stats.frames_searched;
        stats.cells_total += part.stats.cells_total;
        stats.distances_computed += part.stats.distances_computed;
        skipped.extend(part.skipped);
        if let Some(s) = part.shortfall {
            admissible_ends += s.admissible_ends;
            ends_within_threshold += s.ends_within_threshold;
            threshold = threshold.or(s.threshold);
        }
        matches.extend(part.matches);
    }
    matches.sort_by(|a, b| a.distance.total_cmp(&b.distance).then(a.clip_index.cmp(&b.clip_index)).then(a.end_frame.cmp(&b.end_frame)));
    matches.truncate(max_results);
    let shortfall = (matches.len() < max_results).then(|| Shortfall { asked: max_results, shown: matches.len(), admissible_ends, ends_within_threshold, threshold });
    SearchOutcome { matches, skipped, stats, shortfall }
}

/// The plain subsequence DP (every cell of every clip computed): the reference the fast search
/// must agree with, and the benchmark baseline. Same arguments and results as [`search`].
pub fn search_plain(
    index: &FeatureIndex,
    query: &ClipFeatures,
    params: &SearchParams,
    progress: &mut dyn FnMut(SearchProgress) -> ControlFlow<()>,
) -> Result<SearchOutcome, SearchError> {
    let prep = Prepared::new(index, query, params)?;
    dp::run(index, &prep, progress)
}

/// Self-check of the frame-distance kernel in the running build: (vector path compiled in —
/// "sse", "simd128" or "scalar" — and how many of `cases` random inputs give other bits than
/// the scalar kernel; 0 is the contract the fast search's exactness rests on).
pub fn distance_kernel_check(cases: u32) -> (&'static str, u32) {
    (lanes::VECTOR_PATH, lanes::kernel_mismatches(cases))
}

/// A progress callback that never cancels.
pub fn no_progress() -> impl FnMut(SearchProgress) -> ControlFlow<()> {
    |_| ControlFlow::Continue(())
}
