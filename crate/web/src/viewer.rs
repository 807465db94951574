//! `Viewer`: the wgpu renderer on a canvas, fed from a `Library` once per frame.
//!
//! A chosen character (`setCharacter`: the built-in body or an imported skinned humanoid)
//! plays every humanoid clip that has no mesh of its own — the dance, the six candidates, text
//! animations, BVH moves — through the core's retargeting (the path *Put on* and export on a
//! character take), so the figure on screen is what an export gives. The retargeted clips are
//! kept per library clip and made again when that clip changes (its revision) or the
//! character does; a figure drawn with style "stick" is the stick figure as before.
//!
//! A long clip (the whole dance: 11–61 ms onto Xbot) is not retargeted inside `draw` or
//! `frameFigures`, which a page calls from its animation frames and input handlers: the
//! figure keeps the clip's previous retargeting (or a stick figure, the first time) and the
//! clip is listed in `bodiesPending`; the page calls `prepareBodies` in a task of its own,
//! between frames, then draws again. Short clips (moves, candidates) are made at once.
//!
//! `Viewer.create` starts the renderer a step per task of the event loop (the canvas and
//! adapter, the device, then each pipeline the first frame draws with, made and drawn with
//! once), so no one task holds a page's main thread for the sum of them; the skinned-mesh
//! pipeline is made by `warmUp` or when a character is first drawn.
//!
//! An MMD model's face morphs play from the drawn clip's face keys (an imported VMD's, or a
//! project VMD source's; a generated dance has none): at the drawn time the core gives each
//! keyed morph's weight and the offsets they put on the mesh's drawn vertices
//! (`odori_core::mmd::morph`), which the renderer adds before skinning (`setMorphs` turns them
//! off; authoring build only: the player draws no MMD model).
//!
//! A `draw` that would put the same image on screen again is skipped (it returns false): the
//! figures' sampled poses (clip, revision and the clamped position `timeSecs × fps` the clip is
//! sampled at — poses are interpolated between frames, so any change of time is a new pose),
//! the camera, the canvas size and the body are compared with the last drawn. On a machine
//! with no GPU the browser draws in software and every frame costs whole milliseconds of CPU:
//! `adapterInfo` says so (wgpu's device type `Cpu`: on Chromium, WebGL2's ANGLE renderer names
//! SwiftShader, and WebGPU's adapter is the fallback adapter), so a page can draw less often.

use std::cell::{Cell, RefCell};
use std::collections::HashMap;
use std::rc::Rc;

use glam::{Mat4, Vec3};
use odori_core::camera::CameraPose;
use odori_core::canon::builtin::canonical_skeleton;
use odori_core::canon::character::Character;
use odori_core::import::{MeshTexture, SkinnedBounds, SkinnedMesh};
use odori_core::library::body::builtin_body;
use odori_core::canon::retarget::{is_canonical, to_canonical};
use odori_core::mmd::spring::{SpringFollower, SpringParams};
use odori_core::motion::WorldPose;
use odori_core::Clip;
use odori_render::{Figure, MeshDraw, MeshHandle, OrbitCamera, PartLook, PipelineKind, Renderer, FIGURE_COLORS};
use serde::{Deserialize, Serialize};
use wasm_bindgen::prelude::*;
use web_sys::HtmlCanvasElement;

use crate::error::{from_js, JsResult, OdoriError};
use crate::library::{Entry, Library};

mod capture;

#[derive(Deserialize, Default)]
#[serde(rename_all = "camelCase", default, deny_unknown_fields)]
struct ViewerOptions {
    backend: Option<String>,
}

#[derive(Deserialize)]
#[serde(rename_all = "camelCase", deny_unknown_fields)]
struct FigureSpec {
    clip: u32,
    time_secs: f32,
    color: Option<[f32; 3]>,
    offset: Option<[f32; 3]>,
    style: Option<String>,
}

/// What `planCamera` plans over (see there).
#[cfg(feature = "authoring")]
#[derive(Deserialize, Default)]
#[serde(rename_all = "camelCase", deny_unknown_fields)]
struct CameraRequest {
    times_secs: Vec<f32>,
    bars: Vec<odori_core::bars::Bar>,
    #[serde(default)]
    sections: Option<odori_core::music::Sections>,
    #[serde(default)]
    camera: odori_core::camera::CameraOptions,
    /// An MMD camera VMD of the library (`Library.cameraTracks()`) drives the camera instead.
    #[serde(default)]
    camera_track: Option<CameraTrackRequest>,
}

/// Which camera track, and where its frame 0 falls in song time.
#[cfg(feature = "authoring")]
#[derive(Deserialize)]
#[serde(rename_all = "camelCase", deny_unknown_fields)]
struct CameraTrackRequest {
    index: usize,
    #[serde(default)]
    offset_secs: f32,
}

#[wasm_bindgen(typescript_custom_section)]
const TS_CAMERA: &'static str = r#"
/** Where the camera is (metres, radians): it looks at `target` from `distance` away, turned `yaw` about +Y (0: from the front, +Z) and `pitch` above the ground, through a vertical field of view `fovY`. */
export interface CameraPose { target: [number, number, number]; yaw: number; pitch: number; distance: number; fovY: number; }
/** A video camera's settings (`Viewer.planCamera`); every field may be left out. */
export interface CameraOptions { mode?: "fixed" | "orbit" | "follow" | "director"; aspect?: number; phraseBars?: number; minShotBars?: number; intensityJump?: number; noveltyCut?: number; orbitBars?: number; followSmoothSecs?: number; }
/** What `Viewer.planCamera` plans over: the video's frame times (song seconds), the range's bars as the grid gives them, the song's sections (`Project.sections()`). */
export interface CameraRequest { timesSecs: number[] | Float32Array; bars: { index: number; startSecs: number; endSecs: number; intensity: number; beats?: number }[]; sections?: unknown; camera?: CameraOptions; cameraTrack?: { index: number; offsetSecs?: number }; }
/** A planned camera: a pose per frame, and the shots (the first at frame 0; each later one a cut on a bar line at a phrase start). */
export interface CameraPlan { poses: CameraPose[]; shots: { frame: number; bar: number; shot: "wide" | "medium" | "close" | "lowAngle" }[]; phraseBars: number; }
"#;

/// Mesh key of the built-in body in the viewer's uploads (library mesh ids count up from 1).
const BUILTIN_MESH_KEY: u32 = u32::MAX;

/// What clips without a mesh of their own are drawn on.
enum Body {
    /// Each clip as it is: its own mesh, or a stick figure.
    Stick,
    /// The engine's built-in body (humanoid clips carried onto the canonical skeleton first).
    Builtin { mesh: Rc<SkinnedMesh> },
    /// An imported character (library clip `id`), with its shared mesh.
    Imported { id: u32, character: Box<Character>, mesh_key: u32, mesh: Rc<SkinnedMesh> },
}

/// Clips of more than this many frames × character joints are retargeted by `prepareBodies`,
/// not in a draw (about 4 ms of the 61 ms the 68 s dance took onto Xbot's 65 joints, on a
/// loaded machine: a move or a candidate is made at once, the dance is not).
#[cfg(feature = "authoring")]
const DEFER_FRAME_JOINTS: usize = 8_000;

/// Longest a frame is held back for a skinned figure's textures (ms): the browser decodes
/// Fox-sized images in well under a second; an image that never decodes is then drawn without.
const TEXTURE_WAIT_MS: f64 = 3_000.0;

/// A library clip on the chosen body, at the clip's revision `rev`.
struct OnBody {
    rev: u64,
    clip: Option<Rc<Clip>>,
}

/// How one figure was last drawn (`lastDrawn`, for tests and labels; the player build leaves
/// `lastDrawn` and `figureJoints` out, for size).
#[derive(Clone)]
#[cfg_attr(feature = "authoring", derive(Serialize), serde(rename_all = "camelCase"))]
#[cfg_attr(not(feature = "authoring"), allow(dead_code))]
struct Drawn {
    clip: u32,
    time_secs: f32,
    /// "own" (the clip's own mesh), "character" (an imported character), "builtin" or "stick".
    body: &'static str,
    /// Drawn vertices its face morphs moved (an MMD model playing face keys; else 0).
    morphed: u32,
    /// Morphs the project's face tracks key that the drawn MMD model lacks: their keys are
    /// ignored (the page says so, naming them).
    #[cfg(feature = "authoring")]
    missing_morphs: Vec<String>,
}

#[cfg(feature = "authoring")]
#[derive(Serialize)]
#[serde(rename_all = "camelCase")]
struct FigureJoints {
    names: Vec<String>,
    positions: Vec<f32>,
    /// World rotation of each joint, x, y, z, w.
    rotations: Vec<f32>,
    body: &'static str,
    /// The pose is the one last drawn with the springs stepped (an MMD model's hair and skirt).
    sprung: bool,
}

/// The spring joints of the mesh under `key` when it is an MMD model's (authoring build: the
/// player build imports no MMD models).
fn spring_joints(#[cfg_attr(not(feature = "authoring"), allow(unused_variables))] library: &Library, #[cfg_attr(not(feature = "authoring"), allow(unused_variables))] key: u32) -> Option<&[usize]> {
    #[cfg(feature = "authoring")]
    {
        library.spring_joints(key).filter(|j| !j.is_empty())
    }
    #[cfg(not(feature = "authoring"))]
    {
        None
    }
}

