//! Retargeting onto real characters (spec §L): the built-in dance and the CMU salsa played by
//! Xbot (Mixamo `mixamorig:` rig) and RobotExpressive, checked by the product's own measures
//! (bone directions, forearm/hand roll against the direction-only control, foot skate), then
//! exported on the character's own mesh and skin and re-imported; and the bad characters
//! (not humanoid, no skin, limbs missing) refused with messages naming what is wrong; and the
//! hold's release (issue 27) against the former one on every rig in ../shared/data.

use odori_core::canon::builtin::demo_clip;
use odori_core::canon::character::{report, Character, CharacterError, RetargetOptions, Transfer};
use odori_core::export::gltf::{glb, GlbOptions};
use odori_core::canon::humanoid::{Canon, HumanoidMap};
use odori_core::import::{import_bytes, ImportOptions, Imported};
use odori_core::Clip;
use odori_tests::{fps_override_for, read};

/// A foot joint of the character may move in one frame at most this much further than the
/// source's same joint ever does (at the character's size), m: a held foot dragged out of
/// reach, or snapping back, is a jump a viewer sees. Fixed before the figures were looked at.
const FOOT_JUMP_MARGIN_M: f32 = 0.05;

/// Cases (character, clip, the excess over the source's jump in m, rounded up to the cm) known
/// to break the foot-jump bound: each may not get worse than its figure, a case that comes
/// within the bound must leave the list, and any other case above the bound fails. Main at
/// 78b94ed had 18 here, all RobotExpressive (hips 3.7× wider than the source's at its size).
/// s7-11b took 13 off: a take's calibration frame is neither played nor measured (the CMU
/// salsa and Indian jumps were the swing from it onto the first real pose), and a foot that
/// lands comes down to the source's height over the frames before instead of in one (the
/// built-in moves' jumps: the robot lifts its longer foot higher than the source). Left: on
/// pivot turns the body swings round the held foot and drags the other out of reach; salsa's
/// and Indian's are the robot's free feet themselves (the transfer alone moves them that far).
/// Open (issue #11). The one foot-contact rule (`canon::contact`, measured at the canonical
/// size) made the pivot and waltz turns worse on the robot (1.88× the canonical size: its feet
/// were held on fewer frames when the rule was measured at its size): pivot turns +0.22/+0.18/
/// +0.15 → +0.37/+0.35/+0.29 m (measured +0.362/+0.343/+0.284), the waltz turn +0.13 → +0.15 m
/// (+0.146). Issue 27's mend (`hold.rs`, `Release::Ease`: a foot released far from its free
/// path steps to it over its swing, lifted, instead of snapping back in 0.15 s) lowered them to
/// +0.112/+0.110/+0.189 and the waltz turn to +0.105 m (`a_released_foot_eases_over_its_swing_…`
/// measures it against the former release in the same run). The arm wave's 0.20 is also the
/// ceiling every built-in move is held to: the worst, "pivot turn + arm swing (high, left)",
/// +0.191 m.
const KNOWN_FOOT_JUMPS: &[(&str, &str, f32)] = &[
    ("gltf/RobotExpressive.glb", "mocap/cmu-indian/indian_04.bvh", 0.10),
    ("gltf/RobotExpressive.glb", "pivot turn + arm swing (low, right)", 0.12),
    ("gltf/RobotExpressive.glb", "pivot turn + arm wave (high, right)", 0.20),
    ("gltf/RobotExpressive.glb", "pivot turn + claps (medium, right)", 0.12),
    ("gltf/RobotExpressive.glb", "salsa_01 (20 s)", 0.10),
    // The built-in waltz turn (a move in 3) on RobotExpressive's wide hips, like the pivot turns.
    ("gltf/RobotExpressive.glb", "waltz turn + open arms (high, right)", 0.11),
];

