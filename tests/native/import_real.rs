//! Every real motion file in ../shared/data imports, and what comes out agrees with the file.

use odori_core::humanoid::{canonical_positions, Canon};
use odori_core::import::{import_bytes, ImportOptions};
use odori_core::HumanoidStatus;
use odori_tests::{all_bvh, fps_override_for, read};

/// Joint count, frame count and frame time read straight from the text, independently of
/// the importer.
fn header_facts(text: &str) -> (usize, usize, f32, usize) {
    let joints = text
        .lines()
        .filter(|l| matches!(l.split_whitespace().next(), Some("ROOT") | Some("JOINT")))
        .count();
    let mut lines = text.lines().skip_while(|l| l.trim() != "MOTION").skip(1);
    let frames: usize = lines.next().unwrap().split_whitespace().nth(1).unwrap().parse().unwrap();
    let frame_time: f32 = lines.next().unwrap().split_whitespace().nth(2).unwrap().parse().unwrap();
    let rows = lines.filter(|l| !l.trim().is_empty()).count();
    (joints, frames, frame_time, rows)
}

#[test]
fn every_bvh_imports_with_the_files_counts_and_rigid_bones() {
    let files = all_bvh();
    assert_eq!(files.len(), 29, "expected the 29 BVH files of ../shared/data/mocap, found {files:?}");
    for rel in &files {
        let bytes = read(rel);
        let text = String::from_utf8_lossy(&bytes);
        let (joints, frames, frame_time, rows) = header_facts(&text);
        assert_eq!(rows, frames, "{rel}: data rows vs Frames: header");
        let opts = ImportOptions { fps_override: fps_override_for(rel), ..Default::default() };
        let im = import_bytes(rel, &bytes, &opts).unwrap_or_else(|e| panic!("{rel}: {e}"));
        assert_eq!(im.clips.len(), 1);
        let clip = &im.clips[0];
        assert_eq!(clip.frame_count(), frames, "{rel}: frame count");
        assert_eq!(im.skeleton.animated_joint_count(), joints, "{rel}: joint count");
        let expected_fps = fps_override_for(rel).unwrap_or(1.0 / frame_time);
        assert!((clip.fps - expected_fps).abs() < 0.01, "{rel}: fps {} vs {expected_fps}", clip.fps);
        assert!(matches!(im.status, HumanoidStatus::Complete | HumanoidStatus::Partial { .. }), "{rel}: {:?}", im.status);

        // FK sanity: every bone keeps its rest length in every frame (rigid skeleton), and the
        // figure is a plausible human size in metres.
        let rest_len: Vec<f32> = im.skeleton.joints.iter().map(|j| j.rest_offset.length()).collect();
        let has_track: Vec<bool> = (0..im.skeleton.len()).map(|j| clip.translations.iter().any(|t| t.joint == j)).collect();
        let step = (frames / 60).max(1);
        let mut worst = 0f32;
        for f in (0..frames).step_by(step) {
            let p = clip.world_positions(f);
            for (j, joint) in im.skeleton.joints.iter().enumerate() {
                if let (Some(par), false) = (joint.parent, has_track[j]) {
                    worst = worst.max(((p[j] - p[par]).length() - rest_len[j]).abs());
                }
            }
        }
        assert!(worst < 1e-4, "{rel}: a bone length changes by {worst} m across frames");
        let canon = canonical_positions(clip, &im.humanoid);
        let h = odori_core::normalize::body_height(&canon);
        assert!((1.0..2.2).contains(&h), "{rel}: body height {h} m is not human (units wrong?)");
        // Head above hips in the first frame: Y is up.
        let head = canon[Canon::Head.index()];
        let hips = canon[Canon::Hips.index()];
        assert!(head.y > hips.y + 0.3, "{rel}: head {head} not above hips {hips}");
    }
}

#[test]
fn salsa_frame_rate_override_gives_true_durations() {
    let rel = "mocap/cmu-salsa/salsa_01.bvh";
    let bytes = read(rel);
    let header = import_bytes(rel, &bytes, &ImportOptions::default()).unwrap();
    let fixed = import_bytes(rel, &bytes, &ImportOptions { fps_override: Some(60.0), ..Default::default() }).unwrap();
    let (a, b) = (header.clips[0].duration_secs(), fixed.clips[0].duration_secs());
    assert!((b / a - 2.0).abs() < 1e-3, "{a} s at the header's rate, {b} s at 60 fps");
    assert!((20.0..40.0).contains(&b), "salsa_01 lasts {b} s at 60 fps");
}

/// Animation names and durations read from the GLB's JSON chunk, independently.
fn gltf_animations(bytes: &[u8]) -> Vec<(String, f32)> {
    let len = u32::from_le_bytes(bytes[12..16].try_into().unwrap()) as usize;
    let json: serde_json::Value = serde_json::from_slice(&bytes[20..20 + len]).unwrap();
    let acc = json["accessors"].as_array().unwrap();
    json["animations"]
        .as_array()
        .unwrap()
        .iter()
        .map(|a| {
            let dur = a["samplers"]
                .as_array()
                .unwrap()
                .iter()
                .map(|s| acc[s["input"].as_u64().unwrap() as usize]["max"][0].as_f64().unwrap() as f32)
                .fold(0.0, f32::max);
            (a["name"].as_str().unwrap().to_string(), dur)
        })
        .collect()
}

