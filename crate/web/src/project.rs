//! `Project`: the one handle that holds a dance — everything a person made (spec §K), every
//! edit with undo/redo, `.odori` save and open, and the manifest + blobs that autosave writes
//! to IndexedDB. Moves are kept by stable keys (`MoveKey`), never by segment numbers.
//!
//! It is the whole dance API (the `Choreographer` handle it replaced is gone; see
//! pkg/README.md's changelog): the song and its grid (`setSong`, `correctGrid`), the segment
//! library (`importInto` / `addSource`, `setClipTempo`, `loadBuiltin`, `segment`, `keyOf`),
//! the dance by key (`candidates`, `search`, `set`) or by segment number for a panel
//! (`danceView`, `candidateSegments`, `searchSegments`, `setSegment`), the filling's settings,
//! `generate`, `quality`, `renderDance`, `prepareTable`, and what a player needs to play a
//! saved project (`playInto`), so no page reads the project's schema itself.

use js_sys::{Array, Float32Array, Function, Uint8Array};
use odori_core::choreo::{segment_clip, RenderOptions, TableBuilder};
use odori_core::music::{AnalysisOptions, GridCorrection, RmsEnvelope};
use odori_core::project::{self, BarKind, BlobHash, Camera, ClipRef, MoveKey, Project as CoreProject, ProjectError};
use odori_core::ImportOptions;
use serde::{Deserialize, Serialize};
use wasm_bindgen::prelude::*;

use crate::error::{from_js, to_js, JsResult, OdoriError};
use crate::library::Library;

fn arg<T: serde::de::DeserializeOwned>(value: JsValue, what: &str) -> JsResult<T> {
    serde_wasm_bindgen::from_value(value).map_err(|e| OdoriError::new("bad-argument", format!("{what}: {e}")))
}

/// `Project.generate`'s options (`GenerateOptions` in the `.d.ts`).
#[derive(Deserialize, Default)]
#[serde(rename_all = "camelCase", default, deny_unknown_fields)]
struct JsGenerateOptions {
    take: Option<u32>,
}

#[derive(Deserialize, Default)]
#[serde(rename_all = "camelCase", default, deny_unknown_fields)]
struct JsImportOptions {
    fps_override: Option<f32>,
    unit_scale: Option<f32>,
    gltf_fps: Option<f32>,
    song_offset_frames: Option<u32>,
}

/// A project: what a person made, its history, and how to save it.
#[wasm_bindgen]
pub struct Project {
    inner: CoreProject,
    /// Bumped by every change, so the host knows when to autosave.
    revision: u32,
    /// The filling's transition table being built in slices (see `prepareTable`).
    builder: Option<TableBuilder>,
}

/// A bar or segment index from JS: anything but a whole number ≥ 0 is refused with the value
/// given (a `usize` parameter would wrap −1 to 4294967295).
fn index_arg(what: &str, value: f64) -> Result<usize, OdoriError> {
    if value.is_finite() && value >= 0.0 && value.fract() == 0.0 && value <= f64::from(u32::MAX) {
        Ok(value as usize)
    } else {
        Err(OdoriError::new("bad-argument", format!("{what} {value} is not an index (a whole number from 0)")))
    }
}

impl Default for Project {
    fn default() -> Self {
        Self::new()
    }
}

impl Project {
    fn changed<T>(&mut self, r: T) -> T {
        self.revision = self.revision.wrapping_add(1);
        r
    }

    fn opened(o: project::Opened) -> Project {
        Project { inner: o.project, revision: 0, builder: None }
    }
}

#[wasm_bindgen]
impl Project {
    /// An empty project.
    #[wasm_bindgen(constructor)]
    pub fn new() -> Project {
        Project { inner: CoreProject::new(), revision: 0, builder: None }
    }

    /// Opens an `.odori` file. Throws an `OdoriError` whose `kind` names the problem
    /// ("empty", "not-odori", "truncated", "corrupt", "newer-version", "too-old"); a blob the
    /// file lacks does not throw: see `missing()`.
    pub fn open(bytes: &[u8]) -> Result<Project, OdoriError> {
        Ok(Self::opened(project::open(bytes)?))
    }

    /// Rebuilds a project from its manifest (`manifest()`) and a function giving a blob's
    /// bytes by hash (`Uint8Array`, or undefined when the store lacks it): how autosave
    /// restores from IndexedDB.
    #[wasm_bindgen(js_name = fromManifest)]
    pub fn from_manifest(manifest: &[u8], get_blob: &Function) -> Result<Project, OdoriError> {
        let opened = project::file::from_manifest(manifest, |h: &BlobHash| {
            let v = get_blob.call1(&JsValue::NULL, &JsValue::from_str(h.as_str())).ok()?;
            v.dyn_into::<Uint8Array>().ok().map(|a| std::sync::Arc::from(a.to_vec()))
        })?;
        Ok(Self::opened(opened))
    }

    /// The whole project as an `.odori` file.
    pub fn save(&self) -> Result<Vec<u8>, OdoriError> {
        Ok(project::save(&self.inner)?)
    }

    /// The manifest (UTF-8 JSON: schema version, document, undo/redo history), what autosave
    /// writes after each edit; blobs are written apart, once each.
    pub fn manifest(&self) -> Vec<u8> {
        project::file::manifest_json(&self.inner)
    }

    /// Hashes of every blob the project refers to (document and history).
    #[wasm_bindgen(js_name = blobHashes)]
    pub fn blob_hashes(&self) -> Vec<String> {
        self.inner.referenced_blobs().into_iter().filter(|h| self.inner.blobs().contains(h)).map(|h| h.to_string()).collect()
    }

    /// A blob's bytes (undefined when the project does not hold it).
    pub fn blob(&self, hash: &str) -> Option<Vec<u8>> {
        BlobHash::parse(hash).and_then(|h| self.inner.blobs().get(&h).map(|b| b.to_vec()))
    }

    /// What the document names that was missing when it was opened: `{ hash, what }[]`.
    pub fn missing(&self) -> JsValue {
        to_js(&self.inner.missing())
    }

    /// Changes with every edit (and undo/redo) made through this handle.
    #[wasm_bindgen(getter)]
    pub fn revision(&self) -> u32 {
        self.revision
    }

    /// The document (JSON-compatible object): sources, song, dance by keys, tags, texts,
    /// character, camera. Its shape is the file's schema: the page reads no field of it (it
    /// asks `summary()`); tests and tools may.
    pub fn doc(&self) -> JsValue {
        to_js(self.inner.doc())
    }

    /// What the page shows of the project (`ProjectSummary`): name, sources, song (with a key
    /// that changes only when the song does), tags, put-on clips (each with a key), the body,
    /// texts, ρ, the music weight, the camera motions and the face tracks (each with a key), the
    /// MMD files it keeps (`mmdFiles`).
    #[wasm_bindgen(unchecked_return_type = "ProjectSummary")]
    pub fn summary(&self) -> JsValue {
        to_js(&self.inner.summary())
    }

