//! Text → animation end to end (issue 6): the paper's sentence, composition with sway,
//! foot locking during Transitions, switch times by F, person-tagged and real imported clips,
//! and bad input.

#[path = "../text_figures.rs"]
mod figures;

use odori_core::actions::{detect_contacts, ActionLibrary, BodyPart};
use odori_core::canon::humanoid::Canon;
use odori_core::import::{import_bytes, ImportOptions};
use odori_core::text::{animate_table, animate_text, animate_text_with_progress, parse, DiagnosticKind, JoinType, Lexicon, TextError};
use odori_tests::read;

fn lib() -> ActionLibrary {
    ActionLibrary::builtin()
}

#[test]
fn papers_sentence_animates_with_three_rows() {
    let lib = lib();
    let a = animate_text("太郎は走って，ボールを蹴る．そして喜ぶ．", &lib).unwrap();
    let rows: Vec<(&str, JoinType, Option<usize>)> = a.elements.iter().map(|e| (e.motion.as_str(), e.join, e.previous)).collect();
    assert_eq!(rows, [("run", JoinType::Initial, None), ("kick", JoinType::Transition, Some(0)), ("rejoice", JoinType::Connection, Some(1))]);
    a.clip.validate().unwrap();
    assert_eq!(a.joins.len(), 2);
    // Start times: in order; the Transition overlaps the run, the Connection does not.
    let (run, kick, joy) = (&a.elements[0], &a.elements[1], &a.elements[2]);
    assert_eq!(run.start_secs, 0.0);
    assert!(kick.start_secs > 0.5 && kick.start_secs < run.start_secs + lib.entries[run.clip.unwrap()].clip_for(2.2).duration_secs());
    assert!(joy.start_secs >= kick.start_secs + kick.duration_secs - 1e-3, "{kick:?} {joy:?}");
    let total = a.clip.duration_secs();
    assert!(joy.start_secs < total);
    // The figure travels while running and stays on the floor.
    let root = &a.clip.translations[0].values;
    assert!(root[root.len() - 1].z - root[0].z > 2.0, "ran {}", root[root.len() - 1].z - root[0].z);
    for f in (0..a.clip.frame_count()).step_by(5) {
        let p = a.clip.world_positions(f);
        let low = p.iter().map(|v| v.y).fold(f32::MAX, f32::min);
        assert!(low > -0.06 && low < 0.5, "frame {f}: lowest {low}");
    }
    for j in &a.joins {
        assert!(j.drift_with_lock_cm < 2.0, "{j:?}");
    }
    // Over the whole animation, every detected planted run (not only the blends).
    let (max_cm, mean_cm) = figures::whole_skate_cm(&a.clip);
    println!("paper's sentence, whole animation: planted-foot drift max {max_cm:.2} cm, mean {mean_cm:.2} cm");
    assert!(max_cm < 4.0 && mean_cm < 1.0, "{max_cm} {mean_cm}");
    // The table serialises the way JavaScript gets it.
    let json = serde_json::to_value(&a.elements).unwrap();
    assert_eq!(json[1]["join"], "transition");
    assert_eq!(json[1]["previous"], 0);
    assert!(json[0]["startSecs"].is_number() && json[0]["clipName"].is_string());
}

#[test]
fn english_equivalent_animates_the_same_way() {
    let lib = lib();
    let ja = animate_text("太郎は走って，ボールを蹴る．そして喜ぶ．", &lib).unwrap();
    let en = animate_text("Taro runs, then kicks the ball. Then he rejoices.", &lib).unwrap();
    let key = |a: &odori_core::text::TextAnimation| a.elements.iter().map(|e| (e.motion.clone(), e.join, e.previous, e.clip, e.start_secs)).collect::<Vec<_>>();
    assert_eq!(key(&ja), key(&en));
    assert_eq!(ja.clip.frame_count(), en.clip.frame_count());
}

