// Song sections in the page (issue 26 item 2), on both back ends: the song strip shows the
// sections the engine finds (`Project.sections()`, the analysis Generate repeats moves on and
// the video's director camera cuts on) as coloured bands with a letter each — read back from the
// strip's own pixels: bands of one label share a colour, bands of different labels differ — and
// follows a grid correction; after Generate on the demo song (built-in moves), the bars of the
// repeated chorus hold the moves of the first chorus's bars and the Dance strip says so
// ("= bar N" beside its number, "repeats bar N" in its title), while no other bar does.
import { test, before, after } from "node:test";
import assert from "node:assert/strict";
import { join } from "node:path";
import { startServer, launch, openApp, artifacts, BACKENDS } from "./harness.mjs";

let server;
before(async () => { server = await startServer(); });
after(() => server && server.stop());

/** The project's sections as the engine gives them, and what the strip shows. */
const shown = (page) => page.evaluate(() => {
  const s = window.odori.project.project.sections();
  const root = document.querySelector("#song");
  return {
    engine: s.sections.map((x) => ({ firstBar: x.firstBar, bars: x.bars, label: x.label, repeatOf: x.repeatOf ?? null })),
    letters: root.dataset.sections ?? "",
    starts: root.dataset.sectionStarts ?? "",
    bars: window.odori.song.grid.bars.length,
  };
});

/** The colour of the strip's section band at the middle of each section (canvas pixels). */
const bandColours = (page) => page.evaluate(() => {
  const c = document.querySelector("#song canvas");
  const g = c.getContext("2d");
  const grid = window.odori.song.grid;
  const secs = window.odori.project.project.sections().sections;
  const dpr = c.width / Math.max(1, c.clientWidth);
  return secs.map((s) => {
    const a = grid.bars[s.firstBar].startSecs, b = grid.bars[s.firstBar + s.bars - 1].endSecs;
    // The commonest colour over columns from 40 % to 95 % into the section (clear of its letter;
    // a beat or bar line may cross a column), 2 px above the strip's bottom.
    const counts = new Map();
    for (let k = 0; k <= 11; k++) {
      const x = Math.round(((a + (b - a) * (0.4 + 0.05 * k)) / grid.durationSecs) * c.width);
      const d = g.getImageData(Math.min(c.width - 1, x), c.height - Math.round(2 * dpr) - 1, 1, 1).data;
      const key = `${d[0]},${d[1]},${d[2]}`;
      counts.set(key, (counts.get(key) ?? 0) + 1);
    }
    const best = [...counts.entries()].sort((p, q) => q[1] - p[1])[0][0];
    return best.split(",").map(Number);
  });
});