    /// The blob hashes a stored manifest (`manifest()`'s bytes) lists, without opening it:
    /// what the browser store's collection keeps.
    #[wasm_bindgen(js_name = manifestBlobHashes)]
    pub fn manifest_blob_hashes(manifest: &[u8]) -> Result<Vec<String>, OdoriError> {
        Ok(project::manifest_blob_hashes(manifest)?.into_iter().map(|h| h.to_string()).collect())
    }

    /// Every clip of every source: `{ clip: { source, clip }, name, fileName, fps, frames,
    /// durationSecs, joints, humanoid, cut, refused }[]`.
    pub fn clips(&mut self) -> JsValue {
        to_js(&self.inner.derived().clips())
    }

    /// The song's grid (`SongGrid`), or undefined without a song.
    pub fn grid(&mut self) -> Result<JsValue, OdoriError> {
        match self.inner.derived().grid() {
            None => Ok(JsValue::UNDEFINED),
            Some(Ok(g)) => Ok(to_js(g)),
            Some(Err(e)) => Err(e.clone().into()),
        }
    }

    /// The song's sections (`music::sections` with its default options over the project's
    /// grid and envelope): `{ sections: [{ firstBar, bars, label, intensity, repeatOf,
    /// similarity }], novelty: number[] }`, or undefined without a song. The video camera cuts
    /// at their boundaries (`Viewer.planCamera`).
    pub fn sections(&mut self) -> Result<JsValue, OdoriError> {
        Ok(match self.inner.sections()? {
            Some(s) => to_js(&s),
            None => JsValue::UNDEFINED,
        })
    }

    /// The runs of repeated bars Generate follows: the song's sections' repeats with the
    /// person's marks laid over them, `[{ firstBar, bars, ofBar, marked }]` (bars from 0: bars
    /// `firstBar .. firstBar + bars` take the moves of bars `ofBar ..`); `marked` when the person
    /// marked it (`markRepeat`). Empty without a song.
    pub fn repeats(&mut self) -> Result<JsValue, OdoriError> {
        Ok(to_js(&self.inner.repeat_runs()?))
    }

    /// Marks bars `firstBar .. firstBar + bars` as repeating the earlier bars `ofFirstBar ..
    /// ofFirstBar + ofBars` (bars from 0): Generate gives them the same moves. One undo step,
    /// kept in the project. A bad range is an error of kind `bad-repeat` naming it (empty, out
    /// of the song, unequal lengths, overlapping, or the repeated bars not earlier).
    #[wasm_bindgen(js_name = markRepeat)]
    pub fn mark_repeat(&mut self, first_bar: f64, bars: f64, of_first_bar: f64, of_bars: f64) -> Result<(), OdoriError> {
        let range = odori_core::project::BarRange { first_bar: index_arg("firstBar", first_bar)?, bars: index_arg("bars", bars)? };
        let of = odori_core::project::BarRange { first_bar: index_arg("ofFirstBar", of_first_bar)?, bars: index_arg("ofBars", of_bars)? };
        self.inner.mark_repeat(range, of)?;
        Ok(self.changed(()))
    }

    /// Removes the repeat holding bar `bar` (found by the analysis or marked; its whole run):
    /// Generate then fills those bars on their own. One undo step. Returns the run removed
    /// (`{ firstBar, bars, ofBar, marked }`); a bar that repeats nothing is `not-found`.
    #[wasm_bindgen(js_name = removeRepeat)]
    pub fn remove_repeat(&mut self, bar: f64) -> Result<JsValue, OdoriError> {
        let run = self.inner.remove_repeat(index_arg("bar", bar)?)?;
        Ok(self.changed(to_js(&run)))
    }

    /// The segment a move key names now (for the calls by segment number), or undefined.
    #[wasm_bindgen(js_name = segmentOf)]
    pub fn segment_of(&mut self, key: JsValue) -> Result<Option<u32>, OdoriError> {
        let key: MoveKey = arg(key, "key")?;
        Ok(self.inner.derived().index_of(&key).map(|i| i as u32))
    }

    #[wasm_bindgen(js_name = setName)]
    pub fn set_name(&mut self, name: &str) {
        self.inner.set_name(name);
        self.changed(())
    }

    /// Imports a motion file into the project (its bytes are kept as given). Returns
    /// `{ id, clips, warnings }`.
    #[wasm_bindgen(js_name = addSource)]
    pub fn add_source(&mut self, file_name: &str, bytes: &[u8], #[wasm_bindgen(unchecked_param_type = "ImportOptions | undefined")] options: JsValue) -> Result<JsValue, OdoriError> {
        let o: JsImportOptions = from_js(options, "import options", &["fpsOverride", "unitScale", "gltfFps", "songOffsetFrames"])?;
        let options = ImportOptions { fps_override: o.fps_override, unit_scale: o.unit_scale, gltf_fps: o.gltf_fps.unwrap_or(ImportOptions::default().gltf_fps), song_offset_frames: o.song_offset_frames };
        let r = self.inner.add_source(file_name, bytes, options)?;
        Ok(self.changed(to_js(&r)))
    }

    #[wasm_bindgen(js_name = removeSource)]
    pub fn remove_source(&mut self, source: u32) -> Result<(), OdoriError> {
        self.inner.remove_source(project::SourceId(source))?;
        Ok(self.changed(()))
    }

    /// Re-cuts a clip (`{ source, clip }`) at `tempoBpm` counts per minute, or at its detected
    /// tempo (undefined). Moves of the earlier cut the dance holds are kept.
    #[wasm_bindgen(js_name = setClipTempo)]
    pub fn set_clip_tempo(&mut self, clip: JsValue, tempo_bpm: Option<f32>) -> Result<JsValue, OdoriError> {
        let clip: ClipRef = arg(clip, "clip")?;
        let r = self.inner.set_clip_tempo(clip, tempo_bpm)?;
        Ok(self.changed(to_js(&r)))
    }

    /// [`setClipTempo`] that says what it meant for the dance: `RecutReport` `{ clip (the new
    /// cut), removed, kept, pinnedBars, generatedBars }` (segments of the earlier cut removed
    /// from the library and kept because bars hold them; the bars pinned to, or generated with,
    /// a move of the earlier cut, which keep it).
    #[wasm_bindgen(js_name = recutClip, unchecked_return_type = "RecutReport")]
    pub fn recut_clip(&mut self, clip: JsValue, tempo_bpm: Option<f32>) -> Result<JsValue, OdoriError> {
        let clip: ClipRef = arg(clip, "clip")?;
        let r = self.inner.recut_clip(clip, tempo_bpm)?;
        Ok(self.changed(to_js(&r)))
    }

