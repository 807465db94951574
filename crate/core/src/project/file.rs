//! The `.odori` file (spec §K): one zip archive holding `manifest.json` — the format name, a
//! schema version, the project document and its undo/redo history — and `blobs/<sha256>`, the
//! bytes the document refers to, each named by the SHA-256 of its contents. The zip container
//! is the `zip` crate (pure Rust deflate through `flate2`/`miniz_oxide`, so the same code runs
//! in wasm); it gives a file any zip tool can list, per-entry CRCs and random access.
//!
//! Opening checks everything before anything is replaced: a file that is not a zip, is cut
//! short, has a bad checksum, a blob whose bytes do not match its name, no or a malformed
//! manifest, or a schema version newer than this build gives a typed [`FileError`] naming the
//! problem, and the caller keeps its open project. A blob the manifest names but the file
//! lacks is not fatal: the rest opens and [`Opened::missing`] names what is gone. Older schema
//! versions go through [`migrate`] step by step.
//!
//! The history is kept compactly (schema 2): each undo/redo state is written as the change
//! from its neighbour nearer the current document ([`json_diff`]: changed object fields and
//! array elements only, by position), not as a whole document. An edit changes a bar or a
//! field, so a step costs a few hundred bytes instead of the whole dance; the manifest that
//! autosave writes after every edit stays small however long the session. Schema 1 (whole
//! documents) is read through the migration step.

use std::collections::BTreeMap;
use std::io::{Cursor, Read, Write};
use std::sync::Arc;

use serde::{Deserialize, Serialize};
use thiserror::Error;
use zip::write::SimpleFileOptions;
use zip::{CompressionMethod, ZipArchive, ZipWriter};

use super::{BlobHash, BlobStore, Project, ProjectDoc};

/// The schema version this build writes. Bump it with a step in [`migrate`] and a golden file
/// of the old version in `tests/golden/`.
pub const CURRENT_SCHEMA_VERSION: u32 = 7;
/// The oldest schema version this build opens.
pub const OLDEST_SCHEMA_VERSION: u32 = 1;
/// The value of the manifest's `format` field.
pub const FORMAT_NAME: &str = "odori-project";
/// MIME type for downloads and the File System Access API.
pub const ODORI_MIME: &str = "application/x-odori+zip";
const MANIFEST: &str = "manifest.json";
const BLOB_DIR: &str = "blobs/";

/// Why a file could not be opened (or written). The open project is never touched by a
/// failed open.
#[derive(Debug, Error, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "camelCase")]
pub enum FileError {
    #[error("the file is empty")]
    Empty,
    #[error("not an .odori file: it is not a zip archive (it starts with {start:?})")]
    NotOdori { start: String },
    #[error("the file is truncated: {size_bytes} bytes, and its end ({message}) is missing")]
    Truncated { size_bytes: usize, message: String },
    #[error("the file is corrupt: {entry}: {message}")]
    Corrupt { entry: String, message: String },
    #[error("not an .odori file: the archive has no manifest.json")]
    NoManifest,
    #[error("manifest.json is malformed at line {line}, column {column}: {message}")]
    BadManifest { line: usize, column: usize, message: String },
    #[error("manifest.json does not describe a project: {message}")]
    BadProject { message: String },
    #[error("not an .odori file: its manifest says format {format:?}")]
    WrongFormat { format: String },
    #[error("the file was made by a newer version of Odori (schema {found}; this version reads up to {supported}): update Odori to open it")]
    NewerVersion { found: u32, supported: u32 },
    #[error("schema version {found} is older than any this version reads (oldest {oldest})")]
    TooOld { found: u32, oldest: u32 },
    #[error("the file is corrupt: blob {name} holds bytes whose hash is {actual}")]
    BlobMismatch { name: String, actual: String },
    #[error("could not write the file: {message}")]
    Write { message: String },
}

impl FileError {
    /// A short machine-readable kind, stable for the JS API.
    pub fn kind(&self) -> &'static str {
        match self {
            FileError::Empty => "empty",
            FileError::NotOdori { .. } | FileError::NoManifest | FileError::WrongFormat { .. } => "not-odori",
            FileError::Truncated { .. } => "truncated",
            FileError::Corrupt { .. } | FileError::BlobMismatch { .. } | FileError::BadManifest { .. } | FileError::BadProject { .. } => "corrupt",
            FileError::NewerVersion { .. } => "newer-version",
            FileError::TooOld { .. } => "too-old",
            FileError::Write { .. } => "write",
        }
    }
}