/// World positions of a clip at a time (its nearest frames blended), by the motion kernel's
/// one entry point.
pub(crate) fn pose_at(clip: &Clip, time_secs: f32) -> Vec<Vec3> {
    std::mem::take(&mut WorldPose::new().of_time(clip, time_secs).positions)
}

/// The 3D view of a page.
#[wasm_bindgen]
pub struct Viewer {
    surface: wgpu::Surface<'static>,
    config: wgpu::SurfaceConfiguration,
    view_format: wgpu::TextureFormat,
    renderer: Renderer,
    camera: OrbitCamera,
    backend: &'static str,
    /// Uploaded meshes by the library's mesh id; `None` when the mesh cannot be skinned on
    /// the GPU (too many joints) and is drawn as a stick figure instead.
    meshes: HashMap<u32, Option<MeshHandle>>,
    pose: WorldPose,
    mats: Vec<Mat4>,
    /// Following travelling figures: the camera's height above the ground while its target
    /// tracks the figures' centre on the ground plane each frame (see `frameFigures`).
    follow_y: Option<f32>,
    /// Base-colour images decoded by the browser, waiting to be copied into their textures
    /// at the next draw; and how many are still being decoded.
    decoded: Rc<RefCell<Vec<(MeshHandle, usize, web_sys::ImageBitmap)>>>,
    decoding: Rc<Cell<usize>>,
    body: Body,
    /// Library clips on `body`, by clip id.
    on_body: HashMap<u32, OnBody>,
    /// Clips a draw wanted on the body and left for `prepareBodies` (in the order asked).
    #[cfg(feature = "authoring")]
    pending: Vec<u32>,
    /// Retarget long clips in `prepareBodies` (true), or in the draw that needs them (the
    /// control of the frame-time benchmark, tests/browser/retarget-trace.mjs).
    #[cfg(feature = "authoring")]
    defer: bool,
    last_drawn: Vec<Drawn>,
    /// What the last presented frame showed (`None`: nothing yet, the surface was lost, or a
    /// frame held back for textures).
    shown: Option<Shown>,
    /// Since when (ms, `Date.now()`) frames are held back because a skinned figure's
    /// base-colour images are still being decoded (see `draw`).
    held_since_ms: Option<f64>,
    /// Bumped when the body's clips change outside a draw (`setCharacter`, `prepareBodies`),
    /// so the next draw is not taken for a repeat.
    body_generation: u32,
    adapter: AdapterInfo,
    /// Frames presented since the viewer was made (for tests of the drawing budget).
    #[cfg(feature = "authoring")]
    frames_drawn: u32,
    /// Draws go to a texture read back for the video export (`setCapture`), not the canvas.
    capture: Option<capture::Capture>,
    /// MMD models' hair and skirt chains follow by spring (`setSprings`; on by default).
    springs_on: bool,
    /// The springs of each drawn MMD figure, by figure index and clip id, stepped from the
    /// time it was last drawn.
    followers: HashMap<(usize, u32), SpringFollower>,
    /// MMD models play their clips' face keys (`setMorphs`; on by default).
    #[cfg(feature = "authoring")]
    morphs_on: bool,
    /// A clip's face keys and the project's face tracks matched to an MMD model's morphs, by
    /// (clip id, mesh key), with the clip's revision and the library's face-track generation.
    #[cfg(feature = "authoring")]
    faces: HashMap<(u32, u32), (u64, u32, Rc<odori_core::mmd::face_track::LayeredFaces>)>,
    /// Offset buffers (one per drawn vertex) reused from frame to frame.
    #[cfg(feature = "authoring")]
    morph_pool: Vec<Vec<Vec3>>,
    /// Per (figure index, mesh key), the UV morphs' offsets last drawn and the weights they
    /// came from: reused from frame to frame, computed again only when the weights change.
    #[cfg(feature = "authoring")]
    uv_morphs: HashMap<(usize, u32), UvMorphs>,
    /// A drawn MMD model's sampled local pose with its bone morphs on (reused), and the
    /// per-bone morphs they came from.
    #[cfg(feature = "authoring")]
    bone_locals: (Vec<glam::Quat>, Vec<Vec3>, Vec<odori_core::mmd::morph_effects::BoneMorph>),
    /// Per mesh key, its vertices' boxes per palette slot (`frameFigures` frames a skinned
    /// figure by them).
    bounds: HashMap<u32, Rc<SkinnedBounds>>,
}

#[wasm_bindgen(typescript_custom_section)]
const TS_ADAPTER_INFO: &'static str = r#"
/** What the browser reports of a viewer's graphics adapter (`Viewer.adapterInfo`). */
export interface AdapterInfo {
  backend: "webgpu" | "webgl2";
  /** WebGL2: the renderer's name (e.g. "ANGLE (Google, Vulkan 1.3.0 (SwiftShader Device (Subzero) …)"); WebGPU: the adapter's description, often empty. */
  name: string;
  deviceType: "cpu" | "integrated-gpu" | "discrete-gpu" | "virtual-gpu" | "other";
  /** The CPU draws (no GPU): each frame costs the page milliseconds of CPU, so draw less often. */
  software: boolean;
}
"#;

/// What the adapter reports (`adapterInfo`), from wgpu's `AdapterInfo`.
#[derive(Serialize)]
#[serde(rename_all = "camelCase")]
struct AdapterInfo {
    backend: &'static str,
    /// The adapter's name as the browser gives it (WebGL2: the unmasked renderer; WebGPU: the
    /// adapter's description, which Chromium leaves empty).
    name: String,
    /// wgpu's device type: "cpu", "integrated-gpu", "discrete-gpu", "virtual-gpu" or "other".
    device_type: &'static str,
    /// Drawn by the CPU: device type "cpu" or a software rasteriser's name.
    software: bool,
}

impl AdapterInfo {
    fn of(info: &wgpu::AdapterInfo, backend: &'static str) -> AdapterInfo {
        let device_type = match info.device_type {
            wgpu::DeviceType::Cpu => "cpu",
            wgpu::DeviceType::IntegratedGpu => "integrated-gpu",
            wgpu::DeviceType::DiscreteGpu => "discrete-gpu",
            wgpu::DeviceType::VirtualGpu => "virtual-gpu",
            wgpu::DeviceType::Other => "other",
        };
        let name = info.name.to_ascii_lowercase();
        // wgpu infers `Cpu` from these names on GL; a WebGPU adapter that is software but not
        // flagged as the fallback adapter (Mesa's lavapipe under Vulkan) still names its
        // rasteriser. A plain byte search: `str::contains` brings the two-way string searcher
        // into the player build (about 1 kB gzip).
        let has = |word: &str| name.as_bytes().windows(word.len()).any(|w| w == word.as_bytes());
        let software = device_type == "cpu" || ["swiftshader", "llvmpipe", "softpipe", "software"].into_iter().any(has);
        AdapterInfo { backend, name: info.name.clone(), device_type, software }
    }
}

/// The key of a drawn image: two draws with equal `Shown` put the same pixels on screen.
#[derive(PartialEq)]
struct Shown {
    camera: OrbitCamera,
    size: (u32, u32),
    body_generation: u32,
    /// Per figure: clip, revision (two words), sampled position, style, colour, offset (bits).
    figures: Vec<u32>,
}

/// Resolves in a later task of the event loop (a `setTimeout(0)`, in a page or a worker):
/// awaiting it ends the current task, so the browser can paint and handle input between
/// start-up steps. A microtask (an already resolved promise) would not.
async fn next_task() {
    let promise = js_sys::Promise::new(&mut |resolve, _reject| {
        let global = js_sys::global();
        let set_timeout = js_sys::Reflect::get(&global, &JsValue::from_str("setTimeout")).and_then(|f| f.dyn_into::<js_sys::Function>());
        match set_timeout {
            Ok(f) => {
                let _ = f.call2(&global, &resolve, &JsValue::from(0));
            }
            // No timer in this global: go on at once rather than never.
            Err(_) => {
                let _ = resolve.call0(&JsValue::UNDEFINED);
            }
        }
    });
    let _ = wasm_bindgen_futures::JsFuture::from(promise).await;
}

/// Waits, a task at a time, until the GPU has done the work submitted so far (at most about
/// half a second). A browser runs the GPU work in another process; a task that follows before
/// it is done blocks on it at its first call that needs an answer, so a start-up step that
/// only yields would still hand its GPU cost to the next step's task.
async fn gpu_done(device: &wgpu::Device, queue: &wgpu::Queue) {
    let done = std::sync::Arc::new(std::sync::atomic::AtomicBool::new(false));
    let flag = done.clone();
    queue.on_submitted_work_done(move || flag.store(true, std::sync::atomic::Ordering::Release));
    for _ in 0..120 {
        next_task().await;
        // WebGL2: reads the submission's fence without blocking; WebGPU: nothing (the browser
        // calls back from its event loop).
        let _ = device.poll(wgpu::PollType::Poll);
        if done.load(std::sync::atomic::Ordering::Acquire) {
            break;
        }
    }
}

fn gpu_err(msg: impl Into<String>) -> OdoriError {
    OdoriError::new("gpu", msg)
}

