// What the video export uses of Mediabunny: the build bundles only these (esbuild, tree-shaken)
// into www/video/mediabunny.js and pkg/video/mediabunny.js (crate/xtask, `build-web`).
export {
  Output, Mp4OutputFormat, WebMOutputFormat, BufferTarget, StreamTarget, VideoSampleSource, VideoSample, AudioBufferSource,
  canEncodeVideo, canEncodeAudio,
} from "mediabunny";
