//! Exactness: the fast search returns the same matches and distances as a plain reference DP
//! (written in the test from spec §C) and as the core's own plain DP, on random motion and on
//! real clips.

#[path = "search_common.rs"]
mod common;

use common::{reference_search, Rng};
use odori_core::canon::humanoid::CANON_COUNT;
use odori_core::canon::normalize::Origin;
use odori_core::search::{
    joined_bound, merge_parts, no_progress, search, search_bounded_cached, search_plain, search_probe_cached, search_threads, SearchCache, BodyPreset, ClipFeatures, FeatureIndex, MotionFeatures,
    SearchError, SearchOutcome, SearchParams, FRAME_FLOATS,
};

/// Smooth random motion: each coordinate a sum of three sinusoids plus a slow random walk.
fn random_motion(rng: &mut Rng, frames: usize) -> Vec<f32> {
    let mut data = vec![0f32; frames * FRAME_FLOATS];
    for c in 0..FRAME_FLOATS {
        let waves: Vec<(f32, f32, f32)> = (0..3).map(|_| (rng.range(0.02, 0.4), rng.range(0.0, 6.28), rng.range(0.02, 0.3))).collect();
        let mut walk = 0.0f32;
        for f in 0..frames {
            walk += 0.01 * rng.normal();
            data[f * FRAME_FLOATS + c] = waves.iter().map(|(w, p, a)| a * (w * f as f32 + p).sin()).sum::<f32>() + walk;
        }
    }
    data
}

fn features(name: &str, data: Vec<f32>) -> ClipFeatures {
    ClipFeatures::new(name, 60.0, MotionFeatures { origin: Origin::Hips, data })
}

/// A query cut from `src` at `start`, time-warped by a random speed in [0.8, 1.25] and noised.
fn warped_query(rng: &mut Rng, src: &[f32], start: usize, frames: usize) -> Vec<f32> {
    let speed = rng.range(0.8, 1.25);
    let src_frames = src.len() / FRAME_FLOATS;
    let mut out = Vec::with_capacity(frames * FRAME_FLOATS);
    for f in 0..frames {
        let x = (start as f32 + f as f32 * speed).min((src_frames - 1) as f32);
        let (f0, a) = (x.floor() as usize, x.fract());
        let f1 = (f0 + 1).min(src_frames - 1);
        for c in 0..FRAME_FLOATS {
            let v = src[f0 * FRAME_FLOATS + c] * (1.0 - a) + src[f1 * FRAME_FLOATS + c] * a;
            out.push(v + 0.02 * rng.normal());
        }
    }
    out
}

fn assert_same(what: &str, fast: &SearchOutcome, reference: &[common::RefMatch], (query, index, params): (&ClipFeatures, &FeatureIndex, &SearchParams)) {
    let got: Vec<(usize, usize, usize)> = fast.matches.iter().map(|m| (m.clip_index, m.start_frame, m.end_frame)).collect();
    let want: Vec<(usize, usize, usize)> = reference.iter().map(|r| (r.0, r.1, r.2)).collect();
    assert_eq!(got, want, "{what}: matches differ");
    for (m, r) in fast.matches.iter().zip(reference) {
        assert!((m.distance - r.3).abs() <= 1e-5 * r.3.abs().max(1.0), "{what}: distance {} vs reference {}", m.distance, r.3);
        // The warping path runs from (0, start) to (last, end) in unit steps.
        let first = m.path.first().copied().unwrap_or([9, 9]);
        let last = m.path.last().copied().unwrap_or([9, 9]);
        assert_eq!(first, [0, m.start_frame as u32], "{what}: path start");
        assert_eq!(last[1], m.end_frame as u32, "{what}: path end");
        for w in m.path.windows(2) {
            let (di, dj) = (w[1][0] - w[0][0], w[1][1] - w[0][1]);
            assert!(di <= 1 && dj <= 1 && di + dj >= 1, "{what}: bad step {w:?}");
        }
        // The path's own cost (step weights 1/2/1) is the match's cost and distance.
        {
            let (q, t) = (&query.features(params.origin).data, &index.clips[m.clip_index].features(params.origin).data);
            let d = |p: [u32; 2]| {
                let (i, j) = (p[0] as usize, p[1] as usize);
                common::ref_distance(params, &q[i * FRAME_FLOATS..(i + 1) * FRAME_FLOATS], &t[j * FRAME_FLOATS..(j + 1) * FRAME_FLOATS])
            };
            let mut cost = 2.0 * d(m.path[0]);
            for w in m.path.windows(2) {
                let diag = w[1][0] != w[0][0] && w[1][1] != w[0][1];
                cost += if diag { 2.0 } else { 1.0 } * d(w[1]);
            }
            assert_eq!(last[0] as usize + 1, q.len() / FRAME_FLOATS, "{what}: path ends on the last query frame");
            assert!((cost - m.cost).abs() <= 1e-4 * m.cost.max(1.0), "{what}: path cost {cost} vs match cost {}", m.cost);
            let norm = cost / (q.len() / FRAME_FLOATS + m.length_frames) as f32;
            assert!((norm - m.distance).abs() <= 1e-4 * m.distance.max(1.0), "{what}: path distance {norm} vs {}", m.distance);
        }
    }
}

