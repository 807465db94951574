// VRM animation export (spec §M, `.vrma`) checked by the players VRM users have: the
// `.vrma` the npm package writes passes the Khronos glTF validator with no errors, and in
// headless Chromium pixiv's `@pixiv/three-vrm-animation` (VRMAnimationLoaderPlugin +
// createVRMAnimationClip) plays it on a VRM 1.0 avatar loaded by `@pixiv/three-vrm`, with
// three.js's AnimationMixer. The avatar is made here from the product's own GLB of the
// built-in body (its nodes are the canonical joints) by adding a `VRMC_vrm` humanoid; the
// avatar's joints are then compared with the product's own at 10 times: within 1 cm per
// metre of body height. Clips: the built-in dance and a text animation (both on the canonical
// skeleton), and CMU salsa (its own rig, carried onto the canonical one by the export; there
// the product's reference is the `.vrma` re-imported into the product).
import { test, before, after } from "node:test";
import assert from "node:assert/strict";
import { readFileSync } from "node:fs";
import { join } from "node:path";
import * as esbuild from "esbuild";
import validator from "gltf-validator";
import { root, data, launch } from "./harness.mjs";

const pkg = await import(join(root, "pkg", "odori.js"));
pkg.initSync({ module: readFileSync(join(root, "pkg", "odori_bg.wasm")) });
const { Library, TextAnimator } = pkg;

/** The VRM 1.0 humanoid bone of a canonical joint (the names are VRM's but two). */
const vrmBone = (name) => ({ leftForearm: "leftLowerArm", rightForearm: "rightLowerArm", leftToe: "leftToes", rightToe: "rightToes" })[name] ?? name;

/** GLB → { json, bin } and back (chunks padded to 4 bytes: JSON with spaces, BIN with zeros). */
function splitGlb(bytes) {
  const dv = new DataView(bytes.buffer, bytes.byteOffset, bytes.byteLength);
  const jsonLen = dv.getUint32(12, true);
  const json = JSON.parse(new TextDecoder().decode(bytes.subarray(20, 20 + jsonLen)));
  const binLen = dv.getUint32(20 + jsonLen, true);
  const bin = bytes.subarray(28 + jsonLen, 28 + jsonLen + binLen);
  return { json, bin };
}
function joinGlb(json, bin) {
  let text = new TextEncoder().encode(JSON.stringify(json));
  const jsonPad = (4 - (text.length % 4)) % 4;
  const total = 12 + 8 + text.length + jsonPad + 8 + bin.length;
  const out = new Uint8Array(total);
  const dv = new DataView(out.buffer);
  dv.setUint32(0, 0x46546c67, true); dv.setUint32(4, 2, true); dv.setUint32(8, total, true);
  dv.setUint32(12, text.length + jsonPad, true); dv.setUint32(16, 0x4e4f534a, true);
  out.set(text, 20); out.fill(0x20, 20 + text.length, 20 + text.length + jsonPad);
  const b = 20 + text.length + jsonPad;
  dv.setUint32(b, bin.length, true); dv.setUint32(b + 4, 0x004e4942, true);
  out.set(bin, b + 8);
  return out;
}

/** A VRM 1.0 avatar: the product's GLB of the built-in body with a `VRMC_vrm` humanoid. */
function builtinVrm(lib, canonicalClipId) {
  const { json, bin } = splitGlb(lib.exportGlb(canonicalClipId, { character: "builtin" }));
  const names = lib.jointNames(canonicalClipId);
  const humanBones = {};
  json.nodes.forEach((n, i) => { if (names.includes(n.name)) humanBones[vrmBone(n.name)] = { node: i }; });
  delete json.animations;
  json.extensionsUsed = [...(json.extensionsUsed ?? []), "VRMC_vrm"];
  json.extensions = {
    ...(json.extensions ?? {}),
    VRMC_vrm: {
      specVersion: "1.0",
      meta: { name: "Odori built-in body", version: "1", authors: ["Odori tests"], licenseUrl: "https://vrm.dev/licenses/1.0/", avatarPermission: "onlyAuthor", commercialUsage: "personalNonProfit" },
      humanoid: { humanBones },
    },
  };
  return { vrm: joinGlb(json, bin), bones: Object.keys(humanBones).length };
}

