//! Odori's wgpu renderer: a ground grid, stick figures (any number, each its own colour),
//! and GPU-skinned characters. It knows nothing of the app: it is given a device, a target
//! and, per frame, a camera and what to draw.
//!
//! Works on WebGPU and on WebGL2 (wgpu's GL backend): no storage buffers, palettes in a 16 KiB
//! uniform block (256 joints), WGSL compiled by naga for either. A part with a base-colour
//! texture samples it (group 2) with the file's sampler; until its image arrives (the caller
//! decodes it and fills [`Renderer::texture_target`]) and for untextured parts, a 1×1 white
//! texture stands in, so the material's colour alone shows. A texture whose sampler
//! minifies through mipmaps gets a full chain, made on the GPU (`mipmap.rs`; feature
//! `mipmaps`, which the player build leaves out); a part's
//! `KHR_texture_transform` is applied to its UVs as the mesh is uploaded (the transform is
//! affine, so transforming the vertices' UVs gives the same sample at every pixel as
//! transforming the interpolated UV in the shader, with nothing added per draw).
//!
//! MMD models (feature `toon`, on in the full engine, off in the player): a part with a
//! [`odori_core::import::ToonLook`] is drawn with MMD's toon shading (its ramp texture looked
//! up on N·L, alpha blended; its sphere map, if any, looked up by the view-space normal and
//! multiplied or added as MMD does, or in PMX's sub-texture mode sampled at the vertex's
//! additional UV 1 and multiplied) and, where its edge width is above 0, an outline by the
//! inverted hull (the skinned mesh pushed out along its normals by the width, times the
//! vertex's edge scale, times the distance to the camera, front faces culled, in the edge
//! colour). Without the feature they draw as plain parts.
//!
//! Morphs: every skinned vertex has an offset added to its rest position before skinning
//! (vertex buffer 1, 12 bytes a vertex, `skin.wgsl`): zero from a buffer each mesh keeps, or
//! for a draw that gives [`MeshDraw::morph`] (an MMD model's face morphs at the drawn time;
//! feature `toon`) that draw's offsets, written whole into a buffer of its draw slot each frame
//! — the 112-byte vertices are never rewritten. Toon and outline read the same offsets, so the
//! outline follows an opened mouth. A mesh with toon parts also has a UV offset per vertex
//! (vertex buffer 2, 8 bytes, read by the toon pipeline only): zeros, or a draw's
//! [`MeshDraw::uv_morph`] (an MMD model's UV morphs) written the same way, but only when they
//! differ from what the slot last had.
//!
//! Its pipelines can be made one at a time ([`Renderer::new_deferred`], then
//! [`Renderer::prepare`]): on WebGL2 each one is a shader compile and link that holds the
//! thread for tens of milliseconds, so a page starting up makes them in separate tasks, and a
//! pipeline nothing has asked for yet is made when it is first drawn with.

mod camera;
mod mipmap;

/// The WGSL of a pipeline: `common.wgsl` (the camera, the light), then for the skinned
/// pipelines `skin.wgsl` (the palette binding and `skin_matrix`, written once for the three),
/// then the pipeline's own file.
fn pipeline_wgsl(kind: PipelineKind) -> String {
    let common = include_str!("shaders/common.wgsl");
    // The MMD shaders are in the full engine only (feature `toon`); without it the player
    // never asks for these pipelines (its parts carry no toon look that reaches `render`).
    #[cfg(feature = "toon")]
    let (toon_src, outline_src) = (include_str!("shaders/toon.wgsl"), include_str!("shaders/outline.wgsl"));
    #[cfg(not(feature = "toon"))]
    let (toon_src, outline_src) = (include_str!("shaders/mesh.wgsl"), include_str!("shaders/mesh.wgsl"));
    let skin = include_str!("shaders/skin.wgsl");
    // The material-morph `Look` the toon and outline shaders share (none without `toon`).
    #[cfg(feature = "toon")]
    let look = include_str!("shaders/look.wgsl");
    #[cfg(not(feature = "toon"))]
    let look = "";
    match kind {
        PipelineKind::Lines => format!("{common}\n{}", include_str!("shaders/lines.wgsl")),
        PipelineKind::Figure => format!("{common}\n{}", include_str!("shaders/figure.wgsl")),
        PipelineKind::Mesh => format!("{common}\n{skin}\n{}", include_str!("shaders/mesh.wgsl")),
        PipelineKind::Toon => format!("{common}\n{skin}\n{look}\n{toon_src}"),
        PipelineKind::Outline => format!("{common}\n{skin}\n{look}\n{outline_src}"),
    }
}

#[cfg(test)]
mod shader_tests {
    use super::*;

    /// Every pipeline's WGSL, as `build_pipeline` puts it together, parses and validates (naga,
    /// as wgpu compiles it), with `vs_main` and `fs_main`; the palette is declared once, in
    /// skin.wgsl, and every skinned shader skins through `skin_matrix`. Run with and without
    /// `--features toon` (the MMD shaders are only put together with it).
    #[test]
    fn every_pipeline_shader_validates_and_skinning_is_written_once() {
        let kinds = [PipelineKind::Lines, PipelineKind::Figure, PipelineKind::Mesh, PipelineKind::Toon, PipelineKind::Outline];
        for kind in kinds {
            let src = pipeline_wgsl(kind);
            let module = naga::front::wgsl::parse_str(&src).unwrap_or_else(|e| panic!("{kind:?}: {}", e.emit_to_string(&src)));
            naga::valid::Validator::new(naga::valid::ValidationFlags::all(), naga::valid::Capabilities::default())
                .validate(&module)
                .unwrap_or_else(|e| panic!("{kind:?}: {e:?}"));
            for entry in ["vs_main", "fs_main"] {
                assert!(module.entry_points.iter().any(|e| e.name == entry), "{kind:?}: no {entry}");
            }
        }
        for (name, src) in [("mesh", include_str!("shaders/mesh.wgsl")), ("toon", include_str!("shaders/toon.wgsl")), ("outline", include_str!("shaders/outline.wgsl"))] {
            assert!(!src.contains("var<uniform> palette") && !src.contains("palette.m["), "{name}.wgsl declares or reads the palette itself");
            assert!(src.contains("skin_matrix(joints, weights)"), "{name}.wgsl does not skin through skin_matrix");
            // Morph offsets go in before skinning, the same way in all three (the outline must
            // follow an opened mouth), and no position is skinned without them.
            assert!(src.contains("@location(8) morph: vec3<f32>") && src.contains("skin_position(skin, p, morph)"), "{name}.wgsl does not add the morph offset");
            assert!(!src.contains("vec4<f32>(p, 1.0)"), "{name}.wgsl skins a position without its morph offset");
        }
    }

    /// The WGSL `Look` (look.wgsl, declared there only) is `PartLook` field for field: the
    /// same names in the same order at the same byte offsets (naga's layout, as the GPU reads
    /// the uniform), the same size, and every field 16 bytes so `FIELDS` misses none.
    #[cfg(feature = "toon")]
    #[test]
    fn the_wgsl_look_is_part_look_field_for_field() {
        for (name, src) in [("toon", include_str!("shaders/toon.wgsl")), ("outline", include_str!("shaders/outline.wgsl"))] {
            assert!(!src.contains("struct Look"), "{name}.wgsl declares Look itself");
        }
        let src = pipeline_wgsl(PipelineKind::Toon);
        let module = naga::front::wgsl::parse_str(&src).unwrap_or_else(|e| panic!("{}", e.emit_to_string(&src)));
        let (members, span) = module
            .types
            .iter()
            .find_map(|(_, t)| match (&t.name, &t.inner) {
                (Some(n), naga::TypeInner::Struct { members, span }) if n == "Look" => Some((members.clone(), *span)),
                _ => None,
            })
            .expect("toon's WGSL declares Look");
        let wgsl: Vec<(String, usize)> = members.iter().map(|m| (m.name.clone().unwrap_or_default(), m.offset as usize)).collect();
        let rust: Vec<(String, usize)> = PartLook::FIELDS.iter().map(|(n, o)| (n.to_string(), *o)).collect();
        assert_eq!(wgsl, rust, "WGSL Look vs PartLook (name, offset)");
        assert_eq!(span as usize, std::mem::size_of::<PartLook>(), "sizes");
        assert_eq!(PartLook::FIELDS.len() * 16, std::mem::size_of::<PartLook>(), "PartLook::FIELDS lists every field");
    }
}
pub use camera::OrbitCamera;

