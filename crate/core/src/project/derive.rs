//! What a project derives from its document: the imported clips, the segment library (the
//! built-in moves plus every humanoid clip cut at its tempo — and, for moves the dance or its
//! history still holds, the earlier cuts they came from), the map between [`MoveKey`]s and the
//! library's segment numbers, and the song's grid. Rebuilt from scratch whenever what it
//! depends on changes, so the state after any sequence of edits is the state a fresh session
//! builds from the same document: that is what makes a saved project reopen identically.

use std::collections::{BTreeMap, BTreeSet, HashMap, HashSet};
use std::sync::Arc;

use serde::{Deserialize, Serialize};

use super::models::{Drawn, ModelIn};
use super::{decode_envelope, BarDoc, BarKind, BlobHash, BlobStore, ClipRef, MoveKey, ProjectDoc, ProjectError, SearchDoc, SongDoc, Source, SourceId};
use crate::choreo::{BarState, BuiltinLoader, ClipSummary, FeedbackSession, SegmentLibrary, SegmentOptions};
use crate::canon::humanoid::HumanoidStatus;
use crate::import::{import_bytes, ImportError, ImportOptions, Imported};
use crate::music::{analyze, SongGrid};

/// One clip of a source, as the library panel shows it.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "camelCase")]
pub struct ClipInfo {
    pub clip: ClipRef,
    pub name: String,
    pub file_name: String,
    pub fps: f32,
    pub frames: usize,
    pub duration_secs: f32,
    pub joints: usize,
    pub humanoid: HumanoidStatus,
    /// Its current cut in the segment library (`clip`: the library's clip number).
    pub cut: Option<ClipSummary>,
    /// Why it is not in the dance library (not humanoid, too short at its tempo, ...).
    pub refused: Option<String>,
}

/// The clips of an imported file, before any cut.
pub(crate) fn clip_infos(id: SourceId, imported: &Imported) -> Vec<ClipInfo> {
    imported
        .clips
        .iter()
        .enumerate()
        .map(|(j, c)| ClipInfo {
            clip: ClipRef { source: id, clip: j as u32 },
            name: c.name.clone(),
            file_name: c.source.clone(),
            fps: c.fps,
            frames: c.frame_count(),
            duration_secs: c.duration_secs(),
            joints: c.skeleton.joints.len(),
            humanoid: imported.status.clone(),
            cut: None,
            refused: match &imported.status {
                HumanoidStatus::NotHumanoid { reason } => Some(format!("not humanoid: {reason}")),
                _ => None,
            },
        })
        .collect()
}

/// The song's grid: the analysis of its envelope with every correction applied in order.
pub(crate) fn song_grid(song: &SongDoc, blobs: &BlobStore) -> Result<SongGrid, ProjectError> {
    let bytes = blobs.get(&song.envelope).ok_or_else(|| ProjectError::BadEnvelope { message: format!("the envelope of {} ({}) is missing", song.file_name, song.envelope) })?;
    let env = decode_envelope(bytes)?;
    let mut grid = analyze(&env, &song.options)?;
    for c in &song.corrections {
        grid = grid.corrected(c)?;
    }
    Ok(grid)
}

/// What a parsed file is kept under: the same bytes read under another name or options are
/// another parse.
fn import_key(hash: &BlobHash, file_name: &str, options: &ImportOptions) -> String {
    format!("{hash}|{file_name}|{}", serde_json::to_string(options).unwrap_or_default())
}

/// State derived from a project's document (see the module doc).
#[derive(Default)]
pub struct Derived {
    /// Imported files by (hash, file name, options).
    imports: HashMap<String, Arc<Imported>>,
    /// What the library was built from: one entry per source, and the earlier cuts kept.
    lib_sources: Vec<String>,
    lib_tail: Option<String>,
    lib: SegmentLibrary,
    /// The key of every segment of `lib`, by segment number.
    keys: Vec<MoveKey>,
    index: HashMap<String, usize>,
    clips: Vec<ClipInfo>,
    grid_spec: Option<String>,
    grid: Option<Result<SongGrid, ProjectError>>,
    /// The built-in library, made once (in slices with [`Derived::load_builtin`], or at once
    /// on first need); every rebuild starts from a copy of it.
    builtin: Option<SegmentLibrary>,
    /// The built-in library being made in slices.
    builtin_loading: Option<(SegmentLibrary, BuiltinLoader)>,
}

