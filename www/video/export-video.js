// The dance as a video with its song, made in the tab (issue 29).
//
// The engine draws every frame at its exact time on a canvas of its own (not the page's: the
// on-screen playback is not involved), with the camera the core plans for the range
// (`Viewer.planCamera`: fixed, orbit, follow or the director's cuts on phrase starts); each
// frame goes to WebCodecs' VideoEncoder, the song (trimmed to the range, with short fades) to
// its AudioEncoder, and Mediabunny (the maintained successor of mp4-muxer / webm-muxer) writes
// the MP4 or WebM: into memory (a Blob) or, given a stream (a FileSystemWritableFileStream
// from `showSaveFilePicker`), straight to disk, so a long video never needs its whole size in
// memory. Codecs are chosen by what the browser says it can encode (`isConfigSupported`,
// through Mediabunny's `canEncodeVideo`/`canEncodeAudio`), falling back in order, and the
// result says which were used. The page stays responsive: each frame is drawn into a texture
// of the viewer's own and read back asynchronously (`Viewer.setCapture`): the page's thread
// yields to the event loop while the GPU draws, instead of waiting for it as reading the
// canvas does (`new VideoFrame(canvas)` held the thread 60–250 ms a frame with software
// drawing). Each frame's steps run in tasks of their own (draw; read back into one reused
// array and a VideoFrame; the encoder's intake), so no task holds more than one step, and the
// pixels are copied twice a frame (read back → array → VideoFrame), not four times with a new
// 3.6 MB array each. The work stays on the page's thread (`result.path` says so): a Worker would
// need its own engine and a copy of the library. A page that draws a view of its own should
// pause it meanwhile (the app pauses its playback): its frames wait behind the export's on the
// same GPU, holding the page's thread in each frame's commit (docs/benchmarks.md, the video
// section). An AbortSignal cancels it, leaving nothing written.
import {
  Output, Mp4OutputFormat, WebMOutputFormat, BufferTarget, StreamTarget, VideoSampleSource, VideoSample, AudioBufferSource,
  canEncodeVideo, canEncodeAudio,
} from "./mediabunny.js";

/** An error of the video export: `kind` is one of VIDEO_ERROR_KINDS. */
export class VideoExportError extends Error {
  constructor(kind, message) {
    super(message);
    this.name = "VideoExportError";
    this.kind = kind;
  }
}

/** Every `kind` a VideoExportError carries. */
export const VIDEO_ERROR_KINDS = Object.freeze({
  "video-unsupported": "this browser has no WebCodecs VideoEncoder, or encodes none of the codecs the container takes at this size",
  "video-no-audio-encoder": "the browser encodes video but has no AudioEncoder (or none for this container): export again with `withoutSound: true`",
  "video-cancelled": "the export was cancelled (its AbortSignal): nothing was written",
  "video-bad-option": "an option is missing or out of range (the message names it)",
  "video-encode": "the encoder or the muxer failed while writing (the browser's words in the message)",
});

/** The sizes the app offers (width × height): landscape 1080p and 720p, vertical, square. */
export const VIDEO_SIZES = Object.freeze([[1920, 1080], [1280, 720], [1080, 1920], [1080, 1080]]);
/** Frame rates offered. */
export const VIDEO_FPS = Object.freeze([30, 60]);

/** Codecs by container, in order of preference: the first the browser encodes is used. */
const CODECS = {
  mp4: { video: ["avc", "vp9", "av1"], audio: ["aac", "opus"] },
  webm: { video: ["vp9", "av1", "vp8"], audio: ["opus"] },
};
const CODEC_NAMES = { avc: "H.264", vp9: "VP9", av1: "AV1", vp8: "VP8", aac: "AAC", opus: "Opus" };

/** Seconds of fade in and out at the ends of the trimmed song (no click at a cut mid-note). */
export const FADE_SECS = 0.02;
/**
 * Progress is reported about this often (ms): each report moves the page's progress bar, and
 * each frame the page then paints can wait behind the export's GPU work (docs/benchmarks.md).
 */
const PROGRESS_MS = 250;
/** Where the frames are drawn and read back (`result.path`). */
export const EXPORT_PATH = "main thread, frames read back asynchronously";

