// A model looks like itself (issue 28 item 2), on WebGL2 and WebGPU, in the app: sphere maps,
// the per-vertex edge scale, and framing by the skinned vertices. The model is read
// independently of the engine by three r171's MMDParser (`three-mmd`).
//
// - Sphere maps: none of the real models ships one, so 初音ミク Ver2's PMD is patched here the
//   way MMD writes one (the skin material's 20-byte texture field names `tone.spa` or
//   `tint.sph`) and the sphere file is a BMP written here. At skin vertices facing the camera
//   and the light, projected by `viewer.project`, the drawn colour against the unpatched model
//   (the control) is, in linear light: added (.spa, a uniform grey) control + grey × the
//   control's ramp (= control / diffuse), brighter; multiplied (.sph, a uniform orange)
//   control × orange, each channel as the sphere says. The lookup by the view-space normal: a
//   multiplied sphere black on its left half darkens the skin that faces the camera's left and
//   leaves that facing its right as the control.
// - Edge scale: PMD vertices whose edge flag is set draw no outline. With the flag set on
//   every vertex on the model's own left (x > 0 in the file), the outline (black pixels that the
//   control has) goes on that side of the screen and stays on the other.
// - Framing: Gene (Gene_light.pmx) at rest and playing 時間のカケラ (a dance made for another
//   model): after `frameFigures`, every vertex skinned here (MMDParser's weights and rest
//   positions, the bones the viewer drew: `figureJoints`) projects inside the canvas with a
//   margin; framed by the joints instead (`style: "stick"`, the old framing: the control) she is
//   smaller on screen or cut off.
// Screenshots go to tests/artifacts/.
import { test, before, after } from "node:test";
import assert from "node:assert/strict";
import { readFileSync, readdirSync, existsSync } from "node:fs";
import { join } from "node:path";
import { root, data, startServer, launch, openApp, canvasPixels, pixel, waitUntil } from "./harness.mjs";

const parserPath = join(root, "node_modules", "three-mmd", "examples", "jsm", "libs", "mmdparser.module.js");
if (!existsSync(parserPath)) throw new Error("node_modules/three-mmd (three@0.171.0) is missing: run npm ci");
const { MMDParser } = await import(parserPath);

const mikuDir = join(data, "mmd", "miku_v2");
const geneDir = join(data, "mmd", "gene");
const dance = join(data, "mmd", "motion", "tokino_kakera.vmd");
for (const f of [join(mikuDir, "miku_v2.pmd"), join(geneDir, "Gene_light.pmx"), dance]) {
  if (!existsSync(f)) throw new Error(`${f} is missing (the MMD test data in ../shared/data)`);
}

const LIGHT = (() => { const l = [0.4, 0.9, 0.6]; const n = Math.hypot(...l); return l.map((x) => x / n); })();
const M = 0.08; // metres per MMD unit
const s2l = (c) => { const x = c / 255; return x <= 0.04045 ? x / 12.92 : ((x + 0.055) / 1.055) ** 2.4; };
const l2s = (x) => 255 * (x <= 0.0031308 ? x * 12.92 : 1.055 * Math.max(x, 0) ** (1 / 2.4) - 0.055);
const SKIN = 2; // miku_v2's material 2: the skin (face, arms), untextured, opaque

/** A 24-bit BMP, `w` × `h`, the colour at each pixel from `rgb(x, y)` (y from the top). */
function bmp(w, h, rgb) {
  const row = Math.ceil((w * 3) / 4) * 4;
  const b = Buffer.alloc(54 + row * h);
  b.write("BM", 0, "latin1");
  b.writeUInt32LE(b.length, 2);
  b.writeUInt32LE(54, 10);
  b.writeUInt32LE(40, 14);
  b.writeInt32LE(w, 18);
  b.writeInt32LE(h, 22);
  b.writeUInt16LE(1, 26);
  b.writeUInt16LE(24, 28);
  b.writeUInt32LE(row * h, 34);
  for (let y = 0; y < h; y++) for (let x = 0; x < w; x++) {
    const [r, g, bl] = rgb(x, h - 1 - y); // rows bottom first
    b.set([bl, g, r], 54 + y * row + x * 3);
  }
  return b;
}

