// The dance panel's engine is the Project itself. `ProjectDance` answers the calls the panel
// (ui/choreo-panel.js), the share link (share.js) and the tests make of a dance engine — view,
// candidates, search, set, unpin, generate, undo/redo, previews, quality, the join table — by
// calling the one wasm `Project` the page holds (www/project/app.js): the segment library is
// the project's (the built-in moves plus every humanoid clip of its sources, cut once), bars
// and searches are kept in the project by stable keys, and undo/redo is the project's history,
// which covers every edit the page makes (imports, the song and its grid, tags, texts, the
// dance). Segment numbers only live here, between the project and the panel: the project maps
// them to keys in each call.

export class ProjectDance {
  /** @param {import("./app.js").ProjectSession} session */
  constructor(session) {
    this.session = session;
  }

  get project() { return this.session.project; }

  /** Runs a project edit and has it autosaved. */
  edit(f) {
    const r = f(this.project);
    this.session.edited();
    return r;
  }

  /** Runs `f` (several edits: a share link applied bar by bar) as one project edit: one undo takes it all back. */
  batch(f) {
    this.project.beginGroup();
    try { return f(); } finally { this.project.endGroup(); this.session.edited(); }
  }

  // The built-in moves and the join table, a slice at a time (the page stays responsive).
  loadBuiltin(count) { return this.project.loadBuiltin(count); }
  prepareTable(columns) { return this.project.prepareTable(columns); }
  get tableReady() { return this.project.tableReady; }
  get segmentCount() { return this.project.segmentCount; }

  /** The bars come from the project's own grid (its song and corrections): nothing to set. */
  setBars() {}

  /**
   * A library clip in the dance library: the project cut it when its file was imported; this
   * returns that cut (`{ clip, name, tempoBpm, tempoDetected, beats, segments }`) or throws
   * why it is not in the dance library.
   */
  addClip(library, clipId) {
    const info = this.session.projectClip(clipId);
    if (!info) throw new Error(`${library.clip(clipId).name} is not a file of the project`);
    if (!info.cut) throw new Error(`${info.name}: ${info.refused || "not in the dance library"}`);
    return info.cut;
  }

  /** Imported clips in the dance library, with their library ids: `{ id, clip, name, tempoBpm, tempoDetected, beats, segments }[]`. */
  cutClips() {
    const out = [];
    for (const c of this.project.clips()) {
      const id = this.session.libraryId(c.clip);
      if (c.cut && id != null) out.push({ id, ...c.cut });
    }
    return out;
  }

  /**
   * Re-cuts a clip at `tempoBpm` (undefined: its detected beats) as one project edit. Returns
   * `{ clip, removed, kept, pinnedBars, generatedBars }`: bars holding a move of the earlier
   * cut keep it (the project keeps that cut in its library, never offered again).
   */
  recutClip(clipId, tempoBpm) {
    const ref = this.session.clipRefs.get(clipId);
    if (!ref) throw new Error(`clip ${clipId} is not in the dance library (only humanoid clips of the project's files are)`);
    // The engine says what the re-cut meant for the dance (the page never reads the schema).
    return this.edit((p) => p.recutClip(ref, tempoBpm));
  }

  segment(index) { return this.project.segment(index); }
  keyOf(index) { return this.project.keyOf(index); }
  view() { return this.project.danceView(); }

  /** A bar's candidates (looking is not an edit: no undo step, but the open search is kept). */
  candidates(bar) { return this.edit((p) => p.candidateSegments(bar)); }
  search(bar, liked) { return this.edit((p) => p.searchSegments(bar, Array.from(liked))); }
  set(bar, segment) { return this.edit((p) => p.setSegment(bar, segment)); }
  unpin(bar) { return this.edit((p) => p.unpin(bar)); }
  clear(bar) { return this.edit((p) => p.clear(bar)); }
  resetSearch(bar) { return this.edit((p) => p.resetSearch(bar)); }
  setRho(rho) { return this.edit((p) => p.setRho(rho)); }
  setMusicWeight(w) { return this.edit((p) => p.setMusicWeight(w)); }
  /** Which moves Generate uses: "mine", "mixed" or "builtin". */
  setMovesSource(source) { return this.edit((p) => p.setMovesSource(source)); }
  get movesSource() { return this.project.movesSource; }
  /** Fills every open bar: one project edit (one undo takes the whole Generate back). `{ take }`: which take (0: Generate's dance; another take: a different dance of comparable cost). */
  generate(options) { return this.edit((p) => p.generate(options)); }
  /** The take of Generate the dance comes from. */
  get take() { return this.project.take; }

  quality(beatTimesSecs) { return this.project.quality(beatTimesSecs); }
  /** Each bar's move (name, source) and weak spots in words, with the readout: `{ quality, notes }`. */
  barNotes(beatTimesSecs) { return this.project.barNotes(beatTimesSecs); }
  /** Candidates' notes, each measured in place, clean ones first (the engine's ranking). */
  candidateNotes(bar, segments, beatTimesSecs) { return this.project.candidateNotes(bar, Array.from(segments), beatTimesSecs); }
  renderDance(library, replace) { return this.project.renderDance(library, replace); }
  previewSegment(library, segment, durationSecs, replace) { return this.project.previewSegment(library, segment, durationSecs, replace); }

  /** The project's history: every edit of the page, not only the dance's. */
  undo() { return this.session.undo(); }
  redo() { return this.session.redo(); }
  canUndo() { return this.project.canUndo(); }
  canRedo() { return this.project.canRedo(); }
}
