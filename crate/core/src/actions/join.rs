//! Serial joins of two motions (spec §I): Connection and Transition, with the planted foot
//! locked by two-bone IK.
//!
//! * **Switch frames.** Near the end of motion 1 and the start of motion 2, the pair of frames
//!   whose foot-ground contacts agree best (at least one foot the same; a foot planted in both
//!   preferred), then whose joint angles are closest, then the latest in motion 1 and the
//!   earliest in motion 2.
//! * **Connection** (no overlap): motion 1 holds its switch pose for any stated delay, then
//!   the joint angles blend to motion 2's switch pose over a gap with a smooth time-varying
//!   weight, then motion 2 plays on.
//! * **Transition** (overlap): both motions keep playing while the weight goes 0 → 1. When
//!   both are gait cycles (walk → run; one foot landing at a time), the switch frames are the same foot landing in both; the
//!   foot-up and foot-down keyframes of one cycle of each are paired (longest common
//!   subsequence of the event kinds) and the interval between paired keyframes is
//!   time-warped, its length blended with the weight, so the cycles stay in step. Otherwise
//!   ("run, then kick") the overlap is a fixed blend of the two playing motions.
//! * **Alignment.** Motion 2 is turned about the vertical so its heading matches motion 1 at
//!   the switch, and moved so a foot planted in both is in the same place (else the hips).
//! * **Foot locking** (`step_feet`). From the start of the blend, a foot in contact
//!   (found from the motions' own contacts: sole near the floor and barely moving, so it
//!   works on imported clips as on built-in ones) keeps its place and orientation on the
//!   floor, legs by two-bone IK ([`crate::actions::ik::solve_leg_oriented`], on
//!   [`crate::motion::two_bone`]). A foot that lifts, that is in the air when the blend
//!   starts, or whose leg can no longer reach its hold *steps*: straight up, across clear of
//!   the floor, straight down where the animation next puts it on the floor. After the blend,
//!   a foot rejoins motion 2 at its first landing there. So no foot near the floor slides: a
//!   blend that would drag a foot along the floor (run → sit) lifts it over instead.

use crate::fmath;
use glam::{Quat, Vec3};
use serde::{Deserialize, Serialize};

use crate::actions::contact::{detect_contacts, ContactEvent, ContactEventKind, Contacts, Foot};
use crate::actions::ik::{forward, solve_leg, solve_leg_oriented};
use crate::actions::procedural::smooth;
use crate::actions::ActionError;
use crate::clip::{Clip, TranslationTrack};
use crate::canon::humanoid::{Canon, CANON_COUNT};

/// How motion 2 follows motion 1.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "camelCase")]
pub enum JoinKind {
    /// No overlap: a gap (and any stated delay) between the two.
    Connection,
    /// Overlap: both play while one blends into the other.
    Transition,
}

/// Parameters of a serial join. Defaults in [`JoinOptions::default`].
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "camelCase")]
pub struct JoinOptions {
    /// Length of the Connection gap blend, seconds (> 0; default 0.4).
    pub gap_secs: f32,
    /// Overlap of a non-cyclic Transition, seconds (> 0; default 0.35).
    pub overlap_secs: f32,
    /// Stated delay before motion 2 ("2秒後に"), seconds (≥ 0; Connection only).
    pub delay_secs: f32,
    /// How far from the end of motion 1 and the start of motion 2 switch frames are searched,
    /// seconds (default 0.6).
    pub search_secs: f32,
    /// Lock planted feet with IK (default true). Off only to measure what it prevents.
    pub foot_lock: bool,
}

impl Default for JoinOptions {
    fn default() -> Self {
        JoinOptions { gap_secs: 0.4, overlap_secs: 0.35, delay_secs: 0.0, search_secs: 0.6, foot_lock: true }
    }
}

/// What a join did, with the foot-skate figures of its blend.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "camelCase")]
pub struct JoinReport {
    pub kind: JoinKind,
    /// Whether the cycle-aligned (time-warped) Transition was used.
    pub cyclic: bool,
    /// Switch frame in motion 1 and in motion 2.
    pub switch_frame_a: usize,
    pub switch_frame_b: usize,
    /// Output frames of the blend: `[window_start_frame, window_end_frame)`.
    pub window_start_frame: usize,
    pub window_end_frame: usize,
    /// Output frame where motion 2 starts to show (after any delay).
    pub b_start_frame: usize,
    /// Output frame = motion-2 frame + this, for the frames after the blend.
    pub b_frame_offset: i64,
    /// Largest horizontal drift of a planted foot during the blend when the root and angles
    /// are simply blended (no locking), centimetres.
    pub drift_without_lock_cm: f32,
    /// The same with the planted foot locked (what the output has when `foot_lock`), cm.
    pub drift_with_lock_cm: f32,
    /// With the root following the planted foot but before IK, cm (the IK's share is the
    /// difference to `drift_with_lock_cm`; equals the unlocked figure when `foot_lock` is off).
    pub drift_root_only_cm: f32,
    /// Frames on which a foot was held by IK.
    pub locked_frames: usize,
}

