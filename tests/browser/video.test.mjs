// The dance as a video (issue 29), made in headless Chromium on both back ends and checked by
// readers no one here wrote: ffprobe (@ffprobe-installer/ffprobe) for the container, codecs,
// size, frame rate and the decoded frame count; the static ffmpeg (@ffmpeg-installer) to
// decode frames and sound. Checked against the engine itself: five decoded frames (one in the
// middle of a join) match the engine's own rendering of their instant (PSNR ≥ 30 dB on the
// figure's bounding box) better than the renderings a frame before and after; the decoded
// sound lines up with the song's own samples (cross-correlation peak at lag 0 ± 1 ms). Then a
// WebM streamed into a file (the Origin Private File System's writable, the same kind of
// stream `showSaveFilePicker` gives), a cancelled stream (the file stays empty), and Cancel
// at 50 % in the app's dialog: no file, no error, the project unchanged, the page's playback
// paused during the export and playing after.
import { test, before, after } from "node:test";
import assert from "node:assert/strict";
import { execFileSync } from "node:child_process";
import { readFileSync, writeFileSync } from "node:fs";
import { join } from "node:path";
import { createRequire } from "node:module";
import { startServer, launch, openApp, artifacts, root, data, isWarmFigure, floatsFromBase64, generateDance } from "./harness.mjs";

const require = createRequire(import.meta.url);
const FFPROBE = require("@ffprobe-installer/ffprobe").path;
const FFMPEG = join(root, "node_modules", "@ffmpeg-installer", "linux-x64", "ffmpeg");

let server;
before(async () => { server = await startServer(); });
after(() => server && server.stop());

const FPS = 30, W = 1280, H = 720;
// Bars 1–4 of the dance (0-based 0..3): the lead-in count is included.
const FIRST = 0, LAST = 3;

/** Opens the app, generates a dance on the demo song, and returns the page. */
async function danceReady(backend) {
  const l = await launch(backend);
  await openApp(l.page, server, backend);
  await l.page.waitForFunction(() => Number(document.querySelector("#dance").dataset.bars) > 8, null, { timeout: 90000 });
  await generateDance(l.page, 90000);
  return l;
}

function probe(file) {
  const j = JSON.parse(execFileSync(FFPROBE, ["-v", "error", "-count_frames", "-show_entries", "stream=index,codec_type,codec_name,width,height,r_frame_rate,avg_frame_rate,nb_read_frames,duration,sample_rate,channels,color_space,color_range:format=format_name,duration", "-of", "json", file], { maxBuffer: 1 << 24 }).toString());
  return { format: j.format, video: j.streams.find((s) => s.codec_type === "video"), audio: j.streams.find((s) => s.codec_type === "audio") };
}

/** Frame `n` of the file decoded to RGBA by ffmpeg, with the colour matrix the stream declares. */
function decodeFrame(file, n, v) {
  const matrix = v.color_space === "bt709" ? "bt709" : "bt601";
  const range = v.color_range === "pc" ? "full" : "tv";
  return execFileSync(FFMPEG, ["-v", "error", "-i", file, "-vf", `select=eq(n\\,${n}),scale=in_color_matrix=${matrix}:in_range=${range}:out_range=full`, "-vsync", "0", "-frames:v", "1", "-f", "rawvideo", "-pix_fmt", "rgba", "-"], { maxBuffer: 1 << 26 });
}

/** The first audio channel decoded to 32-bit float at `sr` Hz. */
function decodeSound(file, sr) {
  const b = execFileSync(FFMPEG, ["-v", "error", "-i", file, "-map", "0:a:0", "-af", "pan=mono|c0=c0", "-ar", String(sr), "-f", "f32le", "-"], { maxBuffer: 1 << 28 });
  return new Float32Array(b.buffer, b.byteOffset, b.length / 4);
}

/** PSNR (dB) of two RGBA images over the box { x0, y0, x1, y1 } (RGB only). */
function psnr(a, b, width, box) {
  let se = 0, n = 0;
  for (let y = box.y0; y < box.y1; y++) for (let x = box.x0; x < box.x1; x++) {
    const i = (y * width + x) * 4;
    for (let c = 0; c < 3; c++) { const d = a[i + c] - b[i + c]; se += d * d; }
    n += 3;
  }
  return 10 * Math.log10((255 * 255) / Math.max(se / n, 1e-9));
}

