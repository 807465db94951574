// The npm package's Project handle (spec §K) from Node: edits by stable move keys, undo/redo,
// `.odori` save → open identical, the manifest + blobs autosave writes, and typed errors for
// bad files (the open project untouched).
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
const { Project, DemoSong, Song, Library } = pkg;

const read = (rel) => new Uint8Array(readFileSync(join(data, rel)));

/** A demo-song envelope computed the way the page does (mono RMS, one band). */
function demoEnvelope() {
  const demo = DemoSong.render(22050);
  const hop = Math.round(demo.sampleRateHz * 0.01);
  const s = demo.samples;
  const n = Math.floor(s.length / hop);
  const band = new Float32Array(n);
  for (let f = 0; f < n; f++) {
    let acc = 0;
    for (let i = f * hop; i < (f + 1) * hop; i++) acc += s[i] * s[i];
    band[f] = Math.sqrt(acc / hop);
  }
  return { hopSecs: hop / demo.sampleRateHz, bands: [band] };
}

function sampleProject() {
  const p = new Project();
  p.setName("node test");
  const env = demoEnvelope();
  p.setSong("demo", undefined, env.hopSecs, env.bands, undefined);
  const src = p.addSource("salsa_10.bvh", read("mocap/cmu-salsa/salsa_10.bvh"), { fpsOverride: 60 });
  p.correctGrid({ nudgeSecs: 0.01 });
  const round = p.candidates(0);
  p.set(1, round[0]);
  p.search(0, [round[1]]);
  p.generate();
  p.setTags({ source: src.id, clip: 0 }, ["salsa", "サルサ"]);
  p.setTexts(["サルサして、喜ぶ。"]);
  return { p, src, round };
}

function poses(p) {
  const lib = new Library();
  const id = p.renderDance(lib);
  const d = lib.clip(id).durationSecs;
  return [0, 0.25, 0.5, 0.75, 1].map((k) => Array.from(lib.jointPositions(id, d * k)));
}

test("a project saves to .odori and opens identical, dance included", () => {
  const { p, src } = sampleProject();
  assert.equal(src.clips.length, 1);
  assert.ok(src.clips[0].cut.segments > 10, "the salsa clip is cut into segments");
  const doc = p.doc();
  assert.equal(doc.dance.bars[1].state, "pinned");
  assert.equal(doc.dance.bars[1].move.kind, "builtin");
  const bytes = p.save();
  const q = Project.open(bytes);
  assert.deepEqual(q.doc(), doc);
  assert.deepEqual(Array.from(q.save()), Array.from(bytes), "saving again gives the same bytes");
  assert.deepEqual(poses(q), poses(p));
  assert.deepEqual(q.grid().beatTimesSecs, p.grid().beatTimesSecs);
  assert.ok(q.undo() && p.undo());
  assert.deepEqual(q.doc(), p.doc(), "undo works the same after the round trip");
});

test("manifest + blobs rebuild the project (what autosave stores)", () => {
  const { p } = sampleProject();
  const manifest = p.manifest();
  const hashes = p.blobHashes();
  assert.equal(hashes.length, 2, "the BVH and the song envelope, once each");
  const store = new Map(hashes.map((h) => [h, p.blob(h)]));
  const q = Project.fromManifest(manifest, (h) => store.get(h));
  assert.deepEqual(q.doc(), p.doc());
  assert.deepEqual(q.missing(), []);
  // A blob the store lost: the rest opens and the missing item is named.
  const bvhHash = p.doc().sources[0].blob;
  const r = Project.fromManifest(manifest, (h) => (h === bvhHash ? undefined : store.get(h)));
  assert.equal(r.missing().length, 1);
  assert.equal(r.missing()[0].what, "motion file salsa_10.bvh");
  assert.throws(() => r.generate(), (e) => e.name === "OdoriError" && e.kind === "missing-blob");
});

