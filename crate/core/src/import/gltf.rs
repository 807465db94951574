//! glTF 2.0 / GLB reader (through the `gltf` crate): node hierarchy and skins become one
//! skeleton, every animation its own clip resampled to a fixed rate (LINEAR, STEP and
//! CUBICSPLINE samplers), and the meshes are kept for GPU skinning.
//!
//! Node scale is baked into offsets (uniform scale; a non-uniform one is averaged, with a
//! warning), so the clip's forward kinematics stays rigid and in metres. Buffers are checked
//! against every accessor before anything is read, so a broken file is an error, not a panic.

use crate::fmath;
use std::collections::{BTreeSet, HashMap};
use std::sync::Arc;

use glam::{Mat4, Quat, Vec3};
use gltf::animation::{Interpolation, Property};
use serde::{Deserialize, Serialize};

use super::{finish, stem, Format, ImportError, ImportOptions, Imported};
use crate::clip::{Clip, TranslationTrack};
use crate::skeleton::{Joint, Skeleton};

/// One drawable primitive. Vertex `joints` index the mesh's `palette`.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct MeshPart {
    pub positions: Vec<[f32; 3]>,
    pub normals: Vec<[f32; 3]>,
    pub joints: Vec<[u16; 4]>,
    pub weights: Vec<[f32; 4]>,
    pub indices: Vec<u32>,
    /// Linear RGBA base colour of the material.
    pub color: [f32; 4],
    /// The material's base-colour texture (an index into [`SkinnedMesh::textures`]), which
    /// multiplies `color`; `uvs` are its texture coordinates (the set the material names),
    /// one per vertex. Empty and `None` for an untextured part.
    #[serde(default)]
    pub texture: Option<usize>,
    #[serde(default)]
    pub uvs: Vec<[f32; 2]>,
    /// The material's `KHR_texture_transform` on its base-colour texture, applied to `uvs`
    /// when sampling (the drawing side's, and written back on export). `None`: the UVs as they are.
    #[serde(default)]
    pub uv_transform: Option<UvTransform>,
    /// MMD-style drawing (PMX/PMD models, `mmd::mesh`): a toon ramp and an outline. `None` for
    /// glTF parts (and ignored by GLB export).
    #[serde(default)]
    pub toon: Option<ToonLook>,
    /// MMD: per vertex, the factor on the outline's width there (PMX's vertex edge scale; PMD
    /// 0 where a vertex's edge flag turns the edge off). Empty: 1 everywhere (glTF parts).
    #[serde(default)]
    pub edge_scales: Vec<f32>,
    /// MMD: per vertex, the UV the sphere map is sampled at as an ordinary texture (PMX sphere
    /// mode 3, the sub-texture: the vertex's additional UV 1). Empty: the sphere map, if any,
    /// is looked up by the view-space normal.
    #[serde(default)]
    pub sphere_uvs: Vec<[f32; 2]>,
}

/// How an MMD material is drawn besides its colour and texture: its toon ramp looked up on
/// N·L (v = ½(1 − N·L), top lit), and an inverted-hull outline.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct ToonLook {
    /// The ramp texture, an index into [`SkinnedMesh::textures`]; `None`: no ramp (white).
    pub ramp: Option<usize>,
    /// Outline colour, RGBA.
    pub edge_colour: [f32; 4],
    /// Outline width, metres per metre of distance from the camera (so it keeps its width on
    /// screen); 0: no outline.
    pub edge_width: f32,
    /// The sphere map (MMD's `.sph`/`.spa`, PMX's sphere texture), an index into
    /// [`SkinnedMesh::textures`], looked up by the view-space normal; `None`: none.
    #[serde(default)]
    pub sphere: Option<usize>,
    /// How the sphere map combines with the colour: added (`.spa`, PMX mode 2), else
    /// multiplied (`.sph`, PMX mode 1; the sub-texture, mode 3, sampled at the part's
    /// [`MeshPart::sphere_uvs`]).
    #[serde(default)]
    pub sphere_add: bool,
}

/// A `KHR_texture_transform`: the UVs are scaled, then rotated, then offset
/// (uv' = T · R · S · uv). The rotation is the one the implementations and the Khronos sample
/// model agree on (glTF issue #1563: the extension's GLSL listing has the sign of the sine
/// wrong for a V-down UV space): u' = cos·u + sin·v, v' = −sin·u + cos·v.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct UvTransform {
    pub offset: [f32; 2],
    pub rotation_rad: f32,
    pub scale: [f32; 2],
}

impl Default for UvTransform {
    fn default() -> Self {
        UvTransform { offset: [0.0, 0.0], rotation_rad: 0.0, scale: [1.0, 1.0] }
    }
}

impl UvTransform {
    /// Where `uv` samples the texture.
    pub fn apply(&self, uv: [f32; 2]) -> [f32; 2] {
        let (s, c) = fmath::sin_cos(self.rotation_rad);
        let (x, y) = (uv[0] * self.scale[0], uv[1] * self.scale[1]);
        [c * x + s * y + self.offset[0], -s * x + c * y + self.offset[1]]
    }
}

