//! `Library`: the clips a person has loaded, addressed by numeric id.

use std::rc::Rc;

use odori_core::canon::humanoid::{Canon, HumanoidMap};
use odori_core::import::{import_bytes, Format, ImportOptions, Imported, SkinnedMesh};
use odori_core::canon::builtin;
use odori_core::{Clip, HumanoidStatus};
use serde::{Deserialize, Serialize};
use wasm_bindgen::prelude::*;

use crate::error::{from_js, to_js, JsResult, OdoriError};

pub(crate) struct Entry {
    pub id: u32,
    pub clip: Clip,
    pub format: &'static str,
    #[cfg_attr(not(feature = "authoring"), allow(dead_code))]
    pub humanoid: HumanoidMap,
    pub status: HumanoidStatus,
    /// Shared by every clip of one glTF file; the id lets the viewer upload it once.
    pub mesh: Option<(u32, Rc<SkinnedMesh>)>,
    pub bones: Vec<(usize, usize)>,
    pub head: Option<usize>,
    /// Changes whenever the clip under this id changes (a dance or text animation made
    /// again keeps its id): the viewer's character cache is keyed by it.
    pub rev: u64,
}

#[derive(Serialize)]
#[serde(rename_all = "camelCase")]
struct ClipInfo<'a> {
    id: u32,
    name: &'a str,
    source: &'a str,
    format: &'a str,
    fps: f32,
    frames: usize,
    duration_secs: f32,
    joints: usize,
    points: usize,
    humanoid: &'a HumanoidStatus,
    has_mesh: bool,
    /// The textures its mesh draws with (0: no mesh, or drawn in its materials' colours).
    mesh_textures: usize,
}

#[derive(Serialize)]
#[serde(rename_all = "camelCase")]
struct ImportReport<'a> {
    file: &'a str,
    clips: Vec<ClipInfo<'a>>,
    warnings: Vec<String>,
}

#[derive(Deserialize, Default)]
#[serde(rename_all = "camelCase", default, deny_unknown_fields)]
struct JsImportOptions {
    fps_override: Option<f32>,
    unit_scale: Option<f32>,
    gltf_fps: Option<f32>,
}

pub(crate) fn info_of(e: &Entry) -> impl Serialize + '_ {
    info(e)
}

fn info(e: &Entry) -> ClipInfo<'_> {
    ClipInfo {
        id: e.id,
        name: &e.clip.name,
        source: &e.clip.source,
        format: e.format,
        fps: e.clip.fps,
        frames: e.clip.frame_count(),
        duration_secs: e.clip.duration_secs(),
        joints: e.clip.skeleton.animated_joint_count(),
        points: e.clip.joint_count(),
        humanoid: &e.status,
        has_mesh: e.mesh.is_some(),
        mesh_textures: e.mesh.as_ref().map_or(0, |(_, m)| m.textures.len()),
    }
}

/// The motion clips loaded in this session.
#[wasm_bindgen]
pub struct Library {
    pub(crate) entries: Vec<Entry>,
    next_id: u32,
    next_rev: u64,
    /// MMD models and camera tracks (issue 28), besides the clips.
    #[cfg(feature = "authoring")]
    pub(crate) mmd: crate::mmd::MmdStore,
}

impl Default for Library {
    fn default() -> Self {
        Self::new()
    }
}

impl Library {
    pub(crate) fn push(&mut self, clip: Clip, format: &'static str, humanoid: HumanoidMap, status: HumanoidStatus, mesh: Option<(u32, Rc<SkinnedMesh>)>) -> u32 {
        let id = self.next_id;
        self.next_id += 1;
        let bones = if status.is_humanoid() { humanoid.figure_bones(&clip.skeleton) } else { clip.skeleton.bones() };
        let head = humanoid.get(Canon::Head).filter(|_| status.is_humanoid());
        let rev = self.bump_rev();
        self.entries.push(Entry { id, clip, format, humanoid, status, mesh, bones, head, rev });
        id
    }

    /// Adds a clip played by a character (put on it): drawn with the mesh of library clip
    /// `character` when that is still there (one mesh on the GPU for the character's clips),
    /// else with `mesh`, a copy of its own.
    #[cfg_attr(not(feature = "authoring"), allow(dead_code))]
    pub(crate) fn push_on_character(&mut self, clip: Clip, character: Option<u32>, mesh: Option<&SkinnedMesh>) -> u32 {
        let shared = character.and_then(|c| self.entries.iter().find(|e| e.id == c)).and_then(|e| e.mesh.clone());
        let mesh = shared.or_else(|| mesh.map(|m| (self.next_id, Rc::new(m.clone()))));
        let map = HumanoidMap::from_skeleton(&clip.skeleton);
        let status = map.status(&clip.skeleton, Some(&clip));
        self.push(clip, "character", map, status, mesh)
    }

