//! Eigen signatures of motion segments (spec §F) and the kWAS-style similarity between them.
//!
//! A segment's signature is the principal axes of its (frames × features) matrix: the
//! eigenvectors and eigenvalues of the covariance of its per-frame feature vectors. Both are
//! computed here: a cyclic Jacobi eigen-decomposition of small symmetric matrices
//! ([`symmetric_eigen`]), and for the signature's top-k axes a block (subspace) power
//! iteration on k + 3 vectors finished by a Rayleigh–Ritz step that diagonalises the projected
//! (k + 3)² matrix with the same Jacobi ([`top_eigen`]) — about 20 times cheaper than a full
//! Jacobi of the 30 × 30 covariance, with the same top axes to float precision for any
//! segment whose k-th and (k + 4)-th eigenvalues differ; for a segment with fewer sampled
//! frames than features the products go through its rows ([`top_eigen_of_rows`]). Deterministic. The moments are about
//! the segment's mean ([`Signature::of`]) or, as Li & Prabhakaran take the raw matrix's SVD,
//! about zero ([`Signature::of_uncentred`], what the segment library uses). Similarity follows Li & Prabhakaran's k-weighted angular
//! similarity (kWAS): Sim(a, b) = ½ Σ_{i<k} (λ̂ᵃᵢ + λ̂ᵇᵢ) · |uᵃᵢ · uᵇᵢ| with λ̂ the top-k
//! eigenvalues scaled to sum to 1 (so Sim(a, a) = 1 and Sim ∈ [0, 1]); D = 1 − Sim.

use serde::{Deserialize, Serialize};

/// Eigen-decomposition of a symmetric `n × n` matrix (row-major) by cyclic Jacobi rotations.
/// Returns eigenvalues in descending order and the matching unit eigenvectors (each of length
/// `n`, concatenated). Non-finite input gives zeros.
pub fn symmetric_eigen(matrix: &[f64], n: usize) -> (Vec<f64>, Vec<f64>) {
    let mut a = matrix.to_vec();
    if a.len() != n * n || a.iter().any(|v| !v.is_finite()) {
        return (vec![0.0; n], identity(n));
    }
    let mut v = identity(n);
    let scale: f64 = a.iter().map(|x| x * x).sum::<f64>().sqrt().max(1e-300);
    for _sweep in 0..60 {
        let mut off = 0.0;
        for p in 0..n {
            for q in p + 1..n {
                off += a[p * n + q] * a[p * n + q];
            }
        }
        if off.sqrt() <= 1e-13 * scale {
            break;
        }
        for p in 0..n {
            for q in p + 1..n {
                let apq = a[p * n + q];
                if apq.abs() <= 1e-300 {
                    continue;
                }
                let app = a[p * n + p];
                let aqq = a[q * n + q];
                let theta = (aqq - app) / (2.0 * apq);
                let t = theta.signum() / (theta.abs() + (theta * theta + 1.0).sqrt());
                let t = if theta == 0.0 { 1.0 } else { t };
                let c = 1.0 / (t * t + 1.0).sqrt();
                let s = t * c;
                // Rotate rows/columns p and q.
                for k in 0..n {
                    let akp = a[k * n + p];
                    let akq = a[k * n + q];
                    a[k * n + p] = c * akp - s * akq;
                    a[k * n + q] = s * akp + c * akq;
                }
                for k in 0..n {
                    let apk = a[p * n + k];
                    let aqk = a[q * n + k];
                    a[p * n + k] = c * apk - s * aqk;
                    a[q * n + k] = s * apk + c * aqk;
                }
                for k in 0..n {
                    let vkp = v[k * n + p];
                    let vkq = v[k * n + q];
                    v[k * n + p] = c * vkp - s * vkq;
                    v[k * n + q] = s * vkp + c * vkq;
                }
            }
        }
    }
    let mut order: Vec<usize> = (0..n).collect();
    order.sort_by(|&i, &j| a[j * n + j].total_cmp(&a[i * n + i]).then(i.cmp(&j)));
    let values = order.iter().map(|&i| a[i * n + i]).collect();
    let mut vectors = Vec::with_capacity(n * n);
    for &i in &order {
        for k in 0..n {
            vectors.push(v[k * n + i]);
        }
    }
    (values, vectors)
}

