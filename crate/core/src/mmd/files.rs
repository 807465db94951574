//! A set of MikuMikuDance files brought in at once (several files, a dropped folder's files, or
//! a `.zip`): models (PMX/PMD with their textures), motions (VMD bone keys posed on a model and
//! turned into a clip on the canonical humanoid's naming) and camera motions (a [`CameraTrack`]).
//!
//! Why one entry point for a set: an MMD model needs the texture files beside it, and a VMD needs
//! the model it was made for; both usually arrive together. Each file succeeds or fails on its
//! own: a bad file becomes a [`FileProblem`] naming it (with a stable kind), the others still
//! import. Paths are compared ignoring case and `\` vs `/`, as MMD on Windows finds them.

use std::collections::HashSet;
use std::io::Read;

use glam::Vec3;
use thiserror::Error;

use super::{standard_rig, to_right_handed, MmdClipOptions, MmdMotion, MmdRig, MmdRigError, METRES_PER_MMD_UNIT};
use crate::clip::Clip;
use crate::import::mmd_bytes::MmdError;
use crate::import::mmd_model::{find_texture, read_model, MmdModel};
use crate::import::vmd::{self, Vmd};

/// The largest file taken out of a zip (a zip bomb must not fill the tab): 256 MiB.
pub const MAX_ZIP_ENTRY_BYTES: u64 = 256 << 20;
/// The most entries read from one zip.
pub const MAX_ZIP_ENTRIES: usize = 10_000;

/// What went wrong with one file of the set.
#[derive(Debug, Error, PartialEq)]
pub enum MmdFilesError {
    #[error(transparent)]
    Parse(#[from] MmdError),
    #[error("{file}: not a readable zip: {message}")]
    Zip { file: String, message: String },
    #[error("{file}: entry '{entry}' is {bytes} bytes unpacked, more than the {max} a tab takes")]
    ZipEntryTooLarge { file: String, entry: String, bytes: u64, max: u64 },
    #[error("{file}: the motion has no bone keys")]
    NoBoneKeys { file: String },
    #[error("{file}: none of its {keyed} keyed bones is a bone of {rig} (first names: {sample})")]
    NoBonesMatch { file: String, rig: String, keyed: usize, sample: String },
    #[error("{file}: model '{model}': {source}")]
    Rig { file: String, model: String, source: MmdRigError },
    #[error("{file}: textures not among the files given: {missing} (the model is kept; give the folder or zip that holds them)")]
    MissingTextures { file: String, missing: String },
    #[error("{file}: song offset frame {offset} is past the motion's last frame {last}")]
    OffsetPastEnd { file: String, offset: u32, last: u32 },
    #[error("{file}: no model named '{model}' among the models given or in the library")]
    NoSuchModel { file: String, model: String },
}

impl MmdFilesError {
    /// A stable string for JS (`OdoriError.kind`).
    pub fn kind(&self) -> &'static str {
        match self {
            MmdFilesError::Parse(e) => e.kind(),
            MmdFilesError::Zip { .. } => "mmd-zip",
            MmdFilesError::ZipEntryTooLarge { .. } => "too-large",
            MmdFilesError::NoBoneKeys { .. } => "mmd-no-bone-keys",
            MmdFilesError::NoBonesMatch { .. } => "mmd-no-matching-bones",
            MmdFilesError::Rig { .. } => "mmd-rig",
            MmdFilesError::MissingTextures { .. } => "mmd-missing-textures",
            MmdFilesError::OffsetPastEnd { .. } => "bad-argument",
            MmdFilesError::NoSuchModel { .. } => "bad-argument",
        }
    }

    pub fn file(&self) -> &str {
        match self {
            MmdFilesError::Parse(e) => e.file(),
            MmdFilesError::Zip { file, .. }
            | MmdFilesError::ZipEntryTooLarge { file, .. }
            | MmdFilesError::NoBoneKeys { file }
            | MmdFilesError::NoBonesMatch { file, .. }
            | MmdFilesError::Rig { file, .. }
            | MmdFilesError::MissingTextures { file, .. }
            | MmdFilesError::OffsetPastEnd { file, .. }
            | MmdFilesError::NoSuchModel { file, .. } => file,
        }
    }
}

