//! The editable choreography: the song's bars, each empty, pinned to a segment by the person or
//! filled by the engine, each with its own relevance-feedback session, and every edit
//! undoable. The web layer keeps no state of its own: it calls a command, then reads
//! [`Choreography::view`] (and [`Choreography::render`] to play).
//!
//! Commands: [`Choreography::candidates`] (open a bar's search: first round), [`search`]
//! (like some of the shown candidates, next round, τ ← τ·19/20), [`reset_search`], [`set`]
//! (pin a segment), [`unpin`], [`clear`], [`generate`] (fill every bar not pinned), settings
//! ([`set_rho`], [`set_music_weight`], [`set_repeat_penalty`], [`set_repeat_window`]), [`undo`]
//! and [`redo`]. Every
//! command that changes the document records the previous state for undo and clears redo.
//! Looking is not an edit: opening a bar's first round of candidates records nothing (it is
//! deterministic, so it opens the same again after an undo), nor does a grid that did not change.
//!
//! [`search`]: Choreography::search
//! [`reset_search`]: Choreography::reset_search
//! [`set`]: Choreography::set
//! [`unpin`]: Choreography::unpin
//! [`clear`]: Choreography::clear
//! [`generate`]: Choreography::generate
//! [`set_bars`]: Choreography::set_bars
//! [`set_rho`]: Choreography::set_rho
//! [`set_music_weight`]: Choreography::set_music_weight
//! [`set_repeat_penalty`]: Choreography::set_repeat_penalty
//! [`set_repeat_window`]: Choreography::set_repeat_window
//! [`undo`]: Choreography::undo
//! [`redo`]: Choreography::redo

use crate::history::History;
use std::collections::BTreeSet;

use serde::{Deserialize, Serialize};
use thiserror::Error;

use super::feedback::{FeedbackSession, CANDIDATES_PER_ROUND};
use super::fill::{FillError, FillWeights, Layer};
use super::generate::{self, bar_counts, GenerateOptions};
use super::render::{render, RenderOptions};
use super::segment::{ClipSummary, SegmentError, SegmentLibrary, SegmentOptions};
use super::table::TableScope;
use crate::bars::Bar;
use crate::clip::Clip;

/// Most undo steps kept.
pub const UNDO_LIMIT: usize = 500;

/// What a bar holds.
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

/// Knobs of the search and the filling.
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

#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "camelCase")]
struct Doc {
    bars: Vec<Bar>,
    states: Vec<BarState>,
    sessions: Vec<Option<FeedbackSession>>,
    settings: Settings,
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
}

/// What re-cutting a clip meant for the dance (see [`recut_clip`]).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "camelCase")]
pub struct RecutReport {
    /// The new cut.
    pub clip: ClipSummary,
    /// Segments of the earlier cut removed from the library.
    pub removed: usize,
    /// Segments of the earlier cut kept because the dance (or its undo history) uses them.
    pub kept: usize,
    /// Bars pinned to a segment of the earlier cut: they keep that motion.
    pub pinned_bars: Vec<usize>,
    /// Bars the engine filled with a segment of the earlier cut: they keep it until the next
    /// Generate, which fills them from the new cut.
    pub generated_bars: Vec<usize>,
}

/// Re-cuts library clip `clip` into 4-count segments with new options (a tempo the person
/// states for it, or `tempo_bpm: None` to detect its beats again) without losing anything of
/// the dance: segments of the earlier cut that any bar holds — now or anywhere in the undo and
/// redo history — or that a bar's search liked stay in the library as retired (they play as
/// before but are never offered or chosen again), the rest go, and the document's segment
/// numbers follow the library's. On error nothing changes.
pub fn recut_clip(lib: &mut SegmentLibrary, doc: Option<&mut Choreography>, clip: usize, options: &SegmentOptions) -> Result<RecutReport, SegmentError> {
    let in_use = doc.as_ref().map(|d| d.segments_in_use()).unwrap_or_default();
    let recut = lib.recut_clip(clip, options, &|i| in_use.contains(&i))?;
    let (mut pinned_bars, mut generated_bars) = (Vec::new(), Vec::new());
    if let Some(doc) = doc {
        doc.remap_segments(&recut.remap);
        for (bar, state) in doc.states().iter().enumerate() {
            match *state {
                BarState::Pinned { segment } if recut.kept.contains(&segment) => pinned_bars.push(bar),
                BarState::Generated { segment } if recut.kept.contains(&segment) => generated_bars.push(bar),
                _ => {}
            }
        }
    }
    Ok(RecutReport { clip: recut.summary, removed: recut.removed, kept: recut.kept.len(), pinned_bars, generated_bars })
}

