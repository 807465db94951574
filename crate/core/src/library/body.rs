//! The built-in character: a simple skinned body of the product's own making, generated on the
//! canonical skeleton, so every dance has a body and every export a mesh with no character
//! imported. Each canonical bone is a capsule (rounded cylinder) around the bone, each end of
//! the body (head, hands, feet) an ellipsoid-like capsule, in one material. Vertices are bound
//! rigidly to the joint that carries their bone (weight 1), with the rest pose's exact inverse
//! as bind matrix, so the body skins with the same matrices the stick figure uses.

use crate::fmath;
use std::f32::consts::PI;

use glam::{Mat4, Vec3};

use crate::canon::humanoid::Canon;
use crate::import::{MeshPart, SkinnedMesh};
use crate::motion;
use crate::skeleton::Skeleton;

/// Linear RGBA of the built-in body (a warm clay; distinct from the stick figures' colours).
pub const BODY_COLOR: [f32; 4] = [0.72, 0.45, 0.32, 1.0];

/// Segments around each capsule and rings per hemisphere: enough to read as round at the
/// viewer's usual distance, few enough to stay small (about 3 k vertices for the body).
const AROUND: usize = 12;
const RINGS: usize = 4;

/// Appends a capsule from `a` to `b` of radius `r`, bound to palette slot `slot`.
fn capsule(part: &mut MeshPart, a: Vec3, b: Vec3, r: f32, slot: u16) {
    let d = (b - a).try_normalize().unwrap_or(Vec3::Y);
    let u = d.any_orthonormal_vector();
    let v = d.cross(u);
    let base = part.positions.len() as u32;
    let mut push = |p: Vec3, n: Vec3| {
        part.positions.push(p.to_array());
        part.normals.push(n.normalize().to_array());
        part.joints.push([slot, 0, 0, 0]);
        part.weights.push([1.0, 0.0, 0.0, 0.0]);
    };
    // Pole at a, rings from a's hemisphere through the cylinder to b's, pole at b.
    push(a - d * r, -d);
    let mut rings = 0u32;
    for (centre, k0, k1) in [(a, 1, RINGS), (b, RINGS, 2 * RINGS - 1)] {
        for k in k0..=k1 {
            let phi = k as f32 * PI / (2 * RINGS) as f32; // 0 at a's pole, π at b's
            for s in 0..AROUND {
                let lambda = s as f32 * 2.0 * PI / AROUND as f32;
                let n = -d * fmath::cos(phi) + (u * fmath::cos(lambda) + v * fmath::sin(lambda)) * fmath::sin(phi);
                push(centre + n * r, n);
            }
            rings += 1;
        }
    }
    push(b + d * r, d);
    let ring = |k: u32, s: usize| base + 1 + k * AROUND as u32 + (s % AROUND) as u32;
    let last = base + 1 + rings * AROUND as u32;
    for s in 0..AROUND {
        // Counter-clockwise seen from outside.
        part.indices.extend([base, ring(0, s + 1), ring(0, s)]);
        for k in 0..rings - 1 {
            let (p, q, r2, t) = (ring(k, s), ring(k, s + 1), ring(k + 1, s), ring(k + 1, s + 1));
            part.indices.extend([p, q, t, p, t, r2]);
        }
        part.indices.extend([last, ring(rings - 1, s), ring(rings - 1, s + 1)]);
    }
}

