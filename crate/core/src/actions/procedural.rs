//! The built-in everyday actions, authored procedurally on the canonical skeleton.
//!
//! Each action is a function of time giving a [`Pose`] (a few anatomical angles per joint:
//! hip flexion, knee bend, arm elevation...), either interpolated between key poses with a
//! Catmull-Rom spline (ease in and out at both ends) or written as a gait cycle (walk, run).
//! Secondary motion comes on top: breathing in the chest, the head and the distal arm joints
//! lagging their key poses slightly (overlapping action), and the torso answering the arms.
//! [`build_clip`] turns the pose function into a clip and puts it on the floor: the root
//! height keeps the lowest sole of the feet in contact at the floor, and the root's ground
//! position keeps a planted foot where it landed, so the feet do not slide; frames where no
//! foot is in contact follow a ballistic parabola.

use crate::fmath;
use std::f32::consts::{FRAC_PI_2, PI, TAU};
use std::sync::Arc;

use glam::{EulerRot, Quat, Vec3};

use crate::canon::builtin::canonical_skeleton;
use crate::clip::{Clip, TranslationTrack};
use crate::canon::humanoid::{Canon, CANON_COUNT};
use crate::skeleton::Skeleton;

/// Frame rate of the built-in actions.
pub const ACTION_FPS: f32 = 60.0;
/// Height of the toe joint above the floor when the foot is flat: the canonical body's, one home.
pub use crate::canon::SOLE_HEIGHT;
const GRAVITY: f32 = 9.81;

/// Number of scalar parameters of a [`Pose`].
pub const POSE_LEN: usize = 33;

/// Indices into a [`Pose`]. Angles in radians. Sides: 0 = left, 1 = right.
pub mod idx {
    /// Whole-body heading about Y; positive turns the figure to its left.
    pub const YAW: usize = 0;
    /// Pelvis tilt forward (+) and roll.
    pub const HIPS_PITCH: usize = 1;
    pub const HIPS_ROLL: usize = 2;
    /// Spine and chest: pitch forward (+), yaw to the left (+), roll.
    pub const SPINE: usize = 3;
    pub const CHEST: usize = 6;
    /// Neck pitch forward (+).
    pub const NECK: usize = 9;
    /// Head pitch (+ nods down), yaw, roll.
    pub const HEAD: usize = 10;
    /// First arm parameter; arm `side` starts at `ARM + 6 * side`.
    pub const ARM: usize = 13;
    /// Collarbone raise.
    pub const CLAV: usize = 0;
    /// Elevation of the upper arm from hanging down (0) through horizontal (π/2) to overhead (π).
    pub const ABDUCT: usize = 1;
    /// Forward swing of the upper arm (+ forward).
    pub const FLEX: usize = 2;
    /// Elbow bend (0 straight).
    pub const ELBOW: usize = 3;
    /// Plane of the elbow bend: 0 forward, + toward the side / up, − toward the body's midline.
    pub const ELBOW_PLANE: usize = 4;
    /// Wrist bend.
    pub const WRIST: usize = 5;
    /// First leg parameter; leg `side` starts at `LEG + 4 * side`.
    pub const LEG: usize = 25;
    /// Thigh forward (+).
    pub const HIP_FLEX: usize = 0;
    /// Thigh out to the side (+).
    pub const HIP_ABDUCT: usize = 1;
    /// Knee bend (+).
    pub const KNEE: usize = 2;
    /// Foot pointing down (+) relative to flat on the floor.
    pub const ANKLE: usize = 3;
}

/// An anatomical pose: [`POSE_LEN`] angles addressed through [`idx`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Pose(pub [f32; POSE_LEN]);

impl Default for Pose {
    fn default() -> Self {
        Pose::standing()
    }
}

impl Pose {
    /// Relaxed standing: arms down by the sides, knees soft.
    pub fn standing() -> Pose {
        let mut p = Pose([0.0; POSE_LEN]);
        for s in 0..2 {
            p.set_arm(s, idx::ABDUCT, 0.12);
            p.set_arm(s, idx::ELBOW, 0.15);
            p.set_leg(s, idx::KNEE, 0.04);
            p.set_leg(s, idx::HIP_FLEX, 0.02);
        }
        p
    }

    pub fn arm(&self, side: usize, k: usize) -> f32 {
        self.0[idx::ARM + 6 * side + k]
    }
    pub fn set_arm(&mut self, side: usize, k: usize, v: f32) {
        self.0[idx::ARM + 6 * side + k] = v;
    }
    pub fn leg(&self, side: usize, k: usize) -> f32 {
        self.0[idx::LEG + 4 * side + k]
    }
    pub fn set_leg(&mut self, side: usize, k: usize, v: f32) {
        self.0[idx::LEG + 4 * side + k] = v;
    }

    /// Builder-style: one arm parameter.
    pub fn with_arm(mut self, side: usize, k: usize, v: f32) -> Pose {
        self.set_arm(side, k, v);
        self
    }
    /// Builder-style: one leg parameter.
    pub fn with_leg(mut self, side: usize, k: usize, v: f32) -> Pose {
        self.set_leg(side, k, v);
        self
    }
    /// Builder-style: any parameter.
    pub fn with(mut self, i: usize, v: f32) -> Pose {
        self.0[i] = v;
        self
    }

