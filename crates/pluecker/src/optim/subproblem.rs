//! The trust-region subproblem `min ½ dᵀHd + gᵀd  s.t. ‖d‖ ≤ δ` (Phong & Horaud 1995, eq. 29).
//!
//! Both solvers rest on Theorem 1 (Gay; Moré & Sorensen): `d*` solves it iff for some `μ* ≥ 0`,
//! `H + μ*I ⪰ 0`, `(H + μ*I) d* = −g` and `μ*(‖d*‖ − δ) = 0`.
//! - [`hebden_step`] is the paper's algorithm (Appendix A, eq. 34) for a positive-definite `H`
//!   (the shifted Gauss-Newton Hessian `JᵀJ + αI`): Newton's method on `ψ(μ) = 1/δ − 1/‖d(μ)‖` with
//!   one Cholesky factorisation per iteration.
//! - [`more_sorensen_step`] handles an indefinite `H` (the exact Hessian of large-residual problems,
//!   section 4.2): the same Newton iteration on `ψ`, safeguarded by a bracket `[μ_L, μ_U]` as Moré &
//!   Sorensen do, and the "hard case" (g orthogonal to the lowest eigenvector) solved exactly. Since
//!   `N ≤ 8` here it works in the eigenbasis of `H` instead of probing with Cholesky factorisations.

use nalgebra::{DMatrix, SMatrix, SVector};

/// Relative accuracy of `‖d‖ = δ` at which both iterations stop (the ε of step 1.3, relative to δ).
pub const BOUNDARY_TOLERANCE: f64 = 1e-2;
/// Iteration cap of both secular-equation iterations (the paper reports 4 on average).
const MAX_SECULAR_ITERATIONS: usize = 60;

/// Solution of the subproblem.
#[derive(Debug, Clone, Copy)]
pub struct Step<const N: usize> {
    /// The step `d`.
    pub d: SVector<f64, N>,
    /// The multiplier `μ*` (0 for an interior Newton step).
    pub mu: f64,
    /// The model decrease `q(0) − q(d) = −gᵀd − ½ dᵀHd ≥ 0` (denominator of eq. 28).
    pub predicted_decrease: f64,
}

fn step_with_decrease<const N: usize>(
    h: &SMatrix<f64, N, N>,
    g: &SVector<f64, N>,
    d: SVector<f64, N>,
    mu: f64,
) -> Step<N> {
    let predicted_decrease = -g.dot(&d) - 0.5 * d.dot(&(h * d));
    Step {
        d,
        mu,
        predicted_decrease,
    }
}

/// The factorisation `H + μI = L D Lᵀ` (`L` unit lower triangular, `D` diagonal) of a small dense
/// matrix, in plain arrays: the subproblem factorises an `N ≤ 8` matrix once or more per iteration,
/// where nalgebra's general decomposition spends more on bookkeeping than on arithmetic. Free of square
/// roots, and of divisions after one per column: they are the long-latency steps. The Cholesky factor
/// of Appendix A is `R = D^½ Lᵀ`. Reads the lower triangle of `H`.
struct Cholesky<const N: usize> {
    /// `L` below the diagonal (the unit diagonal is implicit).
    l: [[f64; N]; N],
    /// `1 / Dᵢᵢ`.
    inv_d: [f64; N],
}

impl<const N: usize> Cholesky<N> {
    /// `None` unless `H + μI` is positive definite (every pivot positive and finite).
    fn of(h: &SMatrix<f64, N, N>, mu: f64) -> Option<Self> {
        let mut l = [[0.0; N]; N];
        let mut inv_d = [0.0; N];
        // w[i][j] = L[i][j] D[j]: the products the next pivots need, before the division.
        let mut w = [[0.0; N]; N];
        for j in 0..N {
            let mut pivot = h[(j, j)] + mu;
            for k in 0..j {
                pivot -= w[j][k] * l[j][k];
            }
            if !(pivot > 0.0 && pivot < f64::INFINITY) {
                return None;
            }
            inv_d[j] = 1.0 / pivot;
            for i in j + 1..N {
                let mut v = h[(i, j)];
                for k in 0..j {
                    v -= w[i][k] * l[j][k];
                }
                w[i][j] = v;
                l[i][j] = v * inv_d[j];
            }
        }
        Some(Cholesky { l, inv_d })
    }

    /// `L⁻¹ b` (forward substitution, unit diagonal).
    fn solve_unit_lower(&self, b: &SVector<f64, N>) -> SVector<f64, N> {
        let mut y = *b;
        for i in 0..N {
            for k in 0..i {
                y[i] -= self.l[i][k] * y[k];
            }
        }
        y
    }

    /// `‖R⁻ᵀ p‖` with `R = D^½ Lᵀ`: `‖D^-½ L⁻¹ p‖`.
    fn lower_solve_norm(&self, p: &SVector<f64, N>) -> f64 {
        let y = self.solve_unit_lower(p);
        (0..N).map(|i| y[i] * y[i] * self.inv_d[i]).sum::<f64>().sqrt()
    }