/// The built-in body on `skeleton`, which must be the canonical skeleton (joint `i` is
/// `Canon::ALL[i]`); the palette has one slot per joint.
pub fn builtin_body(skeleton: &Skeleton) -> SkinnedMesh {
    let (rot, pos) = motion::rest_world(skeleton);
    let palette: Vec<(usize, Mat4)> = rot.iter().zip(&pos).enumerate().map(|(i, (r, p))| (i, motion::rigid(*r, *p).1)).collect();
    let mut part = MeshPart { color: BODY_COLOR, ..Default::default() };
    let at = |c: Canon| pos.get(c.index()).copied().unwrap_or(Vec3::ZERO);
    use Canon::*;
    // (carrying joint, from, to, radius in metres)
    let mut bones: Vec<(Canon, Vec3, Vec3, f32)> = vec![
        (Hips, at(Hips), at(Spine), 0.13),
        (Spine, at(Spine), at(Chest), 0.13),
        (Chest, at(Chest) + Vec3::Y * 0.04, at(Neck) - Vec3::Y * 0.05, 0.15),
        (Neck, at(Neck), at(Head), 0.05),
        (Head, at(Head) + Vec3::Y * 0.04, at(Head) + Vec3::Y * 0.12, 0.1),
    ];
    for (sh, ua, fa, hand) in [(LeftShoulder, LeftUpperArm, LeftForearm, LeftHand), (RightShoulder, RightUpperArm, RightForearm, RightHand)] {
        bones.push((sh, at(sh), at(ua), 0.055));
        bones.push((ua, at(ua), at(fa), 0.05));
        bones.push((fa, at(fa), at(hand), 0.04));
        let out = (at(hand) - at(fa)).normalize_or_zero();
        bones.push((hand, at(hand) + out * 0.03, at(hand) + out * 0.11, 0.035));
    }
    for (ul, ll, foot, toe) in [(LeftUpperLeg, LeftLowerLeg, LeftFoot, LeftToe), (RightUpperLeg, RightLowerLeg, RightFoot, RightToe)] {
        bones.push((ul, at(ul), at(ll), 0.075));
        bones.push((ll, at(ll), at(foot), 0.055));
        // The foot lies along the ground from heel to toe tip.
        let sole = at(toe).y + 0.025;
        let heel = Vec3::new(at(foot).x, sole, at(foot).z - 0.05);
        bones.push((foot, heel, Vec3::new(at(toe).x, sole, at(toe).z + 0.02), 0.045));
    }
    for (c, a, b, r) in bones {
        capsule(&mut part, a, b, r, c.index() as u16);
    }
    SkinnedMesh { parts: vec![part], palette, textures: Vec::new() }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::canon::builtin::canonical_skeleton;

    #[test]
    fn body_is_closed_outward_and_bound_at_rest() {
        let sk = canonical_skeleton();
        let body = builtin_body(&sk);
        let p = &body.parts[0];
        assert_eq!(p.positions.len(), p.normals.len());
        assert!(p.indices.iter().all(|&i| (i as usize) < p.positions.len()));
        // Every triangle faces the way its vertices' normals point (outward), and none is degenerate.
        for t in p.indices.chunks(3) {
            let v: Vec<Vec3> = t.iter().map(|&i| Vec3::from(p.positions[i as usize])).collect();
            let face = (v[1] - v[0]).cross(v[2] - v[0]);
            assert!(face.length() > 1e-9, "degenerate triangle {t:?}");
            let n: Vec3 = t.iter().map(|&i| Vec3::from(p.normals[i as usize])).sum();
            assert!(face.dot(n) > 0.0, "triangle {t:?} faces inward");
        }
        // Feet reach the floor, the head the body's top.
        let (lo, hi) = p.positions.iter().fold((f32::MAX, f32::MIN), |(lo, hi), q| (lo.min(q[1]), hi.max(q[1])));
        assert!(lo < 0.03 && lo > -0.05, "lowest point {lo}");
        assert!(hi > 1.6 && hi < 1.85, "highest point {hi}");
        // Bind matrices undo the rest pose: skinning at rest leaves vertices where they are.
        let (rot, pos) = motion::rest_world(&sk);
        for (j, bind) in &body.palette {
            let m = motion::rigid(rot[*j], pos[*j]).0 * *bind;
            assert!(m.abs_diff_eq(Mat4::IDENTITY, 1e-5));
        }
    }
}
