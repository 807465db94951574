// The app as a person meets it (issue #13), on both graphics back ends: one transport for
// song, dance and clip (Pause really pauses both; space leaves focused controls alone), undo
// steps only for edits, messages shown where the action happened (errors stay until
// dismissed, and are still logged), a library table that fits its panel with clickable
// Overlay boxes and a remove button, import options asked per file and kept per file, consistent fps and
// joint counts, unpin, the small ones (Tap counter, tempo placeholder), the keyboard sheet and
// first-run hint, the layout at phone and laptop sizes (touch targets, overflow, view size,
// screenshots), an axe-core accessibility check, and the start-up figures.
import { test, before, after } from "node:test";
import assert from "node:assert/strict";
import { join } from "node:path";
import { readFileSync, writeFileSync } from "node:fs";
import { chromium } from "playwright-core";
import { startServer, launch, openApp, importFiles, waitUntil, artifacts, data, root, BACKENDS } from "./harness.mjs";

let server;
before(async () => { server = await startServer(); });
after(() => server && server.stop());

const SALSA_01 = join(data, "mocap/cmu-salsa/salsa_01.bvh");
const SALSA_02 = join(data, "mocap/cmu-salsa/salsa_02.bvh");
const SALSA_16 = join(data, "mocap/cmu-salsa/salsa_16.bvh");
const ROBOT = join(data, "gltf/RobotExpressive.glb");
const ARM_BVH = `HIERARCHY
ROOT base
{
  OFFSET 0 0 0
  CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation
  JOINT arm
  {
    OFFSET 0 10 0
    CHANNELS 3 Zrotation Xrotation Yrotation
    End Site
    {
      OFFSET 0 10 0
    }
  }
}
MOTION
Frames: 3
Frame Time: 0.0333333
0 0 0 0 0 0 0 0 0
0 0 0 0 10 0 0 5 0
0 0 0 0 20 0 0 10 0
`;
const AXE = join(root, "node_modules/axe-core/axe.min.js");

const state = (page) => page.evaluate(() => ({
  playing: window.odori.player.playing,
  song: window.odori.songPlayer.playing,
  time: window.odori.player.time,
  songPos: window.odori.songPlayer.position(),
  play: document.querySelector("#play").textContent,
  songButton: document.querySelector("#song-play").textContent,
}));
const sleep = (ms) => new Promise((r) => setTimeout(r, ms));
/** The song waveform's box against the viewport: { top, bottom, height }. */
const songWave = (page) => page.evaluate(() => {
  const r = document.querySelector("#song-view").getBoundingClientRect();
  return { top: r.top, bottom: r.bottom, height: innerHeight };
});
const messagesCount = (page, re) => page.evaluate((src) => [...document.querySelectorAll("#messages li")].filter((li) => new RegExp(src).test(li.textContent)).length, re.source);

