//! Generate (spec §G, with §J's goals): how the open bars of a dance are filled, as five stages
//! run in order, each a function of its inputs with the figure it checks.
//!
//! 1. [`fill_stage`]: the minimum-cost path of §G ([`super::fill`]) over the objective's terms.
//!    Its objective includes the variety term ([`super::variety`],
//!    [`GenerateOptions::variety_weight`]): nearby bars sharing a step, arm pattern or source
//!    clip cost more, so no kind of move dominates the dance.
//! 2. [`beat_rate_stage`]: the dance's kinetic beats per count, measured on the rendered dance,
//!    in [`super::BEAT_RATE_BAND`]; if not, refills with the beat-rate term at each weight of
//!    [`beat_rate_ladder_for`] (the plain ladder, continued to weigh as much beside the fill's
//!    scaled beat term) and keeps the first dance inside it.
//! 3. [`free_skate_stage`]: foot skate where it is free ([`super::free_skate_pass`]).
//! 4. [`skate_stage`]: the dance's foot skate no worse than its source clips'
//!    ([`skate_goal_cm_per_s`]); if not, refills charging skate at each weight of
//!    [`skate_ladder`], preferring one that lands no more bars off their counts as played or
//!    keeps its BAS-music as played; when no weight gives one, bars the moves whose bars slide
//!    past their own source clip's skate as played and refills ([`SKATE_BAN_ROUNDS`]: the
//!    ladder charges each move's predicted skate, which some cuts play far above).
//!
//!    4b. [`order_stage`], the preference order (issue 26): under *my moves*, a bar takes a
//!    built-in move only where the imported moves tried there miss the beat or join goal as
//!    the dance is played, and says why ([`BuiltinWhy`]).
//! 5. [`join_repair_stage`]: every join within [`GenerateOptions::join_jump_goal`]; if not,
//!    a few refills barring the move after every join over the goal at once, kept when they
//!    meet every goal; else bars the move after the worst join and refills, up to
//!    [`GenerateOptions::join_repairs`] times, keeping a refill only when it improves that
//!    join and keeps what the dance met; when that ends over the goal, the same again with
//!    stage 4's skate charge kept from the first refill (without it refills slide back past
//!    the skate goal and are refused), the smoother kept. A refill sliding past the skate goal makes the next
//!    charge skate ([`skate_ladder_for`]). With [`GenerateOptions::join_wider_reach`], when all
//!    that ends over the goal, it runs once more with a wider reach: each barred built-in move's
//!    other side barred with it (the mirrored pair joins with the same jump) and each refill
//!    windowed around the barred moves' bars (a whole refill moved the rough join elsewhere).
//!
//! Another take ([`GenerateOptions::take`], issue 26): take k > 0 runs the same stages on the
//! objective plus a penalty on the moves the earlier takes' dances chose in each bar
//! ([`takes`]), the weakest of [`TAKE_LADDER`] that makes it differ from each earlier take in at
//! least [`TAKE_DIFFER`] of the open bars while its objective stays within [`TAKE_SLACK`] of the
//! best; take 0 is the dance without it.
//!
//! Stages 2 to 4 render the dance unheld and measure it as §J does ([`dance_figures`]); stages
//! 4b and 5 measure it as it is played, feet held ([`played_figures`]);
//! a path's figures are measured once and kept ([`Measured`]). Deterministic: the same library,
//! bars and options give the same dance.

use std::collections::BTreeSet;
use std::sync::Arc;

use serde::{Deserialize, Serialize};

use super::fill::{
    bar_count_rate_bpm, beat_rate_cost, beat_rate_ladder_for, count_rate_bpm, fill_with_tempi, free_skate_pass, path_cost_with_tempi, MovesSource, MOVES_SOURCE_CHARGE, in_beat_rate_band, FREE_SKATE_SLACK_DEFAULT, node_costs_with_skate, skate_ladder, skate_ladder_for, FillError, FillWeights, Layer, Tempi, TransitionTable,
};
use super::notes::OFF_BEAT_MARGIN;
use super::profile::{self, Work};
use super::quality::JOIN_JUMP_GOAL;
use super::segment::SegmentLibrary;
use super::table::TableScope;
pub use super::figures::{dance_figures, played_figures, DanceFigures, Measured, Played, PlayedBar};
pub use super::takes::{takes, takes_explained, MAX_TAKE, TAKE_DIFFER, TAKE_LADDER, TAKE_SLACK};

mod order;
mod repair;
mod skate;
pub use order::{order_stage, ORDER_IMPORTED_FLOOR, ORDER_ROUNDS};
pub use repair::JOIN_BANS_AT_ONCE_TRIES;
pub use skate::SKATE_BAN_ROUNDS;
use crate::bars::Bar;

/// Refills the join repair tries at most by default ([`GenerateOptions::join_repairs`]).
pub const JOIN_REPAIRS: usize = 16;
/// Default [`GenerateOptions::variety_weight`]: see there.
pub const VARIETY_WEIGHT_DEFAULT: f32 = 0.25;

/// Cost added to a segment in the bar after a join it made too abrupt, so the refill takes
/// another there: far above any term of the objective (a ban that stays finite, so a bar
/// whose every segment is banned still gets one).
const JOIN_BAN: f32 = 100.0;

