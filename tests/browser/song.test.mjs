// Song analysis in the page: the built-in demo song is analysed at start; a real recording
// opened through the song input gets the same bars as the native analysis (within one hop);
// grid corrections re-derive the bars; a file that is not audio gets a message naming it.
import { test, before, after } from "node:test";
import assert from "node:assert/strict";
import { join } from "node:path";
import { execFileSync } from "node:child_process";
import { startServer, launch, openApp, data, root, artifacts } from "./harness.mjs";

const DRUMS = "beats/drummer1_eval_session_1_funk-groove1_138_beat_4-4.FluidR3GM.flac";
let server;
before(async () => { server = await startServer(); });
after(() => server && server.stop());

test("song: demo song, a real file matching the native bars, corrections, an undecodable file", async () => {
  const native = JSON.parse(execFileSync("cargo", ["run", "-q", "-p", "odori-tests", "--example", "song_grid", "--", DRUMS], { cwd: root, encoding: "utf8" }));
  const { browser, page, logs } = await launch("webgl2");
  try {
    await openApp(page, server, "webgl2");
    await page.waitForFunction(() => document.body.dataset.song === "demo", null, { timeout: 60000 });
    const demo = await page.evaluate(() => window.odori.song.grid);
    assert.ok(Math.abs(demo.bpm - 120) < 1.5, `demo song tempo ${demo.bpm}`);
    assert.ok(demo.bars.length >= 16, `${demo.bars.length} bars`);
    const intens = demo.bars.map((b) => b.intensity);
    assert.ok(Math.max(...intens) - Math.min(...intens) > 0.3, "the demo's sections differ in intensity");

    await page.setInputFiles("#song-input", join(data, DRUMS));
    await page.waitForFunction((n) => document.body.dataset.song === n, DRUMS.split("/").pop(), { timeout: 60000 });
    const grid = await page.evaluate(() => window.odori.song.grid);
    const hop = native.hopSecs;
    assert.equal(grid.bars.length, native.grid.bars.length, "bar count, page vs native");
    let worst = 0;
    grid.bars.forEach((b, i) => { worst = Math.max(worst, Math.abs(b.startSecs - native.grid.bars[i].startSecs)); });
    assert.ok(worst <= hop + 1e-4, `a bar starts ${worst.toFixed(4)} s away from the native result (hop ${hop})`);
    console.log(`# page vs native: ${grid.bars.length} bars, worst bar-start difference ${(worst * 1000).toFixed(2)} ms, ${grid.bpm.toFixed(2)} vs ${native.grid.bpm.toFixed(2)} BPM`);
    await page.screenshot({ path: join(artifacts, "song-01-drums.png") });

    // Corrections: typed BPM, beats per bar, nudge; reset goes back.
    await page.fill("#song-bpm", "100");
    await page.dispatchEvent("#song-bpm", "change");
    const g100 = await page.evaluate(() => window.odori.song.grid);
    assert.ok(Math.abs(g100.bpm - 100) < 1e-3 && g100.regular);
    await page.selectOption("#song-bpb", "3");
    const g3 = await page.evaluate(() => window.odori.song.grid);
    assert.equal(g3.beatsPerBar, 3);
    assert.ok(g3.bars.length > g100.bars.length, "3-beat bars are more numerous");
    const before = g3.bars[1].startSecs;
    await page.click("#song-later");
    const nudged = await page.evaluate(() => window.odori.song.grid);
    assert.ok(Math.abs(nudged.bars[1].startSecs - before - 0.01) < 1e-3 || Math.abs(nudged.bars[0].startSecs - g3.bars[0].startSecs - 0.01) < 1e-3, "nudged 10 ms later");
    await page.click("#song-reset");
    const back = await page.evaluate(() => window.odori.song.grid);
    assert.equal(back.bars.length, native.grid.bars.length);

    // Not audio: a clear message naming the file; the song stays.
    await page.setInputFiles("#song-input", { name: "notes.mp3", mimeType: "audio/mpeg", buffer: Buffer.from("this is not audio at all".repeat(50)) });
    await page.waitForSelector("#messages li.error");
    assert.match(await page.textContent("#messages li.error"), /^notes\.mp3: /);
    assert.equal(await page.evaluate(() => window.odori.song.grid.bars.length), native.grid.bars.length);
    const errors = logs.filter((l) => l.startsWith("[pageerror]"));
    assert.deepEqual(errors, []);
  } finally {
    await browser.close();
  }
});
