//! Any humanoid clip (an imported motion, a text animation, a generated dance) as VMD keys on
//! MMD's standard bones of a rig (a model's, or the built-in standard skeleton), so MMD plays it.
//!
//! The clip is first put on the rig's deforming skeleton: unchanged when it already is that
//! skeleton (a VMD imported on the same model), else by the engine's character retargeting
//! (which handles the A-stance of MMD rest poses). Then, per frame at 30 fps: each exported bone
//! takes its world rotation relative to its nearest exported ancestor (every other bone stays
//! at rest in MMD, so twist and helper bones fold into the exported ones); センター carries the
//! body's travel, placed so 下半身 lands where the clip has it; 全ての親 and グルーブ are keyed at
//! rest. The legs are keyed both as rotations and as 足ＩＫ / つま先ＩＫ positions (the ankle's and
//! toe's place under those rotations), so MMD's IK, which overrides leg rotations, reproduces them.

use std::sync::Arc;

use glam::{Quat, Vec3};
use thiserror::Error;

use super::{quat_to_right_handed, to_right_handed, MmdRig, METRES_PER_MMD_UNIT};
use crate::canon::character::{Character, CharacterError};
use crate::canon::humanoid::HumanoidMap;
use crate::clip::Clip;
use crate::import::gltf::SkinnedMesh;
use crate::import::vmd::{BoneCurves, BoneKey, MorphKey, Vmd, VmdVersion};

/// The bones a VMD export keys, where the rig has them (item 3 of issue 28).
pub const EXPORT_BONES: &[&str] = &[
    "全ての親", "センター", "グルーブ", "下半身", "上半身", "上半身2", "首", "頭", "左肩", "右肩", "左腕", "右腕", "左ひじ", "右ひじ", "左手首", "右手首",
    "左足", "右足", "左ひざ", "右ひざ", "左足首", "右足首",
];
/// Keyed at rest (the body's travel is on センター).
const AT_REST: &[&str] = &["全ての親", "グルーブ"];
/// The leg IK bones keyed as positions.
pub const IK_BONES: &[&str] = &["左足ＩＫ", "右足ＩＫ", "左つま先ＩＫ", "右つま先ＩＫ"];

#[derive(Debug, Error, Clone, PartialEq)]
pub enum VmdExportError {
    #[error("clip '{clip}' has no frames")]
    NoFrames { clip: String },
    #[error("clip '{clip}' cannot be put on {rig}: {source}")]
    Retarget { clip: String, rig: String, source: CharacterError },
    #[error("{rig} has none of MMD's standard bones (センター, 下半身, 上半身 …)")]
    NoStandardBones { rig: String },
    #[error("clip '{clip}': frame {frame}, bone '{bone}' holds a value that is not finite")]
    NotFinite { clip: String, frame: usize, bone: String },
    #[error("clip '{clip}' is {frames} frames at 30 fps, more than a VMD export takes ({max})")]
    TooLong { clip: String, frames: usize, max: usize },
}

impl VmdExportError {
    pub fn kind(&self) -> &'static str {
        match self {
            VmdExportError::NoFrames { .. } => "export-bad-clip",
            VmdExportError::Retarget { .. } => "export-not-humanoid",
            VmdExportError::NoStandardBones { .. } => "export-skeleton-mismatch",
            VmdExportError::NotFinite { .. } => "export-not-finite",
            VmdExportError::TooLong { .. } => "too-large",
        }
    }
}

/// The clip on `rig`'s deforming skeleton at 30 fps (see the module doc): the engine's own
/// playback of the clip on that rig, which the exported keys reproduce.
pub fn clip_on_rig(clip: &Clip, rig: &MmdRig) -> Result<Clip, VmdExportError> {
    let (skeleton, _) = rig.deform_skeleton(METRES_PER_MMD_UNIT);
    let same = clip.skeleton.len() == skeleton.len()
        && clip.skeleton.joints.iter().zip(&skeleton.joints).all(|(a, b)| a.name == b.name && a.parent == b.parent && (a.rest_offset - b.rest_offset).length() < 1e-5 && a.rest_rotation.angle_between(b.rest_rotation) < 1e-6);
    let on = if same {
        clip.clone()
    } else {
        let map = HumanoidMap::from_skeleton(&skeleton);
        let status = map.status(&skeleton, None);
        let retarget = |source| VmdExportError::Retarget { clip: clip.name.clone(), rig: rig.name.clone(), source };
        let character = Character::from_parts(&rig.name, Arc::new(skeleton), Some(&SkinnedMesh::default()), &map, &status).map_err(retarget)?;
        let clip_map = HumanoidMap::from_skeleton(&clip.skeleton);
        character.retarget(clip, &clip_map).map_err(retarget)?
    };
    Ok(if (on.fps - 30.0).abs() > 1e-3 { on.resampled(30.0) } else { on })
}