const PAGE_SCRIPT = `
import * as THREE from "three";
import { GLTFLoader } from "three/examples/jsm/loaders/GLTFLoader.js";
import { VRMLoaderPlugin } from "@pixiv/three-vrm";
import { VRMAnimationLoaderPlugin, createVRMAnimationClip } from "@pixiv/three-vrm-animation";
const bytes = (b64) => Uint8Array.from(atob(b64), (c) => c.charCodeAt(0)).buffer;
window.playVrma = async (vrmB64, vrmaB64, times, boneNames) => {
  const loader = new GLTFLoader();
  loader.register((parser) => new VRMLoaderPlugin(parser));
  loader.register((parser) => new VRMAnimationLoaderPlugin(parser));
  const vrm = (await loader.parseAsync(bytes(vrmB64), "")).userData.vrm;
  const anim = (await loader.parseAsync(bytes(vrmaB64), "")).userData.vrmAnimations;
  if (!vrm) throw new Error("three-vrm did not load the avatar");
  if (!anim || !anim.length) throw new Error("three-vrm-animation found no VRM animation");
  const clip = createVRMAnimationClip(anim[0], vrm);
  const mixer = new THREE.AnimationMixer(vrm.scene);
  mixer.clipAction(clip).play();
  const v = new THREE.Vector3();
  const frames = times.map((t) => {
    mixer.setTime(t);
    vrm.update(0);
    vrm.scene.updateMatrixWorld(true);
    return boneNames.map((b) => { const node = vrm.humanoid.getRawBoneNode(b); return node ? node.getWorldPosition(v).toArray() : null; });
  });
  return { frames, tracks: clip.tracks.map((t) => t.name), duration: anim[0].duration, metaVersion: vrm.meta.metaVersion };
};
window.vrmaReady = true;
`;

let browser, page, logs;
before(async () => {
  const bundle = await esbuild.build({
    stdin: { contents: PAGE_SCRIPT, resolveDir: root, loader: "js" },
    bundle: true, format: "iife", write: false, logLevel: "silent",
  });
  ({ browser, page, logs } = await launch("webgl2"));
  await page.goto("about:blank");
  await page.addScriptTag({ content: bundle.outputFiles[0].text });
  await page.waitForFunction(() => window.vrmaReady === true);
});
after(async () => { await browser?.close(); });

const b64 = (u8) => Buffer.from(u8.buffer, u8.byteOffset, u8.byteLength).toString("base64");

/** Body height of a clip at time 0 from the product's own joint positions (y extent). */
function heightOf(lib, id) {
  const p = lib.jointPositions(id, 0);
  let lo = Infinity, hi = -Infinity;
  for (let i = 1; i < p.length; i += 3) { lo = Math.min(lo, p[i]); hi = Math.max(hi, p[i]); }
  return hi - lo;
}

