// Odori app bootstrap: loads the wasm engine, opens the viewer, wires the UI modules.
import init, { Library, Viewer, Song, DemoSong, TextAnimator, Project, SearchIndex, tempoLimits, envelopeDefinition, version, importFormats } from "./pkg/odori.js";
import { LibraryPanel } from "./ui/library-panel.js";
import { Player } from "./ui/player.js";
import { FileLoader } from "./ui/files.js";
import { Messages } from "./ui/messages.js";
import { SongPanel } from "./ui/song-panel.js";
import { SongPlayer, decodeSong, bufferFromSamples } from "./audio/song-player.js";
import { rmsEnvelope } from "./audio/rms.js";
import { SearchClient } from "./search/client.js";
import { IndexStore } from "./project/index-store.js";
import { SearchPanel } from "./ui/search-panel.js";
import { TextPanel } from "./ui/text-panel.js";
import { ChoreoPanel } from "./ui/choreo-panel.js";
import { ExportPanel } from "./ui/export-panel.js";
import { installShare } from "./share.js";
import { ProjectSession } from "./project/app.js";
import { ProjectDance } from "./project/dance.js";

const t0 = performance.now();
const $ = (sel) => document.querySelector(sel);

async function main() {
  // Marks for the start-up figures (the browser test prints where the time goes).
  performance.mark("odori:script");
  await init();
  performance.mark("odori:engine");
  // Separate tasks for the engine, the graphics device and the first pose: none of them
  // then holds the main thread for the sum of all three.
  await nextTask();
  const messages = new Messages($("#messages"), $("#toasts"));
  const library = new Library();
  const canvas = $("#view");
  const params = new URLSearchParams(location.search);
  const backend = params.get("backend") || "auto";
  bindPage(messages);
  // The tempo fields' ranges are the engine's (one place: odori_core::choreo / music::grid).
  const limits = tempoLimits();
  Object.assign($("#dance-clip-bpm"), { min: String(limits.moveMinBpm), max: String(limits.moveMaxBpm) });
  Object.assign($("#song-bpm"), { min: String(limits.songMinBpm), max: String(limits.songMaxBpm) });
  fitCanvas(canvas);
  // The project (what the person made, autosaved): read back from IndexedDB while the 3D
  // view starts; every edit below is an edit of it, and undo/redo is its history
  // (www/project/app.js).
  const session = new ProjectSession({ Project, messages, library });
  const sessionReady = session.start();
  let viewer;
  try {
    viewer = await Viewer.create(canvas, { backend });
  } catch (e) {
    messages.error(`The 3D view cannot start: ${e.message}`);
    $("#backend").textContent = "no 3D";
    document.body.dataset.ready = "error";
    throw e;
  }
  performance.mark("odori:viewer");
  await nextTask();
  const badge = $("#backend");
  badge.textContent = viewer.backend === "webgpu" ? "WebGPU" : "WebGL2";
  badge.classList.add(viewer.backend);
  document.body.dataset.backend = viewer.backend;

  // Panels created after the first pose fill these in; the handlers below check for them.
  let searchClient = null, searchPanel = null, textPanel = null, choreo = null;
  const waitingForDance = [], waitingForSearch = [];
  const player = new Player({ viewer, library, canvas, scrub: $("#scrub"), label: $("#frame-label"), playButton: $("#play"), loop: $("#loop") });
  bindDrawCap(player, viewer.adapterInfo, badge);
  // A face (lip-sync) track keying morphs the drawn MMD model lacks: ignored there, and said.
  player.onMissingMorphs = (names) => messages.info(`This model lacks the face track's morphs ${names.join(", ")}: their keys are ignored on it`);
  // The library's order and selection as the person left them, kept per project in this browser.
  const viewKey = () => (session.store && session.store.projectId ? `odori.view.${session.store.projectId}` : null);
  const panel = new LibraryPanel($("#library tbody"), library, {
    view: {
      load: () => { try { const k = viewKey(); return k ? JSON.parse(localStorage.getItem(k) || "null") : null; } catch { return null; } },
      save: (state) => { try { const k = viewKey(); if (k) localStorage.setItem(k, JSON.stringify(state)); } catch { /* storage off */ } },
    },
    onSelect: (id) => { player.select(id); if (searchPanel) searchPanel.clipChanged(); },
    onOverlay: (ids) => player.setOverlays(ids),
    onRemove: (id) => {
      const info = library.clip(id);
      if (searchClient) searchClient.remove(id);
      if (choreo && choreo.danceId === id) choreo.danceId = null;
      if (textPanel && textPanel.clipId === id) textPanel.clipId = null;
      library.remove(id);
      session.clipRemoved(id);
      if (player.clip === id) player.clear();
      messages.info(`${info.name} removed from the library${choreo && choreo.clips?.some((c) => c.id === id) ? " (bars dancing its moves are emptied; Undo brings it all back)" : ""}`);
      if (choreo) { choreo.refreshClips(); choreo.refresh(); }
    },
  });
  let exporter = null;
  const imported = (report, how) => {
    for (const c of report.clips) {
      if (searchClient) searchClient.add(c.id); else waitingForSearch.push(c.id);
      // MMD dances inside a zip stay in the library only; a VMD given as a file is a project source.
      if (how && how.mmd === true) continue;
      if (choreo) choreo.addClip(c); else waitingForDance.push(c);
    }
    panel.refresh();
    const first = report.clips[0];
    if (first) {
      panel.select(first.id);
    }
    // An imported character is offered at once in the Character list.
    if (exporter) exporter.refreshCharacters();
  };
  const restored = await sessionReady;
  const loader = new FileLoader({
    library,
    messages,
    status: $("#status"),
    optionsDialog: $("#import-options"),
    // The project parses the file (once) and shows its clips in the library.
    importer: (fileName, bytes, options, model) => session.importFile(fileName, bytes, options, model),
    cameraImporter: (fileName, bytes, options) => session.importCamera(fileName, bytes, options),
    faceImporter: (fileName, bytes, options) => session.importFaceTrack(fileName, bytes, options),
    onImported: (report, how) => imported(report, how),
    onFiles: (files) => session.takeProjectFiles(files),
    formats: importFormats(),
  });
  loader.bindInput($("#file-input"));
  exporter = new ExportPanel({
    button: $("#export"), format: $("#export-format"), character: $("#character"), putOn: $("#put-on"), library, player, messages,
    onAdded: (info) => { if (searchClient) searchClient.add(info.id); else waitingForSearch.push(info.id); panel.refresh(); panel.select(info.id); },
  });
  loader.bindDrop(document.body, $("#drop"));
  $("#stick-figure").addEventListener("change", (ev) => player.setStick(ev.target.checked));
  bindSprings(viewer, player, $("#springs"));
  // What Export offers first: the dance, once it has a move (rendered if it is not yet).
  exporter.dance = () => {
    if (!choreo || !(choreo.view || []).some((v) => v.state.kind !== "empty")) return null;
    if (choreo.danceId == null) choreo.renderDance();
    return choreo.danceId == null ? null : { id: choreo.danceId, bars: choreo.view.map((v) => ({ startSecs: v.bar.startSecs, endSecs: v.bar.endSecs })) };
  };
  // The chosen character and the clips put on it are project edits (kept, undone, saved).
  exporter.wear = (id, character) => session.putOn(id, character);
  // The video export (www/video/): the engine draws on a canvas of its own, with the song and
  // the project's grid and sections (for the camera's cuts).
  exporter.video = { engine: { Viewer }, song: () => songPlayer.buffer, grid: () => session.project.grid(), sections: () => session.project.sections() };
  exporter.onCharacter = (id) => session.setCharacter(id);
  // Every figure has a body from the first pose: the built-in one, unless the project chose
  // stick figures (an imported character it chose follows once its file is shown, `reconcile`).
  const firstBody = restored && restored.stickFigures ? null : "builtin";
  viewer.setCharacter(library, firstBody);
  exporter.character.value = firstBody ?? "";

  // The app opens on the engine's own demo clip: something moves with no file. Only what the
  // first pose needs runs before it; the rest waits for it (see `afterFirstPose`).
  const firstPose = new Promise((resolve) => {
    player.onFirstFrame = () => {
      window.odoriTimings = { firstPoseMs: performance.now() - t0, firstPoseSinceNavigationMs: performance.now() };
      document.body.dataset.posed = "1";
      performance.mark("odori:first-pose");
      resolve();
    };
  });
  const demo = library.addBuiltinDemo();
  panel.refresh();
  panel.select(demo.id);
  const songPlayer = new SongPlayer();
  player.attachSong(songPlayer);
  player.start();
  // A new canvas size clears the canvas: frame and draw again at once (a paused figure would
  // otherwise vanish until the next edit, and the framing is made for the view's shape).
  new ResizeObserver(() => { fitCanvas(canvas); viewer.resize(canvas.width, canvas.height); player.reframe(); player.drawNow(); }).observe(canvas);
  const odori = { library, viewer, player, panel, loader, messages, songPlayer, exporter, version: version() };
  window.odori = odori;

  await firstPose;
  // Each step in its own task, so the page answers input between them. First the 3D view's
  // skinned-character pipeline, which the first pose did not need.
  await nextTask();
  viewer.warmUp();
  await nextTask();
  // The search index is kept in IndexedDB between visits (www/project/index-store.js).
  const indexStore = await IndexStore.open();
  searchClient = new SearchClient(library, undefined, { store: indexStore, libraryKey: (keys) => SearchIndex.libraryKey(keys), onNote: (m) => messages.warning(m) });
  searchClient.add(demo.id);
  for (const id of waitingForSearch.splice(0)) searchClient.add(id);
  searchPanel = new SearchPanel($("#search"), { client: searchClient, library, player, messages });
  searchPanel.clipChanged(); // the clip was selected before the panel existed
  await nextTask();
  textPanel = new TextPanel($("#text"), { animator: new TextAnimator(), library, panel, messages, player });
  textPanel.onTag = (id, tags) => session.setTags(id, tags);
  textPanel.onText = (text) => session.setTexts([text]);
  await nextTask();
  // The 558 built-in moves (420 in 4, 90 in 3, 48 in 4 held on the counts), a slice per task (building them at once blocked the page for
  // 1–2 s on this kind of machine).
  // The dance panel's engine is the project (www/project/dance.js).
  const dance = await loadMoves($("#status"), new ProjectDance(session));
  choreo = new ChoreoPanel($("#dance"), { choreographer: dance, library, player, songPlayer, panel, messages });
  // Undo/redo buttons follow the project's history, whatever edit made it.
  session.onEdited = () => {
    $("#dance-undo").disabled = !session.project.canUndo();
    $("#dance-redo").disabled = !session.project.canRedo();
  };
  // Files opened while the moves were being made join the dance library now.
  for (const c of waitingForDance.splice(0)) choreo.addClip(c);
  const songPanel = new SongPanel($("#song"), {
    player: songPlayer, messages, onGrid: (grid) => choreo.setBars(grid.bars, grid.beatTimesSecs),
    onCorrect: (c) => (c ? session.correctGrid(c) : session.resetGrid()),
    sections: () => session.project?.sections(),
    // Repeats are project edits (kept, one undo step each); the Dance strip's notes follow.
    repeats: {
      list: () => session.project?.repeats(),
      mark: (first, bars, of) => { session.project.markRepeat(first, bars, of, bars); session.edited(); choreo.refresh(); },
      remove: (bar) => { const r = session.project.removeRepeat(bar); session.edited(); choreo.refresh(); return r; },
    },
  });
  songPanel.attachTransport(player);
  player.onTick = () => { if (songPlayer.playing) songPanel.draw(); };
  bindSongInput($("#song-input"), songPanel, messages, session);
  // How the page shows the project's document (after undo/redo, and a stored project opened):
  // these hooks display only, they never edit the project (www/project/app.js, `reconcile`).
  session.view = {
    addClips: (report) => imported(report),
    removeClips: (ids) => {
      for (const id of ids) {
        if (searchClient) searchClient.remove(id);
        if (textPanel && textPanel.clipId === id) textPanel.clipId = null;
        library.remove(id);
        if (player.clip === id) player.clear();
      }
      panel.refresh();
    },
    loadSong: (fileName, bytes) => (bytes ? loadSongBytes(fileName, bytes, songPanel, messages, null) : loadDemoSong(songPanel, messages, null)),
    showCorrections: (list) => {
      if (!songPanel.song) return;
      try {
        let g = songPanel.song.reset();
        for (const c of list) g = songPanel.song.correct(c);
        songPanel.setGrid(g);
      } catch (e) { messages.error(`${songPanel.name}: ${e.message}`); }
    },
    retag: (pairs) => {
      // A TextAnimator cannot forget a tag: a new one is given the document's tags.
      textPanel.animator = new TextAnimator();
      for (const [id, tags] of pairs) {
        try { textPanel.animator.tagClip(library, id, tags); } catch (e) { messages.error(`Text: ${e.message}`); }
      }
    },
    animate: (text) => { $("#text-input").value = text; textPanel.run(); },
    addWorn: (info) => { if (searchClient) searchClient.add(info.id); else waitingForSearch.push(info.id); panel.refresh(); },
    character: (id) => exporter.showCharacter(id),
    dance: (summary) => {
      songPanel.refreshRepeats();
      $("#dance-rho").value = String(summary.rho);
      $("#dance-music").value = String(summary.musicWeight);
      choreo.refreshClips();
      choreo.refresh();
    },
  };
  // The project's song (the built-in demo song for a new project, which then becomes its
  // song), analysed like any file (WebAudio envelope → core), in a task of its own; a stored
  // project is shown from its document (its files, song, grid, tags, texts; the dance panel
  // reads its bars and open searches from the project).
  const demoSong = nextTask().then(async () => {
    if (restored) {
      // Shown again as it was left: what it says was said when it was done (log, no toasts).
      await messages.replay(async () => {
        await session.reconcile();
        choreo.renderDance();
      });
    }
    // The library as it was left (order, selected clip); from here on it is kept.
    panel.restore();
    if (!session.project.summary().song) await loadDemoSong(songPanel, messages, session);
    keepRows(session);
    performance.mark("odori:project-ready");
    document.body.dataset.project = "ready";
  });
  await session.bindButtons({ newButton: $("#project-new"), openButton: $("#project-open"), saveButton: $("#project-save"), recent: $("#project-recent") });
  // Share by link: a button beside Generate; a #dance=… link is applied once the bars are in
  // (a link on a song file asks for the file, checks its hash, and loads it as any song).
  const share = installShare({
    choreo, messages, songReady: demoSong,
    song: () => (document.body.dataset.song === "demo" ? { demo: true }
      : { name: songPanel.name, durationSecs: songPlayer.duration, sha256: session.project?.summary().song?.audio ?? undefined }),
    loadSong: (fileName, bytes) => loadSongBytes(fileName, bytes, songPanel, messages, session),
  });
  Object.assign(odori, { song: songPanel, search: searchPanel, searchClient, text: textPanel, choreo, share, project: session });
  document.body.dataset.ready = "1";
}