/// Key reduction: a key is dropped when linear interpolation between the keys kept around it
/// reproduces it within these: the largest quaternion component difference (about half the
/// angle in radians: 5e-5 ≈ 0.006°) and the translation, model units (5e-5 ≈ 4 µm). Tight enough
/// that a VMD imported and exported again reads back within 1e-4 at every frame.
pub const KEY_TOLERANCE_QUAT: f32 = 5e-5;
pub const KEY_TOLERANCE_UNITS: f32 = 5e-5;
/// Longest span between two kept keys, frames: bounds the reduction's cost (it checks every key
/// of a span each time the span grows) at a few kept keys per still second.
pub const MAX_KEY_SPAN_FRAMES: usize = 60;

/// Whether linear interpolation from key `a` to key `e` (one bone's keys, by frame) reproduces
/// every key between them within the tolerances.
fn span_reproduces(keys: &[&BoneKey], a: usize, e: usize) -> bool {
    let (ka, ke) = (keys[a], keys[e]);
    let len = ke.frame.saturating_sub(ka.frame) as f32;
    if len <= 0.0 {
        return false;
    }
    keys[a + 1..e].iter().all(|k| {
        let x = k.frame.saturating_sub(ka.frame) as f32 / len;
        let t = ka.translation.lerp(ke.translation, x);
        let q = ka.rotation.slerp(ke.rotation, x).normalize();
        let r = if q.dot(k.rotation) < 0.0 { -k.rotation } else { k.rotation };
        (t - k.translation).abs().max_element() <= KEY_TOLERANCE_UNITS && (glam::Vec4::from(q) - glam::Vec4::from(r)).abs().max_element() <= KEY_TOLERANCE_QUAT
    })
}

/// Which of one bone's keys (sorted by frame) to keep: the first and last, and greedily the
/// farthest key each span can reach with every key between reproduced (see [`span_reproduces`]).
fn keys_to_keep(keys: &[&BoneKey]) -> Vec<bool> {
    let n = keys.len();
    let mut keep = vec![false; n];
    if n == 0 {
        return keep;
    }
    keep[0] = true;
    keep[n - 1] = true;
    let mut a = 0;
    while a + 1 < n {
        let mut e = a + 1;
        while e + 1 < n && e + 1 - a <= MAX_KEY_SPAN_FRAMES && span_reproduces(keys, a, e + 1) {
            e += 1;
        }
        keep[e] = true;
        a = e;
    }
    keep
}

/// Drops the bone keys that linear interpolation between the kept ones reproduces (per bone,
/// within [`KEY_TOLERANCE_QUAT`] and [`KEY_TOLERANCE_UNITS`]), except those `must_keep(bone,
/// frame)` names; keeps the rest in order.
pub fn reduce_bone_keys(keys: Vec<BoneKey>, must_keep: &dyn Fn(&str, u32) -> bool) -> Vec<BoneKey> {
    let mut by_bone: std::collections::HashMap<&str, Vec<usize>> = std::collections::HashMap::new();
    for (i, k) in keys.iter().enumerate() {
        by_bone.entry(k.name.as_str()).or_default().push(i);
    }
    let mut keep = vec![false; keys.len()];
    for idx in by_bone.values_mut() {
        idx.sort_by_key(|&i| keys[i].frame);
        // Split at the keys that must stay: each piece is reduced on its own, its ends kept.
        let mut start = 0;
        for end in 1..=idx.len() {
            if end < idx.len() && !must_keep(&keys[idx[end]].name, keys[idx[end]].frame) {
                continue;
            }
            let piece = &idx[start..end.min(idx.len() - 1) + 1];
            let track: Vec<&BoneKey> = piece.iter().map(|&i| &keys[i]).collect();
            for (k, kept) in keys_to_keep(&track).into_iter().enumerate() {
                keep[piece[k]] |= kept;
            }
            start = end;
        }
    }
    keys.into_iter().zip(keep).filter_map(|(k, kept)| kept.then_some(k)).collect()
}

