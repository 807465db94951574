//! Composition (spec §I): one body part of motion 1 replaced by that of motion 2 ("walk while
//! waving the right hand"), with switch times searched, a blend in and out, and the sway that
//! motion 2's part causes in the rest of the body carried over.
//!
//! * **Switch times** minimise F(t_a, t_b) = α‖P₁(t_a) − P₂(t_b)‖ + β‖V₁(t_a) − V₂(t_b)‖ + γT_f,
//!   P and V the end effector's position and velocity relative to the hips (in the hips'
//!   heading frame, so facing does not count). The start pair is searched in the first
//!   `search_secs` of both (no T_f); the end pair in the last part of motion 2 and in motion 1
//!   near the same absolute time, with T_f = |ln(stretch)| where stretch is the ratio of the
//!   two intervals (0 when motion 2 keeps its own speed).
//! * **Blend**: duration ‖P_a − P_b‖ / ‖V_a‖ (clamped to `[min_blend_secs, max_blend_secs]`),
//!   angles of the switched joints interpolated with ratio = time / duration, in at the start
//!   and back out after the end.
//! * **Sway**: for every joint outside the switched part (legs excepted: they carry the
//!   floor contact), motion 2's rotation over the switched interval, as a rotation vector
//!   relative to its start, minus the cubic Hermite curve fitted to its start and end values
//!   and angular velocities, is the sway; it is added to motion 1's rotation of that joint.

use crate::fmath;
use glam::{Quat, Vec3};
use serde::{Deserialize, Serialize};

use crate::actions::{ActionError, BodyPart};
use crate::clip::Clip;
use crate::canon::humanoid::{Canon, CANON_COUNT};

/// Weights and windows of the Composition. Defaults in [`ComposeOptions::default`].
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "camelCase")]
pub struct ComposeOptions {
    /// Weight of the effector position difference, per metre (default 1).
    pub alpha: f32,
    /// Weight of the effector velocity difference, per metre/second (default 0.1).
    pub beta: f32,
    /// Weight of the stretch term T_f (default 0.5).
    pub gamma: f32,
    /// Window searched at the start of both motions and around the end, seconds (default 0.8).
    pub search_secs: f32,
    pub min_blend_secs: f32,
    pub max_blend_secs: f32,
    /// Carry motion 2's sway into motion 1 (default true).
    pub sway: bool,
    /// Use these switch times instead of searching (for comparisons).
    pub fixed: Option<SwitchTimes>,
    /// Earliest frame of motion 1 the overlay may start at (the element's own start).
    pub base_from_frame: usize,
}

impl Default for ComposeOptions {
    fn default() -> Self {
        ComposeOptions { alpha: 1.0, beta: 0.1, gamma: 0.5, search_secs: 0.8, min_blend_secs: 0.1, max_blend_secs: 0.8, sway: true, fixed: None, base_from_frame: 0 }
    }
}

/// Switch frames: motion 2's `[overlay_start, overlay_end]` is played over motion 1's
/// `[base_start, base_end]`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "camelCase")]
pub struct SwitchTimes {
    pub base_start_frame: usize,
    pub overlay_start_frame: usize,
    pub base_end_frame: usize,
    pub overlay_end_frame: usize,
}

/// What a Composition did, and how smooth its switches are.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "camelCase")]
pub struct CompositionReport {
    pub part: BodyPart,
    pub times: SwitchTimes,
    pub f_start: f32,
    pub f_end: f32,
    pub start_blend_secs: f32,
    pub end_blend_secs: f32,
    /// Effector position gap between the two motions at the start and end switch, cm.
    pub start_gap_cm: f32,
    pub end_gap_cm: f32,
    /// Largest frame-to-frame move of the effector (relative to the hips) around the
    /// switches in the output, cm: the visible jump.
    pub peak_effector_step_cm: f32,
    /// Motion 2's interval length over motion 1's (1 = own speed).
    pub stretch: f32,
    /// Joints that received sway.
    pub sway_joints: Vec<Canon>,
}