/// The `k` largest eigenvalues (descending) and their unit eigenvectors (concatenated, each
/// `n` long) of a symmetric positive semi-definite `n × n` matrix, by subspace iteration on
/// `k + 3` vectors (started on the axes of the largest diagonal entries) and a Rayleigh–Ritz
/// step.
pub fn top_eigen(matrix: &[f64], n: usize, k: usize) -> (Vec<f64>, Vec<f64>) {
    let p = (k + 3).min(n);
    if p == 0 || matrix.len() != n * n || matrix.iter().any(|v| !v.is_finite()) {
        return (vec![0.0; k.min(n)], vec![0.0; k.min(n) * n]);
    }
    if p == n {
        let (vals, vecs) = symmetric_eigen(matrix, n);
        return (vals[..k.min(n)].to_vec(), vecs[..k.min(n) * n].to_vec());
    }
    let diagonal: Vec<f64> = (0..n).map(|i| matrix[i * n + i]).collect();
    // W = A V, column by column as a sum of A's columns (A is symmetric, so its rows): the
    // inner loop is an axpy over contiguous memory, which vectorises (a dot product's
    // reduction would not).
    let mul = |v: &[f64], w: &mut [f64]| {
        for (vj, wj) in v.chunks_exact(n).zip(w.chunks_exact_mut(n)) {
            wj.fill(0.0);
            for (&c, row) in vj.iter().zip(matrix.chunks_exact(n)) {
                if c != 0.0 {
                    for (o, &a) in wj.iter_mut().zip(row) {
                        *o += c * a;
                    }
                }
            }
        }
    };
    subspace_iteration(n, k, &diagonal, mul)
}

/// [`top_eigen`] of the second moments A = XᵀX / r of the `r × n` matrix `rows` (row-major)
/// without forming A: each product A·v is Xᵀ(X·v) / r, 2·r·n operations instead of n², so a
/// segment with fewer sampled frames than features (a 3-count bar: about 30 × 127) costs about
/// half (the same iteration, so the same axes to float precision).
pub fn top_eigen_of_rows(rows: &[f64], r: usize, n: usize, k: usize) -> (Vec<f64>, Vec<f64>) {
    let p = (k + 3).min(n);
    if p == 0 || rows.len() != r * n || rows.iter().any(|v| !v.is_finite()) {
        return (vec![0.0; k.min(n)], vec![0.0; k.min(n) * n]);
    }
    let scale = 1.0 / r.max(1) as f64;
    let mut diagonal = vec![0.0f64; n];
    for row in rows.chunks_exact(n) {
        for (d, &x) in diagonal.iter_mut().zip(row) {
            *d += x * x;
        }
    }
    diagonal.iter_mut().for_each(|d| *d *= scale);
    if p == n {
        let mut a = vec![0.0f64; n * n];
        for row in rows.chunks_exact(n) {
            for i in 0..n {
                for j in 0..n {
                    a[i * n + j] += row[i] * row[j] * scale;
                }
            }
        }
        let (vals, vecs) = symmetric_eigen(&a, n);
        return (vals[..k.min(n)].to_vec(), vecs[..k.min(n) * n].to_vec());
    }
    let mut t = vec![0.0f64; r];
    let mul = |v: &[f64], w: &mut [f64]| {
        for (vj, wj) in v.chunks_exact(n).zip(w.chunks_exact_mut(n)) {
            for (ti, row) in t.iter_mut().zip(rows.chunks_exact(n)) {
                *ti = dot(row, vj) * scale;
            }
            wj.fill(0.0);
            for (&c, row) in t.iter().zip(rows.chunks_exact(n)) {
                for (o, &a) in wj.iter_mut().zip(row) {
                    *o += c * a;
                }
            }
        }
    };
    subspace_iteration(n, k, &diagonal, mul)
}

