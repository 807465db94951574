//! Filling the open bars (spec §G): a shortest path through a layered graph, one layer per
//! bar, one node per segment in an open bar and the single pinned segment in a pinned bar.
//!
//! The edge cost from segment A to segment B is C = 1 / S with S = S_pose + S_move exactly as
//! spec §G, plus the product's end-effector gap term (see [`super::table`], which builds the
//! M × M table of them).
//!
//! The product adds five terms: a music term `music_weight · |bar intensity − segment
//! intensity|` per open bar, a beat term `beat_weight · (1 − beat fit)` per open bar (a segment
//! whose counts fall on its kinetic beats turns on the song's beats once warped onto the bar,
//! spec §E/§J), a tempo-stretch term `stretch_weight · |log₂(bar count rate / segment count
//! tempo)|` per open bar (off by default, see [`STRETCH_WEIGHT_DEFAULT`]; [`Tempi`]), the person's-own-moves preference (`own_moves_preference` per open bar filled
//! by a built-in move when imported moves exist; [`node_costs`], [`fill_with_node_costs`]), and a repetition penalty `repeat_penalty` on an edge whose two
//! segments share frames of the same clip (the same segment twice in a row included). Both
//! keep the objective a sum over edges and nodes, so the dynamic programme below is exact: it
//! returns a minimum-cost path (ties broken towards lower segment indices). Repeats further
//! apart than one bar but within `repeat_window` bars (default 4: an A B A B alternation) are
//! not a sum over edges. They are charged in the same pass along each node's chosen path: when
//! a node's best predecessor path already used the same segment 2..=window bars earlier, the
//! node pays `repeat_penalty` (the usual path-dependent extension of Viterbi; it steers away
//! from repeats at no extra cost but is not guaranteed optimal for that term). The reported
//! cost is the full objective, window included. With `repeat_window` ≤ 1 the result is exactly
//! optimal. The variety term ([`Tempi::variety`], [`super::variety`]: nearby bars sharing a step,
//! arm pattern or source clip) is path-dependent too and charged the same way.
//!
//! The bar's metre ([`Tempi::bar_counts`]): an open bar of n beats takes only segments of n
//! counts (a segment of another count costs ∞ there), so a waltz bar is danced by 3-count moves
//! whose counts land on its 3 beats ([`super::segment`]'s module docs). The document leaves a
//! bar unrestricted (0) when the library holds no live segment of its count.
//!
//! Speed: the edge costs depend only on the library and are computed once per library, for
//! the pairs of metres the song's bars join ([`super::table`]; cached by
//! [`super::SegmentLibrary::transition_table_for`]); an open layer after an open layer reads the
//! block from the previous bar's metre to its own. In a within-metre block a column
//! first tries the previous layer's [`LOW_L`] cheapest nodes (every edge from them, streamed)
//! and its [`TOP_K`] cheapest edges (in increasing cost, stopping where the cheapest node
//! outside those with the next edge costs more than the best found), and accepts their best when it is provably optimal: any other predecessor costs at
//! least (the cheapest node outside that set) + (the cheapest edge outside that list).
//! Otherwise the whole column is reduced with a vectorised minimum. Either way the result is
//! exact.

use crate::fmath;
use serde::{Deserialize, Serialize};
use thiserror::Error;

use super::table::Block;
pub use super::table::{link_weights, TransitionTable, MIN_S, TOP_K};

/// Cheapest nodes of the previous layer tried by every column on the fast path.
pub const LOW_L: usize = 96;

/// One bar of the filling problem.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "camelCase")]
pub enum Layer {
    /// A pinned bar: this segment, fixed.
    Fixed { segment: usize },
    /// An open bar with the music's intensity there (0..1).
    Open { intensity: f32 },
}

/// Which moves Generate fills the open bars with (issue 26): the person's own (imported) moves
/// first, both kinds as the objective weighs them, or built-in moves only.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "camelCase")]
pub enum MovesSource {
    /// Imported moves first: in a bar the library holds an imported move of the bar's count for,
    /// the first fill charges a built-in move [`MOVES_SOURCE_CHARGE`] more (far above any term
    /// of the objective), so built-in moves fill only bars no imported move fits, and the bars
    /// the preference order opens from measured goals: where the imported moves tried there
    /// miss the beat or join goal as played ([`super::generate::order_stage`]; the join repair
    /// opens the bar of an imported move it bars too, [`super::generate::join_repair_stage`]). With no imported move in the library, as `Mixed` (built-in moves only, there
    /// being no other): so the default is *my moves* once the person has imported a humanoid
    /// clip, and the built-in moves before (issue 26).
    #[default]
    Mine,
    /// Both kinds as the objective weighs them (with [`FillWeights::own_moves_preference`]).
    Mixed,
    /// Built-in moves only, wherever the library holds one of the bar's count.
    Builtin,
}

/// What [`MovesSource::Mine`] and [`MovesSource::Builtin`] add to a move of the kind they put
/// second, per open bar.
pub const MOVES_SOURCE_CHARGE: f32 = 100.0;

/// Weights of the product's extra terms.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "camelCase", default)]
pub struct FillWeights {
    /// Weight of |bar intensity − segment intensity| per open bar (0 = the paper's method).
    pub music_weight: f32,
    /// Added to an edge between segments sharing frames of one clip, and to an open bar that
    /// repeats a segment used within `repeat_window` bars before it.
    pub repeat_penalty: f32,
    /// Bars within which a repeated segment counts as "too soon" (1: only the bar right
    /// before, which the exact search handles; larger windows are charged along the chosen
    /// paths, see the module documentation).
    pub repeat_window: usize,
    /// Weight of the beat term per open bar: `beat_weight · (1 − beat fit)` of the segment
    /// (how well its counts fall on its kinetic beats, [`super::Segment::beat_fit`]), so the
    /// filled dance turns on the song's beats, not between them. 0 turns it off.
    pub beat_weight: f32,
    /// The person's own moves first: added per open bar filled by a built-in move when the
    /// library holds imported moves. Built-in moves all start and end near one neutral stance,
    /// so they join one another almost perfectly and, without this, win every transition
    /// against mocap that starts and ends anywhere; with it, a built-in move is chosen only
    /// where it is better than every imported move that fits the beat by more than this (see
    /// [`node_costs`]). 0: no preference. The default, 0.03, is the largest measured in `benches/choreo_quality`
    /// that keeps every real song's beat alignment ≥ random + 0.05: larger values fill more bars
    /// with the person's mocap, whose counts and joins are rougher than the built-in moves'.
    pub own_moves_preference: f32,
    /// Weight of the tempo-stretch term per open bar: `stretch_weight · |log₂(bar count rate /
    /// segment count tempo)|`, where the bar's count rate is its 4 counts over its length (what
    /// the warp plays the segment at) and the segment's is its own (spec §E). A segment played
    /// at twice or half its own tempo costs `stretch_weight`: a move sped up moves its limbs
    /// faster by the same factor, and one slowed far below its tempo may turn on more kinetic
    /// beats than the bar has counts. 0 (the default, see [`STRETCH_WEIGHT_DEFAULT`]) turns it
    /// off.
    pub stretch_weight: f32,
    /// Weight of the foot-skate term per open bar: `skate_weight · excess`, the excess being how
    /// far the segment's own §J foot skate ([`super::Segment::skate_cm_per_s`]) exceeds its
    /// source clip's ([`super::Segment::clip_skate_cm_per_s`]), in metres per second: feet that
    /// slide in a bar of the source slide in the dance, and §J asks a dance to skate no more than
    /// its source clips. Charging the excess, not the skate itself, keeps the term from ruling
    /// out the person's mocap, which skates more than the built-in moves throughout. See
    /// [`SKATE_WEIGHT_DEFAULT`]; 0 turns it off.
    pub skate_weight: f32,
    /// Weight of the beat-rate term per open bar: `beat_rate_weight · beat_rate_cost`, how far
    /// (in octaves) the segment's kinetic beats per count, played at the bar's count rate
    /// ([`super::Segment::kinetic_per_count_at`]), are from 1 or ½ (§J asks a dance's
    /// kinetic beat rate to be within 25 % of the song's beat rate or its half); see
    /// [`beat_rate_cost`]. 0 (the default) leaves it to [`super::GenerateOptions::follow_beat_rate`],
    /// which applies the weakest weight that works, and only to a dance off the song's beat
    /// rate: a fixed weight acts on every song, and measured with the `choreo_quality` bench
    /// (`ODORI_BEAT_RATE_WEIGHT=x`, with `ODORI_FOLLOW_BEAT_RATE=0`) 0.07 turns Vibe Ace, which
    /// was on its beat rate, wholly to built-in moves (imported 79 % → 0 %, skate 25.5 → 38.8
    /// cm/s). (The one-bar trumpet song's 1.50 that no weight moved came from its grid: its bar
    /// held 2 of its 4 beats.) A value above 0 is used as it is, on every song.
    pub beat_rate_weight: f32,
    /// Which moves fill the open bars ([`MovesSource`]). Default `Mine` (issue 26: the
    /// person's moves first); absent in files written before it, which read the default.
    pub moves_source: MovesSource,
}

