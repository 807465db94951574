//! Motion clips: per-frame local joint rotations and translations at a fixed frame rate
//! (posed in world space by the motion kernel's [`crate::motion::WorldPose`]).

use std::sync::Arc;

use glam::{Quat, Vec3};
use serde::{Deserialize, Serialize};
use thiserror::Error;

use crate::motion;
use crate::skeleton::Skeleton;

/// A per-frame local translation of one joint (the root's always; others where the source
/// animates them). Joints without a track use their rest offset.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct TranslationTrack {
    pub joint: usize,
    /// One value per frame, metres, in the parent's frame.
    pub values: Vec<Vec3>,
}

/// A motion clip.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Clip {
    /// Display name ("salsa_01", "Dance").
    pub name: String,
    /// The file (or "built-in") the clip came from.
    pub source: String,
    /// Frames per second; `> 0`.
    pub fps: f32,
    pub skeleton: Arc<Skeleton>,
    /// Local rotations, `frame_count * skeleton.len()`, frame-major.
    pub rotations: Vec<Quat>,
    /// Animated translations; the root's is always first when present.
    pub translations: Vec<TranslationTrack>,
}

#[derive(Debug, Error, PartialEq)]
pub enum ClipError {
    #[error("clip '{name}': frame rate must be positive and finite, got {fps}")]
    BadFps { name: String, fps: f32 },
    #[error("clip '{name}': {rotations} rotations is not a whole number of frames of {joints} joints")]
    RaggedRotations { name: String, rotations: usize, joints: usize },
    #[error("clip '{name}': translation track of joint {joint} has {values} values for {frames} frames")]
    RaggedTranslations { name: String, joint: usize, values: usize, frames: usize },
    #[error("clip '{name}' has no frames")]
    Empty { name: String },
    #[error("clip '{name}': skeleton joints are not ordered parents before children")]
    Unordered { name: String },
}

impl Clip {
    /// Checks every invariant the rest of the engine relies on.
    pub fn validate(&self) -> Result<(), ClipError> {
        let name = self.name.clone();
        if !(self.fps.is_finite() && self.fps > 0.0) {
            return Err(ClipError::BadFps { name, fps: self.fps });
        }
        let joints = self.skeleton.len();
        if joints == 0 || self.rotations.is_empty() {
            return Err(ClipError::Empty { name });
        }
        if self.rotations.len() % joints != 0 {
            return Err(ClipError::RaggedRotations { name, rotations: self.rotations.len(), joints });
        }
        if !self.skeleton.is_topologically_ordered() {
            return Err(ClipError::Unordered { name });
        }
        let frames = self.frame_count();
        for t in &self.translations {
            if t.values.len() != frames || t.joint >= joints {
                return Err(ClipError::RaggedTranslations { name, joint: t.joint, values: t.values.len(), frames });
            }
        }
        Ok(())
    }

    pub fn frame_count(&self) -> usize {
        match self.skeleton.len() {
            0 => 0,
            n => self.rotations.len() / n,
        }
    }

    /// Time from the first frame to the last, seconds: `(frames − 1) / fps`. Frame `k` is at
    /// `k / fps`, so this is the animation's own length (a glTF animation of 1 s sampled at
    /// 30 fps has 31 frames and lasts 1 s; a single-frame clip lasts 0 s).
    pub fn duration_secs(&self) -> f32 {
        self.frame_count().saturating_sub(1) as f32 / self.fps
    }

    pub fn joint_count(&self) -> usize {
        self.skeleton.len()
    }

    /// Local rotations of one frame.
    pub fn frame_rotations(&self, frame: usize) -> &[Quat] {
        let n = self.skeleton.len();
        &self.rotations[frame * n..(frame + 1) * n]
    }

    fn local_translation(&self, joint: usize, frame: usize) -> Vec3 {
        for t in &self.translations {
            if t.joint == joint {
                return t.values[frame];
            }
        }
        self.skeleton.joints[joint].rest_offset
    }

    /// Root translation of a frame (the first root joint's local translation).
    pub fn root_translation(&self, frame: usize) -> Vec3 {
        self.local_translation(0, frame)
    }

    /// Local translations of every joint at `frame` (tracks where present, rest offsets
    /// elsewhere), into `out` (resized).
    pub fn local_translations_into(&self, frame: usize, out: &mut Vec<Vec3>) {
        out.clear();
        out.extend(self.skeleton.joints.iter().map(|j| j.rest_offset));
        for t in &self.translations {
            if let (Some(slot), Some(v)) = (out.get_mut(t.joint), t.values.get(frame)) {
                *slot = *v;
            }
        }
    }

    /// World position of every joint at `frame` ([`motion::WorldPose::of_frame`]; a loop over
    /// frames keeps one `WorldPose` instead).
    pub fn world_positions(&self, frame: usize) -> Vec<Vec3> {
        std::mem::take(&mut motion::WorldPose::new().of_frame(self, frame).positions)
    }

    /// World positions of every frame, frame-major (`frame_count * joints`).
    pub fn all_world_positions(&self) -> Vec<Vec3> {
        let mut all = Vec::with_capacity(self.skeleton.len() * self.frame_count());
        let mut pose = motion::WorldPose::new();
        for f in 0..self.frame_count() {
            all.extend_from_slice(&pose.of_frame(self, f).positions);
        }
        all
    }

