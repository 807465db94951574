//! Export from the library (spec §M): any clip (an imported one, a text animation, a
//! composed dance) as GLB, VRM animation (`.vrma`) or BVH bytes, returned to JS as a `Uint8Array`; and any humanoid
//! clip put on an imported character (spec §L), so it is drawn and exported on that body.

use odori_core::canon::character::Character;
use odori_core::export::{bvh::bvh, gltf::{glb, GlbOptions}, vrma::vrma};
use odori_core::canon::humanoid::HumanoidMap;
use odori_core::import::SkinnedMesh;
use odori_core::library::body::builtin_body;
use odori_core::canon::retarget::is_canonical;
use odori_core::Clip;
use std::rc::Rc;

use serde::Deserialize;
use wasm_bindgen::prelude::*;

use crate::error::{from_js, to_js, JsResult, OdoriError};
use crate::library::Library;

#[derive(Deserialize, Default)]
#[serde(rename_all = "camelCase", default, deny_unknown_fields)]
struct JsExportOptions {
    /// "auto" (default): the clip's own character when it has one, else the built-in body
    /// when the clip is on the canonical skeleton; "builtin"; "none" (skeleton only); or the
    /// id of an imported character's clip: the motion put on that character (as the viewer
    /// draws it with `setCharacter`).
    character: Option<CharacterChoice>,
    /// Export only this stretch of the clip, seconds (a range of bars of a dance).
    start_secs: Option<f32>,
    end_secs: Option<f32>,
}

#[derive(Deserialize)]
#[serde(untagged)]
enum CharacterChoice {
    Named(String),
    Clip(u32),
}

const KNOWN: &[&str] = &["character", "startSecs", "endSecs"];
/// Options of the exports that write no mesh (VRMA): a range only.
const KNOWN_RANGE: &[&str] = &["startSecs", "endSecs"];

/// [`ranged`] for an export with options of its own (VMD).
#[cfg_attr(not(feature = "authoring"), allow(dead_code))]
pub(crate) fn ranged_clip(clip: &Clip, start_secs: Option<f32>, end_secs: Option<f32>) -> JsResult<Clip> {
    ranged(clip, &JsExportOptions { character: None, start_secs, end_secs })
}

fn ranged(clip: &Clip, o: &JsExportOptions) -> JsResult<Clip> {
    if o.start_secs.is_none() && o.end_secs.is_none() {
        return Ok(clip.clone());
    }
    let start = o.start_secs.unwrap_or(0.0);
    let end = o.end_secs.unwrap_or(clip.duration_secs());
    if !(start.is_finite() && end.is_finite() && start >= 0.0 && end > start) {
        return Err(OdoriError::new("bad-argument", format!("export range {start}..{end} s is not a stretch of the clip (0..{} s)", clip.duration_secs())));
    }
    let f0 = (start * clip.fps).round() as usize;
    let f1 = ((end * clip.fps).round() as usize + 1).min(clip.frame_count());
    if f0 >= f1 {
        return Err(OdoriError::new("bad-argument", format!("export range {start}..{end} s holds no frame of the clip (0..{} s)", clip.duration_secs())));
    }
    Ok(clip.slice(f0, f1, clip.name.clone()))
}

impl Library {
    /// The character of clip `id` (an imported skinned humanoid glTF) ready to play humanoid
    /// motion, with the library's shared mesh (its id lets the viewer upload it once). One
    /// path for *Put on*, export on a character and the viewer's chosen character.
    pub(crate) fn character_of(&self, id: u32) -> JsResult<(Character, Option<(u32, Rc<SkinnedMesh>)>)> {
        let ch = self.entry(id)?;
        let character = Character::from_parts(&ch.clip.source, ch.clip.skeleton.clone(), ch.mesh.as_ref().map(|(_, m)| m.as_ref()), &ch.humanoid, &ch.status)
            .map_err(|e| OdoriError::new(e.kind(), e.to_string()))?;
        Ok((character, ch.mesh.clone()))
    }
}

