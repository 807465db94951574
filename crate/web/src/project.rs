//! `Project`: one handle over the core's project (spec §K) — everything a person made, every
//! edit with undo/redo, `.odori` save and open, and the manifest + blobs that autosave writes
//! to IndexedDB. Moves are named by stable keys (`MoveKey`), never by segment numbers.

use js_sys::{Array, Float32Array, Function, Uint8Array};
use odori_core::choreo::RenderOptions;
use odori_core::music::{AnalysisOptions, GridCorrection, RmsEnvelope};
use odori_core::project::{self, BlobHash, Camera, ClipRef, MoveKey, Project as CoreProject};
use odori_core::ImportOptions;
use serde::Deserialize;
use wasm_bindgen::prelude::*;

use crate::error::{from_js, to_js, JsResult, OdoriError};
use crate::library::Library;

fn arg<T: serde::de::DeserializeOwned>(value: JsValue, what: &str) -> JsResult<T> {
    serde_wasm_bindgen::from_value(value).map_err(|e| OdoriError::new("bad-argument", format!("{what}: {e}")))
}

#[derive(Deserialize, Default)]
#[serde(rename_all = "camelCase", default, deny_unknown_fields)]
struct JsImportOptions {
    fps_override: Option<f32>,
    unit_scale: Option<f32>,
    gltf_fps: Option<f32>,
}

/// A project: what a person made, its history, and how to save it.
#[wasm_bindgen]
pub struct Project {
    inner: CoreProject,
    /// Bumped by every change, so the host knows when to autosave.
    revision: u32,
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
        Project { inner: o.project, revision: 0 }
    }
}

#[wasm_bindgen]
impl Project {
    /// An empty project.
    #[wasm_bindgen(constructor)]
    pub fn new() -> Project {
        Project { inner: CoreProject::new(), revision: 0 }
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
    /// character, camera.
    pub fn doc(&self) -> JsValue {
        to_js(self.inner.doc())
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

    /// The segment a move key names now (for previews through `Choreographer`-style calls),
    /// or undefined.
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
        let o: JsImportOptions = from_js(options, "import options", &["fpsOverride", "unitScale", "gltfFps"])?;
        let options = ImportOptions { fps_override: o.fps_override, unit_scale: o.unit_scale, gltf_fps: o.gltf_fps.unwrap_or(ImportOptions::default().gltf_fps) };
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

    /// Sets the song: file name, its bytes as given (undefined for the demo song), the RMS
    /// envelope the host computed (`hopSecs`, one `Float32Array` per band) and analysis
    /// options.
    #[wasm_bindgen(js_name = setSong)]
    pub fn set_song(&mut self, file_name: &str, audio: Option<Vec<u8>>, hop_secs: f32, bands: Array, options: JsValue) -> Result<(), OdoriError> {
        let options: AnalysisOptions = from_js(options, "analysis options", &["beatsPerBar", "minBpm", "maxBpm", "priorBpm", "priorOctaves", "tightness"])?;
        let bands = bands
            .iter()
            .enumerate()
            .map(|(i, v)| v.dyn_into::<Float32Array>().map(|a| a.to_vec()).map_err(|_| OdoriError::new("bad-argument", format!("bands[{i}] must be a Float32Array"))))
            .collect::<Result<Vec<_>, _>>()?;
        self.inner.set_song(file_name, audio.as_deref(), &RmsEnvelope { hop_secs, bands }, options)?;
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
    pub fn candidates(&mut self, bar: usize) -> Result<JsValue, OdoriError> {
        let r = self.inner.candidates(bar)?;
        Ok(self.changed(to_js(&r)))
    }

    /// Likes `liked` (keys from the current round) and returns the next round.
    pub fn search(&mut self, bar: usize, liked: JsValue) -> Result<JsValue, OdoriError> {
        let liked: Vec<MoveKey> = arg(liked, "liked")?;
        let r = self.inner.search(bar, &liked)?;
        Ok(self.changed(to_js(&r)))
    }

    #[wasm_bindgen(js_name = resetSearch)]
    pub fn reset_search(&mut self, bar: usize) -> Result<bool, OdoriError> {
        let r = self.inner.reset_search(bar)?;
        Ok(self.changed(r))
    }

    /// Pins a move (a `MoveKey`) to a bar.
    pub fn set(&mut self, bar: usize, key: JsValue) -> Result<(), OdoriError> {
        let key: MoveKey = arg(key, "key")?;
        self.inner.set(bar, &key)?;
        Ok(self.changed(()))
    }

    pub fn unpin(&mut self, bar: usize) -> Result<(), OdoriError> {
        self.inner.unpin(bar)?;
        Ok(self.changed(()))
    }

    pub fn clear(&mut self, bar: usize) -> Result<(), OdoriError> {
        self.inner.clear(bar)?;
        Ok(self.changed(()))
    }

    /// Fills every open bar: `{ filled, pinned, cost }`.
    pub fn generate(&mut self) -> Result<JsValue, OdoriError> {
        let r = self.inner.generate()?;
        Ok(self.changed(to_js(&r)))
    }

    #[wasm_bindgen(js_name = setRho)]
    pub fn set_rho(&mut self, rho: f32) -> Result<(), OdoriError> {
        self.inner.set_rho(rho)?;
        Ok(self.changed(()))
    }

    #[wasm_bindgen(js_name = setMusicWeight)]
    pub fn set_music_weight(&mut self, w: f32) -> Result<(), OdoriError> {
        self.inner.set_music_weight(w)?;
        Ok(self.changed(()))
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

    /// The character (`{ source, clip }`, or undefined for the stick figure).
    #[wasm_bindgen(js_name = setCharacter)]
    pub fn set_character(&mut self, clip: JsValue) -> Result<(), OdoriError> {
        let clip: Option<ClipRef> = if clip.is_undefined() || clip.is_null() { None } else { Some(arg(clip, "clip")?) };
        self.inner.set_character(clip)?;
        Ok(self.changed(()))
    }

    /// The camera (`{ yawRad, pitchRad, distanceM, targetM }`, or undefined); not undoable.
    #[wasm_bindgen(js_name = setCamera)]
    pub fn set_camera(&mut self, camera: JsValue) -> Result<(), OdoriError> {
        let camera: Option<Camera> = if camera.is_undefined() || camera.is_null() { None } else { Some(arg(camera, "camera")?) };
        self.inner.set_camera(camera);
        Ok(self.changed(()))
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

    /// Renders the dance into `library` (replacing clip `replace`) for the viewer; frame time
    /// is song time. Returns the clip id.
    #[wasm_bindgen(js_name = renderDance)]
    pub fn render_dance(&mut self, library: &mut Library, replace: Option<u32>) -> Result<u32, OdoriError> {
        let clip = self.inner.render_dance(&RenderOptions::default())?;
        Ok(library.insert_clip(clip, "dance", replace))
    }
}

#[wasm_bindgen(typescript_custom_section)]
const TS_PROJECT: &'static str = r#"
export interface ClipRef { source: number; clip: number; }
export type MoveKey =
  | { kind: "builtin"; move: { step: string; arms: string; energy: string; mirrored: boolean } }
  | { kind: "cut"; clip: ClipRef; cutTempoBpm: number | null; firstCount: number };
"#;