/// The settings of the pipeline's measured stages (the objective's terms are
/// [`FillWeights`]). Each field: its default, its range.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GenerateOptions {
    /// Stage 2, [`beat_rate_stage`]: follow the song's beat rate. Default true. Only when the
    /// objective's own `beat_rate_weight` is 0 (a weight above 0 is used as it is, on every
    /// song).
    pub follow_beat_rate: bool,
    /// Stage 3, [`free_skate_stage`]: how much the objective may rise per bar to take a segment
    /// whose feet slide less. Default [`super::FREE_SKATE_SLACK_DEFAULT`]; range 0..=10
    /// (0: stage off).
    pub free_skate_slack: f32,
    /// Stage 4, [`skate_stage`]: keep the dance's foot skate no worse than its source clips'.
    /// Default true.
    pub follow_skate: bool,
    /// Stage 5, [`join_repair_stage`]: keep every join within `join_jump_goal`. Default true.
    pub follow_joins: bool,
    /// The largest join jump stage 5 accepts (spec §J). Default [`JOIN_JUMP_GOAL`] (1.5);
    /// range 0..=100.
    pub join_jump_goal: f32,
    /// Refills stage 5 tries at most. Default [`JOIN_REPAIRS`] (16); range 0..=64.
    pub join_repairs: usize,
    /// Weight of the variety term ([`super::variety`], issue 26): the cost of a bar sharing a
    /// step, an arm pattern or a source clip with the bar before (less further back, up to
    /// [`super::variety::VARIETY_WINDOW`] bars). Default [`VARIETY_WEIGHT_DEFAULT`]; range 0..=10
    /// (0: off, the plain objective).
    pub variety_weight: f32,
    /// Which take (issue 26, "another take"): 0 is the dance of least cost; take k > 0 is a
    /// different dance of comparable cost ([`takes`]). Deterministic: the same take of
    /// the same problem is the same dance. Default 0; range 0..=[`MAX_TAKE`].
    pub take: u32,
    /// Stage 4b, [`order_stage`]: under [`MovesSource::Mine`], a bar takes a built-in move only
    /// where the imported moves tried there miss the beat or join goal as the dance is played.
    /// Default true; false: the control (the source's charge alone keeps built-in moves out of
    /// every bar an imported move of its count fits, session 13's rule).
    pub follow_order: bool,
    /// Stage 5 (and 1b) measure the dance as it is played ([`played_figures`]: joins blended,
    /// feet held), what the viewer sees. Default true; false: the control (unheld, session
    /// 13's rule, blind to a join the held feet make abrupt).
    pub measure_played: bool,
    /// Stages 4b and 5 refill only the bars around those a refill changes the cost of
    /// ([`super::refill`]: a window with its neighbours fixed), not the whole dance. Default
    /// false (issue 26's speed goal: measured by `choreo_generate`, not yet the default);
    /// false: every refill is a whole fill, the control.
    pub windowed_refills: bool,
    /// Stages 4b and 5 screen each refill by a measure near the bars it changes from the
    /// nearest dance measured whole ([`super::figures::Measured::screened`],
    /// [`super::figures::played_near`]: those bars and their neighbours rendered and measured,
    /// the rest kept), when the changed bars' windows are under half the dance; a refill the
    /// screen would keep (or that would end stage 5's pass) is measured whole before it is kept.
    /// Default true (issue 26's speed goal, session 33: the second bench library's Generate in
    /// 0.7 of the time, the same dance on both bench libraries); false: every refill measured
    /// whole, the control.
    pub windowed_measures: bool,
    /// Measure each dance posing only what the measures read ([`super::figures`]: the
    /// held-feet rule's free pass posed once for all its rounds, only the frames the 30 fps
    /// measures read, the played dance not measured twice, and since session 20 each of §J's
    /// measures of it taken once for the whole dance and its bars). The same figures and dances
    /// (`quick_measures_keep_every_figure`, `dance_fixture`). Default true; false: the control
    /// (session 15's measures), which `choreo_generate` times beside it.
    pub quick_measures: bool,
    /// Stage 5, [`join_repair_stage`], as played ([`GenerateOptions::measure_played`]): first
    /// up to [`JOIN_BANS_AT_ONCE_TRIES`] refills that each bar the move after every join over
    /// the goal in the measure they read, not only after the worst one, so one refill does the
    /// work of several; their dance is kept only when it meets the join goal, the skate goal and
    /// the beat-rate band the dance met; else the stage runs as with this off. Default true;
    /// false: the control (session 16's stage 5: one join a refill).
    pub join_bans_at_once: bool,
    /// Measure each dance as played posing, in every round of the held-feet rule, only the
    /// frames its measures read (the 30 fps samples: half of the 60 fps dance;
    /// `figures::played_figures_posed`). The same figures and dances
    /// (`posing_only_the_frames_read_keeps_every_figure`, `dance_fixture`). Default true; false:
    /// the control (session 17's measures), which `choreo_generate` times beside it.
    pub pose_read_frames_only: bool,
    /// Each fill's columns stop trying their cheapest predecessors once the cheapest node
    /// outside the previous layer's [`super::fill::LOW_L`] cheapest (whose every edge is tried
    /// first) with the next edge costs more than the best found ([`super::fill`]'s fast path).
    /// The same paths (`the_fast_path_finds_the_plain_dynamic_programmes_path`,
    /// `dance_fixture`); and each layer streams its cheapest nodes' rows vectorised. Default
    /// true; false: the control (session 18's fills, stopping by the cheapest node of all, a
    /// branch per lane in the stream, [`Tempi::top_lists_stop_at_rest`]), which `choreo_generate`
    /// times beside it.
    pub top_lists_stop_at_rest: bool,
    /// A fill's whole-column scans skip each chunk of predecessors whose cheapest node and
    /// edge already cost more than the best found ([`super::scan`]). The same paths. Default
    /// true; false: every entry scanned (session 19's fills, the control `choreo_generate` times).
    pub columns_scanned_by_chunks: bool,
    /// Stage 5, [`join_repair_stage`]: a refill sliding past the skate goal makes the next one
    /// charge skate at weights scaled beside the fill's beat term ([`skate_ladder_for`]), not the
    /// plain [`skate_ladder`] (0.1–0.4 moved no bar of Vibe Ace's refill beside the variety
    /// term's ×3 beat term: its take 0 joins at 1.47 with this on, 1.59 off). Default true
    /// (session 19, with stage 5's carried skate charge: `choreo_blended_cost`'s control dances
    /// join over 1.5 in 5 of 64, the blended-jump term's in 4); false: the plain ladder, the
    /// control (`docs/benchmarks-notes-choreo.md`, session 19).
    pub skate_beside_beat_term: bool,
    /// Measure each dance as played with the held-feet rule's free pass posing only the joints
    /// it reads (hips and legs, [`crate::canon::character::RetargetOptions::free_pass_legs_only`]),
    /// and the unheld dance measured from the source poses that pass posed, not posed again.
    /// The same figures and dances (`the_free_pass_posing_its_legs_alone_keeps_every_figure`,
    /// `dance_fixture`). Default true; false: the control (session 20's measures).
    pub free_pass_legs_only: bool,
    /// Stage 5, [`join_repair_stage`]: when its runs end over the join goal, run them once more
    /// with a wider reach (`generate/repair.rs`: each barred built-in move's other side barred
    /// too, refills windowed) and keep the smoother dance. Default true (with the built-in
    /// moves held on the counts, session 26): with those moves it brings Vibe Ace's take 3 from
    /// 1.67 to 1.43 and changes no dance within the goal (`docs/benchmarks-notes-choreo.md`,
    /// session 21); false: the control.
    pub join_wider_reach: bool,
    /// Measure each dance as played with the held-feet rule's rounds after the first copying
    /// the last round's held frames whose plan (each foot's target, the pelvis drop, the body's
    /// shift, the toe pitch) is the same bits, and the positions its measure posed of frames
    /// that are the same bits, not posing them again (`canon::character`'s `HeldFrames`,
    /// `QualityMotion::from_clip_reusing`). The same figures and dances
    /// (`copying_the_rounds_same_frames_changes_no_frame`). Default true; false: the control
    /// (session 24's measures).
    pub rounds_copy_same_frames: bool,
}

impl Default for GenerateOptions {
    fn default() -> Self {
        GenerateOptions {
            follow_beat_rate: true,
            free_skate_slack: FREE_SKATE_SLACK_DEFAULT,
            follow_skate: true,
            follow_joins: true,
            join_jump_goal: JOIN_JUMP_GOAL,
            join_repairs: JOIN_REPAIRS,
            variety_weight: VARIETY_WEIGHT_DEFAULT,
            take: 0,
            follow_order: true,
            measure_played: true,
            windowed_refills: false,
            windowed_measures: true,
            quick_measures: true,
            join_bans_at_once: true,
            pose_read_frames_only: true,
            top_lists_stop_at_rest: true,
            columns_scanned_by_chunks: true,
            skate_beside_beat_term: true,
            free_pass_legs_only: true,
            join_wider_reach: true,
            rounds_copy_same_frames: true,
        }
    }
}

impl GenerateOptions {
    /// Refused with the setting's name, range and value when a number is out of its range.
    pub fn validate(&self) -> Result<(), super::ChoreoError> {
        let bad = |name: &str, range: &str, value: f32| Err(super::ChoreoError::BadSetting { name: name.into(), range: range.into(), value });
        if !(0.0..=10.0).contains(&self.free_skate_slack) {
            return bad("freeSkateSlack", "0..=10", self.free_skate_slack);
        }
        if !(0.0..=100.0).contains(&self.join_jump_goal) {
            return bad("joinJumpGoal", "0..=100", self.join_jump_goal);
        }
        if self.join_repairs > 64 {
            return bad("joinRepairs", "0..=64", self.join_repairs as f32);
        }
        if !(0.0..=10.0).contains(&self.variety_weight) {
            return bad("varietyWeight", "0..=10", self.variety_weight);
        }
        if self.take > MAX_TAKE {
            return bad("take", "0..=15", self.take as f32);
        }
        Ok(())
    }
}

/// Why a bar holds a built-in move under [`MovesSource::Mine`] (issue 26's preference order:
/// built-in moves fill only where no imported move does), for the bar's readout
/// ([`super::notes::MoveNote::builtin_why`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "camelCase")]
pub enum BuiltinWhy {
    /// The library holds no imported move of the bar's count (e.g. none in 3).
    NoneOfItsCount { counts: usize },
    /// The imported moves tried in the bar missed its counts as played (the strip's "off the
    /// beat" rule, [`PlayedBar::beat_margin`]).
    OffBeat,
    /// The imported moves tried in the bar joined it over the join goal as played.
    RoughJoin,
}

impl BuiltinWhy {
    /// In words, for the strip.
    pub fn words(&self) -> String {
        match self {
            BuiltinWhy::NoneOfItsCount { counts } => format!("built-in: none of your moves is a bar of {counts} counts"),
            BuiltinWhy::OffBeat => "built-in: no move of yours tried here lands on the beat".to_string(),
            BuiltinWhy::RoughJoin => "built-in: no move of yours tried here joins smoothly".to_string(),
        }
    }
}

/// The counts each bar takes (spec §E, [`super::segment`]'s module docs): its beats, when the
/// library holds a live segment of that many counts; 0 (any segment) when it holds none.
pub fn bar_counts(lib: &SegmentLibrary, bars: &[Bar]) -> Vec<usize> {
    let mut has = BTreeSet::new();
    for s in lib.segments().iter().filter(|s| !s.retired) {
        has.insert(s.counts());
    }
    bars.iter().map(|b| if has.contains(&b.beat_count()) { b.beat_count() } else { 0 }).collect()
}