/// The web app's split search (www/search/client.js) done with the core's API: whole clips
/// dealt to `parts` indexes (each to the one holding the fewest frames, as the client places
/// them), round 1 probes every part, the probes are joined into one bound, round 2 searches
/// every part from it, and the answers are merged as `mergeOutcomes` does — best first by
/// distance, then clip in library order, then end — keeping the first `maxResults`. Returns
/// the merged answer (clip indexes of the whole library) and the bound round 2 started from.
///
/// Each part keeps what its probe builds for its round 2 (`SearchCache`, as the app's workers
/// do), and every cache first serves a decoy query (the query's features halved and shifted,
/// same length and parameters): the real probe must replace what the decoy left, so a cache
/// that kept another query's tables would show up as a result differing from the reference.
fn split_search(index: &FeatureIndex, parts: usize, query: &ClipFeatures, params: &SearchParams) -> (SearchOutcome, f32) {
    let mut owned: Vec<(FeatureIndex, Vec<usize>, usize)> = (0..parts).map(|_| (FeatureIndex::new(), Vec::new(), 0)).collect();
    for (ci, c) in index.clips.iter().enumerate() {
        let part = owned.iter_mut().min_by_key(|p| p.2).expect("parts > 0");
        part.0.add_features(c.clone());
        part.1.push(ci);
        part.2 += c.frame_count();
    }
    owned.retain(|p| !p.1.is_empty());
    // A part whose clips are all shorter than the shortest match has nothing to offer.
    fn usable<T>(r: &Result<T, SearchError>) -> bool {
        !matches!(r, Err(SearchError::QueryTooLong { .. }))
    }
    let decoy = features("decoy", query.features(Origin::Hips).data.iter().map(|v| v * 0.5 + 0.1).collect());
    let mut caches: Vec<SearchCache> = owned.iter().map(|_| SearchCache::default()).collect();
    for (p, cache) in owned.iter().zip(&mut caches) {
        let _ = search_probe_cached(&p.0, &decoy, params, cache);
    }
    let probes: Vec<Vec<f32>> = owned
        .iter()
        .zip(&mut caches)
        .map(|(p, cache)| search_probe_cached(&p.0, query, params, cache))
        .filter(|r| usable(r))
        .map(|r| r.expect("probe").distances)
        .collect();
    let lists: Vec<&[f32]> = probes.iter().map(|p| p.as_slice()).collect();
    let bound = joined_bound(&lists, params.max_results);
    let mut answers = Vec::new();
    for (p, cache) in owned.iter().zip(&mut caches) {
        let r = search_bounded_cached(&p.0, query, params, bound, cache, &mut no_progress());
        if !usable(&r) {
            continue;
        }
        let mut answer = r.expect("bounded search");
        for m in &mut answer.matches {
            m.clip_index = p.1[m.clip_index];
        }
        answers.push(answer);
    }
    // The merge the app's page asks the engine for (SearchIndex.mergeOutcomes).
    (merge_parts(answers, params.max_results), bound)
}

fn random_params(rng: &mut Rng, round: usize) -> SearchParams {
    let preset = BodyPreset::ALL[round % BodyPreset::ALL.len()];
    let mut p = SearchParams::preset(preset);
    p.max_results = [1, 3, 10, 40][rng.usize(4)];
    if round % 5 == 4 {
        // Random per-joint weights, some zero.
        for w in p.weights.iter_mut() {
            *w = if rng.f32() < 0.3 { 0.0 } else { rng.range(0.1, 3.0) };
        }
        p.weights[rng.usize(CANON_COUNT)] = 1.0;
    }
    p
}

