// <odori-player>: a dance on any web page, in one tag.
//
// A small custom element (Rust cannot subclass HTMLElement) over the player build of the
// engine (odori_player.js: Library + Viewer, no authoring). Attribute names follow
// <model-viewer> where they mean the same: src, poster, loading, autoplay, camera-controls,
// animation-name; plus music (an audio URL, or "#id" of an <audio> on the page: its clock
// drives the figure), loop, character ("auto" | "stick" | "builtin" | a character's URL), backend ("auto" | "webgpu" |
// "webgl2") and max-fps (draws per second while playing: a number, or "none"). Methods play(), pause(); properties currentTime, duration, paused; events load,
// progress, error, ended.
//
// `src` is a motion file (GLB/glTF with animation, BVH) or a `.odori` project. A project's
// dance is rendered from its moves by the full engine (pkg/odori.js), loaded only for such a
// source: the choreography (built-in moves, cutting the project's own files into moves) is
// what the player build leaves out to stay small, and a baked copy of the dance in the file
// would be a second truth to keep in step. The project's own song becomes the music clock.
//
// Why it is shaped this way:
// - The engine is fetched only when the element comes near the viewport (IntersectionObserver),
//   or at once with loading="eager"; every player on a page shares the one engine module.
// - Browsers allow a handful of live GPU contexts per page (Chromium: 16 WebGL). A player that
//   leaves the viewport pauses, destroys its device, loses its WebGL context and drops its
//   canvas; it takes a fresh one when it comes back. Many players on one page never run out.
// - With music, the audio element's clock is the only clock: each frame reads
//   audio.currentTime and draws that instant of the dance, so figure and song cannot drift.
// - Where neither WebGPU nor WebGL2 exists the poster stays, with a message.
// - Autoplay with sound is often blocked: the player then starts muted and shows "Unmute".
// - Drawing costs only what can be seen: a paused player draws nothing, a playing one every
//   display frame, but on a software adapter (no GPU: the browser draws with the
//   CPU, whatever else the page runs) at most `OdoriPlayer.softwareMaxFps` (30) a second and
//   no faster than its clip's frames, unless `max-fps` says otherwise.

let enginePromise = null;
let fullEnginePromise = null;
let graphicsProbe = null;

/** Loads (once per page) the player build of the engine. */
function loadEngine() {
  // A literal specifier, so bundlers (esbuild, vite) follow it into the player build.
  enginePromise ??= import("./odori_player.js").then(async (engine) => {
    const wasm = OdoriPlayer.wasmUrl;
    await engine.default(wasm ? { module_or_path: wasm } : undefined);
    return engine;
  });
  return enginePromise;
}

/**
 * Loads (once per page, and only for a `.odori` source) the full engine: a project's dance is
 * made of the engine's built-in moves and of moves cut from the project's own files, so
 * rendering it needs the choreography the player build leaves out. The specifier is computed,
 * not literal, so a bundler does not pull the full engine into a player bundle: when it moved
 * the files, say where they are with `OdoriPlayer.fullEngineUrl` / `fullEngineWasmUrl`.
 */
function loadFullEngine() {
  fullEnginePromise ??= (async () => {
    // Not a literal in new URL(): vite would copy the module as an asset into every bundle.
    const beside = "../odori.js";
    const url = OdoriPlayer.fullEngineUrl ?? new URL(beside, import.meta.url).href;
    const engine = await import(/* @vite-ignore */ String(url));
    const wasm = OdoriPlayer.fullEngineWasmUrl;
    await engine.default(wasm ? { module_or_path: wasm } : undefined);
    return engine;
  })();
  fullEnginePromise.catch(() => { fullEnginePromise = null; });
  return fullEnginePromise;
}

/** A `.odori` project: by its name, or by its bytes (a zip whose first entry is manifest.json). */
function isProject(fileName, bytes) {
  if (/\.odori$/i.test(fileName)) return true;
  if (!bytes || bytes.length < 30 || bytes[0] !== 0x50 || bytes[1] !== 0x4b || bytes[2] !== 3 || bytes[3] !== 4) return false;
  const nameLen = bytes[26] | (bytes[27] << 8);
  return new TextDecoder().decode(bytes.subarray(30, 30 + nameLen)) === "manifest.json";
}

/** Mono PCM (±1) as a 16-bit WAV file, for an <audio> element (the demo song is synthesised). */
function wavFromSamples(samples, sampleRateHz) {
  const rate = Math.round(sampleRateHz);
  const buf = new ArrayBuffer(44 + samples.length * 2);
  const v = new DataView(buf);
  const text = (at, s) => { for (let i = 0; i < s.length; i++) v.setUint8(at + i, s.charCodeAt(i)); };
  text(0, "RIFF"); v.setUint32(4, 36 + samples.length * 2, true); text(8, "WAVE");
  text(12, "fmt "); v.setUint32(16, 16, true); v.setUint16(20, 1, true); v.setUint16(22, 1, true);
  v.setUint32(24, rate, true); v.setUint32(28, rate * 2, true); v.setUint16(32, 2, true); v.setUint16(34, 16, true);
  text(36, "data"); v.setUint32(40, samples.length * 2, true);
  for (let i = 0; i < samples.length; i++) v.setInt16(44 + i * 2, Math.round(Math.max(-1, Math.min(1, samples[i])) * 32767), true);
  return new Blob([buf], { type: "audio/wav" });
}