/** PMD layout: the offset of material `k`'s 20-byte texture field, and of vertex `i`'s edge flag. */
const pmd = {
  vertexCount: (b) => b.readUInt32LE(283),
  edgeFlagAt: (b, i) => 287 + 38 * i + 37,
  textureFieldAt(b, k) {
    let at = 287 + 38 * b.readUInt32LE(283);
    at += 4 + 2 * b.readUInt32LE(at);
    assert.ok(k < b.readUInt32LE(at), `material ${k}`);
    return at + 4 + 70 * k + 50;
  },
};

function mikuWithTexture(k, field) {
  const b = Buffer.from(readFileSync(join(mikuDir, "miku_v2.pmd")));
  const at = pmd.textureFieldAt(b, k);
  b.fill(0, at, at + 20);
  b.write(field, at, "latin1");
  return b;
}

const parse = (buf, pmx) => {
  const ab = buf.buffer.slice(buf.byteOffset, buf.byteOffset + buf.byteLength);
  return pmx ? new MMDParser.Parser().parsePmx(ab, true) : new MMDParser.Parser().parsePmd(ab, true);
};

/** Vertices of material `mi` facing the viewer (+z) and the light: { p (metres), n, ndl }. */
function facingPoints(model, mi, per = 60) {
  let face = 0;
  for (let k = 0; k < mi; k++) face += model.materials[k].faceCount;
  const seen = new Set(), cands = [];
  for (let f = face; f < face + model.materials[mi].faceCount; f++) {
    for (const vi of model.faces[f].indices) {
      if (seen.has(vi)) continue;
      seen.add(vi);
      const v = model.vertices[vi], n = v.normal;
      const ndl = n[0] * LIGHT[0] + n[1] * LIGHT[1] + n[2] * LIGHT[2];
      if (n[2] > 0.5 && ndl > 0.2) cands.push({ p: v.position.map((x) => x * M), n, ndl });
    }
  }
  const step = Math.max(1, Math.floor(cands.length / per));
  return cands.filter((_, k) => k % step === 0);
}

const b64 = (buf) => Buffer.from(buf).toString("base64");

/** Imports a file set and shows its model, the camera on the body as mmd-draw does; returns the report's model. */
async function importAndShow(page, files) {
  const model = await page.evaluate((files) => {
    const { library, player } = window.odori;
    const r = library.importFiles(files.map((f) => ({ name: f.name, bytes: window.__test.bytes(f.b64) })), {});
    const m = r.models[0];
    if (m && m.characterId != null) player.select(m.characterId);
    player.pause();
    return { ...m, notices: r.notices, problems: r.problems };
  }, files);
  await waitUntil(() => page.evaluate(() => { window.odori.player.drawNow(); return window.odori.viewer.texturesLoading === 0; }), { what: "the model's textures decoded" });
  // The page's layout settles after an import (the Character list, messages): then the camera.
  await page.waitForTimeout(400);
  await page.evaluate(() => {
    const { viewer, player } = window.odori;
    viewer.setCamera({ target: [0, 1.3, 0], yaw: 0, pitch: 0, distance: 1.6, fovY: 0.785 });
    player.drawNow();
  });
  return model;
}

const project = (page, points) => page.evaluate((ps) => ps.map((p) => window.odori.viewer.project(p[0], p[1], p[2])), points);

/** The drawn colour (sRGB 0–255) at each point, the middle of its 3×3 window; null off the canvas. */
function colours(img, xys) {
  return xys.map((xy) => {
    if (!xy || xy[0] < 3 || xy[1] < 3 || xy[0] > img.width - 4 || xy[1] > img.height - 4) return null;
    const acc = [0, 0, 0], lo = [255, 255, 255], hi = [0, 0, 0];
    for (let dy = -1; dy <= 1; dy++) for (let dx = -1; dx <= 1; dx++) {
      const c = pixel(img, xy[0] + dx, xy[1] + dy);
      for (let k = 0; k < 3; k++) { acc[k] += c[k] / 9; lo[k] = Math.min(lo[k], c[k]); hi[k] = Math.max(hi[k], c[k]); }
    }
    // Whether the window is one surface (no edge of another part or of a toon step through it).
    acc.even = [0, 1, 2].every((k) => hi[k] - lo[k] <= 6);
    return acc;
  });
}

let server;
before(async () => { server = await startServer(); });
after(() => server && server.stop());

const mikuSet = () => readdirSync(mikuDir).filter((f) => /\.bmp$/i.test(f)).map((f) => ({ name: `miku_v2/${f}`, b64: b64(readFileSync(join(mikuDir, f))) }));

