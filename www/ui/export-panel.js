// Put the clip on screen on a character, and export it.
// *Character*: the built-in body (the page opens on it), stick figures, or any imported skinned
// humanoid (glTF): the viewer draws the dance, the candidates and text animations on it
// (`onCharacter`; the *Stick* checkbox draws stick figures for a moment); *Put on* plays the clip on screen (the dance, a text animation, a move, a BVH) on an
// imported one as a new library clip, drawn skinned.
// Export the clip on screen (an imported clip, a text animation, the composed dance) as a GLB
// (with the character's mesh, or the built-in body for the engine's own skeleton), a VRM
// animation (.vrma, for VRM avatars) or a BVH file, through the engine's exporters; the browser downloads the bytes. Errors go to the
// message list with the engine's words; nothing in the library changes.
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
    button.addEventListener("click", () => this.exportSelected());
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

  /** Lists the library's skinned humanoid characters (one entry per file). */
  refreshCharacters() {
    const keep = this.character.value;
    const seen = new Set();
    const items = this.library.clips().filter((c) => c.hasMesh && c.humanoid.kind !== "notHumanoid" && c.format === "gltf" && !seen.has(c.source) && seen.add(c.source));
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

  exportSelected() {
    const id = this.player.clip;
    if (id == null) { this.messages.warning("Export: select a clip first."); return null; }
    const info = this.library.clip(id);
    const kind = ["bvh", "vrma"].includes(this.format.value) ? this.format.value : "glb";
    try {
      // A humanoid clip with no mesh of its own goes out on the chosen character, else on the
      // built-in body (with stick figures on screen too: every GLB has a body).
      const bodyless = !info.hasMesh && info.humanoid.kind !== "notHumanoid";
      const chosen = this.chosen();
      const bytes = kind === "bvh" ? this.library.exportBvh(id) : kind === "vrma" ? this.library.exportVrma(id)
        : this.library.exportGlb(id, bodyless ? { character: typeof chosen === "number" ? chosen : "builtin" } : undefined);
      const name = `${info.name.replace(/[^\p{L}\p{N}_.-]+/gu, "_") || "odori"}.${kind}`;
      const url = URL.createObjectURL(new Blob([bytes], { type: kind === "bvh" ? "text/plain" : "model/gltf-binary" }));
      const a = document.createElement("a");
      a.href = url;
      a.download = name;
      document.body.append(a);
      a.click();
      a.remove();
      setTimeout(() => URL.revokeObjectURL(url), 10_000);
      this.messages.info(`Exported ${info.name} as ${name} (${(bytes.length / 1024).toFixed(0)} KiB)`);
      return { name, bytes };
    } catch (e) {
      this.messages.error(`Export of ${info.name} failed: ${e.message}`);
      return null;
    }
  }
}
