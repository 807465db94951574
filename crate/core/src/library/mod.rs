//! The built-in dance-move library: the engine's own starter set of moves on the canonical
//! skeleton (no data from outside the project). In 4: every combination of a step
//! (step-touch, grapevine, box step, kick-ball-change, chassé, pivot turn, jump, bounce, hip
//! sway, body roll) with an arm pattern (swing, waves, punches, claps, arm rolls, overhead
//! reaches, arm wave), at three energy levels, leading with the right or (mirrored) the left:
//! 420 moves of one bar of 4 counts. In 3, so a waltz needs no mocap: every combination of a
//! step in 3 (the forward and back halves of the waltz box, balancé, a waltz turn, a
//! hesitation) with an arm pattern in 3 (waltz frame, port de bras, open arms), at the same
//! energies and sides: 90 moves of one bar of 3 counts. Held on the counts, so the dance turns
//! once a count at slow tempi too: every combination of a step keyed only on its counts (side
//! touch, slow grapevine, slow box, sway) with an arm pattern likewise (presses, open and
//! close), at the same energies and sides: 48 moves of one bar of 4 counts. 558 moves in all.
//! Each at 120 counts per minute, 30 fps, with one extra frame (the next bar's first pose) so
//! segment ends have a velocity.
//!
//! Limbs are placed by two-bone IK on authored foot and hand targets ([`pose`]), so planted
//! feet stay on the floor; the root height is then corrected so the lowest point of the body
//! never goes below the floor ([`crate::canon::builtin::lowest_point`]).

pub mod body;
pub mod moves;
pub mod pose;

use std::sync::Arc;

use glam::Vec3;
use serde::{Deserialize, Serialize};

use crate::canon::builtin::canonical_skeleton;
use crate::clip::{Clip, TranslationTrack};
use crate::canon::humanoid::CANON_COUNT;
use crate::skeleton::Skeleton;

pub use moves::{Arms, Energy, Step};

/// Tempo of every built-in move.
pub const BUILTIN_BPM: f32 = 120.0;
/// Frame rate of every built-in move.
pub const BUILTIN_FPS: f32 = 30.0;
/// Counts per built-in move in 4 (one bar); the moves in 3 have 3 ([`MoveInfo::counts`]).
pub const COUNTS: usize = 4;
/// Built-in moves in 4 (the first of [`builtin_moves`]).
pub const MOVES_IN_FOUR: usize = 420;
/// Built-in moves in 3 (after those in 4).
pub const MOVES_IN_THREE: usize = 90;
/// Built-in moves in 4 held on the counts (after those in 3, so every earlier move keeps its
/// place).
pub const MOVES_ON_COUNTS: usize = 48;
/// Standing hips height of the built-in figure with soft knees, metres.
pub const STANDING_HIPS_HEIGHT: f32 = 0.935;

/// What a built-in move is made of.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "camelCase")]
pub struct MoveInfo {
    pub step: Step,
    pub arms: Arms,
    pub energy: Energy,
    /// Led by the figure's left side (the right-leading move mirrored).
    pub mirrored: bool,
}

impl MoveInfo {
    /// Counts of the move (one bar): 3 for a step in 3, else 4.
    pub fn counts(&self) -> usize {
        self.step.counts()
    }

    /// Display name, e.g. "grapevine + claps (high, left)".
    pub fn name(&self) -> String {
        format!(
            "{} + {} ({}, {})",
            self.step.name(),
            self.arms.name(),
            self.energy.name(),
            if self.mirrored { "left" } else { "right" }
        )
    }
}

/// Every built-in move, in a fixed order: the moves in 4 (step, arms, energy, side), then
/// those in 3, then those held on the counts (the same order), so earlier moves keep their
/// places.
pub fn builtin_moves() -> Vec<MoveInfo> {
    let mut out = Vec::with_capacity(MOVES_IN_FOUR + MOVES_IN_THREE + MOVES_ON_COUNTS);
    for (steps, arm_patterns) in [(&Step::ALL[..], &Arms::ALL[..]), (&Step::THREE[..], &Arms::THREE[..]), (&Step::ON_COUNTS[..], &Arms::ON_COUNTS[..])] {
        for &step in steps {
            for &arms in arm_patterns {
                for energy in Energy::ALL {
                    for mirrored in [false, true] {
                        out.push(MoveInfo { step, arms, energy, mirrored });
                    }
                }
            }
        }
    }
    out
}

