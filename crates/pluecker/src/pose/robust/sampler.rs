//! Minimal samples of three correspondences drawn from points and lines together, and the adaptive
//! number of samples.
//!
//! A sample is uniform over the 3-subsets of all correspondences whose *mix* (`k` points and `3 − k`
//! lines) has a minimal solver in [`crate::pose::minimal::solve`]: the mix is drawn with probability
//! proportional to `C(n_p, k) C(n_l, 3 − k)`, then `k` distinct points and `3 − k` distinct lines
//! uniformly. With every mix solvable this is uniform sampling of the combined set; a mix without a
//! solver is never drawn (it would cost a draw and give no hypothesis).
//!
//! Which mixes are solvable is found once per process by a probe: each mix is solved on a fixed
//! well-conditioned noise-free instance, and the mix counts when the true pose is among the answers.
//! Thus solvers for lines are used as soon as they exist, and the stopping rule never counts on a
//! solver that does not.
//!
//! **Stopping rule.** With inlier fractions `ε_p` (points) and `ε_l` (lines) of the best model, a sample
//! of mix `k` is all-inlier with probability `ε_p^k ε_l^(3−k)` (the product of per-type fractions,
//! i.e. drawing with replacement), so a sample is all-inlier with probability
//! `P = Σ_k w_k ε_p^k ε_l^(3−k) / Σ_k w_k` over the drawable mixes (`w_k = C(n_p, k) C(n_l, 3 − k)`).
//! After `N = ⌈log(1 − confidence) / log(1 − P)⌉` samples the probability of never having drawn an
//! all-inlier sample is below `1 − confidence` (Fischler & Bolles 1981; Hartley & Zisserman §4.7.1).
//! With the sequential test of [`super::sprt`], the hypothesis of an all-inlier sample is kept with
//! probability at least `1 − αᵢ`, `αᵢ = 1 / Aᵢ` for the test of threshold `Aᵢ`, so the loop stops
//! when `Σᵢ kᵢ ln(1 − P (1 − αᵢ)) ≤ ln(1 − confidence)` over the `kᵢ` samples verified with each test
//! (Chum & Matas 2008, eq. 9; `αᵢ = 0` for a sample scored without the test).
//!
//! **Cap.** The same formula at the fractions `ε_p = ε_l = min_inlier_ratio` caps the loop whatever the
//! best model (COLMAP's `min_inlier_ratio`): after that many samples, a model with at least that
//! fraction of inliers would have been found with probability `confidence`. Without it, data with no
//! model at all (every correspondence an outlier) would run to `max_iterations`.

use super::super::minimal::{solve, Feature};
use crate::camera_pose::Pose;
use crate::geometry::quaternion::{exp_so3, rotation_distance};
use crate::rng::Rng;
use nalgebra::Vector3;
use std::sync::OnceLock;

/// `solvable()[k]`: whether a sample of `k` points and `3 − k` lines has a minimal solver.
pub(crate) fn solvable() -> &'static [bool; 4] {
    static SOLVABLE: OnceLock<[bool; 4]> = OnceLock::new();
    SOLVABLE.get_or_init(|| std::array::from_fn(probe))
}

/// Solves the fixed instance of mix `k` (points first) and reports whether the truth is found.
fn probe(k: usize) -> bool {
    let rotation = exp_so3(&Vector3::new(0.3, -0.2, 0.4));
    let translation = Vector3::new(0.1, -0.2, 5.0);
    let points = [
        Vector3::new(0.5, 0.3, 0.2),
        Vector3::new(-0.4, 0.6, -0.3),
        Vector3::new(0.2, -0.5, 0.4),
    ];
    let lines = [
        [Vector3::new(-0.6, -0.1, 0.3), Vector3::new(0.7, 0.4, -0.2)],
        [Vector3::new(0.1, -0.7, -0.4), Vector3::new(-0.2, 0.8, 0.5)],
        [Vector3::new(-0.5, 0.5, -0.6), Vector3::new(0.4, -0.3, 0.7)],
    ];
    let cam = |x: &Vector3<f64>| rotation * x + translation;
    let sample: [Feature; 3] = std::array::from_fn(|i| {
        if i < k {
            Feature::Point {
                bearing: cam(&points[i]),
                point: points[i],
            }
        } else {
            let [a, b] = lines[i];
            Feature::Line {
                normal: cam(&a).cross(&cam(&b)).normalize(),
                endpoints: [a, b],
            }
        }
    });
    solve(&sample).iter().any(
        |Pose {
             rotation: r,
             translation: t,
         }| rotation_distance(r, &rotation) < 1e-6 && (t - translation).norm() < 1e-6 * translation.norm(),
    )
}

