//! Image lines and ellipses fitted to detected edge points, with the covariance of their residual
//! (Josephson & Kahl 2008, section 3.1 and Figures 1-2).
//!
//! The triangulation cost (eq. 19) weights each view by the inverse covariance of its residual
//! (eq. 18). For a primitive fitted to edge points with i.i.d. Gaussian pixel noise of standard
//! deviation σ, the residual of the true primitive in the frame of the fitted one (see
//! `line::residual` and `quadric::residual`) is, to first order, `r = −J δ`, with `δ`
//! the error of the fit and `J` the Jacobian of the residual with the frame held fixed (the frame's own
//! dependence on the fit cancels to first order, because the residual of the fit in its own frame is
//! identically 0). These functions return the fit and that covariance `J Cov(δ) Jᵀ`.

use super::line::residual::{LineFrame, LINE_FRAME_DISTANCE};
use super::quadric::residual::{ConicFrame, Vector5};
use crate::covariance::whitening;
use crate::error::{Error, Result};
use crate::geometry::quadric::{sym3_to_vec, Ellipse};
use crate::rng::Rng;
use nalgebra::{Matrix2, Matrix3, Rotation2, SMatrix, SVector, Vector2, Vector3, Vector6};

/// Iteration cap of the reweighted conic fit.
const MAX_REWEIGHTING: usize = 50;
/// Relative change of the conic coefficients below which reweighting stops.
const REWEIGHTING_TOLERANCE: f64 = 1e-13;

/// A line fitted to image points.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct FittedLine {
    /// Homogeneous image line `(n, c₀)`, unit normal, `c₀ ≤ 0` (the sign convention of
    /// [`LineFrame`]); pixels.
    pub line: Vector3<f64>,
    /// Covariance of the residual of `line::residual` (pixels²), for `triangulate_line`.
    #[cfg_attr(feature = "serde", serde(with = "crate::matrix_rows"))]
    pub covariance: Matrix2<f64>,
    /// Root-mean-square distance of the points from the line, pixels.
    pub rms_distance: f64,
}

/// An ellipse fitted to image points.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct FittedConic {
    /// The point conic `c` of eq. 8, pixels, normalised to unit Frobenius norm.
    #[cfg_attr(feature = "serde", serde(with = "crate::matrix_rows"))]
    pub conic: Matrix3<f64>,
    /// The same ellipse: centre, axes, semi-axes.
    pub ellipse: Ellipse,
    /// Covariance of the 5-entry residual of `quadric::residual`, for `triangulate_quadric`.
    #[cfg_attr(feature = "serde", serde(with = "crate::matrix_rows"))]
    pub covariance: SMatrix<f64, 5, 5>,
    /// Reweighting iterations used.
    pub iterations: usize,
}

fn check_points(points: &[Vector2<f64>], sigma: f64, needed: usize, what: &str) -> Result<()> {
    if points.len() < needed {
        return Err(Error::TooFewCorrespondences {
            method: what.into(),
            required: format!("at least {needed} points"),
            actual: format!("{}", points.len()),
        });
    }
    if let Some(i) = points.iter().position(|p| !p.iter().all(|v| v.is_finite())) {
        return Err(Error::NonFinite {
            what: "points".into(),
            index: i,
        });
    }
    if !(sigma.is_finite() && sigma > 0.0) {
        return Err(Error::InvalidOption {
            name: "sigma".into(),
            reason: "must be a positive finite number of pixels".into(),
        });
    }
    Ok(())
}

/// True when every point equals the first to within the rounding of their coordinates (4 ulps of
/// the largest magnitude): no line, let alone a conic, is determined.
fn coincide(points: &[Vector2<f64>]) -> bool {
    let largest = points.iter().map(|p| p.amax()).fold(0.0, f64::max);
    let spread = points.iter().map(|p| (p - points[0]).amax()).fold(0.0, f64::max);
    !(spread > 4.0 * f64::EPSILON * largest)
}

/// The total-least-squares line of points that do not [`coincide`]: the centroid, the unit normal,
/// and the points' centred coordinates divided by `scale` (their largest magnitude), so that squares
/// of coordinates up to `f64::MAX` neither overflow nor underflow.
struct PrincipalLine {
    centroid: Vector2<f64>,
    normal: Vector2<f64>,
    scaled: Vec<Vector2<f64>>,
    scale: f64,
}