/// One problem of the set, as the UI shows it.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct FileProblem {
    pub file: String,
    pub kind: &'static str,
    pub message: String,
}

impl From<&MmdFilesError> for FileProblem {
    fn from(e: &MmdFilesError) -> Self {
        FileProblem { file: e.file().to_string(), kind: e.kind(), message: e.to_string() }
    }
}

/// A PMX/PMD model with the texture files it names that were found in the set.
#[derive(Clone, Debug, PartialEq)]
pub struct ImportedModel {
    /// The model file's path as given (inside a zip: `zip name/entry`).
    pub file: String,
    pub model: MmdModel,
    /// (path the model names, the file's path in the set, its bytes) for each texture found.
    pub textures: Vec<(String, String, Vec<u8>)>,
    /// Texture paths the model names that were not in the set.
    pub missing_textures: Vec<String>,
    /// The model file's bytes as given, so a host can keep the model with a project dance
    /// later (`Project::add_source_on`) without asking for the file again.
    pub bytes: Vec<u8>,
    /// (the file's path in the set, its bytes) of each of MMD's shared toon ramps
    /// (`toon01.bmp` … `toon10.bmp`) the model's materials use that the set held.
    pub shared_toons: Vec<(String, Vec<u8>)>,
}

impl ImportedModel {
    /// The files the model draws with, as [`super::mesh::model_character`] takes them (path the
    /// model names — `toonNN.bmp` for a shared ramp —, path in the set, bytes): its textures and
    /// the shared toon ramps it uses. What a project keeps with a dance posed on the model
    /// (`Project::add_source_with_model`), so a reopened project draws it textured.
    pub fn drawn_files(&self) -> Vec<(String, String, Vec<u8>)> {
        drawn_list(&self.textures, &self.shared_toons)
    }
}

/// Textures then shared toon ramps (named `toonNN.bmp`), a ramp the textures hold under that
/// name left out.
fn drawn_list(textures: &[(String, String, Vec<u8>)], shared_toons: &[(String, Vec<u8>)]) -> Vec<(String, String, Vec<u8>)> {
    use crate::import::mmd_model::normalize_texture_path;
    let toon_name = |p: &str| normalize_texture_path(p).rsplit('/').next().unwrap_or_default().to_string();
    let named = |n: &str| textures.iter().any(|(t, _, _)| normalize_texture_path(t) == n);
    let toons = shared_toons.iter().map(|(p, b)| (toon_name(p), p.clone(), b.clone())).filter(|(n, _, _)| !named(n));
    textures.iter().cloned().chain(toons).collect()
}

/// MMD's shared toon ramps the model's materials use (`toonNN.bmp`, which MMD ships and models
/// name by number), found among `files` by file name: (path in the set, bytes), once each.
pub fn shared_toon_files(model: &MmdModel, files: &[(String, Vec<u8>)]) -> Vec<(String, Vec<u8>)> {
    use crate::import::mmd_model::{normalize_texture_path, Toon};
    let base = |p: &str| normalize_texture_path(p).rsplit('/').next().unwrap_or_default().to_string();
    let mut out: Vec<(String, Vec<u8>)> = Vec::new();
    for m in &model.materials {
        let Toon::Shared(k) = m.toon else { continue };
        let name = format!("toon{:02}.bmp", k as u32 + 1);
        if out.iter().any(|(p, _)| base(p) == name) {
            continue;
        }
        if let Some((p, b)) = files.iter().find(|(p, _)| base(p) == name) {
            out.push((p.clone(), b.clone()));
        }
    }
    out
}

