// Text to animation (paper 003): a sentence becomes a motion time table (actor, motion, how
// it joins the previous element, start time) shown as a table and as tracks on a timeline,
// and the joined animation plays. Each element's clip can be swapped for another with the
// same tag.
import { redrawOnResize } from "./canvas.js";
const JOIN_COLOURS = { initial: "#9a9cab", connection: "#7fb6ff", transition: "#f2731a", composition: "#4fd18b" };

export class TextPanel {
  constructor(root, { animator, library, panel, messages, player }) {
    Object.assign(this, { root, animator, library, panel, messages, player });
    this.$ = (s) => root.querySelector(s);
    this.clipId = null;
    this.elements = [];
    this.$("#text-go").addEventListener("click", () => this.run());
    this.$("#text-tag").addEventListener("click", () => this.tagSelected());
    this.$("#text-input").addEventListener("keydown", (ev) => {
      if (ev.key === "Enter" && (ev.ctrlKey || ev.metaKey)) { ev.preventDefault(); this.run(); }
    });
    this.$("#text-table tbody").addEventListener("change", (ev) => {
      const k = Number(ev.target.dataset.k);
      this.elements[k].clip = Number(ev.target.value);
      try {
        this.show(this.animator.animateTable(this.library, this.elements, this.clipId ?? undefined));
      } catch (e) { this.messages.error(`Text: ${e.message}`); }
    });
  }

  /** Makes the selected library clip an action the text can call by these words. */
  tagSelected() {
    const tags = this.$("#text-tags").value.split(/[,、，]/).map((t) => t.trim()).filter(Boolean);
    const id = this.player.clip;
    if (!tags.length || id == null) { this.messages.error("Text: select a clip and type at least one tag"); return; }
    const info = this.library.clip(id);
    try {
      this.animator.tagClip(this.library, id, tags);
      if (this.onTag) this.onTag(id, tags);
      this.messages.info(`${info.name} can now be called by: ${tags.join(", ")}`);
      this.$("#text-tags").value = "";
    } catch (e) { this.messages.error(`Text: ${info.name}: ${e.message}`); }
  }

  run() {
    const text = this.$("#text-input").value;
    try {
      this.show(this.animator.animate(this.library, text, this.clipId ?? undefined));
      if (this.onText) this.onText(text);
    } catch (e) {
      this.messages.error(`Text: ${e.message}`);
      this.root.dataset.rows = "0";
    }
  }

  show(r) {
    this.clipId = r.clipId;
    this.elements = r.elements;
    for (const d of r.diagnostics) this.messages.warning(`Text: ${d.message}`);
    const rows = r.elements.map((e, k) => {
      const tr = document.createElement("tr");
      tr.dataset.join = e.join;
      const sel = document.createElement("select");
      sel.dataset.k = k;
      for (const i of [e.clip, ...e.alternatives.filter((a) => a !== e.clip)]) {
        if (i == null) continue;
        sel.append(new Option(this.animator.actionName(i) ?? `#${i}`, String(i), i === e.clip, i === e.clip));
      }
      const cells = [e.index + 1, e.motion, sel, e.join, e.previous == null ? "–" : e.previous + 1, e.switchedPart ?? "", e.startSecs.toFixed(2), e.durationSecs.toFixed(2)];
      for (const v of cells) {
        const td = document.createElement("td");
        if (v instanceof Node) td.append(v); else td.textContent = v;
        tr.append(td);
      }
      tr.children[3].style.color = JOIN_COLOURS[e.join];
      return tr;
    });
    this.$("#text-table tbody").replaceChildren(...rows);
    this.$("#text-summary").textContent = `${r.elements.length} element${r.elements.length === 1 ? "" : "s"}, ${r.durationSecs.toFixed(1)} s`;
    this.root.dataset.rows = String(r.elements.length);
    this.drawTracks(r);
    this.panel.refresh();
    this.panel.select(r.clipId);
  }

  drawTracks(r) {
    const c = this.$("#text-tracks");
    if (!this.tracksObserved) {
      this.tracksObserved = true;
      redrawOnResize(c, () => this.lastTracks && this.drawTracks(this.lastTracks));
    }
    this.lastTracks = r;
    const rowH = 18;
    c.style.height = `${Math.max(1, r.elements.length) * rowH + 16}px`;
    const w = (c.width = c.clientWidth || 300), h = (c.height = c.clientHeight || 60);
    const g = c.getContext("2d");
    g.fillStyle = "#10121a"; g.fillRect(0, 0, w, h);
    const dur = Math.max(r.durationSecs, 0.1);
    g.fillStyle = "#2a2d3a";
    for (let s = 0; s <= dur; s += 1) g.fillRect((s / dur) * w, 0, 1, h);
    g.font = "11px system-ui";
    r.elements.forEach((e, k) => {
      const x = (e.startSecs / dur) * w, x2 = ((e.startSecs + e.durationSecs) / dur) * w;
      g.fillStyle = JOIN_COLOURS[e.join];
      g.globalAlpha = 0.75;
      g.fillRect(x, 4 + k * rowH, Math.max(3, x2 - x), rowH - 4);
      g.globalAlpha = 1;
      g.fillStyle = "#0e0f13";
      g.fillText(`${e.index + 1} ${e.motion} (${e.join})`, x + 4, 4 + k * rowH + 11);
    });
  }
}
