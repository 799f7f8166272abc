"""Quadrics: ``pluecker.triangulate_quadric`` (an ellipsoid from its outline conics, Josephson & Kahl
2008, section 2.3) and ``pluecker.triangulate_quadrics`` (the batch equals single calls, with shared
cameras or cameras per track, and visibility)."""

from __future__ import annotations

import numpy as np
import pytest
from triangulation_scenes import METHODS, NODES, assert_same_report, cameras, ellipsoid, outlines, random_visibility

import pluecker
from pluecker.experiments.josephson_kahl_2008.conics import disc_scene, ellipse_points


@pytest.mark.parametrize("method", METHODS)
def test_exact_outlines_give_the_ellipsoid(method, seed):
    rng = np.random.default_rng(seed)
    P = cameras(4, 60.0, rng)
    centre, axes, semi, dual = ellipsoid(rng)
    r = pluecker.triangulate_quadric(P, outlines(P, dual), options=pluecker.TriangulationOptions(method=method))
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
    results = {m: pluecker.triangulate_quadric(scene.cameras, scene.conics, scene.covariances, options=pluecker.TriangulationOptions(method=m))
               for m in METHODS}
    truth_centre = scene.dual[:3, 3] / scene.dual[3, 3]
    for m, r in results.items():
        # 1 px noise on 63 points per view, 5 views, a disc ~2 units across 6-10 units away: its centre is
        # known to ~1e-3 units; 0.05 is a wide margin that still catches a wrong quadric.
        assert np.linalg.norm(r.centre - truth_centre) < 0.05, (m, r)
        assert r.semi_axes[2] < 0.05 * r.semi_axes[0], (m, r.semi_axes)
    opt, local, linear = results["optimal"], results["local"], results["linear"]
    # No search, no certificate: None, not a placeholder bound.
    assert local.certificate is None and linear.certificate is None and not local.certified
    assert local.to_dict()["certificate"] is None
    assert local.cost <= linear.cost * (1 + 1e-9)
    assert opt.cost <= local.cost * (1 + 1e-9)
    # The raw bound against numpy's cost (eq. 19: the image dual conics in the observed ellipse's frame,
    # section 3.1, Mahalanobis norm) of the answer and of the other methods' answers, and the gap
    # recomputed from them; numpy's cost agrees with the library's to 1e-7.
    cost = {m: quadric_cost(scene.cameras, scene.conics, scene.covariances, r.Q) for m, r in results.items()}
    assert cost["optimal"] == pytest.approx(opt.cost, rel=1e-7)
    raw = opt.certificate.raw_lower_bound
    assert raw <= cost["optimal"] * (1 + 1e-7) and raw <= min(cost.values()) * (1 + 1e-7), (raw, cost)
    assert opt.certified == (opt.status == "success")
    if opt.certified:
        assert (cost["optimal"] - min(raw, cost["optimal"])) / cost["optimal"] <= 1e-3 * (1 + 1e-4), (raw, cost)
    # A flat quadric has no primal form (or an ill-conditioned one).
    d = results["local"].to_dict()
    assert {"Q", "primal", "centre", "axes", "semi_axes", "cost", "certified"} <= set(d)
    assert "QuadricTriangulation(" in repr(results["local"])


def quadric_cost(P, conics, cov, Q) -> float:
    """Eq. 19 in numpy: per view the image dual conic ``P Q Pᵀ`` and the observed one ``c⁻¹`` moved to the
    observed ellipse's centre, ``v(e) = (e₁₁, e₁₂, e₂₂, e₁₃, e₂₃)/e₃₃`` of each, the Mahalanobis norm of
    the difference."""
    total = 0.0
    for p, c, s in zip(P, conics, cov):
        observed = np.linalg.inv(c)
        x0 = observed[:2, 2] / observed[2, 2]
        T = np.array([[1.0, 0.0, -x0[0]], [0.0, 1.0, -x0[1]], [0.0, 0.0, 1.0]])
        v = lambda e: np.array([e[0, 0], e[0, 1], e[1, 1], e[0, 2], e[1, 2]]) / e[2, 2]  # noqa: E731
        r = v(T @ p @ Q @ p.T @ T.T) - v(T @ observed @ T.T)
        total += r @ np.linalg.solve(s, r)
    return float(total)


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
        (lambda P, c: (P, c, np.eye(5)[None].repeat(3, 0)), pluecker.ShapeError, "covariances: expected 4 rows"),
        (lambda P, c: (P, c, -np.eye(5)[None].repeat(4, 0)), pluecker.DegenerateConfigurationError,
         "covariances[0] is not positive definite"),
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



# --- the batch: triangulate_quadrics ----------------------------------------------------------


def test_quadric_batch_equals_single_calls_with_cameras_per_track(seed):
    # The reproduction's discs: each scene has its own cameras, solved together.
    scenes = [disc_scene(seed % 1000 + k) for k in range(3)]
    P = np.stack([s.cameras for s in scenes])
    conics = np.stack([s.conics for s in scenes])
    cov = np.stack([s.covariances for s in scenes])
    for method in METHODS:
        batch = pluecker.triangulate_quadrics(P, conics, covariances=cov, options=pluecker.TriangulationOptions(method=method, certify=pluecker.CertifyOptions(max_nodes=NODES)))
        assert batch.Q.shape == (3, 4, 4) and batch.primal.shape == (3, 4, 4) and batch.axes.shape == (3, 3, 3)
        assert batch.centre.shape == (3, 3) and batch.semi_axes.shape == (3, 3)
        for i, s in enumerate(scenes):
            single = pluecker.triangulate_quadric(s.cameras, s.conics, s.covariances, options=pluecker.TriangulationOptions(method=method, certify=pluecker.CertifyOptions(max_nodes=NODES)))
            for field in ("Q", "centre", "semi_axes", "axes"):
                np.testing.assert_array_equal(getattr(batch, field)[i], getattr(single, field), err_msg=field)
            if single.primal is None:
                assert np.all(np.isnan(batch.primal[i]))
            else:
                np.testing.assert_array_equal(batch.primal[i], single.primal)
            assert_same_report(batch, i, single)


def test_quadric_batch_with_shared_cameras_and_visibility(seed):
    rng = np.random.default_rng(seed)
    n, views = 5, 5
    P = cameras(views, 60.0, rng)
    conics = np.stack([outlines(P, ellipsoid(rng)[3]) for _ in range(n)])
    conics += rng.normal(0.0, 1e-9, conics.shape) * np.abs(conics)
    visible = random_visibility(rng, n, views, 3)
    visible[4] = [True, True, False, False, False]  # two views: too few for a quadric
    conics[0, 1] = np.diag([1.0, -1.0, -100.0])  # a hyperbola, in a view the track is seen in
    visible[0, 1] = True
    batch = pluecker.triangulate_quadrics(P, conics, visible, options=pluecker.TriangulationOptions(method="local"))
    assert batch.status[4] == "too_few_views" and "3 visible views" in batch.messages[4]
    assert batch.status[0] == "degenerate" and "conics[0][1] is not a real ellipse" in batch.messages[0]
    for i in range(1, 4):
        seen = visible[i]
        single = pluecker.triangulate_quadric(P[seen], conics[i][seen], options=pluecker.TriangulationOptions(method="local"))
        np.testing.assert_array_equal(batch.Q[i], single.Q)
        assert_same_report(batch, i, single)
    assert "QuadricTriangulations(method='local', tracks=5" in repr(batch)

