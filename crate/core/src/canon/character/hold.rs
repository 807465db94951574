//! Feet held where they are planted: which frames a foot is planted on, where each held foot
//! goes and how far the body shifts to keep it put, how a released foot returns to its free
//! path, the toe kept off the floor and the pelvis dropped to reach (the kernel
//! [`super::Character`] plays with), and a rendered dance held the same way
//! ([`hold_feet_in_dance`]).

use crate::fmath;
use std::sync::Arc;

use glam::{Quat, Vec3};

use super::{Character, Leg, RetargetOptions, Transfer};
use crate::canon::builtin::canonical_skeleton;
use crate::canon::contact::{planted_frames, CONTACT_HEIGHT_M, CONTACT_SPEED_M_S};
use crate::clip::Clip;
use crate::canon::humanoid::HumanoidMap;
use crate::import::SkinnedMesh;
use crate::motion;
use crate::skeleton::Skeleton;
use crate::canon::retarget::is_canonical;

/// Planted frames and release for [`Character::play`], from outside the source's own tracks.
pub(super) struct GivenHolds {
    /// Per leg (left, right) and frame: the point a planted foot stands on.
    pub(super) contacts: Vec<Vec<Option<Contact>>>,
    pub(super) release: Release,
}

/// Pass 0 of [`Character::play`] on one dance, kept ([`hold_feet_in_dance`]): the character
/// posed freely (where its feet, hips and ankle hinges go, where the source's feet are) and the
/// source's world rotations and hips per frame. None of it depends on the holds, so the
/// held-feet rule's rounds, which play the same dance with other holds, pose it once and the
/// held pass reads the source's pose instead of posing it again: the same figures.
#[derive(Clone, Debug, Default)]
pub(crate) struct FreePass {
    pub(super) frames: usize,
    pub(super) feet: Vec<FootTracks>,
    pub(super) free_hip: Vec<Vec<Vec3>>,
    pub(super) free_hinge: Vec<Vec<Vec3>>,
    /// The source's world rotation of every joint, frame-major, and its hips' world position.
    pub(super) src_rotations: Vec<Quat>,
    pub(super) src_hips: Vec<Vec3>,
    /// With [`RetargetOptions::free_pass_legs_only`] and the frames read given: the source's
    /// world position of every joint on those frames, frame-major (zero on the others), as
    /// pass 0 posed them; empty otherwise ([`FreePass::source_positions`]).
    pub(super) src_positions: Vec<Vec3>,
    /// The last held pass on this clip ([`HeldFrames`]), when kept: the next round's frames
    /// whose plan is the same to the bit are copied from it, not posed again.
    pub(crate) held: Option<HeldFrames>,
    /// Frames the held passes on this clip copied from the last one ([`HeldFrames`]), and posed.
    pub(crate) held_reused: usize,
    pub(crate) held_posed: usize,
}

/// A held pass of [`super::Character::play`] kept for the next on the same clip (the held-feet
/// rule's rounds play one dance with other holds): per frame, the plan it was posed from (each
/// leg's target, the pelvis drop, the body's shift, each foot's toe pitch, as bits) and what it
/// gave (every joint's local rotation and the translation tracks' values). A held frame is posed
/// on its own from the source's frame and these (the plan carries what passes from frame to
/// frame), so a frame whose plan is the same bits gives the same bits: copied, not posed.
#[derive(Clone, Debug, Default)]
pub(crate) struct HeldFrames {
    pub(super) keys: Vec<HeldKey>,
    pub(super) posed: Vec<bool>,
    pub(super) rotations: Vec<Quat>,
    pub(super) tracks: Vec<Vec<Vec3>>,
}

/// One frame's plan for [`HeldFrames`], as bits: per leg (two) its target (a flag and three
/// coordinates) and toe pitch (a flag and four components); the drop; the shift.
pub(super) type HeldKey = [u32; 22];

/// [`HeldKey`] of a frame: `targets` and `pitches` per leg (two legs), `drop`, `shift`.
pub(super) fn held_key(targets: [Option<Vec3>; 2], pitches: [Option<Quat>; 2], drop: f32, shift: Vec3) -> HeldKey {
    let mut k = [0u32; 22];
    for (l, t) in targets.iter().enumerate() {
        if let Some(v) = t {
            k[l * 4] = 1;
            k[l * 4 + 1..l * 4 + 4].copy_from_slice(&v.to_array().map(f32::to_bits));
        }
    }
    for (l, q) in pitches.iter().enumerate() {
        if let Some(q) = q {
            k[8 + l * 5] = 1;
            k[9 + l * 5..13 + l * 5].copy_from_slice(&q.to_array().map(f32::to_bits));
        }
    }
    k[18] = drop.to_bits();
    k[19..22].copy_from_slice(&shift.to_array().map(f32::to_bits));
    k
}