for (const backend of Object.keys(BACKENDS)) {
  test(`${backend}: one transport, undo only for edits, visible messages, library`, async (t) => {
    const { browser, page, logs } = await launch(backend);
    try {
      await openApp(page, server, backend);
      await page.waitForFunction(() => Number(document.querySelector("#dance").dataset.bars) > 8 && document.body.dataset.song === "demo", null, { timeout: 60000 });

      await t.test("at 1280×800 the whole song waveform shows under the view and the dance strip", async () => {
        // As a person first meets the page (no clip of theirs yet, whose tempo row would add
        // a line to the dance strip).
        const wave = await songWave(page);
        assert.ok(wave.top >= 0 && wave.bottom <= wave.height, `the song waveform is at ${wave.top.toFixed(0)}–${wave.bottom.toFixed(0)} px, the viewport ${wave.height} px tall`);
        assert.equal(await page.evaluate(() => document.querySelector(".stage").scrollTop), 0, "the stage was scrolled");
      });

      await t.test("Pause during Play dance pauses the music and the figure; space resumes both", async () => {
        await page.click("#dance-play");
        await page.waitForFunction(() => window.odori.songPlayer.playing, null, { timeout: 10000 });
        let s = await state(page);
        assert.equal(s.play, "Pause");
        assert.equal(s.songButton, "Pause song", "the song button shows that the song plays");
        await page.click("#play");
        s = await state(page);
        assert.equal(s.playing, false);
        assert.equal(s.song, false, "Pause left the music playing");
        await sleep(400);
        const later = await state(page);
        assert.equal(later.time, s.time, "the figure moved while paused");
        assert.equal(later.songPos, s.songPos, "the song moved while paused");
        assert.equal(later.songButton, "Play song");
        // Space on the page (nothing focused) resumes figure and song together.
        await page.evaluate(() => document.activeElement && document.activeElement.blur());
        await page.keyboard.press("Space");
        await page.waitForFunction(() => window.odori.songPlayer.playing, null, { timeout: 10000 });
        assert.equal((await state(page)).playing, true);
        // The song button stops both, not just the music.
        await page.click("#song-play");
        s = await state(page);
        assert.equal(s.song, false);
        assert.equal(s.playing, false, "the song button stopped the music but not the figure");
      });

      await t.test("space on a focused button or checkbox only presses that control", async () => {
        const before = await state(page);
        await page.focus("#song-tap");
        await page.keyboard.press("Space");
        assert.equal(await page.textContent("#song-tap"), "Tap (1)");
        assert.equal((await state(page)).playing, before.playing, "space on Tap toggled playback");
        const loop = await page.isChecked("#loop");
        await page.focus("#loop");
        await page.keyboard.press("Space");
        assert.equal(await page.isChecked("#loop"), !loop);
        assert.equal((await state(page)).playing, before.playing, "space on Loop toggled playback");
        await page.focus("#loop");
        await page.keyboard.press("Space");
        // The Tap counter goes back to plain Tap after a pause.
        await page.waitForFunction(() => document.querySelector("#song-tap").textContent === "Tap", null, { timeout: 5000 });
      });

      await t.test("undo after Generate takes back the Generate, whatever bars were looked at since", async () => {
        await page.click("#dance-generate");
        await page.waitForFunction(() => !document.querySelector("#dance").dataset.busy && window.odori.choreo.view.every((v) => v.state.kind === "generated"), null, { timeout: 60000 });
        // The info is shown where the person is looking, and logged.
        const toast = page.locator(".toast", { hasText: /filled \d+ bars/ });
        await toast.waitFor({ state: "visible", timeout: 5000 });
        assert.ok(await toast.isVisible());
        assert.ok(await messagesCount(page, /filled \d+ bars/) >= 1);
        await page.click('#dance-bars [data-bar="2"]');
        await page.click('#dance-bars [data-bar="5"]');
        await page.waitForFunction(() => document.querySelector("#dance").dataset.candidates === "6");
        await page.click("#dance-undo");
        const kinds = await page.evaluate(() => window.odori.choreo.view.map((v) => v.state.kind));
        assert.ok(kinds.every((k) => k === "empty"), `after one undo: ${kinds.join(",")}`);
        // Redo brings it back; the selected bar still shows its candidates and Search works.
        await page.click("#dance-redo");
        assert.ok(await page.evaluate(() => window.odori.choreo.view.every((v) => v.state.kind === "generated")));
        await page.click('#dance-candidates [data-k="0"]');
        await page.click("#dance-search");
        assert.equal(await page.evaluate(() => window.odori.choreo.view[5].rounds), 2);
      });

      await t.test("a pinned bar can be unpinned", async () => {
        await page.click('#dance-bars [data-bar="3"]');
        assert.equal(await page.isDisabled("#dance-unpin"), true);
        await page.click('#dance-candidates [data-k="1"]');
        await page.click("#dance-set");
        assert.equal(await page.evaluate(() => window.odori.choreo.view[3].state.kind), "pinned");
        assert.equal(await page.isDisabled("#dance-unpin"), false);
        await page.click("#dance-unpin");
        const st = await page.evaluate(() => window.odori.choreo.view[3].state);
        assert.equal(st.kind, "generated", "the bar keeps its move, unpinned");
        await page.click("#dance-undo");
        assert.equal(await page.evaluate(() => window.odori.choreo.view[3].state.kind), "pinned", "unpin is an undoable edit");
      });

      await t.test("a broken file shows an error at once that stays until dismissed", async () => {
        await importFiles(page, { name: "broken.bvh", mimeType: "text/plain", buffer: Buffer.from("HIERARCHY\nROOT hip\n{\n OFFSET 0 0 0\n CHANNELS 6 Xposition\n") });
        const toast = page.locator(".toast.error", { hasText: "broken.bvh" });
        await toast.waitFor({ state: "visible", timeout: 10000 });
        const box = await toast.boundingBox();
        const vp = page.viewportSize();
        assert.ok(box.y >= 0 && box.y + box.height <= vp.height && box.x >= 0 && box.x + box.width <= vp.width, `the error is off screen: ${JSON.stringify(box)}`);
        assert.ok(await messagesCount(page, /^broken\.bvh:\d+:\d+/) >= 1, "the error is logged too");
        await sleep(6000); // longer than any information toast lasts
        assert.ok(await toast.isVisible(), "the error went away by itself");
        await toast.getByRole("button", { name: "Dismiss" }).click();
        assert.equal(await toast.count(), 0);
      });

      await t.test("import options are asked per file at import time, apply to that file only and stay with it in the project", async () => {
        const rows = () => page.evaluate(() => Object.fromEntries([...document.querySelectorAll("#library tbody tr")].map((tr) => [tr.children[0].textContent, { fps: tr.children[2].textContent, frames: Number(tr.children[3].textContent), secs: Number(tr.children[4].textContent), id: Number(tr.dataset.id) }])));
        const dialogRows = () => page.evaluate(() => Object.fromEntries([...document.querySelectorAll("#import-options tbody tr")].map((tr) => [tr.dataset.file, { fps: tr.querySelector(".import-fps").value, units: tr.querySelector(".import-units").value }])));
        // Two BVH files at once: a row for each, each starting at its own header's rate.
        await page.setInputFiles("#file-input", [SALSA_01, SALSA_02]);
        await page.locator("#import-options").waitFor({ state: "visible", timeout: 30000 });
        assert.deepEqual(await dialogRows(), { "salsa_01.bvh": { fps: "120", units: "" }, "salsa_02.bvh": { fps: "120", units: "" } });
        // Different options for each: salsa_01 at 60 fps, salsa_02 at its own rate in stated centimetres.
        await page.fill('#import-options tr[data-file="salsa_01.bvh"] .import-fps', "60");
        await page.selectOption('#import-options tr[data-file="salsa_02.bvh"] .import-units', "0.01");
        await page.click("#import-go");
        await waitUntil(async () => { const r = await rows(); return r.salsa_01 && r.salsa_02; }, { what: "both files in the library" });
        let r = await rows();
        assert.equal(r.salsa_01.fps, "60", "salsa_01 not at the rate chosen for it");
        assert.equal(r.salsa_02.fps, "120", "salsa_02 got salsa_01's rate");
        // Each plays at its own rate: the frame shown for a time is time × the clip's fps.
        for (const [name, want] of [["salsa_01", 60], ["salsa_02", 120]]) {
          assert.ok(Math.abs(r[name].secs - (r[name].frames - 1) / want) < 0.02, `${name}: ${r[name].frames} frames in ${r[name].secs} s is not ${want} fps`);
          const shown = await page.evaluate(({ id }) => { const p = window.odori.player; p.select(id); p.pause(); p.time = 2; p.drawNow(); return Number(document.querySelector("#scrub").value); }, r[name]);
          assert.ok(Math.abs(shown - 2 * want) <= 1, `${name} at 2 s shows frame ${shown}, not ${2 * want}`);
        }
        // The next import starts from its own file again: nothing leaks from the last one.
        await page.setInputFiles("#file-input", SALSA_16);
        await page.locator("#import-options").waitFor({ state: "visible", timeout: 30000 });
        assert.deepEqual(await dialogRows(), { "salsa_16.bvh": { fps: "120", units: "" } }, "the last import's options leaked into this one");
        await page.click("#import-go");
        await waitUntil(async () => (await rows()).salsa_16, { what: "salsa_16 in the library" });
        r = await rows();
        assert.equal(r.salsa_16.fps, "120", "a later file was played at an earlier file's rate");
        for (const [name, v] of Object.entries(r)) assert.match(v.fps, /^\d+(\.\d?[1-9])?$/, `${name}: fps shown as ${v.fps}`);
        // Kept per source in the project (a reload imports each file the same way).
        const sources = await page.evaluate(() => Object.fromEntries(window.odori.project.project.doc().sources.map((s) => [s.file_name ?? s.fileName, s.options])));
        assert.equal(sources["salsa_01.bvh"].fps_override ?? null, 60);
        assert.equal(sources["salsa_01.bvh"].unit_scale ?? null, null);
        assert.equal(sources["salsa_02.bvh"].fps_override ?? null, null);
        assert.ok(Math.abs((sources["salsa_02.bvh"].unit_scale ?? 0) - 0.01) < 1e-6, `salsa_02 units: ${JSON.stringify(sources["salsa_02.bvh"])}`);
        assert.equal(sources["salsa_16.bvh"].fps_override ?? null, null);
        assert.equal(sources["salsa_16.bvh"].unit_scale ?? null, null);
        // salsa_16 has done its part: removed, so the library has the rows the later checks expect.
        await page.click('#library button.remove[aria-label="Remove salsa_16"]');
        await waitUntil(async () => !(await rows()).salsa_16, { what: "salsa_16 removed" });
        // Cancel imports nothing of the batch, and says so.
        const before = await page.evaluate(() => window.odori.library.size);
        await page.setInputFiles("#file-input", SALSA_01);
        await page.locator("#import-options").waitFor({ state: "visible", timeout: 30000 });
        await page.click("#import-cancel");
        await page.locator(".toast", { hasText: "Import cancelled" }).waitFor({ state: "visible", timeout: 10000 });
        assert.equal(await page.evaluate(() => window.odori.library.size), before);
        // A clip that is not humanoid (a two-bone arm with an end site, at 30 fps): its message
        // counts the joints the table shows, and its frame rate reads 30.
        await importFiles(page, { name: "arm.bvh", mimeType: "text/plain", buffer: Buffer.from(ARM_BVH) });
        await page.waitForFunction(() => [...document.querySelectorAll("#library tbody tr")].some((tr) => tr.children[1].textContent === "arm.bvh"), null, { timeout: 30000 });
        const arm = await page.evaluate(() => [...document.querySelectorAll("#library tbody tr")].filter((tr) => tr.children[1].textContent === "arm.bvh").map((tr) => ({ fps: tr.children[2].textContent, joints: tr.children[5].textContent, why: tr.children[6].title }))[0]);
        const m = arm.why.match(/among its (\d+) joints/);
        assert.ok(m, `humanoid message: ${arm.why}`);
        assert.equal(m[1], arm.joints, `joints ${arm.joints} vs humanoid message “${arm.why}”`);
        assert.equal(arm.fps, "30");
        // Toasts of these imports would lie over the library's rows in the next check.
        await page.evaluate(() => { for (const b of document.querySelectorAll('.toast button[aria-label="Dismiss"]')) b.click(); });
        await waitUntil(() => page.evaluate(() => !document.querySelector(".toast")), { what: "the import toasts dismissed" });
      });

      await t.test("after opening a GLB the table fits its panel, Overlay is clickable, a clip can be removed", async () => {
        await page.setInputFiles("#file-input", ROBOT);
        await page.waitForFunction(() => [...document.querySelectorAll("#library tbody tr")].some((tr) => /RobotExpressive/.test(tr.children[1].textContent)), null, { timeout: 30000 });
        const fit = await page.evaluate(() => {
          const side = document.querySelector("#library-panel");
          const table = document.querySelector("#library");
          return { table: table.getBoundingClientRect().right, panel: side.getBoundingClientRect().right, scroll: table.scrollWidth, width: table.clientWidth };
        });
        assert.ok(fit.table <= fit.panel + 0.5 && fit.scroll <= fit.width + 1, `table wider than its panel: ${JSON.stringify(fit)}`);
        const rows = page.locator("#library tbody tr", { hasText: "RobotExpressive" });
        const n = await rows.count();
        assert.ok(n > 3);
        const box = rows.nth(2).locator("input[type=checkbox]");
        await box.scrollIntoViewIfNeeded();
        const hit = await box.evaluate((el) => { const r = el.getBoundingClientRect(); const top = document.elementFromPoint(r.x + r.width / 2, r.y + r.height / 2); return top === el ? true : `${top ? top.outerHTML.slice(0, 160) : "nothing"} at ${JSON.stringify(r)}`; });
        assert.equal(hit, true, `the Overlay box is covered or cut off: ${hit}`);
        await box.click();
        const id = Number(await rows.nth(2).getAttribute("data-id"));
        assert.ok((await page.evaluate(() => window.odori.player.overlays)).includes(id));
        // Remove it: gone from the table and the library, the overlay with it.
        const size = await page.evaluate(() => window.odori.library.clips().length);
        await rows.nth(2).getByRole("button", { name: /^Remove / }).click();
        assert.equal(await page.evaluate(() => window.odori.library.clips().length), size - 1);
        assert.equal(await page.locator(`#library tbody tr[data-id="${id}"]`).count(), 0);
        assert.ok(!(await page.evaluate(() => window.odori.player.overlays)).includes(id));
        // Removing the selected clip selects a neighbour and the view keeps drawing.
        const sel = await page.evaluate(() => window.odori.player.clip);
        await page.locator(`#library tbody tr[data-id="${sel}"]`).getByRole("button", { name: /^Remove / }).click();
        const next = await page.evaluate(() => window.odori.player.clip);
        assert.ok(next != null && next !== sel);
      });

      await t.test("the clip tempo placeholder is not cut off", async () => {
        await page.waitForSelector("#dance-clip-row:not([hidden])");
        const m = await page.evaluate(() => {
          const el = document.querySelector("#dance-clip-bpm");
          const cs = getComputedStyle(el);
          const g = document.createElement("canvas").getContext("2d");
          g.font = `${cs.fontSize} ${cs.fontFamily}`;
          return { text: el.placeholder, need: g.measureText(el.placeholder).width, have: el.clientWidth - parseFloat(cs.paddingLeft) - parseFloat(cs.paddingRight) };
        });
        assert.ok(m.need <= m.have, `placeholder “${m.text}” needs ${m.need.toFixed(0)} px, has ${m.have.toFixed(0)}`);
      });

      await t.test("? opens the keyboard sheet, which explains τ and ρ", async () => {
        await page.evaluate(() => document.activeElement && document.activeElement.blur());
        await page.keyboard.press("?");
        const dlg = page.locator("dialog#keys");
        assert.ok(await dlg.evaluate((d) => d.open));
        assert.match(await dlg.textContent(), /Variety τ.*Music fit ρ/s);
        await page.keyboard.press("Escape");
        assert.ok(!(await dlg.evaluate((d) => d.open)));
      });

      const errors = logs.filter((l) => l.startsWith("[pageerror]"));
      assert.deepEqual(errors, [], "page errors");
    } catch (e) {
      await page.screenshot({ path: join(artifacts, `usable-${backend}-failure.png`) }).catch(() => {});
      console.log(logs.join("\n"));
      throw e;
    } finally {
      await browser.close();
    }
  });
}

