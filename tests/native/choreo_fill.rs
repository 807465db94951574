//! Filling (spec §G) and the choreography document: optimality against brute force, join
//! quality on a 32-bar song against random choices, bad input, determinism, undo/redo.

use odori_core::bars::Bar;
use odori_core::choreo::render::join_frames;
use odori_core::choreo::{
    bars_from_tempo, fill, path_cost, speed_jumps, BarState, ChoreoError, Choreography, FillWeights, GridError, Layer, RenderOptions, SegmentError,
    SegmentLibrary, SegmentOptions, TransitionTable,
};
use odori_core::humanoid::HumanoidMap;

/// A small deterministic generator (SplitMix64).
struct Rng(u64);
impl Rng {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    fn f32(&mut self) -> f32 {
        (self.next() >> 40) as f32 / (1u64 << 24) as f32
    }
    fn below(&mut self, n: usize) -> usize {
        (self.next() % n as u64) as usize
    }
}

fn brute_force(table: &TransitionTable, layers: &[Layer], inten: &[f32], w: &FillWeights) -> f32 {
    let m = table.len();
    let open: Vec<usize> = layers.iter().enumerate().filter(|(_, l)| matches!(l, Layer::Open { .. })).map(|(i, _)| i).collect();
    let mut path: Vec<usize> = layers.iter().map(|l| if let Layer::Fixed { segment } = l { *segment } else { 0 }).collect();
    let mut best = f32::INFINITY;
    let total = m.pow(open.len() as u32);
    for code in 0..total {
        let mut c = code;
        for &i in &open {
            path[i] = c % m;
            c /= m;
        }
        // The objective written out independently of the library code.
        let mut cost = 0.0;
        for (t, l) in layers.iter().enumerate() {
            if let Layer::Open { intensity } = l {
                cost += w.music_weight * (intensity - inten[path[t]]).abs();
            }
            if t > 0 {
                cost += table.cost(path[t - 1], path[t]);
            }
        }
        best = best.min(cost);
    }
    best
}

#[test]
fn filling_equals_brute_force_on_small_random_instances() {
    let mut rng = Rng(7);
    for case in 0..60 {
        let m = 2 + rng.below(5);
        let bars = 1 + rng.below(6);
        let costs: Vec<f32> = (0..m * m).map(|_| 0.2 + 5.0 * rng.f32()).collect();
        let table = TransitionTable::from_costs(m, costs);
        let inten: Vec<f32> = (0..m).map(|_| rng.f32()).collect();
        let layers: Vec<Layer> = (0..bars)
            .map(|_| if rng.f32() < 0.3 { Layer::Fixed { segment: rng.below(m) } } else { Layer::Open { intensity: rng.f32() } })
            .collect();
        let w = FillWeights { music_weight: 2.0 * rng.f32(), repeat_penalty: 3.0 * rng.f32(), repeat_window: 1, ..FillWeights::default() };
        let (path, cost) = fill(&table, &layers, &inten, &w).unwrap();
        let brute = brute_force(&table, &layers, &inten, &w);
        assert!((cost - brute).abs() < 1e-4, "case {case}: fill {cost} vs brute force {brute}");
        assert!((path_cost(&table, &layers, &inten, &w, &path) - cost).abs() < 1e-4);
        for (l, s) in layers.iter().zip(&path) {
            if let Layer::Fixed { segment } = l {
                assert_eq!(s, segment, "case {case}: a pinned bar changed");
            }
        }
    }
}

#[test]
fn filling_equals_brute_force_on_a_real_library_subset() {
    // Spec §G costs between 6 built-in segments, repetition penalty included.
    let lib = SegmentLibrary::builtin();
    let full = lib.transition_table(3.0);
    let pick = [3usize, 41, 88, 150, 233, 377];
    let costs: Vec<f32> = pick.iter().flat_map(|&a| pick.iter().map(move |&b| (a, b))).map(|(a, b)| full.cost(a, b)).collect();
    let table = TransitionTable::from_costs(pick.len(), costs);
    let inten: Vec<f32> = pick.iter().map(|&s| lib.segments()[s].intensity01).collect();
    let layers = vec![
        Layer::Open { intensity: 0.2 },
        Layer::Fixed { segment: 2 },
        Layer::Open { intensity: 0.9 },
        Layer::Open { intensity: 0.5 },
        Layer::Open { intensity: 0.1 },
        Layer::Fixed { segment: 4 },
    ];
    // Exact objective (window 1).
    let w = FillWeights { repeat_window: 1, ..FillWeights::default() };
    let (_, cost) = fill(&table, &layers, &inten, &w).unwrap();
    let brute = brute_force(&table, &layers, &inten, &w);
    assert!((cost - brute).abs() < 1e-4, "fill {cost} vs brute force {brute}");
}

