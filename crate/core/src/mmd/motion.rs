//! VMD bone keys sampled as MMD samples them (per-channel cubic Bézier easing between keys at
//! 30 fps), posed on an [`MmdRig`] and turned into an engine [`Clip`] in metres.
//!
//! The Clip's skeleton is the rig's deforming bones: IK bones and the targets hanging from them
//! are dropped, because after IK is solved their whole effect is already in the leg rotations,
//! and a 足ＩＫ joint dangling beside the foot would be a stray limb to every humanoid operation.

use std::collections::HashMap;
use std::sync::Arc;

use glam::{Quat, Vec3};

use super::{quat_to_right_handed, to_right_handed, MmdPose, MmdRig, MmdRigError};
use crate::clip::{Clip, TranslationTrack};
use crate::skeleton::{Joint, Skeleton};

/// The longest motion turned into a clip: one hour at 30 fps (a key at frame 4 billion must
/// not become a 4-billion-frame allocation).
pub const MAX_CLIP_FRAMES: usize = 30 * 60 * 60;

/// MMD's usual scale: one unit is 8 cm (a ~20-unit model is 1.6 m tall).
pub const METRES_PER_MMD_UNIT: f32 = 0.08;

/// One VMD bone key, as stored in the file (MMD's left-handed frame, model units).
#[derive(Clone, Debug, PartialEq)]
pub struct VmdBoneKey {
    pub frame: u32,
    pub translation: Vec3,
    pub rotation: Quat,
    /// Bézier control points `(x1, y1, x2, y2)`, each 0–127, per channel X, Y, Z, rotation.
    pub curves: [[u8; 4]; 4],
}

impl VmdBoneKey {
    /// The curves of a key from its 64 interpolation bytes (the layout three.js's MMDLoader reads:
    /// channel `c`'s x1, y1, x2, y2 at bytes `c`, `c + 4`, `c + 8`, `c + 12`).
    pub fn curves_from_vmd(bytes: &[u8; 64]) -> [[u8; 4]; 4] {
        let mut c = [[0u8; 4]; 4];
        for (ch, out) in c.iter_mut().enumerate() {
            *out = [bytes[ch], bytes[ch + 4], bytes[ch + 8], bytes[ch + 12]];
        }
        c
    }

    /// MMD's default (linear) curves: (20, 20, 107, 107) on every channel.
    pub const LINEAR: [[u8; 4]; 4] = [[20, 20, 107, 107]; 4];

    /// A parsed VMD key (its name goes to the [`BoneKeys`] holding it).
    pub fn from_vmd_key(k: &crate::import::vmd::BoneKey) -> VmdBoneKey {
        let curves = [k.curves.x, k.curves.y, k.curves.z, k.curves.rotation].map(|b| [b.x1, b.y1, b.x2, b.y2]);
        VmdBoneKey { frame: k.frame, translation: k.translation, rotation: k.rotation, curves }
    }
}

/// The keys of one bone, by name.
#[derive(Clone, Debug, PartialEq)]
pub struct BoneKeys {
    pub bone: String,
    pub keys: Vec<VmdBoneKey>,
}

/// A VMD-like motion: bone keys per bone name.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct MmdMotion {
    /// The model name the VMD was made for (its header), if any.
    pub model_name: String,
    pub bones: Vec<BoneKeys>,
}

/// How a motion becomes a clip.
#[derive(Clone, Debug, PartialEq)]
pub struct MmdClipOptions {
    pub name: String,
    pub source: String,
    /// Model units to metres.
    pub metres_per_unit: f32,
}

impl Default for MmdClipOptions {
    fn default() -> Self {
        MmdClipOptions { name: "MMD motion".into(), source: "VMD".into(), metres_per_unit: METRES_PER_MMD_UNIT }
    }
}

/// three.js's `CubicBezierInterpolation._calculate`: the eased ratio at `x` in `0..=1` of the
/// curve through (0,0), (x1,y1), (x2,y2), (1,1), found by 15 bisection steps on the curve's x.
pub fn bezier_ratio(x1: f32, x2: f32, y1: f32, y2: f32, x: f32) -> f32 {
    let mut c = 0.5f32;
    let mut t = c;
    let mut s = 1.0 - t;
    let (mut sst3, mut stt3, mut ttt) = (0.0, 0.0, 0.0);
    for _ in 0..15 {
        sst3 = 3.0 * s * s * t;
        stt3 = 3.0 * s * t * t;
        ttt = t * t * t;
        let ft = sst3 * x1 + stt3 * x2 + ttt - x;
        if ft.abs() < 1e-5 {
            break;
        }
        c /= 2.0;
        t += if ft < 0.0 { c } else { -c };
        s = 1.0 - t;
    }
    sst3 * y1 + stt3 * y2 + ttt
}