    /// Sets the song: file name, its bytes as given (undefined for the demo song), the RMS
    /// envelope the host computed (`hopSecs`, one `Float32Array` per band) and analysis
    /// options. `record: false`: no undo step (the song a new project starts with).
    #[wasm_bindgen(js_name = setSong)]
    pub fn set_song(&mut self, file_name: &str, audio: Option<Vec<u8>>, hop_secs: f32, bands: Array, options: JsValue, record: Option<bool>) -> Result<(), OdoriError> {
        let options: AnalysisOptions = from_js(options, "analysis options", &["beatsPerBar", "minBpm", "maxBpm", "priorBpm", "priorOctaves", "tightness"])?;
        let bands = bands
            .iter()
            .enumerate()
            .map(|(i, v)| v.dyn_into::<Float32Array>().map(|a| a.to_vec()).map_err(|_| OdoriError::new("bad-argument", format!("bands[{i}] must be a Float32Array"))))
            .collect::<Result<Vec<_>, _>>()?;
        let env = RmsEnvelope { hop_secs, bands };
        if record == Some(false) {
            self.inner.set_initial_song(file_name, audio.as_deref(), &env, options)?;
        } else {
            self.inner.set_song(file_name, audio.as_deref(), &env, options)?;
        }
        Ok(self.changed(()))
    }

    /// Corrects the grid (`{ bpm?, tapTimesSecs?, beatsPerBar?, firstDownbeatSecs?, nudgeSecs? }`).
    #[wasm_bindgen(js_name = correctGrid)]
    pub fn correct_grid(&mut self, correction: JsValue) -> Result<(), OdoriError> {
        let c: GridCorrection = from_js(correction, "correction", &["bpm", "tapTimesSecs", "beatsPerBar", "firstDownbeatSecs", "nudgeSecs"])?;
        self.inner.correct_grid(c)?;
        Ok(self.changed(()))
    }

    #[wasm_bindgen(js_name = resetGrid)]
    pub fn reset_grid(&mut self) -> Result<(), OdoriError> {
        self.inner.reset_grid()?;
        Ok(self.changed(()))
    }

    /// The bar's current candidates (`MoveKey[]`), opening its search when none is open.
    pub fn candidates(&mut self, bar: f64) -> Result<JsValue, OdoriError> {
        let r = self.inner.candidates(index_arg("bar", bar)?)?;
        Ok(self.changed(to_js(&r)))
    }

    /// Likes `liked` (keys from the current round) and returns the next round.
    pub fn search(&mut self, bar: f64, liked: JsValue) -> Result<JsValue, OdoriError> {
        let bar = index_arg("bar", bar)?;
        let liked: Vec<MoveKey> = arg(liked, "liked")?;
        let r = self.inner.search(bar, &liked)?;
        Ok(self.changed(to_js(&r)))
    }

    /// Starts the bar's search over (τ back to 1, nothing shown).
    #[wasm_bindgen(js_name = resetSearch)]
    pub fn reset_search(&mut self, bar: f64) -> Result<bool, OdoriError> {
        let r = self.inner.reset_search(index_arg("bar", bar)?)?;
        Ok(self.changed(r))
    }

    /// Pins a move (a `MoveKey`) to a bar.
    pub fn set(&mut self, bar: f64, key: JsValue) -> Result<(), OdoriError> {
        let bar = index_arg("bar", bar)?;
        let key: MoveKey = arg(key, "key")?;
        self.inner.set(bar, &key)?;
        Ok(self.changed(()))
    }

    /// Unpins a bar (its move stays, as generated).
    pub fn unpin(&mut self, bar: f64) -> Result<(), OdoriError> {
        self.inner.unpin(index_arg("bar", bar)?)?;
        Ok(self.changed(()))
    }

    /// Empties a bar.
    pub fn clear(&mut self, bar: f64) -> Result<(), OdoriError> {
        self.inner.clear(index_arg("bar", bar)?)?;
        Ok(self.changed(()))
    }

    /// Fills every open bar: `{ filled, pinned, cost }`. `{ take }` (0..=15, default 0): which
    /// take of Generate; each take above 0 is a different dance of comparable cost, kept with
    /// its number (`take`). One undo step.
    pub fn generate(&mut self, #[wasm_bindgen(unchecked_param_type = "GenerateOptions | undefined")] options: JsValue) -> Result<JsValue, OdoriError> {
        let o: JsGenerateOptions = from_js(options, "generate options", &["take"])?;
        let r = self.inner.generate_take(o.take.unwrap_or(0))?;
        Ok(self.changed(to_js(&r)))
    }

    /// The take of Generate the dance's generated bars come from (0 until another take).
    #[wasm_bindgen(getter)]
    pub fn take(&self) -> u32 {
        self.inner.take()
    }

    /// ρ of spec §F eq. 1 (0..=1): music fit against diversity and preference.
    #[wasm_bindgen(js_name = setRho)]
    pub fn set_rho(&mut self, rho: f32) -> Result<(), OdoriError> {
        self.inner.set_rho(rho)?;
        Ok(self.changed(()))
    }

    /// Weight of the music term (bar intensity vs segment intensity) in the filling, 0..=100.
    #[wasm_bindgen(js_name = setMusicWeight)]
    pub fn set_music_weight(&mut self, w: f32) -> Result<(), OdoriError> {
        self.inner.set_music_weight(w)?;
        Ok(self.changed(()))
    }

    /// Weight of the beat term in the filling (segments whose counts fall on their kinetic
    /// beats; 0 turns it off; default 0.3), 0..=100.
    #[wasm_bindgen(js_name = setBeatWeight)]
    pub fn set_beat_weight(&mut self, w: f32) -> Result<(), OdoriError> {
        self.inner.set_beat_weight(w)?;
        Ok(self.changed(()))
    }

    /// Preference of the filling for the person's imported moves that fit the beat over
    /// built-in ones (0: none; default 0.03), 0..=100.
    #[wasm_bindgen(js_name = setOwnMovesPreference)]
    pub fn set_own_moves_preference(&mut self, w: f32) -> Result<(), OdoriError> {
        self.inner.set_own_moves_preference(w)?;
        Ok(self.changed(()))
    }

    /// Which moves Generate fills the open bars with: `"mine"` (the person's imported moves
    /// first: built-in moves only in bars no imported move fits; the default, which is the
    /// built-in moves alone until a humanoid clip is imported), `"mixed"` (both, as the filling
    /// weighs them) or `"builtin"`. One undo step.
    #[wasm_bindgen(js_name = setMovesSource)]
    pub fn set_moves_source(&mut self, #[wasm_bindgen(unchecked_param_type = "\"mine\" | \"mixed\" | \"builtin\"")] source: &str) -> Result<(), OdoriError> {
        let s = match source {
            "mine" => odori_core::choreo::MovesSource::Mine,
            "mixed" => odori_core::choreo::MovesSource::Mixed,
            "builtin" => odori_core::choreo::MovesSource::Builtin,
            other => return Err(OdoriError::new("bad-argument", format!("moves source: {other:?} is none of \"mine\", \"mixed\", \"builtin\""))),
        };
        self.inner.set_moves_source(s)?;
        Ok(self.changed(()))
    }

    /// Which moves Generate fills the open bars with (`setMovesSource`).
    #[wasm_bindgen(getter, js_name = movesSource)]
    pub fn moves_source(&self) -> String {
        match self.inner.fill_weights().moves_source {
            odori_core::choreo::MovesSource::Mine => "mine",
            odori_core::choreo::MovesSource::Mixed => "mixed",
            odori_core::choreo::MovesSource::Builtin => "builtin",
        }
        .into()
    }

