// <odori-player> from the keyboard and under the browser's autoplay policy, and its
// `character` attribute, in headless Chromium (WebGL2):
// - keyboard only: Tab reaches the player and each control, each has a name; Space and Enter
//   toggle play on the player, on the Play button and on the 3D view; arrows (player and
//   slider) seek by 5 s, Home/End go to the ends; nothing needs a pointer;
// - `--autoplay-policy=user-gesture-required` (not even muted playback): an autoplaying player
//   with music starts muted, shows Unmute, and its clock still advances (its own, until the
//   song may play); Unmute (a click) brings the song in at that time. With Chromium's default
//   (`document-user-activation-required`) the song plays muted; with `no-user-gesture-required`
//   it plays with sound and no Unmute;
// - `character`: "stick", "builtin" (the engine's body) and a GLB character (Xbot, retargeted)
//   draw different pixels for the same pose; a file that is no character gives an `error`
//   event with the engine's kind and the dance goes on.
import { test, before, after } from "node:test";
import assert from "node:assert/strict";
import { readFileSync } from "node:fs";
import { join } from "node:path";
import { chromium } from "playwright-core";
import { startServer, data, artifacts, countAll, isBackground } from "./harness.mjs";

let server;
before(async () => { server = await startServer(); });
after(() => server && server.stop());

const SONG = join(data, "music", "Kevin_MacLeod_-_Vibe_Ace.hq.ogg");

/** Chromium on WebGL2 (SwiftShader) with the given autoplay policy. */
async function launchWith(policy) {
  const browser = await chromium.launch({
    executablePath: "/usr/bin/chromium",
    headless: true,
    args: ["--headless", "--no-sandbox", "--disable-background-networking", "--disable-component-update", "--disable-sync", "--no-first-run", "--disable-dev-shm-usage", `--autoplay-policy=${policy}`],
  });
  const page = await browser.newPage({ viewport: { width: 1000, height: 700 } });
  const logs = [];
  page.on("console", (m) => logs.push(`[${m.type()}] ${m.text()}`));
  page.on("pageerror", (e) => logs.push(`[pageerror] ${e.message}`));
  await page.addInitScript(() => {
    customElements.whenDefined("odori-player").then(() => { customElements.get("odori-player").backend = "webgl2"; });
  });
  return { browser, page, logs };
}

/** Serves a test page and media under /examples/t/ (byte ranges for the song, so it can seek). */
async function route(page, html) {
  const files = {
    "page.html": ["text/html", Buffer.from(html)],
    "song.ogg": ["audio/ogg", readFileSync(SONG)],
    "xbot.glb": ["model/gltf-binary", readFileSync(join(data, "gltf", "Xbot.glb"))],
    "text.glb": ["model/gltf-binary", Buffer.from("not a glb at all")],
  };
  await page.route("**/examples/t/*", (r) => {
    const name = new URL(r.request().url()).pathname.split("/").pop();
    const f = files[name];
    if (!f) return r.fulfill({ status: 404, body: "not found" });
    const m = /bytes=(\d+)-(\d*)/.exec(r.request().headers().range || "");
    if (!m) return r.fulfill({ status: 200, contentType: f[0], headers: { "accept-ranges": "bytes" }, body: f[1] });
    const start = Number(m[1]), end = m[2] ? Math.min(Number(m[2]), f[1].length - 1) : f[1].length - 1;
    return r.fulfill({ status: 206, contentType: f[0], headers: { "accept-ranges": "bytes", "content-range": `bytes ${start}-${end}/${f[1].length}` }, body: f[1].subarray(start, end + 1) });
  });
}

const page = (players) => `<!doctype html><meta charset="utf-8"><body style="margin:0;display:flex;gap:8px">
<button id="before">before</button>
${players}
<script>
  for (const p of document.querySelectorAll("odori-player")) p.addEventListener("error", (e) => { p.dataset.error = JSON.stringify(e.detail); });
</script>
<script type="module" src="/pkg/player/odori-player.js"></script>`;

