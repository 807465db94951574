//! Face morphs of an MMD model played from a VMD's morph keys (issue 28): each keyed morph's
//! weight at a frame (VMD morph keys are linear between keys and held outside them), and the
//! vertex offsets the weighted morphs put on the model's vertices — vertex morphs directly,
//! group morphs expanded into their members (one level, as MMD does: a group inside a group is
//! not followed), the other kinds left out here (bone and material morphs are in
//! [`super::morph_effects`]; UV morphs of the base UV are laid on the drawn mesh here as
//! UV offsets, those of the additional UVs and flip and impulse morphs are not played). Offsets are in
//! the drawn mesh's frame: right-handed (z negated, as the mesh's positions) and in metres.
//!
//! Kept apart from the drawing so it is checked natively: a viewer adds the offsets of the
//! frame to the model's vertices before skinning. [`DrawnMorphs`] lays the morphs on the drawn
//! mesh ([`super::mesh::model_character`] draws a model vertex once in each material part that
//! uses it), so a frame's offsets come out in the order the renderer's per-vertex offset buffer
//! holds them, with no model-sized pass between.

use std::collections::HashMap;

use glam::{Quat, Vec3};

use super::morph_effects::{apply_bone_morphs, BoneMorph, MaterialBase, MaterialFactors, MorphEffects};
use super::{to_right_handed, METRES_PER_MMD_UNIT};
use crate::import::mmd_model::{MmdModel, MorphData};
use crate::import::vmd::MorphKey;

/// One model morph's keys, in frame order: (frame, weight).
#[derive(Clone, Debug, PartialEq)]
struct Track {
    morph: usize,
    keys: Vec<(f32, f32)>,
}

/// A VMD's morph keys matched to a model's morphs by name.
#[derive(Clone, Debug, PartialEq, Default)]
pub struct FaceMorphs {
    tracks: Vec<Track>,
    /// Keyed morph names the model lacks (their keys are ignored, as MMD ignores them).
    pub unmatched: Vec<String>,
}

impl FaceMorphs {
    /// The keys of `keys` whose names are morphs of `model` (the first morph of a repeated
    /// name, as MMD takes it); keys of one morph at the same frame: the last in the file wins.
    /// Non-finite weights are dropped.
    pub fn new(model: &MmdModel, keys: &[MorphKey]) -> FaceMorphs {
        FaceMorphs::for_names(model.morphs.iter().map(|m| m.name.as_str()), keys)
    }

    /// [`FaceMorphs::new`] for a model given by its morph names, in the model's order.
    pub fn for_names<'a>(names: impl IntoIterator<Item = &'a str>, keys: &[MorphKey]) -> FaceMorphs {
        let mut index: HashMap<&str, usize> = HashMap::new();
        for (i, name) in names.into_iter().enumerate() {
            index.entry(name).or_insert(i);
        }
        let mut by_morph: HashMap<usize, Vec<(f32, f32)>> = HashMap::new();
        let mut unmatched: Vec<String> = Vec::new();
        for k in keys.iter().filter(|k| k.weight.is_finite()) {
            match index.get(k.name.as_str()) {
                Some(&m) => by_morph.entry(m).or_default().push((k.frame as f32, k.weight)),
                None => {
                    if !unmatched.contains(&k.name) {
                        unmatched.push(k.name.clone());
                    }
                }
            }
        }
        let mut tracks: Vec<Track> = by_morph
            .into_iter()
            .map(|(morph, mut keys)| {
                // Stable: the later key of a frame stays after the earlier one.
                keys.sort_by(|a, b| a.0.total_cmp(&b.0));
                let mut dedup: Vec<(f32, f32)> = Vec::with_capacity(keys.len());
                for k in keys {
                    match dedup.last_mut() {
                        Some(last) if last.0 == k.0 => *last = k,
                        _ => dedup.push(k),
                    }
                }
                Track { morph, keys: dedup }
            })
            .collect();
        tracks.sort_by_key(|t| t.morph);
        FaceMorphs { tracks, unmatched }
    }

    /// Whether any key matched a morph of the model.
    pub fn is_empty(&self) -> bool {
        self.tracks.is_empty()
    }

    /// The model morphs its keys play (whatever their weight), in the model's order.
    pub fn keyed(&self) -> impl Iterator<Item = usize> + '_ {
        self.tracks.iter().map(|t| t.morph)
    }

    /// Each keyed morph's weight at `frame` (30 fps motion frames; fractional between them):
    /// linear between its keys, its first weight before them and its last after. Morphs at
    /// weight 0 are left out.
    pub fn weights_at(&self, frame: f32) -> Vec<(usize, f32)> {
        let frame = if frame.is_finite() { frame } else { 0.0 };
        let mut out = Vec::new();
        for t in &self.tracks {
            let w = match t.keys.partition_point(|k| k.0 <= frame) {
                0 => t.keys[0].1,
                i if i == t.keys.len() => t.keys[i - 1].1,
                i => {
                    let (a, b) = (t.keys[i - 1], t.keys[i]);
                    let s = (frame - a.0) / (b.0 - a.0);
                    a.1 + (b.1 - a.1) * s
                }
            };
            if w != 0.0 {
                out.push((t.morph, w));
            }
        }
        out
    }
}