use glam::{Mat4, Vec3};
use odori_core::import::SkinnedMesh;
use wgpu::util::DeviceExt;

/// Joints a skinned mesh may use (the uniform palette's size).
pub const MAX_PALETTE: usize = 256;
const DEPTH: wgpu::TextureFormat = wgpu::TextureFormat::Depth24Plus;

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct CameraUniform {
    view_proj: [[f32; 4]; 4],
    eye: [f32; 4],
    light: [f32; 4],
}

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct LineVertex {
    p: [f32; 3],
    color: [f32; 4],
}

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct CapsuleInstance {
    a: [f32; 4],
    b: [f32; 4],
    color: [f32; 4],
}

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct MeshVertex {
    p: [f32; 3],
    n: [f32; 3],
    joints: [u32; 4],
    weights: [f32; 4],
    color: [f32; 4],
    uv: [f32; 2],
    /// MMD outline colour (RGBA) and width (metres per metre from the camera; 0: none).
    edge: [f32; 4],
    edge_width: f32,
    /// MMD sub-texture (PMX sphere mode 3): the UV its sphere map is sampled at, and 1 (else
    /// 0: the sphere map, if any, looked up by the view-space normal). Read by toon.wgsl only.
    sphere_uv: [f32; 3],
}

/// One stick figure to draw this frame.
pub struct Figure<'a> {
    /// World positions of the joints, metres.
    pub joints: &'a [Vec3],
    /// (parent, child) joint index pairs.
    pub bones: &'a [(usize, usize)],
    /// Linear RGB(A).
    pub color: [f32; 4],
    /// Bone radius, metres (joints are drawn 1.3× as thick; the head larger: see `head`).
    pub radius: f32,
    /// Joint drawn as the head (a ball of 4× radius), if any.
    pub head: Option<usize>,
}

/// The renderer's pipelines, in the order a first frame needs them.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PipelineKind {
    /// The ground grid.
    Lines,
    /// Stick figures (capsules).
    Figure,
    /// GPU-skinned meshes (characters).
    Mesh,
    /// MMD toon shading (feature `toon`): made when a toon part is first drawn.
    Toon,
    /// MMD outlines, the inverted hull (feature `toon`).
    Outline,
}

impl PipelineKind {
    /// What a first frame may need (the MMD pipelines are made when an MMD model is drawn).
    pub const ALL: [PipelineKind; 3] = [PipelineKind::Lines, PipelineKind::Figure, PipelineKind::Mesh];
}

/// How a part is drawn.
#[derive(Clone, Debug, PartialEq)]
struct PartDraw {
    range: std::ops::Range<u32>,
    texture: Option<usize>,
    /// MMD toon: its ramp and sphere textures, whether it has an outline.
    toon: Option<ToonDraw>,
}

/// An MMD part's textures besides its base colour, and whether it has an outline.
#[derive(Clone, Copy, Debug, PartialEq)]
struct ToonDraw {
    ramp: Option<usize>,
    outline: bool,
    /// The sphere map, and whether it is added (else multiplied).
    sphere: Option<(usize, bool)>,
    /// The sphere map is a sub-texture (sampled at the vertices' `sphere_uv`, with its own
    /// sampler), not looked up by the normal.
    sub_texture: bool,
}

/// A skinned mesh uploaded once.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct MeshHandle(usize);

/// One skinned mesh to draw this frame: `palette[k]` = world(joint k) · bind(k).
pub struct MeshDraw<'a> {
    pub mesh: MeshHandle,
    pub palette: &'a [Mat4],
    /// Linear RGB(A) multiplying the mesh's colours: white draws it as it is; several figures
    /// on one character (the six candidates) are told apart by their figure colours.
    pub tint: [f32; 4],
    /// Per vertex of the mesh (its parts' vertices one after another, as uploaded), the offset
    /// (metres, the mesh's rest frame) added before skinning: an MMD model's face morphs.
    /// `None`, or a length other than the mesh's vertex count, draws it unmorphed. Feature
    /// `toon` only (the player draws no MMD model).
    pub morph: Option<&'a [Vec3]>,
    /// Per part of the mesh (as uploaded), the factors an MMD model's material morphs put on
    /// its look at the drawn time. `None`, or a length other than the mesh's part count, draws
    /// every part as uploaded. Feature `toon` only, on the toon and outline pipelines.
    pub looks: Option<&'a [PartLook]>,
    /// Per vertex of the mesh (as `morph`), the offset added to its UV: an MMD model's UV
    /// morphs at the drawn time. `None`, or a length other than the mesh's vertex count, draws
    /// the UVs as uploaded. Feature `toon` only, on the toon pipeline.
    pub uv_morph: Option<&'a [[f32; 2]]>,
}

/// An MMD part's look changed by material morphs (PMX type 8) at one frame: each colour
/// becomes colour × mul + add (the diffuse colour and alpha, the base texture's colour, the
/// edge colour, the sphere map's colour in its mode — `sph_*` multiplied, `spa_*` added — and
/// the toon ramp's), the outline's width is scaled by `edge_width_scale`, and the morphs'
/// change to MMD's ambient term and highlight is added (`shaders/look.wgsl` says how).
/// [`PartLook::NONE`] draws the part as uploaded. The WGSL `Look` struct mirrors it field for
/// field (a test holds them in step).
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
pub struct PartLook {
    pub diffuse_mul: [f32; 4],
    pub diffuse_add: [f32; 4],
    pub texture_mul: [f32; 4],
    pub texture_add: [f32; 4],
    pub edge_mul: [f32; 4],
    pub edge_add: [f32; 4],
    /// x: the outline width's scale; y, z, w unused.
    pub edge_width_scale: [f32; 4],
    pub sph_mul: [f32; 4],
    pub sph_add: [f32; 4],
    pub spa_mul: [f32; 4],
    pub spa_add: [f32; 4],
    pub toon_mul: [f32; 4],
    pub toon_add: [f32; 4],
    /// rgb: the ambient colour with the morphs minus without; w unused.
    pub ambient_add: [f32; 4],
    /// The specular colour (rgb) and power (w) without the morphs and with them; equal: no change.
    pub specular_before: [f32; 4],
    pub specular_after: [f32; 4],
}

impl PartLook {
    pub const NONE: PartLook = PartLook {
        diffuse_mul: [1.0; 4],
        diffuse_add: [0.0; 4],
        texture_mul: [1.0; 4],
        texture_add: [0.0; 4],
        edge_mul: [1.0; 4],
        edge_add: [0.0; 4],
        edge_width_scale: [1.0, 0.0, 0.0, 0.0],
        sph_mul: [1.0; 4],
        sph_add: [0.0; 4],
        spa_mul: [1.0; 4],
        spa_add: [0.0; 4],
        toon_mul: [1.0; 4],
        toon_add: [0.0; 4],
        ambient_add: [0.0; 4],
        specular_before: [0.0; 4],
        specular_after: [0.0; 4],
    };

