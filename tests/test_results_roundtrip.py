"""Every result class exposed to Python (issue 10 §5): ``to_dict()`` is strict JSON (NaN and inf are
``null``) also for a failed result, and results survive ``pickle`` and ``copy.deepcopy`` exactly."""

from __future__ import annotations

import copy
import inspect
import json
import pickle

import numpy as np
import pytest

import pluecker

K = np.array([[800.0, 0, 320], [0, 800.0, 240], [0, 0, 1]])
P = np.stack([K @ np.hstack([np.eye(3), [[-b], [0.0], [0.0]]]) for b in (0.0, 0.5, 1.0)])


def project(X):
    h = P @ np.append(X, 1.0)
    return h[:, :2] / h[:, 2:]


def ellipsoid_outlines():
    """The outline conics of a sphere of radius 0.5 at (0.2, 0.1, 6) in the three cameras."""
    Q = np.diag([1.0, 1.0, 1.0, -0.25])
    T = np.eye(4)
    T[:3, 3] = [0.2, 0.1, 6.0]
    dual = T @ np.linalg.inv(Q) @ T.T
    return np.stack([np.linalg.inv(p @ dual @ p.T) for p in P])


def line_images():
    A, B = np.array([0.0, -0.5, 5.0]), np.array([0.3, 0.6, 6.0])
    return np.array([np.cross(p @ np.append(A, 1), p @ np.append(B, 1)) for p in P])


def results():
    """(name, result) of every result class, successful and failed ones."""
    scene = pluecker.random_scene("general", 12, 3, seed=4)
    cam = scene["camera"]
    out = []
    ok = pluecker.estimate_pose(cam, scene["points2d"], scene["points3d"], scene["lines2d"], scene["lines3d"], options=pluecker.PoseOptions(certify=pluecker.CertifyOptions()))
    out += [("pose", ok), ("pose-stage", ok.details.stages[-1]), ("pose-pose", ok.pose), ("pose-details", ok.details),
            ("pose-certificate", ok.certificate)]
    robust = pluecker.estimate_pose(cam, scene["points2d"], scene["points3d"], options=pluecker.PoseOptions(ransac=pluecker.RansacOptions(min_inliers=6)))
    out += [("pose-robust", robust), ("pose-ransac", robust.details.ransac)]
    lines2d = scene["lines2d"].copy()
    lines2d[0, 1] = lines2d[0, 0] + 1e300  # numerical failure: rms_error_px is inf
    failed = pluecker.estimate_pose(cam, scene["points2d"], scene["points3d"], lines2d, scene["lines3d"])
    assert failed.status == "numerical_failure"
    out.append(("pose-failed", failed))
    linear = pluecker.estimate_pose(cam, scene["points2d"], scene["points3d"], options=pluecker.PoseOptions(method="linear"))
    out.append(("pose-linear", linear))
    X = np.array([0.2, -0.1, 5.0])
    out.append(("point", pluecker.triangulate_point(P, project(X))))
    parallel = np.tile([[300.0, 200.0]], (3, 1))
    out.append(("point-at-infinity", pluecker.triangulate_point(P, parallel, options=pluecker.TriangulationOptions(method="linear"))))
    x = np.stack([project(X), parallel, project(X)])
    visible = np.array([[1, 1, 1], [1, 1, 1], [1, 0, 0]], dtype=bool)
    out.append(("points", pluecker.triangulate_points(P, x, visible)))
    out.append(("points-linear", pluecker.triangulate_points(P, x, visible, options=pluecker.TriangulationOptions(method="linear"))))
    line = pluecker.triangulate_line(P, line_images())
    out += [("line", line), ("line-certificate", line.certificate)]
    out.append(("lines", pluecker.triangulate_lines(P, np.stack([line_images(), np.zeros((3, 3))]))))
    out.append(("quadric", pluecker.triangulate_quadric(P, ellipsoid_outlines())))
    flat = np.tile(np.diag([1.0, 1.0, -100.0**2]), (3, 1, 1))
    out.append(("quadric-behind", pluecker.triangulate_quadric(P, flat, options=pluecker.TriangulationOptions(method="linear"))))
    out.append(("quadrics", pluecker.triangulate_quadrics(P, np.stack([ellipsoid_outlines(), flat]))))
    t = np.linspace(0, 100, 10)
    out.append(("fitted-line", pluecker.fit_line(np.c_[t, 0.5 * t + 0.01 * np.sin(t)])))
    angles = np.linspace(0, 2 * np.pi, 30, endpoint=False)
    out.append(("fitted-conic", pluecker.fit_conic(np.c_[100 + 40 * np.cos(angles), 80 + 20 * np.sin(angles)])))
    return out


RESULTS = results()


def test_every_result_class_is_covered():
    classes = {type(r).__name__ for _, r in RESULTS}
    exposed = {name for name in pluecker.__all__ if isinstance(getattr(pluecker, name), type)
               and not issubclass(getattr(pluecker, name), Exception) and not name.endswith("Options")
               and name not in {"Camera", "View", "Rig", "BatchReport", "TriangulationReport", "Status", "StoppingCriteria"}}
    assert exposed <= classes, exposed - classes


