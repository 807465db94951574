// Search by example (paper 002): pick a query as a frame range of the selected clip (drag on
// its timeline) or the whole clip, choose a body part or per-joint weights, search every clip
// in a worker, list the matches; a match plays overlaid on the query, aligned along the
// warping path, beside a plot of one joint's x, y, z over time.
import { redrawOnResize } from "./canvas.js";
import { bodyVocabulary, searchFrameFloats } from "../pkg/odori.js";

// The canonical joints and the body-part presets come from the engine (one place for the
// vocabulary, crate/core canon::body_vocabulary), read once the engine is loaded.
let vocabulary = null;
function vocab() {
  if (!vocabulary) {
    const v = bodyVocabulary();
    vocabulary = { joints: v.joints, order: v.searchPresets.map((p) => p.name), presets: new Map(v.presets.map((p) => [p.name, p])) };
  }
  return vocabulary;
}

/** "wholeBody" → "whole body": a preset's name as the page shows it. */
const words = (name) => name.replace(/[A-Z]/g, (c) => " " + c.toLowerCase());

export class SearchPanel {
  constructor(root, { client, library, player, messages }) {
    Object.assign(this, { root, client, library, player, messages });
    this.$ = (s) => root.querySelector(s);
    this.range = null;       // { clipId, startSecs, endSecs }
    this.results = [];
    this.current = null;     // the match being shown
    this.fps = 60;
    this.buildWeights();
    this.bind();
  }

  buildWeights() {
    const presets = this.$("#search-preset");
    for (const name of vocab().order) presets.append(new Option(words(name), name));
    const box = this.$("#search-weights");
    for (const j of vocab().joints) {
      const label = document.createElement("label");
      label.innerHTML = `<span>${j}</span><input type="range" min="0" max="2" step="0.1" value="1" data-joint="${j}">`;
      box.append(label);
    }
    const plotJoint = this.$("#plot-joint");
    for (const j of vocab().joints) plotJoint.append(new Option(j, j, j === "rightHand", j === "rightHand"));
  }

  weights() { return [...this.root.querySelectorAll("#search-weights input")].map((i) => Number(i.value)); }

  applyPreset(name) {
    const on = new Set(vocab().presets.get(name)?.joints ?? []);
    for (const i of this.root.querySelectorAll("#search-weights input")) i.value = on.has(i.dataset.joint) ? "1" : "0";
  }

  bind() {
    const $ = this.$;
    $("#search-preset").addEventListener("change", (ev) => this.applyPreset(ev.target.value));
    $("#search-whole").addEventListener("click", () => {
      const c = this.library.clip(this.player.clip);
      this.setRange({ clipId: c.id, startSecs: 0, endSecs: (c.frames - 1) / c.fps });
    });
    $("#search-go").addEventListener("click", () => this.run());
    $("#search-cancel").addEventListener("click", () => this.client.cancel());
    $("#plot-joint").addEventListener("change", () => this.plot());
    $("#search-results tbody").addEventListener("click", (ev) => {
      const tr = ev.target.closest("tr");
      if (tr) this.show(this.results[Number(tr.dataset.k)]);
    });
    const tl = $("#search-timeline");
    redrawOnResize(tl, () => this.drawTimeline());
    redrawOnResize($("#search-plot"), () => this.plot());
    let drag = null;
    const secsAt = (ev) => {
      const c = this.library.clip(this.player.clip);
      const r = tl.getBoundingClientRect();
      return Math.max(0, Math.min(1, (ev.clientX - r.left) / r.width)) * ((c.frames - 1) / c.fps);
    };
    tl.addEventListener("pointerdown", (ev) => { drag = secsAt(ev); tl.setPointerCapture(ev.pointerId); });
    tl.addEventListener("pointermove", (ev) => {
      if (drag == null) return;
      const t = secsAt(ev);
      this.setRange({ clipId: this.player.clip, startSecs: Math.min(drag, t), endSecs: Math.max(drag, t) });
    });
    tl.addEventListener("pointerup", () => { drag = null; });
  }

  setRange(range) {
    this.range = range;
    const c = this.library.clip(range.clipId);
    this.$("#search-query").textContent = `${c.name}: ${range.startSecs.toFixed(2)}–${range.endSecs.toFixed(2)} s (${(range.endSecs - range.startSecs).toFixed(2)} s)`;
    this.drawTimeline();
  }

