//! The person's moves first (issue 26 item 1, spec §G and §J): with the library of a person who
//! imported every humanoid dance clip in ../shared/data/mocap (CMU salsa, Indian, modern dance
//! without its walk 005_01; not the martial-arts negatives) and RobotExpressive's Dance, Generate
//! at **default settings** (the default moves source is *my moves*), on every song in
//! ../shared/data/music, the drum take and demo pieces in 4/4 and 3/4 (none tuned on), with the
//! core's own grid, takes at least half its bars from imported clips and keeps the beat and join
//! goals: BAS-music ≥ random moves' + 0.05 (the mean of at least 5 random dances on the same
//! bars, 100 bars in all, each bar drawn from the dance's own pool: imported where the dance took
//! an imported move, built-in where built-in; the whole library's random is printed beside it and
//! held to [`KNOWN_UNDER_WHOLE_LIBRARY_RANDOM`]) and ≥ the same dance on the half-shifted beats + 0.10, kinetic beats per
//! count in 0.8–1.2 or 0.4–0.6, join jump ≤ 1.5 measured on the rendered (blended, feet-held)
//! dance, foot skate no more than its sources' (each bar's source clip at the bar's pace, §N).
//! The same with half the clips held out (every other file of the sorted list), so the rule is
//! not fitted to one set of files. Known misses are listed in [`KNOWN_MISSES`] with the figure
//! that misses, and asserted to be the only ones. Each dance is printed beside two others made
//! in the same run: session 13's rule ("control") and the table's cost with the predicted
//! blended jump ("term on", `JumpTerm::MEASURED`, off by default). Figures per song are also printed by
//! `tests/bench/choreo_person.rs`. `ODORI_ONLY=a|b` keeps the songs whose label contains a or b,
//! `ODORI_LIBS=all,half 0` the libraries named; the goals are then printed, not asserted.

#[path = "person_common.rs"]
mod person_common;

use odori_core::bars::Bar;
use odori_core::choreo::quality::{dance_quality, dance_quality_switched, DanceQuality};
use odori_core::choreo::{bar_counts, count_rate_bpm, skate_goal_cm_per_s, GenerateOptions, JumpTerm, RenderOptions, SegmentLibrary};
use odori_core::music::{analyze, AnalysisOptions, RmsEnvelope};


