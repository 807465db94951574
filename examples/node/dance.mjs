#!/usr/bin/env node
// Analyses a song, generates a dance of the engine's built-in moves to it and writes the
// dance's joint positions as JSON — all in Node, with the npm package `odori`.
//
//   node dance.mjs [song.wav] [out.json | out.bvh]
//
// With no song, the engine's own demo song (rendered by the engine) is used. Node has no
// audio decoder, so the song is a WAV file (PCM 16/24/32-bit or float; convert other formats
// first, e.g. `ffmpeg -i song.ogg song.wav`). The output: { fps, bpm, bars, joints, bones,
// frames: [[x, y, z, …] per frame] } in metres, Y up.
// An output path ending in .bvh writes the dance as BVH instead (the engine's canonical skeleton,
// centimetres), for Blender and other tools.
import { readFileSync, writeFileSync } from "node:fs";
import { fileURLToPath } from "node:url";
import { basename } from "node:path";
import { initSync, Library, DemoSong, Project, rmsEnvelope, version } from "odori";

initSync({ module: readFileSync(fileURLToPath(import.meta.resolve("odori/odori_bg.wasm"))) });

/** Decodes a RIFF/WAVE file into one Float32Array per channel. */
export function decodeWav(bytes) {
  const v = new DataView(bytes.buffer, bytes.byteOffset, bytes.byteLength);
  const tag = (at) => String.fromCharCode(bytes[at], bytes[at + 1], bytes[at + 2], bytes[at + 3]);
  if (bytes.length < 12 || tag(0) !== "RIFF" || tag(8) !== "WAVE") throw new Error("not a WAV file (no RIFF/WAVE header)");
  let fmt = null;
  for (let at = 12; at + 8 <= bytes.length; ) {
    const id = tag(at), size = v.getUint32(at + 4, true), body = at + 8;
    if (id === "fmt ") {
      fmt = { format: v.getUint16(body, true), channels: v.getUint16(body + 2, true), rate: v.getUint32(body + 4, true), bits: v.getUint16(body + 14, true) };
      if (fmt.format === 0xfffe) fmt.format = v.getUint16(body + 24, true); // WAVE_FORMAT_EXTENSIBLE: the sub-format
    } else if (id === "data") {
      if (!fmt) throw new Error("WAV data before its fmt chunk");
      const { format, channels, rate, bits } = fmt;
      const step = bits / 8, frames = Math.floor(Math.min(size, bytes.length - body) / (step * channels));
      const out = Array.from({ length: channels }, () => new Float32Array(frames));
      for (let i = 0; i < frames; i++) for (let c = 0; c < channels; c++) {
        const p = body + (i * channels + c) * step;
        out[c][i] = format === 3 ? (bits === 64 ? v.getFloat64(p, true) : v.getFloat32(p, true))
          : bits === 16 ? v.getInt16(p, true) / 32768
          : bits === 24 ? ((v.getUint8(p) | (v.getUint8(p + 1) << 8) | (v.getInt8(p + 2) << 16)) / 8388608)
          : bits === 32 ? v.getInt32(p, true) / 2147483648
          : (v.getUint8(p) - 128) / 128;
      }
      return { channels: out, sampleRate: rate };
    }
    at = body + size + (size & 1);
  }
  throw new Error("WAV file has no data chunk");
}

/** Writes the dance: BVH when the path ends in .bvh, joint positions as JSON otherwise. */
function writeDance(path, library, clipId, grid) {
  const info = library.clip(clipId);
  if (path.toLowerCase().endsWith(".bvh")) {
    const bvh = library.exportBvh(clipId);
    writeFileSync(path, bvh);
    return { frames: { length: info.frames }, joints: library.jointNames(clipId), bytes: bvh.length };
  }
  const fps = 30;
  const frames = [];
  for (let f = 0; f * (1 / fps) <= info.durationSecs; f++) frames.push(Array.from(library.jointPositions(clipId, f / fps), (x) => Math.round(x * 1e4) / 1e4));
  const out = { engine: version(), fps, bpm: grid.bpm, bars: grid.bars.length, durationSecs: info.durationSecs, joints: library.jointNames(clipId), bones: Array.from(library.bones(clipId)), frames };
  writeFileSync(path, JSON.stringify(out));
  return out;
}

const [songPath, outPath = "dance.json"] = process.argv.slice(2);
let channels, sampleRate;
if (songPath) {
  ({ channels, sampleRate } = decodeWav(new Uint8Array(readFileSync(songPath))));
} else {
  const demo = DemoSong.render(44100);
  channels = [demo.samples];
  sampleRate = demo.sampleRateHz;
}
// The project holds the dance: the song (its bytes and the loudness envelope the engine
// computes from the samples), its grid, and the moves by stable keys.
const project = new Project();
const env = rmsEnvelope(channels, sampleRate);
project.setSong(songPath ? basename(songPath) : "demo", songPath ? new Uint8Array(readFileSync(songPath)) : undefined, env.hopSecs, env.bands);
const grid = project.grid();
const { filled } = project.generate();
const library = new Library();
const dance = project.renderDance(library);
// `project.save()` gives the .odori file (the app and <odori-player> open it).
const out = writeDance(outPath, library, dance, grid);
console.log(`${songPath || "demo song"}: ${grid.bpm.toFixed(1)} BPM, ${grid.bars.length} bars, ${filled} filled with built-in moves → ${outPath} (${out.frames.length} frames × ${out.joints.length} joints)`);
