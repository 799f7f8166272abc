"""Covariances of triangulated points, lines and quadrics (``covariance`` attributes) against Monte Carlo.

Scenes come from ``test_triangulation`` / ``test_triangulation_quadric`` (numpy, independent of the
library). Each Monte-Carlo case draws N noisy copies of one primitive's observations from their
covariances and solves them as the N tracks of one batch call; errors are expressed in the chart of the
predicted covariance, which is computed from the noise-free observations (so at the truth).

**The test** (``check_monte_carlo``, the same as the Rust test ``triangulation_uncertainty.rs``): with
``Σ = C Cᵀ`` the prediction, the whitened errors ``y = C⁻¹ e`` are i.i.d. N(0, I_k) to first order, so
at 4 standard deviations of each statistic: the mean of ``d² = ‖y‖²`` is ``k ± 4√(2k/N)``; the whitened
empirical covariance about the truth ``W = mean(y yᵀ)`` has diagonal entries ``1 ± 4√(2/N)`` and
off-diagonal entries ``0 ± 4/√N``; the whitened mean (bias) is ``0 ± 4/√N`` per entry. Noise levels keep
the ``O(σ²)`` bias well below the last bound (stated per case).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from triangulation_scenes import cameras, ellipsoid, outlines, project

import pluecker


def check_monte_carlo(name: str, errors: np.ndarray, predicted: np.ndarray) -> None:
    n, k = errors.shape
    y = np.linalg.solve(np.linalg.cholesky(predicted), errors.T).T
    d2 = float(np.mean(np.sum(y * y, axis=1)))
    assert abs(d2 - k) <= 4 * math.sqrt(2 * k / n), f"{name}: mean d² = {d2:.3f}, expected {k}"
    w = y.T @ y / n
    assert np.all(np.abs(np.diag(w) - 1) <= 4 * math.sqrt(2 / n)), f"{name}: W diagonal {np.diag(w)}"
    off = w[~np.eye(k, dtype=bool)]
    assert np.all(np.abs(off) <= 4 / math.sqrt(n)), f"{name}: W off-diagonal\n{w}"
    assert np.all(np.abs(y.mean(axis=0)) <= 4 / math.sqrt(n)), f"{name}: whitened bias {y.mean(axis=0)}"


def anisotropic_covariances(views: int, rng: np.random.Generator) -> np.ndarray:
    """(views, 2, 2) pixel covariances, standard deviations 0.3-0.6 and 0.2-0.3 px along random axes."""
    out = []
    for _ in range(views):
        a = rng.uniform(0, math.pi)
        R = np.array([[math.cos(a), -math.sin(a)], [math.sin(a), math.cos(a)]])
        out.append(R @ np.diag([rng.uniform(0.3, 0.6) ** 2, rng.uniform(0.2, 0.3) ** 2]) @ R.T)
    return np.array(out)


@pytest.mark.parametrize("views, parallax", [(4, 30.0), (2, 1.5)])
def test_point_covariance_matches_monte_carlo(views, parallax):
    """N = 2000 draws. At 1.5° the depth error is about 4 % of the depth (0.6 px at 800 px over 10 units,
    0.026 rad of parallax), so the bias along the ray (about (4 %)² of the depth) is 0.04 depth standard
    deviations, below the bound 4/√N = 0.09."""
    rng = np.random.default_rng(500 + views)
    P = cameras(views, parallax, rng)
    X = rng.uniform(-0.5, 0.5, 3)
    x = project(P, X)
    cov = anisotropic_covariances(views, rng)
    exact = pluecker.triangulate_point(P, x, cov)
    assert exact.covariance is not None and np.linalg.norm(exact.point - X) < 1e-9
    n = 2000
    noise = np.einsum("vij,nvj->nvi", np.linalg.cholesky(cov), rng.normal(size=(n, views, 2)))
    batch = pluecker.triangulate_points(P, x[None] + noise, covariances=np.broadcast_to(cov, (n, views, 2, 2)))
    assert np.all(batch.status == "success")
    check_monte_carlo(f"point, {views} views, {parallax}°", batch.point - X, exact.covariance)


def test_low_parallax_covariance_is_large():
    """The same two cameras (same distances, same pixel covariances) at 1.5° and 30° of parallax: the
    largest standard deviation, along the depth, grows like ``1/tan(parallax/2)`` for a symmetric pair
    (the lateral ones do not change): within a factor 1.5 of ``tan(15°)/tan(0.75°) ≈ 20.5``."""
    cov = anisotropic_covariances(2, np.random.default_rng(7))
    largest = []
    for parallax in (1.5, 30.0):
        P = cameras(2, parallax, np.random.default_rng(8))
        c = pluecker.triangulate_point(P, project(P, np.zeros(3)), cov).covariance
        largest.append(math.sqrt(np.linalg.eigvalsh(c).max()))
    expected = math.tan(math.radians(15)) / math.tan(math.radians(0.75))
    assert expected / 1.5 < largest[0] / largest[1] < expected * 1.5, largest


@pytest.mark.parametrize("method", ["linear", "local", "optimal"])
def test_point_covariance_is_the_same_single_and_batch_and_nan_for_rejected_tracks(method, seed):
    rng = np.random.default_rng(seed)
    P = cameras(3, 20.0, rng)
    x = np.array([project(P, rng.uniform(-1, 1, 3)) + rng.normal(size=(3, 2)) for _ in range(4)])
    x[2, 1] = np.nan
    batch = pluecker.triangulate_points(P, x, options=pluecker.TriangulationOptions(method=method))
    assert batch.covariance.shape == (4, 3, 3)
    for t in (0, 1, 3):
        single = pluecker.triangulate_point(P, x[t], options=pluecker.TriangulationOptions(method=method))
        np.testing.assert_allclose(batch.covariance[t], single.covariance, rtol=1e-9)
        assert np.all(np.linalg.eigvalsh(single.covariance) > 0)
    assert batch.status[2] == "non_finite" and np.all(np.isnan(batch.covariance[2]))
    r = pluecker.triangulate_point(P, x[0], options=pluecker.TriangulationOptions(method=method))
    assert r.to_dict()["covariance"] == r.covariance.tolist()
    # Parallel rays: a point at infinity has no covariance.
    K = np.array([[800.0, 0, 320], [0, 800.0, 240], [0, 0, 1]])
    Pp = np.array([K @ np.hstack([np.eye(3), [[tx], [0.0], [5.0]]]) for tx in (0.0, 1.0)])
    far = pluecker.triangulate_point(Pp, np.array([[300.0, 200.0]] * 2), options=pluecker.TriangulationOptions(method=method))
    assert far.covariance is None


def chart_coordinates(axes: np.ndarray, pivot: np.ndarray, direction: np.ndarray, point: np.ndarray,
                      d: np.ndarray) -> np.ndarray:
    """The chart coordinates (a1, a2, t1, t2) of the line ``point + s d`` in the chart of
    ``LineTriangulation.covariance`` at (``pivot``, ``direction``, ``axes``), computed here exactly."""
    d = d / (direction @ d)
    crossing = point + d * (direction @ (pivot - point))
    return np.concatenate([axes @ d, axes @ (crossing - pivot)])


def test_line_covariance_matches_monte_carlo_and_its_6x6_forms():
    """N = 1000 draws of 4 image segments (endpoint noise 0.5 px, segments 150+ px): their line
    covariances from ``sigma`` are anisotropic (offset and angle, correlated); angular errors stay
    below 1e-2 rad, so the chart is linear to about 1 %."""
    rng = np.random.default_rng(510)
    P = cameras(4, 40.0, rng)
    A, B = np.array([0.6, -0.3, 0.2]), np.array([-0.5, 0.4, -0.3])
    segments = np.stack([project(P, A), project(P, B)], axis=1)
    sigma, n = 0.5, 1000
    exact = pluecker.triangulate_line(P, segments, sigma=sigma, options=pluecker.TriangulationOptions(method="local"))
    cov = exact.covariance
    assert cov is not None and cov.shape == (4, 4)
    noisy = segments[None] + sigma * rng.normal(size=(n, *segments.shape))
    batch = pluecker.triangulate_lines(P, noisy, sigma=sigma, options=pluecker.TriangulationOptions(method="local"))
    assert np.all(batch.status == "success")
    errors = np.array([chart_coordinates(exact.chart_axes, exact.point, exact.direction, p, d)
                       for p, d in zip(batch.point, batch.direction)])
    check_monte_carlo("line, 4 views", errors, cov)
    # The batch carries the same covariance and axes as the single call.
    np.testing.assert_allclose(batch.covariance[0], pluecker.triangulate_line(P, noisy[0], sigma=sigma,
                                                                              options=pluecker.TriangulationOptions(method="local")).covariance, rtol=1e-9)
    assert batch.chart_axes.shape == (n, 2, 3) and batch.covariance.shape == (n, 4, 4)
    # 6x6 forms: rank 4; the Plücker one is orthogonal to the unit coordinates; the point closest to the
    # origin (full-rank 3x3 block when that point is not the origin) passes the same test.
    pl, pd = exact.plucker_covariance(), exact.point_direction_covariance()
    for c in (pl, pd):
        assert np.linalg.matrix_rank(c, tol=1e-9 * np.linalg.norm(c)) == 4
    assert np.linalg.norm(pl @ exact.plucker) < 1e-9 * np.linalg.norm(pl)
    check_monte_carlo("closest point", batch.point - exact.point, pd[:3, :3])
    d = exact.to_dict()
    assert d["covariance"] == cov.tolist() and d["chart_axes"] == exact.chart_axes.tolist()


def test_quadric_covariance_is_the_same_single_and_batch_and_has_its_chart():
    rng = np.random.default_rng(520)
    P = cameras(4, 60.0, rng)
    centre, axes, semi, dual = ellipsoid(rng)
    conics = outlines(P, dual)
    r = pluecker.triangulate_quadric(P, conics, options=pluecker.TriangulationOptions(method="local"))
    cov = r.covariance
    assert cov is not None and cov.shape == (9, 9)
    np.testing.assert_allclose(cov, cov.T)
    assert np.all(np.linalg.eigvalsh(cov) > 0)
    batch = pluecker.triangulate_quadrics(P, np.stack([conics, conics]), options=pluecker.TriangulationOptions(method="local"))
    np.testing.assert_allclose(batch.covariance[1], cov, rtol=1e-9)
    assert r.to_dict()["covariance"] == cov.tolist()
    # Unit residual covariances scaled by s² scale the covariance by s² (the given covariances carry it).
    scaled = pluecker.triangulate_quadric(P, conics, np.broadcast_to(4.0 * np.eye(5), (4, 5, 5)), options=pluecker.TriangulationOptions(method="local"))
    np.testing.assert_allclose(scaled.covariance, 4.0 * cov, rtol=1e-6)
