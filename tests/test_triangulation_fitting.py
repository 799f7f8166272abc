"""``pluecker.fit_line``, ``fit_conic`` and ``fitting_residual_samples`` (Josephson & Kahl 2008, section 3.1)."""

from __future__ import annotations

import numpy as np
import pytest

import pluecker


def ellipse_points(centre, semi_axes, angle, n=63, phase=0.0):
    t = phase + np.linspace(0.0, 2 * np.pi, n, endpoint=False)
    c, s = np.cos(angle), np.sin(angle)
    local = np.c_[semi_axes[0] * np.cos(t), semi_axes[1] * np.sin(t)]
    return local @ np.array([[c, s], [-s, c]]) + centre


def test_exact_points_give_the_line(seed):
    rng = np.random.default_rng(seed)
    for _ in range(20):
        a, b = rng.uniform(0, 1000, (2, 2))
        pts = a + np.linspace(0, 1, 21)[:, None] * (b - a)
        fit = pluecker.fit_line(pts, sigma=1.0)
        line = fit.line
        assert np.hypot(line[0], line[1]) == pytest.approx(1.0, abs=1e-12)
        assert line[2] <= 0.0
        # Every point on the line, to round-off of coordinates ~1e3.
        assert np.max(np.abs(pts @ line[:2] + line[2])) < 1e-9
        assert fit.rms_distance < 1e-9
        cov = fit.covariance
        np.testing.assert_allclose(cov, cov.T)
        assert np.all(np.linalg.eigvalsh(cov) > 0)


def test_exact_points_give_the_ellipse(seed):
    rng = np.random.default_rng(seed)
    for _ in range(20):
        centre = rng.uniform(300, 700, 2)
        semi = np.sort(rng.uniform(60, 240, 2))[::-1]
        angle = rng.uniform(0, np.pi)
        pts = ellipse_points(centre, semi, angle)
        fit = pluecker.fit_conic(pts, sigma=1.0)
        np.testing.assert_allclose(fit.centre, centre, atol=1e-6)
        np.testing.assert_allclose(fit.semi_axes, semi, rtol=1e-8)
        # The point conic vanishes on every point (homogeneous, unit Frobenius norm).
        h = np.c_[pts, np.ones(len(pts))]
        assert np.max(np.abs(np.einsum("ni,ij,nj->n", h, fit.conic, h))) < 1e-9
        assert np.linalg.norm(fit.conic) == pytest.approx(1.0)
        np.testing.assert_allclose(fit.axes.T @ fit.axes, np.eye(2), atol=1e-12)
        assert np.all(np.linalg.eigvalsh(fit.covariance) > 0)


def test_predicted_covariances_whiten_the_residuals(seed):
    """Figures 1-2: residuals whitened by the predicted covariance are standard normal to first order.
    With 4000 draws a variance is estimated to ±2.2 % (one standard error); 10 % (line) and 15 % (conic,
    whose first-order prediction is coarser for small ellipses) are ≥ 4.5 standard errors."""
    s = pluecker.fitting_residual_samples(4000, size=1000.0, sigma=1.0, seed=seed % 2**32)
    assert s["line"].shape == (4000, 2) and s["conic"].shape == (4000, 5)
    for key, tolerance in (("line_whitened", 0.10), ("conic_whitened", 0.15)):
        w = s[key]
        assert np.all(np.isfinite(w))
        cov = np.cov(w.T)
        assert np.max(np.abs(cov - np.eye(w.shape[1]))) < tolerance, (key, cov.round(3))
        # Means within 5 standard errors of 0.
        assert np.max(np.abs(w.mean(axis=0))) < 5 / np.sqrt(len(w)), key
    # The raw line residuals are in pixels: their spread is of the order of sigma, not 0 and not 100.
    assert 0.05 < np.std(s["line"][:, 1]) < 20


def test_residual_samples_are_seeded(seed):
    a = pluecker.fitting_residual_samples(50, seed=7)
    b = pluecker.fitting_residual_samples(50, seed=7)
    c = pluecker.fitting_residual_samples(50, seed=8)
    np.testing.assert_array_equal(a["conic"], b["conic"])
    assert not np.array_equal(a["conic"], c["conic"])


@pytest.mark.parametrize(
    "fn, points, error, message",
    [
        (pluecker.fit_line, [[1.0, 2.0]], pluecker.TooFewCorrespondencesError, "at least 2 points"),
        (pluecker.fit_line, [[1.0, 2.0], [1.0, 2.0]], pluecker.DegenerateConfigurationError, "coincide"),
        (pluecker.fit_line, [[1.0, 2.0], [np.nan, 2.0]], pluecker.NonFiniteError, "row 1"),
        (pluecker.fit_line, [[1.0, 2.0, 3.0]], pluecker.ShapeError, "points: expected shape (N, 2)"),
        (pluecker.fit_conic, [[0.0, 0.0]] * 4, pluecker.TooFewCorrespondencesError, "at least 5 points"),
        (pluecker.fit_conic, [[k, 2.0 * k] for k in range(10)], pluecker.DegenerateConfigurationError, "lie on a line"),
        # A hyperbola 100 px across: far from a line at σ = 1 px, and no ellipse.
        (pluecker.fit_conic, [[10.0 * k, 100.0 / k] for k in range(1, 12)], pluecker.DegenerateConfigurationError, "not lie on a real ellipse"),
    ],
    ids=["line-one-point", "line-coincident", "line-nan", "line-shape", "conic-four", "conic-collinear",
         "conic-hyperbola"],
)
def test_bad_points_raise(fn, points, error, message):
    with pytest.raises(error, match=message.replace("(", r"\(").replace(")", r"\)")):
        fn(np.array(points, dtype=float))


@pytest.mark.parametrize("fn", [pluecker.fit_line, pluecker.fit_conic])
@pytest.mark.parametrize("sigma", [0.0, -1.0, np.inf])
def test_bad_sigma_raises(fn, sigma):
    pts = ellipse_points((100.0, 100.0), (50.0, 30.0), 0.3, n=12)
    with pytest.raises(pluecker.InvalidOptionError, match="sigma"):
        fn(pts, sigma=sigma)


def test_bad_sample_arguments_raise():
    with pytest.raises(pluecker.InvalidOptionError, match="draws"):
        pluecker.fitting_residual_samples(0)
    with pytest.raises(pluecker.InvalidOptionError, match="size"):
        pluecker.fitting_residual_samples(10, size=-5.0)