/** Lag (samples, within ±maxLag) of the peak of the cross-correlation of `dec` against `ref` over [from, from + len). */
function xcorrPeak(ref, dec, from, len, maxLag) {
  let best = -Infinity, at = 0;
  for (let lag = -maxLag; lag <= maxLag; lag++) {
    let s = 0;
    for (let i = from; i < from + len; i++) s += ref[i] * (dec[i + lag] || 0);
    if (s > best) { best = s; at = lag; }
  }
  return at;
}

const b64 = (s) => Buffer.from(s, "base64");

for (const backend of ["webgl2", "webgpu"]) {
  test(`video (${backend}): MP4 of bars 1–4 with its lead-in, checked by ffprobe and ffmpeg against the engine and the song`, { timeout: 900000 }, async () => {
    const { browser, page, logs } = await danceReady(backend);
    try {
      const made = await page.evaluate(async ({ first, last, fps, w, h, backend }) => {
        const { exportVideo, danceRange, frameTimes } = await import("/video/export-video.js");
        const { choreo, library, songPlayer, project, exporter } = window.odori;
        choreo.renderDance();
        const id = choreo.danceId;
        const grid = project.project.grid();
        const sections = project.project.sections();
        const range = danceRange(grid.bars, first, last, grid.beatsPerBar);
        const bars = grid.bars.slice(first, last + 1);
        const t0 = performance.now();
        const r = await exportVideo({ engine: exporter.video.engine, library, clip: id, ...range, bars, sections, character: "builtin", width: w, height: h, fps, container: "mp4", song: songPlayer.buffer, backend }, () => {});
        const wallMs = performance.now() - t0;
        const mp4 = window.__test.base64(new Uint8Array(await r.blob.arrayBuffer()));
        // The engine's own renderings: a viewer of its own, the same camera plan (deterministic).
        const canvas = Object.assign(document.createElement("canvas"), { width: w, height: h });
        const viewer = await exporter.video.engine.Viewer.create(canvas, { backend });
        viewer.setCharacter(library, "builtin");
        const times = frameTimes(range.startSecs, range.endSecs, fps);
        const plan = viewer.planCamera(library, [{ clip: id, timeSecs: 0 }], { timesSecs: Array.from(times), bars, sections, camera: { aspect: w / h } });
        const n = times.length;
        // The middle of the join between bars 2 and 3: its bar line (5 frames rewritten each side).
        const join = Math.round((bars[2].startSecs - range.startSecs) * fps);
        const picks = [Math.round(n * 0.2), Math.round(n * 0.4), join, Math.round(n * 0.7), Math.round(n * 0.9)];
        const grab = () => {
          const c = new OffscreenCanvas(w, h);
          const g = c.getContext("2d");
          g.drawImage(canvas, 0, 0);
          return g.getImageData(0, 0, w, h).data;
        };
        const enc = window.__test.base64;
        const renders = [];
        for (const i of picks) {
          viewer.setCamera(plan.poses[i]);
          // The figure's box: its joints at the instant, projected, with room for the body.
          const fj = viewer.figureJoints(library, id, times[i]);
          let x0 = w, y0 = h, x1 = 0, y1 = 0;
          for (let k = 0; k < fj.positions.length; k += 3) {
            const p = viewer.project(fj.positions[k], fj.positions[k + 1], fj.positions[k + 2]);
            if (!p) continue;
            x0 = Math.min(x0, p[0]); x1 = Math.max(x1, p[0]); y0 = Math.min(y0, p[1]); y1 = Math.max(y1, p[1]);
          }
          const pad = 0.15 * Math.max(x1 - x0, y1 - y0) + 8;
          const box = { x0: Math.max(0, Math.floor(x0 - pad)), y0: Math.max(0, Math.floor(y0 - pad)), x1: Math.min(w, Math.ceil(x1 + pad)), y1: Math.min(h, Math.ceil(y1 + pad)) };
          const shots = {};
          for (const [k, dt] of [["at", 0], ["before", -1 / fps], ["after", 1 / fps]]) {
            viewer.setCamera(plan.poses[i]);
            viewer.draw(library, [{ clip: id, timeSecs: times[i] + dt }]);
            shots[k] = enc(grab());
          }
          renders.push({ frame: i, box, ...shots });
        }
        viewer.release();
        // The song's own first channel over the range.
        const sr = songPlayer.buffer.sampleRate;
        const a = Math.round(range.startSecs * sr), len = Math.round(r.durationSecs * sr);
        const song = songPlayer.buffer.getChannelData(0).slice(a, a + len);
        return {
          mp4, codecs: r.codecs, frames: r.frames, durationSecs: r.durationSecs, range, wallMs, sr, renders,
          song: enc(new Uint8Array(song.buffer)), shots: r.camera.shots, samePlan: JSON.stringify(plan.poses) === JSON.stringify(r.camera.poses),
          aacSupported: (await AudioEncoder.isConfigSupported({ codec: "mp4a.40.2", sampleRate: sr, numberOfChannels: 2, bitrate: 128000 })).supported,
          h264Supported: (await VideoEncoder.isConfigSupported({ codec: "avc1.640028", width: w, height: h, bitrate: 2e6 })).supported,
        };
      }, { first: FIRST, last: LAST, fps: FPS, w: W, h: H, backend });
      const file = join(artifacts, `video-${backend}.mp4`);
      writeFileSync(file, b64(made.mp4));
      console.log(`${backend}: ${made.frames} frames (${made.durationSecs.toFixed(3)} s from ${made.range.startSecs.toFixed(3)} s) in ${(made.wallMs / 1000).toFixed(1)} s; codecs ${made.codecs.videoName} + ${made.codecs.audioName} in MP4${made.codecs.fallback ? ` (${made.codecs.fallback})` : ""}; ${b64(made.mp4).length} bytes; shots ${JSON.stringify(made.shots)}`);
      assert.ok(made.samePlan, "the camera plan is the same when planned again");

      // The codec path: H.264 where the browser encodes it, AAC where it does, else Opus, said so.
      assert.equal(made.codecs.video, made.h264Supported ? "avc" : made.codecs.video);
      if (!made.aacSupported) {
        assert.equal(made.codecs.audio, "opus");
        assert.match(made.codecs.fallback, /AAC refused, Opus used/);
      } else assert.equal(made.codecs.audio, "aac");

      // ffprobe: container, codecs, size, rate, and the decoded frame count exactly.
      const p = probe(file);
      const expectFrames = Math.round((made.range.endSecs - made.range.startSecs) * FPS);
      console.log(`${backend}: ffprobe ${p.format.format_name}; video ${p.video.codec_name} ${p.video.width}×${p.video.height} ${p.video.r_frame_rate} (${p.video.nb_read_frames} frames decoded, colour ${p.video.color_space}/${p.video.color_range}); audio ${p.audio.codec_name} ${p.audio.sample_rate} Hz ×${p.audio.channels}, ${p.audio.duration} s`);
      assert.match(p.format.format_name, /mp4/);
      assert.equal(p.video.codec_name, { avc: "h264", vp9: "vp9", av1: "av1" }[made.codecs.video]);
      assert.equal(p.audio.codec_name, { aac: "aac", opus: "opus" }[made.codecs.audio]);
      assert.equal(p.video.width, W);
      assert.equal(p.video.height, H);
      assert.equal(p.video.r_frame_rate, `${FPS}/1`);
      assert.equal(Number(p.video.nb_read_frames), expectFrames, "decoded frames = round(duration × fps)");
      assert.equal(made.frames, expectFrames);

      // The sound: as long as the range (within a frame), and in time with the song.
      const sound = decodeSound(file, made.sr);
      const soundSecs = sound.length / made.sr;
      const rangeSecs = made.range.endSecs - made.range.startSecs;
      console.log(`${backend}: sound decoded ${soundSecs.toFixed(4)} s (ffprobe ${p.audio.duration} s) for ${rangeSecs.toFixed(4)} s of bars`);
      assert.ok(Math.abs(soundSecs - rangeSecs) <= 1 / FPS, `the sound lasts ${soundSecs} s, the bars ${rangeSecs} s`);
      const ref = floatsFromBase64(made.song);
      const maxLag = Math.round(0.02 * made.sr);
      const lags = [0.25, 0.5, 0.75].map((f) => xcorrPeak(ref, sound, Math.round(ref.length * f) - made.sr / 4, Math.round(made.sr / 2), maxLag));
      console.log(`${backend}: cross-correlation peaks at lags ${lags.map((l) => `${((l / made.sr) * 1000).toFixed(2)} ms`).join(", ")}`);
      for (const l of lags) assert.ok(Math.abs(l) / made.sr <= 0.001, `the sound is ${(l / made.sr) * 1000} ms off the song`);

      // Frame-exact: each decoded frame is its own instant's rendering, not a neighbour's.
      for (const r of made.renders) {
        const dec = decodeFrame(file, r.frame, p.video);
        const at = psnr(dec, b64(r.at), W, r.box), bef = psnr(dec, b64(r.before), W, r.box), aft = psnr(dec, b64(r.after), W, r.box);
        console.log(`${backend}: frame ${r.frame} box ${r.box.x1 - r.box.x0}×${r.box.y1 - r.box.y0}: PSNR ${at.toFixed(1)} dB at its instant, ${bef.toFixed(1)} a frame before, ${aft.toFixed(1)} after`);
        assert.ok(at >= 30, `frame ${r.frame}: PSNR ${at} dB`);
        assert.ok(at > bef && at > aft, `frame ${r.frame} matches a neighbouring instant better (${at} vs ${bef} / ${aft})`);
      }
      assert.deepEqual(logs.filter((l) => l.startsWith("[pageerror]")), []);
    } finally {
      await browser.close();
    }
  });
}

