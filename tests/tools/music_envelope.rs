//! The native side of tests/tools/webaudio_check: `dump <file under ../shared/data>` prints the
//! envelope the Rust twin computes (JSON `RmsEnvelope`); `analyze <envelope.json>` analyses an
//! envelope (e.g. one a browser computed) and prints the grid (JSON `SongGrid`).
//! Run: `cargo run --release -p odori-tests --example music_envelope -- dump beats/….flac`.

#[path = "../native/music_audio.rs"]
mod music_audio;

use odori_core::music::{analyze, AnalysisOptions, RmsEnvelope};

fn main() {
    let args: Vec<String> = std::env::args().collect();
    match (args.get(1).map(String::as_str), args.get(2)) {
        (Some("dump"), Some(rel)) => {
            let env = music_audio::decode_data(rel).envelope().expect("envelope");
            println!("{}", serde_json::to_string(&env).expect("json"));
        }
        (Some("analyze"), Some(path)) => {
            let text = std::fs::read_to_string(path).expect("read envelope json");
            let env: RmsEnvelope = serde_json::from_str(&text).expect("parse envelope json");
            let grid = analyze(&env, &AnalysisOptions::default()).expect("analysis");
            println!("{}", serde_json::to_string(&grid).expect("json"));
        }
        _ => {
            eprintln!("usage: music_envelope dump <data-relative file> | analyze <envelope.json>");
            std::process::exit(2);
        }
    }
}
