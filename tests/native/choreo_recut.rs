//! Stating an imported clip's tempo after the fact: the clip is re-cut into 4-count segments
//! at that tempo, and nothing of the dance is lost — bars pinned (or filled) with a segment
//! of the earlier cut keep that motion, other clips' pinned bars keep theirs, the undo/redo
//! history still holds, and the earlier cut is never offered or chosen again.

use std::sync::Arc;

use odori_core::choreo::{
    bars_from_tempo, recut_clip, BarState, Choreography, RenderOptions, SegmentError, SegmentLibrary, SegmentOptions, LIBRARY_FPS,
};
use odori_core::clip::{Clip, TranslationTrack};
use odori_core::humanoid::HumanoidMap;
use odori_core::library::{builtin_clips, BUILTIN_BPM};
use odori_core::HumanoidStatus;

/// 24 built-in moves played one after another (120 counts per minute), as an "imported" clip.
fn medley() -> Clip {
    let clips = builtin_clips();
    let sk = clips[0].skeleton.clone();
    let (mut rotations, mut root) = (Vec::new(), Vec::new());
    for c in clips.iter().step_by(17).take(24) {
        let n = c.frame_count() - 1;
        rotations.extend_from_slice(&c.rotations[..n * sk.len()]);
        root.extend_from_slice(&c.translations[0].values[..n]);
    }
    Clip { name: "medley".into(), source: "medley.bvh".into(), fps: 30.0, skeleton: Arc::clone(&sk), rotations, translations: vec![TranslationTrack { joint: 0, values: root }] }
}

fn library_with_medley() -> (SegmentLibrary, usize) {
    let mut lib = SegmentLibrary::builtin();
    let clip = medley();
    let map = HumanoidMap::from_skeleton(&clip.skeleton);
    let s = lib.add_clip(&clip, &map, &HumanoidStatus::Complete, &SegmentOptions::default()).unwrap();
    // Detected from the motion (the moves' own 120 counts per minute, or an octave of it:
    // exactly when a person wants to state the tempo).
    assert!(s.tempo_detected);
    let octave = (s.tempo_bpm / BUILTIN_BPM).log2();
    assert!((octave - octave.round()).abs() < 0.05, "detected {} counts/min", s.tempo_bpm);
    (lib, s.clip)
}

fn of_clip(lib: &SegmentLibrary, clip: usize) -> Vec<usize> {
    lib.segments().iter().filter(|s| s.clip == clip && !s.retired).map(|s| s.index).collect()
}

