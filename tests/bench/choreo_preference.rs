//! The preference test of spec §J for the relevance-feedback search (§F), measured on the
//! product's code path (`choreo::feedback`): a simulated person hides a target segment and,
//! each round, likes the 2 shown candidates closest to it by the perceptual distance
//! (`quality::perceptual_distance`: mean joint distance after time-normalising both to 32
//! frames and normalising as §B, not the eigen similarity the search uses). The control likes
//! 2 shown candidates at random. Library: the built-in moves plus the real salsa and Indian
//! clips; each set is 64 targets spread over the library, each hidden (showing it counts for
//! nothing); the bar's intensity is the target's; ρ and τ as the app's defaults. Sets: A (the
//! product's choices were tuned on it), B and C held out; `PREFERENCE_SETS=10` runs all ten
//! disjoint sets (offsets 0..10, the whole library) instead, for a steadier count. Prints per
//! set, per round, the mean distance of the best candidate shown so far and eq. 9's diversity
//! of the shown (which should fall), and at round 5 the fall from round 1 (goal ≥ 20 %) and
//! the share of targets where the guided person is closer than random likes (goal ≥ 75 %):
//! against the mean of 5 random people (the control's expected result), and against one
//! random person at a time (the median over the 5, with ties — the same best for both —
//! counted apart); then the totals over the sets. `PREFERENCE_DRAWS=n` (n > 5) also compares
//! with the mean of n random people, a steadier estimate of their expected result.
//! `PREFERENCE_LIKE=pairs` runs Φ's like term as the option [`LikeTerm::ChoicePairs`] instead of
//! the spec's max (the default), `PREFERENCE_LIKE=both` runs the two side by side. Also how
//! well the search's similarity agrees with the perceptual distance (Spearman's rank correlation over the library). Asserts
//! nothing. `cargo test -p odori-tests --bench choreo_preference` for a quick build.

use glam::Vec3;
use odori_core::choreo::quality::perceptual_distance;
use odori_core::choreo::{mean_pairwise_dissimilarity, FeedbackSession, LikeTerm, SegmentLibrary, SegmentOptions, Settings, CANDIDATES_PER_ROUND};
use odori_core::canon::humanoid::{canonical_positions, HumanoidMap, CANON_COUNT};
use odori_core::import::import_bytes;
use odori_core::ImportOptions;
use odori_tests::{all_bvh, fps_override_for, read, simulated_likes, spearman};

const TARGETS: usize = 64;
const ROUNDS: usize = 5;
const LIKES: usize = 2;

/// The figures of one run.
pub struct Figures {
    pub targets: usize,
    pub segments: usize,
    /// Mean over targets of Spearman's ρ between Sim(target, ·) and −perceptual distance.
    pub agreement: f32,
    /// Mean best-shown distance per round, guided and random likes.
    pub guided_curve: Vec<f32>,
    pub random_curve: Vec<f32>,
    /// Mean over targets of the guided best distance's fall from round 1 to round 5.
    pub mean_fall: f32,
    /// Targets where guided likes end closer than random ones (one random person), equal, and
    /// farther.
    pub wins: usize,
    pub ties: usize,
    pub losses: usize,
    /// Targets where guided likes end closer than the mean of [`RANDOM_DRAWS`] random people
    /// (the random person's expected result, not one lucky or unlucky draw).
    pub wins_vs_mean: usize,
    /// Over the [`RANDOM_DRAWS`] random people taken one at a time: the median of the targets
    /// where guided likes end closer than that person, and the median of the ties.
    pub wins_median: usize,
    pub ties_median: usize,
    /// With `PREFERENCE_DRAWS=n` (n > 5): targets where guided likes end closer than the mean
    /// of n random people (a steadier estimate of the random person's expected result); else 0.
    pub wins_vs_many: usize,
    pub many_draws: usize,
    /// Mean over targets of eq. 9 (mean pairwise raw kWAS D of the 6 shown) per round, guided:
    /// §F's check that the shown set narrows.
    pub diversity: Vec<f32>,
}

/// Random people per target for [`Figures::wins_vs_mean`].
pub const RANDOM_DRAWS: usize = 5;

/// The target sets: A (the one the product's choices were tuned on), then B and C, held out; each 64 segments spread over the library, at offsets 3, 8 and 5.
pub const SETS: [(&str, usize); 3] = [("A (tuned on)", 3), ("B (held out)", 8), ("C (held out)", 5)];