#[test]
fn walking_while_waving_composes_the_right_arm() {
    let lib = lib();
    let a = animate_text("歩きながら右手を振る", &lib).unwrap();
    assert_eq!(a.elements.len(), 2);
    assert_eq!(a.elements[1].join, JoinType::Composition);
    assert_eq!(a.elements[1].switched_part, Some(BodyPart::RightArm));
    assert_eq!(a.compositions.len(), 1);
    let (w, v) = (&a.elements[0], &a.elements[1]);
    assert!(v.start_secs >= w.start_secs && v.start_secs + v.duration_secs <= w.start_secs + w.duration_secs + 1e-3);
    // While the wave plays, the right hand is up and the legs still walk.
    let mid = ((v.start_secs + 0.5 * v.duration_secs) * a.clip.fps) as usize;
    let p = a.clip.world_positions(mid);
    assert!(p[Canon::RightHand.index()].y > p[Canon::Head.index()].y - 0.15);
    let c = detect_contacts(&a.clip);
    assert!(c.has_cycle());
}

#[test]
fn sway_moves_hips_and_neck_with_the_wave() {
    let s = figures::sway(&lib());
    println!(
        "sway: hips var {:.4} vs {:.4} deg², neck var {:.4} vs {:.4} deg², neck-hand corr {:.3} vs {:.3} (wave itself {:.3})",
        s.hips_var_with, s.hips_var_without, s.neck_var_with, s.neck_var_without, s.neck_hand_corr_with, s.neck_hand_corr_without, s.neck_hand_corr_wave
    );
    assert!(s.hips_var_without < 0.01 && s.neck_var_without < 0.01, "without sway the body is the walk's");
    assert!(s.hips_var_with > 0.05 && s.neck_var_with > 0.5, "with sway hips and neck move");
    assert!(s.neck_hand_corr_with.abs() > s.neck_hand_corr_without.abs() + 0.1, "the neck follows the wave");
    assert!(s.report_with.sway_joints.contains(&Canon::Hips) && s.report_with.sway_joints.contains(&Canon::Neck));
}

#[test]
fn switch_times_by_f_jump_less_than_fixed_ones() {
    let rows = figures::switch_times(&lib());
    for (label, r) in &rows {
        println!("{label}: start gap {:.1} cm, end gap {:.1} cm, peak step {:.2} cm/frame, blends {:.2}/{:.2} s, stretch {:.2}", r.start_gap_cm, r.end_gap_cm, r.peak_effector_step_cm, r.start_blend_secs, r.end_blend_secs, r.stretch);
    }
    let f = &rows[0].1;
    for (label, r) in &rows[1..] {
        assert!(f.start_gap_cm + f.end_gap_cm <= r.start_gap_cm + r.end_gap_cm + 1e-3, "F should not leave larger gaps than {label}");
    }
}

/// Transitions known to drift a locked foot ≥ 2 cm, each with the most it may drift, cm: walk →
/// jump since the one foot-contact rule (`canon::contact`) took the text actions' contacts
/// (4.53 cm locked, 4.42 of it with the root alone: its landing frames are planted now, 43.4 cm
/// unlocked). An entry must leave once its transition is within 2 cm.
const KNOWN_LOCKED_DRIFT_CM: &[(&str, f32)] = &[("walk → jump", 4.6)];

#[test]
fn planted_feet_stay_put_during_transitions() {
    for s in figures::builtin_skates(&lib()) {
        println!("{}: drift {:.2} cm unlocked, {:.3} cm locked ({} frames held)", s.label, s.without_lock.drift_without_lock_cm, s.with_lock.drift_with_lock_cm, s.with_lock.locked_frames);
        let bound = match KNOWN_LOCKED_DRIFT_CM.iter().find(|(l, _)| *l == s.label) {
            Some(&(_, ceiling)) => {
                assert!(s.with_lock.drift_with_lock_cm >= 2.0, "{}: within 2 cm now: take it off KNOWN_LOCKED_DRIFT_CM", s.label);
                ceiling
            }
            None => 2.0,
        };
        assert!(s.with_lock.drift_with_lock_cm < bound, "{}: {:?}", s.label, s.with_lock);
        assert!(s.with_lock.drift_with_lock_cm <= s.without_lock.drift_without_lock_cm + 0.05, "{}", s.label);
    }
}

