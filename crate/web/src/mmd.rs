//! MikuMikuDance in the library (issue 28; authoring build only): `Library.importFiles` takes a
//! set of MMD files (VMD motions, PMX/PMD models with their textures, zips) and
//! `Library.exportVmd` writes any humanoid clip back as a VMD on MMD's standard bones.
//!
//! The work is in the core (`odori_core::mmd::files`, `odori_core::mmd::export`); this module
//! moves bytes across and keeps the imported models and camera tracks with the library.

use js_sys::{Array, Reflect, Uint8Array};
use odori_core::canon::humanoid::HumanoidMap;
use odori_core::mmd::export::clip_to_vmd_keeping;
use odori_core::mmd::face_track::{layer_keys, FaceTrack};
use odori_core::mmd::files::{import_files, CameraTrack, ImportedModel, MmdFilesOptions, STANDARD_RIG};
use odori_core::import::SkinnedMesh;
use odori_core::mmd::mesh::model_character;
use odori_core::mmd::morph::DrawnMorphs;
use odori_core::mmd::spring::spring_bones;
use odori_core::mmd::{standard_rig, MmdClipOptions, MmdMotion, MmdRig};
use std::rc::Rc;
use serde::{Deserialize, Serialize};
use wasm_bindgen::prelude::*;

use crate::error::{from_js, to_js, JsResult, OdoriError};
use crate::library::Library;

/// The MMD files a library holds besides its clips.
#[derive(Default)]
pub(crate) struct MmdStore {
    pub models: Vec<ImportedModel>,
    /// Camera tracks imported into the library itself (a camera VMD inside a zip).
    pub cameras: Vec<CameraTrack>,
    /// The open project's camera motions (`Project.camerasInto`): listed after `cameras`.
    pub project_cameras: Vec<CameraTrack>,
    /// Clip id → the rig (model name, or the standard skeleton) an imported VMD was posed on.
    pub posed_on: Vec<(u32, String)>,
    /// Model name → the library clip (its rest pose, with its mesh) that is the model as a
    /// character (`setCharacter`, the *Character* list).
    pub characters: Vec<(String, u32)>,
    /// Clip id → an imported VMD's face (morph) keys and the song offset its clip starts at:
    /// the viewer plays them on an MMD model's mesh (`drawn_morphs`), `exportVmd` writes them back.
    pub morphs: Vec<(u32, Vec<odori_core::import::vmd::MorphKey>, u32)>,
    /// Clip id → an imported VMD's own bone keys (bone, frame on the clip's timeline): the
    /// export's key reduction keeps them.
    pub own_keys: Vec<(u32, std::collections::HashMap<String, std::collections::HashSet<u32>>)>,
    /// Mesh key → the joints (of the model's skeleton, which its motions share) that follow by
    /// spring when the viewer draws the model (`odori_core::mmd::spring`).
    pub springs: Vec<(u32, Vec<usize>)>,
    /// Mesh key → the model's morphs laid on that mesh's drawn vertices (models with vertex
    /// morphs only): where the viewer draws a clip's face keys.
    pub drawn_morphs: Vec<(u32, Rc<DrawnMorphs>)>,
    /// The models the open project keeps with its VMD dances (`Project.clipsInto`), by name:
    /// `exportVmd` fits a project dance to its model with them when the library has no model of
    /// that name (a reopened project).
    pub project_models: Vec<odori_core::import::mmd_model::MmdModel>,
    /// The open project's face (lip-sync) tracks (`Project.faceTracksInto`), in its order: the
    /// viewer plays them on the song-time clips below, `exportVmd` writes them into their VMDs.
    pub face_tracks: Vec<FaceTrack>,
    /// Bumped whenever `face_tracks` changes (the viewer's cached faces and last frame key on it).
    pub faces_generation: u32,
    /// Clips whose time is song time and that face tracks play on: the project's dance
    /// (`renderDance`, `playInto` and the dance put on its character) and its VMD dances.
    pub song_clips: Vec<u32>,
}

impl MmdStore {
    /// Camera track `index` of `cameraTracks()`: the library's own, then the project's.
    pub fn camera(&self, index: usize) -> Option<&CameraTrack> {
        self.cameras.iter().chain(&self.project_cameras).nth(index)
    }

