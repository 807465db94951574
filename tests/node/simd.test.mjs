// The shipped wasm build's SIMD frame-distance kernel (issue 17): the npm package runs its own
// self-check in Node's engine. The web build must have the simd128 path compiled in (else the
// check would compare the scalar kernel with itself), and every one of 200,000 random inputs
// must give the scalar kernel's bits: the fast search's exactness (fast = plain DP, bit for
// bit) rests on it, and the native test of the same property runs SSE, not wasm.
import { test } from "node:test";
import assert from "node:assert/strict";
import { readFileSync } from "node:fs";
import { fileURLToPath } from "node:url";
import { dirname, join } from "node:path";

const root = join(dirname(fileURLToPath(import.meta.url)), "..", "..");
const pkg = await import(join(root, "pkg", "odori.js"));
pkg.initSync({ module: readFileSync(join(root, "pkg", "odori_bg.wasm")) });

test("wasm simd128 distance kernel gives the scalar kernel's bits", () => {
  const r = JSON.parse(pkg.distanceKernelCheck(200000));
  assert.equal(r.path, "simd128", "the web build does not run the simd128 kernel");
  assert.equal(r.cases, 200000);
  assert.equal(r.mismatches, 0, `${r.mismatches} of ${r.cases} distances differ in bits from the scalar kernel`);
});