/// One output frame: where it samples each motion (fractional frames), the blend weight of
/// motion 2, and which feet are planted.
#[derive(Clone, Copy, Debug)]
struct PlanFrame {
    a: f32,
    b: f32,
    w: f32,
    contact: [bool; 2],
}

fn heading(q: Quat) -> f32 {
    let f = q * Vec3::Z;
    fmath::atan2(f.x, f.z)
}

/// Mean heading of the hips over `±half` frames around `frame`: a gait's pelvis swings from
/// side to side, and one frame's heading would send motion 2 off at an angle.
fn mean_heading(clip: &Clip, frame: usize, half: usize) -> f32 {
    let n = clip.frame_count();
    let (lo, hi) = (frame.saturating_sub(half), (frame + half).min(n.saturating_sub(1)));
    let mut sum = Vec3::ZERO;
    for f in lo..=hi {
        let h = heading(clip.frame_rotations(f)[0]);
        sum += Vec3::new(fmath::sin(h), 0.0, fmath::cos(h));
    }
    fmath::atan2(sum.x, sum.z)
}

/// A foot counts as planted during a blend only when both motions plant it: then both roots
/// keep their distance to it and the locked leg can reach.
fn both_planted(a: [bool; 2], b: [bool; 2]) -> [bool; 2] {
    [a[0] && b[0], a[1] && b[1]]
}

fn pose_distance(a: &[Quat], b: &[Quat]) -> f32 {
    // Root excluded: heading and position are aligned afterwards.
    a.iter().zip(b).skip(1).map(|(x, y)| x.angle_between(*y)).sum()
}

fn contact_score(a: [bool; 2], b: [bool; 2]) -> i32 {
    let same = (a[0] == b[0]) as i32 + (a[1] == b[1]) as i32;
    let planted = ((a[0] && b[0]) || (a[1] && b[1])) as i32;
    if same == 0 {
        -100
    } else {
        2 * same + 3 * planted
    }
}

/// Searches switch frames: `i` in motion 1 (leaving `tail` frames after it), `j` in motion 2.
fn switch_frames(a: &Clip, b: &Clip, ca: &Contacts, cb: &Contacts, tail: usize, search: usize) -> (usize, usize) {
    let na = a.frame_count();
    let nb = b.frame_count();
    let i_hi = na.saturating_sub(1 + tail);
    let i_lo = i_hi.saturating_sub(search);
    let j_hi = search.min(nb.saturating_sub(1 + tail));
    let mut best = (i_hi, 0usize);
    let mut best_key = (i32::MIN, f32::MAX);
    for i in i_lo..=i_hi {
        let pa = a.frame_rotations(i);
        for j in 0..=j_hi {
            let s = contact_score(ca.at(i), cb.at(j));
            let d = pose_distance(pa, b.frame_rotations(j)) + 0.5 * ((i_hi - i) + j) as f32 / a.fps;
            if (s, -d) > (best_key.0, -best_key.1) {
                best_key = (s, d);
                best = (i, j);
            }
        }
    }
    best
}

/// Fewest frames between two paired keyframes of a cycle-aligned Transition.
const MIN_KEY_GAP: usize = 4;

/// Events of both feet within `[from, to]`.
fn events_in(c: &Contacts, from: usize, to: usize) -> Vec<ContactEvent> {
    c.events().into_iter().filter(|e| e.frame >= from && e.frame <= to).collect()
}

