// Stating an imported clip's tempo in the Dance strip: the clip is re-cut into 4-count
// segments at that tempo; bars pinned to its earlier cut keep their motion (and the person is
// told), a pinned built-in move is untouched, bad tempos get a clear message and change nothing.
import { test, before, after } from "node:test";
import assert from "node:assert/strict";
import { join } from "node:path";
import { startServer, launch, openApp, artifacts, data, importFiles } from "./harness.mjs";

let server;
before(async () => { server = await startServer(); });
after(() => server && server.stop());

const messages = (page) => page.evaluate(() => [...document.querySelectorAll("#messages li")].map((li) => `${li.className}: ${li.textContent}`));

test("dance: state an imported clip's tempo and re-cut it, keeping the pinned bars", async () => {
  const { browser, page, logs } = await launch("webgl2");
  try {
    await openApp(page, server, "webgl2");
    await page.waitForFunction(() => Number(document.querySelector("#dance").dataset.bars) > 8, null, { timeout: 60000 });
    assert.equal(await page.isVisible("#dance-clip-row"), false, "no clip row before any clip is imported");
    await importFiles(page, join(data, "mocap/cmu-salsa/salsa_02.bvh"), { "salsa_02.bvh": { fps: 60 } });
    await page.waitForFunction(() => [...document.querySelectorAll("#messages li")].some((li) => /dance segments/.test(li.textContent)), null, { timeout: 30000 });
    assert.ok(await page.isVisible("#dance-clip-row"));
    assert.match(await page.textContent("#dance-clip-info"), /found in the motion/);
    const clips = await page.evaluate(() => window.odori.choreo.choreographer.cutClips());
    assert.equal(clips.length, 1);
    assert.equal(clips[0].name, await page.$eval("#dance-clip option", (o) => o.textContent));
    // Bar 2 pinned to a salsa segment, bar 5 to a built-in move; Generate fills the rest.
    const pins = await page.evaluate(() => {
      const { choreo } = window.odori;
      const ch = choreo.choreographer;
      let salsa = -1;
      for (let i = 0; i < ch.segmentCount && salsa < 0; i++) if (/salsa_02/.test(ch.segment(i).source)) salsa = i + 3;
      choreo.act(() => { ch.set(1, salsa); ch.set(4, 10); });
      return { salsa, salsaName: ch.segment(salsa).name, builtinName: ch.segment(10).name, count: ch.segmentCount };
    });
    await page.click("#dance-generate");
    await page.waitForFunction(() => !document.querySelector("#dance").dataset.busy && window.odori.choreo.view.every((v) => v.state.kind !== "empty"), null, { timeout: 30000 });
    const poses = () => page.evaluate(() => {
      const { choreo, library } = window.odori;
      choreo.renderDance();
      const at = (bar, f) => { const b = choreo.view[bar].bar; return library.jointPositions(choreo.danceId, b.startSecs + f * (b.endSecs - b.startSecs)); };
      return [1, 4].flatMap((bar) => [0.25, 0.5, 0.75].map((f) => Array.from(at(bar, f))));
    });
    const before = await poses();

    // A tempo out of range: a clear message, nothing changes.
    await page.fill("#dance-clip-bpm", "500");
    await page.click("#dance-recut");
    assert.match((await messages(page))[0], /^error: .*30 to 300 counts per minute/);
    assert.equal(await page.evaluate(() => window.odori.choreo.choreographer.segmentCount), pins.count);

    // State 100 counts per minute and re-cut.
    await page.fill("#dance-clip-bpm", "100");
    await page.click("#dance-recut");
    await page.waitForFunction(() => document.querySelector("#dance").dataset.recuts === "1");
    const said = await messages(page);
    assert.ok(said.some((m) => /^info: .*re-cut at 100 counts\/min/.test(m)), said.join("\n"));
    assert.ok(said.some((m) => /^warning: .*bar 2 keeps the pinned move from .*earlier cut/.test(m)), said.join("\n"));
    assert.match(await page.textContent("#dance-clip-info"), /100\.0 counts\/min \(stated\)/);
    const after = await page.evaluate(() => {
      const ch = window.odori.choreo.choreographer;
      const view = window.odori.choreo.view;
      const segs = Array.from({ length: ch.segmentCount }, (_, i) => ch.segment(i));
      return {
        bar2: view[1].state, bar5: view[4].state,
        bar2Name: ch.segment(view[1].state.segment).name, bar5Name: ch.segment(view[4].state.segment).name,
        newCut: segs.filter((s) => /salsa_02/.test(s.source) && !s.retired).map((s) => s.tempoBpm),
        retired: segs.filter((s) => s.retired).length,
        clip: ch.cutClips()[0],
      };
    });
    assert.equal(after.bar2.kind, "pinned");
    assert.ok(after.bar2Name.startsWith(pins.salsaName), `bar 2 now holds ${after.bar2Name}`);
    assert.deepEqual([after.bar5.kind, after.bar5Name], ["pinned", pins.builtinName]);
    assert.ok(after.retired >= 1);
    assert.ok(after.newCut.length > 10 && after.newCut.every((t) => Math.abs(t - 100) < 2), `new cut tempos ${after.newCut}`);
    assert.deepEqual([after.clip.tempoBpm, after.clip.tempoDetected], [100, false]);
    // The dance is the same motion in the pinned bars.
    const now = await poses();
    const worst = Math.max(...now.flatMap((p, i) => p.map((v, k) => Math.abs(v - before[i][k]))));
    assert.ok(worst < 1e-5, `pinned bars' pose changed by ${worst}`);
    // Generate again: the pins stay, open bars come from what can be offered.
    await page.click("#dance-generate");
    await page.waitForFunction(() => !document.querySelector("#dance").dataset.busy && document.querySelector("#dance").dataset.joins === "ready", null, { timeout: 30000 });
    const regen = await page.evaluate(() => {
      const ch = window.odori.choreo.choreographer;
      return window.odori.choreo.view.map((v) => ({ kind: v.state.kind, retired: ch.segment(v.state.segment).retired }));
    });
    assert.ok(regen.every((b, i) => b.kind === (i === 1 || i === 4 ? "pinned" : "generated")));
    assert.ok(regen.every((b, i) => i === 1 || !b.retired), "an open bar was filled from the earlier cut");
    await page.screenshot({ path: join(artifacts, "dance-03-recut.png") });
    assert.deepEqual(logs.filter((l) => l.startsWith("[pageerror]")), []);
  } finally {
    await browser.close();
  }
});
