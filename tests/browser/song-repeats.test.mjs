// Repeats marked by hand on the song strip (issue 26 item 2), on both back ends, from the
// keyboard: the Repeats disclosure opens with Enter, its fields and button are reached with Tab
// and each has a name; marking the demo song's last four bars clear of its found repeat (the
// second chorus) as repeating bars 1–4 lists the
// repeat, draws its band on the strip (read from the strip's pixels, against a column outside
// it), and Generate then gives those bars the first four bars' moves, the Dance strip saying
// "= bar N (marked)" — where the same Generate before the mark did not repeat them (the
// control). The mark is one undo step (undo takes it away, redo brings it back), a reload keeps
// it, a bad range says what is wrong, and the repeat's button removes it.
import { test, before, after } from "node:test";
import assert from "node:assert/strict";
import { join } from "node:path";
import { startServer, launch, openApp, generateDance, artifacts, BACKENDS } from "./harness.mjs";

let server;
before(async () => { server = await startServer(); });
after(() => server && server.stop());

const segments = (page) => page.evaluate(() => window.odori.choreo.view.map((v) => v.state.segment));
const runs = (page) => page.evaluate(() => window.odori.project.project.repeats());
const strip = (page) => page.evaluate(() => [...document.querySelectorAll("#dance-bars .bar")].map((b) => ({
  n: b.querySelector(".bar-n")?.textContent ?? "",
  repeats: b.dataset.repeats ?? null,
  marked: b.dataset.repeatMarked === "1",
  title: b.title,
})));

/** What has the keyboard focus, and its accessible name (its label's text or aria-label). */
const focused = (page) => page.evaluate(() => {
  const el = document.activeElement;
  const name = (el.getAttribute("aria-label") || (el.labels && el.labels[0] ? el.labels[0].textContent : "") || el.textContent || "").trim();
  return { id: el.id || el.tagName.toLowerCase(), name };
});

/** The share of strip pixels in the marked repeats' band (yellow) at a column `secs` into the song. */
const bandAt = (page, secs) => page.evaluate((secs) => {
  const c = document.querySelector("#song canvas");
  const g = c.getContext("2d");
  const dpr = c.width / Math.max(1, c.clientWidth);
  const x = Math.min(c.width - 1, Math.round((secs / window.odori.song.grid.durationSecs) * c.width));
  const band = 14 * dpr;
  let yellow = 0, n = 0;
  for (let y = Math.round(c.height - 2 * band + 2 * dpr); y < c.height - band - dpr; y++, n++) {
    const [r, gg, b] = g.getImageData(x, y, 1, 1).data;
    if (r > 200 && gg > 160 && b < 140) yellow++;
  }
  return yellow / Math.max(1, n);
}, secs);

const waitReady = async (page) => {
  await page.waitForFunction(() => document.body.dataset.ready === "1" && document.body.dataset.project === "ready" && document.body.dataset.song === "demo", null, { timeout: 120000 });
  await page.waitForFunction(() => Number(document.querySelector("#dance").dataset.bars) > 8 && document.querySelector("#dance").dataset.joins === "ready", null, { timeout: 120000 });
};

