//! What the library holds: its clips on the canonical skeleton ([`LibraryClip`]), the segments
//! cut from them ([`Segment`], with the count warp that puts a segment's counts on a bar's
//! beats), what adding or re-cutting a clip gave, and the links whose ends the transition cost
//! reads.

use crate::fmath;
use std::sync::Arc;

use glam::Vec3;
use serde::{Deserialize, Serialize};

use super::tempo::KINETIC_RATES_BPM;
use super::{LIBRARY_FPS, SEGMENT_COUNTS};
use crate::clip::Clip;
use crate::canon::humanoid::{canonical_positions, Canon, HumanoidMap, CANON_COUNT};
use crate::library::MoveInfo;

/// Number of canonical links (parent → child bones).
pub const LINK_COUNT: usize = CANON_COUNT - 1;

/// Per-joint weights α_i of the motion intensity (eq. 2): hands and feet count double.
pub fn intensity_weight(c: Canon) -> f32 {
    match c {
        Canon::LeftHand | Canon::RightHand | Canon::LeftFoot | Canon::RightFoot => 2.0,
        _ => 1.0,
    }
}

/// A clip of the library on the canonical skeleton.
#[derive(Clone, Debug)]
pub struct LibraryClip {
    pub clip: Clip,
    /// The clip's counts, frames at [`LIBRARY_FPS`].
    pub beat_frames: Vec<f32>,
    pub tempo_bpm: f32,
    /// The built-in move it renders, if any.
    pub builtin: Option<MoveInfo>,
    /// Where its feet are planted, found the first time a rendered dance holds them
    /// ([`LibraryClip::planted_feet`]); the clip never changes, so neither do they.
    planted: std::sync::OnceLock<Arc<[Vec<bool>; 4]>>,
}

impl LibraryClip {
    /// A library clip (its planted feet not yet found).
    pub fn new(clip: Clip, beat_frames: Vec<f32>, tempo_bpm: f32, builtin: Option<MoveInfo>) -> LibraryClip {
        LibraryClip { clip, beat_frames, tempo_bpm, builtin, planted: std::sync::OnceLock::new() }
    }

    /// Per frame of the clip as recorded, whether its left ankle, left toe, right ankle and
    /// right toe are planted (the engine's one contact rule, [`crate::canon::contact::planted_frames`]):
    /// found once per clip, not on every render of a dance that plays it.
    pub(crate) fn planted_feet(&self) -> &[Vec<bool>; 4] {
        self.planted.get_or_init(|| {
            let c = &self.clip;
            let pos = canonical_positions(c, &HumanoidMap::from_skeleton(&c.skeleton));
            let n = pos.len() / CANON_COUNT;
            let joints = [Canon::LeftFoot, Canon::LeftToe, Canon::RightFoot, Canon::RightToe];
            Arc::new(joints.map(|j| crate::canon::contact::planted_frames(&(0..n).map(|k| pos[k * CANON_COUNT + j.index()]).collect::<Vec<_>>(), c.fps)))
        })
    }
}