test("video (webgl2): a WebM streamed into a file, a cancelled stream leaves it empty, and Cancel at 50 % in the app", { timeout: 900000 }, async () => {
  const { browser, page, logs } = await danceReady("webgl2");
  try {
    const out = await page.evaluate(async () => {
      const { exportVideo, danceRange } = await import("/video/export-video.js");
      const { choreo, library, songPlayer, project, exporter } = window.odori;
      choreo.renderDance();
      const grid = project.project.grid();
      const range = danceRange(grid.bars, 0, 1, grid.beatsPerBar);
      const opfs = await navigator.storage.getDirectory();
      const common = { engine: exporter.video.engine, library, clip: choreo.danceId, ...range, bars: grid.bars.slice(0, 2), character: null, width: 1080, height: 1080, fps: 30, container: "webm", song: songPlayer.buffer, backend: "webgl2" };
      const fh = await opfs.getFileHandle("whole.webm", { create: true });
      const r = await exportVideo({ ...common, stream: await fh.createWritable() });
      const webm = window.__test.base64(new Uint8Array(await (await fh.getFile()).arrayBuffer()));
      // Cancelled half-way: the stream is aborted, so the file keeps nothing.
      const ch = await opfs.getFileHandle("cancelled.webm", { create: true });
      const abort = new AbortController();
      let kind = null, atCancel = 0;
      try {
        await exportVideo({ ...common, stream: await ch.createWritable(), signal: abort.signal }, (p) => { if (p.fraction >= 0.5 && !abort.signal.aborted) { atCancel = p.fraction; abort.abort(); } });
      } catch (e) { kind = e.kind; }
      const left = (await ch.getFile()).size;
      return { webm, blob: r.blob, codecs: r.codecs, frames: r.frames, range, kind, left, atCancel };
    });
    const file = join(artifacts, "video-stream.webm");
    writeFileSync(file, b64(out.webm));
    const p = probe(file);
    console.log(`stream: ${p.format.format_name}, ${p.video.codec_name} ${p.video.width}×${p.video.height} ${p.video.r_frame_rate}, ${p.video.nb_read_frames} frames, ${p.audio.codec_name}; cancelled at ${(out.atCancel * 100).toFixed(0)} %: ${out.kind}, ${out.left} bytes left`);
    assert.equal(out.blob, null, "written to the stream, no Blob");
    assert.match(p.format.format_name, /webm/);
    assert.equal(p.video.codec_name, "vp9");
    assert.equal(p.audio.codec_name, "opus");
    assert.equal(p.video.width, 1080);
    assert.equal(p.video.height, 1080);
    assert.equal(Number(p.video.nb_read_frames), Math.round((out.range.endSecs - out.range.startSecs) * 30));
    assert.equal(out.kind, "video-cancelled");
    assert.equal(out.left, 0, "the cancelled file keeps nothing");

    // Cancel at 50 % in the app's dialog: no download, no error, the project unchanged.
    const downloads = [];
    page.on("download", (d) => downloads.push(d.suggestedFilename()));
    const before = await page.evaluate(() => { delete window.showSaveFilePicker; window.odori.player.play(); return { rev: window.odori.project.project.revision, doc: JSON.stringify(window.odori.project.project.doc()) }; });
    await page.click("#export");
    await page.selectOption("#export-format", "video");
    await page.click("#export-go");
    await page.locator("#video-dialog").waitFor({ state: "visible" });
    await page.selectOption("#video-size", "1280x720");
    await page.click("#video-go");
    await page.waitForFunction(() => Number(document.querySelector("#video-progress").value) >= 0.5, null, { timeout: 600000 });
    // The page's playback pauses while the video is made (its frames would wait behind the
    // export's on the GPU, holding the page's thread) and plays on after.
    assert.equal(await page.evaluate(() => window.odori.player.playing), false, "the playback is paused during the export");
    await page.click("#video-cancel");
    await page.waitForFunction(() => /Cancelled/.test(document.querySelector("#video-status").textContent), null, { timeout: 60000 });
    await new Promise((r) => setTimeout(r, 500));
    const after = await page.evaluate(() => ({
      rev: window.odori.project.project.revision, doc: JSON.stringify(window.odori.project.project.doc()),
      errors: [...document.querySelectorAll("#messages li.error")].map((li) => li.textContent),
      status: document.querySelector("#video-status").textContent,
      playing: window.odori.player.playing,
    }));
    console.log(`app: ${after.status}`);
    assert.deepEqual(downloads, [], "no file was downloaded");
    assert.deepEqual(after.errors, [], "no error shown");
    assert.equal(after.rev, before.rev, "the project's revision");
    assert.equal(after.doc, before.doc, "the project's document");
    assert.equal(after.playing, true, "the playback plays on after the export");
    assert.deepEqual(logs.filter((l) => l.startsWith("[pageerror]")), []);
  } finally {
    await browser.close();
  }
});