    pub fn camera_count(&self) -> usize {
        self.cameras.len() + self.project_cameras.len()
    }
}

#[derive(Deserialize, Default)]
#[serde(rename_all = "camelCase", default, deny_unknown_fields)]
struct JsMmdOptions {
    model: Option<String>,
    song_offset_frames: Option<u32>,
}

#[derive(Deserialize, Default)]
#[serde(rename_all = "camelCase", default, deny_unknown_fields)]
struct JsVmdExportOptions {
    model: Option<String>,
    start_secs: Option<f32>,
    end_secs: Option<f32>,
}

#[derive(Serialize)]
#[serde(rename_all = "camelCase")]
struct ModelInfo<'a> {
    name: &'a str,
    file: &'a str,
    format: &'static str,
    vertices: usize,
    bones: usize,
    morphs: usize,
    textures: Vec<&'a str>,
    missing_textures: &'a [String],
    /// The library clip that is the model as a character (null when it cannot be one).
    character_id: Option<u32>,
}

fn model_info<'a>(m: &'a ImportedModel, store: &MmdStore) -> ModelInfo<'a> {
    ModelInfo {
        name: &m.model.name,
        file: &m.file,
        format: match m.model.format {
            odori_core::import::mmd_model::ModelFormat::Pmd => "pmd",
            odori_core::import::mmd_model::ModelFormat::Pmx { .. } => "pmx",
        },
        vertices: m.model.vertices.len(),
        bones: m.model.bones.len(),
        morphs: m.model.morphs.len(),
        textures: m.textures.iter().map(|(t, _, _)| t.as_str()).collect(),
        missing_textures: &m.missing_textures,
        character_id: store.characters.iter().find(|(n, _)| *n == m.model.name).map(|(_, id)| *id),
    }
}

#[derive(Serialize)]
#[serde(rename_all = "camelCase")]
struct MotionInfo<'a> {
    clip: serde_json::Value,
    file: &'a str,
    header_model: &'a str,
    rig: &'a str,
    matched_bones: usize,
    unmatched_bones: &'a [String],
    morph_keys: usize,
    song_offset_frames: Option<u32>,
}

#[derive(Serialize)]
#[serde(rename_all = "camelCase")]
struct CameraInfo<'a> {
    name: &'a str,
    source: &'a str,
    keys: usize,
    duration_secs: f32,
}

fn camera_info(c: &CameraTrack) -> CameraInfo<'_> {
    CameraInfo { name: &c.name, source: &c.source, keys: c.keys.len(), duration_secs: c.keys.last().map_or(0.0, |k| k.time_secs) }
}

/// A face (lip-sync) track as the page sees it.
#[derive(Serialize)]
#[serde(rename_all = "camelCase")]
pub(crate) struct FaceTrackInfo<'a> {
    /// The file's name.
    source: &'a str,
    keys: usize,
    /// The morphs it keys, each once.
    morphs: Vec<String>,
    song_offset_frames: u32,
    /// Song time of its last key.
    duration_secs: f32,
}

pub(crate) fn face_track_info(t: &FaceTrack) -> FaceTrackInfo<'_> {
    FaceTrackInfo { source: &t.source, keys: t.keys.len(), morphs: t.morph_names(), song_offset_frames: t.song_offset_frames, duration_secs: t.duration_secs() }
}

/// One file of the set, as `Library.inspectMmdFiles` sees it before importing.
#[derive(Serialize)]
#[serde(rename_all = "camelCase")]
struct Inspected {
    file: String,
    kind: &'static str,
    /// A VMD's header model name, or a model's own name.
    model_name: String,
    bone_keys: usize,
    morph_keys: usize,
    camera_keys: usize,
    last_frame: u32,
    /// A VMD: whether its header's model is among the set's or the library's models.
    model_found: bool,
    error: Option<String>,
}

