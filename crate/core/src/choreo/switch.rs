//! Join points within a count of the bar line (issue 26 item 1): where the render
//! ([`super::render`]) switches from one bar's move to the next's. On the bar line by default;
//! with [`super::RenderOptions::join_points`] each join may switch up to a count earlier (the
//! incoming move played from before its start: its clip's frames before the segment) or later
//! (the outgoing move played past its end), each move still warped as in its own bar so its
//! counts land on the beats, at the offset of [`OFFSET_COUNTS`] where the two motions agree
//! best: the least abrupt blend, judged on the frames there with the inertialized join applied
//! (the largest joint acceleration over the blend, what spec §J's join jump measures). An offset
//! needs the clip's frames there, so a move cut at its clip's start or end (every built-in move,
//! one bar a clip) switches on the bar line.

use crate::fmath;
use glam::{Quat, Vec3};

use super::render::inertialize_at;
use super::segment::{Segment, SegmentLibrary, LIBRARY_FPS};
use crate::bars::Bar;
use crate::canon::humanoid::{canonical_positions, HumanoidMap, CANON_COUNT};
use crate::clip::{Clip, TranslationTrack};

/// The candidate switch offsets, in counts from the bar line (negative: earlier).
pub const OFFSET_COUNTS: [f32; 4] = [-1.0, -0.5, 0.5, 1.0];

/// An offset is taken only when its blend's largest acceleration is below this fraction of the
/// bar line's (so a join switches off the bar line only for a clear gain).
pub const OFFSET_GAIN: f32 = 0.95;

/// Frames before the switch in a candidate's window: 3 carry the outgoing motion into the
/// blend ([`inertialize_at`]), and §J looks 3 frames (at 30 fps) either side of a join.
const PRE_FRAMES: usize = 6;

/// Where bar i's move is placed in the dance: the ground position the render has reached when
/// the bar starts, the source's ground point at the move's start, and the yaw turning the
/// source's facing onto the dance's.
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct Placement {
    pub pos: Vec3,
    pub start: Vec3,
    pub dyaw: f32,
}

/// Yaw (about +Y) of a root rotation's forward (+Z) direction.
pub(super) fn yaw_of(q: Quat) -> f32 {
    let f = q * Vec3::Z;
    fmath::atan2(f.x, f.z)
}

/// The clip frame (at [`LIBRARY_FPS`]) segment `s` plays at `u` of its bar: within the bar
/// [`Segment::frame_at`], up to a count before it [`Segment::frame_before`], and past its end at
/// its last count's pace (so the counts after it keep landing a count apart).
pub(super) fn played_frame(s: &Segment, u: f32) -> f32 {
    if u < 0.0 {
        return (s.start_frame + u * s.counts() as f32 * first_count_frames(s)).max(0.0);
    }
    if u <= 1.0 {
        return s.frame_at(u);
    }
    let n = s.counts();
    let c = &s.count_frames;
    let last = if c.len() == n + 1 && c[n] > c[n - 1] { c[n] - c[n - 1] } else { (s.end_frame - s.start_frame) / n as f32 };
    s.end_frame + (u - 1.0) * n as f32 * last
}

/// Whether segment `s`'s clip (of `clip_frames` frames at [`LIBRARY_FPS`]) holds the frame it
/// plays at `u` (no clamping at its ends).
fn has_frame(s: &Segment, clip_frames: usize, u: f32) -> bool {
    let last = clip_frames.saturating_sub(1) as f32;
    if u >= 0.0 {
        return played_frame(s, u) <= last;
    }
    s.start_frame + u * s.counts() as f32 * first_count_frames(s) >= 0.0
}

/// Clip frames (at [`LIBRARY_FPS`]) of segment `s`'s first count: the pace it plays at before
/// its start.
fn first_count_frames(s: &Segment) -> f32 {
    let c = &s.count_frames;
    if c.len() >= 2 && c[1] > c[0] { c[1] - c[0] } else { (s.end_frame - s.start_frame) / s.counts() as f32 }
}

/// Samples segment `seg` at `u` of its bar (local rotations, root translation).
pub(super) fn sample(lib: &SegmentLibrary, seg: usize, u: f32, rot: &mut Vec<Quat>, trans: &mut Vec<Vec3>) -> Option<(Vec3, Quat)> {
    let s = lib.segment(seg)?;
    let lc = lib.clips().get(s.clip)?;
    lc.clip.sample_into(played_frame(s, u) / LIBRARY_FPS, rot, trans);
    Some((trans.first().copied().unwrap_or(Vec3::ZERO), rot.first().copied().unwrap_or(Quat::IDENTITY)))
}

