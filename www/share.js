// Share by link: a dance of built-in moves on the demo song, written into the URL fragment
// (no server sees it). Opening the link rebuilds the same dance: same bars, same moves.
//
// Format (version 1): `#dance=1.demo.<bars>.<bar>.<bar>…`, one item per bar: `-` (empty),
// `p<segment>` (pinned) or `g<segment>` (generated), segment indices in base 36. The bars
// themselves are not in the link: the demo song is built into the engine, so its bars are
// found again. Built-in moves have stable indices; a move cut from a person's own file would
// not exist on another machine, so such a dance cannot be linked (the message says which bar).
// Opening: pinned bars are set, then Generate runs (deterministic: the same moves come back);
// any bar that still differs (another engine version) is set explicitly and reported.

const PREFIX = "#dance=";
const VERSION = "1";

/** The link of the current dance. Throws an Error naming the problem when it cannot be linked. */
export function danceLink(choreographer, songName, base = location.href) {
  if (songName !== "demo") {
    throw new Error("only dances on the built-in demo song can be shared by link (a song you opened stays on your machine)");
  }
  const view = choreographer.view();
  if (!view.length) throw new Error("there is no dance yet");
  const items = view.map((v, i) => {
    if (v.state.kind === "empty") return "-";
    const seg = choreographer.segment(v.state.segment);
    if (!seg || seg.source !== "built-in") {
      throw new Error(`bar ${i + 1} holds "${seg ? seg.name : v.state.segment}", a move cut from your own file: links carry built-in moves only`);
    }
    return (v.state.kind === "pinned" ? "p" : "g") + v.state.segment.toString(36);
  });
  const url = new URL(base);
  url.hash = `dance=${[VERSION, "demo", view.length, ...items].join(".")}`;
  return url.href;
}

/** Reads a link's fragment: `{ song, bars, items: [{ kind, segment }] }`, null when there is none. */
export function parseDanceHash(hash) {
  if (!hash || !hash.startsWith(PREFIX)) return null;
  const parts = hash.slice(PREFIX.length).split(".");
  const [version, song, bars, ...rest] = parts;
  if (version !== VERSION) throw new Error(`this dance link is version ${version}, this app reads version ${VERSION}`);
  if (song !== "demo") throw new Error(`this dance link is for the song "${song}", which this app does not have`);
  const n = Number(bars);
  if (!Number.isInteger(n) || n <= 0 || rest.length !== n) throw new Error(`this dance link is damaged: it says ${bars} bars and holds ${rest.length}`);
  const items = rest.map((s, i) => {
    if (s === "-") return { kind: "empty" };
    const segment = parseInt(s.slice(1), 36);
    if (!/^[pg][0-9a-z]+$/.test(s) || !Number.isInteger(segment)) throw new Error(`this dance link is damaged at bar ${i + 1} ("${s}")`);
    return { kind: s[0] === "p" ? "pinned" : "generated", segment };
  });
  return { song, bars: n, items };
}

/** Rebuilds a parsed dance in the choreographer; returns the bars that had to be set by hand. */
export function applyDance(choreographer, dance) {
  const view = choreographer.view();
  if (view.length !== dance.bars) throw new Error(`the link was made for ${dance.bars} bars; the demo song here has ${view.length}`);
  const count = choreographer.segmentCount;
  dance.items.forEach((it, i) => {
    if (it.kind !== "empty" && it.segment >= count) throw new Error(`bar ${i + 1}: move ${it.segment} is not in this engine's library (${count} moves)`);
  });
  dance.items.forEach((it, i) => { if (it.kind === "pinned") choreographer.set(i, it.segment); });
  if (dance.items.some((it) => it.kind === "generated")) choreographer.generate();
  const fixed = [];
  const now = choreographer.view();
  dance.items.forEach((it, i) => {
    if (it.kind === "generated" && now[i].state.segment !== it.segment) {
      choreographer.set(i, it.segment);
      fixed.push(i);
    }
  });
  return fixed;
}

/**
 * The app's hook: a *Share link* button beside Generate, and the dance of the page's own link
 * applied once the demo song's bars are in (`songReady` resolves then).
 */
export function installShare({ choreo, messages, songReady }) {
  const share = {
    link: () => danceLink(choreo.choreographer, document.body.dataset.song),
    applied: null,
  };
  const generate = choreo.root.querySelector("#dance-generate");
  if (generate) {
    const button = document.createElement("button");
    button.type = "button";
    button.id = "dance-share";
    button.textContent = "Share link";
    button.title = "A link that opens this dance (built-in moves on the demo song)";
    button.addEventListener("click", async () => {
      try {
        const url = share.link();
        history.replaceState(null, "", url);
        try { await navigator.clipboard.writeText(url); messages.info("Link to this dance copied (it is also in the address bar)."); }
        catch { messages.info(`Link to this dance (also in the address bar): ${url}`); }
      } catch (e) {
        messages.error(`Share link: ${e.message}`);
      }
    });
    generate.after(button);
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
