//! The video camera: where it stands in every frame of an exported dance (issue 29).
//!
//! Four modes over the figures' joint positions, one pose per frame: *fixed* (one framing of
//! the whole range), *orbit* (a slow turn about the figures), *follow* (tracks their centre on
//! the ground) and *director* (cut shots — wide, medium, close, low angle — that change only on
//! bar lines at phrase starts: every 8 bars, 4 for a short range, and sooner at a section
//! change or a jump in intensity from [`crate::music::sections`]). Every pose is fitted so no
//! joint of any figure projects outside the frame: the distance is the least at which every
//! joint the pose must hold lies inside the field of view (with a margin), computed exactly
//! per joint rather than from a bounding sphere. Pure maths, deterministic for its inputs.
//! A camera track read from a file (an MMD camera VMD) can replace the plan later: the
//! viewer takes one [`CameraPose`] at a time, whatever made it.

use crate::fmath;
use glam::{Mat4, Vec3, Vec4};
use serde::{Deserialize, Serialize};
use thiserror::Error;

use crate::bars::Bar;
use crate::music::sections::Sections;

/// What can go wrong planning a camera, with the offending values.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum CameraError {
    #[error("no frames to plan a camera for")]
    NoFrames,
    #[error("frame {frame} has {got} joint positions, frame 0 has {want}: every frame needs the same joints")]
    JointCount { frame: usize, got: usize, want: usize },
    #[error("frame {frame}, joint {joint}: position {value:?} is not finite")]
    BadJoint { frame: usize, joint: usize, value: [f32; 3] },
    #[error("frame time {time_secs} s at frame {frame} is not finite or goes back in time")]
    BadTime { frame: usize, time_secs: f32 },
    #[error("camera option {what} = {value} is invalid")]
    BadOption { what: &'static str, value: f32 },
    #[error("bar {index} spans {start_secs} s to {end_secs} s: not a finite, increasing span after the previous bar")]
    BadBar { index: usize, start_secs: f32, end_secs: f32 },
}

/// Where the camera is: it looks at `target` from `distance` metres away, turned `yaw`
/// radians about +Y (0: from +Z, the figure's front) and `pitch` radians above the ground
/// plane, through a vertical field of view of `fov_y` radians. The same parameters as the
/// renderer's orbit camera, so the viewer takes a pose as it is.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "camelCase")]
pub struct CameraPose {
    pub target: [f32; 3],
    pub yaw: f32,
    pub pitch: f32,
    pub distance: f32,
    pub fov_y: f32,
}

impl CameraPose {
    /// The eye's position.
    pub fn eye(&self) -> Vec3 {
        let (sy, cy) = fmath::sin_cos(self.yaw);
        let (sp, cp) = fmath::sin_cos(self.pitch);
        Vec3::from(self.target) + Vec3::new(sy * cp, sp, cy * cp) * self.distance
    }

    /// View-projection matrix for a view of this aspect (width / height): the renderer's
    /// (`odori_render::OrbitCamera::view_proj`, right-handed, depth 0..1).
    pub fn view_proj(&self, aspect: f32) -> Mat4 {
        let view = glam::camera::rh::view::look_at_mat4(self.eye(), Vec3::from(self.target), Vec3::Y);
        let near = (self.distance * 0.01).max(0.01);
        let proj = glam::camera::rh::proj::directx::perspective(self.fov_y, aspect.max(1e-3), near, near * 20_000.0);
        proj * view
    }

    /// Where a world point lands in normalised device coordinates (x, y in −1..1 inside the
    /// frame), or `None` behind the camera.
    pub fn project(&self, aspect: f32, p: Vec3) -> Option<[f32; 2]> {
        let c = self.view_proj(aspect) * Vec4::new(p.x, p.y, p.z, 1.0);
        (c.w > 1e-6).then(|| [c.x / c.w, c.y / c.w])
    }

