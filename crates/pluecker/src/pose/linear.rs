//! Faugeras-Toscani linear camera calibration (O. D. Faugeras and G. Toscani, "The calibration problem
//! for stereo", CVPR 1986), the "linear" baseline of Phong & Horaud 1995 (sections 1.2 and 5).
//!
//! Each correspondence `(u, v) ↔ X` gives two equations linear in the 12 entries of the projection
//! matrix `M = K [R | t]` (rows `(mᵢᵀ, mᵢ₄)`):
//! `u (m₃·X + m₃₄) − (m₁·X + m₁₄) = 0` and `v (m₃·X + m₃₄) − (m₂·X + m₂₄) = 0`.
//! Stacked as `A x + B y = 0` with `y = m₃` and `x` the other nine entries, the method minimises the
//! **algebraic error** `‖A x + B y‖²` subject to `‖m₃‖ = 1`. Unlike `‖M‖ = 1`, this normalisation is
//! physical: `m₃` is the third row of `R`. The minimiser is `x = −A⁺ B y`, with `y` the unit vector
//! that minimises `‖(I − A A⁺) B y‖`, i.e. the eigenvector of the smallest eigenvalue of
//! `Bᵀ(I − A(AᵀA)⁻¹Aᵀ)B` (computed here as a singular vector). The points and pixels are first
//! centred and isotropically scaled; this conditioning multiplies every residual by the same constant
//! and `‖m₃‖` by another, so it changes nothing but the rounding and is undone exactly.
//!
//! `M` is then decomposed with the closed-form formulas of Faugeras-Toscani (zero skew, as in the
//! paper's camera model): `u₀ = m₁·m₃`, `v₀ = m₂·m₃`, `α_v = ‖m₂ × m₃‖`, `α_u = ±‖m₁ × m₃‖`,
//! `r₁ = (m₁ − u₀ m₃)/α_u`, `r₂ = (m₂ − v₀ m₃)/α_v`, `r₃ = m₃`, `t = K⁻¹ (m₁₄, m₂₄, m₃₄)`. The overall
//! sign of `M` is chosen so that most points are in front of the camera, `α_v > 0` and the sign of
//! `α_u` so that `det R = +1` — `α_u` may come out negative (the paper's camera has `α_u ≈ −1730`,
//! a mirrored axis). Under noise `r₁, r₂, r₃` are only approximately orthonormal: the returned
//! rotation is their nearest rotation (SVD projection); `t` uses the returned `K` and `t_z = m₃₄`.
//!
//! Conventions: `x_cam = R X_world + t`, pixels `u = K x_cam / z`, `K = [[α_u, 0, u₀], [0, α_v, v₀],
//! [0, 0, 1]]`. Besides the pose the method estimates the intrinsics: the paper runs it on 460 points
//! and takes the result (intrinsics and pose, Table 1, last row) as its ground truth.
//!
//! Minimal data: 6 points (11 unknowns up to scale, 2 equations each), not coplanar. Degenerate cases:
//! coplanar (or collinear) 3-D points, rejected; points and camera centre on a twisted cubic, which
//! makes the system rank-deficient; an affine-looking configuration (negligible depth range) that
//! makes it nearly so. Rank-deficient systems are rejected as [`Error::Degenerate`].
//!
//! Known limitation: the error minimised is algebraic, not the reprojection error, and the orthogonality
//! of `R` is not enforced during the estimation, so the method is noise sensitive — in the paper's
//! Table 2 the translation is unreliable beyond half a pixel of noise and the intrinsics drift by
//! hundreds of pixels at 1-3 px. Refine on the reprojection error when accuracy matters.

use crate::camera::Intrinsics;
use crate::error::{Error, Result};
use nalgebra::{DMatrix, DVector, Dyn, Matrix3, Matrix3x4, Matrix4, SVector, Vector2, Vector3, Vector4, SVD};

/// Singular-value ratio (smallest / largest) below which a matrix counts as rank-deficient.
const RANK_TOL: f64 = 1e-9;
/// Iteration cap of the SVDs (they converge in a few dozen sweeps; the cap only avoids hanging).
const SVD_MAX_ITER: usize = 10_000;

