"""``pluecker.triangulate_line``: recovery, the cost of eq. 19 recomputed here, certificates, bad input.

The residual is recomputed with numpy from its definition (section 3.1 normalisation as pluecker applies
it in pixels): an observed line ``l`` gets the unit normal ``n`` and offset ``c0 <= 0``, the frame origin
``o = (D - c0) n`` with ``D = 1000`` px, and a candidate image line ``(a, b, c)`` has the residual
``D (D (a, b) / c' - n)`` with ``c' = c + (a, b)·o`` its offset in that frame.
"""

from __future__ import annotations

import numpy as np
import pytest
from test_triangulation import cameras

import pluecker

D = 1000.0
METHODS = pluecker.TRIANGULATION_METHODS


def project_point(P: np.ndarray, X: np.ndarray) -> np.ndarray:
    h = P @ np.append(X, 1.0)
    return h[:, :2] / h[:, 2:]


def image_line(P: np.ndarray, A: np.ndarray, B: np.ndarray) -> np.ndarray:
    """Homogeneous image lines (v, 3) of the 3-D line through A and B."""
    a, b = P @ np.append(A, 1.0), P @ np.append(B, 1.0)
    return np.cross(a, b)


def residual(observed: np.ndarray, candidate: np.ndarray) -> np.ndarray:
    scale = np.hypot(observed[0], observed[1])
    n, c0 = observed[:2] / scale, observed[2] / scale
    if c0 > 0:
        n, c0 = -n, -c0
    origin = (D - c0) * n
    shifted = candidate[2] + candidate[:2] @ origin
    return D * (D * candidate[:2] / shifted - n)


def line_cost(P, observed, A, B, cov=None) -> float:
    total = 0.0
    for i, (Pi, li) in enumerate(zip(P, observed)):
        r = residual(li, np.cross(Pi @ np.append(A, 1.0), Pi @ np.append(B, 1.0)))
        total += r @ (r if cov is None else np.linalg.solve(cov[i], r))
    return float(total)


def line_problem(seed: int, views: int = 4, sigma: float = 1.0):
    """Cameras, the true line (A, B), and noisy image segments (views, 2, 2) of the part between A and B."""
    rng = np.random.default_rng(seed)
    P = cameras(views, 30.0, rng)
    A, B = rng.uniform(-1.0, 1.0, (2, 3))
    segments = np.stack([project_point(P, A), project_point(P, B)], axis=1)
    return P, A, B, segments + rng.normal(0.0, sigma, segments.shape)


def on_line(result, A, B, tol):
    d = (B - A) / np.linalg.norm(B - A)
    assert abs(abs(result.direction @ d) - 1.0) < tol
    for X in (A, B):
        off = (X - result.point) - ((X - result.point) @ result.direction) * result.direction
        assert np.linalg.norm(off) < tol * 10


@pytest.mark.parametrize("method", METHODS)
def test_noise_free_images_give_the_line(method, seed):
    P, A, B, _ = line_problem(seed)
    r = pluecker.triangulate_line(P, image_line(P, A, B), method=method)
    assert r.method == method
    assert r.status == "success", f"seed={seed} {r}"
    on_line(r, A, B, 1e-7)
    L = r.plucker
    assert np.linalg.norm(L) == pytest.approx(1.0)
    assert abs(L[0] * L[5] + L[1] * L[4] + L[2] * L[3]) < 1e-12  # eq. 4
    # The direction (l14, -l42, l34) of eq. 3 is parallel to the returned unit direction.
    assert abs(abs(np.array([L[2], -L[4], L[5]]) @ r.direction) - np.linalg.norm([L[2], L[4], L[5]])) < 1e-12
    # The point is the one closest to the origin.
    assert abs(r.point @ r.direction) < 1e-9


@pytest.mark.parametrize("method", METHODS)
def test_reported_cost_is_eq19(method, seed):
    P, A, B, segments = line_problem(seed, views=3)
    observed = np.cross(np.c_[segments[:, 0], np.ones(3)], np.c_[segments[:, 1], np.ones(3)])
    r = pluecker.triangulate_line(P, observed, method=method)
    ours = line_cost(P, observed, r.point, r.point + r.direction)
    assert r.cost == pytest.approx(ours, rel=1e-6), f"seed={seed}"


