//! The engine's own motion: the canonical humanoid skeleton and the built-in demo clip the app
//! opens on (no file needed, nothing from outside the project).

use crate::fmath;
use std::f32::consts::{PI, TAU};
use std::sync::Arc;

use glam::{EulerRot, Quat, Vec3};

use crate::clip::{Clip, TranslationTrack};
use crate::canon::humanoid::{Canon, CANON_COUNT};
// 0..1 → 0..1 with zero slope at both ends: the motion kernel's one easing curve.
use crate::motion::smoothstep as smooth;
use crate::skeleton::{Joint, Skeleton};

/// Rest offsets of the canonical skeleton (T-pose, facing +Z, the figure's left on +X),
/// for a 1.70 m body. Index = [`Canon::index`].
fn rest_offset(c: Canon) -> Vec3 {
    use Canon::*;
    match c {
        Hips => Vec3::new(0.0, 0.95, 0.0),
        Spine => Vec3::new(0.0, 0.10, 0.0),
        Chest => Vec3::new(0.0, 0.15, 0.0),
        Neck => Vec3::new(0.0, 0.22, 0.0),
        Head => Vec3::new(0.0, 0.12, 0.02),
        LeftShoulder => Vec3::new(0.03, 0.17, 0.0),
        RightShoulder => Vec3::new(-0.03, 0.17, 0.0),
        LeftUpperArm => Vec3::new(0.15, 0.0, 0.0),
        RightUpperArm => Vec3::new(-0.15, 0.0, 0.0),
        LeftForearm => Vec3::new(0.28, 0.0, 0.0),
        RightForearm => Vec3::new(-0.28, 0.0, 0.0),
        LeftHand => Vec3::new(0.25, 0.0, 0.0),
        RightHand => Vec3::new(-0.25, 0.0, 0.0),
        LeftUpperLeg => Vec3::new(0.09, -0.05, 0.0),
        RightUpperLeg => Vec3::new(-0.09, -0.05, 0.0),
        LeftLowerLeg | RightLowerLeg => Vec3::new(0.0, -0.42, 0.0),
        LeftFoot | RightFoot => Vec3::new(0.0, -0.40, 0.0),
        LeftToe | RightToe => Vec3::new(0.0, -0.06, 0.13),
    }
}

/// The canonical skeleton: exactly the 21 canonical joints, in [`Canon::ALL`] order.
pub fn canonical_skeleton() -> Skeleton {
    Skeleton {
        joints: Canon::ALL
            .iter()
            .map(|&c| Joint {
                name: c.name().to_string(),
                parent: c.parent().map(Canon::index),
                rest_offset: rest_offset(c),
                rest_rotation: Quat::IDENTITY,
                end_site: matches!(c, Canon::LeftToe | Canon::RightToe),
            })
            .collect(),
    }
}


/// Lowest joint height of a pose with the root at the origin.
pub fn lowest_point(skeleton: &Skeleton, local: &[Quat]) -> f32 {
    let n = skeleton.len();
    crate::motion::lowest_height(skeleton, local, Vec3::ZERO, &mut vec![Quat::IDENTITY; n], &mut vec![Vec3::ZERO; n])
}

