// Put the clip on screen on a character, and export it.
// *Character*: any imported skinned humanoid (glTF); *Put on* plays the clip on screen (the
// dance, a text animation, a move, a BVH) on it as a new library clip, drawn skinned.
// Export the clip on screen (an imported clip, a text animation, the composed dance) as a GLB
// (with the character's mesh, or the built-in body for the engine's own skeleton), a VRM
// animation (.vrma, for VRM avatars) or a BVH file, through the engine's exporters; the browser downloads the bytes. Errors go to the
// message list with the engine's words; nothing in the library changes.
export class ExportPanel {
  /** `wear(clipId, characterId)` → ClipInfo and `onCharacter(id | null)` may be set by the page. */
  constructor({ button, format, character, putOn, library, player, messages, onAdded }) {
    this.library = library;
    this.player = player;
    this.messages = messages;
    this.format = format;
    this.character = character;
    this.onAdded = onAdded;
    button.addEventListener("click", () => this.exportSelected());
    if (character && putOn) {
      character.addEventListener("focus", () => this.refreshCharacters());
      character.addEventListener("pointerdown", () => this.refreshCharacters());
      putOn.addEventListener("click", () => this.putOnCharacter());
      character.addEventListener("change", () => { if (this.onCharacter) this.onCharacter(this.character.value === "" ? null : Number(this.character.value)); });
      this.refreshCharacters();
    }
  }

  /** Lists the library's skinned humanoid characters (one entry per file). */
  refreshCharacters() {
    const keep = this.character.value;
    const seen = new Set();
    const items = this.library.clips().filter((c) => c.hasMesh && c.humanoid.kind !== "notHumanoid" && c.format === "gltf" && !seen.has(c.source) && seen.add(c.source));
    this.character.replaceChildren(new Option(items.length ? "Character…" : "Character: import a skinned glTF", ""));
    for (const c of items) this.character.append(new Option(c.source.replace(/^.*[\\/]/, ""), String(c.id)));
    if ([...this.character.options].some((o) => o.value === keep)) this.character.value = keep;
  }

  /** Shows `id` (a library clip of a character, null: none) as the chosen character. */
  showCharacter(id) {
    this.refreshCharacters();
    this.character.value = id == null ? "" : String(id);
  }

  putOnCharacter() {
    const id = this.player.clip;
    const character = Number(this.character.value);
    if (id == null || !this.character.value) { this.messages.warning("Put on: choose a character (an imported skinned glTF) and a clip."); return null; }
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
      const bytes = kind === "bvh" ? this.library.exportBvh(id) : kind === "vrma" ? this.library.exportVrma(id) : this.library.exportGlb(id);
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