    /// Local rotations of the 21 canonical joints, in [`Canon::ALL`] order.
    pub fn to_rotations(&self) -> [Quat; CANON_COUNT] {
        use idx::*;
        use Canon::*;
        let p = &self.0;
        let mut r = [Quat::IDENTITY; CANON_COUNT];
        r[Hips.index()] = Quat::from_euler(EulerRot::YXZ, p[YAW], p[HIPS_PITCH], p[HIPS_ROLL]);
        r[Spine.index()] = Quat::from_euler(EulerRot::YXZ, p[SPINE + 1], p[SPINE], p[SPINE + 2]);
        r[Chest.index()] = Quat::from_euler(EulerRot::YXZ, p[CHEST + 1], p[CHEST], p[CHEST + 2]);
        r[Neck.index()] = Quat::from_rotation_x(p[NECK]);
        r[Head.index()] = Quat::from_euler(EulerRot::YXZ, p[HEAD + 1], p[HEAD], p[HEAD + 2]);
        let arms = [(LeftShoulder, LeftUpperArm, LeftForearm, LeftHand), (RightShoulder, RightUpperArm, RightForearm, RightHand)];
        for (side, (sh, ua, fa, ha)) in arms.into_iter().enumerate() {
            // s = +1 for the left arm (rest along +X), −1 for the right (rest along −X).
            let s = if side == 0 { 1.0 } else { -1.0 };
            r[sh.index()] = Quat::from_rotation_z(s * self.arm(side, CLAV));
            r[ua.index()] = Quat::from_rotation_x(-self.arm(side, FLEX)) * Quat::from_rotation_z(s * (self.arm(side, ABDUCT) - FRAC_PI_2));
            r[fa.index()] = Quat::from_rotation_x(-self.arm(side, ELBOW_PLANE)) * Quat::from_rotation_y(-s * self.arm(side, ELBOW));
            r[ha.index()] = Quat::from_rotation_z(s * self.arm(side, WRIST));
        }
        let legs = [(LeftUpperLeg, LeftLowerLeg, LeftFoot), (RightUpperLeg, RightLowerLeg, RightFoot)];
        for (side, (ul, ll, ft)) in legs.into_iter().enumerate() {
            let s = if side == 0 { 1.0 } else { -1.0 };
            let flex = self.leg(side, HIP_FLEX);
            let knee = self.leg(side, KNEE);
            r[ul.index()] = Quat::from_rotation_z(s * self.leg(side, HIP_ABDUCT)) * Quat::from_rotation_x(-flex);
            r[ll.index()] = Quat::from_rotation_x(knee);
            // Flat on the floor when the ankle parameter is 0, whatever the hip and knee do.
            r[ft.index()] = Quat::from_rotation_x(flex - knee + self.leg(side, ANKLE));
        }
        r
    }
}

/// Smoothstep 0..1 with zero slope at both ends: the motion kernel's one easing curve.
pub use crate::motion::smoothstep as smooth;

/// Key poses interpolated with a Catmull-Rom spline (zero slope at the first and last key).
#[derive(Clone, Debug)]
pub struct KeyPoses {
    keys: Vec<(f32, Pose)>,
}

impl KeyPoses {
    /// Keys must be in increasing time; at least one.
    pub fn new(keys: Vec<(f32, Pose)>) -> KeyPoses {
        KeyPoses { keys }
    }

    pub fn duration_secs(&self) -> f32 {
        self.keys.last().map(|k| k.0).unwrap_or(0.0)
    }

    /// The pose at `time_secs` (clamped to the keys).
    pub fn sample(&self, time_secs: f32) -> Pose {
        let k = &self.keys;
        let Some(first) = k.first() else { return Pose::standing() };
        if k.len() == 1 || time_secs <= first.0 {
            return first.1;
        }
        let last = k.len() - 1;
        if time_secs >= k[last].0 {
            return k[last].1;
        }
        let i = k.iter().rposition(|(t, _)| *t <= time_secs).unwrap_or(0).min(last - 1);
        let (t0, p0) = k[i];
        let (t1, p1) = k[i + 1];
        let h = (t1 - t0).max(1e-6);
        let u = ((time_secs - t0) / h).clamp(0.0, 1.0);
        let tangent = |j: usize| -> [f32; POSE_LEN] {
            let mut m = [0.0; POSE_LEN];
            if j == 0 || j == last {
                return m;
            }
            let (ta, pa) = k[j - 1];
            let (tb, pb) = k[j + 1];
            let d = (tb - ta).max(1e-6);
            for (n, v) in m.iter_mut().enumerate() {
                *v = (pb.0[n] - pa.0[n]) / d;
            }
            m
        };
        let (m0, m1) = (tangent(i), tangent(i + 1));
        let (u2, u3) = (u * u, u * u * u);
        let h00 = 2.0 * u3 - 3.0 * u2 + 1.0;
        let h10 = u3 - 2.0 * u2 + u;
        let h01 = -2.0 * u3 + 3.0 * u2;
        let h11 = u3 - u2;
        let mut out = [0.0; POSE_LEN];
        for n in 0..POSE_LEN {
            out[n] = h00 * p0.0[n] + h10 * h * m0[n] + h01 * p1.0[n] + h11 * h * m1[n];
        }
        Pose(out)
    }
}

/// Adds the secondary motion every authored action gets: breathing, and the head, forearms
/// and hands lagging their key poses by a few hundredths of a second.
fn with_secondary(time_secs: f32, pose_at: &dyn Fn(f32) -> Pose) -> Pose {
    let now = pose_at(time_secs);
    let late = pose_at((time_secs - 0.07).max(0.0));
    let mut p = now;
    let lag = 0.45;
    for i in [idx::HEAD, idx::HEAD + 1, idx::HEAD + 2, idx::NECK] {
        p.0[i] = now.0[i] + lag * (late.0[i] - now.0[i]);
    }
    for s in 0..2 {
        for k in [idx::ELBOW, idx::WRIST] {
            let v = now.arm(s, k) + lag * (late.arm(s, k) - now.arm(s, k));
            p.set_arm(s, k, v);
        }
    }
    let breath = fmath::sin(time_secs * TAU / 3.6);
    p.0[idx::CHEST] += 0.012 * breath;
    p.0[idx::HEAD] -= 0.008 * breath;
    p
}

