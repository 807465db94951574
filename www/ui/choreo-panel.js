// Composing a dance (paper 000): the song's bars in a row (pinned, generated, empty), a bar's
// 6 candidates playing side by side in sync with that bar of the music, Set / Search /
// Generate, τ and ρ, undo/redo, and the whole dance played with the music.
import { tempoLimits } from "../pkg/odori.js";
import { candidateOffsets, screenRight } from "./candidate-layout.js";

const CHIP_COLOURS = ["#f9b25a", "#5cd3ea", "#c79cf5", "#b5e96b", "#f38aa9", "#9dc2fb"];
/** A bar's flags in a word each on the strip (the full words are in its title). */
const FLAG_WORDS = { offBeat: "off-beat", joinJump: "join jump", footSkate: "foot skate" };
/** Target time of one slice of the join-table build, so frames keep coming. */
const SLICE_MS = 8;

export class ChoreoPanel {
  constructor(root, { choreographer, library, player, songPlayer, panel, messages }) {
    Object.assign(this, { root, choreographer, library, player, songPlayer, panel, messages });
    this.$ = (s) => root.querySelector(s);
    this.bar = null;            // selected bar index
    this.candidates = [];       // segment ids shown
    this.previewIds = [];       // library clip ids of the 6 previews (reused)
    this.ticked = new Set();    // indices into candidates
    this.danceId = null;
    this.preparing = null;      // the running join-table build (a promise)
    this.bind();
    this.prepareJoins();
  }

  /**
   * Builds the filling's join costs (spec §G, for the pairs of segments the song's bars can
   * join: the blocks of their metres) a slice at a time between frames, so the page stays
   * responsive; shows progress. Resolves when ready. Runs again whenever the library or the
   * bars change; Generate waits for it.
   */
  prepareJoins() {
    if (this.preparing) return this.preparing;
    const label = this.$("#dance-joins");
    this.preparing = (async () => {
      let columns = 16;
      const stats = { slices: 0, longestMs: 0, totalMs: 0, segments: 0 };
      for (;;) {
        const t = performance.now();
        const p = this.choreographer.prepareTable(columns);
        const dt = performance.now() - t;
        stats.slices++;
        stats.totalMs += dt;
        stats.longestMs = Math.max(stats.longestMs, dt);
        if (p >= 1) break;
        this.root.dataset.joins = "preparing";
        label.textContent = `Preparing joins ${Math.floor(p * 100)}%`;
        // Aim each slice at SLICE_MS, whatever the machine.
        columns = Math.max(1, Math.min(4096, Math.round(columns * SLICE_MS / Math.max(dt, 0.25))));
        await new Promise((r) => setTimeout(r, 0));
      }
      this.root.dataset.joins = "ready";
      label.textContent = "";
      stats.segments = this.choreographer.segmentCount;
      this.lastPrepare = stats;
    })().catch((e) => {
      this.messages.error(`Dance: ${e.message}`);
    }).finally(() => { this.preparing = null; });
    return this.preparing;
  }

  bind() {
    const $ = this.$;
    $("#dance-generate").addEventListener("click", () => this.generate());
    $("#dance-another-take").addEventListener("click", () => this.generate(true));
    $("#dance-recut").addEventListener("click", () => this.recut());
    $("#dance-clip").addEventListener("change", () => this.showClip());
    $("#dance-clip-bpm").addEventListener("keydown", (ev) => { if (ev.key === "Enter") this.recut(); });
    $("#dance-play").addEventListener("click", () => this.playDance());
    $("#dance-undo").addEventListener("click", () => this.undo());
    $("#dance-redo").addEventListener("click", () => this.redo());
    $("#dance-search").addEventListener("click", () => this.search());
    $("#dance-set").addEventListener("click", () => this.set());
    $("#dance-unpin").addEventListener("click", () => this.unpin());
    $("#dance-reset").addEventListener("click", () => this.act(() => this.choreographer.resetSearch(this.bar), true));
    $("#dance-rho").addEventListener("change", (ev) => this.act(() => this.choreographer.setRho(Number(ev.target.value))));
    $("#dance-music").addEventListener("change", (ev) => this.act(() => this.choreographer.setMusicWeight(Number(ev.target.value))));
    $("#dance-moves-source").addEventListener("change", (ev) => this.act(() => this.choreographer.setMovesSource(ev.target.value)));
    $("#dance-bars").addEventListener("click", (ev) => {
      const b = ev.target.closest("[data-bar]");
      if (b) this.selectBar(Number(b.dataset.bar));
    });
    $("#dance-candidates").addEventListener("click", (ev) => {
      const c = ev.target.closest("[data-k]");
      if (!c) return;
      const k = Number(c.dataset.k);
      if (this.ticked.has(k)) this.ticked.delete(k); else this.ticked.add(k);
      this.renderCandidates();
    });
    window.addEventListener("keydown", (ev) => {
      if (ev.target.matches("input, textarea, select")) return;
      const k = ev.key.toLowerCase();
      if ((ev.ctrlKey || ev.metaKey) && k === "z") { ev.preventDefault(); ev.shiftKey ? this.redo() : this.undo(); }
      else if ((ev.ctrlKey || ev.metaKey) && k === "y") { ev.preventDefault(); this.redo(); }
      else if (ev.ctrlKey || ev.metaKey || ev.altKey) return;
      else if (k === "[") this.step(-1);
      else if (k === "]") this.step(1);
      else if (k === "s") this.set();
      else if (k === "f") this.search();
      else if (ev.key === "G") this.generate(true);
      else if (k === "g") this.generate();
      else if (k === "p") this.playDance();
    });
  }