#[test]
fn person_tagged_clip_is_found_by_its_tags() {
    let mut lib = lib();
    assert!(parse("太郎は踊って、蹴る。", &Lexicon::for_library(&lib)).diagnostics.iter().any(|d| d.kind == DiagnosticKind::UnknownVerb));
    let demo = odori_core::canon::builtin::demo_clip();
    let i = lib.add_clip(&demo, &["dance".into(), "踊る".into()], None).unwrap();
    let a = animate_text("太郎は踊って、蹴る。", &lib).unwrap();
    assert!(a.diagnostics.iter().all(|d| d.kind != DiagnosticKind::UnknownVerb), "{:?}", a.diagnostics);
    assert_eq!(a.elements[0].clip, Some(i));
    let e = animate_text("Taro dances, then kicks.", &lib).unwrap();
    assert_eq!(e.elements[0].clip, Some(i));
    assert_eq!(e.elements[1].join, JoinType::Transition);
    // Swapping an element's clip for another with the same tag re-animates the table.
    let mut table = a.elements.clone();
    let kick_alt = lib.add_clip(&lib.entries[lib.find("kick", &[]).unwrap()].clip.clone(), &["kick".into()], None).unwrap();
    table[1].clip = Some(kick_alt);
    let swapped = animate_table(&table, &lib, Vec::new()).unwrap();
    assert_eq!(swapped.elements[1].clip, Some(kick_alt));
    let builtin_kick = lib.entries.iter().position(|e| e.builtin && e.has_tag("kick")).unwrap();
    assert_eq!(lib.alternatives(kick_alt, "kick"), [builtin_kick]);
    assert_eq!(swapped.elements[1].alternatives, [builtin_kick]);
    // The table goes to JavaScript and comes back edited as JSON (camelCase).
    let json = serde_json::to_string(&swapped.elements).unwrap();
    assert!(json.contains("\"switchedPart\"") && json.contains("\"delaySecs\"") && json.contains("\"utf16Start\""));
    let back: Vec<odori_core::text::TimeTableElement> = serde_json::from_str(&json).unwrap();
    assert_eq!(back, swapped.elements);
    let again = animate_table(&back, &lib, Vec::new()).unwrap();
    assert_eq!(again.clip.frame_count(), swapped.clip.frame_count());
    let whole = serde_json::to_value(&again).unwrap();
    assert!(whole["clip"]["rotations"].is_array() && whole["joins"][0]["driftWithLockCm"].is_number());
}

#[test]
fn real_salsa_tagged_by_the_person_joins_built_in_actions() {
    let rel = "mocap/cmu-salsa/salsa_01.bvh";
    let imported = import_bytes(rel, &read(rel), &ImportOptions { fps_override: odori_tests::fps_override_for(rel), ..ImportOptions::default() }).unwrap();
    // The person trims eight seconds and tags them.
    let take = imported.clips[0].slice(0, 480, "salsa_01 (0–8 s)");
    let mut lib = lib();
    let i = lib.add_clip(&take, &["salsa".into(), "dance".into(), "踊る".into()], None).unwrap();
    let salsa = &lib.entries[i].clip;
    salsa.validate().unwrap();
    assert_eq!(salsa.joint_count(), 21, "retargeted onto the canonical skeleton");
    let c = detect_contacts(salsa);
    let steps = c.events().len();
    assert!(steps >= 4, "the salsa's steps are found ({steps} contact events)");
    for (text, kind) in [("太郎は踊って、走る。", JoinType::Transition), ("Taro dances. Then he bows.", JoinType::Connection), ("走って、サルサを踊る", JoinType::Transition)] {
        let a = animate_text(text, &lib).unwrap();
        assert_eq!(a.elements.len(), 2, "{text}: {:?}", a.diagnostics);
        assert_eq!(a.elements[1].join, kind, "{text}");
        assert!(a.elements.iter().any(|e| e.clip == Some(i)), "{text}");
        a.clip.validate().unwrap();
        let j = &a.joins[0];
        println!("real salsa, '{text}': drift {:.2} cm unlocked, {:.3} cm locked, {} frames held", j.drift_without_lock_cm, j.drift_with_lock_cm, j.locked_frames);
        assert!(j.drift_with_lock_cm < 2.0, "{text}: {j:?}");
    }
}

