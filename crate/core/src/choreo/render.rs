//! The dance as one canonical clip, in sync with the song (the count before the first bar
//! plays the first segment's lead-in, held still before that): each bar's segment is warped in
//! time onto the bar, piecewise-linearly between its counts so count k of its n plays at k/n of
//! the bar (the bar's beats when n is the bar's metre, spec §E; [`super::segment`]), placed so it starts where (and facing the way) the previous one
//! ended, and consecutive segments are joined by rewriting the last 5 frames of the earlier and
//! joined by inertialization (Bollo 2016): at the switch the outgoing motion's pose, velocity
//! and acceleration, carried on past its end, differ from the incoming one's by an offset that
//! is added to the incoming motion and decayed to zero by a quintic within
//! [`INERTIAL_BLEND_SECS`], so the viewer sees no jump and the incoming segment keeps its own
//! timing: no time is added and every bar stays on its beat. (The spec's §G join, a cubic
//! Hermite rewrite of 5 frames either side, is kept as [`JoinBlend::Hermite`], the control.)
//! The switch is on the bar line, or with [`RenderOptions::join_points`] within a count of it
//! ([`super::switch`]); [`render_switched`] reports where each falls, for the join measures.
//! Frame 0 is song time 0.

use crate::fmath;
use std::sync::Arc;

use glam::{Quat, Vec3};
use serde::{Deserialize, Serialize};

use super::profile::{part, Part};
use super::quality::{beat_alignment, DanceMeasures, DanceReadout, QualityMotion};
use super::segment::{SegmentLibrary, LIBRARY_FPS};
use crate::bars::Bar;
use crate::canon::builtin::canonical_skeleton;
use crate::clip::{Clip, TranslationTrack};
use crate::canon::humanoid::{canonical_positions, HumanoidMap, CANON_COUNT};
use crate::library::neutral_pose;

/// How to render.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "camelCase", default)]
pub struct RenderOptions {
    /// Output frame rate.
    pub fps: f32,
    /// Joins on (any value above 0) or off (0); with [`JoinBlend::Hermite`], the frames
    /// rewritten on each side of a join (spec §G: 5).
    pub join_frames: usize,
    /// How consecutive segments are joined (default [`JoinBlend::Inertial`]; files saved before
    /// the option read the default).
    pub join_blend: JoinBlend,
    /// Hold each foot where it lands for as long as its bar's source clip has it planted, read
    /// at the clip's own pace ([`hold_planted_feet`]); default on (and for files saved before
    /// the option: missing reads as the default). Off: the control.
    pub hold_feet: bool,
    /// Choose each inertialized join's switch within a count of the bar line, where the two
    /// moves agree best ([`super::switch`]); off (the default for now, and the control): every
    /// switch on the bar line. Missing reads as the default.
    pub join_points: bool,
}

impl Default for RenderOptions {
    fn default() -> Self {
        Self { fps: 60.0, join_frames: 5, join_blend: JoinBlend::Inertial, hold_feet: true, join_points: false }
    }
}

/// How two consecutive segments are joined.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "camelCase")]
pub enum JoinBlend {
    /// Inertialization ([`inertialize_at`]): the incoming segment plays on its own timing
    /// with the outgoing one's pose, velocity and acceleration offset decayed over
    /// [`INERTIAL_BLEND_SECS`]; the outgoing segment is not touched.
    #[default]
    Inertial,
    /// Spec §G: the last `join_frames` frames of the earlier segment and the first of the later
    /// one rewritten by a cubic Hermite curve ([`join_at`]). The control.
    Hermite,
}

/// How long an inertialized join's offset takes to decay to zero (shorter where the next bar
/// starts sooner). Long enough that the offset's acceleration stays within what the segments
/// themselves do, short enough to be gone well inside a count at dance tempi (a count at 180
/// BPM is 0.33 s).
pub const INERTIAL_BLEND_SECS: f32 = 0.3;

/// Yaw (about +Y) of a root rotation's forward (+Z) direction.
fn yaw_of(q: Quat) -> f32 {
    let f = q * Vec3::Z;
    fmath::atan2(f.x, f.z)
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
    let mut clip = render(lib, &[bar], &[Some(seg)], &RenderOptions { fps, join_frames: 0, hold_feet: false, ..RenderOptions::default() });
    clip.name = lib.segment(seg)?.name.clone();
    Some(clip)
}

/// Renders one segment (or `None`: a neutral stance) per bar. Bars are taken in order;
/// `choices` shorter than `bars` leaves the rest neutral.
pub fn render(lib: &SegmentLibrary, bars: &[Bar], choices: &[Option<usize>], options: &RenderOptions) -> Clip {
    render_traced(lib, bars, choices, options).0
}

/// [`render`], with where each join falls: the song time (seconds) at which the dance switches
/// from bar i's move to bar i + 1's, one per bar after the first. What every measure of the
/// joins reads (spec §J's join jump is measured at the switch, [`super::quality::dance_quality_switched`]).
pub fn render_switched(lib: &SegmentLibrary, bars: &[Bar], choices: &[Option<usize>], options: &RenderOptions) -> (Clip, Vec<f32>) {
    let (clip, _, switches) = render_traced(lib, bars, choices, options);
    (clip, switches)
}

/// What the held-feet rule ([`hold_planted_feet`]) spares itself; each off is the control of a
/// [`super::GenerateOptions`] switch, the same figures either way.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct HoldWork {
    /// The free pass posed once, not each round; each measure poses only the frames it reads;
    /// the dance measured is handed back ([`super::GenerateOptions::quick_measures`]).
    pub quick: bool,
    /// With `quick`: the held passes pose only the frames the measures read
    /// ([`QualityMotion::frames_read`], [`super::GenerateOptions::pose_read_frames_only`]), so
    /// the clip handed back is whole only there: for measuring, not for playing.
    pub read_only: bool,
    /// The free pass poses only the joints it reads
    /// ([`crate::canon::character::RetargetOptions::free_pass_legs_only`]).
    pub legs_only: bool,
    /// With `quick`: each round after the first copies the last round's held frames whose plan
    /// is the same bits, and the positions its measure posed of frames that are the same bits,
    /// not posing them again ([`super::GenerateOptions::rounds_copy_same_frames`]).
    pub reuse_frames: bool,
}

/// A rendered dance measured ([`QualityMotion`]) and, when handed on, its §J measures and
/// their readout on its bars' counts.
pub(super) type MeasuredDance = (QualityMotion, Option<(DanceMeasures, DanceReadout)>);

