//! Issue #14 figures: foot drift at serial joins over EVERY ordered pair of the built-in
//! actions, joined as Transition and as Connection, measured independently of the join's own
//! contact detection ([`odori_tests::foot_stay_drift_cm`], after spec §J foot skate: a foot
//! joint — ankle or toe — is on the floor while within 5 cm of its floor, the 1st percentile
//! of its height over the clip; its drift is the largest horizontal distance from where it
//! touched down, over each stay on the floor). The join's share is what the joined animation
//! adds to the worse of the two actions alone, all measured on the joined animation's floors
//! ([`odori_tests::join_added_drift_cm`]). Printed for the join as shipped (foot locking
//! and stepping) and, as the control, for the same join with `foot_lock: false` (the blend
//! alone). Beside it the join jump (spec §J) around the blend, as a ratio to the actions' own
//! 95th percentile, so smoother feet do not come at the price of a jerk. Goal (issue #14):
//! < 2 cm at every pair. `cargo bench -p odori-tests --bench join_drift`.

use std::time::Instant;

use odori_core::actions::{join_serial, ActionLibrary, JoinKind, JoinOptions};
use odori_core::Clip;
use odori_tests::{foot_stay_drift_cm, join_added_drift_cm, join_jump_ratio};

fn percentile(v: &[f32], q: f32) -> f32 {
    let mut v = v.to_vec();
    v.sort_by(f32::total_cmp);
    v.get(((v.len().max(1) - 1) as f32 * q).round() as usize).copied().unwrap_or(0.0)
}

struct Figures {
    added_cm: Vec<f32>,
    joined_cm: Vec<f32>,
    jump: Vec<f32>,
    rows: Vec<(f32, f32, String)>,
    failed: usize,
}

fn run(actions: &[(String, Clip)], kind: JoinKind, foot_lock: bool) -> Figures {
    let mut fig = Figures { added_cm: Vec::new(), joined_cm: Vec::new(), jump: Vec::new(), rows: Vec::new(), failed: 0 };
    let opts = JoinOptions { foot_lock, ..JoinOptions::default() };
    for (na, a) in actions {
        for (nb, b) in actions {
            match join_serial(a, b, kind, &opts) {
                Ok((c, rep)) => {
                    let (added, d) = join_added_drift_cm(&c, a, b);
                    let tail = (0.5 * c.fps) as usize;
                    fig.jump.push(join_jump_ratio(&c, [a, b], rep.window_start_frame.saturating_sub(1), rep.window_end_frame + tail));
                    fig.joined_cm.push(d);
                    fig.added_cm.push(added);
                    fig.rows.push((added, d, format!("{na} → {nb}")));
                }
                Err(e) => {
                    fig.failed += 1;
                    println!("  {na} → {nb}: {e}");
                }
            }
        }
    }
    fig.rows.sort_by(|x, y| y.0.total_cmp(&x.0));
    fig
}

fn main() {
    let lib = ActionLibrary::builtin();
    let actions: Vec<(String, Clip)> = lib.entries.iter().filter(|e| e.builtin).map(|e| (e.name.clone(), e.clip_for(2.2))).collect();
    let alone: Vec<f32> = actions.iter().map(|(_, c)| foot_stay_drift_cm(c)).collect();
    println!("join drift over every ordered pair of {} built-in actions ({} pairs per kind)", actions.len(), actions.len() * actions.len());
    println!("foot joints: ankles and toes; contact: within 5 cm of the joint's 1st-percentile height; drift: horizontal, from touch-down");
    println!("actions alone, each on its own floor: max {:.2} cm; a join's share is the joined clip's drift less the worse source's, all on the joined clip's floors", alone.iter().copied().fold(0.0, f32::max));
    for kind in [JoinKind::Transition, JoinKind::Connection] {
        for foot_lock in [true, false] {
            let t0 = Instant::now();
            let f = run(&actions, kind, foot_lock);
            let secs = t0.elapsed().as_secs_f64();
            let over = f.added_cm.iter().filter(|&&d| d >= 2.0).count();
            println!(
                "{kind:?} {}: {} pairs in {secs:.1} s ({} failed); drift added by the join: max {:.2} cm, p95 {:.2} cm, {over} pairs ≥ 2 cm | whole joined animation: max {:.2} cm, p95 {:.2} cm | join jump ratio: max {:.2}, p95 {:.2}, median {:.2}",
                if foot_lock { "with foot locking" } else { "CONTROL, blend alone (foot_lock off)" },
                f.added_cm.len(),
                f.failed,
                percentile(&f.added_cm, 1.0),
                percentile(&f.added_cm, 0.95),
                percentile(&f.joined_cm, 1.0),
                percentile(&f.joined_cm, 0.95),
                percentile(&f.jump, 1.0),
                percentile(&f.jump, 0.95),
                percentile(&f.jump, 0.5),
            );
            for (added, d, label) in f.rows.iter().take(if foot_lock { 5 } else { 3 }) {
                println!("    worst: {label:<28} +{added:.2} cm (joined {d:.2} cm)");
            }
        }
    }
}
