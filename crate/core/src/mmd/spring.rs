//! Secondary motion for MMD models (issue 28 item 2, step 5): hair and skirt chains follow the
//! body with a lag, by a damped angular spring per bone instead of MMD's rigid-body physics.
//!
//! Which bones: those carrying a rigid body the model simulates (`RigidMode::Physics` or
//! `PhysicsWithBone`: hair, skirt, breasts, ribbons), else bones named for hair or skirt (髪,
//! スカート, hair, skirt) that are in no IK chain. Each such bone's world rotation is pulled
//! toward where the animation puts it (its animated local rotation under its parent's
//! *simulated* world rotation, so a chain swings as a whole) with angular acceleration
//! `stiffness · error − damping · velocity`, integrated at a fixed step of [`STEP_S`] whatever the
//! clip's frame rate, so 30 and 60 fps clips swing alike. Stiffness 1/s² and damping 1/s are
//! named in [`SpringParams`]; the default is a little under critically damped (ζ = 0.8) with a
//! 0.35 s natural period, so a lag shows and a chain of several bones (each lagging its
//! parent) settles within a second.

use glam::{Quat, Vec3};

use crate::clip::Clip;
use crate::import::mmd_model::{MmdModel, RigidMode};

/// The integration step, seconds (240 Hz).
pub const STEP_S: f32 = 1.0 / 240.0;

/// The spring of each bone.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SpringParams {
    /// Angular acceleration per radian of error, 1/s² (ω₀²).
    pub stiffness_per_s2: f32,
    /// Angular deceleration per rad/s of velocity, 1/s (2ζω₀).
    pub damping_per_s: f32,
}

impl Default for SpringParams {
    fn default() -> Self {
        // ω₀ = 2π / 0.35 s ≈ 18 rad/s; ζ = 0.8.
        let w0 = std::f32::consts::TAU / 0.35;
        SpringParams { stiffness_per_s2: w0 * w0, damping_per_s: 2.0 * 0.8 * w0 }
    }
}

/// Whether a bone name is one of hair or skirt (Japanese or English, as models name them).
pub fn is_hair_or_skirt(name: &str) -> bool {
    let lower = name.to_lowercase();
    name.contains('髪') || name.contains("スカート") || name.contains("ｽｶｰﾄ") || lower.contains("hair") || lower.contains("skirt")
}

/// The model bones that follow by spring (see the module doc), as model bone indices.
pub fn spring_bones(model: &MmdModel) -> Vec<usize> {
    let mut out: Vec<usize> = model
        .rigid_bodies
        .iter()
        .filter(|r| matches!(r.mode, RigidMode::Physics | RigidMode::PhysicsWithBone))
        .filter_map(|r| r.bone)
        .filter(|&b| b < model.bones.len())
        .collect();
    if out.is_empty() {
        let in_ik: std::collections::HashSet<usize> = model.bones.iter().filter_map(|b| b.ik.as_ref()).flat_map(|ik| ik.links.iter().map(|l| l.bone).chain([ik.target])).collect();
        out = (0..model.bones.len()).filter(|i| !in_ik.contains(i) && is_hair_or_skirt(&model.bones[*i].name)).collect();
    }
    out.sort_unstable();
    out.dedup();
    out
}

/// `clip` with the listed joints (clip skeleton joints) following by spring. The clip's
/// rotations are full local rotations (the MMD character's skeleton has identity rest
/// rotations); the other joints are as they were. A clip of one frame, or no joints, is returned
/// unchanged.
pub fn apply_springs(clip: &Clip, joints: &[usize], params: SpringParams) -> Clip {
    let n = clip.skeleton.len();
    let frames = clip.frame_count();
    let mut out = clip.clone();
    let mut on = vec![false; n];
    for &j in joints {
        if j < n && clip.skeleton.joints[j].parent.is_some() {
            on[j] = true;
        }
    }
    if frames < 2 || !on.iter().any(|&x| x) || !(clip.fps > 0.0) {
        return out;
    }
    let parent: Vec<Option<usize>> = clip.skeleton.joints.iter().map(|j| j.parent).collect();
    let frame_dt = 1.0 / clip.fps;
    let steps = (frame_dt / STEP_S).ceil().max(1.0) as usize;
    let h = frame_dt / steps as f32;
    // Simulated world rotations and angular velocities (world axes, rad/s) of spring joints.
    let world_at = |rot: &[Quat], sim: &[Quat], j: usize| -> Quat { parent[j].map_or(Quat::IDENTITY, |p| sim[p]) * rot[j] };
    let mut sim = vec![Quat::IDENTITY; n];
    let mut vel = vec![Vec3::ZERO; n];
    // Frame 0: at the animated pose, at rest.
    {
        let r = clip.frame_rotations(0);
        for j in 0..n {
            sim[j] = world_at(r, &sim, j).normalize();
        }
    }
    let mut local = vec![Quat::IDENTITY; n];
    for f in 1..frames {
        let (a, b) = (clip.frame_rotations(f - 1), clip.frame_rotations(f));
        for s in 1..=steps {
            let t = s as f32 / steps as f32;
            for j in 0..n {
                local[j] = a[j].slerp(b[j], t);
            }
            // Parents come before children (skeletons are topologically ordered).
            for j in 0..n {
                let target = world_at(&local, &sim, j).normalize();
                if !on[j] {
                    sim[j] = target;
                    continue;
                }
                let mut err = target * sim[j].inverse();
                if err.w < 0.0 {
                    err = -err;
                }
                let (axis, angle) = err.to_axis_angle();
                let e = if angle.is_finite() && axis.is_finite() { axis * angle } else { Vec3::ZERO };
                let v = vel[j];
                vel[j] = v + (params.stiffness_per_s2 * e - params.damping_per_s * v) * h;
                let turn = vel[j] * h;
                let q = if turn.length_squared() > 0.0 { Quat::from_scaled_axis(turn) } else { Quat::IDENTITY };
                sim[j] = (q * sim[j]).normalize();
            }
        }
        let rot = &mut out.rotations[f * n..(f + 1) * n];
        for j in 0..n {
            if on[j] {
                let pw = parent[j].map_or(Quat::IDENTITY, |p| sim[p]);
                rot[j] = (pw.inverse() * sim[j]).normalize();
            }
        }
    }
    out
}
