"""``pluecker.triangulate_points``: agreement with the single-point function, visibility, per-track errors."""

from __future__ import annotations

import threading

import numpy as np
import pytest
from test_triangulation import cameras, cost_eq19, depths

import pluecker


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
    batch = pluecker.triangulate_points(P, x, method=method)
    assert len(batch) == 200 and batch.method == method
    assert batch.X.shape == (200, 3) and batch.status.shape == (200,)
    for i in range(0, 200, 7):
        single = pluecker.triangulate_point(P, x[i], method=method)
        # The same equations on the same data; the batch's linear path sums in another order, so the
        # points may differ in the last bits (1e-16 relative), and a local minimisation started there by
        # its step tolerance (1e-10 relative). 1e-9 is well above both and far below the noise (~1e-3).
        np.testing.assert_allclose(batch.X[i], single.X, rtol=1e-9, atol=1e-9)
        for field in ("cost", "lower_bound", "relative_gap"):
            assert getattr(batch, field)[i] == pytest.approx(getattr(single, field), rel=1e-9, abs=1e-12), (i, field)
        assert batch.certified[i] == single.certified and batch.nodes[i] == single.nodes
        assert batch.status[i] == single.status and batch.certificate[i] == single.certificate
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
        np.testing.assert_allclose(batch.X[i], single.X, rtol=1e-9, atol=1e-9)
        assert batch.cost[i] == pytest.approx(cost_eq19(P[seen], batch.X[i], x[i][seen]), rel=1e-9)


def test_covariances_per_observation(seed):
    P, _, x = scene(seed, views=3, n=40)
    rng = np.random.default_rng(seed)
    A = rng.normal(size=(40, 3, 2, 2))
    cov = A @ A.transpose(0, 1, 3, 2) + 0.3 * np.eye(2)
    batch = pluecker.triangulate_points(P, x, cov=cov, method="local")
    for i in range(0, 40, 5):
        assert batch.cost[i] == pytest.approx(cost_eq19(P, batch.X[i], x[i], cov[i]), rel=1e-9)


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
        assert np.all(np.isnan(batch.X[i])) and not batch.certified[i]
    # The messages name the track and the view (as a row of that track's observations).
    assert "x[3]: non-finite value (NaN or inf) in row 1" in batch.messages[3]
    assert "cov[11][2] is not positive definite" in batch.messages[11]
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
        assert np.all(depths(P, batch.X[i]) > 0), i


def test_empty_batch(seed):
    P, _, _ = scene(seed)
    batch = pluecker.triangulate_points(P, np.zeros((0, 4, 2)))
    assert len(batch) == 0 and batch.X.shape == (0, 3) and batch.status.shape == (0,)


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
        pluecker.triangulate_points(P, x, method="optimal")
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
        (lambda P, x: (P, x[:, :, :1]), pluecker.ShapeError, "x: expected shape (n, v, 2)"),
        (lambda P, x: (np.where(np.arange(48).reshape(4, 3, 4) == 20, np.nan, P), x), pluecker.NonFiniteError,
         "P: non-finite value (NaN or inf) in row 1"),
        (lambda P, x: (P * np.array([1, 1, 0, 1])[:, None, None], x), pluecker.SingularCameraError, "P[2]"),
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
    with pytest.raises(pluecker.ShapeError, match="cov"):
        pluecker.triangulate_points(P, x, cov=np.ones((5, 3, 2, 2)))
    with pytest.raises(pluecker.InvalidOptionError, match="max_nodes"):
        pluecker.triangulate_points(P, x, options=pluecker.TriangulationOptions(max_nodes=0))