/// A VMD's bone keys posed on a rig: the clip, where it was posed, and what was set aside.
#[derive(Clone, Debug, PartialEq)]
pub struct ImportedMotion {
    pub file: String,
    pub clip: Clip,
    /// The model name the VMD header names ("" when none).
    pub header_model: String,
    /// The rig it was posed on: a model's name, or [`STANDARD_RIG`].
    pub rig: String,
    /// Keyed bone names the rig lacks (their keys are ignored, as three.js ignores them).
    pub unmatched_bones: Vec<String>,
    pub matched_bones: usize,
    /// Morph (face) keys kept aside: the clip carries bones only (a viewer plays them on an MMD
    /// model's face, `super::morph`; the VMD export writes them back).
    pub morph_keys: usize,
    /// Camera keys in the same file (a camera track is made of them too).
    pub camera_keys: usize,
    /// The motion frame that is song time 0 (the clip starts there), when one was given.
    pub song_offset_frames: Option<u32>,
    /// The parsed file, kept so the motion can be written back or its morphs played later.
    pub vmd: Vmd,
}

/// The name [`ImportedMotion::rig`] gives the built-in standard skeleton.
pub const STANDARD_RIG: &str = "standard MMD skeleton";

/// One camera key in the engine's frame (right-handed, Y up, metres).
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "camelCase")]
pub struct CameraTrackKey {
    pub time_secs: f32,
    /// The point the camera looks at, metres.
    pub target_m: Vec3,
    /// MMD's camera rotation (x pitch, y yaw, z roll), radians, converted as positions are.
    pub rotation_rad: Vec3,
    /// Distance from the target along the view axis, metres (MMD stores it negative: in front).
    pub distance_m: f32,
    pub fov_deg: f32,
    pub perspective: bool,
    /// The span's easing (x1, y1, x2, y2 per channel X, Y, Z, rotation, distance, fov; 0–127).
    pub curves: [[u8; 4]; 6],
}

/// A camera motion, plain data: what a camera director can play.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "camelCase")]
pub struct CameraTrack {
    pub name: String,
    pub source: String,
    pub keys: Vec<CameraTrackKey>,
}

impl CameraTrack {
    /// The camera keys of a VMD, sorted by time (None when it has none).
    pub fn from_vmd(file: &str, vmd: &Vmd, offset_frames: u32) -> Option<CameraTrack> {
        if vmd.camera_keys.is_empty() {
            return None;
        }
        let mut keys: Vec<CameraTrackKey> = vmd
            .camera_keys
            .iter()
            .map(|k| {
                let c = &k.curves;
                let curves = [c.x, c.y, c.z, c.rotation, c.distance, c.fov].map(|b| [b.x1, b.y1, b.x2, b.y2]);
                CameraTrackKey {
                    time_secs: (k.frame as f32 - offset_frames as f32) / vmd::VMD_FPS,
                    target_m: to_right_handed(k.target) * METRES_PER_MMD_UNIT,
                    rotation_rad: Vec3::new(-k.rotation_rad.x, -k.rotation_rad.y, k.rotation_rad.z),
                    distance_m: k.distance * METRES_PER_MMD_UNIT,
                    fov_deg: k.fov_deg as f32,
                    perspective: !k.perspective_off,
                    curves,
                }
            })
            .collect();
        keys.sort_by(|a, b| a.time_secs.total_cmp(&b.time_secs));
        Some(CameraTrack { name: crate::import::stem(file).to_string(), source: file.to_string(), keys })
    }
}

/// How the set's motions are posed.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct MmdFilesOptions {
    /// Pose every VMD on this model (a model name, or [`STANDARD_RIG`]) instead of the one its
    /// header names: what the import dialog asks when that is ambiguous.
    pub model: Option<String>,
    /// The motion frame that is song time 0 (WAVEFILE's is 160): the clip starts there.
    pub song_offset_frames: Option<u32>,
}

/// Everything the set gave, and what went wrong with which file.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct MmdFilesImport {
    pub models: Vec<ImportedModel>,
    pub motions: Vec<ImportedMotion>,
    pub cameras: Vec<CameraTrack>,
    /// VMDs of face (morph) keys and no bone keys (lip-sync files): no motion of their own,
    /// offered as a face track of the project (`Project::add_face_track`).
    pub face_tracks: Vec<super::face_track::FaceTrack>,
    /// Things set aside or chosen (morph keys not played, a motion posed on the standard skeleton).
    pub notices: Vec<String>,
    pub problems: Vec<FileProblem>,
}

