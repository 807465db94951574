// A lip-sync VMD as the project's face track (issue 28: "face morph keys play on the model"), on
// WebGL2 and WebGPU, in the app: the demo song's generated dance (no face keys of its own) drawn
// on 初音ミク Ver2 (miku_v2.pmd, chosen as the character) with a face-only VMD kept in the project
// as its face track. The lip-sync is written here byte by byte: WAVEFILE's morph-key section
// copied after a header and an empty bone section (no data file committed, none written). Its
// keys and the model are read by three r171's MMDParser (`three-mmd`), not the engine: the frame
// where あ (the open mouth) is keyed strongest within the dance gives the song time (motion frame
// 160 is song time 0), the PMD the vertices あ moves that the head (頭) alone carries, projected
// through the engine's camera looking the face in the eye. The same frame drawn with the track
// and with it removed (`removeFaceTrack`, the control; undone after): around the mouth at least
// 300 pixels change, none away from the weighted morphs; the drawn figure says its morphs moved
// vertices only with the track. Then the project is reloaded (IndexedDB): the track is back and
// the mouth opens again. Screenshots go to tests/artifacts/.
import { test, before, after } from "node:test";
import assert from "node:assert/strict";
import { readFileSync, readdirSync } from "node:fs";
import { join } from "node:path";
import { data, startServer, launch, openDemoDance, pixel, waitUntil, BACKENDS } from "./harness.mjs";
import { needData, readMorphKeys, readPmdMorphs, faceCamera, shotPair, morphBox, movingBoxes, inBox, countIn, CHANGED } from "./mmd-common.mjs";

const mikuDir = join(data, "mmd", "miku_v2");
const vmdPath = join(data, "mmd", "motion", "wavefile_v2.vmd");
needData(join(mikuDir, "miku_v2.pmd"), vmdPath);

const OFFSET = 160; // WAVEFILE's motion frame at song time 0

/** WAVEFILE's morph keys as a face-only VMD, byte by byte: its 50-byte header, 0 bone keys, its morph section (count and 23-byte keys), 0 camera keys. */
function lipSyncVmd() {
  const wave = readFileSync(vmdPath);
  const bones = wave.readUInt32LE(50);
  const at = 54 + 111 * bones;
  const morphs = wave.readUInt32LE(at);
  const section = wave.subarray(at, at + 4 + 23 * morphs);
  const zero = Buffer.alloc(4);
  return { bytes: Buffer.concat([wave.subarray(0, 50), zero, section, zero]), morphs };
}

/** The lip-sync's keys by three's parser: name → [{ frame, weight }] in frame order. */
function readKeys(bytes) {
  const { keys, boneKeys } = readMorphKeys(bytes);
  assert.equal(boneKeys, 0, "the lip-sync has no bone keys");
  return keys;
}

let server;
before(async () => { server = await startServer(); });
after(() => server && server.stop());

