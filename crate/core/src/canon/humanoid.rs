//! The canonical humanoid every rig is mapped onto, so clips from different sources compare.
//!
//! Mapping is by joint name first (Mixamo `mixamorig:*`, VRM humanoid bone names, CMU BVH and
//! ASF names, iClone `CC_Base_*`, Blender `.L/.R` rigs such as RobotExpressive, MMD's 左腕 / 下半身) and by
//! structure second (the hip branch point, two legs going down, a spine going up that splits
//! into neck and arms). A rig whose mapped body is not upright and two-legged in its rest pose
//! (the Fox) is reported as not humanoid, with the reason.

use crate::fmath;
use glam::Vec3;
use serde::{Deserialize, Serialize};

use crate::clip::Clip;
use crate::skeleton::Skeleton;

/// The 21 canonical joints.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
pub enum Canon {
    Hips,
    Spine,
    Chest,
    Neck,
    Head,
    LeftShoulder,
    LeftUpperArm,
    LeftForearm,
    LeftHand,
    RightShoulder,
    RightUpperArm,
    RightForearm,
    RightHand,
    LeftUpperLeg,
    LeftLowerLeg,
    LeftFoot,
    LeftToe,
    RightUpperLeg,
    RightLowerLeg,
    RightFoot,
    RightToe,
}

pub const CANON_COUNT: usize = 21;

impl Canon {
    pub const ALL: [Canon; CANON_COUNT] = [
        Canon::Hips,
        Canon::Spine,
        Canon::Chest,
        Canon::Neck,
        Canon::Head,
        Canon::LeftShoulder,
        Canon::LeftUpperArm,
        Canon::LeftForearm,
        Canon::LeftHand,
        Canon::RightShoulder,
        Canon::RightUpperArm,
        Canon::RightForearm,
        Canon::RightHand,
        Canon::LeftUpperLeg,
        Canon::LeftLowerLeg,
        Canon::LeftFoot,
        Canon::LeftToe,
        Canon::RightUpperLeg,
        Canon::RightLowerLeg,
        Canon::RightFoot,
        Canon::RightToe,
    ];

    pub fn index(self) -> usize {
        self as usize
    }

