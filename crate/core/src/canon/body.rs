//! The body-part vocabulary: the canonical body's regions (head, torso, hips, each arm, each
//! leg, each foot), each a fixed list of canonical joints. Search presets
//! ([`crate::search::BodyPreset`]) and the parts text composition switches
//! ([`crate::actions::BodyPart`]) are unions of these regions, and [`body_vocabulary`] gives the
//! page all of them, so no list of joints is written twice.

use serde::Serialize;

use super::humanoid::Canon;
use Canon::*;

/// A region of the canonical body.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize)]
#[serde(rename_all = "camelCase")]
pub enum Region {
    Head,
    Torso,
    Hips,
    LeftArm,
    RightArm,
    LeftLeg,
    RightLeg,
    LeftFoot,
    RightFoot,
}

pub const HEAD: [Canon; 2] = [Neck, Canon::Head];
pub const TORSO: [Canon; 2] = [Spine, Chest];
pub const HIPS: [Canon; 1] = [Canon::Hips];
pub const LEFT_ARM: [Canon; 4] = [LeftShoulder, LeftUpperArm, LeftForearm, LeftHand];
pub const RIGHT_ARM: [Canon; 4] = [RightShoulder, RightUpperArm, RightForearm, RightHand];
pub const LEFT_FOOT: [Canon; 2] = [Canon::LeftFoot, LeftToe];
pub const RIGHT_FOOT: [Canon; 2] = [Canon::RightFoot, RightToe];
pub const LEFT_LEG: [Canon; 4] = [LeftUpperLeg, LeftLowerLeg, LEFT_FOOT[0], LEFT_FOOT[1]];
pub const RIGHT_LEG: [Canon; 4] = [RightUpperLeg, RightLowerLeg, RIGHT_FOOT[0], RIGHT_FOOT[1]];

/// `a` then `b`, as one list (for parts made of two regions, as static lists).
pub const fn union2<const A: usize, const B: usize, const N: usize>(a: [Canon; A], b: [Canon; B]) -> [Canon; N] {
    let mut out = [Canon::Hips; N];
    let mut i = 0;
    while i < A {
        out[i] = a[i];
        i += 1;
    }
    while i < N {
        out[i] = b[i - A];
        i += 1;
    }
    out
}

impl Region {
    /// Every region, head to feet.
    pub const ALL: [Region; 9] = [Region::Head, Region::Torso, Region::Hips, Region::LeftArm, Region::RightArm, Region::LeftLeg, Region::RightLeg, Region::LeftFoot, Region::RightFoot];

    /// Its canonical joints, from the one nearest the body's root out.
    pub const fn joints(self) -> &'static [Canon] {
        match self {
            Region::Head => &HEAD,
            Region::Torso => &TORSO,
            Region::Hips => &HIPS,
            Region::LeftArm => &LEFT_ARM,
            Region::RightArm => &RIGHT_ARM,
            Region::LeftLeg => &LEFT_LEG,
            Region::RightLeg => &RIGHT_LEG,
            Region::LeftFoot => &LEFT_FOOT,
            Region::RightFoot => &RIGHT_FOOT,
        }
    }
}

/// The joints of `regions`, in their order (a joint in two regions once, where it first comes).
pub fn joints_of(regions: &[Region]) -> Vec<Canon> {
    let mut out: Vec<Canon> = Vec::new();
    for r in regions {
        for &j in r.joints() {
            if !out.contains(&j) {
                out.push(j);
            }
        }
    }
    out
}

/// One named part as the page lists it: its name (as the engine's API spells it) and its
/// regions and joints (canonical joint names).
#[derive(Clone, Debug, PartialEq, Serialize)]
#[serde(rename_all = "camelCase")]
pub struct NamedPart {
    pub name: String,
    pub regions: Vec<Region>,
    pub joints: Vec<&'static str>,
}

/// Everything the page may list of the body, derived from the one vocabulary above.
#[derive(Clone, Debug, PartialEq, Serialize)]
#[serde(rename_all = "camelCase")]
pub struct BodyVocabulary {
    /// The canonical joints' names, in index order.
    pub joints: Vec<&'static str>,
    /// The regions.
    pub regions: Vec<NamedPart>,
    /// The search presets, in UI order (whole body: every joint, no region list).
    pub search_presets: Vec<NamedPart>,
    /// The parts text composition switches.
    pub composition_parts: Vec<NamedPart>,
}

fn named<T: Serialize>(item: T, regions: Vec<Region>, joints: Vec<Canon>) -> NamedPart {
    let name = serde_json::to_value(item).ok().and_then(|v| v.as_str().map(str::to_owned)).unwrap_or_default();
    NamedPart { name, regions, joints: joints.into_iter().map(Canon::name).collect() }
}

/// The body-part vocabulary for the page (joint names, regions, search presets, composition
/// parts), all derived from [`Region`].
pub fn body_vocabulary() -> BodyVocabulary {
    use crate::actions::BodyPart;
    use crate::search::BodyPreset;
    BodyVocabulary {
        joints: Canon::ALL.iter().map(|c| c.name()).collect(),
        regions: Region::ALL.iter().map(|&r| named(r, vec![r], r.joints().to_vec())).collect(),
        search_presets: BodyPreset::ALL.iter().map(|&p| named(p, p.regions().to_vec(), p.joints())).collect(),
        composition_parts: BodyPart::ALL.iter().map(|&p| named(p, p.regions().to_vec(), p.joints().to_vec())).collect(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::actions::BodyPart;
    use crate::search::BodyPreset;

    #[test]
    fn regions_cover_the_body_and_the_lists_are_unions_of_regions() {
        let all = joints_of(&Region::ALL);
        assert_eq!(all.len(), Canon::ALL.len(), "every canonical joint is in a region");
        for p in BodyPreset::ALL {
            if p != BodyPreset::WholeBody {
                assert_eq!(p.joints(), joints_of(p.regions()), "{p:?}");
            }
        }
        for p in BodyPart::ALL {
            assert_eq!(p.joints().to_vec(), joints_of(p.regions()), "{p:?}");
        }
        let v = body_vocabulary();
        assert_eq!(v.search_presets.len(), BodyPreset::ALL.len());
        assert_eq!(v.composition_parts.len(), BodyPart::ALL.len());
        assert_eq!(v.search_presets[0].name, "wholeBody");
        assert_eq!(v.composition_parts.iter().find(|p| p.name == "head").map(|p| p.joints.clone()), Some(vec![Canon::Neck.name(), Canon::Head.name()]));
    }
}