/// Checks one case's foot jump against the bound and the known list: `Err` says what is wrong.
fn check_foot_jump(file: &str, clip: &str, excess_m: f32) -> Result<(), String> {
    let known = KNOWN_FOOT_JUMPS.iter().find(|&&(f, c, _)| f == file && c == clip);
    match known {
        None if excess_m > FOOT_JUMP_MARGIN_M => Err(format!("{file} ← '{clip}': a foot joint jumps {excess_m:+.3} m more than the source's in one frame (bound {FOOT_JUMP_MARGIN_M} m)")),
        Some(&(_, _, ceiling_m)) if excess_m > ceiling_m => Err(format!("{file} ← '{clip}': known foot jump got worse: {excess_m:+.3} m, listed {ceiling_m:+.2} m")),
        Some(_) if excess_m <= FOOT_JUMP_MARGIN_M => Err(format!("{file} ← '{clip}': foot jump {excess_m:+.3} m is now within the bound: take it off KNOWN_FOOT_JUMPS")),
        _ => Ok(()),
    }
}

/// The largest horizontal distance, m, between the character's hips with the feet held and
/// with them free (the transfer's scaled path): how far holding the feet moves the body.
fn body_drift_m(ch: &Character, held: &Clip, free: &Clip) -> f32 {
    let hips = ch.map.get(Canon::Hips).unwrap();
    (0..held.frame_count().min(free.frame_count()))
        .map(|f| {
            let d = held.world_positions(f)[hips] - free.world_positions(f)[hips];
            (d.x * d.x + d.z * d.z).sqrt()
        })
        .fold(0.0, f32::max)
}

fn character(file: &str) -> (Imported, Character) {
    let im = import_bytes(file, &read(file), &ImportOptions::default()).unwrap_or_else(|e| panic!("{e}"));
    let ch = Character::from_imported(file, &im).unwrap_or_else(|e| panic!("{e}"));
    (im, ch)
}

fn salsa() -> (Clip, HumanoidMap) {
    let rel = "mocap/cmu-salsa/salsa_01.bvh";
    let im = import_bytes(rel, &read(rel), &ImportOptions { fps_override: fps_override_for(rel), ..Default::default() }).unwrap();
    // 20 s is plenty for the checks and keeps the test quick.
    let clip = im.clips[0].slice(0, 1200, "salsa_01 (20 s)");
    (clip, im.humanoid)
}

#[test]
fn characters_follow_the_source_twist_included() {
    let demo = demo_clip();
    let demo_map = HumanoidMap::from_skeleton(&demo.skeleton);
    let (salsa, salsa_map) = salsa();
    let mut jumps = Vec::new();
    for file in ["gltf/Xbot.glb", "gltf/RobotExpressive.glb"] {
        let (_, ch) = character(file);
        for (clip, map) in [(&demo, &demo_map), (&salsa, &salsa_map)] {
            let out = ch.retarget(clip, map).unwrap();
            out.validate().unwrap();
            assert_eq!(out.frame_count(), clip.frame_count());
            let r = report(clip, map, &ch, &out);
            let control = report(clip, map, &ch, &ch.retarget_with(clip, map, Transfer::DirectionOnly).unwrap());
            println!(
                "{file} ← '{}': direction median {:.2}° p95 {:.2}°; twist median {:.2}° p95 {:.2}° (direction-only control: {:.2}° / {:.2}°); skate {:.2} cm/s (source {:.2})",
                clip.name,
                r.direction_median_rad.to_degrees(),
                r.direction_p95_rad.to_degrees(),
                r.twist_median_rad.to_degrees(),
                r.twist_p95_rad.to_degrees(),
                control.twist_median_rad.to_degrees(),
                control.twist_p95_rad.to_degrees(),
                r.skate_mean_cm_s,
                r.source_skate_mean_cm_s
            );
            // The transfer itself (feet free): every bone follows the source's direction. With
            // the feet held, the legs bend away from it where IK holds a planted foot or keeps a
            // swing foot's height while the pelvis drops (as they must): most bones still
            // follow exactly, and the legs' share stays bounded.
            let free = report(clip, map, &ch, &ch.retarget_options(clip, map, &RetargetOptions { hold_feet: false, ..Default::default() }).unwrap());
            println!("  feet free: direction median {:.2}° p95 {:.2}°", free.direction_median_rad.to_degrees(), free.direction_p95_rad.to_degrees());
            assert!(free.direction_median_rad.to_degrees() < 1.0 && free.direction_p95_rad.to_degrees() < 2.0, "{file}: feet free {free:?}");
            assert!(r.direction_median_rad.to_degrees() < 2.0 && r.direction_p95_rad.to_degrees() < 12.0, "{file}: {r:?}");
            assert!(r.twist_p95_rad.to_degrees() < 2.0, "{file}: twist {r:?}");
            if let Err(e) = check_foot_jump(file, &clip.name, r.foot_jump_excess_m()) {
                jumps.push(format!("{e}: {r:?}"));
            }
            // Foot skate is asserted on other clips (`held_feet_skate_no_more_than_the_source`).
            // The control loses roll: conjugation must be clearly better where the source rolls.
            assert!(control.twist_p95_rad > r.twist_p95_rad + 0.05, "{file}: control {control:?} vs {r:?}");
        }
    }
    assert!(jumps.is_empty(), "one-frame foot moves against the source's + {FOOT_JUMP_MARGIN_M} m: {jumps:#?}");
}

