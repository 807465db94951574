//! Search features: per clip, the 21 canonical joint positions normalised per spec §B, as one
//! flat `f32` array (frames × 21 joints × xyz), built once per library clip and reused by every
//! query. The shoulder-origin variant for arm-only searches (spec §B.1) is derived from the
//! hip-origin one on first use, so a library that is never searched by arms pays nothing for it.

use std::sync::OnceLock;

use glam::Vec3;
use serde::{Deserialize, Serialize};

use crate::clip::Clip;
use crate::canon::humanoid::{canonical_positions, Canon, HumanoidMap, HumanoidStatus, CANON_COUNT};
use crate::canon::normalize::{body_height, normalize_in_place, Origin};

use super::SearchError;

/// Floats per frame in a feature array: 21 joints × (x, y, z).
pub const FRAME_FLOATS: usize = CANON_COUNT * 3;

/// Normalised canonical joint positions of one motion, frame-major, joint order
/// [`Canon::ALL`], each joint as x, y, z (body heights, Y up, hips' right→left along +Z).
#[derive(Clone, Debug, PartialEq)]
pub struct MotionFeatures {
    /// Which midpoint is the origin.
    pub origin: Origin,
    /// `frames * FRAME_FLOATS` values.
    pub data: Vec<f32>,
}

impl MotionFeatures {
    /// Number of frames.
    pub fn frame_count(&self) -> usize {
        self.data.len() / FRAME_FLOATS
    }

    /// The `FRAME_FLOATS` values of one frame (empty past the end).
    pub fn frame(&self, frame: usize) -> &[f32] {
        self.data.get(frame * FRAME_FLOATS..(frame + 1) * FRAME_FLOATS).unwrap_or(&[])
    }

    /// Position of one joint at one frame (`None` past the end).
    pub fn joint(&self, frame: usize, joint: Canon) -> Option<Vec3> {
        let f = self.frame(frame);
        let k = joint.index() * 3;
        f.get(k..k + 3).map(|v| Vec3::new(v[0], v[1], v[2]))
    }

    /// Frames `start_frame..end_frame` (clamped) as new features.
    pub fn slice(&self, start_frame: usize, end_frame: usize) -> MotionFeatures {
        let end = end_frame.min(self.frame_count());
        let start = start_frame.min(end);
        MotionFeatures { origin: self.origin, data: self.data[start * FRAME_FLOATS..end * FRAME_FLOATS].to_vec() }
    }

    /// Hip-origin features from raw canonical world positions (`frames * CANON_COUNT`),
    /// normalised by their own body height (spec §B).
    pub fn from_positions(positions: &[Vec3]) -> MotionFeatures {
        let height = body_height(positions);
        let mut p = positions.to_vec();
        normalize_in_place(&mut p, Origin::Hips, height);
        MotionFeatures { origin: Origin::Hips, data: flatten(&p) }
    }

    /// The same motion with the shoulder midpoint as origin (spec §B.1). Normalisation is
    /// `rot · (p − o) / height` with the rotation and height independent of the origin, so
    /// moving the origin from the hips to the shoulders is subtracting the normalised shoulder
    /// midpoint, frame by frame.
    pub fn to_shoulder_origin(&self) -> MotionFeatures {
        if self.origin == Origin::Shoulders {
            return self.clone();
        }
        let mut data = self.data.clone();
        let (l, r) = (Canon::LeftUpperArm.index() * 3, Canon::RightUpperArm.index() * 3);
        for f in data.chunks_exact_mut(FRAME_FLOATS) {
            let o = [(f[l] + f[r]) * 0.5, (f[l + 1] + f[r + 1]) * 0.5, (f[l + 2] + f[r + 2]) * 0.5];
            for p in f.chunks_exact_mut(3) {
                p[0] -= o[0];
                p[1] -= o[1];
                p[2] -= o[2];
            }
        }
        MotionFeatures { origin: Origin::Shoulders, data }
    }
}

fn flatten(p: &[Vec3]) -> Vec<f32> {
    let mut out = Vec::with_capacity(p.len() * 3);
    for v in p {
        out.extend_from_slice(&[v.x, v.y, v.z]);
    }
    out
}