/// The beat term's factor when [`MovesSource::Mine`] puts the person's imported moves first (a
/// library holding any); see [`fill_weights_for`]. Measured with `tests/native/choreo_my_moves.rs`
/// (every song, the drum take and five demo pieces, the person library of every dance clip): at
/// ×1 (0.3) the dance scored below random moves on Let's Go Fishin' (0.615 against 0.686) and the
/// drum take (0.436 against 0.681); at ×3.3 (1.0) the drum take was still 0.705 against 0.681; at
/// ×10 (3.0) every piece met the beat goals.
pub const MINE_BEAT_FACTOR: f32 = 10.0;

/// The beat term's factor while the variety term ([`super::variety`]) is on; see
/// [`fill_weights_for`]. Measured with `tests/native/choreo_variety.rs`: at ×1 the dance fell
/// below random moves on Let's Go Fishin' (0.705 against 0.710); at ×2 every piece kept the beat
/// goals with the spread. 3 since the term also counts the whole dance (issue 26's share caps):
/// at 2 the 100 BPM demo's dance beat random moves by only 0.024 in `choreo_takes` (0.755 against
/// 0.731), at 3 by 0.099.
pub const VARIETY_BEAT_FACTOR: f32 = 3.0;

/// The weights the fill runs with, given the set `weights` (its moves source among them),
/// whether the library holds live imported moves (`has_imported`) and whether the variety term
/// is on (`variety_on`): the set weights with the beat term multiplied by
/// [`MINE_BEAT_FACTOR`] when *my moves* applies (source [`MovesSource::Mine`], imported moves
/// present) and by [`VARIETY_BEAT_FACTOR`] when the variety term is on (both: the product).
///
/// Why, once for both: the beat term is the objective's only term that tells a move on the beat
/// from one between beats, and with the joins blended
/// ([`super::render::JoinBlend::Inertial`]) random moves keep their counts at the bar lines too,
/// so the floor the dance must clear (random moves + 0.05, spec §J) is high. Any other term
/// that narrows or reorders the choice — *my moves* keeping the fill to imported moves, which
/// all fit the bar's count and whose joins the viewer barely sees, or the variety term trading
/// beat fit for spread — leaves the beat a smaller share of the objective unless it weighs more
/// by as much. A set weight of 0 still turns the term off.
pub fn fill_weights_for(weights: FillWeights, has_imported: bool, variety_on: bool) -> FillWeights {
    let mut factor = 1.0;
    if weights.moves_source == MovesSource::Mine && has_imported {
        factor *= MINE_BEAT_FACTOR;
    }
    if variety_on {
        factor *= VARIETY_BEAT_FACTOR;
    }
    FillWeights { beat_weight: weights.beat_weight * factor, ..weights }
}

/// Skate weights (per m/s of skate above the source clip's) tried, weakest first, by
/// [`super::GenerateOptions::follow_skate`]: 0.1 to 12.8, doubling.
pub fn skate_ladder() -> impl Iterator<Item = f32> {
    (0..8).map(|k| 0.1 * 2f32.powi(k))
}

/// [`skate_ladder`] beside the fill's beat term (`beat_weight`, as [`fill_weights_for`] scaled
/// it), for the join repair's refills with [`super::GenerateOptions::skate_beside_beat_term`]:
/// each weight times as much as that term outweighs the default one the ladder was measured
/// beside (0.3; at least ×1, so 0 gives the plain ladder), as [`beat_rate_ladder_for`] reaches
/// further.
pub fn skate_ladder_for(beat_weight: f32) -> impl Iterator<Item = f32> {
    let scale = (beat_weight / FillWeights::default().beat_weight).max(1.0);
    skate_ladder().map(move |w| w * scale)
}

/// The kinetic beats per count [`super::GenerateOptions::follow_beat_rate`] accepts: one turn a count or
/// one every other count, each within 20 % (the §J goal is 25 %; the 5 % between is a margin
/// for beats the grid's bars hold more or fewer of than 4).
pub const BEAT_RATE_BAND: [(f32, f32); 2] = [(0.8, 1.2), (0.4, 0.6)];

/// Beat-rate weights tried, weakest first, when the dance's beat rate is outside
/// [`BEAT_RATE_BAND`] ([`super::GenerateOptions::follow_beat_rate`]): 0.01 to 0.45 in steps of √2 (the
/// weakest that works is wanted: from about 0.1 a weight tips whole dances between kinds of
/// move).
pub fn beat_rate_ladder() -> impl Iterator<Item = f32> {
    beat_rate_steps().take(BEAT_RATE_RUNGS)
}

/// Rungs of the plain [`beat_rate_ladder`].
const BEAT_RATE_RUNGS: usize = 12;

/// 0.01, then each weight √2 times the last (a product, not `powi`: the same bits natively and
/// in wasm), up to 64 weights.
fn beat_rate_steps() -> impl Iterator<Item = f32> {
    std::iter::successors(Some(0.01f32), |w| Some(w * std::f32::consts::SQRT_2)).take(64)
}

/// [`beat_rate_ladder`], continued in its steps until its top weighs as much beside the fill's
/// beat term (`beat_weight`, as [`fill_weights_for`] scaled it) as the plain ladder's top did
/// beside the default beat term it was measured with (0.45 beside 0.3): the two terms trade
/// against each other, so a beat term 30 times heavier (*my moves* × variety) left the plain
/// ladder too weak to move any bar (half 1 of `choreo_my_moves`' Let's Go Fishin' stayed at
/// 1.30 kinetic beats a count through all 12 weights). The first 12 weights are the plain
/// ladder's, so a dance one of them brings into the band is the same.
pub fn beat_rate_ladder_for(beat_weight: f32) -> impl Iterator<Item = f32> {
    let scale = (beat_weight / FillWeights::default().beat_weight).max(1.0);
    let top = beat_rate_ladder().last().unwrap_or(0.0) * scale * (1.0 + 1e-4);
    beat_rate_steps().enumerate().take_while(move |&(k, w)| k < BEAT_RATE_RUNGS || w <= top).map(|(_, w)| w)
}

/// Whether a predicted kinetic beats per count is inside [`BEAT_RATE_BAND`].
pub fn in_beat_rate_band(kinetic_per_count: f32) -> bool {
    BEAT_RATE_BAND.iter().any(|&(lo, hi)| (lo..=hi).contains(&kinetic_per_count))
}

impl Default for FillWeights {
    fn default() -> Self {
        Self { music_weight: 1.0, repeat_penalty: 3.0, repeat_window: 4, beat_weight: 0.3, own_moves_preference: 0.03, stretch_weight: STRETCH_WEIGHT_DEFAULT, skate_weight: SKATE_WEIGHT_DEFAULT, beat_rate_weight: 0.0, moves_source: MovesSource::Mine }
    }
}

/// Default [`super::GenerateOptions::free_skate_slack`]: the same size as the default preference for the
/// person's own moves (0.03), the amount the product already treats as a small difference
/// between two moves that fit a bar. So a swap never trades an imported move that fits for a
/// built-in one unless the built-in one is otherwise better.
pub const FREE_SKATE_SLACK_DEFAULT: f32 = 0.03;


/// Default [`FillWeights::stretch_weight`]: off. Measured with the `choreo_quality` bench (with
/// the table's end-effector gap term, which is what keeps joins smooth): any weight from 0.05
/// up tips whole dances between imported and built-in moves (moves of one kind join each
/// other best, so the choice is nearly all-or-nothing), and on the real songs that cost beat
/// alignment (a one-bar song fell to random + 0.03), foot skate (Vibe Ace 25.5 → 40.3 cm/s) and
/// the share of the person's moves (Vibe Ace 79 % → 0 %), while joins were already ≤ 1.1
/// without it. A person may still turn it on.
pub const STRETCH_WEIGHT_DEFAULT: f32 = 0.0;