#[test]
fn retargeted_dance_exports_on_the_characters_own_mesh() {
    let demo = demo_clip();
    let map = HumanoidMap::from_skeleton(&demo.skeleton);
    for file in ["gltf/Xbot.glb", "gltf/RobotExpressive.glb"] {
        let (im, ch) = character(file);
        let out = ch.retarget(&demo, &map).unwrap();
        let bytes = glb(&out.skeleton, &[&out], &GlbOptions { mesh: im.mesh.as_ref() }).unwrap();
        let back = import_bytes("dance.glb", &bytes, &ImportOptions { gltf_fps: out.fps, ..Default::default() }).unwrap();
        assert!(back.mesh.is_some() && back.status.is_humanoid(), "{file}: {:?}", back.status);
        let b = &back.clips[0];
        assert_eq!(b.frame_count(), out.frame_count());
        let (pa, pb) = (out.world_positions(100), b.world_positions(100));
        for (i, j) in out.skeleton.joints.iter().enumerate() {
            let k = b.skeleton.find(&j.name).unwrap();
            assert!((pa[i] - pb[k]).length() < 2e-3, "{file} joint {}: {} vs {}", j.name, pa[i], pb[k]);
        }
    }
}

#[test]
fn bad_characters_are_refused_naming_what_is_missing() {
    let fox = import_bytes("Fox.glb", &read("gltf/Fox.glb"), &ImportOptions::default()).unwrap();
    let e = Character::from_imported("Fox.glb", &fox).unwrap_err();
    assert!(matches!(e, CharacterError::NotHumanoid { .. }), "{e}");
    assert!(e.to_string().contains("Fox.glb"), "{e}");

    let rel = "mocap/cmu-salsa/salsa_01.bvh";
    let bvh = import_bytes(rel, &read(rel), &ImportOptions::default()).unwrap();
    let e = Character::from_imported(rel, &bvh).unwrap_err();
    assert_eq!(e, CharacterError::NoSkin { file: rel.to_string() });

    let mut xbot = import_bytes("Xbot.glb", &read("gltf/Xbot.glb"), &ImportOptions::default()).unwrap();
    xbot.humanoid.joints[Canon::LeftHand.index()] = None;
    xbot.humanoid.joints[Canon::RightLowerLeg.index()] = None;
    let e = Character::from_imported("Xbot.glb", &xbot).unwrap_err();
    assert_eq!(e, CharacterError::MissingLimbs { file: "Xbot.glb".into(), missing: vec!["leftHand".into(), "rightLowerLeg".into()] });
    assert!(e.to_string().contains("leftHand, rightLowerLeg"), "{e}");
}