    /// The camera's axes: towards the eye from the target, right, up.
    fn axes(yaw: f32, pitch: f32) -> (Vec3, Vec3, Vec3) {
        let (sy, cy) = fmath::sin_cos(yaw);
        let (sp, cp) = fmath::sin_cos(pitch);
        let back = Vec3::new(sy * cp, sp, cy * cp);
        let right = Vec3::Y.cross(back).normalize_or(Vec3::X);
        let up = back.cross(right);
        (back, right, up)
    }
}

/// The least distance at which every point lies inside the frame of a camera at `target`
/// turned (`yaw`, `pitch`), filling at most `fill` of the half-width and half-height: point
/// `v` (from the target) at depth `d − v·back` from the eye needs `|v·right| ≤ fill · tanₕ ·
/// depth` and `|v·up| ≤ fill · tanᵥ · depth`.
fn fit_distance(points: impl Iterator<Item = Vec3>, target: Vec3, yaw: f32, pitch: f32, fov_y: f32, aspect: f32, fill: f32) -> f32 {
    let (back, right, up) = CameraPose::axes(yaw, pitch);
    let tan_v = fmath::tan(fov_y * 0.5) * fill;
    let tan_h = fmath::tan(fov_y * 0.5) * aspect * fill;
    let mut d: f32 = MIN_DISTANCE_M;
    for p in points {
        let v = p - target;
        let z = v.dot(back);
        // Also in front of the near plane by a little, whatever the point's place in the frame.
        d = d.max(z + v.dot(right).abs() / tan_h).max(z + v.dot(up).abs() / tan_v).max(z + MIN_DEPTH_M);
    }
    d
}

/// The camera never comes nearer the target than this.
const MIN_DISTANCE_M: f32 = 0.5;
/// Nor nearer any joint, along the view, than this.
const MIN_DEPTH_M: f32 = 0.3;
/// The eye stays at least this far above the floor (a low angle looks up, not through it).
const MIN_EYE_HEIGHT_M: f32 = 0.12;

/// The four ways the camera moves.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "camelCase")]
pub enum CameraMode {
    /// One framing of the whole range, still.
    Fixed,
    /// Turns about the figures at a steady pace (one turn per [`CameraOptions::orbit_bars`]).
    Orbit,
    /// Tracks the figures' centre on the ground, smoothed, at a steady distance.
    Follow,
    /// Cuts between shots on phrase starts.
    Director,
}

/// The director's shots.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "camelCase")]
pub enum Shot {
    Wide,
    Medium,
    Close,
    LowAngle,
}

impl Shot {
    /// (yaw magnitude, pitch, vertical field of view, fill): a wide shot from a little above
    /// with room around; medium from the side; close with a long lens filling the frame; low
    /// angle from below the hips looking up.
    fn lens(self) -> (f32, f32, f32, f32) {
        match self {
            Shot::Wide => (0.35, 0.24, 0.80, 0.72),
            Shot::Medium => (0.65, 0.12, 0.60, 0.86),
            Shot::Close => (0.20, 0.06, 0.36, 0.94),
            Shot::LowAngle => (0.45, -0.16, 0.70, 0.86),
        }
    }
}

/// Settings of [`plan`]. Fields left out of a JS object keep their default.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "camelCase", default, deny_unknown_fields)]
pub struct CameraOptions {
    pub mode: CameraMode,
    /// The frame's width over its height (16/9, 9/16, 1).
    pub aspect: f32,
    /// Bars per phrase for the director; 0 chooses: 8, or 4 when the range has fewer than
    /// [`SHORT_RANGE_BARS`] bars.
    pub phrase_bars: usize,
    /// The fewest bars between two cuts (a section change right after a cut waits).
    pub min_shot_bars: usize,
    /// A bar whose intensity differs from the previous bar's by at least this (0..=1) starts a
    /// phrase, as a section change does.
    pub intensity_jump: f32,
    /// A bar line whose section novelty is at least this (0..=1) starts a phrase.
    pub novelty_cut: f32,
    /// Bars per orbit turn.
    pub orbit_bars: f32,
    /// Seconds of the follow camera's moving average (centred).
    pub follow_smooth_secs: f32,
}

