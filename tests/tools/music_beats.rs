//! Prints, as JSON, Odori's analysis of the shared music files (tempo, beats, downbeats and,
//! where ground truth exists, F-measures at ±70 ms): the "ours" side of
//! `tests/tools/compare_beats.sh`. Run: `cargo run --release -p odori-tests --example music_beats`.

#[path = "../native/music_audio.rs"]
mod music_audio;

use music_audio::*;
use odori_core::music::{analyze, f_measure, AnalysisOptions};

fn main() {
    let mut files = vec![DRUMS, TRUMPET];
    files.extend(FULL_TRACKS);
    let (ref_beats, ref_downbeats) = read_beats(DRUMS_BEATS);
    let mut out = Vec::new();
    for rel in files {
        let audio = decode_data(rel);
        let env = audio.envelope().expect("envelope");
        let t = std::time::Instant::now();
        let mut options = AnalysisOptions::default();
        if let Some(v) = std::env::var("MUSIC_TIGHTNESS").ok().and_then(|v| v.parse().ok()) {
            options.tightness = v;
        }
        let result = analyze(&env, &options);
        let secs = t.elapsed().as_secs_f64();
        let mut entry = serde_json::json!({ "file": rel, "durationSecs": audio.duration_secs(), "analysisSecs": secs });
        match result {
            Ok(g) => {
                entry["bpm"] = g.bpm.into();
                entry["beats"] = g.beat_times_secs.len().into();
                entry["firstDownbeatSecs"] = g.first_downbeat_secs.into();
                entry["bars"] = g.bars.len().into();
                if rel == DRUMS {
                    entry["beatF"] = f_measure(&g.beat_times_secs, &ref_beats, 0.07).into();
                    entry["downbeatF"] = f_measure(&g.downbeat_times_secs, &ref_downbeats, 0.07).into();
                }
                if std::env::var_os("MUSIC_BEATS_TIMES").is_some() {
                    entry["beatTimesSecs"] = serde_json::to_value(&g.beat_times_secs).unwrap_or_default();
                    entry["downbeatTimesSecs"] = serde_json::to_value(&g.downbeat_times_secs).unwrap_or_default();
                }
            }
            Err(e) => entry["error"] = e.to_string().into(),
        }
        out.push(entry);
    }
    println!("{}", serde_json::to_string_pretty(&out).unwrap_or_default());
}