for (const backend of Object.keys(BACKENDS)) {
  test(`song repeats (${backend}): mark a repeat from the keyboard, Generate follows it, undo, reload keeps it, remove it`, async () => {
    const { browser, page, logs } = await launch(backend);
    try {
      await openApp(page, server, backend);
      await waitReady(page);
      const n = await page.evaluate(() => window.odori.song.grid.bars.length);
      const found = await runs(page);
      // The last four bars clear of the found repeats (as what repeats or what is repeated).
      const k = 4;
      const inFound = (t) => found.some((r) => (t >= r.firstBar && t < r.firstBar + r.bars) || (t >= r.ofBar && t < r.ofBar + r.bars));
      const clear = (a) => [0, 1, 2, 3].every((i) => !inFound(a + i) && !inFound(i));
      let first = n - k;
      while (first > k && !clear(first)) first--;
      assert.ok(clear(first), `no four bars clear of the found repeats ${JSON.stringify(found)}`);
      const last = first + k;

      // The control: Generate before the mark does not repeat bars 1–4 at the end.
      await generateDance(page, 90000);
      const before = await segments(page);
      const sameBefore = [0, 1, 2, 3].filter((i) => before[first + i] === before[i]).length;
      assert.ok(sameBefore < k, "the control already repeats bars 1–4 at the end: the test shows nothing");

      // From the keyboard: open Repeats, type the range, Tab to the button, Enter.
      await page.focus("#song-repeats summary");
      assert.equal((await focused(page)).name, "Repeats");
      await page.keyboard.press("Enter");
      assert.equal(await page.evaluate(() => document.querySelector("#song-repeats").open), true, "Enter opens the Repeats disclosure");
      const order = [];
      for (const value of [first + 1, last, 1]) {
        await page.keyboard.press("Tab");
        const f = await focused(page);
        order.push(f);
        await page.keyboard.type(String(value));
      }
      await page.keyboard.press("Tab");
      order.push(await focused(page));
      assert.deepEqual(order.map((f) => f.id), ["repeat-first", "repeat-last", "repeat-of", "repeat-mark"], "Tab reaches the fields and the button in order");
      for (const f of order) assert.ok(f.name.length > 1, `${f.id} has no name`);
      await page.keyboard.press("Enter");
      await page.waitForFunction((want) => (document.querySelector("#song").dataset.repeats ?? "").split(",").includes(want), `${first + 1}-${last}=1m`, { timeout: 10000 });
      assert.ok((await runs(page)).some((r) => r.firstBar === first && r.bars === k && r.ofBar === 0 && r.marked));
      const listed = await page.locator("#repeat-list button").allTextContents();
      assert.ok(listed.some((t) => t === `Remove ${first + 1}–${last} = bar 1 (marked)`), `the list: ${listed}`);
      // The strip draws the marked band over the repeat, not elsewhere.
      const grid = await page.evaluate(() => window.odori.song.grid.bars.map((b) => [b.startSecs, b.endSecs]));
      const mid = (t) => (grid[t][0] + grid[t][1]) / 2;
      // (Its last bar: clear of the band's label, which starts at its first bar.)
      const inside = await bandAt(page, mid(first + k - 1)), outside = await bandAt(page, mid(1));
      assert.ok(inside > 0.5 && outside < 0.1, `the marked band: ${inside.toFixed(2)} of the column inside the repeat, ${outside.toFixed(2)} outside`);

      // Generate follows the mark, and the Dance strip says so.
      await generateDance(page, 90000);
      const after = await segments(page);
      let bars = await strip(page);
      for (let i = 0; i < k; i++) {
        const t = first + i;
        assert.equal(after[t], after[i], `bar ${t + 1} is marked as repeating bar ${i + 1} but holds another move`);
        assert.ok(bars[t].marked && bars[t].n === `${t + 1} = bar ${i + 1} (marked)` && bars[t].title.includes(`repeats bar ${i + 1} (marked)`), `bar ${t + 1}: ${JSON.stringify(bars[t])}`);
      }
      await page.screenshot({ path: join(artifacts, `song-repeats-${backend}.png`) });
      console.log(`# ${backend}: ${n} bars; bars ${first + 1}–${last} marked as repeating 1–4: the same move in ${k} of ${k} (the control: ${sameBefore}); band ${inside.toFixed(2)} inside, ${outside.toFixed(2)} outside`);

      // Undo: the Generate, then the mark; redo brings both back.
      await page.click("#dance-undo");
      await page.click("#dance-undo");
      await page.waitForFunction(() => !(document.querySelector("#song").dataset.repeats ?? "").includes("m"), null, { timeout: 10000 });
      assert.ok((await runs(page)).every((r) => !r.marked), "undo took the mark away");
      await page.click("#dance-redo");
      await page.click("#dance-redo");
      await page.waitForFunction((want) => (document.querySelector("#song").dataset.repeats ?? "").split(",").includes(want), `${first + 1}-${last}=1m`, { timeout: 10000 });
      assert.deepEqual(await segments(page), after, "redo brings the dance back");

      // A reload keeps the mark, and the dance that follows it.
      await page.evaluate(() => window.odori.project.store.flush());
      await page.reload();
      await waitReady(page);
      await page.waitForFunction((want) => (document.querySelector("#song").dataset.repeats ?? "").split(",").includes(want), `${first + 1}-${last}=1m`, { timeout: 30000 });
      assert.deepEqual(await segments(page), after, "the reloaded dance");
      bars = await strip(page);
      assert.ok(bars[first].marked, `after the reload bar ${first + 1}: ${JSON.stringify(bars[first])}`);

      // A bad range says what is wrong (bars 2–5 cannot repeat bar 1: they overlap).
      await page.click("#song-repeats summary");
      await page.fill("#repeat-first", "2");
      await page.fill("#repeat-last", "5");
      await page.fill("#repeat-of", "1");
      await page.click("#repeat-mark");
      await page.waitForFunction(() => [...document.querySelectorAll("#messages li")].some((li) => /Repeat: .*overlap/.test(li.textContent)), null, { timeout: 10000 });
      assert.ok((await runs(page)).every((r) => r.firstBar !== 1), "the bad range was not marked");

      // The repeat's button removes it (from the keyboard).
      await page.focus(`#repeat-list button[data-first-bar="${first}"]`);
      const name = (await focused(page)).name;
      assert.equal(name, `Remove ${first + 1}–${last} = bar 1 (marked)`, "the remove button's name");
      await page.keyboard.press("Enter");
      await page.waitForFunction(() => !(document.querySelector("#song").dataset.repeats ?? "").includes("m"), null, { timeout: 10000 });
      assert.ok((await runs(page)).every((r) => !r.marked));
      const errors = logs.filter((l) => l.startsWith("[pageerror]"));
      assert.deepEqual(errors, []);
    } finally {
      await browser.close();
    }
  });
}
