//! What an MMD model's bone and material morphs do at given weights (issue 28 item 2): PMX
//! bone morphs (type 2) as a local translation and rotation per bone, PMX material morphs
//! (type 8) as multiply and add factors per material, group morphs expanded into their members
//! one level deep (as [`super::morph`] expands them for vertex morphs, and as MMD does).
//!
//! The rules are PMX 2.0's, as MMD and babylon-mmd apply them: a bone morph at weight w moves
//! its bone by w × its translation and turns it by its rotation slerped from identity by w, on
//! top of the motion's key; a multiply material morph scales each value by lerp(1, value, w),
//! an add morph adds w × value, and several morphs combine as value × Π(mul) + Σ(add). Kept
//! apart from the drawing so it is checked natively against the model's data × weight; the
//! viewer hands the factors of each drawn part to the renderer (a small uniform per part), and
//! puts the bone morphs on the pose it samples from the clip ([`apply_bone_morphs`]) before
//! world transforms and skinning. The clip's IK and grants were solved when it was made, so a
//! bone morph on an IK link or a grant parent moves that bone alone (MMD would re-solve), and
//! one on an IK bone (not in the drawn skeleton) moves nothing.

use glam::{Quat, Vec3, Vec4};

use super::{quat_to_right_handed, to_right_handed};
use crate::import::mmd_model::{MaterialMorphOffset, MmdModel, MorphData};

/// Calls `f(morph, weight)` for each weighted morph and, for a group morph, for each of its
/// members at weight × member weight (one level: a group inside a group is not followed).
/// `data` gives a morph's data by index; non-finite weights and morphs out of range are skipped.
fn expanded<'a>(data: impl Fn(usize) -> Option<&'a MorphData>, weights: &[(usize, f32)], mut f: impl FnMut(&MorphData, f32)) {
    for &(m, w) in weights.iter().filter(|(_, w)| w.is_finite()) {
        match data(m) {
            Some(MorphData::Group(members)) => {
                for &(member, mw) in members.iter().filter(|(k, mw)| *k != m && mw.is_finite()) {
                    if let Some(d) = data(member) {
                        f(d, w * mw);
                    }
                }
            }
            Some(d) => f(d, w),
            None => {}
        }
    }
}

/// A model's bone and material morphs kept apart from the model (what a viewer holds per
/// mesh, beside its vertex morphs in [`super::morph::DrawnMorphs`]): the morphs' data (groups,
/// bone and material morphs; other kinds kept as empty groups so indices stay the model's),
/// and the materials' edge sizes and the values the other factors act on.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct MorphEffects {
    data: Vec<MorphData>,
    bones: usize,
    edge_sizes: Vec<f32>,
    bases: Vec<MaterialBase>,
}

/// The values of a material that its morphs' ambient and specular factors act on (as the
/// model gives them: the ambient colour MMD adds to the lit diffuse, the specular colour and
/// power of its Blinn-Phong highlight).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct MaterialBase {
    pub ambient: Vec3,
    pub specular: Vec3,
    pub specular_power: f32,
}

impl MorphEffects {
    pub fn new(model: &MmdModel) -> MorphEffects {
        let data = model
            .morphs
            .iter()
            .map(|m| match &m.data {
                d @ (MorphData::Group(_) | MorphData::Bone(_) | MorphData::Material(_)) => d.clone(),
                _ => MorphData::Group(Vec::new()),
            })
            .collect();
        MorphEffects {
            data,
            bones: model.bones.len(),
            edge_sizes: model.materials.iter().map(|m| m.edge_size).collect(),
            bases: model.materials.iter().map(|m| MaterialBase { ambient: m.ambient, specular: m.specular, specular_power: m.specular_power }).collect(),
        }
    }

    /// Whether the model has no bone or material morph.
    pub fn is_empty(&self) -> bool {
        !self.data.iter().any(|d| matches!(d, MorphData::Bone(_) | MorphData::Material(_)))
    }

