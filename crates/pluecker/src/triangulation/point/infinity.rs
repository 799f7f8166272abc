//! Points at infinity in front of the cameras: where eq. 19 goes when no finite point is best.
//!
//! With the views of [`super::cost`] (`W = [A | b]`, depth row `(c, d)`, `‖c‖ = 1`), along a ray
//! `X = X₀ + t D` with `cᵢ·D > 0` in every view the residual of view `i` tends, as `t → ∞`, to
//! `rᵢ(D) = Aᵢ D / (cᵢ·D)`, the whitened error of the vanishing point of `D`; so eq. 19 tends to
//! `f_∞(D) = Σᵢ ‖Aᵢ D‖² / (cᵢ·D)²`, the cost of the point at infinity `D`, which does not depend on
//! `X₀` or on the length of `D`. Points at infinity close the set of points in front of every camera:
//! the infimum of eq. 19 over that set is the least of its finite minimum and `min_D f_∞(D)`.
//!
//! A finite point `X` in front with `f(X) ≥ f_∞(D)` for some `D` is therefore no minimiser worth
//! reporting: the infimum is approached at infinity (exactly so when `X` is the certified best finite
//! point). That happens when the observations are best explained behind the cameras (the rays
//! diverge in front) or by parallel rays, and the minimisation then runs off towards infinity.
//!
//! `f_∞` is minimised over unit directions with the trust region of [`crate::optim`] in the gnomonic
//! chart `D(s) = (D₀ + E s)/‖D₀ + E s‖` (`E` an orthonormal basis of `D₀^⊥`), where the Jacobian of
//! view `i` at `s = 0` is `(Aᵢ − rᵢ cᵢᵀ) E / (cᵢ·D₀)`.

use super::cost::PointView;
use crate::optim::{trust_region, Linearization, Objective, TrustRegionOptions};
use nalgebra::{Matrix3x2, Vector2, Vector3};

/// `f_∞(d)` (module docs) for the point at infinity in direction `d` or `−d`, whichever is in front
/// of every camera (`cᵢ·d > 0` in every view); `None` when neither is.
#[cfg(test)]
pub fn cost_at_infinity(views: &[PointView], d: &Vector3<f64>) -> Option<f64> {
    oriented(views, d).and_then(|d| cost_in_direction(views, &d))
}

/// `d` or `−d`, whichever is in front of every camera, as a unit vector; `None` when neither is.
fn oriented(views: &[PointView], d: &Vector3<f64>) -> Option<Vector3<f64>> {
    let n = d.norm();
    if !(n > 0.0 && n.is_finite()) {
        return None;
    }
    [d / n, -d / n]
        .into_iter()
        .find(|d| views.iter().all(|v| v.c().dot(d) > 0.0))
}

/// `f_∞(d)` when `d` itself is in front of every camera.
fn cost_in_direction(views: &[PointView], d: &Vector3<f64>) -> Option<f64> {
    views
        .iter()
        .map(|v| {
            let z = v.c().dot(d);
            (z > 0.0).then(|| (v.a() * d).norm_squared() / (z * z))
        })
        .sum()
}

/// The least `f_∞` found by local minimisations from each direction of `starts` (either sign, see
/// [`cost_at_infinity`]), and its unit direction; `None` when no start has a sign in front of every
/// camera.
pub(crate) fn best_at_infinity(
    views: &[PointView],
    starts: &[Vector3<f64>],
    opts: &TrustRegionOptions,
) -> Option<(Vector3<f64>, f64)> {
    let objective = InfinityObjective { views };
    starts
        .iter()
        .filter_map(|d| oriented(views, d))
        .filter_map(|d0| {
            let (d, _) = trust_region::minimize(&objective, d0, opts);
            Some((d, cost_in_direction(views, &d)?))
        })
        .min_by(|a, b| a.1.total_cmp(&b.1))
}

/// An orthonormal basis of the plane orthogonal to the unit vector `d`.
fn tangent_basis(d: &Vector3<f64>) -> Matrix3x2<f64> {
    let helper = if d.x.abs() < 0.9 { Vector3::x() } else { Vector3::y() };
    let e1 = d.cross(&helper).normalize();
    let e2 = d.cross(&e1);
    Matrix3x2::from_columns(&[e1, e2])
}

