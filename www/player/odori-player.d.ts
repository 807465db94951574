// Types of `odori/player`: the <odori-player> custom element.
import type { Library, ImportReport } from "./odori_player.js";

/** Detail of the `error` event. `kind` is an OdoriErrorKind, or "load" for a network/media failure. */
export interface OdoriPlayerErrorDetail {
  kind: string;
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

/** The player's own events (its `progress` and `error` are CustomEvents, as <model-viewer>'s). */
export interface OdoriPlayerEventMap {
  load: CustomEvent<{ clip: OdoriPlayerClip }>;
  progress: CustomEvent<OdoriPlayerProgressDetail>;
  error: CustomEvent<OdoriPlayerErrorDetail>;
  ended: CustomEvent<Record<string, never>>;
  firstpose: CustomEvent<{ ms: number; backend: "webgpu" | "webgl2" }>;
}

/**
 * `<odori-player src="dance.glb" animation-name="Dance" music="song.ogg" autoplay loop camera-controls poster="poster.png">`
 *
 * Attributes: `src` (GLB/glTF with animation or BVH; none: the engine's built-in routine), `music`
 * (audio URL or `#id` of an `<audio>`: its clock drives the figure), `animation-name`, `character`
 * ("auto" | "stick"), `autoplay`, `loop`, `camera-controls`, `poster`, `loading` ("lazy" | "eager"),
 * `backend` ("auto" | "webgpu" | "webgl2").
 */
export declare class OdoriPlayer extends HTMLElement {
  /** Where the player build's .wasm is, when a bundler moved it (default: beside odori_player.js). */
  static wasmUrl: string | URL | undefined;
  /** How far outside the viewport (CSS margin) a player loads and keeps its GPU context. */
  static nearMargin: string;
  /** Graphics back end for players without a `backend` attribute. */
  static backend: "auto" | "webgpu" | "webgl2";
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
  readonly audioElement: HTMLMediaElement | null;
  readonly clip: OdoriPlayerClip | null;
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

/** Turns a source's bytes into clips (the seam where `.odori` projects plug in). */
export declare function importSource(library: Library, fileName: string, bytes: Uint8Array): ImportReport;

declare global {
  interface HTMLElementTagNameMap {
    "odori-player": OdoriPlayer;
  }
}
