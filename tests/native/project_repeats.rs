//! Repeats marked by hand through the project (issue 26 item 2; `Project::mark_repeat`,
//! `Project::remove_repeat`, `Project::repeats`, `.odori` schema 5). On the demo song (whose
//! second chorus the analysis finds as a repeat) and on a real song of ../shared/data/music
//! (where it finds none), with the built-in library:
//! - a range marked as repeating an earlier one takes that range's moves by key at the next
//!   Generate, and the bars' notes say "repeats bar N (marked)"; the control, the same project's
//!   Generate before the mark, does not repeat them (so the test can fail); the mark is one undo
//!   step, survives save and open, and undo takes it away;
//! - removing the found repeat frees its bars: Generate no longer gives them the first chorus's
//!   moves (the control, with the repeat, does), and undo brings the repeat back;
//! - a bad range (empty, out of the song, unequal lengths, overlapping, not earlier) and removing
//!   a bar that repeats nothing are typed errors naming the bars, with the project unchanged.

#[path = "music_audio.rs"]
mod music_audio;

use odori_core::choreo::{bar_notes, MoveNote};
use odori_core::music::demo_song::{demo_song_with, DemoSongOptions};
use odori_core::music::{envelope, AnalysisOptions, RmsEnvelope};
use odori_core::project::{self, BarRange, MoveKey, Project, ProjectError, RepeatError, RepeatRun};

fn project_on(env: &RmsEnvelope, name: &str) -> Project {
    let mut p = Project::new();
    p.set_song(name, None, env, AnalysisOptions::default()).unwrap_or_else(|e| panic!("{name}: {e}"));
    p
}

fn demo_project() -> Project {
    let song = demo_song_with(22050.0, &DemoSongOptions::default()).expect("demo song");
    project_on(&envelope(&[&song.samples], 22050.0).expect("envelope"), "demo")
}

