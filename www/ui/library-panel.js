// The library table: one row per clip with its facts; click selects, the checkbox overlays,
// × removes. Fixed columns so it always fits its panel (long names end in an ellipsis).
//
// The rows keep the order the person saw them in, and the selected clip, across a reload: a
// reopened project makes its clips again in another order (the demo clip, then its files,
// then what was made from them), so the order and the selection are kept by each clip's key
// (its source and name, which a reload makes again the same) in `view` (`load()` → `{ order,
// selected }`, `save(state)`; the page keeps it per project), and put back by `restore()`.
const fmt = (x, d = 2) => Number(x).toFixed(d);
/** A frame rate the same way everywhere: at most two decimals, no trailing zeros (60, 29.97). */
export const fmtFps = (fps) => String(Number(Number(fps).toFixed(2)));

function humanoidText(h) {
  switch (h.kind) {
    case "complete": return ["yes", "all 21 canonical joints"];
    case "partial": return ["partial", `missing: ${h.missing.join(", ")}`];
    default: return ["no", h.reason];
  }
}

/** Keys of clips: source and name, and a count for the same pair seen again (stable across a reload). */
function clipKeys(clips) {
  const seen = new Map();
  return clips.map((c) => {
    const base = `${c.source}\u0000${c.name}`;
    const n = (seen.get(base) || 0) + 1;
    seen.set(base, n);
    return n === 1 ? base : `${base}\u0000${n}`;
  });
}

export class LibraryPanel {
  constructor(tbody, library, { onSelect, onOverlay, onRemove, view = null }) {
    this.tbody = tbody;
    this.library = library;
    this.onSelect = onSelect;
    this.onOverlay = onOverlay;
    this.onRemove = onRemove;
    this.selected = null;
    this.overlays = new Set();
    /** Where the order and selection are kept (`{ load, save }`), or null. */
    this.view = view;
    /** The kept order of keys (read by `restore`); nothing is saved until `restore` has put the kept state back. */
    this.order = [];
    this.restored = !view;
    tbody.addEventListener("click", (ev) => {
      const tr = ev.target.closest("tr");
      if (!tr || ev.target.matches("input")) return;
      if (ev.target.closest("button.remove")) { this.remove(Number(tr.dataset.id)); return; }
      this.select(Number(tr.dataset.id));
    });
    tbody.addEventListener("change", (ev) => {
      const tr = ev.target.closest("tr");
      if (!tr) return;
      const id = Number(tr.dataset.id);
      if (ev.target.checked) this.overlays.add(id); else this.overlays.delete(id);
      this.onOverlay([...this.overlays]);
    });
  }

  /** The library's clips in the kept order (clips not in it after, as the library lists them), with their keys. */
  ordered() {
    // Candidate previews are working clips of the dance panel, not the person's library.
    const clips = this.library.clips().filter((c) => c.source !== "candidate");
    const keys = clipKeys(clips);
    const rank = new Map(this.order.map((k, i) => [k, i]));
    const rows = clips.map((c, i) => ({ c, key: keys[i], i }));
    rows.sort((a, b) => (rank.get(a.key) ?? Infinity) - (rank.get(b.key) ?? Infinity) || a.i - b.i);
    return rows;
  }

  /** Keeps the order shown and the selection (by key). */
  save(rows) {
    if (!this.view || !this.restored) return;
    this.order = rows.map((r) => r.key);
    const sel = rows.find((r) => r.c.id === this.selected);
    this.view.save({ order: this.order, selected: sel ? sel.key : null });
  }

  /**
   * After a reopened project is shown: the kept order, and the kept selection (if that clip is
   * back); from now on changes are kept. Returns the selected id, or null.
   */
  restore() {
    const kept = this.view ? this.view.load() : null;
    if (kept && Array.isArray(kept.order)) this.order = kept.order;
    this.restored = true;
    this.refresh();
    const row = kept && kept.selected != null ? this.ordered().find((r) => r.key === kept.selected) : null;
    if (row) this.select(row.c.id);
    return row ? row.c.id : null;
  }

  refresh() {
    const ordered = this.ordered();
    this.save(ordered);
    const rows = ordered.map(({ c }) => {
      const tr = document.createElement("tr");
      tr.dataset.id = c.id;
      const [hum, why] = humanoidText(c.humanoid);
      const cells = [[c.name, "name"], [c.source, "source"], [fmtFps(c.fps), "num"], [c.frames, "num"], [fmt(c.durationSecs), "num"], [c.joints, "num"]];
      for (const [v, cls] of cells) {
        const td = document.createElement("td");
        td.textContent = v;
        td.className = cls;
        tr.append(td);
      }
      tr.children[0].title = `${c.name} — ${c.source}`;
      tr.children[1].title = c.source;
      tr.children[3].className = "num frames";
      tr.children[4].title = `${c.frames} frames`;
      const h = document.createElement("td");
      h.textContent = hum;
      h.title = why;
      h.className = `hum-${c.humanoid.kind}`;
      tr.append(h);
      const o = document.createElement("td");
      const box = document.createElement("input");
      box.type = "checkbox";
      box.checked = this.overlays.has(c.id);
      box.setAttribute("aria-label", `Overlay ${c.name}`);
      o.append(box);
      tr.append(o);
      const r = document.createElement("td");
      const del = document.createElement("button");
      del.type = "button";
      del.className = "remove";
      del.textContent = "×";
      del.title = `Remove ${c.name} from the library`;
      del.setAttribute("aria-label", `Remove ${c.name}`);
      r.append(del);
      tr.append(r);
      if (c.id === this.selected) tr.classList.add("selected");
      return tr;
    });
    this.tbody.replaceChildren(...rows);
  }

  /** Removes a clip; the selection moves to a neighbour. */
  remove(id) {
    const ids = [...this.tbody.children].map((tr) => Number(tr.dataset.id));
    const at = ids.indexOf(id);
    this.overlays.delete(id);
    if (this.onRemove) this.onRemove(id);
    this.refresh();
    if (this.selected === id) {
      const rest = ids.filter((x) => x !== id);
      this.selected = null;
      if (rest.length) this.select(rest[Math.min(at, rest.length - 1)]);
    }
    this.onOverlay([...this.overlays]);
  }

  select(id) {
    this.selected = id;
    for (const tr of this.tbody.children) tr.classList.toggle("selected", Number(tr.dataset.id) === id);
    if (this.restored) this.save(this.ordered());
    this.onSelect(id);
  }
}
