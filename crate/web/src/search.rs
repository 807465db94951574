//! Search by example (spec §B–C): a `SearchIndex` of normalised canonical features, built
//! once per clip and searched with the exact fast subsequence DP. In the app it lives in a Web
//! Worker (www/search-worker.js): the main thread sends each clip's canonical positions
//! (`Library.searchFeatures`) and the worker searches off the UI thread with progress.

use std::cell::RefCell;
use std::ops::ControlFlow;

use js_sys::Float32Array;
use odori_core::canon::humanoid::{canonical_positions, Canon, CANON_COUNT};
use odori_core::canon::normalize::Origin;
use odori_core::search::{self, BodyPreset, ClipFeatures, FeatureIndex, MotionFeatures, SearchParams, StoredClip, DEFAULT_INDEX_FPS};
use odori_core::HumanoidStatus;
use serde::{Deserialize, Serialize};
use wasm_bindgen::prelude::*;

use crate::error::{from_js, to_js, OdoriError};
use crate::library::Library;

fn stored_err(e: search::StoredIndexError) -> OdoriError {
    let kind = match e {
        search::StoredIndexError::Version { .. } => "index-version",
        _ => "index-corrupt",
    };
    OdoriError::new(kind, e.to_string())
}

/// A content key as the page sees it: 32 hex digits.
fn key_hex(k: u128) -> String {
    format!("{k:032x}")
}

fn parse_key(s: &str) -> Result<u128, OdoriError> {
    (s.len() == 32).then(|| u128::from_str_radix(s, 16).ok()).flatten().ok_or_else(|| OdoriError::new("bad-argument", format!("'{s}' is not a content key (32 hex digits)")))
}

fn search_err(e: search::SearchError) -> OdoriError {
    let kind = match e {
        search::SearchError::Cancelled { .. } => "cancelled",
        search::SearchError::QueryTooLong { .. } => "query-too-long",
        _ => "search",
    };
    OdoriError::new(kind, e.to_string())
}

#[wasm_bindgen]
impl Library {
    /// Canonical joint positions of a humanoid clip resampled to the search rate (60 fps),
    /// flat `frames × 21 × 3`, for `SearchIndex.addFeatures` (transferable to a worker).
    /// Throws for a non-humanoid clip, naming why.
    #[wasm_bindgen(js_name = searchFeatures)]
    pub fn search_features(&self, id: u32) -> Result<Float32Array, OdoriError> {
        let e = self.entry(id)?;
        if let HumanoidStatus::NotHumanoid { reason } = &e.status {
            return Err(OdoriError::new("not-humanoid", format!("clip \"{}\" cannot be searched: {reason}", e.clip.name)));
        }
        let index = FeatureIndex::new();
        let clip = index.resampled(&e.clip);
        let p = canonical_positions(&clip, &e.humanoid);
        let flat: Vec<f32> = p.iter().flat_map(|v| v.to_array()).collect();
        Ok(Float32Array::from(flat.as_slice()))
    }

    /// Content key of a clip for the stored search index (32 hex digits): a hash of its name,
    /// frame rate, skeleton and every channel value, so a stored index can be checked against
    /// the library without indexing it again. Pass it to `SearchIndex.addFeatures`.
    #[wasm_bindgen(js_name = searchKey)]
    pub fn search_key(&self, id: u32) -> Result<String, OdoriError> {
        let e = self.entry(id)?;
        Ok(key_hex(search::clip_key(&e.clip.name, &e.clip)))
    }
}

#[derive(Deserialize, Default)]
#[serde(rename_all = "camelCase", default)]
struct JsQuery {
    clip_id: u32,
    start_frame: usize,
    end_frame: usize,
}

#[derive(Deserialize, Default)]
#[serde(rename_all = "camelCase", default)]
struct JsParams {
    preset: Option<BodyPreset>,
    weights: Option<Vec<f32>>,
    threshold: Option<f32>,
    max_results: Option<usize>,
}

impl JsParams {
    fn decode(params: JsValue) -> Result<SearchParams, OdoriError> {
        let p: JsParams = from_js(params, "search params", &["preset", "weights", "threshold", "maxResults"])?;
        let mut sp = SearchParams::preset(p.preset.unwrap_or(BodyPreset::WholeBody));
        if let Some(w) = p.weights {
            if w.len() != CANON_COUNT {
                return Err(OdoriError::new("bad-argument", format!("weights: {} values given, one per canonical joint (21) needed", w.len())));
            }
            sp.weights.copy_from_slice(&w);
        }
        sp.threshold = p.threshold;
        if let Some(m) = p.max_results {
            sp.max_results = m;
        }
        Ok(sp)
    }
}

