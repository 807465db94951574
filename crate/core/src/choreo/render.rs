//! The dance as one canonical clip, in sync with the song (the count before the first bar
//! plays the first segment's lead-in, held still before that): each bar's segment is warped in
//! time onto the bar, piecewise-linearly between its counts so count k of its n plays at k/n of
//! the bar (the bar's beats when n is the bar's metre, spec §E; [`super::segment`]), placed so it starts where (and facing the way) the previous one
//! ended, and consecutive segments are joined by rewriting the last 5 frames of the earlier and
//! the first 5 of the later one with a cubic Hermite curve between the untouched poses on
//! either side (positions and velocities matched), so no time is added and every bar stays on
//! its beat (spec §G). Frame 0 is song time 0.

use std::sync::Arc;

use glam::{Quat, Vec3};
use serde::{Deserialize, Serialize};

use super::segment::{SegmentLibrary, LIBRARY_FPS};
use crate::bars::Bar;
use crate::builtin::canonical_skeleton;
use crate::clip::{Clip, TranslationTrack};
use crate::humanoid::{canonical_positions, HumanoidMap, CANON_COUNT};
use crate::library::neutral_pose;

/// How to render.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "camelCase", default)]
pub struct RenderOptions {
    /// Output frame rate.
    pub fps: f32,
    /// Frames rewritten on each side of a join (spec: 5); 0 turns joins off.
    pub join_frames: usize,
}

impl Default for RenderOptions {
    fn default() -> Self {
        Self { fps: 60.0, join_frames: 5 }
    }
}

/// Yaw (about +Y) of a root rotation's forward (+Z) direction.
fn yaw_of(q: Quat) -> f32 {
    let f = q * Vec3::Z;
    f.x.atan2(f.z)
}

/// Samples segment `seg` at `u` in 0..=1 of its length (or up to a count before it, −¼..0,
/// [`super::Segment::frame_before`]): local rotations and root translation.
fn sample_segment(lib: &SegmentLibrary, seg: usize, u: f32, rot: &mut Vec<Quat>, trans: &mut Vec<Vec3>) -> Option<(Vec3, Quat)> {
    let s = lib.segment(seg)?;
    let lc = lib.clips().get(s.clip)?;
    // Piecewise-linear between the segment's counts, so each count lands on the bar's beat.
    let frame = s.frame_before(u);
    lc.clip.sample_into(frame / LIBRARY_FPS, rot, trans);
    let root_t = trans.first().copied().unwrap_or(Vec3::ZERO);
    let root_q = rot.first().copied().unwrap_or(Quat::IDENTITY);
    Some((root_t, root_q))
}

/// One segment played over `duration_secs` at `fps`, starting at the origin facing +Z: what a
/// candidate view plays in sync with its bar.
pub fn segment_clip(lib: &SegmentLibrary, seg: usize, duration_secs: f32, fps: f32) -> Option<Clip> {
    let beats = lib.segment(seg).map_or(4, |s| s.counts() as u32);
    let bar = Bar { index: 0, start_secs: 0.0, end_secs: duration_secs.max(1e-3), intensity: 0.5, beats };
    let mut clip = render(lib, &[bar], &[Some(seg)], &RenderOptions { fps, join_frames: 0 });
    clip.name = lib.segment(seg)?.name.clone();
    Some(clip)
}

