//! Quality measures of a clip or a dance (spec §J): kinetic speed and kinetic beats, the two
//! published Beat Alignment Scores (BAS-music after Bailando/EDGE, BAS-motion after
//! FACT/AIST++) with the half-beat-shifted control, kinetic beats per second, foot skate and
//! EDGE's Physical Foot Contact score (PFC), the join jump at bar joins, and the perceptual
//! distance the preference test's simulated user judges by. The app shows them per bar and for
//! the whole dance; the benchmarks print them.
//!
//! Everything is computed on the canonical joints at [`QUALITY_FPS`], after the body is scaled
//! to the canonical figure's height ([`standard_body_height`]) but not moved: placement and
//! height above the floor matter for foot skate, and one scale makes centimetres comparable
//! between a small and a tall dancer.

use crate::fmath;
use std::sync::{Arc, OnceLock};

use glam::{Quat, Vec3};
use serde::{Deserialize, Serialize};
use thiserror::Error;

use crate::bars::Bar;
use crate::canon::builtin::canonical_skeleton;
use crate::clip::Clip;
use crate::canon::humanoid::{canonical_positions, Canon, HumanoidMap, CANON_COUNT};
use crate::canon::normalize::{body_height, normalize_in_place, Origin};

/// Frame rate every measure works at (spec §J).
pub const QUALITY_FPS: f32 = 30.0;
/// σ of the Gaussian that smooths the kinetic speed, frames (spec §J).
pub const SPEED_SIGMA_FRAMES: f32 = 2.0;
/// σ of the Beat Alignment Score, seconds (3 frames at 30 fps).
pub const BAS_SIGMA_SECS: f32 = 0.1;
/// Frames around a join (each side) searched for its jump: 0.1 s, covering the 5-frame
/// Hermite rewrite at 60 fps that the renderer does.
pub const JOIN_REACH_FRAMES: usize = 3;
/// Frames a frame must be from every join to count as "inside a segment" (0.2 s).
pub const JOIN_CLEAR_FRAMES: usize = 6;
/// Frames both motions are time-normalised to by the perceptual distance (spec §J).
pub const PERCEPTUAL_FRAMES: usize = 32;
/// The largest join jump a generated dance should have (spec §J; the goal): joins no
/// more abrupt than 1.5 times the sharpest moments (95th percentile) of the moves themselves.
/// What Generate's join repair keeps to ([`super::GenerateOptions::join_jump_goal`]) and the
/// rendered dance's held feet respect ([`super::render`]).
pub const JOIN_JUMP_GOAL: f32 = 1.5;

/// The feet joints foot skate watches: ankles and toes.
const FOOT_JOINTS: [Canon; 4] = [Canon::LeftFoot, Canon::LeftToe, Canon::RightFoot, Canon::RightToe];

/// Why a measure could not be computed.
#[derive(Debug, Error, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "camelCase")]
pub enum QualityError {
    #[error("positions hold {values} joint positions, not a whole number of {joints}-joint frames")]
    RaggedPositions { values: usize, joints: usize },
    #[error("frame rate {fps} is not a positive finite number")]
    BadFps { fps: f32 },
    #[error("the motion has {frames} frame(s) at {fps} fps: the measures need at least 3")]
    TooShort { frames: usize, fps: f32 },
    #[error("beat {index} at {value} s is not finite or comes before the beat before it")]
    BadBeat { index: usize, value: f32 },
    #[error("the dance has no bars")]
    NoBars,
}

/// Body height ([`body_height`]) of the canonical figure in its rest pose, metres: every
/// motion is scaled to it before measuring.
pub fn standard_body_height() -> f32 {
    static H: OnceLock<f32> = OnceLock::new();
    *H.get_or_init(|| {
        let rest = canonical_skeleton().rest_positions();
        if rest.len() == CANON_COUNT {
            body_height(&rest)
        } else {
            1.0
        }
    })
}

/// Canonical joint positions at [`QUALITY_FPS`], scaled to the standard body height, frame-major.
#[derive(Clone, Debug, PartialEq)]
pub struct QualityMotion {
    pub positions: Vec<Vec3>,
}

impl QualityMotion {
    /// From any clip: mapped onto the canonical joints (missing ones filled from neighbours),
    /// then as [`QualityMotion::from_positions`].
    /// Only the clip frames the resampling weighs are posed (at 60 fps every other one: a
    /// [`QUALITY_FPS`] frame falling on a clip frame weighs the next by 0, and an unposed frame
    /// is 0, so the lerp gives the same bits), the figures those of posing them all
    /// ([`canonical_positions`]; the test `from_clip_poses_only_what_it_reads`).
    pub fn from_clip(clip: &Clip) -> Result<Self, QualityError> {
        Self::from_clip_reusing(clip, None).0
    }

    /// [`QualityMotion::from_clip`], each frame that is the same bits in `last` (a clip and the
    /// canonical positions this gave it, handed back as the second value: the held-feet rule's
    /// rounds measure one dance held differently) copied from it, not posed again: the same
    /// motion. Also how many frames were copied.
    pub(crate) fn from_clip_reusing(clip: &Clip, last: Option<(&Clip, &[Vec3])>) -> (Result<Self, QualityError>, Vec<Vec3>, usize) {
        let map = HumanoidMap::from_skeleton(&clip.skeleton);
        let frames = clip.frame_count();
        if !(clip.fps.is_finite() && clip.fps > 0.0) || frames < 3 {
            return (Self::from_positions(&canonical_positions(clip, &map), clip.fps), Vec::new(), 0);
        }
        let n = clip.skeleton.len();
        let last = last.filter(|(c, p)| p.len() == frames * CANON_COUNT && c.fps.to_bits() == clip.fps.to_bits() && c.frame_count() == frames && Arc::ptr_eq(&c.skeleton, &clip.skeleton) && c.translations.len() == clip.translations.len() && c.translations.iter().zip(&clip.translations).all(|(a, b)| a.joint == b.joint && a.values.len() == b.values.len() && b.values.len() == frames));
        let bits = |q: &Quat| q.to_array().map(f32::to_bits);
        let same = |c: &Clip, f: usize| {
            c.rotations[f * n..(f + 1) * n].iter().zip(&clip.rotations[f * n..(f + 1) * n]).all(|(a, b)| bits(a) == bits(b))
                && c.translations.iter().zip(&clip.translations).all(|(a, b)| a.values[f].to_array().map(f32::to_bits) == b.values[f].to_array().map(f32::to_bits))
        };
        let mut pos = vec![Vec3::ZERO; frames * CANON_COUNT];
        let mut posed = vec![false; frames];
        let mut copied = 0;
        let mut pose = crate::motion::WorldPose::new();
        for (f0, f1, a) in resample_frames(frames, clip.fps) {
            for f in if a != 0.0 { [Some(f0), Some(f1)] } else { [Some(f0), None] }.into_iter().flatten() {
                if std::mem::replace(&mut posed[f], true) {
                    continue;
                }
                let out = f * CANON_COUNT..(f + 1) * CANON_COUNT;
                if let Some((_, p)) = last.filter(|(c, _)| same(c, f)) {
                    pos[out.clone()].copy_from_slice(&p[out]);
                    copied += 1;
                    continue;
                }
                let world = &pose.of_frame(clip, f).positions;
                let out = &mut pos[f * CANON_COUNT..(f + 1) * CANON_COUNT];
                for (slot, c) in out.iter_mut().zip(Canon::ALL) {
                    *slot = map.get(c).and_then(|j| world.get(j).copied()).unwrap_or(Vec3::NAN);
                }
                crate::canon::humanoid::fill_missing(out);
            }
        }
        (Self::from_positions(&pos, clip.fps), pos, copied)
    }