    /// camelCase name used in the API and UI ("leftUpperArm").
    pub fn name(self) -> &'static str {
        match self {
            Canon::Hips => "hips",
            Canon::Spine => "spine",
            Canon::Chest => "chest",
            Canon::Neck => "neck",
            Canon::Head => "head",
            Canon::LeftShoulder => "leftShoulder",
            Canon::LeftUpperArm => "leftUpperArm",
            Canon::LeftForearm => "leftForearm",
            Canon::LeftHand => "leftHand",
            Canon::RightShoulder => "rightShoulder",
            Canon::RightUpperArm => "rightUpperArm",
            Canon::RightForearm => "rightForearm",
            Canon::RightHand => "rightHand",
            Canon::LeftUpperLeg => "leftUpperLeg",
            Canon::LeftLowerLeg => "leftLowerLeg",
            Canon::LeftFoot => "leftFoot",
            Canon::LeftToe => "leftToe",
            Canon::RightUpperLeg => "rightUpperLeg",
            Canon::RightLowerLeg => "rightLowerLeg",
            Canon::RightFoot => "rightFoot",
            Canon::RightToe => "rightToe",
        }
    }

    /// The VRM 1.0 humanoid bone this joint is (`VRMC_vrm` / `VRMC_vrm_animation`):
    /// the canonical names are VRM's but for the forearms (`leftLowerArm`) and toes (`leftToes`).
    pub fn vrm_name(self) -> &'static str {
        match self {
            Canon::LeftForearm => "leftLowerArm",
            Canon::RightForearm => "rightLowerArm",
            Canon::LeftToe => "leftToes",
            Canon::RightToe => "rightToes",
            c => c.name(),
        }
    }

    /// Parent in the canonical tree (`None` for the hips).
    pub fn parent(self) -> Option<Canon> {
        use Canon::*;
        Some(match self {
            Hips => return None,
            Spine => Hips,
            Chest => Spine,
            Neck => Chest,
            Head => Neck,
            LeftShoulder | RightShoulder => Chest,
            LeftUpperArm => LeftShoulder,
            LeftForearm => LeftUpperArm,
            LeftHand => LeftForearm,
            RightUpperArm => RightShoulder,
            RightForearm => RightUpperArm,
            RightHand => RightForearm,
            LeftUpperLeg | RightUpperLeg => Hips,
            LeftLowerLeg => LeftUpperLeg,
            LeftFoot => LeftLowerLeg,
            LeftToe => LeftFoot,
            RightLowerLeg => RightUpperLeg,
            RightFoot => RightLowerLeg,
            RightToe => RightFoot,
        })
    }

    /// The canonical links (parent, child), for drawing and for spec §G's link vectors.
    pub fn links() -> impl Iterator<Item = (Canon, Canon)> {
        Canon::ALL.into_iter().filter_map(|c| c.parent().map(|p| (p, c)))
    }

    /// Joints whose absence makes a body not humanoid.
    fn essential(self) -> bool {
        !matches!(self, Canon::Spine | Canon::Chest | Canon::Neck | Canon::LeftShoulder | Canon::RightShoulder | Canon::LeftToe | Canon::RightToe)
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Side {
    Left,
    Right,
    Centre,
}

/// Words that mark joints no canonical joint should take (fingers, twist helpers, face).
const IGNORED: [&str; 22] = [
    "thumb", "index", "middle", "mid", "ring", "pinky", "little", "finger", "twist", "share", "eye", "jaw", "tongue", "teeth", "breast",
    "ribs", "pole", "target", "ik", "roll", "bigtoe", "palm",
];

/// Splits a joint name into lowercase words: `mixamorig:LeftUpLeg` → [left, up, leg];
/// `CC_Base_L_Thigh` → [l, thigh]; `lShldr` → [l, shldr]; `Foot.L` → [foot, l].
fn words(name: &str) -> Vec<String> {
    let name = name.rsplit(':').next().unwrap_or(name);
    let mut out: Vec<String> = Vec::new();
    let mut cur = String::new();
    let chars: Vec<char> = name.chars().collect();
    for (i, &c) in chars.iter().enumerate() {
        if !c.is_alphanumeric() {
            if !cur.is_empty() {
                out.push(std::mem::take(&mut cur));
            }
            continue;
        }
        let boundary = !cur.is_empty()
            && ((c.is_uppercase() && chars[i - 1].is_lowercase())
                || (c.is_ascii_digit() != chars[i - 1].is_ascii_digit()));
        if boundary {
            out.push(std::mem::take(&mut cur));
        }
        cur.extend(c.to_lowercase());
    }
    if !cur.is_empty() {
        out.push(cur);
    }
    out.retain(|w| !matches!(w.as_str(), "cc" | "base" | "mixamorig" | "bip" | "bip01" | "j" | "c" | "def" | "b" | "jnt"));
    out
}

/// Side and body-word of a joint name (`None` for names no canonical joint takes).
fn classify(name: &str) -> Option<(Side, String)> {
    // MMD's Japanese standard names (左腕, 下半身 …) read as their English body words.
    let name = crate::mmd::english_alias(name).unwrap_or(name);
    let mut w = words(name);
    if w.is_empty() {
        return None;
    }
    let mut side = Side::Centre;
    let mut keep = Vec::new();
    for x in w.drain(..) {
        match x.as_str() {
            "left" | "l" => side = Side::Left,
            "right" | "r" => side = Side::Right,
            _ => keep.push(x),
        }
    }
    // CMU-style one-letter prefixes glued to the word: lShldr, rThigh, lhumerus, rfemur.
    if side == Side::Centre && keep.len() == 1 {
        for (p, s) in [("l", Side::Left), ("r", Side::Right)] {
            let rest = keep[0].strip_prefix(p).map(str::to_string);
            if let Some(rest) = rest.filter(|r| body_word(r).is_some()) {
                side = s;
                keep[0] = rest;
            }
        }
    }
    // iClone necks are "NeckTwist01/02": a neck all the same.
    if keep.first().is_some_and(|k| k == "neck") {
        return Some((side, "neck".into()));
    }
    if keep.iter().any(|k| IGNORED.iter().any(|ig| k == ig)) {
        return None;
    }
    Some((side, keep.join("")))
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Part {
    Hips,
    SpineLike,
    Chest,
    Neck,
    Head,
    Shoulder,
    UpperArm,
    Forearm,
    Hand,
    UpperLeg,
    LowerLeg,
    Foot,
    Toe,
}

fn body_word(w: &str) -> Option<Part> {
    let w = w.trim_end_matches(|c: char| c.is_ascii_digit());
    Some(match w {
        "hips" | "hip" | "pelvis" => Part::Hips,
        "spine" | "abdomen" | "waist" | "lowerback" | "belly" | "torsolower" => Part::SpineLike,
        "chest" | "upperchest" | "thorax" | "upperback" | "torso" | "spineupper" => Part::Chest,
        "neck" | "neckupper" => Part::Neck,
        "head" => Part::Head,
        "shoulder" | "clavicle" | "collar" | "collarbone" => Part::Shoulder,
        "upperarm" | "arm" | "shldr" | "humerus" | "uparm" => Part::UpperArm,
        "forearm" | "lowerarm" | "radius" | "elbow" => Part::Forearm,
        "hand" | "wrist" => Part::Hand,
        "upleg" | "upperleg" | "thigh" | "femur" | "hipjoint" => Part::UpperLeg,
        "leg" | "lowerleg" | "shin" | "calf" | "knee" | "tibia" | "loleg" => Part::LowerLeg,
        "foot" | "ankle" => Part::Foot,
        "toe" | "toes" | "toebase" | "ball" | "toeend" => Part::Toe,
        _ => return None,
    })
}

/// How an imported skeleton's joints stand for the canonical humanoid.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct HumanoidMap {
    /// Source joint index per canonical joint (indexed by [`Canon::index`]).
    pub joints: [Option<usize>; CANON_COUNT],
}

/// Whether humanoid-only operations (search, segments, generation) may use a clip.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "camelCase")]
pub enum HumanoidStatus {
    /// Every canonical joint found.
    Complete,
    /// Usable; these canonical joints are missing and are filled in from their neighbours.
    Partial { missing: Vec<String> },
    /// Refused for humanoid operations; loaded and drawn as it is.
    NotHumanoid { reason: String },
}

impl HumanoidStatus {
    pub fn is_humanoid(&self) -> bool {
        !matches!(self, HumanoidStatus::NotHumanoid { .. })
    }
}

/// The status in words, for messages people read (never the `Debug` form).
impl std::fmt::Display for HumanoidStatus {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            HumanoidStatus::Complete => write!(f, "a complete humanoid"),
            HumanoidStatus::Partial { missing } => write!(f, "a humanoid missing {}", missing.join(", ")),
            HumanoidStatus::NotHumanoid { reason } => write!(f, "{reason}"),
        }
    }
}

