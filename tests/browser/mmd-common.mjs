// Helpers the browser MMD tests share (mmd-face, mmd-morphs, mmd-material-morphs, mmd-uv-morphs,
// mmd-draw, mmd-synthetic-morphs): three r171's MMDParser (`three-mmd`, a reader no one here
// wrote) and what the tests read with it — a VMD's morph keys, a PMD's vertex morphs and the
// vertices 頭 alone carries —, the quaternion maths that puts a head-rest point where the posed
// head has it and a camera in front of the face, and a model folder and its VMD imported in the
// page (`modelFiles`, `importOnModel`), and pairs of shots of one view (`shotPair`).
import assert from "node:assert/strict";
import { readFileSync, readdirSync, existsSync } from "node:fs";
import { join } from "node:path";
import { root, canvasPixels, waitUntil } from "./harness.mjs";

const parserPath = join(root, "node_modules", "three-mmd", "examples", "jsm", "libs", "mmdparser.module.js");
if (!existsSync(parserPath)) throw new Error("node_modules/three-mmd (three@0.171.0) is missing: run npm ci");
export const { MMDParser } = await import(parserPath);

/** Metres per MMD unit (the engine's and three's MMD examples' scale). */
export const M = 0.08;

/** A Node Buffer's bytes as the ArrayBuffer MMDParser reads. */
export const ab = (buf) => buf.buffer.slice(buf.byteOffset, buf.byteOffset + buf.byteLength);

/**
 * A model folder as `importFiles` takes it from the test ({ name, b64 }): the model file `model`
 * of `dir` under the name `${prefix}/${model}`, then the files of `dir` (or of its subfolders
 * `sub`, each `${prefix}/${sub}/…`) that `keep` accepts, then each extra file ({ name, bytes }).
 */
export function modelFiles(dir, prefix, model, { subfolders = [], keep = () => true, extra = [] } = {}) {
  const files = [{ name: `${prefix}/${model}`, b64: readFileSync(join(dir, model)).toString("base64") }];
  for (const sub of subfolders.length ? subfolders : [""]) {
    for (const f of readdirSync(join(dir, sub))) {
      const name = sub ? `${sub}/${f}` : f;
      if (name !== model && keep(f)) files.push({ name: `${prefix}/${name}`, b64: readFileSync(join(dir, sub, f)).toString("base64") });
    }
  }
  for (const f of extra) files.push({ name: f.name, b64: Buffer.from(f.bytes).toString("base64") });
  return files;
}

/**
 * Imports `files` ({ name, b64 }) in the page with `library.importFiles`, the VMDs posed on the
 * model named `modelName`; turns the springs off (both draws of a frame then pose every bone
 * alike), selects the first motion and pauses. Asserts no file is a problem and the motion plays
 * on the model's mesh, then waits for its textures. Returns { clip, notices, rig, morphsDefault }
 * (the motion's clip and rig, the import's notices, whether morphs were on before).
 */
export async function importOnModel(page, files, modelName, what = modelName) {
  const setup = await page.evaluate(({ files, modelName }) => {
    const { library, player, viewer } = window.odori;
    const r = library.importFiles(files.map((f) => ({ name: f.name, bytes: window.__test.bytes(f.b64) })), { model: modelName });
    const clip = r.motions[0]?.clip;
    viewer.setSprings(false);
    if (clip) player.select(clip.id);
    player.pause();
    return { problems: r.problems, notices: r.notices, clip, rig: r.motions[0]?.rig, morphsDefault: viewer.morphs };
  }, { files, modelName });
  assert.equal(setup.problems.length, 0, JSON.stringify(setup.problems));
  assert.ok(setup.clip && setup.clip.hasMesh, `the motion plays on ${what}'s mesh (posed on ${setup.rig}): ${JSON.stringify(setup.notices)}`);
  await waitUntil(() => page.evaluate(() => { window.odori.player.drawNow(); return window.odori.viewer.texturesLoading === 0; }), { what: `${what}'s textures decoded` });
  return setup;
}

