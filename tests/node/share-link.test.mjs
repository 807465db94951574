// Share links (www/share.js) in Node with the real engine: a dance generated on the demo song
// is written as a link and rebuilt in a second Project (through the dance panel's engine,
// www/project/dance.js, as the app does), by stable move keys (version 2)
// and from an old version-1 link (segment indices); a song file's identity (a name outside
// ASCII, length, SHA-256) survives the link; damaged links name what is wrong. The browser
// test (tests/browser/share.test.mjs) does the same through the app.
import { test } from "node:test";
import assert from "node:assert/strict";
import { createHash } from "node:crypto";
import { readFileSync, existsSync } from "node:fs";
import { fileURLToPath } from "node:url";
import { dirname, join } from "node:path";
import { danceLink, parseDanceHash, applyDance, sha256Hex } from "../../www/share.js";
import { ProjectDance } from "../../www/project/dance.js";

const root = join(dirname(fileURLToPath(import.meta.url)), "..", "..");
const data = join(root, "..", "shared", "data");
if (!existsSync(data)) throw new Error(`../shared/data is missing: these tests read the shared real data beside the repository (${data})`);
const pkg = await import(join(root, "pkg", "odori.js"));
pkg.initSync({ module: readFileSync(join(root, "pkg", "odori_bg.wasm")) });
const { DemoSong, Project, rmsEnvelope } = pkg;

const demo = DemoSong.render(44100);
const env = rmsEnvelope([demo.samples], demo.sampleRateHz);
const BASE = "https://example.org/odori/?backend=webgl2";

/** A project on the demo song, seen through the dance panel's engine (www/project/dance.js). */
function dancing(project) {
  return new ProjectDance({ project, edited() {}, undo: () => project.undo(), redo: () => project.redo() });
}
function choreographer() {
  const p = new Project();
  p.setSong("Demo song (built-in)", undefined, env.hopSecs, env.bands, undefined, false);
  while (p.prepareTable(512) < 1) { /* the join table, a slice at a time */ }
  return dancing(p);
}
const dance = (ch) => ch.view().map((v) => ({ kind: v.state.kind, segment: v.state.segment ?? null }));

test("a dance on the demo song: link (moves by key) → a fresh choreographer → the same dance; version-1 links still open", () => {
  // Empty bars travel too: a dance with two pinned bars and nothing else opens as it was.
  const half = choreographer();
  half.set(1, half.candidates(1)[2]);
  half.set(6, half.candidates(6)[4]);
  const halfLink = parseDanceHash(new URL(danceLink(half, { demo: true }, BASE)).hash);
  assert.equal(halfLink.items.filter((it) => it.kind === "empty").length, halfLink.bars - 2);
  const half2 = choreographer();
  applyDance(half2, halfLink);
  assert.deepEqual(dance(half2), dance(half));

  const a = choreographer();
  a.set(1, a.candidates(1)[2]);
  a.set(6, a.candidates(6)[4]);
  a.generate();
  const original = dance(a);
  const link = danceLink(a, { demo: true }, BASE);
  const url = new URL(link);
  assert.equal(url.search, "?backend=webgl2");
  const parsed = parseDanceHash(url.hash);
  assert.deepEqual([parsed.version, parsed.song, parsed.bars], ["2", { demo: true }, original.length]);
  assert.equal(parsed.items[1].kind, "pinned");
  assert.deepEqual(Object.keys(parsed.items[1].move).sort(), ["arms", "energy", "mirrored", "step"]);
  assert.equal(parsed.items[2].kind, "generated");
  const b = choreographer();
  assert.deepEqual(applyDance(b, parsed), [], "generation gives the same moves: no bar set by hand");
  assert.deepEqual(dance(b), original);
  // The whole link is one edit of the project: one undo takes it back.
  assert.equal(b.undo(), true);
  assert.ok(dance(b).every((d) => d.kind === "empty"), "one undo empties the dance the link made");
  console.log(`demo-song link: ${link.length} characters for ${original.length} bars`);

  // A version-1 link of the same dance (segment indices in base 36) opens the same.
  const v1 = `#dance=1.demo.${original.length}.` + original.map((d) => (d.kind === "empty" ? "-" : (d.kind === "pinned" ? "p" : "g") + d.segment.toString(36))).join(".");
  const c = choreographer();
  applyDance(c, parseDanceHash(v1));
  assert.deepEqual(dance(c), original);
});