#[wasm_bindgen]
impl Library {
    /// The clip as a GLB file (glTF 2.0 binary): its skeleton as nodes, the character's mesh
    /// and skin, the motion as one animation. `options`: `{ character?: "auto" | "builtin" |
    /// "none", startSecs?, endSecs? }`; "builtin" carries a humanoid clip on a rig of its own
    /// (with no mesh) onto the canonical skeleton first, as the viewer draws it. Throws an `OdoriError` (`export-*` kinds) naming the problem.
    #[wasm_bindgen(js_name = exportGlb)]
    pub fn export_glb(&self, id: u32, #[wasm_bindgen(unchecked_param_type = "ExportOptions | undefined")] options: JsValue) -> Result<Vec<u8>, OdoriError> {
        let o: JsExportOptions = from_js(options, "export options", KNOWN)?;
        let e = self.entry(id)?;
        let named = match &o.character {
            Some(CharacterChoice::Clip(ch)) => {
                // On an imported character: the clip put on it first (the viewer's path), then
                // exported with the character's mesh and skin.
                let (character, _) = self.character_of(*ch)?;
                let on = character.retarget(&e.clip, &e.humanoid).map_err(|err| OdoriError::new(err.kind(), err.to_string()))?;
                let clip = ranged(&on, &o)?;
                return Ok(glb(&clip.skeleton, &[&clip], &GlbOptions { mesh: Some(&character.mesh) })?);
            }
            Some(CharacterChoice::Named(s)) => s.as_str(),
            None => "auto",
        };
        // The app draws a humanoid clip on a rig of its own (a BVH) on the built-in body by
        // carrying it onto the canonical skeleton: "builtin" exports what it shows. (Authoring
        // only: the player exports its own canonical dances.)
        #[cfg(feature = "authoring")]
        let carried = (named == "builtin" && e.mesh.is_none() && e.status.is_humanoid() && !is_canonical(&e.clip.skeleton))
            .then(|| odori_core::canon::retarget::to_canonical(&e.clip, &e.humanoid, e.clip.fps));
        #[cfg(feature = "authoring")]
        let source = carried.as_ref().unwrap_or(&e.clip);
        #[cfg(not(feature = "authoring"))]
        let source = &e.clip;
        let clip = ranged(source, &o)?;
        let canonical = is_canonical(&clip.skeleton);
        let body: Option<SkinnedMesh>;
        let mesh: Option<&SkinnedMesh> = match named {
            "auto" => match &e.mesh {
                Some((_, m)) => Some(m.as_ref()),
                None if canonical => {
                    body = Some(builtin_body(&clip.skeleton));
                    body.as_ref()
                }
                None => None,
            },
            "builtin" if canonical => {
                body = Some(builtin_body(&clip.skeleton));
                body.as_ref()
            }
            "builtin" => {
                return Err(OdoriError::new(
                    "export-needs-canonical",
                    format!("the built-in body is made for the canonical skeleton; clip '{}' is on its own rig of {} joints", clip.name, clip.skeleton.len()),
                ))
            }
            "none" => None,
            other => return Err(OdoriError::new("bad-argument", format!("export options: character must be \"auto\", \"builtin\", \"none\" or a character's clip id, got \"{other}\""))),
        };
        Ok(glb(&clip.skeleton, &[&clip], &GlbOptions { mesh })?)
    }

    /// The clip as a VRM animation (`.vrma`: glTF binary with `VRMC_vrm_animation`): the
    /// canonical humanoid in T-pose, rotations on every humanoid bone, translation on the hips
    /// only; a clip on another humanoid rig is carried onto the canonical skeleton first.
    /// `options`: `{ startSecs?, endSecs? }`. A clip that is not humanoid throws an
    /// `OdoriError` of kind `export-not-humanoid` saying why.
    #[wasm_bindgen(js_name = exportVrma)]
    pub fn export_vrma(&self, id: u32, #[wasm_bindgen(unchecked_param_type = "VrmaExportOptions | undefined")] options: JsValue) -> Result<Vec<u8>, OdoriError> {
        let o: JsExportOptions = from_js(options, "VRMA export options", KNOWN_RANGE)?;
        let e = self.entry(id)?;
        let clip = ranged(&e.clip, &o)?;
        Ok(vrma(&clip, &e.humanoid)?)
    }

    /// The clip as a BVH file (its own skeleton, centimetres, `Zrotation Xrotation Yrotation`).
    /// `options`: `{ startSecs?, endSecs? }`.
    #[wasm_bindgen(js_name = exportBvh)]
    pub fn export_bvh(&self, id: u32, #[wasm_bindgen(unchecked_param_type = "ExportOptions | undefined")] options: JsValue) -> Result<Vec<u8>, OdoriError> {
        let o: JsExportOptions = from_js(options, "export options", KNOWN)?;
        let e = self.entry(id)?;
        let clip = ranged(&e.clip, &o)?;
        Ok(bvh(&clip)?)
    }

    /// The motion of clip `clipId` (any humanoid clip: the dance, a text animation, a move,
    /// an imported BVH) played by the character of clip `characterId` (an imported skinned
    /// humanoid glTF), twist included. Adds the result as a new clip on the character's rig,
    /// drawn with its mesh and exported with it, and returns its `ClipInfo`. A character with
    /// no skin, not humanoid or missing limbs throws an `OdoriError` (`character-*`) saying
    /// what is missing; the library is left as it was.
    #[wasm_bindgen(js_name = putOnCharacter, unchecked_return_type = "ClipInfo")]
    pub fn put_on_character(&mut self, clip_id: u32, character_id: u32) -> Result<JsValue, OdoriError> {
        let (character, mesh) = self.character_of(character_id)?;
        let src = self.entry(clip_id)?;
        let map: HumanoidMap = src.humanoid.clone();
        let out = character.retarget(&src.clip, &map).map_err(|e| OdoriError::new(e.kind(), e.to_string()))?;
        let out_map = HumanoidMap::from_skeleton(&out.skeleton);
        let status = out_map.status(&out.skeleton, Some(&out));
        let id = self.push(out, "character", out_map, status, mesh);
        Ok(to_js(&crate::library::info_of(self.entry(id)?)))
    }
}
