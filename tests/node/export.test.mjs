// Export (spec §M) checked by tools no one here wrote: every GLB the npm package writes (the
// built-in dance on the built-in body, Xbot and RobotExpressive on their own mesh) passes the
// Khronos glTF validator with 0 errors and 0 warnings, and three.js (GLTFLoader +
// AnimationMixer; BVHLoader for BVH) puts the joints where the product does: within 1 cm per
// metre of body height for GLB and 1 mm per metre for BVH, at 10 times through each clip.
import { test } from "node:test";
import assert from "node:assert/strict";
import { readFileSync, existsSync } from "node:fs";
import { fileURLToPath } from "node:url";
import { dirname, join } from "node:path";
import validator from "gltf-validator";
import * as THREE from "three";
import { GLTFLoader } from "three/examples/jsm/loaders/GLTFLoader.js";
import { BVHLoader } from "three/examples/jsm/loaders/BVHLoader.js";
import { texturedBox, QUADRANTS, CHECKER } from "./textured-glb.mjs";

const root = join(dirname(fileURLToPath(import.meta.url)), "..", "..");
const data = join(root, "..", "shared", "data");
if (!existsSync(data)) throw new Error(`../shared/data is missing: these tests read the shared real data beside the repository (${data})`);
const pkg = await import(join(root, "pkg", "odori.js"));
pkg.initSync({ module: readFileSync(join(root, "pkg", "odori_bg.wasm")) });
const { Library } = pkg;
const read = (rel) => new Uint8Array(readFileSync(join(data, rel)));

/** The cases: [label, library, clip id]. */
function cases() {
  const lib = new Library();
  const demo = lib.addBuiltinDemo().id;
  const out = [["built-in dance on the built-in body", lib, demo]];
  for (const file of ["gltf/Xbot.glb", "gltf/RobotExpressive.glb"]) {
    const report = lib.importFile(file, read(file));
    // The longest animation of each character (Xbot's are short poses; RobotExpressive's Dance).
    const clip = report.clips.reduce((a, b) => (b.frames > a.frames ? b : a));
    out.push([`${file} '${clip.name}'`, lib, clip.id]);
    // The built-in dance retargeted onto the character, exported on its own mesh and skin.
    const on = lib.putOnCharacter(demo, clip.id);
    assert.equal(on.format, "character");
    assert.ok(on.hasMesh, `${file}: the retargeted clip is drawn skinned`);
    out.push([`built-in dance on ${file}`, lib, on.id]);
  }
  return out;
}

/** Body height of a clip at time 0 from the product's own joint positions (y extent). */
function heightOf(lib, id) {
  const p = lib.jointPositions(id, 0);
  let lo = Infinity, hi = -Infinity;
  for (let i = 1; i < p.length; i += 3) { lo = Math.min(lo, p[i]); hi = Math.max(hi, p[i]); }
  return hi - lo;
}

/** Largest distance between the product's joint positions and three.js's, over 10 times. */
function worstAgainstThree(lib, id, object3d, animation, scale, lookUp) {
  const info = lib.clip(id);
  const names = lib.jointNames(id);
  const mixer = new THREE.AnimationMixer(object3d);
  mixer.clipAction(animation).play();
  const v = new THREE.Vector3();
  let worst = 0, compared = 0;
  for (let k = 0; k < 10; k++) {
    const t = (info.durationSecs - 1 / info.fps) * k / 9;
    mixer.setTime(t);
    object3d.updateMatrixWorld(true);
    const ours = lib.jointPositions(id, t);
    names.forEach((name, j) => {
      const node = lookUp(name);
      if (!node) return;
      node.getWorldPosition(v).multiplyScalar(scale);
      worst = Math.max(worst, Math.hypot(v.x - ours[3 * j], v.y - ours[3 * j + 1], v.z - ours[3 * j + 2]));
      compared++;
    });
  }
  return { worst, compared };
}

/** Textured characters: the Fox (PNG, LINEAR_MIPMAP_LINEAR) and boxes made in the test (a KHR_texture_transform; a nearest-filtered clamped sampler; a checker). */
function texturedCases() {
  const lib = new Library();
  const fox = lib.importFile("Fox.glb", read("gltf/Fox.glb")).clips[0];
  const quad = lib.importFile("quadrants.glb", texturedBox({ image: QUADRANTS(), sampler: { magFilter: 9728, minFilter: 9728, wrapS: 33071, wrapT: 33648 }, transform: { offset: [0.5, 0], rotation: 0.25, scale: [0.5, 0.5] } })).clips[0];
  const checker = lib.importFile("checker.glb", texturedBox({ image: CHECKER(64), sampler: {} })).clips[0];
  return [["gltf/Fox.glb (textured)", lib, fox.id], ["box with a texture transform", lib, quad.id], ["box with a default sampler", lib, checker.id]];
}