/// Keyframes for a cycle-aligned Transition: `(a_knots, b_knots)` in frames, paired.
fn cycle_knots(ca: &Contacts, cb: &Contacts, na: usize, nb: usize, search: usize) -> Option<(Vec<usize>, Vec<usize>)> {
    let ev_a = ca.events();
    let ev_b = cb.events();
    // Latest landing in motion 1 with the same foot landing again before the end.
    for (k, e) in ev_a.iter().enumerate().rev() {
        if e.kind != ContactEventKind::Down {
            continue;
        }
        let Some(next_a) = ev_a[k + 1..].iter().find(|x| x.kind == ContactEventKind::Down && x.foot == e.foot) else { continue };
        if next_a.frame + 2 > na {
            continue;
        }
        // A gait lands one foot at a time. A landing on both feet together (a hop, a jump)
        // is not a cycle to align: taken for one, it would put the switch before the jump.
        let alternates = |ev: &[ContactEvent], from: usize, to: usize| {
            !ev.iter().any(|x| x.kind == ContactEventKind::Down && x.foot != e.foot && (x.frame.abs_diff(from) < MIN_KEY_GAP || x.frame.abs_diff(to) < MIN_KEY_GAP))
        };
        if !alternates(&ev_a, e.frame, next_a.frame) {
            return None;
        }
        // Motion 2: its first landing of the same foot (within the search window) and the next.
        let (m, first_b) = ev_b.iter().enumerate().find(|(_, x)| x.kind == ContactEventKind::Down && x.foot == e.foot)?;
        if first_b.frame > search.max(1) * 2 {
            return None;
        }
        let next_b = ev_b[m + 1..].iter().find(|x| x.kind == ContactEventKind::Down && x.foot == e.foot)?;
        if next_b.frame + 2 > nb || !alternates(&ev_b, first_b.frame, next_b.frame) {
            return None;
        }
        // Pair the keyframes in between by the longest common subsequence of their kinds.
        let ia: Vec<ContactEvent> = events_in(ca, e.frame + 1, next_a.frame.saturating_sub(1));
        let ib: Vec<ContactEvent> = events_in(cb, first_b.frame + 1, next_b.frame.saturating_sub(1));
        let same = |x: &ContactEvent, y: &ContactEvent| x.foot == y.foot && x.kind == y.kind;
        let (p, q) = (ia.len(), ib.len());
        let mut dp = vec![vec![0usize; q + 1]; p + 1];
        for u in (0..p).rev() {
            for v in (0..q).rev() {
                dp[u][v] = if same(&ia[u], &ib[v]) { dp[u + 1][v + 1] + 1 } else { dp[u + 1][v].max(dp[u][v + 1]) };
            }
        }
        let (mut ka, mut kb) = (vec![e.frame], vec![first_b.frame]);
        let (mut u, mut v) = (0, 0);
        while u < p && v < q {
            if same(&ia[u], &ib[v]) {
                ka.push(ia[u].frame);
                kb.push(ib[v].frame);
                u += 1;
                v += 1;
            } else if dp[u + 1][v] >= dp[u][v + 1] {
                u += 1;
            } else {
                v += 1;
            }
        }
        ka.push(next_a.frame);
        kb.push(next_b.frame);
        // Keyframes closer than a few frames in either motion would make the warp race
        // through an interval: drop such interior pairs.
        let mut k = 1;
        while k + 1 < ka.len() {
            if ka[k] < ka[k - 1] + MIN_KEY_GAP || kb[k] < kb[k - 1] + MIN_KEY_GAP || ka[k + 1] < ka[k] + MIN_KEY_GAP || kb[k + 1] < kb[k] + MIN_KEY_GAP {
                ka.remove(k);
                kb.remove(k);
            } else {
                k += 1;
            }
        }
        return Some((ka, kb));
    }
    None
}

/// Samples local rotations and the root translation at a fractional frame.
fn sample(clip: &Clip, frame: f32, rot: &mut Vec<Quat>, tr: &mut Vec<Vec3>) -> Vec3 {
    clip.sample_into(frame / clip.fps, rot, tr);
    tr.first().copied().unwrap_or(Vec3::ZERO)
}

