//! A PMD/PMX model as an engine character: its mesh skinned to the skeleton of its own
//! deforming bones ([`MmdRig::deform_skeleton`], metres, right-handed, identity rest rotations),
//! so a VMD posed on the model by its MMD rig (IK, grants) plays on it unchanged, and any other
//! humanoid clip through the character retargeting every imported character has.
//!
//! - Skinning: BDEF1/2/4 as stored (BDEF4 weights normalised); SDEF drawn as BDEF2 on its two
//!   bones, as three.js r171's MMDLoader does (its C/R0/R1 points are kept in the model but not
//!   used); QDEF (PMX 2.1) as linear BDEF4. A weight on an IK bone or its target (bones that
//!   are not in the deforming skeleton) goes to its nearest deforming ancestor.
//! - One part per material (vertices compacted per part), diffuse RGBA as the part's colour,
//!   triangle order reversed with the z flip (as three's MMDParser does) so fronts stay fronts;
//!   the rest of the material (ambient, specular, double-sided, toon, edge) in [`MmdLook`].
//! - Textures: PNG/JPEG as given, TGA/BMP decoded ([`super::texture`]); a texture that is
//!   missing or undecodable leaves its material drawn in its colour, with a notice naming it.
//! - Sphere maps (`.sph` multiplied, `.spa` added; PMX modes 1 and 2) go to the part's
//!   [`ToonLook`] for the toon shader, which looks them up by the view-space normal as MMD
//!   does; a missing one is a notice and the material is drawn without it. PMX's sub-texture
//!   mode (3) is drawn as MMD's shader (MME's `use_subtexture`) draws it: the sphere texture
//!   sampled at the vertex's additional UV 1 (x, y; [`MeshPart::sphere_uvs`]) and multiplied,
//!   as an ordinary second texture (three.js r171 leaves it out); a model with no additional
//!   UV draws it without, with a notice.
//! - Outline width per vertex: the material's edge size times the vertex's edge scale (PMX),
//!   or 0 where a PMD vertex's edge flag turns the edge off ([`MeshPart::edge_scales`]).

use std::collections::HashMap;
use std::sync::Arc;

use glam::{Mat4, Vec3, Vec4};
use thiserror::Error;

use super::texture::mesh_texture;
use super::{to_right_handed, MmdRig, MmdRigError, METRES_PER_MMD_UNIT};
use crate::canon::character::{Character, CharacterError};
use crate::canon::humanoid::HumanoidMap;
use crate::import::mmd_model::{material_flags, normalize_texture_path, MmdModel, SkinKind, SphereMode, Toon};
use crate::import::{MeshPart, SkinnedMesh, ToonLook};
use crate::skeleton::Skeleton;

/// Why a model cannot be made a character.
#[derive(Debug, Error, PartialEq)]
pub enum ModelMeshError {
    #[error("{file}: the model has no vertices or no triangles")]
    Empty { file: String },
    #[error("{file}: {source}")]
    Rig { file: String, source: MmdRigError },
    #[error("{file}: material {material} ('{name}') runs to index {end}, past the {indices} triangle indices the model has")]
    MaterialRunsPast { file: String, material: usize, name: String, end: usize, indices: usize },
    #[error("{file}: triangle index {index} names vertex {vertex}, but the model has {vertices}")]
    VertexOutOfRange { file: String, index: usize, vertex: u32, vertices: usize },
    #[error("{file}: the mesh is weighted to {joints} bones; the renderer skins at most {max}")]
    TooManyBones { file: String, joints: usize, max: usize },
    #[error("{file}: {source}")]
    Character { file: String, source: CharacterError },
}

/// Outline width per unit of MMD edge size, metres per metre from the camera: about one pixel
/// of a 800-pixel-high view at 45° field of view, as MMD's edge of size 1 looks.
pub const EDGE_WIDTH_PER_SIZE: f32 = 0.0012;

/// The renderer's palette size (odori-render's `MAX_PALETTE`).
pub const MAX_SKIN_BONES: usize = 256;

