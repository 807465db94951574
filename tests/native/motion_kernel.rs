//! The motion kernel (`odori_core::motion`, its one entry point `WorldPose`) in place of the
//! copies it replaced: the forward kinematics of `Skeleton::forward_kinematics`, `pose_into`,
//! `posed_at_origin` and `Clip::world_matrices_into` (since folded into `WorldPose`'s
//! `of_locals`, `of_rotations`, `of_frame` and `matrices_into`), `actions::ik::forward`, the lowest-point functions of
//! `builtin.rs` and `library/pose.rs`, and the Hermite curve of the choreography's joins. Each
//! removed copy is kept here, as it was, as the reference; on real clips (CMU salsa's 43-joint
//! BVH rig, Xbot's and RobotExpressive's glTF rigs with rest rotations, the built-in moves) the
//! kernel gives the same bits (the same arithmetic in the same order) — or, for the world
//! matrices, which the copy built as a product of matrices and the kernel builds from the
//! world rotation and position, the same within 1e-5.
//! One two-bone IK solver: `motion::two_bone_rotations` in place of the joins' leg IK
//! (`actions::ik::solve_leg`) and of the retargeting's own swing of thigh and shin
//! (`character.rs`), both kept here as they were: the same rotations within 1e-4 rad and the
//! same ankle within 1e-5 m, on the legs of the canonical rig, Xbot and RobotExpressive. The two
//! IK copies are as they were but for the arc: they take the kernel's `motion::shortest_arc`
//! where they took glam's `Quat::from_rotation_arc`, which returns the identity for arcs under
//! about 7e-4 rad (a thigh that should turn 3e-4 rad stays, and the ankle misses by 0.2–0.3 mm;
//! the kernel's unit tests cover the arc and that miss). So this compares the algorithm (where
//! each solver aims each bone), not glam's dead zone: with it, the kernel (aiming the shin from
//! the solver's knee) and the old retargeting copy (from the knee the turned thigh gives)
//! missed differently, by 2.5e-4 rad and 2.9e-4 m when the random targets hit such an arc.

use glam::{Mat4, Quat, Vec3};
use odori_core::import::{import_bytes, ImportOptions};
use odori_core::library::pose::lowest_height;
use odori_core::motion::{shortest_arc, WorldPose};
use odori_core::{Clip, Skeleton};
use odori_tests::{fps_override_for, read};

/// `Skeleton::forward_kinematics` before the kernel.
fn old_forward_kinematics(sk: &Skeleton, local_rotations: &[Quat], local_translations: &[Vec3], positions: &mut Vec<Vec3>, mut matrices: Option<&mut Vec<Mat4>>) {
    let n = sk.len().min(local_rotations.len()).min(local_translations.len());
    positions.clear();
    let mut rots: Vec<Quat> = Vec::with_capacity(n);
    if let Some(m) = matrices.as_deref_mut() {
        m.clear();
    }
    for i in 0..n {
        let (r, p) = match sk.joints[i].parent {
            None => (local_rotations[i], local_translations[i]),
            Some(p) => (rots[p] * local_rotations[i], positions[p] + rots[p] * local_translations[i]),
        };
        rots.push(r);
        positions.push(p);
        if let Some(m) = matrices.as_deref_mut() {
            m.push(Mat4::from_rotation_translation(r, p));
        }
    }
}

/// `Skeleton::pose_into` before the kernel.
fn old_pose_into(sk: &Skeleton, local: &[Quat], root: Vec3, rot: &mut [Quat], pos: &mut [Vec3]) {
    let n = sk.len().min(local.len()).min(rot.len()).min(pos.len());
    for (i, j) in sk.joints.iter().enumerate().take(n) {
        match j.parent {
            Some(p) if p < i => {
                rot[i] = rot[p] * local[i];
                pos[i] = pos[p] + rot[p] * j.rest_offset;
            }
            _ => {
                rot[i] = local[i];
                pos[i] = root;
            }
        }
    }
}

/// `Clip::world_matrices_into` before the kernel (a product of local matrices).
fn old_world_matrices(clip: &Clip, frame: usize) -> Vec<Mat4> {
    let local = clip.frame_rotations(frame);
    let mut trans = Vec::new();
    clip.local_translations_into(frame, &mut trans);
    let mut out: Vec<Mat4> = Vec::new();
    for (i, j) in clip.skeleton.joints.iter().enumerate() {
        let m = Mat4::from_rotation_translation(local[i], trans[i]);
        let w = match j.parent {
            None => m,
            Some(p) => out[p] * m,
        };
        out.push(w);
    }
    out
}

