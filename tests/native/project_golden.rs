//! The golden `.odori` files of schema versions 1 to 7 (`tests/golden/project_v1.odori` …
//! `project_v7.odori`, each written once by `tests/tools/make_golden_project.rs` with the build of
//! its schema and reviewed; never written by the tests) open with this build: everything its
//! maker put in is there, it renders, and its history works. When the schema changes, these
//! files must keep opening (through `project::file::migrate`).

use odori_core::choreo::RenderOptions;
use odori_core::library::builtin_moves;
use odori_core::project::{self, BarKind, MoveKey, TrackKind};

const GOLDEN: &[u8] = include_bytes!("../golden/project_v1.odori");
/// Written by the tool at main 8823db9 (schema 2: the history as changes, no take).
const GOLDEN_V2: &[u8] = include_bytes!("../golden/project_v2.odori");
/// Written by the tool at main 8ed782d (schema 3: the dance's take, no cameras).
const GOLDEN_V3: &[u8] = include_bytes!("../golden/project_v3.odori");
/// Written by the tool at s13-mmdcam (schema 4: a camera VMD kept in the project).
const GOLDEN_V4: &[u8] = include_bytes!("../golden/project_v4.odori");
/// Written by the tool at s14-repeats (schema 5: a found repeat removed and a repeat marked).
const GOLDEN_V5: &[u8] = include_bytes!("../golden/project_v5.odori");
/// Written by the tool at s15-mmdface (schema 6: a face (lip-sync) track kept in the project).
const GOLDEN_V6: &[u8] = include_bytes!("../golden/project_v6.odori");
/// Written by the tool at s16-schema7 (schema 7: one list of MMD tracks, a model's texture and
/// shared toon ramp kept with its VMD dance, built-in bars keeping why).
const GOLDEN_V7: &[u8] = include_bytes!("../golden/project_v7.odori");

#[test]
fn golden_v1_opens_with_everything_in_it() {
    // Schema 2 keeps the history as changes: the v1 file (whole documents) is migrated.
    golden_opens_with_everything_in_it(GOLDEN, 1);
}

#[test]
fn golden_v2_opens_with_everything_in_it() {
    // Schema 3 keeps the dance's take (issue 26): a v2 dance is take 0.
    golden_opens_with_everything_in_it(GOLDEN_V2, 2);
}

#[test]
fn golden_v3_opens_with_everything_in_it() {
    // Schema 4 keeps camera VMDs: a v3 project has none.
    let p = golden_opens_with_everything_in_it(GOLDEN_V3, 3);
    assert!(p.doc().tracks(TrackKind::Camera).next().is_none());
}

#[test]
fn golden_v4_opens_with_its_camera_vmd() {
    let mut p = golden_opens_with_everything_in_it(GOLDEN_V4, 4);
    // Schema 5 keeps the repeats marked by hand: a v4 dance has none, and follows the analysis.
    assert!(p.doc().dance.repeats.is_empty());
    assert!(p.repeat_runs().expect("repeats").iter().all(|r| !r.marked));
    let doc = p.doc().clone();
    assert_eq!(doc.tracks(TrackKind::Camera).count(), 1);
    assert_eq!((doc.mmd_tracks[0].file_name.as_str(), doc.mmd_tracks[0].song_offset_frames), ("golden_cam.vmd", Some(0)));
    // The kept bytes are the camera the tool wrote: three keys a second apart, yawing 0 → 1 rad.
    let track = p.camera_track(0).expect("the camera track reads from the kept bytes");
    assert_eq!(track.keys.len(), 3);
    assert_eq!(track.keys.iter().map(|k| k.time_secs).collect::<Vec<_>>(), vec![0.0, 1.0, 2.0]);
    assert!((track.keys[2].rotation_rad.y.abs() - 1.0).abs() < 1e-6, "{:?}", track.keys[2]);
    assert!((track.keys[0].target_m.y - 10.0 * odori_core::mmd::METRES_PER_MMD_UNIT).abs() < 1e-6);
    // The import was the last edit: one undo takes the camera (and its blob) away, redo brings it back.
    assert!(p.undo());
    assert!(p.doc().tracks(TrackKind::Camera).next().is_none());
    assert!(p.redo());
    assert_eq!(p.doc(), &doc);
}

