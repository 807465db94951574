//! The README's choreography claims checked against controls (issue 17): the built-in library
//! holds exactly 558 moves (420 in 4, 90 in 3, 48 in 4 held on the counts) that differ in motion (not only in name); relevance feedback ends
//! closer to what the person likes than the same rounds with likes at random; the default
//! filling (repeat window 4, charged heuristically along chosen paths) against an exhaustive
//! search of the full objective on small cases.

use odori_core::choreo::{fill, path_cost, FeedbackSession, FillWeights, Layer, SegmentLibrary, TransitionTable, CANDIDATES_PER_ROUND};
use odori_core::canon::humanoid::Canon;
use odori_core::library::{builtin_clips, builtin_moves};

/// SplitMix64.
struct Rng(u64);
impl Rng {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    fn f32(&mut self) -> f32 {
        (self.next() >> 40) as f32 / (1u64 << 24) as f32
    }
    fn below(&mut self, n: usize) -> usize {
        (self.next() % n as u64) as usize
    }
}

#[test]
fn exactly_558_builtin_moves_each_moving_differently() {
    let moves = builtin_moves();
    let clips = builtin_clips();
    assert_eq!((moves.len(), clips.len(), SegmentLibrary::builtin().len()), (558, 558, 558), "the README says 558 built-in moves");
    assert_eq!(moves.iter().filter(|m| m.counts() == 3).count(), 90, "the README says 90 of them in 3");
    assert_eq!(moves.iter().filter(|m| m.step.on_counts()).count(), 48, "the README says 48 held on the counts");
    // Each move as its joints' positions relative to the root at 16 moments of the bar.
    let feats: Vec<Vec<glam::Vec3>> = clips
        .iter()
        .map(|c| {
            let n = c.frame_count() - 1;
            (0..16)
                .flat_map(|k| {
                    let p = c.world_positions(k * n / 16);
                    let root = p[0];
                    p.into_iter().map(move |v| v - root)
                })
                .collect()
        })
        .collect();
    let dist = |a: &[glam::Vec3], b: &[glam::Vec3]| a.iter().zip(b).map(|(x, y)| (*x - *y).length()).sum::<f32>() / a.len() as f32;
    let mut nearest = (f32::MAX, 0, 0);
    let mut alike = Vec::new();
    for i in 0..feats.len() {
        for j in i + 1..feats.len() {
            let d = dist(&feats[i], &feats[j]);
            if d < nearest.0 {
                nearest = (d, i, j);
            }
            if d <= 0.01 {
                alike.push(format!("{} = {} ({:.4} m)", clips[i].name, clips[j].name, d));
            }
        }
    }
    println!("closest two built-in moves: {} and {}, mean joint distance {:.4} m", clips[nearest.1].name, clips[nearest.2].name, nearest.0);
    // The same motion: less than 1 mm of mean joint distance over the bar. The only pairs
    // allowed are mirror twins (same step, arms, energy, other side) of a move that is itself
    // left/right symmetric (equal to its own mirror image, measured here: x negated, left and
    // right joints swapped): the README's 558 counts those twice (a finding of issue 17, see
    // tests/README.md). Any other duplicate fails, a broken mirroring included.
    let names: Vec<&str> = Canon::ALL.iter().map(|c| c.name()).collect();
    let partner: Vec<usize> = names
        .iter()
        .map(|n| {
            let swapped = if let Some(r) = n.strip_prefix("left") { format!("right{r}") } else if let Some(r) = n.strip_prefix("right") { format!("left{r}") } else { n.to_string() };
            names.iter().position(|m| *m == swapped).unwrap_or_else(|| panic!("no partner for {n}"))
        })
        .collect();
    let joints = Canon::ALL.len();
    let mirror = |f: &[glam::Vec3]| -> Vec<glam::Vec3> {
        f.chunks(joints).flat_map(|frame| (0..joints).map(|j| frame[partner[j]] * glam::Vec3::new(-1.0, 1.0, 1.0)).collect::<Vec<_>>()).collect()
    };
    let same: Vec<(usize, usize)> = (0..feats.len()).flat_map(|i| (i + 1..feats.len()).map(move |j| (i, j))).filter(|&(i, j)| dist(&feats[i], &feats[j]) < 0.001).collect();
    for &(i, j) in &same {
        let (a, b) = (&moves[i], &moves[j]);
        let twins = a.step == b.step && a.arms == b.arms && a.energy == b.energy && a.mirrored != b.mirrored;
        let symmetric = dist(&feats[i], &mirror(&feats[i])) < 0.001;
        assert!(twins && symmetric, "{} and {} are the same motion (twins: {twins}, symmetric move: {symmetric})", clips[i].name, clips[j].name);
    }
    println!("distinct motions: {} of 558 ({} mirror twins of symmetric moves; {} pairs within 1 cm)", 558 - same.len(), same.len(), alike.len());
}

