//! Join points within a count of the bar line (issue 26 item 1, spec §G and §J;
//! [`odori_core::choreo::switch`]): each dance the person's library makes (the libraries and
//! songs of `choreo_my_moves`: every humanoid dance clip in ../shared/data/mocap but the
//! martial-arts negatives and the walk 005_01, and RobotExpressive's Dance, all files and each
//! half; every song in ../shared/data/music, the drum take and the demo pieces: 30 dances) is
//! generated once at default settings and rendered twice in the same run, as it is played
//! (blended, feet held): with the join points chosen ([`RenderOptions::join_points`]) and with
//! every switch on the bar line (the control). Each is measured where its joins fall
//! ([`render_switched`], [`dance_quality_switched`]): worst join per dance, dances with a join
//! over 1.5 (§J's goal), BAS-music against random moves (+0.05) and the half-shifted beats
//! (+0.10), kinetic beats per count, foot skate; printed per dance and in all.
//! (The built-in library gains nothing: a built-in move is its whole clip, so its joins stay on
//! the bar line.)
//!
//! Asserted: the dances' worst joins are smoother on average than the control's. Not asserted,
//! printed (and why the option is not the default, `docs/benchmarks-notes-choreo.md`): dances
//! over 1.5, beat goals lost, skate. `ODORI_ONLY=s` keeps the songs
//! whose label contains s; `ODORI_HALVES=0` measures the full library alone.


#[path = "person_common.rs"]
mod person_common;

use odori_core::bars::Bar;
use odori_core::choreo::quality::{dance_quality_switched, DanceQuality};
use odori_core::choreo::{render_switched, RenderOptions, SegmentLibrary};
use odori_core::music::{analyze, AnalysisOptions, RmsEnvelope};
use odori_tests::{random_moves_bas, RANDOM_MOVES_SEED};

/// The person's library of `choreo_my_moves` (`half` keeps every other one of the sorted list).
fn person_library(half: Option<usize>) -> SegmentLibrary {
    person_common::person_library(half).0
}

/// The songs of `choreo_my_moves`.
fn songs() -> Vec<(String, RmsEnvelope)> {
    person_common::songs()
}

/// The dance `choices` as played (feet held), with or without join points, measured at its switches.
fn measured(lib: &SegmentLibrary, bars: &[Bar], beats: &[f32], choices: &[Option<usize>], join_points: bool) -> (DanceQuality, Vec<f32>) {
    let (clip, switches) = render_switched(lib, bars, choices, &RenderOptions { join_points, ..RenderOptions::default() });
    (dance_quality_switched(&clip, bars, beats, &switches).expect("dance quality"), switches)
}

fn beat_goals(q: &DanceQuality, random: f32) -> bool {
    let rate = q.beats.kinetic_beats_per_sec / q.beats.music_beats_per_sec.max(1e-6);
    q.beats.bas_music >= random + 0.05 && q.beats.bas_music >= q.beats.bas_music_shifted + 0.10 && ((0.8..=1.2).contains(&rate) || (0.4..=0.6).contains(&rate))
}

