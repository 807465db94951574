// Types of `odori/player`: the <odori-player> custom element.
import type { Library, ImportReport, OdoriErrorKind, AdapterInfo } from "./odori_player.js";

/** Detail of the `error` event. `kind` is an OdoriErrorKind, or "load" for a network/media failure. */
export interface OdoriPlayerErrorDetail {
  kind: OdoriErrorKind | "load";
  message: string;
  file?: string;
}

/** Detail of the `progress` event (same shape as <model-viewer>'s). */
export interface OdoriPlayerProgressDetail {
  /** 0..1 of the source file fetched. */
  totalProgress: number;
}

/** What a clip is (see `ClipInfo` in `odori`). */
export interface OdoriPlayerClip {
  id: number;
  name: string;
  fps: number;
  frames: number;
  durationSecs: number;
}

/**
 * With a `.odori` src: the project's name, its song's file name, its character's file (or null),
 * and what `character="auto"` draws the dance on: the project's character, else the built-in
 * body (as the app does), or stick figures when the project chose them.
 */
export interface OdoriPlayerProject {
  name: string;
  song: string;
  character: string | null;
  body: "character" | "builtin" | "stick";
}

/** The player's own events (its `progress` and `error` are CustomEvents, as <model-viewer>'s). */
export interface OdoriPlayerEventMap {
  load: CustomEvent<{ clip: OdoriPlayerClip; project?: OdoriPlayerProject }>;
  progress: CustomEvent<OdoriPlayerProgressDetail>;
  error: CustomEvent<OdoriPlayerErrorDetail>;
  ended: CustomEvent<Record<string, never>>;
  firstpose: CustomEvent<{ ms: number; backend: "webgpu" | "webgl2" }>;
}

/**
 * `<odori-player src="dance.glb" animation-name="Dance" music="song.ogg" autoplay loop camera-controls poster="poster.png">`
 *
 * Attributes: `src` (GLB/glTF with animation, BVH, or a `.odori` project: its dance on its own
 * song; none: the engine's built-in routine), `music` (audio URL or `#id` of an `<audio>`: its
 * clock drives the figure), `animation-name`, `character` ("auto" | "stick" | "builtin" | URL of
 * a skinned humanoid GLB), `autoplay`, `loop`, `camera-controls`, `poster`, `loading`
 * ("lazy" | "eager"), `backend` ("auto" | "webgpu" | "webgl2"), `max-fps` (draws per second while
 * playing: a positive number, or "none"; default 30 on a software adapter, else uncapped).
 */
export declare class OdoriPlayer extends HTMLElement {
  /** Where the player build's .wasm is, when a bundler moved it (default: beside odori_player.js). */
  static wasmUrl: string | URL | undefined;
  /** The full engine's module (`odori.js`), loaded only for a `.odori` src; default `../odori.js`. */
  static fullEngineUrl: string | URL | undefined;
  /** The full engine's .wasm, when a bundler moved it (default: beside its module). */
  static fullEngineWasmUrl: string | URL | undefined;
  /** How far outside the viewport (CSS margin) a player loads and keeps its GPU context. */
  static nearMargin: string;
  /** Seconds the arrow keys seek (on the player or its slider). */
  static seekStepSecs: number;
  /** Graphics back end for players without a `backend` attribute. */
  static backend: "auto" | "webgpu" | "webgl2";
  /** Draws per second while playing on a software adapter (no GPU), for players without `max-fps` (30). */
  static softwareMaxFps: number;
  static readonly observedAttributes: string[];

  src: string | null;
  music: string | null;
  loop: boolean;
  autoplay: boolean;
  loading: "lazy" | "eager";
  /** Seconds: the song's position with music, else the clip's. */
  currentTime: number;
  /** Seconds: the song's length with music, else the clip's; NaN before loading. */
  readonly duration: number;
  readonly paused: boolean;
  readonly state: "idle" | "loading" | "ready" | "error";
  /** The back end while a GPU context is held, else null (off-screen players hold none). */
  readonly gpuContext: "webgpu" | "webgl2" | null;
  /** What the browser reports of the graphics adapter while a GPU context is held, else null. */
  readonly adapterInfo: AdapterInfo | null;
  /** Draws per second while playing (the `max-fps` attribute, else 30 on a software adapter); Infinity: no cap. Setting it sets the attribute. */
  maxFps: number;
  /** Frames put on screen so far (a draw that would repeat the last image is not one). */
  readonly framesDrawn: number;
  readonly audioElement: HTMLMediaElement | null;
  readonly clip: OdoriPlayerClip | null;
  /** With a `.odori` src: the project playing, else null. */
  readonly project: OdoriPlayerProject | null;
  /** The figure's points (metres; x, y, z each) at `clipTimeSecs` (default: the pose last drawn); null before loading. */
  jointPositions(clipTimeSecs?: number): Float32Array | null;
  /** The last drawn frame. */
  lastFrame: { songTimeSecs: number; clipTimeSecs: number } | null;
  /** Milliseconds from attach to the engine + source being ready and to the first drawn pose. */
  timings: { engineMs?: number; firstPoseMs?: number };

  /** Starts playing (after loading); with music, starts muted when autoplay with sound is blocked. */
  play(): Promise<void>;
  pause(): void;

  addEventListener<K extends keyof OdoriPlayerEventMap>(type: K, listener: (this: OdoriPlayer, ev: OdoriPlayerEventMap[K]) => unknown, options?: boolean | AddEventListenerOptions): void;
  addEventListener<K extends keyof HTMLElementEventMap>(type: K, listener: (this: OdoriPlayer, ev: HTMLElementEventMap[K]) => unknown, options?: boolean | AddEventListenerOptions): void;
  addEventListener(type: string, listener: EventListenerOrEventListenerObject, options?: boolean | AddEventListenerOptions): void;
}

/** Turns a motion file's bytes into clips (a `.odori` project is refused: the element opens those with the full engine). */
export declare function importSource(library: Library, fileName: string, bytes: Uint8Array): ImportReport;

declare global {
  interface HTMLElementTagNameMap {
    "odori-player": OdoriPlayer;
  }
}
