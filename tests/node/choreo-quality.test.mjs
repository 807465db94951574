// The dance quality readout (spec §J) from Node, as an npm user gets it: a Project's dance
// generated on the demo song with a real salsa clip in its library, measured per bar and whole;
// bad beats are a typed error; the filling's settings are project edits.
import { test } from "node:test";
import assert from "node:assert/strict";
import { readFileSync, existsSync } from "node:fs";
import { fileURLToPath } from "node:url";
import { dirname, join } from "node:path";

const root = join(dirname(fileURLToPath(import.meta.url)), "..", "..");
const data = join(root, "..", "shared", "data");
if (!existsSync(data)) throw new Error(`../shared/data is missing: these tests read the shared real data beside the repository (${data})`);
const pkg = await import(join(root, "pkg", "odori.js"));
pkg.initSync({ module: readFileSync(join(root, "pkg", "odori_bg.wasm")) });
const { Library, DemoSong, Project, rmsEnvelope } = pkg;

const demo = DemoSong.render(44100);
const env = rmsEnvelope([demo.samples], demo.sampleRateHz);

/** A project on the demo song with a real salsa clip in its dance library. */
function salsaProject() {
  const lib = new Library();
  const p = new Project();
  p.setSong("Demo song (built-in)", undefined, env.hopSecs, env.bands, undefined);
  const report = p.importInto(lib, "salsa_01.bvh", new Uint8Array(readFileSync(join(data, "mocap/cmu-salsa/salsa_01.bvh"))), { fpsOverride: 60 });
  assert.equal(report.clips.length, 1);
  assert.ok(p.clips()[0].cut, `salsa_01 is cut into moves: ${JSON.stringify(p.clips()[0])}`);
  return p;
}

test("quality of a generated dance: beat alignment above its half-shifted control, per bar and whole", () => {
  const p = salsaProject();
  const grid = p.grid();
  while (p.prepareTable(256) < 1) { /* slices of the join table */ }
  p.generate();
  const q = p.quality(new Float32Array(grid.beatTimesSecs));
  assert.equal(q.bars.length, grid.bars.length);
  assert.ok(q.bars[0].joinJump == null, "the first bar has no join");
  assert.ok(q.bars.slice(1).every((b) => Number.isFinite(b.joinJump)), "every bar after the first has a join jump");
  assert.ok(q.beats.basMusic >= q.beats.basMusicShifted + 0.1, `BAS-music ${q.beats.basMusic} vs half-shifted ${q.beats.basMusicShifted}`);
  assert.ok(q.beats.kineticBeatsPerSec > 0.5 && q.beats.musicBeatsPerSec > 1, JSON.stringify(q.beats));
  assert.ok(Number.isFinite(q.footSkate.meanCmPerS) && q.footSkate.contacts > 0, JSON.stringify(q.footSkate));
  assert.ok(q.joinJumpMean <= q.joinJumpMax && Number.isFinite(q.pfc));
  // Without beats the bars' quarters are used.
  const own = p.quality();
  assert.ok(own.beats.basMusic > 0 && own.bars.length === q.bars.length);
  // Beats out of order are refused with the offending one named.
  assert.throws(() => p.quality(new Float32Array([1, 0.5])), (e) => e.name === "OdoriError" && e.kind === "bad-argument" && /beat 1/.test(e.message));
  // The filling's settings are project edits, kept in the document and checked.
  p.setBeatWeight(0.5);
  p.setOwnMovesPreference(0);
  const fill = p.doc().dance.settings.fill;
  assert.deepEqual([fill.beatWeight, fill.ownMovesPreference], [0.5, 0], JSON.stringify(fill));
  assert.throws(() => p.setBeatWeight(-1), (e) => e.name === "OdoriError" && /beatWeight/.test(e.message));
  assert.throws(() => p.setOwnMovesPreference(101), (e) => e.name === "OdoriError" && /ownMovesPreference/.test(e.message));
  assert.equal(p.undo(), true);
  const back = p.doc().dance.settings.fill.ownMovesPreference;
  assert.ok(Math.abs(back - 0.03) < 1e-6, `undo takes the preference back to its default 0.03: ${back}`);
});

