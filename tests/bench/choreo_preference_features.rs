//! Which per-frame features §F's eigen-analysis should run on (the spec fixes Φ, τ and kWAS,
//! not the features): each variant's kWAS signatures are computed here from every segment's
//! §B-normalised canonical positions (every other frame, as `choreo::segment::signature_of`
//! does), and each is measured three ways, on the real library of the `choreo_preference`
//! bench (built-in moves + the CMU salsa and Indian clips, cut at their clip tempo):
//! - **agreement** with the §J perceptual distance: Spearman of Sim(t, ·) against −distance
//!   over the library, mean over 192 targets;
//! - the **§J preference test** with the product's loop (`choreo::feedback`, rewritten here on
//!   a precomputed similarity matrix so one run compares every variant: percentile Sim and D,
//!   S_n without the likes, τ × 19/20 per like, ρ the app's default), 2 likes per round, 5
//!   rounds, on the ten disjoint sets of 64 hidden targets of `PREFERENCE_SETS=10` against the
//!   mean of 5 random people: offsets 0–4 choose (tuning sets), offsets 5–9 are held out, and
//!   each is reported apart; with Φ's like term the spec's max over L (the default) and the
//!   `ChoicePairs` option;
//! - **Fig. 4** (§F's check: eq. 9, the mean pairwise raw D of the 6 shown, falls over the
//!   first rounds), simulated as `choreo_feedback` does (like the shown candidate nearest the
//!   hidden target by D, ρ 0.3, the bar at intensity ½, 6 rounds) on the built-in moves alone
//!   and on the real library, with *every* segment as a target, and on `choreo_feedback`'s 12.
//!   The rule was fixed before any variant was measured: over all targets, eq. 9 at round 2
//!   and at round 3 below round 1, and its least-squares slope over rounds 1–6 negative.
//!
//! The choice (session 7), the product's `signature_of` since: every joint, velocity ×2 (its
//! displacement over 4 frames), offset 1, 5 axes — 247/320 on the tuning sets with the max,
//! agreement 0.793. The highest tuning count, 249/320, was offset 0.75's; the two differ by
//! less than the random draws' noise, and offset 1 was kept for its better agreement (0.777
//! for 0.75) and for eq. 9 falling strictly over rounds 1–3 on the real library (it rises from
//! round 2 to 3 with 0.75) — a tie-break made after seeing the grid, so both held-out counts
//! are given: 238/320 for offset 1, 229/320 for 0.75. The product's own run
//! (`choreo_preference`, signatures cut from the whole clip) gives 241/320 and 240/320.
//!
//! `FEATURES=a,b` keeps the variants whose names contain a or b. Asserts nothing.
//! `cargo test -p odori-tests --bench choreo_preference_features --release` (a dev build runs
//! it too, slower).

#[path = "choreo_preference.rs"]
#[allow(dead_code)]
mod preference;

use glam::Vec3;
use odori_core::choreo::quality::perceptual_frames;
use odori_core::choreo::{feedback::relevance, SegmentLibrary, Settings, Signature};
use odori_core::canon::humanoid::{Canon, CANON_COUNT};
use odori_core::canon::normalize::{body_height, normalize_in_place, Origin};
use odori_tests::{simulated_likes, spearman};

const ROUNDS: usize = 5;
const LIKES: usize = 2;
const PER: usize = 6;
const DRAWS: usize = 5;

/// One feature set for the signatures.
#[derive(Clone)]
struct Features {
    name: String,
    /// Canonical joints and their weights (a joint's three coordinates are multiplied by it).
    joints: Vec<(usize, f32)>,
    /// Weight of each joint's velocity (body heights per frame at 15 fps × this); 0: none.
    velocity: f32,
    /// The constant last feature (0: none).
    offset: f32,
    /// Eigen axes kept.
    axes: usize,
    /// Subtract the built-in moves' mean pose (else raw hip-relative positions).
    reference: bool,
}

