// The app's project session: what a person makes in the page is held in one wasm `Project`
// (spec §K) and autosaved to IndexedDB by `ProjectStore` (store.js).
//
// Design (the least invasive path that is real): the panels keep their own handles for display
// (`Library`, `Song`, `TextAnimator`, `Choreographer`), and every edit they make is mirrored
// into the Project through the hooks below — imported files (name, bytes as given, import
// options), the song (bytes, or none for the built-in demo song, plus the envelope the page
// computed), every grid correction and reset, clip tags and texts. Each mirrored edit
// schedules an autosave. On start-up the last project is read back from IndexedDB and the page
// is rebuilt from it by replaying its document through the same panels: the motion files are
// imported again from their stored bytes with their options, the song is decoded and analysed
// again and its corrections applied in order, tags and texts are applied again. New project,
// Open… (.odori, also dropped on the page) and a Recent pick switch the stored "last project"
// and reload the page, so one rebuild path serves all of them. Save as writes `Project.save()`
// through the File System Access API where the browser has it, a download otherwise.
//
// The dance: after every change the Choreographer panel shows (Set, Unpin, Generate, undo/redo,
// a shared link), each bar's state is compared with the Project's and the differences are
// applied by stable key (`MoveKey`: the built-in move, or the source clip, its cut tempo and
// the count the segment starts on, `Choreographer.firstCount`), so the Project holds exactly the
// dance on screen (a generated bar is set, then unpinned: the Project never generates on its
// own). A restore sets those keys back into the Choreographer. Re-cutting a clip and ρ and the
// music weight are mirrored too.
//
// Not mirrored yet: a bar's open search (shown and liked candidates: they are the page
// Choreographer's rounds, which the Project would have to replay). The Project's undo history
// holds the mirrored edits; the page's Undo button stays the Choreographer's.
import { ProjectStore, openStore } from "./store.js";
import { saveBytes, pickFile, fileNameFor, isOdoriFile } from "./file.js";

const LAST_KEY = "odori.lastProject";

export class ProjectSession {
  /**
   * @param {{ Project, messages, library }} deps `Project`: the wasm class; `library`: the page's
   *   `Library` (its clip ids are mapped to the Project's `{ source, clip }`).
   */
  constructor({ Project, messages, library }) {
    Object.assign(this, { Project, messages, library });
    this.project = null;
    this.store = null;
    /** Library clip id → the Project's ClipRef. */
    this.clipRefs = new Map();
    /** True while the page is being rebuilt from the project (edits are not mirrored then). */
    this.replaying = false;
  }

  /** Opens the store and the last project (or a new one). Returns the project's document. */
  async start() {
    let restored = null;
    try {
      const db = await openStore();
      this.store = new ProjectStore(db, {
        onError: (m) => this.messages.error(m),
        onConflict: (m) => this.messages.warning(m),
        onSaved: (info) => { if (info.recovered) this.messages.info("Saved in the browser again."); document.body.dataset.saved = String(Date.now()); },
      });
      const id = await this.store.lastId();
      if (id) {
        try {
          const { project, missing } = await this.store.load(this.Project, id);
          for (const m of missing) this.messages.error(`This project lacks ${m.what} (${m.hash.slice(0, 12)}…): the rest is opened.`);
          await this.store.attach(project, id);
          this.project = project;
          restored = project.doc();
        } catch (e) {
          this.messages.error(`The last project could not be read back (${e.message}); a new one is started, the stored copy is kept.`);
        }
      }
    } catch (e) {
      this.messages.error(`Browser storage is not available (${e.message}): work is kept in this tab only; use Save as to keep a file.`);
      this.store = null;
    }
    if (!this.project) {
      this.project = new this.Project();
      this.project.setName("Untitled");
      if (this.store) await this.store.attach(this.project);
    }
    return restored;
  }

  edited() {
    if (this.store) this.store.schedule();
  }

  /** Runs a mirrored edit; a refusal is reported, never thrown into the panel that made it. */
  mirror(what, f) {
    if (this.replaying || !this.project) return undefined;
    try {
      const r = f(this.project);
      this.edited();
      return r;
    } catch (e) {
      this.messages.error(`Project: ${what} is not kept in the project: ${e.message}`);
      return undefined;
    }
  }

  /** An imported motion file (the page's import `report` maps its clip ids to the Project's). */
  addSource(fileName, bytes, options, report) {
    const r = this.mirror(`${fileName}`, (p) => p.addSource(fileName, bytes, options && options.fpsOverride ? { fpsOverride: options.fpsOverride } : undefined));
    if (r) this.mapClips(r.id, report);
  }

  mapClips(sourceId, report) {
    report.clips.forEach((c, k) => this.clipRefs.set(c.id, { source: sourceId, clip: k }));
  }

