// Legible bars, honest candidates and the share note (issue 26 items 5–6), on both back ends:
// import a salsa BVH, Generate → every bar of the Dance strip names its move and its source,
// and a bar holding the salsa names it; every candidate the engine flags says so in words on
// its chip, after the clean ones; every line of a cell shows (none cut off by the strip, a thin
// scrollbar's room kept); the strip keeps its height; a dance with an imported move
// shows the share note (a link cannot carry the person's files; the .odori file is offered)
// and a dance of built-in moves alone does not.
import { test, before, after } from "node:test";
import assert from "node:assert/strict";
import { startServer, launch, openApp, importSalsaForDance, generateDance, candidateChips, BACKENDS } from "./harness.mjs";

let server;
before(async () => { server = await startServer(); });
after(() => server && server.stop());

const strip = (page) => page.evaluate(() => [...document.querySelectorAll("#dance-bars .bar")].map((b) => ({
  kind: b.className,
  move: b.querySelector(".bar-move")?.textContent ?? "",
  src: b.querySelector(".bar-src")?.textContent ?? "",
  flags: b.querySelector(".bar-flags")?.textContent ?? "",
  title: b.title,
  height: b.getBoundingClientRect().height,
  // What of the cell shows: each line's bottom (px) over the cell's and over the strip's visible
  // bottom, with a thin scrollbar's room (11 px) kept when the browser hides its scrollbars
  // (headless does): a positive figure is a line cut off.
  cut: (() => {
    const s = document.querySelector("#dance-bars");
    const sr = s.getBoundingClientRect();
    const room = s.offsetHeight === s.clientHeight ? 11 : 0;
    const visible = Math.min(b.getBoundingClientRect().bottom, sr.top + s.clientHeight - room);
    return Math.max(0, ...[...b.querySelectorAll("span")].filter((x) => x.textContent).map((x) => x.getBoundingClientRect().bottom - visible));
  })(),
})));

