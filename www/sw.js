// Offline: the app keeps working with no network. Network first (so a new build is always
// picked up when online), the cache when the network fails. Everything the app needs to
// start is cached at install; anything else it fetches is cached as it goes.
const CACHE = "odori-v2";
const SHELL = [
  "./", "./index.html", "./style.css", "./favicon.svg", "./boot.js", "./main.js", "./search-worker.js", "./demo-song-worker.js",
  "./ui/messages.js", "./ui/library-panel.js", "./ui/player.js", "./ui/files.js", "./ui/song-panel.js",
  "./ui/search-panel.js", "./ui/text-panel.js", "./ui/choreo-panel.js", "./ui/candidate-layout.js", "./ui/export-panel.js", "./ui/canvas.js",
  "./audio/rms.js", "./audio/song-player.js", "./search/client.js", "./share.js",
  "./project/store.js", "./project/index-store.js", "./project/file.js", "./project/app.js", "./project/dance.js", "./vendor/idb.js",
  "./video/export-video.js", "./video/video-panel.js", "./video/mediabunny.js",
  "./pkg/odori.js", "./pkg/odori_bg.wasm",
];

self.addEventListener("install", (ev) => {
  ev.waitUntil(caches.open(CACHE).then((c) => c.addAll(SHELL)).then(() => self.skipWaiting()));
});

self.addEventListener("activate", (ev) => {
  ev.waitUntil(
    caches.keys().then((keys) => Promise.all(keys.filter((k) => k !== CACHE).map((k) => caches.delete(k)))).then(() => self.clients.claim()),
  );
});

self.addEventListener("fetch", (ev) => {
  const req = ev.request;
  if (req.method !== "GET" || new URL(req.url).origin !== self.location.origin) return;
  ev.respondWith(
    fetch(req)
      .then((res) => {
        if (res.ok) {
          // Kept without the query (?backend=…): the page opened with a query must refresh the
          // same entry the install made, or an offline start after an update finds the old one.
          const copy = res.clone();
          const key = new URL(req.url);
          key.search = "";
          caches.open(CACHE).then((c) => c.put(key.href, copy));
        }
        return res;
      })
      .catch(() => caches.match(req, { ignoreSearch: true }).then((hit) => hit || Response.error())),
  );
});