impl PrincipalLine {
    fn of(points: &[Vector2<f64>]) -> PrincipalLine {
        let n = points.len() as f64;
        let largest = points.iter().map(|p| p.amax()).fold(0.0, f64::max);
        let centroid = points.iter().map(|p| p / largest).sum::<Vector2<f64>>() / n * largest;
        let centred: Vec<Vector2<f64>> = points.iter().map(|p| p - centroid).collect();
        let scale = centred.iter().map(|d| d.amax()).fold(0.0, f64::max);
        let scaled: Vec<Vector2<f64>> = centred.iter().map(|d| d / scale).collect();
        let scatter = scaled.iter().fold(Matrix2::zeros(), |acc, d| acc + d * d.transpose());
        let eig = scatter.symmetric_eigen();
        let minor = if eig.eigenvalues[0] >= eig.eigenvalues[1] { 1 } else { 0 };
        PrincipalLine {
            centroid,
            normal: eig.eigenvectors.column(minor).into_owned(),
            scaled,
            scale,
        }
    }

    /// `Σ (n·(pₖ − m))² / σ²`: the χ² of the points' distances from the line for noise `sigma`.
    fn chi_square(&self, sigma: f64) -> f64 {
        let ratio = self.scale / sigma;
        self.scaled.iter().map(|d| (self.normal.dot(d) * ratio).powi(2)).sum()
    }
}

/// Pixel noise σ assumed by the Python `fit_line`/`fit_conic` when none is given.
pub const DEFAULT_SIGMA_PX: f64 = 1.0;

/// Side of the square images of the paper's Figures 1-2 (section 3.1), pixels.
pub const PAPER_IMAGE_SIZE: f64 = 1000.0;

/// Total least squares line through `points` (pixels) and the covariance of its residual for
/// i.i.d. isotropic Gaussian noise of `sigma` px per coordinate.
///
/// To first order the fit moves by `δρ` along the normal at the centroid `m` (variance `σ²/N`) and
/// turns by `δθ` (variance `σ²/S`, `S = Σ sₖ²` with `sₖ` the positions along the line, uncorrelated
/// with `δρ` since `Σ sₖ = 0`). With the frame fixed, the residual is `D δθ n⊥ + (δρ + a δθ) n`,
/// `a = n⊥·m` (the position of the centroid along the line from the foot point), hence in the basis
/// `(n⊥, n)`: `Σ = σ² [[D²/S, D a/S], [D a/S, 1/N + a²/S]]`, computed as `σ² Σ₁` with the ratios
/// `D/√S`, `a/√S` (no square of a coordinate is formed).
///
/// Errors: fewer than 2 points, non-finite values, `sigma ≤ 0`, all points coincident (to the
/// rounding of their coordinates), or a `σ` for which `σ² Σ₁` overflows or underflows
/// ([`Error::InvalidOption`] naming `sigma`, see `scaled_covariance`).
pub fn fit_line(points: &[Vector2<f64>], sigma: f64) -> Result<FittedLine> {
    check_points(points, sigma, 2, "fit_line")?;
    if coincide(points) {
        return Err(Error::Degenerate {
            what: "fit_line: all points coincide".into(),
        });
    }
    let fit = PrincipalLine::of(points);
    let (centroid, normal) = (fit.centroid, fit.normal);
    let frame = LineFrame::of_line(&Vector3::new(normal.x, normal.y, -normal.dot(&centroid))).ok_or_else(|| {
        Error::Degenerate {
            what: "fit_line: no line".into(),
        }
    })?;
    let n = frame.normal;
    let n_perp = Vector2::new(-n.y, n.x);
    // √S = scale · √(Σ (n⊥·dₖ)²) over the scaled centred points dₖ.
    let root_s = fit.scale * fit.scaled.iter().map(|d| n_perp.dot(d).powi(2)).sum::<f64>().sqrt();
    let (d, a) = (LINE_FRAME_DISTANCE / root_s, n_perp.dot(&centroid) / root_s);
    let unit = Matrix2::new(d * d, d * a, d * a, 1.0 / points.len() as f64 + a * a);
    let basis = Matrix2::from_columns(&[n_perp, n]);
    let unit = basis * unit * basis.transpose();
    let rms = fit.scale * (fit.chi_square(fit.scale) / points.len() as f64).sqrt();
    Ok(FittedLine {
        line: frame.line(),
        covariance: scaled_covariance(&unit, sigma)?,
        rms_distance: rms,
    })
}

