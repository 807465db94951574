// MMD models drawn as themselves (issue 28 item 2), on WebGL2 and WebGPU, in the app:
// 初音ミク Ver2 (miku_v2.pmd, BMP texture, toon ramps), the low-poly miku (low_poly/miku.pmd,
// TGA textures decoded in Rust), Gene (Gene_light.pmx, PNG textures) and mokou_A.pmd (BMP and
// RLE TGA textures; its hair IK chain skips a bone, as MMD tolerates) are imported with
// `Library.importFiles`, become characters (one in the *Character* list) and are drawn with
// toon shading and outlines. At vertices of textured materials facing the camera and the light,
// projected through the engine's camera (`viewer.project`), the drawn colour is the model's
// texture there (sampled at the vertex UV by this test: PNG/BMP decoded by the browser, TGA by a
// decoder written here), times the material's diffuse, times its toon ramp at N·L (sampled from
// the toon file the same way): the reading of the model is three.js r171's MMDParser
// (`three-mmd`), not the engine's. The control, the same model imported without its texture
// files, fails the same check (its pixels are the diffuse and ramp alone). Each model is framed
// by the viewer (`frameFigures`), as selecting it frames it.
// Screenshots go to tests/artifacts/.
import { test, before, after } from "node:test";
import assert from "node:assert/strict";
import { readFileSync, readdirSync, statSync } from "node:fs";
import { join, relative } from "node:path";
import { data, startServer, launch, openApp, canvasPixels, decodeImageInPage, pixel, waitUntil } from "./harness.mjs";
import { MMDParser, M } from "./mmd-common.mjs";


const LIGHT = (() => { const l = [0.4, 0.9, 0.6]; const n = Math.hypot(...l); return l.map((x) => x / n); })();
const s2l = (c) => { const x = c / 255; return x <= 0.04045 ? x / 12.92 : ((x + 0.055) / 1.055) ** 2.4; };
const l2s = (x) => 255 * (x <= 0.0031308 ? x * 12.92 : 1.055 * Math.max(x, 0) ** (1 / 2.4) - 0.055);

/** Every file under a data folder: { name (relative to `base`), path }. */
function filesUnder(dir, base = dir) {
  const out = [];
  for (const e of readdirSync(dir)) {
    const p = join(dir, e);
    if (statSync(p).isDirectory()) out.push(...filesUnder(p, base));
    else out.push({ name: relative(base, p).split("\\").join("/"), path: p });
  }
  return out;
}

/** An uncompressed true-colour TGA (type 2, 24/32 bits), written here: RGBA rows top first. */
function decodeTga(buf) {
  const idLen = buf[0], type = buf[2], w = buf.readUInt16LE(12), h = buf.readUInt16LE(14), bpp = buf[16], desc = buf[17];
  if (type !== 2 || (bpp !== 24 && bpp !== 32) || buf[1] !== 0) throw new Error(`TGA type ${type} ${bpp} bits: the test's decoder reads uncompressed true colour only`);
  const px = bpp / 8, topFirst = (desc & 0x20) !== 0, at = 18 + idLen;
  const rgba = new Uint8Array(w * h * 4);
  for (let y = 0; y < h; y++) {
    const row = topFirst ? y : h - 1 - y;
    for (let x = 0; x < w; x++) {
      const s = at + (y * w + x) * px, d = (row * w + x) * 4;
      rgba[d] = buf[s + 2]; rgba[d + 1] = buf[s + 1]; rgba[d + 2] = buf[s]; rgba[d + 3] = px === 4 ? buf[s + 3] : 255;
    }
  }
  return { width: w, height: h, rgba };
}

/** Decodes PNG/BMP/JPEG in the page (the browser's decoders), the file's own values: { width, height, rgba }. */
const decodeInPage = (page, buf) => decodeImageInPage(page, buf, { premultiplyAlpha: "none", colorSpaceConversion: "none" });

/** The mean colour of a (2k+1)² texel window around `uv` (repeating), RGBA 0–255. */
function sample(img, [u, v], k = 2) {
  const wrap = (a, n) => ((a % n) + n) % n;
  const cx = Math.floor(wrap(u, 1) * img.width), cy = Math.floor(wrap(v, 1) * img.height);
  const acc = [0, 0, 0, 0];
  let n = 0;
  for (let dy = -k; dy <= k; dy++) for (let dx = -k; dx <= k; dx++) {
    const i = (wrap(cy + dy, img.height) * img.width + wrap(cx + dx, img.width)) * 4;
    for (let c = 0; c < 4; c++) acc[c] += img.rgba[i + c];
    n++;
  }
  return acc.map((x) => x / n);
}

