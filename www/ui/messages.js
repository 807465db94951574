// Messages: each one shows at once as a toast over the page, where the person is looking
// (a broken file, a refused tempo, "filled 41 bars"), and is kept in the Messages log. Errors
// stay until dismissed; information and warnings fade after a few seconds. Nothing modal.
const FADE_MS = { info: 5000, warning: 9000 };
const MAX_TOASTS = 4;

export class Messages {
  constructor(list, toasts = null) {
    this.list = list;
    this.toasts = toasts;
  }

  add(kind, text) {
    const li = document.createElement("li");
    li.className = kind;
    li.textContent = text;
    this.list.prepend(li);
    while (this.list.children.length > 30) this.list.lastChild.remove();
    if (this.toasts) this.toast(kind, text);
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
}
