// The app's project session: what a person makes in the page is held in one wasm `Project`
// (spec §K) and autosaved to IndexedDB by `ProjectStore` (store.js).
//
// The Project drives the page. Every edit is an operation on it, made once: an imported file is
// parsed by the project, which shows the same clips in the page's `Library` (the viewer's clip
// store) and cuts its humanoid clips into its own dance library; the dance panel's engine is
// the project (`ProjectDance`, dance.js: bars, searches and Generate are project edits by
// stable keys); the song, its grid corrections, tags and texts are project edits too. The
// page's Undo/Redo (the dance panel's buttons, Ctrl+Z / Ctrl+Shift+Z / Ctrl+Y) are the
// project's history, so one undo takes back the last edit whatever made it, a whole Generate
// included. The page holds only what it displays: after an undo or redo, and when a stored
// project is opened, `reconcile` brings the display in line with the project's document —
// clips of files added or gone, the song and its grid, tags, texts, the dance settings — and
// the dance panel reads the rest (bars, open searches with their shown and liked candidates)
// from the project itself. The chosen character and the clips put on it ("Put on") are project
// edits too: a put-on clip is kept as its recipe (the character, and the motion's project clip
// or, for a clip made in the page, the BVH the engine writes of it) and rebuilt from it.
//
// Edits made while a stored project is being shown (the second or so after a reload) are
// project edits like any other: nothing the person does then is dropped (the display hooks of
// `reconcile` never call back into the session).
//
// New project, Open… (.odori, also dropped on the page) and a Recent pick switch the stored
// "last project" and reload the page, so one rebuild path serves all of them. Save as writes
// `Project.save()` through the File System Access API where the browser has it, a download
// otherwise.
import { ProjectStore, openStore, NEW_PROJECT } from "./store.js";
import { saveBytes, pickFile, fileNameFor, isOdoriFile } from "./file.js";

const LAST_KEY = "odori.lastProject";

export class ProjectSession {
  /**
   * @param {{ Project, messages, library }} deps `Project`: the wasm class; `library`: the page's
   *   `Library` (the clips the project shows; their ids are mapped to the Project's `{ source, clip }`).
   */
  constructor({ Project, messages, library }) {
    Object.assign(this, { Project, messages, library });
    this.project = null;
    this.store = null;
    /** Library clip id → the Project's ClipRef. */
    this.clipRefs = new Map();
    /** What the page shows of the document (see `reconcile`). */
    this.shown = { sources: new Map(), song: null, corrections: "[]", tags: "[]", texts: "[]", character: bodyKey({}), worn: [], cameras: "[]", faceTracks: "[]" };
    /** Called after every edit (undo/redo buttons). */
    this.onEdited = null;
    /** The display hooks `reconcile` uses (set by the page, see main.js). */
    this.view = null;
  }

