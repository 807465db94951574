//! Is the dance the person's (issue 26, spec §G and §J)? On every song in ../shared/data/music,
//! the drum take in ../shared/data/beats and the demo pieces (4/4 and 3/4, none tuned on), with
//! the core's own grid, at default settings, it prints for two libraries:
//! - **person**: built-in moves + every humanoid dance clip in ../shared/data/mocap (CMU salsa,
//!   Indian, modern dance without its walk 005_01; not the martial-arts negatives) +
//!   RobotExpressive's Dance, each cut at its detected tempo as the app does. Per song: the
//!   share of bars from imported clips; beat alignment (BAS-music, §J) of the dance against
//!   random moves on the same bars (mean of ≥ 5 draws, ≥ 100 random bars) and against the
//!   half-beat-shifted beats; kinetic beats per count; the largest join jump after the blend;
//!   foot skate of the dance as played (feet held, the product's default) against its sources'
//!   (each bar's own source clip at the bar's pace, spec §N); and whether each goal of issue 26
//!   is met (≥ 50 % imported, ≥ random + 0.05, ≥ shifted + 0.10, 0.8–1.2 or 0.4–0.6 kinetic
//!   beats per count, join ≤ 1.5, skate ≤ sources').
//! - **built-in**: the built-in library alone. Per song: the largest share of bars taken by one
//!   step, one arm pattern and one move, and distinct moves ÷ bars (goals: ≤ 1/3, ≤ 1/3 in 4/4;
//!   ≤ 1/3 for one move in 3/4; distinct ≥ 0.7).
//!
//! Then, per song and library, `ODORI_TAKES=n` (default 5) takes of Generate
//! ([`GenerateOptions::take`]): the least share of bars any two takes differ in (goal ≥ 50 %),
//! each take's objective against the best take's (goal within 10 %), and how many takes meet
//! the beat goals; with the time of each Generate.
//!
//! Prints figures; asserts nothing. `cargo bench -p odori-tests --bench choreo_person` (release),
//! or `cargo test -p odori-tests --bench choreo_person` for a quicker build.
//! `ODORI_SONGS=substring` keeps the songs whose label contains it. `ODORI_MOVES=mine|mixed|builtin`
//! sets the person library's moves source (`FillWeights::moves_source`; default: the product's).
//! `ODORI_VARIETY_WEIGHT=x` sets the variety term's weight for the built-in dances
//! (`GenerateOptions::variety_weight`; default: the product's; 0: off).

#[path = "../native/music_audio.rs"]
mod music_audio;
#[path = "../native/person_common.rs"]
mod person_common;

use std::collections::BTreeMap;
use std::time::Instant;

use odori_core::bars::Bar;
use odori_core::choreo::quality::{dance_quality, DanceQuality};
use odori_core::choreo::{GenerateOptions, MovesSource, RenderOptions, SegmentLibrary};
use odori_core::music::demo_song::{demo_song_with, DemoSongOptions};
use odori_core::music::{analyze, envelope, AnalysisOptions, RmsEnvelope};


/// The library of a person who imported every dance clip the shared data holds.
fn person_library() -> SegmentLibrary {
    person_common::person_library_with(None, |rel, clip, taken| match taken {
        Ok(s) => println!("  imported {rel} {}: {:.1} s, {:.1} counts/min, {} segments", clip.name, clip.duration_secs(), s.tempo_bpm, s.segments),
        Err(e) => println!("  imported {rel} {}: refused: {e}", clip.name),
    })
    .0
}