/// The foot skate a dance on `path` should not exceed (spec §J: no worse than its source
/// clips'): per bar, the mean skate of the source clips of its segment's kind (imported or
/// built-in), averaged over the bars.
pub fn skate_goal_cm_per_s(lib: &SegmentLibrary, path: &[usize]) -> f32 {
    let mut seen = BTreeSet::new();
    let (mut sum, mut n) = ([0.0f32; 2], [0usize; 2]);
    for s in lib.segments() {
        if seen.insert(s.clip) {
            let k = usize::from(s.builtin.is_some());
            sum[k] += s.clip_skate_cm_per_s;
            n[k] += 1;
        }
    }
    let mean = |k: usize| sum[k] / n[k].max(1) as f32;
    path.iter().map(|&s| mean(usize::from(lib.segments()[s].builtin.is_some()))).sum::<f32>() / path.len().max(1) as f32
}

/// The filling problem every stage reads: the library, the bars and their layers (open or
/// pinned), the objective's weights and what they are computed from (the transition table of
/// the song's metres, each segment's node cost, the bars' and segments' count rates and
/// metres, and each segment's beat-rate cost at each bar's count rate when a stage needs it).
pub struct Problem<'a> {
    pub lib: &'a SegmentLibrary,
    pub bars: &'a [Bar],
    pub layers: &'a [Layer],
    pub weights: FillWeights,
    pub(super) table: Arc<TransitionTable>,
    pub(super) intensity: Vec<f32>,
    pub(super) node_cost: Vec<f32>,
    bar_counts: Vec<usize>,
    segment_counts: Vec<usize>,
    bar_bpm: Vec<f32>,
    segment_bpm: Vec<f32>,
    beat_rate: Vec<Vec<f32>>,
    /// Whether stage 2 runs (its switch on, no fixed beat-rate weight, rates measured).
    follow_beat_rate: bool,
    /// Stage 3's slack ([`GenerateOptions::free_skate_slack`]).
    free_skate_slack: f32,
    /// [`GenerateOptions::join_jump_goal`], which stage 4's bans keep.
    join_jump_goal: f32,
    /// The variety term ([`GenerateOptions::variety_weight`]); None when off.
    variety: Option<super::variety::Variety>,
    /// Per layer, per segment: a cost every fill of this problem adds (the moves source's
    /// charge, a take's penalty on the earlier takes' moves, [`takes`], and the charge lifted
    /// where [`order_stage`] opened a bar). Empty: none.
    pub(super) base: Vec<Vec<f32>>,
    /// The moves source's charge ([`Problem::moves_source_charge`]), per layer and segment.
    charge: Vec<Vec<f32>>,
    /// Per layer, why the preference order opened the bar to built-in moves (the last
    /// pipeline run's, [`order_stage`] and [`join_repair_stage`]).
    why: std::cell::RefCell<Vec<Option<BuiltinWhy>>>,
    /// Per layer, whether the charge is already lifted in `base` ([`order_stage`]).
    opened: Vec<bool>,
    /// [`GenerateOptions::quick_measures`].
    pub(super) quick_measures: bool,
    /// [`GenerateOptions::windowed_measures`].
    pub(super) windowed_measures: bool,
    /// [`GenerateOptions::pose_read_frames_only`].
    pub(super) pose_read_frames_only: bool,
    /// [`GenerateOptions::free_pass_legs_only`].
    pub(super) free_pass_legs_only: bool,
    /// [`GenerateOptions::rounds_copy_same_frames`].
    pub(super) rounds_copy_same_frames: bool,
    /// [`GenerateOptions::top_lists_stop_at_rest`], [`GenerateOptions::columns_scanned_by_chunks`].
    top_lists_stop_at_rest: bool,
    columns_scanned_by_chunks: bool,
}

impl<'a> Problem<'a> {
    /// The problem of filling `layers` (one per bar of `bars`) from `lib` with `weights`.
    pub fn new(lib: &'a SegmentLibrary, bars: &'a [Bar], layers: &'a [Layer], weights: FillWeights, options: &GenerateOptions) -> Self {
        let variety = Some(super::variety::Variety::new(lib, options.variety_weight)).filter(super::variety::Variety::is_on);
        let has_imported = lib.segments().iter().any(|s| s.builtin.is_none() && !s.retired);
        let weights = super::fill::fill_weights_for(weights, has_imported, variety.is_some());
        // The joins this song's bars make (its metres, and any change between two bars).
        let bar_counts = bar_counts(lib, bars);
        let table = lib.transition_table_for(weights.repeat_penalty, &TableScope::for_bar_counts(&bar_counts));
        let intensity: Vec<f32> = lib.segments().iter().map(|s| s.intensity01).collect();
        let beat_fit: Vec<f32> = lib.segments().iter().map(|s| s.beat_fit).collect();
        let builtin: Vec<bool> = lib.segments().iter().map(|s| s.builtin.is_some()).collect();
        // Skate beyond the source clip's own (the §J goal is "no worse than the source clips'").
        let skate: Vec<f32> = lib.segments().iter().map(|s| (s.skate_cm_per_s - s.clip_skate_cm_per_s).max(0.0)).collect();
        let node_cost = node_costs_with_skate(&weights, &beat_fit, &builtin, &skate);
        // The bar's metre: a bar of n beats takes segments of n counts (0: any), played at n
        // counts over the bar.
        let segment_counts: Vec<usize> = lib.segments().iter().map(|s| s.counts()).collect();
        let bar_bpm: Vec<f32> = bars.iter().zip(&bar_counts).map(|(b, &n)| if n == 0 { bar_count_rate_bpm(b.duration_secs()) } else { count_rate_bpm(n, b.duration_secs()) }).collect();
        let segment_bpm: Vec<f32> = lib.segments().iter().map(|s| s.tempo_bpm).collect();
        // Each segment's kinetic beats per count at each bar's count rate, and its beat-rate cost.
        let follow = options.follow_beat_rate && weights.beat_rate_weight == 0.0;
        let kinetic: Vec<Vec<f32>> = if follow || weights.beat_rate_weight > 0.0 {
            bar_bpm.iter().map(|&r| lib.segments().iter().map(|s| s.kinetic_per_count_at(r)).collect()).collect()
        } else {
            Vec::new()
        };
        let beat_rate: Vec<Vec<f32>> = kinetic.iter().map(|v| v.iter().map(|&k| beat_rate_cost(k)).collect()).collect();
        let follow_beat_rate = follow && !kinetic.is_empty();
        let mut p = Problem {
            lib,
            bars,
            layers,
            weights,
            table,
            intensity,
            node_cost,
            bar_counts,
            segment_counts,
            bar_bpm,
            segment_bpm,
            beat_rate,
            follow_beat_rate,
            free_skate_slack: options.free_skate_slack,
            join_jump_goal: options.join_jump_goal,
            variety,
            base: Vec::new(),
            charge: Vec::new(),
            why: std::cell::RefCell::new(vec![None; layers.len()]),
            opened: vec![false; layers.len()],
            quick_measures: options.quick_measures,
            windowed_measures: options.windowed_measures,
            pose_read_frames_only: options.pose_read_frames_only,
            free_pass_legs_only: options.free_pass_legs_only,
            rounds_copy_same_frames: options.rounds_copy_same_frames,
            top_lists_stop_at_rest: options.top_lists_stop_at_rest,
            columns_scanned_by_chunks: options.columns_scanned_by_chunks,
        };
        p.charge = p.moves_source_charge();
        p.base = p.charge.clone();
        p
    }

    /// `extra` with the problem's base cost added (each as it is when the other is empty).
    pub(super) fn with_base<'b>(&'b self, extra: &'b [Vec<f32>]) -> std::borrow::Cow<'b, [Vec<f32>]> {
        if self.base.is_empty() {
            return std::borrow::Cow::Borrowed(extra);
        }
        if extra.is_empty() {
            return std::borrow::Cow::Borrowed(&self.base);
        }
        std::borrow::Cow::Owned(self.base.iter().zip(extra).map(|(b, e)| b.iter().zip(e).map(|(x, y)| x + y).collect()).collect())
    }

    /// The objective of `path` with the problem's own weights and no added cost: what takes
    /// are compared by.
    pub fn objective(&self, path: &[usize]) -> f32 {
        path_cost_with_tempi(&self.table, self.layers, &self.intensity, &self.node_cost, &self.tempi(&[]), &self.weights, path)
    }

