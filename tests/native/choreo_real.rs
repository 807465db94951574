//! Choreography on real data: the segment library built from every real clip in
//! ../shared/data/mocap (and the RobotExpressive glTF) together with the built-in one, and a
//! dance generated for a real song from ../shared/data/music.
//!
//! The song's bars come from the core's own analysis of the decoded song (spec §D: tempo,
//! beats, downbeats, bars, each bar's intensity the mean loudness over it scaled to the
//! song's range), exactly as the app gets them; the audio is decoded and enveloped as in the
//! music tests (`music_audio.rs`).

use std::time::Instant;

use odori_core::bars::Bar;
use odori_core::choreo::render::join_frames;
use odori_core::choreo::{
    generate_states, mean_pairwise_dissimilarity, speed_jumps, BarState, FeedbackSession, FillWeights, GenerateOptions, RenderOptions, SegmentLibrary, SegmentOptions,
};
use odori_core::import::import_bytes;
use odori_core::music::{analyze, AnalysisOptions};
use odori_core::ImportOptions;
use odori_tests::{all_bvh, fps_override_for, read};

#[path = "music_audio.rs"]
mod music_audio;

/// The song's bars from the core's analysis of the real recording.
fn song_bars(rel: &str) -> Vec<Bar> {
    let audio = music_audio::decode_data(rel);
    let env = audio.envelope().unwrap_or_else(|e| panic!("{rel}: {e}"));
    let grid = analyze(&env, &AnalysisOptions::default()).unwrap_or_else(|e| panic!("{rel}: {e}"));
    let (lo, hi) = grid.bars.iter().fold((f32::MAX, f32::MIN), |(a, b), x| (a.min(x.intensity), b.max(x.intensity)));
    println!(
        "song {rel}: {:.1} s analysed by the core: {:.1} BPM, first downbeat {:.2} s, {} bars, bar intensity {lo:.2}..{hi:.2}",
        grid.duration_secs,
        grid.bpm,
        grid.first_downbeat_secs,
        grid.bars.len()
    );
    grid.bars
}

fn real_library() -> (SegmentLibrary, usize) {
    let t = Instant::now();
    let mut lib = SegmentLibrary::builtin();
    let builtin = lib.len();
    println!("built-in library: {builtin} segments in {:.1} ms (dev profile)", t.elapsed().as_secs_f64() * 1e3);
    let t = Instant::now();
    let mut secs = 0.0;
    for rel in all_bvh() {
        let opts = ImportOptions { fps_override: fps_override_for(&rel), ..Default::default() };
        let imp = import_bytes(&rel, &read(&rel), &opts).expect("import");
        for clip in &imp.clips {
            secs += clip.duration_secs();
            match lib.add_clip(clip, &imp.humanoid, &imp.status, &SegmentOptions::default()) {
                Ok(s) => println!("  {rel}: {:.1} s, detected {:.1} counts/min, {} beats, {} segments", clip.duration_secs(), s.tempo_bpm, s.beats, s.segments),
                Err(e) => println!("  {rel}: refused: {e}"),
            }
        }
    }
    let imp = import_bytes("RobotExpressive.glb", &read("gltf/RobotExpressive.glb"), &ImportOptions::default()).expect("glb");
    for clip in &imp.clips {
        secs += clip.duration_secs();
        match lib.add_clip(clip, &imp.humanoid, &imp.status, &SegmentOptions::default()) {
            Ok(s) => println!("  RobotExpressive/{}: {:.1} s, {:.1} counts/min, {} segments", clip.name, clip.duration_secs(), s.tempo_bpm, s.segments),
            Err(e) => println!("  RobotExpressive/{}: refused: {e}", clip.name),
        }
    }
    println!(
        "real clips: {:.1} min of motion → {} segments in {:.2} s (dev profile); library total {}",
        secs / 60.0,
        lib.len() - builtin,
        t.elapsed().as_secs_f64(),
        lib.len()
    );
    (lib, builtin)
}

fn stats(v: &[f32]) -> (f32, f32) {
    let mut s = v.to_vec();
    s.sort_by(f32::total_cmp);
    let mean = s.iter().sum::<f32>() / s.len().max(1) as f32;
    (mean, s.get(((s.len() as f32 * 0.95) as usize).min(s.len().saturating_sub(1))).copied().unwrap_or(0.0))
}

fn joins(lib: &SegmentLibrary, bars: &[Bar], choices: &[Option<usize>], join: usize) -> ((f32, f32), (f32, f32)) {
    let clip = odori_core::choreo::render(lib, bars, choices, &RenderOptions { fps: 60.0, join_frames: join, ..RenderOptions::default() });
    let jumps = speed_jumps(&clip);
    let jf = join_frames(bars, 60.0);
    let at: Vec<f32> = jf.iter().filter(|&&j| j + 1 < jumps.len()).map(|&j| jumps[j - 1].max(jumps[j]).max(jumps[j + 1])).collect();
    let end = ((bars[bars.len() - 1].end_secs * 60.0) as usize).min(jumps.len());
    let inside: Vec<f32> = (1..end).filter(|f| jf.iter().all(|&j| f + 8 < j || *f > j + 8)).map(|f| jumps[f]).collect();
    (stats(&at), stats(&inside))
}