const bitrateFor = (w, h, fps) => Math.round(Math.min(12e6, Math.max(1.5e6, w * h * fps * 0.1)));

/**
 * Which codecs this browser would use: `{ container, video, audio, fallback, videoName,
 * audioName }` (`audio` null when there is no sound), or a VideoExportError. `fallback`
 * says, in words, when the first choice was refused. Asks the browser (`isConfigSupported`).
 */
export async function chooseCodecs({ container = "mp4", width, height, fps, sound = true, sampleRate = 48000, channels = 2 }) {
  if (!CODECS[container]) throw new VideoExportError("video-bad-option", `container must be mp4 or webm, not '${container}'`);
  if (typeof VideoEncoder === "undefined") throw new VideoExportError("video-unsupported", "this browser has no VideoEncoder (WebCodecs): it cannot make a video in the tab");
  const bitrate = bitrateFor(width, height, fps);
  const refused = [];
  let video = null;
  for (const c of CODECS[container].video) {
    if (await canEncodeVideo(c, { width, height, bitrate }).catch(() => false)) { video = c; break; }
    refused.push(CODEC_NAMES[c]);
  }
  if (!video) throw new VideoExportError("video-unsupported", `this browser encodes none of ${CODECS[container].video.map((c) => CODEC_NAMES[c]).join(", ")} at ${width}×${height} for ${container.toUpperCase()}`);
  let audio = null;
  const audioRefused = [];
  if (sound) {
    if (typeof AudioEncoder === "undefined") throw new VideoExportError("video-no-audio-encoder", "this browser has a VideoEncoder but no AudioEncoder: the video can be made without sound");
    for (const c of CODECS[container].audio) {
      if (await canEncodeAudio(c, { numberOfChannels: channels, sampleRate, bitrate: 128e3 }).catch(() => false)) { audio = c; break; }
      audioRefused.push(CODEC_NAMES[c]);
    }
    if (!audio) throw new VideoExportError("video-no-audio-encoder", `this browser encodes none of ${CODECS[container].audio.map((c) => CODEC_NAMES[c]).join(", ")} for ${container.toUpperCase()}: the video can be made without sound`);
  }
  const notes = [];
  if (refused.length) notes.push(`${refused.join(", ")} refused by this browser, ${CODEC_NAMES[video]} used`);
  if (audioRefused.length) notes.push(`${audioRefused.join(", ")} refused, ${CODEC_NAMES[audio]} used`);
  return { container, video, audio, fallback: notes.length ? notes.join("; ") : null, videoName: CODEC_NAMES[video], audioName: audio ? CODEC_NAMES[audio] : null, bitrate };
}

/**
 * The frames of a range: `round(duration × fps)`, the duration from `startSecs` (the range's
 * first bar, less its lead-in) to `endSecs`; frame i shows song time `startSecs + i / fps`.
 */
export function frameTimes(startSecs, endSecs, fps) {
  const frames = Math.round((endSecs - startSecs) * fps);
  const t = new Float32Array(Math.max(0, frames));
  for (let i = 0; i < t.length; i++) t[i] = startSecs + i / fps;
  return t;
}

/**
 * The song's samples from `startSecs` for `durationSecs` (silence past its ends), with
 * `FADE_SECS` fades, as an AudioBuffer at the song's rate.
 */
export function trimSong(song, startSecs, durationSecs) {
  const sr = song.sampleRate;
  const length = Math.max(1, Math.round(durationSecs * sr));
  const first = Math.round(startSecs * sr);
  const out = new AudioBuffer({ length, numberOfChannels: song.numberOfChannels, sampleRate: sr });
  const fade = Math.min(Math.round(FADE_SECS * sr), Math.floor(length / 2));
  for (let ch = 0; ch < song.numberOfChannels; ch++) {
    const src = song.getChannelData(ch);
    const dst = new Float32Array(length);
    const from = Math.max(0, first), to = Math.min(src.length, first + length);
    if (to > from) dst.set(src.subarray(from, to), from - first);
    for (let i = 0; i < fade; i++) {
      const g = i / fade;
      dst[i] *= g;
      dst[length - 1 - i] *= g;
    }
    out.copyToChannel(dst, ch);
  }
  return out;
}

