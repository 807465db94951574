//! The person's library, shared by the native tests and the benchmark that dance with the
//! moves a person imported (`choreo_my_moves`, `choreo_join_points`, `choreo_blended_cost`,
//! `choreo_join_cost`, `tests/bench/choreo_person.rs`): one list of the person's files and one
//! way they are loaded, so the tests' figures are all on the same library; the songs they
//! dance to ([`songs`]); and a library whose table is built with a given jump term ([`with_table`]).
#![allow(dead_code)]

#[path = "music_audio.rs"]
mod music_audio;

use odori_core::bars::Bar;
use odori_core::choreo::{bar_counts, ClipSummary, FillWeights, JumpTerm, SegmentError, SegmentLibrary, SegmentOptions, TableScope, TransitionTable};
use odori_core::import::{import_bytes, ImportOptions};
use odori_core::music::demo_song::{demo_song_with, DemoSongOptions};
use odori_core::music::{envelope, RmsEnvelope};
use odori_core::Clip;
use odori_tests::{fps_override_for, read};

/// The person's files, in the order they are added ([`odori_tests::person_files`]: every BVH
/// take in ../shared/data/mocap but the martial-arts takes and modern dance's 005_01, then
/// RobotExpressive's glTF).
pub fn person_files() -> Vec<String> {
    odori_tests::person_files()
}

/// The built-in moves and the person's files (`half`: every other one of [`person_files`],
/// `Some(0)` or `Some(1)`; `None`: all), each file imported at its own frame rate and cut at
/// its own tempo with the default options; `on_clip` hears how each clip was taken (a clip the
/// segmenter refuses, too short or not humanoid, is simply not in the library). Returns the
/// library and how many files went into it.
pub fn person_library_with(half: Option<usize>, mut on_clip: impl FnMut(&str, &Clip, &Result<ClipSummary, SegmentError>)) -> (SegmentLibrary, usize) {
    let mut lib = SegmentLibrary::builtin();
    let files: Vec<String> = person_files().into_iter().enumerate().filter(|(i, _)| half.is_none_or(|h| i % 2 == h)).map(|(_, f)| f).collect();
    for rel in &files {
        let opts = ImportOptions { fps_override: fps_override_for(rel), ..Default::default() };
        let imp = import_bytes(rel, &read(rel), &opts).unwrap_or_else(|e| panic!("{rel}: {e}"));
        for clip in imp.clips.iter().filter(|c| !rel.ends_with(".glb") || c.name == "Dance") {
            let taken = lib.add_clip(clip, &imp.humanoid, &imp.status, &SegmentOptions::default());
            on_clip(rel, clip, &taken);
        }
    }
    (lib, files.len())
}

/// [`person_library_with`], quietly.
pub fn person_library(half: Option<usize>) -> (SegmentLibrary, usize) {
    person_library_with(half, |_, _, _| {})
}

/// The songs the person's dances are made for: every full track of ../shared/data/music, the
/// trumpet and the drum take, then the demo song in 4 (100 BPM; 90→130 BPM) and in 3 (150, 108,
/// 96→120 BPM), each with its envelope as the browser host computes it.
pub fn songs() -> Vec<(String, RmsEnvelope)> {
    let mut out: Vec<(String, RmsEnvelope)> = music_audio::FULL_TRACKS
        .iter()
        .chain([&music_audio::TRUMPET, &music_audio::DRUMS])
        .map(|rel| (rel.to_string(), music_audio::decode_data(rel).envelope().unwrap_or_else(|e| panic!("{rel}: {e}"))))
        .collect();
    for (bpb, bpm, end) in [(4u32, 100.0f32, 100.0f32), (4, 90.0, 130.0), (3, 150.0, 150.0), (3, 108.0, 108.0), (3, 96.0, 120.0)] {
        let song = demo_song_with(22050.0, &DemoSongOptions { beats_per_bar: bpb, bpm, end_bpm: end }).expect("demo song");
        out.push((format!("demo in {bpb}, {bpm}→{end} BPM"), envelope(&[&song.samples], 22050.0).expect("envelope")));
    }
    out
}

/// A copy of `lib` whose cached table (the blocks `bars` need) is built with `term`: Generate on
/// it runs on that cost, every stage as the product's (the term-on comparisons).
pub fn with_table(lib: &SegmentLibrary, bars: &[Bar], term: JumpTerm) -> SegmentLibrary {
    let copy = lib.clone();
    copy.drop_table();
    let scope = TableScope::for_bar_counts(&bar_counts(lib, bars));
    let penalty = FillWeights::default().repeat_penalty;
    assert!(copy.install_table_for(TransitionTable::for_scope_with_term(lib, penalty, &scope, term), &scope), "table refused");
    copy
}
