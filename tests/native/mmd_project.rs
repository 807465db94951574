//! An imported VMD dance as a source of the project (issue 28 item 1), on the real WAVEFILE
//! dance: `Project::add_source` takes the VMD like a BVH (posed on the standard MMD skeleton,
//! the song offset kept in its import options), cuts it into segments, Generate with *my moves*
//! fills bars with them, and the project saved to `.odori` bytes and opened again holds the
//! same source, the same offset and renders the same dance. A bad VMD is a typed error and
//! leaves the project as it was. A VMD given with its model (`add_source_on`) is posed on it as
//! the library's MMD import poses it, and the project keeps the model so it is posed on it again
//! after reopening (withheld: the standard skeleton, saying so). A camera VMD (`add_camera`) is
//! kept as given, survives save and open, and anything else is refused as a camera.

use odori_core::choreo::{MovesSource, RenderOptions};
use odori_core::music::AnalysisOptions;
use odori_core::project::{self, BarKind, MoveKey, Project, TrackKind};
use odori_core::{Clip, ImportOptions};
use odori_tests::read;

#[path = "music_audio.rs"]
mod music_audio;

const SONG: &str = "music/Kevin_MacLeod_-_Vibe_Ace.hq.ogg";
const WAVEFILE: &str = "mmd/motion/wavefile_v2.vmd";

fn dance_poses(p: &mut Project) -> Vec<Vec<glam::Vec3>> {
    let clip: Clip = p.render_dance(&RenderOptions::default()).expect("render");
    let n = clip.frame_count();
    (0..5).map(|k| clip.world_positions((n.saturating_sub(1)) * k / 4)).collect()
}

