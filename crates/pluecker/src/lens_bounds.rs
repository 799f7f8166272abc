//! Interval enclosures of a lens's distortion Jacobian `∂D/∂n` over a box of normalised coordinates,
//! for the certificates through a lens ([`crate::triangulation::point::lens`]).
//!
//! They cover the radially symmetric models (every model whose tangential and thin-prism terms are
//! zero), in two families of [`crate::camera_model`]'s table:
//! - **polynomial**, `D(n) = n g(s)`, `s = |n|²`, `g(s) = 1 + c₁s + c₂s² + …` (SIMPLE_RADIAL, RADIAL,
//!   OPENCV, FULL_OPENCV without a denominator): `∂D/∂n = g I + 2g' n nᵀ`;
//! - **fisheye**, `D(n) = m g(θ²)`, `m = n σ(r)`, `σ = θ/r`, `θ = atan r` (`|m| = θ`; the fisheye
//!   models): `∂D/∂n = (g I + 2g' m mᵀ)(σ I + q n nᵀ)` with `q = σ'(r)/r`.
//!
//! Over a box the enclosure evaluates these formulas in interval arithmetic
//! ([`crate::global::interval`]), with exact ranges for the one-dimensional pieces: `θ` is increasing
//! in `r`; `σ(r) = ∫₀¹ du/(1 + r²u²)` is decreasing; `q(r) = −∫₀¹ 2u²/(1 + r²u²)² du` (from
//! `d/dt (t/(1 + t²) − atan t) = −2t²/(1 + t²)²`) is increasing, from `−⅔` at `r = 0`. Each enclosure is
//! widened by [`ROUNDING`] of its magnitude for the rounding of its floating-point evaluation (the
//! interval type does not round outwards).
//!
//! Where a box reaches the lens's fold radius ([`LensCamera::fold_radius`]) there is no enclosure:
//! the certificates work inside it, where the distortion is one-to-one.

use crate::camera_model::{CameraModel, LensCamera};
use crate::global::interval::Interval;
use nalgebra::{Matrix2, Vector2};

/// The relative widening of every enclosure for the rounding of its evaluation (a few hundred
/// operations of relative error 1.1e-16 each, with room to spare).
pub const ROUNDING: f64 = 1e-12;

/// A radially symmetric distortion (module docs).
#[derive(Debug, Clone, PartialEq)]
pub enum RadialProfile {
    /// `D(n) = n g(|n|²)` with `g(s) = 1 + c₁s + c₂s² + …`, the coefficients `[c₁, c₂, …]`.
    Polynomial(Vec<f64>),
    /// `D(n) = m g(θ²)`, `m = n θ/r`, `θ = atan |n|`, with `g` as above in `θ²`.
    Fisheye(Vec<f64>),
}

/// The radial profile of `lens`, or `None` when its distortion is not radially symmetric (non-zero
/// tangential or thin-prism terms, a rational FULL_OPENCV) or is not covered (FOV, the division models,
/// EUCM).
pub fn radial_profile(lens: &LensCamera) -> Option<RadialProfile> {
    let p = lens.params();
    let zero = |range: &[f64]| range.iter().all(|&v| v == 0.0);
    use RadialProfile::{Fisheye, Polynomial};
    match lens.model() {
        CameraModel::SimplePinhole | CameraModel::Pinhole => Some(Polynomial(vec![])),
        CameraModel::SimpleRadial => Some(Polynomial(p[3..4].to_vec())),
        CameraModel::Radial => Some(Polynomial(p[3..5].to_vec())),
        CameraModel::OpenCv if zero(&p[6..8]) => Some(Polynomial(p[4..6].to_vec())),
        CameraModel::FullOpenCv if zero(&p[6..8]) && zero(&p[9..12]) => Some(Polynomial(vec![p[4], p[5], p[8]])),
        CameraModel::SimpleFisheye | CameraModel::Fisheye => Some(Fisheye(vec![])),
        CameraModel::SimpleRadialFisheye => Some(Fisheye(p[3..4].to_vec())),
        CameraModel::RadialFisheye => Some(Fisheye(p[3..5].to_vec())),
        CameraModel::OpenCvFisheye => Some(Fisheye(p[4..8].to_vec())),
        CameraModel::ThinPrismFisheye if zero(&p[6..8]) && zero(&p[10..12]) => {
            Some(Fisheye(vec![p[4], p[5], p[8], p[9]]))
        }
        CameraModel::RadTanThinPrismFisheye if zero(&p[10..16]) => Some(Fisheye(p[4..10].to_vec())),
        _ => None,
    }
}

/// A 2x2 matrix of intervals, row-major.
pub type IntervalMatrix = [[Interval; 2]; 2];

