//! Benchmark (issue 4): core song analysis of a 3-minute song, native. The song is a real full
//! track from ../shared/data/music (Let's Go Fishin', 133 s) decoded and looped to 180 s, so it
//! has one tempo like a real 3-minute song. Printed: the envelope (the host's job, here in Rust as the fallback path),
//! the analysis from the envelope (the core's job), each grid correction, and the ratio of
//! analysis time to the baseline of one plain pass over the envelope (summing every value),
//! measured in the same run. Run: `cargo bench -p odori-tests --bench music_analysis`.

#[path = "../native/music_audio.rs"]
mod music_audio;

use std::time::Instant;

use music_audio::*;
use odori_core::music::{analyze, envelope, AnalysisOptions, GridCorrection};

/// Median wall time of `runs` calls, seconds.
fn median_secs<T>(runs: usize, mut f: impl FnMut() -> T) -> f64 {
    let mut times: Vec<f64> = (0..runs)
        .map(|_| {
            let t = Instant::now();
            std::hint::black_box(f());
            t.elapsed().as_secs_f64()
        })
        .collect();
    times.sort_by(f64::total_cmp);
    times[times.len() / 2]
}

fn main() {
    let a = decode_data(FULL_TRACKS[1]);
    let fs = a.sample_rate_hz;
    let len = (180.0 * fs) as usize;
    let channels: Vec<Vec<f32>> = a.channels.iter().map(|x| x.iter().cycle().copied().take(len).collect()).collect();
    let refs: Vec<&[f32]> = channels.iter().map(Vec::as_slice).collect();
    println!("song: {:.1} s, {} channels at {} Hz", channels[0].len() as f32 / fs, channels.len(), fs);

    let env_secs = median_secs(5, || envelope(&refs, fs).expect("envelope"));
    let env = envelope(&refs, fs).expect("envelope");
    let options = AnalysisOptions::default();
    let analysis_secs = median_secs(21, || analyze(&env, &options).expect("analysis"));
    let baseline_secs = median_secs(21, || env.bands.iter().flatten().map(|&v| f64::from(v)).sum::<f64>());
    let grid = analyze(&env, &options).expect("analysis");
    let bpm_secs = median_secs(101, || grid.with_bpm(100.0).expect("bpm"));
    let shift_secs = median_secs(101, || grid.with_first_downbeat(grid.beat_times_secs[1]).expect("shift"));
    let combined = GridCorrection { bpm: Some(128.0), beats_per_bar: Some(3), first_downbeat_secs: Some(1.0), ..Default::default() };
    let combined_secs = median_secs(101, || grid.corrected(&combined).expect("correction"));

    let demo_secs = median_secs(3, || odori_core::music::demo_song(44100.0).expect("demo"));
    // The wasm bench's input (tests/wasm_bench): the demo song's envelope looped to 180 s.
    let demo = odori_core::music::demo_song(44100.0).expect("demo");
    let demo_env = envelope(&[&demo.samples], demo.sample_rate_hz).expect("demo envelope");
    let frames = (180.0 / demo_env.hop_secs).round() as usize;
    let demo_180 = odori_core::music::RmsEnvelope {
        hop_secs: demo_env.hop_secs,
        bands: demo_env.bands.iter().map(|b| b.iter().cycle().copied().take(frames).collect()).collect(),
    };
    let demo_analysis_secs = median_secs(21, || analyze(&demo_180, &options).expect("demo analysis"));
    // A 20-minute song (the same 3-minute envelope looped; moved here from the bad-input test,
    // which printed the time without asserting it): the ratio to the 3-minute analysis says
    // whether the analysis stays near linear in the song's length.
    let frames_20 = (1200.0 / env.hop_secs).round() as usize;
    let env_20 = odori_core::music::RmsEnvelope {
        hop_secs: env.hop_secs,
        bands: env.bands.iter().map(|b| b.iter().cycle().copied().take(frames_20).collect()).collect(),
    };
    let analysis_20_secs = median_secs(5, || analyze(&env_20, &options).expect("20-minute analysis"));
    println!("frames per band: {}, bands: {}", env.frame_count(), env.bands.len());
    println!("core analysis, 20-minute song:                                 {:.1} ms ({:.1}x the 3-minute song's time for {:.1}x its length)", analysis_20_secs * 1e3, analysis_20_secs / analysis_secs, 1200.0 / 180.0);
    println!("result: {:.2} BPM, {} beats, {} bars", grid.bpm, grid.beat_times_secs.len(), grid.bars.len());
    println!("envelope from PCM (Rust fallback of the host's WebAudio step): {:.1} ms", env_secs * 1e3);
    println!("core analysis, envelope -> grid (3-minute song):              {:.2} ms", analysis_secs * 1e3);
    println!("baseline, one pass summing the envelope:                       {:.3} ms", baseline_secs * 1e3);
    println!("ratio analysis / baseline:                                     {:.0}x", analysis_secs / baseline_secs);
    println!("real-time factor of the analysis:                              {:.0}x faster than real time", 180.0 / analysis_secs);
    println!("demo song render (70 s at 44.1 kHz):                           {:.1} ms", demo_secs * 1e3);
    println!("core analysis of the wasm bench's input (demo looped to 180 s): {:.2} ms", demo_analysis_secs * 1e3);
    println!("correction with_bpm:                                           {:.1} us", bpm_secs * 1e6);
    println!("correction with_first_downbeat:                                {:.1} us", shift_secs * 1e6);
    println!("correction bpm + 3/4 + downbeat:                               {:.1} us", combined_secs * 1e6);
}
