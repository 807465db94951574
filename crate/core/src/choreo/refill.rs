//! Windowed refills (issue 26's speed goal, [`super::generate::GenerateOptions::windowed_refills`]):
//! a refill of the preference order or the join repair changes the cost of a few bars (a move
//! barred in the bars that hold it, a bar opened to built-in moves), so only the bars around
//! them are filled again, the rest kept as the dance had them (pinned for that fill).
//!
//! What is local and what is not: the shortest path over a window whose neighbours are fixed is
//! the exact shortest path of the whole dance for every term that is a sum over nodes and edges
//! (music, beat fit, stretch, beat rate, skate, the stage's costs, the joins' table cost). Two
//! terms reach further: the repeat window ([`super::FillWeights::repeat_window`] bars back) and
//! the variety count ([`super::variety::VARIETY_WINDOW`] bars back). The window runs that far
//! (plus one) past each changed bar on both sides, so every bar whose charge such a change can
//! alter is open in the window and pays it; the charges of the bars beyond (fixed) do not depend
//! on the window's choices. What a window cannot see: a cheaper path that changes bars far from
//! every changed bar (the whole-dance optimum can move when costs change anywhere); a refill
//! that changes the weights of every bar (the skate ladder's next weight) is a whole fill.

use super::fill::{fill_with_tempi, FillError, FillWeights, Layer};
use super::generate::Problem;
use super::profile::{self, Work};
use super::variety::VARIETY_WINDOW;

/// Bars each side of a changed bar a windowed refill reopens (beyond the reach of the repeat
/// window or the variety count, whichever is longer).
pub fn margin_bars(weights: &FillWeights) -> usize {
    weights.repeat_window.max(VARIETY_WINDOW) + 1
}

/// The layers of a windowed refill of `path`: open (as `p`'s layers have it) within
/// [`margin_bars`] of a bar of `changed`, pinned to `path`'s move elsewhere.
pub fn window_layers(p: &Problem, weights: &FillWeights, path: &[usize], changed: &[usize]) -> Vec<Layer> {
    let w = margin_bars(weights);
    let n = p.layers.len();
    let mut open = vec![false; n];
    for &c in changed.iter().filter(|&&c| c < n) {
        for o in open.iter_mut().take((c + w + 1).min(n)).skip(c.saturating_sub(w)) {
            *o = true;
        }
    }
    p.layers
        .iter()
        .enumerate()
        .map(|(t, l)| match (l, path.get(t)) {
            (Layer::Open { .. }, Some(&segment)) if !open[t] => Layer::Fixed { segment },
            _ => *l,
        })
        .collect()
}

impl Problem<'_> {
    /// The minimum-cost path with `weights` and `extra` costs (the problem's base added) over
    /// the bars within [`margin_bars`] of `changed`, the others kept as `path` has them. With
    /// no bar changed, `path` itself.
    pub(super) fn fill_window(&self, weights: &FillWeights, extra: &[Vec<f32>], path: &[usize], changed: &[usize]) -> Result<Vec<usize>, FillError> {
        if changed.is_empty() || path.len() != self.layers.len() {
            return Ok(path.to_vec());
        }
        let layers = window_layers(self, weights, path, changed);
        let extra = self.with_base(extra);
        profile::timed(Work::Fill, || Ok(fill_with_tempi(&self.table, &layers, &self.intensity, &self.node_cost, &self.tempi(&extra), weights)?.0))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::choreo::generate::{fill_stage, GenerateOptions};
    use crate::choreo::grid::bars_from_tempo;
    use crate::choreo::segment::SegmentLibrary;

    #[test]
    fn a_window_refills_only_the_bars_near_a_change_and_a_whole_window_is_the_whole_fill() {
        let lib = SegmentLibrary::builtin();
        let secs = 24.0 * 2.0 + 0.01;
        let bars = bars_from_tempo(secs, 120.0, 4, 0.0, |a, _| (a / secs).clamp(0.0, 1.0)).unwrap();
        let layers: Vec<Layer> = bars.iter().map(|b| Layer::Open { intensity: b.intensity }).collect();
        // Every term local (repeat window 1, no variety count): the shortest path is exact.
        let exact = FillWeights { repeat_window: 1, ..FillWeights::default() };
        let p = Problem::new(&lib, &bars, &layers, exact, &GenerateOptions { variety_weight: 0.0, ..GenerateOptions::default() });
        let path = fill_stage(&p).unwrap();
        let w = margin_bars(&p.weights);
        let d = FillWeights::default();
        assert!(margin_bars(&d) > d.repeat_window && margin_bars(&d) > VARIETY_WINDOW && w > VARIETY_WINDOW);
        // Nothing changed: the path as it was.
        assert_eq!(p.fill_window(&p.weights, &[], &path, &[]).unwrap(), path);
        // Bar 12's move barred there: it takes another, and no bar further than the margin moves.
        let mut barred = vec![vec![0.0f32; lib.len()]; bars.len()];
        barred[12][path[12]] = 100.0;
        let q = p.fill_window(&p.weights, &barred, &path, &[12]).unwrap();
        assert_ne!(q[12], path[12]);
        for t in (0..bars.len()).filter(|&t| t.abs_diff(12) > w) {
            assert_eq!(q[t], path[t], "bar {t}, outside the window, moved");
        }
        // Its cost with the bar: no higher than the path's own with the bar barred, and every
        // window path tried from the reference (the path with bar 12 alone changed) is no cheaper.
        let cost = |r: &[usize]| crate::choreo::fill::path_cost_with_tempi(&p.table, p.layers, &p.intensity, &p.node_cost, &p.tempi(&p.with_base(&barred)), &p.weights, r);
        for s in (0..lib.len()).filter(|&s| s != path[12]) {
            let mut r = path.clone();
            r[12] = s;
            assert!(cost(&q) <= cost(&r) + 1e-4, "bar 12 → segment {s} is cheaper than the window's path");
        }
        // A window over every bar is the whole fill.
        let all: Vec<usize> = (0..bars.len()).collect();
        let whole = crate::choreo::fill::fill_with_tempi(&p.table, p.layers, &p.intensity, &p.node_cost, &p.tempi(&p.with_base(&barred)), &p.weights).unwrap().0;
        assert_eq!(p.fill_window(&p.weights, &barred, &path, &all).unwrap(), whole);
    }
}