/// Default [`FillWeights::skate_weight`] (per m/s of skate above the source clip's): off.
/// Measured with the `choreo_quality` bench (`ODORI_SKATE_WEIGHT=x`): the one-bar trumpet song's
/// skate falls below its source clips' (41.3 → 34.1 cm/s) only from a weight of 0.5, and there
/// its beat alignment falls (random + 0.197 → + 0.128); any weight from 0.05 up tips Vibe Ace
/// (join jump max 1.04 → 1.60, imported 79 % → 73 %) and Let's Go Fishin' (imported 33 % →
/// 0 %), the near all-or-nothing choice between kinds of move that the stretch term shows too.
/// Charging the skate itself rather than its excess fills every song with built-in moves from
/// 0.1 up. A person may still turn it on. The product instead swaps where it is free
/// ([`super::GenerateOptions::free_skate_slack`]) and steers only a dance that slides more than
/// its sources ([`super::GenerateOptions::follow_skate`]).
pub const SKATE_WEIGHT_DEFAULT: f32 = 0.0;

/// The beat-rate cost of a segment turning `kinetic_per_count` times a count: octaves from the
/// nearer of 1 and ½ per count, `min(|log₂ r|, |log₂ 2r|)`, with r at least ¼ (a segment that
/// never turns costs 1); 0 when r is unknown (not finite).
pub fn beat_rate_cost(kinetic_per_count: f32) -> f32 {
    if !kinetic_per_count.is_finite() {
        return 0.0;
    }
    let r = kinetic_per_count.max(0.25);
    fmath::log2(r).abs().min(fmath::log2(2.0 * r).abs())
}

/// Count rate (counts per minute) a segment of 4 counts is played at over a bar of
/// `duration_secs`.
pub fn bar_count_rate_bpm(duration_secs: f32) -> f32 {
    count_rate_bpm(crate::choreo::segment::SEGMENT_COUNTS, duration_secs)
}

/// Count rate (counts per minute) a segment of `counts` counts is played at over a bar of
/// `duration_secs` (a 3-count segment on a bar in 3).
pub fn count_rate_bpm(counts: usize, duration_secs: f32) -> f32 {
    counts.max(1) as f32 * 60.0 / duration_secs.max(1e-3)
}

/// The tempo-stretch cost of playing a segment of count tempo `segment_bpm` over a bar whose
/// count rate is `bar_bpm` ([`FillWeights::stretch_weight`]); 0 when either is unknown.
pub fn stretch_cost(weight: f32, bar_bpm: f32, segment_bpm: f32) -> f32 {
    if weight == 0.0 || !(bar_bpm > 0.0 && segment_bpm > 0.0) || !bar_bpm.is_finite() || !segment_bpm.is_finite() {
        return 0.0;
    }
    weight * fmath::log2(bar_bpm / segment_bpm).abs()
}


#[derive(Debug, Error, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "camelCase")]
pub enum FillError {
    #[error("the segment library is empty: add the built-in moves or a humanoid clip first")]
    EmptyLibrary,
    #[error("bar {bar} is pinned to segment {segment}, but the library has only {segments} segments")]
    UnknownSegment { bar: usize, segment: usize, segments: usize },
    #[error("segment intensities: {given} given for {segments} segments")]
    IntensityCount { given: usize, segments: usize },
    #[error("segment node costs: {given} given for {segments} segments")]
    NodeCostCount { given: usize, segments: usize },
}

/// min over `a` of `prev[a] + col[a]` and the first `a` reaching it.
fn column_min(prev: &[f32], col: &[f32]) -> (f32, usize) {
    let n = prev.len().min(col.len());
    let (prev, col) = (&prev[..n], &col[..n]);
    let mut lanes = [f32::INFINITY; 8];
    let split = n - n % 8;
    for (p8, c8) in prev[..split].chunks_exact(8).zip(col[..split].chunks_exact(8)) {
        for i in 0..8 {
            let v = p8[i] + c8[i];
            lanes[i] = if v < lanes[i] { v } else { lanes[i] };
        }
    }
    let mut min = lanes.iter().cloned().fold(f32::INFINITY, f32::min);
    for a in split..n {
        let v = prev[a] + col[a];
        if v < min {
            min = v;
        }
    }
    let at = (0..n).find(|&a| prev[a] + col[a] == min).unwrap_or(0);
    (min, at)
}

/// One open layer after an open layer: for every segment `b` this bar can take (`node[b]`
/// finite), the cheapest predecessor `a` (by `prev[a] + C(a, b)`, ties to the lowest index)
/// into `arg[b]` and that cost plus `node[b]` into `next[b]` (∞ elsewhere). The reachable
/// predecessors all lie in one group of the table (one metre: the previous bar's) and the
/// successors in one per metre, so each group of successors reads one block: its own group's
/// (the fast path of the module docs) or a cross block (every pair, exact); a pair outside
/// the table's blocks is computed (the same value, slowly).
#[allow(clippy::too_many_arguments)]
fn relax_open(table: &TransitionTable, prev: &[f32], node: &[f32], next: &mut [f32], arg: &mut [u32], low: &mut Vec<u32>, stats: &mut FillStats, tempi: &Tempi) {
    let m = table.len();
    let groups = table.metres().len().max(1);
    let mut from = vec![false; groups];
    let mut to = vec![false; groups];
    for a in 0..m {
        if prev[a] != f32::INFINITY {
            from[table.group_of(a)] = true;
        }
        if node[a] != f32::INFINITY {
            to[table.group_of(a)] = true;
        }
    }
    let from: Vec<usize> = (0..groups).filter(|&g| from[g]).collect();
    for h in (0..groups).filter(|&h| to[h]) {
        match from.as_slice() {
            // Nothing reachable: every node stays at ∞.
            [] => {}
            [g] if table.block(*g, h).is_some() => {
                if let Some(block) = table.block(*g, h) {
                    if *g == h {
                        relax_within(block, prev, node, next, arg, low, stats, tempi);
                    } else {
                        relax_across(block, prev, node, next, arg, stats);
                    }
                }
            }
            _ => {
                for b in (0..m).filter(|&b| table.group_of(b) == h && node[b] != f32::INFINITY) {
                    let mut best = (f32::INFINITY, 0usize);
                    for (a, &p) in prev.iter().enumerate() {
                        if p == f32::INFINITY {
                            continue;
                        }
                        let v = p + table.cost(a, b);
                        if v < best.0 {
                            best = (v, a);
                        }
                    }
                    next[b] = best.0 + node[b];
                    arg[b] = best.1 as u32;
                    stats.full_scans += 1;
                }
                stats.open_columns += (0..m).filter(|&b| table.group_of(b) == h).count();
            }
        }
    }
}

