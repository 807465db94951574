//! BVH writer (spec §M): one hierarchy (whatever skeleton the clip is on: the canonical one or
//! a character's rig), in centimetres, the root with 6 channels and every other joint with 3,
//! rotations in one order for the whole file (`Zrotation Xrotation Yrotation`, the CMU
//! convention most tools read), and the frame time written with enough digits to be exact
//! at any rate the product uses.
//!
//! BVH has no rest rotations: a joint's channels hold its whole local rotation (rest included,
//! for a glTF rig), so the motion is exact while the file's zero pose is the rig's bind pose
//! only when the rig has no rest rotations (the canonical skeleton has none). A joint other
//! than the root whose translation is animated away from its rest offset (a glTF rig whose
//! hips sit under a static `Armature` node) gets 6 channels too, since dropping its motion
//! would move the whole body; on the canonical skeleton only the root has 6.
//! A joint with no children gets an `End Site` with a zero offset, as the format requires.

use std::fmt::Write;

use glam::{EulerRot, Vec3};

use super::{check_clips, ExportError};
use crate::clip::Clip;

/// Centimetres per metre: the unit the file is written in.
pub const CM_PER_M: f32 = 100.0;

fn v3(out: &mut String, v: Vec3) {
    let _ = write!(out, "{:.6} {:.6} {:.6}", v.x * CM_PER_M, v.y * CM_PER_M, v.z * CM_PER_M);
}

/// Writes `clip` as a BVH file (text, UTF-8).
pub fn bvh(clip: &Clip) -> Result<Vec<u8>, ExportError> {
    let sk = &clip.skeleton;
    check_clips(sk, &[clip])?;
    // BVH has one root: a second root (a prop beside the rig) is refused with its name.
    let roots: Vec<usize> = sk.joints.iter().enumerate().filter(|(_, j)| j.parent.is_none()).map(|(i, _)| i).collect();
    if roots.len() != 1 {
        return Err(ExportError::BadClip {
            clip: clip.name.clone(),
            message: format!("BVH holds one hierarchy but the skeleton has {} roots ({})", roots.len(), roots.iter().map(|&r| sk.joints[r].name.as_str()).collect::<Vec<_>>().join(", ")),
        });
    }
    let n = sk.len();
    let mut children: Vec<Vec<usize>> = vec![Vec::new(); n];
    for (i, j) in sk.joints.iter().enumerate() {
        if let Some(p) = j.parent {
            children[p].push(i);
        }
    }
    let mut out = String::from("HIERARCHY\n");
    // Depth-first in skeleton order; the channel order of the MOTION lines follows it.
    let mut order = Vec::with_capacity(n);
    // Translation tracks that move away from the rest offset (more than 1 µm).
    let moving: Vec<Option<&crate::clip::TranslationTrack>> = (0..n)
        .map(|i| clip.translations.iter().find(|t| t.joint == i && t.values.iter().any(|v| (*v - sk.joints[i].rest_offset).length() > 1e-6)))
        .collect();
    #[allow(clippy::too_many_arguments)]
    fn walk(i: usize, depth: usize, sk: &crate::Skeleton, children: &[Vec<usize>], six: &[bool], out: &mut String, order: &mut Vec<usize>) {
        let pad = "  ".repeat(depth);
        let j = &sk.joints[i];
        let name: String = j.name.chars().map(|c| if c.is_whitespace() { '_' } else { c }).collect();
        let _ = writeln!(out, "{pad}{} {name}", if depth == 0 { "ROOT" } else { "JOINT" });
        let _ = writeln!(out, "{pad}{{");
        out.push_str(&pad);
        out.push_str("  OFFSET ");
        v3(out, if depth == 0 { Vec3::ZERO } else { j.rest_offset });
        out.push('\n');
        if depth == 0 || six[i] {
            let _ = writeln!(out, "{pad}  CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation");
        } else {
            let _ = writeln!(out, "{pad}  CHANNELS 3 Zrotation Xrotation Yrotation");
        }
        order.push(i);
        if children[i].is_empty() {
            let _ = writeln!(out, "{pad}  End Site\n{pad}  {{\n{pad}    OFFSET 0.000000 0.000000 0.000000\n{pad}  }}");
        }
        for &c in &children[i] {
            walk(c, depth + 1, sk, children, six, out, order);
        }
        let _ = writeln!(out, "{pad}}}");
    }
    let six: Vec<bool> = moving.iter().map(Option::is_some).collect();
    walk(roots[0], 0, sk, &children, &six, &mut out, &mut order);
    let frames = clip.frame_count();
    let _ = writeln!(out, "MOTION\nFrames: {frames}\nFrame Time: {:.9}", 1.0 / clip.fps as f64);
    let root_track = clip.translations.iter().find(|t| t.joint == roots[0]);
    for f in 0..frames {
        let rot = clip.frame_rotations(f);
        let root = root_track.map(|t| t.values[f]).unwrap_or(sk.joints[roots[0]].rest_offset);
        v3(&mut out, root);
        for &i in &order {
            if i != roots[0] {
                if let Some(t) = moving[i] {
                    out.push(' ');
                    v3(&mut out, t.values[f]);
                }
            }
            // Rz · Rx · Ry, the order the channels are listed in.
            let (z, x, y) = rot[i].normalize().to_euler(EulerRot::ZXY);
            let _ = write!(out, " {:.6} {:.6} {:.6}", z.to_degrees(), x.to_degrees(), y.to_degrees());
        }
        out.push('\n');
    }
    Ok(out.into_bytes())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::canon::builtin::demo_clip;
    use crate::import::{import_bytes, ImportOptions};
    use glam::Quat;

    #[test]
    fn euler_order_matches_the_channel_order() {
        let q = Quat::from_rotation_z(0.4) * Quat::from_rotation_x(-0.7) * Quat::from_rotation_y(1.3);
        let (z, x, y) = q.to_euler(EulerRot::ZXY);
        assert!((z - 0.4).abs() < 1e-5 && (x + 0.7).abs() < 1e-5 && (y - 1.3).abs() < 1e-5, "{z} {x} {y}");
    }

    #[test]
    fn bvh_round_trips_the_demo_clip() {
        let clip = demo_clip();
        let text = bvh(&clip).unwrap();
        let back = import_bytes("demo.bvh", &text, &ImportOptions::default()).unwrap();
        let b = &back.clips[0];
        assert_eq!(b.frame_count(), clip.frame_count());
        assert!((b.fps - clip.fps).abs() < 1e-3, "{} vs {}", b.fps, clip.fps);
        for f in [0, clip.frame_count() / 2, clip.frame_count() - 1] {
            let a = clip.world_positions(f);
            let p = b.world_positions(f);
            for (i, j) in clip.skeleton.joints.iter().enumerate() {
                let k = b.skeleton.find(&j.name).unwrap();
                assert!((a[i] - p[k]).length() < 1e-3, "frame {f} joint {}: {} vs {}", j.name, a[i], p[k]);
            }
        }
    }
}
