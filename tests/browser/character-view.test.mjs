// The chosen character in the viewer, in headless Chromium on WebGL2 and WebGPU:
// - a textured character (the Fox, ../shared/data/gltf/Fox.glb, whose base-colour texture is
//   mostly orange fur) is drawn with its texture, not white;
// - end to end: compose (Generate) → choose a character (Xbot) → the skinned figure plays the
//   dance on the song clock (figure time vs song time, polled) → the candidates and a text
//   animation are drawn on it too, the stick figure one click away → Export GLB (a real
//   download) → the file re-opens in the app and plays the same (joint positions by name).
// Screenshots go to tests/artifacts/.
import { test, before, after } from "node:test";
import assert from "node:assert/strict";
import { join } from "node:path";
import { readFileSync } from "node:fs";
import { startServer, launch, openApp, canvasPixels, countNear, countAll, isOrange, isWarmFigure, isBackground, waitUntil, data, artifacts } from "./harness.mjs";

let server;
before(async () => { server = await startServer(); });
after(() => server && server.stop());

/** Projected joints of `joints` (flat xyz) that land inside the canvas. */
async function projected(page, joints) {
  return page.evaluate((p) => {
    const out = [];
    for (let i = 0; i < p.length; i += 3) out.push(window.odori.viewer.project(p[i], p[i + 1], p[i + 2]));
    return out.filter(Boolean);
  }, joints);
}

/**
 * Draws the player's figures (paused at `time`, when given) until the viewer has made every
 * clip it leaves for between frames (`bodiesPending`: a long clip on the body, such as the
 * dance or a text animation, is not retargeted inside a draw); returns how they were drawn.
 */
async function settledDraw(page, time) {
  await waitUntil(() => page.evaluate((t) => {
    const { player, viewer } = window.odori;
    player.pause();
    if (t != null) player.time = t;
    player.drawNow();
    return viewer.bodiesPending === 0;
  }, time), { what: "the figures made on the chosen body" });
  return page.evaluate(() => window.odori.viewer.lastDrawn());
}

function coverage(img, pts, pred, r = 3) {
  const inside = pts.filter(([x, y]) => x > r && y > r && x < img.width - r && y < img.height - r);
  return { inside: inside.length, hit: inside.filter(([x, y]) => countNear(img, x, y, r, pred) > 0).length };
}

