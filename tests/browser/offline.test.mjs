// Offline: once the app has been opened, it starts again with the origin gone (the server is
// stopped, so nothing can come from the network: Playwright's setOffline does not cover a
// service worker's own fetches), from the service worker's cache; every file of the shell is
// cached byte for byte, and so is every file the page fetched. Network first: when the origin
// comes back with a new build, a reload shows the new build, and the cache then holds it, so
// the next offline start is the new build too.
import { test } from "node:test";
import assert from "node:assert/strict";
import { createHash } from "node:crypto";
import { readFileSync } from "node:fs";
import { join } from "node:path";
import { launch, openApp, canvasPixelsUntil, countAll, isWarmFigure, root, startStaticServer, waitUntil } from "./harness.mjs";

// The shell and cache name as the service worker states them, so the test follows the file.
const swSource = readFileSync(join(root, "www", "sw.js"), "utf8");
const CACHE = swSource.match(/const CACHE = "([^"]+)"/)[1];
const SHELL = JSON.parse(swSource.match(/const SHELL = (\[[^\]]*\])/)[1].replace(/,\s*\]/, "]"));
const onDisk = (entry) => {
  const rel = entry.replace(/^\.\//, "");
  return readFileSync(rel === "" ? join(root, "www", "index.html") : rel.startsWith("pkg/") ? join(root, rel) : join(root, "www", rel));
};
const sha256 = (bytes) => createHash("sha256").update(bytes).digest("hex");

/** SHA-256 of each cache entry (null when missing), computed in the page. */
const cachedHashes = (page, entries) => page.evaluate(async ([name, entries]) => {
  const c = await caches.open(name);
  const out = {};
  for (const e of entries) {
    const r = await c.match(e, { ignoreSearch: true });
    out[e] = r ? [...new Uint8Array(await crypto.subtle.digest("SHA-256", await r.arrayBuffer()))].map((b) => b.toString(16).padStart(2, "0")).join("") : null;
  }
  return out;
}, [CACHE, entries]);

async function assertOriginGone(url) {
  await assert.rejects(fetch(url), "the origin still answers: the test would not tell the cache from the network");
}

async function assertAppWorks(page, logs, shot) {
  await page.waitForFunction(() => document.body.dataset.ready, null, { timeout: 60000 });
  assert.equal(await page.evaluate(() => document.body.dataset.ready), "1", await page.textContent("#messages"));
  assert.equal(await page.$$eval("#library tbody tr", (trs) => trs.length), 1);
  const img = await canvasPixelsUntil(page, (i) => countAll(i, isWarmFigure) > 300, "the built-in figure drawn", shot);
  assert.ok(countAll(img, isWarmFigure) > 300);
  await page.waitForFunction(() => document.body.dataset.song === "demo", null, { timeout: 60000 });
  assert.deepEqual(logs.filter((l) => l.startsWith("[pageerror]")), []);
}

test("offline: every file cached, the app starts with the origin gone, a new build is picked up online", async () => {
  assert.ok(SHELL.length >= 19 && SHELL.includes("./pkg/odori_bg.wasm"), `shell list parsed from sw.js: ${SHELL}`);
  let server = await startStaticServer();
  const { port, url } = server;
  const { browser, page, logs } = await launch("webgl2");
  try {
    await openApp(page, server, "webgl2");
    // The worker controls the page and has cached the whole shell.
    await waitUntil(async () => page.evaluate(async ([name, shell]) => {
      if (!navigator.serviceWorker.controller) return false;
      const c = await caches.open(name);
      for (const e of shell) if (!(await c.match(e))) return false;
      return true;
    }, [CACHE, SHELL]), { what: "the service worker controlling the page with the whole shell cached", timeoutMs: 60000 });
    // Every cached shell file is the file on disk, byte for byte.
    const hashes = await cachedHashes(page, SHELL);
    for (const e of SHELL) assert.equal(hashes[e], sha256(onDisk(e)), `cached ${e} differs from the file served`);
    // Everything the page fetched from its origin is cached (else it would be missing offline).
    const fetched = await page.evaluate(() => [location.href, ...performance.getEntriesByType("resource").map((r) => r.name)].filter((u) => new URL(u).origin === location.origin).map((u) => new URL(u).pathname));
    const fetchedHashes = await cachedHashes(page, [...new Set(fetched)]);
    assert.deepEqual(Object.entries(fetchedHashes).filter(([, h]) => !h).map(([p]) => p), [], "fetched by the page but not cached");

    // The origin goes away: connections are refused from here on.
    await server.stop();
    await assertOriginGone(url);
    await page.reload();
    await assertAppWorks(page, logs, "offline.png");
    assert.equal(await page.evaluate(() => document.body.dataset.build), undefined);

    // The origin comes back with a new build (a changed page and script): network first.
    const BUILD = "offline-test-2";
    const html = readFileSync(join(root, "www", "index.html"), "utf8").replace("<head>", `<head>\n<meta name="odori-build" content="${BUILD}">`);
    assert.ok(html.includes(BUILD), "index.html has a <head> to mark");
    const mainJs = readFileSync(join(root, "www", "main.js"), "utf8") + `\ndocument.body.dataset.build = "${BUILD}";\n`;
    server = await startStaticServer({ port, overrides: { "/index.html": Buffer.from(html), "/main.js": Buffer.from(mainJs) } });
    await page.reload();
    await assertAppWorks(page, logs, "offline-new-build.png");
    assert.equal(await page.evaluate(() => document.querySelector('meta[name="odori-build"]')?.content), BUILD, "the new page was not picked up online");
    assert.equal(await page.evaluate(() => document.body.dataset.build), BUILD, "the new script was not picked up online");
    // The worker refreshes its cache from the network as it goes (asynchronously).
    await waitUntil(async () => page.evaluate(async ([name, build]) => {
      const c = await caches.open(name);
      const js = await c.match("./main.js");
      return Boolean(js) && (await js.text()).includes(build);
    }, [CACHE, BUILD]), { what: "the new main.js in the cache" });

    // Offline again: the new build starts from the cache, page and script alike.
    await server.stop();
    server = null;
    await assertOriginGone(url);
    await page.reload();
    await assertAppWorks(page, logs, "offline-new-build-cached.png");
    assert.equal(await page.evaluate(() => document.body.dataset.build), BUILD, "offline start after an update runs the old script");
    assert.equal(await page.evaluate(() => document.querySelector('meta[name="odori-build"]')?.content), BUILD, "offline start after an update shows the old page");
  } catch (e) {
    console.log(logs.join("\n"));
    throw e;
  } finally {
    await browser.close();
    if (server) await server.stop();
  }
});
