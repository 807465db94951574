//! Unit tests of the segment library: links, tempo detection, cutting in 3 and 4, the count
//! warp, beat fit, kinetic beats per count, loading in slices, signatures.

use crate::fmath;
use super::library::*;
use super::signature::*;
use super::tempo::*;
use super::types::*;
use super::*;
use super::super::eigen::Signature;
use crate::canon::humanoid::{Canon, HumanoidMap, HumanoidStatus, CANON_COUNT};
use crate::canon::normalize::{body_height, normalize_in_place, Origin};
use glam::Vec3;

#[test]
fn links_match_the_canonical_tree() {
    let from_tree: Vec<(usize, usize)> = Canon::links().map(|(p, c)| (p.index(), c.index())).collect();
    assert_eq!(from_tree, LINKS.to_vec());
}

#[test]
fn detects_the_tempo_of_a_pulsing_speed_curve() {
    // 110 counts per minute with dips on every count.
    let period = LIBRARY_FPS * 60.0 / 110.0;
    let speed: Vec<f32> = (0..600).map(|f| 2.0 - fmath::cos(f as f32 / period * std::f32::consts::TAU) + 0.1 * ((f * 7 % 13) as f32 / 13.0)).collect();
    let (beats, p) = detect_beats(&speed);
    assert!((p - period).abs() < 0.5, "period {p} vs {period}");
    assert!(beats.len() >= 30);
    for b in &beats {
        let phase = (b / period).fract();
        assert!(phase < 0.12 || phase > 0.88, "beat at {b} is off the dips");
    }
}

#[test]
fn comb_finds_the_count_of_uneven_steps_not_their_octave_or_three_to_four() {
    // Salsa-like feet: a step (a bump of speed) on counts 1, 2 and 3 of every 4, none on 4,
    // at 82 counts per minute; the body sways once per bar; a little deterministic noise.
    let fps = LIBRARY_FPS;
    let count = fps * 60.0 / 82.0;
    // SplitMix64 of the frame: white, unlike a bare multiplicative hash (a Weyl sequence).
    let noise = |f: usize| {
        let mut z = (f as u64).wrapping_add(1).wrapping_mul(0x9E37_79B9_7F4A_7C15);
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^= z >> 31;
        0.2 * ((z >> 40) as f32 / (1u64 << 24) as f32 - 0.5)
    };
    let feet: Vec<f32> = (0..900)
        .map(|f| {
            let c = f as f32 / count;
            let in_bar = c.rem_euclid(4.0);
            let step = if in_bar < 3.0 { fmath::sin(std::f32::consts::PI * in_bar.fract()).powi(2) } else { 0.0 };
            1.0 + step + noise(f)
        })
        .collect();
    let body: Vec<f32> = (0..900).map(|f| 2.0 + fmath::sin(f as f32 / (4.0 * count) * std::f32::consts::TAU) + noise(f + 13)).collect();
    let (period, support) = comb_period(&[feet, body], fps).expect("a period");
    assert!(support > 0.0);
    assert!((period / count - 1.0).abs() < 0.03, "period {period:.2} frames ({:.1}/min) vs {count:.2} (82/min)", fps * 60.0 / period);
    // Noise alone: at best chance support, far below the steps'.
    let flat: Vec<f32> = (0..900).map(|f| 1.0 + noise(f)).collect();
    let chance = comb_period(&[flat.clone(), flat], fps).map_or(0.0, |(_, s)| s);
    assert!(chance < 0.25 * support, "noise support {chance:.3} vs steps {support:.3}");
}

fn seg_with_counts(counts: Vec<f32>) -> Segment {
    Segment {
        index: 0,
        name: "s".into(),
        clip: 0,
        source: "test".into(),
        start_frame: counts[0],
        end_frame: counts[4],
        count_frames: counts,
        beat_fit: 0.5,
        skate_cm_per_s: 0.0,
        clip_skate_cm_per_s: 0.0,
        kinetic_per_count: 0.0,
        kinetic_per_count_by_rate: Vec::new(),
        tempo_bpm: 120.0,
        intensity: 1.0,
        intensity01: 0.5,
        builtin: None,
        retired: false,
    }
}

