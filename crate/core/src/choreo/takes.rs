//! Another take (issue 26, [`super::generate::GenerateOptions::take`]): take k > 0 runs the whole
//! pipeline on the objective plus a penalty on the moves the earlier takes' dances chose in each
//! bar (and on their other sides: a built-in move mirrored costs and measures the same, so it is
//! not another move), the weakest penalty of [`TAKE_LADDER`] that makes it differ from each
//! earlier take in at least [`TAKE_DIFFER`] of the open bars while its objective stays within
//! [`TAKE_SLACK`] of the best, it keeps take 0's beat-rate band (when take 0 is in it) and it
//! meets the join goal, measured as the dance is played (feet held, joins blended: what stages 4b
//! and 5 and the viewer see); take 0 is the dance without it.

use std::collections::HashMap;

use super::fill::{in_beat_rate_band, FillError, Layer};
use super::figures::{dance_figures_with, played_figures_with, DanceFigures};
use super::profile;
use super::segment::SegmentLibrary;
use crate::library::MoveInfo;
use super::generate::{builtin_why, fill_stage, stages, BuiltinWhy, GenerateOptions, Problem};

/// The largest take [`GenerateOptions::take`] accepts: take k makes the k takes before it
/// first (the whole pipeline each), so its time grows with k.
pub const MAX_TAKE: u32 = 15;
/// Penalties tried per bar on an earlier take's move, as multiples of the best path's mean
/// cost per open bar, weakest first ([`takes`]).
pub const TAKE_LADDER: [f32; 7] = [0.05, 0.1, 0.2, 0.3, 0.5, 0.75, 1.0];
/// The share of open bars a take should differ in from each earlier take.
pub const TAKE_DIFFER: f32 = 0.5;
/// How far above the best path's objective a take's may be (a fraction of it).
pub const TAKE_SLACK: f32 = 0.1;

/// Per segment, its built-in move's other side (the same move led by the other side, mirrored),
/// if the library holds it: a take of every move's other side costs what take 0 costs and
/// measures the same, so it is the same dance to the eye, not another take. One pass over the
/// library into a map by move (the first segment of each), then a look-up per segment.
pub(crate) fn other_sides(lib: &SegmentLibrary) -> Vec<Option<usize>> {
    let segments = lib.segments();
    let mut by_move: HashMap<MoveInfo, usize> = HashMap::new();
    for s in segments {
        if let Some(info) = s.builtin {
            by_move.entry(info).or_insert(s.index);
        }
    }
    segments.iter().map(|s| s.builtin.and_then(|info| by_move.get(&MoveInfo { mirrored: !info.mirrored, ..info }).copied())).collect()
}

/// The share of `open` bars in which paths `a` and `b` differ: by more than a built-in move's
/// side (`sides`, [`other_sides`]).
fn differ(a: &[usize], b: &[usize], open: &[usize], sides: &[Option<usize>]) -> f32 {
    let same = |t: usize| match (a.get(t), b.get(t)) {
        (Some(&x), Some(&y)) => x == y || sides.get(x).copied().flatten() == Some(y),
        (x, y) => x == y,
    };
    open.iter().filter(|&&t| !same(t)).count() as f32 / open.len().max(1) as f32
}

/// `penalty` on each move `earlier` dances chose in each open bar, and on its other side
/// (`sides`), per bar and segment.
fn take_penalty(p: &Problem, earlier: &[Vec<usize>], open: &[usize], penalty: f32, sides: &[Option<usize>]) -> Vec<Vec<f32>> {
    let mut m = vec![vec![0.0f32; p.lib.len()]; p.layers.len()];
    for path in earlier {
        for &t in open {
            let Some(&s) = path.get(t) else { continue };
            for u in std::iter::once(s).chain(sides.get(s).copied().flatten()) {
                if let Some(c) = m[t].get_mut(u) {
                    *c += penalty;
                }
            }
        }
    }
    m
}