async function sphereMaps(page, backend) {
  const plain = readFileSync(join(mikuDir, "miku_v2.pmd"));
  const model = parse(plain, false);
  const diffuse = model.materials[SKIN].diffuse;
  const points = facingPoints(model, SKIN, 200);
  const GREY = [90, 90, 90], ORANGE = [255, 150, 70];
  const variants = {
    control: { pmd: plain, extra: [] },
    add: { pmd: mikuWithTexture(SKIN, "tone.spa"), extra: [{ name: "miku_v2/tone.spa", b64: b64(bmp(16, 16, () => GREY)) }] },
    multiply: { pmd: mikuWithTexture(SKIN, "tint.sph"), extra: [{ name: "miku_v2/tint.sph", b64: b64(bmp(16, 16, () => ORANGE)) }] },
    // Black on the left half (u < ½), white on the right.
    leftDark: { pmd: mikuWithTexture(SKIN, "half.sph"), extra: [{ name: "miku_v2/half.sph", b64: b64(bmp(64, 64, (x) => (x < 32 ? [0, 0, 0] : [255, 255, 255]))) }] },
  };
  const drawn = {};
  // Each variant is drawn on the same canvas size and camera, so each point lands on the same
  // pixels: the canvas is held at one size (imports change the page's layout around it), and a
  // first import settles the page.
  await page.evaluate(() => Object.assign(document.querySelector("#view").style, { flex: "none", width: "960px", height: "420px" }));
  await importAndShow(page, [...mikuSet(), { name: "miku_v2/miku_v2.pmd", b64: b64(plain) }]);
  const size = await page.evaluate(() => [document.querySelector("#view").width, document.querySelector("#view").height]);
  for (const [name, v] of Object.entries(variants)) {
    const info = await importAndShow(page, [...mikuSet(), ...v.extra, { name: "miku_v2/miku_v2.pmd", b64: b64(v.pmd) }]);
    assert.equal(info.problems.length, 0, `${name}: ${JSON.stringify(info.problems)}`);
    assert.ok(!info.notices.some((n) => /sphere/.test(n)), `${name}: ${JSON.stringify(info.notices)}`);
    assert.deepEqual(await page.evaluate(() => [document.querySelector("#view").width, document.querySelector("#view").height]), size, `${name}: the canvas kept its size`);
    const xys = await project(page, points.map((p) => p.p));
    drawn[name] = colours(await canvasPixels(page, `${backend}-mmd-look-sphere-${name}.png`), xys);
  }
  // Missing sphere file: a notice names it, the model is drawn as the control.
  const missing = await importAndShow(page, [...mikuSet(), { name: "miku_v2/miku_v2.pmd", b64: b64(variants.add.pmd) }]);
  assert.ok(missing.characterId != null && missing.notices.some((n) => /sphere map 'tone\.spa'/.test(n)), JSON.stringify(missing.notices));
  const missingDrawn = colours(await canvasPixels(page), await project(page, points.map((p) => p.p)));
  await page.evaluate(() => Object.assign(document.querySelector("#view").style, { flex: "", width: "", height: "" }));

  // Where the skin shows (other parts, hair or the shirt, cover some points), each variant's
  // check is made on the points the *other* variant changed: added grey raised every channel
  // there (by > 3/255) / multiplied orange lowered blue (by > 8/255); and where the control's
  // 3×3 window is even (not across the edge of the skin or of a toon step). Elsewhere nothing
  // changes.
  const TOL = 14;
  const grey = GREY.map(s2l), orange = ORANGE.map(s2l);
  const miss = (a, b) => Math.max(...[0, 1, 2].map((i) => Math.abs(a[i] - b[i])));
  const t = { points: 0, raised: 0, lowered: 0, both: 0, add: 0, multiply: 0, missing: 0, unchanged: 0, neither: 0 };
  points.forEach((pt, k) => {
    const c = drawn.control[k];
    if (!c || !drawn.add[k] || !drawn.multiply[k] || !missingDrawn[k]) return;
    t.points++;
    const lin = c.map(s2l);
    const wantAdd = [0, 1, 2].map((i) => l2s(lin[i] + grey[i] * (lin[i] / Math.max(diffuse[i], 1e-3))));
    const wantMul = [0, 1, 2].map((i) => l2s(lin[i] * orange[i]));
    const raised = c.even && [0, 1, 2].every((i) => drawn.add[k][i] > c[i] + 3);
    const lowered = c.even && drawn.multiply[k][2] < c[2] - 8;
    t.raised += raised;
    t.lowered += lowered;
    t.both += raised && lowered;
    if (lowered && miss(drawn.add[k], wantAdd) <= TOL) t.add++;
    if (raised && miss(drawn.multiply[k], wantMul) <= TOL) t.multiply++;
    if (![0, 1, 2].every((i) => drawn.add[k][i] > c[i] + 3) && !(drawn.multiply[k][2] < c[2] - 8)) { t.neither++; if (miss(drawn.add[k], c) <= 2 && miss(drawn.multiply[k], c) <= 2) t.unchanged++; }
    if (miss(missingDrawn[k], c) <= 2) t.missing++;
  });
  console.log(`${backend}: sphere maps on miku_v2's skin, ${t.points} points: added grey raised every channel at ${t.raised}, multiplied orange lowered blue at ${t.lowered} (both at ${t.both}); drawn within ${TOL}/255 of control + grey × ramp at ${t.add} of ${t.lowered}, of control × orange at ${t.multiply} of ${t.raised}; ${t.neither} points (skin covered) unchanged at ${t.unchanged}; sphere file missing: as the control at ${t.missing}`);
  assert.ok(t.raised >= 25 && t.lowered >= 25, `skin points the spheres changed: ${JSON.stringify(t)}`);
  assert.ok(t.both >= 0.9 * Math.min(t.raised, t.lowered), `the two spheres change the same points: ${JSON.stringify(t)}`);
  assert.ok(t.add >= 0.9 * t.lowered && t.multiply >= 0.9 * t.raised, `drawn as the sphere modes say: ${JSON.stringify(t)}`);
  assert.ok(t.unchanged >= 0.9 * t.neither && t.missing === t.points, JSON.stringify(t));

  // The lookup by the view-space normal: the camera looks along −z (yaw 0), so its left is −x.
  const left = [0, 0], right = [0, 0];
  points.forEach((pt, k) => {
    const c = drawn.control[k], d = drawn.leftDark[k], a = drawn.add[k];
    if (!c || !d || !a || ![0, 1, 2].every((i) => a[i] > c[i] + 3)) return; // where the skin shows
    if (pt.n[0] < -0.45) { left[0]++; if (Math.max(...d) < 0.35 * Math.max(...c)) left[1]++; }
    if (pt.n[0] > 0.45) { right[0]++; if (miss(d, c) <= 6) right[1]++; }
  });
  console.log(`${backend}: a sphere black on its left half: ${left[1]} of ${left[0]} skin points facing the camera's left darkened, ${right[1]} of ${right[0]} facing its right as the control`);
  assert.ok(left[0] >= 4 && right[0] >= 4, `points facing each side: ${left[0]} / ${right[0]}`);
  assert.ok(left[1] >= 0.75 * left[0] && right[1] >= 0.75 * right[0], `left ${left[1]}/${left[0]}, right ${right[1]}/${right[0]}`);
}