const norm = (p) => p.replace(/\\/g, "/").replace(/^\.\//, "").toLowerCase();

/**
 * The model as three's MMDParser reads it, with per textured material up to `per` test points:
 * vertices whose normal faces the viewer (+z, the way the model faces) and the light, each with
 * its position (metres), UV, material and N·L.
 */
function testPoints(file, per = 30) {
  const buf = readFileSync(file);
  const ab = buf.buffer.slice(buf.byteOffset, buf.byteOffset + buf.byteLength);
  const parser = new MMDParser.Parser();
  const model = /\.pmx$/i.test(file) ? parser.parsePmx(ab, true) : parser.parsePmd(ab, true);
  const pmx = /\.pmx$/i.test(file);
  const points = [];
  let face = 0;
  model.materials.forEach((m, mi) => {
    const tris = m.faceCount;
    const texName = pmx ? (m.textureIndex >= 0 ? model.textures[m.textureIndex] : null) : (m.fileName || "").split("*")[0] || null;
    const toon = pmx ? (m.toonFlag === 0 ? (m.toonIndex >= 0 ? model.textures[m.toonIndex] : null) : `toon${String(m.toonIndex + 1).padStart(2, "0")}.bmp`) : (m.toonIndex >= 0 && m.toonIndex < 255 ? model.toonTextures?.[m.toonIndex]?.fileName : null);
    const diffuse = m.diffuse;
    const cands = [];
    const texture = texName && !/\.(sph|spa)$/i.test(texName) ? texName : null;
    if (diffuse[3] >= 0.999) {
      for (let f = face; f < face + tris; f++) {
        for (const vi of model.faces[f].indices) {
          const v = model.vertices[vi];
          const n = v.normal;
          const ndl = n[0] * LIGHT[0] + n[1] * LIGHT[1] + n[2] * LIGHT[2];
          if (n[2] > 0.5 && ndl > 0.3) cands.push({ material: mi, name: m.name, texture, toon, diffuse, ndl, uv: v.uv, p: v.position.map((x) => x * M) });
        }
      }
    }
    for (let k = 0; k < Math.min(per, cands.length); k++) points.push(cands[Math.floor((k * cands.length) / Math.min(per, cands.length))]);
    face += tris;
  });
  return points;
}

let server;
before(async () => { server = await startServer(); });
after(() => server && server.stop());

const MODELS = [
  { label: "miku_v2.pmd", dir: "mmd/miku_v2", model: "miku_v2.pmd" },
  { label: "low_poly/miku.pmd (TGA)", dir: "mmd/low_poly", model: "miku.pmd", skip: /gumi|\.png$/i },
  { label: "Gene_light.pmx", dir: "mmd/gene", model: "Gene_light.pmx", skip: /motion\/|\.pmd$|README/i },
  // mokou_A's hair IK chain lists a bone off its path (右髪ＣＩＫ → 右髪Ｃ０), which MMD tolerates.
  { label: "mokou_A.pmd (BMP, RLE TGA)", dir: "mmd/mokou", model: "mokou_A.pmd", skip: /\.png$/i },
];

/** Imports the set into the app's library and draws the model's own clip (its rest pose); returns the report's model. */
async function importAndShow(page, set) {
  const model = await page.evaluate((files) => {
    const { library, player, exporter } = window.odori;
    const r = library.importFiles(files.map((f) => ({ name: f.name, bytes: Uint8Array.from(atob(f.b64), (c) => c.charCodeAt(0)) })), {});
    if (exporter && exporter.refreshCharacters) exporter.refreshCharacters();
    const m = r.models[0];
    if (m && m.characterId != null) player.select(m.characterId);
    player.pause();
    return { ...m, notices: r.notices, problems: r.problems, listed: [...document.querySelectorAll("#character option")].map((o) => o.value) };
  }, set);
  await waitUntil(() => page.evaluate(() => { window.odori.player.drawNow(); return window.odori.viewer.texturesLoading === 0; }), { what: "the model's textures decoded" });
  // Framed by the viewer (`frameFigures`, by the skinned vertices), as selecting it frames it.
  await page.evaluate(() => {
    const { viewer, player, library } = window.odori;
    viewer.frameFigures(library, player.figures());
    player.drawNow();
  });
  return model;
}

/**
 * Compares drawn and expected colours at the points (`textured`: only those of textured
 * materials); returns { checked, matched, medianMiss }.
 */
async function check(page, img, points, textures, tolerance, textured = false) {
  const projected = await page.evaluate((ps) => ps.map((p) => window.odori.viewer.project(p[0], p[1], p[2])), points.map((p) => p.p));
  let checked = 0, matched = 0;
  const misses = [];
  points.forEach((pt, k) => {
    const xy = projected[k];
    if (!xy || xy[0] < 3 || xy[1] < 3 || xy[0] > img.width - 4 || xy[1] > img.height - 4) return;
    if (textured && !pt.texture) return;
    const tex = pt.texture ? textures.get(norm(pt.texture)) : null;
    if (pt.texture && !tex) return;
    const t = tex ? sample(tex, pt.uv) : [255, 255, 255, 255];
    if (t[3] < 250) return; // a see-through texel shows what is behind it
    const toon = pt.toon ? textures.get(norm(pt.toon)) : null;
    const ramp = toon ? sample(toon, [0.5, Math.min(0.98, Math.max(0.02, 0.5 * (1 - pt.ndl)))], 0) : [255, 255, 255];
    const want = [0, 1, 2].map((c) => l2s(s2l(t[c]) * pt.diffuse[c] * s2l(ramp[c])));
    // On textured materials only the informative points: where the texture's colour differs
    // from white (drawn without it, the point would be the diffuse and ramp alone).
    const bare = [0, 1, 2].map((c) => l2s(pt.diffuse[c] * s2l(ramp[c])));
    if (textured && Math.max(...[0, 1, 2].map((c) => Math.abs(want[c] - bare[c]))) <= 2 * tolerance) return;
    // The drawn colour at the point or a neighbour (the projection is to the pixel's corner).
    let best = Infinity;
    for (let dy = -1; dy <= 1; dy++) for (let dx = -1; dx <= 1; dx++) {
      const got = pixel(img, xy[0] + dx, xy[1] + dy);
      best = Math.min(best, Math.max(...[0, 1, 2].map((c) => Math.abs(got[c] - want[c]))));
    }
    checked++;
    if (best <= tolerance) matched++;
    else misses.push(best);
  });
  misses.sort((a, b) => a - b);
  return { checked, matched, medianMiss: misses[misses.length >> 1] ?? 0 };
}

for (const backend of ["webgl2", "webgpu"]) {
  test(`MMD models drawn with their textures, toon and outline on ${backend}`, async (t) => {
    const { browser, page, logs } = await launch(backend);
    try {
      await openApp(page, server, backend);
      for (const m of MODELS) {
        await t.test(m.label, async () => {
          const base = join(data, m.dir);
          const inSet = filesUnder(base).filter((f) => !(m.skip && m.skip.test(f.name)) && /\.(pmd|pmx|png|bmp|tga|jpe?g|sph|spa)$/i.test(f.name) && (!/\.(pmd|pmx)$/i.test(f.name) || f.name === m.model));
          const set = inSet.map((f) => ({ name: f.name, b64: readFileSync(f.path).toString("base64") }));
          const points = testPoints(join(base, m.model));
          // The test's own decoding of every image the points need.
          const textures = new Map();
          for (const f of inSet) {
            if (!/\.(png|bmp|jpe?g|tga)$/i.test(f.name)) continue;
            const buf = readFileSync(f.path);
            // The test's TGA decoder reads uncompressed files only (mokou's hair is RLE): points
            // on a texture it cannot read are not checked.
            if (/\.tga$/i.test(f.name) && buf[2] !== 2) continue;
            textures.set(norm(f.name), /\.tga$/i.test(f.name) ? decodeTga(buf) : await decodeInPage(page, buf));
          }
          const info = await importAndShow(page, set);
          assert.equal(info.problems.length, 0, JSON.stringify(info.problems));
          assert.ok(info.characterId != null, `the model became a character: ${JSON.stringify(info.notices)}`);
          assert.ok(info.listed.includes(String(info.characterId)), `the model is in the Character list (${info.listed})`);
          const img = await canvasPixels(page, `${backend}-mmd-${m.model}.png`);
          const all = await check(page, img, points, textures, 40);
          const r = await check(page, img, points, textures, 40, true);
          console.log(`${backend}: ${m.label}: ${all.matched} of ${all.checked} points (every material) and ${r.matched} of ${r.checked} on textured materials where the texture is not white drawn within 40/255 of texture × diffuse × toon (median miss ${r.medianMiss.toFixed(0)})`);
          assert.ok(all.checked >= 30 && all.matched >= 0.6 * all.checked, `${all.matched} of ${all.checked} points match`);
          assert.ok(r.checked >= 8, `${r.checked} informative textured points checked`);
          // Occlusion (hair over the face, Gene's scarf over her chest) and fine texture detail
          // under the mipmaps take some points: at least 45 % of the informative ones match, and
          // the control (below) matches under a third as many.
          assert.ok(r.matched >= 0.45 * r.checked, `${r.matched} of ${r.checked} textured points match`);

          // Control: the same model without its texture files.
          const bare = set.filter((f) => /\.(pmd|pmx)$/i.test(f.name) || /toon\d+\.bmp$/i.test(f.name));
          const ctl = await importAndShow(page, bare);
          assert.ok(ctl.notices.some((n) => /not in the files given/.test(n)), "the control names its missing textures");
          const cimg = await canvasPixels(page, `${backend}-mmd-${m.model}-control.png`);
          const c = await check(page, cimg, points, textures, 40, true);
          console.log(`${backend}: ${m.label} without its textures (control): ${c.matched} of ${c.checked} points match`);
          assert.ok(c.matched < r.matched / 3, `the control should fail the check: ${c.matched} of ${c.checked} match vs ${r.matched}`);
        });
      }
      assert.ok(!logs.some((l) => l.startsWith("[pageerror]") || /could not be decoded|Validation/.test(l)), logs.join("\n"));
    } finally {
      await browser.close();
    }
  });
}