/// Joins motion 2 after motion 1. Both on the canonical skeleton; motion 2 is resampled to
/// motion 1's frame rate when they differ.
pub fn join_serial(a: &Clip, b: &Clip, kind: JoinKind, opts: &JoinOptions) -> Result<(Clip, JoinReport), ActionError> {
    for c in [a, b] {
        c.validate().map_err(|e| ActionError::BadClip { name: c.name.clone(), reason: e.to_string() })?;
        if c.joint_count() != CANON_COUNT {
            return Err(ActionError::NotHumanoid { name: c.name.clone(), reason: format!("{} joints, not the 21 canonical ones", c.joint_count()) });
        }
        if c.frame_count() < 4 {
            return Err(ActionError::TooShort { name: c.name.clone(), frames: c.frame_count(), needed: 4 });
        }
    }
    let b_resampled;
    let b = if (b.fps - a.fps).abs() > 1e-3 {
        b_resampled = b.resampled(a.fps);
        &b_resampled
    } else {
        b
    };
    let fps = a.fps;
    let (na, nb) = (a.frame_count(), b.frame_count());
    let ca = detect_contacts(a);
    let cb = detect_contacts(b);
    let search = ((opts.search_secs.max(0.05) * fps) as usize).max(2);
    let overlap = ((opts.overlap_secs.max(1.0 / fps) * fps).round() as usize).clamp(2, nb.min(na) / 2 + 2);

    // The plan: which frames of each motion each output frame shows.
    let mut plan: Vec<PlanFrame> = Vec::new();
    let knots = if kind == JoinKind::Transition { cycle_knots(&ca, &cb, na, nb, search) } else { None };
    let cyclic = knots.is_some();
    let (i, j, window_start, window_end, b_start);
    match (&knots, kind) {
        (Some((ka, kb)), _) => {
            i = ka[0];
            j = kb[0];
            for f in 0..i {
                plan.push(PlanFrame { a: f as f32, b: j as f32, w: 0.0, contact: ca.at(f) });
            }
            window_start = plan.len();
            b_start = window_start;
            let intervals = ka.len() - 1;
            // The weight follows output time over the expected length of the blend, so it
            // rises smoothly whatever the keyframe spacing.
            let expected: f32 = (0..intervals).map(|k| 0.5 * ((ka[k + 1] - ka[k]) + (kb[k + 1] - kb[k])) as f32).sum::<f32>().max(1.0);
            let mut s = 0.0f32; // knot coordinate: interval index + fraction
            let mut elapsed = 0.0f32;
            while s < intervals as f32 {
                let k = (s.floor() as usize).min(intervals - 1);
                let frac = s - k as f32;
                let w = smooth(elapsed / expected);
                elapsed += 1.0;
                let da = (ka[k + 1] - ka[k]) as f32;
                let db = (kb[k + 1] - kb[k]) as f32;
                let fa = ka[k] as f32 + frac * da;
                let fb = kb[k] as f32 + frac * db;
                let contact = both_planted(ca.at(fa.round() as usize), cb.at(fb.round() as usize));
                plan.push(PlanFrame { a: fa, b: fb, w, contact });
                // One output frame advances the knot coordinate by 1 / blended interval length.
                s += 1.0 / (da + (db - da) * w).max(1.0);
            }
            window_end = plan.len();
            let j_end = kb[kb.len() - 1];
            for f in j_end..nb {
                plan.push(PlanFrame { a: (na - 1) as f32, b: f as f32, w: 1.0, contact: cb.at(f) });
            }
        }
        (None, JoinKind::Transition) => {
            let (ii, jj) = switch_frames(a, b, &ca, &cb, overlap, search);
            i = ii;
            j = jj;
            for f in 0..i {
                plan.push(PlanFrame { a: f as f32, b: j as f32, w: 0.0, contact: ca.at(f) });
            }
            window_start = plan.len();
            b_start = window_start;
            for k in 0..overlap {
                let w = smooth((k + 1) as f32 / (overlap + 1) as f32);
                let (fa, fb) = ((i + k).min(na - 1), (j + k).min(nb - 1));
                let contact = both_planted(ca.at(fa), cb.at(fb));
                plan.push(PlanFrame { a: fa as f32, b: fb as f32, w, contact });
            }
            window_end = plan.len();
            for f in (j + overlap).min(nb)..nb {
                plan.push(PlanFrame { a: (na - 1) as f32, b: f as f32, w: 1.0, contact: cb.at(f) });
            }
        }
        (None, JoinKind::Connection) => {
            let (ii, jj) = switch_frames(a, b, &ca, &cb, 0, search);
            i = ii;
            j = jj;
            for f in 0..=i {
                plan.push(PlanFrame { a: f as f32, b: j as f32, w: 0.0, contact: ca.at(f) });
            }
            window_start = plan.len();
            let (sa, sb) = (ca.at(i), cb.at(j));
            let both = [sa[0] && sb[0], sa[1] && sb[1]];
            let hold = (opts.delay_secs.max(0.0) * fps).round() as usize;
            for _ in 0..hold {
                plan.push(PlanFrame { a: i as f32, b: j as f32, w: 0.0, contact: sa });
            }
            b_start = plan.len();
            let gap = ((opts.gap_secs.max(1.0 / fps) * fps).round() as usize).max(1);
            for k in 0..gap {
                let w = smooth((k + 1) as f32 / (gap + 1) as f32);
                plan.push(PlanFrame { a: i as f32, b: j as f32, w, contact: both });
            }
            window_end = plan.len();
            for f in j..nb {
                plan.push(PlanFrame { a: i as f32, b: f as f32, w: 1.0, contact: cb.at(f) });
            }
        }
    }
    let b_frame_offset = window_end as i64 - match (&knots, kind) {
        (Some((_, kb)), _) => kb[kb.len() - 1] as i64,
        (None, JoinKind::Transition) => (j + overlap).min(nb) as i64,
        (None, JoinKind::Connection) => j as i64,
    };

    // Align motion 2 with motion 1 at the switch: heading, then a shared planted foot.
    let pa_i = a.world_positions(i);
    let pb_j = b.world_positions(j);
    let half = (0.6 * fps) as usize;
    let yaw = Quat::from_rotation_y(mean_heading(a, i, half) - mean_heading(b, j, half));
    let (sa, sb) = (ca.at(i), cb.at(j));
    let anchor = Foot::BOTH.into_iter().find(|f| sa[f.index()] && sb[f.index()]).map(|f| f.ankle()).unwrap_or(Canon::Hips).index();
    let (pa_ref, pb_ref) = (pa_i[anchor], pb_j[anchor]);
    let place_b = |p: Vec3| -> Vec3 {
        let d = yaw * Vec3::new(p.x - pb_ref.x, 0.0, p.z - pb_ref.z);
        Vec3::new(pa_ref.x + d.x, p.y, pa_ref.z + d.z)
    };

    // Render the plan. Without foot locking the root is the plain blend of the two aligned
    // roots. With it, inside the blend the root keeps its blended offset from a planted foot
    // that stays where it landed (the ground position of a flight follows the blended
    // velocity), and after the blend motion 2 carries on from where the blend left the root.
    let render = |lock: bool| -> Clip {
        let frames = plan.len();
        let sk = a.skeleton.clone();
        let mut rotations = Vec::with_capacity(frames * CANON_COUNT);
        let mut root: Vec<Vec3> = Vec::with_capacity(frames);
        let (mut qa, mut ta, mut qb, mut tb) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
        let mut anchor: Option<(usize, Vec3)> = None;
        let mut prev_src: Option<(Vec3, Vec3)> = None;
        let mut correction = Vec3::ZERO;
        for (k, pf) in plan.iter().enumerate() {
            let root_a = sample(a, pf.a, &mut qa, &mut ta);
            let root_b = place_b(sample(b, pf.b, &mut qb, &mut tb));
            if let Some(q) = qb.first_mut() {
                *q = yaw * *q;
            }
            let base = rotations.len();
            for c in 0..CANON_COUNT {
                rotations.push(qa[c].slerp(qb[c], pf.w).normalize());
            }
            let plain = root_a.lerp(root_b, pf.w);
            let r = if !lock || k < window_start {
                plain
            } else if k < window_end {
                let (da, db) = match prev_src {
                    Some((pa, pb)) => (root_a - pa, root_b - pb),
                    None => (Vec3::ZERO, Vec3::ZERO),
                };
                let prev = root.last().copied().unwrap_or(plain);
                let estimate = prev + da.lerp(db, pf.w);
                let (_, rel) = forward(&sk, &rotations[base..], Vec3::ZERO);
                let rel_of = |s: usize| rel[Foot::BOTH[s].ankle().index()];
                if anchor.is_some_and(|(s, _)| !pf.contact[s]) {
                    anchor = None;
                }
                // A foot that lands carries the body from now on; the other one, about to
                // lift, is held by IK for its last frames on the floor.
                let landed = (0..2).find(|&s| pf.contact[s] && k > window_start && !plan[k - 1].contact[s] && anchor.is_some_and(|(a, _)| a != s));
                if let Some(s) = landed {
                    anchor = Some((s, Vec3::new(estimate.x, 0.0, estimate.z) + rel_of(s)));
                }
                if anchor.is_none() {
                    anchor = (0..2).find(|&s| pf.contact[s]).map(|s| (s, Vec3::new(estimate.x, 0.0, estimate.z) + rel_of(s)));
                }
                match anchor {
                    Some((s, at)) => Vec3::new(at.x - rel_of(s).x, plain.y, at.z - rel_of(s).z),
                    None => Vec3::new(estimate.x, plain.y, estimate.z),
                }
            } else {
                if k == window_end {
                    let last = root.last().copied().unwrap_or(plain);
                    let prev_b = prev_src.map(|p| p.1).unwrap_or(root_b);
                    correction = Vec3::new(last.x - prev_b.x, 0.0, last.z - prev_b.z);
                }
                root_b + correction
            };
            prev_src = Some((root_a, root_b));
            root.push(r);
        }
        Clip {
            name: format!("{} + {}", a.name, b.name),
            source: "joined".into(),
            fps,
            skeleton: a.skeleton.clone(),
            rotations,
            translations: vec![TranslationTrack { joint: 0, values: root }],
        }
    };
    let plain = render(false);
    let mut out = if opts.foot_lock { render(true) } else { plain.clone() };
    let contacts: Vec<[bool; 2]> = plan.iter().map(|p| p.contact).collect();
    let anchored_drift = planted_drift_cm(&out, &contacts, window_start, window_end);
    let locked_frames = if opts.foot_lock { step_feet(&mut out, &contacts, window_start, window_end) } else { 0 };
    let report = JoinReport {
        kind,
        cyclic,
        switch_frame_a: i,
        switch_frame_b: j,
        window_start_frame: window_start,
        window_end_frame: window_end,
        b_start_frame: b_start,
        b_frame_offset,
        drift_without_lock_cm: planted_drift_cm(&plain, &contacts, window_start, window_end),
        drift_root_only_cm: anchored_drift,
        drift_with_lock_cm: planted_drift_cm(&out, &contacts, window_start, window_end),
        locked_frames,
    };
    Ok((out, report))
}