    /// `(L D Lᵀ)⁻¹ b`.
    fn solve(&self, b: &SVector<f64, N>) -> SVector<f64, N> {
        let mut x = self.solve_unit_lower(b);
        for i in 0..N {
            x[i] *= self.inv_d[i];
        }
        for i in (0..N).rev() {
            for k in i + 1..N {
                x[i] -= self.l[k][i] * x[k];
            }
        }
        x
    }
}

/// Hebden's algorithm (Appendix A, steps 1.1-1.6) for a symmetric positive-definite `H`.
///
/// First tries the unconstrained step `H d = −g` (section 4, `μ* = 0`); if `‖d‖ ≥ δ` iterates
/// `μ ← μ + (‖p‖/‖q‖)² (‖p‖ − δ)/δ` (eq. 34) with `RᵀR = H + μI`, `RᵀR p = −g`, `Rᵀ q = p`.
/// Returns `None` when `H + μI` is not positive definite (the caller should not pass such an `H`).
pub fn hebden_step<const N: usize>(h: &SMatrix<f64, N, N>, g: &SVector<f64, N>, delta: f64) -> Option<Step<N>> {
    let mut chol = Cholesky::of(h, 0.0)?;
    let d = -chol.solve(g);
    if d.norm() <= delta {
        return Some(step_with_decrease(h, g, d, 0.0));
    }
    let mut mu = 0.0;
    let mut p = d;
    for _ in 0..MAX_SECULAR_ITERATIONS {
        let pn = p.norm();
        if (pn - delta).abs() <= BOUNDARY_TOLERANCE * delta {
            break;
        }
        // Rᵀ q = p with R the Cholesky factor of H + μI.
        let qn = chol.lower_solve_norm(&p);
        mu += (pn / qn).powi(2) * (pn - delta) / delta;
        mu = mu.max(0.0);
        chol = Cholesky::of(h, mu)?;
        p = -chol.solve(g);
    }
    Some(step_with_decrease(h, g, p, mu))
}

