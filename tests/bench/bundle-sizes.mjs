// The npm package's bundle sizes, one definition for the embedding benchmark (embed.mjs) and
// for the test that checks the sizes the docs state (tests/node/doc-sizes.test.mjs): each
// bundle's files read from the built pkg/, raw bytes and gzip (level 9) of each file, summed.
//  - full: the full engine (`odori`): odori.js + odori_bg.wasm
//  - player: `odori/player`: the element + the player build's JS + wasm
// Imports nothing but Node's own modules, so a test can use it without a browser.
import { readFileSync } from "node:fs";
import { gzipSync } from "node:zlib";
import { join } from "node:path";

export const BUNDLES = {
  full: ["odori.js", "odori_bg.wasm"],
  player: ["player/odori-player.js", "player/odori_player.js", "player/odori_player_bg.wasm"],
};

/** `{ raw, gzip }` in bytes of the given files, summed over the files. */
export function size(files) {
  const bufs = files.map((f) => readFileSync(f));
  return { raw: bufs.reduce((s, b) => s + b.length, 0), gzip: bufs.reduce((s, b) => s + gzipSync(b, { level: 9 }).length, 0) };
}

/** `{ full: { raw, gzip }, player: { raw, gzip } }` of the package built in `pkgDir`. */
export function bundleSizes(pkgDir) {
  return Object.fromEntries(Object.entries(BUNDLES).map(([k, files]) => [k, size(files.map((f) => join(pkgDir, f)))]));
}
