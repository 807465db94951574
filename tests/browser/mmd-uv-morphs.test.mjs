// An MMD model's UV morph played (issue 28: "face morph keys play on the model"), on WebGL2 and
// WebGPU, in the app: Gene (Gene_light.pmx) has one UV morph, メッシュなし (PMX type 3, the base
// UV: v + 0.5 on 6,747 vertices of the hair material 髪, moving their UVs to the other half of
// hair2.png). No shared motion keys it, so the test writes the VMD it imports: 29_Terrified's
// bone keys except the hair chains' and earrings' (names read as the file's Shift-JIS bytes; unkeyed, the
// hair and earring bones stay at rest under 頭, so 96 % of the hair material's vertices move with the head rigidly) and one
// morph key, メッシュなし at weight 1 at frame 0 (its name written in Shift-JIS by a table made
// from the browser-independent TextDecoder). The reading of the model is three r171's
// MMDParser (`three-mmd`): the morph's vertices, posed by the head as the viewer drew it
// (`figureJoints`; world = R(頭) · (rest − rest(頭)) + pos(頭), exact for vertices carried by
// 頭 and its unkeyed hair bones), projected through the engine's camera (`viewer.project`),
// give the morph's box on screen. The same frame is drawn with morphs on and off
// (`viewer.setMorphs(false)`, the control, weight 0): in the box at least 300 pixels change,
// away from it under 1 % as many, and no vertex is morphed in either draw (the change is the
// UVs' alone). Screenshots go to tests/artifacts/.
import { test, before, after } from "node:test";
import assert from "node:assert/strict";
import { readFileSync } from "node:fs";
import { join } from "node:path";
import { data, startServer, launch, openApp, pixel } from "./harness.mjs";
import { MMDParser, M, ab, needData, faceCamera, onPosedHead, headPose, shotsMorphsOnOff, projectedBox, inBox, countIn, CHANGED, shiftJis, modelFiles, importOnModel } from "./mmd-common.mjs";

const geneDir = join(data, "mmd", "gene");
const vmdPath = join(geneDir, "motion", "29_Terrified.vmd");
needData(join(geneDir, "Gene_light.pmx"), vmdPath);
const MORPH = "メッシュなし";

/** 29_Terrified's bone keys without the hair's, and one key of `name` at weight 1, frame 0. */
function vmdKeying(buf, name) {
  const sjis = new TextDecoder("shift_jis");
  const bones = buf.readUInt32LE(50);
  const kept = [];
  for (let k = 0; k < bones; k++) {
    const s = 54 + k * 111;
    const raw = buf.subarray(s, s + 15);
    const end = raw.indexOf(0);
    const bone = sjis.decode(end < 0 ? raw : raw.subarray(0, end));
    if (!/髪|アホ毛|イヤリング/.test(bone)) kept.push(buf.subarray(s, s + 111));
  }
  const key = Buffer.alloc(23);
  shiftJis(name).copy(key, 0);
  key.writeUInt32LE(0, 15);
  key.writeFloatLE(1, 19);
  const u32 = (n) => { const b = Buffer.alloc(4); b.writeUInt32LE(n); return b; };
  return { vmd: Buffer.concat([buf.subarray(0, 50), u32(kept.length), ...kept, u32(1), key, Buffer.alloc(12)]), dropped: bones - kept.length };
}

/** Gene by three's parser: the UV morph's vertices (rest positions, metres), checked to hang from 頭 through unkeyed hair bones only; 頭's rest position. */
function readModel() {
  const model = new MMDParser.Parser().parsePmx(ab(readFileSync(join(geneDir, "Gene_light.pmx"))), true);
  const morph = model.morphs.find((m) => m.name === MORPH);
  assert.ok(morph && morph.type === 3, `${MORPH} is a UV morph of the base UV`);
  const head = model.bones.findIndex((b) => b.name === "頭");
  const rigid = (b) => { for (let k = b; k >= 0; k = model.bones[k].parentIndex) { if (k === head) return true; if (!/髪|アホ毛|イヤリング/.test(model.bones[k].name)) return false; } return false; };
  const verts = morph.elements.map((e) => e.index);
  const onHead = verts.filter((v) => { const x = model.vertices[v]; return x.skinWeights.every((w, k) => w === 0 || rigid(x.skinIndices[k])); });
  return { name: model.metadata.modelName, all: verts.length, rest: onHead.map((v) => model.vertices[v].position.map((x) => x * M)), headRest: model.bones[head].position.map((x) => x * M), shift: morph.elements[0].uv };
}

let server;
before(async () => { server = await startServer(); });
after(() => server && server.stop());

for (const backend of ["webgl2", "webgpu"]) {
  test(`Gene's hair takes the UV morph ${MORPH} at weight 1, morphs on vs off, on ${backend}`, async () => {
    const model = readModel();
    assert.ok(model.rest.length >= 0.9 * model.all, `${model.rest.length} of the morph's ${model.all} vertices move with 頭 rigidly`);
    const { vmd, dropped } = vmdKeying(readFileSync(vmdPath), MORPH);
    assert.ok(dropped > 0, "the hair's keys are dropped");
    const files = modelFiles(geneDir, "gene", "Gene_light.pmx", { subfolders: ["light"], extra: [{ name: "29_Terrified_uv.vmd", bytes: vmd }] });
    const { browser, page, logs } = await launch(backend);
    try {
      await openApp(page, server, backend);
      const setup = await importOnModel(page, files, model.name, "Gene");
      assert.ok(!setup.notices.some((n) => n.includes(MORPH) && /not played/.test(n)), `the UV morph is played: ${setup.notices.join("\n")}`);

      const t = 1.0;
      const pose = await headPose(page, setup.clip.id, t);
      assert.equal(pose.body, "own", "drawn with the model's own mesh");
      const { on, off } = await shotsMorphsOnOff(page, faceCamera(pose, 0.05, 0.9), `${backend}-mmd-uv-morph`);
      const box = await projectedBox(page, model.rest.map(onPosedHead(pose, model.headRest)), 6);
      const changed = (x, y) => CHANGED(pixel(on.img, x, y), pixel(off.img, x, y));
      const inside = countIn(on.img, box, changed);
      const all = { x0: 0, y0: 0, x1: on.img.width - 1, y1: on.img.height - 1 };
      const outside = countIn(on.img, all, (x, y) => !inBox(box, x, y) && changed(x, y));
      console.log(`${backend}: ${MORPH} at 1 (UV offset ${JSON.stringify(model.shift)}): ${inside} pixels in its vertices' box (x ${box.x0}–${box.x1}, y ${box.y0}–${box.y1}, ${model.rest.length} vertices) changed against morphs off; ${outside} changed elsewhere; vertices morphed on ${on.drawn.morphed}, off ${off.drawn.morphed}`);
      assert.equal(on.drawn.morphed, 0, "no vertex morph is keyed: the change is the UVs'");
      assert.ok(inside >= 300, `the hair's UVs do not move: ${inside} pixels changed`);
      assert.ok(outside <= 0.01 * inside, `pixels changed away from the morph's vertices: ${outside}`);
      assert.ok(!logs.some((l) => l.startsWith("[pageerror]") || /Validation/.test(l)), logs.join("\n"));
    } finally {
      await browser.close();
    }
  });
}
