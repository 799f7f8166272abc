"""``PoseResult.covariance``: a Monte-Carlo check of the predicted pose covariance.

The test. For N noisy draws of one scene (1 px Gaussian noise on every image point and segment
endpoint), e is the refined pose's error in the covariance's coordinates (``ω = log(R R₀ᵀ)``, then
``t − t₀``) and Σ the result's own covariance with the true σ given. To first order e ~ N(0, Σ), so

- ``d² = eᵀ Σ⁻¹ e`` is χ²₆: its mean over N draws is 6 with standard deviation √(2·6/N);
- per axis k, ``Σ e_k² / Σ Σ_kk`` is χ²_N / N: mean 1, standard deviation √(2/N);

and both must hold within 4 standard deviations (N = 500: ±0.62 and ±0.25). With σ estimated,
``σ̂² = Σ r² / (m − 6)`` is σ² χ²_{m−6} / (m − 6): its mean over the draws must be within 4 standard
deviations √(2 / ((m − 6) N)) of σ².
"""

from __future__ import annotations

import numpy as np
import pytest

import pluecker
from test_robust_pose import random_segments, tangent_error

DRAWS = 500


def monte_carlo(kind: str, n_points: int, n_lines: int, scene_seed: int, outlier_ratio: float = 0.0, **kwargs):
    """Errors, covariances and σ̂ of ``DRAWS`` noisy draws (outliers at a fixed random set of rows)."""
    scene = pluecker.random_scene(kind, n_points, n_lines, seed=scene_seed)
    rng = np.random.default_rng(scene_seed)
    bad_p = rng.choice(n_points, int(outlier_ratio * n_points), replace=False)
    bad_l = rng.choice(n_lines, int(outlier_ratio * n_lines), replace=False)
    errors, covariances, sigmas = [], [], []
    for draw in range(DRAWS):
        p2 = scene["points2d"] + rng.normal(size=(n_points, 2))
        l2 = scene["lines2d"] + rng.normal(size=(n_lines, 2, 2))
        p2[bad_p] = rng.uniform([0, 0], [640, 480], size=(len(bad_p), 2))
        if len(bad_l):
            l2[bad_l] = random_segments(rng, len(bad_l))
        r = pluecker.estimate_pose(scene["camera"], p2, scene["points3d"], l2, scene["lines3d"], **kwargs)
        assert r.status == "success", f"seed={scene_seed} draw={draw}: {r}"
        errors.append(tangent_error(r, scene))
        covariances.append(r.covariance)
        sigmas.append(r.details.sigma_px)
    return np.array(errors), np.array(covariances), np.array(sigmas)


def assert_matches(errors: np.ndarray, covariances: np.ndarray, label: str) -> None:
    n = len(errors)
    d2 = np.einsum("ni,ni->n", errors, np.linalg.solve(covariances, errors[..., None])[..., 0])
    assert abs(d2.mean() - 6.0) < 4 * np.sqrt(12.0 / n), f"{label}: mean d² = {d2.mean():.3f}"
    ratio = (errors**2).sum(axis=0) / np.diagonal(covariances, axis1=1, axis2=2).sum(axis=0)
    assert np.all(np.abs(ratio - 1.0) < 4 * np.sqrt(2.0 / n)), f"{label}: variance ratios {ratio}"


def test_covariance_matches_monte_carlo_in_a_general_scene(seed):
    errors, cov, _ = monte_carlo("general", 30, 10, seed % 1000, options=pluecker.PoseOptions(sigma_px=1.0))
    assert_matches(errors, cov, f"general seed={seed % 1000}")


def test_covariance_matches_monte_carlo_at_low_parallax_where_it_is_large(seed):
    """Far, narrow field of view (a 10-unit box at depth 50, ±80 px): weak perspective, where the
    rotation about the image axes trades off against the depth and the covariance is large."""
    s = seed % 1000
    errors, cov, _ = monte_carlo("far", 30, 10, s, options=pluecker.PoseOptions(sigma_px=1.0))
    assert_matches(errors, cov, f"far seed={s}")
    _, cov_general, _ = monte_carlo("general", 30, 10, s, options=pluecker.PoseOptions(sigma_px=1.0))
    rot = lambda c: np.trace(c[:, :3, :3], axis1=1, axis2=2).mean()  # noqa: E731
    assert rot(cov) > 10 * rot(cov_general), (rot(cov), rot(cov_general))


def test_estimated_sigma_is_close_to_the_true_one(seed):
    s = seed % 1000
    errors, cov, sigmas = monte_carlo("general", 30, 10, s)
    m = 2 * (30 + 10)
    assert abs(np.mean(sigmas**2) - 1.0) < 4 * np.sqrt(2.0 / ((m - 6) * DRAWS)), np.mean(sigmas**2)


def test_robust_covariance_uses_the_inliers(seed):
    s = seed % 1000
    errors, cov, _ = monte_carlo("general", 60, 15, s, outlier_ratio=0.3, options=pluecker.PoseOptions(sigma_px=1.0, ransac=pluecker.RansacOptions(seed=s)))
    assert_matches(errors, cov, f"robust seed={s}")


def test_sources_and_the_cases_without_a_covariance(seed):
    scene = pluecker.random_scene("general", 3, 0, seed=seed % 1000)
    args = (scene["camera"], scene["points2d"], scene["points3d"])
    # Three points: m = 6 residuals, nothing left to estimate σ from.
    r = pluecker.estimate_pose(*args)
    assert (r.covariance, r.details.covariance_source, r.details.sigma_px) == (None, None, None)
    given = pluecker.estimate_pose(*args, options=pluecker.PoseOptions(sigma_px=0.5))
    assert given.details.covariance_source == "given" and given.details.sigma_px == 0.5 and given.covariance.shape == (6, 6)
    # Same as the standalone function at the returned pose.
    expected = pluecker.pose_covariance(scene["camera"], given.pose.rotation, given.pose.translation, scene["points2d"], scene["points3d"],
                                        sigma_px=0.5)
    np.testing.assert_allclose(given.covariance, expected, rtol=1e-6, atol=1e-12)