test("every exported GLB passes the Khronos glTF validator with no errors or warnings", async () => {
  for (const [label, lib, id] of [...cases(), ...texturedCases()]) {
    const glb = lib.exportGlb(id);
    assert.ok(glb instanceof Uint8Array && glb.length > 1000, `${label}: exportGlb returns the bytes`);
    const report = await validator.validateBytes(glb, { maxIssues: 100 });
    const issues = report.issues;
    const bad = issues.messages.filter((m) => m.severity <= 1).map((m) => `${m.code} ${m.pointer}: ${m.message}`);
    console.log(`${label}: ${glb.length} bytes, ${issues.numErrors} errors, ${issues.numWarnings} warnings, ${issues.numInfos} infos`);
    assert.equal(issues.numErrors, 0, `${label}: ${bad.join("; ")}`);
    assert.equal(issues.numWarnings, 0, `${label}: ${bad.join("; ")}`);
    assert.ok(report.info.animationCount === 1 && report.info.hasSkins, `${label}: one animation and a skin`);
    if (label.includes("textured") || label.includes("box")) {
      assert.ok(report.info.hasTextures, `${label}: the export has its texture`);
      assert.equal(report.info.resources.filter((r) => r.pointer.startsWith("/images/")).length, 1, `${label}: one image`);
    }
    if (label.includes("transform")) assert.deepEqual(report.info.extensionsUsed, ["KHR_texture_transform"], `${label}: the transform's extension is named`);
  }
});

test("three.js GLTFLoader + AnimationMixer reproduce the product's joints within 1 cm per metre", async () => {
  for (const [label, lib, id] of cases()) {
    const glb = lib.exportGlb(id);
    const gltf = await new GLTFLoader().parseAsync(glb.buffer.slice(glb.byteOffset, glb.byteOffset + glb.byteLength), "");
    let skinned = 0;
    gltf.scene.traverse((o) => { if (o.isSkinnedMesh) skinned++; });
    assert.ok(skinned > 0, `${label}: three.js sees a skinned mesh`);
    const lookUp = (name) => gltf.scene.getObjectByName(THREE.PropertyBinding.sanitizeNodeName(name));
    const { worst, compared } = worstAgainstThree(lib, id, gltf.scene, gltf.animations[0], 1, lookUp);
    const height = heightOf(lib, id);
    console.log(`${label}: three.js vs product, worst joint ${(worst * 1000).toFixed(3)} mm over ${compared} joint samples (height ${height.toFixed(2)} m)`);
    assert.ok(compared >= 10 * 20, `${label}: only ${compared} joints compared`);
    assert.ok(worst < 0.01 * height, `${label}: worst ${worst} m > 1 cm per metre of ${height} m`);
  }
});

test("a BVH clip exported on the built-in body (as the app draws it) has the body, passes the validator and plays in three.js", async () => {
  const lib = new Library();
  const salsa = lib.importFile("salsa_01.bvh", read("mocap/cmu-salsa/salsa_01.bvh"), { fpsOverride: 60 }).clips[0];
  // Without "builtin" it is the clip's own skeleton, with no mesh (the control).
  const bare = await validator.validateBytes(lib.exportGlb(salsa.id), { maxIssues: 100 });
  assert.ok(!bare.info.hasSkins, "auto: a BVH clip goes out on its own skeleton, no skin");
  const glb = lib.exportGlb(salsa.id, { character: "builtin", startSecs: 0, endSecs: 10 });
  const report = await validator.validateBytes(glb, { maxIssues: 100 });
  const bad = report.issues.messages.filter((m) => m.severity <= 1).map((m) => `${m.code} ${m.pointer}: ${m.message}`);
  console.log(`salsa_01 on the built-in body: ${glb.length} bytes, ${report.issues.numErrors} errors, ${report.issues.numWarnings} warnings`);
  assert.equal(report.issues.numErrors + report.issues.numWarnings, 0, bad.join("; "));
  assert.ok(report.info.animationCount === 1 && report.info.hasSkins, "one animation and a skin");
  // Read back by the product: the built-in body's canonical rig, 10 s of the salsa's 60 fps.
  const back = lib.importFile("salsa_on_body.glb", glb).clips[0];
  assert.ok(back.hasMesh && back.humanoid.kind !== "notHumanoid", JSON.stringify(back));
  assert.ok(Math.abs(back.durationSecs - 10) < 0.1, `${back.durationSecs} s`);
  // And by three.js, which puts the joints where the product's re-import does.
  const gltf = await new GLTFLoader().parseAsync(glb.buffer.slice(glb.byteOffset, glb.byteOffset + glb.byteLength), "");
  const lookUp = (name) => gltf.scene.getObjectByName(THREE.PropertyBinding.sanitizeNodeName(name));
  const { worst, compared } = worstAgainstThree(lib, back.id, gltf.scene, gltf.animations[0], 1, lookUp);
  const height = heightOf(lib, back.id);
  console.log(`salsa_01 on the built-in body: three.js vs product, worst joint ${(worst * 1000).toFixed(3)} mm over ${compared} samples (height ${height.toFixed(2)} m)`);
  assert.ok(compared >= 10 * 20 && worst < 0.01 * height, `worst ${worst} m over ${compared}`);
});

