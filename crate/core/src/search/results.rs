//! Search results: candidate match ends, the best-first non-overlapping selection, and each
//! selected match's start, distance and warping path, re-chosen for its end by a backward DP
//! over its admissible spans (so the scan itself keeps only two DP columns).

use std::cmp::Ordering;

use serde::{Deserialize, Serialize};

use super::features::{FeatureIndex, SkippedClip};
use super::{Prepared, LANE_FLOATS};

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

/// Best first, skipping any candidate whose forward span overlaps one already taken in the same
/// clip, up to `max_results`: the cheap estimate of [`select_matches`] (which spans the
/// re-chosen starts) that the fast search uses to lower its bound as it goes.
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

/// A selected match: the DP's candidate end, with the start, cost, distance and path that
/// [`refine`] re-chose for that end.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Refined {
    pub clip: usize,
    pub start: usize,
    pub end: usize,
    /// Raw cost of the re-chosen path.
    pub cost: f32,
    /// `cost / (I + span)`.
    pub score: f32,
    pub path: Vec<[u32; 2]>,
}

/// The final selection. Candidates are taken best first by the forward DP's distance (the rule
/// of spec §C); `take` turns a candidate into its match ([`refine`]; the fast search first
/// checks the candidate is the full DP's own, and returns `None` if not), which is kept when
/// its span overlaps no match already kept in the same clip, up to `max_results`. A
/// candidate's fate depends only on the better candidates. The matches come back best first by
/// their own (re-chosen) distance.
pub(crate) fn select_matches(
    pool: &mut [Candidate],
    max_results: usize,
    take: &mut dyn FnMut(&Candidate) -> Option<Refined>,
) -> Vec<Refined> {
    pool.sort_by(order);
    let mut taken: Vec<Refined> = Vec::new();
    for c in pool.iter() {
        if taken.len() >= max_results {
            break;
        }
        // The re-chosen start is never after the candidate's own, so a candidate overlapping a
        // kept match cannot be kept (and need not be checked or refined).
        if taken.iter().any(|t| t.clip == c.clip && c.end >= t.start && c.start <= t.end) {
            continue;
        }
        let Some(m) = take(c) else { continue };
        if std::env::var("ODORI_DEBUG").is_ok() { eprintln!("refined {:?} -> {}..={} {}", c, m.start, m.end, m.score); }
        if taken.iter().all(|t| t.clip != m.clip || m.end < t.start || m.start > t.end) {
            taken.push(m);
        }
    }
    taken.sort_by(|a, b| a.score.total_cmp(&b.score).then(a.clip.cmp(&b.clip)).then(a.end.cmp(&b.end)));
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
    /// Whether the fast search had to scan again with a higher fixed bound, or fell back to the
    /// plain DP (see `fast.rs`).
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

/// Turns selected matches into the answer.
pub(crate) fn finish(index: &FeatureIndex, selected: Vec<Refined>, stats: SearchStats) -> SearchOutcome {
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
    SearchOutcome { matches, skipped: index.skipped.clone(), stats }
}

/// The start re-chosen for the end of candidate `c` (see the module docs of `search`): the DP
/// of spec §C run backwards from (last query frame, `c.end`) over the columns an admissible
/// span can reach gives, for every start `s`, the least cost `c(s)` of a path from (0, `s`) to
/// that end (the same paths and step weights as the forward DP, including its rule that row 0
/// is only ever entered as a new start); the start with the least normalised distance
/// `c(s) / (I + span)` among the admissible spans is taken (ties to the later start), with its
/// path. Only starts up to the candidate's own are compared: a later start costs at least the
/// forward DP's least cost `g(I, end)` over a shorter span, so its distance is always larger;
/// leaving them out makes that hold despite rounding, so a match always contains its
/// candidate's span. `None` only if no admissible start has a finite cost.
pub(crate) fn refine(index: &FeatureIndex, prep: &Prepared, cand: &Candidate) -> Option<Refined> {
    let (clip, end) = (cand.clip, cand.end);
    let target = index.clips[clip].lanes(prep.origin);
    let rows = prep.query_frames;
    let lo = (end + 1).saturating_sub(prep.max_span);
    let cols = end + 1 - lo;
    // step[i * cols + c]: 1 = down (i+1, j), 2 = diagonal (i+1, j+1), 3 = right (i, j+1), 0 = none.
    let mut step = vec![0u8; rows * cols];
    let mut h_next = vec![f32::INFINITY; rows]; // column j + 1
    let mut d_next = vec![0f32; rows];
    let mut h = vec![f32::INFINITY; rows];
    let mut d = vec![0f32; rows];
    let mut c0 = vec![f32::INFINITY; cols]; // c(s) for s = lo + c
    for c in (0..cols).rev() {
        let j = lo + c;
        let t = &target[j * LANE_FLOATS..(j + 1) * LANE_FLOATS];
        for (i, di) in d.iter_mut().enumerate() {
            *di = prep.d(i, t);
        }
        for i in (0..rows).rev() {
            if i == rows - 1 && c == cols - 1 {
                h[i] = 0.0;
                continue;
            }
            let mut best = f32::INFINITY;
            let mut s = 0u8;
            if i + 1 < rows {
                let v = h[i + 1] + d[i + 1];
                if v < best {
                    best = v;
                    s = 1;
                }
                if c + 1 < cols {
                    let v = h_next[i + 1] + 2.0 * d_next[i + 1];
                    if v < best {
                        best = v;
                        s = 2;
                    }
                }
            }
            if i > 0 && c + 1 < cols {
                let v = h_next[i] + d_next[i];
                if v < best {
                    best = v;
                    s = 3;
                }
            }
            h[i] = best;
            step[i * cols + c] = s;
        }
        c0[c] = d[0] + h[0];
        std::mem::swap(&mut h, &mut h_next);
        std::mem::swap(&mut d, &mut d_next);
    }
    let latest = cand.start;
    let mut best = (f32::INFINITY, f32::INFINITY, end);
    for c in (0..cols).rev() {
        let span = cols - c;
        if span < prep.min_span || span > prep.max_span || lo + c > latest || !c0[c].is_finite() {
            continue;
        }
        let score = c0[c] / (rows + span) as f32;
        if score < best.0 {
            best = (score, c0[c], lo + c);
        }
    }
    let (score, cost, start) = best;
    if !score.is_finite() {
        return None;
    }
    let (mut i, mut c) = (0usize, start - lo);
    let mut path = vec![[0u32, start as u32]];
    while !(i == rows - 1 && c == cols - 1) {
        match step[i * cols + c] {
            1 => i += 1,
            2 => {
                i += 1;
                c += 1;
            }
            3 => c += 1,
            _ => unreachable!("every cell with a finite cost has a next step"),
        }
        path.push([i as u32, (lo + c) as u32]);
    }
    Some(Refined { clip, start, end, cost, score, path })
}