/// `actions::ik::forward` before the kernel.
fn old_ik_forward(sk: &Skeleton, local: &[Quat], root: Vec3) -> (Vec<Quat>, Vec<Vec3>) {
    let n = sk.len().min(local.len());
    let mut rot: Vec<Quat> = Vec::with_capacity(n);
    let mut pos: Vec<Vec3> = Vec::with_capacity(n);
    for i in 0..n {
        let j = &sk.joints[i];
        match j.parent {
            Some(p) if p < i => {
                rot.push(rot[p] * local[i]);
                pos.push(pos[p] + rot[p] * j.rest_offset);
            }
            _ => {
                rot.push(local[i]);
                pos.push(if i == 0 { root } else { j.rest_offset });
            }
        }
    }
    (rot, pos)
}

/// The choreography's Hermite before the kernel.
fn old_hermite(p0: [f32; 4], m0: [f32; 4], p1: [f32; 4], m1: [f32; 4], s: f32) -> [f32; 4] {
    let s2 = s * s;
    let s3 = s2 * s;
    let h00 = 2.0 * s3 - 3.0 * s2 + 1.0;
    let h10 = s3 - 2.0 * s2 + s;
    let h01 = -2.0 * s3 + 3.0 * s2;
    let h11 = s3 - s2;
    std::array::from_fn(|i| h00 * p0[i] + h10 * m0[i] + h01 * p1[i] + h11 * m1[i])
}

/// The glTF importer's CUBICSPLINE value before the kernel (tangents scaled by `dt` inside).
fn old_cubic(v0: [f32; 4], b0: [f32; 4], v1: [f32; 4], a1: [f32; 4], dt: f32, s: f32) -> [f32; 4] {
    let (s2, s3) = (s * s, s * s * s);
    let h00 = 2.0 * s3 - 3.0 * s2 + 1.0;
    let h10 = s3 - 2.0 * s2 + s;
    let h01 = -2.0 * s3 + 3.0 * s2;
    let h11 = s3 - s2;
    std::array::from_fn(|i| h00 * v0[i] + h10 * dt * b0[i] + h01 * v1[i] + h11 * dt * a1[i])
}

/// Real clips on four rigs: CMU salsa (BVH), Xbot and RobotExpressive (glTF rest rotations,
/// several roots for the robot), and every 10th built-in move (canonical).
fn clips() -> Vec<Clip> {
    let mut out = Vec::new();
    let rel = "mocap/cmu-salsa/salsa_01.bvh";
    let im = import_bytes(rel, &read(rel), &ImportOptions { fps_override: fps_override_for(rel), ..Default::default() }).unwrap();
    out.push(im.clips[0].slice(0, 600, "salsa_01 (10 s)"));
    for rel in ["gltf/Xbot.glb", "gltf/RobotExpressive.glb"] {
        let im = import_bytes(rel, &read(rel), &ImportOptions::default()).unwrap();
        out.extend(im.clips.into_iter().take(4));
    }
    out.extend(odori_core::library::builtin_clips().into_iter().step_by(10));
    out
}

