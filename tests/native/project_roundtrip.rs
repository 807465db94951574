//! The project (spec §K) on real data: random edit sequences over a real song, a real BVH and
//! a real GLB (property test: project → `.odori` bytes → project is identical, saves to the
//! same bytes, renders the same dance — joint positions equal — and its undo history still
//! works), and every way an `.odori` file can be bad, each with its typed error and the caller's
//! project untouched.

use std::io::{Cursor, Read, Write};
use std::sync::OnceLock;

use odori_core::choreo::RenderOptions;
use odori_core::music::{AnalysisOptions, GridCorrection, RmsEnvelope};
use odori_core::project::{self, BarKind, ClipRef, FileError, MoveKey, Project, ProjectError};
use odori_core::{Clip, ImportOptions};
use odori_tests::read;

#[path = "music_audio.rs"]
mod music_audio;

const SONG: &str = "music/Kevin_MacLeod_-_Vibe_Ace.hq.ogg";
const BVH: &str = "mocap/cmu-salsa/salsa_10.bvh";
const GLB: &str = "gltf/RobotExpressive.glb";

/// The song's bytes as given and the envelope the host would compute (decoded once).
fn song() -> &'static (Vec<u8>, RmsEnvelope) {
    static SONG_DATA: OnceLock<(Vec<u8>, RmsEnvelope)> = OnceLock::new();
    SONG_DATA.get_or_init(|| {
        let audio = music_audio::decode_data(SONG);
        (read(SONG), audio.envelope().unwrap_or_else(|e| panic!("{SONG}: {e}")))
    })
}

fn bvh() -> &'static Vec<u8> {
    static B: OnceLock<Vec<u8>> = OnceLock::new();
    B.get_or_init(|| read(BVH))
}

fn glb() -> &'static Vec<u8> {
    static B: OnceLock<Vec<u8>> = OnceLock::new();
    B.get_or_init(|| read(GLB))
}

/// xorshift64*: a small deterministic generator, so a failing seed can be replayed.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_F491_4F6C_DD1D)
    }
    fn below(&mut self, n: usize) -> usize {
        (self.next() % n.max(1) as u64) as usize
    }
    fn unit(&mut self) -> f32 {
        (self.next() >> 40) as f32 / (1u64 << 24) as f32
    }
}

/// Joint positions of the rendered dance at five times across it.
fn dance_poses(p: &mut Project) -> Vec<Vec<glam::Vec3>> {
    let clip: Clip = p.render_dance(&RenderOptions::default()).expect("render");
    let n = clip.frame_count();
    (0..5).map(|k| clip.world_positions((n.saturating_sub(1)) * k / 4)).collect()
}

fn robot_clip(p: &Project) -> Option<ClipRef> {
    p.doc().sources.iter().find(|s| s.file_name.ends_with(".glb")).map(|s| ClipRef { source: s.id, clip: 0 })
}

/// Joint positions of every put-on clip at three frames.
fn worn_poses(p: &mut Project) -> Vec<Vec<Vec<glam::Vec3>>> {
    (0..p.doc().worn.len())
        .map(|i| {
            let (clip, _) = p.worn_clip(i).unwrap_or_else(|e| panic!("put-on clip {i} does not rebuild: {e}"));
            let n = clip.frame_count();
            (0..3).map(|k| clip.world_positions(n.saturating_sub(1) * k / 2)).collect()
        })
        .collect()
}

fn salsa_clip(p: &Project) -> Option<ClipRef> {
    p.doc().sources.iter().find(|s| s.file_name.ends_with(".bvh")).map(|s| ClipRef { source: s.id, clip: 0 })
}