/** The dance engine (the project) with its built-in moves made in slices of about SLICE_MS each. */
async function loadMoves(status, choreographer) {
  const SLICE_MS = 30;
  let count = 8;
  for (;;) {
    const t = performance.now();
    const p = choreographer.loadBuiltin(count);
    const dt = performance.now() - t;
    if (p >= 1) break;
    status.textContent = `Preparing dance moves ${Math.floor(p * 100)} %`;
    count = Math.max(1, Math.min(558, Math.round(count * SLICE_MS / Math.max(dt, 1))));
    await nextTask();
  }
  status.textContent = "";
  return choreographer;
}

/** Resolves in a new task (after pending input and a chance to paint). */
function nextTask() {
  return new Promise((r) => setTimeout(r, 0));
}

/** Tabs on narrow screens, the first-run hint and the keyboard sheet (`?`). */
function bindPage(messages) {
  const tabs = [...document.querySelectorAll(".tabs [role=tab]")];
  const show = (tab) => {
    for (const t of tabs) {
      const on = t === tab;
      t.setAttribute("aria-selected", String(on));
      t.tabIndex = on ? 0 : -1;
      document.getElementById(t.getAttribute("aria-controls")).classList.toggle("active", on);
    }
  };
  for (const t of tabs) t.addEventListener("click", () => show(t));
  show(tabs[0]);
  // A message names where it happened; on a narrow screen the log is one tap away.
  void messages;

  const hint = $("#hint");
  let seen = false;
  try { seen = localStorage.getItem("odori.hintSeen") === "1"; } catch { /* storage off: show it */ }
  hint.hidden = seen;
  $("#hint-close").addEventListener("click", () => {
    hint.hidden = true;
    try { localStorage.setItem("odori.hintSeen", "1"); } catch { /* storage off */ }
  });

  const keys = $("#keys");
  $("#help").addEventListener("click", () => keys.showModal());
  window.addEventListener("keydown", (ev) => {
    if (ev.key !== "?" || ev.target.closest("input, textarea, select, [contenteditable]")) return;
    ev.preventDefault();
    if (keys.open) keys.close(); else keys.showModal();
  });
}

