//! The video camera (`odori_core::camera`, issue 29) on generated dances: the built-in demo
//! song (sections known by construction) and a real recording from ../shared/data, each
//! analysed, danced through the project over the built-in moves and rendered; the camera is
//! planned over 32 bars at 30 fps. Checked: the director cuts at least 3 times, every cut on
//! the first frame of a bar line that is a phrase start by the rule restated here (a full
//! phrase since the last cut, or a section change, a novelty peak or an intensity jump);
//! every mode keeps every joint of every frame inside the frame at three aspects.

#[path = "music_audio.rs"]
mod music_audio;

use glam::Vec3;
use odori_core::bars::Bar;
use odori_core::camera::{effective_phrase_bars, plan, CameraInput, CameraMode, CameraOptions, CameraPlan};
use odori_core::choreo::RenderOptions;
use odori_core::music::demo_song::demo_song;
use odori_core::music::{analyze, envelope, sections, AnalysisOptions, RmsEnvelope, SectionOptions, Sections};
use odori_core::project::Project;
use odori_core::Clip;

const FPS: f32 = 30.0;
const BARS: usize = 32;

struct Case {
    name: String,
    bars: Vec<Bar>,
    sections: Sections,
    times: Vec<f32>,
    joints: Vec<Vec<Vec3>>,
}

fn pose_at(clip: &Clip, t: f32) -> Vec<Vec3> {
    std::mem::take(&mut odori_core::motion::WorldPose::new().of_time(clip, t).positions)
}

/// The song danced and the camera's input over its first 32 bars (from a beat before the
/// first, the lead-in), at 30 fps.
fn case(name: &str, env: &RmsEnvelope) -> Case {
    let grid = analyze(env, &AnalysisOptions::default()).unwrap_or_else(|e| panic!("{name}: {e}"));
    assert!(grid.bars.len() >= BARS, "{name}: only {} bars", grid.bars.len());
    let secs = sections(&grid, env, &SectionOptions::default()).unwrap_or_else(|e| panic!("{name}: {e}"));
    let mut project = Project::new();
    project.set_song(name, None, env, AnalysisOptions::default()).unwrap_or_else(|e| panic!("{name}: {e}"));
    project.generate().unwrap_or_else(|e| panic!("{name}: generate: {e}"));
    let clip = project.render_dance(&RenderOptions::default()).unwrap_or_else(|e| panic!("{name}: render: {e}"));
    let bars: Vec<Bar> = grid.bars[..BARS].to_vec();
    let beat = bars[0].duration_secs() / bars[0].beat_count() as f32;
    let start = (bars[0].start_secs - beat).max(0.0);
    let frames = ((bars[BARS - 1].end_secs - start) * FPS).round() as usize;
    let times: Vec<f32> = (0..frames).map(|i| start + i as f32 / FPS).collect();
    let joints = times.iter().map(|&t| pose_at(&clip, t)).collect();
    Case { name: name.into(), bars, sections: secs, times, joints }
}

fn cases() -> Vec<Case> {
    let demo = demo_song(22050.0).expect("demo song");
    let mut out = vec![case("demo song", &envelope(&[&demo.samples], demo.sample_rate_hz).expect("envelope"))];
    let rel = music_audio::FULL_TRACKS[0];
    out.push(case(rel, &music_audio::decode_data(rel).envelope().expect("envelope")));
    out
}

fn input(c: &Case) -> CameraInput<'_> {
    CameraInput { times_secs: &c.times, joints: &c.joints, bars: &c.bars, sections: Some(&c.sections) }
}

fn worst_ndc(c: &Case, p: &CameraPlan, aspect: f32) -> f32 {
    let mut worst: f32 = 0.0;
    for (i, (pose, f)) in p.poses.iter().zip(&c.joints).enumerate() {
        for (j, q) in f.iter().enumerate() {
            let n = pose.project(aspect, *q).unwrap_or_else(|| panic!("{}: frame {i} joint {j} behind the camera", c.name));
            worst = worst.max(n[0].abs()).max(n[1].abs());
        }
    }
    worst
}