    /// The frames of a clip of `frames` frames at `fps` that [`QualityMotion::from_clip`] poses
    /// (and so reads): a measure of a clip reads only these, and the others need not be posed.
    pub(crate) fn frames_read(frames: usize, fps: f32) -> Vec<bool> {
        if !(fps.is_finite() && fps > 0.0) || frames < 3 {
            return vec![true; frames];
        }
        let mut read = vec![false; frames];
        for (f0, f1, a) in resample_frames(frames, fps) {
            read[f0] = true;
            if a != 0.0 {
                read[f1] = true;
            }
        }
        read
    }

    /// [`QualityMotion::from_clip`] of `clip` from its joints' world positions already posed
    /// (`world`: frame-major, the clip's skeleton's joints, [`crate::motion::WorldPose::of_frame`]'s
    /// on every frame [`QualityMotion::frames_read`] marks; the others are not read): the same
    /// motion, the clip not posed again. `None` where `from_clip` would not pose frames one by
    /// one (too short, a bad frame rate) or `world` is not of the clip.
    pub(crate) fn from_posed(clip: &Clip, world: &[Vec3]) -> Option<Result<Self, QualityError>> {
        let (frames, n) = (clip.frame_count(), clip.skeleton.len());
        if !(clip.fps.is_finite() && clip.fps > 0.0) || frames < 3 || world.len() != frames * n {
            return None;
        }
        let map = HumanoidMap::from_skeleton(&clip.skeleton);
        let mut pos = vec![Vec3::ZERO; frames * CANON_COUNT];
        for (f, read) in Self::frames_read(frames, clip.fps).into_iter().enumerate() {
            if !read {
                continue;
            }
            let posed = &world[f * n..(f + 1) * n];
            let out = &mut pos[f * CANON_COUNT..(f + 1) * CANON_COUNT];
            for (slot, c) in out.iter_mut().zip(Canon::ALL) {
                *slot = map.get(c).and_then(|j| posed.get(j).copied()).unwrap_or(Vec3::NAN);
            }
            crate::canon::humanoid::fill_missing(out);
        }
        Some(Self::from_positions(&pos, clip.fps))
    }

    /// [`QualityMotion::from_clip`] posing every frame of the clip ([`canonical_positions`]):
    /// the control ([`super::GenerateOptions::quick_measures`] off).
    pub fn from_clip_every_frame(clip: &Clip) -> Result<Self, QualityError> {
        Self::from_positions(&canonical_positions(clip, &HumanoidMap::from_skeleton(&clip.skeleton)), clip.fps)
    }

    /// From canonical positions at `fps` (frame-major): linearly resampled to
    /// [`QUALITY_FPS`] over the same duration and scaled to [`standard_body_height`].
    pub fn from_positions(positions: &[Vec3], fps: f32) -> Result<Self, QualityError> {
        if positions.len() % CANON_COUNT != 0 {
            return Err(QualityError::RaggedPositions { values: positions.len(), joints: CANON_COUNT });
        }
        if !(fps.is_finite() && fps > 0.0) {
            return Err(QualityError::BadFps { fps });
        }
        let frames = positions.len() / CANON_COUNT;
        if frames < 3 {
            return Err(QualityError::TooShort { frames, fps });
        }
        let samples = resample_frames(frames, fps);
        let out_frames = samples.len();
        let mut out = Vec::with_capacity(out_frames * CANON_COUNT);
        for (f0, f1, a) in samples {
            for j in 0..CANON_COUNT {
                out.push(positions[f0 * CANON_COUNT + j].lerp(positions[f1 * CANON_COUNT + j], a));
            }
        }
        if out_frames < 3 {
            return Err(QualityError::TooShort { frames: out_frames, fps: QUALITY_FPS });
        }
        let scale = standard_body_height() / body_height(&out);
        if scale.is_finite() && scale > 0.0 {
            out.iter_mut().for_each(|p| *p *= scale);
        }
        Ok(Self { positions: out })
    }

    pub fn frames(&self) -> usize {
        self.positions.len() / CANON_COUNT
    }

    pub fn duration_secs(&self) -> f32 {
        self.frames().saturating_sub(1) as f32 / QUALITY_FPS
    }

    fn at(&self, f: usize, c: Canon) -> Vec3 {
        self.positions[f * CANON_COUNT + c.index()]
    }
}

/// Each [`QUALITY_FPS`] frame of a motion of `frames` frames (at least 1) at `fps`: the two
/// frames it lies between and how far it is from the first.
fn resample_frames(frames: usize, fps: f32) -> Vec<(usize, usize, f32)> {
    let duration = frames.saturating_sub(1) as f32 / fps;
    let out_frames = ((duration * QUALITY_FPS).round() as usize + 1).max(1);
    (0..out_frames)
        .map(|k| {
            let x = (k as f32 * fps / QUALITY_FPS).min(frames.saturating_sub(1) as f32);
            let f0 = x.floor() as usize;
            (f0, (f0 + 1).min(frames.saturating_sub(1)), x - f0 as f32)
        })
        .collect()
}

/// Gaussian smoothing with σ `sigma` samples; the kernel is renormalised at the ends.
fn gaussian_smooth(x: &[f32], sigma: f32) -> Vec<f32> {
    let r = (3.0 * sigma).ceil() as isize;
    let kernel: Vec<f32> = (-r..=r).map(|k| fmath::exp(-(k * k) as f32 / (2.0 * sigma * sigma))).collect();
    let n = x.len() as isize;
    (0..n)
        .map(|i| {
            let (mut s, mut w) = (0.0, 0.0);
            for k in -r..=r {
                let j = i + k;
                if (0..n).contains(&j) {
                    let kw = kernel[(k + r) as usize];
                    s += kw * x[j as usize];
                    w += kw;
                }
            }
            s / w
        })
        .collect()
}

/// Kinetic speed e(t), metres per second: the mean over joints of ‖x_j(t) − x_j(t−1)‖ · fps,
/// Gaussian-smoothed with σ = 2 frames (frame 0 takes frame 1's speed).
pub fn kinetic_speed(m: &QualityMotion) -> Vec<f32> {
    let frames = m.frames();
    let mut e = vec![0.0f32; frames];
    // Joint by joint over every frame: each frame's sum still adds its joints in order (the
    // same bits), and the frames' sums no longer wait on each other.
    for j in 0..CANON_COUNT {
        for f in 1..frames {
            e[f] += (m.positions[f * CANON_COUNT + j] - m.positions[(f - 1) * CANON_COUNT + j]).length();
        }
    }
    for s in e.iter_mut().skip(1) {
        *s = *s / CANON_COUNT as f32 * QUALITY_FPS;
    }
    if frames > 1 {
        e[0] = e[1];
    }
    gaussian_smooth(&e, SPEED_SIGMA_FRAMES)
}

/// Below this, m/s, two kinetic speeds count as equal: f32 rounding of positions a metre from
/// the origin wobbles a steady speed by ~1e-5 m/s, which must not make beats.
const SPEED_TOLERANCE: f32 = 1e-4;