/// [`relax_open`] over a within-group block: the fast path of the module docs, on the
/// block's own (local) indices. [`Tempi::top_lists_stop_at_rest`]: a column's list stops by the
/// cheapest node outside the previous layer's cheapest, and the cheapest rows stream vectorised
/// ([`stream_row`]); else session 18's fills, the control (the cheapest node of all, a branch
/// per lane); [`Tempi::columns_scanned_by_chunks`]: whole columns by chunks. The same values.
#[allow(clippy::too_many_arguments)]
fn relax_within(block: &Block, prev_all: &[f32], node_all: &[f32], next_all: &mut [f32], arg_all: &mut [u32], low: &mut Vec<u32>, stats: &mut FillStats, tempi: &Tempi) {
    let (top_lists_stop_at_rest, by_chunks) = (tempi.top_lists_stop_at_rest, tempi.columns_scanned_by_chunks);
    let m = block.to.len();
    let prev: Vec<f32> = block.from.iter().map(|&a| prev_all[a as usize]).collect();
    // The previous layer's LOW_L cheapest nodes, and the cheapest cost outside them.
    low.clear();
    low.extend(0..m as u32);
    let l = LOW_L.min(m);
    let prev_rest = if l < m {
        low.select_nth_unstable_by(l, |x, y| prev[*x as usize].total_cmp(&prev[*y as usize]).then(x.cmp(y)));
        let r = low[l..].iter().map(|&a| prev[a as usize]).fold(f32::INFINITY, f32::min);
        low.truncate(l);
        r
    } else {
        f32::INFINITY
    };
    let k = TOP_K.min(m);
    // Where a column's list (in increasing cost) stops: once the next edge from a node outside
    // the cheapest (those streamed below, whose every edge is tried) costs more than the best
    // found, no later entry can win (`top_lists_stop_at_rest`); session 18's bound was the cheapest node
    // of all, which the cheapest nodes' own entries kept from stopping.
    let prev_min = if top_lists_stop_at_rest { prev_rest } else { prev.iter().copied().fold(f32::INFINITY, f32::min) };
    let mut prev_chunk = Vec::new();
    if by_chunks {
        super::scan::chunk_mins(&prev, &mut prev_chunk);
    }
    // The cheapest nodes' rows, streamed (vectorised).
    let mut next = vec![f32::INFINITY; m];
    let mut arg = vec![0u32; m];
    low.sort_unstable();
    for &a in low.iter() {
        let pa = prev[a as usize];
        let row = &block.rows[a as usize * m..(a as usize + 1) * m];
        if top_lists_stop_at_rest {
            stream_row(pa, a, row, &mut next, &mut arg);
        } else {
            // Session 18's loop (the control): a store per lane under a branch.
            for ((n, g), &c) in next.iter_mut().zip(arg.iter_mut()).zip(row) {
                let v = pa + c;
                let better = v < *n;
                *n = if better { v } else { *n };
                *g = if better { a } else { *g };
            }
        }
    }
    for b in 0..m {
        // A segment this bar cannot take (retired, or held out by another term) stays at ∞:
        // no need to prove its best predecessor (exact: it is on no finite path).
        let global = block.to[b] as usize;
        let node = node_all[global];
        if node == f32::INFINITY {
            continue;
        }
        let (mut best, mut best_a) = (next[b], arg[b]);
        // Then the column's cheapest edges. Any other predecessor costs at least
        // prev_rest + rest_min[b], so the best found is exact when no worse.
        let (ti, tc) = (&block.top[b * k..(b + 1) * k], &block.top_cost[b * k..(b + 1) * k]);
        let mut tried = 0;
        for (&a, &c) in ti.iter().zip(tc) {
            // Every later entry costs at least prev_min + c (the list rises, and a sum rounds
            // monotonically): none can reach `best` once that is above it. Exact. With the
            // bound outside the cheapest nodes, a later entry from one of them can reach
            // `best` but not below it, nor at a lower index (the stream kept the lowest index
            // of the cheapest nodes reaching their minimum), so it is skipped too.
            if prev_min + c > best {
                stats.early_stops += 1;
                break;
            }
            tried += 1;
            let v = prev[a as usize] + c;
            if v < best || (v == best && a < best_a) {
                best = v;
                best_a = a;
            }
        }
        stats.top_tries += tried;
        if best > prev_rest + block.rest_min[b] {
            // Not provable from the list: the whole column, contiguous (vectorised
            // minimum, then the first predecessor reaching it), by chunks when kept.
            let chunks = prev_chunk.len();
            if by_chunks && block.chunk_min.len() == chunks * m {
                let scanned;
                (best, best_a, scanned) = super::scan::column_min_by_chunks(&prev, &prev_chunk, block.column(b), &block.chunk_min[b * chunks..(b + 1) * chunks], best, best_a);
                stats.chunks_scanned += scanned;
            } else {
                let (min, at) = column_min(&prev, block.column(b));
                best = min;
                best_a = at as u32;
            }
            stats.full_scans += 1;
        }
        next_all[global] = best + node;
        arg_all[global] = block.from.get(best_a as usize).copied().unwrap_or(0);
    }
    stats.open_columns += m;
}

/// `next[b], arg[b] = pa + row[b], a` wherever that is less than `next[b]`, by selects on the
/// bits (the same values as a comparison and a branch): written so, the loop vectorises, where
/// a store per lane under a branch made it the fill's hottest loop.
fn stream_row(pa: f32, a: u32, row: &[f32], next: &mut [f32], arg: &mut [u32]) {
    let n = row.len().min(next.len()).min(arg.len());
    let (row, next, arg) = (&row[..n], &mut next[..n], &mut arg[..n]);
    for ((x, g), &c) in next.iter_mut().zip(arg.iter_mut()).zip(row) {
        let v = pa + c;
        // All ones where the value is kept (not less), else none.
        let keep = u32::from(v < *x).wrapping_sub(1);
        *x = f32::from_bits((x.to_bits() & keep) | (v.to_bits() & !keep));
        *g = (*g & keep) | (a & !keep);
    }
}

/// [`relax_open`] over a cross block (a metre change between the bars): every pair.
fn relax_across(block: &Block, prev_all: &[f32], node_all: &[f32], next_all: &mut [f32], arg_all: &mut [u32], stats: &mut FillStats) {
    let prev: Vec<f32> = block.from.iter().map(|&a| prev_all[a as usize]).collect();
    for (lb, &b) in block.to.iter().enumerate() {
        let node = node_all[b as usize];
        if node == f32::INFINITY {
            continue;
        }
        let (min, at) = column_min(&prev, block.column(lb));
        next_all[b as usize] = min + node;
        arg_all[b as usize] = block.from.get(at).copied().unwrap_or(0);
        stats.full_scans += 1;
    }
    stats.open_columns += block.to.len();
}

/// Whether segment `b` in layer `t`, reached from node `pred` of layer `t - 1`, repeats a
/// segment of that node's best path 2..=`window` layers back.
fn repeats_on_path(back: &[Vec<u32>], t: usize, pred: usize, b: usize, window: usize) -> bool {
    let (mut node, mut layer) = (pred, t.saturating_sub(1));
    for _ in 2..=window {
        if layer == 0 {
            return false;
        }
        let Some(bt) = back.get(layer) else { return false };
        node = if bt.len() == 1 { bt[0] as usize } else { bt.get(node).copied().unwrap_or(0) as usize };
        layer -= 1;
        if node == b {
            return true;
        }
    }
    false
}

/// Whether bar `t` of a path repeats a segment used 2..=`window` bars before it.
fn repeats_too_soon(path: &[usize], t: usize, window: usize) -> bool {
    (2..=window).any(|d| t >= d && path[t - d] == path[t])
}

/// How much work a filling did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "camelCase")]
pub struct FillStats {
    /// Columns (open-bar nodes after an open bar) relaxed.
    pub open_columns: usize,
    /// Of those, columns whose top-[`TOP_K`] list could not prove the optimum and were scanned.
    pub full_scans: usize,
    /// Nodes charged for repeating a segment of their path within the window.
    pub window_charges: usize,
    /// Top-list entries tried, and columns whose list stopped before its end (no later entry
    /// could win).
    pub top_tries: usize,
    pub early_stops: usize,
    /// Chunks read by the whole scans done by chunks ([`super::scan`]).
    pub chunks_scanned: usize,
}

/// A minimum-cost choice of one segment per layer. `segment_intensity[s]` is segment `s`'s
/// intensity in 0..1. Returns the chosen segment per layer (pinned layers keep theirs) and the
/// path's cost.
pub fn fill(table: &TransitionTable, layers: &[Layer], segment_intensity: &[f32], weights: &FillWeights) -> Result<(Vec<usize>, f32), FillError> {
    fill_with_stats(table, layers, segment_intensity, weights).map(|(p, c, _)| (p, c))
}

/// [`fill`], also saying how much work it took (no per-segment node costs).
pub fn fill_with_stats(table: &TransitionTable, layers: &[Layer], segment_intensity: &[f32], weights: &FillWeights) -> Result<(Vec<usize>, f32, FillStats), FillError> {
    fill_with_node_costs(table, layers, segment_intensity, &[], weights)
}

/// Beat fit ([`super::Segment::beat_fit`]) from which an imported move counts as fitting the
/// music and gets the own-moves preference: BAS on its counts ≥ BAS on its half-counts + 0.5.
pub const OWN_MOVE_MIN_FIT: f32 = 0.75;

/// The per-open-bar cost of each segment beyond the music term: the beat term
/// `beat_weight · (1 − beat_fit[s])` plus, when any segment is imported, `own_moves_preference`
/// for every segment that is not an imported move fitting the beat (fit ≥ [`OWN_MOVE_MIN_FIT`]);
/// see [`FillWeights`]. What [`fill_with_node_costs`] takes. No skate term: see
/// [`node_costs_with_skate`].
pub fn node_costs(weights: &FillWeights, beat_fit: &[f32], builtin: &[bool]) -> Vec<f32> {
    node_costs_with_skate(weights, beat_fit, builtin, &[])
}

