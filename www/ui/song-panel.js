// The song strip: loudness over time with beat and bar lines, the playhead, and the grid
// corrections (BPM, tap tempo, nudge, downbeat, beats per bar, reset) that re-derive the
// bars at once. Shift-click on the strip puts a downbeat there; a plain click seeks. Along the
// strip's foot, the song's sections (the engine's `music::sections`, the analysis Generate repeats moves
// on and the video's director camera cuts on): a letter each, a repeated section named after the
// one it repeats. Below the strip, the repeats Generate follows (found, or marked by the person:
// "Bars 17 to 24 repeat bar 1", each with a button that removes it, one undo step each).
/** Taps further apart than this start a new count. */
const TAP_GAP_SECS = 2.5;

export class SongPanel {
  constructor(root, { player, onGrid, messages, onCorrect, sections, repeats }) {
    this.getSections = sections; // () => the project's sections ({ sections: [...] }) or undefined
    // { list: () => the project's repeat runs, mark(firstBar, bars, ofFirstBar), remove(bar) }
    // (bars from 0; mark and remove are project edits that throw the engine's error when refused).
    this.repeatEdits = repeats;
    this.repeats = null;         // the repeat runs shown, for the grid shown
    this.onCorrect = onCorrect; // (correction | null for a reset) after one the song took
    this.root = root;
    this.player = player;        // SongPlayer
    this.onGrid = onGrid;        // called with the new grid after every change
    this.messages = messages;
    this.song = null;            // wasm Song
    this.name = "";
    this.grid = null;
    this.taps = [];
    this.sections = null;        // the sections shown, for the grid shown
    this.canvas = root.querySelector("canvas");
    this.$ = (s) => root.querySelector(s);
    this.bind();
  }

  bind() {
    const $ = this.$;
    $("#song-play").addEventListener("click", () => this.toggle());
    $("#song-bpm").addEventListener("change", (ev) => this.correct({ bpm: Number(ev.target.value) }));
    $("#song-bpb").addEventListener("change", (ev) => this.correct({ beatsPerBar: Number(ev.target.value) }));
    $("#song-earlier").addEventListener("click", (ev) => this.correct({ nudgeSecs: ev.shiftKey ? -0.05 : -0.01 }));
    $("#song-later").addEventListener("click", (ev) => this.correct({ nudgeSecs: ev.shiftKey ? 0.05 : 0.01 }));
    $("#song-downbeat").addEventListener("click", () => this.correct({ firstDownbeatSecs: this.player.position() }));
    $("#song-reset").addEventListener("click", () => { if (this.song) { const g = this.song.reset(); if (this.onCorrect) this.onCorrect(null); this.setGrid(g); } });
    $("#song-metronome").addEventListener("change", (ev) => { this.player.metronome = ev.target.checked; });
    $("#song-tap").addEventListener("click", (ev) => this.tap(ev.timeStamp));
    $("#repeat-mark").addEventListener("click", () => this.markRepeat());
    for (const id of ["#repeat-first", "#repeat-last", "#repeat-of"]) {
      $(id).addEventListener("keydown", (ev) => { if (ev.key === "Enter") this.markRepeat(); });
    }
    $("#repeat-list").addEventListener("click", (ev) => {
      const b = ev.target.closest("[data-first-bar]");
      if (b) this.removeRepeat(Number(b.dataset.firstBar));
    });
    this.canvas.addEventListener("click", (ev) => {
      if (!this.song) return;
      const r = this.canvas.getBoundingClientRect();
      const t = ((ev.clientX - r.left) / r.width) * this.grid.durationSecs;
      if (ev.shiftKey) this.correct({ firstDownbeatSecs: t });
      else this.player.seek(t);
    });
  }

  /** The app's one transport (the Player): the song button asks it, and shows its state. */
  attachTransport(transport) {
    this.transport = transport;
    transport.onChange((st) => {
      const b = this.$("#song-play");
      b.textContent = st.songPlaying ? "Pause song" : "Play song";
      b.setAttribute("aria-pressed", String(st.songPlaying));
    });
  }

  load(song, name, buffer) {
    this.song = song;
    this.name = name;
    this.player.load(buffer);
    this.setGrid(song.grid());
  }

  /** A tap at `atMs` (the click's own time stamp, on performance.now()'s clock: a tap that
   * waits while the page is busy — the dance re-rendered on the last tap's grid — still
   * counts when it was made, not when it is handled). */
  tap(atMs = performance.now()) {
    const now = (Number.isFinite(atMs) && atMs > 0 ? atMs : performance.now()) / 1000;
    if (this.taps.length && now - this.taps[this.taps.length - 1] > TAP_GAP_SECS) this.taps = [];
    this.taps.push(now);
    this.$("#song-tap").textContent = `Tap (${this.taps.length})`;
    if (this.taps.length >= 4) this.correct({ tapTimesSecs: this.taps.slice(-16) });
    // A pause longer than a beat could be ends the tapping: the counter goes back to plain Tap.
    clearTimeout(this.tapTimer);
    this.tapTimer = setTimeout(() => { this.taps = []; this.$("#song-tap").textContent = "Tap"; }, TAP_GAP_SECS * 1000);
  }

