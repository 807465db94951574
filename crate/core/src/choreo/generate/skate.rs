//! Stage 4's measured bans ([`skate_stage`]'s last step): the ladder charges each move's skate
//! as predicted from its own feet at the bar's pace, right on average but not for every cut
//! (`choreo_my_moves`' trumpet loop: a cut predicted at 28.5 cm/s plays at 53.4). When no weight
//! of the ladder brings the dance within the goal, the moves of the bars that slide past their
//! own goal as the dance is played are barred and the dance refilled, as stage 5 does for rough
//! joins. A child of `generate`, split out to keep each core file under 1,200 lines.

use super::*;

/// Refills [`skate_bans`] tries at most (its bars add up over them).
pub const SKATE_BAN_ROUNDS: usize = 3;

/// Stage 4's measured bans, when its ladder reached no dance within the goal and `path`'s dance
/// as played ([`played_figures`]) slides past §N's goal (its bars' source clips at the bars'
/// pace, [`Problem::paced_source_skate_cm_per_s`]): bars from every bar the move of each open
/// bar sliding past its own source clip's skate at the bar's pace as played, and refills; a
/// refill's own sliding moves are barred in the next, up to [`SKATE_BAN_ROUNDS`]. Returns the
/// first refill within stage 4's goal ([`skate_goal_cm_per_s`]) and §N's as played that keeps
/// what `path`'s dance met: the beat-rate band, its bars on their counts as played or its
/// BAS-music as played (stage 4's floor), and its worst join as played within the join goal
/// (or no worse than it was); else `None`.
pub(super) fn skate_bans(p: &Problem, weights: &FillWeights, path: &[usize], measured: &mut Measured) -> Result<Option<(Vec<usize>, f32)>, FillError> {
    let (Some(unheld), Some(played)) = (measured.of(p, path), measured.played(p, path)) else { return Ok(None) };
    // Only a dance that slides past §N's goal as played: its bars' source clips at their pace.
    let paced_met = |q: &[usize], f: &Played| f.whole.foot_skate_cm_per_s <= p.paced_source_skate_cm_per_s(q);
    if paced_met(path, &played) {
        return Ok(None);
    }
    let on_beat = in_beat_rate_band(unheld.kinetic_per_count);
    let off = |f: &Played| f.bars.iter().filter(|b| b.beat_margin < OFF_BEAT_MARGIN).count();
    let (off_before, bas_before) = (off(&played), played.bas_music);
    let join_cap = played.whole.join_jump_max.max(p.join_jump_goal);
    // The moves of the open bars that slide past their own goal as played.
    let sliding = |q: &[usize], f: &Played| -> Vec<usize> {
        (0..q.len())
            .filter(|&t| matches!(p.layers[t], Layer::Open { .. }))
            .filter(|&t| f.bars.get(t).zip(p.lib.segments().get(q[t])).is_some_and(|(b, seg)| b.foot_skate_cm_per_s > seg.clip_skate_at(p.bar_bpm[t])))
            .map(|t| q[t])
            .collect()
    };
    let mut barred = vec![0.0f32; p.lib.len()];
    let (mut q, mut f) = (path.to_vec(), played);
    for _ in 0..SKATE_BAN_ROUNDS {
        let moves = sliding(&q, &f);
        if moves.is_empty() {
            break;
        }
        for s in moves {
            barred[s] = JOIN_BAN;
        }
        let extra = vec![barred.clone(); p.layers.len()];
        let r = p.fill(weights, &extra)?;
        let (r, c) = p.free_skate(weights, &extra, &r);
        let (Some(u), Some(g)) = (measured.of(p, &r), measured.played(p, &r)) else { break };
        let keeps = u.foot_skate_cm_per_s <= skate_goal_cm_per_s(p.lib, &r)
            && paced_met(&r, &g)
            && (!on_beat || in_beat_rate_band(u.kinetic_per_count))
            && (off(&g) <= off_before || g.bas_music >= bas_before)
            && g.whole.join_jump_max <= join_cap;
        if keeps {
            return Ok(Some((r, c)));
        }
        (q, f) = (r, g);
    }
    Ok(None)
}