/// Largest horizontal distance, in cm, a planted foot moves from where it was planted, over
/// the runs of planted frames within `[start, end)` (a run starts at `start` or at a landing).
pub fn planted_drift_cm(clip: &Clip, contacts: &[[bool; 2]], start: usize, end: usize) -> f32 {
    let end = end.min(clip.frame_count()).min(contacts.len());
    let mut worst = 0.0f32;
    let mut pose = crate::motion::WorldPose::new();
    let mut anchor: [Option<Vec3>; 2] = [None, None];
    for f in start..end {
        let pos = &pose.of_frame(clip, f).positions;
        for foot in Foot::BOTH {
            let s = foot.index();
            if !contacts[f][s] {
                anchor[s] = None;
                continue;
            }
            let p = pos[foot.ankle().index()];
            match anchor[s] {
                None => anchor[s] = Some(p),
                Some(a) => worst = worst.max(Vec3::new(p.x - a.x, 0.0, p.z - a.z).length()),
            }
        }
    }
    worst * 100.0
}

/// Longest release of a lifted foot back into motion 2's own leg angles, seconds.
const RELEASE_SECS: f32 = 0.3;

/// Locks planted feet from `start`: during the window every planted foot stays where it
/// landed; after it, feet still locked stay locked until they lift, then their leg angles
/// blend back to the clip's own while the foot is in the air. Returns the frames with IK.
pub(crate) fn lock_feet(out: &mut Clip, contacts: &[[bool; 2]], start: usize, end: usize) -> usize {
    let n = CANON_COUNT;
    let frames = out.frame_count().min(contacts.len());
    let sk = out.skeleton.clone();
    let release_frames = (RELEASE_SECS * out.fps).max(1.0);
    let mut target: [Option<Vec3>; 2] = [None, None];
    // Release: leg rotations at lift-off and frames since.
    let mut release: [Option<([Quat; 3], f32)>; 2] = [None, None];
    let mut ik_frames = 0;
    for f in start..frames {
        let in_window = f < end;
        let root = out.translations[0].values[f];
        let local: &mut [Quat] = &mut out.rotations[f * n..(f + 1) * n];
        let (_, raw_pos) = forward(&sk, local, root);
        let mut any = false;
        for foot in Foot::BOTH {
            let s = foot.index();
            let chain = foot.chain().map(|c| c.index());
            if contacts[f][s] {
                if target[s].is_none() && (in_window || f == start) {
                    target[s] = Some(raw_pos[foot.ankle().index()]);
                }
                if let Some(t) = target[s] {
                    // Held on the ground plane; the height follows the motion so the heel
                    // can rise at push-off.
                    let t = Vec3::new(t.x, raw_pos[foot.ankle().index()].y, t.z);
                    solve_leg(&sk, local, root, foot, t);
                    release[s] = None;
                    any = true;
                    continue;
                }
            }
            if let Some((from, age)) = release[s] {
                let u = smooth((age + 1.0) / release_frames);
                for (k, c) in chain.iter().enumerate() {
                    local[*c] = from[k].slerp(local[*c], u).normalize();
                }
                release[s] = if u >= 1.0 || contacts[f][s] { None } else { Some((from, age + 1.0)) };
                any = true;
            }
        }
        if any {
            ik_frames += 1;
        }
        // Record lift-offs for the next frame: a foot locked here that is free next frame.
        if f + 1 < frames {
            for foot in Foot::BOTH {
                let s = foot.index();
                if target[s].is_some() && !contacts[f + 1][s] {
                    let chain = foot.chain().map(|c| c.index());
                    let local = &out.rotations[f * n..(f + 1) * n];
                    release[s] = Some((chain.map(|c| local[c]), 0.0));
                    target[s] = None;
                }
            }
        }
        if !in_window && target.iter().all(|t| t.is_none()) && release.iter().all(|r| r.is_none()) {
            break;
        }
    }
    ik_frames
}