  correct(correction) {
    if (!this.song) return;
    try {
      const grid = this.song.correct(correction);
      // The project first, so the dance mirrored on the new grid finds the same bars there.
      if (this.onCorrect) this.onCorrect(correction);
      this.setGrid(grid);
    } catch (e) {
      this.messages.error(`${this.name}: ${e.message}`);
      this.setGrid(this.grid);
    }
  }

  setGrid(grid) {
    this.grid = grid;
    this.player.setGrid(grid);
    this.$("#song-bpm").value = grid.bpm.toFixed(1);
    this.$("#song-bpb").value = String(grid.beatsPerBar);
    this.$("#song-info").title = this.$("#song-info").textContent = `${this.name} — ${grid.bpm.toFixed(1)} BPM, ${grid.bars.length} bars of ${grid.beatsPerBar}${grid.regular ? " (regular grid)" : ""}${grid.clearBeat === false ? " — no clear beat found: the grid is a guess; type the tempo or tap along" : ""}`;
    this.root.dataset.bars = String(grid.bars.length);
    this.sections = null;
    this.repeats = null;
    delete this.root.dataset.sections;
    delete this.root.dataset.sectionStarts;
    this.draw();
    if (this.onGrid) this.onGrid(grid);
  }

  toggle() {
    if (this.transport) { this.transport.toggleSong(); return; }
    if (this.player.playing) this.player.stop(); else this.player.play();
  }

  /** The project's sections for the grid shown, fetched once per grid (null while the project's
   * grid is not this one yet: they are asked again at the next draw). */
  currentSections() {
    if (this.sections || !this.getSections || !this.grid) return this.sections;
    let s;
    try { s = this.getSections(); } catch (e) { return null; }
    const list = s?.sections ?? [];
    const covered = list.reduce((n, x) => n + x.bars, 0);
    if (!list.length || covered !== this.grid.bars.length) return null;
    this.sections = list;
    const letter = (x) => String.fromCharCode(65 + (x.label % 26));
    this.root.dataset.sections = list.map(letter).join("");
    this.root.dataset.sectionStarts = list.map((x) => x.firstBar).join(",");
    return list;
  }

  /** The project's repeat runs for the grid shown (null while the project's grid is not this
   * one yet), listed below the strip with a button each that removes it. */
  currentRepeats() {
    if (this.repeats || !this.repeatEdits || !this.grid) return this.repeats;
    let list;
    try { list = this.repeatEdits.list() ?? []; } catch (e) { return null; }
    const n = this.grid.bars.length;
    if (list.some((r) => r.firstBar + r.bars > n)) return null;
    this.repeats = list;
    const range = (a, k) => (k > 1 ? `${a + 1}–${a + k}` : `${a + 1}`);
    this.root.dataset.repeats = list.map((r) => `${r.firstBar + 1}-${r.firstBar + r.bars}=${r.ofBar + 1}${r.marked ? "m" : ""}`).join(",");
    const box = this.$("#repeat-list");
    box.replaceChildren(...list.map((r) => {
      const b = document.createElement("button");
      b.type = "button";
      b.className = "repeat-remove";
      b.dataset.firstBar = String(r.firstBar);
      b.textContent = `Remove ${range(r.firstBar, r.bars)} = bar ${r.ofBar + 1}${r.marked ? " (marked)" : ""}`;
      b.title = `Bars ${range(r.firstBar, r.bars)} take the moves of bars ${range(r.ofBar, r.bars)} (${r.marked ? "marked" : "found in the song"}); remove this repeat and Generate fills them on their own (one undo step)`;
      return b;
    }));
    return list;
  }

  /** After an edit, undo or redo of the project: show its repeats again. */
  refreshRepeats() {
    this.repeats = null;
    this.draw();
  }

  /** Marks the bars typed (from 1, as the strip numbers them) as repeating the earlier bars typed. */
  markRepeat() {
    if (!this.repeatEdits || !this.grid) return;
    const $ = this.$;
    const first = Number($("#repeat-first").value), last = Number($("#repeat-last").value), of = Number($("#repeat-of").value);
    if (![first, last, of].every((v) => Number.isInteger(v) && v >= 1) || last < first) {
      this.messages.error("Repeat: type the first and last bar of the repeat and the first bar it repeats (whole numbers from 1, the last not before the first)");
      return;
    }
    const bars = last - first + 1;
    try {
      this.repeatEdits.mark(first - 1, bars, of - 1, bars);
      this.messages.info(`Bars ${first}–${last} repeat bars ${of}–${of + bars - 1}: Generate gives them the same moves`);
    } catch (e) {
      this.messages.error(`Repeat: ${e.message}`);
    }
    this.refreshRepeats();
  }

