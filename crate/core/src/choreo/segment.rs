//! The segment library (spec §E): clips cut into 4-count segments (and, from imported clips,
//! 3-count ones too) at the motion's own beats, each with its source, frame range, tempo, motion intensity W (eq. 2), eigen signature
//! (§F) and the start/end link vectors and velocities the filling's transition cost (§G)
//! reads.
//!
//! Every clip is first put on the canonical skeleton at [`LIBRARY_FPS`], so segments from the
//! built-in library and from imported glTF/BVH files compare, join and play as one dance.
//! Counts come from the motion (spec §E revised): the count period is the one the speed curves
//! of the feet, the whole body, the hands and the hips support together at the count, two
//! counts and the bar (an autocorrelation comb over 30..200 per minute, so octave and 3:2
//! alternatives compete on the same evidence), folded by octaves into a choreographer's count
//! of 60..=150 per minute (fast footwork such as salsa's steps is counted in twos); the phase
//! is where the whole-body speed is lowest on that grid, and each count snaps to the nearest
//! local minimum of the speed (its kinetic beat). A person may instead state the clip's tempo.
//!
//! Bars in 3 (extends §E, which says "segments of 4 counts (one bar)"): a segment is one bar
//! *of its own metre*. Each imported clip is cut at the same counts twice: into windows of 4
//! counts plus the next bar's first every `hop_counts` counts, and into windows of 3 counts plus
//! the next one on every count ([`SEGMENT_METRES`]). Why every count: in 3 only the imported
//! clips' windows can fill a bar, and they join each other roughly (the path the table (§G)
//! finds first has joins at 5.7–14 times the moves' own sharpest moments on pieces in 3, §J's
//! join jump, either way; [`super::FillWeights::follow_joins`] repairs them). With windows
//! every 2 counts (185 of them from the real clips) the repair left a 126 BPM piece at 2.92; on
//! every count (362) it brings six pieces in 3 under the goal of 1.5 (`choreo_beats`). Most dance
//! mocap repeats its step in 4 or 8 counts, so a 3-count window ends on another count of that
//! cycle than it starts on, and windows on every count give each end more starts on the same
//! count (the likely reason, not measured). A bar of n beats
//! ([`crate::bars::Bar::beats`]) is filled only by segments of n counts ([`Segment::counts`]),
//! and the count warp puts count k at k/n of the bar, so each count lands on one of its beats;
//! only when the library holds no segment of n counts does a bar take any segment, its counts
//! spread evenly over the bar (what every bar in 3 did before). The objective's terms (§G) and
//! the feedback signatures (§F) are per segment and apply unchanged. The built-in moves give no
//! 3-count windows: each is one 4-count bar at 120 counts per minute composed to leave and
//! return to one neutral stance on its counts 1 and 5 (which is why built-in moves join each
//! other so well); its first 3 counts stop mid-phrase, away from that stance, and cut off the
//! fourth count's motion, so in 3 they would end away from the stance the other moves start
//! from (not measured) and not be the move the person picked.
//! They also stay one segment each, so the built-in library (and its load time) is unchanged.

use std::sync::{Arc, Mutex};

use glam::Vec3;
use serde::{Deserialize, Serialize};
use thiserror::Error;

use super::eigen::Signature;
use super::quality::{bas_music, foot_skate_samples, kinetic_beats_secs, summarize_skate, QualityMotion, QUALITY_FPS};
use super::table::{TableBuilder, TableScope, TransitionTable};
use crate::retarget::to_canonical;
use crate::clip::Clip;
use crate::humanoid::{canonical_positions, Canon, HumanoidMap, HumanoidStatus, CANON_COUNT};
use crate::library::{builtin_clips_lazily, builtin_moves, MoveInfo};
use crate::normalize::{body_height, normalize_in_place, Origin};

/// Frame rate every library clip is stored and analysed at.
pub const LIBRARY_FPS: f32 = 30.0;
/// Counts per segment (one bar of 4/4): every built-in move, and the default.
pub const SEGMENT_COUNTS: usize = 4;
/// The counts of the segments cut from each imported clip: one bar of 4/4 and one of 3/4
/// (module docs: a bar of n beats takes segments of n counts).
pub const SEGMENT_METRES: [usize; 2] = [4, 3];
/// Eigen axes kept per signature.
pub const SIGNATURE_AXES: usize = 5;
/// The pose the signature's features are measured from: the mean §B-normalised position (body
/// heights; x, y, z) of every canonical joint (in [`Canon::ALL`]'s order) over the built-in
/// moves (a unit test recomputes it). A fixed pose, not the current library's mean, so a
/// segment's signature never changes when clips are added.
pub const SIGNATURE_REFERENCE: [[f32; 3]; CANON_COUNT] = [
    [0.000, 0.035, 0.0],    // hips
    [0.000, 0.106, 0.0],    // spine
    [-0.004, 0.212, 0.0],   // chest
    [-0.015, 0.367, 0.0],   // neck
    [-0.036, 0.450, 0.0],   // head
    [-0.013, 0.331, 0.021], // left shoulder
    [-0.013, 0.334, 0.127], // left upper arm
    [-0.018, 0.233, 0.193], // left forearm
    [-0.135, 0.258, 0.178], // left hand
    [-0.013, 0.331, -0.021], // right side, the same order
    [-0.013, 0.334, -0.127],
    [-0.018, 0.233, -0.193],
    [-0.135, 0.258, -0.178],
    [0.000, 0.000, 0.064],   // left upper leg
    [-0.111, -0.266, 0.108], // left lower leg
    [-0.002, -0.523, 0.093], // left foot
    [-0.077, -0.587, 0.103], // left toe
    [0.000, 0.000, -0.064],
    [-0.111, -0.266, -0.108],
    [-0.002, -0.523, -0.093],
    [-0.077, -0.587, -0.103],
];
/// The velocity part of the signature's features: each joint's displacement over this span
/// (seconds; a central difference over ±2 frames at [`LIBRARY_FPS`], doubled), body heights.
/// Chosen with the constant below by the `choreo_preference_features` bench on its tuning
/// sets (spans of 0.07–0.4 s tried; module docs of `choreo::feedback` give the figures).
pub const SIGNATURE_VELOCITY_SECS: f32 = 4.0 / LIBRARY_FPS;
/// The constant last feature of every frame, body heights, so the first principal axis of the
/// uncentred matrix carries the segment's mean pose with its sign (eigenvectors have none;
/// against the constant, +pose and −pose point differently) and the rest how it moves. Its
/// size sets how much that first axis weighs against the others in kWAS; 0.25–1.25 tried
/// (`choreo_preference_features`).
pub const SIGNATURE_OFFSET: f32 = 1.0;

/// The eigen signature (spec §F) of frames `si..ei` of a clip's §B-normalised canonical
/// positions. Features per frame (every other frame: 15 per second is plenty for the principal
/// axes): every canonical joint's position minus its [`SIGNATURE_REFERENCE`], then its
/// displacement over [`SIGNATURE_VELOCITY_SECS`] (within the segment), then
/// [`SIGNATURE_OFFSET`]; axes of the uncentred matrix ([`Signature::of_uncentred`]).
///
/// Why these features: §J's perceptual distance (what the relevance feedback should agree
/// with) is the mean distance of *every* joint's position, frame by frame. The centred
/// covariance of positions (session 4) saw only the directions joints move in and agreed with
/// it at a Spearman rank correlation of 0.05–0.09; ten joints' positions from a reference
/// pose (sessions 5–6) at 0.72; all joints with their velocities at 0.79. The velocities let
/// the signature tell motions that pass through the same poses at different speeds or in a
/// different order apart, which a second-moment matrix of positions alone cannot.
pub fn signature_of(normed: &[Vec3], si: usize, ei: usize) -> Signature {
    const J: usize = CANON_COUNT;
    let dims = J * 6 + 1;
    let last = ei.max(si);
    let mut feats = Vec::with_capacity((ei.saturating_sub(si) / 2 + 1) * dims);
    for f in (si..ei).step_by(2) {
        let frame = &normed[f * J..(f + 1) * J];
        for (p, r) in frame.iter().zip(&SIGNATURE_REFERENCE) {
            feats.extend_from_slice(&[p.x - r[0], p.y - r[1], p.z - r[2]]);
        }
        // Central difference over ±2 frames, one-sided at the segment's ends, scaled to the
        // displacement over SIGNATURE_VELOCITY_SECS.
        let (f0, f1) = (f.saturating_sub(2).max(si), (f + 2).min(last));
        let scale = if f1 > f0 { SIGNATURE_VELOCITY_SECS * LIBRARY_FPS / (f1 - f0) as f32 } else { 0.0 };
        for j in 0..J {
            let d = (normed[f1 * J + j] - normed[f0 * J + j]) * scale;
            feats.extend_from_slice(&[d.x, d.y, d.z]);
        }
        feats.push(SIGNATURE_OFFSET);
    }
    Signature::of_uncentred(&feats, dims, SIGNATURE_AXES)
}

/// Number of canonical links (parent → child bones).
pub const LINK_COUNT: usize = CANON_COUNT - 1;

