// Base-colour textures through export and back, and as the viewer samples them (spec §M, #11):
// - three.js (GLTFLoader, a client no one here wrote) loads the product's GLB of the Fox
//   (../shared/data/gltf/Fox.glb) with a base-colour map of the source image's size, and reads
//   the KHR_texture_transform the product writes back for a character that had one;
// - on WebGL2 and WebGPU, in the app: the exported Fox re-opened draws textured (orange fur at
//   its projected joints); a KHR_texture_transform that picks one quadrant of a four-colour
//   image (a GLB made here, tests/node/textured-glb.mjs) draws that quadrant's colour only;
//   and a one-texel checkerboard seen from afar is an even grey through the mipmaps the
//   renderer makes (LINEAR_MIPMAP_LINEAR), while the same file with a LINEAR minification
//   filter (no mipmaps: the sampler honoured) shows the aliasing.
// Screenshots go to tests/artifacts/.
import { test, before, after } from "node:test";
import assert from "node:assert/strict";
import { readFileSync } from "node:fs";
import { join } from "node:path";
import * as esbuild from "esbuild";
import { root, data, startServer, launch, openApp, canvasPixels, countNear, isOrange, isBackground, pixel, waitUntil } from "./harness.mjs";
import { texturedBox, QUADRANTS, CHECKER, pngSize } from "../node/textured-glb.mjs";

const pkg = await import(join(root, "pkg", "odori.js"));
pkg.initSync({ module: readFileSync(join(root, "pkg", "odori_bg.wasm")) });
const { Library } = pkg;
const foxBytes = new Uint8Array(readFileSync(join(data, "gltf/Fox.glb")));
const b64 = (u8) => Buffer.from(u8.buffer, u8.byteOffset, u8.byteLength).toString("base64");

/** The first PNG embedded in a GLB (its size is in the IHDR). */
function firstPng(bytes) {
  const sig = Buffer.from("\x89PNG\r\n\x1a\n", "latin1");
  const at = Buffer.from(bytes.buffer, bytes.byteOffset, bytes.byteLength).indexOf(sig);
  assert.ok(at >= 0, "the file holds a PNG");
  return bytes.subarray(at);
}

/** A four-colour box whose transform picks the top-right (green) quadrant. */
const QUAD_TRANSFORM = { offset: [0.5, 0], scale: [0.5, 0.5] };
const quadBox = () => texturedBox({ image: QUADRANTS(), sampler: { magFilter: 9728, minFilter: 9728, wrapS: 33071, wrapT: 33071 }, transform: QUAD_TRANSFORM });

const PAGE_SCRIPT = `
import * as THREE from "three";
import { GLTFLoader } from "three/examples/jsm/loaders/GLTFLoader.js";
const bytes = (b64) => Uint8Array.from(atob(b64), (c) => c.charCodeAt(0)).buffer;
window.maps = async (glbB64) => {
  const gltf = await new GLTFLoader().parseAsync(bytes(glbB64), "");
  const out = [];
  gltf.scene.traverse((o) => {
    if (!o.isSkinnedMesh) return;
    const map = o.material.map;
    out.push(map ? { width: map.image?.width, height: map.image?.height, offset: map.offset.toArray(), repeat: map.repeat.toArray(), rotation: map.rotation, channel: map.channel } : null);
  });
  return out;
};
window.threeReady = true;
`;

test("three.js loads the exported Fox with its base-colour map, and reads the exported texture transform", async () => {
  const bundle = await esbuild.build({ stdin: { contents: PAGE_SCRIPT, resolveDir: root, loader: "js" }, bundle: true, format: "iife", write: false, logLevel: "silent" });
  const { browser, page, logs } = await launch("webgl2");
  try {
    await page.goto("about:blank");
    await page.addScriptTag({ content: bundle.outputFiles[0].text });
    await page.waitForFunction(() => window.threeReady === true);
    const lib = new Library();
    const fox = lib.importFile("Fox.glb", foxBytes).clips[0];
    const [w, h] = pngSize(firstPng(foxBytes));
    const maps = await page.evaluate((g) => window.maps(g), b64(lib.exportGlb(fox.id)));
    console.log(`three.js, exported Fox: ${maps.length} skinned meshes, maps ${JSON.stringify(maps.map((m) => m && [m.width, m.height]))} (source image ${w}×${h})`);
    assert.ok(maps.length > 0, "three.js sees the Fox's skinned mesh");
    for (const m of maps) assert.deepEqual(m && [m.width, m.height], [w, h], "a base-colour map of the source image's size");

    const box = lib.importFile("quadrants.glb", quadBox()).clips[0];
    const [bm] = await page.evaluate((g) => window.maps(g), b64(lib.exportGlb(box.id)));
    assert.ok(bm, "the box's map is loaded");
    assert.deepEqual([bm.width, bm.height, bm.offset, bm.repeat, bm.channel], [64, 64, QUAD_TRANSFORM.offset, QUAD_TRANSFORM.scale, 0], "three.js reads the transform back");
    assert.ok(!logs.some((l) => l.startsWith("[pageerror]") || /GLTFLoader/.test(l)), logs.join("\n"));
  } finally {
    await browser.close();
  }
});