/// `{ name, bytes }[]` from JS.
pub(crate) fn files_from_js(files: &JsValue) -> JsResult<Vec<(String, Vec<u8>)>> {
    let arr: &Array = files.dyn_ref().ok_or_else(|| OdoriError::new("bad-argument", "importFiles: expected an array of { name, bytes }"))?;
    let mut out = Vec::with_capacity(arr.length() as usize);
    for (i, f) in arr.iter().enumerate() {
        let name = Reflect::get(&f, &"name".into()).ok().and_then(|v| v.as_string());
        let bytes = Reflect::get(&f, &"bytes".into()).ok().and_then(|v| v.dyn_into::<Uint8Array>().ok());
        match (name, bytes) {
            (Some(n), Some(b)) => out.push((n, b.to_vec())),
            _ => return Err(OdoriError::new("bad-argument", format!("importFiles: file {i} is not {{ name: string, bytes: Uint8Array }}"))),
        }
    }
    Ok(out)
}

impl Library {
    /// The spring joints of an MMD model's mesh (`None`: not an MMD model's mesh).
    pub(crate) fn spring_joints(&self, mesh_key: u32) -> Option<&[usize]> {
        self.mmd.springs.iter().find(|(k, _)| *k == mesh_key).map(|(_, j)| j.as_slice())
    }

    /// The face morphs of the MMD model whose mesh is under `mesh_key` (`None`: not an MMD
    /// model's mesh, or one without vertex morphs).
    pub(crate) fn drawn_morphs(&self, mesh_key: u32) -> Option<&Rc<DrawnMorphs>> {
        self.mmd.drawn_morphs.iter().find(|(k, _)| *k == mesh_key).map(|(_, d)| d)
    }

    /// The files the library's MMD model with file bytes `model_bytes` draws with (its textures
    /// and shared toon ramps, `ImportedModel::drawn_files`): what a project keeps with a dance
    /// posed on it. Empty when the library holds no model of those bytes.
    pub(crate) fn mmd_drawn_files(&self, model_bytes: &[u8]) -> Vec<(String, String, Vec<u8>)> {
        self.mmd.models.iter().find(|m| m.bytes == model_bytes).map(|m| m.drawn_files()).unwrap_or_default()
    }

    /// Keeps a model's morphs on its mesh under `mesh_key` (replacing any kept there before).
    pub(crate) fn keep_drawn_morphs(&mut self, mesh_key: u32, drawn: DrawnMorphs) {
        self.mmd.drawn_morphs.retain(|(k, _)| *k != mesh_key);
        if !drawn.shows_nothing() {
            self.mmd.drawn_morphs.push((mesh_key, Rc::new(drawn)));
        }
    }

    /// Clip `id`'s face (morph) keys and the motion frame the clip starts at, when it has any.
    pub(crate) fn face_keys(&self, id: u32) -> Option<(&[odori_core::import::vmd::MorphKey], u32)> {
        self.mmd.morphs.iter().find(|(i, _, _)| *i == id).map(|(_, k, o)| (k.as_slice(), *o))
    }

    /// The project's face tracks and whether they play on clip `id` (a song-time clip).
    pub(crate) fn face_tracks_on(&self, id: u32) -> &[FaceTrack] {
        if self.mmd.song_clips.contains(&id) {
            &self.mmd.face_tracks
        } else {
            &[]
        }
    }

    /// Marks clip `id` as on song time: the project's face tracks play on it.
    pub(crate) fn mark_song_clip(&mut self, id: u32) {
        if !self.mmd.song_clips.contains(&id) {
            self.mmd.song_clips.push(id);
        }
    }

    /// Shows the project's face tracks (replacing the ones shown before).
    pub(crate) fn set_face_tracks(&mut self, tracks: Vec<FaceTrack>) {
        if tracks != self.mmd.face_tracks {
            self.mmd.face_tracks = tracks;
            self.mmd.faces_generation = self.mmd.faces_generation.wrapping_add(1);
        }
    }

    /// Keeps face keys for clip `id` (a project's VMD source shown in the library).
    pub(crate) fn keep_face_keys(&mut self, id: u32, keys: Vec<odori_core::import::vmd::MorphKey>, offset_frames: u32) {
        self.mmd.morphs.retain(|(i, _, _)| *i != id);
        self.mmd.morphs.push((id, keys, offset_frames));
    }

