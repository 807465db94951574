//! The figures the generation pipeline checks of a dance (spec §J, [`super::generate`]): the
//! dance rendered unheld ([`dance_figures`], what stages 2 to 4 follow) or as it is played,
//! joins blended and feet held ([`played_figures`], what the preference order and the join repair
//! follow), and [`Measured`], which keeps each path's figures so no stage renders a path twice.

use super::generate::Problem;
use super::profile::{self, Work};
use super::quality::{DanceMeasures, FootSkate, QualityMotion};
use super::render::{render_measured, render_switched, HoldWork, RenderOptions};
use super::segment::SegmentLibrary;
use crate::bars::Bar;

/// What the pipeline checks of a dance it made (spec §J, on the rendered dance within its bars).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DanceFigures {
    /// Kinetic beats over the bars' beats (4 a bar in 4/4, 3 in 3/4): 1 turns on every count,
    /// 0.5 on every other.
    pub kinetic_per_count: f32,
    /// Mean foot skate, centimetres per second.
    pub foot_skate_cm_per_s: f32,
    /// The largest join jump (spec §J, [`super::quality::join_jumps`]), 0 with one bar.
    pub join_jump_max: f32,
    /// The bar after that join (its first bar is 1), if any.
    pub worst_join_bar: Option<usize>,
}

/// [`DanceFigures`] of the dance `path` fills `bars` with; `None` when it cannot be measured
/// (too short, no bars).
pub fn dance_figures(lib: &SegmentLibrary, bars: &[Bar], path: &[usize]) -> Option<DanceFigures> {
    dance_figures_with(lib, bars, path, true)
}

/// [`dance_figures`]; `quick` off: the control, every rendered frame posed
/// ([`super::GenerateOptions::quick_measures`]).
pub fn dance_figures_with(lib: &SegmentLibrary, bars: &[Bar], path: &[usize], quick: bool) -> Option<DanceFigures> {
    let choices: Vec<Option<usize>> = path.iter().map(|&s| Some(s)).collect();
    // Unheld: holding the feet (a cost on every measure of a refill) only lowers the skate the
    // filling follows, and each bar keeps its holds only where they keep its beat figures.
    let (clip, switches) = render_switched(lib, bars, &choices, &RenderOptions { hold_feet: false, ..RenderOptions::default() });
    let m = profile::part(profile::Part::Posed, || if quick { QualityMotion::from_clip(&clip) } else { QualityMotion::from_clip_every_frame(&clip) }).ok()?;
    profile::part(profile::Part::Measures, || figures_of(&m, bars, &switches))
}

/// One bar of the dance as it is played ([`played_figures`]), measured as the strip's notes
/// measure it ([`super::notes`]) on the bar's own counts.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PlayedBar {
    /// BAS-music on the bar's counts less BAS-music on its counts moved by half a count (§J's
    /// control): the bar lands on its counts when this is at least
    /// [`super::notes::OFF_BEAT_MARGIN`] (else the strip flags it "off the beat").
    pub beat_margin: f32,
    /// The join jump at the bar's start (§J), `None` for the first bar.
    pub join_jump: Option<f32>,
    /// The bar's mean foot skate (§J), centimetres per second.
    pub foot_skate_cm_per_s: f32,
    /// BAS-music on the bar's counts (§J).
    pub bas_music: f32,
    /// Kinetic beats within the bar.
    pub kinetic_beats: usize,
    /// Joint-frames on the floor the bar's foot skate is over.
    pub skate_contacts: usize,
}

/// The dance as it is played, measured ([`played_figures`]).
#[derive(Clone, Debug, PartialEq)]
pub struct Played {
    /// The whole dance's figures.
    pub whole: DanceFigures,
    /// BAS-music of the whole dance on its bars' counts (§J).
    pub bas_music: f32,
    /// Each bar's.
    pub bars: Vec<PlayedBar>,
    /// Joint-frames on the floor the whole dance's foot skate is over.
    pub skate_contacts: usize,
    /// The divisor of its join jumps (§J's 95th percentile of the velocity changes inside the
    /// moves); 0 when not known.
    pub join_norm: f32,
}