fn ratio(curve: [u8; 4], w: f32) -> f32 {
    let [x1, y1, x2, y2] = curve;
    // x1 = y1 and x2 = y2 is the line y = x (MMD's default curve): no search needed.
    if x1 == y1 && x2 == y2 {
        return w;
    }
    let [x1, y1, x2, y2] = curve.map(|v| v as f32 / 127.0);
    bezier_ratio(x1, x2, y1, y2, w)
}

/// One bone's keys, sorted (a frame keyed twice: the later key in the file wins), converted to
/// the right-handed frame, sampled as three.js r171 samples them. The engine's one VMD sampler:
/// the parser ([`crate::import::vmd`]) gives keys only.
#[derive(Clone, Debug, PartialEq)]
pub struct BoneSampler {
    frames: Vec<u32>,
    translations: Vec<Vec3>,
    rotations: Vec<Quat>,
    curves: Vec<[[u8; 4]; 4]>,
}

impl BoneSampler {
    pub fn new(keys: &[VmdBoneKey]) -> BoneSampler {
        let mut sorted: Vec<&VmdBoneKey> = keys.iter().collect();
        sorted.sort_by_key(|k| k.frame);
        // Two keys on one frame: the later one in the file wins.
        let mut dedup: Vec<&VmdBoneKey> = Vec::with_capacity(sorted.len());
        for k in sorted {
            match dedup.last_mut() {
                Some(last) if last.frame == k.frame => *last = k,
                _ => dedup.push(k),
            }
        }
        let clean_q = |q: Quat| {
            let q = quat_to_right_handed(q).normalize();
            if q.is_finite() { q } else { Quat::IDENTITY }
        };
        let clean_v = |v: Vec3| if v.is_finite() { to_right_handed(v) } else { Vec3::ZERO };
        BoneSampler {
            frames: dedup.iter().map(|k| k.frame).collect(),
            translations: dedup.iter().map(|k| clean_v(k.translation)).collect(),
            rotations: dedup.iter().map(|k| clean_q(k.rotation)).collect(),
            curves: dedup.iter().map(|k| k.curves).collect(),
        }
    }

    /// Local (rotation, translation) at `frame`, as three's interpolant gives it: the first key
    /// before the first, the last after the last; between keys, each channel eased by the later
    /// key's curve (keys one frame apart do not interpolate). No keys: the rest pose.
    pub fn sample(&self, frame: f32) -> (Quat, Vec3) {
        let n = self.frames.len();
        if n == 0 {
            return (Quat::IDENTITY, Vec3::ZERO);
        }
        let i1 = self.frames.partition_point(|&f| f as f32 <= frame);
        if i1 == 0 || frame.is_nan() {
            return (self.rotations[0], self.translations[0]);
        }
        if i1 >= n {
            return (self.rotations[n - 1], self.translations[n - 1]);
        }
        let i0 = i1 - 1;
        let (f0, f1) = (self.frames[i0] as f32, self.frames[i1] as f32);
        let w = if f1 - f0 < 1.5 { 0.0 } else { (frame - f0) / (f1 - f0) };
        let c = self.curves[i1];
        let (t0, t1) = (self.translations[i0], self.translations[i1]);
        // A channel whose two keys agree needs no easing (most bones are not translated).
        let lerp = |a: f32, b: f32, curve: [u8; 4]| if a == b { a } else { let r = ratio(curve, w); a * (1.0 - r) + b * r };
        let t = Vec3::new(lerp(t0.x, t1.x, c[0]), lerp(t0.y, t1.y, c[1]), lerp(t0.z, t1.z, c[2]));
        let (q0, q1) = (self.rotations[i0], self.rotations[i1]);
        let q = if q0 == q1 { q0 } else { q0.slerp(q1, ratio(c[3], w)) };
        (q, t)
    }
}

impl MmdMotion {
    /// Last keyed frame (0 with no keys).
    pub fn last_frame(&self) -> u32 {
        self.bones.iter().flat_map(|b| b.keys.iter().map(|k| k.frame)).max().unwrap_or(0)
    }

    /// Bone names with keys that the rig does not have.
    pub fn unmatched_bones(&self, rig: &MmdRig) -> Vec<String> {
        self.bones.iter().filter(|b| !b.keys.is_empty() && rig.find(&b.bone).is_none()).map(|b| b.bone.clone()).collect()
    }
}

