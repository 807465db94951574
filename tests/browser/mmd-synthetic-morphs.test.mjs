// MMD bone morphs, material-morph factors and PMX's sub-texture sphere mode drawn (issue 28
// item 2: "the model looks and moves like itself"), on WebGL2 and WebGPU, in the app, on a model
// the test writes byte by byte (`pmx-writer.mjs`): no shared model has a bone morph or a
// sub-texture, and Gene's material morphs change only alpha. The model is a standard MMD
// humanoid skeleton (the engine's standard table's bones, without IK) carrying quads facing the
// camera: the torso's (上半身) and the head's (頭) of material A — textured (a BMP), a multiplied
// sphere map (.sph, a BMP) and its own toon ramp —, the legs' (下半身) of material B, plain
// colour, and one beside the torso of material C, untextured, its sphere map a sub-texture (PMX
// sphere mode 3) red on its left half and blue on its right, sampled at the additional UV 1 that
// runs 0 → 1 across the quad. Its morphs: one bone morph moving and turning 頭, and six
// material morphs on A alone, each changing one factor: diffuse × (1, 0.3, 0.3), ambient + 0.5,
// specular + 0.8, sphere + 0.5, toon × (0.3, 1, 1), sphere × 0 (alpha too: the map blended away, as
// MMD's shader does). A VMD, written too, keys each at weight 1 at
// its own frame (0 five frames either side), the body at rest.
// Three r171's MMDParser (`three-mmd`, a reader no one here wrote) reads both files back: every
// field written, every morph offset and key, as the test meant them.
// Each morph's frame is drawn with morphs on and off (`viewer.setMorphs(false)`, the control),
// the camera on the model, the quads' corners projected through the engine's camera
// (`viewer.project`). The bone morph: the head quad's pixels move — the moved quad's centre
// drawn in the colour the rest quad's centre had, the rest centre uncovered —, every changed
// pixel in the box of the head quad's rest and moved corners (under 1 % elsewhere), no vertex
// morphed. Each material morph: at least half the torso quad's box changes, the legs' box
// (material B) not at all, under 1 % outside material A, and the mean colour at the torso's
// centre moves the way the engine's rule (colour × mul + add, docs/mmd-rig.md) says for the
// factor, against the control: diffuse and toon drop the channels they scale and leave the
// others within 6; ambient, specular and sphere adds brighten every channel. The sub-texture:
// the quad's left quarter is red, its right quarter blue (a sphere map looked up by the normal
// gives a flat quad one colour; not drawn, it was grey).
// Screenshots go to tests/artifacts/.
import { test, before, after } from "node:test";
import assert from "node:assert/strict";
import { startServer, launch, openApp, pixel } from "./harness.mjs";
import { MMDParser, M, ab, rotate, shotsMorphsOnOff, inBox, countIn, CHANGED, importOnModel } from "./mmd-common.mjs";
import { writePmx, writeVmd, writeBmp, materialOffset } from "./pmx-writer.mjs";

const MODEL = "odori-morph-test";

/** The standard humanoid's bones (the engine's standard MMD skeleton's table, MMD file frame), no IK. */
function humanoidBones() {
  const bones = [
    ["全ての親", null, [0, 0, 0]], ["センター", "全ての親", [0, 8, 0]], ["グルーブ", "センター", [0, 8.2, 0]],
    ["下半身", "グルーブ", [0, 11.4, 0.2]], ["上半身", "グルーブ", [0, 11.4, 0.2]], ["上半身2", "上半身", [0, 12.8, 0.1]],
    ["首", "上半身2", [0, 15.6, 0.3]], ["頭", "首", [0, 16.6, 0.1]],
  ];
  const side = [
    ["肩", "上半身2", [0.6, 15.2, 0.3]], ["腕", "肩", [1.6, 15.0, 0.4]], ["ひじ", "腕", [3.9, 12.9, 0.4]], ["手首", "ひじ", [5.8, 11.0, 0.2]],
    ["足", "下半身", [1.0, 10.4, 0.2]], ["ひざ", "足", [1.0, 5.8, 0.0]], ["足首", "ひざ", [1.0, 1.2, 0.4]], ["つま先", "足首", [1.0, 0.0, -1.4]],
  ];
  for (const [s, sign] of [["左", 1], ["右", -1]])
    for (const [n, parent, p] of side) bones.push([`${s}${n}`, bones.some((b) => b[0] === parent) ? parent : `${s}${parent}`, [p[0] * sign, p[1], p[2]]]);
  return bones.map(([name, parent, p]) => ({ name, p, parent: parent === null ? -1 : bones.findIndex((b) => b[0] === parent) }));
}