/// Which search runs.
#[derive(Clone, Copy)]
enum Method {
    Fast,
    Plain,
    /// Round 2 of a split search, from this bound.
    Bounded(f32),
}

#[derive(Serialize)]
#[serde(rename_all = "camelCase")]
struct JsMatch<'a> {
    clip_id: u32,
    #[serde(flatten)]
    inner: &'a search::SearchMatch,
}

/// The search library, in one thread (a worker in the app).
#[wasm_bindgen]
pub struct SearchIndex {
    index: FeatureIndex,
    ids: Vec<u32>,
    /// Content key per clip (see `Library.searchKey`), parallel to `ids`.
    keys: Vec<u128>,
    /// What `probeFeatures` built from its query, for the `searchFeaturesBounded` that follows
    /// with the same query (the app's two rounds): cleared whenever clips change.
    cache: RefCell<search::SearchCache>,
}

impl Default for SearchIndex {
    fn default() -> Self {
        Self::new()
    }
}

#[wasm_bindgen]
impl SearchIndex {
    #[wasm_bindgen(constructor)]
    pub fn new() -> SearchIndex {
        SearchIndex { index: FeatureIndex::new(), ids: Vec::new(), keys: Vec::new(), cache: RefCell::default() }
    }

    /// The index in its stored binary form (versioned, checksummed; see `fromBytes`): every
    /// clip's normalised features and lower-bound boxes, with its id and content key.
    #[wasm_bindgen(js_name = toBytes)]
    pub fn to_bytes(&self) -> js_sys::Uint8Array {
        let clips: Vec<StoredClip> = self.ids.iter().zip(&self.keys).map(|(&id, &key)| StoredClip { id, key }).collect();
        let bytes = search::encode_index(&self.index, &clips);
        js_sys::Uint8Array::from(bytes.as_slice())
    }

    /// An index read back from `toBytes` output, with the clip ids it was stored with. Throws
    /// kind "index-version" for another format version and "index-corrupt" for damaged bytes.
    #[wasm_bindgen(js_name = fromBytes)]
    pub fn from_bytes(bytes: &[u8]) -> Result<SearchIndex, OdoriError> {
        let s = search::decode_index(bytes).map_err(stored_err)?;
        Ok(SearchIndex { ids: s.clips.iter().map(|c| c.id).collect(), keys: s.clips.iter().map(|c| c.key).collect(), index: s.index, cache: RefCell::default() })
    }

    /// Adds the clips of a stored index (`toBytes`) whose content key is in `keys`, under the
    /// id at the same place in `ids` (a reopened library gives its clips new ids). Returns the
    /// ids of the clips added; stored clips of other keys are left out (the library no longer
    /// has them), and ids not returned must be indexed from their features. Throws like
    /// `fromBytes`.
    #[wasm_bindgen(js_name = addBytes)]
    pub fn add_bytes(&mut self, bytes: &[u8], keys: Vec<String>, ids: Vec<u32>) -> Result<Vec<u32>, OdoriError> {
        self.cache.get_mut().clear();
        if keys.len() != ids.len() {
            return Err(OdoriError::new("bad-argument", format!("{} keys and {} ids: give one id per key", keys.len(), ids.len())));
        }
        let wanted = keys.iter().map(|k| parse_key(k)).collect::<Result<Vec<_>, _>>()?;
        let s = search::decode_index(bytes).map_err(stored_err)?;
        // Two clips of the same content (a file imported twice) have the same key: each
        // stored copy goes to the next id of that key not yet given one.
        let mut taken = vec![false; wanted.len()];
        let mut added = Vec::new();
        for (c, clip) in s.clips.into_iter().zip(s.index.clips) {
            if let Some(k) = (0..wanted.len()).find(|&k| !taken[k] && wanted[k] == c.key) {
                taken[k] = true;
                self.remove(ids[k]);
                self.index.clips.push(clip);
                self.ids.push(ids[k]);
                self.keys.push(c.key);
                added.push(ids[k]);
            }
        }
        Ok(added)
    }