/// What of an MMD material the engine's plain mesh part does not carry, for MMD-style drawing
/// (toon ramp, outline). Colours linear-as-stored RGBA/RGB 0–1, as the file gives them.
#[derive(Clone, Debug, PartialEq)]
pub struct MmdLook {
    pub name: String,
    pub diffuse: Vec4,
    pub ambient: Vec3,
    pub specular: Vec3,
    pub specular_power: f32,
    pub double_sided: bool,
    /// The base texture, an index into the mesh's textures (None: untextured or not found).
    pub texture: Option<usize>,
    /// The toon ramp: the model's own or one of MMD's shared `toonNN.bmp`, an index into the
    /// mesh's textures when the file was in the set.
    pub toon: Toon,
    pub toon_texture: Option<usize>,
    /// The sphere map as drawn, an index into the mesh's textures (None: none, not found, or
    /// a mode not drawn), and the mode the material gives.
    pub sphere: Option<usize>,
    pub sphere_mode: SphereMode,
    pub edge: bool,
    pub edge_colour: Vec4,
    pub edge_size: f32,
}

/// A model ready to draw and to play motion: the engine character (skeleton, mesh, humanoid
/// mapping), per part its MMD look, and the rig that poses its bones.
#[derive(Clone, Debug)]
pub struct ModelCharacter {
    pub character: Character,
    pub rig: MmdRig,
    /// Per skeleton joint, the rig bone it is.
    pub rig_index: Vec<usize>,
    /// One per mesh part.
    pub looks: Vec<MmdLook>,
    /// Per mesh part, the model's material it draws.
    pub part_material: Vec<usize>,
    /// Per mesh part, the model vertex each of its vertices draws (a vertex used by several
    /// materials is drawn once in each): face morphs find their vertices by it
    /// ([`super::morph::DrawnMorphs`]).
    pub drawn_vertices: Vec<Vec<u32>>,
    /// Textures missing or undecodable, one line each naming the file.
    pub notices: Vec<String>,
}