def test_segments_carry_the_endpoint_covariance(seed):
    P, A, B, segments = line_problem(seed, views=3)
    r1 = pluecker.triangulate_line(P, segments, method="local")
    r2 = pluecker.triangulate_line(P, segments, method="local", sigma=2.0)
    # cov ∝ sigma²: the same line, a quarter of the cost. The two local runs stop at their own step
    # tolerance; 1e-5 rad is 1 % of the direction's uncertainty at 1 px (~1e-3 rad) and would catch any
    # change of the minimum.
    np.testing.assert_allclose(r2.direction * np.sign(r2.direction @ r1.direction), r1.direction, atol=1e-5)
    assert r2.cost == pytest.approx(r1.cost / 4.0, rel=1e-6)
    # The same covariances given explicitly (from fit_line on the endpoints) give the same answer.
    fits = [pluecker.fit_line(s, sigma=1.0) for s in segments]
    observed = np.array([f.line for f in fits])
    cov = np.array([f.covariance for f in fits])
    r3 = pluecker.triangulate_line(P, observed, cov, method="local")
    assert r3.cost == pytest.approx(r1.cost, rel=1e-9)
    assert r3.cost == pytest.approx(line_cost(P, observed, r3.point, r3.point + r3.direction, cov), rel=1e-6)


def test_optimal_is_certified_and_never_worse(seed):
    for k in range(6):
        P, A, B, segments = line_problem(seed + k, views=2 + k % 3)
        results = {m: pluecker.triangulate_line(P, segments, method=m) for m in METHODS}
        opt = results["optimal"]
        assert opt.status in ("success", "gap_not_closed"), f"seed={seed + k} {opt}"
        assert opt.certified == (opt.relative_gap <= 1e-3 and opt.status == "success")
        assert opt.lower_bound <= opt.cost * (1 + 1e-12)
        for m in ("linear", "local"):
            assert not results[m].certified and results[m].certificate == "none"
            # Two views determine a line exactly (cost ~1e-25): an absolute 1e-12 absorbs that round-off.
            assert results[m].cost >= opt.lower_bound * (1 - 1e-9) - 1e-12, f"seed={seed + k}: {m} beats the bound"
            assert results[m].cost >= opt.cost * (1 - 1e-9) - 1e-12, f"seed={seed + k}: {m} beats optimal"


def test_result_fields(seed):
    P, A, B, segments = line_problem(seed)
    r = pluecker.triangulate_line(P, segments, method="local")
    assert isinstance(r, pluecker.TriangulationReport)
    d = r.to_dict()
    assert {"plucker", "point", "direction", "cost", "certified", "status"} <= set(d)
    assert d["plucker"] == r.plucker.tolist()
    assert "LineTriangulation(" in repr(r)


@pytest.mark.parametrize(
    "change, kwargs, error, message",
    [
        (lambda P, s: (P[:1], s[:1]), {}, pluecker.TooFewCorrespondencesError, "2 views"),
        (lambda P, s: (P, s[:2]), {}, pluecker.ShapeError, "lines: expected 4 rows"),
        (lambda P, s: (P, s.reshape(4, 4)), {}, pluecker.ShapeError, "(n, 3) (homogeneous lines) or (n, 2, 2)"),
        (lambda P, s: (P, np.where(np.arange(16).reshape(4, 2, 2) == 9, np.nan, s)), {}, pluecker.NonFiniteError,
         "row 2"),
        (lambda P, s: (P, np.concatenate([s[:1, :1], s[:1, :1]], axis=1).repeat(4, 0)), {},
         pluecker.DegenerateConfigurationError, "zero length"),
        (lambda P, s: (P, np.zeros((4, 3)) + [0.0, 0.0, 1.0]), {}, pluecker.DegenerateConfigurationError,
         "zero normal"),
        (lambda P, s: (P, np.ones((4, 3))), {"sigma": 1.0}, pluecker.InvalidOptionError, "sigma"),
        (lambda P, s: (P, s), {"sigma": -1.0}, pluecker.InvalidOptionError, "sigma"),
    ],
    ids=["one-view", "count", "shape", "nan", "zero-length", "line-at-infinity", "sigma-homogeneous", "sigma-negative"],
)
def test_bad_input(change, kwargs, error, message, seed):
    P, _, _, segments = line_problem(seed)
    args = change(P, segments)
    with pytest.raises(error) as info:
        pluecker.triangulate_line(*args, **kwargs)
    assert message in str(info.value)


def test_cov_and_sigma_together_is_an_error(seed):
    P, _, _, segments = line_problem(seed)
    with pytest.raises(pluecker.InvalidOptionError, match="cov or sigma"):
        pluecker.triangulate_line(P, segments, np.eye(2)[None].repeat(4, 0), sigma=1.0)


def test_line_in_an_epipolar_plane_is_degenerate(seed):
    # Two cameras; the 3-D line lies in the plane through both centres: its back-projected planes coincide.
    rng = np.random.default_rng(seed)
    P = cameras(2, 30.0, rng)
    centres = [-np.linalg.solve(p[:, :3], p[:, 3]) for p in P]
    A = 0.5 * (centres[0] + centres[1]) * 0.1
    B = A + 0.3 * (centres[1] - centres[0]) + 0.2 * (A - centres[0])
    with pytest.raises(pluecker.DegenerateConfigurationError, match="epipolar|coincide|plane"):
        pluecker.triangulate_line(P, image_line(P, A, B))
