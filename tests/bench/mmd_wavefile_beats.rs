//! A human dance as the anchor (issue 28, check 4c): the WAVEFILE dance (wavefile_v2.vmd on
//! miku_v2.pmd, IK solved) imported with its song (wavefile_short.mp3; motion frame 160 is song
//! time 0, as three.js's MMD example plays it), cut into segments at the song's tempo, and its
//! beat alignment printed beside the dances the engine generates for the same song: from the
//! built-in moves alone, and from the built-in moves plus the WAVEFILE segments. Each row also
//! has the half-beat-shifted control (the same motion against beats moved half a beat).
//! Prints figures; asserts nothing. `cargo bench -p odori-tests --bench mmd_wavefile_beats`.

use std::time::Instant;

use odori_core::choreo::quality::{dance_quality, DanceQuality};
use odori_core::choreo::{GenerateOptions, RenderOptions, SegmentLibrary, SegmentOptions};
use odori_core::import::{mmd_model, vmd};
use odori_core::mmd::files::{pose_vmd, MmdFilesOptions};
use odori_core::music::{analyze, envelope, AnalysisOptions};
use odori_core::HumanoidMap;
use odori_tests::read;

fn row(label: &str, q: &DanceQuality) {
    let b = &q.beats;
    println!(
        "{label:<44} {:>8.3} {:>8.3} {:>8.3} {:>8.3} {:>7.2} {:>7.2} {:>7.1}",
        b.bas_music, b.bas_music_shifted, b.bas_motion, b.bas_motion_shifted, b.kinetic_beats_per_sec, b.music_beats_per_sec, q.foot_skate.mean_cm_per_s
    );
}

fn main() {
    let t = Instant::now();
    // The engine takes decoded audio (the browser decodes MP3); here ffmpeg (the devDependency
    // @ffmpeg-installer/linux-x64) decodes the MP3 to raw 32-bit float mono samples at 22,050 Hz.
    let ffmpeg = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../node_modules/@ffmpeg-installer/linux-x64/ffmpeg");
    let mp3 = odori_tests::data_dir().join("mmd/music/wavefile_short.mp3");
    let out = std::process::Command::new(&ffmpeg).args(["-loglevel", "error", "-i"]).arg(&mp3).args(["-ac", "1", "-ar", "22050", "-f", "f32le", "-"]).output();
    let pcm = match out {
        Ok(o) if o.status.success() => o.stdout,
        _ => panic!("{} could not decode {} (run npm ci for ffmpeg; the MP3 is in ../shared/data)", ffmpeg.display(), mp3.display()),
    };
    let samples: Vec<f32> = pcm.chunks_exact(4).map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]])).collect();
    let env = envelope(&[&samples], 22050.0).expect("envelope");
    let grid = analyze(&env, &AnalysisOptions::default()).expect("analysis");
    println!("wavefile_short.mp3: {:.1} s, {:.1} BPM, {} bars ({:.1} s)", grid.duration_secs, grid.bpm, grid.bars.len(), t.elapsed().as_secs_f64());

    let model = mmd_model::read_model("miku_v2.pmd", &read("mmd/miku_v2/miku_v2.pmd")).expect("miku_v2.pmd");
    let v = vmd::read("wavefile_v2.vmd", &read("mmd/motion/wavefile_v2.vmd")).expect("wavefile_v2.vmd");
    let t = Instant::now();
    let human = pose_vmd("wavefile_v2.vmd", v, &[&model], &MmdFilesOptions { song_offset_frames: Some(160), ..Default::default() }).expect("WAVEFILE on miku");
    println!("WAVEFILE on miku_v2 from frame 160: {} frames ({:.1} s), imported in {:.0} ms", human.clip.frame_count(), human.clip.duration_secs(), t.elapsed().as_secs_f64() * 1e3);

    // The bars the human dance covers (the song runs a little longer than the motion).
    let end = human.clip.duration_secs();
    let bars: Vec<_> = grid.bars.iter().filter(|b| b.end_secs <= end).cloned().collect();
    let beats: Vec<f32> = grid.beat_times_secs.iter().copied().filter(|&b| b <= end).collect();
    println!("{} bars within the dance (0 – {:.1} s)\n", bars.len(), bars.last().map_or(0.0, |b| b.end_secs));

    println!("{:<44} {:>8} {:>8} {:>8} {:>8} {:>7} {:>7} {:>7}", "dance", "BASm", "shifted", "BASk", "shifted", "kb/s", "mb/s", "skate");
    let hq = dance_quality(&human.clip, &bars, &beats).expect("quality of WAVEFILE");
    row("WAVEFILE (human, as danced)", &hq);
    // Cut at the song's tempo (and phase: the song's first beat), as the app cuts a clip whose
    // tempo the person states.
    let mut with_wave = SegmentLibrary::builtin();
    let map = HumanoidMap::from_skeleton(&human.clip.skeleton);
    let status = map.status(&human.clip.skeleton, Some(&human.clip));
    let opts = SegmentOptions { tempo_bpm: Some(grid.bpm), first_beat_secs: grid.beat_times_secs.first().copied(), ..Default::default() };
    match with_wave.add_clip(&human.clip, &map, &status, &opts) {
        Ok(s) => println!("\nWAVEFILE cut at {:.1} counts/min: {} segments", s.tempo_bpm, s.segments),
        Err(e) => println!("\nWAVEFILE refused by the segmenter: {e}"),
    }
    let builtin = SegmentLibrary::builtin();
    for (label, lib) in [("generated, built-in moves", &builtin), ("generated, built-in + WAVEFILE segments", &with_wave)] {
        let mut doc = odori_tests::Dance::new(bars.clone());
        let t = Instant::now();
        doc.generate_with(lib, &GenerateOptions::default()).expect("generate");
        let chosen = doc.segments();
        let clip = odori_core::choreo::render(lib, &bars, &chosen, &RenderOptions::default());
        let q = dance_quality(&clip, &bars, &beats).expect("dance quality");
        let from_wave = chosen.iter().flatten().filter(|&&s| lib.segments()[s].builtin.is_none()).count();
        row(label, &q);
        println!("  ({} bars, {from_wave} from WAVEFILE, generated and rendered in {:.0} ms)", chosen.len(), t.elapsed().as_secs_f64() * 1e3);
    }
}
