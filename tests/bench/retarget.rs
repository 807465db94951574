//! Retargeting figures (spec §L checks), printed: real clips (CMU salsa, every 20th built-in
//! move) onto Xbot and RobotExpressive, by the product's conjugation and by the direction-only
//! control. Per case: bone direction error (median, p95), forearm/hand twist error (median,
//! p95) for both, foot skate of the character vs the source (mean cm/s; the acceptance item
//! is character ≤ source + 1 cm/s) and vs the control with the feet not held by IK, the
//! largest horizontal drift of the hips that holding the feet causes, the largest one-frame
//! move of a foot joint against the source's (scaled; a held foot snapping back shows here),
//! and the time to retarget per 1000 frames. Under each case whose foot jump is above the
//! source's + 5 cm (the bound `character_retarget` asserts), the frames where it is, per joint.
//! Under each case above the skate bound (and each case whose clip name contains
//! `RETARGET_DETAIL`), what each foot joint's skate is made of: its floor, its frames in the
//! 5 cm band and their speeds, and its height on the source's drag frames, against the source's.
//! Last, the pivot turns on RobotExpressive (every built-in "pivot turn" move the benchmark or
//! `character_retarget` plays), frame by frame where a foot joint breaks that bound: each
//! ankle's move, the pelvis's yaw rate and the stance width, the source's (scaled) against
//! the robot's.
//! `cargo bench -p odori-tests --bench retarget`.

use std::time::Instant;

use glam::Vec3;

use odori_core::canon::character::{measured_source, report, Character, RetargetOptions, Transfer};
use odori_core::canon::humanoid::{Canon, HumanoidMap};
use odori_core::import::{import_bytes, ImportOptions};
use odori_core::Clip;
use odori_tests::{fps_override_for, read};

