//! The predicted blended join jump (issue 26 item 1, [`super::table`]'s [`JumpTerm`]): spec §J's
//! join jump after the inertialized join ([`super::render`]), predicted from two segments' ends
//! alone ([`blended_join_jump_at`]), and the same prediction laid out for the table's pair loop
//! ([`blend_sides`], [`blend_jumps`]) so that each pair costs one distance per sample and joint.

use super::segment::{JoinEnds, SegmentLibrary};
use crate::canon::humanoid::CANON_COUNT;

/// Frames (at [`super::LIBRARY_FPS`], the segments' own rate) an inertialized join's offset
/// decays over: [`super::render::INERTIAL_BLEND_SECS`].
pub(super) fn blend_span_frames() -> f32 {
    super::render::INERTIAL_BLEND_SECS * super::LIBRARY_FPS
}

/// Spec §J's join jump predicted for segment `a` followed by `b` under the inertialized join
/// ([`super::JoinBlend::Inertial`]), each played at its own tempo, from the two ends alone:
/// what the viewer sees after the blend, where the table's C (§G: link directions, end gaps)
/// measures the join before it. [`blended_join_jump_at`] at `None`.
pub fn blended_join_jump(lib: &SegmentLibrary, a: usize, b: usize) -> Option<f32> {
    blended_join_jump_at(lib, a, b, None)
}

/// [`blended_join_jump`] with both segments played at `count_rate_bpm` counts a minute
/// (`None`: each at its own tempo).
///
/// The render places `b` where `a` ends, facing the same way; the blend carries the outgoing
/// motion on into the switch and adds the offset — pose x₀ = (x_A + v_A + ½a_A) − x_B, velocity
/// v₀ = v_A − v_B, acceleration a₀ = a_A − a_B, per joint (from the hips' ground point, facing
/// removed, body heights, per frame) — to the incoming motion, decayed by the quintic of
/// [`super::render`] over [`super::render::INERTIAL_BLEND_SECS`]. The jump the viewer sees is
/// the largest joint acceleration near the join: the outgoing move's at its end, or the
/// incoming move's at its start plus the offset's (sampled at ten points of the decay). §J
/// divides it by the 95th percentile of the moves' own; here by the mean of the two segments'
/// own sharpness (the mean ranked joins better than the larger or the geometric mean: ρ 0.62
/// and 0.59 on the two halves of `tests/native/choreo_join_cost.rs` against 0.58/0.57 and
/// 0.61/0.57). Played at r times its tempo, a segment's velocities scale by r and its
/// accelerations by r². `None` when either index is out of range.
pub fn blended_join_jump_at(lib: &SegmentLibrary, a: usize, b: usize, count_rate_bpm: Option<f32>) -> Option<f32> {
    let (ea, eb) = (lib.ends.get(a)?, lib.ends.get(b)?);
    let rate = |s: usize| -> f32 {
        let tempo = lib.segments().get(s).map_or(0.0, |s| s.tempo_bpm);
        match count_rate_bpm {
            Some(r) if r > 0.0 && tempo > 0.0 => r / tempo,
            _ => 1.0,
        }
    };
    let (ra, rb) = (rate(a), rate(b));
    let span = blend_span_frames();
    let mut peak = 0.0f32;
    for (&[xa, va, aa], &[xb, vb, ab]) in ea.end_joint.iter().zip(&eb.start_joint) {
        let (va, aa, vb, ab) = (va * ra, aa * ra * ra, vb * rb, ab * rb * rb);
        let (x0, v0, a0) = (xa + va + 0.5 * aa - xb, va - vb, aa - ab);
        peak = peak.max(aa.length());
        for k in 0..BLEND_SAMPLES {
            let t = span * k as f32 / BLEND_SAMPLES as f32;
            peak = peak.max((ab + super::render::quintic_offset_accel(x0, v0, a0, span, t)).length());
        }
    }
    let own = 0.5 * (ea.sharpness * ra * ra + eb.sharpness * rb * rb);
    Some(peak / own.max(1e-6))
}