    /// Pose at a time in seconds: nearest frames blended (slerp / lerp); clamps to the clip.
    pub fn sample_into(&self, time_secs: f32, rotations: &mut Vec<Quat>, translations: &mut Vec<Vec3>) {
        let frames = self.frame_count();
        let n = self.skeleton.len();
        let x = (time_secs * self.fps).clamp(0.0, (frames.saturating_sub(1)) as f32);
        let f0 = x.floor() as usize;
        let f1 = (f0 + 1).min(frames - 1);
        let a = x - f0 as f32;
        rotations.clear();
        translations.clear();
        for i in 0..n {
            let q0 = self.rotations[f0 * n + i];
            let q1 = self.rotations[f1 * n + i];
            rotations.push(q0.slerp(q1, a));
            translations.push(self.local_translation(i, f0).lerp(self.local_translation(i, f1), a));
        }
    }

    /// Frames `start..end` as a new clip.
    pub fn slice(&self, start: usize, end: usize, name: impl Into<String>) -> Clip {
        let n = self.skeleton.len();
        let end = end.min(self.frame_count());
        let start = start.min(end);
        Clip {
            name: name.into(),
            source: self.source.clone(),
            fps: self.fps,
            skeleton: self.skeleton.clone(),
            rotations: self.rotations[start * n..end * n].to_vec(),
            translations: self
                .translations
                .iter()
                .map(|t| TranslationTrack { joint: t.joint, values: t.values[start..end].to_vec() })
                .collect(),
        }
    }

    /// Resampled to `fps` (slerp between neighbouring frames); keeps the duration: the first
    /// and last frames stay where they were, so the end is not a repeated frame.
    pub fn resampled(&self, fps: f32) -> Clip {
        let frames = self.frame_count();
        let n = self.skeleton.len();
        let new_frames = (self.duration_secs() * fps).round() as usize + 1;
        let mut rotations = Vec::with_capacity(new_frames * n);
        let mut tracks: Vec<TranslationTrack> =
            self.translations.iter().map(|t| TranslationTrack { joint: t.joint, values: Vec::with_capacity(new_frames) }).collect();
        for k in 0..new_frames {
            let x = (k as f32 * self.fps / fps).min((frames - 1) as f32);
            let f0 = x.floor() as usize;
            let f1 = (f0 + 1).min(frames - 1);
            let a = x - f0 as f32;
            for i in 0..n {
                rotations.push(self.rotations[f0 * n + i].slerp(self.rotations[f1 * n + i], a));
            }
            for (dst, src) in tracks.iter_mut().zip(&self.translations) {
                dst.values.push(src.values[f0].lerp(src.values[f1], a));
            }
        }
        Clip { name: self.name.clone(), source: self.source.clone(), fps, skeleton: self.skeleton.clone(), rotations, translations: tracks }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::skeleton::Joint;

    fn two_bone() -> Clip {
        let sk = Skeleton {
            joints: vec![
                Joint { name: "a".into(), parent: None, rest_offset: Vec3::ZERO, rest_rotation: Quat::IDENTITY, end_site: false },
                Joint { name: "b".into(), parent: Some(0), rest_offset: Vec3::Y, rest_rotation: Quat::IDENTITY, end_site: false },
            ],
        };
        let q = Quat::from_rotation_z(std::f32::consts::FRAC_PI_2);
        Clip {
            name: "t".into(),
            source: "test".into(),
            fps: 10.0,
            skeleton: Arc::new(sk),
            rotations: vec![Quat::IDENTITY, Quat::IDENTITY, q, Quat::IDENTITY],
            translations: vec![TranslationTrack { joint: 0, values: vec![Vec3::ZERO, Vec3::X] }],
        }
    }

    #[test]
    fn forward_kinematics_rotates_children() {
        let c = two_bone();
        c.validate().unwrap();
        let p = c.world_positions(1);
        assert!((p[0] - Vec3::X).length() < 1e-6);
        assert!((p[1] - Vec3::new(0.0, 0.0, 0.0)).length() < 1e-6, "{:?}", p[1]);
    }

    #[test]
    fn validate_rejects_ragged_and_bad_fps() {
        let mut c = two_bone();
        c.fps = 0.0;
        assert!(matches!(c.validate(), Err(ClipError::BadFps { .. })));
        let mut c = two_bone();
        c.rotations.pop();
        assert!(matches!(c.validate(), Err(ClipError::RaggedRotations { .. })));
    }

    #[test]
    fn resample_keeps_duration() {
        // Two frames at 10 fps span 0.1 s: at 20 fps that is three frames, the last one the
        // source's last frame (not a copy of it one frame later).
        let src = two_bone();
        let c = src.resampled(20.0);
        assert_eq!(c.frame_count(), 3);
        assert!((c.duration_secs() - src.duration_secs()).abs() < 1e-6);
        assert!((c.root_translation(2) - Vec3::X).length() < 1e-6);
        assert!((c.root_translation(1) - Vec3::X * 0.5).length() < 1e-6);
        c.validate().unwrap();
    }
}