const AUDIO_TYPES = { mp3: "audio/mpeg", ogg: "audio/ogg", oga: "audio/ogg", opus: "audio/ogg", wav: "audio/wav", flac: "audio/flac", m4a: "audio/mp4", aac: "audio/aac", webm: "audio/webm" };

/**
 * A `.odori` project as the player plays it: its dance rendered into a library of the full
 * engine (frame time is song time), and its own song as the music (the file as saved; the
 * demo song is synthesised again by the engine, the same samples the grid was found on).
 * Returns `{ library, clip, musicUrl, demoSong }`; `musicUrl` is an object URL the caller
 * revokes, null for the demo song (`demoSong`: made by `demoSongUrl`, after the first pose).
 * Throws the engine's typed errors (`not-odori`, `truncated`, `corrupt`, `newer-version`, …;
 * from `Project.playInto`: `no-song`, `choreo` when no bar holds a move, `missing-blob`).
 */
function openProject(engine, fileName, bytes) {
  let project;
  try {
    project = engine.Project.open(bytes);
  } catch (e) {
    // The engine's typed error (kind, message); the page also wants to know which file.
    throw Object.assign(e, { file: e.file || fileName, message: e.message.startsWith(fileName) ? e.message : `${fileName}: ${e.message}` });
  }
  const library = new engine.Library();
  try {
    // The engine reads the project (song, dance, character) and says what to play: the page
    // never reads the document's schema. Its errors carry the engine's kinds ("no-song",
    // "choreo" for an empty dance, "missing-blob"), one vocabulary with errorKinds().
    let play;
    try {
      play = project.playInto(library);
    } catch (e) {
      throw Object.assign(e, { message: e.message.startsWith(fileName) ? e.message : `${fileName}: ${e.message}` });
    }
    let musicUrl = null; // the demo song: synthesised later (it takes a while), see demoSongUrl
    if (play.audio) {
      const ext = (play.songName.split(".").pop() || "").toLowerCase();
      musicUrl = URL.createObjectURL(new Blob([play.audio], AUDIO_TYPES[ext] ? { type: AUDIO_TYPES[ext] } : {}));
    }
    // No character chosen: the built-in body, as the app draws it (stick figures only when the
    // project chose them).
    return { library, clip: play.clip, musicUrl, demoSong: play.demoSong, name: play.name || fileName, songName: play.songName, characterClip: play.characterClip, characterName: play.characterName, stickFigures: play.stickFigures };
  } catch (e) {
    library.free();
    throw Object.assign(e, { file: e.file || fileName });
  } finally {
    project.free();
  }
}

/** The engine's demo song (the same samples a project's grid was found on), as a WAV object URL. */
function demoSongUrl(engine) {
  const demo = engine.DemoSong.render(44100);
  try { return URL.createObjectURL(wavFromSamples(demo.samples, demo.sampleRateHz)); } finally { demo.free(); }
}

/** Does this browser have WebGPU or WebGL2 at all? Probed once per page. */
function graphicsAvailable() {
  graphicsProbe ??= (async () => {
    if (navigator.gpu) {
      try {
        if (await navigator.gpu.requestAdapter()) return true;
      } catch { /* fall through to WebGL2 */ }
    }
    try {
      const gl = document.createElement("canvas").getContext("webgl2");
      if (gl) {
        // Give the probe's context back at once: contexts are scarce.
        gl.getExtension("WEBGL_lose_context")?.loseContext();
        return true;
      }
    } catch { /* no WebGL2 */ }
    return false;
  })();
  return graphicsProbe;
}

/**
 * Turns a motion file's bytes (GLB/glTF, BVH) into clips in the library and returns the import
 * report. `.odori` projects are opened by the element itself (they need the full engine).
 */
export function importSource(library, fileName, bytes) {
  if (isProject(fileName, bytes)) {
    throw Object.assign(new Error(`${fileName}: a .odori project is played by <odori-player src>, not imported as motion`), { name: "OdoriError", kind: "bad-argument", file: fileName });
  }
  return library.importFile(fileName, bytes, {});
}

const STYLE = `
:host { display: inline-block; position: relative; width: 300px; height: 300px; background: #16181d; color: #eee;
  font: 13px system-ui, sans-serif; overflow: hidden; contain: strict; }
.stage, canvas, img.poster, .message { position: absolute; inset: 0; width: 100%; height: 100%; }
canvas { display: block; touch-action: none; outline: none; }
canvas:focus-visible { box-shadow: inset 0 0 0 2px #6cf; }
img.poster { object-fit: contain; }
img.poster[hidden], .message[hidden], [hidden] { display: none !important; }
.message { display: flex; align-items: center; justify-content: center; text-align: center; padding: 1em;
  box-sizing: border-box; height: auto; top: auto; bottom: 2.6em; background: rgba(0,0,0,.65); }
.controls { position: absolute; left: 0; right: 0; bottom: 0; display: flex; gap: .5em; align-items: center;
  padding: .35em .5em; background: linear-gradient(transparent, rgba(0,0,0,.6)); }
button { font: inherit; color: inherit; background: rgba(255,255,255,.12); border: 1px solid rgba(255,255,255,.3);
  border-radius: 4px; min-width: 2.2em; padding: .15em .5em; cursor: pointer; }
button:focus-visible, input:focus-visible { outline: 2px solid #6cf; outline-offset: 1px; }
input[type=range] { flex: 1; min-width: 0; }
.time { font-variant-numeric: tabular-nums; white-space: nowrap; }
`;