#[test]
fn real_library_and_real_song() {
    let (lib, builtin) = real_library();
    assert!(lib.len() > builtin + 100, "the real clips gave only {} segments", lib.len() - builtin);
    // Salsa is danced at roughly 2 counts per second or a little less: the detected tempi of the
    // salsa clips must be dance tempi.
    for c in lib.clips().iter().filter(|c| c.clip.source.contains("salsa")) {
        assert!((60.0..=200.0).contains(&c.tempo_bpm), "{}: {} counts/min", c.clip.source, c.tempo_bpm);
    }
    let bars = song_bars("music/Kevin_MacLeod_-_Vibe_Ace.hq.ogg");
    assert!(bars.len() >= 30, "only {} bars", bars.len());
    assert!(bars.iter().any(|b| b.intensity < 0.3) && bars.iter().any(|b| b.intensity > 0.7), "bar intensities are not scaled to the song's range");
    // Pin three bars to real salsa/indian segments, generate the rest.
    let real: Vec<usize> = lib.segments().iter().filter(|s| s.builtin.is_none()).map(|s| s.index).collect();
    let pins = [(0usize, real[3]), (10, real[real.len() / 2]), (20, real[real.len() - 5])];
    let mut states = vec![BarState::Empty; bars.len()];
    for (b, s) in pins {
        states[b] = BarState::Pinned { segment: s };
    }
    let t = Instant::now();
    let (states, rep) = generate_states(&lib, &bars, &states, FillWeights::default(), &GenerateOptions::default()).unwrap();
    println!(
        "generate: {} open bars from {} segments in {:.1} ms incl. the transition table (dev profile), path cost {:.2}",
        rep.filled,
        lib.len(),
        t.elapsed().as_secs_f64() * 1e3,
        rep.cost
    );
    let chosen: Vec<Option<usize>> = states.iter().map(BarState::segment).collect();
    let from_real = chosen.iter().flatten().filter(|&&s| lib.segments()[s].builtin.is_none()).count();
    println!("  bars using real-mocap segments: {from_real} of {}", bars.len());
    let mut x = 12345u64;
    let random: Vec<Option<usize>> = (0..bars.len())
        .map(|i| {
            x = x.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            pins.iter().find(|p| p.0 == i).map(|p| p.1).or(Some((x >> 33) as usize % lib.len()))
        })
        .collect();
    let mut res = Vec::new();
    for (name, ch) in [("generated", &chosen), ("random", &random)] {
        for j in [0, 5] {
            let ((am, ap), (im, ip)) = joins(&lib, &bars, ch, j);
            println!("  {name:9} joins {}: at joins mean {am:.3} p95 {ap:.3} m/s | inside mean {im:.3} p95 {ip:.3} m/s", if j == 0 { "off" } else { "on " });
            res.push(am);
        }
    }
    assert!(res[0] < 0.7 * res[2], "generated joins ({}) not clearly smoother than random ({})", res[0], res[2]);
    for (b, s) in pins {
        assert_eq!(chosen[b], Some(s));
    }
    // Fig. 4 on the real + built-in library.
    let mut div = [0.0f32; 3];
    let targets: Vec<usize> = real.iter().step_by(real.len() / 6).take(6).copied().collect();
    for &target in &targets {
        let mut s = FeedbackSession::new();
        let mut round = s.next_round(&lib, 0.5, 0.3, 6).to_vec();
        for d in div.iter_mut() {
            *d += mean_pairwise_dissimilarity(&lib, &round) / targets.len() as f32;
            let liked = *round.iter().min_by(|&&a, &&b| lib.dissimilarity(a, target).total_cmp(&lib.dissimilarity(b, target))).unwrap();
            round = s.search(&lib, &[liked], 0.5, 0.3, 6).to_vec();
        }
    }
    println!("Fig. 4 on the real + built-in library (6 real targets): rounds 1..3 mean pairwise D = {:.4}, {:.4}, {:.4}", div[0], div[1], div[2]);
    assert!(div[2] < div[0]);
}

/// Each segment's own foot skate (spec §J, kept for the filling's skate term) measures the
/// frames it plays: the imported segments whose stored skate is in the lowest third skate less,
/// when each is rendered alone at its own length and measured afresh, than those in the
/// highest third; and every figure is finite and not negative.
#[test]
fn segment_skate_measures_its_own_frames() {
    use odori_core::choreo::quality::foot_skate;
    use odori_core::choreo::{segment_clip, QualityMotion};
    let (lib, builtin) = real_library();
    let mut pairs: Vec<(f32, f32)> = Vec::new();
    for s in &lib.segments()[builtin..] {
        assert!(s.skate_cm_per_s.is_finite() && s.skate_cm_per_s >= 0.0, "{}: skate {}", s.name, s.skate_cm_per_s);
        assert!(s.clip_skate_cm_per_s.is_finite() && s.clip_skate_cm_per_s >= 0.0, "{}: clip skate {}", s.name, s.clip_skate_cm_per_s);
        let clip = segment_clip(&lib, s.index, s.duration_secs(), 30.0).expect("segment clip");
        let Ok(m) = QualityMotion::from_clip(&clip) else { continue };
        pairs.push((s.skate_cm_per_s, foot_skate(&m).mean_cm_per_s));
    }
    assert!(pairs.len() >= 30, "only {} imported segments measured", pairs.len());
    pairs.sort_by(|a, b| a.0.total_cmp(&b.0));
    let third = pairs.len() / 3;
    let mean = |v: &[(f32, f32)]| v.iter().map(|p| p.1).sum::<f32>() / v.len() as f32;
    let (low, high) = (mean(&pairs[..third]), mean(&pairs[pairs.len() - third..]));
    println!("imported segments rendered alone: skate {low:.1} cm/s (stored lowest third) vs {high:.1} (highest third), {} segments", pairs.len());
    assert!(high > low, "rendered skate {high:.1} (stored highest third) is not above {low:.1} (lowest third)");
}