fn keys(p: &Project) -> Vec<Option<MoveKey>> {
    p.doc().dance.bars.iter().map(|b| b.r#move.clone()).collect()
}

/// The bars' notes as the page's `barNotes` gives them (without the readout's flags).
fn notes(p: &mut Project) -> Vec<MoveNote> {
    let bars = p.song_bars().expect("bars");
    let choices: Vec<Option<usize>> = p.dance_view().expect("view").iter().map(|v| v.state.segment()).collect();
    let mut notes = bar_notes(p.segment_library(), &bars, &choices, &[]);
    project::repeats::mark_notes(&mut notes, &p.repeats().expect("repeats"));
    notes
}

/// The first `k`-bar range from the end that, like bars `0..k`, lies outside every repeat the
/// analysis found.
fn free_range(p: &mut Project, k: usize) -> BarRange {
    let n = p.song_bars().expect("bars").len();
    let found = p.repeat_of_bars().expect("repeats");
    let free = |a: usize| (a..a + k).all(|t| found[t].is_none() && !found.iter().any(|r| *r == Some(t)));
    assert!(free(0), "bars 0..{k} are in a found repeat: {found:?}");
    let first_bar = (k..=n - k).rev().find(|&a| free(a)).expect("a free range");
    BarRange { first_bar, bars: k }
}

/// Marks `range` as repeating bars from 0 on `p` and checks everything the module doc lists
/// for a marked repeat. Returns how many of its bars the control already repeated.
fn check_marked(label: &str, p: &mut Project, range: BarRange) -> usize {
    let of = BarRange { first_bar: 0, bars: range.bars };
    // The control: Generate before the mark.
    p.generate().unwrap_or_else(|e| panic!("{label}: {e}"));
    let before = keys(p);
    let same_before = (0..range.bars).filter(|&i| before[range.first_bar + i] == before[i]).count();
    let steps = p.undo_history().len();
    p.mark_repeat(range, of).unwrap_or_else(|e| panic!("{label}: {e}"));
    assert_eq!(p.undo_history().len(), steps + 1, "{label}: marking is one undo step");
    assert!(p.repeat_runs().expect("runs").contains(&RepeatRun { first_bar: range.first_bar, bars: range.bars, of_bar: 0, marked: true }), "{label}: {:?}", p.repeat_runs());
    p.generate().unwrap_or_else(|e| panic!("{label}: {e}"));
    let after = keys(p);
    for i in 0..range.bars {
        assert_eq!(after[range.first_bar + i], after[i], "{label}: bar {} is marked as repeating bar {i}", range.first_bar + i);
    }
    let notes = notes(p);
    for i in 0..range.bars {
        let words = notes[range.first_bar + i].words();
        assert!(words.contains(&format!("repeats bar {} (marked)", i + 1)), "{label}: bar {}'s note: {words:?}", range.first_bar + i);
    }
    // Kept in the file (schema 5): the reopened project has the marks and repeats the same.
    let bytes = project::save(p).expect("save");
    let mut again = project::open(&bytes).expect("open").project;
    assert_eq!(again.doc().dance.repeats, p.doc().dance.repeats);
    assert_eq!(again.repeat_runs().expect("runs"), p.repeat_runs().expect("runs"));
    // Undo the Generate and the mark: no marked repeat is left.
    assert!(p.undo() && p.undo());
    assert!(p.doc().dance.repeats.is_empty());
    assert!(p.repeat_runs().expect("runs").iter().all(|r| !r.marked));
    println!("{label}: bars {}..{} marked as repeating bars 0..{}: the same move in all {} (the control: {same_before})", range.first_bar, range.first_bar + range.bars, range.bars, range.bars);
    same_before
}

#[test]
fn a_marked_repeat_takes_the_earlier_bars_moves_and_is_kept() {
    let mut p = demo_project();
    let range = free_range(&mut p, 4);
    let same = check_marked("demo song", &mut p, range);
    assert!(same < range.bars, "the control already repeats every bar: the test shows nothing");
}

#[test]
fn a_marked_repeat_on_a_real_song() {
    let rel = music_audio::FULL_TRACKS[0];
    let mut p = project_on(&music_audio::decode_envelope(rel), rel);
    let n = p.song_bars().expect("bars").len();
    assert!(n >= 16, "{rel}: {n} bars");
    let range = free_range(&mut p, 8);
    let same = check_marked(rel, &mut p, range);
    assert!(same < range.bars, "{rel}: the control already repeats every bar: the test shows nothing");
}

#[test]
fn removing_a_found_repeat_frees_its_bars() {
    let mut p = demo_project();
    let found = p.repeat_runs().expect("runs");
    let run = *found.first().expect("the demo song's second chorus repeats the first");
    assert!(!run.marked);
    // The control: with the repeat, Generate repeats the first chorus bar for bar.
    p.generate().expect("generate");
    let with = keys(&p);
    assert!((0..run.bars).all(|i| with[run.first_bar + i] == with[run.of_bar + i]));
    let steps = p.undo_history().len();
    let removed = p.remove_repeat(run.first_bar + run.bars / 2).expect("remove");
    assert_eq!(removed, run, "the whole run is removed");
    assert_eq!(p.undo_history().len(), steps + 1, "removing is one undo step");
    let repeats = p.repeats().expect("repeats");
    assert!(repeats[run.first_bar..run.first_bar + run.bars].iter().all(Option::is_none));
    p.generate().expect("generate");
    let without = keys(&p);
    let same = (0..run.bars).filter(|&i| without[run.first_bar + i] == without[run.of_bar + i]).count();
    println!("demo song: found repeat of bars {}..{} removed: {same} of {} bars still hold the first chorus's move", run.first_bar, run.first_bar + run.bars, run.bars);
    assert!(same < run.bars, "the bars still repeat the first chorus after the repeat was removed");
    assert!(notes(&mut p)[run.first_bar..run.first_bar + run.bars].iter().all(|n| n.repeats_bar.is_none()));
    // Undo the Generate and the removal: the analysis's repeat is back.
    assert!(p.undo() && p.undo());
    assert_eq!(p.repeat_runs().expect("runs"), found);
    // Nothing to remove where nothing repeats: a typed error, nothing changed.
    let doc = p.doc().clone();
    let e = p.remove_repeat(0).expect_err("bar 0 repeats nothing");
    assert_eq!(e.kind(), "not-found");
    assert!(matches!(e, ProjectError::Repeat(RepeatError::NotARepeat { bar: 0, .. })), "{e:?}");
    assert_eq!(p.doc(), &doc);
}

#[test]
fn a_bad_range_is_refused_with_a_typed_error_and_nothing_changed() {
    let mut p = demo_project();
    let n = p.song_bars().expect("bars").len();
    let steps = p.undo_history().len();
    let doc = p.doc().clone();
    let r = |first_bar, bars| BarRange { first_bar, bars };
    let cases: [(BarRange, BarRange, &str); 6] = [
        (r(8, 0), r(0, 0), "at least one bar"),
        (r(n - 2, 4), r(0, 4), "out of the song"),
        (r(8, 4), r(n, 4), "out of the song"),
        (r(8, 4), r(0, 3), "length"),
        (r(4, 4), r(2, 4), "overlap"),
        (r(0, 4), r(8, 4), "later"),
    ];
    for (range, of, words) in cases {
        let e = p.mark_repeat(range, of).expect_err("a bad range");
        assert_eq!(e.kind(), "bad-repeat", "{e}");
        assert!(e.to_string().contains(words), "{range:?} of {of:?}: {e}");
        assert_eq!(p.doc(), &doc, "{range:?} of {of:?} changed the project");
        assert_eq!(p.undo_history().len(), steps);
    }
    // Without a song there is nothing to mark.
    let mut empty = Project::new();
    assert_eq!(empty.mark_repeat(r(4, 4), r(0, 4)), Err(ProjectError::NoSong));
}
