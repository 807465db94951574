//! Benchmark (issue 3): a 2-s query (120 frames) against 1 hour of 60-fps motion (216,000
//! frames, built by concatenating the real clips of ../shared/data/mocap over and over), whole
//! body and other presets. Prints the plain DP time, the fast exact search time and their ratio,
//! checks both return the same matches, and exports the arrays for the peer comparison
//! (`tests/tools/peer_dtaidistance.py`). Run: `cargo bench -p odori-tests --bench search`.

#[path = "../native/search_common.rs"]
mod common;

use std::time::Instant;

use common::Rng;
use odori_core::normalize::Origin;
use odori_core::search::{
    no_progress, search, search_plain, BodyPreset, ClipFeatures, FeatureIndex, MotionFeatures, SearchOutcome, SearchParams, FRAME_FLOATS,
};

const LIBRARY_FRAMES: usize = 216_000;
const QUERY_FRAMES: usize = 120;

fn same(a: &SearchOutcome, b: &SearchOutcome) -> bool {
    a.matches.len() == b.matches.len()
        && a.matches.iter().zip(&b.matches).all(|(x, y)| {
            x.clip_index == y.clip_index && x.start_frame == y.start_frame && x.end_frame == y.end_frame && (x.distance - y.distance).abs() <= 1e-5 * y.distance.max(1.0)
        })
}

