// The song's RMS envelope computed with WebAudio, as the core defines it (crate/core/src/music/
// rms.rs: mono mix-down, bands of cookbook biquads, frames of 2H samples centred every
// H = round(fs · hopTargetSecs) samples). The definition — the bands' filter types, frequencies,
// Q and stages, and the hop — comes from the engine (`envelopeDefinition()`), never restated
// here; WebAudio computes the filtering. Native tests compute the same in Rust.

/**
 * RMS envelope of an AudioBuffer: `{ hopSecs, bands: Float32Array[] }`, one band per
 * `definition.bands` entry, in its order. `definition` is the engine's `envelopeDefinition()`.
 */
export async function rmsEnvelope(buffer, definition) {
  const specs = definition?.bands;
  if (!Array.isArray(specs) || !specs.length || !(definition.hopTargetSecs > 0)) throw new Error("rmsEnvelope needs the engine's envelopeDefinition()");
  const fs = buffer.sampleRate, len = buffer.length;
  const ctx = new OfflineAudioContext({ numberOfChannels: specs.length, length: len, sampleRate: fs });
  ctx.destination.channelInterpretation = "discrete";
  const src = new AudioBufferSourceNode(ctx, { buffer });
  const mono = new GainNode(ctx, { channelCount: 1, channelCountMode: "explicit", channelInterpretation: "speakers" });
  const merge = new ChannelMergerNode(ctx, { numberOfInputs: specs.length });
  src.connect(mono);
  specs.forEach((b, i) => {
    let node = mono;
    // "full": the mono mix itself; otherwise `stages` identical BiquadFilterNodes of that type.
    for (let s = 0; b.kind !== "full" && s < Math.max(1, b.stages); s++) {
      const f = new BiquadFilterNode(ctx, { type: b.kind, frequency: b.frequencyHz, Q: b.q });
      node.connect(f);
      node = f;
    }
    node.connect(merge, 0, i);
  });
  merge.connect(ctx.destination);
  src.start(0);
  const out = await ctx.startRendering();
  const H = Math.max(1, Math.round(fs * definition.hopTargetSecs)), N = Math.ceil(len / H);
  const bands = specs.map((_, i) => {
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
