// Playback: a clock in seconds drives the viewer; play, pause, scrub by frame, loop; the
// selected clip plus any overlaid ones, each in its own colour; orbit by drag, zoom by wheel.
// This is the app's one transport: `playing` (and `withSong`) are the single source of truth
// for the figure, the dance and the song. While the song sounds its audio clock drives the
// figure; Pause (button or space) stops both, Play resumes both; the buttons only show state.
//
// The drawing budget: the animation loop draws only what a person can see change. A paused
// figure is not drawn again (the camera, when it moves, is drawn at the next animation frame);
// a playing one at every display frame (the viewer interpolates between a clip's frames), except
// under `maxFps` (set by the page on a software adapter, where each frame costs the CPU whole
// milliseconds: see www/main.js), where it draws at most `maxFps` times a second and no faster
// than the fastest shown clip's own frame rate. Scrubs, steps and edits still draw at once.
export class Player {
  constructor({ viewer, library, canvas, scrub, label, playButton, loop }) {
    Object.assign(this, { viewer, library, canvas, scrub, label, playButton, loop });
    this.clip = null;
    this.overlays = [];
    this.time = 0;
    this.playing = true;
    this.last = null;
    this.onFirstFrame = null;
    this.songClock = null;
    this.compare = null;
    this.onTick = null;
    this.drawnOnce = false;
    this.stick = false;         // stick figures even when a character is chosen
    this.preparing = null;      // the task that makes clips left by a draw (`preparePending`)
    this.withSong = false;      // does Play also play the song?
    this.listeners = [];        // called with the transport state after every change
    this.maxFps = null;         // cap on animation draws per second (null: none)
    this.poseFps = Infinity;    // fastest frame rate among the clips shown (Infinity: unknown)
    this.dueMs = 0;             // the animation loop's next draw is due (rAF clock)
    this.cameraMoved = false;   // paused, the camera moved: draw at the next allowed frame
    this.onDrawRate = null;     // told `{ maxFps }` when the cap changes (the page's status)
    playButton.addEventListener("click", () => this.toggle());
    scrub.addEventListener("input", () => {
      this.pause();
      this.time = Number(scrub.value) / this.info().fps;
      this.drawNow();
    });
    window.addEventListener("keydown", (ev) => {
      // A focused control owns its keys: space on a button presses that button (Tap, Loop…),
      // arrows move a slider; only keys aimed at the page drive the transport.
      if (ev.target.closest && ev.target.closest("input, textarea, select, button, summary, a[href], [contenteditable], dialog")) return;
      if (ev.ctrlKey || ev.metaKey || ev.altKey) return;
      if (ev.code === "Space") { ev.preventDefault(); this.toggle(); }
      if (ev.code === "ArrowRight") { this.step(1); }
      if (ev.code === "ArrowLeft") { this.step(-1); }
    });
    this.bindCamera();
  }

  /** What the clock runs over: the selected clip, or a search comparison. */
  info() {
    if (this.compare) return { fps: 60, frames: Math.round(this.compare.duration * 60) + 1 };
    return this.library.clip(this.clip);
  }

  figures() {
    const style = this.stick ? { style: "stick" } : {};
    if (this.compare) return this.compare.figures(this.time).map((f) => ({ ...f, ...style }));
    const ids = [this.clip, ...this.overlays.filter((id) => id !== this.clip)];
    return ids.map((id) => ({ clip: id, timeSecs: this.time, ...style }));
  }

  /**
   * The body humanoid clips without a mesh of their own are drawn on: "builtin", an imported
   * character's clip id, or null (stick figures). Throws the engine's error when that
   * character cannot dance (the view keeps its body).
   */
  setCharacter(character) {
    this.viewer.setCharacter(this.library, character);
    this.reframe();
    this.drawNow();
  }

  /** Stick figures instead of the character (one click away), or the character again. */
  setStick(on) {
    this.stick = on;
    this.reframe();
    this.drawNow();
  }

  /** Plays a comparison: `{ duration, figures(t) }` (the search's overlay view). */
  setCompare(spec) {
    this.compare = spec;
    this.time = 0;
    // Candidates are played sped up or slowed to the music: their frames come faster than
    // their clips' rates, so only the cap (if any) limits them.
    this.poseFps = Infinity;
    this.scrub.max = String(Math.max(0, this.info().frames - 1));
    this.viewer.frameFigures(this.library, this.figures());
    // Candidates loop on their own clock, or on the song's when it already sounds.
    if (!(this.songClock && this.songClock.playing)) this.withSong = false;
    this.play();
    this.drawNow();
  }