for (const backend of ["webgl2", "webgpu"]) {
  test(`a fresh page opens on the built-in body on ${backend}; stick figures are a choice it keeps`, async () => {
    const { browser, page, logs } = await launch(backend);
    try {
      await openApp(page, server, backend);
      await page.waitForFunction(() => document.body.dataset.project === "ready", null, { timeout: 90000 });
      assert.equal(await page.evaluate(() => document.querySelector("#character").value), "builtin", "the Character menu shows the built-in body");
      assert.equal(await page.evaluate(() => window.odori.viewer.character), "builtin");
      // The demo clip, paused, on the body: the skin covers its joints, and it fills far more
      // of the canvas than the same pose as a stick figure.
      const drawn = await settledDraw(page, 0.5);
      assert.deepEqual(drawn.map((d) => d.body), ["builtin"], "the first figure is drawn on the built-in body");
      const fig = await page.evaluate(() => { const { viewer, library, player } = window.odori; return viewer.figureJoints(library, player.clip, 0.5); });
      assert.equal(fig.body, "builtin");
      const body = await canvasPixels(page, `${backend}-fresh-builtin-body.png`);
      const cov = coverage(body, await projected(page, fig.positions), (c) => !isBackground(c));
      assert.ok(cov.inside > 10 && cov.hit >= cov.inside * 0.8, `the body drawn at ${cov.hit} of ${cov.inside} projected joints`);
      await page.check("#stick-figure");
      assert.equal(await page.evaluate(() => window.odori.viewer.lastDrawn()[0].body), "stick", "stick figures are one click away");
      const sticks = await canvasPixels(page, `${backend}-fresh-stick.png`);
      // Figure pixels (warm: the clay body, the orange sticks; not the grey floor's lines).
      const [bodyPx, stickPx] = [countAll(body, isWarmFigure), countAll(sticks, isWarmFigure)];
      console.log(`${backend}: fresh page: the built-in body covers ${bodyPx} px, the same pose as sticks ${stickPx} px`);
      assert.ok(bodyPx > 2 * stickPx, `the body (${bodyPx} px) is drawn, not a stick figure (${stickPx} px)`);
      await page.uncheck("#stick-figure");
      // Stick figures chosen in the menu are the project's choice: kept across a reload.
      await page.selectOption("#character", "");
      assert.equal(await page.evaluate(() => window.odori.viewer.character), null);
      assert.equal(await page.evaluate(() => window.odori.project.project.doc().stickFigures), true, "the project keeps stick figures");
      await page.evaluate(() => window.odori.project.store.flush()); // the autosave, written
      await page.reload();
      await page.waitForFunction(() => document.body.dataset.ready === "1" && document.body.dataset.project === "ready", null, { timeout: 90000 });
      const after = await settledDraw(page, 0.5);
      assert.deepEqual(after.map((d) => d.body), ["stick"], "after a reload: stick figures, as chosen");
      assert.equal(await page.evaluate(() => document.querySelector("#character").value), "");
      // And the built-in body chosen again is kept as the project's default (no stick figures).
      await page.selectOption("#character", "builtin");
      assert.equal(await page.evaluate(() => window.odori.project.project.doc().stickFigures ?? false), false);
      await page.evaluate(() => window.odori.project.store.flush());
      await page.reload();
      await page.waitForFunction(() => document.body.dataset.ready === "1" && document.body.dataset.project === "ready", null, { timeout: 90000 });
      assert.deepEqual((await settledDraw(page, 0.5)).map((d) => d.body), ["builtin"], "after a reload: the built-in body");
      assert.ok(!logs.some((l) => l.startsWith("[pageerror]")), logs.join("\n"));
    } finally {
      await browser.close();
    }
  });

  test(`textured character on ${backend}: the Fox is drawn with its base-colour texture`, async () => {
    const { browser, page, logs } = await launch(backend);
    try {
      await openApp(page, server, backend);
      const n = await page.evaluate(() => window.odori.library.size);
      await page.setInputFiles("#file-input", join(data, "gltf/Fox.glb"));
      await page.waitForFunction((n) => window.odori.library.size > n, n, { timeout: 60000 });
      const fox = await page.evaluate(() => window.odori.player.clip);
      // The image is decoded by the browser off the main thread; it shows from the next draw.
      await waitUntil(() => page.evaluate(() => { const { player, viewer } = window.odori; player.pause(); player.time = 0.5; player.drawNow(); return viewer.texturesLoading === 0; }), { what: "the Fox's texture decoded" });
      const { joints, drawn } = await page.evaluate(() => {
        const { player, viewer, library } = window.odori;
        player.drawNow();
        return { joints: [...library.jointPositions(player.clip, 0.5)], drawn: viewer.lastDrawn() };
      });
      assert.deepEqual(drawn.map((d) => [d.clip, d.body]), [[fox, "own"]], "the Fox is drawn with its own mesh");
      const img = await canvasPixels(page, `${backend}-character-fox-textured.png`);
      const pts = await projected(page, joints);
      // Fur is orange in the texture; the material's factor is white, so untextured it is grey.
      const orange = coverage(img, pts, isOrange, 4);
      const body = coverage(img, pts, (c) => !isBackground(c), 4);
      assert.ok(body.inside > 10 && body.hit >= body.inside * 0.7, `the Fox is drawn at ${body.hit} of ${body.inside} joints`);
      assert.ok(orange.hit >= body.inside * 0.5, `orange fur near ${orange.hit} of ${body.inside} joints (a white Fox has none)`);
      assert.ok(!logs.some((l) => l.startsWith("[pageerror]") || /texture .* could not be decoded/.test(l)), logs.join("\n"));
    } finally {
      await browser.close();
    }
  });

  test(`character end to end on ${backend}: Generate, choose Xbot, dance on the song clock, export GLB, re-open`, async () => {
    const { browser, page, logs } = await launch(backend);
    try {
      await openApp(page, server, backend);
      // Compose: Generate fills every bar.
      await page.waitForFunction(() => Number(document.querySelector("#dance").dataset.bars) > 8 && document.body.dataset.project === "ready", null, { timeout: 90000 });
      await page.waitForFunction(() => document.querySelector("#dance").dataset.joins === "ready", null, { timeout: 60000 });
      await page.click("#dance-generate");
      await page.waitForFunction(() => !document.querySelector("#dance").dataset.busy && window.odori.choreo.view.every((v) => v.state.kind !== "empty"), null, { timeout: 60000 });
      // Choose the character: import Xbot, pick it in the Character menu.
      const n = await page.evaluate(() => window.odori.library.size);
      await page.setInputFiles("#file-input", join(data, "gltf/Xbot.glb"));
      await page.waitForFunction((n) => window.odori.library.size > n, n, { timeout: 60000 });
      const charId = await page.evaluate(() => {
        window.odori.exporter.refreshCharacters();
        const opt = [...document.querySelectorAll("#character option")].find((o) => o.textContent === "Xbot.glb");
        return opt && Number(opt.value);
      });
      assert.ok(charId, "Xbot is offered as a character");
      await page.selectOption("#character", String(charId));
      assert.equal(await page.evaluate(() => window.odori.viewer.character), charId, "the viewer draws on Xbot");
      // Play the dance with the song: the skinned figure follows the song's clock.
      await page.click('#dance-bars [data-bar="0"]');
      await page.click("#dance-play");
      const danceId = await page.evaluate(() => window.odori.choreo.danceId);
      await waitUntil(() => page.evaluate(() => window.odori.songPlayer.playing && window.odori.songPlayer.position() > 1.0), { what: "the song playing past 1 s", timeoutMs: 60000 });
      // The dance is put on Xbot between frames (not in one): until then it is drawn as before.
      await waitUntil(() => page.evaluate(() => window.odori.viewer.bodiesPending === 0 && window.odori.viewer.lastDrawn()[0]?.body === "character"), { what: "the dance made on Xbot", timeoutMs: 60000 });
      // Read the last drawn figure and the song clock in one animation frame, after the
      // player's tick; polled until several frames agree (a loaded machine skips frames).
      const lags = [];
      await waitUntil(async () => {
        const s = await page.evaluate(() => new Promise((done) => requestAnimationFrame(() => {
          const d = window.odori.viewer.lastDrawn();
          done({ song: window.odori.songPlayer.position(), playing: window.odori.songPlayer.playing, drawn: d });
        })));
        assert.ok(s.playing, "the song plays");
        assert.equal(s.drawn.length, 1);
        assert.equal(s.drawn[0].clip, danceId, "the dance is on screen");
        assert.equal(s.drawn[0].body, "character", `the dance is drawn on the character: ${JSON.stringify(s.drawn)}`);
        lags.push(Math.abs(s.drawn[0].timeSecs - s.song));
        return lags.length >= 8;
      }, { what: "eight frames of the dance on the song clock", timeoutMs: 60000 });
      lags.sort((a, b) => a - b);
      const median = lags[lags.length >> 1];
      console.log(`${backend}: figure time vs song clock over ${lags.length} frames: median ${(median * 1000).toFixed(1)} ms, max ${(lags.at(-1) * 1000).toFixed(1)} ms`);
      assert.ok(median < 2 / 60, `figure time lags the song by ${(median * 1000).toFixed(1)} ms (median)`);
      await page.screenshot({ path: join(artifacts, `${backend}-character-dance-xbot.png`) });
      // What a change of the dance costs the view: the whole dance retargeted once (then only
      // sampled each frame). Printed, not asserted.
      const cost = await page.evaluate(() => {
        const { choreo, viewer, library, player } = window.odori;
        player.pause();
        choreo.renderDance(); // a new revision of the dance clip
        const t0 = performance.now();
        viewer.figureJoints(library, choreo.danceId, 0);
        const t1 = performance.now();
        viewer.figureJoints(library, choreo.danceId, 1);
        return { first: t1 - t0, again: performance.now() - t1, secs: library.clip(choreo.danceId).durationSecs };
      });
      console.log(`${backend}: the ${cost.secs.toFixed(0)} s dance put on Xbot for the view in ${cost.first.toFixed(0)} ms; a pose after that ${cost.again.toFixed(2)} ms`);
      // Paused at a moment: Xbot's skin covers the joints the viewer says it posed.
      await page.evaluate(() => { const p = window.odori.player; p.pause(); p.time = 2.0; p.drawNow(); });
      const fig = await page.evaluate(([id]) => window.odori.viewer.figureJoints(window.odori.library, id, 2.0), [danceId]);
      assert.equal(fig.body, "character");
      assert.ok(fig.names.some((s) => s.startsWith("mixamorig:")), "the figure is posed on Xbot's own rig");
      const img = await canvasPixels(page, `${backend}-character-dance-xbot-still.png`);
      const cov = coverage(img, await projected(page, fig.positions), (c) => !isBackground(c));
      assert.ok(cov.inside > 10 && cov.hit >= cov.inside * 0.7, `Xbot drawn at ${cov.hit} of ${cov.inside} projected joints`);
      // The stick figure is one click away, and back.
      await page.check("#stick-figure");
      assert.equal(await page.evaluate(() => window.odori.viewer.lastDrawn()[0].body), "stick");
      await page.uncheck("#stick-figure");
      assert.equal(await page.evaluate(() => window.odori.viewer.lastDrawn()[0].body), "character");
      // The six candidates of a bar are drawn on the character.
      await page.click('#dance-bars [data-bar="3"]');
      await page.waitForFunction(() => document.querySelector("#dance").dataset.candidates === "6");
      const cands = await settledDraw(page, 0.5);
      assert.equal(cands.length, 6);
      assert.ok(cands.every((d) => d.body === "character"), `candidates: ${JSON.stringify(cands)}`);
      // Each skinned candidate takes a wash of its chip's colour: the first (orange) is
      // drawn orange where its joints are, the second (teal) is not.
      const shot = await canvasPixels(page, `${backend}-character-candidates-xbot.png`);
      const candJoints = await page.evaluate(() => {
        const { viewer, library, player } = window.odori;
        return player.figures().map((f) => {
          const j = viewer.figureJoints(library, f.clip, f.timeSecs);
          return j.positions.map((v, k) => v + (f.offset ? f.offset[k % 3] : 0));
        });
      });
      const first = coverage(shot, await projected(page, candJoints[0]), isOrange);
      const second = coverage(shot, await projected(page, candJoints[1]), isOrange);
      assert.ok(first.hit >= first.inside * 0.5 && second.hit <= second.inside * 0.2, `orange at ${first.hit}/${first.inside} joints of candidate 1, ${second.hit}/${second.inside} of candidate 2`);
      // A text animation is drawn on it; so is everything on the built-in body.
      await page.fill("#text-input", "Taro runs, then kicks the ball.");
      await page.click("#text-go");
      const text = await settledDraw(page, 1.0);
      assert.equal(text[0].clip, await page.evaluate(() => window.odori.text.clipId));
      assert.equal(text[0].body, "character", `text animation: ${JSON.stringify(text)}`);
      await page.selectOption("#character", "builtin");
      assert.equal(await page.evaluate(() => window.odori.viewer.lastDrawn()[0].body), "builtin");
      await page.selectOption("#character", String(charId));
      // Export GLB (the dance on Xbot) through a real download, and re-open it in the app.
      await page.evaluate((id) => { window.odori.panel.select(id); window.odori.player.pause(); }, danceId);
      // The Export dialog opens on the dance, on the chosen character (Xbot), as GLB.
      await page.click("#export");
      assert.equal(await page.evaluate(() => document.querySelector("input[name=export-what]:checked").value), "dance");
      await page.selectOption("#export-format", "glb");
      assert.match(await page.textContent("#export-summary"), /The dance .* on Xbot\.glb, as GLB/);
      const [download] = await Promise.all([page.waitForEvent("download"), page.click("#export-go")]);
      const bytes = readFileSync(await download.path());
      assert.equal(bytes.subarray(0, 4).toString(), "glTF", "the download is a GLB");
      const before = await page.evaluate(() => window.odori.library.size);
      await page.setInputFiles("#file-input", { name: download.suggestedFilename(), mimeType: "model/gltf-binary", buffer: bytes });
      await page.waitForFunction((n) => window.odori.library.size > n, before, { timeout: 60000 });
      const back = await page.evaluate(([danceId]) => {
        const { library, player, viewer } = window.odori;
        const b = player.clip;
        const names = library.jointNames(b);
        let worst = 0, compared = 0;
        for (const t of [0.25, 1.0, 2.5, 5.0, 9.0]) {
          const want = viewer.figureJoints(library, danceId, t);
          const got = library.jointPositions(b, t);
          want.names.forEach((name, j) => {
            const k = names.indexOf(name);
            if (k < 0) return;
            compared++;
            worst = Math.max(worst, Math.hypot(want.positions[3 * j] - got[3 * k], want.positions[3 * j + 1] - got[3 * k + 1], want.positions[3 * j + 2] - got[3 * k + 2]));
          });
        }
        player.pause();
        player.time = 1.0;
        player.drawNow();
        return { worst, compared, info: library.clip(b), drawn: viewer.lastDrawn() };
      }, [danceId]);
      assert.ok(back.info.hasMesh && back.info.joints >= 50, `the re-opened file has Xbot's mesh and rig: ${JSON.stringify(back.info)}`);
      assert.equal(back.drawn[0].body, "own", "the re-opened file plays on its own mesh");
      assert.ok(back.compared >= 5 * 50, `${back.compared} joint positions compared`);
      console.log(`${backend}: re-opened GLB vs the figure drawn: worst joint ${(back.worst * 1000).toFixed(2)} mm over ${back.compared} joint positions`);
      assert.ok(back.worst < 0.01, `the re-opened GLB differs from the figure drawn by ${back.worst} m`);
      await canvasPixels(page, `${backend}-character-reopened-xbot.png`);
      assert.ok(!logs.some((l) => l.startsWith("[pageerror]")), logs.join("\n"));
    } finally {
      await browser.close();
    }
  });
}