    /// Key of a library (32 hex digits) from its clips' content keys in library order: what a
    /// stored index is filed under.
    #[wasm_bindgen(js_name = libraryKey)]
    pub fn library_key(keys: Vec<String>) -> Result<String, OdoriError> {
        let keys = keys.iter().map(|k| parse_key(k)).collect::<Result<Vec<_>, _>>()?;
        Ok(key_hex(search::library_key(DEFAULT_INDEX_FPS, keys)))
    }

    /// The indexed clips' ids, in index order.
    #[wasm_bindgen(getter, js_name = clipIds)]
    pub fn clip_ids(&self) -> Vec<u32> {
        self.ids.clone()
    }

    /// The indexed clips' content keys, in index order.
    #[wasm_bindgen(getter, js_name = clipKeys)]
    pub fn clip_keys(&self) -> Vec<String> {
        self.keys.iter().map(|&k| key_hex(k)).collect()
    }

    /// Frames indexed, over all clips.
    #[wasm_bindgen(getter, js_name = totalFrames)]
    pub fn total_frames(&self) -> usize {
        self.index.total_frames()
    }

    /// Bytes of memory the index holds now: features, boxes, and what searches built on first
    /// use (the distance's lane layout, shoulder-origin features).
    #[wasm_bindgen(getter, js_name = heapBytes)]
    pub fn heap_bytes(&self) -> f64 {
        self.index.heap_bytes() as f64
    }

    /// Frame rate of every indexed clip's features (query and result frames count at it).
    #[wasm_bindgen(getter)]
    pub fn fps(&self) -> f32 {
        DEFAULT_INDEX_FPS
    }

    /// Adds a clip from `Library.searchFeatures` under the library's clip id.
    /// `key`: the clip's content key (`Library.searchKey`); without it the key is a hash of
    /// the positions themselves.
    #[wasm_bindgen(js_name = addFeatures)]
    pub fn add_features(&mut self, clip_id: u32, name: String, positions: Float32Array, key: Option<String>) -> Result<usize, OdoriError> {
        self.cache.get_mut().clear();
        let key = key.as_deref().map(parse_key).transpose()?;
        let flat = positions.to_vec();
        if flat.is_empty() || flat.len() % (CANON_COUNT * 3) != 0 {
            return Err(OdoriError::new("bad-argument", format!("features of \"{name}\": {} values is not a whole number of 21-joint frames", flat.len())));
        }
        let pts: Vec<glam::Vec3> = flat.chunks_exact(3).map(|c| glam::Vec3::new(c[0], c[1], c[2])).collect();
        self.remove(clip_id);
        let key = key.unwrap_or_else(|| search::positions_key(&name, &pts));
        let k = self.index.add_features(ClipFeatures::new(name, DEFAULT_INDEX_FPS, MotionFeatures::from_positions(&pts)));
        self.ids.push(clip_id);
        self.keys.push(key);
        Ok(k)
    }

    /// Adds a clip straight from a library in the same thread.
    #[wasm_bindgen(js_name = addFromLibrary)]
    pub fn add_from_library(&mut self, library: &Library, clip_id: u32) -> Result<usize, OdoriError> {
        self.cache.get_mut().clear();
        let f = library.search_features(clip_id)?;
        let name = library.entry(clip_id)?.clip.name.clone();
        let key = library.search_key(clip_id)?;
        self.add_features(clip_id, name, f, Some(key))
    }

    /// Drops a clip; false when it was not indexed.
    pub fn remove(&mut self, clip_id: u32) -> bool {
        self.cache.get_mut().clear();
        match self.ids.iter().position(|&i| i == clip_id) {
            Some(k) => {
                self.ids.remove(k);
                self.keys.remove(k);
                self.index.clips.remove(k);
                true
            }
            None => false,
        }
    }

    #[wasm_bindgen(getter, js_name = clipCount)]
    pub fn clip_count(&self) -> usize {
        self.ids.len()
    }

    fn position(&self, clip_id: u32) -> Result<usize, OdoriError> {
        self.ids
            .iter()
            .position(|&i| i == clip_id)
            .ok_or_else(|| OdoriError::new("not-found", format!("clip {clip_id} is not in the search index (not humanoid, or not added)")))
    }

