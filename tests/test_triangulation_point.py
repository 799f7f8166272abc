"""Points: ``pluecker.triangulate_point`` (recovery, the cost it reports, its certificate, options and bad
input) and ``pluecker.triangulate_points`` (the batch equals single calls; visibility, covariances, bad
tracks, the GIL). Scenes and costs: ``triangulation_scenes``."""

from __future__ import annotations

import math
import threading

import numpy as np
import pytest
from triangulation_scenes import METHODS, cameras, cost_eq19, depths, many_start_point_minimum, project

import pluecker


REPORT_FIELDS = ("method", "status", "success", "cost", "cost_kind", "certificate", "certified", "iterations", "termination",
                 "time_seconds", "residual_dof", "residual_test")


def noisy_problem(seed: int, views: int = 4, parallax_deg: float = 30.0, sigma: float = 1.0):
    rng = np.random.default_rng(seed)
    P = cameras(views, parallax_deg, rng)
    X = rng.uniform(-1.0, 1.0, 3)
    return P, X, project(P, X) + rng.normal(0.0, sigma, (views, 2))


@pytest.mark.parametrize("method", METHODS)
@pytest.mark.parametrize("views", [2, 3, 7])
def test_noise_free_observations_give_the_point(method, views, seed):
    rng = np.random.default_rng(seed)
    P = cameras(views, 30.0, rng)
    X = rng.uniform(-1.0, 1.0, 3)
    r = pluecker.triangulate_point(P, project(P, X), options=pluecker.TriangulationOptions(method=method))
    assert r.method == method and r.status == "success" and r.success, f"seed={seed} {r}"
    # Exact data: only round-off remains (the point is ~10 units away, pixels ~1e2).
    np.testing.assert_allclose(r.point, X, atol=1e-8, err_msg=f"seed={seed}")
    assert r.cost < 1e-12
    assert r.certified == (method == "optimal")


@pytest.mark.parametrize("method", METHODS)
def test_reported_cost_is_eq19_at_the_returned_point(method, seed):
    for k in range(10):
        P, _, x = noisy_problem(seed + k, views=5)
        r = pluecker.triangulate_point(P, x, options=pluecker.TriangulationOptions(method=method))
        assert r.cost == pytest.approx(cost_eq19(P, r.point, x), rel=1e-9), f"seed={seed + k}"


def test_covariance_weights_the_residuals_as_eq18(seed):
    rng = np.random.default_rng(seed)
    P, _, x = noisy_problem(seed, views=4)
    A = rng.normal(size=(4, 2, 2))
    cov = A @ A.transpose(0, 2, 1) + 0.5 * np.eye(2)
    r = pluecker.triangulate_point(P, x, cov, options=pluecker.TriangulationOptions(method="local"))
    assert r.cost == pytest.approx(cost_eq19(P, r.point, x, cov), rel=1e-9)
    # The weighted optimum: the gradient of Σ rᵢᵀ Σᵢ⁻¹ rᵢ vanishes there (central differences, step
    # 1e-6 of a ~10-unit point; the cost is ~1 so a gradient of 1e-4 would be a real error).
    step = 1e-6
    grad = [(cost_eq19(P, r.point + e, x, cov) - cost_eq19(P, r.point - e, x, cov)) / (2 * step) for e in np.eye(3) * step]
    assert np.max(np.abs(grad)) < 1e-4, grad
    # Scaling every covariance by k scales the cost by 1/k and leaves the point.
    scaled = pluecker.triangulate_point(P, x, 4.0 * cov, options=pluecker.TriangulationOptions(method="local"))
    np.testing.assert_allclose(scaled.point, r.point, atol=1e-7)
    assert scaled.cost == pytest.approx(r.cost / 4.0, rel=1e-9)


