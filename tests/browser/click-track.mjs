// A test signal with true beats, shared by the song-format tests.

/** A 16-bit mono WAV: a kick-like click on every beat at `bpm` (accented downbeats, 4/4) over quiet noise. */
export function clickTrackWav(bpm, secs, rate = 22050) {
  const n = Math.round(secs * rate);
  const pcm = new Int16Array(n);
  let seed = 5;
  const noise = () => { seed = (seed * 1664525 + 1013904223) >>> 0; return seed / 2 ** 32 - 0.5; };
  const beats = [];
  for (let t = 0.5; t < secs - 0.3; t += 60 / bpm) beats.push(t);
  const x = new Float32Array(n).map(() => 0.01 * noise());
  beats.forEach((t, k) => {
    const s0 = Math.round(t * rate), amp = k % 4 === 0 ? 0.9 : 0.5;
    for (let i = 0; i < 0.12 * rate && s0 + i < n; i++) {
      const s = i / rate;
      x[s0 + i] += amp * Math.sin(2 * Math.PI * (60 * s + 2.4 * (1 - Math.exp(-s / 0.02)))) * Math.exp(-s / 0.04) + 0.3 * amp * noise() * Math.exp(-s / 0.01);
    }
  });
  for (let i = 0; i < n; i++) pcm[i] = Math.max(-32767, Math.min(32767, Math.round(x[i] * 32767)));
  const b = Buffer.alloc(44 + n * 2);
  b.write("RIFF", 0); b.writeUInt32LE(36 + n * 2, 4); b.write("WAVE", 8); b.write("fmt ", 12);
  b.writeUInt32LE(16, 16); b.writeUInt16LE(1, 20); b.writeUInt16LE(1, 22); b.writeUInt32LE(rate, 24);
  b.writeUInt32LE(rate * 2, 28); b.writeUInt16LE(2, 32); b.writeUInt16LE(16, 34); b.write("data", 36); b.writeUInt32LE(n * 2, 40);
  Buffer.from(pcm.buffer).copy(b, 44);
  return { bytes: b, beats };
}