#[test]
fn fast_equals_reference_on_random_motion() {
    let mut rng = Rng(0x5EED_0003);
    let mut clips: Vec<Vec<f32>> = (0..4).map(|k| random_motion(&mut rng, 250 + 120 * k)).collect();
    // Repetitive motion, like a dance's repeated step: one 40-frame phrase played over and over
    // at varying speeds. Many near-equal paths compete here, and many best paths are too long
    // or too short to report, which is where a pruned scan is most likely to go wrong.
    for _ in 0..2 {
        let phrase = random_motion(&mut rng, 40);
        let mut data = Vec::new();
        for _ in 0..12 {
            let frames = 30 + rng.usize(20);
            data.extend(warped_query(&mut rng, &phrase, 0, frames));
        }
        clips.push(data);
    }
    let mut index = FeatureIndex::new();
    for (k, c) in clips.iter().enumerate() {
        index.add_features(features(&format!("random{k}"), c.clone()));
    }
    let mut pruned = 0u64;
    let mut cells = 0u64;
    let mut bounded = 0usize;
    for round in 0..120 {
        let rows = 12 + rng.usize(30);
        let src = rng.usize(clips.len());
        let data = if round % 4 == 3 {
            random_motion(&mut rng, rows) // unrelated motion
        } else {
            let start = rng.usize(clips[src].len() / FRAME_FLOATS - 2 * rows);
            warped_query(&mut rng, &clips[src], start, rows)
        };
        let query = features("query", data);
        let mut params = random_params(&mut rng, round);
        let reference_all = reference_search(&index, &query, &params);
        if round % 2 == 1 {
            // A threshold between the best distances, so it bites.
            if let Some(r) = reference_all.get(reference_all.len() / 2) {
                params.threshold = Some(r.3);
            }
        }
        let reference = reference_search(&index, &query, &params);
        let fast = search(&index, &query, &params, &mut no_progress()).unwrap();
        let plain = search_plain(&index, &query, &params, &mut no_progress()).unwrap();
        // The library cut into 2–4 parts (clips split too: every clip is longer than 2·maxSpan).
        let threads = 2 + round % 3;
        let threaded = search_threads(&index, &query, &params, threads, &mut no_progress()).unwrap();
        let what = format!("round {round} ({rows} frames, {params:?})");
        assert_same(&format!("fast, {what}"), &fast, &reference, (&query, &index, &params));
        assert_same(&format!("fast on {threads} threads, {what}"), &threaded, &reference, (&query, &index, &params));
        assert_same(&format!("plain, {what}"), &plain, &reference, (&query, &index, &params));
        // The web app's workers: whole clips in 2–3 parts, round 2 from the joined probes' bound.
        let (split, bound) = split_search(&index, 2 + round % 2, &query, &params);
        assert_same(&format!("split in {} parts from bound {bound}, {what}", 2 + round % 2), &split, &reference, (&query, &index, &params));
        // The merged shortfall is the whole library's (every part's counts are exact when short).
        assert_eq!(split.shortfall, fast.shortfall, "{what}: merged shortfall");
        assert_eq!(split.stats.frames_searched, fast.stats.frames_searched, "{what}: merged frames searched");
        if let Some(kth) = reference.get(params.max_results - 1) {
            assert!(bound >= kth.3, "{what}: the joined bound {bound} is below the k-th result's distance {}", kth.3);
        }
        bounded += bound.is_finite() as usize;
        if round % 4 != 3 {
            assert!(!reference.is_empty(), "{what}: a query cut from the library should match");
        }
        pruned += fast.stats.distances_computed;
        cells += plain.stats.distances_computed;
    }
    println!("random exactness: 120 rounds; the fast search computed {:.1} % of the plain DP's frame distances; the split search's round 2 started from a finite joined bound in {bounded} rounds", 100.0 * pruned as f64 / cells as f64);
    // The joined bound is what makes round 2 prune: it must be finite wherever the probes can
    // find k far ends (every round asks for at most 40 of six clips of 250–700 frames).
    assert!(bounded >= 60, "the joined bound was finite in only {bounded} of 120 rounds");
}

