//! Plücker coordinates of 3-D lines (Josephson & Kahl 2008, section 2.2, eqs. 2-7).
//!
//! A line through the homogeneous points `A`, `B` has the Plücker matrix `L = A Bᵀ − B Aᵀ` (eq. 2), a
//! skew-symmetric 4x4 matrix of rank 2, and the six Plücker coordinates (eq. 3, indices 1-based)
//! `𝓛 = (l₁₂, l₁₃, l₁₄, l₂₃, l₄₂, l₃₄)`, defined up to a non-zero scale. They satisfy the Plücker
//! constraint `l₁₂l₃₄ + l₁₃l₄₂ + l₁₄l₂₃ = 0` (eq. 4) and transform as `L' = H L Hᵀ` when points
//! transform as `X' = H X` (eq. 5).
//!
//! For finite points `A = (a, 1)`, `B = (b, 1)` (world frame) the coordinates split into
//! - the **direction** `d = (l₁₄, −l₄₂, l₃₄) = a − b` (from `B` towards `A`), and
//! - the **moment** `m = (−l₂₃, l₁₃, −l₁₂) = p × d` for any point `p` of the line,
//!
//! so that eq. 4 reads `d · m = 0`. A line is *at infinity* when `d = 0`.
//!
//! The Plücker camera of eq. 7, `P_𝓛 = (p₂∧p₃; p₃∧p₁; p₁∧p₂)` with `pᵢᵀ` the rows of a 3x4 camera `P`
//! and `p∧q` the coordinates of eq. 3 computed from the 4-vectors `p`, `q`, maps `𝓛` to the image line
//! by a plain matrix product (eq. 6): `P_𝓛 𝓛(A, B) = (P A) × (P B)`, the homogeneous line through the
//! two image points, with this sign (see the test `plucker_camera_maps_to_the_image_line`).

use crate::error::{Error, Result};
use nalgebra::{Matrix3, Matrix3x4, Matrix4, Rotation3, SMatrix, Vector3, Vector4, Vector6};

/// The 3x6 Plücker camera of eq. 7.
pub type PluckerCamera = SMatrix<f64, 3, 6>;

/// Relative size of the direction (against the moment) below which a line is treated as lying at
/// infinity.
const MIN_RELATIVE_DIRECTION: f64 = 1e-12;

/// Eqs. 2-3: the Plücker coordinates of the line through the homogeneous points `a`, `b`.
pub fn from_homogeneous_points(a: &Vector4<f64>, b: &Vector4<f64>) -> Vector6<f64> {
    let l = |i: usize, j: usize| a[i] * b[j] - b[i] * a[j];
    Vector6::new(l(0, 1), l(0, 2), l(0, 3), l(1, 2), l(3, 1), l(2, 3))
}

/// The Plücker coordinates of the line through the world points `a`, `b`; its direction is `a − b`.
pub fn from_points(a: &Vector3<f64>, b: &Vector3<f64>) -> Vector6<f64> {
    from_homogeneous_points(&a.push(1.0), &b.push(1.0))
}

/// The skew-symmetric Plücker matrix `L` of eq. 2 from the coordinates of eq. 3.
pub fn to_matrix(l: &Vector6<f64>) -> Matrix4<f64> {
    let (l12, l13, l14, l23, l42, l34) = (l[0], l[1], l[2], l[3], l[4], l[5]);
    Matrix4::new(
        0.0, l12, l13, l14, //
        -l12, 0.0, l23, -l42, //
        -l13, -l23, 0.0, l34, //
        -l14, l42, -l34, 0.0,
    )
}

/// The coordinates of eq. 3 read from a Plücker matrix (its strictly upper part; `l₄₂ = −L[1,3]`).
pub fn from_matrix(m: &Matrix4<f64>) -> Vector6<f64> {
    Vector6::new(m[(0, 1)], m[(0, 2)], m[(0, 3)], m[(1, 2)], m[(3, 1)], m[(2, 3)])
}

/// The left side of the Plücker constraint, eq. 4: `l₁₂l₃₄ + l₁₃l₄₂ + l₁₄l₂₃` (zero for every line).
pub fn constraint(l: &Vector6<f64>) -> f64 {
    l[0] * l[5] + l[1] * l[4] + l[2] * l[3]
}

/// Eq. 5: the coordinates of the line after the point transformation `X' = H X`, from `L' = H L Hᵀ`.
pub fn transform(h: &Matrix4<f64>, l: &Vector6<f64>) -> Vector6<f64> {
    from_matrix(&(h * to_matrix(l) * h.transpose()))
}