/// [`render_switched`], with the rendered dance measured ([`QualityMotion::from_clip`]) and its
/// §J measures ([`DanceMeasures::of`]) when the held-feet rule took them on the way (`None`
/// otherwise; the measures `None` when a join falls on the motion's last frame): not taken
/// twice. With `work.quick` off (the control) nothing is handed back.
pub(super) fn render_measured(lib: &SegmentLibrary, bars: &[Bar], choices: &[Option<usize>], options: &RenderOptions, work: HoldWork) -> (Clip, Vec<f32>, Option<MeasuredDance>) {
    let work = HoldWork { read_only: work.quick && work.read_only, ..work };
    let (clip, holds, switches) = render_traced_with(lib, bars, choices, options, work);
    let motion = if work.quick { holds.motion.map(|m| (m, holds.measures.filter(|(d, _)| d.every_join_inside))) } else { None };
    (clip, switches, motion)
}

/// [`render`], with what its feet were held to and where its joins fall ([`render_switched`]).
fn render_traced(lib: &SegmentLibrary, bars: &[Bar], choices: &[Option<usize>], options: &RenderOptions) -> (Clip, Holds, Vec<f32>) {
    render_traced_with(lib, bars, choices, options, HoldWork { quick: true, read_only: false, legs_only: true, reuse_frames: true })
}

/// [`render_traced`]; `work.quick` off: the held-feet rule as before session 16 (its free pass
/// posed anew each round, every frame posed for its measures), the control the test
/// `keeping_the_free_pass_changes_no_frame` compares with ([`HoldWork`]).
fn render_traced_with(lib: &SegmentLibrary, bars: &[Bar], choices: &[Option<usize>], options: &RenderOptions, work: HoldWork) -> (Clip, Holds, Vec<f32>) {
    let t0 = super::profile::part_start();
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
    // Per frame: the library clip and its frame (at LIBRARY_FPS) the frame plays, and its bar
    // (the lead-in counts as the first bar's).
    let mut played: Vec<Option<(usize, f32)>> = Vec::with_capacity(frames);
    let mut bar_of: Vec<Option<usize>> = Vec::with_capacity(frames);
    // Where each join switches ([`super::switch`]): on the bar line unless join points are
    // chosen (inertialized joins only).
    let blend_frames = ((INERTIAL_BLEND_SECS * fps).round() as usize).max(2);
    let chosen = options.join_points && options.join_frames > 0 && options.join_blend == JoinBlend::Inertial && bars.len() > 1;
    let places = if chosen { super::switch::placements(lib, bars, choices) } else { Vec::new() };
    let switches: Vec<f32> =
        if chosen { super::switch::choose_switches(lib, bars, choices, &places, fps, blend_frames) } else { bars.iter().skip(1).map(|b| b.start_secs).collect() };
    // The bar whose move the previous frame within the bars played.
    let mut playing_prev: Option<usize> = None;
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
            }
            let (start, dyaw) = match seg.and_then(|s| sample_segment(lib, s, 0.0, &mut rot, &mut trans)) {
                Some((rt, rq)) => (Vec3::new(rt.x, 0.0, rt.z), place_yaw - yaw_of(rq)),
                None => (Vec3::ZERO, 0.0),
            };
            xf = Some((bar_i, start, dyaw));
        }
        // A switch off the bar line: this frame plays the neighbouring bar's move.
        let instead = if chosen && in_bar { super::switch::played_instead(bars, &switches, bar_i, t) } else { None };
        if in_bar {
            let playing = instead.map_or(bar_i, |(k, _)| k);
            if playing_prev.is_some_and(|p| p != playing) {
                boundaries.push(f);
            }
            playing_prev = Some(playing);
        }
        if let Some((k, uk)) = instead {
            let sk = choices.get(k).copied().flatten();
            if let Some(root) = sk.zip(places.get(k)).and_then(|(s, p)| super::switch::placed(lib, s, uk, p, &mut rot, &mut trans)) {
                played.push(sk.and_then(|s| lib.segment(s)).map(|s| (s.clip, super::switch::played_frame(s, uk))));
                bar_of.push(Some(bar_i));
                rotations.extend_from_slice(&rot);
                roots.push(root);
                continue;
            }
        }
        let sampled = seg.and_then(|s| sample_segment(lib, s, u, &mut rot, &mut trans));
        played.push(seg.and_then(|s| lib.segment(s)).filter(|_| sampled.is_some()).map(|s| (s.clip, s.frame_before(u))));
        bar_of.push(bar.map(|_| bar_i));
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
        for (i, &j) in boundaries.iter().enumerate() {
            match options.join_blend {
                JoinBlend::Hermite => join_at(&mut rotations, &mut roots, j, options.join_frames),
                JoinBlend::Inertial => {
                    let blend = blend_frames;
                    let until_next = boundaries.get(i + 1).map_or(usize::MAX, |&n| n.saturating_sub(j));
                    inertialize_at(&mut rotations, &mut roots, j, blend.min(until_next));
                }
            }
        }
    }
    let clip = Clip {
        name: "Choreography".into(),
        source: "choreography".into(),
        fps,
        skeleton,
        rotations,
        translations: vec![TranslationTrack { joint: 0, values: roots }],
    };
    super::profile::part_end(Part::Render, t0);
    let (clip, holds) = if options.hold_feet { hold_planted_feet(lib, bars, clip, &played, &bar_of, &switches, work) } else { (clip, Holds::default()) };
    (clip, holds, switches)
}

/// What [`hold_planted_feet`] held: per frame, the source's planted flags (left ankle, left
/// toe, right ankle, right toe; before the per-bar rule), and per bar whether it kept its holds.
#[derive(Clone, Debug, Default)]
#[cfg_attr(not(test), allow(dead_code))]
struct Holds {
    planted: Vec<[bool; 4]>,
    kept: Vec<bool>,
    /// The returned dance measured, when the rule measured it, §J's measures of it
    /// ([`DanceMeasures::of_every_join`]) and their readout ([`DanceMeasures::readout`]).
    motion: Option<QualityMotion>,
    measures: Option<(DanceMeasures, DanceReadout)>,
    /// Held frames the rounds copied from the round before ([`HoldWork::reuse_frames`]) and
    /// posed, over every round; frames the rounds' measures copied.
    copied: usize,
    posed: usize,
    measure_copied: usize,
}

/// Rounds of [`hold_planted_feet`]'s per-bar rule at most (each drops the holds of the bars
/// they made worse, then holds again).
const HOLD_RULE_ROUNDS: usize = 4;