/// A query that holds one pose finds its own exact copy at distance 0 (the old rule lost it:
/// its best unconstrained path into any end was one frame long and thrown away).
#[test]
fn held_pose_finds_its_own_copy() {
    let mut rng = Rng(0x401D);
    let mut data = random_motion(&mut rng, 600);
    let pose: Vec<f32> = data[100 * FRAME_FLOATS..101 * FRAME_FLOATS].to_vec();
    let (hold_start, hold_frames) = (300, 40);
    for f in hold_start..hold_start + hold_frames {
        data[f * FRAME_FLOATS..(f + 1) * FRAME_FLOATS].copy_from_slice(&pose);
    }
    let mut index = FeatureIndex::new();
    index.add_features(features("held", data));
    let query = features("q", pose.repeat(30));
    for k in [1, 5] {
        let params = SearchParams { max_results: k, ..SearchParams::default() };
        let reference = reference_search(&index, &query, &params);
        for (name, out) in [
            ("fast", search(&index, &query, &params, &mut no_progress()).unwrap()),
            ("plain", search_plain(&index, &query, &params, &mut no_progress()).unwrap()),
            ("fast on 3 threads", search_threads(&index, &query, &params, 3, &mut no_progress()).unwrap()),
        ] {
            assert_same(name, &out, &reference, (&query, &index, &params));
            let m = out.matches.first().unwrap_or_else(|| panic!("{name}: no result"));
            assert_eq!(m.distance, 0.0, "{name}: {m:?}");
            assert!(m.start_frame >= hold_start && m.end_frame < hold_start + hold_frames, "{name}: the match lies in the held stretch: {}..={}", m.start_frame, m.end_frame);
            assert_eq!(out.matches.len(), k, "{name}: {k} asked, the clip holds more admissible spans");
        }
    }
}

/// All-zero features (every frame distance 0): every admissible end is a match at distance 0,
/// and as many non-overlapping ones come back as were asked for.
#[test]
fn all_zero_features_give_results() {
    let mut index = FeatureIndex::new();
    index.add_features(features("zeros", vec![0.0; 400 * FRAME_FLOATS]));
    let query = features("q", vec![0.0; 20 * FRAME_FLOATS]);
    let params = SearchParams { max_results: 8, ..SearchParams::default() };
    let reference = reference_search(&index, &query, &params);
    for out in [
        search(&index, &query, &params, &mut no_progress()).unwrap(),
        search_plain(&index, &query, &params, &mut no_progress()).unwrap(),
        search_threads(&index, &query, &params, 2, &mut no_progress()).unwrap(),
    ] {
        assert_same("zeros", &out, &reference, (&query, &index, &params));
        assert_eq!(out.matches.len(), 8);
        assert!(out.matches.iter().all(|m| m.distance == 0.0));
        assert!(out.shortfall.is_none());
    }
}

