// Text to animation in the page: the paper's sentence gives a three-row time table with the
// right join types, and the figure moves; swapping a clip re-animates; nonsense is reported.
import { test, before, after } from "node:test";
import assert from "node:assert/strict";
import { join } from "node:path";
import { startServer, launch, openApp, canvasPixels, artifacts, data, importFiles } from "./harness.mjs";

let server;
before(async () => { server = await startServer(); });
after(() => server && server.stop());

test("text: 太郎は走って，ボールを蹴る．そして喜ぶ． → run, kick (transition), rejoice (connection); the figure moves", async () => {
  const { browser, page, logs } = await launch("webgl2");
  try {
    await openApp(page, server, "webgl2");
    await page.fill("#text-input", "太郎は走って，ボールを蹴る．そして喜ぶ．");
    await page.click("#text-go");
    await page.waitForFunction(() => document.querySelector("#text").dataset.rows !== undefined);
    const rows = await page.$$eval("#text-table tbody tr", (trs) => trs.map((tr) => [...tr.children].map((td) => td.querySelector("select") ? td.querySelector("select").selectedOptions[0].textContent : td.textContent)));
    assert.equal(rows.length, 3, JSON.stringify(rows));
    assert.deepEqual(rows.map((r) => r[3]), ["initial", "transition", "connection"]);
    assert.deepEqual(rows.map((r) => r[4]), ["–", "1", "2"]);
    assert.match(rows[0][1], /run/);
    assert.match(rows[1][1], /kick/);
    assert.match(rows[2][1], /rejoice|cheer/);
    // The animation is the selected clip: two moments differ on screen.
    const shot = async (t, name) => {
      await page.evaluate((t) => { const p = window.odori.player; p.pause(); p.time = t; p.drawNow(); }, t);
      return canvasPixels(page, name);
    };
    const a = await shot(0.5, "text-t0.5.png");
    const dur = await page.evaluate(() => window.odori.library.clip(window.odori.player.clip).durationSecs);
    const b = await shot(dur * 0.8, "text-t-late.png");
    let changed = 0;
    for (let i = 0; i < a.rgba.length; i += 4) if (Math.abs(a.rgba[i] - b.rgba[i]) + Math.abs(a.rgba[i + 1] - b.rgba[i + 1]) > 60) changed++;
    assert.ok(changed > 300, `only ${changed} pixels changed`);
    await page.screenshot({ path: join(artifacts, "text-page.png") });

    // English gives the same table.
    await page.fill("#text-input", "Taro runs, then kicks the ball. Then he rejoices.");
    await page.click("#text-go");
    await page.waitForFunction(() => document.querySelectorAll("#text-table tbody tr").length === 3);
    const joins = await page.$$eval("#text-table tbody tr", (trs) => trs.map((tr) => tr.dataset.join));
    assert.deepEqual(joins, ["initial", "transition", "connection"]);

    // A clip tagged by the person is called by its tag: import salsa, tag it, use the word.
    await importFiles(page, join(data, "mocap/cmu-salsa/salsa_02.bvh"), { "salsa_02.bvh": { fps: 60 } });
    await page.waitForFunction(() => [...document.querySelectorAll("#library tbody tr")].some((tr) => tr.textContent.includes("salsa_02")));
    await page.click("#library tbody tr:last-child td:first-child");
    await page.fill("#text-tags", "salsa, サルサ");
    await page.click("#text-tag");
    await page.fill("#text-input", "サルサして、喜ぶ。");
    await page.click("#text-go");
    await page.waitForFunction(() => document.querySelectorAll("#text-table tbody tr").length === 2);
    const clips = await page.$$eval("#text-table tbody tr select", (ss) => ss.map((s) => s.selectedOptions[0].textContent));
    assert.equal(clips[0], "salsa_02", JSON.stringify(clips));

    // Only unknown words: a message, no crash.
    await page.fill("#text-input", "xyzzy plugh");
    await page.click("#text-go");
    await page.waitForSelector("#messages li.error");
    assert.match(await page.textContent("#messages li.error"), /^Text: /);
    assert.deepEqual(logs.filter((l) => l.startsWith("[pageerror]")), []);
  } finally {
    await browser.close();
  }
});
