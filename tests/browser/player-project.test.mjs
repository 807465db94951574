// <odori-player src="x.odori">: a project made through the API (a song, a pinned move, the
// rest generated), saved to .odori bytes, played by the element in a fresh page. The player
// draws that dance — the same joint positions as the project renders where it was made —
// and the project's own song is the music clock (the demo song synthesised again, or the song
// file the project keeps). A bad .odori gives an `error` event with the engine's typed kind.
import { test, before, after } from "node:test";
import assert from "node:assert/strict";
import { readFileSync } from "node:fs";
import { join } from "node:path";
import { startServer, launch, data, artifacts, countAll, isOrange, isBackground, isWarmFigure } from "./harness.mjs";

/** The built-in body's clay (linear 0.72, 0.45, 0.32: blue well above the sticks' orange), whatever the shading. */
const isClay = ([r, g, b]) => r > 80 && r > g && g > b && b > 0.5 * r && r - b > 20;

let server;
before(async () => { server = await startServer(); });
after(() => server && server.stop());

/** Serves `files` ({ name: bytes | string }) under /examples/t/ (same origin as the engine). */
async function routeFiles(page, files) {
  await page.route("**/examples/t/*", (route) => {
    const name = decodeURIComponent(new URL(route.request().url()).pathname.split("/").pop());
    if (!(name in files)) return route.fulfill({ status: 404, body: "not found" });
    const body = files[name];
    const contentType = name.endsWith(".html") ? "text/html" : name.endsWith(".ogg") ? "audio/ogg" : "application/octet-stream";
    return route.fulfill({ status: 200, contentType, body: typeof body === "string" ? body : Buffer.from(body) });
  });
}

/**
 * Makes a project in the page with the full engine: the song (`songFile` bytes, or the demo
 * song), a move pinned to bar 2, the rest generated. Returns the .odori bytes, the dance's
 * joint positions at `times` (as the project renders it), the song's duration and bar count.
 */
async function makeProject(page, songFile, characterFile, times) {
  return page.evaluate(async ({ songB64, characterB64, times }) => {
    const engine = await import("/pkg/odori.js");
    await engine.default();
    const { rmsEnvelope } = await import("/audio/rms.js");
    const { bufferFromSamples, decodeSong } = await import("/audio/song-player.js");
    const p = new engine.Project();
    let buffer, env;
    if (songB64) {
      const bytes = Uint8Array.from(atob(songB64), (c) => c.charCodeAt(0));
      buffer = await decodeSong(bytes, "song.ogg");
      env = await rmsEnvelope(buffer, engine.envelopeDefinition());
      p.setSong("song.ogg", bytes, env.hopSecs, env.bands, undefined);
    } else {
      const demo = engine.DemoSong.render(44100);
      buffer = bufferFromSamples(demo.samples, demo.sampleRateHz);
      demo.free();
      env = await rmsEnvelope(buffer, engine.envelopeDefinition());
      p.setSong("Demo song (built-in)", undefined, env.hopSecs, env.bands, undefined);
    }
    p.setName("Test dance");
    if (characterB64) {
      // A character file: its clips join the moves (cut at their beats) and it wears the dance.
      const r = p.addSource("Xbot.glb", Uint8Array.from(atob(characterB64), (c) => c.charCodeAt(0)), undefined);
      p.setCharacter({ source: r.id, clip: 0 });
    }
    const bars = p.grid().bars.length;
    const keys = p.candidates(2);
    p.set(2, keys[0]);
    p.generate();
    const lib = new engine.Library();
    const id = p.renderDance(lib, undefined);
    const poses = times.map((t) => Array.from(lib.jointPositions(id, t)));
    const clip = lib.clip(id);
    const saved = p.save();
    // The same project with no dance (a bad source for the player: nothing to play).
    const empty = new engine.Project();
    empty.setSong("Demo song (built-in)", undefined, env.hopSecs, env.bands, undefined);
    const noDance = empty.save();
    // What the engine itself says about broken files: the kinds the player must report.
    const kindOf = (bytes) => { try { engine.Project.open(bytes); return "opened"; } catch (e) { return e.kind; } };
    const cut = saved.slice(0, saved.length >> 1);
    const junk = new TextEncoder().encode("this is not a project, just some text in a file named .odori");
    let b64 = "";
    for (let i = 0; i < saved.length; i += 0x8000) b64 += String.fromCharCode.apply(null, saved.subarray(i, i + 0x8000));
    let b64n = "";
    for (let i = 0; i < noDance.length; i += 0x8000) b64n += String.fromCharCode.apply(null, noDance.subarray(i, i + 0x8000));
    return {
      odori: btoa(b64), noDance: btoa(b64n), cutKind: kindOf(cut), junkKind: kindOf(junk), emptyKind: kindOf(new Uint8Array(0)),
      poses, bars, songSecs: buffer.duration, clip: { frames: clip.frames, durationSecs: clip.durationSecs, fps: clip.fps },
      kinds: engine.errorKinds(),
    };
  }, { songB64: songFile ? readFileSync(songFile).toString("base64") : null, characterB64: characterFile ? readFileSync(characterFile).toString("base64") : null, times });
}

