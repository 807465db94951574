// Issue 28: MMD dances and models linked wherever they arrive, through the page on both back
// ends. miku_v2's folder is imported first, on its own; then
// - a VMD imported in a later `importFiles` call is posed on miku_v2 *and* drawn with its mesh
//   (`hasMesh`; the control, the same VMD on the standard skeleton, has none);
// - WAVEFILE opened alone through the MMD dialog: the dialog offers the library's miku_v2 (the
//   library kept its file), the project keeps that model with the dance, the dance is drawn with
//   the model's mesh, and `exportVmd`'s default model is miku_v2 (the VMD header names it; the
//   control, `model: "standard"`, names another); the project keeps the model's textures and
//   toon ramps with it (schema 7), so after a reload (the library empty again) the project's
//   dance is still drawn with a mesh — the one the project makes from the model file and those
//   files, with as many textures as the library's mesh had — and still exports on miku_v2; the
//   page names the files it keeps when the project is saved;
// - a camera VMD inside a .zip (made here with Python's zipfile) goes into the project, like a
//   loose one, and is listed once.
import { test, before, after } from "node:test";
import assert from "node:assert/strict";
import { readFileSync, readdirSync, mkdtempSync, rmSync } from "node:fs";
import { execFileSync } from "node:child_process";
import { tmpdir } from "node:os";
import { join } from "node:path";
import { startServer, launch, data, BACKENDS } from "./harness.mjs";

let server;
before(async () => { server = await startServer(); });
after(() => server && server.stop());

const WAVEFILE = join(data, "mmd/motion/wavefile_v2.vmd");
const CAMERA = join(data, "mmd/motion/tokino_kakera_cam.vmd");
const MIKU = join(data, "mmd/miku_v2");

/** A .zip of `files` (`[name in the zip, path]`), written by Python's zipfile (deflated). */
function zipOf(files) {
  const dir = mkdtempSync(join(tmpdir(), "mmd-link-"));
  try {
    const out = join(dir, "set.zip");
    const py = "import sys, zipfile\nwith zipfile.ZipFile(sys.argv[1], 'w', zipfile.ZIP_DEFLATED) as z:\n    for i in range(2, len(sys.argv), 2): z.write(sys.argv[i + 1], sys.argv[i])\n";
    execFileSync("python3", ["-c", py, out, ...files.flat()]);
    return readFileSync(out);
  } finally {
    rmSync(dir, { recursive: true, force: true });
  }
}

async function waitReady(page) {
  await page.waitForFunction(() => document.body.dataset.ready && document.body.dataset.project === "ready", null, { timeout: 120000 });
  const ready = await page.evaluate(() => document.body.dataset.ready);
  if (ready !== "1") throw new Error(`the app did not start: ${await page.textContent("#messages")}`);
}

const messages = (page) => page.textContent("#messages");

/** The project's WAVEFILE dance as the page shows it: its model, its library clip, the model its VMD export names. */
const projectDance = (page) => page.evaluate(() => {
  const app = window.odori.project;
  const lib = window.odori.library;
  const src = app.project.doc().sources.find((s) => s.fileName === "wavefile_v2.vmd");
  const id = src && app.libraryId({ source: src.id, clip: 0 });
  if (id == null) return { model: src?.model?.fileName ?? null, id: null };
  const header = (bytes) => lib.inspectMmdFiles([{ name: "x.vmd", bytes }])[0].modelName;
  return {
    model: src.model?.fileName ?? null,
    id,
    hasMesh: lib.clip(id).hasMesh,
    meshTextures: lib.clip(id).meshTextures,
    keptTextures: (src.model?.textures ?? []).map((t) => t.name),
    exported: header(lib.exportVmd(id, { endSecs: 2 })),
    standard: header(lib.exportVmd(id, { endSecs: 2, model: "standard" })),
    at10: Array.from(lib.jointPositions(id, 10)),
  };
});