/// The dance `path` fills `bars` with as the viewer sees it (rendered as played: joins
/// blended, feet held, [`RenderOptions::default`]), measured ([`Played`]); `None` when it
/// cannot be measured. What the join repair and the preference
/// order measure ([`GenerateOptions::measure_played`], [`order_stage`]): holding the feet moves
/// the feet across a join, so a dance whose joins are within the goal unheld can join over it
/// as played (the 150 BPM demo piece in 3 of `choreo_my_moves`: 1.92 held).
pub fn played_figures(lib: &SegmentLibrary, bars: &[Bar], path: &[usize]) -> Option<Played> {
    played_figures_with(lib, bars, path, true)
}

/// [`played_figures`]; `quick` off: the control, measured as before session 16 (the held-feet
/// rule's free pass posed each round, every frame posed, the played dance measured again, and
/// §J's measures taken anew for the whole dance and for its bars):
/// [`super::GenerateOptions::quick_measures`]. The same figures either way (the test
/// `quick_measures_keep_every_figure`).
pub fn played_figures_with(lib: &SegmentLibrary, bars: &[Bar], path: &[usize], quick: bool) -> Option<Played> {
    played_figures_posed(lib, bars, path, HoldWork { quick, read_only: quick, legs_only: quick, reuse_frames: quick })
}

/// [`played_figures_with`] with the held-feet rule's work named ([`HoldWork`]): `read_only`
/// off is session 17's measures, each round of the rule posing every frame of its held pass,
/// not only the frames its measures read ([`super::GenerateOptions::pose_read_frames_only`],
/// the control; the test `posing_only_the_frames_read_keeps_every_figure`); `legs_only` off,
/// the rule's free pass posing every joint, not only those it reads (session 20's measures,
/// [`super::GenerateOptions::free_pass_legs_only`], the control). The same figures either way.
pub(super) fn played_figures_posed(lib: &SegmentLibrary, bars: &[Bar], path: &[usize], work: HoldWork) -> Option<Played> {
    let quick = work.quick;
    let choices: Vec<Option<usize>> = path.iter().map(|&s| Some(s)).collect();
    let (clip, switches, measured) = render_measured(lib, bars, &choices, &RenderOptions::default(), work);
    let (m, handed) = match measured {
        Some((m, d)) => (m, d),
        None if quick => (profile::part(profile::Part::Posed, || QualityMotion::from_clip(&clip)).ok()?, None),
        None => (QualityMotion::from_clip_every_frame(&clip).ok()?, None),
    };
    if !quick {
        return played_of_control(&m, bars, &switches);
    }
    let counts = bar_counts_secs(bars);
    super::quality::check_beats(&counts).ok()?;
    // Each of §J's measures and their readout once, read by both the whole dance's figures and
    // each bar's: those the held-feet rule took of this motion last, when it hands them on
    // (read on these bars' counts, as here).
    let (measures, readout) = match handed {
        Some(d) => d,
        None => {
            let (d, r) = profile::part(profile::Part::Measures, || {
                let d = DanceMeasures::of(&m, bars, &switches);
                let r = d.readout(bars, &counts);
                (d, r)
            });
            (d, r?)
        }
    };
    let whole = whole_figures(&measures, readout.kinetic_beats, readout.foot_skate, bars);
    let per_bar = readout.bars.iter().zip(bars).map(|(q, b)| PlayedBar::of(q, b)).collect();
    Some(Played { whole, bas_music: readout.beats.bas_music, bars: per_bar, skate_contacts: readout.foot_skate.contacts, join_norm: measures.join_norm })
}

impl PlayedBar {
    fn of(b: &super::quality::BarQuality, bar: &Bar) -> PlayedBar {
        PlayedBar {
            beat_margin: b.beats.bas_music - b.beats.bas_music_shifted,
            join_jump: b.join_jump,
            foot_skate_cm_per_s: b.foot_skate.mean_cm_per_s,
            bas_music: b.beats.bas_music,
            kinetic_beats: (b.beats.kinetic_beats_per_sec * bar.duration_secs().max(1e-6) + 0.5) as usize,
            skate_contacts: b.foot_skate.contacts,
        }
    }
}

