//! `Choreographer`: the dance being composed to a song's bars (spec §E–G): a segment library
//! (the built-in moves plus the person's humanoid clips), relevance-feedback candidates per
//! bar, pinning, automatic filling, undo/redo, and the whole dance rendered as one clip whose
//! frame time is song time.

use odori_core::bars::Bar;
use odori_core::choreo::{recut_clip, segment_clip, BuiltinLoader, Choreography, ClipSummary, FillWeights, RenderOptions, SegmentLibrary, SegmentOptions, TableBuilder, TableScope};
use serde::Serialize;
use wasm_bindgen::prelude::*;

use crate::error::{to_js, OdoriError};
use crate::library::Library;

fn choreo_err(e: impl std::fmt::Display) -> OdoriError {
    OdoriError::new("choreo", e.to_string())
}

/// A bar or segment index from JS. Taken as a JS number (not `usize`, which wasm-bindgen
/// converts modulo 2³², so −1 became bar 4294967295): anything but a whole number ≥ 0 is
/// refused with the value the caller gave.
fn index_arg(what: &str, value: f64) -> Result<usize, OdoriError> {
    if value.is_finite() && value >= 0.0 && value.fract() == 0.0 && value <= f64::from(u32::MAX) {
        Ok(value as usize)
    } else {
        Err(OdoriError::new("bad-argument", format!("{what} {value} is not an index (a whole number from 0)")))
    }
}

/// A dance in progress.
#[wasm_bindgen]
pub struct Choreographer {
    lib: SegmentLibrary,
    doc: Option<Choreography>,
    /// The filling's transition table being built in slices (see `prepareTable`).
    builder: Option<TableBuilder>,
    /// The imported clips cut into segments, by library clip id.
    cut: Vec<CutClip>,
    /// Built-in moves still to add (see `loading` / `loadBuiltin`).
    loader: Option<BuiltinLoader>,
}

/// An imported clip in the segment library (`cutClips()`).
#[derive(Clone, Debug, Serialize)]
#[serde(rename_all = "camelCase")]
struct CutClip {
    /// Its id in the `Library`.
    id: u32,
    /// What cutting it gave (`clip`: the segment library's clip index).
    #[serde(flatten)]
    summary: ClipSummary,
}

impl Default for Choreographer {
    fn default() -> Self {
        Self::new()
    }
}

impl Choreographer {
    /// The repetition penalty the next Generate uses (the table depends on it).
    fn repeat_penalty(&self) -> f32 {
        self.doc.as_ref().map_or(FillWeights::default().repeat_penalty, |d| d.settings().fill.repeat_penalty)
    }

    /// The pairs of segments the song's bars join (none before there are bars).
    fn table_scope(&self) -> TableScope {
        self.doc.as_ref().map_or_else(TableScope::none, |d| d.table_scope(&self.lib))
    }

    fn doc(&mut self) -> Result<&mut Choreography, OdoriError> {
        self.doc.as_mut().ok_or_else(|| OdoriError::new("choreo", "no song bars yet: open a song (or use the demo song) first"))
    }
}

#[wasm_bindgen]
impl Choreographer {
    /// Starts with the built-in move library (420 four-count moves) and no bars.
    #[wasm_bindgen(constructor)]
    pub fn new() -> Choreographer {
        Choreographer { lib: SegmentLibrary::builtin(), doc: None, builder: None, cut: Vec::new(), loader: None }
    }

    /// A choreographer whose built-in moves are still to be added, a slice at a time with
    /// `loadBuiltin`, so a page need not block for the whole library at start.
    pub fn loading() -> Choreographer {
        Choreographer { lib: SegmentLibrary::new(), doc: None, builder: None, cut: Vec::new(), loader: Some(BuiltinLoader::new()) }
    }

    /// Adds up to `count` more built-in moves; returns the fraction added (1: all, the
    /// library is the same as `new()`'s). Call between frames until it returns 1, before
    /// anything else.
    #[wasm_bindgen(js_name = loadBuiltin)]
    pub fn load_builtin(&mut self, count: u32) -> f32 {
        let Some(loader) = self.loader.as_mut() else { return 1.0 };
        let p = self.lib.load_builtin(loader, count as usize);
        if p >= 1.0 {
            self.loader = None;
            self.builder = None;
        }
        p
    }

