//! Search results: candidate match ends, the best-first non-overlapping selection, and the
//! warping path of each selected match (recomputed on its span, so the scan itself keeps only
//! two DP columns).

use std::cmp::Ordering;

use serde::{Deserialize, Serialize};

use super::features::{FeatureIndex, SkippedClip, FRAME_FLOATS};
use super::{frame_distance, Prepared};

/// A match end found by the DP: the path ending at `end_frame` of clip `clip`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Candidate {
    pub clip: usize,
    pub start: usize,
    /// Inclusive.
    pub end: usize,
    /// Normalised distance `g / (I + span)`.
    pub score: f32,
    /// Raw DP cost `g(I, end)`.
    pub cost: f32,
}

fn order(a: &Candidate, b: &Candidate) -> Ordering {
    a.score.total_cmp(&b.score).then(a.clip.cmp(&b.clip)).then(a.end.cmp(&b.end))
}

/// Best first, skipping any candidate whose span overlaps one already taken in the same clip,
/// up to `max_results`. A candidate's fate depends only on the better ones, so the selection
/// among all candidates at or below some score is decided by those candidates alone.
pub(crate) fn select(pool: &mut [Candidate], max_results: usize) -> Vec<Candidate> {
    pool.sort_by(order);
    let mut taken: Vec<Candidate> = Vec::new();
    for c in pool.iter() {
        if taken.len() >= max_results {
            break;
        }
        if taken.iter().all(|t| t.clip != c.clip || c.end < t.start || c.start > t.end) {
            taken.push(*c);
        }
    }
    taken
}

/// [`select`], but a candidate that would be taken is first checked by `genuine` and dropped
/// if it fails (the fast search's check that the full DP chose that very path).
pub(crate) fn select_checked(pool: &mut [Candidate], max_results: usize, genuine: &mut dyn FnMut(&Candidate) -> bool) -> Vec<Candidate> {
    pool.sort_by(order);
    let mut taken: Vec<Candidate> = Vec::new();
    for c in pool.iter() {
        if taken.len() >= max_results {
            break;
        }
        if taken.iter().all(|t| t.clip != c.clip || c.end < t.start || c.start > t.end) && genuine(c) {
            taken.push(*c);
        }
    }
    taken
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
    /// Normalised distance: `g(I, end) / (I + lengthFrames)`, the weighted mean frame
    /// distance along the warping path (body heights × summed joint weights).
    pub distance: f32,
    /// Raw accumulated DP cost `g(I, end)`.
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
    /// Whether the fast search had to rescan without its k-th-best bound (see `fast.rs`).
    pub rescanned: bool,
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
}

/// Turns selected candidates into matches with their warping paths.
pub(crate) fn finish(index: &FeatureIndex, prep: &Prepared, selected: &[Candidate], stats: SearchStats) -> SearchOutcome {
    let matches = selected
        .iter()
        .map(|c| {
            let clip = &index.clips[c.clip];
            let target = &clip.features(prep.origin).data;
            let fps = if clip.fps > 0.0 { clip.fps } else { 1.0 };
            SearchMatch {
                clip_index: c.clip,
                clip_name: clip.name.clone(),
                start_frame: c.start,
                end_frame: c.end,
                length_frames: c.end + 1 - c.start,
                start_secs: c.start as f32 / fps,
                end_secs: (c.end + 1) as f32 / fps,
                distance: c.score,
                cost: c.cost,
                path: warping_path(prep, target, c.start, c.end),
            }
        })
        .collect();
    SearchOutcome { matches, skipped: index.skipped.clone(), stats }
}

/// The DP path ending at (last query frame, `end`), recomputed on columns `start..=end` with a
/// traceback table. It is the path the full scan chose: every cell on that path has all of its
/// own best path inside these columns, so its value and its choice (same order of ties) are the
/// same here, while other cells can only get dearer by losing columns before `start`.
fn warping_path(prep: &Prepared, target: &[f32], start: usize, end: usize) -> Vec<[u32; 2]> {
    let rows = prep.query_frames;
    let cols = end + 1 - start;
    // 0 = start, 1 = vertical, 2 = diagonal, 3 = horizontal.
    let mut step = vec![0u8; rows * cols];
    let mut prev = vec![0f32; rows];
    let mut cur = vec![0f32; rows];
    for c in 0..cols {
        let t = &target[(start + c) * FRAME_FLOATS..(start + c + 1) * FRAME_FLOATS];
        cur[0] = frame_distance(prep.q(0), t, &prep.joints);
        for i in 1..rows {
            let d = frame_distance(prep.q(i), t, &prep.joints);
            let mut v = cur[i - 1] + d;
            let mut s = 1u8;
            if c > 0 {
                let dg = prev[i - 1] + 2.0 * d;
                if dg < v {
                    v = dg;
                    s = 2;
                }
                let h = prev[i] + d;
                if h < v {
                    v = h;
                    s = 3;
                }
            }
            cur[i] = v;
            step[i * cols + c] = s;
        }
        std::mem::swap(&mut prev, &mut cur);
    }
    let (mut i, mut c) = (rows - 1, cols - 1);
    let mut path = vec![[i as u32, (start + c) as u32]];
    loop {
        match step[i * cols + c] {
            1 => i -= 1,
            2 => {
                i -= 1;
                c -= 1;
            }
            3 => c -= 1,
            _ => break,
        }
        path.push([i as u32, (start + c) as u32]);
    }
    path.reverse();
    path
}