/// `σ² Σ₁` for the covariance `Σ₁` of unit noise, or [`Error::InvalidOption`] naming `sigma` when
/// `σ² Σ₁` overflows, or underflows where `Σ₁` is a usable covariance (see [`whitening`]) and `σ² Σ₁`
/// is not. A `Σ₁` that is itself numerically singular (points far closer together than their
/// distance from the origin) is returned scaled: it is the data's, not `σ`'s.
fn scaled_covariance<const D: usize>(unit: &SMatrix<f64, D, D>, sigma: f64) -> Result<SMatrix<f64, D, D>> {
    let unit = 0.5 * (unit + unit.transpose());
    let scaled = unit * (sigma * sigma);
    let finite = scaled.iter().all(|v| v.is_finite());
    if !finite || (whitening(&unit, "covariance", 0).is_ok() && whitening(&scaled, "covariance", 0).is_err()) {
        let flow = if finite { "underflows" } else { "overflows" };
        return Err(Error::InvalidOption {
            name: "sigma".into(),
            reason: format!("σ = {sigma:e} px: the covariance σ² Σ {flow} double precision"),
        });
    }
    Ok(scaled)
}

/// The line through an image segment `a`–`b` (pixels) whose endpoints have i.i.d. Gaussian noise of
/// `sigma` px per coordinate: [`fit_line`] on the two endpoints (the paper's real-data setting when
/// only segments are known).
pub fn line_from_segment(a: &Vector2<f64>, b: &Vector2<f64>, sigma: f64) -> Result<FittedLine> {
    if coincide(&[*a, *b]) {
        return Err(Error::Degenerate {
            what: "line_from_segment: zero-length segment".into(),
        });
    }
    fit_line(&[*a, *b], sigma)
}

/// The line through the image points `a` and `b` (pixels) with independent Gaussian noise of
/// covariances `cov_a` and `cov_b` (pixels², any 2x2 positive definite: the endpoints of a segment seen
/// through a lens, whose undistorted covariances differ): [`line_from_segment`] for `σ² I`.
///
/// Only the noise across the line moves it: `x = n·δa`, `y = n·δb`, of variances `nᵀ Σ n`. With `L`
/// the signed length `n⊥·(b − a)` and `m` the midpoint, the line moves by `δρ = (x + y)/2` at `m` and
/// turns by `δθ = (x − y)/L` (the frame's sense of rotation); in the frame's basis `(n⊥, n)` its
/// residual is `(D δθ, δρ + (n⊥·m) δθ)` (as in [`fit_line`], where the two endpoints' equal variances
/// hide the sense), whose covariance this returns.
pub fn line_from_endpoints(
    a: &Vector2<f64>,
    b: &Vector2<f64>,
    cov_a: &Matrix2<f64>,
    cov_b: &Matrix2<f64>,
) -> Result<FittedLine> {
    if !(a.iter().chain(b.iter()).all(|v| v.is_finite())) {
        return Err(Error::NonFinite {
            what: "endpoints".into(),
            index: 0,
        });
    }
    if coincide(&[*a, *b]) {
        return Err(Error::Degenerate {
            what: "line_from_endpoints: zero-length segment".into(),
        });
    }
    for (i, c) in [cov_a, cov_b].into_iter().enumerate() {
        whitening(c, "endpoint covariances", i)?;
    }
    let centroid = 0.5 * (a + b);
    let direction = (b - a).normalize();
    let normal = Vector2::new(-direction.y, direction.x);
    let frame = LineFrame::of_line(&Vector3::new(normal.x, normal.y, -normal.dot(&centroid))).ok_or_else(|| {
        Error::Degenerate {
            what: "line_from_endpoints: no line".into(),
        }
    })?;
    let n = frame.normal;
    let n_perp = Vector2::new(-n.y, n.x);
    let length = n_perp.dot(&(b - a));
    let (var_x, var_y) = (n.dot(&(cov_a * n)), n.dot(&(cov_b * n)));
    let (d, pos) = (LINE_FRAME_DISTANCE / length, n_perp.dot(&centroid) / length);
    // r = A (x, y) with A = [[D/L, −D/L], [½ + pos, ½ − pos]] (pos = (n⊥·m)/L).
    let rows = Matrix2::new(d, -d, 0.5 + pos, 0.5 - pos);
    let local = rows * Matrix2::new(var_x, 0.0, 0.0, var_y) * rows.transpose();
    let basis = Matrix2::from_columns(&[n_perp, n]);
    let covariance = basis * local * basis.transpose();
    Ok(FittedLine {
        line: frame.line(),
        covariance: 0.5 * (covariance + covariance.transpose()),
        rms_distance: 0.0,
    })
}

