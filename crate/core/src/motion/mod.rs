//! The motion kernel: the one forward kinematics of the engine (local rotations and
//! translations to world rotations and positions) behind one entry point, [`WorldPose`]: a
//! pose's world rotations and positions in buffers it keeps, filled from a clip's frame, a clip
//! at a time, local rotations and translations, or rotations only (every joint at its rest
//! offset); and rest-pose transforms, the lowest point of a pose, the one cubic Hermite curve
//! and the one smoothstep, the one shortest arc that aims a bone ([`shortest_arc`]), two-bone
//! IK (positions, and the rotations of the chain: the joins' leg IK and the retargeting's held
//! feet both use [`two_bone_rotations`]), floor and foot-skate measures, and the quaternion
//! hygiene every writer of keyframes needs (unit length, sign continuity).
//! Clips, characters (retargeting and its report), the viewer, `actions::ik::forward`, the
//! segment signatures, the lowest points of `builtin.rs` and `library/pose.rs`, the
//! choreography's joins, the text actions' sway and the glTF importer's CUBICSPLINE sampler all
//! call it (`tests/native/motion_kernel.rs` checks each against the copy it replaced: the same
//! bits, or within 1e-5 for the world matrices).

use glam::{Mat4, Quat, Vec3};

use crate::clip::Clip;
use crate::skeleton::Skeleton;

/// One pose in world space, and the one entry point of forward kinematics: each `of_*` method
/// poses a skeleton into the buffers this keeps (reused from call to call, so a loop over
/// frames allocates once) and returns them. Every joint's world rotation and position, in
/// skeleton order; a joint whose parent is not before it is posed as a root.
#[derive(Clone, Debug, Default)]
pub struct WorldPose {
    /// World rotation of each joint.
    pub rotations: Vec<Quat>,
    /// World position of each joint, metres.
    pub positions: Vec<Vec3>,
    /// Scratch: the local pose sampled from a clip.
    local_rotations: Vec<Quat>,
    local_translations: Vec<Vec3>,
}

impl WorldPose {
    pub fn new() -> Self {
        Self::default()
    }

    fn resize(&mut self, n: usize) {
        self.rotations.clear();
        self.rotations.resize(n, Quat::IDENTITY);
        self.positions.clear();
        self.positions.resize(n, Vec3::ZERO);
    }

    /// Poses `skeleton` from local rotations and translations (joint `i`'s in its parent's
    /// frame; a root's in world space), for the first `min` of their lengths and the joint count.
    pub fn of_locals(&mut self, skeleton: &Skeleton, local_rotations: &[Quat], local_translations: &[Vec3]) -> &mut Self {
        self.resize(skeleton.len().min(local_rotations.len()).min(local_translations.len()));
        local_to_world(skeleton, local_rotations, local_translations, &mut self.rotations, &mut self.positions);
        self
    }

    /// Poses `skeleton` from local rotations only: every joint at its rest offset, the roots
    /// (joints without a parent before them) at `root`.
    pub fn of_rotations(&mut self, skeleton: &Skeleton, local_rotations: &[Quat], root: Vec3) -> &mut Self {
        self.resize(skeleton.len().min(local_rotations.len()));
        local_to_world_at(skeleton, local_rotations, root, &mut self.rotations, &mut self.positions);
        self
    }

    /// Poses frame `frame` of `clip` (translation tracks where present, rest offsets elsewhere).
    /// A frame past the end poses nothing (empty buffers).
    pub fn of_frame(&mut self, clip: &Clip, frame: usize) -> &mut Self {
        if frame >= clip.frame_count() {
            self.resize(0);
            return self;
        }
        let mut trans = std::mem::take(&mut self.local_translations);
        clip.local_translations_into(frame, &mut trans);
        self.of_locals(&clip.skeleton, clip.frame_rotations(frame), &trans);
        self.local_translations = trans;
        self
    }

