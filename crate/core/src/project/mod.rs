//! The project (spec §K): one document holding all that a person made — the imported sources
//! (file name, the bytes as given, import options, the tempo each clip is cut at), the song
//! (audio bytes, its loudness envelope, the analysis options and every grid correction), the
//! dance (each bar's state and move by a stable [`MoveKey`], never by an index into a vector;
//! the shown and liked candidates of each bar's search; ρ and the filling's weights), clip
//! tags, texts, the chosen character and the camera, and the MMD camera motions and face
//! (lip-sync) tracks imported (one list of [`MmdTrack`]s, [`tracks`]: the bytes as given, like a
//! source's).
//!
//! Edits are methods on [`Project`]; each one that changes the document records the previous
//! document, so undo/redo is the project's history (kept and saved with it). Everything else —
//! the imported clips, the segment library, the join table, the song's grid, the rendered
//! dance — is derived from the document and rebuilt on demand ([`derive`]), so a project read
//! back from bytes ([`file`]) is the same project and renders the same dance.
//!
//! Why the dance is stored by keys: segment numbers change whenever the library changes
//! (another clip imported, a clip re-cut); a key names the motion itself — a built-in move by
//! what it is made of, an imported one by its source, clip, the tempo it was cut at and the
//! count it starts on — so it means the same motion in any session that rebuilds the library.

pub mod blob;
mod dance;
pub mod derive;
pub mod models;
pub mod file;
pub mod repeats;
pub mod summary;
pub mod tracks;

use crate::history::History;
use std::collections::BTreeSet;

use serde::{Deserialize, Serialize};
use thiserror::Error;

use crate::bars::Bar;
use crate::choreo::{ChoreoError, FillWeights, GenerateReport, SegmentError, Setting, Settings};
use crate::clip::Clip;
use crate::import::{ImportError, ImportOptions};
use crate::library::MoveInfo;
use crate::music::{AnalysisOptions, GridCorrection, MusicError, RmsEnvelope};

pub use blob::{BlobHash, BlobStore};
pub use derive::{ClipInfo, Derived};
pub use models::{GivenModel, ModelFile, ModelTexture};
pub use tracks::{MmdTrack, TrackKeys, TrackKind};
pub use file::{open, save, FileError, MissingBlob, Opened, CURRENT_SCHEMA_VERSION, ODORI_MIME};
pub use repeats::{BarRange, BarRepeat, RepeatError, RepeatMark, RepeatRun};
pub use summary::{manifest_blob_hashes, ProjectSummary};

/// Most undo steps a project keeps (and saves): enough for a session's work, small enough that
/// the manifest written on every autosave stays a few hundred kilobytes.
pub const UNDO_LIMIT: usize = 100;

/// A source's number in its project: given once, never reused (so keys stay valid after a
/// source is gone from the current document but still referred to by its history).
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
#[serde(transparent)]
pub struct SourceId(pub u32);

/// One clip of one source: the `clip`-th animation of the file (BVH: always 0).
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
#[serde(rename_all = "camelCase")]
pub struct ClipRef {
    pub source: SourceId,
    pub clip: u32,
}

/// An imported file, as given.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "camelCase")]
pub struct Source {
    pub id: SourceId,
    pub file_name: String,
    /// The file's bytes, exactly as given.
    pub blob: BlobHash,
    pub options: ImportOptions,
    /// Tempo (counts per minute) the person stated for a clip, by clip number; a clip not
    /// listed is cut at the tempo detected from its motion.
    #[serde(default)]
    pub cut_tempos_bpm: Vec<(u32, f32)>,
    /// A VMD dance only: the MMD model file it is posed on (its bones and IK), kept with it so
    /// a reopened project poses it on that model again; `None`: the standard MMD skeleton
    /// (schema 4; absent when none).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub model: Option<ModelFile>,
}

impl Source {
    /// The stated cut tempo of clip `clip` (`None`: detected).
    pub fn cut_tempo_bpm(&self, clip: u32) -> Option<f32> {
        self.cut_tempos_bpm.iter().find(|(c, _)| *c == clip).map(|&(_, t)| t)
    }
}

