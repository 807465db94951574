//! VRM animation writer (spec §M: `.vrma`, the `VRMC_vrm_animation` extension), for people
//! who dance on VRM avatars (three-vrm, VRM apps). A `.vrma` is a GLB with no mesh: a
//! humanoid skeleton in T-pose, a map from VRM humanoid bone names to its nodes, and one
//! animation whose channels are rotations on every humanoid bone and a translation on the
//! hips only (no scale tracks; a player rescales the hips' path to its avatar's hip height).
//!
//! The skeleton written is the canonical one (§A): its rest is already the T-pose VRM asks
//! for (facing +Z, the figure's left on +X, identity rest rotations), so a bone's animated
//! rotation is exactly VRM's normalised local rotation and players need no conversion. A clip
//! on another humanoid rig (an imported BVH or glTF) is first carried onto the canonical
//! skeleton by the library's one retargeting (`retarget::to_canonical`), as the dance and
//! search see it. The document is built with the same `gltf-json` writer as the GLB export;
//! the extension is a typed serde value, not assembled text.

use std::collections::BTreeMap;
use std::sync::Arc;

use glam::Quat;
use gltf::json;
use serde::Serialize;

use super::gltf::{animations, finish, joint_nodes, start};
use super::{check_clips, ExportError};
use crate::clip::Clip;
use crate::canon::humanoid::{Canon, HumanoidMap, HumanoidStatus};
use crate::canon::retarget::{is_canonical, to_canonical};

/// The extension's name, as it appears in `extensionsUsed` and `extensions`.
pub const EXTENSION: &str = "VRMC_vrm_animation";

/// `VRMC_vrm_animation` (specVersion 1.0): the parts this writer fills.
#[derive(Serialize, Debug, Clone, PartialEq)]
#[serde(rename_all = "camelCase")]
struct VrmcVrmAnimation {
    spec_version: &'static str,
    humanoid: Humanoid,
}

#[derive(Serialize, Debug, Clone, PartialEq)]
#[serde(rename_all = "camelCase")]
struct Humanoid {
    /// VRM humanoid bone name → node (sorted: the output is deterministic).
    human_bones: BTreeMap<&'static str, HumanBone>,
}

#[derive(Serialize, Debug, Clone, PartialEq)]
struct HumanBone {
    node: u32,
}