/// Every count of `bars`, seconds (a bar of n beats: n counts evenly over it).
pub(super) fn bar_counts_secs(bars: &[Bar]) -> Vec<f32> {
    bars.iter()
        .flat_map(|b| {
            let n = b.beat_count().max(1);
            (0..n).map(move |k| b.start_secs + b.duration_secs() * k as f32 / n as f32)
        })
        .collect()
}

/// [`played_figures_posed`]'s figures measured as before session 20: the whole dance's
/// ([`figures_of`]) and the readout's ([`super::quality::dance_quality_switched_of`]) each
/// measuring §J anew. The control of `quick_measures_keep_every_figure`.
fn played_of_control(m: &QualityMotion, bars: &[Bar], switches: &[f32]) -> Option<Played> {
    let whole = figures_of(m, bars, switches)?;
    let q = super::quality::dance_quality_switched_of(m, bars, &bar_counts_secs(bars), switches).ok()?;
    let per_bar = q.bars.iter().zip(bars).map(|(q, b)| PlayedBar::of(q, b)).collect();
    Some(Played { whole, bas_music: q.beats.bas_music, bars: per_bar, skate_contacts: q.foot_skate.contacts, join_norm: 0.0 })
}

/// [`DanceFigures`] of a rendered dance `m` over `bars`, its joins falling at `switches`
/// ([`super::render_switched`]).
fn figures_of(m: &QualityMotion, bars: &[Bar], switches: &[f32]) -> Option<DanceFigures> {
    let d = DanceMeasures::of(m, bars, switches);
    let (first, last) = (bars.first()?, bars.last()?);
    Some(whole_figures(&d, d.kinetic_in(first.start_secs, last.end_secs), d.skate_in(first.start_secs, last.end_secs), bars))
}

/// [`DanceFigures`] of the whole dance over `bars`, from its measures, the kinetic beats within
/// the bars and the foot skate over them ([`super::quality::DanceReadout`]'s).
fn whole_figures(d: &DanceMeasures, kinetic: usize, skate: FootSkate, bars: &[Bar]) -> DanceFigures {
    let counts: usize = bars.iter().map(Bar::beat_count).sum();
    // Join jumps as dance_quality measures them (at each switch, wherever it falls).
    let worst = d.jumps.iter().enumerate().max_by(|a, b| a.1.total_cmp(b.1)).map(|(k, &j)| (d.joins[k], j));
    DanceFigures {
        kinetic_per_count: kinetic as f32 / counts.max(1) as f32,
        foot_skate_cm_per_s: skate.mean_cm_per_s,
        join_jump_max: worst.map_or(0.0, |w| w.1),
        worst_join_bar: worst.map(|w| w.0),
    }
}

/// The figures of the paths measured so far (a render and a measure each: kept, not redone).
#[derive(Default)]
pub struct Measured {
    pub(super) done: Vec<(Vec<usize>, Option<DanceFigures>)>,
    pub(super) played: Vec<(Vec<usize>, Option<Played>)>,
    /// Paths measured near their changes only ([`Measured::screened`]), not yet whole.
    near: Vec<(Vec<usize>, Played)>,
}

impl Measured {
    /// [`dance_figures`] of `path`, measured once.
    pub fn of(&mut self, p: &Problem, path: &[usize]) -> Option<DanceFigures> {
        if let Some((_, f)) = self.done.iter().find(|(q, _)| q == path) {
            return *f;
        }
        let f = profile::timed(Work::Measure, || dance_figures_with(p.lib, p.bars, path, p.quick_measures));
        self.done.push((path.to_vec(), f));
        f
    }

    fn work(p: &Problem) -> HoldWork {
        HoldWork { quick: p.quick_measures, read_only: p.pose_read_frames_only, legs_only: p.free_pass_legs_only, reuse_frames: p.rounds_copy_same_frames }
    }

    /// [`played_figures`] of `path`, the whole dance measured once.
    pub fn played(&mut self, p: &Problem, path: &[usize]) -> Option<Played> {
        if let Some((_, f)) = self.played.iter().find(|(q, _)| q == path) {
            return f.clone();
        }
        let f = profile::timed(Work::Measure, || played_figures_posed(p.lib, p.bars, path, Self::work(p)));
        self.near.retain(|(q, _)| q != path);
        self.played.push((path.to_vec(), f.clone()));
        f
    }