/// Mean and 95th percentile.
fn stats(v: &[f32]) -> (f32, f32) {
    let mut s = v.to_vec();
    s.sort_by(f32::total_cmp);
    let mean = s.iter().sum::<f32>() / s.len().max(1) as f32;
    let p95 = s.get(((s.len() as f32 * 0.95) as usize).min(s.len().saturating_sub(1))).copied().unwrap_or(0.0);
    (mean, p95)
}

/// Joint-speed jumps at the joins and inside segments of a rendering.
pub fn join_report(lib: &SegmentLibrary, bars: &[Bar], choices: &[Option<usize>], join: usize) -> ((f32, f32), (f32, f32)) {
    let opts = RenderOptions { fps: 60.0, join_frames: join, ..RenderOptions::default() };
    let clip = odori_core::choreo::render(lib, bars, choices, &opts);
    let jumps = speed_jumps(&clip);
    let joins = join_frames(bars, opts.fps);
    let mut at = Vec::new();
    let mut inside = Vec::new();
    let start = (bars[0].start_secs * opts.fps).ceil() as usize + 1;
    let end = (bars[bars.len() - 1].end_secs * opts.fps) as usize - 1;
    for f in start..end.min(jumps.len()) {
        // A join's discontinuity shows at its first frame or the one before.
        if joins.iter().any(|&j| f + 1 >= j && f <= j + 1) {
            if joins.contains(&f) {
                at.push(jumps[f - 1].max(jumps[f]).max(jumps[f + 1]));
            }
        } else if joins.iter().all(|&j| f + 8 < j || f > j + 8) {
            inside.push(jumps[f]);
        }
    }
    (stats(&at), stats(&inside))
}

fn song(bars: usize) -> Vec<Bar> {
    // 120 BPM, intensity rising and falling over the song.
    bars_from_tempo(bars as f32 * 2.0 + 0.3, 120.0, 4, 0.0, |s, _| 0.5 + 0.45 * (s / 16.0).sin()).unwrap()
}