async function edgeScale(page, backend) {
  const plain = readFileSync(join(mikuDir, "miku_v2.pmd"));
  const model = parse(plain, false);
  // The file's own x (left-handed, the model's left at +x); three's right-handed x is the same.
  const patched = Buffer.from(plain);
  let off = 0;
  for (let i = 0; i < pmd.vertexCount(patched); i++) if (patched.readFloatLE(287 + 38 * i) > 0.3) { patched[pmd.edgeFlagAt(patched, i)] = 1; off++; }
  const img = {};
  for (const [name, bytes] of [["control", plain], ["halfOff", patched]]) {
    await importAndShow(page, [...mikuSet(), { name: "miku_v2/miku_v2.pmd", b64: b64(bytes) }]);
    await page.evaluate(() => { const { viewer, player } = window.odori; viewer.setCamera({ target: [0, 0.8, 0], yaw: 0, pitch: 0, distance: 3.2, fovY: 0.785 }); player.drawNow(); });
    img[name] = await canvasPixels(page, `${backend}-mmd-look-edge-${name}.png`);
  }
  // Which side of the screen the model's +x is on.
  const [[xl], [xr]] = await project(page, [[-0.5, 1, 0], [0.5, 1, 0]]);
  const centre = (await project(page, [[0, 1, 0]]))[0][0];
  const black = (c) => Math.max(...c) < 16;
  const counts = { plusSide: [0, 0], minusSide: [0, 0] };
  const { width, height } = img.control;
  for (let y = 0; y < height; y++) for (let x = 0; x < width; x++) {
    const side = (x - centre) * (xr - xl) > 0 ? "plusSide" : "minusSide";
    if (Math.abs(x - centre) < 6) continue;
    if (black(pixel(img.control, x, y))) counts[side][0]++;
    if (black(pixel(img.halfOff, x, y))) counts[side][1]++;
  }
  console.log(`${backend}: miku_v2 outline pixels (control → edge flag set on the ${off} vertices at x > 0.3): model's +x side ${counts.plusSide[0]} → ${counts.plusSide[1]}, −x side ${counts.minusSide[0]} → ${counts.minusSide[1]}`);
  assert.ok(counts.plusSide[0] > 300 && counts.minusSide[0] > 300, `the control has an outline on both sides: ${JSON.stringify(counts)}`);
  assert.ok(counts.plusSide[1] < 0.35 * counts.plusSide[0], `the outline where the edge is off: ${JSON.stringify(counts)}`);
  assert.ok(Math.abs(counts.minusSide[1] - counts.minusSide[0]) < 0.1 * counts.minusSide[0], `the outline where the edge is on: ${JSON.stringify(counts)}`);
  assert.ok(model.vertices.filter((v) => v.edgeFlag).length === 133, "miku_v2's own edge flags (133 vertices, three's parser)");
}

