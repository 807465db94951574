// Where a bar's six candidates stand (issue 30): side by side along the screen's horizontal,
// each in a slot as wide as the room its move takes over the whole bar, so no two can be taken
// for one. A move that travels (an imported salsa step, a turn) is centred on its own slot
// (its mean hip position over the bar), and the slots are laid out along the camera's right
// direction on the floor, not the world's x axis (the view is seen at an angle). Fixed spacing
// let travelling moves walk into each other: screen boxes overlapped by up to 99 % after a
// Search round on imported mocap (tests/browser/newcomer.test.mjs measures the overlap).

/** Free floor between two neighbouring candidates' widest reach over the bar, metres. */
export const CANDIDATE_GAP_M = 0.35;
/** Poses sampled over the bar to find each move's reach. */
const SAMPLES = 13;

/**
 * The floor direction (unit `[x, z]`) that runs left to right on the screen, from where the
 * viewer projects points one metre apart; `[1, 0]` when it cannot tell.
 */
export function screenRight(viewer) {
  const o = viewer.project(0, 0, 0), px = viewer.project(1, 0, 0), pz = viewer.project(0, 0, 1);
  if (!o || !px || !pz) return [1, 0];
  const a = px[0] - o[0], b = pz[0] - o[0];
  const n = Math.hypot(a, b);
  return n > 1e-6 ? [a / n, b / n] : [1, 0];
}

/**
 * Offsets (`[x, 0, z]` per clip, metres) that put the clips `ids` (each played from 0 to
 * `durSecs`) side by side along `right` with CANDIDATE_GAP_M between their reaches, the row
 * centred on the origin. `positions(id, t)` gives a pose's joint positions (x, y, z flat;
 * joint 0 the root), as `Library.jointPositions`.
 */
export function candidateOffsets(ids, durSecs, right, positions) {
  const [rx, rz] = right;
  const reach = ids.map((id) => {
    const poses = [];
    let cx = 0, cz = 0;
    for (let s = 0; s < SAMPLES; s++) {
      const p = positions(id, (durSecs * s) / (SAMPLES - 1));
      poses.push(p);
      cx += p[0] / SAMPLES;
      cz += p[2] / SAMPLES;
    }
    let lo = Infinity, hi = -Infinity;
    for (const p of poses) for (let i = 0; i + 2 < p.length; i += 3) {
      const along = (p[i] - cx) * rx + (p[i + 2] - cz) * rz;
      if (Number.isFinite(along)) { lo = Math.min(lo, along); hi = Math.max(hi, along); }
    }
    if (!(lo <= hi)) { lo = -0.3; hi = 0.3; }
    return { cx, cz, lo, hi };
  });
  // Slot centres along the row: each next one clears the last one's reach by the gap.
  const at = [];
  reach.forEach((r, k) => at.push(k === 0 ? 0 : at[k - 1] + reach[k - 1].hi + CANDIDATE_GAP_M - r.lo));
  const mid = reach.length ? (at[0] + reach[0].lo + at[at.length - 1] + reach[reach.length - 1].hi) / 2 : 0;
  return reach.map((r, k) => {
    const u = at[k] - mid;
    return [u * rx - r.cx, 0, u * rz - r.cz];
  });
}