/// Per-joint weights α_i of the motion intensity (eq. 2): hands and feet count double.
pub fn intensity_weight(c: Canon) -> f32 {
    match c {
        Canon::LeftHand | Canon::RightHand | Canon::LeftFoot | Canon::RightFoot => 2.0,
        _ => 1.0,
    }
}

/// Why a clip gave no segments.
#[derive(Debug, Error, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "camelCase")]
pub enum SegmentError {
    #[error("clip '{name}' is not humanoid ({reason}): segments need a standing two-legged body")]
    NotHumanoid { name: String, reason: String },
    #[error("clip '{name}' is {duration_secs:.2} s long and holds only {beats} beat(s) at {tempo_bpm:.0} counts per minute: a segment needs 4 counts (5 beats)")]
    TooShort { name: String, duration_secs: f32, beats: usize, tempo_bpm: f32 },
    #[error("clip '{name}': stated tempo {tempo_bpm} BPM is outside {min}..={max}", min = super::MIN_MOVE_BPM, max = super::MAX_MOVE_BPM)]
    BadTempo { name: String, tempo_bpm: f32 },
    #[error("clip '{name}' is invalid: {message}")]
    Invalid { name: String, message: String },
    #[error("there is no clip {clip} in the segment library (it has {clips})")]
    NoSuchClip { clip: usize, clips: usize },
    #[error("'{name}' is a built-in move: it is one bar at 120 counts per minute and cannot be re-cut")]
    BuiltinClip { name: String },
}

/// How to cut a clip.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "camelCase", default)]
pub struct SegmentOptions {
    /// The clip's tempo in counts per minute, when the person knows it; `None`: detect it from
    /// the motion.
    pub tempo_bpm: Option<f32>,
    /// Time of a count in the clip, seconds (with `tempo_bpm`); `None`: the phase is detected.
    pub first_beat_secs: Option<f32>,
    /// Counts between the starts of consecutive segments (1..=4; default 2: segments overlap
    /// by half a bar, giving the filling more ways to join).
    pub hop_counts: usize,
}