/** Gene's vertices (metres, right-handed, every `step`th) with their bones and weights, and her bones' rest positions, by three's parser. */
function geneSkin(step = 3) {
  const model = parse(readFileSync(join(geneDir, "Gene_light.pmx")), true);
  const bones = model.bones.map((b) => ({ name: b.name, parent: b.parentIndex, rest: b.position.map((x) => x * M) }));
  const vertices = [];
  for (let i = 0; i < model.vertices.length; i += step) {
    const v = model.vertices[i];
    vertices.push({ p: v.position.map((x) => x * M), bones: v.skinIndices, weights: v.skinWeights });
  }
  return { bones, vertices, modelName: model.metadata.modelName };
}

const qrot = (q, v) => {
  const [x, y, z, w] = q;
  const t = [2 * (y * v[2] - z * v[1]), 2 * (z * v[0] - x * v[2]), 2 * (x * v[1] - y * v[0])];
  return [v[0] + w * t[0] + (y * t[2] - z * t[1]), v[1] + w * t[1] + (z * t[0] - x * t[2]), v[2] + w * t[2] + (x * t[1] - y * t[0])];
};

/** The vertices skinned by the joints the viewer drew (a bone not among them moves with its nearest ancestor that is). */
function skin(gene, joints) {
  const at = new Map(joints.names.map((n, i) => [n, i]));
  const jointOf = gene.bones.map((_, b) => { for (let k = b, n = 0; k >= 0 && n < 1000; k = gene.bones[k].parent, n++) if (at.has(gene.bones[k].name)) return [at.get(gene.bones[k].name), k]; return null; });
  return gene.vertices.map((v) => {
    const out = [0, 0, 0];
    let total = 0;
    v.bones.forEach((b, k) => {
      const w = v.weights[k];
      const j = jointOf[b];
      if (!(w > 0) || !j) return;
      const [ji, bi] = j;
      const rest = gene.bones[bi].rest;
      const r = qrot(joints.rotations.slice(4 * ji, 4 * ji + 4), [v.p[0] - rest[0], v.p[1] - rest[1], v.p[2] - rest[2]]);
      for (let c = 0; c < 3; c++) out[c] += w * (joints.positions[3 * ji + c] + r[c]);
      total += w;
    });
    return out.map((x) => x / (total || 1));
  });
}