/** The same samples as an AudioBuffer slice `[a, b)` (the encoder is fed a second at a time). */
function slice(buffer, a, b) {
  const out = new AudioBuffer({ length: b - a, numberOfChannels: buffer.numberOfChannels, sampleRate: buffer.sampleRate });
  for (let ch = 0; ch < buffer.numberOfChannels; ch++) out.copyToChannel(buffer.getChannelData(ch).subarray(a, b), ch);
  return out;
}

/** Waits a little (a timer): while the GPU draws, polling without a pause would spin the thread. */
const nextTask = () => new Promise((r) => setTimeout(r, 0));

/**
 * Ends the current task and goes on in a new one at once (a MessageChannel message, not a
 * timer: nested timers are held to 4 ms): input and rendering that came meanwhile run first.
 */
const channel = typeof MessageChannel === "function" ? new MessageChannel() : null;
const waiting = [];
if (channel) channel.port1.onmessage = () => waiting.shift()?.();
const yieldTask = () => (channel ? new Promise((r) => { waiting.push(r); channel.port2.postMessage(0); }) : nextTask());

/**
 * Draws `figures` into the viewer's capture and, once the GPU has drawn them, copies the
 * pixels into `pixels` (width × height × 4, reused every frame), yielding to the event loop
 * meanwhile. Leaves `pixels` as they are when the draw repeats the last frame (the viewer draws
 * nothing then: a clip's end held), `first` saying whether there is a last frame. Waits out
 * a skinned figure's textures still being decoded (the viewer holds such frames back, at
 * most a few seconds).
 */
async function drawCaptured(viewer, library, figures, pixels, first) {
  let drew = viewer.draw(library, figures);
  while (!drew && viewer.waitingForTextures) {
    await nextTask();
    drew = viewer.draw(library, figures);
  }
  if (!drew) {
    if (first) throw new VideoExportError("video-encode", "the first frame could not be drawn");
    return;
  }
  await nextTask();
  while (!viewer.captureReady()) await nextTask();
  viewer.takeCaptureInto(pixels);
}

/**
 * The caller's stream behind one of ours: the muxer closes its stream when cancelled too, and
 * closing a FileSystemWritableFileStream keeps what was written; ours aborts the caller's
 * instead once `discard()` was called, so a cancelled export leaves nothing written.
 */
function guarded(stream) {
  const writer = stream.getWriter();
  let discarded = false;
  const ws = new WritableStream({
    write: (chunk) => writer.write(chunk),
    close: () => (discarded ? undefined : writer.close()),
    abort: (reason) => writer.abort(reason),
  });
  return { ws, discard: () => { if (discarded) return Promise.resolve(); discarded = true; return writer.abort(new Error("video export cancelled")).catch(() => {}); } };
}

/**
 * Makes the video. Options:
 * - `engine`: the module with `Viewer` (the full engine: `import * as engine from "odori"`);
 *   `library`: its Library; `clip`: the clip drawn (the dance); `figures` (optional): several
 *   `{ clip, offset?, style? }` drawn together instead.
 * - `startSecs`, `endSecs`: the range in the clip's (song's) time, the lead-in included (a
 *   dance starting at bar 1 starts a beat early: see `danceRange`).
 * - `bars`: the range's song bars `{ index, startSecs, endSecs, intensity }`, `sections`:
 *   the song's sections (`Project.sections()`), for the director; `camera`: CameraOptions
 *   (`{ mode: "director" }` by default), or `{ mode: "vmd", track, offsetSecs? }`: the
 *   library's MMD camera track `track` (an index of `library.cameraTracks()`) drives the
 *   camera, sampled at each frame's song time less `offsetSecs` (0 by default).
 * - `cameraTrack` (optional): `(timeSecs) => CameraPose`, a camera from elsewhere (an MMD
 *   camera VMD, once read) used instead of the planned one.
 * - `character`: "builtin" (default), a character clip id, or null (stick figures).
 * - `width`, `height` (one of VIDEO_SIZES), `fps` (30 or 60), `container`: "mp4" | "webm".
 * - `song`: the song as an AudioBuffer (song time 0 at its first sample), or null: then no
 *   sound track unless `silentTrack`; `withoutSound`: true to leave the sound out (a
 *   browser with no AudioEncoder).
 * - `stream`: a WritableStream of `{ type: "write", position, data }` (a
 *   FileSystemWritableFileStream): the file is written there and the result is null; else a Blob.
 * - `signal`: an AbortSignal; `backend`: "auto" | "webgpu" | "webgl2".
 * `onProgress({ frame, frames, fraction, elapsedSecs, remainingSecs })` is called as frames are
 * encoded. Resolves `{ blob, codecs, frames, durationSecs, mimeType, camera, path }` (`path`:
 * where the frames were made, EXPORT_PATH); rejects with a
 * VideoExportError (`video-cancelled` when `signal` aborts).
 */
