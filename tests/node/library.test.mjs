// The npm package (pkg/) used from Node, as a consumer would: the Library API, typed errors.
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
const { Library } = pkg;

const read = (rel) => new Uint8Array(readFileSync(join(data, rel)));

test("package.json describes the module", () => {
  const meta = JSON.parse(readFileSync(join(root, "pkg", "package.json"), "utf8"));
  assert.equal(meta.name, "odori");
  assert.equal(meta.module, "odori.js");
  assert.equal(meta.types, "odori.d.ts");
  const dts = readFileSync(join(root, "pkg", "odori.d.ts"), "utf8");
  for (const name of ["class Library", "class Viewer", "interface ClipInfo", "interface OdoriError", "importFile("]) {
    assert.ok(dts.includes(name), `odori.d.ts lacks ${name}`);
  }
});

test("built-in demo clip moves and is humanoid", () => {
  const lib = new Library();
  const info = lib.addBuiltinDemo();
  assert.equal(info.source, "built-in");
  assert.equal(info.humanoid.kind, "complete");
  assert.equal(info.points, 21, "the 21 canonical joints");
  assert.equal(info.joints, 19, "toes are tips");
  const a = lib.jointPositions(info.id, 0);
  const b = lib.jointPositions(info.id, 0.5);
  assert.equal(a.length, 21 * 3);
  const moved = a.reduce((s, v, i) => s + Math.abs(v - b[i]), 0);
  assert.ok(moved > 0.3, `joints moved ${moved}`);
});

test("BVH import with a frame-rate override", () => {
  const lib = new Library();
  const report = lib.importFile("salsa_01.bvh", read("mocap/cmu-salsa/salsa_01.bvh"), { fpsOverride: 60 });
  assert.equal(report.clips.length, 1);
  const c = report.clips[0];
  assert.equal(c.name, "salsa_01");
  assert.equal(c.fps, 60);
  assert.equal(c.frames, 2243);
  assert.ok(Math.abs(c.durationSecs - (2243 - 1) / 60) < 1e-3, "duration spans the frames: (frames - 1) / fps");
  assert.equal(c.format, "bvh");
  assert.notEqual(c.humanoid.kind, "notHumanoid");
  const p = lib.jointPositions(c.id, 1.0);
  assert.equal(c.joints, 43);
  assert.equal(c.points, 57, "43 joints and 14 end sites");
  assert.equal(p.length, c.points * 3);
  assert.equal(lib.bones(c.id).length, (c.points - 1) * 2);
  // Metres, Y up: the figure's top is between 1 and 2.2 m above its lowest joint.
  const ys = p.filter((_, i) => i % 3 === 1);
  const h = Math.max(...ys) - Math.min(...ys);
  assert.ok(h > 1.0 && h < 2.2, `height ${h}`);
});

test("glTF: RobotExpressive gives 14 clips with a mesh; the Fox is not humanoid", () => {
  const lib = new Library();
  const robot = lib.importFile("RobotExpressive.glb", read("gltf/RobotExpressive.glb"));
  assert.equal(robot.clips.length, 14);
  assert.ok(robot.clips.every((c) => c.hasMesh && c.format === "gltf"));
  assert.ok(robot.clips.some((c) => c.name === "Dance"));
  const fox = lib.importFile("Fox.glb", read("gltf/Fox.glb"));
  assert.equal(fox.clips.length, 3);
  assert.equal(fox.clips[0].humanoid.kind, "notHumanoid");
  assert.match(fox.clips[0].humanoid.reason, /upright|legs/);
  assert.equal(lib.size, 17);
});

test("bad files throw OdoriError with kind and file, and the library keeps what it had", () => {
  const lib = new Library();
  lib.addBuiltinDemo();
  const cases = [
    ["empty.bvh", new Uint8Array(0), "empty"],
    ["noise.glb", Uint8Array.from({ length: 512 }, (_, i) => (i * 7919) % 251), "unknown-format"],
    ["cut.bvh", read("mocap/cmu-salsa/salsa_02.bvh").slice(0, 40000), "bvh"],
    ["half.glb", read("gltf/Fox.glb").slice(0, 20000), "gltf"],
  ];
  for (const [name, bytes, kind] of cases) {
    assert.throws(() => lib.importFile(name, bytes), (e) => {
      assert.equal(e.name, "OdoriError");
      assert.equal(e.kind, kind, e.message);
      assert.equal(e.file, name);
      assert.ok(e.message.startsWith(name), e.message);
      return true;
    });
  }
  assert.equal(lib.size, 1);
  assert.throws(() => lib.importFile("x.bvh", read("mocap/cmu-salsa/salsa_02.bvh"), { fpsOverride: -5 }), (e) => e.kind === "bad-argument");
  assert.throws(() => lib.importFile("x.bvh", read("mocap/cmu-salsa/salsa_02.bvh"), { fps: 60 }), (e) => e.kind === "bad-argument" && /fps/.test(e.message));
  assert.throws(() => lib.clip(999), (e) => e.kind === "not-found");
});
