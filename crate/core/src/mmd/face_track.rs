//! A lip-sync track (issue 28): the morph (face) keys of a VMD that MMD users load beside a dance
//! VMD onto the same model — usually a file of face keys only, which is no motion clip (it has no
//! bone keys). The project keeps such files ([`crate::project::tracks`]); this module is what they
//! mean on a model: the track's weights at a song time, laid over the drawn clip's own face keys
//! (a track overrides them for the morphs it keys, the clip's keys still play the others), and
//! its keys on an export's timeline, so a dance goes back to MMD with its lip-sync.
//!
//! Weights come from [`super::morph::FaceMorphs`] (linear between keys, held outside them): a
//! track plays exactly as the same keys in a dance VMD would.

use serde::{Deserialize, Serialize};

use super::morph::FaceMorphs;
use crate::import::vmd::{MorphKey, Vmd, VMD_FPS};

/// The name of a PMD's base morph, which some VMDs key (WAVEFILE does) though it moves nothing.
pub const PMD_BASE_MORPH: &str = "base";

/// A VMD's morph keys with the motion frame that is song time 0.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "camelCase")]
pub struct FaceTrack {
    /// The file's name, as given.
    pub source: String,
    /// The morph keys in file order, motion frames as in the file.
    pub keys: Vec<MorphKey>,
    /// The motion frame that is song time 0.
    pub song_offset_frames: u32,
}

impl FaceTrack {
    /// The morph keys of `vmd` (`None` when it has none).
    pub fn from_vmd(file: &str, vmd: &Vmd, song_offset_frames: u32) -> Option<FaceTrack> {
        (!vmd.morph_keys.is_empty()).then(|| FaceTrack { source: file.to_string(), keys: vmd.morph_keys.clone(), song_offset_frames })
    }

    /// The morphs it keys, each once, in the order first keyed.
    pub fn morph_names(&self) -> Vec<String> {
        let mut out: Vec<String> = Vec::new();
        for k in &self.keys {
            if !out.contains(&k.name) {
                out.push(k.name.clone());
            }
        }
        out
    }

    /// Song time of its last key, seconds (0 when every key is before song time 0).
    pub fn duration_secs(&self) -> f32 {
        let last = self.keys.iter().map(|k| k.frame).max().unwrap_or(0);
        last.saturating_sub(self.song_offset_frames) as f32 / VMD_FPS
    }

    /// The motion frame played at `song_secs` (fractional; song times before 0 play frame
    /// `song_offset_frames`, where the song starts).
    pub fn frame_at(&self, song_secs: f32) -> f32 {
        let s = if song_secs.is_finite() { song_secs.max(0.0) } else { 0.0 };
        self.song_offset_frames as f32 + s * VMD_FPS
    }

    /// Its keys on an export's timeline that starts at song frame `first_song_frame` (30 fps):
    /// motion frame `song_offset_frames + first_song_frame` becomes frame 0, keys before it are
    /// dropped, and a morph keyed both before and after that frame (and not on it) gets a key
    /// at frame 0 with its weight there, so the exported file plays the same weights from its
    /// first frame. File order is kept; the added keys come first.
    pub fn keys_from(&self, first_song_frame: u32) -> Vec<MorphKey> {
        let first = self.song_offset_frames.saturating_add(first_song_frame);
        let mut out = Vec::new();
        for name in self.morph_names() {
            let of: Vec<&MorphKey> = self.keys.iter().filter(|k| k.name == name && k.weight.is_finite()).collect();
            let before = of.iter().any(|k| k.frame < first);
            let on = of.iter().any(|k| k.frame == first);
            if before && !on {
                let faces = FaceMorphs::for_names([name.as_str()], &self.keys);
                let w = faces.weights_at(first as f32).first().map_or(0.0, |&(_, w)| w);
                out.push(MorphKey { name: name.clone(), frame: 0, weight: w });
            }
        }
        out.extend(self.keys.iter().filter(|k| k.frame >= first).map(|k| MorphKey { name: k.name.clone(), frame: k.frame - first, weight: k.weight }));
        out
    }
}

/// `base`'s keys (a dance's own face keys) with `over`'s laid over them: every key of a morph
/// that `over` keys is dropped from `base`, then `over`'s keys follow — a track's morphs play as
/// the track has them, the others as the dance has them.
pub fn layer_keys(base: Vec<MorphKey>, over: &[MorphKey]) -> Vec<MorphKey> {
    let mut out: Vec<MorphKey> = base.into_iter().filter(|k| !over.iter().any(|o| o.name == k.name)).collect();
    out.extend(over.iter().cloned());
    out
}

/// The face weights a model plays: the drawn clip's own face keys (`base`) and the project's
/// face tracks laid over them in order (a later track overrides an earlier one, and every track
/// the clip's own keys, for the morphs it keys). Built once per model and clip.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct LayeredFaces {
    base: Option<(FaceMorphs, u32)>,
    tracks: Vec<(FaceMorphs, u32)>,
    /// Morphs the tracks key that the model lacks (their keys are ignored), each once.
    pub missing: Vec<String>,
}

