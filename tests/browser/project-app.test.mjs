// The app keeps what a person made (issue #10, the acceptance on the real app page, both back
// ends): import a BVH and a GLB from ../shared/data, open a song, correct the grid, pin 3 bars,
// Search twice, Generate, tag a clip, animate a text → reload → everything is back (the dance's
// joint positions equal at 5 times, the grid equal, the bars' states and keys equal, the tags,
// the text table, the library; the Project's undo history back; the chosen character and the
// clips put on it — a project clip and the composed dance — with the same joint positions).
// Then the project's `.odori`
// bytes (what Save as writes) are dropped on the app in a fresh browser profile → identical;
// New project gives an empty one, and Recent brings the opened one back, identical.
//
// Everything goes through the page's own controls; `window.odori` is only read from.
import { test, before, after } from "node:test";
import assert from "node:assert/strict";
import { join } from "node:path";
import { startServer, launch, data, BACKENDS, importFiles } from "./harness.mjs";

let server;
before(async () => { server = await startServer(); });
after(() => server && server.stop());

const SONG = "music/Kevin_MacLeod_-_Vibe_Ace.hq.ogg";

/** Opens the app and waits until the project is rebuilt (or the demo song made). */
async function openProjectApp(page, backend) {
  await page.goto(server.url + BACKENDS[backend].query);
  await waitReady(page);
}

async function waitReady(page) {
  await page.waitForFunction(() => document.body.dataset.ready && document.body.dataset.project === "ready", null, { timeout: 120000 });
  const ready = await page.evaluate(() => document.body.dataset.ready);
  if (ready !== "1") throw new Error(`the app did not start: ${await page.textContent("#messages")}`);
}

/** What must come back, read from the page. */
async function snapshot(page) {
  return page.evaluate(() => {
    const o = window.odori;
    o.choreo.renderDance();
    const id = o.choreo.danceId;
    const view = o.choreo.view;
    const end = view[view.length - 1].bar.endSecs;
    const poses = [0.1, 0.3, 0.5, 0.7, 0.9].map((k) => Array.from(o.library.jointPositions(id, end * k)));
    const doc = o.project.project.doc();
    return {
      poses,
      grid: Array.from(o.song.grid.beatTimesSecs),
      bpm: o.song.grid.bpm,
      song: o.song.name,
      states: view.map((v) => v.state.kind),
      keys: doc.dance.bars.map((b) => [b.state, b.move]),
      sources: doc.sources.map((s) => [s.fileName, s.blob, s.options]),
      corrections: doc.song.corrections,
      tags: doc.tags,
      texts: doc.texts,
      textRows: [...document.querySelectorAll("#text-table tbody tr select")].map((s) => s.selectedOptions[0].textContent),
      // The imported clips (made clips — previews, the dance, the text animation — are rebuilt
      // in another order).
      library: (() => {
        const names = new Set(o.project.project.clips().map((c) => c.name));
        return [...document.querySelectorAll("#library tbody tr")].map((tr) => tr.children[0].textContent).filter((n) => names.has(n));
      })(),
      canUndo: o.project.project.canUndo(),
      character: doc.character,
      characterShown: document.querySelector("#character").selectedOptions[0]?.textContent,
      worn: doc.worn,
      // The put-on clips as the library holds them (rebuilt from the project after a reload).
      wornClips: o.project.shown.worn.map((w) => {
        const c = w.id == null ? null : o.library.clip(w.id);
        return c && { name: c.name, format: c.format, hasMesh: c.hasMesh, frames: c.frames, poses: [0.2, 0.5, 0.8].map((k) => Array.from(o.library.jointPositions(w.id, c.durationSecs * k))) };
      }),
      messages: [...document.querySelectorAll("#messages li.error")].map((li) => li.textContent),
    };
  });
}

/** The Project's document after one undo (then redone): the history came back too. */
async function undoProbe(page) {
  return page.evaluate(() => {
    const p = window.odori.project.project;
    p.undo();
    const d = JSON.stringify(p.doc());
    p.redo();
    return d;
  });
}

function assertSame(a, b, what) {
  assert.deepEqual(b.states, a.states, `${what}: bar states`);
  assert.deepEqual(b.keys, a.keys, `${what}: the dance by keys`);
  assert.deepEqual(b.grid, a.grid, `${what}: the grid`);
  assert.equal(b.song, a.song);
  assert.deepEqual(b.sources, a.sources, `${what}: the sources`);
  assert.deepEqual(b.corrections, a.corrections);
  assert.deepEqual(b.tags, a.tags);
  assert.deepEqual(b.texts, a.texts);
  assert.deepEqual(b.textRows, a.textRows, `${what}: the text table`);
  assert.deepEqual(b.library, a.library, `${what}: the library`);
  assert.deepEqual(b.character, a.character, `${what}: the chosen character`);
  assert.equal(b.characterShown, a.characterShown, `${what}: the character shown as chosen`);
  assert.deepEqual(b.worn, a.worn, `${what}: the put-on clips in the project`);
  assert.equal(b.wornClips.length, a.wornClips.length, `${what}: the put-on clips in the library`);
  a.wornClips.forEach((w, i) => {
    const x = b.wornClips[i];
    assert.ok(x, `${what}: put-on clip ${i + 1} is in the library`);
    assert.deepEqual([x.name, x.format, x.hasMesh, x.frames], [w.name, w.format, w.hasMesh, w.frames], `${what}: put-on clip ${i + 1}`);
    for (let k = 0; k < 3; k++) {
      const d = Math.max(...w.poses[k].map((v, j) => Math.abs(v - x.poses[k][j])));
      assert.ok(d < 1e-5, `${what}: put-on clip ${i + 1}'s joint positions at time ${k + 1} of 3 differ by ${d} m`);
    }
  });
  assert.equal(b.poses.length, 5);
  for (let k = 0; k < 5; k++) {
    const d = Math.max(...a.poses[k].map((v, i) => Math.abs(v - b.poses[k][i])));
    assert.ok(d < 1e-5, `${what}: dance joint positions at time ${k + 1} of 5 differ by ${d} m`);
  }
}

