//! Body-part presets (seed 002 §3.4, spec §C): which canonical joints a search compares, as
//! per-joint weights, and which origin the normalisation uses (the shoulder midpoint for the
//! arm-only presets, spec §B.1).

use serde::{Deserialize, Serialize};

use crate::canon::body::{joints_of, Region};
use crate::canon::humanoid::{Canon, CANON_COUNT};
use crate::canon::normalize::Origin;

/// The presets the UI offers. Each sets weight 1 on its joints and 0 elsewhere.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "camelCase")]
pub enum BodyPreset {
    /// All 21 canonical joints.
    WholeBody,
    /// Spine, chest, neck, head, both shoulders and arms.
    UpperBody,
    /// Hips and both legs down to the toes.
    LowerBody,
    /// Both shoulders and arms (shoulder-midpoint origin).
    Arms,
    /// Left shoulder and arm (shoulder-midpoint origin).
    LeftArm,
    /// Right shoulder and arm (shoulder-midpoint origin).
    RightArm,
    /// Both legs, upper leg to toe.
    Legs,
    /// Feet (ankles/heels) and toes only.
    FeetOnly,
}

impl BodyPreset {
    /// Every preset, in UI order.
    pub const ALL: [BodyPreset; 8] = [
        BodyPreset::WholeBody,
        BodyPreset::UpperBody,
        BodyPreset::LowerBody,
        BodyPreset::Arms,
        BodyPreset::LeftArm,
        BodyPreset::RightArm,
        BodyPreset::Legs,
        BodyPreset::FeetOnly,
    ];

    /// The regions of the canonical body it compares ([`crate::canon::body`]); none for the
    /// whole body (every joint).
    pub fn regions(self) -> &'static [Region] {
        match self {
            BodyPreset::WholeBody => &[],
            BodyPreset::UpperBody => &[Region::Torso, Region::Head, Region::LeftArm, Region::RightArm],
            BodyPreset::LowerBody => &[Region::Hips, Region::LeftLeg, Region::RightLeg],
            BodyPreset::Arms => &[Region::LeftArm, Region::RightArm],
            BodyPreset::LeftArm => &[Region::LeftArm],
            BodyPreset::RightArm => &[Region::RightArm],
            BodyPreset::Legs => &[Region::LeftLeg, Region::RightLeg],
            BodyPreset::FeetOnly => &[Region::LeftFoot, Region::RightFoot],
        }
    }

    /// The joints the preset compares: its regions' joints (every joint for the whole body).
    pub fn joints(self) -> Vec<Canon> {
        match self {
            BodyPreset::WholeBody => Canon::ALL.to_vec(),
            _ => joints_of(self.regions()),
        }
    }

    /// Per-joint weights, indexed by [`Canon::index`].
    pub fn weights(self) -> [f32; CANON_COUNT] {
        let mut w = [0.0; CANON_COUNT];
        for j in self.joints() {
            w[j.index()] = 1.0;
        }
        w
    }

    /// The normalisation origin: shoulders for the arm-only presets (spec §B.1), else hips.
    pub fn origin(self) -> Origin {
        match self {
            BodyPreset::Arms | BodyPreset::LeftArm | BodyPreset::RightArm => Origin::Shoulders,
            _ => Origin::Hips,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn presets_have_joints_and_arms_use_shoulders() {
        for p in BodyPreset::ALL {
            assert!(p.weights().iter().any(|w| *w > 0.0), "{p:?}");
        }
        assert_eq!(BodyPreset::WholeBody.weights().iter().sum::<f32>(), CANON_COUNT as f32);
        assert_eq!(BodyPreset::Arms.origin(), Origin::Shoulders);
        assert_eq!(BodyPreset::FeetOnly.origin(), Origin::Hips);
        assert_eq!(BodyPreset::FeetOnly.weights()[Canon::LeftHand.index()], 0.0);
    }
}
