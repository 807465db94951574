//! Why §F's feedback converges or not: the preference test of §J (as the `choreo_preference`
//! bench: built-in moves + the CMU salsa and Indian clips, hidden targets, 2 likes per round, 5
//! rounds, ρ and τ as the app's defaults) run on variants of the loop, written here on
//! precomputed matrices so one run compares them all. Not the product's code path (that is
//! `choreo::feedback`, measured by `choreo_preference`); a study of the decisions the spec
//! leaves to the product:
//! - which shown candidates enter Φ's min D (all, as the spec's S_n; or those not liked),
//! - τ's 19/20 per Search round (the spec) or per like,
//! - Sim and D as raw kWAS or as percentiles among the anchor's neighbours in the library,
//! - how the likes enter Φ: the spec's max over L of Sim (also weighted by recency, or over the
//!   last round's likes only, or the mean over L), or the share of (liked, passed-over) pairs
//!   the candidate agrees with — Sim(m, l) > Sim(m, n) — within each round or over all rounds
//!   (the product's), on raw kWAS or on percentiles, alone or mixed with the max,
//! - min D over this round's picks only (maximal-marginal-relevance style), 2 of the 6
//!   picked with τ = 0 (exploitation) before the diverse ones, both Φ terms min–max scaled
//!   over U, and ρ at 0, 0.15 and 0.5,
//! - and two controls: a *perfect* similarity (1 − perceptual distance / its maximum, the
//!   simulated person's own distance, which the search must not use) and a greedy loop (ρ = 0
//!   throughout and τ = 0 once something is liked: every candidate the nearest unseen
//!   neighbour of a like, no diversity at all), the ceiling of what any schedule could reach.
//! Similarities compared (`STUDY_SIMS=a,b` keeps those whose names contain a or b): the
//! library's kWAS (the product's signatures), Krzanowski's PCA similarity on the same
//! signatures, kWAS on other features computed here from each segment's positions
//! time-normalised to 32 frames and normalised as §B (the 10 signature joints or all canonical
//! joints, less the library's mean pose, with or without velocities), and the perfect one; for
//! each, its agreement with the perceptual distance (Spearman over the library, 192 targets).
//! Target sets: A (the `choreo_preference` bench's), B and C, disjoint, and with
//! `STUDY_SETS=n` up to 7 more (X0..), so that A tunes and the rest test. Per variant: targets
//! where the guided person ends closer than one random person (and ties, losses; and the median
//! over 5 random people), closer than the mean of 5 random people, closer summed over the 5
//! rounds (`auc`), the mean fall of the best distance from round 1 to 5, targets whose nearest
//! segment is already in round 1 (`r1 has NN`: no loop can improve on those), and the mean
//! best distance at rounds 1 and 5, guided (`g`) and random (`r`). Also prints how raw kWAS
//! spreads over a segment's neighbours next to the spread of the intensities rel compares.
//! Asserts nothing.

use glam::Vec3;
use odori_core::choreo::quality::{perceptual_distance, perceptual_frames};
use odori_core::choreo::segment::{SIGNATURE_AXES, SIGNATURE_OFFSET};
use odori_core::canon::humanoid::Canon;
use odori_core::choreo::{feedback::relevance, SegmentLibrary, SegmentOptions, Settings, Signature};
use odori_core::canon::humanoid::{canonical_positions, HumanoidMap, CANON_COUNT};
use odori_core::import::import_bytes;
use odori_core::ImportOptions;
use odori_tests::{all_bvh, fps_override_for, read, simulated_likes, spearman};

const ROUNDS: usize = 5;
const LIKES: usize = 2;
const PER: usize = 6;

#[derive(Clone, Copy, Debug)]
struct V {
    /// Φ's min D over: 0 every candidate shown (the spec's S_n), 1 those shown and not liked,
    /// 2 this round's picks only.
    mind: u8,
    /// 0 per round, 1 per like
    tau: u8,
    /// Sim to L: 0 the max (the spec), 1 the max weighted by γ per round of the like's age, 2
    /// the max over the last round's likes.
    agg: u8,
    gamma: f32,
    /// Picks per round made with τ = 0 (once something is liked).
    exploit: usize,
    decay: f32,
    /// Sim and D: 0 raw kWAS, 1 percentile among the anchor's neighbours.
    scale: u8,
    rho: f32,
}