/// Result of the linear calibration.
#[derive(Debug, Clone, PartialEq)]
pub struct LinearCalibration {
    /// Estimated intrinsics (`skew = 0`; `fx` may be negative).
    pub camera: Intrinsics,
    /// Rotation, world → camera: the nearest rotation to the Faugeras-Toscani rows `r₁, r₂, r₃`.
    pub rotation: Matrix3<f64>,
    /// Translation, world units: `K⁻¹ (m₁₄, m₂₄, m₃₄)` with the returned `K`.
    pub translation: Vector3<f64>,
    /// The estimated projection matrix `M ≈ K [R | t]`, scaled so that `‖m₃‖ = 1` with the sign that
    /// puts most points in front of the camera.
    pub projection: Matrix3x4<f64>,
    /// Root-mean-square of the `2n` algebraic residuals `u (m₃·X + m₃₄) − (m₁·X + m₁₄)` (and v) at
    /// `projection`: pixels × depth in world units.
    pub algebraic_residual: f64,
}

fn degenerate(what: impl Into<String>) -> Error {
    Error::Degenerate { what: what.into() }
}

/// Centroid and isotropic scale (RMS distance to the centroid / √D) of a non-empty point set.
fn centroid_and_scale<const D: usize>(p: &[SVector<f64, D>]) -> (SVector<f64, D>, f64) {
    let n = p.len() as f64;
    let c = p.iter().sum::<SVector<f64, D>>() / n;
    let ms = p.iter().map(|x| (x - c).norm_squared()).sum::<f64>() / n;
    (c, (ms / D as f64).sqrt())
}

fn svd(m: DMatrix<f64>, u: bool, v: bool, what: &str) -> Result<SVD<f64, Dyn, Dyn>> {
    m.try_svd(u, v, f64::EPSILON, SVD_MAX_ITER)
        .ok_or_else(|| degenerate(format!("{what}: SVD did not converge")))
}

fn validate(points2d: &[Vector2<f64>], points3d: &[Vector3<f64>]) -> Result<()> {
    if points2d.len() != points3d.len() {
        return Err(Error::Shape {
            what: "points2d / points3d".into(),
            expected: "the same number of rows".into(),
            actual: format!("{} and {}", points2d.len(), points3d.len()),
        });
    }
    if points2d.len() < 6 {
        return Err(Error::TooFewCorrespondences {
            method: "linear".into(),
            required: "at least 6 points".into(),
            actual: format!("{} points", points2d.len()),
        });
    }
    let bad = |p: &[f64]| !p.iter().all(|v| v.is_finite());
    match (
        points2d.iter().position(|p| bad(p.as_slice())),
        points3d.iter().position(|p| bad(p.as_slice())),
    ) {
        (Some(index), _) => Err(Error::NonFinite {
            what: "points2d".into(),
            index,
        }),
        (None, Some(index)) => Err(Error::NonFinite {
            what: "points3d".into(),
            index,
        }),
        (None, None) => Ok(()),
    }
}