/// One 4-count segment.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "camelCase")]
pub struct Segment {
    /// Index in the library.
    pub index: usize,
    /// Display name: the clip's and the counts it spans.
    pub name: String,
    /// Index of the library clip it was cut from.
    pub clip: usize,
    /// File (or "built-in") of that clip.
    pub source: String,
    /// Frames `start_frame..=end_frame` of the clip at [`LIBRARY_FPS`]: `end_frame` is the
    /// first count of the next bar (played as the start of the following segment).
    pub start_frame: f32,
    pub end_frame: f32,
    /// Tempo of the motion, counts per minute.
    pub tempo_bpm: f32,
    /// Mean motion intensity W (eq. 2): Σ α_i |ẋ_i| in metres per second.
    pub intensity: f32,
    /// W scaled to the library's range (5th to 95th percentile → 0..1, clamped).
    pub intensity01: f32,
    /// The built-in move, for built-in segments.
    pub builtin: Option<MoveInfo>,
    /// The frames of its n + 1 counts (the n it spans, n = [`Segment::counts`], and the next
    /// bar's first), each where the motion has it (its kinetic beat): `count_frames[0] ==
    /// start_frame`, `[n] == end_frame`.
    /// Filling a bar warps time piecewise-linearly between them so every count lands on the
    /// song's beat (spec §E). Empty in documents saved before counts were kept: linear then.
    #[serde(default)]
    pub count_frames: Vec<f32>,
    /// How well its counts fall on its kinetic beats once warped onto a bar (spec §J), 0..1:
    /// (BAS on the counts − BAS on the half-counts + 1) / 2 over the inner counts. The filling's
    /// beat term prefers high values.
    #[serde(default)]
    pub beat_fit: f32,
    /// Its own foot skate (spec §J) in the clip it was cut from, centimetres per second: the
    /// mean horizontal speed of ankles and toes on the floor over its frames, measured once
    /// when the library is cut. The filling's skate term ([`super::FillWeights::skate_weight`])
    /// prefers low values. 0 in documents saved before it was kept (and for a segment whose feet
    /// never touch the floor).
    #[serde(default)]
    pub skate_cm_per_s: f32,
    /// Foot skate of the whole clip it was cut from, centimetres per second (spec §J, the
    /// source clip's figure): the skate term charges only a segment's skate above it.
    #[serde(default)]
    pub clip_skate_cm_per_s: f32,
    /// Kinetic beats (spec §J) per count over its frames: 1 turns once a count, 0.5 every other
    /// count. Warped onto a bar its counts fall on the song's beats, so this is the dance's
    /// kinetic beat rate over the song's beat rate there (the beat-rate term,
    /// [`super::FillWeights::beat_rate_weight`]). 0 in documents saved before it was kept.
    #[serde(default)]
    pub kinetic_per_count: f32,
    /// Its kinetic beats per count when played at each count rate of [`KINETIC_RATES_BPM`]
    /// (warped onto a bar as the dance plays it, with half a count of its own clip on either
    /// side): §J's kinetic beats are minima of a speed smoothed over a fixed 0.067 s, so a
    /// move slowed below its own tempo shows turns inside its counts that its own tempo
    /// smoothed away (the built-in moves turn 0.97 times a count at 120 counts per minute and
    /// 1.23 times at 89). What the filling's beat-rate term reads
    /// ([`Segment::kinetic_per_count_at`]). Empty in documents saved before it was kept.
    #[serde(default)]
    pub kinetic_per_count_by_rate: Vec<f32>,
    /// Kept only for the bars that already hold it (an older cut of a clip the person re-cut
    /// at a stated tempo): never offered as a candidate nor chosen to fill an open bar.
    #[serde(default)]
    pub retired: bool,
}

impl Segment {
    pub fn duration_secs(&self) -> f32 {
        (self.end_frame - self.start_frame) / LIBRARY_FPS
    }

    /// Its source clip's foot skate played at `rate_bpm` counts a minute (§N: skate is a speed,
    /// so a move played faster slides faster in its source too); the clip's own without a tempo.
    pub fn clip_skate_at(&self, rate_bpm: f32) -> f32 {
        if self.tempo_bpm > 0.0 && rate_bpm > 0.0 { self.clip_skate_cm_per_s * rate_bpm / self.tempo_bpm } else { self.clip_skate_cm_per_s }
    }

    /// Its counts: the beats of the bar it fills (4, or 3 for a bar in 3; module docs). 4 in
    /// documents saved before counts were kept.
    pub fn counts(&self) -> usize {
        if self.count_frames.len() >= 2 { self.count_frames.len() - 1 } else { SEGMENT_COUNTS }
    }

    /// Whether its count frames are usable for the warp (as many as its counts + 1, increasing).
    fn counts_known(&self) -> bool {
        let c = &self.count_frames;
        c.len() >= 2 && c.windows(2).all(|w| w[1] > w[0])
    }

    /// The clip frame shown at `u` (0..=1) of the bar it fills: piecewise-linear between its
    /// counts, count k of n at u = k/n (linear from start to end when the counts are unknown).
    pub fn frame_at(&self, u: f32) -> f32 {
        let u = u.clamp(0.0, 1.0);
        let c = &self.count_frames;
        if !self.counts_known() {
            return self.start_frame + u * (self.end_frame - self.start_frame);
        }
        let n = self.counts();
        let x = u * n as f32;
        let k = (x.floor() as usize).min(n - 1);
        c[k] + (x - k as f32) * (c[k + 1] - c[k])
    }

    /// The clip frame shown at `u` of the bar it fills, for `u` before the bar (−1/n..0: the
    /// count before its first, at the first count's pace), clamped to the clip's start. What the
    /// dance plays as its lead-in before its first bar ([`super::render`]). `u` ≥ 0: [`Segment::frame_at`].
    pub fn frame_before(&self, u: f32) -> f32 {
        if u >= 0.0 {
            return self.frame_at(u);
        }
        let n = self.counts() as f32;
        let u = u.max(-1.0 / n);
        let c = &self.count_frames;
        let count_frames = if c.len() >= 2 && c[1] > c[0] { c[1] - c[0] } else { (self.end_frame - self.start_frame) / n };
        (self.start_frame + u * n * count_frames).max(0.0)
    }

