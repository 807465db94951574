//! Secondary motion for MMD models (issue 28 item 2, step 5): hair and skirt chains follow the
//! body with a lag, by a damped angular spring per bone instead of MMD's rigid-body physics.
//!
//! Which bones: those carrying a rigid body the model simulates (`RigidMode::Physics` or
//! `PhysicsWithBone`: hair, skirt, breasts, ribbons), else bones named for hair or skirt (髪,
//! スカート, hair, skirt) that are in no IK chain. Each such bone's world rotation is pulled
//! toward where the animation puts it (its animated local rotation under its parent's
//! *simulated* world rotation) with angular acceleration `stiffness · error − damping ·
//! velocity`, integrated at a fixed step of [`STEP_S`] whatever the clip's frame rate, so 30 and
//! 60 fps clips swing alike; a bone whose parent is a spring bone is also carried along by most
//! of its parent's turn ([`SpringParams::carry`]), so a chain swings on its root with some
//! follow-through instead of each bone lagging the one above (with which a 6-bone chain's tip
//! stood still through a quick head turn). Stiffness 1/s², damping 1/s and the carry are named
//! in [`SpringParams`]; the default is a little under critically damped (ζ = 0.8) with a 0.35 s
//! natural period and a carry of 0.8, so a lag shows and a chain settles within a second.
//! [`apply_springs`] runs over a whole clip; [`SpringFollower`] steps frame by frame from the
//! last drawn time, as the viewer and the video export draw.

use glam::{Quat, Vec3};

use crate::clip::Clip;
use crate::import::mmd_model::{MmdModel, RigidMode};

/// The integration step, seconds (240 Hz).
pub const STEP_S: f32 = 1.0 / 240.0;

/// The default [`SpringParams::carry`] (see there, and the module doc).
pub const DEFAULT_CARRY: f32 = 0.8;

/// The spring of each bone.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SpringParams {
    /// Angular acceleration per radian of error, 1/s² (ω₀²).
    pub stiffness_per_s2: f32,
    /// Angular deceleration per rad/s of velocity, 1/s (2ζω₀).
    pub damping_per_s: f32,
    /// How much of its spring parent's simulated turn a spring bone is carried along by each
    /// step, 0..1 (a chain's root, whose parent is not a spring, is not carried: it lags the
    /// body): 1 swings a chain as a whole on its root; 0 leaves each bone where it was in world
    /// space, so each lags its parent and a chain of n bones is a filter of order 2n whose tip
    /// hardly moves during a quick turn (Gene's 6-bone アホ毛 tip moved 0.0° during a 0.2 s, 60°
    /// head turn: all of its lag was the tip standing still).
    pub carry: f32,
}