#[test]
fn forward_kinematics_pose_and_lowest_points_are_bit_identical() {
    let clips = clips();
    assert!(clips.len() >= 20, "{} clips", clips.len());
    let (mut frames, mut joints) = (0usize, 0usize);
    for clip in &clips {
        let sk = &*clip.skeleton;
        let n = sk.len();
        let mut trans = Vec::new();
        let (mut pa, mut pb, mut ma, mut mb) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
        let mut pose = WorldPose::new();
        for f in (0..clip.frame_count()).step_by(3) {
            let local = clip.frame_rotations(f);
            clip.local_translations_into(f, &mut trans);
            let posed = pose.of_locals(sk, local, &trans);
            posed.matrices_into(&mut ma);
            pa.clone_from(&posed.positions);
            old_forward_kinematics(sk, local, &trans, &mut pb, Some(&mut mb));
            assert_eq!(pa, pb, "'{}' frame {f}: forward_kinematics positions", clip.name);
            assert_eq!(ma, mb, "'{}' frame {f}: forward_kinematics matrices", clip.name);

            let root = clip.root_translation(f);
            let (mut rb, mut qb) = (vec![Quat::IDENTITY; n], vec![Vec3::ZERO; n]);
            let posed = pose.of_rotations(sk, local, root);
            let (ra, qa) = (&posed.rotations, &posed.positions);
            old_pose_into(sk, local, root, &mut rb, &mut qb);
            assert_eq!((ra, qa), (&rb, &qb), "'{}' frame {f}: pose_into", clip.name);

            // posed_at_origin and builtin::lowest_point: rest offsets, root at the origin.
            let offsets: Vec<Vec3> = sk.joints.iter().map(|j| if j.parent.is_some() { j.rest_offset } else { Vec3::ZERO }).collect();
            let mut origin = Vec::new();
            old_forward_kinematics(sk, local, &offsets, &mut origin, None);
            assert_eq!(pose.of_rotations(sk, local, Vec3::ZERO).positions, origin, "'{}' frame {f}: posed_at_origin", clip.name);
            let lowest = origin.iter().map(|p| p.y).fold(f32::MAX, f32::min);
            assert_eq!(odori_core::canon::builtin::lowest_point(sk, local).to_bits(), lowest.to_bits(), "'{}' frame {f}: lowest_point", clip.name);
            frames += 1;
            joints += n;
        }
    }
    println!("forward kinematics: {frames} frames, {joints} joints of {} clips, bit-identical", clips.len());
}

#[test]
fn canonical_pose_helpers_are_bit_identical() {
    // ik::forward and library::pose::lowest_height take canonical poses.
    let mut checked = 0;
    for clip in odori_core::library::builtin_clips().into_iter().step_by(7) {
        let sk = &*clip.skeleton;
        for f in (0..clip.frame_count()).step_by(5) {
            let local = clip.frame_rotations(f);
            let root = clip.root_translation(f);
            assert_eq!(odori_core::actions::ik::forward(sk, local, root), old_ik_forward(sk, local, root), "'{}' frame {f}: ik::forward", clip.name);
            let arr: [Quat; odori_core::canon::humanoid::CANON_COUNT] = local.try_into().unwrap();
            let (mut rot, mut pos) = ([Quat::IDENTITY; 21], [Vec3::ZERO; 21]);
            old_pose_into(sk, local, root, &mut rot, &mut pos);
            let old = pos.iter().map(|p| p.y).fold(f32::MAX, f32::min);
            assert_eq!(lowest_height(sk, &arr, root).to_bits(), old.to_bits(), "'{}' frame {f}: lowest_height", clip.name);
            checked += 1;
        }
    }
    assert!(checked > 100, "{checked} poses");
}

#[test]
fn world_matrices_match_the_matrix_product_within_1e5() {
    let mut worst = 0.0f32;
    let mut out = Vec::new();
    let mut pose = WorldPose::new();
    for clip in clips() {
        for f in (0..clip.frame_count()).step_by(5) {
            pose.of_frame(&clip, f).matrices_into(&mut out);
            let old = old_world_matrices(&clip, f);
            assert_eq!(out.len(), old.len());
            for (a, b) in out.iter().zip(&old) {
                for (x, y) in a.to_cols_array().iter().zip(b.to_cols_array()) {
                    worst = worst.max((x - y).abs() / y.abs().max(1.0));
                }
            }
        }
    }
    println!("world matrices: worst difference from the matrix product {worst:e} (relative, metres above 1)");
    assert!(worst < 1e-5, "{worst}");
}

#[test]
fn one_hermite_curve() {
    // The kernel's curve is the joins' copy bit for bit, and the importer's CUBICSPLINE (which
    // scaled the tangents inside the sum) within 1e-5, over a grid of values and tangents.
    let mut worst = 0.0f32;
    let mut k = 0u32;
    let mut next = || {
        k = k.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
        (k >> 8) as f32 / (1u32 << 24) as f32 * 4.0 - 2.0
    };
    for _ in 0..2000 {
        let v: [[f32; 4]; 4] = std::array::from_fn(|_| std::array::from_fn(|_| next()));
        let s = (next() + 2.0) / 4.0;
        let dt = (next() + 2.0) / 4.0 + 0.01;
        let a = odori_core::motion::hermite(v[0], v[1], v[2], v[3], s);
        assert_eq!(a.map(f32::to_bits), old_hermite(v[0], v[1], v[2], v[3], s).map(f32::to_bits));
        let c = odori_core::motion::hermite(v[0], v[1].map(|x| dt * x), v[2], v[3].map(|x| dt * x), s);
        let o = old_cubic(v[0], v[1], v[2], v[3], dt, s);
        for (x, y) in c.iter().zip(o) {
            worst = worst.max((x - y).abs());
        }
    }
    assert!(worst < 1e-5, "{worst}");
}