/** What has the keyboard focus: the element (and inside a player, the control) and its name. */
const focused = (p) => p.evaluate(() => {
  const a = document.activeElement;
  const inner = a?.shadowRoot?.activeElement;
  const el = inner || a;
  return { host: a?.tagName.toLowerCase(), id: a?.id, inner: inner ? (inner.className || inner.tagName.toLowerCase()) : null, name: el?.getAttribute("aria-label") || el?.textContent || "" };
});

test("keyboard only: every control is reachable and named; Space/Enter play and pause; arrows seek", async () => {
  const { browser, page: pg, logs } = await launchWith("no-user-gesture-required");
  try {
    await route(pg, page(`<odori-player id="p" music="song.ogg" camera-controls loading="eager" style="width:400px;height:400px"></odori-player>`));
    await pg.goto(server.url + "examples/t/page.html");
    await pg.waitForFunction(() => document.getElementById("p").lastFrame && document.getElementById("p").audioElement?.readyState >= 1, null, { timeout: 60000 });
    const st = () => pg.evaluate(() => { const p = document.getElementById("p"); return { paused: p.paused, t: p.currentTime, audioPaused: p.audioElement.paused, label: p.shadowRoot.querySelector(".play").getAttribute("aria-label") }; });

    // Tab order: the page's button, the player, the 3D view, Play, the slider.
    await pg.focus("#before");
    const order = [];
    for (let i = 0; i < 4; i++) { await pg.keyboard.press("Tab"); order.push(await focused(pg)); }
    assert.deepEqual(order.map((f) => [f.host, f.inner]), [["odori-player", null], ["odori-player", "canvas"], ["odori-player", "play"], ["odori-player", "seek"]], JSON.stringify(order));
    for (const f of order) assert.ok(f.name.trim().length >= 4, `focus stop without a name: ${JSON.stringify(f)}`);
    assert.equal(await pg.evaluate(() => document.getElementById("p").getAttribute("aria-label")), "Dance player");

    // On the player itself: Space plays, Enter pauses.
    for (let i = 0; i < 3; i++) await pg.keyboard.press("Shift+Tab");
    assert.deepEqual(Object.values(await focused(pg)).slice(0, 3), ["odori-player", "p", null]);
    await pg.keyboard.press("Space");
    await pg.waitForFunction(() => document.getElementById("p").audioElement.currentTime > 0.3, null, { timeout: 20000 });
    let s = await st();
    assert.deepEqual([s.paused, s.audioPaused, s.label], [false, false, "Pause"]);
    await pg.keyboard.press("Enter");
    s = await st();
    assert.deepEqual([s.paused, s.audioPaused, s.label], [true, true, "Play"]);

    // Arrows seek by 5 s on the player; Home goes to the start.
    const t0 = s.t;
    await pg.keyboard.press("ArrowRight");
    await pg.keyboard.press("ArrowRight");
    s = await st();
    assert.ok(Math.abs(s.t - (t0 + 10)) < 0.05, `two → from ${t0} s went to ${s.t} s`);
    await pg.keyboard.press("ArrowLeft");
    s = await st();
    assert.ok(Math.abs(s.t - (t0 + 5)) < 0.05, `← went to ${s.t} s`);
    await pg.keyboard.press("Home");
    assert.equal((await st()).t, 0);
    // The figure follows the seek (a frame is drawn at the new time).
    await pg.keyboard.press("ArrowRight");
    await pg.waitForFunction(() => Math.abs(document.getElementById("p").lastFrame.songTimeSecs - 5) < 0.05, null, { timeout: 5000 });

    // The 3D view: arrows turn the camera (pixels change) and do not seek; Space plays and pauses.
    await pg.keyboard.press("Tab");
    assert.equal((await focused(pg)).inner, "canvas");
    const a = await (await pg.$("#p")).screenshot();
    for (let i = 0; i < 6; i++) await pg.keyboard.press("ArrowLeft");
    await pg.waitForTimeout(100);
    const b = await (await pg.$("#p")).screenshot();
    assert.notDeepEqual(a, b, "arrows on the 3D view turn the camera");
    assert.ok(Math.abs((await st()).t - 5) < 0.05, "arrows on the 3D view do not seek");
    await pg.keyboard.press("Space");
    await pg.waitForFunction(() => !document.getElementById("p").audioElement.paused);
    await pg.keyboard.press("Space");
    await pg.waitForFunction(() => document.getElementById("p").audioElement.paused);

    // The Play button: Enter and Space toggle (a button's own keys).
    await pg.keyboard.press("Tab");
    assert.equal((await focused(pg)).inner, "play");
    await pg.keyboard.press("Enter");
    await pg.waitForFunction(() => !document.getElementById("p").audioElement.paused);
    await pg.keyboard.press("Space");
    await pg.waitForFunction(() => document.getElementById("p").audioElement.paused);

    // The slider: arrows seek by 5 s (not its 0.01 s step); End, Home; its value is read out as time.
    await pg.keyboard.press("Tab");
    assert.equal((await focused(pg)).inner, "seek");
    const before = (await st()).t;
    await pg.keyboard.press("ArrowRight");
    s = await st();
    assert.ok(Math.abs(s.t - (before + 5)) < 0.05, `slider → from ${before} s went to ${s.t} s`);
    await pg.keyboard.press("End");
    s = await st();
    const dur = await pg.evaluate(() => document.getElementById("p").duration);
    assert.ok(Math.abs(s.t - dur) < 0.05, `End went to ${s.t} s of ${dur} s`);
    await pg.keyboard.press("Home");
    assert.equal((await st()).t, 0);
    const valuetext = await pg.evaluate(() => document.getElementById("p").shadowRoot.querySelector(".seek").getAttribute("aria-valuetext"));
    assert.match(valuetext, /^0:00 of \d+:\d\d$/);
    assert.ok(!logs.some((l) => l.includes("[pageerror]")), logs.join("\n"));
  } finally {
    await browser.close();
  }
});

