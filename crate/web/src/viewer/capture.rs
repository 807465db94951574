//! Frames read back without holding the page (the video export, issue 29): with capture on,
//! a draw renders into a texture of the viewer's own instead of the canvas, copies it into a
//! buffer and asks for the buffer's mapping; the page waits for it between tasks
//! (`captureReady`) and takes the pixels (`takeCapture`). Reading the canvas instead
//! (`new VideoFrame(canvas)`, `createImageBitmap`) makes the page's thread wait until the GPU
//! has drawn the frame, 60–250 ms a frame with software drawing here.

use std::cell::Cell;
use std::rc::Rc;

use wasm_bindgen::prelude::*;

use super::{gpu_err, Viewer};
use crate::error::OdoriError;

/// Where a capture's buffer is.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
enum State {
    /// Nothing drawn into it, or its pixels were taken.
    Idle,
    /// Drawn and copied; the mapping was asked for.
    Pending,
    /// Mapped: the pixels can be taken.
    Mapped,
    /// The mapping failed (the device was lost).
    Failed,
}

/// The texture a captured frame is drawn into, and the buffer it is read back through.
pub(super) struct Capture {
    texture: wgpu::Texture,
    buffer: wgpu::Buffer,
    width_px: u32,
    height_px: u32,
    /// Bytes per row in the buffer: width × 4 rounded up to wgpu's copy alignment (256).
    padded_row_bytes: u32,
    state: Rc<Cell<State>>,
}

impl Capture {
    fn new(device: &wgpu::Device, format: wgpu::TextureFormat, width_px: u32, height_px: u32) -> Capture {
        let width_px = width_px.max(1);
        let height_px = height_px.max(1);
        let align = wgpu::COPY_BYTES_PER_ROW_ALIGNMENT;
        let padded_row_bytes = (width_px * 4).div_ceil(align) * align;
        let texture = device.create_texture(&wgpu::TextureDescriptor {
            label: Some("capture"),
            size: wgpu::Extent3d { width: width_px, height: height_px, depth_or_array_layers: 1 },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format,
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
            view_formats: &[],
        });
        let buffer = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("capture readback"),
            size: u64::from(padded_row_bytes) * u64::from(height_px),
            usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
            mapped_at_creation: false,
        });
        Capture { texture, buffer, width_px, height_px, padded_row_bytes, state: Rc::new(Cell::new(State::Idle)) }
    }
}

impl Viewer {
    /// Draws into the capture texture (capture is on): copies it into the buffer and asks for
    /// its mapping. False, drawing nothing, while the last frame's pixels were not taken.
    pub(super) fn present_captured(&mut self, figures: &[odori_render::Figure], meshes: &[odori_render::MeshDraw]) -> bool {
        let Some(c) = self.capture.as_ref() else { return false };
        if c.state.get() != State::Idle {
            return false;
        }
        let view = c.texture.create_view(&wgpu::TextureViewDescriptor::default());
        let (w, h, row) = (c.width_px, c.height_px, c.padded_row_bytes);
        let (texture, buffer, state) = (c.texture.clone(), c.buffer.clone(), c.state.clone());
        self.take_decoded();
        self.renderer.render(&view, w, h, &self.camera, figures, meshes);
        let device = self.renderer.device();
        let mut enc = device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("capture copy") });
        enc.copy_texture_to_buffer(
            wgpu::TexelCopyTextureInfo { texture: &texture, mip_level: 0, origin: wgpu::Origin3d::ZERO, aspect: wgpu::TextureAspect::All },
            wgpu::TexelCopyBufferInfo {
                buffer: &buffer,
                layout: wgpu::TexelCopyBufferLayout { offset: 0, bytes_per_row: Some(row), rows_per_image: Some(h) },
            },
            wgpu::Extent3d { width: w, height: h, depth_or_array_layers: 1 },
        );
        self.renderer.queue().submit([enc.finish()]);
        state.set(State::Pending);
        let flag = state.clone();
        buffer.slice(..).map_async(wgpu::MapMode::Read, move |r| flag.set(if r.is_ok() { State::Mapped } else { State::Failed }));
        true
    }
}

#[wasm_bindgen]
impl Viewer {
    /// Capture on (true): later draws go to a texture of the viewer's own, the canvas's size,
    /// not to the canvas, and each frame is read back (`captureReady`, `takeCapture`). Off
    /// (false): draws show on the canvas again.
    #[wasm_bindgen(js_name = setCapture)]
    pub fn set_capture(&mut self, on: bool) {
        self.capture = on.then(|| Capture::new(self.renderer.device(), self.view_format, self.config.width, self.config.height));
        self.shown = None;
    }