/// A range of fewer bars than this is short: phrases of 4 bars.
pub const SHORT_RANGE_BARS: usize = 24;

impl Default for CameraOptions {
    fn default() -> Self {
        Self {
            mode: CameraMode::Director,
            aspect: 16.0 / 9.0,
            phrase_bars: 0,
            min_shot_bars: 2,
            intensity_jump: 0.3,
            novelty_cut: 0.6,
            orbit_bars: 16.0,
            follow_smooth_secs: 1.0,
        }
    }
}

impl CameraOptions {
    fn validate(&self) -> Result<(), CameraError> {
        let bad = |what, value: f32| Err(CameraError::BadOption { what, value });
        if !(self.aspect.is_finite() && (0.1..=10.0).contains(&self.aspect)) {
            return bad("aspect", self.aspect);
        }
        if self.phrase_bars > 64 {
            return bad("phraseBars", self.phrase_bars as f32);
        }
        if self.min_shot_bars == 0 || self.min_shot_bars > 64 {
            return bad("minShotBars", self.min_shot_bars as f32);
        }
        for (what, v) in [("intensityJump", self.intensity_jump), ("noveltyCut", self.novelty_cut)] {
            if !(v.is_finite() && (0.0..=1.0).contains(&v)) {
                return bad(what, v);
            }
        }
        if !(self.orbit_bars.is_finite() && self.orbit_bars >= 1.0) {
            return bad("orbitBars", self.orbit_bars);
        }
        if !(self.follow_smooth_secs.is_finite() && (0.0..=30.0).contains(&self.follow_smooth_secs)) {
            return bad("followSmoothSecs", self.follow_smooth_secs);
        }
        Ok(())
    }
}

/// What the camera is planned over: per frame its time (song seconds) and the positions of
/// every figure's joints as drawn; the bars of the range (song bars, in order, with their
/// grid `index`), and the song's sections when it has them (indexed by grid bar).
pub struct CameraInput<'a> {
    pub times_secs: &'a [f32],
    pub joints: &'a [Vec<Vec3>],
    pub bars: &'a [Bar],
    pub sections: Option<&'a Sections>,
}

/// A cut of the director: from `frame` on, `shot`, starting at the range's bar `bar` (0 =
/// its first bar; the song's bar is `bars[bar].index`).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "camelCase")]
pub struct Cut {
    pub frame: usize,
    pub bar: usize,
    pub shot: Shot,
}

/// The camera of every frame, and the director's shots (one for the other modes' single
/// take: its first "cut" at frame 0 is the opening, not a change).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "camelCase")]
pub struct CameraPlan {
    pub poses: Vec<CameraPose>,
    pub shots: Vec<Cut>,
    /// Bars per phrase the director used.
    pub phrase_bars: usize,
}