    /// Tags a clip (`{ source, clip }`) with words text can call it by.
    #[wasm_bindgen(js_name = setTags)]
    pub fn set_tags(&mut self, clip: JsValue, tags: Vec<String>) -> Result<(), OdoriError> {
        let clip: ClipRef = arg(clip, "clip")?;
        self.inner.set_tags(clip, tags)?;
        Ok(self.changed(()))
    }

    #[wasm_bindgen(js_name = setTexts)]
    pub fn set_texts(&mut self, texts: Vec<String>) {
        self.inner.set_texts(texts);
        self.changed(())
    }

    /// What the dance is shown on: a character (`{ source, clip }`), `"stick"` (stick
    /// figures), or undefined/null (the built-in body, as in a new project). Kept in
    /// `doc().character` and `doc().stickFigures`.
    #[wasm_bindgen(js_name = setCharacter)]
    pub fn set_character(
        &mut self,
        #[wasm_bindgen(unchecked_param_type = "ClipRef | \"stick\" | null | undefined")] clip: JsValue,
    ) -> Result<(), OdoriError> {
        if clip.as_string().as_deref() == Some("stick") {
            self.inner.set_stick_figures();
            return Ok(self.changed(()));
        }
        let clip: Option<ClipRef> = if clip.is_undefined() || clip.is_null() { None } else { Some(arg(clip, "clip")?) };
        self.inner.set_character(clip)?;
        Ok(self.changed(()))
    }

    /// Puts library clip `motionId` on the character shown as library clip `characterId`
    /// (the project's clip `character`, `{ source, clip }`: an imported skinned humanoid), as
    /// an edit of the project (undoable, kept, saved). `motion` is the motion's project clip
    /// when it is one; undefined for a clip made in the page (the dance, a text animation, a
    /// move, the built-in clip), which the project keeps as the BVH file the engine writes of
    /// it. Adds the put-on clip to `library` and returns its `ClipInfo` with `worn` (its
    /// number in the project's `doc().worn`). A character or motion that cannot be put on
    /// throws (`character-*`, `motion-not-humanoid`), nothing changed.
    #[wasm_bindgen(js_name = putOnInto, unchecked_return_type = "ClipInfo & { worn: number }")]
    pub fn put_on_into(&mut self, library: &mut Library, motion_id: u32, motion: JsValue, character_id: u32, character: JsValue) -> Result<JsValue, OdoriError> {
        let character: ClipRef = arg(character, "character")?;
        let motion: Option<ClipRef> = if motion.is_undefined() || motion.is_null() { None } else { Some(arg(motion, "motion")?) };
        let index = match motion {
            Some(m) => self.inner.put_on(character, Some(m), None)?,
            None => {
                let e = library.entry(motion_id)?;
                let file = odori_core::export::bvh::bvh(&e.clip)?;
                let name = e.clip.name.clone();
                self.inner.put_on(character, None, Some((&name, &file)))?
            }
        };
        self.changed(());
        self.worn_into(library, index as u32, Some(character_id))
    }

    /// Shows put-on clip `index` of the document (`doc().worn[index]`) in `library`, rebuilt
    /// from its recipe (a restored project, or one brought back by undo/redo), drawn with the
    /// mesh of library clip `characterId` when given. Returns its `ClipInfo` with `worn`.
    #[wasm_bindgen(js_name = wornInto, unchecked_return_type = "ClipInfo & { worn: number }")]
    pub fn worn_into(&mut self, library: &mut Library, index: u32, character_id: Option<u32>) -> Result<JsValue, OdoriError> {
        let (clip, imported) = self.inner.worn_clip(index as usize)?;
        let id = library.push_on_character(clip, character_id, imported.mesh.as_ref());
        let info = to_js(&crate::library::info_of(library.entry(id)?));
        js_sys::Reflect::set(&info, &JsValue::from_str("worn"), &JsValue::from(index)).map_err(|_| OdoriError::new("bad-argument", "clip info"))?;
        Ok(info)
    }

    /// Takes put-on clip `index` out of the project (undoable).
    #[wasm_bindgen(js_name = removeWorn)]
    pub fn remove_worn(&mut self, index: u32) -> Result<(), OdoriError> {
        self.inner.remove_worn(index as usize)?;
        Ok(self.changed(()))
    }

    /// The camera (`{ yawRad, pitchRad, distanceM, targetM }`, or undefined); not undoable.
    #[wasm_bindgen(js_name = setCamera)]
    pub fn set_camera(&mut self, camera: JsValue) -> Result<(), OdoriError> {
        let camera: Option<Camera> = if camera.is_undefined() || camera.is_null() { None } else { Some(arg(camera, "camera")?) };
        self.inner.set_camera(camera);
        Ok(self.changed(()))
    }

    /// Opens a group of edits one undo takes back (a share link applied bar by bar, then
    /// Generate): every edit until `endGroup()` joins the first one's undo step.
    #[wasm_bindgen(js_name = beginGroup)]
    pub fn begin_group(&mut self) {
        self.inner.begin_group();
    }

    #[wasm_bindgen(js_name = endGroup)]
    pub fn end_group(&mut self) {
        self.inner.end_group();
    }

    pub fn undo(&mut self) -> bool {
        let r = self.inner.undo();
        if r {
            self.changed(())
        }
        r
    }

    pub fn redo(&mut self) -> bool {
        let r = self.inner.redo();
        if r {
            self.changed(())
        }
        r
    }

    #[wasm_bindgen(js_name = canUndo)]
    pub fn can_undo(&self) -> bool {
        self.inner.can_undo()
    }

    #[wasm_bindgen(js_name = canRedo)]
    pub fn can_redo(&self) -> bool {
        self.inner.can_redo()
    }

    /// Imports a motion file into the project (as `addSource`) and shows its clips in
    /// `library`: the file is parsed once, and the library holds the very clips the project
    /// cuts. Returns the library's `ImportReport` with `source` (the project's source id).
    #[wasm_bindgen(js_name = importInto)]
    pub fn import_into(&mut self, library: &mut Library, file_name: &str, bytes: &[u8], #[wasm_bindgen(unchecked_param_type = "ImportOptions | undefined")] options: JsValue) -> Result<JsValue, OdoriError> {
        let o: JsImportOptions = from_js(options, "import options", &["fpsOverride", "unitScale", "gltfFps", "songOffsetFrames"])?;
        let options = ImportOptions { fps_override: o.fps_override, unit_scale: o.unit_scale, gltf_fps: o.gltf_fps.unwrap_or(ImportOptions::default().gltf_fps), song_offset_frames: o.song_offset_frames };
        let r = self.inner.add_source(file_name, bytes, options)?;
        self.changed(());
        self.clips_into(library, r.id.0)
    }

