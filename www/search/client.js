// Talks to the search workers. The library is split across several Web Workers (one per core,
// at most four), each holding whole clips, balanced by frames; a search sends every worker the
// same normalised query and has the engine merge their answers exactly (`mergeOutcomes`: the
// core's `merge_parts`, which states why the merge is exact).
// With more than one worker a search runs in two rounds, so that every worker prunes with the
// whole library's bound and not only its own part's (a worker whose own best matches are poor
// would otherwise do most of the work): round 1, each worker's cheap probe returns distances of
// real admissible paths whose ends are pairwise far apart (`probeFeatures`); their union's
// k-th smallest (`joinedBound`, asked of the engine) bounds the whole library's k-th result
// (the proof is at `joined_bound` in crate/core/src/search/mod.rs); round 2, each worker
// searches its clips from that bound (`searchFeaturesBounded`).
// Cancel terminates the workers (a running DP cannot be interrupted from outside) and starts
// fresh ones with the same clips.
//
// With an index store (www/project/index-store.js) the index is not built again on every
// visit: clips are added in batches; each batch's clips are looked up by content key in the
// stored libraries (the store's catalog says which clips each holds), the clips found are read
// back, and only the others are indexed from their features. Once the library has been still
// for a moment the workers' indexes are saved under the library's key (its clips' content keys
// in library order). `indexStats` says what came from where.
import { SearchIndex, searchFrameFloats } from "../pkg/odori.js";

const SAVE_AFTER_MS = 1500;
/** Longest a stored index's clips wait for the library's before the index is saved without them. */
const RESERVE_MS = 20000;
const WORKERS = Math.max(1, Math.min(4, (typeof navigator !== "undefined" && navigator.hardwareConcurrency) || 2));

export class SearchClient {
  /**
   * @param {{ store?: import("../project/index-store.js").IndexStore | null,
   *   libraryKey?: (keys: string[]) => string, onNote?: (message: string) => void }} [options]
   *   `store` keeps the index between visits; `libraryKey` is `SearchIndex.libraryKey`.
   */
  constructor(library, workers = WORKERS, options = {}) {
    this.library = library;
    this.store = options.store || null;
    this.keyOf = options.libraryKey || null;
    this.onNote = options.onNote || null;
    /** id -> { name, key, frames, worker (-1: not placed yet), positions (kept only without a store, for a respawn) } */
    this.features = new Map();
    /** Clip ids waiting for the next batch (store mode). */
    this.queued = [];
    /** Settles when every batch so far is in the workers. */
    this.loading = Promise.resolve();
    this.batching = false;
    this.saveTimer = 0;
    /** Parts of stored indexes the workers keep for clips still to come: `{ n, worker, keys }`. */
    this.reserve = [];
    /** Stored libraries read this session (each at most once), and parts handed out so far. */
    this.fetched = new Set();
    this.parts = 0;
    this.reserveAt = 0;
    this.saving = null;
    /** Where the index came from: clips restored from the store and built, times, the last save. */
    this.indexStats = { restored: 0, built: 0, restoreMs: 0, storedKey: null, libraryKey: null, savedKey: null, savedBytes: 0, saves: 0, note: null };
    this.pending = new Map();  // token -> { resolve, reject, onProgress }
    this.token = 0;
    this.workerCount = workers;
    this.spawn();
  }

  spawn() {
    this.workers = [];
    for (let k = 0; k < this.workerCount; k++) {
      const w = new Worker(new URL("../search-worker.js", import.meta.url), { type: "module" });
      w.onmessage = (ev) => this.receive(ev.data);
      w.onerror = (ev) => {
        for (const p of this.pending.values()) p.reject(new Error(`search worker failed: ${ev.message}`));
        this.pending.clear();
      };
      this.workers.push({ worker: w, frames: 0 });
    }
    if (this.store) {
      // Fresh workers: every clip goes through a batch again (from the store when saved).
      Object.assign(this, { reserve: [], fetched: new Set(), reserveAt: 0 });
      for (const [id, f] of this.features) { f.worker = -1; this.queued.push(id); }
      if (this.features.size) this.batch();
    } else {
      for (const [id, f] of this.features) this.place(id, f, f.positions.slice());
    }
  }

