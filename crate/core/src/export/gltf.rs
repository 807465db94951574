//! GLB writer (spec §M) built on `gltf-json`, the `gltf` crate's own JSON types, and its
//! `binary::Glb` (which pads both chunks to 4 bytes).
//!
//! Layout of what is written: one node per skeleton joint with separate translation and
//! rotation (the rest pose; no matrices, no scale), the joints' roots and one mesh node at the
//! scene root; one skin over every joint whose inverse bind matrices are the exact inverses of
//! the rest pose's rigid world transforms; one animation per clip with LINEAR samplers, one
//! shared time accessor per clip (strictly increasing, with min/max), a rotation channel per
//! joint (unit quaternions, made sign-continuous) and a translation channel per animated
//! translation. The mesh is written in the rest pose: each vertex is moved to where the
//! product's own skinning puts it at rest, so a character bound in another pose (or with
//! several bind matrices per joint, as the importer's palette allows) comes out bound at rest
//! with the same look; a rig bound at rest (the usual case) keeps its vertices exactly.
//!
//! A textured part keeps its look: its UV set is written as `TEXCOORD_0`, its base-colour
//! image (PNG or JPEG, byte for byte) goes into the binary chunk through a buffer view with its
//! MIME type, with the source's sampler, and its `KHR_texture_transform` is written back (and
//! named in `extensionsUsed`).

use std::borrow::Cow;
use std::collections::BTreeMap;

use glam::{Mat3, Mat4, Quat, Vec3};
use gltf::json;
use json::validation::{Checked::Valid, USize64};

use super::{check_clips, ExportError};
use crate::clip::Clip;
use crate::import::{MeshTexture, SkinnedMesh, UvTransform};
use crate::motion;
use crate::skeleton::Skeleton;

/// What the GLB holds besides the skeleton.
#[derive(Clone, Copy, Debug, Default)]
pub struct GlbOptions<'a> {
    /// The character's drawable parts, skinned to the exported skeleton (the built-in body,
    /// or an imported character's own mesh). `None`: a skeleton and animations only.
    pub mesh: Option<&'a SkinnedMesh>,
}

/// Collects the binary chunk: every piece starts on a 4-byte boundary.
pub(super) struct Bin {
    bytes: Vec<u8>,
    views: Vec<json::buffer::View>,
    accessors: Vec<json::Accessor>,
}

pub(super) enum Kind {
    Scalar,
    // UVs, written only with the `export-textures` feature.
    #[cfg_attr(not(feature = "export-textures"), allow(dead_code))]
    Vec2,
    Vec3,
    Vec4,
    Mat4,
}

impl Bin {
    fn view(&mut self, data: &[u8], target: Option<json::buffer::Target>) -> json::Index<json::buffer::View> {
        while !self.bytes.len().is_multiple_of(4) {
            self.bytes.push(0);
        }
        let offset = self.bytes.len();
        self.bytes.extend_from_slice(data);
        self.views.push(json::buffer::View {
            buffer: json::Index::new(0),
            byte_length: USize64::from(data.len()),
            byte_offset: Some(USize64::from(offset)),
            byte_stride: None,
            name: None,
            target: target.map(Valid),
            extensions: None,
            extras: Default::default(),
        });
        json::Index::new(self.views.len() as u32 - 1)
    }

    pub(super) fn accessor(
        &mut self,
        data: &[u8],
        count: usize,
        component: json::accessor::ComponentType,
        kind: Kind,
        target: Option<json::buffer::Target>,
        min_max: Option<(Vec<f32>, Vec<f32>)>,
    ) -> json::Index<json::Accessor> {
        let view = self.view(data, target);
        let type_ = match kind {
            Kind::Scalar => json::accessor::Type::Scalar,
            Kind::Vec2 => json::accessor::Type::Vec2,
            Kind::Vec3 => json::accessor::Type::Vec3,
            Kind::Vec4 => json::accessor::Type::Vec4,
            Kind::Mat4 => json::accessor::Type::Mat4,
        };
        let (min, max) = match min_max {
            Some((a, b)) => (Some(serde_json::json!(a)), Some(serde_json::json!(b))),
            None => (None, None),
        };
        self.accessors.push(json::Accessor {
            buffer_view: Some(view),
            byte_offset: None,
            count: USize64::from(count),
            component_type: Valid(json::accessor::GenericComponentType(component)),
            extensions: None,
            extras: Default::default(),
            type_: Valid(type_),
            min,
            max,
            name: None,
            normalized: false,
            sparse: None,
        });
        json::Index::new(self.accessors.len() as u32 - 1)
    }
}