#[test]
fn real_robot_wave_composes_onto_its_walk() {
    let rel = "gltf/RobotExpressive.glb";
    let imported = import_bytes(rel, &read(rel), &ImportOptions::default()).unwrap();
    let clip = |n: &str| imported.clips.iter().find(|c| c.name == n).unwrap_or_else(|| panic!("{n} in {rel}"));
    let mut lib = lib();
    let walk = lib.add_clip(clip("Walking"), &["walk".into()], None).unwrap();
    let wave = lib.add_clip(clip("Wave"), &["wave".into(), "right".into()], Some(BodyPart::RightArm)).unwrap();
    assert!(lib.entries[walk].cycle_advance.is_some(), "the robot's walk loops");
    let a = animate_text("歩きながら右手を振る", &lib).unwrap();
    assert_eq!(a.elements.iter().map(|e| e.clip).collect::<Vec<_>>(), [Some(walk), Some(wave)]);
    assert_eq!(a.elements[1].join, JoinType::Composition);
    assert_eq!(a.compositions.len(), 1);
    let r = &a.compositions[0];
    println!("robot walk + wave: switch base {}..{} overlay {}..{}, gaps {:.1}/{:.1} cm, blends {:.2}/{:.2} s", r.times.base_start_frame, r.times.base_end_frame, r.times.overlay_start_frame, r.times.overlay_end_frame, r.start_gap_cm, r.end_gap_cm, r.start_blend_secs, r.end_blend_secs);
    assert!(r.times.base_end_frame > r.times.base_start_frame + 30);
    a.clip.validate().unwrap();
    // The composed right arm is the robot's wave, the legs its walk.
    let n = a.clip.joint_count();
    let mid = (r.times.base_start_frame + r.times.base_end_frame) / 2;
    let composed = &a.clip.rotations[mid * n..(mid + 1) * n];
    // The walk at the same time: the cycle repeats every `frames / fps` seconds (its frames
    // tile), so frame `mid` at 60 fps is cycle position `mid · fps / 60` modulo its frames.
    let cycle = lib.entries[walk].clip_for(0.0);
    let x = (mid as f32 * cycle.fps / 60.0) % cycle.frame_count() as f32;
    let (f0, a) = (x.floor() as usize, x.fract());
    let f1 = (f0 + 1) % cycle.frame_count();
    let plain: Vec<_> = (0..n).map(|j| cycle.rotations[f0 * n + j].slerp(cycle.rotations[f1 * n + j], a)).collect();
    assert!(composed[Canon::LeftLowerLeg.index()].angle_between(plain[Canon::LeftLowerLeg.index()]) < 1e-3);
    assert!(composed[Canon::RightUpperArm.index()].angle_between(plain[Canon::RightUpperArm.index()]) > 0.1);
    // The robot walks and runs on the spot; the library gives them their travel back, so
    // its run → walk is a cycle-aligned Transition with the planted foot locked.
    let run = lib.add_clip(clip("Running"), &["run".into()], None).unwrap();
    assert!(lib.entries[walk].cycle_advance.is_some_and(|v| v.length() > 0.5), "{:?}", lib.entries[walk].cycle_advance);
    assert!(lib.entries[run].cycle_advance.is_some_and(|v| v.length() > 0.3), "{:?}", lib.entries[run].cycle_advance);
    let t = animate_text("走って、歩く", &lib).unwrap();
    assert_eq!(t.elements.iter().map(|e| e.clip).collect::<Vec<_>>(), [Some(run), Some(walk)]);
    let j = &t.joins[0];
    println!("robot run → walk: cyclic {}, drift {:.2} cm unlocked, {:.3} cm locked", j.cyclic, j.drift_without_lock_cm, j.drift_with_lock_cm);
    assert!(j.cyclic && j.drift_with_lock_cm < 2.0, "{j:?}");
}

