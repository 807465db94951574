// The app end to end in Debian's headless Chromium, on WebGL2 and on WebGPU: it starts on
// the built-in clip, opens a real BVH through the file input, draws the figure where it
// should be, moves between frames, overlays two clips in two colours and reports a broken
// file by name. Screenshots go to tests/artifacts/.
import { test, before, after } from "node:test";
import assert from "node:assert/strict";
import { join } from "node:path";
import { writeFileSync } from "node:fs";
import { startServer, launch, openApp, canvasPixels, canvasPixelsUntil, waitUntil, countNear, countAll, isOrange, isTeal, isBackground, data, artifacts, importFiles } from "./harness.mjs";

let server;
before(async () => { server = await startServer(); });
after(() => server && server.stop());

async function figureIsWhereExpected(page, id, timeSecs, shot) {
  // Pause on a frame, ask the engine where the joints are and where they project.
  const pts = await page.evaluate(([id, t]) => {
    const { player, library, viewer } = window.odori;
    player.pause();
    player.time = t;
    player.drawNow();
    const p = library.jointPositions(id, t);
    const out = [];
    for (let i = 0; i < p.length; i += 3) out.push(viewer.project(p[i], p[i + 1], p[i + 2]));
    return out.filter(Boolean);
  }, [id, timeSecs]);
  const img = await canvasPixels(page, shot);
  const inside = pts.filter(([x, y]) => x > 4 && y > 4 && x < img.width - 4 && y < img.height - 4);
  assert.ok(inside.length > pts.length * 0.9, `only ${inside.length}/${pts.length} joints project inside the canvas`);
  const hits = inside.filter(([x, y]) => countNear(img, x, y, 3, isOrange) > 0).length;
  assert.ok(hits >= inside.length * 0.8, `figure colour found at ${hits} of ${inside.length} projected joints`);
  // Far from every joint, the canvas is background (grid lines allowed).
  const xs = inside.map((p) => p[0]);
  const far = Math.max(...xs) + 60 < img.width - 10 ? [img.width - 8, 20] : [8, 20];
  assert.equal(countNear(img, far[0], far[1], 3, isOrange), 0, "figure colour far from the figure");
  return img;
}

