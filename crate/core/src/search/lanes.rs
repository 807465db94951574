//! The frame distance of spec §C, `d = Σ_k w_k ‖p_k − q_k‖`, laid out for SIMD: the 21
//! canonical joints in [`DISTANCE_ORDER`] are packed four to a group (six groups, the last
//! padded with three zero-weight lanes), and a frame is stored group by group as
//! `[x0 x1 x2 x3, y0 y1 y2 y3, z0 z1 z2 z3]`. Four joints' distances are then one vector
//! subtract/multiply/add/square-root: SSE on x86-64, `f32x4` with wasm `simd128` (the web
//! build enables it, see `wasm-pack.toml`). A search visits only the groups holding a weighted joint, and
//! the sum is always formed in the same order (each group's four lanes as `(l0 + l2) + (l1 +
//! l3)`, groups in order), so every code path that computes a distance gets the same bits.

use super::features::FRAME_FLOATS;
use super::DISTANCE_ORDER;
use crate::canon::humanoid::CANON_COUNT;

/// Joints per group (SIMD width).
pub const LANES: usize = 4;
/// Groups per frame.
pub const GROUPS: usize = CANON_COUNT.div_ceil(LANES);
/// Floats per group: x, y, z of four joints.
pub const GROUP_FLOATS: usize = 3 * LANES;
/// Floats per frame in the lane layout.
pub const LANE_FLOATS: usize = GROUPS * GROUP_FLOATS;

/// Frames of `FRAME_FLOATS` (joint-major xyz, canonical order) → lane layout.
pub fn to_lanes(data: &[f32]) -> Vec<f32> {
    let frames = data.len() / FRAME_FLOATS;
    let mut out = vec![0f32; frames * LANE_FLOATS];
    for (src, dst) in data.chunks_exact(FRAME_FLOATS).zip(out.chunks_exact_mut(LANE_FLOATS)) {
        for (n, joint) in DISTANCE_ORDER.iter().enumerate() {
            let (g, l) = (n / LANES, n % LANES);
            let k = joint.index() * 3;
            for a in 0..3 {
                dst[g * GROUP_FLOATS + a * LANES + l] = src[k + a];
            }
        }
    }
    out
}

/// The groups a set of joint weights (canonical order) needs, with each lane's weight.
pub fn weighted_groups(weights: &[f32; CANON_COUNT]) -> Vec<(usize, [f32; LANES])> {
    let mut out = Vec::new();
    for g in 0..GROUPS {
        let mut w = [0f32; LANES];
        for (l, wl) in w.iter_mut().enumerate() {
            if let Some(joint) = DISTANCE_ORDER.get(g * LANES + l) {
                *wl = weights[joint.index()];
            }
        }
        if w.iter().any(|&x| x > 0.0) {
            out.push((g, w));
        }
    }
    out
}

/// Four f32 lanes: SSE on x86-64, `simd128` on wasm32 when enabled, an array elsewhere. Every
/// operation is the IEEE operation lane by lane (the square root correctly rounded), so all
/// three give the same bits.
#[derive(Clone, Copy)]
struct V4(
    #[cfg(target_arch = "x86_64")] std::arch::x86_64::__m128,
    #[cfg(all(target_arch = "wasm32", target_feature = "simd128"))] core::arch::wasm32::v128,
    #[cfg(not(any(target_arch = "x86_64", all(target_arch = "wasm32", target_feature = "simd128"))))] [f32; LANES],
);

