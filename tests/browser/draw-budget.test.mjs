// The drawing budget in Debian's headless Chromium, on WebGL2 and on WebGPU. This machine has
// no GPU: Chromium draws both in software (SwiftShader), and the viewer must say so
// (`adapterInfo`). The app draws only what a person can see change: paused, it draws nothing
// for 2 s (the viewer's own count of frames put on screen) until the camera moves; playing, it
// draws at most 30 frames a second (+2 for where the window falls and a late frame caught up) and its pixels still move
// (real screenshots); lifting the cap (the setting beside the back end's badge, kept in the
// browser) draws more. <odori-player> caps itself on the software adapter too, and honours
// `max-fps` (a number, or "none").
import { test, before, after } from "node:test";
import assert from "node:assert/strict";
import { startServer, launch, openApp, canvasPixels, waitUntil } from "./harness.mjs";

const CAP_FPS = 30;

let server;
before(async () => { server = await startServer(); });
after(() => server && server.stop());

/**
 * Counts draws during `seconds` one-second windows: `[{ frames, ticks, secs }]`, each window's
 * frames put on screen by the counter `which` reads ("app": the viewer's framesDrawn; "player":
 * the element's), the page's animation frames and the window's measured length.
 */
async function drawWindows(page, which, seconds) {
  return page.evaluate(async ([which, seconds]) => {
    const count = () => (which === "app" ? window.odori.viewer.framesDrawn : document.querySelector("odori-player").framesDrawn);
    // The page's animation frames in the same windows: on a loaded machine the display's rate
    // is what the browser manages, not 60.
    let ticks = 0, on = true;
    const tick = () => { ticks++; if (on) requestAnimationFrame(tick); };
    requestAnimationFrame(tick);
    const out = [];
    for (let i = 0; i < seconds; i++) {
      const n0 = count(), k0 = ticks, t0 = performance.now();
      await new Promise((r) => setTimeout(r, 1000));
      out.push({ frames: count() - n0, ticks: ticks - k0, secs: (performance.now() - t0) / 1000 });
    }
    on = false;
    return out;
  }, [which, seconds]);
}

/**
 * Asserts the cap: no window drew more than `fps` a second, and neither did the windows together.
 * The cap's due times advance by whole intervals (a late frame does not push the later ones
 * back, so the one after it may come sooner) with 2 ms of slack for the timestamps' jitter: the
 * due times of the draws in a window of `secs` then lie in `secs` + one interval + 2 ms, spaced
 * at least one interval apart, so a window holds at most floor(fps × (secs + 0.002)) + 2 draws:
 * one for where the window falls and one for a late frame caught up (a 1.016 s window at 30
 * may hold 32, as CI once saw). A faster cap would overrun that over the windows together.
 */
function atMost(windows, fps, what) {
  const bound = (secs) => Math.floor(fps * (secs + 0.002)) + 2;
  for (const w of windows) {
    assert.ok(w.frames <= bound(w.secs), `${what}: ${w.frames} frames in ${w.secs.toFixed(3)} s, more than ${fps} a second (+2): ${JSON.stringify(windows)}`);
  }
  const frames = windows.reduce((s, w) => s + w.frames, 0), secs = windows.reduce((s, w) => s + w.secs, 0);
  assert.ok(frames <= bound(secs), `${what}: ${frames} frames in ${secs.toFixed(3)} s together, more than ${fps} a second (+2): ${JSON.stringify(windows)}`);
}

const perSec = (windows, what = "frames") => windows.reduce((s, w) => s + w[what], 0) / windows.reduce((s, w) => s + w.secs, 0);

/**
 * Asserts that uncapped, every animation frame draws (the clip is 60 fps: each frame is a new
 * pose), and that this is more than the cap whenever the browser's frames come faster than it.
 */
function drawsEveryFrame(lifted, capFps, what) {
  const frames = perSec(lifted), ticks = perSec(lifted, "ticks");
  assert.ok(frames >= 0.9 * ticks - 1, `${what}: ${frames.toFixed(1)} frames drawn a second, of ${ticks.toFixed(1)} animation frames (${JSON.stringify(lifted)})`);
  if (ticks > capFps * 1.2) assert.ok(frames > capFps + 3, `${what}: ${frames.toFixed(1)} frames a second, not more than the cap (${JSON.stringify(lifted)})`);
}

function changedPixels(a, b) {
  let n = 0;
  for (let i = 0; i < a.rgba.length; i += 4) {
    if (Math.abs(a.rgba[i] - b.rgba[i]) + Math.abs(a.rgba[i + 1] - b.rgba[i + 1]) + Math.abs(a.rgba[i + 2] - b.rgba[i + 2]) > 60) n++;
  }
  return n;
}

