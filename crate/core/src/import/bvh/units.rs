//! Which length unit a BVH file is in, from its rig. BVH states no unit: a file in
//! centimetres, inches, millimetres or metres reads the same. Two things in the file do tell:
//! the joint names say which tool wrote it (Mixamo, iClone, CMU's ASF converters, Daz, 3ds Max
//! Biped, ...) and so the units that tool writes; and the bone lengths measured against human
//! proportions (a thigh is about a quarter of a person's height, whatever their height) give the
//! person's height in file units, so the unit that makes it a person's height follows. The
//! figure's overall extent alone cannot (a rest pose may lie down or be baked into the motion).

use crate::fmath;
use glam::Vec3;

use crate::canon::humanoid::{Canon, HumanoidMap};
use crate::skeleton::Skeleton;

/// A length unit a motion file may be written in.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LengthUnit {
    /// What a person calls it ("centimetres").
    pub name: &'static str,
    /// Metres per unit.
    pub metres: f32,
}

pub const METRE: LengthUnit = LengthUnit { name: "metres", metres: 1.0 };
pub const DECIMETRE: LengthUnit = LengthUnit { name: "decimetres", metres: 0.1 };
pub const CENTIMETRE: LengthUnit = LengthUnit { name: "centimetres", metres: 0.01 };
pub const MILLIMETRE: LengthUnit = LengthUnit { name: "millimetres", metres: 0.001 };
pub const INCH: LengthUnit = LengthUnit { name: "inches", metres: 0.0254 };
/// The CMU motion-capture database's ASF/AMC unit, kept by the common BVH conversions of it
/// (cgspeed's): the ASF header's `length 0.45` means a file unit is 1/0.45 inch.
pub const CMU_ASF_UNIT: LengthUnit = LengthUnit { name: "CMU ASF units (1/0.45 inch)", metres: 0.0254 / 0.45 };

/// The units any file may be in when its rig's own units do not fit: the ones tools write.
pub const COMMON_UNITS: [LengthUnit; 4] = [CENTIMETRE, INCH, METRE, MILLIMETRE];

/// The tool (or skeleton convention) a rig's joint names come from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RigFamily {
    /// `mixamorig:Hips`, `mixamorig:LeftUpLeg` (Adobe Mixamo).
    Mixamo,
    /// `CC_Base_Hip`, `CC_Base_L_Thigh` (Reallusion iClone / Character Creator).
    IClone,
    /// `lfemur`, `lhumerus`, `lowerback` (CMU ASF) or `LHipJoint`, `LowerBack` (its BVH conversions).
    CmuAsf,
    /// `abdomen`, `rButtock`, `lShldr`, `rShin` (Daz Studio, Poser).
    DazPoser,
    /// `Bip01 L Thigh`, `Bip001 Pelvis` (3ds Max Biped).
    Biped,
    /// `pelvis`, `thigh_l`, `upperarm_l`, `spine_01` (Unreal Engine's mannequin).
    Unreal,
    /// `LeftHip`, `LeftKnee`, `LeftAnkle`, `LeftElbow` (Biovision's own files).
    Biovision,
    /// `Hips`, `LeftUpLeg`, `LeftForeArm`, `Spine1` (MotionBuilder / HumanIK).
    MotionBuilder,
    /// `J_Bip_L_UpperLeg` (VRoid / VRM).
    Vrm,
    /// `thigh.L`, `DEF-shin.R` (Blender, Rigify).
    Blender,
    /// No known naming.
    Unknown,
}

