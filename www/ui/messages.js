// Messages: each one shows at once as a toast over the page, where the person is looking
// (a broken file, a refused tempo, "filled 41 bars"), and is kept in the Messages log. Errors
// stay until dismissed; information and warnings fade after a few seconds. Nothing modal.
// A toast answers something the person just did: what the page says while it shows a stored
// project again (a reload, Open…, a Recent pick: `replay`) was said when it was done, so then
// only errors are toasts and the rest goes to the log; `note` is for the log only (a detail
// worth keeping, not worth interrupting for).
const FADE_MS = { info: 5000, warning: 9000 };
const MAX_TOASTS = 4;

export class Messages {
  constructor(list, toasts = null) {
    this.list = list;
    this.toasts = toasts;
    /** How many `replay`s are running: while any is, only errors are toasts. */
    this.replaying = 0;
  }

  /** Runs `f` (async: showing a stored project again) with its messages kept in the log, errors still toasts. */
  async replay(f) {
    this.replaying++;
    try { return await f(); } finally { this.replaying--; }
  }

  /**
   * Adds a message to the log and, unless `toast` is false or a replay is running (errors
   * always), shows it as a toast.
   */
  add(kind, text, { toast = true } = {}) {
    const li = document.createElement("li");
    li.className = kind;
    li.textContent = text;
    this.list.prepend(li);
    while (this.list.children.length > 30) this.list.lastChild.remove();
    if (this.toasts && (kind === "error" || (toast && this.replaying === 0))) this.toast(kind, text);
    if (kind === "error") console.warn(text);
    return li;
  }

  toast(kind, text) {
    const t = document.createElement("div");
    t.className = `toast ${kind}`;
    // Errors interrupt screen readers; the rest waits its turn.
    t.setAttribute("role", kind === "error" ? "alert" : "status");
    const span = document.createElement("span");
    span.textContent = text;
    const close = document.createElement("button");
    close.type = "button";
    close.className = "toast-close";
    close.textContent = "×";
    close.setAttribute("aria-label", "Dismiss");
    close.addEventListener("click", () => t.remove());
    t.append(span, close);
    this.toasts.append(t);
    // Old information makes way for new; errors are only dropped by the person.
    const infos = [...this.toasts.children].filter((c) => !c.classList.contains("error"));
    if (this.toasts.children.length > MAX_TOASTS && infos.length) infos[0].remove();
    if (kind !== "error") setTimeout(() => t.remove(), FADE_MS[kind] ?? 5000);
    return t;
  }

  error(text) { return this.add("error", text); }
  warning(text) { return this.add("warning", text); }
  info(text) { return this.add("info", text); }
  /** Information for the log only (no toast). */
  note(text) { return this.add("info", text, { toast: false }); }
}