fn main() {
    let mut sources: Vec<(Clip, HumanoidMap)> = Vec::new();
    for rel in ["mocap/cmu-salsa/salsa_01.bvh", "mocap/cmu-salsa/salsa_02.bvh"] {
        let im = import_bytes(rel, &read(rel), &ImportOptions { fps_override: fps_override_for(rel), ..Default::default() }).unwrap_or_else(|e| panic!("{e}"));
        sources.push((im.clips[0].clone(), im.humanoid));
    }
    let moves = odori_core::library::builtin_clips();
    let move_count = moves.iter().step_by(20).count();
    for m in moves.into_iter().step_by(20) {
        let map = HumanoidMap::from_skeleton(&m.skeleton);
        sources.push((m, map));
    }
    // `RETARGET_DETAIL=name` prints the per-joint skate of the cases whose clip name contains
    // it (cases above the source's skate + 1 cm/s are always printed).
    let detail = std::env::var("RETARGET_DETAIL").ok();
    println!("retarget: {} sources (2 CMU salsa, {move_count} built-in moves)", sources.len());
    println!("{:<22} {:<34} {:>7} {:>7} | {:>7} {:>7} | {:>8} {:>8} | {:>7} {:>7} {:>7} {:>7} {:>7} | {:>6} {:>6} {:>7} | {:>8}", "character", "source", "dir.med", "dir.p95", "tw.med", "tw.p95", "ctl.med", "ctl.p95", "skate", "src", "Δ cm/s", "free", "drift m", "jump m", "src m", "excess", "ms/1k f");
    for file in ["gltf/Xbot.glb", "gltf/RobotExpressive.glb"] {
        let im = import_bytes(file, &read(file), &ImportOptions::default()).unwrap_or_else(|e| panic!("{e}"));
        let ch = Character::from_imported(file, &im).unwrap_or_else(|e| panic!("{e}"));
        let mut worse = 0;
        let mut free_worse = 0;
        let mut deltas = Vec::new();
        let mut dir_p95 = Vec::new();
        let (mut jump_excess, mut drifts) = (Vec::new(), Vec::new());
        for (clip, map) in &sources {
            let t0 = Instant::now();
            let out = ch.retarget(clip, map).unwrap();
            let ms = t0.elapsed().as_secs_f64() * 1000.0 * 1000.0 / clip.frame_count() as f64;
            let r = report(clip, map, &ch, &out);
            let c = report(clip, map, &ch, &ch.retarget_with(clip, map, Transfer::DirectionOnly).unwrap());
            let free_clip = ch.retarget_options(clip, map, &RetargetOptions { hold_feet: false, ..Default::default() }).unwrap();
            let free = report(clip, map, &ch, &free_clip);
            // How far holding the feet moves the body off the free (scaled source) path, m.
            let hips = ch.map.get(odori_core::canon::humanoid::Canon::Hips).unwrap();
            let drift_m = (0..out.frame_count()).map(|f| {
                let d = out.world_positions(f)[hips] - free_clip.world_positions(f)[hips];
                (d.x * d.x + d.z * d.z).sqrt()
            }).fold(0.0f32, f32::max);
            free_worse += usize::from(free.skate_mean_cm_s - free.source_skate_mean_cm_s > 1.0);
            let delta = r.skate_mean_cm_s - r.source_skate_mean_cm_s;
            deltas.push(delta);
            dir_p95.push(r.direction_p95_rad.to_degrees());
            if delta > 1.0 {
                worse += 1;
            }
            let name: String = clip.name.chars().take(34).collect();
            println!(
                "{:<22} {:<34} {:>6.2}° {:>6.2}° | {:>6.2}° {:>6.2}° | {:>7.2}° {:>7.2}° | {:>7.2} {:>7.2} {:>+7.2} {:>7.2} {:>7.2} | {:>6.3} {:>6.3} {:>+7.3} | {:>8.2}",
                file.trim_start_matches("gltf/"),
                name,
                r.direction_median_rad.to_degrees(),
                r.direction_p95_rad.to_degrees(),
                r.twist_median_rad.to_degrees(),
                r.twist_p95_rad.to_degrees(),
                c.twist_median_rad.to_degrees(),
                c.twist_p95_rad.to_degrees(),
                r.skate_mean_cm_s,
                r.source_skate_mean_cm_s,
                delta,
                free.skate_mean_cm_s,
                drift_m,
                r.foot_jump_m.iter().copied().fold(0.0, f32::max),
                r.source_foot_jump_m.iter().copied().fold(0.0, f32::max),
                r.foot_jump_excess_m(),
                ms
            );
            jump_excess.push(r.foot_jump_excess_m());
            drifts.push(drift_m);
            if r.foot_jump_excess_m() > 0.05 {
                println!("{:<22}   one-frame moves above the source's largest + 5 cm (frame: character / source there, m): {}", "", jump_frames(clip, map, &ch, &out, 0.05).join("; "));
            }
            if delta > 1.0 || detail.as_deref().is_some_and(|d| clip.name.contains(d)) {
                for line in skate_joints(clip, map, &ch, &out) {
                    println!("{:<22}   {line}", "");
                }
            }
        }
        deltas.sort_by(f32::total_cmp);
        dir_p95.sort_by(f32::total_cmp);
        println!(
            "{file}: A-pose swing {:.1}°, hip height {:.3} m, leg length {:.3} m; skate worse than source + 1 cm/s in {worse} of {} cases (median Δ {:+.2} cm/s; feet not held: {free_worse}); direction p95 per case: median {:.2}°, worst {:.2}°; one-frame foot move above the source's: worst {:+.3} m, {} cases above +0.05 m; body drift worst {:.2} m",
            ch.arm_swing_rad.to_degrees(),
            ch.hip_height_m(),
            ch.leg_length_m(),
            deltas.len(),
            deltas[deltas.len() / 2],
            dir_p95[dir_p95.len() / 2],
            dir_p95[dir_p95.len() - 1],
            jump_excess.iter().copied().fold(f32::NEG_INFINITY, f32::max),
            jump_excess.iter().filter(|&&e| e > 0.05).count(),
            drifts.iter().copied().fold(0.0, f32::max)
        );
    }
    pivot_turns();
}