    /// `importInto` of a VMD dance posed on an MMD model file given with it (`modelFileName`,
    /// `modelBytes`: a PMX/PMD; its bones and IK pose the dance). The project keeps the model
    /// with the dance, and the files it is drawn with (its textures and MMD's shared toon ramps
    /// it uses: schema 7), each once by hash, so a reopened project poses the dance on that model
    /// and draws it textured even without the model in the library. `modelFiles`
    /// (`{ name, bytes }[]`, as `importFiles` takes them): where its textures are found by the
    /// paths the model names; omitted, they are the ones the library's model of that name found
    /// (when its file is the same). When the model's bytes are missing it is posed on the standard
    /// MMD skeleton and the report's warnings say so. Like every MMD file they stay with the
    /// person: in the `.odori` file, never in a share link (`summary().mmdFiles` names them).
    #[wasm_bindgen(js_name = importOnModelInto)]
    #[allow(clippy::too_many_arguments)]
    pub fn import_on_model_into(
        &mut self,
        library: &mut Library,
        file_name: &str,
        bytes: &[u8],
        #[wasm_bindgen(unchecked_param_type = "ImportOptions | undefined")] options: JsValue,
        model_file_name: &str,
        model_bytes: &[u8],
        #[wasm_bindgen(unchecked_param_type = "{ name: string, bytes: Uint8Array }[] | undefined")] model_files: JsValue,
    ) -> Result<JsValue, OdoriError> {
        let o: JsImportOptions = from_js(options, "import options", &["fpsOverride", "unitScale", "gltfFps", "songOffsetFrames"])?;
        let options = ImportOptions { fps_override: o.fps_override, unit_scale: o.unit_scale, gltf_fps: o.gltf_fps.unwrap_or(ImportOptions::default().gltf_fps), song_offset_frames: o.song_offset_frames };
        let drawn = if model_files.is_undefined() || model_files.is_null() {
            library.mmd_drawn_files(model_bytes)
        } else {
            let files = crate::mmd::files_from_js(&model_files)?;
            let model = odori_core::import::mmd_model::read_model(model_file_name, model_bytes).map_err(|e| {
                let e = odori_core::mmd::files::MmdFilesError::from(e);
                OdoriError { kind: e.kind(), message: e.to_string(), file: Some(model_file_name.to_string()) }
            })?;
            odori_core::mmd::files::drawn_files_in(model_file_name, &model, &files)
        };
        let given = project::GivenModel { file_name: model_file_name, bytes: model_bytes, drawn: &drawn };
        let r = self.inner.add_source_with_model(file_name, bytes, options, given)?;
        self.changed(());
        self.clips_into(library, r.id.0)
    }

    /// Shows a source's clips in `library` (a restored project, or an import brought back by
    /// undo/redo): the library's `ImportReport` with `source`. Throws "missing-blob" when the
    /// source's bytes are missing, the importer's error when they do not read.
    #[wasm_bindgen(js_name = clipsInto)]
    pub fn clips_into(&mut self, library: &mut Library, source: u32) -> Result<JsValue, OdoriError> {
        let id = project::SourceId(source);
        let file_name = self.inner.doc().source(id).map(|s| s.file_name.clone()).ok_or_else(|| OdoriError::new("not-found", format!("there is no source {source} in the project")))?;
        let imported = match self.inner.imported(id) {
            None => return Err(OdoriError::new("missing-blob", format!("{file_name}: its bytes are missing from the project"))),
            Some(r) => r?,
        };
        // A VMD dance posed on the model kept with it: drawn with the library's mesh of that
        // model when it has one (with its textures), else the mesh the project made from the
        // model file; `exportVmd` fits it to that model by default.
        let model = self.inner.source_model(id).ok().flatten();
        let shared = model.as_ref().zip(imported.clips.first()).and_then(|(m, c)| library.character_mesh(&m.name, &c.skeleton));
        let before = library.size();
        let report = library.add_imported_on(&file_name, &imported, shared);
        // A VMD's face keys, from the bytes the project keeps: played on an MMD model's face.
        if let Some((keys, offset)) = self.inner.face_keys(id) {
            for clip in library.ids_from(before) {
                library.keep_face_keys(clip, keys.clone(), offset);
            }
        }
        if let Some(m) = model {
            let ids = library.ids_from(before);
            library.link_project_dance(&ids, m);
        }
        // A VMD dance starts at its song offset: its clip's time is song time, and the
        // project's face tracks play on it.
        if file_name.to_ascii_lowercase().ends_with(".vmd") {
            for clip in library.ids_from(before) {
                library.mark_song_clip(clip);
            }
        }
        js_sys::Reflect::set(&report, &JsValue::from_str("source"), &JsValue::from(source)).map_err(|_| OdoriError::new("bad-argument", "report"))?;
        Ok(report)
    }

    /// Imports a camera motion (a MikuMikuDance camera VMD) into the project — its bytes kept as
    /// given, like a source's (in the `.odori` file and the browser's store, never in a share
    /// link); undoable — and shows the project's camera motions in `library` (`camerasInto`).
    /// `options`: `{ songOffsetFrames? }` (the motion frame that is song time 0). Returns the
    /// track `{ name, source, keys, durationSecs, index }` (`index`: in `library.cameraTracks()`).
    /// Throws "mmd-no-camera-keys" for a VMD without camera keys, the reader's kind for a bad file.
    #[wasm_bindgen(js_name = addCameraInto)]
    pub fn add_camera_into(&mut self, library: &mut Library, file_name: &str, bytes: &[u8], #[wasm_bindgen(unchecked_param_type = "{ songOffsetFrames?: number } | undefined")] options: JsValue) -> Result<JsValue, OdoriError> {
        let o: JsImportOptions = from_js(options, "camera import options", &["songOffsetFrames"])?;
        self.inner.add_camera(file_name, bytes, o.song_offset_frames)?;
        self.changed(());
        self.cameras_into(library);
        let index = library.mmd.camera_count().saturating_sub(1);
        let info = library.camera_track_info(index)?;
        js_sys::Reflect::set(&info, &JsValue::from_str("index"), &JsValue::from(index as u32)).map_err(|_| OdoriError::new("bad-argument", "camera info"))?;
        Ok(info)
    }

    /// Removes the project's camera motion `index` (in the project's order, `summary().cameras`). Undoable.
    #[wasm_bindgen(js_name = removeCamera)]
    pub fn remove_camera(&mut self, index: u32) -> Result<(), OdoriError> {
        self.inner.remove_camera(index as usize)?;
        self.changed(());
        Ok(())
    }

    /// Shows the project's camera motions in `library` (after an import, undo/redo, or a
    /// restored project): they replace the ones shown before and follow the library's own
    /// (`library.cameraTracks()`). Returns the problems, one message per camera motion that
    /// cannot be read (its bytes missing from the project).
    #[wasm_bindgen(js_name = camerasInto)]
    pub fn cameras_into(&mut self, library: &mut Library) -> Vec<String> {
        let mut tracks = Vec::new();
        let mut problems = Vec::new();
        for i in 0..self.inner.doc().tracks(project::TrackKind::Camera).count() {
            match self.inner.camera_track(i) {
                Ok(t) => tracks.push(t),
                Err(e) => problems.push(e.to_string()),
            }
        }
        library.mmd.project_cameras = tracks;
        problems
    }

