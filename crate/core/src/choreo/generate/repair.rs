//! Stage 5's refills ([`join_repair_stage`]): bars the moves after the joins over the goal and
//! refills, at once then one join a refill, uncharged then with stage 4's skate charge; when
//! those end over the goal, the same again with a wider reach (each barred move's other side
//! barred too, refills windowed). A child of `generate`, split out to keep each core file under
//! 1,200 lines.

use super::*;

/// Stage 5's refills from `path` ([`join_repair_stage`]): uncharged, then, when they end over the
/// join goal and stage 4 kept a skate charge (`carried`), charging it from the first refill; the
/// smoother kept. `wide`: the reach of [`join_repair_stage`]'s last runs (each move barred with
/// its other side, refills windowed).
#[allow(clippy::too_many_arguments)]
pub(super) fn runs(p: &Problem, weights: &FillWeights, options: &GenerateOptions, path: &[usize], cost: f32, carried: f32, measured: &mut Measured, wide: bool) -> Result<(Vec<usize>, f32), FillError> {
    let why = p.why.borrow().clone();
    let options = &GenerateOptions { windowed_refills: options.windowed_refills || wide, ..*options };
    let (q, c) = repairs(p, weights, options, path.to_vec(), cost, measured, 0.0, wide)?;
    let worst = |m: &mut Measured, q: &[usize]| m.figures(p, q, options.measure_played).map_or(f32::INFINITY, |f| f.join_jump_max);
    if carried > 0.0 && worst(measured, &q) > options.join_jump_goal {
        let first_why = std::mem::replace(&mut *p.why.borrow_mut(), why);
        let (r, d) = repairs(p, weights, options, path.to_vec(), cost, measured, carried, wide)?;
        if worst(measured, &r) < worst(measured, &q) {
            return Ok((r, d));
        }
        *p.why.borrow_mut() = first_why;
    }
    Ok((q, c))
}

/// Stage 5's refills from `path`, charging skate at `carried` and heavier weights of
/// [`skate_ladder`] ([`join_repair_stage`]): bans at once first, then one join a refill;
/// `wide`: each barred move's other side barred too ([`Reach`]).
#[allow(clippy::too_many_arguments)]
fn repairs(p: &Problem, weights: &FillWeights, options: &GenerateOptions, path: Vec<usize>, cost: f32, measured: &mut Measured, carried: f32, wide: bool) -> Result<(Vec<usize>, f32), FillError> {
    if options.join_bans_at_once && options.measure_played {
        let why = p.why.borrow().clone();
        let on_beat = measured.figures(p, &path, true).is_some_and(|f| in_beat_rate_band(f.kinetic_per_count));
        let (q, c, f) = repair_pass(p, weights, options, path.clone(), cost, measured, Reach { at_once: true, carried, wide }, options.join_repairs.min(JOIN_BANS_AT_ONCE_TRIES))?;
        // Kept only when it meets every goal the stage follows at the goal itself (not a
        // dance past the skate goal on entry sliding no more than it did).
        let met = f.is_some_and(|f| f.join_jump_max <= options.join_jump_goal && f.foot_skate_cm_per_s <= skate_goal_cm_per_s(p.lib, &q) && (!on_beat || in_beat_rate_band(f.kinetic_per_count)));
        if met {
            return Ok((q, c));
        }
        *p.why.borrow_mut() = why;
    }
    repair_pass(p, weights, options, path, cost, measured, Reach { at_once: false, carried, wide }, options.join_repairs).map(|(q, c, _)| (q, c))
}

/// How one pass of stage 5's refills reaches ([`repair_pass`]).
#[derive(Clone, Copy)]
struct Reach {
    /// Bar the move after every join over the goal in a refill, not only after the worst.
    at_once: bool,
    /// The skate charge each refill keeps at least: 0, or stage 4's kept weight.
    carried: f32,
    /// Each barred built-in move's other side barred with it.
    wide: bool,
}

/// Refills [`GenerateOptions::join_bans_at_once`] tries before stage 5 falls back to one join a
/// refill ([`join_repair_stage`]).
pub const JOIN_BANS_AT_ONCE_TRIES: usize = 4;