/// Height an ankle clears, above the line between where it lifted and where it lands, while
/// a foot steps during a join, metres (a short real step; the spec §J contact band is 5 cm).
const STEP_CLEARANCE_M: f32 = 0.08;
/// Longest lift (and set-down) at each end of a step, seconds: the foot rises and lowers
/// straight, and travels only while clear of the floor.
const STEP_RAMP_SECS: f32 = 0.15;
/// Share of a lift (or set-down) ramp before the foot starts (after it ends) travelling.
const STEP_TRAVEL_IN_RAMP: f32 = 0.7;
/// A planted foot with less than this to go to where it lands next slides instead of
/// stepping, metres.
const SLIDE_M: f32 = 0.005;
/// Longest step, seconds: a foot that finds no contact ahead within it rejoins the animation.
const MAX_STEP_SECS: f32 = 0.6;
/// Length of a step a planted foot is forced into when the leg can no longer reach it, s.
const FORCED_STEP_SECS: f32 = 0.3;
/// A held foot further from its hip than the leg's length plus this is out of reach: the
/// straightened leg would drag it (metres; half the 1 cm a foot may slip before it steps).
const REACH_SLACK_M: f32 = 0.005;

/// What a foot is doing in [`step_feet`].
#[derive(Clone, Copy, Debug)]
enum FootState {
    /// Following the animation as rendered (no IK).
    Free,
    /// Held where it landed, with the orientation it landed with.
    Planted { at: Vec3, rot: Quat },
    /// Lifting at `from` (frame `f0`), landing at the animation's own place at `f1`.
    Step { from: Vec3, from_rot: Quat, f0: usize, f1: usize, lift: bool, then_free: bool },
}

/// World positions and rotations of a frame of `clip` as it stands.
fn frame_world(clip: &Clip, f: usize) -> (Vec<Quat>, Vec<Vec3>) {
    let n = CANON_COUNT;
    forward(&clip.skeleton, &clip.rotations[f * n..(f + 1) * n], clip.translations[0].values[f])
}