  /** Removes the repeat that starts at bar `firstBar` (from 0). */
  removeRepeat(firstBar) {
    if (!this.repeatEdits) return;
    try {
      const r = this.repeatEdits.remove(firstBar);
      this.messages.info(`Bars ${r.firstBar + 1}–${r.firstBar + r.bars} no longer repeat bar ${r.ofBar + 1}`);
    } catch (e) {
      this.messages.error(`Repeat: ${e.message}`);
    }
    this.refreshRepeats();
    const next = this.$("#repeat-list button") ?? this.$("#repeat-first");
    if (next) next.focus();
  }

  /** Sections as bands along the foot of the strip: a colour per label, a letter each (a repeat names the section
   * it repeats); a line at each section change. */
  drawSections(g, x, h, dpr) {
    const list = this.currentSections() ?? [];
    const repeats = this.currentRepeats() ?? [];
    const bars = this.grid.bars;
    const band = 14 * dpr;
    const hues = [210, 30, 130, 280, 350, 60, 180, 0];
    g.font = `bold ${10 * dpr}px system-ui`;
    for (const s of list) {
      const first = bars[s.firstBar], last = bars[s.firstBar + s.bars - 1];
      if (!first || !last) continue;
      const x0 = x(first.startSecs), x1 = x(last.endSecs);
      g.fillStyle = `hsl(${hues[s.label % hues.length]}, 60%, 42%)`;
      g.fillRect(x0, h - band, x1 - x0, band);
      g.fillStyle = "#ffffff";
      g.fillRect(x0, 0, Math.max(1, 2 * dpr), h);
      // A repeat takes the moves of the first section of its label (as Generate does), unless
      // the person removed it.
      const found = repeats.some((r) => !r.marked && r.firstBar === s.firstBar);
      const src = s.repeatOf != null && found ? list.find((o) => o.label === s.label) : null;
      const name = String.fromCharCode(65 + (s.label % 26)) + (src && src !== s ? ` = bar ${src.firstBar + 1}` : "");
      if (x1 - x0 > 12 * dpr) g.fillText(name, x0 + 3 * dpr, h - 3 * dpr, Math.max(1, x1 - x0 - 4 * dpr));
    }
    // Marked repeats: a band above the sections', named after the bar they repeat.
    for (const r of repeats) {
      if (!r.marked) continue;
      const first = bars[r.firstBar], last = bars[r.firstBar + r.bars - 1];
      if (!first || !last) continue;
      const x0 = x(first.startSecs), x1 = x(last.endSecs);
      g.fillStyle = "rgba(255, 214, 102, 0.85)";
      g.fillRect(x0, h - 2 * band, x1 - x0, band - dpr);
      g.fillStyle = "#10121a";
      if (x1 - x0 > 12 * dpr) g.fillText(`= bar ${r.ofBar + 1} (marked)`, x0 + 3 * dpr, h - band - 4 * dpr, Math.max(1, x1 - x0 - 4 * dpr));
    }
  }

  draw() {
    const c = this.canvas;
    const dpr = Math.min(window.devicePixelRatio || 1, 2);
    const w = Math.max(1, Math.round(c.clientWidth * dpr)), h = Math.max(1, Math.round(c.clientHeight * dpr));
    if (c.width !== w || c.height !== h) { c.width = w; c.height = h; }
    const g = c.getContext("2d");
    g.fillStyle = "#10121a";
    g.fillRect(0, 0, w, h);
    if (!this.grid) return;
    const { loudness, durationSecs: dur, bars, beatTimesSecs } = this.grid;
    const x = (t) => (t / dur) * w;
    // Bars shaded by their intensity, so loud sections read at a glance.
    for (const b of bars) {
      g.fillStyle = `rgba(242, 115, 26, ${0.05 + 0.25 * b.intensity})`;
      g.fillRect(x(b.startSecs), 0, x(b.endSecs) - x(b.startSecs), h);
    }
    // Loudness as a mirrored envelope.
    g.fillStyle = "#7fb6ff";
    const vals = loudness.values, step = Math.max(1, Math.floor(vals.length / w));
    for (let i = 0; i < vals.length; i += step) {
      let m = 0;
      for (let k = i; k < Math.min(vals.length, i + step); k++) m = Math.max(m, vals[k]);
      const px = x(i * loudness.hopSecs), hh = m * (h * 0.42);
      g.fillRect(px, h / 2 - hh, Math.max(1, w / (vals.length / step)), 2 * hh);
    }
    this.drawSections(g, x, h, dpr);
    // Beat lines thin, bar lines bold and numbered.
    g.fillStyle = "rgba(230, 230, 234, 0.25)";
    for (const t of beatTimesSecs) g.fillRect(x(t), h * 0.75, 1, h * 0.25);
    g.fillStyle = "#e6e6ea";
    g.font = `${10 * dpr}px system-ui`;
    let lastLabel = -1e9;
    for (const b of bars) {
      const px = x(b.startSecs);
      g.fillRect(px, 0, Math.max(1, dpr), h);
      if (px - lastLabel > 24 * dpr) { g.fillText(String(b.index + 1), px + 2 * dpr, 11 * dpr); lastLabel = px; }
    }
    // Playhead.
    const p = this.player.position();
    g.fillStyle = "#f2731a";
    g.fillRect(x(p) - dpr, 0, 2 * dpr, h);
  }
}