  act(fn, reselect = false) {
    try {
      const r = fn();
      this.refresh();
      if (reselect && this.bar != null) this.selectBar(this.bar);
      return r;
    } catch (e) {
      this.messages.error(`Dance: ${e.message}`);
      return undefined;
    }
  }

  /** Cuts an imported humanoid clip into 4- and 3-count segments at its own beats; says why not. */
  addClip(info) {
    if (info.humanoid.kind === "notHumanoid") return;
    try {
      const s = this.choreographer.addClip(this.library, info.id);
      this.messages.info(`${info.name}: ${s.segments} dance segments at ${s.tempoBpm.toFixed(0)} counts/min`);
      this.refreshClips(info.id);
      this.prepareJoins();
    } catch (e) {
      // A clip too short to hold a bar's move (a character's one-frame T-pose, a 1 s gesture)
      // is no fault: said plainly, in the Messages log only. Other refusals are warnings.
      if (info.frames <= 1 || info.durationSecs < 0.5) {
        this.messages.note(`${info.name}: a still pose, so no dance moves are made from it (it can still be a character)`);
      } else if (/needs? \d+ counts/.test(e.message)) {
        this.messages.note(`${info.name}: ${info.durationSecs.toFixed(1)} s is too short to make dance moves from (a move is a whole bar: 3 or 4 counts)`);
      } else {
        this.messages.warning(`Dance: ${e.message}`);
      }
    }
  }

  /** The clip-tempo row: every imported clip in the dance library, with its cut. */
  refreshClips(select) {
    const clips = this.choreographer.cutClips();
    const sel = this.$("#dance-clip");
    const keep = select ?? (sel.value === "" ? undefined : Number(sel.value));
    sel.replaceChildren(...clips.map((c) => {
      const o = document.createElement("option");
      o.value = String(c.id);
      o.textContent = c.name;
      return o;
    }));
    if (keep != null && clips.some((c) => c.id === keep)) sel.value = String(keep);
    this.$("#dance-clip-row").hidden = clips.length === 0;
    this.clips = clips;
    this.showClip();
  }

  showClip() {
    const c = (this.clips ?? []).find((x) => String(x.id) === this.$("#dance-clip").value);
    const bpm = this.$("#dance-clip-bpm");
    if (!c) { this.$("#dance-clip-info").textContent = ""; return; }
    bpm.value = c.tempoDetected ? "" : String(Math.round(c.tempoBpm * 10) / 10);
    bpm.placeholder = c.tempoDetected ? `auto (${c.tempoBpm.toFixed(0)})` : "auto";
    this.$("#dance-clip-info").textContent =
      `${c.segments} segments at ${c.tempoBpm.toFixed(1)} counts/min (${c.tempoDetected ? "found in the motion" : "stated"})`;
  }

