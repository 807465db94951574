//! Retargeting onto a character (spec §L): a humanoid clip played by an imported skinned
//! character (Xbot's `mixamorig:` rig, RobotExpressive, VRM bone names), twist included.
//!
//! The motion is carried as each canonical bone's rotation away from its reference pose, in
//! world axes (D = G · R⁻¹, G the bone's world rotation, R its reference world rotation);
//! the character's mapped bone then gets world rotation D · R_character and its local rotation
//! follows from its own parent's pose. This is the spec's conjugation N = W · L⁻¹ · Local · W⁻¹,
//! Local' = L' · W'⁻¹ · N · W' composed down each chain: a full rotation, so forearm and hand
//! roll reach the skin (the direction-only transfer of `retarget.rs` loses it).
//! - Reference pose: both rigs in T-pose. The canonical skeleton's rest is one; the
//!   character's rest bones are each swung once onto the canonical rest direction of the same
//!   bone, which turns an A-pose (or bent elbows, or splayed legs) into the T-pose while
//!   keeping each bone's roll.
//! - A canonical bone the character lacks (no chest, no shoulders) has no joint to set: the
//!   world rotation of the next mapped bone down the chain already includes it (folded).
//!   Character joints no canonical bone maps to (extra spine joints, fingers, twist helpers)
//!   keep their rest rotation and follow their parent.
//! - Root: the hips follow the source's hips scaled by the ratio of leg lengths (thigh +
//!   shin), raised by what the rig's bent rest legs gain when straightened.
//! - Planted feet: where the source's ankle is planted (near its floor and slow), the
//!   character's ankle is held where it landed, at the source's ankle height on the
//!   character's ground; where only the source's toe is planted (the heel up: turning on the
//!   ball of the foot, as in pivot turns) the character's toe is held and its ankle circles
//!   round it. The legs reach by the kernel's two-bone IK (`motion::two_bone_rotations`). The body
//!   shifts horizontally (smoothly) to keep held feet put — a rig with wider hips than the
//!   source's, turning on one foot, must move round it — so the character's path can drift
//!   from the source's scaled one; the pelvis drops where a held foot would be out of reach
//!   (a foot not held then keeps its free path by IK, so the drop does not drag a step down
//!   onto the floor), and a released foot eases back onto its free path (one released far
//!   from it — the other foot of a wide rig turning on one, as RobotExpressive's pivot turns —
//!   steps there, lifted, over its swing rather than snapping back). A landing foot comes
//!   down to the hold's height (the source's) over the frames before it, on its free path or
//!   over the release ease it lands within, not in one frame: a rig that lifts its foot
//!   higher than the source (RobotExpressive's longer feet) would otherwise snap down.
//!   Where the source's toe is on the floor, the character's is kept off it: a rig whose foot
//!   is longer or whose ankle is lower than the source's (RobotExpressive's) would point its
//!   toe through the floor, so its foot is pitched up about the ankle, smoothly over several
//!   frames (`toe_clearance`).
//!   The benchmark prints the skate against the source's and against the free-feet control
//!   (`tests/bench/retarget.rs`).
//! - A motion-capture take's calibration frame (frame 0 in its skeleton's rest pose, as in
//!   the CMU files) is not played: the character starts in the take's first real pose. The
//!   report measures the source without it too.

use crate::fmath;
use std::sync::Arc;

use glam::{Quat, Vec3};
use thiserror::Error;

use crate::canon::builtin::canonical_skeleton;
use crate::clip::{Clip, TranslationTrack};
use crate::canon::humanoid::{Canon, HumanoidMap, HumanoidStatus, CANON_COUNT};
use crate::import::{Imported, SkinnedMesh};
use crate::motion;
use crate::canon::retarget::{is_canonical, to_canonical};
use crate::skeleton::Skeleton;

mod hold;

use hold::*;
pub(crate) use hold::{hold_feet_in_dance, FreePass, DANCE_CATCH_UP_M_S};

/// Why a character cannot play humanoid motion, naming what is missing.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum CharacterError {
    #[error("{file}: the character has no skinned mesh to put the motion on (a skeleton or animation file only)")]
    NoSkin { file: String },
    #[error("{file}: not a humanoid character: {reason}")]
    NotHumanoid { file: String, reason: String },
    #[error("{file}: the rig lacks limbs a dance needs: {}", missing.join(", "))]
    MissingLimbs { file: String, missing: Vec<String> },
    #[error("the motion '{clip}' is not humanoid: {reason}")]
    SourceNotHumanoid { clip: String, reason: String },
}

impl CharacterError {
    pub fn kind(&self) -> &'static str {
        match self {
            CharacterError::NoSkin { .. } => "character-no-skin",
            CharacterError::NotHumanoid { .. } => "character-not-humanoid",
            CharacterError::MissingLimbs { .. } => "character-missing-limbs",
            CharacterError::SourceNotHumanoid { .. } => "motion-not-humanoid",
        }
    }
}

/// Canonical bones a character must have to dance (the rest may fold).
const REQUIRED: [Canon; 15] = [
    Canon::Hips,
    Canon::Head,
    Canon::LeftUpperArm,
    Canon::LeftForearm,
    Canon::LeftHand,
    Canon::RightUpperArm,
    Canon::RightForearm,
    Canon::RightHand,
    Canon::LeftUpperLeg,
    Canon::LeftLowerLeg,
    Canon::LeftFoot,
    Canon::RightUpperLeg,
    Canon::RightLowerLeg,
    Canon::RightFoot,
    Canon::Spine,
];

/// The bone whose direction orients canonical joint `c` in the reference pose: (from, to).
/// Ends of chains (hands, head, toes) take their parent bone's direction.
fn direction_bone(c: Canon) -> (Canon, Canon) {
    use Canon::*;
    match c {
        Hips => (Hips, Spine),
        Spine => (Spine, Chest),
        Chest => (Chest, Neck),
        Neck | Head => (Neck, Head),
        LeftShoulder => (LeftShoulder, LeftUpperArm),
        LeftUpperArm => (LeftUpperArm, LeftForearm),
        LeftForearm | LeftHand => (LeftForearm, LeftHand),
        RightShoulder => (RightShoulder, RightUpperArm),
        RightUpperArm => (RightUpperArm, RightForearm),
        RightForearm | RightHand => (RightForearm, RightHand),
        LeftUpperLeg => (LeftUpperLeg, LeftLowerLeg),
        LeftLowerLeg => (LeftLowerLeg, LeftFoot),
        LeftFoot | LeftToe => (LeftFoot, LeftToe),
        RightUpperLeg => (RightUpperLeg, RightLowerLeg),
        RightLowerLeg => (RightLowerLeg, RightFoot),
        RightFoot | RightToe => (RightFoot, RightToe),
    }
}

/// How each bone's rotation is carried over.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Transfer {
    /// Full rotation by rest-pose conjugation (twist kept): the product's method.
    #[default]
    Conjugate,
    /// Only the bone's direction (the shortest swing from the reference onto the source's
    /// direction; twist lost): the control the benchmark compares against.
    DirectionOnly,
}

/// The spec §L checks of a retargeted clip against its source, on the canonical joints.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct RetargetReport {
    /// Angle between source and character bone directions over every mapped canonical bone
    /// (each joint's own bone, e.g. upper arm → forearm; not the feet, which keep each rig's
    /// rest slope) and frame, radians: median and 95th percentile.
    pub direction_median_rad: f32,
    pub direction_p95_rad: f32,
    /// Roll about the forearm and hand bones (the angle between the source's and the
    /// character's perpendicular axis, in the plane across the bone), radians: median, p95.
    pub twist_median_rad: f32,
    pub twist_p95_rad: f32,
    /// Foot skate (spec §J: ankles and toes within 5 cm of their floor), cm/s: mean, p95.
    pub source_skate_mean_cm_s: f32,
    pub source_skate_p95_cm_s: f32,
    pub skate_mean_cm_s: f32,
    pub skate_p95_cm_s: f32,
    /// The largest one-frame move of each foot joint (left ankle, left toe, right ankle,
    /// right toe; 0 where the rig lacks it), m: the character's, and the source's at the
    /// character's size (scaled by the ratio of leg lengths). A held foot dragged out of
    /// reach, or snapping back onto its path, shows here as a jump the source never makes.
    pub foot_jump_m: [f32; 4],
    pub source_foot_jump_m: [f32; 4],
}

