//! MMD rigs from parsed models ([`MmdModel`], PMD or PMX), and a VMD's bone keys as an
//! [`MmdMotion`]; [`vmd_to_clip`] poses a VMD on the model it names (or on the built-in standard
//! skeleton) and returns the clip.
//!
//! Read the way three.js r171's MMDLoader reads them: positions converted to right-handed; PMD
//! links named ひざ bend one way about +X (three's `limitation`), PMX link limits converted
//! (x and y negated and swapped, as three does); PMX transform levels and the after-physics flag
//! give the deformation order. PMD has no levels: an IK bone below another IK bone (つま先ＩＫ under
//! 足ＩＫ) is given a higher level so it solves after it, as MMD's IK list order does. PMD's
//! "rotation influenced" bone kinds are not applied (three.js does not either).

use glam::Vec3;
use thiserror::Error;

use super::{standard_rig, to_right_handed, AngleLimit, BoneKeys, Grant, IkChain, IkLink, MmdBone, MmdClipOptions, MmdMotion, MmdRig, MmdRigError, VmdBoneKey};
use crate::clip::Clip;
use crate::import::mmd_model::{bone_flags, MmdModel, ModelFormat};
use crate::import::vmd::Vmd;

impl MmdRig {
    /// The rig of a parsed PMD/PMX model's bones.
    pub fn from_model(model: &MmdModel) -> Result<MmdRig, MmdRigError> {
        let n = model.bones.len();
        let pmd = model.format == ModelFormat::Pmd;
        let mut bones = Vec::with_capacity(n);
        for b in &model.bones {
            let mut bone = MmdBone::new(b.name.clone(), b.parent, to_right_handed(b.position));
            bone.deform_level = b.layer;
            bone.after_physics = b.has(bone_flags::AFTER_PHYSICS);
            bone.fixed_axis = b.fixed_axis.map(to_right_handed);
            bone.grant = b.grant.map(|g| Grant { parent: g.parent, ratio: g.ratio, rotate: g.rotation, translate: g.translation, local: g.local });
            if let Some(ik) = &b.ik {
                let mut links = Vec::with_capacity(ik.links.len());
                for l in &ik.links {
                    let named_knee = model.bones.get(l.bone).is_some_and(|lb| lb.name.contains("ひざ"));
                    let limit = if pmd {
                        named_knee.then_some(AngleLimit::KneeX)
                    } else {
                        l.limits.map(|(lo, hi)| AngleLimit::Euler { min_rad: Vec3::new(-hi.x, -hi.y, lo.z), max_rad: Vec3::new(-lo.x, -lo.y, hi.z) })
                    };
                    links.push(IkLink { bone: l.bone, limit });
                }
                bone.ik = Some(IkChain { effector: ik.target, loop_count: ik.loop_count, limit_angle_rad: ik.limit_angle_rad, links });
            }
            bones.push(bone);
        }
        if pmd {
            // IK bones after the plain bones, each after the IK bones above it.
            let levels: Vec<i32> = (0..n)
                .map(|i| {
                    if bones[i].ik.is_none() {
                        return 0;
                    }
                    let (mut k, mut level, mut steps) = (bones[i].parent, 1, 0);
                    while let Some(p) = k.filter(|&p| p < n && steps <= n) {
                        if bones[p].ik.is_some() {
                            level += 1;
                        }
                        steps += 1;
                        k = bones[p].parent;
                    }
                    level
                })
                .collect();
            for (b, l) in bones.iter_mut().zip(levels) {
                b.deform_level = l;
            }
        }
        MmdRig::new(model.name.clone(), bones)
    }
}

impl MmdMotion {
    /// The bone keys of a parsed VMD, grouped by bone in file order.
    pub fn from_vmd(vmd: &Vmd) -> MmdMotion {
        let mut bones: Vec<BoneKeys> = Vec::new();
        let mut index = std::collections::HashMap::new();
        for k in &vmd.bone_keys {
            let at = *index.entry(k.name.as_str()).or_insert_with(|| {
                bones.push(BoneKeys { bone: k.name.clone(), keys: Vec::new() });
                bones.len() - 1
            });
            bones[at].keys.push(VmdBoneKey::from_vmd_key(k));
        }
        MmdMotion { model_name: vmd.model_name.clone(), bones }
    }
}

#[derive(Debug, Error, PartialEq)]
pub enum MmdImportError {
    #[error("{file}: model '{model}': {source}")]
    Rig { file: String, model: String, source: MmdRigError },
    #[error("{file}: the motion has no bone keys")]
    NoBoneKeys { file: String },
}

/// Which rig a VMD was posed on, and how well its names matched.
#[derive(Clone, Debug, PartialEq)]
pub struct MmdImportReport {
    /// The model's name, or "standard" for the built-in skeleton.
    pub rig: String,
    /// The VMD names a model and that model was given.
    pub header_matched: bool,
    /// Keyed bone names the rig lacks (their keys are ignored).
    pub unmatched_bones: Vec<String>,
}

/// Poses a VMD's bone keys into a clip: on the given model whose name the VMD header names,
/// else on the first model given, else on the built-in standard skeleton.
pub fn vmd_to_clip(file: &str, vmd: &Vmd, models: &[MmdModel]) -> Result<(Clip, MmdImportReport), MmdImportError> {
    let motion = MmdMotion::from_vmd(vmd);
    if motion.bones.is_empty() {
        return Err(MmdImportError::NoBoneKeys { file: file.into() });
    }
    let named = models.iter().find(|m| !vmd.model_name.is_empty() && m.name == vmd.model_name);
    let rig = match named.or(models.first()) {
        Some(m) => MmdRig::from_model(m).map_err(|source| MmdImportError::Rig { file: file.into(), model: m.name.clone(), source })?,
        None => standard_rig(),
    };
    let name = crate::import::stem(file).to_string();
    let opts = MmdClipOptions { name, source: file.into(), ..Default::default() };
    let clip = rig.motion_to_clip(&motion, &opts).map_err(|source| MmdImportError::Rig { file: file.into(), model: rig.name.clone(), source })?;
    let report = MmdImportReport { rig: rig.name.clone(), header_matched: named.is_some(), unmatched_bones: motion.unmatched_bones(&rig) };
    Ok((clip, report))
}
