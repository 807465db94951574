//! Song sections (intro, verse, chorus, …) from the analysis: the one structure both the dance
//! fill (repeated sections may take the same moves, issue 26) and the video camera (cuts at
//! phrase starts and section changes, issue 29) use.
//!
//! Method (Foote 2000, on bars rather than frames): each bar of the [`SongGrid`] gets a feature
//! vector from the song's banded RMS envelope — per band the bar's mean level and its spread
//! (dB), and its per-beat loudness pattern (each beat's level against the bar's) — each feature
//! z-scored over the song with a floor on its spread, so a steady signal stays one section. A
//! bar-level self-similarity (`exp(−d²)` of the weighted feature distance, [`BarSimilarity`]) is scanned
//! with Foote's checkerboard kernel: the novelty at a bar line is how much more alike the bars
//! on each side are among themselves than across it. Boundaries are novelty peaks on bar lines,
//! favoured (not forced) at phrase starts (multiples of 4 bars from the first downbeat), at
//! least [`SectionOptions::min_section_bars`] apart. Each section is then compared with the
//! earlier ones bar against bar (the repetition stripe of the matrix); one alike enough takes
//! its label. Deterministic, O(bars · kernel² · features) for the novelty and O(sections² · bars) for the labels, memory
//! linear in the bars: about a millisecond for a 3-minute song natively.

use crate::fmath;
use serde::{Deserialize, Serialize};
use thiserror::Error;

use super::{MusicError, RmsEnvelope, SongGrid};

/// Levels below this RMS count as this RMS (−100 dBFS), so silence has a finite level.
const FLOOR_RMS: f32 = 1e-5;
/// The smallest spread a feature is scaled by, dB: differences smaller than this across the
/// whole song are noise, not structure.
const MIN_FEATURE_SPREAD_DB: f32 = 1.0;