impl RetargetReport {
    /// How much further any foot joint moves in one frame than the source's same joint ever
    /// does (at the character's size), m: the largest of the four differences.
    pub fn foot_jump_excess_m(&self) -> f32 {
        (0..4).map(|k| self.foot_jump_m[k] - self.source_foot_jump_m[k]).fold(f32::NEG_INFINITY, f32::max)
    }
}

/// Mean height of the two hip (thigh) joints above their ankles, metres (at least 1 mm).
fn hip_height(map: &HumanoidMap, rest_pos: &[Vec3]) -> f32 {
    let mut sum = 0.0;
    let mut n = 0;
    for (ul, foot) in [(Canon::LeftUpperLeg, Canon::LeftFoot), (Canon::RightUpperLeg, Canon::RightFoot)] {
        if let (Some(a), Some(b)) = (map.get(ul), map.get(foot)) {
            sum += rest_pos[a].y - rest_pos[b].y;
            n += 1;
        }
    }
    if n == 0 {
        1.0
    } else {
        (sum / n as f32).max(1e-3)
    }
}

/// Mean length of the two legs (thigh plus shin bone, hip joint to ankle), metres (at least
/// 1 mm): the size the root's motion scales by. It is the hip height once the legs are
/// straightened into the reference pose, which a rig standing with bent or splayed legs at
/// rest (RobotExpressive) is not.
fn leg_length(map: &HumanoidMap, rest_pos: &[Vec3]) -> f32 {
    let mut sum = 0.0;
    let mut n = 0;
    for (ul, ll, foot) in [(Canon::LeftUpperLeg, Canon::LeftLowerLeg, Canon::LeftFoot), (Canon::RightUpperLeg, Canon::RightLowerLeg, Canon::RightFoot)] {
        if let (Some(a), Some(b), Some(c)) = (map.get(ul), map.get(ll), map.get(foot)) {
            sum += (rest_pos[b] - rest_pos[a]).length() + (rest_pos[c] - rest_pos[b]).length();
            n += 1;
        }
    }
    if n == 0 {
        1.0
    } else {
        (sum / n as f32).max(1e-3)
    }
}

/// The canonical joint below `c` on its chain toward the head or the hands (for a bone whose
/// canonical child the rig lacks: a spine without a chest points at the neck).
fn next_down(c: Canon) -> Option<Canon> {
    use Canon::*;
    Some(match c {
        Spine => Chest,
        Chest => Neck,
        Neck => Head,
        LeftShoulder => LeftUpperArm,
        RightShoulder => RightUpperArm,
        _ => return None,
    })
}

/// A character ready to play canonical motion: its rig, mesh, mapping and reference pose.
#[derive(Clone, Debug)]
pub struct Character {
    pub name: String,
    pub skeleton: Arc<Skeleton>,
    pub mesh: SkinnedMesh,
    pub map: HumanoidMap,
    /// Reference (T-pose) world rotation per canonical joint, for mapped joints.
    reference: [Quat; CANON_COUNT],
    /// Height of the hip joints (thighs) above the ankles at rest, metres: the leg length
    /// that scales the root's motion (a rig whose hips joint sits high in the body, as
    /// RobotExpressive's `Body` does, is not taken for long-legged).
    hip_height_m: f32,
    /// Mean leg length (thigh + shin), metres: what the root's motion scales by.
    leg_length_m: f32,
    /// Rest world position of the hips joint.
    hips_rest: Vec3,
    /// How far the character's upper arms were swung to reach the T-pose, radians (0 for a
    /// T-pose rig, about 0.7–0.8 for an A-pose one): reported, not used.
    pub arm_swing_rad: f32,
}

impl Character {
    /// Checks that an imported file can play humanoid motion and builds its reference pose.
    pub fn from_imported(file: &str, im: &Imported) -> Result<Character, CharacterError> {
        Self::from_parts(file, im.skeleton.clone(), im.mesh.as_ref(), &im.humanoid, &im.status)
    }

    /// The same checks from the pieces a library keeps of an imported file.
    pub fn from_parts(
        file: &str,
        skeleton: Arc<Skeleton>,
        mesh: Option<&SkinnedMesh>,
        map: &HumanoidMap,
        status: &HumanoidStatus,
    ) -> Result<Character, CharacterError> {
        let mesh = mesh.cloned().ok_or_else(|| CharacterError::NoSkin { file: file.to_string() })?;
        if let HumanoidStatus::NotHumanoid { reason } = status {
            return Err(CharacterError::NotHumanoid { file: file.to_string(), reason: reason.clone() });
        }
        let missing: Vec<String> = REQUIRED.iter().filter(|c| map.get(**c).is_none()).map(|c| c.name().to_string()).collect();
        if !missing.is_empty() {
            return Err(CharacterError::MissingLimbs { file: file.to_string(), missing });
        }
        Ok(Self::build(file, skeleton, mesh, map.clone()))
    }

    fn build(name: &str, skeleton: Arc<Skeleton>, mesh: SkinnedMesh, map: HumanoidMap) -> Character {
        let (rest_rot, rest_pos) = motion::rest_world(&skeleton);
        let canon = canonical_skeleton();
        let canon_pos = canon.rest_positions();
        let mut reference = [Quat::IDENTITY; CANON_COUNT];
        let mut arm_swing_rad = 0.0f32;
        for c in Canon::ALL {
            let Some(j) = map.get(c) else { continue };
            let (a, mut b) = direction_bone(c);
            while map.get(b).is_none() {
                match next_down(b) {
                    Some(d) => b = d,
                    None => break,
                }
            }
            // Feet keep the rig's rest orientation: a rig stands with its feet flat on the
            // floor at rest, as the canonical one does, whatever way its foot bone points
            // (RobotExpressive's runs flat along a long foot, the canonical one slopes to the toe).
            let flat_foot = matches!(c, Canon::LeftFoot | Canon::RightFoot | Canon::LeftToe | Canon::RightToe);
            let swing = match (map.get(a), map.get(b)) {
                _ if flat_foot => Quat::IDENTITY,
                (Some(ja), Some(jb)) => {
                    let have = rest_pos[jb] - rest_pos[ja];
                    let want = canon_pos[b.index()] - canon_pos[a.index()];
                    motion::shortest_arc(have, want)
                }
                _ => Quat::IDENTITY,
            };
            if matches!(c, Canon::LeftUpperArm | Canon::RightUpperArm) {
                arm_swing_rad = arm_swing_rad.max(swing.angle_between(Quat::IDENTITY));
            }
            reference[c.index()] = (swing * rest_rot[j]).normalize();
        }
        let hip_height_m = hip_height(&map, &rest_pos);
        let leg_length_m = leg_length(&map, &rest_pos);
        let hips_rest = map.get(Canon::Hips).map(|j| rest_pos[j]).unwrap_or(Vec3::ZERO);
        Character { name: name.to_string(), skeleton, mesh, map, reference, hip_height_m, leg_length_m, hips_rest, arm_swing_rad }
    }

    /// Height of the hip (thigh) joints above the ankles in the rest pose, metres.
    pub fn hip_height_m(&self) -> f32 {
        self.hip_height_m
    }

    /// Mean leg length (thigh + shin bones), metres: the root's motion is scaled by the ratio
    /// of this to the source's.
    pub fn leg_length_m(&self) -> f32 {
        self.leg_length_m
    }

    /// The factor from the canonical skeleton's size to this character's (leg lengths).
    pub fn scale_from_canonical(&self) -> f32 {
        let canon = canonical_skeleton();
        self.leg_length_m / leg_length(&HumanoidMap::from_skeleton(&canon), &canon.rest_positions())
    }

    /// The motion of `clip` (any humanoid clip; `clip_map` its mapping) played by this
    /// character, at the clip's frame rate, as a clip on the character's skeleton.
    pub fn retarget(&self, clip: &Clip, clip_map: &HumanoidMap) -> Result<Clip, CharacterError> {
        self.retarget_with(clip, clip_map, Transfer::Conjugate)
    }