test("every .vrma passes the Khronos validator and three-vrm-animation plays it on a VRM within 1 cm per metre", async () => {
  const lib = new Library();
  const demo = lib.addBuiltinDemo();
  const text = new TextAnimator().animate(lib, "Taro runs, then kicks the ball. Then he rejoices.");
  const salsa = lib.importFile("salsa_01.bvh", new Uint8Array(readFileSync(join(data, "mocap", "cmu-salsa", "salsa_01.bvh"))), { fpsOverride: 60 }).clips[0];
  const { vrm, bones } = builtinVrm(lib, demo.id);
  assert.equal(bones, 21, "the avatar maps all 21 canonical joints");
  const cases = [["built-in dance", demo.id], ["text animation", text.clipId], ["CMU salsa_01 (own rig)", salsa.id]];
  let checked = 0;
  for (const [label, id] of cases) {
    const vrma = lib.exportVrma(id);
    assert.ok(vrma instanceof Uint8Array && vrma.length > 1000, `${label}: exportVrma returns the bytes`);
    const report = await validator.validateBytes(vrma, { maxIssues: 100 });
    const issues = report.issues;
    const bad = issues.messages.filter((m) => m.severity <= 1).map((m) => `${m.code} ${m.pointer}: ${m.message}`);
    assert.equal(issues.numErrors, 0, `${label}: ${bad.join("; ")}`);
    // The product's reference: the clip itself when it is on the canonical skeleton, else the
    // canonical motion the file carries, read back by the product's own importer.
    const canonical = lib.jointNames(id).length === 21 && lib.jointNames(id).includes("leftForearm");
    const refId = canonical ? id : lib.importFile(`${label}.vrma`, vrma, { gltfFps: lib.clip(id).fps }).clips[0].id;
    const info = lib.clip(refId);
    const names = lib.jointNames(refId);
    const times = Array.from({ length: 10 }, (_, k) => (info.durationSecs - 1 / info.fps) * k / 9);
    const played = await page.evaluate(([a, b, t, n]) => window.playVrma(a, b, t, n), [b64(vrm), b64(vrma), times, names.map(vrmBone)]);
    assert.equal(played.metaVersion, "1", `${label}: loaded as a VRM 1.0 avatar`);
    const rot = played.tracks.filter((t) => t.endsWith(".quaternion")).length;
    const pos = played.tracks.filter((t) => t.endsWith(".position")).length;
    assert.equal(rot, 21, `${label}: a rotation track per humanoid bone (${played.tracks.join(", ")})`);
    assert.equal(pos, 1, `${label}: a translation track on the hips only`);
    assert.ok(Math.abs(played.duration - info.durationSecs) < 1e-3, `${label}: duration ${played.duration} vs ${info.durationSecs}`);
    let worst = 0, compared = 0, moved = 0;
    times.forEach((t, k) => {
      const ours = lib.jointPositions(refId, t);
      names.forEach((_, j) => {
        const p = played.frames[k][j];
        assert.ok(p, `${label}: the avatar has no ${vrmBone(names[j])}`);
        worst = Math.max(worst, Math.hypot(p[0] - ours[3 * j], p[1] - ours[3 * j + 1], p[2] - ours[3 * j + 2]));
        moved = Math.max(moved, Math.hypot(p[0] - played.frames[0][j][0], p[1] - played.frames[0][j][1], p[2] - played.frames[0][j][2]));
        compared++;
      });
    });
    const height = heightOf(lib, refId);
    console.log(`${label}: ${vrma.length} bytes, validator ${issues.numErrors} errors / ${issues.numWarnings} warnings / ${issues.numInfos} infos; three-vrm vs product worst joint ${(worst * 1000).toFixed(3)} mm over ${compared} samples (height ${height.toFixed(2)} m, joints travel up to ${moved.toFixed(2)} m)`);
    assert.equal(compared, 10 * 21);
    assert.ok(moved > 0.1, `${label}: the avatar moves (${moved} m)`);
    assert.ok(worst < 0.01 * height, `${label}: worst ${worst} m > 1 cm per metre of ${height} m`);
    checked++;
  }
  assert.equal(checked, cases.length);
  // Neither loader complained (three-vrm warns on a T-pose violation, an unknown spec
  // version or a translation track on another bone than the hips).
  assert.deepEqual(logs.filter((l) => l.startsWith("[pageerror]") || /^\[(warning|error)\]/.test(l)), []);
});

test("exportVrma refuses what it cannot write with typed errors and changes nothing", () => {
  const lib = new Library();
  const fox = lib.importFile("Fox.glb", new Uint8Array(readFileSync(join(data, "gltf", "Fox.glb")))).clips[0];
  const n = lib.size;
  assert.throws(() => lib.exportVrma(fox.id), (e) => e.name === "OdoriError" && e.kind === "export-not-humanoid" && /not humanoid/.test(e.message));
  assert.throws(() => lib.exportVrma(9999), (e) => e.kind === "not-found");
  const demo = lib.addBuiltinDemo();
  assert.throws(() => lib.exportVrma(demo.id, { character: "builtin" }), (e) => e.kind === "bad-argument" && /character/.test(e.message));
  assert.throws(() => lib.exportVrma(demo.id, { startSecs: 3, endSecs: 1 }), (e) => e.kind === "bad-argument");
  assert.equal(lib.size, n + 1);
  // A range exports only those frames (the animation's time accessor says so).
  const part = lib.exportVrma(demo.id, { startSecs: 1, endSecs: 2 });
  const { json } = splitGlb(part);
  const timeAcc = json.accessors[json.animations[0].samplers[0].input];
  assert.equal(timeAcc.count, Math.round(demo.fps) + 1);
});
