//! Step 3's bounds of one box of rotations beyond the points' minorant ([`super`]'s module docs): the
//! segments' residuals added to the minorant where the points' alone fall short
//! (`Problem::lines_bound`, with depth bounds), and the bound of a box without depth bounds, from the
//! residuals at its centre rotation with the translations in an ellipsoid handed down box by box
//! (`Problem::ball_bound`); each with the quadratic linearised in the rotation.

use super::minorant::{ball_minimum_lower_bound, largest_eigenvalue, minkowski, rotation_rest, ScaledMinorant};
use super::problem::{Problem, NEAR_ANSWER};
use crate::geometry::quaternion::skew;
use crate::global::branch_and_bound::Region;
use nalgebra::{Matrix3, Vector3};

/// One box of rotation vectors `ω` (`R = exp(ω) R̂`): centre and half-widths. Every rotation of the
/// box is within the angle `θ = ‖half‖` (half the diagonal) of the centre's: the angle between
/// `exp(ω) R̂` and `exp(ω_c) R̂` is at most `‖ω − ω_c‖` (Hartley & Kahl 2009, lemma 1).
#[derive(Clone, Copy)]
pub(super) struct Cell {
    pub(super) centre: Vector3<f64>,
    pub(super) half: Vector3<f64>,
}

impl Cell {
    pub(super) fn of(region: &Region) -> Self {
        // Element by element: a slice copy of three numbers would call memcpy for every box.
        let (l, u) = (&region.lower, &region.upper);
        let lower = Vector3::new(l[0], l[1], l[2]);
        let upper = Vector3::new(u[0], u[1], u[2]);
        Cell {
            centre: (lower + upper) * 0.5,
            half: (upper - lower) * 0.5,
        }
    }
}

/// An ellipsoid `{centre + L z : ‖z‖ ≤ 1}` (`shape = L Lᵀ`) that holds the translation of every pose
/// of `S` in a box (the search without depth bounds hands it down box by box), and its largest
/// semi-axis `radius = √λ_max(shape)`.
#[derive(Clone)]
pub(super) struct TranslationEllipsoid {
    pub(super) centre: Vector3<f64>,
    pub(super) shape: Matrix3<f64>,
    pub(super) radius: f64,
}

impl TranslationEllipsoid {
    /// The ball of centre `centre` and radius `radius`.
    pub(super) fn round(centre: Vector3<f64>, radius: f64) -> TranslationEllipsoid {
        TranslationEllipsoid {
            centre,
            shape: Matrix3::identity() * (radius * radius),
            radius,
        }
    }
}

/// The translations of [`Problem::line_terms`]: within `spread` of `t_star` and, given `shape`, in
/// the ellipsoid `{t* + L z : ‖z‖ ≤ 1}` (`shape = L Lᵀ`, largest semi-axis `spread`).
#[derive(Clone, Copy)]
pub(super) struct TranslationSet<'a> {
    pub(super) t_star: &'a Vector3<f64>,
    pub(super) spread: f64,
    pub(super) shape: Option<&'a Matrix3<f64>>,
}

/// A segment endpoint's term of [`Problem::lines_bound`] for a box: the weight `1 / W²`, the residual
/// numerator `n = α + βᵀ t` at the box's centre rotation, and `drift` with `|Δn| ≤ θ drift` over the
/// box ([`Problem::line_terms`]).
#[derive(Clone)]
pub(super) struct LineTerm {
    pub(super) weight: f64,
    pub(super) alpha: f64,
    pub(super) beta: Vector3<f64>,
    pub(super) drift: f64,
    /// `ē`, and the parts of `drift` for another translation: `‖ē‖ ‖a × d‖` and `‖d‖`.
    pub(super) e: Vector3<f64>,
    pub(super) moment_part: f64,
    pub(super) d_norm: f64,
    /// `r (a × d)` and `r d` at the box's centre rotation `r`.
    pub(super) rm: Vector3<f64>,
    pub(super) rd: Vector3<f64>,
    /// The offset `e_k` of the segment's camera ([`super::problem::LineForm::offset`]): the
    /// numerator at the translation `t` is the single camera's at `t + e_k` (zero for one camera).
    pub(super) offset: Vector3<f64>,
}

impl LineTerm {
    /// `γ = r m × ē + r d × (ē × t)`: the numerator's first-order change `φᵀ γ` under the rotation
    /// `exp(φ) r` at the translation `t` ([`Problem::linear_ball_bound`]).
    pub(super) fn gamma(&self, t: &Vector3<f64>) -> Vector3<f64> {
        self.rm.cross(&self.e) + self.rd.cross(&self.e.cross(&(t + self.offset)))
    }