/// The k-results guarantee: with no threshold, k non-overlapping admissible spans in the
/// library give k results — k exact copies of the query hidden in unrelated motion are all
/// found, best first at distance 0; k clips of novel motion give one result each; and when
/// the library holds fewer, the shortfall says how many ends there are and why.
#[test]
fn k_results_guarantee() {
    let mut rng = Rng(0xC0FE);
    let phrase = random_motion(&mut rng, 50);
    let mut data = random_motion(&mut rng, 200);
    let mut copies = Vec::new();
    for _ in 0..5 {
        copies.push(data.len() / FRAME_FLOATS);
        data.extend_from_slice(&phrase);
        let gap = 150 + rng.usize(100);
        data.extend(random_motion(&mut rng, gap));
    }
    let mut index = FeatureIndex::new();
    index.add_features(features("copies", data));
    let query = features("q", phrase.clone());
    let params = SearchParams { max_results: 5, ..SearchParams::default() };
    let reference = reference_search(&index, &query, &params);
    let out = search(&index, &query, &params, &mut no_progress()).unwrap();
    assert_same("copies", &out, &reference, (&query, &index, &params));
    let mut found: Vec<usize> = out.matches.iter().map(|m| m.start_frame).collect();
    found.sort();
    assert_eq!(found, copies, "every copy found");
    assert!(out.matches.iter().all(|m| m.distance == 0.0 && m.length_frames == 50));

    // Novel motion in k clips: each clip has an admissible span, so k results come back.
    let mut index = FeatureIndex::new();
    for k in 0..6 {
        index.add_features(features(&format!("c{k}"), random_motion(&mut rng, 40 + 10 * k)));
    }
    let query = features("q", random_motion(&mut rng, 40));
    let params = SearchParams { max_results: 6, ..SearchParams::default() };
    let reference = reference_search(&index, &query, &params);
    for out in [search(&index, &query, &params, &mut no_progress()).unwrap(), search_plain(&index, &query, &params, &mut no_progress()).unwrap()] {
        assert_same("novel", &out, &reference, (&query, &index, &params));
        assert_eq!(out.matches.len(), 6, "one per clip");
    }

    // Fewer than asked: the shortfall counts the admissible ends and those within the threshold.
    let params = SearchParams { max_results: 20, threshold: reference.get(2).map(|r| r.3), ..SearchParams::default() };
    let reference = reference_search(&index, &query, &params);
    let all_ends = common::reference_ends(&index, &query, &params);
    for out in [
        search(&index, &query, &params, &mut no_progress()).unwrap(),
        search_plain(&index, &query, &params, &mut no_progress()).unwrap(),
        search_threads(&index, &query, &params, 2, &mut no_progress()).unwrap(),
    ] {
        assert_same("short", &out, &reference, (&query, &index, &params));
        let s = out.shortfall.as_ref().expect("fewer than asked");
        assert_eq!((s.asked, s.shown), (20, out.matches.len()));
        assert_eq!(s.admissible_ends as usize, all_ends.len());
        let within = all_ends.iter().filter(|e| e.3 <= params.threshold.unwrap()).count();
        assert_eq!(s.ends_within_threshold as usize, within);
        assert!(within > out.matches.len(), "the others overlap the shown ones");
    }
}

/// The fast search's first pass lowers τ as it goes and keeps values summed under earlier,
/// higher τ; its marks are then re-checked under the final τ. Long clips where the good matches
/// lie late (after a long stretch of unrelated motion) make τ fall a long way during the pass:
/// the results must still be the brute force's.
#[test]
fn falling_bound_over_long_clips_keeps_exactness() {
    let mut rng = Rng(0xFA11_0016);
    let phrase = random_motion(&mut rng, 50);
    let mut index = FeatureIndex::new();
    for k in 0..2 {
        // Unrelated motion first, then the phrase repeated at varying speeds.
        let mut data = random_motion(&mut rng, 900 + 300 * k);
        for _ in 0..14 {
            let frames = 35 + rng.usize(30);
            data.extend(warped_query(&mut rng, &phrase, 0, frames));
        }
        index.add_features(features(&format!("long{k}"), data));
    }
    for round in 0..8 {
        let rows = 16 + rng.usize(24);
        let at = rng.usize(8);
        let query = features("query", warped_query(&mut rng, &phrase, at, rows));
        let mut params = SearchParams { max_results: [1, 4, 12, 30][round % 4], ..SearchParams::preset(BodyPreset::ALL[round % BodyPreset::ALL.len()]) };
        if round >= 6 {
            let all = reference_search(&index, &query, &params);
            params.threshold = all.get(all.len() / 2).map(|r| r.3);
        }
        let reference = reference_search(&index, &query, &params);
        let fast = search(&index, &query, &params, &mut no_progress()).unwrap();
        assert_same(&format!("long clips, round {round} ({rows} frames, k {})", params.max_results), &fast, &reference, (&query, &index, &params));
        // Split into parts that share τ: a part's bound lowers the others'.
        let threaded = search_threads(&index, &query, &params, 2 + round % 2, &mut no_progress()).unwrap();
        assert_same(&format!("long clips on threads, round {round} ({rows} frames, k {})", params.max_results), &threaded, &reference, (&query, &index, &params));
        // Two clips, two parts: each worker holds one, and prunes with the other's probe too.
        let (split, _) = split_search(&index, 2, &query, &params);
        assert_same(&format!("long clips split in 2 parts, round {round} ({rows} frames, k {})", params.max_results), &split, &reference, (&query, &index, &params));
        assert!(!fast.matches.is_empty(), "round {round}: the phrase is in the library");
    }
}