fn depth(sk: &Skeleton, mut j: usize) -> usize {
    let mut d = 0;
    while let Some(p) = sk.joints[j].parent {
        j = p;
        d += 1;
    }
    d
}

fn is_ancestor(sk: &Skeleton, a: usize, mut b: usize) -> bool {
    while let Some(p) = sk.joints[b].parent {
        if p == a {
            return true;
        }
        b = p;
    }
    false
}

impl HumanoidMap {
    pub fn get(&self, c: Canon) -> Option<usize> {
        self.joints[c.index()]
    }

    /// The bones to draw for this skeleton: every (parent, child) pair, except, when the hips
    /// are found below other nodes (a moving `Root` / `Character` / `Armature` node above them),
    /// the bones hanging from those nodes. Such a node is not part of the body; drawn, it is a
    /// long stick from the ground or the world origin to the pelvis.
    pub fn figure_bones(&self, sk: &Skeleton) -> Vec<(usize, usize)> {
        let all = sk.bones();
        let Some(hips) = self.get(Canon::Hips).filter(|&h| h < sk.len() && sk.joints[h].parent.is_some()) else {
            return all;
        };
        all.into_iter().filter(|&(p, _)| p == hips || is_ancestor(sk, hips, p)).collect()
    }

    pub fn missing(&self) -> Vec<Canon> {
        Canon::ALL.into_iter().filter(|c| self.get(*c).is_none()).collect()
    }