impl RigFamily {
    /// A name a person knows the rig by.
    pub fn name(self) -> &'static str {
        match self {
            RigFamily::Mixamo => "Mixamo",
            RigFamily::IClone => "iClone",
            RigFamily::CmuAsf => "CMU",
            RigFamily::DazPoser => "Daz/Poser",
            RigFamily::Biped => "3ds Max Biped",
            RigFamily::Biovision => "Biovision",
            RigFamily::Unreal => "Unreal",
            RigFamily::MotionBuilder => "MotionBuilder",
            RigFamily::Vrm => "VRM",
            RigFamily::Blender => "Blender",
            RigFamily::Unknown => "unnamed",
        }
    }

    /// The units the tools that name joints this way write, most usual first: Mixamo,
    /// iClone, MotionBuilder and Unreal work in centimetres; Daz Studio writes centimetres and Poser
    /// inches; 3ds Max in its system unit (inches by default, often centimetres); Biovision's
    /// files are in inches; VRM and Blender in metres; CMU's conversions keep the ASF unit.
    pub fn usual_units(self) -> &'static [LengthUnit] {
        match self {
            RigFamily::Mixamo | RigFamily::IClone | RigFamily::MotionBuilder | RigFamily::Unreal => &[CENTIMETRE],
            RigFamily::DazPoser => &[CENTIMETRE, INCH],
            RigFamily::Biped => &[INCH, CENTIMETRE],
            RigFamily::Biovision => &[INCH],
            RigFamily::CmuAsf => &[CMU_ASF_UNIT],
            RigFamily::Vrm | RigFamily::Blender => &[METRE],
            RigFamily::Unknown => &[],
        }
    }

    /// The family the joint names point to (end sites ignored).
    pub fn detect(skeleton: &Skeleton) -> RigFamily {
        let names: Vec<String> =
            skeleton.joints.iter().filter(|j| !j.end_site).map(|j| j.name.to_ascii_lowercase()).collect();
        let any = |f: &dyn Fn(&str) -> bool| names.iter().any(|n| f(n));
        let count = |set: &[&str]| set.iter().filter(|s| names.iter().any(|n| n == *s)).count();
        if any(&|n| n.contains("mixamorig")) {
            RigFamily::Mixamo
        } else if any(&|n| n.starts_with("cc_base_")) {
            RigFamily::IClone
        } else if any(&|n| n.starts_with("j_bip_")) {
            RigFamily::Vrm
        } else if any(&|n| n.starts_with("bip01") || n.starts_with("bip001")) {
            RigFamily::Biped
        } else if count(&["lfemur", "rfemur", "lhumerus", "rhumerus", "ltibia", "rtibia", "lhipjoint", "rhipjoint", "lowerback", "upperback", "thorax"]) >= 2 {
            RigFamily::CmuAsf
        } else if count(&["abdomen", "lbuttock", "rbuttock", "lshldr", "rshldr", "lshin", "rshin", "lthigh", "rthigh"]) >= 2 {
            RigFamily::DazPoser
        } else if count(&["thigh_l", "thigh_r", "calf_l", "calf_r", "upperarm_l", "upperarm_r", "lowerarm_l", "spine_01"]) >= 2 {
            RigFamily::Unreal
        } else if count(&["lefthip", "righthip", "leftknee", "rightknee", "leftankle", "rightankle", "leftelbow", "rightelbow"]) >= 2 {
            RigFamily::Biovision
        } else if count(&["leftupleg", "rightupleg", "leftleg", "rightleg", "leftforearm", "rightforearm", "lefttoebase", "spine1"]) >= 2 {
            RigFamily::MotionBuilder
        } else if any(&|n| n.ends_with(".l") || n.ends_with(".r") || n.starts_with("def-")) {
            RigFamily::Blender
        } else {
            RigFamily::Unknown
        }
    }
}

/// Human proportions: each limb segment's length as a share of standing height, from
/// Drillis & Contini's segment table (as given in Winter, *Biomechanics and Motor Control of
/// Human Movement*, fig. 4.1): thigh (hip to knee) 0.245, shank (knee to ankle) 0.246, upper
/// arm 0.186, forearm 0.146, and hip joint to shoulder (0.818 − 0.530) 0.288 for the trunk.
/// (proximal joint, distal joint, share of height).
pub const SEGMENT_SHARE_OF_HEIGHT: [(Canon, Canon, f32); 9] = [
    (Canon::LeftUpperLeg, Canon::LeftLowerLeg, 0.245),
    (Canon::RightUpperLeg, Canon::RightLowerLeg, 0.245),
    (Canon::LeftLowerLeg, Canon::LeftFoot, 0.246),
    (Canon::RightLowerLeg, Canon::RightFoot, 0.246),
    (Canon::LeftUpperArm, Canon::LeftForearm, 0.186),
    (Canon::RightUpperArm, Canon::RightForearm, 0.186),
    (Canon::LeftForearm, Canon::LeftHand, 0.146),
    (Canon::RightForearm, Canon::RightHand, 0.146),
    (Canon::Hips, Canon::Neck, 0.288),
];

