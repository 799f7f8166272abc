//! Early rejection of bad hypotheses by Wald's sequential probability ratio test, with the adaptive
//! estimates of Matas & Chum, "Randomized RANSAC with sequential probability ratio test", ICCV 2005 (and
//! Chum & Matas, "Optimal randomized RANSAC", PAMI 2008); and the number of inliers that a wrong model
//! reaches by chance.
//!
//! **The test.** A hypothesis is *good* when each correspondence is consistent with it (within its
//! threshold) with probability `ε`, *bad* when with probability `δ ≪ ε`. Its correspondences are
//! verified in a random order (see [`super::scoring`]), the correspondences of its own sample skipped
//! (they are consistent by construction), and after `j` of them the likelihood ratio
//!
//! `λ_j = Π_{i ≤ j} p(xᵢ | bad) / p(xᵢ | good)`, a factor `δ / ε` for a consistent correspondence
//! and `(1 − δ) / (1 − ε)` for an inconsistent one,
//!
//! is compared with a threshold `A`: the hypothesis is rejected as soon as `λ_j > A` (checked after
//! every batch of points and every line). The first hypothesis of a run is scored in full: the test
//! needs a best model to compare with. Under a good
//! hypothesis `λ_j` is a martingale of mean 1, so it is rejected with probability `α ≤ 1 / A` (Wald;
//! Ville's inequality), whatever `δ`. Points and lines have their own `ε` and `δ`; `ln λ` is the sum of
//! their terms.
//!
//! **The threshold** minimises the expected time per sample (Matas & Chum 2005, eq. 11): `A` is the
//! fixed point of `A = K + ln A`, `K = t_M C / m_S + 1`, with `t_M` the time of a minimal solve in
//! units of one error evaluation ([`MODEL_COST`]), `m_S` the mean number of poses per sample, and
//! `C = (1 − δ) ln((1 − δ) / (1 − ε)) + δ ln(δ / ε)` the expected increment of `ln λ` per bad
//! correspondence (a count-weighted mean over points and lines).
//!
//! **Adaptation.** `ε` is the inlier fraction of the best model so far, but at least
//! [`super::RansacOptions::min_inlier_ratio`] (the smallest fraction the loop is designed to find) and
//! at most [`MAX_EPSILON`]. `δ` is estimated from the rejected hypotheses: `(I + 1) / (E + 1 / δ₀)`
//! over their `E` verified correspondences of which `I` were consistent, starting from the chance
//! probability `δ₀` of [`chance_probabilities`]. The test is designed anew when `ε` or `δ` moves by more
//! than [`REDESIGN_CHANGE`]. The stopping rule counts a sample verified with threshold `A` as
//! successful with probability `P (1 − 1 / A)` (see [`super::sampler`]).
//!
//! **Chance inliers.** Under the outlier model (each observation uniform in the window of the observed
//! pixels, [`chance_probabilities`]), a wrong model has its 3 sample correspondences plus
//! `X = X_p + X_l` chance inliers, `X_p ~ Binomial(n_p, p_p)` among the points and
//! `X_l ~ Binomial(n_l, p_l)` among the lines. [`chance_inliers`] gives the count that the best of `M`
//! such models exceeds with probability at most `ψ`.

/// `t_M`: the time of a minimal sample (P3P, the pose checks and the loop's bookkeeping) in units of
/// one point-error evaluation, measured on 20,000 all-outlier points (the timings:
/// docs/benchmarks.md, "Figures behind code comments"). It sets how much verification a
/// rejection may cost; the line solvers are slower, so the constant is set below the measured ratio
/// and errs towards a smaller `A`.
pub const MODEL_COST: f64 = 200.0;

/// Largest `ε` of a test: with `ε → 1` one inconsistent correspondence would reject a good model.
pub const MAX_EPSILON: f64 = 0.99;

/// Relative change of `ε` or `δ` that triggers a new design of the test.
pub const REDESIGN_CHANGE: f64 = 0.05;