/// A blob the document names that was not in the file (or the store).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "camelCase")]
pub struct MissingBlob {
    pub hash: BlobHash,
    /// What it was, for the message: "motion file salsa_01.bvh", "song audio fishin.ogg"...
    pub what: String,
}

/// A project read back, with what was missing and whether it was migrated.
#[derive(Debug)]
pub struct Opened {
    pub project: Project,
    pub missing: Vec<MissingBlob>,
    /// The schema version the file had when older than [`CURRENT_SCHEMA_VERSION`].
    pub migrated_from: Option<u32>,
}

/// The manifest as written.
#[derive(Serialize, Deserialize)]
#[serde(rename_all = "camelCase")]
struct Manifest {
    format: String,
    schema_version: u32,
    /// The program that wrote it (informative).
    generator: String,
    project: ProjectDoc,
    /// Undo states, oldest first, each as [`json_diff`] from the state after it (the last one:
    /// from `project`).
    undo: Vec<serde_json::Value>,
    /// Redo states, as stacked (the next redo last), each as [`json_diff`] from the state after
    /// it (the last one: from `project`).
    redo: Vec<serde_json::Value>,
    /// Every blob the file holds, with its size (informative; the archive is the truth).
    blobs: BTreeMap<BlobHash, usize>,
}

/// The manifest as written (borrowing, so a write copies nothing it need not).
#[derive(Serialize)]
#[serde(rename_all = "camelCase")]
struct ManifestOut<'a> {
    format: &'a str,
    schema_version: u32,
    generator: &'a str,
    project: &'a ProjectDoc,
    undo: &'a [Option<serde_json::Value>],
    redo: &'a [Option<serde_json::Value>],
    blobs: BTreeMap<BlobHash, usize>,
}

/// The history's changes ([`diff_chain`]) kept between writes: entry `i` of a stack is the
/// change from entry `i + 1`, which never changes while both are on the stack, so each is
/// computed once. The last entry's change is from the current document, which edits that are
/// not undo steps (a name, the camera, an open search) change in place: it is recomputed on
/// every write. Without this, every autosave serialised and compared the whole history
/// (up to [`super::UNDO_LIMIT`] documents), which put a write over its 4 ms budget.
#[derive(Debug, Default)]
pub(crate) struct DiffCache {
    undo: Vec<Option<serde_json::Value>>,
    redo: Vec<Option<serde_json::Value>>,
}

/// Which stack of the history.
#[derive(Clone, Copy)]
pub(crate) enum Stack {
    Undo,
    Redo,
}

impl DiffCache {
    fn stack(&mut self, s: Stack) -> &mut Vec<Option<serde_json::Value>> {
        match s {
            Stack::Undo => &mut self.undo,
            Stack::Redo => &mut self.redo,
        }
    }

    /// A state was pushed on `s`: the former top's change was from the current document and
    /// is now from the pushed state.
    pub(crate) fn pushed(&mut self, s: Stack) {
        let v = self.stack(s);
        if let Some(last) = v.last_mut() {
            *last = None;
        }
        v.push(None);
    }

    pub(crate) fn popped(&mut self, s: Stack) {
        self.stack(s).pop();
    }

    /// The oldest undo state was dropped (the undo limit).
    pub(crate) fn dropped_oldest(&mut self) {
        if !self.undo.is_empty() {
            self.undo.remove(0);
        }
    }

    pub(crate) fn cleared(&mut self, s: Stack) {
        self.stack(s).clear();
    }

    /// Fills in what is not cached of `states`' changes (see [`diff_chain`]); the last from
    /// `current`, always afresh.
    fn fill(cache: &mut Vec<Option<serde_json::Value>>, current: &serde_json::Value, states: &[ProjectDoc]) {
        if cache.len() != states.len() {
            // Out of step (never expected): start over rather than write a wrong change.
            *cache = vec![None; states.len()];
        }
        let n = states.len();
        let mut next: Option<serde_json::Value> = None;
        for i in (0..n).rev() {
            if i + 1 == n {
                let v = serde_json::to_value(&states[i]).unwrap_or_default();
                cache[i] = Some(json_diff(current, &v));
                next = Some(v);
            } else if cache[i].is_some() {
                next = None;
            } else {
                let after = match next.take() {
                    Some(v) => v,
                    None => serde_json::to_value(&states[i + 1]).unwrap_or_default(),
                };
                let v = serde_json::to_value(&states[i]).unwrap_or_default();
                cache[i] = Some(json_diff(&after, &v));
                next = Some(v);
            }
        }
    }
}

