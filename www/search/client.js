// Talks to the search workers. The library is split across several Web Workers (one per core,
// at most four), each holding whole clips, balanced by frames; a search sends every worker the
// same normalised query and merges their answers exactly: matches only knock each other out
// within one clip, so each worker's best-first list is the whole library's list restricted to
// its clips, and the merged list is the best `maxResults` of their union in the same order
// (distance, then clip in library order, then end frame).
// Cancel terminates the workers (a running DP cannot be interrupted from outside) and starts
// fresh ones with the same clips.
const WORKERS = Math.max(1, Math.min(4, (typeof navigator !== "undefined" && navigator.hardwareConcurrency) || 2));

export class SearchClient {
  constructor(library, workers = WORKERS) {
    this.library = library;
    this.features = new Map(); // id -> { name, positions, worker }
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
    for (const [id, f] of this.features) this.place(id, f);
  }

  /** Sends a clip to the worker holding the fewest frames. */
  place(id, f) {
    const slot = this.workers.reduce((a, b) => (b.frames < a.frames ? b : a));
    slot.frames += f.positions.length / 63;
    f.worker = this.workers.indexOf(slot);
    slot.worker.postMessage({ type: "add", id, name: f.name, positions: f.positions.slice() });
  }

  receive(m) {
    const p = this.pending.get(m.token);
    if (!p) return;
    if (m.type === "progress") { if (p.onProgress) p.onProgress(m.done, m.total); return; }
    this.pending.delete(m.token);
    if (m.type === "error") { const e = new Error(m.message); e.kind = m.kind; p.reject(e); }
    else p.resolve(m.type === "curve" ? m.curve : m.type === "features" ? m.features : m.outcome);
  }

  /** Indexes a library clip; false (with the reason) when it cannot be searched. */
  add(id) {
    const info = this.library.clip(id);
    if (info.humanoid.kind === "notHumanoid") return { ok: false, reason: info.humanoid.reason };
    if (this.features.has(id)) this.remove(id);
    const f = { name: info.name, positions: this.library.searchFeatures(id), worker: 0 };
    this.features.set(id, f);
    this.place(id, f);
    return { ok: true };
  }

  /** Forgets a clip removed from the library. */
  remove(id) {
    const f = this.features.get(id);
    if (!f) return;
    this.workers[f.worker].frames -= f.positions.length / 63;
    this.workers[f.worker].worker.postMessage({ type: "remove", id });
    this.features.delete(id);
  }

  request(worker, msg, onProgress) {
    const token = ++this.token;
    return new Promise((resolve, reject) => {
      this.pending.set(token, { resolve, reject, onProgress });
      this.workers[worker].worker.postMessage({ ...msg, token });
    });
  }

  /** Searches every clip (see `SearchIndex.search`); progress sums the workers'. */
  async search(query, params, onProgress) {
    const owner = this.features.get(query.clipId);
    if (!owner) { const e = new Error(`clip ${query.clipId} is not in the search index`); e.kind = "not-found"; throw e; }
    const features = await this.request(owner.worker, { type: "queryFeatures", query });
    const busy = this.workers.map((w, k) => k).filter((k) => this.workers[k].frames > 0);
    const done = new Map();
    const total = new Map();
    const report = () => { if (onProgress) onProgress([...done.values()].reduce((a, b) => a + b, 0), [...total.values()].reduce((a, b) => a + b, 0)); };
    const settled = await Promise.allSettled(busy.map((k) => this.request(k, { type: "search", features, params }, (d, t) => { done.set(k, d); total.set(k, t); report(); })));
    const outcomes = [];
    for (const s of settled) {
      if (s.status === "fulfilled") outcomes.push(s.value);
      // A worker whose clips are all shorter than the shortest admissible match has nothing
      // to offer; any other failure (cancel, bad parameters) is the search's.
      else if (s.reason.kind !== "query-too-long") throw s.reason;
    }
    if (outcomes.length === 0) throw settled[0].reason;
    return mergeOutcomes(outcomes, [...this.features.keys()], params?.maxResults ?? 10);
  }

  curve(id, joint, shoulders = false) {
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

/** Merges per-worker outcomes exactly (see the top of this file). `order` lists clip ids in
 * library order. */
export function mergeOutcomes(outcomes, order, maxResults) {
  const rank = new Map(order.map((id, k) => [id, k]));
  const matches = outcomes.flatMap((o) => o.matches);
  matches.sort((a, b) => a.distance - b.distance || rank.get(a.clipId) - rank.get(b.clipId) || a.endFrame - b.endFrame);
  matches.length = Math.min(matches.length, maxResults);
  const sum = (f) => outcomes.reduce((a, o) => a + f(o), 0);
  const stats = {
    framesSearched: sum((o) => o.stats.framesSearched),
    cellsTotal: sum((o) => o.stats.cellsTotal),
    distancesComputed: sum((o) => o.stats.distancesComputed),
    workers: outcomes.length,
  };
  // Short only if every worker was short; then each worker's counts are exact.
  const shortfall = matches.length < maxResults ? {
    asked: maxResults,
    shown: matches.length,
    admissibleEnds: sum((o) => (o.shortfall ? o.shortfall.admissibleEnds : 0)),
    endsWithinThreshold: sum((o) => (o.shortfall ? o.shortfall.endsWithinThreshold : 0)),
    threshold: outcomes[0].shortfall ? outcomes[0].shortfall.threshold : null,
  } : null;
  return { matches, skipped: outcomes.flatMap((o) => o.skipped), stats, shortfall };
}