/// The decision rule of one design: per kind (points, lines), the increment of `ln λ` for a
/// consistent and for an inconsistent correspondence, and `ln A`. A kind with `δ ≥ ε` carries no
/// evidence and adds nothing.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct SprtTest {
    /// `ln(δ / ε)` per kind (≤ 0).
    pub consistent: [f64; 2],
    /// `ln((1 − δ) / (1 − ε))` per kind (≥ 0).
    pub inconsistent: [f64; 2],
    /// `ln A`.
    pub log_a: f64,
}

impl SprtTest {
    /// A test that never rejects (no evidence from either kind).
    pub const NONE: SprtTest = SprtTest {
        consistent: [0.0; 2],
        inconsistent: [0.0; 2],
        log_a: f64::INFINITY,
    };

    /// `ln λ` after `evaluated` correspondences per kind (sample excluded) of which `consistent` were
    /// (the scorer keeps a running sum instead).
    #[cfg(test)]
    pub fn log_lambda(&self, evaluated: [usize; 2], consistent: [usize; 2]) -> f64 {
        (0..2)
            .map(|k| {
                let c = consistent[k] as f64;
                c * self.consistent[k] + (evaluated[k] as f64 - c) * self.inconsistent[k]
            })
            .sum()
    }
}

/// The adaptive state of the test over one run of the loop.
#[derive(Debug, Clone)]
pub(crate) struct Sprt {
    /// Correspondences per kind (points, lines), for the weights of `C`.
    counts: [usize; 2],
    /// Floor of `ε`: `min_inlier_ratio`.
    min_epsilon: f64,
    /// The prior `δ₀` per kind.
    delta0: [f64; 2],
    /// `ε` and `δ` per kind, current estimates.
    epsilon: [f64; 2],
    delta: [f64; 2],
    /// Verified (sample excluded) and consistent correspondences of the rejected hypotheses, per kind.
    rejected_evaluated: [f64; 2],
    rejected_consistent: [f64; 2],
    /// `ε`, `δ` of the current design, and the design.
    designed: ([f64; 2], [f64; 2]),
    test: SprtTest,
}

impl Sprt {
    /// A test for `counts` (points, lines) with chance probabilities `delta0` and `ε` floor
    /// `min_epsilon`; `models_per_sample` is `m_S`.
    pub fn new(counts: [usize; 2], delta0: [f64; 2], min_epsilon: f64, models_per_sample: f64) -> Sprt {
        let epsilon = [min_epsilon.min(MAX_EPSILON); 2];
        let test = design(counts, epsilon, delta0, models_per_sample);
        Sprt {
            counts,
            min_epsilon,
            delta0,
            epsilon,
            delta: delta0,
            rejected_evaluated: [0.0; 2],
            rejected_consistent: [0.0; 2],
            designed: (epsilon, delta0),
            test,
        }
    }

    /// The current test.
    pub fn test(&self) -> &SprtTest {
        &self.test
    }

    /// `1 / A`: a bound on the probability that the current test rejects a good hypothesis.
    pub fn rejection_bound(&self) -> f64 {
        (-self.test.log_a).exp()
    }

    /// `δ` per kind, the current estimate.
    #[cfg(test)]
    pub fn delta(&self) -> [f64; 2] {
        self.delta
    }

    /// Records a rejected hypothesis (sample excluded: `evaluated` verified, `consistent` of them);
    /// true when the test was designed anew.
    pub fn rejected(&mut self, evaluated: [usize; 2], consistent: [usize; 2], models_per_sample: f64) -> bool {
        for k in 0..2 {
            self.rejected_evaluated[k] += evaluated[k] as f64;
            self.rejected_consistent[k] += consistent[k] as f64;
            self.delta[k] = if self.delta0[k] > 0.0 {
                (self.rejected_consistent[k] + 1.0) / (self.rejected_evaluated[k] + 1.0 / self.delta0[k])
            } else {
                0.0
            };
        }
        self.redesign_if_moved(models_per_sample)
    }

    /// Records the inlier fractions (points, lines) of a new best model.
    pub fn new_best(&mut self, fractions: [f64; 2], models_per_sample: f64) {
        self.epsilon = fractions.map(|f| f.max(self.min_epsilon).min(MAX_EPSILON));
        self.redesign_if_moved(models_per_sample);
    }