/// Plans the camera for every frame of `input` (see the module's notes).
pub fn plan(input: &CameraInput, options: &CameraOptions) -> Result<CameraPlan, CameraError> {
    options.validate()?;
    validate_input(input)?;
    let phrase = effective_phrase_bars(input.bars.len(), options);
    let all = || input.joints.iter().flat_map(|f| f.iter().copied());
    let (lo, hi) = bounds(all());
    let centre = (lo + hi) * 0.5;
    let n = input.times_secs.len();
    let aspect = options.aspect;
    match options.mode {
        CameraMode::Fixed => {
            let (yaw, pitch, fov, fill) = (0.5, 0.2, 0.8, 0.8);
            let pose = fitted(all(), centre, yaw, pitch, fov, aspect, fill);
            Ok(CameraPlan { poses: vec![pose; n], shots: vec![Cut { frame: 0, bar: 0, shot: Shot::Wide }], phrase_bars: phrase })
        }
        CameraMode::Orbit => {
            let (pitch, fov, fill) = (0.2, 0.8, 0.8);
            // Every joint lies in the vertical cylinder of radius r about the centre's axis, so
            // in the box (±r across, ±r along the view, lo.y..hi.y) whatever the yaw: fitting
            // that box once holds for every frame of the turn.
            let r = all().map(|p| Vec3::new(p.x - centre.x, 0.0, p.z - centre.z).length()).fold(0.0f32, f32::max);
            let (back, right, _) = CameraPose::axes(0.0, pitch);
            let flat_back = Vec3::new(back.x, 0.0, back.z).normalize_or(Vec3::Z);
            let corners = (0..8).map(|k| {
                let a = if k & 1 == 0 { -r } else { r };
                let b = if k & 2 == 0 { -r } else { r };
                let y = if k & 4 == 0 { lo.y } else { hi.y };
                Vec3::new(centre.x, y, centre.z) + right * a + flat_back * b
            });
            let base = fitted(corners, centre, 0.0, pitch, fov, aspect, fill);
            let t0 = input.times_secs[0];
            let turn_secs = options.orbit_bars * mean_bar_secs(input);
            let yaw_at = |t: f32| 0.5 + std::f32::consts::TAU * (t - t0) / turn_secs;
            // The box holds at every yaw but is loose for a figure that travels; the yaw of
            // each frame is known, so the one steady distance is the largest any frame needs
            // at its own yaw (never more than the box's, and exact: every frame inside).
            let tight = (0..n)
                .map(|i| fit_distance(input.joints[i].iter().copied(), centre, yaw_at(input.times_secs[i]), base.pitch, fov, aspect, fill))
                .fold(MIN_DISTANCE_M, f32::max);
            let distance = if centre.y + fmath::sin(base.pitch) * tight >= MIN_EYE_HEIGHT_M { tight.min(base.distance) } else { base.distance };
            let poses = input.times_secs.iter().map(|&t| CameraPose { yaw: yaw_at(t), distance, ..base }).collect();
            Ok(CameraPlan { poses, shots: vec![Cut { frame: 0, bar: 0, shot: Shot::Wide }], phrase_bars: phrase })
        }
        CameraMode::Follow => {
            let (yaw, pitch, fov, fill) = (0.5, 0.2, 0.8, 0.8);
            // Each frame's centre on the ground, then a centred moving average of it.
            let centres: Vec<Vec3> = input.joints.iter().map(|f| { let (a, b) = bounds(f.iter().copied()); (a + b) * 0.5 }).collect();
            let dt = mean_frame_secs(input);
            let half = if dt > 0.0 { (options.follow_smooth_secs * 0.5 / dt).round() as usize } else { 0 };
            let targets: Vec<Vec3> = (0..n)
                .map(|i| {
                    let (a, b) = (i.saturating_sub(half), (i + half).min(n - 1));
                    let s = centres[a..=b].iter().fold(Vec3::ZERO, |s, c| s + *c) / (b - a + 1) as f32;
                    Vec3::new(s.x, centre.y, s.z)
                })
                .collect();
            // One distance for the whole take: the most any frame needs about its own target.
            let d = (0..n).map(|i| fit_distance(input.joints[i].iter().copied(), targets[i], yaw, pitch, fov, aspect, fill)).fold(MIN_DISTANCE_M, f32::max);
            let poses = targets.iter().map(|t| CameraPose { target: t.to_array(), yaw, pitch, distance: d, fov_y: fov }).collect();
            Ok(CameraPlan { poses, shots: vec![Cut { frame: 0, bar: 0, shot: Shot::Medium }], phrase_bars: phrase })
        }
        CameraMode::Director => director(input, options, phrase),
    }
}