    /// Searches every indexed clip for the query (`{ clipId, startFrame, endFrame }`, frames
    /// at `fps`, end exclusive) with `{ preset?, weights?, threshold?, maxResults? }`.
    /// `progress(framesDone, framesTotal)` is called between chunks; returning `false` cancels
    /// (throws kind "cancelled"); a callback that throws stops
    /// the search too, which then throws kind "callback" carrying the callback's message. Returns `{ matches: [{ clipId, clipIndex, clipName,
    /// startFrame, endFrame, lengthFrames, startSecs, endSecs, distance, cost, path }],
    /// skipped, stats, shortfall }`, best first.
    ///
    /// The rule (spec §C): a match is a warping path of the symmetric slope-constrained steps
    /// (P = 1), so it spans between about ½ and 2 times the query; its distance is its cost
    /// divided by its total step weight (query frames + span); for each end the match is the
    /// path of least distance over every start; results are the best ends, each kept unless
    /// it shares more than half of the shorter span with a better one in the same clip, up to
    /// `maxResults` and within `threshold`. `shortfall` (null when enough came back) says how
    /// many admissible match ends the library has and how many are within the threshold, so
    /// the rest were left out for overlapping a shown match.
    pub fn search(
        &self,
        #[wasm_bindgen(unchecked_param_type = "SearchQuery")] query: JsValue,
        #[wasm_bindgen(unchecked_param_type = "SearchParamsJs | undefined")] params: JsValue,
        progress: Option<js_sys::Function>,
    ) -> Result<JsValue, OdoriError> {
        let query = self.query(query)?;
        self.run(&query, params, progress, Method::Fast)
    }

    /// The plain DP (every cell computed, nothing pruned): the same arguments and results as
    /// `search`, for benchmarks and as the reference the fast search is checked against.
    #[wasm_bindgen(js_name = searchPlain)]
    pub fn search_plain(
        &self,
        #[wasm_bindgen(unchecked_param_type = "SearchQuery")] query: JsValue,
        #[wasm_bindgen(unchecked_param_type = "SearchParamsJs | undefined")] params: JsValue,
        progress: Option<js_sys::Function>,
    ) -> Result<JsValue, OdoriError> {
        let query = self.query(query)?;
        self.run(&query, params, progress, Method::Plain)
    }

    /// The normalised features (hip origin, body heights, flat `frames × 21 × 3`) of a query
    /// range of an indexed clip, for `searchFeatures` in other indexes (the app splits the
    /// library over several workers and sends every one the same query).
    #[wasm_bindgen(js_name = queryFeatures)]
    pub fn query_features(&self, #[wasm_bindgen(unchecked_param_type = "SearchQuery")] query: JsValue) -> Result<Float32Array, OdoriError> {
        let q = self.query(query)?;
        Ok(Float32Array::from(q.features(Origin::Hips).data.as_slice()))
    }

    /// `search` with the query given as normalised features from `queryFeatures`.
    #[wasm_bindgen(js_name = searchFeatures)]
    pub fn search_features(
        &self,
        features: Float32Array,
        #[wasm_bindgen(unchecked_param_type = "SearchParamsJs | undefined")] params: JsValue,
        progress: Option<js_sys::Function>,
    ) -> Result<JsValue, OdoriError> {
        let query = feature_query(features)?;
        self.run(&query, params, progress, Method::Fast)
    }

    /// Round 1 of a search split over several indexes that each hold whole clips (the app's
    /// workers): for query features from `queryFeatures` and the same params as `search`, the
    /// `{ distances, distancesComputed }`: the distances of real admissible paths this index's
    /// probe found, pairwise far apart, best first, at most `maxResults` (none for more than
    /// 32), and the work done. The k-th smallest over every index's lists (k = `maxResults`;
    /// +Infinity when they hold fewer) bounds the whole library's k-th result; pass it to
    /// `searchFeaturesBounded` in every index.
    #[wasm_bindgen(js_name = probeFeatures, unchecked_return_type = "{ distances: number[]; distancesComputed: number }")]
    pub fn probe_features(&self, features: Float32Array, #[wasm_bindgen(unchecked_param_type = "SearchParamsJs | undefined")] params: JsValue) -> Result<JsValue, OdoriError> {
        let query = feature_query(features)?;
        let sp = JsParams::decode(params)?;
        let probe = self.with_cache(|cache| search::search_probe_cached(&self.index, &query, &sp, cache)).map_err(search_err)?;
        Ok(to_js(&probe))
    }

