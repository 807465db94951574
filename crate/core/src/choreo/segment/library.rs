//! The library every choreography chooses from: built-in moves (one segment each, loadable in
//! slices) and imported clips cut at their counts into windows of each metre, with their
//! overlaps (following a segment by one that shares its frames repeats the motion), re-cut at
//! a stated tempo, and intensities scaled within each metre.

use std::sync::{Arc, Mutex};

use super::super::eigen::Signature;
use super::super::quality::{foot_skate_samples, kinetic_beats_secs, summarize_skate, QualityMotion, QUALITY_FPS};
use super::super::table::TransitionTable;
use super::signature::signature_of;
use super::tempo::{beat_fit, cut_beats, kinetic_per_count_by_rate};
use super::types::{canonical_world_positions, intensity_weight, join_ends, ClipSummary, JoinEnds, LibraryClip, Recut, Segment};
use super::{SegmentError, SegmentOptions, LIBRARY_FPS, SEGMENT_COUNTS, SEGMENT_METRES};
use crate::clip::Clip;
use crate::canon::humanoid::{Canon, HumanoidMap, HumanoidStatus, CANON_COUNT};
use crate::library::{builtin_clips_lazily, builtin_moves, MoveInfo};
use crate::canon::normalize::{body_height, normalize_in_place, Origin};
use crate::canon::retarget::to_canonical;

/// The segments every choreography chooses from.
#[derive(Debug, Default)]
pub struct SegmentLibrary {
    pub(super) clips: Vec<LibraryClip>,
    pub(super) segments: Vec<Segment>,
    pub(super) signatures: Vec<Signature>,
    pub(crate) ends: Vec<JoinEnds>,
    /// Clip-frame overlaps: for each segment, the segments sharing frames of its clip
    /// (itself included). Following one with an overlapping one repeats the same motion.
    pub(crate) overlaps: Vec<Vec<usize>>,
    pub(super) table: Mutex<Option<Arc<TransitionTable>>>,
    /// Bumped by every change of the segments, so a table built elsewhere can be checked.
    pub(super) revision: u64,
}

/// The built-in moves still to add to a library (see [`SegmentLibrary::load_builtin`]).
pub struct BuiltinLoader {
    clips: Box<dyn Iterator<Item = (Clip, MoveInfo)>>,
    done: usize,
    total: usize,
}

impl BuiltinLoader {
    pub fn new() -> Self {
        BuiltinLoader { clips: Box::new(builtin_clips_lazily()), done: 0, total: builtin_moves().len() }
    }
}

impl Default for BuiltinLoader {
    fn default() -> Self {
        Self::new()
    }
}

impl std::fmt::Debug for BuiltinLoader {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "BuiltinLoader({}/{})", self.done, self.total)
    }
}

impl SegmentLibrary {
    /// An empty library.
    pub fn new() -> Self {
        Self::default()
    }

    /// The built-in library: one segment per built-in move (in 4, and in 3).
    pub fn builtin() -> Self {
        let mut lib = Self::new();
        lib.add_builtin();
        lib
    }

    /// Adds every built-in move (one segment of its own counts each).
    pub fn add_builtin(&mut self) -> usize {
        let before = self.segments.len();
        let mut loader = BuiltinLoader::new();
        while self.load_builtin(&mut loader, usize::MAX) < 1.0 {}
        self.segments.len() - before
    }

    /// Adds up to `count` more built-in moves from `loader`; returns the fraction of them
    /// added so far (1 when all are in: the intensities are then rescaled, as
    /// [`SegmentLibrary::add_builtin`] does). Same library as `add_builtin`, built in slices.
    pub fn load_builtin(&mut self, loader: &mut BuiltinLoader, count: usize) -> f32 {
        if loader.done >= loader.total {
            return 1.0;
        }
        for _ in 0..count.max(1) {
            let Some((clip, info)) = loader.clips.next() else { break };
            let frames = clip.frame_count();
            let last = frames.saturating_sub(1) as f32;
            // One bar of the move's own counts (4, or 3 for a move in 3).
            let n = info.counts();
            let beats: Vec<f32> = (0..=n).map(|k| last * k as f32 / n as f32).collect();
            let lc = LibraryClip::new(clip, beats, crate::library::BUILTIN_BPM, Some(info));
            self.push_clip(lc, n, false);
            loader.done += 1;
        }
        if loader.done >= loader.total {
            self.rescale();
            return 1.0;
        }
        loader.done as f32 / loader.total as f32
    }