/// The standard normal quantile of 0.999.
const Z_999: f64 = 3.090_232_306_167_813_5;

/// The `p` quantile of χ² with `k` degrees of freedom, `z` the standard normal quantile of `p`
/// (Wilson & Hilferty 1931: `(χ²/k)^⅓` is nearly normal with mean `1 − 2/(9k)` and variance `2/(9k)`;
/// within 1 % of the exact quantile at 0.999 for `k ≥ 3`).
fn chi_square_quantile(k: usize, z: f64) -> f64 {
    let k = k.max(1) as f64;
    let v = 2.0 / (9.0 * k);
    k * (1.0 - v + z * v.sqrt()).powi(3)
}

/// Monomials `(x², xy, y², x, y, 1)` of the conic `θᵀ m(x) = 0`.
fn monomials(x: &Vector2<f64>) -> Vector6<f64> {
    Vector6::new(x.x * x.x, x.x * x.y, x.y * x.y, x.x, x.y, 1.0)
}

/// The symmetric matrix of the conic with coefficients `θ` (order of [`monomials`]).
fn conic_matrix(t: &Vector6<f64>) -> Matrix3<f64> {
    Matrix3::new(
        t[0],
        t[1] / 2.0,
        t[3] / 2.0,
        t[1] / 2.0,
        t[2],
        t[4] / 2.0,
        t[3] / 2.0,
        t[4] / 2.0,
        t[5],
    )
}

/// Unit eigenvector of the least eigenvalue of a symmetric 6x6 matrix.
fn least_eigenvector(m: &SMatrix<f64, 6, 6>) -> Vector6<f64> {
    let eig = m.symmetric_eigen();
    eig.eigenvectors.column(eig.eigenvalues.imin()).into_owned()
}