/// Kinetic beats: the frames where the kinetic speed has a strict local minimum (lower than
/// both neighbours by more than rounding).
pub fn kinetic_beat_frames(speed: &[f32]) -> Vec<usize> {
    (1..speed.len().saturating_sub(1))
        .filter(|&t| speed[t] + SPEED_TOLERANCE < speed[t - 1] && speed[t] + SPEED_TOLERANCE < speed[t + 1])
        .collect()
}

/// Kinetic beats of a motion, seconds.
pub fn kinetic_beats_secs(m: &QualityMotion) -> Vec<f32> {
    kinetic_beat_frames(&kinetic_speed(m)).into_iter().map(|f| f as f32 / QUALITY_FPS).collect()
}

/// Mean over `targets` of exp(−min_k (t − k)² / 2σ²), k over `against` (sorted). `None` when
/// there is no target; 0 for every target when `against` is empty.
fn alignment(targets: &[f32], against: &[f32], sigma_secs: f32) -> Option<f32> {
    if targets.is_empty() {
        return None;
    }
    let s: f32 = targets
        .iter()
        .map(|&t| {
            let i = against.partition_point(|&k| k < t);
            let d = [i.checked_sub(1), Some(i)]
                .into_iter()
                .flatten()
                .filter_map(|j| against.get(j))
                .map(|&k| (k - t).abs())
                .fold(f32::INFINITY, f32::min);
            if d.is_finite() {
                fmath::exp(-(d * d) / (2.0 * sigma_secs * sigma_secs))
            } else {
                0.0
            }
        })
        .sum();
    Some(s / targets.len() as f32)
}

/// BAS-music (Bailando, EDGE): the mean over music beats of how close the nearest kinetic
/// beat is (σ = [`BAS_SIGMA_SECS`]). Both lists sorted, seconds; `None` without music beats.
pub fn bas_music(music_beats_secs: &[f32], kinetic_beats_secs: &[f32]) -> Option<f32> {
    alignment(music_beats_secs, kinetic_beats_secs, BAS_SIGMA_SECS)
}

/// BAS-motion (FACT/AIST++): the mean over kinetic beats of how close the nearest music beat
/// is. `None` without kinetic beats.
pub fn bas_motion(music_beats_secs: &[f32], kinetic_beats_secs: &[f32]) -> Option<f32> {
    alignment(kinetic_beats_secs, music_beats_secs, BAS_SIGMA_SECS)
}

/// The control beats: every beat moved by half a beat (half the interval to the next beat;
/// the last one by half the interval before it).
pub fn half_shifted(beats_secs: &[f32]) -> Vec<f32> {
    let n = beats_secs.len();
    (0..n)
        .map(|i| {
            let step = if i + 1 < n {
                beats_secs[i + 1] - beats_secs[i]
            } else if n >= 2 {
                beats_secs[n - 1] - beats_secs[n - 2]
            } else {
                0.0
            };
            beats_secs[i] + 0.5 * step
        })
        .collect()
}

/// Checks beats are finite and non-decreasing.
pub fn check_beats(beats_secs: &[f32]) -> Result<(), QualityError> {
    for (i, &b) in beats_secs.iter().enumerate() {
        if !b.is_finite() || (i > 0 && b < beats_secs[i - 1]) {
            return Err(QualityError::BadBeat { index: i, value: b });
        }
    }
    Ok(())
}

/// Foot skate summary, centimetres per second of horizontal speed while on the floor.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "camelCase")]
pub struct FootSkate {
    pub mean_cm_per_s: f32,
    pub p95_cm_per_s: f32,
    /// Joint-frames on the floor the figures are over.
    pub contacts: usize,
}

/// Per frame (index = frame) and foot joint, the horizontal speed in cm/s of each ankle/toe
/// that is on the floor by the engine's one contact rule's height band
/// ([`crate::canon::contact::within_band`]: within 5 cm of its floor; the motion is at the
/// canonical size, as the rule wants); `None` when it is off the floor. Frame 0 has no speed.
/// The floor is the 1st percentile of that joint's height over the whole motion, its index
/// rounded where `motion::floor_height` (the rule's other readers) truncates it: the same
/// joint-frames to within one sample's height. Kept so: taking the other index moves the skate
/// figures by that sample and, through Generate's skate terms, the generated dances
/// (`dance_fixture`: bar 1 of the Sugar Plum piece takes another cut).
pub fn foot_skate_samples(m: &QualityMotion) -> Vec<[Option<f32>; 4]> {
    let frames = m.frames();
    let mut out = vec![[None; 4]; frames];
    for (k, &c) in FOOT_JOINTS.iter().enumerate() {
        let mut heights: Vec<f32> = (0..frames).map(|f| m.at(f, c).y).collect();
        let floor = nth_smallest(&mut heights, ((frames - 1) as f32 * 0.01).round() as usize);
        for f in 1..frames {
            let p = m.at(f, c);
            if crate::canon::contact::within_band(p.y - floor) {
                let d = p - m.at(f - 1, c);
                out[f][k] = Some((d.x * d.x + d.z * d.z).sqrt() * QUALITY_FPS * 100.0);
            }
        }
    }
    out
}

/// Mean and 95th percentile of the skate samples of frames `range`.
pub fn summarize_skate(samples: &[[Option<f32>; 4]], range: std::ops::Range<usize>) -> FootSkate {
    let mut v: Vec<f32> = samples.get(range).unwrap_or(&[]).iter().flat_map(|s| s.iter().flatten().copied()).collect();
    if v.is_empty() {
        return FootSkate::default();
    }
    // Sorted for the mean: summed in rising order, as its figures (and the dances that follow
    // them, `dance_fixture`) have been measured. Unstable: values equal in `total_cmp`'s order
    // are the same bits, so the order is the stable sort's.
    v.sort_unstable_by(f32::total_cmp);
    let mean = v.iter().sum::<f32>() / v.len() as f32;
    FootSkate { mean_cm_per_s: mean, p95_cm_per_s: percentile_select(&mut v, 0.95), contacts: v.len() }
}

/// Foot skate over the whole motion.
pub fn foot_skate(m: &QualityMotion) -> FootSkate {
    let s = foot_skate_samples(m);
    summarize_skate(&s, 0..s.len())
}

/// The `i`-th smallest of `v` in [`f32::total_cmp`]'s order (`v` reordered): the value sorting
/// would put at `i` (values equal in that order are the same bits), without the sort.
fn nth_smallest(v: &mut [f32], i: usize) -> f32 {
    *v.select_nth_unstable_by(i, f32::total_cmp).1
}

/// The `q` quantile of `v` (0 when empty; `v` reordered): the value sorting would put at
/// `round((len − 1) · q)`, selected ([`nth_smallest`]). The one percentile rule of the foot
/// skate's and the join jumps' 95th percentiles.
fn percentile_select(v: &mut [f32], q: f32) -> f32 {
    if v.is_empty() {
        return 0.0;
    }
    let i = ((v.len() - 1) as f32 * q).round() as usize;
    nth_smallest(v, i)
}

