// Autosave of a Project handle to the browser's own storage (IndexedDB, through the `idb`
// wrapper, vendored into www/vendor/ by the build), as spec §K asks:
// - blobs once by hash: a blob already stored is never written again, so 30 minutes of mocap
//   costs one write, not one per edit;
// - the manifest (document + history, JSON) debounced (≤ 0.5 s) and flushed on `pagehide` and
//   when the page is hidden;
// - write new, then switch: a new manifest record is written first; only once that
//   transaction completed does the project's pointer move to it (and the old one go), so a tab
//   killed mid-write keeps the last good copy;
// - `navigator.storage.persist()` is asked for;
// - one tab per project: a Web Lock held while the project is open; a second tab is told and
//   never writes (it can still Save as);
// - storage full or refused: the error is reported, work continues in memory, the next edit
//   tries again;
// - blobs no project refers to any more (a file whose import fell out of the undo history, a
//   song replaced long ago) are deleted, after the pointer switch, never before: a crash
//   between the two leaves an extra blob, never a missing one. A blob this tab believes stored
//   is checked in the write's own transaction (another tab's collection may have taken it).
import { openDB } from "../vendor/idb.js";

const DB_NAME = "odori";
const DB_VERSION = 1;
/** Manifest writes wait this long after the last edit (spec: at most 0.5 s). */
export const DEBOUNCE_MS = 400;
const LAST_KEY = "odori.lastProject";
/** LAST_KEY's value after New: the next start opens a new project (stored once something is made). */
export const NEW_PROJECT = "new";

function newId() {
  return (crypto.randomUUID && crypto.randomUUID()) || `p${Date.now().toString(36)}${Math.random().toString(36).slice(2)}`;
}

/** Opens (and on first use creates) the database. */
export function openStore() {
  return openDB(DB_NAME, DB_VERSION, {
    upgrade(db) {
      // hash → Uint8Array, shared by every project.
      db.createObjectStore("blobs");
      // auto key → { projectId, bytes: Uint8Array (manifest JSON), savedAt }.
      db.createObjectStore("manifests", { autoIncrement: true });
      // projectId → { id, name, manifestKey, updatedAt }: the pointer to the last good copy.
      db.createObjectStore("projects", { keyPath: "id" });
    },
  });
}

/** Why a write failed, in words a person understands. */
function describe(err) {
  const name = err && (err.name || (err.inner && err.inner.name));
  if (name === "QuotaExceededError") return "the browser's storage for this site is full";
  if (name === "InvalidStateError" || name === "UnknownError") return "the browser refused to store data (private mode or storage turned off?)";
  return (err && err.message) || String(err);
}

export class ProjectStore {
  /**
   * @param {object} db from openStore()
   * @param {{ onSaved?: (info) => void, onError?: (message, err) => void, onConflict?: (message) => void }} hooks
   */
  constructor(db, hooks = {}) {
    this.db = db;
    this.hooks = hooks;
    this.projectId = null;
    this.project = null;
    this.storedBlobs = new Set();
    /** Blobs the project's last stored manifest refers to (what a later write may drop). */
    this.lastHashes = new Set();
    this.timer = 0;
    this.writing = null;
    this.dirty = false;
    this.readOnly = false;
    this.releaseLock = null;
    this.lastError = null;
    this.stats = { writes: 0, blobsWritten: 0, blobBytesWritten: 0, lastManifestBytes: 0, mainThreadMs: [] };
    this.onHide = () => { if (document.visibilityState === "hidden") this.flush(); };
    this.onPageHide = () => this.flush();
    addEventListener("pagehide", this.onPageHide);
    document.addEventListener("visibilitychange", this.onHide);
    if (navigator.storage && navigator.storage.persist) navigator.storage.persist().catch(() => {});
  }

  /** Recent projects, newest first: `{ id, name, updatedAt }[]`. */
  async recent() {
    const all = await this.db.getAll("projects");
    return all.sort((a, b) => b.updatedAt - a.updatedAt).map(({ id, name, updatedAt }) => ({ id, name, updatedAt }));
  }

  /**
   * The id of the project open last in this browser, if it is still stored. localStorage is
   * written to disk lazily (a killed browser can lose it), so the project saved last in
   * IndexedDB (which commits each write) answers when it has nothing.
   */
  async lastId() {
    const id = localStorage.getItem(LAST_KEY);
    if (id === NEW_PROJECT) return null;
    if (id && (await this.db.get("projects", id))) return id;
    const recent = await this.recent();
    return recent.length ? recent[0].id : null;
  }

