//! Body-part presets (seed 002 §3.4, spec §C): which canonical joints a search compares, as
//! per-joint weights, and which origin the normalisation uses (the shoulder midpoint for the
//! arm-only presets, spec §B.1).

use serde::{Deserialize, Serialize};

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

    /// The joints the preset compares.
    pub fn joints(self) -> Vec<Canon> {
        use Canon::*;
        const LEFT_ARM: [Canon; 4] = [LeftShoulder, LeftUpperArm, LeftForearm, LeftHand];
        const RIGHT_ARM: [Canon; 4] = [RightShoulder, RightUpperArm, RightForearm, RightHand];
        const LEGS: [Canon; 8] = [LeftUpperLeg, LeftLowerLeg, LeftFoot, LeftToe, RightUpperLeg, RightLowerLeg, RightFoot, RightToe];
        match self {
            BodyPreset::WholeBody => Canon::ALL.to_vec(),
            BodyPreset::UpperBody => [Spine, Chest, Neck, Head].into_iter().chain(LEFT_ARM).chain(RIGHT_ARM).collect(),
            BodyPreset::LowerBody => std::iter::once(Hips).chain(LEGS).collect(),
            BodyPreset::Arms => LEFT_ARM.into_iter().chain(RIGHT_ARM).collect(),
            BodyPreset::LeftArm => LEFT_ARM.to_vec(),
            BodyPreset::RightArm => RIGHT_ARM.to_vec(),
            BodyPreset::Legs => LEGS.to_vec(),
            BodyPreset::FeetOnly => vec![LeftFoot, LeftToe, RightFoot, RightToe],
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