/// Faugeras-Toscani linear calibration from `n ≥ 6` non-coplanar 2-D/3-D point correspondences
/// (pixels, world units). Returns intrinsics (zero skew), pose and the projection matrix; see the
/// module documentation for what is minimised, the conventions and the degenerate cases.
pub fn faugeras_toscani(points2d: &[Vector2<f64>], points3d: &[Vector3<f64>]) -> Result<LinearCalibration> {
    validate(points2d, points3d)?;
    let n = points2d.len();
    let (c2, s2) = centroid_and_scale(points2d);
    let (c3, s3) = centroid_and_scale(points3d);
    if !(s2 > 0.0 && s3 > 0.0) {
        return Err(degenerate("all image points or all 3-D points coincide"));
    }
    let xs: Vec<Vector3<f64>> = points3d.iter().map(|p| (p - c3) / s3).collect();
    let us: Vec<Vector2<f64>> = points2d.iter().map(|p| (p - c2) / s2).collect();

    // Coplanarity: the centred (scaled) 3-D points must span three dimensions.
    let sv = svd(DMatrix::from_fn(n, 3, |i, j| xs[i][j]), false, false, "3-D points")?.singular_values;
    if !(sv[2] > RANK_TOL * sv[0]) {
        return Err(degenerate(format!(
            "the 3-D points are coplanar or collinear (singular values {:.3e}, {:.3e}, {:.3e}); \
             the linear method needs non-coplanar points",
            sv[0], sv[1], sv[2]
        )));
    }

    // A x + B y = 0, x = (m₁, m₁₄, m₂, m₂₄, m₃₄), y = m₃, in the conditioned coordinates.
    let mut a = DMatrix::<f64>::zeros(2 * n, 9);
    let mut b = DMatrix::<f64>::zeros(2 * n, 3);
    for (i, (x, u)) in xs.iter().zip(&us).enumerate() {
        for k in 0..2 {
            let row = 2 * i + k;
            for j in 0..3 {
                a[(row, 4 * k + j)] = x[j];
                b[(row, j)] = -u[k] * x[j];
            }
            a[(row, 4 * k + 3)] = 1.0;
            a[(row, 8)] = -u[k];
        }
    }
    let sa = svd(a, true, true, "projection equations")?;
    let (Some(ua), Some(va_t)) = (&sa.u, &sa.v_t) else {
        return Err(degenerate("projection equations: SVD returned no singular vectors"));
    };
    let sig = &sa.singular_values;
    if !(sig[8] > RANK_TOL * sig[0]) {
        return Err(degenerate(
            "the projection equations are rank-deficient (points and camera centre on a twisted cubic, \
             or an affine configuration)",
        ));
    }
    let bp = &b - ua * (ua.transpose() * &b); // (I − A A⁺) B
    let sb = svd(bp, false, true, "reduced system")?;
    let Some(vb_t) = &sb.v_t else {
        return Err(degenerate("reduced system: SVD returned no singular vectors"));
    };
    if !(sb.singular_values[1] > RANK_TOL * sb.singular_values[0]) {
        return Err(degenerate(
            "the minimiser over m₃ is not unique (rank-deficient system)",
        ));
    }
    let y = Vector3::new(vb_t[(2, 0)], vb_t[(2, 1)], vb_t[(2, 2)]);
    let uby = ua.transpose() * (&b * DVector::from_column_slice(y.as_slice()));
    let x = -(va_t.transpose() * uby.component_div(sig));
    #[rustfmt::skip]
    let mc = Matrix3x4::new(
        x[0], x[1], x[2], x[3],
        x[4], x[5], x[6], x[7],
        y[0], y[1], y[2], x[8],
    );

    // Undo the conditioning: M = T⁻¹ M' D, then ‖m₃‖ = 1 and points in front of the camera.
    let t_inv = Matrix3::new(s2, 0.0, c2.x, 0.0, s2, c2.y, 0.0, 0.0, 1.0);
    let mut d = Matrix4::identity() / s3;
    d.fixed_view_mut::<3, 1>(0, 3).copy_from(&(-c3 / s3));
    d[(3, 3)] = 1.0;
    let mut m = t_inv * mc * d;
    let m3_norm = m.fixed_view::<1, 3>(2, 0).norm();
    if !(m3_norm > 0.0 && m3_norm.is_finite()) {
        return Err(degenerate("the estimated projection matrix has m₃ = 0"));
    }
    m /= m3_norm;
    let homog = |p: &Vector3<f64>| Vector4::new(p.x, p.y, p.z, 1.0);
    let in_front = points3d.iter().filter(|p| (m.row(2) * homog(p))[0] > 0.0).count();
    if 2 * in_front < n {
        m = -m;
    }
    let sum_sq: f64 = points2d
        .iter()
        .zip(points3d)
        .map(|(uv, p)| {
            let q = m * homog(p);
            (uv.x * q.z - q.x).powi(2) + (uv.y * q.z - q.y).powi(2)
        })
        .sum();
    let algebraic_residual = (sum_sq / (2 * n) as f64).sqrt();

    // Closed-form decomposition (zero skew).
    let row = |i: usize| Vector3::new(m[(i, 0)], m[(i, 1)], m[(i, 2)]);
    let (m1, m2, m3) = (row(0), row(1), row(2));
    let (u0, v0) = (m1.dot(&m3), m2.dot(&m3));
    let av = m2.cross(&m3).norm();
    let mut au = m1.cross(&m3).norm();
    let r2 = (m2 - v0 * m3) / av;
    let mut r1 = (m1 - u0 * m3) / au;
    if r1.dot(&r2.cross(&m3)) < 0.0 {
        au = -au;
        r1 = -r1;
    }
    let camera = Intrinsics::new(au, av, u0, v0, 0.0)
        .map_err(|e| degenerate(format!("the estimated intrinsics are singular: {e}")))?;
    let r_raw = Matrix3::from_rows(&[r1.transpose(), r2.transpose(), m3.transpose()]);
    let rotation = nearest_rotation(&r_raw)?;
    let translation = Vector3::new(
        (m[(0, 3)] - u0 * m[(2, 3)]) / au,
        (m[(1, 3)] - v0 * m[(2, 3)]) / av,
        m[(2, 3)],
    );
    if !(rotation.iter().chain(translation.iter()).all(|v| v.is_finite()) && algebraic_residual.is_finite()) {
        return Err(degenerate("the linear calibration produced non-finite values"));
    }
    Ok(LinearCalibration {
        camera,
        rotation,
        translation,
        projection: m,
        algebraic_residual,
    })
}

