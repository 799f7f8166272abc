//! Step 2 of [`super`]'s module docs: the quadratic minorant `Q(R, t) = Σ wᵢ ‖Aᵢ (R Xᵢ + t + eᵢ)‖²`
//! of `2f` for one set of depth bounds (`wᵢ = 1 / Dᵢ²`; `eᵢ` the offset of the point's camera, zero
//! for one camera), the same minorant scaled by `κ` for tighter
//! depth bounds, and the two bounds of step 3 it gives over a box of rotations: Minkowski's
//! `½ (√q_min − θ η)₊²`, and the minorant linearised in the rotation, whose minimum over the ball of
//! rotations is bounded by its Lagrangian dual.

use nalgebra::{Matrix3, SMatrix, Vector3};
use std::cell::OnceCell;
use std::rc::Rc;

/// The rotation search rebuilds a box's minorant for its octants when the tightened depth bounds
/// raise the weights `wᵢ ∝ 1/Dᵢ²` on average by this factor more than the least of them, which a
/// scale of the minorant takes up ([`ScaledMinorant`]): a rebuild costs about as much as ten boxes' bounds,
/// and without rebuilds the f = 15000 px scenes lose certificates.
pub(super) const REBUILD_GAIN: f64 = 1.2;

/// A point's part of step 2's minorant: `H = AᵀA` for the 2x3 map `A` with `r = A x / x_z` (the
/// point's whitened residual at the camera-frame position `x`), and `λ_max(H) = ‖A‖²`.
pub(super) struct PointForm {
    /// `H = AᵀA`.
    pub(super) h: Matrix3<f64>,
    pub(super) norm2: f64,
}

/// Step 2's minorant `Q(R, t) = Σ wᵢ ‖Aᵢ (R Xᵢ + t + eᵢ)‖²`, `wᵢ = 1 / Dᵢ²`, for one set of depth
/// bounds `Dᵢ` (a minorant of `2f` where every `‖xᵢ‖ ≤ Dᵢ`), as a quadratic form in
/// `z = (vec R, 1, t)` (row-major `vec`), and `η = √(Σ wᵢ ‖Aᵢ‖² ‖Xᵢ‖²)`: over rotations within the
/// angle `θ` of `R`, `√Q` moves by at most `θ η`. `eᵢ` is the offset of the camera that saw point `i`
/// in the frame of the pose (zero for one camera; for a rig's camera `x_camera = R_k (x + e_k)`, and
/// `Aᵢ` is the point's map times `R_k`: [`super::problem::Problem::offsets`]).
///
/// The Hessian `C` in `t` does not depend on the rotation: `C⁻¹`, its largest eigenvalue, the
/// `bᵢᵀ C⁻¹ bᵢ` and the ellipsoid's whitened extent are computed once per minorant, not per box.
pub(super) struct Minorant {
    pub(super) depths: Vec<f64>,
    /// The form in `z = (vec R, 1, t)`: rows and columns 0-8 the rotation, 9 the constant, 10-12 `t`.
    pub(super) gram: SMatrix<f64, 13, 13>,
    pub(super) eta: f64,
    /// The lower-right block `C` and its inverse (`None`: the minorant does not fix `t`).
    pub(super) c: Matrix3<f64>,
    pub(super) c_inv: Option<Matrix3<f64>>,
    /// `λ_max(C⁻¹)`: the ellipsoid `(t − t*)ᵀ C (t − t*) ≤ slack` reaches `‖t − t*‖ ≤ √(slack λ_max)`.
    pub(super) c_inv_max: f64,
    /// `bᵢᵀ C⁻¹ bᵢ`: over that ellipsoid `bᵢ · t` moves by at most `√(slack bᵢᵀ C⁻¹ bᵢ)`.
    pub(super) bearing_spread: Vec<f64>,
    /// [`super::local_bound::Whitening::ellipsoid_factor`] of `C`, once it is needed.
    pub(super) extent: OnceCell<Option<f64>>,
    /// The form minimised over `t`: `min_t Q(R, t) = ṽᵀ S ṽ`, `ṽ = (vec R, 1)`, with the Schur
    /// complement `S = A − B C⁻¹ Bᵀ` of the blocks `[A B; Bᵀ C]` (zero when `C` is singular; unused
    /// then).
    pub(super) schur: SMatrix<f64, 10, 10>,
}