/// `textures`: (path the model names, path in the set, bytes) of each texture file found, as
/// [`super::files::ImportedModel::textures`] holds them; `missing`: the paths not found;
/// `others`: the other files of the set (path, bytes), where MMD's shared toon ramps
/// (`toon01.bmp` … `toon10.bmp`, which MMD ships and models name by number) are looked for by
/// file name. A shared ramp not given is white (no toon shading), as MMD without its files.
pub fn model_character(file: &str, model: &MmdModel, textures: &[(String, String, Vec<u8>)], missing: &[String], others: &[(String, Vec<u8>)]) -> Result<ModelCharacter, ModelMeshError> {
    if model.vertices.is_empty() || model.indices.len() < 3 {
        return Err(ModelMeshError::Empty { file: file.into() });
    }
    let rig = MmdRig::from_model(model).map_err(|source| ModelMeshError::Rig { file: file.into(), source })?;
    let (skeleton, rig_index) = rig.deform_skeleton(METRES_PER_MMD_UNIT);
    // A path only materials' sphere maps name is a sphere map (the rest are drawn without it).
    let sphere_only = |path: &str| {
        let want = normalize_texture_path(path);
        let named = |i: Option<usize>| i.and_then(|i| model.textures.get(i)).is_some_and(|p| normalize_texture_path(p) == want);
        model.materials.iter().any(|m| named(m.sphere)) && !model.materials.iter().any(|m| named(m.texture) || matches!(m.toon, Toon::Texture(t) if named(Some(t))))
    };
    let mut notices: Vec<String> = missing
        .iter()
        .map(|m| {
            if sphere_only(m) {
                format!("{file}: sphere map '{m}' is not in the files given: its materials are drawn without it")
            } else {
                format!("{file}: texture '{m}' is not in the files given: its materials are drawn in their colour")
            }
        })
        .collect();

    // Rig bone → skeleton joint (IK helpers → their nearest deforming ancestor, else joint 0).
    let n = rig.len();
    let mut joint_of_bone = vec![None; n];
    for (j, &i) in rig_index.iter().enumerate() {
        joint_of_bone[i] = Some(j);
    }
    let joint_for = |b: u32| -> usize {
        let mut k = Some(b as usize).filter(|&b| b < n);
        let mut steps = 0;
        while let Some(i) = k {
            if let Some(j) = joint_of_bone[i] {
                return j;
            }
            steps += 1;
            if steps > n {
                break;
            }
            k = rig.bones[i].parent;
        }
        0
    };

    // Textures: the model's texture index → the mesh's.
    let mut mesh_textures = Vec::new();
    let mut tex_of_path: HashMap<String, usize> = HashMap::new();
    for (named, path, bytes) in textures {
        match mesh_texture(path, bytes) {
            Ok(t) => {
                tex_of_path.insert(normalize_texture_path(named), mesh_textures.len());
                mesh_textures.push(t);
            }
            Err(e) => notices.push(format!("{file}: {e}: its materials are drawn in their colour")),
        }
    }
    // MMD's shared ramps the materials use, from the set's other files by name.
    for m in &model.materials {
        let Toon::Shared(k) = m.toon else { continue };
        let name = format!("toon{:02}.bmp", k as u32 + 1);
        if tex_of_path.contains_key(&name) {
            continue;
        }
        let base = |p: &str| normalize_texture_path(p).rsplit('/').next().unwrap_or_default().to_string();
        if let Some((path, bytes)) = others.iter().find(|(p, _)| base(p) == name) {
            match mesh_texture(path, bytes) {
                Ok(t) => {
                    tex_of_path.insert(name, mesh_textures.len());
                    mesh_textures.push(t);
                }
                Err(e) => notices.push(format!("{file}: {e}: its toon shading is left out")),
            }
        }
    }
    let model_tex = |i: Option<usize>| i.and_then(|i| model.textures.get(i)).and_then(|p| tex_of_path.get(&normalize_texture_path(p)).copied());
    let shared_toon = |k: u8| tex_of_path.get(&format!("toon{:02}.bmp", k as u32 + 1)).copied();

    // Skin per vertex, in skeleton joints.
    let skins: Vec<([usize; 4], [f32; 4])> = model
        .vertices
        .iter()
        .map(|v| {
            let s = &v.skin;
            let (count, mut w) = match s.kind {
                SkinKind::Bdef1 => (1, [1.0, 0.0, 0.0, 0.0]),
                SkinKind::Bdef2 | SkinKind::Sdef => (2, [s.weights[0], 1.0 - s.weights[0], 0.0, 0.0]),
                SkinKind::Bdef4 | SkinKind::Qdef => (4, s.weights),
            };
            let mut j = [0usize; 4];
            for k in 0..4 {
                if k < count {
                    j[k] = joint_for(s.bones[k]);
                    w[k] = if w[k].is_finite() { w[k].clamp(0.0, 1.0) } else { 0.0 };
                } else {
                    w[k] = 0.0;
                }
            }
            let sum: f32 = w.iter().sum();
            if sum > 1e-6 {
                for x in &mut w {
                    *x /= sum;
                }
            } else {
                w = [1.0, 0.0, 0.0, 0.0];
            }
            (j, w)
        })
        .collect();

    // Palette: the joints vertices use, each bound at its rest position.
    let rest = skeleton.rest_positions();
    let mut slot_of_joint: Vec<Option<u16>> = vec![None; skeleton.len()];
    let mut palette = Vec::new();
    for (j, w) in &skins {
        for k in 0..4 {
            if w[k] > 0.0 && slot_of_joint[j[k]].is_none() {
                slot_of_joint[j[k]] = Some(palette.len().min(u16::MAX as usize) as u16);
                palette.push((j[k], Mat4::from_translation(-rest[j[k]])));
            }
        }
    }
    if palette.len() > MAX_SKIN_BONES {
        return Err(ModelMeshError::TooManyBones { file: file.into(), joints: palette.len(), max: MAX_SKIN_BONES });
    }

    let mut parts = Vec::new();
    let mut looks = Vec::new();
    let mut part_material = Vec::new();
    let mut drawn_vertices = Vec::new();
    let mut local = vec![u32::MAX; model.vertices.len()];
    let mut start = 0usize;
    for (mi, m) in model.materials.iter().enumerate() {
        let end = start + m.index_count as usize;
        if end > model.indices.len() {
            return Err(ModelMeshError::MaterialRunsPast { file: file.into(), material: mi, name: m.name.clone(), end, indices: model.indices.len() });
        }
        let run = &model.indices[start..end];
        start = end;
        if run.len() < 3 {
            continue;
        }
        let texture = model_tex(m.texture);
        let toon_texture = match m.toon {
            Toon::None => None,
            Toon::Shared(k) => shared_toon(k),
            Toon::Texture(i) => model_tex(Some(i)),
        };
        let mut sphere = match m.sphere_mode {
            SphereMode::Multiply | SphereMode::Add | SphereMode::SubTexture => model_tex(m.sphere),
            SphereMode::None => None,
        };
        // Sub-texture mode samples the sphere map at the vertex's additional UV 1, which a
        // model without additional UVs does not have: drawn without it, with a notice.
        let sub_texture = m.sphere_mode == SphereMode::SubTexture && sphere.is_some();
        if sub_texture && model.additional_uv_count == 0 {
            notices.push(format!("{file}: material {mi} ('{}') uses its sphere map as a sub-texture (PMX sphere mode 3), but the model has no additional UV: drawn without it", m.name));
            sphere = None;
        }
        let sub_texture = sub_texture && sphere.is_some();
        // The sphere map is looked up by the normal, not the UVs (but in sub-texture mode): a
        // part with only a sphere map still needs none.
        let mut part = MeshPart { color: m.diffuse.to_array(), texture, ..Default::default() };
        let mut used = Vec::new();
        for (k, tri) in run.chunks_exact(3).enumerate() {
            // Reversed with the z flip: (a, c, b).
            for &vi in &[tri[0], tri[2], tri[1]] {
                let v = vi as usize;
                if v >= model.vertices.len() {
                    return Err(ModelMeshError::VertexOutOfRange { file: file.into(), index: start - run.len() + 3 * k, vertex: vi, vertices: model.vertices.len() });
                }
                if local[v] == u32::MAX {
                    local[v] = used.len() as u32;
                    used.push(v);
                }
                part.indices.push(local[v]);
            }
        }
        for &v in &used {
            let mv = &model.vertices[v];
            part.positions.push((to_right_handed(mv.position) * METRES_PER_MMD_UNIT).to_array());
            part.normals.push(to_right_handed(mv.normal).normalize_or(Vec3::Y).to_array());
            let (j, w) = &skins[v];
            part.joints.push(std::array::from_fn(|k| if w[k] > 0.0 { slot_of_joint[j[k]].unwrap_or(0) } else { 0 }));
            part.weights.push(*w);
            part.edge_scales.push(if mv.edge_scale.is_finite() { mv.edge_scale.max(0.0) } else { 1.0 });
            if texture.is_some() {
                part.uvs.push(mv.uv.to_array());
            }
            if sub_texture {
                let uv1 = model.additional_uvs.get(v * model.additional_uv_count).copied().unwrap_or_default();
                part.sphere_uvs.push([uv1.x, uv1.y]);
            }
            local[v] = u32::MAX;
        }
        let edge = m.flags & material_flags::EDGE != 0 && m.edge_size > 0.0 && m.edge_size.is_finite();
        part.toon = Some(ToonLook {
            ramp: toon_texture,
            edge_colour: m.edge_colour.to_array(),
            edge_width: if edge { m.edge_size * EDGE_WIDTH_PER_SIZE } else { 0.0 },
            sphere,
            sphere_add: m.sphere_mode == SphereMode::Add,
        });
        looks.push(MmdLook {
            name: m.name.clone(),
            diffuse: m.diffuse,
            ambient: m.ambient,
            specular: m.specular,
            specular_power: m.specular_power,
            double_sided: m.flags & material_flags::DOUBLE_SIDED != 0,
            texture,
            toon: m.toon,
            toon_texture,
            sphere,
            sphere_mode: m.sphere_mode,
            edge: m.flags & material_flags::EDGE != 0,
            edge_colour: m.edge_colour,
            edge_size: m.edge_size,
        });
        parts.push(part);
        part_material.push(mi);
        drawn_vertices.push(used.iter().map(|&v| v as u32).collect());
    }
    if parts.is_empty() {
        return Err(ModelMeshError::Empty { file: file.into() });
    }
    // Ramps are looked up down one column: clamped, never wrapped (the renderer clamps them too).
    let mut mesh_textures = mesh_textures;
    for l in &looks {
        if let Some(t) = l.toon_texture.and_then(|t| mesh_textures.get_mut(t)) {
            if !looks.iter().any(|o| o.texture == l.toon_texture) {
                t.sampler.wrap_s = 33071;
                t.sampler.wrap_t = 33071;
            }
        }
    }
    let mesh = SkinnedMesh { parts, palette, textures: mesh_textures };
    let character = character_of(file, skeleton, mesh)?;
    Ok(ModelCharacter { character, rig, rig_index, looks, part_material, drawn_vertices, notices })
}

fn character_of(file: &str, skeleton: Skeleton, mesh: SkinnedMesh) -> Result<Character, ModelMeshError> {
    let map = HumanoidMap::from_skeleton(&skeleton);
    let status = map.status(&skeleton, None);
    Character::from_parts(file, Arc::new(skeleton), Some(&mesh), &map, &status).map_err(|source| ModelMeshError::Character { file: file.into(), source })
}