impl FreePass {
    /// The source's world position of every joint (frame-major, its skeleton's joints) on the
    /// frames the caller reads (zero on the others), as pass 0 posed the source: the same bits
    /// as posing those frames of the source clip again ([`crate::motion::WorldPose::of_frame`]).
    /// `None` when not kept.
    pub(crate) fn source_positions(&self) -> Option<&[Vec3]> {
        Some(self.src_positions.as_slice()).filter(|p| !p.is_empty())
    }
}

/// Fastest a released foot in a rendered dance catches up with its free path, m/s (a
/// foot stepping: a person's swing foot moves at 2–4 m/s, so this is a slow, visible-but-smooth
/// glide, never a snap).
pub(crate) const DANCE_CATCH_UP_M_S: f32 = 1.0;

/// A dance on the canonical skeleton with its feet held where they were planted, the legs
/// reaching by the retargeting's two-bone IK (the canonical figure playing the dance, as a
/// character plays a source): `planted[leg]` = (ankle planted, toe planted) per frame of
/// `clip`, legs left then right, read by the caller wherever the dance's source is (a
/// rendered dance: each bar's source clip at its own pace). A released foot catches up with
/// its free path at no more than `catch_up_m_s`, at its free height. Everything else as
/// [`Character::retarget`] does it: body shift, pelvis drop, contact on ankle or toe.
/// Returns `None` when the clip is not on the canonical skeleton. `free` keeps the free pass
/// ([`FreePass`]) between calls on the same `clip` (start with `None`; another clip needs
/// another). `only`: the frames the caller reads (a measure's: the 30 fps samples
/// `QualityMotion::from_clip` poses); the others are placeholders, not the held dance (each frame of the held
/// pass is posed on its own, so the frames read are the same either way). `None`: every frame.
/// `legs_only`: pass 0 poses only the joints it reads ([`RetargetOptions::free_pass_legs_only`]).
pub(crate) fn hold_feet_in_dance(clip: &Clip, planted: &[(Vec<bool>, Vec<bool>); 2], catch_up_m_s: f32, free: &mut Option<FreePass>, only: Option<&[bool]>, legs_only: bool) -> Option<Clip> {
    use std::sync::OnceLock;
    static FIGURE: OnceLock<Character> = OnceLock::new();
    if !is_canonical(&clip.skeleton) {
        return None;
    }
    let figure = FIGURE.get_or_init(|| {
        let sk = Arc::new(canonical_skeleton());
        let map = HumanoidMap::from_skeleton(&sk);
        Character::build("canonical", sk, SkinnedMesh::default(), map)
    });
    let frames = clip.frame_count();
    let contacts = planted
        .iter()
        .map(|(ankle, toe)| {
            (0..frames)
                .map(|f| match (ankle.get(f).copied().unwrap_or(false), toe.get(f).copied().unwrap_or(false)) {
                    (true, _) => Some(Contact::Ankle),
                    (false, true) => Some(Contact::Toe),
                    _ => None,
                })
                .collect()
        })
        .collect();
    let given = GivenHolds { contacts, release: Release::CatchUp { speed: catch_up_m_s } };
    let map = HumanoidMap::from_skeleton(&clip.skeleton);
    let mut out = figure.play(clip, &map, &RetargetOptions { transfer: Transfer::Conjugate, hold_feet: true, release_over_swing: true, free_pass_legs_only: legs_only }, Some(&given), Some(free), only).ok()?;
    out.name = clip.name.clone();
    out.source = clip.source.clone();
    Some(out)
}

/// Time over which a released foot is eased from where it was held back to its free path, s.
pub(super) const RELEASE_S: f32 = 0.15;

/// The source joint's planted frames by the engine's one foot-contact rule
/// ([`planted_frames`]), measured at the canonical size: `src` is at the character's, `scale`
/// times it, so every rig holds the same frames of the same source.
fn planted_at_canonical_size(src: &[Vec3], scale: f32, fps: f32) -> Vec<bool> {
    let s = if scale.is_finite() && scale > 0.0 { scale } else { 1.0 };
    planted_frames(&src.iter().map(|p| *p / s).collect::<Vec<_>>(), fps)
}

/// One leg's tracks for [`hold_plan`]: the source's ankle and toe (at the character's size) and
/// the character's free ankle and toe (pass 0: the transfer alone), per frame; the toe tracks
/// are empty for a rig without toes. `y_offset` takes the source's ankle height onto the
/// character's ground; `scale` is the character's size over the canonical skeleton's (the
/// source tracks are scaled by it).
#[derive(Clone, Debug)]
pub(super) struct FootTracks {
    pub(super) src_ankle: Vec<Vec3>,
    pub(super) src_toe: Vec<Vec3>,
    pub(super) free_ankle: Vec<Vec3>,
    pub(super) free_toe: Vec<Vec3>,
    pub(super) y_offset: f32,
    pub(super) scale: f32,
}