/// Planted feet held by IK (spec §L): foot skate of the character against the source's + 1
/// cm/s, on clips the benchmark does not print (it takes every 20th built-in move from the
/// first; these are every 20th from the 10th, the built-in demo dance, and CMU modern, Indian
/// and martial-arts capture where the benchmark has salsa), with the free-feet control.
/// - Xbot (a rig in the source's proportions): every clip within the acceptance.
/// - Both characters: fewer cases above the acceptance with the feet held than free, and a
///   lower total skate.
/// - RobotExpressive (hips 3.7× wider than the source's at its size): only the clips in
///   `KNOWN` above the acceptance; the test fails when another joins them, or when one of them
///   is fixed (then it leaves the list).
/// - Every case: no foot joint moves in one frame more than the source's + 5 cm, but for the
///   cases in `KNOWN_FOOT_JUMPS` (each held to its listed figure).
#[test]
fn held_feet_skate_no_more_than_the_source() {
    let mut sources: Vec<(Clip, HumanoidMap)> =
        odori_core::library::builtin_clips().into_iter().skip(10).step_by(20).chain([demo_clip()]).map(|c| {
            let map = HumanoidMap::from_skeleton(&c.skeleton);
            (c, map)
        }).collect();
    assert!(sources.len() >= 10, "{} built-in clips", sources.len());
    // CMU capture of other styles than the benchmark's salsa (20 s of each).
    for rel in ["mocap/cmu-modern/005_01.bvh", "mocap/cmu-indian/indian_04.bvh", "mocap/cmu-martial/martial_04.bvh"] {
        let im = import_bytes(rel, &read(rel), &ImportOptions { fps_override: fps_override_for(rel), ..Default::default() }).unwrap_or_else(|e| panic!("{rel}: {e}"));
        let c = &im.clips[0];
        let frames = c.frame_count().min((20.0 * c.fps) as usize);
        sources.push((c.slice(0, frames, rel), im.humanoid));
    }
    // None since the takes' calibration frame is no longer played (indian_04 was 88 cm/s
    // against the source's 69 with it; 41 against 56 without).
    // The built-in waltz turn (a move in 3, added in issue 26): held 52 cm/s against the
    // source's 34 (free feet: 117) on RobotExpressive's hips, 3.7x wider than the source's; a
    // turn in 3 with the weight on one foot, which the hold's contact rule (30 cm/s) splits.
    // Not fixed by the one contact rule of issue 27; fixed by its mend of the release (a foot
    // released far from its free path steps there, lifted, over its swing): 32.4 against 33.7.
    const KNOWN: [&str; 0] = [];
    for file in ["gltf/Xbot.glb", "gltf/RobotExpressive.glb"] {
        let (_, ch) = character(file);
        let (mut worse, mut worse_names, mut jumps, mut free_worse, mut xbot_worse, mut held_sum, mut free_sum) = (Vec::new(), Vec::new(), Vec::new(), 0, 0, 0.0, 0.0);
        for (clip, map) in &sources {
            let held = ch.retarget(clip, map).unwrap();
            let r = report(clip, map, &ch, &held);
            let free = ch.retarget_options(clip, map, &RetargetOptions { hold_feet: false, ..Default::default() }).unwrap();
            let f = report(clip, map, &ch, &free);
            println!(
                "{file} ← '{}': skate held {:.2} cm/s, free {:.2}, source {:.2}; largest one-frame foot move {:.3} m (source {:.3}, excess {:+.3}); body drift {:.2} m",
                clip.name,
                r.skate_mean_cm_s,
                f.skate_mean_cm_s,
                r.source_skate_mean_cm_s,
                r.foot_jump_m.iter().copied().fold(0.0, f32::max),
                r.source_foot_jump_m.iter().copied().fold(0.0, f32::max),
                r.foot_jump_excess_m(),
                body_drift_m(&ch, &held, &free)
            );
            if let Err(e) = check_foot_jump(file, &clip.name, r.foot_jump_excess_m()) {
                jumps.push(format!("{e}: {:?} m vs source {:?} m", r.foot_jump_m, r.source_foot_jump_m));
            }
            if r.skate_mean_cm_s > r.source_skate_mean_cm_s + 1.0 {
                worse.push(format!("{}: {:.2} vs source {:.2}", clip.name, r.skate_mean_cm_s, r.source_skate_mean_cm_s));
                worse_names.push(clip.name.clone());
                if file.contains("Xbot") {
                    xbot_worse += 1;
                }
            }
            free_worse += usize::from(f.skate_mean_cm_s > f.source_skate_mean_cm_s + 1.0);
            held_sum += r.skate_mean_cm_s;
            free_sum += f.skate_mean_cm_s;
        }
        println!("{file}: {} of {} worse than source + 1 cm/s held, {free_worse} free", worse.len(), sources.len());
        assert_eq!(xbot_worse, 0, "{file}: skate above the source's + 1 cm/s: {worse:#?}");
        if file.contains("RobotExpressive") {
            assert_eq!(worse_names, KNOWN, "{file}: the clips above the source's skate + 1 cm/s changed: {worse:#?}");
        }
        assert!(worse.len() < free_worse && held_sum < free_sum, "{file}: held {} cases (skate sum {held_sum:.1}) vs free {free_worse} ({free_sum:.1}): {worse:#?}", worse.len());
        assert!(jumps.is_empty(), "{file}: one-frame foot moves against the source's + {FOOT_JUMP_MARGIN_M} m: {jumps:#?}");
    }
}

