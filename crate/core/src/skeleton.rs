//! Joint hierarchies: names, parents (always before children), rest offsets and rotations.

use glam::{Quat, Vec3};
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

    /// World positions of the rest pose (posing any other is [`crate::motion::WorldPose`]'s).
    pub fn rest_positions(&self) -> Vec<Vec3> {
        crate::motion::rest_world(self).1
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