let server;
before(async () => { server = await startServer(); });
after(() => server && server.stop());

/** Opens `bytes` as file `name` through the page's picker; resolves to the new clip's id once its textures are decoded and a pose at 0.5 s is drawn. */
async function openGlb(page, name, bytes) {
  const n = await page.evaluate(() => window.odori.library.size);
  await page.setInputFiles("#file-input", { name, mimeType: "model/gltf-binary", buffer: Buffer.from(bytes.buffer, bytes.byteOffset, bytes.byteLength) });
  await page.waitForFunction((n) => window.odori.library.size > n, n, { timeout: 60000 });
  await waitUntil(() => page.evaluate(() => { const { player, viewer } = window.odori; player.pause(); player.time = 0.5; player.drawNow(); return viewer.texturesLoading === 0; }), { what: `${name}: its texture decoded` });
  return page.evaluate(() => { window.odori.player.drawNow(); return window.odori.player.clip; });
}

/** Projected points on the box's vertical axis (inside its silhouette from any side), between `lo` and `hi` of its height. */
async function boxAxis(page, clip, lo = 0.2, hi = 0.8, count = 13) {
  return page.evaluate(({ clip, lo, hi, count }) => {
    const { library, viewer } = window.odori;
    const p = library.jointPositions(clip, 0.5);
    const out = [];
    for (let k = 0; k < count; k++) {
      const f = lo + ((hi - lo) * k) / (count - 1);
      out.push(viewer.project(p[0] + (p[3] - p[0]) * f, p[1] + (p[4] - p[1]) * f, p[2] + (p[5] - p[2]) * f));
    }
    return out.filter(Boolean);
  }, { clip, lo, hi, count });
}

/** The points whose (2r+1)² window lies inside the image. */
const inside = (img, pts, r) => pts.filter(([x, y]) => x > r + 1 && y > r + 1 && x < img.width - r - 2 && y < img.height - r - 2);

const hue = ([r, g, b]) => {
  if (Math.max(r, g, b) < 60) return null;
  if (r > 2 * g && r > 2 * b) return "red";
  if (g > 2 * r && g > 2 * b) return "green";
  if (b > 2 * r && b > 2 * g) return "blue";
  if (r > 2 * b && g > 2 * b && Math.abs(r - g) < 0.35 * Math.max(r, g)) return "yellow";
  return null;
};
const luma = ([r, g, b]) => 0.2126 * r + 0.7152 * g + 0.0722 * b;

/** Mean |Δ luma| between horizontal neighbours in a (2r+1)² window around each point, and the mean luma. */
function roughness(img, pts, r = 6) {
  let d = 0, n = 0, sum = 0;
  for (const [x, y] of inside(img, pts, r)) {
    for (let dy = -r; dy <= r; dy++) for (let dx = -r; dx < r; dx++) {
      const a = luma(pixel(img, x + dx, y + dy)), b = luma(pixel(img, x + dx + 1, y + dy));
      d += Math.abs(a - b); sum += a; n++;
    }
  }
  return { rough: d / n, mean: sum / n };
}