/// A few bars of the built-in demo dance: step-touch side to side with a bounce on every
/// count, arms swinging across the body and a clap over the head on the last counts of the
/// phrase. 120 BPM, 60 fps, 8 counts (4 s), loops seamlessly.
pub fn demo_clip() -> Clip {
    let fps = 60.0;
    let bpm = 120.0;
    let counts = 8.0;
    let frames = (counts * 60.0 / bpm * fps) as usize;
    let skeleton = Arc::new(canonical_skeleton());
    let mut rotations = Vec::with_capacity(frames * CANON_COUNT);
    let mut root = Vec::with_capacity(frames);
    use Canon::*;
    for f in 0..frames {
        let beat = f as f32 / fps * bpm / 60.0; // 0..8
        let step = beat.floor() as i32;
        let within = beat - step as f32;
        // Side of the step: counts 0,1 → right; 2,3 → left; ...
        let side = if (step / 2) % 2 == 0 { 1.0 } else { -1.0 };
        let phase = (beat / 4.0) * TAU; // one full left-right cycle per 4 counts
        let sway = fmath::sin(phase); // -1..1 lateral position
        let bounce = fmath::cos(beat * TAU) * 0.5 + 0.5; // 1 on the count, 0 between
        let mut r = [Quat::IDENTITY; CANON_COUNT];
        // Weight shifts: the standing leg bends on the count (a bounce), the free leg touches.
        let knee = 0.25 + 0.2 * bounce;
        let free_lift = smooth(1.0 - (within * 2.0 - 1.0).abs()) * 0.35;
        let (stand_ul, stand_ll, free_ul, free_ll) = if sway >= 0.0 {
            (LeftUpperLeg, LeftLowerLeg, RightUpperLeg, RightLowerLeg)
        } else {
            (RightUpperLeg, RightLowerLeg, LeftUpperLeg, LeftLowerLeg)
        };
        r[stand_ul.index()] = Quat::from_rotation_x(-knee * 0.5);
        r[stand_ll.index()] = Quat::from_rotation_x(knee);
        r[free_ul.index()] = Quat::from_rotation_x(-knee * 0.5 - free_lift);
        r[free_ll.index()] = Quat::from_rotation_x(knee + free_lift * 1.6);
        // Feet flat-ish.
        r[LeftFoot.index()] = Quat::from_rotation_x(-0.1 * bounce);
        r[RightFoot.index()] = Quat::from_rotation_x(-0.1 * bounce);
        // Hips sway opposite to the step, torso counter-rotates, head settles.
        r[Hips.index()] = Quat::from_euler(EulerRot::YXZ, 0.25 * sway, 0.05 * bounce, -0.08 * sway);
        r[Spine.index()] = Quat::from_euler(EulerRot::YXZ, -0.12 * sway, 0.05, 0.05 * sway);
        r[Chest.index()] = Quat::from_euler(EulerRot::YXZ, -0.12 * sway, 0.03 * bounce, 0.04 * sway);
        r[Head.index()] = Quat::from_euler(EulerRot::YXZ, 0.1 * sway, -0.05 + 0.08 * bounce, 0.0);
        // Arms: down by the sides (from the T-pose) swinging across; clap overhead on 7-8.
        let clap = smooth(((beat - 6.0) * 2.0).clamp(0.0, 1.0)) * smooth(((8.0 - beat) * 3.0).clamp(0.0, 1.0));
        for (s, ua, fa, sh) in [(1.0, LeftUpperArm, LeftForearm, LeftShoulder), (-1.0, RightUpperArm, RightForearm, RightShoulder)] {
            let swing = 0.5 * fmath::sin(phase + if s > 0.0 { PI } else { 0.0 });
            let down = -s * (1.25 - 0.25 * bounce); // arms down by the sides
            let up = s * 1.35; // arms up over the head
            let z = down + (up - down) * clap;
            r[ua.index()] = Quat::from_euler(EulerRot::YZX, -s * (swing * (1.0 - clap) + 0.3 * clap), z, 0.0);
            r[fa.index()] = Quat::from_rotation_y(-s * (0.6 + 0.5 * bounce) * (1.0 - clap) - s * 0.4 * clap);
            r[sh.index()] = Quat::from_rotation_z(s * 0.15 * clap);
        }
        rotations.extend_from_slice(&r);
        let _ = side;
        // Put the lowest foot on the floor: the bounce comes from the bent knees.
        let lowest = lowest_point(&skeleton, &r);
        root.push(Vec3::new(0.22 * sway, 0.02 - lowest, 0.0));
    }
    Clip {
        name: "Step-touch & clap (built-in)".into(),
        source: "built-in".into(),
        fps,
        skeleton,
        rotations,
        translations: vec![TranslationTrack { joint: 0, values: root }],
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::canon::humanoid::{HumanoidMap, HumanoidStatus};

    #[test]
    fn canonical_skeleton_maps_onto_itself() {
        let sk = canonical_skeleton();
        let m = HumanoidMap::from_skeleton(&sk);
        for c in Canon::ALL {
            assert_eq!(m.get(c), Some(c.index()), "{c:?}");
        }
        assert_eq!(m.status(&sk, None), HumanoidStatus::Complete);
    }

    #[test]
    fn demo_moves_and_stays_on_the_floor() {
        let c = demo_clip();
        c.validate().unwrap();
        let a = c.world_positions(0);
        let b = c.world_positions(30);
        let moved: f32 = a.iter().zip(&b).map(|(x, y)| (*x - *y).length()).sum();
        assert!(moved > 0.5, "moved {moved}");
        for f in 0..c.frame_count() {
            let p = c.world_positions(f);
            let lowest = p.iter().map(|v| v.y).fold(f32::MAX, f32::min);
            assert!(lowest > -0.05 && lowest < 0.15, "frame {f}: lowest joint at {lowest}");
        }
    }
}