impl std::fmt::Debug for Derived {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Derived")
            .field("segments", &self.lib.len())
            .field("clips", &self.clips.len())
            .field("grid", &self.grid)
            .field("builtin_ready", &self.builtin.is_some())
            .finish()
    }
}

impl Derived {
    /// Makes up to `count` more of the built-in moves (the library every rebuild starts
    /// from), so a page need not block for all of them at once; returns the fraction made
    /// (1: ready).
    pub(crate) fn load_builtin(&mut self, count: usize) -> f32 {
        if self.builtin.is_some() {
            return 1.0;
        }
        let (lib, loader) = self.builtin_loading.get_or_insert_with(|| (SegmentLibrary::new(), BuiltinLoader::new()));
        let p = lib.load_builtin(loader, count);
        if p >= 1.0 {
            self.builtin = self.builtin_loading.take().map(|(lib, _)| lib);
            return 1.0;
        }
        p
    }

    /// A copy of the built-in library (made at once when [`Derived::load_builtin`] has not
    /// finished it).
    fn builtin_library(&mut self) -> SegmentLibrary {
        while self.load_builtin(usize::MAX) < 1.0 {}
        self.builtin.clone().unwrap_or_else(SegmentLibrary::builtin)
    }

    /// The file a source was imported from, as imported (parsed once per session: the page
    /// shows the same clips the project cuts).
    pub(crate) fn imported_source(&mut self, src: &Source, blobs: &BlobStore) -> Option<Result<Arc<Imported>, ImportError>> {
        let bytes = blobs.get(&src.blob)?.clone();
        let model = src.model.as_ref().map(|m| (m, blobs.get(&m.blob).cloned()));
        let on = model.as_ref().map(|(m, b)| ModelIn { file: &m.file_name, hash: &m.blob, bytes: b.as_deref(), drawn: Drawn::Kept(m, blobs) });
        Some(self.import_on(&src.blob, &src.file_name, &bytes, &src.options, on))
    }

    /// [`Derived::import`] of a VMD dance posed on an MMD model file (`None` bytes: named but
    /// missing, so posed on the standard skeleton with a warning; drawn on its mesh with the
    /// files kept with it), or on the standard skeleton like any file when `model` is `None`.
    pub(crate) fn import_on(&mut self, hash: &BlobHash, file_name: &str, bytes: &[u8], options: &ImportOptions, model: Option<ModelIn<'_>>) -> Result<Arc<Imported>, ImportError> {
        use crate::mmd::files::{import_vmd_source_on, SourceModel};
        let Some(m) = model else { return self.import(hash, file_name, bytes, options) };
        let key = format!("{}|on {} {} {} {}", import_key(hash, file_name, options), m.file, m.hash, m.bytes.is_some(), m.drawn.key());
        if let Some(i) = self.imports.get(&key) {
            return Ok(i.clone());
        }
        options.validate(file_name)?;
        let drawn = m.drawn.files();
        let on = match m.bytes {
            Some(b) => SourceModel::File(m.file, b, &drawn),
            None => SourceModel::Missing(m.file),
        };
        let imported = Arc::new(import_vmd_source_on(file_name, bytes, options.song_offset_frames, on)?);
        self.imports.insert(key, imported.clone());
        Ok(imported)
    }

    /// Imports a file (or returns the copy imported before).
    pub(crate) fn import(&mut self, hash: &BlobHash, file_name: &str, bytes: &[u8], options: &ImportOptions) -> Result<Arc<Imported>, ImportError> {
        let key = import_key(hash, file_name, options);
        if let Some(i) = self.imports.get(&key) {
            return Ok(i.clone());
        }
        let imported = Arc::new(import_bytes(file_name, bytes, options)?);
        self.imports.insert(key, imported.clone());
        Ok(imported)
    }