/// Frames of one built-in move in 4 (4 counts plus the closing frame).
pub fn move_frame_count() -> usize {
    frame_count_of(COUNTS)
}

/// Frames of one built-in move of `counts` counts (plus the closing frame).
pub fn frame_count_of(counts: usize) -> usize {
    (counts as f32 * 60.0 / BUILTIN_BPM * BUILTIN_FPS).round() as usize + 1
}

/// Renders one built-in move as a clip on `skeleton` (the canonical skeleton).
pub fn build_move(info: &MoveInfo, skeleton: &Arc<Skeleton>) -> Clip {
    let legs = moves::leg_poses(info.step, info.energy);
    let track = leg_track(info.step, info.energy, &legs, info.mirrored, skeleton);
    build_move_on_legs(info, skeleton, &legs, &track)
}

/// Time of frame `f` of a built-in move, in counts.
fn frame_counts(f: usize) -> f32 {
    f as f32 * (BUILTIN_BPM / 60.0 / BUILTIN_FPS)
}

/// The solved legs of a step's key poses (at one energy, on one side), frame by frame: the
/// same for every arm pattern, so [`builtin_clips`] solves them once per step, energy and
/// side instead of once per move.
fn leg_track(step: Step, energy: Energy, legs: &[pose::KeyPose], mirrored: bool, skeleton: &Skeleton) -> Vec<pose::LegSolution> {
    (0..frame_count_of(step.counts()))
        .map(|f| {
            // The legs' fields of `moves::pose_at`: the leg keys interpolated (arms change
            // nothing below the hips).
            let p = moves::legs_at(step, energy, legs, frame_counts(f));
            let p = if mirrored { p.mirrored() } else { p };
            pose::solve_legs(skeleton, &p, STANDING_HIPS_HEIGHT)
        })
        .collect()
}

/// [`build_move`] on legs already solved by [`leg_track`] for the move's step, energy and side.
fn build_move_on_legs(info: &MoveInfo, skeleton: &Arc<Skeleton>, legs: &[pose::KeyPose], track: &[pose::LegSolution]) -> Clip {
    let frames = frame_count_of(info.counts());
    let mut rotations = Vec::with_capacity(frames * CANON_COUNT);
    let mut root = Vec::with_capacity(frames);
    for (f, leg) in track.iter().enumerate().take(frames) {
        let mut p = moves::pose_at(info.step, info.arms, info.energy, frame_counts(f), legs);
        if info.mirrored {
            p = p.mirrored();
        }
        let mut local = [glam::Quat::IDENTITY; CANON_COUNT];
        let mut r = pose::solve_upper(skeleton, &p, STANDING_HIPS_HEIGHT, &mut local);
        leg.write_into(&mut local);
        // Never below the floor (toe tips 2 cm above it when flat).
        if leg.lowest < 0.015 {
            r.y += 0.015 - leg.lowest;
        }
        rotations.extend_from_slice(&local);
        root.push(r);
    }
    Clip {
        name: info.name(),
        source: "built-in".into(),
        fps: BUILTIN_FPS,
        skeleton: skeleton.clone(),
        rotations,
        translations: vec![TranslationTrack { joint: 0, values: root }],
    }
}

/// The whole built-in library as clips, one per move, in [`builtin_moves`] order.
pub fn builtin_clips() -> Vec<Clip> {
    builtin_clips_lazily().map(|(clip, _)| clip).collect()
}

/// The built-in moves one at a time, each with its clip, in [`builtin_moves`] order: the same
/// clips as [`builtin_clips`], made as they are asked for, so a caller can spread the work
/// (the page builds the library a slice per task instead of blocking for a second or more).
pub fn builtin_clips_lazily() -> impl Iterator<Item = (Clip, MoveInfo)> {
    let skeleton = Arc::new(canonical_skeleton());
    let mut tracks: Vec<(Step, Energy, Vec<pose::KeyPose>, [Vec<pose::LegSolution>; 2])> = Vec::new();
    builtin_moves()
        .into_iter()
        .map(move |m| {
            let cached = tracks.iter().position(|(s, e, _, _)| *s == m.step && *e == m.energy);
            let i = match cached {
                Some(i) => i,
                None => {
                    // Moves come step by step: the previous step's tracks are done with.
                    tracks.retain(|(s, _, _, _)| *s == m.step);
                    let keys = moves::leg_poses(m.step, m.energy);
                    let sides = [leg_track(m.step, m.energy, &keys, false, &skeleton), leg_track(m.step, m.energy, &keys, true, &skeleton)];
                    tracks.push((m.step, m.energy, keys, sides));
                    tracks.len() - 1
                }
            };
            let (_, _, keys, sides) = &tracks[i];
            (build_move_on_legs(&m, &skeleton, keys, &sides[usize::from(m.mirrored)]), m)
        })
}

