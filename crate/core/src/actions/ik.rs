//! Two-bone inverse kinematics for the legs (spec §I): during a join the planted foot stays
//! where it is and the hip and knee angles come from IK.
//!
//! Analytic: the knee bends about its own hinge (the upper leg's X axis, the axis the knee
//! flexes about on the canonical skeleton) until hip-to-ankle distance equals hip-to-target,
//! then the thigh swings to point the ankle at the target; the foot keeps its world
//! orientation so it stays flat. Unreachable targets stretch the leg straight toward them.

use glam::{Quat, Vec3};

use crate::actions::contact::Foot;
use crate::skeleton::Skeleton;

/// World rotations and positions of one pose of `skeleton` (root translation given, other
/// joints at their rest offsets).
pub fn forward(skeleton: &Skeleton, local: &[Quat], root: Vec3) -> (Vec<Quat>, Vec<Vec3>) {
    let n = skeleton.len().min(local.len());
    let mut rot = vec![Quat::IDENTITY; n];
    let mut pos = vec![Vec3::ZERO; n];
    crate::motion::local_to_world_at(skeleton, local, root, &mut rot, &mut pos);
    (rot, pos)
}

/// Moves the ankle of `foot` to `target` by changing the hip and knee rotations of `local`
/// (canonical skeleton, root at `root`). Returns the remaining distance, metres (0 when the
/// target is reachable).
pub fn solve_leg(skeleton: &Skeleton, local: &mut [Quat], root: Vec3, foot: Foot, target: Vec3) -> f32 {
    let [hip, knee, ankle] = foot.chain().map(|c| c.index());
    if local.len() <= ankle || skeleton.len() <= ankle {
        return f32::INFINITY;
    }
    let hip_parent = skeleton.joints[hip].parent.unwrap_or(0);
    for _ in 0..3 {
        let (rot, pos) = forward(skeleton, local, root);
        let (h, k, a) = (pos[hip], pos[knee], pos[ankle]);
        let foot_world = rot[ankle];
        let l1 = (k - h).length();
        let l2 = (a - k).length();
        if l1 < 1e-5 || l2 < 1e-5 {
            return (a - target).length();
        }
        let want = (target - h).length().clamp((l1 - l2).abs() + 1e-4, l1 + l2 - 1e-4);
        let have = (a - h).length();
        let interior = |d: f32| ((l1 * l1 + l2 * l2 - d * d) / (2.0 * l1 * l2)).clamp(-1.0, 1.0).acos();
        let delta = interior(have) - interior(want);
        // Knee: more flexion about the thigh's X axis shrinks the interior angle.
        local[knee] = (Quat::from_rotation_x(delta) * local[knee]).normalize();
        // Thigh: point the ankle at the target.
        let (rot2, pos2) = forward(skeleton, local, root);
        let from = (pos2[ankle] - pos2[hip]).normalize_or_zero();
        let to = (target - pos2[hip]).normalize_or_zero();
        if from != Vec3::ZERO && to != Vec3::ZERO {
            let w_thigh = Quat::from_rotation_arc(from, to) * rot2[hip];
            local[hip] = (rot2[hip_parent].inverse() * w_thigh).normalize();
        }
        // Foot keeps its world orientation.
        let (rot3, _) = forward(skeleton, local, root);
        local[ankle] = (rot3[knee].inverse() * foot_world).normalize();
    }
    let (_, pos) = forward(skeleton, local, root);
    (pos[ankle] - target).length()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::builtin::canonical_skeleton;
    use crate::humanoid::{Canon, CANON_COUNT};

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
