// Put the clip on screen on a character, and export it.
// *Character*: the built-in body (the page opens on it), stick figures, or any imported skinned
// humanoid (glTF): the viewer draws the dance, the candidates and text animations on it
// (`onCharacter`; the *Stick* checkbox draws stick figures for a moment); *Put on* plays the clip on screen (the dance, a text animation, a move, a BVH) on an
// imported one as a new library clip, drawn skinned.
// *Export…* opens a dialog that names what it exports (the dance, bars a–b of it, or a clip),
// on whom (the chosen character or the built-in body, any VRM avatar, the skeleton written),
// in which format (GLB, VRMA, BVH: one entry each of EXPORT_FORMATS) and how large the file
// is, through the engine's exporters; the browser downloads those bytes. Errors go to the
// message list with the engine's words; nothing in the library changes.
import { VIDEO_FORMAT } from "../video/video-panel.js";

export class ExportPanel {
  /** `wear(clipId, characterId)` → ClipInfo may be set by the page (its project keeps the clip). */
  constructor({ button, format, character, putOn, library, player, messages, onAdded, onCharacter }) {
    this.library = library;
    this.player = player;
    this.messages = messages;
    this.format = format;
    this.character = character;
    this.onAdded = onAdded;
    this.onCharacter = onCharacter;
    if (button) this.bindDialog({ dialog: document.querySelector("#export-dialog"), button });
    if (character && putOn) {
      character.addEventListener("focus", () => this.refreshCharacters());
      character.addEventListener("pointerdown", () => this.refreshCharacters());
      putOn.addEventListener("click", () => this.putOnCharacter());
      character.addEventListener("change", () => this.characterChanged());
      this.refreshCharacters();
      // Nothing chosen yet: the built-in body (the page's project may show another choice).
      this.character.value = "builtin";
    }
  }

  /** Lists the library's skinned humanoid characters (one entry per file: glTF, MMD models). */
  refreshCharacters() {
    const keep = this.character.value;
    const seen = new Set();
    const items = this.library.clips().filter((c) => c.hasMesh && c.humanoid.kind !== "notHumanoid" && (c.format === "gltf" || c.format === "mmd") && !seen.has(c.source) && seen.add(c.source));
    this.character.replaceChildren(new Option("Built-in body", "builtin"), new Option("Stick figures", ""));
    for (const c of items) this.character.append(new Option(c.source.replace(/^.*[\\/]/, ""), String(c.id)));
    if ([...this.character.options].some((o) => o.value === keep)) this.character.value = keep;
  }

  /** The chosen body: "builtin", a character's clip id, or null (stick figures). */
  chosen() {
    const v = this.character.value;
    return v === "builtin" ? "builtin" : v ? Number(v) : null;
  }

  /** The viewer draws on the chosen body; one that cannot dance is refused with the engine's words. */
  characterChanged() {
    try {
      this.player.setCharacter(this.chosen());
      if (this.onCharacter) this.onCharacter(this.chosen());
    } catch (e) {
      this.messages.error(`Character: ${e.message}`);
      const had = this.player.viewer.character;
      this.character.value = had == null ? "" : String(had);
      // The page shows why; the body drawn is the one it had.
    }
  }

  /** Shows `id` (a library clip of a character, "builtin", null: stick figures) as the chosen
   * character, and draws on it (the page's project restoring its choice). */
  showCharacter(id) {
    this.refreshCharacters();
    this.character.value = id == null ? "" : String(id);
    try {
      this.player.setCharacter(this.chosen());
    } catch (e) {
      this.messages.error(`Character: ${e.message}`);
    }
  }

  putOnCharacter() {
    const id = this.player.clip;
    const character = this.chosen();
    if (id == null || typeof character !== "number") { this.messages.warning("Put on: choose a character (an imported skinned glTF) and a clip."); return null; }
    try {
      // `wear` (the page's project) keeps it; without one, the library alone holds it.
      const info = this.wear ? this.wear(id, character) : this.library.putOnCharacter(id, character);
      this.messages.info(`${info.name}: ready (drawn on the character; Export gives it with the character's mesh)`);
      if (this.onAdded) this.onAdded(info);
      return info;
    } catch (e) {
      this.messages.error(`Put on character failed: ${e.message}`);
      return null;
    }
  }

  /**
   * The Export dialog: what (the dance — the default when there is one —, bars a–b of it, or a
   * clip), on whom (the chosen character or the built-in body for GLB; any VRM avatar for
   * VRMA; the skeleton written for BVH), the format (one entry of EXPORT_FORMATS each), and the
   * file's size, from the very bytes Download saves. `dance()` (set by the page) gives
   * `{ id, bars: [{ startSecs, endSecs }] }` of the rendered dance, or null.
   */
  bindDialog({ dialog, button }) {
    this.dialog = dialog;
    const $ = (sel) => dialog.querySelector(sel);
    this.ui = { what: [...dialog.querySelectorAll("input[name=export-what]")], from: $("#export-bar-from"), to: $("#export-bar-to"), clip: $("#export-clip"), summary: $("#export-summary"), danceLabel: $("#export-dance-label"), go: $("#export-go") };
    this.format.replaceChildren(...EXPORT_FORMATS.map((f) => new Option(f.label, f.id)));
    button.addEventListener("click", () => this.open());
    const changed = () => this.update();
    for (const r of this.ui.what) r.addEventListener("change", changed);
    for (const el of [this.ui.from, this.ui.to, this.ui.clip, this.format]) el.addEventListener("input", changed);
    for (const el of [this.ui.from, this.ui.to]) el.addEventListener("focus", () => { this.ui.what.find((r) => r.value === "bars").checked = true; });
    this.ui.clip.addEventListener("change", () => { this.ui.what.find((r) => r.value === "clip").checked = true; changed(); });
    this.ui.go.addEventListener("click", (ev) => {
      ev.preventDefault();
      if (this.download()) dialog.close();
    });
  }