    /// Kinetic beats per count when played at `count_rate_bpm` counts per minute: interpolated
    /// in log rate between [`Segment::kinetic_per_count_by_rate`] (held at the ends), or its
    /// own-tempo [`Segment::kinetic_per_count`] when those were not measured.
    pub fn kinetic_per_count_at(&self, count_rate_bpm: f32) -> f32 {
        let v = &self.kinetic_per_count_by_rate;
        if v.len() != KINETIC_RATES_BPM.len() || !count_rate_bpm.is_finite() || count_rate_bpm <= 0.0 {
            return self.kinetic_per_count;
        }
        let r = &KINETIC_RATES_BPM;
        if count_rate_bpm <= r[0] {
            return v[0];
        }
        for i in 1..r.len() {
            if count_rate_bpm <= r[i] {
                let a = fmath::log2(count_rate_bpm / r[i - 1]) / fmath::log2(r[i] / r[i - 1]);
                return v[i - 1] + a * (v[i] - v[i - 1]);
            }
        }
        v[v.len() - 1]
    }

    /// Where in 0..=1 of the bar clip frame `frame` plays (the inverse of [`Segment::frame_at`]).
    pub fn bar_position(&self, frame: f32) -> f32 {
        let c = &self.count_frames;
        if !self.counts_known() {
            return ((frame - self.start_frame) / (self.end_frame - self.start_frame).max(1e-6)).clamp(0.0, 1.0);
        }
        let n = self.counts();
        let k = (0..n).rfind(|&k| frame >= c[k]).unwrap_or(0);
        ((k as f32 + ((frame - c[k]) / (c[k + 1] - c[k])).clamp(0.0, 1.0)) / n as f32).clamp(0.0, 1.0)
    }
}

/// Link vectors and velocities at a segment's start and end (normalised body, spec §B).
#[derive(Clone, Debug, Default)]
pub(crate) struct JoinEnds {
    pub start: [Vec3; LINK_COUNT],
    pub end: [Vec3; LINK_COUNT],
    pub start_velocity: [Vec3; LINK_COUNT],
    pub end_velocity: [Vec3; LINK_COUNT],
    /// Joint positions (from the hips' ground point, facing removed, body heights),
    /// velocities and accelerations (per frame, per frame², in that frame) at the segment's
    /// last frame and its first: what
    /// an inertialized join's offset is made of ([`super::super::table::blended_join_jump`]).
    pub end_joint: [[Vec3; 3]; CANON_COUNT],
    pub start_joint: [[Vec3; 3]; CANON_COUNT],
    /// The 95th percentile over the segment's frames of the largest joint acceleration in the
    /// normalised body (hips origin, facing removed, body heights per frame²): how sharp the
    /// move itself is, what spec §J's join jump divides by. (Measured on world positions, with
    /// the hips' own sway, it ranked joins far worse: Spearman ρ 0.19–0.23 against 0.59–0.62,
    /// `tests/native/choreo_join_cost.rs`.)
    pub sharpness: f32,
}

/// What adding a clip gave.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "camelCase")]
pub struct ClipSummary {
    pub clip: usize,
    pub name: String,
    pub tempo_bpm: f32,
    /// Whether the tempo was detected from the motion (else stated).
    pub tempo_detected: bool,
    pub beats: usize,
    pub segments: usize,
}

/// What re-cutting a clip did (see [`SegmentLibrary::recut_clip`]).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "camelCase")]
pub struct Recut {
    /// The new cut.
    pub summary: ClipSummary,
    /// For every segment index before the re-cut, its index after (`None`: removed).
    pub remap: Vec<Option<usize>>,
    /// Segments of the earlier cut kept (as retired) because something still uses them, by
    /// their new index.
    pub kept: Vec<usize>,
    /// Segments of the earlier cut removed.
    pub removed: usize,
}