impl Viewer {
    /// Clip `e` on the chosen body: `Some((clip to pose, mesh key, mesh, body name))`, or `None`
    /// when it is drawn as it is (no body chosen, a mesh of its own, or not humanoid). With
    /// `defer`, a long clip not yet made is left for `prepareBodies`: its previous making (an
    /// earlier revision) is given meanwhile, or `None` when there is none.
    fn on_body(&mut self, e: &Entry, #[cfg_attr(not(feature = "authoring"), allow(unused_variables))] defer: bool) -> Option<(Rc<Clip>, u32, Rc<SkinnedMesh>, &'static str)> {
        if e.mesh.is_some() {
            return None;
        }
        let (key, mesh, name) = match &self.body {
            Body::Stick => return None,
            Body::Builtin { mesh } => (BUILTIN_MESH_KEY, mesh.clone(), "builtin"),
            Body::Imported { mesh_key, mesh, .. } => (*mesh_key, mesh.clone(), "character"),
        };
        if let Some(c) = self.on_body.get(&e.id).filter(|c| c.rev == e.rev) {
            return c.clip.clone().map(|c| (c, key, mesh, name));
        }
        #[cfg(feature = "authoring")]
        if defer && self.defer && self.is_long(e) {
            if !self.pending.contains(&e.id) {
                self.pending.push(e.id);
            }
            return self.on_body.get(&e.id).and_then(|c| c.clip.clone()).map(|c| (c, key, mesh, name));
        }
        // Made once per clip revision (a whole dance takes a moment; each frame then only samples).
        let clip = match &self.body {
            Body::Stick => None,
            Body::Builtin { .. } if !e.status.is_humanoid() => None,
            Body::Builtin { .. } if is_canonical(&e.clip.skeleton) => Some(Rc::new(e.clip.clone())),
            Body::Builtin { .. } => Some(Rc::new(to_canonical(&e.clip, &e.humanoid, e.clip.fps))),
            // A clip that is not humanoid (the Fox's, a prop) stays a stick figure.
            Body::Imported { character, .. } => character.retarget(&e.clip, &e.humanoid).ok().map(Rc::new),
        };
        self.on_body.insert(e.id, OnBody { rev: e.rev, clip: clip.clone() });
        clip.map(|c| (c, key, mesh, name))
    }

    /// Whether making clip `e` on the body would hold a frame (see [`DEFER_FRAME_JOINTS`]).
    #[cfg(feature = "authoring")]
    fn is_long(&self, e: &Entry) -> bool {
        let joints = match &self.body {
            Body::Stick => return false,
            // A canonical clip is the built-in body's own: nothing to make.
            Body::Builtin { .. } if is_canonical(&e.clip.skeleton) => return false,
            Body::Builtin { .. } => e.clip.skeleton.len(),
            Body::Imported { character, .. } => character.skeleton.len(),
        };
        e.clip.frame_count() * joints > DEFER_FRAME_JOINTS
    }

    /// The uploaded mesh under `key`, uploading it the first time (`None`: drawn as sticks).
    fn mesh_handle(&mut self, key: u32, mesh: &SkinnedMesh) -> Option<MeshHandle> {
        if let Some(h) = self.meshes.get(&key) {
            return *h;
        }
        let h = self.renderer.upload_mesh(mesh).ok();
        if let Some(h) = h {
            for (i, t) in mesh.textures.iter().enumerate() {
                self.decode_texture(h, i, t);
            }
        }
        self.meshes.insert(key, h);
        h
    }

    /// Decodes a base-colour image with the browser's own decoders (`createImageBitmap`: PNG
    /// and JPEG, off the main thread, nothing added to the wasm); the texture is filled at
    /// the first draw after it is ready. A broken image leaves the part its base colour.
    fn decode_texture(&self, mesh: MeshHandle, index: usize, t: &MeshTexture) {
        let Some(window) = web_sys::window() else { return };
        let parts = js_sys::Array::of1(&js_sys::Uint8Array::from(t.image.as_slice()));
        let bag = web_sys::BlobPropertyBag::new();
        bag.set_type(&t.mime_type);
        let Ok(blob) = web_sys::Blob::new_with_u8_array_sequence_and_options(&parts, &bag) else { return };
        let opts = web_sys::ImageBitmapOptions::new();
        // The texels as stored: glTF colour is straight alpha, sRGB-encoded.
        opts.set_premultiply_alpha(web_sys::PremultiplyAlpha::None);
        opts.set_color_space_conversion(web_sys::ColorSpaceConversion::None);
        let Ok(promise) = window.create_image_bitmap_with_blob_and_image_bitmap_options(&blob, &opts) else { return };
        let (out, decoding) = (self.decoded.clone(), self.decoding.clone());
        decoding.set(decoding.get() + 1);
        wasm_bindgen_futures::spawn_local(async move {
            match wasm_bindgen_futures::JsFuture::from(promise).await {
                Ok(bmp) => out.borrow_mut().push((mesh, index, bmp.unchecked_into())),
                Err(e) => web_sys::console::warn_2(&JsValue::from_str(&format!("texture {index} could not be decoded; its base colour is drawn:")), &e),
            }
            decoding.set(decoding.get() - 1);
        });
    }

    /// Copies decoded images into their textures.
    fn take_decoded(&mut self) {
        let ready: Vec<_> = self.decoded.borrow_mut().drain(..).collect();
        for (mesh, index, bmp) in ready {
            let Some(tex) = self.renderer.texture_target(mesh, index, bmp.width(), bmp.height()) else { continue };
            let size = wgpu::Extent3d { width: tex.width(), height: tex.height(), depth_or_array_layers: 1 };
            self.renderer.queue().copy_external_image_to_texture(
                &wgpu::CopyExternalImageSourceInfo { source: wgpu::ExternalImageSource::ImageBitmap(bmp), origin: wgpu::Origin2d::ZERO, flip_y: false },
                wgpu::CopyExternalImageDestInfo {
                    texture: &tex,
                    mip_level: 0,
                    origin: wgpu::Origin3d::ZERO,
                    aspect: wgpu::TextureAspect::All,
                    color_space: wgpu::PredefinedColorSpace::Srgb,
                    premultiplied_alpha: false,
                },
                size,
            );
        }
    }
}

#[wasm_bindgen]
impl Viewer {
    /// Opens a viewer on a canvas. `options.backend`: "auto" (default: WebGPU when the
    /// browser offers it, else WebGL2), "webgpu" or "webgl2".
    pub async fn create(
        canvas: HtmlCanvasElement,
        #[wasm_bindgen(unchecked_param_type = "ViewerOptions | undefined")] options: JsValue,
    ) -> Result<Viewer, OdoriError> {
        let o: ViewerOptions = from_js(options, "viewer options", &["backend"])?;
        let want = o.backend.as_deref().unwrap_or("auto");
        let mut desc = wgpu::InstanceDescriptor::new_without_display_handle();
        let instance = match want {
            "webgl2" => {
                desc.backends = wgpu::Backends::GL;
                wgpu::Instance::new(desc)
            }
            "webgpu" => {
                if !wgpu::util::is_browser_webgpu_supported().await {
                    return Err(gpu_err("WebGPU was asked for but this browser offers no WebGPU adapter"));
                }
                desc.backends = wgpu::Backends::BROWSER_WEBGPU;
                wgpu::Instance::new(desc)
            }
            "auto" => {
                desc.backends = wgpu::Backends::BROWSER_WEBGPU | wgpu::Backends::GL;
                wgpu::util::new_instance_with_webgpu_detection(desc).await
            }
            other => return Err(OdoriError::new("bad-argument", format!("backend must be auto, webgpu or webgl2, not '{other}'"))),
        };
        let (width, height) = (canvas.width().max(1), canvas.height().max(1));
        let surface = instance
            .create_surface(wgpu::SurfaceTarget::Canvas(canvas))
            .map_err(|e| gpu_err(format!("cannot draw on the canvas: {e}")))?;
        next_task().await;
        let adapter = instance
            .request_adapter(&wgpu::RequestAdapterOptions {
                power_preference: wgpu::PowerPreference::HighPerformance,
                force_fallback_adapter: false,
                compatible_surface: Some(&surface),
                ..Default::default()
            })
            .await
            .map_err(|e| gpu_err(format!("no graphics adapter: {e}")))?;
        let info = adapter.get_info();
        let backend = match info.backend {
            wgpu::Backend::BrowserWebGpu => "webgpu",
            _ => "webgl2",
        };
        let adapter_info = AdapterInfo::of(&info, backend);
        let (device, queue) = adapter
            .request_device(&wgpu::DeviceDescriptor {
                label: Some("odori"),
                required_features: wgpu::Features::empty(),
                required_limits: wgpu::Limits::downlevel_webgl2_defaults().using_resolution(adapter.limits()),
                ..Default::default()
            })
            .await
            .map_err(|e| gpu_err(format!("cannot open the graphics device: {e}")))?;
        next_task().await;
        let caps = surface.get_capabilities(&adapter);
        let format = *caps.formats.first().ok_or_else(|| gpu_err("the canvas offers no texture format"))?;
        let view_format = format.add_srgb_suffix();
        let config = wgpu::SurfaceConfiguration {
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT,
            format,
            width,
            height,
            present_mode: wgpu::PresentMode::Fifo,
            desired_maximum_frame_latency: 2,
            alpha_mode: caps.alpha_modes.first().copied().unwrap_or(wgpu::CompositeAlphaMode::Auto),
            view_formats: if view_format != format { vec![view_format] } else { vec![] },
            ..surface.get_default_config(&adapter, width, height).ok_or_else(|| gpu_err("the canvas cannot be configured"))?
        };
        surface.configure(&device, &config);
        let renderer = Renderer::new_deferred(device, queue, view_format);
        let mut viewer = Viewer {
            surface,
            config,
            view_format,
            renderer,
            camera: OrbitCamera::default(),
            backend,
            meshes: HashMap::new(),
            pose: WorldPose::new(),
            mats: Vec::new(),
            follow_y: None,
            decoded: Rc::new(RefCell::new(Vec::new())),
            decoding: Rc::new(Cell::new(0)),
            body: Body::Stick,
            on_body: HashMap::new(),
            #[cfg(feature = "authoring")]
            pending: Vec::new(),
            #[cfg(feature = "authoring")]
            defer: true,
            last_drawn: Vec::new(),
            shown: None,
            held_since_ms: None,
            body_generation: 0,
            adapter: adapter_info,
            #[cfg(feature = "authoring")]
            frames_drawn: 0,
            capture: None,
            springs_on: true,
            followers: HashMap::new(),
            #[cfg(feature = "authoring")]
            morphs_on: true,
            #[cfg(feature = "authoring")]
            faces: HashMap::new(),
            #[cfg(feature = "authoring")]
            morph_pool: Vec::new(),
            #[cfg(feature = "authoring")]
            uv_morphs: HashMap::new(),
            #[cfg(feature = "authoring")]
            bone_locals: Default::default(),
            bounds: HashMap::new(),
        };
        // WebGL2: the pipelines the first frame draws with, each made and then drawn with once, a
        // task for each step: on WebGL2 the browser's GL (ANGLE) compiles a pipeline's GPU code only
        // when it is first drawn with, so without these frames the first pose's task would pay
        // for all of it. The frames show the empty floor (the page's start-up cover hides it).
        // The figure's frame draws one capsule of zero radius: nothing is seen. Each frame's GPU
        // work is waited for (without blocking) before the next step.
        let nothing = [Vec3::ZERO];
        let invisible = Figure { joints: &nothing, bones: &[], color: [0.0; 4], radius: 0.0, head: None };
        // WebGPU compiles pipelines in the GPU process without holding the page's thread: there
        // the two are made at once and the first frame is not waited for.
        for kind in [PipelineKind::Lines, PipelineKind::Figure] {
            if backend == "webgpu" {
                viewer.renderer.prepare(kind);
                continue;
            }
            next_task().await;
            viewer.renderer.prepare(kind);
            next_task().await;
            viewer.present(if kind == PipelineKind::Figure { std::slice::from_ref(&invisible) } else { &[] }, &[]);
            gpu_done(viewer.renderer.device(), viewer.renderer.queue()).await;
        }
        Ok(viewer)
    }