  /** Opens the dialog on the dance (when there is one), else the clip on screen. */
  open() {
    const dance = this.dance ? this.dance() : null;
    const onScreen = this.player.clip;
    const clips = this.library.clips().filter((c) => c.source !== "candidate" && (!dance || c.id !== dance.id));
    this.ui.clip.replaceChildren(...clips.map((c) => new Option(c.name, String(c.id))));
    if (clips.some((c) => c.id === onScreen)) this.ui.clip.value = String(onScreen);
    const danceRadio = this.ui.what.find((r) => r.value === "dance");
    const barsRadio = this.ui.what.find((r) => r.value === "bars");
    danceRadio.disabled = barsRadio.disabled = this.ui.from.disabled = this.ui.to.disabled = !dance;
    if (dance) {
      const n = dance.bars.length;
      Object.assign(this.ui.from, { max: String(n), value: "1" });
      Object.assign(this.ui.to, { max: String(n), value: String(n) });
      const d = this.library.clip(dance.id);
      this.ui.danceLabel.textContent = `The dance (bars 1–${n}, ${d.durationSecs.toFixed(1)} s)`;
    } else {
      this.ui.danceLabel.textContent = "The dance (none yet: Generate makes one)";
    }
    this.ui.what.find((r) => r.value === (dance ? "dance" : "clip")).checked = true;
    if (!dance && !clips.length) { this.messages.warning("Export: there is nothing to export yet."); return; }
    this.update();
    if (!this.dialog.open) this.dialog.showModal();
  }

  /**
   * What the dialog names now: `{ id, info, range, what, on, format, body }` (`range`: the
   * export's { startSecs, endSecs } or {}), or `{ error }`.
   */
  plan() {
    const what = this.ui.what.find((r) => r.checked)?.value || "clip";
    const format = EXPORT_FORMATS.find((f) => f.id === this.format.value) || EXPORT_FORMATS[0];
    const dance = this.dance ? this.dance() : null;
    let id, range = {}, label;
    if (what === "clip") {
      id = Number(this.ui.clip.value);
      if (!this.ui.clip.value || !this.library.clip(id)) return { error: "choose a clip" };
      label = this.library.clip(id).name;
    } else {
      if (!dance) return { error: "there is no dance yet (Generate makes one)" };
      id = dance.id;
      const n = dance.bars.length;
      if (what === "bars") {
        const a = Number(this.ui.from.value), b = Number(this.ui.to.value);
        if (!Number.isInteger(a) || !Number.isInteger(b) || a < 1 || b > n || a > b) return { error: `bars go from 1 to ${n}, the first not after the last` };
        range = { startSecs: dance.bars[a - 1].startSecs, endSecs: dance.bars[b - 1].endSecs };
        label = `bars ${a}–${b} of the dance`;
      } else {
        label = "the dance";
      }
    }
    const info = this.library.clip(id);
    // A humanoid clip with no mesh of its own goes out on the chosen character, else on the
    // built-in body (with stick figures on screen too: every GLB has a body).
    const chosen = this.chosen();
    const bodyless = !info.hasMesh && info.humanoid.kind !== "notHumanoid";
    const character = typeof chosen === "number" ? chosen : "builtin";
    const characterName = typeof chosen === "number" ? this.library.clip(chosen)?.source.replace(/^.*[\\/]/, "") || "the character" : "the built-in body";
    const ctx = { info, bodyless, character, characterName, library: this.library };
    return { id, info, range, what, label, format, ctx, on: format.on(ctx) };
  }

  /** The bytes the dialog would save (made again only when what it names changes). */
  bytesFor(plan) {
    const key = JSON.stringify([plan.id, this.library.clip(plan.id)?.frames, plan.range, plan.format.id, plan.ctx.character]);
    if (this.made && this.made.key === key) return this.made.bytes;
    const bytes = plan.format.make(this.library, plan.id, plan.range, plan.ctx);
    this.made = { key, bytes };
    return bytes;
  }

