//! Unit tests of the camera (fixed, orbit, follow, director): framing, cuts on phrase starts.

use crate::fmath;
use super::*;
use crate::music::sections::Section;

/// A figure of 5 joints swaying and stepping sideways across `secs` at 30 fps.
fn swaying(secs: f32) -> (Vec<f32>, Vec<Vec<Vec3>>) {
    let n = (secs * 30.0).round() as usize;
    let times: Vec<f32> = (0..n).map(|i| i as f32 / 30.0).collect();
    let joints = times
        .iter()
        .map(|&t| {
            let x = fmath::sin(t * 0.7) * 1.5;
            let z = fmath::cos(t * 0.3) * 0.8;
            let arm = fmath::sin(t * 3.0) * 0.7;
            vec![
                Vec3::new(x, 0.0, z),
                Vec3::new(x, 1.0, z),
                Vec3::new(x, 1.7, z),
                Vec3::new(x - 0.6 - arm.abs(), 1.4 + arm, z),
                Vec3::new(x + 0.6, 1.4 - arm, z + arm * 0.5),
            ]
        })
        .collect();
    (times, joints)
}

fn bars(n: usize, secs: f32) -> Vec<Bar> {
    (0..n)
        .map(|i| Bar { index: i, start_secs: i as f32 * secs, end_secs: (i + 1) as f32 * secs, intensity: 0.5, beats: 4 })
        .collect()
}

fn assert_inside(plan: &CameraPlan, input: &CameraInput, aspect: f32, what: &str) {
    assert_eq!(plan.poses.len(), input.times_secs.len(), "{what}: a pose per frame");
    for (i, (pose, f)) in plan.poses.iter().zip(input.joints).enumerate() {
        for (j, p) in f.iter().enumerate() {
            let q = pose.project(aspect, *p).unwrap_or_else(|| panic!("{what}: frame {i} joint {j} behind the camera"));
            assert!(q[0].abs() <= 1.0 && q[1].abs() <= 1.0, "{what}: frame {i} joint {j} at {q:?}, outside the frame");
        }
    }
}

#[test]
fn every_mode_keeps_every_joint_in_the_frame() {
    let (times, joints) = swaying(40.0);
    let b = bars(20, 2.0);
    let input = CameraInput { times_secs: &times, joints: &joints, bars: &b, sections: None };
    for mode in [CameraMode::Fixed, CameraMode::Orbit, CameraMode::Follow, CameraMode::Director] {
        for aspect in [16.0 / 9.0, 9.0 / 16.0, 1.0] {
            let plan = plan(&input, &CameraOptions { mode, aspect, ..Default::default() }).expect("plan");
            assert_inside(&plan, &input, aspect, &format!("{mode:?} at aspect {aspect}"));
        }
    }
}

#[test]
fn the_fit_is_tight_not_merely_inside() {
    // Control for the test above: a camera twice as far would pass it too, so the fitted
    // fixed shot must bring some joint near the frame's edge (its fill, 0.8).
    let (times, joints) = swaying(20.0);
    let b = bars(10, 2.0);
    let input = CameraInput { times_secs: &times, joints: &joints, bars: &b, sections: None };
    let plan = plan(&input, &CameraOptions { mode: CameraMode::Fixed, ..Default::default() }).expect("plan");
    let most = joints.iter().flatten().filter_map(|p| plan.poses[0].project(16.0 / 9.0, *p)).map(|q| q[0].abs().max(q[1].abs())).fold(0.0f32, f32::max);
    assert!(most > 0.7 && most <= 0.81, "the fixed shot fills {most} of the frame, not about 0.8");
}

