import { readFileSync } from 'fs';
const bytes = readFileSync(process.env.WASM ?? "/tmp/choreo_wasm_bench/target/wasm32-unknown-unknown/release/choreo_wasm_bench.wasm");
const { instance } = await WebAssembly.instantiate(bytes, {});
const e = instance.exports;
const time = (f) => { const t = performance.now(); const r = f(); return [performance.now() - t, r]; };
let best = 1e9;
for (let i = 0; i < 3; i++) { const [ms] = time(e.build_builtin); best = Math.min(best, ms); }
console.log(`wasm: built-in library ${e.build_builtin()} segments in ${best.toFixed(1)} ms (best of 3)`);
const [sms, m] = time(e.setup);
console.log(`wasm: library of ${m} segments built in ${sms.toFixed(0)} ms`);
const [tms] = time(e.table);
console.log(`wasm: transition table ${m} x ${m} in ${tms.toFixed(0)} ms`);
let fb = 1e9, cost = 0;
for (let i = 0; i < 5; i++) { const [ms, c] = time(e.fill90); fb = Math.min(fb, ms); cost = c; }
console.log(`wasm: fill 90 open bars from ${m} segments (exact, repeat window 1) in ${fb.toFixed(1)} ms (best of 5), cost ${cost.toFixed(3)}`);
fb = 1e9;
for (let i = 0; i < 3; i++) { const [ms, c] = time(e.fill90_default); fb = Math.min(fb, ms); cost = c; }
console.log(`wasm: fill 90 open bars, default repeat window 4: ${fb.toFixed(1)} ms (best of 3), cost ${cost.toFixed(3)}`);
