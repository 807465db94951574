// Opening motion files by picker or drag and drop. Reading shows progress; a bad file gets
// a message naming the file and the problem, and the library keeps what it had. Import
// options belong to one file: when BVH files are opened, a dialog shows a row per file with
// its own frame rate (read from its header) and units, and what is chosen there is used for
// that file only (and kept with it in the project, so a reload imports it the same way).
// glTF and GLB files state their units (metres) and key times themselves: nothing to ask.
// Which files are taken, and the message for any other, come from the engine's list
// (`importFormats()`, passed in as `formats`): the page keeps no list of its own.
const BVH = /\.bvh$/i;
// MikuMikuDance: motions (VMD), models (PMX/PMD) and a zip of them go to `importFiles` as one
// set; the files beside a model (its textures, any image MMD uses) come along when a model or
// zip is in the batch.
const MMD_TEXTURES = ["bmp", "tga", "png", "jpg", "jpeg", "spa", "sph", "dds"];

/** A file name's extension, lower case, without the dot ("" for none). */
const extensionOf = (name) => (/\.([^./\\]+)$/.exec(name)?.[1] ?? "").toLowerCase();

/**
 * The page's file filters from the engine's `importFormats()` (`{ name, extension, mmd, alone }[]`):
 * `accepts(name)` (a file the engine imports on its own), `isMmd(name)` (goes to `importFiles`
 * with its set), `isMmdModel(name)` (a model or zip: its textures come along), the file input's
 * `accept` list, and `message(name)`: a file of any other kind named, with every format listed.
 */
export function fileFormats(formats) {
  const list = [...formats];
  const plain = new Set(list.filter((f) => !f.mmd).map((f) => f.extension));
  const mmd = new Set(list.filter((f) => f.mmd).map((f) => f.extension));
  const names = list.map((f) => f.name);
  const spoken = names.length > 1 ? `${names.slice(0, -1).join(", ")} or ${names[names.length - 1]}` : names.join("");
  return {
    accepts: (name) => plain.has(extensionOf(name)),
    isMmd: (name) => mmd.has(extensionOf(name)),
    // A model, or a zip that may hold one: an MMD file the importer does not read alone.
    isMmdModel: (name) => list.some((f) => f.mmd && !f.alone && f.extension === extensionOf(name)),
    isMmdTexture: (name) => MMD_TEXTURES.includes(extensionOf(name)),
    accept: [...list.map((f) => f.extension), ...MMD_TEXTURES].map((e) => `.${e}`).join(","),
    message: (name) => `${name}: not a file Odori reads (it reads ${spoken})`,
  };
}

/** Units a BVH file may be in: metres per file unit ("" = guessed from the skeleton's size). */
const UNITS = [["", "guess from the rig"], ["0.01", "centimetres"], ["1", "metres"], ["0.001", "millimetres"], ["0.0254", "inches"]];

/**
 * The frame rate a BVH file's header states (1 / "Frame Time"), or null when the header cannot
 * be read. Only a default for the dialog: the engine's parser reads the file itself.
 */
export function bvhHeaderFps(bytes) {
  // The MOTION header follows the hierarchy, which is a few kilobytes even for big skeletons.
  const head = new TextDecoder().decode(bytes.subarray(0, 1 << 18));
  const m = head.match(/\bMOTION\s+Frames:\s*\d+\s+Frame\s+Time:\s*([0-9.eE+-]+)/);
  const secs = m ? Number(m[1]) : NaN;
  return secs > 0 && Number.isFinite(1 / secs) ? 1 / secs : null;
}