    /// Each field's name and byte offset, in order (what the WGSL `Look` must declare).
    pub const FIELDS: [(&'static str, usize); 16] = [
        ("diffuse_mul", std::mem::offset_of!(PartLook, diffuse_mul)),
        ("diffuse_add", std::mem::offset_of!(PartLook, diffuse_add)),
        ("texture_mul", std::mem::offset_of!(PartLook, texture_mul)),
        ("texture_add", std::mem::offset_of!(PartLook, texture_add)),
        ("edge_mul", std::mem::offset_of!(PartLook, edge_mul)),
        ("edge_add", std::mem::offset_of!(PartLook, edge_add)),
        ("edge_width_scale", std::mem::offset_of!(PartLook, edge_width_scale)),
        ("sph_mul", std::mem::offset_of!(PartLook, sph_mul)),
        ("sph_add", std::mem::offset_of!(PartLook, sph_add)),
        ("spa_mul", std::mem::offset_of!(PartLook, spa_mul)),
        ("spa_add", std::mem::offset_of!(PartLook, spa_add)),
        ("toon_mul", std::mem::offset_of!(PartLook, toon_mul)),
        ("toon_add", std::mem::offset_of!(PartLook, toon_add)),
        ("ambient_add", std::mem::offset_of!(PartLook, ambient_add)),
        ("specular_before", std::mem::offset_of!(PartLook, specular_before)),
        ("specular_after", std::mem::offset_of!(PartLook, specular_after)),
    ];
}

/// A draw slot's part looks: one uniform block per part at `stride` bytes (the device's
/// uniform offset alignment), bound with a dynamic offset per part.
struct LookSlot {
    buffer: wgpu::Buffer,
    bind_group: wgpu::BindGroup,
    parts: usize,
}

struct GpuMesh {
    vertices: wgpu::Buffer,
    /// Zero morph offsets, one per vertex (vertex buffer 1 of a draw without morphs).
    no_morph: wgpu::Buffer,
    /// Zero UV offsets, one per vertex (vertex buffer 2 of a toon draw without UV morphs);
    /// only for a mesh with toon parts.
    no_uv: Option<wgpu::Buffer>,
    vertex_count: usize,
    indices: wgpu::Buffer,
    /// Per part: drawn one call each, so each can bind its texture.
    parts: Vec<PartDraw>,
    palette_len: usize,
    /// The mesh's textures: their samplers, and bind groups once their images are in.
    samplers: Vec<odori_core::import::Sampler>,
    textures: Vec<Option<wgpu::BindGroup>>,
    /// The textures' views once their images are in (the toon parts' bind groups take two).
    views: Vec<Option<wgpu::TextureView>>,
    /// Per part, its toon bind group (base, ramp and sphere maps), made at the first draw after its
    /// textures last changed.
    toon_groups: Vec<Option<wgpu::BindGroup>>,
}

struct PaletteSlot {
    buffer: wgpu::Buffer,
    tint: wgpu::Buffer,
    bind_group: wgpu::BindGroup,
}

/// Errors the renderer reports instead of panicking.
#[derive(Debug, Clone, PartialEq)]
pub enum RenderError {
    /// The mesh needs more joints than the palette holds; draw it as a stick figure instead.
    PaletteTooLarge { joints: usize, max: usize },
    EmptyMesh,
}

impl std::fmt::Display for RenderError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            RenderError::PaletteTooLarge { joints, max } => write!(f, "the mesh uses {joints} joints; the renderer skins at most {max}"),
            RenderError::EmptyMesh => write!(f, "the mesh has no triangles"),
        }
    }
}

impl std::error::Error for RenderError {}

pub struct Renderer {
    device: wgpu::Device,
    queue: wgpu::Queue,
    camera_buffer: wgpu::Buffer,
    camera_bg: wgpu::BindGroup,
    palette_layout: wgpu::BindGroupLayout,
    texture_layout: wgpu::BindGroupLayout,
    /// The 1×1 white texture untextured parts (and textures still loading) are drawn with.
    white: wgpu::BindGroup,
    basic_layout: wgpu::PipelineLayout,
    mesh_layout: wgpu::PipelineLayout,
    /// MMD: base colour and toon ramp textures (group 2 of the toon pipeline).
    toon_texture_layout: wgpu::BindGroupLayout,
    toon_layout: wgpu::PipelineLayout,
    outline_layout: wgpu::PipelineLayout,
    white_view: wgpu::TextureView,
    /// 1×1 black: the added sphere map of a part that has none.
    black_view: wgpu::TextureView,
    format: wgpu::TextureFormat,
    /// Made on demand (`prepare`): `None` until then.
    line_pipeline: Option<wgpu::RenderPipeline>,
    figure_pipeline: Option<wgpu::RenderPipeline>,
    mesh_pipeline: Option<wgpu::RenderPipeline>,
    toon_pipeline: Option<wgpu::RenderPipeline>,
    outline_pipeline: Option<wgpu::RenderPipeline>,
    grid: wgpu::Buffer,
    grid_count: u32,
    instances: wgpu::Buffer,
    instance_capacity: usize,
    meshes: Vec<GpuMesh>,
    /// Textures given out by `texture_target` whose mip levels are still to be made (at the
    /// next frame, after the caller has copied level 0 in).
    pending_mips: Vec<wgpu::Texture>,
    /// The pipeline that makes them, made the first time one is needed.
    mip_blit: Option<mipmap::MipBlit>,
    palettes: Vec<PaletteSlot>,
    /// Per draw slot (as `palettes`), the morph offsets of the draw in it when it has any,
    /// grown to the largest mesh given morphs.
    morph_slots: Vec<Option<wgpu::Buffer>>,
    /// Per draw slot, the UV offsets of the draw in it when it has any (as `morph_slots`), and
    /// the offsets last written to it: a frame giving the same offsets writes nothing (UV
    /// morphs are keyed sparsely, so most frames repeat the last).
    uv_slots: Vec<Option<(wgpu::Buffer, Vec<[f32; 2]>)>>,
    /// MMD parts' looks (group 3 of the toon pipeline, 2 of the outline): per draw slot, grown
    /// to the most parts drawn in it; the layout, and the bytes between two parts' blocks.
    look_slots: Vec<Option<LookSlot>>,
    look_layout: wgpu::BindGroupLayout,
    look_stride: u64,
    depth: Option<(wgpu::TextureView, u32, u32)>,
    scratch: Vec<CapsuleInstance>,
    /// Background colour.
    pub clear: wgpu::Color,
}

fn grid_lines() -> Vec<LineVertex> {
    let mut v = Vec::new();
    let n = 10;
    let step = 0.5;
    let ext = n as f32 * step;
    for i in -n..=n {
        let x = i as f32 * step;
        let c = if i == 0 { [0.45, 0.45, 0.5, 1.0] } else { [0.22, 0.23, 0.27, 1.0] };
        v.push(LineVertex { p: [x, 0.0, -ext], color: c });
        v.push(LineVertex { p: [x, 0.0, ext], color: c });
        v.push(LineVertex { p: [-ext, 0.0, x], color: c });
        v.push(LineVertex { p: [ext, 0.0, x], color: c });
    }
    v
}

impl Renderer {
    /// Builds the renderer and all its pipelines for a target of `format`.
    pub fn new(device: wgpu::Device, queue: wgpu::Queue, format: wgpu::TextureFormat) -> Renderer {
        let mut r = Renderer::new_deferred(device, queue, format);
        for kind in PipelineKind::ALL {
            r.prepare(kind);
        }
        r
    }

