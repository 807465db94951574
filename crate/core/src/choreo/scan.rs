//! A fill column's whole scan ([`super::fill`]'s fast path, when a column's top list cannot
//! prove its best predecessor), by chunks: the predecessors are taken [`SCAN_CHUNK`] at a time,
//! and a chunk is skipped when the cheapest node in it plus its cheapest edge into the column
//! already costs more than the best found (the table keeps each column's cheapest edge per chunk,
//! [`chunk_mins`]). Exact: every entry of a skipped chunk costs at least that bound (a float sum
//! rounds monotonically), so none reaches the best, and the chunks scanned keep the lowest index
//! reaching the minimum, as the plain scan does. Why: a fill's few thousand whole scans read the
//! whole column each (`docs/benchmarks-notes-choreo.md`, session 20).

/// Predecessors per chunk of a column's scan.
pub const SCAN_CHUNK: usize = 64;

/// Each chunk's minimum of `v` ([`SCAN_CHUNK`] consecutive entries, the last one shorter),
/// appended to `out`: a lower bound of every entry in it.
pub(crate) fn chunk_mins(v: &[f32], out: &mut Vec<f32>) {
    out.extend(v.chunks(SCAN_CHUNK).map(|c| c.iter().copied().fold(f32::INFINITY, f32::min)));
}

/// min over `a` of `prev[a] + col[a]` and the lowest `a` reaching it, from a candidate `best`
/// that `prev[best_a] + col[best_a]` reaches (or ∞ and 0), skipping each chunk whose bound
/// (`prev_chunk[k] + col_chunk[k]`, [`chunk_mins`] of `prev` and of `col`) is above the best so
/// far. Returns the minimum, the lowest index reaching it, and the chunks scanned.
pub(crate) fn column_min_by_chunks(prev: &[f32], prev_chunk: &[f32], col: &[f32], col_chunk: &[f32], mut best: f32, mut best_a: u32) -> (f32, u32, usize) {
    let n = prev.len().min(col.len());
    let mut scanned = 0;
    for (k, (&pc, &cc)) in prev_chunk.iter().zip(col_chunk).enumerate() {
        if pc + cc > best {
            continue;
        }
        let lo = k * SCAN_CHUNK;
        let hi = (lo + SCAN_CHUNK).min(n);
        if lo >= hi {
            break;
        }
        scanned += 1;
        let (p, c) = (&prev[lo..hi], &col[lo..hi]);
        // The chunk's minimum (lanes that vectorise), then the first entry reaching it.
        let mut lanes = [f32::INFINITY; 8];
        let split = p.len() - p.len() % 8;
        for (p8, c8) in p[..split].chunks_exact(8).zip(c[..split].chunks_exact(8)) {
            for i in 0..8 {
                let v = p8[i] + c8[i];
                lanes[i] = if v < lanes[i] { v } else { lanes[i] };
            }
        }
        let mut min = lanes.iter().copied().fold(f32::INFINITY, f32::min);
        for i in split..p.len() {
            let v = p[i] + c[i];
            if v < min {
                min = v;
            }
        }
        if min < best || min == best {
            if let Some(i) = (0..p.len()).find(|&i| p[i] + c[i] == min) {
                let a = (lo + i) as u32;
                if min < best || a < best_a {
                    best = min;
                    best_a = a;
                }
            }
        }
    }
    (best, best_a, scanned)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The plain scan: every entry, the first reaching the minimum.
    fn plain(prev: &[f32], col: &[f32]) -> (f32, u32) {
        let min = prev.iter().zip(col).map(|(p, c)| p + c).fold(f32::INFINITY, f32::min);
        let at = (0..prev.len()).find(|&a| prev[a] + col[a] == min).unwrap_or(0);
        (min, at as u32)
    }

    #[test]
    fn the_chunked_scan_finds_the_plain_scans_minimum_and_index() {
        // Costs on a coarse grid (many ties, some across chunks), ∞ nodes, lengths that are and
        // are not a multiple of the chunk, and every kind of starting candidate.
        let mut seed = 7u64;
        let mut next = || {
            seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (seed >> 33) as u32
        };
        let mut skipped = 0;
        for n in [1usize, 7, 64, 65, 200, 1000] {
            for round in 0..40 {
                let prev: Vec<f32> = (0..n).map(|_| if next() % 9 == 0 { f32::INFINITY } else { (next() % 20) as f32 * 0.25 }).collect();
                let col: Vec<f32> = (0..n).map(|_| (next() % 30) as f32 * 0.125 + if round % 2 == 0 { 0.0 } else { 3.0 }).collect();
                let (mut pc, mut cc) = (Vec::new(), Vec::new());
                chunk_mins(&prev, &mut pc);
                chunk_mins(&col, &mut cc);
                let want = plain(&prev, &col);
                // From no candidate, from the answer, from a tie at a higher index, from a
                // worse entry.
                let start = next() as usize % n;
                let candidates = [(f32::INFINITY, 0u32), want, (prev[start] + col[start], start as u32)];
                for (b, a) in candidates {
                    let (min, at, scanned) = column_min_by_chunks(&prev, &pc, &col, &cc, b, a);
                    assert_eq!((min.to_bits(), at), (want.0.to_bits(), want.1), "n {n}, round {round}, from ({b}, {a})");
                    skipped += pc.len() - scanned;
                }
            }
        }
        // The bound skips chunks (else it proves nothing here).
        assert!(skipped > 0);
    }
}