/// One motion ready for searching, as a library clip or as a query: its hip-origin features
/// and, built on first use, the shoulder-origin ones.
#[derive(Clone, Debug)]
pub struct ClipFeatures {
    /// Display name (file and clip name).
    pub name: String,
    /// Frame rate of the features, frames per second.
    pub fps: f32,
    hips: MotionFeatures,
    shoulders: OnceLock<MotionFeatures>,
    /// Per origin (hips, shoulders): bounding boxes of every joint over each run of
    /// [`BOX_CHUNK_FRAMES`] frames, in the lane layout.
    boxes: [OnceLock<Vec<f32>>; 2],
    /// Per origin: bounding boxes of every joint over each run of the coupled bound's
    /// `coupled::FINE` frames, in the lane layout (built with the index, not stored).
    fine: [OnceLock<Vec<f32>>; 2],
    /// Per origin: the frames in the distance's lane layout (see `search::lanes`), built on
    /// first use.
    lanes: [OnceLock<Vec<f32>>; 2],
}

/// Frames per precomputed joint bounding box (used by the fast search's lower bounds).
pub const BOX_CHUNK_FRAMES: usize = 16;

impl ClipFeatures {
    /// Wraps hip-origin features.
    pub fn new(name: impl Into<String>, fps: f32, hips: MotionFeatures) -> ClipFeatures {
        let hips = if hips.origin == Origin::Hips { hips } else { MotionFeatures { origin: Origin::Hips, data: hips.data } };
        ClipFeatures {
            name: name.into(),
            fps,
            hips,
            shoulders: OnceLock::new(),
            boxes: [OnceLock::new(), OnceLock::new()],
            fine: [OnceLock::new(), OnceLock::new()],
            lanes: [OnceLock::new(), OnceLock::new()],
        }
    }

    /// [`ClipFeatures::new`] with the hip-origin chunk boxes given instead of built (a stored
    /// index being reopened, see `stored.rs`, which checks their length and checksum).
    pub(crate) fn with_hip_boxes(name: impl Into<String>, fps: f32, hips: MotionFeatures, boxes: Vec<f32>) -> ClipFeatures {
        let c = ClipFeatures::new(name, fps, hips);
        let _ = c.boxes[0].set(boxes);
        c
    }

    /// Features of a humanoid clip: canonical positions (missing joints filled from their
    /// neighbours), normalised per spec §B by the clip's own body height.
    pub fn from_clip(name: impl Into<String>, clip: &Clip, map: &HumanoidMap) -> ClipFeatures {
        let positions = canonical_positions(clip, map);
        ClipFeatures::new(name, clip.fps, MotionFeatures::from_positions(&positions))
    }

    /// Number of frames.
    pub fn frame_count(&self) -> usize {
        self.hips.frame_count()
    }

    /// Bytes of memory the clip's features hold now: the hip-origin features, and whatever
    /// was built on first use (shoulder-origin features, lane layouts, boxes).
    pub fn heap_bytes(&self) -> usize {
        let floats = self.hips.data.len()
            + self.shoulders.get().map_or(0, |m| m.data.len())
            + self.boxes.iter().chain(&self.fine).chain(&self.lanes).map(|l| l.get().map_or(0, Vec::len)).sum::<usize>();
        floats * std::mem::size_of::<f32>() + self.name.len()
    }

    /// Duration in seconds.
    pub fn duration_secs(&self) -> f32 {
        if self.fps > 0.0 {
            self.frame_count() as f32 / self.fps
        } else {
            0.0
        }
    }

    /// The features with the given origin.
    pub fn features(&self, origin: Origin) -> &MotionFeatures {
        match origin {
            Origin::Hips => &self.hips,
            Origin::Shoulders => self.shoulders.get_or_init(|| self.hips.to_shoulder_origin()),
        }
    }

    /// The frames with the given origin in the frame distance's lane layout
    /// (`super::lanes::LANE_FLOATS` per frame), built on first use.
    pub(crate) fn lanes(&self, origin: Origin) -> &[f32] {
        let slot = match origin {
            Origin::Hips => &self.lanes[0],
            Origin::Shoulders => &self.lanes[1],
        };
        slot.get_or_init(|| super::lanes::to_lanes(&self.features(origin).data))
    }

    /// Joint bounding boxes per [`BOX_CHUNK_FRAMES`] frames for an origin, in the lane layout
    /// (`super::lanes::BOX_FLOATS` per chunk), built on first use.
    pub(crate) fn chunk_boxes(&self, origin: Origin) -> &[f32] {
        let slot = match origin {
            Origin::Hips => &self.boxes[0],
            Origin::Shoulders => &self.boxes[1],
        };
        slot.get_or_init(|| super::lanes::chunk_boxes(self.lanes(origin), BOX_CHUNK_FRAMES))
    }

    /// Joint bounding boxes per `coupled::FINE` (8) frames for an origin, in the lane layout,
    /// for the coupled bound's tables (built on first use; the index builds the hip-origin
    /// ones when a clip is added, so a search does not box the library again every time).
    pub(crate) fn fine_boxes(&self, origin: Origin) -> &[f32] {
        let slot = match origin {
            Origin::Hips => &self.fine[0],
            Origin::Shoulders => &self.fine[1],
        };
        slot.get_or_init(|| super::lanes::chunk_boxes(self.lanes(origin), super::coupled::FINE))
    }