    /// Builds the filling's transition table (spec §G costs between the pairs of segments the
    /// song's bars can join: the blocks of their metres, and across a metre change; see
    /// `TableScope`) in slices of up to `columns` segments, so the page stays responsive: call
    /// it between frames until it returns 1. Returns the fraction done. `generate` builds
    /// whatever is left in one go, so calling this is optional; it is needed again after the
    /// library changes, and after new bars bring in a metre (or a metre change) not yet built.
    #[wasm_bindgen(js_name = prepareTable)]
    pub fn prepare_table(&mut self, columns: u32) -> f32 {
        let penalty = self.repeat_penalty();
        let scope = self.table_scope();
        if self.lib.cached_table_for(penalty, &scope).is_some() {
            self.builder = None;
            return 1.0;
        }
        let stale = self.builder.as_ref().is_none_or(|b| b.revision() != self.lib.revision() || b.repeat_penalty() != penalty || !b.scope().covers(&scope));
        if stale {
            self.builder = Some(self.lib.table_builder_for(penalty, &scope));
        }
        let Some(builder) = self.builder.as_mut() else { return 0.0 };
        let progress = builder.step(columns.max(1) as usize);
        if !progress.is_done() {
            return progress.fraction().min(0.999);
        }
        if let Some(table) = self.builder.take().and_then(TableBuilder::finish) {
            // Refused (false) when the library or the bars changed meanwhile: the next call
            // starts again.
            if !self.lib.install_table_for(table, &scope) {
                return 0.0;
            }
        }
        1.0
    }

    /// Whether the transition table holds what the song's bars need (Generate then takes
    /// milliseconds).
    #[wasm_bindgen(getter, js_name = tableReady)]
    pub fn table_ready(&self) -> bool {
        self.lib.cached_table_for(self.repeat_penalty(), &self.table_scope()).is_some()
    }

    /// Number of segments in the library.
    #[wasm_bindgen(getter, js_name = segmentCount)]
    pub fn segment_count(&self) -> usize {
        self.lib.len()
    }

    /// The bars to dance to (`Bar[]` from a `SongGrid`). The first call starts the document;
    /// later calls re-grid it, keeping each bar's state (undoable).
    #[wasm_bindgen(js_name = setBars)]
    pub fn set_bars(&mut self, #[wasm_bindgen(unchecked_param_type = "Bar[]")] bars: JsValue) -> Result<(), OdoriError> {
        let bars: Vec<Bar> = serde_wasm_bindgen::from_value(bars).map_err(|e| OdoriError::new("bad-argument", format!("bars: {e}")))?;
        match &mut self.doc {
            Some(d) => d.set_bars(bars).map_err(choreo_err),
            None => {
                self.doc = Some(Choreography::new(bars).map_err(choreo_err)?);
                Ok(())
            }
        }
    }

    /// Cuts a library clip into 4-count segments at its own beats (or at `tempoBpm` when the
    /// person states it) and adds them. Returns a summary; throws for a non-humanoid clip or
    /// one shorter than 4 counts.
    #[wasm_bindgen(js_name = addClip)]
    pub fn add_clip(&mut self, library: &Library, clip_id: u32, tempo_bpm: Option<f32>) -> Result<JsValue, OdoriError> {
        let e = library.entry(clip_id)?;
        let opts = SegmentOptions { tempo_bpm, ..Default::default() };
        if self.cut.iter().any(|c| c.id == clip_id) {
            return Err(OdoriError::new("choreo", format!("{} is already in the dance library: re-cut it to change its tempo", e.clip.name)));
        }
        let summary = self.lib.add_clip(&e.clip, &e.humanoid, &e.status, &opts).map_err(|err| OdoriError::new("choreo", format!("{}: {err}", e.clip.name)))?;
        self.cut.push(CutClip { id: clip_id, summary: summary.clone() });
        Ok(to_js(&summary))
    }

