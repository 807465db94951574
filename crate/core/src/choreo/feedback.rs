//! Relevance-feedback candidate search for one bar (spec §F, paper 000 eq. 1, 3, 4).
//!
//! Each round shows [`CANDIDATES_PER_ROUND`] segments, chosen one at a time:
//! m_{n+1} = argmax_{m ∈ U \ S_n} ρ · rel(q, m) + (1 − ρ) · Φ(m, S_n, L) with
//! Φ = τ · min_{m_i ∈ S_n} D(m, m_i) + (1 − τ) · max_{m_j ∈ L} Sim(m, m_j),
//! rel(q, m) = 1 − |music intensity of the bar − motion intensity of m| (both 0..1), L the
//! segments the person liked, and S_n the segments already shown for the bar: none is shown
//! again, and in the min D term S_n counts those shown and not liked (plus this round's picks),
//! so a like draws the search toward its neighbours instead of repelling it (the product's
//! decision; see `next_round`).
//! τ starts at 1 and is multiplied by 19/20 at every Search. Where the spec is silent: with
//! nothing shown yet the min over S_n counts as 1 (all candidates equally new), with nothing
//! liked the max over L counts as 0, and ties go to the lower segment index.

use serde::{Deserialize, Serialize};

use super::segment::SegmentLibrary;

/// Candidates per round.
pub const CANDIDATES_PER_ROUND: usize = 6;
/// τ's factor per Search (eq. 4).
pub const TAU_DECAY: f32 = 19.0 / 20.0;

/// The search state of one bar.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "camelCase")]
pub struct FeedbackSession {
    /// Current τ.
    pub tau: f32,
    /// Every segment shown so far (S_n), in the order shown.
    pub shown: Vec<usize>,
    /// Segments the person liked (L).
    pub liked: Vec<usize>,
    /// The current round's candidates.
    pub round: Vec<usize>,
    /// Rounds shown so far (1 after the first).
    pub rounds: usize,
}

impl Default for FeedbackSession {
    fn default() -> Self {
        Self { tau: 1.0, shown: Vec::new(), liked: Vec::new(), round: Vec::new(), rounds: 0 }
    }
}

/// rel(q, m) of eq. 1.
pub fn relevance(bar_intensity: f32, segment_intensity: f32) -> f32 {
    1.0 - (bar_intensity - segment_intensity).abs().min(1.0)
}

impl FeedbackSession {
    /// A new session (τ = 1, nothing shown).
    pub fn new() -> Self {
        Self::default()
    }

    /// Chooses the next round of up to `count` unseen candidates by eq. 1 and records them as
    /// shown. Fewer come back when the library runs out of unseen segments.
    pub fn next_round(&mut self, lib: &SegmentLibrary, bar_intensity: f32, rho: f32, count: usize) -> &[usize] {
        let m = lib.len();
        let rho = if rho.is_finite() { rho.clamp(0.0, 1.0) } else { 0.5 };
        let tau = self.tau;
        // Segments kept only for the bars that hold them (an earlier cut) are never offered.
        let mut is_shown: Vec<bool> = lib.segments().iter().map(|s| s.retired).collect();
        for &s in &self.shown {
            if s < m {
                is_shown[s] = true;
            }
        }
        // min D to the shown set, and max Sim to the liked set, for every segment. A liked
        // candidate stays out of U (never shown again) but does not push its neighbours away:
        // with D = 1 − Sim, a neighbour's τ · D loses more than its (1 − τ) · Sim gains while
        // τ > ½ (the first 13 rounds), so counting liked ones in the min would make every like
        // repel the search from what was liked.
        let mut min_d = vec![1.0f32; m];
        for &s in &self.shown {
            if !self.liked.contains(&s) {
                update_min_d(lib, &mut min_d, s);
            }
        }
        let mut max_sim = vec![0.0f32; m];
        for &l in &self.liked {
            if let Some(sig) = lib.signature(l) {
                for (c, slot) in max_sim.iter_mut().enumerate() {
                    if let Some(other) = lib.signature(c) {
                        *slot = slot.max(sig.similarity(other));
                    }
                }
            }
        }
        let rel: Vec<f32> = lib.segments().iter().map(|s| relevance(bar_intensity, s.intensity01)).collect();
        self.round.clear();
        for _ in 0..count {
            let mut best: Option<(f32, usize)> = None;
            for c in 0..m {
                if is_shown[c] {
                    continue;
                }
                let phi = tau * min_d[c] + (1.0 - tau) * max_sim[c];
                let score = rho * rel[c] + (1.0 - rho) * phi;
                if best.is_none_or(|(b, _)| score > b) {
                    best = Some((score, c));
                }
            }
            let Some((_, pick)) = best else { break };
            is_shown[pick] = true;
            self.shown.push(pick);
            self.round.push(pick);
            update_min_d(lib, &mut min_d, pick);
        }
        self.rounds += 1;
        &self.round
    }

    /// A Search: the liked candidates join L, τ ← τ · 19/20, and the next round is chosen.
    pub fn search(&mut self, lib: &SegmentLibrary, liked: &[usize], bar_intensity: f32, rho: f32, count: usize) -> &[usize] {
        for &l in liked {
            if !self.liked.contains(&l) {
                self.liked.push(l);
            }
        }
        self.tau *= TAU_DECAY;
        self.next_round(lib, bar_intensity, rho, count)
    }
}

fn update_min_d(lib: &SegmentLibrary, min_d: &mut [f32], shown: usize) {
    let Some(sig) = lib.signature(shown) else { return };
    for (c, slot) in min_d.iter_mut().enumerate() {
        if let Some(other) = lib.signature(c) {
            *slot = slot.min(sig.dissimilarity(other));
        }
    }
}

/// Mean pairwise dissimilarity of a set (eq. 9): (1 / pairs) Σ_{i<j} D(m_i, m_j); 0 for fewer
/// than two.
pub fn mean_pairwise_dissimilarity(lib: &SegmentLibrary, set: &[usize]) -> f32 {
    let mut sum = 0.0;
    let mut pairs = 0;
    for i in 0..set.len() {
        for j in i + 1..set.len() {
            sum += lib.dissimilarity(set[i], set[j]);
            pairs += 1;
        }
    }
    if pairs == 0 {
        0.0
    } else {
        sum / pairs as f32
    }
}