  /** Opens the store and the last project (or a new one). Returns the restored project's summary (`Project.summary()`), or null for a new one. */
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
          restored = project.summary();
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
      // Each project is listed once by its name in Recent projects: a new one takes a free name.
      this.project.setName(this.store ? await this.store.freeName("Untitled") : "Untitled");
      // Not stored until the person makes something (the demo song set for it is not that).
      if (this.store) await this.store.attach(this.project, null, { pristine: true });
    }
    return restored;
  }

  /** After every edit: autosave, and the undo/redo buttons. `automatic`: an edit the page made
   * by itself (a new project's demo song), which does not store a project not yet stored. */
  edited(automatic = false) {
    if (this.store && !(automatic && this.store.pristine)) this.store.schedule();
    if (this.onEdited) this.onEdited();
  }

  /** Runs a project edit; a refusal is reported, never thrown into the panel that made it. */
  mirror(what, f, automatic = false) {
    if (!this.project) return undefined;
    try {
      const r = f(this.project);
      this.markShown();
      this.edited(automatic);
      return r;
    } catch (e) {
      this.messages.error(`Project: ${what} is not kept in the project: ${e.message}`);
      return undefined;
    }
  }

  /** Records that the page shows the document as it is (after an edit the page made itself). */
  markShown() {
    const now = this.project.summary();
    this.shown.song = songKey(now.song);
    this.shown.corrections = JSON.stringify(now.song ? now.song.corrections : []);
    this.shown.tags = JSON.stringify(now.tags);
    this.shown.texts = JSON.stringify(now.texts);
    this.shown.character = bodyKey(now);
  }

  /**
   * Imports a motion file: the project parses it once and shows its clips in the page's
   * library. Returns the library's import report (throws the importer's error).
   */
  importFile(fileName, bytes, options, model) {
    // The file's own options (frame rate, units) are kept with its source: a reload imports it the same way.
    const o = {};
    if (options && options.fpsOverride) o.fpsOverride = options.fpsOverride;
    if (options && options.unitScale) o.unitScale = options.unitScale;
    // A VMD's song offset (the motion frame that is song time 0) is kept the same way.
    if (options && options.songOffsetFrames) o.songOffsetFrames = options.songOffsetFrames;
    // A VMD dance with its MMD model (`{ fileName, bytes }`): the project keeps the model and poses the dance on it.
    const report = model ? this.project.importOnModelInto(this.library, fileName, bytes, o, model.fileName, model.bytes) : this.project.importInto(this.library, fileName, bytes, o);
    this.mapClips(report.source, report);
    this.edited();
    return report;
  }

  /**
   * Imports a camera VMD into the project (kept with it, undoable) and shows the project's
   * camera motions in the library's `cameraTracks()`, where the video dialog finds them.
   * Returns the track's info (throws the engine's error: not a VMD, no camera keys).
   */
  importCamera(fileName, bytes, options) {
    const o = options && options.songOffsetFrames ? { songOffsetFrames: options.songOffsetFrames } : {};
    const info = this.project.addCameraInto(this.library, fileName, bytes, o);
    this.shown.cameras = JSON.stringify(this.project.summary().cameras);
    this.edited();
    return info;
  }

  /**
   * Keeps a lip-sync VMD (face keys only) as the project's face track (kept with it, undoable)
   * and shows the project's face tracks in the library, where the viewer plays them on the dance
   * drawn on an MMD model. Returns the track's info (throws the engine's error: not a VMD, no
   * morph keys, cut short).
   */
  importFaceTrack(fileName, bytes, options) {
    const o = options && options.songOffsetFrames ? { songOffsetFrames: options.songOffsetFrames } : {};
    const info = this.project.addFaceTrack(this.library, fileName, bytes, o);
    this.shown.faceTracks = JSON.stringify(this.project.summary().faceTracks);
    this.edited();
    return info;
  }

  mapClips(sourceId, report) {
    report.clips.forEach((c, k) => this.clipRefs.set(c.id, { source: sourceId, clip: k }));
    this.shown.sources.set(sourceId, report.clips.map((c) => c.id));
  }

  /** The project's facts about a library clip (`ClipInfo` with its cut), if it is a project clip. */
  projectClip(clipId) {
    const ref = this.clipRefs.get(clipId);
    return ref && this.project.clips().find((c) => c.clip.source === ref.source && c.clip.clip === ref.clip);
  }

  /** The library id showing a project clip (`{ source, clip }`), if shown. */
  libraryId(ref) {
    for (const [id, r] of this.clipRefs) if (r.source === ref.source && r.clip === ref.clip) return id;
    return undefined;
  }

  /** The song: its bytes (undefined for the built-in demo song) and its RMS envelope. */
  setSong(fileName, bytes, env) {
    // A new project's first song (the demo song) starts its history: undo never takes it away.
    const first = !this.project.summary().song;
    // The built-in demo song given to a new project is the page's doing, not the person's.
    this.mirror(`the song ${fileName}`, (p) => p.setSong(fileName, bytes, env.hopSecs, env.bands, undefined, !first), first && bytes === undefined);
  }

  correctGrid(correction) { this.mirror("the grid correction", (p) => p.correctGrid(correction)); }
  resetGrid() { this.mirror("the grid reset", (p) => p.resetGrid()); }
  setTexts(texts) { this.mirror("the text", (p) => p.setTexts(texts)); }

  setTags(clipId, tags) {
    const ref = this.clipRefs.get(clipId);
    if (!ref) return; // the built-in clip and made clips are not sources of the project
    this.mirror("the tags", (p) => p.setTags(ref, tags));
  }

  /**
   * The body chosen: a library clip of a project file (an imported character), "builtin", or
   * null (stick figures). The built-in body is not a file of the project: it is kept as no
   * character, which is also what a new project (and one made before the choice) shows;
   * stick figures are kept as the project's `stickFigures`.
   */
  setCharacter(clipId) {
    if (clipId === "builtin") { this.mirror("the character", (p) => p.setCharacter(undefined)); return; }
    if (clipId == null) { this.mirror("the character", (p) => p.setCharacter("stick")); return; }
    const ref = this.clipRefs.get(clipId);
    if (!ref) return;
    this.mirror("the character", (p) => p.setCharacter(ref));
  }

  /**
   * Puts library clip `motionId` on the character shown as library clip `characterId`, as a
   * project edit (kept, undoable; rebuilt from the project after a reload). Returns the new
   * clip's `ClipInfo`; throws why it cannot be put on (nothing changed).
   */
  putOn(motionId, characterId) {
    const character = this.clipRefs.get(characterId);
    if (!character) throw new Error("the character is not a file of the project");
    const info = this.project.putOnInto(this.library, motionId, this.clipRefs.get(motionId), characterId, character);
    this.shown.worn.push({ key: this.project.summary().worn[info.worn]?.key, id: info.id });
    this.edited();
    return info;
  }

  /** A library clip removed by the person: its file leaves the project when none of its clips stay. */
  clipRemoved(clipId) {
    const worn = this.shown.worn.findIndex((w) => w.id === clipId);
    if (worn >= 0) {
      this.shown.worn.splice(worn, 1);
      this.mirror("removing the put-on clip", (p) => p.removeWorn(worn));
      return;
    }
    const ref = this.clipRefs.get(clipId);
    if (!ref) return;
    this.clipRefs.delete(clipId);
    const ids = (this.shown.sources.get(ref.source) || []).filter((id) => id !== clipId);
    this.shown.sources.set(ref.source, ids);
    if (ids.length) return;
    this.shown.sources.delete(ref.source);
    this.mirror("removing the file", (p) => p.removeSource(ref.source));
  }

  /** Undo: the project's last edit, whatever made it; the page then shows the document. */
  undo() { return this.step((p) => p.undo()); }
  redo() { return this.step((p) => p.redo()); }

  step(f) {
    if (!this.project || !f(this.project)) return false;
    this.edited();
    this.reconcile().catch((e) => this.messages.error(`Project: ${e.message}`));
    return true;
  }

  /**
   * Brings the page's display in line with the project (after undo/redo, and when a stored
   * project is opened), read through `Project.summary()`, through `this.view`'s hooks, which only display:
   * `addClips(report)`, `removeClips(ids)`, `loadSong(fileName, bytes | undefined)` → true when
   * shown, `showCorrections(list)`, `retag(tags by library id)`, `addWorn(ClipInfo)` (a clip
   * put on the character), `character(library id | null)`, `animate(text)`, `dance(summary)`.
   */
  reconcile() {
    // One at a time, in order (a song decode is awaited inside).
    this.reconciling = (this.reconciling || Promise.resolve()).then(() => this.reconcileNow());
    return this.reconciling;
  }

  async reconcileNow() {
    const v = this.view;
    if (!v) return;
    const at = this.project.summary();
    const inDoc = new Set(at.sources);
    for (const [source, ids] of [...this.shown.sources]) {
      if (inDoc.has(source)) continue;
      this.shown.sources.delete(source);
      for (const id of ids) this.clipRefs.delete(id);
      v.removeClips(ids);
    }
    for (const id of at.sources) {
      if (this.shown.sources.has(id)) continue;
      try {
        const report = this.project.clipsInto(this.library, id);
        this.mapClips(id, report);
        v.addClips(report);
      } catch (e) {
        this.shown.sources.set(id, []);
        this.messages.error(e.message);
      }
    }
    const key = songKey(at.song);
    if (at.song && key !== this.shown.song) {
      const bytes = at.song.audio ? this.project.blob(at.song.audio) : undefined;
      if (at.song.audio && !bytes) this.messages.error(`${at.song.fileName}: the song's audio is missing from the project`);
      else {
        this.shown.song = key;
        this.shown.corrections = "[]";
        if (!(await v.loadSong(at.song.fileName, bytes))) this.shown.song = null;
      }
    }
    // The document may have moved on while the song was decoded: show the latest.
    const now = this.project.summary();
    const corrections = JSON.stringify(now.song ? now.song.corrections : []);
    if (now.song && this.shown.song === songKey(now.song) && corrections !== this.shown.corrections) {
      this.shown.corrections = corrections;
      v.showCorrections(now.song.corrections);
    }
    const tags = JSON.stringify(now.tags);
    if (tags !== this.shown.tags) {
      this.shown.tags = tags;
      v.retag(now.tags.map((t) => [this.libraryId(t.clip), t.tags]).filter(([id]) => id != null));
    }
    // Put-on clips: the ones still as shown stay, the rest are rebuilt from the document.
    const worn = now.worn;
    let same = 0;
    while (same < worn.length && same < this.shown.worn.length && this.shown.worn[same].key === worn[same].key) same++;
    const stale = this.shown.worn.splice(same).map((w) => w.id).filter((id) => id != null);
    if (stale.length) v.removeClips(stale);
    for (let i = same; i < worn.length; i++) {
      const key = worn[i].key;
      try {
        const info = this.project.wornInto(this.library, i, this.libraryId(worn[i].character));
        this.shown.worn.push({ key, id: info.id });
        if (v.addWorn) v.addWorn(info);
      } catch (e) {
        this.shown.worn.push({ key, id: null });
        this.messages.error(`A clip put on the character could not be made again: ${e.message}`);
      }
    }
    // Camera motions: the library shows the project's (the video dialog lists them).
    const cameras = JSON.stringify(now.cameras || []);
    if (cameras !== this.shown.cameras) {
      this.shown.cameras = cameras;
      for (const problem of this.project.camerasInto(this.library)) this.messages.error(problem);
    }
    // Face tracks: the library shows the project's (the viewer plays them on the dance).
    const faceTracks = JSON.stringify(now.faceTracks || []);
    if (faceTracks !== this.shown.faceTracks && this.project.faceTracksInto) {
      this.shown.faceTracks = faceTracks;
      for (const problem of this.project.faceTracksInto(this.library)) this.messages.error(problem);
    }
    const character = bodyKey(now);
    if (character !== this.shown.character) {
      this.shown.character = character;
      if (v.character) v.character(now.character ? (this.libraryId(now.character) ?? "builtin") : now.stickFigures ? null : "builtin");
    }
    const texts = JSON.stringify(now.texts);
    if (texts !== this.shown.texts) {
      this.shown.texts = texts;
      if (now.texts.length) v.animate(now.texts[now.texts.length - 1]);
    }
    v.dance(now);
  }

  /** Switches the page to another stored project (or a new one, `null`) by reloading. */
  async switchTo(id) {
    if (this.store) await this.store.detach();
    if (id) localStorage.setItem(LAST_KEY, id); else localStorage.removeItem(LAST_KEY);
    location.reload();
  }

  /** A new project: opened empty by the reload, stored once the person makes something in it. */
  async newProject() {
    if (this.store) await this.switchTo(NEW_PROJECT);
    else location.reload();
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
    // The same project opened again (a file saved from here, unchanged) is the stored one, not
    // a second entry; another project of the same name gets a name of its own.
    const same = await this.store.findSame(p.manifest());
    if (same) {
      p.free?.();
      if (same !== this.store.projectId) await this.switchTo(same);
      else this.messages.info(`${name} is the project already open`);
      return true;
    }
    // A project never named (Untitled…) takes its file's name.
    const docName = p.summary().name || "";
    const base = docName && !/^Untitled( \d+)?$/.test(docName) ? docName : name.replace(/\.odori$/i, "").trim() || "Untitled";
    const free = await this.store.freeName(base);
    if (free !== docName) p.setName(free);
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
      const r = await saveBytes(bytes, fileNameFor(this.project.summary().name));
      if (r) this.messages.info(`Saved ${r.name} (${(bytes.length / 1024).toFixed(0)} KiB)`);
      // MMD files go into the person's own .odori file, never further: say so when it holds some.
      // (VMD dances, their models with the textures kept for them, camera and face tracks.)
      const mmd = this.project.summary().mmdFiles || [];
      if (r && mmd.length) this.messages.info(`${r.name} holds your MMD file${mmd.length === 1 ? "" : "s"} (${mmd.join(", ")}) for you: MMD creators' terms usually forbid passing them on, so keep this file to yourself (a share link leaves them out).`);
      // Named where it was saved ("my dance.odori" → "my dance"): how Recent projects lists it.
      const named = r && r.name.replace(/\.odori$/i, "").trim();
      if (named && named !== this.project.summary().name && this.store) {
        this.project.setName(await this.store.freeName(named, this.store.projectId));
        this.edited();
      }
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
    // Once per project, by its name (the time it was last changed in its tooltip).
    for (const r of list) {
      const o = new Option(`${r.name || "Untitled"}${r.id === this.store.projectId ? " (open)" : ""}`, r.id);
      o.title = `last changed ${new Date(r.updatedAt).toLocaleString()}`;
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

/** What identifies the song shown (not its corrections): the engine's key. */
function songKey(song) {
  return song ? song.key : null;
}

/** What the project's body choice looks like to the page (a character, stick figures, or none: the built-in body). */
function bodyKey(summary) {
  return JSON.stringify([summary.character ?? null, !!summary.stickFigures]);
}