    /// Brings everything up to date with the document (and the history, whose moves keep
    /// their earlier cuts in the library).
    pub(crate) fn update(&mut self, doc: &ProjectDoc, undo: &[ProjectDoc], redo: &[ProjectDoc], blobs: &BlobStore) {
        let grid_spec = serde_json::to_string(&doc.song).unwrap_or_default();
        if self.grid_spec.as_deref() != Some(grid_spec.as_str()) {
            self.grid = doc.song.as_ref().map(|s| song_grid(s, blobs));
            self.grid_spec = Some(grid_spec);
        }
        // Earlier cuts a kept move (a bar's move or a liked one, now or in the history) still
        // comes from, per clip, in the order they first appear.
        let mut referenced: HashSet<String> = HashSet::new();
        let mut cut_refs: Vec<(ClipRef, String)> = Vec::new();
        let mut cuts_seen: BTreeMap<ClipRef, Vec<Option<f32>>> = BTreeMap::new();
        for d in undo.iter().chain(std::iter::once(doc)).chain(redo.iter().rev()) {
            for k in d.kept_keys() {
                let id = k.id();
                if referenced.insert(id.clone()) {
                    if let MoveKey::Cut { clip, cut_tempo_bpm, .. } = k {
                        cut_refs.push((*clip, id));
                        let list = cuts_seen.entry(*clip).or_default();
                        if !list.contains(cut_tempo_bpm) {
                            list.push(*cut_tempo_bpm);
                        }
                    }
                }
            }
        }
        // Only cuts other than a clip's current one change the library (and, for those clips,
        // which moves a re-cut keeps): pinning a move of a current cut rebuilds nothing.
        let current = |c: &ClipRef| doc.source(c.source).map(|s| s.cut_tempo_bpm(c.clip));
        let earlier: BTreeMap<ClipRef, Vec<Option<f32>>> = cuts_seen
            .iter()
            .filter_map(|(c, v)| {
                let now = current(c);
                let v: Vec<Option<f32>> = v.iter().copied().filter(|t| now != Some(*t)).collect();
                (!v.is_empty()).then_some((*c, v))
            })
            .collect();
        let keep_refs: BTreeSet<&String> = cut_refs.iter().filter(|(c, _)| earlier.contains_key(c)).map(|(_, id)| id).collect();
        let tail = serde_json::to_string(&(&earlier, &keep_refs)).unwrap_or_default();
        let sources: Vec<String> = doc
            .sources
            .iter()
            .map(|s| serde_json::to_string(&(s.id, &s.blob, blobs.contains(&s.blob), &s.file_name, &s.options, &s.cut_tempos_bpm)).unwrap_or_default())
            .collect();
        let same_tail = self.lib_tail.as_deref() == Some(tail.as_str());
        if same_tail && self.lib_sources == sources {
            return;
        }
        // Sources only added (the common edit: an import): cut just the new ones, which gives
        // the library a full rebuild in the same order would.
        let from = if same_tail && sources.starts_with(&self.lib_sources) { self.lib_sources.len() } else { 0 };
        self.rebuild_library(doc, blobs, &referenced, &earlier, from);
        self.lib_sources = sources;
        self.lib_tail = Some(tail);
        self.forget_imports(doc);
    }

    /// Forgets the parsed files the document no longer names (a removed source, a source whose
    /// options changed, a put-on motion taken away): a parse holds the whole clip, and a
    /// session that imports and removes files would otherwise keep every one of them. The
    /// blobs stay while the history refers to them, so an undo parses the file again.
    fn forget_imports(&mut self, doc: &ProjectDoc) {
        let mut keep: HashSet<String> = doc.sources.iter().map(|s| import_key(&s.blob, &s.file_name, &s.options)).collect();
        for w in &doc.worn {
            if let super::WornMotion::Motion { name, bvh } = &w.motion {
                keep.insert(import_key(bvh, &super::worn_file_name(name), &ImportOptions::default()));
            }
        }
        self.imports.retain(|k, _| keep.contains(k));
    }

