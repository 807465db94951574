//! Where Generate's time goes (issue 26's speed goal, [`super::generate`]): per stage, the
//! time in the fills (shortest paths, and the free-skate pass after a refill) against the
//! renders and measures of the dance ([`super::figures`]), and inside those the parts of a
//! measure ([`PARTS`]). Off unless a caller lends a clock
//! ([`profiled`]): the core reads no clock of its own (a wasm module has none without its
//! host's), so the benches pass theirs, natively `Instant` and in wasm the host's
//! `performance.now()`. When off, each record is one thread-local read.

use std::cell::RefCell;

/// The stages [`Profile`] reports, in pipeline order.
pub const STAGES: [&str; 7] = ["1 fill", "2 beat rate", "3 free skate", "4 skate", "4b order", "5 join repair", "takes"];

/// One stage's time, milliseconds, and its work.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct StageProfile {
    /// The whole stage.
    pub total_ms: f64,
    /// Fills run (a shortest path, or a free-skate pass) and the time in them.
    pub fills: usize,
    pub fill_ms: f64,
    /// Dances rendered and measured (unheld or as played), and the time in them.
    pub measures: usize,
    pub measure_ms: f64,
}

/// The parts of a render and measure ([`Work::Measure`]) that [`Profile::parts`] reports, over
/// every stage: the render before the feet are held (each bar's move sampled, placed and
/// joined); the held-feet rule's first call of its kernel (`hold_feet_in_dance`: the free pass,
/// pass 0, and round 0's held pass); each later round's held pass; the dances posed for §J
/// (`QualityMotion`); §J's measures and their readout (`DanceMeasures`).
pub const PARTS: [&str; 5] = ["render (sampled, placed, joined)", "free pass + round 0's held pass", "held pass, later rounds", "posed for §J (QualityMotion)", "§J measures and readout"];

/// One part's count and time, milliseconds ([`PARTS`]).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PartProfile {
    pub count: usize,
    pub ms: f64,
}

/// Per stage of [`STAGES`], its [`StageProfile`]; per part of a measure ([`PARTS`]), its
/// [`PartProfile`] over every stage.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Profile {
    pub stages: [StageProfile; 7],
    pub parts: [PartProfile; 5],
}

impl Profile {
    /// The stage called `name` (one of [`STAGES`]).
    pub fn stage(&self, name: &str) -> Option<&StageProfile> {
        STAGES.iter().position(|s| *s == name).and_then(|k| self.stages.get(k))
    }
}

struct Recorder {
    clock: fn() -> f64,
    stage: usize,
    profile: Profile,
}

thread_local! {
    static RECORDER: RefCell<Option<Recorder>> = const { RefCell::new(None) };
}

/// Runs `f` with `clock` (milliseconds, any origin) lent to the recorder and returns what it
/// returned with where the time went. Not nested: an inner call's records go to itself.
pub fn profiled<R>(clock: fn() -> f64, f: impl FnOnce() -> R) -> (R, Profile) {
    let outer = RECORDER.with(|r| r.borrow_mut().replace(Recorder { clock, stage: 0, profile: Profile::default() }));
    let out = f();
    let profile = RECORDER.with(|r| std::mem::replace(&mut *r.borrow_mut(), outer)).map(|r| r.profile).unwrap_or_default();
    (out, profile)
}

fn now() -> Option<f64> {
    RECORDER.with(|r| r.borrow().as_ref().map(|r| (r.clock)()))
}

/// What kind of work [`timed`] records.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Work {
    Fill,
    Measure,
}

/// Runs `f`, recording its time as `work` of the current stage (when profiled).
pub(super) fn timed<R>(work: Work, f: impl FnOnce() -> R) -> R {
    let Some(t0) = now() else { return f() };
    let out = f();
    RECORDER.with(|r| {
        if let Some(r) = r.borrow_mut().as_mut() {
            let ms = (r.clock)() - t0;
            if let Some(s) = r.profile.stages.get_mut(r.stage) {
                match work {
                    Work::Fill => (s.fills, s.fill_ms) = (s.fills + 1, s.fill_ms + ms),
                    Work::Measure => (s.measures, s.measure_ms) = (s.measures + 1, s.measure_ms + ms),
                }
            }
        }
    });
    out
}