    /// A refill's figures as played for the stages to screen it by: with
    /// [`super::GenerateOptions::windowed_measures`], measured near the bars it changes from
    /// the nearest dance measured whole ([`played_near`]) when those windows are under half the
    /// dance, else [`Measured::played`]. A stage keeps a dance only by its whole measure.
    pub fn screened(&mut self, p: &Problem, path: &[usize]) -> Option<Played> {
        if let Some((_, f)) = self.played.iter().find(|(q, _)| q == path) {
            return f.clone();
        }
        if let Some((_, f)) = self.near.iter().find(|(q, _)| q == path) {
            return Some(f.clone());
        }
        if p.windowed_measures {
            let nearest = self
                .played
                .iter()
                .rev()
                .filter_map(|(q, f)| Some((q, f.as_ref()?)))
                .filter(|(q, _)| q.len() == path.len())
                .min_by_key(|(q, _)| q.iter().zip(path).filter(|(a, b)| a != b).count());
            if let Some(f) = nearest.and_then(|(q, f)| profile::timed(Work::Measure, || played_near(p.lib, p.bars, path, q, f, Self::work(p)))) {
                self.near.push((path.to_vec(), f.clone()));
                return Some(f);
            }
        }
        self.played(p, path)
    }

    /// Whether `path`'s figures as played are known only near its changes ([`Measured::screened`]).
    pub fn is_near(&self, path: &[usize]) -> bool {
        self.near.iter().any(|(q, _)| q == path)
    }

    /// The whole dance's figures as played ([`Measured::played`]) when `played`, else unheld
    /// ([`Measured::of`]).
    pub fn figures(&mut self, p: &Problem, path: &[usize], played: bool) -> Option<DanceFigures> {
        if played {
            self.played(p, path).map(|f| f.whole)
        } else {
            self.of(p, path)
        }
    }
}

/// Bars a windowed measure ([`played_near`]) reads beside each changed bar: the bar after it
/// (its join) and one more each side (the held feet carry across a join).
pub const NEAR_READ_BARS: usize = 1;

/// Bars rendered beyond those a windowed measure reads, each side, so the joins and held feet of
/// the read bars have their neighbours. Four were no closer to the whole measure than two (the
/// test `a_dance_measured_near_its_changes_reads_its_joins_as_the_whole_measure`: the gap left
/// is the whole dance's rules, not the window's reach).
pub const NEAR_MARGIN_BARS: usize = 2;

