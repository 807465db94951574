// The library table: one row per clip with its facts; click selects, the checkbox overlays.
const fmt = (x, d = 2) => Number(x).toFixed(d);

function humanoidText(h) {
  switch (h.kind) {
    case "complete": return ["yes", "all 21 canonical joints"];
    case "partial": return ["partial", `missing: ${h.missing.join(", ")}`];
    default: return ["no", h.reason];
  }
}

export class LibraryPanel {
  constructor(tbody, library, { onSelect, onOverlay }) {
    this.tbody = tbody;
    this.library = library;
    this.onSelect = onSelect;
    this.onOverlay = onOverlay;
    this.selected = null;
    this.overlays = new Set();
    tbody.addEventListener("click", (ev) => {
      const tr = ev.target.closest("tr");
      if (!tr || ev.target.matches("input")) return;
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

  refresh() {
    // Candidate previews are working clips of the dance panel, not the person's library.
    const rows = this.library.clips().filter((c) => c.source !== "candidate").map((c) => {
      const tr = document.createElement("tr");
      tr.dataset.id = c.id;
      const [hum, why] = humanoidText(c.humanoid);
      const cells = [c.name, c.source, fmt(c.fps, c.fps % 1 ? 2 : 0), c.frames, fmt(c.durationSecs), c.joints];
      for (const v of cells) {
        const td = document.createElement("td");
        td.textContent = v;
        tr.append(td);
      }
      tr.children[1].className = "source";
      tr.children[1].title = c.source;
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
      if (c.id === this.selected) tr.classList.add("selected");
      return tr;
    });
    this.tbody.replaceChildren(...rows);
  }

  select(id) {
    this.selected = id;
    for (const tr of this.tbody.children) tr.classList.toggle("selected", Number(tr.dataset.id) === id);
    this.onSelect(id);
  }
}