const TEMPLATE = `
<style>${STYLE}</style>
<div class="stage" part="stage"></div>
<img class="poster" part="poster" alt="" hidden>
<div class="message" part="message" role="status" hidden></div>
<div class="controls" part="controls">
  <button class="play" type="button" aria-label="Play">▶</button>
  <input class="seek" type="range" min="0" max="0" step="0.01" value="0" aria-label="Position in seconds">
  <span class="time" aria-hidden="true">0:00</span>
  <button class="unmute" type="button" aria-label="Unmute" hidden>🔇 Unmute</button>
</div>`;

const fmt = (s) => {
  const t = Math.max(0, Math.floor(s || 0));
  return `${Math.floor(t / 60)}:${String(t % 60).padStart(2, "0")}`;
};

export class OdoriPlayer extends HTMLElement {
  /** Where the player build's .wasm is, when a bundler moved it (default: beside odori_player.js). */
  static wasmUrl = undefined;
  /**
   * Where the full engine's module is (needed only for a `.odori` src), when a bundler moved
   * it (default: `../odori.js` beside the player build, as in the npm package).
   */
  static fullEngineUrl = undefined;
  /** Where the full engine's .wasm is, when a bundler moved it (default: beside its module). */
  static fullEngineWasmUrl = undefined;
  /** How far outside the viewport (CSS margin) a player loads and keeps its GPU context. */
  static nearMargin = "100px";
  /** Seconds the arrow keys seek (on the player or its slider). */
  static seekStepSecs = 5;
  /** Graphics back end for players without a `backend` attribute: "auto" | "webgpu" | "webgl2". */
  static backend = "auto";
  /** Draws per second while playing on a software adapter, for players without `max-fps`. */
  static softwareMaxFps = 30;

  static get observedAttributes() {
    return ["src", "music", "animation-name", "poster", "loop", "character", "camera-controls"];
  }

  #engine = null;
  #library = null;
  #clip = null; // ClipInfo of the clip playing
  #viewer = null;
  #software = false; // the viewer's adapter draws with the CPU
  #canvas = null;
  #audio = null; // HTMLAudioElement when `music` is set
  #ownAudio = false;
  #state = "idle"; // idle | loading | ready | error
  #near = false;
  #playing = false; // what the person (or autoplay) asked for
  #resume = false; // paused because off-screen: resume when back
  #offsetSecs = 0; // clock without music: time at #startMs
  #startMs = 0;
  #raf = 0;
  #acquiring = null;
  #observer = null;
  #resizeObserver = null;
  #attachMs = 0;
  #drag = null;
  #loadToken = 0;
  #silent = false; // the song may not play at all yet (autoplay policy): the clock is our own
  #dressed = null; // id of the clip drawn when the motion is put on a character
  #dressClips = []; // clips made for the character (removed when it changes)
  #dressToken = 0;
  #project = null; // { name, songName, musicUrl } when src is a .odori project
  #pendingDemo = false; // a project on the demo song whose song is not synthesised yet
  #songUrl = null; // object URL of the project's song, revoked when replaced
  #dueMs = 0; // the animation loop's next draw is due (rAF clock)
  /** The last drawn frame: { songTimeSecs, clipTimeSecs } (for tests and sync checks). */
  lastFrame = null;
  /** Frames put on screen (a draw that would repeat the last image is not one). */
  framesDrawn = 0;
  /** Milliseconds from attach to the first drawn pose (and to the engine/source being ready). */
  timings = {};

  constructor() {
    super();
    const root = this.attachShadow({ mode: "open" });
    root.innerHTML = TEMPLATE;
    this.$ = (sel) => root.querySelector(sel);
    this.$(".play").addEventListener("click", () => (this.paused ? this.play() : this.pause()));
    this.$(".unmute").addEventListener("click", () => {
      const a = this.#audio;
      this.$(".unmute").hidden = true;
      if (!a) return;
      a.muted = false;
      if (this.#silent) {
        // The figure kept time by itself: the song joins it there (this click is the gesture).
        a.currentTime = this.currentTime;
        this.#silent = false;
        if (this.#playing) a.play().catch((e) => this.#fail(e));
      }
    });
    const seek = this.$(".seek");
    seek.addEventListener("input", () => { this.currentTime = Number(seek.value); });
    // The slider's own arrow step would be its 0.01 s resolution: seek by SEEK_STEP_SECS instead.
    seek.addEventListener("keydown", (ev) => {
      const to = this.#seekKey(ev.key);
      if (to === null) return;
      ev.preventDefault();
      this.currentTime = to;
    });
    this.addEventListener("keydown", (ev) => {
      // Keys on the host or the canvas; buttons and the slider handle their own.
      const inner = ev.composedPath()[0];
      if (inner !== this && inner?.tagName !== "CANVAS") return;
      if (ev.code === "Space" || ev.key === "Enter" || ev.key === "k") {
        ev.preventDefault();
        this.paused ? this.play() : this.pause();
        return;
      }
      // Arrows on the canvas turn the camera (camera-controls); on the host they seek.
      if (inner === this) {
        const to = this.#seekKey(ev.key);
        if (to !== null) { ev.preventDefault(); this.currentTime = to; }
      }
    });
  }

  /** Where a seek key takes the clock (seconds), or null when it is not one. */
  #seekKey(key) {
    const now = this.currentTime;
    const end = Number.isFinite(this.duration) ? this.duration : now;
    const step = OdoriPlayer.seekStepSecs;
    const to = { ArrowLeft: now - step, ArrowDown: now - step, ArrowRight: now + step, ArrowUp: now + step, Home: 0, End: end }[key];
    return to === undefined ? null : Math.max(0, Math.min(end, to));
  }

