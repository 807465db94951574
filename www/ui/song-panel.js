// The song strip: loudness over time with beat and bar lines, the playhead, and the grid
// corrections (BPM, tap tempo, nudge, downbeat, beats per bar, reset) that re-derive the
// bars at once. Shift-click on the strip puts a downbeat there; a plain click seeks. Along the
// strip's foot, the song's sections (the engine's `music::sections`, the analysis Generate repeats moves
// on and the video's director camera cuts on): a letter each, a repeated section named after the
// one it repeats.
/** Taps further apart than this start a new count. */
const TAP_GAP_SECS = 2.5;

export class SongPanel {
  constructor(root, { player, onGrid, messages, onCorrect, sections }) {
    this.getSections = sections; // () => the project's sections ({ sections: [...] }) or undefined
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
    this.$("#song-info").textContent = `${this.name} — ${grid.bpm.toFixed(1)} BPM, ${grid.bars.length} bars of ${grid.beatsPerBar}${grid.regular ? " (regular grid)" : ""}${grid.clearBeat === false ? " — no clear beat found: the grid is a guess; type the tempo or tap along" : ""}`;
    this.root.dataset.bars = String(grid.bars.length);
    this.sections = null;
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

  /** Sections as bands along the foot of the strip: a colour per label, a letter each (a repeat names the section
   * it repeats); a line at each section change. */
  drawSections(g, x, h, dpr) {
    const list = this.currentSections();
    if (!list) return;
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
      // A repeat takes the moves of the first section of its label (as Generate does).
      const src = s.repeatOf != null ? list.find((o) => o.label === s.label) : null;
      const name = String.fromCharCode(65 + (s.label % 26)) + (src && src !== s ? ` = bar ${src.firstBar + 1}` : "");
      if (x1 - x0 > 12 * dpr) g.fillText(name, x0 + 3 * dpr, h - 3 * dpr, Math.max(1, x1 - x0 - 4 * dpr));
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