for (const backend of ["webgl2", "webgpu"]) {
  test(`app on ${backend}: built-in clip, BVH by file input, pixels, playback, overlay, broken file`, async () => {
    const { browser, page, logs } = await launch(backend);
    try {
      const t0 = Date.now();
      await openApp(page, server, backend);
      const startMs = Date.now() - t0;
      const timings = await page.evaluate(() => window.odoriTimings);
      // This test checks stick figures' pixels (their colours at the clip's own joints): chosen
      // in the Character menu (the app opens on the built-in body).
      await page.selectOption("#character", "");
      assert.equal(await page.evaluate(() => document.body.dataset.backend), backend);
      assert.equal((await page.textContent("#backend")).trim(), backend === "webgpu" ? "WebGPU" : "WebGL2");
      // The built-in clip plays with no file.
      const rows0 = await page.$$eval("#library tbody tr", (trs) => trs.length);
      assert.equal(rows0, 1);
      await canvasPixelsUntil(page, (img) => countAll(img, isOrange) > 300, "the built-in figure drawn", `${backend}-01-builtin.png`);

      // A real BVH through the file input, with the salsa frame-rate fix.
      await importFiles(page, join(data, "mocap/cmu-salsa/salsa_01.bvh"), { "salsa_01.bvh": { fps: 60 } });
      await page.waitForSelector("#library tbody tr:nth-child(2)", { timeout: 30000 });
      const row = await page.$$eval("#library tbody tr:nth-child(2) td", (tds) => tds.map((t) => t.textContent));
      // Duration spans the frames: (2243 − 1) / 60 = 37.37 s.
      assert.deepEqual(row.slice(0, 6), ["salsa_01", "salsa_01.bvh", "60", "2243", "37.37", "43"]);
      const salsa = await page.evaluate(() => window.odori.player.clip);
      const a = await figureIsWhereExpected(page, salsa, 2.0, `${backend}-02-salsa-t2.png`);
      const b = await figureIsWhereExpected(page, salsa, 5.0, `${backend}-03-salsa-t5.png`);
      let changed = 0;
      for (let i = 0; i < a.rgba.length; i += 4) {
        if (Math.abs(a.rgba[i] - b.rgba[i]) + Math.abs(a.rgba[i + 1] - b.rgba[i + 1]) + Math.abs(a.rgba[i + 2] - b.rgba[i + 2]) > 60) changed++;
      }
      assert.ok(changed > 500, `only ${changed} pixels changed between two frames`);

      // Paused, the canvas changes size (the page's layout moved): the figure is drawn again.
      await page.evaluate(() => { const v = document.querySelector("#view"); v.style.flex = "none"; v.style.height = `${v.clientHeight - 37}px`; });
      // Wait until the canvas has taken its new size, then for the figure on it.
      await waitUntil(() => page.evaluate(() => { const v = document.querySelector("#view"); return v.height === Math.max(1, Math.round(v.clientHeight * Math.min(devicePixelRatio, 2))); }), { what: "the canvas taking its new size" });
      await canvasPixelsUntil(page, (img) => countAll(img, isOrange) > 300, "the paused figure drawn again after the canvas was resized", `${backend}-03b-resized-paused.png`);
      await page.evaluate(() => { const v = document.querySelector("#view"); v.style.flex = ""; v.style.height = ""; });

      // Playing advances the frame counter.
      const f0 = await page.evaluate(() => { window.odori.player.play(); return Number(document.querySelector("#scrub").value); });
      await waitUntil(() => page.evaluate((f0) => Number(document.querySelector("#scrub").value) !== f0, f0), { what: "playback moving the frame counter" });

      // Overlay a second clip: two colours in one scene.
      await importFiles(page, join(data, "mocap/cmu-salsa/salsa_16.bvh"));
      await page.waitForSelector("#library tbody tr:nth-child(3)");
      await page.click("#library tbody tr:nth-child(2) td:first-child");
      await page.check("#library tbody tr:nth-child(3) input[type=checkbox]");
      await page.evaluate(() => { const p = window.odori.player; p.pause(); p.time = 3; p.drawNow(); });
      const both = await canvasPixels(page, `${backend}-04-overlay.png`);
      assert.ok(countAll(both, isOrange) > 200, "first figure (orange) missing");
      assert.ok(countAll(both, isTeal) > 200, "overlaid figure (teal) missing");

      // A broken file: message names it, the library keeps its three clips.
      await importFiles(page, { name: "broken.bvh", mimeType: "text/plain", buffer: Buffer.from("HIERARCHY\nROOT hip\n{\n OFFSET 0 0 0\n CHANNELS 6 Xposition\n") });
      await page.waitForSelector("#messages li.error");
      const msg = await page.textContent("#messages li.error");
      assert.match(msg, /^broken\.bvh:\d+:\d+: /);
      assert.equal(await page.$$eval("#library tbody tr", (trs) => trs.length), 3);
      await page.screenshot({ path: join(artifacts, `${backend}-05-error.png`) });
      writeFileSync(join(artifacts, `${backend}-timings.json`), JSON.stringify({ backend, pageLoadToReadyMs: startMs, firstPoseMs: timings.firstPoseMs }, null, 2));
      console.log(`# ${backend}: first drawn pose ${timings.firstPoseMs.toFixed(0)} ms after script start; ${startMs} ms from navigation to ready`);
      const errors = logs.filter((l) => l.startsWith("[error]") || l.startsWith("[pageerror]"));
      assert.deepEqual(errors, [], "console errors");
    } catch (e) {
      await page.screenshot({ path: join(artifacts, `${backend}-failure.png`) }).catch(() => {});
      console.log(logs.join("\n"));
      throw e;
    } finally {
      await browser.close();
    }
  });
}