    /// [`Character::retarget`] with a choice of transfer (the direction-only one is the
    /// benchmark's control).
    pub fn retarget_with(&self, clip: &Clip, clip_map: &HumanoidMap, transfer: Transfer) -> Result<Clip, CharacterError> {
        self.retarget_options(clip, clip_map, &RetargetOptions { transfer, ..Default::default() })
    }

    /// [`Character::retarget`] with every choice spelled out (the benchmark's controls).
    pub fn retarget_options(&self, clip: &Clip, clip_map: &HumanoidMap, options: &RetargetOptions) -> Result<Clip, CharacterError> {
        self.play(clip, clip_map, options, None, None, None)
    }

    /// [`Character::retarget_options`], with the planted frames and the release given instead
    /// of read from the source ([`hold_feet_in_dance`]), and pass 0 kept in `free` (taken from
    /// it when it holds this clip's: [`FreePass`]). `only`: the frames the caller reads (the
    /// rest, not posed, repeat the last posed frame's pose: placeholders, [`hold_feet_in_dance`]).
    fn play(&self, clip: &Clip, clip_map: &HumanoidMap, options: &RetargetOptions, given: Option<&GivenHolds>, mut free: Option<&mut Option<FreePass>>, only: Option<&[bool]>) -> Result<Clip, CharacterError> {
        let transfer = options.transfer;
        let status = clip_map.status(&clip.skeleton, Some(clip));
        if let HumanoidStatus::NotHumanoid { reason } = status {
            return Err(CharacterError::SourceNotHumanoid { clip: clip.name.clone(), reason });
        }
        // A canonical clip is read as it is (a held pass of a rendered dance: no copy of it),
        // copied only where its calibration frame is rewritten.
        let mut src = if is_canonical(&clip.skeleton) { std::borrow::Cow::Borrowed(clip) } else { std::borrow::Cow::Owned(to_canonical(clip, clip_map, clip.fps)) };
        if given.is_none() && starts_on_calibration_frame(clip, clip_map) {
            hold_first_pose(src.to_mut());
        }
        // The canonical rest is the T-pose with identity rest rotations: a source bone's world
        // rotation is already its rotation away from the reference.
        let canon = &src.skeleton;
        let canon_rest = canon.rest_positions();
        let canon_map = HumanoidMap::from_skeleton(canon);
        let scale = self.leg_length_m / leg_length(&canon_map, &canon_rest);
        // Legs straightened into the reference pose reach lower than a rig's bent rest legs
        // did: the hips rise by the difference, so straight legs stand on the rest ankles.
        let lift = Vec3::Y * (self.leg_length_m - self.hip_height_m);
        let canon_hips = canon_rest[Canon::Hips.index()];
        let (char_rest_rot, char_rest_pos) = motion::rest_world(&self.skeleton);
        let n = self.skeleton.len();
        let frames = src.frame_count();
        let hips = self.map.get(Canon::Hips).unwrap_or(0);
        let mut canon_of = vec![None; n];
        for c in Canon::ALL {
            if let Some(j) = self.map.get(c) {
                canon_of[j] = Some(c);
            }
        }
        // Joints a rig hangs outside their limb (RobotExpressive's feet are children of an
        // IK "Bone" at the root, not of the shins): each is placed where its canonical
        // parent's bone ends, with a translation of its own, after everything else is posed.
        let is_ancestor = |a: usize, mut b: usize| {
            while let Some(q) = self.skeleton.joints[b].parent {
                if q == a {
                    return true;
                }
                b = q;
            }
            false
        };
        let mut detached: Vec<Option<(usize, Vec3)>> = vec![None; n];
        for c in Canon::ALL {
            let (Some(i), Some(pc)) = (self.map.get(c), c.parent()) else { continue };
            let mut up = Some(pc);
            while let Some(u) = up.filter(|u| self.map.get(*u).is_none()) {
                up = u.parent();
            }
            if let Some(jp) = up.and_then(|u| self.map.get(u)) {
                if i != jp && !is_ancestor(jp, i) {
                    detached[i] = Some((jp, char_rest_rot[jp].inverse() * (char_rest_pos[i] - char_rest_pos[jp])));
                }
            }
        }
        let mut in_detached = vec![false; n];
        for (i, j) in self.skeleton.joints.iter().enumerate() {
            in_detached[i] = detached[i].is_some() || j.parent.is_some_and(|q| q < i && in_detached[q]);
        }
        let order: Vec<usize> = (0..n).filter(|&i| !in_detached[i]).chain((0..n).filter(|&i| in_detached[i])).collect();
        let mut track_joints = vec![hips];
        track_joints.extend((0..n).filter(|&i| detached[i].is_some() && i != hips));
        let mut tracks: Vec<TranslationTrack> = track_joints.iter().map(|&j| TranslationTrack { joint: j, values: Vec::with_capacity(frames) }).collect();
        let mut track_of = vec![usize::MAX; n];
        for (k, &j) in track_joints.iter().enumerate() {
            track_of[j] = k;
        }

        // The legs for planted-foot IK: thigh, shin and foot joints, bone lengths, and each
        // bone's vector in its joint's own frame (to swing the posed bone onto the IK's).
        let legs: Vec<Leg> = [
            (Canon::LeftUpperLeg, Canon::LeftLowerLeg, Canon::LeftFoot, Canon::LeftToe),
            (Canon::RightUpperLeg, Canon::RightLowerLeg, Canon::RightFoot, Canon::RightToe),
        ]
        .into_iter()
        .filter_map(|(a, b, c, d)| {
            let (hip, knee, foot) = (self.map.get(a)?, self.map.get(b)?, self.map.get(c)?);
            let thigh = char_rest_pos[knee] - char_rest_pos[hip];
            let shin = char_rest_pos[foot] - char_rest_pos[knee];
            Some(Leg {
                canon_knee: b,
                canon_foot: c,
                canon_toe: d,
                hip,
                knee,
                foot,
                toe: self.map.get(d).filter(|&t| t != foot),
                thigh_m: thigh.length(),
                shin_m: shin.length(),
                thigh_local: char_rest_rot[hip].inverse() * thigh,
                shin_local: char_rest_rot[knee].inverse() * shin,
            })
        })
        .collect();
        let mut leg_of = vec![usize::MAX; n];
        for (k, leg) in legs.iter().enumerate() {
            leg_of[leg.hip] = k;
            leg_of[leg.knee] = k;
        }
        // The joints pass 0 reads (its hips, legs, feet and toes, and every joint they are
        // posed from): with `free_pass_legs_only`, the only ones it poses.
        let free_reads = free_pass_joints(&self.skeleton, hips, &legs, &detached);
        let held_reads = held_pass_positions(&self.skeleton, hips, &legs, &detached);
        // Pass 0 poses the character freely and records where its feet (ankles and toes) and
        // hips go and where the source's are; the plants and the pelvis drop follow from
        // those; pass 1 poses again with the feet held.
        let hold = options.hold_feet && legs.len() == 2 && frames > 1;
        let mut feet: Vec<FootTracks> = legs
            .iter()
            .map(|leg| FootTracks {
                src_ankle: Vec::with_capacity(frames),
                src_toe: Vec::new(),
                free_ankle: Vec::with_capacity(frames),
                free_toe: Vec::new(),
                // The source's ankle height maps onto the character's: its rest ankle stands
                // where the canonical rest ankle does, scaled.
                y_offset: char_rest_pos[leg.foot].y - canon_rest[leg.canon_foot.index()].y * scale,
                scale,
            })
            .collect();
        // The same for the toe: the source's toe height onto the character's ground.
        let toe_y_offset: Vec<f32> =
            legs.iter().map(|leg| leg.toe.map_or(0.0, |toe| char_rest_pos[toe].y - canon_rest[leg.canon_toe.index()].y * scale)).collect();
        let mut free_hip: Vec<Vec<Vec3>> = vec![Vec::with_capacity(frames); legs.len()];
        // Each foot's ankle hinge (the horizontal axis across the foot at rest, in the foot
        // joint's own frame; a toe-up turn about it is positive), and its world direction on
        // each frame of pass 0: the axis `toe_clearance` pitches the foot about.
        let hinge_local: Vec<Option<Vec3>> = legs
            .iter()
            .map(|leg| {
                let toe = leg.toe?;
                let across = (char_rest_pos[toe] - char_rest_pos[leg.foot]).cross(Vec3::Y).try_normalize()?;
                Some(char_rest_rot[leg.foot].inverse() * across)
            })
            .collect();
        let mut free_hinge: Vec<Vec<Vec3>> = vec![Vec::with_capacity(frames); legs.len()];
        let mut plant_target: Vec<Vec<Option<Vec3>>> = vec![vec![None; frames]; legs.len()];
        let mut drop_m = vec![0.0f32; frames];
        let mut shift_m = vec![Vec3::ZERO; frames];

        // The world rotation the transfer gives the character's joint of canonical bone `c`.
        let canon_world = |c: Canon, src_rot: &[Quat]| -> Quat {
            match transfer {
                Transfer::Conjugate => src_rot[c.index()] * self.reference[c.index()],
                Transfer::DirectionOnly => {
                    // Swing the reference so the bone points where the source's does.
                    let (a, b) = direction_bone(c);
                    let rest_dir = canon_rest[b.index()] - canon_rest[a.index()];
                    motion::shortest_arc(rest_dir, src_rot[c.index()] * rest_dir) * self.reference[c.index()]
                }
            }
        };
        let mut rotations = Vec::with_capacity(frames * n);
        let mut src_pose = motion::WorldPose::new();
        let mut g = vec![Quat::IDENTITY; n];
        let mut p = vec![Vec3::ZERO; n];
        let mut local = vec![Quat::IDENTITY; n];
        let mut ik_shin = [Quat::IDENTITY; 2];
        // Per leg and frame, the turn that pitches the foot up to keep its toe off the floor
        // (`toe_clearance`), and which leg a foot joint is.
        let mut toe_pitch: Vec<Vec<Option<Quat>>> = vec![vec![None; frames]; legs.len()];
        let mut foot_leg = vec![usize::MAX; n];
        for (k, leg) in legs.iter().enumerate() {
            foot_leg[leg.foot] = k;
        }
        // Pass 0 kept from an earlier call on this clip ([`FreePass`]), or kept by this one.
        let src_n = src.skeleton.len();
        let fits = |c: &FreePass| c.frames == frames && c.feet.len() == legs.len() && c.src_hips.len() == frames && c.src_rotations.len() == frames * src_n;
        let reuse = hold && free.as_deref().and_then(|c| c.as_ref()).is_some_and(fits);
        if let Some(c) = free.as_deref().and_then(|c| c.as_ref()).filter(|_| reuse) {
            (feet, free_hip, free_hinge) = (c.feet.clone(), c.free_hip.clone(), c.free_hinge.clone());
        }
        let record = hold && !reuse && free.is_some();
        let (mut src_rotations, mut src_hips) = (Vec::with_capacity(if record { frames * src_n } else { 0 }), Vec::with_capacity(if record { frames } else { 0 }));
        // The source's positions on the frames the caller reads, kept for its measure of the
        // unheld dance ([`FreePass::source_positions`]).
        let keep_positions = record && options.free_pass_legs_only && only.is_some_and(|o| o.len() == frames);
        let mut src_positions = if keep_positions { vec![Vec3::ZERO; frames * src_n] } else { Vec::new() };
        for pass in if hold && !reuse { 0..2 } else { 1..2 } {
            if pass == 1 && record {
                if let Some(slot) = free.as_deref_mut() {
                    *slot = Some(FreePass {
                        frames,
                        feet: feet.clone(),
                        free_hip: free_hip.clone(),
                        free_hinge: free_hinge.clone(),
                        src_rotations: std::mem::take(&mut src_rotations),
                        src_hips: std::mem::take(&mut src_hips),
                        src_positions: std::mem::take(&mut src_positions),
                        ..FreePass::default()
                    });
                }
            }
            // The last held pass on this clip ([`HeldFrames`]): its frames whose plan is this
            // one's to the bit are copied. Kept in the free pass, so only for this clip.
            let memo_on = pass == 1 && hold && legs.len() == 2 && free.as_deref().and_then(|c| c.as_ref()).is_some_and(fits);
            let last = if memo_on { free.as_deref_mut().and_then(|c| c.as_mut()).and_then(|c| c.held.take()) } else { None };
            let last = last.filter(|m| m.keys.len() == frames && m.rotations.len() == frames * n && m.tracks.len() == tracks.len() && m.tracks.iter().all(|t| t.len() == frames));
            let mut keys: Vec<HeldKey> = Vec::with_capacity(if memo_on { frames } else { 0 });
            let (mut reused, mut posed_now) = (0usize, 0usize);
            // The source's pose per frame, as pass 0 posed it, when kept.
            let posed = free.as_deref().and_then(|c| c.as_ref()).filter(|c| pass == 1 && hold && fits(c));
            if pass == 1 && hold {
                let stepping;
                (plant_target, shift_m, stepping) = match given {
                    Some(g) => hold_plan_stepping(&feet, src.fps, Some(&g.contacts), g.release),
                    None => hold_plan_stepping(&feet, src.fps, None, Release::Ease { over_swing: options.release_over_swing }),
                };
                for hips in free_hip.iter_mut() {
                    for (h, shift) in hips.iter_mut().zip(&shift_m) {
                        *h += *shift;
                    }
                }
                drop_m = pelvis_drop(&legs, &free_hip, &plant_target, &stepping, src.fps);
                toe_pitch = toe_clearance(&feet, &free_hinge, &toe_y_offset, &shift_m, &plant_target, src.fps);
                // A foot not held, where the pelvis drops for the other, keeps its (shifted)
                // free path by IK: lowering the body must not lower the step with it — a
                // swing foot dragged down to the floor slides on it (the skate the source does
                // not have), and a standing one sinks into it. A rig much wider or longer in
                // the leg than the source drops most often (RobotExpressive); a rig in the
                // source's proportions rarely drops at all.
                for (k, targets) in plant_target.iter_mut().enumerate() {
                    for (f, t) in targets.iter_mut().enumerate() {
                        if t.is_none() && drop_m[f] > 1e-4 {
                            *t = Some(feet[k].free_ankle[f] + shift_m[f]);
                        }
                    }
                }
            }
            rotations.clear();
            for t in tracks.iter_mut() {
                t.values.clear();
            }
            for f in 0..frames {
                if memo_on {
                    let key = held_key([plant_target[0][f], plant_target[1][f]], [toe_pitch[0][f], toe_pitch[1][f]], drop_m[f], shift_m[f]);
                    keys.push(key);
                    let read = only.is_none_or(|o| o.get(f).copied().unwrap_or(true));
                    if let Some(m) = last.as_ref().filter(|m| read && m.posed[f] && m.keys[f] == key) {
                        local.copy_from_slice(&m.rotations[f * n..(f + 1) * n]);
                        rotations.extend_from_slice(&local);
                        for (t, v) in tracks.iter_mut().zip(&m.tracks) {
                            t.values.push(v[f]);
                        }
                        reused += 1;
                        continue;
                    }
                    posed_now += usize::from(read);
                }
                // The held pass poses each frame on its own (the plan holds what carries over
                // from frame to frame): a frame the caller does not read is left a placeholder.
                if pass == 1 && only.is_some_and(|o| !o.get(f).copied().unwrap_or(true)) {
                    rotations.extend_from_slice(&local);
                    for t in tracks.iter_mut() {
                        let last = t.values.last().copied().unwrap_or(Vec3::ZERO);
                        t.values.push(last);
                    }
                    continue;
                }
                let (src_rot, src_hips_now, src_pos): (&[Quat], Vec3, &[Vec3]) = match posed {
                    Some(c) => (&c.src_rotations[f * src_n..(f + 1) * src_n], c.src_hips[f], &[]),
                    None => {
                        let src_now = src_pose.of_frame(&src, f);
                        if record && pass == 0 {
                            src_rotations.extend_from_slice(&src_now.rotations);
                            src_hips.push(src_now.positions[Canon::Hips.index()]);
                            if keep_positions && only.is_some_and(|o| o[f]) && src_now.positions.len() == src_n {
                                src_positions[f * src_n..(f + 1) * src_n].copy_from_slice(&src_now.positions);
                            }
                        }
                        (&src_now.rotations, src_now.positions[Canon::Hips.index()], &src_now.positions)
                    }
                };
                // Hips target: the character's rest hips moved as the source's hips move from
                // theirs, scaled by the ratio of leg lengths, lowered where a held foot would
                // otherwise be out of reach and shifted to keep held feet put.
                let target = self.hips_rest + lift + (src_hips_now - canon_hips) * scale - Vec3::Y * drop_m[f] + shift_m[f];
                for &i in &order {
                    if pass == 0 && options.free_pass_legs_only && !free_reads[i] {
                        continue;
                    }
                    let j = &self.skeleton.joints[i];
                    let parent = j.parent.filter(|&q| q < i);
                    let (pg, pp) = parent.map(|q| (g[q], p[q])).unwrap_or((Quat::IDENTITY, Vec3::ZERO));
                    local[i] = match canon_of[i] {
                        Some(c) => (pg.inverse() * canon_world(c, &src_rot)).normalize(),
                        None => j.rest_rotation,
                    };
                    if let Some(turn) = foot_leg.get(i).and_then(|&k| toe_pitch.get(k)).and_then(|t| t[f]) {
                        local[i] = (pg.inverse() * turn * pg * local[i]).normalize();
                    }
                    g[i] = pg * local[i];
                    let t = if i == hips {
                        pg.inverse() * (target - pp)
                    } else if let Some((jp, rel)) = detached[i] {
                        pg.inverse() * (p[jp] + g[jp] * rel - pp)
                    } else {
                        j.rest_offset
                    };
                    if track_of[i] != usize::MAX {
                        tracks[track_of[i]].values.push(t);
                    }
                    if pass == 0 || held_reads[i] || !options.free_pass_legs_only {
                        p[i] = pp + pg * t;
                    }
                    // Held foot: thigh and shin turned onto the two-bone solution by the
                    // kernel's solver, at the thigh; the shin (turned from the world rotation
                    // the transfer gives it) is set when its turn comes. The foot keeps its
                    // own world rotation.
                    let k = leg_of[i];
                    if pass == 1 && k != usize::MAX {
                        if let Some(goal) = plant_target[k][f] {
                            let leg = &legs[k];
                            if i == leg.hip {
                                let shin_before = canon_world(leg.canon_knee, &src_rot);
                                let knee_now = g[i] * leg.thigh_local;
                                let solved = motion::two_bone_rotations(p[i], g[i], leg.thigh_local, leg.shin_local, |_| shin_before, goal, knee_now);
                                g[i] = solved.upper;
                                ik_shin[k] = solved.lower;
                            } else {
                                g[i] = ik_shin[k];
                            }
                            local[i] = (pg.inverse() * g[i]).normalize();
                        }
                    }
                }
                if pass == 0 {
                    for (k, leg) in legs.iter().enumerate() {
                        let t = &mut feet[k];
                        t.free_ankle.push(p[leg.foot]);
                        t.src_ankle.push(src_pos[leg.canon_foot.index()] * scale);
                        if let Some(toe) = leg.toe {
                            t.free_toe.push(p[toe]);
                            t.src_toe.push(src_pos[leg.canon_toe.index()] * scale);
                        }
                        free_hip[k].push(p[leg.hip]);
                        if let Some(h) = hinge_local[k] {
                            free_hinge[k].push(g[leg.foot] * h);
                        }
                    }
                } else {
                    rotations.extend_from_slice(&local);
                }
            }
            if memo_on {
                if let Some(c) = free.as_deref_mut().and_then(|c| c.as_mut()) {
                    let posed = (0..frames).map(|f| only.is_none_or(|o| o.get(f).copied().unwrap_or(true))).collect();
                    c.held = Some(HeldFrames { keys: std::mem::take(&mut keys), posed, rotations: rotations.clone(), tracks: tracks.iter().map(|t| t.values.clone()).collect() });
                    (c.held_reused, c.held_posed) = (c.held_reused + reused, c.held_posed + posed_now);
                }
            }
        }
        Ok(Clip {
            name: format!("{} on {}", src.name, self.name),
            source: src.source.clone(),
            fps: src.fps,
            skeleton: self.skeleton.clone(),
            rotations,
            translations: tracks,
        })
    }
}