    /// Keeps a lip-sync VMD (its morph keys; usually a file of face keys only) as a face track
    /// of the project — its bytes kept as given, like a source's (in the `.odori` file and the
    /// browser's store, never in a share link); undoable — and shows the project's face tracks
    /// in `library` (`faceTracksInto`). When the dance is drawn on an MMD model's mesh the
    /// viewer plays the track's weights at the song time (over the dance's own face keys, for
    /// the morphs it keys), and `exportVmd` of the dance writes its keys. `options`:
    /// `{ songOffsetFrames? }` (the motion frame that is song time 0). Returns
    /// `{ source, keys, morphs, songOffsetFrames, durationSecs, index }`. Throws
    /// "mmd-no-morph-keys" for a VMD without morph keys, the reader's kind ("mmd-bad-magic",
    /// "mmd-truncated", "mmd-count-too-large") for a bad file, naming it; nothing changes then.
    #[wasm_bindgen(js_name = addFaceTrack, unchecked_return_type = "FaceTrackInfo & { index: number }")]
    pub fn add_face_track(&mut self, library: &mut Library, file_name: &str, bytes: &[u8], #[wasm_bindgen(unchecked_param_type = "{ songOffsetFrames?: number } | undefined")] options: JsValue) -> Result<JsValue, OdoriError> {
        let o: JsImportOptions = from_js(options, "face track options", &["songOffsetFrames"])?;
        let track = self.inner.add_face_track(file_name, bytes, o.song_offset_frames).map_err(|e| OdoriError { kind: e.kind(), message: e.to_string(), file: Some(file_name.to_string()) })?;
        self.changed(());
        self.face_tracks_into(library);
        let info = to_js(&crate::mmd::face_track_info(&track));
        let index = self.inner.doc().tracks(project::TrackKind::Face).count().saturating_sub(1) as u32;
        js_sys::Reflect::set(&info, &JsValue::from_str("index"), &JsValue::from(index)).map_err(|_| OdoriError::new("bad-argument", "face track info"))?;
        Ok(info)
    }

    /// Removes the project's face track `index` (in `summary().faceTracks`' order) and shows
    /// the rest in `library`. Undoable.
    #[wasm_bindgen(js_name = removeFaceTrack)]
    pub fn remove_face_track(&mut self, library: &mut Library, index: u32) -> Result<(), OdoriError> {
        self.inner.remove_face_track(index as usize)?;
        self.changed(());
        self.face_tracks_into(library);
        Ok(())
    }

    /// Shows the project's face tracks in `library` (after an import, undo/redo, or a restored
    /// project): they replace the ones shown before. Returns the problems, one message per
    /// track that cannot be read (its bytes missing from the project).
    #[wasm_bindgen(js_name = faceTracksInto)]
    pub fn face_tracks_into(&mut self, library: &mut Library) -> Vec<String> {
        let mut tracks = Vec::new();
        let mut problems = Vec::new();
        for i in 0..self.inner.doc().tracks(project::TrackKind::Face).count() {
            match self.inner.face_track(i) {
                Ok(t) => tracks.push(t),
                Err(e) => problems.push(e.to_string()),
            }
        }
        library.set_face_tracks(tracks);
        problems
    }

    /// Makes up to `count` more built-in moves of the dance library; returns the fraction
    /// made (1: all). Call between frames until 1, so the page never blocks for all 558.
    #[wasm_bindgen(js_name = loadBuiltin)]
    pub fn load_builtin(&mut self, count: u32) -> f32 {
        self.inner.load_builtin(count as usize)
    }

    /// Builds the filling's transition table over the project's segment library in slices
    /// of up to `columns` segments: the pairs the song's bars can join (the blocks of their
    /// metres, and across a metre change); returns the fraction done (1: ready). Needed again
    /// after the library changes or new bars bring in a metre not yet built; `generate` builds
    /// what is left in one go otherwise.
    #[wasm_bindgen(js_name = prepareTable)]
    pub fn prepare_table(&mut self, columns: u32) -> f32 {
        let penalty = self.inner.fill_weights().repeat_penalty;
        let scope = self.inner.table_scope();
        let lib = self.inner.segment_library();
        if lib.cached_table_for(penalty, &scope).is_some() {
            self.builder = None;
            return 1.0;
        }
        let stale = self.builder.as_ref().is_none_or(|b| b.revision() != lib.revision() || b.repeat_penalty() != penalty || !b.scope().covers(&scope));
        if stale {
            self.builder = Some(lib.table_builder_for(penalty, &scope));
        }
        let Some(builder) = self.builder.as_mut() else { return 0.0 };
        let progress = builder.step(columns.max(1) as usize);
        if !progress.is_done() {
            return progress.fraction().min(0.999);
        }
        if let Some(table) = self.builder.take().and_then(TableBuilder::finish) {
            // Refused (false) when the library or the bars changed meanwhile: the next call starts again.
            if !self.inner.segment_library().install_table_for(table, &scope) {
                return 0.0;
            }
        }
        1.0
    }

    /// Whether the transition table holds what the song's bars need (Generate then takes
    /// milliseconds).
    #[wasm_bindgen(getter, js_name = tableReady)]
    pub fn table_ready(&mut self) -> bool {
        let penalty = self.inner.fill_weights().repeat_penalty;
        let scope = self.inner.table_scope();
        self.inner.segment_library().cached_table_for(penalty, &scope).is_some()
    }

    /// Number of segments in the project's dance library.
    #[wasm_bindgen(getter, js_name = segmentCount)]
    pub fn segment_count(&mut self) -> usize {
        self.inner.segment_library().len()
    }

    /// One segment's facts (`{ index, name, source, tempoBpm, intensity01, retired, ... }`).
    pub fn segment(&mut self, index: f64) -> JsValue {
        let lib = self.inner.segment_library();
        index_arg("segment", index).ok().and_then(|i| lib.segment(i)).map(to_js).unwrap_or(JsValue::UNDEFINED)
    }

    /// The stable key (`MoveKey`) of segment `index` now, or undefined.
    #[wasm_bindgen(js_name = keyOf)]
    pub fn key_of(&mut self, index: f64) -> JsValue {
        let d = self.inner.derived();
        index_arg("segment", index).ok().and_then(|i| d.key(i)).map(to_js).unwrap_or(JsValue::UNDEFINED)
    }

    /// Each bar by segment numbers of the current library, for display: `BarView[]` (empty
    /// without a song).
    #[wasm_bindgen(js_name = danceView, unchecked_return_type = "BarView[]")]
    pub fn dance_view(&mut self) -> JsValue {
        match self.inner.dance_view() {
            Ok(view) => to_js(&view),
            Err(_) => to_js(&Vec::<u8>::new()),
        }
    }