    /// Draws clip `id` with `mesh` from now on (a clip posed on an MMD model linked to the
    /// model's mesh once the model is in the library).
    #[cfg_attr(not(feature = "authoring"), allow(dead_code))]
    pub(crate) fn set_mesh(&mut self, id: u32, mesh: (u32, Rc<SkinnedMesh>)) {
        let rev = self.bump_rev();
        if let Some(e) = self.entries.iter_mut().find(|e| e.id == id) {
            e.mesh = Some(mesh);
            e.rev = rev;
        }
    }

    /// The id the next added clip gets (a mesh shared by clips is keyed by its first clip's id).
    #[cfg_attr(not(feature = "authoring"), allow(dead_code))]
    pub(crate) fn next_id(&self) -> u32 {
        self.next_id
    }

    fn bump_rev(&mut self) -> u64 {
        self.next_rev += 1;
        self.next_rev
    }

    /// Adds a clip the engine made (text animation, a generated dance); with `replace`, it
    /// takes that clip's place and id.
    #[cfg_attr(not(feature = "authoring"), allow(dead_code))]
    pub(crate) fn insert_clip(&mut self, clip: Clip, format: &'static str, replace: Option<u32>) -> u32 {
        let map = HumanoidMap::from_skeleton(&clip.skeleton);
        let status = map.status(&clip.skeleton, Some(&clip));
        if let Some(old) = replace.and_then(|r| self.entries.iter().position(|e| e.id == r)) {
            let id = self.entries[old].id;
            let bones = if status.is_humanoid() { map.figure_bones(&clip.skeleton) } else { clip.skeleton.bones() };
            let head = map.get(Canon::Head);
            let rev = self.bump_rev();
            self.entries[old] = Entry { id, clip, format, humanoid: map, status, mesh: None, bones, head, rev };
            return id;
        }
        self.push(clip, format, map, status, None)
    }

    /// Adds every clip of an imported file; returns the `ImportReport` (clips with their ids).
    #[cfg_attr(not(feature = "authoring"), allow(dead_code))]
    pub(crate) fn add_imported(&mut self, file_name: &str, im: &Imported) -> JsValue {
        self.add_imported_on(file_name, im, None)
    }

    /// [`Library::add_imported`] drawn with `mesh` (a mesh the library already holds, shared)
    /// instead of the file's own when given.
    #[cfg_attr(not(feature = "authoring"), allow(dead_code))]
    pub(crate) fn add_imported_on(&mut self, file_name: &str, im: &Imported, mesh: Option<(u32, Rc<SkinnedMesh>)>) -> JsValue {
        let format = match im.format {
            Format::Bvh => "bvh",
            Format::Gltf => "gltf",
            Format::Vmd => "vmd",
        };
        let mesh = mesh.or_else(|| im.mesh.clone().map(|m| (self.next_id, Rc::new(m))));
        let first = self.entries.len();
        for clip in &im.clips {
            self.push(clip.clone(), format, im.humanoid.clone(), im.status.clone(), mesh.clone());
        }
        let report = ImportReport { file: file_name, clips: self.entries[first..].iter().map(info).collect(), warnings: im.warnings.clone() };
        to_js(&report)
    }

    /// Ids of the clips added since the library held `count` clips (those of the last import).
    #[cfg_attr(not(feature = "authoring"), allow(dead_code))]
    pub(crate) fn ids_from(&self, count: usize) -> Vec<u32> {
        self.entries.iter().skip(count).map(|e| e.id).collect()
    }

    pub(crate) fn entry(&self, id: u32) -> JsResult<&Entry> {
        self.entries.iter().find(|e| e.id == id).ok_or_else(|| OdoriError::new("not-found", format!("no clip with id {id} in the library")))
    }
}

#[wasm_bindgen]
impl Library {
    /// An empty library.
    #[wasm_bindgen(constructor)]
    pub fn new() -> Library {
        Library {
            entries: Vec::new(),
            next_id: 1,
            next_rev: 0,
            #[cfg(feature = "authoring")]
            mmd: Default::default(),
        }
    }

