//! How well generated dances follow the music (spec §J), on every song in ../shared/data/music
//! and the drum take in ../shared/data/beats, with the core's own grid and real dance clips
//! imported into the library as the app has them (built-in moves + the CMU salsa and Indian
//! clips, cut at their detected tempo). For each song it prints, against controls measured in
//! the same run:
//! - BAS-music and BAS-motion of the generated dance (default settings), of dances of random
//!   segments on the same bars (mean of 5 draws, more on a short song: at least 100 bars), and of the generated dance scored against
//!   the half-beat-shifted beats;
//! - kinetic beats per second against the song's beat rate;
//! - foot skate (mean, p95 cm/s) and PFC against the source clips'; the skate goal in three
//!   readings: each bar's own source clip at the bar's speed (the paced reading: the source as
//!   the dance plays it; skate is a speed, so a clip played faster slides faster), each bar's own
//!   source clip at the clip's own speed (the strictest), and each kind's clips' mean (the loose
//!   reading, the one the filling follows);
//! - join jump (mean, max);
//! - the share of bars filled from imported clips.
//!
//! Then the cut tempo of the two pairs of salsa partners (same take, same music).
//! `ODORI_BEAT_WEIGHT=x` sets the filling's beat weight (default: the product's; 0: off, the
//! filling before the beat term).
//! `ODORI_OWN_MOVES=x` sets the preference for imported moves (0: none).
//! `ODORI_STRETCH_WEIGHT=x` sets the tempo-stretch weight (0: off, the filling before it).
//! `ODORI_FREE_SKATE_SLACK=x` sets the free skate swap's slack (0: off, the filling before it).
//! `ODORI_FOLLOW_SKATE=0` turns off keeping the dance's skate within its sources' (the filling
//! before it).
//! `ODORI_FOLLOW_BEAT_RATE=0` turns off following the song's beat rate (the filling before it).
//! `ODORI_FOLLOW_JOINS=0` turns off keeping every join within the join-jump goal (the filling
//! before it).
//! `ODORI_RATES=1` also prints the segments' kinetic beats per count at four count rates.
//! The songs are followed by pieces from the demo-song generator that nothing was tuned on
//! (other tempi, a waltz, a tempo ramp, a short piece).
//! `ODORI_SKATE_BARS=1` also prints each bar's foot skate as the dance plays it (whole bar, and
//! without the 4 frames either side of its joins) against its segment's own skate, sped up to
//! the bar, and its source clip's.
//! `ODORI_JOINS=1` also prints each song's five worst joins (of the dance with its feet held)
//! and the segments either side.
//! Every generated dance is rendered twice, its feet held to their floor contacts (the
//! product's default, `RenderOptions::hold_feet`) and unheld (the control): the table's row is
//! the unheld dance, the line under it ("held") the same dance held, each against random
//! dances rendered the same way, with the render time of each.
//! `ODORI_FRESH=n` replaces the songs and the demo pieces by n fresh short pieces (8 bars,
//! from the demo-song generator: tempo 70–170 BPM, 3/4 or 4/4, a third of them ramping by up to
//! ±25 %, drawn by a fixed generator: the same pieces every run), and prints how many keep
//! each goal held where it was met unheld. `ODORI_FRESH_SEED=x` draws another set.
//! Prints figures; asserts nothing. `cargo bench -p odori-tests --bench choreo_quality`
//! (release), or `cargo test -p odori-tests --bench choreo_quality` for a quicker build.

#[path = "../native/music_audio.rs"]
mod music_audio;

use std::time::Instant;

use odori_core::bars::Bar;
use odori_core::choreo::quality::{dance_quality, motion_quality, DanceQuality, QualityMotion};
use odori_core::choreo::{generate_states, BarState, FillWeights, GenerateOptions, RenderOptions, SegmentLibrary, SegmentOptions};
use odori_core::import::import_bytes;
use odori_core::music::demo_song::{demo_song_with, DemoSongOptions};
use odori_core::music::{analyze, envelope, AnalysisOptions, RmsEnvelope};
use odori_core::ImportOptions;
use odori_tests::{all_bvh, fps_override_for, read};