/// The point a planted foot stands on: the ankle (a flat foot, or one turning on its heel) or
/// the toe joint (the heel raised: turning on the ball of the foot).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Contact {
    Ankle,
    Toe,
}

/// Where each held ankle goes, and how far the whole body moves horizontally to keep held
/// feet put.
/// - A foot is held while the source's ankle is planted, or else its toe (the heel raised);
///   that joint is the foot's contact point, and it stays where it is. A foot turning on its
///   ball so holds the ball, its ankle circling round it as the foot turns (the character's
///   foot keeps the transfer's world rotation) — not the ankle, which would swing the ball
///   (and a rig's longer foot swings it farther) round the ankle, nor nothing, which would
///   leave the foot to the character's free path: a rig with wider hips than the source's
///   sweeps its feet farther round when the body turns (pivot turns).
/// - Each hold starts where the foot is (its free path moved by the body, or where it was
///   being eased to), so landing never jumps; a foot that changes point (heel down, heel up)
///   keeps its place.
/// - While feet are held the body shifts so they stay put (a rig turning on one foot must
///   move its body round it, as a person would); the shift is smoothed over ±[`RELEASE_S`]
///   and the IK takes up what is left. The shift is planned first, with each foot landing
///   where the running (unsmoothed) shift puts it; then the feet are planned again, landing
///   where the smoothed shift — the body's real path — puts them.
/// - Targets sit at the source's ankle height plus `y_offset` (the character's ground); a
///   released foot eases back onto its (shifted) free path over [`RELEASE_S`].
#[cfg(test)]
pub(super) fn hold_plan(feet: &[FootTracks], fps: f32) -> (Vec<Vec<Option<Vec3>>>, Vec<Vec3>) {
    hold_plan_with(feet, fps, None, Release::Ease { over_swing: true })
}

/// The longest a released foot takes to close its horizontal gap to its free path (within the
/// swing until it lands again, [`Release::Ease`]), s.
pub(super) const RELEASE_SWING_MAX_S: f32 = 0.6;
/// How fast, on average, a released foot closes its horizontal gap to its free path at most
/// ([`Release::Ease`] over its swing), m/s: the ease's steepest frame (smoothstep: 1.5× the
/// mean) then moves the foot 1.5 m/s past its free path, 5 cm a frame at 30 fps — the
/// one-frame bound `character_retarget` holds a foot's move to over the source's.
pub(super) const RELEASE_CLOSE_M_S: f32 = 1.0;
/// How high a foot released into a long ease ([`RELEASE_CLOSE_M_S`]) rises while it travels,
/// m at canonical size: clear of the contact band ([`CONTACT_HEIGHT_M`]), so it steps rather
/// than slides (the text actions' joins step 8 cm).
pub(super) const RELEASE_STEP_LIFT_M: f32 = 0.08;

/// How a released foot goes back onto its free path.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) enum Release {
    /// Eased back (retargeting: the free path is near the hold): its height over
    /// [`RELEASE_S`] (the foot lifts as the source's does); its horizontal gap over [`RELEASE_S`]
    /// too, or, when `over_swing` and the gap is too wide to close that fast at
    /// [`RELEASE_CLOSE_M_S`], over as long as that takes within the swing (until the foot lands
    /// again, at most [`RELEASE_SWING_MAX_S`]). `over_swing` off: the control (the hold before
    /// issue 27's mend). Why: a rig with wider hips than the source's turning on one foot
    /// (RobotExpressive's pivot turns, its stance 1.2 m wide) carries the other, held, foot a
    /// metre off its free path; closed in 0.15 s that gap was a snap of up to 0.47 m a frame
    /// (+0.36 m over the source's fastest foot). Only wide gaps take longer: easing every
    /// release over the whole swing also halved that, but bent the legs off the source's
    /// directions on every rig (Xbot's pivot turns' direction p95 2.2° → 5.9°) and let more of
    /// the robot's moves skate (24 → 46 above the source's + 1 cm/s).
    Ease { over_swing: bool },
    /// Horizontally at no more than `speed` m/s, at its free (unheld) height, until it
    /// reaches its free path (a rendered dance: a planted foot may have been held far from a
    /// free path that the time warp, the placement or a join slid away; an ease over a fixed
    /// time would snap it back). The gap closes at `speed`; the foot also moves with its free
    /// path meanwhile (a dancer travelling faster than `speed` would otherwise never be
    /// caught up with, and the leg would be stretched ever farther).
    CatchUp { speed: f32 },
}