/// How a texture is sampled (glTF's sampler codes: 9728 nearest, 9729 linear, the mipmap
/// minifications; 33071 clamp, 33648 mirrored repeat, 10497 repeat).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct Sampler {
    pub mag_filter: Option<u32>,
    pub min_filter: Option<u32>,
    pub wrap_s: u32,
    pub wrap_t: u32,
}

impl Default for Sampler {
    fn default() -> Self {
        Sampler { mag_filter: None, min_filter: None, wrap_s: 10497, wrap_t: 10497 }
    }
}

/// A base-colour texture as the file holds it: the encoded image (PNG or JPEG; decoding is
/// the drawing side's, the browser's decoders in the app) and its sampler.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct MeshTexture {
    /// `image/png` or `image/jpeg`.
    pub mime_type: String,
    pub image: Vec<u8>,
    pub sampler: Sampler,
}

/// A character's drawable parts, skinned to the clip skeleton.
///
/// A vertex ends at `Σ weight · world(joint) · bind` over its palette entries, where
/// `world(joint)` is [`crate::motion::WorldPose::matrices_into`]. Rigidly parented meshes are palette
/// entries with one joint and weight 1.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct SkinnedMesh {
    pub parts: Vec<MeshPart>,
    /// (skeleton joint, bind matrix) per palette slot.
    pub palette: Vec<(usize, Mat4)>,
    /// Base-colour textures the parts refer to.
    #[serde(default)]
    pub textures: Vec<MeshTexture>,
}

fn gerr(file: &str, message: impl Into<String>) -> ImportError {
    ImportError::Gltf { file: file.to_string(), message: message.into() }
}

/// Checks that every buffer view and accessor lies inside the data it points at.
fn check_buffers(file: &str, doc: &gltf::Document, data: &[Vec<u8>]) -> Result<(), ImportError> {
    for b in doc.buffers() {
        let have = data[b.index()].len();
        if have < b.length() {
            return Err(gerr(file, format!("buffer {} declares {} bytes but only {have} are present (truncated or broken file)", b.index(), b.length())));
        }
    }
    for v in doc.views() {
        let blen = data[v.buffer().index()].len();
        if v.offset().checked_add(v.length()).is_none_or(|end| end > blen) {
            return Err(gerr(file, format!("buffer view {} (bytes {}..{}) runs past the end of buffer {} ({blen} bytes)", v.index(), v.offset(), v.offset() + v.length(), v.buffer().index())));
        }
    }
    let check_view = |what: String, view: gltf::buffer::View, offset: usize, count: usize, elem: usize| -> Result<(), ImportError> {
        if count == 0 {
            return Ok(());
        }
        let stride = view.stride().unwrap_or(elem);
        let need = offset.checked_add(stride.saturating_mul(count - 1)).and_then(|x| x.checked_add(elem));
        if need.is_none_or(|n| n > view.length()) {
            return Err(gerr(file, format!("{what} needs {} bytes but its buffer view {} has {}", need.unwrap_or(usize::MAX), view.index(), view.length())));
        }
        Ok(())
    };
    for a in doc.accessors() {
        // Without a buffer view an accessor is zeros (plus any sparse values): nothing bounds
        // its count but the JSON, so bound it here before a reader allocates for it.
        if a.view().is_none() && a.count() > super::MAX_VIEWLESS_ACCESSOR_ELEMENTS {
            return Err(ImportError::TooLarge {
                file: file.to_string(),
                what: format!("accessor {} declares {} elements with no buffer data behind them", a.index(), a.count()),
                limit: format!("{} elements", super::MAX_VIEWLESS_ACCESSOR_ELEMENTS),
            });
        }
        // glTF requires count ≥ 1 and a stride of at least one element; the crate's readers
        // compute `count − 1` and assume the stride (found by fuzzing).
        if a.count() == 0 {
            return Err(gerr(file, format!("accessor {} has no elements (count 0; glTF requires at least 1)", a.index())));
        }
        if let Some(stride) = a.view().and_then(|v| v.stride()).filter(|&st| st < a.size()) {
            return Err(gerr(file, format!("accessor {}: its buffer view's stride {stride} is shorter than one element ({} bytes)", a.index(), a.size())));
        }
        if let Some(s) = a.sparse().filter(|s| s.count() > a.count()) {
            return Err(gerr(file, format!("accessor {} has {} sparse values for {} elements", a.index(), s.count(), a.count())));
        }
        if let Some(view) = a.view() {
            check_view(format!("accessor {}", a.index()), view, a.offset(), a.count(), a.size())?;
        }
        if let Some(s) = a.sparse() {
            let iv = s.indices();
            let isz = match iv.index_type() {
                gltf::accessor::sparse::IndexType::U8 => 1,
                gltf::accessor::sparse::IndexType::U16 => 2,
                gltf::accessor::sparse::IndexType::U32 => 4,
            };
            check_view(format!("sparse indices of accessor {}", a.index()), iv.view(), iv.offset() as usize, s.count(), isz)?;
            let vv = s.values();
            check_view(format!("sparse values of accessor {}", a.index()), vv.view(), vv.offset() as usize, s.count(), a.size())?;
        }
    }
    Ok(())
}