/// Random dances per song: 5, or enough for 100 random bars on a short song (one draw of a
/// one-bar song is one segment: 5 are too few to estimate a random dance's score).
fn random_draws(bars: usize) -> usize {
    5usize.max(100usize.div_ceil(bars.max(1)))
}

/// The library as the app has it after the person opens the dance clips: built-in moves plus
/// every salsa and Indian BVH, cut at the detected tempo (the app's default).
fn library() -> SegmentLibrary {
    let mut lib = SegmentLibrary::builtin();
    for rel in all_bvh().into_iter().filter(|r| r.contains("cmu-salsa") || r.contains("cmu-indian")) {
        let opts = ImportOptions { fps_override: fps_override_for(&rel), ..Default::default() };
        let imp = import_bytes(&rel, &read(&rel), &opts).unwrap_or_else(|e| panic!("{rel}: {e}"));
        for clip in &imp.clips {
            match lib.add_clip(clip, &imp.humanoid, &imp.status, &SegmentOptions::default()) {
                Ok(s) => println!("  imported {rel}: {:.1} s, {:.1} counts/min, {} segments", clip.duration_secs(), s.tempo_bpm, s.segments),
                Err(e) => println!("  imported {rel}: refused: {e}"),
            }
        }
    }
    lib
}

/// Test pieces from the demo-song generator that no setting was tuned on: other tempi, two
/// pieces in 3/4 (150, 108, 126, 138, 84 BPM and a 96 → 120 BPM ramp), a tempo ramp and a short piece (three bars of the chorus, which the analysis takes as
/// a loop).
fn demo_pieces() -> Vec<(String, RmsEnvelope)> {
    let make = |beats_per_bar: u32, bpm: f32, end_bpm: f32| {
        demo_song_with(22050.0, &DemoSongOptions { beats_per_bar, bpm, end_bpm }).expect("demo song")
    };
    let env = |samples: &[f32]| envelope(&[samples], 22050.0).expect("envelope");
    let mut out = Vec::new();
    for (bpb, bpm, end) in [(4u32, 100.0f32, 100.0f32), (4, 140.0, 140.0), (3, 150.0, 150.0), (3, 108.0, 108.0), (3, 126.0, 126.0), (3, 96.0, 120.0), (3, 138.0, 138.0), (3, 84.0, 84.0), (4, 90.0, 130.0)] {
        let song = make(bpb, bpm, end);
        let label = if bpm == end { format!("demo in {bpb}, {bpm:.0} BPM") } else { format!("demo in {bpb}, ramp {bpm:.0}→{end:.0} BPM") };
        out.push((label, env(&song.samples)));
    }
    // Short: 3 bars of the first chorus at 140 BPM.
    let song = make(4, 140.0, 140.0);
    let chorus = song.sections.iter().find(|s| s.name == "chorus").expect("a chorus");
    let (a, b) = ((chorus.start_secs * 22050.0) as usize, ((chorus.start_secs + 3.0 * 4.0 * 60.0 / 140.0) * 22050.0) as usize);
    out.push(("demo in 4, 140 BPM, 3 bars".to_string(), env(&song.samples[a..b.min(song.samples.len())])));
    out
}

