//! Exporters (spec §M), beside the importers: GLB and VRM animation (`.vrma`) through
//! `gltf-json` (the `gltf` crate's own JSON types, so no JSON is assembled by hand) and BVH. Both take a skeleton, the clips on it
//! and, for GLB, the character's skinned mesh, and give bytes: nothing touches a filesystem,
//! so the same code serves the npm package (`Uint8Array`) and native tools.
//!
//! What is written re-imports into the product with the same world joint positions (checked
//! by the round-trip tests within 1 mm per metre of body height), and the GLB passes the
//! Khronos validator with no errors or warnings (checked in `tests/node/export.test.mjs`).

pub mod bvh;
pub mod gltf;
pub mod vmd;
pub mod vrma;

use thiserror::Error;

/// Why an export was refused, with the offending values.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum ExportError {
    #[error("nothing to export: no clip was given")]
    NoClips,
    #[error("the skeleton has no joints")]
    EmptySkeleton,
    #[error("clip '{clip}' is on a skeleton of {clip_joints} joints, not the exported one of {skeleton_joints}")]
    SkeletonMismatch { clip: String, clip_joints: usize, skeleton_joints: usize },
    #[error("clip '{clip}' is invalid: {message}")]
    BadClip { clip: String, message: String },
    #[error("clip '{clip}': frame {frame}, joint '{joint}' holds a value that is not finite")]
    NotFinite { clip: String, frame: usize, joint: String },
    #[error("mesh part {part}: {message}")]
    BadMesh { part: usize, message: String },
    #[error("clip '{clip}' is not humanoid, so it has no VRM humanoid bones to animate: {reason}")]
    NotHumanoid { clip: String, reason: String },
    #[error("could not encode the file: {message}")]
    Encode { message: String },
}

impl ExportError {
    /// A short machine-readable kind, stable for the JS API.
    pub fn kind(&self) -> &'static str {
        match self {
            ExportError::NoClips => "export-no-clips",
            ExportError::EmptySkeleton => "export-empty-skeleton",
            ExportError::SkeletonMismatch { .. } => "export-skeleton-mismatch",
            ExportError::BadClip { .. } => "export-bad-clip",
            ExportError::NotFinite { .. } => "export-not-finite",
            ExportError::BadMesh { .. } => "export-bad-mesh",
            ExportError::NotHumanoid { .. } => "export-not-humanoid",
            ExportError::Encode { .. } => "export-encode",
        }
    }
}

/// Checks shared by every exporter: clips exist, are valid, lie on `skeleton` and are finite.
pub(crate) fn check_clips(skeleton: &crate::Skeleton, clips: &[&crate::Clip]) -> Result<(), ExportError> {
    if skeleton.is_empty() {
        return Err(ExportError::EmptySkeleton);
    }
    if clips.is_empty() {
        return Err(ExportError::NoClips);
    }
    for c in clips {
        c.validate().map_err(|e| ExportError::BadClip { clip: c.name.clone(), message: e.to_string() })?;
        if c.skeleton.len() != skeleton.len() {
            return Err(ExportError::SkeletonMismatch { clip: c.name.clone(), clip_joints: c.skeleton.len(), skeleton_joints: skeleton.len() });
        }
        let n = skeleton.len();
        if let Some(k) = c.rotations.iter().position(|q| !q.is_finite()) {
            return Err(ExportError::NotFinite { clip: c.name.clone(), frame: k / n, joint: skeleton.joints[k % n].name.clone() });
        }
        for t in &c.translations {
            if let Some(f) = t.values.iter().position(|v| !v.is_finite()) {
                return Err(ExportError::NotFinite { clip: c.name.clone(), frame: f, joint: skeleton.joints[t.joint].name.clone() });
            }
        }
    }
    Ok(())
}