/// EDGE's Physical Foot Contact score ×10⁴ (lower is better): the mean over frames of
/// min(v_left ankle, v_left toe) · min(v_right ankle, v_right toe) · â(t), with foot speeds in
/// metres per frame and â the root's acceleration with its upward component clamped at 0 from
/// below, divided by its maximum over the motion. As EDGE computes it (both feet sliding while
/// the body is accelerated is what no real dancer does).
pub fn pfc(m: &QualityMotion) -> f32 {
    let frames = m.frames();
    if frames < 3 {
        return 0.0;
    }
    let root = |f: usize| m.at(f, Canon::Hips);
    // Root acceleration at frames 1..frames-1 (index t-1).
    let acc: Vec<f32> = (1..frames - 1)
        .map(|f| {
            let mut a = (root(f + 1) - root(f)) - (root(f) - root(f - 1));
            a.y = a.y.max(0.0);
            a.length()
        })
        .collect();
    let max = acc.iter().copied().fold(0.0f32, f32::max);
    if max <= 0.0 {
        return 0.0;
    }
    let v = |f: usize, c: Canon| (m.at(f + 1, c) - m.at(f, c)).length();
    let sum: f32 = (1..frames - 1)
        .map(|f| {
            let l = v(f, Canon::LeftFoot).min(v(f, Canon::LeftToe));
            let r = v(f, Canon::RightFoot).min(v(f, Canon::RightToe));
            l * r * acc[f - 1] / max
        })
        .sum();
    sum / (frames - 2) as f32 * 1e4
}

/// Per frame t (1..frames−1), the largest change of any joint's velocity between
/// consecutive frames, m/s per frame: max_j ‖v_j(t) − v_j(t−1)‖, v_j(t) = (x_j(t+1) − x_j(t))·fps.
pub fn velocity_changes(m: &QualityMotion) -> Vec<f32> {
    let frames = m.frames();
    let mut out = vec![0.0f32; frames];
    // The largest squared change first, then its length: a square root and a product by a
    // positive constant are correctly rounded and never decrease, so the length of the
    // largest is the largest length, to the bit (one root a frame, not one a joint).
    for f in 1..frames.saturating_sub(1) {
        let most = (0..CANON_COUNT)
            .map(|j| {
                let x = |t: usize| m.positions[t * CANON_COUNT + j];
                ((x(f + 1) - x(f)) - (x(f) - x(f - 1))).length_squared()
            })
            .fold(0.0, f32::max);
        out[f] = most.sqrt() * QUALITY_FPS;
    }
    out
}

/// Join jump at each join (frames at [`QUALITY_FPS`] where a bar starts): the largest velocity
/// change within [`JOIN_REACH_FRAMES`] of it, divided by the 95th percentile of the same
/// change over the frames at least [`JOIN_CLEAR_FRAMES`] from every join (inside segments).
/// 1 means a join is as abrupt as the sharpest moments of the segments themselves.
pub fn join_jumps(m: &QualityMotion, joins: &[usize]) -> Vec<f32> {
    join_jumps_normed(m, joins).0
}

thread_local! {
    /// The divisor [`join_jumps_normed`] uses instead of the motion's own 95th percentile, while
    /// [`with_join_normaliser`] runs.
    static JOIN_NORMALISER: std::cell::Cell<Option<f32>> = const { std::cell::Cell::new(None) };
}

/// Runs `f` with every join jump divided by `p95` instead of the measured motion's own 95th
/// percentile: a stretch of a dance measured as part of the whole
/// ([`super::figures::played_near`]), by the whole dance's divisor.
pub(crate) fn with_join_normaliser<R>(p95: f32, f: impl FnOnce() -> R) -> R {
    let outer = JOIN_NORMALISER.with(|n| n.replace(Some(p95)));
    let out = f();
    JOIN_NORMALISER.with(|n| n.set(outer));
    out
}

/// [`join_jumps`] and the divisor they were taken by (the 95th percentile, or the one
/// [`with_join_normaliser`] gives).
pub(crate) fn join_jumps_normed(m: &QualityMotion, joins: &[usize]) -> (Vec<f32>, f32) {
    let c = velocity_changes(m);
    let n = c.len();
    let p95 = match JOIN_NORMALISER.with(|n| n.get()) {
        Some(p) => p,
        None => {
            let mut inside: Vec<f32> =
                (1..n.saturating_sub(1)).filter(|&f| joins.iter().all(|&j| f.abs_diff(j) >= JOIN_CLEAR_FRAMES)).map(|f| c[f]).collect();
            percentile_select(&mut inside, 0.95).max(1e-6)
        }
    };
    let jumps = joins
        .iter()
        .map(|&j| {
            let lo = j.saturating_sub(JOIN_REACH_FRAMES).max(1);
            let hi = (j + JOIN_REACH_FRAMES).min(n.saturating_sub(2));
            (lo..=hi).map(|f| c[f]).fold(0.0f32, f32::max) / p95
        })
        .collect();
    (jumps, p95)
}

/// Beat alignment of one stretch: on the true beats and on the half-shifted control.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "camelCase")]
pub struct BeatAlignment {
    pub bas_music: f32,
    pub bas_music_shifted: f32,
    pub bas_motion: f32,
    pub bas_motion_shifted: f32,
    /// Kinetic beats per second in the stretch (report beside BAS: jitter inflates BAS).
    pub kinetic_beats_per_sec: f32,
    /// Music beats per second in the stretch.
    pub music_beats_per_sec: f32,
}

/// Beat alignment of the stretch `start_secs..end_secs`: music beats and kinetic beats in it
/// (each matched against the other list over the whole motion, so a beat at the stretch's edge
/// finds its partner across it).
pub fn beat_alignment(music_beats_secs: &[f32], kinetic_secs: &[f32], start_secs: f32, end_secs: f32) -> BeatAlignment {
    let shifted = half_shifted(music_beats_secs);
    let within = |v: &[f32]| -> Vec<f32> { v.iter().copied().filter(|&t| t >= start_secs && t < end_secs).collect() };
    let (mb, sb, kb) = (within(music_beats_secs), within(&shifted), within(kinetic_secs));
    let span = (end_secs - start_secs).max(1e-6);
    BeatAlignment {
        bas_music: alignment(&mb, kinetic_secs, BAS_SIGMA_SECS).unwrap_or(0.0),
        bas_music_shifted: alignment(&sb, kinetic_secs, BAS_SIGMA_SECS).unwrap_or(0.0),
        bas_motion: alignment(&kb, music_beats_secs, BAS_SIGMA_SECS).unwrap_or(0.0),
        bas_motion_shifted: alignment(&kb, &shifted, BAS_SIGMA_SECS).unwrap_or(0.0),
        kinetic_beats_per_sec: kb.len() as f32 / span,
        music_beats_per_sec: mb.len() as f32 / span,
    }
}

/// The readout of one bar.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "camelCase")]
pub struct BarQuality {
    pub bar: usize,
    pub beats: BeatAlignment,
    pub foot_skate: FootSkate,
    /// Join jump at the bar's start (`None` for the first bar).
    pub join_jump: Option<f32>,
}

/// The readout of a whole dance, and of each bar.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "camelCase")]
pub struct DanceQuality {
    pub beats: BeatAlignment,
    pub foot_skate: FootSkate,
    pub pfc: f32,
    pub join_jump_mean: f32,
    pub join_jump_max: f32,
    pub bars: Vec<BarQuality>,
}

/// Summary of a motion without music (a source clip): what a dance made of it is compared to.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "camelCase")]
pub struct MotionQuality {
    pub kinetic_beats_per_sec: f32,
    pub foot_skate: FootSkate,
    pub pfc: f32,
}

/// Quality of a motion with no music.
pub fn motion_quality(m: &QualityMotion) -> MotionQuality {
    let kb = kinetic_beats_secs(m);
    MotionQuality { kinetic_beats_per_sec: kb.len() as f32 / m.duration_secs().max(1e-6), foot_skate: foot_skate(m), pfc: pfc(m) }
}