impl LayeredFaces {
    /// `names`: the model's morph names in its order; `base`: the clip's own face keys and the
    /// motion frame its clip starts at.
    pub fn new(names: &[&str], base: Option<(&[MorphKey], u32)>, tracks: &[&FaceTrack]) -> LayeredFaces {
        let base = base.map(|(keys, offset)| (FaceMorphs::for_names(names.iter().copied(), keys), offset)).filter(|(f, _)| !f.is_empty());
        let mut missing: Vec<String> = Vec::new();
        let mut layers = Vec::new();
        for t in tracks {
            let faces = FaceMorphs::for_names(names.iter().copied(), &t.keys);
            for m in &faces.unmatched {
                // A PMD's base morph (the vertex list its other morphs index) moves nothing
                // when keyed and is no morph of the model as read: not worth a notice.
                if m != PMD_BASE_MORPH && !missing.contains(m) {
                    missing.push(m.clone());
                }
            }
            if !faces.is_empty() {
                layers.push((faces, t.song_offset_frames));
            }
        }
        LayeredFaces { base, tracks: layers, missing }
    }

    /// Whether nothing plays (no key matched a morph of the model).
    pub fn is_empty(&self) -> bool {
        self.base.is_none() && self.tracks.is_empty()
    }

    /// Whether a project face track plays on the model.
    pub fn has_tracks(&self) -> bool {
        !self.tracks.is_empty()
    }

    /// Each morph's weight (model morph index, weight; weight-0 morphs left out): the clip's own
    /// keys at motion frame `base_frame` for the morphs no track keys, each track's at the motion
    /// frame of `song_secs` for the morphs it keys (a later track over an earlier one).
    pub fn weights_at(&self, base_frame: f32, song_secs: f32) -> Vec<(usize, f32)> {
        let mut out: Vec<(usize, f32)> = Vec::new();
        let mut covered: Vec<usize> = Vec::new();
        for (faces, offset) in self.tracks.iter().rev() {
            let s = if song_secs.is_finite() { song_secs.max(0.0) } else { 0.0 };
            let frame = *offset as f32 + s * VMD_FPS;
            out.extend(faces.weights_at(frame).into_iter().filter(|(m, _)| !covered.contains(m)));
            covered.extend(faces.keyed());
        }
        if let Some((faces, _)) = &self.base {
            out.extend(faces.weights_at(base_frame).into_iter().filter(|(m, _)| !covered.contains(m)));
        }
        out.sort_by_key(|(m, _)| *m);
        out
    }

    /// The motion frame the clip's own keys start at (0 without own keys).
    pub fn base_offset_frames(&self) -> u32 {
        self.base.as_ref().map_or(0, |(_, o)| *o)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn key(name: &str, frame: u32, weight: f32) -> MorphKey {
        MorphKey { name: name.into(), frame, weight }
    }

    #[test]
    fn a_track_overrides_the_clips_keys_only_for_the_morphs_it_keys() {
        let names = ["あ", "まばたき", "い"];
        let own = [key("あ", 0, 1.0), key("まばたき", 0, 0.5)];
        let track = FaceTrack { source: "lip.vmd".into(), keys: vec![key("あ", 10, 0.0), key("あ", 20, 0.8), key("う", 0, 1.0)], song_offset_frames: 10 };
        let mut keys = track.keys.clone();
        keys.push(key("base", 0, 1.0));
        let l = LayeredFaces::new(&names, Some((&own, 0)), &[&FaceTrack { keys, ..track.clone() }]);
        assert_eq!(l.missing, vec!["う".to_string()], "the PMD base morph is not named");
        // Song time 0.5 s = motion frame 25 of the track: あ held at 0.8; まばたき from the clip.
        assert_eq!(l.weights_at(3.0, 0.5), vec![(0, 0.8), (1, 0.5)]);
        // Song time 1/6 s = frame 15: halfway up.
        let w = l.weights_at(0.0, 1.0 / 6.0);
        assert!((w[0].1 - 0.4).abs() < 1e-5, "{w:?}");
        // Control: without the track the clip's あ plays.
        assert_eq!(LayeredFaces::new(&names, Some((&own, 0)), &[]).weights_at(3.0, 0.5), vec![(0, 1.0), (1, 0.5)]);
    }

    #[test]
    fn exported_keys_start_at_the_song_frame_with_the_weight_held_there() {
        let track = FaceTrack { source: "lip.vmd".into(), keys: vec![key("あ", 100, 0.0), key("あ", 200, 1.0), key("い", 170, 0.3)], song_offset_frames: 140 };
        // Song frame 10 = motion frame 150: あ is at 0.5 there and keyed before and after.
        let k = track.keys_from(10);
        assert_eq!(k, vec![key("あ", 0, 0.5), key("あ", 50, 1.0), key("い", 20, 0.3)]);
        assert_eq!(layer_keys(vec![key("あ", 3, 1.0), key("お", 3, 1.0)], &k).len(), 4);
        assert!((track.duration_secs() - 2.0).abs() < 1e-6);
    }
}