/// The direction `d = (l₁₄, −l₄₂, l₃₄)` and moment `m = (−l₂₃, l₁₃, −l₁₂)` (see the module docs).
pub fn direction_moment(l: &Vector6<f64>) -> (Vector3<f64>, Vector3<f64>) {
    (Vector3::new(l[2], -l[4], l[5]), Vector3::new(-l[3], l[1], -l[0]))
}

/// The inverse of [`direction_moment`].
pub fn from_direction_moment(d: &Vector3<f64>, m: &Vector3<f64>) -> Vector6<f64> {
    Vector6::new(-m.z, m.y, d.x, -m.x, -d.y, d.z)
}

/// The line through the world point `p` with direction `d` (any length, non-zero).
pub fn from_point_direction(p: &Vector3<f64>, d: &Vector3<f64>) -> Vector6<f64> {
    from_direction_moment(d, &p.cross(d))
}

/// The point of the line closest to the world origin and the unit direction of the line (the sign
/// of `d`, see the module docs). `None` for a line at infinity or a zero vector.
pub fn to_point_direction(l: &Vector6<f64>) -> Option<(Vector3<f64>, Vector3<f64>)> {
    let (d, m) = direction_moment(l);
    let dn = d.norm();
    if !(dn > MIN_RELATIVE_DIRECTION * m.norm()) || !dn.is_finite() {
        return None;
    }
    Some((d.cross(&m) / (dn * dn), d / dn))
}

/// Two world points `A`, `B` of the line, one unit apart, with `from_points(A, B)` a positive multiple
/// of `l` when `l` satisfies eq. 4: `B` is the point closest to the origin and `A = B + d/‖d‖`.
pub fn to_points(l: &Vector6<f64>) -> Option<(Vector3<f64>, Vector3<f64>)> {
    to_point_direction(l).map(|(p, d)| (p + d, p))
}

/// The Plücker camera of eq. 7 for a 3x4 point camera `P`: rows `p₂∧p₃`, `p₃∧p₁`, `p₁∧p₂`, so that
/// `P_𝓛 𝓛(A, B) = (P A) × (P B)` (eq. 6 with `λ = 1`). Its entries are quadratic in `P`.
pub fn camera(p: &Matrix3x4<f64>) -> PluckerCamera {
    let row = |i: usize| -> Vector4<f64> { p.row(i).transpose() };
    let (p1, p2, p3) = (row(0), row(1), row(2));
    let mut out = PluckerCamera::zeros();
    out.set_row(0, &from_homogeneous_points(&p2, &p3).transpose());
    out.set_row(1, &from_homogeneous_points(&p3, &p1).transpose());
    out.set_row(2, &from_homogeneous_points(&p1, &p2).transpose());
    out
}

/// Eq. 6: the homogeneous image line `P_𝓛 𝓛` of the 3-D line `l` seen by camera `p`.
pub fn project(p: &Matrix3x4<f64>, l: &Vector6<f64>) -> Vector3<f64> {
    camera(p) * l
}

/// The vector satisfying eq. 4 nearest to `l` in the Euclidean norm of ℝ⁶.
///
/// In terms of `(d, m)` (an isometry of ℝ⁶) the stationarity conditions of
/// `min ‖d' − d‖² + ‖m' − m‖²` s.t. `d'·m' = 0` give `d' = d − μ m'`, `m' = m − μ d'`, i.e.
/// `d' = (d − μ m)/(1 − μ²)`, `m' = (m − μ d)/(1 − μ²)`, and `d'·m' = 0` is the quadratic
/// `c μ² − s μ + c = 0` with `c = d·m`, `s = ‖d‖² + ‖m‖²`, whose root of modulus < 1 is taken.
pub fn nearest_line(l: &Vector6<f64>) -> Vector6<f64> {
    let (d, m) = direction_moment(l);
    let c = d.dot(&m);
    let s = d.norm_squared() + m.norm_squared();
    if c == 0.0 || s == 0.0 {
        return *l;
    }
    // Stable root: μ = 2c / (s + sqrt(s² − 4c²)); |2c| ≤ s by Cauchy-Schwarz, so |μ| ≤ 1.
    let mu = 2.0 * c / (s + (s * s - 4.0 * c * c).max(0.0).sqrt());
    let k = 1.0 / (1.0 - mu * mu).max(f64::MIN_POSITIVE);
    from_direction_moment(&((d - mu * m) * k), &((m - mu * d) * k))
}

