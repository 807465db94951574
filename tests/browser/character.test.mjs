// Characters and export in the app, in headless Chromium on WebGL2 and WebGPU: import a real
// character (Xbot, RobotExpressive), put the built-in dance on it (*Put on*), see the skinned
// figure drawn where the engine says its joints are, *Export* it as GLB through a real
// download, re-open the file in the app and find the same motion. Screenshots of the dance on
// both characters on both back ends go to tests/artifacts/.
import { test, before, after } from "node:test";
import assert from "node:assert/strict";
import { join } from "node:path";
import { readFileSync } from "node:fs";
import { startServer, launch, openApp, canvasPixels, countNear, isBackground, data } from "./harness.mjs";

let server;
before(async () => { server = await startServer(); });
after(() => server && server.stop());

for (const backend of ["webgl2", "webgpu"]) {
  test(`characters on ${backend}: put on, draw skinned, export GLB, re-open`, async () => {
    const { browser, page, logs } = await launch(backend);
    try {
      await openApp(page, server, backend);
      const demo = await page.evaluate(() => window.odori.player.clip);
      for (const [file, shot] of [["gltf/Xbot.glb", "xbot"], ["gltf/RobotExpressive.glb", "robot"]]) {
        const before = await page.evaluate(() => window.odori.library.size);
        await page.setInputFiles("#file-input", join(data, file));
        await page.waitForFunction((n) => window.odori.library.size > n, before, { timeout: 60000 });
        // Choose the character and put the built-in dance on it.
        const charId = await page.evaluate(([demo, name]) => {
          const { panel, exporter, library } = window.odori;
          panel.select(demo);
          exporter.refreshCharacters();
          const opt = [...document.querySelectorAll("#character option")].find((o) => o.textContent === name);
          document.querySelector("#character").value = opt.value;
          return Number(opt.value) && library.clip(Number(opt.value)).id;
        }, [demo, file.split("/")[1]]);
        assert.ok(charId, `${file} is offered as a character`);
        await page.click("#put-on");
        const on = await page.evaluate(() => window.odori.library.clip(window.odori.player.clip));
        assert.equal(on.format, "character", `the new clip is selected: ${JSON.stringify(on)}`);
        assert.ok(on.hasMesh && on.name.includes(file.split("/")[1]), JSON.stringify(on));
        // The skinned figure is drawn where the engine puts the joints.
        const pts = await page.evaluate(([id, t]) => {
          const { player, library, viewer } = window.odori;
          player.pause();
          player.time = t;
          player.drawNow();
          const p = library.jointPositions(id, t);
          const out = [];
          for (let i = 0; i < p.length; i += 3) out.push(viewer.project(p[i], p[i + 1], p[i + 2]));
          return out.filter(Boolean);
        }, [on.id, 1.0]);
        const img = await canvasPixels(page, `${backend}-character-${shot}.png`);
        const inside = pts.filter(([x, y]) => x > 4 && y > 4 && x < img.width - 4 && y < img.height - 4);
        const covered = inside.filter(([x, y]) => countNear(img, x, y, 3, (c) => !isBackground(c)) > 0).length;
        assert.ok(inside.length > 10 && covered >= inside.length * 0.7, `${file}: body drawn at ${covered} of ${inside.length} projected joints`);
        // Export GLB through a real download, then re-open it in the app.
        // The Export dialog: the clip on screen (the one put on the character), as GLB.
        await page.click("#export");
        await page.check('input[name=export-what][value=clip]');
        await page.selectOption("#export-clip", String(await page.evaluate(() => window.odori.player.clip)));
        await page.selectOption("#export-format", "glb");
        const [download] = await Promise.all([page.waitForEvent("download"), page.click("#export-go")]);
        const bytes = readFileSync(await download.path());
        assert.equal(bytes.subarray(0, 4).toString(), "glTF", `${file}: the download is a GLB`);
        const n = await page.evaluate(() => window.odori.library.size);
        await page.setInputFiles("#file-input", { name: download.suggestedFilename(), mimeType: "model/gltf-binary", buffer: bytes });
        await page.waitForFunction((n) => window.odori.library.size > n, n, { timeout: 60000 });
        const worst = await page.evaluate(([a]) => {
          const { library, player } = window.odori;
          const b = player.clip;
          const na = library.jointNames(a), nb = library.jointNames(b);
          let worst = 0;
          for (const t of [0, 0.5, 1.0, 2.0, 3.0]) {
            const pa = library.jointPositions(a, t), pb = library.jointPositions(b, t);
            na.forEach((name, j) => {
              const k = nb.indexOf(name);
              if (k >= 0) worst = Math.max(worst, Math.hypot(pa[3 * j] - pb[3 * k], pa[3 * j + 1] - pb[3 * k + 1], pa[3 * j + 2] - pb[3 * k + 2]));
            });
          }
          return { worst, hasMesh: library.clip(b).hasMesh };
        }, [on.id]);
        assert.ok(worst.hasMesh, `${file}: the re-opened file has the character's mesh`);
        assert.ok(worst.worst < 0.01, `${file}: re-opened GLB differs by ${worst.worst} m`);
      }
      assert.ok(!logs.some((l) => l.startsWith("[pageerror]")), logs.join("\n"));
    } finally {
      await browser.close();
    }
  });
}
