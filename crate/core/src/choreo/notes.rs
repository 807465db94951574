//! What a bar's move is and where it is weak, in words (issue 26 item 5): the move's name and
//! source (built-in, or the imported clip it was cut from) and the flags the app's §J readouts
//! raise on it: off the beat, a join jump over the goal, foot skate beyond its source's. The
//! Dance strip shows them on every bar, and the relevance-feedback candidates carry them too
//! (measured in place, as the bar would play them once Set), so no candidate the app would flag
//! is shown without saying so; [`candidate_notes`] ranks clean candidates first.
//!
//! The rules are the strip's: a bar is off the beat when its BAS-music is not at least 0.10
//! above the same bar scored on half-shifted beats (§J's control), its join is rough when its
//! join jump passes [`JOIN_JUMP_GOAL`], and it skates when its feet slide faster than its source
//! clip's do played at the bar's pace (§N: skate is a speed).

use serde::{Deserialize, Serialize};
use thiserror::Error;

use super::quality::{dance_quality_switched, BarQuality, QualityError, JOIN_JUMP_GOAL};
use super::render::{render_switched, RenderOptions};
use super::segment::SegmentLibrary;
use crate::bars::Bar;

/// Margin of BAS-music over the half-shifted control below which a bar is off the beat.
pub const OFF_BEAT_MARGIN: f32 = 0.10;

/// A bar's foot skate is flagged only when it is visibly more than its source's at the bar's
/// pace: more by [`SKATE_FLAG_MARGIN_CM_PER_S`] and by [`SKATE_FLAG_RATIO`] (a flag reading
/// "foot skate 1 cm/s (its source 1 cm/s)" or "33 cm/s (its source 33)" named no weakness a
/// person can see; the tolerance is retargeting's, spec §L's check: the source's + 1 cm/s).
pub const SKATE_FLAG_MARGIN_CM_PER_S: f32 = 1.0;
/// See [`SKATE_FLAG_MARGIN_CM_PER_S`]: 10 % over the source's, the figures' own spread from bar
/// to bar of one clip being of that order.
pub const SKATE_FLAG_RATIO: f32 = 1.1;

/// Whether a bar sliding `skate` cm/s, its source `paced` cm/s at the bar's pace, is flagged.
pub fn skate_flagged(skate: f32, paced: f32) -> bool {
    skate.is_finite() && paced.is_finite() && skate > paced + SKATE_FLAG_MARGIN_CM_PER_S && skate > paced * SKATE_FLAG_RATIO
}

/// Why notes could not be made.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum NotesError {
    #[error("bar {bar} is out of range: the dance has {bars} bars")]
    NoSuchBar { bar: usize, bars: usize },
    #[error("there is no segment {segment} in the library (it has {segments})")]
    NoSuchSegment { segment: usize, segments: usize },
    #[error("{choices} moves given for {bars} bars")]
    ChoicesMismatch { choices: usize, bars: usize },
    #[error("the dance cannot be measured: {0}")]
    Quality(#[from] QualityError),
}

/// What a flag is about.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "camelCase")]
pub enum FlagKind {
    OffBeat,
    JoinJump,
    FootSkate,
}

/// One weak spot of a bar, in words, with the figure and the goal it missed.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "camelCase")]
pub struct Flag {
    pub kind: FlagKind,
    /// For the person, e.g. "foot skate 47 cm/s (its source 12 cm/s)".
    pub words: String,
    pub value: f32,
    pub goal: f32,
}

/// A bar's move and its flags.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "camelCase")]
pub struct MoveNote {
    pub bar: usize,
    /// The segment, or `None` for an empty bar.
    pub segment: Option<usize>,
    /// The move's name ("" for an empty bar).
    pub name: String,
    /// "built-in", or the imported clip's name.
    pub source: String,
    pub builtin: bool,
    pub flags: Vec<Flag>,
    /// The bar (0-based) whose move this bar repeats because its section repeats that bar's
    /// (issue 26; [`mark_repeats`]); absent otherwise.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub repeats_bar: Option<usize>,
    /// The repeat was marked by the person on the song strip (`project::Project::mark_repeat`),
    /// not found by the analysis; absent when false.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub repeat_marked: bool,
    /// Why the bar holds a built-in move though the person's moves come first (issue 26's
    /// preference order: "built-in: no move of yours tried here lands on the beat"), from the
    /// Generate that chose it ([`mark_builtin_why`]); absent otherwise.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub builtin_why: Option<String>,
}