  /**
   * Reads a stored project into a new Project handle: `{ project, missing }`. `ProjectClass` is
   * the wasm `Project`. Throws an OdoriError when the stored manifest cannot be read.
   */
  async load(ProjectClass, id) {
    const rec = await this.db.get("projects", id);
    if (!rec) throw new Error(`no stored project ${id}`);
    const m = await this.db.get("manifests", rec.manifestKey);
    if (!m) throw new Error(`project ${rec.name || id}: its last saved state is missing from storage`);
    // The manifest names its blobs (the engine reads them out): fetch them all before the
    // (synchronous) rebuild.
    const hashes = ProjectClass.manifestBlobHashes(m.bytes);
    const tx = this.db.transaction("blobs");
    const blobs = new Map();
    await Promise.all(hashes.map(async (h) => { const b = await tx.store.get(h); if (b) blobs.set(h, b); }));
    const project = ProjectClass.fromManifest(m.bytes, (h) => blobs.get(h));
    for (const h of blobs.keys()) this.storedBlobs.add(h);
    this.lastHashes = new Set(hashes);
    return { project, missing: project.missing() };
  }

  /**
   * Makes `project` the one this store keeps (`id`: its stored id; none: a new project).
   * Takes the project's lock; when another tab holds it this tab is told and never writes.
   */
  /**
   * Keeps `project` stored under `id` (a stored project), or under a new id. `pristine` (a new
   * project): nothing is written, and it is not the last project, until its first `schedule`
   * (the person's first edit), so opening the page and leaving stores nothing.
   */
  async attach(project, id = null, { pristine = false } = {}) {
    await this.detach();
    this.project = project;
    if (!id) this.lastHashes = new Set();
    this.projectId = id || newId();
    this.readOnly = false;
    this.pristine = !id && pristine;
    if (!this.pristine) localStorage.setItem(LAST_KEY, this.projectId);
    if (navigator.locks) {
      const got = await new Promise((resolve) => {
        navigator.locks.request(`odori-project-${this.projectId}`, { ifAvailable: true }, (lock) => {
          if (!lock) { resolve(false); return undefined; }
          resolve(true);
          return new Promise((release) => { this.releaseLock = release; });
        });
      });
      if (!got) {
        this.readOnly = true;
        this.hooks.onConflict?.("This project is open in another tab: changes here are not saved to the browser (use Save as, or close the other tab and reload).");
      }
    }
    if (!id && !this.pristine) this.schedule();
    return this.projectId;
  }

  async detach() {
    await this.flush();
    if (this.releaseLock) { this.releaseLock(); this.releaseLock = null; }
    this.project = null;
  }

  /** Call after every edit: the manifest is written within DEBOUNCE_MS. */
  schedule() {
    if (!this.project || this.readOnly) return;
    if (this.pristine) {
      this.pristine = false;
      localStorage.setItem(LAST_KEY, this.projectId);
    }
    this.dirty = true;
    clearTimeout(this.timer);
    this.timer = setTimeout(() => this.flush(), DEBOUNCE_MS);
  }

  /** Writes now if anything changed (returns when the write is done or failed). */
  async flush() {
    clearTimeout(this.timer);
    if (this.writing) await this.writing;
    if (!this.dirty || !this.project || this.readOnly) return;
    this.dirty = false;
    this.writing = this.write().finally(() => { this.writing = null; });
    return this.writing;
  }