/// [`hold_plan`] with the planted frames given (`contacts`: per leg and frame, the point a
/// planted foot stands on; `None`: read from the source tracks by the one contact rule,
/// [`planted_frames`]) and a
/// choice of [`Release`].
#[cfg(test)]
pub(super) fn hold_plan_with(feet: &[FootTracks], fps: f32, contacts: Option<&[Vec<Option<Contact>>]>, release: Release) -> (Vec<Vec<Option<Vec3>>>, Vec<Vec3>) {
    let (targets, shift, _) = hold_plan_stepping(feet, fps, contacts, release);
    (targets, shift)
}

/// [`hold_plan_with`], and per leg and frame whether the foot is stepping: released into a
/// long ease ([`RELEASE_CLOSE_M_S`]), travelling to its free path (the pelvis does not drop
/// for it: [`pelvis_drop`]).
pub(super) fn hold_plan_stepping(feet: &[FootTracks], fps: f32, contacts: Option<&[Vec<Option<Contact>>]>, release: Release) -> (Vec<Vec<Option<Vec3>>>, Vec<Vec3>, Vec<Vec<bool>>) {
    let legs = feet.len();
    let frames = feet.iter().flat_map(|t| [t.src_ankle.len(), t.free_ankle.len()]).min().unwrap_or(0);
    let flat = |v: Vec3| Vec3::new(v.x, 0.0, v.z);
    let contact: Vec<Vec<Option<Contact>>> = match contacts {
        Some(given) => (0..legs).map(|k| (0..frames).map(|f| given.get(k).and_then(|c| c.get(f).copied().flatten())).collect()).collect(),
        None => feet
            .iter()
            .map(|t| {
                let ankle = planted_at_canonical_size(&t.src_ankle[..frames], t.scale, fps);
                let has_toe = t.src_toe.len() >= frames && t.free_toe.len() >= frames;
                let toe = if has_toe { planted_at_canonical_size(&t.src_toe[..frames], t.scale, fps) } else { vec![false; frames] };
                (0..frames).map(|f| if ankle[f] { Some(Contact::Ankle) } else if toe[f] { Some(Contact::Toe) } else { None }).collect()
            })
            .collect(),
    };
    // The character's toe from its ankle, horizontal, as its foot is turned on each frame.
    let toe_from_ankle = |k: usize, f: usize| -> Vec3 {
        let t = &feet[k];
        if t.free_toe.len() > f {
            flat(t.free_toe[f] - t.free_ankle[f])
        } else {
            Vec3::ZERO
        }
    };
    let w = ((RELEASE_S * fps).round() as usize).max(1);
    let smooth = |shift: &[Vec3]| -> Vec<Vec3> {
        (0..frames)
            .map(|f| {
                let r = f.saturating_sub(w)..(f + w + 1).min(frames);
                let len = r.len() as f32;
                shift[r].iter().copied().sum::<Vec3>() / len
            })
            .collect()
    };
    let mut body: Option<Vec<Vec3>> = None;
    let mut targets: Vec<Vec<Option<Vec3>>> = Vec::new();
    let mut stepping: Vec<Vec<bool>> = Vec::new();
    for plan in 0..2 {
        targets = vec![vec![None; frames]; legs];
        stepping = vec![vec![false; frames]; legs];
        let mut shift = vec![Vec3::ZERO; frames];
        let mut offset = Vec3::ZERO;
        // Per leg: the contact point held now (which, where), and the last held target.
        let mut point: Vec<Option<(Contact, Vec3)>> = vec![None; legs];
        let mut last: Vec<Option<(Vec3, usize)>> = vec![None; legs];
        // Per leg: the frames a release eases its horizontal gap over ([`Release::Ease`]).
        let mut swing: Vec<usize> = vec![w; legs];
        for f in 0..frames {
            // Where the body is: the first plan's smoothed shift; in the first, the running
            // shift so far.
            let body_at = body.as_ref().map_or(offset, |b| b[f]);
            let (mut sum, mut count) = (Vec3::ZERO, 0);
            for k in 0..legs {
                let t = &feet[k];
                let free = t.free_ankle[f] + body_at;
                let Some(c) = contact[k][f] else {
                    point[k] = None;
                    match release {
                        Release::Ease { over_swing } => {
                            if let Some((held, end)) = last[k] {
                                // The swing: the frames until the foot lands again.
                                if f == end + 1 {
                                    let next = (f..frames).find(|&g| contact[k][g].is_some()).unwrap_or(frames);
                                    let most = ((RELEASE_SWING_MAX_S * fps).round() as usize).min(next - f).max(w);
                                    let gap = flat(held - free).length();
                                    let need = (gap * fps / RELEASE_CLOSE_M_S).ceil() as usize;
                                    swing[k] = if over_swing { need.clamp(w, most) } else { w };
                                }
                                if f - end <= swing[k] {
                                    let u = (f - end) as f32 / (swing[k] + 1) as f32;
                                    let lifted = held.lerp(free, motion::smoothstep((f - end) as f32 / (w + 1) as f32));
                                    let across = held.lerp(free, motion::smoothstep(u));
                                    // A long ease is a step: the foot rises clear of the floor
                                    // while it travels (not a slide along it), and comes down
                                    // as it ends.
                                    let step = if swing[k] > w { RELEASE_STEP_LIFT_M * t.scale * fmath::sin(std::f32::consts::PI * u) } else { 0.0 };
                                    targets[k][f] = Some(Vec3::new(across.x, lifted.y + step, across.z));
                                    stepping[k][f] = swing[k] > w;
                                }
                            }
                        }
                        Release::CatchUp { speed } => {
                            // From where it was on the previous frame (held or catching up),
                            // its gap to the free path closed by at most `speed`: the foot moves
                            // with its free path (a dancer travelling faster than `speed` would
                            // never be caught up with) and closes on it.
                            if let Some(prev) = f.checked_sub(1).and_then(|g| targets[k][g]) {
                                let was = t.free_ankle[f - 1] + body.as_ref().map_or(shift[f - 1], |b| b[f - 1]);
                                let gap = flat(prev) - flat(was);
                                let step = speed.max(0.0) / fps;
                                let len = gap.length();
                                if len > step.max(1e-4) {
                                    let p = flat(free) + gap * (1.0 - step / len);
                                    targets[k][f] = Some(Vec3::new(p.x, free.y, p.z));
                                }
                            }
                        }
                    }
                    continue;
                };
                let lead = if c == Contact::Toe { toe_from_ankle(k, f) } else { Vec3::ZERO };
                let lands = point[k].is_none();
                // A frame at the foot's free height: left free, or eased past its height.
                let eased_since = last[k].map(|(_, end)| end).filter(|_| matches!(release, Release::Ease { over_swing: true }));
                let at_free_height = |tg: &[Option<Vec3>], g: usize| tg[g].is_none() || eased_since.is_some_and(|end| g > end + w);
                let p = match point[k] {
                    Some((c0, p)) if c0 == c => p,
                    // Lands, or changes point: where the ankle was on the previous frame (its
                    // target, or where the body put it).
                    _ => flat(f.checked_sub(1).and_then(|g| targets[k][g]).unwrap_or(free)) + lead,
                };
                point[k] = Some((c, p));
                let ankle = p - lead;
                let target = Vec3::new(ankle.x, t.src_ankle[f].y + t.y_offset, ankle.z);
                // Landing again within a release ease: the ease kept the height it was held at
                // while the source's foot went up or down (faster than the ease), and the new
                // hold sits at the source's height. Spread that step in height over the eased
                // frames, so the foot does not snap to it in one.
                if lands {
                    if let Some((_, end)) = last[k].filter(|&(_, end)| matches!(release, Release::Ease { .. }) && end + 1 < f && f - end <= w + 1) {
                        if let Some(prev) = targets[k][f - 1] {
                            let step = target.y - prev.y;
                            for g in end + 1..f {
                                if let Some(eased) = targets[k][g].as_mut() {
                                    eased.y += step * (g - end) as f32 / (f - end) as f32;
                                }
                            }
                        }
                    } else if f > 0 && at_free_height(&targets[k], f - 1) {
                        // Landing from the free path: a rig that lifts its foot higher than
                        // the source (a longer foot, straightened legs) comes down to the
                        // source's height over the frames before, on its (shifted) free path,
                        // not in one.
                        // Only frames at their free height: left free, or a release ease's past
                        // its height (its swing, `Release::Ease`), which keep their place.
                        // The step is how much higher the free path is than the hold at the
                        // landing frame itself: measured against the frame before, it also held
                        // the foot's own last frame of descent, and a figure whose free path is
                        // its source (a rendered dance) landed a frame early (6.3 mm high).
                        let mut start = f;
                        while start > f.saturating_sub(w + 1) && at_free_height(&targets[k], start - 1) {
                            start -= 1;
                        }
                        let step = target.y - t.free_ankle[f].y;
                        for g in start..f {
                            let at = body.as_ref().map_or(shift[g], |b| b[g]);
                            let s = (g + 1 - start) as f32 / (f - start + 1) as f32;
                            let on = t.free_ankle[g] + at + Vec3::Y * (step * s);
                            targets[k][g] = Some(match targets[k][g] {
                                Some(eased) => Vec3::new(eased.x, eased.y + step * s, eased.z),
                                None => on,
                            });
                        }
                    }
                }
                targets[k][f] = Some(target);
                last[k] = Some((target, f));
                sum += ankle - flat(t.free_ankle[f]);
                count += 1;
            }
            if count > 0 {
                offset = sum / count as f32;
            }
            shift[f] = offset;
        }
        if plan == 0 {
            body = Some(smooth(&shift));
        }
    }
    (targets, body.unwrap_or_else(|| vec![Vec3::ZERO; frames]), stepping)
}