    /// Whether the model has material morphs.
    pub fn has_material_morphs(&self) -> bool {
        self.data.iter().any(|d| matches!(d, MorphData::Material(_)))
    }

    /// Whether the model has bone morphs.
    pub fn has_bone_morphs(&self) -> bool {
        self.data.iter().any(|d| matches!(d, MorphData::Bone(_)))
    }

    /// Material `m`'s edge size as the model gives it (0 when out of range).
    pub fn edge_size(&self, m: usize) -> f32 {
        self.edge_sizes.get(m).copied().unwrap_or(0.0)
    }

    /// Material `m`'s ambient and specular values as the model gives them (zero when out of range).
    pub fn material_base(&self, m: usize) -> MaterialBase {
        self.bases.get(m).copied().unwrap_or_default()
    }

    /// [`bone_morphs_into`] on the kept morphs.
    pub fn bone_morphs_into(&self, weights: &[(usize, f32)], out: &mut Vec<BoneMorph>) -> usize {
        bones_into(|i| self.data.get(i), self.bones, weights, out)
    }

    /// [`material_factors_into`] on the kept morphs.
    pub fn material_factors_into(&self, weights: &[(usize, f32)], out: &mut Vec<MaterialFactors>) -> usize {
        materials_into(|i| self.data.get(i), self.edge_sizes.len(), weights, out)
    }
}

/// One bone's share of the bone morphs: a translation (MMD units, right-handed, as
/// [`super::MmdRig`] poses) added to its local key and a rotation (right-handed) applied after it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BoneMorph {
    pub translation: Vec3,
    pub rotation: Quat,
}

impl BoneMorph {
    pub const NONE: BoneMorph = BoneMorph { translation: Vec3::ZERO, rotation: Quat::IDENTITY };
}

/// The bone morphs of `weights` per model bone, into `out` (one per bone; resized and reset):
/// translation w × the morph's (right-handed, MMD units), rotation slerp(identity, the morph's,
/// w) (right-handed), several morphs on one bone adding their translations and composing their
/// rotations in the order given. Bones out of range and non-finite offsets are skipped. Returns
/// how many bones moved.
pub fn bone_morphs_into(model: &MmdModel, weights: &[(usize, f32)], out: &mut Vec<BoneMorph>) -> usize {
    bones_into(|i| model.morphs.get(i).map(|m| &m.data), model.bones.len(), weights, out)
}

fn bones_into<'a>(data: impl Fn(usize) -> Option<&'a MorphData>, bones: usize, weights: &[(usize, f32)], out: &mut Vec<BoneMorph>) -> usize {
    out.clear();
    out.resize(bones, BoneMorph::NONE);
    expanded(data, weights, |d, w| {
        if let MorphData::Bone(offsets) = d {
            for &(b, t, q) in offsets {
                let Some(o) = out.get_mut(b) else { continue };
                let q = q.normalize();
                if !(t.is_finite() && q.is_finite()) {
                    continue;
                }
                o.translation += to_right_handed(t) * w;
                o.rotation = (o.rotation * Quat::IDENTITY.slerp(quat_to_right_handed(q), w)).normalize();
            }
        }
    });
    out.iter().filter(|b| **b != BoneMorph::NONE).count()
}

/// Puts bone morphs (per rig bone, as [`bone_morphs_into`] gives them) on a local pose of the
/// model's deforming skeleton ([`super::MmdRig::deform_skeleton`]; `rig_index`: per joint, its
/// rig bone), in place: each joint's translation (metres, its parent's frame) moved by its
/// bone's morph translation × `metres_per_unit`, its rotation turned by the morph's after the
/// key's (`rotation × morph`, the morph's turn in the bone's own frame, as the rig composes a
/// key with its grant share). Bones with no joint (IK bones and their targets) are not posed
/// here. Joints past the pose's or the index's length are left. Returns how many joints moved.
pub fn apply_bone_morphs(morphs: &[BoneMorph], rig_index: &[usize], metres_per_unit: f32, rotations: &mut [Quat], translations: &mut [Vec3]) -> usize {
    let mut moved = 0;
    for (j, &b) in rig_index.iter().enumerate() {
        let Some(m) = morphs.get(b).filter(|m| **m != BoneMorph::NONE) else { continue };
        if let Some(r) = rotations.get_mut(j) {
            *r = (*r * m.rotation).normalize();
        }
        if let Some(t) = translations.get_mut(j) {
            *t += m.translation * metres_per_unit;
        }
        moved += 1;
    }
    moved
}

