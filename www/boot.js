// Before the first paint (a classic script in <head>): what the stored settings hide is hidden
// from the start, so nothing appears or vanishes once the page is drawn (layout shift, issue 30).
try {
  if (localStorage.getItem("odori.hintSeen") === "1") document.documentElement.dataset.hintSeen = "1";
} catch { /* storage off: the first steps show */ }
// The Dance strip's rows that come and go with the project (the clip row when it has imported
// clips, the share note when its dance uses them): the lines the project opened last showed are
// held from the start (main.js keeps the list), so restoring it moves nothing below them (the
// bars and the song strip moved 28 px, a shift of 0.005 a reload).
try {
  const last = localStorage.getItem("odori.lastProject");
  const rows = last && localStorage.getItem(`odori.rows.${last}`);
  if (rows) document.documentElement.dataset.rows = rows;
} catch { /* storage off: the rows come with the project */ }