    /// Builds the renderer for a target of `format` without its pipelines: each is made by
    /// [`Renderer::prepare`], or when first drawn with. The buffers and layouts made here are
    /// cheap; the pipelines are not (a WGSL parse, and on WebGL2 a GLSL compile and link each).
    pub fn new_deferred(device: wgpu::Device, queue: wgpu::Queue, format: wgpu::TextureFormat) -> Renderer {
        let uniform_entry = |visibility| wgpu::BindGroupLayoutEntry {
            binding: 0,
            visibility,
            ty: wgpu::BindingType::Buffer { ty: wgpu::BufferBindingType::Uniform, has_dynamic_offset: false, min_binding_size: None },
            count: None,
        };
        let camera_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("camera"),
            entries: &[uniform_entry(wgpu::ShaderStages::VERTEX_FRAGMENT)],
        });
        let palette_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("palette"),
            entries: &[
                uniform_entry(wgpu::ShaderStages::VERTEX),
                wgpu::BindGroupLayoutEntry { binding: 1, ..uniform_entry(wgpu::ShaderStages::FRAGMENT) },
            ],
        });
        let texture_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("base colour"),
            entries: &[
                wgpu::BindGroupLayoutEntry {
                    binding: 0,
                    visibility: wgpu::ShaderStages::FRAGMENT,
                    ty: wgpu::BindingType::Texture {
                        sample_type: wgpu::TextureSampleType::Float { filterable: true },
                        view_dimension: wgpu::TextureViewDimension::D2,
                        multisampled: false,
                    },
                    count: None,
                },
                wgpu::BindGroupLayoutEntry {
                    binding: 1,
                    visibility: wgpu::ShaderStages::FRAGMENT,
                    ty: wgpu::BindingType::Sampler(wgpu::SamplerBindingType::Filtering),
                    count: None,
                },
            ],
        });
        let camera_buffer = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("camera"),
            size: std::mem::size_of::<CameraUniform>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let camera_bg = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("camera"),
            layout: &camera_layout,
            entries: &[wgpu::BindGroupEntry { binding: 0, resource: camera_buffer.as_entire_binding() }],
        });
        let basic_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("basic"),
            bind_group_layouts: &[Some(&camera_layout)],
            immediate_size: 0,
        });
        let mesh_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("mesh"),
            bind_group_layouts: &[Some(&camera_layout), Some(&palette_layout), Some(&texture_layout)],
            immediate_size: 0,
        });
        let tex_entry = |binding| wgpu::BindGroupLayoutEntry {
            binding,
            visibility: wgpu::ShaderStages::FRAGMENT,
            ty: wgpu::BindingType::Texture { sample_type: wgpu::TextureSampleType::Float { filterable: true }, view_dimension: wgpu::TextureViewDimension::D2, multisampled: false },
            count: None,
        };
        let sampler_entry = |binding| wgpu::BindGroupLayoutEntry { binding, visibility: wgpu::ShaderStages::FRAGMENT, ty: wgpu::BindingType::Sampler(wgpu::SamplerBindingType::Filtering), count: None };
        let toon_texture_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("toon textures"),
            // Base, ramp, then the sphere map twice: as multiplied (white when none) and as
            // added (black when none), so one shader does either without a branch.
            entries: &[tex_entry(0), sampler_entry(1), tex_entry(2), sampler_entry(3), tex_entry(4), tex_entry(5), sampler_entry(6)],
        });
        // One part's look at a dynamic offset into its draw slot's buffer.
        let look_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("part looks"),
            entries: &[wgpu::BindGroupLayoutEntry {
                ty: wgpu::BindingType::Buffer {
                    ty: wgpu::BufferBindingType::Uniform,
                    has_dynamic_offset: true,
                    min_binding_size: wgpu::BufferSize::new(std::mem::size_of::<PartLook>() as u64),
                },
                ..uniform_entry(wgpu::ShaderStages::VERTEX_FRAGMENT)
            }],
        });
        let look_stride = (std::mem::size_of::<PartLook>() as u64).next_multiple_of(u64::from(device.limits().min_uniform_buffer_offset_alignment.max(1)));
        let toon_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("toon"),
            bind_group_layouts: &[Some(&camera_layout), Some(&palette_layout), Some(&toon_texture_layout), Some(&look_layout)],
            immediate_size: 0,
        });
        let outline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("outline"),
            bind_group_layouts: &[Some(&camera_layout), Some(&palette_layout), Some(&look_layout)],
            immediate_size: 0,
        });
        let grid_v = grid_lines();
        let grid = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("grid"),
            contents: bytemuck::cast_slice(&grid_v),
            usage: wgpu::BufferUsages::VERTEX,
        });
        let instance_capacity = 256;
        let instances = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("capsules"),
            size: (instance_capacity * std::mem::size_of::<CapsuleInstance>()) as u64,
            usage: wgpu::BufferUsages::VERTEX | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let white_tex = solid_texture(&device, &queue, "white", [255, 255, 255, 255]);
        let white = texture_bind_group(&device, &texture_layout, &white_tex, &odori_core::import::Sampler::default());
        let white_view = white_tex.create_view(&Default::default());
        let black_view = solid_texture(&device, &queue, "black", [0, 0, 0, 255]).create_view(&Default::default());
        Renderer {
            device,
            queue,
            camera_buffer,
            camera_bg,
            palette_layout,
            texture_layout,
            white,
            basic_layout,
            mesh_layout,
            toon_texture_layout,
            toon_layout,
            outline_layout,
            white_view,
            black_view,
            format,
            line_pipeline: None,
            figure_pipeline: None,
            mesh_pipeline: None,
            toon_pipeline: None,
            outline_pipeline: None,
            grid,
            grid_count: grid_v.len() as u32,
            instances,
            instance_capacity,
            meshes: Vec::new(),
            pending_mips: Vec::new(),
            mip_blit: None,
            palettes: Vec::new(),
            morph_slots: Vec::new(),
            uv_slots: Vec::new(),
            look_slots: Vec::new(),
            look_layout,
            look_stride,
            depth: None,
            scratch: Vec::new(),
            clear: wgpu::Color { r: 0.055, g: 0.06, b: 0.075, a: 1.0 },
        }
    }

    /// Makes pipeline `kind` if it is not made yet.
    pub fn prepare(&mut self, kind: PipelineKind) {
        if self.is_prepared(kind) {
            return;
        }
        let p = self.build_pipeline(kind);
        match kind {
            PipelineKind::Lines => self.line_pipeline = Some(p),
            PipelineKind::Figure => self.figure_pipeline = Some(p),
            PipelineKind::Mesh => self.mesh_pipeline = Some(p),
            PipelineKind::Toon => self.toon_pipeline = Some(p),
            PipelineKind::Outline => self.outline_pipeline = Some(p),
        }
    }

    /// Whether pipeline `kind` is made.
    pub fn is_prepared(&self, kind: PipelineKind) -> bool {
        match kind {
            PipelineKind::Lines => self.line_pipeline.is_some(),
            PipelineKind::Figure => self.figure_pipeline.is_some(),
            PipelineKind::Mesh => self.mesh_pipeline.is_some(),
            PipelineKind::Toon => self.toon_pipeline.is_some(),
            PipelineKind::Outline => self.outline_pipeline.is_some(),
        }
    }

    fn build_pipeline(&self, kind: PipelineKind) -> wgpu::RenderPipeline {
        let device = &self.device;
        let mesh_buffer = wgpu::VertexBufferLayout {
            array_stride: std::mem::size_of::<MeshVertex>() as u64,
            step_mode: wgpu::VertexStepMode::Vertex,
            attributes: &wgpu::vertex_attr_array![0 => Float32x3, 1 => Float32x3, 2 => Uint32x4, 3 => Float32x4, 4 => Float32x4, 5 => Float32x2, 6 => Float32x4, 7 => Float32, 10 => Float32x3],
        };
        // Skinned pipelines' second buffer: the per-vertex morph offsets (skin.wgsl).
        let morph_buffer = wgpu::VertexBufferLayout {
            array_stride: 12,
            step_mode: wgpu::VertexStepMode::Vertex,
            attributes: &wgpu::vertex_attr_array![8 => Float32x3],
        };
        // The toon pipeline's third: the per-vertex UV offsets (an MMD model's UV morphs).
        let uv_buffer = wgpu::VertexBufferLayout {
            array_stride: 8,
            step_mode: wgpu::VertexStepMode::Vertex,
            attributes: &wgpu::vertex_attr_array![9 => Float32x2],
        };
        let (label, layout, buffer) = match kind {
            PipelineKind::Toon => ("toon", &self.toon_layout, mesh_buffer.clone()),
            PipelineKind::Outline => ("outline", &self.outline_layout, mesh_buffer.clone()),
            PipelineKind::Lines => (
                "lines",
                &self.basic_layout,
                wgpu::VertexBufferLayout {
                    array_stride: std::mem::size_of::<LineVertex>() as u64,
                    step_mode: wgpu::VertexStepMode::Vertex,
                    attributes: &wgpu::vertex_attr_array![0 => Float32x3, 1 => Float32x4],
                },
            ),
            PipelineKind::Figure => (
                "figure",
                &self.basic_layout,
                wgpu::VertexBufferLayout {
                    array_stride: std::mem::size_of::<CapsuleInstance>() as u64,
                    step_mode: wgpu::VertexStepMode::Instance,
                    attributes: &wgpu::vertex_attr_array![0 => Float32x4, 1 => Float32x4, 2 => Float32x4],
                },
            ),
            PipelineKind::Mesh => ("mesh", &self.mesh_layout, mesh_buffer.clone()),
        };
        // The outline is the hull's inside: front faces culled (MMD's triangles are turned to
        // counter-clockwise fronts on import). Toon parts blend by their alpha, as MMD does.
        let cull_mode = if kind == PipelineKind::Outline { Some(wgpu::Face::Front) } else { None };
        let blend = if kind == PipelineKind::Toon { Some(wgpu::BlendState::ALPHA_BLENDING) } else { None };
        let topology = if kind == PipelineKind::Lines { wgpu::PrimitiveTopology::LineList } else { wgpu::PrimitiveTopology::TriangleList };
        let skinned = matches!(kind, PipelineKind::Mesh | PipelineKind::Toon | PipelineKind::Outline);
        let buffers = [Some(buffer), skinned.then_some(morph_buffer), (kind == PipelineKind::Toon).then_some(uv_buffer)];
        let buffers = match kind {
            PipelineKind::Toon => &buffers[..],
            _ if skinned => &buffers[..2],
            _ => &buffers[..1],
        };
        let sm = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some(label),
            source: wgpu::ShaderSource::Wgsl(pipeline_wgsl(kind).into()),
        });
        device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some(label),
            layout: Some(layout),
            vertex: wgpu::VertexState { module: &sm, entry_point: Some("vs_main"), compilation_options: Default::default(), buffers },
            primitive: wgpu::PrimitiveState { topology, cull_mode, ..Default::default() },
            depth_stencil: Some(wgpu::DepthStencilState {
                format: DEPTH,
                depth_write_enabled: Some(true),
                depth_compare: Some(wgpu::CompareFunction::Less),
                stencil: Default::default(),
                bias: Default::default(),
            }),
            multisample: Default::default(),
            fragment: Some(wgpu::FragmentState {
                module: &sm,
                entry_point: Some("fs_main"),
                compilation_options: Default::default(),
                targets: &[Some(wgpu::ColorTargetState { format: self.format, blend, write_mask: wgpu::ColorWrites::ALL })],
            }),
            multiview_mask: None,
            cache: None,
        })
    }

    pub fn device(&self) -> &wgpu::Device {
        &self.device
    }

    pub fn queue(&self) -> &wgpu::Queue {
        &self.queue
    }

    /// Uploads a skinned mesh (vertex joints index its palette).
    pub fn upload_mesh(&mut self, mesh: &SkinnedMesh) -> Result<MeshHandle, RenderError> {
        if mesh.palette.len() > MAX_PALETTE {
            return Err(RenderError::PaletteTooLarge { joints: mesh.palette.len(), max: MAX_PALETTE });
        }
        let mut vertices = Vec::new();
        let mut indices: Vec<u32> = Vec::new();
        let mut parts = Vec::with_capacity(mesh.parts.len());
        for part in &mesh.parts {
            let base = vertices.len() as u32;
            let textured = part.texture.filter(|t| *t < mesh.textures.len() && part.uvs.len() == part.positions.len());
            let toon = if cfg!(feature = "toon") { part.toon } else { None };
            let (edge, edge_width) = toon.map_or(([0.0; 4], 0.0), |t| (t.edge_colour, t.edge_width.max(0.0)));
            // The outline's width per vertex: the part's times the vertex's edge scale.
            let edge_scale = |k: usize| part.edge_scales.get(k).copied().filter(|e| e.is_finite()).map_or(1.0, |e| e.max(0.0));
            let sub_texture = toon.is_some_and(|t| t.sphere.is_some_and(|s| s < mesh.textures.len()) && !t.sphere_add) && part.sphere_uvs.len() == part.positions.len();
            for k in 0..part.positions.len() {
                let j = part.joints[k];
                vertices.push(MeshVertex {
                    p: part.positions[k],
                    n: part.normals[k],
                    joints: [j[0] as u32, j[1] as u32, j[2] as u32, j[3] as u32],
                    weights: part.weights[k],
                    color: part.color,
                    uv: match (textured, part.uv_transform) {
                        (None, _) => [0.0, 0.0],
                        (Some(_), None) => part.uvs[k],
                        (Some(_), Some(t)) => t.apply(part.uvs[k]),
                    },
                    edge,
                    edge_width: edge_width * edge_scale(k),
                    sphere_uv: match part.sphere_uvs.get(k) {
                        Some(u) if sub_texture => [u[0], u[1], 1.0],
                        _ => [0.0; 3],
                    },
                });
            }
            let start = indices.len() as u32;
            indices.extend(part.indices.iter().map(|i| i + base));
            let n_tex = mesh.textures.len();
            let toon = toon.map(|t| ToonDraw { ramp: t.ramp.filter(|r| *r < n_tex), outline: t.edge_width > 0.0, sphere: t.sphere.filter(|s| *s < n_tex).map(|s| (s, t.sphere_add)), sub_texture });
            parts.push(PartDraw { range: start..indices.len() as u32, texture: textured, toon });
        }
        if indices.is_empty() {
            return Err(RenderError::EmptyMesh);
        }
        let vb = self.device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("mesh vertices"),
            contents: bytemuck::cast_slice(&vertices),
            usage: wgpu::BufferUsages::VERTEX,
        });
        let ib = self.device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("mesh indices"),
            contents: bytemuck::cast_slice(&indices),
            usage: wgpu::BufferUsages::INDEX,
        });
        // Zero-filled on creation (wgpu clears new buffers).
        let no_morph = self.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("no morph"),
            size: (vertices.len() * 12) as u64,
            usage: wgpu::BufferUsages::VERTEX,
            mapped_at_creation: false,
        });
        let no_uv = parts.iter().any(|p| p.toon.is_some()).then(|| {
            self.device.create_buffer(&wgpu::BufferDescriptor { label: Some("no uv morph"), size: (vertices.len() * 8) as u64, usage: wgpu::BufferUsages::VERTEX, mapped_at_creation: false })
        });
        self.meshes.push(GpuMesh {
            vertices: vb,
            no_morph,
            no_uv,
            vertex_count: vertices.len(),
            indices: ib,
            parts,
            palette_len: mesh.palette.len(),
            samplers: mesh.textures.iter().map(|t| t.sampler).collect(),
            textures: vec![None; mesh.textures.len()],
            views: vec![None; mesh.textures.len()],
            toon_groups: vec![None; mesh.parts.len()],
        });
        Ok(MeshHandle(self.meshes.len() - 1))
    }

    /// A `width` × `height` sRGB RGBA8 texture for texture `texture` of an uploaded mesh
    /// (bound with that texture's sampler from now on), for the caller to fill: with
    /// `queue().write_texture`, or on the web `copy_external_image_to_texture` from a decoded
    /// image (usable as a copy destination and a render attachment, as WebGPU asks of that
    /// copy). Fill level 0: when the sampler minifies through mipmaps the texture has a full
    /// chain, and the other levels are made from level 0 before the next frame is drawn.
    /// `None` for a mesh or texture that does not exist.
    pub fn texture_target(&mut self, mesh: MeshHandle, texture: usize, width: u32, height: u32) -> Option<wgpu::Texture> {
        let sampler = *self.meshes.get(mesh.0)?.samplers.get(texture)?;
        let max = self.device.limits().max_texture_dimension_2d;
        let (width, height) = (width.clamp(1, max), height.clamp(1, max));
        let levels = if cfg!(feature = "mipmaps") && mipmap::wants_mipmaps(sampler.min_filter) { mipmap::full_chain(width, height) } else { 1 };
        let tex = self.device.create_texture(&wgpu::TextureDescriptor {
            label: Some("base colour"),
            size: wgpu::Extent3d { width, height, depth_or_array_layers: 1 },
            mip_level_count: levels,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: TEXTURE_FORMAT,
            usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST | wgpu::TextureUsages::RENDER_ATTACHMENT,
            view_formats: &[],
        });
        let bg = texture_bind_group(&self.device, &self.texture_layout, &tex, &sampler);
        let g = &mut self.meshes[mesh.0];
        g.textures[texture] = Some(bg);
        g.views[texture] = Some(tex.create_view(&Default::default()));
        for t in &mut g.toon_groups {
            *t = None;
        }
        if levels > 1 {
            self.pending_mips.push(tex.clone());
        }
        Some(tex)
    }

    fn ensure_depth(&mut self, width: u32, height: u32) {
        if matches!(&self.depth, Some((_, w, h)) if *w == width && *h == height) {
            return;
        }
        let tex = self.device.create_texture(&wgpu::TextureDescriptor {
            label: Some("depth"),
            size: wgpu::Extent3d { width: width.max(1), height: height.max(1), depth_or_array_layers: 1 },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: DEPTH,
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT,
            view_formats: &[],
        });
        self.depth = Some((tex.create_view(&Default::default()), width, height));
    }

    fn ensure_palettes(&mut self, n: usize) {
        while self.palettes.len() < n {
            let buffer = self.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("palette"),
                size: (MAX_PALETTE * 64) as u64,
                usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            });
            let tint = self.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("tint"),
                size: 16,
                usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            });
            let bind_group = self.device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("palette"),
                layout: &self.palette_layout,
                entries: &[wgpu::BindGroupEntry { binding: 0, resource: buffer.as_entire_binding() }, wgpu::BindGroupEntry { binding: 1, resource: tint.as_entire_binding() }],
            });
            self.palettes.push(PaletteSlot { buffer, tint, bind_group });
        }
    }

    /// Draws one frame into `target` (of the format given at creation).
    pub fn render(
        &mut self,
        target: &wgpu::TextureView,
        width: u32,
        height: u32,
        camera: &OrbitCamera,
        figures: &[Figure],
        meshes: &[MeshDraw],
    ) {
        self.ensure_depth(width, height);
        let aspect = width.max(1) as f32 / height.max(1) as f32;
        let cam = CameraUniform {
            view_proj: camera.view_proj(aspect).to_cols_array_2d(),
            eye: camera.eye().extend(1.0).to_array(),
            light: Vec3::new(0.4, 0.9, 0.6).normalize().extend(0.0).to_array(),
        };
        self.queue.write_buffer(&self.camera_buffer, 0, bytemuck::bytes_of(&cam));

        // Capsules for every figure.
        self.scratch.clear();
        for fig in figures {
            let r = fig.radius;
            for &(p, c) in fig.bones {
                if let (Some(a), Some(b)) = (fig.joints.get(p), fig.joints.get(c)) {
                    self.scratch.push(CapsuleInstance { a: a.extend(r).to_array(), b: b.extend(0.0).to_array(), color: fig.color });
                }
            }
            for (j, p) in fig.joints.iter().enumerate() {
                let rr = if Some(j) == fig.head { r * 4.0 } else { r * 1.3 };
                let col = if Some(j) == fig.head { fig.color.map(|x| x * 0.9) } else { fig.color };
                self.scratch.push(CapsuleInstance { a: p.extend(rr).to_array(), b: p.extend(0.0).to_array(), color: col });
            }
        }
        if self.scratch.len() > self.instance_capacity {
            self.instance_capacity = self.scratch.len().next_power_of_two();
            self.instances = self.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("capsules"),
                size: (self.instance_capacity * std::mem::size_of::<CapsuleInstance>()) as u64,
                usage: wgpu::BufferUsages::VERTEX | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            });
        }
        if !self.scratch.is_empty() {
            self.queue.write_buffer(&self.instances, 0, bytemuck::cast_slice(&self.scratch));
        }
        let drawable: Vec<&MeshDraw> =
            meshes.iter().filter(|m| self.meshes.get(m.mesh.0).is_some_and(|g| m.palette.len() >= g.palette_len)).collect();
        self.ensure_palettes(drawable.len());
        for (slot, m) in drawable.iter().enumerate() {
            let n = m.palette.len().min(MAX_PALETTE);
            self.queue.write_buffer(&self.palettes[slot].buffer, 0, bytemuck::cast_slice(&m.palette[..n]));
            self.queue.write_buffer(&self.palettes[slot].tint, 0, bytemuck::cast_slice(&m.tint));
        }
        // Morph offsets, whole, into the slot's buffer (12 B a vertex); a slot without leaves
        // its buffer unused this frame and draws from the mesh's zeros.
        let morphs: Vec<bool> = drawable.iter().map(|m| cfg!(feature = "toon") && m.morph.is_some_and(|o| o.len() == self.meshes[m.mesh.0].vertex_count)).collect();
        self.morph_slots.resize_with(self.morph_slots.len().max(drawable.len()), || None);
        for (slot, m) in drawable.iter().enumerate().filter(|_| cfg!(feature = "toon")) {
            let Some(offsets) = m.morph.filter(|_| morphs[slot]) else { continue };
            let bytes: &[u8] = bytemuck::cast_slice(offsets);
            if self.morph_slots[slot].as_ref().is_none_or(|b| b.size() < bytes.len() as u64) {
                self.morph_slots[slot] = Some(self.device.create_buffer(&wgpu::BufferDescriptor {
                    label: Some("morph offsets"),
                    size: bytes.len() as u64,
                    usage: wgpu::BufferUsages::VERTEX | wgpu::BufferUsages::COPY_DST,
                    mapped_at_creation: false,
                }));
            }
            if let Some(b) = &self.morph_slots[slot] {
                self.queue.write_buffer(b, 0, bytes);
            }
        }

        // UV offsets the same way (8 B a vertex), for toon meshes, written only when they differ
        // from what the slot's buffer holds.
        let uv_given: Vec<bool> = drawable.iter().map(|m| cfg!(feature = "toon") && self.meshes[m.mesh.0].no_uv.is_some() && m.uv_morph.is_some_and(|o| o.len() == self.meshes[m.mesh.0].vertex_count)).collect();
        self.uv_slots.resize_with(self.uv_slots.len().max(drawable.len()), || None);
        for (slot, m) in drawable.iter().enumerate() {
            let Some(offsets) = m.uv_morph.filter(|_| uv_given[slot]) else { continue };
            let bytes: &[u8] = bytemuck::cast_slice(offsets);
            if self.uv_slots[slot].as_ref().is_none_or(|(b, _)| b.size() < bytes.len() as u64) {
                let buffer = self.device.create_buffer(&wgpu::BufferDescriptor {
                    label: Some("uv offsets"),
                    size: bytes.len() as u64,
                    usage: wgpu::BufferUsages::VERTEX | wgpu::BufferUsages::COPY_DST,
                    mapped_at_creation: false,
                });
                self.uv_slots[slot] = Some((buffer, Vec::new()));
            }
            if let Some((b, written)) = &mut self.uv_slots[slot] {
                if written.as_slice() != offsets {
                    self.queue.write_buffer(b, 0, bytes);
                    written.clear();
                    written.extend_from_slice(offsets);
                }
            }
        }

        // MMD parts' looks: every toon mesh's slot holds one block per part (the given looks,
        // or none changed), so its parts bind their block by offset.
        if cfg!(feature = "toon") {
            self.look_slots.resize_with(self.look_slots.len().max(drawable.len()), || None);
            for (slot, m) in drawable.iter().enumerate() {
                let g = &self.meshes[m.mesh.0];
                if !g.parts.iter().any(|p| p.toon.is_some()) {
                    continue;
                }
                let n = g.parts.len();
                let given = m.looks.filter(|l| l.len() == n);
                if self.look_slots[slot].as_ref().is_none_or(|l| l.parts < n) {
                    let buffer = self.device.create_buffer(&wgpu::BufferDescriptor {
                        label: Some("part looks"),
                        size: self.look_stride * n as u64,
                        usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
                        mapped_at_creation: false,
                    });
                    let bind_group = self.device.create_bind_group(&wgpu::BindGroupDescriptor {
                        label: Some("part looks"),
                        layout: &self.look_layout,
                        entries: &[wgpu::BindGroupEntry {
                            binding: 0,
                            resource: wgpu::BindingResource::Buffer(wgpu::BufferBinding { buffer: &buffer, offset: 0, size: wgpu::BufferSize::new(std::mem::size_of::<PartLook>() as u64) }),
                        }],
                    });
                    self.look_slots[slot] = Some(LookSlot { buffer, bind_group, parts: n });
                }
                let mut bytes = vec![0u8; (self.look_stride as usize) * n];
                for k in 0..n {
                    let look = given.map_or(PartLook::NONE, |l| l[k]);
                    let at = k * self.look_stride as usize;
                    bytes[at..at + std::mem::size_of::<PartLook>()].copy_from_slice(bytemuck::bytes_of(&look));
                }
                if let Some(l) = &self.look_slots[slot] {
                    self.queue.write_buffer(&l.buffer, 0, &bytes);
                }
            }
        }

        // Pipelines not made yet are made now, for what this frame draws only.
        self.prepare(PipelineKind::Lines);
        if !drawable.is_empty() {
            self.prepare(PipelineKind::Mesh);
        }
        let handles: Vec<usize> = drawable.iter().map(|m| m.mesh.0).collect();
        let any_toon = handles.iter().any(|&h| self.meshes[h].parts.iter().any(|p| p.toon.is_some()));
        if any_toon {
            self.prepare(PipelineKind::Toon);
            self.prepare(PipelineKind::Outline);
            for &h in &handles {
                self.make_toon_groups(h);
            }
        }
        if !self.scratch.is_empty() {
            self.prepare(PipelineKind::Figure);
        }
        let mut encoder = self.device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("frame") });
        if cfg!(feature = "mipmaps") && !self.pending_mips.is_empty() {
            let blit = self.mip_blit.get_or_insert_with(|| mipmap::MipBlit::new(&self.device, TEXTURE_FORMAT));
            for tex in self.pending_mips.drain(..) {
                blit.encode(&self.device, &mut encoder, &tex);
            }
        }
        {
            let morph_slots = &self.morph_slots;
            let morph_of = |slot: usize, g| morph_slice(morphs[slot], morph_slots.get(slot).and_then(Option::as_ref), g);
            let depth_view = &self.depth.as_ref().map(|d| &d.0).expect("depth texture was just made");
            let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("scene"),
                color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                    view: target,
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations { load: wgpu::LoadOp::Clear(self.clear), store: wgpu::StoreOp::Store },
                })],
                depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                    view: depth_view,
                    depth_ops: Some(wgpu::Operations { load: wgpu::LoadOp::Clear(1.0), store: wgpu::StoreOp::Store }),
                    stencil_ops: None,
                }),
                timestamp_writes: None,
                occlusion_query_set: None,
                multiview_mask: None,
            });
            pass.set_bind_group(0, &self.camera_bg, &[]);
            if let Some(lines) = &self.line_pipeline {
                pass.set_pipeline(lines);
                pass.set_vertex_buffer(0, self.grid.slice(..));
                pass.draw(0..self.grid_count, 0..1);
            }
            if let (false, Some(mesh)) = (drawable.is_empty(), &self.mesh_pipeline) {
                pass.set_pipeline(mesh);
                for (slot, m) in drawable.iter().enumerate() {
                    let g = &self.meshes[m.mesh.0];
                    pass.set_bind_group(1, &self.palettes[slot].bind_group, &[]);
                    pass.set_vertex_buffer(0, g.vertices.slice(..));
                    pass.set_vertex_buffer(1, morph_of(slot, g));
                    if let Some(zeros) = &g.no_uv {
                        // Only the toon pipeline reads it.
                        let given = self.uv_slots.get(slot).and_then(Option::as_ref).map(|(b, _)| b).filter(|_| uv_given[slot]);
                        pass.set_vertex_buffer(2, given.map_or(zeros.slice(..), |b| b.slice(..(g.vertex_count * 8) as u64)));
                    }
                    pass.set_index_buffer(g.indices.slice(..), wgpu::IndexFormat::Uint32);
                    for (k, part) in g.parts.iter().enumerate() {
                        let look = self.look_slots.get(slot).and_then(Option::as_ref);
                        if let (Some(_), Some(toon), Some(bg), Some(look)) = (part.toon, &self.toon_pipeline, g.toon_groups[k].as_ref(), look) {
                            pass.set_pipeline(toon);
                            pass.set_bind_group(2, bg, &[]);
                            pass.set_bind_group(3, &look.bind_group, &[(k as u64 * self.look_stride) as u32]);
                        } else {
                            let bg = part.texture.and_then(|t| g.textures.get(t)).and_then(Option::as_ref).unwrap_or(&self.white);
                            pass.set_pipeline(mesh);
                            pass.set_bind_group(2, bg, &[]);
                        }
                        pass.draw_indexed(part.range.clone(), 0, 0..1);
                    }
                }
                // MMD outlines after the model's own surfaces (depth-tested against them).
                if let Some(outline) = &self.outline_pipeline {
                    for (slot, m) in drawable.iter().enumerate() {
                        let g = &self.meshes[m.mesh.0];
                        let Some(look) = self.look_slots.get(slot).and_then(Option::as_ref) else { continue };
                        if !g.parts.iter().any(|p| p.toon.is_some_and(|t| t.outline)) {
                            continue;
                        }
                        pass.set_pipeline(outline);
                        pass.set_bind_group(1, &self.palettes[slot].bind_group, &[]);
                        pass.set_vertex_buffer(0, g.vertices.slice(..));
                        pass.set_vertex_buffer(1, morph_of(slot, g));
                        pass.set_index_buffer(g.indices.slice(..), wgpu::IndexFormat::Uint32);
                        for (k, part) in g.parts.iter().enumerate().filter(|(_, p)| p.toon.is_some_and(|t| t.outline)) {
                            pass.set_bind_group(2, &look.bind_group, &[(k as u64 * self.look_stride) as u32]);
                            pass.draw_indexed(part.range.clone(), 0, 0..1);
                        }
                    }
                }
            }
            if let (false, Some(figure)) = (self.scratch.is_empty(), &self.figure_pipeline) {
                pass.set_pipeline(figure);
                pass.set_vertex_buffer(0, self.instances.slice(..));
                pass.draw(0..6, 0..self.scratch.len() as u32);
            }
        }
        self.queue.submit([encoder.finish()]);
    }
}

