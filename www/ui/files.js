// Opening motion files by picker or drag and drop. Reading shows progress; a bad file gets
// a message naming the file and the problem, and the library keeps what it had. Import
// options (the BVH fps override) belong to one import: they are read when the files are
// chosen, said in the message of each file they changed, and then cleared, so a later file
// is never played at a rate meant for another.
const ACCEPT = /\.(bvh|glb|gltf)$/i;

export class FileLoader {
  constructor({ library, messages, status, fpsInput, onImported, onFiles, importer }) {
    // `importer(fileName, bytes, options)` → import report: who parses the file (the app's
    // project, which shows its clips in the library); the library's own import otherwise.
    Object.assign(this, { library, messages, status, fpsInput, onImported, onFiles, importer });
    this.queue = Promise.resolve();
  }

  bindInput(input) {
    input.addEventListener("change", () => {
      this.openAll([...input.files]);
      input.value = "";
    });
  }

  bindDrop(target, overlay) {
    let depth = 0;
    target.addEventListener("dragenter", (ev) => { ev.preventDefault(); depth++; overlay.hidden = false; });
    target.addEventListener("dragover", (ev) => ev.preventDefault());
    target.addEventListener("dragleave", () => { if (--depth <= 0) { depth = 0; overlay.hidden = true; } });
    target.addEventListener("drop", (ev) => {
      ev.preventDefault();
      depth = 0;
      overlay.hidden = true;
      this.openAll([...ev.dataTransfer.files]);
    });
  }

  openAll(files) {
    if (this.onFiles) files = this.onFiles(files);
    const fps = Number(this.fpsInput.value);
    const options = { fpsOverride: fps > 0 ? fps : undefined };
    if (files.length) this.fpsInput.value = "";
    for (const f of files) this.queue = this.queue.then(() => this.open(f, options));
    return this.queue;
  }

  async read(file) {
    const total = file.size || 1;
    const reader = file.stream().getReader();
    const chunks = [];
    let got = 0;
    for (;;) {
      const { done, value } = await reader.read();
      if (done) break;
      chunks.push(value);
      got += value.length;
      this.progress(`Reading ${file.name}`, got / total);
    }
    const bytes = new Uint8Array(got);
    let at = 0;
    for (const c of chunks) { bytes.set(c, at); at += c.length; }
    return bytes;
  }

  progress(text, fraction) {
    this.status.replaceChildren(document.createTextNode(`${text} `));
    if (fraction != null) {
      const bar = document.createElement("span");
      bar.className = "progress";
      const fill = document.createElement("i");
      fill.style.width = `${Math.round(fraction * 100)}%`;
      bar.append(fill);
      this.status.append(bar);
    }
  }

  async open(file, { fpsOverride } = {}) {
    if (!ACCEPT.test(file.name)) {
      this.messages.error(`${file.name}: not a motion file Odori reads (BVH, glTF or GLB)`);
      return null;
    }
    try {
      const bytes = await this.read(file);
      this.progress(`Parsing ${file.name}…`);
      await new Promise((r) => requestAnimationFrame(() => setTimeout(r, 0)));
      const bvh = /\.bvh$/i.test(file.name);
      const options = fpsOverride && bvh ? { fpsOverride } : {};
      const report = this.importer ? this.importer(file.name, bytes, options) : this.library.importFile(file.name, bytes, options);
      for (const w of report.warnings) this.messages.warning(`${file.name}: ${w}`);
      const n = report.clips.length;
      const how = options.fpsOverride ? ` (played at ${options.fpsOverride} fps, as stated for this import)` : "";
      this.messages.info(`${file.name}: ${n} clip${n === 1 ? "" : "s"} added${how}`);
      this.status.textContent = "";
      this.onImported(report, { fileName: file.name, bytes, options });
      return report;
    } catch (e) {
      this.status.textContent = "";
      // OdoriError messages start with the file name already.
      const text = e && e.name === "OdoriError" ? e.message : `${file.name}: ${e && e.message ? e.message : e}`;
      this.messages.error(text);
      return null;
    }
  }
}