/// Fresh short pieces ([`ODORI_FRESH`]): 8 bars of a demo song at a drawn tempo and metre
/// (some ramping), from a drawn bar of the song.
fn fresh_pieces(n: usize, seed: u64) -> Vec<(String, RmsEnvelope)> {
    let mut x = seed;
    let mut next = || {
        x = x.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        (x >> 40) as f32 / (1u64 << 24) as f32
    };
    let mut out = Vec::new();
    for i in 0..n {
        let bpb = if next() < 0.5 { 3 } else { 4 };
        let bpm = 70.0 + 100.0 * next();
        let end = if i % 3 == 2 { (bpm * (0.75 + 0.5 * next())).clamp(60.0, 190.0) } else { bpm };
        let song = demo_song_with(22050.0, &DemoSongOptions { beats_per_bar: bpb, bpm, end_bpm: end }).expect("demo song");
        let bar_secs = bpb as f32 * 60.0 / bpm.max(end);
        let total = song.samples.len() as f32 / 22050.0;
        let start = (next() * (total - 9.0 * bar_secs).max(0.0)).max(0.0);
        let (a, b) = ((start * 22050.0) as usize, (((start + 8.0 * bar_secs) * 22050.0) as usize).min(song.samples.len()));
        let label = if bpm == end { format!("fresh {i} in {bpb}, {bpm:.0} BPM") } else { format!("fresh {i} in {bpb}, {bpm:.0}→{end:.0} BPM") };
        out.push((label, envelope(&[&song.samples[a..b]], 22050.0).expect("envelope")));
    }
    out
}

fn quality(lib: &SegmentLibrary, bars: &[Bar], beats: &[f32], choices: &[Option<usize>], hold_feet: bool) -> DanceQuality {
    let clip = odori_core::choreo::render(lib, bars, choices, &RenderOptions { hold_feet, ..RenderOptions::default() });
    dance_quality(&clip, bars, beats).expect("dance quality")
}

/// The beat goals of a dance against its controls: gen − random ≥ +0.05, gen − shifted ≥
/// +0.10, kinetic/song beat rate in 0.75..1.25 or 0.375..0.625; and join jump ≤ 1.5.
fn goals(gen: &DanceQuality, random_bas: f32) -> [bool; 4] {
    let r = gen.beats.kinetic_beats_per_sec / gen.beats.music_beats_per_sec.max(1e-6);
    [
        gen.beats.bas_music - random_bas >= 0.05,
        gen.beats.bas_music - gen.beats.bas_music_shifted >= 0.10,
        (0.75..=1.25).contains(&r) || (0.375..=0.625).contains(&r),
        gen.join_jump_max <= 1.5,
    ]
}