/// One random edit; on error the document must be unchanged.
fn random_edit(p: &mut Project, rng: &mut Rng, log: &mut Vec<String>) {
    let bars = p.doc().dance.bars.len();
    assert!(bars > 0, "the song's bars are always there");
    let before = p.doc().clone();
    let bar = rng.below(bars.min(12));
    let op = rng.below(20);
    let result: Result<(), ProjectError> = match op {
        0 if salsa_clip(p).is_none() => p.add_source("salsa_10.bvh", bvh(), ImportOptions { fps_override: Some(60.0), ..Default::default() }).map(|_| ()),
        1 if !p.doc().sources.iter().any(|s| s.file_name.ends_with(".glb")) => p.add_source("RobotExpressive.glb", glb(), ImportOptions::default()).map(|_| ()),
        0..=2 => p.candidates(bar).map(|_| ()),
        3 => {
            let round = p.doc().dance.bars[bar].search.as_ref().map(|s| s.round.clone()).unwrap_or_default();
            let liked: Vec<MoveKey> = round.into_iter().filter(|_| rng.below(2) == 0).collect();
            p.search(bar, &liked).map(|_| ())
        }
        4 => {
            let round = p.doc().dance.bars[bar].search.as_ref().map(|s| s.round.clone()).unwrap_or_default();
            let key = if !round.is_empty() && rng.below(2) == 0 {
                round[rng.below(round.len())].clone()
            } else {
                let lib_len = p.derived().library().len();
                let i = rng.below(lib_len);
                p.derived().key(i).cloned().expect("every segment has a key")
            };
            p.set(bar, &key)
        }
        5 => p.unpin(bar),
        6 => p.clear(bar),
        7 => p.generate().map(|_| ()),
        8 => p.set_rho(rng.unit()),
        9 => p.set_music_weight(rng.unit() * 5.0),
        10 => {
            let c = match rng.below(3) {
                0 => GridCorrection { nudge_secs: Some((rng.unit() - 0.5) * 0.1), ..Default::default() },
                1 => GridCorrection { bpm: Some(100.0 + rng.unit() * 40.0), ..Default::default() },
                _ => GridCorrection { first_downbeat_secs: Some(rng.unit() * 4.0), ..Default::default() },
            };
            p.correct_grid(c)
        }
        11 => match salsa_clip(p) {
            Some(c) => p.set_tags(c, vec!["salsa".into(), format!("tag{}", rng.below(9))]),
            None => Ok(()),
        },
        12 => {
            p.set_texts(vec![format!("Taro runs, then kicks the ball {}.", rng.below(100)), "歩きながら右手を振る".into()]);
            Ok(())
        }
        13 => {
            p.undo();
            Ok(())
        }
        14 => {
            p.redo();
            Ok(())
        }
        15 => match salsa_clip(p) {
            Some(c) => p.set_clip_tempo(c, if rng.below(3) == 0 { None } else { Some(90.0 + 10.0 * rng.below(5) as f32) }).map(|_| ()),
            None => Ok(()),
        },
        16 => {
            let c = salsa_clip(p);
            p.set_character(c)
        }
        // Stick figures chosen over any body, now and then.
        18 if rng.below(3) == 0 => {
            p.set_stick_figures();
            Ok(())
        }
        17 => match (robot_clip(p), salsa_clip(p)) {
            // The character plays a clip of the project, or a move made in the page.
            (Some(robot), Some(salsa)) if rng.below(2) == 0 => p.put_on(robot, Some(salsa), None).map(|_| ()),
            (Some(robot), _) => {
                let seg = rng.below(p.segment_library().len());
                let made = odori_core::choreo::segment_clip(p.segment_library(), seg, 1.0, 30.0).expect("a segment of the library");
                let file = odori_core::export::bvh::bvh(&made).expect("a built-in move writes as BVH");
                p.put_on(robot, None, Some((&format!("move {seg}"), &file))).map(|_| ())
            }
            _ => Ok(()),
        },
        18 => p.set_character(robot_clip(p)),
        _ => match p.doc().worn.len() {
            0 => Ok(()),
            n => p.remove_worn(rng.below(n)),
        },
    };
    match &result {
        Ok(()) => log.push(format!("op {op} bar {bar}: ok")),
        Err(e) => {
            log.push(format!("op {op} bar {bar}: refused ({e})"));
            assert_eq!(p.doc(), &before, "a refused edit ({e}) changed the document");
        }
    }
}

