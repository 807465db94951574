// Processes started by this benchmark (Chromium and its helpers), read from Linux's /proc: the
// machine is shared, so the benches read the CPU time of their own processes rather than wall time.
import { readdirSync, readFileSync } from "node:fs";

/** Every process under this one, by pid. */
export function descendants() {
  const kids = new Map();
  for (const d of readdirSync("/proc")) {
    if (!/^\d+$/.test(d)) continue;
    try {
      const st = readFileSync(`/proc/${d}/stat`, "utf8");
      const ppid = Number(st.slice(st.lastIndexOf(")") + 2).split(" ")[1]);
      if (!kids.has(ppid)) kids.set(ppid, []);
      kids.get(ppid).push(Number(d));
    } catch { /* gone */ }
  }
  const out = [];
  const walk = (p) => { for (const c of kids.get(p) || []) { out.push(c); walk(c); } };
  walk(process.pid);
  return out;
}