/// The most [`toe_clearance`] pitches a foot up: a quarter turn (a foot pointed straight down
/// brought level), however far below the source's its toe would be.
pub(super) const TOE_PITCH_MAX_RAD: f32 = std::f32::consts::FRAC_PI_2;

/// Keeps the character's toe off the floor where the source's is: wherever the source's toe
/// is on its floor (within the contact rule's band, [`CONTACT_HEIGHT_M`], taken at the
/// character's size: the clearance was measured so) and the character's toe
/// would go lower than it (at the character's size, on the character's ground:
/// `toe_y_offset`), the foot is pitched up about its ankle hinge (`hinge`: the horizontal
/// axis across the foot at rest, as the transfer turns the foot on each frame) just enough to
/// lift the toe to the source's height. Returns the world turn per leg and frame (`None`: the
/// foot as the transfer turns it), applied on top of the foot's world rotation.
/// - Why: a rig whose foot is longer than the source's and whose ankle is lower
///   (RobotExpressive's) points its toe deeper when the source points its foot. In
///   "step-touch + claps" the robot's toe went 5–6 cm under its ground while the source
///   dragged the ball of its foot along the floor, while its heel rose on a held ankle, and
///   on a one-frame hold on the ball. A toe under the floor is wrong to see, and it lowers
///   the toe's measured floor (spec §J's 1st percentile), so its slow flat-foot frames fall
///   out of the 5 cm contact band and its skate reads as the drags alone.
/// - Why the foot and not the ankle: the ankle stays where the transfer or the hold puts it,
///   so a held ankle stays held and the legs keep the source's directions (raising the ankle
///   by the leg's IK instead bent the robot's knees: its direction p95 rose 0.5°).
/// - Only raised, never lowered: a toe higher than the source's is the rig's shape (a shorter
///   foot) and is left, and a foot is turned no further than level with its ankle (nor more
///   than [`TOE_PITCH_MAX_RAD`]).
/// - Every such frame counts, held or not (a heel rising on a held ankle, a foot held on its
///   ball, a release ease), but one where the transfer sweeps the toe faster than the source's
///   by more than a planted foot moves ([`CONTACT_SPEED_M_S`], at the character's size): its
///   path there is the rig's own
///   (a body with wider hips turning round a held foot, as in pivot turns), not the source's
///   contact, and putting it on the floor would draw a slide the source does not make. A foot
///   in the air keeps the transfer's pose (a pointed foot lifted in a kick is not turned).
/// - The pitch is smoothed as the pelvis drop is (a running maximum, then a running mean over
///   ±[`RELEASE_S`]), so the foot turns into and out of it over several frames, never in one.
pub(super) fn toe_clearance(feet: &[FootTracks], hinge: &[Vec<Vec3>], toe_y_offset: &[f32], shift: &[Vec3], targets: &[Vec<Option<Vec3>>], fps: f32) -> Vec<Vec<Option<Quat>>> {
    let mut turns = Vec::with_capacity(feet.len());
    for (k, t) in feet.iter().enumerate() {
        let frames = targets[k].len().min(t.src_ankle.len()).min(t.free_ankle.len());
        let mut leg_turns = vec![None; targets[k].len()];
        if frames == 0 || t.src_toe.len() < frames || t.free_toe.len() < frames || hinge[k].len() < frames {
            turns.push(leg_turns);
            continue;
        }
        // The source's toe is on its floor within spec §J's contact band.
        let heights: Vec<f32> = t.src_toe[..frames].iter().map(|p| p.y).collect();
        let Some(floor) = motion::floor_height(&heights) else {
            turns.push(leg_turns);
            continue;
        };
        // Horizontal speed of a track over frames f−1..f+1, cm/s (`shift`: the body's move).
        let speed_cm_s = |track: &[Vec3], f: usize, moved: bool| {
            let (a, b) = (f.saturating_sub(1), (f + 1).min(frames - 1));
            let d = track[b] - track[a] + if moved { shift[b] - shift[a] } else { Vec3::ZERO };
            Vec3::new(d.x, 0.0, d.z).length() * fps * 100.0 / (b - a).max(1) as f32
        };
        let mut pitch = vec![0.0f32; frames];
        for f in 0..frames {
            if t.src_toe[f].y - floor >= CONTACT_HEIGHT_M || speed_cm_s(&t.free_toe, f, true) > speed_cm_s(&t.src_toe, f, false) + CONTACT_SPEED_M_S * 100.0 {
                continue;
            }
            // The foot, ankle to toe, as the transfer turns it (the IK leaves the foot its
            // world rotation). Turned by θ about the hinge h, its toe's height from the ankle
            // is p + a·cos θ + b·sin θ = p + m·cos(θ − top).
            let (v, h) = (t.free_toe[f] - t.free_ankle[f], hinge[k][f]);
            let along = h * h.dot(v);
            let u = v - along;
            let (p, a, b) = (along.y, u.y, h.cross(u).y);
            let m = (a * a + b * b).sqrt();
            if m < 1e-6 {
                continue;
            }
            // The toe-up turn that takes the toe highest, in [0, 2π): a foot pointed past
            // straight down (b < 0) first goes a little lower, then up.
            let top = fmath::atan2(b, a).rem_euclid(std::f32::consts::TAU);
            let level = (top - fmath::acos((-p / m).clamp(-1.0, 1.0))).clamp(0.0, top).min(TOE_PITCH_MAX_RAD);
            let at = targets[k][f].unwrap_or(t.free_ankle[f] + shift[f]);
            let want = (t.src_toe[f].y + toe_y_offset[k] - at.y).min(0.0);
            if want > p + a {
                pitch[f] = (top - fmath::acos(((want - p) / m).clamp(-1.0, 1.0))).clamp(0.0, level);
            }
        }
        let w = ((RELEASE_S * fps).round() as usize).max(1);
        let window = |f: usize| f.saturating_sub(w)..(f + w + 1).min(frames);
        let most: Vec<f32> = (0..frames).map(|f| pitch[window(f)].iter().copied().fold(0.0, f32::max)).collect();
        for f in 0..frames {
            let turn = most[window(f)].iter().sum::<f32>() / window(f).len() as f32;
            if turn > 1e-5 {
                leg_turns[f] = Some(Quat::from_axis_angle(hinge[k][f], turn));
            }
        }
        turns.push(leg_turns);
    }
    turns
}

