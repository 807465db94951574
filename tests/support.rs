//! Helpers shared by the integration tests: where the real data lives, and reading it.

use std::path::PathBuf;

/// `../shared/data` relative to the repository root. Panics with a clear message when it is
/// absent: real-data tests must not pass silently without their data.
pub fn data_dir() -> PathBuf {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("..");
    let dir = std::env::var_os("ODORI_DATA").map(PathBuf::from).unwrap_or_else(|| root.join("../shared/data"));
    if !dir.is_dir() {
        panic!(
            "real-data test: {} is missing. These tests read the shared real data (mocap, glTF, music) \
             that sits beside the repository as ../shared/data; set ODORI_DATA to point elsewhere.",
            dir.display()
        );
    }
    dir
}

/// Reads a file under the data directory.
pub fn read(rel: &str) -> Vec<u8> {
    let p = data_dir().join(rel);
    std::fs::read(&p).unwrap_or_else(|e| panic!("cannot read {}: {e}", p.display()))
}

/// Every file under a folder of the data directory (`rel`) whose name passes `keep`, as a
/// dropped folder gives them: (its name relative to the folder, `/`-separated; its bytes),
/// sorted by name. Panics naming the folder when it is missing.
pub fn data_folder(rel: &str, keep: impl Fn(&str) -> bool) -> Vec<(String, Vec<u8>)> {
    let dir = data_dir().join(rel);
    let mut out = Vec::new();
    let mut stack = vec![dir.clone()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap_or_else(|e| panic!("{}: {e} (the test data is missing)", d.display())).flatten() {
            let p = e.path();
            if p.is_dir() {
                stack.push(p);
            } else {
                let name = p.strip_prefix(&dir).map(|r| r.to_string_lossy().replace('\\', "/")).unwrap_or_default();
                if keep(&name) {
                    out.push((name, std::fs::read(&p).unwrap_or_else(|e| panic!("cannot read {}: {e}", p.display()))));
                }
            }
        }
    }
    out.sort();
    out
}

/// The shortest of `runs` timings of `f`, milliseconds: what the benchmarks print.
pub fn best_ms(runs: usize, mut f: impl FnMut()) -> f64 {
    (0..runs)
        .map(|_| {
            let t = std::time::Instant::now();
            f();
            t.elapsed().as_secs_f64() * 1e3
        })
        .fold(f64::INFINITY, f64::min)
}

/// Every BVH file under `mocap/`, sorted, as paths relative to the data directory.
pub fn all_bvh() -> Vec<String> {
    let base = data_dir();
    let mut out = Vec::new();
    let mut stack = vec![base.join("mocap")];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap_or_else(|e| panic!("cannot list {}: {e}", d.display())).flatten() {
            let p = e.path();
            if p.is_dir() {
                stack.push(p);
            } else if p.extension().is_some_and(|x| x == "bvh") {
                out.push(p.strip_prefix(&base).unwrap().to_string_lossy().replace('\\', "/"));
            }
        }
    }
    out.sort();
    out
}

/// The frame rate a real file should be played at: the CMU salsa headers say 120 fps but the
/// recordings are 60 fps (see ../shared/data/mocap/SOURCE-cmu-acrnn.txt).
pub fn fps_override_for(rel: &str) -> Option<f32> {
    rel.contains("cmu-salsa").then_some(60.0)
}

/// The person's files, in the order they are added: every BVH take in ../shared/data/mocap
/// but the martial-arts takes and modern dance's 005_01 (sorted, as [`all_bvh`] lists them),
/// then RobotExpressive's glTF (its `Dance` clip). (The tests' person library,
/// `tests/native/person_common.rs`, and the Generate benches' library of real files.)
pub fn person_files() -> Vec<String> {
    let mut files: Vec<String> = all_bvh().into_iter().filter(|r| is_person_bvh(r)).collect();
    files.push("gltf/RobotExpressive.glb".into());
    files
}

/// Whether a BVH take of ../shared/data/mocap (`rel`, relative to the data directory) is one of
/// the person's files ([`person_files`]): a dance, not a martial-arts take or 005_01's walk.
pub fn is_person_bvh(rel: &str) -> bool {
    !rel.contains("cmu-martial") && !rel.ends_with("005_01.bvh")
}