/// The height a person is taken to have when choosing between units, metres.
pub const TYPICAL_HEIGHT_M: f32 = 1.7;
/// Heights (metres) for which a rig's usual unit is taken as it is: a small child to a very
/// tall adult. Outside it the unit that makes the figure nearest a typical height is taken.
pub const USUAL_UNIT_HEIGHT_M: std::ops::RangeInclusive<f32> = 0.9..=2.4;

/// The outcome of [`guess`]: the unit and what it was read from.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct UnitGuess {
    pub unit: LengthUnit,
    pub rig: RigFamily,
    /// The person's height in file units from the bone lengths, or the rest pose's size when
    /// no limb could be measured.
    pub height_units: f32,
    /// How many limb segments were measured (0: the size rule was used).
    pub segments_measured: usize,
}

impl UnitGuess {
    /// The estimated height in metres at the guessed unit.
    pub fn height_m(&self) -> f32 {
        self.height_units * self.unit.metres
    }

    /// How the guess was made, in words ("a Mixamo rig's bone lengths: centimetres").
    pub fn describe(&self) -> String {
        if self.segments_measured > 0 {
            format!("guessed from the {} rig's bone lengths: {}", self.rig.name(), self.unit.name)
        } else {
            format!("guessed from the skeleton's size: {}", self.unit.name)
        }
    }
}

/// Guesses a BVH file's unit from its skeleton (in file units) and each joint's local
/// translation in the first frame (the rest offset, or the position channels where a joint
/// has them: that is what is drawn). `local` may be shorter than the skeleton (the missing
/// joints use their rest offsets).
///
/// The rule: the person's height in file units is the median over the measured limb
/// segments of length / [`SEGMENT_SHARE_OF_HEIGHT`]; the rig's usual unit is taken if it makes
/// that height a person's ([`USUAL_UNIT_HEIGHT_M`]); otherwise the unit among the rig's and
/// [`COMMON_UNITS`] that brings it nearest [`TYPICAL_HEIGHT_M`] (ratio, either way). A skeleton
/// with no humanoid limbs keeps the size rule: more than 20 units tall is centimetres, more
/// than 3 decimetres, else metres.
pub fn guess(skeleton: &Skeleton, local: &[Vec3]) -> UnitGuess {
    let rig = RigFamily::detect(skeleton);
    let offset = |j: usize| local.get(j).copied().unwrap_or(skeleton.joints[j].rest_offset);
    let map = HumanoidMap::from_skeleton(skeleton);
    // Length of the joint chain from `a` down to its descendant `d` (None if `d` is not below `a`).
    let chain_length = |a: usize, d: usize| -> Option<f32> {
        let mut len = 0.0;
        let mut k = d;
        let mut steps = 0;
        while k != a {
            len += offset(k).length();
            k = skeleton.joints.get(k)?.parent?;
            steps += 1;
            if steps > skeleton.len() {
                return None;
            }
        }
        Some(len)
    };
    let mut heights: Vec<f32> = SEGMENT_SHARE_OF_HEIGHT
        .iter()
        .filter_map(|&(a, d, share)| {
            let len = chain_length(map.get(a)?, map.get(d)?)?;
            (len.is_finite() && len > 0.0).then_some(len / share)
        })
        .collect();
    heights.sort_by(f32::total_cmp);
    if heights.is_empty() {
        let extent = size_extent(skeleton, &offset);
        let unit = if extent > 20.0 {
            CENTIMETRE
        } else if extent > 3.0 {
            DECIMETRE
        } else {
            METRE
        };
        return UnitGuess { unit, rig, height_units: extent, segments_measured: 0 };
    }
    let n = heights.len();
    let height_units = if n % 2 == 1 { heights[n / 2] } else { 0.5 * (heights[n / 2 - 1] + heights[n / 2]) };
    let misfit = |u: &LengthUnit| fmath::ln(height_units * u.metres / TYPICAL_HEIGHT_M).abs();
    let best = |units: &mut dyn Iterator<Item = LengthUnit>| units.min_by(|a, b| misfit(a).total_cmp(&misfit(b)));
    let usual = best(&mut rig.usual_units().iter().copied().filter(|u| USUAL_UNIT_HEIGHT_M.contains(&(height_units * u.metres))));
    let unit = usual
        .or_else(|| best(&mut rig.usual_units().iter().copied().chain(COMMON_UNITS)))
        .unwrap_or(CENTIMETRE);
    UnitGuess { unit, rig, height_units, segments_measured: n }
}