#[test]
fn generated_joins_are_smoother_than_random_choices() {
    let lib = SegmentLibrary::builtin();
    let bars = song(32);
    let mut doc = Choreography::new(bars.clone()).unwrap();
    // The transition cost's own effect: without the beat term (checked with it below).
    doc.set_beat_weight(0.0).unwrap();
    let pins = [(0usize, 5usize), (8, 120), (16, 260), (24, 333)];
    for (bar, seg) in pins {
        doc.set(&lib, bar, seg).unwrap();
    }
    let report = doc.generate(&lib).unwrap();
    assert_eq!(report.filled, 28);
    let generated = doc.segments();
    let mut distinct: Vec<usize> = generated.iter().flatten().copied().collect();
    distinct.sort();
    distinct.dedup();
    let repeats_within_4 = (0..generated.len()).filter(|&i| (1..=4).any(|d| i >= d && generated[i] == generated[i - d])).count();
    println!("generated: {} distinct segments in 32 bars; bars repeating a segment used in the 4 bars before: {repeats_within_4}", distinct.len());
    println!("  {:?}", generated.iter().map(|s| s.unwrap_or(usize::MAX)).collect::<Vec<_>>());
    let open_repeats = (0..generated.len()).filter(|&i| !pins.iter().any(|p| p.0 == i) && (2..=4).any(|d| i >= d && generated[i] == generated[i - d])).count();
    assert_eq!(open_repeats, 0, "an open bar repeats a segment from 2..4 bars before");
    let mut rng = Rng(2026);
    let random: Vec<Option<usize>> =
        (0..bars.len()).map(|i| pins.iter().find(|p| p.0 == i).map(|p| p.1).or(Some(rng.below(lib.len())))).collect();
    println!("Join quality, 32 bars at 120 BPM, built-in library ({} segments), 4 pinned bars; joint-speed jump in m/s:", lib.len());
    let mut results = Vec::new();
    for (name, choices) in [("generated", &generated), ("random", &random)] {
        for join in [0, 5] {
            let ((am, ap), (im, ip)) = join_report(&lib, &bars, choices, join);
            println!(
                "  {name:9} joins {}: at joins mean {am:.3} p95 {ap:.3} | inside segments mean {im:.3} p95 {ip:.3}",
                if join == 0 { "off (raw cuts)" } else { "on (5+5 Hermite)" }
            );
            results.push((am, ap));
        }
    }
    let (gen_raw, rand_raw, gen_joined, rand_joined) = (results[0], results[2], results[1], results[3]);
    assert!(gen_raw.0 < 0.6 * rand_raw.0, "generated mean jump {} not clearly below random {}", gen_raw.0, rand_raw.0);
    assert!(gen_raw.1 < 0.7 * rand_raw.1, "generated p95 jump {} not clearly below random {}", gen_raw.1, rand_raw.1);
    assert!(gen_joined.0 < rand_joined.0);
    assert!(gen_joined.0 <= gen_raw.0 + 1e-3, "the Hermite joins must not make joins rougher");
    // With the default beat term (spec §G + §J: dances that turn on the beat), the joins the
    // person sees (Hermite on) stay about as smooth as without it and clearly smoother than random.
    let mut beat = Choreography::new(bars.clone()).unwrap();
    for (bar, seg) in pins {
        beat.set(&lib, bar, seg).unwrap();
    }
    beat.generate(&lib).unwrap();
    let ((bm, bp), _) = join_report(&lib, &bars, &beat.segments(), 5);
    println!("  with the beat term, joins on: at joins mean {bm:.3} p95 {bp:.3}");
    assert!(bm <= 1.25 * gen_joined.0 && bp <= 1.25 * gen_joined.1, "beat term made joins rougher: mean {bm} p95 {bp} vs {gen_joined:?}");
    assert!(bm < 0.75 * rand_joined.0, "with the beat term, joins ({bm}) not clearly smoother than random ({})", rand_joined.0);
    // Pinned bars unchanged.
    for (bar, seg) in pins {
        assert_eq!(doc.states()[bar], BarState::Pinned { segment: seg });
    }
}

#[test]
fn table_progress_reports_and_cancels() {
    let lib = SegmentLibrary::builtin();
    let mut seen = Vec::new();
    let t = lib.transition_table_with_progress(1.5, &mut |p| {
        seen.push(p);
        true
    });
    assert!(t.is_some());
    assert!(seen.windows(2).all(|w| w[0] < w[1]) && (seen.last().copied().unwrap() - 1.0).abs() < 1e-6, "{seen:?}");
    let mut calls = 0;
    let cancelled = lib.transition_table_with_progress(2.5, &mut |_| {
        calls += 1;
        false
    });
    assert!(cancelled.is_none());
    assert_eq!(calls, 1);
    // The cached table is the completed one.
    assert_eq!(lib.transition_table(1.5).repeat_penalty(), 1.5);
}