/// One take's dance on `p` whose base is `base` (stages 1 to 5), and why each of its built-in
/// bars is ([`builtin_why`]).
fn take_dance(p: &mut Problem, options: &GenerateOptions, base: Vec<Vec<f32>>) -> Result<(Vec<usize>, Vec<Option<BuiltinWhy>>), FillError> {
    p.base = base;
    let path = profile::stage("1 fill", || fill_stage(p))?;
    let path = stages(p, options, path)?.0;
    let why = builtin_why(p, &path);
    Ok((path, why))
}

/// Takes 0 to `take` in order (issue 26, [`GenerateOptions::take`]); returns the last. Take 0 is
/// the pipeline on `p`. Take k > 0 adds a penalty on the move each earlier take's dance (as the
/// whole pipeline made it) chose in each open bar: of [`TAKE_LADDER`] (times take 0's mean cost
/// per open bar; also on that move's other side, [`other_sides`]), weakest first, the first whose
/// shortest path differs from every earlier take in at least [`TAKE_DIFFER`] of the open bars
/// (by more than a move's side) and whose dance, after every stage, does too,
/// with objectives within [`TAKE_SLACK`] of take 0's shortest path's, and whose kinetic beats per
/// count stay in [`super::BEAT_RATE_BAND`] when take 0's are and whose joins stay within
/// [`GenerateOptions::join_jump_goal`] (every dance's goal, §J), both measured as the dance is played
/// ([`played_figures_with`], with [`GenerateOptions::measure_played`]; unheld without it).
/// When none does, of the dances made, the one that keeps the most of those goals (the band
/// first, then the joins; among those missing the joins, the smoothest worst join; else the
/// last made), or the weakest penalty's when none was made. Pinned bars never change, so they
/// never differ. Take k runs the pipeline at least k + 1 times.
pub fn takes(p: &mut Problem, options: &GenerateOptions, take: u32) -> Result<Vec<usize>, FillError> {
    Ok(takes_explained(p, options, take)?.0)
}