/// The offsets (metres, the mesh's right-handed frame) the weighted morphs put on the model's
/// vertices, into `out` (one per model vertex; resized and zeroed). Group morphs add their
/// vertex-morph members at weight × member weight; morph and vertex indices out of range are
/// skipped. Returns how many vertices moved.
pub fn vertex_offsets_into(model: &MmdModel, weights: &[(usize, f32)], out: &mut Vec<Vec3>) -> usize {
    out.clear();
    out.resize(model.vertices.len(), Vec3::ZERO);
    let add = |morph: usize, w: f32, out: &mut Vec<Vec3>| {
        if let Some(MorphData::Vertex(offsets)) = model.morphs.get(morph).map(|m| &m.data) {
            for (v, d) in offsets {
                if let Some(o) = out.get_mut(*v) {
                    *o += to_right_handed(*d) * (w * METRES_PER_MMD_UNIT);
                }
            }
        }
    };
    for &(m, w) in weights {
        match model.morphs.get(m).map(|m| &m.data) {
            Some(MorphData::Vertex(_)) => add(m, w, out),
            Some(MorphData::Group(members)) => {
                for &(member, mw) in members {
                    if member != m && mw.is_finite() {
                        add(member, w * mw, out);
                    }
                }
            }
            _ => {}
        }
    }
    out.iter().filter(|o| **o != Vec3::ZERO).count()
}

/// A model's morphs laid on its drawn mesh: per vertex morph, the drawn vertices it moves (each
/// model vertex once per material part that draws it) and their offsets (metres, right-handed);
/// per group morph, its members. Built once per model; [`DrawnMorphs::offsets_into`] then gives
/// a frame's offsets in drawn-vertex order (the parts of [`super::mesh::ModelCharacter`]'s mesh
/// one after another), which is what the renderer adds to each vertex before skinning.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct DrawnMorphs {
    /// The model's morph names, in its order (what a VMD's keys are matched by).
    names: Vec<String>,
    /// Per model morph: a vertex morph's (drawn vertex, offset); empty for other kinds.
    vertex: Vec<Vec<(u32, Vec3)>>,
    /// Per model morph: a group morph's (member, weight); empty for other kinds.
    group: Vec<Vec<(usize, f32)>>,
    /// Per model morph: a UV morph's (drawn vertex, offset of the base UV); empty for other
    /// kinds and for morphs of the additional UVs (which nothing draws).
    uv: Vec<Vec<(u32, [f32; 2])>>,
    drawn_len: usize,
    /// The model's bone and material morphs ([`DrawnMorphs::with_effects`]; empty without).
    effects: MorphEffects,
    /// Per mesh part, the model material it draws ([`super::mesh::ModelCharacter::part_material`]).
    part_material: Vec<usize>,
    /// Per skeleton joint, the rig bone it is ([`super::mesh::ModelCharacter::rig_index`]):
    /// where bone morphs go on a sampled pose ([`DrawnMorphs::bone_morph_pose`]; empty without).
    rig_index: Vec<usize>,
}