/// Draws samples and computes how many are needed.
#[derive(Debug, Clone)]
pub(crate) struct Sampler {
    n_points: usize,
    n_lines: usize,
    /// Drawable mixes: `(k, w_k)` with `k` the number of points.
    mixes: Vec<(usize, f64)>,
    total_weight: f64,
}

/// `C(n, k)` for `k ≤ 3`, as a float.
fn choose(n: usize, k: usize) -> f64 {
    if k > n {
        return 0.0;
    }
    (0..k).map(|i| (n - i) as f64).product::<f64>() / (1..=k).map(|i| i as f64).product::<f64>()
}

impl Sampler {
    /// A sampler over `n_points` points and `n_lines` lines using the mixes marked in `solvable`.
    pub fn new(n_points: usize, n_lines: usize, solvable: &[bool; 4]) -> Sampler {
        let mixes: Vec<(usize, f64)> = (0..4)
            .filter(|&k| solvable[k])
            .map(|k| (k, choose(n_points, k) * choose(n_lines, 3 - k)))
            .filter(|&(_, w)| w > 0.0)
            .collect();
        let total_weight = mixes.iter().map(|m| m.1).sum();
        Sampler {
            n_points,
            n_lines,
            mixes,
            total_weight,
        }
    }

    /// False when no mix can be drawn (e.g. lines only, and no solver for three lines).
    pub fn can_draw(&self) -> bool {
        !self.mixes.is_empty()
    }

    /// A sample of three distinct feature indices (points `0..n_p`, lines `n_p..n_p + n_l`).
    /// Requires [`Sampler::can_draw`].
    pub fn draw(&self, rng: &mut Rng) -> [usize; 3] {
        let mut pick = rng.uniform() * self.total_weight;
        let mut k = self.mixes[self.mixes.len() - 1].0;
        for &(mix, w) in &self.mixes {
            if pick < w {
                k = mix;
                break;
            }
            pick -= w;
        }
        let mut sample = [0; 3];
        for i in 0..3 {
            let (offset, n) = if i < k {
                (0, self.n_points)
            } else {
                (self.n_points, self.n_lines)
            };
            // Rejection of repeats: at most a few draws, since a mix is only drawn when n ≥ its count.
            sample[i] = loop {
                let candidate = offset + rng.below(n);
                if !sample[..i].contains(&candidate) {
                    break candidate;
                }
            };
        }
        sample
    }

    /// The probability that a sample is all-inlier given the inlier fractions (see the module docs).
    pub fn all_inlier_probability(&self, point_fraction: f64, line_fraction: f64) -> f64 {
        if self.mixes.is_empty() {
            return 0.0;
        }
        let sum: f64 = self
            .mixes
            .iter()
            .map(|&(k, w)| w * point_fraction.powi(k as i32) * line_fraction.powi(3 - k as i32))
            .sum();
        (sum / self.total_weight).clamp(0.0, 1.0)
    }

    /// `N = ⌈log(1 − confidence) / log(1 − P (1 − α))⌉` samples for the given inlier fractions, with
    /// `α` a bound on the probability that the hypothesis of an all-inlier sample is rejected by the
    /// sequential test (`1 / A` of [`super::sprt`]; 0 without it); `usize::MAX` when
    /// `P (1 − α) = 0`, 1 when it is 1.
    #[cfg(test)]
    pub fn required_samples(&self, point_fraction: f64, line_fraction: f64, confidence: f64, rejection: f64) -> usize {
        self.required_samples_after(point_fraction, line_fraction, confidence, &[], rejection)
    }