  /** Selection changed in the library: redraw the timeline for the new clip. */
  clipChanged() { this.drawTimeline(); }

  drawTimeline() {
    const cv = this.$("#search-timeline");
    const w = (cv.width = cv.clientWidth || 300), h = (cv.height = cv.clientHeight || 28);
    const g = cv.getContext("2d");
    g.fillStyle = "#10121a"; g.fillRect(0, 0, w, h);
    if (this.player.clip == null) return;
    const c = this.library.clip(this.player.clip);
    const dur = (c.frames - 1) / c.fps || 1;
    g.fillStyle = "#2a2d3a";
    for (let s = 0; s <= dur; s += 1) g.fillRect((s / dur) * w, h - 8, 1, 8);
    if (this.range && this.range.clipId === c.id) {
      g.fillStyle = "rgba(242,115,26,0.55)";
      g.fillRect((this.range.startSecs / dur) * w, 0, Math.max(2, ((this.range.endSecs - this.range.startSecs) / dur) * w), h);
    }
    g.fillStyle = "#9a9cab"; g.font = "11px system-ui";
    g.fillText(this.range ? "" : "drag here to choose the query", 6, 14);
  }

  async run() {
    if (!this.range) { this.messages.error("Search: choose a query first (drag on the timeline, or Whole clip)"); return; }
    const q = this.range;
    const query = { clipId: q.clipId, startFrame: Math.round(q.startSecs * this.fps), endFrame: Math.round(q.endSecs * this.fps) + 1 };
    const preset = this.$("#search-preset").value;
    const threshold = this.$("#search-threshold").value === "" ? undefined : Number(this.$("#search-threshold").value);
    const params = { weights: this.weights(), maxResults: Number(this.$("#search-max").value) || 10, ...(threshold != null ? { threshold } : {}) };
    if (vocab().presets.get(preset)?.shoulders) params.preset = preset;
    const bar = this.$("#search-progress");
    bar.hidden = false; bar.value = 0;
    this.$("#search-cancel").hidden = false;
    this.root.dataset.state = "running";
    const t0 = performance.now();
    try {
      const out = await this.client.search(query, params, (done, total) => { bar.value = done / total; });
      this.query = query;
      this.results = out.matches;
      this.renderResults(out, performance.now() - t0);
      this.root.dataset.state = "done";
    } catch (e) {
      this.root.dataset.state = e.kind === "cancelled" ? "cancelled" : "error";
      if (e.kind === "cancelled") this.messages.info("Search cancelled");
      else this.messages.error(`Search: ${e.message}`);
    } finally {
      bar.hidden = true;
      this.$("#search-cancel").hidden = true;
    }
  }

  renderResults(out, ms) {
    const rows = out.matches.map((m, k) => {
      const tr = document.createElement("tr");
      tr.dataset.k = k;
      for (const v of [m.clipName, m.startFrame, m.endFrame, m.lengthFrames, m.distance.toFixed(4)]) {
        const td = document.createElement("td"); td.textContent = v; tr.append(td);
      }
      return tr;
    });
    this.$("#search-results tbody").replaceChildren(...rows);
    const skipped = out.skipped.length ? `; skipped: ${out.skipped.map((s) => `${s.name} (${s.reason})`).join(", ")}` : "";
    this.$("#search-summary").textContent = `${out.matches.length} ${out.matches.length === 1 ? "match" : "matches"} in ${ms.toFixed(0)} ms over ${out.stats.framesSearched} frames${skipped}${shortfallText(out.shortfall)}`;
  }

  hipsAt(id, frame) {
    const positions = this.client.positions(id);
    // Flat frames × joints × xyz, the stride the engine gives (hips first).
    const stride = searchFrameFloats();
    const n = positions.length / stride;
    const k = Math.max(0, Math.min(n - 1, frame)) * stride;
    return [positions[k], positions[k + 1], positions[k + 2]];
  }

