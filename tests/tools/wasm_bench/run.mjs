// Times the wasm build of odori-core's song analysis under Node: prepare the 3-minute input,
// then the median of 21 analyses. Usage: node run.mjs path/to/odori_music_wasm_bench.wasm
import { readFileSync } from "node:fs";
import { performance } from "node:perf_hooks";

const bytes = readFileSync(process.argv[2]);
const { instance } = await WebAssembly.instantiate(bytes, {});
const x = instance.exports;
const time = (f) => { const t = performance.now(); const r = f(); return [performance.now() - t, r]; };
const median = (f, n) => { const ts = []; let r; for (let i = 0; i < n; i++) { const [t, v] = time(f); ts.push(t); r = v; } ts.sort((a, b) => a - b); return [ts[n >> 1], r]; };

const [prepMs, frames] = time(() => x.prepare());
console.log(`wasm (node ${process.version}): input = demo song envelope looped to 180 s, ${frames} frames (prepared in ${prepMs.toFixed(0)} ms)`);
const [renderMs] = median(() => x.render_demo(), 3);
console.log(`demo song render (70 s at 44.1 kHz):              ${renderMs.toFixed(1)} ms`);
const [envMs] = median(() => x.demo_envelope(), 3);
console.log(`demo song render + envelope (Rust RMS fallback):  ${envMs.toFixed(1)} ms`);
const [analysisMs, bpm] = median(() => x.analyze_once(), 21);
console.log(`core analysis, envelope -> grid (3-minute song):  ${analysisMs.toFixed(2)} ms  (${bpm.toFixed(2)} BPM)`);
