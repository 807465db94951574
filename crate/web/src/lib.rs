//! WebAssembly bindings of the Odori engine: the only crate that knows about JavaScript.
//!
//! Two handles in every build: [`Library`] (motion clips: import, inspect, pose; no rendering,
//! usable from Node or a worker) and [`Viewer`] (wgpu on a canvas: WebGPU when the browser has
//! it, WebGL2 otherwise). The full engine adds [`Project`], the one handle that holds a dance,
//! and stateless helpers (`Song`, `DemoSong`, `SearchIndex`, `TextAnimator`). Every error becomes a JS `Error` named `OdoriError` with a `kind` and, for
//! imports, the `file`; no panic crosses into JS with a bad file (and if a bug panics, the
//! panic hook prints it to the console).

mod error;
mod export;
mod library;
mod viewer;
// Authoring (feature "authoring", on by default): left out of the player build.
#[cfg(feature = "authoring")]
mod formats;
#[cfg(feature = "authoring")]
mod mmd;
#[cfg(feature = "authoring")]
mod music;
#[cfg(feature = "authoring")]
mod project;
#[cfg(feature = "authoring")]
mod search;
#[cfg(feature = "authoring")]
mod text;

pub use error::{OdoriError, ERROR_KINDS};
pub use library::Library;
pub use viewer::Viewer;
#[cfg(feature = "authoring")]
pub use music::{DemoSong, Song};
#[cfg(feature = "authoring")]
pub use project::Project;
#[cfg(feature = "authoring")]
pub use search::SearchIndex;
#[cfg(feature = "authoring")]
pub use text::TextAnimator;

use wasm_bindgen::prelude::*;

#[wasm_bindgen(start)]
pub fn start() {
    console_error_panic_hook::set_once();
}

/// Every `kind` an `OdoriError` can have, in this build and the other (the list is the same).
#[wasm_bindgen(js_name = errorKinds, unchecked_return_type = "OdoriErrorKind[]")]
pub fn error_kinds() -> Vec<String> {
    ERROR_KINDS.iter().map(|k| k.to_string()).collect()
}

/// True in the full engine, false in the player build (no search, text, music analysis or
/// choreography).
#[wasm_bindgen(js_name = hasAuthoring)]
pub fn has_authoring() -> bool {
    cfg!(feature = "authoring")
}

/// The engine's version (the crate's).
#[wasm_bindgen]
pub fn version() -> String {
    env!("CARGO_PKG_VERSION").into()
}

/// Self-check of the search's frame-distance kernel in this build: `{ path, cases, mismatches }`
/// — the vector path compiled in ("simd128" in the web build) and how many of `cases` random
/// inputs give other bits than the scalar kernel (0 expected). For tests and bug reports.
#[wasm_bindgen(js_name = distanceKernelCheck)]
pub fn distance_kernel_check(cases: u32) -> String {
    let (path, mismatches) = odori_core::search::distance_kernel_check(cases);
    format!("{{\"path\":\"{path}\",\"cases\":{cases},\"mismatches\":{mismatches}}}")
}

#[wasm_bindgen(typescript_custom_section)]
const TS_TYPES: &'static str = r#"
/** What an Odori call throws: an Error with name "OdoriError", a machine-readable kind and, for imports, the file. */
export interface OdoriError extends Error {
  name: "OdoriError";
  /** One of `errorKinds()`. */
  kind: OdoriErrorKind;
  file?: string;
}
export type HumanoidStatus =
  | { kind: "complete" }
  | { kind: "partial"; missing: string[] }
  | { kind: "notHumanoid"; reason: string };
export interface ClipInfo {
  id: number;
  name: string;
  /** The file the clip came from, or "built-in". */
  source: string;
  format: "bvh" | "gltf" | "builtin" | "text" | "dance" | "character" | "vmd" | "mmd";
  fps: number;
  frames: number;
  /** From the first frame to the last: (frames - 1) / fps. */
  durationSecs: number;
  /** Joints of the clip's own skeleton, as the file counts them (BVH: ROOT and JOINT). */
  joints: number;
  /** Points `jointPositions` returns: the joints plus end sites / tip nodes. */
  points: number;
  humanoid: HumanoidStatus;
  /** True when the clip drives a skinned character (glTF; an MMD model, and a VMD posed on one). */
  hasMesh: boolean;
  /** The textures its mesh draws with (0: no mesh, or drawn in its materials' colours; an MMD model's kept with a project dance count too). */
  meshTextures: number;
}
export interface GenerateOptions {
  /** Which take of Generate, 0..=15 (default 0): each take above 0 is a different dance of comparable cost (issue 26). */
  take?: number;
}
export interface ImportOptions {
  /** Play at this frame rate instead of the file's (CMU salsa BVH headers say 120, the data is 60). */
  fpsOverride?: number;
  /** Metres per BVH unit, 0.0001..=10 (refused outside); guessed from the rig when absent (its joint naming and bone lengths against a person's) (a humanoid of implausible height is then reported in `warnings`). */
  unitScale?: number;
  /** Resampling rate for glTF animations (default 30). */
  gltfFps?: number;
  /** VMD (project sources): the motion frame that is song time 0 (WAVEFILE's is 160); the clip starts there. */
  songOffsetFrames?: number;
}
export interface ImportReport {
  file: string;
  clips: ClipInfo[];
  warnings: string[];
}
export interface FigureSpec {
  clip: number;
  timeSecs: number;
  /** Linear RGB 0..1; default: a distinct colour per figure. */
  color?: [number, number, number];
  /** Added to every joint, metres (side-by-side layouts). */
  offset?: [number, number, number];
  /** "auto": the clip's own skinned character when it has one, else the viewer's chosen character (`setCharacter`), else a stick figure. */
  style?: "auto" | "stick" | "mesh";
}
/** How a figure was drawn: its own mesh, the chosen imported character, the built-in body, or a stick figure. */
export type FigureBody = "own" | "character" | "builtin" | "stick";
export interface DrawnFigure {
  clip: number;
  timeSecs: number;
  body: FigureBody;
  /** Drawn vertices the face morphs moved (an MMD model playing face keys; else 0). */
  morphed: number;
  /** Morphs the project's face tracks key that the drawn MMD model lacks (their keys are ignored). */
  missingMorphs: string[];
}
export interface FigureJoints {
  /** Joint names of the skeleton the figure is posed on (the character's rig when on one). */
  names: string[];
  /** World positions, x, y, z per joint, metres. */
  positions: number[];
  /** World rotations, x, y, z, w per joint. */
  rotations: number[];
  body: FigureBody;
  /** The pose last drawn with an MMD model's springs stepped (hair and skirt where they swung to). */
  sprung: boolean;
}
export interface ExportOptions {
  /** GLB only. "auto": the clip's own character, else the built-in body for canonical clips; "builtin"; "none": skeleton only; or an imported character's clip id: the motion put on that character. */
  character?: "auto" | "builtin" | "none" | number;
  /** Export only this stretch of the clip, seconds. */
  startSecs?: number;
  endSecs?: number;
}
/** Options of `exportVrma`: a stretch of the clip, seconds. */
export interface VrmaExportOptions {
  startSecs?: number;
  endSecs?: number;
}
export interface ViewerOptions {
  /** "auto" (WebGPU if available, else WebGL2), "webgpu" or "webgl2". */
  backend?: "auto" | "webgpu" | "webgl2";
}
"#;