/// Each bar's [`Placement`], as the render chains them: every bar starts where (and facing the
/// way) the previous one's move ended.
pub(super) fn placements(lib: &SegmentLibrary, bars: &[Bar], choices: &[Option<usize>]) -> Vec<Placement> {
    let (mut rot, mut trans) = (Vec::new(), Vec::new());
    let (mut pos, mut yaw) = (Vec3::ZERO, 0.0f32);
    let mut out: Vec<Placement> = Vec::with_capacity(bars.len());
    for i in 0..bars.len() {
        if let (Some(prev), Some(Some(ps))) = (out.last().copied(), i.checked_sub(1).and_then(|k| choices.get(k))) {
            if let Some((rt, rq)) = sample(lib, *ps, 1.0, &mut rot, &mut trans) {
                let q = Quat::from_rotation_y(prev.dyaw);
                pos += q * Vec3::new(rt.x - prev.start.x, 0.0, rt.z - prev.start.z);
                yaw = yaw_of(q * rq);
            }
        }
        let (start, dyaw) = match choices.get(i).copied().flatten().and_then(|s| sample(lib, s, 0.0, &mut rot, &mut trans)) {
            Some((rt, rq)) => (Vec3::new(rt.x, 0.0, rt.z), yaw - yaw_of(rq)),
            None => (Vec3::ZERO, 0.0),
        };
        out.push(Placement { pos, start, dyaw });
    }
    out
}

/// The pose of segment `seg` at `u` of its bar placed by `p`: local rotations (the root's turned
/// onto the dance's facing) into `rot`, and the root's position.
pub(super) fn placed(lib: &SegmentLibrary, seg: usize, u: f32, p: &Placement, rot: &mut Vec<Quat>, trans: &mut Vec<Vec3>) -> Option<Vec3> {
    let (rt, _) = sample(lib, seg, u, rot, trans)?;
    let q = Quat::from_rotation_y(p.dyaw);
    if let Some(r0) = rot.first_mut() {
        *r0 = (q * *r0).normalize();
    }
    let g = q * Vec3::new(rt.x - p.start.x, 0.0, rt.z - p.start.z);
    Some(Vec3::new(p.pos.x + g.x, rt.y, p.pos.z + g.z))
}

/// Where in its bar the move of bar `k` is at song time `t` (outside 0..=1 before or after it).
fn bar_u(bars: &[Bar], k: usize, t: f32) -> f32 {
    let b = &bars[k];
    (t - b.start_secs) / b.duration_secs().max(1e-6)
}

/// The bar whose move song time `t` plays instead of bar `bar_i`'s (the bar it falls in), with
/// `u` in that move's bar, when a switch off the bar line moves it there: before bar i + 1's
/// switch when that is early, or before bar i's own when that is late.
pub(super) fn played_instead(bars: &[Bar], switches: &[f32], bar_i: usize, t: f32) -> Option<(usize, f32)> {
    if let Some(&sw) = switches.get(bar_i) {
        // The switch into bar i + 1.
        if bar_i + 1 < bars.len() && sw < bars[bar_i + 1].start_secs && t >= sw {
            return Some((bar_i + 1, bar_u(bars, bar_i + 1, t)));
        }
    }
    if let Some(&sw) = bar_i.checked_sub(1).and_then(|k| switches.get(k)) {
        if sw > bars[bar_i].start_secs && t < sw {
            return Some((bar_i - 1, bar_u(bars, bar_i - 1, t)));
        }
    }
    None
}

