//! Figures of issue 6 computed the same way by the tests (which assert on them) and by the
//! `text_figures` bench (which prints them): foot skate during Transitions, sway transfer in
//! "walk while waving", switch times by F against fixed ones.

#![allow(dead_code)]

use glam::{Quat, Vec3};
use odori_core::actions::{compose, join_serial, ActionLibrary, BodyPart, ComposeOptions, CompositionReport, JoinKind, JoinOptions, JoinReport, SwitchTimes};
use odori_core::canon::humanoid::Canon;
use odori_core::Clip;

/// One Transition measured with and without foot locking.
pub struct SkateFigure {
    pub label: String,
    pub with_lock: JoinReport,
    pub without_lock: JoinReport,
}

pub fn skate(a: &Clip, b: &Clip, label: &str) -> SkateFigure {
    let on = JoinOptions::default();
    let off = JoinOptions { foot_lock: false, ..JoinOptions::default() };
    let (_, with_lock) = join_serial(a, b, JoinKind::Transition, &on).expect("join");
    let (_, without_lock) = join_serial(a, b, JoinKind::Transition, &off).expect("join");
    SkateFigure { label: label.to_string(), with_lock, without_lock }
}

/// The built-in Transitions the parser produces most: walk → run, run → walk, run → kick,
/// walk → jump, walk → turn.
pub fn builtin_skates(lib: &ActionLibrary) -> Vec<SkateFigure> {
    let clip = |tag: &str, secs: f32| lib.entries[lib.find(tag, &[]).expect(tag)].clip_for(secs);
    vec![
        skate(&clip("walk", 3.0), &clip("run", 2.0), "walk → run (cycle-aligned)"),
        skate(&clip("run", 2.0), &clip("walk", 3.0), "run → walk (cycle-aligned)"),
        skate(&clip("run", 2.0), &clip("kick", 0.0), "run → kick"),
        skate(&clip("walk", 3.0), &clip("jump", 0.0), "walk → jump"),
        skate(&clip("walk", 3.0), &clip("turn", 0.0), "walk → turn"),
    ]
}

fn world_rotation(clip: &Clip, frame: usize, joint: Canon) -> Quat {
    let n = clip.joint_count();
    let mut j = Some(joint);
    let mut chain = Vec::new();
    while let Some(c) = j {
        chain.push(c.index());
        j = c.parent();
    }
    chain.iter().rev().fold(Quat::IDENTITY, |acc, &i| acc * clip.rotations[frame * n + i])
}

fn correlation(a: &[f32], b: &[f32]) -> f32 {
    let n = a.len().min(b.len()) as f32;
    if n < 3.0 {
        return 0.0;
    }
    let ma = a.iter().sum::<f32>() / n;
    let mb = b.iter().sum::<f32>() / n;
    let (mut sab, mut saa, mut sbb) = (0.0, 0.0, 0.0);
    for (x, y) in a.iter().zip(b) {
        sab += (x - ma) * (y - mb);
        saa += (x - ma) * (x - ma);
        sbb += (y - mb) * (y - mb);
    }
    if saa < 1e-12 || sbb < 1e-12 {
        0.0
    } else {
        sab / (saa * sbb).sqrt()
    }
}

/// Sway figures of "walk while waving the right hand".
pub struct SwayFigure {
    pub report_with: CompositionReport,
    /// Hips and neck: variance of their world-rotation deviation from plain walking over the
    /// composed interval, degrees², with and without sway transfer.
    pub hips_var_with: f32,
    pub hips_var_without: f32,
    pub neck_var_with: f32,
    pub neck_var_without: f32,
    /// Correlation of the neck's sideways tilt velocity with the waving hand's sideways
    /// velocity (relative to the hips), with and without sway transfer.
    pub neck_hand_corr_with: f32,
    pub neck_hand_corr_without: f32,
    /// The same correlation inside the wave clip itself (what the sway carries over).
    pub neck_hand_corr_wave: f32,
}

fn roll_series(clip: &Clip, joint: Canon, frames: std::ops::Range<usize>) -> Vec<f32> {
    frames.map(|f| {
        let up = world_rotation(clip, f, joint) * Vec3::Y;
        let fwd = world_rotation(clip, f, Canon::Hips) * Vec3::Z;
        // Sideways tilt: the joint's up vector along the body's left-right axis.
        let side = Vec3::Y.cross(fwd).normalize_or_zero();
        up.dot(side)
    }).collect()
}

fn hand_side_series(clip: &Clip, frames: std::ops::Range<usize>) -> Vec<f32> {
    frames.map(|f| {
        let p = clip.world_positions(f);
        let fwd = world_rotation(clip, f, Canon::Hips) * Vec3::Z;
        let side = Vec3::Y.cross(fwd).normalize_or_zero();
        (p[Canon::RightHand.index()] - p[Canon::Hips.index()]).dot(side)
    }).collect()
}

