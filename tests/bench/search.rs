//! Benchmark (issues 3, 16): a 2-s query (120 frames) against 1 hour of 60-fps motion (216,000
//! frames, built by concatenating the real clips of ../shared/data/mocap over and over, one clip
//! held out), top 1 and top 10, for (a) a query whose source is in the library (salsa_02, played
//! 1.1× faster with noise) and (b) a novel query (2 s of the held-out clip, the same way). Prints
//! the plain DP time (every cell, the product's baseline), the fast exact search time and their
//! ratio, checks both return the same matches, and exports the arrays for the peer comparison
//! (`tests/tools/peer_dtaidistance.py`). Run: `cargo bench -p odori-tests --bench search`.

#[path = "../native/search_common.rs"]
mod common;

use std::time::Instant;

use common::Rng;
use odori_core::canon::normalize::Origin;
use odori_core::search::{
    joined_bound, no_progress, search, search_bounded_cached, search_plain, search_probe_cached, search_threads, SearchCache, BodyPreset, ClipFeatures, FeatureIndex, MotionFeatures, SearchOutcome, SearchParams, FRAME_FLOATS,
};

const LIBRARY_FRAMES: usize = 216_000;
const QUERY_FRAMES: usize = 120;

fn same(a: &SearchOutcome, b: &SearchOutcome) -> bool {
    a.matches.len() == b.matches.len()
        && a.matches.iter().zip(&b.matches).all(|(x, y)| {
            x.clip_index == y.clip_index && x.start_frame == y.start_frame && x.end_frame == y.end_frame && (x.distance - y.distance).abs() <= 1e-5 * y.distance.max(1.0)
        })
}

/// CPU time of the calling thread, seconds (Linux: the first field of
/// /proc/thread-self/schedstat, nanoseconds on a CPU). The machine these figures come from is
/// shared, so wall times vary with its load; a single-threaded search's CPU time does not.
fn thread_cpu_secs() -> f64 {
    std::fs::read_to_string("/proc/thread-self/schedstat").ok().and_then(|s| s.split_whitespace().next()?.parse::<f64>().ok()).map_or(f64::NAN, |ns| ns * 1e-9)
}

