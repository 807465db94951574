// "Open song… takes any format the browser decodes (mp3, ogg, wav, flac, m4a)" (README): the two
// formats the other tests do not cover, mp3 and m4a (AAC), in the app in headless Chromium. A
// click track with known beats (100 BPM, 24 s, written by `click-track.mjs`) is encoded by ffmpeg
// (npm `@ffmpeg-installer/linux-x64`, a static build installed by `./dev setup`) into each format;
// the page must decode the whole file and find the true tempo and beats, as it does for the WAV
// the encoder started from (checked first, as the control for the encoders' own delay).
import { test, before, after } from "node:test";
import assert from "node:assert/strict";
import { join } from "node:path";
import { execFileSync } from "node:child_process";
import { existsSync, mkdtempSync, readFileSync, writeFileSync, rmSync } from "node:fs";
import { tmpdir } from "node:os";
import { startServer, launch, openApp, waitUntil, root, artifacts } from "./harness.mjs";
import { clickTrackWav } from "./click-track.mjs";

const FFMPEG = join(root, "node_modules", "@ffmpeg-installer", "linux-x64", "ffmpeg");
const BPM = 100, SECS = 24;

let server;
before(async () => { server = await startServer(); });
after(() => server && server.stop());

test("mp3 and m4a songs: decoded whole, true tempo and beats found", async () => {
  assert.ok(existsSync(FFMPEG), `no ffmpeg at ${FFMPEG}: run ./dev setup (npm devDependency @ffmpeg-installer/linux-x64)`);
  const wav = clickTrackWav(BPM, SECS, 44100);
  const dir = mkdtempSync(join(tmpdir(), "odori-formats-"));
  const files = [{ name: "clicks-100.wav", mime: "audio/wav", bytes: wav.bytes }];
  try {
    writeFileSync(join(dir, "in.wav"), wav.bytes);
    for (const [name, mime, args] of [
      ["clicks-100.mp3", "audio/mpeg", ["-c:a", "libmp3lame", "-b:a", "128k"]],
      ["clicks-100.m4a", "audio/mp4", ["-c:a", "aac", "-b:a", "128k"]],
    ]) {
      execFileSync(FFMPEG, ["-hide_banner", "-loglevel", "error", "-y", "-i", join(dir, "in.wav"), ...args, join(dir, name)]);
      files.push({ name, mime, bytes: readFileSync(join(dir, name)) });
    }
  } finally {
    rmSync(dir, { recursive: true, force: true });
  }
  const { browser, page, logs } = await launch("webgl2");
  try {
    await openApp(page, server, "webgl2");
    await waitUntil(() => page.evaluate(() => document.body.dataset.song === "demo"), { what: "the demo song" });
    for (const f of files) {
      await page.setInputFiles("#song-input", { name: f.name, mimeType: f.mime, buffer: f.bytes });
      await waitUntil(() => page.evaluate((n) => document.body.dataset.song === n, f.name), { what: `${f.name} analysed`, timeoutMs: 60000 });
      const g = await page.evaluate(() => window.odori.song.grid);
      assert.ok(Math.abs(g.durationSecs - SECS) < 0.15, `${f.name}: decoded ${g.durationSecs} s of a ${SECS} s file`);
      assert.ok(Math.abs(g.bpm - BPM) < 1, `${f.name}: ${BPM} BPM analysed as ${g.bpm}`);
      const offsets = wav.beats.map((b) => Math.min(...g.beatTimesSecs.map((t) => Math.abs(t - b))));
      const hits = offsets.filter((d) => d <= 0.07).length;
      offsets.sort((a, b) => a - b);
      console.log(`${f.name}: ${f.bytes.length} bytes, ${g.durationSecs.toFixed(3)} s, ${g.bpm.toFixed(2)} BPM, ${hits}/${wav.beats.length} true beats within 70 ms (median offset ${(1000 * offsets[offsets.length >> 1]).toFixed(1)} ms)`);
      assert.ok(hits >= 0.9 * wav.beats.length, `${f.name}: only ${hits} of ${wav.beats.length} true beats found`);
    }
    assert.deepEqual(logs.filter((l) => l.startsWith("[pageerror]")), []);
  } catch (e) {
    await page.screenshot({ path: join(artifacts, "song-formats-failure.png") }).catch(() => {});
    console.log(logs.join("\n"));
    throw e;
  } finally {
    await browser.close();
  }
});
