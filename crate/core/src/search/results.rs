//! Search results: the least-distance match for each end (found by `dp.rs`), the best-first
//! non-overlapping selection of spec §C, and each selected match's warping path.

use std::cmp::Ordering;

use serde::{Deserialize, Serialize};

use super::features::{FeatureIndex, SkippedClip};
use super::{Prepared, LANE_FLOATS};

/// The match ending at `end` of clip `clip`: the least-distance admissible path into that end
/// over every start.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Candidate {
    pub clip: usize,
    pub start: usize,
    /// Inclusive.
    pub end: usize,
    /// Distance `cost / (I + span)`.
    pub score: f32,
    /// Cost of the path (step weights of spec §C).
    pub cost: f32,
}

/// Best first: distance, then clip, then end.
pub(crate) fn order(a: &Candidate, b: &Candidate) -> Ordering {
    a.score.total_cmp(&b.score).then(a.clip.cmp(&b.clip)).then(a.end.cmp(&b.end))
}

/// The non-overlap rule of spec §C: two spans of one clip conflict when they share more than
/// half of the shorter one's frames.
pub(crate) fn conflicts(a: (usize, usize, usize), b: (usize, usize, usize)) -> bool {
    if a.0 != b.0 {
        return false;
    }
    let lo = a.1.max(b.1);
    let hi = a.2.min(b.2);
    if hi < lo {
        return false;
    }
    let shared = hi - lo + 1;
    let shorter = (a.2 - a.1 + 1).min(b.2 - b.1 + 1);
    2 * shared > shorter
}

/// The candidates spec §C takes: best first, each kept unless it conflicts with one already
/// kept, up to `max_results`. A candidate's fate depends only on the better candidates.
pub(crate) fn select(pool: &mut [Candidate], max_results: usize) -> Vec<Candidate> {
    pool.sort_by(order);
    let mut taken: Vec<Candidate> = Vec::new();
    for c in pool.iter() {
        if taken.len() >= max_results {
            break;
        }
        if !taken.iter().any(|t| conflicts((t.clip, t.start, t.end), (c.clip, c.start, c.end))) {
            taken.push(*c);
        }
    }
    taken
}

/// A selected match with its warping path.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Refined {
    pub clip: usize,
    pub start: usize,
    pub end: usize,
    pub cost: f32,
    pub score: f32,
    pub path: Vec<[u32; 2]>,
}

/// [`select`], each taken candidate with its warping path.
pub(crate) fn select_matches(index: &FeatureIndex, prep: &Prepared, pool: &mut [Candidate]) -> Vec<Refined> {
    select(pool, prep.max_results).iter().map(|c| Refined { clip: c.clip, start: c.start, end: c.end, cost: c.cost, score: c.score, path: path(index, prep, c) }).collect()
}

/// The least-cost path from (0, start) to (last query frame, end) by the steps of spec §C
/// (the DP run from that start alone, with back pointers), as unit steps: a compound step
/// lists its middle cell.
pub(crate) fn path(index: &FeatureIndex, prep: &Prepared, c: &Candidate) -> Vec<[u32; 2]> {
    let target = index.clips[c.clip].lanes(prep.origin);
    let rows = prep.query_frames;
    let cols = c.end + 1 - c.start;
    let d: Vec<f32> = (0..cols)
        .flat_map(|k| {
            let t = &target[(c.start + k) * LANE_FLOATS..(c.start + k + 1) * LANE_FLOATS];
            (0..rows).map(move |i| prep.d(i, t))
        })
        .collect();
    let at = |i: usize, k: usize| d[k * rows + i];
    let mut g = vec![f32::INFINITY; rows * cols];
    // 0 none, 1 diagonal, 2 through (i, k−1), 3 through (i−1, k).
    let mut from = vec![0u8; rows * cols];
    g[0] = 2.0 * at(0, 0);
    for k in 0..cols {
        for i in 1..rows {
            let mut best = f32::INFINITY;
            let mut how = 0u8;
            if k >= 1 {
                let v = g[(k - 1) * rows + i - 1] + 2.0 * at(i, k);
                if v < best {
                    best = v;
                    how = 1;
                }
            }
            if k >= 2 {
                let v = g[(k - 2) * rows + i - 1] + (2.0 * at(i, k - 1) + at(i, k));
                if v < best {
                    best = v;
                    how = 2;
                }
            }
            if k >= 1 && i >= 2 {
                let v = g[(k - 1) * rows + i - 2] + (2.0 * at(i - 1, k) + at(i, k));
                if v < best {
                    best = v;
                    how = 3;
                }
            }
            g[k * rows + i] = best;
            from[k * rows + i] = how;
        }
    }
    let (mut i, mut k) = (rows - 1, cols - 1);
    let mut rev = vec![[i as u32, (c.start + k) as u32]];
    while i > 0 {
        match from[k * rows + i] {
            1 => {
                i -= 1;
                k -= 1;
            }
            2 => {
                rev.push([i as u32, (c.start + k - 1) as u32]);
                i -= 1;
                k -= 2;
            }
            3 => {
                rev.push([(i - 1) as u32, (c.start + k) as u32]);
                i -= 2;
                k -= 1;
            }
            // The candidate came from a finite path from this start, so one exists.
            _ => break,
        }
        rev.push([i as u32, (c.start + k) as u32]);
    }
    rev.reverse();
    rev
}