/// Quality of a dance rendered to `clip` (frame 0 = song time 0) over `bars`, against the
/// song's beats. Beats outside the bars are not scored.
pub fn dance_quality(clip: &Clip, bars: &[Bar], music_beats_secs: &[f32]) -> Result<DanceQuality, QualityError> {
    let m = QualityMotion::from_clip(clip)?;
    dance_quality_of(&m, bars, music_beats_secs)
}

/// [`dance_quality`] of a motion already at [`QUALITY_FPS`].
pub fn dance_quality_of(m: &QualityMotion, bars: &[Bar], music_beats_secs: &[f32]) -> Result<DanceQuality, QualityError> {
    dance_quality_switched_of(m, bars, music_beats_secs, &[])
}

/// [`dance_quality`] of a dance whose joins fall at `switch_secs` (song time of the switch into
/// bar i + 1's move, one per bar after the first, as [`super::render_switched`] reports them):
/// each join jump is measured there, wherever it falls; a join not given is on its bar line.
pub fn dance_quality_switched(clip: &Clip, bars: &[Bar], music_beats_secs: &[f32], switch_secs: &[f32]) -> Result<DanceQuality, QualityError> {
    let m = QualityMotion::from_clip(clip)?;
    dance_quality_switched_of(&m, bars, music_beats_secs, switch_secs)
}

/// Where bar `i`'s join falls (`i` ≥ 1): `switch_secs[i - 1]` when given and finite, else the
/// bar's start.
pub fn switch_of(bars: &[Bar], switch_secs: &[f32], i: usize) -> f32 {
    let start = bars.get(i).map_or(0.0, |b| b.start_secs);
    i.checked_sub(1).and_then(|k| switch_secs.get(k)).copied().filter(|t| t.is_finite()).unwrap_or(start)
}

/// [`dance_quality_switched`] of a motion already at [`QUALITY_FPS`].
pub fn dance_quality_switched_of(m: &QualityMotion, bars: &[Bar], music_beats_secs: &[f32], switch_secs: &[f32]) -> Result<DanceQuality, QualityError> {
    check_beats(music_beats_secs)?;
    let (Some(first), Some(last)) = (bars.first(), bars.last()) else { return Err(QualityError::NoBars) };
    let d = DanceMeasures::of(m, bars, switch_secs);
    let jumps = &d.jumps;
    Ok(DanceQuality {
        beats: beat_alignment(music_beats_secs, &d.kinetic, first.start_secs, last.end_secs),
        foot_skate: d.skate_in(first.start_secs, last.end_secs),
        pfc: pfc(m),
        join_jump_mean: if jumps.is_empty() { 0.0 } else { jumps.iter().sum::<f32>() / jumps.len() as f32 },
        join_jump_max: jumps.iter().copied().fold(0.0, f32::max),
        bars: d.bar_qualities(bars, music_beats_secs),
    })
}

/// The frame of a motion of `frames` frames at [`QUALITY_FPS`] that time `t` (seconds) falls
/// on: the nearest, clamped to `0..=frames`.
pub fn frame_at(t: f32, frames: usize) -> usize {
    ((t * QUALITY_FPS).round().max(0.0) as usize).min(frames)
}

/// §J's measures of a rendered dance over its bars, each taken once, for every figure read of
/// them (the readout [`dance_quality_switched_of`] and the pipeline's
/// [`super::figures`]): kinetic beats, foot skate samples, and the join jump at each switch
/// that has a frame after it.
#[derive(Clone, Debug, PartialEq)]
pub struct DanceMeasures {
    /// The motion's frames.
    pub frames: usize,
    /// Kinetic beats, seconds ([`kinetic_beats_secs`]).
    pub kinetic: Vec<f32>,
    /// Foot skate samples per frame ([`foot_skate_samples`]).
    pub skate: Vec<[Option<f32>; 4]>,
    /// The bar after each join measured (bars 1.., in order; a join with no frame after it is
    /// left out, except by [`DanceMeasures::of_every_join`]), and its jump ([`join_jumps`]).
    pub joins: Vec<usize>,
    pub jumps: Vec<f32>,
    /// Whether every join has a frame after it: then [`DanceMeasures::of`] and
    /// [`DanceMeasures::of_every_join`] are the same measures.
    pub every_join_inside: bool,
    /// The divisor of the join jumps ([`join_jumps_normed`]).
    pub join_norm: f32,
}

impl DanceMeasures {
    /// The measures of `m` over `bars`, its joins falling at `switch_secs` ([`switch_of`]).
    pub fn of(m: &QualityMotion, bars: &[Bar], switch_secs: &[f32]) -> DanceMeasures {
        Self::with_joins(m, bars, switch_secs, false)
    }

    /// [`DanceMeasures::of`] keeping every join, one on the motion's last frame too (its jump
    /// read over the frames before it): what the held-feet rule has always read
    /// ([`super::render`]), a jump for every bar after the first. A join lands there only on a
    /// last bar shorter than about two frames (a switch is at most a count past its bar line).
    pub(crate) fn of_every_join(m: &QualityMotion, bars: &[Bar], switch_secs: &[f32]) -> DanceMeasures {
        Self::with_joins(m, bars, switch_secs, true)
    }

    fn with_joins(m: &QualityMotion, bars: &[Bar], switch_secs: &[f32], every: bool) -> DanceMeasures {
        let frames = m.frames();
        let all: Vec<(usize, usize)> = (1..bars.len()).map(|i| (i, frame_at(switch_of(bars, switch_secs, i), frames))).collect();
        let every_join_inside = all.iter().all(|&(_, f)| f + 1 < frames);
        let joins: Vec<(usize, usize)> = all.into_iter().filter(|&(_, f)| every || f + 1 < frames).collect();
        let (jumps, join_norm) = join_jumps_normed(m, &joins.iter().map(|&(_, f)| f).collect::<Vec<_>>());
        DanceMeasures { frames, kinetic: kinetic_beats_secs(m), skate: foot_skate_samples(m), joins: joins.into_iter().map(|j| j.0).collect(), jumps, every_join_inside, join_norm }
    }

    /// The jump of the join into bar `bar`, if it was measured.
    pub fn jump_into(&self, bar: usize) -> Option<f32> {
        self.joins.binary_search(&bar).ok().and_then(|k| self.jumps.get(k)).copied()
    }

    /// [`frame_at`] in this motion.
    pub fn frame_of(&self, t: f32) -> usize {
        frame_at(t, self.frames)
    }

    /// Each bar's readout against `music_beats_secs`.
    pub fn bar_qualities(&self, bars: &[Bar], music_beats_secs: &[f32]) -> Vec<BarQuality> {
        let mut jumps = self.joins.iter().zip(&self.jumps).peekable();
        bars.iter()
            .enumerate()
            .map(|(i, b)| BarQuality {
                bar: i,
                beats: beat_alignment(music_beats_secs, &self.kinetic, b.start_secs, b.end_secs),
                foot_skate: self.skate_in(b.start_secs, b.end_secs),
                join_jump: jumps.next_if(|&(&bar, _)| bar == i).map(|(_, &j)| j),
            })
            .collect()
    }

