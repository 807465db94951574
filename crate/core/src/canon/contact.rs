//! The one foot-contact rule of the engine: a foot point (the ankle, or the toe joint) is planted
//! on a frame when it is within [`CONTACT_HEIGHT_M`] of its floor and moves horizontally slower
//! than [`CONTACT_SPEED_M_S`]. The text actions' contacts (`actions::contact`: a foot is down
//! when its ankle is planted), the retargeting's held feet and the rendered dance's
//! held feet (`character/hold.rs`) all read it.
//!
//! Both are measured on the motion at the canonical skeleton's size (a character's source before
//! it is scaled to the rig), so the same source plants the same frames on every rig; and the
//! height is the point's height over its own floor (the 1st percentile of its heights over the
//! clip, as spec §J's skate measure takes it), which is the height of the sole under it whatever
//! the rig's ankle height or a capture's floor offset.
//! Why these values: 5 cm is spec §J's foot-contact band, so a foot the skate measure judges as
//! on the floor is the foot that is held; 0.25 m/s is the text actions' speed (a stepping foot,
//! 1–4 m/s, passes it within a frame or two). Tried against the checks of joins and retargeting
//! (`claims_actions`, `character_retarget`): at 0.30 m/s (the retargeting's earlier speed) the
//! text actions' walk → stand join, foot-locked, skated more than unlocked (31.4 → 42.2 cm/s);
//! at 3.5 cm (the text actions' earlier height) RobotExpressive's pivot turns jumped further.
//! The rules replaced: the text actions' (3.5 cm on a sole guessed 6 cm under the ankle,
//! 0.25 m/s) and the retargeting's (5 cm, 30 cm/s, measured at the character's size, so a rig
//! 1.88× the canonical size held other frames of the same source than one 1.08× its size).

use glam::Vec3;

use crate::motion;

/// A foot point within this height of its floor may be planted, metres (at canonical size).
pub const CONTACT_HEIGHT_M: f32 = 0.05;
/// A foot point moving faster than this horizontally is not planted, metres per second (at
/// canonical size).
pub const CONTACT_SPEED_M_S: f32 = 0.25;

/// Per frame, whether a foot point is within the contact band: at most [`CONTACT_HEIGHT_M`]
/// (exclusive) over its floor, the 1st percentile of its heights (`heights_m`, at the canonical
/// size). The height half of the rule, which spec §J's foot skate measures its speeds on
/// (`motion::skate_speeds_cm_s`; `choreo::quality` takes [`within_band`] over its own floor): a
/// speed bound there would hide the skate it measures. No finite height: never in the band.
pub fn in_contact_band(heights_m: &[f32]) -> Vec<bool> {
    let Some(floor) = motion::floor_height(heights_m) else { return vec![false; heights_m.len()] };
    heights_m.iter().map(|&y| within_band(y - floor)).collect()
}

/// The band's one comparison: a foot point `over_floor_m` above its floor (at the canonical
/// size) is in the contact band.
pub fn within_band(over_floor_m: f32) -> bool {
    over_floor_m < CONTACT_HEIGHT_M
}

/// Per frame, whether a foot point is planted: `track_m` is its world position per frame at the
/// canonical skeleton's size (a track at another size is divided by that size first), `fps` the
/// frame rate. In the contact band ([`in_contact_band`]) and slower than [`CONTACT_SPEED_M_S`],
/// the speed over frames f−1..f+1. No finite height: never planted.
pub fn planted_frames(track_m: &[Vec3], fps: f32) -> Vec<bool> {
    let frames = track_m.len();
    let band = in_contact_band(&track_m.iter().map(|p| p.y).collect::<Vec<_>>());
    (0..frames)
        .map(|f| {
            let (a, b) = (f.saturating_sub(1), (f + 1).min(frames - 1));
            let span = (b - a).max(1) as f32;
            let speed_m_s = Vec3::new(track_m[b].x - track_m[a].x, 0.0, track_m[b].z - track_m[a].z).length() * fps / span;
            band[f] && speed_m_s < CONTACT_SPEED_M_S
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_still_foot_on_its_floor_is_planted_and_a_lifted_or_sliding_one_is_not() {
        // 30 fps: 10 frames still at a floor 8 cm up (an ankle's height), 10 sliding at
        // 0.6 m/s on it, 10 still but 10 cm up.
        let mut t: Vec<Vec3> = (0..10).map(|_| Vec3::new(0.0, 0.08, 0.0)).collect();
        t.extend((1..=10).map(|f| Vec3::new(f as f32 * 0.02, 0.08, 0.0)));
        t.extend((0..10).map(|_| Vec3::new(0.2, 0.18, 0.0)));
        let p = planted_frames(&t, 30.0);
        assert!(p[..9].iter().all(|&x| x), "{p:?}");
        assert!(p[11..19].iter().all(|&x| !x), "{p:?}");
        assert!(p[21..].iter().all(|&x| !x), "{p:?}");
        // The same motion at another size, divided back, plants the same frames.
        let big: Vec<Vec3> = t.iter().map(|v| *v * 1.7).collect();
        assert_eq!(planted_frames(&big.iter().map(|v| *v / 1.7).collect::<Vec<_>>(), 30.0), p);
        assert!(planted_frames(&[], 30.0).is_empty());
        assert_eq!(planted_frames(&[Vec3::NAN; 3], 30.0), vec![false; 3]);
        // The band alone (what foot skate reads): the sliding frames are in it, the lifted not.
        let band = in_contact_band(&t.iter().map(|p| p.y).collect::<Vec<_>>());
        assert!(band[..20].iter().all(|&x| x) && band[20..].iter().all(|&x| !x), "{band:?}");
        assert_eq!(in_contact_band(&[f32::NAN; 2]), vec![false; 2]);
    }
}
