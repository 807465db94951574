// An MMD model's face morphs drawn (issue 28: "face morph keys play on the model"), on WebGL2
// and WebGPU, in the app: 初音ミク Ver2 (miku_v2.pmd) and the WAVEFILE dance (wavefile_v2.vmd)
// are imported in one set, the dance posed on her and drawn with her mesh. The reading of the
// files here is three r171's MMDParser (`three-mmd`), not the engine's: the VMD's morph keys give
// the frame where あ (the open mouth) is at its strongest key and one where まばたき (the blink)
// is fully on; the PMD's morphs give the vertices each moves (PMD morph elements index the base
// morph's vertices) and the skin tells which of them the head bone (頭) alone carries. Those
// vertices, posed by the head as the viewer drew it (`figureJoints`: world = R(頭) · (rest −
// rest(頭)) + pos(頭), exact for vertices weighted to 頭 alone) and moved by the key's weight,
// are projected through the engine's camera (`viewer.project`), looking the face in the eye.
// The same frame is drawn with morphs on and off (`viewer.setMorphs(false)`, the control):
// around the mouth (and the eyes) at least 500 drawn pixels change (about 2 cm² of face at this
// zoom); everywhere away from the moving morphs' vertices none does, so the difference is the
// morphs' alone; and at the blink the eye opening's dark and saturated iris pixels give way to
// the eyelid.
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
const vmdPath = join(data, "mmd", "motion", "wavefile_v2.vmd");
for (const p of [join(mikuDir, "miku_v2.pmd"), vmdPath]) if (!existsSync(p)) throw new Error(`${p} is missing (the MMD test data in ../shared/data)`);

const M = 0.08; // metres per MMD unit
const ab = (buf) => buf.buffer.slice(buf.byteOffset, buf.byteOffset + buf.byteLength);

/** The model's morphs as three's parser reads them (right-handed): name → [{ v, d }] (model vertex, offset in metres); and the vertices 頭 alone carries. */
function readModel() {
  const model = new MMDParser.Parser().parsePmd(ab(readFileSync(join(mikuDir, "miku_v2.pmd"))), true);
  const base = model.morphs.find((m) => m.type === 0);
  assert.ok(base, "a PMD has a base morph");
  const morphs = new Map();
  for (const m of model.morphs) {
    if (m === base) continue;
    morphs.set(m.name, m.elements.map((e) => ({ v: base.elements[e.index].index, d: e.position.map((x) => x * M) })));
  }
  const head = model.bones.findIndex((b) => b.name === "頭");
  assert.ok(head >= 0, "miku_v2 has 頭");
  const onHead = (v) => {
    const x = model.vertices[v];
    return x.skinWeights.every((w, k) => w === 0 || x.skinIndices[k] === head);
  };
  const rest = (v) => model.vertices[v].position.map((x) => x * M);
  return { morphs, onHead, rest, headRest: model.bones[head].position.map((x) => x * M), name: model.metadata.modelName };
}

/** WAVEFILE's morph keys by three's parser: name → [{ frame, weight }] in frame order. */
function readKeys() {
  const vmd = new MMDParser.Parser().parseVmd(ab(readFileSync(vmdPath)), true);
  const keys = new Map();
  for (const k of vmd.morphs) {
    if (!keys.has(k.morphName)) keys.set(k.morphName, []);
    keys.get(k.morphName).push({ frame: k.frameNum, weight: k.weight });
  }
  for (const list of keys.values()) list.sort((a, b) => a.frame - b.frame);
  return keys;
}

const rotate = (q, v) => {
  // v + 2 w (u × v) + 2 u × (u × v)
  const [x, y, z, w] = q;
  const c1 = [y * v[2] - z * v[1], z * v[0] - x * v[2], x * v[1] - y * v[0]];
  const c2 = [y * c1[2] - z * c1[1], z * c1[0] - x * c1[2], x * c1[1] - y * c1[0]];
  return [0, 1, 2].map((i) => v[i] + 2 * w * c1[i] + 2 * c2[i]);
};

let server;
before(async () => { server = await startServer(); });
after(() => server && server.stop());

