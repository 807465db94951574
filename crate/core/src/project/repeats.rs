//! Repeats the person marks by hand (issue 26 item 2): a range of bars that repeats an earlier
//! range of the same length, or a repeat the analysis found that the person removes. The marks
//! are kept in the dance ([`super::DanceDoc::repeats`], `.odori` schema 5) in the order made and
//! laid over the song's found repeats ([`resolve`]): a later mark wins over an earlier one and
//! over the analysis. Generate gives a repeated bar its first occurrence's move, so a chain (C
//! repeats B, which repeats A) resolves to A.
//!
//! Why ranges and not sections: the analysis can miss or misplace a boundary, and a person
//! hears a repeat by bars; a range is what the song strip lets them choose.

use serde::{Deserialize, Serialize};
use thiserror::Error;

/// A range of bars of the song (0-based first bar, bar count).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "camelCase")]
pub struct BarRange {
    pub first_bar: usize,
    pub bars: usize,
}

impl BarRange {
    /// One past the last bar (saturating: a range from the page is never trusted).
    pub fn end_bar(&self) -> usize {
        self.first_bar.saturating_add(self.bars)
    }
}

/// One mark the person made: bars `first_bar .. first_bar + bars` repeat the bars from
/// `of_bar` (`Some`), or are no repeat whatever the analysis found (`None`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "camelCase")]
pub struct RepeatMark {
    pub first_bar: usize,
    pub bars: usize,
    pub of_bar: Option<usize>,
}

impl RepeatMark {
    fn range(&self) -> BarRange {
        BarRange { first_bar: self.first_bar, bars: self.bars }
    }
}

/// What one bar repeats: the bar (0-based) whose move it takes, and whether the person marked it.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "camelCase")]
pub struct BarRepeat {
    pub of_bar: usize,
    pub marked: bool,
}

/// A run of consecutive repeated bars (what the song strip draws and offers to remove): bars
/// `first_bar .. first_bar + bars` repeat bars `of_bar .. of_bar + bars`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "camelCase")]
pub struct RepeatRun {
    pub first_bar: usize,
    pub bars: usize,
    pub of_bar: usize,
    pub marked: bool,
}

/// Why a repeat was refused; bars are counted from 0, as the API gives them.
#[derive(Debug, Error, Clone, PartialEq, Eq)]
pub enum RepeatError {
    #[error("a repeat needs at least one bar: bars {first_bar}..{end_bar} repeating bars {of_first_bar}..{of_end_bar}")]
    Empty { first_bar: usize, end_bar: usize, of_first_bar: usize, of_end_bar: usize },
    #[error("bars {first_bar}..{end_bar} are out of the song: it has {song_bars} bars")]
    OutOfSong { first_bar: usize, end_bar: usize, song_bars: usize },
    #[error("a repeat has the length of what it repeats: {bars} bars from bar {first_bar} against {of_bars} from bar {of_first_bar}")]
    UnequalLength { first_bar: usize, bars: usize, of_first_bar: usize, of_bars: usize },
    #[error("bars {first_bar}..{end_bar} cannot repeat bars {of_first_bar}..{of_end_bar}: the ranges overlap")]
    Overlapping { first_bar: usize, end_bar: usize, of_first_bar: usize, of_end_bar: usize },
    #[error("bars {first_bar}..{end_bar} cannot repeat the later bars {of_first_bar}..{of_end_bar}: a repeat follows what it repeats")]
    NotEarlier { first_bar: usize, end_bar: usize, of_first_bar: usize, of_end_bar: usize },
    #[error("bar {bar} repeats no other bar (the song has {song_bars} bars)")]
    NotARepeat { bar: usize, song_bars: usize },
}

impl RepeatError {
    /// A short machine-readable kind, stable for the JS API.
    pub fn kind(&self) -> &'static str {
        match self {
            RepeatError::NotARepeat { .. } => "not-found",
            _ => "bad-repeat",
        }
    }
}

/// Checks that `range` may be marked as repeating `of` in a song of `song_bars` bars.
pub fn check(range: BarRange, of: BarRange, song_bars: usize) -> Result<(), RepeatError> {
    let (first_bar, end_bar, of_first_bar, of_end_bar) = (range.first_bar, range.end_bar(), of.first_bar, of.end_bar());
    if range.bars == 0 || of.bars == 0 {
        return Err(RepeatError::Empty { first_bar, end_bar, of_first_bar, of_end_bar });
    }
    for r in [range, of] {
        if r.end_bar() > song_bars {
            return Err(RepeatError::OutOfSong { first_bar: r.first_bar, end_bar: r.end_bar(), song_bars });
        }
    }
    if range.bars != of.bars {
        return Err(RepeatError::UnequalLength { first_bar, bars: range.bars, of_first_bar, of_bars: of.bars });
    }
    if first_bar < of_end_bar && of_first_bar < end_bar {
        return Err(RepeatError::Overlapping { first_bar, end_bar, of_first_bar, of_end_bar });
    }
    if of_first_bar > first_bar {
        return Err(RepeatError::NotEarlier { first_bar, end_bar, of_first_bar, of_end_bar });
    }
    Ok(())
}

