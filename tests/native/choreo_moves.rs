//! A contact sheet of the built-in moves (tests/artifacts/choreo_moves.png): one row per step,
//! 8 poses per bar (every half count), front view, with the move's arm pattern varying by row.
//! Checks that every step moves the feet and every arm pattern moves the hands.

mod png;

use odori_core::canon::humanoid::Canon;
use odori_core::library::{builtin_clips, builtin_moves, Arms, Energy, Step};

#[test]
fn contact_sheet_and_moves_move() {
    let clips = builtin_clips();
    let moves = builtin_moves();
    let rows: Vec<usize> = Step::ALL
        .iter()
        .enumerate()
        .map(|(i, &s)| moves.iter().position(|m| m.step == s && m.arms == Arms::ALL[i % Arms::ALL.len()] && m.energy == Energy::High && !m.mirrored).unwrap())
        .collect();
    let (cell_w, cell_h) = (90u32, 150u32);
    let cols = 8u32;
    let mut c = png::Canvas::new(cell_w * cols, cell_h * rows.len() as u32);
    let bones: Vec<(usize, usize)> = Canon::links().map(|(p, ch)| (p.index(), ch.index())).collect();
    for (r, &mi) in rows.iter().enumerate() {
        let clip = &clips[mi];
        let frames = clip.frame_count() - 1;
        for k in 0..cols as usize {
            let f = k * frames / cols as usize;
            let p = clip.world_positions(f);
            let root = clip.root_translation(0);
            let (ox, oy) = ((k as u32 * cell_w + cell_w / 2) as f32, ((r as u32 + 1) * cell_h - 8) as f32);
            let to = |v: glam::Vec3| (ox - (v.x - root.x) * 75.0, oy - v.y * 75.0);
            c.line((ox - 40.0, oy), (ox + 40.0, oy), [200, 200, 200], 0);
            for &(a, b) in &bones {
                let col = if a >= Canon::LeftUpperLeg.index() || b >= Canon::LeftUpperLeg.index() { [40, 90, 200] } else if (5..13).contains(&b) { [200, 60, 40] } else { [30, 30, 30] };
                c.line(to(p[a]), to(p[b]), col, 1);
            }
            c.dot(to(p[Canon::Head.index()]), 5, [30, 30, 30]);
        }
        println!("row {}: {}", r + 1, clip.name);
    }
    let path = png::artifacts_dir().join("choreo_moves.png");
    std::fs::write(&path, c.png()).unwrap();
    println!("contact sheet: {}", path.display());
    // Every step moves the feet relative to the hips, every arm pattern the hands.
    let travel = |clip: &odori_core::Clip, j: Canon| -> f32 {
        (1..clip.frame_count())
            .map(|f| {
                let (a, b) = (clip.world_positions(f - 1), clip.world_positions(f));
                ((b[j.index()] - b[0]) - (a[j.index()] - a[0])).length()
            })
            .sum()
    };
    for (m, clip) in moves.iter().zip(&clips).step_by(5) {
        let feet = travel(clip, Canon::LeftFoot) + travel(clip, Canon::RightFoot);
        let hands = travel(clip, Canon::LeftHand) + travel(clip, Canon::RightHand);
        assert!(feet > 0.2 || matches!(m.step, Step::BodyRoll | Step::HipSway | Step::Bounce), "{}: feet travel {feet}", clip.name);
        // The ballroom frame holds the arms by design (they rise and fall with the bar only).
        let hands_goal = if m.arms == Arms::Frame { 0.2 } else { 0.5 };
        assert!(hands > hands_goal, "{}: hands travel {hands}", clip.name);
    }
}