/// The VMD bone keys of `clip` on `rig` (values in the file's left-handed frame and units) at
/// 30 fps with linear curves: a key per bone per frame, then per bone only those linear
/// interpolation does not reproduce ([`reduce_bone_keys`]). `model_name` goes in the header (MMD
/// shows it; readers pick the model by it).
pub fn clip_to_vmd(clip: &Clip, rig: &MmdRig, model_name: &str) -> Result<Vmd, VmdExportError> {
    clip_to_vmd_keeping(clip, rig, model_name, &|_, _| false)
}

/// [`clip_to_vmd`], never dropping the keys `must_keep(bone, frame)` names: an imported VMD
/// exported again keeps its own keys (frames on the clip's timeline, the song offset taken off).
pub fn clip_to_vmd_keeping(clip: &Clip, rig: &MmdRig, model_name: &str, must_keep: &dyn Fn(&str, u32) -> bool) -> Result<Vmd, VmdExportError> {
    let mut vmd = clip_to_vmd_every_frame(clip, rig, model_name)?;
    vmd.bone_keys = reduce_bone_keys(std::mem::take(&mut vmd.bone_keys), must_keep);
    Ok(vmd)
}

/// Face (morph) keys an import set aside ([`super::files::ImportedMotion::vmd`]), written back
/// into an exported VMD on the export's timeline: `first_frame` (the import's song offset, plus
/// the start of an exported range) taken off, keys before it dropped, file order kept. The
/// engine does not play morphs; this is how they survive a round trip through it.
pub fn put_morph_keys(vmd: &mut Vmd, morphs: &[MorphKey], first_frame: u32) {
    vmd.morph_keys = morphs.iter().filter(|k| k.frame >= first_frame).map(|k| MorphKey { name: k.name.clone(), frame: k.frame - first_frame, weight: k.weight }).collect();
}