    /// Adds an imported clip: refused when its skeleton is not humanoid or it holds fewer than
    /// 4 counts.
    pub fn add_clip(&mut self, clip: &Clip, map: &HumanoidMap, status: &HumanoidStatus, options: &SegmentOptions) -> Result<ClipSummary, SegmentError> {
        let name = clip.name.clone();
        if let HumanoidStatus::NotHumanoid { reason } = status {
            return Err(SegmentError::NotHumanoid { name, reason: reason.clone() });
        }
        clip.validate().map_err(|e| SegmentError::Invalid { name: name.clone(), message: e.to_string() })?;
        if let Some(t) = options.tempo_bpm {
            if !(super::super::MIN_MOVE_BPM..=super::super::MAX_MOVE_BPM).contains(&t) {
                return Err(SegmentError::BadTempo { name, tempo_bpm: t });
            }
        }
        let canon = to_canonical(clip, map, LIBRARY_FPS);
        let (beats, tempo_bpm, detected) = cut_beats(&canon, options);
        if beats.len() < SEGMENT_COUNTS + 1 {
            return Err(SegmentError::TooShort { name, duration_secs: clip.duration_secs(), beats: beats.len(), tempo_bpm });
        }
        let hop = options.hop_counts.clamp(1, SEGMENT_COUNTS);
        let beat_count = beats.len();
        let lc = LibraryClip::new(canon, beats, tempo_bpm, None);
        let index = self.clips.len();
        let added = self.push_clip(lc, hop, options.steps_in_three);
        self.rescale();
        Ok(ClipSummary { clip: index, name, tempo_bpm, tempo_detected: detected, beats: beat_count, segments: added })
    }

    fn push_clip(&mut self, lc: LibraryClip, hop: usize, stepped: bool) -> usize {
        let clip_index = self.clips.len();
        self.clips.push(lc);
        let added = self.cut_segments(clip_index, hop, stepped);
        self.changed();
        added
    }

