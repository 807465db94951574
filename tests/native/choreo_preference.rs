//! The §J preference test as assertions (the bench `choreo_preference` prints the same runs):
//! on the real library (built-in moves + the CMU salsa and Indian clips), three disjoint sets
//! of 64 hidden targets (A, the one the product's choices were tuned on, and B and C, held
//! out), a simulated person liking the 2 shown candidates closest to the target by the
//! perceptual distance, against people liking at random.
//! - The similarity §F uses agrees with the perceptual distance: mean Spearman ≥ 0.5 (the
//!   centred-position kWAS of session 4 scored 0.075; the uncentred one now about 0.73).
//! - Likes steer the search, on every set: the guided best distance falls by ≥ 20 % from
//!   round 1 to round 5 (mean over targets; 27–29 % now), and guided likes end closer than one
//!   random person on at least twice as many targets as they end farther (median over 5
//!   random people; ties — the same best for both, often found in the shared first round —
//!   count for neither).
//! - Against the random people's mean result (5 people per target), pooled over the three
//!   sets: guided likes end closer on at least 2/3 of the targets. The goal is 75 %:
//!   on the tuned set A it is met (48/64), over A, B and C 138/192 (72 %), over all ten
//!   disjoint sets of the library (`PREFERENCE_SETS=10` on the bench) 468/640 (73 %). The
//!   floor here is a regression guard below those, not the goal.
//! - §F's check of the method: eq. 9's diversity of the 6 shown falls over the first rounds.

#[path = "../bench/choreo_preference.rs"]
#[allow(dead_code)]
mod preference;

#[test]
fn likes_steer_the_search_toward_what_a_person_sees_as_close() {
    let (lib, positions) = preference::library();
    let (mut pooled, mut pooled_wins) = (0, 0);
    for (name, offset) in preference::SETS {
        let f = preference::measure_on(&lib, &positions, offset);
        println!(
            "set {name}: agreement {:.3}; guided {:?}; random {:?}; diversity {:?}; mean fall {:.1} %; vs one random person (median of {}) closer {} / equal {}; closer than the random mean on {}/{}",
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
        let losses = f.targets - f.wins_median - f.ties_median;
        assert!(f.wins_median >= 2 * losses.max(1), "set {name}: guided likes end closer than one random person on {} targets and farther on about {losses}: likes do not steer the search", f.wins_median);
        assert!(f.diversity[1] < f.diversity[0] && f.diversity[2] < f.diversity[1], "set {name}: eq. 9's diversity of the shown does not fall over the first rounds: {:?}", f.diversity);
        assert!(f.mean_fall >= 0.20, "set {name}: the guided best distance falls by {:.1} % only from round 1 to 5", 100.0 * f.mean_fall);
        pooled += f.targets;
        pooled_wins += f.wins_vs_mean;
    }
    assert!(
        3 * pooled_wins >= 2 * pooled,
        "guided likes end closer than the mean of {} random people on {pooled_wins}/{pooled} targets only (floor 2/3, goal 75 %)",
        preference::RANDOM_DRAWS
    );
}