/// Like terms beyond the spec's max (study only): 3 the mean over L of Sim, 4 the share of
/// (liked, not liked) pairs of one round for which the candidate is more similar (raw) to the
/// liked one, 5 the spec's max with both Φ terms min–max normalised over U each round.
const AGG_MEAN: u8 = 3;
const AGG_PAIRS: u8 = 4;
const AGG_MINMAX: u8 = 5;
/// 6: the max over L of, per like, the share of its round's not-liked candidates the candidate is
/// less similar to than to the like (+ 0.01 × the percentile Sim, to break ties).
const AGG_PAIRS_MAX: u8 = 6;
/// 7: as 4 over every (liked, shown and not liked) pair, whatever the rounds.
const AGG_PAIRS_ALL: u8 = 7;
/// 8: as 7 comparing percentiles (c's rank among l's neighbours against among n's).
const AGG_PAIRS_RANK: u8 = 8;
/// 9: ½ (7) + ½ the spec's max over L of the percentile Sim.
const AGG_PAIRS_MIX: u8 = 9;

fn run(v: V, sim_raw: &[f32], sim_rank: &[f32], m: usize, rel_of: &dyn Fn(usize) -> f32, retired: &[bool], rho: f32, target: usize, dist: &dyn Fn(usize) -> f32, guided: bool, seed: &mut u64) -> Vec<f32> {
    let mut shown: Vec<usize> = Vec::new();
    let mut liked: Vec<(usize, usize)> = Vec::new(); // (segment, round liked)
    let mut rejected: Vec<(usize, usize)> = Vec::new(); // (segment, round shown and not liked)
    let mut tau = 1.0f32;
    let mut best = f32::INFINITY;
    let mut out = Vec::new();
    let rel: Vec<f32> = (0..m).map(rel_of).collect();
    let sim = if v.scale == 1 { sim_rank } else { sim_raw };
    let rho = if v.rho >= 0.0 { v.rho } else { rho };
    for r in 0..ROUNDS {
        // choose the round
        let mut is_shown: Vec<bool> = retired.to_vec();
        for &s in &shown {
            is_shown[s] = true;
        }
        let mut min_d = vec![1.0f32; m];
        let upd = |min_d: &mut [f32], s: usize| {
            for c in 0..m {
                min_d[c] = min_d[c].min(1.0 - sim[s * m + c]);
            }
        };
        let liked_set: Vec<usize> = liked.iter().map(|l| l.0).collect();
        match v.mind {
            0 => shown.iter().for_each(|&s| upd(&mut min_d, s)),
            1 => shown.iter().filter(|s| !liked_set.contains(s)).for_each(|&s| upd(&mut min_d, s)),
            _ => {}
        }
        let mut max_sim = vec![0.0f32; m];
        if v.agg == AGG_MEAN && !liked.is_empty() {
            for &(l, _) in &liked {
                for c in 0..m {
                    max_sim[c] += sim[l * m + c] / liked.len() as f32;
                }
            }
        } else if matches!(v.agg, AGG_PAIRS | AGG_PAIRS_ALL | AGG_PAIRS_RANK | AGG_PAIRS_MIX) && !liked.is_empty() {
            let mut pairs = 0.0f32;
            let cmp = if v.agg == AGG_PAIRS_RANK { sim } else { sim_raw };
            for &(l, lr) in &liked {
                for &(n, nr) in &rejected {
                    if nr == lr || v.agg != AGG_PAIRS {
                        pairs += 1.0;
                        for c in 0..m {
                            if cmp[l * m + c] > cmp[n * m + c] {
                                max_sim[c] += 1.0;
                            }
                        }
                    }
                }
            }
            max_sim.iter_mut().for_each(|x| *x /= pairs.max(1.0));
            if v.agg == AGG_PAIRS_MIX {
                for c in 0..m {
                    let mx = liked.iter().map(|&(l, _)| sim[l * m + c]).fold(0.0f32, f32::max);
                    max_sim[c] = 0.5 * max_sim[c] + 0.5 * mx;
                }
            }
        } else if v.agg == AGG_PAIRS_MAX && !liked.is_empty() {
            for &(l, lr) in &liked {
                let mates: Vec<usize> = rejected.iter().filter(|r| r.1 == lr).map(|r| r.0).collect();
                for c in 0..m {
                    let share = mates.iter().filter(|&&n| sim_raw[l * m + c] > sim_raw[n * m + c]).count() as f32 / mates.len().max(1) as f32;
                    max_sim[c] = max_sim[c].max(0.99 * share + 0.01 * sim[l * m + c]);
                }
            }
        } else {
        for &(l, lr) in &liked {
            let w = match v.agg {
                3..=9 => 1.0,
                0 => 1.0,
                1 => v.gamma.powi((r - 1 - lr) as i32),
                _ => {
                    if lr + 1 == r {
                        1.0
                    } else {
                        0.0
                    }
                }
            };
            for c in 0..m {
                max_sim[c] = max_sim[c].max(w * sim[l * m + c]);
            }
        }
        }
        // Min–max scales of both Φ terms over U (AGG_MINMAX), fixed for the round.
        let (mut d_lo, mut d_span, mut s_lo, mut s_span) = (0.0f32, 1.0f32, 0.0f32, 1.0f32);
        if v.agg == AGG_MINMAX {
            let range = |x: &[f32]| {
                let (lo, hi) = (0..m).filter(|&c| !is_shown[c]).map(|c| x[c]).fold((f32::INFINITY, f32::NEG_INFINITY), |(a, b), y| (a.min(y), b.max(y)));
                (lo, (hi - lo).max(1e-6))
            };
            (d_lo, d_span) = range(&min_d);
            if !liked.is_empty() {
                (s_lo, s_span) = range(&max_sim);
            }
        }
        let mut round = Vec::new();
        for n in 0..PER {
            let t = if n < v.exploit && !liked.is_empty() { 0.0 } else { tau };
            let mut bestc: Option<(f32, usize)> = None;
            for c in 0..m {
                if is_shown[c] {
                    continue;
                }
                let phi = t * (min_d[c] - d_lo) / d_span + (1.0 - t) * (max_sim[c] - s_lo) / s_span;
                let s = rho * rel[c] + (1.0 - rho) * phi;
                if bestc.is_none_or(|(b, _)| s > b) {
                    bestc = Some((s, c));
                }
            }
            let Some((_, p)) = bestc else { break };
            is_shown[p] = true;
            shown.push(p);
            round.push(p);
            upd(&mut min_d, p);
        }
        let scored: Vec<(f32, usize)> = round.iter().filter(|&&c| c != target).map(|&c| (dist(c), c)).collect();
        best = scored.iter().map(|s| s.0).fold(best, f32::min);
        out.push(best);
        if r + 1 == ROUNDS {
            break;
        }
        let picks = simulated_likes(scored, guided, LIKES, seed);
        for &p in &picks {
            liked.push((p, r));
        }
        for &c in &round {
            if !picks.contains(&c) {
                rejected.push((c, r));
            }
        }
        tau *= match v.tau {
            0 => v.decay,
            _ => v.decay.powi(picks.len() as i32),
        };
    }
    out
}

