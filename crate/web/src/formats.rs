//! The files the app opens, stated once by the engine (`importFormats()`): each format's name
//! and extension, and whether it goes to `Library.importFiles` (MMD's motions, models and zips)
//! or to a plain import (BVH, glTF, GLB). The page builds its file filters and its "not a file
//! Odori reads" message from this list (`www/ui/files.js`) instead of keeping its own.

use odori_core::import::Format;
use odori_core::mmd::files::MMD_FILE_FORMATS;
use serde::Serialize;
use wasm_bindgen::prelude::*;

#[derive(Serialize)]
#[serde(rename_all = "camelCase")]
struct ImportFormat {
    name: &'static str,
    extension: &'static str,
    mmd: bool,
    alone: bool,
}

/// Every kind of file the full engine imports, `{ name, extension, mmd, alone }[]`: the formats
/// the importer reads on their own (`alone`: BVH, glTF, GLB, VMD), then the MMD files only
/// `importFiles` takes (PMX, PMD, a zip of MMD files); `mmd`: the page hands the file to
/// `Library.importFiles` with the rest of its set.
#[wasm_bindgen(js_name = importFormats, unchecked_return_type = "ImportFormat[]")]
pub fn import_formats() -> JsValue {
    let is_mmd = |ext: &str| MMD_FILE_FORMATS.iter().any(|&(_, e)| e == ext);
    let mut out: Vec<ImportFormat> = Format::ALL
        .iter()
        .flat_map(|f| f.names().iter().zip(f.extensions()))
        .map(|(&name, &extension)| ImportFormat { name, extension, mmd: is_mmd(extension), alone: true })
        .collect();
    for (name, extension) in MMD_FILE_FORMATS {
        if !out.iter().any(|f| f.extension == extension) {
            out.push(ImportFormat { name, extension, mmd: true, alone: false });
        }
    }
    crate::error::to_js(&out)
}

#[wasm_bindgen(typescript_custom_section)]
const TS_FORMATS: &'static str = r#"
/** A kind of file the engine imports (`importFormats()`). */
export interface ImportFormat {
  /** The name a person knows it by ("BVH", "GLB", "PMX", "zip of MMD files"). */
  name: string;
  /** Its file extension, lower case, without the dot. */
  extension: string;
  /** Whether it goes to `Library.importFiles` with the rest of its MMD set. */
  mmd: boolean;
  /** Whether the importer reads it on its own (`Library.importFile`); else only with its MMD set. */
  alone: boolean;
}
"#;