#[allow(dead_code)]
fn main() {
    let rho = Settings::default().rho;
    let (lib, positions) = library();
    // `PREFERENCE_SETS=10`: every offset 0..10, ten disjoint sets (the whole library), for a
    // steadier count than three sets give.
    let sets: Vec<(String, usize)> = match std::env::var("PREFERENCE_SETS").ok().and_then(|v| v.parse::<usize>().ok()) {
        Some(n) => (0..n.min(10)).map(|o| (format!("offset {o}"), o)).collect(),
        None => SETS.iter().map(|&(n, o)| (n.to_string(), o)).collect(),
    };
    for like_term in like_terms() {
        println!("== Φ's like term: {} ==", like_term_name(like_term));
        let mut total = [0usize; 5];
        let mut fall_sum = 0.0f32;
        for (name, offset) in &sets {
            let f = measure_with(&lib, &positions, *offset, like_term);
            fall_sum += f.mean_fall;
            total[0] += f.targets;
            total[1] += f.wins_vs_mean;
            total[2] += f.wins_median;
            total[3] += f.ties_median;
            total[4] += f.wins_vs_many;
            println!("preference test (spec §J), set {name}, {} targets, {} segments, {LIKES} likes per round, ρ {rho}:", f.targets, f.segments);
            print_figures(&f);
        }
        println!(
            "all sets: guided closer than the mean of {RANDOM_DRAWS} random people on {}/{} ({:.1} %); than one random person (median per set) on {} ({:.1} %), equal on {}",
            total[1],
            total[0],
            100.0 * total[1] as f32 / total[0].max(1) as f32,
            total[2],
            100.0 * total[2] as f32 / total[0].max(1) as f32,
            total[3]
        );
        if let Some(n) = many_draws() {
            println!("all sets: guided closer than the mean of {n} random people on {}/{} ({:.1} %)", total[4], total[0], 100.0 * total[4] as f32 / total[0].max(1) as f32);
        }
        println!("all sets: mean fall of the guided best distance, round 1 → 5: {:.1} %", 100.0 * fall_sum / sets.len().max(1) as f32);
    }
}

/// `PREFERENCE_LIKE`: `max` (the spec's rule, the default), `pairs` (the option), or `both`
/// (side by side).
fn like_terms() -> Vec<LikeTerm> {
    match std::env::var("PREFERENCE_LIKE").as_deref() {
        Ok("pairs") => vec![LikeTerm::ChoicePairs],
        Ok("both") => vec![LikeTerm::MaxSimilarity, LikeTerm::ChoicePairs],
        _ => vec![LikeTerm::MaxSimilarity],
    }
}

fn like_term_name(t: LikeTerm) -> &'static str {
    match t {
        LikeTerm::MaxSimilarity => "max over L of Sim (spec §F, default)",
        LikeTerm::ChoicePairs => "share of (liked, passed-over) pairs (option)",
    }
}

/// `PREFERENCE_DRAWS`, when above [`RANDOM_DRAWS`].
fn many_draws() -> Option<usize> {
    std::env::var("PREFERENCE_DRAWS").ok().and_then(|v| v.parse::<usize>().ok()).filter(|&n| n > RANDOM_DRAWS)
}

fn print_figures(f: &Figures) {
    println!("  agreement of the search's Sim with the perceptual distance: Spearman {:.3} (mean over the targets)", f.agreement);
    println!("  round:                 {}", (1..=ROUNDS).map(|r| format!("{r:>7}")).collect::<String>());
    println!("  best shown, guided:    {}", f.guided_curve.iter().map(|v| format!("{v:>7.4}")).collect::<String>());
    println!("  best shown, random:    {}", f.random_curve.iter().map(|v| format!("{v:>7.4}")).collect::<String>());
    println!("  eq. 9 diversity, guided: {}", f.diversity.iter().map(|v| format!("{v:>7.4}")).collect::<String>());
    println!(
        "  guided closer than the mean of {RANDOM_DRAWS} random people on {}/{} targets ({:.0} %, goal ≥ 75 %)",
        f.wins_vs_mean,
        f.targets,
        100.0 * f.wins_vs_mean as f32 / f.targets.max(1) as f32
    );
    if f.many_draws > 0 {
        println!("  guided closer than the mean of {} random people on {}/{} targets ({:.0} %)", f.many_draws, f.wins_vs_many, f.targets, 100.0 * f.wins_vs_many as f32 / f.targets.max(1) as f32);
    }
    println!(
        "  guided closer than one random person: median over {RANDOM_DRAWS} people {}/{} ({:.0} %), equal on {} (median)",
        f.wins_median,
        f.targets,
        100.0 * f.wins_median as f32 / f.targets.max(1) as f32,
        f.ties_median
    );
    println!(
        "  round 5 vs round 1 (guided): mean fall {:.1} % (goal ≥ 20 %), fall of the mean {:.1} %; guided closer than the first random person on {}/{} targets ({:.0} %), equal on {}, farther on {}",
        100.0 * f.mean_fall,
        100.0 * (1.0 - f.guided_curve[ROUNDS - 1] / f.guided_curve[0].max(1e-9)),
        f.wins,
        f.targets,
        100.0 * f.wins as f32 / f.targets.max(1) as f32,
        f.ties,
        f.losses
    );
}