/// Multiply and add factors on a material's values at the weights given: each value becomes
/// value × mul + add. [`MaterialFactors::NONE`] changes nothing.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MaterialFactors {
    pub diffuse_mul: Vec4,
    pub diffuse_add: Vec4,
    pub specular_mul: Vec3,
    pub specular_add: Vec3,
    pub specular_power_mul: f32,
    pub specular_power_add: f32,
    pub ambient_mul: Vec3,
    pub ambient_add: Vec3,
    pub edge_colour_mul: Vec4,
    pub edge_colour_add: Vec4,
    pub edge_size_mul: f32,
    pub edge_size_add: f32,
    pub texture_mul: Vec4,
    pub texture_add: Vec4,
    pub sphere_mul: Vec4,
    pub sphere_add: Vec4,
    pub toon_mul: Vec4,
    pub toon_add: Vec4,
}

impl MaterialFactors {
    pub const NONE: MaterialFactors = MaterialFactors {
        diffuse_mul: Vec4::ONE,
        diffuse_add: Vec4::ZERO,
        specular_mul: Vec3::ONE,
        specular_add: Vec3::ZERO,
        specular_power_mul: 1.0,
        specular_power_add: 0.0,
        ambient_mul: Vec3::ONE,
        ambient_add: Vec3::ZERO,
        edge_colour_mul: Vec4::ONE,
        edge_colour_add: Vec4::ZERO,
        edge_size_mul: 1.0,
        edge_size_add: 0.0,
        texture_mul: Vec4::ONE,
        texture_add: Vec4::ZERO,
        sphere_mul: Vec4::ONE,
        sphere_add: Vec4::ZERO,
        toon_mul: Vec4::ONE,
        toon_add: Vec4::ZERO,
    };

    /// Takes one material morph offset at weight `w` into these factors.
    fn take(&mut self, o: &MaterialMorphOffset, w: f32) {
        if o.operation == 0 {
            let l4 = |v: Vec4| Vec4::ONE + (v - Vec4::ONE) * w;
            let l3 = |v: Vec3| Vec3::ONE + (v - Vec3::ONE) * w;
            let l1 = |v: f32| 1.0 + (v - 1.0) * w;
            self.diffuse_mul *= l4(o.diffuse);
            self.specular_mul *= l3(o.specular);
            self.specular_power_mul *= l1(o.specular_power);
            self.ambient_mul *= l3(o.ambient);
            self.edge_colour_mul *= l4(o.edge_colour);
            self.edge_size_mul *= l1(o.edge_size);
            self.texture_mul *= l4(o.texture_tint);
            self.sphere_mul *= l4(o.sphere_tint);
            self.toon_mul *= l4(o.toon_tint);
        } else {
            self.diffuse_add += o.diffuse * w;
            self.specular_add += o.specular * w;
            self.specular_power_add += o.specular_power * w;
            self.ambient_add += o.ambient * w;
            self.edge_colour_add += o.edge_colour * w;
            self.edge_size_add += o.edge_size * w;
            self.texture_add += o.texture_tint * w;
            self.sphere_add += o.sphere_tint * w;
            self.toon_add += o.toon_tint * w;
        }
    }