/// [`node_costs`] plus the foot-skate term `skate_weight · skate_cm_per_s[s] / 100` (the skate
/// charged, in m/s: [`super::generate`] passes each segment's excess over its source
/// clip's; [`FillWeights::skate_weight`]); a segment missing from `skate_cm_per_s` pays none.
pub fn node_costs_with_skate(weights: &FillWeights, beat_fit: &[f32], builtin: &[bool], skate_cm_per_s: &[f32]) -> Vec<f32> {
    let any_imported = builtin.iter().any(|b| !b);
    (0..beat_fit.len().max(builtin.len()).max(skate_cm_per_s.len()))
        .map(|s| {
            let skate = skate_cm_per_s.get(s).filter(|v| v.is_finite()).map_or(0.0, |v| weights.skate_weight * v.max(0.0) / 100.0);
            let beat = beat_fit.get(s).map_or(0.0, |f| weights.beat_weight * (1.0 - f.clamp(0.0, 1.0)));
            // An imported move "fits" when it clearly turns on its counts (BAS on the counts at
            // least 0.5 above BAS on the half-counts); only those are preferred.
            let fits = beat_fit.get(s).is_some_and(|&f| f >= OWN_MOVE_MIN_FIT);
            let own = if any_imported && (builtin.get(s).copied().unwrap_or(false) || !fits) { weights.own_moves_preference } else { 0.0 };
            beat + own + skate
        })
        .collect()
}

/// [`fill`] with a cost per segment added in every open bar it fills (`node_cost[s]`, e.g.
/// from [`node_costs`]); empty: none.
pub fn fill_with_node_costs(
    table: &TransitionTable,
    layers: &[Layer],
    segment_intensity: &[f32],
    node_cost: &[f32],
    weights: &FillWeights,
) -> Result<(Vec<usize>, f32, FillStats), FillError> {
    fill_with_tempi(table, layers, segment_intensity, node_cost, &Tempi::default(), weights)
}

/// The count rates the tempo-stretch term ([`FillWeights::stretch_weight`]) compares: per layer
/// the rate its bar plays a segment at ([`bar_count_rate_bpm`]), per segment its own count
/// tempo. Either empty: no stretch term.
#[derive(Clone, Copy, Debug)]
pub struct Tempi<'a> {
    pub bar_bpm: &'a [f32],
    pub segment_bpm: &'a [f32],
    /// Per layer, per segment: the beat-rate cost ([`beat_rate_cost`]) of the segment played at
    /// that bar's count rate (from [`super::Segment::kinetic_per_count_at`]), charged
    /// `beat_rate_weight` times. Empty: no beat-rate term here.
    pub beat_rate: &'a [Vec<f32>],
    /// Per layer, per segment: a cost added as it is (already weighted). Empty: none.
    pub extra: &'a [Vec<f32>],
    /// Per layer, the counts its bar takes (its beats; 0: any): a segment whose
    /// [`Tempi::segment_counts`] differ costs ∞ there. Empty: no metre rule.
    pub bar_counts: &'a [usize],
    /// Per segment, its counts ([`super::Segment::counts`]).
    pub segment_counts: &'a [usize],
    /// The variety term ([`super::variety`]): nearby bars sharing a step, arm pattern or source
    /// clip are charged, along the path. None: no such term.
    pub variety: Option<&'a super::variety::Variety>,
    /// [`super::GenerateOptions::top_lists_stop_at_rest`] (default true): a column's top list
    /// stops by the cheapest node outside those whose every edge is tried, and their rows stream
    /// vectorised; false stops by the previous layer's cheapest node, a branch per lane in the
    /// stream (session 18's fills, the control). The same paths either way.
    pub top_lists_stop_at_rest: bool,
    /// [`super::GenerateOptions::columns_scanned_by_chunks`] (default true): a whole column is
    /// scanned by chunks ([`super::scan`]); false: every entry (the control). The same paths.
    pub columns_scanned_by_chunks: bool,
}

impl Default for Tempi<'_> {
    fn default() -> Self {
        Tempi { bar_bpm: &[], segment_bpm: &[], beat_rate: &[], extra: &[], bar_counts: &[], segment_counts: &[], variety: None, top_lists_stop_at_rest: true, columns_scanned_by_chunks: true }
    }
}

impl Tempi<'_> {
    fn cost(&self, weights: &FillWeights, layer: usize, segment: usize) -> f32 {
        let stretch = match (self.bar_bpm.get(layer), self.segment_bpm.get(segment)) {
            (Some(&b), Some(&s)) => stretch_cost(weights.stretch_weight, b, s),
            _ => 0.0,
        };
        let rate = match self.beat_rate.get(layer).and_then(|v| v.get(segment)) {
            Some(&c) if weights.beat_rate_weight > 0.0 && c.is_finite() => weights.beat_rate_weight * c,
            _ => 0.0,
        };
        let extra = self.extra.get(layer).and_then(|v| v.get(segment)).copied().filter(|c| c.is_finite()).unwrap_or(0.0);
        let metre = match (self.bar_counts.get(layer), self.segment_counts.get(segment)) {
            (Some(&b), Some(&n)) if b != 0 && b != n => f32::INFINITY,
            _ => 0.0,
        };
        stretch + rate + extra + metre
    }
}

/// [`fill_with_node_costs`] with the tempo-stretch term on `tempi`.
pub fn fill_with_tempi(
    table: &TransitionTable,
    layers: &[Layer],
    segment_intensity: &[f32],
    node_cost: &[f32],
    tempi: &Tempi,
    weights: &FillWeights,
) -> Result<(Vec<usize>, f32, FillStats), FillError> {
    let mut stats = FillStats::default();
    let m = table.len();
    if m == 0 {
        return Err(FillError::EmptyLibrary);
    }
    if segment_intensity.len() != m {
        return Err(FillError::IntensityCount { given: segment_intensity.len(), segments: m });
    }
    if !node_cost.is_empty() && node_cost.len() != m {
        return Err(FillError::NodeCostCount { given: node_cost.len(), segments: m });
    }
    let extra = |b: usize| node_cost.get(b).copied().unwrap_or(0.0);
    for (bar, l) in layers.iter().enumerate() {
        if let Layer::Fixed { segment } = *l {
            if segment >= m {
                return Err(FillError::UnknownSegment { bar, segment, segments: m });
            }
        }
    }
    if layers.is_empty() {
        return Ok((Vec::new(), 0.0, stats));
    }
    if layers.iter().any(|l| matches!(l, Layer::Open { .. })) && !(0..m).any(|s| table.is_available(s)) {
        return Err(FillError::EmptyLibrary);
    }
    let window = if weights.repeat_penalty > 0.0 { weights.repeat_window } else { 0 };
    // A segment kept only for the bars that hold it (an old cut of a re-cut clip) never fills
    // an open bar.
    let music = |t: usize, intensity: f32, b: usize| {
        let unavailable = if table.is_available(b) { 0.0 } else { f32::INFINITY };
        weights.music_weight * (intensity - segment_intensity[b]).abs() + extra(b) + tempi.cost(weights, t, b) + unavailable
    };
    // Node costs of the current layer: either one fixed node or all m.
    enum Nodes {
        One(usize, f32),
        All(Vec<f32>),
    }
    let mut back: Vec<Vec<u32>> = Vec::with_capacity(layers.len());
    let mut low: Vec<u32> = Vec::with_capacity(m);
    let mut cur = match layers[0] {
        Layer::Fixed { segment } => Nodes::One(segment, 0.0),
        Layer::Open { intensity } => {
            Nodes::All((0..m).map(|b| music(0, intensity, b)).collect())
        }
    };
    back.push(Vec::new());
    for (t, layer) in layers.iter().enumerate().skip(1) {
        match (*layer, &cur) {
            (Layer::Fixed { segment }, Nodes::One(a, c)) => {
                let v = c + table.cost(*a, segment);
                back.push(vec![*a as u32]);
                cur = Nodes::One(segment, v);
            }
            (Layer::Fixed { segment }, Nodes::All(prev)) => {
                // Every predecessor, in index order (one that cannot be reached adds ∞ and never
                // wins).
                let mut best = (f32::INFINITY, 0usize);
                for (a, p) in prev.iter().enumerate() {
                    if *p == f32::INFINITY {
                        continue;
                    }
                    let v = p + table.cost(a, segment);
                    if v < best.0 {
                        best = (v, a);
                    }
                }
                back.push(vec![best.1 as u32]);
                cur = Nodes::One(segment, best.0);
            }
            (Layer::Open { intensity }, Nodes::One(a, c)) => {
                let mut next: Vec<f32> = (0..m)
                    .map(|b| {
                        let node = music(t, intensity, b);
                        // A segment this bar cannot take stays at ∞ (its join is not looked up).
                        if node == f32::INFINITY { f32::INFINITY } else { c + table.cost(*a, b) + node }
                    })
                    .collect();
                for (b, v) in next.iter_mut().enumerate() {
                    if repeats_on_path(&back, t, *a, b, window) {
                        *v += weights.repeat_penalty;
                        stats.window_charges += 1;
                    }
                }
                if let Some(variety) = tempi.variety {
                    variety.charge_after_pinned(&back, t, *a, &mut next);
                }
                back.push(vec![*a as u32; m]);
                cur = Nodes::All(next);
            }
            (Layer::Open { intensity }, Nodes::All(prev)) => {
                let node: Vec<f32> = (0..m).map(|b| music(t, intensity, b)).collect();
                let mut next = vec![f32::INFINITY; m];
                let mut arg = vec![0u32; m];
                relax_open(table, prev, &node, &mut next, &mut arg, &mut low, &mut stats, tempi);
                if let Some(variety) = tempi.variety {
                    variety.relax(table, &back, t, prev, &node, &mut next, &mut arg);
                }
                for (b, v) in next.iter_mut().enumerate() {
                    if repeats_on_path(&back, t, arg[b] as usize, b, window) {
                        *v += weights.repeat_penalty;
                        stats.window_charges += 1;
                    }
                }
                back.push(arg);
                cur = Nodes::All(next);
            }
        }
    }
    // Backtrack.
    let n = layers.len();
    let mut path = vec![0usize; n];
    // The last layer's best node (its cost is recomputed below with the full objective).
    let mut node = match &cur {
        Nodes::One(s, _) => *s,
        Nodes::All(v) => {
            let mut best = (f32::INFINITY, 0usize);
            for (b, c) in v.iter().enumerate() {
                if *c < best.0 {
                    best = (*c, b);
                }
            }
            best.1
        }
    };
    for t in (0..n).rev() {
        path[t] = match layers[t] {
            Layer::Fixed { segment } => segment,
            Layer::Open { .. } => node,
        };
        if t > 0 {
            let bt = &back[t];
            node = if bt.len() == 1 { bt[0] as usize } else { bt.get(path[t]).copied().unwrap_or(0) as usize };
        }
    }
    let cost = path_cost_with_tempi(table, layers, segment_intensity, node_cost, tempi, weights, &path);
    Ok((path, cost, stats))
}