impl Default for SpringParams {
    fn default() -> Self {
        // ω₀ = 2π / 0.35 s ≈ 18 rad/s; ζ = 0.8.
        let w0 = std::f32::consts::TAU / 0.35;
        SpringParams { stiffness_per_s2: w0 * w0, damping_per_s: 2.0 * 0.8 * w0, carry: DEFAULT_CARRY }
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

/// The simulated state of a skeleton's spring joints: each joint's world rotation and angular
/// velocity (world axes, rad/s). Joints that are not springs follow their animated rotation under
/// their parent's simulated one. One integrator for [`apply_springs`] (a whole clip) and
/// [`SpringFollower`] (frame by frame, as a viewer draws).
#[derive(Clone, Debug)]
struct Springs {
    parent: Vec<Option<usize>>,
    on: Vec<bool>,
    sim: Vec<Quat>,
    vel: Vec<Vec3>,
    /// Scratch: the simulated rotations at the start of a step, and the interpolated locals.
    before: Vec<Quat>,
    local: Vec<Quat>,
}

impl Springs {
    fn new(clip_skeleton: &crate::skeleton::Skeleton, joints: &[usize]) -> Springs {
        let n = clip_skeleton.len();
        let parent: Vec<Option<usize>> = clip_skeleton.joints.iter().enumerate().map(|(i, j)| j.parent.filter(|&p| p < i)).collect();
        let mut on = vec![false; n];
        for &j in joints {
            if j < n && parent[j].is_some() {
                on[j] = true;
            }
        }
        Springs { parent, on, sim: vec![Quat::IDENTITY; n], vel: vec![Vec3::ZERO; n], before: vec![Quat::IDENTITY; n], local: vec![Quat::IDENTITY; n] }
    }

    fn any(&self) -> bool {
        self.on.iter().any(|&x| x)
    }

    /// Every joint at its animated pose `rot` (local rotations), at rest.
    fn settle(&mut self, rot: &[Quat]) {
        for j in 0..self.sim.len().min(rot.len()) {
            self.sim[j] = (self.parent[j].map_or(Quat::IDENTITY, |p| self.sim[p]) * rot[j]).normalize();
            self.vel[j] = Vec3::ZERO;
        }
    }

    /// Advances `dt` seconds while the animated locals go from `a` to `b` (slerped), in equal
    /// steps of at most [`STEP_S`].
    fn advance(&mut self, a: &[Quat], b: &[Quat], dt: f32, params: SpringParams) {
        let n = self.sim.len().min(a.len()).min(b.len());
        if !(dt > 0.0) || !dt.is_finite() {
            return;
        }
        // (A hair under a whole number of steps: 1/30 s is 8 steps whether it came as 1/30 or
        // as the difference of two frame times.)
        let steps = (dt / STEP_S - 1e-3).ceil().clamp(1.0, 1.0e5) as usize;
        let h = dt / steps as f32;
        let carry = params.carry.clamp(0.0, 1.0);
        for s in 1..=steps {
            let t = s as f32 / steps as f32;
            for j in 0..n {
                self.local[j] = a[j].slerp(b[j], t);
            }
            self.before[..n].copy_from_slice(&self.sim[..n]);
            // Parents come before children (skeletons are topologically ordered).
            for j in 0..n {
                let pw = self.parent[j].map_or(Quat::IDENTITY, |p| self.sim[p]);
                let target = (pw * self.local[j]).normalize();
                if !self.on[j] {
                    self.sim[j] = target;
                    continue;
                }
                // Carried along by a spring parent's turn this step (a chain's root is not: it
                // is the hinge that lags the body).
                if let Some(p) = self.parent[j].filter(|&p| self.on[p]) {
                    let mut turn = self.sim[p] * self.before[p].inverse();
                    if turn.w < 0.0 {
                        turn = -turn;
                    }
                    self.sim[j] = (Quat::IDENTITY.slerp(turn, carry) * self.sim[j]).normalize();
                }
                let mut err = target * self.sim[j].inverse();
                if err.w < 0.0 {
                    err = -err;
                }
                let (axis, angle) = err.to_axis_angle();
                let e = if angle.is_finite() && axis.is_finite() { axis * angle } else { Vec3::ZERO };
                let v = self.vel[j];
                self.vel[j] = v + (params.stiffness_per_s2 * e - params.damping_per_s * v) * h;
                let turn = self.vel[j] * h;
                let q = if turn.length_squared() > 0.0 && turn.is_finite() { Quat::from_scaled_axis(turn) } else { Quat::IDENTITY };
                self.sim[j] = (q * self.sim[j]).normalize();
            }
        }
    }

    /// The local rotations of the simulated pose: `rot` (the animated locals) with each spring
    /// joint's replaced.
    fn write_locals(&self, rot: &mut [Quat]) {
        for j in 0..self.sim.len().min(rot.len()) {
            if self.on[j] {
                let pw = self.parent[j].map_or(Quat::IDENTITY, |p| self.sim[p]);
                rot[j] = (pw.inverse() * self.sim[j]).normalize();
            }
        }
    }
}

/// `clip` with the listed joints (clip skeleton joints) following by spring. The clip's
/// rotations are full local rotations (the MMD character's skeleton has identity rest
/// rotations); the other joints are as they were. A clip of one frame, or no joints, is returned
/// unchanged.
pub fn apply_springs(clip: &Clip, joints: &[usize], params: SpringParams) -> Clip {
    let n = clip.skeleton.len();
    let frames = clip.frame_count();
    let mut out = clip.clone();
    let mut springs = Springs::new(&clip.skeleton, joints);
    if frames < 2 || !springs.any() || !(clip.fps > 0.0) || clip.rotations.len() < frames * n {
        return out;
    }
    // Frame 0: at the animated pose, at rest.
    springs.settle(clip.frame_rotations(0));
    for f in 1..frames {
        springs.advance(clip.frame_rotations(f - 1), clip.frame_rotations(f), 1.0 / clip.fps, params);
        springs.write_locals(&mut out.rotations[f * n..(f + 1) * n]);
    }
    out
}

/// A gap between two drawn times (seconds) past which the follower does not step the springs
/// across it but starts again from the animated pose: a seek, a loop back to the start, a jump
/// along the song.
pub const MAX_GAP_S: f32 = 0.25;

/// The springs of one drawn figure, stepped frame by frame from the previous drawn time (the
/// viewer and the video export draw through it): each [`SpringFollower::pose`] samples the
/// clip at the new time and steps the springs from the last time to it. Time going back, or
/// forward by more than [`MAX_GAP_S`], puts every joint at its animated pose at rest (rather
/// than flinging the hair across the jump); the same time again gives the same pose.
#[derive(Clone, Debug)]
pub struct SpringFollower {
    springs: Springs,
    /// The last time drawn and the animated locals there.
    last: Option<(f32, Vec<Quat>)>,
    rot: Vec<Quat>,
    trans: Vec<Vec3>,
}

impl SpringFollower {
    /// A follower for clips on `skeleton` with the listed spring joints (indices in it).
    pub fn new(skeleton: &crate::skeleton::Skeleton, joints: &[usize]) -> SpringFollower {
        SpringFollower { springs: Springs::new(skeleton, joints), last: None, rot: Vec::new(), trans: Vec::new() }
    }

    /// Whether any joint follows by spring.
    pub fn has_springs(&self) -> bool {
        self.springs.any()
    }

    /// The time last posed (`None`: never, or just reset).
    pub fn last_time_secs(&self) -> Option<f32> {
        self.last.as_ref().map(|(t, _)| *t)
    }

    /// The pose last given by [`SpringFollower::pose`] (local rotations and translations).
    pub fn last_pose(&self) -> Option<(&[Quat], &[Vec3])> {
        self.last.as_ref().map(|_| (self.rot.as_slice(), self.trans.as_slice()))
    }

    /// Forgets the motion: the next pose starts at rest.
    pub fn reset(&mut self) {
        self.last = None;
    }

    /// `clip` at `time_secs` with the springs stepped to it: its local rotations (spring joints
    /// simulated) and translations, in the clip skeleton's order. A clip on another skeleton
    /// (other joint count) is sampled as it is.
    pub fn pose(&mut self, clip: &Clip, time_secs: f32, params: SpringParams) -> (&[Quat], &[Vec3]) {
        clip.sample_into(time_secs, &mut self.rot, &mut self.trans);
        if self.rot.len() != self.springs.sim.len() || !self.springs.any() || clip.frame_count() == 0 {
            return (&self.rot, &self.trans);
        }
        let time_secs = if time_secs.is_finite() { time_secs } else { 0.0 };
        match self.last.take() {
            Some((t0, prev)) if time_secs >= t0 && time_secs - t0 <= MAX_GAP_S => {
                self.springs.advance(&prev, &self.rot, time_secs - t0, params);
                self.last = Some((time_secs, prev));
            }
            other => {
                self.springs.settle(&self.rot);
                self.last = other.map(|(_, p)| (time_secs, p)).or_else(|| Some((time_secs, Vec::new())));
            }
        }
        if let Some((_, prev)) = self.last.as_mut() {
            prev.clear();
            prev.extend_from_slice(&self.rot);
        }
        self.springs.write_locals(&mut self.rot);
        (&self.rot, &self.trans)
    }
}
