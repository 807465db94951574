//! What `.odori` schema 7 keeps (issues 28 and 26), through save/reopen and undo:
//! - an MMD model's textures and MMD's shared toon ramps it uses, kept with a VMD dance posed on
//!   it (blobs by hash, shared across dances): on the real miku_v2 with its folder, the dance
//!   reopened without any library is drawn with the very textures the library's import of the
//!   folder draws it with (the control: the model given without them is drawn untextured); a
//!   second dance on the model adds no texture bytes; a lost texture is named and the rest opens;
//!   `summary().mmd_files` names every MMD file kept (what the page says on save);
//! - why a bar is built-in (`BuiltinWhy`), kept with the bar: the same after save/reopen and
//!   through undo/redo, dropped when the bar's move is changed;
//! - camera and face tracks as one list (`mmd_tracks`) whose add/remove keep each kind's order.

use odori_core::choreo::{GenerateOptions, MovesSource, RenderOptions};
use odori_core::import::SkinnedMesh;
use odori_core::library::builtin_moves;
use odori_core::mmd::files::{import_files, MmdFilesOptions};
use odori_core::mmd::mesh::model_character;
use odori_core::music::{demo_song, envelope, AnalysisOptions};
use odori_core::project::{self, GivenModel, MoveKey, Project, TrackKind};
use odori_core::ImportOptions;
use odori_tests::read;

/// The golden tool's VMDs written byte by byte (a three-key camera, a three-key face track).
#[path = "../tools/make_golden_project.rs"]
#[allow(dead_code)]
mod tool;

const WAVEFILE: &str = "mmd/motion/wavefile_v2.vmd";
const MIKU_DIR: &str = "mmd/miku_v2";

/// miku_v2's folder as a dropped folder gives it: every file (but the readme) with its path.
fn miku_folder() -> Vec<(String, Vec<u8>)> {
    odori_tests::data_folder(MIKU_DIR, |n| !n.ends_with(".txt")).into_iter().map(|(n, b)| (format!("miku_v2/{n}"), b)).collect()
}

/// A mesh's textures as (pixels' PNG bytes) for comparing two meshes.
fn texture_bytes(mesh: &SkinnedMesh) -> Vec<Vec<u8>> {
    mesh.textures.iter().map(|t| t.image.clone()).collect()
}