test("BVH re-imports into the product and into three.js BVHLoader within 1 mm per metre", async () => {
  const lib = new Library();
  const salsa = lib.importFile("salsa_01.bvh", read("mocap/cmu-salsa/salsa_01.bvh"), { fpsOverride: 60 }).clips[0];
  const demo = lib.addBuiltinDemo();
  for (const clip of [demo, salsa]) {
    const bytes = lib.exportBvh(clip.id);
    const text = new TextDecoder().decode(bytes);
    assert.match(text, /Frame Time: 0\.0\d{8}/);
    const height = heightOf(lib, clip.id);
    // Into the product.
    const back = lib.importFile(`${clip.name}.bvh`, bytes).clips[0];
    assert.equal(back.frames, clip.frames);
    assert.ok(Math.abs(back.fps - clip.fps) < 1e-3 * clip.fps, `fps ${back.fps} vs ${clip.fps}`);
    const namesBack = lib.jointNames(back.id);
    let worstOurs = 0;
    for (let k = 0; k < 10; k++) {
      const t = (clip.durationSecs - 1 / clip.fps) * k / 9;
      const a = lib.jointPositions(clip.id, t), b = lib.jointPositions(back.id, t);
      lib.jointNames(clip.id).forEach((n, j) => {
        const i = namesBack.indexOf(n);
        worstOurs = Math.max(worstOurs, Math.hypot(a[3 * j] - b[3 * i], a[3 * j + 1] - b[3 * i + 1], a[3 * j + 2] - b[3 * i + 2]));
      });
    }
    // Into three.js (file units are centimetres).
    const parsed = new BVHLoader().parse(text);
    const rootBone = parsed.skeleton.bones[0];
    const lookUp = (name) => parsed.skeleton.bones.find((b) => b.name === name);
    const { worst, compared } = worstAgainstThree(lib, clip.id, rootBone, parsed.clip, 0.01, lookUp);
    console.log(`BVH '${clip.name}': product re-import worst ${(worstOurs * 1000).toFixed(4)} mm, three.js worst ${(worst * 1000).toFixed(4)} mm (${compared} samples, height ${height.toFixed(2)} m)`);
    assert.ok(worstOurs < 0.001 * height, `product re-import: worst ${worstOurs} m`);
    assert.ok(compared >= 10 * 20, `only ${compared} joints compared`);
    assert.ok(worst < 0.001 * height, `three.js: worst ${worst} m > 1 mm per metre of ${height} m`);
  }
});

test("bad export requests throw typed OdoriErrors and change nothing", () => {
  const lib = new Library();
  const xbot = lib.importFile("Xbot.glb", read("gltf/Xbot.glb")).clips[0];
  const before = lib.size;
  assert.throws(() => lib.exportGlb(9999), (e) => e.name === "OdoriError" && e.kind === "not-found");
  assert.throws(() => lib.exportGlb(xbot.id, { character: "builtin" }), (e) => e.kind === "export-needs-canonical" && /canonical/.test(e.message));
  assert.throws(() => lib.exportGlb(xbot.id, { charakter: "none" }), (e) => e.kind === "bad-argument" && /charakter/.test(e.message));
  assert.throws(() => lib.exportBvh(xbot.id, { startSecs: 5, endSecs: 1 }), (e) => e.kind === "bad-argument");
  const demoId = lib.addBuiltinDemo().id;
  const foxClips = lib.importFile("Fox.glb", read("gltf/Fox.glb")).clips;
  const fox = foxClips[0];
  const n = lib.size;
  assert.throws(() => lib.putOnCharacter(demoId, demoId), (e) => e.kind === "character-no-skin");
  assert.throws(() => lib.putOnCharacter(demoId, fox.id), (e) => e.kind === "character-not-humanoid" && /Fox/.test(e.message));
  assert.equal(lib.size, n, "a refused character adds nothing");
  lib.remove(demoId);
  for (const c of foxClips) lib.remove(c.id);
  assert.equal(lib.size, before);
  // A range of the clip exports only those frames.
  const demo = lib.addBuiltinDemo();
  const part = new TextDecoder().decode(lib.exportBvh(demo.id, { startSecs: 1, endSecs: 2 }));
  assert.match(part, new RegExp(`Frames: ${Math.round(demo.fps) + 1}\\n`));
});
