// The search runs here, off the UI thread: the main thread sends each clip's canonical
// positions once, then queries; progress goes back while the DP runs. The app runs several of
// these, each with part of the library (see search/client.js).
import init, { SearchIndex } from "./pkg/odori.js";

let index = null;
const ready = init().then(() => { index = new SearchIndex(); });

self.onmessage = async (ev) => {
  await ready;
  const m = ev.data;
  try {
    if (m.type === "add") {
      index.addFeatures(m.id, m.name, m.positions);
      self.postMessage({ type: "added", id: m.id, clipCount: index.clipCount });
    } else if (m.type === "remove") {
      index.remove(m.id);
    } else if (m.type === "queryFeatures") {
      self.postMessage({ type: "features", token: m.token, features: index.queryFeatures(m.query) });
    } else if (m.type === "search") {
      let last = 0;
      const outcome = index.searchFeatures(m.features, m.params, (done, total) => {
        const now = performance.now();
        if (now - last > 40) { last = now; self.postMessage({ type: "progress", token: m.token, done, total }); }
        return true;
      });
      self.postMessage({ type: "result", token: m.token, outcome });
    } else if (m.type === "curve") {
      self.postMessage({ type: "curve", token: m.token, curve: index.jointCurve(m.id, m.joint, m.shoulders) });
    }
  } catch (e) {
    self.postMessage({ type: "error", token: m.token, kind: e.kind || "error", message: e.message || String(e) });
  }
};