// A song whose first bar starts well after its first sample (Sugar Plum Fairy: the demo song's
// first bar starts at 0 s, where a lead-in has no room): bars 1–2 of its dance from the lead-in
// count. The frames are round((the bars' duration + the lead-in) × fps) by ffprobe; the sound
// starts at the lead-in (found by searching the song, not assumed: the decoded sound's best
// match lies a beat before bar 1, not at bar 1). How far the figure moves in the lead-in is printed.
const LEAD_SONG = "Kevin_MacLeod_-_P_I_Tchaikovsky_Dance_of_the_Sugar_Plum_Fairy.hq.ogg";
test("video (webgl2): a dance from bar 1 of a song whose first bar starts later includes its lead-in count", { timeout: 900000 }, async () => {
  const { browser, page, logs } = await launch("webgl2");
  try {
    await openApp(page, server, "webgl2");
    await page.setInputFiles("#song-input", join(data, "music", LEAD_SONG));
    await page.waitForFunction((n) => document.body.dataset.song === n, LEAD_SONG, { timeout: 180000 });
    // The file is picked as soon as the page is ready, while the new project's demo song may
    // still be in the making: the song picked last must stay the project's song.
    await page.waitForFunction(() => document.body.dataset.project === "ready", null, { timeout: 180000 });
    assert.equal(await page.evaluate(() => document.body.dataset.song), LEAD_SONG, "the demo song, made later, replaced the picked song");
    assert.equal(await page.evaluate(() => window.odori.project.project.summary().song?.fileName), LEAD_SONG, "the project's song");
    await page.waitForFunction(() => Number(document.querySelector("#dance").dataset.bars) > 8, null, { timeout: 90000 });
    await page.click("#dance-generate");
    await page.waitForFunction(() => !document.querySelector("#dance").dataset.busy && window.odori.choreo.view.every((v) => v.state.kind !== "empty"), null, { timeout: 90000 });
    const made = await page.evaluate(async ({ fps }) => {
      const { exportVideo, danceRange } = await import("/video/export-video.js");
      const { choreo, library, songPlayer, project, exporter } = window.odori;
      choreo.renderDance();
      const id = choreo.danceId;
      const grid = project.project.grid();
      const bars = grid.bars.slice(0, 2);
      const range = danceRange(grid.bars, 0, 1, grid.beatsPerBar);
      const r = await exportVideo({ engine: exporter.video.engine, library, clip: id, ...range, bars, character: null, width: 1280, height: 720, fps, container: "mp4", song: songPlayer.buffer, backend: "webgl2" });
      const bytes = new Uint8Array(await r.blob.arrayBuffer());
      const enc = window.__test.base64;
      const sr = songPlayer.buffer.sampleRate;
      const song = songPlayer.buffer.getChannelData(0).slice(0, Math.round((range.endSecs + 0.5) * sr));
      // How far the figure moves during the lead-in (largest joint displacement from its first
      // pose, metres, sampled at every frame of it): printed.
      const a = library.jointPositions(id, range.startSecs);
      let moved = 0;
      for (let t = range.startSecs; t <= bars[0].startSecs; t += 1 / fps) {
        const b = library.jointPositions(id, t);
        for (let k = 0; k < a.length; k += 3) moved = Math.max(moved, Math.hypot(a[k] - b[k], a[k + 1] - b[k + 1], a[k + 2] - b[k + 2]));
      }
      return { mp4: enc(bytes), frames: r.frames, range, bars, beats: bars[0].beats || grid.beatsPerBar, sr, song: enc(new Uint8Array(song.buffer)), moved, path: r.path };
    }, { fps: FPS });
    const file = join(artifacts, "video-lead-in.mp4");
    writeFileSync(file, b64(made.mp4));
    const [b0, b1] = made.bars;
    const leadIn = (b0.endSecs - b0.startSecs) / made.beats;
    assert.ok(b0.startSecs >= leadIn, `${LEAD_SONG}'s first bar starts at ${b0.startSecs} s, less than a beat (${leadIn} s) in: the test needs a song with room for the lead-in`);
    const expectFrames = Math.round((b1.endSecs - b0.startSecs + leadIn) * FPS);
    const p = probe(file);
    console.log(`lead-in: bar 1 at ${b0.startSecs.toFixed(3)} s, lead-in ${leadIn.toFixed(3)} s, video from ${made.range.startSecs.toFixed(3)} s: ${p.video.nb_read_frames} frames decoded (expected ${expectFrames}); the figure moves ${made.moved.toFixed(3)} m in the lead-in; ${made.path}`);
    assert.equal(Number(p.video.nb_read_frames), expectFrames, "decoded frames = round((bars + lead-in) × fps)");
    assert.equal(made.frames, expectFrames);
    // Where in the song the sound starts: the offset whose samples best match the decoded
    // sound's first quarter second (after the fade in), searched from 1.5 beats before bar 1
    // to a quarter beat after it (normalised cross-correlation).
    const sr = made.sr;
    const sound = decodeSound(file, sr);
    const song = floatsFromBase64(made.song);
    const from = Math.round(0.05 * sr), len = Math.round(0.25 * sr);
    let best = -Infinity, at = 0;
    const lo = Math.max(0, Math.round((b0.startSecs - 1.5 * leadIn) * sr)), hi = Math.round((b0.startSecs + 0.25 * leadIn) * sr);
    for (let o = lo; o <= hi; o++) {
      let s = 0, e = 0;
      for (let i = 0; i < len; i++) { const v = song[o + from + i] || 0; s += v * sound[from + i]; e += v * v; }
      const c = s / Math.sqrt(e + 1e-12);
      if (c > best) { best = c; at = o; }
    }
    const startsAt = at / sr;
    console.log(`lead-in: the sound starts at song time ${startsAt.toFixed(4)} s (lead-in ${(b0.startSecs - leadIn).toFixed(4)} s, bar 1 ${b0.startSecs.toFixed(4)} s)`);
    assert.ok(Math.abs(startsAt - (b0.startSecs - leadIn)) <= 0.001, `the sound starts at ${startsAt} s of the song, not at the lead-in ${b0.startSecs - leadIn} s`);
    assert.deepEqual(logs.filter((l) => l.startsWith("[pageerror]")), []);
  } finally {
    await browser.close();
  }
});