for (const backend of (process.env.BACKENDS || "webgl2,webgpu").split(",")) {
  test(`the app keeps the work (${backend}): reload, and an .odori in a fresh profile`, async () => {
    const { browser, page, logs } = await launch(backend);
    let fresh;
    try {
      await openProjectApp(page, backend);
      // Motion: a BVH (at 60 fps, as the CMU salsa files are) and a GLB.
      await importFiles(page, join(data, "mocap/cmu-salsa/salsa_10.bvh"), { "salsa_10.bvh": { fps: 60 } });
      await page.waitForFunction(() => [...document.querySelectorAll("#messages li")].some((li) => /salsa_10.*dance segments/.test(li.textContent)), null, { timeout: 60000 });
      await page.setInputFiles("#file-input", join(data, "gltf/RobotExpressive.glb"));
      await page.waitForFunction(() => [...document.querySelectorAll("#messages li")].some((li) => /RobotExpressive.glb: \d+ clips? added/.test(li.textContent)), null, { timeout: 60000 });
      // A song, and a grid correction (a nudge later).
      await page.setInputFiles("#song-input", join(data, SONG));
      await page.waitForFunction((n) => document.body.dataset.song === n, SONG.split("/").pop(), { timeout: 120000 });
      await page.waitForFunction(() => Number(document.querySelector("#dance").dataset.bars) > 8, null, { timeout: 60000 });
      await page.click("#song-later");
      // Pin 3 bars (2, 4, 6), each with a candidate.
      for (const [bar, k] of [[1, 0], [3, 2], [5, 4]]) {
        await page.click(`#dance-bars [data-bar="${bar}"]`);
        await page.waitForFunction(() => document.querySelector("#dance").dataset.candidates === "6");
        await page.click(`#dance-candidates [data-k="${k}"]`);
        await page.click("#dance-set");
      }
      // Search twice on bar 1, liking one candidate each round.
      await page.click('#dance-bars [data-bar="0"]');
      await page.waitForFunction(() => document.querySelector("#dance").dataset.candidates === "6");
      for (let round = 0; round < 2; round++) {
        await page.click('#dance-candidates [data-k="0"]');
        await page.click("#dance-search");
      }
      // Generate: every bar filled.
      await page.click("#dance-generate");
      await page.waitForFunction(() => !document.querySelector("#dance").dataset.busy && window.odori.choreo.view.every((v) => v.state.kind !== "empty"), null, { timeout: 60000 });
      // Tag the salsa clip, animate a text that calls it.
      await page.evaluate(() => {
        const row = [...document.querySelectorAll("#library tbody tr")].find((tr) => tr.textContent.includes("salsa_10"));
        row.children[0].click();
      });
      await page.fill("#text-tags", "salsa, サルサ");
      await page.click("#text-tag");
      await page.fill("#text-input", "サルサして、喜ぶ。");
      await page.click("#text-go");
      await page.waitForFunction(() => document.querySelectorAll("#text-table tbody tr").length === 2);
      // Choose the robot as the character; put the salsa clip on it, then the composed dance.
      await page.focus("#character"); // the list is filled when it is opened
      await page.selectOption("#character", { label: "RobotExpressive.glb" });
      const putOn = async (n) => {
        await page.click("#put-on");
        await page.waitForFunction((k) => [...document.querySelectorAll("#messages li")].filter((li) => /ready \(drawn on the character/.test(li.textContent)).length === k, n, { timeout: 60000 });
      };
      await page.evaluate(() => {
        const row = [...document.querySelectorAll("#library tbody tr")].find((tr) => tr.textContent.includes("salsa_10"));
        row.children[0].click();
      });
      await putOn(1);
      await page.evaluate(() => { window.odori.choreo.renderDance(); window.odori.panel.select(window.odori.choreo.danceId); });
      await putOn(2);
      // The autosave (debounced) has written it all.
      await page.evaluate(() => window.odori.project.store.flush());
      const made = await snapshot(page);
      assert.equal(made.characterShown, "RobotExpressive.glb");
      assert.ok(made.character && made.character.clip === 0, `the character is in the project: ${JSON.stringify(made.character)}`);
      assert.deepEqual(made.worn.map((w) => w.motion.kind), ["clip", "motion"], "a project clip and the dance (kept as a BVH) are put on");
      assert.ok(made.wornClips.every((w) => w && w.hasMesh && w.format === "character"), `put-on clips drawn with the robot's mesh: ${JSON.stringify(made.wornClips.map((w) => w && w.name))}`);
      assert.deepEqual(made.messages, [], "no error while composing");
      assert.equal(made.keys.filter(([s]) => s === "pinned").length, 3, "3 pinned bars in the project");
      assert.ok(made.keys.every(([s, m]) => s !== "empty" && m), "every bar of the project's dance has a move");
      assert.ok(made.keys.some(([, m]) => m.kind === "cut") || made.keys.some(([, m]) => m.kind === "builtin"));
      assert.deepEqual(made.sources.map((s) => s[0]), ["salsa_10.bvh", "RobotExpressive.glb"]);
      assert.equal(made.sources[0][2].fps_override, 60);
      assert.equal(made.corrections.length, 1, "the grid correction is in the project");
      assert.deepEqual(made.texts, ["サルサして、喜ぶ。"]);
      assert.equal(made.textRows[0], "salsa_10");
      assert.ok(made.library.includes("salsa_10") && made.library.length >= 2, `imported clips in the library: ${made.library}`);
      assert.ok(made.canUndo);
      const undoneBefore = await undoProbe(page);
      const cost = await page.evaluate(() => { const s = window.odori.project.store.stats; return { ms: s.mainThreadMs.slice().sort((a, b) => a - b), writes: s.writes, bytes: s.lastManifestBytes }; });

      // Reload: everything is back.
      await page.reload();
      await waitReady(page);
      const back = await snapshot(page);
      assertSame(made, back, "after a reload");
      const restoreMs = await page.evaluate(() => performance.getEntriesByName("odori:project-ready")[0].startTime);
      console.log(`${backend}: autosave main-thread cost per write in the app: median ${cost.ms[cost.ms.length >> 1].toFixed(2)} ms, max ${cost.ms[cost.ms.length - 1].toFixed(2)} ms over ${cost.writes} writes (manifest ${cost.bytes} bytes); reload → project rebuilt in ${restoreMs.toFixed(0)} ms`);
      assert.deepEqual(back.messages, [], "no error while restoring");
      assert.ok(back.canUndo, "the project's history is back");
      assert.equal(await undoProbe(page), undoneBefore, "undo gives the same project as before the reload");

      // Save as: the .odori bytes; dropped on the app in a fresh profile → identical.
      const b64 = await page.evaluate(() => {
        const bytes = window.odori.project.project.save();
        let s = "";
        for (let i = 0; i < bytes.length; i += 0x8000) s += String.fromCharCode(...bytes.subarray(i, i + 0x8000));
        return btoa(s);
      });
      fresh = await launch(backend);
      await openProjectApp(fresh.page, backend);
      await Promise.all([
        fresh.page.waitForNavigation({ timeout: 60000 }),
        fresh.page.evaluate((b) => {
          const bytes = Uint8Array.from(atob(b), (c) => c.charCodeAt(0));
          const dt = new DataTransfer();
          dt.items.add(new File([bytes], "made in the test.odori"));
          document.body.dispatchEvent(new DragEvent("drop", { dataTransfer: dt, bubbles: true, cancelable: true }));
        }, b64),
      ]);
      await waitReady(fresh.page);
      const opened = await snapshot(fresh.page);
      assertSame(made, opened, "opened in a fresh profile");
      // New project: an empty one (the demo song only); the opened one stays in Recent and
      // comes back from there.
      const openedId = await fresh.page.evaluate(() => window.odori.project.store.projectId);
      await Promise.all([fresh.page.waitForNavigation({ timeout: 60000 }), fresh.page.click("#project-new")]);
      await waitReady(fresh.page);
      const empty = await fresh.page.evaluate(() => ({ doc: window.odori.project.project.doc(), recent: [...document.querySelectorAll("#project-recent option")].map((o) => o.value) }));
      assert.deepEqual(empty.doc.sources, [], "a new project has no files");
      assert.ok(empty.doc.dance.bars.every((b) => b.state === "empty"), "a new project has no dance");
      assert.ok(empty.recent.includes(openedId), `the opened project is in Recent: ${empty.recent}`);
      await Promise.all([fresh.page.waitForNavigation({ timeout: 60000 }), fresh.page.selectOption("#project-recent", openedId)]);
      await waitReady(fresh.page);
      assertSame(made, await snapshot(fresh.page), "picked from Recent");
      console.log(`${backend}: .odori ${(b64.length * 3 / 4 / 1024).toFixed(0)} KiB; ${made.states.length} bars, ${made.library.length} library clips restored`);
    } catch (e) {
      console.log(logs.slice(-40).join("\n"));
      if (fresh) console.log(fresh.logs.slice(-40).join("\n"));
      throw e;
    } finally {
      await browser.close();
      if (fresh) await fresh.browser.close();
    }
  });
}