/// Samples a motion on a rig frame by frame.
pub struct MotionSampler<'a> {
    rig: &'a MmdRig,
    /// Per rig bone, its track (keys of every name it has in the motion, merged).
    tracks: Vec<Option<BoneSampler>>,
    rotations: Vec<Quat>,
    translations: Vec<Vec3>,
}

impl<'a> MotionSampler<'a> {
    pub fn new(rig: &'a MmdRig, motion: &MmdMotion) -> MotionSampler<'a> {
        let mut by_name: HashMap<&str, Vec<VmdBoneKey>> = HashMap::new();
        for b in &motion.bones {
            by_name.entry(b.bone.as_str()).or_default().extend(b.keys.iter().cloned());
        }
        // The first bone of a name takes its keys (three.js binds by name the same way).
        let mut tracks: Vec<Option<BoneSampler>> = Vec::with_capacity(rig.len());
        for (i, bone) in rig.bones.iter().enumerate() {
            let first = rig.find(&bone.name) == Some(i);
            tracks.push(by_name.get(bone.name.as_str()).filter(|k| first && !k.is_empty()).map(|k| BoneSampler::new(k)));
        }
        let n = rig.len();
        MotionSampler { rig, tracks, rotations: vec![Quat::IDENTITY; n], translations: vec![Vec3::ZERO; n] }
    }

    /// Poses the rig at `frame` (30 fps frames; fractions allowed).
    pub fn pose_at(&mut self, frame: f32, out: &mut MmdPose) -> Result<(), MmdRigError> {
        for (i, t) in self.tracks.iter().enumerate() {
            let (q, v) = t.as_ref().map_or((Quat::IDENTITY, Vec3::ZERO), |t| t.sample(frame));
            self.rotations[i] = q;
            self.translations[i] = v;
        }
        self.rig.pose_into(&self.rotations, &self.translations, out)
    }
}

impl MmdRig {
    /// The engine skeleton of this rig's deforming bones (IK bones and their targets dropped),
    /// parents before children, in metres, identity rest rotations; with the rig bone of each joint.
    pub fn deform_skeleton(&self, metres_per_unit: f32) -> (Skeleton, Vec<usize>) {
        let n = self.len();
        let keep: Vec<bool> = (0..n).map(|i| !self.is_ik_helper(i)).collect();
        let kept_parent = |i: usize| {
            let mut k = self.bones[i].parent;
            let mut steps = 0;
            while let Some(p) = k {
                if keep[p] || steps > n {
                    break;
                }
                steps += 1;
                k = self.bones[p].parent;
            }
            k.filter(|&p| keep[p])
        };
        let mut joint_of = vec![usize::MAX; n];
        let mut rig_index = Vec::new();
        let mut joints = Vec::new();
        for &i in &self.fk_order {
            if !keep[i] {
                continue;
            }
            let parent = kept_parent(i);
            let parent_pos = parent.map_or(Vec3::ZERO, |p| self.bones[p].rest_position);
            joint_of[i] = joints.len();
            joints.push(Joint {
                name: self.bones[i].name.clone(),
                parent: parent.map(|p| joint_of[p]),
                rest_offset: (self.bones[i].rest_position - parent_pos) * metres_per_unit,
                rest_rotation: Quat::IDENTITY,
                end_site: false,
            });
            rig_index.push(i);
        }
        (Skeleton { joints }, rig_index)
    }