/// End-effector positions (relative to the hips, heading removed) and velocities per frame.
fn effector_track(clip: &Clip, part: BodyPart) -> (Vec<Vec3>, Vec<Vec3>) {
    let n = clip.frame_count();
    let mut pos = Vec::with_capacity(n);
    let mut pose = crate::motion::WorldPose::new();
    for f in 0..n {
        let world = &pose.of_frame(clip, f).positions;
        let hips = world[Canon::Hips.index()];
        let fwd = clip.frame_rotations(f)[0] * Vec3::Z;
        let unyaw = Quat::from_rotation_y(-fmath::atan2(fwd.x, fwd.z));
        let eff: Vec3 = part.end_effectors().iter().map(|c| world[c.index()] - hips).sum::<Vec3>() / part.end_effectors().len() as f32;
        pos.push(unyaw * eff);
    }
    let vel = (0..n)
        .map(|f| {
            let (a, b) = (f.saturating_sub(1), (f + 1).min(n - 1));
            (pos[b] - pos[a]) * clip.fps / ((b - a).max(1) as f32)
        })
        .collect();
    (pos, vel)
}

fn hermite(v0: Vec3, m0: Vec3, v1: Vec3, m1: Vec3, u: f32) -> Vec3 {
    Vec3::from_array(crate::motion::hermite(v0.to_array(), m0.to_array(), v1.to_array(), m1.to_array(), u))
}

/// The sway of `joint` in `clip` over frames `[from, to]`: rotation vectors (relative to the
/// rotation at `from`) minus their Hermite base trajectory. One value per frame.
pub fn sway_residual(clip: &Clip, joint: usize, from: usize, to: usize) -> Vec<Vec3> {
    let n = clip.joint_count();
    let to = to.min(clip.frame_count().saturating_sub(1));
    if to <= from + 2 {
        return vec![Vec3::ZERO; to.saturating_sub(from) + 1];
    }
    let q0 = clip.rotations[from * n + joint];
    let mut v: Vec<Vec3> = (from..=to).map(|f| (q0.inverse() * clip.rotations[f * n + joint]).to_scaled_axis()).collect();
    // Keep the rotation vectors continuous (a quaternion and its negative are one rotation).
    for k in 1..v.len() {
        if (v[k] - v[k - 1]).length() > std::f32::consts::PI {
            let q = Quat::from_scaled_axis(v[k]);
            let alt = (-q).to_scaled_axis();
            if (alt - v[k - 1]).length() < (v[k] - v[k - 1]).length() {
                v[k] = alt;
            }
        }
    }
    let m = v.len() - 1;
    // Tangents per interval (the curve parameter runs 0..1 over m frames).
    let m0 = (v[1] - v[0]) * m as f32;
    let m1 = (v[m] - v[m - 1]) * m as f32;
    (0..=m).map(|k| v[k] - hermite(v[0], m0, v[m], m1, k as f32 / m as f32)).collect()
}

fn lerp_track(track: &[Vec3], x: f32) -> Vec3 {
    if track.is_empty() {
        return Vec3::ZERO;
    }
    let x = x.clamp(0.0, (track.len() - 1) as f32);
    let k = x.floor() as usize;
    let k1 = (k + 1).min(track.len() - 1);
    track[k].lerp(track[k1], x - k as f32)
}

