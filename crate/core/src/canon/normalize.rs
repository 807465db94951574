//! Normalisation of canonical joint positions (spec §B): the origin moves to the midpoint of
//! the hips (or of the shoulders, for arm-only work), each frame is turned about the vertical
//! so the ground projection of the right-hip → left-hip vector points along +Z (the paper's
//! choice), and distances are divided by body height. Per frame, so turning in place is not a
//! difference (paper 002 §4.4); by height, so dancers of different sizes match (§4.5).

use crate::fmath;
use glam::{Quat, Vec3};
use serde::{Deserialize, Serialize};

use crate::canon::humanoid::{Canon, CANON_COUNT};

/// Which midpoint becomes the origin.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "camelCase")]
pub enum Origin {
    /// Midpoint of the two hip joints (upper legs): whole-body work.
    #[default]
    Hips,
    /// Midpoint of the two shoulders (upper arms): arm-only searches (spec §B.1).
    Shoulders,
}

/// Body height used for scaling: the median over frames of the summed lengths of the
/// spine chain (hips → head) and the mean leg (upper leg → foot). Pose-independent, unlike
/// the head's height above the floor.
pub fn body_height(positions: &[Vec3]) -> f32 {
    use Canon::*;
    let frames = positions.len() / CANON_COUNT;
    if frames == 0 {
        return 1.0;
    }
    let mut h: Vec<f32> = (0..frames)
        .map(|f| {
            let p = |c: Canon| positions[f * CANON_COUNT + c.index()];
            let d = |a: Canon, b: Canon| (p(a) - p(b)).length();
            let spine = d(Hips, Spine) + d(Spine, Chest) + d(Chest, Neck) + d(Neck, Head);
            let leg_l = d(LeftUpperLeg, LeftLowerLeg) + d(LeftLowerLeg, LeftFoot);
            let leg_r = d(RightUpperLeg, RightLowerLeg) + d(RightLowerLeg, RightFoot);
            spine + 0.5 * (leg_l + leg_r)
        })
        .filter(|v| v.is_finite())
        .collect();
    if h.is_empty() {
        return 1.0;
    }
    h.sort_by(f32::total_cmp);
    let m = h[h.len() / 2];
    if m > 1e-6 {
        m
    } else {
        1.0
    }
}

/// The rotation about +Y that takes the ground projection of `right → left` onto +Z.
pub fn facing_rotation(right: Vec3, left: Vec3) -> Quat {
    let v = left - right;
    let (x, z) = (v.x, v.z);
    if x * x + z * z < 1e-12 {
        return Quat::IDENTITY;
    }
    // Angle of v in the ground plane measured from +Z towards +X; rotate by its negative.
    let angle = fmath::atan2(x, z);
    Quat::from_rotation_y(-angle)
}

/// Normalises frames of canonical positions (`frames * CANON_COUNT`) in place.
/// `height` is the body height to divide by (see [`body_height`]).
pub fn normalize_in_place(positions: &mut [Vec3], origin: Origin, height: f32) {
    let inv = if height > 1e-6 { 1.0 / height } else { 1.0 };
    let (a, b) = match origin {
        Origin::Hips => (Canon::RightUpperLeg, Canon::LeftUpperLeg),
        Origin::Shoulders => (Canon::RightUpperArm, Canon::LeftUpperArm),
    };
    for frame in positions.chunks_exact_mut(CANON_COUNT) {
        let (r, l) = (frame[a.index()], frame[b.index()]);
        let o = (r + l) * 0.5;
        // Facing always from the hips, so arm-only searches still see a body-relative frame.
        let rot = facing_rotation(frame[Canon::RightUpperLeg.index()], frame[Canon::LeftUpperLeg.index()]);
        for p in frame.iter_mut() {
            *p = rot * (*p - o) * inv;
        }
    }
}

/// Normalised copy.
pub fn normalized(positions: &[Vec3], origin: Origin) -> Vec<Vec3> {
    let h = body_height(positions);
    let mut v = positions.to_vec();
    normalize_in_place(&mut v, origin, h);
    v
}

#[cfg(test)]
mod tests {
    use super::*;

    fn figure(offset: Vec3, yaw: f32, scale: f32) -> Vec<Vec3> {
        // A crude standing figure on the canonical joints.
        let mut p = vec![Vec3::ZERO; CANON_COUNT];
        use Canon::*;
        let set = |p: &mut Vec<Vec3>, c: Canon, v: Vec3| p[c.index()] = v;
        set(&mut p, Hips, Vec3::new(0.0, 1.0, 0.0));
        set(&mut p, Spine, Vec3::new(0.0, 1.15, 0.0));
        set(&mut p, Chest, Vec3::new(0.0, 1.3, 0.0));
        set(&mut p, Neck, Vec3::new(0.0, 1.5, 0.0));
        set(&mut p, Head, Vec3::new(0.0, 1.65, 0.05));
        for (s, sh, ua, fa, h, ul, ll, f, t) in [
            (1.0, LeftShoulder, LeftUpperArm, LeftForearm, LeftHand, LeftUpperLeg, LeftLowerLeg, LeftFoot, LeftToe),
            (-1.0, RightShoulder, RightUpperArm, RightForearm, RightHand, RightUpperLeg, RightLowerLeg, RightFoot, RightToe),
        ] {
            set(&mut p, sh, Vec3::new(0.05 * s, 1.45, 0.0));
            set(&mut p, ua, Vec3::new(0.18 * s, 1.45, 0.0));
            set(&mut p, fa, Vec3::new(0.2 * s, 1.15, 0.0));
            set(&mut p, h, Vec3::new(0.22 * s, 0.9, 0.1));
            set(&mut p, ul, Vec3::new(0.1 * s, 0.95, 0.0));
            set(&mut p, ll, Vec3::new(0.1 * s, 0.5, 0.0));
            set(&mut p, f, Vec3::new(0.1 * s, 0.08, 0.0));
            set(&mut p, t, Vec3::new(0.1 * s, 0.02, 0.12));
        }
        let q = Quat::from_rotation_y(yaw);
        p.iter().map(|v| q * (*v * scale) + offset).collect()
    }

    #[test]
    fn invariant_to_position_facing_and_size() {
        let a = normalized(&figure(Vec3::ZERO, 0.0, 1.0), Origin::Hips);
        let b = normalized(&figure(Vec3::new(3.0, 0.0, -2.0), 2.1, 1.13), Origin::Hips);
        for (x, y) in a.iter().zip(&b) {
            assert!((*x - *y).length() < 1e-4, "{x} vs {y}");
        }
        // Hip vector along +Z after normalisation.
        let l = a[Canon::LeftUpperLeg.index()];
        assert!(l.z > 0.0 && l.x.abs() < 1e-5);
    }
}
