//! The dance's commands as pure functions over plain values, for the one dance document, the
//! project ([`crate::project::Project`], spec §K), which keeps each bar's state, search and the
//! settings by stable move keys and records every edit in its one history. Here a dance is
//! read by segment numbers of a [`SegmentLibrary`]: the project resolves its keys, calls these,
//! and keeps the result by keys again. Nothing here holds state or history of its own.
//!
//! [`open_search`] (a bar's first round of candidates), [`next_round`] (like some of the shown
//! candidates, next round, τ ← τ·19/20), [`generate_states`] (fill every bar not pinned by the
//! pipeline of [`super::generate`]), [`render_states`] (the whole dance as one clip),
//! [`bar_views`] (what the timeline shows) and [`Settings::apply`] (one checked setting).

use serde::{Deserialize, Serialize};
use thiserror::Error;

use super::feedback::{FeedbackSession, CANDIDATES_PER_ROUND};
use super::fill::{FillError, FillWeights, Layer};
use super::generate::{self, bar_counts, GenerateOptions};
use super::render::{render, RenderOptions};
use super::segment::SegmentLibrary;
use crate::bars::Bar;
use crate::clip::Clip;

/// What a bar holds, by segment number of the library it was resolved in.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "camelCase")]
pub enum BarState {
    #[default]
    Empty,
    /// Chosen by the person: generation never changes it.
    Pinned { segment: usize },
    /// Chosen by the engine: the next Generate may change it.
    Generated { segment: usize },
}

impl BarState {
    pub fn segment(&self) -> Option<usize> {
        match *self {
            BarState::Empty => None,
            BarState::Pinned { segment } | BarState::Generated { segment } => Some(segment),
        }
    }
}

/// Knobs of the search and the filling: the dance's settings, saved with the project. One
/// struct, so a new setting is a field here (with its default) and a [`Setting`] variant.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "camelCase", default)]
pub struct Settings {
    /// ρ of eq. 1: weight of music relevance against diversity/preference (0..=1).
    pub rho: f32,
    pub fill: FillWeights,
    /// Candidates per round.
    pub candidates_per_round: usize,
}

impl Default for Settings {
    fn default() -> Self {
        Self { rho: 0.3, fill: FillWeights::default(), candidates_per_round: CANDIDATES_PER_ROUND }
    }
}

/// One setting a person changes, with its value.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Setting {
    /// ρ of eq. 1, in 0..=1 (applies to the next round).
    Rho(f32),
    /// Weight of the music term of the filling ([`FillWeights::music_weight`]), in 0..=100.
    MusicWeight(f32),
    /// Weight of the beat term of the filling ([`FillWeights::beat_weight`]), in 0..=100.
    BeatWeight(f32),
    /// The filling's preference for the person's imported moves
    /// ([`FillWeights::own_moves_preference`]), in 0..=100.
    OwnMovesPreference(f32),
    /// Repetition penalty of the filling ([`FillWeights::repeat_penalty`]), in 0..=100.
    RepeatPenalty(f32),
    /// Bars within which a repeated segment is penalised ([`FillWeights::repeat_window`]), in
    /// 1..=32.
    RepeatWindow(usize),
    /// Which moves Generate fills the open bars with ([`super::MovesSource`]: the person's own
    /// first, mixed, or built-in only).
    MovesSource(super::MovesSource),
}

impl Settings {
    /// Sets one setting; refused with its name, range and value when out of range (the
    /// settings are then unchanged).
    pub fn apply(&mut self, setting: Setting) -> Result<(), ChoreoError> {
        let check = |name: &str, range: std::ops::RangeInclusive<f32>, value: f32| {
            if range.contains(&value) {
                Ok(value)
            } else {
                Err(ChoreoError::BadSetting { name: name.into(), range: format!("{}..={}", range.start(), range.end()), value })
            }
        };
        match setting {
            Setting::Rho(v) => self.rho = check("rho", 0.0..=1.0, v)?,
            Setting::MusicWeight(v) => self.fill.music_weight = check("musicWeight", 0.0..=100.0, v)?,
            Setting::BeatWeight(v) => self.fill.beat_weight = check("beatWeight", 0.0..=100.0, v)?,
            Setting::OwnMovesPreference(v) => self.fill.own_moves_preference = check("ownMovesPreference", 0.0..=100.0, v)?,
            Setting::RepeatPenalty(v) => self.fill.repeat_penalty = check("repeatPenalty", 0.0..=100.0, v)?,
            Setting::MovesSource(source) => self.fill.moves_source = source,
            Setting::RepeatWindow(n) => {
                if !(1..=32).contains(&n) {
                    return Err(ChoreoError::BadSetting { name: "repeatWindow".into(), range: "1..=32".into(), value: n as f32 });
                }
                self.fill.repeat_window = n;
            }
        }
        Ok(())
    }
}

