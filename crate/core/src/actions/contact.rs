//! Foot-ground contacts (spec §I): a foot touches the floor when its ankle is planted by the
//! engine's one foot-contact rule ([`crate::canon::contact`]: near its own floor and barely
//! moving, at the canonical size these clips are on), so the text actions' joins and the
//! retargeting's held feet agree on which frames a foot is down. The ankle, not the toe: a
//! join locks the ankle, and a foot turning on its ball moves its ankle (the retargeting holds
//! such a foot by its toe instead). Contact onsets and ends
//! are the "foot down" and "foot up" keyframes that Transition aligns cyclic motions on.

use glam::Vec3;
use serde::{Deserialize, Serialize};

use crate::canon::contact::planted_frames;
use crate::canon::humanoid::{Canon, CANON_COUNT};
use crate::clip::Clip;

/// Contact or lift-off shorter than this many frames is noise.
pub const MIN_RUN: usize = 3;

/// Which foot.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "camelCase")]
pub enum Foot {
    Left,
    Right,
}

impl Foot {
    pub const BOTH: [Foot; 2] = [Foot::Left, Foot::Right];

    pub fn index(self) -> usize {
        self as usize
    }
    /// The ankle joint.
    pub fn ankle(self) -> Canon {
        match self {
            Foot::Left => Canon::LeftFoot,
            Foot::Right => Canon::RightFoot,
        }
    }
    /// The toe joint.
    pub fn toe(self) -> Canon {
        match self {
            Foot::Left => Canon::LeftToe,
            Foot::Right => Canon::RightToe,
        }
    }
    /// Hip, knee and ankle joints of the leg.
    pub fn chain(self) -> [Canon; 3] {
        match self {
            Foot::Left => [Canon::LeftUpperLeg, Canon::LeftLowerLeg, Canon::LeftFoot],
            Foot::Right => [Canon::RightUpperLeg, Canon::RightLowerLeg, Canon::RightFoot],
        }
    }
}

/// Per-frame contact flags of both feet, `[left, right]`.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "camelCase")]
pub struct Contacts {
    pub frames: Vec<[bool; 2]>,
}

/// A foot landing or lifting off.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "camelCase")]
pub enum ContactEventKind {
    Down,
    Up,
}

/// A keyframe of a cycle: which foot, landing or lifting, at which frame.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "camelCase")]
pub struct ContactEvent {
    pub frame: usize,
    pub foot: Foot,
    pub kind: ContactEventKind,
}

impl Contacts {
    pub fn len(&self) -> usize {
        self.frames.len()
    }
    pub fn is_empty(&self) -> bool {
        self.frames.is_empty()
    }
    /// Contact flags at a frame (clamped; no contact for an empty set).
    pub fn at(&self, frame: usize) -> [bool; 2] {
        match self.frames.len() {
            0 => [false, false],
            n => self.frames[frame.min(n - 1)],
        }
    }
    /// Landings and lift-offs in frame order (a foot in contact at frame 0 has no landing).
    pub fn events(&self) -> Vec<ContactEvent> {
        let mut out = Vec::new();
        for f in 1..self.frames.len() {
            for foot in Foot::BOTH {
                let (a, b) = (self.frames[f - 1][foot.index()], self.frames[f][foot.index()]);
                if a != b {
                    out.push(ContactEvent { frame: f, foot, kind: if b { ContactEventKind::Down } else { ContactEventKind::Up } });
                }
            }
        }
        out
    }
    /// Whether any foot lands or lifts during the clip: a cyclic gait does.
    pub fn has_cycle(&self) -> bool {
        let ev = self.events();
        Foot::BOTH.iter().all(|f| ev.iter().any(|e| e.foot == *f && e.kind == ContactEventKind::Down))
    }
}

/// Sole height of a foot: the lower of the heel (a little under the ankle) and the toe.
pub fn sole_height(frame: &[Vec3], foot: Foot) -> f32 {
    (frame[foot.ankle().index()].y - 0.06).min(frame[foot.toe().index()].y - 0.02)
}

/// Contacts of a clip on the canonical skeleton: a foot is down where its ankle is planted
/// ([`crate::canon::contact::planted_frames`]). Flickers shorter than [`MIN_RUN`]
/// frames are removed.
pub fn detect_contacts(clip: &Clip) -> Contacts {
    let all = clip.all_world_positions();
    contacts_from_positions(&all, clip.joint_count(), clip.fps)
}

/// As [`detect_contacts`], from frame-major canonical world positions.
pub fn contacts_from_positions(all: &[Vec3], joints: usize, fps: f32) -> Contacts {
    if joints < CANON_COUNT || all.len() < joints {
        return Contacts::default();
    }
    let frames = all.len() / joints;
    let track = |c: Canon| planted_frames(&(0..frames).map(|f| all[f * joints + c.index()]).collect::<Vec<_>>(), fps);
    let planted = Foot::BOTH.map(|ft| track(ft.ankle()));
    let mut out: Vec<[bool; 2]> = (0..frames).map(|f| Foot::BOTH.map(|ft| planted[ft.index()][f])).collect();
    // Runs shorter than MIN_RUN frames (a flicker of contact or of lift) take their
    // neighbours' state.
    for s in 0..2 {
        let mut f = 0;
        while f < frames {
            let start = f;
            while f < frames && out[f][s] == out[start][s] {
                f += 1;
            }
            if f - start < MIN_RUN && start > 0 && f < frames {
                let v = out[start - 1][s];
                for g in out.iter_mut().take(f).skip(start) {
                    g[s] = v;
                }
            }
        }
    }
    Contacts { frames: out }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::actions::ActionLibrary;

    #[test]
    fn walk_alternates_feet_and_jump_leaves_the_floor() {
        let lib = ActionLibrary::builtin();
        let walk = lib.entries[lib.find("walk", &[]).unwrap()].clip_for(3.0);
        let c = detect_contacts(&walk);
        assert!(c.has_cycle());
        // Nearly every frame of a walk has a foot down (the detector may miss the frames around
        // heel strike and toe-off, when the foot still moves).
        let airborne = c.frames.iter().filter(|f| !f[0] && !f[1]).count();
        assert!(airborne * 10 <= c.len(), "walk airborne for {airborne} of {} frames", c.len());
        let downs = c.events().iter().filter(|e| e.kind == ContactEventKind::Down).count();
        assert!(downs >= 4, "{downs} landings in 3 s of walking");
        let run = lib.entries[lib.find("run", &[]).unwrap()].clip_for(2.0);
        let rc = detect_contacts(&run);
        assert!(rc.frames.iter().any(|f| !f[0] && !f[1]), "a run has flight phases");
        let jump = &lib.entries[lib.find("jump", &[]).unwrap()].clip;
        let jc = detect_contacts(jump);
        assert!(jc.frames[0][0] && jc.frames[0][1]);
        assert!(jc.frames.iter().any(|f| !f[0] && !f[1]));
        assert!(!jc.has_cycle() || jc.events().len() >= 4);
    }
}