/// The two VMD dances of ../shared/data/mmd/motion, relative to the data directory.
pub const VMD_DANCES: [&str; 2] = ["mmd/motion/tokino_kakera.vmd", "mmd/motion/wavefile_v2.vmd"];

/// The library of real files the Generate benches time beside the medleys (natively
/// tests/bench/choreo_generate.rs, in wasm tests/wasm_bench, which passes the files' bytes in):
/// the built-in moves, then `files` ((path relative to the data directory, bytes): the person's
/// files and [`VMD_DANCES`]) each imported as the app imports it (a glTF gives its `Dance` clip)
/// and cut at every count (`SegmentOptions::hop_counts` 1); a clip the segmenter refuses is left
/// out, as the app leaves it. Panics naming a file that does not import.
pub fn real_file_library(files: &[(String, Vec<u8>)]) -> odori_core::choreo::SegmentLibrary {
    use odori_core::import::{import_bytes, ImportOptions};
    let mut lib = odori_core::choreo::SegmentLibrary::builtin();
    let opts = odori_core::choreo::SegmentOptions { hop_counts: 1, ..Default::default() };
    for (rel, bytes) in files {
        let io = ImportOptions { fps_override: fps_override_for(rel), ..Default::default() };
        let imp = import_bytes(rel, bytes, &io).unwrap_or_else(|e| panic!("{rel}: {e}"));
        for clip in imp.clips.iter().filter(|c| !rel.ends_with(".glb") || c.name == "Dance") {
            let _ = lib.add_clip(clip, &imp.humanoid, &imp.status, &opts);
        }
    }
    lib
}

/// [`real_file_library`] of the person's files and [`VMD_DANCES`], read from ../shared/data.
pub fn real_files_library() -> odori_core::choreo::SegmentLibrary {
    let files: Vec<(String, Vec<u8>)> = person_files().into_iter().chain(VMD_DANCES.iter().map(|r| r.to_string())).map(|r| {
        let b = read(&r);
        (r, b)
    }).collect();
    real_file_library(&files)
}

/// The ≥ 2,000-segment library the choreography benches time both natively and in wasm
/// (tests/bench/choreo.rs, tests/wasm_bench), built without file access: the built-in moves
/// plus every built-in move (558 clips of one bar each, in 4 or in 3) danced one after another
/// as one clip ([`medley_library`]), cut at every count at its stated 120 counts per minute.
pub fn builtin_medley_library() -> odori_core::choreo::SegmentLibrary {
    medley_library(1)
}

/// A second library for the Generate benches, so their figures are not of one library alone:
/// the built-in moves plus a medley of every other built-in clip (the 1st, 3rd, …), cut at every
/// count as [`builtin_medley_library`]'s is. Other clips meet at the medley's joins, so its
/// segments and the moves they join are other ones.
pub fn every_other_medley_library() -> odori_core::choreo::SegmentLibrary {
    medley_library(2)
}

/// The built-in moves plus a medley of every `step`-th built-in clip, cut at every count: the
/// clips danced one after another, a bar each at their own tempo, as the engine plays a dance
/// ([`odori_core::choreo::render`]: each placed where the one before ended, the joins
/// inertialized, the feet held), then imported as one clip. Until session 34 the medley was the
/// clips' frames laid end to end: every clip began where it was recorded, so each seam was a
/// jump of the whole body, and every segment of the medley held one (a segment spans a bar,
/// cut at every count); the joins as played read 2.7–8.8 where the table's blended jump read
/// 0.4–0.7, no motion a person imports.
fn medley_library(step: usize) -> odori_core::choreo::SegmentLibrary {
    use odori_core::choreo::{render, RenderOptions, SegmentLibrary, SegmentOptions};
    let mut lib = SegmentLibrary::builtin();
    let clips = odori_core::library::builtin_clips().len();
    let choices: Vec<Option<usize>> = (0..clips).step_by(step.max(1)).map(|c| lib.segments().iter().position(|s| s.clip == c)).collect();
    let bpm = odori_core::library::BUILTIN_BPM;
    let bar_secs = 4.0 * 60.0 / bpm;
    let bars = odori_core::choreo::bars_from_tempo(choices.len() as f32 * bar_secs + 0.01, bpm, 4, 0.0, |_, _| 0.5).expect("a bar per clip");
    let mut medley = render(&lib, &bars, &choices, &RenderOptions { fps: odori_core::choreo::LIBRARY_FPS, ..RenderOptions::default() });
    medley.name = "medley".into();
    medley.source = "built-in".into();
    let map = odori_core::canon::humanoid::HumanoidMap::from_skeleton(&medley.skeleton);
    let opts = SegmentOptions { tempo_bpm: Some(bpm), first_beat_secs: Some(0.0), hop_counts: 1, ..Default::default() };
    lib.add_clip(&medley, &map, &odori_core::HumanoidStatus::Complete, &opts).expect("the medley of built-in moves cuts into segments");
    lib
}

