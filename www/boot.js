// Before the first paint (a classic script in <head>): what the stored settings hide is hidden
// from the start, so nothing appears or vanishes once the page is drawn (layout shift, issue 30).
try {
  if (localStorage.getItem("odori.hintSeen") === "1") document.documentElement.dataset.hintSeen = "1";
} catch { /* storage off: the first steps show */ }