/// The manifest of a project (what autosave writes on every edit; the blobs go separately,
/// once each).
pub fn manifest_json(project: &Project) -> Vec<u8> {
    let blobs = project.referenced_blobs().into_iter().filter_map(|h| project.blobs().get(&h).map(|b| (h, b.len()))).collect();
    let current = serde_json::to_value(project.doc()).unwrap_or_default();
    let mut cache = project.diffs.lock().unwrap_or_else(|e| e.into_inner());
    let cache = &mut *cache;
    DiffCache::fill(&mut cache.undo, &current, project.undo_history());
    DiffCache::fill(&mut cache.redo, &current, project.redo_history());
    let m = ManifestOut {
        format: FORMAT_NAME,
        schema_version: CURRENT_SCHEMA_VERSION,
        generator: concat!("odori ", env!("CARGO_PKG_VERSION")),
        project: project.doc(),
        undo: &cache.undo,
        redo: &cache.redo,
        blobs,
    };
    serde_json::to_vec(&m).unwrap_or_default()
}

/// [`manifest_json`] with every change computed afresh (what the cache must equal).
#[doc(hidden)]
pub fn manifest_json_uncached(project: &Project) -> Vec<u8> {
    let blobs = project.referenced_blobs().into_iter().filter_map(|h| project.blobs().get(&h).map(|b| (h, b.len()))).collect();
    let some = |v: Vec<serde_json::Value>| v.into_iter().map(Some).collect::<Vec<_>>();
    let (undo, redo) = (some(diff_chain(project.doc(), project.undo_history())), some(diff_chain(project.doc(), project.redo_history())));
    let m = ManifestOut {
        format: FORMAT_NAME,
        schema_version: CURRENT_SCHEMA_VERSION,
        generator: concat!("odori ", env!("CARGO_PKG_VERSION")),
        project: project.doc(),
        undo: &undo,
        redo: &redo,
        blobs,
    };
    serde_json::to_vec(&m).unwrap_or_default()
}

/// Writes the project as an `.odori` file: the manifest and every blob the document or its
/// history refers to.
pub fn save(project: &Project) -> Result<Vec<u8>, FileError> {
    let werr = |e: &dyn std::fmt::Display| FileError::Write { message: e.to_string() };
    let mut zip = ZipWriter::new(Cursor::new(Vec::new()));
    // Level 1: mocap text shrinks about as much as at higher levels, several times faster.
    let opts = SimpleFileOptions::default().compression_method(CompressionMethod::Deflated).compression_level(Some(1));
    zip.start_file(MANIFEST, opts).map_err(|e| werr(&e))?;
    zip.write_all(&manifest_json(project)).map_err(|e| werr(&e))?;
    for hash in project.referenced_blobs() {
        if let Some(bytes) = project.blobs().get(&hash) {
            zip.start_file(format!("{BLOB_DIR}{hash}"), opts).map_err(|e| werr(&e))?;
            zip.write_all(bytes).map_err(|e| werr(&e))?;
        }
    }
    Ok(zip.finish().map_err(|e| werr(&e))?.into_inner())
}

/// Reads an `.odori` file. See the module doc for what is checked.
pub fn open(bytes: &[u8]) -> Result<Opened, FileError> {
    if bytes.is_empty() {
        return Err(FileError::Empty);
    }
    if !bytes.starts_with(b"PK\x03\x04") {
        let start: String = String::from_utf8_lossy(&bytes[..bytes.len().min(8)]).chars().map(|c| if c.is_control() { '·' } else { c }).collect();
        return Err(FileError::NotOdori { start });
    }
    // A zip ends with its central directory: a file cut short has lost it.
    let tail = &bytes[bytes.len().saturating_sub(65_557)..];
    if !tail.windows(4).any(|w| w == b"PK\x05\x06") {
        return Err(FileError::Truncated { size_bytes: bytes.len(), message: "the archive's central directory".into() });
    }
    let mut zip = ZipArchive::new(Cursor::new(bytes)).map_err(|e| zip_error(bytes.len(), "the archive", e))?;
    let mut manifest = None;
    let mut blobs: BTreeMap<BlobHash, Arc<[u8]>> = BTreeMap::new();
    for i in 0..zip.len() {
        let mut entry = zip.by_index(i).map_err(|e| zip_error(bytes.len(), &format!("entry {i}"), e))?;
        let name = entry.name().to_string();
        // The size is the archive's claim: only a hint, capped so a lying header cannot reserve gigabytes.
        let mut data = Vec::with_capacity(entry.size().min(1 << 26) as usize);
        entry.read_to_end(&mut data).map_err(|e| read_error(bytes.len(), &name, e))?;
        if name == MANIFEST {
            manifest = Some(data);
        } else if let Some(h) = name.strip_prefix(BLOB_DIR) {
            let Some(hash) = BlobHash::parse(h) else { continue };
            let actual = BlobHash::of(&data);
            if actual != hash {
                return Err(FileError::BlobMismatch { name, actual: actual.to_string() });
            }
            blobs.insert(hash, Arc::from(data));
        }
    }
    let manifest = manifest.ok_or(FileError::NoManifest)?;
    // Every blob was checked against its name as it was read.
    read_manifest(&manifest, |h| blobs.get(h).cloned(), false)
}