/// `(g, g')` of `g(s) = 1 + c₁s + c₂s² + …` over the interval `s` (Horner's scheme).
fn polynomial(coefficients: &[f64], s: Interval) -> (Interval, Interval) {
    let (mut p, mut dp) = (Interval::point(0.0), Interval::point(0.0));
    for &c in coefficients.iter().rev() {
        dp = p.add(s.mul(dp));
        p = Interval::point(c).add(s.mul(p));
    }
    (Interval::point(1.0).add(s.mul(p)), p.add(s.mul(dp)))
}

/// `g I + 2g' v vᵀ` over the box `v ∈ x × y`.
fn scaled(g: Interval, dg: Interval, x: Interval, y: Interval) -> IntervalMatrix {
    let two_dg = dg.scale(2.0);
    let off = two_dg.mul(x.mul(y));
    [[g.add(two_dg.mul(x.sqr())), off], [off, g.add(two_dg.mul(y.sqr()))]]
}

/// The product of two interval matrices.
pub fn product(a: &IntervalMatrix, b: &IntervalMatrix) -> IntervalMatrix {
    let entry = |i: usize, j: usize| a[i][0].mul(b[0][j]).add(a[i][1].mul(b[1][j]));
    [[entry(0, 0), entry(0, 1)], [entry(1, 0), entry(1, 1)]]
}

/// `σ(r) = atan(r)/r` (1 at 0), with a series below 0.1 whose truncation is bounded by its next term.
fn sigma(r: f64) -> Interval {
    if r < 0.1 {
        // atan(r)/r = 1 − r²/3 + r⁴/5 − r⁶/7 + …, alternating with decreasing terms for r < 1.
        let s = r * r;
        let value = 1.0 - s / 3.0 + s * s / 5.0 - s * s * s / 7.0;
        Interval::new(value, value + s * s * s * s / 9.0)
    } else {
        Interval::point(r.atan() / r)
    }
}

/// `q(r) = σ'(r)/r = (r/(1 + r²) − atan r)/r³` (module docs; −⅔ at 0), with a series below 0.1.
fn q(r: f64) -> Interval {
    if r < 0.1 {
        // −2 Σₖ (−1)ᵏ (k + 1) r²ᵏ/(2k + 3): alternating with decreasing terms for r < 0.1.
        let s = r * r;
        let value = -2.0 / 3.0 + 4.0 / 5.0 * s - 6.0 / 7.0 * s * s + 8.0 / 9.0 * s * s * s;
        Interval::new(value - 10.0 / 11.0 * s * s * s * s, value)
    } else {
        Interval::point((r / (1.0 + r * r) - r.atan()) / (r * r * r))
    }
}

/// Widens `v` by [`ROUNDING`] of its magnitude (and the smallest normal number).
fn widened(v: Interval) -> Interval {
    let pad = ROUNDING * v.mag() + f64::MIN_POSITIVE;
    Interval::new(v.lo - pad, v.hi + pad)
}

/// An enclosure of `∂D/∂n` over the box `[lo, hi]` of normalised coordinates for `profile`, or
/// `None` when the box is empty or reaches `fold_radius` (module docs).
pub fn jacobian_enclosure(
    profile: &RadialProfile,
    fold_radius: f64,
    lo: &Vector2<f64>,
    hi: &Vector2<f64>,
) -> Option<IntervalMatrix> {
    if !(lo.x <= hi.x && lo.y <= hi.y) {
        return None;
    }
    let (x, y) = (Interval::new(lo.x, hi.x), Interval::new(lo.y, hi.y));
    // The range of r = |n| over the box: the nearest and the farthest point of the box.
    let r_lo = Vector2::new(x.mig(), y.mig()).norm();
    let r_hi = Vector2::new(x.mag(), y.mag()).norm();
    if !(r_hi < fold_radius) || !r_hi.is_finite() {
        return None;
    }
    let j = match profile {
        RadialProfile::Polynomial(c) => {
            let (g, dg) = polynomial(c, x.sqr().add(y.sqr()));
            scaled(g, dg, x, y)
        }
        RadialProfile::Fisheye(c) => {
            let theta = Interval::new(r_lo.atan(), r_hi.atan());
            let s = Interval::new(sigma(r_hi).lo, sigma(r_lo).hi);
            let qr = Interval::new(q(r_lo).lo, q(r_hi).hi);
            let (g, dg) = polynomial(c, theta.sqr());
            let jd = scaled(g, dg, x.mul(s), y.mul(s));
            // σ I + q n nᵀ is `scaled` with g = σ and 2g' = q.
            let jm = scaled(s, qr.scale(0.5), x, y);
            product(&jd, &jm)
        }
    };
    let out = j.map(|row| row.map(widened));
    out.iter()
        .flatten()
        .all(|v| v.lo.is_finite() && v.hi.is_finite())
        .then_some(out)
}

