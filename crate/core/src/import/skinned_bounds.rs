//! Where a skinned mesh is once posed, cheaply: per palette slot, the boxes (in the mesh's bind
//! space) of the vertices that slot moves with any weight, one box per octant of the slot's
//! whole box (a rotated box reaches past its contents by its corners: eight smaller boxes
//! reach less); posed, each box's corners go through that slot's palette matrix
//! (world · bind) and the result is the box of them all.
//!
//! Why: framing a character by its joints leaves out hair, skirts and hands' reach (an MMD
//! model's hair ends far from any joint). Skinning every vertex on the CPU each time the view
//! is framed would cost the whole mesh; this costs 8 corners a slot. It never cuts a vertex
//! off: a skinned vertex Σ wᵢ Mᵢ p is a weighted mean of points Mᵢ p, each inside slot i's
//! moved box (p is in slot i's box), so inside the box of all of them. It can be larger than
//! the exact bounds by what a box's corners add (a rotated box's corners reach past its
//! contents).

use glam::{Mat4, Vec3};

use super::SkinnedMesh;

/// Per palette slot, the bind-space boxes of the vertices it moves.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SkinnedBounds {
    /// Per palette slot, the (min, max) of its vertices in each octant of their whole box
    /// (empty for a slot no vertex is weighted to).
    pub slots: Vec<Vec<(Vec3, Vec3)>>,
}

fn grow(b: &mut Option<(Vec3, Vec3)>, p: Vec3) {
    *b = Some(match *b {
        None => (p, p),
        Some((lo, hi)) => (lo.min(p), hi.max(p)),
    });
}

/// Each vertex position of the mesh with the palette slots it has weight on.
fn weighted(mesh: &SkinnedMesh) -> impl Iterator<Item = (Vec3, [Option<usize>; 4])> + '_ {
    mesh.parts.iter().flat_map(|part| {
        part.positions.iter().enumerate().filter_map(move |(k, p)| {
            let p = Vec3::from(*p);
            let (Some(j), Some(w)) = (part.joints.get(k), part.weights.get(k)) else { return None };
            p.is_finite().then(|| (p, std::array::from_fn(|c| (w[c] > 0.0).then_some(j[c] as usize))))
        })
    })
}

impl SkinnedBounds {
    /// The boxes of a mesh's vertices per palette slot (a vertex counts for every slot it has
    /// weight on; vertices with a joint index past the palette, or non-finite, are left out).
    pub fn of_mesh(mesh: &SkinnedMesh) -> SkinnedBounds {
        let n = mesh.palette.len();
        let mut whole: Vec<Option<(Vec3, Vec3)>> = vec![None; n];
        for (p, slots) in weighted(mesh) {
            for s in slots.into_iter().flatten().filter(|&s| s < n) {
                grow(&mut whole[s], p);
            }
        }
        let mut octants: Vec<[Option<(Vec3, Vec3)>; 8]> = vec![[None; 8]; n];
        for (p, slots) in weighted(mesh) {
            for s in slots.into_iter().flatten().filter(|&s| s < n) {
                let Some((lo, hi)) = whole[s] else { continue };
                let mid = (lo + hi) * 0.5;
                let o = (p.x > mid.x) as usize | ((p.y > mid.y) as usize) << 1 | ((p.z > mid.z) as usize) << 2;
                grow(&mut octants[s][o], p);
            }
        }
        SkinnedBounds {
            slots: octants.into_iter().map(|o| o.into_iter().flatten().collect()).collect(),
        }
    }

    /// The box holding the mesh posed by `palette` (per slot, world · bind, as drawn), or
    /// `None` when no slot has vertices (or the palette is shorter than every used slot).
    pub fn posed(&self, palette: &[Mat4]) -> Option<(Vec3, Vec3)> {
        let mut out: Option<(Vec3, Vec3)> = None;
        for (slot, m) in self.slots.iter().zip(palette) {
            for (lo, hi) in slot {
                for c in 0..8 {
                    let corner = Vec3::new(if c & 1 == 0 { lo.x } else { hi.x }, if c & 2 == 0 { lo.y } else { hi.y }, if c & 4 == 0 { lo.z } else { hi.z });
                    let p = m.transform_point3(corner);
                    if !p.is_finite() {
                        continue;
                    }
                    grow(&mut out, p);
                }
            }
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::import::MeshPart;

    fn two_bone_mesh() -> SkinnedMesh {
        let part = MeshPart {
            positions: vec![[0.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 2.0, 0.0]],
            normals: vec![[1.0, 0.0, 0.0]; 3],
            joints: vec![[0, 0, 0, 0], [0, 1, 0, 0], [1, 0, 0, 0]],
            weights: vec![[1.0, 0.0, 0.0, 0.0], [0.5, 0.5, 0.0, 0.0], [1.0, 0.0, 0.0, 0.0]],
            indices: vec![0, 1, 2],
            ..Default::default()
        };
        SkinnedMesh {
            parts: vec![part],
            palette: vec![(0, Mat4::IDENTITY), (1, Mat4::IDENTITY)],
            textures: vec![],
        }
    }

    #[test]
    fn a_vertex_counts_for_every_slot_it_has_weight_on() {
        let b = SkinnedBounds::of_mesh(&two_bone_mesh());
        // Slot 0: the vertices at 0 and 1 (in two octants of its box); slot 1: at 1 and 2.
        assert_eq!(b.slots[0], vec![(Vec3::ZERO, Vec3::ZERO), (Vec3::Y, Vec3::Y)]);
        assert_eq!(b.slots[1], vec![(Vec3::Y, Vec3::Y), (Vec3::new(0.0, 2.0, 0.0), Vec3::new(0.0, 2.0, 0.0))]);
    }

    #[test]
    fn posed_bounds_hold_the_blended_vertex_and_follow_the_palette() {
        let mesh = two_bone_mesh();
        let b = SkinnedBounds::of_mesh(&mesh);
        // Slot 1 turned 90° about z at y = 1: its vertices swing out to −x.
        let turn = Mat4::from_translation(Vec3::Y) * Mat4::from_rotation_z(std::f32::consts::FRAC_PI_2) * Mat4::from_translation(-Vec3::Y);
        let (lo, hi) = b.posed(&[Mat4::IDENTITY, turn]).unwrap();
        assert!((lo - Vec3::new(-1.0, 0.0, 0.0)).length() < 1e-6, "{lo}");
        assert!((hi - Vec3::new(0.0, 1.0, 0.0)).length() < 1e-6, "{hi}");
        // Without slot 1's vertices (a palette of one): slot 0's box only.
        assert_eq!(b.posed(&[Mat4::IDENTITY]), Some((Vec3::ZERO, Vec3::Y)));
        assert_eq!(SkinnedBounds::default().posed(&[Mat4::IDENTITY]), None);
    }
}