/// How far the pelvis drops on each frame so every held foot is within reach of its hip
/// (legs nearly straight at most), smoothed so the body does not bob: a running maximum then
/// a running mean over ±[`RELEASE_S`]. Not for a stepping foot (`stepping`, from
/// [`hold_plan_stepping`]): a foot travelling a long way to its free path reaches as far as
/// its leg does (dropping the body to its height bent the held leg off its planted frames).
pub(super) fn pelvis_drop(legs: &[Leg], hips: &[Vec<Vec3>], targets: &[Vec<Option<Vec3>>], stepping: &[Vec<bool>], fps: f32) -> Vec<f32> {
    let frames = targets.first().map_or(0, |t| t.len());
    let mut raw = vec![0.0f32; frames];
    for (k, leg) in legs.iter().enumerate() {
        let reach = (leg.thigh_m + leg.shin_m) * 0.995;
        for f in 0..frames {
            let Some(goal) = targets[k][f] else { continue };
            if stepping.get(k).and_then(|s| s.get(f)).copied().unwrap_or(false) {
                continue;
            }
            let d = goal - hips[k][f];
            let across = Vec3::new(d.x, 0.0, d.z).length();
            // Lowering the hip by y brings it to |d + y·Y| = reach: y = −d.y − √(reach² − across²).
            let y = if across < reach { -d.y - (reach * reach - across * across).sqrt() } else { -d.y };
            raw[f] = raw[f].max(y.max(0.0));
        }
    }
    let w = ((RELEASE_S * fps).round() as usize).max(1);
    let window = |f: usize| f.saturating_sub(w)..(f + w + 1).min(frames);
    let held: Vec<f32> = (0..frames).map(|f| raw[window(f)].iter().copied().fold(0.0, f32::max)).collect();
    (0..frames).map(|f| held[window(f)].iter().sum::<f32>() / window(f).len() as f32).collect()
}

