// Typed use of the npm package under `tsc --strict`: the full engine (`odori`) in a page and
// the element (`odori/player`). Checked by tests/node/package.test.mjs in a clean folder.
import init, { Library, Viewer, errorKinds, type ClipInfo, type FigureSpec, type OdoriError, type OdoriErrorKind } from "odori";
import { OdoriPlayer } from "odori/player";

/** Imports a file the person dropped and shows its first clip; returns it, or the error's kind. */
export async function showFirstClip(canvas: HTMLCanvasElement, file: File): Promise<ClipInfo | OdoriErrorKind> {
  await init();
  const library = new Library();
  try {
    const report = library.importFile(file.name, new Uint8Array(await file.arrayBuffer()), { gltfFps: 30 });
    const clip: ClipInfo = report.clips[0];
    const viewer = await Viewer.create(canvas, { backend: "auto" });
    const figures: FigureSpec[] = [{ clip: clip.id, timeSecs: 0, style: "auto" }];
    viewer.frameFigures(library, figures);
    const start = performance.now();
    const frame = (now: number): void => {
      viewer.draw(library, [{ clip: clip.id, timeSecs: ((now - start) / 1000) % clip.durationSecs }]);
      requestAnimationFrame(frame);
    };
    requestAnimationFrame(frame);
    return clip;
  } catch (e) {
    const err = e as OdoriError;
    const known: OdoriErrorKind[] = errorKinds();
    if (!known.includes(err.kind)) throw e;
    return err.kind;
  }
}

/** Adds a player synced to an <audio> of the page and reports its progress. */
export function addPlayer(parent: HTMLElement, src: string, audio: HTMLAudioElement): OdoriPlayer {
  const player = document.createElement("odori-player"); // typed OdoriPlayer
  player.src = src;
  audio.id ||= "odori-song";
  player.music = `#${audio.id}`;
  player.loop = true;
  player.setAttribute("camera-controls", "");
  player.addEventListener("progress", (e) => console.log(`loading ${Math.round(e.detail.totalProgress * 100)} %`));
  player.addEventListener("error", (e) => console.error(`${e.detail.kind}: ${e.detail.message}`));
  player.addEventListener("load", (e) => console.log(`${e.detail.clip.name}: ${e.detail.clip.durationSecs.toFixed(2)} s`));
  parent.append(player);
  const gpu: "webgpu" | "webgl2" | null = player.gpuContext;
  console.log(gpu, player.duration, player.paused);
  return player;
}

/** Plays a project saved by the app (`.odori`) on a character of the page's choosing. */
export function addProjectPlayer(parent: HTMLElement, odoriUrl: string, characterGlbUrl?: string): OdoriPlayer {
  const player = document.createElement("odori-player");
  player.src = odoriUrl; // its dance, on its own song
  player.setAttribute("character", characterGlbUrl ?? "builtin");
  OdoriPlayer.seekStepSecs = 2;
  player.addEventListener("load", (e) => {
    const project = e.detail.project;
    if (project) console.log(`${project.name} on ${project.song}`);
  });
  player.addEventListener("error", (e) => {
    const kind: OdoriErrorKind | "load" = e.detail.kind;
    console.error(kind === "not-odori" ? `${odoriUrl} is not a project` : e.detail.message);
  });
  player.addEventListener("ended", () => {
    const pose: Float32Array | null = player.jointPositions();
    if (pose) console.log(`ended with the head at y = ${pose[1].toFixed(2)} m`);
  });
  parent.append(player);
  return player;
}