/// Index of the constant in `z = (vec R, 1, t)` ([`Minorant::gram`]); `t` follows it.
const ONE: usize = 9;
const T: usize = 10;

/// `ṽ = (vec r, 1)` (row-major `vec`): the rotation's part of `z` ([`Minorant::gram`]).
fn rotation_part(r: &Matrix3<f64>) -> SMatrix<f64, 10, 1> {
    SMatrix::<f64, 10, 1>::from_fn(|i, _| if i < ONE { r[(i / 3, i % 3)] } else { 1.0 })
}

impl Minorant {
    /// The minorant for the depth bounds `depths` of the points `points` with the residual maps
    /// `forms` ([`super::problem::Problem::forms`]) and their cameras' offsets `offsets`: a point's
    /// term is `‖Aᵢ (R Xᵢ + t + eᵢ)‖² / Dᵢ²`.
    pub(super) fn build(
        points: &[Vector3<f64>],
        bearings: &[Vector3<f64>],
        forms: &[PointForm],
        offsets: &[Vector3<f64>],
        depths: Vec<f64>,
    ) -> Minorant {
        // With z = (vec R, 1, t) (row-major vec), R Xᵢ + t + eᵢ = Lᵢ z, Lᵢ = [I ⊗ Xᵢᵀ, eᵢ, I], a
        // point's term is wᵢ zᵀ Lᵢᵀ Hᵢ Lᵢ z (Hᵢ = AᵢᵀAᵢ), whose blocks are Hᵢ ⊗ XᵢXᵢᵀ, Hᵢ ⊗ Xᵢ and
        // Hᵢ, and with the offset Hᵢeᵢ ⊗ Xᵢ, Hᵢeᵢ and eᵢᵀHᵢeᵢ. Both H and XXᵀ are symmetric: six
        // entries each, accumulated by hand (a search rebuilds the minorant about once every ten
        // boxes).
        const PAIRS: [(usize, usize); 6] = [(0, 0), (0, 1), (0, 2), (1, 1), (1, 2), (2, 2)];
        let mut outer = [[0.0f64; 6]; 6];
        let mut linear = [[0.0f64; 3]; 6];
        let mut constant = [0.0f64; 6];
        // The offsets' terms: Σ w (He)_p X_i, Σ w (He)_p and Σ w eᵀHe.
        let mut offset_rotation = [[0.0f64; 3]; 3];
        let mut offset_t = [0.0f64; 3];
        let mut offset_offset = 0.0;
        let mut eta2 = 0.0;
        for (((x, form), e), d) in points.iter().zip(forms).zip(offsets).zip(&depths) {
            let w = 1.0 / (d * d);
            eta2 += w * form.norm2 * x.norm_squared();
            let wx = [w * x.x, w * x.y, w * x.z];
            let wxx = PAIRS.map(|(i, j)| wx[i] * x[j]);
            for (k, &(a, b)) in PAIRS.iter().enumerate() {
                let h = form.h[(a, b)];
                for (entry, v) in outer[k].iter_mut().zip(&wxx) {
                    *entry += h * v;
                }
                for (entry, v) in linear[k].iter_mut().zip(&wx) {
                    *entry += h * v;
                }
                constant[k] += h * w;
            }
            if *e != Vector3::zeros() {
                let he = form.h * e;
                for p in 0..3 {
                    for (entry, v) in offset_rotation[p].iter_mut().zip(&wx) {
                        *entry += he[p] * v;
                    }
                    offset_t[p] += w * he[p];
                }
                offset_offset += w * e.dot(&he);
            }
        }
        let mut gram = SMatrix::<f64, 13, 13>::zeros();
        for (k, &(a, b)) in PAIRS.iter().enumerate() {
            for (l, &(i, j)) in PAIRS.iter().enumerate() {
                // Block (a, b) is Σ w H_ab XXᵀ, and block (b, a) the same (both symmetric).
                for (p, q) in [(a, b), (b, a)] {
                    gram[(3 * p + i, 3 * q + j)] = outer[k][l];
                    gram[(3 * p + j, 3 * q + i)] = outer[k][l];
                }
            }
            for i in 0..3 {
                for (p, q) in [(a, b), (b, a)] {
                    gram[(3 * p + i, T + q)] = linear[k][i];
                    gram[(T + q, 3 * p + i)] = linear[k][i];
                }
            }
            gram[(T + a, T + b)] = constant[k];
            gram[(T + b, T + a)] = constant[k];
        }
        for p in 0..3 {
            for i in 0..3 {
                gram[(3 * p + i, ONE)] = offset_rotation[p][i];
                gram[(ONE, 3 * p + i)] = offset_rotation[p][i];
            }
            gram[(T + p, ONE)] = offset_t[p];
            gram[(ONE, T + p)] = offset_t[p];
        }
        gram[(ONE, ONE)] = offset_offset;
        // What the bound of a box needs of `C` (the same for every box that shares the minorant).
        let c = gram.fixed_view::<3, 3>(T, T).into_owned();
        let c_inv = c.try_inverse();
        Minorant {
            depths,
            gram,
            eta: eta2.sqrt(),
            c,
            c_inv,
            c_inv_max: c_inv.map_or(f64::NAN, |c_inv| largest_eigenvalue(&c_inv)),
            bearing_spread: c_inv.map_or_else(Vec::new, |c_inv| bearings.iter().map(|b| b.dot(&(c_inv * b))).collect()),
            extent: OnceCell::new(),
            schur: c_inv.map_or_else(SMatrix::zeros, |c_inv| {
                let b = gram.fixed_view::<10, 3>(0, T);
                gram.fixed_view::<10, 10>(0, 0) - b * c_inv * b.transpose()
            }),
        }
    }