/// Turns a pose function into a clip on the canonical skeleton, put on the floor.
///
/// `contacts(t)` says which feet (left, right) touch the floor at `t`. The root height keeps
/// the lowest sole of the touching feet at the floor ([`SOLE_HEIGHT`] for the toe joint); the
/// ground position keeps the first-planted touching foot where it landed. When no foot
/// touches, the root follows a ballistic parabola between take-off and landing and keeps its
/// horizontal velocity. `frames` frames at [`ACTION_FPS`]; returns the clip and how far the
/// root moves on the ground from the first frame to one frame past the end (the advance of
/// one cycle, for cyclic actions). `cyclic`:
/// the clip repeats, so smoothing wraps around.
pub fn build_clip(name: &str, frames: usize, cyclic: bool, pose_at: &dyn Fn(f32) -> Pose, contacts: &dyn Fn(f32) -> [bool; 2]) -> (Clip, Vec3) {
    let skeleton = Arc::new(canonical_skeleton());
    let fps = ACTION_FPS;
    let total = frames + 1;
    let mut rotations = Vec::with_capacity(total * CANON_COUNT);
    let mut sole = Vec::with_capacity(total); // relative sole heights (left, right)
    let mut ankle = Vec::with_capacity(total); // relative ankle positions
    let mut touching = Vec::with_capacity(total);
    for f in 0..total {
        let t = f as f32 / fps;
        let pose = with_secondary(t, pose_at);
        let r = pose.to_rotations();
        let rel = relative_positions(&skeleton, &r);
        let lf = rel[Canon::LeftFoot.index()];
        let rf = rel[Canon::RightFoot.index()];
        let lt = rel[Canon::LeftToe.index()];
        let rt = rel[Canon::RightToe.index()];
        // The heel sits a little below the ankle joint; the toe joint at sole height.
        sole.push([(lf.y - 0.06).min(lt.y - SOLE_HEIGHT), (rf.y - 0.06).min(rt.y - SOLE_HEIGHT)]);
        ankle.push([lf, rf]);
        touching.push(contacts(t));
        rotations.extend_from_slice(&r);
    }
    // Heights of the frames with a contact; parabolas in between.
    // On the ground, the lowest sole of either foot sits on the floor: a swing foot coming
    // down takes the weight smoothly instead of sinking through the floor before it lands.
    let mut y: Vec<Option<f32>> = (0..total)
        .map(|f| {
            let c = touching[f];
            (c[0] || c[1]).then(|| -sole[f][0].min(sole[f][1]))
        })
        .collect();
    let mut f = 0;
    while f < total {
        if y[f].is_some() {
            f += 1;
            continue;
        }
        let start = f;
        while f < total && y[f].is_none() {
            f += 1;
        }
        // Flight from start-1 to f.
        let y0 = if start > 0 { y[start - 1].unwrap_or(0.95) } else { y[f.min(total - 1)].unwrap_or(0.95) };
        let y1 = if f < total { y[f].unwrap_or(y0) } else { y0 };
        let t0 = start as f32 - 1.0;
        let t1 = f as f32;
        for (g, v) in y.iter_mut().enumerate().take(f).skip(start) {
            let u = (g as f32 - t0) / (t1 - t0);
            let (a, b) = ((g as f32 - t0) / fps, (t1 - g as f32) / fps);
            *v = Some(y0 + (y1 - y0) * u + 0.5 * GRAVITY * a * b);
        }
    }
    // A light smoothing of the height (±4 frames, wrapping for cycles) takes the kinks out
    // of weight transfers; the feet move by millimetres.
    let raw_y: Vec<f32> = y.iter().map(|v| v.unwrap_or(0.95)).collect();
    let half = 4usize;
    let y: Vec<Option<f32>> = (0..total)
        .map(|f| {
            let mut sum = 0.0;
            let mut n = 0.0;
            for d in 0..=2 * half {
                let g = f as i64 + d as i64 - half as i64;
                let g = if cyclic { g.rem_euclid(frames.max(1) as i64) as usize } else { g.clamp(0, total as i64 - 1) as usize };
                // Symmetric triangle weights.
                let w = (half + 1 - (d as i64 - half as i64).unsigned_abs() as usize) as f32;
                sum += w * raw_y[g];
                n += w;
            }
            Some(sum / n)
        })
        .collect();
    // Ground positions: keep the first-planted foot still.
    let mut root = Vec::with_capacity(total);
    let mut anchor: [Option<Vec3>; 2] = [None, None];
    let mut primary: Option<usize> = None;
    let mut prev = Vec3::ZERO;
    let mut vel = Vec3::ZERO;
    let mut recent: Vec<Vec3> = Vec::with_capacity(7);
    for f in 0..total {
        let c = touching[f];
        for s in 0..2 {
            if !c[s] {
                anchor[s] = None;
            } else if anchor[s].is_none() {
                // Lands where the root estimate (previous position plus velocity) puts it.
                let guess = if f == 0 { Vec3::ZERO } else { prev + vel };
                anchor[s] = Some(guess + Vec3::new(ankle[f][s].x, 0.0, ankle[f][s].z));
            }
        }
        if primary.is_some_and(|s| !c[s]) {
            primary = None;
        }
        // The foot that just landed carries the body from now on (the other is about to
        // push off and is held in place by IK below).
        if let Some(s) = (0..2).find(|&s| c[s] && (f == 0 || !touching[f - 1][s])) {
            if f > 0 || primary.is_none() {
                primary = Some(s);
            }
        }
        if primary.is_none() {
            primary = (0..2).find(|&s| c[s]);
        }
        let grounded = primary.and_then(|s| anchor[s].map(|a| (a, s)));
        let xz = match grounded {
            Some((a, s)) => Vec3::new(a.x - ankle[f][s].x, 0.0, a.z - ankle[f][s].z),
            None => prev + vel,
        };
        // In flight the body keeps the mean ground speed of its last tenth of a second on
        // the floor (one frame's speed would carry the wobble of a push-off).
        if f > 0 && grounded.is_some() {
            recent.push(xz - prev);
            if recent.len() > 6 {
                recent.remove(0);
            }
            vel = recent.iter().copied().sum::<Vec3>() / recent.len() as f32;
        }
        prev = xz;
        root.push(Vec3::new(xz.x, y[f].unwrap_or(0.95) + SOLE_HEIGHT, xz.z));
    }
    let next = root.pop().unwrap_or(Vec3::ZERO);
    let clip_origin = root.first().copied().unwrap_or(Vec3::ZERO);
    rotations.truncate(frames * CANON_COUNT);
    let mut clip = Clip {
        name: name.to_string(),
        source: "built-in".into(),
        fps,
        skeleton,
        rotations,
        translations: vec![TranslationTrack { joint: 0, values: root }],
    };
    // The root follows one planted foot; a second planted foot (double support) is held
    // where it landed by two-bone IK and released smoothly once it lifts.
    touching.truncate(frames);
    crate::actions::join::lock_feet(&mut clip, &touching, 0, frames);
    (clip, Vec3::new(next.x - clip_origin.x, 0.0, next.z - clip_origin.z))
}

