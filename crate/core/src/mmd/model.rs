//! MMD rigs from model files' bone records: PMD's bones and IK list, read the way MMD and
//! three.js r171's MMDLoader read them (left-handed positions converted, PMD's IK control
//! weight × 4 as the per-step limit in radians, links named ひざ bend one way about +X).
//!
//! PMD has no transform levels: the IK list order is carried as the IK bones' levels, so the
//! chains solve in the file's order (つま先ＩＫ after 足ＩＫ) as MMD and three.js solve them. PMD's
//! "rotation influenced" bone kinds (eyes, twist helpers) are not applied, as three.js does not.

use glam::Vec3;

use super::{to_right_handed, AngleLimit, IkChain, IkLink, MmdBone, MmdRig, MmdRigError};

/// One PMD bone record as a reader gives it.
#[derive(Clone, Debug, PartialEq)]
pub struct PmdBoneRecord {
    pub name: String,
    pub parent: Option<usize>,
    /// Model-space position in the file's (left-handed) frame.
    pub position: Vec3,
}

/// One PMD IK record.
#[derive(Clone, Debug, PartialEq)]
pub struct PmdIkRecord {
    /// The IK bone (its position is the target; 足ＩＫ).
    pub ik_bone: usize,
    /// The bone brought to the target (足首).
    pub effector: usize,
    pub iterations: u16,
    /// PMD's control weight; MMD's per-step limit is 4 × this, radians.
    pub control_weight: f32,
    /// Links from the effector's parent upward.
    pub links: Vec<usize>,
}

impl MmdRig {
    /// The rig of a PMD model's bones and IK list.
    pub fn from_pmd_records(name: impl Into<String>, bones: &[PmdBoneRecord], iks: &[PmdIkRecord]) -> Result<MmdRig, MmdRigError> {
        let n = bones.len();
        let mut out: Vec<MmdBone> = bones.iter().map(|b| MmdBone::new(b.name.clone(), b.parent, to_right_handed(b.position))).collect();
        for (order, ik) in iks.iter().enumerate() {
            for (role, index) in [("IK bone", ik.ik_bone), ("effector", ik.effector)].into_iter().chain(ik.links.iter().map(|&l| ("link", l))) {
                if index >= n {
                    return Err(MmdRigError::IkBoneOutOfRange { bone: ik.ik_bone, name: format!("IK {order}"), role, index, count: n });
                }
            }
            let links = ik
                .links
                .iter()
                .map(|&l| IkLink { bone: l, limit: bones[l].name.contains("ひざ").then_some(AngleLimit::KneeX) })
                .collect();
            let b = &mut out[ik.ik_bone];
            b.ik = Some(IkChain { effector: ik.effector, loop_count: ik.iterations as u32, limit_angle_rad: ik.control_weight * 4.0, links });
            b.deform_level = order as i32 + 1;
        }
        MmdRig::new(name, out)
    }
}