/// Moré-Sorensen's safeguarded iteration for a symmetric, possibly indefinite `H`.
pub fn more_sorensen_step<const N: usize>(h: &SMatrix<f64, N, N>, g: &SVector<f64, N>, delta: f64) -> Step<N> {
    let eig = DMatrix::from_column_slice(N, N, h.as_slice()).symmetric_eigen();
    let lambdas: Vec<f64> = eig.eigenvalues.iter().copied().collect();
    let u = &eig.eigenvectors;
    let gt: Vec<f64> = (0..N)
        .map(|i| u.column(i).iter().zip(g.iter()).map(|(a, b)| a * b).sum())
        .collect();
    let (imin, lmin) = lambdas
        .iter()
        .copied()
        .enumerate()
        .fold((0, f64::INFINITY), |a, b| if b.1 < a.1 { b } else { a });
    let hscale = lambdas
        .iter()
        .fold(0.0f64, |a, l| a.max(l.abs()))
        .max(f64::MIN_POSITIVE);

    // d(μ) = −Σ gᵢ/(λᵢ+μ) uᵢ and its norm, in the eigenbasis.
    let coords = |mu: f64| -> Vec<f64> { (0..N).map(|i| -gt[i] / (lambdas[i] + mu)).collect() };
    let to_vec = |c: &[f64]| -> SVector<f64, N> {
        let mut d = SVector::<f64, N>::zeros();
        for i in 0..N {
            for r in 0..N {
                d[r] += c[i] * u[(r, i)];
            }
        }
        d
    };
    let norm = |c: &[f64]| c.iter().map(|v| v * v).sum::<f64>().sqrt();

    // Interior Newton step when H is positive definite and the step fits.
    if lmin > 1e-14 * hscale {
        let c = coords(0.0);
        if norm(&c) <= delta {
            return step_with_decrease(h, g, to_vec(&c), 0.0);
        }
    }
    let mu_floor = (-lmin).max(0.0);
    // Hard case: g has (almost) no component along the lowest eigenvector and the step at μ = −λ_min
    // (excluding that component) is inside the region: move along the eigenvector to the boundary.
    let gnorm = g.norm();
    if gt[imin].abs() <= 1e-10 * gnorm.max(f64::MIN_POSITIVE) {
        let mut c: Vec<f64> = (0..N)
            .map(|i| {
                if (lambdas[i] - lmin).abs() <= 1e-12 * hscale {
                    0.0
                } else {
                    -gt[i] / (lambdas[i] + mu_floor)
                }
            })
            .collect();
        let n = norm(&c);
        if n <= delta {
            c[imin] = (delta * delta - n * n).max(0.0).sqrt();
            return step_with_decrease(h, g, to_vec(&c), mu_floor);
        }
    }
    // Safeguarded Newton on ψ(μ) = 1/δ − 1/‖d(μ)‖ over (μ_floor, ∞).
    let mut mu_lo = mu_floor;
    let mut mu_hi = gnorm / delta + mu_floor + hscale; // ‖d(μ)‖ ≤ ‖g‖/(μ − μ_floor) < δ here
    let mut mu = if lmin > 0.0 {
        0.0
    } else {
        mu_floor + 1e-8 * hscale.max(1.0)
    };
    for _ in 0..MAX_SECULAR_ITERATIONS {
        if mu <= mu_lo || mu >= mu_hi {
            mu = (mu_lo * mu_hi).sqrt().max(mu_lo + 0.01 * (mu_hi - mu_lo));
        }
        let c = coords(mu);
        let phi = norm(&c);
        if (phi - delta).abs() <= BOUNDARY_TOLERANCE * delta {
            return step_with_decrease(h, g, to_vec(&c), mu);
        }
        if phi > delta {
            mu_lo = mu;
        } else {
            mu_hi = mu;
        }
        // φ'(μ) = −Σ gᵢ²/(λᵢ+μ)³ / φ; Newton on ψ: μ ← μ + (φ/φ')... in Hebden's form (eq. 32).
        let dphi = -(0..N).map(|i| gt[i] * gt[i] / (lambdas[i] + mu).powi(3)).sum::<f64>() / phi;
        mu += phi * (delta - phi) / (dphi * delta);
    }
    let c = coords(mu.max(mu_lo));
    let mut d = to_vec(&c);
    if d.norm() > delta {
        d *= delta / d.norm();
    }
    step_with_decrease(h, g, d, mu)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::Rng;
    use nalgebra::{Matrix4, Vector4};

    fn random_spd(rng: &mut Rng, shift: f64) -> Matrix4<f64> {
        let a = Matrix4::from_fn(|_, _| rng.normal());
        a * a.transpose() + Matrix4::identity() * shift
    }

    /// Checks Theorem 1's conditions (ii)-(iii) for a boundary or interior solution.
    fn check_theorem1(h: &Matrix4<f64>, g: &Vector4<f64>, delta: f64, s: &Step<4>) {
        let residual = (h + Matrix4::identity() * s.mu) * s.d + g;
        assert!(residual.norm() <= 1e-8 * (1.0 + g.norm()), "stationarity {residual}");
        assert!(s.d.norm() <= delta * (1.0 + BOUNDARY_TOLERANCE));
        if s.mu > 0.0 {
            assert!((s.d.norm() - delta).abs() <= BOUNDARY_TOLERANCE * delta);
        }
        assert!(s.predicted_decrease >= 0.0);
    }

    #[test]
    fn hebden_solves_the_subproblem_for_spd_matrices() {
        let mut rng = Rng::new(34);
        for _ in 0..200 {
            let h = random_spd(&mut rng, 1e-3);
            let g = Vector4::from_fn(|_, _| rng.normal());
            let delta = 10f64.powf(rng.uniform_in(-3.0, 1.0));
            let s = hebden_step(&h, &g, delta).unwrap();
            check_theorem1(&h, &g, delta, &s);
            // No feasible step does better than the solution (sampled on the boundary and inside).
            let q = |d: &Vector4<f64>| g.dot(d) + 0.5 * d.dot(&(h * d));
            for _ in 0..20 {
                let v = Vector4::from_fn(|_, _| rng.normal()).normalize() * delta * rng.uniform();
                assert!(q(&v) >= q(&s.d) - 0.03 * s.predicted_decrease.abs() - 1e-12);
            }
        }
    }

    #[test]
    fn more_sorensen_handles_indefinite_and_hard_cases() {
        let mut rng = Rng::new(25);
        for _ in 0..200 {
            let h = random_spd(&mut rng, 0.0) - Matrix4::identity() * rng.uniform_in(0.0, 4.0);
            let g = Vector4::from_fn(|_, _| rng.normal());
            let delta = 10f64.powf(rng.uniform_in(-2.0, 1.0));
            let s = more_sorensen_step(&h, &g, delta);
            check_theorem1(&h, &g, delta, &s);
            let min_eig = h.symmetric_eigenvalues().min();
            assert!(min_eig + s.mu >= -1e-9, "condition (i)");
        }
        // Hard case: H = diag(−1, 1, 2, 3), g ⟂ e₁, large radius: the step must use the e₁ direction.
        let h = Matrix4::from_diagonal(&Vector4::new(-1.0, 1.0, 2.0, 3.0));
        let g = Vector4::new(0.0, 1.0, 1.0, 1.0);
        let s = more_sorensen_step(&h, &g, 5.0);
        assert!((s.d.norm() - 5.0).abs() < 1e-9 && (s.mu - 1.0).abs() < 1e-9 && s.d[0].abs() > 1.0);
    }
}