fn diff(v: &[f32]) -> Vec<f32> {
    v.windows(2).map(|w| w[1] - w[0]).collect()
}

pub fn sway(lib: &ActionLibrary) -> SwayFigure {
    let walk = lib.entries[lib.find("walk", &[]).unwrap()].clip_for(5.0);
    let wave = lib.entries[lib.find("wave", &["right"]).unwrap()].clip.clone();
    let (with, rep) = compose(&walk, &wave, BodyPart::RightArm, &ComposeOptions::default()).expect("compose");
    let (without, _) = compose(&walk, &wave, BodyPart::RightArm, &ComposeOptions { sway: false, ..ComposeOptions::default() }).expect("compose");
    let t = rep.times;
    let range = t.base_start_frame..t.base_end_frame;
    let dev_var = |c: &Clip, j: Canon| {
        let d: Vec<f32> = range.clone().map(|f| world_rotation(c, f, j).angle_between(world_rotation(&walk, f, j)).to_degrees()).collect();
        let m = d.iter().sum::<f32>() / d.len().max(1) as f32;
        d.iter().map(|x| (x - m) * (x - m)).sum::<f32>() / d.len().max(1) as f32 + m * m
    };
    let corr = |c: &Clip, r: std::ops::Range<usize>| correlation(&diff(&roll_series(c, Canon::Neck, r.clone())), &diff(&hand_side_series(c, r)));
    let wave_range = t.overlay_start_frame..t.overlay_end_frame;
    SwayFigure {
        hips_var_with: dev_var(&with, Canon::Hips),
        hips_var_without: dev_var(&without, Canon::Hips),
        neck_var_with: dev_var(&with, Canon::Neck),
        neck_var_without: dev_var(&without, Canon::Neck),
        neck_hand_corr_with: corr(&with, range.clone()),
        neck_hand_corr_without: corr(&without, range.clone()),
        neck_hand_corr_wave: corr(&wave, wave_range),
        report_with: rep,
    }
}

/// Switch times found by F against fixed ones, for walk + wave: `(label, report)`, F first.
/// Fixed A: both start together and the overlay plays whole at its own speed (what the
/// paper's system did: "現在は同時に開始する"). Fixed B: the overlay's middle 80 % from the
/// base's start (a scheduler that trims the wave's own rest poses).
pub fn switch_times(lib: &ActionLibrary) -> Vec<(&'static str, CompositionReport)> {
    let walk = lib.entries[lib.find("walk", &[]).unwrap()].clip_for(5.0);
    let wave = lib.entries[lib.find("wave", &["right"]).unwrap()].clip.clone();
    let nb = wave.frame_count();
    let run = |fixed: Option<SwitchTimes>| compose(&walk, &wave, BodyPart::RightArm, &ComposeOptions { fixed, ..ComposeOptions::default() }).expect("compose").1;
    vec![
        ("switch times by F", run(None)),
        ("fixed A: together, whole overlay", run(Some(SwitchTimes { base_start_frame: 0, overlay_start_frame: 0, base_end_frame: nb - 1, overlay_end_frame: nb - 1 }))),
        ("fixed B: overlay's middle 80 %", run(Some(SwitchTimes { base_start_frame: 0, overlay_start_frame: nb / 10, base_end_frame: nb * 8 / 10, overlay_end_frame: nb * 9 / 10 }))),
    ]
}

/// Foot skate over a whole animation: for every run of frames where a foot is detected as
/// planted (height and speed, spec §I), the largest horizontal drift from where it landed;
/// `(max, mean over runs)` in cm.
pub fn whole_skate_cm(clip: &Clip) -> (f32, f32) {
    let c = odori_core::actions::detect_contacts(clip);
    let mut runs = Vec::new();
    let mut pose = odori_core::motion::WorldPose::new();
    let mut anchor: [Option<(Vec3, f32)>; 2] = [None, None];
    for f in 0..clip.frame_count() {
        let pos = &pose.of_frame(clip, f).positions;
        for (s, foot) in [Canon::LeftFoot, Canon::RightFoot].into_iter().enumerate() {
            let p = pos[foot.index()];
            if c.frames[f][s] {
                let (a, worst) = anchor[s].get_or_insert((p, 0.0));
                *worst = worst.max(Vec3::new(p.x - a.x, 0.0, p.z - a.z).length());
            } else if let Some((_, w)) = anchor[s].take() {
                runs.push(w);
            }
        }
    }
    runs.extend(anchor.iter().flatten().map(|a| a.1));
    let max = runs.iter().copied().fold(0.0, f32::max) * 100.0;
    let mean = if runs.is_empty() { 0.0 } else { runs.iter().sum::<f32>() / runs.len() as f32 * 100.0 };
    (max, mean)
}
