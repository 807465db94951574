//! The one place Rust errors become JavaScript errors.

use odori_core::export::ExportError;
use odori_core::import::ImportError;
use odori_core::project::{FileError, ProjectError};
use wasm_bindgen::prelude::*;

/// Declares the list of error kinds once: the Rust constant [`ERROR_KINDS`] and the TypeScript
/// union `OdoriErrorKind` come from the same literals, so they cannot drift apart.
macro_rules! error_kinds {
    ($($kind:literal: $doc:expr,)*) => {
        /// Every `kind` an `OdoriError` thrown to JS can carry.
        pub const ERROR_KINDS: &[&str] = &[$($kind),*];
        #[wasm_bindgen(typescript_custom_section)]
        const TS_ERROR_KINDS: &'static str = concat!(
            "/** The `kind` of an `OdoriError` (the list is also `errorKinds()`). */\nexport type OdoriErrorKind =",
            $("\n  /** ", $doc, " */\n  | \"", $kind, "\""),*,
            ";\n"
        );
    };
}

error_kinds! {
    "empty": "import: the file is empty",
    "unknown-format": concat!("import: not a ", odori_core::import_format_names!(), " file (MMD models, PMX/PMD, and zips of MMD files: importFiles)"),
    "bvh": "import: a BVH syntax or structure error (message has line:column)",
    "gltf": "import: an invalid glTF/GLB file",
    "unsupported": "import: a valid file using something the importer does not handle",
    "invalid": "import: values that make no motion (no frames, bad frame time, ...)",
    "too-large": "import: the file declares more than a tab can hold (refused before allocation)",
    "not-found": "no clip (or segment) with this id",
    "bad-argument": "an argument or option is missing, misspelt or out of range",
    "gpu": "no WebGPU/WebGL2 adapter, device or canvas surface",
    "not-humanoid": "the clip does not map onto the canonical humanoid",
    "search": "search by example failed (bad query or parameters)",
    "query-too-long": "search: the query's shortest admissible match (half its length) is longer than every clip",
    "cancelled": "search cancelled by its progress callback",
    "index-version": "search: a stored index of another format version (it is built again)",
    "index-corrupt": "search: stored index bytes that are damaged or truncated (it is built again)",
    "callback": "a progress callback threw: the work stopped (the message is the callback's)",
    "music": "song analysis failed (bad envelope, samples or correction)",
    "choreo": "choreography: no bars yet, clip already added, bad bar or segment",
    "text": "text to animation: nothing could be animated, or a clip cannot be tagged",
    "no-song": "project: a dance edit needs a song first",
    "bad-repeat": "project: a repeat's bars are empty, out of the song, of another length than the bars they repeat, overlap them or come before them",
    "missing-blob": "project: an item's bytes were missing when the project was opened (the dance is read-only)",
    "not-odori": ".odori: not an Odori project file (no manifest, or another format)",
    "truncated": ".odori: the file ends early",
    "corrupt": ".odori: a damaged container, manifest, document or blob",
    "newer-version": ".odori: written by a newer version of Odori",
    "too-old": ".odori: written by a version too old to migrate",
    "write": ".odori: the file could not be written",
    "export-bad-clip": "export: the clip or range has no frames to export",
    "export-bad-mesh": "export: the character's mesh cannot be written",
    "export-empty-skeleton": "export: the skeleton has no joints",
    "export-encode": "export: the file could not be encoded",
    "export-no-clips": "export: nothing to export",
    "export-not-finite": "export: a position or rotation is not a finite number",
    "export-skeleton-mismatch": "export: the motion does not fit the character's skeleton",
    "export-needs-canonical": "export: this export needs a clip on the canonical humanoid",
    "export-not-humanoid": "export: VRM animation needs a humanoid clip (the message says why this one is not)",
    "character-no-skin": "character: the file has no skinned mesh",
    "character-not-humanoid": "character: the rig does not map onto the canonical humanoid",
    "character-missing-limbs": "character: the rig lacks limbs the motion needs (named in the message)",
    "motion-not-humanoid": "character: the motion to put on the character is not humanoid",
    "camera": "video camera: no frames, joints or bars to plan over, or a bad camera option or pose",
    "mmd-bad-magic": "MMD: not a VMD, PMD or PMX file (its first bytes say otherwise)",
    "mmd-bad-version": "MMD: a PMD/PMX version the reader does not take",
    "mmd-truncated": "MMD: the file ends early (the message names the section and byte)",
    "mmd-count-too-large": "MMD: a count that cannot fit the bytes left (refused before allocation)",
    "mmd-bad-value": "MMD: a bad index size, encoding or enum value (with its byte offset)",
    "mmd-index-out-of-range": "MMD: an index naming a vertex, bone, material … that is not there",
    "mmd-not-shift-jis": "VMD export: a name Shift-JIS cannot hold",
    "mmd-too-many": "VMD export: more keys than a VMD counts",
    "mmd-not-finite": "VMD export: a value that is not a finite number",
    "mmd-bad-curve": "VMD export: a Bézier control value above 127",
    "mmd-zip": "MMD import: a .zip that cannot be read",
    "mmd-no-bone-keys": "MMD import: a VMD with no bone keys to pose",
    "mmd-no-matching-bones": "MMD import: none of a VMD's bones is a bone of the model it is posed on",
    "mmd-no-camera-keys": "Camera import: a VMD with no camera keys (a dance VMD is imported as a motion)",
    "mmd-no-morph-keys": "Face track import: a VMD with no morph (face) keys to use as a lip-sync",
    "mmd-rig": "MMD import: a model whose bones or IK chains cannot be posed",
    "mmd-missing-textures": "MMD import: a model naming textures not among the files given (the model is kept)",
}