impl MoveNote {
    /// The flags as one line ("" when clean), after "repeats bar N" (N counted from 1, as the
    /// strip numbers bars) when the bar repeats another's move.
    pub fn words(&self) -> String {
        let why = if self.repeat_marked { "marked" } else { "its section repeats" };
        let repeat = self.repeats_bar.map(|r| format!("repeats bar {} ({why})", r + 1));
        repeat.iter().map(String::as_str).chain(self.builtin_why.iter().map(String::as_str)).chain(self.flags.iter().map(|f| f.words.as_str())).collect::<Vec<_>>().join("; ")
    }
}

/// Says on the notes of built-in bars why they are built-in (`why[i]`: bar `i`'s move when
/// Generate chose it, and why, from [`super::GenerateReport::builtin_why`]): only where the bar
/// still holds that move (a bar the person changed since says nothing).
pub fn mark_builtin_why(notes: &mut [MoveNote], why: &[Option<(usize, super::generate::BuiltinWhy)>]) {
    for (i, note) in notes.iter_mut().enumerate() {
        note.builtin_why = why.get(i).copied().flatten().filter(|&(s, _)| note.builtin && note.segment == Some(s)).map(|(_, w)| w.words());
    }
}

/// Marks the notes of bars that repeat another bar's move because their section repeats
/// (`repeats[i]`: the bar bar `i` repeats, from Generate,
/// [`super::document::generate_states_with_repeats`]): only where the bar still holds the same
/// move as the bar it repeats (a bar the person changed since no longer repeats it).
pub fn mark_repeats(notes: &mut [MoveNote], repeats: &[Option<usize>]) {
    let segments: Vec<Option<usize>> = notes.iter().map(|n| n.segment).collect();
    for (i, note) in notes.iter_mut().enumerate() {
        note.repeats_bar = repeats.get(i).copied().flatten().filter(|&r| r < i && segments.get(r).copied().flatten().is_some_and(|s| note.segment == Some(s)));
    }
}

/// The note of bar `bar` holding `segment`, from its readout `q` (of the dance it plays in).
fn note_of(lib: &SegmentLibrary, bars: &[Bar], bar: usize, segment: Option<usize>, q: Option<&BarQuality>) -> MoveNote {
    let seg = segment.and_then(|s| lib.segment(s));
    let (name, source, builtin) = match seg {
        Some(s) if s.builtin.is_some() => (s.name.clone(), "built-in".to_string(), true),
        Some(s) => (s.name.clone(), lib.clips().get(s.clip).map_or_else(|| s.source.clone(), |c| c.clip.name.clone()), false),
        None => (String::new(), String::new(), false),
    };
    let mut flags = Vec::new();
    if let (Some(s), Some(q)) = (seg, q) {
        let margin = q.beats.bas_music - q.beats.bas_music_shifted;
        if margin < OFF_BEAT_MARGIN {
            flags.push(Flag {
                kind: FlagKind::OffBeat,
                words: format!("off the beat (beat alignment {:.2}, half a beat off {:.2})", q.beats.bas_music, q.beats.bas_music_shifted),
                value: margin,
                goal: OFF_BEAT_MARGIN,
            });
        }
        if let Some(j) = q.join_jump.filter(|&j| j > JOIN_JUMP_GOAL) {
            flags.push(Flag { kind: FlagKind::JoinJump, words: format!("join jump {j:.2} (goal ≤ {JOIN_JUMP_GOAL})"), value: j, goal: JOIN_JUMP_GOAL });
        }
        // The source clip's skate at the bar's pace (§N).
        let paced = s.clip_skate_at(super::count_rate_bpm(s.counts(), bars.get(bar).map_or(1.0, Bar::duration_secs)));
        let skate = q.foot_skate.mean_cm_per_s;
        if skate_flagged(skate, paced) {
            flags.push(Flag { kind: FlagKind::FootSkate, words: format!("foot skate {skate:.0} cm/s (its source {paced:.0} cm/s)"), value: skate, goal: paced });
        }
    }
    MoveNote { bar, segment, name, source, builtin, flags, repeats_bar: None, repeat_marked: false, builtin_why: None }
}