    /// Poses `clip` at `time_secs`: its nearest frames blended ([`Clip::sample_into`], clamped
    /// to the clip). An empty clip poses nothing.
    pub fn of_time(&mut self, clip: &Clip, time_secs: f32) -> &mut Self {
        if clip.frame_count() == 0 {
            self.resize(0);
            return self;
        }
        let (mut rot, mut trans) = (std::mem::take(&mut self.local_rotations), std::mem::take(&mut self.local_translations));
        clip.sample_into(time_secs, &mut rot, &mut trans);
        self.of_locals(&clip.skeleton, &rot, &trans);
        (self.local_rotations, self.local_translations) = (rot, trans);
        self
    }

    /// Each posed joint's world rotation and position as one rigid matrix (for skinning), into
    /// `out` (resized).
    pub fn matrices_into(&self, out: &mut Vec<Mat4>) {
        out.clear();
        out.extend(self.rotations.iter().zip(&self.positions).map(|(r, p)| Mat4::from_rotation_translation(*r, *p)));
    }

    /// Height of the lowest posed joint; `f32::MAX` for none.
    pub fn lowest_y(&self) -> f32 {
        self.positions.iter().map(|p| p.y).fold(f32::MAX, f32::min)
    }
}

/// Forward kinematics of one pose into the caller's slices, parents before children (the
/// kernel under [`WorldPose::of_locals`]).
///
/// `local_rotations[i]` and `local_translations[i]` are joint `i`'s rotation and translation
/// in its parent's frame; a root's are in world space. Writes `world_rotations` and
/// `world_positions` for the first `min` of all lengths and the skeleton's joint count, and
/// returns that count. A joint whose parent is not before it is treated as a root (the
/// skeleton's own invariant says this never happens; the guard keeps a bad one from panicking).
fn local_to_world(
    skeleton: &Skeleton,
    local_rotations: &[Quat],
    local_translations: &[Vec3],
    world_rotations: &mut [Quat],
    world_positions: &mut [Vec3],
) -> usize {
    let n = skeleton.len().min(local_rotations.len()).min(local_translations.len()).min(world_rotations.len()).min(world_positions.len());
    fk(skeleton, n, local_rotations, |i| local_translations[i], world_rotations, world_positions);
    n
}

/// [`local_to_world`] of a pose whose joints all keep their rest offsets, the root (any joint
/// without a parent before it) standing at `root`: the common case of a pose given by
/// rotations only (the kernel under [`WorldPose::of_rotations`], and allocation-free for
/// [`lowest_height`]'s hot loops). Returns the number of joints written.
fn local_to_world_at(skeleton: &Skeleton, local_rotations: &[Quat], root: Vec3, world_rotations: &mut [Quat], world_positions: &mut [Vec3]) -> usize {
    let n = skeleton.len().min(local_rotations.len()).min(world_rotations.len()).min(world_positions.len());
    let joints = &skeleton.joints;
    fk(skeleton, n, local_rotations, |i| if joints[i].parent.is_some_and(|p| p < i) { joints[i].rest_offset } else { root }, world_rotations, world_positions);
    n
}

/// The one forward-kinematics loop: joint `i`'s local translation comes from `translation(i)`.
#[inline(always)]
fn fk(skeleton: &Skeleton, n: usize, local_rotations: &[Quat], translation: impl Fn(usize) -> Vec3, world_rotations: &mut [Quat], world_positions: &mut [Vec3]) {
    for (i, j) in skeleton.joints.iter().enumerate().take(n) {
        match j.parent {
            Some(p) if p < i => {
                let pr = world_rotations[p];
                world_rotations[i] = pr * local_rotations[i];
                world_positions[i] = world_positions[p] + pr * translation(i);
            }
            _ => {
                world_rotations[i] = local_rotations[i];
                world_positions[i] = translation(i);
            }
        }
    }
}

/// World rotations and positions of the skeleton's rest pose (rest rotations and offsets).
pub fn rest_world(skeleton: &Skeleton) -> (Vec<Quat>, Vec<Vec3>) {
    let local_r: Vec<Quat> = skeleton.joints.iter().map(|j| j.rest_rotation).collect();
    let local_t: Vec<Vec3> = skeleton.joints.iter().map(|j| j.rest_offset).collect();
    let mut pose = WorldPose::new();
    pose.of_locals(skeleton, &local_r, &local_t);
    (pose.rotations, pose.positions)
}

