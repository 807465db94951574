// Autosave's blob collection (www/project/store.js), in headless Chromium with the real engine
// and IndexedDB: blobs are shared by hash between stored projects; once no stored project's
// current copy refers to a blob (a file removed and then fallen out of the undo history), the
// write after the pointer switch deletes it, while a blob another project still uses stays and
// both projects read back whole.
import { test, before, after } from "node:test";
import assert from "node:assert/strict";
import { readFileSync } from "node:fs";
import { join } from "node:path";
import { startServer, launch, data } from "./harness.mjs";

let server;
before(async () => { server = await startServer(); });
after(() => server && server.stop());

test("autosave deletes blobs no stored project refers to, and only those", async () => {
  const { browser, page } = await launch("webgl2");
  try {
    await page.goto(server.url + "favicon.svg");
    const bvh = readFileSync(join(data, "mocap/cmu-salsa/salsa_10.bvh")).toString("base64");
    const r = await page.evaluate(async (b64) => {
      const pkg = await import("/pkg/odori.js");
      await pkg.default();
      const store = await import("/project/store.js");
      const db = await store.openStore();
      const errors = [];
      const ps = new store.ProjectStore(db, { onError: (m) => errors.push(m) });
      const a = Uint8Array.from(atob(b64), (c) => c.charCodeAt(0));
      // The same motion with one more line end: another file, another hash.
      const b = new Uint8Array(a.length + 1);
      b.set(a);
      b[a.length] = 10;
      const keys = async () => (await db.getAllKeys("blobs")).sort();
      // Project 1 keeps file A.
      const p1 = new pkg.Project();
      p1.addSource("a.bvh", a, undefined);
      await ps.attach(p1);
      await ps.flush();
      const id1 = ps.projectId;
      // Project 2 has A and B, then removes both; its history still refers to them.
      const p2 = new pkg.Project();
      const sa = p2.addSource("a.bvh", a, undefined);
      const sb = p2.addSource("b.bvh", b, undefined);
      await ps.attach(p2);
      await ps.flush();
      const both = await keys();
      p2.removeSource(sa.id);
      p2.removeSource(sb.id);
      ps.schedule();
      await ps.flush();
      const whileInHistory = await keys();
      // More edits than the undo history keeps: A and B fall out of project 2's history.
      for (let i = 0; i < 105; i++) p2.setTexts([`edit ${i}`]);
      ps.schedule();
      await ps.flush();
      const after = await keys();
      const id2 = ps.projectId;
      // Both projects still read back whole.
      const back1 = await ps.load(pkg.Project, id1);
      const back2 = await ps.load(pkg.Project, id2);
      return {
        both, whileInHistory, after, errors, collected: ps.stats.blobsCollected || 0,
        p1: { sources: back1.project.doc().sources.length, missing: back1.missing.length },
        p2: { texts: back2.project.doc().texts, missing: back2.missing.length, undo: back2.project.canUndo() },
      };
    }, bvh);
    assert.deepEqual(r.errors, [], "no storage error");
    assert.equal(r.both.length, 2, `A and B stored once each: ${r.both}`);
    assert.deepEqual(r.whileInHistory, r.both, "a blob the undo history still refers to is kept");
    assert.equal(r.after.length, 1, `only A is left: ${r.after}`);
    assert.ok(r.both.includes(r.after[0]), "the blob left is one of the two");
    assert.equal(r.collected, 1, "one blob collected (B); A stays, project 1 uses it");
    assert.deepEqual(r.p1, { sources: 1, missing: 0 }, "project 1 reads back whole");
    assert.deepEqual(r.p2.texts, ["edit 104"]);
    assert.equal(r.p2.missing, 0, "project 2 reads back whole");
    assert.ok(r.p2.undo);
  } finally {
    await browser.close();
  }
});
