// An MMD dance as a source of the project (issue 28 item 1), through the page's own controls on
// both back ends: the WAVEFILE VMD opened through the MMD dialog (song offset 160) becomes a
// project source; Generate with "my moves" fills bars with its segments (the bar strip names
// it); a reload brings it back (the source with its offset, the same bars); the share note says
// the link leaves those bars out because MMD files stay with the person, and the link made has
// them as empty bars. Then (both back ends) WAVEFILE given with miku_v2's folder: posed on miku_v2, the
// model kept in the project, and posed on it again after a reload.
import { test, before, after } from "node:test";
import assert from "node:assert/strict";
import { readFileSync, readdirSync } from "node:fs";
import { join } from "node:path";
import { startServer, launch, data, BACKENDS } from "./harness.mjs";

let server;
before(async () => { server = await startServer(); });
after(() => server && server.stop());

const WAVEFILE = join(data, "mmd/motion/wavefile_v2.vmd");

async function waitReady(page) {
  await page.waitForFunction(() => document.body.dataset.ready && document.body.dataset.project === "ready", null, { timeout: 120000 });
  const ready = await page.evaluate(() => document.body.dataset.ready);
  if (ready !== "1") throw new Error(`the app did not start: ${await page.textContent("#messages")}`);
}

/** The bars as the strip shows them, and which of them the project holds from the VMD source. */
const state = (page) => page.evaluate(() => {
  const doc = window.odori.project.project.doc();
  const src = doc.sources.find((s) => s.fileName === "wavefile_v2.vmd");
  return {
    source: src ? { fileName: src.fileName, options: src.options } : null,
    strip: [...document.querySelectorAll("#dance-bars .bar")].map((b) => b.querySelector(".bar-src")?.textContent ?? ""),
    fromVmd: doc.dance.bars.map((b, i) => (b.move && b.move.kind === "cut" && src && b.move.clip.source === src.id ? i : -1)).filter((i) => i >= 0),
  };
});

