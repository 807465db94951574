//! Building canonical poses from what a choreographer thinks in: where the hips are and how they
//! turn, where each foot and hand goes, how the spine, chest and head bend. Limbs are placed
//! with analytic two-bone IK, so a planted foot stays exactly where it was put.

use glam::{EulerRot, Quat, Vec3};

use crate::canon::humanoid::{Canon, CANON_COUNT};
use crate::skeleton::Skeleton;

/// Height of the ankle joint above the floor when the foot is flat (the canonical toe tip then
/// sits 2 cm above the floor).
pub const ANKLE_HEIGHT: f32 = 0.08;

/// One key pose, in the figure's own frame (facing +Z, its left on +X, metres, radians).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct KeyPose {
    /// Hips (root) position: x sideways, y added to the standing height (negative = knees bend),
    /// z forward.
    pub hips: Vec3,
    /// Hips yaw (turn about Y), pitch (tilt forward, +), roll (tilt towards the figure's left, +).
    pub hips_yaw: f32,
    pub hips_pitch: f32,
    pub hips_roll: f32,
    /// Spine and chest bends relative to the hips: forward (+), towards the left (+), twist.
    pub spine_pitch: f32,
    pub spine_roll: f32,
    pub chest_pitch: f32,
    pub chest_roll: f32,
    pub chest_yaw: f32,
    /// Head nod (forward +), tilt (left +), turn.
    pub head_pitch: f32,
    pub head_roll: f32,
    pub head_yaw: f32,
    /// Ankle targets in the dance floor frame (x, height above [`ANKLE_HEIGHT`], z).
    pub left_foot: Vec3,
    pub right_foot: Vec3,
    /// How much each foot points (0 flat, 1 toes fully pointed) and turns out.
    pub left_point: f32,
    pub right_point: f32,
    pub feet_yaw: f32,
    /// Hand targets relative to the shoulder (upper-arm joint) in the chest frame.
    pub left_hand: Vec3,
    pub right_hand: Vec3,
    /// Shoulder shrug, radians.
    pub left_shrug: f32,
    pub right_shrug: f32,
}

impl KeyPose {
    /// Weighted sum, for interpolation (`a * wa + b * wb + ...`).
    pub fn scaled(&self, w: f32) -> KeyPose {
        self.map2(&KeyPose::default(), |a, _| a * w, |a, _| a * w)
    }

    pub fn add(&self, o: &KeyPose) -> KeyPose {
        self.map2(o, |a, b| a + b, |a, b| a + b)
    }

    fn map2(&self, o: &KeyPose, f: impl Fn(f32, f32) -> f32, v: impl Fn(Vec3, Vec3) -> Vec3) -> KeyPose {
        KeyPose {
            hips: v(self.hips, o.hips),
            hips_yaw: f(self.hips_yaw, o.hips_yaw),
            hips_pitch: f(self.hips_pitch, o.hips_pitch),
            hips_roll: f(self.hips_roll, o.hips_roll),
            spine_pitch: f(self.spine_pitch, o.spine_pitch),
            spine_roll: f(self.spine_roll, o.spine_roll),
            chest_pitch: f(self.chest_pitch, o.chest_pitch),
            chest_roll: f(self.chest_roll, o.chest_roll),
            chest_yaw: f(self.chest_yaw, o.chest_yaw),
            head_pitch: f(self.head_pitch, o.head_pitch),
            head_roll: f(self.head_roll, o.head_roll),
            head_yaw: f(self.head_yaw, o.head_yaw),
            left_foot: v(self.left_foot, o.left_foot),
            right_foot: v(self.right_foot, o.right_foot),
            left_point: f(self.left_point, o.left_point),
            right_point: f(self.right_point, o.right_point),
            feet_yaw: f(self.feet_yaw, o.feet_yaw),
            left_hand: v(self.left_hand, o.left_hand),
            right_hand: v(self.right_hand, o.right_hand),
            left_shrug: f(self.left_shrug, o.left_shrug),
            right_shrug: f(self.right_shrug, o.right_shrug),
        }
    }