/// The rendered dance `clip` with its feet held to their floor contacts: a foot its bar's
/// source clip has planted (spec §J's contact band, and slow: the retargeting's rule) stays
/// where it landed until the source lifts it, the leg reaching it by two-bone IK, and a
/// released foot catches up with its free path at no more than 1 m/s
/// ([`crate::canon::character::hold_feet_in_dance`], the retargeting's kernel). Without it a planted
/// foot slides wherever the time warp speeds its source up, the placement moves it, or a join
/// rewrites it.
/// - Planted is read at the source's own pace: each frame's flags are those of the clip frame
///   it plays (`played`), measured on the clip as recorded. Read on the rendered dance, a foot
///   planted at 20 cm/s in a source played 1.5× faster would read 30 cm/s and not be held.
/// - Per bar: a bar keeps its holds only if, with them, its BAS-music on its own counts is not
///   lower and its kinetic beats per count are not further from the beat-rate target
///   ([`super::beat_rate_cost`]) than without: holding feet changes the kinetic speed curve
///   (§J) and may move a kinetic beat; nor if its feet slide more (§J's foot skate) than
///   without (a released foot catching up on the floor). And a join the holds make more abrupt than §J's goal
///   (and than unheld, [`super::quality::JOIN_JUMP_GOAL`]) takes the holds of the bars either
///   side. Bars that fail are played unheld and the rest held again, up to
///   [`HOLD_RULE_ROUNDS`] times. Last, the whole dance keeps its holds only if its BAS-music on
///   its counts is still as far above that on the half-shifted counts, and its kinetic beats
///   per count no further from the target, as unheld, and its feet slide no more in all.
/// - Every round plays the same dance with other holds: when `quick`, its free pass is posed
///   once ([`crate::canon::character::hold_feet_in_dance`]) and each measure poses only the
///   frames it reads ([`QualityMotion::from_clip`]): the same frames and figures as not. With
///   `read_only` too, each round's held pass poses only those frames (half of them at 60 fps;
///   the held clip returned is then whole only there: for measuring, not for playing).
#[allow(clippy::too_many_arguments)]
fn hold_planted_feet(lib: &SegmentLibrary, bars: &[Bar], clip: Clip, played: &[Option<(usize, f32)>], bar_of: &[Option<usize>], switches: &[f32], work: HoldWork) -> (Clip, Holds) {
    use crate::canon::character::{hold_feet_in_dance, DANCE_CATCH_UP_M_S};
    let HoldWork { quick, read_only, legs_only, reuse_frames } = work;
    let reuse_frames = quick && reuse_frames;
    let frames = clip.frame_count();
    if frames < 3 || played.len() < frames {
        return (clip, Holds::default());
    }
    // Each frame's flags: those of the clip frame it plays, at the clip's own frame rate
    // (found once per library clip, [`super::segment::LibraryClip::planted_feet`]).
    let flag = |f: usize, k: usize| -> bool {
        let Some((ci, at)) = played[f] else { return false };
        let Some(lc) = lib.clips().get(ci) else { return false };
        let v = &lc.planted_feet()[k];
        let i = ((at / LIBRARY_FPS * lc.clip.fps).round().max(0.0) as usize).min(v.len().saturating_sub(1));
        v.get(i).copied().unwrap_or(false)
    };
    let source: Vec<[bool; 4]> = (0..frames).map(|f| [0, 1, 2, 3].map(|k| flag(f, k))).collect();
    // One pass of §J's measures per rendered dance gives the rule's figures ([`rule_figures`]),
    // handed on with the dance they measure.
    let measure = |m: QualityMotion| -> Option<RuleMeasure> {
        let (d, figures) = part(Part::Measures, || {
            let d = DanceMeasures::of_every_join(&m, bars, switches);
            let f = rule_figures(&d, bars);
            (d, f)
        });
        let (per_bar, whole, readout) = figures?;
        Some((per_bar, whole, m, (d, readout)))
    };
    let figures = |c: &Clip| measure(part(Part::Posed, || if quick { QualityMotion::from_clip(c) } else { QualityMotion::from_clip_every_frame(c) }).ok()?);
    let only = (quick && read_only).then(|| QualityMotion::frames_read(frames, clip.fps));
    let mut free = None;
    // With `legs_only` (and the frames read only): round 0's held pass first, and the unheld
    // dance measured from the source poses its free pass posed on the frames read
    // ([`QualityMotion::from_posed`]): the same motion, the unheld dance not posed twice.
    let mut first = None;
    let unheld_figures = if only.is_some() && legs_only {
        let planted = [0, 2].map(|k| ((0..frames).map(|f| source[f][k]).collect(), (0..frames).map(|f| source[f][k + 1]).collect()));
        let Some(held) = part(Part::FreePass, || hold_feet_in_dance(&clip, &planted, DANCE_CATCH_UP_M_S, &mut free, only.as_deref(), legs_only)) else { return (clip, Holds::default()) };
        first = Some(held);
        match part(Part::Posed, || free.as_ref().and_then(|p| p.source_positions()).and_then(|w| QualityMotion::from_posed(&clip, w))) {
            Some(m) => m.ok().and_then(measure),
            None => figures(&clip),
        }
    } else {
        figures(&clip)
    };
    let Some((unheld, unheld_whole, unheld_m, unheld_d)) = unheld_figures else { return (clip, Holds::default()) };
    let worse_whole = |(margin, cost, skate): (f32, f32, f32)| margin < unheld_whole.0 - 1e-4 || cost > unheld_whole.1 + 1e-4 || skate > unheld_whole.2;
    let mut keep = vec![true; bars.len()];
    // The last round's held dance and the positions its measure posed ([`HoldWork::reuse_frames`]).
    let mut last_held: Option<(Clip, Vec<Vec3>)> = None;
    let mut measure_copied = 0;
    let counts = |free: &Option<crate::canon::character::FreePass>, measure_copied: usize| Holds {
        copied: free.as_ref().map_or(0, |c| c.held_reused),
        posed: free.as_ref().map_or(0, |c| c.held_posed),
        measure_copied,
        ..Holds::default()
    };
    for round in 0..=HOLD_RULE_ROUNDS {
        if !quick {
            free = None;
        }
        if !reuse_frames {
            if let Some(c) = free.as_mut() {
                c.held = None;
            }
        }
        let kept = |f: usize| bar_of[f].is_none_or(|b| keep.get(b).copied().unwrap_or(true));
        let track = |k: usize| -> Vec<bool> { (0..frames).map(|f| kept(f) && source[f][k]).collect() };
        let planted = [(track(0), track(1)), (track(2), track(3))];
        let Some(held) = first.take().or_else(|| part(if free.is_none() { Part::FreePass } else { Part::HeldPass }, || hold_feet_in_dance(&clip, &planted, DANCE_CATCH_UP_M_S, &mut free, only.as_deref(), legs_only))) else { return (clip, Holds::default()) };
        let (measured, posed) = if reuse_frames {
            let (m, pos, copied) = part(Part::Posed, || QualityMotion::from_clip_reusing(&held, last_held.as_ref().map(|(c, p)| (c, p.as_slice()))));
            measure_copied += copied;
            (m.ok().and_then(measure), pos)
        } else {
            (figures(&held), Vec::new())
        };
        let Some((with, with_whole, held_m, held_d)) = measured else { return (clip, Holds::default()) };
        if round == HOLD_RULE_ROUNDS {
            if worse_whole(with_whole) {
                break;
            }
            return (held, Holds { planted: source, kept: keep, motion: Some(held_m), measures: Some(held_d), ..counts(&free, measure_copied) });
        }
        let mut dropped = false;
        for (b, (w, u)) in with.iter().zip(&unheld).enumerate() {
            if keep[b] && (w.0 < u.0 - 1e-4 || w.1 > u.1 + 1e-4 || w.3 > u.3 + 1e-3) {
                keep[b] = false;
                dropped = true;
            }
            // A join the holds made more abrupt than the goal (and than unheld): neither bar
            // beside it keeps its holds.
            if w.2 > u.2.max(super::quality::JOIN_JUMP_GOAL) + 1e-4 {
                for a in [b.saturating_sub(1), b] {
                    dropped |= std::mem::replace(&mut keep[a], false);
                }
            }
        }
        if !dropped {
            if worse_whole(with_whole) {
                break;
            }
            return (held, Holds { planted: source, kept: keep, motion: Some(held_m), measures: Some(held_d), ..counts(&free, measure_copied) });
        }
        if reuse_frames {
            last_held = Some((held, posed));
        }
    }
    let kept = vec![false; bars.len()];
    (clip, Holds { planted: source, kept, motion: Some(unheld_m), measures: Some(unheld_d), ..counts(&free, measure_copied) })
}

