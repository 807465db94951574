// Offline: once the app has been opened, it starts again with the network gone (service
// worker cache), draws the built-in clip and analyses the built-in song.
import { test, before, after } from "node:test";
import assert from "node:assert/strict";
import { startServer, launch, openApp, canvasPixels, countAll, isOrange } from "./harness.mjs";

let server;
before(async () => { server = await startServer(); });
after(() => server && server.stop());

test("offline: the app reloads and works with no network", async () => {
  const { browser, page, logs } = await launch("webgl2");
  try {
    await openApp(page, server, "webgl2");
    await page.waitForFunction(async () => {
      const reg = await navigator.serviceWorker.ready;
      const c = await caches.open("odori-v1");
      return Boolean(reg.active) && Boolean(await c.match("./pkg/odori_bg.wasm")) && Boolean(await c.match("./main.js"));
    }, null, { timeout: 60000 });
    await page.context().setOffline(true);
    await page.reload();
    await page.waitForFunction(() => document.body.dataset.ready, null, { timeout: 60000 });
    assert.equal(await page.evaluate(() => document.body.dataset.ready), "1", await page.textContent("#messages"));
    assert.equal(await page.$$eval("#library tbody tr", (trs) => trs.length), 1);
    await page.waitForTimeout(300);
    assert.ok(countAll(await canvasPixels(page, "offline.png"), isOrange) > 300, "the built-in figure is drawn offline");
    await page.waitForFunction(() => document.body.dataset.song === "demo", null, { timeout: 60000 });
    assert.deepEqual(logs.filter((l) => l.startsWith("[pageerror]")), []);
  } finally {
    await browser.close();
  }
});