    /// The pose mirrored left ↔ right (x flips, yaw and roll change sign).
    pub fn mirrored(&self) -> KeyPose {
        let m = |v: Vec3| Vec3::new(-v.x, v.y, v.z);
        KeyPose {
            hips: m(self.hips),
            hips_yaw: -self.hips_yaw,
            hips_pitch: self.hips_pitch,
            hips_roll: -self.hips_roll,
            spine_pitch: self.spine_pitch,
            spine_roll: -self.spine_roll,
            chest_pitch: self.chest_pitch,
            chest_roll: -self.chest_roll,
            chest_yaw: -self.chest_yaw,
            head_pitch: self.head_pitch,
            head_roll: -self.head_roll,
            head_yaw: -self.head_yaw,
            left_foot: m(self.right_foot),
            right_foot: m(self.left_foot),
            left_point: self.right_point,
            right_point: self.left_point,
            feet_yaw: self.feet_yaw,
            left_hand: m(self.right_hand),
            right_hand: m(self.left_hand),
            left_shrug: self.right_shrug,
            right_shrug: self.left_shrug,
        }
    }
}

/// Catmull-Rom weights and key indices at `t` for keys spaced `spacing` apart (ends clamped).
fn catmull_rom(len: usize, spacing: f32, t: f32) -> ([usize; 4], [f32; 4]) {
    let last = len.saturating_sub(1);
    let x = (t / spacing).clamp(0.0, last as f32);
    let i = (x.floor() as usize).min(last.saturating_sub(1));
    let u = x - i as f32;
    let k = |j: isize| j.clamp(0, last as isize) as usize;
    let u2 = u * u;
    let u3 = u2 * u;
    (
        [k(i as isize - 1), k(i as isize), k(i as isize + 1), k(i as isize + 2)],
        [-0.5 * u3 + u2 - 0.5 * u, 1.5 * u3 - 2.5 * u2 + 1.0, -1.5 * u3 + 2.0 * u2 + 0.5 * u, 0.5 * u3 - 0.5 * u2],
    )
}

/// Catmull-Rom interpolation of key poses spaced evenly in time: `keys[k]` is at `k * spacing`;
/// `t` in the same unit. Ends are clamped (the first and last keys repeat).
pub fn interpolate(keys: &[KeyPose], spacing: f32, t: f32) -> KeyPose {
    if keys.is_empty() {
        return KeyPose::default();
    }
    let (i, w) = catmull_rom(keys.len(), spacing, t);
    keys[i[0]].scaled(w[0]).add(&keys[i[1]].scaled(w[1])).add(&keys[i[2]].scaled(w[2])).add(&keys[i[3]].scaled(w[3]))
}

/// One channel of [`interpolate`], cheaply.
pub fn interpolate_channel(keys: &[KeyPose], spacing: f32, t: f32, channel: impl Fn(&KeyPose) -> f32) -> f32 {
    if keys.is_empty() {
        return 0.0;
    }
    let (i, w) = catmull_rom(keys.len(), spacing, t);
    (0..4).map(|j| w[j] * channel(&keys[i[j]])).sum()
}

/// Two-bone IK lives in the motion kernel.
pub use crate::motion::{two_bone, two_bone_rotations};

/// Local rotations and root translation of the canonical skeleton for one key pose, and the
/// height of the lowest foot joint (ankle or toe tip: the feet are always the lowest part of
/// these poses).
pub fn solve(skeleton: &Skeleton, pose: &KeyPose, standing_hips_height: f32) -> ([Quat; CANON_COUNT], Vec3, f32) {
    let mut local = [Quat::IDENTITY; CANON_COUNT];
    let root = solve_upper(skeleton, pose, standing_hips_height, &mut local);
    let legs = solve_legs(skeleton, pose, standing_hips_height);
    legs.write_into(&mut local);
    (local, root, legs.lowest)
}

/// Root position and hips rotation of a key pose.
fn root_and_hips(pose: &KeyPose, standing_hips_height: f32) -> (Vec3, Quat) {
    let root = Vec3::new(pose.hips.x, standing_hips_height + pose.hips.y, pose.hips.z);
    (root, Quat::from_euler(EulerRot::YXZ, pose.hips_yaw, pose.hips_pitch, -pose.hips_roll))
}

/// The joints [`solve_legs`] sets are the last eight canonical joints, left upper leg to right
/// toe, in [`LegSolution::local`] order.
const FIRST_LEG: usize = Canon::LeftUpperLeg as usize;
const _: () = assert!(CANON_COUNT - FIRST_LEG == 8 && Canon::RightToe as usize == CANON_COUNT - 1);

/// The legs of a solved pose. They depend only on the hips and the feet of the key pose
/// (position, turn and tilt of the hips, foot targets, pointing, turn-out), so poses that
/// differ only above the hips (the built-in moves' arm patterns) share them.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LegSolution {
    /// Local rotations of the leg joints (left upper leg, lower leg, foot, toe, then right).
    pub local: [Quat; 8],
    /// Height of the lowest foot joint (ankle or toe tip).
    pub lowest: f32,
}