/// The orthonormal representation of a 3-D line (Bartoli & Sturm 2005): a rotation `U` and an angle
/// `φ ∈ [0, π/2)` with `d = cos φ · U e₁`, `m = sin φ · U e₂` (up to the common scale of `(d, m)`).
/// The distance of the line from the origin is `tan φ`. [`Self::retract`] moves it by a 4-vector
/// `(ω, δφ)`: `U ← U exp([ω]ₓ)`, `φ ← φ + δφ`, a minimal update that keeps eq. 4 exactly.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OrthonormalLine {
    /// Columns: the unit direction, the unit moment, and their cross product.
    pub u: Matrix3<f64>,
    /// `atan(‖m‖ / ‖d‖)`.
    pub phi: f64,
}

impl OrthonormalLine {
    /// The representation of a line given by Plücker coordinates; `None` for a line at infinity.
    /// A line through the origin (`m = 0`) gets an arbitrary unit moment direction orthogonal to `d`.
    pub fn from_plucker(l: &Vector6<f64>) -> Option<OrthonormalLine> {
        let l = nearest_line(l);
        let (d, m) = direction_moment(&l);
        let (dn, mn) = (d.norm(), m.norm());
        if !(dn > MIN_RELATIVE_DIRECTION * mn) || !dn.is_finite() {
            return None;
        }
        let e1 = d / dn;
        let e2 = if mn > 0.0 { m / mn } else { any_orthogonal(&e1) };
        // Re-orthogonalise e2 against e1 (eq. 4 holds to rounding only).
        let e2 = (e2 - e1 * e1.dot(&e2)).normalize();
        let u = Matrix3::from_columns(&[e1, e2, e1.cross(&e2)]);
        Some(OrthonormalLine { u, phi: mn.atan2(dn) })
    }

    /// Plücker coordinates `(d, m) = (cos φ U e₁, sin φ U e₂)` (unit norm in ℝ⁶).
    pub fn to_plucker(&self) -> Vector6<f64> {
        let (c, s) = (self.phi.cos(), self.phi.sin());
        from_direction_moment(&(self.u.column(0) * c), &(self.u.column(1) * s))
    }

    /// The line moved by the tangent step `δ = (ω₁, ω₂, ω₃, δφ)`.
    pub fn retract(&self, delta: &Vector4<f64>) -> OrthonormalLine {
        let r = Rotation3::new(Vector3::new(delta[0], delta[1], delta[2]));
        OrthonormalLine {
            u: self.u * r.matrix(),
            phi: self.phi + delta[3],
        }
    }

    /// `∂𝓛/∂δ` at `δ = 0` (6x4) of `self.retract(δ).to_plucker()`: with `uₖ` the columns of `U`,
    /// `∂d/∂ω = cos φ (0, −u₃, u₂)`, `∂m/∂ω = sin φ (u₃, 0, −u₁)`, `∂d/∂φ = −sin φ u₁`, `∂m/∂φ = cos φ u₂`.
    pub fn tangent(&self) -> SMatrix<f64, 6, 4> {
        let (c, s) = (self.phi.cos(), self.phi.sin());
        let (u1, u2, u3) = (
            self.u.column(0).into_owned(),
            self.u.column(1).into_owned(),
            self.u.column(2).into_owned(),
        );
        let z = Vector3::zeros();
        let dd = [z, -u3 * c, u2 * c, -u1 * s];
        let dm = [u3 * s, z, -u1 * s, u2 * c];
        let mut t = SMatrix::<f64, 6, 4>::zeros();
        for k in 0..4 {
            t.set_column(k, &from_direction_moment(&dd[k], &dm[k]));
        }
        t
    }
}

/// A minimal chart of the lines near a line: the chart of the line covariances of
/// [`crate::triangulation::uncertainty`].
///
/// At the line through the **pivot** `p` with unit **direction** `d`, take the **axes**
/// `e₁ = (d × a)/‖d × a‖` with `a = x̂` when `|d_x| < 0.9`, else `a = ŷ`, and `e₂ = d × e₁`, so that
/// `(e₁, e₂, d)` is a right-handed orthonormal basis. The coordinates `δ = (α₁, α₂, t₁, t₂)` name the
/// line through `p + t₁e₁ + t₂e₂` with direction `d + α₁e₁ + α₂e₂`:
/// - `t₁, t₂` (world units): where the line crosses the plane through `p` normal to `d`;
/// - `α₁, α₂` (dimensionless, radians to first order): its tilt from `d` towards `e₁`, `e₂` about
///   that crossing point (to first order a rotation by `α₁` about `e₂` and by `α₂` about `−e₁`).
///
/// Every line not parallel to that plane has exactly one `δ` ([`Self::coordinates`], exact, not a
/// first-order approximation) and `δ = 0` is the line itself; the chart is singular only for lines
/// perpendicular to `d`. Moving the pivot along the line by `s` (`p' = p + s d`) keeps the axes and
/// changes coordinates linearly and exactly: `t = t' − s α` ([`Self::repivot`]).
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct LineChart {
    /// `p`, a point of the line, world units.
    pub pivot: Vector3<f64>,
    /// `d`, the unit direction of the line.
    pub direction: Vector3<f64>,
    /// `e₁`, `e₂` (see the type docs).
    pub axes: [Vector3<f64>; 2],
}

