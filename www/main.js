// Odori app bootstrap: loads the wasm engine, opens the viewer, wires the UI modules.
import init, { Library, Viewer, version } from "./pkg/odori.js";
import { LibraryPanel } from "./ui/library-panel.js";
import { Player } from "./ui/player.js";
import { FileLoader } from "./ui/files.js";
import { Messages } from "./ui/messages.js";

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

  const player = new Player({ viewer, library, canvas, scrub: $("#scrub"), label: $("#frame-label"), playButton: $("#play"), loop: $("#loop") });
  const panel = new LibraryPanel($("#library tbody"), library, {
    onSelect: (id) => player.select(id),
    onOverlay: (ids) => player.setOverlays(ids),
  });
  const loader = new FileLoader({
    library,
    messages,
    status: $("#status"),
    fpsInput: $("#fps-override"),
    onImported: (report) => {
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
  const demo = library.addBuiltinDemo();
  panel.refresh();
  panel.select(demo.id);
  player.start();
  new ResizeObserver(() => { fitCanvas(canvas); viewer.resize(canvas.width, canvas.height); }).observe(canvas);
  window.odori = { library, viewer, player, panel, loader, messages, version: version() };
}

function fitCanvas(canvas) {
  const dpr = Math.min(window.devicePixelRatio || 1, 2);
  const w = Math.max(1, Math.round(canvas.clientWidth * dpr));
  const h = Math.max(1, Math.round(canvas.clientHeight * dpr));
  if (canvas.width !== w || canvas.height !== h) { canvas.width = w; canvas.height = h; }
}

main().catch((e) => {
  console.error(e);
  const s = document.querySelector("#status");
  if (s) s.textContent = `Odori failed to start: ${e.message || e}`;
});