/// Writes `clip` (any humanoid clip; `map` its mapping onto the canonical humanoid) as a
/// `.vrma` file. A clip that is not humanoid is refused, naming why.
pub fn vrma(clip: &Clip, map: &HumanoidMap) -> Result<Vec<u8>, ExportError> {
    check_clips(&clip.skeleton, &[clip])?;
    if let HumanoidStatus::NotHumanoid { reason } = map.status(&clip.skeleton, Some(clip)) {
        return Err(ExportError::NotHumanoid { clip: clip.name.clone(), reason });
    }
    let canon = if is_canonical(&clip.skeleton) { clip.clone() } else { to_canonical(clip, map, clip.fps) };
    // The file's rest is the T-pose: canonical offsets, identity rest rotations. The clip's
    // rotations are whole local rotations (not relative to rest), so the pose is unchanged.
    let mut skeleton = (*canon.skeleton).clone();
    for j in &mut skeleton.joints {
        j.rest_rotation = Quat::IDENTITY;
    }
    let skeleton = Arc::new(skeleton);
    let clip = Clip { skeleton: skeleton.clone(), ..canon };

    let (mut root, mut bin) = start();
    let scene_nodes = joint_nodes(&mut root, &skeleton);
    // Node i is canonical joint i (`joint_nodes` writes the joints in order).
    let hips = Canon::Hips.index();
    animations(&mut root, &mut bin, &[&clip], |joint| joint == hips)?;

    let ext = VrmcVrmAnimation {
        spec_version: "1.0",
        humanoid: Humanoid { human_bones: Canon::ALL.iter().map(|c| (c.vrm_name(), HumanBone { node: c.index() as u32 })).collect() },
    };
    let value = serde_json::to_value(&ext).map_err(|e| ExportError::Encode { message: e.to_string() })?;
    let mut extensions = json::extensions::root::Root::default();
    extensions.others.insert(EXTENSION.to_string(), value);
    root.extensions = Some(extensions);
    root.extensions_used.push(EXTENSION.to_string());
    finish(root, bin, scene_nodes)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::canon::builtin::demo_clip;
    use crate::import::{import_bytes, ImportOptions};

    fn json_of(glb: &[u8]) -> serde_json::Value {
        let g = gltf::binary::Glb::from_slice(glb).unwrap();
        serde_json::from_slice(&g.json).unwrap()
    }

    #[test]
    fn maps_every_humanoid_bone_and_animates_hips_translation_only() {
        let clip = demo_clip();
        let bytes = vrma(&clip, &HumanoidMap::from_skeleton(&clip.skeleton)).unwrap();
        let doc = json_of(&bytes);
        assert_eq!(doc["extensionsUsed"], serde_json::json!([EXTENSION]));
        let ext = &doc["extensions"][EXTENSION];
        assert_eq!(ext["specVersion"], "1.0");
        let bones = ext["humanoid"]["humanBones"].as_object().unwrap();
        assert_eq!(bones.len(), 21);
        for c in Canon::ALL {
            let node = bones[c.vrm_name()]["node"].as_u64().unwrap() as usize;
            assert_eq!(doc["nodes"][node]["name"], c.name());
            // T-pose rest: no node rotation.
            assert!(doc["nodes"][node].get("rotation").is_none(), "{} has a rest rotation", c.name());
        }
        assert_eq!(bones["leftLowerArm"]["node"], Canon::LeftForearm.index());
        assert_eq!(bones["rightToes"]["node"], Canon::RightToe.index());
        let channels = doc["animations"][0]["channels"].as_array().unwrap();
        let paths = |p: &str| channels.iter().filter(|c| c["target"]["path"] == p).map(|c| c["target"]["node"].as_u64().unwrap()).collect::<Vec<_>>();
        assert_eq!(paths("rotation").len(), 21);
        assert_eq!(paths("translation"), vec![Canon::Hips.index() as u64]);
        assert!(paths("scale").is_empty());
        assert!(doc.get("meshes").is_none() && doc.get("skins").is_none());
    }

    #[test]
    fn reimports_with_the_same_joint_positions() {
        let clip = demo_clip();
        let bytes = vrma(&clip, &HumanoidMap::from_skeleton(&clip.skeleton)).unwrap();
        let back = import_bytes("demo.vrma", &bytes, &ImportOptions { gltf_fps: clip.fps, ..Default::default() }).unwrap();
        let b = &back.clips[0];
        assert_eq!(b.frame_count(), clip.frame_count());
        let mut worst = 0.0f32;
        for f in (0..clip.frame_count()).step_by(7) {
            for (p, q) in clip.world_positions(f).iter().zip(b.world_positions(f)) {
                worst = worst.max((*p - q).length());
            }
        }
        assert!(worst < 1e-4, "worst joint {worst} m");
    }

    #[test]
    fn a_rig_with_its_own_rest_rotations_comes_out_in_t_pose_with_the_same_pose() {
        // The demo on a copy of the canonical skeleton whose forearms have a rest rotation:
        // the clip's rotations are whole local rotations, so dropping the rest keeps the pose.
        let clip = demo_clip();
        let mut sk = (*clip.skeleton).clone();
        sk.joints[Canon::LeftForearm.index()].rest_rotation = Quat::from_rotation_x(0.7);
        let twisted = Clip { skeleton: Arc::new(sk), ..clip.clone() };
        let bytes = vrma(&twisted, &HumanoidMap::from_skeleton(&twisted.skeleton)).unwrap();
        let back = import_bytes("t.vrma", &bytes, &ImportOptions { gltf_fps: clip.fps, ..Default::default() }).unwrap();
        for (p, q) in clip.world_positions(30).iter().zip(back.clips[0].world_positions(30)) {
            assert!((*p - q).length() < 1e-4);
        }
    }

    #[test]
    fn refuses_a_body_that_is_not_humanoid() {
        // Four joints in a row: no legs, no arms.
        let mut clip = demo_clip();
        let mut sk = (*clip.skeleton).clone();
        sk.joints.truncate(4);
        let frames = clip.frame_count();
        let rotations: Vec<Quat> = (0..frames).flat_map(|f| clip.rotations[f * 21..f * 21 + 4].to_vec()).collect();
        sk.joints.iter_mut().enumerate().for_each(|(i, j)| j.name = format!("bone{i}"));
        clip.skeleton = Arc::new(sk);
        clip.rotations = rotations;
        let got = vrma(&clip, &HumanoidMap::from_skeleton(&clip.skeleton));
        assert!(matches!(got, Err(ExportError::NotHumanoid { .. })), "{got:?}");
    }
}