impl DrawnMorphs {
    /// `drawn_vertices`: per mesh part, the model vertex of each of its drawn vertices
    /// ([`super::mesh::ModelCharacter::drawn_vertices`]). Model vertices out of range (in the
    /// map or in a morph) are skipped, as are non-finite offsets.
    pub fn new(model: &MmdModel, drawn_vertices: &[Vec<u32>]) -> DrawnMorphs {
        // Model vertex → its drawn copies, as offsets into one flat list (CSR).
        let n = model.vertices.len();
        let mut start = vec![0u32; n + 1];
        for &v in drawn_vertices.iter().flatten() {
            if let Some(c) = start.get_mut(v as usize + 1).filter(|_| (v as usize) < n) {
                *c += 1;
            }
        }
        for i in 0..n {
            start[i + 1] += start[i];
        }
        let mut fill = start.clone();
        let mut copies = vec![0u32; start[n] as usize];
        for (drawn, &v) in drawn_vertices.iter().flatten().enumerate() {
            if let Some(at) = fill.get_mut(v as usize).filter(|_| (v as usize) < n) {
                copies[*at as usize] = drawn as u32;
                *at += 1;
            }
        }
        let mut vertex = Vec::with_capacity(model.morphs.len());
        let mut group = Vec::with_capacity(model.morphs.len());
        let mut uv = Vec::with_capacity(model.morphs.len());
        for m in &model.morphs {
            let (mut vs, mut gs, mut us) = (Vec::new(), Vec::new(), Vec::new());
            match &m.data {
                MorphData::Vertex(offsets) => {
                    for (v, d) in offsets {
                        let d = to_right_handed(*d) * METRES_PER_MMD_UNIT;
                        if *v >= n || !d.is_finite() {
                            continue;
                        }
                        for &c in &copies[start[*v] as usize..start[*v + 1] as usize] {
                            vs.push((c, d));
                        }
                    }
                }
                MorphData::Group(members) => gs = members.iter().copied().filter(|(_, w)| w.is_finite()).collect(),
                // The base UV's offsets (x, y of PMX's four; UVs as the mesh keeps them, v down).
                MorphData::Uv { channel: 0, offsets } => {
                    for (v, d) in offsets {
                        if *v >= n || !(d.x.is_finite() && d.y.is_finite()) {
                            continue;
                        }
                        for &c in &copies[start[*v] as usize..start[*v + 1] as usize] {
                            us.push((c, [d.x, d.y]));
                        }
                    }
                }
                _ => {}
            }
            vertex.push(vs);
            group.push(gs);
            uv.push(us);
        }
        DrawnMorphs {
            names: model.morphs.iter().map(|m| m.name.clone()).collect(),
            vertex,
            group,
            uv,
            drawn_len: drawn_vertices.iter().map(Vec::len).sum(),
            effects: MorphEffects::default(),
            part_material: Vec::new(),
            rig_index: Vec::new(),
        }
    }

    /// The same, also keeping the model's bone and material morphs, and which material each
    /// mesh part draws (`part_material`, [`super::mesh::ModelCharacter::part_material`]), so
    /// [`DrawnMorphs::part_factors_into`] gives a frame's material factors per part.
    pub fn with_effects(mut self, model: &MmdModel, part_material: &[usize]) -> DrawnMorphs {
        self.effects = MorphEffects::new(model);
        self.part_material = part_material.to_vec();
        self
    }

    /// The same, also keeping which rig bone each joint of the drawn skeleton is (`rig_index`,
    /// [`super::mesh::ModelCharacter::rig_index`]), so [`DrawnMorphs::bone_morph_pose`] can put
    /// the bone morphs on a sampled pose.
    pub fn with_rig_index(mut self, rig_index: &[usize]) -> DrawnMorphs {
        self.rig_index = rig_index.to_vec();
        self
    }

    /// Whether the model has bone morphs this can put on a pose (made [`DrawnMorphs::with_effects`]
    /// and [`DrawnMorphs::with_rig_index`]).
    pub fn has_bone_morphs(&self) -> bool {
        !self.rig_index.is_empty() && self.effects.has_bone_morphs()
    }

    /// Puts the bone morphs of `weights` on a local pose of the drawn skeleton (sampled from a
    /// clip, before world transforms and skinning), in place ([`super::morph_effects::apply_bone_morphs`]);
    /// `scratch` is reused. Returns how many joints moved.
    pub fn bone_morph_pose(&self, weights: &[(usize, f32)], scratch: &mut Vec<BoneMorph>, rotations: &mut [Quat], translations: &mut [Vec3]) -> usize {
        if !self.has_bone_morphs() || self.effects.bone_morphs_into(weights, scratch) == 0 {
            return 0;
        }
        apply_bone_morphs(scratch, &self.rig_index, METRES_PER_MMD_UNIT, rotations, translations)
    }

    /// The model's bone and material morphs (empty unless made [`DrawnMorphs::with_effects`]).
    pub fn effects(&self) -> &MorphEffects {
        &self.effects
    }

    /// Whether the weights a VMD keys can show nothing on the mesh: no vertex or UV morph moves
    /// a drawn vertex and there is no material or bone morph.
    pub fn shows_nothing(&self) -> bool {
        self.is_empty() && !self.has_uv_morphs() && !self.effects.has_material_morphs() && !self.has_bone_morphs()
    }

