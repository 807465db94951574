//! Counts and tempo from the motion (spec §E revised): the count period the speed curves of
//! the feet, the whole body, the hands and the hips support together (an autocorrelation comb),
//! folded into a choreographer's count of 60..=150 per minute; each count snapped to the
//! nearest dip of the speed (its kinetic beat). Also what the filling reads of a segment's
//! beats: its beat fit and its kinetic beats per count at the rates bars play it.

use glam::Vec3;

use super::super::quality::{bas_music, kinetic_beats_secs, QualityMotion, QUALITY_FPS};
use super::types::canonical_world_positions;
use super::{SegmentOptions, LIBRARY_FPS};
use crate::clip::Clip;
use crate::canon::humanoid::{Canon, CANON_COUNT};

/// Overall joint speed per frame of a canonical clip (Σ over joints of world |ẋ|, m/s: a
/// planted step and the end of a gesture both dip), lightly smoothed.
pub fn joint_speed(clip: &Clip) -> Vec<f32> {
    let pos = canonical_world_positions(clip);
    let frames = pos.len() / CANON_COUNT;
    let mut s = vec![0.0f32; frames];
    for f in 1..frames {
        s[f] = (0..CANON_COUNT).map(|j| (pos[f * CANON_COUNT + j] - pos[(f - 1) * CANON_COUNT + j]).length()).sum::<f32>() * clip.fps;
    }
    if frames > 1 {
        s[0] = s[1];
    }
    // 3-tap smoothing.
    let mut out = s.clone();
    for f in 1..frames.saturating_sub(1) {
        out[f] = 0.25 * s[f - 1] + 0.5 * s[f] + 0.25 * s[f + 1];
    }
    out
}

/// Beat period (frames) and beats (frames) from the joint-speed curve alone (the fallback of
/// [`detect_counts`] when no body part shows a period).
pub fn detect_beats(speed: &[f32]) -> (Vec<f32>, f32) {
    let period = speed_period(speed);
    (beats_at_period(speed, period), period)
}

/// Count period (frames) of the joint-speed curve: its strongest autocorrelation peak after the
/// lobe around lag 0, folded into a choreographer's count; 15 frames (120 per minute) when
/// there is none.
fn speed_period(speed: &[f32]) -> f32 {
    let n = speed.len();
    let fps = LIBRARY_FPS;
    let (min_lag, max_lag) = ((fps * 60.0 / 200.0).floor() as usize, ((fps * 60.0 / 30.0).ceil() as usize).min(n / 2));
    if max_lag < min_lag + 2 {
        return fps * 0.5;
    }
    // Remove the slow trend (a 4-second moving mean).
    let win = (4.0 * fps) as usize;
    let mut prefix = vec![0.0f64; n + 1];
    for i in 0..n {
        prefix[i + 1] = prefix[i] + speed[i] as f64;
    }
    let x: Vec<f32> = (0..n)
        .map(|i| {
            let a = i.saturating_sub(win / 2);
            let b = (i + win / 2 + 1).min(n);
            speed[i] - ((prefix[b] - prefix[a]) / (b - a) as f64) as f32
        })
        .collect();
    let energy: f32 = x.iter().map(|v| v * v).sum::<f32>().max(1e-12);
    let ac = |lag: usize| -> f32 {
        if lag >= n {
            return 0.0;
        }
        let s: f32 = (0..n - lag).map(|i| x[i] * x[i + lag]).sum();
        s / energy * n as f32 / (n - lag) as f32
    };
    let acs: Vec<f32> = (0..=max_lag + 1).map(ac).collect();
    // Skip the lobe around lag 0: start after the first local minimum.
    let mut start = 1;
    while start < max_lag && acs[start + 1] < acs[start] {
        start += 1;
    }
    // The shortest period whose peak is nearly as strong as the strongest (longer peaks are
    // its multiples).
    let peaks: Vec<usize> = (start.max(min_lag).max(1)..=max_lag).filter(|&l| acs[l] > 0.0 && acs[l] >= acs[l - 1] && acs[l] >= acs[l + 1]).collect();
    let strongest = peaks.iter().map(|&l| acs[l]).fold(0.0f32, f32::max);
    let mut best = (peaks.iter().copied().find(|&l| acs[l] >= 0.8 * strongest).unwrap_or(0), strongest);
    if best.0 == 0 {
        // No periodicity: a regular grid at 120 counts per minute.
        best.0 = (fps * 0.5) as usize;
    }
    let mut lag = best.0;
    // Fold into a choreographer's count (60..=150 per minute): fast footwork counts in twos,
    // a slow sway in halves.
    while fps * 60.0 / lag as f32 > 150.0 && 2 * lag <= max_lag {
        lag *= 2;
    }
    while fps * 60.0 / (lag as f32) < 60.0 && lag >= 2 * min_lag {
        lag /= 2;
    }
    let lag = lag.clamp(1, max_lag);
    // Parabolic refinement.
    let (y0, y1, y2) = (acs[lag - 1], acs[lag], acs[lag + 1]);
    let den = y0 - 2.0 * y1 + y2;
    lag as f32 + if den.abs() > 1e-9 { (0.5 * (y0 - y2) / den).clamp(-0.5, 0.5) } else { 0.0 }
}

