//! Search by example (issue 3, spec §B–C, seed 002): find where in the library a motion like
//! the query happens, by subsequence DP matching over normalised canonical joint positions.
//!
//! The matching is spec §C exactly: frame distance `d(i, j) = Σ_k w_k ‖p_k(i) − q_k(j)‖`,
//! recurrence `g(i, j) = min{g(i−1, j) + d, g(i−1, j−1) + 2d, g(i, j−1) + d}` (ties go to the
//! first of these, in this order) with a start pointer `G` carried along the chosen
//! predecessor, `g(1, j) = d(1, j)`, `G(1, j) = j` (a match may start anywhere). The DP itself
//! is unconstrained; a candidate match is the path ending at target frame `j`, spanning frames
//! `G(I, j) ..= j` (span `s = j − G + 1`), with distance `g(I, j) / (I + s)` (the path's total
//! step weight, spec §C), kept only when its speed ratio is bounded:
//! `ceil(I · minSpanRatio) ≤ s ≤ floor(I · maxSpanRatio)` (defaults ½ and 2), and when its
//! distance is at or below the threshold. Candidates are taken best first — sorted by
//! (distance, clip, end frame) — up to `maxResults`, skipping any whose match would overlap one
//! already taken in the same clip.
//!
//! *The start of a taken match is re-chosen for its end* (the product's decision, like the
//! normalisation): the forward DP picks each cell's predecessor by raw cost, and raw cost
//! favours short paths, so where the query's opening is slow or still its best path squeezes
//! that opening onto a few frames and starts late (measured on real mocap: 0.3–0.9 s late in
//! 8 of 50 warped queries). The same recurrence run backwards from the end gives the least cost
//! `c(s)` of a path from every start `s` to that end; the match takes the start with the least
//! distance `c(s) / (I + span)` among the admissible spans starting no later than the
//! candidate (a later start can only be worse), and that path. So a match contains its
//! candidate's span, and its distance is never above the candidate's. The matches are listed
//! best first by these distances, and each carries its warping path.
//!
//! [`search`] is the fast exact search (lower bounds and early abandoning, see `fast.rs`);
//! [`search_plain`] computes every cell and is kept as the reference and benchmark baseline.
//! Both return the same results.

mod dp;
mod fast;
mod features;
mod lanes;
mod presets;
mod results;

use std::ops::ControlFlow;

use serde::{Deserialize, Serialize};
use thiserror::Error;

use crate::humanoid::{Canon, CANON_COUNT};
use crate::normalize::Origin;

pub use features::{ClipFeatures, FeatureIndex, JointCurve, MotionFeatures, SkippedClip, DEFAULT_INDEX_FPS, FRAME_FLOATS};
pub use presets::BodyPreset;
pub use results::{SearchMatch, SearchOutcome, SearchStats};

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
    #[error("the query is {query_frames} frames long, longer than every clip in the library (the longest has {longest_frames} frames)")]
    QueryTooLong { query_frames: usize, longest_frames: usize },
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
    /// A match spans at least `ceil(queryFrames · minSpanRatio)` frames (default 0.5:
    /// the library motion is at most twice as fast as the query). In (0, 1].
    pub min_span_ratio: f32,
    /// A match spans at most `floor(queryFrames · maxSpanRatio)` frames (default 2: at most
    /// twice as slow). ≥ 1.
    pub max_span_ratio: f32,
}

impl Default for SearchParams {
    fn default() -> Self {
        SearchParams::preset(BodyPreset::WholeBody)
    }
}

impl SearchParams {
    /// Parameters for a preset, with threshold none, 10 results, span ratio ½ – 2.
    pub fn preset(preset: BodyPreset) -> SearchParams {
        SearchParams {
            weights: preset.weights(),
            origin: preset.origin(),
            threshold: None,
            max_results: 10,
            min_span_ratio: 0.5,
            max_span_ratio: 2.0,
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
        if !(self.min_span_ratio > 0.0 && self.min_span_ratio <= 1.0) {
            return Err(SearchError::BadParam { name: "minSpanRatio", value: self.min_span_ratio, why: "must be in (0, 1]" });
        }
        if !(self.max_span_ratio >= 1.0 && self.max_span_ratio.is_finite()) {
            return Err(SearchError::BadParam { name: "maxSpanRatio", value: self.max_span_ratio, why: "must be finite and ≥ 1" });
        }
        Ok(())
    }

    /// Shortest and longest span (frames) a match of a `query_frames`-frame query may have.
    pub fn span_bounds(&self, query_frames: usize) -> (usize, usize) {
        let lo = ((query_frames as f32 * self.min_span_ratio).ceil() as usize).max(1);
        let hi = ((query_frames as f32 * self.max_span_ratio).floor() as usize).max(lo);
        (lo, hi)
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
    /// Matches found so far (candidates at or below the current bound, before overlap removal).
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
        if query_frames > longest {
            return Err(SearchError::QueryTooLong { query_frames, longest_frames: longest });
        }
        let (min_span, max_span) = params.span_bounds(query_frames);
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
