//! The eigen signature of a segment (spec §F): the principal axes of its frames' features
//! (every canonical joint's position from a fixed reference pose, its velocity, a constant),
//! which the relevance feedback compares by kWAS.

use glam::Vec3;

use super::super::eigen::Signature;
use super::LIBRARY_FPS;
use crate::canon::humanoid::CANON_COUNT;

/// Eigen axes kept per signature.
pub const SIGNATURE_AXES: usize = 5;
/// The pose the signature's features are measured from: the mean §B-normalised position (body
/// heights; x, y, z) of every canonical joint (in [`Canon::ALL`]'s order) over the built-in
/// moves in 4 (a unit test recomputes it; the moves in 3, added later, leave it as it was). A
/// fixed pose, not the current library's mean, so a segment's signature never changes when
/// clips (or moves) are added.
pub const SIGNATURE_REFERENCE: [[f32; 3]; CANON_COUNT] = [
    [0.000, 0.035, 0.0],    // hips
    [0.000, 0.106, 0.0],    // spine
    [-0.004, 0.212, 0.0],   // chest
    [-0.015, 0.367, 0.0],   // neck
    [-0.036, 0.450, 0.0],   // head
    [-0.013, 0.331, 0.021], // left shoulder
    [-0.013, 0.334, 0.127], // left upper arm
    [-0.018, 0.233, 0.193], // left forearm
    [-0.135, 0.258, 0.178], // left hand
    [-0.013, 0.331, -0.021], // right side, the same order
    [-0.013, 0.334, -0.127],
    [-0.018, 0.233, -0.193],
    [-0.135, 0.258, -0.178],
    [0.000, 0.000, 0.064],   // left upper leg
    [-0.111, -0.266, 0.108], // left lower leg
    [-0.002, -0.523, 0.093], // left foot
    [-0.077, -0.587, 0.103], // left toe
    [0.000, 0.000, -0.064],
    [-0.111, -0.266, -0.108],
    [-0.002, -0.523, -0.093],
    [-0.077, -0.587, -0.103],
];
/// The velocity part of the signature's features: each joint's displacement over this span
/// (seconds; a central difference over ±2 frames at [`LIBRARY_FPS`], doubled), body heights.
/// Chosen with the constant below by the `choreo_preference_features` bench on its tuning
/// sets (spans of 0.07–0.4 s tried; module docs of `choreo::feedback` give the figures).
pub const SIGNATURE_VELOCITY_SECS: f32 = 4.0 / LIBRARY_FPS;
/// The constant last feature of every frame, body heights, so the first principal axis of the
/// uncentred matrix carries the segment's mean pose with its sign (eigenvectors have none;
/// against the constant, +pose and −pose point differently) and the rest how it moves. Its
/// size sets how much that first axis weighs against the others in kWAS; 0.25–1.25 tried
/// (`choreo_preference_features`).
pub const SIGNATURE_OFFSET: f32 = 1.0;

/// The eigen signature (spec §F) of frames `si..ei` of a clip's §B-normalised canonical
/// positions. Features per frame (every other frame: 15 per second is plenty for the principal
/// axes): every canonical joint's position minus its [`SIGNATURE_REFERENCE`], then its
/// displacement over [`SIGNATURE_VELOCITY_SECS`] (within the segment), then
/// [`SIGNATURE_OFFSET`]; axes of the uncentred matrix ([`Signature::of_uncentred`]).
///
/// Why these features: §J's perceptual distance (what the relevance feedback should agree
/// with) is the mean distance of *every* joint's position, frame by frame; with velocities the
/// signature tells apart motions that pass through the same poses at other speeds or in
/// another order (the figures: `docs/benchmarks-notes-choreo.md`).
pub fn signature_of(normed: &[Vec3], si: usize, ei: usize) -> Signature {
    const J: usize = CANON_COUNT;
    let dims = J * 6 + 1;
    let last = ei.max(si);
    let mut feats = Vec::with_capacity((ei.saturating_sub(si) / 2 + 1) * dims);
    for f in (si..ei).step_by(2) {
        let frame = &normed[f * J..(f + 1) * J];
        for (p, r) in frame.iter().zip(&SIGNATURE_REFERENCE) {
            feats.extend_from_slice(&[p.x - r[0], p.y - r[1], p.z - r[2]]);
        }
        // Central difference over ±2 frames, one-sided at the segment's ends, scaled to the
        // displacement over SIGNATURE_VELOCITY_SECS.
        let (f0, f1) = (f.saturating_sub(2).max(si), (f + 2).min(last));
        let scale = if f1 > f0 { SIGNATURE_VELOCITY_SECS * LIBRARY_FPS / (f1 - f0) as f32 } else { 0.0 };
        for j in 0..J {
            let d = (normed[f1 * J + j] - normed[f0 * J + j]) * scale;
            feats.extend_from_slice(&[d.x, d.y, d.z]);
        }
        feats.push(SIGNATURE_OFFSET);
    }
    Signature::of_uncentred(&feats, dims, SIGNATURE_AXES)
}