/// Renders one segment (or `None`: a neutral stance) per bar. Bars are taken in order;
/// `choices` shorter than `bars` leaves the rest neutral.
pub fn render(lib: &SegmentLibrary, bars: &[Bar], choices: &[Option<usize>], options: &RenderOptions) -> Clip {
    let fps = if options.fps.is_finite() && options.fps > 0.0 { options.fps } else { 60.0 };
    let skeleton = Arc::new(canonical_skeleton());
    let end_secs = bars.iter().map(|b| b.end_secs).fold(0.0f32, f32::max);
    let frames = ((end_secs * fps).ceil() as usize + 1).max(1);
    let (neutral_rot, neutral_root) = neutral_pose();
    let mut rotations = Vec::with_capacity(frames * CANON_COUNT);
    let mut roots = Vec::with_capacity(frames);
    let mut rot = Vec::with_capacity(CANON_COUNT);
    let mut trans = Vec::with_capacity(CANON_COUNT);
    // Placement: where the previous bar ended (ground position) and its facing.
    let mut place_pos = Vec3::ZERO;
    let mut place_yaw = 0.0f32;
    let mut boundaries = Vec::new();
    let mut bar_i = 0usize;
    // Current bar's transform: source start (ground) and yaw offset.
    let mut xf: Option<(usize, Vec3, f32)> = None; // (bar index, source start ground pos, yaw delta)
    // The lead-in's placement: the first segment's start (ground position) and yaw offset.
    let mut lead_in_placement: Option<(Vec3, f32)> = None;
    for f in 0..frames {
        let t = f as f32 / fps;
        while bar_i + 1 < bars.len() && t >= bars[bar_i + 1].start_secs {
            bar_i += 1;
        }
        let bar = bars.get(bar_i);
        let (u, seg) = match bar {
            Some(b) if t >= b.start_secs => {
                let d = b.duration_secs().max(1e-6);
                (((t - b.start_secs) / d).clamp(0.0, 1.0), choices.get(bar_i).copied().flatten())
            }
            // Before the first bar: the count that leads into its segment (its clip's own frames
            // before it, at the bar's pace), held still before that. A dancer who starts from
            // rest on the one cannot turn on it (§J's kinetic beat is a slowing then a speeding
            // up); with the lead-in the first count is a turn like every other.
            Some(b) => {
                let d = b.duration_secs().max(1e-6);
                let first = choices.first().copied().flatten();
                let counts = first.and_then(|s| lib.segment(s)).map_or(super::segment::SEGMENT_COUNTS, |s| s.counts());
                (((t - b.start_secs) / d).max(-1.0 / counts as f32), first)
            }
            None => (0.0, None),
        };
        let in_bar = bar.is_some_and(|b| t >= b.start_secs);
        if in_bar && xf.as_ref().is_none_or(|x| x.0 != bar_i) {
            // Entering a new bar: close the previous one's placement.
            if let Some((prev_bar, _, _)) = xf {
                if let Some(prev_seg) = choices.get(prev_bar).copied().flatten() {
                    if let Some((rt, rq)) = sample_segment(lib, prev_seg, 1.0, &mut rot, &mut trans) {
                        let (start, dyaw) = (xf.map(|x| x.1).unwrap_or(Vec3::ZERO), xf.map(|x| x.2).unwrap_or(0.0));
                        let q = Quat::from_rotation_y(dyaw);
                        let g = Vec3::new(rt.x - start.x, 0.0, rt.z - start.z);
                        place_pos += q * g;
                        place_yaw = yaw_of(q * rq);
                    }
                }
                boundaries.push(f);
            }
            let (start, dyaw) = match seg.and_then(|s| sample_segment(lib, s, 0.0, &mut rot, &mut trans)) {
                Some((rt, rq)) => (Vec3::new(rt.x, 0.0, rt.z), place_yaw - yaw_of(rq)),
                None => (Vec3::ZERO, 0.0),
            };
            xf = Some((bar_i, start, dyaw));
        }
        let sampled = seg.and_then(|s| sample_segment(lib, s, u, &mut rot, &mut trans));
        match (sampled, xf) {
            (Some((rt, _)), Some((_, start, dyaw))) => {
                let q = Quat::from_rotation_y(dyaw);
                if let Some(r0) = rot.first_mut() {
                    *r0 = (q * *r0).normalize();
                }
                let g = q * Vec3::new(rt.x - start.x, 0.0, rt.z - start.z);
                rotations.extend_from_slice(&rot);
                roots.push(Vec3::new(place_pos.x + g.x, rt.y, place_pos.z + g.z));
            }
            (Some((rt, _)), None) => {
                // Before the first bar: its lead-in, placed as the first bar will place its
                // segment (its first pose at the origin, facing +Z), so it runs on without a seam.
                let (start, yaw) = lead_in_placement.get_or_insert_with(|| {
                    let mut r = Vec::new();
                    let mut tr = Vec::new();
                    match seg.and_then(|s| sample_segment(lib, s, 0.0, &mut r, &mut tr)) {
                        Some((t0, q0)) => (Vec3::new(t0.x, 0.0, t0.z), -yaw_of(q0)),
                        None => (Vec3::ZERO, 0.0),
                    }
                });
                let q = Quat::from_rotation_y(*yaw);
                if let Some(r0) = rot.first_mut() {
                    *r0 = (q * *r0).normalize();
                }
                let g = q * Vec3::new(rt.x - start.x, 0.0, rt.z - start.z);
                rotations.extend_from_slice(&rot);
                roots.push(Vec3::new(g.x, rt.y, g.z));
            }
            _ => {
                let q = Quat::from_rotation_y(place_yaw);
                let mut r = neutral_rot.clone();
                if let Some(r0) = r.first_mut() {
                    *r0 = (q * *r0).normalize();
                }
                rotations.extend_from_slice(&r);
                roots.push(Vec3::new(place_pos.x, neutral_root.y, place_pos.z));
            }
        }
    }
    if options.join_frames > 0 {
        for &j in &boundaries {
            join_at(&mut rotations, &mut roots, j, options.join_frames);
        }
    }
    Clip {
        name: "Choreography".into(),
        source: "choreography".into(),
        fps,
        skeleton,
        rotations,
        translations: vec![TranslationTrack { joint: 0, values: roots }],
    }
}