test("bad files throw typed errors and leave the open project alone", () => {
  const { p } = sampleProject();
  const good = p.save();
  const before = p.save();
  const cases = [
    [new Uint8Array(0), "empty"],
    [read("mocap/cmu-salsa/salsa_10.bvh").slice(0, 2000), "not-odori"],
    [good.slice(0, good.length >> 1), "truncated"],
  ];
  const flipped = good.slice();
  flipped[flipped.length >> 1] ^= 0xff;
  cases.push([flipped, "corrupt"]);
  for (const [bytes, kind] of cases) {
    assert.throws(() => Project.open(bytes), (e) => e.name === "OdoriError" && e.kind === kind && e.message.length > 10, kind);
  }
  assert.deepEqual(Array.from(p.save()), Array.from(before));
});

test("edits are refused with typed errors and change nothing", () => {
  const { p } = sampleProject();
  const doc = p.doc();
  assert.throws(() => p.set(999, { kind: "builtin", move: doc.dance.bars[1].move.move }), (e) => e.kind === "choreo");
  assert.throws(() => p.correctGrid({ bpm: 9999 }), (e) => e.kind === "music");
  assert.throws(() => p.addSource("x.bvh", new TextEncoder().encode("HIERARCHY\nROOT"), undefined), (e) => e.kind === "bvh" && e.file === "x.bvh");
  assert.throws(() => p.correctGrid({ bmp: 120 }), (e) => e.kind === "bad-argument");
  assert.deepEqual(p.doc(), doc);
});

test("recutClip says what a re-cut meant for the dance, as the document shows it", () => {
  const { p, src } = sampleProject();
  const clip = { source: src.id, clip: 0 };
  const before = p.clips().find((c) => c.clip.source === src.id).cut;
  // Pin bar 2 to a move of this clip's current cut (its tempo: the detected one).
  const key = p.candidates(2).find((k) => k.kind === "cut") ?? { kind: "cut", clip, cutTempoBpm: null, firstCount: 0 };
  p.set(2, key);
  const r = p.recutClip(clip, 100);
  assert.deepEqual([r.clip.tempoBpm, r.clip.tempoDetected], [100, false]);
  // The control: the bars the document holds with a move of the earlier cut, read from it here.
  const earlier = (m) => m && m.kind === "cut" && m.clip.source === src.id && m.cutTempoBpm !== 100;
  const bars = p.doc().dance.bars;
  const pinned = bars.flatMap((b, i) => (earlier(b.move) && b.state === "pinned" ? [i] : []));
  const generated = bars.flatMap((b, i) => (earlier(b.move) && b.state !== "pinned" ? [i] : []));
  const kept = new Set(bars.filter((b) => earlier(b.move)).map((b) => JSON.stringify(b.move))).size;
  assert.ok(pinned.includes(2), `bar 2 pinned to the earlier cut: ${pinned}`);
  assert.deepEqual([r.pinnedBars, r.generatedBars, r.kept, r.removed], [pinned, generated, kept, before.segments - kept]);
  assert.throws(() => p.recutClip(clip, 5000), (e) => e.kind === "choreo" || e.kind === "bad-argument" || e.kind === "not-humanoid");
});

test("bodyVocabulary derives every list of body parts from the regions", () => {
  const v = pkg.bodyVocabulary();
  assert.equal(v.joints.length, 21);
  const byRegion = new Map(v.regions.map((r) => [r.name, r.joints]));
  for (const part of [...v.searchPresets, ...v.compositionParts]) {
    if (part.regions.length === 0) continue; // the whole body: every joint
    const union = [...new Set(part.regions.flatMap((r) => byRegion.get(r)))];
    assert.deepEqual([...part.joints].sort(), union.sort(), part.name);
  }
  assert.deepEqual(v.searchPresets.map((p) => p.name), v.presets.map((p) => p.name));
  assert.ok(v.compositionParts.length >= 6 && v.searchPresets.length === 8);
});