/// What can go wrong finding sections, with the offending values.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum SectionError {
    #[error("the grid has no bars: there is nothing to divide into sections")]
    NoBars,
    #[error("bar {index} spans {start_secs} s to {end_secs} s: not a finite, increasing span")]
    BadBar { index: usize, start_secs: f32, end_secs: f32 },
    #[error("section option {what} = {value} is invalid")]
    BadOption { what: &'static str, value: f32 },
    #[error("the envelope is not usable: {0}")]
    Envelope(#[from] MusicError),
}

/// Settings of [`sections`]. The defaults suit popular music (4- and 8-bar phrases).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "camelCase", default)]
pub struct SectionOptions {
    /// Bars on each side of a bar line the checkerboard kernel compares (at least 1).
    pub kernel_bars: usize,
    /// Bars per phrase: bar lines at multiples of it from the first downbeat are favoured
    /// (at least 1; 1 favours none).
    pub phrase_bars: usize,
    /// How much a phrase start's novelty is raised when boundaries are chosen (0.25 = by a
    /// quarter; half that at a half phrase).
    pub phrase_bonus: f32,
    /// The shortest section, bars (at least 1).
    pub min_section_bars: usize,
    /// The least novelty (0..=1) a boundary needs.
    pub min_novelty: f32,
    /// The least novelty a boundary needs as a fraction of the song's highest (0..=1).
    pub relative_novelty: f32,
    /// The least similarity (0..=1, the mean of the bar-against-bar similarities) at which a
    /// section repeats an earlier one.
    pub repeat_similarity: f32,
}

impl Default for SectionOptions {
    fn default() -> Self {
        Self {
            kernel_bars: 4,
            phrase_bars: 4,
            phrase_bonus: 0.25,
            min_section_bars: 2,
            min_novelty: 0.1,
            relative_novelty: 0.3,
            repeat_similarity: 0.6,
        }
    }
}

impl SectionOptions {
    fn validate(&self) -> Result<(), SectionError> {
        let bad = |what, value: f32| Err(SectionError::BadOption { what, value });
        if self.kernel_bars == 0 || self.kernel_bars > 64 {
            return bad("kernelBars", self.kernel_bars as f32);
        }
        if self.phrase_bars == 0 || self.phrase_bars > 64 {
            return bad("phraseBars", self.phrase_bars as f32);
        }
        if self.min_section_bars == 0 || self.min_section_bars > 64 {
            return bad("minSectionBars", self.min_section_bars as f32);
        }
        if !(self.phrase_bonus.is_finite() && (0.0..=4.0).contains(&self.phrase_bonus)) {
            return bad("phraseBonus", self.phrase_bonus);
        }
        for (what, value) in [
            ("minNovelty", self.min_novelty),
            ("relativeNovelty", self.relative_novelty),
            ("repeatSimilarity", self.repeat_similarity),
        ] {
            if !(value.is_finite() && (0.0..=1.0).contains(&value)) {
                return bad(what, value);
            }
        }
        Ok(())
    }
}

/// One section: a run of whole bars.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "camelCase")]
pub struct Section {
    /// Index of its first bar in the grid.
    pub first_bar: usize,
    /// Its length, bars (at least 1).
    pub bars: usize,
    /// Its label: sections with the same label repeat one another (0 = "A", 1 = "B", …; see
    /// [`Section::letter`]). Labels are numbered in order of first appearance.
    pub label: u8,
    /// Mean intensity of its bars (0..=1, as [`crate::bars::Bar::intensity`]).
    pub intensity: f32,
    /// The earlier section it repeats (index in [`Sections::sections`]), if any.
    pub repeat_of: Option<usize>,
    /// Its similarity (0..=1) to the most alike earlier section (the one it repeats, when it
    /// repeats one); 0 for the first section.
    pub similarity: f32,
}

impl Section {
    /// The label as a letter: A–Z, then again from A.
    pub fn letter(&self) -> char {
        char::from(b'A' + self.label % 26)
    }

    /// One past its last bar.
    pub fn end_bar(&self) -> usize {
        self.first_bar + self.bars
    }
}

/// The song's sections, covering every bar of the grid in order.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "camelCase")]
pub struct Sections {
    pub sections: Vec<Section>,
    /// Novelty (0..=1) at the start of each bar (`novelty[i]` is the change between bar `i − 1`
    /// and bar `i`; 0 where the kernel cannot see both sides): how strongly the music changes
    /// there, for cuts that follow lesser changes too.
    pub novelty: Vec<f32>,
}

impl Sections {
    /// The bars at which a section starts after the first (section boundaries), increasing.
    pub fn boundaries(&self) -> Vec<usize> {
        self.sections.iter().skip(1).map(|s| s.first_bar).collect()
    }

    /// The labels as letters, one per section ("ABCB…").
    pub fn letters(&self) -> String {
        self.sections.iter().map(Section::letter).collect()
    }

    /// Per bar of the song (`bars` of them), the earlier bar it repeats: a bar of a section that
    /// repeats an earlier one ([`Section::repeat_of`]) repeats the bar at the same place in that
    /// section's first occurrence (followed back to it: a third chorus repeats the first), when
    /// that section is that long. What the dance fill reads (issue 26: a repeated section may
    /// take the same moves, `choreo::generate::generate_with_repeats`). `None` elsewhere.
    pub fn repeat_of_bars(&self, bars: usize) -> Vec<Option<usize>> {
        let mut out = vec![None; bars];
        for (k, sec) in self.sections.iter().enumerate() {
            // The first occurrence of its label (a third chorus repeats the first).
            if sec.repeat_of.is_none() {
                continue;
            }
            let Some(src) = self.sections[..k].iter().find(|s| s.label == sec.label) else { continue };
            for i in 0..sec.bars.min(src.bars) {
                if let Some(slot) = out.get_mut(sec.first_bar + i) {
                    *slot = Some(src.first_bar + i);
                }
            }
        }
        out
    }
}

/// Feature vectors of the grid's bars: per band its mean level and spread (dB), then per band
/// each beat's level against the bar's (dB), `beats_per_bar` values a band.
pub fn bar_features(grid: &SongGrid, envelope: &RmsEnvelope) -> Result<Vec<Vec<f32>>, SectionError> {
    envelope.validate()?;
    if grid.bars.is_empty() {
        return Err(SectionError::NoBars);
    }
    let hop = envelope.hop_secs;
    let frames = envelope.frame_count();
    let beats = (grid.beats_per_bar as usize).clamp(1, super::grid::MAX_BEATS_PER_BAR as usize);
    // Mean dB and spread of a band over a time span (the nearest frame when it holds none).
    let span = |band: &[f32], start_secs: f32, end_secs: f32| -> (f32, f32) {
        let last = frames.saturating_sub(1);
        let lo = ((start_secs / hop).ceil().max(0.0) as usize).min(last);
        let hi = ((end_secs / hop).ceil().max(0.0) as usize).min(frames).max(lo + 1);
        let db: Vec<f32> = band[lo..hi].iter().map(|&v| 20.0 * fmath::log10(v.max(FLOOR_RMS))).collect();
        let mean = db.iter().sum::<f32>() / db.len() as f32;
        let var = db.iter().map(|d| (d - mean) * (d - mean)).sum::<f32>() / db.len() as f32;
        (mean, var.sqrt())
    };
    let mut out = Vec::with_capacity(grid.bars.len());
    for bar in &grid.bars {
        if !(bar.start_secs.is_finite() && bar.end_secs.is_finite() && bar.end_secs > bar.start_secs) {
            return Err(SectionError::BadBar { index: bar.index, start_secs: bar.start_secs, end_secs: bar.end_secs });
        }
        let mut levels = Vec::new();
        let mut spreads = Vec::new();
        let mut pattern = Vec::new();
        let beat_secs = bar.duration_secs() / beats as f32;
        for band in &envelope.bands {
            let (mean, spread) = span(band, bar.start_secs, bar.end_secs);
            levels.push(mean);
            spreads.push(spread);
            for b in 0..beats {
                let t = bar.start_secs + b as f32 * beat_secs;
                pattern.push(span(band, t, t + beat_secs).0 - mean);
            }
        }
        levels.extend(spreads);
        levels.extend(pattern);
        out.push(levels);
    }
    Ok(out)
}

/// Bar-against-bar similarity of [`bar_features`], computed on demand (no `bars × bars` matrix
/// is stored, so memory stays linear in the song's length): each feature z-scored over the
/// song (spread at least 1 dB), the squared distance averaged within the three groups (levels,
/// spreads, beat patterns; weights 1, ½, ½), similarity `exp(−d²)` in 0..=1, 1 for a bar with
/// itself.
pub struct BarSimilarity {
    z: Vec<Vec<f32>>,
    groups: [(std::ops::Range<usize>, f32); 3],
}

impl BarSimilarity {
    /// From the features of each bar, `band_count` bands each.
    pub fn new(features: &[Vec<f32>], band_count: usize) -> Self {
        let n = features.len().max(1);
        let dims = features.first().map_or(0, Vec::len);
        let mut z = vec![vec![0.0f32; dims]; features.len()];
        for d in 0..dims {
            let mean = features.iter().map(|f| f[d]).sum::<f32>() / n as f32;
            let var = features.iter().map(|f| (f[d] - mean) * (f[d] - mean)).sum::<f32>() / n as f32;
            let spread = var.sqrt().max(MIN_FEATURE_SPREAD_DB);
            for (zi, f) in z.iter_mut().zip(features) {
                zi[d] = (f[d] - mean) / spread;
            }
        }
        let bands = band_count.min(dims / 2);
        Self { z, groups: [(0..bands, 1.0), (bands..2 * bands, 0.5), (2 * bands..dims, 0.5)] }
    }

    /// Number of bars.
    pub fn len(&self) -> usize {
        self.z.len()
    }

    /// True when there are no bars.
    pub fn is_empty(&self) -> bool {
        self.z.is_empty()
    }

    /// Similarity of bars `i` and `j` (0..=1); 0 for a bar out of range.
    pub fn at(&self, i: usize, j: usize) -> f32 {
        let (Some(a), Some(b)) = (self.z.get(i), self.z.get(j)) else {
            return 0.0;
        };
        let mut d2 = 0.0f32;
        for (range, weight) in &self.groups {
            if range.is_empty() {
                continue;
            }
            let sum: f32 = range.clone().map(|d| (a[d] - b[d]).powi(2)).sum();
            d2 += weight * sum / range.len() as f32;
        }
        fmath::exp(-d2)
    }
}

/// Foote's checkerboard novelty at each bar line `i` (between bars `i − 1` and `i`) over
/// `kernel` bars a side: the mean similarity within each side (off the diagonal) less the mean
/// similarity across, clamped to 0..=1; 0 where either side has fewer than `min_side` bars.
pub fn novelty(similarity: &BarSimilarity, kernel: usize, min_side: usize) -> Vec<f32> {
    let n = similarity.len();
    let at = |i: usize, j: usize| similarity.at(i, j);
    let mut out = vec![0.0f32; n];
    for (i, slot) in out.iter_mut().enumerate() {
        let lo = i.saturating_sub(kernel);
        let hi = (i + kernel).min(n);
        if i - lo < min_side.max(1) || hi - i < min_side.max(1) {
            continue;
        }
        let within = |a: usize, b: usize| -> f32 {
            let mut sum = 0.0;
            let mut count = 0usize;
            for p in a..b {
                for q in a..b {
                    if p != q {
                        sum += at(p, q);
                        count += 1;
                    }
                }
            }
            if count == 0 { 1.0 } else { sum / count as f32 }
        };
        let mut cross = 0.0;
        for p in lo..i {
            for q in i..hi {
                cross += at(p, q);
            }
        }
        cross /= ((i - lo) * (hi - i)) as f32;
        *slot = (0.5 * (within(lo, i) + within(i, hi)) - cross).clamp(0.0, 1.0);
    }
    out
}

/// The song's sections from its grid and banded RMS envelope (see the module docs). A song of
/// fewer bars than a phrase is one section.
///
/// Errors: a grid with no bars, a bar that is not a finite increasing span, a malformed
/// envelope, or bad options.
pub fn sections(grid: &SongGrid, envelope: &RmsEnvelope, options: &SectionOptions) -> Result<Sections, SectionError> {
    options.validate()?;
    let features = bar_features(grid, envelope)?;
    let n = features.len();
    let intensity = |first: usize, bars: usize| grid.bars[first..first + bars].iter().map(|b| b.intensity).sum::<f32>() / bars as f32;
    let min_bars = options.min_section_bars;
    if n < options.phrase_bars.max(2 * min_bars) {
        return Ok(Sections {
            sections: vec![Section { first_bar: 0, bars: n, label: 0, intensity: intensity(0, n), repeat_of: None, similarity: 0.0 }],
            novelty: vec![0.0; n],
        });
    }
    let s = BarSimilarity::new(&features, envelope.bands.len());
    let nov = novelty(&s, options.kernel_bars, min_bars);
    // Phrase starts are favoured: their novelty counts for more when boundaries are chosen.
    let phrase = options.phrase_bars;
    let half = phrase / 2;
    let score: Vec<f32> = nov
        .iter()
        .enumerate()
        .map(|(i, &v)| {
            let bonus = if i % phrase == 0 {
                options.phrase_bonus
            } else if half >= 1 && phrase.is_multiple_of(2) && i.is_multiple_of(half) {
                0.5 * options.phrase_bonus
            } else {
                0.0
            };
            v * (1.0 + bonus)
        })
        .collect();
    let peak = nov.iter().copied().fold(0.0f32, f32::max);
    let threshold = options.min_novelty.max(options.relative_novelty * peak);
    let mut candidates: Vec<usize> = (min_bars..=n - min_bars)
        .filter(|&i| nov[i] >= threshold)
        .filter(|&i| score[i] >= score[i - 1] && score.get(i + 1).is_none_or(|&next| score[i] >= next))
        .collect();
    candidates.sort_by(|&a, &b| score[b].total_cmp(&score[a]).then(a.cmp(&b)));
    let mut cuts: Vec<usize> = Vec::new();
    for i in candidates {
        if cuts.iter().all(|&c| c.abs_diff(i) >= min_bars) {
            cuts.push(i);
        }
    }
    cuts.sort_unstable();
    let mut bounds = vec![0];
    bounds.extend(cuts);
    bounds.push(n);
    // Labels: each section against the earlier ones, bar against bar from their starts.
    let mut out: Vec<Section> = Vec::new();
    let mut next_label = 0u8;
    for w in bounds.windows(2) {
        let (first, bars) = (w[0], w[1] - w[0]);
        let mut best: Option<(usize, f32)> = None;
        for (k, earlier) in out.iter().enumerate() {
            let len = bars.min(earlier.bars);
            let sim = (0..len).map(|b| s.at(earlier.first_bar + b, first + b)).sum::<f32>() / len as f32;
            if best.is_none_or(|(_, v)| sim > v) {
                best = Some((k, sim));
            }
        }
        let similarity = best.map_or(0.0, |(_, v)| v);
        let repeat = best.filter(|&(k, v)| {
            let other = out[k].bars;
            v >= options.repeat_similarity && 2 * bars.min(other) >= bars.max(other)
        });
        let label = match repeat {
            Some((k, _)) => out[k].label,
            None => {
                let l = next_label;
                next_label = next_label.saturating_add(1);
                l
            }
        };
        out.push(Section { first_bar: first, bars, label, intensity: intensity(first, bars), repeat_of: repeat.map(|(k, _)| k), similarity });
    }
    Ok(Sections { sections: out, novelty: nov })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::music::{LoudnessCurve, SongGrid};

    /// A 120 BPM envelope whose bars follow `plan` (one level set per bar: full, low, mid, high
    /// in dB), with a kick on each beat shaped by the plan's accent, plus a little deterministic
    /// ripple so no feature is exactly constant.
    fn planned(plan: &[[f32; 4]]) -> (SongGrid, RmsEnvelope) {
        let hop = 0.01f32;
        let frames_per_bar = 200;
        let mut bands = vec![Vec::new(); 4];
        let mut seed = 7u32;
        for levels in plan {
            for f in 0..frames_per_bar {
                let in_beat = (f % 50) as f32 * hop;
                for (b, band) in bands.iter_mut().enumerate() {
                    seed = seed.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
                    let ripple = 1.0 + 0.02 * ((seed >> 16) as f32 / 65536.0 - 0.5);
                    let pulse = if b == 1 { 0.3 + fmath::exp(-in_beat / 0.08) } else { 1.0 };
                    band.push(fmath::powf(10f32, levels[b] / 20.0) * pulse * ripple);
                }
            }
        }
        let env = RmsEnvelope { hop_secs: hop, bands };
        let loudness = LoudnessCurve::from_rms(hop, &env.bands[0]);
        let grid = SongGrid::regular(env.duration_secs(), 120.0, 0.0, 4, loudness).unwrap();
        (grid, env)
    }

    const QUIET: [f32; 4] = [-30.0, -36.0, -32.0, -40.0];
    const VERSE: [f32; 4] = [-20.0, -24.0, -22.0, -30.0];
    const CHORUS: [f32; 4] = [-12.0, -16.0, -14.0, -18.0];

    fn plan(parts: &[([f32; 4], usize)]) -> Vec<[f32; 4]> {
        parts.iter().flat_map(|&(l, n)| std::iter::repeat_n(l, n)).collect()
    }

    #[test]
    fn sections_of_a_planned_song_are_found_and_labelled() {
        let (grid, env) = planned(&plan(&[(QUIET, 4), (VERSE, 8), (CHORUS, 8), (VERSE, 8), (CHORUS, 8)]));
        assert_eq!(grid.bars.len(), 36);
        let s = sections(&grid, &env, &SectionOptions::default()).unwrap();
        assert_eq!(s.boundaries(), vec![4, 12, 20, 28], "{s:?}");
        assert_eq!(s.letters(), "ABCBC");
        assert_eq!(s.sections[3].repeat_of, Some(1));
        assert_eq!(s.sections[4].repeat_of, Some(2));
        assert!(s.sections[4].similarity > 0.9 && s.sections[2].similarity < 0.5, "{s:?}");
        assert!(s.sections[2].intensity > s.sections[1].intensity && s.sections[1].intensity > s.sections[0].intensity);
        // Deterministic.
        assert_eq!(s, sections(&grid, &env, &SectionOptions::default()).unwrap());
    }

    #[test]
    fn a_change_one_bar_off_a_phrase_start_stays_where_it_is() {
        // The change at bar 9 is not moved to the phrase start at 8: the phrase is a preference.
        let (grid, env) = planned(&plan(&[(VERSE, 9), (CHORUS, 7), (VERSE, 8)]));
        let s = sections(&grid, &env, &SectionOptions::default()).unwrap();
        assert_eq!(s.boundaries(), vec![9, 16], "{s:?}");
    }

    #[test]
    fn a_steady_signal_is_one_section_and_so_is_a_short_song() {
        let (grid, env) = planned(&plan(&[(VERSE, 24)]));
        let s = sections(&grid, &env, &SectionOptions::default()).unwrap();
        assert_eq!(s.sections.len(), 1, "{s:?}");
        assert_eq!((s.sections[0].first_bar, s.sections[0].bars), (0, 24));
        let (grid, env) = planned(&plan(&[(QUIET, 1), (CHORUS, 2)]));
        let s = sections(&grid, &env, &SectionOptions::default()).unwrap();
        assert_eq!(s.sections.len(), 1);
        assert_eq!(s.sections[0].bars, 3);
    }

    #[test]
    fn a_repeated_sections_bars_repeat_its_first_occurrence_bar_for_bar() {
        let sec = |first_bar: usize, bars: usize, label: u8, repeat_of: Option<usize>| Section { first_bar, bars, label, intensity: 0.5, repeat_of, similarity: 0.8 };
        // A (4) B (8) A (4) B (6, shorter) B (10, longer: its last 2 bars repeat nothing).
        let s = Sections { sections: vec![sec(0, 4, 0, None), sec(4, 8, 1, None), sec(12, 4, 0, Some(0)), sec(16, 6, 1, Some(1)), sec(22, 10, 1, Some(3))], novelty: vec![0.0; 32] };
        let r = s.repeat_of_bars(32);
        assert_eq!(r.len(), 32);
        assert!(r[..12].iter().all(Option::is_none));
        assert_eq!(r[12..16], [Some(0), Some(1), Some(2), Some(3)]);
        assert_eq!(r[16..22], [Some(4), Some(5), Some(6), Some(7), Some(8), Some(9)]);
        // The third B repeats the first, not the second.
        assert_eq!(r[22..30], [Some(4), Some(5), Some(6), Some(7), Some(8), Some(9), Some(10), Some(11)]);
        assert_eq!(r[30..], [None, None]);
        // Fewer bars than the sections cover: no index past the end.
        assert_eq!(s.repeat_of_bars(14).len(), 14);
    }

    #[test]
    fn bad_input_is_a_typed_error() {
        let (grid, env) = planned(&plan(&[(VERSE, 8)]));
        let o = SectionOptions::default();
        let mut no_bars = grid.clone();
        no_bars.bars.clear();
        assert_eq!(sections(&no_bars, &env, &o), Err(SectionError::NoBars));
        let mut bad_bar = grid.clone();
        bad_bar.bars[3].end_secs = f32::NAN;
        assert!(matches!(sections(&bad_bar, &env, &o), Err(SectionError::BadBar { index: 3, .. })));
        let empty = RmsEnvelope { hop_secs: 0.01, bands: vec![] };
        assert_eq!(sections(&grid, &empty, &o), Err(SectionError::Envelope(MusicError::Empty)));
        let bad = SectionOptions { kernel_bars: 0, ..o };
        assert!(matches!(sections(&grid, &env, &bad), Err(SectionError::BadOption { what: "kernelBars", .. })));
        let bad = SectionOptions { repeat_similarity: f32::NAN, ..o };
        assert!(matches!(sections(&grid, &env, &bad), Err(SectionError::BadOption { what: "repeatSimilarity", .. })));
    }
}