  /** Sends a clip's positions to the worker holding the fewest frames. */
  place(id, f, positions) {
    const slot = this.workers.reduce((a, b) => (b.frames < a.frames ? b : a));
    f.frames = positions.length / searchFrameFloats();
    slot.frames += f.frames;
    f.worker = this.workers.indexOf(slot);
    slot.worker.postMessage({ type: "add", id, name: f.name, positions, key: f.key || undefined }, [positions.buffer]);
  }

  /** The library's key (store mode): its clips' content keys in library order. */
  libraryKey() {
    return this.keyOf([...this.features.values()].map((f) => f.key));
  }

  note(message) {
    this.indexStats.note = message;
    if (this.onNote) this.onNote(message);
  }

  /** Runs a batch of added clips after the current task (a report's clips come together). */
  batch() {
    if (this.batching) return;
    this.batching = true;
    this.loading = this.loading.then(() => { this.batching = false; return this.flush(); }).catch((e) => this.note(`search index: ${e.message}`));
  }

  /**
   * Indexes the queued clips: the stored parts that hold clips of the same content are handed
   * to the workers to keep (`reserveFor`), the clips are taken from them ("load"), and only the
   * others are indexed from their features. The app adds its clips in several batches on
   * opening (the built-in clip first, the project's once it is read back), so the parts are
   * kept until every clip of theirs is taken or the next save.
   */
  async flush() {
    const ids = [...new Set(this.queued.splice(0))].filter((id) => this.features.has(id) && this.features.get(id).worker < 0);
    if (!ids.length) return;
    const t0 = performance.now();
    await this.reserveFor(ids);
    const restored = new Set();
    for (const part of this.reserve) {
      const left = [...part.keys];
      const take = [];
      for (const id of ids) {
        const k = left.indexOf(this.features.get(id).key);
        if (k >= 0 && !restored.has(id)) { left.splice(k, 1); take.push(id); }
      }
      if (!take.length) continue;
      try {
        const r = await this.request(part.worker, { type: "load", part: part.n, keys: take.map((id) => this.features.get(id).key), ids: take });
        this.workers[part.worker].frames = r.totalFrames;
        for (const id of r.added) {
          const f = this.features.get(id);
          if (!f) { this.workers[part.worker].worker.postMessage({ type: "remove", id }); continue; }
          f.worker = part.worker;
          restored.add(id);
          part.keys.splice(part.keys.indexOf(f.key), 1);
        }
      } catch (e) {
        this.note(`The stored search index could not be used (${e.message}); its clips are indexed again.`);
        part.keys = [];
      }
      if (!part.keys.length) this.workers[part.worker].worker.postMessage({ type: "drop", part: part.n });
    }
    this.reserve = this.reserve.filter((p) => p.keys.length);
    const rest = ids.filter((id) => !restored.has(id) && this.features.has(id));
    for (const id of rest) {
      try { this.place(id, this.features.get(id), this.library.searchFeatures(id)); } catch (e) { this.note(`${this.features.get(id).name}: ${e.message}`); this.features.delete(id); }
    }
    const key = this.libraryKey();
    Object.assign(this.indexStats, { restored: this.indexStats.restored + restored.size, built: this.indexStats.built + rest.length, restoreMs: performance.now() - t0, libraryKey: key });
    if (key === this.indexStats.storedKey && rest.length === 0) clearTimeout(this.saveTimer); // the store has this very library
    else this.scheduleSave();
  }

  /**
   * Makes sure the workers keep the stored parts that hold the batch's clips: for the keys no
   * kept part has, the store's catalog (which clips each stored library holds, without its
   * bytes) names the record holding most of them (the newest on a tie); it is read once per
   * session and its parts handed to the workers. A clip no stored library holds costs one
   * catalog read.
   */
  async reserveFor(ids) {
    const kept = this.reserve.flatMap((p) => p.keys);
    const missing = [];
    for (const id of ids) {
      const key = this.features.get(id).key;
      const k = kept.indexOf(key);
      if (k >= 0) kept.splice(k, 1); else missing.push(key);
    }
    if (!missing.length) return;
    let catalog;
    try {
      catalog = await this.store.catalog();
    } catch (e) {
      return this.note(`The stored search index could not be read (${e.message}); the library is indexed again.`);
    }
    for (;;) {
      const best = catalog.filter((r) => !this.fetched.has(r.key))
        .map((r) => ({ r, n: missing.filter((k) => r.clipKeys.includes(k)).length }))
        .filter((c) => c.n > 0)
        .sort((a, b) => b.n - a.n || b.r.savedAt - a.r.savedAt)[0];
      if (!best) return;
      this.fetched.add(best.r.key);
      let rec;
      try { rec = await this.store.get(best.r.key); } catch (e) { this.note(`The stored search index could not be read (${e.message}); its clips are indexed again.`); }
      if (!rec) continue;
      if (!this.indexStats.storedKey) this.indexStats.storedKey = rec.key;
      if (!this.reserveAt) this.reserveAt = performance.now();
      await Promise.all(rec.parts.map((p) => {
        const n = this.parts++;
        const part = { n, worker: n % this.workers.length, keys: [...p.keys] };
        this.reserve.push(part);
        return this.request(part.worker, { type: "reserve", part: part.n, bytes: p.bytes }, null, p.bytes instanceof Blob ? [] : [p.bytes.buffer]);
      }));
      for (const k of best.r.clipKeys) { const i = missing.indexOf(k); if (i >= 0) missing.splice(i, 1); }
      if (!missing.length) return;
    }
  }