/// The filling problem both choreography benches time (native and wasm): 90 open bars whose
/// music intensity swells and falls, between two pinned bars, over `segments` segments.
pub fn bench_layers(segments: usize) -> Vec<odori_core::choreo::Layer> {
    use odori_core::choreo::Layer;
    (0..92)
        .map(|i| match i {
            0 => Layer::Fixed { segment: 17 % segments.max(1) },
            91 => Layer::Fixed { segment: 1234 % segments.max(1) },
            _ => Layer::Open { intensity: 0.5 + 0.45 * odori_core::fmath::sin(i as f32 / 7.0) },
        })
        .collect()
}

/// The song of the Generate bench (issue 26: Generate for 90 bars with ≥ 2,000 segments, timed
/// natively by tests/bench/choreo.rs and in wasm by tests/wasm_bench): 90 bars of 4/4 at
/// 120 BPM whose intensity swells and falls as [`bench_layers`]' does.
pub fn bench_bars() -> Vec<odori_core::bars::Bar> {
    let bar_secs = 2.0f32;
    odori_core::choreo::bars_from_tempo(90.0 * bar_secs + 0.01, 120.0, 4, 0.0, |start, _| 0.5 + 0.45 * odori_core::fmath::sin((start / bar_secs).round() / 7.0)).expect("90 bars at 120 BPM")
}

/// Generate (the whole pipeline, [`odori_core::choreo::generate_states`], default settings) on
/// `bars` from `lib`, every bar open: the dance and its objective.
pub fn generate_all(lib: &odori_core::choreo::SegmentLibrary, bars: &[odori_core::bars::Bar]) -> (Vec<Option<usize>>, f32) {
    let (states, report) = odori_core::choreo::generate_states(lib, bars, &[], odori_core::choreo::FillWeights::default(), &odori_core::choreo::GenerateOptions::default()).expect("generate");
    (states.iter().map(odori_core::choreo::BarState::segment).collect(), report.cost)
}

/// Where one Generate's time went ([`odori_core::choreo::profile`]), a line per stage that took
/// any: its time, its fills and its renders-and-measures (count and time), and the total.
pub fn profile_lines(p: &odori_core::choreo::profile::Profile) -> Vec<String> {
    let mut out = Vec::new();
    let (mut all, mut fills, mut measures) = (0.0, 0.0, 0.0);
    for (name, s) in odori_core::choreo::profile::STAGES.iter().zip(&p.stages) {
        if s.total_ms == 0.0 && s.fills == 0 && s.measures == 0 {
            continue;
        }
        (all, fills, measures) = (all + s.total_ms, fills + s.fill_ms, measures + s.measure_ms);
        out.push(format!("stage {name:<14} {:>7.0} ms: {:>2} fills {:>7.0} ms, {:>2} measures {:>7.0} ms", s.total_ms, s.fills, s.fill_ms, s.measures, s.measure_ms));
    }
    out.push(format!("stages in all {all:.0} ms: fills {fills:.0} ms, renders and measures {measures:.0} ms"));
    // Inside the renders and measures, over every stage.
    for (name, s) in odori_core::choreo::profile::PARTS.iter().zip(&p.parts) {
        if s.count > 0 {
            out.push(format!("  {name:<34} {:>3} x {:>7.0} ms", s.count, s.ms));
        }
    }
    out
}