/// Mean over hidden targets of the least D(candidate, target) among the candidates shown after
/// `rounds` rounds, the person liking each round's candidate closest to the target, or (the
/// control) a candidate at random.
fn feedback_closeness(lib: &SegmentLibrary, targets: &[usize], rounds: usize, at_random: bool) -> f32 {
    let mut rng = Rng(17);
    let mut sum = 0.0;
    for &target in targets {
        let mut s = FeedbackSession::new();
        let mut round = s.next_round(lib, 0.5, 0.3, CANDIDATES_PER_ROUND).to_vec();
        for _ in 0..rounds {
            let liked = if at_random {
                round[rng.below(round.len())]
            } else {
                *round.iter().min_by(|&&a, &&b| lib.dissimilarity(a, target).total_cmp(&lib.dissimilarity(b, target)).then(a.cmp(&b))).unwrap()
            };
            round = s.search(lib, &[liked], 0.5, 0.3, CANDIDATES_PER_ROUND).to_vec();
        }
        // What the search offers after those rounds: the closest of the 6 it shows next (the
        // person's own pick is left out, so only the search's answer to the likes is measured).
        sum += round.iter().map(|&c| lib.dissimilarity(c, target)).fold(f32::MAX, f32::min);
    }
    sum / targets.len() as f32
}

#[test]
fn feedback_gets_closer_to_what_is_liked_than_random_likes() {
    // "first variety, then more like what you liked": after 10 rounds (τ = 0.6) the person who
    // likes what is closest to the move they have in mind is closer to it than the control.
    let lib = SegmentLibrary::builtin();
    let targets: Vec<usize> = (0..lib.len()).step_by(lib.len() / 20).take(20).collect();
    let guided = feedback_closeness(&lib, &targets, 10, false);
    let control = feedback_closeness(&lib, &targets, 10, true);
    println!("after 10 rounds, mean D(closest candidate shown next, target): guided {guided:.4}, random likes {control:.4}");
    assert!(guided < control, "liking what is close to the target ends no closer ({guided}) than liking at random ({control})");
}

/// The full objective of the default filling, written here from the README and the module
/// documentation (not from `path_cost`): transition costs, the music term per open bar, and
/// the repeat penalty on an open bar repeating a segment used 2..=window bars before.
fn objective(table: &TransitionTable, layers: &[Layer], inten: &[f32], w: &FillWeights, path: &[usize]) -> f32 {
    let mut cost = 0.0;
    for (t, l) in layers.iter().enumerate() {
        if let Layer::Open { intensity } = l {
            cost += w.music_weight * (intensity - inten[path[t]]).abs();
            if (2..=w.repeat_window).any(|d| t >= d && path[t - d] == path[t]) {
                cost += w.repeat_penalty;
            }
        }
        if t > 0 {
            cost += table.cost(path[t - 1], path[t]);
        }
    }
    cost
}

