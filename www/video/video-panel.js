// The app's *Video* export (issue 29): the Export dialog's video entry opens this dialog (made
// here, so the page's HTML is untouched): size, frame rate, container, camera; *Make video*
// asks where to save (the File System Access API's `showSaveFilePicker`, so the file streams
// to disk; a download where the browser has no such picker), then shows progress with the time
// left and a *Cancel* that leaves no file and changes nothing in the project.
//
// The exporter and its muxer (about 270 kB) are loaded when the dialog first opens, not with
// the page.
const load = () => import("./export-video.js");

const CAMERAS = [["director", "Director (cuts on phrases)"], ["fixed", "Fixed"], ["orbit", "Orbit"], ["follow", "Follow"]];

/**
 * The Export dialog's entry (one of EXPORT_FORMATS). `summary(plan)` says what it will make;
 * `run(panel, plan)` opens the video dialog. The page sets `panel.video = { engine, song(),
 * grid(), sections() }` (the engine module, the song's AudioBuffer, the project's grid and
 * sections).
 */
export const VIDEO_FORMAT = {
  id: "video", label: "Video with the song (MP4 / WebM)", ext: "mp4", mime: "video/mp4",
  on: (c) => (typeof c.character === "number" ? c.characterName : c.bodyless ? "the chosen body" : "its own figure"),
  make: () => { throw new Error("a video is made by its own dialog"); },
  summary: (plan) => `${plan.label.charAt(0).toUpperCase() + plan.label.slice(1)} as a video with its song: the next step chooses the size, frame rate and camera.`,
  run: (panel, plan) => { openVideoDialog(panel, plan).catch((e) => panel.messages.error(`Video: ${e.message}`)); return true; },
};

let dialog = null;

/** The dialog's camera choice as exportVideo's `camera`: a mode, or `vmd:i`, camera track i. */
export function cameraChoice(value) {
  const m = /^vmd:(\d+)$/.exec(value);
  return m ? { mode: "vmd", track: Number(m[1]) } : { mode: value };
}

function build({ VIDEO_SIZES, VIDEO_FPS }) {
  const d = document.createElement("dialog");
  d.id = "video-dialog";
  d.setAttribute("aria-labelledby", "video-title");
  const sel = (id, label, items) => `<p class="field"><label>${label} <select id="${id}">${items.map(([v, t]) => `<option value="${v}">${t}</option>`).join("")}</select></label></p>`;
  d.innerHTML = `<h2 id="video-title">Video</h2>
    <p id="video-what"></p>
    ${sel("video-size", "Size", VIDEO_SIZES.map(([w, h]) => [`${w}x${h}`, `${w} × ${h}${h > w ? " (vertical)" : w === h ? " (square)" : ""}`]))}
    ${sel("video-fps", "Frame rate", VIDEO_FPS.map((f) => [String(f), `${f} fps`]))}
    ${sel("video-container", "File", [["mp4", "MP4"], ["webm", "WebM"]])}
    ${sel("video-camera", "Camera", CAMERAS)}
    <p><progress id="video-progress" max="1" value="0" hidden></progress> <span id="video-status" role="status" aria-live="polite"></span></p>
    <p class="buttons"><button id="video-close" type="button">Close</button> <button id="video-cancel" type="button" hidden>Cancel</button> <button id="video-go" type="button">Make video</button></p>`;
  document.body.append(d);
  d.querySelector("#video-size").value = "1280x720";
  return d;
}

function fmtSecs(s) {
  if (!Number.isFinite(s)) return "…";
  const m = Math.floor(s / 60), r = Math.round(s % 60);
  return m ? `${m} min ${r} s` : `${r} s`;
}

async function openVideoDialog(panel, plan) {
  dialog = dialog || build(await load());
  const $ = (s) => dialog.querySelector(s);
  $("#video-what").textContent = `${plan.label.charAt(0).toUpperCase() + plan.label.slice(1)} on ${plan.on}.`;
  // The camera VMDs the MMD import kept aside (issue 28) join the planned cameras.
  const tracks = typeof panel.library.cameraTracks === "function" ? panel.library.cameraTracks() : [];
  const cam = $("#video-camera");
  const was = cam.value;
  cam.replaceChildren(...[...CAMERAS, ...tracks.map((t, i) => [`vmd:${i}`, `Camera VMD: ${t.name}`])].map(([v, t]) => Object.assign(document.createElement("option"), { value: v, textContent: t })));
  if ([...cam.options].some((o) => o.value === was)) cam.value = was;
  $("#video-status").textContent = "";
  $("#video-progress").hidden = true;
  $("#video-go").disabled = false;
  $("#video-close").onclick = () => dialog.close();
  $("#video-go").onclick = () => makeVideo(panel, plan);
  if (!dialog.open) dialog.showModal();
}

