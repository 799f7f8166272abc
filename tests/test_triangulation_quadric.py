"""``pluecker.triangulate_quadric``: recovery of ellipsoids and discs, result fields, bad input.

Scenes: an ellipsoid (or the synthetic discs of the reproduction, ``disc_scene``) seen by cameras of
``test_triangulation.cameras``; exact image conics are the outlines ``(P L P^T)^-1`` of the dual quadric.
"""

from __future__ import annotations

import numpy as np
import pytest
from test_triangulation import cameras

import pluecker
from pluecker.experiments.josephson_kahl_2008.conics import disc_scene, ellipse_points

METHODS = pluecker.TRIANGULATION_METHODS


def ellipsoid(rng):
    """A random ellipsoid near the origin: centre, axes (columns), semi-axes, dual quadric (L44 = -1)."""
    centre = rng.uniform(-0.3, 0.3, 3)
    axes, _ = np.linalg.qr(rng.normal(size=(3, 3)))
    semi = np.sort(rng.uniform(0.3, 1.0, 3))[::-1]
    H = np.eye(4)
    H[:3, :3], H[:3, 3] = axes, centre
    return centre, axes, semi, H @ np.diag([*(semi**2), -1.0]) @ H.T


def outlines(P, dual):
    return np.array([np.linalg.inv(p @ dual @ p.T) for p in P])


@pytest.mark.parametrize("method", METHODS)
def test_exact_outlines_give_the_ellipsoid(method, seed):
    rng = np.random.default_rng(seed)
    P = cameras(4, 60.0, rng)
    centre, axes, semi, dual = ellipsoid(rng)
    r = pluecker.triangulate_quadric(P, outlines(P, dual), method=method)
    assert r.method == method and r.status == "success", f"seed={seed} {r}"
    np.testing.assert_allclose(r.centre, centre, atol=1e-6, err_msg=f"seed={seed}")
    np.testing.assert_allclose(r.semi_axes, semi, atol=1e-6)
    np.testing.assert_allclose(r.Q, dual, atol=1e-6)
    assert r.Q[3, 3] == pytest.approx(-1.0)
    # The primal is the inverse of the dual; axes are orthonormal columns.
    np.testing.assert_allclose(r.primal @ r.Q, np.eye(4), atol=1e-6)
    np.testing.assert_allclose(r.axes.T @ r.axes, np.eye(3), atol=1e-9)
    np.testing.assert_allclose(r.axes @ np.diag(r.semi_axes**2) @ r.axes.T, dual[:3, :3] + np.outer(centre, centre),
                               atol=1e-6)
    assert r.cost < 1e-10


def test_fitted_disc_conics_give_a_flat_quadric_and_ordered_costs(seed):
    scene = disc_scene(seed % 1000)
    results = {m: pluecker.triangulate_quadric(scene.cameras, scene.conics, scene.covariances, method=m)
               for m in METHODS}
    truth_centre = scene.dual[:3, 3] / scene.dual[3, 3]
    for m, r in results.items():
        # 1 px noise on 63 points per view, 5 views, a disc ~2 units across 6-10 units away: its centre is
        # known to ~1e-3 units; 0.05 is a wide margin that still catches a wrong quadric.
        assert np.linalg.norm(r.centre - truth_centre) < 0.05, (m, r)
        assert r.semi_axes[2] < 0.05 * r.semi_axes[0], (m, r.semi_axes)
    opt, local, linear = results["optimal"], results["local"], results["linear"]
    assert local.cost <= linear.cost * (1 + 1e-9)
    assert opt.cost <= local.cost * (1 + 1e-9)
    assert opt.lower_bound <= opt.cost * (1 + 1e-12)
    assert opt.certified == (opt.status == "success" and opt.relative_gap <= 1e-3)
    # A flat quadric has no primal form (or an ill-conditioned one).
    d = results["local"].to_dict()
    assert {"Q", "primal", "centre", "axes", "semi_axes", "cost", "certified"} <= set(d)
    assert "QuadricTriangulation(" in repr(results["local"])


def test_ellipse_points_lie_on_the_conic(seed):
    rng = np.random.default_rng(seed)
    P = cameras(3, 30.0, rng)
    _, _, _, dual = ellipsoid(rng)
    conic = outlines(P, dual)[0]
    pts = ellipse_points(conic, 50)
    h = np.c_[pts, np.ones(50)]
    assert np.max(np.abs(np.einsum("ni,ij,nj->n", h, conic / np.linalg.norm(conic), h))) < 1e-9


@pytest.mark.parametrize(
    "change, error, message",
    [
        (lambda P, c: (P[:2], c[:2], None), pluecker.TooFewCorrespondencesError, "3"),
        (lambda P, c: (P, c[:3], None), pluecker.ShapeError, "conics: expected 4 rows"),
        (lambda P, c: (P, c[:, :2], None), pluecker.ShapeError, "conics: expected shape (n, 3, 3)"),
        (lambda P, c: (P, np.where(np.arange(36).reshape(4, 3, 3) == 20, np.nan, c), None), pluecker.NonFiniteError,
         "conics: non-finite value (NaN or inf) in row 2"),
        (lambda P, c: (P, np.array([c[0], c[1], np.diag([1.0, -1.0, -1.0]), c[3]]), None),
         pluecker.DegenerateConfigurationError, "conics[2] is not a real ellipse"),
        (lambda P, c: (P, c, np.eye(5)[None].repeat(3, 0)), pluecker.ShapeError, "cov: expected 4 rows"),
        (lambda P, c: (P, c, -np.eye(5)[None].repeat(4, 0)), pluecker.DegenerateConfigurationError,
         "cov[0] is not positive definite"),
    ],
    ids=["two-views", "count", "shape", "nan", "hyperbola", "cov-count", "cov-negative"],
)
def test_bad_input(change, error, message, seed):
    rng = np.random.default_rng(seed)
    P = cameras(4, 60.0, rng)
    _, _, _, dual = ellipsoid(rng)
    args = change(P, outlines(P, dual))
    with pytest.raises(error) as info:
        pluecker.triangulate_quadric(*args)
    assert message in str(info.value)