    /// The numerator's drift over the rotations `exp(φ) r`, `‖φ‖ ≤ θ`, at translations `t* + Δ`:
    /// `|n(exp(φ) r, t* + Δ) − n(r, t* + Δ)| ≤ spin + θ ‖d‖ ‖ē × Δ‖`. The difference is
    /// `ēᵀ (R − r) m + ēᵀ (t* × (R − r) d) + ēᵀ (Δ × (R − r) d)` (`R = exp(φ) r`, `m = a × d`), the
    /// last at most `‖(R − r) d‖ ‖ē × Δ‖ ≤ θ ‖d‖ ‖ē × Δ‖`. With `a = ‖ē‖ ‖m‖ + ‖d‖ ‖ē × t*‖`, `spin`
    /// bounds the first two: the lesser of `θ a` (each rotated vector moves by at most `θ` times its
    /// norm) and `θ ‖γ‖ + ρ a` (`ρ = e^θ − 1 − θ`: the first-order part `φᵀ γ(t*)` exactly, the rest of
    /// `exp(φ)` costing `ρ` times the norms; `Problem::linear_ball_bound`). Returns `(a, spin, θ)`.
    pub(super) fn spin(&self, theta: f64, t_star: &Vector3<f64>) -> (f64, f64, f64) {
        let rho = rotation_rest(theta);
        let drift = self.moment_part + self.d_norm * self.e.cross(&(t_star + self.offset)).norm();
        let first_order = self.gamma(t_star).norm();
        (drift, (theta * drift).min(theta * first_order + rho * drift), theta)
    }

    /// The bound `θ ‖d‖ cross + ρ (‖ē‖ ‖m‖ + ‖d‖ ‖ē × t*‖)` (`ρ = e^θ − 1 − θ`) on
    /// `|n − (α + βᵀ t + φᵀ γ(t*))|` at the rotation `exp(φ) r`, `‖φ‖ ≤ θ`, and the translation
    /// `t = t* + Δ` with `‖ē × Δ‖ ≤ cross` ([`Problem::linear_lines_bound`]).
    pub(super) fn linear_rest(&self, theta: f64, t_star: &Vector3<f64>, cross: f64) -> f64 {
        theta * self.d_norm * cross
            + rotation_rest(theta) * (self.moment_part + self.d_norm * self.e.cross(&(t_star + self.offset)).norm())
    }

    /// `‖d‖² [ē]ₓᵀ [ē]ₓ`: `Δᵀ (this) Δ = ‖d‖² ‖ē × Δ‖²`, the square of the drift's part in `Δ` per unit
    /// of `θ` ([`Self::spin`]).
    pub(super) fn coupling(&self) -> Matrix3<f64> {
        let e = &self.e;
        (Matrix3::identity() * e.norm_squared() - e * e.transpose()) * (self.d_norm * self.d_norm)
    }
}