    /// The charge of [`FillWeights::moves_source`] per open bar and segment (empty: none):
    /// [`MOVES_SOURCE_CHARGE`] on a move of the kind put second, in a bar the library holds a
    /// live move of the other kind and of the bar's count for.
    fn moves_source_charge(&self) -> Vec<Vec<f32>> {
        let second_is_builtin = match self.weights.moves_source {
            MovesSource::Mixed => return Vec::new(),
            MovesSource::Mine => true,
            MovesSource::Builtin => false,
        };
        let builtin: Vec<bool> = self.lib.segments().iter().map(|s| s.builtin.is_some()).collect();
        let first_kind = |t: usize| self.lib.segments().iter().any(|s| !s.retired && builtin[s.index] != second_is_builtin && (self.bar_counts[t] == 0 || s.counts() == self.bar_counts[t]));
        self.layers
            .iter()
            .enumerate()
            .map(|(t, l)| {
                let charged = matches!(l, Layer::Open { .. }) && first_kind(t);
                builtin.iter().map(|&b| if charged && b == second_is_builtin { MOVES_SOURCE_CHARGE } else { 0.0 }).collect()
            })
            .collect()
    }

    /// Lifts the moves source's charge ([`Problem::moves_source_charge`]) in bar `t` by
    /// adding its negative to `extra` (a full matrix, one row per layer): with it, the
    /// moves the source puts second compete in that bar on their own merits. Used under
    /// [`MovesSource::Mine`] for a bar whose imported move misses the join goal
    /// ([`join_repair_stage`]): the preference order of issue 26, built-in moves only where no
    /// imported move meets the goals.
    fn lift_charge(&self, extra: &mut [Vec<f32>], t: usize) {
        if self.opened.get(t).copied().unwrap_or(false) {
            return;
        }
        if let (Some(base), Some(row)) = (self.charge.get(t), extra.get_mut(t)) {
            for (e, b) in row.iter_mut().zip(base) {
                *e -= b;
            }
        }
    }

    /// The count rates and metres of the problem, with `extra` added per bar and segment.
    pub(super) fn tempi<'b>(&'b self, extra: &'b [Vec<f32>]) -> Tempi<'b> {
        Tempi { bar_bpm: &self.bar_bpm, segment_bpm: &self.segment_bpm, beat_rate: &self.beat_rate, extra, bar_counts: &self.bar_counts, segment_counts: &self.segment_counts, variety: self.variety.as_ref(), top_lists_stop_at_rest: self.top_lists_stop_at_rest, columns_scanned_by_chunks: self.columns_scanned_by_chunks }
    }

    /// The minimum-cost path with `weights` and `extra` costs.
    fn fill(&self, weights: &FillWeights, extra: &[Vec<f32>]) -> Result<Vec<usize>, FillError> {
        let extra = self.with_base(extra);
        profile::timed(Work::Fill, || Ok(fill_with_tempi(&self.table, self.layers, &self.intensity, &self.node_cost, &self.tempi(&extra), weights)?.0))
    }

    /// [`free_skate_pass`] over the problem with `weights` and `extra` costs.
    fn free_skate(&self, weights: &FillWeights, extra: &[Vec<f32>], path: &[usize]) -> (Vec<usize>, f32) {
        let excess = |t: usize, s: usize| self.skate_excess(t, s);
        let extra = self.with_base(extra);
        profile::timed(Work::Fill, || free_skate_pass(&self.table, self.layers, &self.intensity, &self.node_cost, &self.tempi(&extra), weights, self.free_skate_slack, &excess, path))
    }

    /// §N's foot skate goal of the dance `path`: each bar's source clip's skate at the bar's
    /// pace (skate is a speed), averaged over the bars.
    pub fn paced_source_skate_cm_per_s(&self, path: &[usize]) -> f32 {
        let v: Vec<f32> = path
            .iter()
            .enumerate()
            .filter_map(|(t, &s)| {
                let seg = self.lib.segments().get(s)?;
                Some(seg.clip_skate_at(self.bar_bpm.get(t).copied().unwrap_or(0.0)))
            })
            .collect();
        v.iter().sum::<f32>() / v.len().max(1) as f32
    }

    /// The dance `path`'s source clips' own foot skate, unpaced (each bar's clip at its own
    /// tempo), averaged over the bars.
    pub fn source_skate_cm_per_s(&self, path: &[usize]) -> f32 {
        let v: Vec<f32> = path.iter().filter_map(|&s| self.lib.segments().get(s).map(|seg| seg.clip_skate_cm_per_s)).collect();
        v.iter().sum::<f32>() / v.len().max(1) as f32
    }

    /// Segment `s`'s skate above its clip's as bar `t` plays it: its feet slide faster by the
    /// factor it is sped up by (a salsa bar at 80 counts per minute on a bar at 140 slides 1.75
    /// times as fast), against its clip's at the clip's own tempo.
    pub fn skate_excess(&self, t: usize, s: usize) -> f32 {
        let seg = &self.lib.segments()[s];
        let speed_up = if seg.tempo_bpm > 0.0 && self.bar_bpm[t] > 0.0 { self.bar_bpm[t] / seg.tempo_bpm } else { 1.0 };
        seg.skate_cm_per_s * speed_up - seg.clip_skate_cm_per_s
    }
}

/// Stage 1: the minimum-cost path of spec §G over the objective's terms ([`super::fill`]).
pub fn fill_stage(p: &Problem) -> Result<Vec<usize>, FillError> {
    p.fill(&p.weights, &[])
}

/// Stage 2: the dance's kinetic beat rate near the song's ([`GenerateOptions::follow_beat_rate`]),
/// measured on the dance itself as §J measures it (the segments' own rates at the bars' count
/// rates miss what the joins and neighbours add: 0.2 a count on slow songs). Figure: kinetic
/// beats per count in [`super::BEAT_RATE_BAND`]. When `path`'s dance is outside it, refills with the
/// beat-rate term at each weight of [`beat_rate_ladder_for`] the fill's beat term, weakest first
/// (the beat term weighs 30 times the default under *my moves* with variety, and the plain
/// ladder beside it moved no bar), and returns the first dance inside it with the weights that
/// made it; else `path` and the problem's weights.
pub fn beat_rate_stage(p: &Problem, path: Vec<usize>, measured: &mut Measured) -> Result<(Vec<usize>, FillWeights), FillError> {
    if !p.follow_beat_rate {
        return Ok((path, p.weights));
    }
    let first = measured.of(p, &path);
    if first.is_some_and(|f| !in_beat_rate_band(f.kinetic_per_count)) {
        for w in beat_rate_ladder_for(p.weights.beat_weight) {
            let stronger = FillWeights { beat_rate_weight: w, ..p.weights };
            let q = p.fill(&stronger, &[])?;
            if measured.of(p, &q).is_some_and(|f| in_beat_rate_band(f.kinetic_per_count)) {
                return Ok((q, stronger));
            }
        }
    }
    Ok((path, p.weights))
}

/// Stage 3: foot skate where it is free ([`free_skate_pass`] with
/// [`GenerateOptions::free_skate_slack`]): returns the path and its cost (the full objective
/// with `weights`).
pub fn free_skate_stage(p: &Problem, weights: &FillWeights, path: &[usize]) -> (Vec<usize>, f32) {
    p.free_skate(weights, &[], path)
}