    fn rig_named(&self, name: &str) -> JsResult<(MmdRig, String)> {
        if name == STANDARD_RIG || name == "standard" {
            return Ok((standard_rig(), String::new()));
        }
        let model = self.mmd.models.iter().map(|m| (&m.model, m.file.as_str())).chain(self.mmd.project_models.iter().map(|m| (m, "the project's model"))).find(|(m, _)| m.name == name);
        let (m, file) = model.ok_or_else(|| {
            let have: Vec<&str> = self.mmd.models.iter().map(|m| m.model.name.as_str()).collect();
            OdoriError::new("bad-argument", format!("no MMD model named '{name}' in the library (models: {}; or \"standard\")", have.join(", ")))
        })?;
        let rig = MmdRig::from_model(m).map_err(|e| OdoriError::new("mmd-rig", format!("{file}: {e}")))?;
        Ok((rig, m.name.clone()))
    }

    /// The mesh of model `name`'s character clip in the library, when that clip's skeleton is
    /// `skeleton` joint for joint (a motion posed on the model shares it; a different model of
    /// the same name does not).
    pub(crate) fn character_mesh(&self, name: &str, skeleton: &odori_core::Skeleton) -> Option<(u32, Rc<SkinnedMesh>)> {
        let (_, id) = self.mmd.characters.iter().find(|(n, _)| n == name)?;
        let e = self.entry(*id).ok()?;
        let same = e.clip.skeleton.joints.len() == skeleton.joints.len() && e.clip.skeleton.joints.iter().zip(&skeleton.joints).all(|(a, b)| a.name == b.name);
        same.then(|| e.mesh.clone()).flatten()
    }

    /// Links the clips posed on model `name` (`posed_on`) to the mesh of its character clip:
    /// a VMD imported before its model, a project dance shown before the model was imported.
    fn link_posed_to(&mut self, name: &str) {
        let posed: Vec<u32> = self.mmd.posed_on.iter().filter(|(_, r)| r == name).map(|(i, _)| *i).collect();
        for id in posed {
            let Ok(e) = self.entry(id) else { continue };
            let skeleton = e.clip.skeleton.clone();
            if let Some(mesh) = self.character_mesh(name, &skeleton) {
                if e.mesh.as_ref().map(|(k, _)| *k) != Some(mesh.0) {
                    self.set_mesh(id, mesh);
                }
            }
        }
    }

    /// Keeps the model a project dance is posed on (from `Project.clipsInto`) and links the
    /// dance's clips to it: `exportVmd`'s default model, and drawn with the library's mesh of
    /// that model when the library has one (its textures), else the mesh the project made.
    pub(crate) fn link_project_dance(&mut self, ids: &[u32], model: odori_core::import::mmd_model::MmdModel) {
        for &id in ids {
            self.mmd.posed_on.retain(|(i, _)| *i != id);
            self.mmd.posed_on.push((id, model.name.clone()));
        }
        let name = model.name.clone();
        self.mmd.project_models.retain(|m| m.name != name);
        self.mmd.project_models.push(model);
        self.link_posed_to(&name);
    }
}

#[wasm_bindgen]
impl Library {
    /// Reads a set of MikuMikuDance files — `[{ name, bytes }]`: VMD motions, PMX/PMD models with
    /// their textures (a dropped folder's files with their relative paths, several files, or a
    /// `.zip`) — without importing anything: per file its kind, the model a VMD names and
    /// whether that model is in the set or the library, key counts. What the import dialog asks from.
    #[wasm_bindgen(js_name = inspectMmdFiles)]
    pub fn inspect_mmd_files(&self, files: JsValue) -> Result<JsValue, OdoriError> {
        use odori_core::mmd::files::{kind_of, unzip, MmdFileKind};
        let files = files_from_js(&files)?;
        let mut all = Vec::new();
        let mut out = Vec::new();
        for (n, b) in files {
            if kind_of(&n) == MmdFileKind::Zip {
                match unzip(&n, &b) {
                    Ok(e) => all.extend(e),
                    Err(e) => out.push(Inspected { file: n, kind: "zip", model_name: String::new(), bone_keys: 0, morph_keys: 0, camera_keys: 0, last_frame: 0, model_found: false, error: Some(e.to_string()) }),
                }
            } else {
                all.push((n, b));
            }
        }
        let mut names: Vec<String> = self.mmd.models.iter().map(|m| m.model.name.clone()).collect();
        for (n, b) in &all {
            if kind_of(n) == MmdFileKind::Model {
                match odori_core::import::mmd_model::read_model(n, b) {
                    Ok(m) => {
                        names.push(m.name.clone());
                        out.push(Inspected { file: n.clone(), kind: "model", model_name: m.name, bone_keys: 0, morph_keys: 0, camera_keys: 0, last_frame: 0, model_found: true, error: None });
                    }
                    Err(e) => out.push(Inspected { file: n.clone(), kind: "model", model_name: String::new(), bone_keys: 0, morph_keys: 0, camera_keys: 0, last_frame: 0, model_found: false, error: Some(e.to_string()) }),
                }
            }
        }
        for (n, b) in &all {
            if kind_of(n) == MmdFileKind::Vmd {
                out.push(match odori_core::import::vmd::read(n, b) {
                    Ok(v) => Inspected {
                        file: n.clone(),
                        kind: "vmd",
                        model_found: names.contains(&v.model_name),
                        model_name: v.model_name.clone(),
                        bone_keys: v.bone_keys.len(),
                        morph_keys: v.morph_keys.len(),
                        camera_keys: v.camera_keys.len(),
                        last_frame: v.last_frame(),
                        error: None,
                    },
                    Err(e) => Inspected { file: n.clone(), kind: "vmd", model_name: String::new(), bone_keys: 0, morph_keys: 0, camera_keys: 0, last_frame: 0, model_found: false, error: Some(e.to_string()) },
                });
            }
        }
        Ok(to_js(&out))
    }

