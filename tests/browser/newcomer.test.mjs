// A newcomer's path (issue #30), on both back ends: import a BVH and a GLB character (Xbot,
// whose clips are one-frame poses), choose the character, Generate, export the dance through
// the Export dialog, then reload and Open the saved file. Asserted:
// - messages in a person's words: a one-frame pose is said plainly and kept in the Messages
//   log (no toast, no "segment needs 4 counts"); a reload and an Open show no toast but errors;
// - the Export dialog opens on the dance, names it, the character and the format, and its
//   size; the file is what it named (the GLB's animation lasts as long as the dance, or as bars
//   2–3 when those are named);
// - after a reload the library's order, the selected clip, the character and the project's
//   name are as left; Recent projects lists each project once, by its name (the same file
//   opened twice is one project).
import { test, before, after } from "node:test";
import assert from "node:assert/strict";
import { readFileSync } from "node:fs";
import { join } from "node:path";
import { startServer, launch, data, BACKENDS, importFiles, waitUntil } from "./harness.mjs";

let server;
before(async () => { server = await startServer(); });
after(() => server && server.stop());

/** Records every toast the page shows, from the first script on (survives nothing: set per load). */
function recordToasts() {
  window.__toasts = [];
  const start = () => {
    const box = document.querySelector("#toasts");
    if (!box) { requestAnimationFrame(start); return; }
    new MutationObserver((list) => {
      for (const m of list) for (const n of m.addedNodes) if (n.classList) window.__toasts.push({ kind: [...n.classList].find((c) => c !== "toast"), text: n.textContent });
    }).observe(box, { childList: true });
  };
  start();
}

async function waitReady(page) {
  await page.waitForFunction(() => document.body.dataset.ready && document.body.dataset.project === "ready", null, { timeout: 120000 });
  const ready = await page.evaluate(() => document.body.dataset.ready);
  if (ready !== "1") throw new Error(`the app did not start: ${await page.textContent("#messages")}`);
}

/** The GLB's JSON chunk, read here (not by the engine). */
function glbJson(bytes) {
  assert.equal(bytes.subarray(0, 4).toString(), "glTF");
  const len = bytes.readUInt32LE(12);
  return JSON.parse(bytes.subarray(20, 20 + len).toString());
}

/** The longest animation's length, seconds: the largest time accessor max. */
function animationSecs(json) {
  let end = 0;
  for (const a of json.animations || []) for (const s of a.samplers) end = Math.max(end, json.accessors[s.input].max[0]);
  return end;
}

/** What must be as left after a reload. */
async function state(page) {
  return page.evaluate(() => {
    const o = window.odori;
    return {
      order: [...document.querySelectorAll("#library tbody tr")].map((tr) => `${tr.children[1].textContent}/${tr.children[0].textContent}`),
      selected: o.panel.selected == null ? null : o.library.clip(o.panel.selected).name,
      onScreen: o.player.clip == null ? null : o.library.clip(o.player.clip).name,
      character: document.querySelector("#character").selectedOptions[0]?.textContent,
      name: o.project.project.doc().name,
      recent: [...document.querySelectorAll("#project-recent option")].slice(1).map((x) => x.textContent),
    };
  });
}