fn zip_error(size_bytes: usize, what: &str, e: zip::result::ZipError) -> FileError {
    match e {
        zip::result::ZipError::Io(io) => read_error(size_bytes, what, io),
        other => FileError::Corrupt { entry: what.to_string(), message: other.to_string() },
    }
}

fn read_error(size_bytes: usize, what: &str, e: std::io::Error) -> FileError {
    if e.kind() == std::io::ErrorKind::UnexpectedEof {
        FileError::Truncated { size_bytes, message: format!("the rest of {what}") }
    } else {
        FileError::Corrupt { entry: what.to_string(), message: e.to_string() }
    }
}

/// The steps from each schema version to the next: `MIGRATIONS[v - OLDEST_SCHEMA_VERSION]`
/// rewrites a version-`v` manifest (as JSON) into version `v + 1` (a renamed field, a new
/// field's default...).
const MIGRATIONS: &[fn(&mut serde_json::Value)] = &[history_as_changes, dance_take, no_cameras, no_repeat_marks, no_face_tracks, one_track_list];

/// 6 → 7: camera motions and face tracks, two lists of the same fields (`cameras`, `faces`),
/// become one list of MMD tracks with a kind (`mmdTracks`: the cameras, then the faces, each in
/// its order, so every camera and face track keeps its index), in the document and in every
/// state of its history (rebuilt from the changes, rewritten, and written as changes again). The
/// two other things schema 7 keeps — a model's textures and why a bar is built-in — were not
/// kept before, and their absence reads as none. A history that does not rebuild is left for
/// the reader to refuse.
fn one_track_list(m: &mut serde_json::Value) {
    fn rewrite(doc: &mut serde_json::Value) {
        let Some(project) = doc.as_object_mut() else { return };
        let mut tracks = Vec::new();
        for (field, kind) in [("cameras", "camera"), ("faces", "face")] {
            if let Some(serde_json::Value::Array(list)) = project.remove(field) {
                for mut t in list {
                    if let Some(t) = t.as_object_mut() {
                        t.insert("kind".into(), kind.into());
                    }
                    tracks.push(t);
                }
            }
        }
        if !tracks.is_empty() {
            project.insert("mmdTracks".into(), serde_json::Value::Array(tracks));
        }
    }
    rewrite_every_state(m, rewrite);
}

/// Applies `rewrite` to the manifest's document and to every state of its history (schema 2's
/// changes: each state rebuilt from the one after it, rewritten, and its change from the
/// rewritten state after it written again). Leaves the history as it was when it does not
/// rebuild (the reader then refuses it with the reason).
fn rewrite_every_state(m: &mut serde_json::Value, rewrite: fn(&mut serde_json::Value)) {
    let Some(current) = m.get("project").cloned() else { return };
    let mut stacks = Vec::new();
    for stack in ["undo", "redo"] {
        let changes = match m.get(stack) {
            Some(serde_json::Value::Array(c)) => c.clone(),
            _ => Vec::new(),
        };
        // The states, last first (each from the one after it).
        let mut states = Vec::with_capacity(changes.len());
        let mut next = current.clone();
        for change in changes.iter().rev() {
            match json_patch(&next, change) {
                Ok(state) => {
                    states.push(state.clone());
                    next = state;
                }
                Err(_) => return,
            }
        }
        stacks.push((stack, states));
    }
    let mut project = current;
    rewrite(&mut project);
    for (stack, mut states) in stacks {
        let mut next = project.clone();
        let mut out = Vec::with_capacity(states.len());
        for state in states.iter_mut() {
            rewrite(state);
            out.push(json_diff(&next, state));
            next = state.clone();
        }
        out.reverse();
        if m.get(stack).is_some() {
            m[stack] = serde_json::Value::Array(out);
        }
    }
    m["project"] = project;
}

