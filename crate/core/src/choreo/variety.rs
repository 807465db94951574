//! Variety (issue 26 item 2; spec §G): a cost on nearby bars that share a step, an arm pattern
//! or a source clip, and on a step, arm pattern or move that would hold too much of the dance so
//! far, so no kind of move dominates a dance by accident.
//!
//! Two parts, both charged along each node's path. The window: bar t sharing a kind with bar
//! t − d, d = 1..=[`VARIETY_WINDOW`], costs `weight · VARIETY_DECAY[d − 1]` per kind shared. The
//! share: bar t whose step or arm pattern would then hold more than [`VARIETY_SHARE`] (a third)
//! of bars 0..=t, or whose move was used before while more than [`VARIETY_REUSE`] of them would
//! then repeat a move, costs `weight · VARIETY_SHARE_FACTOR` per such kind (issue 26's goals as
//! caps on every prefix of the dance). The window alone left one arm pattern in 41–50 % of a 4/4
//! dance's bars (an A B A B alternation pays only the decayed charge two bars back, less than the
//! rough joins of moving on), and weights high enough to break that lost the beat; the share
//! counts the whole dance so far (tests/native/choreo_variety.rs).
//!
//! The built-in moves that join a move best share its arms, so the plain shortest path holds one
//! arm pattern for most of a dance; a charge on every bar of a kind alike only swaps it for
//! another, hence charges on nearby repetition and on shares over a cap. The term is
//! path-dependent, like the repeat window ([`super::fill`]'s module docs), and is charged the
//! same way, along each node's chosen path; for a node its best predecessor shares a kind with,
//! the previous bar's cheapest nodes are tried as predecessors with the charge counted (the
//! edge part, d = 1, is then exact among them). The reported objective counts it
//! ([`super::path_cost_with_tempi`]).
//!
//! Kinds: a built-in move's step and arm pattern; an imported segment's source clip, when the
//! library holds two imported clips or more (with one, every imported move shares it: no choice)
//! — built, but off ([`CHARGE_CLIPS`]).
//!
//! With imported moves in the library the term is off (issue 26 item 2 covers the built-in
//! library; the person's moves are item 1's): charging the built-in moves alone tipped mixed
//! dances toward the imported moves, which pay nothing (the drum take with the CMU salsa and
//! Indian clips: imported 0 → 11 of 16 bars, BAS-music 0.922 → 0.616, under random moves' 0.572 +
//! 0.05), and charging the imported clips alike broke a two-bar piece ([`CHARGE_CLIPS`]).
//! A class is charged among the moves of one metre only when it has [`VARIETY_MIN_KINDS`] kinds
//! there: the built-in moves in 3 (5 steps, 3 arm patterns) are left to the repeat window, which
//! keeps any one move under a third of a waltz's bars; charging them cost rough joins (up to
//! 4.8 at 84 BPM) and beat alignment.

use super::segment::SegmentLibrary;
use super::table::TransitionTable;

/// Bars back within which a shared kind is charged.
pub const VARIETY_WINDOW: usize = 3;
/// The share of the weight charged for a kind shared with the bar 1, 2, 3 bars before.
pub const VARIETY_DECAY: [f32; VARIETY_WINDOW] = [1.0, 0.6, 0.3];
/// The fewest kinds a class (steps, arm patterns, clips) needs among the moves of one metre to be
/// charged: one more than twice the window, so a kind can stay out of it with choice to spare.
pub const VARIETY_MIN_KINDS: usize = 2 * VARIETY_WINDOW + 1;
/// The share of the dance so far one step or arm pattern may hold ([`Variety::share_cap`]):
/// issue 26's goal, a third of the bars.
pub const VARIETY_SHARE: f32 = 1.0 / 3.0;
/// The share of the bars so far that may repeat a move used earlier in the dance
/// ([`Variety::reuse_cap`]): issue 26's goal, distinct moves ≥ 0.7 × bars.
pub const VARIETY_REUSE: f32 = 0.3;
/// The charge, as a multiple of the weight, on a bar whose step or arm pattern would hold more
/// than [`VARIETY_SHARE`] of the bars so far (per kind over its cap).
pub const VARIETY_SHARE_FACTOR: f32 = 2.0;
/// Previous-bar nodes (the cheapest) tried as predecessors of a charged node.
pub const VARIETY_TRIED: usize = 64;
/// Whether imported segments' source clips are charged. Off: charging them (every distance, the
/// weight of a step) broke `choreo_beats` on a two-bar piece danced with the CMU salsa and Indian
/// clips (BAS-music 0.560 against random 0.559 + 0.05: the second bar left the first bar's clip),
/// and the person's-moves goals of issue 26 item 1 are the joins work's; kept for when a rule
/// that lets a clip continue across the bar line is measured.
const CHARGE_CLIPS: bool = false;
/// No kind (an imported segment's step and arms; a clip that is the library's only imported one).
const NONE: u32 = u32::MAX;