/// The joints whose world position pass 1 of [`super::Character::play`] reads (what it hands back is
/// local rotations and the tracks' translations): each leg's hip (its IK starts there), the
/// joint a detached one hangs from, the parent of the hips and of a detached joint (their
/// translations are read from it), and every joint one of those is posed from. The others'
/// positions (spine, arms, head, knees, feet) it need not compute.
pub(super) fn held_pass_positions(skeleton: &Skeleton, hips: usize, legs: &[Leg], detached: &[Option<(usize, Vec3)>]) -> Vec<bool> {
    let n = skeleton.len();
    let parent = |i: usize| skeleton.joints.get(i).and_then(|j| j.parent).filter(|&q| q < i);
    let mut read = vec![false; n];
    let mut mark = |i: usize| {
        if let Some(r) = read.get_mut(i) {
            *r = true;
        }
    };
    legs.iter().for_each(|l| mark(l.hip));
    parent(hips).into_iter().for_each(&mut mark);
    for (i, d) in detached.iter().enumerate() {
        if let Some((jp, _)) = d {
            mark(*jp);
            parent(i).into_iter().for_each(&mut mark);
        }
    }
    for i in (0..n).rev() {
        if let Some(q) = parent(i).filter(|_| read[i]) {
            read[q] = true;
        }
    }
    read
}