#[test]
fn bad_input_gives_clear_messages_and_partial_results() {
    let lib = lib();
    assert_eq!(animate_text("", &lib).unwrap_err(), TextError::Empty);
    assert_eq!(animate_text("   \n ", &lib).unwrap_err(), TextError::Empty);
    match animate_text("太郎は踊る。Taro sings.", &lib) {
        Err(e @ TextError::NoActions { .. }) => {
            let msg = e.to_string();
            assert!(msg.contains("踊る") && msg.contains("sings"), "{msg}");
        }
        other => panic!("{other:?}"),
    }
    for junk in ["。。。", "!!!", "🙂🙂", "1234", "走", "て、ながら。", "while while while", "99999秒後に跳ぶ"] {
        let r = animate_text(junk, &lib);
        assert!(r.is_ok() || matches!(r, Err(TextError::NoActions { .. })), "{junk}: {r:?}");
    }
    // Very long text: 100 sentences animate, nothing lost.
    let long: String = (0..100).map(|k| ["太郎は走って、ボールを蹴る。", "Taro walks while waving his left hand.", "うなずいて、お辞儀する。", "Jump, then cheer."][k % 4]).collect();
    let a = animate_text(&long, &lib).unwrap();
    assert!(a.elements.len() >= 200, "{} elements", a.elements.len());
    a.clip.validate().unwrap();
    assert!(a.elements.windows(2).all(|w| w[1].join == JoinType::Composition || w[1].start_secs >= w[0].start_secs));
    assert!(a.diagnostics.iter().any(|d| d.kind == DiagnosticKind::MixedLanguages));
    // A part motion that outlasts its one-shot base still runs with it (issue #14: "clap while
    // jumping" is a Composition): the part plays as much as fits, said so.
    let f = animate_text("Nod while waving the right hand.", &lib).unwrap();
    let joins: Vec<JoinType> = f.elements.iter().map(|e| e.join).collect();
    assert_eq!(joins, [JoinType::Initial, JoinType::Composition], "{:?}", f.elements);
    assert!(f.diagnostics.iter().any(|d| d.kind == DiagnosticKind::JoinFallback));
    assert!(f.elements[1].duration_secs > 0.5 && f.elements[1].duration_secs <= f.elements[0].duration_secs);
    // Progress is reported and cancel stops early.
    let mut calls = Vec::new();
    animate_text_with_progress("走って、蹴る。喜ぶ。", &lib, &mut |d, t| {
        calls.push((d, t));
        true
    })
    .unwrap();
    assert_eq!(calls.first(), Some(&(0, 3)));
    assert_eq!(calls.last(), Some(&(3, 3)));
    let r = animate_text_with_progress(&long, &lib, &mut |d, _| d < 5);
    assert!(matches!(r, Err(TextError::Cancelled { done: 5, .. })), "{r:?}");
    // A delay before the first action holds the first pose.
    let first = animate_text("太郎は三秒後に座った。", &lib).unwrap();
    assert!((first.elements[0].start_secs - 3.0).abs() < 1e-3, "{:?}", first.elements[0]);
    assert_eq!(first.clip.frame_count(), 180 + lib.entries[lib.find("sit", &[]).unwrap()].clip.frame_count());
    first.clip.validate().unwrap();
    // A huge stated delay is capped.
    let d = animate_text("走る。99999秒後に跳ぶ。", &lib).unwrap();
    assert!(d.clip.duration_secs() < 60.0, "{}", d.clip.duration_secs());
    // Mixed with unknown words: the rest plays, the unknown one is located.
    let m = animate_text("太郎は走って, then juggles. 喜ぶ。", &lib).unwrap();
    assert_eq!(m.elements.iter().map(|e| e.motion.as_str()).collect::<Vec<_>>(), ["run", "rejoice"]);
    let d = m.diagnostics.iter().find(|d| d.kind == DiagnosticKind::UnknownVerb).unwrap();
    assert_eq!(d.text, "juggles");
    assert_eq!(d.span.start, 13);
    assert_eq!(d.span.utf16_start, 13);
}