#[test]
fn stating_a_tempo_recuts_the_clip_and_keeps_the_dance() {
    let (mut lib, clip) = library_with_medley();
    let first_cut = of_clip(&lib, clip);
    assert!(first_cut.len() >= 10);
    let builtin = 57;
    let mut doc = Choreography::new(bars_from_tempo(33.0, 120.0, 4, 0.0, |_, _| 0.5).unwrap()).unwrap();
    // Bar 2 pinned to the medley's earlier cut, bar 5 to a built-in move, bar 8 filled by
    // the engine with a medley segment (pinned, then unpinned), bar 11 pinned and undone
    // (that pin lives only in the redo history).
    doc.set(&lib, 2, first_cut[3]).unwrap();
    doc.set(&lib, 5, builtin).unwrap();
    doc.generate(&lib).unwrap();
    doc.set(&lib, 8, first_cut[6]).unwrap();
    doc.unpin(8).unwrap();
    doc.set(&lib, 11, first_cut[1]).unwrap();
    assert!(doc.undo());
    let bar2_name = lib.segments()[first_cut[3]].name.clone();
    let bar11_segment_name = lib.segments()[first_cut[1]].name.clone();
    let before = doc.render(&lib, &RenderOptions::default());
    let len_before = lib.len();
    // The bars Generate filled with the earlier cut: bar 8 (pinned, then unpinned) and any the
    // engine chose from the medley itself (which depends on the filling's terms).
    let filled: Vec<usize> = (0..doc.states().len())
        .filter(|&b| matches!(doc.states()[b], BarState::Generated { segment } if first_cut.contains(&segment)))
        .collect();
    assert!(filled.contains(&8), "bar 8 lost the medley segment it was unpinned with: {:?}", doc.states()[8]);
    let mut held: Vec<usize> = filled.iter().filter_map(|&b| doc.states()[b].segment()).chain([first_cut[3], first_cut[1]]).collect();
    held.sort_unstable();
    held.dedup();

    let report = recut_clip(&mut lib, Some(&mut doc), clip, &SegmentOptions { tempo_bpm: Some(90.0), ..Default::default() }).unwrap();

    // The new cut: 4 counts at 90 per minute are 80 frames (and the 3-count segments for bars
    // in 3, 60).
    assert!(!report.clip.tempo_detected);
    assert_eq!(report.clip.tempo_bpm, 90.0);
    let new_cut = of_clip(&lib, clip);
    assert_eq!(new_cut.len(), report.clip.segments);
    for &s in &new_cut {
        let seg = &lib.segments()[s];
        let counts = seg.counts() as f32;
        assert!(((seg.end_frame - seg.start_frame) - counts * 60.0 / 90.0 * LIBRARY_FPS).abs() <= 1.0, "{}: {} frames", seg.name, seg.end_frame - seg.start_frame);
    }
    assert_eq!(lib.len(), len_before - report.removed + report.clip.segments);
    // Kept: the segments of bar 2, of the filled bars and (in the redo history) of bar 11; all
    // others of the earlier cut went.
    assert_eq!(report.kept, held.len(), "{report:?}");
    assert_eq!(report.removed, first_cut.len() - held.len());
    assert_eq!(report.pinned_bars, vec![2]);
    assert_eq!(report.generated_bars, filled, "{report:?}");
    // Nothing of the dance changed: the same motion in every bar, the built-in pin untouched.
    assert_eq!(doc.render(&lib, &RenderOptions::default()), before);
    assert_eq!(doc.states()[5], BarState::Pinned { segment: builtin });
    let BarState::Pinned { segment: s2 } = doc.states()[2] else { panic!("bar 2 lost its pin: {:?}", doc.states()[2]) };
    assert!(lib.segments()[s2].retired);
    assert!(lib.segments()[s2].name.starts_with(&bar2_name), "{}", lib.segments()[s2].name);
    // Redo brings back the pin that lived only in the history, with its motion.
    assert!(doc.redo());
    let BarState::Pinned { segment: s11 } = doc.states()[11] else { panic!("redo lost bar 11's pin") };
    assert!(lib.segments()[s11].name.starts_with(&bar11_segment_name));

    // The earlier cut is never offered, and Generate refills bar 8 from what is available.
    let mut shown = Vec::new();
    for bar in [0, 1, 3] {
        let mut round = doc.candidates(&lib, bar).unwrap();
        for _ in 0..5 {
            shown.extend_from_slice(&round);
            round = doc.search(&lib, bar, &round[..1]).unwrap();
        }
    }
    assert!(shown.iter().all(|&s| !lib.segments()[s].retired), "a retired segment was offered");
    let table = lib.transition_table(doc.settings().fill.repeat_penalty);
    assert_eq!(table.len(), lib.len());
    assert!(!table.is_available(s2) && table.is_available(new_cut[0]));
    doc.generate(&lib).unwrap();
    for (bar, st) in doc.states().iter().enumerate() {
        match *st {
            BarState::Generated { segment } => assert!(!lib.segments()[segment].retired, "bar {bar} generated from the earlier cut"),
            BarState::Pinned { .. } => assert!([2, 5, 11].contains(&bar)),
            BarState::Empty => panic!("bar {bar} empty after Generate"),
        }
    }
    assert_eq!(doc.states()[2], BarState::Pinned { segment: s2 });

    // Back to detected beats: the pins stay, the 90-count cut goes (nothing uses it).
    let bar2 = lib.segments()[s2].name.clone();
    let back = recut_clip(&mut lib, Some(&mut doc), clip, &SegmentOptions::default()).unwrap();
    assert!(back.clip.tempo_detected);
    let BarState::Pinned { segment } = doc.states()[2] else { panic!("bar 2 lost its pin") };
    assert_eq!(lib.segments()[segment].name, bar2);
    assert!(lib.segments().iter().enumerate().all(|(i, s)| s.index == i));
}

#[test]
fn recutting_refuses_bad_requests_and_changes_nothing() {
    let (mut lib, clip) = library_with_medley();
    let (len, rev) = (lib.len(), lib.revision());
    let names: Vec<String> = lib.segments().iter().map(|s| s.name.clone()).collect();
    let opts = |bpm| SegmentOptions { tempo_bpm: Some(bpm), ..Default::default() };
    assert!(matches!(recut_clip(&mut lib, None, clip, &opts(500.0)), Err(SegmentError::BadTempo { .. })));
    assert!(matches!(recut_clip(&mut lib, None, clip, &opts(f32::NAN)), Err(SegmentError::BadTempo { .. })));
    assert!(matches!(recut_clip(&mut lib, None, 0, &opts(100.0)), Err(SegmentError::BuiltinClip { .. })));
    assert!(matches!(recut_clip(&mut lib, None, 9999, &opts(100.0)), Err(SegmentError::NoSuchClip { clip: 9999, .. })));
    // 30 counts per minute over a 48 s clip: 24 counts, fine; the clip holds no 4 counts at a
    // tempo so slow only when it is shorter: a 4 s piece.
    let mut short = medley();
    short.rotations.truncate(120 * short.skeleton.len());
    short.translations[0].values.truncate(120);
    let map = HumanoidMap::from_skeleton(&short.skeleton);
    let s = lib.add_clip(&short, &map, &HumanoidStatus::Complete, &opts(120.0)).unwrap();
    let (len2, rev2) = (lib.len(), lib.revision());
    let e = recut_clip(&mut lib, None, s.clip, &opts(40.0)).unwrap_err();
    assert!(matches!(e, SegmentError::TooShort { .. }), "{e:?}");
    assert!(e.to_string().contains("4 counts"), "{e}");
    assert_eq!((lib.len(), lib.revision()), (len2, rev2));
    assert_eq!(&lib.segments()[..len].iter().map(|s| s.name.clone()).collect::<Vec<_>>(), &names);
    assert!(rev2 > rev);
}