    /// Each bar's readout on `counts` ([`DanceMeasures::bar_qualities`]) and the whole dance's
    /// over `bars`, taken once for every figure read of them: the held-feet rule's last round
    /// and the played figures read the same one ([`super::render`], [`super::figures`]).
    pub fn readout(&self, bars: &[Bar], counts: &[f32]) -> Option<DanceReadout> {
        let (first, last) = (bars.first()?, bars.last()?);
        Some(DanceReadout {
            bars: self.bar_qualities(bars, counts),
            beats: beat_alignment(counts, &self.kinetic, first.start_secs, last.end_secs),
            foot_skate: self.skate_in(first.start_secs, last.end_secs),
            kinetic_beats: self.kinetic_in(first.start_secs, last.end_secs),
        })
    }

    /// Kinetic beats in `start_secs..end_secs`.
    pub fn kinetic_in(&self, start_secs: f32, end_secs: f32) -> usize {
        self.kinetic.iter().filter(|&&t| t >= start_secs && t < end_secs).count()
    }

    /// Foot skate over the frames of `start_secs..end_secs`.
    pub fn skate_in(&self, start_secs: f32, end_secs: f32) -> FootSkate {
        summarize_skate(&self.skate, self.frame_of(start_secs)..self.frame_of(end_secs))
    }
}

/// §J's readout of a dance from its [`DanceMeasures`] ([`DanceMeasures::readout`]).
#[derive(Clone, Debug, PartialEq)]
pub struct DanceReadout {
    /// Each bar's, on the counts given.
    pub bars: Vec<BarQuality>,
    /// The whole dance's (its bars' span), on the counts given.
    pub beats: BeatAlignment,
    pub foot_skate: FootSkate,
    /// Kinetic beats within the bars.
    pub kinetic_beats: usize,
}

/// For each bar, whether its window (`start_secs..end_secs`) holds exactly its own counts of
/// `counts` ([`super::figures::bar_counts_secs`]: each bar's counts in turn): then
/// [`beat_alignment`] on the bar over all `counts` is the same, to the bit, as on its own
/// counts (it keeps the counts inside the window, in their order). Not always so: a bar that
/// ends an ulp past the next one's start (`start + bar` against `first + (i + 1)·bar`, as
/// [`super::bars_from_tempo`] makes them) holds the next bar's first count too.
pub fn bars_hold_own_counts(bars: &[Bar], counts: &[f32]) -> Vec<bool> {
    // Sorted counts: those before a bar's are outside its window when the one just before is,
    // and those after when the one just after is.
    let sorted = counts.windows(2).all(|w| w[0] <= w[1]) && bars.iter().map(Bar::beat_count).sum::<usize>() == counts.len();
    let mut at = 0;
    bars.iter()
        .map(|b| {
            let n = b.beat_count();
            let own = (at, at + n);
            at += n;
            let inside = |t: f32| t >= b.start_secs && t < b.end_secs;
            sorted && counts[own.0..own.1].iter().all(|&t| inside(t)) && !own.0.checked_sub(1).is_some_and(|k| inside(counts[k])) && !counts.get(own.1).is_some_and(|&t| inside(t))
        })
        .collect()
}

/// The perceptual distance of the preference test (spec §J), deliberately not the one the
/// search uses: both motions (canonical positions, frame-major, any lengths) time-normalised
/// to [`PERCEPTUAL_FRAMES`] frames, normalised as §B (hips origin, facing, body height), then
/// the mean joint-position distance. In body heights; 0 for identical motions.
pub fn perceptual_distance(a: &[Vec3], b: &[Vec3]) -> Result<f32, QualityError> {
    let (pa, pb) = (perceptual_frames(a)?, perceptual_frames(b)?);
    Ok(pa.iter().zip(&pb).map(|(x, y)| (*x - *y).length()).sum::<f32>() / pa.len() as f32)
}