    /// The number of samples after which `Σᵢ kᵢ ln(1 − P (1 − αᵢ)) ≤ ln(1 − confidence)` (see the
    /// module documentation), given the samples drawn so far as runs `(αᵢ, kᵢ)` in `history` and
    /// `rejection` = `α` of those still to come; at least the samples drawn. `usize::MAX` if never.
    /// The bound the sampling loop ([`crate::consensus`]) stops on, at the `P` of these fractions.
    #[cfg(test)]
    pub fn required_samples_after(
        &self,
        point_fraction: f64,
        line_fraction: f64,
        confidence: f64,
        history: &[(f64, usize)],
        rejection: f64,
    ) -> usize {
        let p = self.all_inlier_probability(point_fraction, line_fraction);
        crate::consensus::required_samples(p, confidence, history, rejection)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_point_solver_is_found_by_the_probe() {
        assert!(solvable()[3], "P3P must solve its probe instance");
    }

    #[test]
    fn samples_are_distinct_cover_every_mix_in_proportion_and_respect_solvability() {
        let mut rng = Rng::new(1);
        let sampler = Sampler::new(10, 5, &[true; 4]);
        let mut mix_counts = [0usize; 4];
        let draws = 40_000;
        for _ in 0..draws {
            let s = sampler.draw(&mut rng);
            assert!(s[0] != s[1] && s[0] != s[2] && s[1] != s[2] && s.iter().all(|&i| i < 15));
            mix_counts[s.iter().filter(|&&i| i < 10).count()] += 1;
        }
        // Uniform 3-subsets of 15: C(10,k) C(5,3-k) / C(15,3); binomial std √(N p (1-p)), 5 std.
        for k in 0..4 {
            let p = choose(10, k) * choose(5, 3 - k) / choose(15, 3);
            let expected = draws as f64 * p;
            let std = (draws as f64 * p * (1.0 - p)).sqrt();
            assert!(
                (mix_counts[k] as f64 - expected).abs() < 5.0 * std,
                "mix {k}: {mix_counts:?}"
            );
        }
        let points_only = Sampler::new(10, 5, &[false, false, false, true]);
        for _ in 0..1000 {
            assert!(points_only.draw(&mut rng).iter().all(|&i| i < 10));
        }
        assert!(!Sampler::new(0, 5, &[false, false, false, true]).can_draw());
        assert!(!Sampler::new(2, 0, &[true; 4]).can_draw());
    }

    #[test]
    fn required_samples_follow_the_closed_form() {
        let points_only = Sampler::new(100, 30, &[false, false, false, true]);
        // ε = 0.5 for points: P = 1/8, N = ⌈ln(1e-4) / ln(7/8)⌉ = 69.
        assert_eq!(points_only.required_samples(0.5, 0.0, 0.9999, 0.0), 69);
        assert_eq!(points_only.required_samples(0.0, 1.0, 0.9999, 0.0), usize::MAX);
        assert_eq!(points_only.required_samples(1.0, 0.0, 0.9999, 0.0), 1);
        // A sequential test that may reject a good hypothesis with probability 1/20:
        // N = ⌈ln(1e-4) / ln(1 − 0.95 / 8)⌉ = 73.
        assert_eq!(points_only.required_samples(0.5, 0.0, 0.9999, 0.05), 73);
        // The cap of min_inlier_ratio = 0.1: ⌈ln(1e-4) / ln(1 − 1e-3)⌉ = 9206.
        assert_eq!(points_only.required_samples(0.1, 0.1, 0.9999, 0.0), 9206);
        // 40 samples without the test, then a test with α = 1/20: the first 40 count in full,
        // 40 + ⌈(ln(1e-4) − 40 ln(7/8)) / ln(1 − 0.95 / 8)⌉ = 40 + 31 = 71.
        assert_eq!(
            points_only.required_samples_after(0.5, 0.0, 0.9999, &[(0.0, 40)], 0.05),
            71
        );
        assert_eq!(
            points_only.required_samples_after(0.5, 0.0, 0.9999, &[(0.0, 40), (0.05, 40)], 0.05),
            80
        );
        // All mixes and equal fractions: P = ε³ whatever the counts.
        let all = Sampler::new(100, 30, &[true; 4]);
        assert!((all.all_inlier_probability(0.4, 0.4) - 0.064).abs() < 1e-12);
        // Lines all outliers: only the three-point mix can succeed, with weight C(100,3)/C(130,3).
        let expected = choose(100, 3) / choose(130, 3) * 0.125;
        assert!((all.all_inlier_probability(0.5, 0.0) - expected).abs() < 1e-12);
    }
}