impl LineChart {
    /// The chart of the line through `pivot` with direction `direction` (normalised here); `None`
    /// when the direction is zero or an entry is not finite.
    pub fn new(pivot: &Vector3<f64>, direction: &Vector3<f64>) -> Option<LineChart> {
        let n = direction.norm();
        if !(n > 0.0 && n.is_finite() && pivot.iter().all(|v| v.is_finite())) {
            return None;
        }
        let d = direction / n;
        let e1 = any_orthogonal(&d);
        Some(LineChart {
            pivot: *pivot,
            direction: d,
            axes: [e1, d.cross(&e1)],
        })
    }

    /// The chart of a line (eq. 3) pivoted at its point closest to the world origin, with the
    /// direction of [`to_point_direction`]; `None` for a line at infinity.
    pub fn of_line(l: &Vector6<f64>) -> Option<LineChart> {
        let (p, d) = to_point_direction(&nearest_line(l))?;
        LineChart::new(&p, &d)
    }

    /// The same line and axes pivoted at `pivot` (projected onto the line).
    pub fn repivot(&self, pivot: &Vector3<f64>) -> LineChart {
        let s = self.direction.dot(&(pivot - self.pivot));
        LineChart {
            pivot: self.pivot + self.direction * s,
            ..*self
        }
    }

    /// The line (Plücker coordinates, eq. 3, not normalised) of the coordinates `δ`.
    pub fn line(&self, delta: &Vector4<f64>) -> Vector6<f64> {
        let [e1, e2] = self.axes;
        let d = self.direction + e1 * delta[0] + e2 * delta[1];
        let p = self.pivot + e1 * delta[2] + e2 * delta[3];
        from_point_direction(&p, &d)
    }

    /// The coordinates `δ` of a line (eq. 3; projected onto eq. 4 first): `None` when it is at
    /// infinity or (nearly) perpendicular to the chart's direction.
    pub fn coordinates(&self, l: &Vector6<f64>) -> Option<Vector4<f64>> {
        let (q, d) = to_point_direction(&nearest_line(l))?;
        let k = self.direction.dot(&d);
        if !(k.abs() > MIN_RELATIVE_DIRECTION) {
            return None;
        }
        let d = d / k;
        let crossing = q + d * self.direction.dot(&(self.pivot - q));
        let [e1, e2] = self.axes;
        let t = crossing - self.pivot;
        Some(Vector4::new(e1.dot(&d), e2.dot(&d), e1.dot(&t), e2.dot(&t)))
    }

    /// `∂𝓛/∂δ` (6x4) of [`Self::line`] at `δ = 0`: `∂d/∂α_k = e_k`, `∂m/∂α_k = p × e_k`,
    /// `∂d/∂t_k = 0`, `∂m/∂t_k = e_k × d`.
    pub fn tangent(&self) -> SMatrix<f64, 6, 4> {
        let (p, d) = (self.pivot, self.direction);
        let z = Vector3::zeros();
        let mut t = SMatrix::<f64, 6, 4>::zeros();
        for (k, e) in self.axes.iter().enumerate() {
            t.set_column(k, &from_direction_moment(e, &p.cross(e)));
            t.set_column(2 + k, &from_direction_moment(&z, &e.cross(&d)));
        }
        t
    }

    /// The covariance of the unit-norm Plücker coordinates `±𝓛/‖𝓛‖` (6x6, rank 4) of a line whose
    /// chart coordinates have the covariance `cov` (4x4): `G cov Gᵀ` with
    /// `G = (I − ûûᵀ)/‖u‖ · ∂𝓛/∂δ`, `u = 𝓛(0)` (the sign of the coordinates does not change it).
    pub fn plucker_covariance(&self, cov: &Matrix4<f64>) -> SMatrix<f64, 6, 6> {
        let u = self.line(&Vector4::zeros());
        let norm = u.norm();
        let uh = u / norm;
        let g = (SMatrix::<f64, 6, 6>::identity() - uh * uh.transpose()) * self.tangent() / norm;
        g * cov * g.transpose()
    }