/// Joint positions of a pose with the root at the origin.
fn relative_positions(skeleton: &Skeleton, local: &[Quat]) -> Vec<Vec3> {
    std::mem::take(&mut crate::motion::WorldPose::new().of_rotations(skeleton, local, Vec3::ZERO).positions)
}

fn frames_for(duration_secs: f32) -> usize {
    (duration_secs * ACTION_FPS).round().max(2.0) as usize
}

/// Thigh and shin lengths of the canonical skeleton, metres.
const THIGH: f32 = 0.42;
const SHIN: f32 = 0.40;

/// Gait parameters of a walk or run cycle.
struct Gait {
    cycle_secs: f32,
    /// Fraction of the cycle a foot is on the ground.
    stance: f32,
    flex_fwd: f32,
    flex_back: f32,
    knee_stance: f32,
    knee_swing: f32,
    arm_swing: f32,
    elbow: f32,
    lean: f32,
}

fn gait_leg(g: &Gait, phase: f32) -> (f32, f32, f32, bool) {
    let p = phase.rem_euclid(1.0);
    if p < g.stance {
        let u = p / g.stance;
        let knee = 0.05 + g.knee_stance * fmath::sin(PI * u);
        // Hip flexion such that the ankle moves back under the hip at a constant speed: the
        // body then travels at an even pace over a planted foot.
        let reach = |flex: f32, knee: f32| THIGH * fmath::sin(flex) + SHIN * fmath::sin(flex - knee);
        let (z0, z1) = (reach(g.flex_fwd, 0.05), reach(g.flex_back, 0.05));
        let want = z0 + (z1 - z0) * u;
        let (mut lo, mut hi) = (g.flex_back - 0.3, g.flex_fwd + 0.3);
        for _ in 0..30 {
            let mid = 0.5 * (lo + hi);
            if reach(mid, knee) > want {
                hi = mid;
            } else {
                lo = mid;
            }
        }
        let flex = 0.5 * (lo + hi);
        let ankle = 0.35 * smooth((u - 0.75) / 0.25) - 0.12 * (1.0 - smooth(u / 0.12));
        (flex, knee, ankle, true)
    } else {
        let u = (p - g.stance) / (1.0 - g.stance);
        let flex = g.flex_back + (g.flex_fwd - g.flex_back) * smooth(u);
        let knee = 0.05 + g.knee_swing * fmath::sin(PI * fmath::powf(u, 0.8));
        let ankle = 0.35 * (1.0 - smooth(u / 0.35)) - 0.12 * smooth((u - 0.8) / 0.2);
        (flex, knee, ankle, false)
    }
}

fn gait_pose(g: &Gait, time_secs: f32) -> Pose {
    let phase = time_secs / g.cycle_secs;
    let mut p = Pose::standing();
    let mut flexes = [0.0; 2];
    for s in 0..2 {
        let (flex, knee, ankle, _) = gait_leg(g, phase + 0.5 * s as f32);
        p.set_leg(s, idx::HIP_FLEX, flex);
        p.set_leg(s, idx::KNEE, knee);
        p.set_leg(s, idx::ANKLE, ankle);
        flexes[s] = flex;
    }
    let mid = 0.5 * (g.flex_fwd + g.flex_back);
    for s in 0..2 {
        // Arms swing against the leg on the same side.
        let other = flexes[1 - s] - mid;
        p.set_arm(s, idx::FLEX, g.arm_swing * other / (g.flex_fwd - g.flex_back).max(0.1) * 2.0 + 0.05);
        p.set_arm(s, idx::ELBOW, g.elbow + 0.15 * other.max(0.0));
        p.set_arm(s, idx::ABDUCT, 0.12);
    }
    // Pelvis turns with the forward leg, the chest counter-rotates, the head stays level.
    let twist = (flexes[0] - flexes[1]) * 0.25;
    p.0[idx::YAW] = -twist;
    p.0[idx::CHEST + 1] = 1.6 * twist;
    p.0[idx::HEAD + 1] = -0.4 * twist;
    p.0[idx::SPINE] = g.lean;
    p.0[idx::HEAD] = -g.lean * 0.8;
    p.0[idx::HIPS_ROLL] = 0.04 * fmath::sin(TAU * phase);
    p
}