// An MMD camera VMD drives the camera: 時間のカケラ's dance and its camera VMD imported through the
// library's MMD import (on the standard skeleton), 4 s of it made into a video with the camera
// VMD chosen. ffprobe counts round(4 × fps) frames; in 5 decoded frames the figure (the stick
// figure's orange) is drawn where the camera track puts it: 90 % of its pixels lie in the box
// of its joints projected with the poses the export used (planned again), a box under 60 % of
// the frame.
test("video (webgl2): a camera VMD drives the camera", { timeout: 900000 }, async () => {
  const { browser, page, logs } = await launch("webgl2");
  try {
    await openApp(page, server, "webgl2");
    const file = (rel) => readFileSync(join(data, rel)).toString("base64");
    const made = await page.evaluate(async ({ dance, cam, fps }) => {
      const { exportVideo, frameTimes } = await import("/video/export-video.js");
      const { library, exporter } = window.odori;
      const bytes = window.__test.bytes;
      const report = library.importFiles([{ name: "tokino_kakera.vmd", bytes: bytes(dance) }, { name: "tokino_kakera_cam.vmd", bytes: bytes(cam) }], { model: "standard" });
      const id = report.motions[0].clip.id;
      const track = library.cameraTracks().length - 1;
      const range = { startSecs: 40, endSecs: 44 };
      const w = 1280, h = 720;
      const r = await exportVideo({ engine: exporter.video.engine, library, clip: id, ...range, character: null, width: w, height: h, fps, container: "mp4", song: null, camera: { mode: "vmd", track }, backend: "webgl2" });
      const enc = window.__test.base64;
      // The joints' projected centre in 5 frames, with the camera planned again.
      const canvas = Object.assign(document.createElement("canvas"), { width: w, height: h });
      const viewer = await exporter.video.engine.Viewer.create(canvas, { backend: "webgl2" });
      const times = frameTimes(range.startSecs, range.endSecs, fps);
      const plan = viewer.planCamera(library, [{ clip: id, style: "stick", timeSecs: 0 }], { timesSecs: Array.from(times), bars: [], cameraTrack: { index: track } });
      const picks = [0.1, 0.3, 0.5, 0.7, 0.9].map((f) => Math.round(f * (times.length - 1)));
      const centres = picks.map((i) => {
        viewer.setCamera(plan.poses[i]);
        const fj = viewer.figureJoints(library, id, times[i]);
        let x0 = w, y0 = h, x1 = 0, y1 = 0;
        for (let k = 0; k < fj.positions.length; k += 3) {
          const p = viewer.project(fj.positions[k], fj.positions[k + 1], fj.positions[k + 2]);
          if (!p) continue;
          x0 = Math.min(x0, p[0]); x1 = Math.max(x1, p[0]); y0 = Math.min(y0, p[1]); y1 = Math.max(y1, p[1]);
        }
        // Room for the bones' and head's thickness, as the first test's box.
        const pad = 0.15 * Math.max(x1 - x0, y1 - y0) + 8;
        return { frame: i, x0: x0 - pad, y0: y0 - pad, x1: x1 + pad, y1: y1 + pad };
      });
      viewer.release();
      return { mp4: enc(new Uint8Array(await r.blob.arrayBuffer())), frames: r.frames, shots: r.camera.shots.length, samePlan: JSON.stringify(plan.poses) === JSON.stringify(r.camera.poses), centres, cameras: report.cameras, w, h };
    }, { dance: file("mmd/motion/tokino_kakera.vmd"), cam: file("mmd/motion/tokino_kakera_cam.vmd"), fps: FPS });
    const out = join(artifacts, "video-camera-vmd.mp4");
    writeFileSync(out, b64(made.mp4));
    const p = probe(out);
    console.log(`camera VMD: ${JSON.stringify(made.cameras)}; ${p.video.nb_read_frames} frames decoded; ${made.shots} shots`);
    assert.equal(made.cameras.length, 1, "the camera VMD became a camera track");
    assert.equal(Number(p.video.nb_read_frames), Math.round(4 * FPS));
    assert.equal(made.frames, Math.round(4 * FPS));
    assert.ok(made.samePlan, "the camera track gives the same poses when planned again");
    assert.equal(made.shots, 0, "a camera track has no planned shots");
    for (const c of made.centres) {
      const img = decodeFrame(out, c.frame, p.video);
      let n = 0, inside = 0;
      for (let py = 0; py < made.h; py++) for (let px = 0; px < made.w; px++) {
        const i = (py * made.w + px) * 4;
        if (isWarmFigure([img[i], img[i + 1], img[i + 2]])) {
          n++;
          if (px >= c.x0 && px <= c.x1 && py >= c.y0 && py <= c.y1) inside++;
        }
      }
      const boxShare = ((Math.min(made.w, c.x1) - Math.max(0, c.x0)) * (Math.min(made.h, c.y1) - Math.max(0, c.y0))) / (made.w * made.h);
      console.log(`camera VMD: frame ${c.frame}: ${n} figure pixels, ${((100 * inside) / n).toFixed(1)} % inside the joints' projected box (${(100 * boxShare).toFixed(0)} % of the frame)`);
      assert.ok(n > 300, `frame ${c.frame}: only ${n} figure pixels`);
      assert.ok(inside >= 0.9 * n, `frame ${c.frame}: ${inside} of ${n} figure pixels where the camera track puts the figure`);
      assert.ok(boxShare < 0.6, `frame ${c.frame}: the box is ${boxShare} of the frame: the check cannot tell`);
    }
    assert.deepEqual(logs.filter((l) => l.startsWith("[pageerror]")), []);
  } finally {
    await browser.close();
  }
});