def test_a_positive_camera_scale_does_not_matter_and_the_sign_says_which_side_is_in_front(seed):
    P, _, x = noisy_problem(seed, views=3)
    base = pluecker.triangulate_point(P, x)
    rescaled = P * np.array([2.0, 1e-3, 7.0])[:, None, None]
    other = pluecker.triangulate_point(rescaled, x)
    np.testing.assert_allclose(other.point, base.point, atol=1e-8)
    assert other.cost == pytest.approx(base.cost, rel=1e-9)
    assert other.certified and other.status == "success"
    # λ = (P X̃)₃ > 0 in front for the matrix as given (issue 10): −P sees the other half-space, so the
    # same point is behind that camera.
    negated = P * np.array([-1.0, 1.0, 1.0])[:, None, None]
    assert depths(negated, base.point)[0] < 0
    for method in METHODS:
        r = pluecker.triangulate_point(negated, x, options=pluecker.TriangulationOptions(method=method))
        assert r.status != "success" and not r.certified, (method, r)


def relative_gap(cost: float, raw_lower_bound: float) -> float:
    """The gap recomputed from a cost and a raw bound (never read back from the result)."""
    return (cost - min(raw_lower_bound, cost)) / max(cost, 1e-12)


def test_optimal_is_certified_and_never_worse_than_the_others(seed):
    rng = np.random.default_rng(seed)
    for k in range(30):
        P, X, x = noisy_problem(seed + k, views=2 + k % 5)
        results = {m: pluecker.triangulate_point(P, x, options=pluecker.TriangulationOptions(method=m)) for m in METHODS}
        opt = results["optimal"]
        assert opt.certified and opt.status == "success", f"seed={seed + k} {opt}"
        assert opt.certificate.kind in ("convexity_test", "branch_and_bound")
        # The raw bound against numpy's costs: of the answer, of the other methods' answers, of the
        # truth and of the least cost a many-start search of its own finds; the gap recomputed.
        cost = cost_eq19(P, opt.point, x)
        raw = opt.certificate.raw_lower_bound
        assert 0.0 <= raw <= cost * (1 + 1e-12), f"seed={seed + k}: {opt}"
        assert opt.certificate.lower_bound == min(raw, opt.cost)
        assert relative_gap(cost, raw) <= 1e-3 * (1 + 1e-9), f"seed={seed + k}: {opt}"
        assert raw <= cost_eq19(P, X, x) * (1 + 1e-12)
        assert raw <= many_start_point_minimum(P, x, opt.point, rng, starts=10) * (1 + 1e-12), f"seed={seed + k}"
        for m in ("linear", "local"):
            assert results[m].certificate is None and not results[m].certified
            other = cost_eq19(P, results[m].point, x)
            if np.all(depths(P, results[m].point) > 0):
                assert other >= raw * (1 - 1e-12), f"seed={seed + k}: {m} beats the bound"
            assert results[m].cost >= opt.cost * (1 - 1e-9), f"seed={seed + k}: {m} beats optimal"


def test_lower_bound_holds_at_sampled_points_in_front(seed):
    """The certificate is a bound over every point in front of the cameras: no sampled point in front
    (near the answer, along the rays, far away) may cost less."""
    rng = np.random.default_rng(seed)
    for k in range(5):
        P, _, x = noisy_problem(seed + k, views=3, parallax_deg=5.0, sigma=3.0)
        r = pluecker.triangulate_point(P, x)
        assert r.certified, f"seed={seed + k}"
        samples = np.concatenate([r.point + rng.normal(0, s, (2000, 3)) for s in (1e-3, 1e-2, 0.1, 1.0, 10.0)])
        front = np.array([np.all(depths(P, X) > 0) for X in samples])
        costs = np.array([cost_eq19(P, X, x) for X in samples[front]])
        assert front.sum() > 1000
        assert costs.min() >= r.certificate.raw_lower_bound * (1 - 1e-9), f"seed={seed + k}"
        assert many_start_point_minimum(P, x, r.point, rng, starts=20) >= r.certificate.raw_lower_bound * (1 - 1e-12)