/// Three built-in moves and one imported clip (a built-in move's frames under another name,
/// cut at a stated 240 counts per minute: 9 counts in its 2 s).
pub(crate) fn small_library_with_an_imported_clip() -> SegmentLibrary {
    let mut lib = SegmentLibrary::new();
    let mut loader = BuiltinLoader::new();
    lib.load_builtin(&mut loader, 3);
    let mut clip = lib.clips()[1].clip.clone();
    clip.name = "imported".into();
    clip.source = "imported.bvh".into();
    let map = HumanoidMap::from_skeleton(&clip.skeleton);
    let options = SegmentOptions { tempo_bpm: Some(240.0), first_beat_secs: Some(0.0), hop_counts: 2 , ..Default::default() };
    lib.add_clip(&clip, &map, &HumanoidStatus::Complete, &options).unwrap();
    lib
}

#[test]
fn imported_clips_are_cut_in_three_and_four_built_in_moves_in_four() {
    let lib = small_library_with_an_imported_clip();
    let (builtin, imported): (Vec<&Segment>, Vec<&Segment>) = lib.segments().iter().partition(|s| s.builtin.is_some());
    assert_eq!(builtin.len(), 3);
    assert!(builtin.iter().all(|s| s.counts() == 4 && s.count_frames.len() == 5));
    let beats = &lib.clips()[3].beat_frames;
    assert_eq!(beats.len(), 9, "{beats:?}");
    // 4 counts every 2 counts (hop_counts): from counts 0, 2, 4; 3 counts on every count:
    // from 0 to 5.
    let of = |n: usize| imported.iter().filter(|s| s.counts() == n).map(|s| s.start_frame).collect::<Vec<f32>>();
    assert_eq!(of(4), [0, 2, 4].map(|k| beats[k].round()));
    assert_eq!(of(3), [0, 1, 2, 3, 4, 5].map(|k| beats[k].round()));
    for s in imported.iter().filter(|s| s.counts() == 3) {
        assert_eq!(s.count_frames.len(), 4);
        assert!(s.name.ends_with("(in 3)"), "{}", s.name);
        // One count per beat of a bar in 3: count k at k/3 of the bar, and back.
        for (k, c) in s.count_frames.iter().enumerate() {
            assert!((s.frame_at(k as f32 / 3.0) - c).abs() < 1e-4, "{}: count {k}", s.name);
            assert!((s.bar_position(*c) - k as f32 / 3.0).abs() < 1e-4, "{}: count {k}", s.name);
        }
        // Its tempo is its 3 counts over its length, as a 4-count one's is its 4.
        assert!((s.tempo_bpm - 3.0 * 60.0 / s.duration_secs()).abs() < 1e-3);
        assert!(s.kinetic_per_count_by_rate.len() == KINETIC_RATES_BPM.len());
        // The lead-in is one of its counts long: a third of the bar.
        assert!((s.frame_before(-1.0 / 3.0) - (s.count_frames[0] - (s.count_frames[1] - s.count_frames[0])).max(0.0)).abs() < 1e-4);
    }
    // A 3-count segment shares frames with the 4-count one from the same count.
    let a = imported.iter().find(|s| s.counts() == 3).unwrap();
    let b = imported.iter().find(|s| s.counts() == 4 && s.start_frame == a.start_frame).unwrap();
    assert!(lib.overlaps[a.index].contains(&b.index));
}

#[test]
fn the_lead_in_is_the_count_before_at_the_first_counts_pace() {
    let s = seg_with_counts(vec![10.0, 20.0, 40.0, 48.0, 60.0]);
    // A quarter of the bar before: one count (10 frames, the first count's length) earlier.
    assert!((s.frame_before(-0.25) - 0.0).abs() < 1e-4);
    assert!((s.frame_before(-0.125) - 5.0).abs() < 1e-4);
    // No further back than a count, nor before the clip's start; in the bar, as frame_at.
    assert!((s.frame_before(-3.0) - 0.0).abs() < 1e-4);
    assert!((seg_with_counts(vec![3.0, 13.0, 23.0, 33.0, 43.0]).frame_before(-0.25) - 0.0).abs() < 1e-4);
    assert!((s.frame_before(0.375) - s.frame_at(0.375)).abs() < 1e-4);
}