/**
 * The page reports the player's state itself (console), twice 0.6 s apart once the song has
 * played 0.5 s: the test must not evaluate script in the page before then, because Playwright
 * evaluates with a user gesture, which would lift the autoplay policy under test.
 */
const REPORT = `<script>
  const p = document.getElementById("p");
  const state = () => { const u = p.shadowRoot.querySelector(".unmute"); return { error: p.dataset.error, paused: p.paused, muted: p.audioElement.muted, audioPaused: p.audioElement.paused,
    unmuteShown: !u.hidden && getComputedStyle(u).display !== "none", song: p.lastFrame.songTimeSecs, clock: p.currentTime, audio: p.audioElement.currentTime, activated: navigator.userActivation.hasBeenActive }; };
  const poll = setInterval(() => {
    if (p.dataset.error) { clearInterval(poll); console.log("REPORT " + JSON.stringify([{ error: p.dataset.error }])); return; }
    if (!(p.lastFrame && p.audioElement && p.currentTime > 0.5)) return;
    clearInterval(poll);
    const first = state();
    setTimeout(() => console.log("REPORT " + JSON.stringify([first, state()])), 600);
  }, 50);
</script>`;

// Chromium's policies: the strictest blocks all playback; its default (the one real visitors
// have) allows muted autoplay only for <video>, so an <audio> song cannot start either: in both
// the figure keeps time itself until Unmute. The last allows sound.
const POLICIES = [
  { policy: "user-gesture-required", muted: true, audioPlays: false, says: "starts muted (the song cannot play at all: the figure keeps time), shows Unmute, the clock advances; Unmute brings the song in at the figure's time" },
  { policy: "document-user-activation-required", muted: true, audioPlays: false, says: "(Chromium's default: no muted autoplay for audio) the same" },
  { policy: "no-user-gesture-required", muted: false, audioPlays: true, says: "plays with sound, no Unmute" },
];
for (const { policy, muted, audioPlays, says } of POLICIES) {
  test(`autoplay with --autoplay-policy=${policy}: ${says}`, async () => {
    const { browser, page: pg, logs } = await launchWith(policy);
    try {
      await route(pg, page(`<odori-player id="p" music="song.ogg" autoplay style="width:400px;height:400px"></odori-player>`) + REPORT);
      const reported = pg.waitForEvent("console", { predicate: (m) => m.text().startsWith("REPORT "), timeout: 60000 });
      await pg.goto(server.url + "examples/t/page.html");
      const [r1, r2] = JSON.parse((await reported.catch(async (e) => {
        const now = await pg.evaluate(() => { const p = document.getElementById("p"); return { state: p.state, paused: p.paused, audio: p.audioElement && { paused: p.audioElement.paused, muted: p.audioElement.muted, t: p.audioElement.currentTime, ready: p.audioElement.readyState }, drawn: !!p.lastFrame }; });
        throw new Error(`${e.message}\nplayer: ${JSON.stringify(now)}\n${logs.join("\n")}`);
      })).text().slice(7));
      assert.equal(r1.error, undefined);
      assert.equal(r1.activated, false, "no user gesture reached the page before autoplay");
      console.log(`${policy}: ${JSON.stringify(r1)} → ${JSON.stringify(r2)}`);
      assert.deepEqual([r1.paused, r1.audioPaused, r1.muted, r1.unmuteShown], [false, !audioPlays, muted, muted], JSON.stringify(r1));
      assert.ok(r2.clock > r1.clock + 0.3 && r2.song > r1.song + 0.3, `the clock advances (${r1.clock} → ${r2.clock} s; figure ${r1.song} → ${r2.song} s)`);
      if (audioPlays) assert.ok(r2.audio > r1.audio + 0.3, "the song's own clock advances");
      else assert.equal(r2.audio, 0, "the song could not start");
      assert.deepEqual([r2.muted, r2.unmuteShown], [muted, muted], JSON.stringify(r2));
      if (muted) {
        // A click is a user gesture: sound comes on, playing goes on.
        await pg.click("#p >> .unmute");
        const read = () => pg.evaluate(() => { const p = document.getElementById("p"); const u = p.shadowRoot.querySelector(".unmute"); return { muted: p.audioElement.muted, unmuteShown: !u.hidden, audioPaused: p.audioElement.paused, audio: p.audioElement.currentTime, clock: p.currentTime, paused: p.paused }; });
        await pg.waitForFunction(() => !document.getElementById("p").audioElement.paused, null, { timeout: 10000 });
        const r3 = await read();
        assert.deepEqual([r3.muted, r3.unmuteShown, r3.audioPaused, r3.paused], [false, false, false, false], JSON.stringify(r3));
        // The song came in where the figure was (the clock did not jump back to 0).
        assert.ok(r3.audio > r2.clock - 0.1, `the song starts at the figure's time (${r3.audio} s; the figure was at ${r2.clock} s)`);
        await pg.waitForTimeout(300);
        const r4 = await read();
        assert.ok(r4.audio > r3.audio && r4.clock === r4.audio, "playing with sound, the song's clock drives the figure again");
      }
      assert.ok(!logs.some((l) => l.includes("[pageerror]")), logs.join("\n"));
    } finally {
      await browser.close();
    }
  });
}