    /// Gives the graphics device back now instead of when the garbage collector gets to it
    /// (browsers allow only a few live contexts per page: an embedded player that scrolls
    /// off-screen calls this). The viewer cannot be used afterwards. On WebGL2 the caller
    /// also loses the canvas's context (`WEBGL_lose_context`), which wgpu does not do.
    pub fn release(self) {
        self.renderer.device().destroy();
    }

    /// Makes what the first frame did not need (the skinned-mesh pipeline), so the first
    /// character drawn does not pay for it. For when the page is idle after its first frame.
    #[wasm_bindgen(js_name = warmUp)]
    pub fn warm_up(&mut self) {
        for kind in PipelineKind::ALL {
            self.renderer.prepare(kind);
        }
    }

    /// "webgpu" or "webgl2".
    #[wasm_bindgen(getter)]
    pub fn backend(&self) -> String {
        self.backend.to_string()
    }

    /// What the browser reports of the graphics adapter: `{ backend, name, deviceType, software }`.
    /// `software` is true when the CPU draws (no GPU: SwiftShader, llvmpipe), where each frame
    /// costs milliseconds of CPU and a page should draw less often (the app and `<odori-player>`
    /// cap animation at 30 frames per second there).
    #[wasm_bindgen(getter, js_name = adapterInfo, unchecked_return_type = "AdapterInfo")]
    pub fn adapter_info(&self) -> JsValue {
        crate::error::to_js(&self.adapter)
    }

    /// Frames put on screen since the viewer was made (a `draw` that would repeat the last
    /// image is not one).
    #[cfg(feature = "authoring")]
    #[wasm_bindgen(getter, js_name = framesDrawn)]
    pub fn frames_drawn(&self) -> u32 {
        self.frames_drawn
    }

    /// Call when the canvas's pixel size changes.
    pub fn resize(&mut self, width: u32, height: u32) {
        let (w, h) = (width.clamp(1, 8192), height.clamp(1, 8192));
        if (w, h) != (self.config.width, self.config.height) {
            self.config.width = w;
            self.config.height = h;
            self.surface.configure(self.renderer.device(), &self.config);
        }
    }

    /// Turns the camera around its target (dx, dy: fractions of the view's width and height).
    pub fn orbit(&mut self, dx: f32, dy: f32) {
        self.camera.orbit(dx, dy);
    }

    /// Moves the camera closer (negative) or farther (positive).
    pub fn zoom(&mut self, steps: f32) {
        self.camera.zoom(steps);
    }

    /// The body that plays every humanoid clip without a mesh of its own (the dance, the
    /// candidates, text animations, moves): `"builtin"` (the engine's own body), the id of an
    /// imported skinned humanoid glTF clip (its character), or `null`/`undefined` (stick
    /// figures, as before). A character that cannot dance (no skin, not humanoid, missing
    /// limbs) throws an `OdoriError` (`character-*`) naming what is missing, and the viewer
    /// keeps the body it had. Clips with their own mesh keep it; a figure of style "stick"
    /// is always the stick figure.
    #[wasm_bindgen(js_name = setCharacter)]
    pub fn set_character(
        &mut self,
        library: &Library,
        #[wasm_bindgen(unchecked_param_type = "number | \"builtin\" | null | undefined")] character: JsValue,
    ) -> Result<(), OdoriError> {
        let body = if character.is_null() || character.is_undefined() {
            Body::Stick
        } else if character.as_string().as_deref() == Some("builtin") {
            match &self.body {
                Body::Builtin { mesh } => Body::Builtin { mesh: mesh.clone() },
                _ => Body::Builtin { mesh: Rc::new(builtin_body(&canonical_skeleton())) },
            }
        } else if let Some(id) = character.as_f64().filter(|v| v.fract() == 0.0 && *v >= 0.0 && *v <= u32::MAX as f64) {
            let id = id as u32;
            if matches!(&self.body, Body::Imported { id: have, .. } if *have == id) {
                return Ok(());
            }
            let (character, mesh) = library.character_of(id)?;
            // `character_of` has checked the skin: the library's mesh is there.
            let (mesh_key, mesh) = mesh.ok_or_else(|| OdoriError::new("character-no-skin", format!("clip {id} has no skinned mesh")))?;
            Body::Imported { id, character: Box::new(character), mesh_key, mesh }
        } else {
            return Err(OdoriError::new("bad-argument", format!("setCharacter: expected \"builtin\", a character's clip id or null, got {character:?}")));
        };
        self.body = body;
        self.on_body.clear();
        self.followers.clear();
        self.body_generation = self.body_generation.wrapping_add(1);
        Ok(())
    }

    /// How many clips a draw left to `prepareBodies` (long clips on the chosen body, such as
    /// the dance: until made, they are drawn as they were last made, or as stick figures).
    #[cfg(feature = "authoring")]
    #[wasm_bindgen(getter, js_name = bodiesPending)]
    pub fn bodies_pending(&self) -> usize {
        self.pending.len()
    }

    /// Makes the next clip a draw left (see `bodiesPending`) on the chosen body: one clip per
    /// call, so a page calls it in a task of its own, between frames, and draws again. True
    /// when a clip was made (the next draw shows it). Clips since removed or already made
    /// are dropped from the list.
    #[cfg(feature = "authoring")]
    #[wasm_bindgen(js_name = prepareBodies)]
    pub fn prepare_bodies(&mut self, library: &Library) -> bool {
        while !self.pending.is_empty() {
            let id = self.pending.remove(0);
            let Ok(e) = library.entry(id) else { continue };
            if self.on_body.get(&id).is_some_and(|c| c.rev == e.rev) {
                continue;
            }
            self.body_generation = self.body_generation.wrapping_add(1);
            return self.on_body(e, false).is_some();
        }
        false
    }

    /// Whether long clips are retargeted by `prepareBodies` between frames (true, the default)
    /// or in the draw that first needs them (false: how it was, the benchmark's control).
    #[cfg(feature = "authoring")]
    #[wasm_bindgen(setter, js_name = deferRetarget)]
    pub fn set_defer_retarget(&mut self, on: bool) {
        self.defer = on;
    }

    /// The body chosen with `setCharacter`: "builtin", the character's clip id, or `null`.
    #[wasm_bindgen(getter, unchecked_return_type = "number | \"builtin\" | null")]
    pub fn character(&self) -> JsValue {
        match &self.body {
            Body::Stick => JsValue::NULL,
            Body::Builtin { .. } => JsValue::from_str("builtin"),
            Body::Imported { id, .. } => JsValue::from(*id),
        }
    }

