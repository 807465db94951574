//! A lip-sync VMD as the project's face track (issue 28 item 2, `.odori` schema 6), on real face
//! keys: WAVEFILE's 1,279 morph keys written by the engine's own VMD writer into a face-only VMD
//! (no bone keys: what MMD users load beside a dance). `Project::add_face_track` keeps it as
//! given; after save and reopen its keys equal the VMD's; its weights on miku_v2 at a song time
//! equal `mmd::morph`'s of the same keys at the motion frame, laid over a dance's own face keys
//! only for the morphs the track keys; a generated dance exported with it reads back with the
//! track's keys on the song's timeline; a bad file is a typed error naming it, with the project
//! unchanged; `import_files` offers a face-only VMD as a face track instead of refusing it.

use odori_core::choreo::RenderOptions;
use odori_core::import::vmd::{self, MorphKey, Vmd, VmdVersion};
use odori_core::mmd::face_track::{layer_keys, FaceTrack, LayeredFaces};
use odori_core::mmd::morph::FaceMorphs;
use odori_core::music::{demo_song, envelope, AnalysisOptions};
use odori_core::project::{self, Project, TrackKind};
use odori_tests::read;

const WAVEFILE: &str = "mmd/motion/wavefile_v2.vmd";
const MIKU: &str = "mmd/miku_v2/miku_v2.pmd";

/// WAVEFILE's morph keys as a face-only VMD (written by the engine's VMD writer).
fn lip_sync_of_wavefile() -> (Vec<MorphKey>, Vec<u8>) {
    let wave = vmd::read("wavefile_v2.vmd", &read(WAVEFILE)).expect("WAVEFILE reads");
    assert!(wave.morph_keys.len() > 1000 && !wave.bone_keys.is_empty(), "{} morph keys", wave.morph_keys.len());
    let face = Vmd { version: VmdVersion::V2, model_name: wave.model_name.clone(), bone_keys: vec![], morph_keys: wave.morph_keys.clone(), camera_keys: vec![], light_keys: vec![], self_shadow_keys: vec![], property_keys: vec![] };
    let bytes = odori_core::export::vmd::write("lip.vmd", &face).expect("writes");
    (wave.morph_keys, bytes)
}

fn miku() -> odori_core::import::mmd_model::MmdModel {
    odori_core::import::mmd_model::read_model("miku_v2.pmd", &read(MIKU)).expect("miku_v2 reads")
}

#[test]
fn a_lip_sync_vmd_is_a_face_track_kept_after_save_and_reopen() {
    let (keys, bytes) = lip_sync_of_wavefile();
    let mut p = Project::new();
    let track = p.add_face_track("lip.vmd", &bytes, Some(160)).expect("a face-only VMD is a face track");
    assert_eq!(track.keys, keys, "the VMD's keys, in file order");
    assert_eq!(track.song_offset_frames, 160);
    let doc = p.doc().clone();
    assert_eq!(doc.tracks(TrackKind::Face).count(), 1);
    assert!(p.blobs().get(&doc.mmd_tracks[0].blob).is_some_and(|b| **b == bytes[..]), "its bytes are kept as given");
    assert_eq!(p.summary().face_tracks.iter().map(|f| f.file_name.as_str()).collect::<Vec<_>>(), vec!["lip.vmd"]);
    // One undo step: undo takes it back, redo restores it.
    assert_eq!(p.undo_history().len(), 1);
    assert!(p.undo());
    assert!(p.doc().tracks(TrackKind::Face).next().is_none());
    assert!(p.redo());
    assert_eq!(p.doc(), &doc);
    // Saved and opened again: the same keys, read from the kept bytes.
    let mut q = project::open(&project::save(&p).expect("save")).expect("open").project;
    assert_eq!(q.doc().tracks(TrackKind::Face).collect::<Vec<_>>(), doc.tracks(TrackKind::Face).collect::<Vec<_>>());
    let again = q.face_track(0).expect("the reopened track");
    assert_eq!(again, track);
    println!("lip.vmd (WAVEFILE's face keys, no bone keys): {} keys of {} morphs kept, equal after save and reopen", again.keys.len(), again.morph_names().len());
    // Removing is one undo step too.
    q.remove_face_track(0).expect("remove");
    assert!(q.doc().tracks(TrackKind::Face).next().is_none());
    assert!(q.undo());
    assert_eq!(q.face_track(0).expect("back"), track);
    // With its bytes missing the rest opens and the track says what is gone.
    let manifest = project::file::manifest_json(&p);
    let opened = project::file::from_manifest(&manifest, |h| p.blobs().get(h).cloned().filter(|_| *h != doc.mmd_tracks[0].blob)).expect("opens");
    assert_eq!(opened.missing.iter().map(|m| m.what.as_str()).collect::<Vec<_>>(), vec!["face track lip.vmd"]);
    assert_eq!(opened.project.face_track(0).expect_err("no bytes, no track").kind(), "missing-blob");
}