  /** The song: its bytes (undefined for the built-in demo song) and its RMS envelope. */
  setSong(fileName, bytes, env) {
    this.mirror(`the song ${fileName}`, (p) => p.setSong(fileName, bytes, env.hopSecs, env.bands, undefined));
  }

  correctGrid(correction) { this.mirror("the grid correction", (p) => p.correctGrid(correction)); }
  resetGrid() { this.mirror("the grid reset", (p) => p.resetGrid()); }
  setTexts(texts) { this.mirror("the text", (p) => p.setTexts(texts)); }

  setTags(clipId, tags) {
    const ref = this.clipRefs.get(clipId);
    if (!ref) return; // the built-in clip and made clips are not sources of the project
    this.mirror("the tags", (p) => p.setTags(ref, tags));
  }

  /** The stable key of Choreographer segment `seg` (undefined when it has none in the project). */
  keyOf(choreographer, seg) {
    const s = choreographer.segment(seg);
    if (!s) return undefined;
    if (s.builtin) return { kind: "builtin", move: s.builtin };
    const cut = choreographer.cutClips().find((c) => c.clip === s.clip);
    const ref = cut && this.clipRefs.get(cut.id);
    const first = choreographer.firstCount(seg);
    if (!ref || first == null) return undefined;
    return { kind: "cut", clip: ref, cutTempoBpm: cut.tempoDetected ? null : cut.tempoBpm, firstCount: first };
  }

  /** Makes the Project's dance the one the Choreographer holds (see the top of this file). */
  syncDance(choreographer, view, settings) {
    if (this.replaying || !this.project || !view.length) return;
    // Whatever happens here, the panel that called goes on.
    try { this.syncDanceNow(choreographer, view, settings); } catch (e) { this.messages.error(`Project: the dance is not kept in the project: ${e.message}`); }
  }

  syncDanceNow(choreographer, view, settings) {
    const bars = this.project.doc().dance.bars;
    if (bars.length !== view.length) return; // the Project's grid differs (mid-correction): next time
    const same = (a, b) => JSON.stringify(a) === JSON.stringify(b);
    const ops = [];
    view.forEach((v, i) => {
      const want = v.state.kind;
      const key = want === "empty" ? null : this.keyOf(choreographer, v.state.segment);
      if (want !== "empty" && !key) return;
      const have = bars[i];
      if (have.state === want && (want === "empty" || same(have.move, key))) return;
      if (want === "empty") { ops.push((p) => p.clear(i)); return; }
      ops.push((p) => { p.set(i, key); if (want === "generated") p.unpin(i); });
    });
    const st = this.project.doc().dance.settings;
    if (settings && Math.abs(st.rho - settings.rho) > 1e-6) ops.push((p) => p.setRho(settings.rho));
    if (settings && Math.abs(st.fill.musicWeight - settings.musicWeight) > 1e-6) ops.push((p) => p.setMusicWeight(settings.musicWeight));
    if (ops.length) this.mirror("the dance", (p) => { for (const op of ops) op(p); });
  }

  /** A clip re-cut at `tempoBpm` (undefined: its detected tempo). */
  recut(clipId, tempoBpm) {
    const ref = this.clipRefs.get(clipId);
    if (ref) this.mirror("the clip's new cut", (p) => p.setClipTempo(ref, tempoBpm));
  }

  /** Sets the restored dance into the Choreographer (`setState(bar, segment, pinned)`). */
  restoreDance(doc, choreographer, setState) {
    const byKey = new Map();
    for (let i = 0; i < choreographer.segmentCount; i++) {
      const k = this.keyOf(choreographer, i);
      if (k) byKey.set(JSON.stringify(k), i);
    }
    let lost = 0;
    doc.dance.bars.forEach((b, i) => {
      if (b.state === "empty" || !b.move) return;
      const seg = byKey.get(JSON.stringify(b.move));
      if (seg == null) { lost++; return; }
      setState(i, seg, b.state === "pinned");
    });
    if (lost) this.messages.error(`${lost} bar${lost > 1 ? "s" : ""} of the dance name a move this page no longer has: left empty.`);
  }

  /** A library clip removed by the person: its file leaves the project when none of its clips stay. */
  clipRemoved(clipId) {
    const ref = this.clipRefs.get(clipId);
    if (!ref) return;
    this.clipRefs.delete(clipId);
    if ([...this.clipRefs.values()].some((r) => r.source === ref.source)) return;
    this.mirror("removing the file", (p) => p.removeSource(ref.source));
  }