/// Height of the lowest joint of a pose given by rotations (rest offsets, the root at
/// `root`), using `rot` and `pos` as scratch (so a hot loop need not allocate); `f32::MAX`
/// for no joint.
pub fn lowest_height(skeleton: &Skeleton, local_rotations: &[Quat], root: Vec3, rot: &mut [Quat], pos: &mut [Vec3]) -> f32 {
    let n = local_to_world_at(skeleton, local_rotations, root, rot, pos);
    pos[..n].iter().map(|p| p.y).fold(f32::MAX, f32::min)
}

/// The rigid world matrix of a joint and its exact inverse (built from the rotation and
/// translation, so the last row is exactly 0 0 0 1, as glTF's inverse bind matrices must be).
pub fn rigid(rotation: Quat, position: Vec3) -> (Mat4, Mat4) {
    let inv_r = rotation.inverse();
    (Mat4::from_rotation_translation(rotation, position), Mat4::from_rotation_translation(inv_r, -(inv_r * position)))
}

/// `q` or `-q`, whichever is nearer `previous` (the same rotation; keyframe interpolation
/// between neighbours of opposite sign would take the long way round).
pub fn sign_continuous(previous: Quat, q: Quat) -> Quat {
    if previous.dot(q) < 0.0 {
        -q
    } else {
        q
    }
}

/// Cubic Hermite interpolation at `s` in 0..1 between `p0` and `p1` with tangents `m0`, `m1`
/// (already multiplied by the interval's length): the one curve of the engine (glTF
/// CUBICSPLINE sampling, the choreography's joins, the text actions' sway residual).
pub fn hermite<const N: usize>(p0: [f32; N], m0: [f32; N], p1: [f32; N], m1: [f32; N], s: f32) -> [f32; N] {
    let s2 = s * s;
    let s3 = s2 * s;
    let h00 = 2.0 * s3 - 3.0 * s2 + 1.0;
    let h10 = s3 - 2.0 * s2 + s;
    let h01 = -2.0 * s3 + 3.0 * s2;
    let h11 = s3 - s2;
    std::array::from_fn(|i| h00 * p0[i] + h10 * m0[i] + h01 * p1[i] + h11 * m1[i])
}

/// Smoothstep: 0..1 onto 0..1 with zero slope at both ends (`x` clamped), the one easing
/// curve of the engine (joins, procedural and built-in moves, retargeting's released feet).
pub fn smoothstep(x: f32) -> f32 {
    let x = x.clamp(0.0, 1.0);
    x * x * (3.0 - 2.0 * x)
}

/// Smootherstep (quintic): 0..1 onto 0..1 with zero slope and zero curvature at both ends
/// (`x` clamped). The built-in moves held on the counts ease from each count's pose to the next
/// by it, so every joint comes to rest on the count without a jolt of acceleration there.
pub fn smootherstep(x: f32) -> f32 {
    let x = x.clamp(0.0, 1.0);
    x * x * x * (x * (6.0 * x - 15.0) + 10.0)
}

/// Two-bone IK: the middle joint (knee, elbow) and the end (ankle, wrist) of a chain from
/// `root` with bone lengths `l1`, `l2` reaching for `target`, bending towards `pole`. A target
/// out of reach is pulled in along the line from the root.
pub fn two_bone(root: Vec3, target: Vec3, l1: f32, l2: f32, pole: Vec3) -> (Vec3, Vec3) {
    let to = target - root;
    let d_raw = to.length();
    let d = d_raw.clamp((l1 - l2).abs() + 1e-3, l1 + l2 - 1e-4);
    let dir = if d_raw > 1e-6 { to / d_raw } else { Vec3::NEG_Y };
    let end = root + dir * d;
    // Law of cosines: distance along dir to the middle joint's projection, and its offset.
    let a = (l1 * l1 - l2 * l2 + d * d) / (2.0 * d);
    let h = (l1 * l1 - a * a).max(0.0).sqrt();
    let side = (pole - dir * pole.dot(dir)).try_normalize().unwrap_or_else(|| dir.any_orthonormal_vector());
    (root + dir * a + side * h, end)
}