#[cfg(target_arch = "x86_64")]
impl V4 {
    #[inline(always)]
    fn load(s: &[f32]) -> V4 {
        let s = &s[..LANES];
        // SAFETY: SSE is part of the x86-64 baseline; `s` holds four floats (unaligned load).
        V4(unsafe { std::arch::x86_64::_mm_loadu_ps(s.as_ptr()) })
    }
    #[inline(always)]
    fn zero() -> V4 {
        // SAFETY: SSE baseline.
        V4(unsafe { std::arch::x86_64::_mm_setzero_ps() })
    }
    #[inline(always)]
    fn add(self, o: V4) -> V4 {
        // SAFETY: SSE baseline.
        V4(unsafe { std::arch::x86_64::_mm_add_ps(self.0, o.0) })
    }
    #[inline(always)]
    fn sub(self, o: V4) -> V4 {
        // SAFETY: SSE baseline.
        V4(unsafe { std::arch::x86_64::_mm_sub_ps(self.0, o.0) })
    }
    #[inline(always)]
    fn mul(self, o: V4) -> V4 {
        // SAFETY: SSE baseline.
        V4(unsafe { std::arch::x86_64::_mm_mul_ps(self.0, o.0) })
    }
    #[inline(always)]
    fn max(self, o: V4) -> V4 {
        // SAFETY: SSE baseline.
        V4(unsafe { std::arch::x86_64::_mm_max_ps(self.0, o.0) })
    }
    #[inline(always)]
    fn sqrt(self) -> V4 {
        // SAFETY: SSE baseline.
        V4(unsafe { std::arch::x86_64::_mm_sqrt_ps(self.0) })
    }
    /// `(l0 + l2) + (l1 + l3)`.
    #[inline(always)]
    fn sum(self) -> f32 {
        use std::arch::x86_64::*;
        // SAFETY: SSE baseline.
        unsafe {
            let h = _mm_add_ps(self.0, _mm_movehl_ps(self.0, self.0));
            _mm_cvtss_f32(_mm_add_ss(h, _mm_shuffle_ps(h, h, 1)))
        }
    }
}

#[cfg(all(target_arch = "wasm32", target_feature = "simd128"))]
impl V4 {
    #[inline(always)]
    fn load(s: &[f32]) -> V4 {
        let s = &s[..LANES];
        // SAFETY: `s` holds four floats; v128_load reads 16 unaligned bytes.
        V4(unsafe { core::arch::wasm32::v128_load(s.as_ptr() as *const core::arch::wasm32::v128) })
    }
    #[inline(always)]
    fn zero() -> V4 {
        V4(core::arch::wasm32::f32x4_splat(0.0))
    }
    #[inline(always)]
    fn add(self, o: V4) -> V4 {
        V4(core::arch::wasm32::f32x4_add(self.0, o.0))
    }
    #[inline(always)]
    fn sub(self, o: V4) -> V4 {
        V4(core::arch::wasm32::f32x4_sub(self.0, o.0))
    }
    #[inline(always)]
    fn mul(self, o: V4) -> V4 {
        V4(core::arch::wasm32::f32x4_mul(self.0, o.0))
    }
    #[inline(always)]
    fn max(self, o: V4) -> V4 {
        V4(core::arch::wasm32::f32x4_pmax(self.0, o.0))
    }
    #[inline(always)]
    fn sqrt(self) -> V4 {
        V4(core::arch::wasm32::f32x4_sqrt(self.0))
    }
    /// `(l0 + l2) + (l1 + l3)`.
    #[inline(always)]
    fn sum(self) -> f32 {
        use core::arch::wasm32::*;
        let h = f32x4_add(self.0, i32x4_shuffle::<2, 3, 2, 3>(self.0, self.0));
        f32x4_extract_lane::<0>(h) + f32x4_extract_lane::<1>(h)
    }
}