    /// The covariance (6x6, rank 4) of `(q, d)` — the point of the line closest to the world origin
    /// (world units) and the unit direction (the chart's sign) — of a line whose chart coordinates
    /// have the covariance `cov`. First order: `∂d/∂α_k = e_k`, `∂d/∂t_k = 0`,
    /// `∂q/∂α_k = −(d·p) e_k − (e_k·p) d`, `∂q/∂t_k = e_k`.
    pub fn point_direction_covariance(&self, cov: &Matrix4<f64>) -> SMatrix<f64, 6, 6> {
        let (p, d) = (self.pivot, self.direction);
        let s = d.dot(&p);
        let mut g = SMatrix::<f64, 6, 4>::zeros();
        for (k, e) in self.axes.iter().enumerate() {
            let dq = -e * s - d * e.dot(&p);
            g.fixed_view_mut::<3, 1>(0, k).copy_from(&dq);
            g.fixed_view_mut::<3, 1>(3, k).copy_from(e);
            g.fixed_view_mut::<3, 1>(0, 2 + k).copy_from(e);
        }
        g * cov * g.transpose()
    }
}

/// A unit vector orthogonal to the unit vector `v`.
fn any_orthogonal(v: &Vector3<f64>) -> Vector3<f64> {
    let axis = if v.x.abs() < 0.9 { Vector3::x() } else { Vector3::y() };
    v.cross(&axis).normalize()
}

/// A 3-D line: Plücker coordinates (eq. 3) that satisfy the Plücker constraint (eq. 4), scaled to unit
/// norm. The constructors are the only way to make one, and each puts the coordinates on the Plücker
/// quadric ([`nearest_line`]) after checking that they describe a line, so every `PluckerLine` keeps
/// eq. 4 to rounding: `|l₁₂l₃₄ + l₁₃l₄₂ + l₁₄l₂₃| ≤ a few ε`. The finished lines of
/// [`crate::triangulation`] are of this type; the optimisation inside works on plain 6-vectors.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PluckerLine {
    coordinates: Vector6<f64>,
}

impl PluckerLine {
    /// How far from eq. 4 the coordinates given to [`PluckerLine::new`] may be: the cosine of the angle
    /// between the direction `d` and the moment `m`, which eq. 4 makes orthogonal (`d · m = 0`). Lines
    /// computed in double precision are orthogonal to about 1e-15 relative; an optimiser's iterate
    /// moved off the quadric, or a vector that is no line at all, is not.
    pub const TOLERANCE: f64 = 1e-6;

    /// The line of the coordinates `l` (eq. 3, any non-zero scale), moved onto the Plücker quadric and
    /// scaled to unit norm. `Error::NonFinite` for NaN/inf, `Error::Degenerate` for a zero vector or one
    /// whose direction and moment are not orthogonal to within [`PluckerLine::TOLERANCE`] (not a line).
    pub fn new(l: &Vector6<f64>) -> Result<PluckerLine> {
        if let Some(index) = l.iter().position(|v| !v.is_finite()) {
            return Err(Error::NonFinite {
                what: "Plücker coordinates".into(),
                index,
            });
        }
        let (d, m) = direction_moment(l);
        let scale = d.norm() * m.norm();
        if l.norm() == 0.0 {
            return Err(Error::Degenerate {
                what: "Plücker coordinates: the zero vector is no line".into(),
            });
        }
        if d.dot(&m).abs() > Self::TOLERANCE * scale {
            return Err(Error::Degenerate {
                what: format!(
                    "Plücker coordinates: not a line, eq. 4 fails (d · m = {:e} for |d| |m| = {scale:e})",
                    d.dot(&m)
                ),
            });
        }
        Ok(PluckerLine {
            coordinates: nearest_line(l).normalize(),
        })
    }

    /// The line through the world points `a` and `b` (eqs. 2-3), directed from `b` towards `a`;
    /// `Error::Degenerate` when they coincide.
    pub fn through(a: &Vector3<f64>, b: &Vector3<f64>) -> Result<PluckerLine> {
        PluckerLine::through_homogeneous(&a.push(1.0), &b.push(1.0))
    }

    /// The line through the homogeneous points `a` and `b` (eqs. 2-3); `Error::Degenerate` when they are
    /// the same point.
    pub fn through_homogeneous(a: &Vector4<f64>, b: &Vector4<f64>) -> Result<PluckerLine> {
        PluckerLine::new(&from_homogeneous_points(a, b))
    }

    /// The line through the world point `p` with direction `d` (any length, not zero).
    pub fn from_point_direction(p: &Vector3<f64>, d: &Vector3<f64>) -> Result<PluckerLine> {
        PluckerLine::new(&from_point_direction(p, d))
    }