/// Runs the preference test on the real library, set A.
#[allow(dead_code)]
pub fn measure() -> Figures {
    let (lib, positions) = library();
    measure_on(&lib, &positions, SETS[0].1)
}

/// The real library (built-in moves + the CMU salsa and Indian clips) and each segment's
/// canonical positions.
pub fn library() -> (SegmentLibrary, Vec<Vec<Vec3>>) {
    let mut lib = SegmentLibrary::builtin();
    for rel in all_bvh().into_iter().filter(|r| r.contains("cmu-salsa") || r.contains("cmu-indian")) {
        let opts = ImportOptions { fps_override: fps_override_for(&rel), ..Default::default() };
        let imp = import_bytes(&rel, &read(&rel), &opts).unwrap_or_else(|e| panic!("{rel}: {e}"));
        for clip in &imp.clips {
            lib.add_clip(clip, &imp.humanoid, &imp.status, &SegmentOptions::default()).unwrap_or_else(|e| panic!("{rel}: {e}"));
        }
    }
    // Canonical positions of every segment's frames.
    let clip_pos: Vec<Vec<Vec3>> = lib.clips().iter().map(|c| canonical_positions(&c.clip, &HumanoidMap::from_skeleton(&c.clip.skeleton))).collect();
    let seg_pos = |s: usize| -> Vec<Vec3> {
        let seg = &lib.segments()[s];
        let p = &clip_pos[seg.clip];
        let frames = p.len() / CANON_COUNT;
        let (a, b) = (seg.start_frame.round() as usize, (seg.end_frame.round() as usize).min(frames.saturating_sub(1)));
        p[a * CANON_COUNT..(b + 1) * CANON_COUNT].to_vec()
    };
    let positions: Vec<Vec<Vec3>> = (0..lib.len()).map(seg_pos).collect();
    (lib, positions)
}

/// The preference test on 64 targets spread over the library, from segment `offset` on, with
/// the product's default like term.
pub fn measure_on(lib: &SegmentLibrary, positions: &[Vec<Vec3>], offset: usize) -> Figures {
    measure_with(lib, positions, offset, LikeTerm::default())
}