/// Builds the `OdoriError` thrown to JS.
pub struct OdoriError {
    pub kind: &'static str,
    pub message: String,
    pub file: Option<String>,
}

impl OdoriError {
    pub fn new(kind: &'static str, message: impl Into<String>) -> Self {
        OdoriError { kind, message: message.into(), file: None }
    }
}

impl From<odori_core::camera::CameraError> for OdoriError {
    fn from(e: odori_core::camera::CameraError) -> Self {
        OdoriError::new("camera", e.to_string())
    }
}

impl From<ImportError> for OdoriError {
    fn from(e: ImportError) -> Self {
        let file = match &e {
            ImportError::Empty { file }
            | ImportError::UnknownFormat { file, .. }
            | ImportError::Bvh { file, .. }
            | ImportError::Gltf { file, .. }
            | ImportError::Unsupported { file, .. }
            | ImportError::Invalid { file, .. }
            | ImportError::BadOption { file, .. }
            | ImportError::TooLarge { file, .. }
            | ImportError::Mmd { file, .. } => file.clone(),
        };
        OdoriError { kind: e.kind(), message: e.to_string(), file: Some(file) }
    }
}

impl From<ExportError> for OdoriError {
    fn from(e: ExportError) -> Self {
        OdoriError::new(e.kind(), e.to_string())
    }
}

impl From<ProjectError> for OdoriError {
    fn from(e: ProjectError) -> Self {
        match e {
            ProjectError::Import(e) => e.into(),
            other => OdoriError::new(other.kind(), other.to_string()),
        }
    }
}

impl From<FileError> for OdoriError {
    fn from(e: FileError) -> Self {
        OdoriError::new(e.kind(), e.to_string())
    }
}

impl From<OdoriError> for JsValue {
    fn from(e: OdoriError) -> JsValue {
        let err = js_sys::Error::new(&e.message);
        err.set_name("OdoriError");
        let obj: &JsValue = err.as_ref();
        let _ = js_sys::Reflect::set(obj, &"kind".into(), &e.kind.into());
        if let Some(f) = e.file {
            let _ = js_sys::Reflect::set(obj, &"file".into(), &f.into());
        }
        err.into()
    }
}

pub type JsResult<T> = Result<T, OdoriError>;

/// Decodes a JS options object with serde, naming the argument on failure. A key not in
/// `known` is an error (a misspelt option must not be ignored silently).
pub fn from_js<T: serde::de::DeserializeOwned + Default>(value: JsValue, what: &str, known: &[&str]) -> JsResult<T> {
    if value.is_undefined() || value.is_null() {
        return Ok(T::default());
    }
    if let Some(obj) = value.dyn_ref::<js_sys::Object>() {
        for key in js_sys::Object::keys(obj).iter().filter_map(|k| k.as_string()) {
            if !known.contains(&key.as_str()) {
                return Err(OdoriError::new("bad-argument", format!("{what}: unknown option '{key}' (known: {})", known.join(", "))));
            }
        }
    }
    serde_wasm_bindgen::from_value(value).map_err(|e| OdoriError::new("bad-argument", format!("{what}: {e}")))
}

pub fn to_js<T: serde::Serialize>(value: &T) -> JsValue {
    value.serialize(&serde_wasm_bindgen::Serializer::json_compatible()).unwrap_or(JsValue::NULL)
}