/** Quads facing the viewer (front is −z in MMD's file frame) at z = −1.5 units. */
const QUADS = {
  torso: { bone: "上半身", material: 0, x: [-2.5, 2.5], y: [11.5, 15.0] },
  head: { bone: "頭", material: 0, x: [-1.5, 1.5], y: [16.0, 19.0] },
  legs: { bone: "下半身", material: 1, x: [-2.5, 2.5], y: [6.0, 10.5] },
  sub: { bone: "上半身", material: 2, x: [3.5, 6.5], y: [11.5, 15.0] },
};
const Z = -1.5;
const corners = (q) => [[q.x[0], q.y[0]], [q.x[1], q.y[0]], [q.x[1], q.y[1]], [q.x[0], q.y[1]]];

/** The bone morph: 頭 moved 4 units toward +x and turned 0.4 rad about z (MMD's file frame). */
const BONE_T = [4, 0, 0];
const BONE_Q = [0, 0, Math.sin(0.2), Math.cos(0.2)];

/** The morphs, each keyed at 1 at its frame: what each does and the direction the drawn colour takes. */
const MORPHS = [
  { name: "bone-move", frame: 10, type: "bone", offsets: (bones) => [{ bone: bones.findIndex((b) => b.name === "頭"), t: BONE_T, q: BONE_Q }] },
  { name: "diffuse", frame: 20, type: "material", offsets: () => [materialOffset(0, 0, { diffuse: [1, 0.3, 0.3, 1] })], expect: ["same", "down", "down"] },
  { name: "ambient", frame: 30, type: "material", offsets: () => [materialOffset(0, 1, { ambient: [0.5, 0.5, 0.5] })], expect: ["up", "up", "up"] },
  { name: "specular", frame: 40, type: "material", offsets: () => [materialOffset(0, 1, { specular: [0.8, 0.8, 0.8] })], expect: ["up", "up", "up"] },
  { name: "sphere", frame: 50, type: "material", offsets: () => [materialOffset(0, 1, { sphere: [0.5, 0.5, 0.5, 0] })], expect: ["up", "up", "up"] },
  { name: "toon", frame: 60, type: "material", offsets: () => [materialOffset(0, 0, { toon: [0.3, 1, 1, 1] })], expect: ["down", "same", "same"] },
  // Sphere × 0 in every channel, alpha too: MMD's shader blends the map away by mul.a + add.a,
  // so the grey (160) multiplied sphere goes and the colour brightens (× 0 per channel alone
  // would turn it black).
  { name: "sphere-off", frame: 70, type: "material", offsets: () => [materialOffset(0, 0, { sphere: [0, 0, 0, 0] })], expect: ["up", "up", "up"] },
];
const LAST_FRAME = 80;
/** The sub-texture's two halves. */
const SUB_LEFT = [255, 64, 64], SUB_RIGHT = [64, 64, 255];