  select(id) {
    this.compare = null;
    this.clip = id;
    this.time = 0;
    const c = this.info();
    this.updatePoseFps();
    this.scrub.max = String(Math.max(0, c.frames - 1));
    this.viewer.frameFigures(this.library, this.figures());
    this.drawNow();
  }

  /** The fastest frame rate among the clips shown (the selected clip and its overlays). */
  updatePoseFps() {
    const ids = [this.clip, ...this.overlays].filter((id) => id != null);
    let fps = 0;
    for (const id of new Set(ids)) {
      try { fps = Math.max(fps, this.library.clip(id).fps); } catch { /* removed: not shown */ }
    }
    this.poseFps = fps > 0 ? fps : Infinity;
  }

  /**
   * The animation loop's draws per second under `cap`: with a cap (a software adapter), also no
   * faster than the fastest shown clip's frames; uncapped, every display frame (a GPU draws the
   * poses interpolated between a clip's frames at no cost a person feels, and they look smoother).
   */
  drawRate(cap) {
    return cap < Infinity ? Math.min(cap, this.poseFps) : Infinity;
  }

  /** Caps animation draws at `fps` per second (null: no cap, as fast as the display). */
  setMaxFps(fps) {
    this.maxFps = fps > 0 && Number.isFinite(fps) ? fps : null;
    this.dueMs = 0;
    if (this.onDrawRate) this.onDrawRate({ maxFps: this.maxFps });
  }

  /**
   * Whether the animation loop may draw at `nowMs` (a rAF timestamp) at most `fps` times a
   * second. The due time advances by whole intervals, so a frame that comes a little late
   * does not push every later one back (a 60 Hz display then draws exactly every other frame
   * at 30); 2 ms of slack takes up the jitter of the timestamps.
   */
  frameDue(nowMs, fps) {
    if (!(fps < Infinity)) return true;
    const intervalMs = 1000 / fps;
    if (nowMs < this.dueMs - 2) return false;
    this.dueMs = nowMs - this.dueMs > intervalMs ? nowMs + intervalMs : this.dueMs + intervalMs;
    return true;
  }

  /** Frames the figures again (the view changed shape). */
  reframe() {
    if (this.clip != null) this.viewer.frameFigures(this.library, this.figures());
  }

  /** Nothing selected (the last clip was removed): an empty stage. */
  clear() {
    this.compare = null;
    this.clip = null;
    this.overlays = [];
    this.time = 0;
    this.scrub.max = "0";
    this.label.textContent = "0 / 0";
    this.viewer.draw(this.library, []);
  }

  setOverlays(ids) {
    this.overlays = ids;
    if (this.clip == null) return;
    if (!this.compare) this.updatePoseFps();
    this.viewer.frameFigures(this.library, this.figures());
    this.drawNow();
  }

  /** The song player whose clock drives the figure while it sounds. */
  attachSong(songPlayer) {
    this.songClock = songPlayer;
    // The song ran out: the transport stops (the figure does not run on alone).
    songPlayer.onEnded = () => { this.playing = false; this.render(); };
  }

  /** Called with `{ playing, withSong, songPlaying }` after every change. */
  onChange(fn) { this.listeners.push(fn); fn(this.state()); }

  state() {
    return { playing: this.playing, withSong: this.withSong, songPlaying: this.playing && this.withSong };
  }

  render() {
    this.playButton.textContent = this.playing ? "Pause" : "Play";
    this.playButton.dataset.state = this.playing ? "playing" : "paused";
    const st = this.state();
    for (const fn of this.listeners) fn(st);
  }

  toggle() { this.playing ? this.pause() : this.play(); }

  /** Plays the figure, and the song with it when the transport is in song mode. */
  play() {
    this.playing = true;
    this.last = null;
    const song = this.songClock;
    if (this.withSong && song && song.buffer && !song.playing) song.play();
    this.render();
  }

  /** Pauses the figure and the song together. */
  pause() {
    const wasPlaying = this.playing;
    this.playing = false;
    if (this.songClock && this.songClock.playing) this.songClock.stop();
    // Under the drawing cap the last instant the loop reached may not have been drawn: a
    // paused figure (and the frame counter) show exactly where it stopped.
    if (wasPlaying) this.drawNow();
    this.render();
  }

  /** Plays figure and song together, from `fromSecs` of the song (default: where it is). */
  playSong(fromSecs) {
    if (!this.songClock || !this.songClock.buffer) return;
    this.withSong = true;
    this.playing = true;
    this.last = null;
    this.songClock.play(fromSecs ?? this.songClock.position());
    this.render();
  }