def fields(result) -> dict:
    """Every public property of a result, as plain values (arrays compared with NaN equal to NaN)."""
    out = {}
    for name in dir(type(result)):
        if name.startswith("_") or callable(getattr(type(result), name)):
            continue
        value = getattr(result, name)
        if isinstance(value, list) and value and hasattr(value[0], "to_dict"):
            value = [v.to_dict() for v in value]
        elif hasattr(value, "to_dict"):
            value = value.to_dict()
        out[name] = value
    return out


def assert_same(a, b, where=""):
    if isinstance(a, dict):
        assert isinstance(b, dict) and a.keys() == b.keys(), where
        for k in a:
            assert_same(a[k], b[k], f"{where}.{k}")
    elif isinstance(a, np.ndarray):
        assert isinstance(b, np.ndarray) and a.dtype == b.dtype and a.shape == b.shape, where
        if a.dtype.kind == "f":
            assert np.array_equal(a, b, equal_nan=True), where
        else:
            assert np.array_equal(a, b), where
    elif isinstance(a, float) and np.isnan(a):
        assert isinstance(b, float) and np.isnan(b), where
    elif isinstance(a, (list, tuple)):
        assert type(a) is type(b) and len(a) == len(b), where
        for i, (x, y) in enumerate(zip(a, b)):
            assert_same(x, y, f"{where}[{i}]")
    else:
        assert type(a) is type(b) and a == b, (where, a, b)


@pytest.mark.parametrize("name,result", RESULTS, ids=[n for n, _ in RESULTS])
def test_to_dict_has_exactly_the_properties(name, result):
    """Each property is declared once (crates/pluecker-py/src/properties.rs): its getter and its to_dict entry
    come from the same table entry, so the keys are the properties and the values agree."""
    cls = type(result)
    properties = {n for n in dir(cls) if not n.startswith("_")
                  and inspect.isgetsetdescriptor(inspect.getattr_static(cls, n))}
    d = result.to_dict()
    assert set(d) == properties, set(d) ^ properties
    assert d == strict(fields(result))


def strict(value):
    """``value`` as ``to_dict`` writes it: arrays and tuples as lists, NaN and inf as None."""
    if isinstance(value, dict):
        return {k: strict(v) for k, v in value.items()}
    if isinstance(value, np.ndarray):
        return strict(value.tolist())
    if isinstance(value, (list, tuple)):
        return [strict(v) for v in value]
    if isinstance(value, float) and not np.isfinite(value):
        return None
    return value


@pytest.mark.parametrize("name,result", RESULTS, ids=[n for n, _ in RESULTS])
def test_to_dict_is_strict_json(name, result):
    if not hasattr(result, "to_dict"):
        pytest.fail(f"{type(result).__name__} has no to_dict")
    d = result.to_dict()
    text = json.dumps(d, allow_nan=False)  # raises on NaN or inf
    assert json.loads(text) == d


def test_failed_results_have_null_where_they_had_nan():
    failed = dict(RESULTS)["pose-failed"]
    assert np.isinf(failed.details.rms_error_px) and failed.to_dict()["details"]["rms_error_px"] is None
    at_infinity = dict(RESULTS)["point-at-infinity"]
    d = at_infinity.to_dict()
    assert d["status"] == "at_infinity" and d["point"] == [None, None, None] and d["cost"] is None
    pose = dict(RESULTS)["pose-linear"]
    assert pose.certificate is None and pose.to_dict()["certificate"] is None


@pytest.mark.parametrize("protocol", [2, pickle.HIGHEST_PROTOCOL])
@pytest.mark.parametrize("name,result", RESULTS, ids=[n for n, _ in RESULTS])
def test_results_pickle_exactly(name, result, protocol):
    again = pickle.loads(pickle.dumps(result, protocol=protocol))
    assert type(again) is type(result)
    assert_same(fields(result), fields(again))
    assert repr(again) == repr(result)


@pytest.mark.parametrize("name,result", RESULTS, ids=[n for n, _ in RESULTS])
def test_results_deep_copy(name, result):
    for again in (copy.deepcopy(result), copy.copy(result)):
        assert type(again) is type(result)
        assert_same(fields(result), fields(again))


def test_a_pickle_from_another_version_or_corrupted_is_a_pluecker_error():
    import pluecker._core as core

    fn, (kind, data) = dict(RESULTS)["point"].__reduce__()
    assert fn is core._unpickle
    with pytest.raises(pluecker.PlueckerError, match="malformed"):
        core._unpickle(kind, data[:-3])
    with pytest.raises(pluecker.PlueckerError, match="malformed"):
        core._unpickle(kind, data + b"\0")
    other = data.replace(pluecker.__version__.encode(), b"9" * len(pluecker.__version__), 1)
    with pytest.raises(pluecker.PlueckerError, match="made by pluecker 9"):
        core._unpickle(kind, other)
    with pytest.raises(pluecker.PlueckerError, match="not a pluecker result class"):
        core._unpickle("Camera", data)