/// Every bar's note, from the dance's readout `quality` (`dance_quality_switched` of the
/// rendered dance of `choices` on `bars`, its joins measured where they fall).
pub fn bar_notes(lib: &SegmentLibrary, bars: &[Bar], choices: &[Option<usize>], quality: &[BarQuality]) -> Vec<MoveNote> {
    (0..bars.len()).map(|i| note_of(lib, bars, i, choices.get(i).copied().flatten(), quality.get(i))).collect()
}

/// The notes of `candidates` for bar `bar` of the dance `choices` on `bars`: each measured as the
/// bar would play once Set (the bar and its neighbours rendered with the candidate in place,
/// feet held as the app renders them), its flags those of the bar and of the join into the next
/// bar. Returned clean first, then by fewer flags; among equals in the given order (the
/// search's, by relevance).
pub fn candidate_notes(lib: &SegmentLibrary, bars: &[Bar], choices: &[Option<usize>], beats_secs: &[f32], bar: usize, candidates: &[usize]) -> Result<Vec<MoveNote>, NotesError> {
    if bar >= bars.len() {
        return Err(NotesError::NoSuchBar { bar, bars: bars.len() });
    }
    if choices.len() != bars.len() {
        return Err(NotesError::ChoicesMismatch { choices: choices.len(), bars: bars.len() });
    }
    if let Some(&bad) = candidates.iter().find(|&&c| c >= lib.len()) {
        return Err(NotesError::NoSuchSegment { segment: bad, segments: lib.len() });
    }
    // The window: the bar before (its end leads in), the bar, the bar after (the join out).
    let (a, b) = (bar.saturating_sub(1), (bar + 2).min(bars.len()));
    let shift = bars[a].start_secs;
    let window: Vec<Bar> = bars[a..b]
        .iter()
        .enumerate()
        .map(|(i, x)| Bar { index: i, start_secs: x.start_secs - shift, end_secs: x.end_secs - shift, ..x.clone() })
        .collect();
    let end = window.last().map_or(0.0, |x| x.end_secs);
    let beats: Vec<f32> = beats_secs.iter().map(|t| t - shift).filter(|&t| (-1e-3..=end + 1e-3).contains(&t)).collect();
    let beats = if beats.len() >= 2 {
        beats
    } else {
        window.iter().flat_map(|x| (0..x.beat_count()).map(move |k| x.start_secs + x.duration_secs() * k as f32 / x.beat_count() as f32)).collect()
    };
    let at = bar - a;
    let mut notes = Vec::with_capacity(candidates.len());
    for &c in candidates {
        let mut ch: Vec<Option<usize>> = choices[a..b].to_vec();
        ch[at] = Some(c);
        let (clip, switches) = render_switched(lib, &window, &ch, &RenderOptions::default());
        let q = dance_quality_switched(&clip, &window, &beats, &switches)?;
        let mut note = note_of(lib, &window, at, Some(c), q.bars.get(at));
        note.bar = bar;
        // The join into the next bar, when it holds a move.
        if let (Some(next), Some(Some(_))) = (q.bars.get(at + 1), ch.get(at + 1)) {
            if let Some(j) = next.join_jump.filter(|&j| j > JOIN_JUMP_GOAL) {
                note.flags.push(Flag { kind: FlagKind::JoinJump, words: format!("join jump {j:.2} into the next bar (goal ≤ {JOIN_JUMP_GOAL})"), value: j, goal: JOIN_JUMP_GOAL });
            }
        }
        notes.push(note);
    }
    // Stable: among equals, the search's order.
    notes.sort_by_key(|n| n.flags.len());
    Ok(notes)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::choreo::bars_from_tempo;

    #[test]
    fn foot_skate_is_flagged_only_when_visibly_over_its_source() {
        // Within the display's rounding or the bar-to-bar spread: no flag.
        assert!(!skate_flagged(1.3, 0.9));
        assert!(!skate_flagged(0.4, 0.0) && !skate_flagged(36.0, 33.0) && !skate_flagged(33.4, 33.0));
        // Visibly more: flagged.
        assert!(skate_flagged(13.0, 5.0) && skate_flagged(41.0, 37.0) && skate_flagged(2.5, 0.0));
        // No figure, no flag.
        assert!(!skate_flagged(f32::NAN, 1.0) && !skate_flagged(5.0, f32::NAN));
    }

    #[test]
    fn notes_name_every_move_and_rank_clean_candidates_first() {
        let lib = SegmentLibrary::builtin();
        let bars = bars_from_tempo(16.0, 120.0, 4, 0.0, |_, _| 0.5).unwrap();
        let choices: Vec<Option<usize>> = (0..bars.len()).map(|i| Some((i * 37) % 420)).collect();
        let beats: Vec<f32> = (0..40).map(|k| k as f32 * 0.5).collect();
        let (clip, switches) = render_switched(&lib, &bars, &choices, &RenderOptions::default());
        let q = dance_quality_switched(&clip, &bars, &beats, &switches).unwrap();
        let notes = bar_notes(&lib, &bars, &choices, &q.bars);
        assert_eq!(notes.len(), bars.len());
        for (n, c) in notes.iter().zip(&choices) {
            assert_eq!(n.name, lib.segments()[c.unwrap()].name);
            assert_eq!(n.source, "built-in");
            // Each flag agrees with the readout it words.
            let bq = &q.bars[n.bar];
            assert_eq!(n.flags.iter().any(|f| f.kind == FlagKind::OffBeat), bq.beats.bas_music - bq.beats.bas_music_shifted < OFF_BEAT_MARGIN);
            assert_eq!(n.flags.iter().any(|f| f.kind == FlagKind::JoinJump), bq.join_jump.is_some_and(|j| j > JOIN_JUMP_GOAL));
            let s = &lib.segments()[c.unwrap()];
            let paced = s.clip_skate_at(crate::choreo::count_rate_bpm(s.counts(), bars[n.bar].duration_secs()));
            assert_eq!(n.flags.iter().any(|f| f.kind == FlagKind::FootSkate), skate_flagged(bq.foot_skate.mean_cm_per_s, paced));
        }
        // Candidates: ranked by flags, the search's order kept among equals.
        let candidates: Vec<usize> = (0..12).map(|i| i * 31 % 420).collect();
        let cn = candidate_notes(&lib, &bars, &choices, &beats, 3, &candidates).unwrap();
        assert_eq!(cn.len(), candidates.len());
        assert!(cn.windows(2).all(|w| w[0].flags.len() <= w[1].flags.len()));
        for w in cn.windows(2).filter(|w| w[0].flags.len() == w[1].flags.len()) {
            let pos = |s: Option<usize>| candidates.iter().position(|&c| Some(c) == s).unwrap();
            assert!(pos(w[0].segment) < pos(w[1].segment));
        }
        // A candidate measured in place is the bar as the dance would play it once Set.
        let c = cn[0].segment.unwrap();
        let mut set = choices.clone();
        set[3] = Some(c);
        let (clip, switches) = render_switched(&lib, &bars, &set, &RenderOptions::default());
        let whole = dance_quality_switched(&clip, &bars, &beats, &switches).unwrap();
        let bq = &whole.bars[3];
        assert_eq!(cn[0].flags.iter().any(|f| f.kind == FlagKind::OffBeat), bq.beats.bas_music - bq.beats.bas_music_shifted < OFF_BEAT_MARGIN, "{:?} vs {:?}", cn[0], bq.beats);
        // Bad input: typed errors.
        assert_eq!(candidate_notes(&lib, &bars, &choices, &beats, 99, &candidates), Err(NotesError::NoSuchBar { bar: 99, bars: bars.len() }));
        assert!(matches!(candidate_notes(&lib, &bars, &choices, &beats, 3, &[100_000]), Err(NotesError::NoSuchSegment { .. })));
        assert!(matches!(candidate_notes(&lib, &bars, &choices[..2], &beats, 1, &candidates), Err(NotesError::ChoicesMismatch { .. })));
    }
}