impl Problem<'_> {
    /// The segments' terms of [`Self::lines_bound`] for the rotations within the angle `θ` of `r`
    /// and the translations within `spread` of `t_star` (and, given `shape`, in the ellipsoid
    /// `{t* + L z : ‖z‖ ≤ 1}`, `shape = L Lᵀ`, whose largest semi-axis is `spread`). A segment endpoint's residual is
    /// `r_e = n / w` with `n = ēᵀ ((R a + t) × R d) = ēᵀ R (a × d) + tᵀ (R d × ē)` (`d = b − a`),
    /// linear in `t` for a fixed rotation, and
    /// `w = ‖G_e m_xy‖ ≤ ‖G_e‖ ‖m‖ ≤ W`, with two bounds on the moment `m = R (a × d) + t × R d` of the
    /// camera-frame line: it is at most its distance from the camera times `‖d‖`, and
    /// `‖d‖ min(‖R a + t‖, ‖R b + t‖)` is bounded over the rotations and translations as the points'
    /// distances are; and it moves from its value `m_c` at `(r, t*)` by at most
    /// `θ (‖a × d‖ + ‖d‖ ‖t‖) + ‖(t − t*) × r d‖`. So `r_e² ≥ n² / W²`. Between `r` and a rotation
    /// `R'`, `n` moves by at most `θ (‖ē‖ ‖a × d‖ + ‖d‖ ‖ē × t‖)` (`‖(R' − r) y‖ ≤ θ ‖y‖`), with
    /// `‖ē × t‖ ≤ ‖ē × t*‖ + ‖ē‖ spread`, or `‖ē × t*‖ + ‖[ē]ₓ L‖` with the spectral norm below the
    /// Frobenius norm `√(‖ē‖² tr(shape) − ēᵀ shape ē)` (an ellipsoid elongated along the line of
    /// sight moves `ē × t` little).
    pub(super) fn line_terms(
        &self,
        segments: usize,
        (r, theta): (&Matrix3<f64>, f64),
        TranslationSet { t_star, spread, shape }: TranslationSet,
    ) -> Vec<LineTerm> {
        let mut terms = Vec::with_capacity(2 * segments.min(self.lines.len()));
        for line in self.lines.iter().take(segments) {
            let [a_norm, b_norm, d_norm, m_norm] = line.norms;
            // The segment's camera sees the translation t + e_k (zero offset for one camera).
            let t_seen = t_star + line.offset;
            let reach = |x: &Vector3<f64>, norm: f64| (r * x + t_seen).norm() + theta * norm + spread;
            let distance = reach(&line.a, a_norm).min(reach(&line.b, b_norm));
            let (rd, rm) = (r * line.d, r * line.moment);
            let moment = (d_norm * distance).min(
                (rm + t_seen.cross(&rd)).norm()
                    + theta * (m_norm + d_norm * (t_seen.norm() + spread))
                    + Self::cross_extent(&rd, d_norm, spread, shape),
            );
            for &(e, e_norm, g_norm) in &line.ends {
                let beta = rd.cross(&e);
                terms.push(LineTerm {
                    weight: (g_norm * moment).powi(-2),
                    alpha: e.dot(&rm) + beta.dot(&line.offset),
                    beta,
                    drift: e_norm * m_norm
                        + d_norm * (e.cross(&t_seen).norm() + Self::cross_extent(&e, e_norm, spread, shape)),
                    e,
                    moment_part: e_norm * m_norm,
                    d_norm,
                    rm,
                    rd,
                    offset: line.offset,
                });
            }
        }
        terms
    }

    /// The largest `‖ē × Δt‖` over the translation steps `Δt` of [`Self::line_terms`]'s set.
    pub(super) fn cross_extent(e: &Vector3<f64>, e_norm: f64, spread: f64, shape: Option<&Matrix3<f64>>) -> f64 {
        let round = e_norm * spread;
        shape.map_or(round, |shape| {
            let frobenius2 = e_norm * e_norm * shape.trace() - e.dot(&(shape * e));
            round.min(frobenius2.max(0.0).sqrt() * (1.0 + 1e-12))
        })
    }

    /// A lower bound of `f` on the poses of `S` whose rotation is within the angle `θ` of `r` and
    /// whose translation is within `spread` of `t_star`, from the minorant `scaled` (its minimiser
    /// `t_star` and minimum `q_min` at `r`, [`ScaledMinorant::at`]'s, so that `κ Q(r, t) = q_min +
    /// (t − t*)ᵀ κ C (t − t*)`) with the segments' residuals added
    /// ([`Self::line_terms`]): `Q_total(R, t) = κ Q(R, t) + Σ (α + βᵀ t)² / W²` at `r` is a minorant
    /// of `2f` quadratic in `t`, and over the rotations its square root moves by at most
    /// `θ η_total`, `η_total² = κ η² + Σ drift² / W²` (Minkowski over all the terms), so
    /// `f ≥ ½ (√q_min − θ η_total)₊²` as for the points alone (`by_growth`). The first `segments`
    /// segments enter. `None` where the quadratic does not fix the translation.
    ///
    /// Where that falls short of `wanted` (`None`: not tried), the quadratic linearised in the
    /// rotation gives a second bound (`by_linear`), as [`Self::linear_ball_bound`] does without depth bounds: a rotation of
    /// the box is `exp(φ) r` (`‖φ‖ ≤ θ`, `exp(φ) = I + [φ]ₓ + E`, `‖E y‖ ≤ ρ ‖y‖`,
    /// `ρ = e^θ − 1 − θ`) and a translation `t* + Δ` with `‖Δ‖ ≤ spread`. A point's
    /// `Aᵢ (exp(φ) yᵢ + t)` is within `ρ ‖Aᵢ‖ ‖Xᵢ‖` of its linear part (the points' rest `ρ √κ η`),
    /// and a segment endpoint's numerator
    /// `n = α + βᵀ t + φᵀ γ + ēᵀ E r m + ēᵀ (t* × E r d) + ēᵀ (Δ × (R − r) d)` within
    /// `θ ‖d‖ ‖ē × Δ‖ + ρ (‖ē‖ ‖m‖ + ‖d‖ ‖ē × t*‖)` of `α + βᵀ t + φᵀ γ` (`‖ē × Δ‖` at most the
    /// set's [`Self::cross_extent`]). Minkowski over all the weighted terms gives
    /// `√(2f) ≥ √L(φ, Δ) − rest` with `L` the weighted sum of squares of the linear parts, and
    /// `√L ≥ √least` with [`Self::linear_part`]'s bound of its minimum over `Δ` and `‖φ‖ ≤ θ`. So
    /// `f ≥ ½ (√least − rest)₊²`: the rotation's first-order effect, in which the segments' drifts
    /// are large and partly cancel, enters exactly.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn lines_bound(
        &self,
        scaled: &ScaledMinorant,
        r: &Matrix3<f64>,
        theta: f64,
        (t_star, q_min): (&Vector3<f64>, f64),
        spread: f64,
        segments: usize,
        wanted: Option<f64>,
    ) -> Option<LinesBound> {
        let c = scaled.minorant.c * scaled.scale;
        let mut quadratic = Quadratic {
            c,
            g: -(c * t_star),
            c0: q_min + t_star.dot(&(c * t_star)),
            eta2: scaled.minorant.eta.powi(2) * scaled.scale,
        };
        let set = TranslationSet {
            t_star,
            spread,
            shape: None,
        };
        let terms = self.line_terms(segments, (r, theta), set);
        terms.iter().for_each(|term| quadratic.add_line(term));
        let (t_lines, q_lines, c_inv) = quadratic.minimum()?;
        let eta = quadratic.eta2.sqrt();
        let by_growth = minkowski(q_lines, theta * eta);
        let by_linear = match wanted {
            Some(wanted) if by_growth < wanted => {
                self.linear_lines_bound(scaled, (r, theta), set, &terms, &c_inv, (q_lines, wanted))
            }
            _ => 0.0,
        };
        Some(LinesBound {
            lower: by_growth.max(by_linear),
            by_growth,
            by_linear,
            t_star: t_lines,
            q_min: q_lines,
            c: quadratic.c,
            c_inv,
            eta,
        })
    }

    /// [`Self::lines_bound`]'s linearised bound (`by_linear`) for the translation set `set` (its
    /// points' `t*` and `spread`), the segments' `terms` and the quadratic's `C⁻¹` and minimum
    /// `q_lines`; 0 where even
    /// `½ (√q_lines − rest)₊²`, which it cannot exceed, falls short of `wanted`.
    pub(super) fn linear_lines_bound(
        &self,
        scaled: &ScaledMinorant,
        (r, theta): (&Matrix3<f64>, f64),
        set: TranslationSet,
        terms: &[LineTerm],
        c_inv: &Matrix3<f64>,
        (q_lines, wanted): (f64, f64),
    ) -> f64 {
        let lines_rest2: f64 = (terms.iter())
            .map(|term| {
                let cross = Self::cross_extent(&term.e, term.e.norm(), set.spread, None);
                term.weight * term.linear_rest(theta, set.t_star, cross).powi(2)
            })
            .sum();
        let rest = (scaled.second_order_rest(theta).powi(2) + lines_rest2).sqrt();
        if minkowski(q_lines, rest) < wanted {
            return 0.0;
        }
        let points = (self.corr.points3d.iter().zip(scaled.depths())).map(|(x, d)| (r * x, 1.0 / (d * d)));
        let least = self.linear_part(terms, points, set.t_star, c_inv, theta).least;
        minkowski(least.max(0.0), rest)
    }

    /// The segments that enter the bound of `cell`: every one near the answer, where the translation
    /// ellipsoid decides whether the box lies inside the whitened ball; the longest `box_segments`
    /// elsewhere.
    pub(super) fn segments_in(&self, cell: &Cell) -> usize {
        if cell.centre.norm() + cell.half.norm() <= NEAR_ANSWER {
            self.lines.len()
        } else {
            self.box_segments
        }
    }

    /// The bound of a box without depth bounds ([`super::problem::SearchStart::ObjectDistance`]) whose poses of `S` have their
    /// rotations within `θ` of `r` and their translations in `ball`.
    ///
    /// Every point is at most `Dᵢ = ‖r Xᵢ + centre‖ + θ ‖Xᵢ‖ + radius` from the camera, so its term
    /// `‖Aᵢ (R Xᵢ + t)‖² / Dᵢ²` (step 2) and the segments' terms `(α + βᵀ t)² / W²`
    /// ([`Self::line_terms`]) are a minorant of `2f`; at `r` it is the quadratic
    /// `Q(t) = q_min + Δᵀ C Δ`, `Δ = t − t*`. Over the rotations a point's term moves by at most
    /// `θ ‖Aᵢ‖ ‖Xᵢ‖ / Dᵢ`, and a segment endpoint's by `θ (‖ē‖ ‖a × d‖ + ‖d‖ ‖ē × t‖) / W` with
    /// `‖ē × t‖ ≤ ‖ē × t*‖ + ‖ē × Δ‖`. By Minkowski over all the terms,
    /// `√(2f) ≥ √(q_min + Δᵀ C Δ) − θ (η₀ + √(Δᵀ N Δ))` with `η₀` the terms' drifts at `t*` and
    /// `N = Σ ‖d‖² [ē]ₓᵀ [ē]ₓ / W²`. With `μ` the least eigenvalue of `C` relative to `N`
    /// (`Δᵀ C Δ ≥ μ x²`, `x = √(Δᵀ N Δ)`), `√(2f) ≥ v(x) − θ η₀`, `v(x) = √(q_min + μ x²) − θ x`, a
    /// convex function whose least value over `x ≤ x_ball` (the ball's reach) is the bound. The
    /// translations of the box's poses of `S` have `v(x) ≤ β = √(2f̂) + θ η₀`, so `x ≤ x_max` and
    /// `Δᵀ C Δ ≤ (β + θ x_max)² − q_min`: an ellipsoid. The drift of the segments is paid against the
    /// quadratic's own growth, not against the ball, which only weighs the terms.
    pub(super) fn ball_bound(
        &self,
        segments: usize,
        r: &Matrix3<f64>,
        theta: f64,
        ball: &TranslationEllipsoid,
        f_hat: f64,
    ) -> Option<BoxBound> {
        let mut quadratic = Quadratic {
            c: Matrix3::zeros(),
            g: Vector3::zeros(),
            c0: 0.0,
            eta2: 0.0,
        };
        let mut depths = Vec::with_capacity(self.forms.len());
        let mut rotated = Vec::with_capacity(self.forms.len());
        for ((x, form), norm) in self.corr.points3d.iter().zip(&self.forms).zip(&self.norms) {
            let y = r * x;
            let depth = (y + ball.centre).norm() + theta * norm + ball.radius;
            let w = 1.0 / (depth * depth);
            let hy = form.h * y;
            quadratic.c += form.h * w;
            quadratic.g += hy * w;
            quadratic.c0 += w * y.dot(&hy);
            quadratic.eta2 += w * form.norm2 * norm * norm;
            depths.push(depth);
            rotated.push((y, w));
        }
        let points_eta2 = quadratic.eta2;
        let set = TranslationSet {
            t_star: &ball.centre,
            spread: ball.radius,
            shape: Some(&ball.shape),
        };
        let terms = self.line_terms(segments, (r, theta), set);
        terms.iter().for_each(|term| quadratic.add_line(term));
        let (t_star, q_min, c_inv) = quadratic.minimum()?;
        // Per segment endpoint, its drift at t*: θ aₖ with aₖ = ‖ē‖ ‖m‖ + ‖d‖ ‖ē × t*‖, or
        // θ ‖γₖ‖ + ρ aₖ with the exact first-order part γₖ ([`Self::linear_ball_bound`]); the lesser.
        let mut step = theta;
        let mut eta0_2 = points_eta2;
        let mut spin2 = points_eta2 * theta * theta;
        let mut n = Matrix3::zeros();
        for term in &terms {
            let (drift, spin, its_step) = term.spin(theta, &t_star);
            step = step.max(its_step);
            eta0_2 += term.weight * drift * drift;
            spin2 += term.weight * spin * spin;
            n += term.coupling() * term.weight;
        }
        let eta0 = eta0_2.sqrt();
        let (mu, n_max) = relative_floor(&c_inv, &n);
        // The ball's reach in x: ‖Δ‖ ≤ ‖t* − centre‖ + radius.
        let x_ball = n_max.max(0.0).sqrt() * ((t_star - ball.centre).norm() + ball.radius);
        let spin = spin2.sqrt();
        let v = |x: f64| (q_min + mu * x * x).sqrt() - step * x;
        let x_least = if step * step < mu {
            (q_min * step * step / (mu * (mu - step * step))).sqrt().min(x_ball)
        } else {
            x_ball
        };
        let least = if mu.is_finite() { v(x_least) } else { q_min.sqrt() };
        let by_growth = 0.5 * (least - spin).max(0.0).powi(2);
        let mut by_linear = 0.0;
        if by_growth < f_hat {
            let linear = MinorantAtCentre {
                terms: &terms,
                points: &rotated,
                t_star: &t_star,
                c_inv: &c_inv,
                n: &n,
                mu,
                eta0,
            };
            by_linear = self.linear_ball_bound(&linear, theta);
        }
        // The largest x with v(x) ≤ β: the larger root of (μ − s²) x² − 2 β s x + q_min − β²
        // (s = θ; x_ball where that does not bound x).
        let beta = (2.0 * f_hat).sqrt() + spin;
        let x_max = if !mu.is_finite() {
            0.0
        } else if step * step < mu {
            let (a, b) = (mu - step * step, beta * step);
            let disc = (b * b - a * (q_min - beta * beta)).max(0.0);
            ((b + disc.sqrt()) / a).min(x_ball)
        } else {
            x_ball
        };
        let slack = ((beta + step * x_max).powi(2) - q_min).max(0.0);
        Some(BoxBound {
            lower: by_growth.max(by_linear),
            by_growth,
            by_linear,
            t_star,
            c: quadratic.c,
            c_inv,
            slack,
            depths,
            parts: BallBoundParts { q_min, n, spin, eta0 },
        })
    }
}