/** Every visible control: tag, label, size, and whether a tap at its centre reaches it. */
function controlsReport() {
  const out = [];
  // Closed sections open with a tap on their summary: look inside them too.
  for (const d of document.querySelectorAll("details")) d.open = true;
  for (const el of document.querySelectorAll("button, select, textarea, input, summary, label.button")) {
    if (el.closest("[hidden], dialog:not([open])") || (el.matches("input") && el.hidden)) continue;
    const cs = getComputedStyle(el);
    if (cs.display === "none" || cs.visibility === "hidden") continue;
    el.scrollIntoView({ block: "center", inline: "center" });
    const r = el.getBoundingClientRect();
    if (r.width === 0 && r.height === 0) continue;
    const at = document.elementFromPoint(r.x + r.width / 2, r.y + r.height / 2);
    // A tap reaches the control itself, something inside it, or the label that wraps it.
    const reach = at != null && (at === el || el.contains(at) || (at.closest("label") && at.closest("label").contains(el)) || (el.closest("label") && el.closest("label") === at.closest("label")));
    out.push({ what: `${el.tagName.toLowerCase()}#${el.id || ""}${el.type ? `[${el.type}]` : ""} ${(el.getAttribute("aria-label") || el.textContent || "").trim().slice(0, 24)}`, height: r.height, reach });
  }
  return out;
}

