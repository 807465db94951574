// Start-up, traced: each main-thread task before the first drawn pose with its wall time and
// its CPU time (the trace's thread duration). On a loaded machine a long task is mostly the
// thread waiting (descheduled, or blocked on the GPU process); the CPU time says how much of
// it was the page's own work. Not a test: run by hand,
//   node tests/browser/startup-trace.mjs webgl2 webgpu
// after `./dev build` (the long-task figures the `usable` test prints are wall times).
import { startServer, launch, BACKENDS } from "./harness.mjs";
const server = await startServer();
for (const backend of process.argv.slice(2)) {
  const { browser, page } = await launch(backend);
  await browser.startTracing(page, { categories: ["devtools.timeline", "blink.user_timing", "toplevel", "disabled-by-default-devtools.timeline"] });
  await page.goto(server.url + BACKENDS[backend].query);
  await page.waitForFunction(() => document.body.dataset.posed, null, { timeout: 60000 });
  await new Promise((r) => setTimeout(r, 500));
  const buf = await browser.stopTracing();
  const ev = JSON.parse(buf.toString()).traceEvents;
  const main = ev.find((e) => e.name === "thread_name" && e.args.name === "CrRendererMain" && ev.some((m) => m.pid === e.pid && m.name && m.name.startsWith("odori:")));
  const marks = Object.fromEntries(ev.filter((e) => e.name && e.name.startsWith("odori:") && e.pid === main.pid).map((e) => [e.name.slice(6), e.ts]));
  // Trace time of the page's navigation: its "odori:script" mark, less the mark's startTime.
  const scriptAt = await page.evaluate(() => performance.getEntriesByName("odori:script")[0].startTime);
  const nav = marks.script - scriptAt * 1000;
  const pose = marks["first-pose"];
  const tasks = ev.filter((e) => e.pid === main.pid && e.tid === main.tid && e.name === "RunTask" && e.ph === "X" && e.ts < pose && e.dur > 30000).map((e) => [Math.round((e.ts - nav) / 1000), Math.round(e.dur / 1000), Math.round((e.tdur ?? 0) / 1000)]);
  console.log(`${backend}: marks`, JSON.stringify(Object.fromEntries(Object.entries(marks).map(([k, v]) => [k, Math.round((v - nav) / 1000)]))));
  console.log(`${backend}: first pose ${Math.round((pose - nav) / 1000)} ms after navigation; longest task before it ${Math.max(0, ...tasks.map((t) => t[1]))} ms wall, most CPU in one task ${Math.max(0, ...tasks.map((t) => t[2]))} ms`);
  console.log(`${backend}: tasks before the pose over 30 ms [start, wall ms, CPU ms]`, JSON.stringify(tasks));
  await browser.close();
}
server.stop();