/// A box's ellipsoid `(t − centre)ᵀ C (t − centre) ≤ slack` that holds the translations of its poses
/// of `S`, its reach `spread ≥ max ‖t − centre‖` over it, and whether it comes from the quadratic with
/// the segments' terms ([`LinesBound::ellipsoid`]) rather than the points' minorant.
#[derive(Clone, Copy)]
pub(super) struct Ellipsoid {
    pub(super) centre: Vector3<f64>,
    pub(super) c: Matrix3<f64>,
    pub(super) slack: f64,
    pub(super) spread: f64,
    pub(super) with_segments: bool,
}

/// [`Problem::lines_bound`]: the bound, and the quadratic `Q_total(t) = q_min + (t − t*)ᵀ C (t − t*)`
/// at the box's centre rotation with `η_total` (`eta`). The poses of `S` in the box (their
/// translations within the points' ellipsoid) have `√Q_total ≤ √(2f̂) + θ η_total`: a second
/// ellipsoid that holds their translations.
pub(super) struct LinesBound {
    pub(super) lower: f64,
    // The two bounds apart: read by the unit tests, which check each.
    #[cfg_attr(not(test), allow(dead_code))]
    pub(super) by_growth: f64,
    #[cfg_attr(not(test), allow(dead_code))]
    pub(super) by_linear: f64,
    pub(super) t_star: Vector3<f64>,
    pub(super) q_min: f64,
    pub(super) c: Matrix3<f64>,
    pub(super) c_inv: Matrix3<f64>,
    pub(super) eta: f64,
}