/// The exact minimum of [`objective`] over every path (pinned bars fixed).
fn exhaustive(table: &TransitionTable, layers: &[Layer], inten: &[f32], w: &FillWeights) -> f32 {
    let m = table.len();
    let open: Vec<usize> = layers.iter().enumerate().filter(|(_, l)| matches!(l, Layer::Open { .. })).map(|(i, _)| i).collect();
    let mut path: Vec<usize> = layers.iter().map(|l| if let Layer::Fixed { segment } = l { *segment } else { 0 }).collect();
    let mut best = f32::INFINITY;
    for code in 0..m.pow(open.len() as u32) {
        let mut c = code;
        for &i in &open {
            path[i] = c % m;
            c /= m;
        }
        best = best.min(objective(table, layers, inten, w, &path));
    }
    best
}

#[test]
fn default_filling_against_an_exhaustive_search_of_its_full_objective() {
    // The default repeat window (4) is charged along chosen paths, a heuristic (named as such
    // in the README and the fill module). Measured here on small random instances where the
    // window matters (few segments): the reported cost is the true objective of the returned
    // path, never below the exact optimum; the gap to the optimum is printed.
    let mut rng = Rng(4);
    let w = FillWeights::default();
    assert_eq!(w.repeat_window, 4, "the default this test is about");
    let (mut exact, mut gaps, mut worst, mut worse_than_blind, mut better_than_blind) = (0usize, Vec::new(), 0.0f32, 0usize, 0usize);
    let cases = 150;
    for case in 0..cases {
        let m = 4 + rng.below(4);
        let bars = 5 + rng.below(3);
        let costs: Vec<f32> = (0..m * m).map(|_| 0.2 + 2.0 * rng.f32()).collect();
        let table = TransitionTable::from_costs(m, costs);
        let inten: Vec<f32> = (0..m).map(|_| rng.f32()).collect();
        let layers: Vec<Layer> =
            (0..bars).map(|_| if rng.f32() < 0.2 { Layer::Fixed { segment: rng.below(m) } } else { Layer::Open { intensity: rng.f32() } }).collect();
        let (path, cost) = fill(&table, &layers, &inten, &w).unwrap();
        let truth = objective(&table, &layers, &inten, &w, &path);
        assert!((cost - truth).abs() < 1e-4, "case {case}: reported {cost}, objective of its path {truth}");
        assert!((path_cost(&table, &layers, &inten, &w, &path) - truth).abs() < 1e-4, "case {case}: path_cost disagrees with the objective");
        let best = exhaustive(&table, &layers, &inten, &w);
        let (blind, _) = fill(&table, &layers, &inten, &FillWeights { repeat_window: 1, ..w }).unwrap();
        let blind_cost = objective(&table, &layers, &inten, &w, &blind);
        if cost > blind_cost + 1e-4 {
            worse_than_blind += 1;
        }
        if cost < blind_cost - 1e-4 {
            better_than_blind += 1;
        }
        assert!(cost >= best - 1e-4, "case {case}: below the exhaustive optimum ({cost} < {best}): the exhaustive search is wrong");
        let gap = (cost - best) / best;
        if gap < 1e-5 {
            exact += 1;
        }
        worst = worst.max(gap);
        gaps.push(gap);
    }
    let mean = gaps.iter().sum::<f32>() / gaps.len() as f32;
    println!(
        "default filling (window 4) vs exhaustive: optimal in {exact} of {cases} cases, mean gap {:.2} %, worst {:.1} %; \
         vs the exact window-1 path (the control, blind to the window): better in {better_than_blind}, worse in {worse_than_blind}",
        mean * 100.0,
        worst * 100.0
    );
    // What the documentation claims for the heuristic: it steers away from repeats at no extra
    // cost, i.e. it never does worse on the full objective than ignoring the window, and it
    // does better where repeats matter. Optimality is not claimed (the gap above is a figure).
    assert_eq!(worse_than_blind, 0, "the window heuristic made {worse_than_blind} fillings worse than ignoring the window");
    assert!(better_than_blind > 0, "the window heuristic never improved on ignoring the window");
}
