//! Two-bone inverse kinematics for the legs (spec §I): during a join the planted foot stays
//! where it is and the hip and knee angles come from IK.
//!
//! The thigh and shin come from the engine's one two-bone solver,
//! [`crate::motion::two_bone_rotations`] (law of cosines, bending toward the knee's present
//! side, or forward for a straight leg; each bone turned by the shortest arc, so its twist is
//! kept); the foot takes the world orientation asked for (its own by default, so it stays
//! flat). Unreachable targets stretch the leg straight toward them.

use glam::{Quat, Vec3};

use crate::actions::contact::Foot;
use crate::motion::two_bone_rotations;
use crate::skeleton::Skeleton;

/// World rotations and positions of one pose of `skeleton` (root translation given, other
/// joints at their rest offsets), by [`crate::motion::WorldPose::of_rotations`].
pub fn forward(skeleton: &Skeleton, local: &[Quat], root: Vec3) -> (Vec<Quat>, Vec<Vec3>) {
    let mut pose = crate::motion::WorldPose::new();
    pose.of_rotations(skeleton, local, root);
    (pose.rotations, pose.positions)
}

/// Moves the ankle of `foot` to `target` by changing the hip and knee rotations of `local`
/// (canonical skeleton, root at `root`), keeping the foot's world orientation. Returns the
/// remaining distance, metres (0 when the target is reachable).
pub fn solve_leg(skeleton: &Skeleton, local: &mut [Quat], root: Vec3, foot: Foot, target: Vec3) -> f32 {
    solve_leg_oriented(skeleton, local, root, foot, target, None)
}

/// As [`solve_leg`], and the foot ends with world orientation `foot_world` when given (a
/// planted foot keeps the orientation it landed with, so its toe does not swivel either).
pub fn solve_leg_oriented(skeleton: &Skeleton, local: &mut [Quat], root: Vec3, foot: Foot, target: Vec3, foot_world: Option<Quat>) -> f32 {
    let [hip, knee, ankle] = foot.chain().map(|c| c.index());
    if local.len() <= ankle || skeleton.len() <= ankle || !target.is_finite() {
        return f32::INFINITY;
    }
    let hip_parent = skeleton.joints[hip].parent.unwrap_or(0);
    let (rot, pos) = forward(skeleton, local, root);
    let (h, k, a) = (pos[hip], pos[knee], pos[ankle]);
    let foot_world = foot_world.unwrap_or(rot[ankle]);
    let (l1, l2) = ((k - h).length(), (a - k).length());
    if l1 < 1e-5 || l2 < 1e-5 {
        return (a - target).length();
    }
    // Bend toward the side the knee is on now; a straight leg bends forward (the hips' +Z,
    // the way a knee flexes on the canonical skeleton).
    let along = (a - h).normalize_or_zero();
    let side = (k - h) - along * (k - h).dot(along);
    let pole = side + rot[hip_parent] * Vec3::Z * 0.01;
    // Thigh onto the new knee, shin (carried by the thigh) onto the new ankle.
    let knee_local = local[knee];
    let legs = two_bone_rotations(h, rot[hip], skeleton.joints[knee].rest_offset, skeleton.joints[ankle].rest_offset, |thigh| thigh * knee_local, target, pole);
    local[hip] = (rot[hip_parent].inverse() * legs.upper).normalize();
    local[knee] = (legs.upper.inverse() * legs.lower).normalize();
    local[ankle] = (legs.lower.inverse() * foot_world).normalize();
    let (_, pos) = forward(skeleton, local, root);
    (pos[ankle] - target).length()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::canon::builtin::canonical_skeleton;
    use crate::canon::humanoid::{Canon, CANON_COUNT};

    #[test]
    fn reaches_a_reachable_target_and_keeps_the_foot_orientation() {
        let sk = canonical_skeleton();
        let mut local = vec![Quat::IDENTITY; CANON_COUNT];
        local[Canon::LeftLowerLeg.index()] = Quat::from_rotation_x(0.3);
        let root = Vec3::new(0.0, 0.95, 0.0);
        let (rot0, pos0) = forward(&sk, &local, root);
        let target = pos0[Canon::LeftFoot.index()] + Vec3::new(0.05, 0.12, 0.1);
        let err = solve_leg(&sk, &mut local, root, Foot::Left, target);
        assert!(err < 1e-3, "error {err}");
        let (rot1, pos1) = forward(&sk, &local, root);
        assert!((pos1[Canon::LeftFoot.index()] - target).length() < 1e-3);
        assert!(rot1[Canon::LeftFoot.index()].angle_between(rot0[Canon::LeftFoot.index()]) < 1e-3);
        // Knee bends forward (the knee joint moves to +Z of the hip-ankle line).
        let mid = 0.5 * (pos1[Canon::LeftUpperLeg.index()] + pos1[Canon::LeftFoot.index()]);
        assert!(pos1[Canon::LeftLowerLeg.index()].z > mid.z);
        // Unreachable: stretched toward it, error reported.
        let far = root + Vec3::new(0.0, -3.0, 0.0);
        assert!(solve_leg(&sk, &mut local, root, Foot::Left, far) > 1.0);
    }
}