impl LinesBound {
    /// The ellipsoid `(t − t*)ᵀ C (t − t*) ≤ slack` of the translations with
    /// `√Q_total(t) ≤ √(2f̂) + θ η_total`, and its reach `spread = max ‖t − t*‖` over it.
    pub(super) fn ellipsoid(&self, f_hat: f64, theta: f64) -> (f64, f64) {
        let beta = (2.0 * f_hat).sqrt() + theta * self.eta;
        let slack = (beta * beta - self.q_min).max(0.0);
        (slack, (slack * largest_eigenvalue(&self.c_inv)).sqrt())
    }
}

/// `μ` with `Δᵀ C Δ ≥ μ Δᵀ N Δ` for every `Δ` (`C` given by its inverse, `N` positive definite), and
/// `λ_max(N)`: `μ = λ_min(L⁻¹ C L⁻ᵀ) = 1 / λ_max(Lᵀ C⁻¹ L)` for `N = L Lᵀ`, lowered for rounding by
/// [`largest_eigenvalue`]'s raise. `(+∞, 0)` when `N` is not positive definite (no segments).
pub(super) fn relative_floor(c_inv: &Matrix3<f64>, n: &Matrix3<f64>) -> (f64, f64) {
    match n.cholesky() {
        Some(chol) => {
            let l = chol.l();
            (
                1.0 / largest_eigenvalue(&(l.transpose() * c_inv * l)),
                largest_eigenvalue(n),
            )
        }
        None => (f64::INFINITY, 0.0),
    }
}