/// The largest joint acceleration (canonical positions, per frame²) over the blend of a switch
/// from segment `a` (bar `i − 1`, placed by `pa`) to `b` (bar `i`, `pb`) at song time `at`,
/// frames at `fps`, blended over `span` frames; `None` when a frame cannot be sampled.
#[allow(clippy::too_many_arguments)]
fn blend_peak(lib: &SegmentLibrary, bars: &[Bar], i: usize, (a, pa): (usize, &Placement), (b, pb): (usize, &Placement), at: f32, fps: f32, span: usize, map: &HumanoidMap, skeleton: &std::sync::Arc<crate::skeleton::Skeleton>) -> Option<f32> {
    let j = (at * fps).ceil().max(PRE_FRAMES as f32) as usize;
    let frames = PRE_FRAMES + span + 2;
    let (mut rot, mut trans) = (Vec::new(), Vec::new());
    let mut rotations = Vec::with_capacity(frames * CANON_COUNT);
    let mut roots = Vec::with_capacity(frames);
    for k in 0..frames {
        let f = j + k - PRE_FRAMES;
        let t = f as f32 / fps;
        let root = if f < j { placed(lib, a, bar_u(bars, i - 1, t), pa, &mut rot, &mut trans)? } else { placed(lib, b, bar_u(bars, i, t), pb, &mut rot, &mut trans)? };
        if rot.len() != CANON_COUNT {
            return None;
        }
        rotations.extend_from_slice(&rot);
        roots.push(root);
    }
    inertialize_at(&mut rotations, &mut roots, PRE_FRAMES, span);
    let clip = Clip { name: String::new(), source: String::new(), fps, skeleton: skeleton.clone(), rotations, translations: vec![TranslationTrack { joint: 0, values: roots }] };
    let pos = canonical_positions(&clip, map);
    let n = pos.len() / CANON_COUNT;
    let x = |f: usize, c: usize| pos[f * CANON_COUNT + c];
    let mut peak = 0.0f32;
    for f in 1..n.saturating_sub(1) {
        for c in 0..CANON_COUNT {
            peak = peak.max((x(f + 1, c) - 2.0 * x(f, c) + x(f - 1, c)).length());
        }
    }
    peak.is_finite().then_some(peak)
}

