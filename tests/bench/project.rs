//! Project benchmarks (native, release): a project holding every real BVH in ../shared/data
//! (the CMU sets, about 30 minutes of mocap) and a song tiled to 4 minutes, with a dance
//! composed on it. Prints the `.odori` size (against the raw inputs), save and open times,
//! open-to-first-pose (against importing and cutting the same files without a project, the
//! work any session does), and the autosave cost per edit (the manifest written after each
//! edit; blobs are written once). Asserts nothing about time.

use std::time::Instant;

use odori_core::choreo::{RenderOptions, SegmentLibrary, SegmentOptions};
use odori_core::import::import_bytes;
use odori_core::music::{AnalysisOptions, RmsEnvelope};
use odori_core::project::{self, file::manifest_json, Project};
use odori_core::ImportOptions;
use odori_tests::{all_bvh, fps_override_for, read};

#[path = "../native/music_audio.rs"]
mod music_audio;

fn ms(t: Instant) -> f64 {
    t.elapsed().as_secs_f64() * 1e3
}

fn main() {
    let song_rel = "music/Karissa_Hobbs_-_Lets_Go_Fishin.hq.ogg";
    let audio = music_audio::decode_data(song_rel);
    let env = audio.envelope().expect("envelope");
    // Tile the envelope to 4 minutes (the audio bytes stay the file's, as given).
    let frames = (240.0 / env.hop_secs) as usize;
    let env = RmsEnvelope { hop_secs: env.hop_secs, bands: env.bands.iter().map(|b| b.iter().copied().cycle().take(frames).collect()).collect() };
    let song_bytes = read(song_rel);

    let files: Vec<(String, Vec<u8>)> = all_bvh().into_iter().map(|rel| { let b = read(&rel); (rel, b) }).collect();
    let raw_bytes: usize = files.iter().map(|(_, b)| b.len()).sum::<usize>() + song_bytes.len();

    // Baseline: import and cut the same files with no project.
    let t = Instant::now();
    let mut lib = SegmentLibrary::builtin();
    let mut minutes = 0.0;
    for (rel, bytes) in &files {
        let imp = import_bytes(rel, bytes, &ImportOptions { fps_override: fps_override_for(rel), ..Default::default() }).expect("import");
        for c in &imp.clips {
            minutes += c.duration_secs() / 60.0;
            let _ = lib.add_clip(c, &imp.humanoid, &imp.status, &SegmentOptions::default());
        }
    }
    let baseline_ms = ms(t);
    println!("inputs: {} BVH files, {minutes:.1} min of mocap, song {song_rel} tiled to 240 s; raw {:.1} MB", files.len(), raw_bytes as f64 / 1e6);
    println!("baseline: import + cut without a project: {baseline_ms:.0} ms ({} segments)", lib.len());

    // The project, with a dance.
    let t = Instant::now();
    let mut p = Project::new();
    p.set_song("fishin.ogg", Some(&song_bytes), &env, AnalysisOptions::default()).expect("song");
    for (rel, bytes) in &files {
        p.add_source(rel, bytes, ImportOptions { fps_override: fps_override_for(rel), ..Default::default() }).expect("add");
    }
    let bars = p.doc().dance.bars.len();
    let round = p.candidates(0).expect("candidates");
    for bar in [2, 5, 9] {
        p.set(bar, &round[bar % round.len()]).expect("pin");
    }
    let build_ms = ms(t);
    let t = Instant::now();
    p.generate().expect("generate");
    let generate_ms = ms(t);
    println!("project built in {build_ms:.0} ms, {bars} bars, generate {generate_ms:.0} ms");

    // Autosave cost per edit: the manifest after each of 40 more edits.
    let mut costs = Vec::new();
    let mut manifest_bytes = 0;
    let (mut whole_costs, mut whole_bytes) = (Vec::new(), 0);
    for k in 0..40 {
        let bar = 10 + (k % 20);
        match k % 4 {
            0 => { p.candidates(bar).expect("candidates"); }
            1 => { let r = p.doc().dance.bars[bar - 1].search.as_ref().map(|s| s.round.clone()).unwrap_or_default(); if let Some(k0) = r.first() { p.set(bar, k0).expect("set"); } }
            2 => p.set_texts(vec![format!("text {k}")]),
            _ => { p.set_rho(0.1 + 0.01 * k as f32).expect("rho"); }
        }
        let t = Instant::now();
        let m = manifest_json(&p);
        costs.push(ms(t));
        manifest_bytes = m.len();
        // The control: the same history as whole documents (schema 1's manifest).
        let t = Instant::now();
        let whole = serde_json::to_vec(&(p.doc(), p.undo_history(), p.redo_history())).expect("json");
        whole_costs.push(ms(t));
        whole_bytes = whole.len();
    }
    costs.sort_by(|a, b| a.total_cmp(b));
    whole_costs.sort_by(|a, b| a.total_cmp(b));
    println!(
        "autosave per edit (manifest JSON, native): median {:.2} ms, max {:.2} ms; manifest {:.0} kB with {} undo steps \
         (history as whole documents, schema 1: median {:.2} ms, {:.0} kB, {:.1}x the bytes)",
        costs[costs.len() / 2],
        costs[costs.len() - 1],
        manifest_bytes as f64 / 1e3,
        p.undo_history().len(),
        whole_costs[whole_costs.len() / 2],
        whole_bytes as f64 / 1e3,
        whole_bytes as f64 / manifest_bytes as f64
    );

    let t = Instant::now();
    let bytes = project::save(&p).expect("save");
    let save_ms = ms(t);
    println!(".odori: {:.1} MB ({:.2} × the raw inputs), saved in {save_ms:.0} ms", bytes.len() as f64 / 1e6, bytes.len() as f64 / raw_bytes as f64);

    let t = Instant::now();
    let mut q = project::open(&bytes).expect("open").project;
    let open_ms = ms(t);
    let clip = q.render_dance(&RenderOptions::default()).expect("render");
    let _first = clip.world_positions(0);
    let first_pose_ms = ms(t);
    println!(
        "open: read + check {open_ms:.0} ms; open to first pose {first_pose_ms:.0} ms ({:.2} × the baseline import + cut)",
        first_pose_ms / baseline_ms
    );
    assert!(q == p, "the reopened project is the same");
}