/// Checks every enum value and index the gltf crate unwraps when it is read (found by fuzzing:
/// an animation channel whose `path` is not a known property passes its validation and then
/// panics in `Channel::target().property()`). What is refused here can never panic there.
fn check_references(file: &str, root: &gltf::json::Root) -> Result<(), ImportError> {
    use gltf::json::validation::Checked;
    let invalid = |what: String| Err(gerr(file, what));
    use gltf::json::accessor::{ComponentType, GenericComponentType, Type};
    use gltf::json::mesh::Semantic;
    let (nodes, accessors) = (root.nodes.len(), root.accessors.len());
    for (i, a) in root.accessors.iter().enumerate() {
        if matches!(a.component_type, Checked::Invalid) || matches!(a.type_, Checked::Invalid) {
            return invalid(format!("accessor {i} has an unknown component type or element type"));
        }
    }
    // The element type each use reads (the crate's readers assume it: a VEC4 read as times
    // failed a size assertion, found by fuzzing). Indices are checked below before use.
    let type_of = |i: usize| match root.accessors.get(i).map(|a| a.type_) {
        Some(Checked::Valid(t)) => Some(t),
        _ => None,
    };
    let expect = |i: usize, want: Type, what: &str| -> Result<(), ImportError> {
        if i < accessors && type_of(i) != Some(want) {
            return Err(gerr(file, format!("{what}: accessor {i} holds {:?} elements, {want:?} expected", type_of(i))));
        }
        Ok(())
    };
    // And the component types the readers handle (others hit `unreachable!` in the crate,
    // found by fuzzing: a rotation of u32 components).
    let component = |i: usize, allowed: &[ComponentType], what: &str| -> Result<(), ImportError> {
        match root.accessors.get(i).map(|a| a.component_type) {
            Some(Checked::Valid(GenericComponentType(c))) if !allowed.contains(&c) => {
                Err(gerr(file, format!("{what}: accessor {i} has {c:?} components, one of {allowed:?} expected")))
            }
            _ => Ok(()),
        }
    };
    use ComponentType::{F32, I16, I8, U16, U32, U8};
    for (ai, a) in root.animations.iter().enumerate() {
        for (si, s) in a.samplers.iter().enumerate() {
            if matches!(s.interpolation, Checked::Invalid) {
                return invalid(format!("animation {ai}, sampler {si}: unknown interpolation"));
            }
            if s.input.value() >= accessors || s.output.value() >= accessors {
                return invalid(format!("animation {ai}, sampler {si}: accessor {} or {} does not exist ({accessors} accessors)", s.input.value(), s.output.value()));
            }
            expect(s.input.value(), Type::Scalar, &format!("animation {ai}, sampler {si} times"))?;
            if !matches!(root.accessors[s.input.value()].component_type, Checked::Valid(GenericComponentType(ComponentType::F32))) {
                return invalid(format!("animation {ai}, sampler {si}: keyframe times must be floats"));
            }
        }
        for (ci, c) in a.channels.iter().enumerate() {
            if matches!(c.target.path, Checked::Invalid) {
                return invalid(format!("animation {ai}, channel {ci}: the target path is not translation, rotation, scale or weights"));
            }
            if c.target.node.value() >= nodes || c.sampler.value() >= a.samplers.len() {
                return invalid(format!("animation {ai}, channel {ci}: node {} or sampler {} does not exist", c.target.node.value(), c.sampler.value()));
            }
            let want = match c.target.path {
                Checked::Valid(gltf::json::animation::Property::Rotation) => Type::Vec4,
                Checked::Valid(gltf::json::animation::Property::MorphTargetWeights) => Type::Scalar,
                _ => Type::Vec3,
            };
            let out = a.samplers[c.sampler.value()].output.value();
            expect(out, want, &format!("animation {ai}, channel {ci} values"))?;
            let allowed: &[ComponentType] = if want == Type::Vec3 { &[F32] } else { &[F32, I8, U8, I16, U16] };
            component(out, allowed, &format!("animation {ai}, channel {ci} values"))?;
        }
    }
    for (mi, m) in root.meshes.iter().enumerate() {
        for (pi, p) in m.primitives.iter().enumerate() {
            if matches!(p.mode, Checked::Invalid) || p.attributes.keys().any(|k| matches!(k, Checked::Invalid)) {
                return invalid(format!("mesh {mi}, primitive {pi}: unknown mode or attribute name"));
            }
            if p.attributes.values().chain(p.indices.iter()).any(|a| a.value() >= accessors) {
                return invalid(format!("mesh {mi}, primitive {pi}: refers to an accessor that does not exist ({accessors} accessors)"));
            }
            for (k, a) in &p.attributes {
                let (want, allowed): (Type, &[ComponentType]) = match k {
                    Checked::Valid(Semantic::Positions | Semantic::Normals) => (Type::Vec3, &[F32]),
                    Checked::Valid(Semantic::Joints(_)) => (Type::Vec4, &[U8, U16]),
                    Checked::Valid(Semantic::Weights(_)) => (Type::Vec4, &[F32, U8, U16]),
                    _ => continue,
                };
                expect(a.value(), want, &format!("mesh {mi}, primitive {pi}, {k:?}"))?;
                component(a.value(), allowed, &format!("mesh {mi}, primitive {pi}, {k:?}"))?;
            }
            if let Some(i) = p.indices {
                expect(i.value(), Type::Scalar, &format!("mesh {mi}, primitive {pi} indices"))?;
                component(i.value(), &[U8, U16, U32], &format!("mesh {mi}, primitive {pi} indices"))?;
            }
        }
    }
    for (si, skin) in root.skins.iter().enumerate() {
        if let Some(m) = skin.inverse_bind_matrices {
            if m.value() >= accessors {
                return invalid(format!("skin {si}: inverse bind matrices accessor {} does not exist", m.value()));
            }
            expect(m.value(), Type::Mat4, &format!("skin {si} inverse bind matrices"))?;
            component(m.value(), &[F32], &format!("skin {si} inverse bind matrices"))?;
        }
    }
    Ok(())
}

