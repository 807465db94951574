// Issue #14: the page's Content-Security-Policy forbids every connection but the page's own
// files, and the app works under it: it starts, draws the built-in figure, analyses the demo
// song, animates a text and searches in its worker with no policy violation. A request to
// any other origin (fetch, WebSocket, image, beacon) is refused by the policy.
import { test, before, after } from "node:test";
import assert from "node:assert/strict";
import { startServer, launch, openApp, canvasPixels, countAll, isWarmFigure } from "./harness.mjs";

let server;
before(async () => { server = await startServer(); });
after(() => server && server.stop());

test("csp: the app works with no connection outside its own files", async () => {
  const { browser, page, logs } = await launch("webgl2");
  try {
    await page.addInitScript(() => {
      window.__csp = [];
      document.addEventListener("securitypolicyviolation", (e) => window.__csp.push(`${e.effectiveDirective} ${e.blockedURI}`));
    });
    await openApp(page, server, "webgl2");
    const policy = await page.$eval('meta[http-equiv="Content-Security-Policy"]', (m) => m.content);
    assert.match(policy, /connect-src 'self'/);
    assert.match(policy, /default-src 'none'/);
    await page.waitForTimeout(300);
    assert.ok(countAll(await canvasPixels(page, "csp.png"), isWarmFigure) > 300, "the built-in figure is drawn");
    await page.waitForFunction(() => document.body.dataset.song === "demo", null, { timeout: 60000 });
    // The offline cache's service worker registers under the policy.
    await page.waitForFunction(async () => Boolean((await navigator.serviceWorker.ready).active), null, { timeout: 60000 });
    // Text to animation, and a search in the Web Worker, both through the page's own modules.
    const worked = await page.evaluate(async () => {
      const { TextAnimator } = await import("./pkg/odori.js");
      const r = new TextAnimator().animate(window.odori.library, "Taro runs, then jumps.");
      const worker = new Worker(new URL("./search-worker.js", location.href), { type: "module" });
      // A curve of a clip the worker's index lacks: the reply (kind "not-found") proves the
      // worker loaded and instantiated the engine.
      const alive = await new Promise((resolve) => {
        worker.onerror = (e) => resolve(`worker error: ${e.message}`);
        worker.onmessage = (ev) => resolve(`${ev.data.type} ${ev.data.kind}`);
        setTimeout(() => resolve("no reply"), 20000);
        worker.postMessage({ type: "curve", token: 1, id: 999999, joint: "hips", shoulders: false });
      });
      worker.terminate();
      return { elements: r.elements.length, alive };
    });
    assert.equal(worked.elements, 2);
    assert.equal(worked.alive, "error not-found");
    assert.deepEqual(await page.evaluate(() => window.__csp), [], "no violation while the app works");

    // Anything aimed elsewhere is refused by the policy (not merely by a closed port).
    const outside = "http://odori-csp-test.invalid";
    const results = await page.evaluate(async (outside) => {
      const out = {};
      out.fetch = await fetch(`${outside}/x`).then(() => "sent", (e) => `refused: ${e.name}`);
      try { new WebSocket("ws://odori-csp-test.invalid/"); out.ws = "created"; } catch (e) { out.ws = `refused: ${e.name}`; }
      out.img = await new Promise((resolve) => { const i = new Image(); i.onload = () => resolve("loaded"); i.onerror = () => resolve("refused"); i.src = `${outside}/pixel.png`; });
      out.beacon = navigator.sendBeacon(`${outside}/beacon`, "x") ? "queued" : "refused";
      await new Promise((r) => setTimeout(r, 300));
      return out;
    }, outside);
    assert.match(results.fetch, /^refused/);
    assert.equal(results.img, "refused");
    // sendBeacon only queues; the policy blocks the request itself (reported below).
    const violations = await page.evaluate(() => window.__csp);
    assert.ok(violations.some((v) => v.startsWith("connect-src") && v.includes("/beacon")), `beacon blocked: ${violations}`);
    for (const directive of ["connect-src", "img-src"]) {
      assert.ok(violations.some((v) => v.startsWith(directive) && v.includes("odori-csp-test.invalid")), `${directive} violation reported: ${violations}`);
    }
    assert.deepEqual(logs.filter((l) => l.startsWith("[pageerror]")), []);
  } finally {
    await browser.close();
  }
});