    /// World joint positions of clip `clip` at `timeSecs` as the viewer draws it (style
    /// "auto"): on the chosen body when it plays that clip, else the clip's own skeleton.
    /// `{ names, positions (x, y, z per joint, metres), rotations (x, y, z, w per joint),
    /// body, sprung }`; `body` as in `lastDrawn`. An MMD model last drawn at `timeSecs` with
    /// springs on gives the pose drawn, its hair and skirt where the springs put them
    /// (`sprung` true); otherwise the clip's pose.
    #[cfg(feature = "authoring")]
    #[wasm_bindgen(js_name = figureJoints, unchecked_return_type = "FigureJoints")]
    pub fn figure_joints(&mut self, library: &Library, clip: u32, time_secs: f32) -> Result<JsValue, OdoriError> {
        let e = library.entry(clip)?;
        if !time_secs.is_finite() {
            return Err(OdoriError::new("bad-argument", format!("figureJoints: time {time_secs} s is not a finite number")));
        }
        let on = self.on_body(e, false);
        let (c, body): (&Clip, &'static str) = match &on {
            Some((c, _, _, body)) => (c.as_ref(), *body),
            None => (&e.clip, if e.mesh.is_some() { "own" } else { "stick" }),
        };
        // An MMD figure drawn at this time with springs: its pose as drawn.
        let mut pose = WorldPose::new();
        let drawn = self.followers.iter().filter(|((_, id), f)| *id == clip && f.last_time_secs() == Some(time_secs)).find_map(|(_, f)| f.last_pose()).filter(|(r, _)| r.len() == c.skeleton.len());
        let sprung = drawn.is_some();
        match drawn {
            Some((r, t)) => pose.of_locals(&c.skeleton, r, t),
            None => pose.of_time(c, time_secs),
        };
        let positions = pose.positions.iter().flat_map(|p| p.to_array()).collect();
        let rotations = pose.rotations.iter().flat_map(|q| q.to_array()).collect();
        let names = c.skeleton.joints.iter().map(|j| j.name.clone()).collect();
        Ok(crate::error::to_js(&FigureJoints { names, positions, rotations, body, sprung }))
    }

    /// MMD models' hair and skirt chains (the bones their rigid bodies simulate, else bones
    /// named for hair or skirt) follow the body by a damped spring, stepped from the time each
    /// figure was last drawn (a jump back or of more than a quarter second starts again at rest):
    /// on (the default) or off (drawn as the motion poses them).
    #[wasm_bindgen(js_name = setSprings)]
    pub fn set_springs(&mut self, on: bool) {
        if on != self.springs_on {
            self.springs_on = on;
            self.followers.clear();
            self.shown = None;
        }
    }

    /// MMD models play the face (morph) keys of the clip they draw — an imported VMD's, or a
    /// project VMD source's — at the drawn time: on (the default) or off (the face at rest).
    /// (Not in the player build, which draws no MMD model.)
    #[cfg(feature = "authoring")]
    #[wasm_bindgen(js_name = setMorphs)]
    pub fn set_morphs(&mut self, on: bool) {
        if on != self.morphs_on {
            self.morphs_on = on;
            self.shown = None;
        }
    }

    /// Whether MMD models play their clips' face keys (`setMorphs`).
    #[cfg(feature = "authoring")]
    #[wasm_bindgen(getter)]
    pub fn morphs(&self) -> bool {
        self.morphs_on
    }

    /// Whether MMD models' hair and skirt follow by spring (`setSprings`).
    #[wasm_bindgen(getter)]
    pub fn springs(&self) -> bool {
        self.springs_on
    }

    /// Whether the last `draw` was held back until a skinned figure's textures are decoded
    /// (the canvas shows the frame before): draw again (each animation frame) until false.
    #[wasm_bindgen(getter, js_name = waitingForTextures)]
    pub fn waiting_for_textures(&self) -> bool {
        self.held_since_ms.is_some()
    }

    /// Base-colour images still being decoded (a texture shows from the first draw after
    /// this reaches 0).
    #[wasm_bindgen(getter, js_name = texturesLoading)]
    pub fn textures_loading(&self) -> usize {
        self.decoding.get() + self.decoded.borrow().len()
    }

    /// How each figure of the last `draw` was drawn: `[{ clip, timeSecs, body }]`, body
    /// "own" (the clip's mesh), "character", "builtin" or "stick".
    #[cfg(feature = "authoring")]
    #[wasm_bindgen(js_name = lastDrawn, unchecked_return_type = "DrawnFigure[]")]
    pub fn last_drawn(&self) -> JsValue {
        crate::error::to_js(&self.last_drawn)
    }

    /// Where a world point lands on the canvas, in canvas pixels from the top left
    /// (`[x, y]`), or `undefined` when it is behind the camera. For labels and tests.
    pub fn project(&self, x: f32, y: f32, z: f32) -> Option<Vec<f32>> {
        let aspect = self.config.width as f32 / self.config.height.max(1) as f32;
        let clip = self.camera.view_proj(aspect) * glam::Vec4::new(x, y, z, 1.0);
        if clip.w <= 1e-6 {
            return None;
        }
        let ndc = clip.truncate() / clip.w;
        Some(vec![(ndc.x * 0.5 + 0.5) * self.config.width as f32, (0.5 - ndc.y * 0.5) * self.config.height as f32])
    }

    /// Puts the camera at `pose` (`CameraPose`: `{ target: [x, y, z], yaw, pitch, distance,
    /// fovY }`, metres and radians): one frame of a planned video camera (`planCamera`), or of
    /// any camera track. The camera stays there (a following camera set by `frameFigures`
    /// stops following) until moved.
    #[wasm_bindgen(js_name = setCamera)]
    pub fn set_camera(&mut self, #[wasm_bindgen(unchecked_param_type = "CameraPose")] pose: JsValue) -> Result<(), OdoriError> {
        let p: CameraPose = serde_wasm_bindgen::from_value(pose).map_err(|e| OdoriError::new("camera", format!("camera pose: {e}")))?;
        let finite = p.target.iter().chain([&p.yaw, &p.pitch, &p.distance, &p.fov_y]).all(|v| v.is_finite());
        if !finite || p.distance <= 0.0 || !(0.01..3.1).contains(&p.fov_y) {
            return Err(OdoriError::new("camera", format!("camera pose {p:?}: needs finite values, a positive distance and a field of view in 0.01..3.1 rad")));
        }
        self.camera = OrbitCamera { target: Vec3::from(p.target), yaw: p.yaw, pitch: p.pitch, distance: p.distance, fov_y: p.fov_y };
        self.follow_y = None;
        // The next draw is drawn even when it repeats the last image: a video captures the
        // canvas after each draw, and a WebGL canvas keeps its image only until the task ends.
        self.shown = None;
        Ok(())
    }

    /// The camera now, as a `CameraPose`.
    #[wasm_bindgen(getter, unchecked_return_type = "CameraPose")]
    pub fn camera(&self) -> JsValue {
        let c = &self.camera;
        crate::error::to_js(&CameraPose { target: c.target.to_array(), yaw: c.yaw, pitch: c.pitch, distance: c.distance, fov_y: c.fov_y })
    }

    /// Plans a video camera (the core's `camera::plan`) over `figures` (clip and offset; their
    /// `timeSecs` is ignored) at the times `request.timesSecs` (song seconds, one per video
    /// frame), posed as this viewer draws them (on the chosen body). `request`: `{ timesSecs,
    /// bars (the range's song bars, as the grid gives them), sections? (a project's
    /// `sections()`), camera?: { mode: "fixed" | "orbit" | "follow" | "director", aspect,
    /// phraseBars, minShotBars, intensityJump, noveltyCut, orbitBars, followSmoothSecs },
    /// cameraTrack?: { index, offsetSecs } }`: with `cameraTrack`, the library's MMD camera
    /// track `index` (`Library.cameraTracks()`) drives the camera instead (the core's
    /// `camera::mmd`), sampled at each time less `offsetSecs` (where its frame 0 falls in song
    /// time), with no shots. Returns `{ poses: CameraPose[], shots: [{ frame, bar, shot }], phraseBars }`.
    #[cfg(feature = "authoring")]
    #[wasm_bindgen(js_name = planCamera, unchecked_return_type = "CameraPlan")]
    pub fn plan_camera(
        &mut self,
        library: &Library,
        #[wasm_bindgen(unchecked_param_type = "FigureSpec[]")] figures: JsValue,
        #[wasm_bindgen(unchecked_param_type = "CameraRequest")] request: JsValue,
    ) -> Result<JsValue, OdoriError> {
        let specs = parse_figures(figures)?;
        let req: CameraRequest = from_js(request, "camera request", &["timesSecs", "bars", "sections", "camera", "cameraTrack"])?;
        if let Some(ct) = &req.camera_track {
            let track = library.mmd.camera(ct.index).ok_or_else(|| {
                OdoriError::new("not-found", format!("no camera track {} (the library has {})", ct.index, library.mmd.camera_count()))
            })?;
            let poses = odori_core::camera::mmd::poses(track, &req.times_secs, ct.offset_secs)?;
            let plan = odori_core::camera::CameraPlan { poses, shots: Vec::new(), phrase_bars: 0 };
            return Ok(crate::error::to_js(&plan));
        }
        let mut posed: Vec<(Rc<Clip>, Vec3)> = Vec::with_capacity(specs.len());
        for s in &specs {
            let e = library.entry(s.clip)?;
            let on = if s.style.as_deref() == Some("stick") { None } else { self.on_body(e, false) };
            let clip = on.map(|o| o.0).unwrap_or_else(|| Rc::new(e.clip.clone()));
            posed.push((clip, Vec3::from(s.offset.unwrap_or([0.0; 3]))));
        }
        let mut pose = WorldPose::new();
        let joints: Vec<Vec<Vec3>> = req
            .times_secs
            .iter()
            .map(|&time| {
                let mut all = Vec::new();
                for (clip, off) in &posed {
                    all.extend(pose.of_time(clip, time).positions.iter().map(|q| *q + *off));
                }
                all
            })
            .collect();
        let input = odori_core::camera::CameraInput { times_secs: &req.times_secs, joints: &joints, bars: &req.bars, sections: req.sections.as_ref() };
        let plan = odori_core::camera::plan(&input, &req.camera)?;
        Ok(crate::error::to_js(&plan))
    }