/// Stage 4: foot skate no worse than the source clips' ([`GenerateOptions::follow_skate`]).
/// Figure: the dance's mean foot skate ≤ [`skate_goal_cm_per_s`]. When `path`'s dance slides
/// more, refills charging each segment's skate above its clip's as the bar plays it at each
/// weight of [`skate_ladder`], weakest first, and returns the first dance within the goal (and
/// still in the beat-rate band, if `path`'s was); beat alignment being a floor (§J, §N), a dance
/// with both more bars off their counts as played ([`PlayedBar::beat_margin`] under
/// [`OFF_BEAT_MARGIN`]) and a lower BAS-music as played than `path`'s is returned only when no
/// weight gives one without. When no weight gives a dance within the goals, the moves whose bars
/// slide past their own goal as played are barred and the dance refilled ([`SKATE_BAN_ROUNDS`],
/// `generate/skate.rs`: the ladder charges a prediction that some cuts play far above, e.g.
/// the trumpet loop of `choreo_my_moves`, 28.5 cm/s predicted, 53.4 played); else `path` and
/// `cost`. Also returns the skate weight of the ladder's refill kept (0: none), which stage 5
/// may charge ([`join_repair_stage`]'s `carried`).
pub fn skate_stage(p: &Problem, weights: &FillWeights, path: Vec<usize>, cost: f32, measured: &mut Measured) -> Result<(Vec<usize>, f32, f32), FillError> {
    let Some(before) = measured.of(p, &path).filter(|f| f.foot_skate_cm_per_s > skate_goal_cm_per_s(p.lib, &path)) else {
        return Ok((path, cost, 0.0));
    };
    let on_beat = in_beat_rate_band(before.kinetic_per_count);
    // Beat alignment is a floor (spec §J, §N): bars landing off their counts as played (BAS-music
    // less than OFF_BEAT_MARGIN above the half-shifted counts') and BAS-music as played, on entry.
    let off_beat = |m: &mut Measured, q: &[usize]| m.played(p, q).map(|f| (f.bars.iter().filter(|b| b.beat_margin < OFF_BEAT_MARGIN).count(), f.bas_music));
    let off_on_entry = off_beat(measured, &path);
    let over: Vec<Vec<f32>> = (0..p.layers.len()).map(|t| (0..p.lib.len()).map(|s| p.skate_excess(t, s).max(0.0) / 100.0).collect()).collect();
    // The first refill within the goals that lands more bars off their counts at a lower
    // BAS-music: kept only if no later one keeps either.
    let mut off_the_counts: Option<(Vec<usize>, f32, f32)> = None;
    for w in skate_ladder() {
        let extra: Vec<Vec<f32>> = over.iter().map(|v| v.iter().map(|x| w * x).collect()).collect();
        let q = p.fill(weights, &extra)?;
        let (q, c) = p.free_skate(weights, &[], &q);
        let Some(f) = measured.of(p, &q) else { continue };
        if f.foot_skate_cm_per_s <= skate_goal_cm_per_s(p.lib, &q) && (!on_beat || in_beat_rate_band(f.kinetic_per_count)) {
            if off_on_entry.is_some_and(|(n, bas)| off_beat(measured, &q).is_none_or(|(m, b)| m > n && b < bas)) {
                off_the_counts.get_or_insert((q, c, w));
                continue;
            }
            return Ok((q, c, w));
        }
    }
    if off_the_counts.is_none() {
        if let Some((q, c)) = skate::skate_bans(p, weights, &path, measured)? {
            return Ok((q, c, 0.0));
        }
    }
    Ok(off_the_counts.unwrap_or((path, cost, 0.0)))
}

/// Stage 5: joins no more abrupt than [`GenerateOptions::join_jump_goal`]
/// ([`GenerateOptions::follow_joins`]), measured on the dance: the table's cost (§G, link
/// directions and end gaps) misses some abrupt joins, e.g. between two crouched moves of the
/// Indian clips in 3/4, where fewer moves fit a bar. Figure: the largest join jump.
///
/// Each refill bars, from every bar, the move after the worst join of the last refill (the same
/// move makes the same abrupt join wherever the filling puts it after a like move), so the bars
/// add up over the tries. Measured as played, with [`GenerateOptions::join_bans_at_once`] (the
/// default), the stage first tries [`JOIN_BANS_AT_ONCE_TRIES`] refills that bar the move after
/// every join over the goal in the last measure, and keeps their dance when it meets every goal
/// (joins, skate goal, beat-rate band); else it starts again from `path` one join a refill (the
/// 90-bar bench of session 17, its medley laid end to end: 3 refills to a worst join of 0.84, where one join a refill spent all 16 and
/// ended at 5.55; `docs/benchmarks-notes-choreo.md`). Under [`MovesSource::Mine`], the bar of a barred imported move is
/// also opened to built-in moves (the source's charge lifted there, [`Problem::lift_charge`]):
/// the preference order of issue 26 — built-in moves fill only bars where no imported move
/// meets the goals — where the charge alone kept them out of every bar an imported move fits. A refill whose feet slide past the goal the dance
/// met makes the next one charge skate too, at the next weight of [`skate_ladder`] (with
/// [`GenerateOptions::skate_beside_beat_term`], of [`skate_ladder_for`] the fill's beat term). When the
/// refills end over the join goal and stage 4 kept a refill charging skate (`carried`, its weight
/// from [`skate_stage`]), they run again from `path` charging that weight from the first refill (the ladder climbs a weight a refill,
/// so refills that drop stage 4's charge slide back past the goal and are refused;
/// `docs/benchmarks-notes-choreo.md`), and the smoother of the two is kept. The best dance that keeps what
/// the first one met (beat-rate band, skate goal; a dance already past the skate goal slides no
/// more than it did) with a better worst join is returned; else `path` and `cost`. With
/// [`GenerateOptions::join_wider_reach`], when that dance is still over the goal, all of it runs
/// again from `path` with a wider reach
/// (`generate/repair.rs`: each barred move's other side barred too, refills windowed,
/// [`super::refill`]), and the smoother dance is kept: a dance within the goal is as before.
pub fn join_repair_stage(p: &Problem, weights: &FillWeights, options: &GenerateOptions, path: Vec<usize>, cost: f32, carried: f32, measured: &mut Measured) -> Result<(Vec<usize>, f32), FillError> {
    if p.layers.len() < 2 {
        return Ok((path, cost));
    }
    let why = p.why.borrow().clone();
    let worst = |m: &mut Measured, q: &[usize]| m.figures(p, q, options.measure_played).map_or(f32::INFINITY, |f| f.join_jump_max);
    let (q, c) = repair::runs(p, weights, options, &path, cost, carried, measured, false)?;
    if !options.join_wider_reach || worst(measured, &q) <= options.join_jump_goal {
        return Ok((q, c));
    }
    let first_why = std::mem::replace(&mut *p.why.borrow_mut(), why);
    let (r, d) = repair::runs(p, weights, options, &path, cost, carried, measured, true)?;
    if worst(measured, &r) < worst(measured, &q) {
        return Ok((r, d));
    }
    *p.why.borrow_mut() = first_why;
    Ok((q, c))
}

/// The whole pipeline: stages 1 to 5 in order on the problem of filling `layers` (one per bar
/// of `bars`) from `lib`, for take [`GenerateOptions::take`] ([`takes`]). Returns one segment per
/// bar (pinned bars keep theirs) and the path's cost (the objective with `weights`, without any
/// stage's or take's charge, so dances and takes compare: [`Problem::objective`]).
pub fn generate(lib: &SegmentLibrary, bars: &[Bar], layers: &[Layer], weights: FillWeights, options: &GenerateOptions) -> Result<(Vec<usize>, f32), FillError> {
    generate_explained(lib, bars, layers, weights, options).map(|(path, cost, _)| (path, cost))
}

/// [`generate`], with why each built-in bar of the dance is ([`BuiltinWhy`]; `None` for a bar
/// holding an imported move, a pinned bar, or where the moves source is not *my moves*).
pub fn generate_explained(lib: &SegmentLibrary, bars: &[Bar], layers: &[Layer], weights: FillWeights, options: &GenerateOptions) -> Result<(Vec<usize>, f32, Vec<Option<BuiltinWhy>>), FillError> {
    let mut p = Problem::new(lib, bars, layers, weights, options);
    let (path, why) = takes_explained(&mut p, options, options.take)?;
    let cost = p.objective(&path);
    Ok((path, cost, why))
}

/// Generate where the song's sections repeat (issue 26 item 2: a repeated section may take the
/// same moves, as real choreography does). `repeat_of[t]` is the earlier bar bar t repeats
/// (`music::Sections::repeat_of_bars`; empty or all `None`: [`generate`] as it is). The pipeline
/// runs once; then every open bar that repeats a bar, and the bar it repeats, are pinned to the
/// move that bar took (its pin, when the person pinned it: a marked repeat of a pinned bar
/// repeats the pin), and the pipeline runs again for the other bars, so the bars
/// around a repeated section join it. Returns the dance, its objective on `layers` (the repeat
/// is charged nothing beyond what the moves cost: a repeated section pays its repeat window and
/// variety as any other bars) and, per bar, the bar whose move it repeats.
pub fn generate_with_repeats(lib: &SegmentLibrary, bars: &[Bar], layers: &[Layer], weights: FillWeights, options: &GenerateOptions, repeat_of: &[Option<usize>]) -> Result<(Vec<usize>, f32, Vec<Option<usize>>), FillError> {
    generate_with_repeats_explained(lib, bars, layers, weights, options, repeat_of).map(|(path, cost, repeats, _)| (path, cost, repeats))
}

