//! The plain subsequence DP of spec §C: every cell of every clip, two columns of memory. It is
//! the reference the fast search is tested against and the benchmark's baseline.

use std::ops::ControlFlow;

use super::features::FeatureIndex;
use super::results::{finish, refine, select_matches, Candidate, Refined, SearchOutcome, SearchStats};
use super::{Prepared, SearchError, SearchProgress, LANE_FLOATS};

/// Columns between progress reports.
pub(crate) const PROGRESS_COLUMNS: usize = 8192;

pub(crate) fn run(
    index: &FeatureIndex,
    prep: &Prepared,
    progress: &mut dyn FnMut(SearchProgress) -> ControlFlow<()>,
) -> Result<SearchOutcome, SearchError> {
    let (selected, stats) = selection(index, prep, progress)?;
    Ok(finish(index, selected, stats))
}

/// The plain DP's answer before it is dressed as an outcome: every candidate, then the
/// selection (each taken candidate's start re-chosen).
pub(crate) fn selection(
    index: &FeatureIndex,
    prep: &Prepared,
    progress: &mut dyn FnMut(SearchProgress) -> ControlFlow<()>,
) -> Result<(Vec<Refined>, SearchStats), SearchError> {
    let (mut pool, stats) = candidates(index, prep, progress)?;
    let selected = select_matches(&mut pool, prep.max_results, &mut |c| refine(index, prep, c));
    Ok((selected, stats))
}

/// Every candidate end of every clip (admissible span, distance within the threshold): all
/// cells computed.
pub(crate) fn candidates(
    index: &FeatureIndex,
    prep: &Prepared,
    progress: &mut dyn FnMut(SearchProgress) -> ControlFlow<()>,
) -> Result<(Vec<Candidate>, SearchStats), SearchError> {
    let total = index.total_frames();
    let mut done = 0usize;
    let mut pool = Vec::new();
    let rows = prep.query_frames;
    let mut cols_state = Columns::new(rows);
    let mut stats = SearchStats { frames_searched: total, cells_total: (total as u64) * rows as u64, ..Default::default() };
    for (ci, clip) in index.clips.iter().enumerate() {
        let target = clip.lanes(prep.origin);
        let cols = target.len() / LANE_FLOATS;
        if cols < prep.min_span {
            done += cols;
            continue;
        }
        for c0 in (0..cols).step_by(PROGRESS_COLUMNS) {
            let p = SearchProgress { frames_done: done + c0, frames_total: total, candidates: pool.len() };
            if progress(p).is_break() {
                return Err(SearchError::Cancelled { frames_done: done + c0, frames_total: total });
            }
            let c1 = (c0 + PROGRESS_COLUMNS).min(cols);
            columns(prep, target, ci, c0..c1, c0 > 0, &mut cols_state, &mut pool);
            stats.distances_computed += ((c1 - c0) * rows) as u64;
        }
        done += cols;
    }
    Ok((pool, stats))
}

/// Two DP columns (value and start pointer per query frame).
pub(crate) struct Columns {
    prev_g: Vec<f32>,
    prev_s: Vec<usize>,
    cur_g: Vec<f32>,
    cur_s: Vec<usize>,
}

impl Columns {
    pub(crate) fn new(rows: usize) -> Columns {
        Columns { prev_g: vec![0.0; rows], prev_s: vec![0; rows], cur_g: vec![0.0; rows], cur_s: vec![0; rows] }
    }

    /// Fills the current column `j` by the spec §C recurrence (weights 1/2/1, start pointer
    /// carried along the chosen predecessor; ties keep the vertical, then the diagonal step).
    /// Without `has_prev`, `j` is a first column: only vertical steps.
    #[inline]
    fn column(&mut self, prep: &Prepared, target: &[f32], j: usize, has_prev: bool) {
        let t = &target[j * LANE_FLOATS..(j + 1) * LANE_FLOATS];
        self.cur_g[0] = prep.d(0, t);
        self.cur_s[0] = j;
        for i in 1..prep.query_frames {
            let d = prep.d(i, t);
            let mut v = self.cur_g[i - 1] + d;
            let mut s = self.cur_s[i - 1];
            if has_prev {
                let dg = self.prev_g[i - 1] + 2.0 * d;
                if dg < v {
                    v = dg;
                    s = self.prev_s[i - 1];
                }
                let h = self.prev_g[i] + d;
                if h < v {
                    v = h;
                    s = self.prev_s[i];
                }
            }
            self.cur_g[i] = v;
            self.cur_s[i] = s;
        }
    }
}

/// The plain DP over target columns `range` of clip `clip`, pushing every candidate end with an
/// admissible span and a distance within the threshold. With `resume` the previous column is
/// the one left in `st` (the columns just before `range`); without it `range.start` is treated
/// as the clip's first column.
pub(crate) fn columns(
    prep: &Prepared,
    target: &[f32],
    clip: usize,
    range: std::ops::Range<usize>,
    resume: bool,
    st: &mut Columns,
    pool: &mut Vec<Candidate>,
) {
    let rows = prep.query_frames;
    let first = range.start;
    for j in range {
        st.column(prep, target, j, resume || j > first);
        let (g, start) = (st.cur_g[rows - 1], st.cur_s[rows - 1]);
        let span = j + 1 - start;
        if span >= prep.min_span && span <= prep.max_span {
            let score = g / (rows + span) as f32;
            if score <= prep.threshold {
                pool.push(Candidate { clip, start, end: j, score, cost: g });
            }
        }
        std::mem::swap(&mut st.prev_g, &mut st.cur_g);
        std::mem::swap(&mut st.prev_s, &mut st.cur_s);
    }
}

/// The plain DP run fresh from column `from` through `end` (inclusive): the value and start
/// pointer of the last query frame's cell at `end`. Cells whose full-scan path starts at or
/// after `from` get exactly the full scan's values (same operations in the same order).
pub(crate) fn end_cell(prep: &Prepared, target: &[f32], from: usize, end: usize, st: &mut Columns) -> (f32, usize) {
    let rows = prep.query_frames;
    for j in from..=end {
        st.column(prep, target, j, j > from);
        std::mem::swap(&mut st.prev_g, &mut st.cur_g);
        std::mem::swap(&mut st.prev_s, &mut st.cur_s);
    }
    (st.prev_g[rows - 1], st.prev_s[rows - 1])
}