#[test]
fn join_points_near_the_bar_line_against_the_bar_line() {
    let only = std::env::var("ODORI_ONLY").ok();
    let songs: Vec<_> = songs().into_iter().filter(|(l, _)| only.as_deref().is_none_or(|o| l.contains(o))).collect();
    let halves = std::env::var("ODORI_HALVES").map_or(true, |v| v != "0");
    let libraries: Vec<(&str, Option<usize>)> = if halves { vec![("all", None), ("half 0", Some(0)), ("half 1", Some(1))] } else { vec![("all", None)] };
    // (worst join, over the goal, beat goals, skate) per dance: with join points, control.
    let (mut on, mut off): (Vec<(f32, bool, bool, f32)>, Vec<(f32, bool, bool, f32)>) = (Vec::new(), Vec::new());
    let (mut moved, mut joins) = (0usize, 0usize);
    let mut lost = Vec::new();
    for (name, half) in libraries {
        let lib = person_library(half);
        for (label, env) in &songs {
            let grid = analyze(env, &AnalysisOptions::default()).unwrap_or_else(|e| panic!("{label}: {e}"));
            let (bars, beats) = (grid.bars.clone(), grid.beat_times_secs.clone());
            let mut doc = odori_tests::Dance::new(bars.clone());
            doc.generate(&lib).unwrap_or_else(|e| panic!("{label}: {e}"));
            let chosen = doc.segments();
            let random = random_moves_bas(&lib, &bars, &beats, RANDOM_MOVES_SEED);
            let (q, switches) = measured(&lib, &bars, &beats, &chosen, true);
            let (c, line) = measured(&lib, &bars, &beats, &chosen, false);
            assert!(line.iter().zip(&bars[1..]).all(|(s, b)| *s == b.start_secs), "the control switches on the bar line");
            let off_line = switches.iter().zip(&bars[1..]).filter(|(s, b)| (**s - b.start_secs).abs() > 1e-4).count();
            moved += off_line;
            joins += switches.len();
            let (g, gc) = (beat_goals(&q, random), beat_goals(&c, random));
            println!(
                "{name:<6} {label:<44} {:>3} bars, {off_line:>3} joins off the line: join worst {:.2} mean {:.2} (control {:.2} / {:.2}); BAS-music {:.3} shifted {:.3} (control {:.3} / {:.3}, random {random:.3}); kinetic beats/s {:.2} (control {:.2}); skate {:.1} (control {:.1}) cm/s; beat goals {g} (control {gc})",
                bars.len(),
                q.join_jump_max,
                q.join_jump_mean,
                c.join_jump_max,
                c.join_jump_mean,
                q.beats.bas_music,
                q.beats.bas_music_shifted,
                c.beats.bas_music,
                c.beats.bas_music_shifted,
                q.beats.kinetic_beats_per_sec,
                c.beats.kinetic_beats_per_sec,
                q.foot_skate.mean_cm_per_s,
                c.foot_skate.mean_cm_per_s,
            );
            if gc && !g {
                lost.push(format!("{name} {label}"));
            }
            on.push((q.join_jump_max, q.join_jump_max > 1.5, g, q.foot_skate.mean_cm_per_s));
            off.push((c.join_jump_max, c.join_jump_max > 1.5, gc, c.foot_skate.mean_cm_per_s));
        }
    }
    let mean = |v: &[(f32, bool, bool, f32)], f: fn(&(f32, bool, bool, f32)) -> f32| v.iter().map(f).sum::<f32>() / v.len().max(1) as f32;
    let count = |v: &[(f32, bool, bool, f32)], f: fn(&(f32, bool, bool, f32)) -> bool| v.iter().filter(|x| f(x)).count();
    println!(
        "{} dances, {moved} of {joins} joins off the bar line: worst join per dance, mean {:.3} (control {:.3}), largest {:.2} (control {:.2}); dances with a join over 1.5: {} (control {}); on the beat goals: {} (control {}); skate mean {:.1} (control {:.1}) cm/s",
        on.len(),
        mean(&on, |x| x.0),
        mean(&off, |x| x.0),
        on.iter().map(|x| x.0).fold(0.0, f32::max),
        off.iter().map(|x| x.0).fold(0.0, f32::max),
        count(&on, |x| x.1),
        count(&off, |x| x.1),
        count(&on, |x| x.2),
        count(&off, |x| x.2),
        mean(&on, |x| x.3),
        mean(&off, |x| x.3),
    );
    if only.is_some() {
        return;
    }
    // Measured 2026-11-29 (30 dances): the worst join per dance falls on average (1.032 against
    // 1.138), but two dances join over 1.5 (control one), two lose a beat goal (half 1's Sugar
    // Plum and 90→130 BPM piece: BAS-music under random + 0.05) and the feet slide more (34.1
    // against 31.9 cm/s): so the option is not the default (docs/benchmarks-notes-choreo.md).
    // Asserted: what it does gain.
    println!("beat goals lost with join points: {lost:?}");
    assert!(mean(&on, |x| x.0) < mean(&off, |x| x.0), "the dances' worst joins are not smoother on average with join points");
}
