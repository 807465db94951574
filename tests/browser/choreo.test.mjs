// Composing a dance in the page with no file: select a bar, 6 candidates play side by side,
// Set one, Search twice, Generate, play: the pinned bar keeps its segment, every bar is
// filled and the figure moves through every bar, following the song's clock.
import { test, before, after } from "node:test";
import assert from "node:assert/strict";
import { join } from "node:path";
import { startServer, launch, openApp, canvasPixels, countAll, artifacts, data, waitUntil, importFiles } from "./harness.mjs";

let server;
before(async () => { server = await startServer(); });
after(() => server && server.stop());

const hueCount = (img) => {
  // Distinct saturated hues on screen (the six candidate colours differ in hue).
  const bins = new Set();
  for (let i = 0; i < img.rgba.length; i += 4) {
    const [r, g, b] = [img.rgba[i], img.rgba[i + 1], img.rgba[i + 2]];
    const mx = Math.max(r, g, b), mn = Math.min(r, g, b);
    if (mx < 110 || mx - mn < 60) continue;
    let h;
    if (mx === r) h = ((g - b) / (mx - mn) + 6) % 6; else if (mx === g) h = (b - r) / (mx - mn) + 2; else h = (r - g) / (mx - mn) + 4;
    bins.add(Math.floor(h * 4)); // 24 hue bins
  }
  return bins.size;
};