/// An ellipse fitted to `points` (pixels) and the covariance of its residual for i.i.d. isotropic
/// Gaussian noise of `sigma` px per coordinate.
///
/// The fit is Sampson's iteratively reweighted algebraic fit on Hartley-normalised points (weights
/// `1/‖∇Q(xₖ)‖²`, started from the plain algebraic fit). To first order its coefficient vector `θ`
/// (unit norm) has the covariance of the KCR bound, `σ̄² (P M P)⁺` with `M = Σ m(xₖ) m(xₖ)ᵀ / ‖∇Q(xₖ)‖²`
/// and `P = I − θθᵀ` (Kanatani 1996, cited as \[12\] by the paper); it is propagated through the dual
/// conic and the normalisation of `quadric::residual`.
///
/// Errors: fewer than 5 points, non-finite values, `sigma ≤ 0`, points that no real ellipse fits, or a
/// `σ` for which the covariance overflows or underflows (as [`fit_line`], see `scaled_covariance`).
pub fn fit_conic(points: &[Vector2<f64>], sigma: f64) -> Result<FittedConic> {
    check_points(points, sigma, 5, "fit_conic")?;
    if coincide(points) {
        return Err(Error::Degenerate {
            what: "fit_conic: all points coincide".into(),
        });
    }
    let line = PrincipalLine::of(points);
    let (chi2, dof) = (line.chi_square(sigma), points.len() - 2);
    let bound = chi_square_quantile(dof, Z_999);
    if !(chi2 > bound) {
        return Err(Error::Degenerate {
            what: format!(
                "fit_conic: the points lie on a line to within the noise σ = {sigma:e} px (Σ d²/σ² = {chi2:.3e} \
                 ≤ {bound:.1}, the 99.9 % quantile of χ² with {dof} degrees of freedom): no ellipse is determined"
            ),
        });
    }
    let n = points.len() as f64;
    let centroid = line.centroid;
    let rms = line.scale * (line.scaled.iter().map(|d| d.norm_squared()).sum::<f64>() / n).sqrt();
    let scale = std::f64::consts::SQRT_2 / rms;
    let normalized: Vec<Vector2<f64>> = points.iter().map(|p| (p - centroid) * scale).collect();
    let design: Vec<Vector6<f64>> = normalized.iter().map(monomials).collect();
    let gradient = |t: &Vector6<f64>, x: &Vector2<f64>| {
        Vector2::new(
            2.0 * t[0] * x.x + t[1] * x.y + t[3],
            t[1] * x.x + 2.0 * t[2] * x.y + t[4],
        )
    };
    let weighted = |t: &Vector6<f64>| {
        normalized
            .iter()
            .zip(&design)
            .fold(SMatrix::<f64, 6, 6>::zeros(), |acc, (x, m)| {
                acc + m * m.transpose() / gradient(t, x).norm_squared().max(f64::MIN_POSITIVE)
            })
    };
    let mut theta = least_eigenvector(
        &design
            .iter()
            .fold(SMatrix::<f64, 6, 6>::zeros(), |acc, m| acc + m * m.transpose()),
    );
    let mut iterations = 0;
    while iterations < MAX_REWEIGHTING {
        let mut next = least_eigenvector(&weighted(&theta));
        if next.dot(&theta) < 0.0 {
            next = -next;
        }
        iterations += 1;
        let change = (next - theta).norm();
        theta = next;
        if change < REWEIGHTING_TOLERANCE {
            break;
        }
    }
    // Pixels: x̄ = H x.
    let h = Matrix3::new(
        scale,
        0.0,
        -scale * centroid.x,
        0.0,
        scale,
        -scale * centroid.y,
        0.0,
        0.0,
        1.0,
    );
    let to_pixels = |t: &Vector6<f64>| h.transpose() * conic_matrix(t) * h;
    let conic = to_pixels(&theta);
    let ellipse = Ellipse::from_primal(&conic).ok_or_else(|| Error::Degenerate {
        what: "fit_conic: the points do not lie on a real ellipse".into(),
    })?;
    let frame = ConicFrame::of_conic(&conic).expect("an ellipse has a frame");
    // KCR covariance of θ in the normalised image (noise σ̄ = σ · scale).
    let m = weighted(&theta);
    let p = SMatrix::<f64, 6, 6>::identity() - theta * theta.transpose();
    let eig = (p * m * p).symmetric_eigen();
    let null = (0..6)
        .max_by(|&i, &j| {
            eig.eigenvectors
                .column(i)
                .dot(&theta)
                .abs()
                .total_cmp(&eig.eigenvectors.column(j).dot(&theta).abs())
        })
        .unwrap();
    let mut pinv = SMatrix::<f64, 6, 6>::zeros();
    for k in (0..6).filter(|&k| k != null) {
        let v = eig.eigenvectors.column(k);
        pinv += v * v.transpose() / eig.eigenvalues[k];
    }
    // For unit noise σ = 1 px (σ̄ = scale); σ² is applied last, checked as `fit_line` does.
    let cov_theta = pinv * (scale * scale);
    // Jacobian of the residual with respect to θ through l = c⁻¹.
    let dual = conic.try_inverse().ok_or_else(|| Error::Degenerate {
        what: "fit_conic: singular conic".into(),
    })?;
    let dr_dl = frame.residual_jacobian(&sym3_to_vec(&dual));
    let mut dl_dtheta = SMatrix::<f64, 6, 6>::zeros();
    for j in 0..6 {
        let dc = to_pixels(&Vector6::from_fn(|i, _| if i == j { 1.0 } else { 0.0 }));
        dl_dtheta.set_column(j, &sym3_to_vec(&(-dual * dc * dual)));
    }
    let jac = dr_dl * dl_dtheta;
    let unit = jac * cov_theta * jac.transpose();
    let norm = conic.norm();
    Ok(FittedConic {
        conic: conic / norm,
        ellipse,
        covariance: scaled_covariance(&unit, sigma)?,
        iterations,
    })
}

/// Residual samples of Figures 1-2 (section 3.1): `draws` random images of `size x size` pixels, each
/// with one line sampled at 21 points and one ellipse sampled at 63, Gaussian noise of `sigma` px on
/// every point, the primitives refitted by [`fit_line`] / [`fit_conic`]; each sample is the residual of
/// the true primitive in the frame of the fitted one (what triangulation sees).
#[derive(Debug, Clone, PartialEq)]
pub struct ResidualSamples {
    /// Line residuals, pixels (2 entries).
    pub line: Vec<Vector2<f64>>,
    /// The same whitened by the covariance predicted by [`fit_line`]: standard normal to first order.
    pub line_whitened: Vec<Vector2<f64>>,
    /// Conic residuals (5 entries, module `quadric::residual` order).
    pub conic: Vec<Vector5>,
    /// The same whitened by the covariance predicted by [`fit_conic`].
    pub conic_whitened: Vec<Vector5>,
}