    /// Points the camera so the figures of `figures` fill the view. Figures that stay in place
    /// are framed over their whole clip; figures that travel (a text animation running across
    /// the floor) would be drawn tiny that way, so the camera is sized to the largest moment
    /// (all figures at one time) and follows their centre as they move. A figure drawn with a
    /// mesh (an MMD model, a GLB character, a clip on the chosen body) is framed by its posed
    /// vertices' bounds ([`SkinnedBounds`]: hair and skirts included), a stick figure by its
    /// joints.
    #[wasm_bindgen(js_name = frameFigures)]
    pub fn frame_figures(
        &mut self,
        library: &Library,
        #[wasm_bindgen(unchecked_param_type = "FigureSpec[]")] figures: JsValue,
    ) -> Result<(), OdoriError> {
        let specs = parse_figures(figures)?;
        const SAMPLES: usize = 9;
        let empty = (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN));
        // The whole path, and each moment (every figure at the same fraction of its clip).
        let (mut lo, mut hi) = empty;
        let mut moments = [empty; SAMPLES];
        for s in &specs {
            let e = library.entry(s.clip)?;
            let off = Vec3::from(s.offset.unwrap_or([0.0; 3]));
            // Framed as drawn: on the chosen body (a character's size differs from the clip's).
            let stick = s.style.as_deref() == Some("stick");
            // As `draw` chooses: the clip's own mesh, else the chosen body's, else joints.
            let own = e.mesh.clone().filter(|_| !stick);
            let on = if stick || own.is_some() { None } else { self.on_body(e, true) };
            let clip: &Clip = on.as_ref().map(|o| &*o.0).unwrap_or(&e.clip);
            let mesh = own.or_else(|| on.as_ref().map(|o| (o.1, o.2.clone())));
            // An MMD model's hair and skirt sway past the animated pose: framed as `draw` plays
            // them, springs stepped through the whole clip.
            #[cfg(feature = "authoring")]
            let sprung = match &mesh {
                Some((key, _)) if self.springs_on => spring_joints(library, *key).map(|j| odori_core::mmd::spring::apply_springs(clip, j, SpringParams::default())),
                _ => None,
            };
            #[cfg(feature = "authoring")]
            let clip: &Clip = sprung.as_ref().unwrap_or(clip);
            let bounds = mesh.map(|(key, mesh)| (self.bounds.entry(key).or_insert_with(|| Rc::new(SkinnedBounds::of_mesh(&mesh))).clone(), mesh));
            let frames = clip.frame_count();
            let mut pose = WorldPose::new();
            let mut mats = Vec::new();
            for (k, m) in moments.iter_mut().enumerate() {
                let t = (k as f32 / (SAMPLES - 1) as f32) * (frames.saturating_sub(1)) as f32 / clip.fps;
                pose.of_time(clip, t).matrices_into(&mut mats);
                let skinned = bounds.as_ref().and_then(|(b, mesh)| {
                    let palette: Vec<Mat4> = mesh.palette.iter().map(|(j, bind)| mats.get(*j).copied().unwrap_or(Mat4::IDENTITY) * *bind).collect();
                    b.posed(&palette)
                });
                let points = match skinned {
                    Some((a, b)) => vec![a, b],
                    None => pose.positions.clone(),
                };
                for p in points {
                    lo = lo.min(p + off);
                    hi = hi.max(p + off);
                    m.0 = m.0.min(p + off);
                    m.1 = m.1.max(p + off);
                }
            }
        }
        if lo.x > hi.x {
            return Ok(());
        }
        lo.y = lo.y.min(0.0);
        let aspect = self.config.width as f32 / self.config.height.max(1) as f32;
        // The biggest moment, as a box about the origin's vertical (x, z centred later).
        let half = moments.iter().filter(|m| m.0.x <= m.1.x).map(|m| (m.1 - m.0) * 0.5).fold(Vec3::ZERO, Vec3::max);
        let path = (hi - lo) * 0.5;
        // Travel: the path is much wider (on the ground) than any moment.
        let travels = path.x.max(path.z) > 1.6 * half.x.max(half.z) + 0.5;
        if travels {
            let y_mid = (lo.y + hi.y) * 0.5;
            let (mlo, mhi) = (Vec3::new(-half.x, lo.y, -half.z), Vec3::new(half.x, hi.y, half.z));
            self.camera.fit(mlo, mhi, aspect);
            self.follow_y = Some(y_mid);
        } else {
            self.camera.fit(lo, hi, aspect);
            self.follow_y = None;
        }
        Ok(())
    }

    /// Draws one frame: each figure is a clip at a time. Returns false, drawing nothing, when
    /// the frame would repeat the last one drawn (same poses, camera, size and body), or while
    /// a skinned figure's textures are still being decoded (`waitingForTextures`).
    pub fn draw(
        &mut self,
        library: &Library,
        #[wasm_bindgen(unchecked_param_type = "FigureSpec[]")] figures: JsValue,
    ) -> Result<bool, OdoriError> {
        let specs = parse_figures(figures)?;
        let key = self.shown_key(library, &specs)?;
        if self.shown.as_ref() == Some(&key) && self.decoded.borrow().is_empty() {
            return Ok(false);
        }
        // Poses first (positions for sticks, palettes for meshes).
        let mut sticks: Vec<(Vec<Vec3>, &Entry, [f32; 4])> = Vec::new();
        let mut palettes: Vec<(MeshHandle, Vec<Mat4>, [f32; 4], Option<Vec<Vec3>>)> = Vec::new();
        // Per skinned draw, its parts' looks under material morphs (none in the player).
        #[cfg_attr(not(feature = "authoring"), allow(unused_mut))]
        let mut looks: Vec<Option<Vec<PartLook>>> = Vec::new();
        // Per skinned draw, its UV morphs' offsets, taken out of `self.uv_morphs` for the draw
        // and put back after it (none in the player).
        #[cfg_attr(not(feature = "authoring"), allow(unused_mut))]
        let mut uv_morphs: Vec<Option<((usize, u32), UvMorphs)>> = Vec::new();
        // One figure is drawn as it is; several (candidates, overlays) each take a wash of
        // their figure colour, so a skinned candidate matches its chip as a stick one does.
        let several = specs.len() > 1;
        let mut drawn: Vec<Drawn> = Vec::with_capacity(specs.len());
        // Where the figures are now (for a camera following travelling figures).
        let (mut now_lo, mut now_hi) = (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN));
        for (i, s) in specs.iter().enumerate() {
            let e = library.entry(s.clip)?;
            let off = Vec3::from(s.offset.unwrap_or([0.0; 3]));
            let color = s.color.map(|c| [c[0], c[1], c[2], 1.0]).unwrap_or(FIGURE_COLORS[i % FIGURE_COLORS.len()]);
            let style = s.style.as_deref().unwrap_or("auto");
            if !matches!(style, "auto" | "stick" | "mesh") {
                return Err(OdoriError::new("bad-argument", format!("figure style must be auto, stick or mesh, not '{style}'")));
            }
            // The clip's own mesh, else the chosen body, else a stick figure.
            let own = match (&e.mesh, style) {
                (Some((key, mesh)), "auto" | "mesh") => {
                    let (key, mesh) = (*key, mesh.clone());
                    self.mesh_handle(key, &mesh).map(|h| (h, key, mesh, None, "own"))
                }
                _ => None,
            };
            let skinned = match own {
                Some(o) => Some(o),
                None if style != "stick" => match self.on_body(e, true) {
                    Some((clip, key, mesh, body)) => self.mesh_handle(key, &mesh).map(|h| (h, key, mesh, Some(clip), body)),
                    None => None,
                },
                None => None,
            };
            let posed: &Clip = match &skinned {
                Some((_, _, _, Some(c), _)) => c.as_ref(),
                _ => &e.clip,
            };
            // An MMD model's hair and skirt follow by spring, stepped from the last drawn time.
            let springs = match &skinned {
                Some((_, key, ..)) if self.springs_on => spring_joints(library, *key),
                _ => None,
            };
            // An MMD model's bone morphs at this time, put on the sampled local pose before
            // world transforms and skinning (as MMD puts them on the keys).
            #[cfg(feature = "authoring")]
            let bones = match &skinned {
                Some((_, key, ..)) => self.bone_morph_weights(library, e, *key, s.time_secs),
                None => None,
            };
            #[cfg(feature = "authoring")]
            let bones = bones.as_ref();
            #[cfg(not(feature = "authoring"))]
            let bones: Option<()> = None;
            match (springs, bones) {
                (Some(joints), _) => {
                    let f = self.followers.entry((i, s.clip)).or_insert_with(|| SpringFollower::new(&posed.skeleton, joints));
                    let (rot, trans) = f.pose(posed, s.time_secs, SpringParams::default());
                    #[cfg(feature = "authoring")]
                    if let Some((drawn, weights)) = bones {
                        let (r, t, scratch) = &mut self.bone_locals;
                        (r.clear(), t.clear());
                        (r.extend_from_slice(rot), t.extend_from_slice(trans));
                        drawn.bone_morph_pose(weights, scratch, r, t);
                        self.pose.of_locals(&posed.skeleton, r, t).matrices_into(&mut self.mats);
                    } else {
                        self.pose.of_locals(&posed.skeleton, rot, trans).matrices_into(&mut self.mats);
                    }
                    #[cfg(not(feature = "authoring"))]
                    self.pose.of_locals(&posed.skeleton, rot, trans).matrices_into(&mut self.mats);
                }
                #[cfg(feature = "authoring")]
                (None, Some((drawn, weights))) => {
                    let (r, t, scratch) = &mut self.bone_locals;
                    posed.sample_into(s.time_secs, r, t);
                    drawn.bone_morph_pose(weights, scratch, r, t);
                    self.pose.of_locals(&posed.skeleton, r, t).matrices_into(&mut self.mats);
                }
                _ => self.pose.of_time(posed, s.time_secs).matrices_into(&mut self.mats),
            }
            let mut pos = self.pose.positions.clone();
            for p in &pos {
                now_lo = now_lo.min(*p + off);
                now_hi = now_hi.max(*p + off);
            }
            match skinned {
                Some((h, key, mesh, _, body)) => {
                    let shift = Mat4::from_translation(off);
                    let pal = mesh.palette.iter().map(|(j, bind)| shift * self.mats[*j] * *bind).collect();
                    let tint = if several { color.map(|c| 0.35 + 0.65 * c) } else { [1.0; 4] };
                    #[cfg(feature = "authoring")]
                    let (morph, morphed, missing_morphs) = self.face_offsets(library, e, key, s.time_secs);
                    #[cfg(not(feature = "authoring"))]
                    let (morph, morphed): (Option<Vec<Vec3>>, u32) = (None, { let _ = key; 0 });
                    #[cfg(feature = "authoring")]
                    looks.push(self.face_looks(library, e, key, &mesh, s.time_secs));
                    #[cfg(feature = "authoring")]
                    uv_morphs.push(self.uv_offsets(library, e, i, key, s.time_secs));
                    palettes.push((h, pal, tint, morph));
                    drawn.push(Drawn {
                        clip: s.clip,
                        time_secs: s.time_secs,
                        body,
                        morphed,
                        #[cfg(feature = "authoring")]
                        missing_morphs,
                    });
                }
                None => {
                    for p in pos.iter_mut() {
                        *p += off;
                    }
                    sticks.push((pos, e, color));
                    drawn.push(Drawn {
                        clip: s.clip,
                        time_secs: s.time_secs,
                        body: "stick",
                        morphed: 0,
                        #[cfg(feature = "authoring")]
                        missing_morphs: Vec::new(),
                    });
                }
            }
        }
        let figures: Vec<Figure> = sticks
            .iter()
            .map(|(pos, e, color)| Figure {
                joints: pos,
                bones: &e.bones,
                color: *color,
                radius: stick_radius(pos, &e.bones),
                head: e.head,
            })
            .collect();
        // A skinned figure is never shown untextured while its base-colour images are being
        // decoded (a character just imported or chosen, for about a second): the canvas keeps
        // the frame it has (the previous character or clip) until they are in, and a frame
        // comes once they are (`waitingForTextures` tells the page to draw again); at most
        // TEXTURE_WAIT_MS, after which an image that never decodes is drawn without.
        if !palettes.is_empty() && self.decoding.get() > 0 {
            let now = js_sys::Date::now();
            let since = *self.held_since_ms.get_or_insert(now);
            if now - since < TEXTURE_WAIT_MS {
                self.shown = None;
                #[cfg(feature = "authoring")]
                self.morph_pool.extend(palettes.into_iter().filter_map(|p| p.3));
                #[cfg(feature = "authoring")]
                self.uv_morphs.extend(uv_morphs.into_iter().flatten());
                return Ok(false);
            }
        }
        self.held_since_ms = None;
        let meshes: Vec<MeshDraw> = palettes
            .iter()
            .enumerate()
            .map(|(k, (h, p, tint, morph))| MeshDraw {
                mesh: *h,
                palette: p,
                tint: *tint,
                morph: morph.as_deref(),
                looks: looks.get(k).and_then(Option::as_deref),
                uv_morph: uv_morphs.get(k).and_then(Option::as_ref).filter(|(_, u)| u.moved > 0).map(|(_, u)| u.offsets.as_slice()),
            })
            .collect();
        self.last_drawn = drawn;
        if let Some(y) = self.follow_y {
            // Track the travelling figures on the ground plane.
            if now_lo.x <= now_hi.x {
                let c = (now_lo + now_hi) * 0.5;
                self.camera.target = Vec3::new(c.x, y, c.z);
            }
        }

        // Keyed with the camera as drawn (a followed figure moved its target).
        self.shown = self.present(&figures, &meshes).then_some(Shown { camera: self.camera, ..key });
        drop(meshes);
        #[cfg(feature = "authoring")]
        self.morph_pool.extend(palettes.into_iter().filter_map(|p| p.3));
        #[cfg(feature = "authoring")]
        self.uv_morphs.extend(uv_morphs.into_iter().flatten());
        #[cfg(feature = "authoring")]
        {
            self.frames_drawn += u32::from(self.shown.is_some());
        }
        Ok(self.shown.is_some())
    }
}