/// [`clip_to_vmd`] without the key reduction: a key per bone per frame.
pub fn clip_to_vmd_every_frame(clip: &Clip, rig: &MmdRig, model_name: &str) -> Result<Vmd, VmdExportError> {
    if clip.frame_count() == 0 {
        return Err(VmdExportError::NoFrames { clip: clip.name.clone() });
    }
    let max_frames = super::motion::MAX_CLIP_FRAMES;
    let frames_30 = (clip.duration_secs() * 30.0).round() as usize + 1;
    if frames_30 > max_frames {
        return Err(VmdExportError::TooLong { clip: clip.name.clone(), frames: frames_30, max: max_frames });
    }
    let on = clip_on_rig(clip, rig)?;
    let (_, rig_index) = rig.deform_skeleton(METRES_PER_MMD_UNIT);
    let n = rig.len();
    let mut joint_of = vec![None; n];
    for (j, &i) in rig_index.iter().enumerate() {
        joint_of[i] = Some(j);
    }
    let exported: Vec<bool> = (0..n).map(|i| EXPORT_BONES.contains(&rig.bones[i].name.as_str()) && joint_of[i].is_some()).collect();
    if !exported.iter().any(|&e| e) {
        return Err(VmdExportError::NoStandardBones { rig: rig.name.clone() });
    }
    let moving: Vec<bool> = (0..n).map(|i| exported[i] && !AT_REST.contains(&rig.bones[i].name.as_str())).collect();
    let find = |name: &str| rig.find(name);
    let centre = find("センター").filter(|&i| moving[i]);
    let lower = find("下半身").filter(|&i| joint_of[i].is_some());
    let ik_bones: Vec<usize> = IK_BONES.iter().filter_map(|b| find(b)).filter(|&i| rig.bones[i].ik.is_some()).collect();
    // Bones in an order with parents first: the rig's bones by depth.
    let depth = |mut i: usize| {
        let mut d = 0;
        while let Some(p) = rig.bones[i].parent {
            d += 1;
            i = p;
            if d > n {
                break;
            }
        }
        d
    };
    let mut order: Vec<usize> = (0..n).collect();
    order.sort_by_key(|&i| depth(i));

    let mut vmd = Vmd {
        version: VmdVersion::V2,
        model_name: model_name.to_string(),
        bone_keys: Vec::new(),
        morph_keys: vec![],
        camera_keys: vec![],
        light_keys: vec![],
        self_shadow_keys: vec![],
        property_keys: vec![],
    };
    let mut mats = Vec::new();
    let mut pose = crate::motion::WorldPose::new();
    let mut world_rot = vec![Quat::IDENTITY; n];
    let mut world_pos = vec![Vec3::ZERO; n];
    let mut local_rot = vec![Quat::IDENTITY; n];
    let mut local_t = vec![Vec3::ZERO; n];
    let m = METRES_PER_MMD_UNIT;
    for f in 0..on.frame_count() {
        pose.of_frame(&on, f).matrices_into(&mut mats);
        // The clip's world rotation and position of each kept bone (rig units).
        let clip_world = |i: usize| -> Option<(Quat, Vec3)> {
            let j = joint_of[i]?;
            let (_, r, t) = mats.get(j)?.to_scale_rotation_translation();
            Some((r.normalize(), t / m))
        };
        // Exported bones' locals: world relative to the nearest exported ancestor's world.
        for &i in &order {
            local_rot[i] = Quat::IDENTITY;
            local_t[i] = Vec3::ZERO;
            if !moving[i] {
                continue;
            }
            let Some((w, _)) = clip_world(i) else { continue };
            let mut a = rig.bones[i].parent;
            while let Some(p) = a.filter(|&p| !moving[p]) {
                a = rig.bones[p].parent;
            }
            let parent_w = a.and_then(clip_world).map_or(Quat::IDENTITY, |(r, _)| r);
            local_rot[i] = (parent_w.inverse() * w).normalize();
        }
        // Forward kinematics over the rig with those locals (every other bone at rest).
        let fk = |local_t: &[Vec3], world_rot: &mut [Quat], world_pos: &mut [Vec3]| {
            for &i in &order {
                let (pr, pp) = rig.bones[i].parent.map_or((Quat::IDENTITY, Vec3::ZERO), |p| (world_rot[p], world_pos[p]));
                world_pos[i] = pp + pr * (rig.rest_offset(i) + local_t[i]);
                world_rot[i] = (pr * local_rot[i]).normalize();
            }
        };
        fk(&local_t, &mut world_rot, &mut world_pos);
        // センター travels so 下半身 lands where the clip has it.
        if let (Some(c), Some(h)) = (centre, lower) {
            if let Some((_, want)) = clip_world(h) {
                let err = want - world_pos[h];
                let pr = rig.bones[c].parent.map_or(Quat::IDENTITY, |p| world_rot[p]);
                local_t[c] = pr.inverse() * err;
                fk(&local_t, &mut world_rot, &mut world_pos);
            }
        }
        // IK bones where their effectors are (parents first: つま先ＩＫ after its 足ＩＫ).
        for &i in &order {
            if !ik_bones.contains(&i) {
                continue;
            }
            let Some(chain) = &rig.bones[i].ik else { continue };
            let (pr, pp) = rig.bones[i].parent.map_or((Quat::IDENTITY, Vec3::ZERO), |p| (world_rot[p], world_pos[p]));
            let target = world_pos.get(chain.effector).copied().unwrap_or(world_pos[i]);
            local_t[i] = pr.inverse() * (target - pp) - rig.rest_offset(i);
            world_pos[i] = target;
            // Their children (つま先ＩＫ under 足ＩＫ) follow.
            for &k in &order {
                if rig.bones[k].parent == Some(i) {
                    world_pos[k] = world_pos[i] + world_rot[i] * (rig.rest_offset(k) + local_t[k]);
                }
            }
        }
        for &i in &order {
            if !(exported[i] || ik_bones.contains(&i)) {
                continue;
            }
            let (q, t) = (quat_to_right_handed(local_rot[i]), to_right_handed(local_t[i]));
            if !(q.is_finite() && t.is_finite()) {
                return Err(VmdExportError::NotFinite { clip: clip.name.clone(), frame: f, bone: rig.bones[i].name.clone() });
            }
            vmd.bone_keys.push(BoneKey { name: rig.bones[i].name.clone(), frame: f as u32, translation: t, rotation: q, curves: BoneCurves::default() });
        }
    }
    Ok(vmd)
}