/// What a file of the set is, from its name's extension.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MmdFileKind {
    Vmd,
    Model,
    Zip,
    /// Anything else: a possible texture (bmp, tga, png, jpg, spa, sph …).
    Other,
}

/// The MMD files [`import_files`] takes as a set (besides the textures beside a model), as a
/// person knows them and by their extension (lower case, no dot; [`kind_of`] reads it): what a
/// page's file chooser hands to `importFiles` (the web crate's `importFormats()`).
pub const MMD_FILE_FORMATS: [(&str, &str); 4] = [("VMD", "vmd"), ("PMX", "pmx"), ("PMD", "pmd"), ("zip of MMD files", "zip")];

pub fn kind_of(name: &str) -> MmdFileKind {
    let lower = name.to_ascii_lowercase();
    match lower.rsplit('.').next() {
        Some("vmd") => MmdFileKind::Vmd,
        Some("pmx") | Some("pmd") => MmdFileKind::Model,
        Some("zip") => MmdFileKind::Zip,
        _ => MmdFileKind::Other,
    }
}

/// Whether a file name is one [`import_files`] takes as MMD (a VMD, PMX or PMD).
pub fn is_mmd_file(name: &str) -> bool {
    matches!(kind_of(name), MmdFileKind::Vmd | MmdFileKind::Model)
}

/// A zip entry's name: UTF-8 when flagged or valid, else Shift-JIS (Japanese zips name their
/// files in cp932 without the UTF-8 flag).
fn entry_name(raw: &[u8]) -> String {
    match std::str::from_utf8(raw) {
        Ok(s) => s.to_string(),
        Err(_) => encoding_rs::SHIFT_JIS.decode(raw).0.into_owned(),
    }
}

/// The files of a zip, as `zip name/entry` paths.
pub fn unzip(file: &str, bytes: &[u8]) -> Result<Vec<(String, Vec<u8>)>, MmdFilesError> {
    let zerr = |e: zip::result::ZipError| MmdFilesError::Zip { file: file.to_string(), message: e.to_string() };
    let mut z = zip::ZipArchive::new(std::io::Cursor::new(bytes)).map_err(zerr)?;
    if z.len() > MAX_ZIP_ENTRIES {
        return Err(MmdFilesError::Zip { file: file.into(), message: format!("{} entries, more than {MAX_ZIP_ENTRIES}", z.len()) });
    }
    let mut out = Vec::new();
    for i in 0..z.len() {
        let mut f = z.by_index(i).map_err(zerr)?;
        if f.is_dir() {
            continue;
        }
        let name = entry_name(f.name_raw());
        if f.size() > MAX_ZIP_ENTRY_BYTES {
            return Err(MmdFilesError::ZipEntryTooLarge { file: file.into(), entry: name, bytes: f.size(), max: MAX_ZIP_ENTRY_BYTES });
        }
        let mut buf = Vec::with_capacity(f.size() as usize);
        // Read at most one byte past the limit: a lying header cannot make this unbounded.
        (&mut f).take(MAX_ZIP_ENTRY_BYTES + 1).read_to_end(&mut buf).map_err(|e| MmdFilesError::Zip { file: file.into(), message: format!("{name}: {e}") })?;
        if buf.len() as u64 > MAX_ZIP_ENTRY_BYTES {
            return Err(MmdFilesError::ZipEntryTooLarge { file: file.into(), entry: name, bytes: buf.len() as u64, max: MAX_ZIP_ENTRY_BYTES });
        }
        out.push((format!("{file}/{name}"), buf));
    }
    Ok(out)
}

/// The folder part of a path (up to its last `/` or `\`), "" for none.
fn folder(path: &str) -> &str {
    path.rfind(['/', '\\']).map_or("", |i| &path[..i])
}