/** The song's analysis and the envelope it was made from (the project keeps the envelope). */
async function analyse(buffer) {
  const env = await rmsEnvelope(buffer, envelopeDefinition());
  return { song: Song.fromEnvelope(env.hopSecs, env.bands), env };
}

/** The demo song's samples, synthesised in a worker (the main thread stays free). */
function renderDemoSong(sampleRateHz) {
  return new Promise((resolve, reject) => {
    let worker;
    try {
      worker = new Worker(new URL("./demo-song-worker.js", import.meta.url), { type: "module" });
    } catch {
      // No module workers: make it here.
      const demo = DemoSong.render(sampleRateHz);
      resolve({ samples: demo.samples, sampleRateHz: demo.sampleRateHz });
      demo.free();
      return;
    }
    worker.onmessage = (ev) => {
      worker.terminate();
      if (ev.data.error) reject(new Error(ev.data.error)); else resolve(ev.data);
    };
    worker.onerror = (ev) => { worker.terminate(); reject(new Error(ev.message || "the demo song worker failed")); };
    worker.postMessage({ sampleRateHz });
  });
}

/**
 * Song loads are numbered: the song chosen last wins. A load that finishes after a later one
 * started (the new project's demo song still being made when the person picks a file) is
 * dropped instead of replacing the person's song.
 */