/// The held-feet rule's figures of one bar: BAS-music on its own counts, the beat-rate cost of
/// its kinetic beats per count ([`super::beat_rate_cost`]), the join jump at its start (0 for
/// the first bar) and its mean foot skate.
type BarFigures = (f32, f32, f32, f32);
/// The rule's figures of the whole dance: BAS-music on every bar's counts less BAS-music on the
/// counts moved by half a count (§J's control), the beat-rate cost of its kinetic beats per
/// count, and its mean foot skate.
type WholeFigures = (f32, f32, f32);

/// One rendered dance as the rule measures it: its figures per bar and whole, the motion, and
/// §J's measures and readout, handed on with the dance the rule keeps.
type RuleMeasure = (Vec<BarFigures>, WholeFigures, QualityMotion, (DanceMeasures, DanceReadout));

/// [`hold_planted_feet`]'s figures of a rendered dance from its §J measures, per bar and whole.
/// Bars that each keep their figures can still add up to a dance that follows its counts less
/// clearly (a kinetic beat gained between counts here, one lost on a count there) or that
/// leaves the beat-rate band, or (a lifted foot catching up across a bar's edge) slides its feet
/// more in all: hence the whole dance's too.
fn rule_figures(d: &DanceMeasures, bars: &[Bar]) -> Option<(Vec<BarFigures>, WholeFigures, DanceReadout)> {
    use super::fill::beat_rate_cost;
    let counts = super::figures::bar_counts_secs(bars);
    // §J's readout, which the played figures read too when handed on: each bar's BAS-music on
    // every count in its window, the same bits as on its own counts where the window holds
    // just its own (`bars_hold_own_counts`). A bar whose window holds another's count (bars
    // that overlap, even by an ulp) keeps the rule's own figure: the bar's counts alone.
    let readout = d.readout(bars, &counts)?;
    let own = super::quality::bars_hold_own_counts(bars, &counts);
    let per_bar = bars
        .iter()
        .zip(&readout.bars)
        .zip(own)
        .map(|((b, q), own)| {
            let n = b.beat_count();
            let bas = if own { q.beats.bas_music } else { beat_alignment(&super::figures::bar_counts_secs(std::slice::from_ref(b)), &d.kinetic, b.start_secs, b.end_secs).bas_music };
            (bas, beat_rate_cost(d.kinetic_in(b.start_secs, b.end_secs) as f32 / n as f32), q.join_jump.unwrap_or(0.0), q.foot_skate.mean_cm_per_s)
        })
        .collect();
    let a = &readout.beats;
    let whole = (a.bas_music - a.bas_music_shifted, beat_rate_cost(readout.kinetic_beats as f32 / counts.len().max(1) as f32), readout.foot_skate.mean_cm_per_s);
    Some((per_bar, whole, readout))
}

/// Bollo's quintic offset at `t` of `span` (both in frames): starts at `x0` with velocity `v0`
/// and acceleration `a0` (per frame), reaches 0 with zero velocity and acceleration at `span`.
fn quintic_offset(x0: f32, v0: f32, a0: f32, span: f32, t: f32) -> f32 {
    if t >= span {
        return 0.0;
    }
    let (t2, t3) = (span * span, span * span * span);
    let a = -(a0 * t2 + 6.0 * v0 * span + 12.0 * x0) / (2.0 * t3 * t2);
    let b = (3.0 * a0 * t2 + 16.0 * v0 * span + 30.0 * x0) / (2.0 * t2 * t2);
    let c = -(3.0 * a0 * t2 + 12.0 * v0 * span + 20.0 * x0) / (2.0 * t3);
    (((a * t + b) * t + c) * t + 0.5 * a0) * t * t + v0 * t + x0
}

/// The second derivative (per frame²) of [`quintic_offset`] at `t`: the acceleration the
/// decaying offset adds to the incoming motion ([`super::table::blended_join_jump`]).
pub(crate) fn quintic_offset_accel(x0: Vec3, v0: Vec3, a0: Vec3, span: f32, t: f32) -> Vec3 {
    if t >= span {
        return Vec3::ZERO;
    }
    let (t2, t3) = (span * span, span * span * span);
    let a = -(a0 * t2 + 6.0 * v0 * span + 12.0 * x0) / (2.0 * t3 * t2);
    let b = (3.0 * a0 * t2 + 16.0 * v0 * span + 30.0 * x0) / (2.0 * t2 * t2);
    let c = -(3.0 * a0 * t2 + 12.0 * v0 * span + 20.0 * x0) / (2.0 * t3);
    ((20.0 * a * t + 12.0 * b) * t + 6.0 * c) * t + a0
}

/// [`quintic_offset`] per component.
fn quintic_offset3(x0: Vec3, v0: Vec3, a0: Vec3, span: f32, t: f32) -> Vec3 {
    Vec3::new(quintic_offset(x0.x, v0.x, a0.x, span, t), quintic_offset(x0.y, v0.y, a0.y, span, t), quintic_offset(x0.z, v0.z, a0.z, span, t))
}