/// A part of a measure ([`PARTS`]), in order.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Part {
    Render = 0,
    FreePass = 1,
    HeldPass = 2,
    Posed = 3,
    Measures = 4,
}

/// Runs `f`, recording its time as `part` of a measure (when profiled), whatever the stage.
pub(crate) fn part<R>(part: Part, f: impl FnOnce() -> R) -> R {
    let t0 = part_start();
    let out = f();
    part_end(part, t0);
    out
}

/// The clock's reading for [`part_end`] (`None` when not profiled): a part's start where a
/// closure ([`part`]) will not fit.
pub(crate) fn part_start() -> Option<f64> {
    now()
}

/// Records the time since `t0` ([`part_start`]) as `part` of a measure.
pub(crate) fn part_end(part: Part, t0: Option<f64>) {
    let Some(t0) = t0 else { return };
    RECORDER.with(|r| {
        if let Some(r) = r.borrow_mut().as_mut() {
            let ms = (r.clock)() - t0;
            if let Some(s) = r.profile.parts.get_mut(part as usize) {
                (s.count, s.ms) = (s.count + 1, s.ms + ms);
            }
        }
    });
}

/// Runs `f` as stage `name` (one of [`STAGES`]): its fills and measures are recorded there, and
/// its whole time; the stage before is restored after.
pub(super) fn stage<R>(name: &str, f: impl FnOnce() -> R) -> R {
    let Some(k) = STAGES.iter().position(|s| *s == name) else { return f() };
    let Some(t0) = now() else { return f() };
    let before = RECORDER.with(|r| r.borrow_mut().as_mut().map(|r| std::mem::replace(&mut r.stage, k)));
    let out = f();
    RECORDER.with(|r| {
        if let Some(r) = r.borrow_mut().as_mut() {
            let ms = (r.clock)() - t0;
            if let Some(s) = r.profile.stages.get_mut(k) {
                s.total_ms += ms;
            }
            r.stage = before.unwrap_or(0);
        }
    });
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::cell::Cell;

    thread_local! { static TICK: Cell<f64> = const { Cell::new(0.0) }; }
    /// A clock that moves one millisecond per reading.
    fn tick() -> f64 {
        TICK.with(|t| {
            t.set(t.get() + 1.0);
            t.get()
        })
    }

    #[test]
    fn records_work_under_its_stage_and_nothing_without_a_clock() {
        let ((), p) = profiled(tick, || {
            stage("4b order", || {
                timed(Work::Fill, || ());
                timed(Work::Measure, || ());
                timed(Work::Measure, || ());
            });
        });
        let s = p.stage("4b order").copied().unwrap_or_default();
        assert_eq!((s.fills, s.measures), (1, 2));
        assert_eq!((s.fill_ms, s.measure_ms), (1.0, 2.0));
        assert!(s.total_ms >= 7.0, "{s:?}");
        assert_eq!(p.stage("1 fill"), Some(&StageProfile::default()));
        assert_eq!(p.parts, [PartProfile::default(); 5]);
        let ((), p) = profiled(tick, || {
            part(Part::HeldPass, || ());
            stage("5 join repair", || part(Part::HeldPass, || ()));
        });
        assert_eq!(p.parts[Part::HeldPass as usize], PartProfile { count: 2, ms: 2.0 });
        assert_eq!(p.parts[Part::Render as usize], PartProfile::default());
        // Without a clock: runs, records nothing.
        assert_eq!(stage("4b order", || timed(Work::Fill, || 3)), 3);
        assert_eq!(part(Part::Posed, || 4), 4);
    }
}