/// Demo pieces from the demo-song generator (no setting tuned on them): 4/4 at 100, 140 and a
/// 90 → 130 ramp; 3/4 at 150, 108, 126, 138, 84 and a 96 → 120 ramp.
fn demo_pieces() -> Vec<(String, RmsEnvelope)> {
    let mut out = Vec::new();
    for (bpb, bpm, end) in [(4u32, 100.0f32, 100.0f32), (4, 140.0, 140.0), (4, 90.0, 130.0), (3, 150.0, 150.0), (3, 108.0, 108.0), (3, 126.0, 126.0), (3, 96.0, 120.0), (3, 138.0, 138.0), (3, 84.0, 84.0)] {
        let song = demo_song_with(22050.0, &DemoSongOptions { beats_per_bar: bpb, bpm, end_bpm: end }).expect("demo song");
        let label = if bpm == end { format!("demo in {bpb}, {bpm:.0} BPM") } else { format!("demo in {bpb}, ramp {bpm:.0}→{end:.0} BPM") };
        out.push((label, envelope(&[&song.samples], 22050.0).expect("envelope")));
    }
    out
}

fn songs() -> Vec<(String, RmsEnvelope)> {
    let mut out: Vec<(String, RmsEnvelope)> = music_audio::FULL_TRACKS
        .iter()
        .chain([&music_audio::TRUMPET, &music_audio::DRUMS])
        .map(|rel| {
            let env = music_audio::decode_data(rel).envelope().unwrap_or_else(|e| panic!("{rel}: {e}"));
            let name = rel.rsplit('/').next().unwrap_or(rel);
            (name[..name.len().min(40)].to_string(), env)
        })
        .collect();
    out.extend(demo_pieces());
    if let Ok(keep) = std::env::var("ODORI_SONGS") {
        out.retain(|(l, _)| l.contains(&keep));
    }
    out
}

fn quality(lib: &SegmentLibrary, bars: &[Bar], beats: &[f32], choices: &[Option<usize>]) -> DanceQuality {
    let clip = odori_core::choreo::render(lib, bars, choices, &RenderOptions::default());
    dance_quality(&clip, bars, beats).expect("dance quality")
}

/// BAS-music of random dances on the same bars (odori_tests::random_moves).
fn random_bas(lib: &SegmentLibrary, bars: &[Bar], beats: &[f32]) -> f32 {
    odori_tests::random_moves_bas(lib, bars, beats, odori_tests::RANDOM_MOVES_SEED_TAKES)
}

/// Foot skate the dance should not exceed (spec §N): each bar's own source clip played at the
/// bar's pace, averaged over the bars.
fn paced_source_skate(lib: &SegmentLibrary, bars: &[Bar], chosen: &[Option<usize>]) -> f32 {
    let v: Vec<f32> = chosen
        .iter()
        .enumerate()
        .filter_map(|(t, s)| {
            let seg = &lib.segments()[(*s)?];
            let rate = odori_core::choreo::count_rate_bpm(seg.counts(), bars[t].duration_secs());
            Some(seg.clip_skate_cm_per_s * rate / seg.tempo_bpm.max(1e-3))
        })
        .collect();
    v.iter().sum::<f32>() / v.len().max(1) as f32
}

/// `ODORI_MOVES`, when set.
fn moves_source() -> Option<MovesSource> {
    match std::env::var("ODORI_MOVES").ok()?.as_str() {
        "mine" => Some(MovesSource::Mine),
        "mixed" => Some(MovesSource::Mixed),
        "builtin" => Some(MovesSource::Builtin),
        other => panic!("ODORI_MOVES={other}: mine, mixed or builtin"),
    }
}

fn mark(ok: bool) -> char {
    if ok {
        '✓'
    } else {
        '✗'
    }
}

/// The beat goals of issue 26 (spec §J): ≥ random + 0.05, ≥ shifted + 0.10, kinetic beats per
/// count in 0.8–1.2 or 0.4–0.6.
fn beat_goals(q: &DanceQuality, random: f32) -> [bool; 3] {
    let r = q.beats.kinetic_beats_per_sec / q.beats.music_beats_per_sec.max(1e-6);
    [q.beats.bas_music - random >= 0.05, q.beats.bas_music - q.beats.bas_music_shifted >= 0.10, (0.8..=1.2).contains(&r) || (0.4..=0.6).contains(&r)]
}

