// 2D canvases sized from their layout box. A canvas in a panel that is hidden (a tab not shown
// on a phone) has no box when it is first drawn; it must be drawn again once it has one, and
// whenever its box changes, or it shows a stretched bitmap of the wrong size.

/** Calls `draw()` whenever `canvas`'s layout box changes size, including from hidden to shown. */
export function redrawOnResize(canvas, draw) {
  let last = "";
  new ResizeObserver(() => {
    const now = `${canvas.clientWidth}x${canvas.clientHeight}`;
    if (now === last || canvas.clientWidth === 0) return;
    last = now;
    draw();
  }).observe(canvas);
}