/// Foot locking at a join (spec §I), from `start` (the first blended frame) until every foot
/// has rejoined the animation after `end`.
///
/// A foot in contact (`contacts`: found from height near the floor and low speed in the
/// motions joined) is held where it landed — position on the ground plane and orientation —
/// with the leg by two-bone IK; its height follows the animation so the heel can rise. A
/// foot that lifts, that is in the air when the join starts, or whose leg can no longer reach
/// its hold, *steps*: it rises straight up, travels clear of the floor and sets down straight
/// where the animation puts it at its next contact (a foot in the air that the blend would
/// otherwise drag along the floor lifts over it instead). Inside the blend it is held there
/// again; after the blend, where the animation's own feet no longer slide, it simply follows
/// the animation from that landing on. Returns the frames changed.
pub(crate) fn step_feet(out: &mut Clip, contacts: &[[bool; 2]], start: usize, end: usize) -> usize {
    let n = CANON_COUNT;
    let frames = out.frame_count().min(contacts.len()).min(out.translations.first().map_or(0, |t| t.values.len()));
    if start >= frames {
        return 0;
    }
    let sk = out.skeleton.clone();
    let fps = out.fps.max(1.0);
    let ramp_frames = (STEP_RAMP_SECS * fps).max(1.0);
    let forced = ((FORCED_STEP_SECS * fps).round() as usize).max(2);
    // The floor under each ankle (spec §J: its 1st-percentile height): a foot in the air
    // within the one contact rule's band over it (`canon::contact::within_band`) lifts before
    // it travels.
    let all = out.all_world_positions();
    let floors: [f32; 2] = Foot::BOTH.map(|ft| {
        let h: Vec<f32> = (0..frames).map(|f| all[f * n + ft.ankle().index()].y).collect();
        crate::motion::floor_height(&h).unwrap_or(0.0)
    });
    let leg_len: [f32; 2] = Foot::BOTH.map(|ft| {
        let [_, knee, ankle] = ft.chain().map(|c| c.index());
        sk.joints[knee].rest_offset.length() + sk.joints[ankle].rest_offset.length()
    });
    let next_contact = |s: usize, from: usize| (from..frames).find(|&g| contacts[g][s]);
    // A step from frame `f0` (foot at `from`) to the next contact after `f`.
    let plan_step = |s: usize, f: usize, f0: usize, from: Vec3, from_rot: Quat, lift: bool, min_len: usize| -> FootState {
        // A foot with no contact ahead for long (a dance that slides its feet) steps for at
        // most MAX_STEP_SECS and then follows the animation again.
        let longest = ((MAX_STEP_SECS * fps) as usize).max(min_len);
        let f1 = match next_contact(s, f) {
            Some(g) if g >= f0 + min_len && g <= f0 + longest => g,
            Some(g) if g > f0 + longest => f0 + longest,
            _ => (f0 + min_len.max(forced)).max(end.min(frames - 1)).min(f0 + longest),
        }
        .min(frames - 1);
        let then_free = f1 >= end || !contacts[f1][s];
        FootState::Step { from, from_rot, f0, f1: f1.max(f0 + 1), lift, then_free }
    };
    let mut state: [FootState; 2] = [FootState::Free; 2];
    {
        let (rot0, pos0) = frame_world(out, start.saturating_sub(1));
        for ft in Foot::BOTH {
            let s = ft.index();
            let (at, rot) = (pos0[ft.ankle().index()], rot0[ft.ankle().index()]);
            state[s] = if contacts[start][s] {
                FootState::Planted { at, rot }
            } else {
                let lift = crate::canon::contact::within_band(at.y - floors[s]);
                plan_step(s, start, start.saturating_sub(1), at, rot, lift, 1)
            };
        }
    }
    let mut changed = 0;
    for f in start..frames {
        if f >= end && state.iter().all(|s| matches!(s, FootState::Free)) {
            break;
        }
        let root = out.translations[0].values[f];
        let (raw_rot, raw_pos) = frame_world(out, f);
        let mut targets: [Option<(Vec3, Quat)>; 2] = [None, None];
        for ft in Foot::BOTH {
            let s = ft.index();
            let raw_at = raw_pos[ft.ankle().index()];
            // Lift-off: a held foot that is no longer in contact steps to its next contact.
            if let FootState::Planted { at, rot } = state[s] {
                let hip = raw_pos[ft.chain()[0].index()];
                let hold = Vec3::new(at.x, raw_at.y, at.z);
                if !contacts[f][s] {
                    state[s] = plan_step(s, f, f.saturating_sub(1), hold, rot, true, 1);
                } else if (hold - hip).length() > leg_len[s] + REACH_SLACK_M {
                    state[s] = plan_step(s, f + forced, f.saturating_sub(1), hold, rot, true, forced);
                }
            }
            // A foot that lands inside the blend is held from there.
            if matches!(state[s], FootState::Free) && f < end && contacts[f][s] {
                state[s] = FootState::Planted { at: raw_at, rot: raw_rot[ft.ankle().index()] };
            }
            targets[s] = match state[s] {
                FootState::Free => None,
                FootState::Planted { at, rot } => Some((Vec3::new(at.x, raw_at.y, at.z), rot)),
                FootState::Step { from, from_rot, f0, f1, lift, then_free } => {
                    let (dest_rot, dest_pos) = frame_world(out, f1);
                    let dest = dest_pos[ft.ankle().index()];
                    let dest_rot = dest_rot[ft.ankle().index()];
                    let len = (f1 - f0) as f32;
                    let u = ((f - f0) as f32 / len).clamp(0.0, 1.0);
                    let far = Vec3::new(dest.x - from.x, 0.0, dest.z - from.z).length() > SLIDE_M;
                    // Ramps: straight up at a lift, straight down at the landing.
                    let r1 = if far { (ramp_frames / len).min(0.35) } else { 0.0 };
                    let r0 = if far && lift { r1 } else { 0.0 };
                    // Travel starts once the lift has carried the ankle most of the way up (7/10
                    // of the ramp: 6.3 cm of the 8) and ends as late into the set-down, so a short
                    // step does not cross in a few frames.
                    let (t0, t1) = (STEP_TRAVEL_IN_RAMP * r0, STEP_TRAVEL_IN_RAMP * r1);
                    let travel = smooth((u - t0) / (1.0 - t0 - t1).max(1e-3));
                    let env = if far { (if r0 > 0.0 { u / r0 } else { 1.0 }).min(if r1 > 0.0 { (1.0 - u) / r1 } else { 1.0 }).min(1.0) } else { 0.0 };
                    let base = from.lerp(dest, travel);
                    let y = if f >= f1 { dest.y } else { (base.y + STEP_CLEARANCE_M * smooth(env)).max(raw_at.y) };
                    if f >= f1 {
                        state[s] = if then_free { FootState::Free } else { FootState::Planted { at: dest, rot: dest_rot } };
                    }
                    Some((Vec3::new(base.x, y, base.z), from_rot.slerp(dest_rot, travel).normalize()))
                }
            };
        }
        let local: &mut [Quat] = &mut out.rotations[f * n..(f + 1) * n];
        let mut any = false;
        for ft in Foot::BOTH {
            if let Some((t, r)) = targets[ft.index()] {
                solve_leg_oriented(&sk, local, root, ft, t, Some(r));
                any = true;
            }
        }
        changed += any as usize;
    }
    changed
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::actions::ActionLibrary;

    fn clip(lib: &ActionLibrary, tag: &str, secs: f32) -> Clip {
        lib.entries[lib.find(tag, &[]).unwrap()].clip_for(secs)
    }

    fn max_root_step(c: &Clip) -> f32 {
        let v = &c.translations[0].values;
        v.windows(2).map(|w| (w[1] - w[0]).length()).fold(0.0, f32::max)
    }

    #[test]
    fn walk_to_run_is_cycle_aligned_and_feet_stay_locked() {
        let lib = ActionLibrary::builtin();
        let (walk, run) = (clip(&lib, "walk", 3.0), clip(&lib, "run", 2.0));
        let (out, rep) = join_serial(&walk, &run, JoinKind::Transition, &JoinOptions::default()).unwrap();
        out.validate().unwrap();
        assert!(rep.cyclic, "{rep:?}");
        assert!(rep.window_end_frame > rep.window_start_frame + 20);
        eprintln!("walk->run {rep:?}");
        assert!(rep.drift_with_lock_cm < 2.0, "{rep:?}");
        assert!(rep.locked_frames > 0);
        // No teleporting root: at most a run's per-frame travel.
        let v = &out.translations[0].values;
        let worst = (1..v.len()).max_by(|&a, &b| (v[a] - v[a - 1]).length().total_cmp(&(v[b] - v[b - 1]).length())).unwrap();
        assert!(max_root_step(&out) < 0.08, "root step {} at frame {worst} ({rep:?}): {:?}", max_root_step(&out), &v[worst - 3..worst + 3]);
        let off = JoinOptions { foot_lock: false, ..JoinOptions::default() };
        let (_, rep2) = join_serial(&walk, &run, JoinKind::Transition, &off).unwrap();
        assert_eq!(rep2.locked_frames, 0);
        assert!((rep2.drift_without_lock_cm - rep.drift_without_lock_cm).abs() < 1e-3);
    }

    #[test]
    fn run_kick_rejoice_joins_with_matching_contacts() {
        let lib = ActionLibrary::builtin();
        let (run, kick, joy) = (clip(&lib, "run", 2.0), clip(&lib, "kick", 0.0), clip(&lib, "rejoice", 0.0));
        let (a, r1) = join_serial(&run, &kick, JoinKind::Transition, &JoinOptions::default()).unwrap();
        assert!(!r1.cyclic);
        let ca = detect_contacts(&run);
        let cb = detect_contacts(&kick);
        let (x, y) = (ca.at(r1.switch_frame_a), cb.at(r1.switch_frame_b));
        assert!(x[0] == y[0] || x[1] == y[1], "contacts differ at the switch: {x:?} {y:?}");
        let opts = JoinOptions { delay_secs: 1.0, ..JoinOptions::default() };
        let (b, r2) = join_serial(&a, &joy, JoinKind::Connection, &opts).unwrap();
        b.validate().unwrap();
        assert!(r2.b_start_frame >= r2.window_start_frame + 59, "{r2:?}");
        eprintln!("run->kick {r1:?}\nkick->rejoice {r2:?}");
        assert!(r2.drift_with_lock_cm < 2.0, "{r2:?}");
        assert!(r1.drift_with_lock_cm < 2.0, "{r1:?}");
        assert!(b.frame_count() > a.frame_count());
        assert!(max_root_step(&b) < 0.12);
    }

    #[test]
    fn refuses_bad_clips() {
        let lib = ActionLibrary::builtin();
        let walk = clip(&lib, "walk", 1.0);
        let short = walk.slice(0, 2, "short");
        assert!(matches!(join_serial(&walk, &short, JoinKind::Connection, &JoinOptions::default()), Err(ActionError::TooShort { .. })));
        let demo = crate::canon::builtin::demo_clip();
        let mut odd = demo.clone();
        odd.fps = -1.0;
        assert!(matches!(join_serial(&odd, &walk, JoinKind::Connection, &JoinOptions::default()), Err(ActionError::BadClip { .. })));
    }
}
