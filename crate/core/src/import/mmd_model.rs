//! The MikuMikuDance model as plain data, common to PMD and PMX ([`MmdModel`]), and
//! [`read_model`], which picks the reader by the file's magic.
//!
//! Everything is in MMD units and MMD's frame as in the file (1 unit ≈ 8 cm; left-handed,
//! Y up, the model facing −Z), angles in radians: the rig that poses it (`crate::mmd`) and the
//! renderer convert where they need to. The few places where PMD is brought to PMX's meaning
//! are documented on the field (PMD rigid bodies are stored relative to their bone; PMD morphs
//! index a base morph; PMD has no IK link limits but MMD bends its knees one way).

use glam::{Quat, Vec2, Vec3, Vec4};
use serde::{Deserialize, Serialize};

use super::mmd_bytes::{printable_start, MmdError};
use super::{pmd, pmx};

/// Which file a model came from.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub enum ModelFormat {
    /// PMD 1.0.
    Pmd,
    /// PMX with its header version (2.0 or 2.1).
    Pmx { version: f32 },
}

/// How a vertex is skinned, as the file says.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum SkinKind {
    Bdef1,
    Bdef2,
    Bdef4,
    /// Spherical deform: two bones and the centre `c` and the two reference points of [`Sdef`].
    Sdef,
    /// Dual-quaternion deform (PMX 2.1), four bones.
    Qdef,
}

/// The extra points of an SDEF vertex (model space, MMD units).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Sdef {
    pub c: Vec3,
    pub r0: Vec3,
    pub r1: Vec3,
}

/// A vertex's skin: up to four bones and their weights, unused slots bone 0 weight 0. BDEF1 is
/// one bone at weight 1; BDEF2/SDEF two at w and 1 − w. A PMX slot naming bone −1 (none) reads
/// as bone 0 at weight 0. Weights are as stored (BDEF4 weights need not sum to 1).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Skin {
    pub kind: SkinKind,
    pub bones: [u32; 4],
    pub weights: [f32; 4],
    pub sdef: Option<Sdef>,
}

/// One vertex, model space, MMD units.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct MmdVertex {
    pub position: Vec3,
    pub normal: Vec3,
    pub uv: Vec2,
    pub skin: Skin,
    /// Scale of the edge (outline) at this vertex; PMD: 1 where the edge is on, 0 where its
    /// vertex edge flag turns it off.
    pub edge_scale: f32,
}

/// The toon ramp of a material.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum Toon {
    None,
    /// One of MMD's ten shared ramps: `toon01.bmp` for 0 … `toon10.bmp` for 9.
    Shared(u8),
    /// The model's own ramp, an index into [`MmdModel::textures`].
    Texture(usize),
}

/// How a sphere map combines.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum SphereMode {
    None,
    Multiply,
    Add,
    /// PMX: the sphere map is indexed by the additional UV 1.
    SubTexture,
}

/// Material flag bits (PMX's byte; PMD's are set as MMD treats PMD, see [`MmdMaterial::flags`]).
pub mod material_flags {
    pub const DOUBLE_SIDED: u8 = 0x01;
    pub const GROUND_SHADOW: u8 = 0x02;
    pub const CASTS_SELF_SHADOW: u8 = 0x04;
    pub const RECEIVES_SELF_SHADOW: u8 = 0x08;
    pub const EDGE: u8 = 0x10;
    pub const VERTEX_COLOUR: u8 = 0x20;
    pub const POINT: u8 = 0x40;
    pub const LINE: u8 = 0x80;
}

/// One material: a run of `index_count` consecutive triangle indices, after the previous
/// materials' runs.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct MmdMaterial {
    pub name: String,
    pub name_en: String,
    /// RGBA, 0–1.
    pub diffuse: Vec4,
    pub specular: Vec3,
    pub specular_power: f32,
    pub ambient: Vec3,
    /// [`material_flags`] bits. PMD: EDGE from its edge flag, DOUBLE_SIDED when alpha < 1,
    /// and both self-shadow bits and the ground shadow on (MMD's PMD behaviour).
    pub flags: u8,
    /// RGBA; PMD: black.
    pub edge_colour: Vec4,
    /// PMD: 1.
    pub edge_size: f32,
    /// Index into [`MmdModel::textures`].
    pub texture: Option<usize>,
    pub sphere: Option<usize>,
    pub sphere_mode: SphereMode,
    pub toon: Toon,
    pub memo: String,
    /// Number of triangle indices (three per triangle).
    pub index_count: u32,
}

/// Where a bone's tail (its display end) points.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub enum BoneTail {
    /// An offset from the bone's position.
    Offset(Vec3),
    /// Another bone (None: no tail).
    Bone(Option<usize>),
}

/// Grant (付与): the bone takes a share of another bone's rotation and/or translation.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Grant {
    pub parent: usize,
    pub ratio: f32,
    pub rotation: bool,
    pub translation: bool,
    /// PMX "local" grant (flag 0x0080).
    pub local: bool,
}

/// One link of an IK chain, optionally limited (Euler angles, radians, min ≤ max per axis).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct IkLink {
    pub bone: usize,
    pub limits: Option<(Vec3, Vec3)>,
}