/// A path relative to `dir` when it lies inside it.
fn relative_to<'a>(path: &'a str, dir: &str) -> Option<&'a str> {
    if dir.is_empty() {
        return Some(path);
    }
    let rest = path.get(dir.len()..)?;
    if !path.get(..dir.len())?.eq_ignore_ascii_case(dir) {
        return None;
    }
    rest.strip_prefix(['/', '\\'])
}

/// Reads a model and finds the textures it names among `files` (paths relative to the model's
/// folder, ignoring case and separator). Missing textures are a problem, not a failure.
fn import_model(file: &str, bytes: &[u8], files: &[(String, Vec<u8>)]) -> Result<(ImportedModel, Option<MmdFilesError>), MmdFilesError> {
    let model = read_model(file, bytes)?;
    let (textures, missing) = find_textures(file, &model, files);
    let problem = (!missing.is_empty()).then(|| MmdFilesError::MissingTextures { file: file.into(), missing: missing.join(", ") });
    let shared_toons = shared_toon_files(&model, files);
    Ok((ImportedModel { file: file.into(), model, textures, missing_textures: missing, bytes: bytes.to_vec(), shared_toons }, problem))
}

/// The textures model `file` names, found among `files` (paths relative to the model's folder,
/// ignoring case and separator): (path the model names, path in the set, bytes) of each found,
/// and the paths not found (MMD's shared toon ramps, which ship with MMD, are not missing).
pub fn find_textures(file: &str, model: &MmdModel, files: &[(String, Vec<u8>)]) -> (Vec<(String, String, Vec<u8>)>, Vec<String>) {
    let dir = folder(file);
    let rel: Vec<(usize, &str)> = files.iter().enumerate().filter_map(|(i, (p, _))| relative_to(p, dir).map(|r| (i, r))).collect();
    let names: Vec<&str> = rel.iter().map(|(_, r)| *r).collect();
    let mut textures = Vec::new();
    let mut missing = Vec::new();
    for t in &model.textures {
        // MMD's shared toon ramps (toon01.bmp … toon10.bmp) ship with MMD, not with models.
        let shared_toon = t.len() <= 10 && t.to_ascii_lowercase().starts_with("toon") && find_texture(t, &names).is_none();
        match find_texture(t, &names) {
            Some(k) => {
                let (i, _) = rel[k];
                textures.push((t.clone(), files[i].0.clone(), files[i].1.clone()));
            }
            None if shared_toon || t.trim().is_empty() => {}
            None => missing.push(t.clone()),
        }
    }
    (textures, missing)
}

/// The files model `file` draws with among `files`, as [`ImportedModel::drawn_files`] lists
/// them: its textures ([`find_textures`]) and the shared toon ramps it uses.
pub fn drawn_files_in(file: &str, model: &MmdModel, files: &[(String, Vec<u8>)]) -> Vec<(String, String, Vec<u8>)> {
    let (textures, _) = find_textures(file, model, files);
    drawn_list(&textures, &shared_toon_files(model, files))
}

