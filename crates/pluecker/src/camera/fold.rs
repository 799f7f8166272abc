//! The fold radius of a camera model: the first radius where its radial distortion stops
//! increasing (beyond it the image folds and pixels have no preimage on the branch through the
//! principal point).

use super::model::{CameraModel, FOV_SERIES_BOUND};

/// The radius `r*` of normalised coordinates where the radial part of the distortion of `model` stops
/// increasing (`∞` when it increases everywhere): the first positive zero of `dρ/dr` for the radial map
/// `ρ(r) = r g(r²)`, or of the rational model's denominator, or for the fisheyes the first zero of
/// `dθ_d/dθ` in `θ = atan r < π/2`, or where the projection stops existing (division, EUCM). Beyond it
/// the distortion folds back, and a pixel whose Newton solution lies there has no preimage on the
/// branch through the principal point ([`super::Camera::unproject`]).
///
/// In `s = r²` the zeros are those of polynomials: `1 + 3k s` (SIMPLE_RADIAL), `1 + 3k₁ s + 5k₂ s²`
/// (RADIAL, OPENCV), `(1 + 3k₁ s + 5k₂ s² + 7k₃ s³) den(s) − num(s) (2k₄ s + 4k₅ s² + 6k₆ s³)` and
/// `den(s)` (FULL_OPENCV, `g = num / den`), and in `t = θ²` `1 + 3k₁ t + 5k₂ t² + …`, the odd
/// multiples of the radial coefficients (every fisheye: `θ_d = θ (1 + k₁ θ² + …)`; SIMPLE_FISHEYE and
/// FISHEYE have `θ_d = θ`, increasing: `∞`). Tangential and thin-prism terms are not part of it (the
/// Jacobian test of the unprojection covers them where they fold). The others, in closed form:
/// - FOV: `ρ = atan(2 r tan(ω/2)) / ω` increases for `0 < |ω| < π` (`∞`), decreases at once otherwise
///   (`0`); COLMAP's series in `ω` increases (`ρ' = 1 − ω²/12 + ω² r² > 0` for `ω² < 1e-4`), and its
///   series in `r`, `ρ' ∝ 1 − 4 tan²(ω/2) r²`, turns at `r = 1 / (2 |tan(ω/2)|)` if that is below
///   its range `r < 0.01`.
/// - division: `ρ' = 2 / (q (1 + q))`, `q = √(1 − 4k r²)`, is positive wherever the projection exists:
///   `∞` for `k ≤ 0`, `1 / (2 √k)` (the edge of its domain, where `ρ' = ∞`) for `k > 0`.
/// - EUCM: `ρ' = (α / q + 1 − α) / den²`, `q = √(1 + β r²)`, `den = α q + 1 − α`: the first `r > 0`
///   where `q = 0` (the edge of the domain), `den = 0` (a pole, `q = (α − 1) / α`) or the numerator
///   vanishes (`q = α / (α − 1)`); `∞` for COLMAP's valid range `0 ≤ α ≤ 1`, `β > 0`.
pub fn fold_radius(model: CameraModel, params: &[f64]) -> f64 {
    let p = params;
    let radius_of_s = |s: Option<f64>| s.map_or(f64::INFINITY, f64::sqrt);
    // 1 + 3k₁ t + 5k₂ t² + …: the derivative of t ↦ √t (1 + k₁ t + k₂ t² + …) times 2√t.
    let odd_slope = |k: &[f64]| {
        std::iter::once(1.0)
            .chain(k.iter().enumerate().map(|(i, c)| (2 * i + 3) as f64 * c))
            .collect::<Vec<f64>>()
    };
    let fisheye = |k: &[f64]| match first_positive_root(&odd_slope(k)) {
        Some(t) if t.sqrt() < std::f64::consts::FRAC_PI_2 => t.sqrt().tan(),
        _ => f64::INFINITY,
    };
    match model {
        CameraModel::SimplePinhole | CameraModel::Pinhole | CameraModel::SkewedPinhole => f64::INFINITY,
        CameraModel::SimpleRadial => radius_of_s(first_positive_root(&odd_slope(&p[3..4]))),
        CameraModel::Radial => radius_of_s(first_positive_root(&odd_slope(&p[3..5]))),
        CameraModel::OpenCv => radius_of_s(first_positive_root(&odd_slope(&p[4..6]))),
        CameraModel::FullOpenCv => {
            let (k1, k2, k3, k4, k5, k6) = (p[4], p[5], p[8], p[9], p[10], p[11]);
            let num = [1.0, k1, k2, k3];
            let den = [1.0, k4, k5, k6];
            let slope = [1.0, 3.0 * k1, 5.0 * k2, 7.0 * k3];
            let den_slope = [0.0, 2.0 * k4, 4.0 * k5, 6.0 * k6];
            let mut derivative = [0.0; 7];
            for i in 0..4 {
                for j in 0..4 {
                    derivative[i + j] += slope[i] * den[j] - num[i] * den_slope[j];
                }
            }
            let fold = first_positive_root(&derivative);
            let pole = first_positive_root(&den);
            radius_of_s(match (fold, pole) {
                (Some(a), Some(b)) => Some(a.min(b)),
                (a, b) => a.or(b),
            })
        }
        CameraModel::OpenCvFisheye => fisheye(&p[4..8]),
        CameraModel::SimpleRadialFisheye => fisheye(&p[3..4]),
        CameraModel::RadialFisheye => fisheye(&p[3..5]),
        CameraModel::ThinPrismFisheye => fisheye(&[p[4], p[5], p[8], p[9]]),
        CameraModel::RadTanThinPrismFisheye => fisheye(&p[4..10]),
        CameraModel::SimpleFisheye | CameraModel::Fisheye => f64::INFINITY,
        CameraModel::Fov => {
            let omega = p[4];
            if omega * omega < FOV_SERIES_BOUND {
                return f64::INFINITY;
            }
            let t = (omega / 2.0).tan();
            // |ω| ≥ 0.01 here, so t / ω is a number whenever t is finite.
            if !t.is_finite() || t / omega <= 0.0 {
                return 0.0;
            }
            let turn = 1.0 / (2.0 * t.abs());
            if turn * turn < FOV_SERIES_BOUND {
                turn
            } else {
                f64::INFINITY
            }
        }
        CameraModel::SimpleDivision | CameraModel::Division => {
            let k = p[p.len() - 1];
            if k > 0.0 {
                0.5 / k.sqrt()
            } else {
                f64::INFINITY
            }
        }
        CameraModel::Eucm => {
            let (alpha, beta) = (p[4], p[5]);
            // r² of a value of q = √(1 + β r²), when it is reached at some r > 0.
            let s_of_q = |q: f64| {
                let s = (q * q - 1.0) / beta;
                (q >= 0.0 && s > 0.0 && s.is_finite()).then_some(s)
            };
            [
                s_of_q(0.0),
                s_of_q((alpha - 1.0) / alpha),
                s_of_q(alpha / (alpha - 1.0)),
            ]
            .into_iter()
            .flatten()
            .min_by(f64::total_cmp)
            .map_or(f64::INFINITY, f64::sqrt)
        }
    }
}

/// The least positive real root of `c₀ + c₁ x + … + c_d x^d` (`c₀ ≠ 0`), from the eigenvalues of its
/// companion matrix; a root is taken as real when its imaginary part is below `1e-6` of its modulus (a
/// double root that only touches zero may come out so, and is then counted: the answer errs small).
fn first_positive_root(coefficients: &[f64]) -> Option<f64> {
    let degree = coefficients.iter().rposition(|&c| c != 0.0)?;
    if degree == 0 {
        return None;
    }
    let lead = coefficients[degree];
    if coefficients[..degree].iter().any(|c| !(c / lead).is_finite()) {
        // A leading coefficient too small to divide by: its roots are beyond any double, so the
        // polynomial of one degree less has the same roots in range.
        return first_positive_root(&coefficients[..degree]);
    }
    let companion = nalgebra::DMatrix::from_fn(degree, degree, |i, j| {
        if j == degree - 1 {
            -coefficients[i] / lead
        } else if i == j + 1 {
            1.0
        } else {
            0.0
        }
    });
    companion
        .complex_eigenvalues()
        .iter()
        .filter(|z| z.re > 0.0 && z.im.abs() <= 1e-6 * z.norm())
        .map(|z| z.re)
        .min_by(f64::total_cmp)
}