test("summary() states what the page shows, as the document has it; manifestBlobHashes reads a stored manifest", () => {
  const { p } = sampleProject();
  const s = p.summary();
  const doc = p.doc();
  // Checked against the document (the schema only a test may read).
  assert.equal(s.name, doc.name);
  assert.deepEqual(s.sources, doc.sources.map((x) => x.id));
  assert.equal(s.song.fileName, doc.song.fileName);
  assert.equal(s.song.audio, doc.song.audio ?? null);
  assert.deepEqual(s.song.corrections, doc.song.corrections);
  assert.deepEqual(s.tags, doc.tags);
  assert.deepEqual(s.texts, doc.texts);
  assert.equal(s.stickFigures, !!doc.stickFigures);
  assert.equal(s.rho, doc.dance.settings.rho);
  assert.equal(s.musicWeight, doc.dance.settings.fill.musicWeight);
  // The song's key changes with the song, not with its corrections.
  const key = s.song.key;
  p.correctGrid({ nudgeSecs: 0.02 });
  assert.equal(p.summary().song.key, key);
  assert.notDeepEqual(p.summary().song.corrections, s.song.corrections);
  const env = demoEnvelope();
  p.setSong("demo again", undefined, env.hopSecs, env.bands, undefined);
  assert.notEqual(p.summary().song.key, key);
  // A stored manifest's blobs, without opening it: the project's own list.
  assert.deepEqual([...Project.manifestBlobHashes(p.manifest())].sort(), [...p.blobHashes()].sort());
  assert.throws(() => Project.manifestBlobHashes(new TextEncoder().encode("{ not json")), (e) => e.name === "OdoriError" && e.kind === "corrupt");
});

test("importOnModelInto keeps a model's textures (modelFiles, or the library's model): a reopened project draws the dance textured with no library", () => {
  const dir = join(data, "mmd", "miku_v2");
  const folder = ["miku_v2.pmd", "eyeM2.bmp", ...Array.from({ length: 11 }, (_, k) => `toon${String(k).padStart(2, "0")}.bmp`)].map((n) => ({ name: `miku_v2/${n}`, bytes: read(`mmd/miku_v2/${n}`) }));
  const wave = read("mmd/motion/wavefile_v2.vmd");
  const model = folder[0];
  const textures = (lib, report) => lib.clip(report.clips[0].id).meshTextures;
  // The reference: the library's own import of the folder draws the model with its textures.
  const ref = new Library();
  const imported = ref.importFiles(folder, {});
  const character = ref.clip(imported.models[0].characterId);
  assert.ok(character.meshTextures > 0, "the library draws miku_v2 textured");
  // The files given with the model.
  const p = new Project();
  const lib = new Library();
  const r = p.importOnModelInto(lib, "wavefile_v2.vmd", wave, { songOffsetFrames: 160 }, model.name, model.bytes, folder.slice(1));
  assert.equal(textures(lib, r), character.meshTextures, "drawn with as many textures as the library's mesh");
  const kept = p.doc().sources[0].model.textures.map((t) => t.name);
  assert.ok(kept.includes("eyeM2.bmp") && kept.some((n) => /^toon\d\d\.bmp$/.test(n)), JSON.stringify(kept));
  assert.ok(p.summary().mmdFiles.includes("miku_v2/eyeM2.bmp"), JSON.stringify(p.summary().mmdFiles));
  // Left out, they are the library's model's (the same file).
  const q = new Project();
  const r2 = q.importOnModelInto(ref, "wavefile_v2.vmd", wave, { songOffsetFrames: 160 }, model.name, model.bytes);
  assert.deepEqual(q.doc().sources[0].model.textures, p.doc().sources[0].model.textures);
  assert.ok(r2.clips[0].hasMesh);
  // Saved and opened with an empty library: the same textures drawn.
  const o = Project.open(p.save());
  const empty = new Library();
  const again = o.clipsInto(empty, o.doc().sources[0].id);
  assert.equal(textures(empty, again), character.meshTextures);
  // The control: the model alone (no files given, no library model) is drawn untextured.
  const bare = new Project();
  const bareLib = new Library();
  const r3 = bare.importOnModelInto(bareLib, "wavefile_v2.vmd", wave, { songOffsetFrames: 160 }, model.name, model.bytes);
  assert.equal(textures(bareLib, r3), 0);
  assert.deepEqual(bare.doc().sources[0].model.textures ?? [], []);
  assert.ok(r3.warnings.some((w) => /without \d+ of its textures/.test(w)), JSON.stringify(r3.warnings));
});
