//! Joint hierarchies: names, parents (always before children), rest offsets and rotations.

use glam::{Mat4, Quat, Vec3};
use serde::{Deserialize, Serialize};

/// One joint of a skeleton.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Joint {
    pub name: String,
    /// Index of the parent joint; `None` only for roots. Always smaller than this joint's index.
    pub parent: Option<usize>,
    /// Translation from the parent joint in the parent's frame, metres, when the joint has no
    /// animated translation.
    pub rest_offset: Vec3,
    /// Rest rotation in the parent's frame (identity for BVH; the node's rotation for glTF).
    pub rest_rotation: Quat,
    /// A BVH "End Site" or a glTF tip node: it carries no rotation channels of its own.
    pub end_site: bool,
}

/// A joint hierarchy stored parents-before-children in one flat array.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Skeleton {
    pub joints: Vec<Joint>,
}

impl Skeleton {
    pub fn len(&self) -> usize {
        self.joints.len()
    }

    pub fn is_empty(&self) -> bool {
        self.joints.is_empty()
    }

    /// Index of the first joint with this exact name.
    pub fn find(&self, name: &str) -> Option<usize> {
        self.joints.iter().position(|j| j.name == name)
    }

    /// Children of joint `index`, in order.
    pub fn children(&self, index: usize) -> impl Iterator<Item = usize> + '_ {
        self.joints
            .iter()
            .enumerate()
            .filter(move |(_, j)| j.parent == Some(index))
            .map(|(i, _)| i)
    }

    /// Number of joints that are not end sites (what a BVH file calls ROOT and JOINT).
    pub fn animated_joint_count(&self) -> usize {
        self.joints.iter().filter(|j| !j.end_site).count()
    }

    /// Checks the parents-before-children invariant.
    pub fn is_topologically_ordered(&self) -> bool {
        self.joints
            .iter()
            .enumerate()
            .all(|(i, j)| j.parent.is_none_or(|p| p < i))
    }

    /// World positions of the rest pose.
    pub fn rest_positions(&self) -> Vec<Vec3> {
        crate::motion::rest_world(self).1
    }

    /// Forward kinematics of one pose given local rotations and translations (one per joint):
    /// world positions into `positions`, and world matrices into `matrices` when given (the
    /// motion kernel's [`crate::motion::local_to_world`]).
    pub fn forward_kinematics(&self, local_rotations: &[Quat], local_translations: &[Vec3], positions: &mut Vec<Vec3>, matrices: Option<&mut Vec<Mat4>>) {
        let n = self.len().min(local_rotations.len()).min(local_translations.len());
        let mut rots = vec![Quat::IDENTITY; n];
        positions.clear();
        positions.resize(n, Vec3::ZERO);
        crate::motion::local_to_world(self, local_rotations, local_translations, &mut rots, positions);
        if let Some(m) = matrices {
            m.clear();
            m.extend(rots.iter().zip(positions.iter()).map(|(r, p)| Mat4::from_rotation_translation(*r, *p)));
        }
    }

    /// Forward kinematics of one pose without allocating (for hot loops): each joint stands
    /// at its parent's position plus its rest offset turned by the parent's world rotation;
    /// a joint without a parent (or listed before it) stands at `root`. Writes the world
    /// rotations and positions of the first `min(joints, local, rot, pos)` joints (the
    /// motion kernel's [`crate::motion::local_to_world_at`]).
    pub fn pose_into(&self, local: &[Quat], root: Vec3, rot: &mut [Quat], pos: &mut [Vec3]) {
        crate::motion::local_to_world_at(self, local, root, rot, pos);
    }

    /// World positions of a pose given only local rotations: rest offsets for every joint and
    /// the root at the origin.
    pub fn posed_at_origin(&self, local_rotations: &[Quat]) -> Vec<Vec3> {
        let n = self.len().min(local_rotations.len());
        let mut rot = vec![Quat::IDENTITY; n];
        let mut out = vec![Vec3::ZERO; n];
        crate::motion::local_to_world_at(self, local_rotations, Vec3::ZERO, &mut rot, &mut out);
        out
    }

    /// Index pairs (parent, child) of every bone, for drawing.
    pub fn bones(&self) -> Vec<(usize, usize)> {
        self.joints
            .iter()
            .enumerate()
            .filter_map(|(i, j)| j.parent.map(|p| (p, i)))
            .collect()
    }
}