/// One pass of [`join_repair_stage`]'s refills, up to `tries`: barring the move after the worst
/// join of the last refill, or after every join over the goal in it (`at_once`), each refill
/// charging skate at least at `carried`. Returns the best dance kept, its cost and its figures.
#[allow(clippy::too_many_arguments)]
fn repair_pass(p: &Problem, weights: &FillWeights, options: &GenerateOptions, path: Vec<usize>, cost: f32, measured: &mut Measured, reach: Reach, tries: usize) -> Result<(Vec<usize>, f32, Option<DanceFigures>), FillError> {
    let Reach { at_once, carried, wide } = reach;
    let (mut path, mut cost) = (path, cost);
    let played = options.measure_played;
    let current = measured.figures(p, &path, played);
    let (mut trial_path, mut trial) = (path.clone(), current);
    let mut best = current;
    let skate_met = current.is_some_and(|f| f.foot_skate_cm_per_s <= skate_goal_cm_per_s(p.lib, &path));
    // The skate a refill may reach: the goal, or, when the dance slid past it already, no more
    // than it did (session 16: a dance 1 cm/s over the goal let every refill slide freely).
    let entry_skate = if skate_met { 0.0 } else { current.map_or(f32::INFINITY, |f| f.foot_skate_cm_per_s) };
    let skate_cap = |q: &[usize]| skate_goal_cm_per_s(p.lib, q).max(entry_skate);
    let on_beat = current.is_some_and(|f| in_beat_rate_band(f.kinetic_per_count));
    let mut ban: Vec<Vec<f32>> = Vec::new();
    // Bars whose imported move missed the join goal, opened to built-in moves (*my moves*).
    let mut opened = vec![false; p.layers.len()];
    // The skate charge carried (0, or stage 4's weight), then the ladder's heavier weights.
    let mut skate_weights = skate_ladder_for(if options.skate_beside_beat_term { p.weights.beat_weight } else { 0.0 }).filter(|&w| w > carried);
    let mut skate_weight = carried;
    // Each built-in move's other side ([`crate::choreo::takes::other_sides`]), made at the first bar.
    let mut sides: Option<Vec<Option<usize>>> = None;
    for _ in 0..tries {
        let Some(f) = trial else { break };
        let joins_ok = f.join_jump_max <= options.join_jump_goal;
        let skate_ok = f.foot_skate_cm_per_s <= skate_cap(&trial_path);
        if joins_ok && skate_ok {
            break;
        }
        if ban.is_empty() {
            ban = vec![vec![0.0; p.lib.len()]; p.layers.len()];
        }
        // The bars whose cost this refill changes (for a windowed refill, [`super::refill`]).
        let mut changed: Vec<usize> = Vec::new();
        let mut reweighted = false;
        if !joins_ok {
            // The bar after the join takes another move (the one before it, when that one is
            // pinned; both pinned: nothing to change): the worst join's, and with
            // `join_bans_at_once` every other join over the goal in the same measure.
            let Some(worst) = f.worst_join_bar else { break };
            let mut over = vec![worst];
            if at_once && played {
                if let Some(pf) = measured.screened(p, &trial_path) {
                    over.extend(pf.bars.iter().enumerate().filter(|(u, b)| *u != worst && b.join_jump.is_some_and(|j| j > options.join_jump_goal)).map(|(u, _)| u));
                }
            }
            let mut banned: Vec<usize> = Vec::new();
            for bar in over {
                let Some(t) = [bar, bar - 1].into_iter().find(|&t| matches!(p.layers[t], Layer::Open { .. })) else { continue };
                let s = trial_path[t];
                // The move and its other side: the mirrored pair joins with the same jump.
                let other = if wide { sides.get_or_insert_with(|| crate::choreo::takes::other_sides(p.lib)).get(s).copied().flatten() } else { None };
                for s in std::iter::once(s).chain(other) {
                    if !banned.contains(&s) {
                        banned.push(s);
                        for v in ban.iter_mut() {
                            v[s] += JOIN_BAN;
                        }
                        changed.extend((0..trial_path.len()).filter(|&u| trial_path[u] == s));
                    }
                }
                if p.weights.moves_source == MovesSource::Mine && p.lib.segments().get(s).is_some_and(|seg| seg.builtin.is_none()) {
                    if !opened[t] && !p.opened.get(t).copied().unwrap_or(false) {
                        changed.push(t);
                    }
                    opened[t] = true;
                    if let Some(w) = p.why.borrow_mut().get_mut(t) {
                        w.get_or_insert(BuiltinWhy::RoughJoin);
                    }
                }
            }
            if banned.is_empty() {
                break;
            }
        }
        if !skate_ok {
            let Some(w) = skate_weights.next() else { break };
            skate_weight = w;
            reweighted = true;
        }
        let mut extra: Vec<Vec<f32>> = ban.iter().enumerate().map(|(t, v)| v.iter().enumerate().map(|(s, b)| b + skate_weight * p.skate_excess(t, s).max(0.0) / 100.0).collect()).collect();
        for t in (0..opened.len()).filter(|&t| opened[t]) {
            p.lift_charge(&mut extra, t);
        }
        let q = if options.windowed_refills && !reweighted { p.fill_window(weights, &extra, &trial_path, &changed)? } else { p.fill(weights, &extra)? };
        let (q, c) = p.free_skate(weights, &extra, &q);
        // Screened first ([`Measured::screened`]: near its changes); measured whole before it is
        // kept or ends the pass.
        let mut after = if played { measured.screened(p, &q).map(|f| f.whole) } else { measured.figures(p, &q, played) };
        if played && measured.is_near(&q) {
            let keeps = after.is_some_and(|a| {
                let within = a.join_jump_max <= options.join_jump_goal && a.foot_skate_cm_per_s <= skate_cap(&q);
                within || best.is_some_and(|b| a.join_jump_max < b.join_jump_max)
            });
            if keeps {
                after = measured.figures(p, &q, played);
            }
        }
        if let (Some(a), Some(b)) = (after, best) {
            // Kept only when its worst join is better and nothing the dance met is lost: the
            // beat rate's band, and the skate goal.
            let keeps_rate = !on_beat || in_beat_rate_band(a.kinetic_per_count);
            let keeps_skate = a.foot_skate_cm_per_s <= skate_cap(&q);
            if a.join_jump_max < b.join_jump_max && keeps_rate && keeps_skate {
                (path, cost, best) = (q.clone(), c, after);
            }
        }
        (trial_path, trial) = (q, after);
    }
    Ok((path, cost, best))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::choreo::grid::bars_from_tempo;
    use crate::choreo::refill::margin_bars;

    #[test]
    fn the_wider_reach_bars_the_other_side_too_and_refills_only_around_it() {
        let lib = SegmentLibrary::builtin();
        // 32 bars: room for bars beyond a window's reach.
        let secs = 32.0 * 2.0 + 0.01;
        let bars = bars_from_tempo(secs, 120.0, 4, 0.0, |a, _| (a / secs).clamp(0.0, 1.0)).unwrap();
        let layers: Vec<Layer> = bars.iter().map(|b| Layer::Open { intensity: b.intensity }).collect();
        let opts = GenerateOptions::default();
        let p = Problem::new(&lib, &bars, &layers, FillWeights::default(), &opts);
        let path = fill_stage(&p).unwrap();
        let f = Measured::default().played(&p, &path).unwrap().whole;
        let t = f.worst_join_bar.unwrap();
        let (after, other) = (path[t], crate::choreo::takes::other_sides(&lib)[path[t]]);
        let other = other.expect("a built-in move has another side");
        // A goal below the worst join: one refill, one join barred, each reach.
        let strict = GenerateOptions { join_jump_goal: f.join_jump_max * 0.5, ..opts };
        let refill = |wide: bool| {
            let o = GenerateOptions { windowed_refills: wide, ..strict };
            let mut m = Measured::default();
            repair_pass(&p, &p.weights, &o, path.clone(), 0.0, &mut m, Reach { at_once: false, carried: 0.0, wide }, 1).unwrap();
            assert!(m.played.len() >= 2, "no refill measured");
            m.played[1].0.clone()
        };
        let wide = refill(true);
        assert!(!wide.contains(&after) && !wide.contains(&other), "the move after the worst join ({after}) or its other side ({other}) is still in {wide:?}");
        // Windowed: a bar beyond the reach of every bar that held the barred move keeps its move.
        // (A refill that charges skate anew is a whole one: this dance is within the goal.)
        assert!(f.foot_skate_cm_per_s <= skate_goal_cm_per_s(&lib, &path), "{f:?}");
        let held: Vec<usize> = (0..path.len()).filter(|&u| path[u] == after || path[u] == other).collect();
        let far = |u: usize| held.iter().all(|&h| u.abs_diff(h) > margin_bars(&p.weights));
        assert!((0..path.len()).filter(|&u| far(u)).all(|u| wide[u] == path[u]), "a bar far from the barred move changed: {path:?} → {wide:?}");
        // The control (the plain reach): the move after the worst join barred alone.
        let plain = refill(false);
        assert!(!plain.contains(&after));
    }
}