    /// The minorant at the rotation `r` as a quadratic in `t`: `tᵀ C t + 2 gᵀ t + c₀` (`C` is
    /// [`Self::c`]).
    pub(super) fn at(&self, r: &Matrix3<f64>) -> (Vector3<f64>, f64) {
        let v = rotation_part(r);
        let a = self.gram.fixed_view::<10, 10>(0, 0);
        let b = self.gram.fixed_view::<10, 3>(0, T);
        let g: Vector3<f64> = b.transpose() * v;
        let c0 = (v.transpose() * a * v)[0];
        (g, c0)
    }
}

/// A minorant for tighter depth bounds without a rebuild: if every weight may grow at least by the
/// factor `κ` (`Dᵢ' ≤ Dᵢ / √κ` for all `i`), then `κ Q` is a minorant for the depth bounds `Dᵢ'`, as
/// every term of `Q` is. `κ Q` is `Q` for the depth bounds `Dᵢ / √κ` ([`Self::depths`]).
#[derive(Clone)]
pub(super) struct ScaledMinorant {
    pub(super) minorant: Rc<Minorant>,
    pub(super) scale: f64,
}

impl ScaledMinorant {
    /// The depth bounds `Dᵢ / √κ` for which `κ Q` is the minorant.
    pub(super) fn depths(&self) -> impl Iterator<Item = f64> + Clone + '_ {
        let shrink = self.scale.sqrt();
        self.minorant.depths.iter().map(move |d| d / shrink)
    }

    /// The minorant `κ Q` at the rotation `r`: the minimiser `t*` of `κ Q(r, ·)`, its minimum
    /// `q_min` and `√κ η` (`None` when `Q` does not fix the translation). `C`, `g`, `c₀` and `q_min`
    /// scale by `κ`, `η` by `√κ`; `t*` does not move.
    pub(super) fn at(&self, r: &Matrix3<f64>) -> Option<(Vector3<f64>, f64, f64)> {
        let c_inv = self.minorant.c_inv?;
        let (g, c0) = self.minorant.at(r);
        let t_star = -(c_inv * g);
        let q_min = (self.scale * (c0 - g.dot(&(c_inv * g)))).max(0.0);
        Some((t_star, q_min, self.minorant.eta * self.scale.sqrt()))
    }

    /// `(e^θ − 1 − θ) √κ η`: over the rotations `exp(φ) r`, `‖φ‖ ≤ θ`, the points' whitened residuals
    /// `√(κ wᵢ) Aᵢ (exp(φ) yᵢ + t)` (`yᵢ = r Xᵢ`) are within this of their part linear in `φ`, in the
    /// norm of the stacked vector: `exp(φ) = I + [φ]ₓ + E` with `‖E y‖ ≤ (e^θ − 1 − θ) ‖y‖`, and
    /// `η² = Σ wᵢ λ_max(Hᵢ) ‖Xᵢ‖²` ([`Self::linear_bound`], [`super::problem::Problem::linear_lines_bound`]).
    pub(super) fn second_order_rest(&self, theta: f64) -> f64 {
        rotation_rest(theta) * self.minorant.eta * self.scale.sqrt()
    }

    /// A lower bound of `f` on the poses of `S` whose rotation is within the angle `θ` of `r`, from the
    /// minorant linearised in the rotation (0 when `Q` does not fix the translation). Such a
    /// rotation is `exp(φ) r` with `‖φ‖ ≤ θ`, and `exp(φ) r = r + [φ]ₓ r + E` with
    /// `‖E y‖ ≤ (e^θ − 1 − θ) ‖y‖` (the exponential series from its third term). `√Q` is a seminorm
    /// of `(vec R, 1, t)`, so `√Q(exp(φ) r, t) ≥ √Q(r + [φ]ₓ r, t) − (e^θ − 1 − θ) η`, and the first
    /// term, minimised over `t`, is `√m(φ)` with the convex quadratic
    /// `m(φ) = κ (v + Mφ)ᵀ S (v + Mφ)` (`v = (vec r, 1)`, `M φ = (vec([φ]ₓ r), 0)`, `S` the Schur
    /// complement).
    /// Its minimum over the ball `‖φ‖ ≤ θ` is bounded below by the Lagrangian dual
    /// `κ (q₀ − gᵀ (H + λI)⁻¹ g − λ θ²)` at any `λ ≥ 0` with `H + λI` positive definite
    /// (`q₀ = vᵀSv`, `g = MᵀSv`, `H = MᵀSM`); `λ` is found by Newton steps on the secular equation
    /// `‖(H + λI)⁻¹ g‖ = θ`. So `f ≥ ½ (√m_min − (e^θ − 1 − θ) √κ η)₊²`: the rotation's first-order
    /// effect is taken exactly and only the second-order rest costs, where the Minkowski bound
    /// ([`Self::bound_near`]) pays `θ η` for all of it.
    ///
    /// `q_min` is [`Self::at`]'s at `r`: the minimum over the ball is at most that, so the bound is at
    /// most `½ (√q_min − rest)₊²`. Where that is below `wanted` (the level at which the bound would
    /// close the box), nothing is computed and the answer is 0.
    pub(super) fn linear_bound(&self, r: &Matrix3<f64>, theta: f64, q_min: f64, wanted: f64) -> f64 {
        let rest = self.second_order_rest(theta);
        let ceiling = minkowski(q_min, rest);
        if self.minorant.c_inv.is_none() || ceiling == 0.0 || ceiling < wanted {
            return 0.0;
        }
        let s = &self.minorant.schur;
        let v = rotation_part(r);
        // Column k of M is vec(eₖ × each column of r): row (i, j) is (eₖ × r₍:,ⱼ₎)ᵢ; the constant's
        // row is zero.
        let m = SMatrix::<f64, 10, 3>::from_fn(|row, k| {
            if row == ONE {
                return 0.0;
            }
            let (i, j) = (row / 3, row % 3);
            let c = r.column(j);
            match (k, i) {
                (0, 1) => -c.z,
                (0, 2) => c.y,
                (1, 0) => c.z,
                (1, 2) => -c.x,
                (2, 0) => -c.y,
                (2, 1) => c.x,
                _ => 0.0,
            }
        });
        let sv = s * v;
        let q0 = v.dot(&sv);
        let g: Vector3<f64> = m.transpose() * sv;
        let h: Matrix3<f64> = m.transpose() * (s * m);
        let m_min = self.scale * ball_minimum_lower_bound(q0, &g, &h, theta);
        minkowski(m_min.max(0.0), rest)
    }

    /// The Minkowski bound `½ (√q_min − θ η)₊²` of the poses at the rotation `r` and those within the
    /// angle `θ` of it (`−∞` when `Q` does not fix the translation).
    pub(super) fn bound_near(&self, r: &Matrix3<f64>, theta: f64) -> f64 {
        self.at(r)
            .map_or(f64::NEG_INFINITY, |(_, q_min, eta)| minkowski(q_min, theta * eta))
    }

    /// What a box whose poses of `S` keep the points within `reach` hands down: the depth bounds
    /// `min(reachᵢ, Dᵢ / √κ)`, met by the scale that takes up the least growth of the weights, or
    /// by a rebuilt minorant when the weights grow on average by [`REBUILD_GAIN`] more than that.
    /// (`reach` is read twice when the minorant is rebuilt, and is not stored otherwise.)
    ///
    /// A rebuilt minorant weighs most the points that came closest: that raises `q_min` but also `η`,
    /// and where one point came much closer than the others it can weaken the bound. The rebuilt
    /// minorant is handed down only where it bounds at least as well at the box's centre rotation
    /// `r_c` over the octants' half-diagonal `θ_octant` (both are valid minorants).
    pub(super) fn tightened(
        &self,
        rebuild: impl FnOnce(Vec<f64>) -> Minorant,
        reach: impl Iterator<Item = f64> + Clone,
        r_c: &Matrix3<f64>,
        theta_octant: f64,
    ) -> ScaledMinorant {
        // A weight grows by (Dᵢ / √κ)² / reachᵢ² where the reach is the tighter bound, else by 1.
        let (least, sum) =
            (self.minorant.depths.iter().zip(reach.clone())).fold((f64::INFINITY, 0.0), |(least, sum), (d, r)| {
                let (d2, r2) = (d * d, self.scale * r * r);
                let growth = if r2 < d2 { d2 / r2 } else { 1.0 };
                (least.min(growth), sum + growth)
            });
        let mean = sum / self.minorant.depths.len() as f64;
        let scaled = ScaledMinorant {
            minorant: Rc::clone(&self.minorant),
            scale: self.scale * least.max(1.0),
        };
        if mean < REBUILD_GAIN * least {
            return scaled;
        }
        let rebuilt = ScaledMinorant {
            minorant: Rc::new(rebuild(self.depths().zip(reach).map(|(d, r)| r.min(d)).collect())),
            scale: 1.0,
        };
        if rebuilt.bound_near(r_c, theta_octant) >= scaled.bound_near(r_c, theta_octant) {
            rebuilt
        } else {
            scaled
        }
    }
}