fn main() {
    let (lib, positions) = preference::library();
    let m = lib.len();
    let t0 = std::time::Instant::now();
    // §B-normalised positions of each segment, whole frames (for the signatures) and
    // time-normalised to 32 frames (for the perceptual distance, as `perceptual_distance`).
    let normed: Vec<Vec<Vec3>> = positions
        .iter()
        .map(|p| {
            let mut n = p.clone();
            normalize_in_place(&mut n, Origin::Hips, body_height(p));
            n
        })
        .collect();
    let prep32: Vec<Vec<Vec3>> = positions.iter().map(|p| perceptual_frames(p).expect("a segment's canonical positions")).collect();
    let mut pd = vec![0.0f32; m * m];
    for a in 0..m {
        for b in a + 1..m {
            let d = prep32[a].iter().zip(&prep32[b]).map(|(x, y)| (*x - *y).length()).sum::<f32>() / prep32[a].len() as f32;
            pd[a * m + b] = d;
            pd[b * m + a] = d;
        }
    }
    // Same as the product's perceptual distance.
    for (a, b) in [(0, 1), (5, m - 1), (m / 2, m / 3)] {
        let want = odori_core::choreo::quality::perceptual_distance(&positions[a], &positions[b]).unwrap();
        assert!((pd[a * m + b] - want).abs() < 1e-4, "perceptual distance {a} {b}: {} vs {want}", pd[a * m + b]);
    }
    println!("{m} segments; perceptual distances in {:.1} s", t0.elapsed().as_secs_f32());

    // The built-in moves: the real library's first segments, with their own intensities.
    let builtin = SegmentLibrary::builtin();
    let nb = builtin.len();
    for s in 0..nb {
        assert_eq!(builtin.segments()[s].name, lib.segments()[s].name, "segment {s}: the real library does not start with the built-in moves");
    }
    let nb_active = lib.segments()[..nb].iter().filter(|s| s.builtin.is_some()).count();
    assert_eq!(nb_active, nb);

    // The built-in moves' mean pose (every frame of every built-in segment).
    let mut mean_pose = vec![Vec3::ZERO; CANON_COUNT];
    let mut frames = 0usize;
    for n in &normed[..nb] {
        for (i, p) in n.iter().enumerate() {
            mean_pose[i % CANON_COUNT] += *p;
        }
        frames += n.len() / CANON_COUNT;
    }
    mean_pose.iter_mut().for_each(|p| *p /= frames as f32);

    let ten: Vec<(usize, f32)> = [
        Canon::Chest,
        Canon::Head,
        Canon::LeftForearm,
        Canon::RightForearm,
        Canon::LeftHand,
        Canon::RightHand,
        Canon::LeftLowerLeg,
        Canon::RightLowerLeg,
        Canon::LeftFoot,
        Canon::RightFoot,
    ]
    .iter()
    .map(|c| (c.index(), 1.0))
    .collect();
    let all: Vec<(usize, f32)> = (0..CANON_COUNT).map(|j| (j, 1.0)).collect();
    let no_hips: Vec<(usize, f32)> = (1..CANON_COUNT).map(|j| (j, 1.0)).collect();
    let base = Features { name: String::new(), joints: ten.clone(), velocity: 0.0, offset: 0.5, axes: 5, reference: true };
    let mut variants = vec![
        Features { name: "10 joints (the product's)".into(), ..base.clone() },
        Features { name: "all joints".into(), joints: all.clone(), ..base.clone() },
        Features { name: "all joints but the hips".into(), joints: no_hips.clone(), ..base.clone() },
        Features { name: "all joints, offset 0.25".into(), joints: all.clone(), offset: 0.25, ..base.clone() },
        Features { name: "all joints, offset 1".into(), joints: all.clone(), offset: 1.0, ..base.clone() },
        Features { name: "all joints, no reference".into(), joints: all.clone(), reference: false, ..base.clone() },
        Features { name: "all joints, 3 axes".into(), joints: all.clone(), axes: 3, ..base.clone() },
        Features { name: "all joints, 8 axes".into(), joints: all.clone(), axes: 8, ..base.clone() },
        Features { name: "all joints + velocity x2".into(), joints: all.clone(), velocity: 2.0, ..base.clone() },
        Features { name: "10 joints, 8 axes".into(), axes: 8, ..base.clone() },
    ];
    for vel in [1.0f32, 3.0, 4.0, 6.0] {
        variants.push(Features { name: format!("all joints + velocity x{vel}"), joints: all.clone(), velocity: vel, ..base.clone() });
    }
    for (offset, axes) in [(0.75f32, 5usize), (0.5, 3), (0.5, 8), (1.0, 5)] {
        variants.push(Features { name: format!("all joints + velocity x2, offset {offset}, {axes} axes"), joints: all.clone(), velocity: 2.0, offset, axes, ..base.clone() });
    }
    variants.push(Features { name: "10 joints + velocity x2".into(), velocity: 2.0, ..base.clone() });
    // The grid the choice was made on (tuning sets 0–4, max over L).
    for vel in [1.5f32, 2.0, 2.5, 3.0] {
        for offset in [0.75f32, 1.0, 1.25] {
            variants.push(Features { name: format!("grid: all joints, velocity x{vel}, offset {offset}"), joints: all.clone(), velocity: vel, offset, ..base.clone() });
        }
    }
    // Weights by how far each joint strays from the mean pose in the perceptual distance:
    // the distance is a plain mean over joints, so every joint counts once; a joint that
    // barely moves (hips, spine) adds nothing either way.
    variants.push(Features {
        name: "all joints, limbs x1.5".into(),
        joints: (0..CANON_COUNT)
            .map(|j| {
                let limb = [Canon::LeftHand, Canon::RightHand, Canon::LeftFoot, Canon::RightFoot, Canon::LeftToe, Canon::RightToe, Canon::LeftForearm, Canon::RightForearm, Canon::LeftLowerLeg, Canon::RightLowerLeg].iter().any(|c| c.index() == j);
                (j, if limb { 1.5 } else { 1.0 })
            })
            .collect(),
        ..base.clone()
    });
    if let Ok(only) = std::env::var("FEATURES") {
        variants.retain(|v| only.split(',').any(|w| v.name.contains(w)));
    }

    let rho = Settings::default().rho;
    let retired: Vec<bool> = lib.segments().iter().map(|s| s.retired).collect();
    let sets: Vec<Vec<usize>> = (0..10).map(|o| (0..64).map(|i| (i * m) / 64 + o).filter(|&t| t < m).collect()).collect();
    let agree_targets: Vec<usize> = (0..192).map(|i| (i * m) / 192 + 3).filter(|&t| t < m).collect();

    for v in &variants {
        let t1 = std::time::Instant::now();
        let sigs: Vec<Signature> = normed.iter().map(|n| signature(n, v, &mean_pose)).collect();
        let sim: Vec<f32> = (0..m * m).map(|i| sigs[i / m].similarity(&sigs[i % m])).collect();
        let rank = percentiles(&sim, m, &(0..m).collect::<Vec<_>>());
        let agreement = agree_targets
            .iter()
            .map(|&t| {
                let others: Vec<usize> = (0..m).filter(|&c| c != t).collect();
                let a: Vec<f32> = others.iter().map(|&c| sim[t * m + c]).collect();
                let b: Vec<f32> = others.iter().map(|&c| -pd[t * m + c]).collect();
                spearman(&a, &b)
            })
            .sum::<f32>()
            / agree_targets.len() as f32;
        println!("== {} ==", v.name);
        println!("  agreement with the perceptual distance: Spearman {agreement:.3} (192 targets)");
        for pairs in [false, true] {
            let mut per_set = Vec::new();
            let (mut tune, mut held, mut fall) = ((0, 0), (0, 0), 0.0f32);
            for (o, targets) in sets.iter().enumerate() {
                let mut wins = 0;
                for &t in targets {
                    let inten = lib.segments()[t].intensity01;
                    let rel: Vec<f32> = (0..m).map(|c| relevance(inten, lib.segments()[c].intensity01)).collect();
                    let dist = |c: usize| pd[c * m + t];
                    let mut seed = 0x5DEE_CE66_Du64 ^ (t as u64 * 7919);
                    let g = run(&sim, &rank, m, &rel, &retired, rho, pairs, t, &dist, true, &mut seed);
                    let r: f32 = (0..DRAWS).map(|_| run(&sim, &rank, m, &rel, &retired, rho, pairs, t, &dist, false, &mut seed)[ROUNDS - 1]).sum::<f32>() / DRAWS as f32;
                    if g[ROUNDS - 1] < r {
                        wins += 1;
                    }
                    fall += (1.0 - g[ROUNDS - 1] / g[0].max(1e-9)) / (sets.len() * targets.len()) as f32;
                }
                per_set.push(wins);
                let slot = if o < 5 { &mut tune } else { &mut held };
                slot.0 += wins;
                slot.1 += targets.len();
            }
            let pct = |(w, n): (usize, usize)| 100.0 * w as f32 / n.max(1) as f32;
            println!(
                "  preference, {}: vs the mean of {DRAWS} random people: tuning sets (0–4) {}/{} ({:.1} %), held out (5–9) {}/{} ({:.1} %), all {}/{} ({:.1} %); per set {per_set:?}; mean fall {:.1} %",
                if pairs { "choice pairs (option)" } else { "max over L (spec, default)" },
                tune.0,
                tune.1,
                pct(tune),
                held.0,
                held.1,
                pct(held),
                tune.0 + held.0,
                tune.1 + held.1,
                pct((tune.0 + held.0, tune.1 + held.1)),
                100.0 * fall
            );
        }
        // Fig. 4 on the built-in moves alone (their own percentiles and intensities) and on the
        // real library.
        let sub: Vec<usize> = (0..nb).collect();
        let sim_b: Vec<f32> = sub.iter().flat_map(|&a| sub.iter().map(move |&b| (a, b))).map(|(a, b)| sim[a * m + b]).collect();
        let rank_b = percentiles(&sim_b, nb, &sub.iter().map(|_| 0).enumerate().map(|(i, _)| i).collect::<Vec<_>>());
        let rel_b: Vec<f32> = builtin.segments().iter().map(|s| relevance(0.5, s.intensity01)).collect();
        let rel_all: Vec<f32> = lib.segments().iter().map(|s| relevance(0.5, s.intensity01)).collect();
        let twelve: Vec<usize> = (0..nb).step_by(nb / 12).take(12).collect();
        for (name, sim_x, rank_x, n, rel_x, targets, ret) in [
            ("built-in, choreo_feedback's 12 targets", &sim_b, &rank_b, nb, &rel_b, twelve.clone(), vec![false; nb]),
            ("built-in, every segment", &sim_b, &rank_b, nb, &rel_b, (0..nb).collect::<Vec<_>>(), vec![false; nb]),
            ("real library, every segment", &sim, &rank, m, &rel_all, (0..m).filter(|&t| !retired[t]).collect(), retired.clone()),
        ] {
            let div = fig4(sim_x, rank_x, n, rel_x, &ret, &targets);
            let slope = slope(&div);
            let rule = div[1] < div[0] && div[2] < div[0] && slope < 0.0;
            println!(
                "  Fig. 4, {name} ({}): eq. 9 per round {}; slope {slope:+.5}/round; strictly falling over rounds 1–3: {}; the rule (r2 < r1, r3 < r1, slope < 0): {}",
                targets.len(),
                div.iter().map(|d| format!("{d:.4}")).collect::<Vec<_>>().join(" "),
                div[1] < div[0] && div[2] < div[1],
                if rule { "holds" } else { "FAILS" }
            );
        }
        println!("  ({:.1} s)", t1.elapsed().as_secs_f32());
    }
}

