//! Prints the native analysis of one shared audio file as JSON (`SongGrid` plus the envelope's
//! hop), decoded with symphonia and enveloped exactly as the browser host does. The browser
//! test compares the page's bars with this. Run:
//! `cargo run -q -p odori-tests --example song_grid -- beats/drummer1_…flac`; with `--golden`,
//! in the layout of the reviewed golden file `tests/golden/music_drums_grid.json`.

#[path = "../native/music_audio.rs"]
mod music_audio;

use odori_core::music::{analyze, AnalysisOptions};

fn main() {
    let rel = std::env::args().nth(1).expect("usage: song_grid PATH-UNDER-../shared/data");
    let audio = music_audio::decode_data(&rel);
    let env = audio.envelope().expect("envelope");
    let grid = analyze(&env, &AnalysisOptions::default()).expect("analysis");
    if std::env::args().any(|a| a == "--golden") {
        // The layout of tests/golden/music_drums_grid.json, for a person to review and commit
        // (the tests never write golden files).
        let json = serde_json::json!({
            "file": rel,
            "hopSecs": grid.loudness.hop_secs,
            "bpm": grid.bpm,
            "beatTimesSecs": grid.beat_times_secs,
            "downbeatTimesSecs": grid.downbeat_times_secs,
            "bars": grid.bars,
        });
        println!("{}", serde_json::to_string_pretty(&json).expect("json"));
        return;
    }
    let out = serde_json::json!({ "file": rel, "hopSecs": env.hop_secs, "grid": grid });
    println!("{out}");
}