  async write() {
    const t0 = performance.now();
    // The synchronous part on the main thread: the manifest and the blobs not yet stored.
    const manifest = this.project.manifest();
    const name = this.project.summary().name || "Untitled";
    const hashes = this.project.blobHashes();
    const fresh = hashes.filter((h) => !this.storedBlobs.has(h));
    const blobs = fresh.map((h) => [h, this.project.blob(h)]);
    this.stats.mainThreadMs.push(performance.now() - t0);
    const id = this.projectId;
    const project = this.project;
    try {
      // 1. the blobs and the new manifest, in one transaction (a blob believed stored is
      //    checked there, and written again if another tab's collection took it);
      const tx = this.db.transaction(["blobs", "manifests"], "readwrite");
      const store = tx.objectStore("blobs");
      for (const [h, bytes] of blobs) store.put(bytes, h);
      const known = hashes.filter((h) => this.storedBlobs.has(h));
      const present = await Promise.all(known.map((h) => store.getKey(h)));
      known.forEach((h, k) => {
        if (present[k] !== undefined) return;
        const bytes = project.blob(h);
        if (bytes) { store.put(bytes, h); blobs.push([h, bytes]); }
      });
      const keyReq = tx.objectStore("manifests").add({ projectId: id, bytes: manifest, savedAt: Date.now() });
      const [newKey] = await Promise.all([keyReq, tx.done]);
      // 2. only then, the pointer moves to it, and the previous copy goes.
      const tx2 = this.db.transaction(["projects", "manifests"], "readwrite");
      const prev = await tx2.objectStore("projects").get(id);
      await tx2.objectStore("projects").put({ id, name, manifestKey: newKey, updatedAt: Date.now() });
      if (prev && prev.manifestKey !== newKey) await tx2.objectStore("manifests").delete(prev.manifestKey);
      await tx2.done;
      // 3. after the switch: blobs the previous copy referred to and this one does not.
      const now = new Set(hashes);
      const dropped = [...this.lastHashes].filter((h) => !now.has(h));
      this.lastHashes = now;
      if (dropped.length) await this.collect(dropped, project.constructor);
      for (const [h, bytes] of blobs) { this.storedBlobs.add(h); this.stats.blobsWritten += 1; this.stats.blobBytesWritten += bytes.length; }
      this.stats.writes += 1;
      this.stats.lastManifestBytes = manifest.length;
      if (this.lastError) { this.lastError = null; this.hooks.onSaved?.({ recovered: true }); }
      this.hooks.onSaved?.({ id, manifestBytes: manifest.length, blobsWritten: blobs.length });
    } catch (err) {
      // Nothing is lost: the project is in memory, the last good copy is still stored, and the
      // next edit tries again.
      this.dirty = true;
      const said = this.lastError;
      this.lastError = describe(err);
      // Said once until it changes or storage works again (not one more error per edit).
      if (this.lastError !== said) this.hooks.onError?.(`Not saved in the browser: ${this.lastError}. Your work is kept in this tab; use Save as to keep a file.`, err);
    }
  }

  /**
   * Deletes the blobs of `candidates` that no stored project's current manifest refers to
   * (blobs are shared by hash between projects; `ProjectClass`, the wasm `Project`, reads each
   * manifest's list). Returns how many went.
   */
  async collect(candidates, ProjectClass) {
    try {
      const tx = this.db.transaction(["projects", "manifests", "blobs"], "readwrite");
      const inUse = new Set();
      for (const rec of await tx.objectStore("projects").getAll()) {
        const m = await tx.objectStore("manifests").get(rec.manifestKey);
        if (!m) continue;
        for (const h of ProjectClass.manifestBlobHashes(m.bytes)) inUse.add(h);
      }
      const gone = candidates.filter((h) => !inUse.has(h));
      for (const h of gone) { tx.objectStore("blobs").delete(h); this.storedBlobs.delete(h); }
      await tx.done;
      this.stats.blobsCollected = (this.stats.blobsCollected || 0) + gone.length;
      return gone.length;
    } catch (err) {
      // An extra blob costs space, never work: say so quietly and go on.
      console.warn("odori: stored blobs not collected:", err);
      return 0;
    }
  }

  /** The stored project whose last saved manifest is these bytes (the same project opened again), or null. */
  async findSame(manifestBytes) {
    const tx = this.db.transaction(["projects", "manifests"]);
    for (const rec of await tx.objectStore("projects").getAll()) {
      const m = await tx.objectStore("manifests").get(rec.manifestKey);
      if (m && m.bytes.length === manifestBytes.length && m.bytes.every((b, i) => b === manifestBytes[i])) return rec.id;
    }
    return null;
  }

  /** `name`, or `name 2`, `name 3`… : the first no other stored project has (each is listed once by its name). */
  async freeName(name, exceptId = null) {
    const taken = new Set((await this.recent()).filter((r) => r.id !== exceptId).map((r) => r.name));
    if (!taken.has(name)) return name;
    for (let n = 2; ; n++) if (!taken.has(`${name} ${n}`)) return `${name} ${n}`;
  }

  /** Forgets a stored project; its blobs go unless another project uses them (`ProjectClass`: the wasm `Project`). */
  async remove(id, ProjectClass) {
    const tx = this.db.transaction(["projects", "manifests"], "readwrite");
    const rec = await tx.objectStore("projects").get(id);
    let hashes = [];
    if (rec) {
      const m = await tx.objectStore("manifests").get(rec.manifestKey);
      if (m) hashes = ProjectClass.manifestBlobHashes(m.bytes);
      await tx.objectStore("manifests").delete(rec.manifestKey);
      await tx.objectStore("projects").delete(id);
    }
    await tx.done;
    if (hashes.length) await this.collect(hashes, ProjectClass);
  }
}