/// Points sampled on a line segment and on an ellipse of one random image (noise-free), for
/// [`residual_samples`] and the tests: a segment between two uniform points at least `size/5` apart,
/// 21 evenly spaced points; an ellipse with its centre in the middle half of the image, major semi-axis
/// in `[0.06, 0.24] size`, aspect ratio in `[0.3, 1]`, any orientation, 63 points evenly spaced in angle.
pub fn random_image_primitives(size: f64, rng: &mut Rng) -> (Vec<Vector2<f64>>, Ellipse) {
    let (a, b) = loop {
        let a = Vector2::new(rng.uniform_in(0.0, size), rng.uniform_in(0.0, size));
        let b = Vector2::new(rng.uniform_in(0.0, size), rng.uniform_in(0.0, size));
        // In units of `size`: with pixels near the underflow threshold `‖a − b‖` itself is 0 and
        // the loop would never end.
        if ((a - b) / size).norm() >= 0.2 {
            break (a, b);
        }
    };
    let line = (0..21).map(|k| a + (b - a) * (k as f64 / 20.0)).collect();
    let major = rng.uniform_in(0.06, 0.24) * size;
    let ellipse = Ellipse {
        centre: Vector2::new(rng.uniform_in(0.25, 0.75) * size, rng.uniform_in(0.25, 0.75) * size),
        axes: Rotation2::new(rng.uniform_in(0.0, std::f64::consts::PI)).into_inner(),
        semi_axes: Vector2::new(major, major * rng.uniform_in(0.3, 1.0)),
    };
    (line, ellipse)
}

fn whiten<const D: usize>(cov: &SMatrix<f64, D, D>, r: &SVector<f64, D>) -> SVector<f64, D> {
    crate::covariance::whitening(cov, "covariance", 0)
        .map(|l| l * r)
        .unwrap_or_else(|_| SVector::repeat(f64::NAN))
}

/// The most draws [`residual_samples`] accepts: a hundred times the paper's 100000 (about 1 GB).
pub const MAX_RESIDUAL_DRAWS: usize = 10_000_000;

/// The data of Figures 1-2 (see [`ResidualSamples`]); the paper used `draws = 100000`, `size = 1000`,
/// `sigma = 1`. Seeded by `seed`. [`Error::InvalidOption`] for more than [`MAX_RESIDUAL_DRAWS`] draws.
pub fn residual_samples(draws: usize, size: f64, sigma: f64, seed: u64) -> Result<ResidualSamples> {
    if draws > MAX_RESIDUAL_DRAWS {
        return Err(Error::InvalidOption {
            name: "draws".into(),
            reason: format!("at most {MAX_RESIDUAL_DRAWS} draws (the paper used 100000), got {draws}"),
        });
    }
    let mut rng = Rng::new(seed);
    let mut out = ResidualSamples {
        line: vec![],
        line_whitened: vec![],
        conic: vec![],
        conic_whitened: vec![],
    };
    for _ in 0..draws {
        let (line_points, ellipse) = random_image_primitives(size, &mut rng);
        let mut noisy = |p: &Vector2<f64>| p + Vector2::new(rng.normal(), rng.normal()) * sigma;
        let noisy_line: Vec<Vector2<f64>> = line_points.iter().map(&mut noisy).collect();
        let noisy_conic: Vec<Vector2<f64>> = ellipse.sample(63, 0.0).iter().map(&mut noisy).collect();
        let true_line = (line_points[0].push(1.0)).cross(&line_points[20].push(1.0));
        let fit = fit_line(&noisy_line, sigma)?;
        let r = LineFrame::of_line(&fit.line).expect("fitted line").residual(&true_line);
        out.line.push(r);
        out.line_whitened.push(whiten(&fit.covariance, &r));
        let fit = fit_conic(&noisy_conic, sigma)?;
        let r = ConicFrame::of_conic(&fit.conic)
            .expect("fitted ellipse")
            .residual(&ellipse.dual());
        out.conic.push(r);
        out.conic_whitened.push(whiten(&fit.covariance, &r));
    }
    Ok(out)
}