    /// Imports a set of MikuMikuDance files (see `inspectMmdFiles`). Each model is kept in the
    /// library (`mmdModels()`) and added as a character: a one-frame clip (format "mmd") of its
    /// rest pose carrying its skinned, textured mesh (`characterId`, for `setCharacter`); a
    /// missing or undecodable texture is a notice naming it. Each VMD's bone keys become a clip on the
    /// canonical humanoid's naming, posed with MMD's IK and grants on the model `options.model`
    /// names, else the one its header names, else the built-in standard MMD skeleton; camera keys
    /// become a camera track (`cameraTracks()`); morph (face) keys are kept with the motion
    /// (the viewer plays them on an MMD model's face; `exportVmd` writes them back), with a notice.
    /// `options`: `{ model?: string ("standard" for the built-in skeleton), songOffsetFrames?: number }`
    /// (the motion frame that is song time 0: the clip starts there).
    /// A VMD of morph keys and no bone keys (a lip-sync) is no motion: it is listed in
    /// `faceTracks` (`{ source, keys, morphs, songOffsetFrames, durationSecs }`), for the page to
    /// offer as the project's face track (`Project.addFaceTrack`).
    /// Returns `{ motions, models, cameras, faceTracks, notices, problems }`; a bad
    /// file is a problem `{ file, kind, message }` and the rest of the set still imports.
    #[wasm_bindgen(js_name = importFiles)]
    pub fn import_files(&mut self, files: JsValue, #[wasm_bindgen(unchecked_param_type = "MmdImportOptions | undefined")] options: JsValue) -> Result<JsValue, OdoriError> {
        let o: JsMmdOptions = from_js(options, "MMD import options", &["model", "songOffsetFrames"])?;
        let files = files_from_js(&files)?;
        let model = o.model.map(|m| if m == "standard" { STANDARD_RIG.to_string() } else { m });
        let opts = MmdFilesOptions { model, song_offset_frames: o.song_offset_frames };
        let lib_models: Vec<&odori_core::import::mmd_model::MmdModel> = self.mmd.models.iter().map(|m| &m.model).collect();
        let r = import_files(&files, &lib_models, &opts);
        let mut notices = r.notices.clone();
        // Each model as a character first (replacing one of the same name imported before), so
        // the motions posed on it carry its mesh and play on it with every bone the VMD keys.
        let mut meshes: Vec<(String, (u32, Rc<SkinnedMesh>))> = Vec::new();
        for m in &r.models {
            if let Some(at) = self.mmd.characters.iter().position(|(n, _)| *n == m.model.name) {
                let (_, old) = self.mmd.characters.remove(at);
                self.remove(old);
            }
            match model_character(&m.file, &m.model, &m.textures, &m.missing_textures, &files) {
                Ok(c) => {
                    notices.extend(c.notices.iter().cloned());
                    let still = MmdMotion { model_name: m.model.name.clone(), bones: Vec::new() };
                    let opts = MmdClipOptions { name: m.model.name.clone(), source: m.file.clone(), ..Default::default() };
                    match c.rig.motion_to_clip(&still, &opts) {
                        Ok(clip) => {
                            let joints: Vec<usize> = spring_bones(&m.model).iter().filter_map(|b| c.rig_index.iter().position(|i| i == b)).collect();
                            let mesh = (self.next_id(), Rc::new(c.character.mesh));
                            self.mmd.springs.retain(|(k, _)| *k != mesh.0);
                            self.mmd.springs.push((mesh.0, joints));
                            self.keep_drawn_morphs(mesh.0, DrawnMorphs::new(&m.model, &c.drawn_vertices).with_effects(&m.model, &c.part_material).with_rig_index(&c.rig_index));
                            for (name, kind) in odori_core::mmd::morph_effects::unplayed_morphs(&m.model) {
                                notices.push(format!("{}: morph '{name}' is a {kind} morph, which is not played", m.file));
                            }
                            let id = self.push(clip, "mmd", c.character.map.clone(), c.character.map.status(&c.character.skeleton, None), Some(mesh.clone()));
                            self.mmd.characters.push((m.model.name.clone(), id));
                            meshes.push((m.model.name.clone(), mesh));
                        }
                        Err(e) => notices.push(format!("{}: cannot be drawn: {e}", m.file)),
                    }
                }
                Err(e) => notices.push(format!("{e} (the model is kept for motions to play on and for VMD export, not drawn)")),
            }
        }
        // Clips posed on these models before (a VMD imported earlier, a project dance) now draw on them.
        for (name, _) in &meshes {
            self.link_posed_to(name);
        }
        let mut motions = Vec::new();
        for m in &r.motions {
            let map = HumanoidMap::from_skeleton(&m.clip.skeleton);
            let status = map.status(&m.clip.skeleton, Some(&m.clip));
            // The model's mesh: imported in this call, else kept from an earlier one.
            let mesh = meshes.iter().find(|(n, _)| *n == m.rig).map(|(_, mesh)| mesh.clone()).or_else(|| self.character_mesh(&m.rig, &m.clip.skeleton));
            let id = self.push(m.clip.clone(), "vmd", map, status, mesh);
            self.mmd.posed_on.push((id, m.rig.clone()));
            let offset = m.song_offset_frames.unwrap_or(0);
            let mut own: std::collections::HashMap<String, std::collections::HashSet<u32>> = std::collections::HashMap::new();
            for k in m.vmd.bone_keys.iter().filter(|k| k.frame >= offset) {
                own.entry(k.name.clone()).or_default().insert(k.frame - offset);
            }
            self.mmd.own_keys.push((id, own));
            if !m.vmd.morph_keys.is_empty() {
                self.mmd.morphs.push((id, m.vmd.morph_keys.clone(), m.song_offset_frames.unwrap_or(0)));
            }
            let info = serde_json::to_value(crate::library::info_of(self.entry(id)?)).unwrap_or(serde_json::Value::Null);
            motions.push(MotionInfo {
                clip: info,
                file: &m.file,
                header_model: &m.header_model,
                rig: &m.rig,
                matched_bones: m.matched_bones,
                unmatched_bones: &m.unmatched_bones,
                morph_keys: m.morph_keys,
                song_offset_frames: m.song_offset_frames,
            });
        }
        #[derive(Serialize)]
        #[serde(rename_all = "camelCase")]
        struct Report<'a> {
            motions: Vec<MotionInfo<'a>>,
            models: Vec<ModelInfo<'a>>,
            cameras: Vec<CameraInfo<'a>>,
            /// Face-only VMDs (lip-syncs): offered as face tracks of the project (`Project.addFaceTrack`).
            face_tracks: Vec<FaceTrackInfo<'a>>,
            notices: &'a [String],
            problems: &'a [odori_core::mmd::files::FileProblem],
        }
        let report = to_js(&Report {
            motions,
            models: r.models.iter().map(|m| model_info(m, &self.mmd)).collect(),
            cameras: r.cameras.iter().map(camera_info).collect(),
            face_tracks: r.face_tracks.iter().map(face_track_info).collect(),
            notices: &notices,
            problems: &r.problems,
        });
        // Replace a model of the same name (imported again, e.g. with its textures this time).
        for m in r.models {
            self.mmd.models.retain(|k| k.model.name != m.model.name);
            self.mmd.models.push(m);
        }
        self.mmd.cameras.extend(r.cameras);
        Ok(report)
    }

    /// `cameraTracks()[index]`, for the project's import report.
    pub(crate) fn camera_track_info(&self, index: usize) -> Result<JsValue, OdoriError> {
        self.mmd.camera(index).map(|c| to_js(&camera_info(c))).ok_or_else(|| OdoriError::new("not-found", format!("no camera track {index} (there are {})", self.mmd.camera_count())))
    }

    /// The MMD models in the library: `{ name, file, format, vertices, bones, morphs, textures, missingTextures, characterId }[]`.
    #[wasm_bindgen(js_name = mmdModels)]
    pub fn mmd_models(&self) -> JsValue {
        to_js(&self.mmd.models.iter().map(|m| model_info(m, &self.mmd)).collect::<Vec<_>>())
    }

    /// The file of MMD model `name` in the library, as it was given: `{ fileName, bytes }`, so a
    /// project dance can keep the model (`Project.importOnModelInto`) after the model was
    /// imported on its own. Only the model file: `importOnModelInto` takes the textures (and
    /// shared toon ramps) the library's model found along with it, so the project keeps them
    /// too. Throws "not-found" when there is no model of that name.
    #[wasm_bindgen(js_name = mmdModelFile, unchecked_return_type = "{ fileName: string, bytes: Uint8Array }")]
    pub fn mmd_model_file(&self, name: &str) -> Result<JsValue, OdoriError> {
        let m = self.mmd.models.iter().find(|m| m.model.name == name).ok_or_else(|| {
            let have: Vec<&str> = self.mmd.models.iter().map(|m| m.model.name.as_str()).collect();
            OdoriError::new("not-found", format!("no MMD model named '{name}' in the library (models: {})", have.join(", ")))
        })?;
        let o = js_sys::Object::new();
        let set = |k: &str, v: &JsValue| Reflect::set(&o, &JsValue::from_str(k), v).map(|_| ()).map_err(|_| OdoriError::new("bad-argument", "mmdModelFile"));
        set("fileName", &JsValue::from_str(&m.file))?;
        set("bytes", &Uint8Array::from(m.bytes.as_slice()).into())?;
        Ok(o.into())
    }

    /// The files inside a `.zip` of MMD files, `{ name, bytes }[]`, each named `zip name/entry`
    /// as `importFiles` names them (so a page can send one of them elsewhere: a camera VMD into
    /// the project). Throws "mmd-zip" for a zip that does not read, "too-large" for an entry over the limit.
    #[wasm_bindgen(js_name = unzipMmd, unchecked_return_type = "{ name: string, bytes: Uint8Array }[]")]
    pub fn unzip_mmd(file_name: &str, bytes: &[u8]) -> Result<JsValue, OdoriError> {
        let entries = odori_core::mmd::files::unzip(file_name, bytes).map_err(|e| OdoriError { kind: e.kind(), message: e.to_string(), file: Some(file_name.to_string()) })?;
        let out = Array::new();
        for (name, b) in entries {
            let o = js_sys::Object::new();
            Reflect::set(&o, &"name".into(), &JsValue::from_str(&name)).map_err(|_| OdoriError::new("bad-argument", "unzipMmd"))?;
            Reflect::set(&o, &"bytes".into(), &Uint8Array::from(b.as_slice()).into()).map_err(|_| OdoriError::new("bad-argument", "unzipMmd"))?;
            out.push(&o);
        }
        Ok(out.into())
    }

    /// Camera tracks imported from camera VMDs: `{ name, source, keys, durationSecs }[]` — the
    /// library's own (a camera VMD inside a zip), then the open project's (`Project.camerasInto`).
    #[wasm_bindgen(js_name = cameraTracks)]
    pub fn camera_tracks(&self) -> JsValue {
        to_js(&self.mmd.cameras.iter().chain(&self.mmd.project_cameras).map(camera_info).collect::<Vec<_>>())
    }

    /// One camera track's keys (time, target in metres, rotation, distance, fov, curves):
    /// plain data for a camera director.
    #[wasm_bindgen(js_name = cameraTrack)]
    pub fn camera_track(&self, index: usize) -> Result<JsValue, OdoriError> {
        self.mmd.camera(index).map(to_js).ok_or_else(|| OdoriError::new("not-found", format!("no camera track {index} (there are {})", self.mmd.camera_count())))
    }

    /// Whether clip `id` came from an MMD file (its creators' terms usually forbid
    /// redistribution: it must not go in a share link).
    #[wasm_bindgen(js_name = isMmd)]
    pub fn is_mmd(&self, id: u32) -> bool {
        // An imported VMD (a project source is posed on the standard skeleton, format "vmd"), or a model as a character.
        self.mmd.posed_on.iter().any(|(i, _)| *i == id) || self.mmd.characters.iter().any(|(_, i)| *i == id) || self.entry(id).is_ok_and(|e| e.format == "vmd")
    }

    /// Clip `id` (any humanoid clip: an imported motion, a text animation, a dance) as a VMD on
    /// MMD's standard bones (センター, 下半身, 上半身, 首, 頭, 肩, 腕, ひじ, 手首, 足, ひざ, 足首; 全ての親,
    /// グルーブ, 上半身2 where the model has them) with the legs also as 足ＩＫ / つま先ＩＫ keys,
    /// fit to `options.model` (an MMD model in the library, or "standard"); by default the
    /// model an imported VMD was posed on, else the standard skeleton. `{ model?, startSecs?, endSecs? }`.
    #[wasm_bindgen(js_name = exportVmd)]
    pub fn export_vmd(&self, id: u32, #[wasm_bindgen(unchecked_param_type = "VmdExportOptions | undefined")] options: JsValue) -> Result<Vec<u8>, OdoriError> {
        let o: JsVmdExportOptions = from_js(options, "VMD export options", &["model", "startSecs", "endSecs"])?;
        let e = self.entry(id)?;
        let model = o.model.clone().or_else(|| self.mmd.posed_on.iter().find(|(i, _)| *i == id).map(|(_, r)| r.clone())).unwrap_or_else(|| STANDARD_RIG.to_string());
        let (rig, header) = self.rig_named(&model)?;
        let clip = crate::export::ranged_clip(&e.clip, o.start_secs, o.end_secs)?;
        // An imported VMD keeps its own keys (on the exported range's timeline) and its face keys.
        let start = (o.start_secs.unwrap_or(0.0).max(0.0) * 30.0).round() as u32;
        let own = self.mmd.own_keys.iter().find(|(i, _)| *i == id).map(|(_, k)| k);
        let keep = |bone: &str, frame: u32| own.and_then(|k| k.get(bone)).is_some_and(|f| f.contains(&(frame + start)));
        let mut vmd = clip_to_vmd_keeping(&clip, &rig, &header, &keep).map_err(|err| OdoriError::new(err.kind(), err.to_string()))?;
        if let Some((_, morphs, offset)) = self.mmd.morphs.iter().find(|(i, _, _)| *i == id) {
            odori_core::mmd::export::put_morph_keys(&mut vmd, morphs, offset.saturating_add(start));
        }
        // The project's face tracks over the clip's own face keys (a clip on song time: the dance).
        for t in self.face_tracks_on(id) {
            vmd.morph_keys = layer_keys(std::mem::take(&mut vmd.morph_keys), &t.keys_from(start));
        }
        let file = format!("{}.vmd", e.clip.name);
        odori_core::export::vmd::write(&file, &vmd).map_err(|err| OdoriError { kind: err.kind(), message: err.to_string(), file: Some(file) })
    }
}

#[wasm_bindgen(typescript_custom_section)]
const TS_MMD: &'static str = r#"
/** Options of `importFiles`. */
export interface MmdImportOptions {
  /** The model every VMD of the set plays on (a model name in the set or library, or "standard" for the built-in standard MMD skeleton); default: the model the VMD's header names, else the standard skeleton. */
  model?: string;
  /** The motion frame that is song time 0 (WAVEFILE's is 160): the clip starts there. */
  songOffsetFrames?: number;
}
/** Options of `exportVmd`. */
export interface VmdExportOptions {
  /** The MMD model in the library whose rest pose the keys fit, or "standard"; default: the model an imported VMD was posed on, else the standard skeleton. */
  model?: string;
  startSecs?: number;
  endSecs?: number;
}
"#;
