"""Property tests (hypothesis) of every public entry point (issue 10 §6): for any shapes, dtypes,
magnitudes, NaN/inf and degenerate geometry, a call raises a documented error or returns a consistent
result — never a crash, a PanicException, a bare OverflowError or an internal error.

The profile (tests/conftest.py) is "ci" by default; PLUECKER_HYPOTHESIS=nightly runs the deep search.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, note
from conftest import hooks
from hypothesis import strategies as st
from properties import (
    array_likes,
    check_batch,
    check_error,
    check_pose,
    check_report,
    check_strict_json_and_pickle,
    float_arrays,
    integers,
    outcome,
    reals,
)

import pluecker

# The strategies build some inputs with numpy arithmetic that overflows on purpose.
pytestmark = pytest.mark.filterwarnings("ignore::RuntimeWarning")

CAMERAS = [pluecker.Camera.pinhole(800, 800, 320, 240), pluecker.Camera.pinhole(-1730.3, 1220.7, 243.8, 241.2, 3.0),
           pluecker.Camera.pinhole(800, -600, 0, 0)]
ARRAYS = ("points2d", "points3d", "lines2d", "lines3d")
ROWS = {"points2d": (2,), "points3d": (3,), "lines2d": (2, 2), "lines3d": (2, 3)}


# --- camera and geometry helpers -----------------------------------------------------------------------


@given(st.tuples(*[st.one_of(reals(), st.booleans(), st.integers(-5, 5)) for _ in range(5)]))
def test_camera(args):
    camera = outcome(lambda: pluecker.Camera.pinhole(*args), type_error_ok=False)
    if isinstance(camera, pluecker.Camera):
        assert np.all(np.isfinite(camera.K)) and camera.fx != 0 and camera.fy != 0
        assert pluecker.Camera.from_matrix(camera.K) == camera


@given(array_likes((3, 3)))
def test_camera_from_matrix(K):
    camera = outcome(lambda: pluecker.Camera.from_matrix(K))
    if isinstance(camera, pluecker.Camera):
        assert np.all(np.isfinite(camera.K))


@given(st.sampled_from(CAMERAS), st.integers(0, 6).flatmap(lambda n: st.tuples(array_likes((n, 3)),
                                                                               array_likes((n, 2)))))
def test_camera_projections(camera, arrays):
    points, pixels = arrays
    for call, data in ((camera.project, points), (camera.unproject, pixels)):
        out = outcome(lambda: call(data))
        if isinstance(out, np.ndarray):
            assert out.ndim == 2 and out.shape[1] == 2 and out.dtype == np.float64


def rotations():
    """Rotation matrices from random unit quaternions, and non-rotations."""
    def rotation(q):
        q = np.asarray(q, float)
        if not np.linalg.norm(q) > 1e-3:
            q = np.array([1.0, 0, 0, 0])
        w, x, y, z = q / np.linalg.norm(q)
        return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                         [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                         [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])
    quaternions = st.lists(st.floats(-1, 1), min_size=4, max_size=4)
    return st.one_of(quaternions.map(rotation), quaternions.map(rotation), array_likes((3, 3)))


@given(rotations(), array_likes((3,)), array_likes((8,)))
def test_dual_quaternion_and_screw(R, t, q):
    dq = outcome(lambda: pluecker.pose_to_dual_quaternion(R, t))
    if isinstance(dq, np.ndarray):
        assert dq.shape == (8,)
        back = outcome(lambda: pluecker.dual_quaternion_to_pose(dq), type_error_ok=False)
        if isinstance(back, tuple) and np.all(np.isfinite(dq)):
            assert np.allclose(back[0], R, atol=1e-6)
    screw = outcome(lambda: pluecker.pose_to_screw(R, t))
    if isinstance(screw, dict):
        assert set(screw) == {"d", "angle", "direction", "point"}
    pose = outcome(lambda: pluecker.dual_quaternion_to_pose(q))
    if isinstance(pose, tuple):
        assert pose[0].shape == (3, 3) and pose[1].shape == (3,)


@given(st.sampled_from(["general", "planar", "far", "spherical"]), integers(), integers(), integers())
def test_random_scene(kind, n_points, n_lines, seed):
    small = lambda v: v if isinstance(v, bool) or not 0 <= v <= 10**6 else v % 50  # noqa: E731
    scene = outcome(lambda: pluecker.random_scene(kind, small(n_points), small(n_lines), seed), type_error_ok=False)
    if isinstance(scene, dict):
        assert scene["points2d"].shape == (small(n_points), 2)
        assert np.all(np.isfinite(scene["points2d"])) and np.all(np.isfinite(scene["points3d"]))


# --- pose ------------------------------------------------------------------------------------------------


@st.composite
def pose_problems(draw):
    """Arrays for estimate_pose: a random scene perturbed (scaled, noisy, outliers, collinear,
    coplanar, coincident, zero-length or 1e300-long segments, NaN) or plain wild arrays."""
    if draw(st.booleans()):
        n, m = draw(st.integers(0, 12)), draw(st.integers(0, 5))
        kind = draw(st.sampled_from(["general", "planar", "far"]))
        scene = pluecker.random_scene(kind, n, m, seed=draw(st.integers(0, 2**32)))
        arrays = {k: scene[k].copy() for k in ARRAYS}
        camera = scene["camera"]
        scale = draw(st.sampled_from([1e-150, 1e-6, 1.0, 1.0, 1e6, 1e150]))
        arrays["points3d"] *= scale
        arrays["lines3d"] *= scale
        noise = draw(st.sampled_from([0.0, 0.0, 0.5, 5.0, 1e3]))
        rng = np.random.default_rng(draw(st.integers(0, 2**32)))
        arrays["points2d"] += rng.normal(0, noise, arrays["points2d"].shape)
        arrays["lines2d"] += rng.normal(0, noise, arrays["lines2d"].shape)
        damage = draw(st.sampled_from(["none", "collinear", "coincident", "zero-segment", "long-segment", "nan",
                                       "outliers", "coplanar", "huge"]))
        if damage == "collinear" and n:
            arrays["points3d"] = arrays["points3d"][:1] + np.outer(np.arange(n), [1.0, 0.5, 0.25]) * scale
        elif damage == "coincident" and n:
            arrays["points3d"][:] = arrays["points3d"][0]
        elif damage == "zero-segment" and m:
            arrays["lines2d"][0, 1] = arrays["lines2d"][0, 0]
        elif damage == "long-segment" and m:
            arrays["lines2d"][0, 1] += 1e300
        elif damage == "nan" and n:
            arrays["points2d"][n // 2, 1] = np.nan
        elif damage == "outliers" and n:
            arrays["points2d"][: n // 2] = rng.uniform(0, 640, (n // 2, 2))
        elif damage == "coplanar":
            arrays["points3d"][:, 2] = 0.0
        elif damage == "huge" and n:
            arrays["points3d"][0] = 1e200
        note(f"scene {kind} n={n} m={m} scale={scale} noise={noise} damage={damage}")
        return camera, arrays, True
    camera = draw(st.sampled_from(CAMERAS))
    n, m = draw(st.integers(0, 8)), draw(st.integers(0, 4))
    arrays = {k: draw(array_likes((n if k.startswith("points") else m, *ROWS[k]))) for k in ARRAYS}
    return camera, arrays, False


POSE_FIELDS = ["penalty", "sigma_px", "ambiguity_threshold"]
#: Fields of the refinement's stopping tests (``options.refinement.stopping``), nested as in the core.
STOPPING_FIELDS = ["step_tolerance"]
CERTIFY_FIELDS = ["max_relative_gap", "max_nodes"]
RANSAC_FIELDS = ["seed", "min_inliers", "point_threshold", "confidence", "time_budget", "max_iterations"]
INTEGER_FIELDS = {"seed", "min_inliers", "max_iterations",
                  "max_nodes"}


@given(pose_problems(), st.sampled_from(pluecker.METHODS), st.booleans(), st.booleans(),
       st.dictionaries(st.sampled_from(POSE_FIELDS + RANSAC_FIELDS + CERTIFY_FIELDS + STOPPING_FIELDS), st.one_of(reals(), integers()),
                       max_size=2))
def test_estimate_pose(problem, method, robust, certify, fields):
    camera, arrays, well_typed = problem
    for key in ("max_iterations", "max_nodes"):
        if isinstance(fields.get(key), int) and fields[key] > 10**4:
            fields[key] = 10**4  # a valid but huge cap only costs time
    if isinstance(fields.get("time_budget"), float) and fields["time_budget"] > 1.0:
        fields["time_budget"] = 1.0
    note(f"fields={fields}")
    typed = well_typed and not any(k in INTEGER_FIELDS and isinstance(v, float) for k, v in fields.items())

    def run():
        certify_options = pluecker.CertifyOptions(**{k: v for k, v in fields.items() if k in CERTIFY_FIELDS})
        options = pluecker.PoseOptions(certify=certify_options if certify else None,
                                       **{k: v for k, v in fields.items() if k in POSE_FIELDS})
        stopping = {k: v for k, v in fields.items() if k in STOPPING_FIELDS}
        if stopping:
            options.refinement.stopping = pluecker.StoppingCriteria(**stopping)
        ransac = pluecker.RansacOptions(**{k: v for k, v in fields.items() if k in RANSAC_FIELDS})
        options.ransac = ransac if robust else None
        if method is not None:
            options.method = method
        return pluecker.estimate_pose(camera, **arrays, options=options)

    result = outcome(run, type_error_ok=not typed)
    if isinstance(result, pluecker.PoseResult):
        check_pose(result)


@given(pose_problems(), rotations(), array_likes((3,)), st.one_of(reals(), st.booleans()))
def test_reprojection_errors_and_covariance(problem, R, t, sigma):
    camera, arrays, _ = problem
    errors = outcome(lambda: pluecker.reprojection_errors(camera, R, t, **arrays))
    if isinstance(errors, np.ndarray):
        n = sum(len(np.asarray(arrays[k])) for k in ("points2d", "lines2d") if arrays[k] is not None)
        assert errors.shape == (n,)
    cov = outcome(lambda: pluecker.pose_covariance(camera, R, t, **arrays, sigma_px=sigma))
    if isinstance(cov, np.ndarray):
        assert cov.shape == (6, 6) and np.all(np.isfinite(cov)) and np.allclose(cov, cov.T)


# --- triangulation ---------------------------------------------------------------------------------------


def cameras_of(draw, views: int):
    """(views, 3, 4) cameras K [R | t], focal lengths of either sign, scaled by any non-zero factor;
    or wild arrays."""
    if draw(st.integers(0, 3)) == 0:
        return draw(array_likes((views, 3, 4))), False
    rng = np.random.default_rng(draw(st.integers(0, 2**32)))
    P = []
    for _ in range(views):
        f = rng.choice([-1.0, 1.0], 2) * rng.uniform(300, 2000, 2)
        K = np.array([[f[0], 0, 320], [0, f[1], 240], [0, 0, 1]])
        q = rng.normal(size=4)
        w, x, y, z = q / np.linalg.norm(q)
        R = np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                      [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                      [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])
        P.append(K @ np.hstack([R, rng.normal(0, 3, (3, 1))]) * rng.choice([-2.0, 1.0, 1.0, 1e-3]))
    return np.array(P), True


GAPS = st.one_of(st.none(), st.sampled_from([1e-6, 1e-3, 0.1, 0.0, -1.0, np.nan, True]))
NODES = st.one_of(st.none(), st.integers(-2, 30), st.sampled_from([2**64, True]))
THRESHOLDS = st.one_of(st.none(), st.sampled_from([0.5, 10.0, 0.0, np.inf]))
METHODS = st.sampled_from(["linear", "local", "optimal", "best"])


def gap_of(gap) -> float:
    return gap if isinstance(gap, float) and not isinstance(gap, bool) and gap > 0 else 1e-3


@st.composite
def point_problems(draw):
    views = draw(st.integers(1, 4))
    P, typed = cameras_of(draw, views)
    x = draw(st.one_of(float_arrays((views, 2)), float_arrays((views, 2)), array_likes((views, 2))))
    cov = draw(st.one_of(st.none(), st.none(), float_arrays((views, 2, 2)).map(lambda c: c @ np.swapaxes(c, 1, 2)),
                         array_likes((views, 2, 2))))
    return P, x, cov


@given(point_problems(), METHODS, GAPS, THRESHOLDS, NODES)
def test_triangulate_point(problem, method, gap, threshold, nodes):
    P, x, cov = problem
    r = outcome(lambda: pluecker.triangulate_point(P, x, cov, options=pluecker.TriangulationOptions(method=method, certify=pluecker.CertifyOptions(max_relative_gap=gap, max_nodes=nodes), outlier_threshold=threshold)))
    if isinstance(r, pluecker.PointTriangulation):
        check_report(r, gap_of(gap))
        # No consensus of views is a status of the robust point only.
        assert r.status != "too_few_inliers" or threshold is not None, r
        if (r.status == "success"):
            assert np.all(np.isfinite(r.point))


@given(point_problems(), st.integers(0, 4), METHODS, NODES, st.data())
def test_triangulate_points(problem, n, method, nodes, data):
    P, x, cov = problem
    views = len(np.asarray(P)) if isinstance(P, np.ndarray) and P.ndim == 3 else 2
    xs = data.draw(st.one_of(float_arrays((n, views, 2)), array_likes((n, views, 2))))
    visible = data.draw(st.one_of(st.none(), st.just(np.ones((n, views), bool)),
                                  array_likes((n, views)).map(lambda a: a if not isinstance(a, np.ndarray)
                                                              else (a != 0) if a.dtype.kind == "f" else a)))
    covs = data.draw(st.one_of(st.none(), float_arrays((n, views, 2, 2))))
    batch = outcome(lambda: pluecker.triangulate_points(P, xs, visible, covs, options=pluecker.TriangulationOptions(method=method, certify=pluecker.CertifyOptions(max_nodes=nodes))))
    if isinstance(batch, pluecker.PointTriangulations):
        check_batch(batch, n)
        X = batch.point
        assert X.shape == (n, 3) and np.all(np.isfinite(X[np.asarray(batch.status) == "success"]))


@st.composite
def line_problems(draw):
    views = draw(st.integers(1, 4))
    P, _ = cameras_of(draw, views)
    if draw(st.booleans()):
        lines = draw(st.one_of(float_arrays((views, 3)), array_likes((views, 3))))
    else:
        lines = draw(st.one_of(float_arrays((views, 2, 2)), array_likes((views, 2, 2))))
    cov = draw(st.one_of(st.none(), st.none(), float_arrays((views, 2, 2)).map(lambda c: c @ np.swapaxes(c, 1, 2))))
    sigma = draw(st.one_of(st.none(), st.none(), reals(), st.just(True)))
    return P, lines, cov, sigma


@given(line_problems(), METHODS, GAPS, NODES)
def test_triangulate_line(problem, method, gap, nodes):
    P, lines, cov, sigma = problem
    r = outcome(lambda: pluecker.triangulate_line(P, lines, cov, sigma=sigma, options=pluecker.TriangulationOptions(method=method, certify=pluecker.CertifyOptions(max_relative_gap=gap, max_nodes=nodes))))
    if isinstance(r, pluecker.LineTriangulation):
        check_report(r, gap_of(gap))
        if (r.status == "success"):
            assert np.all(np.isfinite(r.plucker)) and np.isclose(np.linalg.norm(r.direction), 1.0)


@given(line_problems(), st.integers(0, 3), METHODS, st.data())
def test_triangulate_lines(problem, n, method, data):
    P, lines, cov, sigma = problem
    views = len(P) if isinstance(P, np.ndarray) and P.ndim == 3 else 2
    tail = data.draw(st.sampled_from([(3,), (2, 2)]))
    batch_lines = data.draw(st.one_of(float_arrays((n, views, *tail)), array_likes((n, views, *tail))))
    visible = data.draw(st.one_of(st.none(), array_likes((n, views)).map(
        lambda a: (a != 0) if isinstance(a, np.ndarray) and a.dtype.kind == "f" else a)))
    batch = outcome(lambda: pluecker.triangulate_lines(P, batch_lines, visible, sigma=sigma, options=pluecker.TriangulationOptions(method=method, certify=pluecker.CertifyOptions(max_nodes=30))))
    if isinstance(batch, pluecker.LineTriangulations):
        check_batch(batch, n)


@st.composite
def quadric_problems(draw):
    views = draw(st.integers(2, 4))
    P, typed = cameras_of(draw, views)
    if typed and draw(st.booleans()):
        # Outlines of a random ellipsoid (any position: in front, across or behind the cameras).
        rng = np.random.default_rng(draw(st.integers(0, 2**32)))
        A = rng.normal(size=(3, 3)) * draw(st.sampled_from([1e-3, 0.5, 2.0, 1e3]))
        T = np.eye(4)
        T[:3, :3] = A
        T[:3, 3] = rng.normal(0, 5, 3)
        dual = T @ np.diag([1.0, 1.0, 1.0, -1.0]) @ T.T
        conics = np.stack([np.linalg.pinv(p @ dual @ p.T) for p in P])
        conics = conics + rng.normal(0, draw(st.sampled_from([0.0, 1e-9, 1e-3])), conics.shape) * np.abs(conics).max()
    else:
        conics = draw(array_likes((views, 3, 3)))
    cov = draw(st.one_of(st.none(), st.none(), float_arrays((views, 5, 5)).map(lambda c: c @ np.swapaxes(c, 1, 2))))
    return P, conics, cov


@given(quadric_problems(), METHODS, GAPS, st.one_of(st.none(), st.integers(1, 20)))
def test_triangulate_quadric(problem, method, gap, nodes):
    P, conics, cov = problem
    r = outcome(lambda: pluecker.triangulate_quadric(P, conics, cov, options=pluecker.TriangulationOptions(method=method, certify=pluecker.CertifyOptions(max_relative_gap=gap, max_nodes=nodes))))
    if isinstance(r, pluecker.QuadricTriangulation):
        check_report(r, gap_of(gap))
        if (r.status == "success"):
            assert np.all(np.isfinite(r.centre)) and np.all(np.isfinite(r.Q))


@given(quadric_problems(), st.integers(0, 3), METHODS, st.data())
def test_triangulate_quadrics(problem, n, method, data):
    P, conics, cov = problem
    if isinstance(P, np.ndarray) and P.ndim == 3:
        views = len(P)
        one = np.asarray(conics) if isinstance(conics, np.ndarray) and conics.dtype.kind == "f" \
            and conics.shape == (views, 3, 3) else np.zeros((views, 3, 3))
        stack = np.repeat(one[None], n, axis=0)
    else:
        stack = data.draw(array_likes((n, 2, 3, 3)))
    batch = outcome(lambda: pluecker.triangulate_quadrics(P, stack, options=pluecker.TriangulationOptions(method=method, certify=pluecker.CertifyOptions(max_nodes=10))))
    if isinstance(batch, pluecker.QuadricTriangulations):
        check_batch(batch, n)


# --- fitting ----------------------------------------------------------------------------------------------


@st.composite
def edge_points(draw):
    """Points on a line or an ellipse (any size and position, noisy), or wild arrays."""
    n = draw(st.integers(0, 40))
    if draw(st.booleans()):
        return draw(array_likes((n, 2)))
    rng = np.random.default_rng(draw(st.integers(0, 2**32)))
    size = draw(st.sampled_from([1e-150, 1e-3, 1.0, 100.0, 1e6, 1e150]))
    offset = draw(st.sampled_from([0.0, 1e3, 1e12, 1e200]))
    s = np.linspace(0, 2 * np.pi, n, endpoint=False)
    if draw(st.booleans()):
        pts = np.c_[np.cos(s), draw(st.sampled_from([1.0, 0.3, 1e-3, 0.0])) * np.sin(s)] * size
    else:
        pts = np.c_[s, 0.5 * s] * size
    return pts + offset + rng.normal(0, draw(st.sampled_from([0.0, 1e-3, 1.0])) * size, pts.shape)


@given(edge_points(), st.one_of(reals(), st.just(True)))
def test_fit_line_and_conic(points, sigma):
    fit = outcome(lambda: pluecker.fit_line(points, sigma=sigma))
    if isinstance(fit, pluecker.FittedLine):
        assert np.all(np.isfinite(fit.line)) and np.isclose(np.linalg.norm(fit.line[:2]), 1.0)
        assert np.all(np.isfinite(fit.covariance)) and np.isfinite(fit.rms_distance)
        check_strict_json_and_pickle(fit)
    fit = outcome(lambda: pluecker.fit_conic(points, sigma=sigma))
    if isinstance(fit, pluecker.FittedConic):
        assert np.all(np.isfinite(fit.conic)) and np.all(fit.semi_axes > 0)
        assert np.all(np.isfinite(fit.covariance))
        check_strict_json_and_pickle(fit)


@given(st.one_of(st.integers(-1, 3), st.sampled_from([2**64, True])), st.one_of(reals(), st.just(True)),
       st.one_of(reals(), st.just(False)), integers())
def test_fitting_residual_samples(draws, size, sigma, seed):
    out = outcome(lambda: pluecker.fitting_residual_samples(draws, size=size, sigma=sigma, seed=seed),
                  type_error_ok=False)
    if isinstance(out, dict):
        assert out["line"].shape == (draws, 2) and out["conic"].shape == (draws, 5)


def test_the_error_check_rejects_internal_errors():
    try:
        hooks._panic_for_tests("boom")
    except pluecker.PlueckerError as error:
        try:
            check_error(error)
        except AssertionError:
            return
    raise AssertionError("check_error accepted an internal error")


RIG_CAMERAS = [pluecker.Camera("OPENCV", [600.0, 610.0, 320.0, 240.0, -0.1, 0.01, 1e-3, -1e-3]),
               pluecker.Camera("SIMPLE_RADIAL", [500.0, 320.0, 240.0, 0.05])]


def camera_indices(rows: int, cameras: int) -> st.SearchStrategy:
    """Mostly one valid camera index per row; sometimes out of range, negative, huge, fractional, the
    wrong length, or not indices at all."""
    valid = st.lists(st.integers(0, cameras - 1), min_size=rows, max_size=rows).map(np.array)
    return st.one_of(valid, valid, valid, st.none(),
                     st.lists(integers(), min_size=rows, max_size=rows).map(lambda v: np.array(v, dtype=object)),
                     st.lists(st.integers(-2, cameras + 2), min_size=0, max_size=rows + 2).map(np.array),
                     array_likes((rows,)))


@given(pose_problems(), st.integers(1, 3), st.booleans(), st.data())
def test_estimate_pose_of_a_rig(problem, cameras, robust, data):
    """A rig of the problem's camera (at the identity) and up to two lens cameras beside it, with any
    camera indices: a documented error or a consistent result, never a crash."""
    camera, arrays, well_typed = problem
    rig = pluecker.Rig([camera, *RIG_CAMERAS][:cameras],
                       [(np.eye(3), np.zeros(3)), (np.eye(3), np.array([0.2, 0.0, 0.0])),
                        (np.eye(3), np.array([0.0, -0.1, 0.05]))][:cameras])
    rows = {k: len(v) if isinstance(v, np.ndarray) and v.ndim >= 1 else 0 for k, v in arrays.items()}
    point_cameras = data.draw(camera_indices(rows["points2d"], cameras), label="point_cameras")
    line_cameras = data.draw(camera_indices(rows["lines2d"], cameras), label="line_cameras")
    options = pluecker.PoseOptions(ransac=pluecker.RansacOptions(max_iterations=200) if robust else None)
    result = outcome(lambda: pluecker.estimate_pose(rig, **arrays, point_cameras=point_cameras,
                                                    line_cameras=line_cameras, options=options))
    if isinstance(result, pluecker.PoseResult):
        check_pose(result)
