//! The action library: clips the text parser can name, each with tags in both languages.
//!
//! Every clip in the library lives on the canonical skeleton, so any two can be joined and
//! composed. Built-in actions are authored there; an imported clip is retargeted onto it when
//! it is added ([`ActionLibrary::add_clip`]) by the engine's retargeting ([`crate::canon::retarget`]).

use glam::Vec3;
use serde::{Deserialize, Serialize};

use crate::actions::procedural::builtin_actions;
use crate::actions::{ActionError, BodyPart};
use crate::clip::Clip;
use crate::canon::humanoid::HumanoidMap;
use crate::canon::retarget::{is_canonical, to_canonical};

/// One clip of the library.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "camelCase")]
pub struct ActionEntry {
    /// Display name, also matched by the parser ("walk", "salsa_01").
    pub name: String,
    /// Tags in any language ("walk", "歩く", "locomotion"); lower-cased English.
    pub tags: Vec<String>,
    /// The body part the action mainly moves: what a Composition switches in from it.
    pub part: Option<BodyPart>,
    /// For cycles (walk, run): how far the root moves in one cycle, metres. The clip can be
    /// repeated seamlessly.
    pub cycle_advance: Option<Vec3>,
    /// Built-in (true) or added by the person.
    pub builtin: bool,
    /// The clip, on the canonical skeleton.
    pub clip: Clip,
}

impl ActionEntry {
    /// Whether the entry carries a tag (case-insensitive) or is named so.
    pub fn has_tag(&self, tag: &str) -> bool {
        let t = tag.trim().to_lowercase();
        self.name.to_lowercase() == t || self.tags.iter().any(|x| x.to_lowercase() == t)
    }

    /// The clip repeated (cycles) or played once, lasting at least `min_secs` when it is a
    /// cycle. Root positions continue from one repeat to the next.
    pub fn clip_for(&self, min_secs: f32) -> Clip {
        match self.cycle_advance {
            Some(adv) => repeat_cycle(&self.clip, adv, min_secs),
            None => self.clip.clone(),
        }
    }
}

/// Repeats a cyclic clip (whose root advances by `advance` per cycle) to last at least
/// `min_secs` (at least once).
pub fn repeat_cycle(clip: &Clip, advance: Vec3, min_secs: f32) -> Clip {
    let cycle = clip.duration_secs().max(1e-3);
    let repeats = ((min_secs / cycle).ceil() as usize).clamp(1, 1000);
    let n = clip.joint_count();
    let frames = clip.frame_count();
    let mut out = clip.clone();
    out.rotations = Vec::with_capacity(frames * n * repeats);
    for t in &mut out.translations {
        t.values.clear();
    }
    for r in 0..repeats {
        out.rotations.extend_from_slice(&clip.rotations);
        for (dst, src) in out.translations.iter_mut().zip(&clip.translations) {
            let shift = if dst.joint == 0 { Vec3::new(advance.x, 0.0, advance.z) * r as f32 } else { Vec3::ZERO };
            dst.values.extend(src.values.iter().map(|v| *v + shift));
        }
    }
    out
}

/// The clips the parser can use.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "camelCase")]
pub struct ActionLibrary {
    pub entries: Vec<ActionEntry>,
}

impl ActionLibrary {
    /// The built-in everyday actions (see [`crate::actions::procedural`]).
    pub fn builtin() -> ActionLibrary {
        let entries = builtin_actions()
            .into_iter()
            .map(|a| ActionEntry { name: a.clip.name.clone(), tags: a.tags, part: a.part, cycle_advance: a.cycle_advance, builtin: true, clip: a.clip })
            .collect();
        ActionLibrary { entries }
    }

    pub fn len(&self) -> usize {
        self.entries.len()
    }

    pub fn is_empty(&self) -> bool {
        self.entries.is_empty()
    }

    pub fn get(&self, index: usize) -> Option<&ActionEntry> {
        self.entries.get(index)
    }