/// A lower bound of `min q₀ + 2 gᵀφ + φᵀHφ` over the ball `‖φ‖ ≤ θ` (`H` positive semidefinite): the
/// Lagrangian dual `q₀ − gᵀ (H + λI)⁻¹ g − λ θ²`, which bounds the minimum from below at every
/// `λ ≥ 0` where `H + λI` is positive definite (weak duality), at the `λ` of a few Newton steps on
/// the secular equation `1/‖p(λ)‖ = 1/θ`, `p(λ) = (H + λI)⁻¹ g` (the dual's maximiser when the
/// constraint is active; `λ = 0` when the unconstrained minimiser lies in the ball). Lowered by a
/// relative `1e-9` of its terms for rounding; `−∞` when no `λ` tried makes `H + λI` definite.
pub(super) fn ball_minimum_lower_bound(q0: f64, g: &Vector3<f64>, h: &Matrix3<f64>, theta: f64) -> f64 {
    let dual = |lambda: f64| -> Option<(f64, Vector3<f64>, f64)> {
        let chol = (h + Matrix3::identity() * lambda).cholesky()?;
        let p = chol.solve(g);
        let gp = g.dot(&p);
        if !(gp >= 0.0 && gp.is_finite()) {
            return None;
        }
        let value = q0 - gp - lambda * theta * theta;
        let rounding = 1e-9 * (q0.abs() + gp + lambda * theta * theta);
        // pᵀ (H + λI)⁻¹ p, for the Newton step.
        let curvature = p.dot(&chol.solve(&p));
        Some((value - rounding, p, curvature))
    };
    // Positive definite from the start: a tiny multiple of the trace (H is only semidefinite).
    let mut lambda = 1e-12 * h.trace().max(f64::MIN_POSITIVE);
    let mut best = f64::NEG_INFINITY;
    for _ in 0..NEWTON_STEPS {
        let Some((value, p, curvature)) = dual(lambda) else {
            break;
        };
        best = best.max(value);
        let norm = p.norm();
        if norm <= theta || !(curvature > 0.0) {
            break;
        }
        // Newton on 1/‖p(λ)‖ − 1/θ (Moré & Sorensen): increases λ monotonically towards the root.
        lambda += (norm * norm / curvature) * (norm - theta) / theta;
    }
    best
}