/// 5 → 6: the project keeps the face (lip-sync) tracks imported (lip-sync VMDs, issue 28); a
/// project saved before has none. (The step writes the empty list the reader would assume
/// anyway: the version is bumped so that a build that does not know face tracks refuses a file
/// holding them instead of dropping them unseen.)
fn no_face_tracks(m: &mut serde_json::Value) {
    if let Some(serde_json::Value::Object(project)) = m.get_mut("project") {
        project.entry("faces").or_insert(serde_json::Value::Array(Vec::new()));
    }
}

/// 4 → 5: the dance keeps the repeats the person marked or removed on the song strip (issue
/// 26); a dance saved before has none. (The step writes the empty list the reader would assume
/// anyway: the version is bumped so that a build that does not know marks refuses a file
/// holding them instead of dropping them unseen, and Generate's repeats stay as the person set
/// them.)
fn no_repeat_marks(m: &mut serde_json::Value) {
    if let Some(serde_json::Value::Object(dance)) = m.get_mut("project").and_then(|p| p.get_mut("dance")) {
        dance.entry("repeats").or_insert(serde_json::Value::Array(Vec::new()));
    }
}

/// 3 → 4: the project keeps the camera motions imported (camera VMDs, issue 28); a project
/// saved before has none. (The step writes the empty list the reader would assume anyway: the
/// version is bumped so that a build that does not know cameras refuses a file holding them
/// instead of dropping them unseen.)
fn no_cameras(m: &mut serde_json::Value) {
    if let Some(serde_json::Value::Object(project)) = m.get_mut("project") {
        project.entry("cameras").or_insert(serde_json::Value::Array(Vec::new()));
    }
}

/// 2 → 3: the dance keeps the take of Generate its bars come from (issue 26); a dance saved
/// before takes existed is take 0 (what Generate made then).
fn dance_take(m: &mut serde_json::Value) {
    if let Some(serde_json::Value::Object(dance)) = m.get_mut("project").and_then(|p| p.get_mut("dance")) {
        dance.entry("take").or_insert(0.into());
    }
}

/// 1 → 2: the undo and redo stacks, whole documents in schema 1, as changes (see the module
/// doc). A stack that is not a list of objects is left for the reader to refuse.
fn history_as_changes(m: &mut serde_json::Value) {
    let Some(current) = m.get("project").cloned() else { return };
    for stack in ["undo", "redo"] {
        let Some(serde_json::Value::Array(states)) = m.get(stack).cloned() else { continue };
        let mut next = current.clone();
        let mut out = vec![serde_json::Value::Null; states.len()];
        for (i, state) in states.iter().enumerate().rev() {
            out[i] = json_diff(&next, state);
            next = state.clone();
        }
        m[stack] = serde_json::Value::Array(out);
    }
}

/// A stack of states (oldest first) as changes, each from the state after it (the last from
/// `current`).
fn diff_chain(current: &ProjectDoc, states: &[ProjectDoc]) -> Vec<serde_json::Value> {
    let mut next = serde_json::to_value(current).unwrap_or_default();
    let mut out = vec![serde_json::Value::Null; states.len()];
    for (i, state) in states.iter().enumerate().rev() {
        let v = serde_json::to_value(state).unwrap_or_default();
        out[i] = json_diff(&next, &v);
        next = v;
    }
    out
}

/// The states of [`diff_chain`] back from their changes.
fn undiff_chain(current: &ProjectDoc, changes: &[serde_json::Value]) -> Result<Vec<ProjectDoc>, FileError> {
    let bad = |message: String| FileError::BadProject { message };
    let mut next = serde_json::to_value(current).map_err(|e| bad(e.to_string()))?;
    let mut out = Vec::with_capacity(changes.len());
    for (i, change) in changes.iter().enumerate().rev() {
        next = json_patch(&next, change).map_err(|m| bad(format!("history step {}: {m}", i + 1)))?;
        out.push(serde_json::from_value(next.clone()).map_err(|e| bad(format!("history step {}: {e}", i + 1)))?);
    }
    out.reverse();
    Ok(out)
}