    /// Appends the segments of clip `clip_index` at its beats (every `hop` counts), and sets
    /// the overlaps among all its segments; its segments in 3 on its steps when `stepped` and it
    /// steps twice a count ([`steps_in_three`]).
    fn cut_segments(&mut self, clip_index: usize, hop: usize, stepped: bool) -> usize {
        let Some(lc) = self.clips.get(clip_index) else { return 0 };
        // Library clips are on the canonical skeleton: world positions are the canonical ones.
        let positions = canonical_world_positions(&lc.clip);
        let frames = positions.len() / CANON_COUNT;
        let mut normed = positions.clone();
        let h = body_height(&positions);
        normalize_in_place(&mut normed, Origin::Hips, h);
        // W per frame (eq. 2), metres per second.
        let mut w = vec![0.0f32; frames];
        for f in 0..frames {
            let (a, b) = if f + 1 < frames { (f, f + 1) } else { (f.saturating_sub(1), f) };
            if a == b {
                continue;
            }
            w[f] = Canon::ALL
                .iter()
                .map(|&c| intensity_weight(c) * (positions[b * CANON_COUNT + c.index()] - positions[a * CANON_COUNT + c.index()]).length() * LIBRARY_FPS)
                .sum();
        }
        // Kinetic beats (spec §J) of the whole clip, for each segment's beat fit, and its foot
        // skate samples (the floor is the whole clip's, as §J measures a source clip), for each
        // segment's own skate.
        let (kinetic, skate): (Vec<f32>, Vec<[Option<f32>; 4]>) = match QualityMotion::from_positions(&positions, lc.clip.fps) {
            Ok(m) => (kinetic_beats_secs(&m).into_iter().map(|t| t * lc.clip.fps).collect(), foot_skate_samples(&m)),
            Err(_) => (Vec::new(), Vec::new()),
        };
        let clip_skate_cm_per_s = summarize_skate(&skate, 0..skate.len()).mean_cm_per_s;
        let quality_frame = |f: usize| ((f as f32 / lc.clip.fps) * QUALITY_FPS).round() as usize;
        let first_new = self.segments.len();
        let beats = &lc.beat_frames;
        // Built-in moves: their one bar only, of their own counts (module docs); imported clips:
        // bars of each metre at the same counts.
        let own = lc.builtin.map(|info| [info.counts()]);
        let metres: &[usize] = match &own {
            Some(n) => n,
            None => &SEGMENT_METRES,
        };
        // A clip that steps twice a count is cut in 3 on its steps (see [`steps_in_three`]).
        let stepped = if stepped && lc.builtin.is_none() { steps_in_three(beats, &kinetic) } else { None };
        for &n in metres {
        // 3-count windows on every count (module docs).
        let hop = if n == SEGMENT_COUNTS { hop.clamp(1, n) } else { 1 };
        let (beats, unit) = match &stepped {
            Some(steps) if n == 3 => (steps, "steps"),
            _ => (beats, "counts"),
        };
        let mut k = 0;
        while k + n < beats.len() {
            let (s, e) = (beats[k], beats[k + n]);
            let (si, ei) = (s.round().max(0.0) as usize, (e.round() as usize).min(frames.saturating_sub(1)));
            if ei > si + 2 {
                let index = self.segments.len();
                let intensity = w[si..ei].iter().sum::<f32>() / (ei - si) as f32;
                self.signatures.push(signature_of(&normed, si, ei));
                self.ends.push(join_ends(&normed, &positions, h, si, ei));
                let name = match &lc.builtin {
                    Some(info) => info.name(),
                    None if n == SEGMENT_COUNTS => format!("{} · counts {}–{}", lc.clip.name, k + 1, k + n),
                    None => format!("{} · {unit} {}–{} (in {n})", lc.clip.name, k + 1, k + n),
                };
                let mut count_frames: Vec<f32> = beats[k..=k + n].to_vec();
                count_frames[0] = si as f32;
                count_frames[n] = ei as f32;
                if count_frames.windows(2).any(|w| !(w[1] > w[0])) {
                    count_frames = (0..=n).map(|j| si as f32 + (ei - si) as f32 * j as f32 / n as f32).collect();
                }
                let beat_fit = beat_fit(&count_frames, &kinetic);
                let (c0, c4) = (count_frames[0], count_frames[n]);
                let kinetic_per_count = kinetic.iter().filter(|&&f| f >= c0 && f < c4).count() as f32 / n as f32;
                let kinetic_per_count_by_rate = kinetic_per_count_by_rate(&positions, &count_frames);
                // Samples of frames after the first: a sample is the speed from the frame before.
                let skate_end = (quality_frame(ei) + 1).min(skate.len());
                let skate_cm_per_s = summarize_skate(&skate, (quality_frame(si) + 1).min(skate_end)..skate_end).mean_cm_per_s;
                self.segments.push(Segment {
                    index,
                    name,
                    count_frames,
                    beat_fit,
                    skate_cm_per_s,
                    clip_skate_cm_per_s,
                    kinetic_per_count,
                    kinetic_per_count_by_rate,
                    clip: clip_index,
                    source: lc.clip.source.clone(),
                    start_frame: si as f32,
                    end_frame: ei as f32,
                    tempo_bpm: n as f32 * 60.0 / ((ei - si) as f32 / LIBRARY_FPS),
                    intensity,
                    intensity01: 0.0,
                    builtin: lc.builtin,
                    retired: false,
                });
                self.overlaps.push(Vec::new());
            }
            k += hop;
        }
        }
        self.set_overlaps(clip_index);
        self.segments.len() - first_new
    }

    /// Overlaps among all the segments of clip `clip` (the new ones and any of its earlier
    /// cut kept by a re-cut).
    fn set_overlaps(&mut self, clip: usize) {
        let of_clip: Vec<usize> = (0..self.segments.len()).filter(|&i| self.segments[i].clip == clip).collect();
        for &i in &of_clip {
            let (a0, a1) = (self.segments[i].start_frame, self.segments[i].end_frame);
            let ov = of_clip
                .iter()
                .copied()
                .filter(|&j| {
                    let (b0, b1) = (self.segments[j].start_frame, self.segments[j].end_frame);
                    b0 < a1 && a0 < b1
                })
                .collect();
            self.overlaps[i] = ov;
        }
    }