  /** The song button: pauses everything while the song sounds, else plays with the song. */
  toggleSong() {
    if (this.playing && this.withSong) { this.pause(); this.withSong = false; this.render(); }
    else this.playSong();
  }

  step(frames) {
    this.pause();
    const c = this.info();
    this.time = Math.min(Math.max(0, this.time + frames / c.fps), (c.frames - 1) / c.fps);
    this.drawNow();
  }

  bindCamera() {
    let drag = null;
    this.canvas.addEventListener("pointerdown", (ev) => { drag = { x: ev.clientX, y: ev.clientY }; this.canvas.setPointerCapture(ev.pointerId); });
    this.canvas.addEventListener("pointermove", (ev) => {
      if (!drag) return;
      const r = this.canvas.getBoundingClientRect();
      this.viewer.orbit((ev.clientX - drag.x) / r.width, (ev.clientY - drag.y) / r.height);
      drag = { x: ev.clientX, y: ev.clientY };
      this.cameraMoved = true;
    });
    this.canvas.addEventListener("pointerup", () => { drag = null; });
    this.canvas.addEventListener("wheel", (ev) => {
      ev.preventDefault();
      this.viewer.zoom(Math.sign(ev.deltaY));
      this.cameraMoved = true;
    }, { passive: false });
  }

  drawNow() {
    this.cameraMoved = false;
    if (this.clip == null) return;
    const c = this.info();
    const frame = Math.min(c.frames - 1, Math.floor(this.time * c.fps + 1e-4));
    this.scrub.value = String(frame);
    this.label.textContent = `${frame} / ${c.frames - 1}`;
    this.viewer.draw(this.library, this.figures());
    // The project's face track keys morphs the drawn MMD model lacks: said once per set of names.
    if (this.onMissingMorphs && this.library.mmdModels && this.viewer.lastDrawn) {
      const missing = [...new Set(this.viewer.lastDrawn().flatMap((d) => d.missingMorphs || []))];
      const key = missing.join("、");
      if (key && key !== this.missingMorphsSaid) this.onMissingMorphs(missing);
      this.missingMorphsSaid = key;
    }
    this.preparePending();
    if (!this.drawnOnce) {
      this.drawnOnce = true;
      if (this.onFirstFrame) this.onFirstFrame();
    }
  }

  /**
   * A long clip on the chosen body (the dance onto a character) is not made inside a frame:
   * the viewer draws it as it was until then and lists it (`bodiesPending`); it is made here,
   * a clip per task between frames, then framed and drawn.
   */
  preparePending() {
    if (this.preparing || !this.viewer.bodiesPending) return;
    this.preparing = setTimeout(() => {
      this.preparing = null;
      if (this.viewer.prepareBodies(this.library)) {
        this.reframe();
        this.drawNow();
      } else {
        this.preparePending();
      }
    }, 0);
  }

  start() {
    const tick = (now) => {
      if (this.onTick) this.onTick();
      const cap = this.maxFps ?? Infinity;
      if (this.songClock && this.songClock.playing && this.clip != null) {
        // A song is playing: its audio clock drives the figure (the clip loops under it).
        const c = this.info();
        const end = (c.frames - 1) / c.fps;
        const t = this.songClock.position() - (this.compare && this.compare.songStart != null ? this.compare.songStart : 0);
        this.time = end > 0 ? ((t % end) + end) % end : 0;
        if (this.frameDue(now, this.drawRate(cap))) this.drawNow();
      } else if (this.playing && this.clip != null) {
        const dt = this.last == null ? 0 : (now - this.last) / 1000;
        this.last = now;
        const c = this.info();
        const end = (c.frames - 1) / c.fps;
        this.time += Math.min(dt, 0.1);
        let ended = false;
        if (this.time > end) {
          if (this.loop.checked) this.time = end > 0 ? this.time % end : 0;
          else { this.time = end; this.pause(); ended = true; }
        }
        // The last frame of a clip that stops is always drawn.
        if (ended || this.frameDue(now, this.drawRate(cap))) this.drawNow();
      } else {
        this.last = null;
        // Paused: draw when the camera moved, or while the viewer holds a frame for a
        // character's textures being decoded (it is never shown untextured).
        if ((this.cameraMoved || this.viewer.waitingForTextures) && this.frameDue(now, cap)) this.drawNow();
      }
      if (this.playing) this.cameraMoved = false;
      requestAnimationFrame(tick);
    };
    requestAnimationFrame(tick);
  }
}