    /// Frames `start_frame..end_frame` as a new motion (a query cut from a library clip keeps
    /// that clip's body-height scaling). Errors on an empty or out-of-range span.
    pub fn slice(&self, start_frame: usize, end_frame: usize) -> Result<ClipFeatures, SearchError> {
        let frames = self.frame_count();
        if start_frame >= end_frame || end_frame > frames {
            return Err(SearchError::BadRange { clip: self.name.clone(), start_frame, end_frame, frames });
        }
        Ok(ClipFeatures::new(format!("{} [{start_frame}..{end_frame})", self.name), self.fps, self.hips.slice(start_frame, end_frame)))
    }

    /// x, y and z of one joint over time, normalised (hip origin: body heights, facing +Z),
    /// for the joint-coordinate plot.
    pub fn joint_curve(&self, joint: Canon, origin: Origin) -> JointCurve {
        let f = self.features(origin);
        let n = f.frame_count();
        let k = joint.index() * 3;
        let mut c = JointCurve { joint: joint.name().to_string(), fps: self.fps, x: Vec::with_capacity(n), y: Vec::with_capacity(n), z: Vec::with_capacity(n) };
        for frame in f.data.chunks_exact(FRAME_FLOATS) {
            c.x.push(frame[k]);
            c.y.push(frame[k + 1]);
            c.z.push(frame[k + 2]);
        }
        c
    }
}

/// One joint's normalised coordinates over a clip, for the joint-coordinate plot
/// (seed 002 Fig. 11–12). Index = frame; time = frame / fps.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "camelCase")]
pub struct JointCurve {
    /// camelCase canonical joint name ("rightHand").
    pub joint: String,
    /// Frames per second of the samples.
    pub fps: f32,
    /// x per frame (body heights; after normalisation +Z is the hips' right→left direction).
    pub x: Vec<f32>,
    /// y per frame (up).
    pub y: Vec<f32>,
    /// z per frame.
    pub z: Vec<f32>,
}

/// A clip the index refused, with why.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "camelCase")]
pub struct SkippedClip {
    /// The clip's name.
    pub name: String,
    /// Why it is not searchable.
    pub reason: String,
}

/// Frame rate every library clip is resampled to, so that "the same speed" means the same
/// number of frames in every clip (the CMU files mix 60 and 120 fps).
pub const DEFAULT_INDEX_FPS: f32 = 60.0;

/// The search library: features of every humanoid clip, built once and reused by every query.
#[derive(Clone, Debug)]
pub struct FeatureIndex {
    /// Frame rate of every clip's features: clips are resampled to it when added.
    pub fps: f32,
    /// Searchable clips, in the order they were added (a result's `clipIndex` refers here).
    pub clips: Vec<ClipFeatures>,
    /// Clips that were offered but refused (non-humanoid, empty), with the reason.
    pub skipped: Vec<SkippedClip>,
}

impl Default for FeatureIndex {
    fn default() -> Self {
        FeatureIndex { fps: DEFAULT_INDEX_FPS, clips: Vec::new(), skipped: Vec::new() }
    }
}

impl FeatureIndex {
    /// An empty library at [`DEFAULT_INDEX_FPS`].
    pub fn new() -> FeatureIndex {
        FeatureIndex::default()
    }

    /// An empty library whose clips are resampled to `fps` (falls back to
    /// [`DEFAULT_INDEX_FPS`] when `fps` is not a positive number).
    pub fn with_fps(fps: f32) -> FeatureIndex {
        FeatureIndex { fps: if fps.is_finite() && fps > 0.0 { fps } else { DEFAULT_INDEX_FPS }, ..FeatureIndex::default() }
    }