/// Counts (frames) on a grid of `period` frames: the phase where the joint speed is lowest,
/// then each count snapped to the nearest local minimum of the speed (its kinetic beat) within
/// a quarter period, so every count keeps its instant in the motion.
fn beats_at_period(speed: &[f32], period: f32) -> Vec<f32> {
    let n = speed.len();
    let phase = best_phase(speed, period);
    let grid_beats = grid(n, period, phase);
    let reach = (period / 4.0).max(1.0) as isize;
    let mut beats: Vec<f32> = Vec::with_capacity(grid_beats.len());
    for g in grid_beats {
        let c = g.round() as isize;
        let mut best_f = c;
        let mut best_v = f32::MAX;
        for f in (c - reach).max(1)..=(c + reach).min(n as isize - 2) {
            let fu = f as usize;
            let v = speed[fu];
            if v <= speed[fu - 1] && v <= speed[fu + 1] && v < best_v {
                best_v = v;
                best_f = f;
            }
        }
        let b = best_f.clamp(0, n as isize - 1) as f32;
        if beats.last().is_none_or(|&last| b > last + period * 0.5) {
            beats.push(b);
        }
    }
    beats
}

/// The body parts whose speed curves vote on a clip's count period (spec §E revised): the
/// feet (the steps: planted on a count, moving between), the whole body (whose dips are the
/// kinetic beats of §J), the hands (a partner dance is led through them) and the hips (the
/// weight moving from foot to foot).
const TEMPO_PARTS: [&[Canon]; 4] = [
    &[Canon::LeftFoot, Canon::LeftToe, Canon::RightFoot, Canon::RightToe],
    &Canon::ALL,
    &[Canon::LeftHand, Canon::RightHand],
    &[Canon::Hips],
];
/// Multiples of the count period whose autocorrelation supports it: the count, two counts and
/// the bar of four. A dance is periodic at its bar even where the steps inside it are uneven
/// (salsa steps on three counts of four), so a period is believed only when its multiples
/// agree.
const COMB_MULTIPLES: [f32; 3] = [1.0, 2.0, 4.0];
/// Periods searched, counts per minute: every octave and 3:2 alternative of a choreographer's
/// count (60..=150) is in range, scored by the same comb, so the best one wins on evidence.
const TEMPO_SEARCH_BPM: (f32, f32) = (30.0, 200.0);
/// Step of the period search, frames (a quarter frame: 0.4 % at 80 counts per minute, well
/// inside the 3 % partners must agree to).
const TEMPO_SEARCH_STEP_FRAMES: f32 = 0.25;
/// Moving-mean window removed from each speed curve before its autocorrelation, seconds: the
/// slow swell of a phrase, not the counts.
const TEMPO_DETREND_SECS: f32 = 2.0;