    /// The captured pixels' layout, as WebCodecs names it (`VideoFrame`'s `format`): "RGBA" or
    /// "BGRA" (the canvas's own format: WebGL2 gives RGBA, WebGPU usually BGRA).
    #[wasm_bindgen(getter, js_name = captureFormat)]
    pub fn capture_format(&self) -> String {
        match self.view_format {
            wgpu::TextureFormat::Bgra8Unorm | wgpu::TextureFormat::Bgra8UnormSrgb => "BGRA",
            _ => "RGBA",
        }
        .to_string()
    }

    /// Whether the last captured draw can be taken (`takeCapture`). Checks the GPU's progress
    /// without waiting: call it again after yielding to the event loop until true. An error
    /// ("gpu") when capture is off, nothing was drawn, or the read back failed.
    #[wasm_bindgen(js_name = captureReady)]
    pub fn capture_ready(&self) -> Result<bool, OdoriError> {
        let c = self.capture.as_ref().ok_or_else(|| gpu_err("capture is off: call setCapture(true) first"))?;
        let _ = self.renderer.device().poll(wgpu::PollType::Poll);
        match c.state.get() {
            State::Mapped => Ok(true),
            State::Pending => Ok(false),
            State::Idle => Err(gpu_err("no captured frame is waiting: draw first (a draw that repeats the last frame draws nothing)")),
            State::Failed => Err(gpu_err("the captured frame could not be read back (the graphics device was lost?)")),
        }
    }

    /// The last captured frame's pixels, width × height × 4 bytes, rows top to bottom, in
    /// `captureFormat`; the capture is then free for the next draw. An error ("gpu") when
    /// it is not ready (`captureReady`).
    #[wasm_bindgen(js_name = takeCapture)]
    pub fn take_capture(&mut self) -> Result<Vec<u8>, OdoriError> {
        let c = self.capture.as_ref().ok_or_else(|| gpu_err("capture is off: call setCapture(true) first"))?;
        if c.state.get() != State::Mapped {
            return Err(gpu_err(format!("the captured frame is not ready ({:?}): wait for captureReady", c.state.get())));
        }
        let row = (c.width_px * 4) as usize;
        let mut out = Vec::with_capacity(row * c.height_px as usize);
        {
            let mapped = c.buffer.slice(..).get_mapped_range().map_err(|e| gpu_err(format!("the captured frame cannot be read: {e}")))?;
            for y in 0..c.height_px as usize {
                let at = y * c.padded_row_bytes as usize;
                out.extend_from_slice(mapped.get(at..at + row).unwrap_or(&[]));
            }
        }
        c.buffer.unmap();
        c.state.set(State::Idle);
        Ok(out)
    }

    /// As `takeCapture`, but into `target`, a Uint8Array of width × height × 4 bytes the caller
    /// keeps and reuses: the pixels are copied once, from the read back straight into it (no
    /// new array a frame, so no 3.6 MB of garbage a frame at 720p for the collector). An error
    /// ("bad-argument") when `target` has another length, ("gpu") when not ready.
    #[wasm_bindgen(js_name = takeCaptureInto)]
    pub fn take_capture_into(&mut self, target: &js_sys::Uint8Array) -> Result<(), OdoriError> {
        let c = self.capture.as_ref().ok_or_else(|| gpu_err("capture is off: call setCapture(true) first"))?;
        if c.state.get() != State::Mapped {
            return Err(gpu_err(format!("the captured frame is not ready ({:?}): wait for captureReady", c.state.get())));
        }
        let row = c.width_px * 4;
        let want = u64::from(row) * u64::from(c.height_px);
        if u64::from(target.length()) != want {
            return Err(OdoriError::new(
                "bad-argument",
                format!("takeCaptureInto: the target holds {} bytes, a {}×{} frame needs {want}", target.length(), c.width_px, c.height_px),
            ));
        }
        {
            let mapped = c.buffer.slice(..).get_mapped_range().map_err(|e| gpu_err(format!("the captured frame cannot be read: {e}")))?;
            let short = || gpu_err(format!("the read back holds {} bytes, short of a {}×{} frame", mapped.len(), c.width_px, c.height_px));
            if c.padded_row_bytes == row {
                // Rows without padding (1280 and 1920 wide): one copy of the whole frame.
                target.copy_from(mapped.get(..want as usize).ok_or_else(short)?);
            } else {
                for y in 0..c.height_px {
                    let at = y as usize * c.padded_row_bytes as usize;
                    let src = mapped.get(at..at + row as usize).ok_or_else(short)?;
                    target.subarray(y * row, (y + 1) * row).copy_from(src);
                }
            }
        }
        c.buffer.unmap();
        c.state.set(State::Idle);
        Ok(())
    }
}
