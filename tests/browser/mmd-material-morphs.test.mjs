// An MMD model's material morphs drawn (issue 28 item 2: "the model looks like itself"), on
// WebGL2 and WebGPU, in the app: Gene (Gene_light.pmx) and her gesture 29_Terrified.vmd, whose
// face turns pale by the material morph 青ざめ (PMX type 8: add 1 to the alpha of the overlay
// material 青ざめ, drawn at alpha 0 otherwise, textured pale.png). The test writes the VMD it
// imports: the gesture's bone keys as they are and, of its morph keys, 青ざめ's only (read and
// written here, names kept as the file's Shift-JIS bytes), so nothing but the material morph
// changes the face. The reading of the model is three r171's MMDParser (`three-mmd`): the
// overlay material's vertices (its triangles' run), posed by the head as the viewer drew it
// (`figureJoints`, exact for vertices carried by 頭 alone), projected through the engine's
// camera (`viewer.project`) looking the face in the eye, give the overlay's box on screen.
// The same frame is drawn with morphs on and off (`viewer.setMorphs(false)`, the control): in
// the box at least 300 pixels change, away from it under 1 % as many, and no vertex is
// morphed in either draw (the change is the material's alone).
// Screenshots go to tests/artifacts/.
import { test, before, after } from "node:test";
import assert from "node:assert/strict";
import { readFileSync } from "node:fs";
import { join } from "node:path";
import { data, startServer, launch, openApp, pixel } from "./harness.mjs";
import { MMDParser, M, ab, needData, faceCamera, onPosedHead, headPose, shotsMorphsOnOff, CHANGED, modelFiles, importOnModel } from "./mmd-common.mjs";

const geneDir = join(data, "mmd", "gene");
const vmdPath = join(geneDir, "motion", "29_Terrified.vmd");
needData(join(geneDir, "Gene_light.pmx"), vmdPath);

const MORPH = "青ざめ";

/** The VMD with its bone keys and, of its morph keys, `name`'s only; and those keys ({ frame, weight }). */
function onlyMorph(buf, name) {
  const sjis = new TextDecoder("shift_jis");
  let at = 50;
  const bones = buf.readUInt32LE(at);
  at += 4 + bones * 111;
  const morphs = buf.readUInt32LE(at);
  const kept = [], keys = [];
  for (let k = 0; k < morphs; k++) {
    const s = at + 4 + k * 23;
    const raw = buf.subarray(s, s + 15);
    const end = raw.indexOf(0);
    if (sjis.decode(end < 0 ? raw : raw.subarray(0, end)) !== name) continue;
    kept.push(buf.subarray(s, s + 23));
    keys.push({ frame: buf.readUInt32LE(s + 15), weight: buf.readFloatLE(s + 19) });
  }
  const count = Buffer.alloc(4);
  count.writeUInt32LE(kept.length);
  // No camera, light or self-shadow keys.
  return { vmd: Buffer.concat([buf.subarray(0, at), count, ...kept, Buffer.alloc(12)]), keys: keys.sort((a, b) => a.frame - b.frame) };
}

/** Gene by three's parser (right-handed): the overlay material's vertices carried by 頭 alone, rest positions in metres; 頭's rest position. */
function readModel() {
  const model = new MMDParser.Parser().parsePmx(ab(readFileSync(join(geneDir, "Gene_light.pmx"))), true);
  const mi = model.materials.findIndex((m) => m.name === MORPH);
  assert.ok(mi >= 0, `Gene has the material ${MORPH}`);
  const morph = model.morphs.find((m) => m.name === MORPH);
  assert.ok(morph && morph.type === 8 && morph.elements.some((e) => e.index === mi && e.type === 1 && e.diffuse[3] === 1), `${MORPH} adds alpha to its material`);
  assert.equal(model.materials[mi].diffuse[3], 0, "the overlay is drawn at alpha 0 without the morph");
  const start = model.materials.slice(0, mi).reduce((n, m) => n + m.faceCount, 0);
  const head = model.bones.findIndex((b) => b.name === "頭");
  const verts = new Set();
  // three's parser keeps faces as { indices: [a, b, c] }, one per triangle, and each
  // material's faceCount in triangles.
  for (let t = start; t < start + model.materials[mi].faceCount; t++) for (const v of model.faces[t].indices) verts.add(v);
  const onHead = [...verts].filter((v) => { const x = model.vertices[v]; return x.skinWeights.every((w, k) => w === 0 || x.skinIndices[k] === head); });
  return { name: model.metadata.modelName, all: verts.size, rest: onHead.map((v) => model.vertices[v].position.map((x) => x * M)), headRest: model.bones[head].position.map((x) => x * M) };
}

