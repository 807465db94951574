//! The canonical humanoid in one place: its skeleton and joint names ([`humanoid`], with the
//! mapping of other rigs onto it; [`builtin`]'s canonical skeleton), its body parts ([`body`]), §B
//! normalisation ([`normalize`]), and retargeting to it ([`retarget`]) and from it onto a
//! character ([`character`]); the one foot-contact rule ([`contact`]). Every module that reads a body reads it through here, so
//! search presets, text composition and the page name the same parts.

pub mod body;
pub mod builtin;
pub mod character;
pub mod contact;
pub mod humanoid;
pub mod normalize;
pub mod retarget;

/// Height of the toe joint above the floor when the foot is flat (the sole's thickness), metres:
/// where the built-in actions put a flat foot, and where retargeting lifts a clip's lowest toe.
pub const SOLE_HEIGHT: f32 = 0.02;

pub use body::{body_vocabulary, BodyVocabulary, Region};