impl Viewer {
    /// The face morph offsets of clip `e` drawn at `time_secs` on the mesh under `mesh_key`
    /// (one per drawn vertex, from the pool), how many vertices they move, and the morphs the
    /// project's face tracks key that the model lacks: `None` when morphs are off, nothing keys
    /// a morph of the model, or the mesh is not an MMD model's with morphs. The clip's own keys
    /// play at the clip's start in the VMD plus the clip's frame at that time, clamped to the
    /// clip as its pose is; the project's face tracks (on a song-time clip: the dance) at the
    /// song time `time_secs`, over the clip's keys for the morphs they key
    /// (`odori_core::mmd::face_track::LayeredFaces`).
    #[cfg(feature = "authoring")]
    fn face_offsets(&mut self, library: &Library, e: &Entry, mesh_key: u32, time_secs: f32) -> (Option<Vec<Vec3>>, u32, Vec<String>) {
        if !self.morphs_on {
            return (None, 0, Vec::new());
        }
        let Some(drawn) = library.drawn_morphs(mesh_key) else { return (None, 0, Vec::new()) };
        let faces = self.layered_faces(library, e, mesh_key, drawn);
        if faces.is_empty() {
            return (None, 0, faces.missing.clone());
        }
        let frame = face_frame(e, &faces, time_secs);
        let mut out = self.morph_pool.pop().unwrap_or_default();
        let moved = drawn.offsets_into(&faces.weights_at(frame, time_secs), &mut out);
        (Some(out), moved as u32, faces.missing.clone())
    }

    /// The layered face weights of clip `e` on the MMD model under `mesh_key` (the clip's own
    /// keys and the project's face tracks), cached per clip revision and face-track generation.
    #[cfg(feature = "authoring")]
    fn layered_faces(&mut self, library: &Library, e: &Entry, mesh_key: u32, drawn: &odori_core::mmd::morph::DrawnMorphs) -> Rc<odori_core::mmd::face_track::LayeredFaces> {
        let generation = library.mmd.faces_generation;
        match self.faces.get(&(e.id, mesh_key)).filter(|(rev, g, _)| *rev == e.rev && *g == generation) {
            Some((_, _, f)) => f.clone(),
            None => {
                let names: Vec<&str> = drawn.morph_names().iter().map(String::as_str).collect();
                let tracks: Vec<&odori_core::mmd::face_track::FaceTrack> = library.face_tracks_on(e.id).iter().collect();
                let faces = Rc::new(odori_core::mmd::face_track::LayeredFaces::new(&names, library.face_keys(e.id), &tracks));
                self.faces.insert((e.id, mesh_key), (e.rev, generation, faces.clone()));
                faces
            }
        }
    }

    /// The weights the face keys give an MMD model's morphs for clip `e` drawn at `time_secs`
    /// on the mesh under `mesh_key`, with the model's drawn morphs, when it has bone morphs and
    /// some are keyed (else `None`): what the draw puts on the sampled pose.
    #[cfg(feature = "authoring")]
    fn bone_morph_weights(&mut self, library: &Library, e: &Entry, mesh_key: u32, time_secs: f32) -> Option<(Rc<odori_core::mmd::morph::DrawnMorphs>, Vec<(usize, f32)>)> {
        let drawn = library.drawn_morphs(mesh_key).filter(|d| self.morphs_on && d.has_bone_morphs())?.clone();
        let faces = self.layered_faces(library, e, mesh_key, &drawn);
        let weights = faces.weights_at(face_frame(e, &faces, time_secs), time_secs);
        (!weights.is_empty()).then_some((drawn, weights))
    }