/// The subspace iteration of [`top_eigen`] on a symmetric PSD operator given by its diagonal
/// and its product with `p` stacked vectors.
fn subspace_iteration(n: usize, k: usize, diagonal: &[f64], mut mul: impl FnMut(&[f64], &mut [f64])) -> (Vec<f64>, Vec<f64>) {
    let p = (k + 3).min(n);
    // Start on the axes with the most variance.
    let mut axes: Vec<usize> = (0..n).collect();
    axes.sort_by(|&a, &b| diagonal[b].total_cmp(&diagonal[a]).then(a.cmp(&b)));
    let mut v = vec![0.0f64; p * n];
    for (j, &ax) in axes.iter().take(p).enumerate() {
        v[j * n + ax] = 1.0;
    }
    let mut w = vec![0.0f64; p * n];
    for _ in 0..10 {
        mul(&v, &mut w);
        orthonormalize(&mut w, n, p, &axes);
        std::mem::swap(&mut v, &mut w);
    }
    // Rayleigh–Ritz: H = Vᵀ A V, diagonalised by Jacobi.
    mul(&v, &mut w);
    let mut h = vec![0.0f64; p * p];
    for a in 0..p {
        for b in 0..p {
            h[a * p + b] = dot(&v[a * n..(a + 1) * n], &w[b * n..(b + 1) * n]);
        }
    }
    for a in 0..p {
        for b in a + 1..p {
            let m = 0.5 * (h[a * p + b] + h[b * p + a]);
            h[a * p + b] = m;
            h[b * p + a] = m;
        }
    }
    let (vals, y) = symmetric_eigen(&h, p);
    let mut vectors = vec![0.0f64; k * n];
    for e in 0..k {
        for i in 0..n {
            vectors[e * n + i] = (0..p).map(|j| v[j * n + i] * y[e * p + j]).sum();
        }
    }
    (vals[..k].to_vec(), vectors)
}

/// Modified Gram–Schmidt on `p` columns of length `n`; a collapsed column is replaced by the
/// next unused axis and orthonormalised again.
fn orthonormalize(w: &mut [f64], n: usize, p: usize, axes: &[usize]) {
    let mut spare = axes.iter().copied().skip(p).chain(axes.iter().copied());
    for j in 0..p {
        let (done, rest) = w.split_at_mut(j * n);
        let wj = &mut rest[..n];
        for _attempt in 0..3 {
            for wq in done.chunks_exact(n) {
                let d = dot(wj, wq);
                for (x, &q) in wj.iter_mut().zip(wq) {
                    *x -= d * q;
                }
            }
            let norm = dot(wj, wj).sqrt();
            if norm > 1e-150 {
                let inv = 1.0 / norm;
                wj.iter_mut().for_each(|x| *x *= inv);
                break;
            }
            let ax = spare.next().unwrap_or(0);
            for (i, x) in wj.iter_mut().enumerate() {
                *x = if i == ax { 1.0 } else { 0.0 };
            }
        }
    }
}

/// Dot product with four running sums (so it vectorises without reassociating one sum).
fn dot(a: &[f64], b: &[f64]) -> f64 {
    let mut acc = [0.0f64; 4];
    let (ac, bc) = (a.chunks_exact(4), b.chunks_exact(4));
    let (ar, br) = (ac.remainder(), bc.remainder());
    for (x, y) in ac.zip(bc) {
        for k in 0..4 {
            acc[k] += x[k] * y[k];
        }
    }
    let tail: f64 = ar.iter().zip(br).map(|(x, y)| x * y).sum();
    (acc[0] + acc[1]) + (acc[2] + acc[3]) + tail
}

fn identity(n: usize) -> Vec<f64> {
    let mut v = vec![0.0; n * n];
    for i in 0..n {
        v[i * n + i] = 1.0;
    }
    v
}

/// The top-k principal axes of a segment.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "camelCase")]
pub struct Signature {
    /// Top-k eigenvalues scaled to sum to 1 (all zero for a motionless segment).
    pub weights: Vec<f32>,
    /// Top-k unit eigenvectors, each `dims` long, concatenated.
    pub vectors: Vec<f32>,
    pub dims: usize,
}

impl Signature {
    /// Signature of `frames` feature vectors of `dims` values each (frame-major), keeping `k`
    /// axes. The covariance is centred on the segment's mean (only how the features vary).
    pub fn of(features: &[f32], dims: usize, k: usize) -> Signature {
        Self::of_moments(features, dims, k, true)
    }

    /// Signature of the raw (frames × features) matrix, as Li & Prabhakaran take it: the
    /// principal axes of its second moments about zero (the right singular vectors of the
    /// matrix), not about the segment's mean, so where the motion is (its mean) counts as well
    /// as how it varies.
    pub fn of_uncentred(features: &[f32], dims: usize, k: usize) -> Signature {
        Self::of_moments(features, dims, k, false)
    }

