// Share by link: a dance of built-in moves, written into the URL fragment (no server sees it),
// on the demo song or on a song file the person who opens the link picks again. Opening the
// link rebuilds the same dance: same bars, same moves.
//
// Format (version 2): `#dance=2.<song>.<bars>.<bar>.<bar>…`
// - `<song>`: `demo` (built into the engine: its bars are found again), or
//   `file~<name>~<duration ms>~<sha-256>` (name in base64url; the SHA-256 of the file's bytes,
//   hex). The song itself is never in the link: whoever opens it is asked for the file, which
//   is checked against the duration and the hash before anything is changed.
// - each bar: `-` (empty), or `p` (pinned) / `g` (generated) and the move's stable key
//   (`MoveKey`, the project's key type, spec §K) written `<step>~<arms>~<energy>~<L|R>`. Keys
//   name what a move is, not where it sits in a list, so a link survives a library that grows
//   or is ordered differently. A move cut from a person's own motion file would not exist on
//   another machine: such a dance cannot be linked (the message says which bar). A move from an
//   MMD file (VMD) is left out instead (an empty bar), and the page says so: MMD creators' terms
//   usually forbid passing their files on, so what comes from them never goes in a link.
// Opening: pinned bars are set, then Generate runs (deterministic: the same moves come back);
// any bar that still differs (another engine version) is set explicitly and reported.
// Version 1 links (`#dance=1.demo.…`, segment indices) are still read.

const PREFIX = "#dance=";
const VERSION = "2";
const DEMO = "demo";