    /// The UV offsets an MMD model's UV morphs give its drawn vertices for clip `e` drawn as
    /// figure `figure` at `time_secs` on the mesh under `mesh_key` (the face keys' weights
    /// `face_offsets` plays), taken out of `self.uv_morphs` under its key (the draw puts it
    /// back) and computed again only when the weights differ from the last draw's; `None` when
    /// morphs are off or the model has no UV morph. Its `moved` is 0 when none moves a UV.
    #[cfg(feature = "authoring")]
    fn uv_offsets(&mut self, library: &Library, e: &Entry, figure: usize, mesh_key: u32, time_secs: f32) -> Option<((usize, u32), UvMorphs)> {
        let drawn = library.drawn_morphs(mesh_key).filter(|d| self.morphs_on && d.has_uv_morphs())?;
        let faces = self.layered_faces(library, e, mesh_key, drawn);
        if faces.is_empty() {
            return None;
        }
        let weights = faces.weights_at(face_frame(e, &faces, time_secs), time_secs);
        let key = (figure, mesh_key);
        let mut uv = self.uv_morphs.remove(&key).unwrap_or_default();
        if uv.weights != weights || uv.offsets.len() != drawn.drawn_len() {
            uv.moved = drawn.uv_offsets_into(&weights, &mut uv.offsets);
            uv.weights = weights;
        }
        Some((key, uv))
    }

    /// The looks an MMD model's material morphs give its mesh's parts for clip `e` drawn at
    /// `time_secs` on the mesh under `mesh_key` (the face keys' weights at the frame
    /// `face_offsets` takes), or `None` when morphs are off or nothing changes a part.
    #[cfg(feature = "authoring")]
    fn face_looks(&mut self, library: &Library, e: &Entry, mesh_key: u32, mesh: &SkinnedMesh, time_secs: f32) -> Option<Vec<PartLook>> {
        let drawn = library.drawn_morphs(mesh_key).filter(|d| self.morphs_on && d.effects().has_material_morphs())?;
        // The same layered weights `face_offsets` plays (the clip's own keys and the project's
        // face tracks), cached there for this clip, mesh and face-track generation.
        let generation = library.mmd.faces_generation;
        let faces = self.faces.get(&(e.id, mesh_key)).filter(|(rev, g, _)| *rev == e.rev && *g == generation).map(|(_, _, f)| f.clone())?;
        if faces.is_empty() {
            return None;
        }
        let frame = face_frame(e, &faces, time_secs);
        let mut parts = Vec::new();
        if drawn.part_factors_into(&faces.weights_at(frame, time_secs), &mut parts) == 0 {
            return None;
        }
        let four = |v: glam::Vec4| v.to_array();
        Some(
            parts
                .iter()
                .enumerate()
                .map(|(k, (f, edge_size))| {
                    // The sphere factors act on the part's own sphere map, in its mode (none: no change).
                    let sphere = mesh.parts.get(k).and_then(|p| p.toon.as_ref()).filter(|t| t.sphere.is_some()).map(|t| t.sphere_add);
                    let (none_mul, none_add) = ([1.0; 4], [0.0; 4]);
                    let (sph, spa) = match sphere {
                        Some(false) => ((four(f.sphere_mul), four(f.sphere_add)), (none_mul, none_add)),
                        Some(true) => ((none_mul, none_add), (four(f.sphere_mul), four(f.sphere_add))),
                        None => ((none_mul, none_add), (none_mul, none_add)),
                    };
                    let base = drawn.part_base(k);
                    let ambient = f.ambient(base.ambient) - base.ambient;
                    PartLook {
                        diffuse_mul: four(f.diffuse_mul),
                        diffuse_add: four(f.diffuse_add),
                        texture_mul: four(f.texture_mul),
                        texture_add: four(f.texture_add),
                        edge_mul: four(f.edge_colour_mul),
                        edge_add: four(f.edge_colour_add),
                        // The outline is as wide as the edge size: an edge of size 0 stays off.
                        edge_width_scale: [if *edge_size > 0.0 { f.edge_size(*edge_size) / edge_size } else { 1.0 }, 0.0, 0.0, 0.0],
                        sph_mul: sph.0,
                        sph_add: sph.1,
                        spa_mul: spa.0,
                        spa_add: spa.1,
                        toon_mul: four(f.toon_mul),
                        toon_add: four(f.toon_add),
                        ambient_add: ambient.extend(0.0).to_array(),
                        specular_before: base.specular.extend(base.specular_power).to_array(),
                        specular_after: f.specular(base.specular).extend(f.specular_power(base.specular_power)).to_array(),
                    }
                })
                .collect(),
        )
    }

    /// What a draw of `specs` would show, to compare with the last drawn (see `Shown`).
    fn shown_key(&self, library: &Library, specs: &[FigureSpec]) -> JsResult<Shown> {
        let mut figures = Vec::with_capacity(specs.len() * 12);
        for s in specs {
            let e = library.entry(s.clip)?;
            // Where `Clip::sample_into` samples: times past either end show the end frame.
            let at = (s.time_secs * e.clip.fps).clamp(0.0, e.clip.frame_count().saturating_sub(1) as f32);
            let style = match s.style.as_deref() {
                None => 0,
                Some("auto") => 1,
                Some("stick") => 2,
                Some("mesh") => 3,
                // An unknown style fails in the draw itself, with its name.
                Some(_) => 4,
            };
            figures.extend([s.clip, e.rev as u32, (e.rev >> 32) as u32, at.to_bits(), style]);
            // The project's face tracks play at the song time itself (not clamped to the clip).
            #[cfg(feature = "authoring")]
            {
                figures.push(library.mmd.faces_generation);
                if !library.face_tracks_on(s.clip).is_empty() {
                    figures.push(s.time_secs.to_bits());
                }
            }
            figures.extend(s.color.map_or([u32::MAX; 3], |c| c.map(f32::to_bits)));
            figures.extend(s.offset.unwrap_or([0.0; 3]).map(f32::to_bits));
        }
        Ok(Shown { camera: self.camera, size: (self.config.width, self.config.height), body_generation: self.body_generation, figures })
    }

    /// Renders `figures` and `meshes` to the canvas with the current camera; false when the
    /// canvas had no texture to draw on (it is configured again for the next draw).
    fn present(&mut self, figures: &[Figure], meshes: &[MeshDraw]) -> bool {
        if self.capture.is_some() {
            return self.present_captured(figures, meshes);
        }
        let frame = match self.surface.get_current_texture() {
            wgpu::CurrentSurfaceTexture::Success(t) | wgpu::CurrentSurfaceTexture::Suboptimal(t) => t,
            wgpu::CurrentSurfaceTexture::Outdated | wgpu::CurrentSurfaceTexture::Lost => {
                self.surface.configure(self.renderer.device(), &self.config);
                return false;
            }
            _ => return false,
        };
        self.take_decoded();
        let view = frame.texture.create_view(&wgpu::TextureViewDescriptor { format: Some(self.view_format), ..Default::default() });
        self.renderer.render(&view, self.config.width, self.config.height, &self.camera, figures, meshes);
        self.renderer.queue().present(frame);
        true
    }
}

/// A drawn MMD figure's UV morph offsets (one per drawn vertex), how many of them move a UV,
/// and the morph weights they were made from (none in the player, which plays no morphs).
#[cfg_attr(not(feature = "authoring"), allow(dead_code))]
#[derive(Default)]
struct UvMorphs {
    weights: Vec<(usize, f32)>,
    offsets: Vec<[f32; 2]>,
    moved: usize,
}

/// The VMD motion frame whose face keys clip `e` plays at `time_secs`: the clip's start in the
/// VMD plus its frame at that time, clamped to the clip as its pose is.
#[cfg(feature = "authoring")]
fn face_frame(e: &Entry, faces: &odori_core::mmd::face_track::LayeredFaces, time_secs: f32) -> f32 {
    let at = (time_secs * e.clip.fps).clamp(0.0, e.clip.frame_count().saturating_sub(1) as f32);
    faces.base_offset_frames() as f32 + at * odori_core::import::vmd::VMD_FPS / e.clip.fps.max(1e-3)
}

fn parse_figures(figures: JsValue) -> JsResult<Vec<FigureSpec>> {
    serde_wasm_bindgen::from_value(figures).map_err(|e| OdoriError::new("bad-argument", format!("figures: {e}")))
}

/// Bone thickness proportional to the figure's size (a 1.7 m body gets about 2 cm): the
/// pose's vertical extent, or a fifth of its summed bone lengths when it lies flat.
fn stick_radius(pos: &[Vec3], bones: &[(usize, usize)]) -> f32 {
    let (lo, hi) = pos.iter().fold((f32::MAX, f32::MIN), |(l, h), p| (l.min(p.y), h.max(p.y)));
    let height = if hi - lo > 1e-3 {
        hi - lo
    } else {
        bones.iter().map(|&(a, b)| (pos[a] - pos[b]).length()).sum::<f32>() / 5.0
    };
    (height * 0.011).clamp(0.004, 0.2)
}