/// Bars whose move is cut from source `id`.
fn bars_from(p: &Project, id: project::SourceId) -> Vec<usize> {
    p.doc()
        .dance
        .bars
        .iter()
        .enumerate()
        .filter(|(_, b)| matches!(&b.r#move, Some(MoveKey::Cut { clip, .. }) if clip.source == id))
        .map(|(i, _)| i)
        .collect()
}

#[test]
fn a_vmd_dance_is_a_project_source_generate_uses_and_a_reopened_project_keeps() {
    let audio = music_audio::decode_data(SONG);
    let env = audio.envelope().unwrap_or_else(|e| panic!("{SONG}: {e}"));
    let mut p = Project::new();
    p.set_song("Vibe_Ace.ogg", Some(&read(SONG)), &env, AnalysisOptions::default()).expect("song");
    let wave = read(WAVEFILE);
    let r = p.add_source("wavefile_v2.vmd", &wave, ImportOptions { song_offset_frames: Some(160), ..Default::default() }).expect("the VMD is a source");
    assert_eq!(r.clips.len(), 1);
    let info = p.derived().clips().iter().find(|c| c.clip.source == r.id).cloned().expect("its clip is listed");
    // WAVEFILE runs frames 0–2,809; from the offset on, 2,650 frames at 30 fps.
    assert_eq!((info.frames, info.fps), (2810 - 160, 30.0), "{info:?}");
    assert!(info.humanoid.is_humanoid(), "{:?}", info.humanoid);
    let cut = info.cut.clone().unwrap_or_else(|| panic!("WAVEFILE is cut into segments: {:?}", info.refused));
    println!("wavefile_v2.vmd as a project source: {} frames, cut at {:.1} counts/min into {} segments", info.frames, cut.tempo_bpm, cut.segments);
    assert!(cut.segments >= 10, "{cut:?}");
    // Without the offset the same file is another clip, 160 frames longer: the offset is applied.
    let mut plain = Project::new();
    let r0 = plain.add_source("wavefile_v2.vmd", &wave, ImportOptions::default()).expect("no offset");
    assert_eq!(plain.derived().clips().iter().find(|c| c.clip.source == r0.id).map(|c| c.frames), Some(2810));

    p.set_moves_source(MovesSource::Mine).expect("my moves");
    p.generate().expect("generate");
    let mine = bars_from(&p, r.id);
    let generated = p.doc().dance.bars.iter().filter(|b| b.state == BarKind::Generated).count();
    println!("Generate (my moves): {} of {generated} generated bars dance WAVEFILE's segments", mine.len());
    assert!(!mine.is_empty() && mine.len() * 2 >= generated, "Generate with my moves uses WAVEFILE's segments: {} of {generated}", mine.len());

    let before = dance_poses(&mut p);
    let bytes = project::save(&p).expect("save");
    let mut q = project::open(&bytes).expect("open").project;
    let src = q.doc().source(r.id).cloned().expect("the VMD source is still there");
    assert_eq!((src.file_name.as_str(), src.options.song_offset_frames), ("wavefile_v2.vmd", Some(160)));
    assert_eq!(bars_from(&q, r.id), mine);
    assert_eq!(dance_poses(&mut q), before, "the reopened project renders the same dance");
    assert_eq!(project::save(&q).expect("save again"), bytes);
}

#[test]
fn a_bad_vmd_is_a_typed_error_and_the_project_is_unchanged() {
    let wave = read(WAVEFILE);
    let mut p = Project::new();
    let before = p.doc().clone();
    let cut = &wave[..wave.len() / 3];
    let e = p.add_source("cut.vmd", cut, ImportOptions::default()).expect_err("a truncated VMD");
    assert_eq!(e.kind(), "mmd-count-too-large", "{e}");
    assert!(e.to_string().contains("cut.vmd"), "{e}");
    let e = p.add_source("late.vmd", &wave, ImportOptions { song_offset_frames: Some(5000), ..Default::default() }).expect_err("an offset past the end");
    assert_eq!(e.kind(), "bad-argument", "{e}");
    assert!(e.to_string().contains("5000"), "{e}");
    assert_eq!(p.doc(), &before);
}

const CAMERA: &str = "mmd/motion/tokino_kakera_cam.vmd";

/// The camera keys' frames as the file lays them out (read here byte by byte, not through the
/// engine's reader): a V2 header, no bone or morph keys, then the camera count and 61-byte keys.
fn camera_frames_in_file(bytes: &[u8]) -> Vec<u32> {
    let word = |at: usize| u32::from_le_bytes([bytes[at], bytes[at + 1], bytes[at + 2], bytes[at + 3]]);
    assert_eq!((&bytes[..25], word(50), word(54)), (&b"Vocaloid Motion Data 0002"[..], 0, 0), "{CAMERA} is a camera-only V2 VMD");
    (0..word(58) as usize).map(|k| word(62 + 61 * k)).collect()
}

#[test]
fn a_camera_vmd_is_kept_in_the_project_and_survives_save_and_open() {
    let cam = read(CAMERA);
    let frames = camera_frames_in_file(&cam);
    let mut p = Project::new();
    let track = p.add_camera("tokino_kakera_cam.vmd", &cam, None).expect("a camera VMD is a project item");
    let mut times: Vec<f32> = frames.iter().map(|&f| f as f32 / 30.0).collect();
    times.sort_by(f32::total_cmp);
    assert_eq!(track.keys.iter().map(|k| k.time_secs).collect::<Vec<_>>(), times, "one key per camera key of the file, at frame / 30 s");
    println!("{CAMERA}: {} camera keys over {:.1} s kept in the project", track.keys.len(), times.last().copied().unwrap_or(0.0));
    let doc = p.doc().clone();
    assert_eq!(doc.tracks(TrackKind::Camera).count(), 1);
    assert!(p.blobs().get(&doc.mmd_tracks[0].blob).is_some_and(|b| **b == cam[..]), "its bytes are kept as given");
    // Undo takes the import back (and its blob out of what a save writes); redo restores it.
    assert!(p.undo());
    assert!(p.doc().tracks(TrackKind::Camera).next().is_none() && p.referenced_blobs().contains(&doc.mmd_tracks[0].blob), "the history still refers to the blob");
    assert!(p.redo());
    assert_eq!(p.doc(), &doc);
    // Saved and opened again (what the .odori file and the browser's store both go through).
    let bytes = project::save(&p).expect("save");
    let q = project::open(&bytes).expect("open").project;
    assert_eq!(q.doc().tracks(TrackKind::Camera).collect::<Vec<_>>(), doc.tracks(TrackKind::Camera).collect::<Vec<_>>());
    assert_eq!(q.camera_track(0).expect("the reopened camera"), track);
    // With its bytes missing (a store that lost the blob) the rest opens and the camera says what is gone.
    let manifest = project::file::manifest_json(&p);
    let opened = project::file::from_manifest(&manifest, |h| p.blobs().get(h).cloned().filter(|_| *h != doc.mmd_tracks[0].blob)).expect("opens");
    assert_eq!(opened.missing.iter().map(|m| m.what.as_str()).collect::<Vec<_>>(), vec!["camera motion tokino_kakera_cam.vmd"]);
    let e = opened.project.camera_track(0).expect_err("no bytes, no track");
    assert_eq!(e.kind(), "missing-blob", "{e}");
}

#[test]
fn a_file_that_is_not_a_camera_vmd_is_refused_and_the_project_is_unchanged() {
    let mut p = Project::new();
    let before = p.doc().clone();
    let e = p.add_camera("wavefile_v2.vmd", &read(WAVEFILE), None).expect_err("a dance VMD is no camera");
    assert_eq!(e.kind(), "mmd-no-camera-keys", "{e}");
    assert!(e.to_string().contains("wavefile_v2.vmd"), "{e}");
    let cam = read(CAMERA);
    let e = p.add_camera("cut_cam.vmd", &cam[..cam.len() - 30], None).expect_err("a truncated camera VMD");
    assert_eq!(e.kind(), "mmd-count-too-large", "{e}");
    let e = p.add_camera("x.vmd", b"not a vmd at all, just text", None).expect_err("not a VMD");
    assert_eq!(e.kind(), "mmd-bad-magic", "{e}");
    assert_eq!(p.doc(), &before);
    assert!(p.undo_history().is_empty());
    assert!(matches!(p.remove_camera(0), Err(e) if e.kind() == "not-found"));
}

const MIKU: &str = "mmd/miku_v2/miku_v2.pmd";

/// A clip's joint positions (metres) at five frames across it.
fn poses_of(clip: &Clip) -> Vec<Vec<glam::Vec3>> {
    let n = clip.frame_count();
    (0..5).map(|k| clip.world_positions((n.saturating_sub(1)) * k / 4)).collect()
}

/// The largest distance (metres) between the same joints of two pose lists.
fn max_gap(a: &[Vec<glam::Vec3>], b: &[Vec<glam::Vec3>]) -> f32 {
    a.iter().zip(b).flat_map(|(x, y)| x.iter().zip(y).map(|(p, q)| p.distance(*q))).fold(0.0, f32::max)
}

#[test]
fn a_vmd_dance_on_its_model_keeps_the_model_and_reopens_on_it() {
    use odori_core::mmd::files::{import_files, MmdFilesOptions, STANDARD_RIG};
    let (wave, miku) = (read(WAVEFILE), read(MIKU));
    let opts = ImportOptions { song_offset_frames: Some(160), ..Default::default() };
    // The reference: the library's own MMD import of the same set, which poses WAVEFILE on the
    // model its header names.
    let lib = import_files(&[("miku_v2.pmd".into(), miku.clone()), ("wavefile_v2.vmd".into(), wave.clone())], &[], &MmdFilesOptions { model: None, song_offset_frames: Some(160) });
    let reference = lib.motions.first().unwrap_or_else(|| panic!("the library poses WAVEFILE: {:?}", lib.problems));
    assert_ne!(reference.rig, STANDARD_RIG, "WAVEFILE's header names miku_v2");

    let mut p = Project::new();
    let r = p.add_source_on("wavefile_v2.vmd", &wave, opts.clone(), Some(("miku_v2.pmd", &miku))).expect("a VMD on its model");
    let on_model = p.imported(r.id).expect("bytes").expect("imports").clips[0].clone();
    let gap = max_gap(&poses_of(&on_model), &poses_of(&reference.clip));
    assert!(gap < 1e-5, "the project's dance on miku_v2 is the library's ({gap} m apart)");
    let mut plain = Project::new();
    let r0 = plain.add_source("wavefile_v2.vmd", &wave, opts.clone()).expect("on the standard skeleton");
    let on_standard = plain.imported(r0.id).expect("bytes").expect("imports").clips[0].clone();
    let apart = max_gap(&poses_of(&on_model), &poses_of(&on_standard));
    println!("WAVEFILE on miku_v2 vs on the standard skeleton: joints up to {apart:.3} m apart");
    assert!(apart > 0.01, "the control: the standard skeleton poses it differently ({apart} m)");

    // Saved and opened again: the model is kept with the dance and poses it again.
    let doc = p.doc().clone();
    let model = doc.sources[0].model.clone().expect("the source names its model");
    assert_eq!(model.file_name, "miku_v2.pmd");
    assert!(p.blobs().get(&model.blob).is_some_and(|b| **b == miku[..]), "the model's bytes are kept as given");
    let mut q = project::open(&project::save(&p).expect("save")).expect("open").project;
    let again = q.imported(r.id).expect("bytes").expect("imports").clips[0].clone();
    assert_eq!(poses_of(&again), poses_of(&on_model), "the reopened dance plays on miku_v2 again");

    // Without the model's bytes: the standard skeleton, and both the open and the import say so.
    let manifest = project::file::manifest_json(&p);
    let opened = project::file::from_manifest(&manifest, |h| p.blobs().get(h).cloned().filter(|_| *h != model.blob)).expect("opens");
    assert_eq!(opened.missing.iter().map(|m| m.what.as_str()).collect::<Vec<_>>(), vec!["MMD model miku_v2.pmd of wavefile_v2.vmd"]);
    let mut lost = opened.project;
    let im = lost.imported(r.id).expect("the dance's bytes are there").expect("imports");
    assert_eq!(poses_of(&im.clips[0]), poses_of(&on_standard), "falls back to the standard skeleton");
    assert!(im.warnings.iter().any(|w| w.contains("miku_v2.pmd is missing from the project") && w.contains(STANDARD_RIG)), "{:?}", im.warnings);

    // A model that cannot be read, or a model with a file that is not a VMD: typed errors, nothing changed.
    let before = p.doc().clone();
    let e = p.add_source_on("wavefile_v2.vmd", &wave, opts.clone(), Some(("bad.pmx", b"not a model"))).expect_err("a bad model");
    assert_eq!(e.kind(), "mmd-bad-magic", "{e}");
    let e = p.add_source_on("walk.bvh", b"HIERARCHY\nROOT Hips\n", ImportOptions::default(), Some(("miku_v2.pmd", &miku))).expect_err("a model with a BVH");
    assert_eq!(e.kind(), "invalid", "{e}");
    assert_eq!(p.doc(), &before);
}

/// Face keys of a project's VMD dance (issue 28: "face morph keys play on the model and survive
/// a VMD round trip"): read again from the bytes the project keeps — no field of the `.odori`
/// file of their own — they are the VMD's own morph keys (as the library's MMD import sets
/// them aside) with the song offset the dance starts at, alike on the model and on the standard
/// skeleton, and after saving and opening again. Written back by the export and read back: equal
/// on the export's timeline. A VMD without morph keys has none (the control).
#[test]
fn a_vmd_sources_face_keys_come_from_its_kept_bytes_and_survive_a_round_trip() {
    use odori_core::mmd::export::{clip_to_vmd, put_morph_keys};
    use odori_core::mmd::MmdRig;
    let (wave, miku) = (read(WAVEFILE), read(MIKU));
    let vmd = odori_core::import::vmd::read("wavefile_v2.vmd", &wave).expect("reads");
    assert!(vmd.morph_keys.len() > 1000, "{}", vmd.morph_keys.len());
    let opts = ImportOptions { song_offset_frames: Some(160), ..Default::default() };
    let mut p = Project::new();
    let on_model = p.add_source_on("wavefile_v2.vmd", &wave, opts.clone(), Some(("miku_v2.pmd", &miku))).expect("a VMD on its model").id;
    let on_standard = p.add_source("wavefile_v2.vmd", &wave, opts.clone()).expect("a VMD").id;
    for id in [on_model, on_standard] {
        let (keys, offset) = p.face_keys(id).expect("face keys");
        assert_eq!(offset, 160);
        assert_eq!(keys, vmd.morph_keys, "the VMD's own keys");
    }
    let mut q = project::open(&project::save(&p).expect("save")).expect("open").project;
    assert_eq!(q.face_keys(on_model), p.face_keys(on_model), "the same after reopening");

    // Exported as VMD on miku_v2 with its face keys, and read back.
    let model = odori_core::import::mmd_model::read_model("miku_v2.pmd", &miku).expect("model");
    let rig = MmdRig::from_model(&model).expect("rig");
    let clip = q.imported(on_model).expect("bytes").expect("imports").clips[0].clone();
    let mut out = clip_to_vmd(&clip, &rig, &model.name).expect("export");
    let (keys, offset) = q.face_keys(on_model).expect("face keys");
    put_morph_keys(&mut out, &keys, offset);
    let back = odori_core::import::vmd::read("out.vmd", &odori_core::export::vmd::write("out.vmd", &out).expect("write")).expect("read back");
    let want: Vec<(String, u32, f32)> = vmd.morph_keys.iter().filter(|k| k.frame >= offset).map(|k| (k.name.clone(), k.frame - offset, k.weight)).collect();
    let got: Vec<(String, u32, f32)> = back.morph_keys.iter().map(|k| (k.name.clone(), k.frame, k.weight)).collect();
    assert_eq!(got, want);
    println!("WAVEFILE as a project source: {} face keys read from the kept bytes (offset {offset}); {} written back from the offset on and read back equal", keys.len(), got.len());

    // Control: a VMD without face keys (the same dance exported without them) has none.
    let bare = odori_core::export::vmd::write("bare.vmd", &clip_to_vmd(&clip, &rig, &model.name).expect("export")).expect("write");
    let r = p.add_source("bare.vmd", &bare, ImportOptions::default()).expect("a VMD without face keys");
    assert_eq!(p.face_keys(r.id), None);
}

// Issue 28: a project dance posed on its model is drawn with that model's mesh (the control, the
// same dance on the standard skeleton, has none), and the project names the model
// (`Project::source_model`) so a host links the dance to it: the library's textured mesh of the
// same model, and `exportVmd`'s default model. The library keeps a model file's bytes, so a
// model imported earlier can be kept with a dance later.
#[test]
fn a_vmd_dance_on_its_model_is_drawn_with_its_mesh_and_names_its_model() {
    use odori_core::mmd::files::{import_files, MmdFilesOptions};
    use odori_core::mmd::mesh::model_character;
    let (wave, miku) = (read(WAVEFILE), read(MIKU));
    let opts = ImportOptions { song_offset_frames: Some(160), ..Default::default() };
    // The reference: the library's import of the model alone, and its mesh as a character.
    let lib = import_files(&[("miku_v2.pmd".into(), miku.clone())], &[], &MmdFilesOptions::default());
    let m = lib.models.first().unwrap_or_else(|| panic!("miku_v2 imports: {:?}", lib.problems));
    assert!(m.bytes == miku, "the library keeps the model file's bytes as given");
    let c = model_character(&m.file, &m.model, &m.textures, &m.missing_textures, &[]).unwrap_or_else(|e| panic!("{e}"));

    let mut p = Project::new();
    let r = p.add_source_on("wavefile_v2.vmd", &wave, opts.clone(), Some(("miku_v2.pmd", &miku))).expect("a VMD on its model");
    let im = p.imported(r.id).expect("bytes").expect("imports");
    let mesh = im.mesh.as_ref().expect("the dance on miku_v2 is drawn with miku_v2's mesh");
    let joints: Vec<&str> = im.clips[0].skeleton.joints.iter().map(|j| j.name.as_str()).collect();
    let character_joints: Vec<&str> = c.character.skeleton.joints.iter().map(|j| j.name.as_str()).collect();
    assert_eq!(joints, character_joints, "the dance's skeleton is the model character's: either mesh draws it");
    assert_eq!(mesh.palette, c.character.mesh.palette, "the same skin as the library's mesh of miku_v2");
    let tris = |m: &odori_core::import::SkinnedMesh| m.parts.iter().map(|p| p.indices.len() / 3).sum::<usize>();
    assert_eq!(tris(mesh), tris(&c.character.mesh));
    assert!(mesh.palette.iter().all(|(j, _)| *j < joints.len()));
    assert!(mesh.textures.is_empty(), "given without its textures, the project keeps the model file only");
    assert!(im.warnings.iter().any(|w| w.contains("keeps the model file miku_v2.pmd without") && w.contains("eyeM2.bmp") && w.contains("drawn in their colours")), "{:?}", im.warnings);
    let named = p.source_model(r.id).expect("reads").expect("the source names its model");
    assert_eq!(named.name, m.model.name);

    // The control: the same dance on the standard skeleton has no mesh and no model.
    let mut plain = Project::new();
    let r0 = plain.add_source("wavefile_v2.vmd", &wave, opts.clone()).expect("on the standard skeleton");
    assert!(plain.imported(r0.id).expect("bytes").expect("imports").mesh.is_none());
    assert_eq!(plain.source_model(r0.id).expect("reads"), None);
    assert_eq!(plain.source_model(project::SourceId(99)).expect_err("no such source").kind(), "not-found");

    // Saved and opened: still drawn with the mesh and named; without the model's bytes neither.
    let mut q = project::open(&project::save(&p).expect("save")).expect("open").project;
    assert_eq!(q.imported(r.id).expect("bytes").expect("imports").mesh.as_ref().map(|m| m.palette.clone()), Some(mesh.palette.clone()));
    assert_eq!(q.source_model(r.id).expect("reads").map(|m| m.name), Some(named.name.clone()));
    let model_blob = p.doc().sources[0].model.clone().expect("kept").blob;
    let manifest = project::file::manifest_json(&p);
    let mut lost = project::file::from_manifest(&manifest, |h| p.blobs().get(h).cloned().filter(|_| *h != model_blob)).expect("opens").project;
    assert!(lost.imported(r.id).expect("bytes").expect("imports").mesh.is_none());
    assert_eq!(lost.source_model(r.id).expect("reads"), None);
}