/// Poses one parsed VMD on the model chosen by `options.model`, else the model its header names
/// (among `models`), else the standard skeleton.
pub fn pose_vmd(file: &str, vmd: Vmd, models: &[&MmdModel], options: &MmdFilesOptions) -> Result<ImportedMotion, MmdFilesError> {
    let motion = MmdMotion::from_vmd(&vmd);
    if motion.bones.is_empty() {
        return Err(MmdFilesError::NoBoneKeys { file: file.into() });
    }
    let chosen: Option<&MmdModel> = match options.model.as_deref() {
        Some(STANDARD_RIG) => None,
        Some(name) => Some(models.iter().copied().find(|m| m.name == name).ok_or_else(|| MmdFilesError::NoSuchModel { file: file.into(), model: name.into() })?),
        None => models.iter().copied().find(|m| !vmd.model_name.is_empty() && m.name == vmd.model_name),
    };
    let rig = match chosen {
        Some(m) => MmdRig::from_model(m).map_err(|source| MmdFilesError::Rig { file: file.into(), model: m.name.clone(), source })?,
        None => standard_rig(),
    };
    let rig_name = if chosen.is_some() { rig.name.clone() } else { STANDARD_RIG.to_string() };
    let unmatched = motion.unmatched_bones(&rig);
    let keyed: HashSet<&str> = motion.bones.iter().filter(|b| !b.keys.is_empty()).map(|b| b.bone.as_str()).collect();
    let matched = keyed.len().saturating_sub(unmatched.iter().collect::<HashSet<_>>().len());
    if matched == 0 {
        let sample = unmatched.iter().take(5).cloned().collect::<Vec<_>>().join(", ");
        return Err(MmdFilesError::NoBonesMatch { file: file.into(), rig: rig_name, keyed: keyed.len(), sample });
    }
    let last = motion.last_frame();
    if let Some(offset) = options.song_offset_frames.filter(|&o| o > last) {
        return Err(MmdFilesError::OffsetPastEnd { file: file.into(), offset, last });
    }
    let opts = MmdClipOptions { name: crate::import::stem(file).to_string(), source: file.into(), ..Default::default() };
    let mut clip = rig.motion_to_clip(&motion, &opts).map_err(|source| MmdFilesError::Rig { file: file.into(), model: rig_name.clone(), source })?;
    if let Some(o) = options.song_offset_frames.filter(|&o| o > 0) {
        let name = clip.name.clone();
        clip = clip.slice(o as usize, clip.frame_count(), name);
    }
    Ok(ImportedMotion {
        file: file.into(),
        clip,
        header_model: vmd.model_name.clone(),
        rig: rig_name,
        unmatched_bones: unmatched,
        matched_bones: matched,
        morph_keys: vmd.morph_keys.len(),
        camera_keys: vmd.camera_keys.len(),
        song_offset_frames: options.song_offset_frames,
        vmd,
    })
}

