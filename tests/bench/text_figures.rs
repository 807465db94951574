//! Issue 6 figures: foot skate during Transitions (with and without locking), sway transfer
//! in "walk while waving", switch times by F against fixed ones, and the speed of
//! `animate_text` against a naive baseline (the same clips concatenated, no search, blend or
//! IK) measured in the same run. `cargo bench -p odori-tests --bench text_figures`.

#[path = "../text_figures.rs"]
mod figures;

use std::time::Instant;

use odori_core::actions::ActionLibrary;
use odori_core::import::{import_bytes, ImportOptions};
use odori_core::text::{animate_text, parse, Lexicon};
use odori_core::Clip;

fn naive_concat(text: &str, lib: &ActionLibrary) -> Clip {
    let p = parse(text, &Lexicon::for_library(lib));
    let mut out: Option<Clip> = None;
    for e in &p.elements {
        let Some(i) = lib.find(&e.motion, &[]) else { continue };
        let c = lib.entries[i].clip_for(2.2);
        match &mut out {
            None => out = Some(c),
            Some(o) => {
                o.rotations.extend_from_slice(&c.rotations);
                o.translations[0].values.extend_from_slice(&c.translations[0].values);
            }
        }
    }
    out.unwrap_or_else(|| lib.entries[0].clip.clone())
}

fn time<T>(reps: usize, mut f: impl FnMut() -> T) -> (f64, T) {
    let mut last = None;
    let t = Instant::now();
    for _ in 0..reps {
        last = Some(f());
    }
    (t.elapsed().as_secs_f64() * 1000.0 / reps as f64, last.expect("reps > 0"))
}