/// The minorant of a box without depth bounds at its centre rotation `r`, as [`Problem::ball_bound`]
/// assembled it and [`Problem::linear_ball_bound`] linearises it in the rotation: the segments'
/// terms, the points' `r Xᵢ` and weights, the quadratic's minimiser and `C⁻¹`, `N`, `μ` and `η₀`.
pub(super) struct MinorantAtCentre<'a> {
    pub(super) terms: &'a [LineTerm],
    pub(super) points: &'a [(Vector3<f64>, f64)],
    pub(super) t_star: &'a Vector3<f64>,
    pub(super) c_inv: &'a Matrix3<f64>,
    pub(super) n: &'a Matrix3<f64>,
    pub(super) mu: f64,
    pub(super) eta0: f64,
}

/// [`Problem::ball_bound`]'s result: the bound (the larger of the two: the minorant's growth against
/// the drift, and the linearised minorant, computed only where the first falls short of `f̂`), the
/// ellipsoid `(t − t*)ᵀ C (t − t*) ≤ slack` (`C⁻¹` given) that holds the translations of the box's
/// poses of `S`, and the points' depth bounds.
pub(super) struct BoxBound {
    pub(super) lower: f64,
    // The two bounds apart: read by the unit tests, which check each.
    #[cfg_attr(not(test), allow(dead_code))]
    pub(super) by_growth: f64,
    #[cfg_attr(not(test), allow(dead_code))]
    pub(super) by_linear: f64,
    pub(super) t_star: Vector3<f64>,
    pub(super) c: Matrix3<f64>,
    pub(super) c_inv: Matrix3<f64>,
    pub(super) slack: f64,
    pub(super) depths: Vec<f64>,
    #[cfg_attr(not(test), allow(dead_code))]
    pub(super) parts: BallBoundParts,
}

