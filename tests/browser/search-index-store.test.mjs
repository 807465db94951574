// The search index kept in IndexedDB (issue #16, build item 3): the app indexes its library
// once, stores the index under the library's content key, and on the next visit reads it back
// instead of indexing again — with the same search results. A changed library (a clip added)
// indexes only the new clip and stores the index under the new key; damaged stored bytes are
// noticed (checksum), reported, and those clips indexed again. Storage does not depend on the
// graphics back end: WebGL2 only.
import { test, before, after } from "node:test";
import assert from "node:assert/strict";
import { join } from "node:path";
import { startServer, launch, openApp, data, importFiles } from "./harness.mjs";

let server;
before(async () => { server = await startServer(); });
after(() => server && server.stop());

const QUERIES = [{ maxResults: 10 }, { preset: "feetOnly", maxResults: 5 }, { preset: "arms", maxResults: 4 }];

/** Waits until the app's library is indexed (n clips) and the search client is idle. */
async function indexed(page, n) {
  await page.waitForFunction((n) => { const c = window.odori?.searchClient; return c && c.features.size === n && !c.batching && [...c.features.values()].every((f) => f.worker >= 0); }, n, { timeout: 120000 });
  return page.evaluate(async () => { await window.odori.searchClient.loading; return { ...window.odori.searchClient.indexStats }; });
}

/** Waits until the index of the current library is stored. */
async function stored(page) {
  await page.waitForFunction(() => { const c = window.odori.searchClient; return c.indexStats.savedKey === c.libraryKey(); }, null, { timeout: 120000 });
  return page.evaluate(() => ({ ...window.odori.searchClient.indexStats }));
}

/** The same searches, from a stretch of salsa_02, as comparable rows. */
function searches(page) {
  return page.evaluate(async (queries) => {
    const { searchClient: c, library } = window.odori;
    const q = { clipId: library.clips().find((x) => x.name === "salsa_02").id, startFrame: 1200, endFrame: 1320 };
    const out = [];
    for (const p of queries) out.push((await c.search(q, p)).matches.map((m) => [m.clipName, m.startFrame, m.endFrame, m.distance]));
    return out;
  }, QUERIES);
}

async function reopen(page) {
  await page.reload();
  await page.waitForFunction(() => document.body.dataset.ready === "1" && document.body.dataset.project === "ready", null, { timeout: 120000 });
}

test("search index: stored in IndexedDB, reopened instead of rebuilt, same results; a changed library re-indexes", async () => {
  const { browser, page, logs } = await launch("webgl2");
  try {
    await openApp(page, server, "webgl2");
    await page.waitForFunction(() => document.body.dataset.project === "ready", null, { timeout: 120000 });
    const t0 = await page.evaluate(() => Date.now());
    await importFiles(page, [join(data, "mocap/cmu-salsa/salsa_01.bvh"), join(data, "mocap/cmu-salsa/salsa_02.bvh")], { "salsa_01.bvh": { fps: 60 }, "salsa_02.bvh": { fps: 60 } });
    const built = await indexed(page, 3);
    assert.equal(built.built, 3, `a first visit indexes every clip: ${JSON.stringify(built)}`);
    assert.equal(built.restored, 0);
    const saved = await stored(page);
    assert.ok(saved.savedBytes > 1e6, `stored ${saved.savedBytes} bytes`);
    const want = await searches(page);
    assert.ok(want[0].length === 10 && want[0][0][0] === "salsa_02", JSON.stringify(want[0].slice(0, 2)));
    // The project (its files) is autosaved too; the reload reads both back.
    await page.waitForFunction((t0) => Number(document.body.dataset.saved || 0) > t0, t0, { timeout: 30000 });

    await reopen(page);
    const back = await indexed(page, 3);
    assert.equal(back.built, 0, `after a reload nothing is indexed again: ${JSON.stringify(back)}`);
    assert.equal(back.restored, 3);
    assert.equal(back.storedKey, saved.savedKey, "read from the record of this library");
    assert.deepEqual(await searches(page), want, "the index read back answers as the one built");
    console.log(`index of 3 clips: ${saved.savedBytes} bytes stored; reopened in ${back.restoreMs.toFixed(0)} ms`);

    // The library changes: one clip more. Only it is indexed; the index is stored under a new key.
    const t1 = await page.evaluate(() => Date.now());
    await importFiles(page, [join(data, "mocap/cmu-salsa/salsa_03.bvh")], { "salsa_03.bvh": { fps: 60 } });
    const grown = await indexed(page, 4);
    assert.equal(grown.built, 1, `only the new clip is indexed: ${JSON.stringify(grown)}`);
    const saved2 = await stored(page);
    assert.notEqual(saved2.savedKey, saved.savedKey, "a changed library has another key");
    const want2 = await searches(page);
    await page.waitForFunction((t) => Number(document.body.dataset.saved || 0) > t, t1, { timeout: 30000 });
    const keys = await page.evaluate(async () => (await (await import("./project/index-store.js")).IndexStore.open()).keys());
    assert.deepEqual(keys.slice(0, 2), [saved2.savedKey, saved.savedKey], "newest first, the earlier library kept");

    await reopen(page);
    const back2 = await indexed(page, 4);
    assert.equal(back2.built, 0, JSON.stringify(back2));
    assert.equal(back2.restored, 4);
    assert.deepEqual(await searches(page), want2);

    // Damaged bytes in storage: the checksum catches them, the page says so, those clips are
    // indexed again (the others still come from the store), and the answers are the same.
    await page.evaluate(async (key) => {
      const store = await (await import("./project/index-store.js")).IndexStore.open();
      const rec = await store.get(key);
      const b = new Uint8Array(await rec.parts[0].bytes.arrayBuffer());
      b[b.length >> 1] ^= 0x40;
      rec.parts[0].bytes = new Blob([b]);
      await store.db.put("indexes", rec);
    }, saved2.savedKey);
    await reopen(page);
    const healed = await indexed(page, 4);
    assert.ok(healed.built >= 1 && healed.built + healed.restored === 4, JSON.stringify(healed));
    assert.match(healed.note || "", /corrupt/, "the damage is reported");
    assert.ok((await page.textContent("#messages")).includes("corrupt"), "and shown in the page");
    assert.deepEqual(await searches(page), want2);
  } catch (e) {
    console.log(logs.join("\n"));
    throw e;
  } finally {
    await browser.close();
  }
});