fn main() {
    let threads = std::thread::available_parallelism().map_or(2, |n| n.get());
    let t0 = Instant::now();
    let real = common::real_index();
    let real_frames = real.total_frames();
    for s in &real.skipped {
        println!("skipped {}: {}", s.name, s.reason);
    }
    println!("real library: {} clips, {} frames ({:.1} min at 60 fps), features built in {:.2} s", real.clips.len(), real_frames, real_frames as f32 / 3600.0, t0.elapsed().as_secs_f32());

    // The held-out clip (the novel query's source): an Indian dance clip, not in the hour.
    let held = real.clips.iter().position(|c| c.name.contains("indian_13")).unwrap_or(real.clips.len() - 1);
    println!("held out of the library (novel query's source): {}", real.clips[held].name);
    // One hour: the other real clips' hip-origin features, concatenated cyclically, cut to 216,000.
    let mut data = Vec::with_capacity(LIBRARY_FRAMES * FRAME_FLOATS);
    'fill: loop {
        for (k, c) in real.clips.iter().enumerate() {
            if k == held {
                continue;
            }
            let f = &c.features(Origin::Hips).data;
            let room = LIBRARY_FRAMES * FRAME_FLOATS - data.len();
            data.extend_from_slice(&f[..f.len().min(room)]);
            if data.len() == LIBRARY_FRAMES * FRAME_FLOATS {
                break 'fill;
            }
        }
    }
    // The same hour as the web app holds it (tests/bench/search-browser.mjs): each copy of a
    // clip its own library clip, the clips dealt to two parts — the app's two workers on this
    // 2-core machine — each to the part holding the fewest frames, as www/search/client.js does.
    let mut parts: Vec<(FeatureIndex, Vec<usize>, usize)> = (0..2).map(|_| (FeatureIndex::new(), Vec::new(), 0)).collect();
    let mut clips_hour = FeatureIndex::new();
    {
        let mut at = 0usize;
        'clips: loop {
            for (k, c) in real.clips.iter().enumerate() {
                if k == held {
                    continue;
                }
                let n = c.frame_count().min(LIBRARY_FRAMES - at);
                let f = ClipFeatures::new(format!("{} copy", c.name), 60.0, MotionFeatures { origin: Origin::Hips, data: data[at * FRAME_FLOATS..(at + n) * FRAME_FLOATS].to_vec() });
                let part = parts.iter_mut().min_by_key(|p| p.2).expect("two parts");
                part.0.add_features(f.clone());
                part.1.push(clips_hour.clips.len());
                part.2 += n;
                clips_hour.add_features(f);
                at += n;
                if at == LIBRARY_FRAMES {
                    break 'clips;
                }
            }
        }
    }
    let mut index = FeatureIndex::new();
    index.add_features(ClipFeatures::new("one hour of real mocap", 60.0, MotionFeatures { origin: Origin::Hips, data }));

    // A query: 2 s of a clip from `from_frame` on, played 1.1× faster with small joint noise
    // (so the library holds near matches, not only exact copies).
    let mut rng = Rng(0xBE7C);
    let mut cut = |clip: usize, from_frame: f32| -> Vec<f32> {
        let src = &real.clips[clip].features(Origin::Hips).data;
        let mut q = Vec::with_capacity(QUERY_FRAMES * FRAME_FLOATS);
        for f in 0..QUERY_FRAMES {
            let x = from_frame + f as f32 * 1.1;
            let (f0, a) = (x.floor() as usize, x.fract());
            for c in 0..FRAME_FLOATS {
                let v = src[f0 * FRAME_FLOATS + c] * (1.0 - a) + src[(f0 + 1) * FRAME_FLOATS + c] * a;
                q.push(v + 0.005 * rng.normal());
            }
        }
        q
    };
    let src_clip = real.clips.iter().position(|c| c.name.contains("salsa_02")).unwrap_or(0);
    let q_in = cut(src_clip, 1200.0);
    let q_novel = cut(held, (real.clips[held].frame_count() / 2) as f32);
    let query_in = ClipFeatures::new("query (source in the library)", 60.0, MotionFeatures { origin: Origin::Hips, data: q_in.clone() });
    let query_novel = ClipFeatures::new("novel query (source held out)", 60.0, MotionFeatures { origin: Origin::Hips, data: q_novel.clone() });

    // Export for the peer comparison.
    let out = std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../target/search-bench");
    std::fs::create_dir_all(&out).expect("create target/search-bench");
    let bytes = |v: &[f32]| v.iter().flat_map(|x| x.to_le_bytes()).collect::<Vec<u8>>();
    std::fs::write(out.join("query_in.f32"), bytes(&q_in)).expect("write query");
    std::fs::write(out.join("query_novel.f32"), bytes(&q_novel)).expect("write query");
    std::fs::write(out.join("library.f32"), bytes(&index.clips[0].features(Origin::Hips).data)).expect("write library");
    std::fs::write(out.join("shape.json"), format!("{{\"queryFrames\":{QUERY_FRAMES},\"libraryFrames\":{LIBRARY_FRAMES},\"floatsPerFrame\":{FRAME_FLOATS}}}")).expect("write shape");
    println!("exported the queries and the library to {}", out.display());

    let mut runs: Vec<(String, &str, SearchParams, &ClipFeatures)> = Vec::new();
    for (tag, q) in [("in", &query_in), ("novel", &query_novel)] {
        for k in [1, 10] {
            runs.push((format!("{}, whole body, top {k}, no threshold", q.name), tag, SearchParams { max_results: k, ..SearchParams::default() }, q));
        }
    }
    let feet = SearchParams { max_results: 10, ..SearchParams::preset(BodyPreset::FeetOnly) };
    runs.push((format!("{}, feet only, top 10, no threshold", query_novel.name), "novel", feet, &query_novel));
    let mut timings = Vec::new();
    // ODORI_BENCH_ONLY=text runs only the cases whose name contains it (for profiling).
    let only = std::env::var("ODORI_BENCH_ONLY").ok();
    for (name, tag, params, query) in &runs {
        if only.as_ref().is_some_and(|o| !name.contains(o.as_str())) {
            continue;
        }
        let query: &ClipFeatures = query;
        // ODORI_BENCH_NO_PLAIN=1 skips the plain DP (for profiling the fast search alone).
        let skip_plain = std::env::var("ODORI_BENCH_NO_PLAIN").is_ok();
        let (t, c) = (Instant::now(), thread_cpu_secs());
        let plain = if skip_plain { SearchOutcome::default() } else { search_plain(&index, query, params, &mut no_progress()).expect("plain search") };
        let (plain_secs, plain_cpu) = (t.elapsed().as_secs_f64(), thread_cpu_secs() - c);
        let median = |v: &mut Vec<f64>| {
            v.sort_by(f64::total_cmp);
            v[v.len() / 2]
        };
        let (mut fast_times, mut fast_cpus, mut par_times) = (Vec::new(), Vec::new(), Vec::new());
        let (mut fast, mut par) = (None, None);
        for _ in 0..3 {
            let (t, c) = (Instant::now(), thread_cpu_secs());
            let r = search(&index, query, params, &mut no_progress()).expect("fast search");
            fast_times.push(t.elapsed().as_secs_f64());
            fast_cpus.push(thread_cpu_secs() - c);
            fast = Some(r);
            let t = Instant::now();
            let r = search_threads(&index, query, params, threads, &mut no_progress()).expect("threaded search");
            par_times.push(t.elapsed().as_secs_f64());
            par = Some(r);
        }
        let (fast, par) = (fast.expect("ran"), par.expect("ran"));
        let (fast_secs, fast_cpu, par_secs) = (median(&mut fast_times), median(&mut fast_cpus), median(&mut par_times));
        let ok = (skip_plain || same(&plain, &fast)) && same(&fast, &par);
        println!(
            "{name}: {} matches; plain DP {:.1} ms (CPU {:.1} ms); fast, 1 thread {:.2} ms (CPU {:.2} ms), median of 3; plain / fast = {:.1}x wall, {:.1}x CPU; fast on {threads} threads {:.2} ms wall, plain / that = {:.1}x; same results: {ok}; frame distances {} of {} cells ({:.2}%); best {:?}",
            plain.matches.len(),
            plain_secs * 1e3,
            plain_cpu * 1e3,
            fast_secs * 1e3,
            fast_cpu * 1e3,
            plain_secs / fast_secs,
            plain_cpu / fast_cpu,
            par_secs * 1e3,
            plain_secs / par_secs,
            fast.stats.distances_computed,
            fast.stats.cells_total,
            100.0 * fast.stats.distances_computed as f64 / fast.stats.cells_total as f64,
            fast.matches.first().map(|m| (m.start_frame, m.end_frame, m.distance)),
        );
        assert!(ok, "{name}: fast, threaded and plain differ");
        // The web app's path: round 1 (probe) in both parts, the joined bound, round 2 in both
        // (one after the other here; each part's CPU time is what its worker takes).
        let (mut split_busiest, mut split_sum, mut probe_max, mut one_clips) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
        // Control: each part searched alone with its own probe and bound (the app before the two
        // rounds), merged the same way.
        let mut alone_busiest = Vec::new();
        let mut split_same = true;
        // The parts' answers merged as the app's client does: library clip numbers, best first
        // (distance, then clip, then end), the first k.
        let merge = |answers: Vec<SearchOutcome>| {
            let mut matches: Vec<_> = answers
                .into_iter()
                .zip(&parts)
                .flat_map(|(r, p)| {
                    r.matches.into_iter().map(|mut m| {
                        m.clip_index = p.1[m.clip_index];
                        m
                    })
                })
                .collect();
            matches.sort_by(|a, b| a.distance.total_cmp(&b.distance).then(a.clip_index.cmp(&b.clip_index)).then(a.end_frame.cmp(&b.end_frame)));
            matches.truncate(params.max_results);
            SearchOutcome { matches, ..SearchOutcome::default() }
        };
        let mut bound = f32::NAN;
        let mut cache_bytes = 0usize;
        for _ in 0..3 {
            let c = thread_cpu_secs();
            let whole = search(&clips_hour, query, params, &mut no_progress()).expect("fast search over the clips");
            one_clips.push(thread_cpu_secs() - c);
            let mut alone = Vec::new();
            let mut alone_answers = Vec::new();
            for p in &parts {
                let c = thread_cpu_secs();
                alone_answers.push(search(&p.0, query, params, &mut no_progress()).expect("part searched alone"));
                alone.push(thread_cpu_secs() - c);
            }
            split_same &= same(&whole, &merge(alone_answers));
            alone_busiest.push(alone.iter().copied().fold(0.0, f64::max));
            let mut probe_cpu = Vec::new();
            let mut lists = Vec::new();
            // Each part's worker keeps what its probe builds for its bounded search (a fresh
            // cache per repetition: nothing carries over from the last one).
            let mut caches: Vec<SearchCache> = parts.iter().map(|_| SearchCache::default()).collect();
            for (p, cache) in parts.iter().zip(&mut caches) {
                let c = thread_cpu_secs();
                lists.push(search_probe_cached(&p.0, query, params, cache).expect("probe").distances);
                probe_cpu.push(thread_cpu_secs() - c);
            }
            let refs: Vec<&[f32]> = lists.iter().map(|l| l.as_slice()).collect();
            bound = joined_bound(&refs, params.max_results);
            let mut part_cpu = Vec::new();
            let mut answers = Vec::new();
            for (p, cache) in parts.iter().zip(&mut caches) {
                let c = thread_cpu_secs();
                answers.push(search_bounded_cached(&p.0, query, params, bound, cache, &mut no_progress()).expect("bounded search"));
                part_cpu.push(thread_cpu_secs() - c);
            }
            split_same &= same(&whole, &merge(answers));
            let per: Vec<f64> = (0..parts.len()).map(|k| probe_cpu[k] + part_cpu[k]).collect();
            split_busiest.push(per.iter().copied().fold(0.0, f64::max));
            split_sum.push(per.iter().sum::<f64>());
            probe_max.push(probe_cpu.iter().copied().fold(0.0, f64::max));
            cache_bytes = caches.iter().map(SearchCache::heap_bytes).max().unwrap_or(0);
        }
        println!(
            "{name}, the hour as {} clips in 2 parts (the app's 2 workers): one thread over the clips CPU {:.1} ms; each part alone (own probe, the control) busiest part's CPU {:.1} ms; two rounds: busiest part's CPU {:.1} ms (its probe {:.1} ms), both parts {:.1} ms, medians of 3; kept from probe to search {:.2} MB (largest part); joined bound {bound:.4}; merged = one thread's: {split_same}",
            clips_hour.clips.len(),
            median(&mut one_clips) * 1e3,
            median(&mut alone_busiest) * 1e3,
            median(&mut split_busiest) * 1e3,
            median(&mut probe_max) * 1e3,
            median(&mut split_sum) * 1e3,
            cache_bytes as f64 / 1e6,
        );
        assert!(split_same, "{name}: the split search differs from one thread's");
        timings.push(format!(
            "{{\"name\":\"{name}\",\"query\":\"{tag}\",\"k\":{},\"plainMs\":{:.3},\"plainCpuMs\":{:.3},\"fastMs\":{:.3},\"fastCpuMs\":{:.3},\"threads\":{threads},\"threadsMs\":{:.3}}}",
            params.max_results,
            plain_secs * 1e3,
            plain_cpu * 1e3,
            fast_secs * 1e3,
            fast_cpu * 1e3,
            par_secs * 1e3
        ));
    }
    std::fs::write(out.join("timings.json"), format!("{{\"cases\":[{}]}}", timings.join(","))).expect("write timings");
}