#[cfg(not(any(target_arch = "x86_64", all(target_arch = "wasm32", target_feature = "simd128"))))]
impl V4 {
    #[inline(always)]
    fn load(s: &[f32]) -> V4 {
        V4([s[0], s[1], s[2], s[3]])
    }
    #[inline(always)]
    fn zero() -> V4 {
        V4([0.0; LANES])
    }
    #[inline(always)]
    fn map2(self, o: V4, f: impl Fn(f32, f32) -> f32) -> V4 {
        V4([f(self.0[0], o.0[0]), f(self.0[1], o.0[1]), f(self.0[2], o.0[2]), f(self.0[3], o.0[3])])
    }
    #[inline(always)]
    fn add(self, o: V4) -> V4 {
        self.map2(o, |a, b| a + b)
    }
    #[inline(always)]
    fn sub(self, o: V4) -> V4 {
        self.map2(o, |a, b| a - b)
    }
    #[inline(always)]
    fn mul(self, o: V4) -> V4 {
        self.map2(o, |a, b| a * b)
    }
    #[inline(always)]
    fn max(self, o: V4) -> V4 {
        self.map2(o, |a, b| if a > b { a } else { b })
    }
    #[inline(always)]
    fn sqrt(self) -> V4 {
        V4(self.0.map(f32::sqrt))
    }
    #[inline(always)]
    fn sum(self) -> f32 {
        (self.0[0] + self.0[2]) + (self.0[1] + self.0[3])
    }
}

/// One group's weighted joint distances `r_l = w_l ‖a_l − b_l‖`, summed as
/// `(r0 + r2) + (r1 + r3)`.
#[inline(always)]
fn group(a: &[f32], b: &[f32], w: &[f32; LANES]) -> f32 {
    let dx = V4::load(a).sub(V4::load(b));
    let dy = V4::load(&a[LANES..]).sub(V4::load(&b[LANES..]));
    let dz = V4::load(&a[2 * LANES..]).sub(V4::load(&b[2 * LANES..]));
    let q = dx.mul(dx).add(dy.mul(dy)).add(dz.mul(dz));
    V4::load(w).mul(q.sqrt()).sum()
}

/// [`group`] without SIMD.
#[cfg_attr(any(target_arch = "x86_64", all(target_arch = "wasm32", target_feature = "simd128")), allow(dead_code))]
#[inline(always)]
fn group_plain(a: &[f32], b: &[f32], w: &[f32; LANES]) -> f32 {
    let mut r = [0f32; LANES];
    for l in 0..LANES {
        let dx = a[l] - b[l];
        let dy = a[LANES + l] - b[LANES + l];
        let dz = a[2 * LANES + l] - b[2 * LANES + l];
        r[l] = w[l] * (dx * dx + dy * dy + dz * dz).sqrt();
    }
    (r[0] + r[2]) + (r[1] + r[3])
}

/// `Σ_k w_k ‖a_k − b_k‖` between two lane-layout frames over the weighted groups.
#[inline]
pub fn distance(a: &[f32], b: &[f32], groups: &[(usize, [f32; LANES])]) -> f32 {
    let mut s = 0.0f32;
    for (g, w) in groups {
        let o = g * GROUP_FLOATS;
        s += group(&a[o..], &b[o..], w);
    }
    s
}

/// [`distance`], abandoned as soon as the partial sum exceeds `limit` (then some value
/// `> limit` is returned). When not abandoned the result is bit-for-bit [`distance`].
#[inline]
pub fn distance_abandon(a: &[f32], b: &[f32], groups: &[(usize, [f32; LANES])], limit: f32) -> f32 {
    let mut s = 0.0f32;
    for (g, w) in groups {
        let o = g * GROUP_FLOATS;
        s += group(&a[o..], &b[o..], w);
        if s > limit {
            return s;
        }
    }
    s
}

/// Floats per group of a bounding box: min x, y, z then max x, y, z, four lanes each.
pub const BOX_GROUP_FLOATS: usize = 2 * GROUP_FLOATS;
/// Floats per bounding box of lane-layout frames.
pub const BOX_FLOATS: usize = GROUPS * BOX_GROUP_FLOATS;

/// Bounding boxes of lane-layout frames, one per run of `chunk` frames (the last may be
/// shorter), `BOX_FLOATS` each.
pub fn chunk_boxes(lanes: &[f32], chunk: usize) -> Vec<f32> {
    let mut out = Vec::with_capacity((lanes.len() / LANE_FLOATS).div_ceil(chunk) * BOX_FLOATS);
    for ch in lanes.chunks(chunk * LANE_FLOATS) {
        push_box(ch, &mut out);
    }
    out
}