  // ---- attributes ----
  get src() { return this.getAttribute("src"); }
  set src(v) { this.setAttribute("src", v); }
  get music() { return this.getAttribute("music"); }
  set music(v) { this.setAttribute("music", v); }
  get loop() { return this.hasAttribute("loop"); }
  set loop(v) { this.toggleAttribute("loop", !!v); }
  get autoplay() { return this.hasAttribute("autoplay"); }
  set autoplay(v) { this.toggleAttribute("autoplay", !!v); }
  get loading() { return this.getAttribute("loading") === "eager" ? "eager" : "lazy"; }
  set loading(v) { this.setAttribute("loading", v); }

  /** Playback position in seconds: the song's when there is music, else the clip's. */
  get currentTime() {
    if (this.#audio && !this.#silent) return this.#audio.currentTime;
    if (!this.#playing) return this.#offsetSecs;
    return this.#offsetSecs + (performance.now() - this.#startMs) / 1000;
  }
  set currentTime(t) {
    const secs = Math.max(0, Number(t) || 0);
    if (this.#audio) this.#audio.currentTime = secs;
    this.#offsetSecs = secs;
    this.#startMs = performance.now();
    this.#drawNow();
  }

  /** Seconds: the song's length with music, else the clip's; NaN before loading. */
  get duration() {
    if (this.#audio) return this.#audio.duration;
    return this.#clip ? this.#clip.durationSecs : NaN;
  }

  get paused() { return !this.#playing; }
  /** "loading", "ready", "error" or "idle" (not loaded yet). */
  get state() { return this.#state; }
  /** The graphics back end while a GPU context is held ("webgpu" | "webgl2"), else null. */
  get gpuContext() { return this.#viewer ? this.#viewer.backend : null; }
  /** What the browser reports of the adapter `{ backend, name, deviceType, software }`, while a GPU context is held. */
  get adapterInfo() { return this.#viewer ? this.#viewer.adapterInfo : null; }
  /**
   * Draws per second while playing: the `max-fps` attribute (a positive number; "none": no
   * cap), else `OdoriPlayer.softwareMaxFps` on a software adapter; Infinity when uncapped.
   */
  get maxFps() {
    const attr = (this.getAttribute("max-fps") || "").trim().toLowerCase();
    if (attr === "none") return Infinity;
    const n = Number(attr);
    if (attr && n > 0) return n;
    return this.#software ? OdoriPlayer.softwareMaxFps : Infinity;
  }
  set maxFps(v) { this.setAttribute("max-fps", v > 0 && Number.isFinite(Number(v)) ? String(v) : "none"); }
  /** The audio element whose clock drives the figure, or null. */
  get audioElement() { return this.#audio; }
  /** The clip being played (ClipInfo), or null. */
  get clip() { return this.#clip; }
  /** With a `.odori` src: `{ name, song, character, body }` of the project playing, else null. */
  get project() {
    const p = this.#project;
    if (!p) return null;
    // What "auto" draws it on: the project's character, the built-in body, or stick figures.
    const body = p.characterClip != null ? "character" : p.stickFigures ? "stick" : "builtin";
    return { name: p.name, song: p.songName, character: p.characterName, body };
  }

  /**
   * Joint positions (metres; x, y, z per point) of the figure at `clipTimeSecs` of its clip
   * (default: the pose last drawn), or null before loading: what the player shows, for pages
   * that attach things to the dancer, and for tests.
   */
  jointPositions(clipTimeSecs = this.lastFrame?.clipTimeSecs ?? 0) {
    if (!this.#library || !this.#clip) return null;
    return this.#library.jointPositions(this.#clip.id, clipTimeSecs);
  }

  // ---- lifecycle ----
  connectedCallback() {
    this.#attachMs = performance.now();
    this.timings = {};
    if (!this.hasAttribute("tabindex")) this.tabIndex = 0;
    if (!this.hasAttribute("role")) this.setAttribute("role", "region");
    if (!this.hasAttribute("aria-label")) this.setAttribute("aria-label", "Dance player");
    this.#showPoster();
    this.#observer = new IntersectionObserver((entries) => {
      const e = entries[entries.length - 1];
      this.#setNear(e.isIntersecting);
    }, { rootMargin: OdoriPlayer.nearMargin });
    this.#observer.observe(this);
    this.#resizeObserver = new ResizeObserver(() => this.#fit());
    this.#resizeObserver.observe(this);
    if (this.loading === "eager") this.#load();
  }

  disconnectedCallback() {
    this.#observer?.disconnect();
    this.#resizeObserver?.disconnect();
    this.#near = false;
    this.pause();
    this.#release();
  }

  attributeChangedCallback(name, oldValue, value) {
    if (oldValue === value) return;
    if (name === "poster") this.#showPoster();
    if (name === "loop" && this.#audio && this.#ownAudio) this.#audio.loop = this.loop;
    if (name === "character" && this.#state === "ready") this.#dress().then(() => { this.#frame(); this.#drawNow(); });
    if (name === "camera-controls" && this.#canvas) this.#bindCamera(this.#canvas);
    if ((name === "src" || name === "music" || name === "animation-name") && this.#state !== "idle") {
      this.pause();
      this.#state = "idle";
      this.#load();
    }
  }

  // ---- playback ----
  /** Starts playing (loading first if needed). Resolves when playback has started. */
  async play() {
    this.#playing = true;
    this.#resume = false;
    this.#updateButton();
    if (this.#state === "idle") this.#load();
    if (this.#state !== "ready" || !this.#viewer) return;
    this.#ensureMusic();
    if (this.#audio && !this.#silent) {
      try {
        await this.#audio.play();
      } catch (e) {
        if (e.name !== "NotAllowedError") throw e;
        // Autoplay with sound is blocked here: start muted, offer to unmute.
        this.#audio.muted = true;
        this.$(".unmute").hidden = false;
        try {
          await this.#audio.play();
        } catch (e2) {
          if (e2.name !== "NotAllowedError") throw e2;
          // Not even muted playback is allowed (a strict autoplay policy): the figure keeps
          // time by itself, and Unmute (a gesture) brings the song in at that time.
          this.#silent = true;
          this.#offsetSecs = this.#audio.currentTime;
          this.#startMs = performance.now();
        }
      }
    } else if (this.#silent) {
      this.#startMs = performance.now();
    } else {
      if (this.#clip && !this.loop && this.#offsetSecs >= this.#clip.durationSecs) this.#offsetSecs = 0;
      this.#startMs = performance.now();
    }
    this.#tick();
  }

  /** Pauses; the figure stays on the current pose. */
  pause() {
    if ((!this.#audio || this.#silent) && this.#playing) this.#offsetSecs = this.currentTime;
    this.#playing = false;
    this.#audio?.pause();
    cancelAnimationFrame(this.#raf);
    this.#raf = 0;
    this.#updateButton();
  }

  // ---- internals ----
  #setNear(near) {
    this.#near = near;
    if (near) {
      this.#load();
      if (this.#state === "ready") this.#acquire();
    } else {
      if (this.#playing) {
        this.pause();
        this.#resume = true;
      }
      this.#release();
    }
  }

  #event(type, detail) {
    this.dispatchEvent(new CustomEvent(type, { detail }));
  }

  #message(text) {
    const m = this.$(".message");
    m.textContent = text || "";
    m.hidden = !text;
  }

  #fail(e) {
    this.#state = "error";
    const detail = { kind: e.kind || "load", message: e.message || String(e), file: e.file };
    this.#message(detail.message);
    this.#event("error", detail);
  }

  #showPoster() {
    const img = this.$(".poster");
    const url = this.getAttribute("poster");
    if (url) img.src = url;
    img.hidden = !url || (this.#viewer !== null && this.lastFrame !== null);
  }

  async #fetchBytes(url, progress = true) {
    const res = await fetch(url);
    if (!res.ok) throw Object.assign(new Error(`${url}: HTTP ${res.status} ${res.statusText}`), { kind: "load", file: url });
    const total = Number(res.headers.get("content-length")) || 0;
    if (!res.body || !total) {
      const bytes = new Uint8Array(await res.arrayBuffer());
      if (progress) this.#event("progress", { totalProgress: 1 });
      return bytes;
    }
    const reader = res.body.getReader();
    const parts = [];
    let got = 0;
    for (;;) {
      const { done, value } = await reader.read();
      if (done) break;
      parts.push(value);
      got += value.length;
      if (progress) this.#event("progress", { totalProgress: Math.min(1, got / total) });
    }
    const bytes = new Uint8Array(got);
    let at = 0;
    for (const p of parts) { bytes.set(p, at); at += p.length; }
    return bytes;
  }

  /** Engine, source and music: once per source (again when src/music change). */
  async #load() {
    if (this.#state !== "idle") return;
    this.#state = "loading";
    const token = ++this.#loadToken;
    this.#message("");
    try {
      if (!(await graphicsAvailable())) {
        // No 3D at all: the poster is the player.
        this.#state = "error";
        this.#showPoster();
        this.$(".controls").hidden = true;
        this.#message(this.getAttribute("poster") ? "" : "3D is not available in this browser.");
        this.#event("error", { kind: "gpu", message: "neither WebGPU nor WebGL2 is available" });
        return;
      }
      const src = this.src;
      const name = src ? decodeURIComponent(new URL(src, document.baseURI).pathname.split("/").pop() || "source") : "built-in";
      // A project named .odori goes straight to the full engine; one found by its bytes
      // (a URL without the extension) after the fetch.
      const [engineGuess, bytes] = await Promise.all([isProject(name, null) ? loadFullEngine() : loadEngine(), src ? this.#fetchBytes(src) : null]);
      const projectSource = bytes !== null && isProject(name, bytes);
      const engine = projectSource ? await loadFullEngine() : engineGuess;
      if (token !== this.#loadToken) return;
      this.timings.engineMs = performance.now() - this.#attachMs;
      // A viewer belongs to one engine's module: switching engines needs a fresh context.
      if (this.#engine && this.#engine !== engine) this.#release();
      this.#engine = engine;
      this.#library?.free();
      this.#library = null;
      this.#project = null;
      this.#pendingDemo = false;
      let clip;
      if (projectSource) {
        const opened = openProject(engine, name, bytes);
        this.#library = opened.library;
        this.#project = { name: opened.name, songName: opened.songName, musicUrl: opened.musicUrl, characterClip: opened.characterClip, characterName: opened.characterName, stickFigures: opened.stickFigures };
        // The demo song is synthesised once the first pose is up (or at play()), not before.
        this.#pendingDemo = opened.demoSong && !this.music;
        clip = opened.clip;
      } else {
        this.#library = new engine.Library();
        let clips;
        if (bytes) {
          clips = importSource(this.#library, name, bytes).clips;
        } else {
          // No src: the engine's own step-touch routine.
          clips = [this.#library.addBuiltinDemo()];
          this.#event("progress", { totalProgress: 1 });
        }
        const wanted = this.getAttribute("animation-name");
        clip = wanted ? clips.find((c) => c.name === wanted) : clips[0];
        if (!clip) {
          throw Object.assign(new Error(`${src || "built-in"}: no animation named "${wanted}" (it has: ${clips.map((c) => c.name).join(", ") || "none"})`), { kind: "not-found", file: src });
        }
      }
      this.#clip = clip;
      this.#dressClips = [];
      this.#dressed = null;
      await this.#dress();
      if (token !== this.#loadToken) return;
      this.#setupAudio();
      this.#offsetSecs = 0;
      this.#state = "ready";
      this.$(".seek").max = String(this.duration || clip.durationSecs);
      this.#event("load", this.#project ? { clip, project: this.project } : { clip });
      // Autoplay starts once a GPU context is held (when near the viewport).
      if (this.autoplay) this.#resume = true;
      if (this.#near) await this.#acquire();
    } catch (e) {
      if (token === this.#loadToken) this.#fail(e);
    }
  }

  /** A project on the demo song: its song is made now (once), and becomes the clock. */
  #ensureMusic() {
    if (!this.#pendingDemo || !this.#project) return;
    this.#pendingDemo = false;
    this.#project.musicUrl = demoSongUrl(this.#engine);
    try {
      this.#setupAudio();
    } catch (e) {
      this.#fail(e);
      return;
    }
    this.$(".seek").max = String(this.duration || this.#clip.durationSecs);
  }

  #setupAudio() {
    if (this.#audio && this.#ownAudio) { this.#audio.pause(); this.#audio.removeAttribute("src"); this.#audio.load(); }
    this.#audio = null;
    this.#silent = false;
    if (this.#songUrl) { URL.revokeObjectURL(this.#songUrl); this.#songUrl = null; }
    // A `music` attribute wins; else a project plays its own song.
    const music = this.music || this.#project?.musicUrl;
    if (this.#project && !this.music) this.#songUrl = this.#project.musicUrl;
    else if (this.#project) URL.revokeObjectURL(this.#project.musicUrl);
    if (!music) return;
    if (music.startsWith("#")) {
      const el = document.getElementById(music.slice(1));
      if (!(el instanceof HTMLMediaElement)) throw Object.assign(new Error(`music="${music}": no <audio> element with that id`), { kind: "bad-argument" });
      this.#audio = el;
      this.#ownAudio = false;
    } else {
      this.#audio = new Audio();
      this.#audio.preload = "auto";
      this.#audio.src = new URL(music, document.baseURI).href;
      this.#audio.loop = this.loop;
      this.#ownAudio = true;
    }
    const a = this.#audio;
    a.addEventListener("loadedmetadata", () => { this.$(".seek").max = String(a.duration || 0); });
    const label = this.music || `${this.src}: the project's song "${this.#project?.songName}"`;
    a.addEventListener("error", () => this.#fail(Object.assign(new Error(`${label}: the song cannot be played (${a.error?.message || "media error " + a.error?.code})`), { kind: "load", file: this.music || this.src })));
    a.addEventListener("ended", () => { this.pause(); this.#event("ended", {}); });
    // An <audio> of the page can be played and paused by its own controls: follow it.
    a.addEventListener("play", () => { if (!this.#playing) { this.#playing = true; this.#updateButton(); this.#tick(); } });
    a.addEventListener("pause", () => { if (this.#playing && !a.ended && !this.#silent) { this.#playing = false; this.#updateButton(); } });
    a.addEventListener("seeked", () => this.#drawNow());
  }

  /** Takes a GPU context (a fresh canvas and viewer) if near and none is held. */
  async #acquire() {
    if (this.#viewer || this.#state !== "ready" || !this.#near) return;
    if (this.#acquiring) return this.#acquiring;
    this.#acquiring = (async () => {
      const canvas = document.createElement("canvas");
      canvas.setAttribute("part", "canvas");
      this.$(".stage").replaceChildren(canvas);
      this.#canvas = canvas;
      this.#fitCanvas(canvas);
      let viewer;
      try {
        viewer = await this.#engine.Viewer.create(canvas, { backend: this.getAttribute("backend") || OdoriPlayer.backend });
      } catch (e) {
        this.#canvas = null;
        canvas.remove();
        this.#showPoster();
        this.#fail(e);
        return;
      }
      if (!this.#near || this.#canvas !== canvas) {
        // Went off-screen while the device was being opened: give it straight back.
        this.#dropViewer(viewer, canvas);
        return;
      }
      this.#viewer = viewer;
      this.#software = viewer.adapterInfo.software;
      this.#bindCamera(canvas);
      this.#frame();
      this.#drawNow();
      if (this.timings.firstPoseMs === undefined) {
        this.timings.firstPoseMs = performance.now() - this.#attachMs;
        this.#event("firstpose", { ms: this.timings.firstPoseMs, backend: viewer.backend });
      }
      this.#showPoster();
      if (this.#pendingDemo) {
        // Let the first pose reach the screen before the demo song is synthesised (~0.5 s of
        // the main thread), then play if asked.
        requestAnimationFrame(() => requestAnimationFrame(() => {
          this.#ensureMusic();
          if (this.#viewer === viewer && (this.#playing || this.#resume)) this.play();
        }));
      } else if (this.#playing || this.#resume) this.play();
    })();
    try { await this.#acquiring; } finally { this.#acquiring = null; }
  }

  #dropViewer(viewer, canvas) {
    const backend = viewer.backend;
    viewer.release();
    if (backend === "webgl2") canvas.getContext("webgl2")?.getExtension("WEBGL_lose_context")?.loseContext();
    canvas.remove();
  }

  /** Gives the GPU context back (off-screen or detached). */
  #release() {
    const canvas = this.#canvas;
    this.#canvas = null;
    if (this.#viewer) {
      const v = this.#viewer;
      this.#viewer = null;
      this.#dropViewer(v, canvas);
    } else {
      canvas?.remove();
    }
    this.#showPoster();
  }

  #figures(clipTimeSecs) {
    const style = this.getAttribute("character") === "stick" ? "stick" : "auto";
    return [{ clip: this.#dressed ?? this.#clip.id, timeSecs: clipTimeSecs, style }];
  }

  /** Frames the camera on the figure (after a load or a change of character). */
  #frame() {
    if (this.#viewer && this.#clip) this.#viewer.frameFigures(this.#library, this.#figures(0));
  }

  /**
   * Puts the motion on the `character` the attribute names: "auto" (the source's own mesh,
   * else a stick figure; for a `.odori` project its chosen character, else the built-in body
   * as in the app, or stick figures when the project chose them), "stick", "builtin" (the engine's built-in body: the clip exported as
   * GLB with that body and read back, so the player build needs nothing more), or the URL of a
   * skinned humanoid GLB/glTF (retargeted with the engine's putOnCharacter, spec §L). A
   * character that cannot be used is reported (`error` event, with the engine's kind) and the
   * dance goes on without it: nothing else is lost.
   */
  async #dress() {
    const token = ++this.#dressToken;
    const library = this.#library;
    for (const id of this.#dressClips) library.remove(id);
    this.#dressClips = [];
    this.#dressed = null;
    let want = (this.getAttribute("character") || "auto").trim();
    // "auto" on a project: what the app draws it on — its own character if it chose one, else
    // the built-in body (stick figures if the project chose those).
    if (want === "auto" && this.#project) {
      if (this.#project.characterClip != null) {
        this.#dressed = this.#project.characterClip;
        return;
      }
      want = this.#project.stickFigures ? "stick" : "builtin";
    }
    if (want === "auto" || want === "stick" || !this.#clip) return;
    const clip = this.#clip;
    try {
      if (want === "builtin") {
        const glb = library.exportGlb(clip.id, { character: "builtin" });
        const report = library.importFile("built-in body.glb", glb, { gltfFps: clip.fps });
        this.#dressClips = report.clips.map((c) => c.id);
        this.#dressed = report.clips[0].id;
        return;
      }
      const url = new URL(want, document.baseURI).href;
      const name = decodeURIComponent(new URL(url).pathname.split("/").pop() || "character");
      const bytes = await this.#fetchBytes(url, false);
      if (token !== this.#dressToken || library !== this.#library) return;
      const report = library.importFile(name, bytes, {});
      this.#dressClips = report.clips.map((c) => c.id);
      const character = report.clips.find((c) => c.hasMesh) ?? report.clips[0];
      if (!character) throw Object.assign(new Error(`${name}: no character in the file`), { kind: "character-no-skin", file: name });
      const worn = library.putOnCharacter(clip.id, character.id);
      this.#dressClips.push(worn.id);
      this.#dressed = worn.id;
    } catch (e) {
      if (token !== this.#dressToken) return;
      for (const id of this.#dressClips) library.remove(id);
      this.#dressClips = [];
      this.#dressed = null;
      const detail = { kind: e.kind || "load", message: `character="${want}": ${e.message || e}`, file: e.file || want };
      this.#message(detail.message);
      this.#event("error", detail);
    }
  }

  #fitCanvas(canvas) {
    const dpr = Math.min(window.devicePixelRatio || 1, 2);
    canvas.width = Math.max(1, Math.round(this.clientWidth * dpr));
    canvas.height = Math.max(1, Math.round(this.clientHeight * dpr));
  }

  #fit() {
    if (!this.#canvas) return;
    this.#fitCanvas(this.#canvas);
    this.#viewer?.resize(this.#canvas.width, this.#canvas.height);
    this.#drawNow();
  }

  /** Draws the pose for the clock's time now; handles the clip's end without music. */
  #drawNow() {
    if (!this.#clip) return;
    let song = this.currentTime;
    const dur = this.#clip.durationSecs;
    let clipTime;
    if (this.#silent && this.#playing && song >= this.duration) {
      // The song's end on our own clock (no `ended` event comes from a song that never played).
      if (this.loop) { this.#offsetSecs = 0; this.#startMs = performance.now(); song = 0; } else { this.#offsetSecs = song = this.duration; this.pause(); this.#event("ended", {}); }
    }
    if (this.#project) {
      // A project's dance is rendered on the song's own time line: frame time is song time.
      clipTime = Math.min(song, dur);
    } else if (this.#audio) {
      // The dance repeats under the song.
      clipTime = dur > 0 ? song % dur : 0;
    } else if (this.loop) {
      clipTime = dur > 0 ? song % dur : 0;
    } else {
      clipTime = Math.min(song, dur);
      if (this.#playing && song >= dur) {
        this.#offsetSecs = dur;
        song = dur;
        this.pause();
        this.#event("ended", {});
      }
    }
    const seek = this.$(".seek");
    if (this.shadowRoot.activeElement !== seek) seek.value = String(this.#audio || !this.loop ? song : clipTime);
    this.$(".time").textContent = fmt(song);
    seek.setAttribute("aria-valuetext", `${fmt(song)} of ${fmt(this.duration)}`);
    if (!this.#viewer) return;
    try {
      if (this.#viewer.draw(this.#library, this.#figures(clipTime))) this.framesDrawn++;
      this.lastFrame = { songTimeSecs: song, clipTimeSecs: clipTime };
      // The character's textures are still being decoded: the frame was held (never drawn
      // untextured); paused, draw again next frame (playing, the next tick does).
      if (this.#viewer.waitingForTextures && !this.#playing) requestAnimationFrame(() => this.#drawNow());
    } catch (e) {
      this.pause();
      this.#fail(e);
    }
  }

  #tick() {
    if (this.#raf || !this.#playing) return;
    const frame = (nowMs) => {
      this.#raf = 0;
      if (!this.#playing) return;
      // Uncapped, every display frame (the viewer interpolates between the clip's frames);
      // capped, at most the cap and the clip's own frame rate. The due time advances by whole intervals, so a late frame does not push
      // the later ones back; 2 ms of slack takes up the timestamps' jitter.
      const intervalMs = this.maxFps < Infinity ? 1000 / Math.min(this.maxFps, this.#clip?.fps || Infinity) : 0;
      if (!(nowMs < this.#dueMs - 2)) {
        this.#dueMs = nowMs - this.#dueMs > intervalMs ? nowMs + intervalMs : this.#dueMs + intervalMs;
        this.#drawNow();
      }
      if (this.#playing) this.#raf = requestAnimationFrame(frame);
    };
    this.#raf = requestAnimationFrame(frame);
  }

  #updateButton() {
    const b = this.$(".play");
    b.textContent = this.#playing ? "❚❚" : "▶";
    b.setAttribute("aria-label", this.#playing ? "Pause" : "Play");
  }

  /** Orbit by drag, zoom by wheel, and the same from the keyboard (arrows, + and -). */
  #bindCamera(canvas) {
    const on = this.hasAttribute("camera-controls");
    canvas.tabIndex = on ? 0 : -1;
    if (on) canvas.setAttribute("aria-label", "3D view: arrow keys turn the camera, + and - zoom");
    if (!on || canvas.dataset.bound) return;
    canvas.dataset.bound = "1";
    const orbit = (dx, dy) => { if (this.hasAttribute("camera-controls") && this.#viewer) { this.#viewer.orbit(dx, dy); this.#drawNow(); } };
    const zoom = (steps) => { if (this.hasAttribute("camera-controls") && this.#viewer) { this.#viewer.zoom(steps); this.#drawNow(); } };
    canvas.addEventListener("pointerdown", (ev) => { this.#drag = { x: ev.clientX, y: ev.clientY }; canvas.setPointerCapture(ev.pointerId); });
    canvas.addEventListener("pointermove", (ev) => {
      if (!this.#drag) return;
      orbit((ev.clientX - this.#drag.x) / canvas.clientWidth, (ev.clientY - this.#drag.y) / canvas.clientHeight);
      this.#drag = { x: ev.clientX, y: ev.clientY };
    });
    canvas.addEventListener("pointerup", () => { this.#drag = null; });
    canvas.addEventListener("wheel", (ev) => { ev.preventDefault(); zoom(Math.sign(ev.deltaY)); }, { passive: false });
    canvas.addEventListener("keydown", (ev) => {
      const moves = { ArrowLeft: [-0.05, 0], ArrowRight: [0.05, 0], ArrowUp: [0, -0.05], ArrowDown: [0, 0.05] };
      if (moves[ev.key]) { ev.preventDefault(); orbit(...moves[ev.key]); }
      if (ev.key === "+" || ev.key === "=") { ev.preventDefault(); zoom(-1); }
      if (ev.key === "-") { ev.preventDefault(); zoom(1); }
    });
  }
}

if (!customElements.get("odori-player")) customElements.define("odori-player", OdoriPlayer);