  scheduleSave() {
    clearTimeout(this.saveTimer);
    this.saveTimer = setTimeout(() => { this.saving = this.save().catch((e) => this.note(`The search index could not be stored (${e.message}); it is built again on the next visit.`)); }, SAVE_AFTER_MS);
  }

  /** Stores the workers' indexes under the library's key (skipped if the library changed meanwhile). */
  async save() {
    await this.loading;
    if (this.queued.length || this.batching) return this.scheduleSave();
    // While stored clips wait for their library clips (the project still being read back) the
    // library is not complete: wait, up to RESERVE_MS.
    if (this.reserve.length && performance.now() - this.reserveAt < RESERVE_MS) return this.scheduleSave();
    const key = this.libraryKey();
    const parts = await Promise.all(this.workers.map((_, k) => this.request(k, { type: "toBytes" })));
    const clips = parts.reduce((a, p) => a + p.keys.length, 0);
    if (this.libraryKey() !== key || clips !== this.features.size || this.queued.length) return this.scheduleSave();
    const bytes = await this.store.put(key, parts.filter((p) => p.keys.length).map((p) => ({ bytes: p.bytes, keys: p.keys, frames: p.frames })));
    Object.assign(this.indexStats, { savedKey: key, savedBytes: bytes, saves: this.indexStats.saves + 1, storedKey: key });
    // Parts kept since the page opened whose clips never came (the library lost them) go now.
    for (const part of this.reserve) this.workers[part.worker].worker.postMessage({ type: "drop", part: part.n });
    this.reserve = [];
  }

  receive(m) {
    const p = this.pending.get(m.token);
    if (!p) return;
    if (m.type === "progress") { if (p.onProgress) p.onProgress(m.done, m.total); return; }
    this.pending.delete(m.token);
    if (m.type === "error") { const e = new Error(m.message); e.kind = m.kind; p.reject(e); }
    else p.resolve(m.type === "curve" ? m.curve : m.type === "features" ? m.features : m.type === "result" ? m.outcome : m);
  }

  /** Indexes a library clip; false (with the reason) when it cannot be searched. */
  add(id) {
    const info = this.library.clip(id);
    if (info.humanoid.kind === "notHumanoid") return { ok: false, reason: info.humanoid.reason };
    if (this.features.has(id)) this.remove(id);
    if (this.store) {
      // frames: at the index's 60 fps, for balancing the workers (exact once placed).
      this.features.set(id, { name: info.name, key: this.library.searchKey(id), frames: Math.round((info.frames - 1) * 60 / (info.fps || 60)) + 1, worker: -1, positions: null });
      this.queued.push(id);
      this.batch();
      return { ok: true };
    }
    const f = { name: info.name, positions: this.library.searchFeatures(id), worker: 0 };
    this.features.set(id, f);
    this.place(id, f, f.positions.slice());
    return { ok: true };
  }

  /** A clip's canonical positions (`Library.searchFeatures`), made on first ask when the
   * index came from the store (they are not kept for every clip). */
  positions(id) {
    const f = this.features.get(id);
    if (!f) throw new Error(`clip ${id} is not in the search index`);
    if (!f.positions) f.positions = this.library.searchFeatures(id);
    return f.positions;
  }