/// Points of the decay [`blended_join_jump_at`] samples the offset's acceleration at.
const BLEND_SAMPLES: usize = 10;

/// Weight of the predicted blended join jump in the table's C (issue 26 item 1): C(a, b) +=
/// this × max(0, J − [`BLENDED_JUMP_FREE`]), J the jump [`blended_join_jump`] predicts (each
/// move at its own tempo), sampled at the points [`TABLE_BLEND_SAMPLES`]. A predicted jump of 2
/// then costs 1, about the spread of C between a good and a poor join before it. Chosen on the
/// songs of `tests/native/choreo_blended_cost.rs` (`docs/benchmarks-notes-choreo.md` lists the
/// terms tried).
pub const BLENDED_JUMP_WEIGHT: f32 = 2.0;
/// The predicted jump the table's term lets pass free: C(a, b) += [`BLENDED_JUMP_WEIGHT`] ×
/// max(0, jump − this). 1.5, spec §J's goal: only a join predicted over the goal pays, so the
/// joins within it keep their C (and the balance of C against the beat term the dances were
/// tuned on). Charging every jump (0) smoothed the joins most but took the built-in moves in 3
/// off the beat (84 BPM: BAS-music 0.42–0.52 against random moves' 0.57); 1 still turned the
/// 84 BPM piece in 3 at 1.25 kinetic beats a count and gave the person's Let's Go Fishin' a
/// join of 1.70 (`docs/benchmarks-notes-choreo.md`).
pub const BLENDED_JUMP_FREE: f32 = 1.5;

/// The blended-jump term of a table's costs: `weight` × max(0, predicted jump − `free`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct JumpTerm {
    pub weight: f32,
    pub free: f32,
}

impl JumpTerm {
    /// The term off: the cost before session 14 (§G's C and the end gaps).
    pub const OFF: JumpTerm = JumpTerm { weight: 0.0, free: 0.0 };

    /// Its weight within 0..=100 and its free jump within 0..=100 (non-finite: 0).
    pub(super) fn clamped(self) -> JumpTerm {
        let c = |x: f32| if x.is_finite() { x.clamp(0.0, 100.0) } else { 0.0 };
        JumpTerm { weight: c(self.weight), free: c(self.free) }
    }
}

impl JumpTerm {
    /// [`BLENDED_JUMP_WEIGHT`] and [`BLENDED_JUMP_FREE`]: the term measured in
    /// `tests/native/choreo_blended_cost.rs`. Not the default yet: with the person's library it
    /// let the feet slide more than the sources' on the 150 BPM piece in 3 (66.8 against 63.0
    /// cm/s; 103.7 against 64.0 on half 0 of the files) and joined one piece at 1.63
    /// (`choreo_my_moves`), and the drum take at 1.51 (`choreo_beats`).
    pub const MEASURED: JumpTerm = JumpTerm { weight: BLENDED_JUMP_WEIGHT, free: BLENDED_JUMP_FREE };
}

impl Default for JumpTerm {
    /// [`JumpTerm::OFF`] for now (see [`JumpTerm::MEASURED`]): the dances are those before it.
    fn default() -> Self {
        JumpTerm::OFF
    }
}

/// The points of the decay (in tenths of [`super::render::INERTIAL_BLEND_SECS`]) at which the
/// table samples the offset's acceleration: the odd tenths. The tenth 0 is the outgoing move's
/// own acceleration (the offset carries it on), counted apart. Five samples ranked the measured
/// jumps as the ten of [`blended_join_jump`] do (ρ 0.61/0.59 against 0.62/0.59,
/// `docs/benchmarks.md`) at half the work.
pub const TABLE_BLEND_SAMPLES: [usize; 5] = [1, 3, 5, 7, 9];
/// Floats per segment of each side's blend data: xyz per sample and canonical joint.
pub(super) const BLEND_FLOATS: usize = 3 * TABLE_BLEND_SAMPLES.len() * CANON_COUNT;