async function framing(page, backend) {
  const gene = geneSkin();
  const files = [
    { name: "gene/Gene_light.pmx", b64: b64(readFileSync(join(geneDir, "Gene_light.pmx"))) },
    ...readdirSync(join(geneDir, "light")).filter((f) => /\.png$/i.test(f)).map((f) => ({ name: `gene/light/${f}`, b64: b64(readFileSync(join(geneDir, "light", f))) })),
    { name: "tokino_kakera.vmd", b64: b64(readFileSync(dance)) },
  ];
  const setup = await page.evaluate(({ files, modelName }) => {
    const { library, player } = window.odori;
    const r = library.importFiles(files.map((f) => ({ name: f.name, bytes: window.__test.bytes(f.b64) })), { model: modelName });
    player.select(r.models[0].characterId);
    player.pause();
    const canvas = document.querySelector("#view");
    return { problems: r.problems, rest: r.models[0].characterId, dance: r.motions[0]?.clip, size: [canvas.width, canvas.height] };
  }, { files, modelName: gene.modelName });
  assert.equal(setup.problems.length, 0, JSON.stringify(setup.problems));
  assert.ok(setup.dance && setup.dance.hasMesh, `the dance plays on Gene's mesh: ${JSON.stringify(setup.dance)}`);
  await waitUntil(() => page.evaluate(() => { window.odori.player.drawNow(); return window.odori.viewer.texturesLoading === 0; }), { what: "Gene's textures decoded" });
  const [W, H] = setup.size;
  const margin = Math.round(0.01 * H);
  const secs = setup.dance.durationSecs ?? setup.dance.duration ?? 120;

  /** Frames `clip` (joints: as a stick figure) and draws it at each time; the projected vertices' box and how many fall outside the canvas less the margin. */
  const run = async (clip, times, joints) => {
    const out = [];
    await page.evaluate(({ clip, joints }) => window.odori.viewer.frameFigures(window.odori.library, [{ clip, timeSecs: 0, ...(joints ? { style: "stick" } : {}) }]), { clip, joints });
    for (const t of times) {
      const j = await page.evaluate(({ clip, t }) => {
        const { library, viewer } = window.odori;
        viewer.draw(library, [{ clip, timeSecs: t }]);
        return viewer.figureJoints(library, clip, t);
      }, { clip, t });
      const xys = await project(page, skin(gene, j));
      let outside = 0, lo = [Infinity, Infinity], hi = [-Infinity, -Infinity];
      for (const xy of xys) {
        if (!xy) { outside++; continue; }
        if (xy[0] < margin || xy[1] < margin || xy[0] > W - margin || xy[1] > H - margin) outside++;
        lo = [Math.min(lo[0], xy[0]), Math.min(lo[1], xy[1])];
        hi = [Math.max(hi[0], xy[0]), Math.max(hi[1], xy[1])];
      }
      out.push({ t, outside, heightPx: hi[1] - lo[1], lo, hi });
    }
    return out;
  };
  const danceTimes = Array.from({ length: 10 }, (_, k) => +(((k + 0.37) / 10) * Math.min(secs, 120)).toFixed(2));
  await canvasPixels(page); // settle
  for (const [label, clip, times] of [["at rest", setup.rest, [0]], ["dancing", setup.dance.id, danceTimes]]) {
    const skinned = await run(clip, times, false);
    await canvasPixels(page, `${backend}-mmd-look-frame-${label.replace(" ", "-")}.png`);
    const byJoints = await run(clip, times, true);
    const worst = Math.max(...skinned.map((r) => r.outside));
    const meanH = (rs) => rs.reduce((a, r) => a + r.heightPx, 0) / rs.length;
    const jointsOut = byJoints.reduce((a, r) => a + r.outside, 0);
    console.log(`${backend}: Gene ${label} (${times.length} times, ${gene.vertices.length} vertices each, canvas ${W}×${H}, margin ${margin} px): framed by skinned bounds: at most ${worst} vertices outside, mean height ${meanH(skinned).toFixed(0)} px (${(meanH(skinned) / H * 100).toFixed(0)} %); by joints (control): ${jointsOut} vertex-times outside, mean height ${meanH(byJoints).toFixed(0)} px`);
    assert.equal(worst, 0, `${label}: vertices outside the frame: ${JSON.stringify(skinned.filter((r) => r.outside))}`);
    assert.ok(meanH(skinned) > 1.05 * meanH(byJoints) || jointsOut > 0, `${label}: framed by joints she is neither smaller (${meanH(byJoints)} vs ${meanH(skinned)} px) nor cut off`);
  }
}

for (const backend of ["webgl2", "webgpu"]) {
  test(`an MMD model looks like itself (sphere maps, edge scale, framing) on ${backend}`, async (t) => {
    const { browser, page, logs } = await launch(backend);
    try {
      await openApp(page, server, backend);
      await t.test("sphere maps", () => sphereMaps(page, backend));
      await t.test("per-vertex edge scale", () => edgeScale(page, backend));
      await t.test("framed by the skinned vertices", () => framing(page, backend));
      assert.ok(!logs.some((l) => l.startsWith("[pageerror]") || /Validation/.test(l)), logs.join("\n"));
    } finally {
      await browser.close();
    }
  });
}