    /// Maps a skeleton by names, then fills gaps by structure.
    pub fn from_skeleton(sk: &Skeleton) -> HumanoidMap {
        let mut map = HumanoidMap::default();
        let classes: Vec<Option<(Side, Part)>> = sk
            .joints
            .iter()
            .map(|j| if j.end_site { None } else { classify(&j.name).and_then(|(s, w)| body_word(&w).map(|p| (s, p))) })
            .collect();
        // For each (side, part), the candidate nearest the root wins, except hips where the
        // joint the legs hang from is preferred when several names match.
        let pick = |side: Side, part: Part| -> Option<usize> {
            (0..sk.len()).filter(|&i| classes[i] == Some((side, part))).min_by_key(|&i| depth(sk, i))
        };
        use Canon::*;
        let set = |m: &mut HumanoidMap, c: Canon, v: Option<usize>| {
            if m.joints[c.index()].is_none() {
                m.joints[c.index()] = v;
            }
        };
        for (side, canon) in [(Side::Left, [LeftShoulder, LeftUpperArm, LeftForearm, LeftHand, LeftUpperLeg, LeftLowerLeg, LeftFoot, LeftToe]), (Side::Right, [RightShoulder, RightUpperArm, RightForearm, RightHand, RightUpperLeg, RightLowerLeg, RightFoot, RightToe])] {
            let parts = [Part::Shoulder, Part::UpperArm, Part::Forearm, Part::Hand, Part::UpperLeg, Part::LowerLeg, Part::Foot, Part::Toe];
            for (c, p) in canon.into_iter().zip(parts) {
                set(&mut map, c, pick(side, p));
            }
        }
        // "Shldr" means upper arm in CMU BVH; when a rig has "Collar" and "Shldr", the word
        // shoulder already went to UpperArm. When a rig has Shoulder but no UpperArm and the
        // shoulder's child is an arm-like chain, read the shoulder as upper arm.
        for (sh, ua, fa) in [(LeftShoulder, LeftUpperArm, LeftForearm), (RightShoulder, RightUpperArm, RightForearm)] {
            if map.get(ua).is_none() {
                if let (Some(s), Some(f)) = (map.get(sh), map.get(fa)) {
                    if sk.joints[f].parent == Some(s) {
                        map.joints[ua.index()] = Some(s);
                        map.joints[sh.index()] = None;
                    }
                }
            }
        }
        // Legs hang from the hips: the nearest common ancestor of both upper legs.
        let hips_by_name = pick(Side::Centre, Part::Hips);
        let leg_root = match (map.get(LeftUpperLeg), map.get(RightUpperLeg)) {
            (Some(l), Some(r)) => common_ancestor(sk, l, r),
            _ => None,
        };
        map.joints[Hips.index()] = match (hips_by_name, leg_root) {
            // Prefer the named hips when it is the leg root or directly related to it.
            (Some(h), Some(lr)) if h == lr || is_ancestor(sk, h, lr) => Some(h),
            (Some(h), Some(lr)) if is_ancestor(sk, lr, h) => Some(lr),
            (h, lr) => h.or(lr),
        };
        set(&mut map, Neck, pick(Side::Centre, Part::Neck));
        set(&mut map, Head, pick(Side::Centre, Part::Head));
        // Chest: where the arms branch off (common ancestor of the two shoulders/upper arms).
        let arm_l = map.get(LeftShoulder).or(map.get(LeftUpperArm));
        let arm_r = map.get(RightShoulder).or(map.get(RightUpperArm));
        let arm_root = match (arm_l, arm_r) {
            (Some(l), Some(r)) => common_ancestor(sk, l, r),
            _ => None,
        };
        set(&mut map, Chest, arm_root.or_else(|| pick(Side::Centre, Part::Chest)));
        // Spine: a joint strictly between hips and chest, the one nearest the middle.
        if let (Some(h), Some(c)) = (map.get(Hips), map.get(Chest)) {
            let mut chain = Vec::new();
            let mut k = c;
            while let Some(p) = sk.joints[k].parent {
                if p == h {
                    break;
                }
                chain.push(p);
                k = p;
            }
            if sk.joints[k].parent == Some(h) || k == h {
                chain.reverse();
                if !chain.is_empty() {
                    map.joints[Spine.index()] = Some(chain[chain.len() / 2]);
                }
            }
        }
        if map.get(Spine).is_none() {
            set(&mut map, Spine, pick(Side::Centre, Part::SpineLike));
        }
        // A toe is often only an end site below the foot.
        for (foot, toe) in [(LeftFoot, LeftToe), (RightFoot, RightToe)] {
            if map.get(toe).is_none() {
                if let Some(f) = map.get(foot) {
                    map.joints[toe.index()] = sk.children(f).next();
                }
            }
        }
        // Rigs without hand bones (RobotExpressive) still have a wrist: the forearm's child.
        for (fa, hand) in [(LeftForearm, LeftHand), (RightForearm, RightHand)] {
            if map.get(hand).is_none() {
                if let Some(f) = map.get(fa) {
                    map.joints[hand.index()] = sk.children(f).max_by_key(|&c| subtree_size(sk, c));
                }
            }
        }
        map.structural_fill(sk);
        map
    }