/// (library, song label substring, goal) pairs known to miss, each with why; every other goal
/// on every song must hold, and each listed one is reported when it starts to hold.
/// Measured 2026-11-29 after the session's merge (inertialized joins, *my moves* with the beat
/// term ×10, the one foot-contact rule, the cut on steps off by default): the full library
/// meets every goal on 8 of 10 pieces, half 0 on 9 of 10, half 1 (346 imported segments) on 4 of
/// 10 — its dances beat random moves by less than 0.05 on four pieces. Then (s13) the join
/// repair opens the bar of an imported move that misses the join goal to built-in moves (the
/// preference order): half 0's Let's Go Fishin' joins at 1.50 (was 1.56; 43 of 48 bars
/// imported). The 150 BPM piece in 3 still joins at 1.92 as rendered with feet held (the repair
/// measures the dance unheld). Met since the held feet's landing fix (s13-mends): half 1's 150
/// BPM piece in 3, skate 84.8 against its sources' 85.0 cm/s (was 87.3).
/// Then (s14) the preference order (`generate::order_stage`: a bar takes a built-in move only
/// where the imported moves tried there miss its counts or its join as played) and the join
/// repair measuring the dance as played (feet held), against the control in the same run
/// (session 13's rule, printed on each song's "control" line): the 150 BPM piece in 3 joins at
/// 1.42 (control 1.92); half 1's four pieces under random + 0.05 were bars landing between the
/// counts (the dance's BAS-music on the half-shifted beats 0.26–0.33), which the order finds and
/// gives another imported move or, where none tried lands, a built-in one: Vibe Ace 0.874
/// against random 0.689 (control 0.720), Sugar Plum 0.763 against 0.671 (0.709; 4 bars
/// built-in), the drum take 0.787 against 0.713 (0.707), the 90→130 BPM piece 0.823 against
/// 0.695 (0.736); every dance ≥ 90 % imported. New: half 1's 108 BPM piece in 3 joins at 1.58
/// as played (control 1.46): as played its dance before the repair joins at 3.59 (unheld the
/// control's repair saw less and refilled differently), and 16 refills reach 1.58. Then the
/// order keeps a refill only if the feet slide no more than before it, or still less than the
/// source clips' both paced and unpaced (it had let the demo pieces in 3 at 150 and 96→120
/// BPM of `choreo_beats` slide 34.8 → 49.6 and 30.1 → 38.8 cm/s, past their sources' 36.2):
/// half 1's 90→130 BPM piece is back under random + 0.05 (0.736 against 0.695, as the
/// control; its 0.823 refill slid more).
/// Session 16: each dance is also made on the table with the predicted blended jump
/// (`JumpTerm::MEASURED`, printed on its "term on" line); the term stays off by default
/// (`docs/benchmarks-notes-choreo.md`, session 16: with it and the join repair's skate cap, half
/// 1's 108 BPM piece in 3 joined at 1.48, but half 1's Sugar Plum fell to 0.718 against random
/// 0.671 + 0.05).
/// Session 18 (after session 17's stage 5, which left these four as they were): stage 2's
/// beat-rate ladder now reaches as far beside the scaled beat term as it did beside the default
/// one (`beat_rate_ladder_for`): half 1's Let's Go Fishin' at 1.20 kinetic beats a count
/// (BAS-music 0.768 against random 0.690, join 1.19, skate 24.1 against 29.4), where all 12
/// plain weights left stage 1's 1.28; no other dance here changed. The three left, stage by
/// stage (`docs/benchmarks-notes-choreo.md`, 2026-11-30). Then stage 4 prefers a skate refill
/// that lands no more bars off their counts as played than the dance entering it, or keeps its
/// BAS-music as played (§J's floor): half 1's 90→130 BPM piece 0.797 against random 0.695 (was 0.736; skate 19.9
/// against 30.2), off this list.
/// Session 19 (`docs/benchmarks-notes-choreo.md`, 2026-11-30, "the last two misses"): stage 4,
/// when its ladder reaches no dance within the goal and the dance as played slides past its
/// sources' at the bars' pace, bars the moves of the bars that slide past their own source
/// clip's skate as played and refills (`generate/skate.rs`): the trumpet loop's one bar skates
/// 16.0 against its sources' 25.4 cm/s (was 53.4 against 37.7; BAS-music 0.857, random 0.562,
/// half-shifted 0.020). Stage 5, when its refills end over the join goal, runs again charging
/// stage 4's skate weight from its first refill: half 1's 108 BPM piece in 3 joins at 1.46 (was
/// 1.58; BAS-music 0.735, random 0.525, skate 23.2 against 31.4). Every goal is met on all 30
/// dances; the list is empty, and a miss must be listed with its figure and why.
const KNOWN_MISSES: &[(&str, &str, &str, &str)] = &[];

/// Dances under the whole library's random moves + 0.05 (the control before session 26), with
/// the shortfall each may reach: (library, song label substring, ceiling). Session 26 added 48
/// built-in moves held on the counts, which land on the beat by construction; the whole
/// library's random dances draw them too and rose by 0.01–0.05 on every piece in 4, while these
/// four dances are main's dances, move for move (the moves held on the counts no longer set the
/// intensity scale: `SegmentLibrary::rescale`), but half 1's Let's Go Fishin', whose dance took
/// one of the new moves (0.752 against main's 0.768). The asserted control is now the dance's
/// own pool ([`random_bas_same_pool`]); this one is printed on every line and held to this list:
/// an unlisted miss fails, so does a listed one past its ceiling or one that meets the goal.
/// Half 1's demo in 4 at 100 BPM came off the list in session 32, when the core's sines and
/// exponentials became libm's in every build (the bits the wasm app ships): its dance is another
/// (BAS-music 0.785, 0.019 over the whole library's random + 0.05). Half 1's Let's Go Fishin'
/// came off it in session 33, when stages 4b and 5 began screening refills by measures near
/// their changes (`GenerateOptions::windowed_measures`): its dance is another (BAS-music 0.760,
/// 0.005 over).
const KNOWN_UNDER_WHOLE_LIBRARY_RANDOM: &[(&str, &str, f32)] = &[
    ("half 1", "Sugar_Plum", 0.05),
    ("half 1", "funk-groove1_138", 0.01),
];