/// A take's first frame within this angle of its skeleton's rest pose on every humanoid bone
/// is the capture's calibration frame, not motion (see [`starts_on_calibration_frame`]).
/// Capture noise on a calibration pose is a few degrees (the CMU takes: under 8°); a danced
/// pose is far from any rest pose (every built-in move's first frame: over 60°).
const CALIBRATION_FRAME_DEG: f32 = 15.0;

/// Whether `clip` opens on its skeleton's rest pose, every humanoid bone within
/// [`CALIBRATION_FRAME_DEG`] of it: the calibration frame a motion-capture take carries
/// before the take (the CMU BVH files: a T-pose facing the capture volume's axis, the dancer's
/// real first pose — turned a quarter or half turn from it — on frame 1). It is not motion: a
/// character played from it would swing its whole body round in one frame, and a rig with
/// wider hips than the source's (RobotExpressive) swings its feet a metre where the source's
/// move half that. A clip easing out of its rest pose loses nothing by starting on its
/// second frame's pose.
fn starts_on_calibration_frame(clip: &Clip, map: &HumanoidMap) -> bool {
    if clip.frame_count() < 2 {
        return false;
    }
    let first = clip.frame_rotations(0);
    let mut bones = Canon::ALL.into_iter().filter_map(|c| map.get(c)).peekable();
    bones.peek().is_some() && bones.all(|j| first[j].angle_between(clip.skeleton.joints[j].rest_rotation) < CALIBRATION_FRAME_DEG.to_radians())
}

