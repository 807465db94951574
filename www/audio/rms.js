// The song's RMS envelope computed with WebAudio, exactly as the core defines it
// (crate/core/src/music/rms.rs: mono mix-down, four bands of cookbook biquads, frames of 2H
// samples centred every H = round(fs / 100) samples). Native tests compute the same in Rust.
const BANDS = [
  null,                                                         // 0 full: the mono mix
  { type: "lowpass",  frequency: 150,  Q: -3.0103, stages: 2 }, // 1 low
  { type: "bandpass", frequency: 800,  Q: 0.7,     stages: 1 }, // 2 mid
  { type: "highpass", frequency: 4000, Q: -3.0103, stages: 2 }, // 3 high
];

/** RMS envelope of an AudioBuffer: { hopSecs, bands: Float32Array[] }. */
export async function rmsEnvelope(buffer) {
  const fs = buffer.sampleRate, len = buffer.length;
  const ctx = new OfflineAudioContext({ numberOfChannels: BANDS.length, length: len, sampleRate: fs });
  ctx.destination.channelInterpretation = "discrete";
  const src = new AudioBufferSourceNode(ctx, { buffer });
  const mono = new GainNode(ctx, { channelCount: 1, channelCountMode: "explicit", channelInterpretation: "speakers" });
  const merge = new ChannelMergerNode(ctx, { numberOfInputs: BANDS.length });
  src.connect(mono);
  BANDS.forEach((b, i) => {
    let node = mono;
    for (let s = 0; b && s < b.stages; s++) {
      const f = new BiquadFilterNode(ctx, { type: b.type, frequency: b.frequency, Q: b.Q });
      node.connect(f);
      node = f;
    }
    node.connect(merge, 0, i);
  });
  merge.connect(ctx.destination);
  src.start(0);
  const out = await ctx.startRendering();
  const H = Math.max(1, Math.round(fs * 0.01)), N = Math.ceil(len / H);
  const bands = BANDS.map((_, i) => {
    const y = out.getChannelData(i), rms = new Float32Array(N);
    let prev = 0; // energy of the previous hop-long block
    for (let n = 0; n < N; n++) {
      let e = 0;
      for (let k = n * H, end = Math.min(len, k + H); k < end; k++) e += y[k] * y[k];
      rms[n] = Math.sqrt((prev + e) / (2 * H));
      prev = e;
    }
    return rms;
  });
  return { hopSecs: H / fs, bands };
}
