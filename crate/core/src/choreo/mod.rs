//! Choreography authoring (spec §E–G, paper 000): a song's bars, a library of 4-count (and 3-count)
//! segments cut from any humanoid clip at the motion's own beats, relevance-feedback candidate
//! search per bar, automatic filling of the open bars by a shortest path, cubic joins, the quality measures of §J, and the
//! dance commands as pure functions the project (the one dance document) calls. Everything here is
//! deterministic: the same library, bars and commands give the same dance.

/// Slowest and fastest tempo, in counts per minute, at which a move is cut or bars are laid
/// out from a stated tempo: the one place these limits live (cutting and re-cutting clips,
/// [`bars_from_tempo`], and the page's tempo fields through the web crate's `tempoLimits()`).
pub const MIN_MOVE_BPM: f32 = 30.0;
/// See [`MIN_MOVE_BPM`].
pub const MAX_MOVE_BPM: f32 = 300.0;

pub mod document;
pub mod eigen;
pub mod feedback;
pub mod figures;
pub mod fill;
pub mod generate;
pub mod grid;
pub mod jump;
pub mod notes;
pub mod profile;
pub mod quality;
pub mod refill;
pub mod render;
pub mod scan;
pub mod segment;
pub mod switch;
pub mod table;
pub mod takes;
pub mod variety;

pub use document::{bar_views, check_bar, check_bars, generate_states, generate_states_with_repeats, next_round, open_search, render_states, BarState, BarView, ChoreoError, GenerateReport, Setting, Settings};
pub use eigen::Signature;
pub use generate::{bar_counts, dance_figures, played_figures, skate_goal_cm_per_s, BuiltinWhy, DanceFigures, GenerateOptions, Played, PlayedBar, JOIN_REPAIRS};
pub use feedback::{mean_pairwise_dissimilarity, FeedbackSession, LikeTerm, CANDIDATES_PER_ROUND, TAU_DECAY};
pub use fill::{
    bar_count_rate_bpm, beat_rate_cost, count_rate_bpm, fill, fill_with_node_costs, fill_with_stats, fill_with_tempi, free_skate_pass, node_costs, node_costs_with_skate, path_cost, path_cost_with_node_costs, path_cost_with_tempi, stretch_cost, FillError, FillStats,
    FillWeights, Layer, MovesSource, MOVES_SOURCE_CHARGE, Tempi, TransitionTable, FREE_SKATE_SLACK_DEFAULT, BEAT_RATE_BAND, beat_rate_ladder, beat_rate_ladder_for, in_beat_rate_band, skate_ladder,
};
pub use grid::{bars_from_tempo, GridError};
pub use notes::{bar_notes, candidate_notes, mark_builtin_why, mark_repeats, Flag, FlagKind, MoveNote, NotesError};
pub use quality::{JOIN_JUMP_GOAL, dance_quality, dance_quality_switched, BarQuality, BeatAlignment, DanceQuality, FootSkate, MotionQuality, QualityError, QualityMotion};
pub use render::{render, render_switched, segment_clip, speed_jumps, JoinBlend, RenderOptions};
pub use table::{blended_join_jump, blended_join_jump_at, JumpTerm, TableBuilder, TableProgress, TableScope};
pub use segment::{kinetic_per_count_by_rate, KINETIC_RATES_BPM, SEGMENT_COUNTS, SEGMENT_METRES, BuiltinLoader, ClipSummary, LibraryClip, Recut, Segment, SegmentError, SegmentLibrary, SegmentOptions, LIBRARY_FPS};
