// README behaviours that had no test (issue 17), in the app in headless Chromium: every
// keyboard shortcut the README lists; the song corrections Tap, Metronome, Downbeat here,
// shift-click and plain click on the strip; song formats other than FLAC (a WAV written by
// this test with known beats, and a real Ogg Vorbis file compared with the native analysis);
// swapping a clip in the text table. Every wait polls state with a deadline.
import { test, before, after } from "node:test";
import assert from "node:assert/strict";
import { join } from "node:path";
import { execFileSync } from "node:child_process";
import { startServer, launch, openApp, waitUntil, data, root, artifacts } from "./harness.mjs";
import { clickTrackWav } from "./click-track.mjs";

let server;
before(async () => { server = await startServer(); });
after(() => server && server.stop());

const state = (page, fn, arg) => page.evaluate(fn, arg);
const until = (page, fn, what, arg, timeoutMs = 30000) => waitUntil(() => page.evaluate(fn, arg), { what, timeoutMs });

test("README behaviours: keyboard shortcuts, song corrections, WAV and Ogg songs, swapping a clip in the text table", async () => {
  const OGG = "music/Kevin_MacLeod_-_Vibe_Ace.hq.ogg";
  const native = JSON.parse(execFileSync("cargo", ["run", "-q", "-p", "odori-tests", "--example", "song_grid", "--", OGG], { cwd: root, encoding: "utf8" }));
  const { browser, page, logs } = await launch("webgl2");
  try {
    await openApp(page, server, "webgl2");
    await until(page, () => Number(document.querySelector("#dance").dataset.bars) > 8 && document.body.dataset.song === "demo", "the demo song's bars");
    await page.click("#view"); // focus on the page, not on a field

    // Space plays / pauses; ←/→ step a frame while paused.
    const playing0 = await state(page, () => window.odori.player.playing);
    await page.keyboard.press("Space");
    await until(page, (p) => window.odori.player.playing !== p, "Space toggling playback", playing0);
    if (await state(page, () => window.odori.player.playing)) await page.keyboard.press("Space");
    await until(page, () => !window.odori.player.playing, "Space pausing");
    const frame = () => state(page, () => Number(document.querySelector("#scrub").value));
    const f0 = await frame();
    await page.keyboard.press("ArrowRight");
    assert.equal(await frame(), f0 + 1, "→ steps one frame");
    await page.keyboard.press("ArrowLeft");
    assert.equal(await frame(), f0, "← steps back one frame");

    // ] and [ select bars; S pins the ticked candidate; F searches; G generates; P plays;
    // Ctrl+Z / Ctrl+Shift+Z undo and redo.
    await page.keyboard.press("]");
    await until(page, () => window.odori.choreo.bar === 0 && document.querySelector("#dance").dataset.candidates === "6", "] selecting bar 1 with six candidates");
    await page.keyboard.press("]");
    await page.keyboard.press("]");
    await page.keyboard.press("[");
    assert.equal(await state(page, () => window.odori.choreo.bar), 1, "] ] ] [ ends on bar 2");
    await page.click('#dance-candidates [data-k="2"]');
    const pick = await state(page, () => window.odori.choreo.candidates[2]);
    await page.keyboard.press("s");
    assert.deepEqual(await state(page, () => window.odori.choreo.view[1].state), { kind: "pinned", segment: pick }, "S pins the ticked candidate");
    await page.keyboard.press("]");
    await until(page, () => window.odori.choreo.bar === 2 && document.querySelector("#dance").dataset.candidates === "6", "bar 3's candidates");
    const shown = await state(page, () => window.odori.choreo.candidates.slice());
    await page.click('#dance-candidates [data-k="0"]');
    await page.keyboard.press("f");
    await until(page, () => Math.abs(window.odori.choreo.view[2].tau - 0.95) < 1e-4, "F: one search round (τ 0.95)");
    const next = await state(page, () => window.odori.choreo.candidates.slice());
    assert.ok(next.every((s) => !shown.includes(s)), "F shows new candidates");
    await until(page, () => document.querySelector("#dance").dataset.joins === "ready", "the join table", undefined, 60000);
    await page.keyboard.press("g");
    await until(page, () => !document.querySelector("#dance").dataset.busy && window.odori.choreo.view.every((v) => v.state.kind !== "empty"), "G filling every bar", undefined, 60000);
    assert.deepEqual(await state(page, () => window.odori.choreo.view[1].state), { kind: "pinned", segment: pick });
    await page.keyboard.press("Control+z");
    await until(page, () => window.odori.choreo.view.some((v) => v.state.kind === "empty"), "Ctrl+Z undoing Generate");
    await page.keyboard.press("Control+Shift+z");
    await until(page, () => window.odori.choreo.view.every((v) => v.state.kind !== "empty"), "Ctrl+Shift+Z redoing Generate");
    await page.keyboard.press("p");
    await until(page, () => window.odori.songPlayer.playing && window.odori.player.clip === window.odori.choreo.danceId, "P playing the dance with the song");
    await page.click("#song-play"); // stop
    await until(page, () => !window.odori.songPlayer.playing, "the song stopping");

    // Ctrl+Enter in the text box animates.
    await page.fill("#text-input", "Taro runs, then kicks the ball. Then he rejoices.");
    await page.focus("#text-input");
    await page.keyboard.press("Control+Enter");
    await until(page, () => document.querySelectorAll("#text-table tbody tr").length === 3, "Ctrl+Enter animating the text");

    // Swapping a clip in the text table re-animates with that clip. An alternative for "run":
    // a second clip tagged "run" (the person's own, here the built-in clip of the library).
    await page.click("#library tbody tr:first-child td:first-child");
    await page.fill("#text-tags", "run");
    await page.click("#text-tag");
    await page.fill("#text-input", "Taro runs, then kicks the ball. Then he rejoices.");
    await page.click("#text-go");
    await until(page, () => document.querySelector("#text-table tbody tr select")?.options.length > 1, "an alternative clip for the first row");
    const before = await state(page, () => ({ clip: window.odori.text.elements[0].clip, id: window.odori.text.clipId, pose: Array.from(window.odori.library.jointPositions(window.odori.text.clipId, 0.3)) }));
    const other = await state(page, () => [...document.querySelector("#text-table tbody tr select").options].map((o) => o.value).find((v) => v !== document.querySelector("#text-table tbody tr select").value));
    await page.selectOption("#text-table tbody tr:first-child select", other);
    await until(page, (c) => window.odori.text.elements[0].clip === c, "the first row taking the swapped clip", Number(other));
    const after = await state(page, () => ({ id: window.odori.text.clipId, pose: Array.from(window.odori.library.jointPositions(window.odori.text.clipId, 0.3)) }));
    assert.notEqual(Number(other), before.clip);
    const moved = after.pose.reduce((s, v, i) => s + Math.abs(v - before.pose[i]), 0);
    assert.ok(moved > 0.05, `the animation did not change after swapping the clip (pose change ${moved})`);
    assert.equal(await page.$eval("#text-table tbody tr:first-child select", (s) => s.value), other);

    // A WAV with known beats (100 BPM), then the corrections on it.
    const wav = clickTrackWav(100, 24);
    await page.setInputFiles("#song-input", { name: "clicks-100.wav", mimeType: "audio/wav", buffer: wav.bytes });
    await until(page, () => document.body.dataset.song === "clicks-100.wav", "the WAV song analysed", undefined, 60000);
    const g = await state(page, () => window.odori.song.grid);
    assert.ok(Math.abs(g.bpm - 100) < 1, `WAV at 100 BPM analysed as ${g.bpm}`);
    const hits = wav.beats.filter((b) => g.beatTimesSecs.some((t) => Math.abs(t - b) <= 0.07)).length;
    assert.ok(hits >= 0.9 * wav.beats.length, `only ${hits} of ${wav.beats.length} true beats found in the WAV`);

    // Tap: six taps on a steady beat 0.5 s apart, each timed from the first (as a person taps:
    // not waiting for the page, which re-renders the dance on each tap from the fourth),
    // clicked in the page on its own clock; the grid takes the tempo of the taps as they
    // actually landed.
    const taps = await page.evaluate(() => new Promise((done) => {
      const at = [];
      const t0 = performance.now();
      const tapOnce = () => {
        at.push(performance.now() / 1000);
        document.querySelector("#song-tap").click();
        if (at.length < 6) setTimeout(tapOnce, Math.max(0, t0 + 500 * at.length - performance.now()));
        else done(at);
      };
      tapOnce();
    }));
    const tapBpm = 60 / ((taps[taps.length - 1] - taps[0]) / (taps.length - 1));
    const gt = await state(page, () => window.odori.song.grid);
    assert.ok(Math.abs(gt.bpm - tapBpm) < 2, `tapped ${tapBpm.toFixed(1)} BPM, grid ${gt.bpm}`);
    await page.click("#song-reset");
    assert.ok(Math.abs((await state(page, () => window.odori.song.grid.bpm)) - g.bpm) < 1e-3, "reset after Tap");

    // Downbeat here: the playhead on a beat that is not a downbeat; a bar then starts there.
    const beatAt = g.beatTimesSecs.find((t) => t > 3 && !g.downbeatTimesSecs.some((d) => Math.abs(d - t) < 1e-3));
    await page.evaluate((t) => window.odori.songPlayer.seek(t), beatAt);
    await page.click("#song-downbeat");
    const gd = await state(page, () => window.odori.song.grid);
    assert.ok(gd.downbeatTimesSecs.some((d) => Math.abs(d - beatAt) < 0.011), `no bar starts at the playhead ${beatAt}: ${gd.downbeatTimesSecs.slice(0, 6)}`);
    await page.click("#song-reset");

    // Shift-click on the strip puts a bar start there; a plain click seeks.
    const strip = await page.$("#song canvas");
    await strip.scrollIntoViewIfNeeded(); // the song strip may sit below the fold at 1280×800
    const box = await strip.boundingBox();
    const secsAt = (x) => (x / box.width) * g.durationSecs;
    const beat2 = g.beatTimesSecs.find((t) => t > 6 && !g.downbeatTimesSecs.some((d) => Math.abs(d - t) < 1e-3));
    const x = (beat2 / g.durationSecs) * box.width;
    await page.keyboard.down("Shift");
    await page.mouse.click(box.x + x, box.y + box.height / 2);
    await page.keyboard.up("Shift");
    const gs = await state(page, () => window.odori.song.grid);
    const pxSecs = g.durationSecs / box.width;
    assert.ok(gs.downbeatTimesSecs.some((d) => Math.abs(d - secsAt(x)) <= pxSecs + 0.011), `shift-click at ${secsAt(x).toFixed(3)} s: bars start at ${gs.downbeatTimesSecs.slice(0, 8)}`);
    await page.click("#song-reset");
    await page.mouse.click(box.x + box.width / 2, box.y + box.height / 2);
    const pos = await state(page, () => window.odori.songPlayer.position());
    assert.ok(Math.abs(pos - secsAt(box.width / 2)) <= pxSecs + 0.05, `plain click seeks: ${pos} vs ${secsAt(box.width / 2)}`);

    // Metronome: on the beats, higher on downbeats, scheduled on the audio clock. The page's
    // OscillatorNode is wrapped to record each click (frequency, start on the context clock).
    await page.evaluate(() => {
      window.__clicks = [];
      const Base = OscillatorNode;
      window.OscillatorNode = class extends Base {
        constructor(ctx, opts) { super(ctx, opts); this.__f = opts?.frequency; }
        start(when) { window.__clicks.push({ f: this.__f, when, startTime: window.odori.songPlayer.startTime }); return super.start(when); }
      };
    });
    await page.check("#song-metronome");
    await page.evaluate(() => window.odori.songPlayer.seek(0));
    await page.click("#song-play");
    await until(page, () => window.__clicks.length >= 6, "six metronome clicks", undefined, 30000);
    await page.click("#song-play");
    const clicks = await state(page, () => window.__clicks);
    const gm = await state(page, () => window.odori.song.grid);
    for (const c of clicks.slice(0, 6)) {
      const t = c.when - c.startTime;
      const beat = gm.beatTimesSecs.reduce((a, b) => (Math.abs(b - t) < Math.abs(a - t) ? b : a));
      assert.ok(Math.abs(beat - t) < 0.002, `a click at ${t.toFixed(3)} s is not on a beat (nearest ${beat})`);
      const down = gm.downbeatTimesSecs.some((d) => Math.abs(d - beat) < 1e-3);
      assert.equal(c.f, down ? 1760 : 1175, `click at ${t.toFixed(3)} s: ${c.f} Hz (downbeat: ${down})`);
    }
    assert.ok(clicks.slice(0, 6).some((c) => c.f === 1760) && clicks.slice(0, 6).some((c) => c.f === 1175), "downbeats and other beats both clicked");

    // Ogg Vorbis (a real track): the page's bars equal the native analysis within one hop.
    await page.setInputFiles("#song-input", join(data, OGG));
    await until(page, (n) => document.body.dataset.song === n, "the Ogg song analysed", OGG.split("/").pop(), 90000);
    const go = await state(page, () => window.odori.song.grid);
    assert.equal(go.bars.length, native.grid.bars.length, "Ogg: bar count, page vs native");
    const worst = go.bars.reduce((w, b, i) => Math.max(w, Math.abs(b.startSecs - native.grid.bars[i].startSecs)), 0);
    assert.ok(worst <= native.hopSecs + 1e-4, `Ogg: a bar starts ${worst} s from the native result`);
    await page.screenshot({ path: join(artifacts, "claims-page.png") });
    assert.deepEqual(logs.filter((l) => l.startsWith("[pageerror]")), []);
  } catch (e) {
    await page.screenshot({ path: join(artifacts, "claims-failure.png") }).catch(() => {});
    console.log(logs.join("\n"));
    throw e;
  } finally {
    await browser.close();
  }
});