/// `actions::ik::solve_leg_oriented` before the kernel's rotation solver (positions from FK,
/// the thigh and shin turned inline), canonical skeleton, left or right leg.
fn old_solve_leg(sk: &Skeleton, local: &mut [Quat], root: Vec3, [hip, knee, ankle]: [usize; 3], target: Vec3) -> (f32, f32) {
    let hip_parent = sk.joints[hip].parent.unwrap_or(0);
    let (rot, pos) = odori_core::actions::ik::forward(sk, local, root);
    let (h, k, a) = (pos[hip], pos[knee], pos[ankle]);
    let foot_world = rot[ankle];
    let (l1, l2) = ((k - h).length(), (a - k).length());
    let along = (a - h).normalize_or_zero();
    let side = (k - h) - along * (k - h).dot(along);
    let pole = side + rot[hip_parent] * Vec3::Z * 0.01;
    let (k2, a2) = odori_core::motion::two_bone(h, target, l1, l2, pole);
    let thigh = (shortest_arc((k - h) / l1, ((k2 - h) / l1).normalize_or_zero()) * rot[hip]).normalize();
    local[hip] = (rot[hip_parent].inverse() * thigh).normalize();
    let shin0 = thigh * local[knee];
    let dir0 = (shin0 * sk.joints[ankle].rest_offset).normalize_or_zero();
    let dir1 = (a2 - k2).normalize_or_zero();
    let shin = if dir0 != Vec3::ZERO && dir1 != Vec3::ZERO { (shortest_arc(dir0, dir1) * shin0).normalize() } else { shin0 };
    local[knee] = (thigh.inverse() * shin).normalize();
    local[ankle] = (shin.inverse() * foot_world).normalize();
    let (_, pos) = odori_core::actions::ik::forward(sk, local, root);
    let widest = (k - h).angle_between(k2 - h).max(dir0.angle_between(dir1));
    ((pos[ankle] - target).length(), widest)
}

/// The retargeting's held-foot IK before the kernel's rotation solver (`character.rs`): the
/// thigh (world rotation `thigh`, at `hip`) swung onto the two-bone knee, then the shin (its
/// world rotation `shin` from the transfer) onto the ankle from where the turned thigh puts
/// the knee. Returns the new world rotations of thigh and shin, and the ankle.
fn old_retarget_leg(hip: Vec3, thigh: Quat, thigh_local: Vec3, shin: Quat, shin_local: Vec3, goal: Vec3) -> (Quat, Quat, Vec3, f32) {
    let knee_now = thigh * thigh_local;
    let ik = odori_core::motion::two_bone(hip, goal, thigh_local.length(), shin_local.length(), knee_now);
    let swing = |g: Quat, bone: Vec3, aim: Vec3| match (bone.try_normalize(), aim.try_normalize()) {
        (Some(a), Some(b)) => (shortest_arc(a, b) * g).normalize(),
        _ => g,
    };
    let widest = knee_now.angle_between(ik.0 - hip);
    let thigh = swing(thigh, knee_now, ik.0 - hip);
    let knee = hip + thigh * thigh_local;
    let widest = widest.max((shin * shin_local).angle_between(ik.1 - knee));
    let shin = swing(shin, shin * shin_local, ik.1 - knee);
    (thigh, shin, knee + shin * shin_local, widest)
}