/// The shortest rotation turning direction `from` onto direction `to` (either of any length;
/// the identity when either has no direction: zero or not finite), the one of the engine for
/// aiming a bone (the two-bone IK's swings, the built-in moves' toes, the retargeting's bone
/// directions). With `a`, `b` the unit directions: `(a × b, 1 + a·b)` normalised up to a
/// quarter turn, exact down to equal directions (the identity) — glam's
/// `Quat::from_rotation_arc` returns the identity for every arc under about 7e-4 rad (its
/// `dot > 1 − 2ε` shortcut), so a thigh that had to turn 3e-4 rad did not turn and a planted
/// ankle missed its goal by 0.2–0.3 mm. Past a quarter turn `1 + a·b` loses its digits as the
/// arc nears a half turn, so the same quaternion is built from `s = a + b` (exact there), as
/// `(a × ŝ, |s| / 2)`; only exactly opposite directions (`s = 0`, no axis) take a half turn
/// about an axis orthogonal to `a`.
pub fn shortest_arc(from: Vec3, to: Vec3) -> Quat {
    let (Some(a), Some(b)) = (from.try_normalize(), to.try_normalize()) else {
        return Quat::IDENTITY;
    };
    let dot = a.dot(b);
    if dot >= 0.0 {
        let c = a.cross(b);
        return Quat::from_xyzw(c.x, c.y, c.z, 1.0 + dot).normalize();
    }
    let s = a + b;
    match s.try_normalize() {
        Some(h) => {
            let c = a.cross(h);
            Quat::from_xyzw(c.x, c.y, c.z, 0.5 * s.length()).normalize()
        }
        None => Quat::from_axis_angle(a.any_orthonormal_vector(), std::f32::consts::PI),
    }
}

/// A two-bone chain turned onto the solution of [`two_bone`]: the upper and lower joints' new
/// world rotations, and where the middle joint and the end now are.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TwoBonePose {
    pub upper: Quat,
    pub lower: Quat,
    pub middle: Vec3,
    pub end: Vec3,
}

/// Two-bone IK on rotations, the one solver of the engine (planted feet in joins, held feet in
/// retargeting): the chain's upper joint stands at `root` with world rotation `upper`, and its
/// bone to the middle joint is `upper_bone` in the joint's own frame; the lower joint's bone to
/// the end is `lower_bone` in its own frame, and `lower_before(new_upper)` gives the lower
/// joint's world rotation before it turns (its local rotation carried by the turned upper
/// joint, or a world rotation a retargeting has already chosen). The middle and end positions
/// come from [`two_bone`] (bending toward `pole`, a direction); each joint is then turned by
/// the shortest arc from where its bone points onto them, so each keeps its twist about its
/// own bone (a knee's roll, a shin's).
pub fn two_bone_rotations(
    root: Vec3,
    upper: Quat,
    upper_bone: Vec3,
    lower_bone: Vec3,
    lower_before: impl FnOnce(Quat) -> Quat,
    target: Vec3,
    pole: Vec3,
) -> TwoBonePose {
    two_bone_rotations_by(shortest_arc, root, upper, upper_bone, lower_bone, lower_before, target, pole)
}

/// [`two_bone_rotations`] with the arc given: the kernel passes [`shortest_arc`]; the unit
/// tests also pass glam's `Quat::from_rotation_arc` (the control that shows its dead zone).
#[allow(clippy::too_many_arguments)]
fn two_bone_rotations_by(
    arc: fn(Vec3, Vec3) -> Quat,
    root: Vec3,
    upper: Quat,
    upper_bone: Vec3,
    lower_bone: Vec3,
    lower_before: impl FnOnce(Quat) -> Quat,
    target: Vec3,
    pole: Vec3,
) -> TwoBonePose {
    let (middle, end) = two_bone(root, target, upper_bone.length(), lower_bone.length(), pole);
    let swing = |world: Quat, bone: Vec3, aim: Vec3| match ((world * bone).try_normalize(), aim.try_normalize()) {
        (Some(a), Some(b)) => (arc(a, b) * world).normalize(),
        _ => world,
    };
    let upper = swing(upper, upper_bone, middle - root);
    let lower = swing(lower_before(upper), lower_bone, end - middle);
    TwoBonePose { upper, lower, middle, end }
}