    /// The unit-norm coordinates `(l₁₂, l₁₃, l₁₄, l₂₃, l₄₂, l₃₄)` of eq. 3.
    pub fn coordinates(&self) -> &Vector6<f64> {
        &self.coordinates
    }

    /// The direction `d` and moment `m` (see the module docs), `d · m = 0`.
    pub fn direction_moment(&self) -> (Vector3<f64>, Vector3<f64>) {
        direction_moment(&self.coordinates)
    }

    /// The point of the line closest to the origin and its unit direction; `None` for a line at infinity.
    pub fn point_direction(&self) -> Option<(Vector3<f64>, Vector3<f64>)> {
        to_point_direction(&self.coordinates)
    }

    /// The Plücker matrix `L` of eq. 2.
    pub fn matrix(&self) -> Matrix4<f64> {
        to_matrix(&self.coordinates)
    }

    /// Eq. 5: the line after the point transformation `X' = H X` (`H` invertible), on the quadric again.
    pub fn transform(&self, h: &Matrix4<f64>) -> Result<PluckerLine> {
        PluckerLine::new(&transform(h, &self.coordinates))
    }
}

/// With the `serde` feature a line is written as its [`PluckerLine::coordinates`] and read back through
/// [`PluckerLine::new`]: checked, and put on the Plücker quadric again (to rounding).
#[cfg(feature = "serde")]
impl serde::Serialize for PluckerLine {
    fn serialize<S: serde::Serializer>(&self, serializer: S) -> std::result::Result<S::Ok, S::Error> {
        serde::Serialize::serialize(&self.coordinates, serializer)
    }
}

#[cfg(feature = "serde")]
impl<'de> serde::Deserialize<'de> for PluckerLine {
    fn deserialize<D: serde::Deserializer<'de>>(deserializer: D) -> std::result::Result<Self, D::Error> {
        let coordinates = <Vector6<f64> as serde::Deserialize>::deserialize(deserializer)?;
        PluckerLine::new(&coordinates).map_err(serde::de::Error::custom)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn plucker_lines_keep_eq4_and_reject_other_vectors() {
        let (a, b) = (Vector3::new(1e3, -2e3, 5e2), Vector3::new(1e3 + 1e-3, -2e3, 5e2 + 2e-3));
        for line in [
            PluckerLine::through(&Vector3::new(0.3, -1.0, 4.0), &Vector3::new(2.0, 0.5, -1.0)).unwrap(),
            PluckerLine::through(&a, &b).unwrap(),
            PluckerLine::from_point_direction(&Vector3::new(7.0, 0.0, 1.0), &Vector3::new(0.0, 0.0, 1e-9)).unwrap(),
        ] {
            let l = line.coordinates();
            assert!((l.norm() - 1.0).abs() < 1e-15);
            assert!(constraint(l).abs() < 1e-15, "eq. 4: {:e}", constraint(l));
            let moved = line
                .transform(&Matrix4::new_scaling(2.0).append_translation(&Vector3::new(1.0, 2.0, 3.0)))
                .unwrap();
            assert!(constraint(moved.coordinates()).abs() < 1e-15);
        }
        assert!(matches!(
            PluckerLine::new(&Vector6::new(1.0, 0.0, 0.0, 0.0, 0.0, 1.0)),
            Err(Error::Degenerate { .. })
        ));
        assert!(matches!(
            PluckerLine::new(&Vector6::zeros()),
            Err(Error::Degenerate { .. })
        ));
        assert!(matches!(
            PluckerLine::new(&Vector6::new(f64::NAN, 0.0, 0.0, 0.0, 0.0, 1.0)),
            Err(Error::NonFinite { .. })
        ));
        assert!(matches!(PluckerLine::through(&a, &a), Err(Error::Degenerate { .. })));
    }
    use crate::rng::Rng;

    fn random_camera(rng: &mut Rng) -> Matrix3x4<f64> {
        let k = Matrix3::new(800.0, 3.0, 320.0, 0.0, 780.0, 240.0, 0.0, 0.0, 1.0);
        let r = rng.rotation();
        let t = Vector3::new(rng.normal(), rng.normal(), 6.0 + rng.normal());
        let mut rt = Matrix3x4::zeros();
        rt.fixed_view_mut::<3, 3>(0, 0).copy_from(&r);
        rt.set_column(3, &t);
        k * rt * rng.uniform_in(-2.0, 2.0)
    }

    fn random_point(rng: &mut Rng) -> Vector3<f64> {
        Vector3::new(rng.normal(), rng.normal(), rng.normal())
    }