impl LegSolution {
    /// Writes the leg joints' local rotations into a full pose.
    pub fn write_into(&self, local: &mut [Quat; CANON_COUNT]) {
        local[FIRST_LEG..].copy_from_slice(&self.local);
    }
}

/// Hips, spine, chest, neck, head and arms of a key pose: writes their local rotations (the
/// hips' included) and returns the root position.
pub fn solve_upper(skeleton: &Skeleton, pose: &KeyPose, standing_hips_height: f32, local: &mut [Quat; CANON_COUNT]) -> Vec3 {
    use Canon::*;
    let off = |c: Canon| skeleton.joints.get(c.index()).map(|j| j.rest_offset).unwrap_or(Vec3::ZERO);
    let mut world = [Quat::IDENTITY; CANON_COUNT];
    let (root, hips_q) = root_and_hips(pose, standing_hips_height);
    local[Hips.index()] = hips_q;
    world[Hips.index()] = hips_q;
    let set = |c: Canon, parent: Canon, l: Quat, world: &mut [Quat; CANON_COUNT], local: &mut [Quat; CANON_COUNT]| {
        local[c.index()] = l;
        world[c.index()] = world[parent.index()] * l;
    };
    set(Spine, Hips, Quat::from_euler(EulerRot::YXZ, pose.chest_yaw * 0.4, pose.spine_pitch, -pose.spine_roll), &mut world, local);
    set(Chest, Spine, Quat::from_euler(EulerRot::YXZ, pose.chest_yaw * 0.6, pose.chest_pitch, -pose.chest_roll), &mut world, local);
    set(Neck, Chest, Quat::from_euler(EulerRot::YXZ, pose.head_yaw * 0.4, pose.head_pitch * 0.4, -pose.head_roll * 0.4), &mut world, local);
    set(Head, Neck, Quat::from_euler(EulerRot::YXZ, pose.head_yaw * 0.6, pose.head_pitch * 0.6, -pose.head_roll * 0.6), &mut world, local);
    // World positions of the chain we need.
    let spine_p = root + world[Hips.index()] * off(Spine);
    let chest_p = spine_p + world[Spine.index()] * off(Chest);
    // Arms.
    for (sh, ua, fa, hand, target, shrug, s) in [
        (LeftShoulder, LeftUpperArm, LeftForearm, LeftHand, pose.left_hand, pose.left_shrug, 1.0f32),
        (RightShoulder, RightUpperArm, RightForearm, RightHand, pose.right_hand, pose.right_shrug, -1.0),
    ] {
        set(sh, Chest, Quat::from_rotation_z(s * shrug), &mut world, local);
        let sh_p = chest_p + world[Chest.index()] * off(sh);
        let ua_p = sh_p + world[sh.index()] * off(ua);
        let chest = world[Chest.index()];
        // Elbows bend down, back and out.
        let pole = chest * Vec3::new(s * 0.4, -1.0, -0.5);
        // Upper arm and forearm by the kernel's two-bone solver, each from its parent's frame.
        let arm = two_bone_rotations(ua_p, world[sh.index()], off(fa), off(hand), |upper| upper, ua_p + chest * target, pole);
        let (wq, fq) = (arm.upper, arm.lower);
        local[ua.index()] = world[sh.index()].inverse() * wq;
        world[ua.index()] = wq;
        local[fa.index()] = wq.inverse() * fq;
        world[fa.index()] = fq;
        local[hand.index()] = Quat::IDENTITY;
        world[hand.index()] = fq;
    }
    root
}