/// The entrywise radius `E` of the enclosure `j` about the matrix `j0`: `|J − j0| ≤ E` entrywise for
/// every `J` in `j` (`j0` need not be its centre).
pub fn radius_about(j: &IntervalMatrix, j0: &Matrix2<f64>) -> Matrix2<f64> {
    Matrix2::from_fn(|r, c| (j[r][c].hi - j0[(r, c)]).max(j0[(r, c)] - j[r][c].lo).max(0.0))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::Rng;

    fn lenses() -> Vec<LensCamera> {
        vec![
            LensCamera::new(CameraModel::SimpleRadial, &[5000.0, 300.0, 300.0, -14.0]).unwrap(),
            LensCamera::new(CameraModel::Radial, &[800.0, 320.0, 240.0, 0.2, -0.05]).unwrap(),
            LensCamera::new(CameraModel::OpenCv, &[600.0, 610.0, 320.0, 240.0, -0.3, 0.08, 0.0, 0.0]).unwrap(),
            LensCamera::new(
                CameraModel::OpenCvFisheye,
                &[300.0, 300.0, 512.0, 384.0, 0.05, -0.01, 0.002, -3e-4],
            )
            .unwrap(),
            LensCamera::new(CameraModel::RadialFisheye, &[300.0, 512.0, 384.0, -0.02, 0.003]).unwrap(),
            LensCamera::new(CameraModel::SimpleFisheye, &[300.0, 512.0, 384.0]).unwrap(),
        ]
    }

    #[test]
    fn the_enclosure_holds_the_jacobian_at_every_sampled_point_of_the_box() {
        // The library's own Jacobian (checked against pycolmap elsewhere) at random points of random
        // boxes, some containing the principal point, some near the fold: always inside.
        let mut rng = Rng::new(31);
        let mut checked = 0;
        for lens in lenses() {
            let profile = radial_profile(&lens).unwrap();
            let fold = lens.fold_radius().min(10.0);
            for _ in 0..400 {
                let centre = Vector2::new(rng.normal(), rng.normal()) * (0.5 * fold * rng.uniform_in(0.0, 1.0));
                let half = Vector2::new(rng.uniform_in(0.0, 0.05), rng.uniform_in(0.0, 0.05)) * fold;
                let Some(j) = jacobian_enclosure(&profile, lens.fold_radius(), &(centre - half), &(centre + half))
                else {
                    continue;
                };
                for _ in 0..20 {
                    let n = centre
                        + half.component_mul(&Vector2::new(rng.uniform_in(-1.0, 1.0), rng.uniform_in(-1.0, 1.0)));
                    let exact = lens.distort(&n).1;
                    for r in 0..2 {
                        for c in 0..2 {
                            let v = exact[(r, c)];
                            assert!(
                                j[r][c].lo <= v && v <= j[r][c].hi,
                                "{:?} at {n:?}: entry ({r},{c}) = {v} outside {:?}",
                                lens.model(),
                                j[r][c]
                            );
                        }
                    }
                    checked += 1;
                }
            }
        }
        assert!(checked > 30_000, "{checked}");
    }

    #[test]
    fn the_enclosure_shrinks_to_the_jacobian_with_the_box() {
        // Not vacuous: a box 1e-6 wide encloses J to about 1e-5 of its size (the dependency effect
        // of interval arithmetic is of the order of the box's width times the second derivative).
        for lens in lenses() {
            let profile = radial_profile(&lens).unwrap();
            let n = Vector2::new(0.3, -0.2) * lens.fold_radius().min(2.0);
            let h = Vector2::repeat(1e-6);
            let j = jacobian_enclosure(&profile, lens.fold_radius(), &(n - h), &(n + h)).unwrap();
            let e = radius_about(&j, &lens.distort(&n).1);
            assert!(e.norm() < 1e-4, "{:?}: {e}", lens.model());
        }
    }

    #[test]
    fn boxes_reaching_the_fold_have_no_enclosure() {
        let lens = LensCamera::new(CameraModel::SimpleRadial, &[5000.0, 300.0, 300.0, -14.0]).unwrap();
        let profile = radial_profile(&lens).unwrap();
        let r = lens.fold_radius();
        assert!(jacobian_enclosure(&profile, r, &Vector2::new(0.9 * r, 0.0), &Vector2::new(1.01 * r, 0.01)).is_none());
        assert!(jacobian_enclosure(&profile, r, &Vector2::new(0.5 * r, 0.0), &Vector2::new(0.6 * r, 0.01)).is_some());
    }

    #[test]
    fn lenses_with_tangential_terms_have_no_profile() {
        let lens = LensCamera::new(
            CameraModel::OpenCv,
            &[600.0, 610.0, 320.0, 240.0, -0.3, 0.08, 1e-4, 0.0],
        )
        .unwrap();
        assert_eq!(radial_profile(&lens), None);
    }
}