#[test]
fn bad_input_gives_clear_errors() {
    // A song shorter than one bar.
    let e = bars_from_tempo(1.2, 120.0, 4, 0.0, |_, _| 0.5).unwrap_err();
    assert!(matches!(e, GridError::ShorterThanABar { .. }));
    println!("song shorter than a bar: {e}");
    let e = Choreography::new(Vec::new()).unwrap_err();
    assert_eq!(e, ChoreoError::NoBars);
    println!("no bars: {e}");
    // A library with no humanoid clip: the Fox is refused; generating from the empty library
    // says so.
    let fox = support_fox();
    let mut lib = SegmentLibrary::new();
    for c in &fox.clips {
        let e = lib.add_clip(c, &fox.humanoid, &fox.status, &SegmentOptions::default()).unwrap_err();
        assert!(matches!(e, SegmentError::NotHumanoid { .. }));
        println!("non-humanoid clip: {e}");
    }
    assert!(lib.is_empty());
    let mut doc = Choreography::new(song(4)).unwrap();
    let e = doc.generate(&lib).unwrap_err();
    assert_eq!(e, ChoreoError::EmptyLibrary);
    println!("empty library: {e}");
    assert_eq!(doc.candidates(&lib, 0).unwrap_err(), ChoreoError::EmptyLibrary);
    // A clip shorter than 4 counts.
    let demo = odori_core::builtin::demo_clip();
    let short = demo.slice(0, 50, "short");
    let e = lib.add_clip(&short, &HumanoidMap::from_skeleton(&short.skeleton), &odori_core::HumanoidStatus::Complete, &SegmentOptions { tempo_bpm: Some(120.0), ..Default::default() }).unwrap_err();
    assert!(matches!(e, SegmentError::TooShort { .. }), "{e:?}");
    println!("short clip: {e}");
    let e = lib.add_clip(&short, &HumanoidMap::from_skeleton(&short.skeleton), &odori_core::HumanoidStatus::Complete, &SegmentOptions::default()).unwrap_err();
    assert!(matches!(e, SegmentError::TooShort { .. }), "{e:?}");
    // Every bar pinned: Generate changes nothing and says so.
    let lib = SegmentLibrary::builtin();
    let mut doc = Choreography::new(song(3)).unwrap();
    for b in 0..3 {
        doc.set(&lib, b, 10 + b).unwrap();
    }
    let before = doc.clone();
    let r = doc.generate(&lib).unwrap();
    assert_eq!(r.filled, 0);
    assert_eq!(doc, before);
    // Out-of-range bars and segments.
    assert!(matches!(doc.set(&lib, 9, 0), Err(ChoreoError::NoSuchBar { .. })));
    assert!(matches!(doc.set(&lib, 0, 99_999), Err(ChoreoError::NoSuchSegment { .. })));
    assert!(matches!(doc.search(&lib, 1, &[]), Err(ChoreoError::NoSearch { .. })));
    let round = doc.candidates(&lib, 1).unwrap();
    let not_shown = (0..lib.len()).find(|s| !round.contains(s)).unwrap();
    assert!(matches!(doc.search(&lib, 1, &[not_shown]), Err(ChoreoError::NotACandidate { .. })));
    assert!(matches!(doc.set_rho(1.5), Err(ChoreoError::BadSetting { .. })));
    let e = Choreography::new(vec![Bar { index: 0, start_secs: 2.0, end_secs: 1.0, intensity: 0.5, beats: 4 }]).unwrap_err();
    assert!(matches!(e, ChoreoError::BadBar { .. }));
}

fn support_fox() -> odori_core::Imported {
    let bytes = odori_tests::read("gltf/Fox.glb");
    odori_core::import::import_bytes("Fox.glb", &bytes, &odori_core::ImportOptions::default()).unwrap()
}

/// A session of commands: the UI's flow (select, Search twice, Set, Generate, edit more).
fn session(lib: &SegmentLibrary) -> Choreography {
    let mut doc = Choreography::new(song(12)).unwrap();
    let round = doc.candidates(lib, 3).unwrap();
    let round = doc.search(lib, 3, &[round[1], round[4]]).unwrap();
    let round = doc.search(lib, 3, &[round[0]]).unwrap();
    doc.set(lib, 3, round[2]).unwrap();
    doc.set(lib, 7, 42).unwrap();
    doc.generate(lib).unwrap();
    doc
}

#[test]
fn same_inputs_give_the_same_dance() {
    let a = SegmentLibrary::builtin();
    let b = SegmentLibrary::builtin();
    assert_eq!(a.segments(), b.segments());
    let da = session(&a);
    let db = session(&b);
    assert_eq!(da, db);
    let ca = da.render(&a, &RenderOptions::default());
    let cb = db.render(&b, &RenderOptions::default());
    assert_eq!(ca, cb);
    // Re-generating changes nothing the person pinned, and is itself deterministic.
    let mut dc = da.clone();
    dc.generate(&a).unwrap();
    assert_eq!(dc.segments(), da.segments());
}