/// A move, by what it is rather than where it sits in a vector.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "camelCase")]
pub enum MoveKey {
    /// One of the built-in moves.
    #[serde(rename_all = "camelCase")]
    Builtin { r#move: MoveInfo },
    /// `counts` counts of an imported clip (4, or 3 for a bar in 3), cut at `cut_tempo_bpm` (the
    /// tempo the person stated; `None`: the tempo detected from the motion), starting on count
    /// `first_count` (0-based). `counts` is left out of the file (and the key's id) when 4, so
    /// projects saved before 3-count segments open, and save, unchanged.
    #[serde(rename_all = "camelCase")]
    Cut {
        clip: ClipRef,
        cut_tempo_bpm: Option<f32>,
        first_count: u32,
        #[serde(default = "four_counts", skip_serializing_if = "is_four_counts")]
        counts: u32,
    },
}

fn four_counts() -> u32 {
    4
}

fn is_four_counts(n: &u32) -> bool {
    *n == 4
}

impl MoveKey {
    /// A string that identifies the key (for maps).
    pub fn id(&self) -> String {
        serde_json::to_string(self).unwrap_or_default()
    }
}

/// The song, as given, with the person's corrections of its grid.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "camelCase")]
pub struct SongDoc {
    /// File name ("demo" for the built-in demo song).
    pub file_name: String,
    /// The audio file's bytes as given (`None` for the demo song, which the engine renders).
    pub audio: Option<BlobHash>,
    /// The loudness envelope the host computed from the decoded audio (see
    /// [`encode_envelope`]): kept so the grid is rebuilt exactly without decoding again.
    pub envelope: BlobHash,
    pub options: AnalysisOptions,
    /// Every correction, in the order made; the grid is the analysis with these applied.
    pub corrections: Vec<GridCorrection>,
}

/// What a bar holds.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "camelCase")]
pub enum BarKind {
    #[default]
    Empty,
    Pinned,
    Generated,
}

/// One bar's relevance-feedback search (spec §F), by keys.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "camelCase")]
pub struct SearchDoc {
    pub tau: f32,
    pub shown: Vec<MoveKey>,
    pub liked: Vec<MoveKey>,
    pub round: Vec<MoveKey>,
    pub rounds: usize,
}

/// One bar of the dance.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "camelCase")]
pub struct BarDoc {
    pub state: BarKind,
    /// The move (with `Pinned` and `Generated`).
    pub r#move: Option<MoveKey>,
    pub search: Option<SearchDoc>,
    /// Why the Generate that filled the bar gave it a built-in move though the person's moves
    /// come first (issue 26, [`crate::choreo::BuiltinWhy`]): kept with the bar so its note
    /// says the same after save/reopen and through undo, and dropped by any edit of its move
    /// (schema 7; absent when none).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub builtin_why: Option<crate::choreo::BuiltinWhy>,
}

/// The dance: one entry per bar of the song's grid, and the knobs of search and filling.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "camelCase")]
pub struct DanceDoc {
    pub bars: Vec<BarDoc>,
    pub settings: Settings,
    /// The take of Generate its generated bars come from ([`crate::choreo::GenerateOptions::take`]:
    /// 0 for Generate, counted up by "another take"); kept from schema 3 (older files read 0).
    #[serde(default)]
    pub take: u32,
    /// The repeats the person marked or removed on the song strip, in the order made
    /// ([`repeats`]; schema 5, absent when none).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub repeats: Vec<RepeatMark>,
}

/// Words a person attached to a clip so text can call it.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "camelCase")]
pub struct Tagging {
    pub clip: ClipRef,
    pub tags: Vec<String>,
}

/// The motion a put-on clip plays (see [`Worn`]).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "camelCase")]
pub enum WornMotion {
    /// A clip of one of the project's sources.
    Clip { clip: ClipRef },
    /// A motion made in the page (the dance, a text animation, a built-in move): kept as the
    /// BVH file the engine wrote of it, because what made it may change later and the put-on
    /// clip is the motion as it was when it was put on.
    #[serde(rename_all = "camelCase")]
    Motion { name: String, bvh: BlobHash },
}

/// A clip "put on" a character: `motion` retargeted to the rig of `character` (an imported
/// skinned humanoid), drawn with its mesh. Only the recipe is kept; the clip is rebuilt from
/// it ([`Project::worn_clip`]).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "camelCase")]
pub struct Worn {
    pub character: ClipRef,
    pub motion: WornMotion,
}

/// Where the viewer looks from.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "camelCase")]
pub struct Camera {
    pub yaw_rad: f32,
    pub pitch_rad: f32,
    pub distance_m: f32,
    pub target_m: [f32; 3],
}

/// Everything a person made (spec §K). Serialised as the manifest's `project`.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "camelCase")]
pub struct ProjectDoc {
    pub name: String,
    /// The next [`SourceId`] to give.
    pub next_source: u32,
    pub sources: Vec<Source>,
    pub song: Option<SongDoc>,
    pub dance: DanceDoc,
    pub tags: Vec<Tagging>,
    pub texts: Vec<String>,
    /// The imported character the dance is shown on; `None` with `stick_figures` false is the
    /// built-in body (a new project's, and what a project made before the choice existed
    /// shows).
    pub character: Option<ClipRef>,
    /// Stick figures chosen over any body (absent, read as false, in files written before it
    /// existed and whenever it is false, so those files keep their bytes).
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub stick_figures: bool,
    pub camera: Option<Camera>,
    /// Clips put on a character, in the order made (absent in files written before it
    /// existed, which read as none: no schema step needed).
    #[serde(default)]
    pub worn: Vec<Worn>,
    /// Camera motions and face (lip-sync) tracks imported, in the order imported ([`tracks`];
    /// schema 7, absent when none; schemas 4–6 kept them as `cameras` and `faces`).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub mmd_tracks: Vec<MmdTrack>,
}

impl ProjectDoc {
    /// Every blob the document refers to.
    pub fn blobs(&self) -> impl Iterator<Item = &BlobHash> {
        self.sources
            .iter()
            .flat_map(|s| std::iter::once(&s.blob).chain(s.model.iter().flat_map(|m| std::iter::once(&m.blob).chain(m.textures.iter().map(|t| &t.blob)))))
            .chain(self.song.iter().flat_map(|s| s.audio.iter().chain(std::iter::once(&s.envelope))))
            .chain(self.worn.iter().filter_map(|w| match &w.motion {
                WornMotion::Motion { bvh, .. } => Some(bvh),
                WornMotion::Clip { .. } => None,
            }))
            .chain(self.mmd_tracks.iter().map(|t| &t.blob))
    }