/// The legs of a key pose by two-bone IK onto the foot targets (see [`LegSolution`]).
pub fn solve_legs(skeleton: &Skeleton, pose: &KeyPose, standing_hips_height: f32) -> LegSolution {
    use Canon::*;
    let off = |c: Canon| skeleton.joints.get(c.index()).map(|j| j.rest_offset).unwrap_or(Vec3::ZERO);
    let (root, hips_q) = root_and_hips(pose, standing_hips_height);
    let mut out = LegSolution { local: [Quat::IDENTITY; 8], lowest: f32::MAX };
    for (side, (ul, ll, foot, toe, target, point, s)) in [
        (LeftUpperLeg, LeftLowerLeg, LeftFoot, LeftToe, pose.left_foot, pose.left_point, 1.0f32),
        (RightUpperLeg, RightLowerLeg, RightFoot, RightToe, pose.right_foot, pose.right_point, -1.0),
    ]
    .into_iter()
    .enumerate()
    {
        let hip_p = root + hips_q * off(ul);
        let ankle = Vec3::new(target.x, ANKLE_HEIGHT + target.y.max(0.0), target.z);
        let facing = Quat::from_rotation_y(pose.hips_yaw + s * pose.feet_yaw);
        let pole = facing * Vec3::new(s * 0.15, 0.0, 1.0);
        // Thigh and shin by the kernel's two-bone solver, each from its parent's frame.
        let leg = two_bone_rotations(hip_p, hips_q, off(ll), off(foot), |upper| upper, ankle, pole);
        let (knee, ank, uq, lq) = (leg.middle, leg.end, leg.upper, leg.lower);
        // Foot flat (toe along the facing on the floor) or pointed (toe along the shin).
        let flat = facing * off(toe);
        let shin = (ank - knee).normalize_or_zero() * off(toe).length();
        let toe_dir = flat.lerp(shin, point.clamp(0.0, 1.0) * 0.8);
        let fq = crate::motion::shortest_arc(lq * off(toe), toe_dir) * lq;
        out.local[side * 4] = hips_q.inverse() * uq;
        out.local[side * 4 + 1] = uq.inverse() * lq;
        out.local[side * 4 + 2] = lq.inverse() * fq;
        out.local[side * 4 + 3] = Quat::IDENTITY;
        out.lowest = out.lowest.min(ank.y).min((ank + fq * off(toe)).y);
    }
    out
}

/// Lowest joint height of a solved pose (root at `root`), without allocating.
pub fn lowest_height(skeleton: &Skeleton, local: &[Quat; CANON_COUNT], root: Vec3) -> f32 {
    let mut rot = [Quat::IDENTITY; CANON_COUNT];
    let mut pos = [Vec3::ZERO; CANON_COUNT];
    crate::motion::lowest_height(skeleton, local, root, &mut rot, &mut pos)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::canon::builtin::canonical_skeleton;

    #[test]
    fn planted_feet_reach_their_targets() {
        let sk = canonical_skeleton();
        let pose = KeyPose {
            hips: Vec3::new(0.05, -0.08, 0.0),
            left_foot: Vec3::new(0.2, 0.0, 0.1),
            right_foot: Vec3::new(-0.15, 0.0, -0.05),
            left_hand: Vec3::new(0.1, -0.4, 0.2),
            right_hand: Vec3::new(-0.1, 0.4, 0.1),
            ..Default::default()
        };
        let (local, root, lowest) = solve(&sk, &pose, 0.93);
        // FK.
        let mut rot = [Quat::IDENTITY; CANON_COUNT];
        let mut pos = [Vec3::ZERO; CANON_COUNT];
        for (i, j) in sk.joints.iter().enumerate() {
            match j.parent {
                None => {
                    rot[i] = local[i];
                    pos[i] = root;
                }
                Some(p) => {
                    rot[i] = rot[p] * local[i];
                    pos[i] = pos[p] + rot[p] * j.rest_offset;
                }
            }
        }
        let lf = pos[Canon::LeftFoot.index()];
        assert!((lf - Vec3::new(0.2, ANKLE_HEIGHT, 0.1)).length() < 1e-3, "{lf}");
        let rf = pos[Canon::RightFoot.index()];
        assert!((rf - Vec3::new(-0.15, ANKLE_HEIGHT, -0.05)).length() < 1e-3, "{rf}");
        // Knees bend forward.
        assert!(pos[Canon::LeftLowerLeg.index()].z > 0.0);
        // Toes near the floor, and the reported lowest point is the true one.
        assert!(pos[Canon::LeftToe.index()].y.abs() < 0.05);
        let true_low = pos.iter().map(|p| p.y).fold(f32::MAX, f32::min);
        assert!((true_low - lowest).abs() < 1e-4, "{true_low} vs {lowest}");
        assert!((lowest_height(&sk, &local, root) - lowest).abs() < 1e-4);
    }

    #[test]
    fn catmull_rom_passes_through_keys() {
        let keys: Vec<KeyPose> = (0..4).map(|k| KeyPose { hips_yaw: k as f32 * k as f32, ..Default::default() }).collect();
        for k in 0..4 {
            assert!((interpolate(&keys, 0.5, k as f32 * 0.5).hips_yaw - (k * k) as f32).abs() < 1e-5);
        }
    }
}