/// The rotation closest to `m` in the Frobenius norm: `U diag(1, 1, det(U Vᵀ)) Vᵀ`.
fn nearest_rotation(m: &Matrix3<f64>) -> Result<Matrix3<f64>> {
    let s = m.try_svd(true, true, f64::EPSILON, SVD_MAX_ITER);
    let Some((Some(mut u), Some(v_t))) = s.map(|s| (s.u, s.v_t)) else {
        return Err(degenerate("could not project the estimated rotation onto SO(3)"));
    };
    if (u * v_t).determinant() < 0.0 {
        u.column_mut(2).neg_mut(); // singular values are sorted: flip the smallest
    }
    Ok(u * v_t)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::quaternion::{from_axis_angle, rotation_distance, to_rotation_matrix};
    use crate::rng::Rng;

    /// `n` points uniform in the camera-frame box `|x|, |y| < half`, `z ∈ depth`, mapped to the world by
    /// `X = Rᵀ (x_cam − t)`, with pixels perturbed by Gaussian noise of standard deviation `sigma`.
    #[allow(clippy::too_many_arguments)]
    fn scene(
        cam: &Intrinsics,
        r: &Matrix3<f64>,
        t: &Vector3<f64>,
        n: usize,
        half: f64,
        depth: (f64, f64),
        sigma: f64,
        rng: &mut Rng,
    ) -> (Vec<Vector2<f64>>, Vec<Vector3<f64>>) {
        let xy = |rng: &mut Rng| rng.uniform_in(-half, half);
        (0..n)
            .map(|_| {
                let xc = Vector3::new(xy(rng), xy(rng), rng.uniform_in(depth.0, depth.1));
                let noise = Vector2::new(rng.normal(), rng.normal()) * sigma;
                (cam.project(&xc) + noise, r.transpose() * (xc - t))
            })
            .unzip()
    }

    fn paper() -> (Intrinsics, Matrix3<f64>, Vector3<f64>) {
        let cam = Intrinsics {
            fx: -1730.3,
            fy: 1220.7,
            cx: 243.8,
            cy: 241.2,
            skew: 0.0,
        };
        let r = to_rotation_matrix(&from_axis_angle(&Vector3::new(-0.185148, -0.973420, -0.156567), 2.9512));
        (cam, r, Vector3::new(2.627650, -11.006138, 77.479236))
    }

    /// Noise-free data is satisfied exactly by the true `M`, so the estimate is exact up to rounding:
    /// ~1e-16 amplified by the conditioning of the (normalised) system, far below 1e-8.
    fn assert_exact(est: &LinearCalibration, cam: &Intrinsics, r: &Matrix3<f64>, t: &Vector3<f64>) {
        let tol = 1e-8;
        let f = cam.fx.abs().max(cam.fy.abs());
        let c = &est.camera;
        for (e, x) in [(c.fx, cam.fx), (c.fy, cam.fy), (c.cx, cam.cx), (c.cy, cam.cy)] {
            assert!((e - x).abs() < tol * f, "intrinsic {e} vs {x}");
        }
        assert_eq!(est.camera.skew, 0.0);
        assert!((est.rotation - r).amax() < tol, "R error {}", (est.rotation - r).amax());
        assert!(
            (est.translation - t).norm() < tol * t.norm(),
            "t {} vs {}",
            est.translation,
            t
        );
        assert!((est.rotation.determinant() - 1.0).abs() < 1e-12);
    }

    #[test]
    fn noise_free_paper_camera_with_mirrored_axis() {
        let (cam, r, t) = paper();
        let (p2, p3) = scene(&cam, &r, &t, 50, 8.0, (70.0, 85.0), 0.0, &mut Rng::new(1));
        let est = faugeras_toscani(&p2, &p3).expect("calibration");
        assert_exact(&est, &cam, &r, &t);
        // The algebraic residual is pixel error × depth: rounding only.
        assert!(
            est.algebraic_residual < 1e-8 * 85.0,
            "residual {}",
            est.algebraic_residual
        );
    }

    #[test]
    fn noise_free_positive_focal_random_rotations_including_minimal_six_points() {
        let cam = Intrinsics {
            fx: 800.0,
            fy: 800.0,
            cx: 320.0,
            cy: 240.0,
            skew: 0.0,
        };
        for seed in 0..10 {
            let mut rng = Rng::new(100 + seed);
            let r = rng.rotation();
            let t = Vector3::new(
                rng.uniform_in(-1.0, 1.0),
                rng.uniform_in(-1.0, 1.0),
                rng.uniform_in(4.0, 8.0),
            );
            for n in [6, 40] {
                let (p2, p3) = scene(&cam, &r, &t, n, 2.0, (3.0, 6.0), 0.0, &mut rng);
                let est = faugeras_toscani(&p2, &p3).expect("calibration");
                assert_exact(&est, &cam, &r, &t);
            }
        }
    }

    /// 0.1 px Gaussian noise, 100 points, the paper's narrow field of view (±6°). Rotation is coupled to
    /// the principal point (a shift δ px looks like a rotation δ/|α_u|), which the narrow view pins down
    /// only to a few px, hence errors of a few mrad: the paper's Table 2 (uniform noise of max. amplitude
    /// 0.1 px, std ≈ 0.06 px) reports ≈ 0.003 rad and 0.46 cm at 77 cm (0.6 %). With ~1.7× that noise
    /// we allow 0.01 rad and 2 % of the depth (≈ 4× and 7× the rms errors over 200 seeds, 0.0022 rad
    /// and 0.21 cm), an order of magnitude below what a broken estimator gives.
    #[test]
    fn noisy_paper_camera() {
        let (cam, r, t) = paper();
        for seed in 0..5 {
            let (p2, p3) = scene(&cam, &r, &t, 100, 8.0, (70.0, 85.0), 0.1, &mut Rng::new(10 + seed));
            let est = faugeras_toscani(&p2, &p3).expect("calibration");
            let rot_err = rotation_distance(&est.rotation, &r);
            let t_err = (est.translation - t).norm();
            assert!(rot_err < 0.01, "seed {seed}: rotation error {rot_err}");
            assert!(t_err < 0.02 * t.z, "seed {seed}: translation error {t_err}");
            assert!(est.camera.fx < 0.0 && est.camera.fy > 0.0);
        }
    }

    #[test]
    fn errors() {
        let (cam, r, t) = paper();
        let (p2, p3) = scene(&cam, &r, &t, 10, 8.0, (70.0, 85.0), 0.0, &mut Rng::new(3));
        assert!(matches!(
            faugeras_toscani(&p2[..5], &p3[..5]),
            Err(Error::TooFewCorrespondences { .. })
        ));
        assert!(matches!(faugeras_toscani(&p2[..7], &p3[..6]), Err(Error::Shape { .. })));
        let mut bad = p3.clone();
        bad[4].y = f64::NAN;
        assert_eq!(
            faugeras_toscani(&p2, &bad),
            Err(Error::NonFinite {
                what: "points3d".into(),
                index: 4
            })
        );
        let mut bad = p2.clone();
        bad[7].x = f64::INFINITY;
        assert_eq!(
            faugeras_toscani(&bad, &p3),
            Err(Error::NonFinite {
                what: "points2d".into(),
                index: 7
            })
        );
        // Coplanar: all points at the same camera depth (a plane, tilted in the world frame).
        let (p2, p3) = scene(&cam, &r, &t, 20, 8.0, (77.0, 77.0), 0.0, &mut Rng::new(4));
        assert!(matches!(faugeras_toscani(&p2, &p3), Err(Error::Degenerate { .. })));
    }
}