#[test]
fn a_32_bar_dance_gets_cuts_on_bar_lines_at_phrase_starts() {
    for c in cases() {
        let opts = CameraOptions::default();
        let p = plan(&input(&c), &opts).unwrap_or_else(|e| panic!("{}: {e}", c.name));
        let phrase = effective_phrase_bars(BARS, &opts);
        assert_eq!(p.phrase_bars, phrase);
        let cuts = &p.shots[1..];
        println!(
            "{}: sections {} (boundaries {:?}), phrase {phrase} bars, cuts at bars {:?}, shots {:?}",
            c.name,
            c.sections.letters(),
            c.sections.boundaries(),
            cuts.iter().map(|x| x.bar).collect::<Vec<_>>(),
            p.shots.iter().map(|x| x.shot).collect::<Vec<_>>()
        );
        assert!(cuts.len() >= 3, "{}: {} cuts in 32 bars", c.name, cuts.len());
        let boundaries = c.sections.boundaries();
        let mut last = 0usize;
        for x in cuts {
            let bar = &c.bars[x.bar];
            // On the bar line: the first frame at or after it.
            let t = c.times[x.frame];
            assert!(t >= bar.start_secs - 1e-4 && t < bar.start_secs + 1.0 / FPS, "{}: cut at {t} s, bar line at {} s", c.name, bar.start_secs);
            assert!(c.times[x.frame - 1] < bar.start_secs, "{}: the frame before the cut is already past the bar line", c.name);
            // At a phrase start: a phrase after the last cut, or the music changes there.
            let since = x.bar - last;
            let section = boundaries.contains(&bar.index);
            let lesser = c.sections.novelty[bar.index] >= opts.novelty_cut || (bar.intensity - c.bars[x.bar - 1].intensity).abs() >= opts.intensity_jump;
            assert!(
                since == phrase || (section && since >= opts.min_shot_bars) || (lesser && since >= phrase / 2),
                "{}: cut at bar {} is {since} bars after the last with no change in the music",
                c.name,
                x.bar
            );
            last = x.bar;
        }
        // Nothing due was skipped: no stretch longer than a phrase without a cut.
        assert!(BARS - last <= phrase, "{}: the last {} bars have no cut", c.name, BARS - last);
        // The camera stands still between cuts and moves at each.
        for (i, w) in p.poses.windows(2).enumerate() {
            let is_cut = cuts.iter().any(|x| x.frame == i + 1);
            assert_eq!(w[0] != w[1], is_cut, "{}: frame {} camera {} a cut", c.name, i + 1, if is_cut { "unchanged at" } else { "moved without" });
        }
        assert_eq!(plan(&input(&c), &opts).expect("again"), p, "{}: not deterministic", c.name);
    }
}

#[test]
fn every_mode_keeps_the_figure_inside_every_frame() {
    for c in cases() {
        for mode in [CameraMode::Fixed, CameraMode::Orbit, CameraMode::Follow, CameraMode::Director] {
            for aspect in [16.0 / 9.0, 9.0 / 16.0, 1.0] {
                let p = plan(&input(&c), &CameraOptions { mode, aspect, ..Default::default() }).unwrap_or_else(|e| panic!("{}: {e}", c.name));
                assert_eq!(p.poses.len(), c.times.len());
                let worst = worst_ndc(&c, &p, aspect);
                println!("{} {mode:?} aspect {aspect:.2}: farthest joint at {worst:.3} of the half-frame", c.name);
                assert!(worst <= 1.0, "{} {mode:?} aspect {aspect}: a joint at {worst} (outside)", c.name);
                // Not merely inside: the figure fills a good part of the frame.
                assert!(worst >= 0.6, "{} {mode:?} aspect {aspect}: the figure reaches only {worst} of the frame", c.name);
            }
        }
    }
}