  /** Re-cuts the chosen clip at the stated tempo (or its detected beats); says what happened to bars that used the earlier cut. */
  recut() {
    const id = Number(this.$("#dance-clip").value);
    const c = (this.clips ?? []).find((x) => x.id === id);
    if (!c) return;
    const text = this.$("#dance-clip-bpm").value.trim();
    const bpm = text === "" ? undefined : Number(text);
    const { moveMinBpm: lo, moveMaxBpm: hi } = tempoLimits(); // the engine's limits, one place
    if (bpm !== undefined && !(bpm >= lo && bpm <= hi)) {
      this.messages.error(`Dance: ${c.name}: a clip's tempo must be ${lo} to ${hi} counts per minute (got “${text}”)`);
      return;
    }
    let r;
    try {
      r = this.choreographer.recutClip(id, bpm);
      if (this.onRecut) this.onRecut(id, bpm);
    } catch (e) {
      this.messages.error(`Dance: ${e.message}`);
      return;
    }
    const how = bpm === undefined ? `at its own beats (${r.clip.tempoBpm.toFixed(0)} counts/min)` : `at ${r.clip.tempoBpm} counts/min`;
    this.messages.info(`${c.name}: re-cut ${how}: ${r.clip.segments} segments; ${r.removed} of the earlier cut removed`);
    const bars = (list) => list.map((b) => b + 1).join(", ");
    if (r.pinnedBars.length) {
      this.messages.warning(`Dance: bar${r.pinnedBars.length > 1 ? "s" : ""} ${bars(r.pinnedBars)} keep${r.pinnedBars.length > 1 ? "" : "s"} the pinned move from ${c.name}'s earlier cut (it is not offered again)`);
    }
    if (r.generatedBars.length) {
      this.messages.info(`Dance: bar${r.generatedBars.length > 1 ? "s" : ""} ${bars(r.generatedBars)} keep${r.generatedBars.length > 1 ? "" : "s"} a move from the earlier cut until you Generate again`);
    }
    this.root.dataset.recuts = String(Number(this.root.dataset.recuts ?? 0) + 1);
    this.refreshClips(id);
    this.refresh();
    // Segment numbers changed: show the selected bar's candidates and the dance afresh.
    if (this.bar != null) this.selectBar(this.bar);
    if (this.danceId != null) this.renderDance();
    this.prepareJoins();
  }

  /** New bars (and the song's beats, for the quality readout) from the song grid. */
  setBars(bars, beatTimesSecs) {
    try {
      this.beats = beatTimesSecs ? new Float32Array(beatTimesSecs) : undefined;
      this.choreographer.setBars(bars);
      if (this.bar != null && this.bar >= bars.length) this.bar = null;
      this.refresh();
      // New bars may bring in a metre (or a change of metre) whose joins are not built yet.
      this.prepareJoins();
    } catch (e) { this.messages.error(`Dance: ${e.message}`); }
  }