/// Foot drift of a whole clip on the canonical skeleton (issue #14's join measure, after spec
/// §J's foot skate): a foot joint — either ankle or toe — is on the floor while within 5 cm of
/// its floor (the 1st percentile of its height over the clip); its drift is the largest
/// horizontal distance, in centimetres, from where it came onto the floor, over every stay.
/// Uses nothing of the product's own contact detection.
pub fn foot_stay_drift_cm(clip: &odori_core::Clip) -> f32 {
    foot_stay_drift_on_floors_cm(clip, &foot_floors_m(clip))
}

/// The feet joints [`foot_stay_drift_cm`] measures: left and right ankle, left and right toe.
pub const DRIFT_JOINTS: [odori_core::canon::humanoid::Canon; 4] =
    [odori_core::canon::humanoid::Canon::LeftFoot, odori_core::canon::humanoid::Canon::RightFoot, odori_core::canon::humanoid::Canon::LeftToe, odori_core::canon::humanoid::Canon::RightToe];

/// The floor under each of [`DRIFT_JOINTS`] over a clip: the 1st percentile of its height.
pub fn foot_floors_m(clip: &odori_core::Clip) -> [f32; 4] {
    let all = clip.all_world_positions();
    let n = clip.joint_count();
    let frames = clip.frame_count();
    DRIFT_JOINTS.map(|j| {
        let mut h: Vec<f32> = (0..frames).filter_map(|f| all.get(f * n + j.index()).map(|p| p.y)).collect();
        h.sort_by(f32::total_cmp);
        h.get((h.len() as f32 * 0.01) as usize).copied().unwrap_or(0.0)
    })
}

/// [`foot_stay_drift_cm`] on given floors. A join's share is measured with the joined
/// animation's floors on the joined clip and on both sources alike: with each source on its
/// own floor, a source whose floor differs from the other's would show stays in the joined
/// clip that it has alone too, and they would count against the join.
pub fn foot_stay_drift_on_floors_cm(clip: &odori_core::Clip, floors: &[f32; 4]) -> f32 {
    const CONTACT_M: f32 = 0.05;
    let all = clip.all_world_positions();
    let n = clip.joint_count();
    let frames = clip.frame_count();
    if frames == 0 || n <= odori_core::canon::humanoid::Canon::RightToe.index() {
        return 0.0;
    }
    let mut worst = 0.0f32;
    for (j, floor) in DRIFT_JOINTS.iter().zip(floors) {
        let mut anchor: Option<glam::Vec3> = None;
        for f in 0..frames {
            let p = all[f * n + j.index()];
            if p.y <= floor + CONTACT_M {
                let a = *anchor.get_or_insert(p);
                worst = worst.max(glam::Vec2::new(p.x - a.x, p.z - a.z).length());
            } else {
                anchor = None;
            }
        }
    }
    worst * 100.0
}

/// The foot drift a join adds, cm: the joined clip's [`foot_stay_drift_cm`] less the worse of
/// its two sources', all three on the joined clip's floors; and the joined clip's own figure.
pub fn join_added_drift_cm(joined: &odori_core::Clip, a: &odori_core::Clip, b: &odori_core::Clip) -> (f32, f32) {
    let floors = foot_floors_m(joined);
    let d = foot_stay_drift_on_floors_cm(joined, &floors);
    let base = foot_stay_drift_on_floors_cm(a, &floors).max(foot_stay_drift_on_floors_cm(b, &floors));
    ((d - base).max(0.0), d)
}

/// Join jump (spec §J) of a joined clip around its blend: the largest change of any joint's
/// velocity between consecutive frames within `[from, to)`, divided by the 95th percentile of
/// the same over the two source clips (how much rougher the join is than the motions).
pub fn join_jump_ratio(joined: &odori_core::Clip, sources: [&odori_core::Clip; 2], from: usize, to: usize) -> f32 {
    fn jumps(c: &odori_core::Clip, from: usize, to: usize) -> Vec<f32> {
        let n = c.joint_count();
        let all = c.all_world_positions();
        let frames = c.frame_count();
        let mut out = Vec::new();
        for f in from.max(1)..to.min(frames.saturating_sub(1)) {
            let mut worst = 0.0f32;
            for j in 0..n {
                let (p0, p1, p2) = (all[(f - 1) * n + j], all[f * n + j], all[(f + 1) * n + j]);
                worst = worst.max(((p2 - p1) - (p1 - p0)).length() * c.fps);
            }
            out.push(worst);
        }
        out
    }
    let mut inside: Vec<f32> = sources.iter().flat_map(|c| jumps(c, 0, c.frame_count())).collect();
    inside.sort_by(f32::total_cmp);
    let p95 = inside.get(((inside.len() as f32 * 0.95) as usize).min(inside.len().saturating_sub(1))).copied().unwrap_or(0.0).max(1e-6);
    jumps(joined, from, to).into_iter().fold(0.0, f32::max) / p95
}

