// The npm package as a stranger gets it: `npm pack` of pkg/, installed from the tarball into a
// clean folder outside the repository; there (a) the Node example (examples/node/dance.mjs)
// analyses a song, generates a dance and writes joint positions, and so does every Node example
// of pkg/README.md, (b) pages bundled with esbuild and with vite from the package (the full
// engine and the <odori-player> element) load and draw in headless Chromium, (c)
// `tsc --noEmit --strict` passes on the TypeScript example.
import { test, before, after } from "node:test";
import assert from "node:assert/strict";
import { execFileSync } from "node:child_process";
import { mkdtempSync, mkdirSync, writeFileSync, readFileSync, copyFileSync, rmSync, readdirSync } from "node:fs";
import { tmpdir } from "node:os";
import { join, extname } from "node:path";
import { root, launch, artifacts } from "./harness.mjs";

let dir;
let tarball;
const bin = (name) => join(root, "node_modules", ".bin", name);
const sh = (cmd, args, cwd) => execFileSync(cmd, args, { cwd, encoding: "utf8", stdio: ["ignore", "pipe", "pipe"] });

before(() => {
  dir = mkdtempSync(join(tmpdir(), "odori-consumer-"));
  assert.ok(!dir.startsWith(root), "the consumer folder is outside the repository");
  const packed = JSON.parse(sh("npm", ["pack", "--json", "--pack-destination", dir], join(root, "pkg")));
  tarball = join(dir, packed[0].filename);
  const files = packed[0].files.map((f) => f.path);
  for (const f of ["odori.js", "odori_bg.wasm", "odori.d.ts", "player/odori-player.js", "player/odori-player.d.ts", "player/odori_player.js", "player/odori_player_bg.wasm", "README.md"]) {
    assert.ok(files.includes(f), `the tarball lacks ${f} (has ${files.join(", ")})`);
  }
  writeFileSync(join(dir, "package.json"), JSON.stringify({ name: "consumer", private: true, type: "module" }));
  sh("npm", ["install", "--offline", "--no-audit", "--no-fund", tarball], dir);
});
after(() => dir && rmSync(dir, { recursive: true, force: true }));

/** A float32 WAV (exact samples, so the analysis sees what the engine rendered). */
function wavFloat32(samples, rate) {
  const buf = Buffer.alloc(44 + samples.length * 4);
  buf.write("RIFF", 0); buf.writeUInt32LE(36 + samples.length * 4, 4); buf.write("WAVE", 8);
  buf.write("fmt ", 12); buf.writeUInt32LE(16, 16); buf.writeUInt16LE(3, 20); buf.writeUInt16LE(1, 22);
  buf.writeUInt32LE(rate, 24); buf.writeUInt32LE(rate * 4, 28); buf.writeUInt16LE(4, 32); buf.writeUInt16LE(32, 34);
  buf.write("data", 36); buf.writeUInt32LE(samples.length * 4, 40);
  for (let i = 0; i < samples.length; i++) buf.writeFloatLE(samples[i], 44 + i * 4);
  return buf;
}

test("(a) the Node example runs from the installed package: song → dance → joint positions", async () => {
  copyFileSync(join(root, "examples", "node", "dance.mjs"), join(dir, "dance.mjs"));
  const out1 = sh("node", ["dance.mjs", "", "demo.json"], dir);
  const a = JSON.parse(readFileSync(join(dir, "demo.json"), "utf8"));
  assert.ok(a.bars >= 16, `${a.bars} bars`);
  assert.ok(Math.abs(a.bpm - 120) < 2, `the demo song is 120 BPM, found ${a.bpm}`);
  assert.equal(a.joints.length, 21);
  assert.ok(a.frames.length > a.durationSecs * 30 - 2, `${a.frames.length} frames for ${a.durationSecs} s`);
  // Half a bar in (bars are 2 s; a four-count move comes back to its start at the bar line).
  const f0 = a.frames[0], f1 = a.frames[15];
  assert.ok(f0.reduce((s, v, i) => s + Math.abs(v - f1[i]), 0) > 0.3, "the dancer moves");
  // The same song as a WAV file: same analysis, same dance (the engine is deterministic).
  const pkg = await import(join(dir, "node_modules", "odori", "odori.js"));
  pkg.initSync({ module: readFileSync(join(dir, "node_modules", "odori", "odori_bg.wasm")) });
  const demo = pkg.DemoSong.render(44100);
  writeFileSync(join(dir, "song.wav"), wavFloat32(demo.samples, 44100));
  const out2 = sh("node", ["dance.mjs", "song.wav", "wav.json"], dir);
  const b = JSON.parse(readFileSync(join(dir, "wav.json"), "utf8"));
  assert.equal(b.bars, a.bars);
  assert.deepEqual(b.frames, a.frames, "the WAV of the demo song gives the same dance");
  // And as BVH: it re-imports into the engine with the dance's frame count and skeleton.
  const out3 = sh("node", ["dance.mjs", "", "demo.bvh"], dir);
  const bvh = readFileSync(join(dir, "demo.bvh"));
  assert.ok(bvh.toString("latin1").startsWith("HIERARCHY"), "not a BVH file");
  const lib = new pkg.Library();
  const back = lib.importFile("demo.bvh", new Uint8Array(bvh)).clips[0];
  assert.ok(Math.abs(back.durationSecs - a.durationSecs) < 0.05, `BVH ${back.durationSecs} s vs ${a.durationSecs} s`);
  assert.equal(back.humanoid.kind, "complete", "the exported skeleton maps onto the humanoid again");
  console.log(out1.trim(), "|", out2.trim(), "|", out3.trim());
});

