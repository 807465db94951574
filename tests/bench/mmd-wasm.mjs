// Benchmark (issue 28): MMD import in wasm, the engine's own package (pkg/, from `./dev build`)
// under Node, through `Library.importFiles` (what the MMD dialog runs): WAVEFILE with the
// miku_v2 folder (IK solved on her rig), WAVEFILE alone on the standard skeleton (as a project
// source is posed), and the Gene folder (PMX, 28,646 vertices). Best of 5 after one warm-up;
// the goals: WAVEFILE < 150 ms, Gene < 300 ms. The native figures come from
// `cargo bench -p odori-tests --bench mmd_import` (docs/benchmarks.md puts them side by side).
// Not a test. Run after `./dev build`: node tests/bench/mmd-wasm.mjs
import { readFileSync, readdirSync, statSync, existsSync } from "node:fs";
import { join, relative } from "node:path";

const root = join(import.meta.dirname, "..", "..");
const data = join(root, "..", "shared", "data");
if (!existsSync(join(data, "mmd"))) throw new Error(`../shared/data/mmd is missing (${data}/mmd)`);
const pkg = await import(join(root, "pkg", "odori.js"));
pkg.initSync({ module: readFileSync(join(root, "pkg", "odori_bg.wasm")) });
const { Library } = pkg;

function folder(rel, keep = () => true) {
  const base = join(data, rel);
  const out = [];
  const walk = (d) => {
    for (const n of readdirSync(d)) {
      const p = join(d, n);
      if (statSync(p).isDirectory()) walk(p);
      else {
        const r = relative(base, p);
        if (keep(r)) out.push({ name: `${rel.split("/").pop()}/${r}`, bytes: new Uint8Array(readFileSync(p)) });
      }
    }
  };
  walk(base);
  return out.sort((a, b) => (a.name < b.name ? -1 : 1));
}

/** Best time of `f(lib)` on a fresh Library each run (made outside the timing). */
function best(f, runs = 5) {
  f(new Library());
  let b = Infinity;
  let last;
  for (let i = 0; i < runs; i++) {
    const lib = new Library();
    const t = performance.now();
    last = f(lib);
    b = Math.min(b, performance.now() - t);
  }
  return [b, last];
}

const wave = { name: "wavefile_v2.vmd", bytes: new Uint8Array(readFileSync(join(data, "mmd/motion/wavefile_v2.vmd"))) };
const miku = [...folder("mmd/miku_v2"), wave];
const [onMiku, r1] = best((lib) => lib.importFiles(miku));
if (r1.problems.length) throw new Error(JSON.stringify(r1.problems));
const [alone] = best((lib) => lib.importFiles([wave], { model: "standard" }));
const gene = folder("mmd/gene", (r) => !r.startsWith("motion") && !r.endsWith(".pmd"));
const [geneMs, r3] = best((lib) => lib.importFiles(gene));
console.log(`mmd-wasm: WAVEFILE (${r1.motions[0].clip.frames} frames) + miku_v2 folder, importFiles → IK-solved clip: ${onMiku.toFixed(1)} ms (wasm in Node ${process.version}, best of 5; goal < 150 ms)`);
console.log(`mmd-wasm: WAVEFILE alone on the standard skeleton: ${alone.toFixed(1)} ms`);
console.log(`mmd-wasm: Gene folder (${r3.models.map((m) => m.vertices).join(", ")} vertices, ${gene.length} files), importFiles: ${geneMs.toFixed(1)} ms (goal < 300 ms)`);
