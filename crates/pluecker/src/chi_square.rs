//! The χ² test of a least-squares fit against the noise the caller gave.
//!
//! With Gaussian noise of the given standard deviation (or covariance), the whitened residuals `r` of
//! a maximum-likelihood fit of `p` parameters to `m` residuals satisfy, to first order,
//! `Σ r² ~ χ²(m − p)`. A fit whose `Σ r²` has a tail probability below [`CONSISTENCY_LEVEL`] is not
//! explained by that noise: a wrong model (lens distortion left in the pixels, a wrong camera, the
//! wrong minimum) or noise larger than stated. [`ResidualTest`] records the test.

/// Tail probability below which the residuals are called inconsistent with the given noise.
pub const CONSISTENCY_LEVEL: f64 = 1e-3;

/// The χ² test of one fit.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct ResidualTest {
    /// `Σ r²` of the whitened residuals (pixels divided by the given σ, or whitened by the given
    /// covariances).
    pub chi2: f64,
    /// Degrees of freedom `m − p`: residuals minus fitted parameters.
    pub dof: usize,
    /// `P(χ²(dof) ≥ chi2)`.
    pub p_value: f64,
    /// `p_value ≥ CONSISTENCY_LEVEL`.
    pub consistent: bool,
}

impl ResidualTest {
    /// The test of `chi2` with `dof` degrees of freedom; `None` when `dof` is 0 (the residuals are
    /// then zero for any noise) or `chi2` is not finite.
    pub fn new(chi2: f64, dof: usize) -> Option<ResidualTest> {
        if dof == 0 || !chi2.is_finite() || chi2 < 0.0 {
            return None;
        }
        let p_value = survival(chi2, dof);
        Some(ResidualTest {
            chi2,
            dof,
            p_value,
            consistent: p_value >= CONSISTENCY_LEVEL,
        })
    }
}

/// `P(χ²(dof) ≥ x)`: the regularised upper incomplete gamma function `Q(dof/2, x/2)`, by its series
/// below `a + 1` and its continued fraction (modified Lentz) above, to about 1e-14 relative.
pub fn survival(x: f64, dof: usize) -> f64 {
    let (a, x) = (0.5 * dof as f64, 0.5 * x);
    if x <= 0.0 {
        return 1.0;
    }
    let log_prefactor = a * x.ln() - x - ln_gamma(a);
    if x < a + 1.0 {
        // P(a, x) = e^{-x} x^a / Γ(a+1) Σ x^n / ((a+1)…(a+n)).
        let (mut term, mut sum, mut ap) = (1.0 / a, 1.0 / a, a);
        for _ in 0..1000 {
            ap += 1.0;
            term *= x / ap;
            sum += term;
            if term.abs() < sum.abs() * 1e-16 {
                break;
            }
        }
        (1.0 - sum * log_prefactor.exp()).max(0.0)
    } else {
        // Q(a, x) = e^{-x} x^a / Γ(a) · 1/(x + 1 − a − 1·(1 − a)/(x + 3 − a − …)).
        let tiny = 1e-300;
        let mut b = x + 1.0 - a;
        let mut c = 1.0 / tiny;
        let mut d = 1.0 / b;
        let mut h = d;
        for i in 1..1000 {
            let an = -(i as f64) * (i as f64 - a);
            b += 2.0;
            d = an * d + b;
            if d.abs() < tiny {
                d = tiny;
            }
            c = b + an / c;
            if c.abs() < tiny {
                c = tiny;
            }
            d = 1.0 / d;
            let step = d * c;
            h *= step;
            if (step - 1.0).abs() < 1e-16 {
                break;
            }
        }
        (log_prefactor.exp() * h).clamp(0.0, 1.0)
    }
}

/// `ln Γ(a)` for `a > 0` (Lanczos, g = 7, 9 terms: about 1e-15 relative).
fn ln_gamma(a: f64) -> f64 {
    const G: f64 = 7.0;
    const C: [f64; 9] = [
        0.999_999_999_999_809_9,
        676.520_368_121_885_1,
        -1_259.139_216_722_402_8,
        771.323_428_777_653_1,
        -176.615_029_162_140_6,
        12.507_343_278_686_905,
        -0.138_571_095_265_720_12,
        9.984_369_578_019_572e-6,
        1.505_632_735_149_311_6e-7,
    ];
    if a < 0.5 {
        // Reflection: Γ(a) Γ(1 − a) = π / sin(πa).
        let pi = std::f64::consts::PI;
        return (pi / (pi * a).sin()).ln() - ln_gamma(1.0 - a);
    }
    let a = a - 1.0;
    let t = a + G + 0.5;
    let series = C[1..]
        .iter()
        .enumerate()
        .fold(C[0], |s, (i, c)| s + c / (a + i as f64 + 1.0));
    0.5 * (2.0 * std::f64::consts::PI).ln() + (a + 0.5) * t.ln() - t + series.ln()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn closed_forms_of_even_degrees_of_freedom() {
        // dof = 2: e^{-x/2}; dof = 4: e^{-x/2} (1 + x/2); dof = 6: e^{-x/2} (1 + x/2 + x²/8).
        for x in [0.01f64, 0.5, 1.0, 2.0, 3.0, 5.0, 10.0, 30.0, 100.0] {
            let h = 0.5 * x;
            let expected = [(-h).exp(), (-h).exp() * (1.0 + h), (-h).exp() * (1.0 + h + h * h / 2.0)];
            for (k, e) in expected.iter().enumerate() {
                let got = survival(x, 2 * (k + 1));
                assert!(
                    (got - e).abs() <= 1e-13 * e.max(1e-300) + 1e-300,
                    "x {x} dof {}: {got} vs {e}",
                    2 * (k + 1)
                );
            }
        }
    }

    #[test]
    fn odd_degrees_of_freedom_and_known_quantiles() {
        // dof = 1: P(χ² ≥ 3.841459) = 0.05 and P(χ² ≥ 6.634897) = 0.01 (the tabulated quantiles);
        // dof = 10: P(χ² ≥ 29.58830) = 0.001; dof = 194: the median is ≈ 193.33.
        for (x, dof, p) in [
            (3.841_458_820_694_124, 1, 0.05),
            (6.634_896_601_021_214, 1, 0.01),
            (29.588_298_445_074_4, 10, 0.001),
        ] {
            assert!((survival(x, dof) - p).abs() < 1e-9 * p.max(1e-3), "{x} {dof}");
        }
        assert!((survival(193.334, 194) - 0.5).abs() < 1e-3);
        assert_eq!(survival(0.0, 3), 1.0);
        assert!(survival(1e4, 3) < 1e-300);
    }

    #[test]
    fn the_test_is_none_without_degrees_of_freedom() {
        assert!(ResidualTest::new(1.0, 0).is_none());
        assert!(ResidualTest::new(f64::NAN, 4).is_none());
        let t = ResidualTest::new(200.0, 10).unwrap();
        assert!(!t.consistent && t.p_value < 1e-30);
        assert!(ResidualTest::new(9.0, 10).unwrap().consistent);
    }
}
