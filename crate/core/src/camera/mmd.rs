//! An MMD camera VMD driving the video camera (issue 29): the track's keys (look-at point,
//! rotation, distance, field of view, each channel eased by its own Bézier curve of the later
//! key, as MMD plays them) sampled at a frame's time, less the dance's offset, and turned into
//! a [`CameraPose`]. MMD's camera stands `-distance` from its look-at point along its view
//! axis, turned by yaw (y) then pitch (x); keys one frame apart (MMD's cuts) are not eased.
//! Roll (z) is not kept: the renderer's camera stays upright.

use crate::fmath;
use glam::{EulerRot, Quat, Vec3};

use super::{CameraError, CameraPose};
use crate::mmd::files::{CameraTrack, CameraTrackKey};
use crate::mmd::bezier_ratio;

/// MMD's frame rate: keys this close are a cut, shown without easing (three.js allows 1.5 frames
/// for float error, as here).
const CUT_SECS: f32 = 1.5 / 30.0;

/// The camera as MMD has it at one instant (metres, the engine's right-handed frame).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MmdCameraState {
    pub target_m: Vec3,
    /// Pitch (x), yaw (y), roll (z), radians, as [`CameraTrackKey::rotation_rad`].
    pub rotation_rad: Vec3,
    /// MMD's signed distance (negative: the camera is in front of the look-at point), metres.
    pub distance_m: f32,
    pub fov_deg: f32,
}

impl MmdCameraState {
    fn of(k: &CameraTrackKey) -> MmdCameraState {
        MmdCameraState { target_m: k.target_m, rotation_rad: k.rotation_rad, distance_m: k.distance_m, fov_deg: k.fov_deg }
    }

    /// Where the camera stands: the look-at point plus the view axis (turned by yaw then
    /// pitch) times the distance.
    pub fn eye(&self) -> Vec3 {
        let r = Quat::from_euler(EulerRot::YXZ, -self.rotation_rad.y, -self.rotation_rad.x, 0.0);
        self.target_m + r * Vec3::new(0.0, 0.0, -self.distance_m)
    }

    /// The renderer's camera for this state (upright: roll dropped). An error when the
    /// state is degenerate (not finite, the eye on the look-at point, no field of view).
    pub fn pose(&self) -> Result<CameraPose, CameraError> {
        let v = self.eye() - self.target_m;
        let distance = v.length();
        if !(distance.is_finite() && distance > 1e-4) {
            return Err(CameraError::BadOption { what: "MMD camera distance (m)", value: self.distance_m });
        }
        if !(self.fov_deg.is_finite() && self.fov_deg > 0.0 && self.fov_deg < 180.0) {
            return Err(CameraError::BadOption { what: "MMD camera field of view (degrees)", value: self.fov_deg });
        }
        if !self.target_m.is_finite() {
            return Err(CameraError::BadOption { what: "MMD camera look-at point (m)", value: self.target_m.x + self.target_m.y + self.target_m.z });
        }
        Ok(CameraPose {
            target: self.target_m.to_array(),
            yaw: fmath::atan2(v.x, v.z),
            pitch: fmath::asin((v.y / distance).clamp(-1.0, 1.0)),
            distance,
            fov_y: self.fov_deg.to_radians(),
        })
    }
}

/// The eased share (0–1) of a span at `w` (0–1) for a curve `[x1, y1, x2, y2]` (0–127).
fn eased(curve: [u8; 4], w: f32) -> f32 {
    let [x1, y1, x2, y2] = curve.map(|c| f32::from(c) / 127.0);
    bezier_ratio(x1, x2, y1, y2, w)
}

/// The track's camera at `time_secs` (the track's own time: the dance's song time less its
/// offset): the first key's before it, the last key's after it. `None` for a track with no keys.
pub fn sample(track: &CameraTrack, time_secs: f32) -> Option<MmdCameraState> {
    let keys = &track.keys;
    let first = keys.first()?;
    if !(time_secs > first.time_secs) {
        return Some(MmdCameraState::of(first));
    }
    // The first key after the time (keys are sorted by time).
    let i = keys.partition_point(|k| k.time_secs <= time_secs);
    let Some(b) = keys.get(i) else { return keys.last().map(MmdCameraState::of) };
    let a = &keys[i - 1];
    let span = b.time_secs - a.time_secs;
    if span < CUT_SECS {
        return Some(MmdCameraState::of(a));
    }
    let w = ((time_secs - a.time_secs) / span).clamp(0.0, 1.0);
    let c = &b.curves;
    let lerp = |x: f32, y: f32, r: f32| x + (y - x) * r;
    let target = Vec3::new(
        lerp(a.target_m.x, b.target_m.x, eased(c[0], w)),
        lerp(a.target_m.y, b.target_m.y, eased(c[1], w)),
        lerp(a.target_m.z, b.target_m.z, eased(c[2], w)),
    );
    Some(MmdCameraState {
        target_m: target,
        rotation_rad: a.rotation_rad.lerp(b.rotation_rad, eased(c[3], w)),
        distance_m: lerp(a.distance_m, b.distance_m, eased(c[4], w)),
        fov_deg: lerp(a.fov_deg, b.fov_deg, eased(c[5], w)),
    })
}

/// One pose per frame time: the track sampled at `time − offset_secs` (the dance's offset:
/// where the track's frame 0 falls in the video's time). An error naming the frame when the
/// track has no keys or a sampled state is degenerate.
pub fn poses(track: &CameraTrack, times_secs: &[f32], offset_secs: f32) -> Result<Vec<CameraPose>, CameraError> {
    if track.keys.is_empty() {
        return Err(CameraError::NoFrames);
    }
    times_secs
        .iter()
        .enumerate()
        .map(|(frame, &t)| {
            if !t.is_finite() {
                return Err(CameraError::BadTime { frame, time_secs: t });
            }
            sample(track, t - offset_secs).ok_or(CameraError::NoFrames)?.pose()
        })
        .collect()
}