    /// How many parsed files are kept (for tests of [`Derived::forget_imports`]).
    pub fn parsed_files(&self) -> usize {
        self.imports.len()
    }

    fn rebuild_library(&mut self, doc: &ProjectDoc, blobs: &BlobStore, referenced: &HashSet<String>, old_cuts: &BTreeMap<ClipRef, Vec<Option<f32>>>, from_source: usize) {
        if from_source > 0 {
            let (lib, keys, clips) = (std::mem::take(&mut self.lib), std::mem::take(&mut self.keys), std::mem::take(&mut self.clips));
            return self.cut_sources(&doc.sources[from_source..], blobs, referenced, old_cuts, lib, keys, clips);
        }
        let lib = self.builtin_library();
        let keys: Vec<MoveKey> = lib
            .segments()
            .iter()
            .map(|s| match s.builtin {
                Some(m) => MoveKey::Builtin { r#move: m },
                // Unreachable: the built-in library holds only built-in moves.
                None => MoveKey::Cut { clip: ClipRef { source: SourceId(u32::MAX), clip: s.index as u32 }, cut_tempo_bpm: None, first_count: 0, counts: 4 },
            })
            .collect();
        self.cut_sources(&doc.sources, blobs, referenced, old_cuts, lib, keys, Vec::new());
    }

    /// Adds the clips of `sources` to a library (see [`Derived::update`]) and installs it.
    #[allow(clippy::too_many_arguments)]
    fn cut_sources(&mut self, sources: &[Source], blobs: &BlobStore, referenced: &HashSet<String>, old_cuts: &BTreeMap<ClipRef, Vec<Option<f32>>>, mut lib: SegmentLibrary, mut keys: Vec<MoveKey>, mut clips: Vec<ClipInfo>) {
        for src in sources {
            let Some(Ok(imported)) = self.imported_source(src, blobs) else { continue };
            let mut infos = clip_infos(src.id, &imported);
            for (j, clip) in imported.clips.iter().enumerate() {
                let info = &mut infos[j];
                if info.refused.is_some() {
                    continue;
                }
                let cref = info.clip;
                let current = src.cut_tempo_bpm(j as u32);
                let mut cuts: Vec<Option<f32>> = old_cuts.get(&cref).map(|v| v.iter().copied().filter(|t| *t != current).collect()).unwrap_or_default();
                cuts.push(current);
                let mut lib_clip: Option<usize> = None;
                for (n, &tempo) in cuts.iter().enumerate() {
                    let is_current = n + 1 == cuts.len();
                    let opts = SegmentOptions { tempo_bpm: tempo, ..Default::default() };
                    let result = match lib_clip {
                        None => lib.add_clip(clip, &imported.humanoid, &imported.status, &opts),
                        Some(ci) => {
                            let keep = |i: usize| keys.get(i).is_some_and(|k| referenced.contains(&k.id()));
                            lib.recut_clip(ci, &opts, &keep).map(|r| {
                                let mut remapped = vec![None; lib.len()];
                                for (old, new) in r.remap.iter().enumerate() {
                                    if let (Some(new), Some(k)) = (new, keys.get(old)) {
                                        remapped[*new] = Some(k.clone());
                                    }
                                }
                                keys = remapped.into_iter().map(|k| k.unwrap_or(MoveKey::Cut { clip: cref, cut_tempo_bpm: tempo, first_count: 0, counts: 4 })).collect();
                                r.summary
                            })
                        }
                    };
                    match result {
                        Ok(summary) => {
                            lib_clip = Some(summary.clip);
                            keys.truncate(lib.len() - summary.segments);
                            for seg in &lib.segments()[lib.len() - summary.segments..] {
                                let beats = &lib.clips()[seg.clip].beat_frames;
                                let first_count = beats.iter().position(|b| b.round().max(0.0) == seg.start_frame).unwrap_or(usize::MAX) as u32;
                                keys.push(MoveKey::Cut { clip: cref, cut_tempo_bpm: tempo, first_count, counts: seg.counts() as u32 });
                            }
                            if is_current {
                                info.cut = Some(summary);
                            }
                        }
                        Err(e) if is_current => info.refused = Some(e.to_string()),
                        Err(_) => {}
                    }
                }
            }
            clips.extend(infos);
        }
        self.index = keys.iter().enumerate().map(|(i, k)| (k.id(), i)).collect();
        self.keys = keys;
        self.lib = lib;
        self.clips = clips;
    }

    pub fn library(&self) -> &SegmentLibrary {
        &self.lib
    }

    /// Every clip of every source (as of the last update).
    pub fn clips(&self) -> &[ClipInfo] {
        &self.clips
    }

    pub fn clip(&self, clip: ClipRef) -> Option<&ClipInfo> {
        self.clips.iter().find(|c| c.clip == clip)
    }

    /// The song's grid (`None`: no song).
    pub fn grid(&self) -> Option<&Result<SongGrid, ProjectError>> {
        self.grid.as_ref()
    }

    /// The key of segment `index`.
    pub fn key(&self, index: usize) -> Option<&MoveKey> {
        self.keys.get(index)
    }

    /// The segment a key names, if it is in the library.
    pub fn index_of(&self, key: &MoveKey) -> Option<usize> {
        self.index.get(&key.id()).copied()
    }

    pub(crate) fn keys_of(&self, segments: &[usize]) -> Vec<MoveKey> {
        segments.iter().filter_map(|&s| self.keys.get(s).cloned()).collect()
    }

    pub(crate) fn indices_of(&self, keys: &[MoveKey]) -> Result<Vec<usize>, ProjectError> {
        keys.iter().map(|k| self.index_of(k).ok_or_else(|| ProjectError::UnknownMove { key: k.id() })).collect()
    }

    /// The segments `keys` name that are in the library, in order (the rest are left out).
    pub(crate) fn resolve(&self, keys: &[MoveKey]) -> Vec<usize> {
        keys.iter().filter_map(|k| self.index_of(k)).collect()
    }

    /// A bar's state by segment number (a move not in the library leaves the bar empty).
    pub(crate) fn state_of(&self, bar: &BarDoc) -> BarState {
        match (bar.state, bar.r#move.as_ref().and_then(|k| self.index_of(k))) {
            (BarKind::Pinned, Some(segment)) => BarState::Pinned { segment },
            (BarKind::Generated, Some(segment)) => BarState::Generated { segment },
            _ => BarState::Empty,
        }
    }

    /// A bar's state by key (what the document keeps).
    pub(crate) fn bar_doc(&self, state: BarState, search: Option<SearchDoc>) -> BarDoc {
        let (kind, seg) = match state {
            BarState::Empty => (BarKind::Empty, None),
            BarState::Pinned { segment } => (BarKind::Pinned, Some(segment)),
            BarState::Generated { segment } => (BarKind::Generated, Some(segment)),
        };
        BarDoc { state: kind, r#move: seg.and_then(|s| self.keys.get(s).cloned()), search, builtin_why: None }
    }

    /// A bar's search by segment number (moves not in the library are forgotten).
    pub(crate) fn session_of(&self, s: &SearchDoc) -> FeedbackSession {
        FeedbackSession { tau: s.tau, shown: self.resolve(&s.shown), liked: self.resolve(&s.liked), round: self.resolve(&s.round), rounds: s.rounds, ..FeedbackSession::new() }
    }

    /// A bar's search by key.
    pub(crate) fn search_doc(&self, s: &FeedbackSession) -> SearchDoc {
        SearchDoc { tau: s.tau, shown: self.keys_of(&s.shown), liked: self.keys_of(&s.liked), round: self.keys_of(&s.round), rounds: s.rounds }
    }
}