/// `½ f_∞` over unit directions in the gnomonic chart (module docs), `+∞` outside the directions in
/// front of every camera.
struct InfinityObjective<'a> {
    views: &'a [PointView],
}

impl Objective<2> for InfinityObjective<'_> {
    type Point = Vector3<f64>;

    fn cost(&self, d: &Vector3<f64>) -> f64 {
        cost_in_direction(self.views, d).map_or(f64::INFINITY, |c| 0.5 * c)
    }

    fn linearize(&self, d: &Vector3<f64>) -> Linearization<2> {
        let e = tangent_basis(d);
        let mut lin = Linearization::zero();
        for v in self.views {
            let z = v.c().dot(d);
            if !(z > 0.0) {
                lin.cost = f64::INFINITY;
                return lin;
            }
            let r = v.a() * d / z;
            let j = (v.a() - r * v.c().transpose()) * e / z;
            lin.add(&r, &j);
        }
        lin
    }

    fn retract(&self, d: &Vector3<f64>, s: &Vector2<f64>) -> Vector3<f64> {
        (d + tangent_basis(d) * s).normalize()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::optim::problem::testing::gradient_error;
    use crate::triangulation::point::cost::{point_cost, point_views};
    use crate::triangulation::views::depth_normalized;
    use nalgebra::{Matrix3, Matrix3x4};

    fn views(observations: &[Vector2<f64>]) -> Vec<PointView> {
        let k = Matrix3::new(800.0, 0.0, 320.0, 0.0, 800.0, 240.0, 0.0, 0.0, 1.0);
        let cameras: Vec<Matrix3x4<f64>> = [-1.0, 0.0, 1.0]
            .iter()
            .map(|c| {
                let mut rt = Matrix3x4::identity();
                rt[(0, 3)] = -c;
                depth_normalized(&(k * rt))
            })
            .collect();
        point_views(&cameras, observations, &[nalgebra::Matrix2::identity(); 3])
    }

    #[test]
    fn the_cost_at_infinity_is_the_limit_of_the_cost_along_a_ray_and_its_gradient_is_exact() {
        let vs = views(&[
            Vector2::new(300.0, 250.0),
            Vector2::new(350.0, 200.0),
            Vector2::new(330.0, 260.0),
        ]);
        let d = Vector3::new(0.1, -0.05, 1.0);
        let limit = cost_at_infinity(&vs, &d).unwrap();
        assert_eq!(cost_at_infinity(&vs, &-d), Some(limit));
        // f(t d) − f_∞(d) = O(1/t): at t = 1e8 (units of the unit baseline) within 1e-6 relative.
        let far = point_cost(&vs, &(d * 1e8));
        assert!((far - limit).abs() < 1e-6 * limit, "{far} vs {limit}");
        let obj = InfinityObjective { views: &vs };
        assert!(gradient_error(&obj, &d.normalize(), 1e-6) < 1e-6);
        // Behind every camera: no direction in front.
        assert_eq!(cost_at_infinity(&vs, &Vector3::new(1.0, 0.0, 0.0)), None);
    }

    #[test]
    fn the_best_direction_at_infinity_is_the_mean_of_the_vanishing_points() {
        // Three identical orientations: the vanishing point of D is the same pixel p in every view,
        // so f_∞ = Σ ‖p − uᵢ‖², least at the mean pixel, with the variance as its value.
        let obs = [
            Vector2::new(300.0, 250.0),
            Vector2::new(350.0, 200.0),
            Vector2::new(330.0, 260.0),
        ];
        let mean = obs.iter().sum::<Vector2<f64>>() / 3.0;
        let least: f64 = obs.iter().map(|u| (u - mean).norm_squared()).sum();
        let (d, cost) = best_at_infinity(
            &views(&obs),
            &[Vector3::new(0.3, 0.2, 1.0)],
            &TrustRegionOptions::default(),
        )
        .unwrap();
        assert!((cost - least).abs() < 1e-9 * least, "{cost} vs {least}");
        let pixel = Vector2::new(320.0 + 800.0 * d.x / d.z, 240.0 + 800.0 * d.y / d.z);
        assert!((pixel - mean).norm() < 1e-6);
    }
}