/// A neutral standing pose (arms relaxed by the sides) on the canonical skeleton: local
/// rotations and root translation. Used for bars that hold no segment yet.
pub fn neutral_pose() -> (Vec<glam::Quat>, Vec3) {
    let sk = canonical_skeleton();
    let p = pose::KeyPose {
        hips: Vec3::new(0.0, -0.02, 0.0),
        left_foot: Vec3::new(0.13, 0.0, 0.0),
        right_foot: Vec3::new(-0.13, 0.0, 0.0),
        left_hand: Vec3::new(0.08, -0.5, 0.06),
        right_hand: Vec3::new(-0.08, -0.5, 0.06),
        feet_yaw: 0.12,
        ..Default::default()
    };
    let (local, root, _) = pose::solve(&sk, &p, STANDING_HIPS_HEIGHT);
    (local.to_vec(), root)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::canon::humanoid::Canon;

    #[test]
    fn at_least_two_hundred_distinct_moves() {
        let moves = builtin_moves();
        assert!(moves.len() >= 200);
        let mut names: Vec<String> = moves.iter().map(|m| m.name()).collect();
        names.sort();
        names.dedup();
        assert_eq!(names.len(), moves.len());
    }

    #[test]
    fn moves_stay_on_the_floor_and_plant_feet() {
        let sk = Arc::new(canonical_skeleton());
        for info in builtin_moves().iter().step_by(7).chain(builtin_moves()[MOVES_IN_FOUR..].iter().step_by(3)) {
            let c = build_move(info, &sk);
            c.validate().unwrap();
            let mut min_low = f32::MAX;
            let mut max_low = f32::MIN;
            for f in 0..c.frame_count() {
                let p = c.world_positions(f);
                let low = p.iter().map(|v| v.y).fold(f32::MAX, f32::min);
                min_low = min_low.min(low);
                max_low = max_low.max(low);
                // The head stays above the hips: a dancer, not a tumble.
                assert!(p[Canon::Head.index()].y > p[Canon::Hips.index()].y + 0.3, "{} frame {f}", c.name);
            }
            assert!(min_low > -0.01, "{}: below the floor by {min_low}", c.name);
            if info.step != Step::Jump {
                assert!(max_low < 0.06, "{}: lowest point rises to {max_low}: feet not on the floor", c.name);
            }
        }
    }

    #[test]
    fn shared_legs_give_the_same_moves_as_solving_every_pose_whole() {
        let sk = Arc::new(canonical_skeleton());
        let clips = builtin_clips();
        let moves = builtin_moves();
        assert_eq!(clips.len(), moves.len());
        for (i, info) in moves.iter().enumerate().step_by(11).chain(moves.iter().enumerate().skip(MOVES_IN_FOUR).step_by(7)) {
            // Every frame's whole key pose solved at once, as a move is defined.
            let keys = moves::leg_poses(info.step, info.energy);
            let mut rotations = Vec::new();
            let mut root = Vec::new();
            for f in 0..frame_count_of(info.counts()) {
                let p = moves::pose_at(info.step, info.arms, info.energy, frame_counts(f), &keys);
                let p = if info.mirrored { p.mirrored() } else { p };
                let (local, mut r, lowest) = pose::solve(&sk, &p, STANDING_HIPS_HEIGHT);
                if lowest < 0.015 {
                    r.y += 0.015 - lowest;
                }
                rotations.extend_from_slice(&local);
                root.push(r);
            }
            assert_eq!(clips[i].rotations, rotations, "{}", clips[i].name);
            assert_eq!(clips[i].translations[0].values, root, "{}", clips[i].name);
            assert_eq!(clips[i].rotations, build_move(info, &sk).rotations);
        }
    }

    /// Mean foot skate (§J: ankles and toes within the contact band) of a move, cm/s.
    fn skate(info: &MoveInfo, sk: &Arc<Skeleton>) -> f32 {
        let c = build_move(info, sk);
        let frames: Vec<Vec<Vec3>> = (0..c.frame_count()).map(|f| c.world_positions(f)).collect();
        let mut speeds = Vec::new();
        for j in [Canon::LeftFoot, Canon::RightFoot, Canon::LeftToe, Canon::RightToe] {
            let track: Vec<Vec3> = frames.iter().map(|p| p[j.index()]).collect();
            speeds.extend(crate::motion::skate_speeds_cm_s(&track, c.fps));
        }
        crate::motion::mean_p95(&speeds).0
    }

    #[test]
    fn moves_on_the_counts_skate_no_more_than_their_half_count_siblings() {
        // Each step held on the counts against the step keyed on the half count it is made
        // from, at every energy and on both sides: a travelling foot lifted clear between the
        // counts slides less on the floor than one that passes through the "and" keys.
        let sk = Arc::new(canonical_skeleton());
        let moves = builtin_moves();
        assert_eq!(moves.len(), MOVES_IN_FOUR + MOVES_IN_THREE + MOVES_ON_COUNTS);
        assert!(moves[MOVES_IN_FOUR + MOVES_IN_THREE..].iter().all(|m| m.step.on_counts() && m.counts() == 4));
        assert!(moves[..MOVES_IN_FOUR + MOVES_IN_THREE].iter().all(|m| !m.step.on_counts()));
        let mut figures = Vec::new();
        for (held, sibling) in [(Step::SideTouch, Step::StepTouch), (Step::SlowGrapevine, Step::Grapevine), (Step::SlowBox, Step::BoxStep), (Step::Sway, Step::HipSway)] {
            for energy in Energy::ALL {
                for mirrored in [false, true] {
                    let a = skate(&MoveInfo { step: held, arms: Arms::Presses, energy, mirrored }, &sk);
                    let b = skate(&MoveInfo { step: sibling, arms: Arms::Swing, energy, mirrored }, &sk);
                    figures.push(format!("{} {} {}: {a:.1} against {b:.1}", held.name(), energy.name(), mirrored));
                    assert!(a <= b, "{} ({}, mirrored {mirrored}) skates {a:.1} cm/s, its sibling {} {b:.1}", held.name(), energy.name(), sibling.name());
                }
            }
        }
        println!("{}", figures.join("\n"));
    }

    #[test]
    fn moves_on_the_counts_rest_on_every_count() {
        // Every joint's speed has a minimum on each count (within a frame) in the moves held on
        // the counts; the control, the same step keyed on the half count, moves through counts.
        let sk = Arc::new(canonical_skeleton());
        let speed_at = |c: &Clip, f: usize| -> f32 {
            let (a, b) = (c.world_positions(f - 1), c.world_positions(f + 1));
            a.iter().zip(&b).map(|(p, q)| (*q - *p).length()).sum::<f32>()
        };
        let frames_per_count = (BUILTIN_FPS * 60.0 / BUILTIN_BPM).round() as usize;
        for step in Step::ON_COUNTS {
            for arms in Arms::ON_COUNTS {
                let c = build_move(&MoveInfo { step, arms, energy: Energy::High, mirrored: false }, &sk);
                for count in 1..4 {
                    let f = count * frames_per_count;
                    let (on, between) = (speed_at(&c, f), speed_at(&c, f - frames_per_count / 2));
                    assert!(on < 0.1 * between, "{}: speed on count {} {on:.4} against mid-count {between:.4}", c.name, count + 1);
                }
            }
        }
        let control = build_move(&MoveInfo { step: Step::StepTouch, arms: Arms::Swing, energy: Energy::High, mirrored: false }, &sk);
        let f = frames_per_count;
        assert!(speed_at(&control, f) > 0.1 * speed_at(&control, f - frames_per_count / 2), "the control rests on its count too");
    }

    #[test]
    fn mirrored_moves_mirror() {
        let sk = Arc::new(canonical_skeleton());
        let a = build_move(&MoveInfo { step: Step::Grapevine, arms: Arms::Punches, energy: Energy::Medium, mirrored: false }, &sk);
        let b = build_move(&MoveInfo { step: Step::Grapevine, arms: Arms::Punches, energy: Energy::Medium, mirrored: true }, &sk);
        let f = 20;
        let pa = a.world_positions(f);
        let pb = b.world_positions(f);
        let la = pa[Canon::LeftHand.index()];
        let rb = pb[Canon::RightHand.index()];
        assert!((la - Vec3::new(-rb.x, rb.y, rb.z)).length() < 0.02, "{la} vs {rb}");
    }
}