/// Frame 0 of `clip` set to frame 1's pose (rotations and translations): the character stands
/// in the take's first real pose from the start, and the frame count (the song clock's
/// frames) is kept.
fn hold_first_pose(clip: &mut Clip) {
    let n = clip.skeleton.len();
    if clip.frame_count() < 2 {
        return;
    }
    clip.rotations.copy_within(n..2 * n, 0);
    for t in clip.translations.iter_mut() {
        if t.values.len() > 1 {
            t.values[0] = t.values[1];
        }
    }
}

/// Choices of [`Character::retarget_options`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct RetargetOptions {
    pub transfer: Transfer,
    /// Hold the character's foot where the source's foot is planted (two-bone IK, the
    /// pelvis lowered to reach); off only as a control.
    pub hold_feet: bool,
    /// A released foot closes its horizontal gap to its free path over its swing, until it
    /// lands again (`hold.rs`, `Release::Ease`); off only as the control (over 0.15 s, the hold
    /// before issue 27's mend).
    pub release_over_swing: bool,
    /// Pass 0 (the character posed freely, to plan the held feet) poses only the joints it
    /// reads: the hips and legs and what they hang from, not the spine, arms and head; and
    /// pass 1 places in the world only the joints whose positions it reads (the legs' hips and
    /// what the hips and detached joints hang from). The same clip either way; off only as the
    /// control, every joint posed and placed in both passes (`GenerateOptions::free_pass_legs_only`).
    pub free_pass_legs_only: bool,
}

impl Default for RetargetOptions {
    fn default() -> Self {
        RetargetOptions { transfer: Transfer::Conjugate, hold_feet: true, release_over_swing: true, free_pass_legs_only: true }
    }
}

/// One leg of the character for planted-foot IK.
struct Leg {
    canon_knee: Canon,
    canon_foot: Canon,
    canon_toe: Canon,
    hip: usize,
    knee: usize,
    foot: usize,
    /// The toe joint, when the rig has one (a foot can then turn on its ball).
    toe: Option<usize>,
    thigh_m: f32,
    shin_m: f32,
    thigh_local: Vec3,
    shin_local: Vec3,
}


/// The source as [`report`] measures it: on the canonical skeleton, without a take's
/// calibration frame (frame 0 given frame 1's pose). The calibration frame is not motion, for
/// the source as for the character: its swing onto the first real pose would count as the
/// source's largest foot move and as skate, and loosen both bounds.
pub fn measured_source(source: &Clip, source_map: &HumanoidMap) -> Clip {
    let mut src = if is_canonical(&source.skeleton) { source.clone() } else { to_canonical(source, source_map, source.fps) };
    if starts_on_calibration_frame(source, source_map) {
        hold_first_pose(&mut src);
    }
    src
}