for (const [name, size, mobile] of [["phone", { width: 390, height: 844 }, true], ["laptop", { width: 1280, height: 800 }, false]]) {
  test(`layout at ${size.width}×${size.height} on touch (${name}): reachable 32 px controls, no overflow, view ≥ 40 %, axe`, async () => {
    const browser = await chromium.launch({ executablePath: "/usr/bin/chromium", args: ["--headless", "--no-sandbox", "--disable-background-networking", "--disable-component-update", "--disable-sync", "--no-first-run", "--disable-dev-shm-usage"], headless: true });
    try {
      const ctx = await browser.newContext({ viewport: size, hasTouch: true, isMobile: mobile });
      const page = await ctx.newPage();
      const logs = [];
      page.on("pageerror", (e) => logs.push(e.message));
      await openApp(page, server, "webgl2");
      await page.waitForFunction(() => Number(document.querySelector("#dance").dataset.bars) > 8, null, { timeout: 60000 });
      assert.ok(await page.evaluate(() => matchMedia("(pointer: coarse)").matches), "touch emulation: pointer is not coarse");
      // The first-run hint greets a new person.
      assert.ok(await page.isVisible("#hint"), "no first-run hint");
      await page.screenshot({ path: join(artifacts, `usable-${name}-first-run.png`) });
      await page.click("#hint-close");
      await page.click('#dance-bars [data-bar="1"]');
      await page.waitForFunction(() => document.querySelector("#dance").dataset.candidates === "6");

      const fig = await page.evaluate(() => {
        const v = document.querySelector("#view").getBoundingClientRect();
        return { view: (v.width * v.height) / (innerWidth * innerHeight), scroll: document.scrollingElement.scrollWidth, width: innerWidth };
      });
      assert.ok(fig.scroll <= fig.width, `horizontal overflow: ${fig.scroll} > ${fig.width}`);
      assert.ok(fig.view >= 0.4, `the 3D view is ${(fig.view * 100).toFixed(0)} % of the viewport`);
      if (!mobile) {
        // On a laptop screen the song waveform starts within the screen without scrolling, under
        // the view and the dance strip (with a bar's candidates shown, as now), even with the
        // taller touch controls (with a mouse all of it shows: the transport test checks that).
        const wave = await songWave(page);
        assert.ok(wave.top >= 0 && wave.top + 16 <= wave.height, `the song waveform is at ${wave.top.toFixed(0)}–${wave.bottom.toFixed(0)} px, the viewport ${wave.height} px tall`);
        // Toasts, as many as are ever shown (errors stay), with long texts, cover none of the
        // side panels' search timeline: each toast's box is clear of the timeline's.
        await page.evaluate(() => {
          const m = window.odori.messages;
          for (let i = 0; i < 3; i++) m.error(`broken-${i}.bvh:5:23: expected a channel name (Xposition, Yposition, Zposition, Xrotation, Yrotation or Zrotation), found the end of the file`);
          m.info("Generate filled 34 bars in 0.4 s (join jump worst 1.2× the moves' own, goal 1.5×)");
        });
        const boxes = await page.evaluate(() => {
          const box = (el) => { const r = el.getBoundingClientRect(); return { x: r.x, y: r.y, w: r.width, h: r.height }; };
          return { timeline: box(document.querySelector("#search-timeline")), view: box(document.querySelector("#view")), toasts: [...document.querySelectorAll(".toast")].map(box) };
        });
        assert.equal(boxes.toasts.length, 4);
        const overlaps = (a, b) => a.x < b.x + b.w && b.x < a.x + a.w && a.y < b.y + b.h && b.y < a.y + a.h;
        assert.ok(boxes.timeline.w > 0 && boxes.timeline.h > 0, "the search timeline is not shown beside the view");
        assert.deepEqual(boxes.toasts.filter((t) => overlaps(t, boxes.timeline)), [], `toasts over the search timeline ${JSON.stringify(boxes.timeline)}`);
        // Where they are instead: over the view (not the strips under it nor the top bar).
        const inside = (a, b) => a.x >= b.x && a.y >= b.y && a.x + a.w <= b.x + b.w && a.y + a.h <= b.y + b.h;
        assert.deepEqual(boxes.toasts.filter((t) => !inside(t, boxes.view)), [], `toasts outside the view ${JSON.stringify(boxes.view)}`);
        await page.screenshot({ path: join(artifacts, `usable-${name}-toasts.png`) });
        await page.evaluate(() => { for (const b of document.querySelectorAll('.toast button[aria-label="Dismiss"]')) b.click(); });
      }
      await page.screenshot({ path: join(artifacts, `usable-${name}.png`) });

      // Every control in every panel (tabs on a phone) is reachable and at least 32 px tall.
      const tabs = await page.locator(".tabs [role=tab]").all();
      const panels = (await tabs[0].isVisible()) ? tabs : [null];
      let all = [];
      for (const tab of panels) {
        if (tab) await tab.click();
        // Every 2D canvas shown (timelines, plots) is drawn at its own size once its panel shows,
        // not left at the size it had while hidden (the search timeline was, on a phone).
        await waitUntil(() => page.evaluate(() => [...document.querySelectorAll("#search-timeline, #song canvas")].every((c) => {
          if (c.clientWidth === 0) return true;
          const dpr = Math.min(devicePixelRatio || 1, 2);
          return [Math.round(c.clientWidth), Math.round(c.clientWidth * dpr)].includes(c.width);
        })), { what: `${name}: every shown canvas drawn at its own width` });
        all = all.concat(await page.evaluate(controlsReport));
        if (tab) await page.screenshot({ path: join(artifacts, `usable-${name}-${(await tab.textContent()).toLowerCase()}.png`), fullPage: true });
      }
      const small = all.filter((c) => c.height < 32);
      const unreachable = all.filter((c) => !c.reach);
      console.log(`# ${name}: ${all.length} controls, ${small.length} under 32 px, ${unreachable.length} unreachable; view ${(fig.view * 100).toFixed(0)} % of the viewport`);
      assert.deepEqual(small.map((c) => `${c.what} ${c.height.toFixed(0)}px`), []);
      assert.deepEqual(unreachable.map((c) => c.what), []);
      // Bars at the end of the song are reachable too.
      const last = page.locator("#dance-bars [data-bar]").last();
      await last.click();
      assert.equal(await page.evaluate(() => window.odori.choreo.bar), (await page.locator("#dance-bars [data-bar]").count()) - 1);

      // Accessibility: axe-core in the page, no serious or critical violations.
      // Evaluated through the test driver, not added as a <script>: the page's Content-Security-
      // Policy (script-src 'self') rightly refuses inline scripts, and the check must run under it.
      await page.evaluate(readFileSync(AXE, "utf8"));
      const axe = await page.evaluate(async () => {
        const r = await window.axe.run(document, { resultTypes: ["violations"] });
        return r.violations.map((v) => ({ id: v.id, impact: v.impact, nodes: v.nodes.length, help: v.help, targets: v.nodes.slice(0, 3).map((n) => n.target.join(" ")) }));
      });
      for (const v of axe) console.log(`# axe ${name}: ${v.impact} ${v.id} (${v.nodes}): ${v.help} ${v.targets.join(" | ")}`);
      const bad = axe.filter((v) => v.impact === "serious" || v.impact === "critical");
      assert.deepEqual(bad, [], "serious or critical accessibility violations");
      assert.deepEqual(logs, []);
    } finally {
      await browser.close();
    }
  });
}