    fn keys_of(&mut self, segments: &[f64], what: &str) -> Result<Vec<MoveKey>, OdoriError> {
        let d = self.inner.derived();
        segments
            .iter()
            .map(|&x| {
                let i = index_arg(what, x)?;
                d.key(i).cloned().ok_or_else(|| OdoriError::new("not-found", format!("no segment {i} in the library")))
            })
            .collect()
    }

    fn indices_of(&mut self, keys: &[MoveKey]) -> Vec<u32> {
        let d = self.inner.derived();
        keys.iter().filter_map(|k| d.index_of(k)).map(|i| i as u32).collect()
    }

    /// `candidates` by segment numbers (not an edit: no undo step).
    #[wasm_bindgen(js_name = candidateSegments)]
    pub fn candidate_segments(&mut self, bar: f64) -> Result<Vec<u32>, OdoriError> {
        let bar = index_arg("bar", bar)?;
        let keys = self.inner.candidates(bar)?;
        self.changed(());
        Ok(self.indices_of(&keys))
    }

    /// `search` by segment numbers: likes `liked`, returns the next round.
    #[wasm_bindgen(js_name = searchSegments)]
    pub fn search_segments(&mut self, bar: f64, liked: Vec<f64>) -> Result<Vec<u32>, OdoriError> {
        let bar = index_arg("bar", bar)?;
        let liked = self.keys_of(&liked, "liked segment")?;
        let keys = self.inner.search(bar, &liked)?;
        self.changed(());
        Ok(self.indices_of(&keys))
    }

    /// `set` by segment number: pins segment `segment` to bar `bar`.
    #[wasm_bindgen(js_name = setSegment)]
    pub fn set_segment(&mut self, bar: f64, segment: f64) -> Result<(), OdoriError> {
        let bar = index_arg("bar", bar)?;
        let key = self.keys_of(&[segment], "segment")?.remove(0);
        self.inner.set(bar, &key)?;
        Ok(self.changed(()))
    }

    /// Quality of the dance as it stands (spec §J), per bar and whole: `{ beats: { basMusic,
    /// basMusicShifted, basMotion, basMotionShifted, kineticBeatsPerSec, musicBeatsPerSec },
    /// footSkate: { meanCmPerS, p95CmPerS, contacts }, pfc, joinJumpMean, joinJumpMax, bars:
    /// [{ bar, beats, footSkate, joinJump }] }`. `beatTimesSecs`: the song's beats (the grid's
    /// `beatTimesSecs`); omitted: each bar's beats spread evenly over it.
    pub fn quality(&mut self, beat_times_secs: Option<Vec<f32>>) -> Result<JsValue, OdoriError> {
        let bars = self.inner.song_bars()?;
        let beats = beat_times_secs.unwrap_or_else(|| bars.iter().flat_map(|b| (0..b.beat_count()).map(move |k| b.start_secs + b.duration_secs() * k as f32 / b.beat_count() as f32)).collect());
        let (clip, switches) = self.inner.render_dance_switched(&RenderOptions::default())?;
        let q = odori_core::choreo::dance_quality_switched(&clip, &bars, &beats, &switches).map_err(|e| OdoriError::new("bad-argument", e.to_string()))?;
        Ok(to_js(&q))
    }

    /// Each bar's move and its weak spots in words, with the readout they come from (one
    /// render): `{ quality: DanceQuality | null, notes: MoveNote[] }`, a `MoveNote` being `{ bar,
    /// segment, name, source, builtin, flags: [{ kind: "offBeat" | "joinJump" | "footSkate",
    /// words, value, goal }], repeatsBar, repeatMarked, builtinWhy }`, `repeatsBar` the bar (from
    /// 0) whose move it repeats where the song's sections repeat (`repeats()`: found, or marked by
    /// the person), else null, and `repeatMarked` true when the person marked that repeat;
    /// `builtinWhy`, on a built-in bar under *my moves*, why no move of the person's is there
    /// (from the Generate that filled it, kept with the bar: the same after reopening and
    /// through undo), else absent; `quality` is null while no bar holds a move.
    /// `beatTimesSecs` as for `quality`.
    #[wasm_bindgen(js_name = barNotes)]
    pub fn bar_notes(&mut self, beat_times_secs: Option<Vec<f32>>) -> Result<JsValue, OdoriError> {
        #[derive(Serialize)]
        struct Notes {
            quality: Option<odori_core::choreo::DanceQuality>,
            notes: Vec<odori_core::choreo::MoveNote>,
        }
        let bars = self.inner.song_bars()?;
        let choices: Vec<Option<usize>> = self.inner.dance_view()?.iter().map(|v| v.state.segment()).collect();
        if choices.iter().all(Option::is_none) {
            return Ok(to_js(&Notes { quality: None, notes: odori_core::choreo::bar_notes(self.inner.segment_library(), &bars, &choices, &[]) }));
        }
        let beats = beat_times_secs.unwrap_or_else(|| bars.iter().flat_map(|b| (0..b.beat_count()).map(move |k| b.start_secs + b.duration_secs() * k as f32 / b.beat_count() as f32)).collect());
        let (clip, switches) = self.inner.render_dance_switched(&RenderOptions::default())?;
        let q = odori_core::choreo::dance_quality_switched(&clip, &bars, &beats, &switches).map_err(|e| OdoriError::new("bad-argument", e.to_string()))?;
        let mut notes = odori_core::choreo::bar_notes(self.inner.segment_library(), &bars, &choices, &q.bars);
        // A bar holding the move of the bar its section repeats says so, and whether the
        // person marked the repeat.
        odori_core::project::repeats::mark_notes(&mut notes, &self.inner.repeats()?);
        // A built-in bar under *my moves* says why (issue 26's preference order).
        odori_core::choreo::mark_builtin_why(&mut notes, &self.inner.builtin_why());
        Ok(to_js(&Notes { quality: Some(q), notes }))
    }

    /// The notes (`MoveNote[]`) of candidate segments `segments` for bar `bar`, each measured
    /// as the bar would play once Set, ranked clean first (among equals in the given order).
    #[wasm_bindgen(js_name = candidateNotes)]
    pub fn candidate_notes(&mut self, bar: f64, segments: Vec<f64>, beat_times_secs: Option<Vec<f32>>) -> Result<JsValue, OdoriError> {
        let bar = index_arg("bar", bar)?;
        let segments: Vec<usize> = segments.iter().map(|&s| index_arg("segment", s)).collect::<Result<_, _>>()?;
        let bars = self.inner.song_bars()?;
        let choices: Vec<Option<usize>> = self.inner.dance_view()?.iter().map(|v| v.state.segment()).collect();
        let beats = beat_times_secs.unwrap_or_else(|| bars.iter().flat_map(|b| (0..b.beat_count()).map(move |k| b.start_secs + b.duration_secs() * k as f32 / b.beat_count() as f32)).collect());
        let notes = odori_core::choreo::candidate_notes(self.inner.segment_library(), &bars, &choices, &beats, bar, &segments).map_err(|e| OdoriError::new("bad-argument", e.to_string()))?;
        Ok(to_js(&notes))
    }

