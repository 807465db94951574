//! Prints the native analysis of one shared audio file as JSON (`SongGrid` plus the envelope's
//! hop), decoded with symphonia and enveloped exactly as the browser host does. The browser
//! test compares the page's bars with this. Run:
//! `cargo run -q -p odori-tests --example song_grid -- beats/drummer1_…flac`.

#[path = "../native/music_audio.rs"]
mod music_audio;

use odori_core::music::{analyze, AnalysisOptions};

fn main() {
    let rel = std::env::args().nth(1).expect("usage: song_grid PATH-UNDER-../shared/data");
    let audio = music_audio::decode_data(&rel);
    let env = audio.envelope().expect("envelope");
    let grid = analyze(&env, &AnalysisOptions::default()).expect("analysis");
    let out = serde_json::json!({ "file": rel, "hopSecs": env.hop_secs, "grid": grid });
    println!("{out}");
}