fn main() {
    let t0 = Instant::now();
    let real = common::real_index();
    let real_frames = real.total_frames();
    for s in &real.skipped {
        println!("skipped {}: {}", s.name, s.reason);
    }
    println!("real library: {} clips, {} frames ({:.1} min at 60 fps), features built in {:.2} s", real.clips.len(), real_frames, real_frames as f32 / 3600.0, t0.elapsed().as_secs_f32());

    // One hour: the real clips' hip-origin features, concatenated cyclically and cut to 216,000.
    let mut data = Vec::with_capacity(LIBRARY_FRAMES * FRAME_FLOATS);
    'fill: loop {
        for c in &real.clips {
            let f = &c.features(Origin::Hips).data;
            let room = LIBRARY_FRAMES * FRAME_FLOATS - data.len();
            data.extend_from_slice(&f[..f.len().min(room)]);
            if data.len() == LIBRARY_FRAMES * FRAME_FLOATS {
                break 'fill;
            }
        }
    }
    let mut index = FeatureIndex::new();
    index.add_features(ClipFeatures::new("one hour of real mocap", 60.0, MotionFeatures { origin: Origin::Hips, data }));

    // The query: 2 s of salsa_02 from 20 s on, played 1.1× faster with small joint noise
    // (so the library holds near matches, not only exact copies).
    let src_clip = real.clips.iter().position(|c| c.name.contains("salsa_02")).unwrap_or(0);
    let src = &real.clips[src_clip].features(Origin::Hips).data;
    let mut rng = Rng(0xBE7C);
    let mut q = Vec::with_capacity(QUERY_FRAMES * FRAME_FLOATS);
    for f in 0..QUERY_FRAMES {
        let x = 1200.0 + f as f32 * 1.1;
        let (f0, a) = (x.floor() as usize, x.fract());
        for c in 0..FRAME_FLOATS {
            let v = src[f0 * FRAME_FLOATS + c] * (1.0 - a) + src[(f0 + 1) * FRAME_FLOATS + c] * a;
            q.push(v + 0.005 * rng.normal());
        }
    }
    let query = ClipFeatures::new("query", 60.0, MotionFeatures { origin: Origin::Hips, data: q.clone() });

    // Export for the peer comparison.
    let out = std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../target/search-bench");
    std::fs::create_dir_all(&out).expect("create target/search-bench");
    let bytes = |v: &[f32]| v.iter().flat_map(|x| x.to_le_bytes()).collect::<Vec<u8>>();
    std::fs::write(out.join("query.f32"), bytes(&q)).expect("write query");
    std::fs::write(out.join("library.f32"), bytes(&index.clips[0].features(Origin::Hips).data)).expect("write library");
    std::fs::write(out.join("shape.json"), format!("{{\"queryFrames\":{QUERY_FRAMES},\"libraryFrames\":{LIBRARY_FRAMES},\"floatsPerFrame\":{FRAME_FLOATS}}}")).expect("write shape");
    println!("exported query and library to {}", out.display());

    // Thresholds are given per unit of joint weight (mean joint distance in body heights),
    // times the preset's summed weights.
    let mut cases: Vec<(String, SearchParams)> = Vec::new();
    let with = |preset: BodyPreset, k: usize, per_joint: Option<f32>| {
        let p = SearchParams::preset(preset);
        let sum: f32 = p.weights.iter().sum();
        SearchParams { max_results: k, threshold: per_joint.map(|t| t * sum), ..p }
    };
    cases.push(("whole body, top 10, threshold 0.05/joint".into(), with(BodyPreset::WholeBody, 10, Some(0.05))));
    cases.push(("whole body, top 10, threshold 0.1/joint".into(), with(BodyPreset::WholeBody, 10, Some(0.1))));
    cases.push(("whole body, top 1, no threshold".into(), with(BodyPreset::WholeBody, 1, None)));
    cases.push(("whole body, top 10, no threshold".into(), with(BodyPreset::WholeBody, 10, None)));
    cases.push(("feet only, top 10, threshold 0.05/joint".into(), with(BodyPreset::FeetOnly, 10, Some(0.05))));
    cases.push(("arms, top 10, threshold 0.05/joint".into(), with(BodyPreset::Arms, 10, Some(0.05))));
    // A query with no copy in the library: the same stretch mirrored left/right (sides swapped,
    // lateral axis negated), so the library holds only other, similar motion.
    let mirrored = ClipFeatures::new("mirrored query", 60.0, common::mirrored(&MotionFeatures { origin: Origin::Hips, data: q.clone() }, false));
    let mut timings = Vec::new();
    let mut runs: Vec<(String, SearchParams, &ClipFeatures)> = cases.into_iter().map(|(n, p)| (n, p, &query)).collect();
    runs.push(("mirrored query (no copy in library), whole body, top 1, no threshold".into(), with(BodyPreset::WholeBody, 1, None), &mirrored));
    runs.push(("mirrored query (no copy in library), whole body, top 10, no threshold".into(), with(BodyPreset::WholeBody, 10, None), &mirrored));
    runs.push(("mirrored query (no copy in library), whole body, top 10, threshold 0.05/joint".into(), with(BodyPreset::WholeBody, 10, Some(0.05)), &mirrored));
    // ODORI_BENCH_ONLY=text runs only the cases whose name contains it (for profiling).
    let only = std::env::var("ODORI_BENCH_ONLY").ok();
    for (name, params, query) in &runs {
        if only.as_ref().is_some_and(|o| !name.contains(o.as_str())) {
            continue;
        }
        let query: &ClipFeatures = query;
        let t = Instant::now();
        let plain = search_plain(&index, &query, params, &mut no_progress()).expect("plain search");
        let plain_secs = t.elapsed().as_secs_f64();
        let mut fast_times = Vec::new();
        let mut fast = None;
        for _ in 0..5 {
            let t = Instant::now();
            let r = search(&index, &query, params, &mut no_progress()).expect("fast search");
            fast_times.push(t.elapsed().as_secs_f64());
            fast = Some(r);
        }
        fast_times.sort_by(f64::total_cmp);
        let fast = fast.expect("ran");
        let fast_secs = fast_times[fast_times.len() / 2];
        let ok = same(&plain, &fast);
        println!(
            "{name}: {} matches; plain DP {:.1} ms, fast {:.2} ms (median of 5), ratio {:.1}x; same results: {ok}; distances computed {} of {} cells ({:.2}%), rescanned: {}; best {:?}",
            plain.matches.len(),
            plain_secs * 1e3,
            fast_secs * 1e3,
            plain_secs / fast_secs,
            fast.stats.distances_computed,
            fast.stats.cells_total,
            100.0 * fast.stats.distances_computed as f64 / fast.stats.cells_total as f64,
            fast.stats.rescanned,
            fast.matches.first().map(|m| (m.start_frame, m.end_frame, m.distance)),
        );
        assert!(ok, "{name}: fast and plain differ");
        timings.push(format!("{{\"name\":\"{name}\",\"plainMs\":{:.3},\"fastMs\":{:.3}}}", plain_secs * 1e3, fast_secs * 1e3));
    }
    std::fs::write(out.join("timings.json"), format!("{{\"cases\":[{}]}}", timings.join(","))).expect("write timings");
}
