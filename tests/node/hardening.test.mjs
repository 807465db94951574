// Issue #14: the npm package refuses nonsense at its boundary with an OdoriError naming the
// value (no silent acceptance, no Rust debug text, no wrapped-around integers).
import { test } from "node:test";
import assert from "node:assert/strict";
import { readFileSync } from "node:fs";
import { fileURLToPath } from "node:url";
import { dirname, join } from "node:path";

const root = join(dirname(fileURLToPath(import.meta.url)), "..", "..");
const pkg = await import(join(root, "pkg", "odori.js"));
pkg.initSync({ module: readFileSync(join(root, "pkg", "odori_bg.wasm")) });
const { Library, Project, TextAnimator, SearchIndex, Song, DemoSong, rmsEnvelope } = pkg;

const odori = (kind, re) => (e) => {
  assert.equal(e.name, "OdoriError", String(e));
  assert.equal(e.kind, kind, e.message);
  if (re) assert.match(e.message, re);
  assert.doesNotMatch(e.message, /\{ *\w+:|Some\(|None\b/, "no Rust debug text");
  return true;
};

// A two-joint tail (not a humanoid), 12 frames.
const tail = new TextEncoder().encode(
  "HIERARCHY\nROOT tail\n{\n OFFSET 0 0 0\n CHANNELS 6 Xposition Yposition Zposition Zrotation Yrotation Xrotation\n JOINT tip\n {\n  OFFSET 0 0 40\n  CHANNELS 3 Xrotation Zrotation Yrotation\n  End Site\n  {\n   OFFSET 0 0 40\n  }\n }\n}\nMOTION\nFrames: 12\nFrame Time: 0.0333333\n" +
    "0 20 0 0 0 0 0 0 0\n".repeat(12),
);

test("import options out of range are refused with the value", () => {
  const lib = new Library();
  for (const [unitScale, shown] of [[NaN, "NaN"], [0, "0"], [-1, "-1"], [1e30, "1e30"]]) {
    assert.throws(() => lib.importFile("tail.bvh", tail, { unitScale }), odori("bad-argument", new RegExp(`unitScale = ${shown} is out of range`)));
  }
  assert.equal(lib.size, 0, "nothing added");
  lib.importFile("tail.bvh", tail, { unitScale: 0.01 });
  assert.equal(lib.size, 1);
});

test("a BVH claiming 10^9 frames is refused before allocation", () => {
  const lib = new Library();
  const huge = new TextDecoder().decode(tail).replace("Frames: 12", "Frames: 1000000000");
  assert.throws(() => lib.importFile("huge.bvh", new TextEncoder().encode(huge)), odori("too-large", /1000000000 frames/));
});

test("jointPositions at a time that is not a number is refused", () => {
  const lib = new Library();
  const { id } = lib.addBuiltinDemo();
  for (const t of [NaN, Infinity, -Infinity]) {
    assert.throws(() => lib.jointPositions(id, t), odori("bad-argument", /not a finite number/));
  }
  assert.equal(lib.jointPositions(id, 0.5).length, 63);
});

test("tagClip on a non-humanoid says why in words", () => {
  const lib = new Library();
  const { clips } = lib.importFile("tail.bvh", tail);
  const t = new TextAnimator();
  assert.throws(() => t.tagClip(lib, clips[0].id, ["wag"]), odori("text", /not a humanoid/));
});

test("animateTable with a clip that does not exist is refused", () => {
  const lib = new Library();
  const t = new TextAnimator();
  const r = t.animate(lib, "Taro runs, then jumps.");
  const table = r.elements.map((e) => ({ ...e }));
  table[1].clip = 100000;
  assert.throws(() => t.animateTable(lib, table), odori("not-found", /clip 100000 does not exist/));
});

test("an error about 10,000 characters of unknown words stays short", () => {
  const t = new TextAnimator();
  const text = "Zork. ".repeat(1666);
  assert.throws(() => t.animate(new Library(), text), (e) => {
    odori("text")(e);
    assert.ok(e.message.length < 600, `${e.message.length} characters`);
    assert.match(e.message, /and 1656 more/);
    return true;
  });
});

test("project dance indices: -1 is not bar 4294967295; a dance needs a song", () => {
  const p = new Project();
  // No song: a dance edit is refused with what to do first.
  assert.throws(() => p.candidateSegments(0), odori("no-song", /no song/));
  const demo = DemoSong.render(22050);
  const env = rmsEnvelope([demo.samples], demo.sampleRateHz);
  assert.throws(() => rmsEnvelope([demo.samples], 100), odori("music", /100/));
  p.setSong("demo", undefined, env.hopSecs, env.bands, undefined);
  const bars = p.danceView().length;
  assert.ok(bars > 4, `${bars} bars`);
  for (const [bar, seg] of [[-1, 0], [0.5, 0], [NaN, 0], [0, -3]]) {
    assert.throws(() => p.setSegment(bar, seg), (e) => {
      odori("bad-argument")(e);
      assert.doesNotMatch(e.message, /4294967295/);
      assert.ok(e.message.includes(String(bar)) || e.message.includes(String(seg)), e.message);
      return true;
    });
  }
  const key = p.keyOf(0);
  for (const f of [() => p.candidateSegments(-1), () => p.candidates(-1), () => p.set(-1, key), () => p.unpin(-1), () => p.clear(-1), () => p.resetSearch(-1), () => p.search(-1, [])]) {
    assert.throws(f, odori("bad-argument", /bar -1/));
  }
  assert.throws(() => p.setSegment(bars + 90, 0), odori("choreo", new RegExp(`no bar ${bars + 90}`)));
  assert.throws(() => p.set(0, { kind: "builtin", move: { step: "moonwalk", arms: "swing", energy: "low", mirrored: false } }), (e) => e.name === "OdoriError" && ["bad-argument", "not-found"].includes(e.kind));
  const cand = p.candidateSegments(0);
  p.setSegment(0, cand[0]);
  assert.equal(p.danceView()[0].state.kind, "pinned");
});

test("a progress callback that throws stops the search with its message", () => {
  const lib = new Library();
  const { id } = lib.addBuiltinDemo();
  const index = new SearchIndex();
  index.addFromLibrary(lib, id);
  const query = { clipId: id, startFrame: 0, endFrame: 30 };
  assert.ok(index.search(query, undefined, () => true).matches.length > 0, "control: the search runs");
  let calls = 0;
  assert.throws(
    () => index.search(query, undefined, () => { calls += 1; throw new Error("ui broke"); }),
    odori("callback", /ui broke/),
  );
  assert.equal(calls, 1, "stopped at the first throw");
});

test("song corrections: a nudge of more than a bar and two taps are refused", () => {
  const demo = DemoSong.render(22050);
  const song = Song.fromSamples([demo.samples], demo.sampleRateHz);
  const before = song.grid();
  assert.equal(before.clearBeat, true);
  assert.ok(before.beatClarity > 5);
  assert.throws(() => song.correct({ nudgeSecs: -5000 }), odori("music", /-5000 s is more than a bar/));
  song.correct({ bpm: 120 });
  assert.throws(() => song.correct({ nudgeSecs: -5000 }), (e) => odori("music", /more than a bar/)(e) && !/finite/.test(e.message));
  assert.ok(song.grid().bars.length >= before.bars.length - 1, "grid kept");
  assert.throws(() => song.correct({ tapTimesSecs: [0, 0.5] }), odori("music", /at least 4 taps, got 2/));
});

test("white noise gives a grid marked as no clear beat", () => {
  let x = 1n;
  const rate = 22050;
  const samples = new Float32Array(rate * 30);
  for (let i = 0; i < samples.length; i++) {
    x ^= (x << 13n) & 0xffffffffffffffffn;
    x ^= x >> 7n;
    x ^= (x << 17n) & 0xffffffffffffffffn;
    samples[i] = (Number(x >> 11n) / 2 ** 53 * 2 - 1) * 0.3;
  }
  const g = Song.fromSamples([samples], rate).grid();
  assert.equal(g.clearBeat, false, `clarity ${g.beatClarity} at ${g.bpm} BPM`);
  assert.ok(g.beatClarity < 5);
});