const CHANGED = (a, b) => Math.max(Math.abs(a[0] - b[0]), Math.abs(a[1] - b[1]), Math.abs(a[2] - b[2])) > 24;
/** The iris and the eye's dark lines: dark, or strongly coloured (Miku's eyes are teal). */
const IRIS = ([r, g, b]) => Math.max(r, g, b) < 110 || Math.max(r, g, b) - Math.min(r, g, b) > 90;

for (const backend of ["webgl2", "webgpu"]) {
  test(`miku_v2's face plays WAVEFILE's morph keys (mouth open, eyes closed), morphs on vs off, on ${backend}`, async () => {
    const model = readModel();
    const keys = readKeys();
    const strongest = (name) => {
      const list = keys.get(name);
      assert.ok(list && list.length, `WAVEFILE keys ${name}`);
      return list.reduce((a, k) => (k.weight > a.weight ? k : a));
    };
    const mouth = strongest("あ");
    const blink = strongest("まばたき");
    assert.ok(mouth.weight >= 0.3 && blink.weight >= 0.99, `あ ${mouth.weight} at ${mouth.frame}, まばたき ${blink.weight} at ${blink.frame}`);
    const files = readdirSync(mikuDir).filter((f) => /\.(pmd|bmp)$/i.test(f)).map((f) => ({ name: `miku_v2/${f}`, b64: readFileSync(join(mikuDir, f)).toString("base64") }));
    files.push({ name: "wavefile_v2.vmd", b64: readFileSync(vmdPath).toString("base64") });
    const { browser, page, logs } = await launch(backend);
    try {
      await openApp(page, server, backend);
      const setup = await page.evaluate(({ files, modelName }) => {
        const { library, player, viewer } = window.odori;
        const r = library.importFiles(files.map((f) => ({ name: f.name, bytes: window.__test.bytes(f.b64) })), { model: modelName });
        const clip = r.motions[0]?.clip;
        // The hair's springs off: both draws of a frame then pose every bone alike.
        viewer.setSprings(false);
        player.select(clip.id);
        player.pause();
        return { problems: r.problems, notices: r.notices, clip, rig: r.motions[0]?.rig, morphsDefault: viewer.morphs };
      }, { files, modelName: model.name });
      assert.equal(setup.problems.length, 0, JSON.stringify(setup.problems));
      assert.ok(setup.clip && setup.clip.hasMesh, `WAVEFILE plays on miku_v2's mesh (posed on ${setup.rig})`);
      assert.equal(setup.morphsDefault, true, "morphs are on by default");
      assert.ok(setup.notices.some((n) => /morph \(face\) keys kept aside: played/.test(n)), setup.notices.join("\n"));
      await waitUntil(() => page.evaluate(() => { window.odori.player.drawNow(); return window.odori.viewer.texturesLoading === 0; }), { what: "miku's textures decoded" });

      /** Draws frame `frame` with the camera on the face, morphs on and off; returns the screenshots, the head's pose and what was drawn. */
      const shoot = async (frame, label) => {
        const pose = await page.evaluate(({ clip, t }) => {
          const { library, viewer, player } = window.odori;
          player.time = t;
          viewer.setMorphs(true);
          player.drawNow();
          const j = viewer.figureJoints(library, clip, t);
          const i = j.names.indexOf("頭");
          const q = j.rotations.slice(4 * i, 4 * i + 4), p = j.positions.slice(3 * i, 3 * i + 3);
          return { q, p, body: j.body };
        }, { clip: setup.clip.id, t: frame / 30 });
        // Looking the face in the eye: the head's forward (+z at rest) from the front, 0.55 m away.
        const fwd = rotate(pose.q, [0, 0, 1]);
        const eye = rotate(pose.q, [0, 0.06, 0]).map((x, k) => x + pose.p[k]);
        const out = { pose };
        const camera = { target: eye, yaw: Math.atan2(fwd[0], fwd[2]), pitch: Math.asin(Math.max(-1, Math.min(1, fwd[1]))), distance: 0.55, fovY: 0.5 };
        for (const on of [true, false]) {
          // The page may frame the figures again meanwhile (a resize as notices come and go):
          // drawn again until the screenshot is of this camera and of the canvas's size.
          for (let tries = 0; ; tries++) {
            const drawn = await page.evaluate(({ on, camera }) => {
              const { viewer, player } = window.odori;
              viewer.setCamera(camera);
              viewer.setMorphs(on);
              player.drawNow();
              return viewer.lastDrawn()[0];
            }, { on, camera });
            const img = await canvasPixels(page, `${backend}-mmd-morphs-${label}-${on ? "on" : "off"}.png`);
            const now = await page.evaluate(() => window.odori.viewer.camera);
            const same = Math.abs(now.yaw - camera.yaw) < 1e-4 && Math.abs(now.pitch - camera.pitch) < 1e-4 && Math.abs(now.distance - camera.distance) < 1e-4 && now.target.every((x, k) => Math.abs(x - camera.target[k]) < 1e-4);
            if (same && (on || (img.width === out.img.width && img.height === out.img.height))) {
              out[on ? "drawn" : "control"] = drawn;
              out[on ? "img" : "ctl"] = img;
              break;
            }
            assert.ok(tries < 10, "the camera keeps being moved by the page");
          }
        }
        await page.evaluate(() => window.odori.viewer.setMorphs(true));
        return out;
      };

      /** The projected box (pixels, padded) of a morph's head-carried vertices at rest and moved by `weight`. */
      const boxOf = async (name, weight, pose, padPx = 4) => {
        const els = model.morphs.get(name).filter((e) => model.onHead(e.v) && Math.hypot(...e.d) > 1e-4);
        const world = (p) => rotate(pose.q, p.map((x, k) => x - model.headRest[k])).map((x, k) => x + pose.p[k]);
        const pts = els.flatMap((e) => { const r = model.rest(e.v); return [world(r), world(r.map((x, k) => x + weight * e.d[k]))]; });
        const xy = (await page.evaluate((ps) => ps.map((p) => window.odori.viewer.project(p[0], p[1], p[2])), pts)).filter(Boolean);
        const xs = xy.map((p) => p[0]), ys = xy.map((p) => p[1]);
        return { n: els.length, x0: Math.floor(Math.min(...xs)) - padPx, x1: Math.ceil(Math.max(...xs)) + padPx, y0: Math.floor(Math.min(...ys)) - padPx, y1: Math.ceil(Math.max(...ys)) + padPx };
      };
      const inBox = (b, x, y) => x >= b.x0 && x <= b.x1 && y >= b.y0 && y <= b.y1;
      const count = (img, b, pred) => { let n = 0; for (let y = Math.max(0, b.y0); y <= Math.min(img.height - 1, b.y1); y++) for (let x = Math.max(0, b.x0); x <= Math.min(img.width - 1, b.x1); x++) if (pred(x, y)) n++; return n; };
      /** Changed pixels inside `box`, and outside every box of `moving` (where nothing should change). */
      const diff = (s, box, moving) => {
        const changed = (x, y) => CHANGED(pixel(s.img, x, y), pixel(s.ctl, x, y));
        const inside = count(s.img, box, changed);
        const all = { x0: 0, y0: 0, x1: s.img.width - 1, y1: s.img.height - 1 };
        const outside = count(s.img, all, (x, y) => !moving.some((b) => inBox(b, x, y)) && changed(x, y));
        return { inside, area: (box.x1 - box.x0 + 1) * (box.y1 - box.y0 + 1), outside };
      };
      /** Boxes of every morph weighted at `frame` (by the parser's keys, held outside them), with their weights. */
      const movingAt = async (frame, pose) => {
        const out = [];
        for (const [name, list] of keys) {
          if (!model.morphs.has(name)) continue;
          let w = list[0].weight;
          for (let k = 0; k < list.length; k++) {
            if (list[k].frame <= frame) w = list[k].weight;
            if (list[k].frame > frame) { const a = list[k - 1]; if (a) w = a.weight + ((list[k].weight - a.weight) * (frame - a.frame)) / (list[k].frame - a.frame); break; }
          }
          if (Math.abs(w) > 1e-4 && model.morphs.get(name).some((e) => model.onHead(e.v))) out.push(await boxOf(name, w, pose, 8));
        }
        return out;
      };

      // The mouth: あ at its strongest key.
      const m = await shoot(mouth.frame, "mouth");
      assert.equal(m.pose.body, "own", "drawn with the model's own mesh");
      assert.ok(m.drawn.morphed > 0 && m.control.morphed === 0, `vertices morphed: on ${m.drawn.morphed}, off ${m.control.morphed}`);
      const mouthBox = await boxOf("あ", mouth.weight, m.pose);
      const md = diff(m, mouthBox, await movingAt(mouth.frame, m.pose));
      console.log(`${backend}: frame ${mouth.frame} (あ ${mouth.weight.toFixed(2)}): ${m.drawn.morphed} drawn vertices morphed; ${md.inside} of ${md.area} pixels around the mouth's ${mouthBox.n} vertices (x ${mouthBox.x0}–${mouthBox.x1}, y ${mouthBox.y0}–${mouthBox.y1}) changed against morphs off; ${md.outside} changed away from the weighted morphs`);
      assert.ok(md.inside >= 500, `the mouth does not open: ${md.inside} of ${md.area} pixels changed`);
      assert.ok(md.outside <= 0.01 * md.inside, `pixels changed away from the morphs: ${md.outside}`);

      // The eyes: まばたき fully on.
      const e = await shoot(blink.frame, "blink");
      const eyeBox = await boxOf("まばたき", blink.weight, e.pose);
      const ed = diff(e, eyeBox, await movingAt(blink.frame, e.pose));
      // Of the pixels the blink changed (the hair round the eyes is teal too, and stays), how
      // many are iris-like open and closed.
      const changedAt = (x, y) => CHANGED(pixel(e.img, x, y), pixel(e.ctl, x, y));
      const irisOn = count(e.img, eyeBox, (x, y) => changedAt(x, y) && IRIS(pixel(e.img, x, y)));
      const irisOff = count(e.ctl, eyeBox, (x, y) => changedAt(x, y) && IRIS(pixel(e.ctl, x, y)));
      console.log(`${backend}: frame ${blink.frame} (まばたき ${blink.weight.toFixed(2)}): ${ed.inside} of ${ed.area} pixels around the eyes' ${eyeBox.n} vertices changed; of them iris-like ${irisOff} open (morphs off) → ${irisOn} closed; ${ed.outside} changed away from the weighted morphs`);
      assert.ok(ed.inside >= 500, `the eyes do not close: ${ed.inside} of ${ed.area} pixels changed`);
      assert.ok(irisOn < 0.5 * irisOff, `the iris still shows: ${irisOn} pixels against ${irisOff} open`);
      assert.ok(ed.outside <= 0.01 * ed.inside, `pixels changed away from the morphs: ${ed.outside}`);

      // The same dance as a project source on its model (the face keys read from the VMD the
      // project keeps), miku_v2 also chosen as the character: the dance is drawn on its own
      // model's mesh (a project dance is linked to the model kept with it), and the same
      // vertices move at the mouth's frame as for the library's import; none with morphs off.
      const proj = await page.evaluate(({ vmd, pmd, t, libClip, modelName }) => {
        const { library, viewer } = window.odori;
        const r = window.odori.project.project.importOnModelInto(library, "wavefile_v2.vmd", window.__test.bytes(vmd), {}, "miku_v2.pmd", window.__test.bytes(pmd));
        const id = r.clips[0].id;
        const character = library.mmdModels().find((m) => m.name === modelName).characterId;
        viewer.setCharacter(library, character);
        viewer.deferRetarget = false;
        const drawAt = (clip, on) => { viewer.setMorphs(on); viewer.draw(library, [{ clip, timeSecs: t }]); return viewer.lastDrawn()[0]; };
        const out = { on: drawAt(id, true), off: drawAt(id, false), library: drawAt(libClip, true) };
        viewer.setMorphs(true);
        return out;
      }, { vmd: files.at(-1).b64, pmd: files.find((f) => /\.pmd$/i.test(f.name)).b64, t: mouth.frame / 30, libClip: setup.clip.id, modelName: model.name });
      console.log(`${backend}: WAVEFILE as a project source on miku_v2 (its own model's mesh): ${proj.on.morphed} drawn vertices morphed at frame ${mouth.frame} (the library's import: ${proj.library.morphed}), ${proj.off.morphed} with morphs off`);
      assert.equal(proj.on.body, "own");
      assert.ok(proj.on.morphed > 0 && proj.on.morphed === proj.library.morphed && proj.off.morphed === 0, JSON.stringify(proj));
      assert.ok(!logs.some((l) => l.startsWith("[pageerror]") || /Validation/.test(l)), logs.join("\n"));
    } finally {
      await browser.close();
    }
  });
}