export async function exportVideo(options, onProgress = () => {}) {
  const o = { container: "mp4", fps: 30, width: 1280, height: 720, character: "builtin", backend: "auto", camera: {}, ...options };
  const { engine, library, signal } = o;
  if (!engine || !engine.Viewer || !library) throw new VideoExportError("video-bad-option", "exportVideo needs { engine, library } (the full engine's module and its Library)");
  if (!VIDEO_FPS.includes(o.fps)) throw new VideoExportError("video-bad-option", `fps must be 30 or 60, not ${o.fps}`);
  if (!VIDEO_SIZES.some(([w, h]) => w === o.width && h === o.height)) throw new VideoExportError("video-bad-option", `size must be one of ${VIDEO_SIZES.map(([w, h]) => `${w}×${h}`).join(", ")}, not ${o.width}×${o.height}`);
  if (!(Number.isFinite(o.startSecs) && Number.isFinite(o.endSecs) && o.endSecs > o.startSecs)) throw new VideoExportError("video-bad-option", `the range ${o.startSecs} s – ${o.endSecs} s is not a finite, increasing span`);
  const figures = o.figures || (o.clip != null ? [{ clip: o.clip }] : null);
  if (!figures || !figures.length) throw new VideoExportError("video-bad-option", "nothing to draw: give `clip` or `figures`");
  const cancelled = () => new VideoExportError("video-cancelled", "the video export was cancelled: nothing was written");
  if (signal?.aborted) throw cancelled();

  const sound = !o.withoutSound && (o.song != null || !!o.silentTrack);
  const sr = o.song?.sampleRate || 48000;
  const channels = Math.min(2, o.song?.numberOfChannels || 2);
  const codecs = await chooseCodecs({ container: o.container, width: o.width, height: o.height, fps: o.fps, sound, sampleRate: sr, channels });

  const times = frameTimes(o.startSecs, o.endSecs, o.fps);
  const frames = times.length;
  const durationSecs = frames / o.fps;

  const canvas = document.createElement("canvas");
  canvas.width = o.width;
  canvas.height = o.height;
  const viewer = await engine.Viewer.create(canvas, { backend: o.backend });
  let output = null;
  const out = o.stream ? guarded(o.stream) : null;
  try {
    viewer.setCharacter(library, o.character ?? null);
    if (o.character != null) viewer.warmUp();
    viewer.setCapture(true);
    const { mode, track: vmdTrack, offsetSecs, ...cameraRest } = o.camera;
    if (mode === "vmd" && !(Number.isInteger(vmdTrack) && vmdTrack >= 0)) throw new VideoExportError("video-bad-option", `camera: a camera VMD needs \`track\`, an index of library.cameraTracks(), not ${vmdTrack}`);
    const plan = viewer.planCamera(library, figures.map((f) => ({ timeSecs: 0, ...f })), {
      timesSecs: Array.from(times), bars: o.bars || [], sections: o.sections || undefined,
      camera: { aspect: o.width / o.height, ...cameraRest, ...(mode && mode !== "vmd" ? { mode } : {}) },
      ...(mode === "vmd" ? { cameraTrack: { index: vmdTrack, offsetSecs: offsetSecs || 0 } } : {}),
    });
    if (signal?.aborted) throw cancelled();

    const target = out ? new StreamTarget(out.ws, { chunked: true, chunkSize: 4 << 20 }) : new BufferTarget();
    const format = o.container === "webm" ? new WebMOutputFormat() : new Mp4OutputFormat({ fastStart: o.stream ? false : "in-memory" });
    output = new Output({ format, target });
    const video = new VideoSampleSource({ codec: codecs.video, bitrate: codecs.bitrate, keyFrameInterval: 2, latencyMode: "quality" });
    const pixelFormat = viewer.captureFormat;
    output.addVideoTrack(video, { frameRate: o.fps });
    let audio = null, track = null;
    if (codecs.audio) {
      audio = new AudioBufferSource({ codec: codecs.audio, bitrate: 128e3 });
      output.addAudioTrack(audio);
      track = o.song ? trimSong(o.song, o.startSecs, durationSecs) : new AudioBuffer({ length: Math.max(1, Math.round(durationSecs * sr)), numberOfChannels: channels, sampleRate: sr });
    }
    await output.start();

    const t0 = performance.now();
    let fed = 0; // audio samples given to the encoder
    let reported = performance.now();
    const pixels = new Uint8Array(o.width * o.height * 4);
    // The colours as they are (sRGB, full range): what Mediabunny assumes for RGBA samples.
    const colorSpace = { primaries: "bt709", transfer: "iec61966-2-1", matrix: "rgb", fullRange: true };
    for (let i = 0; i < frames; i++) {
      if (signal?.aborted) throw cancelled();
      // The sound a second ahead of the picture, a second at a time (the muxer interleaves).
      if (track) {
        const want = Math.min(track.length, Math.round(((i + 1) / o.fps + 1) * track.sampleRate));
        if (want > fed && (want - fed >= track.sampleRate || want === track.length)) {
          await audio.add(slice(track, fed, want));
          fed = want;
        }
      }
      viewer.setCamera(o.cameraTrack ? o.cameraTrack(times[i]) : plan.poses[i]);
      await drawCaptured(viewer, library, figures.map((f) => ({ ...f, timeSecs: times[i] })), pixels, i === 0);
      if (signal?.aborted) throw cancelled();
      // The VideoFrame copies the pixels (the array is reused); the sample wraps the frame.
      const frame = new VideoFrame(pixels, { format: pixelFormat, codedWidth: o.width, codedHeight: o.height, timestamp: Math.trunc((i / o.fps) * 1e6), duration: Math.trunc(1e6 / o.fps), colorSpace });
      const sample = new VideoSample(frame, { timestamp: i / o.fps, duration: 1 / o.fps });
      await yieldTask();
      try {
        await video.add(sample);
      } finally {
        sample.close();
        frame.close();
      }
      await yieldTask();
      if (performance.now() - reported > PROGRESS_MS || i === frames - 1) {
        const elapsed = (performance.now() - t0) / 1000;
        const done = i + 1;
        onProgress({ frame: done, frames, fraction: done / frames, elapsedSecs: elapsed, remainingSecs: (elapsed / done) * (frames - done) });
        reported = performance.now();
      }
    }
    if (track && fed < track.length) await audio.add(slice(track, fed, track.length));
    if (signal?.aborted) throw cancelled();
    await output.finalize();
    const mimeType = await output.getMimeType().catch(() => (o.container === "webm" ? "video/webm" : "video/mp4"));
    const blob = o.stream ? null : new Blob([target.buffer], { type: mimeType });
    return { blob, codecs, frames, durationSecs, mimeType, camera: plan, path: EXPORT_PATH };
  } catch (e) {
    if (out) await out.discard();
    if (output && output.state !== "finalized" && output.state !== "canceled") await output.cancel().catch(() => {});
    if (e instanceof VideoExportError) throw e;
    if (signal?.aborted) throw cancelled();
    throw new VideoExportError("video-encode", `the video could not be written: ${e?.message || e}`);
  } finally {
    try { viewer.release(); } catch { /* already released */ }
    const gl = canvas.getContext("webgl2");
    gl?.getExtension("WEBGL_lose_context")?.loseContext();
  }
}

/**
 * The range of bars `first..=last` (0-based, of `bars`: `{ startSecs, endSecs }`) as video
 * times: from the first bar's start, a beat earlier when it is the dance's first bar (its
 * lead-in count), to the last bar's end.
 */
export function danceRange(bars, first, last, beatsPerBar = 4) {
  const a = bars[first], b = bars[last];
  const beat = (a.endSecs - a.startSecs) / (a.beats || beatsPerBar);
  const startSecs = first === 0 ? Math.max(0, a.startSecs - beat) : a.startSecs;
  return { startSecs, endSecs: b.endSecs };
}