fn gait_contacts(g: &Gait, time_secs: f32) -> [bool; 2] {
    let phase = time_secs / g.cycle_secs;
    [gait_leg(g, phase).3, gait_leg(g, phase + 0.5).3]
}

const WALK: Gait = Gait { cycle_secs: 1.1, stance: 0.6, flex_fwd: 0.36, flex_back: -0.26, knee_stance: 0.12, knee_swing: 0.95, arm_swing: 0.28, elbow: 0.25, lean: 0.03 };
const RUN: Gait = Gait { cycle_secs: 0.7, stance: 0.38, flex_fwd: 0.42, flex_back: -0.5, knee_stance: 0.45, knee_swing: 1.75, arm_swing: 0.6, elbow: 1.45, lean: 0.14 };

/// One built-in action: its clip, tags in both languages, the body part it mainly moves
/// (its switched part in a Composition), and for cycles the root advance of one cycle.
pub struct Authored {
    pub clip: Clip,
    pub tags: Vec<String>,
    pub part: Option<crate::actions::BodyPart>,
    pub cycle_advance: Option<Vec3>,
}

fn tags(list: &[&str]) -> Vec<String> {
    list.iter().map(|s| s.to_string()).collect()
}

fn keyed(name: &str, keys: Vec<(f32, Pose)>, contacts: &dyn Fn(f32) -> [bool; 2]) -> Clip {
    let kp = KeyPoses::new(keys);
    let frames = frames_for(kp.duration_secs());
    build_clip(name, frames, false, &|t| kp.sample(t), contacts).0
}

const BOTH: fn(f32) -> [bool; 2] = |_| [true, true];

fn gait(name: &str, g: &Gait) -> (Clip, Vec3) {
    let frames = frames_for(g.cycle_secs);
    build_clip(name, frames, true, &|t| gait_pose(g, t), &|t| gait_contacts(g, t))
}

fn wave(side: usize) -> Clip {
    let st = Pose::standing();
    // Upper arm up to the side, forearm up; the forearm swings in the frontal plane and the
    // torso answers each swing.
    let up = |swing: f32| {
        let s = if side == 0 { 1.0 } else { -1.0 };
        st.with_arm(side, idx::ABDUCT, 1.4)
            .with_arm(side, idx::FLEX, 0.25)
            .with_arm(side, idx::ELBOW, 1.5 + swing)
            .with_arm(side, idx::ELBOW_PLANE, 1.45)
            .with_arm(side, idx::CLAV, 0.12)
            .with_arm(side, idx::WRIST, -0.3 * swing)
            .with(idx::CHEST + 2, -s * (0.05 + 0.05 * swing))
            .with(idx::SPINE + 2, -s * 0.03 * swing)
            .with(idx::HIPS_ROLL, s * 0.025 * swing)
            .with(idx::CHEST + 1, s * 0.04 * swing)
            .with(idx::HEAD + 2, s * 0.05 * swing)
    };
    let mut keys = vec![(0.0, st), (0.45, up(0.0))];
    let mut t = 0.45;
    for k in 0..6 {
        t += 0.22;
        keys.push((t, up(if k % 2 == 0 { -0.45 } else { 0.35 })));
    }
    keys.push((t + 0.25, up(0.0)));
    keys.push((t + 0.75, st));
    let name = if side == 0 { "wave left hand" } else { "wave right hand" };
    keyed(name, keys, &BOTH)
}