/// The change that turns `base` into `target`, as JSON: `{}` (no change), `{"=": value}`
/// (replaced), `{"o": {field: change}, "d": [fields removed]}` (an object's changed fields) or
/// `{"a": length, "i": {"index": change}}` (an array's changed elements, by position).
pub fn json_diff(base: &serde_json::Value, target: &serde_json::Value) -> serde_json::Value {
    use serde_json::{json, Map, Value};
    if base == target {
        return json!({});
    }
    match (base, target) {
        (Value::Object(b), Value::Object(t)) => {
            let mut o = Map::new();
            for (k, tv) in t {
                match b.get(k) {
                    Some(bv) if bv == tv => {}
                    Some(bv) => {
                        o.insert(k.clone(), json_diff(bv, tv));
                    }
                    None => {
                        o.insert(k.clone(), json!({ "=": tv }));
                    }
                }
            }
            let d: Vec<&String> = b.keys().filter(|k| !t.contains_key(*k)).collect();
            if d.is_empty() {
                json!({ "o": o })
            } else {
                json!({ "o": o, "d": d })
            }
        }
        (Value::Array(b), Value::Array(t)) => {
            let mut i = Map::new();
            for (n, tv) in t.iter().enumerate() {
                match b.get(n) {
                    Some(bv) if bv == tv => {}
                    Some(bv) => {
                        i.insert(n.to_string(), json_diff(bv, tv));
                    }
                    None => {
                        i.insert(n.to_string(), json!({ "=": tv }));
                    }
                }
            }
            json!({ "a": t.len(), "i": i })
        }
        _ => json!({ "=": target }),
    }
}

/// Applies a [`json_diff`] change to `base`; a change that does not fit it is refused with why.
pub fn json_patch(base: &serde_json::Value, change: &serde_json::Value) -> Result<serde_json::Value, String> {
    use serde_json::Value;
    let Value::Object(c) = change else { return Err(format!("a change must be an object, not {change}")) };
    if let Some(v) = c.get("=") {
        return Ok(v.clone());
    }
    if let Some(fields) = c.get("o") {
        let (Value::Object(b), Value::Object(fields)) = (base, fields) else { return Err("an object change on something that is not an object".into()) };
        let mut out = b.clone();
        if let Some(Value::Array(gone)) = c.get("d") {
            for k in gone {
                if let Some(k) = k.as_str() {
                    out.remove(k);
                }
            }
        }
        for (k, fc) in fields {
            let v = json_patch(b.get(k).unwrap_or(&Value::Null), fc)?;
            out.insert(k.clone(), v);
        }
        return Ok(Value::Object(out));
    }
    if let Some(len) = c.get("a") {
        let Value::Array(b) = base else { return Err("an array change on something that is not an array".into()) };
        let len = len.as_u64().ok_or("an array length that is not a whole number")? as usize;
        if len > b.len() + c.get("i").and_then(|i| i.as_object()).map_or(0, |i| i.len()) {
            return Err(format!("an array of {len} elements from {} and fewer changes", b.len()));
        }
        let mut out: Vec<Value> = (0..len).map(|n| b.get(n).cloned().unwrap_or(Value::Null)).collect();
        if let Some(Value::Object(items)) = c.get("i") {
            for (k, ic) in items {
                let n: usize = k.parse().map_err(|_| format!("array index {k:?}"))?;
                let slot = out.get_mut(n).ok_or_else(|| format!("array index {n} past the length {len}"))?;
                *slot = json_patch(slot, ic)?;
            }
        }
        return Ok(Value::Array(out));
    }
    if c.is_empty() {
        return Ok(base.clone());
    }
    Err("a change that is none of {}, =, o, a".into())
}

/// Brings a manifest of schema `from` up to [`CURRENT_SCHEMA_VERSION`], one step at a time.
pub fn migrate(value: &mut serde_json::Value, from: u32) -> Result<(), FileError> {
    for version in from..CURRENT_SCHEMA_VERSION {
        let step = version.checked_sub(OLDEST_SCHEMA_VERSION).and_then(|i| MIGRATIONS.get(i as usize));
        let Some(step) = step else {
            return Err(FileError::TooOld { found: version, oldest: OLDEST_SCHEMA_VERSION });
        };
        step(value);
    }
    if let Some(obj) = value.as_object_mut() {
        obj.insert("schemaVersion".into(), CURRENT_SCHEMA_VERSION.into());
    }
    Ok(())
}

/// A project from its manifest and a way to get each blob (from a zip, or from the
/// browser's store). Blobs `blob` cannot give are reported in [`Opened::missing`].
pub fn from_manifest(manifest: &[u8], blob: impl Fn(&BlobHash) -> Option<Arc<[u8]>>) -> Result<Opened, FileError> {
    read_manifest(manifest, blob, true)
}

