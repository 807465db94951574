//! The engine's own standard MMD skeleton: the standard bone names with 足ＩＫ / つま先ＩＫ chains,
//! so a VMD made for any standard-boned model plays with no model given.
//!
//! Rest positions are this engine's design (no model's data): a figure about 20 units tall in
//! A-stance (arms about 40° below horizontal), facing the viewer as MMD models do (front is −z in
//! MMD's file frame, +z after conversion), left side at +x; at 8 cm per unit about 1.6 m, the
//! 頭 joint at 16.6 units (1.33 m), hips (足) at 10.4 units (0.83 m). IK settings are those MMD's
//! bundled models use (足ＩＫ: 40 loops, 2 rad per step, knees bend one way; つま先ＩＫ: 3 loops, 4 rad).

use glam::Vec3;

use super::{to_right_handed, AngleLimit, IkChain, IkLink, MmdBone, MmdRig};

/// (name, parent name, rest position in MMD's left-handed file frame) of one side's bones, left
/// side (+x); the right side mirrors x.
const SIDE: [(&str, &str, [f32; 3]); 11] = [
    ("肩", "上半身2", [0.6, 15.2, 0.3]),
    ("腕", "肩", [1.6, 15.0, 0.4]),
    ("腕捩", "腕", [2.8, 14.0, 0.4]),
    ("ひじ", "腕捩", [3.9, 12.9, 0.4]),
    ("手捩", "ひじ", [4.9, 11.9, 0.3]),
    ("手首", "手捩", [5.8, 11.0, 0.2]),
    ("足", "下半身", [1.0, 10.4, 0.2]),
    ("ひざ", "足", [1.0, 5.8, 0.0]),
    ("足首", "ひざ", [1.0, 1.2, 0.4]),
    ("つま先", "足首", [1.0, 0.0, -1.4]),
    ("足ＩＫ", "全ての親", [1.0, 1.2, 0.4]),
];

const CENTRE: [(&str, Option<&str>, [f32; 3]); 8] = [
    ("全ての親", None, [0.0, 0.0, 0.0]),
    ("センター", Some("全ての親"), [0.0, 8.0, 0.0]),
    ("グルーブ", Some("センター"), [0.0, 8.2, 0.0]),
    ("下半身", Some("グルーブ"), [0.0, 11.4, 0.2]),
    ("上半身", Some("グルーブ"), [0.0, 11.4, 0.2]),
    ("上半身2", Some("上半身"), [0.0, 12.8, 0.1]),
    ("首", Some("上半身2"), [0.0, 15.6, 0.3]),
    ("頭", Some("首"), [0.0, 16.6, 0.1]),
];

/// The built-in standard MMD rig (see the module docs for its proportions).
pub fn standard_rig() -> MmdRig {
    let mut bones: Vec<MmdBone> = Vec::new();
    let find = |bones: &[MmdBone], name: &str| bones.iter().position(|b| b.name == name);
    for (name, parent, p) in CENTRE {
        let parent = parent.and_then(|n| find(&bones, n));
        bones.push(MmdBone::new(name, parent, to_right_handed(Vec3::from(p))));
    }
    for (side, sign) in [("左", 1.0f32), ("右", -1.0)] {
        for (name, parent, p) in SIDE {
            let parent_name = if CENTRE.iter().any(|c| c.0 == parent) { parent.to_string() } else { format!("{side}{parent}") };
            let parent = find(&bones, &parent_name);
            let pos = to_right_handed(Vec3::new(p[0] * sign, p[1], p[2]));
            bones.push(MmdBone::new(format!("{side}{name}"), parent, pos));
        }
        let ankle = find(&bones, &format!("{side}足首"));
        let toe = find(&bones, &format!("{side}つま先"));
        let (Some(ankle), Some(toe)) = (ankle, toe) else { continue };
        let foot_ik = find(&bones, &format!("{side}足ＩＫ")).unwrap_or(0);
        let knee = find(&bones, &format!("{side}ひざ")).unwrap_or(0);
        let leg = find(&bones, &format!("{side}足")).unwrap_or(0);
        bones[foot_ik].ik = Some(IkChain {
            effector: ankle,
            loop_count: 40,
            limit_angle_rad: 2.0,
            links: vec![IkLink { bone: knee, limit: Some(AngleLimit::KneeX) }, IkLink { bone: leg, limit: None }],
        });
        let mut toe_ik = MmdBone::new(format!("{side}つま先ＩＫ"), Some(foot_ik), bones[toe].rest_position);
        toe_ik.ik = Some(IkChain { effector: toe, loop_count: 3, limit_angle_rad: 4.0, links: vec![IkLink { bone: ankle, limit: None }] });
        bones.push(toe_ik);
    }
    // The table above is a valid rig by construction (checked by the unit tests).
    match MmdRig::new("standard", bones) {
        Ok(r) => r,
        Err(e) => unreachable!("built-in standard MMD rig is invalid: {e}"),
    }
}
