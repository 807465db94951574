//! Everyday actions and the ways they are put together (spec §I, paper 003 §4).
//!
//! The built-in library ([`ActionLibrary::builtin`]) holds the project's own procedural
//! actions — walk, run, kick, jump, wave, clap, rejoice, gutsy pose, turn, bow, sit, stand,
//! nod, point — authored as key poses on [`crate::canon::builtin::canonical_skeleton`] with smooth
//! interpolation, secondary motion and feet planted on the floor. Imported clips join the
//! library with tags chosen by the person. The joins of spec §I live beside them: foot-ground
//! contacts ([`contact`]), Connection and Transition with foot locking by two-bone IK
//! ([`join`], [`ik`]), and Composition with switch-time search and sway transfer ([`mod@compose`]).

pub mod compose;
pub mod contact;
pub mod ik;
pub mod join;
pub mod library;
pub mod procedural;

use serde::{Deserialize, Serialize};
use thiserror::Error;

use crate::canon::body::{self, Region};
use crate::canon::humanoid::Canon;

pub use compose::{compose, ComposeOptions, CompositionReport, SwitchTimes};
pub use contact::{detect_contacts, ContactEvent, ContactEventKind, Contacts, Foot};
pub use join::{join_serial, JoinKind, JoinOptions, JoinReport};
pub use library::{ActionEntry, ActionLibrary};

/// A body part that Composition switches from one motion to the other (spec §I), and that a
/// sentence names ("右手", "left arm").
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "camelCase")]
pub enum BodyPart {
    RightArm,
    LeftArm,
    BothArms,
    RightLeg,
    LeftLeg,
    Head,
}

impl BodyPart {
    /// Every part.
    pub const ALL: [BodyPart; 6] = [BodyPart::RightArm, BodyPart::LeftArm, BodyPart::BothArms, BodyPart::RightLeg, BodyPart::LeftLeg, BodyPart::Head];

    /// The regions of the canonical body it is made of ([`crate::canon::body`]).
    pub fn regions(self) -> &'static [Region] {
        match self {
            BodyPart::RightArm => &[Region::RightArm],
            BodyPart::LeftArm => &[Region::LeftArm],
            BodyPart::BothArms => &[Region::RightArm, Region::LeftArm],
            BodyPart::RightLeg => &[Region::RightLeg],
            BodyPart::LeftLeg => &[Region::LeftLeg],
            BodyPart::Head => &[Region::Head],
        }
    }

    /// The canonical joints the part covers (the root of the part first): its regions' joints.
    pub fn joints(self) -> &'static [Canon] {
        const BOTH_ARMS: [Canon; 8] = body::union2(body::RIGHT_ARM, body::LEFT_ARM);
        match self {
            BodyPart::BothArms => &BOTH_ARMS,
            _ => self.regions()[0].joints(),
        }
    }

    /// The end effector whose position and velocity relative to the hips decide the switch
    /// times of a Composition (spec §I, F).
    pub fn end_effectors(self) -> &'static [Canon] {
        use Canon::*;
        match self {
            BodyPart::RightArm => &[RightHand],
            BodyPart::LeftArm => &[LeftHand],
            BodyPart::BothArms => &[RightHand, LeftHand],
            BodyPart::RightLeg => &[RightFoot],
            BodyPart::LeftLeg => &[LeftFoot],
            BodyPart::Head => &[Head],
        }
    }

    /// Whether a canonical joint belongs to the part.
    pub fn contains(self, c: Canon) -> bool {
        self.joints().contains(&c)
    }

    /// Stable camelCase name ("rightArm"), as serialised.
    pub fn name(self) -> &'static str {
        match self {
            BodyPart::RightArm => "rightArm",
            BodyPart::LeftArm => "leftArm",
            BodyPart::BothArms => "bothArms",
            BodyPart::RightLeg => "rightLeg",
            BodyPart::LeftLeg => "leftLeg",
            BodyPart::Head => "head",
        }
    }
}

/// What can go wrong building, tagging or joining actions.
#[derive(Debug, Error, PartialEq)]
pub enum ActionError {
    #[error("clip '{name}' is not usable: {reason}")]
    BadClip { name: String, reason: String },
    #[error("clip '{name}' is not a humanoid the actions can drive: {reason}")]
    NotHumanoid { name: String, reason: String },
    #[error("clip '{name}' has {frames} frames; joining needs at least {needed}")]
    TooShort { name: String, frames: usize, needed: usize },
    #[error("clips '{a}' and '{b}' run at different frame rates ({fps_a} vs {fps_b} fps)")]
    FpsMismatch { a: String, b: String, fps_a: f32, fps_b: f32 },
    #[error("tag list for clip '{name}' is empty; give at least one tag")]
    NoTags { name: String },
    #[error("no clip with index {index} (the library has {len})")]
    NoSuchClip { index: usize, len: usize },
}