/// The parts of [`Problem::ball_bound`]'s bounds that the unit tests check the algebra on: `q_min`,
/// `N` and the drifts at `t*` (`spin` for the growth bound, `η₀` the linearised one's rest per `ρ`).
#[cfg_attr(not(test), allow(dead_code))]
pub(super) struct BallBoundParts {
    pub(super) q_min: f64,
    pub(super) n: Matrix3<f64>,
    pub(super) spin: f64,
    pub(super) eta0: f64,
}

impl Problem<'_> {
    /// [`Problem::ball_bound`]'s minorant linearised in the rotation, as [`ScaledMinorant::linear_bound`] does
    /// with depth bounds (0 where it cannot be computed). A rotation of the box is `exp(φ) r`,
    /// `‖φ‖ ≤ θ`, `exp(φ) = I + [φ]ₓ + E` with `‖E y‖ ≤ ρ ‖y‖`, `ρ = e^θ − 1 − θ`; write `t = t* + Δ`.
    /// A segment endpoint's numerator is then
    /// `n = α + βᵀ t + φᵀ γ + ēᵀ E r m + ēᵀ (t* × E r d) + ēᵀ (Δ × (R − r) d)` with
    /// `γ = r m × ē + r d × (ē × t*)` (`m = a × d`, `R = exp(φ) r`), so it is within
    /// `θ ‖d‖ ‖ē × Δ‖ + ρ (‖ē‖ ‖m‖ + ‖d‖ ‖ē × t*‖)` of the linear `α + βᵀ t + φᵀ γ`; a point's
    /// `Aᵢ (exp(φ) yᵢ + t)` (`yᵢ = r Xᵢ`) is within `ρ ‖Aᵢ‖ ‖Xᵢ‖` of `Aᵢ (yᵢ + t − [yᵢ]ₓ φ)`. With
    /// `L(φ, Δ)` the weighted sum of squares of the linear parts (a quadratic in `(φ, Δ)`), Minkowski
    /// gives `√(2f) ≥ √L − θ √(Δᵀ N Δ) − ρ η₀`. Minimised over `Δ`,
    /// `L = L_min(φ) + (Δ − Δ*(φ))ᵀ C (Δ − Δ*(φ))` with `Δ*(φ) = −C⁻¹ (B φ + h_Δ)` linear in `φ`, and
    /// `√(Δᵀ N Δ) ≤ y + s`, `y = √((Δ − Δ*)ᵀ N (Δ − Δ*))`, `s ≤ ‖N^½ C⁻¹ B‖ θ + ‖N^½ C⁻¹ h_Δ‖`; as in
    /// [`Problem::ball_bound`], `√(L_min + μ y²) − θ y ≥ √L_min √(1 − θ² / μ)`. `L_min(φ)`
    /// is a convex quadratic, bounded below over the ball `‖φ‖ ≤ θ` by
    /// [`ball_minimum_lower_bound`]. So
    /// `√(2f) ≥ √(min L_min) √(1 − θ² / μ) − θ s − ρ η₀`.
    pub(super) fn linear_ball_bound(&self, lin: &MinorantAtCentre, theta: f64) -> f64 {
        let rho = rotation_rest(theta);
        let step = theta;
        if !(step * step < lin.mu) {
            return 0.0;
        }
        let linear = self.linear_part(lin.terms, lin.points.iter().copied(), lin.t_star, lin.c_inv, theta);
        // s: ‖N^½ C⁻¹ B‖ θ + ‖N^½ C⁻¹ h_Δ‖ (norms through N: ‖N^½ v‖² = vᵀ N v).
        let coupling = largest_eigenvalue(&(linear.cb.transpose() * lin.n * linear.cb))
            .max(0.0)
            .sqrt();
        let s = coupling * theta + linear.offset.dot(&(lin.n * linear.offset)).max(0.0).sqrt();
        let root = linear.least.max(0.0).sqrt() * (1.0 - step * step / lin.mu).sqrt();
        0.5 * (root - step * s - rho * lin.eta0).max(0.0).powi(2)
    }

    /// The linear parts of a box's minorant at its centre rotation `r` ([`Self::linear_ball_bound`],
    /// [`Self::lines_bound`]): a rotation of the box is `exp(φ) r`, `‖φ‖ ≤ θ`, and a translation
    /// `t_ref + Δ`; a segment endpoint's numerator has the linear part `α + βᵀ t_ref + βᵀ Δ + φᵀ γ`
    /// (`γ` at `t_ref`, [`LineTerm::gamma`]) and a point's `Aᵢ (yᵢ + t + eᵢ)` (`yᵢ = r Xᵢ`, `eᵢ` its
    /// camera's offset) the linear part `Aᵢ (yᵢ + t_ref + eᵢ + Δ − [yᵢ]ₓ φ)`. Their weighted sum of squares is a convex quadratic
    /// `L(φ, Δ)`; `C⁻¹` is the inverse of its `Δ` block (the quadratic's own). Minimised over `Δ`,
    /// `L = L_min(φ) + (Δ − Δ*(φ))ᵀ C (Δ − Δ*(φ))`, `Δ*(φ) = −C⁻¹ (B φ + h_Δ)`, and `least` bounds
    /// `L_min` from below over the ball `‖φ‖ ≤ θ` ([`ball_minimum_lower_bound`]).
    pub(super) fn linear_part(
        &self,
        terms: &[LineTerm],
        points: impl Iterator<Item = (Vector3<f64>, f64)>,
        t_ref: &Vector3<f64>,
        c_inv: &Matrix3<f64>,
        theta: f64,
    ) -> LinearPart {
        // L(z) = L₀ + 2 hᵀ z + zᵀ M z, z = (φ, Δ), M = [M_φφ Bᵀ; B C]: C is the quadratic's own
        // (its inverse given), so only M_φφ, B, h and L₀ are summed.
        let (mut m_pp, mut b) = (Matrix3::zeros(), Matrix3::zeros());
        let (mut h_p, mut h_d) = (Vector3::zeros(), Vector3::zeros());
        let mut l0 = 0.0;
        for term in terms {
            let gamma = term.gamma(t_ref);
            let value = term.alpha + term.beta.dot(t_ref);
            let (w_gamma, w_beta) = (gamma * term.weight, term.beta * term.weight);
            m_pp += w_gamma * gamma.transpose();
            b += w_beta * gamma.transpose();
            h_p += w_gamma * value;
            h_d += w_beta * value;
            l0 += value * value * term.weight;
        }
        for (((y, w), form), offset) in points.zip(&self.forms).zip(&self.offsets) {
            // The camera-frame point's linear part is J z with J = [−[y]ₓ | I]: JᵀHJ has the blocks
            // [y]ₓᵀ H [y]ₓ, −H [y]ₓ (B) and H, and JᵀH p the parts [y]ₓ H p and H p (its camera's
            // offset moves p, not the rotation's part).
            let (y_cross, wh) = (skew(&y), form.h * w);
            let wh_cross = wh * y_cross;
            let p = y + t_ref + offset;
            let hp = wh * p;
            m_pp -= y_cross * wh_cross;
            b -= wh_cross;
            h_p += y_cross * hp;
            h_d += hp;
            l0 += p.dot(&hp);
        }
        let schur = m_pp - b.transpose() * c_inv * b;
        let g = h_p - b.transpose() * (c_inv * h_d);
        let q0 = l0 - h_d.dot(&(c_inv * h_d));
        LinearPart {
            least: ball_minimum_lower_bound(q0, &g, &(0.5 * (schur + schur.transpose())), theta),
            cb: c_inv * b,
            offset: c_inv * h_d,
        }
    }
}