  show(m) {
    this.current = m;
    for (const tr of this.$("#search-results tbody").children) tr.classList.toggle("selected", this.results[Number(tr.dataset.k)] === m);
    const q = this.query;
    // Superimpose: move the result so its hips start where the query's do (on the floor).
    const a = this.hipsAt(q.clipId, q.startFrame), b = this.hipsAt(m.clipId, m.startFrame);
    const offset = [a[0] - b[0], 0, a[2] - b[2]];
    // Query frame (relative) → result frame along the warping path.
    const qLen = q.endFrame - q.startFrame;
    const map = new Array(qLen).fill(m.startFrame);
    for (const [i, j] of m.path) if (i < qLen) map[i] = Math.max(map[i], j);
    this.player.setCompare({
      duration: (qLen - 1) / this.fps,
      figures: (t) => {
        const i = Math.max(0, Math.min(qLen - 1, Math.round(t * this.fps)));
        return [
          { clip: q.clipId, timeSecs: (q.startFrame + i) / this.fps },
          { clip: m.clipId, timeSecs: map[i] / this.fps, offset },
        ];
      },
    });
    this.plot();
  }

  async plot() {
    const m = this.current;
    if (!m) return;
    const joint = this.$("#plot-joint").value;
    const q = this.query;
    const [cq, cr] = await Promise.all([this.client.curve(q.clipId, joint), this.client.curve(m.clipId, joint)]);
    const cv = this.$("#search-plot");
    const w = (cv.width = cv.clientWidth || 600), h = (cv.height = cv.clientHeight || 160);
    const g = cv.getContext("2d");
    g.fillStyle = "#10121a"; g.fillRect(0, 0, w, h);
    const half = w / 2 - 6;
    const pad = Math.round(0.5 * this.fps);
    const panels = [
      { c: cq, from: q.startFrame - pad, to: q.endFrame + pad, span: [q.startFrame, q.endFrame], x0: 0, title: `query: ${this.library.clip(q.clipId).name}` },
      { c: cr, from: m.startFrame - pad, to: m.endFrame + pad, span: [m.startFrame, m.endFrame + 1], x0: w / 2 + 6, title: `result: ${m.clipName}` },
    ];
    let lo = Infinity, hi = -Infinity;
    for (const p of panels) for (const k of ["x", "y", "z"]) for (let f = Math.max(0, p.from); f < Math.min(p.c[k].length, p.to); f++) { lo = Math.min(lo, p.c[k][f]); hi = Math.max(hi, p.c[k][f]); }
    if (!(hi > lo)) { hi = lo + 1; }
    const y = (v) => h - 14 - ((v - lo) / (hi - lo)) * (h - 30);
    for (const p of panels) {
      const X = (f) => p.x0 + ((f - p.from) / (p.to - p.from)) * half;
      g.fillStyle = "rgba(242,115,26,0.18)";
      g.fillRect(X(p.span[0]), 0, X(p.span[1]) - X(p.span[0]), h);
      [["x", "#ff6b6b"], ["y", "#4fd18b"], ["z", "#7fb6ff"]].forEach(([k, col]) => {
        g.strokeStyle = col; g.lineWidth = 1.5; g.beginPath();
        let first = true;
        for (let f = Math.max(0, p.from); f < Math.min(p.c[k].length, p.to); f++) {
          if (first) { g.moveTo(X(f), y(p.c[k][f])); first = false; } else g.lineTo(X(f), y(p.c[k][f]));
        }
        g.stroke();
      });
      // Each title stays inside its own half (long clip names overlapped the other's).
      g.save(); g.beginPath(); g.rect(p.x0, 0, half, h); g.clip();
      g.fillStyle = "#e6e6ea"; g.font = "11px system-ui";
      g.fillText(p.x0 === 0 ? `${p.title} — ${joint} (x red, y green, z blue)` : p.title, p.x0 + 4, 12);
      g.restore();
    }
    this.root.dataset.plotted = joint;
  }
}

/** Why fewer matches than asked are shown (spec §C: every admissible end has a match; the rest
 * are over the threshold or overlap a shown match by more than half). */
export function shortfallText(s) {
  if (!s) return "";
  const n = (x) => x.toLocaleString("en");
  const head = `. Fewer than the ${s.asked} asked: the library has ${n(s.admissibleEnds)} admissible match ends`;
  if (s.threshold != null) {
    const over = s.admissibleEnds - s.endsWithinThreshold;
    return `${head}; ${n(over)} are over the threshold ${+s.threshold.toPrecision(6)}; of the ${n(s.endsWithinThreshold)} within it, those not shown overlap a shown match by more than half`;
  }
  return `${head}, and every one not shown overlaps a shown match by more than half (the library is short for this query)`;
}