test("character: stick, the built-in body and a GLB character (Xbot) draw differently; a file that is no character is reported", async () => {
  const { browser, page: pg, logs } = await launchWith("no-user-gesture-required");
  try {
    const players = ["stick", "builtin", "xbot.glb", "text.glb"].map((c, i) => `<odori-player id="c${i}" character="${c}" loading="eager" style="width:220px;height:300px"></odori-player>`).join("\n");
    await route(pg, page(players));
    await pg.goto(server.url + "examples/t/page.html");
    await pg.waitForFunction(() => [0, 1, 2, 3].every((i) => document.getElementById(`c${i}`).lastFrame), null, { timeout: 90000 }).catch(async (e) => {
      throw new Error(`${await pg.evaluate(() => JSON.stringify([0, 1, 2, 3].map((i) => [document.getElementById(`c${i}`).state, document.getElementById(`c${i}`).dataset.error])))}\n${logs.join("\n")}\n${e.message}`);
    });
    // The same instant of the same built-in routine on each.
    await pg.evaluate(() => { for (let i = 0; i < 4; i++) document.getElementById(`c${i}`).currentTime = 1.0; });
    await pg.waitForTimeout(200);
    const shots = [];
    for (let i = 0; i < 4; i++) {
      const png = await (await pg.$(`#c${i}`)).screenshot({ path: join(artifacts, `player-character-${i}.png`) });
      shots.push(await pg.evaluate(async (b64) => {
        const bmp = await createImageBitmap(new Blob([Uint8Array.from(atob(b64), (ch) => ch.charCodeAt(0))]));
        const cv = new OffscreenCanvas(bmp.width, bmp.height);
        const g = cv.getContext("2d");
        g.drawImage(bmp, 0, 0);
        return Array.from(g.getImageData(0, 0, bmp.width, bmp.height - 40).data);
      }, png.toString("base64")));
    }
    const figure = (px) => px.length / 4 - countAll({ rgba: px }, isBackground);
    const diff = (a, b) => { let n = 0; for (let i = 0; i < a.length; i += 4) if (Math.abs(a[i] - b[i]) + Math.abs(a[i + 1] - b[i + 1]) + Math.abs(a[i + 2] - b[i + 2]) > 60) n++; return n; };
    const sizes = shots.map(figure);
    const d = { stickBody: diff(shots[0], shots[1]), stickXbot: diff(shots[0], shots[2]), bodyXbot: diff(shots[1], shots[2]), stickBad: diff(shots[0], shots[3]) };
    console.log(`character pixels (not background): stick ${sizes[0]}, builtin ${sizes[1]}, xbot ${sizes[2]}, bad file ${sizes[3]}; pixels that differ: ${JSON.stringify(d)}`);
    assert.ok(sizes[0] > 300, "the stick figure is drawn");
    assert.ok(sizes[1] > sizes[0] * 1.3, "the built-in body covers more of the view than the stick figure");
    assert.ok(sizes[2] > sizes[0] * 1.3, "the Xbot covers more of the view than the stick figure");
    assert.ok(d.stickBody > 500 && d.stickXbot > 500 && d.bodyXbot > 300, `characters look different: ${JSON.stringify(d)}`);
    // Not a character: the error names the file and the engine's kind; the dance plays on as a stick figure.
    const bad = await pg.evaluate(() => { const p = document.getElementById("c3"); return { error: JSON.parse(p.dataset.error || "null"), state: p.state, kinds: null }; });
    assert.equal(bad.state, "ready");
    assert.ok(bad.error && bad.error.message.includes("text.glb"), JSON.stringify(bad));
    assert.ok(["gltf", "unknown-format", "character-no-skin"].includes(bad.error.kind), JSON.stringify(bad));
    assert.ok(await pg.evaluate(() => document.getElementById("c3").lastFrame !== null), "the player whose character failed still draws");
    for (let i = 0; i < 3; i++) assert.equal(await pg.evaluate((i) => document.getElementById(`c${i}`).dataset.error, i), undefined);
    assert.ok(!logs.some((l) => l.includes("[pageerror]")), logs.join("\n"));
  } finally {
    await browser.close();
  }
});