/// Compares a retargeted clip with its canonical source (same frame count and rate), both
/// without a take's calibration frame ([`starts_on_calibration_frame`]).
pub fn report(source: &Clip, source_map: &HumanoidMap, character: &Character, out: &Clip) -> RetargetReport {
    let src = measured_source(source, source_map);
    let frames = src.frame_count().min(out.frame_count());
    let canon = canonical_skeleton();
    let canon_rest = canon.rest_positions();
    let (mut src_pose, mut out_pose) = (motion::WorldPose::new(), motion::WorldPose::new());
    // Foot bones keep each rig's own rest slope (see `Character::build`): not compared.
    let bones: std::collections::BTreeSet<(Canon, Canon)> =
        Canon::ALL.into_iter().map(direction_bone).filter(|(a, _)| !matches!(a, Canon::LeftFoot | Canon::RightFoot)).collect();
    let mut dir_err = Vec::new();
    let mut twist_err = Vec::new();
    let feet = [Canon::LeftFoot, Canon::LeftToe, Canon::RightFoot, Canon::RightToe];
    let mut src_tracks: Vec<Vec<Vec3>> = (0..4).map(|_| Vec::with_capacity(frames)).collect();
    let mut out_tracks: Vec<Vec<Vec3>> = (0..4).map(|_| Vec::with_capacity(frames)).collect();
    let scale = character.scale_from_canonical();
    for f in 0..frames {
        let (src_now, out_now) = (src_pose.of_frame(&src, f), out_pose.of_frame(out, f));
        let (sr, sp, cr, cp) = (&src_now.rotations, &src_now.positions, &out_now.rotations, &out_now.positions);
        // Each canonical joint's own bone (the one it turns); branch links such as hips→thigh
        // or chest→shoulder are the rig's proportions, not motion, and are not compared.
        for &(s, c) in &bones {
            let (Some(js), Some(jc)) = (character.map.get(s), character.map.get(c)) else { continue };
            if let (Some(a), Some(b)) = ((sp[c.index()] - sp[s.index()]).try_normalize(), (cp[jc] - cp[js]).try_normalize()) {
                dir_err.push(fmath::acos(a.dot(b).clamp(-1.0, 1.0)));
            }
        }
        for c in [Canon::LeftForearm, Canon::RightForearm, Canon::LeftHand, Canon::RightHand] {
            let Some(j) = character.map.get(c) else { continue };
            let (a, b) = direction_bone(c);
            let Some(axis) = (sr[c.index()] * (canon_rest[b.index()] - canon_rest[a.index()])).try_normalize() else { continue };
            // The bone's forward (+Z at the reference pose) in each, projected across the bone.
            let d_src = sr[c.index()];
            let d_out = cr[j] * character.reference[c.index()].inverse();
            let across = |v: Vec3| (v - axis * v.dot(axis)).try_normalize();
            if let (Some(u), Some(w)) = (across(d_src * Vec3::Z), across(d_out * Vec3::Z)) {
                twist_err.push(fmath::acos(u.dot(w).clamp(-1.0, 1.0)));
            }
        }
        for (k, c) in feet.iter().enumerate() {
            src_tracks[k].push(sp[c.index()] * scale);
            if let Some(j) = character.map.get(*c) {
                out_tracks[k].push(cp[j]);
            }
        }
    }
    let median_p95 = |v: &mut Vec<f32>| -> (f32, f32) {
        if v.is_empty() {
            return (0.0, 0.0);
        }
        v.sort_by(f32::total_cmp);
        (v[v.len() / 2], v[((v.len() - 1) as f32 * 0.95).round() as usize])
    };
    let (direction_median_rad, direction_p95_rad) = median_p95(&mut dir_err);
    let (twist_median_rad, twist_p95_rad) = median_p95(&mut twist_err);
    let skate = |tracks: &[Vec<Vec3>], fps: f32| -> (f32, f32) {
        let all: Vec<f32> = tracks.iter().flat_map(|t| motion::skate_speeds_cm_s(t, fps)).collect();
        motion::mean_p95(&all)
    };
    // The source's skate is measured at the character's size (its positions scaled by the
    // ratio of leg lengths), so the two figures compare.
    let (source_skate_mean_cm_s, source_skate_p95_cm_s) = skate(&src_tracks, src.fps);
    let (skate_mean_cm_s, skate_p95_cm_s) = skate(&out_tracks, out.fps);
    let jump = |tracks: &[Vec<Vec3>]| -> [f32; 4] {
        std::array::from_fn(|k| tracks[k].windows(2).map(|w| (w[1] - w[0]).length()).fold(0.0, f32::max))
    };
    let (foot_jump_m, source_foot_jump_m) = (jump(&out_tracks), jump(&src_tracks));
    RetargetReport {
        foot_jump_m,
        source_foot_jump_m,
        direction_median_rad,
        direction_p95_rad,
        twist_median_rad,
        twist_p95_rad,
        source_skate_mean_cm_s,
        source_skate_p95_cm_s,
        skate_mean_cm_s,
        skate_p95_cm_s,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::canon::builtin::demo_clip;
    use crate::library::body::builtin_body;

    #[test]
    fn canonical_character_plays_canonical_motion_unchanged() {
        let demo = demo_clip();
        let sk = demo.skeleton.clone();
        let map = HumanoidMap::from_skeleton(&sk);
        let ch = Character::build("body", sk.clone(), builtin_body(&sk), map.clone());
        assert!(ch.arm_swing_rad < 1e-3);
        // Feet free: the held feet would (rightly) differ from the source's sliding ones.
        let out = ch.retarget_options(&demo, &map, &RetargetOptions { hold_feet: false, ..Default::default() }).unwrap();
        for f in [0, 50, 120] {
            let (a, b) = (demo.world_positions(f), out.world_positions(f));
            for (x, y) in a.iter().zip(&b) {
                assert!((*x - *y).length() < 1e-4, "frame {f}: {x} vs {y}");
            }
        }
    }

    #[test]
    fn the_free_pass_posing_its_legs_alone_changes_no_frame() {
        // Feet held (pass 0 plans the holds): pass 0 posing only the hips and legs against
        // posing every joint, the control. The same clip to the bit, and on the canonical rig
        // 9 of its 21 joints posed.
        let demo = demo_clip();
        let sk = demo.skeleton.clone();
        let map = HumanoidMap::from_skeleton(&sk);
        let ch = Character::build("body", sk.clone(), builtin_body(&sk), map.clone());
        let lean = ch.retarget_options(&demo, &map, &RetargetOptions::default()).unwrap();
        let whole = ch.retarget_options(&demo, &map, &RetargetOptions { free_pass_legs_only: false, ..Default::default() }).unwrap();
        assert_eq!(lean, whole);
        let free = ch.retarget_options(&demo, &map, &RetargetOptions { hold_feet: false, ..Default::default() }).unwrap();
        assert_ne!(lean, free, "the holds changed the dance: pass 0 was read");
        let legs: Vec<Leg> = [(Canon::LeftUpperLeg, Canon::LeftLowerLeg, Canon::LeftFoot, Canon::LeftToe), (Canon::RightUpperLeg, Canon::RightLowerLeg, Canon::RightFoot, Canon::RightToe)]
            .into_iter()
            .map(|(a, b, c, d)| Leg { canon_knee: b, canon_foot: c, canon_toe: d, hip: map.get(a).unwrap(), knee: map.get(b).unwrap(), foot: map.get(c).unwrap(), toe: map.get(d), thigh_m: 0.4, shin_m: 0.4, thigh_local: Vec3::Y, shin_local: Vec3::Y })
            .collect();
        let reads = free_pass_joints(&sk, map.get(Canon::Hips).unwrap(), &legs, &vec![None; sk.len()]);
        assert_eq!(reads.iter().filter(|&&r| r).count(), 9);
    }

    #[test]
    fn a_calibration_first_frame_is_not_played() {
        // The demo with a capture's calibration frame put before it: the rest pose (every
        // rotation the rest's), facing the other way from the dance's first pose.
        let demo = demo_clip();
        let n = demo.skeleton.len();
        let map = HumanoidMap::from_skeleton(&demo.skeleton);
        let mut take = demo.clone();
        take.rotations.splice(0..0, demo.skeleton.joints.iter().map(|j| j.rest_rotation));
        for t in take.translations.iter_mut() {
            let first = t.values[0];
            t.values.insert(0, first + Vec3::X * 0.3);
        }
        take.validate().unwrap();
        assert!(starts_on_calibration_frame(&take, &map));
        assert!(!starts_on_calibration_frame(&demo, &map), "a danced first pose is motion");
        let sk = demo.skeleton.clone();
        let ch = Character::build("body", sk.clone(), builtin_body(&sk), map.clone());
        for hold_feet in [false, true] {
            let out = ch.retarget_options(&take, &map, &RetargetOptions { hold_feet, ..Default::default() }).unwrap();
            assert_eq!(out.frame_count(), take.frame_count());
            assert_eq!(&out.rotations[..n], &out.rotations[n..2 * n], "frame 0 stands in frame 1's pose");
            let (a, b) = (out.world_positions(0), out.world_positions(1));
            for (x, y) in a.iter().zip(&b) {
                assert!((*x - *y).length() < 1e-4, "hold_feet {hold_feet}: {x} vs {y}");
            }
        }
        // The dance itself is played from its first frame.
        let out = ch.retarget_options(&demo, &map, &RetargetOptions { hold_feet: false, ..Default::default() }).unwrap();
        assert!((out.world_positions(0)[0] - demo.world_positions(0)[0]).length() < 1e-4);
    }

    fn tracks(src_ankle: Vec<Vec3>, src_toe: Vec<Vec3>, free_ankle: Vec<Vec3>, free_toe: Vec<Vec3>) -> FootTracks {
        FootTracks { src_ankle, src_toe, free_ankle, free_toe, y_offset: 0.02, scale: 1.0 }
    }

    #[test]
    fn a_foot_lifted_higher_than_the_sources_lands_over_several_frames() {
        // The source's left ankle comes down at frame 20 and stays planted; the character's
        // free left ankle (a rig lifting its foot higher) is 35 cm above where the hold puts it.
        // The right foot stays in the air.
        let fps = 30.0;
        let src_l: Vec<Vec3> = (0..40).map(|f| Vec3::new(0.2, if f < 20 { 0.3 } else { 0.08 }, 0.0)).collect();
        let src_r: Vec<Vec3> = (0..40).map(|_| Vec3::new(-0.2, 0.3, 0.0)).collect();
        let free_l: Vec<Vec3> = (0..40).map(|_| Vec3::new(0.5, 0.45, 0.0)).collect();
        let free_r: Vec<Vec3> = (0..40).map(|_| Vec3::new(-0.5, 0.45, 0.0)).collect();
        let feet = [tracks(src_l, Vec::new(), free_l.clone(), Vec::new()), tracks(src_r, Vec::new(), free_r, Vec::new())];
        let (targets, shift) = hold_plan(&feet, fps);
        // Held from frame 20 at the source's height on the character's ground.
        assert!((targets[0][20].expect("held").y - 0.10).abs() < 1e-5, "{:?}", targets[0][20]);
        // Where the foot goes: its target, or its free path moved by the body.
        let at = |f: usize| targets[0][f].unwrap_or(free_l[f] + shift[f]);
        let steps: Vec<f32> = (1..40).map(|f| (at(f) - at(f - 1)).length()).collect();
        let worst = steps.iter().copied().fold(0.0, f32::max);
        assert!(worst < 0.1, "one-frame moves {steps:?}");
        // Coming down takes the frames just before the landing, on the free path; well before,
        // the foot is left free.
        assert!(targets[0][19].is_some_and(|t| t.y < 0.45 && t.y > 0.10));
        assert!(targets[0][..10].iter().all(Option::is_none));
    }

    #[test]
    fn held_foot_stays_put_while_its_free_path_slides() {
        // Left source ankle planted (on its floor, still) for frames 0..30, then lifted; the
        // character's free left ankle slides 1 cm a frame. The right source ankle swings in
        // the air, then from frame 30 brushes along its floor at 60 cm/s.
        let fps = 30.0;
        let src_l: Vec<Vec3> = (0..60).map(|f| Vec3::new(0.2, if f < 30 { 0.08 } else { 0.3 }, 0.0)).collect();
        let src_r: Vec<Vec3> = (0..60).map(|f| Vec3::new(-0.2 + 0.02 * f as f32, if f < 30 { 0.3 } else { 0.08 }, 0.0)).collect();
        let free_l: Vec<Vec3> = (0..60).map(|f| Vec3::new(0.5 + 0.01 * f as f32, 0.1, 0.0)).collect();
        let free_r: Vec<Vec3> = (0..60).map(|_| Vec3::new(-0.5, 0.4, 0.0)).collect();
        let feet = [tracks(src_l, Vec::new(), free_l, Vec::new()), tracks(src_r, Vec::new(), free_r, Vec::new())];
        let (targets, shift) = hold_plan(&feet, fps);
        // Held where it stands at the start (its free path moved by the body), at the source's
        // ankle height on the character's ground.
        let anchor = Vec3::new(0.5 + shift[0].x, 0.1, shift[0].z);
        for f in 0..30 {
            let t = targets[0][f].expect("held while planted");
            assert!((t - anchor).length() < 1e-5, "frame {f}: {t} vs {anchor}");
            assert!(targets[1][f].is_none());
        }
        // The body moves back by the slide (before smoothing: exactly), so the leg can reach.
        assert!((shift[15].x + 0.15).abs() < 0.02, "{}", shift[15]);
        // Released: eased back onto the (shifted) free path, then free.
        assert!(targets[0][31].is_some() && targets[0][59].is_none());
        let step = (targets[0][31].unwrap() - targets[0][30].unwrap_or(targets[0][29].unwrap())).length();
        assert!(step < 0.05, "no jump on release: {step}");
        // The brushing foot (on its floor but moving) is not held.
        assert!((30..60).all(|f| targets[1][f].is_none()));
    }

    #[test]
    fn a_released_dance_foot_catches_up_slowly_at_its_free_height() {
        // Both feet of a dance planted for frames 0..30 while their free paths part at 1.2 m/s
        // each (a bar played faster than recorded): the body cannot follow both, so each held
        // foot ends 60 cm from its free path. Then both are lifted, and their free paths rise
        // and stop.
        let fps = 60.0;
        let frames = 120;
        let path = |side: f32| -> Vec<Vec3> { (0..frames).map(|f| Vec3::new(side * (0.1 + 0.02 * f.min(30) as f32), if f < 30 { 0.1 } else { 0.25 }, 0.0)).collect() };
        let (free_l, free_r) = (path(1.0), path(-1.0));
        let feet = [tracks(free_l.clone(), Vec::new(), free_l.clone(), Vec::new()), tracks(free_r.clone(), Vec::new(), free_r.clone(), Vec::new())];
        let planted: Vec<Option<Contact>> = (0..frames).map(|f| (f < 30).then_some(Contact::Ankle)).collect();
        let contacts = vec![planted.clone(), planted];
        let (targets, shift) = hold_plan_with(&feet, fps, Some(&contacts), Release::CatchUp { speed: 1.0 });
        // Held where they landed.
        for f in 0..30 {
            assert!((flat_xz(targets[0][f].unwrap()) - flat_xz(targets[0][0].unwrap())).length() < 1e-5);
        }
        // Released: the gap to the free path closes at most 1 m/s, at the free path's height,
        // until the foot is on it.
        let at = |f: usize| targets[0][f].unwrap_or(free_l[f] + shift[f]);
        let gap = |f: usize| (flat_xz(at(f)) - flat_xz(free_l[f] + shift[f])).length();
        assert!(gap(29) > 0.5, "{}", gap(29));
        let mut caught = None;
        for f in 31..frames {
            assert!(gap(f - 1) - gap(f) <= 1.0 / fps + 1e-4, "frame {f}: gap {} -> {}", gap(f - 1), gap(f));
            assert!((flat_xz(at(f)) - flat_xz(at(f - 1))).length() <= 1.0 / fps + 1e-3, "frame {f}: a snap");
            match targets[0][f] {
                Some(t) => assert!((t.y - free_l[f].y).abs() < 1e-5, "frame {f}: catching up at {t}"),
                None => caught = caught.or(Some(f)),
            }
        }
        // It had far to go (so slower than an ease over a fixed time), and got there.
        let caught = caught.expect("back on its free path");
        assert!(caught > 55 && targets[0][caught..].iter().all(Option::is_none), "caught up at {caught}");
        // The retargeting's release (an ease) is unchanged: back within RELEASE_S.
        let (eased, _) = hold_plan_with(&feet, fps, Some(&contacts), Release::Ease { over_swing: false });
        assert!(eased[0][30 + (RELEASE_S * fps) as usize + 2].is_none());
    }

    fn flat_xz(v: Vec3) -> Vec3 {
        Vec3::new(v.x, 0.0, v.z)
    }

    #[test]
    fn a_foot_turning_on_its_ball_holds_the_ball() {
        // The source's heel is up (ankle 12 cm above its floor) and its toe planted, for
        // frames 10..50; the character's foot turns about the vertical a little each frame
        // (its toe circles its ankle), so its ankle must circle the held toe.
        let fps = 60.0;
        let frames = 60;
        let src_ankle: Vec<Vec3> = (0..frames).map(|f| Vec3::new(0.0, if (10..50).contains(&f) { 0.2 } else { 0.08 + 0.3 * fmath::sin(f as f32 * 0.3).abs() }, 0.0)).collect();
        let src_toe: Vec<Vec3> = (0..frames).map(|f| Vec3::new(0.0, if (10..50).contains(&f) { 0.02 } else { 0.3 }, 0.15)).collect();
        let turn = |f: usize| Quat::from_rotation_y(0.02 * f as f32);
        let free_ankle: Vec<Vec3> = (0..frames).map(|_| Vec3::new(0.3, 0.25, 0.0)).collect();
        let free_toe: Vec<Vec3> = (0..frames).map(|f| free_ankle[f] + turn(f) * Vec3::new(0.0, -0.1, 0.2)).collect();
        let idle = |y: f32| (0..frames).map(|_| Vec3::new(-0.3, y, 0.0)).collect::<Vec<_>>();
        let feet = [tracks(src_ankle, src_toe, free_ankle.clone(), free_toe.clone()), tracks(idle(0.5), Vec::new(), idle(0.5), Vec::new())];
        let (targets, _) = hold_plan(&feet, fps);
        let toe_at = |f: usize| {
            let a = targets[0][f].expect("on its ball");
            let v = free_toe[f] - free_ankle[f];
            Vec3::new(a.x + v.x, 0.0, a.z + v.z)
        };
        let ball = toe_at(12);
        for f in 12..50 {
            assert!((toe_at(f) - ball).length() < 1e-5, "frame {f}: ball {} vs {ball}", toe_at(f));
        }
        // The ankle does move: round the ball.
        let (a, b) = (targets[0][12].unwrap(), targets[0][49].unwrap());
        assert!((Vec3::new(a.x - b.x, 0.0, a.z - b.z)).length() > 0.05, "{a} {b}");
    }

    #[test]
    fn a_dragged_toe_on_a_longer_foot_stays_on_the_floor() {
        // The source raises its left heel over frames 8..20 (ankle 8 → 12 cm up, toe on its
        // floor at height 0), drags the ball of its foot along the floor at 150 cm/s for
        // frames 20..60, then lowers the heel again over 60..72. The character stands with its
        // ankle 10 cm up (the hold's `y_offset` of 2 cm) on a foot 30 cm long, its toe on the
        // ground; turned as the source's, its longer foot points its toe 5 cm under the ground
        // on the drag.
        let fps = 60.0;
        let frames = 80;
        let drag = 20..60;
        let x = |f: usize| 0.025 * f.clamp(drag.start, drag.end) as f32;
        // How far the heel is up, 0..1.
        let heel = |f: usize| ((f as f32 - 8.0) / 12.0).min((72.0 - f as f32) / 12.0).clamp(0.0, 1.0);
        let src_ankle: Vec<Vec3> = (0..frames).map(|f| Vec3::new(x(f), 0.08 + 0.04 * heel(f), 0.0)).collect();
        let src_toe: Vec<Vec3> = (0..frames).map(|f| Vec3::new(x(f) + 0.12, 0.0, 0.0)).collect();
        let free_ankle: Vec<Vec3> = (0..frames).map(|f| Vec3::new(x(f), 0.10 + 0.04 * heel(f), 0.0)).collect();
        let drop = |f: usize| 0.10 + 0.09 * heel(f);
        let free_toe: Vec<Vec3> = (0..frames).map(|f| free_ankle[f] + Vec3::new((0.09 - drop(f) * drop(f)).sqrt(), -drop(f), 0.0)).collect();
        let still = |y: f32| (0..frames).map(|_| Vec3::new(0.0, y, -0.3)).collect::<Vec<_>>();
        let feet = [
            tracks(src_ankle, src_toe.clone(), free_ankle.clone(), free_toe.clone()),
            tracks(still(0.08), still(0.0), still(0.0), still(-0.01)),
        ];
        // The hinge across each foot (the foot pitches about it, so it stays put).
        let hinge = vec![vec![Vec3::Z; frames], vec![Vec3::Z; frames]];
        // The source's toe height onto the character's: the same ground.
        let toe_y_offset = [0.0, 0.0];
        let (targets, shift) = hold_plan(&feet, fps);
        let turns = toe_clearance(&feet, &hinge, &toe_y_offset, &shift, &targets, fps);
        let toe_at = |f: usize| {
            let ankle = targets[0][f].unwrap_or(free_ankle[f] + shift[f]);
            ankle + turns[0][f].unwrap_or(Quat::IDENTITY) * (free_toe[f] - free_ankle[f])
        };
        // Without the pitch the toe is 5 cm under; with it, within 1 cm of the ground on every
        // frame the source's toe drags (the turn comes in over the frames before).
        assert!(free_toe[40].y < -0.045);
        for f in drag.clone() {
            let y = toe_at(f).y;
            assert!(y.abs() < 0.01, "frame {f}: toe at {y:+.3} m");
        }
        // The foot turns into it and out of it over several frames, never in one.
        let steps: Vec<f32> = (1..frames).map(|f| (toe_at(f) - toe_at(f - 1)).length()).collect();
        assert!(steps.iter().all(|&d| d < 0.05), "{steps:?}");
        // The other foot, standing flat, is not turned.
        assert!(turns[1].iter().all(Option::is_none));
    }

    #[test]
    fn a_pose_rig_is_swung_to_t_pose_and_keeps_directions() {
        // The canonical rig with its upper arms lowered 45° at rest (an A-pose) and a
        // twisted forearm rest: the motion's directions must still come through.
        let demo = demo_clip();
        let mut sk = (*demo.skeleton).clone();
        sk.joints[Canon::LeftUpperArm.index()].rest_rotation = Quat::from_rotation_z(-0.8);
        sk.joints[Canon::RightUpperArm.index()].rest_rotation = Quat::from_rotation_z(0.8);
        sk.joints[Canon::LeftForearm.index()].rest_rotation = Quat::from_rotation_x(0.5);
        let sk = Arc::new(sk);
        let map = HumanoidMap::from_skeleton(&sk);
        let ch = Character::build("a-pose", sk.clone(), builtin_body(&sk), map);
        assert!((ch.arm_swing_rad - 0.8).abs() < 1e-3, "{}", ch.arm_swing_rad);
        // Feet free: held feet bend the legs away from the source's directions, as they should.
        let out = ch.retarget_options(&demo, &HumanoidMap::from_skeleton(&demo.skeleton), &RetargetOptions { hold_feet: false, ..Default::default() }).unwrap();
        for f in [0, 50, 120] {
            let (a, b) = (demo.world_positions(f), out.world_positions(f));
            for (s, c) in Canon::links() {
                let da = (a[c.index()] - a[s.index()]).normalize();
                let db = (b[c.index()] - b[s.index()]).normalize();
                assert!(da.dot(db) > 0.9999, "frame {f} bone {}→{}: {da} vs {db}", s.name(), c.name());
            }
        }
    }
}