/// The joints of `skeleton` pass 0 of [`super::Character::play`] reads: `hips`, each leg's hip, knee,
/// foot and toe, and every joint one of those is posed from (its parent before it, or the
/// joint a detached one hangs from, `detached`). The rest (spine, arms, head) pass 0 need not
/// pose: what it keeps is where the feet, hips and ankle hinges go, and each frame of pass 1
/// poses every joint anew.
pub(super) fn free_pass_joints(skeleton: &Skeleton, hips: usize, legs: &[Leg], detached: &[Option<(usize, Vec3)>]) -> Vec<bool> {
    let n = skeleton.len();
    let mut reads = vec![false; n];
    for i in std::iter::once(hips).chain(legs.iter().flat_map(|l| [Some(l.hip), Some(l.knee), Some(l.foot), l.toe]).flatten()) {
        if let Some(r) = reads.get_mut(i) {
            *r = true;
        }
    }
    loop {
        let mut grew = false;
        for i in 0..n {
            if !reads[i] {
                continue;
            }
            let from = [skeleton.joints[i].parent.filter(|&q| q < i), detached[i].map(|d| d.0)];
            for q in from.into_iter().flatten() {
                grew |= !std::mem::replace(&mut reads[q], true);
            }
        }
        if !grew {
            return reads;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Issue 27: a foot held while the rig's free path sweeps it a long way off (a body with wide
    /// hips turning on the other foot), then released into a swing, steps back to its free path,
    /// lifted, within the swing, where the control (over [`RELEASE_S`]) snaps it back.
    #[test]
    fn a_foot_released_far_from_its_free_path_steps_back_over_its_swing() {
        let (fps, frames) = (30.0, 60);
        let still = |x: f32| -> Vec<Vec3> { (0..frames).map(|_| Vec3::new(x, 0.08, 0.0)).collect() };
        // Right foot: planted for frames 0..20 and from 40, in the air between; its free path
        // sweeps 1 m away over frames 0..20 (5 cm a frame) and stays there.
        let src_r: Vec<Vec3> = (0..frames).map(|f| Vec3::new(-0.2, if (20..40).contains(&f) { 0.3 } else { 0.08 }, 0.0)).collect();
        let free_r: Vec<Vec3> = (0..frames).map(|f| Vec3::new(-0.2 - 0.05 * f.min(20) as f32, src_r[f].y, 0.0)).collect();
        let feet = |_: ()| {
            [
                FootTracks { src_ankle: still(0.2), src_toe: Vec::new(), free_ankle: still(0.2), free_toe: Vec::new(), y_offset: 0.0, scale: 1.0 },
                FootTracks { src_ankle: src_r.clone(), src_toe: Vec::new(), free_ankle: free_r.clone(), free_toe: Vec::new(), y_offset: 0.0, scale: 1.0 },
            ]
        };
        let moves = |over_swing: bool| -> (f32, f32) {
            let (targets, shift, _) = hold_plan_stepping(&feet(()), fps, None, Release::Ease { over_swing });
            let at = |f: usize| targets[1][f].unwrap_or(free_r[f] + shift[f]);
            let flat = |v: Vec3| Vec3::new(v.x, 0.0, v.z);
            let worst = (21..40).map(|f| (flat(at(f)) - flat(at(f - 1))).length()).fold(0.0, f32::max);
            let lift = (21..40).map(|f| at(f).y - free_r[f].y).fold(f32::MIN, f32::max);
            (worst, lift)
        };
        let (eased, eased_lift) = moves(false);
        let (stepped, lift) = moves(true);
        // The gap is closed in 6 frames by the control, over the swing by the hold (measured:
        // 0.255 against 0.084 m in the worst frame, the body's shift included), the foot lifted
        // clear of the contact band meanwhile.
        assert!(eased > 0.15, "control: {eased}");
        assert!(stepped < eased / 2.0 && stepped < 0.1, "hold: {stepped} (control {eased})");
        assert!(lift > CONTACT_HEIGHT_M && eased_lift < 1e-4, "lift {lift}, control {eased_lift}");
    }
}