  refresh() {
    const view = this.choreographer.view();
    this.view = view;
    if (this.onChange) this.onChange(view);
    const total = view.length ? view[view.length - 1].bar.endSecs : 1;
    // Spec §J readout on the bar row, from the engine: each bar's move (name and source) and
    // where it is weak, in words (off the beat, a rough join, foot skate).
    let q = null;
    let notes = [];
    if (view.some((v) => v.state.kind !== "empty")) {
      try { ({ quality: q, notes } = this.choreographer.barNotes(this.beats)); } catch (e) { this.messages.warning(`Dance quality: ${e.message}`); }
    }
    this.quality = q;
    this.notes = notes;
    const cells = view.map((v, i) => {
      const b = document.createElement("button");
      b.type = "button";
      b.dataset.bar = i;
      b.className = `bar ${v.state.kind}${i === this.bar ? " selected" : ""}`;
      b.style.flexGrow = String(v.bar.endSecs - v.bar.startSecs);
      b.style.setProperty("--intensity", v.bar.intensity.toFixed(2));
      const note = v.state.kind !== "empty" ? notes[i] : null;
      const num = document.createElement("span");
      num.className = "bar-n";
      num.textContent = String(i + 1);
      const move = document.createElement("span");
      move.className = "bar-move";
      const src = document.createElement("span");
      src.className = "bar-src";
      const flags = document.createElement("span");
      flags.className = "bar-flags";
      b.append(num, move, src, flags);
      b.title = `Bar ${i + 1}: ${v.state.kind}, music intensity ${v.bar.intensity.toFixed(2)}`;
      if (note && note.segment != null) {
        move.textContent = note.name;
        src.textContent = note.builtin ? "built-in" : note.source;
        b.dataset.source = note.builtin ? "built-in" : "imported";
        b.title += `\n${note.name} — from ${note.builtin ? "the built-in moves" : note.source}`;
        const bq = q ? q.bars[i] : null;
        if (bq) {
          const j = bq.joinJump == null ? "" : `, join jump ${bq.joinJump.toFixed(2)}`;
          b.title += `\nbeat alignment ${bq.beats.basMusic.toFixed(2)} (half a beat off: ${bq.beats.basMusicShifted.toFixed(2)}), foot skate ${bq.footSkate.meanCmPerS.toFixed(0)} cm/s${j}`;
        }
        if (note.builtinWhy) {
          // Built-in though your moves come first: why, from the Generate that chose it (issue 26).
          b.dataset.builtinWhy = "1";
          b.title += `\n${note.builtinWhy}`;
        }
        if (note.repeatsBar != null) {
          // Its section repeats an earlier one (found, or marked by the person on the song
          // strip), and it holds that bar's move (issue 26 item 2).
          b.dataset.repeats = String(note.repeatsBar + 1);
          if (note.repeatMarked) b.dataset.repeatMarked = "1";
          num.textContent += ` = bar ${note.repeatsBar + 1}${note.repeatMarked ? " (marked)" : ""}`;
          b.title += `\nrepeats bar ${note.repeatsBar + 1} (${note.repeatMarked ? "marked" : "its section repeats"})`;
        }
        if (note.flags.length) {
          b.dataset.weak = "1";
          flags.textContent = note.flags.map((f) => FLAG_WORDS[f.kind] ?? f.kind).join(" · ");
          b.title += `\nweak: ${note.flags.map((f) => f.words).join("; ")}`;
        }
      }
      b.setAttribute("aria-label", b.title.replace(/\n/g, ". "));
      return b;
    });
    this.$("#dance-bars").replaceChildren(...cells);
    this.$("#dance-bars").title = q
      ? `Whole dance: beat alignment ${q.beats.basMusic.toFixed(2)} (half a beat off: ${q.beats.basMusicShifted.toFixed(2)}), ${q.beats.kineticBeatsPerSec.toFixed(1)} moves/s on ${q.beats.musicBeatsPerSec.toFixed(1)} beats/s, foot skate ${q.footSkate.meanCmPerS.toFixed(0)} cm/s, join jump mean ${q.joinJumpMean.toFixed(2)} max ${q.joinJumpMax.toFixed(2)}; each bar names its move, its source and, in red, where it is weak`
      : "";
    this.root.dataset.bars = String(view.length);
    // For whoever shows what the dance is made of (the share note).
    this.root.dispatchEvent(new CustomEvent("dance-refresh", { detail: { notes } }));
    this.$("#dance-undo").disabled = !this.choreographer.canUndo();
    this.$("#dance-redo").disabled = !this.choreographer.canRedo();
    const v = this.bar != null ? view[this.bar] : null;
    this.$("#dance-tau").textContent = v ? `variety τ ${v.tau.toFixed(3)} · round ${v.rounds}` : "variety τ –";
    this.$("#dance-bar-label").textContent = v ? `Bar ${this.bar + 1}` : "Bar –";
    this.$("#dance-unpin").disabled = !(v && v.state.kind === "pinned");
    void total;
  }

  step(d) {
    if (!this.view || !this.view.length) return;
    const next = this.bar == null ? 0 : Math.max(0, Math.min(this.view.length - 1, this.bar + d));
    this.selectBar(next);
  }

  selectBar(i) {
    this.bar = i;
    this.ticked.clear();
    const cands = this.act(() => this.choreographer.candidates(i));
    if (!cands) return;
    this.showCandidates([...cands]);
    this.songPlayer.seek(this.view[i].bar.startSecs);
  }

  showCandidates(cands) {
    // The engine measures each candidate as the bar would play once Set and ranks clean ones
    // first (among equals, the search's order); a flagged one says so in words.
    this.candidateNotes = new Map();
    try {
      const notes = this.choreographer.candidateNotes(this.bar, cands, this.beats);
      cands = notes.map((n) => n.segment);
      for (const n of notes) this.candidateNotes.set(n.segment, n);
    } catch (e) { this.messages.warning(`Dance candidates: ${e.message}`); }
    this.candidates = cands;
    const bar = this.view[this.bar].bar;
    const dur = bar.endSecs - bar.startSecs;
    this.previewIds = cands.map((seg, k) => this.choreographer.previewSegment(this.library, seg, dur, this.previewIds[k] ?? undefined));
    const ids = this.previewIds;
    // Each in a slot of its own, as wide as its move's reach over the bar (candidate-layout.js),
    // along the screen's horizontal as seen once the camera is framed on them (a second pass).
    let offsets = [];
    const place = () => {
      offsets = candidateOffsets(ids, dur, screenRight(this.player.viewer), (id, t) => this.library.jointPositions(id, t));
      this.player.setCompare({
        duration: dur,
        songStart: bar.startSecs,
        figures: (t) => ids.map((clip, k) => ({ clip, timeSecs: t, offset: offsets[k] })),
      });
    };
    place();
    place();
    this.renderCandidates();
    this.refresh();
  }