    /// The motion posed on this rig (grants and IK solved) at 30 fps from frame 0 to its last
    /// key, as a clip on [`MmdRig::deform_skeleton`]: the root's translation track, and a
    /// translation track for any joint the motion moves off its rest offset (センター, グルーブ).
    pub fn motion_to_clip(&self, motion: &MmdMotion, opts: &MmdClipOptions) -> Result<Clip, MmdRigError> {
        let (skeleton, rig_index) = self.deform_skeleton(opts.metres_per_unit);
        let joints = skeleton.len();
        let frames = motion.last_frame() as usize + 1;
        if frames > MAX_CLIP_FRAMES {
            return Err(MmdRigError::TooLong { last_frame: motion.last_frame(), max_frames: MAX_CLIP_FRAMES });
        }
        let mut sampler = MotionSampler::new(self, motion);
        let mut pose = MmdPose::default();
        let mut rotations = Vec::with_capacity(frames * joints);
        let mut locals: Vec<Vec<Vec3>> = vec![Vec::with_capacity(frames); joints];
        for f in 0..frames {
            sampler.pose_at(f as f32, &mut pose)?;
            for (j, joint) in skeleton.joints.iter().enumerate() {
                let i = rig_index[j];
                let (pr, pp) = match joint.parent {
                    Some(p) => (pose.world_rotations[rig_index[p]], pose.world_positions[rig_index[p]]),
                    None => (Quat::IDENTITY, Vec3::ZERO),
                };
                let inv = pr.inverse();
                rotations.push((inv * pose.world_rotations[i]).normalize());
                locals[j].push(inv * (pose.world_positions[i] - pp) * opts.metres_per_unit);
            }
        }
        let mut translations = Vec::new();
        for (j, values) in locals.into_iter().enumerate() {
            let rest = skeleton.joints[j].rest_offset;
            let moved = values.iter().any(|v| (*v - rest).length() > 1e-5);
            if j == 0 || moved {
                translations.push(TranslationTrack { joint: j, values });
            }
        }
        Ok(Clip { name: opts.name.clone(), source: opts.source.clone(), fps: 30.0, skeleton: Arc::new(skeleton), rotations, translations })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn key(frame: u32, t: Vec3, q: Quat, curves: [[u8; 4]; 4]) -> VmdBoneKey {
        VmdBoneKey { frame, translation: t, rotation: q, curves }
    }

    #[test]
    fn linear_and_diagonal_curves_are_the_identity() {
        for i in 0..=20 {
            let x = i as f32 / 20.0;
            assert!((ratio([20, 20, 107, 107], x) - x).abs() < 1e-6);
            assert!((ratio([64, 64, 64, 64], x) - x).abs() < 1e-6);
        }
    }

    #[test]
    fn ease_in_out_matches_the_hand_solved_curve() {
        // Control points (1, 0) and (0, 1): x(t) = 3(1-t)²t + t³, y(t) = 3(1-t)t² + t³, by hand.
        // three's 15 bisection steps stop within 1e-5 of x (or at 2^-16 in t).
        for &t in &[0.1f32, 0.3, 0.5, 0.8] {
            let x = 3.0 * (1.0 - t) * (1.0 - t) * t + t * t * t;
            let y = 3.0 * (1.0 - t) * t * t + t * t * t;
            let r = ratio([127, 0, 0, 127], x);
            assert!((r - y).abs() < 2e-3, "t {t}: ratio({x}) = {r} not {y}");
        }
        assert!(ratio([127, 0, 0, 127], 0.2) < 0.05);
    }

    #[test]
    fn sampling_lerps_slerps_and_holds_ends_in_the_right_handed_frame() {
        let q1 = Quat::from_rotation_y(1.0);
        let s = BoneSampler::new(&[key(10, Vec3::ZERO, Quat::IDENTITY, VmdBoneKey::LINEAR), key(20, Vec3::new(10.0, -4.0, 2.0), q1, VmdBoneKey::LINEAR)]);
        let (q, t) = s.sample(15.0);
        assert!((t - Vec3::new(5.0, -2.0, -1.0)).length() < 1e-5, "{t}");
        assert!(q.angle_between(quat_to_right_handed(Quat::from_rotation_y(0.5))) < 1e-5);
        assert_eq!(s.sample(0.0).1, Vec3::ZERO);
        assert_eq!(s.sample(99.0).1, Vec3::new(10.0, -4.0, -2.0));
        assert_eq!(s.sample(f32::NAN).1, Vec3::ZERO);
        assert_eq!(BoneSampler::new(&[]).sample(3.0), (Quat::IDENTITY, Vec3::ZERO));
    }

    #[test]
    fn each_channel_eases_on_its_own_curve_and_unsorted_keys_sort() {
        let ease = [127, 0, 0, 127];
        let curves = [[20, 20, 107, 107], ease, [20, 20, 107, 107], ease];
        let s = BoneSampler::new(&[key(10, Vec3::splat(1.0), Quat::from_rotation_x(1.0), curves), key(0, Vec3::ZERO, Quat::IDENTITY, VmdBoneKey::LINEAR)]);
        let (q, t) = s.sample(2.0);
        assert!((t.x - 0.2).abs() < 1e-6 && (t.z + 0.2).abs() < 1e-6);
        assert!((t.y - ratio(ease, 0.2)).abs() < 1e-6 && t.y < 0.05);
        assert!((q.angle_between(Quat::IDENTITY) - ratio(ease, 0.2)).abs() < 1e-4);
        // A frame keyed twice: the later key in the file wins.
        let s = BoneSampler::new(&[key(5, Vec3::X, Quat::IDENTITY, VmdBoneKey::LINEAR), key(5, Vec3::Y, Quat::IDENTITY, VmdBoneKey::LINEAR)]);
        assert_eq!(s.sample(5.0).1, Vec3::Y);
    }
}
