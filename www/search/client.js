// Talks to the search worker. Cancel terminates the worker (a running DP cannot be
// interrupted from outside) and starts a fresh one with the same clips.
export class SearchClient {
  constructor(library) {
    this.library = library;
    this.features = new Map(); // id -> { name, positions }
    this.pending = new Map();  // token -> { resolve, reject, onProgress }
    this.token = 0;
    this.spawn();
  }

  spawn() {
    this.worker = new Worker(new URL("../search-worker.js", import.meta.url), { type: "module" });
    this.worker.onmessage = (ev) => this.receive(ev.data);
    this.worker.onerror = (ev) => {
      for (const p of this.pending.values()) p.reject(new Error(`search worker failed: ${ev.message}`));
      this.pending.clear();
    };
    for (const [id, f] of this.features) this.worker.postMessage({ type: "add", id, name: f.name, positions: f.positions.slice() });
  }

  receive(m) {
    const p = this.pending.get(m.token);
    if (!p) return;
    if (m.type === "progress") { if (p.onProgress) p.onProgress(m.done, m.total); return; }
    this.pending.delete(m.token);
    if (m.type === "error") { const e = new Error(m.message); e.kind = m.kind; p.reject(e); }
    else p.resolve(m.type === "curve" ? m.curve : m.outcome);
  }

  /** Indexes a library clip; false (with the reason) when it cannot be searched. */
  add(id) {
    const info = this.library.clip(id);
    if (info.humanoid.kind === "notHumanoid") return { ok: false, reason: info.humanoid.reason };
    const positions = this.library.searchFeatures(id);
    this.features.set(id, { name: info.name, positions });
    this.worker.postMessage({ type: "add", id, name: info.name, positions: positions.slice() });
    return { ok: true };
  }

  /** Forgets a clip removed from the library. */
  remove(id) {
    if (this.features.delete(id)) this.worker.postMessage({ type: "remove", id });
  }

  request(msg, onProgress) {
    const token = ++this.token;
    return new Promise((resolve, reject) => {
      this.pending.set(token, { resolve, reject, onProgress });
      this.worker.postMessage({ ...msg, token });
    });
  }

  search(query, params, onProgress) { return this.request({ type: "search", query, params }, onProgress); }
  curve(id, joint, shoulders = false) { return this.request({ type: "curve", id, joint, shoulders }); }

  cancel() {
    this.worker.terminate();
    for (const p of this.pending.values()) { const e = new Error("search cancelled"); e.kind = "cancelled"; p.reject(e); }
    this.pending.clear();
    this.spawn();
  }
}