fn decode_base64(s: &str) -> Option<Vec<u8>> {
    let mut out = Vec::with_capacity(s.len() * 3 / 4);
    let mut acc = 0u32;
    let mut bits = 0;
    for c in s.bytes() {
        let v = match c {
            b'A'..=b'Z' => c - b'A',
            b'a'..=b'z' => c - b'a' + 26,
            b'0'..=b'9' => c - b'0' + 52,
            b'+' | b'-' => 62,
            b'/' | b'_' => 63,
            b'=' => break,
            b'\r' | b'\n' | b' ' => continue,
            _ => return None,
        } as u32;
        acc = (acc << 6) | v;
        bits += 6;
        if bits >= 8 {
            bits -= 8;
            out.push((acc >> bits) as u8);
            acc &= (1 << bits) - 1;
        }
    }
    Some(out)
}

fn load_buffers(file: &str, g: &gltf::Gltf) -> Result<Vec<Vec<u8>>, ImportError> {
    let mut out = Vec::new();
    for b in g.document.buffers() {
        let data = match b.source() {
            gltf::buffer::Source::Bin => g
                .blob
                .clone()
                .ok_or_else(|| gerr(file, format!("buffer {} refers to the GLB binary chunk, which is missing", b.index())))?,
            gltf::buffer::Source::Uri(uri) => {
                if let Some(rest) = uri.strip_prefix("data:") {
                    let (_, payload) = rest
                        .split_once(";base64,")
                        .ok_or_else(|| gerr(file, format!("buffer {}: data URI is not base64", b.index())))?;
                    decode_base64(payload).ok_or_else(|| gerr(file, format!("buffer {}: bad base64 in data URI", b.index())))?
                } else {
                    return Err(ImportError::Unsupported {
                        file: file.to_string(),
                        message: format!("buffer {} lives in a separate file '{uri}': open the .glb, or a .gltf with embedded buffers", b.index()),
                    });
                }
            }
        };
        out.push(data);
    }
    Ok(out)
}

fn uniform_scale(s: [f32; 3], warnings: &mut Vec<String>, name: &str) -> f32 {
    let m = (s[0] + s[1] + s[2]) / 3.0;
    if (s[0] - m).abs() > 1e-3 * m.abs().max(1.0) || (s[1] - m).abs() > 1e-3 * m.abs().max(1.0) {
        warnings.push(format!("node '{name}' has a non-uniform scale {s:?}; its mean {m} is used"));
    }
    m
}

struct Sampled {
    times: Vec<f32>,
    /// For CUBICSPLINE: in-tangent, value, out-tangent per key; otherwise one value per key.
    values: Vec<[f32; 4]>,
    interp: Interpolation,
}