    /// Whether every factor is finite (a morph with NaN or infinite values is left out whole).
    fn is_finite(&self) -> bool {
        [self.diffuse_mul, self.diffuse_add, self.edge_colour_mul, self.edge_colour_add, self.texture_mul, self.texture_add, self.sphere_mul, self.sphere_add, self.toon_mul, self.toon_add]
            .iter()
            .all(|v| v.is_finite())
            && [self.specular_mul, self.specular_add, self.ambient_mul, self.ambient_add].iter().all(|v| v.is_finite())
            && [self.specular_power_mul, self.specular_power_add, self.edge_size_mul, self.edge_size_add].iter().all(|v| v.is_finite())
    }

    /// A diffuse colour (RGBA) with these factors on it.
    pub fn diffuse(&self, base: Vec4) -> Vec4 {
        base * self.diffuse_mul + self.diffuse_add
    }

    /// An edge colour (RGBA) with these factors on it.
    pub fn edge_colour(&self, base: Vec4) -> Vec4 {
        base * self.edge_colour_mul + self.edge_colour_add
    }

    /// An ambient colour (RGB) with these factors on it.
    pub fn ambient(&self, base: Vec3) -> Vec3 {
        base * self.ambient_mul + self.ambient_add
    }

    /// A specular colour (RGB) with these factors on it.
    pub fn specular(&self, base: Vec3) -> Vec3 {
        base * self.specular_mul + self.specular_add
    }

    /// A specular power with these factors on it (never below 0).
    pub fn specular_power(&self, base: f32) -> f32 {
        (base * self.specular_power_mul + self.specular_power_add).max(0.0)
    }

    /// An edge size with these factors on it (never below 0).
    pub fn edge_size(&self, base: f32) -> f32 {
        (base * self.edge_size_mul + self.edge_size_add).max(0.0)
    }
}

impl Default for MaterialFactors {
    fn default() -> Self {
        MaterialFactors::NONE
    }
}

/// The material morphs of `weights` per model material, into `out` (one per material; resized
/// and reset): an offset naming no material (PMX's −1) acts on every material, one naming a
/// material out of range is skipped, an offset with a non-finite value is left out. Returns
/// how many materials changed.
pub fn material_factors_into(model: &MmdModel, weights: &[(usize, f32)], out: &mut Vec<MaterialFactors>) -> usize {
    materials_into(|i| model.morphs.get(i).map(|m| &m.data), model.materials.len(), weights, out)
}

fn materials_into<'a>(data: impl Fn(usize) -> Option<&'a MorphData>, materials: usize, weights: &[(usize, f32)], out: &mut Vec<MaterialFactors>) -> usize {
    out.clear();
    out.resize(materials, MaterialFactors::NONE);
    expanded(data, weights, |d, w| {
        if let MorphData::Material(offsets) = d {
            for o in offsets {
                let mut probe = MaterialFactors::NONE;
                probe.take(o, 1.0);
                if !probe.is_finite() {
                    continue;
                }
                match o.material {
                    None => out.iter_mut().for_each(|f| f.take(o, w)),
                    Some(m) => {
                        if let Some(f) = out.get_mut(m) {
                            f.take(o, w);
                        }
                    }
                }
            }
        }
    });
    out.iter().filter(|f| **f != MaterialFactors::NONE).count()
}