impl Renderer {
    /// Makes the toon bind groups (base colour, ramp, sphere maps) of mesh `h`'s toon parts
    /// that have none: a texture not in yet is the white one (a ramp of white is no shading),
    /// a sphere map not in yet or absent is white multiplied and black added (no change).
    fn make_toon_groups(&mut self, h: usize) {
        let Some(g) = self.meshes.get_mut(h) else { return };
        for k in 0..g.parts.len() {
            let Some(ToonDraw { ramp, sphere, sub_texture, .. }) = g.parts[k].toon else { continue };
            if g.toon_groups[k].is_some() {
                continue;
            }
            let pick = |t: Option<usize>| t.and_then(|t| g.views.get(t).and_then(Option::as_ref).map(|v| (v, g.samplers[t])));
            let white_sampler = odori_core::import::Sampler::default();
            let (base_view, base_s) = pick(g.parts[k].texture).unwrap_or((&self.white_view, white_sampler));
            // The ramp is looked up at one column, top (lit) to bottom: clamped, never wrapped.
            let (ramp_view, _) = pick(ramp).unwrap_or((&self.white_view, white_sampler));
            let clamp = odori_core::import::Sampler { wrap_s: 33071, wrap_t: 33071, mag_filter: Some(9729), min_filter: Some(9729) };
            let base_sampler = make_sampler(&self.device, &base_s);
            let ramp_sampler = make_sampler(&self.device, &clamp);
            // The sphere map is looked up inside its disc (u, v in 0–1): clamped as well.
            let sphere_view = |add: bool| sphere.filter(|s| s.1 == add).and_then(|s| pick(Some(s.0))).map(|(v, _)| v);
            let sphere_mul = sphere_view(false).unwrap_or(&self.white_view);
            let sphere_add = sphere_view(true).unwrap_or(&self.black_view);
            // A sub-texture is sampled at the vertices' UVs as an ordinary texture: with its own
            // sampler; a sphere looked up by the normal shares the ramp's clamped one.
            let sub_sampler = sphere.filter(|_| sub_texture).map(|(s, _)| make_sampler(&self.device, &g.samplers[s]));
            let sphere_sampler = sub_sampler.as_ref().unwrap_or(&ramp_sampler);
            g.toon_groups[k] = Some(self.device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("toon textures"),
                layout: &self.toon_texture_layout,
                entries: &[
                    wgpu::BindGroupEntry { binding: 0, resource: wgpu::BindingResource::TextureView(base_view) },
                    wgpu::BindGroupEntry { binding: 1, resource: wgpu::BindingResource::Sampler(&base_sampler) },
                    wgpu::BindGroupEntry { binding: 2, resource: wgpu::BindingResource::TextureView(ramp_view) },
                    wgpu::BindGroupEntry { binding: 3, resource: wgpu::BindingResource::Sampler(&ramp_sampler) },
                    wgpu::BindGroupEntry { binding: 4, resource: wgpu::BindingResource::TextureView(sphere_mul) },
                    wgpu::BindGroupEntry { binding: 5, resource: wgpu::BindingResource::TextureView(sphere_add) },
                    wgpu::BindGroupEntry { binding: 6, resource: wgpu::BindingResource::Sampler(sphere_sampler) },
                ],
            }));
        }
    }
}