const b64url = {
  encode: (text) => btoa(String.fromCharCode(...new TextEncoder().encode(text))).replace(/\+/g, "-").replace(/\//g, "_").replace(/=+$/, ""),
  decode: (s) => new TextDecoder().decode(Uint8Array.from(atob(s.replace(/-/g, "+").replace(/_/g, "/")), (c) => c.charCodeAt(0))),
};

/** A built-in move's key as a link token, and back. */
function moveToken(move) {
  return [move.step, move.arms, move.energy, move.mirrored ? "L" : "R"].join("~");
}
function tokenMove(token) {
  const m = /^([A-Za-z0-9]+)~([A-Za-z0-9]+)~([A-Za-z0-9]+)~([LR])$/.exec(token);
  return m ? { step: m[1], arms: m[2], energy: m[3], mirrored: m[4] === "L" } : null;
}

/** The SHA-256 of `bytes`, hex (the same digest a project names its blobs by). */
export async function sha256Hex(bytes) {
  if (!crypto.subtle) throw new Error("checking the song file needs a secure page (https or localhost)");
  const d = new Uint8Array(await crypto.subtle.digest("SHA-256", bytes));
  return Array.from(d, (b) => b.toString(16).padStart(2, "0")).join("");
}

/**
 * The link of the current dance. `song` is `{ demo: true }` or `{ name, durationSecs, sha256 }`
 * of the song file. Throws an Error naming the problem when the dance cannot be linked. Bars
 * dancing a move from an MMD file go in as empty bars, each pushed to `leftOut` as `{ bar, file }`.
 */
export function danceLink(choreographer, song, base = location.href, leftOut = []) {
  let songPart;
  if (song?.demo) songPart = DEMO;
  else if (song && song.name && song.durationSecs > 0 && /^[0-9a-f]{64}$/.test(song.sha256 || "")) {
    songPart = ["file", b64url.encode(song.name), Math.round(song.durationSecs * 1000), song.sha256].join("~");
  } else {
    throw new Error("the song is not known well enough to link it (open the song file again)");
  }
  const view = choreographer.view();
  if (!view.length) throw new Error("there is no dance yet");
  const items = view.map((v, i) => {
    if (v.state.kind === "empty") return "-";
    const seg = choreographer.segment(v.state.segment);
    // A move from an MMD file is left out (an empty bar), never carried: see `isMmdFile`.
    if (seg && !seg.builtin && isMmdFile(seg.source)) {
      leftOut.push({ bar: i, file: seg.source });
      return "-";
    }
    if (!seg || !seg.builtin) {
      throw new Error(`bar ${i + 1} holds "${seg ? seg.name : v.state.segment}", a move cut from your own file: links carry built-in moves only`);
    }
    return (v.state.kind === "pinned" ? "p" : "g") + moveToken(seg.builtin);
  });
  const url = new URL(base);
  url.hash = `dance=${[VERSION, songPart, view.length, ...items].join(".")}`;
  return url.href;
}

/**
 * Whether a source file is MikuMikuDance's (VMD, PMX, PMD): its creators' terms usually forbid
 * passing it on, so its moves stay with the person and a link leaves them out, saying so.
 */
export function isMmdFile(name) {
  return /\.(vmd|pmx|pmd)$/i.test(name || "");
}

/** What a link left out (the bars `danceLink` put in its `leftOut`), as one sentence. */
export function leftOutNote(leftOut) {
  const files = [...new Set(leftOut.map((l) => l.file))];
  const bars = leftOut.map((l) => l.bar + 1);
  return `The link leaves out bar${bars.length === 1 ? "" : "s"} ${bars.join(", ")}: ${bars.length === 1 ? "its move comes" : "their moves come"} from your MMD file${files.length === 1 ? "" : "s"} (${files.join(", ")}), and MMD files stay with you (their creators' terms usually forbid passing them on).`;
}

/**
 * Reads a link's fragment: `{ version, song, bars, items }`, null when there is none. `song` is
 * `{ demo: true }` or `{ name, durationSecs, sha256 }`; each item `{ kind: "empty" }` or
 * `{ kind: "pinned" | "generated", move }` (version 2: a built-in MoveInfo) / `segment` (version 1).
 */
export function parseDanceHash(hash) {
  if (!hash || !hash.startsWith(PREFIX)) return null;
  const [version, songPart, bars, ...rest] = hash.slice(PREFIX.length).split(".");
  if (version !== "1" && version !== VERSION) throw new Error(`this dance link is version ${version}, this app reads versions 1 and ${VERSION}`);
  let song;
  if (songPart === DEMO) song = { demo: true };
  else {
    const m = version === VERSION && /^file~([A-Za-z0-9_-]+)~(\d+)~([0-9a-f]{64})$/.exec(songPart || "");
    if (!m) throw new Error(`this dance link is damaged: its song ("${songPart}") is neither the demo song nor a song file's name, length and hash`);
    let name;
    try { name = b64url.decode(m[1]); } catch { throw new Error("this dance link is damaged: its song's name cannot be read"); }
    song = { name, durationSecs: Number(m[2]) / 1000, sha256: m[3] };
  }
  const n = Number(bars);
  if (!Number.isInteger(n) || n <= 0 || rest.length !== n) throw new Error(`this dance link is damaged: it says ${bars} bars and holds ${rest.length}`);
  const items = rest.map((s, i) => {
    if (s === "-") return { kind: "empty" };
    const kind = s[0] === "p" ? "pinned" : s[0] === "g" ? "generated" : null;
    if (version === "1") {
      const segment = parseInt(s.slice(1), 36);
      if (!kind || !/^[pg][0-9a-z]+$/.test(s) || !Number.isInteger(segment)) throw new Error(`this dance link is damaged at bar ${i + 1} ("${s}")`);
      return { kind, segment };
    }
    const move = kind && tokenMove(s.slice(1));
    if (!move) throw new Error(`this dance link is damaged at bar ${i + 1} ("${s}")`);
    return { kind, move };
  });
  return { version, song, bars: n, items };
}

/** Every built-in move's segment in this choreographer, by its token. */
function builtinSegments(choreographer) {
  const byToken = new Map();
  for (let i = 0; i < choreographer.segmentCount; i++) {
    const s = choreographer.segment(i);
    if (s?.builtin) byToken.set(moveToken(s.builtin), i);
  }
  return byToken;
}

/**
 * Rebuilds a parsed dance in the choreographer; returns the bars that had to be set by hand.
 * With a project's engine (`batch`), the whole link is one edit: one undo takes it back.
 */
export function applyDance(choreographer, dance) {
  return choreographer.batch ? choreographer.batch(() => applyDanceEdits(choreographer, dance)) : applyDanceEdits(choreographer, dance);
}

function applyDanceEdits(choreographer, dance) {
  const view = choreographer.view();
  if (view.length !== dance.bars) throw new Error(`the link was made for ${dance.bars} bars; the song here has ${view.length}`);
  const count = choreographer.segmentCount;
  const byToken = dance.version === "1" ? null : builtinSegments(choreographer);
  const segments = dance.items.map((it, i) => {
    if (it.kind === "empty") return null;
    if (!byToken) {
      if (it.segment >= count) throw new Error(`bar ${i + 1}: move ${it.segment} is not in this engine's library (${count} moves)`);
      return it.segment;
    }
    const seg = byToken.get(moveToken(it.move));
    if (seg === undefined) throw new Error(`bar ${i + 1}: the move "${moveToken(it.move)}" is not among this engine's built-in moves`);
    return seg;
  });
  dance.items.forEach((it, i) => { if (it.kind === "pinned") choreographer.set(i, segments[i]); });
  if (dance.items.some((it) => it.kind === "generated")) choreographer.generate();
  const fixed = [];
  const now = choreographer.view();
  dance.items.forEach((it, i) => {
    if (it.kind === "generated" && now[i].state.segment !== segments[i]) {
      choreographer.set(i, segments[i]);
      choreographer.unpin(i);
      fixed.push(i);
    }
  });
  return fixed;
}

const fmt = (s) => `${Math.floor(s / 60)}:${String(Math.round(s % 60)).padStart(2, "0")}`;

/**
 * Asks for the song file a link names (a small panel with a file chooser) and resolves to its
 * `{ name, bytes }` once a file with the same length and SHA-256 is given; a wrong file is
 * reported and another can be tried. Resolves to null when the person cancels.
 */
function askForSong(song, messages) {
  return new Promise((resolve) => {
    // Styled in style.css (the page's CSP allows no inline style).
    const box = document.createElement("div");
    box.id = "share-song";
    box.setAttribute("role", "dialog");
    box.setAttribute("aria-labelledby", "share-song-title");
    box.innerHTML = `<p id="share-song-title"></p>
      <p><label>Song file: <input id="share-song-input" type="file" accept="audio/*,.mp3,.ogg,.wav,.flac,.m4a"></label></p>
      <p id="share-song-problem" role="alert"></p>
      <button id="share-song-cancel" type="button">Cancel</button>`;
    box.querySelector("#share-song-title").textContent =
      `This dance link is on the song “${song.name}” (${fmt(song.durationSecs)}). The song is not in the link: choose that file on your machine to see the dance.`;
    const input = box.querySelector("#share-song-input");
    const problem = box.querySelector("#share-song-problem");
    input.addEventListener("change", async () => {
      const file = input.files?.[0];
      if (!file) return;
      try {
        const bytes = new Uint8Array(await file.arrayBuffer());
        const hash = await sha256Hex(bytes);
        if (hash !== song.sha256) {
          const text = `${file.name} is not the song of this link: its content differs (SHA-256 ${hash.slice(0, 12)}…, the link's ${song.sha256.slice(0, 12)}…). Choose “${song.name}”.`;
          problem.textContent = text;
          messages.error(`Dance link: ${text}`);
          document.body.dataset.shared = "wrong-song";
          input.value = "";
          return;
        }
        box.remove();
        resolve({ name: file.name, bytes });
      } catch (e) {
        problem.textContent = `${file.name}: ${e.message}`;
      }
    });
    box.querySelector("#share-song-cancel").addEventListener("click", () => { box.remove(); resolve(null); });
    document.body.append(box);
    document.body.dataset.shared = "asking-song";
    input.focus();
  });
}

/**
 * The app's hook: a *Share link* button beside Generate, and the dance of the page's own link
 * applied once the song's bars are in. `songReady` resolves when the page's first song (the
 * demo song) is in; `song()` says which song is loaded (`{ demo: true }` or `{ name,
 * durationSecs, sha256 }`); `loadSong(name, bytes)` loads a song file (true when loaded).
 */
export function installShare({ choreo, messages, songReady, song, loadSong }) {
  const share = {
    link: () => danceLink(choreo.choreographer, song()),
    applied: null,
  };
  const generate = choreo.root.querySelector("#dance-generate");
  if (generate) {
    // In the page from the start (its place kept: nothing moves when it is wired), else made here.
    let button = choreo.root.querySelector("#dance-share");
    if (!button) {
      button = document.createElement("button");
      button.type = "button";
      button.id = "dance-share";
      button.textContent = "Share link";
      button.title = "A link that opens this dance (built-in moves; a song file is asked for again)";
      generate.after(button);
    }
    button.addEventListener("click", async () => {
      try {
        const leftOut = [];
        const url = danceLink(choreo.choreographer, song(), location.href, leftOut);
        history.replaceState(null, "", url);
        if (leftOut.length) messages.info(`Share link: ${leftOutNote(leftOut)}`);
        try { await navigator.clipboard.writeText(url); messages.info("Link to this dance copied (it is also in the address bar)."); }
        catch { messages.info(`Link to this dance (also in the address bar): ${url}`); }
      } catch (e) {
        messages.error(`Share link: ${e.message}`);
      }
    });
    // Where Share is offered: a dance with moves from the person's own files cannot go in a
    // link (the files would not be on the other machine); say so and offer the .odori file.
    // In the page from the start, at the end of the Dance controls (shown, it adds a line below
    // them; boot.js may hold that line).
    const note = choreo.root.querySelector("#dance-share-note");
    const text = document.createElement("span");
    const save = document.createElement("button");
    save.type = "button";
    save.id = "dance-share-save";
    save.textContent = "Save the .odori file";
    save.title = "The project file holds your motion files too: whoever opens it sees this dance";
    save.addEventListener("click", () => document.getElementById("project-save")?.click());
    note.replaceChildren(text, save);
    choreo.root.addEventListener("dance-refresh", (e) => {
      const notes = (e.detail?.notes ?? []).filter((n) => n.segment != null && !n.builtin);
      const fileOf = (n) => choreo.choreographer.segment(n.segment)?.source ?? n.source;
      // Moves from MMD files are left out of the link (saying so); other own files block it.
      const mmd = notes.filter((n) => isMmdFile(fileOf(n)));
      const own = notes.filter((n) => !mmd.includes(n));
      note.hidden = notes.length === 0;
      button.disabled = own.length > 0;
      save.hidden = own.length === 0;
      if (!own.length && mmd.length) {
        text.textContent = `${leftOutNote(mmd.map((n) => ({ bar: n.bar, file: fileOf(n) })))} `;
        button.title = "A link that opens this dance without the bars from your MMD files";
      } else if (own.length) {
        const files = [...new Set(own.map((n) => n.source))];
        text.textContent = `A link cannot share this dance: ${own.length} bar${own.length === 1 ? "" : "s"} use${own.length === 1 ? "s" : ""} moves from your own file${files.length === 1 ? "" : "s"} (${files.join(", ")}), which a link cannot carry. Share the project file instead. `;
        button.title = "Links carry built-in moves only: this dance uses moves from your own files";
      } else {
        button.title = "A link that opens this dance (built-in moves; a song file is asked for again)";
      }
    });
  }
  share.applied = (async () => {
    let dance;
    try {
      dance = parseDanceHash(location.hash);
    } catch (e) {
      messages.error(`Dance link: ${e.message}`);
      document.body.dataset.shared = "error";
      return;
    }
    if (!dance) return;
    await songReady;
    try {
      if (!dance.song.demo) {
        const have = song();
        if (have.sha256 !== dance.song.sha256) {
          const file = await askForSong(dance.song, messages);
          if (!file) { messages.info("Dance link: no song chosen; the link's dance is not shown."); document.body.dataset.shared = "cancelled"; return; }
          if (!(await loadSong(file.name, file.bytes))) throw new Error(`${file.name} could not be loaded`);
        }
      } else if (!song().demo) {
        throw new Error("this link is on the demo song, and another song is open");
      }
      await choreo.prepareJoins();
      const fixed = applyDance(choreo.choreographer, dance);
      choreo.refresh();
      choreo.renderDance?.();
      if (fixed.length) messages.info(`Dance link: bars ${fixed.map((i) => i + 1).join(", ")} were set by hand (this engine generates them differently).`);
      document.body.dataset.shared = "applied";
    } catch (e) {
      messages.error(`Dance link: ${e.message}`);
      document.body.dataset.shared = "error";
    }
  })();
  return share;
}
