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
    let per_bar = readout.bars.iter().map(PlayedBar::of).collect();
    Some(Played { whole, bas_music: readout.beats.bas_music, bars: per_bar })
}

impl PlayedBar {
    fn of(b: &super::quality::BarQuality) -> PlayedBar {
        PlayedBar { beat_margin: b.beats.bas_music - b.beats.bas_music_shifted, join_jump: b.join_jump, foot_skate_cm_per_s: b.foot_skate.mean_cm_per_s }
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
    let per_bar = q.bars.iter().map(PlayedBar::of).collect();
    Some(Played { whole, bas_music: q.beats.bas_music, bars: per_bar })
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

    /// [`played_figures`] of `path`, measured once.
    pub fn played(&mut self, p: &Problem, path: &[usize]) -> Option<Played> {
        if let Some((_, f)) = self.played.iter().find(|(q, _)| q == path) {
            return f.clone();
        }
        let f = profile::timed(Work::Measure, || played_figures_posed(p.lib, p.bars, path, HoldWork { quick: p.quick_measures, read_only: p.pose_read_frames_only, legs_only: p.free_pass_legs_only, reuse_frames: p.rounds_copy_same_frames }));
        self.played.push((path.to_vec(), f.clone()));
        f
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
            assert_eq!(quick, control, "{bpm} BPM: as played");
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
}