fn main() {
    let mut lib = SegmentLibrary::builtin();
    for rel in all_bvh().into_iter().filter(|r| r.contains("cmu-salsa") || r.contains("cmu-indian")) {
        let opts = ImportOptions { fps_override: fps_override_for(&rel), ..Default::default() };
        let imp = import_bytes(&rel, &read(&rel), &opts).unwrap();
        for clip in &imp.clips {
            lib.add_clip(clip, &imp.humanoid, &imp.status, &SegmentOptions::default()).unwrap();
        }
    }
    let clip_pos: Vec<Vec<Vec3>> = lib.clips().iter().map(|c| canonical_positions(&c.clip, &HumanoidMap::from_skeleton(&c.clip.skeleton))).collect();
    let seg_pos = |s: usize| -> Vec<Vec3> {
        let seg = &lib.segments()[s];
        let p = &clip_pos[seg.clip];
        let frames = p.len() / CANON_COUNT;
        let (a, b) = (seg.start_frame.round() as usize, (seg.end_frame.round() as usize).min(frames.saturating_sub(1)));
        p[a * CANON_COUNT..(b + 1) * CANON_COUNT].to_vec()
    };
    let m = lib.len();
    let positions: Vec<Vec<Vec3>> = (0..m).map(seg_pos).collect();
    let t0 = std::time::Instant::now();
    let mut pd = vec![0.0f32; m * m];
    for a in 0..m {
        for b in a + 1..m {
            let d = perceptual_distance(&positions[a], &positions[b]).unwrap_or(f32::INFINITY);
            pd[a * m + b] = d;
            pd[b * m + a] = d;
        }
    }
    println!("perceptual distances of {m} segments: {:.1} s", t0.elapsed().as_secs_f32());
    let kwas: Vec<f32> = (0..m * m).map(|i| lib.similarity(i / m, i % m)).collect();
    let pmax = pd.iter().cloned().filter(|x| x.is_finite()).fold(0.0f32, f32::max);
    // perfect similarity: 1 − d / max
    let perfect: Vec<f32> = pd.iter().map(|d| 1.0 - d / pmax).collect();
    // rank percentile per anchor row: rank[a*m+c] = share of segments less similar to a than c
    let to_rank = |sim: &[f32]| -> Vec<f32> {
        let mut out = vec![0.0f32; m * m];
        for a in 0..m {
            let mut order: Vec<usize> = (0..m).collect();
            order.sort_by(|&i, &j| sim[a * m + i].total_cmp(&sim[a * m + j]));
            for (k, &c) in order.iter().enumerate() {
                out[a * m + c] = k as f32 / (m - 1) as f32;
            }
        }
        out
    };
    let kwas_rank = to_rank(&kwas);
    let perfect_rank = to_rank(&perfect);
    // Feature variants for the eigen signatures, computed here from each segment's positions
    // time-normalised to 32 frames and normalised as §B (as the perceptual distance prepares
    // them), against the library's mean pose.
    let prep = |p: &[Vec3]| perceptual_frames(p).unwrap_or_else(|e| panic!("{e}"));
    let normed: Vec<Vec<Vec3>> = positions.iter().map(|p| prep(p)).collect();
    let mut mean_pose = vec![Vec3::ZERO; CANON_COUNT];
    for n in &normed {
        for (f, p) in n.iter().enumerate() {
            mean_pose[f % CANON_COUNT] += *p / (32 * m) as f32;
        }
    }
    // The ten joints the product's signatures used until session 7.
    let sig_joints: Vec<usize> = [Canon::Chest, Canon::Head, Canon::LeftForearm, Canon::RightForearm, Canon::LeftHand, Canon::RightHand, Canon::LeftLowerLeg, Canon::RightLowerLeg, Canon::LeftFoot, Canon::RightFoot].iter().map(|c| c.index()).collect();
    let all_joints: Vec<usize> = (0..CANON_COUNT).collect();
    let sig_of = |n: &[Vec3], joints: &[usize], vel: f32| -> Signature {
        let dims = joints.len() * if vel > 0.0 { 6 } else { 3 } + 1;
        let mut feats = Vec::new();
        for f in 0..32 {
            for &j in joints {
                let p = n[f * CANON_COUNT + j] - mean_pose[j];
                feats.extend_from_slice(&[p.x, p.y, p.z]);
            }
            if vel > 0.0 {
                let (f0, f1) = (f.saturating_sub(1), (f + 1).min(31));
                for &j in joints {
                    let d = (n[f1 * CANON_COUNT + j] - n[f0 * CANON_COUNT + j]) * (vel / (f1 - f0) as f32);
                    feats.extend_from_slice(&[d.x, d.y, d.z]);
                }
            }
            feats.push(SIGNATURE_OFFSET);
        }
        Signature::of_uncentred(&feats, dims, SIGNATURE_AXES)
    };
    let sim_matrix = |sigs: &[Signature]| -> Vec<f32> { (0..m * m).map(|i| sigs[i / m].similarity(&sigs[i % m])).collect() };
    let krz = |a: &Signature, b: &Signature| -> f32 {
        let (d, k) = (a.dims, a.weights.len().min(b.weights.len()));
        let mut s = 0.0;
        for i in 0..k {
            for j in 0..k {
                let dot: f32 = a.vectors[i * d..(i + 1) * d].iter().zip(&b.vectors[j * d..(j + 1) * d]).map(|(x, y)| x * y).sum();
                s += dot * dot;
            }
        }
        s / k.max(1) as f32
    };
    let lib_sigs: Vec<Signature> = (0..m).map(|i| lib.signature(i).unwrap().clone()).collect();
    let krz_lib: Vec<f32> = (0..m * m).map(|i| krz(&lib_sigs[i / m], &lib_sigs[i % m])).collect();
    let mut sims: Vec<(String, Vec<f32>)> = vec![("kWAS (library)".into(), kwas.clone()), ("Krzanowski (library signatures)".into(), krz_lib)];
    for (name, joints, vel) in [("10 joints, 32 frames", &sig_joints, 0.0f32), ("10 joints + vel x4", &sig_joints, 4.0), ("10 joints + vel x8", &sig_joints, 8.0), ("10 joints + vel x16", &sig_joints, 16.0), ("all joints", &all_joints, 0.0), ("all joints + vel x8", &all_joints, 8.0)] {
        let sigs: Vec<Signature> = normed.iter().map(|n| sig_of(n, joints, vel)).collect();
        sims.push((format!("kWAS {name}"), sim_matrix(&sigs)));
    }
    sims.push(("perfect".into(), perfect.clone()));
    // Agreement (Spearman of Sim(t, ·) with −perceptual distance over the library, mean over
    // the targets of all three sets).
    let agree_targets: Vec<usize> = (0..192).map(|i| (i * m) / 192 + 3).filter(|&t| t < m).collect();
    for (name, sim) in &sims {
        let mut acc = 0.0;
        for &t in &agree_targets {
            let others: Vec<usize> = (0..m).filter(|&c| c != t).collect();
            let a: Vec<f32> = others.iter().map(|&c| sim[t * m + c]).collect();
            let b: Vec<f32> = others.iter().map(|&c| -pd[t * m + c]).collect();
            acc += spearman(&a, &b);
        }
        println!("agreement with the perceptual distance, {name:<34}: Spearman {:.3}", acc / agree_targets.len() as f32);
    }
    // spread of raw kWAS per anchor: similarity of the k-th nearest neighbour (mean over anchors)
    for k in [1usize, 5, 10, 50, 100, 300, 600] {
        let mut acc = 0.0;
        for a in 0..m {
            let mut row: Vec<f32> = (0..m).filter(|&c| c != a).map(|c| kwas[a * m + c]).collect();
            row.sort_by(|x, y| y.total_cmp(x));
            acc += row[k.min(row.len()) - 1];
        }
        println!("raw kWAS of a segment's {k}-th nearest neighbour (mean over segments): {:.4}", acc / m as f32);
    }
    let ints: Vec<f32> = lib.segments().iter().map(|s| s.intensity01).collect();
    let mut si = ints.clone();
    si.sort_by(|a, b| a.total_cmp(b));
    println!("motion intensities (0..1), quartiles: {:.3} {:.3} {:.3}", si[m / 4], si[m / 2], si[3 * m / 4]);
    let retired: Vec<bool> = lib.segments().iter().map(|s| s.retired).collect();
    let rho = Settings::default().rho;
    // two target sets: the bench's 64 and a disjoint 64 (offset)
    let set_a: Vec<usize> = (0..64).map(|i| (i * m) / 64 + 3).filter(|&t| t < m).collect();
    let set_b: Vec<usize> = (0..64).map(|i| (i * m) / 64 + 8).filter(|&t| t < m).collect();
    let set_c: Vec<usize> = (0..64).map(|i| (i * m) / 64 + 5).filter(|&t| t < m).collect();
    // ceiling: round-1 contains the nearest (excl. target)?
    let base = V { mind: 1, tau: 0, agg: 0, gamma: 1.0, exploit: 0, decay: 0.95, scale: 0, rho: -1.0 };
    let variants: Vec<(&str, V)> = vec![
        ("spec loop (S_n incl. liked)", V { mind: 0, ..base }),
        ("previous (S_n not liked)", base),
        ("+ percentile", V { scale: 1, ..base }),
        ("+ per like", V { tau: 1, ..base }),
        ("+ percentile + per like (app)", V { scale: 1, tau: 1, ..base }),
        ("  ... Sim by recency γ = ½", V { scale: 1, tau: 1, agg: 1, gamma: 0.5, ..base }),
        ("  ... min D this round only", V { scale: 1, tau: 1, mind: 2, ..base }),
        ("  ... 2 of 6 with τ = 0", V { scale: 1, tau: 1, exploit: 2, ..base }),
        ("  ... Sim to L: mean", V { scale: 1, tau: 1, agg: AGG_MEAN, ..base }),
        ("  ... Sim to L: pairs", V { scale: 1, tau: 1, agg: AGG_PAIRS, ..base }),
        ("  ... Sim to L: pairs, max", V { scale: 1, tau: 1, agg: AGG_PAIRS_MAX, ..base }),
        ("  ... Sim to L: all pairs", V { scale: 1, tau: 1, agg: AGG_PAIRS_ALL, ..base }),
        ("  ... all pairs, S_n all shown", V { scale: 1, tau: 1, agg: AGG_PAIRS_ALL, mind: 0, ..base }),
        ("  ... all pairs, τ per round", V { scale: 1, tau: 0, agg: AGG_PAIRS_ALL, ..base }),
        ("  ... all pairs, 2 of 6 τ = 0", V { scale: 1, tau: 1, agg: AGG_PAIRS_ALL, exploit: 2, ..base }),
        ("  ... Sim to L: pairs on ranks", V { scale: 1, tau: 1, agg: AGG_PAIRS_RANK, ..base }),
        ("  ... Sim to L: pairs + max", V { scale: 1, tau: 1, agg: AGG_PAIRS_MIX, ..base }),
        ("  ... Sim to L: pairs, ρ 0.5", V { scale: 1, tau: 1, agg: AGG_PAIRS, rho: 0.5, ..base }),
        ("  ... Sim to L: pairs, ρ 0.15", V { scale: 1, tau: 1, agg: AGG_PAIRS, rho: 0.15, ..base }),
        ("  ... Φ terms min-max", V { scale: 1, tau: 1, agg: AGG_MINMAX, ..base }),
        ("  ... ρ 0", V { scale: 1, tau: 1, rho: 0.0, ..base }),
        ("  ... ρ 0.15", V { scale: 1, tau: 1, rho: 0.15, ..base }),
        ("  ... ρ 0.5", V { scale: 1, tau: 1, rho: 0.5, ..base }),
        ("greedy control (ρ = τ = 0)", V { scale: 1, exploit: 6, rho: 0.0, ..base }),
    ];
    let only = std::env::var("STUDY_SIMS").ok();
    let ranks: Vec<Vec<f32>> = sims.iter().map(|(_, x)| to_rank(x)).collect();
    let _ = (&kwas_rank, &perfect_rank);
    for ((simname, sim), rank) in sims.iter().zip(&ranks) {
        if let Some(o) = &only {
            if !o.split(',').any(|w| simname.contains(w)) {
                continue;
            }
        }
        let simname = simname.as_str();
        let extra: usize = std::env::var("STUDY_SETS").ok().and_then(|x| x.parse().ok()).unwrap_or(0);
        let mut sets: Vec<(String, Vec<usize>)> = vec![("A".into(), set_a.clone()), ("B".into(), set_b.clone()), ("C".into(), set_c.clone())];
        // More disjoint sets of 64 (offsets other than A's 3, B's 8 and C's 5), for a steadier count.
        for (k, off) in [0usize, 1, 2, 4, 6, 7, 9].into_iter().take(extra).enumerate() {
            sets.push((format!("X{k}"), (0..64).map(|i| (i * m) / 64 + off).filter(|&t| t < m).collect()));
        }
        for (set_name, targets) in sets.iter().map(|(n, t)| (n.as_str(), t)) {
            println!("== similarity {simname}, targets {set_name} ({}) ==", targets.len());
            for (name, v) in &variants {
                let (mut wins, mut ties, mut losses, mut wins5, mut auc_wins) = (0, 0, 0, 0, 0);
                let mut falls = 0.0;
                let mut g_mean = vec![0.0; ROUNDS];
                let mut r_mean = vec![0.0; ROUNDS];
                let mut round1_has_nn = 0;
                let (mut wins_each, mut ties_each) = ([0usize; 5], [0usize; 5]);
                for &t in targets.iter() {
                    let dist = |c: usize| pd[c * m + t];
                    let inten = lib.segments()[t].intensity01;
                    let rel_of = |c: usize| relevance(inten, lib.segments()[c].intensity01);
                    let mut seed = 0x5DEE_CE66_Du64 ^ (t as u64 * 7919);
                    let g = run(*v, sim, &rank, m, &rel_of, &retired, rho, t, &dist, true, &mut seed);
                    let rs: Vec<Vec<f32>> = (0..5).map(|_| run(*v, sim, &rank, m, &rel_of, &retired, rho, t, &dist, false, &mut seed)).collect();
                    let r0 = &rs[0];
                    for (d, r) in rs.iter().enumerate() {
                        if g[ROUNDS - 1] < r[ROUNDS - 1] {
                            wins_each[d] += 1;
                        } else if g[ROUNDS - 1] == r[ROUNDS - 1] {
                            ties_each[d] += 1;
                        }
                    }
                    let nn = (0..m).filter(|&c| c != t && !retired[c]).map(|c| pd[c * m + t]).fold(f32::INFINITY, f32::min);
                    if (g[0] - nn).abs() < 1e-9 {
                        round1_has_nn += 1;
                    }
                    if g[ROUNDS - 1] < r0[ROUNDS - 1] {
                        wins += 1
                    } else if g[ROUNDS - 1] == r0[ROUNDS - 1] {
                        ties += 1
                    } else {
                        losses += 1
                    }
                    let rmean5: f32 = rs.iter().map(|r| r[ROUNDS - 1]).sum::<f32>() / 5.0;
                    if g[ROUNDS - 1] < rmean5 {
                        wins5 += 1;
                    }
                    let auc = |x: &[f32]| x.iter().sum::<f32>();
                    if auc(&g) < auc(r0) {
                        auc_wins += 1;
                    }
                    falls += 1.0 - g[ROUNDS - 1] / g[0];
                    for k in 0..ROUNDS {
                        g_mean[k] += g[k] / targets.len() as f32;
                        r_mean[k] += r0[k] / targets.len() as f32;
                    }
                }
                let n = targets.len();
                wins_each.sort();
                ties_each.sort();
                println!(
                    "{name:<30} 1-random median wins {:>2} ties {:>2} |",
                    wins_each[2], ties_each[2]
                );
                println!(
                    "{name:<30} wins {wins:>2}/{n} ties {ties:>2} loss {losses:>2} | vs mean-of-5 {wins5:>2} | auc {auc_wins:>2} | fall {:>5.1}% | r1 has NN {round1_has_nn:>2} | g {:.4}->{:.4} r {:.4}->{:.4}",
                    100.0 * falls / n as f32,
                    g_mean[0],
                    g_mean[ROUNDS - 1],
                    r_mean[0],
                    r_mean[ROUNDS - 1]
                );
            }
        }
    }
}