    /// Re-cuts clip `clip` with new options (a tempo the person states, or `None` to detect it
    /// again): its earlier segments are removed, except those `keep` asks for (segments a
    /// choreography still uses), which stay as retired (never offered nor chosen again; see
    /// [`Segment::retired`]), and the new ones are appended. Segment indices change: `remap`
    /// of the result maps every old index to its new one. On error nothing changes.
    pub fn recut_clip(&mut self, clip: usize, options: &SegmentOptions, keep: &dyn Fn(usize) -> bool) -> Result<Recut, SegmentError> {
        let lc = self.clips.get(clip).ok_or(SegmentError::NoSuchClip { clip, clips: self.clips.len() })?;
        let name = lc.clip.name.clone();
        if lc.builtin.is_some() {
            return Err(SegmentError::BuiltinClip { name });
        }
        if let Some(t) = options.tempo_bpm {
            if !(super::super::MIN_MOVE_BPM..=super::super::MAX_MOVE_BPM).contains(&t) {
                return Err(SegmentError::BadTempo { name, tempo_bpm: t });
            }
        }
        let (beats, tempo_bpm, detected) = cut_beats(&lc.clip, options);
        if beats.len() < SEGMENT_COUNTS + 1 {
            return Err(SegmentError::TooShort { name, duration_secs: lc.clip.duration_secs(), beats: beats.len(), tempo_bpm });
        }
        let old_tempo = lc.tempo_bpm;
        let (remap, kept, removed) = self.drop_segments(&|i, s| s.clip != clip || keep(i));
        for &k in &kept {
            let s = &mut self.segments[k];
            if s.clip == clip && !s.retired {
                s.retired = true;
                s.name = format!("{} (earlier cut, {:.0} counts/min)", s.name, old_tempo);
            }
        }
        let kept: Vec<usize> = kept.into_iter().filter(|&k| self.segments[k].clip == clip).collect();
        let beat_count = beats.len();
        self.clips[clip].beat_frames = beats;
        self.clips[clip].tempo_bpm = tempo_bpm;
        let added = self.cut_segments(clip, options.hop_counts.clamp(1, SEGMENT_COUNTS), options.steps_in_three);
        self.rescale();
        self.changed();
        let summary = ClipSummary { clip, name, tempo_bpm, tempo_detected: detected, beats: beat_count, segments: added };
        Ok(Recut { summary, remap, kept, removed })
    }

    /// Keeps the segments `retain` accepts (by old index), compacting every per-segment list.
    /// Returns the old → new index map, the kept indices (new) and how many went.
    fn drop_segments(&mut self, retain: &dyn Fn(usize, &Segment) -> bool) -> (Vec<Option<usize>>, Vec<usize>, usize) {
        let mut remap = Vec::with_capacity(self.segments.len());
        let mut next = 0;
        for (i, s) in self.segments.iter().enumerate() {
            if retain(i, s) {
                remap.push(Some(next));
                next += 1;
            } else {
                remap.push(None);
            }
        }
        let removed = self.segments.len() - next;
        let mask: Vec<bool> = remap.iter().map(Option::is_some).collect();
        retain_by_mask(&mut self.segments, &mask);
        retain_by_mask(&mut self.signatures, &mask);
        retain_by_mask(&mut self.ends, &mask);
        retain_by_mask(&mut self.overlaps, &mask);
        for (i, s) in self.segments.iter_mut().enumerate() {
            s.index = i;
        }
        for ov in self.overlaps.iter_mut() {
            *ov = ov.iter().filter_map(|&j| remap.get(j).copied().flatten()).collect();
        }
        (remap, (0..next).collect(), removed)
    }


    /// Rescales every segment's intensity to the range of the library's segments of its count
    /// (a bar in 3 chooses among 3-count moves only, so they are scaled among themselves; and
    /// the 4-count moves keep the scale they had before 3-count ones were cut). The built-in
    /// moves held on the counts are placed on that scale but do not set it: they are calmer
    /// versions of built-in steps, and with them in the range every other move's intensity rose
    /// by 0.013–0.018, which moved the person's dances (session 24's trace of `choreo_my_moves`).
    fn rescale(&mut self) {
        let metres: std::collections::BTreeSet<usize> = self.segments.iter().map(Segment::counts).collect();
        let sets_scale = |s: &Segment| !s.builtin.is_some_and(|m| m.step.on_counts());
        for n in metres {
            let mut v: Vec<f32> = self.segments.iter().filter(|s| s.counts() == n && sets_scale(s)).map(|s| s.intensity).collect();
            if v.is_empty() {
                v = self.segments.iter().filter(|s| s.counts() == n).map(|s| s.intensity).collect();
            }
            v.sort_by(f32::total_cmp);
            let lo = v[v.len() * 5 / 100];
            let hi = v[(v.len() * 95 / 100).min(v.len() - 1)];
            for s in self.segments.iter_mut().filter(|s| s.counts() == n) {
                s.intensity01 = if hi > lo + 1e-6 { ((s.intensity - lo) / (hi - lo)).clamp(0.0, 1.0) } else { 0.5 };
            }
        }
    }

