//! Any humanoid clip onto the canonical skeleton (the one retargeting of the engine: the
//! choreography's segment library and the text actions' library both use it), so clips from
//! every source play, compare, join and compose as one. Directions, not lengths, are carried
//! over: each canonical bone is turned to point where the source's bone points (the hips and
//! chest take their full frame from the hip and shoulder lines), the root follows the source's
//! hips scaled by body height, and the whole clip is lifted so its feet meet the floor. Twist
//! about a bone's own axis is not carried over; stick figures, joins and IK do not need it. A
//! clip already on the canonical skeleton is only resampled.

use std::sync::Arc;

use glam::{Mat3, Quat, Vec3};

use crate::canon::builtin::canonical_skeleton;
use crate::clip::{Clip, TranslationTrack};
use crate::canon::humanoid::{canonical_positions, Canon, HumanoidMap, CANON_COUNT};
use crate::canon::SOLE_HEIGHT;
use crate::canon::normalize::body_height;
use crate::skeleton::Skeleton;

/// World rotation whose +X is along `left` and +Y along `up` (orthogonalised), or `None` when
/// the two are degenerate.
fn frame(left: Vec3, up: Vec3) -> Option<Quat> {
    let x = left.try_normalize()?;
    let y = (up - x * up.dot(x)).try_normalize()?;
    let z = x.cross(y);
    Some(Quat::from_mat3(&Mat3::from_cols(x, y, z)).normalize())
}

/// Whether a skeleton is the canonical one (same joints, names and parents, in order).
pub fn is_canonical(sk: &Skeleton) -> bool {
    sk.len() == CANON_COUNT && Canon::ALL.iter().zip(&sk.joints).all(|(c, j)| j.name == c.name() && j.parent == c.parent().map(Canon::index))
}

/// The clip on the canonical skeleton at `fps` (resampled first when the source differs).
pub fn to_canonical(clip: &Clip, map: &HumanoidMap, fps: f32) -> Clip {
    let src = if (clip.fps - fps).abs() > 1e-3 { clip.resampled(fps) } else { clip.clone() };
    if is_canonical(&src.skeleton) {
        return src;
    }
    let pos = canonical_positions(&src, map);
    let skeleton = Arc::new(canonical_skeleton());
    let canon_height = body_height(&skeleton.rest_positions());
    let src_height = body_height(&pos);
    let scale = if src_height > 1e-6 { canon_height / src_height } else { 1.0 };
    let frames = pos.len() / CANON_COUNT;
    let off = |c: Canon| skeleton.joints[c.index()].rest_offset;
    let mut rotations = Vec::with_capacity(frames * CANON_COUNT);
    let mut root = Vec::with_capacity(frames);
    let mut prev_world = [Quat::IDENTITY; CANON_COUNT];
    use Canon::*;
    for f in 0..frames {
        let p = &pos[f * CANON_COUNT..(f + 1) * CANON_COUNT];
        let at = |c: Canon| p[c.index()];
        let mut world = [Quat::IDENTITY; CANON_COUNT];
        let mut local = [Quat::IDENTITY; CANON_COUNT];
        let hips_q = frame(at(LeftUpperLeg) - at(RightUpperLeg), at(Chest) - at(Hips)).unwrap_or(prev_world[Hips.index()]);
        world[Hips.index()] = hips_q;
        local[Hips.index()] = hips_q;
        // A bone pointing at one child: swing the parent-carried rest direction onto it.
        let swing = |c: Canon, child: Canon, parent_world: Quat| -> Quat {
            let to = at(child) - at(c);
            if to.length_squared() < 1e-12 {
                parent_world
            } else {
                crate::motion::shortest_arc(parent_world * off(child), to) * parent_world
            }
        };
        let set = |c: Canon, w: Quat, parent: Canon, world: &mut [Quat; CANON_COUNT], local: &mut [Quat; CANON_COUNT]| {
            world[c.index()] = w;
            // Unit quaternions exactly (products drift by an ulp or two per joint).
            local[c.index()] = (world[parent.index()].inverse() * w).normalize();
        };
        let w = swing(Spine, Chest, hips_q);
        set(Spine, w, Hips, &mut world, &mut local);
        let chest_q = frame(at(LeftUpperArm) - at(RightUpperArm), at(Neck) - at(Chest)).unwrap_or(world[Spine.index()]);
        set(Chest, chest_q, Spine, &mut world, &mut local);
        let w = swing(Neck, Head, chest_q);
        set(Neck, w, Chest, &mut world, &mut local);
        set(Head, world[Neck.index()], Neck, &mut world, &mut local);
        for (sh, ua, fa, hand) in [(LeftShoulder, LeftUpperArm, LeftForearm, LeftHand), (RightShoulder, RightUpperArm, RightForearm, RightHand)] {
            let w = swing(sh, ua, chest_q);
            set(sh, w, Chest, &mut world, &mut local);
            let w = swing(ua, fa, world[sh.index()]);
            set(ua, w, sh, &mut world, &mut local);
            let w = swing(fa, hand, world[ua.index()]);
            set(fa, w, ua, &mut world, &mut local);
            set(hand, world[fa.index()], fa, &mut world, &mut local);
        }
        for (ul, ll, foot, toe) in [(LeftUpperLeg, LeftLowerLeg, LeftFoot, LeftToe), (RightUpperLeg, RightLowerLeg, RightFoot, RightToe)] {
            let w = swing(ul, ll, hips_q);
            set(ul, w, Hips, &mut world, &mut local);
            let w = swing(ll, foot, world[ul.index()]);
            set(ll, w, ul, &mut world, &mut local);
            let w = swing(foot, toe, world[ll.index()]);
            set(foot, w, ll, &mut world, &mut local);
            set(toe, world[foot.index()], foot, &mut world, &mut local);
        }
        prev_world = world;
        rotations.extend_from_slice(&local);
        root.push(at(Hips) * scale);
    }
    let mut out = Clip {
        name: src.name.clone(),
        source: src.source.clone(),
        fps,
        skeleton,
        rotations,
        translations: vec![TranslationTrack { joint: 0, values: root }],
    };
    // Feet on the floor: the toes' lowest 2 % (a planted step) at sole height.
    let all = out.all_world_positions();
    let mut lows: Vec<f32> = all.chunks(CANON_COUNT).map(|p| p[LeftToe.index()].y.min(p[RightToe.index()].y)).filter(|v| v.is_finite()).collect();
    lows.sort_by(f32::total_cmp);
    if let Some(&low) = lows.get(lows.len() / 50) {
        let lift = SOLE_HEIGHT - low;
        if let Some(t) = out.translations.first_mut() {
            for v in t.values.iter_mut() {
                v.y += lift;
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::canon::builtin::demo_clip;
    use crate::canon::normalize::normalized;

    #[test]
    fn canonical_clip_round_trips_its_own_directions() {
        let demo = demo_clip();
        let map = HumanoidMap::from_skeleton(&demo.skeleton);
        let c = to_canonical(&demo, &map, 30.0);
        c.validate().unwrap();
        let a = normalized(&canonical_positions(&demo.resampled(30.0), &map), crate::canon::normalize::Origin::Hips);
        let b = normalized(&canonical_positions(&c, &HumanoidMap::from_skeleton(&c.skeleton)), crate::canon::normalize::Origin::Hips);
        let err: f32 = a.iter().zip(&b).map(|(x, y)| (*x - *y).length()).sum::<f32>() / a.len() as f32;
        assert!(err < 0.01, "mean normalised joint error {err}");
    }
}
