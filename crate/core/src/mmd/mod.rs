//! MMD rigs: MikuMikuDance's bones (grant/付与 bones, CCD IK chains with angle limits) posed as
//! MMD poses them, so a VMD motion plays on a PMD/PMX model or on the built-in standard skeleton
//! and becomes an engine [`crate::Clip`] the humanoid mapping takes like a BVH.
//!
//! Coordinates here are three.js's reading of MMD: right-handed, Y up, in the model's own units
//! (MMD files are left-handed; [`to_right_handed`] and [`quat_to_right_handed`] negate z of
//! positions and x, y of rotations, as three's `MMDParser` does), so a pose can be compared with
//! three.js's `MMDAnimationHelper` + `CCDIKSolver` point for point. Clips leave in metres.

pub mod export;
pub mod face_track;
pub mod files;
pub mod mesh;
pub mod morph;
pub mod morph_effects;
mod model;
mod motion;
mod names;
pub mod spring;
mod standard;
pub mod texture;

pub use model::{vmd_to_clip, MmdImportError, MmdImportReport};
pub use motion::{bezier_ratio, BoneKeys, BoneSampler, MmdClipOptions, MmdMotion, MotionSampler, VmdBoneKey, METRES_PER_MMD_UNIT};
pub use names::english_alias;
pub use standard::standard_rig;

use crate::fmath;
use glam::{Quat, Vec3};
use thiserror::Error;

/// Grant (付与): a bone takes a share of another bone's local motion on top of its own.
#[derive(Clone, Debug, PartialEq)]
pub struct Grant {
    /// The bone whose (possibly granted, IK-solved) local motion is shared.
    pub parent: usize,
    /// Share of the motion, usually in `-1..=1` (negative mirrors it).
    pub ratio: f32,
    pub rotate: bool,
    pub translate: bool,
    /// PMX "local grant" flag; posed like a plain grant (three.js does the same).
    pub local: bool,
}

/// An angle limit of one IK link, in the right-handed frame.
#[derive(Clone, Debug, PartialEq)]
pub enum AngleLimit {
    /// MMD's knee rule (three's `limitation = (1, 0, 0)`, PMD links named ひざ): after each step the
    /// link's rotation becomes a rotation about +X by the same angle, so the knee bends one way.
    KneeX,
    /// Per-axis limits on the link's XYZ Euler angles (PMX), radians.
    Euler { min_rad: Vec3, max_rad: Vec3 },
}

#[derive(Clone, Debug, PartialEq)]
pub struct IkLink {
    pub bone: usize,
    pub limit: Option<AngleLimit>,
}

/// A CCD IK chain owned by its IK bone (the bone whose position is the target, 足ＩＫ).
#[derive(Clone, Debug, PartialEq)]
pub struct IkChain {
    /// The bone brought to the target (足首 for 足ＩＫ).
    pub effector: usize,
    /// Iterations (ループ回数).
    pub loop_count: u32,
    /// Largest rotation of one link in one step (単位角), radians.
    pub limit_angle_rad: f32,
    /// Links from the effector's parent upward (ひざ, then 足).
    pub links: Vec<IkLink>,
}

/// One bone of an MMD model.
#[derive(Clone, Debug, PartialEq)]
pub struct MmdBone {
    pub name: String,
    pub parent: Option<usize>,
    /// Rest position in model space, MMD units, right-handed.
    pub rest_position: Vec3,
    pub grant: Option<Grant>,
    pub ik: Option<IkChain>,
    /// PMX transform level (変形階層); 0 for PMD.
    pub deform_level: i32,
    /// PMX "deform after physics" flag.
    pub after_physics: bool,
    /// PMX fixed axis (軸制限). Only MMD's editor uses it: keys already respect it, so posing does not.
    pub fixed_axis: Option<Vec3>,
}

impl MmdBone {
    /// A plain bone (no grant, no IK, level 0).
    pub fn new(name: impl Into<String>, parent: Option<usize>, rest_position: Vec3) -> MmdBone {
        MmdBone { name: name.into(), parent, rest_position, grant: None, ik: None, deform_level: 0, after_physics: false, fixed_axis: None }
    }
}

