// The search index kept in IndexedDB (issue #16), so a large library is not indexed again on
// every visit. A record is filed under the library's key (`SearchIndex.libraryKey` over the
// clips' content keys, `Library.searchKey`, in library order): the same clips give the same
// key, any change another. It holds the index as the search workers serialised it
// (`SearchIndex.toBytes`, one part per worker), with each part's clip keys.
//
// Its own database, beside the project's (store.js): the index is derived data — losing it
// costs an index build, never work — so it never shares a transaction or a schema version with
// the project. The few most recent libraries are kept (switching between recent projects does
// not rebuild), older ones are deleted on each save.
import { openDB } from "../vendor/idb.js";

const DB_NAME = "odori-search-index";
const DB_VERSION = 1;
/** Libraries kept; the rest are deleted, oldest first. */
export const KEEP_LIBRARIES = 3;

export class IndexStore {
  constructor(db) { this.db = db; }

  /** Opens (and on first use creates) the database; null when IndexedDB is not available. */
  static async open() {
    try {
      const db = await openDB(DB_NAME, DB_VERSION, {
        upgrade(db) {
          // key → { key, parts: [{ bytes: Blob, keys: string[], frames }], clips, frames, bytes, savedAt }
          // (records are large: the savedAt index lists them without reading them)
          db.createObjectStore("indexes", { keyPath: "key" }).createIndex("savedAt", "savedAt");
          // key → { key, clipKeys, savedAt }: which clips each record holds, read without its bytes.
          db.createObjectStore("catalog", { keyPath: "key" });
        },
      });
      return new IndexStore(db);
    } catch {
      return null;
    }
  }

  /** The index stored under a library key, if any. */
  get(key) { return this.db.get("indexes", key); }

  /** The most recently saved index of any library (its clips of the same content are reused). */
  async latest() {
    const keys = await this.keys();
    return keys.length ? this.get(keys[0]) : undefined;
  }

  /** What every record holds, newest first: `{ key, clipKeys, savedAt }[]` (small: no bytes). */
  async catalog() {
    return (await this.db.getAll("catalog")).sort((a, b) => b.savedAt - a.savedAt);
  }

  /** Library keys stored, newest first. */
  async keys() {
    return (await this.db.getAllKeysFromIndex("indexes", "savedAt")).reverse();
  }

  /**
   * Stores an index: `parts` as the workers gave them. Returns the record's size in bytes.
   * Throws when the browser refuses the write (storage full): the caller reports it.
   */
  async put(key, parts) {
    const rec = {
      key,
      // Blobs: a read hands out handles at once and the search workers read the bytes
      // themselves, in parallel and off the page's thread (a Uint8Array would be copied out of
      // the database on the page's thread first).
      parts: parts.map((p) => ({ ...p, bytes: p.bytes instanceof Blob ? p.bytes : new Blob([p.bytes]) })),
      clips: parts.reduce((a, p) => a + p.keys.length, 0),
      frames: parts.reduce((a, p) => a + p.frames, 0),
      bytes: parts.reduce((a, p) => a + (p.bytes.byteLength ?? p.bytes.size), 0),
      savedAt: Date.now(),
    };
    const tx = this.db.transaction(["indexes", "catalog"], "readwrite");
    const [indexes, catalog] = [tx.objectStore("indexes"), tx.objectStore("catalog")];
    await indexes.put(rec);
    await catalog.put({ key, clipKeys: parts.flatMap((p) => p.keys), savedAt: rec.savedAt });
    const keys = (await indexes.index("savedAt").getAllKeys()).reverse();
    for (const old of keys.slice(KEEP_LIBRARIES)) { await indexes.delete(old); await catalog.delete(old); }
    await tx.done;
    return rec.bytes;
  }
}