for (const backend of Object.keys(BACKENDS)) {
  test(`dance notes (${backend}): bars name their moves, candidates their flags, the share note`, async () => {
    const { browser, page, logs } = await launch(backend);
    try {
      await openApp(page, server, backend);
      await page.waitForFunction(() => Number(document.querySelector("#dance").dataset.bars) > 8, null, { timeout: 60000 });
      const stripHeight = await page.evaluate(() => document.querySelector("#dance-bars").getBoundingClientRect().height);
      await importSalsaForDance(page);

      // Generate: every bar names its move and its source.
      await generateDance(page);
      let bars = await strip(page);
      assert.ok(bars.length > 8);
      for (const [i, b] of bars.entries()) {
        assert.ok(b.move.length > 0 && b.src.length > 0, `bar ${i + 1} does not name its move: ${JSON.stringify(b)}`);
        // The engine's name for the bar's segment.
        const name = await page.evaluate((i) => window.odori.choreo.choreographer.segment(window.odori.choreo.view[i].state.segment).name, i);
        assert.equal(b.move, name, `bar ${i + 1}`);
      }
      const generatedSalsa = bars.filter((b) => b.src === "salsa_02").length;

      // A salsa move set on a bar (whether or not Generate took one): the bar names the salsa.
      const salsaSeg = await page.evaluate(() => {
        const c = window.odori.choreo.choreographer;
        for (let i = 0; i < c.segmentCount; i++) { const s = c.segment(i); if (!s.builtin && !s.retired && /salsa_02/.test(s.name) && !/\(in 3\)/.test(s.name)) return i; }
        return -1;
      });
      assert.ok(salsaSeg >= 0, "no salsa segment in the library");
      await page.evaluate((seg) => { window.odori.choreo.choreographer.set(2, seg); window.odori.choreo.refresh(); }, salsaSeg);
      bars = await strip(page);
      assert.equal(bars[2].src, "salsa_02", JSON.stringify(bars[2]));
      assert.ok(bars.every((b) => b.move.length > 0), "a bar lost its name");
      // Flags in words: a bar the engine flags shows them (the strip's short words, the full ones in its title).
      const notes = await page.evaluate(() => window.odori.choreo.notes);
      const flagged = notes.filter((n) => n.flags.length);
      for (const n of flagged) {
        assert.ok(bars[n.bar].flags.length > 0, `bar ${n.bar + 1} is flagged (${n.flags.map((f) => f.words).join("; ")}) but its cell says nothing`);
        for (const f of n.flags) assert.ok(bars[n.bar].title.includes(f.words), `bar ${n.bar + 1}: "${f.words}" not in its title`);
      }
      for (const n of notes.filter((n) => !n.flags.length)) assert.equal(bars[n.bar].flags, "", `bar ${n.bar + 1} is clean but shows "${bars[n.bar].flags}"`);
      // Every line of every cell shows (number and move, source, weak spots), a thin scrollbar's room kept.
      for (const [i, b] of bars.entries()) assert.ok(b.cut < 0.5, `bar ${i + 1}: a line is cut off by ${b.cut.toFixed(1)} px (${JSON.stringify({ move: b.move, src: b.src, flags: b.flags })})`);
      // The strip kept its height through Generate and the notes.
      const after = await page.evaluate(() => document.querySelector("#dance-bars").getBoundingClientRect().height);
      assert.ok(Math.abs(after - stripHeight) < 0.5, `the strip's height went from ${stripHeight} to ${after} px`);

      // The share note: shown for a dance with imported moves, with the .odori file offered.
      const share = await page.evaluate(() => ({ hidden: document.querySelector("#dance-share-note").hidden, text: document.querySelector("#dance-share-note").textContent, linkOff: document.querySelector("#dance-share").disabled, save: !!document.querySelector("#dance-share-save") }));
      assert.ok(!share.hidden && /cannot/.test(share.text) && /salsa_02/.test(share.text) && share.linkOff && share.save, JSON.stringify(share));

      // Candidates: every flagged one says so in words, and clean ones come first.
      let sawFlag = 0;
      let sawClean = 0;
      for (const bar of [1, 4, 6, 8, 3, 5]) {
        const chips = await candidateChips(page, bar);
        assert.ok(chips.every((c) => c.flags !== null), "a candidate has no note from the engine");
        for (const c of chips) {
          if (c.flags.length) { sawFlag++; for (const f of c.flags) assert.ok(c.text.includes(f.words), `flagged candidate "${c.text}" does not say "${f.words}"`); }
          else { sawClean++; assert.ok(!/off the beat|join jump|foot skate/.test(c.text), `clean candidate says "${c.text}"`); }
        }
        const counts = chips.map((c) => c.flags.length);
        assert.deepEqual(counts, [...counts].sort((a, b) => a - b), "clean candidates are not first");
        if (sawFlag && sawClean) break;
      }
      console.log(`${backend}: ${bars.length} bars named (${generatedSalsa} salsa from Generate), ${flagged.length} flagged; candidates seen: ${sawFlag} flagged, ${sawClean} clean`);
      assert.ok(sawFlag > 0, "no candidate was flagged on six bars: the words were never shown");

      // Built-in moves only again: the note goes and Share link is offered.
      await page.evaluate(() => { const ch = window.odori.choreo; const c = ch.choreographer; for (let i = 0; i < ch.view.length; i++) c.clear(i); ch.refresh(); });
      await generateDance(page);
      const builtinOnly = await page.evaluate(() => window.odori.choreo.notes.every((n) => n.builtin));
      const note = await page.evaluate(() => ({ hidden: document.querySelector("#dance-share-note").hidden, linkOff: document.querySelector("#dance-share").disabled }));
      if (builtinOnly) assert.ok(note.hidden && !note.linkOff, JSON.stringify(note));
      else assert.ok(!note.hidden && note.linkOff, JSON.stringify(note));
      assert.ok(!logs.some((l) => /pageerror/.test(l)), logs.join("\n"));
    } finally {
      await browser.close();
    }
  });
}