    /// Round 2 of a split search: `searchFeatures` with its bound taken from every index's
    /// `probeFeatures` (the k-th smallest of their union) instead of this index's own probe.
    /// Merging every index's matches best first (distance, then clip in library order, then end
    /// frame) and keeping `maxResults` gives exactly `search` over the whole library.
    #[wasm_bindgen(js_name = searchFeaturesBounded)]
    pub fn search_features_bounded(
        &self,
        features: Float32Array,
        #[wasm_bindgen(unchecked_param_type = "SearchParamsJs | undefined")] params: JsValue,
        bound: f64,
        progress: Option<js_sys::Function>,
    ) -> Result<JsValue, OdoriError> {
        let query = feature_query(features)?;
        self.run(&query, params, progress, Method::Bounded(bound as f32))
    }

    /// The bound round 2 of a split search starts from: the `maxResults`-th smallest of every
    /// part's `probeFeatures` distances (+Infinity when they hold fewer). The proof that it
    /// bounds the whole library's k-th result is at `joined_bound` in the core's search module.
    #[wasm_bindgen(js_name = joinedBound)]
    pub fn joined_bound(#[wasm_bindgen(unchecked_param_type = "Float32Array[]")] lists: js_sys::Array, max_results: u32) -> Result<f32, OdoriError> {
        let lists = lists
            .iter()
            .enumerate()
            .map(|(i, v)| v.dyn_into::<Float32Array>().map(|a| a.to_vec()).map_err(|_| OdoriError::new("bad-argument", format!("lists[{i}] must be a Float32Array"))))
            .collect::<Result<Vec<_>, _>>()?;
        let refs: Vec<&[f32]> = lists.iter().map(Vec::as_slice).collect();
        Ok(search::joined_bound(&refs, max_results as usize))
    }

    /// Merges the parts' round-2 answers (`searchFeaturesBounded` in every worker) into the
    /// whole library's answer, exactly (the core's `merge_parts`): matches best first by
    /// distance, then clip in library order (`order`: clip ids in library order), then end
    /// frame, cut to `maxResults`; work counters summed (`stats.workers`: the parts merged);
    /// a shortfall with the parts' counts summed when the merged answer is short. Throws
    /// "bad-argument" for an answer that is not a search outcome or a clip not in `order`.
    #[wasm_bindgen(js_name = mergeOutcomes, unchecked_return_type = "SearchOutcome")]
    pub fn merge_outcomes(#[wasm_bindgen(unchecked_param_type = "SearchOutcome[]")] outcomes: js_sys::Array, order: Vec<u32>, max_results: u32) -> Result<JsValue, OdoriError> {
        let rank: std::collections::HashMap<u32, usize> = order.iter().enumerate().map(|(k, &id)| (id, k)).collect();
        let workers = outcomes.length() as usize;
        let mut parts = Vec::with_capacity(workers);
        for (k, o) in outcomes.iter().enumerate() {
            let o: PartOutcome = serde_wasm_bindgen::from_value(o).map_err(|e| OdoriError::new("bad-argument", format!("outcome {k}: {e}")))?;
            let matches = o
                .matches
                .into_iter()
                .map(|m| {
                    let at = rank.get(&m.clip_id).copied().ok_or_else(|| OdoriError::new("bad-argument", format!("outcome {k}: clip {} is not in the library order", m.clip_id)))?;
                    Ok(search::SearchMatch { clip_index: at, ..m.inner })
                })
                .collect::<Result<Vec<_>, OdoriError>>()?;
            parts.push(search::SearchOutcome { matches, skipped: o.skipped, stats: o.stats, shortfall: o.shortfall });
        }
        let merged = search::merge_parts(parts, max_results as usize);
        let matches: Vec<JsMatch> = merged.matches.iter().map(|m| JsMatch { clip_id: order.get(m.clip_index).copied().unwrap_or(u32::MAX), inner: m }).collect();
        let mut stats = to_json(&merged.stats);
        if let Some(s) = stats.as_object_mut() {
            s.insert("workers".into(), workers.into());
        }
        Ok(to_js(&serde_json::json!({
            "matches": to_json(&matches),
            "skipped": to_json(&merged.skipped),
            "stats": stats,
            "shortfall": to_json(&merged.shortfall),
        })))
    }

    /// `searchPlain` with the query given as normalised features from `queryFeatures` (the
    /// benchmark's baseline for a query from outside the index).
    #[wasm_bindgen(js_name = searchPlainFeatures)]
    pub fn search_plain_features(
        &self,
        features: Float32Array,
        #[wasm_bindgen(unchecked_param_type = "SearchParamsJs | undefined")] params: JsValue,
        progress: Option<js_sys::Function>,
    ) -> Result<JsValue, OdoriError> {
        let query = feature_query(features)?;
        self.run(&query, params, progress, Method::Plain)
    }