fn main() {
    let t = Instant::now();
    let lib = library();
    let builtin = lib.segments().iter().filter(|s| s.builtin.is_some()).count();
    let in_three = lib.segments().iter().filter(|s| s.counts() == 3).count();
    println!("library: {} segments ({builtin} built-in, {} imported, {in_three} of them in 3) in {:.2} s", lib.len(), lib.len() - builtin, t.elapsed().as_secs_f64());

    for (label, bi) in [("built-in", true), ("imported", false)] {
        let v: Vec<&odori_core::choreo::Segment> = lib.segments().iter().filter(|s| s.builtin.is_some() == bi).collect();
        let n = v.len().max(1) as f32;
        println!(
            "  {label} segments: intensity W mean {:.2} m/s, scaled 0..1 mean {:.2} ({:.0} % at 1.0), beat fit mean {:.2}",
            v.iter().map(|s| s.intensity).sum::<f32>() / n,
            v.iter().map(|s| s.intensity01).sum::<f32>() / n,
            100.0 * v.iter().filter(|s| s.intensity01 >= 0.999).count() as f32 / n,
            v.iter().map(|s| s.beat_fit).sum::<f32>() / n
        );
    }
    // Source clips: what the dances are made of.
    let (mut skate_imp, mut skate_bi, mut pfc_imp, mut kbps_imp) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    for c in lib.clips() {
        let Ok(m) = QualityMotion::from_clip(&c.clip) else { continue };
        let q = motion_quality(&m);
        if c.builtin.is_some() {
            skate_bi.push(q.foot_skate.mean_cm_per_s);
        } else {
            skate_imp.push(q.foot_skate.mean_cm_per_s);
            pfc_imp.push(q.pfc);
            kbps_imp.push(q.kinetic_beats_per_sec);
        }
    }
    let mean = |v: &[f32]| v.iter().sum::<f32>() / v.len().max(1) as f32;
    println!(
        "source clips: imported foot skate mean {:.1} cm/s, PFC {:.2}, kinetic beats {:.2}/s; built-in moves foot skate mean {:.1} cm/s",
        mean(&skate_imp),
        mean(&pfc_imp),
        mean(&kbps_imp),
        mean(&skate_bi)
    );

    // Each segment alone over one 2 s bar (120 BPM): do its inner counts (beats 2, 3, 4 of the
    // bar) fall on kinetic beats once it is stretched linearly to the bar?
    for (label, builtin_only) in [("built-in", true), ("imported", false)] {
        let (mut on, mut off, mut n) = (0.0, 0.0, 0);
        for s in lib.segments().iter().filter(|s| s.builtin.is_some() == builtin_only) {
            let Some(clip) = odori_core::choreo::segment_clip(&lib, s.index, 2.0, 30.0) else { continue };
            let Ok(m) = QualityMotion::from_clip(&clip) else { continue };
            let k = odori_core::choreo::quality::kinetic_beats_secs(&m);
            let a = odori_core::choreo::quality::beat_alignment(&[0.0, 0.5, 1.0, 1.5, 2.0], &k, 0.25, 1.75);
            on += a.bas_music;
            off += a.bas_music_shifted;
            n += 1;
        }
        println!("{label} segments alone on a 120 BPM bar: inner counts BAS-music {:.3}, half-shifted {:.3} ({n} segments)", on / n as f32, off / n as f32);
    }

    if std::env::var("ODORI_RATES").is_ok() {
        // What measuring every segment's kinetic beats per count at the six rates costs, of the
        // library's cut above.
        let t = Instant::now();
        let mut n = 0;
        for (ci, c) in lib.clips().iter().enumerate() {
            let pos = odori_core::canon::humanoid::canonical_positions(&c.clip, &odori_core::canon::humanoid::HumanoidMap::from_skeleton(&c.clip.skeleton));
            for s in lib.segments().iter().filter(|s| s.clip == ci) {
                n += odori_core::choreo::kinetic_per_count_by_rate(&pos, &s.count_frames).len();
            }
        }
        println!("kinetic beats per count at {} rates of {} segments: {:.2} s", odori_core::choreo::KINETIC_RATES_BPM.len(), n / 6, t.elapsed().as_secs_f64());
        // Kinetic beats per count of each segment alone, played at four count rates: §J's
        // speed is smoothed over a fixed time, so a slowed move turns more often a count.
        for (label, bi) in [("built-in", true), ("imported", false)] {
            for bar_secs in [1.6f32, 2.0, 2.7, 3.5] {
                let (mut k, mut n, mut inner) = (0usize, 0usize, 0usize);
                for s in lib.segments().iter().filter(|s| s.builtin.is_some() == bi && !s.retired) {
                    let Some(clip) = odori_core::choreo::segment_clip(&lib, s.index, bar_secs, 30.0) else { continue };
                    let Ok(m) = QualityMotion::from_clip(&clip) else { continue };
                    let kb = odori_core::choreo::quality::kinetic_beats_secs(&m);
                    k += kb.len();
                    inner += kb.iter().filter(|&&t| t > 0.125 * bar_secs && t < 0.875 * bar_secs).count();
                    n += 1;
                }
                println!("  {label} segments on a bar of {bar_secs:.1} s ({:.0} counts/min): kinetic beats per count {:.2}, inner (1/8..7/8 of the bar) per inner count {:.2}", 240.0 / bar_secs, k as f32 / (4 * n) as f32, inner as f32 / (3 * n) as f32);
            }
        }
    }
    let fresh: Option<usize> = std::env::var("ODORI_FRESH").ok().and_then(|v| v.parse().ok());
    let seed: u64 = std::env::var("ODORI_FRESH_SEED").ok().and_then(|v| v.parse().ok()).unwrap_or(0x5EED_F00D);
    let mut songs: Vec<(String, RmsEnvelope)> = if fresh.is_some() { Vec::new() } else { music_audio::FULL_TRACKS
        .iter()
        .chain([&music_audio::TRUMPET, &music_audio::DRUMS])
        .map(|rel| {
            let env = music_audio::decode_data(rel).envelope().unwrap_or_else(|e| panic!("{rel}: {e}"));
            (rel.to_string(), env)
        })
        .collect() };
    // Pieces no setting was tuned on, from the demo-song generator (synthesised here).
    match fresh {
        Some(n) => songs.extend(fresh_pieces(n, seed)),
        None => songs.extend(demo_pieces()),
    }
    // Held against unheld: pieces with held skate ≤ unheld, and goals kept where met unheld.
    let (mut pieces, mut skate_ok, mut goals_kept, mut goals_lost) = (0usize, 0usize, 0usize, Vec::new());
    let (mut render_unheld_ms, mut render_held_ms, mut longest) = (0.0f64, 0.0f64, 0.0f32);
    println!(
        "\n{:<44} {:>5} {:>5} | {:>11} {:>11} {:>11} | {:>9} {:>9} | {:>5} {:>5} | {:>9} {:>5} | {:>9} {:>9} | {:>8}",
        "song", "bars", "b/s", "BASm gen", "BASm rand", "BASm shift", "BASk gen", "BASk rnd", "kb/s", "rnd", "skate", "PFC", "jump mean", "jump max", "imported"
    );
    for (rel, env) in &songs {
        let rel = rel.as_str();
        let grid = analyze(env, &AnalysisOptions::default()).unwrap_or_else(|e| panic!("{rel}: {e}"));
        let bars = grid.bars.clone();
        let beats = grid.beat_times_secs.clone();
        // The objective's weights (FillWeights) and the pipeline's stages (GenerateOptions): the
        // core takes them as plain inputs, the bench reads them from the environment.
        let mut weights = FillWeights::default();
        let env_f32 = |name: &str| std::env::var(name).ok().and_then(|v| v.parse::<f32>().ok());
        if let Some(w) = env_f32("ODORI_BEAT_WEIGHT") {
            weights.beat_weight = w;
        }
        if let Some(w) = env_f32("ODORI_OWN_MOVES") {
            weights.own_moves_preference = w;
        }
        if let Some(w) = env_f32("ODORI_STRETCH_WEIGHT") {
            weights.stretch_weight = w;
        }
        if let Some(w) = env_f32("ODORI_SKATE_WEIGHT") {
            weights.skate_weight = w;
        }
        // The pipeline's stages (GenerateOptions): the core takes options, the bench reads them
        // from the environment.
        let mut options = GenerateOptions::default();
        if let Some(w) = std::env::var("ODORI_FREE_SKATE_SLACK").ok().and_then(|v| v.parse().ok()) {
            options.free_skate_slack = w;
        }
        if std::env::var("ODORI_FOLLOW_SKATE").is_ok_and(|v| v == "0") {
            options.follow_skate = false;
        }
        if std::env::var("ODORI_FOLLOW_JOINS").is_ok_and(|v| v == "0") {
            options.follow_joins = false;
        }
        if std::env::var("ODORI_FOLLOW_BEAT_RATE").is_ok_and(|v| v == "0") {
            options.follow_beat_rate = false;
        }
        if let Some(w) = env_f32("ODORI_BEAT_RATE_WEIGHT") {
            weights.beat_rate_weight = w;
        }
        let tg = Instant::now();
        let (states, _) = generate_states(&lib, &bars, &[], weights, &options).expect("generate");
        let generate_ms = tg.elapsed().as_secs_f64() * 1e3;
        let chosen: Vec<Option<usize>> = states.iter().map(BarState::segment).collect();
        let imported = chosen.iter().flatten().filter(|&&s| lib.segments()[s].builtin.is_none()).count();
        let gen = quality(&lib, &bars, &beats, &chosen, false);
        let tr = Instant::now();
        let held_clip = odori_core::choreo::render(&lib, &bars, &chosen, &RenderOptions::default());
        let held_ms = tr.elapsed().as_secs_f64() * 1e3;
        let tr = Instant::now();
        let unheld_clip = odori_core::choreo::render(&lib, &bars, &chosen, &RenderOptions { hold_feet: false, ..RenderOptions::default() });
        let unheld_ms = tr.elapsed().as_secs_f64() * 1e3;
        drop(unheld_clip);
        let held = dance_quality(&held_clip, &bars, &beats).expect("dance quality");
        if bars.last().map_or(0.0, |b| b.end_secs) > longest {
            (longest, render_unheld_ms, render_held_ms) = (bars.last().map_or(0.0, |b| b.end_secs), unheld_ms, held_ms);
        }
        // Random segments on the same bars (a fixed LCG: the same draws every run).
        if std::env::var("ODORI_JOINS").is_ok() {
            // The five worst joins, with the segments either side (a diagnostic).
            let table = lib.transition_table(3.0);
            let mut cs: Vec<f32> = (1..bars.len()).filter_map(|t| Some(table.cost(chosen[t - 1]?, chosen[t]?))).collect();
            cs.sort_by(f32::total_cmp);
            if !cs.is_empty() {
                println!("    edge costs on the path: median {:.2}, max {:.2}", cs[cs.len() / 2], cs[cs.len() - 1]);
            }
            let clip = odori_core::choreo::render(&lib, &bars, &chosen, &RenderOptions::default());
            let qm = QualityMotion::from_clip(&clip).expect("motion");
            let nj = odori_core::canon::humanoid::CANON_COUNT;
            // The dance as rendered (feet held), not the unheld control.
            let hq = dance_quality(&clip, &bars, &beats).expect("dance quality");
            let mut js: Vec<(f32, usize)> = hq.bars.iter().filter_map(|b| b.join_jump.map(|j| (j, b.bar))).collect();
            js.sort_by(|a, b| b.0.total_cmp(&a.0));
            for (j, bar) in js.iter().take(5) {
                let name = |i: usize| chosen[i].map_or("-".to_string(), |s| format!("{} ({:.0}/min)", lib.segments()[s].name, lib.segments()[s].tempo_bpm));
                let f0 = (bars[*bar].start_secs * 30.0).round() as usize;
                let p = |f: usize, j: usize| qm.positions[f * nj + j];
                let (mut bj, mut bv, mut bf) = (0, 0.0f32, 0);
                for f in f0.saturating_sub(3).max(1)..(f0 + 4).min(qm.positions.len() / nj - 1) {
                    for j in 0..nj {
                        let v = ((p(f + 1, j) - p(f, j)) - (p(f, j) - p(f - 1, j))).length() * 30.0;
                        if v > bv {
                            (bj, bv, bf) = (j, v, f);
                        }
                    }
                }
                let fa = f0.saturating_sub(4);
                let fb = (f0 + 4).min(qm.positions.len() / nj - 1);
                println!("      worst joint {bj} change {bv:.2} m/s at frame {} of the join; hips y {:.2} -> {:.2}; joint {bj} moved {:.2} m over the join (8 frames)", bf as i64 - f0 as i64, p(fa, 0).y, p(fb, 0).y, (p(fb, bj) - p(fa, bj)).length());
                println!("    join {j:.2} (C {:.2}) at bar {bar} ({:.0}/min): {} -> {}", table.cost(chosen[bar - 1].unwrap_or(0), chosen[*bar].unwrap_or(0)), odori_core::choreo::bar_count_rate_bpm(bars[*bar].duration_secs()), name(bar - 1), name(*bar));
            }
        }
        if std::env::var("ODORI_SKATE_BARS").is_ok() {
            // Each bar's foot skate as the dance plays it, whole bar and without the 4 frames
            // either side of its joins, against its segment's own skate in its clip (at the
            // clip's tempo and sped up to the bar's) and its source clip's (a diagnostic).
            let clip = odori_core::choreo::render(&lib, &bars, &chosen, &RenderOptions::default());
            let qm = QualityMotion::from_clip(&clip).expect("motion");
            let samples = odori_core::choreo::quality::foot_skate_samples(&qm);
            let fr = |t: f32| ((t * odori_core::choreo::quality::QUALITY_FPS).round().max(0.0) as usize).min(samples.len());
            for (i, b) in bars.iter().enumerate() {
                let Some(s) = chosen[i] else { continue };
                let seg = &lib.segments()[s];
                let (a, z) = (fr(b.start_secs), fr(b.end_secs));
                let whole = odori_core::choreo::quality::summarize_skate(&samples, a..z).mean_cm_per_s;
                let inner = odori_core::choreo::quality::summarize_skate(&samples, (a + 4).min(z)..z.saturating_sub(4).max(a + 4).min(z)).mean_cm_per_s;
                let rate = odori_core::choreo::bar_count_rate_bpm(b.duration_secs());
                let up = if seg.tempo_bpm > 0.0 { rate / seg.tempo_bpm } else { 1.0 };
                println!(
                    "    bar {i:>3} {:<28} {:>5.0}/min on {:>4.0}/min: played {whole:>5.1} (inner {inner:>5.1}); own {:>5.1}, sped {:>5.1}; clip {:>5.1}",
                    &seg.name[..seg.name.len().min(28)], seg.tempo_bpm, rate, seg.skate_cm_per_s, seg.skate_cm_per_s * up, seg.clip_skate_cm_per_s
                );
            }
        }
        let mut x = 0x9E37_79B9_7F4A_7C15u64;
        // Per bar, the live segments it can take (its count; any when the library has none).
        let live: Vec<Vec<usize>> = odori_core::choreo::bar_counts(&lib, &bars)
            .iter()
            .map(|&n| lib.segments().iter().filter(|s| !s.retired && (n == 0 || s.counts() == n)).map(|s| s.index).collect())
            .collect();
        let (mut rnd, mut rnd_held) = (Vec::new(), Vec::new());
        for _ in 0..random_draws(bars.len()) {
            let ch: Vec<Option<usize>> = (0..bars.len())
                .map(|b| {
                    x = x.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
                    Some(live[b][(x >> 33) as usize % live[b].len()])
                })
                .collect();
            rnd.push(quality(&lib, &bars, &beats, &ch, false));
            rnd_held.push(quality(&lib, &bars, &beats, &ch, true));
        }
        let rm = |f: &dyn Fn(&DanceQuality) -> f32| rnd.iter().map(f).sum::<f32>() / rnd.len() as f32;
        let rm_held = rnd_held.iter().map(|q| q.beats.bas_music).sum::<f32>() / rnd_held.len() as f32;
        let name = rel.rsplit('/').next().unwrap_or(rel);
        let name = &name[..name.len().min(44)];
        println!(
            "{name:<44} {:>5} {:>5.2} | {:>11.3} {:>11.3} {:>11.3} | {:>9.3} {:>9.3} | {:>5.2} {:>5.2} | {:>4.1}/{:<4.1} {:>5.2} | {:>4.2}/{:<4.2} {:>9.2} | {:>3}/{:<3} {:.0}%",
            bars.len(),
            gen.beats.music_beats_per_sec,
            gen.beats.bas_music,
            rm(&|q| q.beats.bas_music),
            gen.beats.bas_music_shifted,
            gen.beats.bas_motion,
            rm(&|q| q.beats.bas_motion),
            gen.beats.kinetic_beats_per_sec,
            rm(&|q| q.beats.kinetic_beats_per_sec),
            gen.foot_skate.mean_cm_per_s,
            gen.foot_skate.p95_cm_per_s,
            gen.pfc,
            gen.join_jump_mean,
            rm(&|q| q.join_jump_mean),
            gen.join_jump_max,
            imported,
            bars.len(),
            100.0 * imported as f32 / bars.len().max(1) as f32
        );
        println!(
            "{:<44}   grid {:.0} BPM in {}; margins: gen − random {:+.3} (goal ≥ +0.05), gen − shifted {:+.3} (goal ≥ +0.10); kinetic/song beat rate {:.2} (goal 0.75..1.25 or 0.375..0.625); skate goal ≤ {:.1} (paced: each bar's own source clip at the bar's speed) / {:.1} (strictest: each bar's own source clip at its own speed) / {:.1} (loose: its kinds' source clips); generate {:.0} ms",
            "",
            grid.bpm,
            grid.beats_per_bar,
            gen.beats.bas_music - rm(&|q| q.beats.bas_music),
            gen.beats.bas_music - gen.beats.bas_music_shifted,
            gen.beats.kinetic_beats_per_sec / gen.beats.music_beats_per_sec.max(1e-6),
            chosen.iter().enumerate().filter_map(|(t, s)| s.map(|s| {
                let seg = &lib.segments()[s];
                seg.clip_skate_cm_per_s * odori_core::choreo::bar_count_rate_bpm(bars[t].duration_secs()) / seg.tempo_bpm.max(1e-3)
            })).sum::<f32>() / chosen.iter().flatten().count().max(1) as f32,
            chosen.iter().flatten().map(|&s| lib.segments()[s].clip_skate_cm_per_s).sum::<f32>() / chosen.iter().flatten().count().max(1) as f32,
            (imported as f32 * mean(&skate_imp) + (bars.len() - imported) as f32 * mean(&skate_bi)) / bars.len().max(1) as f32,
            generate_ms
        );
        let (g0, g1) = (goals(&gen, rm(&|q| q.beats.bas_music)), goals(&held, rm_held));
        let mark = |g: [bool; 4]| g.iter().map(|&b| if b { '✓' } else { '✗' }).collect::<String>();
        println!(
            "{:<44}   held: BASm {:.3} (random held {:.3}, shifted {:.3}); margins {:+.3} / {:+.3}; kinetic/song {:.2}; skate {:.1}/{:.1} (unheld {:.1}/{:.1}); PFC {:.2}; jump {:.2}/{:.2}; goals rnd/shift/rate/jump unheld {} held {}; render {:.0} ms held, {:.0} ms unheld",
            "",
            held.beats.bas_music,
            rm_held,
            held.beats.bas_music_shifted,
            held.beats.bas_music - rm_held,
            held.beats.bas_music - held.beats.bas_music_shifted,
            held.beats.kinetic_beats_per_sec / held.beats.music_beats_per_sec.max(1e-6),
            held.foot_skate.mean_cm_per_s,
            held.foot_skate.p95_cm_per_s,
            gen.foot_skate.mean_cm_per_s,
            gen.foot_skate.p95_cm_per_s,
            held.pfc,
            held.join_jump_mean,
            held.join_jump_max,
            mark(g0),
            mark(g1),
            held_ms,
            unheld_ms
        );
        pieces += 1;
        skate_ok += usize::from(held.foot_skate.mean_cm_per_s <= gen.foot_skate.mean_cm_per_s);
        if (0..4).all(|k| !g0[k] || g1[k]) {
            goals_kept += 1;
        } else {
            goals_lost.push(name.to_string());
        }
    }

    println!(
        "\nheld feet: skate held ≤ unheld on {skate_ok}/{pieces} pieces; every goal met unheld still met held on {goals_kept}/{pieces}{}",
        if goals_lost.is_empty() { String::new() } else { format!(" (not on: {})", goals_lost.join(", ")) }
    );
    println!("render of the longest dance ({longest:.0} s): {render_held_ms:.0} ms held, {render_unheld_ms:.0} ms unheld ({:.1}x)", render_held_ms / render_unheld_ms.max(1e-9));
    let tempo_of = |name: &str| lib.clips().iter().find(|c| c.clip.source.contains(name)).map(|c| c.tempo_bpm);
    for (a, b) in [("salsa_01", "salsa_16"), ("salsa_10", "salsa_25")] {
        match (tempo_of(a), tempo_of(b)) {
            (Some(x), Some(y)) => println!("  {a} {x:.1} vs {b} {y:.1}: differ by {:.1} % (goal ≤ 3 %)", 100.0 * (x - y).abs() / x.min(y)),
            _ => println!("  {a}/{b}: not both in the library"),
        }
    }
    println!("total {:.1} s", t.elapsed().as_secs_f64());
}
