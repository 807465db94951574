//! Stage 4b of Generate ([`super`]), the preference order of issue 26: under *my moves*, a bar
//! takes a built-in move only where the imported moves tried there miss the beat or join goal as
//! the dance is played, and says why ([`BuiltinWhy`]). A child of `generate` (it reads the
//! [`Problem`]'s own fields), split out to keep each core file under 1,200 lines.

use super::*;

/// The share of its bars a dance keeps imported when [`order_stage`] opens bars to built-in
/// moves, where the first fill had it (issue 26's Acceptance: at least half the bars from the
/// person's clips): the stage opens at most as many bars as keep it.
pub const ORDER_IMPORTED_FLOOR: f32 = 0.5;

/// Rounds of [`order_stage`]: in each, the bars still missing a goal first try another imported
/// move, then open to built-in moves.
pub const ORDER_ROUNDS: usize = 2;

/// Stage 4b, the preference order of issue 26 (built-in moves fill only where no imported move
/// does; [`GenerateOptions::follow_order`], under [`MovesSource::Mine`] with imported moves of
/// the bar's count in the library). The first fill keeps built-in moves out of those bars (the
/// source's charge); this stage measures the dance as it is played ([`played_figures`]) and
/// finds the bars whose imported move misses a goal there: off its counts by the strip's rule
/// (BAS-music on the counts less than [`OFF_BEAT_MARGIN`] above on the half-shifted counts), or
/// a join at its start over [`GenerateOptions::join_jump_goal`]. Each round, (1) those bars
/// bar their move and refill (another imported move tried), then (2) the bars still missing
/// open to built-in moves (the charge lifted there, so both kinds compete on the objective),
/// the furthest from their goal first, at most as many as keep [`ORDER_IMPORTED_FLOOR`] of the
/// dance's bars imported; a refill is kept only when fewer bars miss (or as many, by less) and
/// the whole dance's BAS-music on its counts is no lower (fewer bars off their counts alone
/// let the 138 BPM drum take fall from 0.707 to 0.673 with half the person's files).
/// Returns the dance, the cost to add to every later fill (the bars barred and opened) and,
/// per bar, why it was opened.
pub fn order_stage(p: &Problem, weights: &FillWeights, options: &GenerateOptions, path: Vec<usize>, measured: &mut Measured) -> Result<(Vec<usize>, Vec<Vec<f32>>, Vec<Option<BuiltinWhy>>), FillError> {
    let n = p.layers.len();
    let mut why: Vec<Option<BuiltinWhy>> = vec![None; n];
    let charged: Vec<bool> = (0..n).map(|t| p.charge.get(t).is_some_and(|r| r.iter().any(|&c| c > 0.0))).collect();
    if !options.follow_order || p.weights.moves_source != MovesSource::Mine || !charged.iter().any(|&c| c) {
        return Ok((path, Vec::new(), why));
    }
    let imported = |s: usize| p.lib.segments().get(s).is_some_and(|seg| seg.builtin.is_none());
    let goal = options.join_jump_goal;
    // The bars whose imported move misses a goal as played: why, and how far (the beat
    // margin's shortfall, or the join's excess as a share of the goal).
    let misses = |q: &[usize], bars: &[PlayedBar]| -> Vec<(usize, BuiltinWhy, f32)> {
        (0..n)
            .filter(|&t| charged[t] && q.get(t).is_some_and(|&s| imported(s)))
            .filter_map(|t| {
                let b = bars.get(t)?;
                let beat = OFF_BEAT_MARGIN - b.beat_margin;
                let join = b.join_jump.map_or(0.0, |j| (j - goal) / goal.max(1e-3));
                if beat > 0.0 {
                    Some((t, BuiltinWhy::OffBeat, beat))
                } else if join > 0.0 {
                    Some((t, BuiltinWhy::RoughJoin, join))
                } else {
                    None
                }
            })
            .collect()
    };
    let score = |m: &[(usize, BuiltinWhy, f32)]| (m.len(), m.iter().map(|x| x.2).sum::<f32>());
    let better = |a: &[(usize, BuiltinWhy, f32)], b: &[(usize, BuiltinWhy, f32)]| {
        let (sa, sb) = (score(a), score(b));
        sa.0 < sb.0 || (sa.0 == sb.0 && sa.1 < sb.1 - 1e-6)
    };
    let count_imported = |q: &[usize]| q.iter().filter(|&&s| imported(s)).count();
    let floor = (ORDER_IMPORTED_FLOOR * n as f32).ceil() as usize;
    let Some(first) = measured.played(p, &path) else { return Ok((path, Vec::new(), why)) };
    let mut best_miss = misses(&path, &first.bars);
    let mut best_bas = first.bas_music;
    // What the dance met, kept: the beat-rate band and §N's skate goal (each bar's source clip
    // at the bar's pace), as played; and feet sliding no more than before the stage unless
    // still under the source clips' both paced and unpaced (the paced goal alone let the 150 BPM
    // demo piece in 3 slide 34.8 → 49.6 cm/s, and the 96 → 120 BPM one 30.1 → 38.8, past their
    // source clips' 36.2, for a BAS-music they did not need: beat alignment is a floor, §J;
    // `choreo_beats`).
    let on_beat = in_beat_rate_band(first.whole.kinetic_per_count);
    let skate_met = first.whole.foot_skate_cm_per_s <= p.paced_source_skate_cm_per_s(&path);
    let first_skate = first.whole.foot_skate_cm_per_s;
    let keeps = |q: &[usize], f: &Played| {
        let cap = first_skate.max(p.paced_source_skate_cm_per_s(q).min(p.source_skate_cm_per_s(q)));
        (!on_beat || in_beat_rate_band(f.whole.kinetic_per_count))
            && (!skate_met || f.whole.foot_skate_cm_per_s <= p.paced_source_skate_cm_per_s(q))
            && f.whole.foot_skate_cm_per_s <= cap
    };
    // Whether a refill `q` with figures `f` and misses `m` is kept over `best`: fewer misses (or
    // as many, by less), BAS-music no lower, what the dance met kept, and the floor of imported
    // bars.
    let accepts = |q: &[usize], f: &Played, m: &[(usize, BuiltinWhy, f32)], best: &[usize], best_miss: &[(usize, BuiltinWhy, f32)], best_bas: f32| {
        better(m, best_miss) && f.bas_music >= best_bas - 1e-4 && keeps(q, f) && count_imported(q) >= floor.min(count_imported(best))
    };
    // A refill's figures: screened near its changes ([`Measured::screened`]), and measured whole
    // when the screen would keep it (so a dance is kept only by its whole measure).
    let screen = |measured: &mut Measured, q: &[usize], best: &[usize], best_miss: &[(usize, BuiltinWhy, f32)], best_bas: f32| -> Option<Played> {
        let f = measured.screened(p, q)?;
        if measured.is_near(q) && accepts(q, &f, &misses(q, &f.bars), best, best_miss, best_bas) {
            return measured.played(p, q);
        }
        Some(f)
    };
    let mut best = path;
    if best_miss.is_empty() {
        return Ok((best, Vec::new(), why));
    }
    let mut extra: Vec<Vec<f32>> = vec![vec![0.0; p.lib.len()]; n];
    let mut opened = vec![false; n];
    // The last refill tried and its misses: its missing moves are barred too, kept or not, so
    // a round never repeats the last one's refill.
    let (mut last, mut last_miss) = (best.clone(), best_miss.clone());
    for _ in 0..ORDER_ROUNDS {
        // (1) Another imported move: each missing bar's move barred there.
        let mut tried = extra.clone();
        for (q, m) in [(&best, &best_miss), (&last, &last_miss)] {
            for &(t, _, _) in m {
                if let Some(c) = tried.get_mut(t).and_then(|row| row.get_mut(q[t])) {
                    *c = JOIN_BAN;
                }
            }
        }
        let q = if options.windowed_refills {
            let changed: Vec<usize> = best_miss.iter().chain(&last_miss).map(|m| m.0).collect();
            p.fill_window(weights, &tried, &best, &changed)?
        } else {
            p.fill(weights, &tried)?
        };
        if let Some(f) = screen(measured, &q, &best, &best_miss, best_bas) {
            let m = misses(&q, &f.bars);
            (last, last_miss) = (q.clone(), m.clone());
            if accepts(&q, &f, &m, &best, &best_miss, best_bas) {
                (best, best_miss, best_bas, extra) = (q, m, f.bas_music, tried);
            }
        }
        if best_miss.is_empty() {
            break;
        }
        // (2) Built-in moves where it still misses, the furthest first, within the floor.
        let room = count_imported(&best).saturating_sub(floor);
        let mut order = best_miss.clone();
        order.sort_by(|a, b| b.2.total_cmp(&a.2).then(a.0.cmp(&b.0)));
        let newly: Vec<(usize, BuiltinWhy)> = order.iter().filter(|m| !opened[m.0]).take(room).map(|m| (m.0, m.1)).collect();
        if newly.is_empty() {
            break;
        }
        let mut tried = extra.clone();
        for &(t, _) in &newly {
            p.lift_charge(&mut tried, t);
        }
        let q = if options.windowed_refills {
            let changed: Vec<usize> = newly.iter().map(|m| m.0).collect();
            p.fill_window(weights, &tried, &best, &changed)?
        } else {
            p.fill(weights, &tried)?
        };
        if let Some(f) = screen(measured, &q, &best, &best_miss, best_bas) {
            let m = misses(&q, &f.bars);
            if accepts(&q, &f, &m, &best, &best_miss, best_bas) {
                (best, best_miss, best_bas, extra) = (q, m, f.bas_music, tried);
                for &(t, w) in &newly {
                    opened[t] = true;
                    why[t] = Some(w);
                }
            }
        }
        if best_miss.is_empty() {
            break;
        }
    }
    Ok((best, extra, why))
}