/// [`Problem::linear_part`]: the lower bound `least` of `L_min(φ)` over `‖φ‖ ≤ θ`, and the parts of
/// `Δ*(φ) = −(C⁻¹ B φ + C⁻¹ h_Δ)`.
pub(super) struct LinearPart {
    pub(super) least: f64,
    pub(super) cb: Matrix3<f64>,
    pub(super) offset: Vector3<f64>,
}

/// A minorant of `2f` at a box's centre rotation as a quadratic `tᵀ C t + 2 gᵀ t + c₀` in the
/// translation, and `η²`: over the box's rotations (within `θ` of the centre's) its square root moves
/// by at most `θ η` (Minkowski over its terms).
pub(super) struct Quadratic {
    pub(super) c: Matrix3<f64>,
    pub(super) g: Vector3<f64>,
    pub(super) c0: f64,
    pub(super) eta2: f64,
}

impl Quadratic {
    /// Adds a segment endpoint's term `(α + βᵀ t)² / W²` ([`Problem::line_terms`]).
    pub(super) fn add_line(&mut self, term: &LineTerm) {
        self.c += term.beta * term.beta.transpose() * term.weight;
        self.g += term.beta * (term.alpha * term.weight);
        self.c0 += term.alpha * term.alpha * term.weight;
        self.eta2 += term.weight * term.drift * term.drift;
    }

    /// The minimiser `t*`, the minimum `q_min` (clamped at 0) and `C⁻¹` (`None` when `C` is singular:
    /// the quadratic does not fix the translation).
    pub(super) fn minimum(&self) -> Option<(Vector3<f64>, f64, Matrix3<f64>)> {
        let c_inv = self.c.try_inverse()?;
        let t_star = -(c_inv * self.g);
        Some((t_star, (self.c0 + self.g.dot(&t_star)).max(0.0), c_inv))
    }
}