fn main() {
    let lib = ActionLibrary::builtin();
    println!("== foot skate during Transitions (planted ankle, horizontal drift, max over the blend)");
    for s in figures::builtin_skates(&lib) {
        println!("  {:<30} without locking {:6.2} cm   with locking {:6.3} cm   ({} frames held by IK)", s.label, s.without_lock.drift_without_lock_cm, s.with_lock.drift_with_lock_cm, s.with_lock.locked_frames);
    }
    let rel = "mocap/cmu-salsa/salsa_01.bvh";
    let imported = import_bytes(rel, &odori_tests::read(rel), &ImportOptions { fps_override: odori_tests::fps_override_for(rel), ..ImportOptions::default() }).expect("salsa");
    let mut lib_real = lib.clone();
    let i = lib_real.add_clip(&imported.clips[0].slice(0, 480, "salsa"), &["dance".into(), "踊る".into()], None).expect("tag");
    let salsa = lib_real.entries[i].clip.clone();
    let run = lib.entries[lib.find("run", &[]).expect("run")].clip_for(2.0);
    let walk = lib.entries[lib.find("walk", &[]).expect("walk")].clip_for(3.0);
    for s in [figures::skate(&salsa, &run, "real salsa (CMU) → run"), figures::skate(&salsa, &walk, "real salsa (CMU) → walk"), figures::skate(&walk, &salsa, "walk → real salsa (CMU)")] {
        println!("  {:<30} without locking {:6.2} cm   with locking {:6.3} cm   ({} frames held by IK)", s.label, s.without_lock.drift_without_lock_cm, s.with_lock.drift_with_lock_cm, s.with_lock.locked_frames);
    }

    let rel = "gltf/RobotExpressive.glb";
    let robot = import_bytes(rel, &odori_tests::read(rel), &ImportOptions::default()).expect("robot");
    let pick = |n: &str| robot.clips.iter().find(|c| c.name == n).expect("robot clip");
    let mut lib_robot = lib.clone();
    let rw = lib_robot.add_clip(pick("Walking"), &["walk".into()], None).expect("tag");
    let rr = lib_robot.add_clip(pick("Running"), &["run".into()], None).expect("tag");
    let (robot_walk, robot_run) = (lib_robot.entries[rw].clip_for(3.0).resampled(60.0), lib_robot.entries[rr].clip_for(2.0).resampled(60.0));
    for s in [figures::skate(&robot_walk, &robot_run, "robot walk → run (glTF, in place)"), figures::skate(&robot_run, &robot_walk, "robot run → walk (glTF, in place)")] {
        println!("  {:<30} without locking {:6.2} cm   with locking {:6.3} cm   ({} frames held by IK, cycle-aligned {})", s.label, s.without_lock.drift_without_lock_cm, s.with_lock.drift_with_lock_cm, s.with_lock.locked_frames, s.with_lock.cyclic);
    }

    println!("== foot skate over whole animations (every detected planted run, not only the blends)");
    for text in ["太郎は走って，ボールを蹴る．そして喜ぶ．", "歩いて、走って、歩く。", "歩きながら右手を振る", "Walk, then jump and cheer. After that, turn around and bow."] {
        let a = animate_text(text, &lib).expect("animate");
        let (max, mean) = figures::whole_skate_cm(&a.clip);
        println!("  {:<60} max {:5.2} cm, mean {:5.2} cm per planted run", text, max, mean);
    }

    println!("== sway transfer, 'walk while waving the right hand' (composed interval)");
    let s = figures::sway(&lib);
    println!("  hips: variance of deviation from plain walking {:.4} deg² with sway, {:.4} deg² without", s.hips_var_with, s.hips_var_without);
    println!("  neck: variance of deviation from plain walking {:.4} deg² with sway, {:.4} deg² without", s.neck_var_with, s.neck_var_without);
    println!("  correlation of neck sideways tilt velocity with the hand's sideways velocity: {:.3} with sway, {:.3} without (in the wave clip itself: {:.3})", s.neck_hand_corr_with, s.neck_hand_corr_without, s.neck_hand_corr_wave);
    println!("  sway joints: {:?}", s.report_with.sway_joints);

    println!("== switch times: F against fixed (walk + wave right hand; effector = right hand relative to the hips)");
    for (label, r) in figures::switch_times(&lib) {
        let t = r.times;
        println!(
            "  {:<34} base {}..{} overlay {}..{} | gap at start {:5.1} cm, at end {:5.1} cm | peak hand step {:.2} cm/frame | blend {:.2}/{:.2} s | stretch {:.2} | F {:.3}/{:.3}",
            label, t.base_start_frame, t.base_end_frame, t.overlay_start_frame, t.overlay_end_frame, r.start_gap_cm, r.end_gap_cm, r.peak_effector_step_cm, r.start_blend_secs, r.end_blend_secs, r.stretch, r.f_start, r.f_end
        );
    }

    println!("== speed (release build, ms per call; baseline = the same clips concatenated without joins)");
    let paper = "太郎は走って，ボールを蹴る．そして喜ぶ．";
    let long: String = (0..100).map(|k| ["太郎は走って、ボールを蹴る。", "Taro walks while waving his left hand.", "うなずいて、お辞儀する。", "Jump, then cheer."][k % 4]).collect();
    for (label, text, reps) in [("paper's sentence", paper, 20), ("100 sentences (200 elements)", long.as_str(), 3)] {
        let (parse_ms, _) = time(reps, || parse(text, &Lexicon::for_library(&lib)));
        let (base_ms, base) = time(reps, || naive_concat(text, &lib));
        let (anim_ms, a) = time(reps, || animate_text(text, &lib).expect("animate"));
        println!(
            "  {:<30} parse {:8.3} ms | animate {:8.2} ms | naive concat {:7.3} ms | ratio {:6.1}× | {} elements, {:.1} s of motion ({} frames; naive {} frames)",
            label, parse_ms, anim_ms, base_ms, anim_ms / base_ms.max(1e-9), a.elements.len(), a.clip.duration_secs(), a.clip.frame_count(), base.frame_count()
        );
    }
}
