//! The §J preference test as assertions (the bench `choreo_preference` prints the same runs):
//! on the real library (built-in moves + the CMU salsa and Indian clips, cut at their clip
//! tempo), three disjoint sets of 64 hidden targets (A, the one the product's choices were
//! tuned on, and B and C, held out), a simulated person liking the 2 shown candidates closest
//! to the target by the perceptual distance, against people liking at random. Φ as the product
//! runs it (the spec's max over L, [`odori_core::choreo::LikeTerm`]'s default).
//!
//! The asserts are regression guards that follow from what "likes steer the search" means,
//! not figures read off set A:
//! - The similarity §F uses agrees with the perceptual distance: mean Spearman ≥ 0.5 on every
//!   set (the centred-position kWAS of session 4 scored 0.075, the ten-joint signatures of
//!   sessions 5–6 about 0.72; the all-joint positions and velocities of session 7 about 0.79).
//! - On every set the guided best distance falls by ≥ 20 % from round 1 to round 5 (the
//!   issue's goal) and eq. 9's diversity of the 6 shown falls over the first rounds (§F).
//! - Likes beat chance: pooled over the three sets, guided likes end closer than the mean of 5
//!   random people on more targets than a coin would give, by a one-sided sign test at
//!   p < 0.01 (with 192 targets, about 59 %); and against one random person at a time (median
//!   of 5; ties — the same best for both, often found in the shared first round — left out)
//!   they win more often than they lose on every set.
//!
//! The goal (75 % against random likes) is not asserted: it was measured after the
//! features were chosen, and sets of 64 carry a few targets of noise from the random draws
//! alone. With the signatures of session 7 the product reaches 75.2 % over the ten disjoint
//! sets (75.0 % on the five held out from the choice of features; `PREFERENCE_SETS=10` on the
//! bench; figures in `choreo::feedback`'s docs and the closing note).

#[path = "../bench/choreo_preference.rs"]
#[allow(dead_code)]
mod preference;

/// P(X ≥ k) for X ~ Binomial(n, ½): the one-sided sign test's p-value for k wins of n.
fn sign_test_p(k: usize, n: usize) -> f64 {
    let mut p = 0.0f64;
    let mut c = 1.0f64; // C(n, i), built up term by term
    for i in 0..=n {
        if i > 0 {
            c = c * (n - i + 1) as f64 / i as f64;
        }
        if i >= k {
            p += c;
        }
    }
    p / 2f64.powi(n as i32)
}

#[test]
fn the_sign_test_matches_known_values() {
    assert!((sign_test_p(0, 10) - 1.0).abs() < 1e-12);
    assert!((sign_test_p(10, 10) - 1.0 / 1024.0).abs() < 1e-12);
    assert!((sign_test_p(8, 10) - 56.0 / 1024.0).abs() < 1e-12);
}

#[test]
fn likes_steer_the_search_toward_what_a_person_sees_as_close() {
    let (lib, positions) = preference::library();
    let (mut pooled, mut pooled_wins) = (0, 0);
    for (name, offset) in preference::SETS {
        let f = preference::measure_on(&lib, &positions, offset);
        let losses = f.targets - f.wins_median - f.ties_median;
        println!(
            "set {name}: agreement {:.3}; guided {:?}; random {:?}; diversity {:?}; mean fall {:.1} %; vs one random person (median of {}) closer {} / equal {} / farther {losses}; closer than the random mean on {}/{}",
            f.agreement,
            f.guided_curve,
            f.random_curve,
            f.diversity,
            100.0 * f.mean_fall,
            preference::RANDOM_DRAWS,
            f.wins_median,
            f.ties_median,
            f.wins_vs_mean,
            f.targets
        );
        assert!(f.targets >= 30, "set {name}: only {} targets", f.targets);
        assert!(f.agreement >= 0.5, "set {name}: the search's similarity agrees with the perceptual distance at Spearman {:.3} only", f.agreement);
        assert!(f.wins_median > losses, "set {name}: guided likes end closer than one random person on {} targets and farther on about {losses}: likes do not steer the search", f.wins_median);
        assert!(f.diversity[1] < f.diversity[0] && f.diversity[2] < f.diversity[1], "set {name}: eq. 9's diversity of the shown does not fall over the first rounds: {:?}", f.diversity);
        assert!(f.mean_fall >= 0.20, "set {name}: the guided best distance falls by {:.1} % only from round 1 to 5", 100.0 * f.mean_fall);
        pooled += f.targets;
        pooled_wins += f.wins_vs_mean;
    }
    let p = sign_test_p(pooled_wins, pooled);
    assert!(
        p < 0.01,
        "guided likes end closer than the mean of {} random people on {pooled_wins}/{pooled} targets only: a coin does that often (sign test p = {p:.3})",
        preference::RANDOM_DRAWS
    );
}