    fn query(&self, query: JsValue) -> Result<ClipFeatures, OdoriError> {
        let q: JsQuery = from_js(query, "query", &["clipId", "startFrame", "endFrame"])?;
        let k = self.position(q.clip_id)?;
        self.index.query_range(k, q.start_frame, q.end_frame).map_err(search_err)
    }

    /// `f` with the kept cache, or with a fresh one if it is in use (a progress callback that
    /// calls back into this index: the app's worker never does, but a panic must not reach JS).
    fn with_cache<T>(&self, f: impl FnOnce(&mut search::SearchCache) -> T) -> T {
        match self.cache.try_borrow_mut() {
            Ok(mut kept) => f(&mut kept),
            Err(_) => f(&mut search::SearchCache::default()),
        }
    }

    fn run(&self, query: &ClipFeatures, params: JsValue, progress: Option<js_sys::Function>, method: Method) -> Result<JsValue, OdoriError> {
        let sp = JsParams::decode(params)?;
        // A callback that throws stops the search, and the caller gets an error saying so (with
        // the callback's own message): ignoring it would hide a bug in the caller's UI code.
        let mut thrown: Option<String> = None;
        let mut cb = |pr: search::SearchProgress| -> ControlFlow<()> {
            match &progress {
                Some(f) => match f.call2(&JsValue::NULL, &JsValue::from(pr.frames_done as f64), &JsValue::from(pr.frames_total as f64)) {
                    Ok(v) if v.as_bool() == Some(false) => ControlFlow::Break(()),
                    Ok(_) => ControlFlow::Continue(()),
                    Err(e) => {
                        let message = e
                            .dyn_ref::<js_sys::Error>()
                            .map(|e| String::from(e.message()))
                            .or_else(|| e.as_string())
                            .unwrap_or_else(|| "a value that is not an Error".into());
                        thrown = Some(message);
                        ControlFlow::Break(())
                    }
                },
                None => ControlFlow::Continue(()),
            }
        };
        let out = match method {
            Method::Fast => search::search(&self.index, query, &sp, &mut cb),
            Method::Plain => search::search_plain(&self.index, query, &sp, &mut cb),
            Method::Bounded(bound) => self.with_cache(|cache| search::search_bounded_cached(&self.index, query, &sp, bound, cache, &mut cb)),
        };
        if let Some(message) = thrown {
            return Err(OdoriError::new("callback", format!("the progress callback threw ({message}); the search was stopped")));
        }
        let out = out.map_err(search_err)?;
        let matches: Vec<JsMatch> = out.matches.iter().map(|m| JsMatch { clip_id: self.ids[m.clip_index], inner: m }).collect();
        Ok(to_js(&serde_json::json!({
            "matches": to_json(&matches),
            "skipped": to_json(&out.skipped),
            "stats": to_json(&out.stats),
            "shortfall": to_json(&out.shortfall),
        })))
    }

    /// x, y, z of one canonical joint ("rightHand", ...) over an indexed clip, normalised
    /// (body heights; hip origin, or shoulder origin when `shoulders` is true), for plots.
    #[wasm_bindgen(js_name = jointCurve, unchecked_return_type = "JointCurve")]
    pub fn joint_curve(&self, clip_id: u32, joint: &str, shoulders: bool) -> Result<JsValue, OdoriError> {
        let c = Canon::ALL
            .into_iter()
            .find(|c| c.name() == joint)
            .ok_or_else(|| OdoriError::new("bad-argument", format!("'{joint}' is not a canonical joint name")))?;
        let origin = if shoulders { Origin::Shoulders } else { Origin::Hips };
        let k = self.position(clip_id)?;
        Ok(to_js(&self.index.joint_curve(k, c, origin).map_err(search_err)?))
    }
}

fn to_json<T: Serialize>(v: &T) -> serde_json::Value {
    serde_json::to_value(v).unwrap_or(serde_json::Value::Null)
}