/// (parent, child) canonical indices of every link, in [`Canon::links`] order.
pub const LINKS: [(usize, usize); LINK_COUNT] = {
    let mut out = [(0, 0); LINK_COUNT];
    let all = [
        (0, 1), (1, 2), (2, 3), (3, 4), (2, 5), (5, 6), (6, 7), (7, 8), (2, 9), (9, 10),
        (10, 11), (11, 12), (0, 13), (13, 14), (14, 15), (15, 16), (0, 17), (17, 18), (18, 19), (19, 20),
    ];
    let mut i = 0;
    while i < LINK_COUNT {
        out[i] = all[i];
        i += 1;
    }
    out
};

/// World positions of every frame of a clip on the canonical skeleton (frame-major), by
/// the motion kernel's [`crate::motion::WorldPose`], reused from frame to frame.
pub(crate) fn canonical_world_positions(clip: &Clip) -> Vec<Vec3> {
    let frames = clip.frame_count();
    let sk = &clip.skeleton;
    if sk.len() != CANON_COUNT {
        return canonical_positions(clip, &HumanoidMap::from_skeleton(sk));
    }
    let root = clip.translations.iter().find(|t| t.joint == 0).map(|t| t.values.as_slice());
    let mut out = Vec::with_capacity(frames * CANON_COUNT);
    let mut pose = crate::motion::WorldPose::new();
    let rest_root = sk.joints.first().map_or(Vec3::ZERO, |j| j.rest_offset);
    for f in 0..frames {
        let at = root.and_then(|r| r.get(f).copied()).unwrap_or(rest_root);
        out.extend_from_slice(&pose.of_rotations(sk, clip.frame_rotations(f), at).positions);
    }
    out
}

/// Link vectors and velocities at a segment's first and last frames and the segment's
/// sharpness (from `normed`), and the joints' motion at those frames (from `world`, over
/// `height`).
pub(super) fn join_ends(normed: &[Vec3], world: &[Vec3], height: f32, start: usize, end: usize) -> JoinEnds {
    let link = |f: usize, l: usize| -> Vec3 {
        let (p, c) = LINKS[l];
        normed[f * CANON_COUNT + c] - normed[f * CANON_COUNT + p]
    };
    let last = end.saturating_sub(1).max(start);
    let mut e = JoinEnds::default();
    for l in 0..LINK_COUNT {
        e.start[l] = link(start, l);
        e.end[l] = link(last, l);
        e.start_velocity[l] = link((start + 1).min(last), l) - link(start, l);
        e.end_velocity[l] = link(last, l) - link(last.saturating_sub(1).max(start), l);
    }
    // Frames clamped into the segment, so a short one repeats its edge frames (zero velocity).
    let (s0, l0) = (start as isize, last as isize);
    let normed_at = |f: isize, j: usize| -> Vec3 { normed[(f.clamp(s0, l0) as usize) * CANON_COUNT + j] };
    let mut acc: Vec<f32> = (s0 + 1..l0)
        .map(|f| (0..CANON_COUNT).map(|j| (normed_at(f + 1, j) - 2.0 * normed_at(f, j) + normed_at(f - 1, j)).length()).fold(0.0, f32::max))
        .collect();
    acc.sort_by(f32::total_cmp);
    e.sharpness = acc.get(((acc.len() as f32 * 0.95) as usize).min(acc.len().saturating_sub(1))).copied().unwrap_or(0.0);
    // World positions over the body height, seen from the hips' ground point and facing at
    // the end (the start): as the render places the next segment, its start where this one
    // ends and facing the same way, so the offset is the pose the blend must carry.
    let inv_h = if height > 1e-6 { 1.0 / height } else { 1.0 };
    let at = |f: isize, j: usize| -> Vec3 { world[(f.clamp(s0, l0) as usize) * CANON_COUNT + j] * inv_h };
    let frame_of = |f: isize| {
        let (r, l) = (at(f, Canon::RightUpperLeg.index()), at(f, Canon::LeftUpperLeg.index()));
        let hips = at(f, Canon::Hips.index());
        (crate::canon::normalize::facing_rotation(r, l), Vec3::new(hips.x, 0.0, hips.z))
    };
    let ((re, oe), (rs, os)) = (frame_of(l0), frame_of(s0));
    for j in 0..CANON_COUNT {
        let (x, x1, x2) = (at(l0, j), at(l0 - 1, j), at(l0 - 2, j));
        e.end_joint[j] = [re * (x - oe), re * (x - x1), re * (x - 2.0 * x1 + x2)];
        let (y, y1, y2) = (at(s0, j), at(s0 + 1, j), at(s0 + 2, j));
        e.start_joint[j] = [rs * (y - os), rs * (y1 - y), rs * (y2 - 2.0 * y1 + y)];
    }
    e
}
