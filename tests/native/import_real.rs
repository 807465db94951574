//! Every real motion file in ../shared/data imports, and what comes out agrees with the file.

use odori_core::canon::humanoid::{canonical_positions, Canon};
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
        let h = odori_core::canon::normalize::body_height(&canon);
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
    odori_core::motion::WorldPose::new().of_frame(clip, 0).matrices_into(&mut mats);
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
        let n = odori_core::canon::normalize::normalized(&c, Default::default());
        let frames = n.len() / odori_core::canon::humanoid::CANON_COUNT;
        // Median over frames of left-minus-right along the normalised hip axis (+Z).
        let median_gap = |l: Canon, r: Canon| {
            let mut d: Vec<f32> = (0..frames)
                .map(|f| n[f * odori_core::canon::humanoid::CANON_COUNT + l.index()].z - n[f * odori_core::canon::humanoid::CANON_COUNT + r.index()].z)
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

// ---- Units (issue #30, item 8): the unit is guessed from the rig, not the figure's extent ----

use odori_core::import::bvh::figure_height_m;

/// A BVH text rewritten as another tool would have written the same motion: every ROOT/JOINT
/// renamed by `rename`, and every length (OFFSETs, end sites, position channels in every frame)
/// multiplied by `factor`. Parsed here independently of the importer: channel kinds are read
/// from the CHANNELS lines in file order, which is the order of the values in a frame row.
fn rewrite_bvh(text: &str, rename: &dyn Fn(&str) -> String, factor: f32) -> String {
    let mut out = String::with_capacity(text.len());
    let mut is_position: Vec<bool> = Vec::new();
    let mut in_motion = false;
    let mut header_lines = 0;
    for line in text.lines() {
        let mut words = line.split_whitespace();
        let first = words.next().unwrap_or("");
        if in_motion {
            if header_lines < 2 {
                header_lines += 1;
                out.push_str(line);
            } else if !line.trim().is_empty() {
                let row: Vec<String> = line
                    .split_whitespace()
                    .zip(is_position.iter())
                    .map(|(v, &pos)| {
                        let x: f32 = v.parse().unwrap();
                        if pos { (x * factor).to_string() } else { v.to_string() }
                    })
                    .collect();
                assert_eq!(row.len(), is_position.len(), "frame row width");
                out.push_str(&row.join(" "));
            }
        } else {
            match first {
                "ROOT" | "JOINT" => {
                    let name = words.next().unwrap();
                    let indent = &line[..line.len() - line.trim_start().len()];
                    out.push_str(&format!("{indent}{first} {}", rename(name)));
                }
                "OFFSET" => {
                    let v: Vec<String> = words.map(|w| (w.parse::<f32>().unwrap() * factor).to_string()).collect();
                    let indent = &line[..line.len() - line.trim_start().len()];
                    out.push_str(&format!("{indent}OFFSET {}", v.join(" ")));
                }
                "CHANNELS" => {
                    let _count = words.next();
                    is_position.extend(words.map(|w| w.ends_with("position")));
                    out.push_str(line);
                }
                "MOTION" => {
                    in_motion = true;
                    out.push_str(line);
                }
                _ => out.push_str(line),
            }
        }
        out.push('\n');
    }
    out
}

/// The CMU Daz-style rig's joints (the acLSTM salsa/indian/martial files) under Mixamo names;
/// joints Mixamo lacks keep a `mixamorig:` name of what they are.
fn mixamo_name(n: &str) -> String {
    let side = |s: &str| if s.starts_with('l') { "Left" } else { "Right" };
    let m = match n {
        "hip" => "Hips".to_string(),
        "abdomen" => "Spine".into(),
        "chest" => "Spine1".into(),
        "neck" => "Neck".into(),
        "head" => "Head".into(),
        "leftEye" => "LeftEye".into(),
        "rightEye" => "RightEye".into(),
        _ => {
            let (s, rest) = n.split_at(1);
            let s = side(s);
            match rest {
                "Collar" => format!("{s}Shoulder"),
                "Shldr" => format!("{s}Arm"),
                "ForeArm" => format!("{s}ForeArm"),
                "Hand" => format!("{s}Hand"),
                "Buttock" => format!("{s}UpLeg"),
                "Thigh" => format!("{s}UpLegRoll"),
                "Shin" => format!("{s}Leg"),
                "Foot" => format!("{s}Foot"),
                finger => format!("{s}Hand{}", finger.replace("Mid", "Middle")),
            }
        }
    };
    format!("mixamorig:{m}")
}

/// The same rig under CMU ASF names (lfemur, lhumerus, lowerback, ...).
fn cmu_asf_name(n: &str) -> String {
    match n {
        "hip" => "root".into(),
        "abdomen" => "lowerback".into(),
        "chest" => "thorax".into(),
        "neck" => "lowerneck".into(),
        "head" => "head".into(),
        _ => {
            let (s, rest) = n.split_at(1);
            let w = match rest {
                "Collar" => "clavicle",
                "Shldr" => "humerus",
                "ForeArm" => "radius",
                "Hand" => "hand",
                "Buttock" => "hipjoint",
                "Thigh" => "femur",
                "Shin" => "tibia",
                "Foot" => "foot",
                _ => return n.to_string(),
            };
            format!("{s}{w}")
        }
    }
}

/// Height of the figure as imported with the given options, and the warnings.
fn height(rel: &str, text: &str, unit_scale: Option<f32>) -> (f32, Vec<String>) {
    let im = import_bytes(rel, text.as_bytes(), &ImportOptions { unit_scale, ..Default::default() }).unwrap_or_else(|e| panic!("{rel}: {e}"));
    (figure_height_m(&im.clips[0]), im.warnings)
}

#[test]
fn the_guessed_unit_gives_the_documented_height_on_every_real_bvh() {
    // Both sources state centimetres (mocap/SOURCE-cmu-acrnn.txt, cmu-modern/SOURCE.txt): the
    // guess must give the height those give, within 10 %, with no warning.
    let files = all_bvh();
    assert_eq!(files.len(), 29, "expected the 29 BVH files of ../shared/data/mocap, found {files:?}");
    let mut ratios = Vec::new();
    for rel in &files {
        let text = String::from_utf8(read(rel)).unwrap();
        let (documented, _) = height(rel, &text, Some(0.01));
        assert!((1.3..2.1).contains(&documented), "{rel}: {documented} m in centimetres: the reference itself is not a person");
        let (guessed, warnings) = height(rel, &text, None);
        assert!((guessed / documented - 1.0).abs() < 0.1, "{rel}: guessed {guessed:.2} m, documented unit {documented:.2} m");
        assert!(warnings.is_empty(), "{rel}: {warnings:?}");
        ratios.push(guessed / documented);
    }
    let (lo, hi) = ratios.iter().fold((f32::MAX, f32::MIN), |(a, b), &r| (a.min(r), b.max(r)));
    println!("{} real BVH files: guessed height / documented-unit height from {lo:.3} to {hi:.3}", ratios.len());
}

#[test]
fn the_guessed_unit_follows_a_real_rig_rewritten_in_other_units_and_names() {
    // Real motion made into the files other tools write: renamed joints (Mixamo, CMU ASF, or
    // as they are) and every length in metres, centimetres, millimetres, inches or CMU's ASF
    // unit. The figure must come out at the height of the original in centimetres (within 10 %)
    // without a warning. Two rigs: the 43-joint Daz-style CMU rig and the 100-joint iClone one.
    use odori_core::import::bvh::units::{CENTIMETRE, CMU_ASF_UNIT, INCH, METRE, MILLIMETRE};
    let same = |n: &str| n.to_string();
    let cases: [(&str, &str, &dyn Fn(&str) -> String); 4] = [
        ("mocap/cmu-salsa/salsa_01.bvh", "Mixamo", &mixamo_name),
        ("mocap/cmu-indian/indian_04.bvh", "Mixamo", &mixamo_name),
        ("mocap/cmu-salsa/salsa_01.bvh", "as is", &same),
        ("mocap/cmu-modern/005_02.bvh", "as is", &same),
    ];
    for (rel, naming, rename) in cases {
        let text = String::from_utf8(read(rel)).unwrap();
        let (reference, _) = height(rel, &text, Some(0.01));
        for unit in [CENTIMETRE, METRE, MILLIMETRE, INCH] {
            let made = rewrite_bvh(&text, rename, 0.01 / unit.metres);
            if naming == "Mixamo" {
                assert!(made.contains("ROOT mixamorig:Hips") && made.contains("JOINT mixamorig:LeftUpLeg"), "renaming");
            }
            let (h, warnings) = height(rel, &made, None);
            assert!((h / reference - 1.0).abs() < 0.1, "{rel} ({naming} names, {}): {h:.2} m, in centimetres {reference:.2} m", unit.name);
            assert!(warnings.is_empty(), "{rel} ({naming} names, {}): {warnings:?}", unit.name);
            // Control: the importer really read the rewritten lengths (the same file read as
            // centimetres is off by the factor, unless it is centimetres).
            let (as_cm, _) = height(rel, &made, Some(0.01));
            assert!((as_cm / reference - 0.01 / unit.metres).abs() < 0.01 * (0.01 / unit.metres), "{}: {as_cm}", unit.name);
        }
    }
    // CMU's own naming in its ASF unit (1/0.45 inch): the naming tells; by size alone inches
    // would be taken (a 0.7 m figure).
    let rel = "mocap/cmu-salsa/salsa_01.bvh";
    let text = String::from_utf8(read(rel)).unwrap();
    let (reference, _) = height(rel, &text, Some(0.01));
    let made = rewrite_bvh(&text, &cmu_asf_name, 0.01 / CMU_ASF_UNIT.metres);
    assert!(made.contains("JOINT lfemur") && made.contains("JOINT lhumerus"));
    let (h, warnings) = height(rel, &made, None);
    assert!((h / reference - 1.0).abs() < 0.1, "CMU ASF names and unit: {h:.2} m vs {reference:.2} m");
    assert!(warnings.is_empty(), "{warnings:?}");
    let anonymous = rewrite_bvh(&text, &|n: &str| format!("j_{n}").replace("j_hip", "j_pelvis"), 0.01 / CMU_ASF_UNIT.metres);
    let (h_anon, _) = height(rel, &anonymous, None);
    assert!((h_anon / reference - 1.0).abs() > 0.3, "without CMU names the ASF unit is not guessed: {h_anon:.2} m");
}

#[test]
fn the_old_extent_rule_fails_the_rewritten_files() {
    // Control for the test above: the figure's vertical extent alone (the rule this replaced:
    // over 20 units centimetres, over 3 decimetres, else metres) misreads millimetres and
    // inches, so the test above can fail.
    let rel = "mocap/cmu-salsa/salsa_01.bvh";
    let text = String::from_utf8(read(rel)).unwrap();
    let (reference, _) = height(rel, &text, Some(0.01));
    for (per_cm, wrong) in [(10.0f32, "millimetres"), (1.0 / 2.54, "inches")] {
        let made = rewrite_bvh(&text, &mixamo_name, per_cm);
        let (as_cm, _) = height(rel, &made, Some(0.01));
        let extent_units = as_cm * 100.0;
        let old_scale = if extent_units > 20.0 { 0.01 } else if extent_units > 3.0 { 0.1 } else { 1.0 };
        let old_h = as_cm * 100.0 * old_scale;
        assert!((old_h / reference - 1.0).abs() > 0.1, "{wrong}: the extent rule gives {old_h:.2} m");
    }
}