    #[test]
    fn coordinates_satisfy_the_constraint_and_do_not_depend_on_the_points() {
        let mut rng = Rng::new(11);
        for _ in 0..50 {
            let (a, b) = (random_point(&mut rng), random_point(&mut rng));
            let l = from_points(&a, &b);
            assert!(constraint(&l).abs() < 1e-12 * l.norm_squared());
            // Eq. 2: L = A Bᵀ − B Aᵀ, read back through eq. 3.
            let (ah, bh) = (a.push(1.0), b.push(1.0));
            assert!((to_matrix(&l) - (ah * bh.transpose() - bh * ah.transpose())).norm() < 1e-12 * l.norm());
            // Any two other points of the line give the same coordinates up to scale: here s − t.
            let (s, t) = (rng.normal(), rng.normal());
            let l2 = from_points(&(a + s * (a - b)), &(a + t * (a - b)));
            assert!((l2 - l * (s - t)).norm() < 1e-10 * l.norm() * (1.0 + (s - t).abs()));
            let (d, m) = direction_moment(&l);
            assert!((d - (a - b)).norm() < 1e-12 && (m - a.cross(&d)).norm() < 1e-12);
        }
    }

    #[test]
    fn transformation_matches_transforming_the_points() {
        let mut rng = Rng::new(12);
        let h = Matrix4::from_fn(|_, _| rng.normal());
        let (a, b) = (random_point(&mut rng).push(1.0), random_point(&mut rng).push(1.0));
        let direct = from_homogeneous_points(&(h * a), &(h * b));
        assert!((transform(&h, &from_homogeneous_points(&a, &b)) - direct).norm() < 1e-12 * direct.norm());
    }

    #[test]
    fn plucker_camera_maps_to_the_image_line() {
        let mut rng = Rng::new(13);
        for _ in 0..50 {
            let p = random_camera(&mut rng);
            let (a, b) = (random_point(&mut rng), random_point(&mut rng));
            let (pa, pb) = (p * a.push(1.0), p * b.push(1.0));
            let expected = pa.cross(&pb);
            let got = project(&p, &from_points(&a, &b));
            assert!((got - expected).norm() < 1e-10 * expected.norm(), "{got} vs {expected}");
            // Every point of the 3-D line projects onto the image line.
            for s in [-3.0, 0.5, 7.0] {
                let x = p * (a + s * (b - a)).push(1.0);
                assert!(got.dot(&x).abs() < 1e-10 * got.norm() * x.norm());
            }
        }
    }

    #[test]
    fn point_direction_and_two_point_forms_round_trip() {
        let mut rng = Rng::new(14);
        for _ in 0..50 {
            let (a, b) = (random_point(&mut rng), random_point(&mut rng));
            let l = from_points(&a, &b) * rng.uniform_in(0.1, 3.0);
            let (p, d) = to_point_direction(&l).unwrap();
            assert!((d - (a - b).normalize()).norm() < 1e-12);
            // p is on the line and orthogonal to it (closest to the origin).
            assert!((p - a).cross(&d).norm() < 1e-12 && p.dot(&d).abs() < 1e-12);
            let back = from_point_direction(&p, &d);
            assert!((back.normalize() - l.normalize()).norm() < 1e-12);
            let (pa, pb) = to_points(&l).unwrap();
            assert!((from_points(&pa, &pb).normalize() - l.normalize()).norm() < 1e-12);
        }
        let at_infinity = from_homogeneous_points(&Vector4::new(1.0, 0.0, 0.0, 0.0), &Vector4::new(0.0, 1.0, 0.0, 0.0));
        assert!(to_point_direction(&at_infinity).is_none());
    }

    #[test]
    fn nearest_line_is_a_line_and_the_nearest_one() {
        let mut rng = Rng::new(15);
        for _ in 0..100 {
            let v = Vector6::from_fn(|_, _| rng.normal());
            let n = nearest_line(&v);
            assert!(constraint(&n).abs() < 1e-12 * n.norm_squared());
            // No random line near n is closer to v (sampled check of optimality).
            for _ in 0..20 {
                let o = OrthonormalLine::from_plucker(&n).unwrap();
                let delta = Vector4::from_fn(|_, _| 0.05 * rng.normal());
                let other = o.retract(&delta).to_plucker() * n.norm() * rng.uniform_in(0.9, 1.1);
                assert!((other - v).norm() >= (n - v).norm() - 1e-12);
            }
        }
    }