#[cfg(test)]
mod tests {

    #[test]
    fn endpoints_with_covariances_give_the_residual_covariance() {
        let (a, b) = (Vector2::new(120.0, 340.0), Vector2::new(610.0, 90.0));
        // Isotropic noise: the same line and covariance as the two-point fit.
        let sigma = 1.7;
        let iso = line_from_endpoints(
            &a,
            &b,
            &(Matrix2::identity() * sigma * sigma),
            &(Matrix2::identity() * sigma * sigma),
        )
        .unwrap();
        let fit = line_from_segment(&a, &b, sigma).unwrap();
        assert!((iso.line - fit.line).norm() < 1e-12 * fit.line.norm());
        assert!((iso.covariance - fit.covariance).norm() < 1e-9 * fit.covariance.norm());
        // Anisotropic, different endpoints: against the sample covariance of the true line's residual in
        // the frame of lines through noisy endpoints (20000 draws: entries within 3 % at these sizes).
        let (ca, cb) = (Matrix2::new(4.0, 1.5, 1.5, 1.0), Matrix2::new(0.3, -0.2, -0.2, 2.5));
        let truth = a.push(1.0).cross(&b.push(1.0));
        let (la, lb) = (ca.cholesky().unwrap().l(), cb.cholesky().unwrap().l());
        let mut rng = Rng::new(3);
        let draws = 20_000;
        let mut sum = Matrix2::zeros();
        for _ in 0..draws {
            let na = a + la * Vector2::new(rng.normal(), rng.normal());
            let nb = b + lb * Vector2::new(rng.normal(), rng.normal());
            let fitted = line_from_endpoints(&na, &nb, &ca, &cb).unwrap();
            let r = LineFrame::of_line(&fitted.line).unwrap().residual(&truth);
            sum += r * r.transpose();
        }
        let sample = sum / draws as f64;
        let predicted = line_from_endpoints(&a, &b, &ca, &cb).unwrap().covariance;
        for (s, p) in sample.iter().zip(predicted.iter()) {
            assert!(
                (s - p).abs() < 0.03 * predicted.norm(),
                "sample {sample} vs predicted {predicted}"
            );
        }
    }

    use super::*;

    #[test]
    fn exact_points_give_the_exact_primitives() {
        let mut rng = Rng::new(51);
        for _ in 0..20 {
            let (line_points, ellipse) = random_image_primitives(1000.0, &mut rng);
            let fit = fit_line(&line_points, 1.0).unwrap();
            for p in &line_points {
                assert!((fit.line.xy().dot(p) + fit.line.z).abs() < 1e-9);
            }
            assert!(fit.line.z <= 0.0 && (fit.line.xy().norm() - 1.0).abs() < 1e-12);
            let fit = fit_conic(&ellipse.sample(63, 0.1), 1.0).unwrap();
            assert!((fit.ellipse.centre - ellipse.centre).norm() < 1e-6);
            assert!((fit.ellipse.semi_axes - ellipse.semi_axes).norm() < 1e-6);
            let eig = fit.covariance.symmetric_eigen();
            assert!(eig.eigenvalues.min() > 0.0, "covariance is positive definite");
        }
    }

    #[test]
    fn bad_input_is_rejected() {
        let p = Vector2::new(1.0, 2.0);
        assert!(matches!(fit_line(&[p], 1.0), Err(Error::TooFewCorrespondences { .. })));
        assert!(matches!(fit_line(&[p, p], 1.0), Err(Error::Degenerate { .. })));
        assert!(matches!(
            fit_line(&[p, Vector2::new(f64::NAN, 0.0)], 1.0),
            Err(Error::NonFinite { index: 1, .. })
        ));
        assert!(matches!(
            fit_line(&[p, Vector2::zeros()], 0.0),
            Err(Error::InvalidOption { .. })
        ));
        let collinear: Vec<_> = (0..10).map(|k| Vector2::new(k as f64, 2.0 * k as f64)).collect();
        assert!(matches!(fit_conic(&collinear, 1.0), Err(Error::Degenerate { .. })));
        let hyperbola: Vec<_> = (1..12).map(|k| Vector2::new(k as f64, 10.0 / k as f64)).collect();
        assert!(matches!(fit_conic(&hyperbola, 1.0), Err(Error::Degenerate { .. })));
    }
}