/// The rule the retargeting held feet by before the one contact rule (`canon::contact`): a
/// joint within 5 cm of its floor and slower than 30 cm/s, measured at the character's size
/// (`track` scaled by it). Kept as the control.
fn old_hold_rule(track: &[glam::Vec3], scale: f32, fps: f32) -> Vec<bool> {
    let t: Vec<glam::Vec3> = track.iter().map(|p| *p * scale).collect();
    let heights: Vec<f32> = t.iter().map(|p| p.y).collect();
    let Some(floor) = odori_core::motion::floor_height(&heights) else { return vec![false; t.len()] };
    (0..t.len())
        .map(|f| {
            let (a, b) = (f.saturating_sub(1), (f + 1).min(t.len() - 1));
            let speed_cm_s = glam::Vec3::new(t[b].x - t[a].x, 0.0, t[b].z - t[a].z).length() * fps * 100.0 / (b - a).max(1) as f32;
            t[f].y - floor < 0.05 && speed_cm_s < 30.0
        })
        .collect()
}

/// The one foot-contact rule on the rigs in `../shared/data`: it is measured on the source at
/// the canonical size, so Xbot and RobotExpressive (of different sizes) hold the same frames of
/// the same source, where the rule it replaced (the control, measured at each character's size)
/// held different ones; and each rig's held feet stand where the source's do: of the frames the
/// source's ankle is planted on, the character's ankle (at the canonical size) is planted too
/// on at least 80 % (set after the first run, where the lowest was RobotExpressive's pivot turn,
/// 85 %: its wide hips drag the held foot, issue #11).
#[test]
fn one_contact_rule_holds_the_same_frames_on_rigs_of_any_size() {
    use odori_core::canon::character::measured_source;
    use odori_core::canon::contact::planted_frames;
    let (salsa, salsa_map) = salsa();
    let mut sources: Vec<(Clip, HumanoidMap)> = vec![(salsa, salsa_map)];
    sources.extend(odori_core::library::builtin_clips().into_iter().skip(5).step_by(25).map(|c| {
        let map = HumanoidMap::from_skeleton(&c.skeleton);
        (c, map)
    }));
    let rigs: Vec<Character> = ["gltf/Xbot.glb", "gltf/RobotExpressive.glb"].iter().map(|f| character(f).1).collect();
    let scales: Vec<f32> = rigs.iter().map(|c| c.scale_from_canonical()).collect();
    println!("rig sizes over the canonical: Xbot {:.3}, RobotExpressive {:.3}", scales[0], scales[1]);
    let (mut old_differ, mut points) = (0usize, 0usize);
    for (clip, map) in &sources {
        let src = measured_source(clip, map);
        let frames = src.frame_count();
        let all = src.all_world_positions();
        let n = src.skeleton.len();
        let track = |c: Canon| -> Vec<glam::Vec3> { (0..frames).map(|f| all[f * n + c.index()]).collect() };
        for c in [Canon::LeftFoot, Canon::LeftToe, Canon::RightFoot, Canon::RightToe] {
            let t = track(c);
            let old: Vec<Vec<bool>> = scales.iter().map(|&s| old_hold_rule(&t, s, src.fps)).collect();
            old_differ += (0..frames).filter(|&f| old[0][f] != old[1][f]).count();
            points += frames;
        }
        for (ch, &scale) in rigs.iter().zip(&scales) {
            let out = ch.retarget(clip, map).unwrap();
            let out_all = out.all_world_positions();
            let m = out.skeleton.len();
            let mut line = Vec::new();
            for c in [Canon::LeftFoot, Canon::RightFoot] {
                let src_planted = planted_frames(&track(c), src.fps);
                let j = ch.map.get(c).unwrap();
                let out_track: Vec<glam::Vec3> = (0..out.frame_count()).map(|f| out_all[f * m + j] / scale).collect();
                let out_planted = planted_frames(&out_track, out.fps);
                let down = src_planted.iter().filter(|&&p| p).count();
                let kept = (0..frames.min(out_planted.len())).filter(|&f| src_planted[f] && out_planted[f]).count();
                let share = if down == 0 { 1.0 } else { kept as f32 / down as f32 };
                line.push(format!("{c:?} {kept}/{down}"));
                assert!(share >= 0.8, "{} ← '{}': {c:?} planted on {kept} of the source's {down} planted frames", ch.name, clip.name);
            }
            println!("{} ← '{}': the character's ankle planted where the source's is: {}", ch.name, clip.name, line.join(", "));
        }
    }
    println!(
        "the control (the former hold rule, at each rig's size): Xbot and RobotExpressive disagree on {old_differ} of {points} foot-point frames ({:.1} %) (the one rule measures the source at the canonical size: the same frames on every rig)",
        100.0 * old_differ as f32 / points.max(1) as f32
    );
}