#[test]
fn a_models_textures_are_kept_with_its_dance_and_drawn_after_reopening_without_the_library() {
    let folder = miku_folder();
    let wave = read(WAVEFILE);
    // The reference: the library's import of the folder, and the model's mesh drawn from it.
    let lib = import_files(&folder, &[], &MmdFilesOptions::default());
    let m = lib.models.first().unwrap_or_else(|| panic!("miku_v2 imports: {:?}", lib.problems));
    let drawn = m.drawn_files();
    let reference = model_character(&m.file, &m.model, &m.textures, &m.missing_textures, &folder).unwrap_or_else(|e| panic!("{e}")).character.mesh;
    assert!(!reference.textures.is_empty());
    let names: Vec<&str> = drawn.iter().map(|(n, _, _)| n.as_str()).collect();
    println!("miku_v2 draws with {} files: {names:?} ({} textures in the library's mesh)", drawn.len(), reference.textures.len());
    assert!(names.iter().any(|n| n.starts_with("toon")), "the shared toon ramps it uses are kept too: {names:?}");

    let opts = ImportOptions { song_offset_frames: Some(160), ..Default::default() };
    let mut p = Project::new();
    let given = GivenModel { file_name: &m.file, bytes: &m.bytes, drawn: &drawn };
    let r = p.add_source_with_model("wavefile_v2.vmd", &wave, opts.clone(), given).expect("a VMD on its model with its textures");
    let mesh = p.imported(r.id).expect("bytes").expect("imports").mesh.clone().expect("drawn on miku_v2's mesh");
    assert_eq!(texture_bytes(&mesh), texture_bytes(&reference), "the project's mesh has the library's textures");
    let looks = |m: &SkinnedMesh| m.parts.iter().map(|p| (p.texture, p.toon.as_ref().map(|t| t.ramp))).collect::<Vec<_>>();
    assert_eq!(looks(&mesh), looks(&reference), "each part uses the same texture and toon ramp");

    // Saved and opened again, with no library at all: the same textures.
    let bytes = project::save(&p).expect("save");
    let mut q = project::open(&bytes).expect("open").project;
    let again = q.imported(r.id).expect("bytes").expect("imports").mesh.clone().expect("mesh");
    assert_eq!(texture_bytes(&again), texture_bytes(&reference));
    assert_eq!(looks(&again), looks(&reference));
    let kept = q.doc().sources[0].model.as_ref().expect("model").textures.clone();
    assert_eq!(kept.len(), drawn.len());
    for (k, (n, path, b)) in kept.iter().zip(&drawn) {
        assert_eq!((&k.name, &k.path), (n, path));
        assert!(q.blobs().get(&k.blob).is_some_and(|x| **x == b[..]), "{n}: kept as given");
    }

    // The control: the model given without its files is drawn in its materials' colours.
    let mut bare = Project::new();
    let r0 = bare.add_source_on("wavefile_v2.vmd", &wave, opts.clone(), Some((&m.file, &m.bytes))).expect("the model alone");
    assert!(bare.imported(r0.id).expect("bytes").expect("imports").mesh.as_ref().expect("mesh").textures.is_empty());

    // A second dance on the same model keeps no texture twice: one blob per file.
    let before: usize = q.referenced_blobs().iter().map(|h| q.blobs().get(h).map_or(0, |b| b.len())).sum();
    let cut = odori_core::export::vmd::write("second.vmd", &odori_core::import::vmd::read("w", &wave).expect("reads")).expect("writes");
    let given = GivenModel { file_name: &m.file, bytes: &m.bytes, drawn: &drawn };
    q.add_source_with_model("second.vmd", &cut, ImportOptions::default(), given).expect("a second dance");
    let after: usize = q.referenced_blobs().iter().map(|h| q.blobs().get(h).map_or(0, |b| b.len())).sum();
    assert_eq!(after - before, q.blobs().get(&q.doc().sources[1].blob).map_or(0, |b| b.len()), "only the second VMD's bytes were added");
    println!("a second dance on miku_v2 adds {} bytes (its VMD) to the {before} kept", after - before);
    // Every MMD file kept is named for the page's note on save.
    let named = q.summary().mmd_files;
    for n in ["wavefile_v2.vmd", "second.vmd", "miku_v2/miku_v2.pmd", "miku_v2/eyeM2.bmp"] {
        assert!(named.iter().any(|x| x == n), "{n} not in {named:?}");
    }
    assert_eq!(named.iter().filter(|x| x.as_str() == "miku_v2/eyeM2.bmp").count(), 1, "each file once");

    // A lost texture is named; the rest opens and the dance is drawn without it.
    let lost = kept.iter().find(|t| t.name.eq_ignore_ascii_case("eyeM2.bmp")).expect("eyeM2.bmp is kept").clone();
    let manifest = project::file::manifest_json(&p);
    let opened = project::file::from_manifest(&manifest, |h| p.blobs().get(h).cloned().filter(|_| *h != lost.blob)).expect("opens");
    assert_eq!(opened.missing.iter().map(|m| m.what.as_str()).collect::<Vec<_>>(), vec![format!("texture {} of MMD model miku_v2/miku_v2.pmd", lost.name).as_str()]);
    let mut partial = opened.project;
    let im = partial.imported(r.id).expect("bytes").expect("imports");
    assert_eq!(im.mesh.as_ref().expect("mesh").textures.len() + 1, reference.textures.len());
    assert!(im.warnings.iter().any(|w| w.contains(&lost.name)), "{:?}", im.warnings);
    // Undo of the import takes the model's files out of what a save writes.
    assert!(p.undo());
    assert!(p.referenced_blobs().iter().all(|h| p.blobs().get(h).is_some()));
    assert!(p.referenced_blobs().contains(&lost.blob), "the history still refers to it");
}

/// A project with the demo song, four bars of its own dance as the person's moves (a BVH the
/// engine wrote) and a Generate under *my moves* with a join goal no join of those meets, so it
/// leaves bars built-in with why (as `tests/tools/make_golden_project.rs` does).
fn project_with_builtin_whys() -> Project {
    let song = demo_song(22_050.0).expect("demo song");
    let env = envelope(&[song.samples.as_slice()], song.sample_rate_hz).expect("envelope");
    let mut p = Project::new();
    p.set_song("demo", None, &env, AnalysisOptions::default()).expect("song");
    p.generate().expect("generate");
    let dance = p.render_dance(&RenderOptions::default()).expect("render");
    let per_bar = dance.frame_count() / p.doc().dance.bars.len().max(1);
    let mine = odori_core::export::bvh::bvh(&dance.slice(0, 4 * per_bar + 1, "mine")).expect("bvh");
    p.add_source("mine.bvh", &mine, ImportOptions::default()).expect("a humanoid BVH");
    p.set_moves_source(MovesSource::Mine).expect("my moves");
    p.generate_with(&GenerateOptions { join_jump_goal: 0.05, ..GenerateOptions::default() }).expect("generate");
    p
}