/// Foot skate where it is free ([`super::GenerateOptions::free_skate_slack`]): bar by bar in order, an
/// open bar whose segment's feet slide more than its source clip's there
/// (`skate_excess_cm_per_s(bar, segment) > 0`) takes instead the segment with the least such excess among those that keep the whole
/// objective ([`path_cost_with_tempi`], the same terms the path was found with) within
/// `slack` of the path's, its neighbours unchanged (ties: the cheaper). A local
/// swap, not a weight on the whole search: a skate weight tips whole dances between kinds of
/// move, since moves of one kind join each other best; a swap only happens where a cleaner
/// segment fits that bar nearly as well. Returns the path and its objective.
#[allow(clippy::too_many_arguments)]
pub fn free_skate_pass(
    table: &TransitionTable,
    layers: &[Layer],
    segment_intensity: &[f32],
    node_cost: &[f32],
    tempi: &Tempi,
    weights: &FillWeights,
    slack: f32,
    skate_excess_cm_per_s: &dyn Fn(usize, usize) -> f32,
    path: &[usize],
) -> (Vec<usize>, f32) {
    let mut path = path.to_vec();
    let mut cost = path_cost_with_tempi(table, layers, segment_intensity, node_cost, tempi, weights, &path);
    let excess_at = |t: usize, s: usize| Some(skate_excess_cm_per_s(t, s)).filter(|v| v.is_finite()).unwrap_or(0.0).max(0.0);
    if slack.is_nan() || slack <= 0.0 || path.len() != layers.len() || !cost.is_finite() {
        return (path, cost);
    }
    let m = table.len().min(segment_intensity.len());
    for t in 0..layers.len() {
        let Layer::Open { intensity } = layers[t] else { continue };
        let excess = |s: usize| excess_at(t, s);
        let a = path[t];
        if excess(a) <= 0.0 {
            continue;
        }
        // This bar's share of the objective with segment b in it (the window's repeats aside,
        // which the full check below counts).
        let (prev, next) = (t.checked_sub(1).map(|p| path[p]), path.get(t + 1).copied());
        let local = |b: usize| {
            let mut c = weights.music_weight * (intensity - segment_intensity[b]).abs() + node_cost.get(b).copied().unwrap_or(0.0) + tempi.cost(weights, t, b);
            if c == f32::INFINITY {
                // A segment this bar cannot take: its joins are not looked up (∞ either way).
                return c;
            }
            if let Some(p) = prev {
                c += table.cost(p, b);
            }
            if let Some(n) = next {
                c += table.cost(b, n);
            }
            c
        };
        let (here, excess_a) = (local(a), excess(a));
        let mut best: Option<(f32, f32, usize, f32)> = None; // (excess, rise, segment, new cost)
        for b in 0..m {
            // Each figure once per candidate (the same values as asked for anew each time).
            if b == a || !table.is_available(b) {
                continue;
            }
            let excess_b = excess(b);
            if excess_b >= excess_a {
                continue;
            }
            let rise = local(b) - here;
            if rise > slack || best.is_some_and(|(e, r, _, _)| (excess_b, rise) >= (e, r)) {
                continue;
            }
            path[t] = b;
            let c = path_cost_with_tempi(table, layers, segment_intensity, node_cost, tempi, weights, &path);
            path[t] = a;
            if c - cost <= slack {
                best = Some((excess(b), c - cost, b, c));
            }
        }
        if let Some((_, _, b, c)) = best {
            path[t] = b;
            cost = c;
        }
    }
    (path, cost)
}

/// The objective [`fill`] minimises, for any path (for checks and reports).
pub fn path_cost(table: &TransitionTable, layers: &[Layer], segment_intensity: &[f32], weights: &FillWeights, path: &[usize]) -> f32 {
    path_cost_with_node_costs(table, layers, segment_intensity, &[], weights, path)
}

/// The objective [`fill_with_node_costs`] minimises, for any path.
pub fn path_cost_with_node_costs(table: &TransitionTable, layers: &[Layer], segment_intensity: &[f32], node_cost: &[f32], weights: &FillWeights, path: &[usize]) -> f32 {
    path_cost_with_tempi(table, layers, segment_intensity, node_cost, &Tempi::default(), weights, path)
}