let songLoads = 0;

/** Loads the built-in demo song; with `session`, it becomes the project's song. True when loaded. */
async function loadDemoSong(songPanel, messages, session) {
  const load = ++songLoads;
  try {
    const demo = await renderDemoSong(44100);
    const buffer = bufferFromSamples(demo.samples, demo.sampleRateHz);
    const { song, env } = await analyse(buffer);
    if (load !== songLoads) return false;
    // The project first: the dance panel reads its bars from the project's grid.
    if (session) session.setSong(DEMO_SONG_NAME, undefined, env);
    songPanel.load(song, DEMO_SONG_NAME, buffer);
    document.body.dataset.song = "demo";
    return true;
  } catch (e) {
    messages.error(`The demo song could not be made: ${e.message}`);
    return false;
  }
}

const DEMO_SONG_NAME = "Demo song (built-in)";

/** Decodes and analyses a song file's bytes; with `session`, it becomes the project's song. */
async function loadSongBytes(fileName, bytes, songPanel, messages, session) {
  const status = document.querySelector("#status");
  const load = ++songLoads;
  try {
    status.textContent = `Decoding ${fileName}…`;
    const buffer = await decodeSong(bytes, fileName);
    status.textContent = `Analysing ${fileName}…`;
    const { song, env } = await analyse(buffer);
    if (load !== songLoads) return false;
    if (session) session.setSong(fileName, bytes, env);
    songPanel.load(song, fileName, buffer);
    messages.info(`${fileName}: ${song.grid().bars.length} bars at ${song.grid().bpm.toFixed(1)} BPM`);
    document.body.dataset.song = fileName;
    return true;
  } catch (e) {
    const text = e.message.startsWith(fileName) ? e.message : `${fileName}: ${e.message}`;
    messages.error(text);
    return false;
  } finally {
    status.textContent = "";
  }
}