/// Speed curve of a set of canonical joints (Σ |ẋ|, frame-major `positions`).
fn part_speed(positions: &[Vec3], joints: &[Canon], fps: f32) -> Vec<f32> {
    let frames = positions.len() / CANON_COUNT;
    let mut v = vec![0.0f32; frames];
    for f in 1..frames {
        v[f] = joints.iter().map(|c| (positions[f * CANON_COUNT + c.index()] - positions[(f - 1) * CANON_COUNT + c.index()]).length()).sum::<f32>() * fps;
    }
    if frames > 1 {
        v[0] = v[1];
    }
    v
}

/// Autocorrelation of `signal` for lags `0..=max_lag` after removing its
/// [`TEMPO_DETREND_SECS`] moving mean, normalised by the energy and unbiased (1 at lag 0).
fn detrended_autocorrelation(signal: &[f32], max_lag: usize, fps: f32) -> Vec<f32> {
    let n = signal.len();
    let half = ((TEMPO_DETREND_SECS * fps) as usize / 2).max(1);
    let mut prefix = vec![0.0f64; n + 1];
    for i in 0..n {
        prefix[i + 1] = prefix[i] + signal[i] as f64;
    }
    let x: Vec<f32> = (0..n)
        .map(|i| {
            let (a, b) = (i.saturating_sub(half), (i + half + 1).min(n));
            signal[i] - ((prefix[b] - prefix[a]) / (b - a) as f64) as f32
        })
        .collect();
    let energy: f32 = x.iter().map(|v| v * v).sum::<f32>().max(1e-12);
    (0..=max_lag.min(n.saturating_sub(1)))
        .map(|lag| (0..n - lag).map(|i| x[i] * x[i + lag]).sum::<f32>() / energy * n as f32 / (n - lag) as f32)
        .collect()
}

/// Mean autocorrelation at the [`COMB_MULTIPLES`] of `period` (linear between lags); `None`
/// when fewer than two of them fit in `ac`.
fn comb_support(ac: &[f32], period: f32) -> Option<f32> {
    let mut sum = 0.0;
    let mut count = 0;
    for m in COMB_MULTIPLES {
        let lag = m * period;
        let i = lag.floor() as usize;
        if i + 1 >= ac.len() {
            continue;
        }
        let t = lag - i as f32;
        sum += ac[i] * (1.0 - t) + ac[i + 1] * t;
        count += 1;
    }
    (count >= 2).then(|| sum / count as f32)
}

/// A clip's count period (frames at [`LIBRARY_FPS`], folded into 60..=150 counts per minute)
/// and its support: the period whose [`COMB_MULTIPLES`] the speed curves of the
/// [`TEMPO_PARTS`] support most, summed over the parts (each curve's autocorrelation is
/// normalised, so each part has one vote). `None` when no period has positive support (no
/// part moves periodically). Why not the whole-body speed alone (the rule before): on the CMU
/// salsa clips its autocorrelation shows no peak at all in three of the four partner takes
/// (the arms and turns drown the steps), while the feet show the bar of the basic step.
pub fn clip_count_period(canon: &Clip) -> Option<(f32, f32)> {
    let positions = canonical_world_positions(canon);
    let fps = LIBRARY_FPS;
    let curves: Vec<Vec<f32>> = TEMPO_PARTS.iter().map(|joints| part_speed(&positions, joints, fps)).collect();
    comb_period(&curves, fps)
}

/// The count period (frames, folded into 60..=150 per minute) and its support that the speed
/// `curves` (one per body part, at `fps`) support most together (see [`clip_count_period`]).
pub(super) fn comb_period(curves: &[Vec<f32>], fps: f32) -> Option<(f32, f32)> {
    let frames = curves.iter().map(Vec::len).min()?;
    let (lo, hi) = (fps * 60.0 / TEMPO_SEARCH_BPM.1, fps * 60.0 / TEMPO_SEARCH_BPM.0);
    let max_lag = ((COMB_MULTIPLES[COMB_MULTIPLES.len() - 1] * hi).ceil() as usize + 1).min(frames / 2);
    if max_lag < (2.0 * lo) as usize + 2 {
        return None;
    }
    let acs: Vec<Vec<f32>> = curves.iter().map(|c| detrended_autocorrelation(c, max_lag, fps)).collect();
    let mut best: Option<(f32, f32)> = None;
    let mut period = lo;
    while period <= hi {
        let support: Option<f32> = acs.iter().map(|ac| comb_support(ac, period)).sum();
        if let Some(s) = support {
            if best.is_none_or(|(_, b)| s > b) {
                best = Some((period, s));
            }
        }
        period += TEMPO_SEARCH_STEP_FRAMES;
    }
    let (mut period, support) = best.filter(|&(_, s)| s > 0.0)?;
    // A choreographer's count (60..=150 per minute): fast footwork counts in twos, a slow
    // sway in halves.
    while fps * 60.0 / period > 150.0 {
        period *= 2.0;
    }
    while fps * 60.0 / period < 60.0 {
        period /= 2.0;
    }
    Some((period, support))
}