/// [`from_manifest`]; `verify: false` when every blob was checked against its name already.
fn read_manifest(manifest: &[u8], blob: impl Fn(&BlobHash) -> Option<Arc<[u8]>>, verify: bool) -> Result<Opened, FileError> {
    let bad = |e: serde_json::Error| FileError::BadManifest { line: e.line(), column: e.column(), message: e.to_string() };
    let mut value: serde_json::Value = serde_json::from_slice(manifest).map_err(bad)?;
    let format = value.get("format").and_then(|f| f.as_str()).unwrap_or("").to_string();
    if format != FORMAT_NAME {
        return Err(FileError::WrongFormat { format });
    }
    let Some(found) = value.get("schemaVersion").and_then(|v| v.as_u64()) else {
        return Err(FileError::BadManifest { line: 1, column: 1, message: "schemaVersion is missing or not a whole number".into() });
    };
    let found = u32::try_from(found).unwrap_or(u32::MAX);
    if found > CURRENT_SCHEMA_VERSION {
        return Err(FileError::NewerVersion { found, supported: CURRENT_SCHEMA_VERSION });
    }
    if found < OLDEST_SCHEMA_VERSION {
        return Err(FileError::TooOld { found, oldest: OLDEST_SCHEMA_VERSION });
    }
    let migrated_from = (found < CURRENT_SCHEMA_VERSION).then_some(found);
    migrate(&mut value, found)?;
    let m: Manifest = serde_json::from_value(value).map_err(|e| FileError::BadProject { message: e.to_string() })?;
    let undo = undiff_chain(&m.project, &m.undo)?;
    let redo = undiff_chain(&m.project, &m.redo)?;
    let mut store = BlobStore::default();
    let mut missing = Vec::new();
    for d in std::iter::once(&m.project).chain(&undo).chain(&redo) {
        for (hash, what) in named_blobs(d) {
            if store.contains(&hash) || missing.iter().any(|x: &MissingBlob| x.hash == hash) {
                continue;
            }
            match blob(&hash) {
                Some(bytes) if !verify || BlobHash::of(&bytes) == hash => store.insert_checked(hash, bytes),
                Some(bytes) => return Err(FileError::BlobMismatch { name: hash.to_string(), actual: BlobHash::of(&bytes).to_string() }),
                None => missing.push(MissingBlob { hash, what }),
            }
        }
    }
    let project = Project::from_parts(m.project, undo, redo, store, missing.clone());
    Ok(Opened { project, missing, migrated_from })
}

/// Every blob of a document with what it is, for messages.
fn named_blobs(d: &ProjectDoc) -> Vec<(BlobHash, String)> {
    let mut out: Vec<(BlobHash, String)> = d.sources.iter().map(|s| (s.blob.clone(), format!("motion file {}", s.file_name))).collect();
    for s in &d.sources {
        if let Some(m) = &s.model {
            out.push((m.blob.clone(), format!("MMD model {} of {}", m.file_name, s.file_name)));
            for t in &m.textures {
                out.push((t.blob.clone(), format!("texture {} of MMD model {}", t.name, m.file_name)));
            }
        }
    }
    if let Some(song) = &d.song {
        if let Some(a) = &song.audio {
            out.push((a.clone(), format!("song audio {}", song.file_name)));
        }
        out.push((song.envelope.clone(), format!("loudness envelope of {}", song.file_name)));
    }
    for w in &d.worn {
        if let super::WornMotion::Motion { name, bvh } = &w.motion {
            out.push((bvh.clone(), format!("put-on motion {name}")));
        }
    }
    for t in &d.mmd_tracks {
        out.push((t.blob.clone(), format!("{} {}", t.kind.words(), t.file_name)));
    }
    out
}

#[cfg(test)]
mod migration_tests {
    use super::*;
    use serde_json::json;

    /// A schema-6 manifest: the current document has a camera and a face track; its history
    /// goes back through the face track's import (undo 1) and the camera's (undo 0), and a redo
    /// state adds a second camera.
    fn v6() -> serde_json::Value {
        let cam = json!({ "fileName": "cam.vmd", "blob": "a".repeat(64) });
        let cam2 = json!({ "fileName": "cam2.vmd", "blob": "c".repeat(64), "songOffsetFrames": 5 });
        let face = json!({ "fileName": "lip.vmd", "blob": "b".repeat(64), "songOffsetFrames": 10 });
        let state = |cameras: Vec<serde_json::Value>, faces: Vec<serde_json::Value>| json!({ "name": "p", "cameras": cameras, "faces": faces });
        let now = state(vec![cam.clone()], vec![face.clone()]);
        let before_face = state(vec![cam.clone()], vec![]);
        let before_cam = state(vec![], vec![]);
        let redo = state(vec![cam.clone(), cam2], vec![face]);
        json!({
            "format": FORMAT_NAME,
            "schemaVersion": 6,
            "project": now,
            "undo": [json_diff(&before_face, &before_cam), json_diff(&now, &before_face)],
            "redo": [json_diff(&now, &redo)],
        })
    }

