// Takes the README's picture of the app (docs/screenshot.png): the app in headless Chromium
// (the browser tests' flags and server, tests/browser/harness.mjs) on the demo song, a dance
// generated, one bar's six candidates shown side by side. Not a test.
// Run after `./dev build`: node tests/tools/screenshot.mjs [webgl2|webgpu] [out.png]
// The PNG (about 160 KB) is then quantised by Debian's pngquant when it is installed
// (`apt-get install pngquant`; about 55 KB), to keep the repository's picture small.
import { statSync, renameSync } from "node:fs";
import { spawnSync } from "node:child_process";
import { join } from "node:path";
import { startServer, launch, openApp, root } from "../browser/harness.mjs";

const backend = process.argv[2] || "webgl2";
const out = process.argv[3] || join(root, "docs", "screenshot.png");
const server = await startServer();
const { browser, page, logs } = await launch(backend);
try {
  await page.setViewportSize({ width: 1200, height: 720 });
  await openApp(page, server, backend);
  // The first-run hint covers part of the view: close it, as a person would.
  if (await page.isVisible("#hint-close")) await page.click("#hint-close");
  await page.waitForFunction(() => Number(document.querySelector("#dance").dataset.bars) > 8, null, { timeout: 120000 });
  await page.waitForFunction(() => document.querySelector("#dance").dataset.joins === "ready", null, { timeout: 120000 });
  await page.click("#dance-generate");
  await page.waitForFunction(() => !document.querySelector("#dance").dataset.busy && window.odori.choreo.view.every((v) => v.state.kind !== "empty"), null, { timeout: 120000 });
  await page.click('#dance-bars [data-bar="5"]');
  await page.waitForFunction(() => document.querySelector("#dance").dataset.candidates === "6", null, { timeout: 60000 });
  // Let the six candidates play a moment (a tool, not a test: the wait is for the picture).
  await page.waitForTimeout(1500);
  await page.screenshot({ path: out });
  console.log(`${out}: ${statSync(out).size} bytes (${backend})`);
  const q = spawnSync("pngquant", ["--force", "--strip", "--quality=70-90", "--output", `${out}.q`, out], { stdio: "inherit" });
  if (q.error || q.status !== 0) console.log("pngquant not available or failed: the PNG is kept as taken");
  else { renameSync(`${out}.q`, out); console.log(`quantised by pngquant: ${statSync(out).size} bytes`); }
} catch (e) {
  console.error(logs.join("\n"));
  throw e;
} finally {
  await browser.close();
  server.stop();
}