/// An IK chain, carried by its IK bone: move `target` (the effector) onto the IK bone by
/// rotating `links` (first link nearest the target), CCD for `loop_count` iterations, each
/// step at most `limit_angle_rad`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Ik {
    pub target: usize,
    pub loop_count: u32,
    pub limit_angle_rad: f32,
    pub links: Vec<IkLink>,
}

/// Bone flag bits (PMX's u16; PMD's are made from its bone type, see [`MmdBone::pmd_type`]).
pub mod bone_flags {
    pub const TAIL_IS_BONE: u16 = 0x0001;
    pub const ROTATABLE: u16 = 0x0002;
    pub const TRANSLATABLE: u16 = 0x0004;
    pub const VISIBLE: u16 = 0x0008;
    pub const ENABLED: u16 = 0x0010;
    pub const IK: u16 = 0x0020;
    pub const LOCAL_GRANT: u16 = 0x0080;
    pub const GRANT_ROTATION: u16 = 0x0100;
    pub const GRANT_TRANSLATION: u16 = 0x0200;
    pub const FIXED_AXIS: u16 = 0x0400;
    pub const LOCAL_AXES: u16 = 0x0800;
    pub const AFTER_PHYSICS: u16 = 0x1000;
    pub const EXTERNAL_PARENT: u16 = 0x2000;
}

/// One bone. `position` is its rest position in model space (not relative to the parent).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct MmdBone {
    pub name: String,
    pub name_en: String,
    pub position: Vec3,
    pub parent: Option<usize>,
    /// PMX deform layer (bones are transformed layer by layer); PMD: 0.
    pub layer: i32,
    /// [`bone_flags`] bits.
    pub flags: u16,
    pub tail: BoneTail,
    pub grant: Option<Grant>,
    /// The only axis the bone turns about (twist bones 腕捩, 手捩), unit length as stored.
    pub fixed_axis: Option<Vec3>,
    /// Local X and Z axes.
    pub local_axes: Option<(Vec3, Vec3)>,
    pub external_parent_key: Option<i32>,
    pub ik: Option<Ik>,
    /// PMD's bone type byte (0 rotate, 1 rotate+move, 2 IK, 4 under IK, 5 rotation-influenced,
    /// 6 IK target, 7 hidden, 8 twist, 9 rotation-linked); None for PMX.
    pub pmd_type: Option<u8>,
}

impl MmdBone {
    pub fn has(&self, flag: u16) -> bool {
        self.flags & flag != 0
    }
}

/// One material morph offset (PMX); `material` None means every material.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct MaterialMorphOffset {
    pub material: Option<usize>,
    /// 0 multiply, 1 add.
    pub operation: u8,
    pub diffuse: Vec4,
    pub specular: Vec3,
    pub specular_power: f32,
    pub ambient: Vec3,
    pub edge_colour: Vec4,
    pub edge_size: f32,
    pub texture_tint: Vec4,
    pub sphere_tint: Vec4,
    pub toon_tint: Vec4,
}

/// One impulse morph offset (PMX 2.1).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct ImpulseMorphOffset {
    pub rigid_body: usize,
    pub local: bool,
    pub velocity: Vec3,
    pub torque: Vec3,
}

/// What a morph moves.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum MorphData {
    /// Other morphs at a weight each.
    Group(Vec<(usize, f32)>),
    /// Vertex position offsets (MMD units).
    Vertex(Vec<(usize, Vec3)>),
    /// Bone translation and rotation offsets.
    Bone(Vec<(usize, Vec3, Quat)>),
    /// UV offsets: channel 0 is the main UV, 1–4 the additional UVs.
    Uv { channel: u8, offsets: Vec<(usize, Vec4)> },
    Material(Vec<MaterialMorphOffset>),
    /// PMX 2.1: one of the listed morphs, chosen by the weight.
    Flip(Vec<(usize, f32)>),
    /// PMX 2.1: a push on rigid bodies.
    Impulse(Vec<ImpulseMorphOffset>),
}

/// One morph. PMD's morphs are turned into vertex morphs on the model's vertices (PMD stores
/// offsets against a "base" morph's vertex list; the base itself is not a morph and is left out).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct MmdMorph {
    pub name: String,
    pub name_en: String,
    /// Control panel: 0 system, 1 eyebrow, 2 eye, 3 mouth, 4 other.
    pub panel: u8,
    pub data: MorphData,
}

/// One display frame's element.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum DisplayItem {
    Bone(usize),
    Morph(usize),
}

/// One display frame (the groups MMD's UI lists bones and morphs in).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct DisplayFrame {
    pub name: String,
    pub name_en: String,
    pub special: bool,
    pub items: Vec<DisplayItem>,
}

/// Shape of a rigid body.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum RigidShape {
    Sphere,
    Box,
    Capsule,
}

/// How a rigid body moves: 0 follows its bone, 1 physics, 2 physics with the bone's position.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum RigidMode {
    FollowBone,
    Physics,
    PhysicsWithBone,
}