def test_tight_gap_and_branch_and_bound_report_nodes(seed):
    # A 2-view low-parallax problem with large noise is where the convexity test may not decide; a
    # forced tiny gap must still end certified or say that the node budget ran out.
    for k in range(40):
        P, _, x = noisy_problem(seed + k, views=2, parallax_deg=1.0, sigma=5.0)
        r = pluecker.triangulate_point(P, x, options=pluecker.TriangulationOptions(certify=pluecker.CertifyOptions(max_relative_gap=1e-9)))
        assert r.status in ("success", "gap_not_closed"), f"seed={seed + k} {r}"
        # The gap recomputed from numpy's cost and the raw bound; the costs agree to ~1e-13 relative,
        # which moves the recomputed gap by as much.
        gap = relative_gap(cost_eq19(P, r.point, x), r.certificate.raw_lower_bound)
        if r.certified:
            assert gap <= 1e-9 + 1e-12, f"seed={seed + k}: {r}"
        if r.certificate.kind == "branch_and_bound":
            assert r.certificate.nodes >= 1 and r.certificate.solver_iterations >= 1
        else:
            assert r.certificate.nodes == 0
        assert np.all(depths(P, r.point) > 0), f"seed={seed + k}: behind a camera"


def test_node_budget_is_respected(seed):
    P, _, x = noisy_problem(seed, views=2, parallax_deg=0.5, sigma=5.0)
    r = pluecker.triangulate_point(P, x, options=pluecker.TriangulationOptions(certify=pluecker.CertifyOptions(max_relative_gap=1e-12, max_nodes=1)))
    assert r.certificate.nodes <= 1
    assert r.status in ("success", "gap_not_closed")
    assert r.certified == (r.status == "success" and r.certificate.relative_gap <= 1e-12)


def test_there_is_no_max_reprojection_error_option():
    """The paper's γ bounds its search domain; every search here takes γ from the local solution (nothing
    cheaper is left out), so the option is gone. It used to be accepted and ignored: with γ = 0.01 px, below
    every residual of the answer, the point came back ``success``, certified over every point in front."""
    with pytest.raises(TypeError, match="max_reprojection_error"):
        pluecker.TriangulationOptions(max_reprojection_error=0.01)
    assert not hasattr(pluecker.TriangulationOptions(), "max_reprojection_error")
    assert "max_reprojection_error" not in {name for name, _, _ in pluecker.TriangulationOptions.__fields__}


@pytest.mark.parametrize("parallax_deg", [1.0, 0.2])
def test_low_parallax_optimal_stays_in_front(parallax_deg, seed):
    # At 0.2° and 1 px, a pixel moves the point by ~4 units in depth (the cameras are 10 away).
    for k in range(40):
        P, _, x = noisy_problem(seed + k, views=2, parallax_deg=parallax_deg)
        r = pluecker.triangulate_point(P, x)
        assert r.status == "success" and r.certified, f"seed={seed + k} {r}"
        assert np.all(depths(P, r.point) > 0), f"seed={seed + k}"
        assert r.cost == pytest.approx(cost_eq19(P, r.point, x), rel=1e-9)


def test_result_is_frozen_and_owns_its_arrays(seed):
    P, _, x = noisy_problem(seed)
    r = pluecker.triangulate_point(P, x)
    assert isinstance(r, pluecker.TriangulationReport)
    X = r.point
    X[:] = 0.0
    assert not np.all(r.point == 0.0)
    with pytest.raises(AttributeError):
        r.cost = 0.0  # type: ignore[misc]
    d = r.to_dict()
    assert set(d) == set(REPORT_FIELDS) | {"point", "covariance", "inliers"}
    assert d["point"] == r.point.tolist() and d["certificate"] == r.certificate.to_dict()
    assert "PointTriangulation(" in repr(r) and "certified=True" in repr(r)


def test_accepts_lists_and_integers(seed):
    P, X, x = noisy_problem(seed, sigma=0.0)
    r = pluecker.triangulate_point(P.tolist(), np.round(x).astype(int).tolist())
    assert r.status == "success" and np.linalg.norm(r.point - X) < 0.1


def good(seed: int):
    P, _, x = noisy_problem(seed, views=3)
    return P, x