#[test]
fn random_edit_sequences_round_trip_identically() {
    let seeds: u64 = std::env::var("PROJECT_SEEDS").ok().and_then(|s| s.parse().ok()).unwrap_or(6);
    let ops: usize = std::env::var("PROJECT_OPS").ok().and_then(|s| s.parse().ok()).unwrap_or(30);
    let (song_bytes, env) = song();
    let mut checked_recut = false;
    let mut worn_total = 0;
    for seed in 1..=seeds {
        let mut rng = Rng(0x9E37_79B9_7F4A_7C15 ^ seed);
        let mut p = Project::new();
        p.set_name(&format!("seed {seed}"));
        // As the app starts a project: its first song is not an undo step (undoing it would
        // leave no bars to edit).
        p.set_initial_song("Vibe_Ace.ogg", Some(song_bytes), env, AnalysisOptions::default()).expect("song");
        let mut log = Vec::new();
        for _ in 0..ops {
            random_edit(&mut p, &mut rng, &mut log);
            // The manifest autosave writes keeps the history's changes between writes: it
            // must be what computing every change afresh gives.
            assert!(project::file::manifest_json(&p) == project::file::manifest_json_uncached(&p), "seed {seed}: the cached history changes differ from fresh ones\n{}", log.join("\n"));
        }
        let bytes = project::save(&p).expect("save");
        let opened = project::open(&bytes).unwrap_or_else(|e| panic!("seed {seed}: the saved file does not open: {e}\n{}", log.join("\n")));
        assert!(opened.missing.is_empty(), "seed {seed}: missing {:?}", opened.missing);
        let mut q = opened.project;
        assert!(q == p, "seed {seed}: the reopened project differs\n{}", log.join("\n"));
        assert_eq!(project::save(&q).expect("save again"), bytes, "seed {seed}: saving the reopened project gives other bytes");
        assert_eq!(dance_poses(&mut q), dance_poses(&mut p), "seed {seed}: the reopened dance moves differently\n{}", log.join("\n"));
        worn_total += p.doc().worn.len();
        assert_eq!(worn_poses(&mut q), worn_poses(&mut p), "seed {seed}: the reopened put-on clips move differently\n{}", log.join("\n"));
        assert_eq!(q.derived().grid().map(|g| g.clone().map(|g| g.beat_times_secs)), p.derived().grid().map(|g| g.clone().map(|g| g.beat_times_secs)), "seed {seed}: grid");
        // The history came along: undoing on both gives the same project and dance.
        let mut steps = 0;
        while p.can_undo() && steps < 3 {
            assert!(q.undo() && p.undo());
            steps += 1;
        }
        assert!(q == p, "seed {seed}: after {steps} undos");
        assert_eq!(dance_poses(&mut q), dance_poses(&mut p), "seed {seed}: dance after {steps} undos");
        checked_recut |= p.doc().sources.iter().chain(p.undo_history().iter().flat_map(|d| d.sources.iter())).any(|s| !s.cut_tempos_bpm.is_empty());
        let blobs = p.blobs().len();
        println!(
            "seed {seed}: {ops} edits ({} refused), {} bars ({} pinned), {} undo steps, {blobs} blobs, .odori {:.2} MB",
            log.iter().filter(|l| l.contains("refused")).count(),
            p.doc().dance.bars.len(),
            p.doc().dance.bars.iter().filter(|b| b.state == BarKind::Pinned).count(),
            p.undo_history().len(),
            bytes.len() as f64 / 1e6
        );
    }
    println!("a re-cut clip was among the sequences: {checked_recut}; put-on clips at the end: {worn_total}");
}