/** Shift-JIS bytes of `s` (double-byte characters and ASCII), by decoding every double-byte code with the browser-independent TextDecoder. */
export function shiftJis(s) {
  const sjis = new TextDecoder("shift_jis");
  if (!shiftJis.table) {
    shiftJis.table = new Map();
    for (const lead of [...Array(0x1f).keys()].map((i) => 0x81 + i).concat([...Array(0x10).keys()].map((i) => 0xe0 + i)))
      for (let trail = 0x40; trail <= 0xfc; trail++) {
        const ch = sjis.decode(Uint8Array.of(lead, trail));
        if (ch.length === 1 && !shiftJis.table.has(ch)) shiftJis.table.set(ch, [lead, trail]);
      }
  }
  const out = [];
  for (const ch of s) {
    if (ch.charCodeAt(0) < 0x80) out.push(ch.charCodeAt(0));
    else if (shiftJis.table.has(ch)) out.push(...shiftJis.table.get(ch));
    else throw new Error(`no Shift-JIS code for ${ch}`);
  }
  if (sjis.decode(Uint8Array.from(out)) !== s) throw new Error(`${s} does not decode back from Shift-JIS`);
  return Buffer.from(out);
}

/** Fails with a clear message when a file of the shared MMD data is absent. */
export function needData(...paths) {
  for (const p of paths) if (!existsSync(p)) throw new Error(`${p} is missing (the MMD test data in ../shared/data)`);
}

/** `v` rotated by the unit quaternion `q` ([x, y, z, w]): v + 2w (u × v) + 2 u × (u × v). */
export const rotate = (q, v) => {
  const [x, y, z, w] = q;
  const c1 = [y * v[2] - z * v[1], z * v[0] - x * v[2], x * v[1] - y * v[0]];
  const c2 = [y * c1[2] - z * c1[1], z * c1[0] - x * c1[2], x * c1[1] - y * c1[0]];
  return [0, 1, 2].map((i) => v[i] + 2 * w * c1[i] + 2 * c2[i]);
};

/** A pixel changed: some channel differs by more than 24 of 255. */
export const CHANGED = (a, b) => Math.max(Math.abs(a[0] - b[0]), Math.abs(a[1] - b[1]), Math.abs(a[2] - b[2])) > 24;

/** Where a rest point (metres) carried by the head alone is when the head (rest position `headRest`) is posed at { q, p }. */
export const onPosedHead = (pose, headRest) => (r) => rotate(pose.q, r.map((x, k) => x - headRest[k])).map((x, k) => x + pose.p[k]);

/** A camera looking the posed head in the face: at `up` metres above the head joint along its up, from its forward (+z at rest), `distance` away. */
export function faceCamera(pose, up, distance) {
  const fwd = rotate(pose.q, [0, 0, 1]);
  const target = rotate(pose.q, [0, up, 0]).map((x, k) => x + pose.p[k]);
  return { target, yaw: Math.atan2(fwd[0], fwd[2]), pitch: Math.asin(Math.max(-1, Math.min(1, fwd[1]))), distance, fovY: 0.5 };
}

/** A VMD's morph keys by three's parser: name → [{ frame, weight }] in frame order; and its bone-key count. */
export function readMorphKeys(bytes) {
  const vmd = new MMDParser.Parser().parseVmd(ab(bytes), true);
  const keys = new Map();
  for (const k of vmd.morphs) {
    if (!keys.has(k.morphName)) keys.set(k.morphName, []);
    keys.get(k.morphName).push({ frame: k.frameNum, weight: k.weight });
  }
  for (const list of keys.values()) list.sort((a, b) => a.frame - b.frame);
  return { keys, boneKeys: vmd.motions.length };
}

/** A keyed morph's weight at `frame` as MMD plays it: linear between keys, held outside them. */
export function weightAt(list, frame) {
  let w = list[0].weight;
  for (let k = 0; k < list.length; k++) {
    if (list[k].frame <= frame) w = list[k].weight;
    if (list[k].frame > frame) { const a = list[k - 1]; if (a) w = a.weight + ((list[k].weight - a.weight) * (frame - a.frame)) / (list[k].frame - a.frame); break; }
  }
  return w;
}