/// [`played_figures_posed`] of `path` from `reference`'s figures `known` (a dance of the same
/// bars measured before), measuring only near the bars where the two differ: each such bar, the
/// bar after it and [`NEAR_READ_BARS`] each side are read from a render of them with
/// [`NEAR_MARGIN_BARS`] more each side (bars moved to start at 0), the other bars kept from
/// `known`; the whole dance's figures follow by the read bars' differences (BAS-music weighted
/// by counts, kinetic beats added, skate weighted by the joint-frames on the floor), its worst
/// join from the bars'. `None` when the windows would cover half the dance or more, or one
/// cannot be measured (then measure the whole dance).
pub(super) fn played_near(lib: &SegmentLibrary, bars: &[Bar], path: &[usize], reference: &[usize], known: &Played, work: HoldWork) -> Option<Played> {
    let n = bars.len();
    if reference.len() != n || path.len() != n || known.bars.len() != n || known.join_norm <= 0.0 {
        return None;
    }
    // The bars to read, merged into runs, and each run's render window.
    let mut read = vec![false; n];
    for t in (0..n).filter(|&t| path[t] != reference[t]) {
        for r in t.saturating_sub(NEAR_READ_BARS)..=(t + 1 + NEAR_READ_BARS).min(n - 1) {
            read[r] = true;
        }
    }
    let mut runs: Vec<(usize, usize)> = Vec::new();
    for t in (0..n).filter(|&t| read[t]) {
        match runs.last_mut() {
            Some(r) if t <= r.1 + 2 * NEAR_MARGIN_BARS => r.1 = t,
            _ => runs.push((t, t)),
        }
    }
    let windows: Vec<(usize, usize)> = runs.iter().map(|&(a, b)| (a.saturating_sub(NEAR_MARGIN_BARS), (b + 1 + NEAR_MARGIN_BARS).min(n))).collect();
    let rendered: usize = windows.iter().map(|w| w.1 - w.0).sum();
    if rendered * 2 >= n {
        return None;
    }
    let mut out = known.clone();
    let total_counts: usize = bars.iter().map(Bar::beat_count).sum::<usize>().max(1);
    let mut kinetic = (known.whole.kinetic_per_count as f64 * total_counts as f64).round();
    let mut bas_sum = known.bas_music as f64 * total_counts as f64;
    let mut skate_sum = known.whole.foot_skate_cm_per_s as f64 * known.skate_contacts as f64;
    let mut contacts = known.skate_contacts as i64;
    for (&(a, b), &(lo, hi)) in runs.iter().zip(&windows) {
        let off = bars[lo].start_secs;
        let sub: Vec<Bar> = bars[lo..hi].iter().enumerate().map(|(i, x)| Bar { index: i, start_secs: x.start_secs - off, end_secs: x.end_secs - off, ..x.clone() }).collect();
        let got = super::quality::with_join_normaliser(known.join_norm, || played_figures_posed(lib, &sub, &path[lo..hi], work))?;
        for t in a..=b {
            let (old, new) = (known.bars[t], *got.bars.get(t - lo)?);
            let counts = bars[t].beat_count() as f64;
            kinetic += new.kinetic_beats as f64 - old.kinetic_beats as f64;
            bas_sum += (new.bas_music as f64 - old.bas_music as f64) * counts;
            skate_sum += new.foot_skate_cm_per_s as f64 * new.skate_contacts as f64 - old.foot_skate_cm_per_s as f64 * old.skate_contacts as f64;
            contacts += new.skate_contacts as i64 - old.skate_contacts as i64;
            out.bars[t] = new;
        }
    }
    out.skate_contacts = contacts.max(0) as usize;
    out.bas_music = (bas_sum / total_counts as f64) as f32;
    out.whole.kinetic_per_count = (kinetic.max(0.0) / total_counts as f64) as f32;
    out.whole.foot_skate_cm_per_s = if contacts > 0 { (skate_sum / contacts as f64).max(0.0) as f32 } else { 0.0 };
    let worst = out.bars.iter().enumerate().filter_map(|(t, b)| Some((t, b.join_jump?))).max_by(|x, y| x.1.total_cmp(&y.1));
    out.whole.join_jump_max = worst.map_or(0.0, |w| w.1);
    out.whole.worst_join_bar = worst.map(|w| w.0);
    Some(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::choreo::grid::bars_from_tempo;

    #[test]
    fn quick_measures_keep_every_figure() {
        // Dances of built-in moves at four tempi (bar i plays every k-th live move: joins of
        // every kind, some bars keeping their holds and some not), measured quick and as the
        // control (session 15's measures): the same figures, to the bit.
        let lib = SegmentLibrary::builtin();
        let live: Vec<usize> = lib.segments().iter().filter(|s| !s.retired && s.counts() == 4).map(|s| s.index).collect();
        for (k, bpm) in [(3usize, 96.0f32), (7, 120.0), (11, 138.0), (5, 160.0)] {
            let bars = bars_from_tempo(14.0, bpm, 4, 0.0, |_, _| 0.5).unwrap();
            let path: Vec<usize> = (0..bars.len()).map(|i| live[(i * k + bpm as usize) % live.len()]).collect();
            let (quick, control) = (played_figures_with(&lib, &bars, &path, true), played_figures_with(&lib, &bars, &path, false));
            assert!(quick.is_some(), "{bpm} BPM: measured");
            // The control does not keep the join divisor (windowed measures read it).
            assert_eq!(quick.map(|q| Played { join_norm: 0.0, ..q }), control, "{bpm} BPM: as played");
            assert_eq!(dance_figures_with(&lib, &bars, &path, true), dance_figures_with(&lib, &bars, &path, false), "{bpm} BPM: unheld");
        }
    }

    #[test]
    fn posing_only_the_frames_read_keeps_every_figure() {
        // The held passes posing only the frames the measures read, against posing every
        // frame (session 17's measures): the same figures, to the bit, on dances that keep
        // their holds and on ones that drop some (the rule's rounds compared).
        let lib = SegmentLibrary::builtin();
        let live: Vec<usize> = lib.segments().iter().filter(|s| !s.retired && s.counts() == 4).map(|s| s.index).collect();
        for (k, bpm) in [(3usize, 96.0f32), (7, 120.0), (11, 138.0), (5, 160.0), (13, 104.0)] {
            let bars = bars_from_tempo(20.0, bpm, 4, 0.0, |_, _| 0.5).unwrap();
            let path: Vec<usize> = (0..bars.len()).map(|i| live[(i * k + bpm as usize) % live.len()]).collect();
            let (read, every) = (played_figures_posed(&lib, &bars, &path, HoldWork { quick: true, read_only: true, legs_only: true, reuse_frames: true }), played_figures_posed(&lib, &bars, &path, HoldWork { quick: true, read_only: false, legs_only: true, reuse_frames: true }));
            assert!(read.is_some(), "{bpm} BPM: measured");
            assert_eq!(read, every, "{bpm} BPM");
        }
        // The frames read at 60 fps are every other one: half the held pass is not posed.
        let read = crate::choreo::quality::QualityMotion::frames_read(601, 60.0);
        assert_eq!(read.iter().filter(|&&r| r).count(), 301);
    }

    #[test]
    fn the_free_pass_posing_its_legs_alone_keeps_every_figure() {
        // The held-feet rule's free pass posing only the hips and legs, against posing every
        // joint (session 20's measures): the same figures, to the bit, on dances that keep
        // their holds and on ones that drop some, one of them a minute long.
        let lib = SegmentLibrary::builtin();
        let live: Vec<usize> = lib.segments().iter().filter(|s| !s.retired && s.counts() == 4).map(|s| s.index).collect();
        for (k, bpm, secs) in [(3usize, 96.0f32, 20.0), (7, 120.0, 60.0), (11, 138.0, 20.0), (5, 160.0, 20.0)] {
            let bars = bars_from_tempo(secs, bpm, 4, 0.0, |_, _| 0.5).unwrap();
            let path: Vec<usize> = (0..bars.len()).map(|i| live[(i * k + bpm as usize) % live.len()]).collect();
            let (lean, whole) = (played_figures_posed(&lib, &bars, &path, HoldWork { quick: true, read_only: true, legs_only: true, reuse_frames: true }), played_figures_posed(&lib, &bars, &path, HoldWork { quick: true, read_only: true, legs_only: false, reuse_frames: true }));
            assert!(lean.is_some(), "{bpm} BPM: measured");
            assert_eq!(lean, whole, "{bpm} BPM");
        }
    }

    #[test]
    fn a_dance_measured_near_its_changes_reads_its_joins_as_the_whole_measure() {
        // Generated dances of the built-in moves at three tempi (what stage 5 measures); a
        // second dance changes one bar and, further on, two bars in a row, to moves of the same
        // count from elsewhere in the dance. Measured near those changes from the first dance's
        // figures ([`played_near`]), its worst join (what stage 5 screens refills by) reads as
        // the whole measure of the second does within 5 %, each join within 35 % of the larger
        // of it and 0.5 (measured: 0.4 %, 11 % and 29 % at the three tempi, the last on joins of
        // 0.16–0.31), and the whole dance's BAS-music, beat rate and skate within a little; bars
        // far from every change keep the first's figures. A screen, not a measure: the whole
        // measure moves bars far from a change too (the join divisor, the feet's floors and the
        // held-feet rule's rounds are the whole dance's: at 138 BPM a join 14 bars from the
        // nearest change reads 1.53 against 1.48 before it), and wider windows do not close the
        // gap (4 bars each side: 21 % at 138 BPM), so a stage keeps a dance only by its whole
        // measure ([`Measured::screened`]).
        let lib = SegmentLibrary::builtin();
        let work = HoldWork { quick: true, read_only: true, legs_only: true, reuse_frames: true };
        for bpm in [120.0f32, 138.0, 96.0] {
            let bars = bars_from_tempo(150.0, bpm, 4, 0.0, |a, _| 0.3 + 0.4 * crate::fmath::sin(a * 0.05).abs()).unwrap();
            let n = bars.len();
            let layers: Vec<super::super::fill::Layer> = bars.iter().map(|b| super::super::fill::Layer::Open { intensity: b.intensity }).collect();
            let (path, _) = super::super::generate::generate(&lib, &bars, &layers, super::super::fill::FillWeights::default(), &super::super::GenerateOptions::default()).expect("generated");
            let mut q = path.clone();
            let (c1, c2) = (n / 4, 2 * n / 3);
            q[c1] = path[c1 + 7];
            q[c2] = path[c2 + 5];
            q[c2 + 1] = path[c2 + 9];
            let known = played_figures(&lib, &bars, &path).expect("measured");
            let whole = played_figures(&lib, &bars, &q).expect("measured");
            let near = played_near(&lib, &bars, &q, &path, &known, work).expect("measured near the changes");
            assert_ne!(known.bars[c2 + 1], whole.bars[c2 + 1], "{bpm} BPM: the change changes the figures");
            let mut worst = (0.0f32, 0.0f32, 0.0f32);
            for (t, (a, b)) in whole.bars.iter().zip(&near.bars).enumerate() {
                worst.0 = worst.0.max((a.beat_margin - b.beat_margin).abs());
                if let (Some(x), Some(y)) = (a.join_jump, b.join_jump) {
                    worst.1 = worst.1.max((x - y).abs() / x.max(0.5));
                }
                worst.2 = worst.2.max((a.foot_skate_cm_per_s - b.foot_skate_cm_per_s).abs());
                if t + 2 < c1 || (t > c1 + 2 && t + 2 < c2) || t > c2 + 3 {
                    assert_eq!(*b, known.bars[t], "{bpm} BPM: bar {t} far from the changes is kept");
                }
            }
            println!("{bpm} BPM, {n} bars: joins within {:.4} (relative), beat margin within {:.4}, skate within {:.3} cm/s; whole {:?} against {:?}", worst.1, worst.0, worst.2, near.whole, whole.whole);
            assert!(worst.1 <= 0.35, "{bpm} BPM: joins {worst:?}");
            assert!((near.whole.join_jump_max - whole.whole.join_jump_max).abs() <= 0.05 * whole.whole.join_jump_max, "{bpm} BPM: worst join");
            assert!((near.bas_music - whole.bas_music).abs() <= 0.01, "{bpm} BPM: BAS-music {} against {}", near.bas_music, whole.bas_music);
            assert!((near.whole.kinetic_per_count - whole.whole.kinetic_per_count).abs() <= 0.01, "{bpm} BPM: kinetic beats a count");
            assert!((near.whole.foot_skate_cm_per_s - whole.whole.foot_skate_cm_per_s).abs() <= 0.5, "{bpm} BPM: skate");
            // A change in every other bar is measured whole (its windows would cover the dance).
            let spread: Vec<usize> = (0..n).map(|t| if t % 2 == 0 { path[t] } else { path[(t + 4) % n] }).collect();
            assert!(played_near(&lib, &bars, &spread, &path, &known, work).is_none(), "{bpm} BPM: spread changes");
            // The stages' cache: a refill screened near its changes from the dance measured
            // whole, then measured whole when a stage would keep it; with the switch off,
            // screened is the whole measure.
            for on in [true, false] {
                let p = Problem::new(&lib, &bars, &layers, super::super::fill::FillWeights::default(), &super::super::GenerateOptions { windowed_measures: on, ..Default::default() });
                let mut m = Measured::default();
                assert_eq!(m.played(&p, &path).as_ref(), Some(&known));
                let screened = m.screened(&p, &q).expect("screened");
                assert_eq!(m.is_near(&q), on, "{bpm} BPM, windowed {on}");
                assert_eq!(&screened, if on { &near } else { &whole }, "{bpm} BPM, windowed {on}");
                assert_eq!(m.played(&p, &q).as_ref(), Some(&whole), "{bpm} BPM, windowed {on}: measured whole");
                assert!(!m.is_near(&q));
                assert_eq!(m.screened(&p, &q).as_ref(), Some(&whole), "{bpm} BPM, windowed {on}: the whole measure kept");
            }
        }
    }
}
