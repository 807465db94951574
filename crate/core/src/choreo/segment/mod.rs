//! The segment library (spec §E): clips cut into segments of one bar (4 counts, and from
//! imported clips 3 counts too) at the motion's own counts, each with what the choreography
//! reads of it: source and frames, tempo, motion intensity W (eq. 2), eigen signature (§F) and
//! the link vectors and velocities at its ends for the transition cost (§G).
//!
//! Every clip is put on the canonical skeleton at [`LIBRARY_FPS`] first, so built-in and
//! imported moves compare, join and play as one dance. A bar of n beats takes segments of n
//! counts ([`Segment::counts`]); the count warp puts count k at k/n of the bar.
//!
//! Files: `types` (segments and library clips), `library` (cutting clips into the library),
//! `cache` (the transition table each library keeps), `tempo` (counts and tempo detected
//! from the motion, beat fit, kinetic beats per count), `signature` (the §F eigen
//! signature). Why the rules are as they are, and the figures that chose them:
//! `docs/benchmarks-notes-choreo.md`.

mod cache;
mod library;
mod signature;
mod tempo;
mod types;

use serde::{Deserialize, Serialize};
use thiserror::Error;

pub use library::{steps_in_three, BuiltinLoader, SegmentLibrary, STEPS_TWICE_A_COUNT};
pub use signature::{signature_of, SIGNATURE_AXES, SIGNATURE_OFFSET, SIGNATURE_REFERENCE, SIGNATURE_VELOCITY_SECS};
pub use tempo::{beat_fit, clip_count_period, detect_beats, detect_counts, joint_speed, kinetic_per_count_by_rate, KINETIC_RATES_BPM};
pub(crate) use types::JoinEnds;
pub use types::{intensity_weight, ClipSummary, LibraryClip, Recut, Segment, LINKS, LINK_COUNT};

/// Frame rate every library clip is stored and analysed at.
pub const LIBRARY_FPS: f32 = 30.0;
/// Counts per segment (one bar of 4/4): every built-in move, and the default.
pub const SEGMENT_COUNTS: usize = 4;
/// The counts of the segments cut from each imported clip: one bar of 4/4 and one of 3/4
/// (module docs: a bar of n beats takes segments of n counts).
pub const SEGMENT_METRES: [usize; 2] = [4, 3];

/// Why a clip gave no segments.
#[derive(Debug, Error, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "camelCase")]
pub enum SegmentError {
    #[error("clip '{name}' is not humanoid ({reason}): segments need a standing two-legged body")]
    NotHumanoid { name: String, reason: String },
    #[error("clip '{name}' is {duration_secs:.2} s long and holds only {beats} beat(s) at {tempo_bpm:.0} counts per minute: a segment needs 4 counts (5 beats)")]
    TooShort { name: String, duration_secs: f32, beats: usize, tempo_bpm: f32 },
    #[error("clip '{name}': stated tempo {tempo_bpm} BPM is outside {min}..={max}", min = super::MIN_MOVE_BPM, max = super::MAX_MOVE_BPM)]
    BadTempo { name: String, tempo_bpm: f32 },
    #[error("clip '{name}' is invalid: {message}")]
    Invalid { name: String, message: String },
    #[error("there is no clip {clip} in the segment library (it has {clips})")]
    NoSuchClip { clip: usize, clips: usize },
    #[error("'{name}' is a built-in move: it is one bar at 120 counts per minute and cannot be re-cut")]
    BuiltinClip { name: String },
}

/// How to cut a clip.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "camelCase", default)]
pub struct SegmentOptions {
    /// The clip's tempo in counts per minute, when the person knows it; `None`: detect it from
    /// the motion.
    pub tempo_bpm: Option<f32>,
    /// Time of a count in the clip, seconds (with `tempo_bpm`); `None`: the phase is detected.
    pub first_beat_secs: Option<f32>,
    /// Counts between the starts of consecutive segments (1..=4; default 2: segments overlap
    /// by half a bar, giving the filling more ways to join).
    pub hop_counts: usize,
    /// Cut the segments in 3 of a clip that steps twice a count on its steps, not its counts
    /// ([`steps_in_three`]). Default off since the joins are inertialized (session 12): with
    /// blended joins the plain cut on counts dances the six 3/4 demo pieces with `cmu-modern`
    /// 0.03–0.12 above random moves, the cut on steps 0.01 above to 0.02 below
    /// (`choreo_waltz`); before the blend the cut on steps was what brought them on the beat.
    pub steps_in_three: bool,
}

impl Default for SegmentOptions {
    fn default() -> Self {
        Self { tempo_bpm: None, first_beat_secs: None, hop_counts: 2, steps_in_three: false }
    }
}

#[cfg(test)]
pub(crate) mod tests;