    /// The imported clips in the dance library: `{ id, clip, name, tempoBpm, tempoDetected,
    /// beats, segments }[]` (`id`: the `Library` clip id).
    #[wasm_bindgen(js_name = cutClips)]
    pub fn cut_clips(&self) -> JsValue {
        to_js(&self.cut)
    }

    /// Re-cuts an imported clip into 4-count segments at `tempoBpm` counts per minute (the
    /// person knows the clip's tempo), or at its detected beats again when `tempoBpm` is
    /// undefined. Nothing of the dance is lost: bars holding a segment of the earlier cut keep
    /// that motion (the earlier segment stays, never offered again), other clips' bars are
    /// untouched, undo/redo still work. Returns `{ clip: summary, removed, kept, pinnedBars,
    /// generatedBars }` (bars 0-based); throws for an unknown clip, a tempo outside 30..=300
    /// or one at which the clip holds no 4 counts (then nothing changes).
    #[wasm_bindgen(js_name = recutClip)]
    pub fn recut_clip(&mut self, clip_id: u32, tempo_bpm: Option<f32>) -> Result<JsValue, OdoriError> {
        let Some(at) = self.cut.iter().position(|c| c.id == clip_id) else {
            return Err(OdoriError::new("not-found", format!("clip {clip_id} is not in the dance library (only humanoid clips are)")));
        };
        let clip = self.cut[at].summary.clip;
        let opts = SegmentOptions { tempo_bpm, ..Default::default() };
        let report = recut_clip(&mut self.lib, self.doc.as_mut(), clip, &opts).map_err(choreo_err)?;
        self.builder = None;
        self.cut[at].summary = report.clip.clone();
        Ok(to_js(&report))
    }

    /// One segment's facts (`{ index, name, source, tempoBpm, intensity01, ... }`).
    pub fn segment(&self, index: f64) -> JsValue {
        index_arg("segment", index).ok().and_then(|i| self.lib.segment(i)).map(to_js).unwrap_or(JsValue::UNDEFINED)
    }

    /// For a segment cut from an imported clip, the count (0-based, among the clip's counts) it
    /// starts on; undefined for a built-in move or an unknown segment. With the clip and its cut
    /// tempo it makes the segment's stable key (`MoveKey`), how the page mirrors its dance into
    /// a `Project` (the same rule as the project's own library); a 3-count segment's key also
    /// has `counts: 3` (its `countFrames` hold counts + 1 frames).
    #[wasm_bindgen(js_name = firstCount)]
    pub fn first_count(&self, segment: usize) -> Option<u32> {
        let seg = self.lib.segment(segment)?;
        if seg.builtin.is_some() {
            return None;
        }
        let beats = &self.lib.clips().get(seg.clip)?.beat_frames;
        beats.iter().position(|b| b.round().max(0.0) == seg.start_frame).map(|i| i as u32)
    }

    /// Each bar: `{ bar, state: { kind, segment? }, tau, candidates, liked, shownCount, rounds }`.
    #[wasm_bindgen(unchecked_return_type = "BarView[]")]
    pub fn view(&self) -> JsValue {
        self.doc.as_ref().map(|d| to_js(&d.view())).unwrap_or_else(|| to_js(&Vec::<u8>::new()))
    }

    /// The bar's current 6 candidates (opens its search on first use).
    pub fn candidates(&mut self, bar: f64) -> Result<Vec<u32>, OdoriError> {
        let bar = index_arg("bar", bar)?;
        let lib = &self.lib;
        let d = self.doc.as_mut().ok_or_else(|| OdoriError::new("choreo", "no song bars yet"))?;
        Ok(d.candidates(lib, bar).map_err(choreo_err)?.into_iter().map(|s| s as u32).collect())
    }