@pytest.mark.parametrize(
    "change, error, message",
    [
        (lambda P, x: (P[:1], x[:1], None), pluecker.TooFewCorrespondencesError, "2 views"),
        (lambda P, x: (P, x[:2], None), pluecker.ShapeError, "observations: expected 3 rows"),
        (lambda P, x: (P[:, :, :3], x, None), pluecker.ShapeError, "cameras: expected shape (n, 3, 4)"),
        (lambda P, x: (P, x[:, :1], None), pluecker.ShapeError, "observations: expected shape (n, 2)"),
        (lambda P, x: (P, np.where(np.arange(6).reshape(3, 2) == 3, np.nan, x), None), pluecker.NonFiniteError,
         "observations: non-finite value (NaN or inf) in row 1"),
        (lambda P, x: (np.where(np.arange(36).reshape(3, 3, 4) == 30, np.inf, P), x, None), pluecker.NonFiniteError,
         "cameras: non-finite value (NaN or inf) in row 2"),
        (lambda P, x: (P * np.array([1, 0, 1])[:, None, None], x, None), pluecker.SingularCameraError, "cameras[1]"),
        (lambda P, x: (P, x, np.array([np.eye(2), [[1.0, 2.0], [2.0, 1.0]], np.eye(2)])),
         pluecker.DegenerateConfigurationError, "covariances[1] is not positive definite"),
        (lambda P, x: (P, x, np.eye(2)[None].repeat(2, 0)), pluecker.ShapeError, "covariances: expected 3 rows"),
        (lambda P, x: (np.array([P[0], P[0] * 2.0, P[0]]), x, None), pluecker.DegenerateConfigurationError,
         "no parallax"),
    ],
    ids=["one-view", "count", "P-shape", "x-shape", "x-nan", "P-inf", "singular", "cov-indefinite", "cov-count",
         "same-centre"],
)
def test_bad_input_raises_named_errors(change, error, message, seed):
    P, x, cov = change(*good(seed))
    with pytest.raises(error) as info:
        pluecker.triangulate_point(P, x, cov)
    assert message in str(info.value)
    assert isinstance(info.value, ValueError)


@pytest.mark.parametrize(
    "kwargs, message",
    [
        ({"method": "bundle"}, "unknown triangulation method 'bundle'"),
        ({"certify": {"max_relative_gap": 0.0}}, "max_relative_gap"),
        ({"certify": {"max_relative_gap": math.nan}}, "max_relative_gap"),
        ({"certify": {"max_nodes": 0}}, "max_nodes"),
    ],
)
def test_bad_options_raise_invalid_option(kwargs, message, seed):
    with pytest.raises(pluecker.InvalidOptionError, match=message):
        if "certify" in kwargs:
            pluecker.CertifyOptions(**kwargs["certify"])
        else:
            pluecker.triangulate_point(*good(seed), options=pluecker.TriangulationOptions(**kwargs))


def test_unknown_keyword_and_non_numeric_input_are_type_errors(seed):
    P, x = good(seed)
    with pytest.raises(TypeError, match="max_gap"):
        pluecker.triangulate_point(P, x, max_gap=0.1)
    with pytest.raises(TypeError, match="observations: expected an array of real numbers"):
        pluecker.triangulate_point(P, [["a", "b"]] * 3)


# --- the batch: triangulate_points ------------------------------------------------------------


def scene(seed: int, views: int = 4, n: int = 300, sigma: float = 1.0):
    rng = np.random.default_rng(seed)
    P = cameras(views, 30.0, rng)
    X = rng.uniform(-1.0, 1.0, (n, 3))
    h = np.einsum("vij,nj->nvi", P, np.hstack([X, np.ones((n, 1))]))
    x = h[..., :2] / h[..., 2:] + rng.normal(0.0, sigma, (n, views, 2))
    return P, X, x