/// A variant's signature of one segment (frames of §B-normalised canonical positions).
fn signature(n: &[Vec3], v: &Features, mean_pose: &[Vec3]) -> Signature {
    let frames = n.len() / CANON_COUNT;
    let dims = v.joints.len() * if v.velocity > 0.0 { 6 } else { 3 } + (v.offset > 0.0) as usize;
    let mut feats = Vec::new();
    for f in (0..frames).step_by(2) {
        for &(j, w) in &v.joints {
            let p = (n[f * CANON_COUNT + j] - if v.reference { mean_pose[j] } else { Vec3::ZERO }) * w;
            feats.extend_from_slice(&[p.x, p.y, p.z]);
        }
        if v.velocity > 0.0 {
            let (f0, f1) = (f.saturating_sub(2), (f + 2).min(frames - 1));
            for &(j, w) in &v.joints {
                let d = (n[f1 * CANON_COUNT + j] - n[f0 * CANON_COUNT + j]) * (w * v.velocity / ((f1 - f0).max(1) as f32 / 2.0));
                feats.extend_from_slice(&[d.x, d.y, d.z]);
            }
        }
        if v.offset > 0.0 {
            feats.push(v.offset);
        }
    }
    Signature::of_uncentred(&feats, dims, v.axes)
}

/// Per anchor row, as `feedback::similarity_percentiles`: the share of the others less similar
/// to the anchor (ties share a rank).
fn percentiles(sim: &[f32], m: usize, _ids: &[usize]) -> Vec<f32> {
    let mut out = vec![0.0f32; m * m];
    let scale = 1.0 / (m.max(2) - 1) as f32;
    for a in 0..m {
        let row = &sim[a * m..(a + 1) * m];
        let mut order: Vec<usize> = (0..m).collect();
        order.sort_by(|&i, &j| row[i].total_cmp(&row[j]));
        let mut below = 0;
        for (k, &c) in order.iter().enumerate() {
            if k > 0 && row[c] > row[order[k - 1]] {
                below = k;
            }
            out[a * m + c] = below as f32 * scale;
        }
    }
    out
}