const PAGE = (players) => `<!doctype html><meta charset="utf-8"><body style="margin:0">
${players}
<script>
  for (const p of document.querySelectorAll("odori-player")) {
    p.addEventListener("error", (e) => { p.dataset.error = JSON.stringify(e.detail); });
    p.addEventListener("load", (e) => { p.dataset.loaded = JSON.stringify(e.detail.project || null); });
  }
</script>
<script type="module" src="/pkg/player/odori-player.js"></script>`;

const CASES = [
  { backend: "webgl2", song: null, character: null, label: "the demo song" },
  { backend: "webgpu", song: join(data, "music", "Kevin_MacLeod_-_Vibe_Ace.hq.ogg"), character: join(data, "gltf", "Xbot.glb"), label: "a song file (Vibe Ace), on the Xbot character" },
];

for (const c of CASES) {
  test(`a .odori project on ${c.label} plays in <odori-player> (${c.backend}): same dance, its own song as the clock`, async () => {
    const { browser, page, logs } = await launch(c.backend);
    try {
      await routeFiles(page, { "blank.html": "<!doctype html><title>maker</title>" });
      await page.goto(server.url + "examples/t/blank.html");
      const times = [0.5, 3.1, 6.2, 9.9];
      const made = await makeProject(page, c.song, c.character, times);
      assert.ok(made.bars >= 4, `the song has ${made.bars} bars`);
      await page.close();

      // A fresh page (its own browser context: nothing shared with the maker) plays the file.
      const ctx = await browser.newContext({ viewport: { width: 800, height: 600 } });
      const player = await ctx.newPage();
      player.on("console", (m) => logs.push(`[${m.type()}] ${m.text()}`));
      player.on("pageerror", (e) => logs.push(`[pageerror] ${e.message}`));
      await player.addInitScript((b) => {
        customElements.whenDefined("odori-player").then(() => { customElements.get("odori-player").backend = b; });
      }, c.backend);
      await routeFiles(player, {
        "play.html": PAGE(`<odori-player id="p" src="dance.odori" autoplay style="width:480px;height:480px"></odori-player>`),
        "dance.odori": Buffer.from(made.odori, "base64"),
      });
      await player.goto(server.url + "examples/t/play.html");
      await player.waitForFunction(() => { const p = document.getElementById("p"); return p.dataset.error || (p.lastFrame && p.audioElement && p.audioElement.currentTime > 0.8); }, null, { timeout: 120000 }).catch(async (e) => {
        throw new Error(`the player did not play: ${await player.evaluate(() => JSON.stringify({ state: document.getElementById("p").state, error: document.getElementById("p").dataset.error }))}\n${logs.join("\n")}\n${e.message}`);
      });
      const r = await player.evaluate((times) => {
        const p = document.getElementById("p");
        return {
          error: p.dataset.error, loaded: p.dataset.loaded, project: p.project, gpu: p.gpuContext,
          audioSrc: p.audioElement.src, audioDuration: p.audioElement.duration, muted: p.audioElement.muted,
          clip: { frames: p.clip.frames, durationSecs: p.clip.durationSecs, fps: p.clip.fps },
          poses: times.map((t) => Array.from(p.jointPositions(t))),
        };
      }, times);
      assert.equal(r.error, undefined, `error event: ${r.error}`);
      assert.equal(r.gpu, c.backend);
      // No character chosen: the built-in body, as the app draws such a project (pkg/README.md).
      assert.deepEqual(JSON.parse(r.loaded), { name: "Test dance", song: c.song ? "song.ogg" : "Demo song (built-in)", character: c.character ? "Xbot.glb" : null, body: c.character ? "character" : "builtin" });
      assert.deepEqual(r.clip, made.clip, "the player renders the same dance clip");
      for (let i = 0; i < times.length; i++) {
        assert.equal(r.poses[i].length, made.poses[i].length);
        const worst = Math.max(...r.poses[i].map((v, j) => Math.abs(v - made.poses[i][j])));
        assert.ok(worst < 1e-5, `at ${times[i]} s the player's pose differs from the project's by ${worst} m`);
      }
      // The music is the project's own song: a blob of the saved bytes (or the demo song made again).
      assert.match(r.audioSrc, /^blob:/);
      assert.ok(Math.abs(r.audioDuration - made.songSecs) < 0.1, `the player's song lasts ${r.audioDuration} s, the project's ${made.songSecs} s`);
      assert.equal(r.muted, false, "autoplay with sound is allowed in this browser: not muted");

      // Its clock drives the figure: every frame, figure time = song time (the dance is on the song's time line).
      const sync = await player.evaluate(() => new Promise((resolve) => {
        const p = document.getElementById("p");
        const out = [];
        const step = () => {
          out.push({ song: p.lastFrame.songTimeSecs, clip: p.lastFrame.clipTimeSecs, audio: p.audioElement.currentTime, ms: performance.now() });
          if (out.length < 40) requestAnimationFrame(step); else resolve(out);
        };
        requestAnimationFrame(step);
      }));
      // One frame: the display's, or the player's drawing interval when longer (at most the
      // clip's frame rate, and 30 a second on this machine's software adapter).
      const drawFps = await player.evaluate(() => { const p = document.getElementById("p"); return Math.min(p.maxFps, p.clip.fps); });
      const frameSecs = Math.max(1 / 60, sync.slice(1).map((s, i) => (s.ms - sync[i].ms) / 1000).sort((a, b) => a - b)[sync.length >> 1], 1 / drawFps);
      const gaps = sync.map((s) => Math.abs(s.song - s.audio)).sort((a, b) => a - b);
      console.log(`${c.backend}, ${c.label}: ${made.bars} bars, dance ${made.clip.durationSecs.toFixed(1)} s, song ${made.songSecs.toFixed(1)} s; figure vs audio: median ${(gaps[gaps.length >> 1] * 1000).toFixed(1)} ms, frame ${(frameSecs * 1000).toFixed(1)} ms`);
      assert.ok(sync.at(-1).audio - sync[0].audio > 0.2, "the song plays");
      assert.ok(gaps[Math.floor(gaps.length * 0.9)] <= frameSecs, `figure time strays from the song's by more than a frame (${gaps.at(-1)} s)`);
      for (const s of sync) assert.ok(Math.abs(s.clip - Math.min(s.song, made.clip.durationSecs)) < 1e-3, "clip time is song time");

      // Real pixels: a figure is drawn, and it moves.
      const shot = async (name) => {
        const png = await (await player.$("#p")).screenshot({ path: join(artifacts, name) });
        return player.evaluate(async (b64) => {
          const bmp = await createImageBitmap(new Blob([Uint8Array.from(atob(b64), (ch) => ch.charCodeAt(0))]));
          const cv = new OffscreenCanvas(bmp.width, bmp.height);
          const g = cv.getContext("2d");
          g.drawImage(bmp, 0, 0);
          return Array.from(g.getImageData(0, 0, bmp.width, bmp.height - 40).data);
        }, png.toString("base64"));
      };
      const a = await shot(`player-project-${c.backend}-a.png`);
      await player.waitForTimeout(500);
      const b = await shot(`player-project-${c.backend}-b.png`);
      const img = (px) => ({ rgba: px });
      // The built-in body's clay (not the stick figure's orange); with a character, whatever is
      // not the dark background.
      const coloured = c.character ? a.length / 4 - countAll(img(a), isBackground) : countAll(img(a), isClay);
      let moved = 0;
      for (let i = 0; i < a.length; i += 4) if (Math.abs(a[i] - b[i]) + Math.abs(a[i + 1] - b[i + 1]) + Math.abs(a[i + 2] - b[i + 2]) > 60) moved++;
      assert.ok(coloured > 300, `no figure drawn (${coloured} figure pixels)`);
      assert.ok(moved > 100, `the figure did not move (${moved} pixels changed)`);
      if (!c.character) {
        // The same pose, paused, on the body and then as stick figures (character="stick", the
        // control): the body is clay and covers far more of the view; the sticks are orange.
        await player.evaluate(() => { const p = document.getElementById("p"); p.pause(); p.currentTime = 3.1; });
        const body = await shot(`player-project-${c.backend}-body.png`);
        const drawn = await player.evaluate(() => { const p = document.getElementById("p"); const n = p.framesDrawn; p.setAttribute("character", "stick"); return n; });
        await player.waitForFunction((n) => document.getElementById("p").framesDrawn > n, drawn, { timeout: 30000 });
        const sticks = await shot(`player-project-${c.backend}-sticks.png`);
        const [bodyClay, stickClay, bodyWarm, stickWarm, stickOrange] = [countAll(img(body), isClay), countAll(img(sticks), isClay), countAll(img(body), isWarmFigure), countAll(img(sticks), isWarmFigure), countAll(img(sticks), isOrange)];
        console.log(`${c.backend}: no character chosen: the body ${bodyClay} clay / ${bodyWarm} warm px; as sticks ${stickClay} clay / ${stickWarm} warm / ${stickOrange} orange px`);
        assert.ok(bodyClay > 300 && bodyClay > 5 * Math.max(1, stickClay), `the project plays on the built-in body (${bodyClay} clay px; sticks ${stickClay})`);
        assert.ok(bodyWarm > 2 * stickWarm, `the body (${bodyWarm} px) is drawn, not a stick figure (${stickWarm} px)`);
        assert.ok(stickOrange > 100, "the control draws orange sticks");
        await player.evaluate(() => document.getElementById("p").setAttribute("character", "auto"));
      }

      // Bad .odori files: each player reports the kind the engine gives for the same bytes.
      const bad = await ctx.newPage();
      await routeFiles(bad, {
        "bad.html": PAGE(["empty", "junk", "cut", "nodance"].map((n) => `<odori-player id="${n}" src="${n}.odori" style="width:100px;height:100px"></odori-player>`).join("\n")),
        "empty.odori": new Uint8Array(0),
        "junk.odori": new TextEncoder().encode("this is not a project, just some text in a file named .odori"),
        "cut.odori": Buffer.from(made.odori, "base64").subarray(0, Buffer.from(made.odori, "base64").length >> 1),
        "nodance.odori": Buffer.from(made.noDance, "base64"),
      });
      await bad.goto(server.url + "examples/t/bad.html");
      await bad.waitForFunction(() => [...document.querySelectorAll("odori-player")].every((p) => p.dataset.error), null, { timeout: 60000 });
      const errors = await bad.evaluate(() => Object.fromEntries([...document.querySelectorAll("odori-player")].map((p) => [p.id, { ...JSON.parse(p.dataset.error), state: p.state, message: p.shadowRoot.querySelector(".message").textContent }])));
      const expected = { empty: made.emptyKind, junk: made.junkKind, cut: made.cutKind, nodance: "choreo" };
      for (const [id, kind] of Object.entries(expected)) {
        assert.equal(errors[id].kind, kind, `${id}.odori: ${JSON.stringify(errors[id])}`);
        assert.ok(made.kinds.includes(kind), `${kind} is one of errorKinds()`);
        assert.equal(errors[id].state, "error");
        assert.equal(errors[id].file, `${id}.odori`);
        assert.ok(errors[id].message.length > 10, `the player shows a message for ${id}.odori`);
      }
      assert.deepEqual([made.emptyKind, made.junkKind], ["empty", "not-odori"]);
      assert.ok(["truncated", "corrupt"].includes(made.cutKind), made.cutKind);
      console.log(`bad .odori: ${Object.entries(errors).map(([id, e]) => `${id} → ${e.kind} ("${e.message}")`).join("; ")}`);
      assert.ok(!logs.some((l) => l.includes("[pageerror]")), logs.join("\n"));
    } finally {
      await browser.close();
    }
  });
}