/// Rewrites frames `j - n .. j + n` by cubic Hermite interpolation between frame `j - n - 1`
/// and frame `j + n`, with the velocities of the untouched frames outside.
fn join_at(rotations: &mut [Quat], roots: &mut [Vec3], j: usize, n: usize) {
    let frames = roots.len();
    if j < n + 2 || j + n + 1 >= frames {
        return;
    }
    let a = j - n - 1; // last untouched frame before
    let b = j + n; // first untouched frame after
    let span = (b - a) as f32;
    let v4 = |q: Quat| [q.x, q.y, q.z, q.w];
    for joint in 0..CANON_COUNT {
        let q = |f: usize| rotations[f * CANON_COUNT + joint];
        // Sign-align everything to the pose before the join.
        let align = |x: Quat, to: Quat| if x.dot(to) < 0.0 { -x } else { x };
        let qa = q(a);
        let qa0 = align(q(a - 1), qa);
        let qb = align(q(b), qa);
        let qb1 = align(q(b + 1), qb);
        let m0: [f32; 4] = std::array::from_fn(|i| (v4(qa)[i] - v4(qa0)[i]) * span);
        let m1: [f32; 4] = std::array::from_fn(|i| (v4(qb1)[i] - v4(qb)[i]) * span);
        for f in a + 1..b {
            let s = (f - a) as f32 / span;
            let h = crate::motion::hermite(v4(qa), m0, v4(qb), m1, s);
            rotations[f * CANON_COUNT + joint] = Quat::from_array(h).normalize();
        }
    }
    let pa = roots[a];
    let pb = roots[b];
    let m0 = (pa - roots[a - 1]) * span;
    let m1 = (roots[b + 1] - pb) * span;
    for f in a + 1..b {
        let s = (f - a) as f32 / span;
        let h = crate::motion::hermite([pa.x, pa.y, pa.z, 0.0], [m0.x, m0.y, m0.z, 0.0], [pb.x, pb.y, pb.z, 0.0], [m1.x, m1.y, m1.z, 0.0], s);
        roots[f] = Vec3::new(h[0], h[1], h[2]);
    }
}

/// Joint-speed jump per frame of a clip on the canonical skeleton, m/s: for frame f, the mean
/// over joints of |v(f) − v(f−1)| with v(f) the velocity from f to f+1, positions taken
/// relative to the hips (so placement does not count). Frame 0 and the last frame get 0.
pub fn speed_jumps(clip: &Clip) -> Vec<f32> {
    let pos = canonical_positions(clip, &HumanoidMap::from_skeleton(&clip.skeleton));
    let frames = pos.len() / CANON_COUNT;
    let rel = |f: usize, j: usize| pos[f * CANON_COUNT + j] - pos[f * CANON_COUNT];
    let mut out = vec![0.0; frames];
    for f in 1..frames.saturating_sub(1) {
        let mut s = 0.0;
        for j in 1..CANON_COUNT {
            let v0 = rel(f, j) - rel(f - 1, j);
            let v1 = rel(f + 1, j) - rel(f, j);
            s += (v1 - v0).length();
        }
        out[f] = s / (CANON_COUNT - 1) as f32 * clip.fps;
    }
    out
}

/// First frame of each bar after the first (where joins are) for bars rendered at `fps`.
pub fn join_frames(bars: &[Bar], fps: f32) -> Vec<usize> {
    bars.iter().skip(1).map(|b| (b.start_secs * fps).ceil() as usize).collect()
}