/// Spearman's rank correlation (no tie correction: the values are continuous). Used by the
/// preference benches to say how well a similarity agrees with the perceptual distance.
pub fn spearman(a: &[f32], b: &[f32]) -> f32 {
    let rank = |x: &[f32]| {
        let mut order: Vec<usize> = (0..x.len()).collect();
        order.sort_by(|&i, &j| x[i].total_cmp(&x[j]));
        let mut r = vec![0.0f64; x.len()];
        for (k, &i) in order.iter().enumerate() {
            r[i] = k as f64;
        }
        r
    };
    let (ra, rb) = (rank(a), rank(b));
    let mid = (a.len() as f64 - 1.0) / 2.0;
    let (mut ab, mut aa, mut bb) = (0.0, 0.0, 0.0);
    for (x, y) in ra.iter().zip(&rb) {
        ab += (x - mid) * (y - mid);
        aa += (x - mid) * (x - mid);
        bb += (y - mid) * (y - mid);
    }
    (ab / (aa * bb).sqrt().max(1e-300)) as f32
}

/// The simulated person of the preference test (spec §J): of one round's shown candidates
/// (`scored`: each one's perceptual distance to the hidden target and its index, in the order
/// shown, the target left out), the `likes` it likes — the closest (`guided`), or that many
/// distinct ones at random (a 64-bit LCG on `seed`, so a run's draws are reproducible).
pub fn simulated_likes(mut scored: Vec<(f32, usize)>, guided: bool, likes: usize, seed: &mut u64) -> Vec<usize> {
    if guided {
        scored.sort_by(|a, b| a.0.total_cmp(&b.0));
        return scored.iter().take(likes).map(|s| s.1).collect();
    }
    let mut pick = Vec::new();
    while pick.len() < likes.min(scored.len()) {
        *seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        let c = scored[(*seed >> 33) as usize % scored.len()].1;
        if !pick.contains(&c) {
            pick.push(c);
        }
    }
    pick
}

/// A dance over `bars` generated by the core's pipeline with no project around it (the tests
/// and benches that measure the fill alone): the states of every bar, the filling's weights and
/// what [`odori_core::choreo::generate_states`] reported last.
pub struct Dance {
    bars: Vec<odori_core::bars::Bar>,
    states: Vec<odori_core::choreo::BarState>,
    weights: odori_core::choreo::FillWeights,
}

impl Dance {
    /// No bar filled yet, default weights.
    pub fn new(bars: Vec<odori_core::bars::Bar>) -> Self {
        Self { bars, states: Vec::new(), weights: odori_core::choreo::FillWeights::default() }
    }

    /// Which moves Generate fills the open bars with.
    pub fn set_moves_source(&mut self, source: odori_core::choreo::MovesSource) {
        self.weights.moves_source = source;
    }

    /// Generate at the default options.
    pub fn generate(&mut self, lib: &odori_core::choreo::SegmentLibrary) -> Result<odori_core::choreo::GenerateReport, odori_core::choreo::ChoreoError> {
        self.generate_with(lib, &odori_core::choreo::GenerateOptions::default())
    }

    /// Generate with `options` (pinned bars, if any, stay).
    pub fn generate_with(&mut self, lib: &odori_core::choreo::SegmentLibrary, options: &odori_core::choreo::GenerateOptions) -> Result<odori_core::choreo::GenerateReport, odori_core::choreo::ChoreoError> {
        let (states, report) = odori_core::choreo::generate_states(lib, &self.bars, &self.states, self.weights, options)?;
        self.states = states;
        Ok(report)
    }