#[derive(Debug, Error, PartialEq)]
pub enum MmdRigError {
    #[error("MMD rig has no bones")]
    NoBones,
    #[error("bone {bone} '{name}': parent {parent} is not one of the {count} bones")]
    ParentOutOfRange { bone: usize, name: String, parent: usize, count: usize },
    #[error("bone {bone} '{name}' is its own ancestor (a parent cycle)")]
    ParentCycle { bone: usize, name: String },
    #[error("bone {bone} '{name}': grant parent {parent} is not one of the {count} bones or is the bone itself")]
    GrantOutOfRange { bone: usize, name: String, parent: usize, count: usize },
    #[error("bone {bone} '{name}': its grant parents form a cycle")]
    GrantCycle { bone: usize, name: String },
    #[error("bone {bone} '{name}': {what} is not finite")]
    NonFinite { bone: usize, name: String, what: &'static str },
    #[error("IK bone {bone} '{name}': {role} {index} is not one of the {count} bones")]
    IkBoneOutOfRange { bone: usize, name: String, role: &'static str, index: usize, count: usize },
    #[error("motion runs to frame {last_frame}: more than the {max_frames} frames (one hour at 30 fps) a clip may have")]
    TooLong { last_frame: u32, max_frames: usize },
    #[error("pose has {got} {what} for a rig of {bones} bones")]
    PoseLength { what: &'static str, got: usize, bones: usize },
}

/// Converts a position from MMD's left-handed files to the right-handed frame (z negated).
pub fn to_right_handed(v: Vec3) -> Vec3 {
    Vec3::new(v.x, v.y, -v.z)
}

/// Converts a rotation from MMD's left-handed files to the right-handed frame (x, y negated).
pub fn quat_to_right_handed(q: Quat) -> Quat {
    Quat::from_xyzw(-q.x, -q.y, q.z, q.w)
}

/// A validated MMD rig with its evaluation orders.
#[derive(Clone, Debug, PartialEq)]
pub struct MmdRig {
    pub name: String,
    pub bones: Vec<MmdBone>,
    /// Rest translation from the parent (the rest position for roots), per bone.
    offsets: Vec<Vec3>,
    /// Parents before children.
    fk_order: Vec<usize>,
    /// Deformation order (after-physics last, then transform level, then index), with every
    /// grant parent moved before the bones granted from it.
    process_order: Vec<usize>,
    /// Per IK bone: the effector's ancestor path from the outermost link down to the effector.
    ik_paths: Vec<Option<Vec<usize>>>,
    /// Per IK bone: the bones whose world transforms its solve reads (the IK bone's, the
    /// effector's and every link's ancestors, themselves included), parents first.
    ik_inputs: Vec<Option<Vec<usize>>>,
    /// Per IK bone: its links that are not ancestors of the effector (mokou_A.pmd's 右髪Ｃ０),
    /// each with its subtree, parents first. MMD and three.js's `CCDIKSolver` keep such a link:
    /// it turns towards the target like the others but cannot move the effector.
    ik_detached: Vec<Vec<(usize, Vec<usize>)>>,
    /// Run every CCD iteration (three.js's rule) instead of stopping early: see [`MmdRig::with_full_ccd`].
    full_ccd: bool,
}

/// A posed rig: final local motion (grants and IK applied) and world transforms.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct MmdPose {
    pub local_rotations: Vec<Quat>,
    /// Local translation relative to rest (the key's), MMD units.
    pub local_translations: Vec<Vec3>,
    pub world_rotations: Vec<Quat>,
    pub world_positions: Vec<Vec3>,
}

impl MmdRig {
    /// Validates the bones: parents and grant parents in range without cycles, IK bones in
    /// range, finite numbers. An IK link that is not an ancestor of the effector and of the
    /// links before it is kept as MMD keeps it (a detached link, see `ik_detached`).
    pub fn new(name: impl Into<String>, bones: Vec<MmdBone>) -> Result<MmdRig, MmdRigError> {
        let n = bones.len();
        if n == 0 {
            return Err(MmdRigError::NoBones);
        }
        for (i, b) in bones.iter().enumerate() {
            let nf = |what| MmdRigError::NonFinite { bone: i, name: b.name.clone(), what };
            if !b.rest_position.is_finite() {
                return Err(nf("rest position"));
            }
            if let Some(p) = b.parent {
                if p >= n {
                    return Err(MmdRigError::ParentOutOfRange { bone: i, name: b.name.clone(), parent: p, count: n });
                }
            }
            if let Some(g) = &b.grant {
                if g.parent >= n || g.parent == i {
                    return Err(MmdRigError::GrantOutOfRange { bone: i, name: b.name.clone(), parent: g.parent, count: n });
                }
                if !g.ratio.is_finite() {
                    return Err(nf("grant ratio"));
                }
            }
            if let Some(ik) = &b.ik {
                if !ik.limit_angle_rad.is_finite() {
                    return Err(nf("IK limit angle"));
                }
                for (role, index) in std::iter::once(("effector", ik.effector)).chain(ik.links.iter().map(|l| ("link", l.bone))) {
                    if index >= n {
                        return Err(MmdRigError::IkBoneOutOfRange { bone: i, name: b.name.clone(), role, index, count: n });
                    }
                }
                for l in &ik.links {
                    if let Some(AngleLimit::Euler { min_rad, max_rad }) = &l.limit {
                        if !(min_rad.is_finite() && max_rad.is_finite()) {
                            return Err(nf("IK link angle limit"));
                        }
                    }
                }
            }
        }
        // Parent cycles: walking up from any bone must end within n steps.
        for (i, b) in bones.iter().enumerate() {
            let mut k = b.parent;
            let mut steps = 0;
            while let Some(p) = k {
                steps += 1;
                if steps > n {
                    return Err(MmdRigError::ParentCycle { bone: i, name: b.name.clone() });
                }
                k = bones[p].parent;
            }
        }
        let offsets: Vec<Vec3> =
            bones.iter().map(|b| b.rest_position - b.parent.map_or(Vec3::ZERO, |p| bones[p].rest_position)).collect();
        // Parents before children: depth-first from each bone, parents pushed first.
        let mut fk_order = Vec::with_capacity(n);
        let mut placed = vec![false; n];
        for i in 0..n {
            let mut stack = vec![i];
            while let Some(&top) = stack.last() {
                match bones[top].parent.filter(|&p| !placed[p]) {
                    Some(p) => stack.push(p),
                    None => {
                        stack.pop();
                        if !placed[top] {
                            placed[top] = true;
                            fk_order.push(top);
                        }
                    }
                }
            }
        }
        // IK paths: the links that are ancestors of the effector and of the links before them,
        // with the bones between; any other link is detached (its subtree kept to update).
        let mut ik_paths = vec![None; n];
        let mut ik_detached = vec![Vec::new(); n];
        for (i, b) in bones.iter().enumerate() {
            let Some(ik) = &b.ik else { continue };
            let mut path = vec![ik.effector];
            for l in &ik.links {
                let mut k = *path.last().unwrap_or(&ik.effector);
                let mut up = Vec::new();
                let found = loop {
                    match bones[k].parent {
                        Some(p) if p == l.bone => {
                            up.push(p);
                            break true;
                        }
                        Some(p) => {
                            up.push(p);
                            k = p;
                        }
                        None => break false,
                    }
                };
                if found {
                    path.extend(up);
                } else {
                    let below = |j: usize| {
                        let mut k = Some(j);
                        while let Some(x) = k {
                            if x == l.bone {
                                return true;
                            }
                            k = bones[x].parent;
                        }
                        false
                    };
                    ik_detached[i].push((l.bone, fk_order.iter().copied().filter(|&j| below(j)).collect()));
                }
            }
            path.reverse();
            ik_paths[i] = Some(path);
        }
        let ik_inputs = (0..n)
            .map(|i| {
                let ik = bones[i].ik.as_ref()?;
                let mut needed = vec![false; n];
                for start in [i, ik.effector].into_iter().chain(ik.links.iter().map(|l| l.bone)) {
                    let mut k = Some(start);
                    while let Some(j) = k.filter(|&j| !needed[j]) {
                        needed[j] = true;
                        k = bones[j].parent;
                    }
                }
                Some(fk_order.iter().copied().filter(|&j| needed[j]).collect())
            })
            .collect();
        // Deformation order, then grant parents first (three's MMDAnimationHelper does the same
        // by recursion); a grant cycle is an error.
        let mut deform: Vec<usize> = (0..n).collect();
        deform.sort_by_key(|&i| (bones[i].after_physics, bones[i].deform_level, i));
        let mut process_order = Vec::with_capacity(n);
        let mut state = vec![0u8; n]; // 0 new, 1 on the stack, 2 done
        for &start in &deform {
            let mut stack = vec![start];
            while let Some(&top) = stack.last() {
                if state[top] == 2 {
                    stack.pop();
                    continue;
                }
                state[top] = 1;
                match bones[top].grant.as_ref().map(|g| g.parent) {
                    Some(g) if state[g] == 1 => return Err(MmdRigError::GrantCycle { bone: top, name: bones[top].name.clone() }),
                    Some(g) if state[g] == 0 => stack.push(g),
                    _ => {
                        stack.pop();
                        state[top] = 2;
                        process_order.push(top);
                    }
                }
            }
        }
        Ok(MmdRig { name: name.into(), bones, offsets, fk_order, process_order, ik_paths, ik_inputs, ik_detached, full_ccd: false })
    }

    /// The same rig solving IK exactly as three.js does, every CCD iteration run (no early
    /// exit): the control the speed bench and `tests/native/mmd_rig.rs` compare against.
    pub fn with_full_ccd(mut self) -> MmdRig {
        self.full_ccd = true;
        self
    }

    pub fn len(&self) -> usize {
        self.bones.len()
    }

    pub fn is_empty(&self) -> bool {
        self.bones.is_empty()
    }

    /// Index of the first bone with this exact name.
    pub fn find(&self, name: &str) -> Option<usize> {
        self.bones.iter().position(|b| b.name == name)
    }

    /// Rest translation of bone `i` from its parent, MMD units.
    pub fn rest_offset(&self, i: usize) -> Vec3 {
        self.offsets[i]
    }

    /// Bones that are IK bones or hang below one (their targets): they move no vertex.
    pub fn is_ik_helper(&self, i: usize) -> bool {
        let mut k = Some(i);
        let mut steps = 0;
        while let Some(j) = k {
            if self.bones[j].ik.is_some() {
                return true;
            }
            steps += 1;
            if steps > self.bones.len() {
                break;
            }
            k = self.bones[j].parent;
        }
        false
    }

    /// Poses the rig as MMD does from per-bone local keys relative to rest (rotation, and
    /// translation in MMD units; right-handed): bones in deformation order, each taking its
    /// grant parent's share, then each IK bone solving its chain by CCD.
    pub fn pose_into(&self, rotations: &[Quat], translations: &[Vec3], out: &mut MmdPose) -> Result<(), MmdRigError> {
        let n = self.len();
        if rotations.len() != n {
            return Err(MmdRigError::PoseLength { what: "rotations", got: rotations.len(), bones: n });
        }
        if translations.len() != n {
            return Err(MmdRigError::PoseLength { what: "translations", got: translations.len(), bones: n });
        }
        out.local_rotations.clear();
        out.local_rotations.extend(rotations.iter().map(|q| {
            let q = q.normalize();
            if q.is_finite() { q } else { Quat::IDENTITY }
        }));
        out.local_translations.clear();
        out.local_translations.extend(translations.iter().map(|t| if t.is_finite() { *t } else { Vec3::ZERO }));
        out.world_rotations.resize(n, Quat::IDENTITY);
        out.world_positions.resize(n, Vec3::ZERO);
        for &i in &self.process_order {
            let b = &self.bones[i];
            if let Some(g) = &b.grant {
                if g.rotate {
                    let share = Quat::IDENTITY.slerp(out.local_rotations[g.parent], g.ratio);
                    out.local_rotations[i] *= share;
                }
                if g.translate {
                    let t = out.local_translations[g.parent] * g.ratio;
                    out.local_translations[i] += t;
                }
            }
            if let (Some(ik), Some(path), Some(inputs)) = (&b.ik, &self.ik_paths[i], &self.ik_inputs[i]) {
                // Only what this solve reads is brought up to date; everything at the end.
                for &j in inputs {
                    self.world_one(j, out);
                }
                self.solve_ccd(i, ik, path, out);
            }
        }
        self.world_all(out);
        Ok(())
    }

    /// The rest pose posed (identity rotations, zero translations).
    pub fn rest_pose(&self) -> MmdPose {
        let mut p = MmdPose::default();
        let n = self.len();
        // Lengths match by construction.
        let _ = self.pose_into(&vec![Quat::IDENTITY; n], &vec![Vec3::ZERO; n], &mut p);
        p
    }

    fn world_one(&self, i: usize, p: &mut MmdPose) {
        let local_t = self.offsets[i] + p.local_translations[i];
        match self.bones[i].parent {
            Some(par) => {
                let pr = p.world_rotations[par];
                p.world_positions[i] = p.world_positions[par] + pr * local_t;
                p.world_rotations[i] = pr * p.local_rotations[i];
            }
            None => {
                p.world_positions[i] = local_t;
                p.world_rotations[i] = p.local_rotations[i];
            }
        }
    }

    fn world_all(&self, p: &mut MmdPose) {
        for &i in &self.fk_order {
            self.world_one(i, p);
        }
    }

    /// three.js r171's `CCDIKSolver.updateOne`, step for step, except that it stops early once
    /// more iterations cannot move the effector by a visible amount: when the effector is within
    /// [`CCD_REACHED_UNITS`] of its target, or (chains without PMX Euler limits) an iteration
    /// moved it less than [`CCD_STALLED_UNITS`] (a near-straight leg whose target is out of
    /// reach, where three runs all its iterations to no effect). `tests/native/mmd_rig.rs` checks the poses still agree
    /// with three.js's.
    fn solve_ccd(&self, ik_bone: usize, ik: &IkChain, path: &[usize], p: &mut MmdPose) {
        let target = p.world_positions[ik_bone];
        // Per-step Euler clamping (PMX limits) can idle for an iteration and move again later:
        // those chains stop early only on reaching the target.
        let may_stall = !self.full_ccd && !ik.links.iter().any(|l| matches!(l.limit, Some(AngleLimit::Euler { .. })));
        for _ in 0..ik.loop_count {
            let start = p.world_positions[ik.effector];
            if !self.full_ccd && start.distance_squared(target) < CCD_REACHED_UNITS * CCD_REACHED_UNITS {
                break;
            }
            let mut rotated = false;
            for link in &ik.links {
                let l = link.bone;
                let link_pos = p.world_positions[l];
                let inv = p.world_rotations[l].inverse();
                let effector_vec = (inv * (p.world_positions[ik.effector] - link_pos)).normalize_or_zero();
                let target_vec = (inv * (target - link_pos)).normalize_or_zero();
                if effector_vec == Vec3::ZERO || target_vec == Vec3::ZERO {
                    continue;
                }
                // three computes acos(dot) in f64; in f32 acos near 1 has a floor of ~3e-4 rad,
                // so an effector already on its target would turn. atan2(|e × t|, e · t) is
                // exact near 0 in f32 and equals three's angle everywhere else.
                let mut angle = fmath::atan2(effector_vec.cross(target_vec).length(), target_vec.dot(effector_vec));
                if angle < 1e-5 {
                    continue;
                }
                angle = angle.min(ik.limit_angle_rad);
                let axis = effector_vec.cross(target_vec).normalize_or_zero();
                if axis == Vec3::ZERO {
                    continue;
                }
                let mut q = p.local_rotations[l] * Quat::from_axis_angle(axis, angle);
                match &link.limit {
                    Some(AngleLimit::KneeX) => {
                        let c = q.w.min(1.0);
                        q = Quat::from_xyzw((1.0 - c * c).max(0.0).sqrt(), 0.0, 0.0, c);
                    }
                    Some(AngleLimit::Euler { min_rad, max_rad }) => {
                        let e = euler_xyz_from_quat(q).max(*min_rad).min(*max_rad);
                        q = quat_from_euler_xyz(e);
                    }
                    None => {}
                }
                p.local_rotations[l] = q;
                // The link and everything below it on the way to the effector.
                if let Some(start) = path.iter().position(|&b| b == l) {
                    for &b in &path[start..] {
                        self.world_one(b, p);
                    }
                } else if let Some((_, subtree)) = self.ik_detached[ik_bone].iter().find(|(b, _)| *b == l) {
                    // A detached link: it and what hangs below it (three's updateMatrixWorld).
                    for &b in subtree {
                        self.world_one(b, p);
                    }
                }
                rotated = true;
            }
            if !rotated || (may_stall && p.world_positions[ik.effector].distance_squared(start) < CCD_STALLED_UNITS * CCD_STALLED_UNITS) {
                break;
            }
        }
    }
}

/// CCD stops when the effector is this close to its target, model units (1e-4: 8 µm at
/// [`METRES_PER_MMD_UNIT`]).
pub const CCD_REACHED_UNITS: f32 = 1e-4;
/// CCD stops when one iteration moved the effector less than this, model units.
pub const CCD_STALLED_UNITS: f32 = 1e-4;

/// XYZ Euler angles of a rotation as three.js's `Euler.setFromQuaternion(q, 'XYZ')` reads them.
pub fn euler_xyz_from_quat(q: Quat) -> Vec3 {
    let (x, y, z, w) = (q.x, q.y, q.z, q.w);
    let m11 = 1.0 - 2.0 * (y * y + z * z);
    let m12 = 2.0 * (x * y - w * z);
    let m13 = 2.0 * (x * z + w * y);
    let m22 = 1.0 - 2.0 * (x * x + z * z);
    let m23 = 2.0 * (y * z - w * x);
    let m32 = 2.0 * (y * z + w * x);
    let m33 = 1.0 - 2.0 * (x * x + y * y);
    let ey = fmath::asin(m13.clamp(-1.0, 1.0));
    if m13.abs() < 0.9999999 {
        Vec3::new(fmath::atan2(-m23, m33), ey, fmath::atan2(-m12, m11))
    } else {
        Vec3::new(fmath::atan2(m32, m22), ey, 0.0)
    }
}

/// The rotation of XYZ Euler angles (three.js's `Quaternion.setFromEuler`, order 'XYZ').
pub fn quat_from_euler_xyz(e: Vec3) -> Quat {
    let (s1, c1) = fmath::sin_cos(e.x * 0.5);
    let (s2, c2) = fmath::sin_cos(e.y * 0.5);
    let (s3, c3) = fmath::sin_cos(e.z * 0.5);
    Quat::from_xyzw(
        s1 * c2 * c3 + c1 * s2 * s3,
        c1 * s2 * c3 - s1 * c2 * s3,
        c1 * c2 * s3 + s1 * s2 * c3,
        c1 * c2 * c3 - s1 * s2 * s3,
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::canon::humanoid::{HumanoidMap, HumanoidStatus};

    /// Distance between two rotations' quaternions, up to sign.
    fn qdist(a: Quat, b: Quat) -> f32 {
        (a - b).length().min((a + b).length())
    }

    fn chain3() -> Vec<MmdBone> {
        vec![
            MmdBone::new("a", None, Vec3::ZERO),
            MmdBone::new("b", Some(0), Vec3::Y),
            MmdBone::new("c", Some(1), Vec3::Y * 2.0),
        ]
    }

    #[test]
    fn rest_pose_reproduces_rest_positions() {
        let rig = standard_rig();
        let pose = rig.rest_pose();
        for (i, b) in rig.bones.iter().enumerate() {
            assert!((pose.world_positions[i] - b.rest_position).length() < 1e-5, "{}: {:?} vs {:?}", b.name, pose.world_positions[i], b.rest_position);
        }
    }

    #[test]
    fn grant_with_ratio_half_gives_half_the_rotation() {
        let mut bones = chain3();
        bones.push(MmdBone::new("d", Some(0), Vec3::X));
        bones[3].grant = Some(Grant { parent: 1, ratio: 0.5, rotate: true, translate: true, local: false });
        let rig = MmdRig::new("t", bones).unwrap();
        let q = Quat::from_rotation_z(1.2);
        let mut rots = vec![Quat::IDENTITY; 4];
        rots[1] = q;
        let mut trans = vec![Vec3::ZERO; 4];
        trans[1] = Vec3::new(0.4, 0.0, 0.0);
        let mut pose = MmdPose::default();
        rig.pose_into(&rots, &trans, &mut pose).unwrap();
        let (axis, angle) = pose.local_rotations[3].to_axis_angle();
        assert!((angle - 0.6).abs() < 1e-5 && (axis - Vec3::Z).length() < 1e-4, "{axis:?} {angle}");
        assert!((pose.local_translations[3] - Vec3::new(0.2, 0.0, 0.0)).length() < 1e-6);
        // A grant parent listed after its child still comes first, and a child of a granted bone
        // takes the granted motion.
        let mut bones = chain3();
        bones[0].grant = Some(Grant { parent: 2, ratio: -1.0, rotate: true, translate: false, local: false });
        let rig = MmdRig::new("t", bones).unwrap();
        let mut rots = vec![Quat::IDENTITY; 3];
        rots[2] = q;
        rig.pose_into(&rots, &[Vec3::ZERO; 3], &mut pose).unwrap();
        assert!(qdist(pose.local_rotations[0], q.inverse()) < 1e-5);
    }

    #[test]
    fn a_link_off_the_effector_path_is_kept_and_turns_as_three_turns_it() {
        // c (2) is the effector, b (1) an ancestor link, d (3) a link beside the chain with a
        // child e (4); the IK bone (5) out of reach of b alone, so every iteration leaves a gap.
        let mut b = chain3();
        b.push(MmdBone::new("d", Some(0), Vec3::X));
        b.push(MmdBone::new("e", Some(3), Vec3::X * 2.0));
        b.push(MmdBone::new("ik", None, Vec3::new(3.0, 1.0, 0.0)));
        b[5].ik = Some(IkChain { effector: 2, loop_count: 2, limit_angle_rad: 0.25, links: vec![IkLink { bone: 1, limit: None }, IkLink { bone: 3, limit: None }] });
        let rig = MmdRig::new("t", b).unwrap().with_full_ccd();
        let mut pose = MmdPose::default();
        rig.pose_into(&[Quat::IDENTITY; 6], &[Vec3::ZERO; 6], &mut pose).unwrap();
        // b turns 0.25 rad (the unit angle) towards the target per iteration, about -Z.
        let (axis, angle) = pose.local_rotations[1].to_axis_angle();
        assert!((angle - 0.5).abs() < 1e-4 && (axis + Vec3::Z).length() < 1e-4, "b: {axis:?} {angle}");
        // d sees the effector and the target at some angle apart and turns by the unit angle
        // each iteration, moving only itself and e: three's CCDIKSolver does the same.
        let (axis, angle) = pose.local_rotations[3].to_axis_angle();
        assert!((angle - 0.5).abs() < 1e-4 && axis.z.abs() > 0.99, "d: {axis:?} {angle}");
        let e = pose.world_positions[3] + pose.world_rotations[3] * Vec3::X;
        assert!((pose.world_positions[4] - e).length() < 1e-5);
        let c = pose.world_positions[1] + pose.world_rotations[1] * Vec3::Y;
        assert!((pose.world_positions[2] - c).length() < 1e-5, "the effector hangs from b alone");
    }

    #[test]
    fn constructor_rejects_bad_rigs() {
        let mut b = chain3();
        b[1].parent = Some(7);
        assert!(matches!(MmdRig::new("t", b), Err(MmdRigError::ParentOutOfRange { bone: 1, parent: 7, .. })));
        let mut b = chain3();
        b[0].parent = Some(2);
        assert!(matches!(MmdRig::new("t", b), Err(MmdRigError::ParentCycle { .. })));
        let mut b = chain3();
        b[1].grant = Some(Grant { parent: 2, ratio: 1.0, rotate: true, translate: false, local: false });
        b[2].grant = Some(Grant { parent: 1, ratio: 1.0, rotate: true, translate: false, local: false });
        assert!(matches!(MmdRig::new("t", b), Err(MmdRigError::GrantCycle { .. })));
        let mut b = chain3();
        b[2].rest_position.x = f32::NAN;
        assert!(matches!(MmdRig::new("t", b), Err(MmdRigError::NonFinite { bone: 2, .. })));
        assert_eq!(MmdRig::new("t", vec![]), Err(MmdRigError::NoBones));
        let rig = MmdRig::new("t", chain3()).unwrap();
        let mut pose = MmdPose::default();
        assert!(matches!(rig.pose_into(&[Quat::IDENTITY; 2], &[Vec3::ZERO; 3], &mut pose), Err(MmdRigError::PoseLength { .. })));
    }

    /// Standard rig with the left 足ＩＫ moved by `delta` (right-handed units).
    fn leg_pose(delta: Vec3) -> (MmdRig, MmdPose, usize) {
        let rig = standard_rig();
        let n = rig.len();
        let ik = rig.find("左足ＩＫ").unwrap();
        let mut trans = vec![Vec3::ZERO; n];
        trans[ik] = delta;
        let mut pose = MmdPose::default();
        rig.pose_into(&vec![Quat::IDENTITY; n], &trans, &mut pose).unwrap();
        (rig, pose, ik)
    }

    #[test]
    fn ccd_reaches_a_reachable_target_and_knees_bend_one_way() {
        for delta in [Vec3::new(0.0, 3.0, 1.0), Vec3::new(0.5, 2.0, -1.5), Vec3::new(-0.6, 4.5, 2.5), Vec3::new(0.0, 1.0, 0.0)] {
            let (rig, pose, ik) = leg_pose(delta);
            let ankle = rig.find("左足首").unwrap();
            let knee = rig.find("左ひざ").unwrap();
            let leg = rig.find("左足").unwrap();
            let err = (pose.world_positions[ankle] - pose.world_positions[ik]).length();
            assert!(err < 0.05, "target {delta:?}: ankle {err} units from 足ＩＫ");
            // The shin, seen from the thigh's frame, swings backward (−z, the model faces +z).
            let shin = pose.world_rotations[leg].inverse() * (pose.world_positions[ankle] - pose.world_positions[knee]);
            assert!(shin.z <= 1e-4, "target {delta:?}: knee bent forward, shin {shin:?}");
            let q = pose.local_rotations[knee];
            assert!(q.y.abs() < 1e-6 && q.z.abs() < 1e-6 && q.x >= 0.0, "knee rotation not about +X: {q:?}");
        }
    }

    #[test]
    fn ccd_stops_short_of_an_unreachable_target_with_a_straight_leg() {
        let (rig, pose, ik) = leg_pose(Vec3::new(0.0, -6.0, 0.0));
        let ankle = rig.find("左足首").unwrap();
        let leg = rig.find("左足").unwrap();
        let reach = (rig.bones[ankle].rest_position - rig.bones[leg].rest_position).length();
        let got = (pose.world_positions[ankle] - pose.world_positions[leg]).length();
        // The knee cannot bend forward past its slightly bent rest, so the leg ends at its rest reach.
        assert!(got <= reach + 1e-4 && got > reach - 0.02, "leg reach {got} vs rest {reach}");
        assert!(pose.world_positions[ankle].y > pose.world_positions[ik].y);
    }

    #[test]
    fn euler_limits_clamp_each_axis() {
        let mut b = chain3();
        b.push(MmdBone::new("d", Some(2), Vec3::new(0.0, 3.0, 0.0)));
        b.push(MmdBone::new("ik", None, Vec3::new(1.5, 2.0, 0.0)));
        let limit = AngleLimit::Euler { min_rad: Vec3::new(-0.1, -0.1, -0.3), max_rad: Vec3::new(0.1, 0.1, 0.3) };
        b[4].ik = Some(IkChain { effector: 3, loop_count: 20, limit_angle_rad: 1.0, links: vec![IkLink { bone: 2, limit: Some(limit) }, IkLink { bone: 1, limit: None }] });
        let rig = MmdRig::new("t", b).unwrap();
        let mut pose = MmdPose::default();
        rig.pose_into(&[Quat::IDENTITY; 5], &[Vec3::ZERO; 5], &mut pose).unwrap();
        let e = euler_xyz_from_quat(pose.local_rotations[2]);
        assert!(e.x.abs() <= 0.1 + 1e-5 && e.y.abs() <= 0.1 + 1e-5 && e.z.abs() <= 0.3 + 1e-5, "{e:?}");
        assert!(pose.local_rotations[1].angle_between(Quat::IDENTITY) > 0.1, "the free link took the rest");
    }

    #[test]
    fn euler_xyz_round_trips() {
        for e in [Vec3::new(0.3, -0.7, 1.1), Vec3::new(-2.0, 0.2, -0.4), Vec3::ZERO] {
            let q = quat_from_euler_xyz(e);
            assert!((euler_xyz_from_quat(q) - e).length() < 1e-5);
            let g = Quat::from_rotation_x(e.x) * Quat::from_rotation_y(e.y) * Quat::from_rotation_z(e.z);
            assert!(qdist(q, g) < 1e-5, "XYZ means Rx·Ry·Rz");
        }
    }

    #[test]
    fn bezier_ratio_matches_the_curve() {
        // The linear default gives back x; an ease-in curve lags behind it.
        for x in [0.0, 0.1, 0.5, 0.77, 1.0] {
            assert!((bezier_ratio(20.0 / 127.0, 107.0 / 127.0, 20.0 / 127.0, 107.0 / 127.0, x) - x).abs() < 1e-3);
            if x > 0.0 && x < 1.0 {
                assert!(bezier_ratio(0.9, 1.0, 0.0, 0.1, x) < x);
            }
        }
        // Against the curve evaluated directly at t = 0.3.
        let (x1, y1, x2, y2, t) = (0.25f32, 0.1f32, 0.25f32, 1.0f32, 0.3f32);
        let b = |a: f32, c: f32| 3.0 * (1.0 - t) * (1.0 - t) * t * a + 3.0 * (1.0 - t) * t * t * c + t * t * t;
        assert!((bezier_ratio(x1, x2, y1, y2, b(x1, x2)) - b(y1, y2)).abs() < 1e-3);
    }

    #[test]
    fn motion_on_the_standard_rig_makes_a_humanoid_clip() {
        let rig = standard_rig();
        let key = |frame: u32, t: Vec3, q: Quat| VmdBoneKey { frame, translation: t, rotation: q, curves: VmdBoneKey::LINEAR };
        let motion = MmdMotion {
            model_name: String::new(),
            bones: vec![
                BoneKeys { bone: "センター".into(), keys: vec![key(0, Vec3::ZERO, Quat::IDENTITY), key(30, Vec3::new(0.0, -2.0, 0.0), Quat::IDENTITY)] },
                BoneKeys { bone: "左腕".into(), keys: vec![key(0, Vec3::ZERO, Quat::IDENTITY), key(30, Vec3::ZERO, Quat::from_rotation_z(0.5))] },
                BoneKeys { bone: "存在しない".into(), keys: vec![key(0, Vec3::ZERO, Quat::IDENTITY)] },
            ],
        };
        assert_eq!(motion.unmatched_bones(&rig), vec!["存在しない".to_string()]);
        let mut far = motion.clone();
        far.bones[0].keys.push(key(u32::MAX, Vec3::ZERO, Quat::IDENTITY));
        assert!(matches!(rig.motion_to_clip(&far, &MmdClipOptions::default()), Err(MmdRigError::TooLong { .. })));
        let clip = rig.motion_to_clip(&motion, &MmdClipOptions::default()).unwrap();
        clip.validate().unwrap();
        assert_eq!(clip.frame_count(), 31);
        assert!(clip.skeleton.find("左足ＩＫ").is_none() && clip.skeleton.find("右つま先ＩＫ").is_none());
        let map = HumanoidMap::from_skeleton(&clip.skeleton);
        assert_eq!(map.status(&clip.skeleton, Some(&clip)), HumanoidStatus::Complete);
        // センター went down 2 units with the feet held by IK: the ankle stays, the knee bends.
        let ankle = clip.skeleton.find("左足首").unwrap();
        let centre = clip.skeleton.find("センター").unwrap();
        let (p0, p30) = (clip.world_positions(0), clip.world_positions(30));
        assert!(((p30[centre] - p0[centre]).y + 2.0 * METRES_PER_MMD_UNIT).abs() < 1e-4);
        assert!((p30[ankle] - p0[ankle]).length() < 0.005, "ankle moved {}", (p30[ankle] - p0[ankle]).length());
    }
}
