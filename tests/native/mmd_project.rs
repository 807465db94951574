//! An imported VMD dance as a source of the project (issue 28 item 1), on the real WAVEFILE
//! dance: `Project::add_source` takes the VMD like a BVH (posed on the standard MMD skeleton,
//! the song offset kept in its import options), cuts it into segments, Generate with *my moves*
//! fills bars with them, and the project saved to `.odori` bytes and opened again holds the
//! same source, the same offset and renders the same dance. A bad VMD is a typed error and
//! leaves the project as it was.

use odori_core::choreo::{MovesSource, RenderOptions};
use odori_core::music::AnalysisOptions;
use odori_core::project::{self, BarKind, MoveKey, Project};
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