/// The floor under a joint over a clip: the 1st percentile of its heights (spec §J), so a few
/// noisy frames below the real floor do not set it. `None` for no finite height.
pub fn floor_height(heights_m: &[f32]) -> Option<f32> {
    let mut h: Vec<f32> = heights_m.iter().copied().filter(|v| v.is_finite()).collect();
    if h.is_empty() {
        return None;
    }
    h.sort_by(f32::total_cmp);
    Some(h[(h.len() - 1) / 100])
}

/// Foot skate (spec §J): horizontal speed of a joint, cm/s, on the frames where it is within
/// the one contact rule's band over its floor ([`crate::canon::contact::in_contact_band`]: 5 cm
/// over its 1st-percentile height). `track` is the joint's world position per frame. Returns
/// every such speed (between frame f−1 and f, counted when frame f is near the floor).
pub fn skate_speeds_cm_s(track: &[Vec3], fps: f32) -> Vec<f32> {
    let band = crate::canon::contact::in_contact_band(&track.iter().map(|p| p.y).collect::<Vec<_>>());
    track
        .windows(2)
        .zip(&band[band.len().min(1)..])
        .filter(|(_, on)| **on)
        .map(|(w, _)| Vec3::new(w[1].x - w[0].x, 0.0, w[1].z - w[0].z).length() * fps * 100.0)
        .collect()
}