for (const backend of ["webgl2", "webgpu"]) {
  test(`app on ${backend}: software adapter reported, nothing drawn while paused, capped while playing, cap lifted draws more`, async () => {
    const { browser, page, logs } = await launch(backend);
    try {
      // A smaller view than the other tests': software drawing is cheaper, so the uncapped
      // rate below is the display's rather than what a loaded machine manages.
      await page.setViewportSize({ width: 900, height: 640 });
      await openApp(page, server, backend);
      const info = await page.evaluate(() => window.odori.viewer.adapterInfo);
      assert.equal(info.backend, backend);
      // What Chromium reports here (checked by hand, see the README): WebGL2's renderer names
      // SwiftShader; WebGPU's adapter is the fallback adapter with an empty description.
      assert.equal(info.deviceType, "cpu", JSON.stringify(info));
      assert.equal(info.software, true, JSON.stringify(info));
      if (backend === "webgl2") assert.match(info.name, /SwiftShader/i);
      assert.equal(await page.evaluate(() => document.body.dataset.software), "1");
      assert.equal(await page.isVisible("#draw-cap-box"), true, "the software note is shown");
      assert.equal((await page.textContent("#draw-rate")).trim(), "drawn in software, 30 fps");
      assert.equal(await page.evaluate(() => window.odori.player.maxFps), CAP_FPS);

      // Paused: nothing is drawn for 2 s, whatever the page does in the background.
      await page.evaluate(() => window.odori.player.pause());
      await new Promise((r) => setTimeout(r, 500));
      const paused = await drawWindows(page, "app", 2);
      assert.deepEqual(paused.map((w) => w.frames), [0, 0], `drawn while paused: ${JSON.stringify(paused)}`);
      // The viewer itself skips a frame that would repeat the last image, and draws a new time
      // (poses are interpolated: any new time is a new pose), a new camera or a new size.
      const repeats = await page.evaluate(() => {
        const { viewer, library, player } = window.odori;
        const figs = (t) => [{ clip: player.clip, timeSecs: t }];
        const n0 = viewer.framesDrawn;
        const out = { first: viewer.draw(library, figs(1.0)), again: viewer.draw(library, figs(1.0)), pastEnd: null };
        out.newTime = viewer.draw(library, figs(1.001));
        viewer.orbit(0.01, 0);
        out.newCamera = viewer.draw(library, figs(1.001));
        out.sameAgain = viewer.draw(library, figs(1.001));
        // Past the clip's end every time shows the last frame: one draw, then repeats.
        const end = library.clip(player.clip).durationSecs;
        out.pastEnd = [viewer.draw(library, figs(end + 1)), viewer.draw(library, figs(end + 2))];
        out.counted = viewer.framesDrawn - n0;
        player.drawNow();
        return out;
      });
      assert.deepEqual(repeats, { first: true, again: false, newTime: true, newCamera: true, sameAgain: false, pastEnd: [true, false], counted: 4 }, JSON.stringify(repeats));
      // The camera moves: drawn (at the next animation frame), then nothing again.
      const before = await page.evaluate(() => window.odori.viewer.framesDrawn);
      const box = await page.locator("#view").boundingBox();
      await page.mouse.move(box.x + box.width / 2, box.y + box.height / 2);
      await page.mouse.down();
      await page.mouse.move(box.x + box.width / 2 + 80, box.y + box.height / 2, { steps: 4 });
      await page.mouse.up();
      await waitUntil(() => page.evaluate((n) => window.odori.viewer.framesDrawn > n, before), { what: "the orbited view drawn", timeoutMs: 5000 });
      await new Promise((r) => setTimeout(r, 300));
      const still = await drawWindows(page, "app", 1);
      assert.equal(still[0].frames, 0, "drawn again after the camera stopped");

      // Playing, capped: at most 30 a second, and the figure moves on screen.
      await page.evaluate(() => window.odori.player.play());
      await new Promise((r) => setTimeout(r, 300));
      const capped = await drawWindows(page, "app", 3);
      atMost(capped, CAP_FPS, "playing, capped");
      assert.ok(perSec(capped) >= 5, `playing, only ${perSec(capped).toFixed(1)} frames a second drawn: ${JSON.stringify(capped)}`);
      // Three pictures 0.4 s apart: the figure moves between one pair at least (a move can
      // hold a pose for a moment: CI once saw 50 pixels change in one such 0.4 s). The clip's
      // time is read with each picture, so a stalled clock is told apart from a still pose.
      const shots = [];
      for (const k of ["a", "b", "c"]) {
        if (shots.length) await new Promise((r) => setTimeout(r, 400));
        shots.push({ img: await canvasPixels(page, `${backend}-draw-budget-${k}.png`), time: await page.evaluate(() => window.odori.player.time) });
      }
      const moved = [changedPixels(shots[0].img, shots[1].img), changedPixels(shots[1].img, shots[2].img)];
      assert.ok(Math.max(...moved) > 300, `only ${moved.join(" and ")} pixels changed in two 0.4 s steps of capped playing (clip times ${shots.map((x) => x.time.toFixed(3)).join(", ")} s)`);

      // The person lifts the cap: more frames (the demo clip is 60 fps), said in the status.
      await page.uncheck("#draw-cap");
      assert.equal(await page.evaluate(() => window.odori.player.maxFps), null);
      assert.equal((await page.textContent("#draw-rate")).trim(), "drawn in software, not capped");
      await new Promise((r) => setTimeout(r, 300));
      const lifted = await drawWindows(page, "app", 3);
      console.log(`${backend}: capped ${perSec(capped).toFixed(1)} frames/s (${perSec(capped, "ticks").toFixed(1)} animation frames/s), cap lifted ${perSec(lifted).toFixed(1)} frames/s (${perSec(lifted, "ticks").toFixed(1)} animation frames/s)`);
      drawsEveryFrame(lifted, CAP_FPS, "app, cap lifted");

      // The choice is kept: a reload opens with the cap lifted; ticking the box caps again.
      await openApp(page, server, backend);
      assert.equal(await page.isChecked("#draw-cap"), false);
      assert.equal(await page.evaluate(() => window.odori.player.maxFps), null);
      await page.check("#draw-cap");
      assert.equal(await page.evaluate(() => window.odori.player.maxFps), CAP_FPS);
      assert.equal(await page.evaluate(() => localStorage.getItem("odori.drawCap")), "on");
      assert.deepEqual(logs.filter((l) => l.startsWith("[pageerror]")), []);
    } finally {
      await browser.close();
    }
  });

  test(`<odori-player> on ${backend}: capped on the software adapter, honours max-fps`, async () => {
    const { browser, page, logs } = await launch(backend);
    try {
      await page.route("**/examples/draw-budget.html", (route) => route.fulfill({
        contentType: "text/html",
        body: `<!doctype html><meta charset="utf-8"><script type="module" src="../pkg/player/odori-player.js"></script>
          <odori-player loading="eager" autoplay loop character="stick" backend="${backend}" style="display:block;width:480px;height:360px"></odori-player>`,
      }));
      await page.goto(server.url + "examples/draw-budget.html");
      await waitUntil(() => page.evaluate(() => document.querySelector("odori-player")?.gpuContext != null && !document.querySelector("odori-player").paused), { what: "the player playing", timeoutMs: 60000 });
      const info = await page.evaluate(() => document.querySelector("odori-player").adapterInfo);
      assert.equal(info.backend, backend);
      assert.equal(info.software, true, JSON.stringify(info));
      assert.equal(await page.evaluate(() => document.querySelector("odori-player").maxFps), CAP_FPS);
      await new Promise((r) => setTimeout(r, 300));
      const dflt = await drawWindows(page, "player", 2);
      atMost(dflt, CAP_FPS, "player, default cap");

      await page.evaluate(() => document.querySelector("odori-player").setAttribute("max-fps", "10"));
      await new Promise((r) => setTimeout(r, 200));
      const ten = await drawWindows(page, "player", 2);
      atMost(ten, 10, "player, max-fps=10");
      assert.ok(perSec(ten) >= 5, `max-fps=10 drew only ${perSec(ten).toFixed(1)} a second`);

      await page.evaluate(() => { document.querySelector("odori-player").maxFps = Infinity; });
      assert.equal(await page.evaluate(() => document.querySelector("odori-player").getAttribute("max-fps")), "none");
      await new Promise((r) => setTimeout(r, 200));
      const none = await drawWindows(page, "player", 2);
      console.log(`player on ${backend}: default ${perSec(dflt).toFixed(1)}, max-fps=10 ${perSec(ten).toFixed(1)}, none ${perSec(none).toFixed(1)} frames/s`);
      drawsEveryFrame(none, CAP_FPS, `player, max-fps="none"`);
      assert.ok(perSec(none) > perSec(ten) + 5, `max-fps="none": ${perSec(none).toFixed(1)} a second, not more than at 10 (${perSec(ten).toFixed(1)})`);

      // Paused: nothing drawn.
      await page.evaluate(() => document.querySelector("odori-player").pause());
      await new Promise((r) => setTimeout(r, 200));
      const paused = await drawWindows(page, "player", 1);
      assert.equal(paused[0].frames, 0, "the paused player drew");
      assert.deepEqual(logs.filter((l) => l.startsWith("[pageerror]")), []);
    } finally {
      await browser.close();
    }
  });
}