  renderCandidates() {
    const chips = this.candidates.map((seg, k) => {
      const b = document.createElement("button");
      b.type = "button";
      b.dataset.k = k;
      b.className = `chip${this.ticked.has(k) ? " ticked" : ""}`;
      b.style.setProperty("--chip", CHIP_COLOURS[k % CHIP_COLOURS.length]);
      const s = this.choreographer.segment(seg);
      const note = this.candidateNotes?.get(seg);
      b.textContent = `${k + 1} ${s.name}`;
      b.title = `${s.name} — from ${s.source}, intensity ${s.intensity01.toFixed(2)}; click to tick (liked / to set)`;
      if (note && note.flags.length) {
        const w = document.createElement("span");
        w.className = "chip-flags";
        w.textContent = ` — ${note.flags.map((f) => f.words).join("; ")}`;
        b.append(w);
        b.dataset.weak = "1";
        b.title += `\nweak once set: ${note.flags.map((f) => f.words).join("; ")}`;
      }
      return b;
    });
    this.$("#dance-candidates").replaceChildren(...chips);
    this.root.dataset.candidates = String(this.candidates.length);
  }

  search() {
    if (this.bar == null) return;
    const liked = [...this.ticked].map((k) => this.candidates[k]);
    const next = this.act(() => this.choreographer.search(this.bar, Uint32Array.from(liked)));
    if (next) { this.ticked.clear(); this.showCandidates([...next]); }
  }

  set() {
    if (this.bar == null || !this.ticked.size) { this.messages.error("Dance: tick a candidate to set it on the bar"); return; }
    const seg = this.candidates[[...this.ticked][0]];
    this.act(() => this.choreographer.set(this.bar, seg));
    this.renderDance();
  }

  /** Fills the open bars, once the join costs are ready: take 0, or (`another`) the take after the dance's (16 takes, then take 0 again). */
  async generate(another = false) {
    if (this.generating) return;
    this.generating = true;
    this.root.dataset.busy = "generate";
    // The engine holds the page while it composes (a second or more for a long song on a
    // phone): the button says so first, and a frame is painted with it before the engine runs.
    const button = this.$(another ? "#dance-another-take" : "#dance-generate");
    const label = button?.textContent;
    if (button) button.textContent = "Generating…";
    try {
      await this.prepareJoins();
      await new Promise((done) => requestAnimationFrame(() => setTimeout(done, 0)));
      const take = another ? ((this.choreographer.take ?? 0) + 1) % 16 : 0;
      const r = this.act(() => this.choreographer.generate({ take }));
      if (r) {
        this.root.dataset.take = String(take);
        this.messages.info(`Dance: ${take ? `take ${take + 1}: ` : ""}filled ${r.filled} bars (${r.pinned} pinned kept)`);
        this.renderDance();
      }
    } finally {
      if (button) button.textContent = label;
      this.generating = false;
      delete this.root.dataset.busy;
    }
  }

  /** Unpins the selected bar: it keeps its move as a generated one until the next Generate. */
  unpin() {
    if (this.bar == null) return;
    this.act(() => this.choreographer.unpin(this.bar));
    this.renderDance();
  }

  undo() { if (this.act(() => this.choreographer.undo())) this.afterHistory(); }
  redo() { if (this.act(() => this.choreographer.redo())) this.afterHistory(); }

  /**
   * After undo/redo the selected bar's search may differ (or be closed: looking at a bar is
   * not an edit, so an earlier state may not have it open). Open it again, quietly, and show
   * its candidates if they changed.
   */
  afterHistory() {
    this.renderDance();
    if (this.bar == null || !this.view || this.bar >= this.view.length) return;
    const cands = this.act(() => this.choreographer.candidates(this.bar));
    // Compared as sets: the shown order is the engine's ranking by flags, not the search's.
    if (cands && (cands.length !== this.candidates.length || [...cands].some((c) => !this.candidates.includes(c)))) {
      this.ticked.clear();
      this.showCandidates([...cands]);
    }
  }

  renderDance() {
    try {
      // The moves-source choice as the project has it (after an undo, a reopened project).
      const source = this.choreographer.movesSource;
      if (source) this.$("#dance-moves-source").value = source;
      this.danceId = this.choreographer.renderDance(this.library, this.danceId ?? undefined);
      this.panel.refresh();
    } catch (e) { this.messages.error(`Dance: ${e.message}`); }
  }

  /** The whole dance with the music, from the selected bar. */
  playDance() {
    this.renderDance();
    if (this.danceId == null) return;
    this.panel.select(this.danceId);
    const from = this.bar != null ? this.view[this.bar].bar.startSecs : 0;
    // Through the one transport: Pause (or space) then stops the music and the figure together.
    this.player.playSong(from);
  }
}