pub(super) fn f32_bytes(values: impl IntoIterator<Item = f32>) -> Vec<u8> {
    values.into_iter().flat_map(f32::to_le_bytes).collect()
}

fn vec3_min_max(v: &[[f32; 3]]) -> (Vec<f32>, Vec<f32>) {
    let mut lo = [f32::INFINITY; 3];
    let mut hi = [f32::NEG_INFINITY; 3];
    for p in v {
        for k in 0..3 {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
    }
    (lo.to_vec(), hi.to_vec())
}

/// One vertex's influences as (joint, weight), merged by joint, the 4 largest kept, weights
/// summing to 1; unused slots are (0, 0).
fn influences(slots: [u16; 4], weights: [f32; 4], palette: &[(usize, Mat4)]) -> ([u16; 4], [f32; 4]) {
    let mut by_joint: BTreeMap<usize, f32> = BTreeMap::new();
    for (s, w) in slots.iter().zip(weights) {
        if w > 0.0 {
            if let Some(&(j, _)) = palette.get(*s as usize) {
                *by_joint.entry(j).or_insert(0.0) += w;
            }
        }
    }
    let mut list: Vec<(usize, f32)> = by_joint.into_iter().collect();
    list.sort_by(|a, b| b.1.total_cmp(&a.1));
    list.truncate(4);
    let total: f32 = list.iter().map(|x| x.1).sum();
    let mut j = [0u16; 4];
    let mut w = [0f32; 4];
    if total <= 0.0 {
        // No usable weight: hang the vertex on the first palette joint, as the product draws it.
        j[0] = palette.first().map(|p| p.0 as u16).unwrap_or(0);
        w[0] = 1.0;
        return (j, w);
    }
    for (k, (joint, weight)) in list.iter().enumerate() {
        j[k] = *joint as u16;
        w[k] = weight / total;
    }
    // The validator sums the stored floats: make the largest take up the rounding.
    let rest: f32 = w[1..].iter().sum();
    w[0] = 1.0 - rest;
    (j, w)
}

/// The mesh in rest-pose model space: positions, unit normals, joints, weights and indices per part.
struct RestPart {
    positions: Vec<[f32; 3]>,
    normals: Vec<[f32; 3]>,
    joints: Vec<[u16; 4]>,
    weights: Vec<[f32; 4]>,
    indices: Vec<u32>,
    color: [f32; 4],
    /// The base-colour texture (an index into the mesh's textures), its UVs and transform.
    texture: Option<(usize, Vec<[f32; 2]>, Option<UvTransform>)>,
}

fn rest_parts(mesh: &SkinnedMesh, rest: &[Mat4], joints: usize) -> Result<Vec<RestPart>, ExportError> {
    if joints > u16::MAX as usize {
        return Err(ExportError::BadMesh { part: 0, message: format!("{joints} joints is more than a glTF skin's 16-bit joint indices can name") });
    }
    for (slot, (j, m)) in mesh.palette.iter().enumerate() {
        if *j >= joints {
            return Err(ExportError::BadMesh { part: 0, message: format!("palette slot {slot} names joint {j} of a skeleton with {joints}") });
        }
        if !m.is_finite() {
            return Err(ExportError::BadMesh { part: 0, message: format!("palette slot {slot} has a bind matrix that is not finite") });
        }
    }
    let mut out = Vec::with_capacity(mesh.parts.len());
    for (pi, part) in mesh.parts.iter().enumerate() {
        let nv = part.positions.len();
        if part.normals.len() != nv || part.joints.len() != nv || part.weights.len() != nv {
            return Err(ExportError::BadMesh {
                part: pi,
                message: format!("{nv} positions but {} normals, {} joints, {} weights", part.normals.len(), part.joints.len(), part.weights.len()),
            });
        }
        if let Some(bad) = part.indices.iter().find(|&&i| i as usize >= nv) {
            return Err(ExportError::BadMesh { part: pi, message: format!("index {bad} but only {nv} vertices") });
        }
        if part.indices.len() % 3 != 0 || part.indices.is_empty() {
            return Err(ExportError::BadMesh { part: pi, message: format!("{} indices is not a whole number of triangles", part.indices.len()) });
        }
        let mut rp = RestPart {
            positions: Vec::with_capacity(nv),
            normals: Vec::with_capacity(nv),
            joints: Vec::with_capacity(nv),
            weights: Vec::with_capacity(nv),
            indices: part.indices.clone(),
            color: part.color.map(|c| if c.is_finite() { c.clamp(0.0, 1.0) } else { 1.0 }),
            texture: None,
        };
        // Without the feature (the player build) a character is written untextured.
        if let (true, Some(t)) = (cfg!(feature = "export-textures"), part.texture) {
            if t >= mesh.textures.len() {
                return Err(ExportError::BadMesh { part: pi, message: format!("texture {t} but the mesh has {}", mesh.textures.len()) });
            }
            if part.uvs.len() != nv {
                return Err(ExportError::BadMesh { part: pi, message: format!("a texture but {} UVs for {nv} vertices", part.uvs.len()) });
            }
            if let Some(v) = part.uvs.iter().position(|uv| !uv.iter().all(|x| x.is_finite())) {
                return Err(ExportError::BadMesh { part: pi, message: format!("UV {v} is not finite") });
            }
            // A transform that is not finite is left out, as the importer leaves it out.
            let transform = part.uv_transform.filter(|x| x.offset.iter().chain(&x.scale).chain([&x.rotation_rad]).all(|v| v.is_finite()));
            rp.texture = Some((t, part.uvs.clone(), transform));
        }
        for v in 0..nv {
            // Where the product's skinning puts the vertex at rest: Σ w · rest(joint) · bind.
            let mut m = Mat4::ZERO;
            let mut total = 0.0;
            for (s, w) in part.joints[v].iter().zip(part.weights[v]) {
                if w > 0.0 {
                    if let Some((j, bind)) = mesh.palette.get(*s as usize) {
                        m += (rest[*j] * *bind) * w;
                        total += w;
                    }
                }
            }
            let m = if total > 0.0 { m * (1.0 / total) } else { mesh.palette.first().map(|(j, b)| rest[*j] * *b).unwrap_or(Mat4::IDENTITY) };
            let p = m.transform_point3(Vec3::from(part.positions[v]));
            let nm = Mat3::from_mat4(m).inverse().transpose();
            let n = (nm * Vec3::from(part.normals[v])).try_normalize().unwrap_or(Vec3::Y);
            if !p.is_finite() {
                return Err(ExportError::BadMesh { part: pi, message: format!("vertex {v} is not finite at rest") });
            }
            let (j, w) = influences(part.joints[v], part.weights[v], &mesh.palette);
            rp.positions.push(p.to_array());
            rp.normals.push(n.to_array());
            rp.joints.push(j);
            rp.weights.push(w);
        }
        out.push(rp);
    }
    Ok(out)
}

/// Writes `clips` (all on `skeleton`) as one GLB: the skeleton as nodes, the mesh and skin
/// when `options.mesh` is given, one animation per clip.
pub fn glb(skeleton: &Skeleton, clips: &[&Clip], options: &GlbOptions) -> Result<Vec<u8>, ExportError> {
    check_clips(skeleton, clips)?;
    let n = skeleton.len();
    let (rest_rot, rest_pos) = motion::rest_world(skeleton);
    let (rest_m, rest_inv): (Vec<Mat4>, Vec<Mat4>) = rest_rot.iter().zip(&rest_pos).map(|(r, p)| motion::rigid(*r, *p)).unzip();

    let (mut root, mut bin) = start();
    let mut scene_nodes = joint_nodes(&mut root, skeleton);

    // Mesh, materials and skin.
    if let Some(mesh) = options.mesh.filter(|m| !m.parts.is_empty()) {
        let parts = rest_parts(mesh, &rest_m, n)?;
        let texture_index = if cfg!(feature = "export-textures") { textures(&mut root, &mut bin, &mesh.textures, &parts) } else { Vec::new() };
        let mut primitives = Vec::new();
        for (pi, part) in parts.iter().enumerate() {
            use json::accessor::ComponentType as C;
            use json::buffer::Target::{ArrayBuffer, ElementArrayBuffer};
            let nv = part.positions.len();
            let pos = bin.accessor(&f32_bytes(part.positions.iter().flatten().copied()), nv, C::F32, Kind::Vec3, Some(ArrayBuffer), Some(vec3_min_max(&part.positions)));
            let nor = bin.accessor(&f32_bytes(part.normals.iter().flatten().copied()), nv, C::F32, Kind::Vec3, Some(ArrayBuffer), None);
            let jb: Vec<u8> = part.joints.iter().flatten().flat_map(|x| x.to_le_bytes()).collect();
            let jnt = bin.accessor(&jb, nv, C::U16, Kind::Vec4, Some(ArrayBuffer), None);
            let wgt = bin.accessor(&f32_bytes(part.weights.iter().flatten().copied()), nv, C::F32, Kind::Vec4, Some(ArrayBuffer), None);
            let ib: Vec<u8> = part.indices.iter().flat_map(|x| x.to_le_bytes()).collect();
            let idx = bin.accessor(&ib, part.indices.len(), C::U32, Kind::Scalar, Some(ElementArrayBuffer), None);
            let (base_color_texture, uv) = part_texture(&mut root, &mut bin, part, &texture_index);
            root.materials.push(json::Material {
                name: Some(format!("material {pi}")),
                pbr_metallic_roughness: json::material::PbrMetallicRoughness {
                    base_color_texture,
                    base_color_factor: json::material::PbrBaseColorFactor(part.color),
                    metallic_factor: json::material::StrengthFactor(0.0),
                    roughness_factor: json::material::StrengthFactor(0.8),
                    ..Default::default()
                },
                ..Default::default()
            });
            let mut attributes = BTreeMap::new();
            attributes.insert(Valid(json::mesh::Semantic::Positions), pos);
            attributes.insert(Valid(json::mesh::Semantic::Normals), nor);
            if let Some(uv) = uv {
                attributes.insert(Valid(json::mesh::Semantic::TexCoords(0)), uv);
            }
            attributes.insert(Valid(json::mesh::Semantic::Joints(0)), jnt);
            attributes.insert(Valid(json::mesh::Semantic::Weights(0)), wgt);
            primitives.push(json::mesh::Primitive {
                attributes,
                extensions: None,
                extras: Default::default(),
                indices: Some(idx),
                material: Some(json::Index::new(root.materials.len() as u32 - 1)),
                mode: Valid(json::mesh::Mode::Triangles),
                targets: None,
            });
        }
        root.meshes.push(json::Mesh { extensions: None, extras: Default::default(), name: Some("character".into()), primitives, weights: None });
        let ibm = bin.accessor(
            &f32_bytes(rest_inv.iter().flat_map(|m| m.to_cols_array())),
            n,
            json::accessor::ComponentType::F32,
            Kind::Mat4,
            None,
            None,
        );
        let skeleton_root = scene_nodes.first().copied();
        root.skins.push(json::Skin {
            extensions: None,
            extras: Default::default(),
            inverse_bind_matrices: Some(ibm),
            joints: (0..n as u32).map(json::Index::new).collect(),
            name: Some("skeleton".into()),
            skeleton: skeleton_root.filter(|_| scene_nodes.len() == 1),
        });
        // A skinned mesh node sits at the scene root with no transform of its own (glTF
        // ignores it, and the validator warns about one).
        root.nodes.push(json::Node {
            name: Some("character".into()),
            mesh: Some(json::Index::new(0)),
            skin: Some(json::Index::new(0)),
            ..Default::default()
        });
        scene_nodes.push(json::Index::new(root.nodes.len() as u32 - 1));
    }

    animations(&mut root, &mut bin, clips, |_| true)?;
    finish(root, bin, scene_nodes)
}

/// The mesh's textures some part uses, each as an image in the binary chunk (a buffer view
/// with its MIME type), its sampler and a texture; returns the glTF texture index of each of
/// `textures` (unused ones are not written: the validator reports unused objects).
fn textures(root: &mut json::Root, bin: &mut Bin, textures: &[MeshTexture], parts: &[RestPart]) -> Vec<json::Index<json::Texture>> {
    use json::texture::{MagFilter, MinFilter, WrappingMode};
    let mut index = vec![json::Index::new(0); textures.len()];
    for (i, t) in textures.iter().enumerate() {
        if !parts.iter().any(|p| matches!(&p.texture, Some((k, _, _)) if *k == i)) {
            continue;
        }
        let view = bin.view(&t.image, None);
        root.images.push(json::Image {
            buffer_view: Some(view),
            mime_type: Some(json::image::MimeType(t.mime_type.clone())),
            name: None,
            uri: None,
            extensions: None,
            extras: Default::default(),
        });
        // glTF's codes back to its enums; a code the importer never gives is left out (the
        // client's default).
        let mag = match t.sampler.mag_filter {
            Some(9728) => Some(MagFilter::Nearest),
            Some(9729) => Some(MagFilter::Linear),
            _ => None,
        };
        let min = match t.sampler.min_filter {
            Some(9728) => Some(MinFilter::Nearest),
            Some(9729) => Some(MinFilter::Linear),
            Some(9984) => Some(MinFilter::NearestMipmapNearest),
            Some(9985) => Some(MinFilter::LinearMipmapNearest),
            Some(9986) => Some(MinFilter::NearestMipmapLinear),
            Some(9987) => Some(MinFilter::LinearMipmapLinear),
            _ => None,
        };
        let wrap = |code: u32| match code {
            33071 => WrappingMode::ClampToEdge,
            33648 => WrappingMode::MirroredRepeat,
            _ => WrappingMode::Repeat,
        };
        root.samplers.push(json::texture::Sampler {
            mag_filter: mag.map(Valid),
            min_filter: min.map(Valid),
            name: None,
            wrap_s: Valid(wrap(t.sampler.wrap_s)),
            wrap_t: Valid(wrap(t.sampler.wrap_t)),
            extensions: None,
            extras: Default::default(),
        });
        root.textures.push(json::Texture {
            name: None,
            sampler: Some(json::Index::new(root.samplers.len() as u32 - 1)),
            source: json::Index::new(root.images.len() as u32 - 1),
            extensions: None,
            extras: Default::default(),
        });
        index[i] = json::Index::new(root.textures.len() as u32 - 1);
    }
    index
}

/// A part's base-colour texture for its material, and its UVs' accessor. The kept UV set is
/// written as TEXCOORD_0 (whichever set the source's material named), so the material's and the
/// transform's texCoord are 0.
#[cfg(feature = "export-textures")]
fn part_texture(root: &mut json::Root, bin: &mut Bin, part: &RestPart, texture_index: &[json::Index<json::Texture>]) -> (Option<json::texture::Info>, Option<json::Index<json::Accessor>>) {
    use json::accessor::ComponentType as C;
    let Some((t, uvs, transform)) = &part.texture else { return (None, None) };
    let uv = bin.accessor(&f32_bytes(uvs.iter().flatten().copied()), uvs.len(), C::F32, Kind::Vec2, Some(json::buffer::Target::ArrayBuffer), None);
    let texture_transform = transform.map(|x| json::extensions::texture::TextureTransform {
        offset: json::extensions::texture::TextureTransformOffset(x.offset),
        rotation: json::extensions::texture::TextureTransformRotation(x.rotation_rad),
        scale: json::extensions::texture::TextureTransformScale(x.scale),
        // gltf-json writes a `None` here as `null`, which the validator rejects; 0 names the
        // one set written.
        tex_coord: Some(0),
        extras: Default::default(),
    });
    if texture_transform.is_some() && !root.extensions_used.iter().any(|e| e == "KHR_texture_transform") {
        root.extensions_used.push("KHR_texture_transform".into());
    }
    let info = json::texture::Info {
        index: texture_index[*t],
        tex_coord: 0,
        extensions: texture_transform.map(|tt| json::extensions::texture::Info { texture_transform: Some(tt), others: Default::default() }),
        extras: Default::default(),
    };
    (Some(info), Some(uv))
}

/// Without the feature (the player build) a character is written untextured.
#[cfg(not(feature = "export-textures"))]
fn part_texture(_: &mut json::Root, _: &mut Bin, _: &RestPart, _: &[json::Index<json::Texture>]) -> (Option<json::texture::Info>, Option<json::Index<json::Accessor>>) {
    (None, None)
}

/// A fresh document and an empty binary chunk.
pub(super) fn start() -> (json::Root, Bin) {
    let root = json::Root {
        asset: json::Asset { generator: Some(format!("Odori {}", env!("CARGO_PKG_VERSION"))), ..Default::default() },
        ..Default::default()
    };
    (root, Bin { bytes: Vec::new(), views: Vec::new(), accessors: Vec::new() })
}

/// One node per joint (node i is joint i) with its rest translation and rotation, children
/// linked; returns the roots, for the scene.
pub(super) fn joint_nodes(root: &mut json::Root, skeleton: &Skeleton) -> Vec<json::Index<json::Node>> {
    let n = skeleton.len();
    let mut children: Vec<Vec<json::Index<json::Node>>> = vec![Vec::new(); n];
    for (i, j) in skeleton.joints.iter().enumerate() {
        if let Some(p) = j.parent {
            children[p].push(json::Index::new(i as u32));
        }
    }
    for (i, j) in skeleton.joints.iter().enumerate() {
        let r = j.rest_rotation.normalize();
        root.nodes.push(json::Node {
            name: Some(j.name.clone()),
            translation: (j.rest_offset != Vec3::ZERO).then(|| j.rest_offset.to_array()),
            rotation: (r != Quat::IDENTITY).then(|| json::scene::UnitQuaternion(r.to_array())),
            children: (!children[i].is_empty()).then(|| std::mem::take(&mut children[i])),
            ..Default::default()
        });
    }
    skeleton.joints.iter().enumerate().filter(|(_, j)| j.parent.is_none()).map(|(i, _)| json::Index::new(i as u32)).collect()
}

/// One animation per clip (LINEAR samplers, one shared time accessor per clip): a rotation
/// channel for every joint, a translation channel for each animated translation whose joint
/// `translate` accepts.
pub(super) fn animations(root: &mut json::Root, bin: &mut Bin, clips: &[&Clip], translate: impl Fn(usize) -> bool) -> Result<(), ExportError> {
    for clip in clips {
        let n = clip.skeleton.len();
        let frames = clip.frame_count();
        let times: Vec<f32> = (0..frames).map(|f| f as f32 / clip.fps).collect();
        if times.windows(2).any(|w| w[1] <= w[0]) {
            return Err(ExportError::BadClip { clip: clip.name.clone(), message: format!("{frames} frames at {} fps do not give increasing key times", clip.fps) });
        }
        let time_acc = bin.accessor(
            &f32_bytes(times.iter().copied()),
            frames,
            json::accessor::ComponentType::F32,
            Kind::Scalar,
            None,
            Some((vec![times[0]], vec![times[frames - 1]])),
        );
        let mut samplers = Vec::new();
        let mut channels = Vec::new();
        let mut push = |bin: &mut Bin, node: usize, data: Vec<u8>, kind: Kind, path: json::animation::Property| {
            let out = bin.accessor(&data, frames, json::accessor::ComponentType::F32, kind, None, None);
            samplers.push(json::animation::Sampler {
                extensions: None,
                extras: Default::default(),
                input: time_acc,
                interpolation: Valid(json::animation::Interpolation::Linear),
                output: out,
            });
            channels.push(json::animation::Channel {
                sampler: json::Index::new(samplers.len() as u32 - 1),
                target: json::animation::Target { extensions: None, extras: Default::default(), node: json::Index::new(node as u32), path: Valid(path) },
                extensions: None,
                extras: Default::default(),
            });
        };
        for j in 0..n {
            let mut prev = Quat::IDENTITY;
            let mut data = Vec::with_capacity(frames * 16);
            for f in 0..frames {
                let q = motion::sign_continuous(prev, clip.rotations[f * n + j].normalize());
                prev = q;
                data.extend(f32_bytes(q.to_array()));
            }
            push(bin, j, data, Kind::Vec4, json::animation::Property::Rotation);
        }
        for t in clip.translations.iter().filter(|t| translate(t.joint)) {
            push(bin, t.joint, f32_bytes(t.values.iter().flat_map(|v| v.to_array())), Kind::Vec3, json::animation::Property::Translation);
        }
        root.animations.push(json::Animation { extensions: None, extras: Default::default(), channels, name: Some(clip.name.clone()), samplers });
    }
    Ok(())
}

/// The scene over `scene_nodes`, the buffer, and the GLB container around both chunks.
pub(super) fn finish(mut root: json::Root, mut bin: Bin, scene_nodes: Vec<json::Index<json::Node>>) -> Result<Vec<u8>, ExportError> {
    while !bin.bytes.len().is_multiple_of(4) {
        bin.bytes.push(0);
    }
    root.buffers.push(json::Buffer { byte_length: USize64::from(bin.bytes.len()), name: None, uri: None, extensions: None, extras: Default::default() });
    root.buffer_views = bin.views;
    root.accessors = bin.accessors;
    root.scenes.push(json::Scene { extensions: None, extras: Default::default(), name: Some("Odori".into()), nodes: scene_nodes });
    root.scene = Some(json::Index::new(0));

    let text = root.to_vec().map_err(|e| ExportError::Encode { message: e.to_string() })?;
    let glb = gltf::binary::Glb {
        header: gltf::binary::Header { magic: *b"glTF", version: 2, length: 0 },
        json: Cow::Owned(text),
        bin: Some(Cow::Owned(bin.bytes)),
    };
    glb.to_vec().map_err(|e| ExportError::Encode { message: e.to_string() })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::canon::builtin::demo_clip;
    use crate::import::{import_bytes, ImportOptions};

    #[test]
    fn glb_chunks_are_aligned_and_reimport() {
        let clip = demo_clip();
        let bytes = glb(&clip.skeleton, &[&clip], &GlbOptions::default()).unwrap();
        assert_eq!(&bytes[0..4], b"glTF");
        assert_eq!(bytes.len() % 4, 0);
        let json_len = u32::from_le_bytes(bytes[12..16].try_into().unwrap()) as usize;
        assert_eq!(json_len % 4, 0);
        let back = import_bytes("demo.glb", &bytes, &ImportOptions { gltf_fps: clip.fps, ..Default::default() }).unwrap();
        assert_eq!(back.clips.len(), 1);
        assert_eq!(back.clips[0].frame_count(), clip.frame_count());
    }

    #[test]
    fn refuses_nothing_and_foreign_clips() {
        let clip = demo_clip();
        assert_eq!(glb(&clip.skeleton, &[], &GlbOptions::default()), Err(ExportError::NoClips));
        let mut other = clip.clone();
        let mut sk = (*clip.skeleton).clone();
        sk.joints.pop();
        other.skeleton = std::sync::Arc::new(sk);
        other.rotations.truncate(clip.frame_count() * other.skeleton.len());
        let got = glb(&clip.skeleton, &[&other], &GlbOptions::default());
        assert!(matches!(got, Err(ExportError::SkeletonMismatch { .. })), "{got:?}");
    }
}