impl Sampled {
    fn at(&self, t: f32, is_quat: bool) -> [f32; 4] {
        let n = self.times.len();
        let val = |k: usize| if self.interp == Interpolation::CubicSpline { self.values[3 * k + 1] } else { self.values[k] };
        if n == 1 || t <= self.times[0] {
            return val(0);
        }
        if t >= self.times[n - 1] {
            return val(n - 1);
        }
        let k = self.times.partition_point(|&x| x <= t) - 1;
        let (t0, t1) = (self.times[k], self.times[k + 1]);
        let dt = (t1 - t0).max(1e-9);
        let s = (t - t0) / dt;
        match self.interp {
            Interpolation::Step => val(k),
            Interpolation::Linear => {
                let (a, b) = (val(k), val(k + 1));
                if is_quat {
                    let qa = Quat::from_array(a).normalize();
                    let qb = Quat::from_array(b).normalize();
                    qa.slerp(qb, s).to_array()
                } else {
                    std::array::from_fn(|i| a[i] + (b[i] - a[i]) * s)
                }
            }
            Interpolation::CubicSpline => {
                let v0 = self.values[3 * k + 1];
                let b0 = self.values[3 * k + 2];
                let a1 = self.values[3 * (k + 1)];
                let v1 = self.values[3 * (k + 1) + 1];
                // glTF's tangents are per second: scaled by the key interval.
                let out = crate::motion::hermite(v0, b0.map(|x| dt * x), v1, a1.map(|x| dt * x), s);
                if is_quat {
                    Quat::from_array(out).normalize().to_array()
                } else {
                    out
                }
            }
        }
    }
}