impl Default for SegmentOptions {
    fn default() -> Self {
        Self { tempo_bpm: None, first_beat_secs: None, hop_counts: 2 }
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
    /// right toe are planted (the retargeting's rule, [`crate::character::planted_frames`]):
    /// found once per clip, not on every render of a dance that plays it.
    pub(crate) fn planted_feet(&self) -> &[Vec<bool>; 4] {
        self.planted.get_or_init(|| {
            let c = &self.clip;
            let pos = canonical_positions(c, &HumanoidMap::from_skeleton(&c.skeleton));
            let n = pos.len() / CANON_COUNT;
            let joints = [Canon::LeftFoot, Canon::LeftToe, Canon::RightFoot, Canon::RightToe];
            Arc::new(joints.map(|j| crate::character::planted_frames(&(0..n).map(|k| pos[k * CANON_COUNT + j.index()]).collect::<Vec<_>>(), c.fps)))
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
                let a = (count_rate_bpm / r[i - 1]).log2() / (r[i] / r[i - 1]).log2();
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

/// The segments every choreography chooses from.
#[derive(Debug, Default)]
pub struct SegmentLibrary {
    clips: Vec<LibraryClip>,
    segments: Vec<Segment>,
    signatures: Vec<Signature>,
    pub(crate) ends: Vec<JoinEnds>,
    /// Clip-frame overlaps: for each segment, the segments sharing frames of its clip
    /// (itself included). Following one with an overlapping one repeats the same motion.
    pub(crate) overlaps: Vec<Vec<usize>>,
    table: Mutex<Option<Arc<TransitionTable>>>,
    /// Bumped by every change of the segments, so a table built elsewhere can be checked.
    revision: u64,
}

/// A copy shares the cached transition table (it is immutable behind its `Arc`): a project
/// keeps the built-in library once and starts each rebuild from a copy of it, instead of
/// making the 420 moves again (1–2 s in a browser tab).
impl Clone for SegmentLibrary {
    fn clone(&self) -> Self {
        let table = match self.table.lock() {
            Ok(g) => g.clone(),
            Err(poisoned) => poisoned.into_inner().clone(),
        };
        SegmentLibrary {
            clips: self.clips.clone(),
            segments: self.segments.clone(),
            signatures: self.signatures.clone(),
            ends: self.ends.clone(),
            overlaps: self.overlaps.clone(),
            table: Mutex::new(table),
            revision: self.revision,
        }
    }
}

/// The built-in moves still to add to a library (see [`SegmentLibrary::load_builtin`]).
pub struct BuiltinLoader {
    clips: Box<dyn Iterator<Item = (Clip, MoveInfo)>>,
    done: usize,
    total: usize,
}

impl BuiltinLoader {
    pub fn new() -> Self {
        BuiltinLoader { clips: Box::new(builtin_clips_lazily()), done: 0, total: builtin_moves().len() }
    }
}

impl Default for BuiltinLoader {
    fn default() -> Self {
        Self::new()
    }
}

impl std::fmt::Debug for BuiltinLoader {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "BuiltinLoader({}/{})", self.done, self.total)
    }
}

impl SegmentLibrary {
    /// An empty library.
    pub fn new() -> Self {
        Self::default()
    }

    /// The built-in library: one segment per built-in move.
    pub fn builtin() -> Self {
        let mut lib = Self::new();
        lib.add_builtin();
        lib
    }

    /// Adds every built-in move (one 4-count segment each).
    pub fn add_builtin(&mut self) -> usize {
        let before = self.segments.len();
        let mut loader = BuiltinLoader::new();
        while self.load_builtin(&mut loader, usize::MAX) < 1.0 {}
        self.segments.len() - before
    }

    /// Adds up to `count` more built-in moves from `loader`; returns the fraction of them
    /// added so far (1 when all are in: the intensities are then rescaled, as
    /// [`SegmentLibrary::add_builtin`] does). Same library as `add_builtin`, built in slices.
    pub fn load_builtin(&mut self, loader: &mut BuiltinLoader, count: usize) -> f32 {
        if loader.done >= loader.total {
            return 1.0;
        }
        for _ in 0..count.max(1) {
            let Some((clip, info)) = loader.clips.next() else { break };
            let frames = clip.frame_count();
            let last = frames.saturating_sub(1) as f32;
            let beats: Vec<f32> = (0..=SEGMENT_COUNTS).map(|k| last * k as f32 / SEGMENT_COUNTS as f32).collect();
            let lc = LibraryClip::new(clip, beats, crate::library::BUILTIN_BPM, Some(info));
            self.push_clip(lc, SEGMENT_COUNTS);
            loader.done += 1;
        }
        if loader.done >= loader.total {
            self.rescale();
            return 1.0;
        }
        loader.done as f32 / loader.total as f32
    }

    /// Adds an imported clip: refused when its skeleton is not humanoid or it holds fewer than
    /// 4 counts.
    pub fn add_clip(&mut self, clip: &Clip, map: &HumanoidMap, status: &HumanoidStatus, options: &SegmentOptions) -> Result<ClipSummary, SegmentError> {
        let name = clip.name.clone();
        if let HumanoidStatus::NotHumanoid { reason } = status {
            return Err(SegmentError::NotHumanoid { name, reason: reason.clone() });
        }
        clip.validate().map_err(|e| SegmentError::Invalid { name: name.clone(), message: e.to_string() })?;
        if let Some(t) = options.tempo_bpm {
            if !(super::MIN_MOVE_BPM..=super::MAX_MOVE_BPM).contains(&t) {
                return Err(SegmentError::BadTempo { name, tempo_bpm: t });
            }
        }
        let canon = to_canonical(clip, map, LIBRARY_FPS);
        let (beats, tempo_bpm, detected) = cut_beats(&canon, options);
        if beats.len() < SEGMENT_COUNTS + 1 {
            return Err(SegmentError::TooShort { name, duration_secs: clip.duration_secs(), beats: beats.len(), tempo_bpm });
        }
        let hop = options.hop_counts.clamp(1, SEGMENT_COUNTS);
        let beat_count = beats.len();
        let lc = LibraryClip::new(canon, beats, tempo_bpm, None);
        let index = self.clips.len();
        let added = self.push_clip(lc, hop);
        self.rescale();
        Ok(ClipSummary { clip: index, name, tempo_bpm, tempo_detected: detected, beats: beat_count, segments: added })
    }

    fn push_clip(&mut self, lc: LibraryClip, hop: usize) -> usize {
        let clip_index = self.clips.len();
        self.clips.push(lc);
        let added = self.cut_segments(clip_index, hop);
        self.changed();
        added
    }

    /// Appends the segments of clip `clip_index` at its beats (every `hop` counts), and sets
    /// the overlaps among all its segments.
    fn cut_segments(&mut self, clip_index: usize, hop: usize) -> usize {
        let Some(lc) = self.clips.get(clip_index) else { return 0 };
        // Library clips are on the canonical skeleton: world positions are the canonical ones.
        let positions = canonical_world_positions(&lc.clip);
        let frames = positions.len() / CANON_COUNT;
        let mut normed = positions.clone();
        let h = body_height(&positions);
        normalize_in_place(&mut normed, Origin::Hips, h);
        // W per frame (eq. 2), metres per second.
        let mut w = vec![0.0f32; frames];
        for f in 0..frames {
            let (a, b) = if f + 1 < frames { (f, f + 1) } else { (f.saturating_sub(1), f) };
            if a == b {
                continue;
            }
            w[f] = Canon::ALL
                .iter()
                .map(|&c| intensity_weight(c) * (positions[b * CANON_COUNT + c.index()] - positions[a * CANON_COUNT + c.index()]).length() * LIBRARY_FPS)
                .sum();
        }
        // Kinetic beats (spec §J) of the whole clip, for each segment's beat fit, and its foot
        // skate samples (the floor is the whole clip's, as §J measures a source clip), for each
        // segment's own skate.
        let (kinetic, skate): (Vec<f32>, Vec<[Option<f32>; 4]>) = match QualityMotion::from_positions(&positions, lc.clip.fps) {
            Ok(m) => (kinetic_beats_secs(&m).into_iter().map(|t| t * lc.clip.fps).collect(), foot_skate_samples(&m)),
            Err(_) => (Vec::new(), Vec::new()),
        };
        let clip_skate_cm_per_s = summarize_skate(&skate, 0..skate.len()).mean_cm_per_s;
        let quality_frame = |f: usize| ((f as f32 / lc.clip.fps) * QUALITY_FPS).round() as usize;
        let first_new = self.segments.len();
        let beats = &lc.beat_frames;
        // Built-in moves: their one 4-count bar only (module docs); imported clips: bars of each
        // metre at the same counts.
        let metres: &[usize] = if lc.builtin.is_some() { &[SEGMENT_COUNTS] } else { &SEGMENT_METRES };
        for &n in metres {
        // 3-count windows on every count (module docs).
        let hop = if n == SEGMENT_COUNTS { hop.clamp(1, n) } else { 1 };
        let mut k = 0;
        while k + n < beats.len() {
            let (s, e) = (beats[k], beats[k + n]);
            let (si, ei) = (s.round().max(0.0) as usize, (e.round() as usize).min(frames.saturating_sub(1)));
            if ei > si + 2 {
                let index = self.segments.len();
                let intensity = w[si..ei].iter().sum::<f32>() / (ei - si) as f32;
                self.signatures.push(signature_of(&normed, si, ei));
                self.ends.push(join_ends(&normed, si, ei));
                let name = match &lc.builtin {
                    Some(info) => info.name(),
                    None if n == SEGMENT_COUNTS => format!("{} · counts {}–{}", lc.clip.name, k + 1, k + n),
                    None => format!("{} · counts {}–{} (in {n})", lc.clip.name, k + 1, k + n),
                };
                let mut count_frames: Vec<f32> = beats[k..=k + n].to_vec();
                count_frames[0] = si as f32;
                count_frames[n] = ei as f32;
                if count_frames.windows(2).any(|w| !(w[1] > w[0])) {
                    count_frames = (0..=n).map(|j| si as f32 + (ei - si) as f32 * j as f32 / n as f32).collect();
                }
                let beat_fit = beat_fit(&count_frames, &kinetic);
                let (c0, c4) = (count_frames[0], count_frames[n]);
                let kinetic_per_count = kinetic.iter().filter(|&&f| f >= c0 && f < c4).count() as f32 / n as f32;
                let kinetic_per_count_by_rate = kinetic_per_count_by_rate(&positions, &count_frames);
                // Samples of frames after the first: a sample is the speed from the frame before.
                let skate_end = (quality_frame(ei) + 1).min(skate.len());
                let skate_cm_per_s = summarize_skate(&skate, (quality_frame(si) + 1).min(skate_end)..skate_end).mean_cm_per_s;
                self.segments.push(Segment {
                    index,
                    name,
                    count_frames,
                    beat_fit,
                    skate_cm_per_s,
                    clip_skate_cm_per_s,
                    kinetic_per_count,
                    kinetic_per_count_by_rate,
                    clip: clip_index,
                    source: lc.clip.source.clone(),
                    start_frame: si as f32,
                    end_frame: ei as f32,
                    tempo_bpm: n as f32 * 60.0 / ((ei - si) as f32 / LIBRARY_FPS),
                    intensity,
                    intensity01: 0.0,
                    builtin: lc.builtin,
                    retired: false,
                });
                self.overlaps.push(Vec::new());
            }
            k += hop;
        }
        }
        self.set_overlaps(clip_index);
        self.segments.len() - first_new
    }

    /// Overlaps among all the segments of clip `clip` (the new ones and any of its earlier
    /// cut kept by a re-cut).
    fn set_overlaps(&mut self, clip: usize) {
        let of_clip: Vec<usize> = (0..self.segments.len()).filter(|&i| self.segments[i].clip == clip).collect();
        for &i in &of_clip {
            let (a0, a1) = (self.segments[i].start_frame, self.segments[i].end_frame);
            let ov = of_clip
                .iter()
                .copied()
                .filter(|&j| {
                    let (b0, b1) = (self.segments[j].start_frame, self.segments[j].end_frame);
                    b0 < a1 && a0 < b1
                })
                .collect();
            self.overlaps[i] = ov;
        }
    }

    /// Re-cuts clip `clip` with new options (a tempo the person states, or `None` to detect it
    /// again): its earlier segments are removed, except those `keep` asks for (segments a
    /// choreography still uses), which stay as retired (never offered nor chosen again; see
    /// [`Segment::retired`]), and the new ones are appended. Segment indices change: `remap`
    /// of the result maps every old index to its new one. On error nothing changes.
    pub fn recut_clip(&mut self, clip: usize, options: &SegmentOptions, keep: &dyn Fn(usize) -> bool) -> Result<Recut, SegmentError> {
        let lc = self.clips.get(clip).ok_or(SegmentError::NoSuchClip { clip, clips: self.clips.len() })?;
        let name = lc.clip.name.clone();
        if lc.builtin.is_some() {
            return Err(SegmentError::BuiltinClip { name });
        }
        if let Some(t) = options.tempo_bpm {
            if !(super::MIN_MOVE_BPM..=super::MAX_MOVE_BPM).contains(&t) {
                return Err(SegmentError::BadTempo { name, tempo_bpm: t });
            }
        }
        let (beats, tempo_bpm, detected) = cut_beats(&lc.clip, options);
        if beats.len() < SEGMENT_COUNTS + 1 {
            return Err(SegmentError::TooShort { name, duration_secs: lc.clip.duration_secs(), beats: beats.len(), tempo_bpm });
        }
        let old_tempo = lc.tempo_bpm;
        let (remap, kept, removed) = self.drop_segments(&|i, s| s.clip != clip || keep(i));
        for &k in &kept {
            let s = &mut self.segments[k];
            if s.clip == clip && !s.retired {
                s.retired = true;
                s.name = format!("{} (earlier cut, {:.0} counts/min)", s.name, old_tempo);
            }
        }
        let kept: Vec<usize> = kept.into_iter().filter(|&k| self.segments[k].clip == clip).collect();
        let beat_count = beats.len();
        self.clips[clip].beat_frames = beats;
        self.clips[clip].tempo_bpm = tempo_bpm;
        let added = self.cut_segments(clip, options.hop_counts.clamp(1, SEGMENT_COUNTS));
        self.rescale();
        self.changed();
        let summary = ClipSummary { clip, name, tempo_bpm, tempo_detected: detected, beats: beat_count, segments: added };
        Ok(Recut { summary, remap, kept, removed })
    }

    /// Keeps the segments `retain` accepts (by old index), compacting every per-segment list.
    /// Returns the old → new index map, the kept indices (new) and how many went.
    fn drop_segments(&mut self, retain: &dyn Fn(usize, &Segment) -> bool) -> (Vec<Option<usize>>, Vec<usize>, usize) {
        let mut remap = Vec::with_capacity(self.segments.len());
        let mut next = 0;
        for (i, s) in self.segments.iter().enumerate() {
            if retain(i, s) {
                remap.push(Some(next));
                next += 1;
            } else {
                remap.push(None);
            }
        }
        let removed = self.segments.len() - next;
        let mask: Vec<bool> = remap.iter().map(Option::is_some).collect();
        retain_by_mask(&mut self.segments, &mask);
        retain_by_mask(&mut self.signatures, &mask);
        retain_by_mask(&mut self.ends, &mask);
        retain_by_mask(&mut self.overlaps, &mask);
        for (i, s) in self.segments.iter_mut().enumerate() {
            s.index = i;
        }
        for ov in self.overlaps.iter_mut() {
            *ov = ov.iter().filter_map(|&j| remap.get(j).copied().flatten()).collect();
        }
        (remap, (0..next).collect(), removed)
    }

    /// Drops the cached table and gives the library a new revision, unique in the process
    /// (libraries copied from one another then never share a revision once they differ, so a
    /// table built for one is refused by the other).
    fn changed(&mut self) {
        static NEXT_REVISION: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(1);
        self.revision = NEXT_REVISION.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        if let Ok(mut t) = self.table.lock() {
            *t = None;
        }
    }

    /// Changes with every change of the segments.
    pub fn revision(&self) -> u64 {
        self.revision
    }

    /// A builder of this library's all-pairs transition table, to run in slices (see
    /// [`TableBuilder`]); hand its result to [`SegmentLibrary::install_table`].
    pub fn table_builder(&self, repeat_penalty: f32) -> TableBuilder {
        TableBuilder::new(self, repeat_penalty)
    }

    /// A builder of the blocks of `scope` ([`TableScope`]: what a song's bars need,
    /// [`super::Choreography::table_scope`]) that the cached table (same penalty) lacks; its
    /// table holds the cached blocks too. Hand its result to
    /// [`SegmentLibrary::install_table_for`].
    pub fn table_builder_for(&self, repeat_penalty: f32, scope: &TableScope) -> TableBuilder {
        let cached = self.cached_table(repeat_penalty);
        TableBuilder::for_scope(self, repeat_penalty, scope, cached.as_deref())
    }

    /// Caches a table built by [`SegmentLibrary::table_builder`] or
    /// [`SegmentLibrary::table_builder_for`]; refused (`false`) when the library changed since
    /// (another revision, or segments grouped by other metres).
    pub fn install_table(&self, table: TransitionTable) -> bool {
        if table.revision() != self.revision || table.len() != self.len() {
            return false;
        }
        if !table.scope().is_all_pairs() && table.metres() != super::table::library_metres(self).as_slice() {
            return false;
        }
        let mut guard = match self.table.lock() {
            Ok(g) => g,
            Err(poisoned) => poisoned.into_inner(),
        };
        *guard = Some(Arc::new(table));
        true
    }

    /// [`SegmentLibrary::install_table`], refused too when the table lacks a block of `scope`
    /// (built for another set of metres than the song now needs).
    pub fn install_table_for(&self, table: TransitionTable, scope: &TableScope) -> bool {
        table.scope().covers(scope) && self.install_table(table)
    }

    /// Drops the cached table (its memory is freed once no one holds it); the next one needed
    /// is built again.
    pub fn drop_table(&self) {
        if let Ok(mut t) = self.table.lock() {
            *t = None;
        }
    }

    /// The cached table, when there is one for this repetition penalty.
    pub fn cached_table(&self, repeat_penalty: f32) -> Option<Arc<TransitionTable>> {
        let guard = self.table.lock().ok()?;
        guard.as_ref().filter(|t| t.repeat_penalty() == repeat_penalty).cloned()
    }

    /// The cached table, when there is one for this repetition penalty holding every pair of
    /// `scope`.
    pub fn cached_table_for(&self, repeat_penalty: f32, scope: &TableScope) -> Option<Arc<TransitionTable>> {
        self.cached_table(repeat_penalty).filter(|t| t.scope().covers(scope))
    }

    /// Rescales every segment's intensity to the range of the library's segments of its count
    /// (a bar in 3 chooses among 3-count moves only, so they are scaled among themselves; and
    /// the 4-count moves keep the scale they had before 3-count ones were cut).
    fn rescale(&mut self) {
        let metres: std::collections::BTreeSet<usize> = self.segments.iter().map(Segment::counts).collect();
        for n in metres {
            let mut v: Vec<f32> = self.segments.iter().filter(|s| s.counts() == n).map(|s| s.intensity).collect();
            v.sort_by(f32::total_cmp);
            let lo = v[v.len() * 5 / 100];
            let hi = v[(v.len() * 95 / 100).min(v.len() - 1)];
            for s in self.segments.iter_mut().filter(|s| s.counts() == n) {
                s.intensity01 = if hi > lo + 1e-6 { ((s.intensity - lo) / (hi - lo)).clamp(0.0, 1.0) } else { 0.5 };
            }
        }
    }

    pub fn len(&self) -> usize {
        self.segments.len()
    }

    pub fn is_empty(&self) -> bool {
        self.segments.is_empty()
    }

    pub fn segments(&self) -> &[Segment] {
        &self.segments
    }

    pub fn segment(&self, index: usize) -> Option<&Segment> {
        self.segments.get(index)
    }

    pub fn clips(&self) -> &[LibraryClip] {
        &self.clips
    }

    pub fn signature(&self, index: usize) -> Option<&Signature> {
        self.signatures.get(index)
    }

    /// kWAS similarity of two segments (0 when either index is out of range).
    pub fn similarity(&self, a: usize, b: usize) -> f32 {
        match (self.signatures.get(a), self.signatures.get(b)) {
            (Some(x), Some(y)) => x.similarity(y),
            _ => 0.0,
        }
    }

    /// D = 1 − Sim.
    pub fn dissimilarity(&self, a: usize, b: usize) -> f32 {
        1.0 - self.similarity(a, b)
    }

    /// The all-pairs transition table of spec §G for this library with the given repetition
    /// penalty (built once per library and penalty, then shared), reporting progress (0..1);
    /// the callback returns `false` to cancel (then `None`, and nothing is cached).
    pub fn transition_table_with_progress(&self, repeat_penalty: f32, progress: &mut dyn FnMut(f32) -> bool) -> Option<Arc<TransitionTable>> {
        if let Some(t) = self.cached_table_for(repeat_penalty, &TableScope::all_pairs()) {
            return Some(t);
        }
        let t = Arc::new(TransitionTable::from_library_with_progress(self, repeat_penalty, progress)?);
        if let Ok(mut guard) = self.table.lock() {
            *guard = Some(t.clone());
        }
        Some(t)
    }

    /// The all-pairs transition table of spec §G for this library with the given repetition
    /// penalty (built once per library and penalty, then shared).
    pub fn transition_table(&self, repeat_penalty: f32) -> Arc<TransitionTable> {
        self.transition_table_for(repeat_penalty, &TableScope::all_pairs())
    }

    /// A transition table holding (at least) the pairs of `scope` ([`TableScope`]): the cached
    /// one when it does; else one built with the blocks missing from the cached one (same
    /// penalty) added, then cached.
    pub fn transition_table_for(&self, repeat_penalty: f32, scope: &TableScope) -> Arc<TransitionTable> {
        let mut guard = match self.table.lock() {
            Ok(g) => g,
            Err(poisoned) => poisoned.into_inner(),
        };
        let cached = guard.as_ref().filter(|t| t.repeat_penalty() == repeat_penalty).cloned();
        if let Some(t) = cached.as_ref().filter(|t| t.scope().covers(scope)) {
            return t.clone();
        }
        let mut b = TableBuilder::for_scope(self, repeat_penalty, scope, cached.as_deref());
        while !b.step(usize::MAX).is_done() {}
        let t = Arc::new(b.finish().unwrap_or_else(|| TransitionTable::from_library(self, repeat_penalty)));
        *guard = Some(t.clone());
        t
    }
}

/// World positions of every frame of a clip on the canonical skeleton (frame-major), by an
/// allocation-free forward kinematics.
pub(crate) fn canonical_world_positions(clip: &Clip) -> Vec<Vec3> {
    let frames = clip.frame_count();
    let sk = &clip.skeleton;
    if sk.len() != CANON_COUNT {
        return canonical_positions(clip, &HumanoidMap::from_skeleton(sk));
    }
    let root = clip.translations.iter().find(|t| t.joint == 0).map(|t| t.values.as_slice());
    let mut out = Vec::with_capacity(frames * CANON_COUNT);
    let mut rot = [glam::Quat::IDENTITY; CANON_COUNT];
    let mut pos = [Vec3::ZERO; CANON_COUNT];
    let rest_root = sk.joints.first().map_or(Vec3::ZERO, |j| j.rest_offset);
    for f in 0..frames {
        let at = root.and_then(|r| r.get(f).copied()).unwrap_or(rest_root);
        sk.pose_into(clip.frame_rotations(f), at, &mut rot, &mut pos);
        out.extend_from_slice(&pos);
    }
    out
}

/// Unit link vectors, raw link vectors and velocities at a segment's first and last frames.
fn join_ends(normed: &[Vec3], start: usize, end: usize) -> JoinEnds {
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
    e
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

/// Overall joint speed per frame of a canonical clip (Σ over joints of world |ẋ|, m/s: a
/// planted step and the end of a gesture both dip), lightly smoothed.
pub fn joint_speed(clip: &Clip) -> Vec<f32> {
    let pos = canonical_world_positions(clip);
    let frames = pos.len() / CANON_COUNT;
    let mut s = vec![0.0f32; frames];
    for f in 1..frames {
        s[f] = (0..CANON_COUNT).map(|j| (pos[f * CANON_COUNT + j] - pos[(f - 1) * CANON_COUNT + j]).length()).sum::<f32>() * clip.fps;
    }
    if frames > 1 {
        s[0] = s[1];
    }
    // 3-tap smoothing.
    let mut out = s.clone();
    for f in 1..frames.saturating_sub(1) {
        out[f] = 0.25 * s[f - 1] + 0.5 * s[f] + 0.25 * s[f + 1];
    }
    out
}

/// Beat period (frames) and beats (frames) from the joint-speed curve alone (the fallback of
/// [`detect_counts`] when no body part shows a period).
pub fn detect_beats(speed: &[f32]) -> (Vec<f32>, f32) {
    let period = speed_period(speed);
    (beats_at_period(speed, period), period)
}

/// Count period (frames) of the joint-speed curve: its strongest autocorrelation peak after the
/// lobe around lag 0, folded into a choreographer's count; 15 frames (120 per minute) when
/// there is none.
fn speed_period(speed: &[f32]) -> f32 {
    let n = speed.len();
    let fps = LIBRARY_FPS;
    let (min_lag, max_lag) = ((fps * 60.0 / 200.0).floor() as usize, ((fps * 60.0 / 30.0).ceil() as usize).min(n / 2));
    if max_lag < min_lag + 2 {
        return fps * 0.5;
    }
    // Remove the slow trend (a 4-second moving mean).
    let win = (4.0 * fps) as usize;
    let mut prefix = vec![0.0f64; n + 1];
    for i in 0..n {
        prefix[i + 1] = prefix[i] + speed[i] as f64;
    }
    let x: Vec<f32> = (0..n)
        .map(|i| {
            let a = i.saturating_sub(win / 2);
            let b = (i + win / 2 + 1).min(n);
            speed[i] - ((prefix[b] - prefix[a]) / (b - a) as f64) as f32
        })
        .collect();
    let energy: f32 = x.iter().map(|v| v * v).sum::<f32>().max(1e-12);
    let ac = |lag: usize| -> f32 {
        if lag >= n {
            return 0.0;
        }
        let s: f32 = (0..n - lag).map(|i| x[i] * x[i + lag]).sum();
        s / energy * n as f32 / (n - lag) as f32
    };
    let acs: Vec<f32> = (0..=max_lag + 1).map(ac).collect();
    // Skip the lobe around lag 0: start after the first local minimum.
    let mut start = 1;
    while start < max_lag && acs[start + 1] < acs[start] {
        start += 1;
    }
    // The shortest period whose peak is nearly as strong as the strongest (longer peaks are
    // its multiples).
    let peaks: Vec<usize> = (start.max(min_lag).max(1)..=max_lag).filter(|&l| acs[l] > 0.0 && acs[l] >= acs[l - 1] && acs[l] >= acs[l + 1]).collect();
    let strongest = peaks.iter().map(|&l| acs[l]).fold(0.0f32, f32::max);
    let mut best = (peaks.iter().copied().find(|&l| acs[l] >= 0.8 * strongest).unwrap_or(0), strongest);
    if best.0 == 0 {
        // No periodicity: a regular grid at 120 counts per minute.
        best.0 = (fps * 0.5) as usize;
    }
    let mut lag = best.0;
    // Fold into a choreographer's count (60..=150 per minute): fast footwork counts in twos,
    // a slow sway in halves.
    while fps * 60.0 / lag as f32 > 150.0 && 2 * lag <= max_lag {
        lag *= 2;
    }
    while fps * 60.0 / (lag as f32) < 60.0 && lag >= 2 * min_lag {
        lag /= 2;
    }
    let lag = lag.clamp(1, max_lag);
    // Parabolic refinement.
    let (y0, y1, y2) = (acs[lag - 1], acs[lag], acs[lag + 1]);
    let den = y0 - 2.0 * y1 + y2;
    lag as f32 + if den.abs() > 1e-9 { (0.5 * (y0 - y2) / den).clamp(-0.5, 0.5) } else { 0.0 }
}

/// Counts (frames) on a grid of `period` frames: the phase where the joint speed is lowest,
/// then each count snapped to the nearest local minimum of the speed (its kinetic beat) within
/// a quarter period, so every count keeps its instant in the motion.
fn beats_at_period(speed: &[f32], period: f32) -> Vec<f32> {
    let n = speed.len();
    let phase = best_phase(speed, period);
    let grid_beats = grid(n, period, phase);
    let reach = (period / 4.0).max(1.0) as isize;
    let mut beats: Vec<f32> = Vec::with_capacity(grid_beats.len());
    for g in grid_beats {
        let c = g.round() as isize;
        let mut best_f = c;
        let mut best_v = f32::MAX;
        for f in (c - reach).max(1)..=(c + reach).min(n as isize - 2) {
            let fu = f as usize;
            let v = speed[fu];
            if v <= speed[fu - 1] && v <= speed[fu + 1] && v < best_v {
                best_v = v;
                best_f = f;
            }
        }
        let b = best_f.clamp(0, n as isize - 1) as f32;
        if beats.last().is_none_or(|&last| b > last + period * 0.5) {
            beats.push(b);
        }
    }
    beats
}

/// The body parts whose speed curves vote on a clip's count period (spec §E revised): the
/// feet (the steps: planted on a count, moving between), the whole body (whose dips are the
/// kinetic beats of §J), the hands (a partner dance is led through them) and the hips (the
/// weight moving from foot to foot).
const TEMPO_PARTS: [&[Canon]; 4] = [
    &[Canon::LeftFoot, Canon::LeftToe, Canon::RightFoot, Canon::RightToe],
    &Canon::ALL,
    &[Canon::LeftHand, Canon::RightHand],
    &[Canon::Hips],
];
/// Multiples of the count period whose autocorrelation supports it: the count, two counts and
/// the bar of four. A dance is periodic at its bar even where the steps inside it are uneven
/// (salsa steps on three counts of four), so a period is believed only when its multiples
/// agree.
const COMB_MULTIPLES: [f32; 3] = [1.0, 2.0, 4.0];
/// Periods searched, counts per minute: every octave and 3:2 alternative of a choreographer's
/// count (60..=150) is in range, scored by the same comb, so the best one wins on evidence.
const TEMPO_SEARCH_BPM: (f32, f32) = (30.0, 200.0);
/// Step of the period search, frames (a quarter frame: 0.4 % at 80 counts per minute, well
/// inside the 3 % partners must agree to).
const TEMPO_SEARCH_STEP_FRAMES: f32 = 0.25;
/// Moving-mean window removed from each speed curve before its autocorrelation, seconds: the
/// slow swell of a phrase, not the counts.
const TEMPO_DETREND_SECS: f32 = 2.0;

/// Speed curve of a set of canonical joints (Σ |ẋ|, frame-major `positions`).
fn part_speed(positions: &[Vec3], joints: &[Canon], fps: f32) -> Vec<f32> {
    let frames = positions.len() / CANON_COUNT;
    let mut v = vec![0.0f32; frames];
    for f in 1..frames {
        v[f] = joints.iter().map(|c| (positions[f * CANON_COUNT + c.index()] - positions[(f - 1) * CANON_COUNT + c.index()]).length()).sum::<f32>() * fps;
    }
    if frames > 1 {
        v[0] = v[1];
    }
    v
}

/// Autocorrelation of `signal` for lags `0..=max_lag` after removing its
/// [`TEMPO_DETREND_SECS`] moving mean, normalised by the energy and unbiased (1 at lag 0).
fn detrended_autocorrelation(signal: &[f32], max_lag: usize, fps: f32) -> Vec<f32> {
    let n = signal.len();
    let half = ((TEMPO_DETREND_SECS * fps) as usize / 2).max(1);
    let mut prefix = vec![0.0f64; n + 1];
    for i in 0..n {
        prefix[i + 1] = prefix[i] + signal[i] as f64;
    }
    let x: Vec<f32> = (0..n)
        .map(|i| {
            let (a, b) = (i.saturating_sub(half), (i + half + 1).min(n));
            signal[i] - ((prefix[b] - prefix[a]) / (b - a) as f64) as f32
        })
        .collect();
    let energy: f32 = x.iter().map(|v| v * v).sum::<f32>().max(1e-12);
    (0..=max_lag.min(n.saturating_sub(1)))
        .map(|lag| (0..n - lag).map(|i| x[i] * x[i + lag]).sum::<f32>() / energy * n as f32 / (n - lag) as f32)
        .collect()
}

/// Mean autocorrelation at the [`COMB_MULTIPLES`] of `period` (linear between lags); `None`
/// when fewer than two of them fit in `ac`.
fn comb_support(ac: &[f32], period: f32) -> Option<f32> {
    let mut sum = 0.0;
    let mut count = 0;
    for m in COMB_MULTIPLES {
        let lag = m * period;
        let i = lag.floor() as usize;
        if i + 1 >= ac.len() {
            continue;
        }
        let t = lag - i as f32;
        sum += ac[i] * (1.0 - t) + ac[i + 1] * t;
        count += 1;
    }
    (count >= 2).then(|| sum / count as f32)
}

/// A clip's count period (frames at [`LIBRARY_FPS`], folded into 60..=150 counts per minute)
/// and its support: the period whose [`COMB_MULTIPLES`] the speed curves of the
/// [`TEMPO_PARTS`] support most, summed over the parts (each curve's autocorrelation is
/// normalised, so each part has one vote). `None` when no period has positive support (no
/// part moves periodically). Why not the whole-body speed alone (the rule before): on the CMU
/// salsa clips its autocorrelation shows no peak at all in three of the four partner takes
/// (the arms and turns drown the steps), while the feet show the bar of the basic step.
pub fn clip_count_period(canon: &Clip) -> Option<(f32, f32)> {
    let positions = canonical_world_positions(canon);
    let fps = LIBRARY_FPS;
    let curves: Vec<Vec<f32>> = TEMPO_PARTS.iter().map(|joints| part_speed(&positions, joints, fps)).collect();
    comb_period(&curves, fps)
}

/// The count period (frames, folded into 60..=150 per minute) and its support that the speed
/// `curves` (one per body part, at `fps`) support most together (see [`clip_count_period`]).
fn comb_period(curves: &[Vec<f32>], fps: f32) -> Option<(f32, f32)> {
    let frames = curves.iter().map(Vec::len).min()?;
    let (lo, hi) = (fps * 60.0 / TEMPO_SEARCH_BPM.1, fps * 60.0 / TEMPO_SEARCH_BPM.0);
    let max_lag = ((COMB_MULTIPLES[COMB_MULTIPLES.len() - 1] * hi).ceil() as usize + 1).min(frames / 2);
    if max_lag < (2.0 * lo) as usize + 2 {
        return None;
    }
    let acs: Vec<Vec<f32>> = curves.iter().map(|c| detrended_autocorrelation(c, max_lag, fps)).collect();
    let mut best: Option<(f32, f32)> = None;
    let mut period = lo;
    while period <= hi {
        let support: Option<f32> = acs.iter().map(|ac| comb_support(ac, period)).sum();
        if let Some(s) = support {
            if best.is_none_or(|(_, b)| s > b) {
                best = Some((period, s));
            }
        }
        period += TEMPO_SEARCH_STEP_FRAMES;
    }
    let (mut period, support) = best.filter(|&(_, s)| s > 0.0)?;
    // A choreographer's count (60..=150 per minute): fast footwork counts in twos, a slow
    // sway in halves.
    while fps * 60.0 / period > 150.0 {
        period *= 2.0;
    }
    while fps * 60.0 / period < 60.0 {
        period /= 2.0;
    }
    Some((period, support))
}

/// Counts (frames) and count period (frames) of a canonical clip detected from its motion: the
/// period of [`clip_count_period`] (of the joint speed alone when no part is periodic), the
/// counts on it where the motion has them.
pub fn detect_counts(canon: &Clip) -> (Vec<f32>, f32) {
    counts_of(canon, &joint_speed(canon))
}

/// [`detect_counts`] with the clip's [`joint_speed`] already at hand.
fn counts_of(canon: &Clip, speed: &[f32]) -> (Vec<f32>, f32) {
    let period = clip_count_period(canon).map_or_else(|| speed_period(speed), |(p, _)| p);
    (beats_at_period(speed, period), period)
}

/// Nominal count length the beat fit is judged on, seconds (120 per minute).
const FIT_COUNT_SECS: f32 = 0.5;

/// Beat fit of a segment with counts `count_frames` (n + 1 of them) in a clip whose kinetic
/// beats are `kinetic_frames` (both clip frames): its kinetic beats warped onto a bar of n
/// counts of [`FIT_COUNT_SECS`] as the renderer warps them, then (BAS-music on the n − 1 inner
/// counts − BAS on the n half-counts + 1) / 2. 1: turns on every count and never between; 0.5:
/// no preference.
pub fn beat_fit(count_frames: &[f32], kinetic_frames: &[f32]) -> f32 {
    if count_frames.len() < 3 {
        return 0.5;
    }
    let n = count_frames.len() - 1;
    let (c0, c4) = (count_frames[0], count_frames[n]);
    let warp = |f: f32| -> f32 {
        let k = (0..n).rfind(|&k| f >= count_frames[k]).unwrap_or(0);
        let span = (count_frames[k + 1] - count_frames[k]).max(1e-6);
        (k as f32 + (f - count_frames[k]) / span) * FIT_COUNT_SECS
    };
    let mut kin: Vec<f32> = kinetic_frames.iter().copied().filter(|&f| f >= c0 && f <= c4).map(warp).collect();
    kin.sort_by(f32::total_cmp);
    let step = FIT_COUNT_SECS;
    let counts: Vec<f32> = (1..n).map(|k| k as f32 * step).collect();
    let halves: Vec<f32> = (0..n).map(|k| (k as f32 + 0.5) * step).collect();
    let on = bas_music(&counts, &kin).unwrap_or(0.0);
    let off = bas_music(&halves, &kin).unwrap_or(0.0);
    ((on - off + 1.0) * 0.5).clamp(0.0, 1.0)
}

/// Count rates, counts per minute, at which each segment's kinetic beats per count are measured
/// when the library is cut ([`Segment::kinetic_per_count_by_rate`]): the range the grid's bars
/// play segments at, log-spaced.
pub const KINETIC_RATES_BPM: [f32; 6] = [60.0, 75.0, 90.0, 110.0, 135.0, 165.0];

/// Kinetic beats per count (spec §J) of the segment with counts `count_frames` (frames of
/// `positions`, canonical world positions at [`LIBRARY_FPS`], frame-major) played at each rate
/// of [`KINETIC_RATES_BPM`]: resampled at [`QUALITY_FPS`] with its counts on the bar's beats
/// (piecewise-linear, as the renderer warps it) and half a count of the clip either side (so
/// its first count can be a turn, as in a dance), kinetic beats counted over its n counts
/// (`count_frames` holds n + 1).
pub fn kinetic_per_count_by_rate(positions: &[Vec3], count_frames: &[f32]) -> Vec<f32> {
    let frames = positions.len() / CANON_COUNT;
    if count_frames.len() < 2 || frames < 2 {
        return Vec::new();
    }
    let counts = count_frames.len() - 1;
    let c = count_frames;
    // Source frame at u counts from the segment's first count (u may run half a count out).
    let frame_at = |u: f32| -> f32 {
        let f = if u < 0.0 {
            c[0] + u * (c[1] - c[0])
        } else if u >= counts as f32 {
            c[counts] + (u - counts as f32) * (c[counts] - c[counts - 1])
        } else {
            let k = (u.floor() as usize).min(counts - 1);
            c[k] + (u - k as f32) * (c[k + 1] - c[k])
        };
        // Past the clip's ends, the clip mirrored in time (a one-bar built-in move has nothing
        // around it; the dance puts another move there whose speed is as likely to rise away
        // from the join as this one's).
        let last = (frames - 1) as f32;
        let f = if f < 0.0 { -f } else if f > last { 2.0 * last - f } else { f };
        f.clamp(0.0, last)
    };
    KINETIC_RATES_BPM
        .iter()
        .map(|&rate| {
            let count_secs = 60.0 / rate;
            let margin = 0.5 * count_secs;
            let n = ((counts as f32 * count_secs + 2.0 * margin) * QUALITY_FPS).round() as usize + 1;
            let mut out = Vec::with_capacity(n * CANON_COUNT);
            for i in 0..n {
                let t = i as f32 / QUALITY_FPS - margin;
                let f = frame_at(t / count_secs);
                let f0 = f.floor() as usize;
                let f1 = (f0 + 1).min(frames - 1);
                let a = f - f0 as f32;
                for j in 0..CANON_COUNT {
                    out.push(positions[f0 * CANON_COUNT + j].lerp(positions[f1 * CANON_COUNT + j], a));
                }
            }
            let Ok(m) = QualityMotion::from_positions(&out, QUALITY_FPS) else { return 0.0 };
            let span = counts as f32 * count_secs;
            let beats = kinetic_beats_secs(&m).into_iter().filter(|&t| t >= margin - 1e-4 && t < margin + span - 1e-4).count();
            beats as f32 / counts as f32
        })
        .collect()
}

/// Keeps the items whose `mask` entry is true.
fn retain_by_mask<T>(v: &mut Vec<T>, mask: &[bool]) {
    let mut i = 0;
    v.retain(|_| {
        i += 1;
        mask.get(i - 1).copied().unwrap_or(false)
    });
}

/// A canonical clip's counts (frames at [`LIBRARY_FPS`]), tempo (counts per minute) and
/// whether it was detected (else stated in `options`).
fn cut_beats(canon: &Clip, options: &SegmentOptions) -> (Vec<f32>, f32, bool) {
    let speed = joint_speed(canon);
    match options.tempo_bpm {
        Some(bpm) => {
            let period = LIBRARY_FPS * 60.0 / bpm;
            let phase = match options.first_beat_secs {
                Some(t) => (t * LIBRARY_FPS).rem_euclid(period),
                None => best_phase(&speed, period),
            };
            (grid(speed.len(), period, phase), bpm, false)
        }
        None => {
            let (beats, period) = counts_of(canon, &speed);
            (beats, LIBRARY_FPS * 60.0 / period.max(1e-3), true)
        }
    }
}

/// Phase (frames, in `0..period`) of a beat grid where the speed is lowest.
fn best_phase(speed: &[f32], period: f32) -> f32 {
    let steps = period.ceil().max(1.0) as usize;
    let mut best = (0.0, f32::MAX);
    for s in 0..steps {
        let phase = s as f32;
        let mut sum = 0.0;
        let mut count = 0;
        let mut t = phase;
        while (t as usize) < speed.len() {
            sum += speed[t.round() as usize % speed.len()];
            count += 1;
            t += period;
        }
        let mean = if count > 0 { sum / count as f32 } else { f32::MAX };
        if mean < best.1 {
            best = (phase, mean);
        }
    }
    best.0
}

fn grid(frames: usize, period: f32, phase: f32) -> Vec<f32> {
    let mut out = Vec::new();
    if !(period > 0.5) {
        return out;
    }
    let mut t = phase;
    while t <= (frames.saturating_sub(1)) as f32 {
        out.push(t);
        t += period;
    }
    out
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    #[test]
    fn links_match_the_canonical_tree() {
        let from_tree: Vec<(usize, usize)> = Canon::links().map(|(p, c)| (p.index(), c.index())).collect();
        assert_eq!(from_tree, LINKS.to_vec());
    }

    #[test]
    fn detects_the_tempo_of_a_pulsing_speed_curve() {
        // 110 counts per minute with dips on every count.
        let period = LIBRARY_FPS * 60.0 / 110.0;
        let speed: Vec<f32> = (0..600).map(|f| 2.0 - (f as f32 / period * std::f32::consts::TAU).cos() + 0.1 * ((f * 7 % 13) as f32 / 13.0)).collect();
        let (beats, p) = detect_beats(&speed);
        assert!((p - period).abs() < 0.5, "period {p} vs {period}");
        assert!(beats.len() >= 30);
        for b in &beats {
            let phase = (b / period).fract();
            assert!(phase < 0.12 || phase > 0.88, "beat at {b} is off the dips");
        }
    }

    #[test]
    fn comb_finds_the_count_of_uneven_steps_not_their_octave_or_three_to_four() {
        // Salsa-like feet: a step (a bump of speed) on counts 1, 2 and 3 of every 4, none on 4,
        // at 82 counts per minute; the body sways once per bar; a little deterministic noise.
        let fps = LIBRARY_FPS;
        let count = fps * 60.0 / 82.0;
        // SplitMix64 of the frame: white, unlike a bare multiplicative hash (a Weyl sequence).
        let noise = |f: usize| {
            let mut z = (f as u64).wrapping_add(1).wrapping_mul(0x9E37_79B9_7F4A_7C15);
            z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
            z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
            z ^= z >> 31;
            0.2 * ((z >> 40) as f32 / (1u64 << 24) as f32 - 0.5)
        };
        let feet: Vec<f32> = (0..900)
            .map(|f| {
                let c = f as f32 / count;
                let in_bar = c.rem_euclid(4.0);
                let step = if in_bar < 3.0 { (std::f32::consts::PI * in_bar.fract()).sin().powi(2) } else { 0.0 };
                1.0 + step + noise(f)
            })
            .collect();
        let body: Vec<f32> = (0..900).map(|f| 2.0 + (f as f32 / (4.0 * count) * std::f32::consts::TAU).sin() + noise(f + 13)).collect();
        let (period, support) = comb_period(&[feet, body], fps).expect("a period");
        assert!(support > 0.0);
        assert!((period / count - 1.0).abs() < 0.03, "period {period:.2} frames ({:.1}/min) vs {count:.2} (82/min)", fps * 60.0 / period);
        // Noise alone: at best chance support, far below the steps'.
        let flat: Vec<f32> = (0..900).map(|f| 1.0 + noise(f)).collect();
        let chance = comb_period(&[flat.clone(), flat], fps).map_or(0.0, |(_, s)| s);
        assert!(chance < 0.25 * support, "noise support {chance:.3} vs steps {support:.3}");
    }

    fn seg_with_counts(counts: Vec<f32>) -> Segment {
        Segment {
            index: 0,
            name: "s".into(),
            clip: 0,
            source: "test".into(),
            start_frame: counts[0],
            end_frame: counts[4],
            count_frames: counts,
            beat_fit: 0.5,
            skate_cm_per_s: 0.0,
            clip_skate_cm_per_s: 0.0,
            kinetic_per_count: 0.0,
            kinetic_per_count_by_rate: Vec::new(),
            tempo_bpm: 120.0,
            intensity: 1.0,
            intensity01: 0.5,
            builtin: None,
            retired: false,
        }
    }

    /// Three built-in moves and one imported clip (a built-in move's frames under another name,
    /// cut at a stated 240 counts per minute: 9 counts in its 2 s).
    pub(crate) fn small_library_with_an_imported_clip() -> SegmentLibrary {
        let mut lib = SegmentLibrary::new();
        let mut loader = BuiltinLoader::new();
        lib.load_builtin(&mut loader, 3);
        let mut clip = lib.clips()[1].clip.clone();
        clip.name = "imported".into();
        clip.source = "imported.bvh".into();
        let map = HumanoidMap::from_skeleton(&clip.skeleton);
        let options = SegmentOptions { tempo_bpm: Some(240.0), first_beat_secs: Some(0.0), hop_counts: 2 };
        lib.add_clip(&clip, &map, &HumanoidStatus::Complete, &options).unwrap();
        lib
    }

    #[test]
    fn imported_clips_are_cut_in_three_and_four_built_in_moves_in_four() {
        let lib = small_library_with_an_imported_clip();
        let (builtin, imported): (Vec<&Segment>, Vec<&Segment>) = lib.segments().iter().partition(|s| s.builtin.is_some());
        assert_eq!(builtin.len(), 3);
        assert!(builtin.iter().all(|s| s.counts() == 4 && s.count_frames.len() == 5));
        let beats = &lib.clips()[3].beat_frames;
        assert_eq!(beats.len(), 9, "{beats:?}");
        // 4 counts every 2 counts (hop_counts): from counts 0, 2, 4; 3 counts on every count:
        // from 0 to 5.
        let of = |n: usize| imported.iter().filter(|s| s.counts() == n).map(|s| s.start_frame).collect::<Vec<f32>>();
        assert_eq!(of(4), [0, 2, 4].map(|k| beats[k].round()));
        assert_eq!(of(3), [0, 1, 2, 3, 4, 5].map(|k| beats[k].round()));
        for s in imported.iter().filter(|s| s.counts() == 3) {
            assert_eq!(s.count_frames.len(), 4);
            assert!(s.name.ends_with("(in 3)"), "{}", s.name);
            // One count per beat of a bar in 3: count k at k/3 of the bar, and back.
            for (k, c) in s.count_frames.iter().enumerate() {
                assert!((s.frame_at(k as f32 / 3.0) - c).abs() < 1e-4, "{}: count {k}", s.name);
                assert!((s.bar_position(*c) - k as f32 / 3.0).abs() < 1e-4, "{}: count {k}", s.name);
            }
            // Its tempo is its 3 counts over its length, as a 4-count one's is its 4.
            assert!((s.tempo_bpm - 3.0 * 60.0 / s.duration_secs()).abs() < 1e-3);
            assert!(s.kinetic_per_count_by_rate.len() == KINETIC_RATES_BPM.len());
            // The lead-in is one of its counts long: a third of the bar.
            assert!((s.frame_before(-1.0 / 3.0) - (s.count_frames[0] - (s.count_frames[1] - s.count_frames[0])).max(0.0)).abs() < 1e-4);
        }
        // A 3-count segment shares frames with the 4-count one from the same count.
        let a = imported.iter().find(|s| s.counts() == 3).unwrap();
        let b = imported.iter().find(|s| s.counts() == 4 && s.start_frame == a.start_frame).unwrap();
        assert!(lib.overlaps[a.index].contains(&b.index));
    }

    #[test]
    fn the_lead_in_is_the_count_before_at_the_first_counts_pace() {
        let s = seg_with_counts(vec![10.0, 20.0, 40.0, 48.0, 60.0]);
        // A quarter of the bar before: one count (10 frames, the first count's length) earlier.
        assert!((s.frame_before(-0.25) - 0.0).abs() < 1e-4);
        assert!((s.frame_before(-0.125) - 5.0).abs() < 1e-4);
        // No further back than a count, nor before the clip's start; in the bar, as frame_at.
        assert!((s.frame_before(-3.0) - 0.0).abs() < 1e-4);
        assert!((seg_with_counts(vec![3.0, 13.0, 23.0, 33.0, 43.0]).frame_before(-0.25) - 0.0).abs() < 1e-4);
        assert!((s.frame_before(0.375) - s.frame_at(0.375)).abs() < 1e-4);
    }

    #[test]
    fn kinetic_beats_per_count_follow_the_count_rate() {
        // Interpolated in log rate between the measured rates, held at the ends, and the
        // own-tempo figure when none were measured.
        let mut s = seg_with_counts(vec![0.0, 15.0, 30.0, 45.0, 60.0]);
        s.kinetic_per_count = 0.75;
        assert_eq!(s.kinetic_per_count_at(100.0), 0.75);
        s.kinetic_per_count_by_rate = vec![2.0, 1.5, 1.25, 1.0, 0.75, 0.5];
        assert_eq!(s.kinetic_per_count_at(40.0), 2.0);
        assert_eq!(s.kinetic_per_count_at(200.0), 0.5);
        assert!((s.kinetic_per_count_at(90.0) - 1.25).abs() < 1e-5);
        let mid = (90.0f32 * 110.0).sqrt();
        assert!((s.kinetic_per_count_at(mid) - 1.125).abs() < 1e-4);
        // A body bobbing so it turns once a count (every 30 frames at 30 fps, 60 counts per
        // minute; the turns 0.3 frame after the counts, off the resampling grid: an exactly
        // symmetric turn is a two-frame tie, no strict minimum): about one kinetic beat a count
        // at every rate, the first count included (the half count around it gives it a turn).
        let rest = crate::builtin::canonical_skeleton().rest_positions();
        let frames = 240;
        let pos: Vec<Vec3> = (0..frames)
            .flat_map(|f| {
                let y = 0.08 * ((f as f32 - 0.3) / 30.0 * std::f32::consts::PI).cos();
                rest.iter().map(move |p| *p + Vec3::Y * y)
            })
            .collect();
        let counts = [60.0f32, 90.0, 120.0, 150.0, 180.0];
        let v = kinetic_per_count_by_rate(&pos, &counts);
        assert_eq!(v.len(), KINETIC_RATES_BPM.len());
        for (r, k) in KINETIC_RATES_BPM.iter().zip(&v) {
            assert!((0.75..=1.25).contains(k), "{k} kinetic beats a count at {r} counts per minute ({v:?})");
        }
    }

    #[test]
    fn each_count_lands_on_its_quarter_of_the_bar() {
        // Uneven counts: the second count comes early, the third late.
        let s = seg_with_counts(vec![10.0, 20.0, 40.0, 48.0, 60.0]);
        for (k, c) in [10.0f32, 20.0, 40.0, 48.0, 60.0].iter().enumerate() {
            assert!((s.frame_at(k as f32 / 4.0) - c).abs() < 1e-4, "count {k}");
            assert!((s.bar_position(*c) - k as f32 / 4.0).abs() < 1e-4, "count {k}");
        }
        // Linear between counts.
        assert!((s.frame_at(0.375) - 30.0).abs() < 1e-4);
        // Without counts (an older document), linear over the segment.
        let mut old = s.clone();
        old.count_frames.clear();
        assert!((old.frame_at(0.25) - 22.5).abs() < 1e-4);
    }

    #[test]
    fn beat_fit_in_three_prefers_turns_on_its_three_counts() {
        let counts = [0.0f32, 14.0, 31.0, 45.0];
        let between: Vec<f32> = counts.windows(2).map(|w| 0.5 * (w[0] + w[1])).collect();
        assert!(beat_fit(&counts, &counts) > 0.95);
        assert!(beat_fit(&counts, &between) < 0.05);
    }

    #[test]
    fn beat_fit_prefers_turns_on_the_counts() {
        let counts = [0.0f32, 12.0, 27.0, 39.0, 54.0];
        // Kinetic beats exactly on the counts (uneven as they are): the warp puts them on the
        // bar's quarters.
        let on = beat_fit(&counts, &counts);
        // Kinetic beats halfway between counts.
        let between: Vec<f32> = counts.windows(2).map(|w| 0.5 * (w[0] + w[1])).collect();
        let off = beat_fit(&counts, &between);
        assert!(on > 0.95, "{on}");
        assert!(off < 0.05, "{off}");
        // Turning on counts and between: no preference.
        let both: Vec<f32> = counts.iter().chain(&between).copied().collect();
        assert!((beat_fit(&counts, &both) - 0.5).abs() < 0.05);
    }

    #[test]
    fn builtin_library_loaded_in_slices_is_the_same_library() {
        let whole = SegmentLibrary::builtin();
        let mut sliced = SegmentLibrary::new();
        let mut loader = BuiltinLoader::new();
        let mut steps = 0;
        let mut last = 0.0;
        loop {
            let p = sliced.load_builtin(&mut loader, 37);
            assert!(p > last || p == 1.0, "progress {p} after {last}");
            last = p;
            steps += 1;
            if p >= 1.0 {
                break;
            }
        }
        assert!(steps > 5, "{steps} slices");
        assert_eq!(sliced.len(), whole.len());
        for (a, b) in sliced.segments().iter().zip(whole.segments()) {
            assert_eq!((a.name.as_str(), a.intensity.to_bits(), a.intensity01.to_bits()), (b.name.as_str(), b.intensity.to_bits(), b.intensity01.to_bits()));
        }
        // Asking again once done adds nothing.
        assert_eq!(sliced.load_builtin(&mut loader, 10), 1.0);
        assert_eq!(sliced.len(), whole.len());
    }

    #[test]
    fn builtin_library_has_one_segment_per_move() {
        let lib = SegmentLibrary::builtin();
        assert!(lib.len() >= 200);
        let s = &lib.segments()[0];
        assert!((s.tempo_bpm - 120.0).abs() < 1.0, "{}", s.tempo_bpm);
        let (lo, hi) = lib.segments().iter().fold((f32::MAX, f32::MIN), |(a, b), s| (a.min(s.intensity), b.max(s.intensity)));
        assert!(hi > lo * 1.5, "intensities {lo}..{hi}");
    }

    #[test]
    fn signatures_tell_a_move_from_itself_played_backwards() {
        // Played backwards, a move passes through the same poses: position-only features
        // (their second moments) cannot tell the two apart; the velocities can.
        let lib = SegmentLibrary::builtin();
        let lc = &lib.clips()[3];
        let positions = canonical_world_positions(&lc.clip);
        let mut normed = positions.clone();
        normalize_in_place(&mut normed, Origin::Hips, body_height(&positions));
        let frames = normed.len() / CANON_COUNT;
        let reversed: Vec<Vec3> = (0..frames).rev().flat_map(|f| normed[f * CANON_COUNT..(f + 1) * CANON_COUNT].to_vec()).collect();
        // The same span both ways (every other frame: the reverse samples the frames between).
        let (si, ei) = (0, frames - 1);
        let (a, b) = (signature_of(&normed, si, ei), signature_of(&reversed, si, ei));
        assert!((a.similarity(&a) - 1.0).abs() < 1e-4);
        let positions_only = |n: &[Vec3], from: usize, to: usize| {
            let feats: Vec<f32> = (from..to).step_by(2).flat_map(|f| n[f * CANON_COUNT..(f + 1) * CANON_COUNT].iter().zip(&SIGNATURE_REFERENCE).flat_map(|(p, r)| [p.x - r[0], p.y - r[1], p.z - r[2]]).chain([SIGNATURE_OFFSET]).collect::<Vec<f32>>()).collect();
            Signature::of_uncentred(&feats, CANON_COUNT * 3 + 1, SIGNATURE_AXES)
        };
        let same = positions_only(&normed, si, ei).similarity(&positions_only(&reversed, si, ei));
        let with_velocity = a.similarity(&b);
        println!("a move against itself backwards: Sim {with_velocity} with velocities, {same} on positions only");
        assert!(same > 0.99, "position-only signatures of a move and its reverse: Sim {same}");
        // Raw kWAS bunches near 1 (the search ranks it among each segment's neighbours), so
        // the check is on D = 1 − Sim: the velocities make it a hundred times larger.
        assert!(with_velocity < 0.995 && 1.0 - with_velocity > 100.0 * (1.0 - same), "with velocities, a move and its reverse still look alike: Sim {with_velocity} (positions only {same})");
    }

    #[test]
    fn signature_reference_is_the_builtin_moves_mean_pose() {
        let lib = SegmentLibrary::builtin();
        let mut sum = [[0.0f64; 3]; CANON_COUNT];
        let mut frames = 0usize;
        for lc in lib.clips() {
            let positions = canonical_world_positions(&lc.clip);
            let mut normed = positions.clone();
            normalize_in_place(&mut normed, Origin::Hips, body_height(&positions));
            for frame in normed.chunks_exact(CANON_COUNT) {
                for (acc, p) in sum.iter_mut().zip(frame) {
                    acc[0] += p.x as f64;
                    acc[1] += p.y as f64;
                    acc[2] += p.z as f64;
                }
                frames += 1;
            }
        }
        // Printed whole (the table to paste if the built-in moves change), then checked.
        let mut wrong = Vec::new();
        for (j, (acc, r)) in sum.iter().zip(&SIGNATURE_REFERENCE).enumerate() {
            let mean = acc.map(|a| a / frames as f64);
            println!("    [{:.3}, {:.3}, {:.3}], // {:?}", mean[0], mean[1], mean[2], Canon::ALL[j]);
            for a in 0..3 {
                if (mean[a] - r[a] as f64).abs() >= 0.01 {
                    wrong.push(format!("{:?} axis {a}: mean {:.4}, constant {}", Canon::ALL[j], mean[a], r[a]));
                }
            }
        }
        assert!(wrong.is_empty(), "SIGNATURE_REFERENCE is not the built-in moves' mean pose: {wrong:?}");
    }
}