/** A PMD's vertex morphs as three's parser reads them (right-handed): name → [{ v, d }] (model vertex, offset in metres); whether a vertex is carried by 頭 alone; rest positions (metres); 頭's rest position; the model's name. */
export function readPmdMorphs(path) {
  const model = new MMDParser.Parser().parsePmd(ab(readFileSync(path)), true);
  const base = model.morphs.find((m) => m.type === 0);
  if (!base) throw new Error(`${path}: a PMD has a base morph`);
  const morphs = new Map();
  for (const m of model.morphs) if (m !== base) morphs.set(m.name, m.elements.map((e) => ({ v: base.elements[e.index].index, d: e.position.map((x) => x * M) })));
  const head = model.bones.findIndex((b) => b.name === "頭");
  if (head < 0) throw new Error(`${path}: no bone 頭`);
  const onHead = (v) => model.vertices[v].skinWeights.every((w, k) => w === 0 || model.vertices[v].skinIndices[k] === head);
  return { morphs, onHead, rest: (v) => model.vertices[v].position.map((x) => x * M), headRest: model.bones[head].position.map((x) => x * M), name: model.metadata.modelName };
}

/** Whether the viewer's camera `now` is `camera` (within 1e-4): the page may frame the figures again meanwhile. */
export const sameCamera = (now, camera) =>
  Math.abs(now.yaw - camera.yaw) < 1e-4 && Math.abs(now.pitch - camera.pitch) < 1e-4 && Math.abs(now.distance - camera.distance) < 1e-4 && now.target.every((x, k) => Math.abs(x - camera.target[k]) < 1e-4);

/** The box (pixels, padded by `padPx`) the world points `pts` project to in the page's viewer. */
export async function projectedBox(page, pts, padPx) {
  const xy = (await page.evaluate((ps) => ps.map((p) => window.odori.viewer.project(p[0], p[1], p[2])), pts)).filter(Boolean);
  const xs = xy.map((p) => p[0]), ys = xy.map((p) => p[1]);
  return { x0: Math.floor(Math.min(...xs)) - padPx, x1: Math.ceil(Math.max(...xs)) + padPx, y0: Math.floor(Math.min(...ys)) - padPx, y1: Math.ceil(Math.max(...ys)) + padPx };
}

/** The projected box of a PMD morph's head-carried vertices (`readPmdMorphs`) at rest and moved by `weight`, the head posed at `pose`. */
export async function morphBox(page, model, name, weight, pose, padPx) {
  const els = model.morphs.get(name).filter((e) => model.onHead(e.v) && Math.hypot(...e.d) > 1e-4);
  const world = onPosedHead(pose, model.headRest);
  const pts = els.flatMap((e) => { const r = model.rest(e.v); return [world(r), world(r.map((x, k) => x + weight * e.d[k]))]; });
  return { n: els.length, ...(await projectedBox(page, pts, padPx)) };
}

/** Boxes of every head-carried morph `keys` weight at motion `frame` (`weightAt`), padded 8 px. */
export async function movingBoxes(page, model, keys, frame, pose) {
  const out = [];
  for (const [name, list] of keys) {
    if (!model.morphs.has(name)) continue;
    const w = weightAt(list, frame);
    if (Math.abs(w) > 1e-4 && model.morphs.get(name).some((e) => model.onHead(e.v))) out.push(await morphBox(page, model, name, w, pose, 8));
  }
  return out;
}

export const inBox = (b, x, y) => x >= b.x0 && x <= b.x1 && y >= b.y0 && y <= b.y1;

/** How many pixels of `img` inside box `b` satisfy `pred(x, y)`. */
export const countIn = (img, b, pred) => { let n = 0; for (let y = Math.max(0, b.y0); y <= Math.min(img.height - 1, b.y1); y++) for (let x = Math.max(0, b.x0); x <= Math.min(img.width - 1, b.x1); x++) if (pred(x, y)) n++; return n; };

/**
 * The test owns the camera while it shoots: waits until every long clip is made on its body
 * (the page frames the figures again when one is) and the view's size has settled, then holds
 * off the page's own re-framing (a resize of the view, a body made) until the returned
 * `release()` is awaited.
 */