/// The quintic decay's acceleration at tenth `k` of the span as coefficients of the offset's
/// pose, velocity and acceleration (it is linear in them): (k_x, k_v, k_a).
fn decay_coefficients(k: usize) -> (f32, f32, f32) {
    let span = blend_span_frames();
    let t = span * k as f32 / BLEND_SAMPLES as f32;
    let at = |x0: glam::Vec3, v0: glam::Vec3, a0: glam::Vec3| super::render::quintic_offset_accel(x0, v0, a0, span, t).x;
    let (z, one) = (glam::Vec3::ZERO, glam::Vec3::X);
    (at(one, z, z), at(z, one, z), at(z, z, one))
}

/// Each segment's blend data for the table (see [`Ends`]): the predecessor side P_k(a) =
/// k_x·(x_A + v_A + ½a_A) + k_v·v_A + k_a·a_A and the successor side Q_k(b) = k_x·x_B + k_v·v_B
/// + (k_a − 1)·a_B per sample k and joint, so that the incoming motion's acceleration plus the
/// offset's at sample k is P_k(a) − Q_k(b): the pair loop is then one distance per sample and
/// joint. Also the outgoing move's largest joint acceleration at its end, squared.
pub(super) fn blend_sides(e: &JoinEnds) -> ([f32; BLEND_FLOATS], [f32; BLEND_FLOATS], f32) {
    let (mut p, mut q) = ([0.0f32; BLEND_FLOATS], [0.0f32; BLEND_FLOATS]);
    let mut peak2 = 0.0f32;
    for (si, &k) in TABLE_BLEND_SAMPLES.iter().enumerate() {
        let (kx, kv, ka) = decay_coefficients(k);
        for j in 0..CANON_COUNT {
            let [xa, va, aa] = e.end_joint[j];
            let [xb, vb, ab] = e.start_joint[j];
            let pa = kx * (xa + va + 0.5 * aa) + kv * va + ka * aa;
            let qb = kx * xb + kv * vb + (ka - 1.0) * ab;
            let o = 3 * (si * CANON_COUNT + j);
            p[o..o + 3].copy_from_slice(&pa.to_array());
            q[o..o + 3].copy_from_slice(&qb.to_array());
            peak2 = peak2.max(aa.length_squared());
        }
    }
    (p, q, peak2)
}

/// Adds `term` (its weight × the predicted blended jump over its free part) to each cost of a block of predecessors
/// (`a(r)`: row r of their [`blend_sides`] P, `a_peak2`, `a_sharp` alongside; `b`: the
/// successor's Q and sharpness). `peak`: scratch as long as `costs`.
#[allow(clippy::too_many_arguments)]
pub(super) fn blend_jumps<'a>(costs: &mut [f32], peak: &mut [f32], b: &[f32], b_sharp: f32, a: impl Fn(usize) -> &'a [f32], a_peak2: &[f32], a_sharp: &[f32], term: JumpTerm) {
    let n = costs.len();
    let peak = &mut peak[..n];
    peak.copy_from_slice(&a_peak2[..n]);
    for r in 0..BLEND_FLOATS / 3 {
        let (px, py, pz) = (&a(3 * r)[..n], &a(3 * r + 1)[..n], &a(3 * r + 2)[..n]);
        let (qx, qy, qz) = (b[3 * r], b[3 * r + 1], b[3 * r + 2]);
        for i in 0..n {
            let (dx, dy, dz) = (px[i] - qx, py[i] - qy, pz[i] - qz);
            let d2 = dx * dx + dy * dy + dz * dz;
            peak[i] = if d2 > peak[i] { d2 } else { peak[i] };
        }
    }
    let a_sharp = &a_sharp[..n];
    for i in 0..n {
        let own = 0.5 * (a_sharp[i] + b_sharp);
        let over = peak[i].sqrt() / (if own > 1e-6 { own } else { 1e-6 }) - term.free;
        costs[i] += term.weight * if over > 0.0 { over } else { 0.0 };
    }
}