/// Reads a glTF (JSON with embedded buffers) or GLB file.
pub fn import(file: &str, bytes: &[u8], options: &ImportOptions) -> Result<Imported, ImportError> {
    // The GLB header's total length must at least cover the header: the gltf crate (1.4)
    // subtracts 12 from it unchecked (found by fuzzing: an overflow panic in checked builds,
    // a wrapped length in release ones).
    if let Some(len) = bytes.strip_prefix(b"glTF").and_then(|b| b.get(4..8)) {
        let declared = u32::from_le_bytes([len[0], len[1], len[2], len[3]]) as usize;
        if declared < 12 {
            return Err(gerr(file, format!("the GLB header declares a total length of {declared} bytes, less than the 12-byte header itself")));
        }
    }
    let g = gltf::Gltf::from_slice(bytes).map_err(|e| gerr(file, e.to_string()))?;
    check_references(file, g.document.as_json())?;
    let data = load_buffers(file, &g)?;
    let doc = &g.document;
    check_buffers(file, doc, &data)?;
    let get = |b: gltf::Buffer| data.get(b.index()).map(|d| d.as_slice());
    let mut warnings = Vec::new();

    let nodes: Vec<gltf::Node> = doc.nodes().collect();
    let mut parent: Vec<Option<usize>> = vec![None; nodes.len()];
    for n in &nodes {
        for c in n.children() {
            if parent[c.index()].is_some() {
                return Err(gerr(file, format!("node {} has two parents", c.index())));
            }
            parent[c.index()] = Some(n.index());
        }
    }
    // Cycle guard: walking up from any node must end within nodes.len() steps.
    for i in 0..nodes.len() {
        let (mut k, mut steps) = (i, 0);
        while let Some(p) = parent[k] {
            k = p;
            steps += 1;
            if steps > nodes.len() {
                return Err(gerr(file, format!("the node hierarchy has a cycle through node {i}")));
            }
        }
    }

    // Nodes that move: skin joints and animation targets, with their ancestors.
    let mut selected = BTreeSet::new();
    for s in doc.skins() {
        for j in s.joints() {
            selected.insert(j.index());
        }
    }
    for a in doc.animations() {
        for c in a.channels() {
            if !matches!(c.target().property(), Property::MorphTargetWeights) {
                selected.insert(c.target().node().index());
            }
        }
    }
    if selected.is_empty() {
        return Err(ImportError::Unsupported { file: file.to_string(), message: "the file has no skin and no animation: nothing to animate".into() });
    }
    for i in selected.clone() {
        let mut k = i;
        while let Some(p) = parent[k] {
            selected.insert(p);
            k = p;
        }
    }
    // Tip nodes (no mesh) below selected joints, e.g. "Head_end", help draw the figure.
    let mut stack: Vec<usize> = selected.iter().copied().collect();
    while let Some(i) = stack.pop() {
        for c in nodes[i].children() {
            if c.mesh().is_none() && selected.insert(c.index()) {
                stack.push(c.index());
            }
        }
    }

    // Order parents before children: depth-first from the roots in file order.
    let mut order = Vec::new();
    let mut stack: Vec<usize> = (0..nodes.len()).rev().filter(|&i| parent[i].is_none() && selected.contains(&i)).collect();
    while let Some(i) = stack.pop() {
        order.push(i);
        let kids: Vec<usize> = nodes[i].children().map(|c| c.index()).filter(|c| selected.contains(c)).collect();
        stack.extend(kids.into_iter().rev());
    }
    let joint_of: HashMap<usize, usize> = order.iter().enumerate().map(|(j, &n)| (n, j)).collect();
    let animated: BTreeSet<usize> = doc
        .skins()
        .flat_map(|s| s.joints().map(|j| j.index()).collect::<Vec<_>>())
        .chain(doc.animations().flat_map(|a| a.channels().map(|c| c.target().node().index()).collect::<Vec<_>>()))
        .collect();

    // Accumulated uniform scale per node (product down the hierarchy).
    let mut acc_scale = vec![1.0f32; nodes.len()];
    let mut node_scale = vec![1.0f32; nodes.len()];
    for &i in &order {
        let (_, _, s) = nodes[i].transform().decomposed();
        node_scale[i] = uniform_scale(s, &mut warnings, nodes[i].name().unwrap_or("?"));
        acc_scale[i] = parent[i].map(|p| acc_scale[p]).unwrap_or(1.0) * node_scale[i];
    }
    // Parents outside the selection (a scene root above everything) count too.
    let parent_scale = |i: usize| parent[i].map(|p| acc_scale[p]).unwrap_or(1.0);

    let joints: Vec<Joint> = order
        .iter()
        .map(|&i| {
            let n = &nodes[i];
            let (t, r, _) = n.transform().decomposed();
            Joint {
                name: n.name().map(str::to_string).unwrap_or_else(|| format!("node{i}")),
                parent: parent[i].and_then(|p| joint_of.get(&p).copied()),
                rest_offset: Vec3::from(t) * parent_scale(i),
                rest_rotation: Quat::from_array(r).normalize(),
                end_site: !animated.contains(&i) && n.children().next().is_none(),
            }
        })
        .collect();
    let skeleton = Arc::new(Skeleton { joints });
    let nj = skeleton.len();

    // Animations.
    let fps = options.fps_override.unwrap_or(options.gltf_fps);
    if !(fps.is_finite() && fps > 0.0 && fps <= 1000.0) {
        return Err(ImportError::Invalid { file: file.to_string(), message: format!("resampling rate {fps} fps is out of range") });
    }
    let mut clips = Vec::new();
    let mut morph_seen = false;
    for (ai, anim) in doc.animations().enumerate() {
        let name = anim.name().map(str::to_string).unwrap_or_else(|| format!("{} #{ai}", stem(file)));
        let mut rot_tracks: HashMap<usize, Sampled> = HashMap::new();
        let mut pos_tracks: HashMap<usize, Sampled> = HashMap::new();
        let mut duration = 0.0f32;
        for ch in anim.channels() {
            let prop = ch.target().property();
            if matches!(prop, Property::MorphTargetWeights) {
                morph_seen = true;
                continue;
            }
            if matches!(prop, Property::Scale) {
                continue;
            }
            let node = ch.target().node().index();
            let Some(&j) = joint_of.get(&node) else { continue };
            let reader = ch.reader(get);
            let times: Vec<f32> = reader
                .read_inputs()
                .ok_or_else(|| gerr(file, format!("animation '{name}': a sampler has no input times")))?
                .collect();
            let values: Vec<[f32; 4]> = match reader.read_outputs() {
                Some(gltf::animation::util::ReadOutputs::Rotations(r)) => r.into_f32().collect(),
                Some(gltf::animation::util::ReadOutputs::Translations(t)) => t.map(|v| [v[0], v[1], v[2], 0.0]).collect(),
                _ => return Err(gerr(file, format!("animation '{name}': a sampler's outputs cannot be read"))),
            };
            let interp = ch.sampler().interpolation();
            let per_key = if interp == Interpolation::CubicSpline { 3 } else { 1 };
            if times.is_empty() || values.len() != times.len() * per_key {
                return Err(gerr(file, format!("animation '{name}': {} keyframe times but {} values", times.len(), values.len())));
            }
            if times.iter().any(|t| !t.is_finite()) || times.windows(2).any(|w| w[1] < w[0]) {
                return Err(gerr(file, format!("animation '{name}': keyframe times are not increasing")));
            }
            if values.iter().flatten().any(|v| !v.is_finite()) {
                return Err(gerr(file, format!("animation '{name}': keyframe values are not finite")));
            }
            duration = duration.max(*times.last().unwrap_or(&0.0));
            let s = Sampled { times, values, interp };
            match prop {
                Property::Rotation => rot_tracks.insert(j, s),
                _ => pos_tracks.insert(j, s),
            };
        }
        if rot_tracks.is_empty() && pos_tracks.is_empty() {
            continue;
        }
        if duration > 3600.0 {
            return Err(ImportError::Invalid { file: file.to_string(), message: format!("animation '{name}' lasts {duration} s; longer than an hour is refused") });
        }
        // Enough frames that the last one reaches the animation's end (sampling clamps there).
        let frames = (duration * fps - 1e-3).ceil().max(0.0) as usize + 1;
        if frames.saturating_mul(nj) > super::MAX_SAMPLES {
            return Err(ImportError::TooLarge {
                file: file.to_string(),
                what: format!("animation '{name}': {frames} frames of {nj} joints at {fps} fps"),
                limit: format!("{} joint samples", super::MAX_SAMPLES),
            });
        }
        let mut rotations = Vec::with_capacity(frames * nj);
        let mut pos_joints: Vec<usize> = pos_tracks.keys().copied().collect();
        pos_joints.sort_unstable();
        let mut translations: Vec<TranslationTrack> =
            pos_joints.iter().map(|&j| TranslationTrack { joint: j, values: Vec::with_capacity(frames) }).collect();
        for f in 0..frames {
            let t = f as f32 / fps;
            for (j, joint) in skeleton.joints.iter().enumerate() {
                rotations.push(match rot_tracks.get(&j) {
                    Some(s) => Quat::from_array(s.at(t, true)).normalize(),
                    None => joint.rest_rotation,
                });
            }
            for tr in translations.iter_mut() {
                let v = pos_tracks[&tr.joint].at(t, false);
                tr.values.push(Vec3::new(v[0], v[1], v[2]) * parent_scale(order[tr.joint]));
            }
        }
        clips.push(Clip { name, source: file.to_string(), fps, skeleton: skeleton.clone(), rotations, translations });
    }
    if morph_seen {
        warnings.push("morph-target (blend shape) animation is not played".into());
    }
    if clips.is_empty() {
        clips.push(Clip {
            name: format!("{} (rest pose)", stem(file)),
            source: file.to_string(),
            fps,
            skeleton: skeleton.clone(),
            rotations: skeleton.joints.iter().map(|j| j.rest_rotation).collect(),
            translations: vec![],
        });
    }

    let mesh = read_meshes(file, &data, &nodes, &parent, &joint_of, &acc_scale, &mut warnings)?;
    finish(Format::Gltf, file, skeleton, clips, mesh, warnings)
}