/// One match.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "camelCase")]
pub struct SearchMatch {
    /// Index of the clip in the library ([`FeatureIndex::clips`]).
    pub clip_index: usize,
    /// The clip's name.
    pub clip_name: String,
    /// First matched library frame.
    pub start_frame: usize,
    /// Last matched library frame (inclusive).
    pub end_frame: usize,
    /// `endFrame − startFrame + 1`.
    pub length_frames: usize,
    /// `startFrame / fps`.
    pub start_secs: f32,
    /// `(endFrame + 1) / fps`.
    pub end_secs: f32,
    /// Normalised distance: the path's cost `/ (I + lengthFrames)`, the weighted mean frame
    /// distance along the warping path (body heights × summed joint weights).
    pub distance: f32,
    /// Raw accumulated cost of the warping path (step weights 1/2/1).
    pub cost: f32,
    /// The warping path from (query frame 0, `startFrame`) to (last query frame, `endFrame`):
    /// `[queryFrame, libraryFrame]` pairs, both non-decreasing, each step moving one or both
    /// by one. Use it to time-align the overlay and the plot.
    pub path: Vec<[u32; 2]>,
}

/// Work counters of a search, for the benchmark and the UI.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "camelCase")]
pub struct SearchStats {
    /// Library frames scanned.
    pub frames_searched: usize,
    /// DP cells in the full problem (query frames × library frames).
    pub cells_total: u64,
    /// Frame distances actually started (each may have been abandoned part-way).
    pub distances_computed: u64,
}

/// A search's answer.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "camelCase")]
pub struct SearchOutcome {
    /// Best first.
    pub matches: Vec<SearchMatch>,
    /// Library clips that were refused when the index was built, with why.
    pub skipped: Vec<SkippedClip>,
    /// Work counters.
    pub stats: SearchStats,
    /// Set when fewer matches than asked came back: how many admissible ones exist and why
    /// they are not shown.
    pub shortfall: Option<Shortfall>,
}

/// Why fewer matches came back than were asked for (spec §C, the k-results guarantee): every
/// other admissible end of the library is over the threshold or its match overlaps a shown
/// one by more than half of the shorter span.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "camelCase")]
pub struct Shortfall {
    /// `maxResults`.
    pub asked: usize,
    /// Matches returned.
    pub shown: usize,
    /// Ends in the library where an admissible match can end (each has one).
    pub admissible_ends: u64,
    /// Of those, the ends whose match is within the threshold (all of them without one).
    pub ends_within_threshold: u64,
    /// The threshold, if one was set.
    pub threshold: Option<f32>,
}

/// Turns selected matches into the answer. `within` is the number of ends whose match is
/// within the threshold (exact whenever the answer is short: see `fast.rs`).
pub(crate) fn finish(index: &FeatureIndex, prep: &Prepared, selected: Vec<Refined>, stats: SearchStats, within: u64) -> SearchOutcome {
    let shortfall = (selected.len() < prep.max_results).then(|| Shortfall {
        asked: prep.max_results,
        shown: selected.len(),
        admissible_ends: index.clips.iter().map(|c| (c.frame_count() + 1).saturating_sub(prep.min_span) as u64).sum(),
        ends_within_threshold: within,
        threshold: prep.threshold.is_finite().then_some(prep.threshold),
    });
    let matches = selected
        .into_iter()
        .map(|m| {
            let clip = &index.clips[m.clip];
            let fps = if clip.fps > 0.0 { clip.fps } else { 1.0 };
            SearchMatch {
                clip_index: m.clip,
                clip_name: clip.name.clone(),
                start_frame: m.start,
                end_frame: m.end,
                length_frames: m.end + 1 - m.start,
                start_secs: m.start as f32 / fps,
                end_secs: (m.end + 1) as f32 / fps,
                distance: m.score,
                cost: m.cost,
                path: m.path,
            }
        })
        .collect();
    SearchOutcome { matches, skipped: index.skipped.clone(), stats, shortfall }
}