/// Least-squares slope of `y` over its index.
fn slope(y: &[f32]) -> f32 {
    let n = y.len() as f32;
    let mx = (n - 1.0) / 2.0;
    let my = y.iter().sum::<f32>() / n;
    let (mut num, mut den) = (0.0, 0.0);
    for (i, &v) in y.iter().enumerate() {
        num += (i as f32 - mx) * (v - my);
        den += (i as f32 - mx) * (i as f32 - mx);
    }
    num / den
}

/// One round's 6 picks by eq. 1 with the product's Φ (module docs).
#[allow(clippy::too_many_arguments)]
fn pick_round(sim: &[f32], rank: &[f32], m: usize, rel: &[f32], is_shown: &mut [bool], shown: &mut Vec<usize>, liked: &[usize], rho: f32, tau: f32, pairs: bool) -> Vec<usize> {
    let mut min_d = vec![1.0f32; m];
    let upd = |min_d: &mut [f32], s: usize| {
        for c in 0..m {
            min_d[c] = min_d[c].min(1.0 - rank[s * m + c]);
        }
    };
    for &s in shown.iter().filter(|s| !liked.contains(s)) {
        upd(&mut min_d, s);
    }
    let mut like = vec![0.0f32; m];
    let passed: Vec<usize> = shown.iter().copied().filter(|s| !liked.contains(s)).collect();
    if !liked.is_empty() {
        if pairs && !passed.is_empty() {
            let n_pairs = (liked.len() * passed.len()) as f32;
            for c in 0..m {
                let mut agreed = 0;
                for &l in liked {
                    for &n in &passed {
                        if sim[c * m + l] > sim[c * m + n] {
                            agreed += 1;
                        }
                    }
                }
                like[c] = agreed as f32 / n_pairs;
            }
        } else {
            for &l in liked {
                for c in 0..m {
                    like[c] = like[c].max(rank[l * m + c]);
                }
            }
        }
    }
    let mut round = Vec::new();
    for _ in 0..PER {
        let mut best: Option<(f32, usize)> = None;
        for c in 0..m {
            if is_shown[c] {
                continue;
            }
            let phi = tau * min_d[c] + (1.0 - tau) * like[c];
            let s = rho * rel[c] + (1.0 - rho) * phi;
            if best.is_none_or(|(b, _)| s > b) {
                best = Some((s, c));
            }
        }
        let Some((_, p)) = best else { break };
        is_shown[p] = true;
        shown.push(p);
        round.push(p);
        upd(&mut min_d, p);
    }
    round
}