/// The largest vertical extent of the skeleton with every joint at its local translation and
/// no rotation, file units (the old size rule's measure, kept for non-humanoid skeletons).
fn size_extent(skeleton: &Skeleton, offset: &dyn Fn(usize) -> Vec3) -> f32 {
    let mut world: Vec<Vec3> = Vec::with_capacity(skeleton.len());
    for (j, joint) in skeleton.joints.iter().enumerate() {
        let base = joint.parent.and_then(|p| world.get(p).copied()).unwrap_or(Vec3::ZERO);
        world.push(base + offset(j));
    }
    let (lo, hi) = world.iter().fold((f32::MAX, f32::MIN), |(lo, hi), v| (lo.min(v.y), hi.max(v.y)));
    if world.is_empty() || !(hi - lo).is_finite() {
        0.0
    } else {
        hi - lo
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::skeleton::Joint;
    use glam::Quat;

    /// A humanoid with human proportions (1.7 m) in the given unit, joint names from `name`.
    fn person(units_per_m: f32, name: &dyn Fn(&str) -> String) -> Skeleton {
        let mut joints = Vec::new();
        let mut add = |n: &str, parent: Option<usize>, o: [f32; 3]| {
            joints.push(Joint { name: name(n), parent, rest_offset: Vec3::from(o) * units_per_m, rest_rotation: Quat::IDENTITY, end_site: false });
            joints.len() - 1
        };
        let hips = add("Hips", None, [0.0, 0.95, 0.0]);
        let spine = add("Spine", Some(hips), [0.0, 0.12, 0.0]);
        let chest = add("Spine1", Some(spine), [0.0, 0.2, 0.0]);
        let neck = add("Neck", Some(chest), [0.0, 0.18, 0.0]);
        add("Head", Some(neck), [0.0, 0.1, 0.0]);
        for (side, x) in [("Left", 1.0f32), ("Right", -1.0)] {
            let sh = add(&format!("{side}Shoulder"), Some(chest), [0.04 * x, 0.15, 0.0]);
            let ua = add(&format!("{side}Arm"), Some(sh), [0.14 * x, 0.0, 0.0]);
            let fa = add(&format!("{side}ForeArm"), Some(ua), [0.316 * x, 0.0, 0.0]);
            add(&format!("{side}Hand"), Some(fa), [0.248 * x, 0.0, 0.0]);
            let ul = add(&format!("{side}UpLeg"), Some(hips), [0.09 * x, -0.05, 0.0]);
            let ll = add(&format!("{side}Leg"), Some(ul), [0.0, -0.417, 0.0]);
            let ft = add(&format!("{side}Foot"), Some(ll), [0.0, -0.418, 0.0]);
            add(&format!("{side}ToeBase"), Some(ft), [0.0, -0.06, 0.12]);
        }
        Skeleton { joints }
    }

    #[test]
    fn the_unit_follows_the_bone_lengths_whatever_the_unit() {
        let plain = |n: &str| n.to_string();
        for unit in [CENTIMETRE, INCH, METRE, MILLIMETRE] {
            let g = guess(&person(1.0 / unit.metres, &plain), &[]);
            assert_eq!(g.unit, unit, "{g:?}");
            assert_eq!(g.rig, RigFamily::MotionBuilder);
            assert_eq!(g.segments_measured, 9);
            assert!((g.height_m() - 1.7).abs() < 0.1, "{g:?}");
        }
    }

    /// Names that map onto the humanoid but belong to no known tool: `l_upleg`, `r_forearm`.
    fn neutral(n: &str) -> String {
        n.replace("Left", "l_").replace("Right", "r_").to_ascii_lowercase()
    }

    #[test]
    fn the_rigs_naming_settles_what_sizes_alone_cannot() {
        // A 1.0 m child in centimetres (100 units): by size alone inches fit better than
        // centimetres (2.54 m vs 1.0 m against 1.7 m); a Mixamo rig says centimetres.
        let child = |name: &dyn Fn(&str) -> String| person(100.0 / 1.7, name);
        let unknown = guess(&child(&neutral), &[]);
        assert_eq!(unknown.rig, RigFamily::Unknown);
        assert_eq!(unknown.segments_measured, 9);
        assert_eq!(unknown.unit, INCH, "{unknown:?}");
        let mixamo = guess(&child(&|n: &str| format!("mixamorig:{n}")), &[]);
        assert_eq!(mixamo.rig, RigFamily::Mixamo);
        assert_eq!(mixamo.unit, CENTIMETRE, "{mixamo:?}");
        assert!((mixamo.height_m() - 1.0).abs() < 0.06, "{mixamo:?}");
        // A CMU-named rig in the ASF unit (30 units tall): by size alone, inches (0.76 m).
        let cmu = |n: &str| match n {
            "LeftUpLeg" => "lfemur".to_string(),
            "RightUpLeg" => "rfemur".to_string(),
            "LeftArm" => "lhumerus".to_string(),
            "RightArm" => "rhumerus".to_string(),
            "LeftLeg" => "ltibia".into(),
            "RightLeg" => "rtibia".into(),
            "LeftForeArm" => "lradius".into(),
            "RightForeArm" => "rradius".into(),
            "LeftHand" => "lhand".into(),
            "RightHand" => "rhand".into(),
            "LeftFoot" => "lfoot".into(),
            "RightFoot" => "rfoot".into(),
            "Spine" => "lowerback".into(),
            "Spine1" => "thorax".into(),
            other => neutral(other),
        };
        let g = guess(&person(1.0 / CMU_ASF_UNIT.metres, &cmu), &[]);
        assert_eq!(g.rig, RigFamily::CmuAsf);
        assert_eq!(g.unit, CMU_ASF_UNIT, "{g:?}");
        assert!((g.height_m() - 1.7).abs() < 0.1, "{g:?}");
        let anon = guess(&person(1.0 / CMU_ASF_UNIT.metres, &neutral), &[]);
        assert_eq!(anon.unit, INCH, "{anon:?}");
    }

    #[test]
    fn a_rigs_usual_unit_gives_way_when_the_bones_say_otherwise() {
        // Mixamo names, metres: centimetres would make a 1.7 cm figure.
        let g = guess(&person(1.0, &|n: &str| format!("mixamorig:{n}")), &[]);
        assert_eq!(g.unit, METRE, "{g:?}");
    }

    #[test]
    fn drawn_translations_count_not_only_offsets() {
        // Every joint's offset is zero but the first frame's position channels hold the bones
        // (some exporters write 6 channels per joint): measured from those, in centimetres.
        let sk = person(100.0, &|n: &str| n.to_string());
        let local: Vec<Vec3> = sk.joints.iter().map(|j| j.rest_offset).collect();
        let mut zeroed = sk.clone();
        for j in &mut zeroed.joints {
            j.rest_offset = Vec3::ZERO;
        }
        assert_eq!(guess(&zeroed, &local).unit, CENTIMETRE);
        assert_eq!(guess(&zeroed, &local).segments_measured, 9);
    }

    #[test]
    fn non_humanoids_keep_the_size_rule_and_nothing_panics() {
        let stick = |len: f32| Skeleton {
            joints: vec![
                Joint { name: "a".into(), parent: None, rest_offset: Vec3::ZERO, rest_rotation: Quat::IDENTITY, end_site: false },
                Joint { name: "b".into(), parent: Some(0), rest_offset: Vec3::new(0.0, -len, 0.0), rest_rotation: Quat::IDENTITY, end_site: false },
            ],
        };
        assert_eq!(guess(&stick(80.0), &[]).unit, CENTIMETRE);
        assert_eq!(guess(&stick(8.0), &[]).unit, DECIMETRE);
        assert_eq!(guess(&stick(1.0), &[]).unit, METRE);
        assert_eq!(guess(&stick(f32::NAN), &[]).unit, METRE);
        assert_eq!(guess(&Skeleton::default(), &[]).unit, METRE);
        // A humanoid with degenerate limbs: zero and infinite lengths are not measured.
        let mut sk = person(100.0, &|n: &str| n.to_string());
        for j in &mut sk.joints {
            j.rest_offset = Vec3::ZERO;
        }
        assert_eq!(guess(&sk, &[]).segments_measured, 0);
        sk.joints[2].rest_offset = Vec3::splat(f32::INFINITY);
        let _ = guess(&sk, &[]);
    }
}