/// Bars must exist, have positive length and come in order.
fn check_bars(bars: &[Bar]) -> Result<(), ChoreoError> {
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

/// A dance being composed to a song.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "camelCase")]
pub struct Choreography {
    doc: Doc,
    #[serde(flatten)]
    history: History<Doc>,
}

impl Choreography {
    /// A choreography with every bar empty. Refuses a song without a bar, and bars out of
    /// order or of non-positive length.
    pub fn new(bars: Vec<Bar>) -> Result<Self, ChoreoError> {
        check_bars(&bars)?;
        let n = bars.len();
        Ok(Self { doc: Doc { bars, states: vec![BarState::Empty; n], sessions: vec![None; n], settings: Settings::default() }, history: History::default() })
    }

    /// A choreography in a given state, with no undo history: how a document that keeps its
    /// own history (the project, spec §K) hands its dance to the commands here. Bars are
    /// checked as in [`Choreography::new`]; states and sessions are padded or cut to the bars.
    pub fn from_parts(bars: Vec<Bar>, mut states: Vec<BarState>, mut sessions: Vec<Option<FeedbackSession>>, settings: Settings) -> Result<Self, ChoreoError> {
        check_bars(&bars)?;
        let n = bars.len();
        states.resize(n, BarState::Empty);
        sessions.resize(n, None);
        Ok(Self { doc: Doc { bars, states, sessions, settings }, history: History::default() })
    }

    /// Every bar's feedback session (`None`: no search open).
    pub fn sessions(&self) -> &[Option<FeedbackSession>] {
        &self.doc.sessions
    }

    /// Replaces the bar grid (after the person corrects the tempo or the first downbeat): bar
    /// `i` keeps its state and search when it still exists; new bars start empty. Undoable.
    pub fn set_bars(&mut self, bars: Vec<Bar>) -> Result<(), ChoreoError> {
        check_bars(&bars)?;
        if bars == self.doc.bars {
            return Ok(());
        }
        self.record();
        let n = bars.len();
        // A bar whose metre changed forgets its search: what it showed and liked were moves of
        // the old count (undo brings it back). Its move stays until the next Generate (a pinned
        // one stays: what the person chose is never dropped; it plays its counts evenly).
        for (i, b) in bars.iter().enumerate() {
            if self.doc.bars.get(i).is_some_and(|old| old.beat_count() != b.beat_count()) {
                if let Some(s) = self.doc.sessions.get_mut(i) {
                    *s = None;
                }
            }
        }
        self.doc.bars = bars;
        self.doc.states.resize(n, BarState::Empty);
        self.doc.sessions.resize(n, None);
        Ok(())
    }

    pub fn bars(&self) -> &[Bar] {
        &self.doc.bars
    }

    pub fn settings(&self) -> &Settings {
        &self.doc.settings
    }

    /// Each bar's state.
    pub fn states(&self) -> &[BarState] {
        &self.doc.states
    }

    /// The segment in each bar, if any.
    pub fn segments(&self) -> Vec<Option<usize>> {
        self.doc.states.iter().map(BarState::segment).collect()
    }

    /// Every segment the document refers to, now or in its undo/redo history: the bars'
    /// segments and the candidates a search liked.
    pub fn segments_in_use(&self) -> BTreeSet<usize> {
        let mut out = BTreeSet::new();
        for d in std::iter::once(&self.doc).chain(&self.history.undo).chain(&self.history.redo) {
            out.extend(d.states.iter().filter_map(BarState::segment));
            out.extend(d.sessions.iter().flatten().flat_map(|s| s.liked.iter().copied()));
        }
        out
    }

    /// Renumbers segments after the library dropped some (`remap[old]` = new index, `None`:
    /// gone), in the document and its whole undo/redo history. A bar whose segment is gone
    /// becomes empty (it cannot happen after [`recut_clip`], which keeps every segment in
    /// use); searches forget shown candidates that are gone. Not an edit: nothing is recorded.
    pub fn remap_segments(&mut self, remap: &[Option<usize>]) {
        let map = |s: usize| remap.get(s).copied().flatten();
        let map_list = |v: &mut Vec<usize>| *v = v.iter().filter_map(|&s| map(s)).collect();
        for d in std::iter::once(&mut self.doc).chain(self.history.undo.iter_mut()).chain(self.history.redo.iter_mut()) {
            for st in d.states.iter_mut() {
                *st = match *st {
                    BarState::Empty => BarState::Empty,
                    BarState::Pinned { segment } => map(segment).map_or(BarState::Empty, |segment| BarState::Pinned { segment }),
                    BarState::Generated { segment } => map(segment).map_or(BarState::Empty, |segment| BarState::Generated { segment }),
                };
            }
            for s in d.sessions.iter_mut().flatten() {
                map_list(&mut s.shown);
                map_list(&mut s.liked);
                map_list(&mut s.round);
            }
        }
    }

    /// The bar's feedback session, if one is open.
    pub fn session(&self, bar: usize) -> Option<&FeedbackSession> {
        self.doc.sessions.get(bar).and_then(|s| s.as_ref())
    }

    /// What the timeline shows, one entry per bar.
    pub fn view(&self) -> Vec<BarView> {
        self.doc
            .bars
            .iter()
            .zip(&self.doc.states)
            .zip(&self.doc.sessions)
            .map(|((bar, state), session)| BarView {
                bar: *bar,
                state: *state,
                tau: session.as_ref().map_or(1.0, |s| s.tau),
                candidates: session.as_ref().map_or_else(Vec::new, |s| s.round.clone()),
                liked: session.as_ref().map_or_else(Vec::new, |s| s.liked.clone()),
                shown_count: session.as_ref().map_or(0, |s| s.shown.len()),
                rounds: session.as_ref().map_or(0, |s| s.rounds),
            })
            .collect()
    }

    /// The counts bar `bar`'s candidates must have ([`bar_counts`]; `None`: any).
    fn counts_of_bar(&self, lib: &SegmentLibrary, bar: usize) -> Option<usize> {
        self.doc.bars.get(bar).and_then(|b| bar_counts(lib, std::slice::from_ref(b)).first().copied()).filter(|&n| n != 0)
    }

    fn check_bar(&self, bar: usize) -> Result<(), ChoreoError> {
        if bar < self.doc.bars.len() {
            Ok(())
        } else {
            Err(ChoreoError::NoSuchBar { bar, bars: self.doc.bars.len() })
        }
    }

    fn check_segment(lib: &SegmentLibrary, segment: usize) -> Result<(), ChoreoError> {
        if segment < lib.len() {
            Ok(())
        } else {
            Err(ChoreoError::NoSuchSegment { segment, segments: lib.len() })
        }
    }

    fn record(&mut self) {
        self.history.record(self.doc.clone(), UNDO_LIMIT);
    }

    /// The bar's current candidates, opening its search (first round, τ = 1) when none is
    /// open. Opening is not an edit (no undo step: a person who only looked at a bar expects
    /// Undo to take back their last edit); asking again returns the same round.
    pub fn candidates(&mut self, lib: &SegmentLibrary, bar: usize) -> Result<Vec<usize>, ChoreoError> {
        self.check_bar(bar)?;
        if lib.is_empty() {
            return Err(ChoreoError::EmptyLibrary);
        }
        if let Some(s) = &self.doc.sessions[bar] {
            return Ok(s.round.clone());
        }
        let (intensity, rho, count) = (self.doc.bars[bar].intensity, self.doc.settings.rho, self.doc.settings.candidates_per_round);
        let mut s = FeedbackSession::new();
        s.counts = self.counts_of_bar(lib, bar);
        let round = s.next_round(lib, intensity, rho, count).to_vec();
        self.doc.sessions[bar] = Some(s);
        Ok(round)
    }

    /// Search: the `liked` candidates (from the current round) join the bar's liked set, τ is
    /// multiplied by 19/20 and a new round of unseen candidates is returned.
    pub fn search(&mut self, lib: &SegmentLibrary, bar: usize, liked: &[usize]) -> Result<Vec<usize>, ChoreoError> {
        self.check_bar(bar)?;
        let Some(session) = &self.doc.sessions[bar] else {
            return Err(ChoreoError::NoSearch { bar });
        };
        if let Some(&bad) = liked.iter().find(|l| !session.round.contains(l)) {
            return Err(ChoreoError::NotACandidate { bar, segment: bad });
        }
        self.record();
        let (intensity, rho, count) = (self.doc.bars[bar].intensity, self.doc.settings.rho, self.doc.settings.candidates_per_round);
        let counts = self.counts_of_bar(lib, bar);
        let Some(session) = self.doc.sessions[bar].as_mut() else {
            return Err(ChoreoError::NoSearch { bar });
        };
        session.counts = counts;
        Ok(session.search(lib, liked, intensity, rho, count).to_vec())
    }

    /// Forgets the bar's search (τ back to 1, nothing shown or liked). Returns whether there
    /// was one.
    pub fn reset_search(&mut self, bar: usize) -> Result<bool, ChoreoError> {
        self.check_bar(bar)?;
        if self.doc.sessions[bar].is_none() {
            return Ok(false);
        }
        self.record();
        self.doc.sessions[bar] = None;
        Ok(true)
    }

    /// Set: pins `segment` to the bar.
    pub fn set(&mut self, lib: &SegmentLibrary, bar: usize, segment: usize) -> Result<(), ChoreoError> {
        self.check_bar(bar)?;
        Self::check_segment(lib, segment)?;
        if self.doc.states[bar] == (BarState::Pinned { segment }) {
            return Ok(());
        }
        self.record();
        self.doc.states[bar] = BarState::Pinned { segment };
        Ok(())
    }

    /// Unpins a bar, keeping its segment as a generated one (the next Generate may change it).
    pub fn unpin(&mut self, bar: usize) -> Result<(), ChoreoError> {
        self.check_bar(bar)?;
        if let BarState::Pinned { segment } = self.doc.states[bar] {
            self.record();
            self.doc.states[bar] = BarState::Generated { segment };
        }
        Ok(())
    }

    /// Empties a bar.
    pub fn clear(&mut self, bar: usize) -> Result<(), ChoreoError> {
        self.check_bar(bar)?;
        if self.doc.states[bar] != BarState::Empty {
            self.record();
            self.doc.states[bar] = BarState::Empty;
        }
        Ok(())
    }

    /// ρ of eq. 1, in 0..=1 (applies to the next round).
    pub fn set_rho(&mut self, rho: f32) -> Result<(), ChoreoError> {
        if !(0.0..=1.0).contains(&rho) {
            return Err(ChoreoError::BadSetting { name: "rho".into(), range: "0..=1".into(), value: rho });
        }
        self.record();
        self.doc.settings.rho = rho;
        Ok(())
    }

    /// Weight of the music term of the filling, in 0..=100.
    pub fn set_music_weight(&mut self, w: f32) -> Result<(), ChoreoError> {
        if !(0.0..=100.0).contains(&w) {
            return Err(ChoreoError::BadSetting { name: "musicWeight".into(), range: "0..=100".into(), value: w });
        }
        self.record();
        self.doc.settings.fill.music_weight = w;
        Ok(())
    }

    /// Weight of the beat term of the filling (spec §G, [`FillWeights::beat_weight`]), in 0..=100.
    pub fn set_beat_weight(&mut self, w: f32) -> Result<(), ChoreoError> {
        if !(0.0..=100.0).contains(&w) {
            return Err(ChoreoError::BadSetting { name: "beatWeight".into(), range: "0..=100".into(), value: w });
        }
        self.record();
        self.doc.settings.fill.beat_weight = w;
        Ok(())
    }

    /// The filling's preference for the person's imported moves over built-in ones
    /// ([`FillWeights::own_moves_preference`]), in 0..=100.
    pub fn set_own_moves_preference(&mut self, w: f32) -> Result<(), ChoreoError> {
        if !(0.0..=100.0).contains(&w) {
            return Err(ChoreoError::BadSetting { name: "ownMovesPreference".into(), range: "0..=100".into(), value: w });
        }
        self.record();
        self.doc.settings.fill.own_moves_preference = w;
        Ok(())
    }

    /// Which moves Generate fills the open bars with ([`super::MovesSource`]: the person's own
    /// first, mixed, or built-in only).
    pub fn set_moves_source(&mut self, source: super::MovesSource) -> Result<(), ChoreoError> {
        self.record();
        self.doc.settings.fill.moves_source = source;
        Ok(())
    }

    /// Weight of the filling's tempo-stretch term ([`FillWeights::stretch_weight`]), in 0..=100.
    pub fn set_stretch_weight(&mut self, w: f32) -> Result<(), ChoreoError> {
        if !(0.0..=100.0).contains(&w) {
            return Err(ChoreoError::BadSetting { name: "stretchWeight".into(), range: "0..=100".into(), value: w });
        }
        self.record();
        self.doc.settings.fill.stretch_weight = w;
        Ok(())
    }

    /// Weight of the filling's foot-skate term ([`FillWeights::skate_weight`]), in 0..=100.
    pub fn set_skate_weight(&mut self, w: f32) -> Result<(), ChoreoError> {
        if !(0.0..=100.0).contains(&w) {
            return Err(ChoreoError::BadSetting { name: "skateWeight".into(), range: "0..=100".into(), value: w });
        }
        self.record();
        self.doc.settings.fill.skate_weight = w;
        Ok(())
    }

    /// Weight of the filling's beat-rate term ([`FillWeights::beat_rate_weight`]), in 0..=100.
    pub fn set_beat_rate_weight(&mut self, w: f32) -> Result<(), ChoreoError> {
        if !(0.0..=100.0).contains(&w) {
            return Err(ChoreoError::BadSetting { name: "beatRateWeight".into(), range: "0..=100".into(), value: w });
        }
        self.record();
        self.doc.settings.fill.beat_rate_weight = w;
        Ok(())
    }

    /// Repetition penalty of the filling, in 0..=100.
    pub fn set_repeat_penalty(&mut self, w: f32) -> Result<(), ChoreoError> {
        if !(0.0..=100.0).contains(&w) {
            return Err(ChoreoError::BadSetting { name: "repeatPenalty".into(), range: "0..=100".into(), value: w });
        }
        self.record();
        self.doc.settings.fill.repeat_penalty = w;
        Ok(())
    }

    /// Bars within which a repeated segment is penalised, in 1..=32.
    pub fn set_repeat_window(&mut self, bars: usize) -> Result<(), ChoreoError> {
        if !(1..=32).contains(&bars) {
            return Err(ChoreoError::BadSetting { name: "repeatWindow".into(), range: "1..=32".into(), value: bars as f32 });
        }
        self.record();
        self.doc.settings.fill.repeat_window = bars;
        Ok(())
    }

    /// The pairs of segments the filling of this song's bars reads ([`TableScope::for_bar_counts`]
    /// of [`bar_counts`]): a song in 4/4 needs the 4-count block alone; a bar in 3 brings in
    /// the (3, 3) block where two such bars follow each other, and the cross blocks where the
    /// metre changes between two bars.
    pub fn table_scope(&self, lib: &SegmentLibrary) -> TableScope {
        TableScope::for_bar_counts(&bar_counts(lib, &self.doc.bars))
    }

    /// Generate: fills every bar that is not pinned by the pipeline of [`super::generate`] at
    /// its default options. Pinned bars never change. With every bar pinned nothing changes
    /// (and nothing is recorded for undo).
    pub fn generate(&mut self, lib: &SegmentLibrary) -> Result<GenerateReport, ChoreoError> {
        self.generate_with(lib, &GenerateOptions::default())
    }

    /// [`Choreography::generate`] with the pipeline's stages set by `options` (benches and
    /// tests turn a stage off to measure what it does); refused when an option is out of range.
    pub fn generate_with(&mut self, lib: &SegmentLibrary, options: &GenerateOptions) -> Result<GenerateReport, ChoreoError> {
        options.validate()?;
        if lib.is_empty() {
            return Err(ChoreoError::EmptyLibrary);
        }
        for s in &self.doc.states {
            if let BarState::Pinned { segment } = *s {
                Self::check_segment(lib, segment)?;
            }
        }
        let pinned = self.doc.states.iter().filter(|s| matches!(s, BarState::Pinned { .. })).count();
        if pinned == self.doc.bars.len() {
            return Ok(GenerateReport { filled: 0, pinned, cost: 0.0 });
        }
        let layers: Vec<Layer> = self
            .doc
            .bars
            .iter()
            .zip(&self.doc.states)
            .map(|(b, s)| match *s {
                BarState::Pinned { segment } => Layer::Fixed { segment },
                _ => Layer::Open { intensity: b.intensity },
            })
            .collect();
        let weights = self.doc.settings.fill;
        let (path, cost) = generate::generate(lib, &self.doc.bars, &layers, weights, options)?;
        self.record();
        for (state, seg) in self.doc.states.iter_mut().zip(path) {
            if !matches!(state, BarState::Pinned { .. }) {
                *state = BarState::Generated { segment: seg };
            }
        }
        Ok(GenerateReport { filled: self.doc.bars.len() - pinned, pinned, cost })
    }

    /// Undoes the last edit; `false` when there is none.
    pub fn undo(&mut self) -> bool {
        self.history.undo(&mut self.doc)
    }

    /// Redoes the last undone edit; `false` when there is none.
    pub fn redo(&mut self) -> bool {
        self.history.redo(&mut self.doc)
    }

    pub fn can_undo(&self) -> bool {
        self.history.can_undo()
    }

    pub fn can_redo(&self) -> bool {
        self.history.can_redo()
    }

    /// The whole dance as one canonical clip; frame 0 is song time 0.
    pub fn render(&self, lib: &SegmentLibrary, options: &RenderOptions) -> Clip {
        let choices: Vec<Option<usize>> = self.doc.states.iter().map(|s| s.segment().filter(|&i| i < lib.len())).collect();
        render(lib, &self.doc.bars, &choices, options)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::choreo::generate::dance_figures;
    use crate::choreo::quality::JOIN_JUMP_GOAL;
    use crate::choreo::grid::bars_from_tempo;
    use crate::choreo::segment::LIBRARY_FPS;
    use crate::canon::humanoid::CANON_COUNT;

    #[test]
    fn a_bar_in_three_takes_a_three_count_segment_whose_counts_land_on_its_beats() {
        let lib = crate::choreo::segment::tests::small_library_with_an_imported_clip();
        // Four bars in 3 at 120 BPM: 1.5 s each, a beat every 0.5 s (30 frames at 60 fps).
        let bars = bars_from_tempo(6.0, 120.0, 3, 0.0, |_, _| 0.5).unwrap();
        assert!(bars.iter().all(|b| b.beats == 3));
        let mut doc = Choreography::new(bars.clone()).unwrap();
        doc.generate(&lib).unwrap();
        let chosen: Vec<usize> = doc.segments().into_iter().map(|s| s.unwrap()).collect();
        assert!(chosen.iter().all(|&s| lib.segments()[s].counts() == 3), "{chosen:?}");
        // The search of a bar in 3 shows only 3-count moves.
        let round = doc.candidates(&lib, 1).unwrap();
        assert!(!round.is_empty() && round.iter().all(|&s| lib.segments()[s].counts() == 3), "{round:?}");
        // Count k of each bar's segment plays on the bar's k-th beat: the rendered pose there is
        // the clip's at that count (joints below the root; the root is placed and turned).
        let fps = 60.0;
        let clip = doc.render(&lib, &RenderOptions { fps, join_frames: 5, hold_feet: false });
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
        // The person corrects the metre to 4: the same song in bars of 4 beats (2 s). The bars
        // forget their 3-count searches, and Generate fills them with 4-count moves.
        let in_four = bars_from_tempo(6.0, 120.0, 4, 0.0, |_, _| 0.5).unwrap();
        doc.set_bars(in_four).unwrap();
        assert!(doc.view()[1].candidates.is_empty());
        doc.generate(&lib).unwrap();
        assert!(doc.segments().iter().all(|s| lib.segments()[s.unwrap()].counts() == 4), "{:?}", doc.segments());
        let round = doc.candidates(&lib, 0).unwrap();
        assert!(round.iter().all(|&s| lib.segments()[s].counts() == 4), "{round:?}");
        // And back to 3 (undo brings back the bars in 3 and their search).
        doc.undo();
        doc.undo();
        assert!(doc.bars().iter().all(|b| b.beats == 3));
        assert_eq!(doc.view()[1].candidates, round_in_three(&lib));
    }

    /// The first round of a fresh search on bar 1 of four bars in 3 (as the test above opened).
    fn round_in_three(lib: &SegmentLibrary) -> Vec<usize> {
        let bars = bars_from_tempo(6.0, 120.0, 3, 0.0, |_, _| 0.5).unwrap();
        let mut doc = Choreography::new(bars).unwrap();
        doc.candidates(lib, 1).unwrap()
    }

    #[test]
    fn the_join_repair_leaves_a_dance_with_smooth_joins_as_it_was() {
        let lib = SegmentLibrary::builtin();
        let bars = bars_from_tempo(17.0, 120.0, 4, 0.0, |a, _| (a / 17.0).clamp(0.0, 1.0)).unwrap();
        let mut on = Choreography::new(bars.clone()).unwrap();
        on.generate(&lib).unwrap();
        let f = dance_figures(&lib, &bars, &on.segments().into_iter().flatten().collect::<Vec<_>>()).unwrap();
        assert!(f.join_jump_max <= JOIN_JUMP_GOAL, "{f:?}");
        assert!(f.worst_join_bar.is_some_and(|b| (1..bars.len()).contains(&b)), "{f:?}");
        let mut off = Choreography::new(bars).unwrap();
        off.generate_with(&lib, &GenerateOptions { follow_joins: false, ..GenerateOptions::default() }).unwrap();
        assert_eq!(on.segments(), off.segments());
    }

    #[test]
    fn bars_in_three_with_no_three_count_move_take_any_move() {
        // The built-in moves are all 4 counts: a waltz still gets a dance (counts spread evenly).
        let lib = SegmentLibrary::builtin();
        let bars = bars_from_tempo(6.0, 120.0, 3, 0.0, |_, _| 0.5).unwrap();
        assert_eq!(bar_counts(&lib, &bars), vec![0; bars.len()]);
        let mut doc = Choreography::new(bars).unwrap();
        doc.generate(&lib).unwrap();
        assert!(doc.segments().iter().all(Option::is_some));
    }

    #[test]
    fn bars_saved_before_they_kept_their_beats_have_four() {
        let b: Bar = serde_json::from_str(r#"{"index":0,"startSecs":0.0,"endSecs":2.0,"intensity":0.5}"#).unwrap();
        assert_eq!((b.beats, b.beat_count()), (4, 4));
    }

    #[test]
    fn round_trips_through_json_in_camel_case() {
        let lib = SegmentLibrary::builtin();
        let bars = bars_from_tempo(8.5, 120.0, 4, 0.25, |_, _| 0.5).unwrap();
        let mut doc = Choreography::new(bars).unwrap();
        let round = doc.candidates(&lib, 1).unwrap();
        doc.set(&lib, 1, round[0]).unwrap();
        doc.generate(&lib).unwrap();
        let json = serde_json::to_string(&doc).unwrap();
        let back: Choreography = serde_json::from_str(&json).unwrap();
        assert_eq!(back, doc);
        let view = serde_json::to_value(doc.view()).unwrap();
        assert_eq!(view[1]["state"]["kind"], "pinned");
        assert_eq!(view[0]["state"]["kind"], "generated");
        assert!(view[1]["bar"]["startSecs"].is_number());
        assert!(view[1]["shownCount"].is_number());
        let seg = serde_json::to_value(&lib.segments()[0]).unwrap();
        assert!(seg["intensity01"].is_number() && seg["startFrame"].is_number() && seg["tempoBpm"].is_number());
        let settings = serde_json::to_value(doc.settings()).unwrap();
        assert!(settings["fill"]["repeatWindow"].is_number());
    }
}