/// The largest share of bars one key takes, and how many keys there are.
fn dominance<K: Ord>(keys: impl Iterator<Item = K>, bars: usize) -> (f32, usize) {
    let mut m: BTreeMap<K, usize> = BTreeMap::new();
    for k in keys {
        *m.entry(k).or_default() += 1;
    }
    (m.values().copied().max().unwrap_or(0) as f32 / bars.max(1) as f32, m.len())
}

fn main() {
    let t = Instant::now();
    let person = person_library();
    let builtin = SegmentLibrary::builtin();
    let imported_segments = person.segments().iter().filter(|s| s.builtin.is_none()).count();
    println!("person library: {} segments ({} built-in, {imported_segments} imported) in {:.1} s", person.len(), person.len() - imported_segments, t.elapsed().as_secs_f64());
    let takes: u32 = std::env::var("ODORI_TAKES").ok().and_then(|v| v.parse().ok()).unwrap_or(5);
    let songs = songs();

    println!("\n== person library (built-in + every dance clip), default settings, feet held ==");
    println!(
        "{:<40} {:>4} {:>3} | {:>9} | {:>6} {:>6} {:>6} | {:>5} | {:>5} | {:>11} | {:>6} | goals imp/rnd/shift/rate/join/skate",
        "song", "bars", "bpb", "imported", "BASm", "random", "shift", "kb/ct", "join", "skate/src", "gen ms"
    );
    let mut all_met = 0usize;
    let mut grids = Vec::new();
    for (label, env) in &songs {
        let grid = analyze(env, &AnalysisOptions::default()).unwrap_or_else(|e| panic!("{label}: {e}"));
        let (bars, beats) = (grid.bars.clone(), grid.beat_times_secs.clone());
        let mut doc = odori_tests::Dance::new(bars.clone());
        if let Some(source) = moves_source() {
            doc.set_moves_source(source);
        }
        let tg = Instant::now();
        doc.generate(&person).expect("generate");
        let ms = tg.elapsed().as_secs_f64() * 1e3;
        let chosen = doc.segments();
        let imported = chosen.iter().flatten().filter(|&&s| person.segments()[s].builtin.is_none()).count();
        let q = quality(&person, &bars, &beats, &chosen);
        let rnd = random_bas(&person, &bars, &beats);
        let src = paced_source_skate(&person, &bars, &chosen);
        let share = imported as f32 / bars.len().max(1) as f32;
        let g = beat_goals(&q, rnd);
        let goals = [share >= 0.5, g[0], g[1], g[2], q.join_jump_max <= 1.5, q.foot_skate.mean_cm_per_s <= src];
        all_met += usize::from(goals.iter().all(|&b| b));
        println!(
            "{label:<40} {:>4} {:>3} | {imported:>3}/{:<3}{:>3.0}% | {:>6.3} {:>6.3} {:>6.3} | {:>5.2} | {:>5.2} | {:>5.1}/{:<5.1} | {ms:>6.0} | {}",
            bars.len(),
            grid.beats_per_bar,
            bars.len(),
            100.0 * share,
            q.beats.bas_music,
            rnd,
            q.beats.bas_music_shifted,
            q.beats.kinetic_beats_per_sec / q.beats.music_beats_per_sec.max(1e-6),
            q.join_jump_max,
            q.foot_skate.mean_cm_per_s,
            src,
            goals.iter().map(|&b| mark(b)).collect::<String>()
        );
        grids.push((label.clone(), bars, beats, grid.beats_per_bar, rnd));
    }
    println!("every goal met on {all_met}/{} songs", songs.len());

    println!("\n== built-in library alone, default settings ==");
    println!("{:<40} {:>4} {:>3} | {:>9} {:>9} {:>9} | {:>8} | goals step/arms/move/distinct", "song", "bars", "bpb", "top step", "top arms", "top move", "distinct");
    let mut variety_met = 0usize;
    for (label, bars, _, bpb, _) in &grids {
        let mut doc = odori_tests::Dance::new(bars.clone());
        let variety_weight = std::env::var("ODORI_VARIETY_WEIGHT").ok().and_then(|v| v.parse().ok()).unwrap_or(GenerateOptions::default().variety_weight);
        doc.generate_with(&builtin, &GenerateOptions { variety_weight, ..GenerateOptions::default() }).expect("generate");
        let chosen: Vec<usize> = doc.segments().into_iter().flatten().collect();
        let n = bars.len();
        let info = |s: usize| builtin.segments()[s].builtin;
        let (step, _) = dominance(chosen.iter().filter_map(|&s| info(s)).map(|m| m.step.name()), n);
        let (arms, _) = dominance(chosen.iter().filter_map(|&s| info(s)).map(|m| m.arms.name()), n);
        let (mv, distinct) = dominance(chosen.iter().copied(), n);
        let third = 1.0 / 3.0 + 1e-6;
        // A third of fewer than 3 bars is less than one bar: such a song has no variety goal.
        let goals = if n < 3 {
            vec![]
        } else if *bpb == 3 {
            vec![mv <= third]
        } else {
            vec![step <= third, arms <= third, mv <= third, distinct as f32 >= 0.7 * n as f32]
        };
        variety_met += usize::from(!goals.is_empty() && goals.iter().all(|&b| b));
        println!(
            "{label:<40} {n:>4} {bpb:>3} | {:>8.0}% {:>8.0}% {:>8.0}% | {:>3}/{:<4} | {}",
            100.0 * step,
            100.0 * arms,
            100.0 * mv,
            distinct,
            n,
            if goals.is_empty() { "n/a (under 3 bars)".to_string() } else { goals.iter().map(|&b| mark(b)).collect::<String>() }
        );
    }
    println!("every variety goal met on {variety_met}/{} songs with 3 bars or more", grids.iter().filter(|g| g.1.len() >= 3).count());

    if takes > 1 {
        println!("\n== {takes} takes of Generate per song ==");
        println!("{:<40} {:<9} | {:>12} | {:>14} | {:>10} | {:>8}", "song", "library", "least differ", "worst/best obj", "beat goals", "ms/take");
        for (label, bars, beats, _, rnd) in &grids {
            for (name, lib) in [("person", &person), ("built-in", &builtin)] {
                let rnd = if name == "person" { *rnd } else { random_bas(lib, bars, beats) };
                let mut paths: Vec<Vec<Option<usize>>> = Vec::new();
                let (mut costs, mut on_beat, mut ms) = (Vec::new(), 0usize, 0.0f64);
                for take in 0..takes {
                    let mut doc = odori_tests::Dance::new(bars.clone());
                    if let (Some(source), "person") = (moves_source(), name) {
                        doc.set_moves_source(source);
                    }
                    let tg = Instant::now();
                    let report = doc.generate_with(lib, &GenerateOptions { take, ..GenerateOptions::default() }).expect("generate");
                    ms += tg.elapsed().as_secs_f64() * 1e3;
                    let chosen = doc.segments();
                    on_beat += usize::from(beat_goals(&quality(lib, bars, beats, &chosen), rnd).iter().all(|&b| b));
                    costs.push(report.cost);
                    paths.push(chosen);
                }
                let mut least = 1.0f32;
                for a in 0..paths.len() {
                    for b in a + 1..paths.len() {
                        let d = paths[a].iter().zip(&paths[b]).filter(|(x, y)| x != y).count() as f32 / bars.len().max(1) as f32;
                        least = least.min(d);
                    }
                }
                let best = costs.iter().copied().fold(f32::INFINITY, f32::min);
                let worst = costs.iter().copied().fold(f32::NEG_INFINITY, f32::max);
                println!("{label:<40} {name:<9} | {:>11.0}% | {:>13.3}x | {on_beat:>5}/{takes:<4} | {:>8.0}", 100.0 * least, worst / best.max(1e-9), ms / takes as f64);
            }
        }
    }
    println!("total {:.1} s", t.elapsed().as_secs_f64());
}
