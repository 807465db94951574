// Gene (Gene_light.pmx, 28,646 vertices, 10 PNG textures) imported and made a character in the
// full engine's wasm in Node (`Library.importFiles`: parse, textures resolved, skinned mesh and
// parts built; the GPU upload and the browser's image decoding are not in it): best of 5, ms.
// The goal (issue 28 item 2, step 7) is < 300 ms. Run after `./dev build`: node tests/bench/mmd-draw-wasm.mjs
import { readFileSync, readdirSync, statSync } from "node:fs";
import { join, relative } from "node:path";
import { fileURLToPath } from "node:url";

const root = join(fileURLToPath(import.meta.url), "..", "..", "..");
const data = join(root, "..", "shared", "data", "mmd");
const pkg = await import(join(root, "pkg", "odori.js"));
pkg.initSync({ module: readFileSync(join(root, "pkg", "odori_bg.wasm")) });

function set(dir, keep) {
  const out = [];
  const walk = (d) => { for (const e of readdirSync(d)) { const p = join(d, e); if (statSync(p).isDirectory()) walk(p); else { const name = relative(dir, p).split("\\").join("/"); if (keep(name)) out.push({ name, bytes: new Uint8Array(readFileSync(p)) }); } } };
  walk(dir);
  return out;
}
for (const [label, dir, model] of [["Gene_light.pmx", "gene", "Gene_light.pmx"], ["miku_v2.pmd", "miku_v2", "miku_v2.pmd"], ["low_poly/miku.pmd (TGA)", "low_poly", "miku.pmd"]]) {
  const files = set(join(data, dir), (n) => /\.(pmd|pmx|png|bmp|tga)$/i.test(n) && (!/\.(pmd|pmx)$/i.test(n) || n === model));
  let best = Infinity, info;
  for (let k = 0; k < 5; k++) {
    const lib = new pkg.Library();
    const t = performance.now();
    const r = lib.importFiles(files, {});
    best = Math.min(best, performance.now() - t);
    info = r.models[0];
    if (info.characterId == null) throw new Error(`${label}: not a character: ${r.notices}`);
  }
  console.log(`mmd-draw-wasm: ${label} (${info.vertices} vertices): imported and made a character in ${best.toFixed(1)} ms (wasm in Node, best of 5)`);
}
