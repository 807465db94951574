//! The one place Rust errors become JavaScript errors.

use odori_core::import::ImportError;
use wasm_bindgen::prelude::*;

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
            | ImportError::TooLarge { file, .. } => file.clone(),
        };
        OdoriError { kind: e.kind(), message: e.to_string(), file: Some(file) }
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