/// Inertializes the switch at frame `j` (the incoming segment's first frame) over `span`
/// frames (Bollo 2016, "Inertialization: High-Performance Animation Transitions in Gears of
/// War"): the outgoing motion carried on to frame `j` (its last frames' velocity and
/// acceleration) differs from the incoming motion there by a pose, velocity and acceleration
/// offset; per joint (as a rotation vector relative to the incoming pose at `j`) and for the
/// root position, that offset is added to frames `j .. j + span` of the incoming motion,
/// decayed by [`quintic_offset`]. Frames before `j` are untouched; from `j + span` on the
/// incoming motion plays as it is.
pub(super) fn inertialize_at(rotations: &mut [Quat], roots: &mut [Vec3], j: usize, span: usize) {
    let frames = roots.len();
    // The outgoing motion's acceleration needs frames j-3..j-1; the incoming one's j..j+2.
    if j < 3 || j + 3 > frames || span < 2 {
        return;
    }
    let span_f = span as f32;
    let end = (j + span).min(frames);
    // Pose, velocity and acceleration (per frame) of the outgoing motion carried on to `j`,
    // less those of the incoming motion at `j`, from samples x(f).
    let offsets = |x: &dyn Fn(usize) -> Vec3| -> (Vec3, Vec3, Vec3) {
        let v_out = x(j - 1) - x(j - 2);
        let a_out = x(j - 1) - 2.0 * x(j - 2) + x(j - 3);
        let v_in = x(j + 1) - x(j);
        let a_in = x(j + 2) - 2.0 * x(j + 1) + x(j);
        (x(j - 1) + v_out + 0.5 * a_out - x(j), v_out - v_in, a_out - a_in)
    };
    for joint in 0..CANON_COUNT {
        let at = |f: usize| rotations[f * CANON_COUNT + joint];
        let inv_in = at(j).inverse();
        // Rotation vector of frame f's rotation relative to the incoming pose at j.
        let rel = |f: usize| {
            let d = (at(f) * inv_in).normalize();
            let d = if d.w < 0.0 { -d } else { d };
            d.to_scaled_axis()
        };
        let (x0, v0, a0) = offsets(&rel);
        if !(x0.is_finite() && v0.is_finite() && a0.is_finite()) {
            continue;
        }
        for f in j..end {
            let o = quintic_offset3(x0, v0, a0, span_f, (f - j) as f32);
            let k = f * CANON_COUNT + joint;
            rotations[k] = (Quat::from_scaled_axis(o) * rotations[k]).normalize();
        }
    }
    let (x0, v0, a0) = offsets(&|f: usize| roots[f]);
    if x0.is_finite() && v0.is_finite() && a0.is_finite() {
        for (f, r) in roots.iter_mut().enumerate().take(end).skip(j) {
            *r += quintic_offset3(x0, v0, a0, span_f, (f - j) as f32);
        }
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::choreo::grid::bars_from_tempo;
    use crate::canon::humanoid::Canon;

    /// A dance of built-in moves, bar i playing every 7th live segment, on bars at `bpm`: the
    /// warp plays each move faster or slower than recorded, and every bar after the first starts
    /// on a join.
    fn dance(bpm: f32, secs: f32) -> (SegmentLibrary, Vec<Bar>, Vec<Option<usize>>) {
        let lib = SegmentLibrary::builtin();
        let bars = bars_from_tempo(secs, bpm, 4, 0.0, |_, _| 0.5).unwrap();
        let live: Vec<usize> = lib.segments().iter().filter(|s| !s.retired && s.counts() == 4).map(|s| s.index).collect();
        let choices = (0..bars.len()).map(|i| Some(live[(i * 7) % live.len()])).collect();
        (lib, bars, choices)
    }

    fn bar_of(bars: &[Bar], t: f32) -> usize {
        bars.iter().rposition(|b| t >= b.start_secs).unwrap_or(0)
    }

    fn flat(v: Vec3) -> Vec3 {
        Vec3::new(v.x, 0.0, v.z)
    }

    /// The held-feet rule's figures as its `measure` closure took them before session 22 (its
    /// own frame index, bar counts and joins, every join kept): the control of
    /// `the_rules_figures_from_dance_measures_are_the_closures`.
    fn rule_figures_before(m: &QualityMotion, bars: &[Bar], switches: &[f32]) -> Option<(Vec<BarFigures>, WholeFigures)> {
        let kinetic = super::super::quality::kinetic_beats_secs(m);
        let q_frames = m.frames();
        let frame_of = |t: f32| ((t * super::super::quality::QUALITY_FPS).round().max(0.0) as usize).min(q_frames);
        let joins: Vec<usize> = bars.iter().enumerate().skip(1).map(|(i, b)| frame_of(switches.get(i - 1).copied().unwrap_or(b.start_secs))).collect();
        let jumps = super::super::quality::join_jumps(m, &joins);
        let skate = super::super::quality::foot_skate_samples(m);
        fn bar_counts(b: &Bar) -> impl Iterator<Item = f32> + '_ {
            let n = b.beat_count().max(1);
            (0..n).map(move |k| b.start_secs + b.duration_secs() * k as f32 / n as f32)
        }
        let per_bar = bars
            .iter()
            .enumerate()
            .map(|(i, b)| {
                let counts: Vec<f32> = bar_counts(b).collect();
                let a = super::super::quality::beat_alignment(&counts, &kinetic, b.start_secs, b.end_secs);
                let kb = kinetic.iter().filter(|&&t| t >= b.start_secs && t < b.end_secs).count();
                let jump = i.checked_sub(1).and_then(|j| jumps.get(j)).copied().unwrap_or(0.0);
                let slide = super::super::quality::summarize_skate(&skate, frame_of(b.start_secs)..frame_of(b.end_secs)).mean_cm_per_s;
                (a.bas_music, super::super::fill::beat_rate_cost(kb as f32 / counts.len() as f32), jump, slide)
            })
            .collect();
        let counts: Vec<f32> = bars.iter().flat_map(bar_counts).collect();
        let (first, last) = (bars.first()?, bars.last()?);
        let a = super::super::quality::beat_alignment(&counts, &kinetic, first.start_secs, last.end_secs);
        let kb = kinetic.iter().filter(|&&t| t >= first.start_secs && t < last.end_secs).count();
        let slide = super::super::quality::summarize_skate(&skate, frame_of(first.start_secs)..frame_of(last.end_secs)).mean_cm_per_s;
        Some((per_bar, (a.bas_music - a.bas_music_shifted, super::super::fill::beat_rate_cost(kb as f32 / counts.len().max(1) as f32), slide)))
    }

    fn figure_bits((per_bar, whole): &(Vec<BarFigures>, WholeFigures)) -> (Vec<[u32; 4]>, [u32; 3]) {
        (per_bar.iter().map(|b| [b.0, b.1, b.2, b.3].map(f32::to_bits)).collect(), [whole.0, whole.1, whole.2].map(f32::to_bits))
    }

    #[test]
    fn the_rules_figures_from_dance_measures_are_the_closures() {
        // The held-feet rule's figures from §J's measures taken once (`DanceMeasures`), against
        // the closure it had before: the same bits, held and unheld, at five tempi, and on
        // dances whose last bar is a sliver, so that a join falls on the motion's last frame
        // (which `DanceMeasures::of` leaves out and the rule has always measured).
        let mut at_the_end = 0;
        for (bpm, secs, sliver) in [(90.0, 20.0, None), (120.0, 24.0, None), (150.0, 16.0, None), (170.0, 20.0, None), (104.0, 12.0, None), (120.0, 8.0, Some(0.004f32)), (96.0, 10.0, Some(0.006)), (96.0, 10.0, Some(0.05))] {
            let (lib, mut bars, mut choices) = dance(bpm, secs);
            if let Some(d) = sliver {
                // The last bar ends half a 60 fps frame past an odd frame, so the sliver's join
                // rounds onto the 30 fps motion's last frame.
                let last = bars.last_mut().unwrap();
                last.end_secs = ((last.end_secs * 30.0).floor() * 2.0 + 1.5) / 60.0;
                let last = *last;
                bars.push(Bar { index: last.index + 1, start_secs: last.end_secs, end_secs: last.end_secs + d, ..last });
                choices.push(choices[0]);
            }
            for hold_feet in [true, false] {
                let (clip, switches) = render_switched(&lib, &bars, &choices, &RenderOptions { hold_feet, ..RenderOptions::default() });
                let m = QualityMotion::from_clip(&clip).unwrap();
                let d = DanceMeasures::of_every_join(&m, &bars, &switches);
                let (per_bar, whole, _) = rule_figures(&d, &bars).unwrap();
                let (now, before) = ((per_bar, whole), rule_figures_before(&m, &bars, &switches).unwrap());
                assert_eq!(figure_bits(&now), figure_bits(&before), "{bpm} BPM, last bar {sliver:?}, held {hold_feet}");
                // Where every join is inside, they are `DanceMeasures::of`'s, which the played
                // figures read when handed on.
                assert_eq!(d.every_join_inside, d == DanceMeasures::of(&m, &bars, &switches), "{bpm} BPM, last bar {sliver:?}");
                at_the_end += usize::from(!d.every_join_inside);
            }
        }
        assert!(at_the_end > 0, "no join fell on a motion's last frame: the case was not compared");
    }

    #[test]
    fn a_bars_counts_among_every_count_are_its_own() {
        // What lets the rule read §J's readout (`DanceMeasures::readout`): on a song grid's bars
        // (a sliver last bar too), BAS-music on a bar over every count in its window is the
        // same bits as over the bar's own counts, and the readout's walk of the joins gives
        // `jump_into`'s binary search. Bars that overlap (a count of the next bar in this
        // one's window: bars a caller hands in may; `bars_from_tempo`'s did by an ulp before
        // session 24) are caught
        // (`bars_hold_own_counts`), and the rule keeps its own figures there, the control's.
        use super::super::quality::bars_hold_own_counts;
        let (mut compared, mut differed) = (0, 0);
        for (bpm, secs, sliver, overlap) in [(90.0, 20.0, None, false), (150.0, 16.0, None, false), (120.0, 8.0, Some(0.004f32), false), (96.0, 10.0, Some(0.05), false), (120.0, 12.0, None, true), (104.0, 12.0, None, true)] {
            let (lib, mut bars, mut choices) = dance(bpm, secs);
            if let Some(d) = sliver {
                let last = *bars.last().unwrap();
                bars.push(Bar { index: last.index + 1, start_secs: last.end_secs, end_secs: last.end_secs + d, ..last });
                choices.push(choices[0]);
            }
            if overlap {
                bars[2].end_secs += 0.6 * bars[3].duration_secs();
            }
            let counts = super::super::figures::bar_counts_secs(&bars);
            let own = bars_hold_own_counts(&bars, &counts);
            assert!(!overlap || !own[2], "{bpm} BPM: bar 2 overlaps bar 3");
            let (clip, switches) = render_switched(&lib, &bars, &choices, &RenderOptions::default());
            let m = QualityMotion::from_clip(&clip).unwrap();
            let d = DanceMeasures::of_every_join(&m, &bars, &switches);
            let readout = d.readout(&bars, &counts).unwrap();
            for (i, (b, q)) in bars.iter().zip(&readout.bars).enumerate() {
                let holds_own = own[i];
                let own = beat_alignment(&super::super::figures::bar_counts_secs(std::slice::from_ref(b)), &d.kinetic, b.start_secs, b.end_secs).bas_music;
                if !holds_own {
                    differed += usize::from(own.to_bits() != q.beats.bas_music.to_bits());
                } else {
                    assert_eq!(own.to_bits(), q.beats.bas_music.to_bits(), "{bpm} BPM, bar {i}");
                    compared += 1;
                }
                assert_eq!(d.jump_into(i).map(f32::to_bits), q.join_jump.map(f32::to_bits), "{bpm} BPM, bar {i}");
            }
            let (per_bar, whole, _) = rule_figures(&d, &bars).unwrap();
            assert_eq!(figure_bits(&(per_bar, whole)), figure_bits(&rule_figures_before(&m, &bars, &switches).unwrap()), "{bpm} BPM, overlap {overlap}");
        }
        eprintln!("{compared} bars hold their own counts (compared), {differed} of the rest differ");
        assert!(compared > 20 && differed > 0, "{compared} bars compared, {differed} overlapping bars differed: a case was not reached");
    }

    #[test]
    fn planted_feet_stay_put_across_joins_and_the_dance_keeps_its_time() {
        // The whole-dance rule may play a dance unheld (then its frames are the unheld ones,
        // checked above); at least two of these tempi keep their holds.
        let mut held_dances = 0;
        let (mut runs, mut across, mut slid_unheld, mut air) = (0, 0, 0.0f32, 0);
        for bpm in [90.0, 100.0, 120.0, 150.0, 170.0] {
            let (lib, bars, choices) = dance(bpm, 30.0);
            let opts = RenderOptions::default();
            assert!(opts.hold_feet, "on by default");
            let (held, holds, _) = render_traced(&lib, &bars, &choices, &opts);
            let free = render(&lib, &bars, &choices, &RenderOptions { hold_feet: false, ..opts });
            let fps = opts.fps;
            // No time added: the same frames, song time 0 at frame 0, and everything above the
            // legs posed as unheld (so every count still plays on its beat).
            let end = bars.last().unwrap().end_secs;
            assert_eq!(held.frame_count(), free.frame_count());
            assert_eq!(held.frame_count(), (end * fps).ceil() as usize + 1);
            for f in 0..held.frame_count() {
                for c in [Canon::Spine, Canon::Chest, Canon::Head, Canon::LeftHand, Canon::RightForearm] {
                    let (a, b) = (held.frame_rotations(f)[c.index()], free.frame_rotations(f)[c.index()]);
                    assert!(a.angle_between(b) < 2e-3, "{bpm}: frame {f} {c:?}: {a} vs {b}, {}", a.angle_between(b));
                }
            }
            let map = HumanoidMap::from_skeleton(&held.skeleton);
            let (ph, pf) = (canonical_positions(&held, &map), canonical_positions(&free, &map));
            let at = |p: &[Vec3], f: usize, c: Canon| p[f * CANON_COUNT + c.index()];
            let joins = join_frames(&bars, fps);
            let frames = held.frame_count();
            let planted = |f: usize, k: usize| holds.kept[bar_of(&bars, f as f32 / fps)] && holds.planted[f][k];
            if holds.kept.iter().all(|&k| !k) {
                assert_eq!(held, free, "{bpm}: a dance without holds is the unheld one");
                continue;
            }
            held_dances += 1;
            for (k, ankle) in [(0usize, Canon::LeftFoot), (2, Canon::RightFoot)] {
                let mut f = 0;
                while f < frames {
                    if !planted(f, k) {
                        f += 1;
                        continue;
                    }
                    let start = f;
                    while f < frames && planted(f, k) {
                        f += 1;
                    }
                    // Held on its ankle for frames start..f: it stays where it landed.
                    let (anchor, anchor_free) = (flat(at(&ph, start, ankle)), flat(at(&pf, start, ankle)));
                    for g in start..f {
                        let d = (flat(at(&ph, g, ankle)) - anchor).length();
                        assert!(d < 0.01, "{bpm}: {ankle:?} held from frame {start} moved {d} m by frame {g}");
                        slid_unheld = slid_unheld.max((flat(at(&pf, g, ankle)) - anchor_free).length());
                    }
                    runs += 1;
                    across += usize::from(joins.iter().any(|&j| (start + 1..f).contains(&j)));
                }
                // A foot off the floor for the last 0.6 s (past any catch-up) is where the
                // unheld dance has it, relative to the body (which may have shifted).
                let quiet = (0.6 * fps) as usize;
                for f in quiet..frames {
                    if (f - quiet..=f).any(|g| holds.planted[g][k] || holds.planted[g][k + 1]) {
                        continue;
                    }
                    let moved = (at(&ph, f, ankle) - at(&pf, f, ankle)) - (at(&ph, f, Canon::Hips) - at(&pf, f, Canon::Hips));
                    assert!(flat(moved).length() < 0.005, "{bpm}: {ankle:?} in the air at frame {f} moved {moved}");
                    assert!((at(&ph, f, ankle).y - at(&pf, f, ankle).y).abs() < 0.005, "{bpm}: {ankle:?} height at frame {f}: held {} m, unheld {} m", at(&ph, f, ankle).y, at(&pf, f, ankle).y);
                    air += 1;
                }
            }
        }
        assert!(held_dances >= 2, "{held_dances} of 5 dances kept their holds");
        assert!(runs > 20 && across > 0 && air > 0, "{runs} holds, {across} across a join, {air} frames in the air");
        // The unheld dance slides those feet: the holds changed something.
        assert!(slid_unheld > 0.02, "unheld, the planted feet slid at most {slid_unheld} m");
    }

    #[test]
    fn keeping_the_free_pass_changes_no_frame() {
        // The held-feet rule's rounds with the free pass kept against posing it anew each
        // round (the code before): the same bits, on dances that keep their holds and on ones
        // that drop some.
        let mut rounds_seen = 0;
        for (bpm, secs) in [(90.0, 20.0), (120.0, 24.0), (150.0, 16.0), (170.0, 20.0)] {
            let (lib, bars, choices) = dance(bpm, secs);
            let (kept, holds, s1) = render_traced_with(&lib, &bars, &choices, &RenderOptions::default(), HoldWork { quick: true, read_only: false, legs_only: true, reuse_frames: true });
            let (anew, holds_anew, s2) = render_traced_with(&lib, &bars, &choices, &RenderOptions::default(), HoldWork { quick: false, read_only: false, legs_only: false, reuse_frames: false });
            assert_eq!(kept, anew, "{bpm} BPM");
            assert_eq!((holds.kept.clone(), holds.motion.clone(), s1), (holds_anew.kept, holds_anew.motion, s2), "{bpm} BPM");
            rounds_seen += usize::from(holds.kept.iter().any(|&k| k) && holds.kept.iter().any(|&k| !k));
            // The motion the rule measured is the returned dance's.
            assert_eq!(holds.motion, Some(QualityMotion::from_clip(&kept).unwrap()), "{bpm} BPM");
        }
        assert!(rounds_seen > 0, "no dance dropped some bars' holds: the rounds were not compared");
    }

    #[test]
    fn copying_the_rounds_same_frames_changes_no_frame() {
        // The held-feet rule's rounds after the first copying the last round's held frames
        // whose plan is the same bits (and its measure's posed positions of frames that are the
        // same bits), against posing every frame anew each round (session 24's rounds, the
        // control): the same bits, every frame posed and only the frames read, on dances that
        // keep their holds and on ones that drop some. And both ways were taken: frames
        // copied and frames posed anew in a later round (a rule of one round copies nothing).
        let bits = |c: &Clip| (c.rotations.iter().flat_map(|q| q.to_array()).map(f32::to_bits).collect::<Vec<_>>(), c.translations.iter().flat_map(|t| t.values.iter().flat_map(|v| v.to_array())).map(f32::to_bits).collect::<Vec<_>>());
        let (mut copied, mut anew, mut measure_copied) = (0, 0, 0);
        for (bpm, secs) in [(90.0, 20.0), (120.0, 24.0), (150.0, 16.0), (170.0, 20.0), (104.0, 40.0)] {
            let (lib, bars, choices) = dance(bpm, secs);
            for read_only in [false, true] {
                let work = |reuse_frames: bool| HoldWork { quick: true, read_only, legs_only: true, reuse_frames };
                let (with, holds, s1) = render_traced_with(&lib, &bars, &choices, &RenderOptions::default(), work(true));
                let (without, holds_without, s2) = render_traced_with(&lib, &bars, &choices, &RenderOptions::default(), work(false));
                assert!(bits(&with) == bits(&without), "{bpm} BPM, read only {read_only}: the held dance");
                assert_eq!((holds.kept.clone(), s1), (holds_without.kept.clone(), s2), "{bpm} BPM");
                let motion_bits = |h: &Holds| h.motion.as_ref().map(|m| m.positions.iter().flat_map(|v| v.to_array()).map(f32::to_bits).collect::<Vec<_>>());
                assert!(motion_bits(&holds) == motion_bits(&holds_without), "{bpm} BPM, read only {read_only}: the motion measured");
                assert_eq!(holds.measures.as_ref().map(|m| &m.1), holds_without.measures.as_ref().map(|m| &m.1), "{bpm} BPM: the readout");
                assert_eq!((holds_without.copied, holds_without.measure_copied), (0, 0), "the control copies nothing");
                let read = if read_only { QualityMotion::frames_read(with.frame_count(), with.fps).iter().filter(|&&r| r).count() } else { with.frame_count() };
                copied += holds.copied;
                anew += holds.posed.saturating_sub(read);
                measure_copied += holds.measure_copied;
            }
        }
        println!("later rounds: {copied} held frames copied, {anew} posed anew; {measure_copied} frames' positions copied by the measures");
        assert!(copied > 0 && anew > 0 && measure_copied > 0, "copied {copied} held frames, posed {anew} anew in later rounds, measures copied {measure_copied}");
    }

    #[test]
    fn held_bars_keep_their_beat_figures() {
        use crate::choreo::quality::{beat_alignment, kinetic_beats_secs, QualityMotion};
        let (lib, bars, choices) = dance(128.0, 40.0);
        let (held, holds, _) = render_traced(&lib, &bars, &choices, &RenderOptions::default());
        let free = render(&lib, &bars, &choices, &RenderOptions { hold_feet: false, ..RenderOptions::default() });
        let figures = |c: &Clip| {
            let kinetic = kinetic_beats_secs(&QualityMotion::from_clip(c).unwrap());
            bars.iter()
                .map(|b| {
                    let counts: Vec<f32> = (0..4).map(|k| b.start_secs + b.duration_secs() * k as f32 / 4.0).collect();
                    let kb = kinetic.iter().filter(|&&t| t >= b.start_secs && t < b.end_secs).count();
                    (beat_alignment(&counts, &kinetic, b.start_secs, b.end_secs).bas_music, crate::choreo::beat_rate_cost(kb as f32 / 4.0))
                })
                .collect::<Vec<_>>()
        };
        let (h, u) = (figures(&held), figures(&free));
        for (b, ((hb, hc), (ub, uc))) in h.iter().zip(&u).enumerate() {
            if holds.kept[b] {
                assert!(*hb >= ub - 1e-3 && *hc <= uc + 1e-3, "bar {b} kept its holds: BAS {hb} vs {ub}, rate cost {hc} vs {uc}");
            }
        }
    }

    /// Joins of one dance rendered unheld with `blend` (or none): the clip and §J's join jump
    /// at each join.
    fn joined(lib: &SegmentLibrary, bars: &[Bar], choices: &[Option<usize>], blend: Option<JoinBlend>) -> (Clip, Vec<f32>) {
        use crate::choreo::quality::{join_jumps, QualityMotion, QUALITY_FPS};
        let opts = RenderOptions { hold_feet: false, join_frames: if blend.is_some() { 5 } else { 0 }, join_blend: blend.unwrap_or_default(), ..RenderOptions::default() };
        let clip = render(lib, bars, choices, &opts);
        let m = QualityMotion::from_clip(&clip).unwrap();
        let joins: Vec<usize> = bars.iter().skip(1).map(|b| (b.start_secs * QUALITY_FPS).round() as usize).collect();
        let jumps = join_jumps(&m, &joins);
        (clip, jumps)
    }

    #[test]
    fn inertial_joins_leave_the_outgoing_bar_and_the_beat_alone_and_are_smoother_than_hermite() {
        let mean = |v: &[f32]| v.iter().sum::<f32>() / v.len() as f32;
        let max = |v: &[f32]| v.iter().copied().fold(0.0f32, f32::max);
        let (mut sum_i, mut sum_h, mut sum_n) = (0.0, 0.0, 0.0);
        for bpm in [96.0, 120.0, 150.0] {
            let (lib, bars, choices) = dance(bpm, 24.0);
            let (inertial, ji) = joined(&lib, &bars, &choices, Some(JoinBlend::Inertial));
            let (_, jh) = joined(&lib, &bars, &choices, Some(JoinBlend::Hermite));
            let (raw, jn) = joined(&lib, &bars, &choices, None);
            assert_eq!(inertial.frame_count(), raw.frame_count(), "no time added");
            // Every frame before a join's first frame, and from the blend's end on, is the
            // unjoined dance's: the outgoing bar is untouched and the incoming one keeps its timing.
            let fps = inertial.fps;
            let span = (INERTIAL_BLEND_SECS * fps).round() as usize;
            let joins = join_frames(&bars, fps);
            for f in 0..inertial.frame_count() {
                let blended = joins.iter().any(|&j| (j..j + span).contains(&f));
                let same = inertial.frame_rotations(f) == raw.frame_rotations(f);
                if !blended {
                    assert!(same, "{bpm}: frame {f} outside every blend was changed");
                }
            }
            println!("{bpm} BPM: join jump mean/max inertial {:.2}/{:.2}, hermite {:.2}/{:.2}, none {:.2}/{:.2}", mean(&ji), max(&ji), mean(&jh), max(&jh), mean(&jn), max(&jn));
            sum_i += mean(&ji);
            sum_h += mean(&jh);
            sum_n += mean(&jn);
        }
        assert!(sum_i < sum_n, "inertial joins {sum_i} no smoother than none {sum_n}");
        assert!(sum_i <= sum_h, "inertial joins {sum_i} rougher than Hermite {sum_h}");
    }

    #[test]
    fn the_quintic_offsets_acceleration_is_its_second_difference() {
        let (x0, v0, a0) = (Vec3::new(0.3, -0.1, 0.05), Vec3::new(0.02, 0.04, -0.01), Vec3::new(0.001, 0.0, -0.002));
        let x = |t: f32| quintic_offset3(x0, v0, a0, 9.0, t);
        for t in [0.5f32, 2.0, 4.5, 7.0] {
            let h = 1e-2;
            let fd = (x(t + h) - 2.0 * x(t) + x(t - h)) / (h * h);
            assert!((fd - quintic_offset_accel(x0, v0, a0, 9.0, t)).length() < 1e-3, "t {t}: {fd} against {}", quintic_offset_accel(x0, v0, a0, 9.0, t));
        }
        assert!((quintic_offset_accel(x0, v0, a0, 9.0, 0.0) - a0).length() < 1e-6);
        assert_eq!(quintic_offset_accel(x0, v0, a0, 9.0, 9.0), Vec3::ZERO);
    }

    #[test]
    fn the_quintic_offset_starts_at_the_offset_and_ends_at_rest() {
        let (x0, v0, a0, span) = (0.4, -0.05, 0.01, 18.0);
        assert!((quintic_offset(x0, v0, a0, span, 0.0) - x0).abs() < 1e-6);
        let d = 1e-2;
        let v = (quintic_offset(x0, v0, a0, span, d) - quintic_offset(x0, v0, a0, span, 0.0)) / d;
        assert!((v - v0).abs() < 1e-2, "start velocity {v}");
        assert!(quintic_offset(x0, v0, a0, span, span - 1e-3).abs() < 1e-4);
        let v_end = (quintic_offset(x0, v0, a0, span, span - d) - quintic_offset(x0, v0, a0, span, span - 2.0 * d)) / d;
        assert!(v_end.abs() < 1e-3, "end velocity {v_end}");
        assert_eq!(quintic_offset(x0, v0, a0, span, span + 1.0), 0.0);
    }

    #[test]
    fn a_dance_without_segments_renders_unheld() {
        let lib = SegmentLibrary::builtin();
        let bars = bars_from_tempo(8.0, 120.0, 4, 0.0, |_, _| 0.5).unwrap();
        let a = render(&lib, &bars, &[None; 4], &RenderOptions::default());
        let b = render(&lib, &bars, &[None; 4], &RenderOptions { hold_feet: false, ..RenderOptions::default() });
        assert_eq!(a.frame_count(), b.frame_count());
        let old: RenderOptions = serde_json::from_str(r#"{"fps":30,"joinFrames":5}"#).unwrap();
        assert!(old.hold_feet, "a file saved before the option holds feet");
    }
}
