// The person's moves first, by default (issue 26 item 1), on both back ends: the Dance strip's
// moves choice reads "my moves" from the start; import a CMU salsa BVH, Generate at the default →
// the bar strip names the salsa on at least half of the bars; *Another take* changes the dance
// (the strip's move names differ) and Undo brings the first back (the same names, bar for bar);
// a candidate the engine flags says so in words on its chip.
import { test, before, after } from "node:test";
import assert from "node:assert/strict";
import { startServer, launch, openApp, importSalsaForDance, danceSettled, generateDance, candidateChips, BACKENDS } from "./harness.mjs";

let server;
before(async () => { server = await startServer(); });
after(() => server && server.stop());

const strip = (page) => page.evaluate(() => [...document.querySelectorAll("#dance-bars .bar")].map((b) => ({
  move: b.querySelector(".bar-move")?.textContent ?? "",
  src: b.querySelector(".bar-src")?.textContent ?? "",
})));

for (const backend of Object.keys(BACKENDS)) {
  test(`my moves (${backend}): the default, a salsa on half the bars, another take, undo, flags in words`, async () => {
    const { browser, page, logs } = await launch(backend);
    try {
      await openApp(page, server, backend);
      await page.waitForFunction(() => Number(document.querySelector("#dance").dataset.bars) > 8, null, { timeout: 60000 });
      // The choice shows the engine's default: my moves (with nothing imported, that is the built-in moves).
      const source = await page.evaluate(() => ({ control: document.querySelector("#dance-moves-source").value, engine: window.odori.choreo.choreographer.movesSource }));
      assert.deepEqual(source, { control: "mine", engine: "mine" });

      await importSalsaForDance(page);

      // Generate at the default: the salsa on at least half of the bars, named on the strip.
      await generateDance(page);
      const first = await strip(page);
      const salsa = first.filter((b) => b.src === "salsa_02").length;
      console.log(`${backend}: Generate took the salsa for ${salsa} of ${first.length} bars`);
      assert.ok(first.length > 8 && first.every((b) => b.move.length > 0), JSON.stringify(first));
      assert.ok(salsa * 2 >= first.length, `the salsa on ${salsa} of ${first.length} bars: ${first.map((b) => b.src).join(", ")}`);

      // Another take: a different dance.
      await page.click("#dance-another-take");
      await page.waitForFunction(() => document.querySelector("#dance").dataset.take === "1", null, { timeout: 60000 });
      await danceSettled(page);
      const second = await strip(page);
      const differ = second.filter((b, i) => b.move !== first[i].move).length;
      console.log(`${backend}: another take changed ${differ} of ${first.length} bars`);
      assert.ok(differ > 0, "another take left every bar's move as it was");

      // Undo: the first take's moves, bar for bar.
      await page.click("#dance-undo");
      await page.waitForFunction((names) => [...document.querySelectorAll("#dance-bars .bar .bar-move")].map((m) => m.textContent).join("\n") === names, first.map((b) => b.move).join("\n"), { timeout: 10000 }).catch(() => {});
      assert.deepEqual((await strip(page)).map((b) => b.move), first.map((b) => b.move), "undo did not bring the first take back");

      // A candidate with a flag says so in words (and clean ones come first).
      let flagged = 0;
      for (const bar of [1, 3, 4, 6, 8, 5, 2, 7]) {
        const chips = await candidateChips(page, bar);
        assert.ok(chips.every((c) => c.flags !== null), "a candidate has no note from the engine");
        for (const c of chips.filter((c) => c.flags.length)) {
          flagged++;
          for (const f of c.flags) assert.ok(c.text.includes(f.words), `flagged candidate "${c.text}" does not say "${f.words}"`);
        }
        const counts = chips.map((c) => c.flags.length);
        assert.deepEqual(counts, [...counts].sort((a, b) => a - b), "clean candidates are not first");
        if (flagged) break;
      }
      assert.ok(flagged > 0, "no candidate was flagged on eight bars: the words were never shown");
      assert.ok(!logs.some((l) => /pageerror/.test(l)), logs.join("\n"));
    } finally {
      await browser.close();
    }
  });
}