for (const backend of Object.keys(BACKENDS)) {
  test(`song sections (${backend}): the strip shows the engine's sections; a repeated chorus takes the first one's moves and says so`, async () => {
    const { browser, page, logs } = await launch(backend);
    try {
      await openApp(page, server, backend);
      await page.waitForFunction(() => document.body.dataset.song === "demo" && document.querySelector("#song").dataset.sections, null, { timeout: 60000 });
      let s = await shown(page);
      const letter = (x) => String.fromCharCode(65 + (x.label % 26));
      assert.equal(s.letters, s.engine.map(letter).join(""), "the strip's letters are the engine's sections");
      assert.equal(s.starts, s.engine.map((x) => x.firstBar).join(","));
      assert.equal(s.engine.reduce((n, x) => n + x.bars, 0), s.bars, "the sections cover every bar");
      const repeats = s.engine.filter((x) => x.repeatOf != null);
      assert.ok(repeats.length >= 1, `the demo song's second chorus repeats the first: ${s.letters}`);
      // The band colours, from the strip's pixels: one label, one colour; another label, another.
      const colours = await bandColours(page);
      const dist = (p, q) => Math.hypot(p[0] - q[0], p[1] - q[1], p[2] - q[2]);
      let same = 0, differ = 0;
      for (let i = 0; i < colours.length; i++) {
        for (let j = i + 1; j < colours.length; j++) {
          if (s.engine[i].label === s.engine[j].label) { assert.ok(dist(colours[i], colours[j]) < 12, `sections ${i} and ${j} (${s.letters}) share a label but not a colour: ${colours[i]} vs ${colours[j]}`); same++; }
          else { assert.ok(dist(colours[i], colours[j]) > 30, `sections ${i} and ${j} (${s.letters}) differ but look alike: ${colours[i]} vs ${colours[j]}`); differ++; }
        }
      }
      assert.ok(same > 0 && differ > 0, `${same} alike and ${differ} different pairs compared`);
      await page.screenshot({ path: join(artifacts, `song-sections-01-${backend}.png`) });

      // Generate with the built-in moves: the repeated chorus holds the first chorus's moves.
      await page.waitForFunction(() => Number(document.querySelector("#dance").dataset.bars) > 8 && document.querySelector("#dance").dataset.joins === "ready", null, { timeout: 90000 });
      await page.click("#dance-generate");
      await page.waitForFunction(() => !document.querySelector("#dance").dataset.busy && window.odori.choreo.view.every((v) => v.state.kind !== "empty"), null, { timeout: 90000 });
      const strip = await page.evaluate(() => [...document.querySelectorAll("#dance-bars .bar")].map((b) => ({
        n: b.querySelector(".bar-n")?.textContent ?? "",
        move: b.querySelector(".bar-move")?.textContent ?? "",
        repeats: b.dataset.repeats ?? null,
        title: b.title,
      })));
      const segs = await page.evaluate(() => window.odori.choreo.view.map((v) => v.state.segment));
      const first = (x) => s.engine.find((o) => o.label === x.label);
      let marked = 0;
      for (const r of repeats) {
        const src = first(r);
        for (let i = 0; i < Math.min(r.bars, src.bars); i++) {
          const t = r.firstBar + i, o = src.firstBar + i;
          assert.equal(segs[t], segs[o], `bar ${t + 1} repeats bar ${o + 1} but holds another move`);
          assert.equal(strip[t].repeats, String(o + 1), `bar ${t + 1}: ${JSON.stringify(strip[t])}`);
          assert.ok(strip[t].n === `${t + 1} = bar ${o + 1}` && strip[t].title.includes(`repeats bar ${o + 1}`), `bar ${t + 1} does not say it repeats bar ${o + 1}: ${JSON.stringify(strip[t])}`);
          assert.equal(strip[t].move, strip[o].move);
          marked++;
        }
      }
      const inRepeat = new Set(repeats.flatMap((r) => Array.from({ length: r.bars }, (_, i) => r.firstBar + i)));
      strip.forEach((b, i) => { if (!inRepeat.has(i)) assert.equal(b.repeats, null, `bar ${i + 1} is in no repeat but says ${b.repeats}`); });
      console.log(`# ${backend}: sections ${s.letters}, ${marked} bars repeat their first occurrence's move and say so`);
      await page.screenshot({ path: join(artifacts, `song-sections-02-${backend}.png`) });

      // A grid correction: the strip shows the sections of the new grid.
      await page.fill("#song-bpm", "100");
      await page.dispatchEvent("#song-bpm", "change");
      await page.waitForFunction((n) => window.odori.song.grid.bars.length !== n && document.querySelector("#song").dataset.sectionStarts, s.bars, { timeout: 30000 });
      const s2 = await shown(page);
      assert.notEqual(s2.bars, s.bars);
      assert.equal(s2.letters, s2.engine.map(letter).join(""));
      assert.equal(s2.engine.reduce((n, x) => n + x.bars, 0), s2.bars, "the new sections cover the new bars");
      const errors = logs.filter((l) => l.startsWith("[pageerror]"));
      assert.deepEqual(errors, []);
    } finally {
      await browser.close();
    }
  });
}