/// The pivot turns on RobotExpressive, frame by frame on the frames where a foot joint moves
/// more than the source's largest + 5 cm: each ankle's move (robot / source scaled, m), the
/// pelvis's yaw rate (the hip line's turn per frame, rad; the transfer gives the robot the
/// source's), the stance width (horizontal ankle-to-ankle distance, m, source scaled / robot)
/// the hips' horizontal distance from each ankle (robot), and each source ankle's height above
/// its floor (scaled, m: a foot is held only within 5 cm of it). Every built-in pivot turn that
/// the benchmark (every 20th move) or `character_retarget` (every 20th from the 10th) plays.
fn pivot_turns() {
    let file = "gltf/RobotExpressive.glb";
    let im = import_bytes(file, &read(file), &ImportOptions::default()).unwrap_or_else(|e| panic!("{e}"));
    let ch = Character::from_imported(file, &im).unwrap_or_else(|e| panic!("{e}"));
    let scale = ch.scale_from_canonical();
    let joint = |c: Canon| ch.map.get(c).unwrap_or_else(|| panic!("{file}: no {c:?}"));
    for (_, clip) in odori_core::library::builtin_clips().into_iter().enumerate().filter(|(i, c)| i % 10 == 0 && c.name.starts_with("pivot turn")) {
        let map = HumanoidMap::from_skeleton(&clip.skeleton);
        let out = ch.retarget(&clip, &map).unwrap();
        let src = measured_source(&clip, &map);
        let frames = src.frame_count().min(out.frame_count());
        let (sp, cp): (Vec<_>, Vec<_>) = (0..frames).map(|f| (src.world_positions(f), out.world_positions(f))).unzip();
        let flat = |v: glam::Vec3| glam::Vec3::new(v.x, 0.0, v.z);
        let feet = [Canon::LeftFoot, Canon::LeftToe, Canon::RightFoot, Canon::RightToe];
        let src_move = |f: usize, c: Canon| (sp[f][c.index()] - sp[f - 1][c.index()]).length() * scale;
        let out_move = |f: usize, c: Canon| (cp[f][joint(c)] - cp[f - 1][joint(c)]).length();
        let src_max: Vec<f32> = feet.iter().map(|&c| (1..frames).map(|f| src_move(f, c)).fold(0.0, f32::max)).collect();
        let yaw = |a: glam::Vec3, b: glam::Vec3| (b.z - a.z).atan2(b.x - a.x);
        let wrap = |d: f32| (d + std::f32::consts::PI).rem_euclid(std::f32::consts::TAU) - std::f32::consts::PI;
        let r = report(&clip, &map, &ch, &out);
        // Each source ankle's floor (spec §J: the 1st percentile of its heights), scaled.
        let floor = |c: Canon| odori_core::motion::floor_height(&(0..frames).map(|f| sp[f][c.index()].y * scale).collect::<Vec<_>>()).unwrap_or(0.0);
        let (floor_l, floor_r) = (floor(Canon::LeftFoot), floor(Canon::RightFoot));
        println!("RobotExpressive ← '{}' ({frames} frames at {} fps): excess {:+.3} m; source's largest move per frame (scaled) L ankle {:.3}, L toe {:.3}, R ankle {:.3}, R toe {:.3}", clip.name, clip.fps, r.foot_jump_excess_m(), src_max[0], src_max[1], src_max[2], src_max[3]);
        println!("  {:>5} | {:>13} {:>13} | {:>13} {:>13} | {:>7} | {:>13} | {:>11} | {:>11}", "frame", "L ankle r/s", "R ankle r/s", "L toe r/s", "R toe r/s", "yaw/f", "stance s/r", "hips-L/-R r", "src lift L/R");
        for f in 1..frames {
            if !feet.iter().enumerate().any(|(k, &c)| out_move(f, c) > src_max[k] + 0.05) {
                continue;
            }
            let (sl, sr) = (sp[f][Canon::LeftUpperLeg.index()], sp[f][Canon::RightUpperLeg.index()]);
            let (pl, pr) = (sp[f - 1][Canon::LeftUpperLeg.index()], sp[f - 1][Canon::RightUpperLeg.index()]);
            let yaw_rate = wrap(yaw(sl, sr) - yaw(pl, pr));
            let stance_src = flat(sp[f][Canon::LeftFoot.index()] - sp[f][Canon::RightFoot.index()]).length() * scale;
            let stance_out = flat(cp[f][joint(Canon::LeftFoot)] - cp[f][joint(Canon::RightFoot)]).length();
            let hips = cp[f][joint(Canon::Hips)];
            println!(
                "  {f:>5} | {:>6.3}/{:<6.3} {:>6.3}/{:<6.3} | {:>6.3}/{:<6.3} {:>6.3}/{:<6.3} | {:>+7.3} | {:>6.3}/{:<6.3} | {:>5.3}/{:<5.3} | {:>5.3}/{:<5.3}",
                out_move(f, Canon::LeftFoot),
                src_move(f, Canon::LeftFoot),
                out_move(f, Canon::RightFoot),
                src_move(f, Canon::RightFoot),
                out_move(f, Canon::LeftToe),
                src_move(f, Canon::LeftToe),
                out_move(f, Canon::RightToe),
                src_move(f, Canon::RightToe),
                yaw_rate,
                stance_src,
                stance_out,
                flat(hips - cp[f][joint(Canon::LeftFoot)]).length(),
                flat(hips - cp[f][joint(Canon::RightFoot)]).length(),
                sp[f][Canon::LeftFoot.index()].y * scale - floor_l,
                sp[f][Canon::RightFoot.index()].y * scale - floor_r,
            );
        }
    }
}