@pytest.mark.parametrize("method", ["linear", "local", "optimal"])
def test_batch_equals_single_calls(method, seed):
    P, _, x = scene(seed, n=200)
    batch = pluecker.triangulate_points(P, x, options=pluecker.TriangulationOptions(method=method))
    assert len(batch) == 200 and batch.method == method
    assert batch.point.shape == (200, 3) and batch.status.shape == (200,)
    for i in range(0, 200, 7):
        single = pluecker.triangulate_point(P, x[i], options=pluecker.TriangulationOptions(method=method))
        # The same equations on the same data; the batch's linear path sums in another order, so the
        # points may differ in the last bits (1e-16 relative), and a local minimisation started there by
        # its step tolerance (1e-10 relative). 1e-9 is well above both and far below the noise (~1e-3).
        np.testing.assert_allclose(batch.point[i], single.point, rtol=1e-9, atol=1e-9)
        assert batch.cost[i] == pytest.approx(single.cost, rel=1e-9, abs=1e-12), i
        c = single.certificate
        if c is None:
            # The batch's columns without a certificate: NaN bounds and gap, "none", no nodes.
            assert np.isnan(batch.lower_bound[i]) and np.isnan(batch.relative_gap[i]), i
            assert batch.certificate[i] == "none" and batch.nodes[i] == 0 and not batch.certified[i], i
        else:
            for field in ("lower_bound", "relative_gap"):
                assert getattr(batch, field)[i] == pytest.approx(getattr(c, field), rel=1e-9, abs=1e-12), (i, field)
            assert batch.certified[i] == c.certified and batch.nodes[i] == c.nodes and batch.certificate[i] == c.kind
        assert batch.status[i] == single.status
    assert np.all(batch.status == "success")
    assert np.all(batch.certified) == (method == "optimal")
    assert all(m == "" for m in batch.messages)


def test_visibility_selects_the_views(seed):
    P, _, x = scene(seed, views=5, n=100)
    rng = np.random.default_rng(seed)
    visible = rng.uniform(size=(100, 5)) < 0.6
    visible[np.arange(100), rng.integers(0, 5, 100)] = True
    visible[np.arange(100), (rng.integers(1, 5, 100) + np.argmax(visible, axis=1)) % 5] = True
    masked = np.where(visible[..., None], x, np.nan)  # unseen entries may hold anything, NaN included
    batch = pluecker.triangulate_points(P, masked, visible)
    for i in range(100):
        seen = visible[i]
        if seen.sum() < 2:
            assert batch.status[i] == "too_few_views"
            continue
        single = pluecker.triangulate_point(P[seen], x[i][seen])
        np.testing.assert_allclose(batch.point[i], single.point, rtol=1e-9, atol=1e-9)
        assert batch.cost[i] == pytest.approx(cost_eq19(P[seen], batch.point[i], x[i][seen]), rel=1e-9)


def test_covariances_per_observation(seed):
    P, _, x = scene(seed, views=3, n=40)
    rng = np.random.default_rng(seed)
    A = rng.normal(size=(40, 3, 2, 2))
    cov = A @ A.transpose(0, 1, 3, 2) + 0.3 * np.eye(2)
    batch = pluecker.triangulate_points(P, x, covariances=cov, options=pluecker.TriangulationOptions(method="local"))
    for i in range(0, 40, 5):
        assert batch.cost[i] == pytest.approx(cost_eq19(P, batch.point[i], x[i], cov[i]), rel=1e-9)


def test_one_bad_track_never_loses_the_others(seed):
    P, _, x = scene(seed, views=3, n=50)
    visible = np.ones((50, 3), dtype=bool)
    x = x.copy()
    x[3, 1, 0] = np.nan  # NaN in a visible view
    visible[7] = [True, False, False]  # one view
    cov = np.tile(np.eye(2), (50, 3, 1, 1))
    cov[11, 2] = [[1.0, 2.0], [2.0, 1.0]]  # not positive definite
    batch = pluecker.triangulate_points(P, x, visible, cov)
    expected = {3: "non_finite", 7: "too_few_views", 11: "degenerate"}
    for i, status in expected.items():
        assert batch.status[i] == status, (i, batch.messages[i])
        assert batch.messages[i].startswith(f"track {i}: ")
        assert np.all(np.isnan(batch.point[i])) and not batch.certified[i]
    # The messages name the track and the view (as a row of that track's observations).
    assert "observations[3]: non-finite value (NaN or inf) in row 1" in batch.messages[3]
    assert "covariances[11][2] is not positive definite" in batch.messages[11]
    good = np.setdiff1d(np.arange(50), list(expected))
    assert np.all(batch.status[good] == "success") and np.all(batch.certified[good])
    # The same NaN where the view is not visible is no problem.
    visible[3, 1] = False
    assert pluecker.triangulate_points(P, x, visible).status[3] == "success"