#[test]
fn undo_and_redo_walk_every_edit() {
    let lib = SegmentLibrary::builtin();
    let mut doc = Choreography::new(song(8)).unwrap();
    let mut history = vec![doc.clone()];
    // Looking at a bar's candidates is not an edit: no undo step.
    let round = doc.candidates(&lib, 2).unwrap();
    assert!(!doc.can_undo(), "opening a bar's candidates made an undo step");
    history[0] = doc.clone();
    doc.search(&lib, 2, &[round[0]]).unwrap();
    history.push(doc.clone());
    let pick = doc.view()[2].candidates[3];
    doc.set(&lib, 2, pick).unwrap();
    history.push(doc.clone());
    doc.generate(&lib).unwrap();
    history.push(doc.clone());
    doc.set_rho(0.8).unwrap();
    history.push(doc.clone());
    doc.set_repeat_window(6).unwrap();
    history.push(doc.clone());
    doc.generate(&lib).unwrap();
    history.push(doc.clone());
    doc.unpin(2).unwrap();
    history.push(doc.clone());
    doc.reset_search(2).unwrap();
    history.push(doc.clone());
    doc.clear(5).unwrap();
    history.push(doc.clone());
    // A corrected grid: 10 bars at 126 BPM; bar 2 keeps its search, new bars start empty.
    doc.set_bars(bars_from_tempo(19.5, 126.0, 4, 0.1, |_, _| 0.4).unwrap()).unwrap();
    assert_eq!(doc.bars().len(), 10);
    assert_eq!(doc.states()[9], BarState::Empty);
    history.push(doc.clone());
    let same = |a: &Choreography, b: &Choreography| a.states() == b.states() && a.view() == b.view() && a.settings() == b.settings() && a.bars() == b.bars();
    for k in (0..history.len() - 1).rev() {
        assert!(doc.undo());
        assert!(same(&doc, &history[k]), "undo to step {k}");
    }
    assert!(!doc.undo());
    for (k, h) in history.iter().enumerate().skip(1) {
        assert!(doc.redo());
        assert!(same(&doc, h), "redo to step {k}");
    }
    assert!(!doc.redo());
    // The same grid again (the song panel re-sends it after any correction) is no edit either.
    let steps = { let mut d = doc.clone(); let mut n = 0; while d.undo() { n += 1; } n };
    doc.set_bars(doc.bars().to_vec()).unwrap();
    let after = { let mut d = doc.clone(); let mut n = 0; while d.undo() { n += 1; } n };
    assert_eq!(after, steps, "an unchanged grid made an undo step");
    // A new edit after undo drops the redo branch.
    doc.undo();
    doc.set(&lib, 0, 1).unwrap();
    assert!(!doc.can_redo());
}

#[test]
fn rendered_dance_follows_the_bars() {
    let lib = SegmentLibrary::builtin();
    let doc = session(&lib);
    let clip = doc.render(&lib, &RenderOptions::default());
    clip.validate().unwrap();
    let last = doc.bars().last().unwrap().end_secs;
    assert!((clip.duration_secs() - last).abs() < 0.05, "{} vs {last}", clip.duration_secs());
    // The figure moves in every bar and stays on the floor.
    for b in doc.bars() {
        let f0 = (b.start_secs * clip.fps) as usize + 2;
        let f1 = (b.end_secs * clip.fps) as usize - 2;
        let mut moved = 0.0;
        for f in f0..f1 {
            let p = clip.world_positions(f);
            let q = clip.world_positions(f + 1);
            moved += p.iter().zip(&q).map(|(a, b)| (*a - *b).length()).sum::<f32>();
            let low = p.iter().map(|v| v.y).fold(f32::MAX, f32::min);
            assert!(low > -0.05 && low < 0.4, "bar {}: lowest point {low}", b.index);
        }
        assert!(moved > 0.5, "bar {} barely moves ({moved})", b.index);
    }
    // The pinned bar plays its segment: frame-by-frame the same body pose as the segment alone.
    let pinned = doc.bars()[7];
    let seg = doc.states()[7].segment().unwrap();
    let alone = odori_core::choreo::segment_clip(&lib, seg, pinned.duration_secs(), clip.fps).unwrap();
    let rel = |c: &odori_core::Clip, f: usize| {
        let p = c.world_positions(f);
        p.iter().map(|v| *v - p[0]).collect::<Vec<_>>()
    };
    let mid = (pinned.duration_secs() * clip.fps / 2.0) as usize;
    let a = rel(&clip, (pinned.start_secs * clip.fps) as usize + mid);
    let b = rel(&alone, mid);
    let err: f32 = a.iter().zip(&b).map(|(x, y)| (x.y - y.y).abs()).sum::<f32>() / a.len() as f32;
    assert!(err < 0.02, "pinned bar's pose differs from its segment by {err}");
}