    /// Designs the test anew when `ε` or `δ` moved by more than [`REDESIGN_CHANGE`]; true if it did.
    fn redesign_if_moved(&mut self, models_per_sample: f64) -> bool {
        let moved = |new: &[f64; 2], old: &[f64; 2]| {
            (0..2).any(|k| (new[k] - old[k]).abs() > REDESIGN_CHANGE * old[k].abs().max(f64::MIN_POSITIVE))
        };
        if moved(&self.epsilon, &self.designed.0) || moved(&self.delta, &self.designed.1) {
            self.designed = (self.epsilon, self.delta);
            self.test = design(self.counts, self.epsilon, self.delta, models_per_sample);
            return true;
        }
        false
    }
}

/// The test for `ε`, `δ` per kind (see the module documentation); [`SprtTest::NONE`] when it cannot
/// save work: no kind carries evidence (`δ ≥ ε`, e.g. a threshold so wide that every correspondence
/// agrees with any pose by chance), or a bad model would on average be verified on all `n`
/// correspondences before its rejection (`ln A / C ≥ n`, Wald's expected length under the bad
/// hypothesis). The design of eq. 11 assumes a verification of unbounded length, so as `C → 0` it
/// drives `A → 1` and `α = 1 / A → 1`: a test that saves nothing would then make the stopping rule
/// count every sample as a near-certain miss, and the loop would run to `max_iterations`.
fn design(counts: [usize; 2], epsilon: [f64; 2], delta: [f64; 2], models_per_sample: f64) -> SprtTest {
    let mut test = SprtTest {
        consistent: [0.0; 2],
        inconsistent: [0.0; 2],
        log_a: 0.0,
    };
    let total = (counts[0] + counts[1]).max(1) as f64;
    let mut c = 0.0;
    for k in 0..2 {
        let (e, d) = (epsilon[k], delta[k]);
        if counts[k] == 0 || !(d > 0.0 && d < e && e < 1.0) {
            continue; // no evidence from this kind
        }
        test.consistent[k] = (d / e).ln();
        test.inconsistent[k] = ((1.0 - d) / (1.0 - e)).ln();
        let per = (1.0 - d) * test.inconsistent[k] + d * test.consistent[k];
        c += counts[k] as f64 / total * per;
    }
    let k = MODEL_COST * c / models_per_sample.max(1.0) + 1.0;
    // A = K + ln A: the iteration from A = K converges in a few steps (Matas & Chum 2005).
    let mut a = k;
    for _ in 0..20 {
        let next = k + a.ln();
        if (next - a).abs() <= 1e-9 * a {
            a = next;
            break;
        }
        a = next;
    }
    test.log_a = a.max(1.0 + f64::EPSILON).ln();
    if !(c > 0.0 && test.log_a / c < total) {
        return SprtTest::NONE;
    }
    test
}

/// Probability that an outlier is consistent with a given wrong pose by chance (points, lines), under
/// the model of observations uniform in the axis-aligned window `[u₀, u₁] × [v₀, v₁]` of the observed
/// pixels (points and segment endpoints), of width `W` and height `H`, each taken at least the
/// threshold `τ` of the kind (a window of zero area would make every agreement certain):
/// - a point lies within `τ_p` of its predicted pixel with probability at most
///   `π τ_p² / (W H) = π (τ_p / W) (τ_p / H)`;
/// - a segment's two endpoints have signed distances `d₁, d₂` to the predicted line, each of density at
///   most `√(W² + H²) / (W H)` (the largest density of a projection of the uniform window), so
///   `(d₁² + d₂²) / 2 ≤ τ_l²` holds with probability at most
///   `2 π τ_l² (W² + H²) / (W H)² = 2 π (τ_l / W) (τ_l / H) (W / H + H / W)`.
///
/// Each kind has its own window, so a huge threshold of one kind does not change the other's; the
/// ratios keep thresholds up to `f64::MAX` finite. Both are clamped to `[0, 1]`. `window` is
/// `[u₀, v₀, u₁, v₁]`.
pub(crate) fn chance_probabilities(window: [f64; 4], point_threshold: f64, line_threshold: f64) -> [f64; 2] {
    let pi = std::f64::consts::PI;
    let sides = |tau: f64| {
        let w = (window[2] - window[0]).max(tau);
        let h = (window[3] - window[1]).max(tau);
        (tau / w, tau / h, w / h + h / w)
    };
    let (pw, ph, _) = sides(point_threshold);
    let (lw, lh, aspect) = sides(line_threshold);
    let p = pi * pw * ph;
    let l = 2.0 * pi * lw * lh * aspect;
    [p, l].map(|x| if x.is_finite() { x.clamp(0.0, 1.0) } else { 1.0 })
}