/// What a path holds: per step and arm pattern its bars, the charged moves it holds (a bit per
/// segment) and its bars of charged moves.
#[derive(Clone, Debug)]
struct Tally {
    kinds: Vec<u16>,
    seen: Vec<u64>,
    moves: u16,
}

/// The kinds of every segment of a library and the weight of sharing one.
#[derive(Clone, Debug, PartialEq)]
pub struct Variety {
    /// Per segment: step, arm pattern, source clip (each [`NONE`] when it has none). Steps and
    /// arms are numbered by name; clips by their index.
    kinds: Vec<[u32; 3]>,
    /// How many step and arm-pattern names there are (their numbers are below it).
    names: usize,
    /// Cost of sharing one kind with the bar before ([`VARIETY_DECAY`] scales it further back).
    pub weight: f32,
}

impl Variety {
    /// The kinds of `lib`'s segments, charged `weight` (0: off).
    pub fn new(lib: &SegmentLibrary, weight: f32) -> Self {
        let mut names: Vec<&'static str> = Vec::new();
        let mut id = |name: &'static str| -> u32 {
            match names.iter().position(|&n| n == name) {
                Some(i) => i as u32,
                None => {
                    names.push(name);
                    names.len() as u32 - 1
                }
            }
        };
        let mut imported_clips: Vec<usize> = lib.segments().iter().filter(|s| s.builtin.is_none()).map(|s| s.clip).collect();
        imported_clips.sort_unstable();
        imported_clips.dedup();
        let clips_vary = imported_clips.len() >= 2;
        let mut kinds: Vec<[u32; 3]> = lib
            .segments()
            .iter()
            .map(|s| match s.builtin {
                Some(m) => [id(m.step.name()), id(m.arms.name()), NONE],
                None => [NONE, NONE, if clips_vary && CHARGE_CLIPS { s.clip as u32 } else { NONE }],
            })
            .collect();
        let names = names.len();
        // With imported moves in the library the term is off for now (see the module docs).
        if lib.segments().iter().any(|s| s.builtin.is_none() && !s.retired) {
            kinds.iter_mut().for_each(|k| *k = [NONE; 3]);
        }
        // A class with few kinds among the moves of one metre (the 3 arm patterns and 5 steps in
        // 3) cannot keep a kind out of the window without rough joins: not charged there.
        let counts: Vec<usize> = lib.segments().iter().map(|s| s.counts()).collect();
        let mut metres = counts.clone();
        metres.sort_unstable();
        metres.dedup();
        for n in metres {
            for class in 0..3 {
                let mut seen: Vec<u32> = lib.segments().iter().filter(|s| !s.retired && s.counts() == n).map(|s| kinds[s.index][class]).filter(|&k| k != NONE).collect();
                seen.sort_unstable();
                seen.dedup();
                if seen.len() < VARIETY_MIN_KINDS {
                    for (k, _) in counts.iter().enumerate().filter(|(_, &c)| c == n) {
                        kinds[k][class] = NONE;
                    }
                }
            }
        }
        Variety { kinds, names, weight: if weight.is_finite() { weight.max(0.0) } else { 0.0 } }
    }

    /// Whether it charges anything (a weight above 0 and some segment of a charged kind).
    pub fn is_on(&self) -> bool {
        self.weight > 0.0 && self.kinds.iter().any(|k| k.iter().any(|&x| x != NONE))
    }

    /// Kinds segments `a` and `b` share.
    fn shared(&self, a: usize, b: usize) -> usize {
        match (self.kinds.get(a), self.kinds.get(b)) {
            (Some(x), Some(y)) => (0..3).filter(|&k| x[k] != NONE && x[k] == y[k]).count(),
            _ => 0,
        }
    }

    /// The charge on bar `t` of `path` (0 for the first bar).
    pub fn charge_in_path(&self, path: &[usize], t: usize) -> f32 {
        if !self.is_on() {
            return 0.0;
        }
        let Some(&b) = path.get(t) else { return 0.0 };
        let window: f32 = (1..=VARIETY_WINDOW.min(t)).map(|d| self.weight * VARIETY_DECAY[d - 1] * self.shared(path[t - d], b) as f32).sum();
        let mut tally = self.tally();
        for &s in &path[..t] {
            self.count(&mut tally, s);
        }
        window + self.share_charge(&tally, t, b)
    }

    /// An empty [`Tally`].
    fn tally(&self) -> Tally {
        Tally { kinds: vec![0; self.names], seen: vec![0; self.kinds.len().div_ceil(64)], moves: 0 }
    }

    /// The most bars of `bars` that may repeat a move used earlier before the share charge:
    /// [`VARIETY_REUSE`] of them.
    pub fn reuse_cap(bars: usize) -> u16 {
        (VARIETY_REUSE * bars as f32 + 1e-4).floor() as u16
    }

    /// Whether segment `s` is charged at all (a step or arm pattern of a charged class).
    fn charged(&self, s: usize) -> bool {
        self.kinds.get(s).is_some_and(|k| k[0] != NONE || k[1] != NONE)
    }

    /// The most bars of `bars` one step or arm pattern may hold before the share charge:
    /// [`VARIETY_SHARE`] of them, at least 1.
    pub fn share_cap(bars: usize) -> u16 {
        ((VARIETY_SHARE * bars as f32 + 1e-4).floor() as u16).max(1)
    }

    /// Adds segment `s` to `tally`.
    fn count(&self, tally: &mut Tally, s: usize) {
        if let Some(k) = self.kinds.get(s) {
            for &x in &k[..2] {
                if let Some(c) = tally.kinds.get_mut(x as usize) {
                    *c = c.saturating_add(1);
                }
            }
        }
        if self.charged(s) {
            tally.moves = tally.moves.saturating_add(1);
            if let Some(w) = tally.seen.get_mut(s / 64) {
                *w |= 1 << (s % 64);
            }
        }
    }

    /// The share charge on segment `b` in bar `t` after bars 0..t (`tally`):
    /// [`VARIETY_SHARE_FACTOR`] × weight per kind of `b`'s that would then hold more than
    /// [`Variety::share_cap`] of the t + 1 bars, and once more when `b` is a move used before
    /// and the bars repeating one would then be more than [`Variety::reuse_cap`] of them.
    fn share_charge(&self, tally: &Tally, t: usize, b: usize) -> f32 {
        let Some(k) = self.kinds.get(b) else { return 0.0 };
        let cap = Self::share_cap(t + 1);
        let mut over = k[..2].iter().filter(|&&x| tally.kinds.get(x as usize).is_some_and(|&c| c.saturating_add(1) > cap)).count();
        if self.charged(b) && tally.seen.get(b / 64).is_some_and(|w| w & (1 << (b % 64)) != 0) {
            let distinct: u32 = tally.seen.iter().map(|w| w.count_ones()).sum();
            let reused = u32::from(tally.moves).saturating_sub(distinct);
            over += usize::from(reused + 1 > u32::from(Self::reuse_cap(t + 1)));
        }
        self.weight * VARIETY_SHARE_FACTOR * over as f32
    }

    /// The step and arm-pattern counts along the best path of node `pred` of layer `t − 1`
    /// (layers 0..t), as [`Variety::charge_on_path`] walks it.
    fn counts_on_path(&self, back: &[Vec<u32>], t: usize, pred: usize) -> Tally {
        let mut counts = self.tally();
        if t == 0 {
            return counts;
        }
        let (mut node, mut layer) = (pred, t - 1);
        loop {
            self.count(&mut counts, node);
            if layer == 0 {
                break;
            }
            let Some(bt) = back.get(layer) else { break };
            node = if bt.len() == 1 { bt[0] as usize } else { bt.get(node).copied().unwrap_or(0) as usize };
            layer -= 1;
        }
        counts
    }

    /// The charge on segment `b` in layer `t` reached from node `pred` of layer `t − 1`, along
    /// that node's best path (`back[l][node]`: the node of layer l − 1 before it; one entry when
    /// layer l − 1 was pinned).
    fn charge_on_path(&self, back: &[Vec<u32>], t: usize, pred: usize, b: usize) -> f32 {
        let (mut node, mut layer, mut c) = (pred, t.saturating_sub(1), 0.0);
        for (d, decay) in VARIETY_DECAY.iter().enumerate() {
            if d > 0 {
                if layer == 0 {
                    break;
                }
                let Some(bt) = back.get(layer) else { break };
                node = if bt.len() == 1 { bt[0] as usize } else { bt.get(node).copied().unwrap_or(0) as usize };
                layer -= 1;
            }
            c += self.weight * decay * self.shared(node, b) as f32;
        }
        c
    }

    /// Adds the charge to an open layer `t` relaxed from an open layer: for every node `b` of
    /// finite cost `next[b]` (its best predecessor `arg[b]`, its own cost `node[b]`), the charge
    /// along its predecessor's path; when that is above 0, the [`VARIETY_TRIED`] cheapest nodes of
    /// `prev` are tried as its predecessor with their charge counted, and the cheapest kept.
    pub(crate) fn relax(&self, table: &TransitionTable, back: &[Vec<u32>], t: usize, prev: &[f32], node: &[f32], next: &mut [f32], arg: &mut [u32]) {
        if !self.is_on() || t == 0 {
            return;
        }
        let mut low: Vec<u32> = (0..prev.len() as u32).filter(|&a| prev[a as usize].is_finite()).collect();
        let l = VARIETY_TRIED.min(low.len());
        if l < low.len() {
            low.select_nth_unstable_by(l, |x, y| prev[*x as usize].total_cmp(&prev[*y as usize]).then(x.cmp(y)));
            low.truncate(l);
        }
        low.sort_unstable();
        // Each reachable previous node's counts along its path (one walk each).
        let counts: Vec<Option<Tally>> = prev.iter().enumerate().map(|(a, p)| p.is_finite().then(|| self.counts_on_path(back, t, a))).collect();
        let charge = |a: usize, b: usize| self.charge_on_path(back, t, a, b) + counts.get(a).and_then(Option::as_ref).map_or(0.0, |c| self.share_charge(c, t, b));
        for b in 0..next.len().min(node.len()) {
            if !next[b].is_finite() {
                continue;
            }
            let first = charge(arg[b] as usize, b);
            if first <= 0.0 {
                continue;
            }
            let (mut best, mut best_a) = (next[b] + first, arg[b]);
            for &a in &low {
                let base = prev[a as usize] + table.cost(a as usize, b) + node[b];
                if base >= best {
                    continue;
                }
                let v = base + charge(a as usize, b);
                if v < best || (v == best && a < best_a) {
                    best = v;
                    best_a = a;
                }
            }
            next[b] = best;
            arg[b] = best_a;
        }
    }

    /// Adds the charge to an open layer `t` after a pinned one (node `a` of layer `t − 1`): every
    /// node's predecessor is `a`.
    pub(crate) fn charge_after_pinned(&self, back: &[Vec<u32>], t: usize, a: usize, next: &mut [f32]) {
        if !self.is_on() {
            return;
        }
        let counts = self.counts_on_path(back, t, a);
        for (b, v) in next.iter_mut().enumerate() {
            if v.is_finite() {
                *v += self.charge_on_path(back, t, a, b) + self.share_charge(&counts, t, b);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::choreo::fill::{fill_with_tempi, path_cost_with_tempi, FillWeights, Layer, Tempi};

    /// Four segments, two kinds (segments 0 and 1 share a kind, 2 and 3 another), every join
    /// alike except 0 → 1 and 1 → 0, the cheapest: without the term the path alternates 0 and 1.
    fn toy() -> (TransitionTable, Variety) {
        let m = 4;
        let costs: Vec<f32> = (0..m * m).map(|i| if (i / m, i % m) == (0, 1) || (i / m, i % m) == (1, 0) { 0.2 } else { 0.5 }).collect();
        let table = TransitionTable::from_costs(m, costs);
        let v = Variety { kinds: vec![[0, NONE, NONE], [0, NONE, NONE], [1, NONE, NONE], [1, NONE, NONE]], names: 2, weight: 0.0 };
        (table, v)
    }

    #[test]
    fn nearby_bars_sharing_a_kind_are_charged_and_the_path_mixes_kinds() {
        let (table, mut v) = toy();
        let layers = [Layer::Open { intensity: 0.5 }; 6];
        let w = FillWeights { repeat_penalty: 0.0, ..FillWeights::default() };
        let off = fill_with_tempi(&table, &layers, &[0.5; 4], &[], &Tempi::default(), &w).unwrap().0;
        assert!(off.iter().all(|&s| s < 2), "without the term one kind holds every bar: {off:?}");
        v.weight = 0.5;
        let tempi = Tempi { variety: Some(&v), ..Tempi::default() };
        let (on, cost, _) = fill_with_tempi(&table, &layers, &[0.5; 4], &[], &tempi, &w).unwrap();
        let of_kind0 = on.iter().filter(|&&s| s < 2).count();
        assert!((2..=4).contains(&of_kind0), "with the term both kinds take bars: {on:?}");
        // The reported cost is the objective with the term, and beats the unvaried path's.
        assert!((cost - path_cost_with_tempi(&table, &layers, &[0.5; 4], &[], &tempi, &w, &on)).abs() < 1e-4);
        assert!(cost < path_cost_with_tempi(&table, &layers, &[0.5; 4], &[], &tempi, &w, &off));
        // The charge on a path: bar 2 of [0, 2, 1] shares its kind with bar 0 (two back), and
        // its kind would hold 2 of 3 bars, over the cap of 1 (a third).
        assert_eq!(Variety::share_cap(3), 1);
        assert!((v.charge_in_path(&[0, 2, 1], 2) - 0.5 * (VARIETY_DECAY[1] + VARIETY_SHARE_FACTOR)).abs() < 1e-6);
        assert_eq!(v.charge_in_path(&[0, 2, 1], 1), 0.0);
        assert_eq!(v.charge_in_path(&[0], 0), 0.0);
        // Past the window: six segments, two of each of three kinds. Bar 5 of
        // [0, 2, 4, 0, 3, ·] shares a kind with bar 2 (three back); its kind would hold 2 of 6
        // bars, at the cap. Segment 5 is new; segment 4 was used in bar 2, and a second bar
        // repeating a move (bar 3 repeats bar 0) is over the reuse cap of 1 (0.3 × 6).
        let v6 = Variety { kinds: (0..6).map(|s| [s / 2, NONE, NONE]).collect(), names: 3, weight: 0.5 };
        assert_eq!((Variety::share_cap(6), Variety::reuse_cap(6)), (2, 1));
        assert!((v6.charge_in_path(&[0, 2, 4, 0, 3, 5], 5) - 0.5 * VARIETY_DECAY[2]).abs() < 1e-6);
        assert!((v6.charge_in_path(&[0, 2, 4, 0, 3, 4], 5) - 0.5 * (VARIETY_DECAY[2] + VARIETY_SHARE_FACTOR)).abs() < 1e-6);
        // With no earlier repeat the reuse is within the cap: [0, 2, 4, 1, 3, 4].
        assert!((v6.charge_in_path(&[0, 2, 4, 1, 3, 4], 5) - 0.5 * VARIETY_DECAY[2]).abs() < 1e-6);
    }

    #[test]
    fn the_built_in_library_has_steps_and_arms_in_4_and_no_clip_kind() {
        let lib = SegmentLibrary::builtin();
        let v = Variety::new(&lib, 1.0);
        assert!(v.is_on());
        // Moves in 3 have too few steps and arm patterns to be charged.
        for s in lib.segments() {
            assert_eq!(v.kinds[s.index][0] == NONE, s.counts() == 3, "{}", s.name);
        }
        let four: Vec<&crate::choreo::Segment> = lib.segments().iter().filter(|s| s.counts() == 4).take(40).collect();
        for (a, b) in four.iter().zip(four.iter().skip(1)) {
            let (x, y) = (a.builtin.unwrap(), b.builtin.unwrap());
            assert_eq!(v.shared(a.index, b.index), usize::from(x.step == y.step) + usize::from(x.arms == y.arms));
        }
        assert!(v.kinds.iter().all(|k| k[2] == NONE));
        // With an imported clip in the library: off.
        let mixed = crate::choreo::segment::tests::small_library_with_an_imported_clip();
        assert!(!Variety::new(&mixed, 1.0).is_on());
        // Off, or a bad weight: no charge.
        assert!(!Variety::new(&lib, f32::NAN).is_on());
        assert_eq!(Variety::new(&lib, 0.0).charge_in_path(&[0, 0], 1), 0.0);
    }
}