    /// Next round: like `liked` (from the current round), τ × 19/20, 6 new candidates.
    pub fn search(&mut self, bar: f64, liked: Vec<f64>) -> Result<Vec<u32>, OdoriError> {
        let bar = index_arg("bar", bar)?;
        let liked: Vec<u32> = liked.into_iter().map(|x| index_arg("liked segment", x).map(|i| i as u32)).collect::<Result<_, _>>()?;
        let liked: Vec<usize> = liked.into_iter().map(|x| x as usize).collect();
        let lib = &self.lib;
        let d = self.doc.as_mut().ok_or_else(|| OdoriError::new("choreo", "no song bars yet"))?;
        Ok(d.search(lib, bar, &liked).map_err(choreo_err)?.into_iter().map(|s| s as u32).collect())
    }

    /// Pins a segment to a bar.
    pub fn set(&mut self, bar: f64, segment: f64) -> Result<(), OdoriError> {
        let (bar, segment) = (index_arg("bar", bar)?, index_arg("segment", segment)?);
        let lib = &self.lib;
        let d = self.doc.as_mut().ok_or_else(|| OdoriError::new("choreo", "no song bars yet"))?;
        d.set(lib, bar, segment).map_err(choreo_err)
    }

    /// Unpins a bar (its segment stays, as generated).
    pub fn unpin(&mut self, bar: f64) -> Result<(), OdoriError> {
        let bar = index_arg("bar", bar)?;
        self.doc()?.unpin(bar).map_err(choreo_err)
    }

    /// Starts the bar's search over (τ back to 1, nothing shown).
    #[wasm_bindgen(js_name = resetSearch)]
    pub fn reset_search(&mut self, bar: f64) -> Result<bool, OdoriError> {
        let bar = index_arg("bar", bar)?;
        self.doc()?.reset_search(bar).map_err(choreo_err)
    }

    /// ρ of spec §F eq. 1 (0..1): music fit against diversity/preference.
    #[wasm_bindgen(js_name = setRho)]
    pub fn set_rho(&mut self, rho: f32) -> Result<(), OdoriError> {
        self.doc()?.set_rho(rho).map_err(choreo_err)
    }

    /// Weight of the music term (bar intensity vs segment intensity) in the filling.
    #[wasm_bindgen(js_name = setMusicWeight)]
    pub fn set_music_weight(&mut self, w: f32) -> Result<(), OdoriError> {
        self.doc()?.set_music_weight(w).map_err(choreo_err)
    }

    /// Weight of the beat term in the filling (segments whose counts fall on their kinetic
    /// beats; 0 turns it off; default 0.3).
    #[wasm_bindgen(js_name = setBeatWeight)]
    pub fn set_beat_weight(&mut self, w: f32) -> Result<(), OdoriError> {
        self.doc()?.set_beat_weight(w).map_err(choreo_err)
    }

    /// Preference of the filling for the person's imported moves that fit the beat over
    /// built-in ones (0: none; default 0.03).
    #[wasm_bindgen(js_name = setOwnMovesPreference)]
    pub fn set_own_moves_preference(&mut self, w: f32) -> Result<(), OdoriError> {
        self.doc()?.set_own_moves_preference(w).map_err(choreo_err)
    }

    /// Quality of the dance as it stands (spec §J), per bar and whole: `{ beats: { basMusic,
    /// basMusicShifted, basMotion, basMotionShifted, kineticBeatsPerSec, musicBeatsPerSec },
    /// footSkate: { meanCmPerS, p95CmPerS, contacts }, pfc, joinJumpMean, joinJumpMax, bars:
    /// [{ bar, beats, footSkate, joinJump }] }`. `beatTimesSecs`: the song's beats (the grid's
    /// `beatTimesSecs`); omitted: each bar's beats spread evenly over it.
    pub fn quality(&self, beat_times_secs: Option<Vec<f32>>) -> Result<JsValue, OdoriError> {
        let d = self.doc.as_ref().ok_or_else(|| OdoriError::new("choreo", "no song bars yet"))?;
        let bars = d.bars();
        let beats = beat_times_secs.unwrap_or_else(|| {
            bars.iter().flat_map(|b| (0..b.beat_count()).map(move |k| b.start_secs + b.duration_secs() * k as f32 / b.beat_count() as f32)).collect()
        });
        // As the person sees it (the joined 60 fps dance); the measures resample to 30 fps.
        let clip = d.render(&self.lib, &RenderOptions::default());
        let q = odori_core::choreo::dance_quality(&clip, bars, &beats).map_err(|e| OdoriError::new("bad-argument", e.to_string()))?;
        Ok(to_js(&q))
    }