/// A texture's embedded image (in a buffer view, or a `data:` URI) and sampler; `None` for
/// an image in an outside file or of a type the drawing side cannot decode.
fn read_texture(tex: &gltf::Texture<'_>, data: &[Vec<u8>]) -> Option<MeshTexture> {
    let s = tex.sampler();
    let sampler = Sampler {
        mag_filter: s.mag_filter().map(|f| f.as_gl_enum()),
        min_filter: s.min_filter().map(|f| f.as_gl_enum()),
        wrap_s: s.wrap_s().as_gl_enum(),
        wrap_t: s.wrap_t().as_gl_enum(),
    };
    let (mime_type, image) = match tex.source().source() {
        gltf::image::Source::View { view, mime_type } => {
            let buf = data.get(view.buffer().index())?;
            (mime_type.to_string(), buf.get(view.offset()..view.offset().checked_add(view.length())?)?.to_vec())
        }
        gltf::image::Source::Uri { uri, mime_type } => {
            let rest = uri.strip_prefix("data:")?;
            let (head, body) = rest.split_once(";base64,")?;
            (mime_type.unwrap_or(head).to_string(), decode_base64(body)?)
        }
    };
    // The file's word for the type, checked against the bytes themselves.
    let sniffed = if image.starts_with(b"\x89PNG\r\n\x1a\n") {
        "image/png"
    } else if image.starts_with(&[0xFF, 0xD8, 0xFF]) {
        "image/jpeg"
    } else {
        return None;
    };
    let _ = mime_type;
    Some(MeshTexture { mime_type: sniffed.to_string(), image, sampler })
}

