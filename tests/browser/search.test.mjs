// Search by example in the page: drag a query range on the timeline, search in the worker,
// the results fill the table, a result shows two overlaid figures and the joint plot.
import { test, before, after } from "node:test";
import assert from "node:assert/strict";
import { join } from "node:path";
import { startServer, launch, openApp, canvasPixels, countAll, isOrange, isTeal, data, artifacts, importFiles } from "./harness.mjs";

let server;
before(async () => { server = await startServer(); });
after(() => server && server.stop());

test("search: query by dragging, results, overlay of two figures, plot", async () => {
  const { browser, page, logs } = await launch("webgl2");
  try {
    await openApp(page, server, "webgl2");
    await importFiles(page, [join(data, "mocap/cmu-salsa/salsa_01.bvh"), join(data, "mocap/cmu-salsa/salsa_02.bvh")], { "salsa_01.bvh": { fps: 60 }, "salsa_02.bvh": { fps: 60 } });
    await page.waitForSelector("#library tbody tr:nth-child(3)", { timeout: 30000 });
    await page.click("#library tbody tr:nth-child(3) td:first-child"); // salsa_02
    // The import's toasts stand over the left panel (the search timeline below the library)
    // until they fade: wait for them, as a person would.
    await page.waitForFunction(() => !document.querySelector("#toasts .toast:not(.error)"), null, { timeout: 30000 });
    // Drag on the timeline: from 30 % to 36 % of the clip (about 2.2 s of salsa_02).
    const box = await (await page.$("#search-timeline")).boundingBox();
    await page.mouse.move(box.x + box.width * 0.30, box.y + box.height / 2);
    await page.mouse.down();
    await page.mouse.move(box.x + box.width * 0.33, box.y + box.height / 2, { steps: 4 });
    await page.mouse.move(box.x + box.width * 0.36, box.y + box.height / 2, { steps: 4 });
    await page.mouse.up();
    const q = await page.evaluate(() => window.odori.search.range);
    assert.ok(q.endSecs - q.startSecs > 1.5 && q.endSecs - q.startSecs < 3.5, `query ${q.startSecs}..${q.endSecs}`);
    await page.click("#search-go");
    await page.waitForFunction(() => ["done", "error"].includes(document.querySelector("#search").dataset.state), null, { timeout: 120000 });
    assert.equal(await page.evaluate(() => document.querySelector("#search").dataset.state), "done", await page.textContent("#messages"));
    const rows = await page.$$eval("#search-results tbody tr", (trs) => trs.map((tr) => [...tr.children].map((td) => td.textContent)));
    assert.ok(rows.length >= 1, "no results");
    // The query was cut from salsa_02: its own stretch is the best match, at distance ~0.
    assert.equal(rows[0][0], "salsa_02");
    assert.ok(Math.abs(Number(rows[0][1]) - Math.round(q.startSecs * 60)) <= 15, `best match starts at ${rows[0][1]}`);
    assert.ok(Number(rows[0][4]) < 0.01, `distance ${rows[0][4]}`);
    // A result that is not the query itself, if any; else the first.
    const k = rows.length > 1 ? 1 : 0;
    await page.click(`#search-results tbody tr:nth-child(${k + 1})`);
    await page.waitForFunction(() => document.querySelector("#search").dataset.plotted === "rightHand");
    // The query and result figures' colours are checked as stick figures (chosen in the menu).
    await page.selectOption("#character", "");
    await page.evaluate(() => { const p = window.odori.player; p.pause(); p.time = 0.8; p.drawNow(); });
    const img = await canvasPixels(page, "search-overlay.png");
    assert.ok(countAll(img, isOrange) > 150, "query figure (orange) missing");
    assert.ok(countAll(img, isTeal) > 150, "result figure (teal) missing");
    const plotColoured = await page.evaluate(() => {
      const c = document.querySelector("#search-plot");
      const d = c.getContext("2d").getImageData(0, 0, c.width, c.height).data;
      let red = 0, green = 0, blue = 0;
      for (let i = 0; i < d.length; i += 4) {
        if (d[i] > 200 && d[i + 1] < 140) red++;
        if (d[i + 1] > 170 && d[i] < 140) green++;
        if (d[i + 2] > 200 && d[i] < 160) blue++;
      }
      return { red, green, blue };
    });
    assert.ok(plotColoured.red > 50 && plotColoured.green > 50 && plotColoured.blue > 50, JSON.stringify(plotColoured));
    await page.screenshot({ path: join(artifacts, "search-page.png") });
    // The library is split across workers and merged exactly: the same answer as one index in
    // the page, and the plain DP agrees.
    const cmp = await page.evaluate(async (query) => {
      const { SearchIndex } = await import("./pkg/odori.js");
      const { library, searchClient } = window.odori;
      const one = new SearchIndex();
      for (const id of searchClient.features.keys()) one.addFromLibrary(library, id);
      const params = { maxResults: 12 };
      const key = (o) => o.matches.map((m) => `${m.clipId}:${m.startFrame}-${m.endFrame}:${m.distance.toFixed(5)}`).join(" ");
      const merged = await searchClient.search(query, params);
      return { workers: searchClient.workers.filter((w) => w.frames > 0).length, bound: merged.stats.bound, merged: key(merged), one: key(one.search(query, params)), plain: key(one.searchPlain(query, params)) };
    }, { clipId: await page.evaluate(() => window.odori.search.range.clipId), startFrame: Math.round(q.startSecs * 60), endFrame: Math.round(q.endSecs * 60) + 1 });
    assert.ok(cmp.workers >= 1, JSON.stringify(cmp));
    // With two or more workers the search runs in two rounds: round 2 starts from the bound
    // joined from every worker's probe (a number; Infinity only when the probes found fewer than
    // maxResults far ends together).
    if (cmp.workers > 1) assert.equal(typeof cmp.bound, "number", JSON.stringify(cmp));
    assert.equal(cmp.merged, cmp.one, "merged workers vs one index");
    assert.equal(cmp.one, cmp.plain, "fast vs plain");
    // Fewer than asked under a tight threshold: the summary says how many exist and why.
    await page.fill("#search-threshold", "0.001");
    await page.click("#search-go");
    await page.waitForFunction(() => ["done", "error"].includes(document.querySelector("#search").dataset.state) && /Fewer than/.test(document.querySelector("#search-summary").textContent), null, { timeout: 120000 });
    const summary = await page.textContent("#search-summary");
    assert.match(summary, /admissible match ends/, summary);
    assert.match(summary, /over the threshold 0.001/, summary);
    assert.deepEqual(logs.filter((l) => l.startsWith("[pageerror]")), []);
  } finally {
    await browser.close();
  }
});