fn validate_input(input: &CameraInput) -> Result<(), CameraError> {
    let n = input.times_secs.len();
    if n == 0 || input.joints.len() != n {
        return Err(CameraError::NoFrames);
    }
    let want = input.joints[0].len();
    if want == 0 {
        return Err(CameraError::NoFrames);
    }
    let mut prev = f32::NEG_INFINITY;
    for (frame, (&t, f)) in input.times_secs.iter().zip(input.joints).enumerate() {
        if !t.is_finite() || t < prev {
            return Err(CameraError::BadTime { frame, time_secs: t });
        }
        prev = t;
        if f.len() != want {
            return Err(CameraError::JointCount { frame, got: f.len(), want });
        }
        if let Some((joint, p)) = f.iter().enumerate().find(|(_, p)| !p.is_finite()) {
            return Err(CameraError::BadJoint { frame, joint, value: p.to_array() });
        }
    }
    let mut end = f32::NEG_INFINITY;
    for b in input.bars {
        if !(b.start_secs.is_finite() && b.end_secs.is_finite() && b.end_secs > b.start_secs && b.start_secs >= end - 1e-3) {
            return Err(CameraError::BadBar { index: b.index, start_secs: b.start_secs, end_secs: b.end_secs });
        }
        end = b.end_secs;
    }
    Ok(())
}

/// Bars per phrase: the option, or 8 (4 for a short range).
pub fn effective_phrase_bars(range_bars: usize, options: &CameraOptions) -> usize {
    match options.phrase_bars {
        0 if range_bars < SHORT_RANGE_BARS => 4,
        0 => 8,
        p => p,
    }
}

fn bounds(points: impl Iterator<Item = Vec3>) -> (Vec3, Vec3) {
    let (lo, hi) = points.fold((Vec3::splat(f32::MAX), Vec3::splat(f32::MIN)), |(l, h), p| (l.min(p), h.max(p)));
    if lo.x > hi.x { (Vec3::ZERO, Vec3::ZERO) } else { (lo, hi) }
}

fn mean_frame_secs(input: &CameraInput) -> f32 {
    let n = input.times_secs.len();
    if n < 2 { 0.0 } else { (input.times_secs[n - 1] - input.times_secs[0]) / (n - 1) as f32 }
}

fn mean_bar_secs(input: &CameraInput) -> f32 {
    let b = input.bars;
    if b.is_empty() { 2.0 } else { ((b[b.len() - 1].end_secs - b[0].start_secs) / b.len() as f32).max(0.1) }
}

/// A pose looking at `target`, its distance fitted to `points`; the pitch raised when the
/// eye would go under the floor.
fn fitted(points: impl Iterator<Item = Vec3> + Clone, target: Vec3, yaw: f32, pitch: f32, fov_y: f32, aspect: f32, fill: f32) -> CameraPose {
    let mut pitch = pitch;
    let mut d = fit_distance(points.clone(), target, yaw, pitch, fov_y, aspect, fill);
    for _ in 0..4 {
        let eye_y = target.y + fmath::sin(pitch) * d;
        if eye_y >= MIN_EYE_HEIGHT_M {
            break;
        }
        pitch = fmath::asin(((MIN_EYE_HEIGHT_M - target.y) / d).clamp(-1.0, 1.0)) + 0.01;
        d = fit_distance(points.clone(), target, yaw, pitch, fov_y, aspect, fill);
    }
    CameraPose { target: target.to_array(), yaw, pitch, distance: d, fov_y }
}

/// The range's phrase starts (indices into `input.bars`, increasing, 0 first): every
/// `phrase` bars, the count starting again at a section change (at least `min_shot_bars`
/// after the last start), or at a bar line of novelty at least `novelty_cut` or an intensity
/// jump (at least half a phrase after it).
pub fn phrase_starts(bars: &[Bar], sections: Option<&Sections>, phrase: usize, options: &CameraOptions) -> Vec<usize> {
    let mut starts = vec![0usize];
    if bars.is_empty() {
        return vec![];
    }
    let boundaries: Vec<usize> = sections.map(|s| s.boundaries()).unwrap_or_default();
    let mut last = 0usize;
    for i in 1..bars.len() {
        let song_bar = bars[i].index;
        let section_change = boundaries.contains(&song_bar);
        let novel = sections.and_then(|s| s.novelty.get(song_bar)).is_some_and(|&v| v >= options.novelty_cut);
        let jump = (bars[i].intensity - bars[i - 1].intensity).abs() >= options.intensity_jump;
        let since = i - last;
        // A section change may cut after `min_shot_bars`; a lesser change (a novelty peak
        // inside a section, a jump in loudness) only after half a phrase, so a busy song is
        // not cut every other bar.
        let early = (section_change && since >= options.min_shot_bars) || ((novel || jump) && since >= (phrase / 2).max(options.min_shot_bars));
        if since >= phrase || early {
            starts.push(i);
            last = i;
        }
    }
    starts
}