/// A draw's morph offsets: its slot's buffer when it gave morphs this frame, else the mesh's zeros.
fn morph_slice<'a>(given: bool, slot: Option<&'a wgpu::Buffer>, g: &'a GpuMesh) -> wgpu::BufferSlice<'a> {
    match (given, slot) {
        (true, Some(b)) => b.slice(..(g.vertex_count * 12) as u64),
        _ => g.no_morph.slice(..),
    }
}

/// Base-colour textures are sRGB-encoded (glTF): sampled as linear colour.
const TEXTURE_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8UnormSrgb;

/// A 1×1 texture of one colour (the white base of untextured parts, the black added sphere).
fn solid_texture(device: &wgpu::Device, queue: &wgpu::Queue, label: &str, rgba: [u8; 4]) -> wgpu::Texture {
    device.create_texture_with_data(
        queue,
        &wgpu::TextureDescriptor {
            label: Some(label),
            size: wgpu::Extent3d { width: 1, height: 1, depth_or_array_layers: 1 },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: TEXTURE_FORMAT,
            usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
            view_formats: &[],
        },
        wgpu::util::TextureDataOrder::LayerMajor,
        &rgba,
    )
}

/// glTF sampler codes → wgpu: the minification filter's own filter within a level and its
/// filter between levels (a texture without levels ignores the latter).
fn texture_bind_group(device: &wgpu::Device, layout: &wgpu::BindGroupLayout, tex: &wgpu::Texture, s: &odori_core::import::Sampler) -> wgpu::BindGroup {
    let sampler = make_sampler(device, s);
    let view = tex.create_view(&Default::default());
    device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("base colour"),
        layout,
        entries: &[wgpu::BindGroupEntry { binding: 0, resource: wgpu::BindingResource::TextureView(&view) }, wgpu::BindGroupEntry { binding: 1, resource: wgpu::BindingResource::Sampler(&sampler) }],
    })
}