/// The person's files: every humanoid dance clip and RobotExpressive's Dance; `half` keeps
/// every other one of the sorted list (`Some(0)` or `Some(1)`).
/// (The shared loader: `person_common.rs`.)
fn person_library(half: Option<usize>) -> (SegmentLibrary, usize) {
    person_common::person_library(half)
}

fn songs() -> Vec<(String, RmsEnvelope)> {
    person_common::songs()
}

fn quality(lib: &SegmentLibrary, bars: &[Bar], beats: &[f32], choices: &[Option<usize>]) -> DanceQuality {
    let (clip, switches) = odori_core::choreo::render_switched(lib, bars, choices, &RenderOptions::default());
    dance_quality_switched(&clip, bars, beats, &switches).expect("dance quality")
}

/// BAS-music of random dances on the same bars (each bar's own count; a fixed generator): the
/// control of `choreo_takes` and the `choreo_person` bench (to be shared from tests/support.rs).
fn random_bas(lib: &SegmentLibrary, bars: &[Bar], beats: &[f32]) -> f32 {
    let live: Vec<Vec<usize>> = bar_counts(lib, bars).iter().map(|&n| lib.segments().iter().filter(|s| !s.retired && (n == 0 || s.counts() == n)).map(|s| s.index).collect()).collect();
    let draws = 5usize.max(100usize.div_ceil(bars.len().max(1)));
    let mut x = 0x9E37_79B9_7F4A_7C15u64;
    let mut sum = 0.0;
    for _ in 0..draws {
        let ch: Vec<Option<usize>> = (0..bars.len())
            .map(|b| {
                x = x.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
                Some(live[b][(x >> 33) as usize % live[b].len()])
            })
            .collect();
        sum += quality(lib, bars, beats, &ch).beats.bas_music;
    }
    sum / draws as f32
}

/// Each bar's own source clip's foot skate at the bar's pace, averaged over the bars (§N).
/// BAS-music of random dances drawn from the dance's own pool, bar by bar: where the dance took
/// an imported move, a random imported move of the bar's count; where it took a built-in move, a
/// random built-in one (the same generator and number of draws as [`random_bas`]). Under *my
/// moves* the preference order decides which kind a bar takes; this control asks whether the
/// choice within that kind, and its placement, beat chance.
fn random_bas_same_pool(lib: &SegmentLibrary, bars: &[Bar], beats: &[f32], chosen: &[Option<usize>]) -> f32 {
    let counts = bar_counts(lib, bars);
    let live: Vec<Vec<usize>> = (0..bars.len())
        .map(|b| {
            let builtin = chosen[b].is_some_and(|s| lib.segments()[s].builtin.is_some());
            let n = counts[b];
            lib.segments().iter().filter(|s| !s.retired && (n == 0 || s.counts() == n) && s.builtin.is_some() == builtin).map(|s| s.index).collect()
        })
        .collect();
    let draws = 5usize.max(100usize.div_ceil(bars.len().max(1)));
    let mut x = 0x9E37_79B9_7F4A_7C15u64;
    let mut sum = 0.0;
    for _ in 0..draws {
        let ch: Vec<Option<usize>> = (0..bars.len())
            .map(|b| {
                x = x.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
                Some(live[b][(x >> 33) as usize % live[b].len()])
            })
            .collect();
        sum += quality(lib, bars, beats, &ch).beats.bas_music;
    }
    sum / draws as f32
}

fn paced_source_skate(lib: &SegmentLibrary, bars: &[Bar], chosen: &[Option<usize>]) -> f32 {
    let v: Vec<f32> = chosen
        .iter()
        .enumerate()
        .filter_map(|(t, s)| {
            let seg = &lib.segments()[(*s)?];
            let rate = count_rate_bpm(seg.counts(), bars[t].duration_secs());
            Some(seg.clip_skate_cm_per_s * rate / seg.tempo_bpm.max(1e-3))
        })
        .collect();
    v.iter().sum::<f32>() / v.len().max(1) as f32
}

fn imported_share(lib: &SegmentLibrary, chosen: &[Option<usize>]) -> f32 {
    chosen.iter().flatten().filter(|&&s| lib.segments()[s].builtin.is_none()).count() as f32 / chosen.len().max(1) as f32
}