#[wasm_bindgen(typescript_custom_section)]
const TS_SEARCH: &'static str = r#"
export interface SearchQuery { clipId: number; startFrame: number; endFrame: number; }
export type BodyPreset = "wholeBody" | "upperBody" | "lowerBody" | "arms" | "leftArm" | "rightArm" | "legs" | "feetOnly";
export interface SearchParamsJs { preset?: BodyPreset; weights?: number[]; threshold?: number; maxResults?: number; }
export interface SearchShortfall { asked: number; shown: number; admissibleEnds: number; endsWithinThreshold: number; threshold: number | null; }
export interface SearchMatch { clipId: number; clipIndex: number; clipName: string; startFrame: number; endFrame: number; lengthFrames: number; startSecs: number; endSecs: number; distance: number; cost: number; path: [number, number][]; }
export interface SearchOutcome { matches: SearchMatch[]; skipped: { name: string; reason: string }[]; stats: { framesSearched: number; cellsTotal: number; distancesComputed: number; workers?: number }; shortfall: SearchShortfall | null; }
export interface JointCurve { joint: string; fps: number; x: number[]; y: number[]; z: number[]; }
"#;

/// Floats per frame of the search's features and `Library.searchFeatures` (x, y, z of each
/// canonical joint): the stride a page walks those arrays with.
#[wasm_bindgen(js_name = searchFrameFloats)]
pub fn search_frame_floats() -> u32 {
    search::FRAME_FLOATS as u32
}

/// A match as a part (a worker's index) returned it, read back for the merge.
#[derive(Deserialize)]
#[serde(rename_all = "camelCase")]
struct PartMatch {
    clip_id: u32,
    #[serde(flatten)]
    inner: search::SearchMatch,
}

/// One part's answer as `searchFeaturesBounded` returned it.
#[derive(Deserialize)]
#[serde(rename_all = "camelCase")]
struct PartOutcome {
    matches: Vec<PartMatch>,
    #[serde(default)]
    skipped: Vec<search::SkippedClip>,
    stats: search::SearchStats,
    shortfall: Option<search::Shortfall>,
}

/// One body-part preset as the page offers it (`bodyVocabulary`).
#[derive(Serialize)]
#[serde(rename_all = "camelCase")]
struct PresetInfo {
    name: BodyPreset,
    joints: Vec<&'static str>,
    /// Normalised about the shoulders (the arm-only presets, spec §B.1), else the hips.
    shoulders: bool,
}

/// The body's vocabulary, from the one place the engine keeps it (`canon::body_vocabulary`):
/// `{ joints: string[] (the 21 canonical joints, camelCase, in index order), regions,
/// searchPresets, compositionParts: { name, regions, joints }[] (the body's regions, the search
/// presets in UI order, the parts text composition switches), presets: { name, joints,
/// shoulders }[] (the search presets with where they are normalised) }`. The page builds its
/// joint lists and body-part choices from it instead of copying them.
#[wasm_bindgen(
    js_name = bodyVocabulary,
    unchecked_return_type = "{ joints: string[]; regions: NamedBodyPart[]; searchPresets: NamedBodyPart[]; compositionParts: NamedBodyPart[]; presets: { name: BodyPreset; joints: string[]; shoulders: boolean }[] }"
)]
pub fn body_vocabulary() -> JsValue {
    #[derive(Serialize)]
    struct Vocabulary {
        #[serde(flatten)]
        body: odori_core::canon::BodyVocabulary,
        presets: Vec<PresetInfo>,
    }
    let presets = BodyPreset::ALL
        .iter()
        .map(|&p| PresetInfo { name: p, joints: p.joints().into_iter().map(Canon::name).collect(), shoulders: matches!(p.origin(), Origin::Shoulders) })
        .collect();
    to_js(&Vocabulary { body: odori_core::canon::body_vocabulary(), presets })
}

#[wasm_bindgen(typescript_custom_section)]
const BODY_PART_TS: &str = r#"
/** A named part of the body (`bodyVocabulary()`): its name as the API spells it, the regions it
 * is made of and their canonical joints. */
export interface NamedBodyPart { name: string; regions: string[]; joints: string[] }
"#;

/// A query given as normalised features (flat `frames × 21 × 3`, hip origin), checked.
fn feature_query(features: Float32Array) -> Result<ClipFeatures, OdoriError> {
    let data = features.to_vec();
    if data.is_empty() || data.len() % (CANON_COUNT * 3) != 0 || data.iter().any(|x| !x.is_finite()) {
        return Err(OdoriError::new("bad-argument", format!("query features: {} values is not a whole number of finite 21-joint frames", data.len())));
    }
    Ok(ClipFeatures::new("query", DEFAULT_INDEX_FPS, MotionFeatures { origin: Origin::Hips, data }))
}