function bindSongInput(input, songPanel, messages, session) {
  input.addEventListener("change", async () => {
    const file = input.files[0];
    input.value = "";
    if (!file) return;
    await loadSongBytes(file.name, new Uint8Array(await file.arrayBuffer()), songPanel, messages, session);
  });
}

/**
 * The Dance strip's rows that come and go with the project, remembered per project whenever one
 * shows or hides, for boot.js to hold their lines on the next load; the lines held for this load
 * are let go once the project is restored (each row then is as the project has it).
 */
function keepRows(session) {
  const ids = ["dance-clip-row", "dance-share-note"];
  const remember = () => {
    const id = session.store && session.store.projectId;
    if (!id) return;
    const shown = ids.filter((x) => document.getElementById(x)?.hidden === false);
    try { if (shown.length) localStorage.setItem(`odori.rows.${id}`, shown.join(" ")); else localStorage.removeItem(`odori.rows.${id}`); } catch { /* storage off */ }
  };
  const watch = new MutationObserver(remember);
  for (const x of ids) { const el = document.getElementById(x); if (el) watch.observe(el, { attributes: true, attributeFilter: ["hidden"] }); }
  remember();
  delete document.documentElement.dataset.rows;
}

function fitCanvas(canvas) {
  const dpr = Math.min(window.devicePixelRatio || 1, 2);
  const w = Math.max(1, Math.round(canvas.clientWidth * dpr));
  const h = Math.max(1, Math.round(canvas.clientHeight * dpr));
  if (canvas.width !== w || canvas.height !== h) { canvas.width = w; canvas.height = h; }
}

