//! The generated dances the bit-for-bit fixture fixes (issue 27's acceptance), computed the same
//! way by the test (`dance_fixture.rs`) and by the tool that records the golden file
//! (`tools/make_golden_dances.rs`): each piece's grid by the core's analysis, the dance
//! generated through the project (the one dance document) over the built-in moves plus the
//! shared humanoid dance clips (every CMU salsa and Indian BVH, cut at their detected tempo, as
//! `choreo_beats` and the `choreo_quality` bench build the library), at three settings, each
//! bar's move by its stable key and the rendered dance's (feet held, the product's default)
//! joint positions at 10 times.

#[path = "music_audio.rs"]
mod music_audio;

use odori_core::music::demo_song::{demo_song, demo_song_with, DemoSongOptions};
use odori_core::music::{envelope, AnalysisOptions, RmsEnvelope};
use odori_core::project::Project;
use odori_core::choreo::RenderOptions;
use odori_core::ImportOptions;
use odori_tests::{all_bvh, fps_override_for, read};
use serde_json::{json, Value};

/// Joint positions are recorded at this many times, evenly spaced over the dance.
pub const TIMES: usize = 10;

/// The settings each piece is danced at: the defaults, ρ = 0.9, music weight 0.
pub const SETTINGS: [&str; 3] = ["default", "rho 0.9", "music weight 0"];

/// The pieces: every song in music/, the drum take, and three demo pieces (the demo song, a
/// waltz at 150 BPM, a 4/4 ramp from 90 to 130 BPM, as `choreo_beats` makes them).
pub fn pieces() -> Vec<(String, RmsEnvelope)> {
    let mut songs: Vec<(String, RmsEnvelope)> = music_audio::FULL_TRACKS
        .iter()
        .chain([&music_audio::TRUMPET, &music_audio::DRUMS])
        .map(|rel| (rel.to_string(), music_audio::decode_data(rel).envelope().unwrap_or_else(|e| panic!("{rel}: {e}"))))
        .collect();
    let env = |x: &[f32]| envelope(&[x], 22050.0).expect("demo envelope");
    songs.push(("demo song".into(), env(&demo_song(22050.0).expect("demo song").samples)));
    for (bpb, bpm, end) in [(3u32, 150.0f32, 150.0f32), (4, 90.0, 130.0)] {
        let piece = demo_song_with(22050.0, &DemoSongOptions { beats_per_bar: bpb, bpm, end_bpm: end }).expect("demo piece");
        songs.push((format!("demo in {bpb}, {bpm}→{end} BPM"), env(&piece.samples)));
    }
    songs
}

/// A project holding the shared humanoid dance clips (the library is built once, here, and
/// shared by every piece), and the files in the order they were added (their source ids).
pub fn project_with_clips() -> (Project, Vec<String>) {
    let mut project = Project::new();
    let files: Vec<String> = all_bvh().into_iter().filter(|r| r.contains("cmu-salsa") || r.contains("cmu-indian")).collect();
    for rel in &files {
        let opts = ImportOptions { fps_override: fps_override_for(rel), ..Default::default() };
        project.add_source(rel, &read(rel), opts).unwrap_or_else(|e| panic!("{rel}: {e}"));
    }
    (project, files)
}

/// The generated dance of the project's current song at its current settings: each bar's move
/// key, and the joint positions (metres) at [`TIMES`] evenly spaced frames of the rendered dance.
fn dance(project: &mut Project, piece: &str, setting: &str) -> Value {
    project.generate().unwrap_or_else(|e| panic!("{piece}, {setting}: generate: {e}"));
    let moves: Vec<Value> = project
        .doc()
        .dance
        .bars
        .iter()
        .map(|b| b.r#move.as_ref().map_or(Value::Null, |k| Value::String(k.id())))
        .collect();
    let clip = project.render_dance(&RenderOptions::default()).unwrap_or_else(|e| panic!("{piece}, {setting}: render: {e}"));
    let n = clip.frame_count();
    let frames: Vec<usize> = (0..TIMES).map(|i| (i * (n - 1) + (TIMES - 1) / 2) / (TIMES - 1)).collect();
    let positions: Vec<Value> = frames
        .iter()
        .map(|&f| Value::Array(clip.world_positions(f).iter().map(|p| json!([p.x, p.y, p.z])).collect()))
        .collect();
    json!({ "setting": setting, "moves": moves, "fps": clip.fps, "frames": frames, "positions": positions })
}

/// Every piece danced at every setting, as the golden file holds it.
pub fn all_dances() -> Value {
    let (mut project, files) = project_with_clips();
    let defaults = project.fill_weights();
    let default_rho = project.doc().dance.settings.rho;
    let mut out = Vec::new();
    for (name, env) in pieces() {
        project.set_song(&name, None, &env, AnalysisOptions::default()).unwrap_or_else(|e| panic!("{name}: {e}"));
        let mut dances = Vec::new();
        for setting in SETTINGS {
            let (rho, music) = match setting {
                "default" => (default_rho, defaults.music_weight),
                "rho 0.9" => (0.9, defaults.music_weight),
                _ => (default_rho, 0.0),
            };
            project.set_rho(rho).unwrap_or_else(|e| panic!("{name}: {e}"));
            project.set_music_weight(music).unwrap_or_else(|e| panic!("{name}: {e}"));
            // Every bar emptied first: nothing of the last song's (or setting's) dance is read.
            project.begin_group();
            for bar in 0..project.doc().dance.bars.len() {
                project.clear(bar).unwrap_or_else(|e| panic!("{name}: {e}"));
            }
            project.end_group();
            dances.push(dance(&mut project, &name, setting));
        }
        out.push(json!({ "piece": name, "bars": project.doc().dance.bars.len(), "dances": dances }));
    }
    json!({ "sources": files, "times": TIMES, "pieces": out })
}