  /**
   * Rebuilds the page from `doc` through the panels' own entry points: `importSource(fileName,
   * bytes, options)` → import report; `loadSong(fileName, bytes | undefined)` → the page's
   * `Song` once analysed; `tag(clipId, tags)`; `animate(text)`.
   */
  async replay(doc, { importSource, loadSong, applyCorrection, tag, animate, dance }) {
    this.replaying = true;
    try {
      for (const s of doc.sources) {
        const bytes = this.project.blob(s.blob);
        if (!bytes) { this.messages.error(`${s.fileName}: its bytes are missing from the project`); continue; }
        // The core's ImportOptions, as the document keeps them (snake_case).
        const o = s.options || {};
        const report = importSource(s.fileName, bytes, o.fps_override ? { fpsOverride: o.fps_override } : {});
        if (report) this.mapClips(s.id, report);
      }
      if (doc.song) {
        const bytes = doc.song.audio ? this.project.blob(doc.song.audio) : undefined;
        if (doc.song.audio && !bytes) this.messages.error(`${doc.song.fileName}: the song's audio is missing from the project`);
        else {
          const loaded = await loadSong(doc.song.fileName, bytes);
          if (loaded) for (const c of doc.song.corrections) applyCorrection(c);
        }
      }
      for (const t of doc.tags) {
        const id = [...this.clipRefs].find(([, r]) => r.source === t.clip.source && r.clip === t.clip.clip)?.[0];
        if (id != null) tag(id, t.tags);
      }
      if (doc.texts.length) animate(doc.texts[doc.texts.length - 1]);
      if (dance) dance(doc);
    } finally {
      this.replaying = false;
    }
  }

  /** Switches the page to another stored project (or a new one, `null`) by reloading. */
  async switchTo(id) {
    if (this.store) await this.store.detach();
    if (id) localStorage.setItem(LAST_KEY, id); else localStorage.removeItem(LAST_KEY);
    location.reload();
  }

  async newProject() {
    if (!this.store) { location.reload(); return; }
    const p = new this.Project();
    p.setName(`Project ${new Date().toLocaleString()}`);
    await this.store.attach(p);
    await this.store.flush();
    await this.switchTo(this.store.projectId);
  }

  /** Opens `.odori` bytes: the open project stays untouched when the file is bad. */
  async openBytes(name, bytes) {
    let p;
    try {
      p = this.Project.open(bytes);
    } catch (e) {
      this.messages.error(`${name}: ${e.message} (the open project is unchanged)`);
      return false;
    }
    for (const m of p.missing()) this.messages.error(`${name} lacks ${m.what}: the rest is opened.`);
    if (!this.store) { this.messages.error(`${name}: opening needs the browser's storage, which is not available here`); return false; }
    await this.store.attach(p);
    await this.store.flush();
    if (this.store.lastError) return false;
    await this.switchTo(this.store.projectId);
    return true;
  }

  async open() {
    try {
      const f = await pickFile();
      if (f) await this.openBytes(f.name, f.bytes);
    } catch (e) { this.messages.error(`Open: ${e.message}`); }
  }

  async saveAs() {
    try {
      const bytes = this.project.save();
      const r = await saveBytes(bytes, fileNameFor(this.project.doc().name));
      if (r) this.messages.info(`Saved ${r.name} (${(bytes.length / 1024).toFixed(0)} KiB)`);
      return bytes;
    } catch (e) { this.messages.error(`Save as: ${e.message}`); return null; }
  }

  /** Wires the top bar: New, Open…, Save as, the Recent menu, and .odori files dropped. */
  async bindButtons({ newButton, openButton, saveButton, recent }) {
    newButton.addEventListener("click", () => this.newProject());
    openButton.addEventListener("click", () => this.open());
    saveButton.addEventListener("click", () => this.saveAs());
    recent.addEventListener("change", () => { const id = recent.value; recent.value = ""; if (id) this.switchTo(id); });
    recent.addEventListener("focus", () => this.fillRecent(recent));
    await this.fillRecent(recent);
  }

  async fillRecent(select) {
    const list = this.store ? await this.store.recent() : [];
    const opts = [new Option("Recent projects…", "")];
    for (const r of list) {
      const o = new Option(`${r.name || "Untitled"} — ${new Date(r.updatedAt).toLocaleString()}${r.id === this.store.projectId ? " (open)" : ""}`, r.id);
      o.disabled = r.id === this.store.projectId;
      opts.push(o);
    }
    select.replaceChildren(...opts);
  }

  /** Takes the .odori files out of a drop (the rest are motion files). */
  takeProjectFiles(files) {
    const odori = files.filter(isOdoriFile);
    for (const f of odori) f.arrayBuffer().then((b) => this.openBytes(f.name, new Uint8Array(b)));
    return files.filter((f) => !isOdoriFile(f));
  }
}