/// The model a project's VMD dance is posed on ([`import_vmd_source_on`]).
#[derive(Clone, Copy, Debug)]
pub enum SourceModel<'a> {
    /// The built-in standard MMD skeleton.
    Standard,
    /// A PMX/PMD model file (name, bytes): the dance is posed with its bones and IK, and drawn
    /// on its mesh with the files given with it (as [`ImportedModel::drawn_files`] lists them:
    /// its textures and shared toon ramps; none: its materials' colours).
    File(&'a str, &'a [u8], &'a [(String, String, Vec<u8>)]),
    /// The project names a model file whose bytes are missing: posed on the standard skeleton,
    /// with a warning naming it.
    Missing(&'a str),
}

/// A VMD dance as a project source, like a BVH or GLB ([`crate::import::import_bytes`] sends VMD
/// bytes here): posed on the built-in standard MMD skeleton, starting at `song_offset_frames`
/// when given. See [`import_vmd_source_on`] for a dance on its model.
pub fn import_vmd_source(file: &str, bytes: &[u8], song_offset_frames: Option<u32>) -> Result<crate::import::Imported, crate::import::ImportError> {
    import_vmd_source_on(file, bytes, song_offset_frames, SourceModel::Standard)
}

/// A VMD dance as a project source posed on `model`: the model file the project keeps with it
/// (so a reopened project poses it on that model again, on any machine), or the standard MMD
/// skeleton (none given, or its bytes missing: then a warning says so). Morph keys and keyed
/// bones the rig lacks are warnings; a file (the VMD or the model) that cannot be read or posed
/// is an [`ImportError::Mmd`] with its [`MmdFilesError::kind`].
pub fn import_vmd_source_on(file: &str, bytes: &[u8], song_offset_frames: Option<u32>, model: SourceModel<'_>) -> Result<crate::import::Imported, crate::import::ImportError> {
    use crate::import::{finish, Format, ImportError};
    let err = |e: MmdFilesError| ImportError::Mmd { file: e.file().to_string(), kind: e.kind(), message: e.to_string() };
    let vmd = vmd::read(file, bytes).map_err(|e| err(e.into()))?;
    let mut warnings = Vec::new();
    let parsed = match model {
        SourceModel::File(model_file, model_bytes, _) => Some(read_model(model_file, model_bytes).map_err(|e| err(e.into()))?),
        SourceModel::Missing(model_file) => {
            warnings.push(format!("{file}: its model {model_file} is missing from the project: posed on the {STANDARD_RIG} instead"));
            None
        }
        SourceModel::Standard => None,
    };
    let rig = parsed.as_ref().map_or_else(|| STANDARD_RIG.to_string(), |m| m.name.clone());
    let options = MmdFilesOptions { model: Some(rig.clone()), song_offset_frames };
    let models: Vec<&MmdModel> = parsed.iter().collect();
    let m = pose_vmd(file, vmd, &models, &options).map_err(err)?;
    if m.morph_keys > 0 {
        warnings.push(format!("{file}: {} morph (face) keys kept aside: played on an MMD model's face, written back on VMD export", m.morph_keys));
    }
    if m.camera_keys > 0 {
        warnings.push(format!("{file}: {} camera keys not used by the dance", m.camera_keys));
    }
    if !m.unmatched_bones.is_empty() {
        let on = if parsed.is_some() { format!("model {rig}") } else { format!("the {STANDARD_RIG}") };
        warnings.push(format!("{file}: {} keyed bones are not in {on} and were ignored", m.unmatched_bones.len()));
    }
    // Drawn on the model's own mesh with the files kept with it (its textures and shared toon
    // ramps: schema 7); a texture not kept leaves its materials in their colour, as said.
    let mesh = match (&parsed, model) {
        (Some(pm), SourceModel::File(model_file, _, drawn)) => {
            let kept: Vec<String> = drawn.iter().map(|(n, _, _)| crate::import::mmd_model::normalize_texture_path(n)).collect();
            let shared = |t: &str| t.len() <= 10 && t.to_ascii_lowercase().starts_with("toon");
            let missing: Vec<String> = pm.textures.iter().filter(|t| !t.trim().is_empty() && !shared(t) && !kept.contains(&crate::import::mmd_model::normalize_texture_path(t))).cloned().collect();
            match crate::mmd::mesh::model_character(model_file, pm, drawn, &missing, &[]) {
                Ok(c) => {
                    if !missing.is_empty() {
                        warnings.push(format!("{file}: the project keeps the model file {model_file} without {} of its textures ({}): without the model in the library those materials are drawn in their colours", missing.len(), missing.join(", ")));
                    }
                    warnings.extend(c.notices.iter().filter(|n| !n.contains("is not in the files given")).cloned());
                    Some(c.character.mesh)
                }
                Err(e) => {
                    warnings.push(format!("{e} (the dance is posed on the model but not drawn with its mesh)"));
                    None
                }
            }
        }
        _ => None,
    };
    let skeleton = m.clip.skeleton.clone();
    finish(Format::Vmd, file, skeleton, vec![m.clip], mesh, warnings)
}

/// Imports a set of files: zips are opened; models are read with their textures; each VMD is
/// posed (see [`pose_vmd`]) on a model of the set or of `library_models`; a VMD with camera keys
/// gives a [`CameraTrack`]. Files that are neither (textures, readmes) are used as textures or
/// ignored. A bad file is a problem in the result, never a failure of the whole set.
pub fn import_files(files: &[(String, Vec<u8>)], library_models: &[&MmdModel], options: &MmdFilesOptions) -> MmdFilesImport {
    let mut out = MmdFilesImport::default();
    let mut all: Vec<(String, Vec<u8>)> = Vec::with_capacity(files.len());
    for (name, bytes) in files {
        if kind_of(name) == MmdFileKind::Zip {
            match unzip(name, bytes) {
                Ok(entries) => all.extend(entries),
                Err(e) => out.problems.push((&e).into()),
            }
        } else {
            all.push((name.clone(), bytes.clone()));
        }
    }
    for (name, bytes) in &all {
        if kind_of(name) != MmdFileKind::Model {
            continue;
        }
        match import_model(name, bytes, &all) {
            Ok((m, problem)) => {
                if let Some(p) = problem {
                    out.problems.push((&p).into());
                }
                out.models.push(m);
            }
            Err(e) => out.problems.push((&e).into()),
        }
    }
    let mut models: Vec<&MmdModel> = out.models.iter().map(|m| &m.model).collect();
    models.extend(library_models.iter().copied());
    let mut motions = Vec::new();
    let mut cameras = Vec::new();
    let mut face_tracks = Vec::new();
    let mut problems = Vec::new();
    let mut notices = Vec::new();
    for (name, bytes) in &all {
        if kind_of(name) != MmdFileKind::Vmd {
            continue;
        }
        let vmd = match vmd::read(name, bytes) {
            Ok(v) => v,
            Err(e) => {
                problems.push((&MmdFilesError::from(e)).into());
                continue;
            }
        };
        let offset = options.song_offset_frames.unwrap_or(0);
        if let Some(cam) = CameraTrack::from_vmd(name, &vmd, offset) {
            notices.push(format!("{name}: {} camera keys kept as camera track '{}'", cam.keys.len(), cam.name));
            cameras.push(cam);
            if vmd.bone_keys.is_empty() {
                continue;
            }
        }
        if vmd.bone_keys.is_empty() {
            if let Some(face) = super::face_track::FaceTrack::from_vmd(name, &vmd, offset) {
                notices.push(format!("{name}: {} morph (face) keys and no bone keys: a lip-sync, kept as a face track to add to the project", face.keys.len()));
                face_tracks.push(face);
                continue;
            }
        }
        match pose_vmd(name, vmd, &models, options) {
            Ok(m) => {
                if m.morph_keys > 0 {
                    notices.push(format!("{name}: {} morph (face) keys kept aside: played on an MMD model's face, written back on VMD export", m.morph_keys));
                }
                if m.rig == STANDARD_RIG {
                    let why = if m.header_model.is_empty() { "it names no model".to_string() } else { format!("its model '{}' is not in the library", m.header_model) };
                    notices.push(format!("{name}: posed on the {STANDARD_RIG} ({why})"));
                }
                if !m.unmatched_bones.is_empty() {
                    notices.push(format!("{name}: {} keyed bones are not in {} and were ignored", m.unmatched_bones.len(), m.rig));
                }
                motions.push(m);
            }
            Err(e) => problems.push((&e).into()),
        }
    }
    out.motions = motions;
    out.cameras = cameras;
    out.face_tracks = face_tracks;
    out.problems.extend(problems);
    out.notices = notices;
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn kinds_and_folders() {
        assert_eq!(kind_of("a/B.VMD"), MmdFileKind::Vmd);
        assert_eq!(kind_of("x.Pmx"), MmdFileKind::Model);
        assert_eq!(kind_of("x.zip"), MmdFileKind::Zip);
        assert_eq!(kind_of("tex.bmp"), MmdFileKind::Other);
        for (name, ext) in MMD_FILE_FORMATS {
            assert_ne!(kind_of(&format!("a.{}", ext.to_uppercase())), MmdFileKind::Other, "{name}");
        }
        assert_eq!(folder("m/a\\b.pmd"), "m/a");
        assert_eq!(relative_to("M/Tex/a.png", "m"), Some("Tex/a.png"));
        assert_eq!(relative_to("n/a.png", "m"), None);
        assert_eq!(relative_to("a.png", ""), Some("a.png"));
    }

    #[test]
    fn a_bad_zip_and_a_bad_vmd_are_problems_not_failures() {
        let r = import_files(&[("x.zip".into(), b"PK\x03\x04junk".to_vec()), ("a.vmd".into(), b"nope".to_vec())], &[], &MmdFilesOptions::default());
        assert_eq!(r.problems.iter().map(|p| (p.file.as_str(), p.kind)).collect::<Vec<_>>(), vec![("x.zip", "mmd-zip"), ("a.vmd", "mmd-bad-magic")]);
        assert!(r.motions.is_empty() && r.models.is_empty());
    }
}