/// [`generate_with_repeats`], with why each built-in bar is ([`generate_explained`]; a bar
/// pinned for the second run keeps the first run's reason).
#[allow(clippy::type_complexity)]
pub fn generate_with_repeats_explained(lib: &SegmentLibrary, bars: &[Bar], layers: &[Layer], weights: FillWeights, options: &GenerateOptions, repeat_of: &[Option<usize>]) -> Result<(Vec<usize>, f32, Vec<Option<usize>>, Vec<Option<BuiltinWhy>>), FillError> {
    let (first, cost, first_why) = generate_explained(lib, bars, layers, weights, options)?;
    let open = |t: usize| matches!(layers.get(t), Some(Layer::Open { .. }));
    let repeats: Vec<Option<usize>> = (0..layers.len()).map(|t| repeat_of.get(t).copied().flatten().filter(|&r| r < t && open(t) && r < layers.len())).collect();
    if repeats.iter().all(Option::is_none) {
        return Ok((first, cost, repeats, first_why));
    }
    let mut pinned = layers.to_vec();
    for (t, &r) in repeats.iter().enumerate() {
        let Some(r) = r else { continue };
        // A pinned first occurrence is repeated with its pin.
        let segment = match layers[r] {
            Layer::Fixed { segment } => segment,
            Layer::Open { .. } => match first.get(r) {
                Some(&s) => s,
                None => continue,
            },
        };
        pinned[t] = Layer::Fixed { segment };
        pinned[r] = Layer::Fixed { segment };
    }
    let (path, _, mut why) = generate_explained(lib, bars, &pinned, weights, options)?;
    for (t, w) in why.iter_mut().enumerate() {
        if matches!(pinned[t], Layer::Fixed { .. }) && open(t) {
            *w = first_why.get(t).copied().flatten();
        }
    }
    let cost = Problem::new(lib, bars, layers, weights, options).objective(&path);
    Ok((path, cost, repeats, why))
}

/// Stages 2 to 5 in order on `p`, from stage 1's `path`. Stage 4b's bars barred and opened
/// ([`order_stage`]) hold for every later stage's fills; `p`'s base is as it was afterwards,
/// and `p.why` says why each bar the order opened was.
pub(super) fn stages(p: &mut Problem, options: &GenerateOptions, path: Vec<usize>) -> Result<(Vec<usize>, f32), FillError> {
    let mut measured = Measured::default();
    let (path, weights) = profile::stage("2 beat rate", || beat_rate_stage(p, path, &mut measured))?;
    let (path, cost) = profile::stage("3 free skate", || free_skate_stage(p, &weights, &path));
    let (path, cost, carried) = if options.follow_skate { profile::stage("4 skate", || skate_stage(p, &weights, path, cost, &mut measured))? } else { (path, cost, 0.0) };
    let (order_path, order, why) = profile::stage("4b order", || order_stage(p, &weights, options, path.clone(), &mut measured))?;
    let (base, opened) = (p.base.clone(), p.opened.clone());
    if !order.is_empty() {
        p.base = p.with_base(&order).into_owned();
        for (t, w) in why.iter().enumerate() {
            if w.is_some() {
                p.opened[t] = true;
            }
        }
    }
    *p.why.borrow_mut() = why;
    let cost = if order_path == path { cost } else { path_cost_with_tempi(&p.table, p.layers, &p.intensity, &p.node_cost, &p.tempi(&p.base), &weights, &order_path) };
    let out = if options.follow_joins { profile::stage("5 join repair", || join_repair_stage(p, &weights, options, order_path, cost, carried, &mut measured)) } else { Ok((order_path, cost)) };
    (p.base, p.opened) = (base, opened);
    out
}