    /// Adds a clip with the person's tags (e.g. `["dance", "踊る"]`), retargeting it onto the
    /// canonical skeleton when it lives on another rig. `part` names the body part the clip
    /// mainly moves, for Composition. Returns the new entry's index.
    pub fn add_clip(&mut self, clip: &Clip, tags: &[String], part: Option<BodyPart>) -> Result<usize, ActionError> {
        let tags: Vec<String> = tags.iter().map(|t| t.trim().to_lowercase()).filter(|t| !t.is_empty()).collect();
        if tags.is_empty() {
            return Err(ActionError::NoTags { name: clip.name.clone() });
        }
        clip.validate().map_err(|e| ActionError::BadClip { name: clip.name.clone(), reason: e.to_string() })?;
        let mut clip = retarget_to_canonical(clip)?;
        let mut cycle_advance = detect_cycle(&mut clip);
        if let Some(adv) = cycle_advance {
            if let Some(moved) = walk_out_of_place(&mut clip, adv) {
                cycle_advance = Some(moved);
            }
        }
        self.entries.push(ActionEntry { name: clip.name.clone(), tags, part, cycle_advance, builtin: false, clip });
        Ok(self.entries.len() - 1)
    }

    /// Replaces the tags of an entry.
    pub fn set_tags(&mut self, index: usize, tags: &[String]) -> Result<(), ActionError> {
        let len = self.entries.len();
        let e = self.entries.get_mut(index).ok_or(ActionError::NoSuchClip { index, len })?;
        let tags: Vec<String> = tags.iter().map(|t| t.trim().to_lowercase()).filter(|t| !t.is_empty()).collect();
        if tags.is_empty() {
            return Err(ActionError::NoTags { name: e.name.clone() });
        }
        e.tags = tags;
        Ok(())
    }

    /// Indices of the entries carrying every tag in `tags`, in library order.
    pub fn find_all(&self, tags: &[&str]) -> Vec<usize> {
        (0..self.entries.len()).filter(|&i| tags.iter().all(|t| self.entries[i].has_tag(t))).collect()
    }

    /// The best entry for a motion tag with optional extra tags (a side, "right"): entries with
    /// every tag first, then the motion tag alone. Built-in entries come after the person's
    /// own clips so a tagged import wins.
    pub fn find(&self, motion: &str, extra: &[&str]) -> Option<usize> {
        let mut all: Vec<&str> = vec![motion];
        all.extend_from_slice(extra);
        let pick = |v: Vec<usize>| v.iter().copied().find(|&i| !self.entries[i].builtin).or(v.first().copied());
        pick(self.find_all(&all)).or_else(|| pick(self.find_all(&[motion])))
    }

    /// Other entries sharing the motion tag of `index` (what the UI offers as swaps).
    pub fn alternatives(&self, index: usize, motion: &str) -> Vec<usize> {
        self.find_all(&[motion]).into_iter().filter(|&i| i != index).collect()
    }
}

/// Whether a clip loops (its last pose is its first, up to a small difference), and if so
/// how far the root moves per loop. A last frame that repeats the first exactly (glTF loops
/// often end on their start) is dropped so repeats do not stutter.
pub fn detect_cycle(clip: &mut Clip) -> Option<Vec3> {
    let n = clip.frame_count();
    if n < 8 {
        return None;
    }
    let (a, b) = (clip.frame_rotations(0), clip.frame_rotations(n - 1));
    let joints = a.len().max(2);
    let mean = a.iter().zip(b).skip(1).map(|(x, y)| x.angle_between(*y)).sum::<f32>() / (joints - 1) as f32;
    if !(mean < 0.08) || a[0].angle_between(b[0]) > 0.15 {
        return None;
    }
    let (r0, r1, rp) = (clip.root_translation(0), clip.root_translation(n - 1), clip.root_translation(n - 2));
    if mean < 0.01 {
        // Duplicate end frame: one loop is frames 0..n-1.
        *clip = clip.slice(0, n - 1, clip.name.clone());
        return Some(Vec3::new(r1.x - r0.x, 0.0, r1.z - r0.z));
    }
    let step = r1 - rp;
    Some(Vec3::new(r1.x - r0.x + step.x, 0.0, r1.z - r0.z + step.z))
}