    fn of_moments(features: &[f32], dims: usize, k: usize, centred: bool) -> Signature {
        let frames = if dims == 0 { 0 } else { features.len() / dims };
        let k = k.min(dims);
        let mut mean = vec![0.0f64; dims];
        if centred {
            for f in 0..frames {
                for d in 0..dims {
                    mean[d] += features[f * dims + d] as f64;
                }
            }
            for m in mean.iter_mut() {
                *m /= frames.max(1) as f64;
            }
        }
        let rows: Vec<f64> = features.chunks_exact(dims.max(1)).take(frames).flat_map(|frame| frame.iter().zip(&mean).map(|(&x, &m)| x as f64 - m)).collect();
        // Fewer frames than features (every library segment): the products through the rows
        // ([`top_eigen_of_rows`], about half the work); else through the moments matrix.
        let (values, vectors) = if frames < dims {
            top_eigen_of_rows(&rows, frames, dims, k)
        } else {
            let mut cov = vec![0.0f64; dims * dims];
            for row in rows.chunks_exact(dims.max(1)) {
                // Upper triangle, row by row (an axpy each: vectorises).
                for i in 0..dims {
                    let ri = row[i];
                    for (c, &rj) in cov[i * dims + i..(i + 1) * dims].iter_mut().zip(&row[i..]) {
                        *c += ri * rj;
                    }
                }
            }
            for i in 0..dims {
                for j in i..dims {
                    let v = cov[i * dims + j] / frames.max(1) as f64;
                    cov[i * dims + j] = v;
                    cov[j * dims + i] = v;
                }
            }
            top_eigen(&cov, dims, k)
        };
        let top: Vec<f64> = values.iter().take(k).map(|v| v.max(0.0)).collect();
        let sum: f64 = top.iter().sum();
        let weights = top.iter().map(|v| if sum > 1e-18 { (v / sum) as f32 } else { 0.0 }).collect();
        Signature { weights, vectors: vectors[..k * dims].iter().map(|&x| x as f32).collect(), dims }
    }

    /// kWAS similarity in [0, 1].
    pub fn similarity(&self, other: &Signature) -> f32 {
        if self.dims != other.dims {
            return 0.0;
        }
        let d = self.dims;
        let k = self.weights.len().min(other.weights.len());
        let mut s = 0.0;
        for i in 0..k {
            let (a, b) = (&self.vectors[i * d..(i + 1) * d], &other.vectors[i * d..(i + 1) * d]);
            let dot: f32 = a.iter().zip(b).map(|(x, y)| x * y).sum();
            s += 0.5 * (self.weights[i] + other.weights[i]) * dot.abs();
        }
        s.clamp(0.0, 1.0)
    }