let server;
before(async () => { server = await startServer(); });
after(() => server && server.stop());


for (const backend of ["webgl2", "webgpu"]) {
  test(`Gene's face turns pale by the material morph ${MORPH} (29_Terrified's key), morphs on vs off, on ${backend}`, async () => {
    const model = readModel();
    const { vmd, keys } = onlyMorph(readFileSync(vmdPath), MORPH);
    const strong = keys.filter((k) => k.weight >= 0.99);
    assert.ok(strong.length, `29_Terrified keys ${MORPH} at 1: ${JSON.stringify(keys)}`);
    // A frame inside a run of keys at 1 (held between them), away from the gesture's start.
    const frame = strong.length > 1 ? Math.round((strong[0].frame + strong[1].frame) / 2) : strong[0].frame;
    const files = modelFiles(geneDir, "gene", "Gene_light.pmx", { subfolders: ["light"], extra: [{ name: "29_Terrified_pale.vmd", bytes: vmd }] });
    const { browser, page, logs } = await launch(backend);
    try {
      await openApp(page, server, backend);
      const setup = await importOnModel(page, files, model.name, "Gene");
      // Gene's one UV morph (メッシュなし, base UV) is played, not named as unplayed (mmd-uv-morphs).
      assert.ok(!setup.notices.some((n) => /not played/.test(n)), `no morph is named as not played: ${setup.notices.join("\n")}`);

      const pose = await headPose(page, setup.clip.id, frame / 30);
      assert.equal(pose.body, "own", "drawn with the model's own mesh");
      const shots = await shotsMorphsOnOff(page, faceCamera(pose, 0.08, 0.6), `${backend}-mmd-material-morph`);

      // The overlay's box on screen: its head-carried vertices posed as drawn.
      const world = onPosedHead(pose, model.headRest);
      const xy = (await page.evaluate((ps) => ps.map((p) => window.odori.viewer.project(p[0], p[1], p[2])), model.rest.map(world))).filter(Boolean);
      assert.ok(xy.length >= 0.5 * model.all, `the overlay's vertices on 頭 alone: ${xy.length} of ${model.all}`);
      const pad = 6;
      const box = { x0: Math.floor(Math.min(...xy.map((p) => p[0]))) - pad, x1: Math.ceil(Math.max(...xy.map((p) => p[0]))) + pad, y0: Math.floor(Math.min(...xy.map((p) => p[1]))) - pad, y1: Math.ceil(Math.max(...xy.map((p) => p[1]))) + pad };
      const { on, off } = shots;
      let inside = 0, outside = 0, brighter = 0;
      for (let y = 0; y < on.img.height; y++) for (let x = 0; x < on.img.width; x++) {
        const a = pixel(on.img, x, y), b = pixel(off.img, x, y);
        if (!CHANGED(a, b)) continue;
        if (x >= box.x0 && x <= box.x1 && y >= box.y0 && y <= box.y1) {
          inside++;
          if (a[2] - a[0] > b[2] - b[0]) brighter++;
        } else outside++;
      }
      console.log(`${backend}: frame ${frame} (${MORPH} at 1): ${inside} pixels in the overlay's box (x ${box.x0}–${box.x1}, y ${box.y0}–${box.y1}, ${xy.length} vertices) changed against morphs off, ${brighter} of them bluer; ${outside} changed elsewhere; vertices morphed on ${on.drawn.morphed}, off ${off.drawn.morphed}`);
      assert.equal(on.drawn.morphed, 0, "no vertex morph is keyed: the change is the material's");
      assert.ok(inside >= 300, `the face does not turn pale: ${inside} pixels changed`);
      assert.ok(outside <= 0.01 * inside, `pixels changed away from the overlay: ${outside}`);
      assert.ok(!logs.some((l) => l.startsWith("[pageerror]") || /Validation/.test(l)), logs.join("\n"));
    } finally {
      await browser.close();
    }
  });
}