/// The shot a phrase starting at range bar `bar` takes: by the bar's intensity (loud: wide
/// and low; quiet: close and medium), turned by the section's label and the phrase's place
/// so repeats look alike and consecutive shots differ.
fn choose_shot(bars: &[Bar], bar: usize, sections: Option<&Sections>, k: usize, previous: Option<Shot>) -> Shot {
    let intensity = bars[bar].intensity;
    let order: &[Shot] = if intensity >= 0.66 {
        &[Shot::Wide, Shot::LowAngle, Shot::Medium, Shot::Close]
    } else if intensity >= 0.33 {
        &[Shot::Medium, Shot::LowAngle, Shot::Wide, Shot::Close]
    } else {
        &[Shot::Close, Shot::Medium, Shot::Wide, Shot::LowAngle]
    };
    let label = sections
        .and_then(|s| s.sections.iter().find(|x| x.first_bar <= bars[bar].index && bars[bar].index < x.end_bar()))
        .map_or(0, |s| s.label as usize);
    // Repeats (same label) start alike; within a section, the phrases walk the preferences.
    let first = if k == 0 { 0 } else { (label + k) % 2 };
    (0..order.len()).map(|j| order[(first + j) % order.len()]).find(|s| Some(*s) != previous).unwrap_or(Shot::Wide)
}

fn director(input: &CameraInput, options: &CameraOptions, phrase: usize) -> Result<CameraPlan, CameraError> {
    let n = input.times_secs.len();
    let starts = phrase_starts(input.bars, input.sections, phrase, options);
    // Each phrase start's first frame: the first frame at or after its bar line (a frame is
    // at `times_secs`; a cut lands exactly on the bar line when a frame does).
    let frame_at = |t: f32| input.times_secs.partition_point(|&x| x < t - 1e-4);
    let mut cuts: Vec<Cut> = Vec::new();
    let mut previous = None;
    for (k, &b) in starts.iter().enumerate() {
        let frame = if k == 0 { 0 } else { frame_at(input.bars[b].start_secs) };
        if frame >= n || cuts.last().is_some_and(|c| c.frame == frame) {
            continue;
        }
        let shot = choose_shot(input.bars, b, input.sections, k, previous);
        previous = Some(shot);
        cuts.push(Cut { frame, bar: b, shot });
    }
    if cuts.is_empty() {
        cuts.push(Cut { frame: 0, bar: 0, shot: Shot::Wide });
    }
    let mut poses = Vec::with_capacity(n);
    for (k, c) in cuts.iter().enumerate() {
        let end = cuts.get(k + 1).map_or(n, |x| x.frame);
        let span = &input.joints[c.frame..end];
        let points = || span.iter().flat_map(|f| f.iter().copied());
        let (lo, hi) = bounds(points());
        let (yaw_mag, pitch, fov, fill) = c.shot.lens();
        // Alternate sides shot by shot, so two shots in a row are never mirror-equal.
        let yaw = if k % 2 == 0 { yaw_mag } else { -yaw_mag };
        let pose = fitted(points(), (lo + hi) * 0.5, yaw, pitch, fov, options.aspect, fill);
        poses.extend(std::iter::repeat_n(pose, end - c.frame));
    }
    Ok(CameraPlan { poses, shots: cuts, phrase_bars: phrase })
}

pub mod mmd;

#[cfg(test)]
mod tests;