/// Per bar of `path` (the pipeline's dance on `p`), why it holds a built-in move under
/// [`MovesSource::Mine`] with imported moves in the library (`None` elsewhere, and for a
/// pinned bar).
pub(super) fn builtin_why(p: &Problem, path: &[usize]) -> Vec<Option<BuiltinWhy>> {
    let has_imported = p.lib.segments().iter().any(|s| s.builtin.is_none() && !s.retired);
    let why = p.why.borrow();
    (0..p.layers.len())
        .map(|t| {
            let builtin = path.get(t).and_then(|&s| p.lib.segments().get(s)).is_some_and(|s| s.builtin.is_some());
            if !builtin || !has_imported || p.weights.moves_source != MovesSource::Mine || !matches!(p.layers[t], Layer::Open { .. }) {
                return None;
            }
            let charged = p.charge.get(t).is_some_and(|r| r.iter().any(|&c| c > 0.0));
            if !charged {
                return Some(BuiltinWhy::NoneOfItsCount { counts: p.bars.get(t).map_or(0, Bar::beat_count) });
            }
            why.get(t).copied().flatten()
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::choreo::fill::path_cost_with_tempi;
    use crate::choreo::grid::bars_from_tempo;
    use std::sync::OnceLock;

    /// The built-in library, made once for every test here.
    fn builtin() -> &'static SegmentLibrary {
        static LIB: OnceLock<SegmentLibrary> = OnceLock::new();
        LIB.get_or_init(SegmentLibrary::builtin)
    }

    fn open_layers(bars: &[Bar]) -> Vec<Layer> {
        bars.iter().map(|b| Layer::Open { intensity: b.intensity }).collect()
    }

    /// Eight bars at `bpm` in 4/4, the intensity rising over the song.
    fn bars_at(bpm: f32) -> Vec<Bar> {
        let secs = 8.0 * 4.0 * 60.0 / bpm + 0.01;
        bars_from_tempo(secs, bpm, 4, 0.0, |a, _| (a / secs).clamp(0.0, 1.0)).unwrap()
    }

    fn cost(p: &Problem, weights: &FillWeights, path: &[usize]) -> f32 {
        path_cost_with_tempi(&p.table, p.layers, &p.intensity, &p.node_cost, &p.tempi(&[]), weights, path)
    }

    #[test]
    fn stage_1_no_one_bar_change_lowers_the_objective() {
        let lib = builtin();
        let bars = bars_at(120.0);
        let layers = open_layers(&bars);
        let opts = GenerateOptions::default();
        let p = Problem::new(lib, &bars, &layers, FillWeights { repeat_window: 1, ..FillWeights::default() }, &opts);
        let path = fill_stage(&p).unwrap();
        assert_eq!(path.len(), bars.len());
        let best = cost(&p, &p.weights, &path);
        assert!(best.is_finite());
        // A reference the filling does not use: every path that differs from it in one bar.
        for t in 0..path.len() {
            for s in 0..lib.len() {
                let mut q = path.clone();
                q[t] = s;
                assert!(cost(&p, &p.weights, &q) >= best - 1e-4, "bar {t} → segment {s} is cheaper than the filling's path");
            }
        }
    }

    #[test]
    fn stage_2_brings_a_dance_off_the_beat_rate_into_the_band_and_leaves_one_on_it() {
        let lib = builtin();
        let bars = bars_at(120.0);
        let layers = open_layers(&bars);
        let p = Problem::new(lib, &bars, &layers, FillWeights::default(), &GenerateOptions::default());
        let mut m = Measured::default();
        // The segment that turns most often a count at this count rate, in every bar: far off
        // one or one-half turn a count.
        let rate = count_rate_bpm(4, bars[0].duration_secs());
        let busiest = (0..lib.len()).max_by(|&a, &b| lib.segments()[a].kinetic_per_count_at(rate).total_cmp(&lib.segments()[b].kinetic_per_count_at(rate))).unwrap();
        let off: Vec<usize> = (0..bars.len()).map(|t| if t % 2 == 0 { busiest } else { (busiest + 1) % lib.len() }).collect();
        let before = m.of(&p, &off).unwrap();
        assert!(!in_beat_rate_band(before.kinetic_per_count), "the control is on the beat rate: {before:?}");
        let (fixed, w) = beat_rate_stage(&p, off.clone(), &mut m).unwrap();
        assert_ne!(fixed, off);
        assert!(w.beat_rate_weight > 0.0);
        let after = m.of(&p, &fixed).unwrap();
        assert!(in_beat_rate_band(after.kinetic_per_count), "{after:?}");
        // A dance inside the band is left as it is, with the problem's weights.
        let (same, w) = beat_rate_stage(&p, fixed.clone(), &mut m).unwrap();
        assert_eq!((same, w), (fixed, p.weights));
        // Off: nothing measured, nothing changed.
        let q = Problem::new(lib, &bars, &layers, FillWeights::default(), &GenerateOptions { follow_beat_rate: false, ..GenerateOptions::default() });
        let mut fresh = Measured::default();
        assert_eq!(beat_rate_stage(&q, off.clone(), &mut fresh).unwrap().0, off);
        assert!(fresh.done.is_empty());
    }

    #[test]
    fn stage_3_trades_at_most_its_slack_per_bar_for_less_skate() {
        let lib = crate::choreo::segment::tests::small_library_with_an_imported_clip();
        let bars = bars_at(120.0);
        let layers = open_layers(&bars);
        let p = Problem::new(&lib, &bars, &layers, FillWeights::default(), &GenerateOptions::default());
        let path = fill_stage(&p).unwrap();
        let before = cost(&p, &p.weights, &path);
        // No slack: the path and its cost as they were.
        let none = Problem::new(&lib, &bars, &layers, FillWeights::default(), &GenerateOptions { free_skate_slack: 0.0, ..GenerateOptions::default() });
        let (same, c) = free_skate_stage(&none, &none.weights, &path);
        assert_eq!(same, path);
        assert!((c - before).abs() < 1e-4);
        // A generous slack: each bar it changes slides less, and the objective rises by at most
        // the slack per bar changed.
        let slack = 0.5;
        let loose = Problem::new(&lib, &bars, &layers, FillWeights::default(), &GenerateOptions { free_skate_slack: slack, ..GenerateOptions::default() });
        let (q, c) = free_skate_stage(&loose, &loose.weights, &path);
        let changed: Vec<usize> = (0..path.len()).filter(|&t| q[t] != path[t]).collect();
        for &t in &changed {
            assert!(p.skate_excess(t, q[t]) < p.skate_excess(t, path[t]), "bar {t} took a move that slides no less");
        }
        assert!(c <= before + slack * changed.len() as f32 + 1e-4, "cost {c} from {before} over {} bars", changed.len());
    }

    #[test]
    fn stage_4_brings_a_sliding_dance_within_its_sources_skate() {
        let lib = crate::choreo::segment::tests::small_library_with_an_imported_clip();
        let bars = bars_at(160.0);
        let layers = open_layers(&bars);
        // Both kinds of move open to the stage (with *my moves*, the default, the preference
        // order keeps the imported moves first whatever they slide).
        let weights = FillWeights { moves_source: MovesSource::Mixed, ..FillWeights::default() };
        let p = Problem::new(&lib, &bars, &layers, weights, &GenerateOptions::default());
        let mut m = Measured::default();
        // The control: of the dances that hold one segment or alternate two (bars sped up to
        // 160 BPM, where feet slide faster), the one whose feet slide most above its goal.
        let n = lib.len();
        let mut scored: Vec<(f32, Vec<usize>)> = (0..n * n)
            .map(|k| {
                let q: Vec<usize> = (0..bars.len()).map(|t| if t % 2 == 0 { k / n } else { k % n }).collect();
                (m.of(&p, &q).map_or(f32::MIN, |f| f.foot_skate_cm_per_s - skate_goal_cm_per_s(&lib, &q)), q)
            })
            .collect();
        scored.sort_by(|a, b| a.0.total_cmp(&b.0));
        let sliding = scored.pop().unwrap().1;
        let before = m.of(&p, &sliding).unwrap();
        let goal = skate_goal_cm_per_s(&lib, &sliding);
        assert!(before.foot_skate_cm_per_s > goal, "the control does not slide past its goal: {before:?} against {goal}");
        let (q, _, _) = skate_stage(&p, &p.weights, sliding.clone(), 0.0, &mut m).unwrap();
        let after = m.of(&p, &q).unwrap();
        assert!(after.foot_skate_cm_per_s <= skate_goal_cm_per_s(&lib, &q), "{after:?}");
        // A dance within the goal is left as it is (its cost too).
        let (same, c, _) = skate_stage(&p, &p.weights, q.clone(), 7.0, &mut m).unwrap();
        assert_eq!((same, c), (q, 7.0));
    }

    #[test]
    fn stage_5_smooths_an_abrupt_join_and_leaves_smooth_ones() {
        let lib = builtin();
        let bars = bars_at(120.0);
        let layers = open_layers(&bars);
        let opts = GenerateOptions::default();
        let p = Problem::new(lib, &bars, &layers, FillWeights::default(), &opts);
        let mut m = Measured::default();
        // The filling's own dance at 120 BPM has smooth joins: left as it was.
        let path = fill_stage(&p).unwrap();
        let f = m.of(&p, &path).unwrap();
        assert!(f.join_jump_max <= opts.join_jump_goal, "{f:?}");
        let (same, _) = join_repair_stage(&p, &p.weights, &opts, path.clone(), 0.0, 0.0, &mut m).unwrap();
        assert_eq!(same, path);
        // A strict goal (below what this dance has) makes it look for smoother joins: the dance
        // it returns has a smaller worst join than the one it was given, or is that one.
        let strict = GenerateOptions { join_jump_goal: f.join_jump_max * 0.5, ..opts };
        let (q, _) = join_repair_stage(&p, &p.weights, &strict, path.clone(), 0.0, 0.0, &mut m).unwrap();
        let g = m.of(&p, &q).unwrap();
        assert!(q == path || g.join_jump_max < f.join_jump_max, "{g:?} against {f:?}");
        // No tries: nothing changes.
        let none = GenerateOptions { join_repairs: 0, ..strict };
        assert_eq!(join_repair_stage(&p, &p.weights, &none, path.clone(), 0.0, 0.0, &mut m).unwrap().0, path);
    }

    #[test]
    fn stage_5_bars_the_move_after_every_join_over_the_goal_at_once() {
        let lib = builtin();
        // 32 bars: a refill barring one move changes the dance near it and keeps it elsewhere.
        let secs = 32.0 * 2.0 + 0.01;
        let bars = bars_from_tempo(secs, 120.0, 4, 0.0, |a, _| (a / secs).clamp(0.0, 1.0)).unwrap();
        let layers = open_layers(&bars);
        let opts = GenerateOptions::default();
        assert!(opts.join_bans_at_once, "on by default");
        let p = Problem::new(lib, &bars, &layers, FillWeights::default(), &opts);
        let path = fill_stage(&p).unwrap();
        let f = Measured::default().played(&p, &path).unwrap();
        // A goal a third of the joins miss: several joins over it in one measure.
        let mut jumps: Vec<f32> = f.bars.iter().filter_map(|b| b.join_jump).collect();
        jumps.sort_by(f32::total_cmp);
        let goal = jumps[jumps.len() * 2 / 3];
        let over: Vec<usize> = (1..bars.len()).filter(|&t| f.bars[t].join_jump.is_some_and(|j| j > goal)).map(|t| path[t]).collect();
        let worst = path[f.whole.worst_join_bar.unwrap()];
        assert!(over.iter().any(|&s| s != worst), "one move over the goal: {over:?}");
        // One refill each way: the moves it was given after the joins over the goal, in the
        // first refill it measured (the second dance measured as played).
        let refill = |at_once: bool| {
            let o = GenerateOptions { join_jump_goal: goal, join_repairs: 1, join_bans_at_once: at_once, ..opts };
            let mut m = Measured::default();
            join_repair_stage(&p, &p.weights, &o, path.clone(), 0.0, 0.0, &mut m).unwrap();
            assert!(m.played.len() >= 2, "no refill measured");
            let q = m.played[1].0.clone();
            (over.iter().copied().filter(|s| q.contains(s)).collect::<Vec<usize>>(), q)
        };
        // At once: none of them is left; one a refill (the control): the worst's is barred,
        // some of the others are still there.
        let (left, at_once) = refill(true);
        assert_eq!(left, Vec::<usize>::new());
        let (left, control) = refill(false);
        assert!(!left.contains(&worst), "the control's refill kept the worst join's move {worst}");
        assert!(!left.is_empty() && at_once != control, "the control's refill kept none of {over:?}: {control:?}");
    }

    #[test]
    fn takes_differ_in_half_the_bars_at_comparable_cost_and_take_0_is_the_dance() {
        let lib = builtin();
        let bars = bars_at(120.0);
        let mut layers = open_layers(&bars);
        let opts = GenerateOptions::default();
        let (zero, zero_cost) = generate(lib, &bars, &layers, FillWeights::default(), &opts).unwrap();
        // Take 0 is the pipeline without a take's charge, its stages in order.
        let mut p = Problem::new(lib, &bars, &layers, FillWeights::default(), &opts);
        let first = fill_stage(&p).unwrap();
        let (staged, _) = stages(&mut p, &opts, first).unwrap();
        assert_eq!((zero.clone(), zero_cost), (staged.clone(), p.objective(&staged)));
        let takes: Vec<Vec<usize>> = (0..5).map(|take| generate(lib, &bars, &layers, FillWeights::default(), &GenerateOptions { take, ..opts }).unwrap().0).collect();
        assert_eq!(takes[0], zero);
        let objective: Vec<f32> = takes.iter().map(|q| p.objective(q)).collect();
        let best = objective.iter().copied().fold(f32::INFINITY, f32::min);
        for (k, q) in takes.iter().enumerate() {
            assert!(objective[k] <= best * (1.0 + TAKE_SLACK) + 1e-4, "take {k}: objective {} against the best {best}", objective[k]);
            for (j, r) in takes.iter().enumerate().take(k) {
                let d = q.iter().zip(r).filter(|(a, b)| a != b).count();
                assert!(2 * d >= bars.len(), "takes {j} and {k} differ in {d} of {} bars", bars.len());
            }
        }
        // The same take twice is the same dance.
        assert_eq!(generate(lib, &bars, &layers, FillWeights::default(), &GenerateOptions { take: 3, ..opts }).unwrap().0, takes[3]);
        // A pinned bar stays in every take.
        layers[2] = Layer::Fixed { segment: 7 };
        for take in 0..3 {
            assert_eq!(generate(lib, &bars, &layers, FillWeights::default(), &GenerateOptions { take, ..opts }).unwrap().0[2], 7);
        }
        // Out of range: refused with its name.
        let err = GenerateOptions { take: MAX_TAKE + 1, ..opts }.validate().unwrap_err();
        assert!(err.to_string().contains("take"), "{err}");
    }

    #[test]
    fn the_moves_source_puts_one_kind_first_and_mine_is_the_default() {
        let lib = crate::choreo::segment::tests::small_library_with_an_imported_clip();
        let bars = bars_at(100.0);
        let mut layers = open_layers(&bars);
        let opts = GenerateOptions::default();
        let dance = |source: MovesSource, layers: &[Layer]| generate(&lib, &bars, layers, FillWeights { moves_source: source, ..FillWeights::default() }, &opts).unwrap().0;
        let imported = |path: &[usize]| path.iter().filter(|&&s| lib.segments()[s].builtin.is_none()).count();
        assert_eq!(FillWeights::default().moves_source, MovesSource::Mine);
        let mine = dance(MovesSource::Mine, &layers);
        assert_eq!(mine, generate(&lib, &bars, &layers, FillWeights::default(), &opts).unwrap().0);
        // Mixed, the objective alone, takes fewer imported moves on this library (the control:
        // without the order the built-in moves' smoother joins win bars).
        let mixed = dance(MovesSource::Mixed, &layers);
        assert!(imported(&mixed) < imported(&mine), "mixed {mixed:?} took as many imported bars as mine");
        assert_eq!(imported(&mine), bars.len(), "my moves: every bar imported, {mine:?}");
        let builtin = dance(MovesSource::Builtin, &layers);
        assert_eq!(imported(&builtin), 0, "built-in: no bar imported, {builtin:?}");
        // A pinned bar keeps its move whatever the source.
        let pinned = builtin[0];
        layers[3] = Layer::Fixed { segment: pinned };
        assert_eq!(dance(MovesSource::Mine, &layers)[3], pinned);
    }

    #[test]
    fn a_bar_repeating_a_pinned_bar_takes_the_pin() {
        let lib = crate::choreo::segment::tests::small_library_with_an_imported_clip();
        let bars = bars_at(100.0);
        let n = bars.len();
        let opts = GenerateOptions::default();
        let mut layers = open_layers(&bars);
        let free = generate(&lib, &bars, &layers, FillWeights::default(), &opts).unwrap().0;
        // Bar 0 pinned to a move the free dance does not put last; the last bar repeats bar 0.
        let pin = (0..lib.len()).find(|&s| s != free[n - 1]).unwrap();
        layers[0] = Layer::Fixed { segment: pin };
        let mut repeat_of = vec![None; n];
        repeat_of[n - 1] = Some(0);
        let (path, _, repeats) = generate_with_repeats(&lib, &bars, &layers, FillWeights::default(), &opts, &repeat_of).unwrap();
        assert_eq!((path[0], path[n - 1], repeats[n - 1]), (pin, pin, Some(0)), "{path:?}");
        // The control: without the repeat the last bar is filled freely (not the pin here).
        let plain = generate(&lib, &bars, &layers, FillWeights::default(), &opts).unwrap().0;
        assert_ne!(plain[n - 1], pin, "the control already ends on the pin: {plain:?}");
    }

    #[test]
    fn stage_4b_opens_bars_to_built_in_moves_only_where_imported_ones_miss_and_keeps_half_imported() {
        let lib = crate::choreo::segment::tests::small_library_with_an_imported_clip();
        let bars = bars_at(100.0);
        let layers = open_layers(&bars);
        let imported = |q: &[usize]| q.iter().filter(|&&s| lib.segments()[s].builtin.is_none()).count();
        // A join goal no join of these moves meets: every bar after the first misses it, so
        // the order must open bars, but no more than keep half the dance imported.
        let strict = GenerateOptions { join_jump_goal: 0.05, ..GenerateOptions::default() };
        let p = Problem::new(&lib, &bars, &layers, FillWeights::default(), &strict);
        let first = fill_stage(&p).unwrap();
        assert_eq!(imported(&first), bars.len(), "the first fill keeps built-in moves out: {first:?}");
        let mut m = Measured::default();
        let before = m.played(&p, &first).unwrap();
        let (path, extra, why) = order_stage(&p, &p.weights, &strict, first.clone(), &mut m).unwrap();
        let after = m.played(&p, &path).unwrap();
        let opened: Vec<usize> = (0..bars.len()).filter(|&t| why[t].is_some()).collect();
        assert!(!opened.is_empty(), "nothing opened: {path:?}");
        assert!(opened.iter().all(|&t| why[t] == Some(BuiltinWhy::RoughJoin) && t > 0), "{why:?}");
        assert!(2 * imported(&path) >= bars.len(), "{path:?} keeps fewer than half its bars imported");
        assert!(imported(&path) < bars.len(), "no bar took a built-in move: {path:?}");
        assert!(after.bas_music >= before.bas_music - 1e-4, "{} against {}", after.bas_music, before.bas_music);
        assert_eq!(extra.len(), bars.len());
        // Off, or another moves source: the first fill's dance as it was.
        for (source, opts) in [(MovesSource::Mine, GenerateOptions { follow_order: false, ..strict }), (MovesSource::Mixed, strict)] {
            let q = Problem::new(&lib, &bars, &layers, FillWeights { moves_source: source, ..FillWeights::default() }, &opts);
            let start = fill_stage(&q).unwrap();
            let (same, extra, why) = order_stage(&q, &q.weights, &opts, start.clone(), &mut Measured::default()).unwrap();
            assert_eq!((same, extra.len()), (start, 0));
            assert!(why.iter().all(Option::is_none));
        }
        // Every built-in bar of the whole pipeline's dance says why.
        let (dance, _, whys) = generate_explained(&lib, &bars, &layers, FillWeights::default(), &strict).unwrap();
        for (t, &s) in dance.iter().enumerate() {
            assert_eq!(whys[t].is_some(), lib.segments()[s].builtin.is_some(), "bar {t}: {dance:?} {whys:?}");
        }
    }

    #[test]
    fn the_pipeline_is_its_stages_in_order() {
        let lib = crate::choreo::segment::tests::small_library_with_an_imported_clip();
        let bars = bars_at(100.0);
        let layers = open_layers(&bars);
        let opts = GenerateOptions::default();
        let (whole, cost) = generate(&lib, &bars, &layers, FillWeights::default(), &opts).unwrap();
        let mut p = Problem::new(&lib, &bars, &layers, FillWeights::default(), &opts);
        let mut m = Measured::default();
        let path = fill_stage(&p).unwrap();
        let (path, w) = beat_rate_stage(&p, path, &mut m).unwrap();
        let (path, c) = free_skate_stage(&p, &w, &path);
        let (path, c, carried) = skate_stage(&p, &w, path, c, &mut m).unwrap();
        let (path, order, why) = order_stage(&p, &w, &opts, path, &mut m).unwrap();
        if !order.is_empty() {
            p.base = p.with_base(&order).into_owned();
            for (t, w) in why.iter().enumerate() {
                p.opened[t] |= w.is_some();
            }
        }
        let (path, _) = join_repair_stage(&p, &w, &opts, path, c, carried, &mut m).unwrap();
        assert_eq!((whole, cost), (path.clone(), p.objective(&path)));
    }
}