#[test]
fn why_a_bar_is_built_in_is_kept_through_save_reopen_and_undo() {
    let mut p = project_with_builtin_whys();
    let whys = p.builtin_why();
    let with: Vec<usize> = (0..whys.len()).filter(|&i| whys[i].is_some()).collect();
    let mine = p.doc().dance.bars.iter().filter(|b| matches!(b.r#move, Some(MoveKey::Cut { .. }))).count();
    println!("{} bars: {mine} of the person's moves, {} built-in with a why: {:?}", whys.len(), with.len(), with.iter().map(|&i| whys[i].map(|(_, w)| w.words())).collect::<Vec<_>>());
    assert!(!with.is_empty(), "the strict goal leaves bars built-in with a why");
    // Saved and reopened: the same whys, on the same bars and moves.
    let mut q = project::open(&project::save(&p).expect("save")).expect("open").project;
    assert_eq!(q.builtin_why(), whys);
    // Setting a bar's move drops its why; undo brings it back, redo drops it again.
    let bar = with[0];
    let other = MoveKey::Builtin { r#move: builtin_moves()[3] };
    q.set(bar, &other).expect("set");
    assert_eq!(q.builtin_why()[bar], None);
    assert!(q.undo());
    assert_eq!(q.builtin_why(), whys);
    assert!(q.redo());
    assert_eq!(q.builtin_why()[bar], None);
    assert!(q.undo());
    // Clearing drops it too; undoing the Generate takes every why away with its bars.
    q.clear(bar).expect("clear");
    assert_eq!(q.builtin_why()[bar], None);
    assert!(q.undo() && q.undo());
    assert!(q.builtin_why().iter().all(Option::is_none), "the Generate before had no imported moves: no whys");
    assert!(q.redo());
    assert_eq!(q.builtin_why(), whys);
}

#[test]
fn camera_and_face_tracks_are_one_list_and_each_kind_keeps_its_order() {
    let (cam, face) = (tool::tiny_camera_vmd(), tool::tiny_face_vmd());
    let mut p = Project::new();
    p.add_face_track("lip1.vmd", &face, Some(0)).expect("face");
    p.add_camera("cam1.vmd", &cam, None).expect("camera");
    p.add_face_track("lip2.vmd", &face, Some(5)).expect("face");
    p.add_camera("cam2.vmd", &cam, Some(3)).expect("camera");
    let order: Vec<(TrackKind, &str)> = p.doc().mmd_tracks.iter().map(|t| (t.kind, t.file_name.as_str())).collect();
    assert_eq!(order, vec![(TrackKind::Face, "lip1.vmd"), (TrackKind::Camera, "cam1.vmd"), (TrackKind::Face, "lip2.vmd"), (TrackKind::Camera, "cam2.vmd")]);
    // Each kind's index is its place among its kind.
    assert_eq!(p.face_track(1).expect("second face").song_offset_frames, 5);
    assert_eq!(p.summary().cameras.iter().map(|c| c.file_name.as_str()).collect::<Vec<_>>(), vec!["cam1.vmd", "cam2.vmd"]);
    assert_eq!(p.summary().face_tracks.iter().map(|c| c.file_name.as_str()).collect::<Vec<_>>(), vec!["lip1.vmd", "lip2.vmd"]);
    // One blob for the same bytes, however many tracks keep them.
    assert_eq!(p.referenced_blobs().len(), 2);
    // Removing camera 0 leaves the faces where they were; undo puts it back in its place.
    let before = p.doc().clone();
    p.remove_camera(0).expect("remove");
    assert_eq!(p.doc().mmd_tracks.iter().map(|t| t.file_name.as_str()).collect::<Vec<_>>(), vec!["lip1.vmd", "lip2.vmd", "cam2.vmd"]);
    assert_eq!(p.camera_track(0).expect("cam2 is camera 0 now").keys.len(), 3);
    assert!(p.undo());
    assert_eq!(p.doc(), &before);
    // Out of range, per kind: typed, nothing changed.
    assert!(matches!(p.remove_face_track(2), Err(project::ProjectError::NoSuchFaceTrack { index: 2, count: 2 })));
    assert!(matches!(p.remove_track(TrackKind::Camera, 9), Err(project::ProjectError::NoSuchCamera { index: 9, count: 2 })));
    assert_eq!(p.doc(), &before);
    // Save and reopen: the same list.
    let q = project::open(&project::save(&p).expect("save")).expect("open").project;
    assert_eq!(q.doc().mmd_tracks, before.mmd_tracks);
}