/// The §J preference run for one hidden target: the best shown distance per round.
#[allow(clippy::too_many_arguments)]
fn run(sim: &[f32], rank: &[f32], m: usize, rel: &[f32], retired: &[bool], rho: f32, pairs: bool, target: usize, dist: &dyn Fn(usize) -> f32, guided: bool, seed: &mut u64) -> Vec<f32> {
    let mut is_shown = retired.to_vec();
    let (mut shown, mut liked) = (Vec::new(), Vec::new());
    let mut tau = 1.0f32;
    let mut best = f32::INFINITY;
    let mut out = Vec::new();
    for r in 0..ROUNDS {
        let round = pick_round(sim, rank, m, rel, &mut is_shown, &mut shown, &liked, rho, tau, pairs);
        let scored: Vec<(f32, usize)> = round.iter().filter(|&&c| c != target).map(|&c| (dist(c), c)).collect();
        best = scored.iter().map(|s| s.0).fold(best, f32::min);
        out.push(best);
        if r + 1 == ROUNDS {
            break;
        }
        let picks = simulated_likes(scored, guided, LIKES, seed);
        let new = picks.iter().filter(|p| !liked.contains(*p)).count();
        liked.extend(picks);
        tau *= (19.0f32 / 20.0).powi(new.max(1) as i32);
    }
    out
}

/// `choreo_feedback`'s Fig. 4 simulation: per target, like the shown candidate with the lowest
/// raw D to it, 6 rounds at ρ 0.3; the mean over targets of eq. 9 (raw D) per round.
fn fig4(sim: &[f32], rank: &[f32], m: usize, rel: &[f32], retired: &[bool], targets: &[usize]) -> Vec<f32> {
    let rounds = 6;
    let mut div = vec![0.0f32; rounds];
    for &t in targets {
        let mut is_shown = retired.to_vec();
        let (mut shown, mut liked) = (Vec::new(), Vec::new());
        let mut tau = 1.0f32;
        for r in 0..rounds {
            let round = pick_round(sim, rank, m, rel, &mut is_shown, &mut shown, &liked, 0.3, tau, false);
            let mut sum = 0.0;
            let mut n = 0;
            for i in 0..round.len() {
                for j in i + 1..round.len() {
                    sum += 1.0 - sim[round[i] * m + round[j]];
                    n += 1;
                }
            }
            div[r] += sum / n.max(1) as f32 / targets.len() as f32;
            let like = *round.iter().min_by(|&&a, &&b| (1.0 - sim[a * m + t]).total_cmp(&(1.0 - sim[b * m + t])).then(a.cmp(&b))).unwrap();
            if !liked.contains(&like) {
                liked.push(like);
            }
            tau *= 19.0 / 20.0;
        }
    }
    div
}