test("dance: candidates, Set, Search twice, Generate, play", async () => {
  const { browser, page, logs } = await launch("webgl2");
  try {
    await openApp(page, server, "webgl2");
    // The candidates' colours below are checked as stick figures (chosen in the Character
    // menu; the app opens on the built-in body, where each candidate is a tinted body).
    await page.selectOption("#character", "");
    await page.waitForFunction(() => Number(document.querySelector("#dance").dataset.bars) > 8, null, { timeout: 60000 });
    const nBars = Number(await page.evaluate(() => document.querySelector("#dance").dataset.bars));
    // An imported humanoid clip joins the segment library, cut at its own beats.
    const builtinSegments = await page.evaluate(() => window.odori.choreo.choreographer.segmentCount);
    await importFiles(page, join(data, "mocap/cmu-salsa/salsa_02.bvh"), { "salsa_02.bvh": { fps: 60 } });
    await page.waitForFunction(() => [...document.querySelectorAll("#messages li")].some((li) => /dance segments/.test(li.textContent)), null, { timeout: 30000 });
    assert.ok(await page.evaluate(() => window.odori.choreo.choreographer.segmentCount) > builtinSegments);
    // The join costs for the grown library are built a slice at a time between frames.
    await page.waitForFunction(() => document.querySelector("#dance").dataset.joins === "ready" && window.odori.choreo.lastPrepare?.segments > 558, null, { timeout: 30000 });
    const prep = await page.evaluate(() => window.odori.choreo.lastPrepare);
    assert.ok(prep.slices >= 2, `join table built in ${prep.slices} slice(s)`);
    console.log(`join table for ${prep.segments} segments: ${prep.slices} slices, ${prep.totalMs.toFixed(0)} ms in all, longest ${prep.longestMs.toFixed(1)} ms`);
    const before = await canvasPixels(page);
    await page.click('#dance-bars [data-bar="4"]');
    await page.waitForFunction(() => document.querySelector("#dance").dataset.candidates === "6");
    await page.evaluate(() => { const p = window.odori.player; p.pause(); p.time = 0.6; p.drawNow(); });
    const six = await canvasPixels(page, "dance-01-candidates.png");
    assert.ok(hueCount(six) >= hueCount(before) + 3, `candidate colours on screen: ${hueCount(six)} hue bins (before: ${hueCount(before)})`);
    // Set candidate 2 on bar 5.
    await page.click('#dance-candidates [data-k="1"]');
    await page.click("#dance-set");
    const pinned = await page.evaluate(() => window.odori.choreo.view[4].state);
    assert.equal(pinned.kind, "pinned");
    const seg = pinned.segment;
    // Search twice on bar 3 (liking one candidate each round): τ falls, new candidates.
    await page.click('#dance-bars [data-bar="2"]');
    const first = await page.evaluate(() => window.odori.choreo.candidates.slice());
    for (let round = 0; round < 2; round++) {
      await page.click('#dance-candidates [data-k="0"]');
      await page.click("#dance-search");
    }
    const v2 = await page.evaluate(() => window.odori.choreo.view[2]);
    assert.ok(Math.abs(v2.tau - 0.95 * 0.95) < 1e-4, `τ after two searches: ${v2.tau}`);
    const third = await page.evaluate(() => window.odori.choreo.candidates.slice());
    assert.ok(third.every((s) => !first.includes(s)), "shown candidates never come back");
    // Generate says so, on a painted frame, before the engine holds the page: at the engine's
    // call the button reads "Generating…" and a frame has run since it did.
    await page.evaluate(() => {
      const c = window.odori.choreo.choreographer;
      const generate = c.generate;
      const button = document.querySelector("#dance-generate");
      window.__gen = { labelAt: null, frames: 0, label: null };
      new MutationObserver(() => { if (button.textContent === "Generating…" && window.__gen.labelAt === null) window.__gen.labelAt = performance.now(); }).observe(button, { childList: true, characterData: true, subtree: true });
      // Read the clock in the callback: a frame's own timestamp is its vsync's, which may come
      // before the click that set the label.
      const tick = () => { if (window.__gen.label !== null) return; if (window.__gen.labelAt !== null && performance.now() > window.__gen.labelAt) window.__gen.frames++; requestAnimationFrame(tick); };
      requestAnimationFrame(tick);
      c.generate = function (...args) { window.__gen.label = button.textContent; c.generate = generate; return generate.apply(c, args); };
    });
    // Generate: every bar filled, the pinned bar unchanged.
    await page.click("#dance-generate");
    await page.waitForFunction(() => !document.querySelector("#dance").dataset.busy && window.odori.choreo.view.every((v) => v.state.kind !== "empty"), null, { timeout: 30000 });
    const gen = await page.evaluate(() => ({ ...window.__gen, now: document.querySelector("#dance-generate").textContent }));
    assert.equal(gen.label, "Generating…", `the button at the engine's call: ${JSON.stringify(gen)}`);
    assert.ok(gen.frames >= 1, `no frame ran between "Generating…" and the engine's call: ${JSON.stringify(gen)}`);
    assert.equal(gen.now, "Generate", "the button's label is back");
    const view = await page.evaluate(() => window.odori.choreo.view);
    assert.equal(view.length, nBars);
    assert.ok(view.every((v) => v.state.kind !== "empty"), "an empty bar after Generate");
    assert.deepEqual(view[4].state, { kind: "pinned", segment: seg });
    // The bar row reads out each bar's quality (spec §J) and the whole dance's.
    const readout = await page.evaluate(() => ({
      titles: [...document.querySelectorAll("#dance-bars .bar")].map((b) => b.title),
      row: document.querySelector("#dance-bars").title,
      q: window.odori.choreo.quality,
    }));
    assert.ok(readout.titles.every((t) => /beat alignment \d/.test(t) && /foot skate/.test(t)), readout.titles[0]);
    assert.ok(readout.titles.slice(1).every((t) => /join jump/.test(t)), readout.titles[1]);
    assert.match(readout.row, /Whole dance: beat alignment/);
    assert.equal(readout.q.bars.length, nBars);
    assert.ok(readout.q.beats.musicBeatsPerSec > 1, "the song's beats reach the readout");
    // The dance moves through every bar: each bar's middle pose differs from the next one's.
    const still = await page.evaluate(() => {
      const { choreo, library } = window.odori;
      choreo.renderDance();
      const id = choreo.danceId;
      const mids = choreo.view.map((v) => (v.bar.startSecs + v.bar.endSecs) / 2);
      const poses = mids.map((t) => library.jointPositions(id, t));
      const moving = [];
      // Largest pose change from the bar's first eighth over eight moments of the bar (a
      // 2-count move repeats itself within a bar, so two moments are not enough).
      choreo.view.forEach((v) => {
        const at = (f) => library.jointPositions(id, v.bar.startSecs + f * (v.bar.endSecs - v.bar.startSecs));
        const a = at(0.0625);
        let most = 0;
        for (let s = 1; s < 8; s++) {
          const b = at(0.0625 + s / 8);
          let d = 0;
          for (let k = 0; k < a.length; k++) d += Math.abs(a[k] - b[k]);
          most = Math.max(most, d);
        }
        moving.push(most);
      });
      return { moving, n: poses.length };
    });
    const idle = still.moving.map((d, i) => [i + 1, d]).filter(([, d]) => d < 0.05);
    assert.deepEqual(idle, [], "bars where the figure does not move");
    // Play the dance with the music: the figure follows the song's clock.
    await page.click('#dance-bars [data-bar="0"]');
    await page.click("#dance-play");
    await waitUntil(() => page.evaluate(() => window.odori.songPlayer.playing && window.odori.songPlayer.position() > 0.5), { what: "the song playing past 0.5 s" });
    // Read the figure's time and the song's clock in one animation frame, just after the
    // player's own tick: a loaded machine may skip frames, but never between the two reads.
    const st = await page.evaluate(() => new Promise((done) => requestAnimationFrame(() => done({ song: window.odori.songPlayer.position(), playing: window.odori.songPlayer.playing, time: window.odori.player.time, clip: window.odori.player.clip, dance: window.odori.choreo.danceId }))));
    assert.ok(st.playing, "the song plays");
    assert.equal(st.clip, st.dance);
    assert.ok(st.song > 0.5 && Math.abs(st.time - st.song) < 0.25, `figure time ${st.time} vs song ${st.song}`);
    await page.screenshot({ path: join(artifacts, "dance-02-playing.png") });
    // Undo steps back through the edits (opening bar 1's candidates, then Generate): the
    // bars are empty again but for the pinned one; redo brings the dance back.
    const empties = () => page.evaluate(() => window.odori.choreo.view.filter((v) => v.state.kind === "empty").length);
    let steps = 0;
    while ((await empties()) < nBars - 1 && steps < 3) { await page.click("#dance-undo"); steps++; }
    assert.equal(await empties(), nBars - 1, `after ${steps} undos`);
    assert.deepEqual(await page.evaluate(() => window.odori.choreo.view[4].state), { kind: "pinned", segment: seg });
    await page.click("#dance-redo");
    assert.equal(await empties(), 0, "redo brings Generate back");
    assert.deepEqual(logs.filter((l) => l.startsWith("[pageerror]")), []);
    void countAll;
  } finally {
    await browser.close();
  }
});