test("every Node example of pkg/README.md runs against the installed package", () => {
  const readme = readFileSync(join(dir, "node_modules", "odori", "README.md"), "utf8");
  const blocks = [...readme.matchAll(/```js\n\/\/ node\n([\s\S]*?)```/g)].map((m) => m[1]);
  assert.ok(blocks.length >= 5, `only ${blocks.length} Node examples in the README`);
  const init = blocks[0].split("\n").filter((l) => /^import .*node:(fs|url)|^initSync|^import \{ initSync/.test(l));
  blocks.forEach((code, i) => {
    let src = code.replace("// …init as above\n", "");
    // Each example's own imports first, then the shared init lines.
    const imports = src.split("\n").filter((l) => l.startsWith("import "));
    const body = src.split("\n").filter((l) => !l.startsWith("import "));
    const lines = [...new Set([...imports, ...init.filter((l) => l.startsWith("import "))])];
    const file = join(dir, `readme-${i}.mjs`);
    writeFileSync(file, [...lines, 'import { initSync as __init } from "odori";', i === 0 ? "" : init.find((l) => l.startsWith("initSync")).replace("initSync", "__init"), ...body].join("\n"));
    try {
      const out = sh("node", [file], dir);
      assert.ok(out.trim().length > 0, `README example ${i} printed nothing`);
    } catch (e) {
      assert.fail(`README Node example ${i} failed:\n${code}\n${e.stderr || e.message}`);
    }
  });
});

test("(c) tsc --noEmit --strict passes on the TypeScript example against the installed package", () => {
  const ts = join(dir, "ts");
  mkdirSync(ts, { recursive: true });
  for (const f of ["example.ts", "tsconfig.json"]) copyFileSync(join(root, "examples", "ts", f), join(ts, f));
  try {
    sh(bin("tsc"), ["--noEmit", "--strict", "-p", ts], ts);
  } catch (e) {
    assert.fail(`tsc failed:\n${e.stdout}${e.stderr}`);
  }
  // And a type error is caught (the types are not all `any`).
  writeFileSync(join(ts, "bad.ts"), 'import { Library } from "odori";\nconst n: string = new Library().clips()[0].durationSecs;\nexport { n };\n');
  writeFileSync(join(ts, "tsconfig.bad.json"), JSON.stringify({ extends: "./tsconfig.json", files: ["bad.ts"] }));
  assert.throws(() => sh(bin("tsc"), ["--noEmit", "-p", join(ts, "tsconfig.bad.json")], ts), (e) => /Type 'number' is not assignable to type 'string'/.test(e.stdout));
});

/** The page's script: the full engine draws on a canvas, and an <odori-player> plays. */
const ENTRY = `
import init, { Library, Viewer } from "odori";
import { OdoriPlayer } from "odori/player";
OdoriPlayer.backend = "webgl2";
const player = document.createElement("odori-player");
player.id = "player";
player.setAttribute("character", "stick");
player.autoplay = true;
player.loop = true;
player.style.cssText = "display:block;width:400px;height:300px";
document.body.append(player);
const canvas = document.createElement("canvas");
canvas.id = "engine"; canvas.width = 400; canvas.height = 300;
document.body.append(canvas);
await init();
const library = new Library();
const clip = library.addBuiltinDemo();
const viewer = await Viewer.create(canvas, { backend: "webgl2" });
viewer.frameFigures(library, [{ clip: clip.id, timeSecs: 0 }]);
viewer.draw(library, [{ clip: clip.id, timeSecs: 0.5 }]);
document.body.dataset.engine = "drawn";
`;

/** Opens a bundled page (files under `web`) in Chromium; asserts both figures are drawn. */
async function pageDraws(web, label) {
  const { browser, page, logs } = await launch("webgl2");
  try {
    const types = { ".html": "text/html", ".js": "text/javascript", ".wasm": "application/wasm" };
    // localhost: a secure context like any https page; nothing listens, the test answers.
    await page.route("http://localhost:47124/**", (route) => {
      const path = new URL(route.request().url()).pathname.replace(/\/$/, "/index.html");
      try {
        return route.fulfill({ status: 200, contentType: types[extname(path)] || "application/octet-stream", body: readFileSync(join(web, path)) });
      } catch {
        return route.fulfill({ status: 404, body: "not found" });
      }
    });
    await page.goto("http://localhost:47124/");
    await page.waitForFunction(() => document.body.dataset.engine === "drawn" && document.getElementById("player")?.lastFrame, null, { timeout: 60000 })
      .catch((e) => { throw new Error(`${label}: ${e.message}\n${logs.join("\n")}`); });
    await page.waitForTimeout(200);
    const shot = async (sel, name) => {
      const png = await (await page.$(sel)).screenshot({ path: join(artifacts, name) });
      return page.evaluate(async (src) => {
        const bmp = await createImageBitmap(await (await fetch(`data:image/png;base64,${src}`)).blob());
        const c = new OffscreenCanvas(bmp.width, bmp.height);
        const g = c.getContext("2d");
        g.drawImage(bmp, 0, 0);
        const d = g.getImageData(0, 0, bmp.width, bmp.height).data;
        let n = 0;
        for (let i = 0; i < d.length; i += 4) {
          const [r, gg, b] = [d[i], d[i + 1], d[i + 2]];
          if (r > 90 && r > gg * 1.25 && gg > b * 1.2 && r - b > 60) n++;
        }
        return n;
      }, png.toString("base64"));
    };
    const enginePixels = await shot("#engine", `npm-${label}-engine.png`);
    const playerPixels = await shot("#player", `npm-${label}-player.png`);
    assert.ok(enginePixels > 200, `${label}: the full engine drew ${enginePixels} figure pixels`);
    assert.ok(playerPixels > 200, `${label}: the player drew ${playerPixels} figure pixels`);
  } finally {
    await browser.close();
  }
}

test("(b) a page bundled with esbuild from the package loads and draws (full engine and <odori-player>)", async () => {
  const web = join(dir, "web-esbuild");
  mkdirSync(web, { recursive: true });
  writeFileSync(join(web, "entry.js"), ENTRY);
  writeFileSync(join(web, "index.html"), '<!doctype html><meta charset="utf-8"><body style="margin:0;background:#fff"><script type="module" src="dist/entry.js"></script>');
  sh(bin("esbuild"), ["entry.js", "--bundle", "--format=esm", "--target=es2022", "--outdir=dist"], web);
  // esbuild leaves the .wasm files to be served beside the bundle (pkg/README.md says so).
  copyFileSync(join(dir, "node_modules", "odori", "odori_bg.wasm"), join(web, "dist", "odori_bg.wasm"));
  copyFileSync(join(dir, "node_modules", "odori", "player", "odori_player_bg.wasm"), join(web, "dist", "odori_player_bg.wasm"));
  await pageDraws(web, "esbuild");
});

test("(b) a page bundled with vite from the package loads and draws (the .wasm files found by vite itself)", async () => {
  const src = join(dir, "web-vite");
  mkdirSync(src, { recursive: true });
  writeFileSync(join(src, "main.js"), ENTRY);
  writeFileSync(join(src, "index.html"), '<!doctype html><meta charset="utf-8"><body style="margin:0;background:#fff"><script type="module" src="./main.js"></script>');
  try {
    sh(bin("vite"), ["build", src, "--outDir", join(src, "dist"), "--target", "es2022", "--logLevel", "warn"], src);
  } catch (e) {
    assert.fail(`vite build failed:\n${e.stdout}${e.stderr}`);
  }
  const assets = readdirSync(join(src, "dist", "assets"));
  console.log("vite output:", assets.join(", "));
  assert.ok(assets.some((f) => /^odori_bg-.*\.wasm$/.test(f)) && assets.some((f) => /^odori_player_bg-.*\.wasm$/.test(f)), "vite emitted both .wasm files");
  await pageDraws(join(src, "dist"), "vite");
});