    #[test]
    fn orthonormal_representation_round_trips_and_keeps_the_constraint() {
        let mut rng = Rng::new(16);
        for _ in 0..50 {
            let l = from_points(&random_point(&mut rng), &random_point(&mut rng));
            let o = OrthonormalLine::from_plucker(&l).unwrap();
            assert!((o.to_plucker() - l.normalize()).norm() < 1e-12);
            let moved = o.retract(&Vector4::from_fn(|_, _| rng.normal())).to_plucker();
            assert!(constraint(&moved).abs() < 1e-14);
            let (p, _) = to_point_direction(&l).unwrap();
            assert!((o.phi.tan() - p.norm()).abs() < 1e-10 * (1.0 + p.norm()));
        }
        // The tangent against central differences.
        let o = OrthonormalLine::from_plucker(&from_points(&random_point(&mut rng), &random_point(&mut rng))).unwrap();
        let t = o.tangent();
        for k in 0..4 {
            let mut d = Vector4::zeros();
            d[k] = 1e-6;
            let fd = (o.retract(&d).to_plucker() - o.retract(&-d).to_plucker()) / 2e-6;
            assert!((fd - t.column(k)).norm() < 1e-8, "column {k}");
        }
        // A line through the origin.
        let o = OrthonormalLine::from_plucker(&from_points(&Vector3::zeros(), &Vector3::new(1.0, 2.0, 3.0))).unwrap();
        assert_eq!(o.phi, 0.0);
        assert!((o.u.transpose() * o.u - Matrix3::identity()).norm() < 1e-12);
    }

    #[test]
    fn line_chart_round_trips_and_its_derivatives_match_central_differences() {
        let mut rng = Rng::new(17);
        for _ in 0..30 {
            let l = from_points(&(random_point(&mut rng) * 3.0), &random_point(&mut rng)) * rng.uniform_in(-2.0, 2.0);
            let chart = LineChart::of_line(&l).unwrap();
            let [e1, e2] = chart.axes;
            let frame = Matrix3::from_columns(&[e1, e2, chart.direction]);
            assert!((frame.transpose() * frame - Matrix3::identity()).norm() < 1e-12 && frame.determinant() > 0.0);
            assert!(chart.coordinates(&l).unwrap().norm() < 1e-12);
            for _ in 0..5 {
                let delta = Vector4::from_fn(|_, _| 0.5 * rng.normal());
                let back = chart.coordinates(&(chart.line(&delta) * -1.7)).unwrap();
                assert!((back - delta).norm() < 1e-10, "{back} vs {delta}");
                // Another pivot on the line: t = t' − s α exactly.
                let s = rng.normal() * 2.0;
                let moved = chart.repivot(&(chart.pivot + chart.direction * s + e1 * 0.3));
                let d2 = moved.coordinates(&chart.line(&delta)).unwrap();
                let expected = Vector4::new(d2[0], d2[1], d2[2] - s * d2[0], d2[3] - s * d2[1]);
                assert!((expected - delta).norm() < 1e-10);
            }
            let h = 1e-6;
            let t = chart.tangent();
            let mut g_plucker = SMatrix::<f64, 6, 4>::zeros();
            let mut g_point_direction = SMatrix::<f64, 6, 4>::zeros();
            let unit = |v: Vector6<f64>| {
                let v = v.normalize();
                if v.dot(&chart.line(&Vector4::zeros())) < 0.0 {
                    -v
                } else {
                    v
                }
            };
            let point_direction = |v: Vector6<f64>| {
                let (q, d) = to_point_direction(&v).unwrap();
                let d = if d.dot(&chart.direction) < 0.0 { -d } else { d };
                Vector6::new(q.x, q.y, q.z, d.x, d.y, d.z)
            };
            for k in 0..4 {
                let mut dk = Vector4::zeros();
                dk[k] = h;
                let (plus, minus) = (chart.line(&dk), chart.line(&-dk));
                assert!(
                    ((plus - minus) / (2.0 * h) - t.column(k)).norm() < 1e-8,
                    "tangent column {k}"
                );
                g_plucker.set_column(k, &((unit(plus) - unit(minus)) / (2.0 * h)));
                g_point_direction.set_column(k, &((point_direction(plus) - point_direction(minus)) / (2.0 * h)));
            }
            let a = SMatrix::<f64, 4, 4>::from_fn(|_, _| rng.normal());
            let cov = a * a.transpose();
            let tol = 1e-7 * (1.0 + cov.norm() * (1.0 + chart.pivot.norm_squared()));
            assert!((chart.plucker_covariance(&cov) - g_plucker * cov * g_plucker.transpose()).norm() < tol);
            let expected = g_point_direction * cov * g_point_direction.transpose();
            assert!((chart.point_direction_covariance(&cov) - expected).norm() < tol);
        }
        assert!(LineChart::new(&Vector3::zeros(), &Vector3::zeros()).is_none());
    }
}