/// The objective [`fill_with_tempi`] minimises, for any path.
pub fn path_cost_with_tempi(table: &TransitionTable, layers: &[Layer], segment_intensity: &[f32], node_cost: &[f32], tempi: &Tempi, weights: &FillWeights, path: &[usize]) -> f32 {
    let mut c = 0.0;
    for (t, l) in layers.iter().enumerate() {
        let Some(&s) = path.get(t) else { return f32::INFINITY };
        if let Layer::Open { intensity } = l {
            c += weights.music_weight * (intensity - segment_intensity.get(s).copied().unwrap_or(f32::INFINITY)).abs();
            c += node_cost.get(s).copied().unwrap_or(0.0);
            c += tempi.cost(weights, t, s);
            if !table.is_available(s) {
                return f32::INFINITY;
            }
        }
        if t > 0 {
            c += table.cost(path[t - 1], s);
        }
        if weights.repeat_window > 1 && matches!(l, Layer::Open { .. }) && repeats_too_soon(path, t, weights.repeat_window) {
            c += weights.repeat_penalty;
        }
        if let (Some(variety), Layer::Open { .. }) = (tempi.variety, l) {
            c += variety.charge_in_path(path, t);
        }
    }
    c
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_fast_path_finds_the_plain_dynamic_programmes_path() {
        // A library larger than the top lists (every column's list stops early where it can):
        // pseudo-random joins, a charge far above the rest on a third of the segments (as the
        // moves source's) and per-bar costs, against the plain programme over every pair (ties
        // to the lowest index; none here).
        let m = 3 * TOP_K + 17;
        let mut x = 12345u64;
        let mut rnd = move || {
            x = x.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (x >> 40) as f32 / (1u64 << 24) as f32
        };
        let costs: Vec<f32> = (0..m * m).map(|_| 0.05 + 2.0 * rnd() * rnd()).collect();
        let table = TransitionTable::from_costs(m, costs);
        let intensity: Vec<f32> = (0..m).map(|_| rnd()).collect();
        let n = 24;
        let layers: Vec<Layer> = (0..n).map(|t| Layer::Open { intensity: 0.5 + 0.45 * fmath::sin(t as f32 / 3.0) }).collect();
        let extra: Vec<Vec<f32>> = (0..n).map(|_| (0..m).map(|s| if s % 3 == 0 { 1000.0 } else { 0.3 * rnd() }).collect()).collect();
        let weights = FillWeights { repeat_penalty: 0.0, ..FillWeights::default() };
        let tempi = Tempi { extra: &extra, ..Tempi::default() };
        let (path, _, stats) = fill_with_tempi(&table, &layers, &intensity, &[], &tempi, &weights).unwrap();
        assert!(stats.full_scans < stats.open_columns / 2, "the fast path ran: {stats:?}");
        let node = |t: usize, b: usize| {
            let Layer::Open { intensity: i } = layers[t] else { unreachable!() };
            weights.music_weight * (i - intensity[b]).abs() + 0.0 + tempi.cost(&weights, t, b) + 0.0
        };
        let mut cur: Vec<f32> = (0..m).map(|b| node(0, b)).collect();
        let mut back: Vec<Vec<usize>> = vec![Vec::new()];
        for t in 1..n {
            let (mut next, mut arg) = (vec![0.0; m], vec![0usize; m]);
            for b in 0..m {
                let (mut best, mut at) = (f32::INFINITY, 0);
                for (a, p) in cur.iter().enumerate() {
                    let v = p + table.cost(a, b);
                    if v < best {
                        (best, at) = (v, a);
                    }
                }
                (next[b], arg[b]) = (best + node(t, b), at);
            }
            back.push(arg);
            cur = next;
        }
        let mut b = (0..m).fold(0, |k, s| if cur[s] < cur[k] { s } else { k });
        let mut plain = vec![0; n];
        for t in (0..n).rev() {
            plain[t] = b;
            if t > 0 {
                b = back[t][b];
            }
        }
        assert_eq!(path, plain);
        // The lists stopped by the cheapest node of all (session 18's bound, the control): the
        // same path, more entries tried.
        let cheapest = Tempi { top_lists_stop_at_rest: false, ..tempi };
        let (control, _, control_stats) = fill_with_tempi(&table, &layers, &intensity, &[], &cheapest, &weights).unwrap();
        assert_eq!(control, plain);
        assert!(stats.top_tries < control_stats.top_tries, "{stats:?} against {control_stats:?}");
        // Whole columns scanned entry by entry (the control of super::scan): the same path.
        let every = fill_with_tempi(&table, &layers, &intensity, &[], &Tempi { columns_scanned_by_chunks: false, ..tempi }, &weights).unwrap();
        assert_eq!((every.0, every.2.chunks_scanned), (plain, 0));
    }

    #[test]
    fn a_bar_takes_only_segments_of_its_own_count() {
        // Segments 0 and 2 have 4 counts, 1 has 3; segment 0 joins everything cheapest, so
        // without the metre rule it fills every bar. Bars in 3, 4, any (0), 3.
        let table = TransitionTable::from_costs(3, vec![0.1, 0.5, 0.5, 0.1, 0.5, 0.5, 0.1, 0.5, 0.5]);
        let layers = [Layer::Open { intensity: 0.5 }; 4];
        let weights = FillWeights { repeat_penalty: 0.0, ..FillWeights::default() };
        let free = fill_with_tempi(&table, &layers, &[0.5; 3], &[], &Tempi::default(), &weights).unwrap().0;
        assert_eq!(free, vec![0, 0, 0, 0]);
        let (bar_counts, segment_counts) = ([3, 4, 0, 3], [4, 3, 4]);
        let tempi = Tempi { bar_counts: &bar_counts, segment_counts: &segment_counts, ..Default::default() };
        let (path, cost, _) = fill_with_tempi(&table, &layers, &[0.5; 3], &[], &tempi, &weights).unwrap();
        assert_eq!(path, vec![1, 0, 0, 1]);
        assert!(cost.is_finite());
        // A pinned bar of another count is kept (the person's choice) and costs nothing extra.
        let pinned = [Layer::Fixed { segment: 0 }, Layer::Open { intensity: 0.5 }, Layer::Open { intensity: 0.5 }, Layer::Open { intensity: 0.5 }];
        let (path, cost, _) = fill_with_tempi(&table, &pinned, &[0.5; 3], &[], &tempi, &weights).unwrap();
        assert_eq!(path, vec![0, 0, 0, 1]);
        assert!(cost.is_finite());
        assert!((count_rate_bpm(3, 1.5) - 120.0).abs() < 1e-4);
    }

    #[test]
    fn the_stretch_term_prefers_moves_near_the_bars_count_rate() {
        // log2(120/60) = 1 octave; symmetric; nothing when off or unknown.
        assert!((stretch_cost(0.5, 120.0, 60.0) - 0.5).abs() < 1e-6);
        assert!((stretch_cost(0.5, 60.0, 120.0) - 0.5).abs() < 1e-6);
        assert_eq!(stretch_cost(0.0, 120.0, 60.0), 0.0);
        assert_eq!(stretch_cost(0.5, f32::NAN, 60.0), 0.0);
        assert!((bar_count_rate_bpm(2.0) - 120.0).abs() < 1e-4);
        // Two moves alike in every join and intensity, at 60 and 120 counts per minute, over
        // bars of 2 s (120 per minute) then 4 s (60): with the term each bar takes the move
        // at its rate; without it, the tie goes to the lower index.
        let table = TransitionTable::from_costs(2, vec![1.0; 4]);
        let layers = [Layer::Open { intensity: 0.5 }, Layer::Open { intensity: 0.5 }];
        let (bar_bpm, segment_bpm) = ([bar_count_rate_bpm(2.0), bar_count_rate_bpm(4.0)], [60.0, 120.0]);
        let tempi = Tempi { bar_bpm: &bar_bpm, segment_bpm: &segment_bpm, ..Default::default() };
        let on = FillWeights { stretch_weight: 0.5, repeat_penalty: 0.0, ..FillWeights::default() };
        let (path, cost, _) = fill_with_tempi(&table, &layers, &[0.5, 0.5], &[], &tempi, &on).unwrap();
        assert_eq!(path, vec![1, 0]);
        assert!((cost - 1.0).abs() < 1e-5, "{cost}");
        let off = FillWeights { stretch_weight: 0.0, ..on };
        let (path, _, _) = fill_with_tempi(&table, &layers, &[0.5, 0.5], &[], &tempi, &off).unwrap();
        assert_eq!(path, vec![0, 0]);
    }

    #[test]
    fn the_free_skate_pass_swaps_only_where_a_cleaner_segment_fits_nearly_as_well() {
        // Four segments, all joins alike (C = 1) except into and out of segment 3, whose joins
        // cost 0.5 more. Segment 0 fits the bars' intensity best but slides 8 cm/s above its
        // clip; 1 fits 0.02 worse with no excess; 2 fits 0.2 worse with none; 3 fits 0.01 worse
        // with none but joins badly.
        let m = 4;
        let costs: Vec<f32> = (0..m * m).map(|i| if i / m == 3 || i % m == 3 { 1.5 } else { 1.0 }).collect();
        let table = TransitionTable::from_costs(m, costs);
        let intensity = [0.5, 0.52, 0.7, 0.51];
        let ex = [8.0, 0.0, 0.0, 0.0];
        let excess = |_: usize, s: usize| ex[s];
        let w = FillWeights { repeat_penalty: 0.0, ..FillWeights::default() };
        let one = [Layer::Open { intensity: 0.5 }];
        let tempi = Tempi::default();
        // One bar (no joins): 0 is best; the pass moves it to the cheapest clean one, 3.
        let (path, _, _) = fill_with_tempi(&table, &one, &intensity, &[], &tempi, &w).unwrap();
        assert_eq!(path, vec![0]);
        let (swapped, cost) = free_skate_pass(&table, &one, &intensity, &[], &tempi, &w, FREE_SKATE_SLACK_DEFAULT, &excess, &path);
        assert_eq!(swapped, vec![3]);
        assert!((cost - 0.01).abs() < 1e-5, "{cost}");
        // Off: nothing changes. A slack below the rise: nothing changes.
        assert_eq!(free_skate_pass(&table, &one, &intensity, &[], &tempi, &w, 0.0, &excess, &path).0, vec![0]);
        assert_eq!(free_skate_pass(&table, &one, &intensity, &[], &tempi, &w, 0.005, &excess, &path).0, vec![0]);
        // Between two pinned bars of segment 2, the swap keeps its neighbours and never takes
        // segment 3, whose joins would cost 1.0 more.
        let three = [Layer::Fixed { segment: 2 }, Layer::Open { intensity: 0.5 }, Layer::Fixed { segment: 2 }];
        let (p3, c3) = free_skate_pass(&table, &three, &intensity, &[], &tempi, &w, FREE_SKATE_SLACK_DEFAULT, &excess, &[2, 0, 2]);
        assert_eq!(p3, vec![2, 1, 2]);
        assert!((c3 - 2.02).abs() < 1e-5, "{c3}");
        // With no excess anywhere the path is kept.
        assert_eq!(free_skate_pass(&table, &one, &intensity, &[], &tempi, &w, FREE_SKATE_SLACK_DEFAULT, &|_, _| 0.0, &path).0, vec![0]);
    }

    #[test]
    fn the_beat_rate_ladder_reaches_as_far_beside_a_heavier_beat_term() {
        let plain: Vec<f32> = beat_rate_ladder().collect();
        // The same weights, bit for bit (one ladder, extended).
        let same = |a: &[f32], b: &[f32]| a == b;
        assert_eq!(plain.len(), 12);
        assert_eq!(plain[0], 0.01);
        assert!((plain[11] - 0.01 * 2f32.sqrt().powi(11)).abs() <= 1e-6 * plain[11], "{}", plain[11]);
        // At the default beat term (or lighter): the plain ladder.
        assert!(same(&beat_rate_ladder_for(FillWeights::default().beat_weight).collect::<Vec<_>>(), &plain));
        assert!(same(&beat_rate_ladder_for(0.0).collect::<Vec<_>>(), &plain));
        // Beside the product's *my moves* × variety beat term: the plain ladder first, then on
        // in its steps to its top scaled by as much (the control: the plain top, 30 times lighter).
        let heavy = FillWeights::default().beat_weight * MINE_BEAT_FACTOR * VARIETY_BEAT_FACTOR;
        let long: Vec<f32> = beat_rate_ladder_for(heavy).collect();
        assert!(long.len() > plain.len() && same(&long[..plain.len()], &plain));
        let top = plain[plain.len() - 1] * MINE_BEAT_FACTOR * VARIETY_BEAT_FACTOR;
        let last = long[long.len() - 1];
        assert!(last <= top && last * std::f32::consts::SQRT_2 > top, "top {last} against {top}");
    }

    #[test]
    fn the_skate_ladder_beside_a_heavier_beat_term_scales_each_weight() {
        let plain: Vec<f32> = skate_ladder().collect();
        // At the default beat term, lighter, or 0 (the option off): the plain ladder, bit for bit.
        for w in [0.0, 0.1, FillWeights::default().beat_weight] {
            assert_eq!(skate_ladder_for(w).collect::<Vec<_>>(), plain);
        }
        // Beside the variety term's ×3 beat term: every weight ×3 (the control: the plain one).
        let heavy = FillWeights::default().beat_weight * VARIETY_BEAT_FACTOR;
        let scaled: Vec<f32> = skate_ladder_for(heavy).collect();
        assert_eq!(scaled.len(), plain.len());
        assert!(scaled.iter().zip(&plain).all(|(s, p)| (s - p * VARIETY_BEAT_FACTOR).abs() <= 1e-6 * s && s > p), "{scaled:?}");
    }

    #[test]
    fn one_beat_weight_rule_for_moves_source_and_variety() {
        let w = FillWeights::default();
        let beat = |source: MovesSource, imported: bool, variety: bool| fill_weights_for(FillWeights { moves_source: source, ..w }, imported, variety).beat_weight;
        assert_eq!(beat(MovesSource::Mixed, true, false), w.beat_weight);
        assert_eq!(beat(MovesSource::Mine, false, false), w.beat_weight);
        assert_eq!(beat(MovesSource::Mine, true, false), w.beat_weight * MINE_BEAT_FACTOR);
        assert_eq!(beat(MovesSource::Builtin, true, true), w.beat_weight * VARIETY_BEAT_FACTOR);
        assert_eq!(beat(MovesSource::Mine, true, true), w.beat_weight * MINE_BEAT_FACTOR * VARIETY_BEAT_FACTOR);
        // Only the beat term changes; a set weight of 0 stays off.
        let off = fill_weights_for(FillWeights { beat_weight: 0.0, ..w }, true, true);
        assert_eq!(off, FillWeights { beat_weight: 0.0, ..w });
    }

    #[test]
    fn node_costs_charge_misses_and_prefer_fitting_own_moves() {
        let w = FillWeights { beat_weight: 0.5, own_moves_preference: 0.1, ..FillWeights::default() };
        // Built-in on the beat, built-in off it, imported on it, imported off it.
        let c = node_costs(&w, &[1.0, 0.0, 0.9, 0.5], &[true, true, false, false]);
        let want = [0.1, 0.6, 0.05, 0.35];
        for (got, want) in c.iter().zip(want) {
            assert!((got - want).abs() < 1e-6, "{c:?}");
        }
        // With no imported moves there is nothing to prefer.
        let only = node_costs(&w, &[1.0, 0.0], &[true, true]);
        assert!((only[0] - 0.0).abs() < 1e-6 && (only[1] - 0.5).abs() < 1e-6, "{only:?}");
    }

    #[test]
    fn the_skate_term_prefers_planted_feet() {
        let w = FillWeights { beat_weight: 0.0, own_moves_preference: 0.0, skate_weight: 2.0, ..FillWeights::default() };
        // 10 and 40 cm/s of skate: 2.0 · 0.1 and 2.0 · 0.4; a missing or bad figure pays none.
        let c = node_costs_with_skate(&w, &[0.5, 0.5, 0.5], &[true, true, true], &[10.0, 40.0]);
        assert!((c[0] - 0.2).abs() < 1e-6 && (c[1] - 0.8).abs() < 1e-6 && c[2] == 0.0, "{c:?}");
        assert_eq!(node_costs_with_skate(&w, &[0.5], &[true], &[f32::NAN]), vec![0.0]);
        // Two moves alike in every join and intensity: the tie goes to the lower index without
        // the term, to the one whose feet stay put with it.
        let table = TransitionTable::from_costs(2, vec![1.0; 4]);
        let layers = [Layer::Open { intensity: 0.5 }];
        let skate = [35.0, 5.0];
        let off = FillWeights { skate_weight: 0.0, ..w };
        let (path, _, _) = fill_with_node_costs(&table, &layers, &[0.5, 0.5], &node_costs_with_skate(&off, &[], &[], &skate), &off).unwrap();
        assert_eq!(path, vec![0]);
        let (path, cost, _) = fill_with_node_costs(&table, &layers, &[0.5, 0.5], &node_costs_with_skate(&w, &[], &[], &skate), &w).unwrap();
        assert_eq!(path, vec![1]);
        assert!((cost - 0.1).abs() < 1e-5, "{cost}");
    }

    #[test]
    fn the_beat_rate_term_prefers_one_or_half_a_turn_per_count() {
        assert_eq!(beat_rate_cost(1.0), 0.0);
        assert_eq!(beat_rate_cost(0.5), 0.0);
        // Twice a count is an octave from 1; three quarters is between ½ and 1.
        assert!((beat_rate_cost(2.0) - 1.0).abs() < 1e-6);
        assert!((beat_rate_cost(0.75) - fmath::log2(0.75f32 / 0.5).min(fmath::log2(1.0f32 / 0.75))).abs() < 1e-6);
        // Never turning is charged as a quarter turn per count: an octave below ½.
        assert!((beat_rate_cost(0.0) - 1.0).abs() < 1e-6);
        assert_eq!(beat_rate_cost(f32::NAN), 0.0);
    }
}
