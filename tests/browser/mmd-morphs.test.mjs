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
import { readFileSync } from "node:fs";
import { join } from "node:path";
import { data, startServer, launch, openApp, pixel } from "./harness.mjs";
import { needData, readMorphKeys, readPmdMorphs, faceCamera, headPose, shotsMorphsOnOff, morphBox, movingBoxes, inBox, countIn, CHANGED, modelFiles, importOnModel } from "./mmd-common.mjs";

const mikuDir = join(data, "mmd", "miku_v2");
const vmdPath = join(data, "mmd", "motion", "wavefile_v2.vmd");
needData(join(mikuDir, "miku_v2.pmd"), vmdPath);

let server;
before(async () => { server = await startServer(); });
after(() => server && server.stop());

/** The iris and the eye's dark lines: dark, or strongly coloured (Miku's eyes are teal). */
const IRIS = ([r, g, b]) => Math.max(r, g, b) < 110 || Math.max(r, g, b) - Math.min(r, g, b) > 90;

for (const backend of ["webgl2", "webgpu"]) {
  test(`miku_v2's face plays WAVEFILE's morph keys (mouth open, eyes closed), morphs on vs off, on ${backend}`, async () => {
    const model = readPmdMorphs(join(mikuDir, "miku_v2.pmd"));
    const { keys } = readMorphKeys(readFileSync(vmdPath));
    const strongest = (name) => {
      const list = keys.get(name);
      assert.ok(list && list.length, `WAVEFILE keys ${name}`);
      return list.reduce((a, k) => (k.weight > a.weight ? k : a));
    };
    const mouth = strongest("あ");
    const blink = strongest("まばたき");
    assert.ok(mouth.weight >= 0.3 && blink.weight >= 0.99, `あ ${mouth.weight} at ${mouth.frame}, まばたき ${blink.weight} at ${blink.frame}`);
    const vmd = readFileSync(vmdPath);
    const files = modelFiles(mikuDir, "miku_v2", "miku_v2.pmd", { keep: (f) => /\.bmp$/i.test(f), extra: [{ name: "wavefile_v2.vmd", bytes: vmd }] });
    const { browser, page, logs } = await launch(backend);
    try {
      await openApp(page, server, backend);
      const setup = await importOnModel(page, files, model.name, "miku_v2");
      assert.equal(setup.morphsDefault, true, "morphs are on by default");
      assert.ok(setup.notices.some((n) => /morph \(face\) keys kept aside: played/.test(n)), setup.notices.join("\n"));

      /** Draws frame `frame` with the camera on the face, morphs on and off; returns the screenshots, the head's pose and what was drawn. */
      const shoot = async (frame, label) => {
        const pose = await headPose(page, setup.clip.id, frame / 30);
        // Looking the face in the eye: the head's forward (+z at rest) from the front, 0.55 m away.
        const { on, off } = await shotsMorphsOnOff(page, faceCamera(pose, 0.06, 0.55), `${backend}-mmd-morphs-${label}`);
        return { pose, drawn: on.drawn, img: on.img, control: off.drawn, ctl: off.img };
      };

      const boxOf = (name, weight, pose, padPx = 4) => morphBox(page, model, name, weight, pose, padPx);
      const count = countIn;
      /** Changed pixels inside `box`, and outside every box of `moving` (where nothing should change). */
      const diff = (s, box, moving) => {
        const changed = (x, y) => CHANGED(pixel(s.img, x, y), pixel(s.ctl, x, y));
        const inside = count(s.img, box, changed);
        const all = { x0: 0, y0: 0, x1: s.img.width - 1, y1: s.img.height - 1 };
        const outside = count(s.img, all, (x, y) => !moving.some((b) => inBox(b, x, y)) && changed(x, y));
        return { inside, area: (box.x1 - box.x0 + 1) * (box.y1 - box.y0 + 1), outside };
      };
      const movingAt = (frame, pose) => movingBoxes(page, model, keys, frame, pose);

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
      }, { vmd: vmd.toString("base64"), pmd: files[0].b64, t: mouth.frame / 30, libClip: setup.clip.id, modelName: model.name });
      console.log(`${backend}: WAVEFILE as a project source on miku_v2 (its own model's mesh): ${proj.on.morphed} drawn vertices morphed at frame ${mouth.frame} (the library's import: ${proj.library.morphed}), ${proj.off.morphed} with morphs off`);
      assert.equal(proj.on.body, "own");
      assert.ok(proj.on.morphed > 0 && proj.on.morphed === proj.library.morphed && proj.off.morphed === 0, JSON.stringify(proj));
      assert.ok(!logs.some((l) => l.startsWith("[pageerror]") || /Validation/.test(l)), logs.join("\n"));
    } finally {
      await browser.close();
    }
  });
}