async function holdCamera(page) {
  await waitUntil(() => page.evaluate(() => {
    const { viewer, player } = window.odori;
    if (viewer.bodiesPending === 0) return true;
    player.drawNow();
    return false;
  }), { what: "every clip made on its body (no re-framing pending)", timeoutMs: 60000, intervalMs: 100 });
  // The view's size settled: the same for 300 ms.
  let last = null;
  await waitUntil(async () => {
    const size = await page.evaluate(() => { const c = document.querySelector("#view"); return `${c.clientWidth}×${c.clientHeight}`; });
    const settled = size === last;
    last = size;
    return settled;
  }, { what: "the view's size to settle", timeoutMs: 30000, intervalMs: 300 });
  await page.evaluate(() => {
    const p = window.odori.player;
    if (!Object.hasOwn(p, "reframe")) p.reframe = () => {};
  });
  return () => page.evaluate(() => { delete window.odori.player.reframe; });
}

/** What differs between the viewer's camera `now` and `camera`, and the view's size: for a failure's message. */
const cameraDiff = (now, camera, img) => JSON.stringify({ wanted: camera, now, view: img && [img.width, img.height] });

/** The view's drawing-buffer size and its place on the page: a shot is of one layout only when these hold from its draw to its screenshot. */
const viewLayout = (page) => page.evaluate(() => {
  const c = document.querySelector("#view");
  const r = c.getBoundingClientRect();
  return [c.width, c.height, r.x, r.y, r.width, r.height].join(",");
});

/**
 * Two headless screenshots of the page's frame with the viewer's camera at `camera`, the first
 * after `draw(true)`, the second after `draw(false)` (each sets the camera and draws in the page,
 * and resolves to what was drawn), saved as `names[0]` and `names[1]`: [{ img, drawn }, { img,
 * drawn }]. Both are taken again until both are of this camera and of one layout of the view
 * (its drawing buffer's size and its place on the page, unchanged from each draw to its
 * screenshot: the page's layout can still move when a notice or a status line comes or goes);
 * the page's re-framing is held off meanwhile (`holdCamera`).
 */
export async function shotPair(page, camera, names, draw) {
  const release = await holdCamera(page);
  try {
    for (let tries = 0; ; tries++) {
      const shots = [];
      let diff = null;
      for (const first of [true, false]) {
        const drawn = await draw(first);
        const layout = await viewLayout(page);
        const img = await canvasPixels(page, names[first ? 0 : 1]);
        const now = await page.evaluate(() => window.odori.viewer.camera);
        const after = await viewLayout(page);
        if (!sameCamera(now, camera) || layout !== after || (!first && layout !== shots[0].layout)) {
          diff = `${cameraDiff(now, camera, img)}; the view (buffer w, h; x, y, w, h on the page) ${first ? "" : `at the first shot ${shots[0].layout}, at the second `}${layout} → ${after}`;
          break;
        }
        shots.push({ img, drawn, layout });
      }
      if (!diff) return shots;
      // The page moved the camera, resized or moved the view between the shots: both again.
      if (tries >= 10) throw new Error(`the camera keeps being moved by the page, or the view changes: ${diff}`);
      await new Promise((r) => setTimeout(r, 200));
    }
  } finally {
    await release();
  }
}

/** Headless screenshots of the page's frame (`player.drawNow`) with the viewer's camera at `camera`, morphs on and off (the control): { on, off }, each { img, drawn } (`viewer.lastDrawn()[0]`), of one view (`shotPair`). Morphs are left on. */
export async function shotsMorphsOnOff(page, camera, file) {
  const [on, off] = await shotPair(page, camera, [`${file}-on.png`, `${file}-off.png`], (on) => page.evaluate(({ on, camera }) => {
    const { viewer, player } = window.odori;
    viewer.setCamera(camera);
    viewer.setMorphs(on);
    player.drawNow();
    return viewer.lastDrawn()[0];
  }, { on, camera }));
  await page.evaluate(() => window.odori.viewer.setMorphs(true));
  return { on, off };
}

/** The head 頭's world pose ({ q, p }) and the body drawn, for clip `clip` at `t` s in the page's viewer (drawn there first). */
export const headPose = (page, clip, t) => page.evaluate(({ clip, t }) => {
  const { library, viewer, player } = window.odori;
  player.time = t;
  player.drawNow();
  const j = viewer.figureJoints(library, clip, t);
  const i = j.names.indexOf("頭");
  return { q: j.rotations.slice(4 * i, 4 * i + 4), p: j.positions.slice(3 * i, 3 * i + 3), body: j.body };
}, { clip, t });
