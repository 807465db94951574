//! Song analysis in wasm. The input is the product's own demo song, rendered and enveloped inside wasm, its envelope
//! looped to 180 s: a 3-minute song. The native bench (`tests/bench/music_analysis.rs`) times
//! the same input, so the two figures compare directly.

use std::cell::RefCell;

use odori_core::music::{analyze, demo_song, envelope, AnalysisOptions, RmsEnvelope};

thread_local! {
    static SONG: RefCell<Option<RmsEnvelope>> = const { RefCell::new(None) };
}

/// Loops an envelope to `secs` seconds.
pub fn looped(env: &RmsEnvelope, secs: f32) -> RmsEnvelope {
    let frames = (secs / env.hop_secs).round() as usize;
    RmsEnvelope { hop_secs: env.hop_secs, bands: env.bands.iter().map(|b| b.iter().cycle().copied().take(frames).collect()).collect() }
}

/// Renders the demo song at 44.1 kHz, computes its envelope and loops it to 180 s. Returns the
/// frame count (0 on failure).
#[no_mangle]
pub extern "C" fn prepare() -> u32 {
    let Ok(song) = demo_song(44100.0) else { return 0 };
    let Ok(env) = envelope(&[&song.samples], song.sample_rate_hz) else { return 0 };
    let env = looped(&env, 180.0);
    let frames = env.frame_count() as u32;
    SONG.with(|s| *s.borrow_mut() = Some(env));
    frames
}

/// Renders the demo song only (to time it). Returns its sample count.
#[no_mangle]
pub extern "C" fn render_demo() -> u32 {
    demo_song(44100.0).map_or(0, |s| s.samples.len() as u32)
}

/// Envelope of the demo song only (to time the Rust fallback of the host's RMS step). Returns
/// the frame count.
#[no_mangle]
pub extern "C" fn demo_envelope() -> u32 {
    let Ok(song) = demo_song(44100.0) else { return 0 };
    envelope(&[&song.samples], song.sample_rate_hz).map_or(0, |e| e.frame_count() as u32)
}

/// Analyses the prepared 3-minute envelope once. Returns the tempo (BPM), or -1 on failure.
#[no_mangle]
pub extern "C" fn analyze_once() -> f32 {
    SONG.with(|s| match s.borrow().as_ref() {
        Some(env) => analyze(env, &AnalysisOptions::default()).map_or(-1.0, |g| g.bpm),
        None => -1.0,
    })
}
