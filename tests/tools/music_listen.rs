//! Listening check of the grid (issue 4): writes WAV files under tests/artifacts/ — the demo
//! song, and each shared music file mixed (mono) with a click on every analysed beat (a higher
//! click on downbeats) — so a person can hear whether the grid sits on the music.
//! Run: `cargo run --release -p odori-tests --example music_listen`.

#[path = "../native/music_audio.rs"]
mod music_audio;

use music_audio::*;
use odori_core::music::{analyze, demo_song, AnalysisOptions};

/// Writes mono 16-bit PCM.
fn write_wav(path: &std::path::Path, samples: &[f32], sample_rate_hz: u32) -> std::io::Result<()> {
    let data_len = (samples.len() * 2) as u32;
    let mut out = Vec::with_capacity(44 + samples.len() * 2);
    out.extend_from_slice(b"RIFF");
    out.extend_from_slice(&(36 + data_len).to_le_bytes());
    out.extend_from_slice(b"WAVEfmt ");
    out.extend_from_slice(&16u32.to_le_bytes());
    out.extend_from_slice(&1u16.to_le_bytes());
    out.extend_from_slice(&1u16.to_le_bytes());
    out.extend_from_slice(&sample_rate_hz.to_le_bytes());
    out.extend_from_slice(&(sample_rate_hz * 2).to_le_bytes());
    out.extend_from_slice(&2u16.to_le_bytes());
    out.extend_from_slice(&16u16.to_le_bytes());
    out.extend_from_slice(b"data");
    out.extend_from_slice(&data_len.to_le_bytes());
    for &s in samples {
        out.extend_from_slice(&((s.clamp(-1.0, 1.0) * 32767.0) as i16).to_le_bytes());
    }
    std::fs::write(path, out)
}

fn add_click(mix: &mut [f32], fs: f32, time_secs: f32, hz: f32, gain: f32) {
    let start = (time_secs * fs) as usize;
    for i in 0..(0.03 * fs) as usize {
        let t = i as f32 / fs;
        if let Some(s) = mix.get_mut(start + i) {
            *s += gain * (2.0 * std::f32::consts::PI * hz * t).sin() * (-t / 0.008).exp();
        }
    }
}

fn main() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("artifacts");
    std::fs::create_dir_all(&dir).expect("artifacts dir");
    let song = demo_song(44100.0).expect("demo");
    write_wav(&dir.join("demo_song.wav"), &song.samples, 44100).expect("write");
    println!("{}", dir.join("demo_song.wav").display());
    let mut files = vec![DRUMS, TRUMPET];
    files.extend(FULL_TRACKS);
    for rel in files {
        let audio = decode_data(rel);
        let g = analyze(&audio.envelope().expect("envelope"), &AnalysisOptions::default()).expect("analysis");
        let n = audio.channels[0].len();
        let mut mix: Vec<f32> =
            (0..n).map(|i| 0.7 * audio.channels.iter().map(|c| c[i]).sum::<f32>() / audio.channels.len() as f32).collect();
        for &t in &g.beat_times_secs {
            let down = g.downbeat_times_secs.contains(&t);
            add_click(&mut mix, audio.sample_rate_hz, t, if down { 1760.0 } else { 1100.0 }, if down { 0.5 } else { 0.3 });
        }
        let name = rel.rsplit('/').next().unwrap_or(rel).split('.').next().unwrap_or("song");
        let path = dir.join(format!("{name}.grid.wav"));
        write_wav(&path, &mix, audio.sample_rate_hz as u32).expect("write");
        println!("{} ({:.2} BPM)", path.display(), g.bpm);
    }
}