#[test]
fn golden_v5_opens_with_its_repeats() {
    use odori_core::project::{BarRange, RepeatMark, RepeatRun};
    let mut p = golden_opens_with_everything_in_it(GOLDEN_V5, 5);
    assert_eq!(p.doc().tracks(TrackKind::Camera).count(), 1);
    // Schema 6 keeps face tracks: a v5 project has none.
    assert!(p.doc().tracks(TrackKind::Face).next().is_none());
    let n = p.doc().dance.bars.len();
    let marks = p.doc().dance.repeats.clone();
    // What the tool did: the found repeat (the demo song's second chorus) removed, then the
    // last two bars marked as repeating the first two.
    assert_eq!(marks.len(), 2, "{marks:?}");
    assert_eq!(marks[0].of_bar, None);
    assert_eq!(marks[1], RepeatMark { first_bar: n - 2, bars: 2, of_bar: Some(0) });
    // The removed repeat is one the analysis finds (the same file without the marks has it).
    let mut control = project::open(GOLDEN_V5).expect("opens").project;
    assert!(control.undo() && control.undo(), "the marks are the last two undo steps");
    assert!(control.doc().dance.repeats.is_empty());
    let found = control.repeat_runs().expect("repeats");
    assert!(found.iter().any(|r| !r.marked && r.first_bar == marks[0].first_bar && r.bars == marks[0].bars), "{found:?} against {marks:?}");
    // With the marks: the one marked run, nothing found left.
    assert_eq!(p.repeat_runs().expect("repeats"), vec![RepeatRun { first_bar: n - 2, bars: 2, of_bar: 0, marked: true }]);
    // Generate follows it.
    p.generate().expect("generate");
    let keys: Vec<_> = p.doc().dance.bars.iter().map(|b| b.r#move.clone()).collect();
    assert_eq!(keys[n - 2], keys[0]);
    assert_eq!(keys[n - 1], keys[1]);
    // One undo step each: undo the Generate and the mark, and the mark is gone.
    assert!(p.undo() && p.undo());
    assert_eq!(p.doc().dance.repeats.len(), 1);
    // A bad range is refused with the project unchanged.
    let before = p.doc().clone();
    assert!(p.mark_repeat(BarRange { first_bar: 1, bars: 2 }, BarRange { first_bar: 0, bars: 2 }).is_err());
    assert_eq!(p.doc(), &before);
}

#[test]
fn golden_v6_opens_with_its_face_track() {
    let mut p = golden_opens_with_everything_in_it(GOLDEN_V6, 6);
    assert_eq!((p.doc().tracks(TrackKind::Camera).count(), p.doc().dance.repeats.len()), (1, 2));
    let doc = p.doc().clone();
    assert_eq!(doc.tracks(TrackKind::Face).count(), 1);
    let face = doc.tracks(TrackKind::Face).next().expect("the face track");
    assert_eq!((face.file_name.as_str(), face.song_offset_frames), ("golden_lip.vmd", Some(10)));
    // Schema 7 keeps both kinds in one list, the camera (imported first) first.
    assert_eq!(doc.mmd_tracks.iter().map(|t| t.kind).collect::<Vec<_>>(), vec![TrackKind::Camera, TrackKind::Face]);
    // The kept bytes are the face VMD the tool wrote byte by byte: あ shut at 0, open at 15, shut at 30.
    let track = p.face_track(0).expect("the face track reads from the kept bytes");
    let keys: Vec<(&str, u32, f32)> = track.keys.iter().map(|k| (k.name.as_str(), k.frame, k.weight)).collect();
    assert_eq!(keys, vec![("あ", 0, 0.0), ("あ", 15, 1.0), ("あ", 30, 0.0)]);
    assert_eq!(track.song_offset_frames, 10);
    // At song time 1/6 s (motion frame 15) the mouth is fully open.
    let faces = odori_core::mmd::face_track::LayeredFaces::new(&["い", "あ"], None, &[&track]);
    assert_eq!(faces.weights_at(0.0, 5.0 / 30.0), vec![(1, 1.0)]);
    // The track was the last edit: one undo takes it away, redo brings it back.
    assert!(p.undo());
    assert!(p.doc().tracks(TrackKind::Face).next().is_none());
    assert!(p.redo());
    assert_eq!(p.doc(), &doc);
}

#[test]
fn golden_v7_opens_with_its_model_textures_tracks_and_whys() {
    use odori_core::mmd::texture::decode_rgba;
    let mut p = golden_opens_with_everything_in_it(GOLDEN_V7, 7);
    let doc = p.doc().clone();
    // One list of MMD tracks, in the order imported: the camera, then the face track.
    let tracks: Vec<(TrackKind, &str, Option<u32>)> = doc.mmd_tracks.iter().map(|t| (t.kind, t.file_name.as_str(), t.song_offset_frames)).collect();
    assert_eq!(tracks, vec![(TrackKind::Camera, "golden_cam.vmd", Some(0)), (TrackKind::Face, "golden_lip.vmd", Some(10))]);
    assert_eq!(p.camera_track(0).expect("camera").keys.len(), 3);
    assert_eq!(p.face_track(0).expect("face").keys.len(), 3);
    assert_eq!(p.camera_track(1).expect_err("one camera").kind(), "not-found");
    // The VMD dance keeps its model and the two files it draws with, each a blob of the file.
    let src = doc.sources.iter().find(|s| s.file_name == "golden_dance.vmd").expect("the VMD dance");
    let model = src.model.as_ref().expect("its model");
    assert_eq!(model.file_name, "golden/golden.pmd");
    let names: Vec<(&str, &str)> = model.textures.iter().map(|t| (t.name.as_str(), t.path.as_str())).collect();
    assert_eq!(names, vec![("golden_tex.bmp", "golden/golden_tex.bmp"), ("toon01.bmp", "golden/toon01.bmp")]);
    // The texture is the 2×2 BMP the tool wrote: red, green / blue, white (read by the `image`
    // crate's BMP codec, not by anything the tool shares).
    let tex = p.blobs().get(&model.textures[0].blob).expect("the texture's bytes are in the file");
    let (w, h, rgba) = decode_rgba("golden_tex.bmp", "bmp", tex).expect("a BMP");
    assert_eq!((w, h), (2, 2));
    let px: Vec<[u8; 3]> = rgba.chunks(4).map(|c| [c[0], c[1], c[2]]).collect();
    assert_eq!(px, vec![[255, 0, 0], [0, 255, 0], [0, 0, 255], [255, 255, 255]]);
    // The model names them: its material's texture, and shared toon 1.
    let m = p.source_model(src.id).expect("reads").expect("kept");
    assert_eq!(m.textures, vec!["golden_tex.bmp".to_string()]);
    assert_eq!(m.materials[0].toon, odori_core::import::mmd_model::Toon::Shared(0));
    let files = p.source_model_files(src.id);
    assert_eq!(files.len(), 2);
    assert!(p.summary().mmd_files.iter().any(|f| f == "golden/golden_tex.bmp"), "{:?}", p.summary().mmd_files);
    // Built-in bars keep why (a join goal no move of the person's met): every bar with a why
    // holds a built-in move, and the readout gives it per bar.
    let whys = p.builtin_why();
    let with_why: Vec<usize> = (0..whys.len()).filter(|&i| whys[i].is_some()).collect();
    assert!(!with_why.is_empty(), "the tool's Generate left bars built-in with a why");
    for &i in &with_why {
        assert!(matches!(doc.dance.bars[i].r#move, Some(MoveKey::Builtin { .. })), "bar {i}");
        assert_eq!(whys[i].map(|(_, w)| w), doc.dance.bars[i].builtin_why);
    }
    let mine = doc.dance.bars.iter().filter(|b| matches!(b.r#move, Some(MoveKey::Cut { .. }))).count();
    println!("golden v7: {} bars, {mine} of the person's moves, {} built-in with a why", doc.dance.bars.len(), with_why.len());
    // Generate was the last edit: undo takes the whys away with its bars, redo brings them back.
    assert!(p.undo());
    assert!(p.doc().dance.bars.iter().all(|b| b.builtin_why.is_none()));
    assert!(p.redo());
    assert_eq!(p.builtin_why(), whys);
}

/// A build that knows schema 6 only refuses a v7 file (it would drop the model's textures and
/// the whys unseen, and find no camera or face track where it looks for them): the v7 golden's
/// manifest with its version raised past this build's is refused the same way.
#[test]
fn a_file_newer_than_this_build_is_refused() {
    let mut zip = zip::ZipArchive::new(std::io::Cursor::new(GOLDEN_V7)).expect("a zip");
    let mut manifest = String::new();
    std::io::Read::read_to_string(&mut zip.by_name("manifest.json").expect("manifest"), &mut manifest).expect("reads");
    let next = project::CURRENT_SCHEMA_VERSION + 1;
    let newer = manifest.replacen(&format!("\"schemaVersion\":{}", project::CURRENT_SCHEMA_VERSION), &format!("\"schemaVersion\":{next}"), 1);
    assert_ne!(newer, manifest);
    match project::file::from_manifest(newer.as_bytes(), |_| None) {
        Err(e) => assert_eq!(e, project::FileError::NewerVersion { found: next, supported: project::CURRENT_SCHEMA_VERSION }),
        Ok(_) => panic!("a newer schema opened"),
    }
}

fn golden_opens_with_everything_in_it(bytes: &[u8], version: u32) -> project::Project {
    let opened = project::open(bytes).unwrap_or_else(|e| panic!("the golden v{version} file opens: {e}"));
    assert!(opened.missing.is_empty(), "{:?}", opened.missing);
    assert_eq!(opened.migrated_from, (version < project::CURRENT_SCHEMA_VERSION).then_some(version));
    let mut p = opened.project;
    let doc = p.doc().clone();
    assert_eq!(doc.dance.take, 0, "a dance saved before takes is take 0");
    assert_eq!(doc.name, "golden v1");
    // Schema 7's golden adds a VMD dance on its model and a humanoid BVH of the person's moves.
    assert_eq!(doc.sources.len(), if version >= 7 { 3 } else { 1 });
    assert_eq!(doc.sources[0].file_name, "tiny.bvh");
    assert_eq!(doc.sources[0].options.fps_override, Some(30.0));
    let song = doc.song.as_ref().expect("song");
    assert_eq!((song.file_name.as_str(), song.audio.is_none(), song.corrections.len()), ("demo", true, 1));
    assert_eq!(song.corrections[0].nudge_secs, Some(0.02));
    assert_eq!(doc.tags.len(), 1);
    assert_eq!(doc.tags[0].tags, vec!["lean".to_string(), "傾く".to_string()]);
    assert_eq!(doc.texts[1], "歩きながら右手を振る");
    assert_eq!(doc.dance.settings.rho, 0.5);
    assert_eq!(doc.camera.map(|c| c.distance_m), Some(4.0));
    // Bar 2 is pinned to the eighth built-in move, named by what it is.
    assert_eq!(doc.dance.bars[1].state, BarKind::Pinned);
    assert_eq!(doc.dance.bars[1].r#move, Some(MoveKey::Builtin { r#move: builtin_moves()[7] }));
    let search = doc.dance.bars[3].search.as_ref().expect("bar 4's search");
    assert_eq!((search.rounds, search.liked.len(), search.shown.len()), (2, 2, 12));
    assert!(doc.dance.bars.iter().all(|b| b.state != BarKind::Empty), "Generate filled every bar");
    // Every key resolves in this build's library, and the dance renders.
    for b in &doc.dance.bars {
        let k = b.r#move.as_ref().unwrap();
        assert!(p.derived().index_of(k).is_some(), "{k:?} is not in the library");
    }
    let clip = p.render_dance(&RenderOptions::default()).expect("render");
    assert!(clip.frame_count() > 60);
    // The tiny BVH is not humanoid: it is kept and listed but not in the dance library.
    assert!(p.derived().clips()[0].refused.is_some());
    // History: undo goes back through the edits to the project's start.
    let steps = p.undo_history().len();
    assert!(steps >= 9, "{steps} undo steps");
    while p.undo() {}
    assert!(p.doc().song.is_none() && p.doc().sources.is_empty());
    while p.redo() {}
    assert_eq!(p.doc(), &doc);
    // Saved again by this build, it reopens identically.
    let again = project::open(&project::save(&p).unwrap()).unwrap().project;
    assert!(again == p);
    p
}

/// The error kinds the `.d.ts` lists (`error_kinds!` in crate/web/src/error.rs) cover every kind the project and
/// file errors (and the importer's, which a project edit passes on) can have.
#[test]
fn dts_error_kinds_cover_the_core_kinds() {
    use odori_core::import::ImportError;
    use odori_core::music::MusicError;
    use odori_core::project::{FileError, ProjectError};
    // The kinds are declared once, in `error_kinds!` (crate/web/src/error.rs), which makes both
    // the TypeScript union `OdoriErrorKind` and `errorKinds()`.
    let error_rs = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/../crate/web/src/error.rs")).expect("crate/web/src/error.rs");
    let start = error_rs.find("error_kinds! {").expect("the error_kinds! list");
    let dts = &error_rs[start..start + error_rs[start..].find("\n}").unwrap()];
    let f = || "f".to_string();
    let file_errors = [
        FileError::Empty,
        FileError::NotOdori { start: f() },
        FileError::Truncated { size_bytes: 1, message: f() },
        FileError::Corrupt { entry: f(), message: f() },
        FileError::NoManifest,
        FileError::BadManifest { line: 1, column: 1, message: f() },
        FileError::BadProject { message: f() },
        FileError::WrongFormat { format: f() },
        FileError::NewerVersion { found: 2, supported: 1 },
        FileError::TooOld { found: 0, oldest: 1 },
        FileError::BlobMismatch { name: f(), actual: f() },
        FileError::Write { message: f() },
    ];
    let project_errors = [
        ProjectError::Import(ImportError::Empty { file: f() }),
        ProjectError::Import(ImportError::UnknownFormat { file: f(), start: f() }),
        ProjectError::Import(ImportError::Bvh { file: f(), line: 1, column: 1, message: f() }),
        ProjectError::Import(ImportError::Gltf { file: f(), message: f() }),
        ProjectError::Import(ImportError::Unsupported { file: f(), message: f() }),
        ProjectError::Import(ImportError::Invalid { file: f(), message: f() }),
        ProjectError::Music(MusicError::TooFewTaps { taps: 1, min: 4 }),
        ProjectError::Choreo(odori_core::choreo::ChoreoError::NoBars),
        ProjectError::NoSong,
        ProjectError::NoSuchSource { source_id: 1 },
        ProjectError::NoSuchClip { source_id: 1, file_name: f(), clip: 1, clips: 0 },
        ProjectError::NotDanceable { file_name: f(), clip: 0, reason: f() },
        ProjectError::UnknownMove { key: f() },
        ProjectError::Incomplete { count: 1, first: f() },
        ProjectError::BadEnvelope { message: f() },
        ProjectError::NotACamera { file_name: f(), bone_keys: 1, morph_keys: 0 },
        ProjectError::NoSuchCamera { index: 1, count: 0 },
        ProjectError::NotAFaceTrack { file_name: f(), bone_keys: 1, camera_keys: 0 },
        ProjectError::NoSuchFaceTrack { index: 1, count: 0 },
        ProjectError::Repeat(odori_core::project::RepeatError::Overlapping { first_bar: 1, end_bar: 3, of_first_bar: 0, of_end_bar: 2 }),
        ProjectError::Repeat(odori_core::project::RepeatError::NotARepeat { bar: 1, song_bars: 2 }),
    ];
    let kinds: Vec<&str> = file_errors.iter().map(FileError::kind).chain(project_errors.iter().map(ProjectError::kind)).collect();
    for k in kinds {
        assert!(dts.contains(&format!("\"{k}\"")), "error kind {k:?} is missing from the OdoriError kinds in the .d.ts");
    }
}