test("a song file's identity survives the link; the hash is the file's SHA-256", async () => {
  const bytes = new Uint8Array(readFileSync(join(data, "music", "sorohanro_-_solo-trumpet-06.hq.ogg")));
  const sha = await sha256Hex(bytes);
  assert.equal(sha, createHash("sha256").update(bytes).digest("hex"));
  const a = choreographer();
  a.generate();
  const song = { name: "トランペット solo #6 (take 2).ogg", durationSecs: 12.3456, sha256: sha };
  const parsed = parseDanceHash(new URL(danceLink(a, song, BASE)).hash);
  assert.deepEqual(parsed.song, { name: song.name, durationSecs: 12.346, sha256: sha });
  // A song not known well enough (no hash) cannot be linked; nor a dance with no bars.
  assert.throws(() => danceLink(a, { name: "x.ogg", durationSecs: 3 }, BASE), /not known well enough/);
  const empty = dancing(new Project());
  assert.throws(() => danceLink(empty, { demo: true }, BASE), /no dance yet/);
});

test("damaged links are refused with what is wrong", () => {
  const cases = [
    ["#dance=3.demo.1.-", /version 3/],
    ["#dance=2.demo.3.-.-", /says 3 bars and holds 2/],
    ["#dance=2.demo.2.-.pstepTouch~swing", /damaged at bar 2/],
    ["#dance=2.demo.1.xstepTouch~swing~low~R", /damaged at bar 1/],
    ["#dance=2.song.1.-", /its song \("song"\)/],
    ["#dance=2.file~bmFtZQ~1000~abc.1.-", /its song/],
    ["#dance=1.file~bmFtZQ~1000~" + "0".repeat(64) + ".1.-", /its song/],
  ];
  for (const [hash, message] of cases) assert.throws(() => parseDanceHash(hash), message, hash);
  assert.equal(parseDanceHash("#other"), null);
  // A key this engine does not have, and a link for another number of bars.
  const ch = choreographer();
  const n = ch.view().length;
  assert.throws(() => applyDance(ch, parseDanceHash(`#dance=2.demo.${n}.` + Array(n).fill("pmoonwalk~swing~low~R").join("."))), /bar 1: the move "moonwalk~swing~low~R" is not among this engine's built-in moves/);
  assert.throws(() => applyDance(ch, parseDanceHash("#dance=2.demo.2.-.-")), /made for 2 bars/);
});

test("MMD moves stay out of a link: their bars go in empty and are named, other own-file moves still refuse", () => {
  const wave = join(data, "mmd/motion/wavefile_v2.vmd");
  const a = choreographer();
  const src = a.project.addSource("wavefile_v2.vmd", new Uint8Array(readFileSync(wave)), { songOffsetFrames: 160 });
  while (a.project.prepareTable(512) < 1) { /* the library grew: the join table again */ }
  const mmd = [];
  for (let i = 0; i < a.segmentCount; i++) { const s = a.segment(i); if (!s.builtin && !s.retired && s.source === "wavefile_v2.vmd") mmd.push(i); }
  assert.ok(mmd.length > 10 && src.clips.length === 1, `WAVEFILE segments: ${mmd.length}`);
  a.set(2, a.candidates(2)[0]);
  a.set(4, mmd[0]);
  a.set(5, mmd[1]);
  const leftOut = [];
  const link = danceLink(a, { demo: true }, BASE, leftOut);
  assert.deepEqual(leftOut, [{ bar: 4, file: "wavefile_v2.vmd" }, { bar: 5, file: "wavefile_v2.vmd" }]);
  const parsed = parseDanceHash(new URL(link).hash);
  assert.deepEqual([parsed.items[4].kind, parsed.items[5].kind], ["empty", "empty"]);
  assert.equal(parsed.items[2].kind, "pinned");
  // The link carries nothing of the file: its name is not in it.
  assert.ok(!/wavefile/i.test(decodeURIComponent(link)), link);
  const b = choreographer();
  applyDance(b, parsed);
  const want = dance(a).map((d, i) => (i === 4 || i === 5 ? { kind: "empty", segment: null } : d));
  assert.deepEqual(dance(b), want);
  // A BVH move (not MMD) still cannot be linked.
  const bvh = a.project.addSource("salsa_01.bvh", new Uint8Array(readFileSync(join(data, "mocap/cmu-salsa/salsa_01.bvh"))), { fpsOverride: 60 });
  assert.equal(bvh.clips.length, 1);
  let salsa = -1;
  for (let i = 0; i < a.segmentCount; i++) { const s = a.segment(i); if (!s.builtin && !s.retired && s.source === "salsa_01.bvh") { salsa = i; break; } }
  assert.ok(salsa >= 0);
  a.set(7, salsa);
  assert.throws(() => danceLink(a, { demo: true }, BASE), /bar 8 .*your own file/);
});
