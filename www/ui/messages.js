// The message list under the library: errors name the file and the problem; nothing modal.
export class Messages {
  constructor(list) { this.list = list; }
  add(kind, text) {
    const li = document.createElement("li");
    li.className = kind;
    li.textContent = text;
    this.list.prepend(li);
    while (this.list.children.length > 30) this.list.lastChild.remove();
    return li;
  }
  error(text) { return this.add("error", text); }
  warning(text) { return this.add("warning", text); }
  info(text) { return this.add("info", text); }
}