    /// Fills every open bar (pinned bars stay): `{ filled, pinned, cost }`.
    pub fn generate(&mut self) -> Result<JsValue, OdoriError> {
        let lib = &self.lib;
        let d = self.doc.as_mut().ok_or_else(|| OdoriError::new("choreo", "no song bars yet"))?;
        Ok(to_js(&d.generate(lib).map_err(choreo_err)?))
    }

    pub fn undo(&mut self) -> bool {
        self.doc.as_mut().is_some_and(|d| d.undo())
    }

    pub fn redo(&mut self) -> bool {
        self.doc.as_mut().is_some_and(|d| d.redo())
    }

    #[wasm_bindgen(js_name = canUndo)]
    pub fn can_undo(&self) -> bool {
        self.doc.as_ref().is_some_and(|d| d.can_undo())
    }

    #[wasm_bindgen(js_name = canRedo)]
    pub fn can_redo(&self) -> bool {
        self.doc.as_ref().is_some_and(|d| d.can_redo())
    }

    /// Renders the whole dance into `library` (replacing clip `replace`): frame time = song
    /// time, 5+5-frame cubic joins. Returns the clip id.
    #[wasm_bindgen(js_name = renderDance)]
    pub fn render_dance(&self, library: &mut Library, replace: Option<u32>) -> Result<u32, OdoriError> {
        let d = self.doc.as_ref().ok_or_else(|| OdoriError::new("choreo", "no song bars yet"))?;
        let mut clip = d.render(&self.lib, &RenderOptions::default());
        clip.name = "Dance".into();
        clip.source = "choreography".into();
        Ok(library.insert_clip(clip, "dance", replace))
    }

    /// One segment time-resampled to `durationSecs` (a candidate preview) into `library`.
    #[wasm_bindgen(js_name = previewSegment)]
    pub fn preview_segment(&self, library: &mut Library, segment: f64, duration_secs: f32, replace: Option<u32>) -> Result<u32, OdoriError> {
        let segment = index_arg("segment", segment)?;
        let mut clip = segment_clip(&self.lib, segment, duration_secs, 60.0)
            .ok_or_else(|| OdoriError::new("not-found", format!("no segment {segment} in the library")))?;
        clip.source = "candidate".into();
        Ok(library.insert_clip(clip, "dance", replace))
    }
}

/// The tempo limits, from the one place the engine keeps them: `{ moveMinBpm, moveMaxBpm }`
/// (a clip's stated tempo, counts per minute) and `{ songMinBpm, songMaxBpm }` (a song's
/// corrected grid). The page's tempo fields and messages use them.
#[wasm_bindgen(js_name = tempoLimits, unchecked_return_type = "{ moveMinBpm: number; moveMaxBpm: number; songMinBpm: number; songMaxBpm: number }")]
pub fn tempo_limits() -> JsValue {
    #[derive(Serialize)]
    #[serde(rename_all = "camelCase")]
    struct Limits {
        move_min_bpm: f32,
        move_max_bpm: f32,
        song_min_bpm: f32,
        song_max_bpm: f32,
    }
    use odori_core::music::grid::{MAX_GRID_BPM, MIN_GRID_BPM};
    to_js(&Limits { move_min_bpm: odori_core::choreo::MIN_MOVE_BPM, move_max_bpm: odori_core::choreo::MAX_MOVE_BPM, song_min_bpm: MIN_GRID_BPM, song_max_bpm: MAX_GRID_BPM })
}

#[wasm_bindgen(typescript_custom_section)]
const TS_CHOREO: &'static str = r#"
export interface BarView { bar: Bar; state: { kind: "empty" | "pinned" | "generated"; segment?: number }; tau: number; candidates: number[]; liked: number[]; shownCount: number; rounds: number; }
"#;