/// `½ (√q − rest)₊²`: a lower bound of `½ ‖v‖²` for every `v` within `rest` of a vector whose norm is
/// at least `√q` (Minkowski), the form of every box bound of the rotation search.
pub(super) fn minkowski(q: f64, rest: f64) -> f64 {
    0.5 * (q.sqrt() - rest).max(0.0).powi(2)
}

/// `e^θ − 1 − θ`: `‖(exp(φ) − I − [φ]ₓ) y‖ ≤ (e^θ − 1 − θ) ‖y‖` for `‖φ‖ ≤ θ` (the exponential series
/// from its third term, `‖[φ]ₓᵏ y‖ ≤ θᵏ ‖y‖`).
pub(super) fn rotation_rest(theta: f64) -> f64 {
    theta.exp() - 1.0 - theta
}

/// Newton steps of [`ball_minimum_lower_bound`] (every step's dual value is a valid bound).
pub(super) const NEWTON_STEPS: usize = 8;

/// The largest eigenvalue of a symmetric 3x3 matrix, in closed form (trigonometric solution of the
/// characteristic cubic), raised by a relative `1e-9` to cover its rounding.
pub(super) fn largest_eigenvalue(m: &Matrix3<f64>) -> f64 {
    let q = m.trace() / 3.0;
    let off = m[(0, 1)].powi(2) + m[(0, 2)].powi(2) + m[(1, 2)].powi(2);
    let p2 = (m[(0, 0)] - q).powi(2) + (m[(1, 1)] - q).powi(2) + (m[(2, 2)] - q).powi(2) + 2.0 * off;
    let p = (p2 / 6.0).sqrt();
    if !(p > 1e-300) {
        return q + q.abs() * 1e-9;
    }
    let b = (m - Matrix3::identity() * q) / p;
    let phi = (0.5 * b.determinant()).clamp(-1.0, 1.0).acos() / 3.0;
    let lambda = q + 2.0 * p * phi.cos();
    lambda + 1e-9 * (lambda.abs() + p)
}