    /// Every move key the document refers to for keeps: bars' moves and liked candidates.
    pub(crate) fn kept_keys(&self) -> impl Iterator<Item = &MoveKey> {
        self.dance.bars.iter().flat_map(|b| b.r#move.iter().chain(b.search.iter().flat_map(|s| s.liked.iter())))
    }

    pub fn source(&self, id: SourceId) -> Option<&Source> {
        self.sources.iter().find(|s| s.id == id)
    }
}

/// Why an edit was refused. On error the project is unchanged.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum ProjectError {
    #[error(transparent)]
    Import(#[from] ImportError),
    #[error(transparent)]
    Music(#[from] MusicError),
    #[error(transparent)]
    Choreo(#[from] ChoreoError),
    #[error(transparent)]
    Segment(#[from] SegmentError),
    #[error("the project has no song: open a song (or use the demo song) before composing a dance")]
    NoSong,
    #[error("there is no source {source_id} in the project")]
    NoSuchSource { source_id: u32 },
    #[error("source {source_id} ({file_name}) has no clip {clip}: it has {clips}")]
    NoSuchClip { source_id: u32, file_name: String, clip: u32, clips: usize },
    #[error("clip {clip} of {file_name} is not in the dance library: {reason}")]
    NotDanceable { file_name: String, clip: u32, reason: String },
    #[error("move {key} is not in the library (its source is missing or was cut differently)")]
    UnknownMove { key: String },
    #[error("the dance cannot be edited while {count} stored item(s) are missing ({first}): nothing of it would be kept")]
    Incomplete { count: usize, first: String },
    #[error("bad song envelope: {message}")]
    BadEnvelope { message: String },
    #[error(transparent)]
    Character(#[from] crate::canon::character::CharacterError),
    #[error("there is no put-on clip {index}: the project has {count}")]
    NoSuchWorn { index: usize, count: usize },
    #[error("put on: give a clip of the project or a motion to put on the character")]
    NoMotion,
    #[error("{file_name}: not a camera motion: it has no camera keys ({bone_keys} bone keys, {morph_keys} morph keys; a dance VMD is imported as a motion)")]
    NotACamera { file_name: String, bone_keys: usize, morph_keys: usize },
    #[error("there is no camera motion {index}: the project has {count}")]
    NoSuchCamera { index: usize, count: usize },
    #[error("{file_name}: not a lip-sync (face) motion: it has no morph keys ({bone_keys} bone keys, {camera_keys} camera keys)")]
    NotAFaceTrack { file_name: String, bone_keys: usize, camera_keys: usize },
    #[error("there is no face track {index}: the project has {count}")]
    NoSuchFaceTrack { index: usize, count: usize },
    #[error(transparent)]
    Sections(#[from] crate::music::SectionError),
    #[error(transparent)]
    Repeat(#[from] RepeatError),
}

impl ProjectError {
    /// A short machine-readable kind, stable for the JS API.
    pub fn kind(&self) -> &'static str {
        match self {
            ProjectError::Import(e) => e.kind(),
            ProjectError::Music(_) => "music",
            ProjectError::Choreo(_) | ProjectError::Segment(_) => "choreo",
            ProjectError::NoSong => "no-song",
            ProjectError::NoSuchSource { .. } | ProjectError::NoSuchClip { .. } | ProjectError::UnknownMove { .. } => "not-found",
            ProjectError::NotDanceable { .. } => "not-humanoid",
            ProjectError::Incomplete { .. } => "missing-blob",
            ProjectError::BadEnvelope { .. } => "bad-argument",
            ProjectError::Character(e) => e.kind(),
            ProjectError::NoSuchWorn { .. } => "not-found",
            ProjectError::NoMotion => "bad-argument",
            ProjectError::NotACamera { .. } => "mmd-no-camera-keys",
            ProjectError::NoSuchCamera { .. } => "not-found",
            ProjectError::NotAFaceTrack { .. } => "mmd-no-morph-keys",
            ProjectError::NoSuchFaceTrack { .. } => "not-found",
            ProjectError::Sections(_) => "music",
            ProjectError::Repeat(e) => e.kind(),
        }
    }
}

/// What re-cutting a clip meant for the dance ([`Project::recut_clip`]).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "camelCase")]
pub struct RecutReport {
    /// The new cut.
    pub clip: crate::choreo::ClipSummary,
    /// Segments of the earlier cut removed from the library.
    pub removed: usize,
    /// Moves of the earlier cut kept because bars of the dance hold them.
    pub kept: usize,
    /// Bars pinned to a move of the earlier cut: they keep that motion.
    pub pinned_bars: Vec<usize>,
    /// Bars the engine filled with a move of the earlier cut: they keep it until the next
    /// Generate, which fills them from the new cut.
    pub generated_bars: Vec<usize>,
}

/// What adding a source gave.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "camelCase")]
pub struct SourceReport {
    pub id: SourceId,
    pub clips: Vec<ClipInfo>,
    pub warnings: Vec<String>,
}

/// The project: the document, its history, its blobs, and the derived state built from them.
#[derive(Debug, Default)]
pub struct Project {
    doc: ProjectDoc,
    history: History<ProjectDoc>,
    blobs: BlobStore,
    /// Blobs the document refers to that were absent when it was opened.
    missing: Vec<MissingBlob>,
    derived: Derived,
    /// The history's changes as the manifest writes them, kept between writes (see
    /// [`file::DiffCache`]); kept in step with `history` by every method that moves it.
    pub(crate) diffs: std::sync::Mutex<file::DiffCache>,
    /// An open group of edits ([`Project::begin_group`]): `Some(true)` once its first edit
    /// recorded the undo step the rest join.
    group: Option<bool>,
}

/// Two projects are the same when what a person made (document, history, blobs) is the same;
/// the derived state is rebuilt from those.
impl PartialEq for Project {
    fn eq(&self, other: &Self) -> bool {
        self.doc == other.doc && self.history == other.history && self.blobs == other.blobs
    }
}

/// Writes an envelope as the song's envelope blob: `b"ODRMS1"`, hop seconds (f32), band count
/// and frame count (u32), then the bands one after the other; little-endian throughout.
pub fn encode_envelope(env: &RmsEnvelope) -> Vec<u8> {
    let frames = env.bands.first().map_or(0, Vec::len);
    let mut out = Vec::with_capacity(14 + env.bands.len() * frames * 4);
    out.extend_from_slice(b"ODRMS1");
    out.extend_from_slice(&env.hop_secs.to_le_bytes());
    out.extend_from_slice(&(env.bands.len() as u32).to_le_bytes());
    out.extend_from_slice(&(frames as u32).to_le_bytes());
    for band in &env.bands {
        for v in band.iter().take(frames) {
            out.extend_from_slice(&v.to_le_bytes());
        }
        // A short band is padded so the layout stays rectangular; `analyze` refuses it anyway.
        for _ in band.len()..frames {
            out.extend_from_slice(&0f32.to_le_bytes());
        }
    }
    out
}

/// Reads [`encode_envelope`]'s format.
pub fn decode_envelope(bytes: &[u8]) -> Result<RmsEnvelope, ProjectError> {
    let bad = |message: String| ProjectError::BadEnvelope { message };
    if bytes.len() < 18 || &bytes[..6] != b"ODRMS1" {
        return Err(bad(format!("{} bytes that do not start with the envelope header", bytes.len())));
    }
    let word = |at: usize| [bytes[at], bytes[at + 1], bytes[at + 2], bytes[at + 3]];
    let hop_secs = f32::from_le_bytes(word(6));
    let bands = u32::from_le_bytes(word(10)) as usize;
    let frames = u32::from_le_bytes(word(14)) as usize;
    let need = bands.checked_mul(frames).and_then(|n| n.checked_mul(4)).and_then(|n| n.checked_add(18));
    if need != Some(bytes.len()) {
        return Err(bad(format!("{bands} bands of {frames} frames need {need:?} bytes, the blob has {}", bytes.len())));
    }
    let bands = (0..bands).map(|b| (0..frames).map(|f| f32::from_le_bytes(word(18 + (b * frames + f) * 4))).collect()).collect();
    Ok(RmsEnvelope { hop_secs, bands })
}

/// The file name a put-on motion's BVH is read under (it names the clip).
pub(crate) fn worn_file_name(name: &str) -> String {
    format!("{name}.bvh")
}

impl Project {
    /// An empty project.
    pub fn new() -> Self {
        Self::default()
    }

    /// A project from parts read back from a file or a store (history included). `missing`
    /// names what the document refers to that was not there.
    pub(crate) fn from_parts(doc: ProjectDoc, undo: Vec<ProjectDoc>, redo: Vec<ProjectDoc>, blobs: BlobStore, missing: Vec<MissingBlob>) -> Self {
        let diffs = std::sync::Mutex::new(file::DiffCache::default());
        Self { doc, history: History::from_parts(undo, redo), blobs, missing, derived: Derived::default(), diffs, group: None }
    }

    pub fn doc(&self) -> &ProjectDoc {
        &self.doc
    }

    pub fn blobs(&self) -> &BlobStore {
        &self.blobs
    }

    pub fn undo_history(&self) -> &[ProjectDoc] {
        &self.history.undo
    }

    pub fn redo_history(&self) -> &[ProjectDoc] {
        &self.history.redo
    }

    /// Items the document names whose bytes were missing when it was opened.
    pub fn missing(&self) -> &[MissingBlob] {
        &self.missing
    }

    /// Every blob the document or its history refers to.
    pub fn referenced_blobs(&self) -> BTreeSet<BlobHash> {
        std::iter::once(&self.doc).chain(&self.history.undo).chain(&self.history.redo).flat_map(|d| d.blobs().cloned().collect::<Vec<_>>()).collect()
    }

    /// The derived state, brought up to date with the document.
    pub fn derived(&mut self) -> &Derived {
        self.derived.update(&self.doc, &self.history.undo, &self.history.redo, &self.blobs);
        &self.derived
    }

    /// Commits `doc` as the next state (recording the current one for undo) when it differs.
    fn commit(&mut self, doc: ProjectDoc) -> bool {
        if doc == self.doc {
            return false;
        }
        if self.group == Some(true) {
            // A later edit of a group: part of the group's one undo step.
            self.doc = doc;
            let keep = self.referenced_blobs();
            self.blobs.retain(&keep);
            return true;
        }
        if self.group.is_some() {
            self.group = Some(true);
        }
        let prev = std::mem::replace(&mut self.doc, doc);
        let dropped = self.history.undo.len() >= UNDO_LIMIT;
        self.history.record(prev, UNDO_LIMIT);
        let cache = self.diffs.get_mut().unwrap_or_else(|e| e.into_inner());
        cache.pushed(file::Stack::Undo);
        if dropped {
            cache.dropped_oldest();
        }
        cache.cleared(file::Stack::Redo);
        let keep = self.referenced_blobs();
        self.blobs.retain(&keep);
        true
    }

    /// Sets `doc` as the current state without recording an undo step: for what is not an
    /// edit (opening a bar's search to look at its candidates), kept and saved all the same.
    fn set_unrecorded(&mut self, doc: ProjectDoc) {
        self.doc = doc;
    }

    /// Makes up to `count` more built-in moves of the dance library (see
    /// [`Derived::load_builtin`]); returns the fraction made. Optional: the library is made
    /// at once when first needed otherwise.
    pub fn load_builtin(&mut self, count: usize) -> f32 {
        self.derived.load_builtin(count)
    }

    /// The dance as the timeline shows it: each bar with its state and search by segment number
    /// of the derived library ([`Project::segment_library`]). Edits go through the project's
    /// own methods.
    pub fn dance_view(&mut self) -> Result<Vec<crate::choreo::BarView>, ProjectError> {
        let bars = self.song_bars()?;
        let d = &self.derived;
        let states: Vec<_> = self.doc.dance.bars.iter().map(|b| d.state_of(b)).collect();
        let sessions: Vec<_> = self.doc.dance.bars.iter().map(|b| b.search.as_ref().map(|s| d.session_of(s))).collect();
        Ok(crate::choreo::bar_views(&bars, &states, &sessions))
    }

    /// The song's bars (its grid's, after every correction), checked: refused without a song,
    /// when its grid cannot be made, or when it has no complete bar.
    pub fn song_bars(&mut self) -> Result<Vec<Bar>, ProjectError> {
        self.derived.update(&self.doc, &self.history.undo, &self.history.redo, &self.blobs);
        let bars = match self.derived.grid() {
            None => return Err(ProjectError::NoSong),
            Some(Err(e)) => return Err(e.clone()),
            Some(Ok(g)) => g.bars.clone(),
        };
        crate::choreo::check_bars(&bars)?;
        Ok(bars)
    }

    /// The pairs of segments the filling of the song's bars reads
    /// ([`crate::choreo::TableScope::for_bar_counts`]; none without a song).
    pub fn table_scope(&mut self) -> crate::choreo::TableScope {
        match self.song_bars() {
            Ok(bars) => crate::choreo::TableScope::for_bar_counts(&crate::choreo::bar_counts(self.derived.library(), &bars)),
            Err(_) => crate::choreo::TableScope::none(),
        }
    }

    /// The segment library derived from the document (built-in moves and the cut clips).
    pub fn segment_library(&mut self) -> &crate::choreo::SegmentLibrary {
        self.derived().library()
    }

    /// A source's file as imported (parsed once; `None`: no such source or its bytes are
    /// missing), so a host shows the very clips the project cuts without parsing them again.
    pub fn imported(&mut self, source: SourceId) -> Option<Result<std::sync::Arc<crate::import::Imported>, ImportError>> {
        let src = self.doc.source(source)?.clone();
        self.derived.imported_source(&src, &self.blobs)
    }

    /// A VMD source's face (morph) keys and the motion frame its clip starts at (the song
    /// offset), read again from the kept bytes on each call: the `.odori` file holds the VMD as
    /// given, so they need no field of their own. `None` for a source that is not a VMD, has no
    /// morph keys, or whose bytes are missing or unreadable (its import says why).
    pub fn face_keys(&self, source: SourceId) -> Option<(Vec<crate::import::vmd::MorphKey>, u32)> {
        let src = self.doc.source(source)?;
        let bytes = self.blobs.get(&src.blob)?;
        if !(bytes.starts_with(crate::import::vmd::MAGIC_V1) || bytes.starts_with(crate::import::vmd::MAGIC_V2)) {
            return None;
        }
        let vmd = crate::import::vmd::read(&src.file_name, bytes).ok()?;
        (!vmd.morph_keys.is_empty()).then(|| (vmd.morph_keys, src.options.song_offset_frames.unwrap_or(0)))
    }

    /// Opens a group of edits that one undo takes back (a share link applied bar by bar and
    /// generated): every edit until [`Project::end_group`] joins the undo step of the group's
    /// first edit. Undo, redo and the end close the group.
    pub fn begin_group(&mut self) {
        self.group = Some(false);
    }

    /// Closes the group [`Project::begin_group`] opened (nothing when none is open).
    pub fn end_group(&mut self) {
        self.group = None;
    }

    /// Undoes the last edit; `false` when there is none.
    pub fn undo(&mut self) -> bool {
        self.group = None;
        let done = self.history.undo(&mut self.doc);
        if done {
            let cache = self.diffs.get_mut().unwrap_or_else(|e| e.into_inner());
            cache.popped(file::Stack::Undo);
            cache.pushed(file::Stack::Redo);
        }
        done
    }

    /// Redoes the last undone edit; `false` when there is none.
    pub fn redo(&mut self) -> bool {
        self.group = None;
        let done = self.history.redo(&mut self.doc);
        if done {
            let cache = self.diffs.get_mut().unwrap_or_else(|e| e.into_inner());
            cache.popped(file::Stack::Redo);
            cache.pushed(file::Stack::Undo);
        }
        done
    }

    pub fn can_undo(&self) -> bool {
        self.history.can_undo()
    }

    pub fn can_redo(&self) -> bool {
        self.history.can_redo()
    }

    /// Renames the project. A label, not an edit of the work: kept and saved, not an undo
    /// step (a new project is named before its song is set; undoing the name would take the
    /// song away with it).
    pub fn set_name(&mut self, name: &str) {
        let mut doc = self.doc.clone();
        doc.name = name.to_string();
        self.set_unrecorded(doc);
    }

    /// Imports a motion file (BVH, glTF, GLB): refused with the importer's error when the
    /// bytes are not a readable file. Its humanoid clips join the dance library, cut at their
    /// detected tempo; the report gives each clip's cut (or why it is not in the library).
    /// Undoable.
    pub fn add_source(&mut self, file_name: &str, bytes: &[u8], options: ImportOptions) -> Result<SourceReport, ProjectError> {
        self.add_source_on(file_name, bytes, options, None)
    }

    /// Removes a source from the document. Its clips leave the library; bars that hold one of
    /// its moves keep it in the history only (undo brings everything back). Undoable.
    pub fn remove_source(&mut self, id: SourceId) -> Result<(), ProjectError> {
        let mut doc = self.doc.clone();
        let before = doc.sources.len();
        doc.sources.retain(|s| s.id != id);
        if doc.sources.len() == before {
            return Err(ProjectError::NoSuchSource { source_id: id.0 });
        }
        let uses = |k: &MoveKey| matches!(k, MoveKey::Cut { clip, .. } if clip.source == id);
        for b in &mut doc.dance.bars {
            if b.r#move.as_ref().is_some_and(uses) {
                *b = BarDoc { state: BarKind::Empty, r#move: None, search: b.search.take(), builtin_why: None };
            }
            if let Some(s) = &mut b.search {
                for list in [&mut s.shown, &mut s.liked, &mut s.round] {
                    list.retain(|k| !uses(k));
                }
            }
        }
        doc.tags.retain(|t| t.clip.source != id);
        if doc.character.is_some_and(|c| c.source == id) {
            doc.character = None;
        }
        doc.worn.retain(|w| w.character.source != id && !matches!(w.motion, WornMotion::Clip { clip } if clip.source == id));
        self.commit(doc);
        Ok(())
    }

    /// Re-cuts a clip at a stated tempo (counts per minute), or at its detected tempo again
    /// (`None`). Bars holding a move of the earlier cut keep it (it stays in the library,
    /// never offered again). Refused, with nothing changed, for a clip that is not in the
    /// dance library or a tempo at which it holds no 4 counts. Undoable.
    pub fn set_clip_tempo(&mut self, clip: ClipRef, tempo_bpm: Option<f32>) -> Result<ClipInfo, ProjectError> {
        let source = self.doc.source(clip.source).ok_or(ProjectError::NoSuchSource { source_id: clip.source.0 })?.clone();
        let mut doc = self.doc.clone();
        let Some(src) = doc.sources.iter_mut().find(|s| s.id == clip.source) else {
            return Err(ProjectError::NoSuchSource { source_id: clip.source.0 });
        };
        src.cut_tempos_bpm.retain(|(c, _)| *c != clip.clip);
        if let Some(t) = tempo_bpm {
            src.cut_tempos_bpm.push((clip.clip, t));
            src.cut_tempos_bpm.sort_by_key(|(c, _)| *c);
        }
        // Try the cut on the derived state of the new document before committing it.
        let saved_doc = std::mem::replace(&mut self.doc, doc.clone());
        self.derived.update(&self.doc, &self.history.undo, &self.history.redo, &self.blobs);
        let info = self.derived.clip(clip).cloned();
        self.doc = saved_doc;
        let info = info.ok_or(ProjectError::NoSuchClip { source_id: clip.source.0, file_name: source.file_name.clone(), clip: clip.clip, clips: 0 })?;
        if let Some(reason) = &info.refused {
            return Err(ProjectError::NotDanceable { file_name: source.file_name, clip: clip.clip, reason: reason.clone() });
        }
        self.commit(doc);
        Ok(info)
    }

    /// [`Project::set_clip_tempo`], saying what the re-cut meant for the dance: the new cut,
    /// how many segments of the earlier cut left the library and how many stay (held by bars),
    /// and the bars pinned to, or generated with, a move of the earlier cut (they keep it).
    pub fn recut_clip(&mut self, clip: ClipRef, tempo_bpm: Option<f32>) -> Result<RecutReport, ProjectError> {
        let before = self.derived().clip(clip).and_then(|c| c.cut.as_ref().map(|c| c.segments));
        let info = self.set_clip_tempo(clip, tempo_bpm)?;
        // `set_clip_tempo` refuses a clip it could not cut, so the cut is there.
        let summary = info.cut.ok_or_else(|| ProjectError::NotDanceable { file_name: info.file_name.clone(), clip: clip.clip, reason: "it has no cut".into() })?;
        let earlier = |k: &MoveKey| matches!(k, MoveKey::Cut { clip: c, cut_tempo_bpm, .. } if *c == clip && *cut_tempo_bpm != tempo_bpm);
        let (mut pinned_bars, mut generated_bars, mut kept) = (Vec::new(), Vec::new(), BTreeSet::new());
        for (i, b) in self.doc.dance.bars.iter().enumerate() {
            if let Some(k) = b.r#move.as_ref().filter(|k| earlier(k)) {
                kept.insert(k.id());
                if b.state == BarKind::Pinned { pinned_bars.push(i) } else { generated_bars.push(i) }
            }
        }
        let removed = before.map_or(0, |n| n.saturating_sub(kept.len()));
        Ok(RecutReport { clip: summary, removed, kept: kept.len(), pinned_bars, generated_bars })
    }

    /// Sets the song: its file name and bytes as given (`None` for the demo song), the
    /// loudness envelope the host computed from it, and the analysis options. Refused when the
    /// analysis fails. The dance keeps bar `i`'s state while the new grid has a bar `i`.
    /// Undoable.
    pub fn set_song(&mut self, file_name: &str, audio: Option<&[u8]>, envelope: &RmsEnvelope, options: AnalysisOptions) -> Result<(), ProjectError> {
        self.song_change(true, file_name, audio, envelope, options)
    }

    /// [`Project::set_song`] without an undo step: the song a new project starts with (the
    /// built-in demo song) is where its history begins, not an edit to take back.
    pub fn set_initial_song(&mut self, file_name: &str, audio: Option<&[u8]>, envelope: &RmsEnvelope, options: AnalysisOptions) -> Result<(), ProjectError> {
        self.song_change(false, file_name, audio, envelope, options)
    }

    fn song_change(&mut self, record: bool, file_name: &str, audio: Option<&[u8]>, envelope: &RmsEnvelope, options: AnalysisOptions) -> Result<(), ProjectError> {
        let grid = crate::music::analyze(envelope, &options)?;
        let mut doc = self.doc.clone();
        let audio = audio.map(|a| self.blobs.put(a));
        let envelope = self.blobs.put(&encode_envelope(envelope));
        doc.song = Some(SongDoc { file_name: file_name.to_string(), audio, envelope, options, corrections: Vec::new() });
        doc.dance.bars.resize(grid.bars.len(), BarDoc::default());
        if record {
            self.commit(doc);
        } else {
            self.set_unrecorded(doc);
        }
        Ok(())
    }

    /// Corrects the song's grid (tempo, taps, beats per bar, first downbeat, nudge). Refused
    /// with the music error when the correction is invalid. Undoable.
    pub fn correct_grid(&mut self, correction: GridCorrection) -> Result<(), ProjectError> {
        let mut doc = self.doc.clone();
        let song = doc.song.as_mut().ok_or(ProjectError::NoSong)?;
        song.corrections.push(correction);
        let grid = derive::song_grid(song, &self.blobs)?;
        doc.dance.bars.resize(grid.bars.len(), BarDoc::default());
        self.commit(doc);
        Ok(())
    }

    /// Back to the analysed grid (every correction dropped). Undoable.
    pub fn reset_grid(&mut self) -> Result<(), ProjectError> {
        let mut doc = self.doc.clone();
        let song = doc.song.as_mut().ok_or(ProjectError::NoSong)?;
        song.corrections.clear();
        let grid = derive::song_grid(song, &self.blobs)?;
        doc.dance.bars.resize(grid.bars.len(), BarDoc::default());
        self.commit(doc);
        Ok(())
    }

    /// Tags a clip so text can call it (an empty list removes its tags). Undoable.
    pub fn set_tags(&mut self, clip: ClipRef, tags: Vec<String>) -> Result<(), ProjectError> {
        self.check_clip(clip)?;
        let mut doc = self.doc.clone();
        doc.tags.retain(|t| t.clip != clip);
        if !tags.is_empty() {
            doc.tags.push(Tagging { clip, tags });
        }
        self.commit(doc);
        Ok(())
    }

    /// The texts typed (the text panel's contents). Undoable.
    pub fn set_texts(&mut self, texts: Vec<String>) {
        let mut doc = self.doc.clone();
        doc.texts = texts;
        self.commit(doc);
    }

    /// The character the dance is shown on (`None`: the built-in body). Undoable.
    pub fn set_character(&mut self, clip: Option<ClipRef>) -> Result<(), ProjectError> {
        if let Some(c) = clip {
            self.check_clip(c)?;
        }
        let mut doc = self.doc.clone();
        doc.character = clip;
        doc.stick_figures = false;
        self.commit(doc);
        Ok(())
    }

    /// Stick figures instead of any body (the built-in one or a character). Undoable; a
    /// character chosen after it ([`Project::set_character`]) ends it.
    pub fn set_stick_figures(&mut self) {
        let mut doc = self.doc.clone();
        doc.character = None;
        doc.stick_figures = true;
        self.commit(doc);
    }

    /// Puts a motion on a character (an imported skinned humanoid): `motion` is a clip of a
    /// source, or `bvh` (the BVH file the engine wrote of a motion made in the page, with its
    /// `name`) when `motion` is `None`. Refused, with nothing changed, when either clip is not
    /// in the project or the character cannot play it. Returns the put-on clip's number (for
    /// [`Project::worn_clip`]). Undoable.
    pub fn put_on(&mut self, character: ClipRef, motion: Option<ClipRef>, bvh: Option<(&str, &[u8])>) -> Result<usize, ProjectError> {
        self.check_clip(character)?;
        let motion = match (motion, bvh) {
            (Some(clip), _) => {
                self.check_clip(clip)?;
                WornMotion::Clip { clip }
            }
            (None, Some((name, bytes))) => {
                // Read it now so a file that does not import is refused before it is kept.
                self.derived.import(&BlobHash::of(bytes), &worn_file_name(name), bytes, &ImportOptions::default())?;
                WornMotion::Motion { name: name.to_string(), bvh: BlobHash::of(bytes) }
            }
            (None, None) => return Err(ProjectError::NoMotion),
        };
        let worn = Worn { character, motion };
        self.make_worn(&worn, bvh.map(|(_, b)| b))?;
        if let (WornMotion::Motion { .. }, Some((_, bytes))) = (&worn.motion, bvh) {
            self.blobs.put(bytes);
        }
        let mut doc = self.doc.clone();
        doc.worn.push(worn);
        let index = doc.worn.len() - 1;
        self.commit(doc);
        Ok(index)
    }

    /// Takes a put-on clip away. Undoable.
    pub fn remove_worn(&mut self, index: usize) -> Result<(), ProjectError> {
        if index >= self.doc.worn.len() {
            return Err(ProjectError::NoSuchWorn { index, count: self.doc.worn.len() });
        }
        let mut doc = self.doc.clone();
        doc.worn.remove(index);
        self.commit(doc);
        Ok(())
    }

    /// Put-on clip `index` rebuilt from its recipe: the motion retargeted to the character's
    /// rig, with the character's file as imported (its mesh draws the clip).
    pub fn worn_clip(&mut self, index: usize) -> Result<(Clip, std::sync::Arc<crate::import::Imported>), ProjectError> {
        let worn = self.doc.worn.get(index).cloned().ok_or(ProjectError::NoSuchWorn { index, count: self.doc.worn.len() })?;
        self.make_worn(&worn, None)
    }

    /// The source's file as imported, or why it cannot be had.
    fn imported_or_missing(&mut self, source: SourceId) -> Result<std::sync::Arc<crate::import::Imported>, ProjectError> {
        let src = self.doc.source(source).ok_or(ProjectError::NoSuchSource { source_id: source.0 })?.clone();
        match self.derived.imported_source(&src, &self.blobs) {
            Some(r) => Ok(r?),
            None => Err(ProjectError::Incomplete { count: 1, first: format!("motion file {}", src.file_name) }),
        }
    }

    fn make_worn(&mut self, worn: &Worn, bvh: Option<&[u8]>) -> Result<(Clip, std::sync::Arc<crate::import::Imported>), ProjectError> {
        let ch = self.imported_or_missing(worn.character.source)?;
        let file = self.doc.source(worn.character.source).map(|s| s.file_name.clone()).unwrap_or_default();
        let character = crate::canon::character::Character::from_imported(&file, &ch)?;
        let (clip, map) = match &worn.motion {
            WornMotion::Clip { clip } => {
                let im = self.imported_or_missing(clip.source)?;
                let c = im.clips.get(clip.clip as usize).cloned().ok_or_else(|| ProjectError::NoSuchClip { source_id: clip.source.0, file_name: file.clone(), clip: clip.clip, clips: im.clips.len() })?;
                (c, im.humanoid.clone())
            }
            WornMotion::Motion { name, bvh: hash } => {
                let bytes = match bvh {
                    Some(b) => b.to_vec(),
                    None => self.blobs.get(hash).map(|b| b.to_vec()).ok_or_else(|| ProjectError::Incomplete { count: 1, first: format!("put-on motion {name}") })?,
                };
                let im = self.derived.import(hash, &worn_file_name(name), &bytes, &ImportOptions::default())?;
                let c = im.clips.first().cloned().ok_or_else(|| ProjectError::NoSuchClip { source_id: u32::MAX, file_name: name.clone(), clip: 0, clips: 0 })?;
                (c, im.humanoid.clone())
            }
        };
        Ok((character.retarget(&clip, &map)?, ch))
    }

    /// Where the viewer looks from. A view setting, not an edit: kept and saved, not undone.
    pub fn set_camera(&mut self, camera: Option<Camera>) {
        self.doc.camera = camera;
    }

    fn check_clip(&mut self, clip: ClipRef) -> Result<(), ProjectError> {
        let source = self.doc.source(clip.source).ok_or(ProjectError::NoSuchSource { source_id: clip.source.0 })?.clone();
        let d = self.derived();
        let clips = d.clips().iter().filter(|c| c.clip.source == clip.source).count();
        if clip.clip as usize >= clips && !self.missing.iter().any(|m| m.hash == source.blob) {
            return Err(ProjectError::NoSuchClip { source_id: clip.source.0, file_name: source.file_name, clip: clip.clip, clips });
        }
        Ok(())
    }
}

#[cfg(test)]
mod move_key_tests {
    use super::*;

    #[test]
    fn a_cut_keys_counts_are_left_out_when_four_and_kept_when_three() {
        let clip = ClipRef { source: SourceId(2), clip: 0 };
        let four = MoveKey::Cut { clip, cut_tempo_bpm: None, first_count: 6, counts: 4 };
        let three = MoveKey::Cut { clip, cut_tempo_bpm: None, first_count: 6, counts: 3 };
        // A 4-count key is written (and identified) as before 3-count segments existed.
        let saved_before = r#"{"kind":"cut","clip":{"source":2,"clip":0},"cutTempoBpm":null,"firstCount":6}"#;
        assert_eq!(four.id(), saved_before);
        assert_eq!(serde_json::from_str::<MoveKey>(saved_before).unwrap(), four);
        // The 3-count window from the same count is another move.
        assert_ne!(three.id(), four.id());
        assert_eq!(serde_json::from_str::<MoveKey>(&three.id()).unwrap(), three);
    }
}