  /** Forgets a clip removed from the library. */
  remove(id) {
    const f = this.features.get(id);
    if (!f) return;
    this.features.delete(id);
    if (f.worker < 0) return; // not in a worker yet: its batch skips it
    this.workers[f.worker].frames -= f.frames;
    this.workers[f.worker].worker.postMessage({ type: "remove", id });
    if (this.store) this.scheduleSave();
  }

  request(worker, msg, onProgress, transfer = []) {
    const token = ++this.token;
    return new Promise((resolve, reject) => {
      this.pending.set(token, { resolve, reject, onProgress });
      this.workers[worker].worker.postMessage({ ...msg, token }, transfer);
    });
  }

  /** Bytes of memory the workers' indexes hold, and their frames (`{ heapBytes, frames }`). */
  async memory() {
    await this.loading;
    const r = await Promise.all(this.workers.map((_, k) => this.request(k, { type: "memory" })));
    return { heapBytes: r.reduce((a, m) => a + m.heapBytes, 0), frames: r.reduce((a, m) => a + m.frames, 0) };
  }

  /** Searches every clip (see `SearchIndex.search`); progress sums the workers'. */
  async search(query, params, onProgress) {
    await this.loading;
    const owner = this.features.get(query.clipId);
    if (!owner) { const e = new Error(`clip ${query.clipId} is not in the search index`); e.kind = "not-found"; throw e; }
    const features = await this.request(owner.worker, { type: "queryFeatures", query });
    return this.searchFeatures(features, params, onProgress);
  }

  /** `search` for normalised query features (`SearchIndex.queryFeatures`), in two rounds when
   * more than one worker holds clips (see the top of this file). */
  async searchFeatures(features, params, onProgress) {
    await this.loading;
    const busy = this.workers.map((w, k) => k).filter((k) => [...this.features.values()].some((f) => f.worker === k));
    const k = params?.maxResults ?? 10;
    // A worker whose clips are all shorter than the shortest admissible match has nothing to
    // offer; any other failure (cancel, bad parameters) is the search's.
    const answers = (settled) => {
      const out = [];
      for (const s of settled) {
        if (s.status === "fulfilled") out.push(s.value);
        else if (s.reason.kind !== "query-too-long") throw s.reason;
      }
      if (out.length === 0) throw settled[0].reason;
      return out;
    };
    let bound;
    let probed = 0;
    if (busy.length > 1) {
      const probes = answers(await Promise.allSettled(busy.map((w) => this.request(w, { type: "probe", features, params }))));
      bound = joinedBound(probes.map((p) => p.distances), k);
      probed = probes.reduce((a, p) => a + p.distancesComputed, 0);
    }
    const done = new Map();
    const total = new Map();
    const report = () => { if (onProgress) onProgress([...done.values()].reduce((a, b) => a + b, 0), [...total.values()].reduce((a, b) => a + b, 0)); };
    const outcomes = answers(await Promise.allSettled(busy.map((w) => this.request(w, { type: "search", features, params, bound }, (d, t) => { done.set(w, d); total.set(w, t); report(); }))));
    const merged = mergeOutcomes(outcomes, [...this.features.keys()], k);
    merged.stats.distancesComputed += probed;
    merged.stats.bound = bound ?? null;
    return merged;
  }

  async curve(id, joint, shoulders = false) {
    await this.loading;
    const f = this.features.get(id);
    return this.request(f ? f.worker : 0, { type: "curve", id, joint, shoulders });
  }

  cancel() {
    for (const w of this.workers) w.worker.terminate();
    for (const p of this.pending.values()) { const e = new Error("search cancelled"); e.kind = "cancelled"; p.reject(e); }
    this.pending.clear();
    this.spawn();
  }
}

/** The bound round 2 starts from, asked of the engine (`SearchIndex.joinedBound`, the core's
 * `joined_bound`, where the proof is): the k-th smallest of every worker's probe distances, or
 * Infinity when they hold fewer than k together. */
export function joinedBound(lists, k) {
  return SearchIndex.joinedBound(lists.map((l) => Float32Array.from(l)), k);
}

/** Merges per-worker outcomes exactly, asked of the engine (`SearchIndex.mergeOutcomes`, the
 * core's `merge_parts`, which says why it is exact). `order` lists clip ids in library order. */
export function mergeOutcomes(outcomes, order, maxResults) {
  return SearchIndex.mergeOutcomes(outcomes, Uint32Array.from(order), maxResults);
}