/// Why a command was refused.
#[derive(Debug, Error, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "camelCase")]
pub enum ChoreoError {
    #[error("the song has no complete bar: a choreography needs at least one bar")]
    NoBars,
    #[error("bar {index} runs from {start_secs} s to {end_secs} s: bars must have positive length and come in order")]
    BadBar { index: usize, start_secs: f32, end_secs: f32 },
    #[error("bar {index} has intensity {intensity}: intensity must be a number from 0 to 1")]
    BadBarIntensity { index: usize, intensity: f32 },
    #[error("there is no bar {bar}: the song has {bars} bars")]
    NoSuchBar { bar: usize, bars: usize },
    #[error("there is no segment {segment}: the library has {segments}")]
    NoSuchSegment { segment: usize, segments: usize },
    #[error("segment {segment} was not among bar {bar}'s current candidates")]
    NotACandidate { bar: usize, segment: usize },
    #[error("bar {bar} has no search open: ask for its candidates first")]
    NoSearch { bar: usize },
    #[error("the segment library is empty: add the built-in moves or a humanoid clip first")]
    EmptyLibrary,
    #[error("{name} must be in {range}, got {value}")]
    BadSetting { name: String, range: String, value: f32 },
    #[error(transparent)]
    Fill(#[from] FillError),
}

/// Everything the timeline shows about one bar.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "camelCase")]
pub struct BarView {
    pub bar: Bar,
    pub state: BarState,
    /// τ of the bar's search (1 when none is open).
    pub tau: f32,
    /// The current round's candidates (empty when no search is open).
    pub candidates: Vec<usize>,
    pub liked: Vec<usize>,
    pub shown_count: usize,
    pub rounds: usize,
}

/// What a Generate did.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "camelCase")]
pub struct GenerateReport {
    /// Bars the engine filled.
    pub filled: usize,
    /// Bars kept because they are pinned.
    pub pinned: usize,
    /// Cost of the chosen path (transitions + music + repetition).
    pub cost: f32,
    /// Per bar, why it holds a built-in move under *my moves* (issue 26's preference order,
    /// [`super::generate::BuiltinWhy`]); `None` elsewhere. Empty when nothing was filled.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub builtin_why: Vec<Option<super::generate::BuiltinWhy>>,
}

/// Bars must exist, have positive length, come in order and have an intensity in 0..=1.
pub fn check_bars(bars: &[Bar]) -> Result<(), ChoreoError> {
    if bars.is_empty() {
        return Err(ChoreoError::NoBars);
    }
    let mut prev_end = f32::MIN;
    for b in bars {
        if !(b.end_secs > b.start_secs && b.start_secs.is_finite() && b.end_secs.is_finite() && b.start_secs >= prev_end - 1e-3) {
            return Err(ChoreoError::BadBar { index: b.index, start_secs: b.start_secs, end_secs: b.end_secs });
        }
        // Intensity is a fraction of the song's loudness range: anything else is not a bar the
        // analysis made, and would skew the filling's music term without a word.
        if !(0.0..=1.0).contains(&b.intensity) {
            return Err(ChoreoError::BadBarIntensity { index: b.index, intensity: b.intensity });
        }
        prev_end = b.end_secs;
    }
    Ok(())
}

/// `Ok` when bar `bar` is one of `bars`.
pub fn check_bar(bars: &[Bar], bar: usize) -> Result<&Bar, ChoreoError> {
    bars.get(bar).ok_or(ChoreoError::NoSuchBar { bar, bars: bars.len() })
}

/// The counts a bar's candidates must have ([`bar_counts`]; `None`: any).
fn counts_of_bar(lib: &SegmentLibrary, bar: &Bar) -> Option<usize> {
    bar_counts(lib, std::slice::from_ref(bar)).first().copied().filter(|&n| n != 0)
}

/// A fresh search on `bar` (τ = 1) with its first round shown (`session.round`). Deterministic:
/// the same library, bar and settings open the same round.
pub fn open_search(lib: &SegmentLibrary, bar: &Bar, settings: &Settings) -> Result<FeedbackSession, ChoreoError> {
    if lib.is_empty() {
        return Err(ChoreoError::EmptyLibrary);
    }
    let mut s = FeedbackSession::new();
    s.counts = counts_of_bar(lib, bar);
    s.next_round(lib, bar.intensity, settings.rho, settings.candidates_per_round);
    Ok(s)
}

/// Search: the `liked` candidates (from the session's current round) join the bar's liked set,
/// τ is multiplied by 19/20 and a new round of unseen candidates is returned. Refused, with the
/// session unchanged, when a liked segment was not in the round.
pub fn next_round(lib: &SegmentLibrary, bar: &Bar, session: &mut FeedbackSession, liked: &[usize], settings: &Settings) -> Result<Vec<usize>, ChoreoError> {
    if let Some(&bad) = liked.iter().find(|l| !session.round.contains(l)) {
        return Err(ChoreoError::NotACandidate { bar: bar.index, segment: bad });
    }
    session.counts = counts_of_bar(lib, bar);
    Ok(session.search(lib, liked, bar.intensity, settings.rho, settings.candidates_per_round).to_vec())
}

/// Generate: the states after filling every bar of `states` that is not pinned by the pipeline
/// of [`super::generate`] with `options`, and what it did. Pinned bars never change; with every
/// bar pinned the states come back as they were. Refused when an option is out of range, the
/// library is empty or a pinned segment is not in it.
pub fn generate_states(lib: &SegmentLibrary, bars: &[Bar], states: &[BarState], weights: FillWeights, options: &GenerateOptions) -> Result<(Vec<BarState>, GenerateReport), ChoreoError> {
    generate_states_with_repeats(lib, bars, states, weights, options, &[]).map(|(s, r, _)| (s, r))
}

/// [`generate_states`] where the song's sections repeat (issue 26): `repeat_of[i]` is the earlier
/// bar bar `i` repeats (`music::Sections::repeat_of_bars`; empty: none). An open bar repeating
/// an open bar takes the same move ([`super::generate::generate_with_repeats`]). Also returns, per
/// bar, the bar whose move it repeats (what the bar's note says, [`super::notes::mark_repeats`]).
pub fn generate_states_with_repeats(lib: &SegmentLibrary, bars: &[Bar], states: &[BarState], weights: FillWeights, options: &GenerateOptions, repeat_of: &[Option<usize>]) -> Result<(Vec<BarState>, GenerateReport, Vec<Option<usize>>), ChoreoError> {
    options.validate()?;
    check_bars(bars)?;
    if lib.is_empty() {
        return Err(ChoreoError::EmptyLibrary);
    }
    let state = |i: usize| states.get(i).copied().unwrap_or_default();
    for i in 0..bars.len() {
        if let BarState::Pinned { segment } = state(i) {
            if segment >= lib.len() {
                return Err(ChoreoError::NoSuchSegment { segment, segments: lib.len() });
            }
        }
    }
    let current: Vec<BarState> = (0..bars.len()).map(state).collect();
    let pinned = current.iter().filter(|s| matches!(s, BarState::Pinned { .. })).count();
    if pinned == bars.len() {
        return Ok((current, GenerateReport { filled: 0, pinned, cost: 0.0, builtin_why: Vec::new() }, vec![None; bars.len()]));
    }
    let layers: Vec<Layer> = bars
        .iter()
        .zip(&current)
        .map(|(b, s)| match *s {
            BarState::Pinned { segment } => Layer::Fixed { segment },
            _ => Layer::Open { intensity: b.intensity },
        })
        .collect();
    let (path, cost, repeats, builtin_why) = generate::generate_with_repeats_explained(lib, bars, &layers, weights, options, repeat_of)?;
    let out = current.iter().zip(path).map(|(s, seg)| if matches!(s, BarState::Pinned { .. }) { *s } else { BarState::Generated { segment: seg } }).collect();
    Ok((out, GenerateReport { filled: bars.len() - pinned, pinned, cost, builtin_why }, repeats))
}

/// The dance of `states` over `bars` as one canonical clip; frame 0 is song time 0. A bar that
/// is empty, or whose segment is not in the library, stands neutral.
pub fn render_states(lib: &SegmentLibrary, bars: &[Bar], states: &[BarState], options: &RenderOptions) -> Clip {
    let choices: Vec<Option<usize>> = (0..bars.len()).map(|i| states.get(i).and_then(BarState::segment).filter(|&s| s < lib.len())).collect();
    render(lib, bars, &choices, options)
}

/// What the timeline shows, one entry per bar (a bar with no state given is empty, one with no
/// session has no search open).
pub fn bar_views(bars: &[Bar], states: &[BarState], sessions: &[Option<FeedbackSession>]) -> Vec<BarView> {
    bars.iter()
        .enumerate()
        .map(|(i, bar)| {
            let session = sessions.get(i).and_then(Option::as_ref);
            BarView {
                bar: *bar,
                state: states.get(i).copied().unwrap_or_default(),
                tau: session.map_or(1.0, |s| s.tau),
                candidates: session.map_or_else(Vec::new, |s| s.round.clone()),
                liked: session.map_or_else(Vec::new, |s| s.liked.clone()),
                shown_count: session.map_or(0, |s| s.shown.len()),
                rounds: session.map_or(0, |s| s.rounds),
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::choreo::generate::dance_figures;
    use crate::choreo::quality::JOIN_JUMP_GOAL;
    use crate::choreo::grid::bars_from_tempo;
    use crate::choreo::segment::LIBRARY_FPS;
    use crate::canon::humanoid::CANON_COUNT;

    fn generated(lib: &SegmentLibrary, bars: &[Bar]) -> Vec<BarState> {
        generate_states(lib, bars, &[], FillWeights::default(), &GenerateOptions::default()).unwrap().0
    }

    fn segments(states: &[BarState]) -> Vec<usize> {
        states.iter().map(|s| s.segment().unwrap()).collect()
    }

    #[test]
    fn a_bar_in_three_takes_a_three_count_segment_whose_counts_land_on_its_beats() {
        let lib = crate::choreo::segment::tests::small_library_with_an_imported_clip();
        // Four bars in 3 at 120 BPM: 1.5 s each, a beat every 0.5 s (30 frames at 60 fps).
        let bars = bars_from_tempo(6.0, 120.0, 3, 0.0, |_, _| 0.5).unwrap();
        assert!(bars.iter().all(|b| b.beats == 3));
        let states = generated(&lib, &bars);
        let chosen = segments(&states);
        assert!(chosen.iter().all(|&s| lib.segments()[s].counts() == 3), "{chosen:?}");
        // The search of a bar in 3 shows only 3-count moves.
        let round = open_search(&lib, &bars[1], &Settings::default()).unwrap().round;
        assert!(!round.is_empty() && round.iter().all(|&s| lib.segments()[s].counts() == 3), "{round:?}");
        // Count k of each bar's segment plays on the bar's k-th beat: the rendered pose there is
        // the clip's at that count (joints below the root; the root is placed and turned).
        let fps = 60.0;
        let clip = render_states(&lib, &bars, &states, &RenderOptions { fps, hold_feet: false, ..RenderOptions::default() });
        let (mut rot, mut trans) = (Vec::new(), Vec::new());
        for (b, &s) in bars.iter().zip(&chosen) {
            let seg = &lib.segments()[s];
            let source = &lib.clips()[seg.clip].clip;
            for k in 1..3 {
                let f = ((b.start_secs + b.duration_secs() * k as f32 / 3.0) * fps).round() as usize;
                source.sample_into(seg.count_frames[k] / LIBRARY_FPS, &mut rot, &mut trans);
                for j in 1..CANON_COUNT {
                    let (a, e) = (clip.rotations[f * CANON_COUNT + j], rot[j]);
                    assert!(a.dot(e).abs() > 0.9999, "bar {} beat {k} joint {j}: {a:?} vs {e:?}", b.index);
                }
            }
        }
        // The same song in bars of 4 beats (2 s): Generate fills them with 4-count moves, and
        // their search shows 4-count moves.
        let in_four = bars_from_tempo(6.0, 120.0, 4, 0.0, |_, _| 0.5).unwrap();
        let states = generated(&lib, &in_four);
        assert!(segments(&states).iter().all(|&s| lib.segments()[s].counts() == 4), "{states:?}");
        let round = open_search(&lib, &in_four[0], &Settings::default()).unwrap().round;
        assert!(round.iter().all(|&s| lib.segments()[s].counts() == 4), "{round:?}");
    }

    #[test]
    fn the_join_repair_leaves_a_dance_with_smooth_joins_as_it_was() {
        let lib = SegmentLibrary::builtin();
        let bars = bars_from_tempo(17.0, 120.0, 4, 0.0, |a, _| (a / 17.0).clamp(0.0, 1.0)).unwrap();
        let on = generated(&lib, &bars);
        let f = dance_figures(&lib, &bars, &segments(&on)).unwrap();
        assert!(f.join_jump_max <= JOIN_JUMP_GOAL, "{f:?}");
        assert!(f.worst_join_bar.is_some_and(|b| (1..bars.len()).contains(&b)), "{f:?}");
        let (off, _) = generate_states(&lib, &bars, &[], FillWeights::default(), &GenerateOptions { follow_joins: false, ..GenerateOptions::default() }).unwrap();
        assert_eq!(on, off);
    }

    #[test]
    fn bars_in_three_with_no_three_count_move_take_any_move() {
        // A library of moves in 4 only (the built-in moves in 4, which come first): a waltz
        // still gets a dance (counts spread evenly). The whole built-in library has moves in 3.
        let mut lib = SegmentLibrary::new();
        lib.load_builtin(&mut crate::choreo::segment::BuiltinLoader::new(), crate::library::MOVES_IN_FOUR);
        assert!(lib.segments().iter().all(|s| s.counts() == 4));
        let bars = bars_from_tempo(6.0, 120.0, 3, 0.0, |_, _| 0.5).unwrap();
        assert_eq!(bar_counts(&lib, &bars), vec![0; bars.len()]);
        assert_eq!(bar_counts(&SegmentLibrary::builtin(), &bars), vec![3; bars.len()]);
        assert!(generated(&lib, &bars).iter().all(|s| s.segment().is_some()));
    }

    #[test]
    fn pinned_bars_keep_their_segment_and_all_pinned_changes_nothing() {
        let lib = SegmentLibrary::builtin();
        let bars = bars_from_tempo(8.5, 120.0, 4, 0.25, |_, _| 0.5).unwrap();
        let mut states = vec![BarState::Empty; bars.len()];
        states[1] = BarState::Pinned { segment: 7 };
        let (out, report) = generate_states(&lib, &bars, &states, FillWeights::default(), &GenerateOptions::default()).unwrap();
        assert_eq!(out[1], BarState::Pinned { segment: 7 });
        assert_eq!((report.filled, report.pinned), (bars.len() - 1, 1));
        let all: Vec<BarState> = (0..bars.len()).map(|i| BarState::Pinned { segment: i }).collect();
        let (same, report) = generate_states(&lib, &bars, &all, FillWeights::default(), &GenerateOptions::default()).unwrap();
        assert_eq!((same, report.filled), (all, 0));
        states[2] = BarState::Pinned { segment: lib.len() };
        assert!(matches!(generate_states(&lib, &bars, &states, FillWeights::default(), &GenerateOptions::default()), Err(ChoreoError::NoSuchSegment { .. })));
    }

    #[test]
    fn a_setting_out_of_range_is_refused_by_name_and_changes_nothing() {
        let mut s = Settings::default();
        s.apply(Setting::Rho(0.8)).unwrap();
        s.apply(Setting::RepeatWindow(6)).unwrap();
        assert_eq!((s.rho, s.fill.repeat_window), (0.8, 6));
        let before = s;
        for bad in [Setting::Rho(1.5), Setting::MusicWeight(-1.0), Setting::BeatWeight(f32::NAN), Setting::OwnMovesPreference(101.0), Setting::RepeatPenalty(1e9), Setting::RepeatWindow(0)] {
            let e = s.apply(bad).unwrap_err();
            assert!(matches!(e, ChoreoError::BadSetting { .. }), "{bad:?}: {e:?}");
            assert_eq!(s, before);
        }
        assert_eq!(Settings::default().apply(Setting::Rho(2.0)).unwrap_err().to_string(), "rho must be in 0..=1, got 2");
    }

    #[test]
    fn bars_saved_before_they_kept_their_beats_have_four() {
        let b: Bar = serde_json::from_str(r#"{"index":0,"startSecs":0.0,"endSecs":2.0,"intensity":0.5}"#).unwrap();
        assert_eq!((b.beats, b.beat_count()), (4, 4));
    }

    #[test]
    fn views_and_settings_are_camel_case_json() {
        let lib = SegmentLibrary::builtin();
        let bars = bars_from_tempo(8.5, 120.0, 4, 0.25, |_, _| 0.5).unwrap();
        let session = open_search(&lib, &bars[1], &Settings::default()).unwrap();
        let mut states = vec![BarState::Empty; bars.len()];
        states[1] = BarState::Pinned { segment: session.round[0] };
        let (states, _) = generate_states(&lib, &bars, &states, FillWeights::default(), &GenerateOptions::default()).unwrap();
        let mut sessions = vec![None; bars.len()];
        sessions[1] = Some(session);
        let view = serde_json::to_value(bar_views(&bars, &states, &sessions)).unwrap();
        assert_eq!(view[1]["state"]["kind"], "pinned");
        assert_eq!(view[0]["state"]["kind"], "generated");
        assert!(view[1]["bar"]["startSecs"].is_number());
        assert!(view[1]["shownCount"].is_number());
        let seg = serde_json::to_value(&lib.segments()[0]).unwrap();
        assert!(seg["intensity01"].is_number() && seg["startFrame"].is_number() && seg["tempoBpm"].is_number());
        let settings = serde_json::to_value(Settings::default()).unwrap();
        assert!(settings["fill"]["repeatWindow"].is_number());
    }
}