/// Every built-in move (558; not the chosen few above) on both rigs, feet held: the one-frame
/// foot moves over the source's against the bound, printed per rig (how many moves break it,
/// the worst, the mean excess). Asserted: Xbot breaks it on none; RobotExpressive only on the
/// pivot and waltz turns (the families `KNOWN_FOOT_JUMPS` samples), none beyond the worst
/// ceiling listed there. Measured at 8ed782d: Xbot 0 of 510 (worst +0.028 m); RobotExpressive
/// 60 of 510 — all 42 pivot turns (+0.28 to +0.36 m) and all 18 waltz turns (+0.15 to +0.16 m)
/// — worst +0.362 m, mean excess 0.047 m; under the former hold rule (5 cm and 30 cm/s at the
/// character's size, measured by swapping it back in) the same 60, worst +0.220 m, mean 0.032 m.
/// With issue 27's mend of the release (a foot released far from its free path steps there over
/// its swing): the same 60, worst +0.191 m, mean excess 0.030 m; Xbot unchanged. With the 48
/// moves held on the counts (session 26): Xbot 0 of 558 (worst +0.029 m), RobotExpressive the
/// same 60 of 558 (worst +0.191 m, mean excess 0.029 m): none of the 48 breaks the bound.
#[test]
fn every_builtin_move_keeps_its_feet_within_the_jump_bound() {
    let moves = odori_core::library::builtin_clips();
    assert!(moves.len() >= 500, "{} built-in moves", moves.len());
    let ceiling = KNOWN_FOOT_JUMPS.iter().map(|k| k.2).fold(0.0, f32::max);
    for file in ["gltf/Xbot.glb", "gltf/RobotExpressive.glb"] {
        let (_, ch) = character(file);
        let (mut over, mut worst, mut sum) = (Vec::new(), (0.0f32, String::new()), 0.0f32);
        for clip in &moves {
            let map = HumanoidMap::from_skeleton(&clip.skeleton);
            let r = report(clip, &map, &ch, &ch.retarget(clip, &map).unwrap());
            let e = r.foot_jump_excess_m();
            sum += e.max(0.0);
            if e > FOOT_JUMP_MARGIN_M {
                over.push((clip.name.clone(), e));
            }
            if e > worst.0 {
                worst = (e, clip.name.clone());
            }
        }
        println!(
            "{file}: {} built-in moves; one-frame foot move above the source's + {FOOT_JUMP_MARGIN_M} m in {}, worst {:+.3} m ({}), mean excess (≥ 0) {:.4} m",
            moves.len(),
            over.len(),
            worst.0,
            worst.1,
            sum / moves.len() as f32
        );
        if file.contains("Xbot") {
            assert!(over.is_empty(), "{file}: {over:?}");
        } else {
            let other: Vec<_> = over.iter().filter(|(n, _)| !n.starts_with("pivot turn") && !n.starts_with("waltz turn")).collect();
            assert!(other.is_empty(), "{file}: moves other than the pivot and waltz turns break the bound: {other:?}");
            assert!(worst.0 <= ceiling, "{file}: {} jumps {:+.3} m, above the listed ceiling {ceiling} m", worst.1, worst.0);
        }
    }
}

