// Records three.js r171's pose of WAVEFILE on 初音ミク Ver2 (MMDLoader + MMDAnimationHelper, physics
// off) for the MMD rig's acceptance test (tests/native/mmd_rig.rs, wavefile_on_miku_agrees_with_three_js):
// world positions of センター, 頭, both 手首, 足首 and つま先 at 20 frames spread over 0–2808, in
// three's right-handed frame, model units. three@0.171.0 is the last release with these modules;
// it is not a project dependency:
//   (cd /tmp && npm pack three@0.171.0 && mkdir -p three && tar xzf three-0.171.0.tgz -C three)
//   node tests/tools/mmd_three_reference.mjs ../shared/data /tmp/three/package > tests/golden/mmd/three_wavefile_miku.json
// Another pair: append MODEL MOTION (paths under DATA_DIR), e.g. mmd/gene/Gene_light.pmx mmd/motion/tokino_kakera.vmd;
// bone names after them are recorded too (mokou_A.pmd's hair chain: 右髪C６ 右髪Ｃ０).
// (the clip's very last frame is left out: three's mixer loops there and shows frame 0.)
// Runs in Node: the loader's texture loads fail quietly against a stub document; bones need none.
import fs from 'node:fs';
import path from 'node:path';
import { pathToFileURL } from 'node:url';

const [data, threeDir, modelRel = 'mmd/miku_v2/miku_v2.pmd', motionRel = 'mmd/motion/wavefile_v2.vmd', ...extraBones] = process.argv.slice(2);
if (!data || !threeDir) throw new Error('usage: mmd_three_reference.mjs DATA_DIR THREE_PACKAGE_DIR [MODEL MOTION]');
globalThis.document = { createElementNS: () => ({ addEventListener() {}, removeEventListener() {}, style: {}, setAttribute() {} }), createElement: () => ({ getContext: () => null, style: {} }) };
globalThis.self = globalThis;
// TGA textures load through Request + fetch, which throw at once on a plain path: refuse them quietly too.
globalThis.Request = class { constructor(url) { this.url = String(url); this.headers = new Headers(); } };
globalThis.fetch = () => Promise.reject(new Error('no textures in Node'));
const mod = (rel) => import(pathToFileURL(path.join(threeDir, rel)).href);
const THREE = await mod('build/three.module.js');
const { MMDLoader } = await mod('examples/jsm/loaders/MMDLoader.js');
const { MMDAnimationHelper } = await mod('examples/jsm/animation/MMDAnimationHelper.js');
const { MMDParser } = await mod('examples/jsm/libs/mmdparser.module.js');
const buf = (p) => { const b = fs.readFileSync(p); return b.buffer.slice(b.byteOffset, b.byteOffset + b.byteLength); };
const parser = new MMDParser.Parser();
const modelBytes = buf(`${data}/${modelRel}`);
const pmd = modelRel.endsWith('.pmx') ? parser.parsePmx(modelBytes, true) : parser.parsePmd(modelBytes, true);
const vmd = parser.parseVmd(buf(`${data}/${motionRel}`), true);
const loader = new MMDLoader();
const mesh = loader.meshBuilder.build(pmd, `${data}/${path.dirname(modelRel)}/`, () => {}, () => {});
const clip = loader.animationBuilder.build(vmd, mesh);
const helper = new MMDAnimationHelper({ afterglow: 0 });
helper.add(mesh, { animation: clip, physics: false });
const names = ['センター', '頭', '左手首', '右手首', '左足首', '右足首', '左つま先', '右つま先', ...extraBones];
const last = Math.max(...vmd.motions.map((m) => m.frameNum)) - 1;
const frames = Array.from({ length: 20 }, (_, k) => Math.round((k * last) / 19));
const out = { model: path.basename(modelRel), motion: path.basename(motionRel), three: THREE.REVISION, frames: [] };
let t = 0;
for (const f of frames) {
  helper.update(f / 30 - t);
  t = f / 30;
  mesh.updateMatrixWorld(true);
  const positions = {};
  for (const n of names) {
    const bone = mesh.skeleton.getBoneByName(n);
    if (!bone) continue; // a model without this bone (Gene's toes are 足先)
    const v = bone.getWorldPosition(new THREE.Vector3());
    positions[n] = [v.x, v.y, v.z].map((x) => Math.round(x * 1e4) / 1e4);
  }
  out.frames.push({ frame: f, positions });
}
console.log(JSON.stringify(out));