/** The model, its files and the VMD, as written, with the spec they were written from. */
function makeFiles() {
  const bones = humanoidBones();
  const vertices = [], indices = [];
  const byMaterial = [[], [], []];
  for (const q of Object.values(QUADS)) byMaterial[q.material].push(q);
  const counts = byMaterial.map((qs) => {
    for (const q of qs) {
      const b = bones.findIndex((x) => x.name === q.bone);
      const base = vertices.length;
      const uvs = [[0, 1], [1, 1], [1, 0], [0, 0]];
      // Additional UV 1 runs 0 → 1 left to right (the sub-texture's u), 0 → 1 top to bottom.
      corners(q).forEach(([x, y], k) => vertices.push({ p: [x, y, Z], n: [0, 0, -1], uv: uvs[k], auv: [[uvs[k][0], uvs[k][1], 0, 0]], bones: [b] }));
      indices.push(base, base + 1, base + 2, base, base + 2, base + 3);
    }
    return qs.length * 6;
  });
  const material = (name, o) => ({ name, specular: [0, 0, 0], power: 2, ambient: [0.4, 0.4, 0.4], flags: 0x01, edgeColour: [0, 0, 0, 1], edgeSize: 1, ...o });
  const model = {
    name: MODEL,
    comment: "Written by tests/browser/mmd-synthetic-morphs.test.mjs",
    additionalUvs: 1,
    vertices, indices,
    textures: ["tex\\body.bmp", "tex\\shine.sph", "tex\\ramp.bmp", "tex\\sub.bmp"],
    materials: [
      material("A", { diffuse: [0.5, 0.5, 0.5, 1], texture: 0, sphere: 1, sphereMode: 1, toon: { texture: 2 }, count: counts[0] }),
      material("B", { diffuse: [0.3, 0.5, 0.8, 1], texture: -1, sphere: -1, sphereMode: 0, toon: { texture: 2 }, count: counts[1] }),
      // Untextured, its sphere map a sub-texture (PMX sphere mode 3): red left, blue right.
      material("C", { diffuse: [0.8, 0.8, 0.8, 1], texture: -1, sphere: 3, sphereMode: 3, toon: { texture: 2 }, count: counts[2] }),
    ],
    bones,
    morphs: MORPHS.map((m) => ({ name: m.name, panel: 4, type: m.type, offsets: m.offsets(bones) })),
  };
  const vmd = {
    model: MODEL,
    bones: [{ name: "センター", frame: 0 }, { name: "センター", frame: LAST_FRAME }],
    morphs: MORPHS.flatMap((m) => [{ name: m.name, frame: m.frame - 5, weight: 0 }, { name: m.name, frame: m.frame, weight: 1 }, { name: m.name, frame: m.frame + 5, weight: 0 }]),
  };
  const flat = (c) => () => c;
  const files = [
    { name: "synth/odori-morph-test.pmx", bytes: writePmx(model) },
    { name: "synth/tex/body.bmp", bytes: writeBmp(8, 8, flat([230, 200, 170])) },
    { name: "synth/tex/shine.sph", bytes: writeBmp(8, 8, flat([160, 160, 160])) },
    { name: "synth/tex/ramp.bmp", bytes: writeBmp(8, 8, flat([255, 255, 255])) },
    { name: "synth/tex/sub.bmp", bytes: writeBmp(8, 8, (x) => (x < 4 ? SUB_LEFT : SUB_RIGHT)) },
    { name: "morphs.vmd", bytes: writeVmd(vmd) },
  ];
  return { model, vmd, files };
}

const f32 = (x) => Math.fround(x);
/** Whether three's parsed value `got` is `want` as written (numbers as f32, arrays element by element). */
function sameAs(got, want, where) {
  if (Array.isArray(want)) {
    assert.equal(got.length, want.length, `${where}: length`);
    want.forEach((w, k) => sameAs(got[k], w, `${where}[${k}]`));
  } else if (typeof want === "number") assert.equal(got, f32(want), where);
  else assert.equal(got, want, where);
}