const GOALS: [&str; 6] = ["imported", "random", "shifted", "rate", "join", "skate"];

#[test]
fn my_moves_are_the_default_and_fill_half_the_bars_on_the_beat_with_smooth_joins() {
    let only = std::env::var("ODORI_ONLY").ok();
    let songs: Vec<_> = songs().into_iter().filter(|(l, _)| only.as_deref().is_none_or(|o| o.split('|').any(|o| l.contains(o)))).collect();
    let mut misses: Vec<(String, String, &str)> = Vec::new();
    let mut whole_library: Vec<String> = Vec::new();
    let libs = std::env::var("ODORI_LIBS").ok();
    for (name, half) in [("all", None), ("half 0", Some(0)), ("half 1", Some(1))] {
        if libs.as_deref().is_some_and(|l| !l.split(',').any(|l| l == name)) {
            continue;
        }
        let (lib, files) = person_library(half);
        let imported_segments = lib.segments().iter().filter(|s| s.builtin.is_none()).count();
        println!("library {name}: {files} files, {imported_segments} imported segments beside {} built-in", lib.len() - imported_segments);
        assert!(imported_segments > 100, "{name}: only {imported_segments} imported segments");
        for (label, env) in &songs {
            let grid = analyze(env, &AnalysisOptions::default()).unwrap_or_else(|e| panic!("{label}: {e}"));
            let (bars, beats) = (grid.bars.clone(), grid.beat_times_secs.clone());
            let random = random_bas(&lib, &bars, &beats);
            // The control, same run: session 13's rule (the source's charge alone keeps built-in
            // moves out of every bar an imported move of its count fits; the join repair
            // measures the dance unheld).
            let control = GenerateOptions { follow_order: false, measure_played: false, ..GenerateOptions::default() };
            let mut old = odori_tests::Dance::new(bars.clone());
            old.generate_with(&lib, &control).unwrap_or_else(|e| panic!("{label}: {e}"));
            let (old_chosen, old_share) = (old.segments(), imported_share(&lib, &old.segments()));
            let oq = quality(&lib, &bars, &beats, &old_chosen);
            println!(
                "{name:<6} {label:<44} control: imported {:>3.0} %, BAS-music {:.3} shifted {:.3}, join max {:.2}, skate {:.1} sources {:.1} cm/s",
                100.0 * old_share,
                oq.beats.bas_music,
                oq.beats.bas_music_shifted,
                oq.join_jump_max,
                oq.foot_skate.mean_cm_per_s,
                paced_source_skate(&lib, &bars, &old_chosen)
            );
            // The term-on comparison, same run: the table's cost with the predicted blended
            // jump (JumpTerm::MEASURED), every stage as the product's.
            let off_lib = person_common::with_table(&lib, &bars, JumpTerm::MEASURED);
            let mut off = odori_tests::Dance::new(bars.clone());
            off.generate(&off_lib).unwrap_or_else(|e| panic!("{label}: {e}"));
            let off_chosen = off.segments();
            let fq = quality(&lib, &bars, &beats, &off_chosen);
            let off_path: Vec<usize> = off_chosen.iter().flatten().copied().collect();
            println!(
                "{name:<6} {label:<44} term on: imported {:>3.0} %, BAS-music {:.3} shifted {:.3}, kb/count {:.2}, join max {:.2}, skate {:.1} sources {:.1} cm/s (stage goal {:.1})",
                100.0 * imported_share(&lib, &off_chosen),
                fq.beats.bas_music,
                fq.beats.bas_music_shifted,
                fq.beats.kinetic_beats_per_sec / fq.beats.music_beats_per_sec.max(1e-6),
                fq.join_jump_max,
                fq.foot_skate.mean_cm_per_s,
                paced_source_skate(&lib, &bars, &off_chosen),
                skate_goal_cm_per_s(&lib, &off_path)
            );
            let mut doc = odori_tests::Dance::new(bars.clone());
            let report = doc.generate(&lib).unwrap_or_else(|e| panic!("{label}: {e}"));
            let chosen = doc.segments();
            let imported = chosen.iter().flatten().filter(|&&s| lib.segments()[s].builtin.is_none()).count();
            let share = imported as f32 / bars.len().max(1) as f32;
            // Every built-in bar says why, and only built-in bars do.
            for (t, s) in chosen.iter().enumerate() {
                let builtin = s.is_some_and(|s| lib.segments()[s].builtin.is_some());
                assert_eq!(report.builtin_why.get(t).copied().flatten().is_some(), builtin, "{name} {label} bar {t}: built-in {builtin}, why {:?}", report.builtin_why.get(t));
            }
            let whys: Vec<String> = report.builtin_why.iter().enumerate().filter_map(|(t, w)| w.map(|w| format!("{}: {w:?}", t + 1))).collect();
            if !whys.is_empty() {
                println!("       built-in bars: {}", whys.join(", "));
            }
            let q = quality(&lib, &bars, &beats, &chosen);
            let whole_random = random;
            let random = random_bas_same_pool(&lib, &bars, &beats, &chosen);
            let short = whole_random + 0.05 - q.beats.bas_music;
            let listed = KNOWN_UNDER_WHOLE_LIBRARY_RANDOM.iter().find(|k| k.0 == name && label.contains(k.1));
            match listed {
                Some(_) if short <= 0.0 => whole_library.push(format!("{name} {label}: listed under the whole library's random, but meets it (short {short:.3}): unlist it")),
                Some(k) if short > k.2 => whole_library.push(format!("{name} {label}: {short:.3} under the whole library's random + 0.05, past its ceiling {}", k.2)),
                None if short > 0.0 => whole_library.push(format!("{name} {label}: {short:.3} under the whole library's random + 0.05 ({whole_random:.3}), not listed")),
                _ => {}
            }
            let source_skate = paced_source_skate(&lib, &bars, &chosen);
            let rate = q.beats.kinetic_beats_per_sec / q.beats.music_beats_per_sec.max(1e-6);
            let met = [
                share >= 0.5,
                q.beats.bas_music >= random + 0.05,
                q.beats.bas_music >= q.beats.bas_music_shifted + 0.10,
                (0.8..=1.2).contains(&rate) || (0.4..=0.6).contains(&rate),
                q.join_jump_max <= 1.5,
                q.foot_skate.mean_cm_per_s <= source_skate,
            ];
            println!(
                "{name:<6} {label:<44} {:>3} bars: imported {imported:>3} ({:>3.0} %), BAS-music {:.3} random {random:.3} (whole library {whole_random:.3}) shifted {:.3}, kb/count {rate:.2}, join max {:.2}, skate {:.1} sources {source_skate:.1} cm/s",
                bars.len(),
                100.0 * share,
                q.beats.bas_music,
                q.beats.bas_music_shifted,
                q.join_jump_max,
                q.foot_skate.mean_cm_per_s
            );
            for (g, ok) in GOALS.iter().zip(met) {
                if !ok {
                    misses.push((name.to_string(), label.clone(), g));
                }
            }
        }
    }
    if only.is_some() || libs.is_some() {
        println!("ODORI_ONLY/ODORI_LIBS: goals not asserted; misses {misses:?}; whole library's random: {whole_library:?}");
        return;
    }
    let known = |m: &(String, String, &str)| KNOWN_MISSES.iter().any(|k| k.0 == m.0 && m.1.contains(k.1) && k.2 == m.2);
    let unknown: Vec<_> = misses.iter().filter(|m| !known(m)).collect();
    assert!(unknown.is_empty(), "goals missed: {unknown:?}");
    let fixed: Vec<_> = KNOWN_MISSES.iter().filter(|k| !misses.iter().any(|m| k.0 == m.0 && m.1.contains(k.1) && k.2 == m.2)).collect();
    assert!(fixed.is_empty(), "listed as known misses but met now (take them off the list): {fixed:?}");
    assert!(whole_library.is_empty(), "against the whole library's random moves: {whole_library:?}");
}