for (const backend of (process.env.BACKENDS || Object.keys(BACKENDS).join(",")).split(",")) {
  test(`MMD dances linked to a model imported before them, in the library and the project; a zip's camera VMD into the project (${backend})`, { timeout: 900000 }, async () => {
    const { browser, page, logs } = await launch(backend);
    try {
      await page.goto(server.url + BACKENDS[backend].query);
      await waitReady(page);
      // miku_v2's folder on its own: a model in the library, no dance.
      const folder = readdirSync(MIKU).filter((n) => !/\.txt$/i.test(n)).map((n) => ({ name: n, mimeType: "application/octet-stream", buffer: readFileSync(join(MIKU, n)) }));
      await page.setInputFiles("#file-input", folder);
      await page.waitForFunction(() => /miku_v2\.pmd: MMD model ".+" added/.test(document.querySelector("#messages").textContent), null, { timeout: 120000 });
      const model = await page.evaluate(() => window.odori.library.mmdModels()[0].name);

      // 1. A VMD in a later importFiles call: posed on miku_v2 and drawn with its mesh.
      const later = await page.evaluate(async (b64) => {
        const lib = window.odori.library;
        const bytes = window.__test.bytes(b64);
        const on = lib.importFiles([{ name: "later.vmd", bytes }], {}).motions[0];
        const control = lib.importFiles([{ name: "control.vmd", bytes }], { model: "standard" }).motions[0];
        return { rig: on.rig, hasMesh: on.clip.hasMesh, control: { rig: control.rig, hasMesh: control.clip.hasMesh } };
      }, readFileSync(WAVEFILE).toString("base64"));
      console.log(`${backend}: a VMD imported after ${model}: posed on ${later.rig}, hasMesh ${later.hasMesh}; on the standard skeleton (control) hasMesh ${later.control.hasMesh}`);
      assert.equal(later.rig, model, "posed on the model its header names, kept from the earlier import");
      assert.equal(later.hasMesh, true, "drawn with the model's mesh");
      assert.equal(later.control.hasMesh, false, "the control has no mesh");

      // 2, 3. WAVEFILE alone through the dialog: it offers the library's model; the project keeps it.
      await page.setInputFiles("#file-input", [{ name: "wavefile_v2.vmd", mimeType: "application/octet-stream", buffer: readFileSync(WAVEFILE) }]);
      const dialog = page.locator("#mmd-import");
      await dialog.waitFor({ state: "visible", timeout: 30000 });
      assert.equal(await dialog.locator(".mmd-model").inputValue(), model, "the dialog offers the library's model the VMD was made for first");
      await dialog.locator(".mmd-offset").fill("160");
      await dialog.locator("button[value=import]").click();
      await page.waitForFunction(() => /wavefile_v2\.vmd: dance added to the project, posed on model/.test(document.querySelector("#messages").textContent), null, { timeout: 120000 });
      const kept = await projectDance(page);
      console.log(`${backend}: WAVEFILE in the project on ${kept.model}: hasMesh ${kept.hasMesh}; its VMD export names "${kept.exported}" ("${kept.standard}" with model "standard")`);
      assert.equal(kept.model, "miku_v2.pmd", "the project keeps the library's model file with the dance");
      assert.equal(kept.hasMesh, true, "the project dance is drawn with the model's mesh");
      assert.equal(kept.exported, model, "exportVmd's default model is the dance's model");
      assert.notEqual(kept.standard, model, "the control: exported on the standard skeleton the header names another");

      console.log(`${backend}: the project keeps ${kept.keptTextures.length} files with miku_v2 (${kept.keptTextures.join(", ")}); the dance's mesh draws with ${kept.meshTextures} textures`);
      assert.ok(kept.keptTextures.includes("eyeM2.bmp") && kept.keptTextures.some((n) => /^toon\d\d\.bmp$/.test(n)), `the model's texture and the toon ramps it uses are kept: ${kept.keptTextures}`);
      assert.ok(kept.meshTextures > 0, "the dance is drawn textured");
      assert.doesNotMatch(await messages(page), /not its \d+ textures|without \d+ of its textures/, "no note that textures are left out");
      const mmdFiles = await page.evaluate(() => window.odori.project.project.summary().mmdFiles);
      assert.ok(["wavefile_v2.vmd", "miku_v2.pmd", "eyeM2.bmp"].every((f) => mmdFiles.includes(f)), `summary().mmdFiles names what the save note names: ${mmdFiles}`);

      // Reload: the library is empty again; the project's dance is still on miku_v2, drawn and exported on it.
      await page.evaluate(() => window.odori.project.store.flush());
      await page.reload();
      await waitReady(page);
      await page.waitForFunction(() => { const a = window.odori.project; const s = a.project.doc().sources.find((x) => x.fileName === "wavefile_v2.vmd"); return s && a.libraryId({ source: s.id, clip: 0 }) != null; }, null, { timeout: 120000 });
      const again = await projectDance(page);
      assert.equal(await page.evaluate(() => window.odori.library.mmdModels().length), 0, "the library holds no model after the reload");
      console.log(`${backend}: after the reload: on ${again.model}, hasMesh ${again.hasMesh}, exported on "${again.exported}"`);
      assert.deepEqual({ ...again, id: 0 }, { ...kept, id: 0 }, "after the reload: the same model, mesh (as many textures), export and pose");

      // 4. A camera VMD inside a zip goes into the project, like a loose one, and is listed once.
      const zip = zipOf([["cams/tokino_kakera_cam.vmd", CAMERA]]);
      await page.setInputFiles("#file-input", [{ name: "cams.zip", mimeType: "application/zip", buffer: zip }]);
      await page.waitForFunction(() => /camera motion added to the project/.test(document.querySelector("#messages").textContent), null, { timeout: 60000 });
      const cams = await page.evaluate(() => ({ project: window.odori.project.project.summary().cameras.map((c) => c.fileName), library: window.odori.library.cameraTracks().map((t) => t.source) }));
      console.log(`${backend}: a zip's camera VMD: project ${JSON.stringify(cams.project)}, library ${JSON.stringify(cams.library)}`);
      assert.deepEqual(cams, { project: ["cams.zip/cams/tokino_kakera_cam.vmd"], library: ["cams.zip/cams/tokino_kakera_cam.vmd"] });

      const errors = await page.evaluate(() => [...document.querySelectorAll("#messages li.error")].map((li) => li.textContent));
      assert.deepEqual(errors, []);
      assert.ok(!logs.some((l) => l.startsWith("[pageerror]")), logs.join("\n"));
    } finally {
      await browser.close();
    }
  });
}