/** The files read back by three r171's MMDParser (raw, MMD's left-handed frame), field by field against what was meant. */
function crossCheck({ model, vmd, files }) {
  const parser = new MMDParser.Parser();
  const pmx = parser.parsePmx(ab(files[0].bytes), false);
  sameAs(pmx.metadata.modelName, MODEL, "model name");
  assert.equal(pmx.vertices.length, model.vertices.length);
  model.vertices.forEach((v, k) => {
    sameAs(pmx.vertices[k].position, v.p, `vertex ${k}`);
    sameAs(pmx.vertices[k].skinIndices, v.bones, `vertex ${k} bone`);
    sameAs(pmx.vertices[k].uv, v.uv, `vertex ${k} uv`);
    sameAs(pmx.vertices[k].auvs, v.auv, `vertex ${k} additional uv`);
  });
  sameAs(pmx.faces.flatMap((f) => f.indices), model.indices, "triangles");
  sameAs(pmx.textures, model.textures, "textures");
  model.materials.forEach((m, k) => {
    const p = pmx.materials[k];
    sameAs([p.name, p.diffuse, p.specular, p.shininess, p.ambient, p.flag, p.textureIndex, p.envTextureIndex, p.envFlag, p.toonFlag, p.toonIndex, 3 * p.faceCount],
      [m.name, m.diffuse, m.specular, m.power, m.ambient, m.flags, m.texture, m.sphere, m.sphereMode, 0, m.toon.texture, m.count], `material ${m.name}`);
  });
  sameAs(pmx.bones.map((b) => [b.name, b.position, b.parentIndex]), model.bones.map((b) => [b.name, b.p, b.parent]), "bones");
  assert.equal(pmx.morphs.length, model.morphs.length);
  model.morphs.forEach((m, k) => {
    const p = pmx.morphs[k];
    sameAs([p.name, p.type], [m.name, m.type === "bone" ? 2 : 8], `morph ${m.name}`);
    const got = p.elements.map((e) => (m.type === "bone" ? [e.index, e.position, e.rotation]
      : [e.index, e.type, e.diffuse, e.specular, e.shininess, e.ambient, e.edgeColor, e.edgeSize, e.textureColor, e.sphereTextureColor, e.toonColor]));
    const want = m.offsets.map((e) => (m.type === "bone" ? [e.bone, e.t, e.q]
      : [e.material, e.operation, e.diffuse, e.specular, e.power, e.ambient, e.edgeColour, e.edgeSize, e.texture, e.sphere, e.toon]));
    sameAs(got, want, `morph ${m.name}'s offsets`);
  });
  const v = parser.parseVmd(ab(files.at(-1).bytes), false);
  sameAs(v.metadata.name, MODEL, "VMD model name");
  sameAs(v.motions.map((k) => [k.boneName, k.frameNum, k.position, k.rotation]), vmd.bones.map((k) => [k.name, k.frame, [0, 0, 0], [0, 0, 0, 1]]), "bone keys");
  sameAs(v.morphs.map((k) => [k.morphName, k.frameNum, k.weight]), vmd.morphs.map((k) => [k.name, k.frame, k.weight]), "morph keys");
  return { pmxMorphs: pmx.morphs.length, vmdMorphKeys: v.morphs.length };
}

/** A point of MMD's file frame (units) in the engine's world: right-handed metres (z negated). */
const world = ([x, y, z]) => [x * M, y * M, -z * M];
/** A head-quad corner moved by the bone morph: head + t + R(q)·(p − head), in the engine's world (right-handed: q's x and y negated, t's z). */
function moved(p, head) {
  const h = world(head), t = world(BONE_T), q = [-BONE_Q[0], -BONE_Q[1], BONE_Q[2], BONE_Q[3]];
  const d = rotate(q, world(p).map((x, k) => x - h[k]));
  return d.map((x, k) => x + h[k] + t[k]);
}

/** Mean colour of the (2r+1)² pixels around (x, y). */
function meanAt(img, x, y, r) {
  const s = [0, 0, 0];
  for (let dy = -r; dy <= r; dy++) for (let dx = -r; dx <= r; dx++) { const p = pixel(img, x + dx, y + dy); for (let c = 0; c < 3; c++) s[c] += p[c]; }
  return s.map((v) => v / (2 * r + 1) ** 2);
}

let server;
before(async () => { server = await startServer(); });
after(() => server && server.stop());