/// The mass function of `Binomial(m, p)` from 0 up to where it is negligible, scaled so that its
/// largest entry is 1, with the log of the scale.
fn scaled_binomial(m: usize, p: f64) -> (Vec<f64>, f64) {
    if m == 0 || p <= 0.0 {
        return (vec![1.0], 0.0);
    }
    let mf = m as f64;
    // ln P(X = j) by the ratio of consecutive terms, past the mode until 1e-40 of the largest (far
    // below any ψ / M) or m.
    let ratio = (p / (1.0 - p)).ln();
    let mut log_pmf = Vec::new();
    let (mut lp, mut top) = (mf * (-p).ln_1p(), f64::NEG_INFINITY);
    for j in 0..=m {
        top = top.max(lp);
        log_pmf.push(lp);
        if j as f64 > mf * p && lp < top - 92.0 {
            break;
        }
        lp += ((m - j) as f64 / (j + 1) as f64).ln() + ratio;
    }
    (log_pmf.iter().map(|l| (l - top).exp()).collect(), top)
}

/// The most inliers that chance plausibly gives a wrong model: `3 + k − 1`, with `k` the smallest count
/// such that `P(X ≥ k) ≤ ψ / M` for `X = X_p + X_l`, `X_p ~ Binomial(m_p, p_p)` and
/// `X_l ~ Binomial(m_l, p_l)` the chance inliers among the points and the lines (see the module
/// documentation; `m_p`, `m_l` are the counts of each kind, the sample's 3 counted too, a bound).
/// `models` is `M`, the number of hypotheses the best was chosen from (Bonferroni), `psi` the
/// probability that the best of them has more. The tail is exact (the two mass functions convolved),
/// each truncated where it falls below 1e-40 of its mode. Returns `3 + m_p + m_l` when no count qualifies (`p` near 1).
pub(crate) fn chance_inliers(counts: [usize; 2], p: [f64; 2], models: usize, psi: f64) -> usize {
    let all = counts[0] + counts[1];
    if (0..2).any(|k| counts[k] > 0 && p[k] >= 1.0) {
        return 3 + all;
    }
    let log_alpha = psi.ln() - (models.max(1) as f64).ln();
    let (points, log_scale_p) = scaled_binomial(counts[0], p[0]);
    let (lines, log_scale_l) = scaled_binomial(counts[1], p[1]);
    let mut pmf = vec![0.0; points.len() + lines.len() - 1];
    for (i, a) in points.iter().enumerate() {
        for (j, b) in lines.iter().enumerate() {
            pmf[i + j] += a * b;
        }
    }
    // Tails from the top: k is the smallest count whose tail is at most α.
    let log_scale = log_scale_p + log_scale_l;
    let (mut tail, mut k) = (0.0, pmf.len());
    for j in (0..pmf.len()).rev() {
        tail += pmf[j];
        if tail.ln() + log_scale > log_alpha {
            break;
        }
        k = j;
    }
    if k > all {
        3 + all
    } else {
        2 + k
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Upper tail of Binomial(m, p) by plain summation of the mass function (small m).
    fn binomial_tail(m: usize, p: f64, k: usize) -> f64 {
        let choose = |j: usize| (0..j).map(|i| (m - i) as f64 / (i + 1) as f64).product::<f64>();
        (k..=m)
            .map(|j| choose(j) * p.powi(j as i32) * (1.0 - p).powi((m - j) as i32))
            .sum()
    }

    #[test]
    fn chance_inliers_are_the_binomial_quantile_of_the_best_of_m_models() {
        for (m, p, models) in [
            (97, 1.6e-4, 300),
            (97, 1.6e-4, 20_000),
            (150, 0.01, 10),
            (60, 0.2, 1000),
        ] {
            let alpha = 0.01 / models as f64;
            let k = chance_inliers([m, 0], [p, 0.3], models, 0.01) - 2;
            assert!(
                binomial_tail(m, p, k) <= alpha && binomial_tail(m, p, k - 1) > alpha,
                "m {m} p {p}: k {k}"
            );
            // The same correspondences as lines, or split between points and lines of equal p.
            assert_eq!(chance_inliers([0, m], [0.3, p], models, 0.01), k + 2);
            assert_eq!(chance_inliers([m / 3, m - m / 3], [p, p], models, 0.01), k + 2);
        }
        // Large m: against the Poisson limit (m p = 3.2 at 20,000 points, 4 px, 640 x 480).
        let poisson_tail = |lambda: f64, k: usize| {
            let mut term = (-lambda).exp();
            let mut cdf = 0.0;
            for j in 0..k {
                cdf += term;
                term *= lambda / (j + 1) as f64;
            }
            1.0 - cdf
        };
        let k = chance_inliers([20_000, 0], [1.6e-4, 0.0], 20_000, 0.01) - 2;
        assert!(
            poisson_tail(3.2, k) <= 5e-7 * 1.01 && poisson_tail(3.2, k - 1) > 5e-7 * 0.99,
            "{k}"
        );
        assert_eq!(chance_inliers([100, 5], [1.0, 0.1], 10, 0.01), 108);
        assert_eq!(chance_inliers([100, 0], [0.0, 1.0], 10, 0.01), 3);
        // A million correspondences with half of them agreeing by chance: no underflow; the normal
        // quantile of α = 1e-3, m p + 3.09 σ.
        let k = chance_inliers([1_000_000, 0], [0.5, 0.0], 10, 0.01) as f64 - 2.0;
        assert!((k - 500_000.0 - 3.09 * 500.0).abs() < 0.02 * 500.0, "{k}");
    }

    #[test]
    fn chance_probabilities_of_a_vga_window() {
        let [p, l] = chance_probabilities([0.0, 0.0, 640.0, 480.0], 4.0, 4.0);
        let pi = std::f64::consts::PI;
        assert!((p - pi * 16.0 / (640.0 * 480.0)).abs() < 1e-12);
        assert!(
            (l - 2.0 * pi * 16.0 * (640.0f64.powi(2) + 480.0f64.powi(2)) / (640.0f64 * 480.0).powi(2)).abs() < 1e-12
        );
        // A threshold larger than the window: every correspondence agrees with every pose.
        assert_eq!(chance_probabilities([0.0, 0.0, 10.0, 10.0], 1e6, 1e6), [1.0, 1.0]);
        // Each kind has its own window: a huge line threshold leaves the points' probability as it
        // is (it used to widen the points' window too, to p = 0: no evidence from the points), and a
        // threshold whose square overflows still gives 1, not NaN.
        assert_eq!(chance_probabilities([0.0, 0.0, 640.0, 480.0], 4.0, 1e300)[0], p);
        assert_eq!(chance_probabilities([0.0, 0.0, 640.0, 480.0], 4.0, 1e300)[1], 1.0);
        assert_eq!(chance_probabilities([0.0, 0.0, 640.0, 480.0], 1e300, 4.0), [1.0, l]);
    }

    #[test]
    fn a_test_that_cannot_save_work_is_no_test_and_never_rejects() {
        // Every correspondence agrees with any pose by chance (δ = 1 ≥ ε): no evidence. The design
        // of eq. 11 gave A = 1, so α = 1 / A = 1, and the stopping rule never came down.
        for delta in [[1.0, 1.0], [0.995, 0.0], [0.0, 0.0]] {
            let test = design([20, 0], [0.99, 0.99], delta, 1.0);
            assert_eq!(test, SprtTest::NONE, "δ = {delta:?}");
            let sprt = Sprt::new([20, 0], delta, 0.99, 1.0);
            assert_eq!(sprt.rejection_bound(), 0.0);
        }
        // Evidence, but too little for 20 correspondences: a bad model would on average be verified on
        // all of them before its rejection (ln A / C ≥ n), so the test saves nothing; α here would
        // be 1 / A ≈ 0.87. The same rates on 10,000 correspondences do make a test.
        let (epsilon, delta) = ([0.99, 0.99], [0.989, 0.0]);
        let c = kl(delta[0], epsilon[0]);
        let a = fixed_point(MODEL_COST * c + 1.0);
        assert!(
            a.ln() / c > 20.0 && a.ln() / c < 10_000.0 && 1.0 / a > 0.8,
            "A {a}, C {c}"
        );
        assert_eq!(design([20, 0], epsilon, delta, 1.0), SprtTest::NONE);
        // (The design iterates A ← K + ln A from K, which rises towards the fixed point but slowly
        // when A is near 1: its ln A lies between ln K and the fixed point's.)
        let big = design([10_000, 0], epsilon, delta, 1.0);
        let k = MODEL_COST * c + 1.0;
        assert!(
            big.log_a > k.ln() && big.log_a <= a.ln() + 1e-12,
            "{big:?}, K {k}, A {a}"
        );
        // The usual case, 20 correspondences, half of them inliers and chance agreements rare: a test.
        let usual = design([20, 0], [0.5, 0.5], [1e-3, 0.0], 1.0);
        let (c, a) = (kl(1e-3, 0.5), fixed_point(MODEL_COST * kl(1e-3, 0.5) + 1.0));
        assert!(a.ln() / c < 20.0);
        assert!((usual.log_a - a.ln()).abs() < 1e-9 * a.ln());
    }

    /// `C` of one kind: the Kullback-Leibler divergence of Bernoulli(δ) from Bernoulli(ε), written out.
    fn kl(delta: f64, epsilon: f64) -> f64 {
        (1.0 - delta) * ((1.0 - delta) / (1.0 - epsilon)).ln() + delta * (delta / epsilon).ln()
    }

    /// `A = K + ln A` by bisection on `[1, 2K + 2]` (not the design's iteration).
    fn fixed_point(k: f64) -> f64 {
        let (mut lo, mut hi) = (1.0f64, 2.0 * k + 2.0);
        for _ in 0..200 {
            let mid = 0.5 * (lo + hi);
            if mid - mid.ln() < k {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        0.5 * (lo + hi)
    }

    #[test]
    fn the_threshold_solves_its_fixed_point_and_bad_hypotheses_are_rejected_after_a_few_errors() {
        let test = design([1000, 0], [0.1, 0.1], [2e-4, 2e-4], 2.0);
        let a = test.log_a.exp();
        let c = 0.9998 * (0.9998f64 / 0.9).ln() + 2e-4 * (2e-4f64 / 0.1).ln();
        assert!((a - (MODEL_COST * c / 2.0 + 1.0 + a.ln())).abs() < 1e-6 * a);
        assert_eq!(test.inconsistent[1], 0.0, "no lines: no evidence from lines");
        // A bad hypothesis (no consistent correspondence): rejected once ln λ > ln A.
        let steps = (test.log_a / test.inconsistent[0]).floor() as usize + 1;
        assert!(test.log_lambda([steps, 0], [0, 0]) > test.log_a);
        assert!(test.log_lambda([steps - 1, 0], [0, 0]) <= test.log_a);
        assert!(steps < 40, "{steps}");
        // One consistent correspondence weighs as much as ln(ε/δ) / ln((1-δ)/(1-ε)) ≈ 60 inconsistent ones.
        assert!(test.log_lambda([steps + 50, 0], [1, 0]) < test.log_a);
    }

    #[test]
    fn delta_adapts_to_the_rejected_hypotheses_and_a_better_best_sharpens_the_test() {
        let mut sprt = Sprt::new([5000, 0], [1e-3, 0.0], 0.1, 2.0);
        let a0 = sprt.test().log_a.exp();
        // Rejected hypotheses saw 1 consistent correspondence in 10,000 verified.
        for _ in 0..100 {
            sprt.rejected([100, 0], [0, 0], 2.0);
        }
        sprt.rejected([0, 0], [1, 0], 2.0);
        let d = sprt.delta()[0];
        assert!((d - 2.0 / (10_000.0 + 1000.0)).abs() < 1e-12, "{d}");
        // A good best model raises ε: a sharper test, a larger A, fewer good models rejected.
        sprt.new_best([0.6, 0.0], 2.0);
        assert!(sprt.test().log_a.exp() > a0);
        assert!(sprt.rejection_bound() < 1.0 / a0);
    }
}
