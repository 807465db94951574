// `.odori` files in and out of the page: Save as through the File System Access API where the
// browser has it (a real "Save as" dialog), a download otherwise; Open through the file picker
// (same API, else an <input type=file>) or by dropping a file. The bytes are made and read by
// the engine (`Project.save()` / `Project.open()`), never here.

export const ODORI_TYPE = { description: "Odori project", accept: { "application/x-odori+zip": [".odori"] } };

/** A file name for a project name. */
export function fileNameFor(name) {
  const base = (name || "Untitled").replace(/[\\/:*?"<>|]+/g, "_").trim() || "Untitled";
  return base.endsWith(".odori") ? base : `${base}.odori`;
}

/** Writes `bytes`: `{ how: "picker" | "download", name }`, or null when the person cancelled. */
export async function saveBytes(bytes, suggestedName) {
  if (typeof window.showSaveFilePicker === "function") {
    let handle;
    try {
      handle = await window.showSaveFilePicker({ suggestedName, types: [ODORI_TYPE] });
    } catch (e) {
      if (e && e.name === "AbortError") return null;
      throw e;
    }
    const w = await handle.createWritable();
    await w.write(bytes);
    await w.close();
    return { how: "picker", name: handle.name };
  }
  const url = URL.createObjectURL(new Blob([bytes], { type: "application/x-odori+zip" }));
  const a = document.createElement("a");
  a.href = url;
  a.download = suggestedName;
  document.body.appendChild(a);
  a.click();
  a.remove();
  setTimeout(() => URL.revokeObjectURL(url), 10000);
  return { how: "download", name: suggestedName };
}

/** Asks for an .odori file: `{ name, bytes }`, or null when the person cancelled. */
export async function pickFile() {
  if (typeof window.showOpenFilePicker === "function") {
    let handles;
    try {
      handles = await window.showOpenFilePicker({ types: [ODORI_TYPE], multiple: false });
    } catch (e) {
      if (e && e.name === "AbortError") return null;
      throw e;
    }
    const f = await handles[0].getFile();
    return { name: f.name, bytes: new Uint8Array(await f.arrayBuffer()) };
  }
  return new Promise((resolve) => {
    const input = document.createElement("input");
    input.type = "file";
    input.accept = ".odori";
    input.addEventListener("change", async () => {
      const f = input.files && input.files[0];
      resolve(f ? { name: f.name, bytes: new Uint8Array(await f.arrayBuffer()) } : null);
    });
    input.click();
  });
}

/** True for a dropped file that is an .odori project (motion files are handled elsewhere). */
export function isOdoriFile(file) {
  return /\.odori$/i.test(file.name);
}