    /// Dissimilarity D = 1 − Sim.
    pub fn dissimilarity(&self, other: &Signature) -> f32 {
        1.0 - self.similarity(other)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn top_axes_through_the_rows_are_those_of_the_moments_matrix() {
        // 30 rows of 127 features (a 3-count segment's shape), low rank plus noise.
        let (r, n, k) = (30usize, 127usize, 5usize);
        let mut x = 7u64;
        let mut rnd = || {
            x = x.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (x >> 11) as f64 / (1u64 << 53) as f64 - 0.5
        };
        let basis: Vec<f64> = (0..6 * n).map(|_| rnd()).collect();
        let rows: Vec<f64> = (0..r)
            .flat_map(|_| {
                let c: Vec<f64> = (0..6).map(|b| rnd() * (6 - b) as f64).collect();
                (0..n).map(|i| (0..6).map(|b| c[b] * basis[b * n + i]).sum::<f64>() + 0.01 * rnd()).collect::<Vec<f64>>()
            })
            .collect();
        let mut a = vec![0.0f64; n * n];
        for row in rows.chunks_exact(n) {
            for i in 0..n {
                for j in 0..n {
                    a[i * n + j] += row[i] * row[j] / r as f64;
                }
            }
        }
        let (va, ua) = top_eigen(&a, n, k);
        let (vb, ub) = top_eigen_of_rows(&rows, r, n, k);
        for e in 0..k {
            assert!((va[e] - vb[e]).abs() <= 1e-9 * va[0], "eigenvalue {e}: {} vs {}", va[e], vb[e]);
            let d = dot(&ua[e * n..(e + 1) * n], &ub[e * n..(e + 1) * n]).abs();
            assert!(d > 1.0 - 1e-9, "axis {e}: |cos| {d}");
        }
    }

    #[test]
    fn jacobi_reconstructs_a_symmetric_matrix() {
        let n = 6;
        let mut m = vec![0.0; n * n];
        let mut x = 1u64;
        for i in 0..n {
            for j in i..n {
                x = x.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
                let v = ((x >> 33) as f64 / (1u64 << 31) as f64) - 0.5;
                m[i * n + j] = v;
                m[j * n + i] = v;
            }
        }
        let (vals, vecs) = symmetric_eigen(&m, n);
        for w in vals.windows(2) {
            assert!(w[0] >= w[1]);
        }
        // A v = λ v for each pair, and the vectors are orthonormal.
        for e in 0..n {
            let v = &vecs[e * n..(e + 1) * n];
            for i in 0..n {
                let av: f64 = (0..n).map(|j| m[i * n + j] * v[j]).sum();
                assert!((av - vals[e] * v[i]).abs() < 1e-10, "eigenpair {e}");
            }
            for f in 0..n {
                let dot: f64 = (0..n).map(|i| v[i] * vecs[f * n + i]).sum();
                assert!((dot - if e == f { 1.0 } else { 0.0 }).abs() < 1e-10);
            }
        }
    }

    #[test]
    fn subspace_iteration_matches_full_jacobi() {
        let n = 30;
        // A covariance of random features with a decaying spectrum.
        let mut x = 3u64;
        let mut rnd = || {
            x = x.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            ((x >> 33) as f64 / (1u64 << 31) as f64) - 0.5
        };
        let frames = 60;
        let feats: Vec<f64> = (0..frames * n).map(|i| rnd() * (1.0 + 8.0 / (1.0 + (i % n) as f64))).collect();
        let mut c = vec![0.0; n * n];
        for f in 0..frames {
            for i in 0..n {
                for j in 0..n {
                    c[i * n + j] += feats[f * n + i] * feats[f * n + j] / frames as f64;
                }
            }
        }
        let (fv, fe) = symmetric_eigen(&c, n);
        let (tv, te) = top_eigen(&c, n, 5);
        for e in 0..5 {
            assert!((fv[e] - tv[e]).abs() < 1e-6 * fv[0], "eigenvalue {e}: {} vs {}", fv[e], tv[e]);
            let dot: f64 = (0..n).map(|i| fe[e * n + i] * te[e * n + i]).sum();
            assert!(dot.abs() > 0.999, "eigenvector {e}: |cos| {}", dot.abs());
        }
    }

    #[test]
    fn kwas_is_one_for_itself_and_lower_for_other_motion() {
        let dims = 4;
        let along = |axis: usize| -> Vec<f32> {
            (0..50).flat_map(|f| (0..dims).map(move |d| if d == axis { crate::fmath::sin(f as f32 * 0.3) } else { 0.01 * crate::fmath::cos(f as f32 * (d as f32 + 1.0)) })).collect()
        };
        let a = Signature::of(&along(0), dims, 3);
        let b = Signature::of(&along(2), dims, 3);
        assert!((a.similarity(&a) - 1.0).abs() < 1e-4);
        assert!(a.similarity(&b) < 0.2, "{}", a.similarity(&b));
        assert!((a.similarity(&b) - b.similarity(&a)).abs() < 1e-6);
    }

    #[test]
    fn uncentred_signatures_see_where_the_motion_is_and_its_sign() {
        // The same sway about two opposite offsets, with a constant last feature: centred
        // signatures cannot tell them apart; uncentred ones can, and keep the sign (a plain
        // |cos| of the mean would not).
        let dims = 3;
        let at = |offset: f32| -> Vec<f32> { (0..40).flat_map(|f| [offset + 0.1 * crate::fmath::sin(f as f32 * 0.4), 0.05 * crate::fmath::cos(f as f32 * 0.7), 1.0]).collect() };
        let (a, b, c) = (at(0.8), at(-0.8), at(0.7));
        let centred = |x: &[f32]| Signature::of(x, dims, 2);
        assert!(centred(&a).similarity(&centred(&b)) > 0.99);
        let un = |x: &[f32]| Signature::of_uncentred(x, dims, 2);
        let (sa, sb, sc) = (un(&a), un(&b), un(&c));
        assert!((sa.similarity(&sa) - 1.0).abs() < 1e-4);
        assert!(sa.similarity(&sc) > sa.similarity(&sb) + 0.2, "near {} vs opposite {}", sa.similarity(&sc), sa.similarity(&sb));
    }
}