/// [`takes`], with why each built-in bar of the take is ([`BuiltinWhy`]).
pub fn takes_explained(p: &mut Problem, options: &GenerateOptions, take: u32) -> Result<(Vec<usize>, Vec<Option<BuiltinWhy>>), FillError> {
    let base = p.base.clone();
    let sides = if take > 0 { other_sides(p.lib) } else { Vec::new() };
    let open: Vec<usize> = p.layers.iter().enumerate().filter(|(_, l)| matches!(l, Layer::Open { .. })).map(|(t, _)| t).collect();
    // Take 0 needs no reference (its shortest path is the first stage's own, filled there).
    let best = if take > 0 { profile::stage("takes", || fill_stage(p)).map(|q| p.objective(&q))? } else { 0.0 };
    let per_bar = if best.is_finite() && best > 0.0 { best / open.len().max(1) as f32 } else { 1.0 };
    let within = |obj: f32| obj <= best * (1.0 + TAKE_SLACK) + 1e-6;
    let (zero, zero_why) = take_dance(p, options, base.clone())?;
    let mut earlier: Vec<Vec<usize>> = vec![zero];
    let mut whys = vec![zero_why];
    // A take keeps take 0's beat-rate band and meets the join goal, measured as stages
    // 4b and 5 measure (as played: the test's and the viewer's measure; a take of the demo piece
    // in 3 at 126 BPM joined at 2.93, then 2.81, while its unheld check read take 0's goal kept).
    let (lib, bars, quick) = (p.lib, p.bars, p.quick_measures);
    let measure = |d: &[usize]| -> Option<DanceFigures> {
        if options.measure_played {
            played_figures_with(lib, bars, d, quick).map(|f| f.whole)
        } else {
            dance_figures_with(lib, bars, d, quick)
        }
    };
    let goal = options.join_jump_goal;
    let figures0 = if take > 0 { measure(&earlier[0]) } else { None };
    let band0 = figures0.is_none_or(|f| in_beat_rate_band(f.kinetic_per_count));
    // What a take meets: (take 0's beat-rate band, true where take 0 missed it; §J's join goal,
    // every dance's: a take of Vibe Ace joined at 1.60 when only take 0's goals were asked, its
    // take 0 at 1.59).
    let keeps = |f: Option<DanceFigures>| f.map_or((true, true), |f| (!band0 || in_beat_rate_band(f.kinetic_per_count), f.join_jump_max <= goal));
    for _ in 0..take {
        let least = |q: &[usize], earlier: &[Vec<usize>]| earlier.iter().map(|e| differ(q, e, &open, &sides)).fold(1.0f32, f32::min);
        // The dance to fall back on: what it keeps of take 0's goals, its worst join, it.
        #[allow(clippy::type_complexity)]
        let mut chosen: Option<((bool, bool), f32, Vec<usize>, Vec<Option<BuiltinWhy>>)> = None;
        for f in TAKE_LADDER {
            p.base = base.clone();
            let penalty = take_penalty(p, &earlier, &open, f * per_bar, &sides);
            let charged = p.with_base(&penalty).into_owned();
            p.base = charged.clone();
            let first = fill_stage(p)?;
            if !within(p.objective(&first)) {
                break;
            }
            if least(&first, &earlier) < TAKE_DIFFER {
                continue;
            }
            let (dance, why) = take_dance(p, options, charged)?;
            let figures = measure(&dance);
            let kept = keeps(figures);
            let join = figures.map_or(0.0, |f| f.join_jump_max);
            let done = within(p.objective(&dance)) && least(&dance, &earlier) >= TAKE_DIFFER && kept == (true, true);
            // A dance keeping more of take 0's goals replaces one keeping fewer (the band counts
            // first), not the other way round; of two missing the joins, the smoother stays.
            let better = chosen.as_ref().is_none_or(|c| kept > c.0 || (kept == c.0 && (kept.1 || join < c.1)));
            if better {
                chosen = Some((kept, join, dance, why));
            }
            if done {
                break;
            }
        }
        let (dance, why) = match chosen {
            Some((_, _, d, w)) => (d, w),
            None => {
                p.base = base.clone();
                let penalty = take_penalty(p, &earlier, &open, TAKE_LADDER[0] * per_bar, &sides);
                let charged = p.with_base(&penalty).into_owned();
                take_dance(p, options, charged)?
            }
        };
        earlier.push(dance);
        whys.push(why);
    }
    p.base = base;
    Ok((earlier.pop().unwrap_or_default(), whys.pop().unwrap_or_default()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_built_in_move_has_its_other_side_and_a_side_is_no_difference() {
        let lib = SegmentLibrary::builtin();
        let sides = other_sides(&lib);
        for s in lib.segments().iter().filter(|s| s.builtin.is_some()) {
            let o = sides[s.index].unwrap_or_else(|| panic!("{}: no other side", s.index));
            let (a, b) = (s.builtin.unwrap(), lib.segments()[o].builtin.unwrap());
            assert!(o != s.index && a.mirrored != b.mirrored && MoveInfo { mirrored: a.mirrored, ..b } == a, "{a:?} against {b:?}");
            assert_eq!(sides[o], Some(s.index), "the other side's other side is the move");
        }
        // Two bars: the other side in the first, another move in the second.
        let (s, o) = (0, sides[0].unwrap());
        let other = (1..lib.len()).find(|&u| u != o && Some(u) != sides[o]).unwrap();
        assert_eq!(differ(&[s, s], &[o, s], &[0, 1], &sides), 0.0);
        assert_eq!(differ(&[s, s], &[o, other], &[0, 1], &sides), 0.5);
        // The control: by segment alone, the other side counts as a difference.
        assert_eq!(differ(&[s, s], &[o, s], &[0, 1], &[]), 0.5);
    }
}