fn read_meshes(
    file: &str,
    data: &[Vec<u8>],
    nodes: &[gltf::Node<'_>],
    parent: &[Option<usize>],
    joint_of: &HashMap<usize, usize>,
    acc_scale: &[f32],
    warnings: &mut Vec<String>,
) -> Result<Option<SkinnedMesh>, ImportError> {
    let get = |b: gltf::Buffer<'_>| data.get(b.index()).map(|d| d.as_slice());
    let mut mesh = SkinnedMesh::default();
    // glTF texture index → index in `mesh.textures` (each image is kept once).
    let mut texture_of: HashMap<usize, Option<usize>> = HashMap::new();
    for n in nodes {
        let Some(m) = n.mesh() else { continue };
        // Palette slots this node's vertices refer to.
        let slot_base = mesh.palette.len();
        let skinned = if let Some(skin) = n.skin() {
            let ibm: Vec<Mat4> = match skin.reader(get).read_inverse_bind_matrices() {
                Some(it) => it.map(|c| Mat4::from_cols_array_2d(&c)).collect(),
                None => vec![Mat4::IDENTITY; skin.joints().count()],
            };
            if ibm.len() < skin.joints().count() {
                return Err(gerr(file, format!("skin {} has {} joints but {} inverse bind matrices", skin.index(), skin.joints().count(), ibm.len())));
            }
            for (k, jn) in skin.joints().enumerate() {
                let j = joint_of[&jn.index()];
                mesh.palette.push((j, Mat4::from_scale(Vec3::splat(acc_scale[jn.index()])) * ibm[k]));
            }
            true
        } else {
            // A rigid part: find the nearest ancestor that is a joint.
            let mut k = n.index();
            let mut local = Mat4::from_cols_array_2d(&n.transform().matrix());
            let mut found = None;
            while let Some(p) = parent[k] {
                if let Some(&j) = joint_of.get(&p) {
                    found = Some((j, p));
                    break;
                }
                local = Mat4::from_cols_array_2d(&nodes[p].transform().matrix()) * local;
                k = p;
            }
            match found {
                Some((j, p)) => mesh.palette.push((j, Mat4::from_scale(Vec3::splat(acc_scale[p])) * local)),
                None => {
                    warnings.push(format!("mesh node '{}' is not attached to the skeleton and is not drawn", n.name().unwrap_or("?")));
                    continue;
                }
            }
            false
        };
        let slots = mesh.palette.len() - slot_base;
        for prim in m.primitives() {
            if prim.mode() != gltf::mesh::Mode::Triangles {
                warnings.push(format!("a primitive of mesh '{}' is not triangles and is not drawn", m.name().unwrap_or("?")));
                continue;
            }
            let r = prim.reader(get);
            let Some(pos) = r.read_positions() else { continue };
            let positions: Vec<[f32; 3]> = pos.collect();
            let nv = positions.len();
            let normals: Vec<[f32; 3]> = match r.read_normals() {
                Some(it) => it.collect(),
                None => vec![[0.0, 1.0, 0.0]; nv],
            };
            let indices: Vec<u32> = match r.read_indices() {
                Some(it) => it.into_u32().collect(),
                None => (0..nv as u32).collect(),
            };
            if normals.len() != nv {
                return Err(gerr(file, format!("mesh '{}': {} normals for {nv} positions", m.name().unwrap_or("?"), normals.len())));
            }
            if let Some(bad) = indices.iter().find(|&&i| i as usize >= nv) {
                return Err(gerr(file, format!("mesh '{}': index {bad} but only {nv} vertices", m.name().unwrap_or("?"))));
            }
            let (joints, weights): (Vec<[u16; 4]>, Vec<[f32; 4]>) = if skinned {
                let js: Vec<[u16; 4]> = r.read_joints(0).map(|j| j.into_u16().collect()).unwrap_or_default();
                let ws: Vec<[f32; 4]> = r.read_weights(0).map(|w| w.into_f32().collect()).unwrap_or_default();
                if js.len() != nv || ws.len() != nv {
                    return Err(gerr(file, format!("skinned mesh '{}' lacks JOINTS_0/WEIGHTS_0 for its {nv} vertices", m.name().unwrap_or("?"))));
                }
                if let Some(j) = js.iter().flatten().find(|&&j| j as usize >= slots) {
                    return Err(gerr(file, format!("skinned mesh '{}' names joint {j} of a skin with {slots}", m.name().unwrap_or("?"))));
                }
                (js.into_iter().map(|j| j.map(|x| x + slot_base as u16)).collect(), ws)
            } else {
                (vec![[slot_base as u16, 0, 0, 0]; nv], vec![[1.0, 0.0, 0.0, 0.0]; nv])
            };
            let pbr = prim.material().pbr_metallic_roughness();
            let mut part = MeshPart { positions, normals, joints, weights, indices, color: pbr.base_color_factor(), ..Default::default() };
            if let Some(info) = pbr.base_color_texture() {
                // The transform's own texCoord, when it has one, overrides the texture's.
                // (Read only with the `export-textures` feature: the player build leaves it out.)
                #[cfg(feature = "export-textures")]
                let transform = info.texture_transform().map(|t| (UvTransform { offset: t.offset(), rotation_rad: t.rotation(), scale: t.scale() }, t.tex_coord()));
                #[cfg(not(feature = "export-textures"))]
                let transform: Option<(UvTransform, Option<u32>)> = None;
                let set = transform.and_then(|t| t.1).unwrap_or(info.tex_coord());
                let uvs: Vec<[f32; 2]> = r.read_tex_coords(set).map(|t| t.into_f32().collect()).unwrap_or_default();
                let tex = info.texture();
                let slot = *texture_of.entry(tex.index()).or_insert_with(|| {
                    let t = read_texture(&tex, data);
                    if t.is_none() {
                        warnings.push(format!("texture {} is not an embedded PNG or JPEG image and is not drawn", tex.index()));
                    }
                    t.map(|t| {
                        mesh.textures.push(t);
                        mesh.textures.len() - 1
                    })
                });
                if uvs.len() == nv && slot.is_some() {
                    part.texture = slot;
                    part.uvs = uvs;
                    part.uv_transform = transform.map(|t| t.0);
                    if let Some(t) = part.uv_transform.filter(|t| !(t.offset.iter().chain(&t.scale).all(|v| v.is_finite()) && t.rotation_rad.is_finite())) {
                        warnings.push(format!("mesh '{}': its texture transform {t:?} is not finite and is ignored", m.name().unwrap_or("?")));
                        part.uv_transform = None;
                    }
                } else if slot.is_some() {
                    warnings.push(format!("mesh '{}' has a texture but no TEXCOORD_{set} for its {nv} vertices; its base colour is used", m.name().unwrap_or("?")));
                }
            }
            mesh.parts.push(part);
        }
    }
    Ok(if mesh.parts.is_empty() { None } else { Some(mesh) })
}
