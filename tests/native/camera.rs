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

// --- An MMD camera VMD driving the camera (camera::mmd) -------------------------------------

mod mmd_camera {
    use glam::{EulerRot, Quat, Vec3};
    use odori_core::camera::mmd::{poses, sample};
    use odori_core::import::vmd;
    use odori_core::mmd::files::CameraTrack;
    use odori_core::mmd::{standard_rig, MmdClipOptions, MmdMotion, METRES_PER_MMD_UNIT};
    use odori_core::canon::humanoid::HumanoidMap;
    use odori_core::Canon;
    use odori_tests::read;

    const CAM: &str = "mmd/motion/tokino_kakera_cam.vmd";
    const DANCE: &str = "mmd/motion/tokino_kakera.vmd";

    fn raw() -> vmd::Vmd {
        vmd::read(CAM, &read(CAM)).unwrap_or_else(|e| panic!("{e}"))
    }

    fn track() -> CameraTrack {
        CameraTrack::from_vmd(CAM, &raw(), 0).expect("時間のカケラ's camera VMD has camera keys")
    }

    /// y of the curve through (0,0), (x1,y1), (x2,y2), (1,1) where its x is `w`: solved here in
    /// f64 by bisection on the curve parameter (60 steps), independently of the engine's solver.
    fn curve_y([x1, y1, x2, y2]: [u8; 4], w: f64) -> f64 {
        let (x1, y1, x2, y2) = (x1 as f64 / 127.0, y1 as f64 / 127.0, x2 as f64 / 127.0, y2 as f64 / 127.0);
        let b = |p1: f64, p2: f64, t: f64| 3.0 * (1.0 - t) * (1.0 - t) * t * p1 + 3.0 * (1.0 - t) * t * t * p2 + t * t * t;
        let (mut lo, mut hi) = (0.0, 1.0);
        for _ in 0..60 {
            let mid = 0.5 * (lo + hi);
            if b(x1, x2, mid) < w { lo = mid } else { hi = mid }
        }
        b(y1, y2, 0.5 * (lo + hi))
    }

    #[test]
    fn a_camera_track_holds_its_keys_and_eases_between_them_by_the_later_keys_curves() {
        let t = track();
        let v = raw();
        assert_eq!(t.keys.len(), v.camera_keys.len());
        println!("{CAM}: {} camera keys over {:.1} s", t.keys.len(), t.keys.last().unwrap().time_secs);
        // At every key's own time (a later key at the same time wins): the key as the file has it.
        let mut checked = 0;
        for (i, k) in t.keys.iter().enumerate() {
            if t.keys.get(i + 1).is_some_and(|n| n.time_secs <= k.time_secs) {
                continue;
            }
            let s = sample(&t, k.time_secs).unwrap();
            assert!((s.target_m - k.target_m).length() < 1e-4 && (s.distance_m - k.distance_m).abs() < 1e-4 && (s.fov_deg - k.fov_deg).abs() < 1e-3 && (s.rotation_rad - k.rotation_rad).length() < 1e-4, "key {i} at {} s: {s:?} vs {k:?}", k.time_secs);
            checked += 1;
        }
        assert!(checked > 10);
        // Between two keys two or more frames apart: each channel eased by the later key's curve,
        // interpolated from the earlier key's values to the later's,
        // checked against the raw file (MMD units, left-handed) and a separate curve solver.
        let raw_keys = {
            let mut k = v.camera_keys.clone();
            k.sort_by_key(|k| k.frame);
            k
        };
        let (mut eased, mut curved) = (0, 0);
        for w in raw_keys.windows(2) {
            let (a, b) = (&w[0], &w[1]);
            if b.frame < a.frame + 2 {
                continue;
            }
            let c = &b.curves;
            let curves = [c.x, c.y, c.z, c.rotation, c.distance, c.fov].map(|b| [b.x1, b.y1, b.x2, b.y2]);
            curved += curves.iter().filter(|[x1, y1, x2, y2]| x1 != y1 || x2 != y2).count();
            for frac in [0.25f64, 0.5, 0.8] {
                let tf = a.frame as f64 + frac * (b.frame - a.frame) as f64;
                let s = sample(&t, (tf / 30.0) as f32).unwrap();
                let lerp = |x: f32, y: f32, ch: usize| x as f64 + (y - x) as f64 * curve_y(curves[ch], frac);
                let m = METRES_PER_MMD_UNIT as f64;
                let want_target = [lerp(a.target.x, b.target.x, 0) * m, lerp(a.target.y, b.target.y, 1) * m, -lerp(a.target.z, b.target.z, 2) * m];
                let want_distance = lerp(a.distance, b.distance, 4) * m;
                let want_fov = lerp(a.fov_deg as f32, b.fov_deg as f32, 5);
                let want_yaw = -lerp(a.rotation_rad.y, b.rotation_rad.y, 3);
                // Within the engine's solver's precision (three.js's: 15 bisection steps), a
                // thousandth of the span's change.
                let tol = |x: f32, y: f32, abs: f64| abs + 1e-3 * (y - x).abs() as f64;
                let got = [s.target_m.x as f64, s.target_m.y as f64, s.target_m.z as f64];
                let spans = [(a.target.x, b.target.x), (a.target.y, b.target.y), (a.target.z, b.target.z)];
                for ax in 0..3 {
                    let t = tol(spans[ax].0, spans[ax].1, 2e-4 / m) * m;
                    assert!((got[ax] - want_target[ax]).abs() < t, "frame {tf}: target axis {ax} {} vs {}", got[ax], want_target[ax]);
                }
                assert!((s.distance_m as f64 - want_distance).abs() < tol(a.distance, b.distance, 2e-4 / m) * m, "frame {tf}: distance {} vs {want_distance}", s.distance_m);
                assert!((s.fov_deg as f64 - want_fov).abs() < tol(a.fov_deg as f32, b.fov_deg as f32, 1e-2), "frame {tf}: fov {} vs {want_fov}", s.fov_deg);
                assert!((s.rotation_rad.y as f64 - want_yaw).abs() < tol(a.rotation_rad.y, b.rotation_rad.y, 1e-4), "frame {tf}: yaw {} vs {want_yaw}", s.rotation_rad.y);
                eased += 1;
            }
        }
        println!("{checked} keys held exactly; {eased} eased instants match the hand-solved curves ({curved} of the spans' channels not straight lines)");
        assert!(eased >= 30, "only {eased} eased instants checked");
    }