#[test]
fn robot_expressive_gives_its_14_clips_with_names_and_durations() {
    let rel = "gltf/RobotExpressive.glb";
    let bytes = read(rel);
    let expected = gltf_animations(&bytes);
    assert_eq!(expected.len(), 14);
    let im = import_bytes(rel, &bytes, &ImportOptions::default()).unwrap();
    assert_eq!(im.clips.len(), 14);
    for (clip, (name, dur)) in im.clips.iter().zip(&expected) {
        assert_eq!(&clip.name, name);
        // Frames sample 0..=dur at the resampling rate; the clip lasts one frame longer.
        let last_frame_time = (clip.frame_count() - 1) as f32 / clip.fps;
        assert!(last_frame_time >= dur - 1e-4 && last_frame_time < dur + 1.0 / clip.fps, "{name}: last frame at {last_frame_time} s, animation ends at {dur} s");
    }
    for n in ["Dance", "Idle", "Walking", "Running", "Jump", "Wave", "Punch", "ThumbsUp", "Yes", "No"] {
        assert!(im.clips.iter().any(|c| c.name == n), "missing clip {n}");
    }
    assert!(im.status.is_humanoid(), "{:?}", im.status);
    let mesh = im.mesh.expect("the robot's meshes are kept for rendering");
    assert!(mesh.parts.len() >= 10, "{} mesh parts", mesh.parts.len());
    let verts: usize = mesh.parts.iter().map(|p| p.positions.len()).sum();
    assert!(verts > 1000);
    for p in &mesh.parts {
        assert!(p.joints.iter().flatten().all(|&j| (j as usize) < mesh.palette.len()));
    }
    // The skinned, posed mesh stands where the skeleton is: compare the mesh's bounding box
    // in the rest clip frame 0 with the joints' box.
    let clip = im.clips.iter().find(|c| c.name == "Idle").unwrap();
    let mut mats = Vec::new();
    clip.world_matrices_into(0, &mut mats);
    let joints = clip.world_positions(0);
    let (mut lo, mut hi) = (glam::Vec3::splat(f32::MAX), glam::Vec3::splat(f32::MIN));
    for part in &mesh.parts {
        for (k, v) in part.positions.iter().enumerate() {
            let mut w = glam::Vec3::ZERO;
            for s in 0..4 {
                let (j, b) = mesh.palette[part.joints[k][s] as usize];
                w += part.weights[k][s] * (mats[j] * b).transform_point3(glam::Vec3::from(*v));
            }
            lo = lo.min(w);
            hi = hi.max(w);
        }
    }
    let jy_max = joints.iter().map(|p| p.y).fold(f32::MIN, f32::max);
    assert!(lo.y > -0.2 * hi.y && lo.y < 0.2 * hi.y, "mesh bottom {lo} should be near the floor (top {hi})");
    assert!(hi.y > jy_max * 0.9 && hi.y < jy_max * 1.6, "mesh top {} vs highest joint {jy_max}", hi.y);
}

#[test]
fn fox_loads_but_is_not_humanoid() {
    let rel = "gltf/Fox.glb";
    let im = import_bytes(rel, &read(rel), &ImportOptions::default()).unwrap();
    assert_eq!(im.clips.len(), 3);
    let names: Vec<&str> = im.clips.iter().map(|c| c.name.as_str()).collect();
    assert_eq!(names, ["Survey", "Walk", "Run"]);
    match &im.status {
        HumanoidStatus::NotHumanoid { reason } => assert!(reason.contains("upright") || reason.contains("legs"), "{reason}"),
        other => panic!("the fox was taken for a humanoid: {other:?}"),
    }
    assert!(im.mesh.is_some());
}

#[test]
fn every_real_rig_maps_its_limbs_to_the_right_side() {
    // Left limbs end on the figure's left: with the figure facing +Z that is +X, so in the
    // hips' own frame the left hand and foot lie on the left of the right ones, most of the
    // time. (Not for ballet: 005_02's fifth positions cross the feet, so walks and social
    // dance are used here.)
    for rel in ["mocap/cmu-salsa/salsa_02.bvh", "mocap/cmu-modern/005_01.bvh", "mocap/cmu-indian/indian_04.bvh", "gltf/RobotExpressive.glb"] {
        let im = import_bytes(rel, &read(rel), &ImportOptions { fps_override: fps_override_for(rel), ..Default::default() }).unwrap();
        let c = canonical_positions(&im.clips[0], &im.humanoid);
        let n = odori_core::normalize::normalized(&c, Default::default());
        let frames = n.len() / odori_core::humanoid::CANON_COUNT;
        // Median over frames of left-minus-right along the normalised hip axis (+Z).
        let median_gap = |l: Canon, r: Canon| {
            let mut d: Vec<f32> = (0..frames)
                .map(|f| n[f * odori_core::humanoid::CANON_COUNT + l.index()].z - n[f * odori_core::humanoid::CANON_COUNT + r.index()].z)
                .collect();
            d.sort_by(f32::total_cmp);
            d[d.len() / 2]
        };
        assert!(median_gap(Canon::LeftUpperLeg, Canon::RightUpperLeg) > 0.0, "{rel}");
        assert!(median_gap(Canon::LeftFoot, Canon::RightFoot) > 0.0, "{rel}: feet");
        assert!(median_gap(Canon::LeftUpperArm, Canon::RightUpperArm) > 0.0, "{rel}: arms");
        assert!(median_gap(Canon::LeftHand, Canon::RightHand) > 0.0, "{rel}: hands");
    }
}