/// Spearman's rank correlation of two equally long lists.
fn spearman(a: &[f32], b: &[f32]) -> f32 {
    let ranks = |v: &[f32]| {
        let mut idx: Vec<usize> = (0..v.len()).collect();
        idx.sort_by(|&i, &j| v[i].total_cmp(&v[j]));
        let mut r = vec![0.0f32; v.len()];
        for (k, &i) in idx.iter().enumerate() {
            r[i] = k as f32;
        }
        r
    };
    let (ra, rb) = (ranks(a), ranks(b));
    let n = a.len() as f32;
    let mean = (n - 1.0) / 2.0;
    let cov: f32 = ra.iter().zip(&rb).map(|(x, y)| (x - mean) * (y - mean)).sum();
    let var: f32 = ra.iter().map(|x| (x - mean) * (x - mean)).sum();
    cov / var.max(1e-9)
}

/// Joins of imported moves (spec §J's join jump, measured on the rendered dance, feet held):
/// on 150 pairs of imported 4-count segments drawn at random, each played as two bars at
/// 120 BPM, inertialized joins (the default) are smoother than spec §G's Hermite rewrite on the
/// same pairs (mean and 90th percentile) and than no blend at all, and slide the feet no more
/// than the Hermite rewrite (mean skate within 0.5 cm/s); the join table's cost C(a, b) ranks the
/// pairs as the blended join jump does (Spearman's ρ printed, and above 0: it must predict).
#[test]
fn inertialized_joins_are_smoother_than_hermite_and_the_table_predicts_them() {
    use odori_core::choreo::{bars_from_tempo, JoinBlend, TableScope, TransitionTable};
    let (lib, _) = person_library(None);
    let four: Vec<usize> = lib.segments().iter().filter(|s| !s.retired && s.builtin.is_none() && s.counts() == 4).map(|s| s.index).collect();
    let bars = bars_from_tempo(4.0, 120.0, 4, 0.0, |_, _| 0.5).expect("bars");
    assert_eq!(bars.len(), 2);
    let beats: Vec<f32> = (0..8).map(|k| k as f32 * 0.5).collect();
    let table = TransitionTable::for_scope(&lib, 3.0, &TableScope::for_bar_counts(&[4]));
    let mut x = 0x2545_F491_4F6C_DD1Du64;
    let mut draw = || {
        x = x.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        four[(x >> 33) as usize % four.len()]
    };
    let (mut cost, mut jumps): (Vec<f32>, [Vec<f32>; 3]) = (Vec::new(), Default::default());
    let mut skate: [Vec<f32>; 3] = Default::default();
    while cost.len() < 150 {
        let (a, b) = (draw(), draw());
        if lib.segments()[a].clip == lib.segments()[b].clip {
            continue;
        }
        cost.push(table.cost(a, b));
        for (k, (frames, blend)) in [(5, JoinBlend::Inertial), (5, JoinBlend::Hermite), (0, JoinBlend::Inertial)].into_iter().enumerate() {
            let clip = odori_core::choreo::render(&lib, &bars, &[Some(a), Some(b)], &RenderOptions { join_frames: frames, join_blend: blend, ..RenderOptions::default() });
            let q = dance_quality(&clip, &bars, &beats).expect("quality");
            jumps[k].push(q.join_jump_max);
            skate[k].push(q.foot_skate.mean_cm_per_s);
        }
    }
    let mean = |v: &[f32]| v.iter().sum::<f32>() / v.len() as f32;
    let p90 = |v: &[f32]| {
        let mut s = v.to_vec();
        s.sort_by(f32::total_cmp);
        s[(s.len() * 9) / 10]
    };
    let names = ["inertial", "hermite", "none"];
    for k in 0..3 {
        println!(
            "{:<8}: join jump mean {:.2}, p90 {:.2}, over 1.5 {} of {}; skate mean {:.1} cm/s; Spearman ρ(table cost, join jump) {:.2}",
            names[k],
            mean(&jumps[k]),
            p90(&jumps[k]),
            jumps[k].iter().filter(|&&j| j > 1.5).count(),
            cost.len(),
            mean(&skate[k]),
            spearman(&cost, &jumps[k])
        );
    }
    assert!(mean(&jumps[0]) < mean(&jumps[1]) && p90(&jumps[0]) < p90(&jumps[1]), "inertial joins are no smoother than Hermite's");
    assert!(mean(&jumps[0]) < mean(&jumps[2]), "inertial joins are no smoother than none");
    assert!(mean(&skate[0]) <= mean(&skate[1]) + 0.5, "inertial joins slide the feet more: {} against {} cm/s", mean(&skate[0]), mean(&skate[1]));
    assert!(spearman(&cost, &jumps[0]) > 0.0, "the table's cost does not rank the blended joins");
}