#[test]
fn one_two_bone_solver_for_joins_and_retargeting() {
    use odori_core::actions::ik::solve_leg;
    use odori_core::actions::Foot;
    use odori_core::canon::humanoid::{Canon, HumanoidMap};
    let mut k = 7u32;
    let mut next = || {
        k = k.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
        (k >> 8) as f32 / (1u32 << 24) as f32 * 2.0 - 1.0
    };
    // A shortest arc between nearly opposite directions has an ill-defined axis: the same
    // solve by rounding-different inputs may roll the bone differently there. Rotations are
    // compared where every arc is under 170°; positions everywhere.
    const WELL_POSED_RAD: f32 = 170.0 * std::f32::consts::PI / 180.0;
    let (mut worst_rad, mut worst_m, mut cases, mut ill_posed) = (0.0f32, 0.0f32, 0, 0);
    // The angle between two rotations from the distance of their quaternions (2·|q − ±p| for
    // small angles): `Quat::angle_between` takes an acos of a dot product near 1, which in f32
    // cannot tell apart rotations closer than about 1e-3 rad.
    let apart = |a: Quat, b: Quat| 2.0 * (a - b).length().min((a + b).length());
    // The joins' leg IK on the canonical skeleton: poses of the built-in moves, targets near
    // the ankle (reachable) and far (stretched).
    let canon = odori_core::canon::builtin::canonical_skeleton();
    for clip in odori_core::library::builtin_clips().into_iter().step_by(25) {
        for f in (0..clip.frame_count()).step_by(17) {
            let root = clip.root_translation(f);
            for foot in [Foot::Left, Foot::Right] {
                let chain = foot.chain().map(|c| c.index());
                let (_, pos) = odori_core::actions::ik::forward(&canon, clip.frame_rotations(f), root);
                let reach = if cases % 5 == 0 { 1.5 } else { 0.2 };
                let target = pos[chain[2]] + Vec3::new(next(), next(), next()) * reach;
                let mut a = clip.frame_rotations(f).to_vec();
                let mut b = a.clone();
                let ea = solve_leg(&canon, &mut a, root, foot, target);
                let (eb, widest) = old_solve_leg(&canon, &mut b, root, chain, target);
                if widest < WELL_POSED_RAD {
                    for j in chain {
                        worst_rad = worst_rad.max(apart(a[j], b[j]));
                    }
                } else {
                    ill_posed += 1;
                }
                worst_m = worst_m.max((ea - eb).abs());
                cases += 1;
            }
        }
    }
    // The retargeting's held legs on real rigs: each leg at rest turned by random rotations.
    for rel in ["gltf/Xbot.glb", "gltf/RobotExpressive.glb"] {
        let im = import_bytes(rel, &read(rel), &ImportOptions::default()).unwrap();
        let sk = &im.skeleton;
        let map = HumanoidMap::from_skeleton(sk);
        let (rest_rot, rest_pos) = odori_core::motion::rest_world(sk);
        for (a, b, c) in [(Canon::LeftUpperLeg, Canon::LeftLowerLeg, Canon::LeftFoot), (Canon::RightUpperLeg, Canon::RightLowerLeg, Canon::RightFoot)] {
            let (hip, knee, foot) = (map.get(a).unwrap(), map.get(b).unwrap(), map.get(c).unwrap());
            let thigh_local = rest_rot[hip].inverse() * (rest_pos[knee] - rest_pos[hip]);
            let shin_local = rest_rot[knee].inverse() * (rest_pos[foot] - rest_pos[knee]);
            let leg = thigh_local.length() + shin_local.length();
            for _ in 0..500 {
                let turn = |v: [f32; 3]| Quat::from_scaled_axis(Vec3::from_array(v) * 0.8);
                let thigh = (turn([next(), next(), next()]) * rest_rot[hip]).normalize();
                let shin = (turn([next(), next(), next()]) * rest_rot[knee]).normalize();
                let goal = rest_pos[hip] + Vec3::new(next() * 0.5, -0.3 - next().abs() * 0.9, next() * 0.5) * leg;
                let (t0, s0, end0, widest) = old_retarget_leg(rest_pos[hip], thigh, thigh_local, shin, shin_local, goal);
                let new = odori_core::motion::two_bone_rotations(rest_pos[hip], thigh, thigh_local, shin_local, |_| shin, goal, thigh * thigh_local);
                if widest < WELL_POSED_RAD {
                    worst_rad = worst_rad.max(apart(t0, new.upper)).max(apart(s0, new.lower));
                } else {
                    ill_posed += 1;
                }
                let end = rest_pos[hip] + new.upper * thigh_local + new.lower * shin_local;
                worst_m = worst_m.max((end - end0).length()).max((end - new.end).length());
                cases += 1;
            }
        }
    }
    println!("two-bone IK: {cases} cases ({ill_posed} with an arc over 170°), worst rotation difference {worst_rad:e} rad, worst ankle difference {worst_m:e} m");
    assert!(cases > 2000, "{cases}");
    assert!(worst_rad < 1e-4 && worst_m < 1e-5, "{worst_rad} rad, {worst_m} m");
}