/// Composes `overlay`'s `part` onto `base`. Both on the canonical skeleton at the same frame
/// rate (the overlay is resampled otherwise). The output has the base's length; the overlay's
/// part shows from the start switch to the end switch.
pub fn compose(base: &Clip, overlay: &Clip, part: BodyPart, opts: &ComposeOptions) -> Result<(Clip, CompositionReport), ActionError> {
    for c in [base, overlay] {
        c.validate().map_err(|e| ActionError::BadClip { name: c.name.clone(), reason: e.to_string() })?;
        if c.joint_count() != CANON_COUNT {
            return Err(ActionError::NotHumanoid { name: c.name.clone(), reason: format!("{} joints, not the 21 canonical ones", c.joint_count()) });
        }
        if c.frame_count() < 8 {
            return Err(ActionError::TooShort { name: c.name.clone(), frames: c.frame_count(), needed: 8 });
        }
    }
    let resampled;
    let overlay = if (overlay.fps - base.fps).abs() > 1e-3 {
        resampled = overlay.resampled(base.fps);
        &resampled
    } else {
        overlay
    };
    let fps = base.fps;
    let (na, nb) = (base.frame_count(), overlay.frame_count());
    let (pa, va) = effector_track(base, part);
    let (pb, vb) = effector_track(overlay, part);
    let f_of = |i: usize, j: usize| opts.alpha * (pa[i] - pb[j]).length() + opts.beta * (va[i] - vb[j]).length();
    let search = ((opts.search_secs.max(0.05) * fps) as usize).max(1);
    let from = opts.base_from_frame.min(na - 2);
    let times = match opts.fixed {
        Some(t) => SwitchTimes {
            base_start_frame: t.base_start_frame.min(na - 2),
            overlay_start_frame: t.overlay_start_frame.min(nb - 2),
            base_end_frame: t.base_end_frame.clamp(t.base_start_frame.min(na - 2) + 1, na - 1),
            overlay_end_frame: t.overlay_end_frame.clamp(t.overlay_start_frame.min(nb - 2) + 1, nb - 1),
        },
        None => {
            // Start: first `search` frames of both (motion 2: at most its first 40%).
            let jb_hi = search.min(nb * 2 / 5).max(1);
            let ia_hi = (from + search).min(na - 2);
            let mut best = (f32::MAX, from, 0);
            for i in from..=ia_hi {
                for j in 0..=jb_hi {
                    let f = f_of(i, j);
                    if f < best.0 {
                        best = (f, i, j);
                    }
                }
            }
            let (ta, tb) = (best.1, best.2);
            // End: motion 2's last part, motion 1 near the same absolute time.
            let jb_lo = (nb - 1).saturating_sub(search.min(nb * 2 / 5)).max(tb + 1);
            let mut best_end = (f32::MAX, na - 1, nb - 1);
            for j in jb_lo..nb {
                let nominal = ta + (j - tb);
                let lo = nominal.saturating_sub(search).max(ta + 1);
                let hi = (nominal + search).min(na - 1);
                for i in lo..=hi {
                    let stretch = (j - tb) as f32 / (i - ta) as f32;
                    let f = f_of(i, j) + opts.gamma * fmath::ln(stretch).abs();
                    if f < best_end.0 {
                        best_end = (f, i, j);
                    }
                }
            }
            SwitchTimes { base_start_frame: ta, overlay_start_frame: tb, base_end_frame: best_end.1, overlay_end_frame: best_end.2 }
        }
    };
    let SwitchTimes { base_start_frame: ta, overlay_start_frame: tb, base_end_frame: ta2, overlay_end_frame: tb2 } = times;
    let stretch = (tb2 - tb) as f32 / (ta2 - ta).max(1) as f32;
    let blend = |i: usize, j: usize| -> f32 {
        let speed = va[i].length();
        let d = if speed > 1e-4 { (pa[i] - pb[j]).length() / speed } else { f32::INFINITY };
        // Options may come from the UI: a non-finite bound falls back to the default.
        let fin = |v: f32, dflt: f32| if v.is_finite() && v > 0.0 { v } else { dflt };
        let lo = fin(opts.min_blend_secs, 0.1);
        let hi = fin(opts.max_blend_secs, 0.8).max(lo);
        if d.is_finite() { d.clamp(lo, hi) } else { hi }
    };
    let (d_in, d_out) = (blend(ta, tb), blend(ta2, tb2));
    let (fin, fout) = ((d_in * fps).max(1.0), (d_out * fps).max(1.0));

    // Sway residuals of the joints outside the part (legs excepted).
    let legs = [BodyPart::LeftLeg, BodyPart::RightLeg];
    let sway_joints: Vec<Canon> = if opts.sway {
        Canon::ALL.into_iter().filter(|c| !part.contains(*c) && !legs.iter().any(|l| l.contains(*c)) && !matches!(c, Canon::LeftToe | Canon::RightToe)).collect()
    } else {
        Vec::new()
    };
    let residuals: Vec<(usize, Vec<Vec3>)> = sway_joints.iter().map(|c| (c.index(), sway_residual(overlay, c.index(), tb, tb2))).collect();

    let mut out = base.clone();
    out.name = format!("{} + {}", base.name, overlay.name);
    out.source = "composed".into();
    let part_joints: Vec<usize> = part.joints().iter().map(|c| c.index()).collect();
    let n = CANON_COUNT;
    let end = ((ta2 as f32 + fout).ceil() as usize).min(na);
    for f in ta..end {
        let x = tb as f32 + (f - ta) as f32 * stretch;
        let w = if f <= ta2 {
            ((f - ta) as f32 / fin).min(1.0)
        } else {
            (1.0 - (f - ta2) as f32 / fout).max(0.0)
        };
        let xf = x.clamp(0.0, (nb - 1) as f32);
        let (k0, k1) = (xf.floor() as usize, (xf.floor() as usize + 1).min(nb - 1));
        let a = xf - k0 as f32;
        for &j in &part_joints {
            let q2 = overlay.rotations[k0 * n + j].slerp(overlay.rotations[k1 * n + j], a);
            let q1 = base.rotations[f * n + j];
            out.rotations[f * n + j] = q1.slerp(q2, w).normalize();
        }
        if f <= ta2 {
            for (j, r) in &residuals {
                let s = lerp_track(r, x - tb as f32);
                out.rotations[f * n + j] = (out.rotations[f * n + j] * Quat::from_scaled_axis(s)).normalize();
            }
        }
    }
    // The visible jump: the largest frame-to-frame effector step around the switches.
    let (po, _) = effector_track(&out, part);
    let mut peak = 0.0f32;
    for (lo, hi) in [(ta, ta + fin.ceil() as usize + 1), (ta2, ta2 + fout.ceil() as usize + 1)] {
        for f in lo.max(1)..hi.min(na) {
            peak = peak.max((po[f] - po[f - 1]).length());
        }
    }
    let report = CompositionReport {
        part,
        times,
        f_start: f_of(ta, tb),
        f_end: f_of(ta2, tb2) + opts.gamma * fmath::ln(stretch).abs(),
        start_blend_secs: d_in,
        end_blend_secs: d_out,
        start_gap_cm: (pa[ta] - pb[tb]).length() * 100.0,
        end_gap_cm: (pa[ta2] - pb[tb2]).length() * 100.0,
        peak_effector_step_cm: peak * 100.0,
        stretch,
        sway_joints,
    };
    Ok((out, report))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::actions::ActionLibrary;

    #[test]
    fn hermite_residual_vanishes_at_both_ends_and_for_smooth_motion() {
        let lib = ActionLibrary::builtin();
        let wave = &lib.entries[lib.find("wave", &["right"]).unwrap()].clip;
        let r = sway_residual(wave, Canon::Chest.index(), 10, wave.frame_count() - 10);
        assert!(r[0].length() < 1e-5 && r[r.len() - 1].length() < 1e-5);
        assert!(r.iter().map(|v| v.length()).fold(0.0, f32::max) > 1e-3, "the wave's chest sways");
    }

    #[test]
    fn composition_switches_the_part_and_leaves_legs_alone() {
        let lib = ActionLibrary::builtin();
        let walk = lib.entries[lib.find("walk", &[]).unwrap()].clip_for(5.0);
        let wave = &lib.entries[lib.find("wave", &["right"]).unwrap()].clip;
        let (out, rep) = compose(&walk, wave, BodyPart::RightArm, &ComposeOptions::default()).unwrap();
        assert_eq!(out.frame_count(), walk.frame_count());
        let t = rep.times;
        assert!(t.base_start_frame < t.base_end_frame && t.overlay_start_frame < t.overlay_end_frame);
        let mid = (t.base_start_frame + t.base_end_frame) / 2;
        let p = out.world_positions(mid);
        assert!(p[Canon::RightHand.index()].y > p[Canon::Neck.index()].y, "hand up while walking");
        let n = CANON_COUNT;
        for f in 0..out.frame_count() {
            for c in [Canon::LeftUpperLeg, Canon::RightLowerLeg, Canon::LeftFoot] {
                assert_eq!(out.rotations[f * n + c.index()], walk.rotations[f * n + c.index()]);
            }
        }
        assert!(rep.stretch > 0.5 && rep.stretch < 2.0, "stretch {}", rep.stretch);
    }

    #[test]
    fn odd_options_do_not_panic() {
        let lib = ActionLibrary::builtin();
        let walk = lib.entries[lib.find("walk", &[]).unwrap()].clip_for(5.0);
        let wave = &lib.entries[lib.find("wave", &["right"]).unwrap()].clip;
        let opts = ComposeOptions { min_blend_secs: f32::NAN, max_blend_secs: -1.0, search_secs: f32::NAN, base_from_frame: 1_000_000, ..ComposeOptions::default() };
        let (out, rep) = compose(&walk, wave, BodyPart::RightArm, &opts).unwrap();
        out.validate().unwrap();
        assert!(rep.start_blend_secs.is_finite());
        let fixed = SwitchTimes { base_start_frame: 99_999, overlay_start_frame: 99_999, base_end_frame: 0, overlay_end_frame: 0 };
        assert!(compose(&walk, wave, BodyPart::RightArm, &ComposeOptions { fixed: Some(fixed), ..ComposeOptions::default() }).is_ok());
        assert!(matches!(compose(&walk.slice(0, 3, "short"), wave, BodyPart::RightArm, &opts), Err(ActionError::TooShort { .. })));
    }
}