    /// Every state of a manifest's stacks, rebuilt from its changes (oldest undo first; redo as stacked).
    fn states(m: &serde_json::Value, stack: &str) -> Vec<serde_json::Value> {
        let mut next = m["project"].clone();
        let mut out = Vec::new();
        for c in m[stack].as_array().expect("a stack").iter().rev() {
            next = json_patch(&next, c).expect("patches");
            out.push(next.clone());
        }
        out.reverse();
        out
    }

    #[test]
    fn six_to_seven_makes_one_track_list_in_the_document_and_every_history_state() {
        let mut m = v6();
        one_track_list(&mut m);
        let kinds = |v: &serde_json::Value| -> Vec<(String, String)> {
            assert!(v.get("cameras").is_none() && v.get("faces").is_none(), "the two lists are gone: {v}");
            v.get("mmdTracks").and_then(|t| t.as_array()).map_or(Vec::new(), |t| t.iter().map(|t| (t["kind"].as_str().unwrap_or("").to_string(), t["fileName"].as_str().unwrap_or("").to_string())).collect())
        };
        let pair = |k: &str, f: &str| (k.to_string(), f.to_string());
        assert_eq!(kinds(&m["project"]), vec![pair("camera", "cam.vmd"), pair("face", "lip.vmd")]);
        let undo = states(&m, "undo");
        assert_eq!(undo.iter().map(kinds).collect::<Vec<_>>(), vec![vec![], vec![pair("camera", "cam.vmd")]]);
        let redo = states(&m, "redo");
        assert_eq!(redo.iter().map(kinds).collect::<Vec<_>>(), vec![vec![pair("camera", "cam.vmd"), pair("camera", "cam2.vmd"), pair("face", "lip.vmd")]]);
        // Fields other than the kind are kept as they were.
        assert_eq!(redo[0]["mmdTracks"][1]["songOffsetFrames"], 5);
        assert_eq!(m["project"]["mmdTracks"][1]["songOffsetFrames"], 10);
        // The migrated manifest reads as a project whose history undoes and redoes the tracks.
        let opened = read_manifest(&serde_json::to_vec(&v6_with_rest()).expect("json"), |_| None, true).expect("opens");
        let mut p = opened.project;
        assert_eq!(opened.migrated_from, Some(6));
        assert_eq!((p.doc().tracks(super::super::TrackKind::Camera).count(), p.doc().tracks(super::super::TrackKind::Face).count()), (1, 1));
        assert!(p.undo() && p.undo());
        assert!(p.doc().mmd_tracks.is_empty());
        assert!(p.redo() && p.redo() && p.redo());
        assert_eq!(p.doc().tracks(super::super::TrackKind::Camera).count(), 2);
        // Missing blobs are named by their kind.
        let what: Vec<&str> = opened.missing.iter().map(|m| m.what.as_str()).collect();
        assert!(what.contains(&"camera motion cam.vmd") && what.contains(&"face track lip.vmd"), "{what:?}");
    }

    /// [`v6`] with the rest of a document, so it reads as a project.
    fn v6_with_rest() -> serde_json::Value {
        let mut m = v6();
        let rest = serde_json::to_value(ProjectDoc::default()).expect("json");
        let fill = |v: &mut serde_json::Value| {
            for (k, d) in rest.as_object().expect("an object") {
                if v.get(k).is_none() {
                    v[k] = d.clone();
                }
            }
        };
        fill(&mut m["project"]);
        // The history's changes are from the document: they stay valid with the fields added.
        m["generator"] = "test".into();
        m["blobs"] = json!({});
        m
    }

    #[test]
    fn a_history_that_does_not_rebuild_is_left_for_the_reader() {
        let mut m = v6();
        m["undo"] = json!([{ "a": 3 }]);
        let before = m["undo"].clone();
        one_track_list(&mut m);
        assert_eq!(m["undo"], before);
    }
}
