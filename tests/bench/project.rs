//! Project benchmarks (native, release): a project holding 30 minutes of mocap made from every
//! real BVH in ../shared/data (7.1 minutes: each file is also added in distinct variants —
//! played backwards, its root moved 1 m and 2 m aside — each a real BVH file of its own with
//! other bytes, so content addressing stores each once and cannot fold them together; see
//! [`variant`]) and a song tiled to 4 minutes, with a dance
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

/// A distinct BVH file made from a real one: the frames in reverse order (`reverse`) and/or
/// the root moved `shift_cm` along X (the root's Xposition channel). The header is kept as
/// is, so the skeleton is the file's; the motion is real mocap, played otherwise.
fn variant(bytes: &[u8], reverse: bool, shift_cm: f32) -> Vec<u8> {
    let text = std::str::from_utf8(bytes).expect("a BVH file is text");
    let motion_at = text.find("MOTION").expect("a BVH file has a MOTION section");
    let (header, motion) = text.split_at(motion_at);
    // The root's first CHANNELS line: where Xposition sits among the frame's values.
    let x_channel = header
        .lines()
        .find(|l| l.trim_start().starts_with("CHANNELS"))
        .and_then(|l| l.split_whitespace().skip(2).position(|c| c.eq_ignore_ascii_case("Xposition")));
    let mut lines: Vec<&str> = motion.lines().collect();
    let first_frame = lines.iter().position(|l| l.trim_start().starts_with("Frame Time")).expect("Frame Time") + 1;
    let mut frames: Vec<String> = lines.split_off(first_frame).into_iter().filter(|l| !l.trim().is_empty()).map(str::to_string).collect();
    if reverse {
        frames.reverse();
    }
    if let (Some(x), true) = (x_channel, shift_cm != 0.0) {
        for f in &mut frames {
            let mut v: Vec<String> = f.split_whitespace().map(str::to_string).collect();
            if let Some(val) = v.get_mut(x).and_then(|s| s.parse::<f32>().ok().map(|n| (s, n))) {
                *val.0 = format!("{:.4}", val.1 + shift_cm);
            }
            *f = v.join(" ");
        }
    }
    let mut out = String::with_capacity(bytes.len() + 1024);
    out.push_str(header);
    for l in &lines {
        out.push_str(l);
        out.push('\n');
    }
    for f in &frames {
        out.push_str(f);
        out.push('\n');
    }
    out.into_bytes()
}

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

    // 30 minutes of mocap: every real file, then its variants in turn until there are 30.
    let real: Vec<(String, Vec<u8>, f32)> = all_bvh()
        .into_iter()
        .map(|rel| {
            let b = read(&rel);
            let secs = import_bytes(&rel, &b, &ImportOptions { fps_override: fps_override_for(&rel), ..Default::default() }).map(|i| i.clips.iter().map(|c| c.duration_secs()).sum()).unwrap_or(0.0);
            (rel, b, secs)
        })
        .collect();
    let real_minutes: f32 = real.iter().map(|r| r.2).sum::<f32>() / 60.0;
    let target_secs: f32 = std::env::var("PROJECT_MOCAP_MINUTES").ok().and_then(|m| m.parse::<f32>().ok()).unwrap_or(30.0) * 60.0;
    let kinds: [(&str, bool, f32); 5] = [("as given", false, 0.0), ("reversed", true, 0.0), ("root +1 m", false, 100.0), ("reversed, root +1 m", true, 100.0), ("root +2 m", false, 200.0)];
    let mut files: Vec<(String, Vec<u8>)> = Vec::new();
    let mut total_secs = 0.0;
    let mut per_kind = [0usize; 5];
    'fill: for (k, &(label, reverse, shift)) in kinds.iter().enumerate() {
        for (rel, bytes, secs) in &real {
            if total_secs >= target_secs {
                break 'fill;
            }
            let name = if k == 0 { rel.clone() } else { rel.replace(".bvh", &format!(" ({label}).bvh")) };
            files.push((name, if k == 0 { bytes.clone() } else { variant(bytes, reverse, shift) }));
            total_secs += secs;
            per_kind[k] += 1;
        }
    }
    let distinct = files.iter().map(|(_, b)| project::BlobHash::of(b)).collect::<std::collections::BTreeSet<_>>().len();
    println!(
        "mocap: {} real BVH files ({real_minutes:.1} min) → {} files ({:.1} min): {}; {distinct} distinct contents",
        real.len(),
        files.len(),
        total_secs / 60.0,
        kinds.iter().zip(per_kind).filter(|(_, n)| *n > 0).map(|((l, _, _), n)| format!("{n} {l}")).collect::<Vec<_>>().join(", ")
    );
    assert_eq!(distinct, files.len(), "every file is stored once: no two variants have the same bytes");
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