#[test]
fn kinetic_beats_per_count_follow_the_count_rate() {
    // Interpolated in log rate between the measured rates, held at the ends, and the
    // own-tempo figure when none were measured.
    let mut s = seg_with_counts(vec![0.0, 15.0, 30.0, 45.0, 60.0]);
    s.kinetic_per_count = 0.75;
    assert_eq!(s.kinetic_per_count_at(100.0), 0.75);
    s.kinetic_per_count_by_rate = vec![2.0, 1.5, 1.25, 1.0, 0.75, 0.5];
    assert_eq!(s.kinetic_per_count_at(40.0), 2.0);
    assert_eq!(s.kinetic_per_count_at(200.0), 0.5);
    assert!((s.kinetic_per_count_at(90.0) - 1.25).abs() < 1e-5);
    let mid = (90.0f32 * 110.0).sqrt();
    assert!((s.kinetic_per_count_at(mid) - 1.125).abs() < 1e-4);
    // A body bobbing so it turns once a count (every 30 frames at 30 fps, 60 counts per
    // minute; the turns 0.3 frame after the counts, off the resampling grid: an exactly
    // symmetric turn is a two-frame tie, no strict minimum): about one kinetic beat a count
    // at every rate, the first count included (the half count around it gives it a turn).
    let rest = crate::canon::builtin::canonical_skeleton().rest_positions();
    let frames = 240;
    let pos: Vec<Vec3> = (0..frames)
        .flat_map(|f| {
            let y = 0.08 * fmath::cos((f as f32 - 0.3) / 30.0 * std::f32::consts::PI);
            rest.iter().map(move |p| *p + Vec3::Y * y)
        })
        .collect();
    let counts = [60.0f32, 90.0, 120.0, 150.0, 180.0];
    let v = kinetic_per_count_by_rate(&pos, &counts);
    assert_eq!(v.len(), KINETIC_RATES_BPM.len());
    for (r, k) in KINETIC_RATES_BPM.iter().zip(&v) {
        assert!((0.75..=1.25).contains(k), "{k} kinetic beats a count at {r} counts per minute ({v:?})");
    }
}

#[test]
fn each_count_lands_on_its_quarter_of_the_bar() {
    // Uneven counts: the second count comes early, the third late.
    let s = seg_with_counts(vec![10.0, 20.0, 40.0, 48.0, 60.0]);
    for (k, c) in [10.0f32, 20.0, 40.0, 48.0, 60.0].iter().enumerate() {
        assert!((s.frame_at(k as f32 / 4.0) - c).abs() < 1e-4, "count {k}");
        assert!((s.bar_position(*c) - k as f32 / 4.0).abs() < 1e-4, "count {k}");
    }
    // Linear between counts.
    assert!((s.frame_at(0.375) - 30.0).abs() < 1e-4);
    // Without counts (an older document), linear over the segment.
    let mut old = s.clone();
    old.count_frames.clear();
    assert!((old.frame_at(0.25) - 22.5).abs() < 1e-4);
}

#[test]
fn beat_fit_in_three_prefers_turns_on_its_three_counts() {
    let counts = [0.0f32, 14.0, 31.0, 45.0];
    let between: Vec<f32> = counts.windows(2).map(|w| 0.5 * (w[0] + w[1])).collect();
    assert!(beat_fit(&counts, &counts) > 0.95);
    assert!(beat_fit(&counts, &between) < 0.05);
}

#[test]
fn beat_fit_prefers_turns_on_the_counts() {
    let counts = [0.0f32, 12.0, 27.0, 39.0, 54.0];
    // Kinetic beats exactly on the counts (uneven as they are): the warp puts them on the
    // bar's quarters.
    let on = beat_fit(&counts, &counts);
    // Kinetic beats halfway between counts.
    let between: Vec<f32> = counts.windows(2).map(|w| 0.5 * (w[0] + w[1])).collect();
    let off = beat_fit(&counts, &between);
    assert!(on > 0.95, "{on}");
    assert!(off < 0.05, "{off}");
    // Turning on counts and between: no preference.
    let both: Vec<f32> = counts.iter().chain(&between).copied().collect();
    assert!((beat_fit(&counts, &both) - 0.5).abs() < 0.05);
}

#[test]
fn builtin_library_loaded_in_slices_is_the_same_library() {
    let whole = SegmentLibrary::builtin();
    let mut sliced = SegmentLibrary::new();
    let mut loader = BuiltinLoader::new();
    let mut steps = 0;
    let mut last = 0.0;
    loop {
        let p = sliced.load_builtin(&mut loader, 37);
        assert!(p > last || p == 1.0, "progress {p} after {last}");
        last = p;
        steps += 1;
        if p >= 1.0 {
            break;
        }
    }
    assert!(steps > 5, "{steps} slices");
    assert_eq!(sliced.len(), whole.len());
    for (a, b) in sliced.segments().iter().zip(whole.segments()) {
        assert_eq!((a.name.as_str(), a.intensity.to_bits(), a.intensity01.to_bits()), (b.name.as_str(), b.intensity.to_bits(), b.intensity01.to_bits()));
    }
    // Asking again once done adds nothing.
    assert_eq!(sliced.load_builtin(&mut loader, 10), 1.0);
    assert_eq!(sliced.len(), whole.len());
}