for (const backend of ["webgl2", "webgpu"]) {
  test(`textures on ${backend}: exported Fox re-opened, texture transform, mipmaps`, async (t) => {
    const { browser, page, logs } = await launch(backend);
    try {
      await openApp(page, server, backend);

      await t.test("the exported Fox re-opens in the app and draws textured", async () => {
        const fox = await openGlb(page, "Fox.glb", foxBytes);
        const exported = new Uint8Array(Buffer.from(await page.evaluate((id) => {
          const u8 = window.odori.library.exportGlb(id);
          let s = "";
          for (let i = 0; i < u8.length; i += 0x8000) s += String.fromCharCode.apply(null, u8.subarray(i, i + 0x8000));
          return btoa(s);
        }, fox), "base64"));
        const again = await openGlb(page, "Fox-exported.glb", exported);
        assert.notEqual(again, fox, "the exported file is its own clip");
        const joints = await page.evaluate((id) => [...window.odori.library.jointPositions(id, 0.5)], again);
        const img = await canvasPixels(page, `${backend}-texture-fox-exported.png`);
        const pts = await page.evaluate((p) => {
          const out = [];
          for (let i = 0; i < p.length; i += 3) out.push(window.odori.viewer.project(p[i], p[i + 1], p[i + 2]));
          return out.filter(Boolean);
        }, joints);
        const seen = inside(img, pts, 4);
        const body = seen.filter(([x, y]) => countNear(img, x, y, 4, (c) => !isBackground(c)) > 0).length;
        const orange = seen.filter(([x, y]) => countNear(img, x, y, 4, isOrange) > 0).length;
        console.log(`${backend}: exported Fox re-opened, drawn at ${body} of ${seen.length} joints, orange fur at ${orange}`);
        assert.ok(seen.length > 10 && body >= seen.length * 0.7, `the exported Fox is drawn at ${body} of ${seen.length} joints`);
        assert.ok(orange >= seen.length * 0.5, `orange fur near ${orange} of ${seen.length} joints (an export without its texture is white)`);
      });

      await t.test("KHR_texture_transform picks the quadrant it names", async () => {
        const clip = await openGlb(page, "quadrants.glb", quadBox());
        const img = await canvasPixels(page, `${backend}-texture-transform-quadrant.png`);
        const pts = await boxAxis(page, clip, 0.05, 0.95, 25);
        const counts = { red: 0, green: 0, blue: 0, yellow: 0 };
        for (const [x, y] of inside(img, pts, 8)) for (let dy = -8; dy <= 8; dy++) for (let dx = -8; dx <= 8; dx++) {
          const h = hue(pixel(img, x + dx, y + dy));
          if (h) counts[h]++;
        }
        const all = counts.red + counts.green + counts.blue + counts.yellow;
        console.log(`${backend}: texture transform, coloured pixels on the box ${JSON.stringify(counts)}`);
        // Without the transform every face shows all four quadrants.
        assert.ok(counts.green > 500, `green (the quadrant the transform names) on ${counts.green} pixels`);
        assert.ok(counts.green >= 0.97 * all, `only green: ${JSON.stringify(counts)}`);
      });

      await t.test("a far checkerboard is even grey through mipmaps; a LINEAR (no mipmap) sampler aliases", async () => {
        const measure = async (label, minFilter) => {
          // The same file but for the sampler, on the same camera: only the minification differs.
          const clip = await openGlb(page, `checker-${label}.glb`, texturedBox({ image: CHECKER(512), sampler: { magFilter: 9729, minFilter } }));
          const img = await canvasPixels(page, `${backend}-texture-checker-${label}.png`);
          return roughness(img, await boxAxis(page, clip, 0.25, 0.75, 9));
        };
        const mip = await measure("mipmapped", 9987);
        const flat = await measure("linear", 9729);
        console.log(`${backend}: checker 512² on the box, mean |Δ luma| between neighbours: mipmapped ${mip.rough.toFixed(1)} (mean ${mip.mean.toFixed(0)}), LINEAR without mipmaps ${flat.rough.toFixed(1)} (mean ${flat.mean.toFixed(0)}); ratio ${(flat.rough / Math.max(mip.rough, 0.01)).toFixed(1)}×`);
        assert.ok(mip.mean > 60, `the mipmapped box is grey, not dark (mean ${mip.mean})`);
        assert.ok(mip.rough < 8, `mipmapped: neighbours differ by ${mip.rough} on average`);
        assert.ok(flat.rough > 3 * mip.rough && flat.rough > 15, `without mipmaps the checker aliases (${flat.rough} vs ${mip.rough})`);
      });
      assert.ok(!logs.some((l) => l.startsWith("[pageerror]") || /could not be decoded|wgpu|Validation/.test(l)), logs.join("\n"));
    } finally {
      await browser.close();
    }
  });
}