#[test]
fn a_face_tracks_weights_at_a_song_time_are_the_morph_weights_of_its_keys() {
    let (keys, bytes) = lip_sync_of_wavefile();
    let model = miku();
    let names: Vec<&str> = model.morphs.iter().map(|m| m.name.as_str()).collect();
    let mut p = Project::new();
    p.add_face_track("lip.vmd", &bytes, Some(160)).expect("face track");
    let track = project::open(&project::save(&p).expect("save")).expect("open").project.face_track(0).expect("track");
    let direct = FaceMorphs::new(&model, &keys);
    let layered = LayeredFaces::new(&names, None, &[&track]);
    // WAVEFILE also keys "base" (the PMD's base morph, no morph of the model as read): not named.
    assert!(keys.iter().any(|k| k.name == "base"));
    assert!(layered.missing.is_empty(), "WAVEFILE keys only miku_v2's morphs: {:?}", layered.missing);
    let mut checked = 0;
    let mut any_a = 0;
    let a = names.iter().position(|n| *n == "あ").expect("miku_v2 has あ");
    for k in 0..400 {
        let song_secs = k as f32 * 0.2137;
        let want = direct.weights_at(160.0 + song_secs * 30.0);
        assert_eq!(layered.weights_at(0.0, song_secs), want, "at song time {song_secs} s");
        any_a += usize::from(want.iter().any(|&(m, w)| m == a && w > 0.1));
        checked += 1;
    }
    assert!(any_a > 20, "あ is open at {any_a} of the {checked} times");
    println!("face track on miku_v2: weights equal mmd::morph's at {checked} song times (あ > 0.1 at {any_a})");

    // Over a dance's own face keys (the same WAVEFILE as the dance VMD): a track keying あ only
    // (held shut) overrides あ and nothing else.
    let shut = FaceTrack { source: "shut.vmd".into(), keys: vec![MorphKey { name: "あ".into(), frame: 0, weight: 0.0 }], song_offset_frames: 0 };
    let over = LayeredFaces::new(&names, Some((&keys, 160)), &[&shut]);
    let (mut a_was_open, mut others) = (0, 0);
    for k in 0..400 {
        let frame = 160.0 + k as f32 * 6.4;
        let own = direct.weights_at(frame);
        let got = over.weights_at(frame, (frame - 160.0) / 30.0);
        a_was_open += usize::from(own.iter().any(|&(m, w)| m == a && w > 0.0));
        assert!(got.iter().all(|&(m, _)| m != a), "あ is held shut by the track at frame {frame}");
        let own_others: Vec<_> = own.into_iter().filter(|&(m, _)| m != a).collect();
        others += own_others.len();
        assert_eq!(got, own_others, "every other morph plays the dance's own keys at frame {frame}");
    }
    assert!(a_was_open > 20 && others > 100, "control: the dance opens あ at {a_was_open} frames ({others} other weights)");
    // On a model without those morphs: ignored, the missing morphs named.
    let none = LayeredFaces::new(&["まばたき_x", "笑い_x"], None, &[&track]);
    assert!(none.is_empty() && none.missing.contains(&"あ".to_string()), "{:?}", none.missing);
}