    /// Per mesh part, the material factors the weighted morphs put on its material, into `out`
    /// (one per part; resized and reset), and the part's material's edge size; returns how many
    /// parts changed.
    pub fn part_factors_into(&self, weights: &[(usize, f32)], out: &mut Vec<(MaterialFactors, f32)>) -> usize {
        let mut per_material = Vec::new();
        self.effects.material_factors_into(weights, &mut per_material);
        out.clear();
        out.extend(self.part_material.iter().map(|&m| (per_material.get(m).copied().unwrap_or(MaterialFactors::NONE), self.effects.edge_size(m))));
        out.iter().filter(|(f, _)| *f != MaterialFactors::NONE).count()
    }

    /// Mesh part `part`'s material's ambient and specular values (zero when out of range).
    pub fn part_base(&self, part: usize) -> MaterialBase {
        self.part_material.get(part).map(|&m| self.effects.material_base(m)).unwrap_or_default()
    }

    /// The model's morph names, in its order (what morph indices of weights refer to).
    pub fn morph_names(&self) -> &[String] {
        &self.names
    }

    /// How many drawn vertices the mesh has (the length of [`DrawnMorphs::offsets_into`]'s output).
    pub fn drawn_len(&self) -> usize {
        self.drawn_len
    }

    /// Whether no vertex morph moves a drawn vertex (nothing a VMD's keys could show).
    pub fn is_empty(&self) -> bool {
        self.vertex.iter().all(Vec::is_empty)
    }

    /// A VMD's morph keys matched to this model's morphs by name ([`FaceMorphs::new`]).
    pub fn faces(&self, keys: &[MorphKey]) -> FaceMorphs {
        FaceMorphs::for_names(self.names.iter().map(String::as_str), keys)
    }

    /// Whether the model has a UV morph of the base UV that moves a drawn vertex.
    pub fn has_uv_morphs(&self) -> bool {
        self.uv.iter().any(|u| !u.is_empty())
    }

    /// The base-UV offsets the weighted UV morphs put on the drawn vertices, into `out` (one per
    /// drawn vertex; resized and zeroed), group members one level deep as for vertex morphs:
    /// what the renderer adds to each vertex's UV. Returns how many drawn vertices' UVs moved.
    pub fn uv_offsets_into(&self, weights: &[(usize, f32)], out: &mut Vec<[f32; 2]>) -> usize {
        out.clear();
        out.resize(self.drawn_len, [0.0; 2]);
        let add = |morph: usize, w: f32, out: &mut Vec<[f32; 2]>| {
            for &(v, d) in self.uv.get(morph).map_or(&[][..], Vec::as_slice) {
                if let Some(o) = out.get_mut(v as usize) {
                    o[0] += d[0] * w;
                    o[1] += d[1] * w;
                }
            }
        };
        for &(m, w) in weights.iter().filter(|(_, w)| w.is_finite()) {
            add(m, w, out);
            for &(member, mw) in self.group.get(m).map_or(&[][..], Vec::as_slice) {
                if member != m {
                    add(member, w * mw, out);
                }
            }
        }
        out.iter().filter(|o| **o != [0.0; 2]).count()
    }

    /// The offsets the weighted morphs put on the drawn vertices, into `out` (one per drawn
    /// vertex; resized and zeroed): as [`vertex_offsets_into`] on the model, each model vertex's
    /// offset given to every drawn copy of it. Returns how many drawn vertices moved.
    pub fn offsets_into(&self, weights: &[(usize, f32)], out: &mut Vec<Vec3>) -> usize {
        out.clear();
        out.resize(self.drawn_len, Vec3::ZERO);
        let add = |morph: usize, w: f32, out: &mut Vec<Vec3>| {
            for &(v, d) in self.vertex.get(morph).map_or(&[][..], Vec::as_slice) {
                if let Some(o) = out.get_mut(v as usize) {
                    *o += d * w;
                }
            }
        };
        for &(m, w) in weights.iter().filter(|(_, w)| w.is_finite()) {
            add(m, w, out);
            // Group morphs, one level deep (a group inside a group is not followed, as in MMD).
            for &(member, mw) in self.group.get(m).map_or(&[][..], Vec::as_slice) {
                if member != m {
                    add(member, w * mw, out);
                }
            }
        }
        out.iter().filter(|o| **o != Vec3::ZERO).count()
    }
}