    /// Fills joints names could not place, from the shape of the rest pose.
    fn structural_fill(&mut self, sk: &Skeleton) {
        use Canon::*;
        if self.missing().is_empty() || sk.is_empty() {
            return;
        }
        let rest = sk.rest_positions();
        let chain_down = |start: usize, n: usize| -> Vec<usize> {
            let mut v = vec![start];
            let mut k = start;
            while v.len() < n {
                let Some(c) = sk.children(k).max_by_key(|&c| subtree_size(sk, c)) else { break };
                v.push(c);
                k = c;
            }
            v
        };
        // Hips: the first joint with three or more branches, or the root.
        if self.get(Hips).is_none() {
            let h = (0..sk.len()).find(|&i| sk.children(i).count() >= 3).unwrap_or(0);
            self.joints[Hips.index()] = Some(h);
        }
        let Some(h) = self.get(Hips) else { return };
        // Legs: the two child branches whose ends go lowest, left one at +X (facing +Z).
        if self.get(LeftUpperLeg).is_none() || self.get(RightUpperLeg).is_none() {
            let mut branches: Vec<(usize, f32)> = sk
                .children(h)
                .map(|c| (c, lowest_in_subtree(sk, c, &rest)))
                .filter(|(_, y)| *y < rest[h].y)
                .collect();
            branches.sort_by(|a, b| a.1.total_cmp(&b.1));
            if branches.len() >= 2 {
                let (mut a, mut b) = (branches[0].0, branches[1].0);
                if rest[a].x < rest[b].x {
                    std::mem::swap(&mut a, &mut b);
                }
                for (root, chain) in [(a, [LeftUpperLeg, LeftLowerLeg, LeftFoot, LeftToe]), (b, [RightUpperLeg, RightLowerLeg, RightFoot, RightToe])] {
                    let js = chain_down(root, 4);
                    for (c, j) in chain.iter().zip(js) {
                        if self.get(*c).is_none() {
                            self.joints[c.index()] = Some(j);
                        }
                    }
                }
            }
        }
    }

    /// Humanoid status of a mapped skeleton, judged on its rest pose and on a few frames of
    /// `clip` (rigs such as iClone's BVH exports have a meaningless rest pose: their bone
    /// frames are baked into the animation). Upright in any of them counts.
    pub fn status(&self, sk: &Skeleton, clip: Option<&Clip>) -> HumanoidStatus {
        let missing = self.missing();
        let essential: Vec<&str> = missing.iter().filter(|c| c.essential()).map(|c| c.name()).collect();
        if !essential.is_empty() {
            return HumanoidStatus::NotHumanoid {
                // The same count the library shows for the clip (end sites are not joints).
                reason: format!("no humanoid {} found among its {} joints", essential.join(", "), sk.animated_joint_count()),
            };
        }
        let mut poses = vec![sk.rest_positions()];
        if let Some(c) = clip {
            let n = c.frame_count();
            for k in 0..5 {
                poses.push(c.world_positions(k * n.saturating_sub(1) / 4));
            }
        }
        let tilt = |v: Vec3, dir: Vec3| fmath::acos(v.normalize_or_zero().dot(dir).clamp(-1.0, 1.0)).to_degrees();
        // (spine tilt from vertical, leg tilt from straight down) per pose; keep the most upright.
        let best = poses
            .iter()
            .map(|pose| {
                let p = |c: Canon| pose[self.get(c).unwrap_or(0)];
                let hips = (p(Canon::LeftUpperLeg) + p(Canon::RightUpperLeg)) * 0.5;
                let feet = (p(Canon::LeftFoot) + p(Canon::RightFoot)) * 0.5;
                (tilt(p(Canon::Head) - hips, Vec3::Y), tilt(feet - hips, -Vec3::Y))
            })
            .min_by(|a, b| a.0.max(a.1).total_cmp(&b.0.max(b.1)))
            .unwrap_or((180.0, 180.0));
        if best.0 > 50.0 {
            return HumanoidStatus::NotHumanoid {
                reason: format!(
                    "its body is not upright: hips to head is {:.0}° from vertical (a four-legged or lying figure); humanoid operations need a standing two-legged body",
                    best.0
                ),
            };
        }
        if best.1 > 50.0 {
            return HumanoidStatus::NotHumanoid {
                reason: format!("its legs do not hang below the hips: hips to feet is {:.0}° from straight down", best.1),
            };
        }
        if missing.is_empty() {
            HumanoidStatus::Complete
        } else {
            HumanoidStatus::Partial { missing: missing.iter().map(|c| c.name().to_string()).collect() }
        }
    }
}