/// Appends the bounding box of some lane-layout frames.
pub fn push_box(frames: &[f32], out: &mut Vec<f32>) {
    let base = out.len();
    out.resize(base + BOX_FLOATS, 0.0);
    let b = &mut out[base..];
    for g in b.chunks_exact_mut(BOX_GROUP_FLOATS) {
        g[..GROUP_FLOATS].fill(f32::INFINITY);
        g[GROUP_FLOATS..].fill(f32::NEG_INFINITY);
    }
    for f in frames.chunks_exact(LANE_FLOATS) {
        for (bg, fg) in b.chunks_exact_mut(BOX_GROUP_FLOATS).zip(f.chunks_exact(GROUP_FLOATS)) {
            for (k, &x) in fg.iter().enumerate() {
                bg[k] = bg[k].min(x);
                bg[GROUP_FLOATS + k] = bg[GROUP_FLOATS + k].max(x);
            }
        }
    }
}

/// `Σ_k w_k dist(frame_k, box_k)` over the weighted groups: a lower bound of the frame
/// distance from `frame` to any frame whose joints all lie in their boxes.
/// (The search now bounds with [`box_box`]; this stays for the tests that check boxes hold
/// their frames.)
#[cfg_attr(not(test), allow(dead_code))]
#[inline]
pub fn point_box(frame: &[f32], bx: &[f32], groups: &[(usize, [f32; LANES])]) -> f32 {
    let mut s = 0.0f32;
    for (g, w) in groups {
        let (f, b) = (&frame[g * GROUP_FLOATS..], &bx[g * BOX_GROUP_FLOATS..]);
        let mut e = V4::zero();
        for a in 0..3 {
            let x = V4::load(&f[a * LANES..]);
            let o = V4::load(&b[a * LANES..]).sub(x).max(x.sub(V4::load(&b[GROUP_FLOATS + a * LANES..]))).max(V4::zero());
            e = e.add(o.mul(o));
        }
        s += V4::load(w).mul(e.sqrt()).sum();
    }
    s
}

/// `Σ_k w_k dist(box a_k, box b_k)`: a lower bound of the frame distance between any frame
/// inside boxes `a` and any frame inside boxes `b`.
#[inline]
pub fn box_box(a: &[f32], b: &[f32], groups: &[(usize, [f32; LANES])]) -> f32 {
    let mut s = 0.0f32;
    for (g, w) in groups {
        let (x, y) = (&a[g * BOX_GROUP_FLOATS..], &b[g * BOX_GROUP_FLOATS..]);
        let mut e = V4::zero();
        for k in 0..3 {
            let (xmin, xmax) = (V4::load(&x[k * LANES..]), V4::load(&x[GROUP_FLOATS + k * LANES..]));
            let (ymin, ymax) = (V4::load(&y[k * LANES..]), V4::load(&y[GROUP_FLOATS + k * LANES..]));
            let o = xmin.sub(ymax).max(ymin.sub(xmax)).max(V4::zero());
            e = e.add(o.mul(o));
        }
        s += V4::load(w).mul(e.sqrt()).sum();
    }
    s
}

/// Which [`V4`] this build runs: "sse", "simd128" or "scalar".
pub const VECTOR_PATH: &str = if cfg!(target_arch = "x86_64") {
    "sse"
} else if cfg!(all(target_arch = "wasm32", target_feature = "simd128")) {
    "simd128"
} else {
    "scalar"
};