/// One motion as [`perceptual_distance`] compares it: canonical positions (frame-major, any
/// length) time-normalised to [`PERCEPTUAL_FRAMES`] frames and normalised as §B. The distance
/// of two such is the mean of their joint-position distances; benches that compare many pairs
/// prepare each motion once with this.
pub fn perceptual_frames(p: &[Vec3]) -> Result<Vec<Vec3>, QualityError> {
    if p.is_empty() || p.len() % CANON_COUNT != 0 {
        return Err(QualityError::RaggedPositions { values: p.len(), joints: CANON_COUNT });
    }
    let frames = p.len() / CANON_COUNT;
    let mut out = Vec::with_capacity(PERCEPTUAL_FRAMES * CANON_COUNT);
    for k in 0..PERCEPTUAL_FRAMES {
        let x = k as f32 * (frames - 1) as f32 / (PERCEPTUAL_FRAMES - 1) as f32;
        let f0 = x.floor() as usize;
        let f1 = (f0 + 1).min(frames - 1);
        let w = x - f0 as f32;
        for j in 0..CANON_COUNT {
            out.push(p[f0 * CANON_COUNT + j].lerp(p[f1 * CANON_COUNT + j], w));
        }
    }
    let h = body_height(&out);
    normalize_in_place(&mut out, Origin::Hips, h);
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_nth_smallest_is_what_sorting_puts_there() {
        // Ties, both zeros, repeats and a long run, against the sorted slice at every index.
        let mut x = 7u32;
        let v: Vec<f32> = (0..500)
            .map(|i| {
                x = x.wrapping_mul(1664525).wrapping_add(1013904223);
                match i % 7 {
                    0 => 0.0,
                    1 => -0.0,
                    2 => 1.25,
                    _ => (x >> 8) as f32 / (1u32 << 24) as f32 - 0.5,
                }
            })
            .collect();
        let mut sorted = v.clone();
        sorted.sort_by(f32::total_cmp);
        for i in 0..v.len() {
            assert_eq!(nth_smallest(&mut v.clone(), i).to_bits(), sorted[i].to_bits(), "index {i}");
        }
        // The percentile: the sorted slice at round((len − 1) · q), on every length to 500.
        for len in 1..=v.len() {
            let mut s = v[..len].to_vec();
            s.sort_by(f32::total_cmp);
            for q in [0.01f32, 0.5, 0.95] {
                let want = s[((len - 1) as f32 * q).round() as usize];
                assert_eq!(percentile_select(&mut v[..len].to_vec(), q).to_bits(), want.to_bits(), "len {len}, q {q}");
            }
        }
        assert_eq!(percentile_select(&mut [], 0.95), 0.0);
    }

    /// A standing canonical figure (rest pose) translated by `offset`, one frame.
    fn rest_frame(offset: Vec3) -> Vec<Vec3> {
        let rest = canonical_skeleton().rest_positions();
        let floor = rest.iter().map(|p| p.y).fold(f32::INFINITY, f32::min);
        rest.iter().map(|p| *p - Vec3::Y * floor + offset).collect()
    }

    /// `frames` frames at 30 fps of the rest figure, moved by `at(frame)`.
    fn motion(frames: usize, at: impl Fn(usize) -> Vec3) -> QualityMotion {
        let pos: Vec<Vec3> = (0..frames).flat_map(|f| rest_frame(at(f))).collect();
        QualityMotion::from_positions(&pos, QUALITY_FPS).unwrap()
    }

    /// A figure bobbing up and down so it turns (speed 0) every `period` frames from `phase`
    /// (give a phase off the frame grid: an exactly symmetric turn makes a two-frame tie, no
    /// strict minimum).
    fn bobbing(frames: usize, period: f32, phase: f32) -> QualityMotion {
        motion(frames, |f| Vec3::new(0.0, 0.1 * fmath::cos((f as f32 - phase) / period * std::f32::consts::PI), 0.0))
    }

    #[test]
    fn the_standard_height_is_a_body_and_scaling_is_applied() {
        let h = standard_body_height();
        assert!((1.0..2.0).contains(&h), "standard body height {h}");
        // A figure twice as big is scaled back.
        let pos: Vec<Vec3> = (0..10).flat_map(|_| rest_frame(Vec3::ZERO)).map(|p| p * 2.0).collect();
        let m = QualityMotion::from_positions(&pos, 30.0).unwrap();
        assert!((body_height(&m.positions) - h).abs() < 1e-3);
    }

    #[test]
    fn kinetic_speed_joint_by_joint_keeps_every_bit() {
        // The speeds summed joint by joint over the frames against each frame's joints summed
        // in turn (the code before): the same bits on a rendered dance.
        use crate::choreo::{grid::bars_from_tempo, render::{render, RenderOptions}, SegmentLibrary};
        let lib = SegmentLibrary::builtin();
        let bars = bars_from_tempo(16.0, 108.0, 4, 0.0, |_, _| 0.5).unwrap();
        let live: Vec<usize> = lib.segments().iter().filter(|s| !s.retired && s.counts() == 4).map(|s| s.index).collect();
        let choices: Vec<Option<usize>> = (0..bars.len()).map(|i| Some(live[(i * 11 + 5) % live.len()])).collect();
        let m = QualityMotion::from_clip(&render(&lib, &bars, &choices, &RenderOptions::default())).unwrap();
        let frames = m.frames();
        let mut e = vec![0.0f32; frames];
        for f in 1..frames {
            let s: f32 = (0..CANON_COUNT).map(|j| (m.positions[f * CANON_COUNT + j] - m.positions[(f - 1) * CANON_COUNT + j]).length()).sum();
            e[f] = s / CANON_COUNT as f32 * QUALITY_FPS;
        }
        e[0] = e[1];
        let before = gaussian_smooth(&e, SPEED_SIGMA_FRAMES);
        let bits = |v: &[f32]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(&kinetic_speed(&m)), bits(&before));
        assert!(!kinetic_beat_frames(&before).is_empty());
    }

    #[test]
    fn velocity_changes_are_the_largest_length_to_the_bit() {
        // One root a frame (of the largest squared change) against a length a joint, the
        // largest kept: the same bits on a rendered dance, feet held, and on still frames.
        use crate::choreo::{grid::bars_from_tempo, render::{render, RenderOptions}, SegmentLibrary};
        let lib = SegmentLibrary::builtin();
        let bars = bars_from_tempo(16.0, 132.0, 4, 0.0, |_, _| 0.5).unwrap();
        let live: Vec<usize> = lib.segments().iter().filter(|s| !s.retired && s.counts() == 4).map(|s| s.index).collect();
        let choices: Vec<Option<usize>> = (0..bars.len()).map(|i| Some(live[(i * 7 + 2) % live.len()])).collect();
        let dance = QualityMotion::from_clip(&render(&lib, &bars, &choices, &RenderOptions::default())).unwrap();
        let still = QualityMotion::from_positions(&(0..12).flat_map(|_| rest_frame(Vec3::ZERO)).collect::<Vec<_>>(), 30.0).unwrap();
        for m in [dance, still] {
            let frames = m.frames();
            let lengths: Vec<f32> = (0..frames)
                .map(|f| {
                    if f == 0 || f + 1 >= frames {
                        return 0.0;
                    }
                    (0..CANON_COUNT)
                        .map(|j| {
                            let x = |t: usize| m.positions[t * CANON_COUNT + j];
                            ((x(f + 1) - x(f)) - (x(f) - x(f - 1))).length() * QUALITY_FPS
                        })
                        .fold(0.0, f32::max)
                })
                .collect();
            let fast = velocity_changes(&m);
            assert_eq!(fast.iter().map(|v| v.to_bits()).collect::<Vec<_>>(), lengths.iter().map(|v| v.to_bits()).collect::<Vec<_>>());
            assert!(frames < 20 || fast.iter().any(|&v| v > 0.0));
        }
    }

    #[test]
    fn from_clip_poses_only_what_it_reads() {
        // Rendered dances at 60 fps (every other frame read alone), 48 fps and 25 fps (frames
        // between frames): the same bits as posing every frame.
        use crate::choreo::{grid::bars_from_tempo, render::{render, RenderOptions}, SegmentLibrary};
        let lib = SegmentLibrary::builtin();
        let bars = bars_from_tempo(12.0, 124.0, 4, 0.0, |_, _| 0.5).unwrap();
        let live: Vec<usize> = lib.segments().iter().filter(|s| !s.retired && s.counts() == 4).map(|s| s.index).collect();
        let choices: Vec<Option<usize>> = (0..bars.len()).map(|i| Some(live[(i * 5 + 3) % live.len()])).collect();
        for fps in [60.0, 48.0, 25.0] {
            let clip = render(&lib, &bars, &choices, &RenderOptions { fps, ..RenderOptions::default() });
            let all = QualityMotion::from_clip_every_frame(&clip).unwrap();
            assert_eq!(QualityMotion::from_clip(&clip).unwrap(), all, "{fps} fps");
        }
    }

    #[test]
    fn resamples_to_30_fps() {
        let pos: Vec<Vec3> = (0..121).flat_map(|f| rest_frame(Vec3::X * f as f32 / 120.0)).collect();
        let m = QualityMotion::from_positions(&pos, 120.0).unwrap();
        assert_eq!(m.frames(), 31);
        // Moving 1 m/s for 1 s: the hips moved 1 m.
        let d = m.at(30, Canon::Hips).x - m.at(0, Canon::Hips).x;
        assert!((d - 1.0).abs() < 1e-3, "{d}");
    }

    #[test]
    fn bad_input_is_a_typed_error() {
        assert!(matches!(QualityMotion::from_positions(&[Vec3::ZERO; 5], 30.0), Err(QualityError::RaggedPositions { values: 5, .. })));
        assert!(matches!(QualityMotion::from_positions(&rest_frame(Vec3::ZERO), 30.0), Err(QualityError::TooShort { frames: 1, .. })));
        assert!(matches!(QualityMotion::from_positions(&rest_frame(Vec3::ZERO), f32::NAN), Err(QualityError::BadFps { .. })));
        let m = bobbing(90, 15.0, 0.0);
        assert_eq!(dance_quality_of(&m, &[], &[0.5]), Err(QualityError::NoBars));
        let bar = Bar { index: 0, start_secs: 0.0, end_secs: 2.0, intensity: 0.5, beats: 4 };
        assert_eq!(dance_quality_of(&m, &[bar], &[1.0, 0.5]), Err(QualityError::BadBeat { index: 1, value: 0.5 }));
    }

    #[test]
    fn kinetic_speed_of_steady_motion_is_its_speed_and_has_no_beats() {
        // Whole body gliding at 0.6 m/s (after scaling to the standard height, which the rest
        // figure already has).
        let m = motion(60, |f| Vec3::Z * 0.02 * f as f32);
        let e = kinetic_speed(&m);
        assert!(e.iter().all(|&v| (v - 0.6).abs() < 1e-3), "{e:?}");
        assert!(kinetic_beat_frames(&e).is_empty());
    }

    #[test]
    fn kinetic_beats_fall_where_the_motion_turns() {
        // Turning points every 15 frames (2 per second), starting at frame 7.3.
        let m = bobbing(300, 15.0, 7.3);
        let beats = kinetic_beat_frames(&kinetic_speed(&m));
        assert!(beats.len() >= 18, "{beats:?}");
        for b in &beats {
            let off = ((*b as f32 - 7.3) / 15.0).round() * 15.0 + 7.3 - *b as f32;
            assert!(off.abs() <= 1.0, "beat at frame {b} is not at a turning point");
        }
    }

    #[test]
    fn bas_is_one_on_the_beat_and_low_half_a_beat_off() {
        let music: Vec<f32> = (0..20).map(|i| i as f32 * 0.5).collect();
        assert!((bas_music(&music, &music).unwrap() - 1.0).abs() < 1e-6);
        assert!((bas_motion(&music, &music).unwrap() - 1.0).abs() < 1e-6);
        let off: Vec<f32> = music.iter().map(|t| t + 0.25).collect();
        // exp(−0.25² / 0.02) ≈ 0.044.
        let s = bas_music(&music, &off).unwrap();
        assert!((s - fmath::exp(-0.0625f32 / 0.02)).abs() < 0.01, "{s}");
        assert_eq!(bas_music(&[], &music), None);
        assert_eq!(bas_music(&music, &[]), Some(0.0));
        // The control is half a beat later.
        assert_eq!(half_shifted(&[0.0, 0.5, 1.5]), vec![0.25, 1.0, 2.0]);
    }

    #[test]
    fn a_motion_on_the_beat_scores_above_its_control_and_one_off_the_beat_does_not() {
        // Music at 120 BPM; motion turning on every beat (15 frames), or half a beat late.
        let music: Vec<f32> = (0..20).map(|i| i as f32 * 0.5).collect();
        let on = kinetic_beats_secs(&bobbing(300, 15.0, 0.3));
        let late = kinetic_beats_secs(&bobbing(300, 15.0, 7.8));
        let a = beat_alignment(&music, &on, 0.0, 10.0);
        let b = beat_alignment(&music, &late, 0.0, 10.0);
        // The music beat at 0 s has no turn before it to match (the motion starts there): 19 of
        // 20 beats are hit.
        assert!(a.bas_music > 0.85 && a.bas_music_shifted < 0.2, "{a:?}");
        assert!(b.bas_music < 0.2 && b.bas_music_shifted > 0.85, "{b:?}");
        assert!((a.kinetic_beats_per_sec - 2.0).abs() < 0.15 && (a.music_beats_per_sec - 2.0).abs() < 0.01, "{a:?}");
    }

    #[test]
    fn feet_planted_do_not_skate_and_gliding_feet_do() {
        let still = motion(60, |_| Vec3::ZERO);
        let s = foot_skate(&still);
        assert!(s.contacts > 0 && s.mean_cm_per_s < 1e-3, "{s:?}");
        // Gliding on the floor at 0.3 m/s: 30 cm/s of skate.
        let glide = motion(60, |f| Vec3::X * 0.01 * f as f32);
        let g = foot_skate(&glide);
        assert!((g.mean_cm_per_s - 30.0).abs() < 0.1 && (g.p95_cm_per_s - 30.0).abs() < 0.1, "{g:?}");
        // Moving only while in the air (0.2 m up, higher than the contact band) is no skate:
        // the floor is the 1st percentile, the planted frames.
        let hop = motion(90, |f| if (f / 10) % 2 == 1 { Vec3::new(0.01 * f as f32, 0.2, 0.0) } else { Vec3::new(0.01 * (f / 10 * 10) as f32, 0.0, 0.0) });
        let h = foot_skate(&hop);
        assert!(h.contacts > 0 && h.mean_cm_per_s < 0.1 * g.mean_cm_per_s, "hop {h:?} vs glide {g:?}");
    }

    #[test]
    fn pfc_is_zero_for_a_planted_body_and_positive_when_feet_slide_under_acceleration() {
        assert_eq!(pfc(&motion(60, |_| Vec3::ZERO)), 0.0);
        // Root accelerating upward while the feet (the whole body) slide.
        let slide = motion(60, |f| Vec3::new(0.01 * f as f32, 0.0005 * (f * f) as f32, 0.0));
        assert!(pfc(&slide) > 1.0, "{}", pfc(&slide));
    }

    #[test]
    fn a_kink_at_a_join_is_a_large_join_jump_and_a_smooth_join_is_not() {
        // Bobbing motion; a velocity kink at frame 150 (the motion reverses direction sideways).
        let smooth = bobbing(300, 15.0, 0.3);
        let kinked = motion(300, |f| {
            let y = 0.1 * fmath::cos((f as f32 - 0.3) / 15.0 * std::f32::consts::PI);
            let x = if f < 150 { 0.01 * f as f32 } else { 1.5 - 0.01 * (f - 150) as f32 };
            Vec3::new(x, y, 0.0)
        });
        let joins = [150usize];
        let s = join_jumps(&smooth, &joins)[0];
        let k = join_jumps(&kinked, &joins)[0];
        // The bobbing's turning points are its sharpest moments: an ordinary frame is ≤ 1.
        assert!(s <= 1.05, "smooth join {s}");
        assert!(k > 1.5, "kinked join {k}");
    }

    #[test]
    fn dance_quality_reads_each_bar() {
        let m = bobbing(241, 15.0, 0.3);
        let bars: Vec<Bar> = (0..4).map(|i| Bar { index: i, start_secs: 2.0 * i as f32, end_secs: 2.0 * (i + 1) as f32, intensity: 0.5, beats: 4 }).collect();
        let music: Vec<f32> = (0..16).map(|i| i as f32 * 0.5).collect();
        let q = dance_quality_of(&m, &bars, &music).unwrap();
        assert_eq!(q.bars.len(), 4);
        assert!(q.bars[0].join_jump.is_none() && q.bars[1..].iter().all(|b| b.join_jump.is_some()));
        assert!(q.beats.bas_music > 0.85 && q.beats.bas_music_shifted < 0.2, "{:?}", q.beats);
        // Bar 0 misses its beat at 0 s (nothing turns before the motion starts).
        for b in &q.bars {
            assert!(b.beats.bas_music > if b.bar == 0 { 0.7 } else { 0.9 }, "bar {}: {:?}", b.bar, b.beats);
        }
        let json = serde_json::to_value(&q).unwrap();
        assert!(json["bars"][1]["beats"]["basMusicShifted"].is_number() && json["joinJumpMax"].is_number());
    }

    #[test]
    fn perceptual_distance_ignores_placement_and_length_but_not_pose() {
        let a: Vec<Vec3> = (0..40).flat_map(|f| rest_frame(Vec3::new(0.0, 0.05 * fmath::sin(f as f32 * 0.2), 0.0))).collect();
        // The same motion at double the frame count, elsewhere on the floor.
        let b: Vec<Vec3> = (0..79).flat_map(|f| rest_frame(Vec3::new(3.0, 0.05 * fmath::sin(f as f32 * 0.1), -2.0))).collect();
        assert!(perceptual_distance(&a, &b).unwrap() < 0.01);
        // Raising one hand by 30 cm is a difference.
        let hand = Canon::RightHand.index();
        let c: Vec<Vec3> = a.chunks(CANON_COUNT).flat_map(|f| f.iter().enumerate().map(|(j, p)| if j == hand { *p + Vec3::Y * 0.3 } else { *p }).collect::<Vec<_>>()).collect();
        assert!(perceptual_distance(&a, &c).unwrap() > 0.005);
        assert!(perceptual_distance(&a, &[]).is_err());
    }
}