/// Counts (frames) and count period (frames) of a canonical clip detected from its motion: the
/// period of [`clip_count_period`] (of the joint speed alone when no part is periodic), the
/// counts on it where the motion has them.
pub fn detect_counts(canon: &Clip) -> (Vec<f32>, f32) {
    counts_of(canon, &joint_speed(canon))
}

/// [`detect_counts`] with the clip's [`joint_speed`] already at hand.
fn counts_of(canon: &Clip, speed: &[f32]) -> (Vec<f32>, f32) {
    let period = clip_count_period(canon).map_or_else(|| speed_period(speed), |(p, _)| p);
    (beats_at_period(speed, period), period)
}

/// Nominal count length the beat fit is judged on, seconds (120 per minute).
const FIT_COUNT_SECS: f32 = 0.5;

/// Beat fit of a segment with counts `count_frames` (n + 1 of them) in a clip whose kinetic
/// beats are `kinetic_frames` (both clip frames): its kinetic beats warped onto a bar of n
/// counts of [`FIT_COUNT_SECS`] as the renderer warps them, then (BAS-music on the n − 1 inner
/// counts − BAS on the n half-counts + 1) / 2. 1: turns on every count and never between; 0.5:
/// no preference.
pub fn beat_fit(count_frames: &[f32], kinetic_frames: &[f32]) -> f32 {
    if count_frames.len() < 3 {
        return 0.5;
    }
    let n = count_frames.len() - 1;
    let (c0, c4) = (count_frames[0], count_frames[n]);
    let warp = |f: f32| -> f32 {
        let k = (0..n).rfind(|&k| f >= count_frames[k]).unwrap_or(0);
        let span = (count_frames[k + 1] - count_frames[k]).max(1e-6);
        (k as f32 + (f - count_frames[k]) / span) * FIT_COUNT_SECS
    };
    let mut kin: Vec<f32> = kinetic_frames.iter().copied().filter(|&f| f >= c0 && f <= c4).map(warp).collect();
    kin.sort_by(f32::total_cmp);
    let step = FIT_COUNT_SECS;
    let counts: Vec<f32> = (1..n).map(|k| k as f32 * step).collect();
    let halves: Vec<f32> = (0..n).map(|k| (k as f32 + 0.5) * step).collect();
    let on = bas_music(&counts, &kin).unwrap_or(0.0);
    let off = bas_music(&halves, &kin).unwrap_or(0.0);
    ((on - off + 1.0) * 0.5).clamp(0.0, 1.0)
}

/// Count rates, counts per minute, at which each segment's kinetic beats per count are measured
/// when the library is cut ([`Segment::kinetic_per_count_by_rate`]): the range the grid's bars
/// play segments at, log-spaced.
pub const KINETIC_RATES_BPM: [f32; 6] = [60.0, 75.0, 90.0, 110.0, 135.0, 165.0];