    /// Adds the engine's own demo clip; returns its `ClipInfo`.
    #[wasm_bindgen(js_name = addBuiltinDemo, unchecked_return_type = "ClipInfo")]
    pub fn add_builtin_demo(&mut self) -> JsValue {
        let clip = builtin::demo_clip();
        let map = HumanoidMap::from_skeleton(&clip.skeleton);
        let status = map.status(&clip.skeleton, Some(&clip));
        self.push(clip, "builtin", map, status, None);
        self.entries.last().map(|e| to_js(&info(e))).unwrap_or(JsValue::NULL)
    }

    /// Reads a BVH, glTF or GLB file. Adds every clip it holds and returns an
    /// `ImportReport`; on a bad file throws an `OdoriError` naming the file and the problem,
    /// and the library is left as it was.
    #[wasm_bindgen(js_name = importFile, unchecked_return_type = "ImportReport")]
    pub fn import_file(
        &mut self,
        file_name: &str,
        bytes: &[u8],
        #[wasm_bindgen(unchecked_param_type = "ImportOptions | undefined")] options: JsValue,
    ) -> Result<JsValue, OdoriError> {
        let o: JsImportOptions = from_js(options, "import options", &["fpsOverride", "unitScale", "gltfFps"])?;
        let mut opts = ImportOptions { fps_override: o.fps_override, unit_scale: o.unit_scale, ..Default::default() };
        if let Some(f) = o.gltf_fps {
            opts.gltf_fps = f;
        }
        // Option ranges are checked by the core (`ImportOptions::validate`): one rule, one message.
        let im = import_bytes(file_name, bytes, &opts)?;
        Ok(self.add_imported(file_name, &im))
    }

    /// Every clip, in the order they were added.
    #[wasm_bindgen(unchecked_return_type = "ClipInfo[]")]
    pub fn clips(&self) -> JsValue {
        to_js(&self.entries.iter().map(info).collect::<Vec<_>>())
    }

    /// One clip's `ClipInfo`.
    #[wasm_bindgen(unchecked_return_type = "ClipInfo")]
    pub fn clip(&self, id: u32) -> Result<JsValue, OdoriError> {
        Ok(to_js(&info(self.entry(id)?)))
    }

    /// Removes a clip; false when there was none with this id.
    pub fn remove(&mut self, id: u32) -> bool {
        #[cfg(feature = "authoring")]
        self.mmd.posed_on.retain(|(i, _)| *i != id);
        #[cfg(feature = "authoring")]
        self.mmd.characters.retain(|(_, i)| *i != id);
        #[cfg(feature = "authoring")]
        self.mmd.morphs.retain(|(i, _, _)| *i != id);
        #[cfg(feature = "authoring")]
        self.mmd.own_keys.retain(|(i, _)| *i != id);
        let before = self.entries.len();
        self.entries.retain(|e| e.id != id);
        self.entries.len() != before
    }

    #[wasm_bindgen(getter)]
    pub fn size(&self) -> usize {
        self.entries.len()
    }

    /// World joint positions (x, y, z per joint, metres, Y up) of a clip at a time in seconds,
    /// interpolated between frames and clamped to the clip. A time that is not a finite number
    /// (NaN, ±Infinity) is refused with a "bad-argument" error: there is no pose at NaN.
    #[wasm_bindgen(js_name = jointPositions)]
    pub fn joint_positions(&self, id: u32, time_secs: f32) -> Result<Vec<f32>, OdoriError> {
        let e = self.entry(id)?;
        if !time_secs.is_finite() {
            return Err(OdoriError::new("bad-argument", format!("jointPositions: time {time_secs} s is not a finite number")));
        }
        Ok(crate::viewer::pose_at(&e.clip, time_secs).iter().flat_map(|p| p.to_array()).collect())
    }

    /// Bones of a clip's skeleton as (parent, child) index pairs, flattened.
    pub fn bones(&self, id: u32) -> Result<Vec<u32>, OdoriError> {
        Ok(self.entry(id)?.bones.iter().flat_map(|&(a, b)| [a as u32, b as u32]).collect())
    }

    /// Joint names of a clip's skeleton.
    #[wasm_bindgen(js_name = jointNames)]
    pub fn joint_names(&self, id: u32) -> Result<Vec<String>, OdoriError> {
        Ok(self.entry(id)?.clip.skeleton.joints.iter().map(|j| j.name.clone()).collect())
    }
}