/// Which of a model's morphs are of a kind the engine does not play (UVs of the additional
/// UV channels, flip, impulse), by name, for a notice. Vertex, group, bone, material and base-UV
/// morphs are played.
pub fn unplayed_morphs(model: &MmdModel) -> Vec<(&str, &'static str)> {
    model
        .morphs
        .iter()
        .filter_map(|m| {
            let kind = match &m.data {
                MorphData::Uv { channel: 1.., .. } => "additional-UV",
                MorphData::Flip(_) => "flip",
                MorphData::Impulse(_) => "impulse",
                _ => return None,
            };
            Some((m.name.as_str(), kind))
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::import::mmd_model::{BoneTail, MmdBone, MmdMaterial, MmdMorph, ModelFormat, SphereMode, Toon};

    fn offset(material: Option<usize>, operation: u8, diffuse: Vec4, edge: f32) -> MaterialMorphOffset {
        let z4 = if operation == 0 { Vec4::ONE } else { Vec4::ZERO };
        let z3 = if operation == 0 { Vec3::ONE } else { Vec3::ZERO };
        let z1 = if operation == 0 { 1.0 } else { 0.0 };
        MaterialMorphOffset {
            material,
            operation,
            diffuse,
            specular: z3,
            specular_power: z1,
            ambient: z3,
            edge_colour: z4,
            edge_size: edge,
            texture_tint: z4,
            sphere_tint: z4,
            toon_tint: z4,
        }
    }

    fn model(morphs: Vec<MorphData>, materials: usize, bones: usize) -> MmdModel {
        let material = MmdMaterial {
            name: String::new(),
            name_en: String::new(),
            diffuse: Vec4::ONE,
            specular: Vec3::ZERO,
            specular_power: 0.0,
            ambient: Vec3::ZERO,
            flags: 0,
            edge_colour: Vec4::W,
            edge_size: 1.0,
            texture: None,
            sphere: None,
            sphere_mode: SphereMode::None,
            toon: Toon::None,
            memo: String::new(),
            index_count: 0,
        };
        let bone = |i: usize| MmdBone {
            name: format!("b{i}"),
            name_en: String::new(),
            position: Vec3::ZERO,
            parent: None,
            layer: 0,
            flags: 0,
            tail: BoneTail::Bone(None),
            grant: None,
            fixed_axis: None,
            local_axes: None,
            external_parent_key: None,
            ik: None,
            pmd_type: None,
        };
        MmdModel {
            format: ModelFormat::Pmx { version: 2.0 },
            name: String::new(),
            name_en: String::new(),
            comment: String::new(),
            comment_en: String::new(),
            vertices: Vec::new(),
            additional_uv_count: 0,
            additional_uvs: Vec::new(),
            indices: Vec::new(),
            textures: Vec::new(),
            materials: vec![material; materials],
            bones: (0..bones).map(bone).collect(),
            morphs: morphs.into_iter().enumerate().map(|(i, data)| MmdMorph { name: format!("m{i}"), name_en: String::new(), panel: 4, data }).collect(),
            display_frames: Vec::new(),
            rigid_bodies: Vec::new(),
            joints: Vec::new(),
            soft_bodies: Vec::new(),
        }
    }

    #[test]
    fn material_morphs_multiply_by_lerp_and_add_by_weight_on_their_material_or_all() {
        let m = model(
            vec![
                MorphData::Material(vec![offset(Some(1), 0, Vec4::new(0.0, 0.5, 1.0, 0.0), 2.0)]),
                MorphData::Material(vec![offset(None, 1, Vec4::new(0.0, 0.0, 0.0, 1.0), 0.5)]),
                MorphData::Group(vec![(0, 0.5), (1, 1.0), (2, 1.0)]),
                MorphData::Material(vec![offset(Some(9), 1, Vec4::ONE, 1.0)]),
            ],
            3,
            0,
        );
        let mut out = Vec::new();
        assert_eq!(material_factors_into(&m, &[], &mut out), 0);
        assert_eq!(out.len(), 3);
        // Multiply at 0.5 on material 1: lerp(1, v, 0.5).
        assert_eq!(material_factors_into(&m, &[(0, 0.5)], &mut out), 1);
        assert_eq!(out[1].diffuse_mul, Vec4::new(0.5, 0.75, 1.0, 0.5));
        assert_eq!(out[1].edge_size_mul, 1.5);
        assert_eq!(out[0], MaterialFactors::NONE);
        // Add on every material, weight 0.4.
        assert_eq!(material_factors_into(&m, &[(1, 0.4)], &mut out), 3);
        for f in &out {
            assert!((f.diffuse(Vec4::new(0.2, 0.2, 0.2, 0.0)) - Vec4::new(0.2, 0.2, 0.2, 0.4)).length() < 1e-6);
            assert!((f.edge_size(1.0) - 1.2).abs() < 1e-6);
        }
        // A group at 0.8: member 0 at 0.4, member 1 at 0.8, itself skipped; combined value × mul + add.
        material_factors_into(&m, &[(2, 0.8)], &mut out);
        let d = out[1].diffuse(Vec4::ONE);
        assert!((d - Vec4::new(0.6, 0.8, 1.0, 0.6 + 0.8)).length() < 1e-6, "{d:?}");
        // A material out of range and a non-finite weight change nothing.
        assert_eq!(material_factors_into(&m, &[(3, 1.0), (0, f32::NAN), (99, 1.0)], &mut out), 0);
    }

    #[test]
    fn bone_morphs_go_on_the_joints_of_their_bones_and_ambient_specular_factors_apply() {
        let q = Quat::from_rotation_z(0.5);
        let morphs = [BoneMorph::NONE, BoneMorph { translation: Vec3::new(1.0, 0.0, 0.0), rotation: q }, BoneMorph { translation: Vec3::Y, rotation: Quat::IDENTITY }];
        // Joints 0 and 1 are rig bones 1 and 0; bone 2 (an IK bone) has no joint; a joint past the pose is left.
        let (mut rot, mut trans) = (vec![Quat::from_rotation_x(0.3), Quat::IDENTITY], vec![Vec3::ZERO, Vec3::ONE]);
        assert_eq!(apply_bone_morphs(&morphs, &[1, 0, 1], 0.08, &mut rot, &mut trans), 2);
        assert!((rot[0] - (Quat::from_rotation_x(0.3) * q)).length() < 1e-6, "the key's rotation, then the morph's");
        assert!((trans[0] - Vec3::new(0.08, 0.0, 0.0)).length() < 1e-7, "translation in metres");
        assert_eq!((rot[1], trans[1]), (Quat::IDENTITY, Vec3::ONE), "bone 0 has no morph");
        let mut f = MaterialFactors::NONE;
        assert_eq!((f.ambient(Vec3::splat(0.5)), f.specular(Vec3::splat(0.2)), f.specular_power(5.0)), (Vec3::splat(0.5), Vec3::splat(0.2), 5.0));
        f.ambient_mul = Vec3::splat(0.5);
        f.ambient_add = Vec3::X;
        f.specular_power_add = -10.0;
        assert_eq!(f.ambient(Vec3::splat(0.5)), Vec3::new(1.25, 0.25, 0.25));
        assert_eq!(f.specular_power(5.0), 0.0, "never below 0");
    }

    #[test]
    fn bone_morphs_move_and_turn_their_bones_by_weight() {
        let q = Quat::from_rotation_y(0.8);
        let m = model(
            vec![
                MorphData::Bone(vec![(1, Vec3::new(1.0, 2.0, 3.0), q), (7, Vec3::ONE, q)]),
                MorphData::Group(vec![(0, 0.5)]),
                MorphData::Bone(vec![(1, Vec3::new(f32::NAN, 0.0, 0.0), q)]),
            ],
            0,
            2,
        );
        let mut out = Vec::new();
        assert_eq!(bone_morphs_into(&m, &[(0, 0.25), (2, 1.0)], &mut out), 1);
        assert_eq!(out[0], BoneMorph::NONE);
        assert!((out[1].translation - Vec3::new(0.25, 0.5, -0.75)).length() < 1e-6);
        let want = Quat::IDENTITY.slerp(quat_to_right_handed(q), 0.25);
        // Compared as quaternions, up to sign (an f32 angle between near-equal rotations is no finer than ~1e-3 rad).
        assert!((out[1].rotation - want).length().min((out[1].rotation + want).length()) < 1e-5, "{:?} vs {want:?}", out[1].rotation);
        // Through the group at 1: half the morph.
        bone_morphs_into(&m, &[(1, 1.0)], &mut out);
        assert!((out[1].translation - Vec3::new(0.5, 1.0, -1.5)).length() < 1e-6);
        assert!((out[1].rotation.angle_between(Quat::IDENTITY) - 0.4).abs() < 1e-4);
    }
}
