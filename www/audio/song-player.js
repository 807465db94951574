// Song playback through WebAudio. The AudioContext's clock is the one clock of the app while
// a song plays: the viewer asks `position()` every frame, so picture and sound stay together.
// A metronome clicks on the grid's beats (accent on downbeats), scheduled ahead on the audio
// clock so it is sample-accurate whatever the main thread is doing.

/** Decodes any format the browser can (mp3, ogg, wav, flac, m4a) at 44.1 kHz. */
export async function decodeSong(bytes, name) {
  const ctx = new OfflineAudioContext(1, 1, 44100);
  try {
    // decodeAudioData detaches its input: give it a copy.
    return await ctx.decodeAudioData(bytes.slice().buffer);
  } catch (e) {
    throw new Error(`${name}: this browser cannot decode the file as audio (${e && e.message ? e.message : e})`);
  }
}

/** An AudioBuffer from mono samples. */
export function bufferFromSamples(samples, sampleRate) {
  const b = new AudioBuffer({ numberOfChannels: 1, length: samples.length, sampleRate });
  b.copyToChannel(samples, 0);
  return b;
}

export class SongPlayer {
  constructor() {
    this.ctx = null;
    this.buffer = null;
    this.source = null;
    this.startTime = 0;   // ctx time at which song position 0 would have played
    this.pausedAt = 0;    // song position while stopped
    this.metronome = false;
    this.beats = [];      // [timeSecs, isDownbeat]
    this.timer = null;
    this.nextBeat = 0;
    this.onEnded = null;
    this.generation = 0;  // bumped by every play/stop: a play that was overtaken while the context resumed does not start
  }

  context() {
    if (!this.ctx) this.ctx = new AudioContext({ latencyHint: "interactive" });
    return this.ctx;
  }

  load(buffer) {
    this.stop();
    this.buffer = buffer;
    this.pausedAt = 0;
  }

  setGrid(grid) {
    const down = new Set(grid.downbeatTimesSecs.map((t) => t.toFixed(4)));
    this.beats = grid.beatTimesSecs.map((t) => [t, down.has(t.toFixed(4))]);
    if (this.playing) this.rescheduleFrom(this.position());
  }

  get playing() { return this.source != null; }
  get duration() { return this.buffer ? this.buffer.duration : 0; }

  /** Song position in seconds, from the audio clock. */
  position() {
    if (!this.playing) return this.pausedAt;
    return Math.min(this.duration, this.ctx.currentTime - this.startTime);
  }

  async play(fromSecs = this.pausedAt) {
    if (!this.buffer) return;
    const ctx = this.context();
    const generation = ++this.generation;
    if (ctx.state === "suspended") await ctx.resume();
    // Paused (or played again) while the audio context woke up: the later call wins.
    if (generation !== this.generation) return;
    this.stop(false);
    this.generation = generation;
    const src = new AudioBufferSourceNode(ctx, { buffer: this.buffer });
    src.connect(ctx.destination);
    const when = ctx.currentTime + 0.05;
    const from = Math.max(0, Math.min(fromSecs, this.duration));
    src.start(when, from);
    this.startTime = when - from;
    this.source = src;
    src.onended = () => {
      if (this.source === src) {
        this.source = null;
        this.pausedAt = 0;
        clearInterval(this.timer);
        if (this.onEnded) this.onEnded();
      }
    };
    this.rescheduleFrom(from);
    this.timer = setInterval(() => this.schedule(), 50);
  }

  stop(remember = true) {
    this.generation++;
    if (this.source) {
      if (remember) this.pausedAt = this.position();
      const s = this.source;
      this.source = null;
      try { s.stop(); } catch { /* already stopped */ }
    }
    clearInterval(this.timer);
    this.timer = null;
  }

  seek(secs) {
    if (this.playing) this.play(secs); else this.pausedAt = Math.max(0, Math.min(secs, this.duration));
  }

  rescheduleFrom(pos) {
    this.nextBeat = this.beats.findIndex(([t]) => t >= pos - 1e-3);
    if (this.nextBeat < 0) this.nextBeat = this.beats.length;
  }

  // Clicks for the next 200 ms, on the audio clock.
  schedule() {
    if (!this.playing || !this.metronome) return;
    const ctx = this.ctx;
    const horizon = ctx.currentTime + 0.2;
    while (this.nextBeat < this.beats.length) {
      const [t, down] = this.beats[this.nextBeat];
      const at = this.startTime + t;
      if (at > horizon) break;
      this.nextBeat++;
      if (at < ctx.currentTime) continue;
      const osc = new OscillatorNode(ctx, { frequency: down ? 1760 : 1175 });
      const gain = new GainNode(ctx, { gain: 0 });
      gain.gain.setValueAtTime(0, at);
      gain.gain.linearRampToValueAtTime(down ? 0.5 : 0.3, at + 0.002);
      gain.gain.exponentialRampToValueAtTime(0.001, at + 0.06);
      osc.connect(gain).connect(ctx.destination);
      osc.start(at);
      osc.stop(at + 0.07);
    }
  }
}
