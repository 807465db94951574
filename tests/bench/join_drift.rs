//! Issue #14 figures: foot drift at serial joins over EVERY ordered pair of the built-in
//! actions, joined as Transition and as Connection, measured independently of the join's own
//! contact detector (spec §J foot skate: a foot joint — ankle or toe — is on the floor while
//! within 5 cm of its floor, the 1st percentile of its height over the clip; its drift is the
//! largest horizontal distance from where it touched down, over each stay on the floor). The
//! control is the same measure on the two actions alone: the join's share is what the joined
//! animation adds to the worse of the two. Goal (issue #14): < 2 cm at every pair.
//! `cargo bench -p odori-tests --bench join_drift`.

use std::time::Instant;

use glam::Vec3;
use odori_core::actions::{join_serial, ActionLibrary, JoinKind, JoinOptions};
use odori_core::humanoid::Canon;
use odori_core::Clip;

/// Contact: within this height of the joint's floor, metres (spec §J).
const CONTACT_M: f32 = 0.05;

/// Largest drift of any foot joint during any stay on the floor, centimetres.
fn drift_cm(clip: &Clip) -> f32 {
    let joints = [Canon::LeftFoot, Canon::RightFoot, Canon::LeftToe, Canon::RightToe];
    let all = clip.all_world_positions();
    let n = clip.joint_count();
    let frames = clip.frame_count();
    let mut worst = 0.0f32;
    for j in joints {
        let heights: Vec<f32> = (0..frames).map(|f| all[f * n + j.index()].y).collect();
        let mut sorted = heights.clone();
        sorted.sort_by(f32::total_cmp);
        let floor = sorted[(sorted.len() as f32 * 0.01) as usize];
        let mut anchor: Option<Vec3> = None;
        for f in 0..frames {
            let p = all[f * n + j.index()];
            if heights[f] <= floor + CONTACT_M {
                let a = *anchor.get_or_insert(p);
                worst = worst.max(Vec3::new(p.x - a.x, 0.0, p.z - a.z).length());
            } else {
                anchor = None;
            }
        }
    }
    worst * 100.0
}

fn percentile(v: &mut [f32], q: f32) -> f32 {
    v.sort_by(f32::total_cmp);
    v[((v.len() - 1) as f32 * q).round() as usize]
}

fn main() {
    let lib = ActionLibrary::builtin();
    let actions: Vec<(String, Clip)> = lib.entries.iter().filter(|e| e.builtin).map(|e| (e.name.clone(), e.clip_for(2.2))).collect();
    let alone: Vec<f32> = actions.iter().map(|(_, c)| drift_cm(c)).collect();
    println!("join drift over every ordered pair of {} built-in actions ({} pairs per kind)", actions.len(), actions.len() * actions.len());
    println!("foot joints: ankles and toes; contact: within {:.0} cm of the joint's 1st-percentile height; drift: horizontal, from touch-down", CONTACT_M * 100.0);
    for kind in [JoinKind::Transition, JoinKind::Connection] {
        let t0 = Instant::now();
        let mut joined_cm = Vec::new();
        let mut added_cm = Vec::new();
        let mut rows = Vec::new();
        let mut failed = 0;
        for (i, (na, a)) in actions.iter().enumerate() {
            for (k, (nb, b)) in actions.iter().enumerate() {
                match join_serial(a, b, kind, &JoinOptions::default()) {
                    Ok((c, _)) => {
                        let d = drift_cm(&c);
                        let added = (d - alone[i].max(alone[k])).max(0.0);
                        joined_cm.push(d);
                        added_cm.push(added);
                        rows.push((added, d, format!("{na} → {nb}")));
                    }
                    Err(e) => {
                        failed += 1;
                        println!("  {na} → {nb}: {e}");
                    }
                }
            }
        }
        let secs = t0.elapsed().as_secs_f64();
        rows.sort_by(|x, y| y.0.total_cmp(&x.0));
        let over = added_cm.iter().filter(|&&d| d >= 2.0).count();
        let n = added_cm.len();
        println!(
            "{kind:?}: {n} pairs in {secs:.1} s ({failed} failed); drift added by the join: max {:.2} cm, p95 {:.2} cm, {over} pairs ≥ 2 cm | whole joined animation: max {:.2} cm, p95 {:.2} cm | control, actions alone: max {:.2} cm",
            percentile(&mut added_cm, 1.0),
            percentile(&mut added_cm.clone(), 0.95),
            percentile(&mut joined_cm, 1.0),
            percentile(&mut joined_cm.clone(), 0.95),
            alone.iter().copied().fold(0.0, f32::max),
        );
        for (added, d, label) in rows.iter().take(8) {
            println!("    worst: {label:<28} +{added:.2} cm (joined {d:.2} cm)");
        }
    }
}
