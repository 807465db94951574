// The search runs here, off the UI thread: the main thread sends each clip's canonical
// positions once, then queries; progress goes back while the DP runs. The app runs several of
// these, each with part of the library (see search/client.js).
import init, { SearchIndex } from "./pkg/odori.js";

let index = null;
/** Stored index parts not yet taken (part number → bytes). */
const reserves = new Map();
const ready = init().then(() => { index = new SearchIndex(); });

// Messages are handled one after another, in order, even when one waits (reading a stored part).
let queue = ready;
self.onmessage = (ev) => { queue = queue.then(() => handle(ev.data)); };

async function handle(m) {
  try {
    if (m.type === "add") {
      index.addFeatures(m.id, m.name, m.positions, m.key);
      self.postMessage({ type: "added", token: m.token, id: m.id, clipCount: index.clipCount, totalFrames: index.totalFrames });
    } else if (m.type === "reserve") {
      // A part of a stored index (www/project/index-store.js), kept as bytes until the
      // library's clips of the same content arrive ("load").
      // Stored as a Blob: IndexedDB hands it over without reading it; it is read here.
      reserves.set(m.part, m.bytes instanceof Blob ? new Uint8Array(await m.bytes.arrayBuffer()) : m.bytes);
      self.postMessage({ type: "reserved", token: m.token });
    } else if (m.type === "drop") {
      reserves.delete(m.part);
    } else if (m.type === "load") {
      // The clips of a stored part whose content keys are given, under the library's ids.
      const added = Array.from(index.addBytes(reserves.get(m.part), m.keys, m.ids));
      self.postMessage({ type: "loaded", token: m.token, added, totalFrames: index.totalFrames });
    } else if (m.type === "toBytes") {
      const bytes = index.toBytes();
      self.postMessage({ type: "bytes", token: m.token, bytes, keys: index.clipKeys, ids: Array.from(index.clipIds), frames: index.totalFrames, heapBytes: index.heapBytes }, [bytes.buffer]);
    } else if (m.type === "memory") {
      self.postMessage({ type: "memory", token: m.token, heapBytes: index.heapBytes, frames: index.totalFrames });
    } else if (m.type === "remove") {
      index.remove(m.id);
    } else if (m.type === "queryFeatures") {
      self.postMessage({ type: "features", token: m.token, features: index.queryFeatures(m.query) });
    } else if (m.type === "probe") {
      // Round 1 of a search over several workers (see search/client.js).
      const probe = index.probeFeatures(m.features, m.params);
      self.postMessage({ type: "probe", token: m.token, distances: probe.distances, distancesComputed: probe.distancesComputed });
    } else if (m.type === "search") {
      let last = 0;
      const progress = (done, total) => {
        const now = performance.now();
        if (now - last > 40) { last = now; self.postMessage({ type: "progress", token: m.token, done, total }); }
        return true;
      };
      // Round 2 from the bound joined from every worker's probe, or alone with its own probe.
      const outcome = m.bound === undefined ? index.searchFeatures(m.features, m.params, progress) : index.searchFeaturesBounded(m.features, m.params, m.bound, progress);
      self.postMessage({ type: "result", token: m.token, outcome });
    } else if (m.type === "curve") {
      self.postMessage({ type: "curve", token: m.token, curve: index.jointCurve(m.id, m.joint, m.shoulders) });
    }
  } catch (e) {
    self.postMessage({ type: "error", token: m.token, kind: e.kind || "error", message: e.message || String(e) });
  }
}