/// Kinetic beats per count (spec §J) of the segment with counts `count_frames` (frames of
/// `positions`, canonical world positions at [`LIBRARY_FPS`], frame-major) played at each rate
/// of [`KINETIC_RATES_BPM`]: resampled at [`QUALITY_FPS`] with its counts on the bar's beats
/// (piecewise-linear, as the renderer warps it) and half a count of the clip either side (so
/// its first count can be a turn, as in a dance), kinetic beats counted over its n counts
/// (`count_frames` holds n + 1).
pub fn kinetic_per_count_by_rate(positions: &[Vec3], count_frames: &[f32]) -> Vec<f32> {
    let frames = positions.len() / CANON_COUNT;
    if count_frames.len() < 2 || frames < 2 {
        return Vec::new();
    }
    let counts = count_frames.len() - 1;
    let c = count_frames;
    // Source frame at u counts from the segment's first count (u may run half a count out).
    let frame_at = |u: f32| -> f32 {
        let f = if u < 0.0 {
            c[0] + u * (c[1] - c[0])
        } else if u >= counts as f32 {
            c[counts] + (u - counts as f32) * (c[counts] - c[counts - 1])
        } else {
            let k = (u.floor() as usize).min(counts - 1);
            c[k] + (u - k as f32) * (c[k + 1] - c[k])
        };
        // Past the clip's ends, the clip mirrored in time (a one-bar built-in move has nothing
        // around it; the dance puts another move there whose speed is as likely to rise away
        // from the join as this one's).
        let last = (frames - 1) as f32;
        let f = if f < 0.0 { -f } else if f > last { 2.0 * last - f } else { f };
        f.clamp(0.0, last)
    };
    KINETIC_RATES_BPM
        .iter()
        .map(|&rate| {
            let count_secs = 60.0 / rate;
            let margin = 0.5 * count_secs;
            let n = ((counts as f32 * count_secs + 2.0 * margin) * QUALITY_FPS).round() as usize + 1;
            let mut out = Vec::with_capacity(n * CANON_COUNT);
            for i in 0..n {
                let t = i as f32 / QUALITY_FPS - margin;
                let f = frame_at(t / count_secs);
                let f0 = f.floor() as usize;
                let f1 = (f0 + 1).min(frames - 1);
                let a = f - f0 as f32;
                for j in 0..CANON_COUNT {
                    out.push(positions[f0 * CANON_COUNT + j].lerp(positions[f1 * CANON_COUNT + j], a));
                }
            }
            let Ok(m) = QualityMotion::from_positions(&out, QUALITY_FPS) else { return 0.0 };
            let span = counts as f32 * count_secs;
            let beats = kinetic_beats_secs(&m).into_iter().filter(|&t| t >= margin - 1e-4 && t < margin + span - 1e-4).count();
            beats as f32 / counts as f32
        })
        .collect()
}

/// A canonical clip's counts (frames at [`LIBRARY_FPS`]), tempo (counts per minute) and
/// whether it was detected (else stated in `options`).
pub(super) fn cut_beats(canon: &Clip, options: &SegmentOptions) -> (Vec<f32>, f32, bool) {
    let speed = joint_speed(canon);
    match options.tempo_bpm {
        Some(bpm) => {
            let period = LIBRARY_FPS * 60.0 / bpm;
            let phase = match options.first_beat_secs {
                Some(t) => (t * LIBRARY_FPS).rem_euclid(period),
                None => best_phase(&speed, period),
            };
            (grid(speed.len(), period, phase), bpm, false)
        }
        None => {
            let (beats, period) = counts_of(canon, &speed);
            (beats, LIBRARY_FPS * 60.0 / period.max(1e-3), true)
        }
    }
}

/// Phase (frames, in `0..period`) of a beat grid where the speed is lowest.
fn best_phase(speed: &[f32], period: f32) -> f32 {
    let steps = period.ceil().max(1.0) as usize;
    let mut best = (0.0, f32::MAX);
    for s in 0..steps {
        let phase = s as f32;
        let mut sum = 0.0;
        let mut count = 0;
        let mut t = phase;
        while (t as usize) < speed.len() {
            sum += speed[t.round() as usize % speed.len()];
            count += 1;
            t += period;
        }
        let mean = if count > 0 { sum / count as f32 } else { f32::MAX };
        if mean < best.1 {
            best = (phase, mean);
        }
    }
    best.0
}

fn grid(frames: usize, period: f32, phase: f32) -> Vec<f32> {
    let mut out = Vec::new();
    if !(period > 0.5) {
        return out;
    }
    let mut t = phase;
    while t <= (frames.saturating_sub(1)) as f32 {
        out.push(t);
        t += period;
    }
    out
}