#[test]
fn builtin_library_has_one_segment_per_move() {
    let lib = SegmentLibrary::builtin();
    assert!(lib.len() >= 200);
    let s = &lib.segments()[0];
    assert!((s.tempo_bpm - 120.0).abs() < 1.0, "{}", s.tempo_bpm);
    let (lo, hi) = lib.segments().iter().fold((f32::MAX, f32::MIN), |(a, b), s| (a.min(s.intensity), b.max(s.intensity)));
    assert!(hi > lo * 1.5, "intensities {lo}..{hi}");
}

#[test]
fn signatures_tell_a_move_from_itself_played_backwards() {
    // Played backwards, a move passes through the same poses: position-only features
    // (their second moments) cannot tell the two apart; the velocities can.
    let lib = SegmentLibrary::builtin();
    let lc = &lib.clips()[3];
    let positions = canonical_world_positions(&lc.clip);
    let mut normed = positions.clone();
    normalize_in_place(&mut normed, Origin::Hips, body_height(&positions));
    let frames = normed.len() / CANON_COUNT;
    let reversed: Vec<Vec3> = (0..frames).rev().flat_map(|f| normed[f * CANON_COUNT..(f + 1) * CANON_COUNT].to_vec()).collect();
    // The same span both ways (every other frame: the reverse samples the frames between).
    let (si, ei) = (0, frames - 1);
    let (a, b) = (signature_of(&normed, si, ei), signature_of(&reversed, si, ei));
    assert!((a.similarity(&a) - 1.0).abs() < 1e-4);
    let positions_only = |n: &[Vec3], from: usize, to: usize| {
        let feats: Vec<f32> = (from..to).step_by(2).flat_map(|f| n[f * CANON_COUNT..(f + 1) * CANON_COUNT].iter().zip(&SIGNATURE_REFERENCE).flat_map(|(p, r)| [p.x - r[0], p.y - r[1], p.z - r[2]]).chain([SIGNATURE_OFFSET]).collect::<Vec<f32>>()).collect();
        Signature::of_uncentred(&feats, CANON_COUNT * 3 + 1, SIGNATURE_AXES)
    };
    let same = positions_only(&normed, si, ei).similarity(&positions_only(&reversed, si, ei));
    let with_velocity = a.similarity(&b);
    println!("a move against itself backwards: Sim {with_velocity} with velocities, {same} on positions only");
    assert!(same > 0.99, "position-only signatures of a move and its reverse: Sim {same}");
    // Raw kWAS bunches near 1 (the search ranks it among each segment's neighbours), so
    // the check is on D = 1 − Sim: the velocities make it a hundred times larger.
    assert!(with_velocity < 0.995 && 1.0 - with_velocity > 100.0 * (1.0 - same), "with velocities, a move and its reverse still look alike: Sim {with_velocity} (positions only {same})");
}

#[test]
fn signature_reference_is_the_builtin_moves_mean_pose() {
    let lib = SegmentLibrary::builtin();
    let mut sum = [[0.0f64; 3]; CANON_COUNT];
    let mut frames = 0usize;
    // The moves in 4 (the reference was fixed before the moves in 3 came; see the constant).
    for lc in lib.clips().iter().filter(|c| c.builtin.is_some_and(|m| m.counts() == 4)) {
        let positions = canonical_world_positions(&lc.clip);
        let mut normed = positions.clone();
        normalize_in_place(&mut normed, Origin::Hips, body_height(&positions));
        for frame in normed.chunks_exact(CANON_COUNT) {
            for (acc, p) in sum.iter_mut().zip(frame) {
                acc[0] += p.x as f64;
                acc[1] += p.y as f64;
                acc[2] += p.z as f64;
            }
            frames += 1;
        }
    }
    // Printed whole (the table to paste if the built-in moves change), then checked.
    let mut wrong = Vec::new();
    for (j, (acc, r)) in sum.iter().zip(&SIGNATURE_REFERENCE).enumerate() {
        let mean = acc.map(|a| a / frames as f64);
        println!("    [{:.3}, {:.3}, {:.3}], // {:?}", mean[0], mean[1], mean[2], Canon::ALL[j]);
        for a in 0..3 {
            if (mean[a] - r[a] as f64).abs() >= 0.01 {
                wrong.push(format!("{:?} axis {a}: mean {:.4}, constant {}", Canon::ALL[j], mean[a], r[a]));
            }
        }
    }
    assert!(wrong.is_empty(), "SIGNATURE_REFERENCE is not the built-in moves' mean pose: {wrong:?}");
}
