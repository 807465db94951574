// The error kinds of the npm package, checked against the engine: the list `errorKinds()`
// returns is the one in odori.d.ts and in pkg/README.md, every kind the Rust sources can throw
// is on it, the import errors the core raises on real bad files come out with listed kinds,
// and the player build (pkg/player/) has the same list but none of the authoring classes.
import { test } from "node:test";
import assert from "node:assert/strict";
import { readFileSync, readdirSync, statSync } from "node:fs";
import { fileURLToPath } from "node:url";
import { dirname, join } from "node:path";

const root = join(dirname(fileURLToPath(import.meta.url)), "..", "..");
const full = await import(join(root, "pkg", "odori.js"));
full.initSync({ module: readFileSync(join(root, "pkg", "odori_bg.wasm")) });
const player = await import(join(root, "pkg", "player", "odori_player.js"));
player.initSync({ module: readFileSync(join(root, "pkg", "player", "odori_player_bg.wasm")) });

const kinds = full.errorKinds();

function rustFiles(dir) {
  return readdirSync(dir).flatMap((f) => {
    const p = join(dir, f);
    return statSync(p).isDirectory() ? rustFiles(p) : p.endsWith(".rs") ? [p] : [];
  });
}

test("errorKinds() is the same in both builds, has no duplicates, and equals the .d.ts union", () => {
  assert.ok(kinds.length >= 10, `only ${kinds.length} kinds`);
  assert.equal(new Set(kinds).size, kinds.length);
  assert.deepEqual(player.errorKinds(), kinds);
  for (const [file] of [["odori.d.ts"], ["player/odori_player.d.ts"]]) {
    const dts = readFileSync(join(root, "pkg", file), "utf8");
    const union = dts.match(/export type OdoriErrorKind =([\s\S]*?);/);
    assert.ok(union, `${file} has no OdoriErrorKind`);
    const listed = [...union[1].matchAll(/\|\s*"([a-z-]+)"/g)].map((m) => m[1]);
    assert.deepEqual(listed, kinds, `${file}'s OdoriErrorKind`);
    assert.match(dts, /kind: OdoriErrorKind;/, `${file}: OdoriError.kind is typed`);
  }
});

test("pkg/README.md documents every kind", () => {
  const readme = readFileSync(join(root, "pkg", "README.md"), "utf8");
  const missing = kinds.filter((k) => !readme.includes(`\`"${k}"\``));
  assert.deepEqual(missing, [], "kinds missing from pkg/README.md");
});

test("every kind the Rust sources throw is on the list", () => {
  const thrown = new Set();
  for (const f of rustFiles(join(root, "crate", "web", "src"))) {
    const src = readFileSync(f, "utf8");
    for (const m of src.matchAll(/OdoriError::new\(\s*"([a-z-]+)"/g)) thrown.add(m[1]);
    // Kinds chosen by a match before OdoriError::new(kind, ...).
    for (const m of src.matchAll(/let kind = match[\s\S]*?\};/g)) for (const k of m[0].matchAll(/=> "([a-z-]+)"/g)) thrown.add(k[1]);
  }
  // The core's own kinds (ImportError::kind).
  const core = readFileSync(join(root, "crate", "core", "src", "import", "mod.rs"), "utf8");
  const kindFn = core.match(/pub fn kind\(&self\)[\s\S]*?\n    \}/);
  assert.ok(kindFn, "ImportError::kind not found in the core");
  for (const m of kindFn[0].matchAll(/=> "([a-z-]+)"/g)) thrown.add(m[1]);
  assert.ok(thrown.size >= 10, `found only ${[...thrown]}`);
  const unlisted = [...thrown].filter((k) => !kinds.includes(k));
  assert.deepEqual(unlisted, [], "kinds thrown by the Rust sources but not in errorKinds()");
});

test("bad files and bad arguments throw listed kinds (both builds)", () => {
  const cases = [
    ["empty.bvh", new Uint8Array(0), "empty"],
    ["noise.bin", new Uint8Array([1, 2, 3, 4, 5, 6, 7, 8]), "unknown-format"],
    ["bad.bvh", new TextEncoder().encode("HIERARCHY\nROOT Hips\n{\n  OFFSET 0 0\n"), "bvh"],
    ["bad.gltf", new TextEncoder().encode('{"asset": 5}'), "gltf"],
  ];
  for (const pkg of [full, player]) {
    const lib = new pkg.Library();
    for (const [name, bytes, kind] of cases) {
      assert.throws(() => lib.importFile(name, bytes), (e) => {
        assert.equal(e.name, "OdoriError");
        assert.equal(e.kind, kind, `${name}: ${e.message}`);
        assert.equal(e.file, name);
        return kinds.includes(e.kind);
      });
    }
    assert.throws(() => lib.jointPositions(99, 0), (e) => e.kind === "not-found" && kinds.includes(e.kind));
    assert.throws(() => lib.importFile("x.bvh", new Uint8Array(1), { fpsOverrid: 60 }), (e) => e.kind === "bad-argument");
  }
});

test("the player build keeps Library and Viewer and leaves authoring out", () => {
  assert.equal(full.hasAuthoring(), true);
  assert.equal(player.hasAuthoring(), false);
  for (const name of ["Song", "DemoSong", "SearchIndex", "TextAnimator", "Project"]) {
    assert.equal(typeof full[name], "function", `the full engine has ${name}`);
    assert.equal(player[name], undefined, `the player build has no ${name}`);
  }
  // One handle holds a dance: the Choreographer it replaced is gone from both builds.
  assert.equal(full.Choreographer, undefined, "the full engine has no Choreographer (Project replaced it)");
  assert.equal(player.Choreographer, undefined);
  // The .d.ts says so too: its handles are Project (the dance) and stateless helpers (song,
  // search, text) besides Library and Viewer. A new handle belongs here only if it holds no dance.
  const dts = readFileSync(join(root, "pkg", "odori.d.ts"), "utf8");
  assert.doesNotMatch(dts, /Choreographer/);
  const classes = [...dts.matchAll(/^export class (\w+)/gm)].map((m) => m[1]).sort();
  assert.deepEqual(classes, ["DemoSong", "Library", "Project", "SearchIndex", "Song", "TextAnimator", "Viewer"], "the full engine's handles");
  const lib = new player.Library();
  const demo = lib.addBuiltinDemo();
  assert.equal(demo.humanoid.kind, "complete");
  assert.equal(lib.jointPositions(demo.id, 0.5).length, demo.points * 3);
  const fullSize = statSync(join(root, "pkg", "odori_bg.wasm")).size;
  const playerSize = statSync(join(root, "pkg", "player", "odori_player_bg.wasm")).size;
  console.log(`wasm: full ${fullSize} bytes, player ${playerSize} bytes (${(playerSize / fullSize * 100).toFixed(0)} %)`);
  assert.ok(playerSize < fullSize * 0.9, `the player build (${playerSize} B) is not much smaller than the full one (${fullSize} B)`);
});