def test_low_parallax_batch_stays_in_front(seed):
    rng = np.random.default_rng(seed)
    P = cameras(2, 0.2, rng)
    X = rng.uniform(-1.0, 1.0, (300, 3))
    h = np.einsum("vij,nj->nvi", P, np.hstack([X, np.ones((300, 1))]))
    x = h[..., :2] / h[..., 2:] + rng.normal(0.0, 1.0, (300, 2, 2))
    batch = pluecker.triangulate_points(P, x)
    ok = batch.status == "success"
    assert ok.mean() > 0.95, np.unique(batch.status, return_counts=True)
    for i in np.flatnonzero(ok):
        assert np.all(depths(P, batch.point[i]) > 0), i


def test_empty_batch(seed):
    P, _, _ = scene(seed)
    batch = pluecker.triangulate_points(P, np.zeros((0, 4, 2)))
    assert len(batch) == 0 and batch.point.shape == (0, 3) and batch.status.shape == (0,)


def test_gil_is_released_during_the_solve(seed):
    """Python keeps running while a batch is solved in another thread. The main thread's loop is timed
    alone first; during a call of ~0.2 s it must do at least 10 % of the iterations it would do alone in
    that time. With the GIL held it could run only before the call enters Rust: at most one switch
    interval (5 ms), 2.5 % of the call."""
    import sys
    import time

    P, _, x = scene(seed, n=200_000)
    state = {"inside": False, "seconds": 0.0}

    def loop(seconds: float) -> int:
        count, end = 0, time.perf_counter() + seconds
        while time.perf_counter() < end:
            count += 1
        return count

    rate = loop(0.02) / 0.02

    def work():
        state["inside"] = True
        start = time.perf_counter()
        pluecker.triangulate_points(P, x, options=pluecker.TriangulationOptions(method="optimal"))
        state["seconds"] = time.perf_counter() - start
        state["inside"] = False

    worker = threading.Thread(target=work)
    counted = 0
    worker.start()
    while not state["inside"]:
        time.sleep(0)
    while state["inside"]:
        time.perf_counter()
        counted += 1
    worker.join()
    assert state["seconds"] > 20 * sys.getswitchinterval(), "the call is too short to tell"
    assert counted > 0.1 * rate * state["seconds"], (counted, rate, state["seconds"])


@pytest.mark.parametrize(
    "make, error, message",
    [
        (lambda P, x: (P[:1], x[:, :1]), pluecker.TooFewCorrespondencesError, "2 cameras"),
        (lambda P, x: (P, x[:, :3]), pluecker.ShapeError, "one column per camera"),
        (lambda P, x: (P, x[:, :, :1]), pluecker.ShapeError, "observations: expected shape (n, v, 2)"),
        (lambda P, x: (np.where(np.arange(48).reshape(4, 3, 4) == 20, np.nan, P), x), pluecker.NonFiniteError,
         "cameras: non-finite value (NaN or inf) in row 1"),
        (lambda P, x: (P * np.array([1, 1, 0, 1])[:, None, None], x), pluecker.SingularCameraError, "cameras[2]"),
    ],
    ids=["one-camera", "columns", "x-shape", "P-nan", "P-singular"],
)
def test_bad_arguments_raise(make, error, message, seed):
    P, _, x = scene(seed, n=5)
    with pytest.raises(error) as info:
        pluecker.triangulate_points(*make(P, x))
    assert message in str(info.value)