    /// The clip as the index sees it: resampled to the index's frame rate when it differs.
    /// Frame numbers in results refer to this timing (`frame / fps` seconds).
    pub fn resampled<'c>(&self, clip: &'c Clip) -> std::borrow::Cow<'c, Clip> {
        if clip.fps > 0.0 && (clip.fps - self.fps).abs() > 1e-3 && clip.frame_count() > 1 {
            std::borrow::Cow::Owned(clip.resampled(self.fps))
        } else {
            std::borrow::Cow::Borrowed(clip)
        }
    }

    /// Adds a clip, resampled to the index's frame rate. A non-humanoid or empty clip is
    /// refused: it is recorded in [`FeatureIndex::skipped`] with its reason and the error is
    /// returned; the index stays usable. Returns the clip's index.
    pub fn add_clip(&mut self, name: impl Into<String>, clip: &Clip, map: &HumanoidMap, status: &HumanoidStatus) -> Result<usize, SearchError> {
        let name = name.into();
        if let HumanoidStatus::NotHumanoid { reason } = status {
            self.skipped.push(SkippedClip { name: name.clone(), reason: reason.clone() });
            return Err(SearchError::NotHumanoid { clip: name, reason: reason.clone() });
        }
        if clip.frame_count() == 0 {
            let reason = "it has no frames".to_string();
            self.skipped.push(SkippedClip { name: name.clone(), reason: reason.clone() });
            return Err(SearchError::NotHumanoid { clip: name, reason });
        }
        let clip = self.resampled(clip);
        let features = ClipFeatures::from_clip(name, &clip, map);
        Ok(self.add_features(features))
    }

    /// Adds ready-made features (for example a concatenated benchmark library), and builds
    /// its hip-origin bounding boxes.
    pub fn add_features(&mut self, features: ClipFeatures) -> usize {
        features.chunk_boxes(Origin::Hips);
        features.fine_boxes(Origin::Hips);
        self.clips.push(features);
        self.clips.len() - 1
    }

    /// Total frames over all clips.
    pub fn total_frames(&self) -> usize {
        self.clips.iter().map(ClipFeatures::frame_count).sum()
    }

    /// Bytes of memory the clips' features hold now (see [`ClipFeatures::heap_bytes`]).
    pub fn heap_bytes(&self) -> usize {
        self.clips.iter().map(ClipFeatures::heap_bytes).sum()
    }

    /// A query cut from a library clip: frames `start_frame..end_frame` of clip `clip_index`.
    pub fn query_range(&self, clip_index: usize, start_frame: usize, end_frame: usize) -> Result<ClipFeatures, SearchError> {
        let clip = self.clips.get(clip_index).ok_or(SearchError::UnknownClip { clip_index, clip_count: self.clips.len() })?;
        clip.slice(start_frame, end_frame)
    }

    /// A joint's x/y/z curve over a library clip (for the plot).
    pub fn joint_curve(&self, clip_index: usize, joint: Canon, origin: Origin) -> Result<JointCurve, SearchError> {
        let clip = self.clips.get(clip_index).ok_or(SearchError::UnknownClip { clip_index, clip_count: self.clips.len() })?;
        Ok(clip.joint_curve(joint, origin))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::canon::builtin::demo_clip;
    use crate::canon::normalize::normalized;

    #[test]
    fn shoulder_origin_matches_spec_normalisation() {
        let clip = demo_clip();
        let map = HumanoidMap::from_skeleton(&clip.skeleton);
        let positions = canonical_positions(&clip, &map);
        let f = ClipFeatures::from_clip("demo", &clip, &map);
        for (origin, want) in [(Origin::Hips, normalized(&positions, Origin::Hips)), (Origin::Shoulders, normalized(&positions, Origin::Shoulders))] {
            let got = &f.features(origin).data;
            assert_eq!(got.len(), want.len() * 3);
            for (g, w) in got.chunks_exact(3).zip(&want) {
                assert!((Vec3::new(g[0], g[1], g[2]) - *w).length() < 1e-5, "{origin:?}: {g:?} vs {w}");
            }
        }
    }

    #[test]
    fn chunk_boxes_contain_every_frame_and_curves_read_back() {
        use super::super::lanes::{point_box, weighted_groups, BOX_FLOATS, LANE_FLOATS};
        let clip = demo_clip();
        let map = HumanoidMap::from_skeleton(&clip.skeleton);
        let f = ClipFeatures::from_clip("demo", &clip, &map);
        let boxes = f.chunk_boxes(Origin::Hips);
        let lanes = f.lanes(Origin::Hips);
        assert_eq!(boxes.len(), f.frame_count().div_ceil(BOX_CHUNK_FRAMES) * BOX_FLOATS);
        let groups = weighted_groups(&[1.0; CANON_COUNT]);
        for (n, frame) in lanes.chunks_exact(LANE_FLOATS).enumerate() {
            assert_eq!(point_box(frame, &boxes[(n / BOX_CHUNK_FRAMES) * BOX_FLOATS..], &groups), 0.0, "frame {n} outside its box");
        }
        let c = f.joint_curve(Canon::RightHand, Origin::Hips);
        assert_eq!(c.x.len(), f.frame_count());
        assert_eq!(c.joint, "rightHand");
        let p = f.features(Origin::Hips).joint(7, Canon::RightHand).expect("frame 7");
        assert_eq!((c.x[7], c.y[7], c.z[7]), (p.x, p.y, p.z));
    }
}