fn make_sampler(device: &wgpu::Device, s: &odori_core::import::Sampler) -> wgpu::Sampler {
    let filter = |code: Option<u32>| match code {
        Some(9728) | Some(9984) | Some(9986) => wgpu::FilterMode::Nearest,
        _ => wgpu::FilterMode::Linear,
    };
    let wrap = |code: u32| match code {
        33071 => wgpu::AddressMode::ClampToEdge,
        33648 => wgpu::AddressMode::MirrorRepeat,
        _ => wgpu::AddressMode::Repeat,
    };
    device.create_sampler(&wgpu::SamplerDescriptor {
        label: Some("base colour"),
        address_mode_u: wrap(s.wrap_s),
        address_mode_v: wrap(s.wrap_t),
        mag_filter: filter(s.mag_filter),
        min_filter: filter(s.min_filter),
        // NEAREST_MIPMAP_NEAREST and LINEAR_MIPMAP_NEAREST pick one level; the others blend two.
        mipmap_filter: match s.min_filter {
            Some(9984) | Some(9985) => wgpu::MipmapFilterMode::Nearest,
            _ => wgpu::MipmapFilterMode::Linear,
        },
        ..Default::default()
    })
}

/// Distinct figure colours (linear RGB): orange, teal, violet, lime, rose, sky, amber, mint.
pub const FIGURE_COLORS: [[f32; 4]; 8] = [
    [0.95, 0.45, 0.10, 1.0],
    [0.10, 0.65, 0.80, 1.0],
    [0.60, 0.35, 0.90, 1.0],
    [0.45, 0.80, 0.15, 1.0],
    [0.90, 0.25, 0.45, 1.0],
    [0.35, 0.55, 0.95, 1.0],
    [0.95, 0.75, 0.15, 1.0],
    [0.25, 0.85, 0.60, 1.0],
];

/// Matrix helper for callers: palette entry = world · bind.
pub fn palette_entry(world: Mat4, bind: Mat4) -> Mat4 {
    world * bind
}