#[test]
fn a_generated_dance_exported_with_its_face_track_reads_back_with_the_tracks_keys() {
    use odori_core::mmd::export::clip_to_vmd;
    use odori_core::mmd::MmdRig;
    let (keys, bytes) = lip_sync_of_wavefile();
    let song = demo_song(22_050.0).expect("demo song");
    let env = envelope(&[song.samples.as_slice()], song.sample_rate_hz).expect("envelope");
    let mut p = Project::new();
    p.set_song("demo", None, &env, AnalysisOptions::default()).expect("song");
    p.generate().expect("generate");
    p.add_face_track("lip.vmd", &bytes, Some(160)).expect("face track");
    let dance = p.render_dance(&RenderOptions::default()).expect("render");
    let track = p.face_track(0).expect("track");
    let model = miku();
    let rig = MmdRig::from_model(&model).expect("rig");
    let mut out = clip_to_vmd(&dance, &rig, &model.name).expect("export");
    assert!(out.morph_keys.is_empty(), "a generated dance has no face keys of its own");
    out.morph_keys = layer_keys(std::mem::take(&mut out.morph_keys), &track.keys_from(0));
    let back = vmd::read("dance.vmd", &odori_core::export::vmd::write("dance.vmd", &out).expect("write")).expect("read back");
    // Every key from the song's start on, on the song's timeline; plus one at frame 0 for each
    // morph keyed across it.
    let from_160: Vec<(String, u32, f32)> = keys.iter().filter(|k| k.frame >= 160).map(|k| (k.name.clone(), k.frame - 160, k.weight)).collect();
    let got: Vec<(String, u32, f32)> = back.morph_keys.iter().map(|k| (k.name.clone(), k.frame, k.weight)).collect();
    let added = got.len() - from_160.len();
    assert_eq!(got[added..], from_160[..]);
    assert!(got[..added].iter().all(|k| k.1 == 0));
    // The file plays the track's weights at every song frame, its first included.
    let (a, b) = (FaceMorphs::new(&model, &back.morph_keys), FaceMorphs::new(&model, &keys));
    let frames = (dance.duration_secs() * 30.0) as u32;
    for f in 0..=frames {
        let (x, y) = (a.weights_at(f as f32), b.weights_at(160.0 + f as f32));
        assert_eq!(x.len(), y.len(), "frame {f}");
        for (p, q) in x.iter().zip(&y) {
            assert!(p.0 == q.0 && (p.1 - q.1).abs() < 1e-6, "frame {f}: {p:?} against {q:?}");
        }
    }
    println!("generated dance ({:.1} s) exported with its face track: {} morph keys ({} added at frame 0), weights equal the track's at all {} song frames", dance.duration_secs(), got.len(), added, frames + 1);
}

#[test]
fn a_file_that_is_no_face_track_is_refused_naming_it_and_the_project_is_unchanged() {
    let (_, bytes) = lip_sync_of_wavefile();
    let mut p = Project::new();
    let before = p.doc().clone();
    // A camera VMD: no morph keys.
    let e = p.add_face_track("cam.vmd", &read("mmd/motion/tokino_kakera_cam.vmd"), None).expect_err("no morph keys");
    assert_eq!(e.kind(), "mmd-no-morph-keys", "{e}");
    assert!(e.to_string().contains("cam.vmd"), "{e}");
    // Cut short inside its morph keys.
    let e = p.add_face_track("cut.vmd", &bytes[..bytes.len() / 2], None).expect_err("truncated");
    assert!(matches!(e.kind(), "mmd-truncated" | "mmd-count-too-large"), "{}: {e}", e.kind());
    assert!(e.to_string().contains("cut.vmd"), "{e}");
    // Not a VMD.
    let e = p.add_face_track("words.vmd", b"not a vmd at all, just some text", None).expect_err("not a VMD");
    assert_eq!(e.kind(), "mmd-bad-magic", "{e}");
    assert!(e.to_string().contains("words.vmd"), "{e}");
    assert_eq!(p.doc(), &before);
    assert!(p.undo_history().is_empty());
    assert_eq!(p.remove_face_track(0).expect_err("none").kind(), "not-found");
    assert_eq!(p.face_track(0).expect_err("none").kind(), "not-found");
}

#[test]
fn import_files_offers_a_face_only_vmd_as_a_face_track() {
    use odori_core::mmd::files::{import_files, MmdFilesOptions};
    let (keys, bytes) = lip_sync_of_wavefile();
    let r = import_files(&[("lip.vmd".into(), bytes)], &[], &MmdFilesOptions { song_offset_frames: Some(160), ..Default::default() });
    assert!(r.problems.is_empty() && r.motions.is_empty(), "{:?}", r.problems);
    assert_eq!(r.face_tracks.len(), 1);
    assert_eq!((r.face_tracks[0].keys.len(), r.face_tracks[0].song_offset_frames), (keys.len(), 160));
    // Control: the dance VMD itself is a motion, not a face track.
    let r = import_files(&[("wavefile_v2.vmd".into(), read(WAVEFILE))], &[], &MmdFilesOptions::default());
    assert_eq!((r.motions.len(), r.face_tracks.len()), (1, 0));
}