/// Mean and 95th percentile of a list (0, 0 when empty).
pub fn mean_p95(values: &[f32]) -> (f32, f32) {
    if values.is_empty() {
        return (0.0, 0.0);
    }
    let mut v = values.to_vec();
    v.sort_by(f32::total_cmp);
    (v.iter().sum::<f32>() / v.len() as f32, v[((v.len() - 1) as f32 * 0.95).round() as usize])
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::canon::builtin::canonical_skeleton;

    #[test]
    fn rest_world_matches_skeleton_rest_positions() {
        let sk = canonical_skeleton();
        let (_, pos) = rest_world(&sk);
        for (a, b) in pos.iter().zip(sk.rest_positions()) {
            assert!((*a - b).length() < 1e-6);
        }
    }

    #[test]
    fn smootherstep_rests_with_zero_slope_and_curvature_at_both_ends() {
        // Finite differences at the ends: slope and curvature vanish for smootherstep; the
        // control, smoothstep, has zero slope but a curvature of ±6 there.
        let h = 1e-2_f32;
        let slope = |f: fn(f32) -> f32, x: f32| (f(x + h) - f(x - h)) / (2.0 * h);
        let curve = |f: fn(f32) -> f32, x: f32| (f(x + h) - 2.0 * f(x) + f(x - h)) / (h * h);
        // One-sided at the ends (the curves are clamped outside 0..1): second differences inward.
        let curve_in = |f: fn(f32) -> f32, x: f32, dir: f32| (f(x + 2.0 * dir * h) - 2.0 * f(x + dir * h) + f(x)) / (h * h);
        for (x, dir) in [(0.0, 1.0), (1.0, -1.0)] {
            // One-sided differences read 60·h for smootherstep (0 in the limit), 6 − 12·h for
            // smoothstep.
            assert!(curve_in(smootherstep, x, dir).abs() < 1.0, "smootherstep curvature at {x}: {}", curve_in(smootherstep, x, dir));
            assert!(curve_in(smoothstep, x, dir).abs() > 5.0, "the control's curvature at {x}: {}", curve_in(smoothstep, x, dir));
            assert!((smootherstep(x) - x).abs() < 1e-7);
        }
        assert!(slope(smootherstep, h).abs() < 1e-2 && slope(smootherstep, 1.0 - h).abs() < 1e-2);
        assert!((smootherstep(0.5) - 0.5).abs() < 1e-7 && (slope(smootherstep, 0.5) - 1.875).abs() < 1e-2);
        assert!(curve(smootherstep, 0.5).abs() < 0.1);
        let mut last = 0.0;
        for i in 0..=100 {
            let y = smootherstep(i as f32 / 100.0);
            assert!(y >= last, "not rising at {i}");
            last = y;
        }
    }

    #[test]
    fn rigid_inverse_is_exact_affine() {
        let q = Quat::from_euler(glam::EulerRot::ZXY, 0.3, -1.1, 2.0);
        let (m, inv) = rigid(q, Vec3::new(0.1, 1.2, -0.4));
        assert!((m * inv).abs_diff_eq(Mat4::IDENTITY, 1e-5));
        assert_eq!(inv.row(3), glam::Vec4::W);
    }

    #[test]
    fn skate_counts_only_frames_near_the_floor() {
        // A foot sliding 1 cm per frame on the floor at 30 fps, then lifted 20 cm and moving.
        let mut track: Vec<Vec3> = (0..10).map(|f| Vec3::new(f as f32 * 0.01, 0.0, 0.0)).collect();
        track.extend((0..10).map(|f| Vec3::new(1.0 + f as f32 * 0.1, 0.2, 0.0)));
        let s = skate_speeds_cm_s(&track, 30.0);
        assert_eq!(s.len(), 9);
        assert!(s.iter().all(|v| (v - 30.0).abs() < 1e-3), "{s:?}");
    }

    /// A deterministic generator of numbers in -1..1 (an LCG), and unit vectors from it.
    fn lcg(seed: u32) -> impl FnMut() -> f32 {
        let mut k = seed;
        move || {
            k = k.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
            (k >> 8) as f32 / (1u32 << 24) as f32 * 2.0 - 1.0
        }
    }

    fn unit(next: &mut impl FnMut() -> f32) -> Vec3 {
        loop {
            if let Some(v) = Vec3::new(next(), next(), next()).try_normalize() {
                return v;
            }
        }
    }

    /// `to` turned by `angle` from `from` about a random axis orthogonal to it.
    fn turned(next: &mut impl FnMut() -> f32, from: Vec3, angle: f32) -> Vec3 {
        let axis = from.cross(unit(next)).normalize();
        (Quat::from_axis_angle(axis, angle) * from).normalize()
    }

    /// Eight ulps of a unit vector (about 9.5e-7): turning a vector by a quaternion alone
    /// rounds by up to about four.
    const ULPS: f32 = 8.0 * f32::EPSILON;

    #[test]
    fn shortest_arc_turns_the_tiny_arcs_glam_leaves_undone() {
        // Arcs of 3e-6..1e-3 rad about random axes: the arc puts `from` on `to` within eight
        // ulps. The control: glam's `from_rotation_arc` gives the identity under 4e-4 rad (its
        // dead zone, whose edge rounding blurs up to about 7e-4), and so misses `to` by more.
        let mut next = lcg(11);
        let (mut worst, mut worst_glam, mut dead) = (0.0f32, f32::MAX, 0);
        for _ in 0..4000 {
            let from = unit(&mut next);
            let angle = crate::fmath::powf(10f32, -5.5 + 1.25 * (next() + 1.0));
            let to = turned(&mut next, from, angle);
            worst = worst.max((shortest_arc(from, to) * from - to).length());
            let glam = Quat::from_rotation_arc(from, to);
            if angle < 4e-4 {
                assert_eq!(glam, Quat::IDENTITY, "glam turns an arc of {angle:e} rad");
                worst_glam = worst_glam.min((glam * from - to).length());
                dead += 1;
            }
        }
        println!("tiny arcs: worst miss {worst:e} (glam's least miss in its dead zone {worst_glam:e}, {dead} arcs)");
        assert!(dead > 2000, "{dead}");
        assert!(worst < ULPS, "{worst:e}");
        assert!(worst_glam > ULPS, "{worst_glam:e}");
    }

    #[test]
    fn shortest_arc_quarter_and_half_turns_and_equal_directions() {
        let mut next = lcg(5);
        let (mut quarter, mut half, mut half_glam) = (0.0f32, 0.0f32, 0.0f32);
        for _ in 0..2000 {
            let from = unit(&mut next);
            // Equal directions (any lengths): the identity, exactly; no direction: the identity.
            assert_eq!(shortest_arc(from * 0.5, from * 2.0), Quat::IDENTITY);
            assert_eq!(shortest_arc(Vec3::ZERO, from), Quat::IDENTITY);
            assert_eq!(shortest_arc(from, Vec3::splat(f32::NAN)), Quat::IDENTITY);
            // A quarter turn: onto `to`, and by a quarter turn (the shortest way).
            let to = turned(&mut next, from, std::f32::consts::FRAC_PI_2);
            let q = shortest_arc(from, to);
            quarter = quarter.max((q * from - to).length()).max((q.w - std::f32::consts::FRAC_1_SQRT_2).abs());
            // Near a half turn (1e-6..1e-2 rad short of it) and exactly opposite.
            let short = crate::fmath::powf(10f32, -6.0 + 2.0 * (next() + 1.0));
            let to = turned(&mut next, -from, short);
            half = half.max((shortest_arc(from, to) * from - to).length());
            half_glam = half_glam.max((Quat::from_rotation_arc(from, to) * from - to).length());
            half = half.max((shortest_arc(from, -from) * from + from).length());
        }
        println!("quarter turns: worst {quarter:e}; near half turns: worst {half:e} (glam's {half_glam:e})");
        assert!(quarter < ULPS, "{quarter:e}");
        assert!(half < ULPS, "{half:e}");
    }

    #[test]
    fn two_bone_ik_reaches_near_stretched_targets_that_glams_arc_misses() {
        // A leg near full stretch (the target 0.6–6 mm inside its reach) solved once, then the
        // whole leg turned about the hip by 1.6e-4..2.4e-4 rad (a held foot's small correction):
        // solving again must turn it back, the thigh by about that arc. With the kernel's arc
        // the ankle lands within 1e-5 m of the target; the control, the same solver with glam's
        // `from_rotation_arc`, leaves both bones where they are (arcs in its dead zone) and
        // misses by more than 1e-4 m in over 90 % of the cases (995 of 1000 when written: in a
        // few, rounding takes the dot product of the unit directions under glam's threshold).
        let mut next = lcg(3);
        let (mut worst, mut glam_missed) = (0.0f32, 0);
        for _ in 0..1000 {
            let (l1, l2) = (0.45 + 0.05 * next(), 0.45 + 0.05 * next());
            let (upper_bone, lower_bone) = (unit(&mut next) * l1, unit(&mut next) * l2);
            let root = Vec3::new(next(), 1.0 + next() * 0.2, next());
            let dir = Vec3::new(next() * 0.5, -1.0, next() * 0.5).normalize();
            let target = root + dir * (l1 + l2 - crate::fmath::powf(10f32, -3.2 + 0.5 * (next() + 1.0)));
            let pole = unit(&mut next);
            let upper0 = Quat::from_scaled_axis(unit(&mut next) * 3.0 * next());
            let knee0 = Quat::from_scaled_axis(unit(&mut next) * 3.0 * next());
            let first = two_bone_rotations(root, upper0, upper_bone, lower_bone, |u| u * knee0, target, pole);
            let knee = (first.upper.inverse() * first.lower).normalize();
            let turn = Quat::from_axis_angle(dir.cross(unit(&mut next)).normalize(), 2e-4 + 0.4e-4 * next());
            let upper = (turn * first.upper).normalize();
            let ankle = |p: TwoBonePose| root + p.upper * upper_bone + p.lower * lower_bone;
            let kernel = two_bone_rotations(root, upper, upper_bone, lower_bone, |u| u * knee, target, pole);
            worst = worst.max((ankle(kernel) - target).length());
            let glam = two_bone_rotations_by(Quat::from_rotation_arc, root, upper, upper_bone, lower_bone, |u| u * knee, target, pole);
            glam_missed += usize::from((ankle(glam) - target).length() > 1e-4);
        }
        println!("near-stretched legs: worst ankle miss {worst:e} m (glam's arc: {glam_missed} of 1000 missed by over 1e-4 m)");
        assert!(worst < 1e-5, "{worst:e} m");
        assert!(glam_missed > 900, "{glam_missed}");
    }

    #[test]
    fn sign_continuity_keeps_the_short_way() {
        let a = Quat::from_rotation_y(0.1);
        let b = -Quat::from_rotation_y(0.2);
        let c = sign_continuous(a, b);
        assert!(a.dot(c) > 0.0);
        assert!(c.angle_between(b) < 1e-5);
    }
}