  update() {
    const plan = this.plan();
    this.ui.go.disabled = !!plan.error;
    if (plan.error) { this.ui.summary.textContent = `Nothing to export: ${plan.error}.`; return plan; }
    // A format made by its own dialog (the video) says what it will make instead of a size.
    if (plan.format.summary) { this.ui.summary.textContent = plan.format.summary(plan); delete this.ui.summary.dataset.bytes; return plan; }
    try {
      const bytes = this.bytesFor(plan);
      const secs = plan.range.endSecs != null ? plan.range.endSecs - plan.range.startSecs : plan.info.durationSecs;
      plan.fileName = this.fileName(plan);
      this.ui.summary.textContent = `${capital(plan.label)} (${secs.toFixed(1)} s) on ${plan.on}, as ${plan.format.label}: ${plan.fileName}, ${size(bytes.length)}.`;
      this.ui.summary.dataset.bytes = String(bytes.length);
    } catch (e) {
      this.ui.go.disabled = true;
      this.ui.summary.textContent = `${capital(plan.label)} cannot be exported as ${plan.format.label}: ${e.message}`;
    }
    return plan;
  }

  fileName(plan) {
    const base = plan.what === "clip" ? plan.info.name : plan.what === "bars" ? `${plan.info.name} ${plan.label.replace(/ of the dance$/, "")}` : plan.info.name;
    return `${base.replace(/[^\p{L}\p{N}_.-]+/gu, "_") || "odori"}.${plan.format.ext}`;
  }

  /** Saves what the dialog names; returns `{ name, bytes, plan }` or null (said why). */
  download() {
    const plan = this.plan();
    if (plan.error) { this.messages.warning(`Export: ${plan.error}.`); return null; }
    if (plan.format.run) return plan.format.run(this, plan);
    try {
      const bytes = this.bytesFor(plan);
      const name = this.fileName(plan);
      const url = URL.createObjectURL(new Blob([bytes], { type: plan.format.mime }));
      const a = document.createElement("a");
      a.href = url;
      a.download = name;
      document.body.append(a);
      a.click();
      a.remove();
      setTimeout(() => URL.revokeObjectURL(url), 10_000);
      this.messages.info(`Exported ${plan.label} on ${plan.on} as ${name} (${size(bytes.length)})`);
      this.last = { name, bytes, plan };
      return this.last;
    } catch (e) {
      this.messages.error(`Export of ${plan.label} failed: ${e.message}`);
      return null;
    }
  }
}

const capital = (s) => s.charAt(0).toUpperCase() + s.slice(1);
const size = (n) => (n < 1024 * 1024 ? `${Math.max(1, Math.round(n / 1024))} KiB` : `${(n / 1024 / 1024).toFixed(1)} MiB`);

/** Where a humanoid clip without a mesh of its own, exported as BVH, gets its skeleton from. */
function skeletonOf(info) {
  return info.format === "bvh" || info.format === "gltf" || info.format === "character" ? `its own skeleton (${info.joints} joints)` : "the canonical skeleton";
}

/**
 * The export formats, one entry each: adding a format (MMD's VMD, a video) is one entry here.
 * `on(ctx)` says on whom the motion goes out; `make(library, clipId, range, ctx)` gives the
 * file's bytes (`range`: `{ startSecs, endSecs }` or `{}`; `ctx`: `{ info, bodyless,
 * character, characterName }`).
 */
export const EXPORT_FORMATS = [
  {
    id: "glb", label: "GLB (glTF 2.0)", ext: "glb", mime: "model/gltf-binary",
    on: (c) => (c.bodyless ? c.characterName : c.info.hasMesh ? `its own character (${c.info.source.replace(/^.*[\\/]/, "")})` : skeletonOf(c.info)),
    make: (library, id, range, c) => library.exportGlb(id, { ...range, ...(c.bodyless ? { character: c.character } : {}) }),
  },
  {
    id: "vrma", label: "VRM animation (.vrma)", ext: "vrma", mime: "application/octet-stream",
    on: () => "any VRM avatar (VRM humanoid bones)",
    make: (library, id, range) => library.exportVrma(id, range),
  },
  {
    id: "bvh", label: "BVH (centimetres)", ext: "bvh", mime: "text/plain",
    on: (c) => skeletonOf(c.info),
    make: (library, id, range) => library.exportBvh(id, range),
  },
  {
    // MikuMikuDance (issue 28): MMD's standard bones, legs also as 足ＩＫ / つま先ＩＫ keys, fit to the
    // MMD model an imported VMD was posed on, else the first MMD model in the library, else
    // Odori's standard MMD skeleton.
    id: "vmd", label: "MikuMikuDance motion (.vmd)", ext: "vmd", mime: "application/octet-stream",
    on: (c) => `MMD's standard bones (${c.info.format === "vmd" ? "the MMD rig it was imported on" : vmdModel(c.library, c.info) ?? "Odori's standard MMD skeleton"})`,
    make: (library, id, range) => library.exportVmd(id, { ...range, ...(vmdModel(library, library.clip(id)) ? { model: vmdModel(library, library.clip(id)) } : {}) }),
  },
  // The dance as a video with its song (www/video/, issue 29).
  VIDEO_FORMAT,
];

/** The MMD model a VMD export fits: the clip's own (an imported VMD), else the library's first. */
function vmdModel(library, info) {
  if (!library || typeof library.mmdModels !== "function") return null;
  if (info && info.format === "vmd") return null; // exportVmd's default: the model it was posed on
  return library.mmdModels()[0]?.name ?? null;
}