/// Runs `cases` random lane groups (coordinates in ±1.5, one weight 0) through the vector
/// kernel and the scalar one in the build that runs it, and counts results that differ in any
/// bit. The fast search's exactness rests on 0; the wasm build checks it under Node.
pub fn kernel_mismatches(cases: u32) -> u32 {
    let mut x = 0x2545_f491_4f6c_dd1du64;
    let mut next = || {
        x ^= x << 13;
        x ^= x >> 7;
        x ^= x << 17;
        ((x >> 40) as f32 / (1u64 << 24) as f32 - 0.5) * 3.0
    };
    let mut bad = 0;
    for _ in 0..cases {
        let a: Vec<f32> = (0..GROUP_FLOATS).map(|_| next()).collect();
        let b: Vec<f32> = (0..GROUP_FLOATS).map(|_| next()).collect();
        let w = [next().abs(), next().abs(), 0.0, next().abs()];
        if group(&a, &b, &w).to_bits() != group_plain(&a, &b, &w).to_bits() {
            bad += 1;
        }
    }
    bad
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn simd_and_plain_give_the_same_bits() {
        let mut x = 0x2545_f491_4f6c_dd1du64;
        let mut next = || {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            ((x >> 40) as f32 / (1u64 << 24) as f32 - 0.5) * 3.0
        };
        for _ in 0..20_000 {
            let a: Vec<f32> = (0..GROUP_FLOATS).map(|_| next()).collect();
            let b: Vec<f32> = (0..GROUP_FLOATS).map(|_| next()).collect();
            let w = [next().abs(), next().abs(), 0.0, next().abs()];
            assert_eq!(group(&a, &b, &w).to_bits(), group_plain(&a, &b, &w).to_bits());
        }
    }

    #[test]
    fn lane_layout_distance_is_the_joint_distance() {
        let data: Vec<f32> = (0..2 * FRAME_FLOATS).map(|i| ((i * 37) % 101) as f32 / 50.0).collect();
        let l = to_lanes(&data);
        let mut weights = [0f32; CANON_COUNT];
        weights.iter_mut().enumerate().for_each(|(k, w)| *w = (k % 3) as f32 * 0.5);
        let d = distance(&l[..LANE_FLOATS], &l[LANE_FLOATS..], &weighted_groups(&weights));
        let want: f32 = (0..CANON_COUNT)
            .map(|k| {
                let (a, b) = (&data[k * 3..k * 3 + 3], &data[FRAME_FLOATS + k * 3..FRAME_FLOATS + k * 3 + 3]);
                weights[k] * ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
            })
            .sum();
        assert!((d - want).abs() < 1e-4 * want, "{d} vs {want}");
        // Groups without a weighted joint are skipped.
        assert!(weighted_groups(&weights).len() <= GROUPS);
        let mut feet = [0f32; CANON_COUNT];
        feet[crate::canon::humanoid::Canon::LeftFoot.index()] = 1.0;
        assert_eq!(weighted_groups(&feet).len(), 1);
    }

    #[test]
    fn box_bounds_are_lower_bounds() {
        let mut x = 0x9e37_79b9_7f4a_7c15u64;
        let mut next = || {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            (x >> 40) as f32 / (1u64 << 24) as f32 - 0.5
        };
        let frames: Vec<f32> = (0..40 * FRAME_FLOATS).map(|_| next()).collect();
        let l = to_lanes(&frames);
        let boxes = chunk_boxes(&l, 8);
        assert_eq!(boxes.len(), 5 * BOX_FLOATS);
        let groups = weighted_groups(&[1.0; CANON_COUNT]);
        for (i, a) in l.chunks_exact(LANE_FLOATS).enumerate() {
            let own = &boxes[(i / 8) * BOX_FLOATS..];
            assert_eq!(point_box(a, own, &groups), 0.0, "a frame lies in its own chunk's box");
            for (j, b) in l.chunks_exact(LANE_FLOATS).enumerate() {
                let d = distance(a, b, &groups);
                let bb = &boxes[(j / 8) * BOX_FLOATS..];
                assert!(point_box(a, bb, &groups) <= d * (1.0 + 1e-5), "point-box bound above the distance");
                assert!(box_box(own, bb, &groups) <= d * (1.0 + 1e-5), "box-box bound above the distance");
            }
        }
        // Far apart boxes give a positive bound.
        let shifted: Vec<f32> = frames.iter().map(|v| v + 10.0).collect();
        let far = chunk_boxes(&to_lanes(&shifted), 40);
        assert!(box_box(&boxes[..BOX_FLOATS], &far, &groups) > 21.0 * 9.0);
    }
}