/** Animation draws per second on a software adapter (see `bindDrawCap`). */
const SOFTWARE_MAX_FPS = 30;

/**
 * With no GPU the browser draws in software: at the display's rate that took about 1.8 cores
 * on this project's test machine and halved the search's speed beside it. There the figure is
 * drawn at most SOFTWARE_MAX_FPS times a second (motion pictures' and most mocap's rate: the
 * motion still reads as continuous), said quietly beside the back end's badge; the person can
 * lift the cap (the box, kept in this browser).
 */
function bindDrawCap(player, adapter, badge) {
  badge.title = `Graphics back end (${adapter.name || "adapter name not given"}${adapter.software ? ", drawn in software" : ""})`;
  document.body.dataset.software = adapter.software ? "1" : "0";
  const box = document.querySelector("#draw-cap-box");
  const input = document.querySelector("#draw-cap");
  const text = document.querySelector("#draw-rate");
  player.onDrawRate = ({ maxFps }) => {
    text.textContent = maxFps ? `drawn in software, ${maxFps} fps` : "drawn in software, not capped";
  };
  if (!adapter.software) return;
  let lifted = false;
  try { lifted = localStorage.getItem("odori.drawCap") === "off"; } catch { /* storage off: capped */ }
  box.hidden = false;
  input.checked = !lifted;
  player.setMaxFps(lifted ? null : SOFTWARE_MAX_FPS);
  input.addEventListener("change", () => {
    player.setMaxFps(input.checked ? SOFTWARE_MAX_FPS : null);
    try { localStorage.setItem("odori.drawCap", input.checked ? "on" : "off"); } catch { /* storage off */ }
  });
}

/**
 * The *Sway* box: an MMD model's hair and skirt follow by spring (the viewer's `setSprings`),
 * on unless the person turned it off in this browser.
 */
function bindSprings(viewer, player, input) {
  let off = false;
  try { off = localStorage.getItem("odori.springs") === "off"; } catch { /* storage off: on */ }
  input.checked = !off;
  viewer.setSprings(!off);
  input.addEventListener("change", () => {
    viewer.setSprings(input.checked);
    try { localStorage.setItem("odori.springs", input.checked ? "on" : "off"); } catch { /* storage off */ }
    player.drawNow();
  });
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

