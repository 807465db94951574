// Odori app bootstrap: loads the wasm engine, opens the viewer, wires the UI modules.
import init, { Library, Viewer, Song, DemoSong, TextAnimator, Choreographer, version } from "./pkg/odori.js";
import { LibraryPanel } from "./ui/library-panel.js";
import { Player } from "./ui/player.js";
import { FileLoader } from "./ui/files.js";
import { Messages } from "./ui/messages.js";
import { SongPanel } from "./ui/song-panel.js";
import { SongPlayer, decodeSong, bufferFromSamples } from "./audio/song-player.js";
import { rmsEnvelope } from "./audio/rms.js";
import { SearchClient } from "./search/client.js";
import { SearchPanel } from "./ui/search-panel.js";
import { TextPanel } from "./ui/text-panel.js";
import { ChoreoPanel } from "./ui/choreo-panel.js";
import { installShare } from "./share.js";

const t0 = performance.now();
const $ = (sel) => document.querySelector(sel);

async function main() {
  await init();
  const messages = new Messages($("#messages"));
  const library = new Library();
  const canvas = $("#view");
  const params = new URLSearchParams(location.search);
  const backend = params.get("backend") || "auto";
  fitCanvas(canvas);
  let viewer;
  try {
    viewer = await Viewer.create(canvas, { backend });
  } catch (e) {
    messages.error(`The 3D view cannot start: ${e.message}`);
    $("#backend").textContent = "no 3D";
    document.body.dataset.ready = "error";
    throw e;
  }
  const badge = $("#backend");
  badge.textContent = viewer.backend === "webgpu" ? "WebGPU" : "WebGL2";
  badge.classList.add(viewer.backend);
  document.body.dataset.backend = viewer.backend;

  const searchClient = new SearchClient(library);
  const player = new Player({ viewer, library, canvas, scrub: $("#scrub"), label: $("#frame-label"), playButton: $("#play"), loop: $("#loop") });
  const panel = new LibraryPanel($("#library tbody"), library, {
    onSelect: (id) => { player.select(id); if (searchPanel) searchPanel.clipChanged(); },
    onOverlay: (ids) => player.setOverlays(ids),
  });
  let searchPanel = null;
  let choreo = null;
  const loader = new FileLoader({
    library,
    messages,
    status: $("#status"),
    fpsInput: $("#fps-override"),
    onImported: (report) => {
      for (const c of report.clips) {
        searchClient.add(c.id);
        if (choreo) choreo.addClip(c);
      }
      panel.refresh();
      const first = report.clips[0];
      if (first) {
        panel.select(first.id);
      }
    },
  });
  loader.bindInput($("#file-input"));
  loader.bindDrop(document.body, $("#drop"));

  player.onFirstFrame = () => {
    window.odoriTimings = { firstPoseMs: performance.now() - t0 };
    document.body.dataset.ready = "1";
  };
  // The app opens on the engine's own demo clip: something moves with no file.
  searchPanel = new SearchPanel($("#search"), { client: searchClient, library, player, messages });
  const textPanel = new TextPanel($("#text"), { animator: new TextAnimator(), library, panel, messages, player });
  const demo = library.addBuiltinDemo();
  searchClient.add(demo.id);
  panel.refresh();
  panel.select(demo.id);
  const songPlayer = new SongPlayer();
  choreo = new ChoreoPanel($("#dance"), { choreographer: new Choreographer(), library, player, songPlayer, panel, messages });
  const songPanel = new SongPanel($("#song"), { player: songPlayer, messages, onGrid: (grid) => choreo.setBars(grid.bars) });
  player.songClock = songPlayer;
  player.onTick = () => { if (songPlayer.playing) songPanel.draw(); };
  player.start();
  bindSongInput($("#song-input"), songPanel, messages);
  // The built-in demo song, analysed like any file (WebAudio envelope → core), after the
  // first pose is on screen.
  const demoSong = loadDemoSong(songPanel, messages);
  // Share by link: a button beside Generate; a #dance=… link is applied once the bars are in.
  const share = installShare({ choreo, messages, songReady: demoSong });
  // A new canvas size clears the canvas: draw again at once (a paused figure would
  // otherwise vanish until the next edit).
  new ResizeObserver(() => { fitCanvas(canvas); viewer.resize(canvas.width, canvas.height); player.drawNow(); }).observe(canvas);
  window.odori = { library, viewer, player, panel, loader, messages, song: songPanel, songPlayer, search: searchPanel, searchClient, text: textPanel, choreo, share, version: version() };
}

async function analyse(buffer) {
  const env = await rmsEnvelope(buffer);
  return Song.fromEnvelope(env.hopSecs, env.bands);
}

async function loadDemoSong(songPanel, messages) {
  try {
    const demo = DemoSong.render(44100);
    const buffer = bufferFromSamples(demo.samples, demo.sampleRateHz);
    demo.free();
    songPanel.load(await analyse(buffer), "Demo song (built-in)", buffer);
    document.body.dataset.song = "demo";
  } catch (e) {
    messages.error(`The demo song could not be made: ${e.message}`);
  }
}

function bindSongInput(input, songPanel, messages) {
  input.addEventListener("change", async () => {
    const file = input.files[0];
    input.value = "";
    if (!file) return;
    const status = document.querySelector("#status");
    try {
      status.textContent = `Decoding ${file.name}…`;
      const bytes = new Uint8Array(await file.arrayBuffer());
      const buffer = await decodeSong(bytes, file.name);
      status.textContent = `Analysing ${file.name}…`;
      const song = await analyse(buffer);
      songPanel.load(song, file.name, buffer);
      messages.info(`${file.name}: ${song.grid().bars.length} bars at ${song.grid().bpm.toFixed(1)} BPM`);
      document.body.dataset.song = file.name;
    } catch (e) {
      const text = e.message.startsWith(file.name) ? e.message : `${file.name}: ${e.message}`;
      messages.error(text);
    } finally {
      status.textContent = "";
    }
  });
}

function fitCanvas(canvas) {
  const dpr = Math.min(window.devicePixelRatio || 1, 2);
  const w = Math.max(1, Math.round(canvas.clientWidth * dpr));
  const h = Math.max(1, Math.round(canvas.clientHeight * dpr));
  if (canvas.width !== w || canvas.height !== h) { canvas.width = w; canvas.height = h; }
}

// Offline use: a service worker keeps the app (and the engine) cached.
if ("serviceWorker" in navigator && location.protocol !== "file:") {
  navigator.serviceWorker.register("./sw.js").catch((e) => console.warn("offline cache unavailable:", e.message));
}

main().catch((e) => {
  console.error(e);
  const s = document.querySelector("#status");
  if (s) s.textContent = `Odori failed to start: ${e.message || e}`;
});