/// Locomotion recorded in place (a treadmill walk: the feet slide back, the root stays) is
/// given the root motion it stands for: the lower foot is kept still on the ground and the
/// root moves instead. Returns the new advance per loop, or `None` (clip untouched) when the
/// clip already travels or its feet do not travel under it.
pub fn walk_out_of_place(clip: &mut Clip, advance: Vec3) -> Option<Vec3> {
    use crate::actions::contact::{sole_height, Foot};
    let n = clip.frame_count();
    if n < 8 || Vec3::new(advance.x, 0.0, advance.z).length() > 0.1 {
        return None;
    }
    let all = clip.all_world_positions();
    let joints = clip.joint_count();
    let frame = |f: usize| &all[f * joints..(f + 1) * joints];
    // Root displacement that keeps the lower foot still, frame to frame.
    let floor = (0..n).map(|f| sole_height(frame(f), Foot::Left).min(sole_height(frame(f), Foot::Right))).fold(f32::MAX, f32::min);
    let mut root = Vec::with_capacity(n);
    let mut at = Vec3::ZERO;
    let mut travelled = 0.0;
    let mut last_step = Vec3::ZERO;
    root.push(at);
    for f in 1..n {
        let (a, b) = (frame(f - 1), frame(f));
        let low = if sole_height(b, Foot::Left) <= sole_height(b, Foot::Right) { Foot::Left } else { Foot::Right };
        // A foot on the ground carries the body; in a flight the body keeps its speed.
        let step = if sole_height(b, low) - floor < 0.04 {
            let d = b[low.ankle().index()] - a[low.ankle().index()];
            Vec3::new(-d.x, 0.0, -d.z)
        } else {
            last_step
        };
        last_step = step;
        travelled += step.length();
        at += step;
        root.push(at);
    }
    // Only when the feet really travel under the body (not a dance on the spot).
    if at.length() < 0.2 || at.length() < 0.35 * travelled {
        return None;
    }
    let track = clip.translations.iter_mut().find(|t| t.joint == 0)?;
    for (v, r) in track.values.iter_mut().zip(&root) {
        v.x += r.x;
        v.z += r.z;
    }
    // One more step closes the loop (the last frame to the first of the next loop).
    let last = root[n - 1] - root[n - 2];
    Some(at + last)
}