/// One rigid body (the hair, skirt and breast chains follow them). Position in model space
/// (PMD stores it relative to its bone: the reader adds the bone's position, as three.js does).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct MmdRigidBody {
    pub name: String,
    pub name_en: String,
    pub bone: Option<usize>,
    pub group: u8,
    /// Bit i set: does NOT collide with group i.
    pub no_collision_mask: u16,
    pub shape: RigidShape,
    /// Sphere: radius in x; box: half extents; capsule: radius x, height y.
    pub size: Vec3,
    pub position: Vec3,
    /// Euler angles, radians.
    pub rotation_rad: Vec3,
    pub mass: f32,
    pub linear_damping: f32,
    pub angular_damping: f32,
    pub restitution: f32,
    pub friction: f32,
    pub mode: RigidMode,
}

/// One joint (a 6-DOF spring) between two rigid bodies.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct MmdJoint {
    pub name: String,
    pub name_en: String,
    /// PMX joint type (0 = 6-DOF spring, 2.1 adds others); PMD: 0.
    pub kind: u8,
    pub rigid_a: usize,
    pub rigid_b: usize,
    pub position: Vec3,
    pub rotation_rad: Vec3,
    pub translation_min: Vec3,
    pub translation_max: Vec3,
    pub rotation_min_rad: Vec3,
    pub rotation_max_rad: Vec3,
    pub spring_translation: Vec3,
    pub spring_rotation: Vec3,
}

/// A PMX 2.1 soft body, read and kept in outline (the engine does not simulate soft bodies).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct MmdSoftBody {
    pub name: String,
    pub name_en: String,
    /// 0 tri-mesh, 1 rope.
    pub shape: u8,
    pub material: Option<usize>,
    pub anchors: usize,
    pub pinned_vertices: usize,
}

/// A PMD or PMX model.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct MmdModel {
    pub format: ModelFormat,
    pub name: String,
    pub name_en: String,
    pub comment: String,
    pub comment_en: String,
    pub vertices: Vec<MmdVertex>,
    /// PMX additional UVs per vertex (0–4).
    pub additional_uv_count: usize,
    /// `additional_uv_count` values per vertex, vertex-major.
    pub additional_uvs: Vec<Vec4>,
    /// Triangle list, three indices per triangle, materials' runs in order.
    pub indices: Vec<u32>,
    /// Texture paths as the file names them (relative to the model's folder, `\` or `/`; see
    /// [`find_texture`]). PMD: the distinct file names its materials and toon list name.
    pub textures: Vec<String>,
    pub materials: Vec<MmdMaterial>,
    pub bones: Vec<MmdBone>,
    pub morphs: Vec<MmdMorph>,
    pub display_frames: Vec<DisplayFrame>,
    pub rigid_bodies: Vec<MmdRigidBody>,
    pub joints: Vec<MmdJoint>,
    pub soft_bodies: Vec<MmdSoftBody>,
}

impl MmdModel {
    /// The index of the bone named `name`.
    pub fn bone_index(&self, name: &str) -> Option<usize> {
        self.bones.iter().position(|b| b.name == name)
    }

    /// The bones that carry an IK chain.
    pub fn ik_bones(&self) -> impl Iterator<Item = (usize, &Ik)> {
        self.bones.iter().enumerate().filter_map(|(i, b)| b.ik.as_ref().map(|ik| (i, ik)))
    }
}

/// Reads a PMD or PMX model, chosen by its first bytes ("Pmd" or "PMX ").
pub fn read_model(file: &str, bytes: &[u8]) -> Result<MmdModel, MmdError> {
    if bytes.starts_with(pmx::MAGIC) {
        pmx::read(file, bytes)
    } else if bytes.starts_with(pmd::MAGIC) {
        pmd::read(file, bytes)
    } else {
        Err(MmdError::BadMagic { file: file.to_string(), expected: "PMD or PMX model", found: printable_start(bytes, 8) })
    }
}

/// A texture path as MMD resolves it: `\` and `/` alike, no leading `./`, case ignored.
pub fn normalize_texture_path(path: &str) -> String {
    let p = path.trim().replace('\\', "/");
    let p = p.trim_start_matches("./");
    p.to_lowercase()
}

/// The index in `available` (file paths relative to the model's folder, as a dropped folder
/// or a zip lists them) of the file `texture` names, compared as [`normalize_texture_path`]
/// does. MMD on Windows finds files case-insensitively, and models name them in any case.
pub fn find_texture(texture: &str, available: &[&str]) -> Option<usize> {
    let want = normalize_texture_path(texture);
    available.iter().position(|a| normalize_texture_path(a) == want)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn texture_paths_resolve_with_any_case_and_separator() {
        let files = ["tex/Body.PNG", "face.bmp", "toon01.bmp"];
        assert_eq!(find_texture("TEX\\body.png", &files), Some(0));
        assert_eq!(find_texture(".\\Face.bmp", &files), Some(1));
        assert_eq!(find_texture("hair.png", &files), None);
    }

    #[test]
    fn unknown_magic_is_refused() {
        match read_model("x.pmx", b"PK\x03\x04") {
            Err(MmdError::BadMagic { file, .. }) => assert_eq!(file, "x.pmx"),
            other => panic!("{other:?}"),
        }
    }
}