/// Per foot joint, what the skate (spec §J: horizontal speed on the frames within 5 cm of the
/// joint's floor, the 1st percentile of its heights) is made of, for the character and the
/// source (at the character's size): the floor, how many frames are in the band, their summed
/// and mean speed; and on the source's drag frames (in its band and faster than 30 cm/s) each
/// one's height above its own floor (mean, lowest) and world height (mean): a character joint that sinks below where
/// the source's is lowers its floor, and its slow frames drop out of the band.
fn skate_joints(clip: &Clip, map: &HumanoidMap, ch: &Character, out: &Clip) -> Vec<String> {
    let src = measured_source(clip, map);
    let scale = ch.scale_from_canonical();
    let frames = src.frame_count().min(out.frame_count());
    let (sp, cp): (Vec<_>, Vec<_>) = (0..frames).map(|f| (src.world_positions(f), out.world_positions(f))).unzip();
    let fps = src.fps;
    let mut lines = Vec::new();
    for c in [Canon::LeftFoot, Canon::LeftToe, Canon::RightFoot, Canon::RightToe] {
        let Some(j) = ch.map.get(c) else { continue };
        let s: Vec<_> = sp.iter().map(|p| p[c.index()] * scale).collect();
        let o: Vec<_> = cp.iter().map(|p| p[j]).collect();
        let floor = |t: &[Vec3]| odori_core::motion::floor_height(&t.iter().map(|p| p.y).collect::<Vec<_>>()).unwrap_or(0.0);
        let (fs, fo) = (floor(&s), floor(&o));
        let speed = |t: &[Vec3], f: usize| (t[f] - t[f - 1]).with_y(0.0).length() * fps * 100.0;
        let band = |t: &[Vec3], fl: f32| -> (usize, f32) {
            let v: Vec<f32> = (1..frames).filter(|&f| t[f].y - fl < 0.05).map(|f| speed(t, f)).collect();
            (v.len(), v.iter().sum())
        };
        let ((ns, ss), (no, so)) = (band(&s, fs), band(&o, fo));
        let drag: Vec<usize> = (1..frames).filter(|&f| s[f].y - fs < 0.05 && speed(&s, f) > 30.0).collect();
        let heights = |t: &[Vec3], fl: f32| -> (f32, f32) {
            let h: Vec<f32> = drag.iter().map(|&f| t[f].y - fl).collect();
            (h.iter().sum::<f32>() / h.len().max(1) as f32, h.iter().copied().fold(f32::INFINITY, f32::min))
        };
        let ((hs, ls), (ho, lo)) = (heights(&s, fs), heights(&o, fo));
        lines.push(format!(
            "{c:?}: floor {fo:+.3} m (source {fs:+.3}); in band {no} frames, sum {so:.0}, mean {:.1} cm/s (source {ns}, {ss:.0}, {:.1}); on the source's {} drag frames, height above its floor: mean {ho:+.3} lowest {lo:+.3} m (source {hs:+.3} / {ls:+.3}); world y mean {:+.3} (source {:+.3})",
            so / no.max(1) as f32,
            ss / ns.max(1) as f32,
            drag.len(),
            drag.iter().map(|&f| o[f].y).sum::<f32>() / drag.len().max(1) as f32,
            drag.iter().map(|&f| s[f].y).sum::<f32>() / drag.len().max(1) as f32,
        ));
    }
    lines
}

/// Per foot joint, the frames where the character's one-frame move is more than `margin_m`
/// above the largest the source's same joint makes (at the character's size, as
/// `character::report` measures): the first three, with the character's and the source's move
/// on that frame, and how many there are.
fn jump_frames(clip: &Clip, map: &HumanoidMap, ch: &Character, out: &Clip, margin_m: f32) -> Vec<String> {
    let src = measured_source(clip, map);
    let scale = ch.scale_from_canonical();
    let frames = src.frame_count().min(out.frame_count());
    let (sp, cp): (Vec<_>, Vec<_>) = (0..frames).map(|f| (src.world_positions(f), out.world_positions(f))).unzip();
    let mut parts = Vec::new();
    for c in [Canon::LeftFoot, Canon::LeftToe, Canon::RightFoot, Canon::RightToe] {
        let Some(j) = ch.map.get(c) else { continue };
        let src_move = |f: usize| (sp[f][c.index()] - sp[f - 1][c.index()]).length() * scale;
        let src_max = (1..frames).map(src_move).fold(0.0, f32::max);
        let over: Vec<usize> = (1..frames).filter(|&f| (cp[f][j] - cp[f - 1][j]).length() > src_max + margin_m).collect();
        if over.is_empty() {
            continue;
        }
        let first: Vec<String> = over.iter().take(3).map(|&f| format!("{f}: {:.3} / {:.3}", (cp[f][j] - cp[f - 1][j]).length(), src_move(f))).collect();
        parts.push(format!("{c:?} ({} frames; source's largest {src_max:.3}) {}", over.len(), first.join(", ")));
    }
    parts
}
