//! The plain subsequence DP of spec §C: every cell of every clip, two columns of memory. It is
//! the reference the fast search is tested against and the benchmark's baseline.

use std::ops::ControlFlow;

use super::features::{FeatureIndex, FRAME_FLOATS};
use super::results::{finish, select, Candidate, SearchOutcome, SearchStats};
use super::{frame_distance, Prepared, SearchError, SearchProgress};

/// Columns between progress reports.
pub(crate) const PROGRESS_COLUMNS: usize = 8192;

pub(crate) fn run(
    index: &FeatureIndex,
    prep: &Prepared,
    progress: &mut dyn FnMut(SearchProgress) -> ControlFlow<()>,
) -> Result<SearchOutcome, SearchError> {
    let total = index.total_frames();
    let mut done = 0usize;
    let mut pool = Vec::new();
    let rows = prep.query_frames;
    let mut prev_g = vec![0f32; rows];
    let mut prev_s = vec![0usize; rows];
    let mut cur_g = vec![0f32; rows];
    let mut cur_s = vec![0usize; rows];
    let mut stats = SearchStats { frames_searched: total, cells_total: (total as u64) * rows as u64, ..Default::default() };
    for (ci, clip) in index.clips.iter().enumerate() {
        let target = &clip.features(prep.origin).data;
        let cols = target.len() / FRAME_FLOATS;
        if cols < prep.min_span {
            done += cols;
            continue;
        }
        for j in 0..cols {
            if j % PROGRESS_COLUMNS == 0 {
                let p = SearchProgress { frames_done: done + j, frames_total: total, candidates: pool.len() };
                if progress(p).is_break() {
                    return Err(SearchError::Cancelled { frames_done: done + j, frames_total: total });
                }
            }
            let t = &target[j * FRAME_FLOATS..(j + 1) * FRAME_FLOATS];
            cur_g[0] = frame_distance(prep.q(0), t, &prep.joints);
            cur_s[0] = j;
            for i in 1..rows {
                let d = frame_distance(prep.q(i), t, &prep.joints);
                let mut v = cur_g[i - 1] + d;
                let mut s = cur_s[i - 1];
                if j > 0 {
                    let dg = prev_g[i - 1] + 2.0 * d;
                    if dg < v {
                        v = dg;
                        s = prev_s[i - 1];
                    }
                    let h = prev_g[i] + d;
                    if h < v {
                        v = h;
                        s = prev_s[i];
                    }
                }
                cur_g[i] = v;
                cur_s[i] = s;
            }
            stats.distances_computed += rows as u64;
            let (g, start) = (cur_g[rows - 1], cur_s[rows - 1]);
            let span = j + 1 - start;
            if span >= prep.min_span && span <= prep.max_span {
                let score = g / (rows + span) as f32;
                if score <= prep.threshold {
                    pool.push(Candidate { clip: ci, start, end: j, score, cost: g });
                }
            }
            std::mem::swap(&mut prev_g, &mut cur_g);
            std::mem::swap(&mut prev_s, &mut cur_s);
        }
        done += cols;
    }
    let selected = select(&mut pool, prep.max_results);
    Ok(finish(index, prep, &selected, stats))
}