    pub fn len(&self) -> usize {
        self.segments.len()
    }

    pub fn is_empty(&self) -> bool {
        self.segments.is_empty()
    }

    pub fn segments(&self) -> &[Segment] {
        &self.segments
    }

    pub fn segment(&self, index: usize) -> Option<&Segment> {
        self.segments.get(index)
    }

    pub fn clips(&self) -> &[LibraryClip] {
        &self.clips
    }

    pub fn signature(&self, index: usize) -> Option<&Signature> {
        self.signatures.get(index)
    }

    /// kWAS similarity of two segments (0 when either index is out of range).
    pub fn similarity(&self, a: usize, b: usize) -> f32 {
        match (self.signatures.get(a), self.signatures.get(b)) {
            (Some(x), Some(y)) => x.similarity(y),
            _ => 0.0,
        }
    }

    /// D = 1 − Sim.
    pub fn dissimilarity(&self, a: usize, b: usize) -> f32 {
        1.0 - self.similarity(a, b)
    }

}

/// Kinetic beats per count at and above which a clip steps twice a count: halfway between
/// one and two.
pub const STEPS_TWICE_A_COUNT: f32 = 1.5;

/// The counts a clip's segments in 3 are cut on when it steps twice a count (its kinetic
/// beats, §J, run at [`STEPS_TWICE_A_COUNT`] or more per count over the clip): its counts with
/// the half counts between them, each half count at the clip's kinetic beat nearest to it
/// within a quarter of a count (else the midpoint); `None` otherwise (cut on the counts).
///
/// Why: such a clip (slow phrases counted by the bar, steps between the counts: CMU subject
/// 5's trials 12 and 19 at 61 and 68 counts per minute, 1.66 and 1.72 kinetic beats a count)
/// played as a bar in 3 of a fast waltz is sped up 2.5 times; its turns on the counts and
/// between them merge and the ones left fall between the song's beats, while the filling,
/// seeing one turn a count at that rate, prefers it: with the CMU modern-dance clips as the
/// library, the 150 and 138 BPM demo waltzes danced off the beat (BAS-music 0.43 and 0.46
/// against 0.50 and 0.48 on the half-shifted beats). Cut on its steps, a window of 3 is three
/// steps, each on a count. Bars of 4 keep the clip's counts (its phrase is in 4: the comb's
/// bar).
pub fn steps_in_three(beats: &[f32], kinetic: &[f32]) -> Option<Vec<f32>> {
    let (first, last) = (*beats.first()?, *beats.last()?);
    let counts = beats.len().checked_sub(1).filter(|&c| c > 0)? as f32;
    let turns = kinetic.iter().filter(|&&f| f >= first && f < last).count() as f32;
    if turns / counts < STEPS_TWICE_A_COUNT {
        return None;
    }
    let mut out = Vec::with_capacity(2 * beats.len());
    for w in beats.windows(2) {
        out.push(w[0]);
        let (mid, reach) = (0.5 * (w[0] + w[1]), 0.25 * (w[1] - w[0]));
        let near = kinetic.iter().copied().filter(|&f| (f - mid).abs() <= reach).min_by(|a, b| (a - mid).abs().total_cmp(&(b - mid).abs()));
        out.push(near.unwrap_or(mid));
    }
    out.push(last);
    Some(out)
}

/// Keeps the items whose `mask` entry is true.
fn retain_by_mask<T>(v: &mut Vec<T>, mask: &[bool]) {
    let mut i = 0;
    v.retain(|_| {
        i += 1;
        mask.get(i - 1).copied().unwrap_or(false)
    });
}