/** Makes the video the dialog names; resolves the export's result, or null when cancelled or failed (said why). */
export async function makeVideo(panel, plan, { withoutSound = false } = {}) {
  const { exportVideo, danceRange, VideoExportError } = await load();
  const $ = (s) => dialog.querySelector(s);
  const ctx = panel.video;
  if (!ctx || !ctx.engine) { panel.messages.error("Video: this page has no engine for videos."); return null; }
  const [width, height] = $("#video-size").value.split("x").map(Number);
  const fps = Number($("#video-fps").value);
  const container = $("#video-container").value;
  const grid = ctx.grid ? ctx.grid() : null;
  const info = panel.library.clip(plan.id);
  // The range: the dance (from its lead-in) or the bars chosen, else the whole clip.
  let startSecs = 0, endSecs = info.durationSecs, bars = [];
  if (plan.what !== "clip" && grid && grid.bars.length) {
    const a = plan.range.startSecs ?? grid.bars[0].startSecs;
    const b = plan.range.endSecs ?? info.durationSecs;
    const first = grid.bars.findIndex((x) => Math.abs(x.startSecs - a) < 1e-3);
    let last = -1;
    grid.bars.forEach((x, i) => { if (x.endSecs <= b + 1e-3) last = i; });
    if (first >= 0 && last >= first) {
      bars = grid.bars.slice(first, last + 1);
      ({ startSecs, endSecs } = danceRange(grid.bars, first, last, grid.beatsPerBar));
    }
  }
  const name = panel.fileName({ ...plan, format: { ...plan.format, ext: container } });
  let stream = null, handle = null;
  if (typeof window.showSaveFilePicker === "function") {
    try {
      handle = await window.showSaveFilePicker({ suggestedName: name, types: [{ description: container.toUpperCase(), accept: { [`video/${container}`]: [`.${container}`] } }] });
      stream = await handle.createWritable();
    } catch (e) {
      if (e?.name === "AbortError") return null; // the person closed the picker
      stream = null; handle = null;
    }
  }
  const abort = new AbortController();
  const go = $("#video-go"), cancel = $("#video-cancel"), bar = $("#video-progress"), status = $("#video-status");
  go.disabled = true;
  cancel.hidden = false;
  bar.hidden = false;
  bar.value = 0;
  cancel.onclick = () => abort.abort();
  status.textContent = "Starting…";
  // The page's own view pauses while the video is made, and plays on after if it played: its
  // frames would wait behind the export's on the same GPU, each holding the page's thread for
  // 100–330 ms in its commit with software drawing (docs/benchmarks.md, the video section).
  const player = panel.player;
  const wasPlaying = !!player?.playing;
  if (wasPlaying) player.pause();
  try {
    const result = await exportVideo({
      engine: ctx.engine, library: panel.library, clip: plan.id, startSecs, endSecs, bars,
      sections: bars.length && ctx.sections ? ctx.sections() : undefined,
      character: panel.chosen(), width, height, fps, container, camera: cameraChoice($("#video-camera").value),
      song: plan.what === "clip" ? null : ctx.song ? ctx.song() : null, withoutSound, stream, signal: abort.signal,
    }, (p) => {
      bar.value = p.fraction;
      status.textContent = `${Math.floor(p.fraction * 100)} % — about ${fmtSecs(p.remainingSecs)} left`;
    });
    const used = `${result.codecs.videoName}${result.codecs.audioName ? ` + ${result.codecs.audioName}` : ", no sound"} in ${container.toUpperCase()}`;
    if (result.blob) {
      const url = URL.createObjectURL(result.blob);
      const a = Object.assign(document.createElement("a"), { href: url, download: name });
      document.body.append(a);
      a.click();
      a.remove();
      setTimeout(() => URL.revokeObjectURL(url), 60_000);
    }
    status.textContent = `Done: ${result.frames} frames, ${used}.`;
    panel.messages.info(`Video of ${plan.label}: ${name} (${result.frames} frames at ${fps} fps, ${used}${result.codecs.fallback ? `; ${result.codecs.fallback}` : ""})`);
    panel.lastVideo = { name, result };
    return result;
  } catch (e) {
    // The stream was aborted (nothing of it was kept); the file the picker made is removed
    // when it is still empty (a file chosen to be replaced keeps its old bytes).
    if (handle && typeof handle.remove === "function") {
      const size = await handle.getFile().then((f) => f.size).catch(() => -1);
      if (size === 0) await handle.remove().catch(() => {});
    }
    if (e instanceof VideoExportError && e.kind === "video-cancelled") {
      status.textContent = "Cancelled: no file was made.";
      return null;
    }
    if (e instanceof VideoExportError && e.kind === "video-no-audio-encoder" && !withoutSound) {
      status.textContent = `${e.message}.`;
      if (window.confirm(`${e.message}. Make the video without sound?`)) return makeVideo(panel, plan, { withoutSound: true });
      return null;
    }
    status.textContent = `Failed: ${e.message}`;
    panel.messages.error(`Video of ${plan.label} failed: ${e.message}`);
    return null;
  } finally {
    go.disabled = false;
    cancel.hidden = true;
    if (wasPlaying && !player.playing) player.play();
  }
}