    /// One segment time-resampled to `durationSecs` (a candidate preview) into `library`.
    #[wasm_bindgen(js_name = previewSegment)]
    pub fn preview_segment(&mut self, library: &mut Library, segment: f64, duration_secs: f32, replace: Option<u32>) -> Result<u32, OdoriError> {
        let segment = index_arg("segment", segment)?;
        let mut clip = segment_clip(self.inner.segment_library(), segment, duration_secs, 60.0).ok_or_else(|| OdoriError::new("not-found", format!("no segment {segment} in the library")))?;
        clip.source = "candidate".into();
        Ok(library.insert_clip(clip, "dance", replace))
    }

    /// What a player needs to play the saved dance, read by the engine (so a page never reads
    /// the document's schema): renders the dance into `library` and returns `PlayableDance`:
    /// `{ clip: ClipInfo, name, songName, demoSong, audio?: Uint8Array, characterClip,
    /// characterName }`. `audio` is the song file's bytes as given (absent for the demo song,
    /// which `DemoSong.render` makes again, the samples its grid was found on);
    /// `characterClip` is the dance put on the project's character (an imported skinned
    /// humanoid), added to `library` too, or null; `stickFigures` is true when the project chose
    /// stick figures (no character and not: the built-in body). Throws "no-song" without a song, "choreo"
    /// when no bar holds a move, "missing-blob" when the song's bytes are missing.
    #[wasm_bindgen(js_name = playInto, unchecked_return_type = "PlayableDance")]
    pub fn play_into(&mut self, library: &mut Library) -> Result<JsValue, OdoriError> {
        #[derive(Serialize)]
        #[serde(rename_all = "camelCase")]
        struct Playable<'a, C: Serialize> {
            clip: C,
            name: &'a str,
            song_name: &'a str,
            demo_song: bool,
            character_clip: Option<u32>,
            character_name: Option<String>,
            stick_figures: bool,
        }
        let doc = self.inner.doc().clone();
        let Some(song) = doc.song.as_ref() else { return Err(ProjectError::NoSong.into()) };
        if doc.dance.bars.iter().all(|b| b.state == BarKind::Empty) {
            return Err(OdoriError::new("choreo", "the project's dance is empty (no bar holds a move)"));
        }
        let audio = match &song.audio {
            None => None,
            Some(h) => Some(self.inner.blobs().get(h).map(|b| b.to_vec()).ok_or_else(|| OdoriError::new("missing-blob", format!("the song \"{}\" is missing from the project", song.file_name)))?),
        };
        let clip = self.inner.render_dance(&RenderOptions::default())?;
        let id = library.insert_clip(clip, "dance", None);
        library.mark_song_clip(id);
        // The project's character, when its file is there (a missing one plays on the built-in body).
        let (mut character_clip, mut character_name) = (None, None);
        if let Some(c) = doc.character {
            if let (Some(source), Some(imported)) = (doc.source(c.source), self.inner.imported(c.source)) {
                let before = library.size();
                let imported = imported?;
                library.add_imported(&source.file_name, &imported);
                if let Some(&character) = library.ids_from(before).get(c.clip as usize) {
                    let on = library.put_on_character(id, character)?;
                    character_clip = js_sys::Reflect::get(&on, &JsValue::from_str("id")).ok().and_then(|v| v.as_f64()).map(|v| v as u32);
                    if let Some(c) = character_clip {
                        library.mark_song_clip(c);
                    }
                    character_name = Some(source.file_name.clone());
                }
            }
        }
        let info = crate::library::info_of(library.entry(id)?);
        let out = to_js(&Playable { clip: info, name: &doc.name, song_name: &song.file_name, demo_song: song.audio.is_none(), character_clip, character_name, stick_figures: doc.stick_figures });
        if let Some(bytes) = audio {
            js_sys::Reflect::set(&out, &JsValue::from_str("audio"), &Uint8Array::from(bytes.as_slice())).map_err(|_| OdoriError::new("bad-argument", "playable dance"))?;
        }
        Ok(out)
    }

    /// Renders the dance into `library` (replacing clip `replace`) for the viewer; frame time
    /// is song time. Returns the clip id.
    #[wasm_bindgen(js_name = renderDance)]
    pub fn render_dance(&mut self, library: &mut Library, replace: Option<u32>) -> Result<u32, OdoriError> {
        let clip = self.inner.render_dance(&RenderOptions::default())?;
        let id = library.insert_clip(clip, "dance", replace);
        library.mark_song_clip(id);
        Ok(id)
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
const TS_PROJECT: &'static str = r#"
/** What `recutClip` did: the new cut, segments of the earlier cut removed and kept, and the bars
 * (0-based) that keep a move of the earlier cut. */
export interface RecutReport { clip: { clip: number; name: string; tempoBpm: number; tempoDetected: boolean; beats: number; segments: number }; removed: number; kept: number; pinnedBars: number[]; generatedBars: number[] }
/** One bar as `danceView()` shows it, by segment numbers of the project's library now. */
export interface BarView { bar: Bar; state: { kind: "empty" | "pinned" | "generated"; segment?: number }; tau: number; candidates: number[]; liked: number[]; shownCount: number; rounds: number; }
/** What `playInto` gives a player. */
export interface PlayableDance { clip: ClipInfo; name: string; songName: string; demoSong: boolean; audio?: Uint8Array; characterClip: number | null; characterName: string | null; stickFigures: boolean; }
export interface ClipRef { source: number; clip: number; }
/** What the page shows of a project (`Project.summary()`): the page reads this, never `doc()`. */
export interface ProjectSummary {
  name: string;
  /** Every source of the project, by id. */
  sources: number[];
  /** `key` changes only when the song does (not its grid corrections); `audio` is its blob hash, null for the demo song. */
  song: { fileName: string; audio: string | null; key: string; corrections: GridCorrection[] } | null;
  tags: { clip: ClipRef; tags: string[] }[];
  /** Clips put on a character, in order; `key` changes only when the recipe does. */
  worn: { key: string; character: ClipRef }[];
  character: ClipRef | null;
  stickFigures: boolean;
  texts: string[];
  rho: number;
  musicWeight: number;
  /** Camera motions (camera VMDs) kept in the project, in order; `key` changes only when one does. */
  cameras: { fileName: string; key: string }[];
  /** Face (lip-sync) tracks kept in the project (`addFaceTrack`), in order; `key` changes only when one does. */
  faceTracks: { fileName: string; key: string }[];
  /** Every MikuMikuDance file the project keeps, by name (VMD dances, their models and the models' textures, camera and face tracks): they stay in the person's `.odori` file, never in a share link. */
  mmdFiles: string[];
}
/** A face (lip-sync) track: its file, key count, the morphs it keys (each once), the motion frame that is song time 0 and the song time of its last key. */
export interface FaceTrackInfo { source: string; keys: number; morphs: string[]; songOffsetFrames: number; durationSecs: number; }
export type MoveKey =
  | { kind: "builtin"; move: { step: string; arms: string; energy: string; mirrored: boolean } }
  | { kind: "cut"; clip: ClipRef; cutTempoBpm: number | null; firstCount: number };
"#;