/// Each of `song_bars` bars' repeat: the analysis's `found` (per bar, the earlier bar it
/// repeats) with `marks` laid over it in order, chains resolved to the first occurrence. A mark
/// reaching past the song (after a grid correction) counts only inside it; a mark that would
/// point a bar at itself or a later bar (a file not written by this build) is skipped.
pub fn resolve(found: &[Option<usize>], marks: &[RepeatMark], song_bars: usize) -> Vec<Option<BarRepeat>> {
    let mut out: Vec<Option<BarRepeat>> = (0..song_bars).map(|t| found.get(t).copied().flatten().filter(|&r| r < t).map(|of_bar| BarRepeat { of_bar, marked: false })).collect();
    for m in marks {
        if let Some(of) = m.of_bar {
            if check(m.range(), BarRange { first_bar: of, bars: m.bars }, usize::MAX).is_err() {
                continue;
            }
        }
        for i in 0..m.bars {
            let Some(slot) = m.first_bar.checked_add(i).and_then(|t| out.get_mut(t)) else { break };
            *slot = m.of_bar.map(|of| BarRepeat { of_bar: of + i, marked: true });
        }
    }
    for t in 0..out.len() {
        if let Some(r) = out[t] {
            if let Some(Some(root)) = out.get(r.of_bar).copied() {
                out[t] = Some(BarRepeat { of_bar: root.of_bar, marked: r.marked });
            }
        }
    }
    out
}

/// The runs of consecutive bars of `repeats` ([`resolve`]) that repeat consecutive bars, marked
/// and found apart.
pub fn runs(repeats: &[Option<BarRepeat>]) -> Vec<RepeatRun> {
    let mut out: Vec<RepeatRun> = Vec::new();
    for (t, r) in repeats.iter().enumerate() {
        let Some(r) = r else { continue };
        match out.last_mut() {
            Some(run) if run.first_bar + run.bars == t && run.of_bar + run.bars == r.of_bar && run.marked == r.marked => run.bars += 1,
            _ => out.push(RepeatRun { first_bar: t, bars: 1, of_bar: r.of_bar, marked: r.marked }),
        }
    }
    out
}

/// `marks` with `range` marked as repeating `of` (checked against `song_bars`): earlier marks
/// inside the range are dropped (the new one covers them).
pub fn with_mark(marks: &[RepeatMark], range: BarRange, of: BarRange, song_bars: usize) -> Result<Vec<RepeatMark>, RepeatError> {
    check(range, of, song_bars)?;
    let mut out: Vec<RepeatMark> = marks.iter().copied().filter(|m| !inside(m.range(), range)).collect();
    out.push(RepeatMark { first_bar: range.first_bar, bars: range.bars, of_bar: Some(of.first_bar) });
    Ok(out)
}

/// `marks` with the repeat holding bar `bar` removed (its whole run, [`runs`]): marks inside the
/// run are dropped, and where the analysis still finds a repeat there, a mark says it is none.
/// Returns the run removed too.
pub fn without_repeat(found: &[Option<usize>], marks: &[RepeatMark], bar: usize, song_bars: usize) -> Result<(Vec<RepeatMark>, RepeatRun), RepeatError> {
    let now = resolve(found, marks, song_bars);
    let run = runs(&now).into_iter().find(|r| r.first_bar <= bar && bar < r.first_bar + r.bars).ok_or(RepeatError::NotARepeat { bar, song_bars })?;
    let range = BarRange { first_bar: run.first_bar, bars: run.bars };
    let mut out: Vec<RepeatMark> = marks.iter().copied().filter(|m| !inside(m.range(), range)).collect();
    let left = resolve(found, &out, song_bars);
    if left[run.first_bar..run.first_bar + run.bars].iter().any(Option::is_some) {
        out.push(RepeatMark { first_bar: run.first_bar, bars: run.bars, of_bar: None });
    }
    Ok((out, run))
}

/// The bars' notes say which bar's move they repeat ([`crate::choreo::mark_repeats`]) and
/// whether the person marked that repeat (the readout's "= bar N (marked)").
pub fn mark_notes(notes: &mut [crate::choreo::MoveNote], repeats: &[Option<BarRepeat>]) {
    crate::choreo::mark_repeats(notes, &repeats.iter().map(|r| r.map(|r| r.of_bar)).collect::<Vec<_>>());
    for (n, r) in notes.iter_mut().zip(repeats) {
        n.repeat_marked = n.repeats_bar.is_some() && r.is_some_and(|r| r.marked);
    }
}