for (const backend of Object.keys(BACKENDS)) {
  test(`${backend}: start-up figures (navigation → first drawn pose, longest main-thread task before it)`, async () => {
    const { browser, page } = await launch(backend);
    try {
      // Long tasks from the very start of the page, before any of its scripts.
      await page.addInitScript(() => {
        window.__longTasks = [];
        new PerformanceObserver((list) => { for (const e of list.getEntries()) window.__longTasks.push({ start: e.startTime, ms: e.duration }); }).observe({ type: "longtask", buffered: true });
        // Whether the start-up indicator shows as soon as the page is parsed (before the engine).
        document.addEventListener("DOMContentLoaded", () => {
          const s = document.querySelector("#startup");
          window.__startupShown = !!s && !window.odoriTimings && getComputedStyle(s).display !== "none";
        });
      });
      await page.goto(server.url + BACKENDS[backend].query, { waitUntil: "domcontentloaded" });
      await page.waitForFunction(() => window.odoriTimings, null, { timeout: 60000 });
      await page.waitForFunction(() => document.body.dataset.ready === "1", null, { timeout: 60000 });
      const shown = await page.evaluate(() => window.__startupShown);
      const f = await page.evaluate(() => {
        const pose = window.odoriTimings.firstPoseSinceNavigationMs;
        const before = window.__longTasks.filter((t) => t.start < pose);
        const after = window.__longTasks.filter((t) => t.start >= pose);
        const marks = Object.fromEntries(performance.getEntriesByType("mark").filter((m) => m.name.startsWith("odori:")).map((m) => [m.name.slice(6), Math.round(m.startTime)]));
        return { pose, longestBefore: Math.max(0, ...before.map((t) => t.ms)), longBefore: before.length, longestAfter: Math.max(0, ...after.map((t) => t.ms)), ready: performance.now(), marks, tasks: before.map((t) => [Math.round(t.start), Math.round(t.ms)]) };
      });
      console.log(`# start-up ${backend}: first drawn pose ${f.pose.toFixed(0)} ms after navigation (goal < 1000); longest main-thread task before it ${f.longestBefore.toFixed(0)} ms (goal ≤ 200; ${f.longBefore} tasks over 50 ms); longest task after it until the panels were ready ${f.longestAfter.toFixed(0)} ms`);
      console.log(`# start-up ${backend}: marks (ms since navigation) ${JSON.stringify(f.marks)}; long tasks before the pose [start, ms] ${JSON.stringify(f.tasks)}`);
      writeFileSync(join(artifacts, `usable-${backend}-startup.json`), JSON.stringify(f, null, 2));
      assert.ok(shown, "no start-up indicator while the engine loads");
      assert.ok(await page.evaluate(() => getComputedStyle(document.querySelector("#startup")).display === "none"), "the start-up indicator stayed");
      assert.ok(Number.isFinite(f.pose) && f.pose > 0);
      // The goals of issue 13 (first pose < 1000 ms, no task over 200 ms before it) are wall
      // times: printed above, not asserted, since the test run has another test file and the
      // fuzz run beside this one. `node tests/browser/startup-trace.mjs webgl2 webgpu` measures
      // them alone (with each task's CPU time).
    } finally {
      await browser.close();
    }
  });
}