/// Every rig in `../shared/data` that can be a character: Xbot and RobotExpressive (glTF) and
/// the MMD models (each imported alone: textures are not needed to retarget); an MMD model that
/// cannot be a character (mokou_A's hair IK chain) is named and left out.
fn every_rig() -> Vec<Character> {
    use odori_core::mmd::files::{import_files, MmdFilesOptions};
    use odori_core::mmd::mesh::model_character;
    let mut rigs: Vec<Character> = ["gltf/Xbot.glb", "gltf/RobotExpressive.glb"].iter().map(|f| character(f).1).collect();
    for rel in ["mmd/miku_v2/miku_v2.pmd", "mmd/gene/Gene_light.pmx", "mmd/low_poly/miku.pmd", "mmd/low_poly/gumi.pmd", "mmd/mokou/mokou_A.pmd", "mmd/mokou/mokou_B.pmd"] {
        let r = import_files(&[(rel.to_string(), read(rel))], &[], &MmdFilesOptions::default());
        let Some(m) = r.models.into_iter().next() else { panic!("{rel}: not imported: {:?}", r.problems) };
        match model_character(&m.file, &m.model, &[], &m.missing_textures, &[]) {
            Ok(c) => rigs.push(c.character),
            Err(e) => println!("{rel}: not a character ({e}): left out"),
        }
    }
    rigs
}