fn inside(a: BarRange, b: BarRange) -> bool {
    b.first_bar <= a.first_bar && a.end_bar() <= b.end_bar()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn range(first_bar: usize, bars: usize) -> BarRange {
        BarRange { first_bar, bars }
    }

    #[test]
    fn a_bad_range_is_a_typed_error_naming_it() {
        assert!(matches!(check(range(8, 4), range(0, 4), 16), Ok(())));
        assert!(matches!(check(range(8, 0), range(0, 0), 16), Err(RepeatError::Empty { .. })));
        assert_eq!(check(range(14, 4), range(0, 4), 16), Err(RepeatError::OutOfSong { first_bar: 14, end_bar: 18, song_bars: 16 }));
        assert!(matches!(check(range(usize::MAX, 4), range(0, 4), 16), Err(RepeatError::OutOfSong { .. })));
        assert_eq!(check(range(8, 4), range(0, 3), 16), Err(RepeatError::UnequalLength { first_bar: 8, bars: 4, of_first_bar: 0, of_bars: 3 }));
        assert!(matches!(check(range(4, 4), range(2, 4), 16), Err(RepeatError::Overlapping { .. })));
        assert!(matches!(check(range(0, 4), range(8, 4), 16), Err(RepeatError::NotEarlier { .. })));
        // Adjacent ranges do not overlap.
        assert!(check(range(4, 4), range(0, 4), 16).is_ok());
        assert!(RepeatError::NotARepeat { bar: 1, song_bars: 2 }.to_string().contains("bar 1"));
    }

    #[test]
    fn marks_lie_over_the_found_repeats_in_order_and_chains_resolve() {
        // Found: bars 8..12 repeat 0..4.
        let found: Vec<Option<usize>> = (0..16).map(|t| (8..12).contains(&t).then(|| t - 8)).collect();
        // Marked: 12..16 repeat 8..12, which repeats 0..4: resolved to 0..4, marked.
        let marks = with_mark(&[], range(12, 4), range(8, 4), 16).unwrap();
        let r = resolve(&found, &marks, 16);
        assert_eq!(r[8], Some(BarRepeat { of_bar: 0, marked: false }));
        assert_eq!(r[13], Some(BarRepeat { of_bar: 1, marked: true }));
        assert_eq!(runs(&r), vec![RepeatRun { first_bar: 8, bars: 4, of_bar: 0, marked: false }, RepeatRun { first_bar: 12, bars: 4, of_bar: 0, marked: true }]);
        // Removing the found one leaves a mark saying "none" there; the marked chain now ends at 8.
        let (marks, run) = without_repeat(&found, &marks, 9, 16).unwrap();
        assert_eq!(run, RepeatRun { first_bar: 8, bars: 4, of_bar: 0, marked: false });
        assert_eq!(marks.last(), Some(&RepeatMark { first_bar: 8, bars: 4, of_bar: None }));
        let r = resolve(&found, &marks, 16);
        assert!(r[..12].iter().all(Option::is_none));
        assert_eq!(r[12], Some(BarRepeat { of_bar: 8, marked: true }));
        // Removing a marked repeat drops its mark; no "none" mark is needed where nothing is found.
        let (marks, _) = without_repeat(&found, &marks, 15, 16).unwrap();
        assert_eq!(marks, vec![RepeatMark { first_bar: 8, bars: 4, of_bar: None }]);
        assert_eq!(without_repeat(&found, &marks, 15, 16), Err(RepeatError::NotARepeat { bar: 15, song_bars: 16 }));
        // Without the analysis's repeat (control), the marked range alone repeats.
        let marks = with_mark(&[], range(12, 4), range(8, 4), 16).unwrap();
        assert_eq!(resolve(&[], &marks, 16)[12], Some(BarRepeat { of_bar: 8, marked: true }));
    }

    #[test]
    fn marks_past_the_song_or_pointing_forward_are_harmless() {
        // A grid correction left 10 bars: the mark counts inside the song only.
        let marks = [RepeatMark { first_bar: 8, bars: 4, of_bar: Some(0) }];
        let r = resolve(&[], &marks, 10);
        assert_eq!(r.len(), 10);
        assert_eq!(r[9], Some(BarRepeat { of_bar: 1, marked: true }));
        // A hand-edited file: a forward or self-overlapping mark is skipped, never a panic.
        let bad = [RepeatMark { first_bar: 0, bars: 4, of_bar: Some(2) }, RepeatMark { first_bar: usize::MAX, bars: usize::MAX, of_bar: Some(0) }];
        assert!(resolve(&[], &bad, 8).iter().all(Option::is_none));
        // Found repeats pointing forward are ignored too.
        assert!(resolve(&[Some(3), None, None, None], &[], 4).iter().all(Option::is_none));
    }
}