for (const backend of (process.env.BACKENDS || "webgl2,webgpu").split(",")) {
  test(`a newcomer's path on ${backend}: plain messages, the Export dialog, reopened as left`, async () => {
    const { browser, page, logs } = await launch(backend);
    try {
      await page.addInitScript(recordToasts);
      await page.goto(server.url + BACKENDS[backend].query);
      await waitReady(page);
      await importFiles(page, join(data, "mocap/cmu-salsa/salsa_01.bvh"), { "salsa_01.bvh": { fps: 60 } });
      await page.waitForFunction(() => [...document.querySelectorAll("#messages li")].some((li) => /salsa_01.*dance segments/.test(li.textContent)), null, { timeout: 60000 });
      await page.setInputFiles("#file-input", join(data, "gltf/Xbot.glb"));
      await page.waitForFunction(() => [...document.querySelectorAll("#messages li")].some((li) => /Xbot.glb: \d+ clips? added/.test(li.textContent)), null, { timeout: 60000 });
      await waitUntil(() => page.evaluate(() => [...document.querySelectorAll("#messages li")].some((li) => /still pose|too short to make dance moves/.test(li.textContent))), { what: "the pose clips said plainly in Messages" });
      // Xbot's clips are one-frame poses: said in a person's words, in the log only.
      const said = await page.evaluate(() => ({ log: [...document.querySelectorAll("#messages li")].map((li) => li.textContent), toasts: window.__toasts }));
      assert.ok(!said.log.concat(said.toasts.map((t) => t.text)).some((t) => /segment needs|counts \(5 beats\)/.test(t)), `jargon shown: ${JSON.stringify(said)}`);
      assert.ok(!said.toasts.some((t) => /still pose|too short to make/.test(t.text)), "the pose note is not a toast");
      assert.ok(said.toasts.some((t) => /Xbot\.glb: \d+ clips? added.*choose it in Character/.test(t.text)), `the character is offered: ${JSON.stringify(said.toasts)}`);
      assert.ok(await page.evaluate(() => [...document.querySelector("#character").options].some((o) => o.textContent === "Xbot.glb")), "Xbot is in the Character list at once");
      // Choose the character, Generate the dance.
      await page.focus("#character");
      await page.selectOption("#character", { label: "Xbot.glb" });
      await page.click("#dance-generate");
      await page.waitForFunction(() => !document.querySelector("#dance").dataset.busy && window.odori.choreo.view.length > 3 && window.odori.choreo.view.every((v) => v.state.kind !== "empty"), null, { timeout: 120000 });

      // Export: the dialog opens on the dance, on Xbot, and says the size of the file it saves.
      await page.evaluate(() => { const row = [...document.querySelectorAll("#library tbody tr")].find((tr) => tr.textContent.includes("salsa_01")); row.children[0].click(); });
      await page.click("#export");
      await page.locator("#export-dialog").waitFor({ state: "visible" });
      assert.equal(await page.evaluate(() => document.querySelector("input[name=export-what]:checked").value), "dance", "the dance first, not the clip on screen");
      await page.selectOption("#export-format", "glb");
      const summary = await page.textContent("#export-summary");
      assert.match(summary, /^The dance \(\d+\.\d s\) on Xbot\.glb, as GLB \(glTF 2\.0\): .+\.glb, \d+(\.\d)? (KiB|MiB)\.$/, summary);
      const dance = await page.evaluate(() => { const o = window.odori; return { id: o.choreo.danceId, secs: o.library.clip(o.choreo.danceId).durationSecs, fps: o.library.clip(o.choreo.danceId).fps, bars: o.choreo.view.map((v) => [v.bar.startSecs, v.bar.endSecs]) }; });
      let [download] = await Promise.all([page.waitForEvent("download"), page.click("#export-go")]);
      let bytes = readFileSync(await download.path());
      const shownBytes = await page.evaluate(() => Number(document.querySelector("#export-summary").dataset.bytes));
      assert.equal(bytes.length, shownBytes, "the size said is the file's");
      let json = glbJson(bytes);
      assert.ok(json.skins?.length && json.meshes?.length, "the GLB carries the character");
      assert.ok(Math.abs(animationSecs(json) - dance.secs) <= 1.01 / dance.fps, `the GLB's animation lasts ${animationSecs(json)} s, the dance ${dance.secs} s`);
      // Bars 2–3, as BVH then GLB: the file is as long as those bars.
      await page.click("#export");
      await page.fill("#export-bar-from", "2");
      await page.fill("#export-bar-to", "3");
      assert.equal(await page.evaluate(() => document.querySelector("input[name=export-what]:checked").value), "bars");
      await page.selectOption("#export-format", "bvh");
      assert.match(await page.textContent("#export-summary"), /^Bars 2–3 of the dance \(\d+\.\d s\) on the canonical skeleton, as BVH/);
      await page.selectOption("#export-format", "glb");
      [download] = await Promise.all([page.waitForEvent("download"), page.click("#export-go")]);
      json = glbJson(readFileSync(await download.path()));
      const want = dance.bars[2][1] - dance.bars[1][0];
      assert.ok(Math.abs(animationSecs(json) - want) <= 1.01 / dance.fps, `bars 2–3: ${animationSecs(json)} s, the bars ${want} s`);
      const exportLog = await page.evaluate(() => [...document.querySelectorAll("#messages li")].map((li) => li.textContent).filter((t) => /^Exported/.test(t)));
      console.log(`${backend}: ${summary} | ${exportLog[0]}`);

      // Leave it: a clip selected (salsa_01), the library in its order; the autosave written.
      await page.evaluate(() => { const row = [...document.querySelectorAll("#library tbody tr")].find((tr) => tr.textContent.includes("salsa_01")); row.children[0].click(); });
      await page.evaluate(() => window.odori.project.store.flush());
      const left = await state(page);
      const saved = await page.evaluate(() => { const b = window.odori.project.project.save(); let s = ""; for (let i = 0; i < b.length; i += 0x8000) s += String.fromCharCode(...b.subarray(i, i + 0x8000)); return btoa(s); });

      await page.reload();
      await waitReady(page);
      await page.waitForTimeout(1500); // anything the restore says late would be shown by now
      const back = await state(page);
      const toasts = await page.evaluate(() => window.__toasts);
      console.log(`${backend}: left ${JSON.stringify(left)}\n  back ${JSON.stringify(back)}\n  toasts on reload: ${JSON.stringify(toasts)}`);
      assert.deepEqual(toasts.filter((t) => t.kind !== "error"), [], "a reload shows no toast but errors");
      assert.deepEqual(back.order, left.order, "the library's order");
      assert.equal(back.selected, left.selected, "the selected clip");
      assert.equal(back.onScreen, left.onScreen, "the clip on screen");
      assert.equal(back.character, "Xbot.glb", "the character");
      assert.equal(back.name, left.name, "the project's name");
      const byName = (list) => list.map((t) => t.replace(/ \(open\)$/, ""));
      assert.equal(new Set(byName(back.recent)).size, back.recent.length, `Recent lists each project once by its name: ${back.recent}`);

      // New project, then Open the saved file (dropped on the page): it is the stored project
      // (not a second entry), shown as left, with no toast but errors on the way.
      await Promise.all([page.waitForNavigation({ timeout: 60000 }), page.click("#project-new")]);
      await waitReady(page);
      const fresh = await state(page);
      assert.equal(fresh.recent.length, back.recent.length + 1, `a new project is one more entry: ${fresh.recent}`);
      await Promise.all([
        page.waitForNavigation({ timeout: 60000 }),
        page.evaluate((b) => {
          const bytes = Uint8Array.from(atob(b), (c) => c.charCodeAt(0));
          const dt = new DataTransfer();
          dt.items.add(new File([bytes], "my dance.odori"));
          document.body.dispatchEvent(new DragEvent("drop", { dataTransfer: dt, bubbles: true, cancelable: true }));
        }, saved),
      ]);
      await waitReady(page);
      await page.waitForTimeout(1500);
      const opened = await state(page);
      assert.deepEqual((await page.evaluate(() => window.__toasts)).filter((t) => t.kind !== "error"), [], "Open shows no toast but errors");
      assert.equal(opened.recent.length, fresh.recent.length, `the same project opened again is not listed twice: ${opened.recent}`);
      assert.equal(new Set(byName(opened.recent)).size, opened.recent.length, `each once by its name: ${opened.recent}`);
      assert.deepEqual(opened.order, left.order, "opened: the library's order");
      assert.equal(opened.selected, left.selected, "opened: the selected clip");
      assert.equal(opened.name, left.name, "opened: the project's name");
      assert.ok(!logs.some((l) => l.includes("[pageerror]")), logs.join("\n"));
    } catch (e) {
      console.log(logs.slice(-40).join("\n"));
      console.log("Messages:\n" + (await page.evaluate(() => [...document.querySelectorAll("#messages li")].map((li) => `${li.className}: ${li.textContent}`).join("\n")).catch(() => "")));
      throw e;
    } finally {
      await browser.close();
    }
  });
}