// Issue 28: a camera VMD opened through the page's file picker is kept in the project (undo and
// redo take it out and back); after a reload (the project restored from the browser's store)
// the video dialog offers it, and picked there — not through the API — it makes a video of bars
// 1–2 whose frames ffprobe counts.
for (const backend of ["webgl2", "webgpu"]) test(`video (${backend}): a camera VMD kept in the project is picked in the video dialog after a reload`, { timeout: 900000 }, async () => {
  const { browser, page, logs } = await danceReady(backend);
  try {
    const CAM = "tokino_kakera_cam.vmd";
    await page.setInputFiles("#file-input", [{ name: CAM, mimeType: "application/octet-stream", buffer: readFileSync(join(data, "mmd/motion", CAM)) }]);
    await page.waitForFunction((cam) => document.querySelector("#messages").textContent.includes(`${cam}: camera motion added to the project`), CAM, { timeout: 60000 });
    const kept = () => page.evaluate(() => ({ project: window.odori.project.project.summary().cameras.map((c) => c.fileName), library: window.odori.library.cameraTracks().map((t) => t.source) }));
    assert.deepEqual(await kept(), { project: [CAM], library: [CAM] });
    await page.evaluate(async () => { window.odori.project.undo(); await window.odori.project.reconciling; });
    assert.deepEqual(await kept(), { project: [], library: [] }, "undo takes the import back");
    await page.evaluate(async () => { window.odori.project.redo(); await window.odori.project.reconciling; });
    assert.deepEqual(await kept(), { project: [CAM], library: [CAM] }, "redo brings it back");

    // Reload: the project (with its camera) comes back from IndexedDB.
    await page.evaluate(() => window.odori.project.store.flush());
    await page.reload();
    await page.waitForFunction(() => document.body.dataset.ready === "1" && document.body.dataset.project === "ready" && window.odori.choreo?.view?.length && window.odori.choreo.view.every((v) => v.state.kind !== "empty"), null, { timeout: 120000 });
    await page.waitForFunction(() => window.odori.library.cameraTracks().length > 0, null, { timeout: 30000 });
    assert.deepEqual(await kept(), { project: [CAM], library: [CAM] }, "the reopened project shows its camera");

    // Export → bars 1–2 → Video; the camera chosen in the dialog's own list.
    const downloads = [];
    page.on("download", (d) => downloads.push(d));
    await page.evaluate(() => { delete window.showSaveFilePicker; });
    await page.click("#export");
    await page.selectOption("#export-format", "video");
    await page.check("input[name=export-what][value=bars]");
    await page.fill("#export-bar-from", "1");
    await page.fill("#export-bar-to", "2");
    await page.click("#export-go");
    await page.locator("#video-dialog").waitFor({ state: "visible" });
    const offered = await page.$$eval("#video-camera option", (os) => os.map((o) => o.textContent));
    assert.ok(offered.includes("Camera VMD: tokino_kakera_cam"), `the dialog offers the project's camera: ${offered.join(", ")}`);
    await page.selectOption("#video-camera", { label: "Camera VMD: tokino_kakera_cam" });
    const chosen = await page.evaluate(async () => {
      const { cameraChoice } = await import("/video/video-panel.js");
      return cameraChoice(document.querySelector("#video-camera").value);
    });
    const track = await page.evaluate((i) => window.odori.library.cameraTracks()[i], chosen.track);
    assert.equal(chosen.mode, "vmd");
    assert.equal(track.source, CAM, "the option picks the project's camera track");
    await page.click("#video-go");
    await page.waitForFunction(() => /^Done: \d+ frames/.test(document.querySelector("#video-status").textContent), null, { timeout: 600000 });
    const status = await page.textContent("#video-status");
    await waitForDownload(downloads);
    const out = join(artifacts, `video-camera-vmd-dialog-${backend}.mp4`);
    await downloads[0].saveAs(out);
    // The range the dialog exports: bars 1–2 from their lead-in count (the same function the dialog uses).
    const range = await page.evaluate(async () => {
      const { danceRange } = await import("/video/export-video.js");
      const grid = window.odori.project.project.grid();
      return danceRange(grid.bars, 0, 1, grid.beatsPerBar);
    });
    const p = probe(out);
    const want = Math.round((range.endSecs - range.startSecs) * FPS);
    console.log(`${backend}: camera VMD from the project, picked in the dialog: ${status} ffprobe: ${p.video.codec_name} ${p.video.width}×${p.video.height}, ${p.video.nb_read_frames} frames (bars 1–2 with the lead-in: ${want})`);
    assert.equal(Number(p.video.nb_read_frames), want);
    assert.equal(Number(/Done: (\d+) frames/.exec(status)[1]), want);
    const errors = await page.evaluate(() => [...document.querySelectorAll("#messages li.error")].map((li) => li.textContent));
    assert.deepEqual(errors, []);
    assert.deepEqual(logs.filter((l) => l.startsWith("[pageerror]")), []);
  } finally {
    await browser.close();
  }
});

async function waitForDownload(list, timeoutMs = 60000) {
  const t0 = Date.now();
  while (!list.length && Date.now() - t0 < timeoutMs) await new Promise((r) => setTimeout(r, 100));
  assert.ok(list.length, "the dialog's video was downloaded");
}