    /// three.js r171's camera (MMDParser's left-to-right conversion, MMDLoader's
    /// `buildCameraAnimation`, MMDAnimationHelper's look-at), transcribed: rotation Euler XYZ of
    /// (x, y, −z) of the file's angles, the eye at R·(centre + (0, 0, −distance)), metres.
    fn three_eye(k: &vmd::CameraKey) -> Vec3 {
        let r = Quat::from_euler(EulerRot::XYZ, k.rotation_rad.x, k.rotation_rad.y, -k.rotation_rad.z);
        let c = Vec3::new(k.target.x, k.target.y, -k.target.z);
        r * (c + Vec3::new(0.0, 0.0, -k.distance)) * METRES_PER_MMD_UNIT
    }

    #[test]
    fn the_camera_looks_the_way_three_js_reads_it_and_frames_the_dance_it_was_made_for() {
        let t = track();
        let v = raw();
        // three.js's camera at every key, seen from its look-at point, against the engine's. They
        // differ by design by a few degrees (three turns the look-at point with the camera and
        // takes the angles in X, Y, Z order; MMD turns about the look-at point, yaw then pitch),
        // far less than the engine's camera with its yaw's or its pitch's sign flipped (controls).
        let angle = |a: Vec3, b: Vec3| a.normalize().dot(b.normalize()).clamp(-1.0, 1.0).acos().to_degrees();
        let (mut ours, mut yaw_flipped, mut pitch_flipped, mut worst) = (0.0f32, 0.0f32, 0.0f32, 0.0f32);
        for k in &v.camera_keys {
            let s = sample(&t, k.frame as f32 / 30.0).unwrap();
            let three = three_eye(k) - Vec3::new(k.target.x, k.target.y, -k.target.z) * METRES_PER_MMD_UNIT;
            let a = angle(s.eye() - s.target_m, three);
            let mut y = s;
            y.rotation_rad.y = -y.rotation_rad.y;
            let mut p = s;
            p.rotation_rad.x = -p.rotation_rad.x;
            ours += a;
            worst = worst.max(a);
            yaw_flipped += angle(y.eye() - y.target_m, three);
            pitch_flipped += angle(p.eye() - p.target_m, three);
        }
        let n = v.camera_keys.len() as f32;
        println!("{n} keys: the view axis is {:.1}° from three.js's on average (worst {worst:.1}°); yaw flipped {:.1}°, pitch flipped {:.1}°", ours / n, yaw_flipped / n, pitch_flipped / n);
        assert!(ours / n < 6.0, "the view axis is {:.1}° from three.js's on average", ours / n);
        assert!(yaw_flipped / n > 2.0 * ours / n && pitch_flipped / n > 2.0 * ours / n, "the controls are as close to three.js as the camera: the check cannot tell");

        // The dance the camera was made for, on the standard skeleton: its head projects inside
        // the 16:9 frame, and the eye stays above the floor, in (nearly) every frame.
        let motion = MmdMotion::from_vmd(&vmd::read(DANCE, &read(DANCE)).unwrap_or_else(|e| panic!("{e}")));
        let clip = standard_rig().motion_to_clip(&motion, &MmdClipOptions::default()).unwrap();
        let head = HumanoidMap::from_skeleton(&clip.skeleton).get(Canon::Head).expect("a head joint");
        let end = clip.duration_secs().min(t.keys.last().unwrap().time_secs);
        let times: Vec<f32> = (0..).map(|i| i as f32 / 10.0).take_while(|&s| s <= end).collect();
        let cams = poses(&t, &times, 0.0).unwrap();
        let (mut inside, mut above) = (0, 0);
        for (i, &s) in times.iter().enumerate() {
            let p = super::pose_at(&clip, s)[head];
            if cams[i].project(16.0 / 9.0, p).is_some_and(|[x, y]| x.abs() <= 1.0 && y.abs() <= 1.0) {
                inside += 1;
            }
            above += usize::from(cams[i].eye().y > 0.0);
        }
        let n = times.len() as f32;
        println!("{} instants over {end:.1} s: head in frame {:.1} %, eye above the floor {:.1} %", times.len(), 100.0 * inside as f32 / n, 100.0 * above as f32 / n);
        assert!(inside as f32 >= 0.9 * n, "the head is in frame at only {inside} of {n} instants");
        assert!(above as f32 >= 0.95 * n, "the eye is above the floor at only {above} of {n} instants");
    }
}
