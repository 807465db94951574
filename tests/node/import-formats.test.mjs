// The files the app opens are stated once, by the engine (`importFormats()`), and the page's
// file filters and its "not a file Odori reads" message come from that list (`www/ui/files.js`
// `fileFormats`): the list names every format the importer's own error names, each format on it
// imports a real file of its kind, and the page's message names every format on it.
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
const { fileFormats } = await import(join(root, "www", "ui", "files.js"));
const read = (rel) => new Uint8Array(readFileSync(join(data, rel)));

const formats = pkg.importFormats();

test("importFormats() names every format the importer's own error names, once each", () => {
  assert.equal(new Set(formats.map((f) => f.extension)).size, formats.length, JSON.stringify(formats));
  const lib = new pkg.Library();
  let message = "";
  try {
    lib.importFile("notes.txt", new TextEncoder().encode("just some notes"));
  } catch (e) {
    assert.equal(e.kind, "unknown-format", e.message);
    message = e.message;
  }
  // "notes.txt: not a BVH, glTF, GLB or VMD file (...)": the importer's list (the core's Format::ALL).
  const named = /not a (.*?) file/.exec(message)?.[1]?.split(/, | or /);
  assert.ok(named && named.length >= 4, message);
  for (const name of named) {
    const f = formats.find((x) => x.name === name);
    assert.ok(f && f.alone, `${name} (named by the importer's error) is not on importFormats() as read alone: ${JSON.stringify(formats)}`);
  }
  // and nothing else is read alone.
  assert.deepEqual(formats.filter((f) => f.alone).map((f) => f.name).sort(), [...named].sort());
});

test("each format on the list imports a real file of its kind", () => {
  const samples = { bvh: "mocap/cmu-indian/indian_04.bvh", glb: "gltf/Xbot.glb", vmd: "mmd/motion/tokino_kakera.vmd", pmd: "mmd/low_poly/miku.pmd", pmx: "mmd/gene/Gene_light.pmx" };
  const lib = new pkg.Library();
  for (const f of formats) {
    const rel = samples[f.extension];
    if (!rel) continue; // glTF (text) and zip: no such file in ../shared/data
    const name = rel.split("/").pop();
    assert.ok(name.toLowerCase().endsWith(`.${f.extension}`));
    if (f.alone) {
      const report = lib.importFile(name, read(rel));
      assert.ok(report.clips.length >= 1, `${name}: ${JSON.stringify(report)}`);
    }
    if (f.mmd) {
      const r = lib.importFiles([{ name, bytes: read(rel) }]);
      // A model given without its folder lacks its textures: kept, and said so.
      assert.deepEqual(r.problems.filter((p) => p.kind !== "mmd-missing-textures"), [], `${name}`);
      assert.ok(r.models.length + r.motions.length >= 1, `${name}: ${JSON.stringify(Object.keys(r))}`);
    }
  }
  // Every extension but the two above has a sample.
  assert.deepEqual(formats.map((f) => f.extension).filter((e) => !samples[e]).sort(), ["gltf", "zip"]);
});

test("the page's filters and message come from the list", () => {
  const page = fileFormats(formats);
  const message = page.message("song.mp3");
  assert.ok(message.startsWith("song.mp3: "), message);
  for (const f of formats) {
    assert.ok(message.includes(f.name), `the message does not name ${f.name}: ${message}`);
    const name = `Clip.${f.extension.toUpperCase()}`;
    assert.equal(page.accepts(name) || page.isMmd(name), true, name);
    assert.equal(page.isMmd(name), f.mmd, name);
    assert.ok(page.accept.split(",").includes(`.${f.extension}`), page.accept);
  }
  assert.equal(page.isMmdModel("a.pmx") && page.isMmdModel("b.zip") && !page.isMmdModel("c.vmd") && !page.isMmdModel("d.bvh"), true);
  for (const other of ["song.mp3", "notes.txt", "noextension"]) assert.equal(page.accepts(other) || page.isMmd(other), false, other);
  // Control: a format the engine stops listing is no longer named or taken by the page.
  const fewer = fileFormats(formats.filter((f) => f.extension !== "bvh"));
  assert.ok(!fewer.message("x.mp3").includes("BVH") && !fewer.accepts("a.bvh"));
});