test("a bar in 3 is danced with 3-count moves, a bar set back to 4 with 4-count ones", () => {
  const p = salsaProject();
  // The person sets the metre to 3: every bar has 3 beats.
  p.correctGrid({ beatsPerBar: 3 });
  const inThree = p.grid();
  assert.ok(inThree.bars.length > 4 && inThree.bars.every((b) => b.beats === 3), JSON.stringify(inThree.bars[0]));
  while (p.prepareTable(256) < 1) { /* slices of the join table */ }
  const counts = (i) => p.segment(i).countFrames.length - 1;
  assert.ok(p.candidateSegments(0).every((s) => counts(s) === 3), "a bar in 3 shows only 3-count moves");
  p.generate();
  const moves = p.danceView().map((v) => v.state.segment);
  assert.ok(moves.every((s) => counts(s) === 3), `moves in 3: ${moves.map(counts)}`);
  // Each bar's beats, spread over it, are what quality() uses without beats: 3 a bar.
  const own = p.quality();
  assert.ok(Math.abs(own.beats.musicBeatsPerSec - 3 / (inThree.bars[0].endSecs - inThree.bars[0].startSecs)) < 0.1, JSON.stringify(own.beats));
  // Back to 4: the next Generate fills the bars with 4-count moves.
  p.correctGrid({ beatsPerBar: 4 });
  p.generate();
  assert.ok(p.danceView().every((v) => counts(v.state.segment) === 4));
});

test("bar notes name each bar's move and source and word its flags; candidate notes rank clean ones first", () => {
  const p = salsaProject();
  const grid = p.grid();
  const beats = new Float32Array(grid.beatTimesSecs);
  assert.equal(p.barNotes(beats).quality, null, "no readout while no bar holds a move");
  while (p.prepareTable(256) < 1) { /* slices of the join table */ }
  p.generate();
  // A salsa move on bar 2, so an imported source is named.
  let salsa = -1;
  for (let i = 0; i < p.segmentCount; i++) { const s = p.segment(i); if (!s.builtin && !/\(in 3\)/.test(s.name)) { salsa = i; break; } }
  p.setSegment(1, salsa);
  const { quality, notes } = p.barNotes(beats);
  assert.equal(notes.length, grid.bars.length);
  const view = p.danceView();
  notes.forEach((n, i) => {
    assert.equal(n.segment, view[i].state.segment);
    assert.equal(n.name, p.segment(n.segment).name);
    // Each flag is the readout's, in words.
    const bq = quality.bars[i];
    assert.equal(n.flags.some((f) => f.kind === "offBeat"), bq.beats.basMusic - bq.beats.basMusicShifted < 0.1, `bar ${i + 1}`);
    assert.equal(n.flags.some((f) => f.kind === "joinJump"), bq.joinJump != null && bq.joinJump > 1.5, `bar ${i + 1}`);
    assert.ok(n.flags.every((f) => typeof f.words === "string" && f.words.length > 5));
  });
  assert.equal(notes[1].builtin, false);
  assert.equal(notes[1].source, "salsa_01");
  assert.ok(notes.filter((n) => n.builtin).every((n) => n.source === "built-in"));
  const cands = Array.from(p.candidateSegments(4));
  const cn = p.candidateNotes(4, cands, beats);
  assert.deepEqual([...cn.map((n) => n.segment)].sort((a, b) => a - b), [...cands].sort((a, b) => a - b));
  const flags = cn.map((n) => n.flags.length);
  assert.deepEqual(flags, [...flags].sort((a, b) => a - b), "clean candidates first");
  assert.throws(() => p.candidateNotes(9999, cands, beats), (e) => e.name === "OdoriError" && /bar 9999/.test(e.message));
  assert.throws(() => p.candidateNotes(4, [1e7], beats), (e) => e.name === "OdoriError" && /segment/.test(e.message));
});