for (const backend of (process.env.BACKENDS || Object.keys(BACKENDS).join(",")).split(",")) {
  test(`an MMD dance is a project source (${backend}): Generate uses it, a reload keeps it, a link leaves it out`, async () => {
    const { browser, page, logs } = await launch(backend);
    try {
      await page.goto(server.url + BACKENDS[backend].query);
      await waitReady(page);
      await page.setInputFiles("#file-input", [{ name: "wavefile_v2.vmd", mimeType: "application/octet-stream", buffer: readFileSync(WAVEFILE) }]);
      const dialog = page.locator("#mmd-import");
      await dialog.waitFor({ state: "visible", timeout: 30000 });
      assert.match(await dialog.textContent(), /project's dance library/);
      await dialog.locator(".mmd-offset").fill("160");
      await dialog.locator("button[value=import]").click();
      await page.waitForFunction(() => /wavefile_v2\.vmd: dance added to the project/.test(document.querySelector("#messages").textContent), null, { timeout: 120000 });
      assert.match(await page.textContent("#messages"), /MMD files stay with you/);
      let s = await state(page);
      assert.deepEqual(s.source?.options?.song_offset_frames, 160, JSON.stringify(s.source));

      // Generate with my moves: bars dance WAVEFILE's segments, and the strip names it.
      await page.waitForFunction(() => document.querySelector("#dance").dataset.joins === "ready" && window.odori.choreo.lastPrepare?.segments > 558, null, { timeout: 180000 });
      await page.selectOption("#dance-moves-source", "mine");
      await page.click("#dance-generate");
      await page.waitForFunction(() => !document.querySelector("#dance").dataset.busy && window.odori.choreo.view.every((v) => v.state.kind !== "empty"), null, { timeout: 180000 });
      s = await state(page);
      assert.ok(s.fromVmd.length * 2 >= s.strip.length, `Generate (my moves) put WAVEFILE in ${s.fromVmd.length} of ${s.strip.length} bars`);
      for (const i of s.fromVmd) assert.match(s.strip[i], /wavefile_v2/, `bar ${i + 1} names its source`);

      // The share note: those bars are left out of a link, saying why; the link is offered.
      const note = await page.evaluate(() => ({ hidden: document.querySelector("#dance-share-note").hidden, text: document.querySelector("#dance-share-note").textContent, off: document.querySelector("#dance-share").disabled }));
      assert.ok(!note.hidden && !note.off, JSON.stringify(note));
      assert.match(note.text, /leaves out bars? [\d, ]+: .*wavefile_v2\.vmd.*MMD files stay with you/);
      await page.click("#dance-share");
      await page.waitForFunction(() => location.hash.startsWith("#dance="), null, { timeout: 10000 });
      const hash = await page.evaluate(() => location.hash);
      const items = hash.split(".").slice(3);
      assert.equal(items.length, s.strip.length, hash);
      for (const [i, it] of items.entries()) assert.equal(it === "-", s.fromVmd.includes(i), `bar ${i + 1} in the link: ${it}`);
      assert.match(await page.textContent("#messages"), /Share link: The link leaves out bar/);

      // Reload (the link cleared, so the page opens the project, not the link): all still there.
      await page.evaluate(() => history.replaceState(null, "", location.pathname + location.search));
      const before = s;
      // The autosave (debounced) has written it all.
      await page.evaluate(() => window.odori.project.store.flush());
      await page.reload();
      await waitReady(page);
      await page.waitForFunction(() => window.odori.choreo && window.odori.choreo.view.every((v) => v.state.kind !== "empty"), null, { timeout: 180000 });
      s = await state(page);
      assert.deepEqual(s.source, before.source, "the VMD source and its offset after the reload");
      assert.deepEqual(s.fromVmd, before.fromVmd, "the bars dancing WAVEFILE after the reload");
      for (const i of s.fromVmd) assert.match(s.strip[i], /wavefile_v2/);
      console.log(`${backend}: WAVEFILE (offset 160) in the project, ${before.fromVmd.length} of ${before.strip.length} bars from it after Generate (my moves); reload keeps them; the link leaves them out`);
      assert.ok(!logs.some((l) => l.startsWith("[pageerror]")), logs.join("\n"));
    } finally {
      await browser.close();
    }
  });
}

// Issue 28: a VMD given with its model (miku_v2's folder and WAVEFILE, as a person drops them)
// is posed on that model, and the project keeps the model with the dance: after a reload the
// dance is posed on miku_v2 again (its joints are miku_v2's bones, not the standard skeleton's,
// which the same VMD imported on the standard skeleton shows as the control).
for (const backend of (process.env.BACKENDS || Object.keys(BACKENDS).join(",")).split(",")) test(`an MMD dance given with its model keeps the model in the project across a reload (${backend})`, async () => {
  const { browser, page, logs } = await launch(backend);
  try {
    await page.goto(server.url + BACKENDS[backend].query);
    await waitReady(page);
    const dir = join(data, "mmd/miku_v2");
    const files = readdirSync(dir).filter((n) => !/\.txt$/i.test(n)).map((n) => ({ name: n, mimeType: "application/octet-stream", buffer: readFileSync(join(dir, n)) }));
    await page.setInputFiles("#file-input", [...files, { name: "wavefile_v2.vmd", mimeType: "application/octet-stream", buffer: readFileSync(WAVEFILE) }]);
    const dialog = page.locator("#mmd-import");
    await dialog.waitFor({ state: "visible", timeout: 30000 });
    const model = await dialog.locator(".mmd-model").inputValue();
    assert.notEqual(model, "standard", "the dialog offers the model the VMD's header names first");
    await dialog.locator(".mmd-offset").fill("160");
    await dialog.locator("button[value=import]").click();
    await page.waitForFunction(() => /wavefile_v2\.vmd: dance added to the project, posed on model/.test(document.querySelector("#messages").textContent), null, { timeout: 120000 });
    const dance = () => page.evaluate(() => {
      const app = window.odori.project;
      const src = app.project.doc().sources.find((s) => s.fileName === "wavefile_v2.vmd");
      const id = src && app.libraryId({ source: src.id, clip: 0 });
      const lib = window.odori.library;
      return { model: src?.model?.fileName ?? null, offset: src?.options?.song_offset_frames, joints: id != null ? lib.jointNames(id) : null, at10: id != null ? Array.from(lib.jointPositions(id, 10)) : null };
    });
    const before = await dance();
    assert.equal(before.model, "miku_v2.pmd");
    assert.equal(before.offset, 160);
    // The control: the same VMD on Odori's standard MMD skeleton has other joints.
    const standard = await page.evaluate(async (b64) => {
      const bytes = Uint8Array.from(atob(b64), (c) => c.charCodeAt(0));
      const r = window.odori.library.importFiles([{ name: "control.vmd", bytes }], { model: "standard" });
      const id = r.motions[0].clip.id;
      return { joints: window.odori.library.jointNames(id), at10: Array.from(window.odori.library.jointPositions(id, 10)) };
    }, readFileSync(WAVEFILE).toString("base64"));
    // Joint by joint (by name) at 10 s: posed on miku_v2, the figure stands elsewhere than on the standard skeleton.
    let gap = 0;
    before.joints.forEach((n, i) => {
      const k = standard.joints.indexOf(n);
      if (k >= 0) gap = Math.max(gap, Math.hypot(...[0, 1, 2].map((c) => before.at10[3 * i + c] - standard.at10[3 * k + c])));
    });
    console.log(`${backend}: WAVEFILE on miku_v2 vs on the standard skeleton at 10 s: joints up to ${gap.toFixed(3)} m apart (${before.joints.length} and ${standard.joints.length} joints)`);
    assert.ok(gap > 0.01 || JSON.stringify(before.joints) !== JSON.stringify(standard.joints), "posed on miku_v2, not on the standard skeleton");

    await page.evaluate(() => window.odori.project.store.flush());
    await page.reload();
    await waitReady(page);
    await page.waitForFunction(() => { const a = window.odori.project; const s = a.project.doc().sources.find((x) => x.fileName === "wavefile_v2.vmd"); return s && a.libraryId({ source: s.id, clip: 0 }) != null; }, null, { timeout: 120000 });
    const after = await dance();
    console.log(`${backend}: WAVEFILE on ${after.model}: ${after.joints.length} joints after the reload, the same pose at 10 s`);
    assert.deepEqual(after, before, "after the reload the dance is posed on miku_v2 again");
    const errors = await page.evaluate(() => [...document.querySelectorAll("#messages li.error")].map((li) => li.textContent));
    assert.deepEqual(errors, []);
    assert.ok(!logs.some((l) => l.startsWith("[pageerror]")), logs.join("\n"));
  } finally {
    await browser.close();
  }
});