/// A pinned move of an earlier cut survives a re-cut, a save and an open.
#[test]
fn recut_keeps_pinned_moves_across_save() {
    let (song_bytes, env) = song();
    let mut p = Project::new();
    p.set_song("Vibe_Ace.ogg", Some(song_bytes), env, AnalysisOptions::default()).expect("song");
    let src = p.add_source("salsa_10.bvh", bvh(), ImportOptions { fps_override: Some(60.0), ..Default::default() }).expect("bvh");
    let clip = ClipRef { source: src.id, clip: 0 };
    let key = (0..p.derived().library().len())
        .filter_map(|i| p.derived().key(i).cloned())
        .find(|k| matches!(k, MoveKey::Cut { .. }))
        .expect("the salsa clip is cut into segments");
    p.set(2, &key).expect("pin");
    let before = dance_poses(&mut p);
    let first_cut = p.derived().clip(clip).and_then(|c| c.cut.clone()).expect("first cut").segments;
    let r = p.recut_clip(clip, Some(100.0)).expect("re-cut at 100");
    // What the engine says the re-cut meant: the new cut, bar 2 keeps its move, one move kept.
    assert_eq!((r.clip.tempo_bpm, r.clip.tempo_detected), (100.0, false));
    assert_eq!((r.pinned_bars, r.generated_bars, r.kept, r.removed), (vec![2], vec![], 1, first_cut - 1));
    assert_eq!(p.doc().dance.bars[2].r#move.as_ref(), Some(&key), "the pinned move keeps its key");
    assert_eq!(dance_poses(&mut p), before, "the pinned move plays as before after the re-cut");
    let mut q = project::open(&project::save(&p).unwrap()).unwrap().project;
    assert_eq!(dance_poses(&mut q), before, "and after save + open");
    let retired = q.derived().index_of(&key).map(|i| q.derived().library().segments()[i].retired);
    assert_eq!(retired, Some(true), "the earlier cut's move is kept, retired");
    assert!(q.undo(), "undo the re-cut");
    assert_eq!(q.doc().source(src.id).unwrap().cut_tempo_bpm(0), None);
}

// ---- malformed files: every case a typed error, the open project untouched ----

fn sample_project() -> Project {
    let (song_bytes, env) = song();
    let mut p = Project::new();
    p.set_song("Vibe_Ace.ogg", Some(song_bytes), env, AnalysisOptions::default()).expect("song");
    p.add_source("salsa_10.bvh", bvh(), ImportOptions { fps_override: Some(60.0), ..Default::default() }).expect("bvh");
    p.candidates(0).expect("candidates");
    p.generate().expect("generate");
    p
}

/// Rebuilds an archive entry by entry, letting `edit` change or drop each (name, bytes).
fn rewrite(file: &[u8], edit: impl Fn(&str, Vec<u8>) -> Option<Vec<u8>>) -> Vec<u8> {
    let mut zin = zip::ZipArchive::new(Cursor::new(file)).unwrap();
    let mut zout = zip::ZipWriter::new(Cursor::new(Vec::new()));
    for i in 0..zin.len() {
        let mut e = zin.by_index(i).unwrap();
        let name = e.name().to_string();
        let mut data = Vec::new();
        e.read_to_end(&mut data).unwrap();
        if let Some(data) = edit(&name, data) {
            zout.start_file(name, zip::write::SimpleFileOptions::default()).unwrap();
            zout.write_all(&data).unwrap();
        }
    }
    zout.finish().unwrap().into_inner()
}

fn manifest_edit(file: &[u8], f: impl Fn(&mut serde_json::Value)) -> Vec<u8> {
    rewrite(file, |name, data| {
        if name == "manifest.json" {
            let mut v: serde_json::Value = serde_json::from_slice(&data).unwrap();
            f(&mut v);
            Some(serde_json::to_vec(&v).unwrap())
        } else {
            Some(data)
        }
    })
}

#[test]
fn malformed_files_give_typed_errors_and_leave_the_project_alone() {
    let p = sample_project();
    let good = project::save(&p).unwrap();
    let cases: Vec<(&str, Vec<u8>, &str)> = vec![
        ("empty", Vec::new(), "empty"),
        ("a BVH renamed .odori", bvh()[..4096].to_vec(), "not-odori"),
        ("cut in half", good[..good.len() / 2].to_vec(), "truncated"),
        ("last 10 bytes lost", good[..good.len() - 10].to_vec(), "truncated"),
        ("newer schema", manifest_edit(&good, |v| v["schemaVersion"] = 99.into()), "newer-version"),
        ("schema 0", manifest_edit(&good, |v| v["schemaVersion"] = 0.into()), "too-old"),
        ("another format", manifest_edit(&good, |v| v["format"] = "something-else".into()), "not-odori"),
        ("no manifest", rewrite(&good, |n, d| (n != "manifest.json").then_some(d)), "not-odori"),
        ("manifest not JSON", rewrite(&good, |n, d| Some(if n == "manifest.json" { b"{\"format\": \"odori-project\", oops".to_vec() } else { d })), "corrupt"),
        ("manifest missing its project", manifest_edit(&good, |v| { v.as_object_mut().unwrap().remove("project"); }), "corrupt"),
        ("blob bytes changed", rewrite(&good, |n, mut d| { if n.starts_with("blobs/") { d[100] ^= 0x20; } Some(d) }), "corrupt"),
    ];
    // A flipped byte inside a compressed entry: the entry's CRC (or its deflate stream) fails.
    let mut flipped = good.clone();
    let mid = good.len() / 2;
    flipped[mid] ^= 0xFF;
    let mut cases = cases;
    cases.push(("a byte flipped", flipped, "corrupt"));
    let mut open_project = sample_project();
    let before = project::save(&open_project).unwrap();
    for (what, bytes, kind) in cases {
        let err: FileError = match project::open(&bytes) {
            Ok(_) => panic!("{what}: opened"),
            Err(e) => e,
        };
        assert_eq!(err.kind(), kind, "{what}: {err}");
        println!("{what}: {kind}: {err}");
        // The caller only replaces its project on success: it is untouched.
        assert_eq!(project::save(&open_project).unwrap(), before);
    }
    // The good file still opens.
    open_project = project::open(&good).unwrap().project;
    assert!(open_project == p);
}

#[test]
fn a_missing_blob_opens_the_rest_and_names_what_is_gone() {
    let p = sample_project();
    let bvh_hash = p.doc().sources[0].blob.to_string();
    let file = rewrite(&project::save(&p).unwrap(), |n, d| (n != format!("blobs/{bvh_hash}")).then_some(d));
    let opened = project::open(&file).expect("the rest opens");
    assert_eq!(opened.missing.len(), 1);
    assert_eq!(opened.missing[0].what, "motion file salsa_10.bvh");
    let mut q = opened.project;
    assert_eq!(q.doc(), p.doc(), "the document is whole");
    assert!(matches!(q.derived().grid(), Some(Ok(_))), "the song is there");
    let before = q.doc().clone();
    let err = q.generate().expect_err("the dance is not edited while a source is missing");
    assert!(matches!(err, ProjectError::Incomplete { .. }), "{err}");
    assert_eq!(q.doc(), &before);
    // It still renders (bars of the missing clip stand neutral) and saves (keeping its name).
    q.render_dance(&RenderOptions::default()).expect("render");
    let again = project::open(&project::save(&q).unwrap()).unwrap();
    assert_eq!(again.missing.len(), 1);
}

// ---- the project as the page's engine (the Project drives the page) ----

/// Looking at a bar's candidates is not an edit (no undo step) but the open search is kept
/// and saved; a new project's first song starts its history; Search is an edit; one undo
/// takes a whole Generate back.
#[test]
fn looking_is_not_an_edit_and_one_undo_takes_a_generate_back() {
    let (_, env) = song();
    let mut p = Project::new();
    p.set_initial_song("Demo song (built-in)", None, env, AnalysisOptions::default()).expect("song");
    assert!(!p.can_undo(), "a new project's first song is where its history starts");
    let shown = p.candidates(2).expect("candidates");
    assert_eq!(shown.len(), 6, "six candidates");
    assert!(!p.can_undo(), "opening a bar's search is not an undo step");
    assert!(p.doc().dance.bars[2].search.is_some(), "the open search is kept in the document");
    let q = project::open(&project::save(&p).expect("save")).expect("open").project;
    assert_eq!(q.doc().dance.bars[2].search.as_ref().map(|s| s.round.clone()), Some(shown.clone()), "the open round comes back from the file");
    let next = p.search(2, &shown[..1]).expect("search");
    assert_eq!(next.len(), 6);
    assert!(p.can_undo(), "Search (liking) is an edit");
    p.set(4, &next[0]).expect("set");
    let before = p.doc().dance.clone();
    let r = p.generate().expect("generate");
    assert!(r.filled > 1, "Generate filled {} bars", r.filled);
    assert!(p.doc().dance.bars.iter().all(|b| b.state != BarKind::Empty), "every bar filled");
    assert!(p.undo(), "undo");
    assert_eq!(p.doc().dance, before, "one undo takes the whole Generate back");
    assert!(p.redo());
    assert!(p.doc().dance.bars.iter().all(|b| b.state != BarKind::Empty), "redo brings it back");
}

/// Another take (issue 26): a different dance in at least half the bars, one undo step, kept
/// with its number in the file; the same take again is the same dance; a take out of range is
/// refused with the project untouched.
#[test]
fn another_take_differs_is_one_undo_step_and_is_kept_in_the_file() {
    let (_, env) = song();
    let mut p = Project::new();
    p.set_initial_song("Vibe_Ace.ogg", None, env, AnalysisOptions::default()).expect("song");
    p.generate().expect("generate");
    assert_eq!(p.take(), 0);
    let first = p.doc().dance.clone();
    p.generate_take(1).expect("take 1");
    assert_eq!(p.take(), 1);
    let second = p.doc().dance.clone();
    let differ = first.bars.iter().zip(&second.bars).filter(|(a, b)| a.r#move != b.r#move).count();
    assert!(2 * differ >= first.bars.len(), "take 1 differs from take 0 in {differ} of {} bars", first.bars.len());
    let reopened = project::open(&project::save(&p).expect("save")).expect("open").project;
    assert_eq!(reopened.doc().dance, second, "the take and its bars come back from the file");
    assert!(p.undo());
    assert_eq!(p.doc().dance, first, "one undo brings take 0 back");
    assert!(p.redo());
    assert_eq!(p.doc().dance, second);
    p.generate_take(1).expect("take 1 again");
    assert_eq!(p.doc().dance, second, "the same take is the same dance");
    let err = p.generate_take(16).expect_err("take 16 is out of range");
    assert!(err.to_string().contains("take"), "{err}");
    assert_eq!(p.doc().dance, second, "a refused take changes nothing");
}

/// The built-in moves made a slice at a time (as the page does, between frames) give the
/// same library — same segments, same keys — and the same dance as made at once.
#[test]
fn builtin_moves_made_in_slices_give_the_same_library_and_dance() {
    let (_, env) = song();
    let mut sliced = Project::new();
    let mut slices = 1;
    while sliced.load_builtin(37) < 1.0 {
        slices += 1;
    }
    assert!(slices >= 10, "558 moves in slices of 37: {slices} slices");
    let mut at_once = Project::new();
    for p in [&mut sliced, &mut at_once] {
        p.set_song("Vibe_Ace.ogg", None, env, AnalysisOptions::default()).expect("song");
        p.add_source("salsa_10.bvh", bvh(), ImportOptions { fps_override: Some(60.0), ..Default::default() }).expect("bvh");
        p.generate().expect("generate");
    }
    assert_eq!(sliced.doc(), at_once.doc(), "same dance by keys");
    let n = sliced.segment_library().len();
    assert_eq!(n, at_once.segment_library().len());
    for i in 0..n {
        assert_eq!(sliced.derived().key(i).cloned(), at_once.derived().key(i).cloned(), "key of segment {i}");
    }
    assert_eq!(dance_poses(&mut sliced), dance_poses(&mut at_once), "same joint positions");
}

/// A library copied from another (the project starts each rebuild from a copy of the built-in
/// library) never shares a revision with it once they differ: a join table built for one is
/// refused by the other.
#[test]
fn a_table_built_for_one_copy_is_refused_by_another_that_changed() {
    use odori_core::choreo::{SegmentLibrary, SegmentOptions};
    let im = odori_core::import::import_bytes("salsa_10.bvh", bvh(), &ImportOptions { fps_override: Some(60.0), ..Default::default() }).expect("import");
    let base = SegmentLibrary::builtin();
    let (mut x, mut y) = (base.clone(), base.clone());
    assert_eq!(x.len(), base.len());
    x.add_clip(&im.clips[0], &im.humanoid, &im.status, &SegmentOptions { tempo_bpm: Some(100.0), ..Default::default() }).expect("cut x");
    y.add_clip(&im.clips[0], &im.humanoid, &im.status, &SegmentOptions { tempo_bpm: Some(120.0), ..Default::default() }).expect("cut y");
    assert_ne!(x.revision(), y.revision(), "diverged copies have distinct revisions");
    let penalty = odori_core::choreo::FillWeights::default().repeat_penalty;
    let mut builder = x.table_builder(penalty);
    while !builder.step(4096).is_done() {}
    let table = builder.finish().expect("table");
    assert!(!y.install_table(table), "x's table refused by y");
    let mut builder = x.table_builder(penalty);
    while !builder.step(4096).is_done() {}
    assert!(x.install_table(builder.finish().expect("table")), "and taken by x");
}

/// The manifest a schema-1 build wrote for `p`: the history as whole documents.
fn manifest_v1(p: &Project) -> Vec<u8> {
    let current: serde_json::Value = serde_json::from_slice(&project::file::manifest_json(p)).expect("manifest");
    let mut v = current.clone();
    v["schemaVersion"] = 1.into();
    v["undo"] = serde_json::to_value(p.undo_history()).unwrap();
    v["redo"] = serde_json::to_value(p.redo_history()).unwrap();
    serde_json::to_vec(&v).unwrap()
}

/// The history kept as changes (schema 2): a long session's manifest — what autosave writes
/// after every edit — against the same history as whole documents (schema 1, the control, in
/// the same run); both read back to the same project, and a schema-1 manifest still opens
/// (migrated) to the same project with the same history.
#[test]
fn history_as_changes_is_smaller_and_reads_back_the_same() {
    let (song_bytes, env) = song();
    let mut printed = Vec::new();
    for seed in [11u64, 12, 13] {
        let mut rng = Rng(0x5DEE_CE66_D1CE_4E5B ^ seed);
        let mut p = Project::new();
        p.set_initial_song("Vibe_Ace.ogg", Some(song_bytes), env, AnalysisOptions::default()).expect("song");
        // About ten minutes of work: an edit every five seconds.
        let mut log = Vec::new();
        for _ in 0..120 {
            random_edit(&mut p, &mut rng, &mut log);
        }
        let v2 = project::file::manifest_json(&p);
        let v1 = manifest_v1(&p);
        let get = |h: &project::BlobHash| p.blobs().get(h).cloned();
        let from_v2 = project::file::from_manifest(&v2, get).expect("v2 manifest reads back");
        assert_eq!(from_v2.migrated_from, None);
        assert!(from_v2.project == p, "seed {seed}: v2 manifest → the same project, history included\n{}", log.join("\n"));
        let from_v1 = project::file::from_manifest(&v1, get).expect("v1 manifest reads back");
        assert_eq!(from_v1.migrated_from, Some(1));
        assert!(from_v1.project == p, "seed {seed}: v1 manifest (migrated) → the same project");
        assert!(v2.len() < v1.len(), "seed {seed}: changes ({} bytes) are not smaller than whole documents ({} bytes)", v2.len(), v1.len());
        printed.push(format!(
            "seed {seed}: 120 edits, {} undo + {} redo steps: manifest {:.1} KB as changes vs {:.1} KB as whole documents ({:.1}x smaller)",
            p.undo_history().len(),
            p.redo_history().len(),
            v2.len() as f64 / 1e3,
            v1.len() as f64 / 1e3,
            v1.len() as f64 / v2.len() as f64
        ));
    }
    for line in printed {
        println!("{line}");
    }
}

/// A change that does not fit its base is refused with a typed error, never a panic.
#[test]
fn a_history_change_that_does_not_fit_is_a_typed_error() {
    let p = sample_project();
    let mut m: serde_json::Value = serde_json::from_slice(&project::file::manifest_json(&p)).unwrap();
    assert!(m["undo"].as_array().is_some_and(|u| !u.is_empty()), "the sample has history");
    m["undo"][0] = serde_json::json!({ "a": 3 });
    let bytes = serde_json::to_vec(&m).unwrap();
    let err = project::file::from_manifest(&bytes, |h| p.blobs().get(h).cloned()).err().expect("refused");
    assert!(matches!(err, FileError::BadProject { .. }), "{err:?}");
    assert!(err.to_string().contains("history step"), "{err}");
}

/// The character chosen and clips put on it are edits of the project: kept in the file, rebuilt
/// on open (the same joint positions), taken back by undo, and gone with their source.
#[test]
fn the_character_and_put_on_clips_are_kept() {
    let mut p = sample_project();
    let glb = p.add_source("RobotExpressive.glb", glb(), ImportOptions::default()).expect("glb").id;
    let robot = ClipRef { source: glb, clip: 0 };
    let salsa = salsa_clip(&p).expect("the sample has a BVH");
    p.set_character(Some(robot)).expect("character");
    let from_clip = p.put_on(robot, Some(salsa), None).expect("put the salsa on the robot");
    let made = odori_core::choreo::segment_clip(p.segment_library(), 3, 2.0, 30.0).expect("segment");
    let file = odori_core::export::bvh::bvh(&made).expect("bvh");
    let from_motion = p.put_on(robot, None, Some(("a built-in move", &file))).expect("put a move on the robot");
    assert_eq!((from_clip, from_motion), (0, 1));
    // A motion file that does not read is refused, nothing changed.
    let before = p.doc().clone();
    assert!(matches!(p.put_on(robot, None, Some(("junk", b"not a bvh"))), Err(ProjectError::Import(_))));
    // A character that is not a skinned file is refused with the character's error.
    assert!(matches!(p.put_on(salsa, Some(salsa), None), Err(ProjectError::Character(_))));
    assert!(matches!(p.remove_worn(7), Err(ProjectError::NoSuchWorn { index: 7, count: 2 })));
    assert_eq!(p.doc(), &before);

    let bytes = project::save(&p).expect("save");
    let mut q = project::open(&bytes).expect("open").project;
    assert_eq!(q.doc().character, Some(robot));
    assert_eq!(q.doc().worn, p.doc().worn);
    let poses = worn_poses(&mut p);
    assert_eq!(worn_poses(&mut q), poses, "the put-on clips rebuild to the same motion");
    // The clip is on the character's rig, and moves.
    let (clip, ch) = q.worn_clip(0).expect("rebuilt");
    assert_eq!(clip.skeleton.joints.len(), ch.skeleton.joints.len());
    assert_ne!(poses[0][0], poses[0][2], "the put-on clip moves");

    // Undo takes the last put-on away; removing the GLB takes the character and both put-on clips.
    assert!(q.undo());
    assert_eq!(q.doc().worn.len(), 1);
    q.remove_source(glb).expect("remove the robot");
    assert!(q.doc().worn.is_empty() && q.doc().character.is_none());
    assert!(q.undo() && q.doc().worn.len() == 1 && q.doc().character == Some(robot));
}

/// What the figures are drawn on: a new project (and a file written before the choice) has no
/// choice, which the page shows as the built-in body; stick figures are a choice of their own,
/// kept in the file, undone like any edit, ended by choosing a character. A file that never
/// chose stick figures is written without the field (the bytes of older files stay).
#[test]
fn stick_figures_are_a_kept_choice_and_no_choice_is_the_builtin_body() {
    let mut p = sample_project();
    assert!(!p.doc().stick_figures && p.doc().character.is_none(), "a new project has no choice");
    let manifest = |p: &Project| String::from_utf8(project::file::manifest_json(p)).unwrap();
    assert!(!manifest(&p).contains("stickFigures"), "no choice: the field is not written");
    p.set_stick_figures();
    assert!(p.doc().stick_figures);
    assert!(manifest(&p).contains("\"stickFigures\":true"));
    let bytes = project::save(&p).expect("save");
    let mut q = project::open(&bytes).expect("open").project;
    assert!(q.doc().stick_figures && q.doc().character.is_none(), "kept in the file");
    // A character chosen ends stick figures; undo brings them back.
    let glb = q.add_source("RobotExpressive.glb", glb(), ImportOptions::default()).expect("glb").id;
    let robot = ClipRef { source: glb, clip: 0 };
    q.set_character(Some(robot)).expect("character");
    assert!(!q.doc().stick_figures && q.doc().character == Some(robot));
    assert!(q.undo() && q.doc().stick_figures && q.doc().character.is_none());
    // The built-in body chosen again (no character, no stick figures) is the new project's state.
    q.set_character(None).expect("built-in body");
    assert!(!q.doc().stick_figures && q.doc().character.is_none());
    assert!(q.undo() && q.doc().stick_figures, "one undo step each");
}

/// The project's cache of parsed files forgets a file once the document no longer names it
/// (its bytes stay while the history needs them: undo parses it again).
#[test]
fn the_parsed_file_cache_forgets_a_removed_file() {
    let mut p = sample_project();
    let glb = p.add_source("RobotExpressive.glb", glb(), ImportOptions::default()).expect("glb").id;
    let with_both = p.derived().parsed_files();
    assert_eq!(with_both, p.doc().sources.len(), "one parse per source");
    p.remove_source(glb).expect("remove");
    assert_eq!(p.derived().parsed_files(), with_both - 1, "the removed file's parse is forgotten");
    assert!(p.undo());
    assert_eq!(p.derived().parsed_files(), with_both, "undo brings the file back, parsed again");
    assert!(p.derived().clips().iter().any(|c| c.clip.source == glb), "its clips are back");
}

/// A group of edits (a share link applied bar by bar, then Generate) is one undo step.
#[test]
fn a_group_of_edits_is_one_undo_step() {
    let mut p = sample_project();
    let before = p.doc().clone();
    let steps = p.undo_history().len();
    let keys: Vec<MoveKey> = (0..3).map(|i| p.derived().key(i * 7).cloned().expect("key")).collect();
    p.begin_group();
    for (bar, k) in keys.iter().enumerate() {
        p.set(bar + 1, k).expect("pin");
    }
    p.generate().expect("generate");
    p.end_group();
    assert_eq!(p.undo_history().len(), steps + 1, "the group is one undo step");
    assert_eq!(p.doc().dance.bars.iter().filter(|b| b.state == BarKind::Pinned).count(), 3);
    let after = p.doc().clone();
    // Its changes in the manifest are what computing them afresh gives.
    assert!(project::file::manifest_json(&p) == project::file::manifest_json_uncached(&p));
    assert!(p.undo());
    assert_eq!(p.doc(), &before, "one undo takes the whole group back");
    assert!(p.redo());
    assert_eq!(p.doc(), &after);
    // After the group, edits are their own steps again.
    p.clear(1).expect("clear");
    assert_eq!(p.undo_history().len(), steps + 2);
}