/// [`measure_on`] with Φ's like term `like_term`.
pub fn measure_with(lib: &SegmentLibrary, positions: &[Vec<Vec3>], offset: usize, like_term: LikeTerm) -> Figures {
    let dist = |a: usize, b: usize| perceptual_distance(&positions[a], &positions[b]).unwrap_or(f32::INFINITY);
    let settings = Settings::default();
    let targets: Vec<usize> = (0..TARGETS).map(|i| (i * lib.len()) / TARGETS + offset).filter(|&t| t < lib.len()).collect();
    let mut guided_curve = vec![0.0f32; ROUNDS];
    let mut random_curve = vec![0.0f32; ROUNDS];
    let mut diversity = vec![0.0f32; ROUNDS];
    let (mut falls, mut wins, mut ties, mut losses, mut wins_vs_mean) = (Vec::new(), 0, 0, 0, 0);
    let (mut wins_each, mut ties_each) = ([0usize; RANDOM_DRAWS], [0usize; RANDOM_DRAWS]);
    let mut wins_vs_many = 0;
    let mut z = 0x9E37_79B9_7F4A_7C15u64;
    // The first random person of every target draws from `x` (as before the extra draws were
    // added, so the one-person count stays comparable); the others from `y`.
    let mut x = 0x5DEE_CE66_Du64;
    let mut y = 0x2545_F491_4F6C_DD1Du64;
    for &t in &targets {
        let intensity = lib.segments()[t].intensity01;
        let best_at_round = |guided: bool, x: &mut u64, diversity: &mut [f32]| -> Vec<f32> {
            let mut session = FeedbackSession::with_like_term(like_term);
            let mut round: Vec<usize> = session.next_round(lib, intensity, settings.rho, CANDIDATES_PER_ROUND).to_vec();
            let mut best = f32::INFINITY;
            let mut out = Vec::new();
            for r in 0..ROUNDS {
                if guided {
                    diversity[r] += mean_pairwise_dissimilarity(lib, &round) / targets.len() as f32;
                }
                // The target is hidden: the person has it in mind, it is not in the library they
                // see, so showing it counts for nothing (otherwise ρ's intensity match, with the
                // bar at the target's own intensity, finds it in the first round and every run
                // ties at distance 0).
                let scored: Vec<(f32, usize)> = round.iter().filter(|&&c| c != t).map(|&c| (dist(c, t), c)).collect();
                best = scored.iter().map(|s| s.0).fold(best, f32::min);
                out.push(best);
                if r + 1 == ROUNDS {
                    break;
                }
                let liked = simulated_likes(scored, guided, LIKES, x);
                round = session.search(lib, &liked, intensity, settings.rho, CANDIDATES_PER_ROUND).to_vec();
            }
            out
        };
        let g = best_at_round(true, &mut x, &mut diversity);
        let r = best_at_round(false, &mut x, &mut []);
        let mut finals = vec![r[ROUNDS - 1]];
        for _ in 1..RANDOM_DRAWS {
            finals.push(best_at_round(false, &mut y, &mut [])[ROUNDS - 1]);
        }
        let random_final: f32 = finals.iter().sum();
        for (d, &fd) in finals.iter().enumerate() {
            if g[ROUNDS - 1] < fd {
                wins_each[d] += 1;
            } else if g[ROUNDS - 1] == fd {
                ties_each[d] += 1;
            }
        }
        if let Some(n) = many_draws() {
            let mut sum = random_final;
            for _ in RANDOM_DRAWS..n {
                sum += best_at_round(false, &mut z, &mut [])[ROUNDS - 1];
            }
            if g[ROUNDS - 1] < sum / n as f32 {
                wins_vs_many += 1;
            }
        }
        if g[ROUNDS - 1] < random_final / RANDOM_DRAWS as f32 {
            wins_vs_mean += 1;
        }
        for k in 0..ROUNDS {
            guided_curve[k] += g[k] / targets.len() as f32;
            random_curve[k] += r[k] / targets.len() as f32;
        }
        falls.push(1.0 - g[ROUNDS - 1] / g[0].max(1e-9));
        if g[ROUNDS - 1] < r[ROUNDS - 1] {
            wins += 1;
        } else if g[ROUNDS - 1] == r[ROUNDS - 1] {
            ties += 1;
        } else {
            losses += 1;
        }
    }
    // How well the similarity the search uses agrees with the perceptual distance: per target,
    // Spearman's rank correlation of Sim(target, c) with −distance(target, c) over every other
    // segment c, averaged.
    let agreement = targets.iter().map(|&t| {
        let others: Vec<usize> = (0..lib.len()).filter(|&c| c != t).collect();
        let sim: Vec<f32> = others.iter().map(|&c| lib.similarity(t, c)).collect();
        let near: Vec<f32> = others.iter().map(|&c| -dist(t, c)).collect();
        spearman(&sim, &near)
    }).sum::<f32>() / targets.len() as f32;
    let mean_fall = falls.iter().sum::<f32>() / falls.len().max(1) as f32;
    wins_each.sort_unstable();
    ties_each.sort_unstable();
    let (wins_median, ties_median) = (wins_each[RANDOM_DRAWS / 2], ties_each[RANDOM_DRAWS / 2]);
    Figures { targets: targets.len(), segments: lib.len(), agreement, guided_curve, random_curve, mean_fall, wins, ties, losses, wins_vs_mean, wins_median, ties_median, wins_vs_many, many_draws: many_draws().unwrap_or(0), diversity }
}