fn subtree_size(sk: &Skeleton, j: usize) -> usize {
    1 + sk.children(j).map(|c| subtree_size(sk, c)).sum::<usize>()
}

fn lowest_in_subtree(sk: &Skeleton, j: usize, rest: &[Vec3]) -> f32 {
    sk.children(j).map(|c| lowest_in_subtree(sk, c, rest)).fold(rest[j].y, f32::min)
}

fn common_ancestor(sk: &Skeleton, a: usize, b: usize) -> Option<usize> {
    let mut anc = Vec::new();
    let mut k = a;
    while let Some(p) = sk.joints[k].parent {
        anc.push(p);
        k = p;
    }
    let mut k = b;
    while let Some(p) = sk.joints[k].parent {
        if anc.contains(&p) {
            return Some(p);
        }
        k = p;
    }
    None
}

/// World positions of the canonical joints for every frame of a clip, frame-major
/// (`frames * CANON_COUNT`). Missing joints are filled from their neighbours (a missing
/// shoulder sits at its upper arm, a missing spine halfway between hips and chest, a
/// missing toe at its foot), so the array is always complete.
pub fn canonical_positions(clip: &Clip, map: &HumanoidMap) -> Vec<Vec3> {
    let frames = clip.frame_count();
    let mut out = Vec::with_capacity(frames * CANON_COUNT);
    let mut pose = crate::motion::WorldPose::new();
    for f in 0..frames {
        let world = &pose.of_frame(clip, f).positions;
        let base = out.len();
        for c in Canon::ALL {
            out.push(map.get(c).map(|j| world[j]).unwrap_or(Vec3::NAN));
        }
        fill_missing(&mut out[base..]);
    }
    out
}

/// Fills NaN canonical joints of one frame from their neighbours.
pub fn fill_missing(frame: &mut [Vec3]) {
    use Canon::*;
    let get = |f: &[Vec3], c: Canon| f[c.index()];
    let ok = |v: Vec3| v.is_finite();
    // Hips from the upper legs if needed.
    if !ok(get(frame, Hips)) && ok(get(frame, LeftUpperLeg)) && ok(get(frame, RightUpperLeg)) {
        frame[Hips.index()] = (get(frame, LeftUpperLeg) + get(frame, RightUpperLeg)) * 0.5;
    }
    if !ok(get(frame, Chest)) {
        let v = if ok(get(frame, Neck)) { get(frame, Neck) } else { get(frame, Head) };
        frame[Chest.index()] = (get(frame, Hips) + v * 2.0) / 3.0;
    }
    if !ok(get(frame, Spine)) {
        frame[Spine.index()] = (get(frame, Hips) + get(frame, Chest)) * 0.5;
    }
    if !ok(get(frame, Neck)) {
        frame[Neck.index()] = (get(frame, Chest) + get(frame, Head)) * 0.5;
    }
    for (sh, ua) in [(LeftShoulder, LeftUpperArm), (RightShoulder, RightUpperArm)] {
        if !ok(get(frame, sh)) {
            frame[sh.index()] = (get(frame, ua) * 2.0 + get(frame, Chest)) / 3.0;
        }
    }
    for (foot, toe) in [(LeftFoot, LeftToe), (RightFoot, RightToe)] {
        if !ok(get(frame, toe)) {
            frame[toe.index()] = get(frame, foot);
        }
    }
    for v in frame.iter_mut() {
        if !v.is_finite() {
            *v = Vec3::ZERO;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_split_into_side_and_part() {
        assert_eq!(classify("mixamorig:LeftUpLeg"), Some((Side::Left, "upleg".into())));
        assert_eq!(classify("CC_Base_R_Forearm"), Some((Side::Right, "forearm".into())));
        assert_eq!(classify("lShldr"), Some((Side::Left, "shldr".into())));
        assert_eq!(classify("rhumerus"), Some((Side::Right, "humerus".into())));
        assert_eq!(classify("UpperArm.L"), Some((Side::Left, "upperarm".into())));
        assert_eq!(classify("leftUpperArm"), Some((Side::Left, "upperarm".into())));
        assert_eq!(classify("J_Bip_L_UpperArm"), Some((Side::Left, "upperarm".into())));
        assert_eq!(classify("mixamorig:LeftHandThumb1"), None);
        assert_eq!(classify("CC_Base_L_UpperarmTwist01"), None);
        assert_eq!(body_word("spine01"), Some(Part::SpineLike));
    }
}