for (const backend of ["webgl2", "webgpu"]) {
  test(`a bone morph, each material-morph factor and a sub-texture sphere map of a written PMX drawn, on ${backend}`, async () => {
    const made = makeFiles();
    const read = crossCheck(made);
    const files = made.files.map((f) => ({ name: f.name, b64: Buffer.from(f.bytes).toString("base64") }));
    const { browser, page, logs } = await launch(backend);
    try {
      await openApp(page, server, backend);
      const setup = await importOnModel(page, files, MODEL, "the written model");
      console.log(`${backend}: written model read back by three r171: ${read.pmxMorphs} morphs, ${read.vmdMorphKeys} morph keys; import notices: ${JSON.stringify(setup.notices)}`);
      assert.ok(!setup.notices.some((n) => /not played|not in the files|drawn in their colour|not drawn/.test(n)), setup.notices.join("\n"));

      // The body at rest where the test puts it: 頭 at its rest position (metres, right-handed).
      const head = made.model.bones.find((b) => b.name === "頭").p;
      const joints = await page.evaluate(({ clip }) => {
        const { library, viewer } = window.odori;
        const j = viewer.figureJoints(library, clip, 0);
        const i = j.names.indexOf("頭");
        return { head: j.positions.slice(3 * i, 3 * i + 3), body: j.body };
      }, { clip: setup.clip.id });
      assert.ok(joints.head.every((x, k) => Math.abs(x - world(head)[k]) < 1e-4), `頭 drawn at ${joints.head}, not at rest ${world(head)}`);

      const camera = { target: [0, 12.5 * M, -Z * M], yaw: 0, pitch: 0, distance: 2.2, fovY: 0.6 };
      // Projected through this camera (set again in the same task: the page may have framed
      // the figures again since the shots were taken).
      const project = (pts) => page.evaluate(({ ps, camera }) => { const { viewer } = window.odori; viewer.setCamera(camera); return ps.map((p) => viewer.project(p[0], p[1], p[2])); }, { ps: pts, camera });
      const at = async (q, pts) => {
        const xy = await project(pts ?? corners(q).map(([x, y]) => world([x, y, Z])));
        const xs = xy.map((p) => p[0]), ys = xy.map((p) => p[1]);
        return { x0: Math.floor(Math.min(...xs)) - 4, x1: Math.ceil(Math.max(...xs)) + 4, y0: Math.floor(Math.min(...ys)) - 4, y1: Math.ceil(Math.max(...ys)) + 4 };
      };
      const centre = async (p) => (await project([p]))[0].map(Math.round);
      const shoot = async (m) => {
        await page.evaluate((t) => { const { player } = window.odori; player.time = t; player.drawNow(); }, m.frame / 30);
        return shotsMorphsOnOff(page, camera, `${backend}-mmd-synthetic-${m.name}`);
      };

      for (const m of MORPHS) {
        const { on, off } = await shoot(m);
        assert.equal(on.drawn.body, "own", "drawn with the model's own mesh");
        assert.equal(on.drawn.morphed, 0, "no vertex morph: the change is the bone's or the material's");
        const changed = (x, y) => CHANGED(pixel(on.img, x, y), pixel(off.img, x, y));
        const all = { x0: 0, y0: 0, x1: on.img.width - 1, y1: on.img.height - 1 };
        if (m.type === "bone") {
          const rest = corners(QUADS.head).map(([x, y]) => world([x, y, Z]));
          const after = corners(QUADS.head).map(([x, y]) => moved([x, y, Z], head));
          const box = await at(null, [...rest, ...after]);
          const inside = countIn(on.img, box, changed);
          const outside = countIn(on.img, all, (x, y) => !inBox(box, x, y) && changed(x, y));
          const mid = (ps) => ps.reduce((a, p) => a.map((v, k) => v + p[k] / ps.length), [0, 0, 0]);
          const [rx, ry] = await centre(mid(rest));
          const [mx, my] = await centre(mid(after));
          const restColour = pixel(off.img, rx, ry);
          console.log(`${backend}: ${m.name} (frame ${m.frame}): ${inside} pixels changed in the head quad's rest + moved box (x ${box.x0}–${box.x1}, y ${box.y0}–${box.y1}), ${outside} elsewhere; rest centre (${rx}, ${ry}) ${restColour} → ${pixel(on.img, rx, ry)}; moved centre (${mx}, ${my}) ${pixel(off.img, mx, my)} → ${pixel(on.img, mx, my)}`);
          assert.ok(inside >= 1000, `the head quad does not move: ${inside} pixels changed`);
          assert.ok(outside <= 0.01 * inside, `pixels changed away from the head quad: ${outside}`);
          assert.ok(pixel(on.img, mx, my).every((c, k) => Math.abs(c - restColour[k]) <= 12), `the moved quad's centre is not drawn in the quad's colour ${restColour}: ${pixel(on.img, mx, my)}`);
          assert.ok(changed(mx, my) && changed(rx, ry), "the quad left its rest place for the moved one");
          continue;
        }
        const torso = await at(QUADS.torso), headBox = await at(QUADS.head), legs = await at(QUADS.legs);
        const inA = (x, y) => inBox(torso, x, y) || inBox(headBox, x, y);
        const inside = countIn(on.img, torso, changed);
        const area = (torso.x1 - torso.x0 + 1) * (torso.y1 - torso.y0 + 1);
        const onB = countIn(on.img, legs, changed);
        const outside = countIn(on.img, all, (x, y) => !inA(x, y) && changed(x, y));
        const [cx, cy] = await centre(world([0, (QUADS.torso.y[0] + QUADS.torso.y[1]) / 2, Z]));
        const a = meanAt(on.img, cx, cy, 10), b = meanAt(off.img, cx, cy, 10);
        console.log(`${backend}: ${m.name} (frame ${m.frame}): ${inside} of ${area} pixels of the torso's box changed, ${onB} in the legs' (material B), ${outside} outside material A; torso centre rgb ${b.map(Math.round)} → ${a.map(Math.round)}`);
        assert.ok(inside >= 0.5 * area, `${m.name}: material A's colour does not change: ${inside} of ${area} pixels`);
        assert.equal(onB, 0, `${m.name}: material B changed`);
        assert.ok(outside <= 0.01 * inside, `${m.name}: pixels changed outside material A: ${outside}`);
        m.expect.forEach((want, c) => {
          const d = a[c] - b[c];
          const ok = want === "up" ? d > 10 : want === "down" ? d < -10 : Math.abs(d) <= 6;
          assert.ok(ok, `${m.name}: channel ${"rgb"[c]} should go ${want}: ${b[c].toFixed(1)} → ${a[c].toFixed(1)}`);
        });
      }

      // PMX sphere mode 3: material C's sphere map sampled at the additional UV 1 (u 0 → 1 left
      // to right) as an ordinary texture, multiplied: red on the quad's left, blue on its
      // right. Looked up by the normal (modes 1 and 2) a flat quad facing the camera takes one
      // colour, and not drawn (the engine before) it is the diffuse grey.
      await page.evaluate(() => { const { player } = window.odori; player.time = 0; player.drawNow(); });
      const { on: sub } = await shotsMorphsOnOff(page, camera, `${backend}-mmd-synthetic-sub-texture`);
      const q = QUADS.sub, ym = (q.y[0] + q.y[1]) / 2;
      const [lx, ly] = await centre(world([q.x[0] + 0.25 * (q.x[1] - q.x[0]), ym, Z]));
      const [rx, ry] = await centre(world([q.x[0] + 0.75 * (q.x[1] - q.x[0]), ym, Z]));
      const left = meanAt(sub.img, lx, ly, 5), right = meanAt(sub.img, rx, ry, 5);
      console.log(`${backend}: sub-texture quad: left quarter (${lx}, ${ly}) rgb ${left.map(Math.round)}, right quarter (${rx}, ${ry}) rgb ${right.map(Math.round)}`);
      assert.ok(left[0] > left[2] + 60 && left[0] > left[1] + 60, `the sub-texture's left half (red) is not drawn on the quad's left: ${left}`);
      assert.ok(right[2] > right[0] + 60 && right[2] > right[1] + 30, `the sub-texture's right half (blue) is not drawn on the quad's right: ${right}`);
      assert.ok(!logs.some((l) => l.startsWith("[pageerror]") || /Validation/.test(l)), logs.join("\n"));
    } finally {
      await browser.close();
    }
  });
}
