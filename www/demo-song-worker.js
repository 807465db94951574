// The built-in demo song is synthesised by the engine (a few seconds of work on a slow
// machine): here, off the UI thread, so the page answers input while it is made. The samples
// go back as a transferred Float32Array.
import init, { DemoSong } from "./pkg/odori.js";

self.onmessage = async (ev) => {
  try {
    await init();
    const demo = DemoSong.render(ev.data.sampleRateHz);
    const samples = demo.samples;
    const sampleRateHz = demo.sampleRateHz;
    demo.free();
    self.postMessage({ samples, sampleRateHz }, [samples.buffer]);
  } catch (e) {
    self.postMessage({ error: e && e.message ? e.message : String(e) });
  }
};