export class FileLoader {
  constructor({ library, messages, status, optionsDialog, onImported, onFiles, importer, cameraImporter, faceImporter, formats }) {
    // `importer(fileName, bytes, options)` → import report: who parses the file (the app's
    // project, which shows its clips in the library); the library's own import otherwise.
    // `cameraImporter(fileName, bytes, options)` → camera track info: who keeps a camera VMD
    // (the app's project, which shows it in `library.cameraTracks()`); the library otherwise.
    // `faceImporter(fileName, bytes, options)` → face track info: who keeps a lip-sync VMD (face
    // keys only) as the project's face track; without it the library lists it (not refused).
    // `optionsDialog`: the `<dialog>` asking each BVH file's options (index.html #import-options).
    // `formats`: the engine's `importFormats()`, what files are taken (see `fileFormats`).
    Object.assign(this, { library, messages, status, optionsDialog, onImported, onFiles, importer, cameraImporter, faceImporter });
    this.formats = fileFormats(formats);
    this.queue = Promise.resolve();
  }

  bindInput(input) {
    input.accept = this.formats.accept;
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

  /**
   * Reads `files`, asks each BVH file's options (one dialog for the batch), then imports them
   * in order. Resolves when done; a cancelled dialog imports none of the batch.
   */
  openAll(files) {
    if (this.onFiles) files = this.onFiles(files);
    if (!files.length) return this.queue;
    // A batch that fails as a whole is reported, and the next batch still runs.
    this.queue = this.queue.then(() => this.openBatch(files)).catch((e) => this.messages.error(`Opening files failed: ${e && e.message ? e.message : e}`));
    return this.queue;
  }

  async openBatch(files) {
    const read = [];
    // MMD files go to the library's importFiles as one set (a model needs its textures).
    const withModel = files.some((f) => this.formats.isMmdModel(f.name));
    const mmd = files.filter((f) => this.formats.isMmd(f.name) || (withModel && this.formats.isMmdTexture(f.name)));
    if (mmd.length) {
      await this.openMmd(mmd);
      files = files.filter((f) => !mmd.includes(f));
    }
    for (const file of files) {
      if (!this.formats.accepts(file.name)) {
        this.messages.error(this.formats.message(file.name));
        continue;
      }
      try {
        read.push({ file, bytes: await this.read(file) });
      } catch (e) {
        this.messages.error(`${file.name}: cannot be read (${e && e.message ? e.message : e})`);
      }
    }
    this.status.textContent = "";
    const options = await this.askOptions(read);
    if (!options) {
      this.messages.info(`Import cancelled: ${read.map((r) => r.file.name).join(", ")} not added`);
      return;
    }
    for (let i = 0; i < read.length; i++) await this.open(read[i].file, read[i].bytes, options[i]);
  }

  /**
   * The options of each read file: `{ fpsOverride?, unitScale?, headerFps? }`, from the dialog
   * when a BVH file is among them (null when the person cancels it), else none.
   */
  askOptions(read) {
    const dialog = this.optionsDialog;
    const rows = read.map(({ file, bytes }) => (BVH.test(file.name) ? { name: file.name, headerFps: bvhHeaderFps(bytes) } : null));
    if (!dialog || !rows.some(Boolean)) return Promise.resolve(read.map(() => ({})));
    const body = dialog.querySelector("tbody");
    body.replaceChildren();
    const inputs = rows.map((row) => {
      if (!row) return null;
      const tr = document.createElement("tr");
      tr.dataset.file = row.name;
      const name = document.createElement("th");
      name.scope = "row";
      name.textContent = row.name;
      const fpsCell = document.createElement("td");
      const fps = Object.assign(document.createElement("input"), { type: "number", className: "import-fps", min: "0.1", max: "1000", step: "any", placeholder: "file's" });
      fps.setAttribute("aria-label", `Frame rate of ${row.name}, frames per second`);
      // The file's own rate as the default, to two decimals (1 / 0.008333 s reads 120).
      if (row.headerFps) fps.value = String(Number(row.headerFps.toFixed(2)));
      const said = document.createElement("small");
      said.textContent = row.headerFps ? `file says ${Number(row.headerFps.toFixed(2))}` : "header unreadable";
      fpsCell.append(fps, said);
      const unitCell = document.createElement("td");
      const units = Object.assign(document.createElement("select"), { className: "import-units" });
      units.setAttribute("aria-label", `Units of ${row.name}`);
      for (const [value, label] of UNITS) units.append(new Option(label, value));
      unitCell.append(units);
      tr.append(name, fpsCell, unitCell);
      body.append(tr);
      return { fps, units };
    });
    return new Promise((resolve) => {
      dialog.addEventListener("close", () => {
        if (dialog.returnValue !== "import") return resolve(null);
        resolve(rows.map((row, i) => {
          if (!row) return {};
          const o = { headerFps: row.headerFps };
          const fps = Number(inputs[i].fps.value);
          // Left at the file's own (as shown, rounded): no override, the file's exact rate.
          const shown = row.headerFps ? Number(row.headerFps.toFixed(2)) : null;
          if (inputs[i].fps.value !== "" && fps > 0 && fps !== shown) o.fpsOverride = fps;
          if (inputs[i].units.value) o.unitScale = Number(inputs[i].units.value);
          return o;
        }));
      }, { once: true });
      dialog.returnValue = "";
      dialog.showModal();
    });
  }

  /**
   * Imports a set of MikuMikuDance files. A VMD dance given as a file of its own becomes a
   * source of the project like a BVH (`importer`: kept with the project on this device, cut into
   * segments Generate and search use, posed on Odori's standard MMD skeleton, starting at its
   * song offset); a camera VMD given as a file of its own or inside a zip becomes a camera motion
   * of the project (`cameraImporter`: kept with the project, offered as the video's camera);
   * models, textures and zips go to `library.importFiles` as one set (a model needs its
   * textures). When a dance is opened a dialog asks its song offset (the motion frame that is
   * song time 0) and, for a dance inside a zip or when a model is given or in the library, the
   * model it plays on (a project dance keeps that model's file — one given with it, or the one
   * the library kept — and is posed on it and drawn with its mesh again when the project is
   * reopened).
   * Problems name their file; the rest still imports.
   */
  async openMmd(files) {
    let set = [];
    for (const file of files) {
      try {
        // A dropped folder's files keep their folder path, so textures resolve beside the model.
        set.push({ name: file.webkitRelativePath || file.name, bytes: await this.read(file) });
      } catch (e) {
        this.messages.error(`${file.name}: cannot be read (${e && e.message ? e.message : e})`);
      }
    }
    this.status.textContent = "";
    if (!set.length || typeof this.library.importFiles !== "function") return null;
    let options = {};
    let toProject = [];
    let cameras = [];
    let lipSyncs = [];
    let setModels = [];
    try {
      const seen = this.library.inspectMmdFiles(set);
      // Models given in this set: a project dance can keep one of them (its bytes are here).
      setModels = seen.filter((f) => f.kind === "model" && !f.error);
      const libraryModels = this.library.mmdModels().map((m) => m.name);
      const models = [...libraryModels, ...seen.filter((f) => f.kind === "model" && !f.error).map((f) => f.modelName)];
      const dances = seen.filter((f) => f.kind === "vmd" && !f.error && f.boneKeys > 0);
      // A dance given as its own file goes into the project (a zip's stays in the library).
      if (this.importer) toProject = dances.filter((d) => set.some((f) => f.name === d.file));
      // So does a camera VMD (camera keys, no bone keys), given as its own file or inside a zip:
      // a zip holding one is opened here, the camera goes to the project and the zip's other
      // files to the library as one set, named as importFiles names them ("zip name/entry").
      // A lip-sync VMD (face keys only) is offered as the project's face track the same way.
      if (this.cameraImporter || this.faceImporter) {
        const isCamera = (f) => f.kind === "vmd" && !f.error && f.cameraKeys > 0 && f.boneKeys === 0;
        const isLipSync = (f) => f.kind === "vmd" && !f.error && f.morphKeys > 0 && f.boneKeys === 0 && f.cameraKeys === 0;
        const wanted = (f) => (this.cameraImporter && isCamera(f)) || (this.faceImporter && isLipSync(f));
        const zipped = seen.filter((f) => wanted(f) && !set.some((s) => s.name === f.file));
        const opened = [];
        for (const z of set) {
          if (/\.zip$/i.test(z.name) && zipped.some((c) => c.file.startsWith(`${z.name}/`))) opened.push(...this.library.constructor.unzipMmd(z.name, z.bytes));
          else opened.push(z);
        }
        set = opened;
        if (this.cameraImporter) cameras = seen.filter((f) => isCamera(f) && set.some((s) => s.name === f.file));
        if (this.faceImporter) lipSyncs = seen.filter((f) => isLipSync(f) && set.some((s) => s.name === f.file));
      }
      if (dances.length || lipSyncs.length) {
        // A project dance can be posed on a model of the set or one kept in the library (whose file it keeps).
        const chosen = await this.askMmd(dances, [...new Set(models)], dances.length > 0 && (toProject.length < dances.length || setModels.length > 0 || libraryModels.length > 0), lipSyncs);
        if (!chosen) {
          this.messages.info(`Import cancelled: ${set.map((f) => f.name).join(", ")} not added`);
          return null;
        }
        const { lipSync = [], ...rest } = chosen;
        lipSyncs = lipSyncs.filter((l) => lipSync.includes(l.file));
        options = rest;
      }
    } catch (e) {
      this.messages.error(e && e.name === "OdoriError" ? e.message : `MMD files: ${e && e.message ? e.message : e}`);
      return null;
    }
    this.progress(`Importing ${set.length} MMD file${set.length === 1 ? "" : "s"}…`);
    await new Promise((r) => requestAnimationFrame(() => setTimeout(r, 0)));
    const rest = set.filter((f) => !toProject.some((d) => d.file === f.name) && !cameras.some((c) => c.file === f.name) && !lipSyncs.some((l) => l.file === f.name));
    let report = { motions: [], models: [], cameras: [], notices: [], problems: [] };
    try {
      if (rest.length) report = this.library.importFiles(rest, options);
    } catch (e) {
      this.status.textContent = "";
      this.messages.error(e && e.name === "OdoriError" ? e.message : `MMD files: ${e && e.message ? e.message : e}`);
      return null;
    }
    this.status.textContent = "";
    for (const p of report.problems) this.messages.error(p.message);
    for (const n of report.notices) this.messages.info(n);
    for (const m of report.models) {
      this.messages.info(`${m.file}: MMD model "${m.name}" added (${m.vertices} vertices, ${m.bones} bones, ${m.textures.length} textures)${m.characterId != null ? ": choose it in the Character list" : ""}`);
    }
    for (const t of report.faceTracks || []) {
      this.messages.info(`${t.source}: a lip-sync (${t.keys} face keys, no bone keys)${this.faceImporter ? "" : ": open it in the app to keep it as the project's face track"}`);
    }
    for (const m of report.motions) {
      this.messages.info(`${m.file}: dance added, posed on ${m.rig}${m.songOffsetFrames ? `, starting at motion frame ${m.songOffsetFrames} (song time 0)` : ""}`);
    }
    const clips = report.motions.map((m) => m.clip);
    if (clips.length) this.onImported({ clips, warnings: [] }, { mmd: true });
    let added = 0;
    for (const d of toProject) {
      const f = set.find((x) => x.name === d.file);
      const o = options.songOffsetFrames ? { songOffsetFrames: options.songOffsetFrames } : {};
      // The model chosen (or the one its header names), kept with the dance when given in this set.
      const name = options.model && options.model !== "standard" ? options.model : null;
      const m = name ? setModels.find((x) => x.modelName === name) : null;
      let mf = m ? set.find((x) => x.name === m.file) : null;
      // A model in the library (imported now or earlier): the library kept its file.
      if (name && !mf) {
        try {
          const lib = this.library.mmdModelFile(name);
          mf = { name: lib.fileName, bytes: lib.bytes };
        } catch {
          // not-found: said below
        }
      }
      if (name && !mf) this.messages.info(`${f.name}: model "${name}" is neither among the files given nor in the library, so the project cannot keep it: posed on Odori's standard MMD skeleton`);
      try {
        const r = this.importer(f.name, f.bytes, o, mf ? { fileName: mf.name, bytes: mf.bytes } : undefined);
        for (const w of r.warnings) this.messages.info(w.startsWith(f.name) ? w : `${f.name}: ${w}`);
        this.messages.info(`${f.name}: dance added to the project, posed on ${mf ? `model "${name}" (${mf.name}, kept in the project with the dance, with the textures found for it)` : "Odori's standard MMD skeleton"}${o.songOffsetFrames ? `, starting at motion frame ${o.songOffsetFrames} (song time 0)` : ""}`);
        this.onImported(r, { fileName: f.name, mmd: "project" });
        added++;
      } catch (e) {
        this.messages.error(e && e.name === "OdoriError" ? e.message : `${f.name}: ${e && e.message ? e.message : e}`);
      }
    }
    for (const c of cameras) {
      const f = set.find((x) => x.name === c.file);
      const o = options.songOffsetFrames ? { songOffsetFrames: options.songOffsetFrames } : {};
      try {
        const t = this.cameraImporter(f.name, f.bytes, o);
        this.messages.info(`${f.name}: camera motion added to the project (${t.keys} keys, ${t.durationSecs.toFixed(1)} s): choose "Camera VMD: ${t.name}" as the video's camera`);
        added++;
      } catch (e) {
        this.messages.error(e && e.name === "OdoriError" ? e.message : `${f.name}: ${e && e.message ? e.message : e}`);
      }
    }
    for (const l of lipSyncs) {
      const f = set.find((x) => x.name === l.file);
      const o = options.songOffsetFrames ? { songOffsetFrames: options.songOffsetFrames } : {};
      try {
        const t = this.faceImporter(f.name, f.bytes, o);
        const morphs = t.morphs.slice(0, 6).join(", ") + (t.morphs.length > 6 ? " …" : "");
        this.messages.info(`${f.name}: lip-sync added to the project (${t.keys} face keys of ${t.morphs.length} morphs: ${morphs}; ${t.durationSecs.toFixed(1)} s): the dance plays it when drawn on an MMD model`);
        added++;
      } catch (e) {
        this.messages.error(e && e.name === "OdoriError" ? e.message : `${f.name}: ${e && e.message ? e.message : e}`);
      }
    }
    if (added || report.motions.length || report.models.length) {
      this.messages.info("MMD files stay with you: MMD creators' terms usually forbid passing them on, so the project keeps them on this device (and in the .odori file you save for yourself) and a share link leaves them out.");
    }
    return report;
  }

  /**
   * The MMD dialog: the song offset and, when a dance plays from the library (`pickModel`: a
   * dance inside a zip), the model it plays on; null when cancelled.
   */
  askMmd(dances, models, pickModel = true, lipSyncs = []) {
    let dialog = document.getElementById("mmd-import");
    if (!dialog) {
      dialog = document.createElement("dialog");
      dialog.id = "mmd-import";
      dialog.setAttribute("aria-labelledby", "mmd-import-title");
      const form = document.createElement("form");
      form.method = "dialog";
      const title = Object.assign(document.createElement("h2"), { id: "mmd-import-title", textContent: "Import MMD dance" });
      const body = document.createElement("div");
      body.className = "mmd-rows";
      const buttons = document.createElement("p");
      buttons.append(Object.assign(document.createElement("button"), { value: "cancel", textContent: "Cancel" }), Object.assign(document.createElement("button"), { value: "import", textContent: "Import" }));
      form.append(title, body, buttons);
      dialog.append(form);
      document.body.append(dialog);
    }
    const body = dialog.querySelector(".mmd-rows");
    body.replaceChildren();
    const head = dances.map((d) => d.modelName).filter(Boolean);
    const model = Object.assign(document.createElement("select"), { className: "mmd-model" });
    model.setAttribute("aria-label", "Model the dance plays on");
    // The dance's own model first when it is here, else the standard skeleton.
    const own = dances.find((d) => d.modelFound);
    if (own) model.append(new Option(`${own.modelName} (the model it was made for)`, own.modelName));
    model.append(new Option("Odori's standard MMD skeleton", "standard"));
    for (const m of models) if (!own || m !== own.modelName) model.append(new Option(m, m));
    const offset = Object.assign(document.createElement("input"), { type: "number", className: "mmd-offset", min: "0", step: "1", value: "0" });
    offset.setAttribute("aria-label", "Motion frame that is song time 0");
    const names = dances.map((d) => `${d.file} (${d.lastFrame + 1} frames${head.length ? `, made for ${d.modelName || "no named model"}` : ""})`).join(", ");
    const l1 = document.createElement(pickModel ? "label" : "p");
    if (pickModel) l1.append(`Plays on: `, model);
    else l1.textContent = "The dance goes into the project's dance library, posed on Odori's standard MMD skeleton.";
    const l2 = document.createElement("label");
    l2.append(`Song offset: motion frame `, offset, ` is song time 0 (30 frames a second; WAVEFILE's is 160)`);
    dialog.querySelector("h2").textContent = dances.length ? "Import MMD dance" : "Import MMD lip-sync";
    // Each lip-sync (face keys only) offered as the project's face track, checked.
    const lips = lipSyncs.map((l) => {
      const box = Object.assign(document.createElement("input"), { type: "checkbox", className: "mmd-lip-sync", checked: true, value: l.file });
      const label = document.createElement("label");
      label.append(box, ` ${l.file}: lip-sync for this project (${l.morphKeys} face keys, no bone keys; played on the dance when it is drawn on an MMD model)`);
      return { box, label };
    });
    if (dances.length) body.append(Object.assign(document.createElement("p"), { textContent: names }), l1);
    body.append(l2, ...lips.map((l) => l.label));
    return new Promise((resolve) => {
      dialog.addEventListener("close", () => {
        if (dialog.returnValue !== "import") return resolve(null);
        const o = pickModel ? { model: model.value } : {};
        const f = Math.round(Number(offset.value));
        if (f > 0) o.songOffsetFrames = f;
        if (lips.length) o.lipSync = lips.filter((l) => l.box.checked).map((l) => l.box.value);
        resolve(o);
      }, { once: true });
      dialog.returnValue = "";
      dialog.showModal();
    });
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

  /** Imports one read file with its options; the report, or null after an error message. */
  async open(file, bytes, { fpsOverride, unitScale, headerFps } = {}) {
    try {
      this.progress(`Parsing ${file.name}…`);
      await new Promise((r) => requestAnimationFrame(() => setTimeout(r, 0)));
      const options = {};
      if (fpsOverride) options.fpsOverride = fpsOverride;
      if (unitScale) options.unitScale = unitScale;
      const report = this.importer ? this.importer(file.name, bytes, options) : this.library.importFile(file.name, bytes, options);
      for (const w of report.warnings) this.messages.warning(`${file.name}: ${w}`);
      const n = report.clips.length;
      const how = [];
      if (fpsOverride) how.push(`played at ${fpsOverride} fps${headerFps ? ` instead of the file's ${Number(headerFps.toFixed(2))}` : ""}`);
      if (unitScale) how.push(`in ${UNITS.find(([v]) => Number(v) === unitScale)?.[1] ?? `${unitScale} m units`}`);
      // A skinned humanoid is a character the person may want to dance: say where to choose it.
      const character = report.clips.some((c) => c.hasMesh && c.humanoid.kind !== "notHumanoid" && c.format === "gltf");
      if (character) how.push("a character: choose it in Character to dance on it");
      this.messages.info(`${file.name}: ${n} clip${n === 1 ? "" : "s"} added${how.length ? ` (${how.join(", ")})` : ""}`);
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
