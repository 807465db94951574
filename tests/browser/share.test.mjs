// Share by link (issue 12): a dance of built-in moves goes into the URL fragment by the moves'
// stable keys; opening that link in a fresh browser context gives the same bars and the same
// moves (pinned bars pinned, generated ones generated). On the demo song the link is all there
// is; on a song file the link carries the song's name, length and SHA-256, the fresh page asks
// for the file (the test gives it through the file chooser), refuses a wrong one with a
// message, and takes the right one. A damaged link is reported by name.
import { test, before, after } from "node:test";
import assert from "node:assert/strict";
import { join } from "node:path";
import { startServer, launch, openApp, data } from "./harness.mjs";

let server;
before(async () => { server = await startServer(); });
after(() => server && server.stop());

const danceOf = (page) => page.evaluate(() => window.odori.choreo.choreographer.view().map((v) => ({
  start: Math.round(v.bar.startSecs * 1000), end: Math.round(v.bar.endSecs * 1000), kind: v.state.kind, segment: v.state.segment ?? null,
})));

async function demoReady(page) {
  await page.waitForFunction(() => document.body.dataset.song === "demo" && window.odori.choreo.choreographer.view().length > 0, null, { timeout: 60000 });
}

test("a dance's link opens the same dance in a fresh page; a damaged link is reported", async () => {
  const { browser, page, logs } = await launch("webgl2");
  try {
    await openApp(page, server, "webgl2");
    await demoReady(page);
    // Build a dance: pin two bars to candidates, generate the rest.
    const pins = await page.evaluate(async () => {
      const { choreo } = window.odori;
      await choreo.prepareJoins();
      const c = choreo.choreographer;
      const a = c.candidates(1)[2], b = c.candidates(5)[4];
      c.set(1, a);
      c.set(5, b);
      c.generate();
      choreo.refresh();
      return [a, b];
    });
    const original = await danceOf(page);
    assert.ok(original.length >= 16, `${original.length} bars`);
    assert.deepEqual([original[1].kind, original[1].segment, original[5].segment], ["pinned", pins[0], pins[1]]);
    assert.ok(original.filter((b) => b.kind === "generated").length >= original.length - 2, "the other bars are generated");
    // The button puts the link in the address bar; it is the same as share.link().
    await page.click("#dance-share");
    const link = await page.evaluate(() => window.odori.share.link());
    assert.equal(await page.evaluate(() => location.href), link);
    assert.match(link, /#dance=2\.demo\.\d+\.[-pg]/);
    assert.doesNotMatch(link, /\.[pg][0-9a-z]{1,3}(\.|$)/, "moves are named by key, not by index");
    console.log(`link: ${link.length} characters for ${original.length} bars`);

    // A fresh context (nothing shared with the first page but the link); the first page is
    // closed so the new one is the only one drawing.
    await page.close();
    const ctx = await browser.newContext({ viewport: { width: 1280, height: 800 } });
    const fresh = await ctx.newPage();
    assert.match(link, /\?backend=webgl2#/, "the link keeps the page's own query");
    await fresh.goto(link);
    await fresh.waitForFunction(() => document.body.dataset.shared, null, { timeout: 90000 }).catch(async (e) => {
      throw new Error(`${e.message}: ${JSON.stringify(await fresh.evaluate(() => ({ ...document.body.dataset, messages: document.querySelector("#messages")?.textContent })))}`);
    });
    assert.equal(await fresh.evaluate(() => document.body.dataset.shared), "applied", await fresh.textContent("#messages"));
    assert.deepEqual(await danceOf(fresh), original, "same bars, same moves, same pinned/generated");
    // The link is one edit of the project: one Undo takes the whole dance back, Redo brings it.
    await fresh.click("#dance-undo");
    await fresh.waitForFunction(() => window.odori.choreo.view.every((v) => v.state.kind === "empty"), null, { timeout: 10000 }).catch(async (e) => {
      throw new Error(`one undo did not take the applied link back: ${e.message}: ${JSON.stringify(await danceOf(fresh))}`);
    });
    assert.equal(await fresh.evaluate(() => window.odori.project.project.canUndo()), false, "applying the link was one undo step");
    await fresh.click("#dance-redo");
    await fresh.waitForFunction(() => window.odori.choreo.view.every((v) => v.state.kind !== "empty"), null, { timeout: 10000 });
    assert.deepEqual(await danceOf(fresh), original, "redo gives the linked dance back");
    await ctx.close();

    // A damaged link: a clear message, the app still works.
    const ctx2 = await browser.newContext();
    const bad = await ctx2.newPage();
    await bad.goto(server.url + "?backend=webgl2#dance=2.demo.3.pstepTouch~none~low~R.zz!.-");
    await bad.waitForFunction(() => document.body.dataset.shared === "error", null, { timeout: 60000 });
    assert.match(await bad.textContent("#messages"), /Dance link: this dance link is damaged/);
    await ctx2.close();
    assert.ok(!logs.some((l) => l.includes("[pageerror]")), logs.join("\n"));
  } finally {
    await browser.close();
  }
});

const SONG = join(data, "music", "Kevin_MacLeod_-_Vibe_Ace.hq.ogg");
const OTHER = join(data, "music", "Karissa_Hobbs_-_Lets_Go_Fishin.hq.ogg");

test("a dance on a song file: the link names the song; a fresh page asks for it, refuses a wrong file, rebuilds the dance from the right one", async () => {
  const { browser, page, logs } = await launch("webgl2");
  try {
    await openApp(page, server, "webgl2");
    await demoReady(page);
    const demoBars = (await danceOf(page)).length;
    await page.setInputFiles("#song-input", SONG);
    await page.waitForFunction(() => document.body.dataset.song === "Kevin_MacLeod_-_Vibe_Ace.hq.ogg", null, { timeout: 90000 });
    await page.waitForFunction((n) => window.odori.choreo.choreographer.view().length !== n, demoBars, { timeout: 30000 });
    const pins = await page.evaluate(async () => {
      const { choreo } = window.odori;
      await choreo.prepareJoins();
      const c = choreo.choreographer;
      const a = c.candidates(2)[1], b = c.candidates(7)[3];
      c.set(2, a);
      c.set(7, b);
      c.generate();
      choreo.refresh();
      return [a, b];
    });
    const original = await danceOf(page);
    assert.deepEqual([original[2].kind, original[2].segment, original[7].segment], ["pinned", pins[0], pins[1]]);
    const link = await page.evaluate(() => window.odori.share.link());
    assert.match(link, /#dance=2\.file~[A-Za-z0-9_-]+~\d+~[0-9a-f]{64}\.\d+\./);
    console.log(`song-file link: ${link.length} characters for ${original.length} bars`);
    await page.close();

    const ctx = await browser.newContext({ viewport: { width: 1280, height: 800 } });
    const fresh = await ctx.newPage();
    fresh.on("pageerror", (e) => logs.push(`[pageerror] ${e.message}`));
    fresh.on("console", (m) => logs.push(`[${m.type()}] ${m.text()}`));
    await fresh.goto(link);
    await fresh.waitForFunction(() => document.body.dataset.shared === "asking-song", null, { timeout: 90000 });
    assert.match(await fresh.textContent("#share-song"), /Kevin_MacLeod_-_Vibe_Ace\.hq\.ogg/);
    // A wrong file: refused with a message; nothing changes; the chooser stays.
    let [chooser] = await Promise.all([fresh.waitForEvent("filechooser"), fresh.click("#share-song-input")]);
    await chooser.setFiles(OTHER);
    await fresh.waitForFunction(() => document.body.dataset.shared === "wrong-song", null, { timeout: 30000 });
    assert.match(await fresh.textContent("#share-song-problem"), /Karissa_Hobbs_-_Lets_Go_Fishin\.hq\.ogg is not the song of this link/);
    assert.equal(await fresh.evaluate(() => document.body.dataset.song), "demo", "the wrong file was not loaded");
    // The right file: loaded as the song, the dance rebuilt.
    [chooser] = await Promise.all([fresh.waitForEvent("filechooser"), fresh.click("#share-song-input")]);
    await chooser.setFiles(SONG);
    await fresh.waitForFunction(() => ["applied", "error"].includes(document.body.dataset.shared), null, { timeout: 120000 });
    assert.equal(await fresh.evaluate(() => document.body.dataset.shared), "applied", await fresh.textContent("#messages"));
    assert.equal(await fresh.evaluate(() => document.body.dataset.song), "Kevin_MacLeod_-_Vibe_Ace.hq.ogg");
    assert.equal(await fresh.$("#share-song"), null, "the song chooser is gone");
    assert.deepEqual(await danceOf(fresh), original, "same bars, same moves, same pinned/generated");
    // The link is one edit of the project: one Undo takes the whole dance back, Redo brings it.
    await fresh.click("#dance-undo");
    await fresh.waitForFunction(() => window.odori.choreo.view.every((v) => v.state.kind === "empty"), null, { timeout: 10000 }).catch(async (e) => {
      throw new Error(`one undo did not take the applied link back: ${e.message}: ${JSON.stringify(await danceOf(fresh))}`);
    });
    // Opening the song file was an edit of its own, before the link's: that one Undo left it.
    assert.equal(await fresh.evaluate(() => document.body.dataset.song), "Kevin_MacLeod_-_Vibe_Ace.hq.ogg", "one undo took back only the link's dance");
    await fresh.click("#dance-redo");
    await fresh.waitForFunction(() => window.odori.choreo.view.every((v) => v.state.kind !== "empty"), null, { timeout: 10000 });
    assert.deepEqual(await danceOf(fresh), original, "redo gives the linked dance back");
    await ctx.close();
    assert.ok(!logs.some((l) => l.includes("[pageerror]")), logs.join("\n"));
    assert.ok(!logs.some((l) => /Content Security Policy/i.test(l)), `the song chooser works under the page's CSP: ${logs.filter((l) => /Content Security/i.test(l)).join("\n")}`);
  } finally {
    await browser.close();
  }
});