/// All built-in actions, in a fixed order.
pub fn builtin_actions() -> Vec<Authored> {
    let st = Pose::standing();
    let mut out = Vec::new();
    let (walk, walk_adv) = gait("walk", &WALK);
    out.push(Authored { clip: walk, tags: tags(&["walk", "歩く", "locomotion", "cycle"]), part: None, cycle_advance: Some(walk_adv) });
    let (run, run_adv) = gait("run", &RUN);
    out.push(Authored { clip: run, tags: tags(&["run", "走る", "locomotion", "cycle"]), part: None, cycle_advance: Some(run_adv) });

    // Kick with the right leg: wind up, swing through, follow through, set down.
    fn plant(p: Pose) -> Pose {
        p.with_leg(0, idx::KNEE, 0.18).with_leg(0, idx::HIP_FLEX, 0.09)
    }
    let kick = keyed(
        "kick",
        vec![
            (0.0, st),
            (0.3, plant(st).with_leg(1, idx::HIP_FLEX, -0.35).with_leg(1, idx::KNEE, 1.1).with_arm(0, idx::FLEX, 0.4).with_arm(1, idx::FLEX, -0.3).with_arm(0, idx::ABDUCT, 0.4).with_arm(1, idx::ABDUCT, 0.4).with(idx::SPINE, -0.05)),
            (0.55, plant(st).with_leg(1, idx::HIP_FLEX, 1.25).with_leg(1, idx::KNEE, 0.1).with_leg(1, idx::ANKLE, 0.5).with_arm(0, idx::FLEX, -0.4).with_arm(1, idx::FLEX, 0.35).with_arm(0, idx::ABDUCT, 0.5).with_arm(1, idx::ABDUCT, 0.5).with(idx::SPINE, -0.12)),
            (0.75, plant(st).with_leg(1, idx::HIP_FLEX, 0.8).with_leg(1, idx::KNEE, 0.7).with(idx::SPINE, 0.02)),
            (1.05, st.with_leg(1, idx::HIP_FLEX, 0.1).with_leg(1, idx::KNEE, 0.12)),
            (1.35, st),
        ],
        &|t| [true, !(0.12..1.12).contains(&t)],
    );
    out.push(Authored { clip: kick, tags: tags(&["kick", "蹴る", "leg"]), part: Some(crate::actions::BodyPart::RightLeg), cycle_advance: None });

    // Jump: crouch with arms back, take off, tuck, land, absorb, stand.
    fn crouch(k: f32) -> Pose {
        Pose::standing().with_leg(0, idx::HIP_FLEX, 0.8 * k).with_leg(1, idx::HIP_FLEX, 0.8 * k).with_leg(0, idx::KNEE, 1.3 * k).with_leg(1, idx::KNEE, 1.3 * k).with(idx::SPINE, 0.35 * k)
    }
    let jump = keyed(
        "jump",
        vec![
            (0.0, st),
            (0.4, crouch(1.0).with_arm(0, idx::FLEX, -0.7).with_arm(1, idx::FLEX, -0.7)),
            (0.58, st.with_leg(0, idx::ANKLE, 0.5).with_leg(1, idx::ANKLE, 0.5).with_arm(0, idx::ABDUCT, 2.4).with_arm(1, idx::ABDUCT, 2.4).with_arm(0, idx::FLEX, 0.6).with_arm(1, idx::FLEX, 0.6)),
            (0.78, crouch(0.35).with_arm(0, idx::ABDUCT, 2.2).with_arm(1, idx::ABDUCT, 2.2)),
            (0.98, st.with_leg(0, idx::ANKLE, 0.2).with_leg(1, idx::ANKLE, 0.2).with_arm(0, idx::ABDUCT, 1.2).with_arm(1, idx::ABDUCT, 1.2)),
            (1.15, crouch(0.7).with_arm(0, idx::ABDUCT, 0.6).with_arm(1, idx::ABDUCT, 0.6)),
            (1.7, st),
        ],
        &|t| {
            let air = (0.6..1.0).contains(&t);
            [!air, !air]
        },
    );
    out.push(Authored { clip: jump, tags: tags(&["jump", "跳ぶ", "ジャンプ"]), part: None, cycle_advance: None });

    out.push(Authored { clip: wave(1), tags: tags(&["wave", "right", "手を振る", "右手"]), part: Some(crate::actions::BodyPart::RightArm), cycle_advance: None });
    out.push(Authored { clip: wave(0), tags: tags(&["wave", "left", "手を振る", "左手"]), part: Some(crate::actions::BodyPart::LeftArm), cycle_advance: None });

    // Clap: hands together in front of the chest three times.
    fn open(p: Pose) -> Pose {
        let mut p = p;
        for s in 0..2 {
            p = p.with_arm(s, idx::FLEX, 0.75).with_arm(s, idx::ELBOW, 1.35).with_arm(s, idx::ELBOW_PLANE, 0.3).with_arm(s, idx::ABDUCT, 0.45);
        }
        p
    }
    fn shut(p: Pose) -> Pose {
        let mut p = p;
        for s in 0..2 {
            p = p.with_arm(s, idx::FLEX, 0.95).with_arm(s, idx::ELBOW, 1.5).with_arm(s, idx::ELBOW_PLANE, -1.25).with_arm(s, idx::ABDUCT, 0.0);
        }
        p.with(idx::HEAD, 0.08)
    }
    let mut keys = vec![(0.0, st), (0.35, open(st))];
    for k in 0..3 {
        let t0 = 0.35 + 0.42 * k as f32;
        keys.push((t0 + 0.2, shut(st)));
        keys.push((t0 + 0.42, open(st)));
    }
    let t_end = keys.last().map(|k| k.0).unwrap_or(0.0);
    keys.push((t_end + 0.4, st));
    out.push(Authored { clip: keyed("clap", keys, &BOTH), tags: tags(&["clap", "拍手", "手を叩く"]), part: Some(crate::actions::BodyPart::BothArms), cycle_advance: None });

    // Rejoice: both arms thrown up, two little hops, arms shaking.
    fn arms_up(p: Pose, shake: f32) -> Pose {
        let mut p = p;
        for s in 0..2 {
            p = p.with_arm(s, idx::ABDUCT, 2.55 + shake).with_arm(s, idx::FLEX, 0.35).with_arm(s, idx::ELBOW, 0.3 - shake).with_arm(s, idx::ELBOW_PLANE, 1.2);
        }
        p.with(idx::HEAD, -0.25).with(idx::CHEST, -0.1)
    }
    let rejoice = keyed(
        "rejoice",
        vec![
            (0.0, st),
            (0.3, arms_up(crouch(0.45), 0.0)),
            (0.5, arms_up(st.with_leg(0, idx::ANKLE, 0.4).with_leg(1, idx::ANKLE, 0.4), 0.15)),
            (0.75, arms_up(crouch(0.45), -0.1)),
            (0.95, arms_up(st.with_leg(0, idx::ANKLE, 0.4).with_leg(1, idx::ANKLE, 0.4), 0.15)),
            (1.2, arms_up(crouch(0.3), 0.0)),
            (1.5, arms_up(st, 0.1)),
            (2.1, st),
        ],
        &|t| {
            let air = (0.45..0.65).contains(&t) || (0.9..1.1).contains(&t);
            [!air, !air]
        },
    );
    out.push(Authored { clip: rejoice, tags: tags(&["rejoice", "cheer", "celebrate", "喜ぶ", "happy"]), part: None, cycle_advance: None });

    // Gutsy pose: right fist pulled down hard by the side, knees and chest crunch.
    fn fist(p: Pose, k: f32) -> Pose {
        p.with_arm(1, idx::FLEX, 0.4 - 0.35 * k)
            .with_arm(1, idx::ELBOW, 2.2 + 0.3 * k)
            .with_arm(1, idx::ABDUCT, 0.35 - 0.2 * k)
            .with_arm(1, idx::ELBOW_PLANE, -0.2)
            .with_arm(1, idx::WRIST, 0.3)
            .with(idx::CHEST, 0.04 + 0.16 * k)
            .with(idx::HEAD, 0.1 * k)
            .with_leg(0, idx::KNEE, 0.04 + 0.3 * k)
            .with_leg(1, idx::KNEE, 0.04 + 0.3 * k)
            .with_leg(0, idx::HIP_FLEX, 0.02 + 0.15 * k)
            .with_leg(1, idx::HIP_FLEX, 0.02 + 0.15 * k)
    }
    let guts = keyed("gutsy pose", vec![(0.0, st), (0.35, fist(st, 0.0)), (0.55, fist(st, 1.0)), (0.75, fist(st, 0.75)), (0.9, fist(st, 1.0)), (1.5, fist(st, 0.85)), (2.0, st)], &BOTH);
    out.push(Authored { clip: guts, tags: tags(&["gutsy pose", "fist pump", "ガッツポーズ", "celebrate"]), part: Some(crate::actions::BodyPart::RightArm), cycle_advance: None });

    // Turn around (180° to the left) in two steps: pivot on the left foot, then the right.
    let turn = keyed(
        "turn",
        vec![
            (0.0, st),
            (0.3, st.with(idx::YAW, 0.2).with_leg(1, idx::HIP_FLEX, 0.35).with_leg(1, idx::KNEE, 0.7).with(idx::HEAD + 1, 0.4)),
            (0.6, st.with(idx::YAW, FRAC_PI_2).with(idx::HEAD + 1, 0.3)),
            (0.9, st.with(idx::YAW, 2.3).with_leg(0, idx::HIP_FLEX, 0.35).with_leg(0, idx::KNEE, 0.7).with(idx::HEAD + 1, 0.2)),
            (1.25, st.with(idx::YAW, PI)),
        ],
        &|t| [!(0.68..1.12).contains(&t), !(0.1..0.55).contains(&t)],
    );
    out.push(Authored { clip: turn, tags: tags(&["turn", "回る", "振り向く", "turn around"]), part: None, cycle_advance: None });

    // Bow: bend at the hips, hold, come back up.
    fn bent(k: f32) -> Pose {
        Pose::standing().with(idx::HIPS_PITCH, 0.35 * k).with(idx::SPINE, 0.3 * k).with(idx::CHEST, 0.2 * k).with(idx::HEAD, 0.15 * k).with_leg(0, idx::HIP_FLEX, 0.02 - 0.3 * k).with_leg(1, idx::HIP_FLEX, 0.02 - 0.3 * k)
    }
    let bow = keyed("bow", vec![(0.0, st), (0.6, bent(1.0)), (1.2, bent(0.95)), (1.9, st)], &BOTH);
    out.push(Authored { clip: bow, tags: tags(&["bow", "お辞儀", "礼"]), part: None, cycle_advance: None });

    // Sit down on a chair-high seat, and stand back up.
    let seated = st
        .with_leg(0, idx::HIP_FLEX, 1.5)
        .with_leg(1, idx::HIP_FLEX, 1.5)
        .with_leg(0, idx::KNEE, 1.5)
        .with_leg(1, idx::KNEE, 1.5)
        .with(idx::SPINE, 0.1)
        .with_arm(0, idx::FLEX, 0.5)
        .with_arm(1, idx::FLEX, 0.5)
        .with_arm(0, idx::ELBOW, 1.0)
        .with_arm(1, idx::ELBOW, 1.0);
    let lowering = st.with_leg(0, idx::HIP_FLEX, 1.1).with_leg(1, idx::HIP_FLEX, 1.1).with_leg(0, idx::KNEE, 1.2).with_leg(1, idx::KNEE, 1.2).with(idx::SPINE, 0.45).with_arm(0, idx::FLEX, 0.6).with_arm(1, idx::FLEX, 0.6);
    out.push(Authored { clip: keyed("sit", vec![(0.0, st), (0.7, lowering), (1.4, seated), (1.8, seated)], &BOTH), tags: tags(&["sit", "座る", "sit down"]), part: None, cycle_advance: None });
    out.push(Authored { clip: keyed("stand", vec![(0.0, seated), (0.4, seated), (1.0, lowering), (1.7, st)], &BOTH), tags: tags(&["stand", "立つ", "stand up", "立ち上がる"]), part: None, cycle_advance: None });

    // Nod twice.
    let nod = keyed("nod", vec![(0.0, st), (0.25, st.with(idx::NECK, 0.15).with(idx::HEAD, 0.3)), (0.5, st.with(idx::HEAD, -0.05)), (0.75, st.with(idx::NECK, 0.12).with(idx::HEAD, 0.28)), (1.2, st)], &BOTH);
    out.push(Authored { clip: nod, tags: tags(&["nod", "うなずく", "頷く"]), part: Some(crate::actions::BodyPart::Head), cycle_advance: None });

    // Point forward with the right arm, look where it points.
    let pointing = st.with_arm(1, idx::FLEX, 1.45).with_arm(1, idx::ABDUCT, 0.25).with_arm(1, idx::ELBOW, 0.05).with_arm(1, idx::WRIST, 0.1).with(idx::HEAD + 1, -0.12).with(idx::CHEST + 1, 0.1);
    let point = keyed("point", vec![(0.0, st), (0.45, pointing), (1.4, pointing.with_arm(1, idx::FLEX, 1.4)), (1.9, st)], &BOTH);
    out.push(Authored { clip: point, tags: tags(&["point", "指差す", "指さす", "right"]), part: Some(crate::actions::BodyPart::RightArm), cycle_advance: None });
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn hand(clip: &Clip, frame: usize, c: Canon) -> Vec3 {
        clip.world_positions(frame)[c.index()]
    }

    #[test]
    fn every_action_stays_on_the_floor() {
        for a in builtin_actions() {
            a.clip.validate().unwrap();
            let mut lowest_all = f32::MAX;
            for f in 0..a.clip.frame_count() {
                let p = a.clip.world_positions(f);
                let lowest = p.iter().map(|v| v.y).fold(f32::MAX, f32::min);
                lowest_all = lowest_all.min(lowest);
                assert!(lowest > -0.06, "{}: frame {f} sinks to {lowest}", a.clip.name);
            }
            assert!(lowest_all < 0.1, "{} never touches the floor ({lowest_all})", a.clip.name);
        }
    }

    #[test]
    fn walk_plants_its_feet_and_moves_forward() {
        let acts = builtin_actions();
        let walk = &acts[0];
        let adv = walk.cycle_advance.unwrap();
        assert!(adv.z > 0.8 && adv.z < 1.6, "walk advances {adv}");
        // A planted foot (lowest, on the floor) moves less than a few mm per frame.
        let c = &walk.clip;
        for f in 1..c.frame_count() {
            let (a, b) = (c.world_positions(f - 1), c.world_positions(f));
            for foot in [Canon::LeftFoot, Canon::RightFoot] {
                let (pa, pb) = (a[foot.index()], b[foot.index()]);
                if pa.y < 0.085 && pb.y < 0.085 {
                    let d = Vec3::new(pb.x - pa.x, 0.0, pb.z - pa.z).length();
                    assert!(d < 0.01, "frame {f} {foot:?} slides {d}");
                }
            }
        }
    }

    #[test]
    fn waving_hand_goes_above_the_head_side_and_claps_meet() {
        let acts = builtin_actions();
        let wave_r = acts.iter().find(|a| a.clip.name == "wave right hand").unwrap();
        let mid = wave_r.clip.frame_count() / 2;
        let p = wave_r.clip.world_positions(mid);
        assert!(p[Canon::RightHand.index()].y > p[Canon::Neck.index()].y, "hand not raised: {:?}", p[Canon::RightHand.index()]);
        assert!(p[Canon::RightHand.index()].x < 0.0, "right hand on the figure's right (−X)");
        let clap = acts.iter().find(|a| a.clip.name == "clap").unwrap();
        let closest = (0..clap.clip.frame_count())
            .map(|f| (hand(&clap.clip, f, Canon::LeftHand) - hand(&clap.clip, f, Canon::RightHand)).length())
            .fold(f32::MAX, f32::min);
        assert!(closest < 0.12, "clap hands come within {closest} m");
        let jump = acts.iter().find(|a| a.clip.name == "jump").unwrap();
        let top = (0..jump.clip.frame_count()).map(|f| jump.clip.root_translation(f).y).fold(f32::MIN, f32::max);
        assert!(top > 1.0, "jump apex {top}");
    }

    #[test]
    fn gaits_travel_evenly_without_pops() {
        for a in builtin_actions().iter().filter(|a| a.cycle_advance.is_some()) {
            let adv = a.cycle_advance.unwrap();
            let c = crate::actions::library::repeat_cycle(&a.clip, adv, 3.0);
            let v = &c.translations[0].values;
            let mean = Vec3::new(adv.x, 0.0, adv.z).length() / a.clip.frame_count() as f32;
            for (f, w) in v.windows(2).enumerate() {
                let step = Vec3::new(w[1].x - w[0].x, 0.0, w[1].z - w[0].z).length();
                assert!((step - mean).abs() < 0.35 * mean, "{} frame {f}: ground step {step} vs mean {mean}", a.clip.name);
                assert!((w[1].y - w[0].y).abs() < 0.01, "{} frame {f}: height jumps {}", a.clip.name, w[1].y - w[0].y);
            }
        }
    }

    #[test]
    fn arm_only_actions_leave_the_legs_standing() {
        // Guards the key poses: clapping, waving, pointing and nodding must not bend a knee.
        let standing = Pose::standing().to_rotations();
        for a in builtin_actions().iter().filter(|a| matches!(a.clip.name.as_str(), "clap" | "wave right hand" | "wave left hand" | "point" | "nod")) {
            for f in 0..a.clip.frame_count() {
                for c in [Canon::LeftLowerLeg, Canon::RightLowerLeg, Canon::LeftUpperLeg, Canon::RightUpperLeg] {
                    let q = a.clip.frame_rotations(f)[c.index()];
                    assert!(q.angle_between(standing[c.index()]) < 1e-4, "{} frame {f}: {c:?} moved", a.clip.name);
                }
            }
        }
    }
}