    /// Each bar's segment (`None`: empty).
    pub fn segments(&self) -> Vec<Option<usize>> {
        (0..self.bars.len()).map(|i| self.states.get(i).and_then(odori_core::choreo::BarState::segment)).collect()
    }
}

/// The seed of the random-moves control in the beat tests (`choreo_beats`, `choreo_waltz`).
pub const RANDOM_MOVES_SEED: u64 = 0x2545_F491_4F6C_DD1D;
/// The seed of the random-moves control in the takes test and the `choreo_person` bench.
pub const RANDOM_MOVES_SEED_TAKES: u64 = 0x9E37_79B9_7F4A_7C15;

/// Random moves on `bars` (spec §J's control for beat alignment): per bar, a live segment of
/// the counts that bar takes ([`odori_core::choreo::bar_counts`]; any when the library holds
/// none), drawn by a 64-bit LCG from `seed`, for `max(5, ⌈100 / bars⌉)` dances (at least 100
/// random bars: one draw of a one-bar song is one segment). Returns the dances.
pub fn random_moves(lib: &odori_core::choreo::SegmentLibrary, bars: &[odori_core::bars::Bar], seed: u64) -> Vec<Vec<Option<usize>>> {
    let live: Vec<Vec<usize>> = odori_core::choreo::bar_counts(lib, bars)
        .iter()
        .map(|&n| lib.segments().iter().filter(|s| !s.retired && (n == 0 || s.counts() == n)).map(|s| s.index).collect())
        .collect();
    let draws = 5usize.max(100usize.div_ceil(bars.len().max(1)));
    let mut x = seed;
    (0..draws)
        .map(|_| {
            (0..bars.len())
                .map(|b| {
                    x = x.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
                    live[b].get((x >> 33) as usize % live[b].len().max(1)).copied()
                })
                .collect()
        })
        .collect()
}

/// BAS-music (spec §J) of the dance `choices` fills `bars` with, rendered as the product plays it
/// (default render options), scored on the song's `beats`.
pub fn dance_quality_of(lib: &odori_core::choreo::SegmentLibrary, bars: &[odori_core::bars::Bar], beats: &[f32], choices: &[Option<usize>]) -> odori_core::choreo::quality::DanceQuality {
    let (clip, switches) = odori_core::choreo::render_switched(lib, bars, choices, &odori_core::choreo::RenderOptions::default());
    odori_core::choreo::quality::dance_quality_switched(&clip, bars, beats, &switches).expect("dance quality")
}

/// The random-moves control's BAS-music: the mean over the dances of [`random_moves`].
pub fn random_moves_bas(lib: &odori_core::choreo::SegmentLibrary, bars: &[odori_core::bars::Bar], beats: &[f32], seed: u64) -> f32 {
    let dances = random_moves(lib, bars, seed);
    dances.iter().map(|ch| dance_quality_of(lib, bars, beats, ch).beats.bas_music).sum::<f32>() / dances.len().max(1) as f32
}

/// The built-in library, and the songs the issue-26 acceptance tests read: every song in
/// ../shared/data/music (`full_tracks`), the trumpet loop and the drum take, decoded by the
/// caller (`decode`: path → envelope), then demo pieces `(beats per bar, start BPM, end BPM)`
/// from the demo-song generator (none tuned on). Labels: the data path, or "demo in B, S→E BPM".
pub fn acceptance_songs(
    data_songs: &[&str],
    decode: impl Fn(&str) -> odori_core::music::RmsEnvelope,
    demos: &[(u32, f32, f32)],
) -> Vec<(String, odori_core::music::RmsEnvelope)> {
    use odori_core::music::demo_song::{demo_song_with, DemoSongOptions};
    let mut out: Vec<(String, odori_core::music::RmsEnvelope)> = data_songs.iter().map(|rel| (rel.to_string(), decode(rel))).collect();
    for &(beats_per_bar, bpm, end_bpm) in demos {
        let song = demo_song_with(22050.0, &DemoSongOptions { beats_per_bar, bpm, end_bpm }).expect("demo song");
        out.push((format!("demo in {beats_per_bar}, {bpm}→{end_bpm} BPM"), odori_core::music::envelope(&[&song.samples], 22050.0).expect("envelope")));
    }
    out
}