/// A clip on the canonical skeleton: unchanged when it already is; otherwise retargeted by
/// bone directions ([`crate::canon::retarget::to_canonical`], the engine's one retargeting) at its own
/// frame rate. Refused when the skeleton is not humanoid.
pub fn retarget_to_canonical(clip: &Clip) -> Result<Clip, ActionError> {
    if is_canonical(&clip.skeleton) {
        return Ok(clip.clone());
    }
    let map = HumanoidMap::from_skeleton(&clip.skeleton);
    let status = map.status(&clip.skeleton, Some(clip));
    if !status.is_humanoid() {
        return Err(ActionError::NotHumanoid { name: clip.name.clone(), reason: status.to_string() });
    }
    Ok(to_canonical(clip, &map, clip.fps))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::canon::humanoid::Canon;
    use std::sync::Arc;

    #[test]
    fn builtin_has_every_action_the_parser_needs() {
        let lib = ActionLibrary::builtin();
        for tag in ["walk", "run", "kick", "jump", "wave", "clap", "rejoice", "gutsy pose", "turn", "bow", "sit", "stand", "nod", "point", "歩く", "ガッツポーズ"] {
            assert!(lib.find(tag, &[]).is_some(), "{tag}");
        }
        let r = lib.find("wave", &["right"]).unwrap();
        let l = lib.find("wave", &["left"]).unwrap();
        assert_ne!(r, l);
        assert_eq!(lib.entries[r].part, Some(BodyPart::RightArm));
    }

    #[test]
    fn tagged_clip_wins_and_retargets_identity() {
        let mut lib = ActionLibrary::builtin();
        let demo = crate::canon::builtin::demo_clip();
        let i = lib.add_clip(&demo, &["Walk".into(), "dance".into()], None).unwrap();
        assert_eq!(lib.find("walk", &[]), Some(i));
        // The demo dance loops seamlessly: it is recognised as a cycle.
        assert!(lib.entries[i].cycle_advance.is_some());
        let mut once = lib.entries[lib.find("kick", &[]).unwrap()].clip.slice(0, 40, "half a kick");
        assert!(detect_cycle(&mut once).is_none());
        assert!(lib.add_clip(&demo, &[" ".into()], None).is_err());
        assert_eq!(lib.alternatives(i, "walk").len(), 1);
    }

    #[test]
    fn a_treadmill_walk_gets_its_travel_back() {
        let lib = ActionLibrary::builtin();
        let walk = &lib.entries[lib.find("walk", &[]).unwrap()];
        let mut in_place = walk.clip.clone();
        for v in &mut in_place.translations[0].values {
            v.x = 0.0;
            v.z = 0.0;
        }
        let adv = walk_out_of_place(&mut in_place, Vec3::ZERO).expect("feet travel under the body");
        let want = walk.cycle_advance.unwrap();
        assert!((adv - want).length() < 0.15 * want.length(), "{adv} vs {want}");
        // A dance on the spot stays where it is.
        let mut demo = crate::canon::builtin::demo_clip();
        let before = demo.translations[0].values.clone();
        assert!(walk_out_of_place(&mut demo, Vec3::ZERO).is_none());
        assert_eq!(demo.translations[0].values, before);
    }

    #[test]
    fn retarget_reproduces_bone_directions() {
        // A renamed copy of the canonical skeleton is not "canonical" by name, so it goes
        // through the position-based retarget; bone directions must come back.
        let lib = ActionLibrary::builtin();
        let src = &lib.entries[lib.find("wave", &["right"]).unwrap()].clip;
        let mut sk = (*src.skeleton).clone();
        for j in &mut sk.joints {
            j.name = format!("mixamorig:{}", match j.name.as_str() {
                "hips" => "Hips", "spine" => "Spine", "chest" => "Spine2", "neck" => "Neck", "head" => "Head",
                "leftShoulder" => "LeftShoulder", "leftUpperArm" => "LeftArm", "leftForearm" => "LeftForeArm", "leftHand" => "LeftHand",
                "rightShoulder" => "RightShoulder", "rightUpperArm" => "RightArm", "rightForearm" => "RightForeArm", "rightHand" => "RightHand",
                "leftUpperLeg" => "LeftUpLeg", "leftLowerLeg" => "LeftLeg", "leftFoot" => "LeftFoot", "leftToe" => "LeftToeBase",
                "rightUpperLeg" => "RightUpLeg", "rightLowerLeg" => "RightLeg", "rightFoot" => "RightFoot", _ => "RightToeBase",
            });
        }
        let renamed = Clip { skeleton: Arc::new(sk), ..src.clone() };
        let out = retarget_to_canonical(&renamed).unwrap();
        out.validate().unwrap();
        let f = src.frame_count() / 2;
        let (a, b) = (src.world_positions(f), out.world_positions(f));
        for (p, c) in Canon::links() {
            if matches!(c, Canon::LeftShoulder | Canon::RightShoulder | Canon::Head | Canon::LeftToe | Canon::RightToe) {
                continue;
            }
            let da = (a[c.index()] - a[p.index()]).normalize();
            let db = (b[c.index()] - b[p.index()]).normalize();
            assert!(da.dot(db) > 0.99, "{p:?}->{c:?}: {da} vs {db}");
        }
    }
}