def test_bad_mask_and_cov_shapes(seed):
    P, _, x = scene(seed, n=5)
    with pytest.raises(pluecker.ShapeError, match="visible"):
        pluecker.triangulate_points(P, x, np.ones((5, 3), dtype=bool))
    with pytest.raises(TypeError, match="visible: expected a boolean array"):
        pluecker.triangulate_points(P, x, np.ones((5, 4)))
    with pytest.raises(pluecker.ShapeError, match="covariances"):
        pluecker.triangulate_points(P, x, covariances=np.ones((5, 3, 2, 2)))
    with pytest.raises(pluecker.InvalidOptionError, match="max_nodes"):
        pluecker.triangulate_points(P, x, options=pluecker.TriangulationOptions(certify=pluecker.CertifyOptions(max_nodes=0)))



# --- the batch from observations: triangulate_points(track=, image=) ---------------------------------


def observation_rows(x, visible, cov, rng):
    """The dense tracks as observation rows (track, image, pixel, covariance): the rows of different
    tracks interleaved at random, each track's rows in ascending image order (the dense order)."""
    queues = {t: [j for j in range(x.shape[1]) if visible[t, j]] for t in range(x.shape[0])}
    rows = []
    while any(queues.values()):
        t = rng.choice([t for t, q in queues.items() if q])
        rows.append((t, queues[t].pop(0)))
    track, image = np.array(rows).T
    return track, image, x[track, image], cov[track, image]


@pytest.mark.parametrize("method", METHODS)
def test_observation_rows_give_the_dense_batch(method, seed):
    rng = np.random.default_rng(seed)
    P = cameras(6, 40.0, rng)
    n = 30
    X = rng.uniform(-1.0, 1.0, (n, 3))
    x = np.stack([project(P, Xi) for Xi in X]) + rng.normal(0.0, 1.0, (n, 6, 2))
    visible = rng.uniform(size=(n, 6)) < 0.6
    visible[np.arange(n), rng.integers(0, 6, n)] = True
    visible[np.arange(n), (rng.integers(0, 5, n) + 1 + rng.integers(0, 6, n)) % 6] = True
    s = rng.uniform(0.5, 2.0, (n, 6))
    cov = s[..., None, None] * np.eye(2)
    dense = pluecker.triangulate_points(P, x, visible, cov, options=pluecker.TriangulationOptions(method=method))
    track, image, rows, row_cov = observation_rows(x, visible, cov, rng)
    sparse = pluecker.triangulate_points(P, rows, covariances=row_cov, track=track, image=image, options=pluecker.TriangulationOptions(method=method))
    assert len(sparse) == n
    if method == "linear":
        # The dense linear batch has its own allocation-free DLT; the same sums in another order agree to
        # rounding (about 1e-16 of the coordinates, 1e-12 allowed).
        np.testing.assert_allclose(sparse.point, dense.point, rtol=1e-12, atol=1e-12)
        np.testing.assert_allclose(sparse.cost, dense.cost, rtol=1e-9)
    else:
        np.testing.assert_array_equal(sparse.point, dense.point)
        np.testing.assert_array_equal(sparse.cost, dense.cost)
    np.testing.assert_array_equal(sparse.certified, dense.certified)
    np.testing.assert_array_equal(sparse.status, dense.status)


def test_observation_rows_name_their_bad_rows_and_keep_the_others():
    rng = np.random.default_rng(4)
    P = cameras(4, 30.0, rng)
    X = rng.uniform(-1.0, 1.0, (3, 3))
    track = np.repeat([0, 1, 2], 4)
    image = np.tile(np.arange(4), 3)
    x = np.concatenate([project(P, Xi) for Xi in X])
    image[5] = 9  # track 1 names a camera that does not exist
    r = pluecker.triangulate_points(P, x, track=track, image=image)
    assert r.status[1] == "invalid_input" and "image[5]" in r.messages[1]
    assert r.status[0] == r.status[2] == "success"
    with pytest.raises(pluecker.ShapeError, match="^image: expected 12 rows"):
        pluecker.triangulate_points(P, x, track=track, image=image[:5])
    with pytest.raises(pluecker.InvalidOptionError, match="^track: entry 2 is -1"):
        pluecker.triangulate_points(P, x, track=np.where(np.arange(12) == 2, -1, track), image=image)