for (const backend of (process.env.BACKENDS || Object.keys(BACKENDS).join(",")).split(",")) {
  test(`a lip-sync VMD is the project's face track: the generated dance on miku_v2 opens its mouth, and again after a reload (${backend})`, async () => {
    const model = readPmdMorphs(join(mikuDir, "miku_v2.pmd"));
    const lip = lipSyncVmd();
    const keys = readKeys(lip.bytes);
    const files = readdirSync(mikuDir).filter((f) => /\.(pmd|bmp)$/i.test(f)).map((f) => ({ name: `miku_v2/${f}`, b64: readFileSync(join(mikuDir, f)).toString("base64") }));
    const { browser, page, logs } = await launch(backend);
    try {
      await openDemoDance(page, server, backend);
      /** miku_v2's folder into the library, chosen as the character; the dance rendered. */
      const setUp = () => page.evaluate(({ files, modelName }) => {
        const { library, viewer, player, choreo } = window.odori;
        // The canvas is read by an element screenshot, which also takes whatever stands over
        // it: Generate's toast ("Dance: filled 34 bars") still showed under load. Notifications
        // are not what this test looks at, so they are kept out of sight (again after a reload).
        document.querySelector("#toasts").style.visibility = "hidden";
        const r = library.importFiles(files.map((f) => ({ name: f.name, bytes: window.__test.bytes(f.b64) })), {});
        const character = library.mmdModels().find((m) => m.name === modelName).characterId;
        viewer.setSprings(false);
        viewer.deferRetarget = false;
        viewer.setCharacter(library, character);
        if (choreo.danceId == null) choreo.renderDance();
        player.select(choreo.danceId);
        player.pause();
        return { problems: r.problems, dance: choreo.danceId, secs: library.clip(choreo.danceId).durationSecs };
      }, { files, modelName: model.name });
      const s = await setUp();
      assert.equal(s.problems.length, 0, JSON.stringify(s.problems));
      await waitUntil(() => page.evaluate(() => { window.odori.player.drawNow(); return window.odori.viewer.texturesLoading === 0; }), { what: "miku's textures decoded" });

      // Not refused: the library lists the lip-sync as a face track; the project keeps it.
      const added = await page.evaluate(({ b64 }) => {
        const { library, project } = window.odori;
        const listed = library.importFiles([{ name: "lip.vmd", bytes: window.__test.bytes(b64) }], { songOffsetFrames: 160 });
        const info = project.importFaceTrack("lip.vmd", window.__test.bytes(b64), { songOffsetFrames: 160 });
        return { listed: listed.faceTracks, motions: listed.motions.length, problems: listed.problems, info, summary: project.project.summary().faceTracks };
      }, { b64: lip.bytes.toString("base64") });
      assert.deepEqual([added.motions, added.problems.length, added.listed.length], [0, 0, 1], JSON.stringify(added));
      assert.equal(added.info.keys, lip.morphs);
      assert.deepEqual(added.summary.map((f) => f.fileName), ["lip.vmd"]);

      // あ's strongest key whose song time lies inside the dance (a second in from either end).
      const a = keys.get("あ").filter((k) => k.frame >= OFFSET + 30 && (k.frame - OFFSET) / 30 <= s.secs - 1);
      const mouth = a.reduce((x, k) => (k.weight > x.weight ? k : x));
      assert.ok(mouth.weight >= 0.3, `あ ${mouth.weight} at ${mouth.frame}`);
      const t = (mouth.frame - OFFSET) / 30;

      /** Draws the dance at `t` with the camera on the face, with the track and with it removed; returns both screenshots, the head's pose and what was drawn. */
      const shoot = async (label) => {
        const pose = await page.evaluate(({ t }) => {
          const { library, viewer, player, choreo } = window.odori;
          player.time = t;
          player.drawNow();
          const j = viewer.figureJoints(library, choreo.danceId, t);
          const i = j.names.indexOf("頭");
          return { q: j.rotations.slice(4 * i, 4 * i + 4), p: j.positions.slice(3 * i, 3 * i + 3), body: j.body };
        }, { t });
        const camera = faceCamera(pose, 0.06, 0.55);
        const [w, n] = await shotPair(page, camera, [`${backend}-mmd-face-${label}-track.png`, `${backend}-mmd-face-${label}-none.png`], (withTrack) => page.evaluate(({ withTrack, camera }) => {
          const { viewer, player, library, project } = window.odori;
          if (!withTrack) project.project.removeFaceTrack(library, 0);
          viewer.setCamera(camera);
          player.drawNow();
          const d = viewer.lastDrawn()[0];
          if (!withTrack) { project.project.undo(); project.project.faceTracksInto(library); }
          return d;
        }, { withTrack, camera }));
        return { pose, drawn: w.drawn, img: w.img, control: n.drawn, ctl: n.img };
      };
      const check = async (label) => {
        const shot = await shoot(label);
        assert.equal(shot.pose.body, "character", "the dance is drawn on miku_v2 as the character");
        assert.ok(shot.drawn.morphed > 0 && shot.control.morphed === 0, `vertices morphed: with the track ${shot.drawn.morphed}, without ${shot.control.morphed}`);
        assert.deepEqual(shot.drawn.missingMorphs, [], "miku_v2 has every morph WAVEFILE keys");
        const box = await morphBox(page, model, "あ", mouth.weight, shot.pose, 4);
        const moving = await movingBoxes(page, model, keys, mouth.frame, shot.pose);
        const changed = (x, y) => CHANGED(pixel(shot.img, x, y), pixel(shot.ctl, x, y));
        const inside = countIn(shot.img, box, changed);
        const all = { x0: 0, y0: 0, x1: shot.img.width - 1, y1: shot.img.height - 1 };
        const outside = countIn(shot.img, all, (x, y) => !moving.some((b) => inBox(b, x, y)) && changed(x, y));
        console.log(`${backend} ${label}: song time ${t.toFixed(2)} s (motion frame ${mouth.frame}, あ ${mouth.weight.toFixed(2)}): ${shot.drawn.morphed} drawn vertices morphed with the track, ${shot.control.morphed} without; ${inside} pixels around the mouth's ${box.n} vertices changed against the track removed, ${outside} away from the weighted morphs`);
        assert.ok(inside >= 300, `the mouth does not open: ${inside} pixels changed`);
        assert.ok(outside <= 0.01 * inside, `pixels changed away from the morphs: ${outside}`);
        return inside;
      };
      await check("added");

      // Reload: the project (its face track) comes back from IndexedDB; the library is new, so
      // miku_v2's folder is opened again and chosen as the character.
      await page.evaluate(() => window.odori.project.store.flush());
      await page.reload();
      await page.waitForFunction(() => document.body.dataset.ready === "1", null, { timeout: 120000 });
      await page.waitForFunction(() => window.odori.choreo && window.odori.choreo.view && window.odori.choreo.view.length > 8 && window.odori.choreo.view.every((v) => v.state.kind !== "empty"), null, { timeout: 180000 });
      const back = await page.evaluate(() => window.odori.project.project.summary().faceTracks.map((f) => f.fileName));
      assert.deepEqual(back, ["lip.vmd"], "the face track after the reload");
      await setUp();
      await waitUntil(() => page.evaluate(() => { window.odori.player.drawNow(); return window.odori.viewer.texturesLoading === 0; }), { what: "miku's textures decoded again" });
      await check("reloaded");
      const errors = await page.evaluate(() => [...document.querySelectorAll("#messages li.error")].map((li) => li.textContent));
      assert.deepEqual(errors, []);
      assert.ok(!logs.some((l) => l.startsWith("[pageerror]") || /Validation/.test(l)), logs.join("\n"));
    } finally {
      await browser.close();
    }
  });
}