#[test]
fn director_cuts_every_phrase_and_restarts_the_count_at_a_section_change() {
    let (times, joints) = swaying(64.0);
    let b = bars(32, 2.0);
    // Sections: A for bars 0–4, B from bar 5 (not a multiple of the phrase).
    let sections = Sections {
        sections: vec![
            Section { first_bar: 0, bars: 5, label: 0, intensity: 0.5, repeat_of: None, similarity: 0.0 },
            Section { first_bar: 5, bars: 27, label: 1, intensity: 0.5, repeat_of: None, similarity: 0.2 },
        ],
        novelty: vec![0.0; 32],
    };
    let input = CameraInput { times_secs: &times, joints: &joints, bars: &b, sections: Some(&sections) };
    let plan = plan(&input, &CameraOptions::default()).expect("plan");
    let bars_cut: Vec<usize> = plan.shots.iter().map(|c| c.bar).collect();
    assert_eq!(plan.phrase_bars, 8);
    assert_eq!(bars_cut, vec![0, 5, 13, 21, 29]);
    for w in plan.shots.windows(2) {
        assert_ne!(w[0].shot, w[1].shot, "two shots in a row alike: {:?}", plan.shots);
    }
    // Each cut's frame is the first at or after its bar line.
    for c in &plan.shots[1..] {
        let t = times[c.frame];
        assert!(t >= b[c.bar].start_secs - 1e-4 && t < b[c.bar].start_secs + 1.0 / 30.0, "cut at {t} s for bar line {}", b[c.bar].start_secs);
    }
    // A short range: phrases of 4.
    let short = CameraInput { times_secs: &times[..600], joints: &joints[..600], bars: &b[..10], sections: None };
    let p = super::plan(&short, &CameraOptions::default()).expect("plan");
    assert_eq!(p.shots.iter().map(|c| c.bar).collect::<Vec<_>>(), vec![0, 4, 8]);
    // Deterministic.
    assert_eq!(super::plan(&input, &CameraOptions::default()).expect("plan"), plan);
}

#[test]
fn an_intensity_jump_starts_a_phrase() {
    let (times, joints) = swaying(64.0);
    let mut b = bars(32, 2.0);
    for bar in b.iter_mut().skip(11) {
        bar.intensity = 0.95;
    }
    let input = CameraInput { times_secs: &times, joints: &joints, bars: &b, sections: None };
    let plan = plan(&input, &CameraOptions::default()).expect("plan");
    // At bar 11, 3 bars after the cut at 8: less than half a phrase, so no cut yet (control:
    // the jump at bar 13 is 5 bars after it and cuts).
    assert_eq!(plan.shots.iter().map(|c| c.bar).collect::<Vec<_>>(), vec![0, 8, 16, 24]);
    let mut b2 = bars(32, 2.0);
    for bar in b2.iter_mut().skip(13) {
        bar.intensity = 0.95;
    }
    let input = CameraInput { times_secs: &times, joints: &joints, bars: &b2, sections: None };
    let plan = super::plan(&input, &CameraOptions::default()).expect("plan");
    assert_eq!(plan.shots.iter().map(|c| c.bar).collect::<Vec<_>>(), vec![0, 8, 13, 21, 29]);
}

#[test]
fn bad_input_is_a_typed_error() {
    let (times, mut joints) = swaying(4.0);
    let b = bars(2, 2.0);
    let none = CameraInput { times_secs: &[], joints: &[], bars: &b, sections: None };
    assert_eq!(plan(&none, &CameraOptions::default()), Err(CameraError::NoFrames));
    joints[7][2].y = f32::NAN;
    let input = CameraInput { times_secs: &times, joints: &joints, bars: &b, sections: None };
    assert!(matches!(plan(&input, &CameraOptions::default()), Err(CameraError::BadJoint { frame: 7, joint: 2, .. })));
    joints[7].pop();
    let input = CameraInput { times_secs: &times, joints: &joints, bars: &b, sections: None };
    assert!(matches!(plan(&input, &CameraOptions::default()), Err(CameraError::JointCount { frame: 7, got: 4, want: 5 })));
    let (times, joints) = swaying(4.0);
    let input = CameraInput { times_secs: &times, joints: &joints, bars: &b, sections: None };
    assert!(matches!(plan(&input, &CameraOptions { aspect: 0.0, ..Default::default() }), Err(CameraError::BadOption { what: "aspect", .. })));
    let backwards = bars(2, 2.0).into_iter().rev().collect::<Vec<_>>();
    let input = CameraInput { times_secs: &times, joints: &joints, bars: &backwards, sections: None };
    assert!(matches!(plan(&input, &CameraOptions::default()), Err(CameraError::BadBar { .. })));
}
