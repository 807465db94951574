// Sizes stated = sizes built (issue 27): every size of the npm package that README.md,
// docs/*.md or pkg/README.md states is compared with the built pkg/, measured as the embedding
// benchmark measures it (tests/bench/bundle-sizes.mjs: raw bytes and gzip level 9 of each
// file, summed, for the full engine and for the player).
//
// The documented form (docs/benchmarks.md, "Bundle sizes"): a size of the package is written
// as `N unit<!-- size:KEY -->`, KEY one of full-raw, full-gzip, player-raw, player-gzip; units
// B, KiB, MiB (binary) or kB, MB (decimal); a `~` before N is allowed. A size on a line that
// mentions gzip but is not the package's (another bundle, a saving, a goal) is marked
// `<!-- size:not-the-package -->`; an unmarked size figure on such a line fails, so a new
// size statement cannot slip past the check.
import { test } from "node:test";
import assert from "node:assert/strict";
import { readFileSync, readdirSync, existsSync } from "node:fs";
import { fileURLToPath } from "node:url";
import { dirname, join } from "node:path";
import { bundleSizes, BUNDLES } from "../bench/bundle-sizes.mjs";

const root = join(dirname(fileURLToPath(import.meta.url)), "..", "..");
const pkgDir = join(root, "pkg");

/** Sizes move a little with each change of the engine: a statement within ±2 % holds. */
const TOLERANCE = 0.02;
const UNITS = { B: 1, KiB: 1024, MiB: 1048576, kB: 1000, MB: 1e6 };
const KEYS = ["full-raw", "full-gzip", "player-raw", "player-gzip"];
const NUMBER = String.raw`(~?)(\d[\d,]*(?:\.\d+)?)\s*(B|KiB|MiB|kB|MB|KB)\b`;
const MARKED = new RegExp(`${NUMBER}\\s*<!--\\s*size:([a-z-]+)\\s*-->`, "g");
const ANY_SIZE = new RegExp(`${NUMBER}(?!\\s*<!--\\s*size:)`, "g");

/** The files whose statements are checked, relative to the repository root. */
function docFiles() {
  const docs = existsSync(join(root, "docs")) ? readdirSync(join(root, "docs")).filter((f) => f.endsWith(".md")).map((f) => `docs/${f}`) : [];
  return ["README.md", ...docs, "pkg/README.md"];
}

/** Every size statement of `text`, and every problem with the form (`file` names it). */
export function statements(file, text) {
  const found = [], problems = [];
  text.split("\n").forEach((line, i) => {
    const where = `${file}:${i + 1}`;
    for (const m of line.matchAll(MARKED)) {
      const [whole, , digits, unit, key] = m;
      if (key === "not-the-package") continue;
      if (!KEYS.includes(key)) problems.push(`${where}: unknown size key "${key}" in "${whole}" (keys: ${KEYS.join(", ")}, not-the-package)`);
      else if (!(unit in UNITS)) problems.push(`${where}: "${whole}": say KiB (1024) or kB (1000), not ${unit}`);
      else found.push({ where, text: whole.replace(/\s*<!--.*-->/, ""), key, bytes: Number(digits.replace(/,/g, "")) * UNITS[unit] });
    }
    if (/gzip/i.test(line)) {
      for (const m of line.matchAll(ANY_SIZE)) {
        problems.push(`${where}: a size on a gzip line without a <!-- size:KEY --> marker: "${m[0]}" in: ${line.trim()}`);
      }
    }
  });
  return { found, problems };
}

/** The statements that do not match the measured sizes, as messages. */
export function mismatches(found, measured) {
  const out = [];
  for (const s of found) {
    const [bundle, kind] = s.key.split("-");
    const actual = measured[bundle][kind];
    const off = s.bytes / actual - 1;
    if (Math.abs(off) > TOLERANCE) {
      out.push(`${s.where}: states "${s.text}" (${s.key}) = ${Math.round(s.bytes).toLocaleString("en")} B; built: ${actual.toLocaleString("en")} B = ${(actual / 1048576).toFixed(2)} MiB (${(off * 100).toFixed(1)} % off, tolerance ±${TOLERANCE * 100} %)`);
    }
  }
  return out;
}

function measuredOrFail() {
  for (const files of Object.values(BUNDLES)) {
    for (const f of files) {
      if (!existsSync(join(pkgDir, f))) assert.fail(`pkg/${f} is not built: run ./dev build (this test compares the docs' sizes with the built package)`);
    }
  }
  return bundleSizes(pkgDir);
}

test("every size of the package the docs state matches the built pkg/ (±2 %)", () => {
  const measured = measuredOrFail();
  const all = [], problems = [];
  for (const file of docFiles()) {
    const { found, problems: p } = statements(file, readFileSync(join(root, file), "utf8"));
    all.push(...found);
    problems.push(...p);
  }
  console.log(`measured: full ${measured.full.raw} B raw / ${measured.full.gzip} B gzip; player ${measured.player.raw} B raw / ${measured.player.gzip} B gzip`);
  console.log(`statements: ${all.map((s) => `${s.where} ${s.text} (${s.key})`).join("; ")}`);
  assert.deepEqual(problems, [], "size statements not in the documented form");
  assert.deepEqual(mismatches(all, measured), [], "size statements that do not match the build");
  // The bundle table of docs/benchmarks.md states all four; pkg/README.md states both gzip sizes.
  for (const key of KEYS) assert.ok(all.some((s) => s.key === key), `no statement of ${key} found in ${docFiles().join(", ")}`);
  for (const key of ["full-gzip", "player-gzip"]) assert.ok(all.some((s) => s.key === key && s.where.startsWith("pkg/README.md")), `pkg/README.md states no ${key}`);
});

test("the check catches a wrong size, an unmarked one and an unknown key (control)", () => {
  const measured = measuredOrFail();
  const mib = (n) => (n / 1048576).toFixed(2);
  const right = `full ${mib(measured.full.gzip)} MiB<!-- size:full-gzip --> gzip`;
  const wrong = `full ${mib(measured.full.gzip * 1.05)} MiB<!-- size:full-gzip --> gzip`;
  const ok = statements("control", right);
  assert.deepEqual([ok.problems, mismatches(ok.found, measured)], [[], []], right);
  const bad = statements("control", wrong);
  assert.equal(mismatches(bad.found, measured).length, 1, `${wrong} should be caught`);
  assert.equal(statements("control", "player 1.61 MiB gzip").problems.length, 1, "an unmarked size on a gzip line");
  assert.equal(statements("control", "1.6 MiB<!-- size:full-zip --> gzip").problems.length, 1, "an unknown key");
  assert.equal(statements("control", "1.6 KB<!-- size:full-gzip -->").problems.length, 1, "an ambiguous unit");
});
