//! `Viewer`: the wgpu renderer on a canvas, fed from a `Library` once per frame.
//!
//! `Viewer.create` starts the renderer a step per task of the event loop (the canvas and
//! adapter, the device, then each pipeline the first frame draws with, made and drawn with
//! once), so no one task holds a page's main thread for the sum of them; the skinned-mesh
//! pipeline is made by `warmUp` or when a character is first drawn.

use std::collections::HashMap;

use glam::{Mat4, Quat, Vec3};
use odori_core::Clip;
use odori_render::{Figure, MeshDraw, MeshHandle, OrbitCamera, PipelineKind, Renderer, FIGURE_COLORS};
use serde::Deserialize;
use wasm_bindgen::prelude::*;
use web_sys::HtmlCanvasElement;

use crate::error::{from_js, JsResult, OdoriError};
use crate::library::{Entry, Library};

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

/// Local pose of a clip at a time (interpolated), then world positions.
pub(crate) fn pose_at(clip: &Clip, time_secs: f32) -> Vec<Vec3> {
    let (mut r, mut t, mut p) = (Vec::new(), Vec::new(), Vec::new());
    clip.sample_into(time_secs, &mut r, &mut t);
    clip.skeleton.forward_kinematics(&r, &t, &mut p, None);
    p
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
    rot: Vec<Quat>,
    trans: Vec<Vec3>,
    mats: Vec<Mat4>,
    /// Following travelling figures: the camera's height above the ground while its target
    /// tracks the figures' centre on the ground plane each frame (see `frameFigures`).
    follow_y: Option<f32>,
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
        let backend = match adapter.get_info().backend {
            wgpu::Backend::BrowserWebGpu => "webgpu",
            _ => "webgl2",
        };
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
            rot: Vec::new(),
            trans: Vec::new(),
            mats: Vec::new(),
            follow_y: None,
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

    /// Points the camera so the figures of `figures` fill the view. Figures that stay in place
    /// are framed over their whole clip; figures that travel (a text animation running across
    /// the floor) would be drawn tiny that way, so the camera is sized to the largest moment
    /// (all figures at one time) and follows their centre as they move.
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
            let frames = e.clip.frame_count();
            for (k, m) in moments.iter_mut().enumerate() {
                let t = (k as f32 / (SAMPLES - 1) as f32) * (frames.saturating_sub(1)) as f32 / e.clip.fps;
                for p in pose_at(&e.clip, t) {
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

    /// Draws one frame: each figure is a clip at a time.
    pub fn draw(
        &mut self,
        library: &Library,
        #[wasm_bindgen(unchecked_param_type = "FigureSpec[]")] figures: JsValue,
    ) -> Result<(), OdoriError> {
        let specs = parse_figures(figures)?;
        // Poses first (positions for sticks, palettes for meshes).
        let mut sticks: Vec<(Vec<Vec3>, &Entry, [f32; 4])> = Vec::new();
        let mut palettes: Vec<(MeshHandle, Vec<Mat4>)> = Vec::new();
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
            e.clip.sample_into(s.time_secs, &mut self.rot, &mut self.trans);
            let mut pos = Vec::new();
            e.clip.skeleton.forward_kinematics(&self.rot, &self.trans, &mut pos, Some(&mut self.mats));
            for p in &pos {
                now_lo = now_lo.min(*p + off);
                now_hi = now_hi.max(*p + off);
            }
            let handle = match (&e.mesh, style) {
                (Some((mesh_id, mesh)), "auto" | "mesh") => *self
                    .meshes
                    .entry(*mesh_id)
                    .or_insert_with(|| self.renderer.upload_mesh(mesh).ok()),
                _ => None,
            };
            match (handle, &e.mesh) {
                (Some(h), Some((_, mesh))) => {
                    let shift = Mat4::from_translation(off);
                    let pal = mesh.palette.iter().map(|(j, bind)| shift * self.mats[*j] * *bind).collect();
                    palettes.push((h, pal));
                }
                _ => {
                    for p in pos.iter_mut() {
                        *p += off;
                    }
                    sticks.push((pos, e, color));
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
        let meshes: Vec<MeshDraw> = palettes.iter().map(|(h, p)| MeshDraw { mesh: *h, palette: p }).collect();
        if let Some(y) = self.follow_y {
            // Track the travelling figures on the ground plane.
            if now_lo.x <= now_hi.x {
                let c = (now_lo + now_hi) * 0.5;
                self.camera.target = Vec3::new(c.x, y, c.z);
            }
        }

        self.present(&figures, &meshes);
        Ok(())
    }
}

impl Viewer {
    /// Renders `figures` and `meshes` to the canvas with the current camera.
    fn present(&mut self, figures: &[Figure], meshes: &[MeshDraw]) {
        let frame = match self.surface.get_current_texture() {
            wgpu::CurrentSurfaceTexture::Success(t) | wgpu::CurrentSurfaceTexture::Suboptimal(t) => t,
            wgpu::CurrentSurfaceTexture::Outdated | wgpu::CurrentSurfaceTexture::Lost => {
                self.surface.configure(self.renderer.device(), &self.config);
                return;
            }
            _ => return,
        };
        let view = frame.texture.create_view(&wgpu::TextureViewDescriptor { format: Some(self.view_format), ..Default::default() });
        self.renderer.render(&view, self.config.width, self.config.height, &self.camera, figures, meshes);
        self.renderer.queue().present(frame);
    }
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