/// Issue 27's mend of the hold, measured against its control in the same run: a released foot
/// closes its horizontal gap to its free path over its swing, until it lands again (the hold),
/// instead of over 0.15 s (`release_over_swing: false`, the hold before). On every rig in
/// `../shared/data` and every clip this file plays (every built-in move, the demo dance, 20 s
/// of CMU salsa, modern, Indian and martial arts): per rig, the worst and mean one-frame foot
/// move over the source's, the cases above the bound, the mean skate and the cases above the
/// source's + 1 cm/s, and the direction p95 (worst, and the pivot turns'). Asserted: on no rig
/// are the foot jumps (worst, cases above the bound) or the skate cases worse than the control's.
#[test]
fn a_released_foot_eases_over_its_swing_against_the_fixed_ease_control() {
    let mut sources: Vec<(Clip, HumanoidMap)> = odori_core::library::builtin_clips().into_iter().chain([demo_clip()]).map(|c| {
        let map = HumanoidMap::from_skeleton(&c.skeleton);
        (c, map)
    }).collect();
    sources.push(salsa());
    for rel in ["mocap/cmu-modern/005_01.bvh", "mocap/cmu-indian/indian_04.bvh", "mocap/cmu-martial/martial_04.bvh"] {
        let im = import_bytes(rel, &read(rel), &ImportOptions { fps_override: fps_override_for(rel), ..Default::default() }).unwrap_or_else(|e| panic!("{rel}: {e}"));
        let c = &im.clips[0];
        let frames = c.frame_count().min((20.0 * c.fps) as usize);
        sources.push((c.slice(0, frames, rel), im.humanoid));
    }
    #[derive(Default, Debug)]
    struct Figures {
        worst_jump: (f32, String),
        excess_sum: f32,
        over_bound: usize,
        skate_sum: f32,
        skate_worse: usize,
        dir_p95_worst: (f32, String),
        pivot_dir_p95: Vec<f32>,
    }
    let mut failures = Vec::new();
    for ch in every_rig() {
        let mut figures: Vec<Figures> = Vec::new();
        for release_over_swing in [true, false] {
            let mut g = Figures { worst_jump: (f32::NEG_INFINITY, String::new()), ..Default::default() };
            for (clip, map) in &sources {
                let out = ch.retarget_options(clip, map, &RetargetOptions { release_over_swing, ..Default::default() }).unwrap_or_else(|e| panic!("{}: {e}", ch.name));
                let r = report(clip, map, &ch, &out);
                let e = r.foot_jump_excess_m();
                if e > g.worst_jump.0 {
                    g.worst_jump = (e, clip.name.clone());
                }
                g.excess_sum += e.max(0.0);
                g.over_bound += usize::from(e > FOOT_JUMP_MARGIN_M);
                g.skate_sum += r.skate_mean_cm_s;
                g.skate_worse += usize::from(r.skate_mean_cm_s > r.source_skate_mean_cm_s + 1.0);
                let p95 = r.direction_p95_rad.to_degrees();
                if p95 > g.dir_p95_worst.0 {
                    g.dir_p95_worst = (p95, clip.name.clone());
                }
                if clip.name.starts_with("pivot turn") {
                    g.pivot_dir_p95.push(p95);
                }
            }
            g.pivot_dir_p95.sort_by(f32::total_cmp);
            figures.push(g);
        }
        let n = sources.len() as f32;
        for (g, label) in figures.iter().zip(["released over the swing (the hold)", "released over 0.15 s (control)"]) {
            let pivots = &g.pivot_dir_p95;
            println!(
                "{} — {label}: one-frame foot move over the source's: worst {:+.3} m ('{}'), mean excess {:.4} m, {} of {} above +{FOOT_JUMP_MARGIN_M} m; skate mean {:.2} cm/s, {} above the source's + 1; direction p95 worst {:.1}° ('{}'), pivot turns' median {:.1}° worst {:.1}°",
                ch.name,
                g.worst_jump.0,
                g.worst_jump.1,
                g.excess_sum / n,
                g.over_bound,
                sources.len(),
                g.skate_sum / n,
                g.skate_worse,
                g.dir_p95_worst.0,
                g.dir_p95_worst.1,
                pivots.get(pivots.len() / 2).copied().unwrap_or(0.0),
                pivots.last().copied().unwrap_or(0.0)
            );
        }
        let (new, old) = (&figures[0], &figures[1]);
        if new.worst_jump.0 > old.worst_jump.0 + 1e-3 || new.over_bound > old.over_bound || new.skate_worse > old.skate_worse {
            failures.push(format!("{}: the hold's foot jumps or skate are worse than the control's: {new:?} vs {old:?}", ch.name));
        }
    }
    assert!(failures.is_empty(), "{failures:#?}");
}


/// Sessions 21 and 23 (issue 26's speed goal): pass 0 posing only the joints it reads (the hips
/// and legs, and what they hang from: RobotExpressive's feet hang from an IK bone at the root)
/// and pass 1 placing only the joints whose positions it reads, against posing and placing
/// every joint, the control: the same retargeted clip, to the bit, on every rig (the MMD
/// models' extra bones and the robot's detached feet included), on a salsa take.
#[test]
fn the_free_pass_posing_its_legs_alone_changes_no_rigs_frame() {
    let (clip, map) = salsa();
    let clip = clip.slice(0, 600, "salsa_01 (10 s)");
    for ch in every_rig() {
        let lean = ch.retarget_options(&clip, &map, &RetargetOptions::default()).unwrap_or_else(|e| panic!("{}: {e}", ch.name));
        let whole = ch.retarget_options(&clip, &map, &RetargetOptions { free_pass_legs_only: false, ..Default::default() }).unwrap();
        assert!(lean == whole, "{}: the retargeted clip changed", ch.name);
    }
}