/// The song time of each join's switch (one per bar after the first): the bar line, or the
/// offset of [`OFFSET_COUNTS`] (a count being the shorter of the two bars') whose blend is least
/// abrupt ([`blend_peak`]) when it beats the bar line's by [`OFFSET_GAIN`] and both clips hold
/// the frames it plays. `blend_frames`: the inertialized join's span at `fps`.
pub(super) fn choose_switches(lib: &SegmentLibrary, bars: &[Bar], choices: &[Option<usize>], places: &[Placement], fps: f32, blend_frames: usize) -> Vec<f32> {
    let skeleton = std::sync::Arc::new(crate::canon::builtin::canonical_skeleton());
    let map = HumanoidMap::from_skeleton(&skeleton);
    let mut out = Vec::with_capacity(bars.len().saturating_sub(1));
    for i in 1..bars.len() {
        let line = bars[i].start_secs;
        let pair = (choices.get(i - 1).copied().flatten(), choices.get(i).copied().flatten());
        let (Some(a), Some(b)) = pair else {
            out.push(line);
            continue;
        };
        let (Some(sa), Some(sb), Some(pa), Some(pb)) = (lib.segment(a), lib.segment(b), places.get(i - 1), places.get(i)) else {
            out.push(line);
            continue;
        };
        let frames_of = |s: &Segment| lib.clips().get(s.clip).map_or(0, |c| ((c.clip.duration_secs() * LIBRARY_FPS).floor() as usize) + 1);
        let (fa, fb) = (frames_of(sa), frames_of(sb));
        let (ba, bb) = (&bars[i - 1], &bars[i]);
        let count = (ba.duration_secs() / ba.beat_count().max(1) as f32).min(bb.duration_secs() / bb.beat_count().max(1) as f32);
        // The blend ends before the next bar's switch could start.
        let until_next = bars.get(i + 1).map_or(usize::MAX, |n| ((n.start_secs - count - line) * fps).floor().max(2.0) as usize);
        let span = blend_frames.min(until_next).max(2);
        let peak = |at: f32| blend_peak(lib, bars, i, (a, pa), (b, pb), at, fps, span, &map, &skeleton);
        let Some(on_line) = peak(line) else {
            out.push(line);
            continue;
        };
        let mut best = (on_line * OFFSET_GAIN, line);
        for k in OFFSET_COUNTS {
            let at = line + k * count;
            // The frames the offset plays: the incoming move from `at` (before its start), or
            // the outgoing one up to `at` (past its end), a frame's margin either way.
            let margin = 2.0 / fps;
            let ok = if k < 0.0 { has_frame(sb, fb, bar_u(bars, i, at - margin)) } else { has_frame(sa, fa, bar_u(bars, i - 1, at + margin)) };
            if !ok {
                continue;
            }
            if let Some(p) = peak(at).filter(|&p| p < best.0) {
                best = (p, at);
            }
        }
        out.push(best.1);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::choreo::grid::bars_from_tempo;
    use crate::choreo::render::{render_switched, RenderOptions};

    #[test]
    fn a_move_played_beyond_its_segment_keeps_its_counts_a_count_apart() {
        let lib = crate::choreo::segment::tests::small_library_with_an_imported_clip();
        for s in lib.segments().iter().filter(|s| s.builtin.is_none() && s.count_frames.len() == s.counts() + 1) {
            let n = s.counts();
            let c = &s.count_frames;
            let after = played_frame(s, 1.0 + 1.0 / n as f32);
            assert!((after - (s.end_frame + c[n] - c[n - 1])).abs() < 1e-3, "{after} {c:?}");
            let before = played_frame(s, -1.0 / n as f32);
            assert!((before - (s.start_frame - (c[1] - c[0])).max(0.0)).abs() < 1e-3, "{before} {c:?}");
            assert_eq!(played_frame(s, 0.5), s.frame_at(0.5));
        }
    }

    #[test]
    fn joins_switch_within_a_count_of_the_bar_line_and_the_bars_keep_their_beat() {
        let lib = crate::choreo::segment::tests::small_library_with_an_imported_clip();
        let imported: Vec<usize> = lib.segments().iter().filter(|s| s.builtin.is_none() && s.counts() == 4).map(|s| s.index).collect();
        let builtin: Vec<usize> = lib.segments().iter().filter(|s| s.builtin.is_some()).map(|s| s.index).collect();
        assert!(imported.len() >= 2 && builtin.len() >= 2, "{imported:?} {builtin:?}");
        let bars = bars_from_tempo(16.0, 120.0, 4, 0.0, |_, _| 0.5).unwrap();
        // Imported moves (frames on either side of most segments) and built-in ones (none).
        let pick = [imported[1], imported[0], builtin[0], builtin[1], imported[1], imported[imported.len() - 1], builtin[0], imported[1]];
        let choices: Vec<Option<usize>> = (0..bars.len()).map(|i| Some(pick[i % pick.len()])).collect();
        let off = RenderOptions { hold_feet: false, ..RenderOptions::default() };
        let on = RenderOptions { join_points: true, ..off };
        let (plain, line) = render_switched(&lib, &bars, &choices, &off);
        assert_eq!(line, bars.iter().skip(1).map(|b| b.start_secs).collect::<Vec<_>>(), "off: every switch on the bar line");
        let (joined, switches) = render_switched(&lib, &bars, &choices, &on);
        assert_eq!(switches.len(), bars.len() - 1);
        assert_eq!(joined.frame_count(), plain.frame_count(), "no time added");
        let fps = joined.fps;
        for (k, &sw) in switches.iter().enumerate() {
            let (a, b) = (&bars[k], &bars[k + 1]);
            let count = (a.duration_secs() / a.beat_count() as f32).min(b.duration_secs() / b.beat_count() as f32);
            assert!((sw - b.start_secs).abs() <= count + 1e-4, "join {k}: switch {sw} off {}", b.start_secs);
            let (sa, sb) = (lib.segment(choices[k].unwrap()).unwrap(), lib.segment(choices[k + 1].unwrap()).unwrap());
            // A built-in move is its whole clip: nothing before it to start early on, nothing
            // after it to end late on.
            if sb.builtin.is_some() {
                assert!(sw >= b.start_secs, "join {k} starts a built-in move early");
            }
            if sa.builtin.is_some() {
                assert!(sw <= b.start_secs, "join {k} plays a built-in move past its end");
            }
        }
        println!("switches off the bar line: {:?}", switches.iter().zip(&bars[1..]).map(|(s, b)| s - b.start_secs).collect::<Vec<_>>());
        // Away from every switch and its blend, the dance is the bar-line one frame for frame:
        // each move plays where it did, on its beats.
        let reach = 0.5 + INERTIAL_BLEND + 2.0 / fps;
        let mut same = 0;
        for f in 0..joined.frame_count() {
            let t = f as f32 / fps;
            if bars.iter().skip(1).any(|b| (t - b.start_secs).abs() <= reach) {
                continue;
            }
            assert_eq!(joined.frame_rotations(f), plain.frame_rotations(f), "frame {f} ({t:.3} s)");
            same += 1;
        }
        assert!(same > joined.frame_count() / 4, "{same} frames compared");
    }

    const INERTIAL_BLEND: f32 = crate::choreo::render::INERTIAL_BLEND_SECS;
}
