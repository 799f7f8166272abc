"""Defaults and properties are declared once (issue 11 §1, §3): in Rust, by each options struct's
``Default`` and each result's field table (crates/pluecker-py/src/properties.rs). Everything else is
derived from them and checked here: the stub ``_core.pyi``, the functions' signatures, the options
classes' behaviour."""

from __future__ import annotations

import copy
import inspect
import pickle

import numpy as np
import pytest

import pluecker
from pluecker import _core, _stubgen

OPTIONS = [pluecker.PoseOptions, pluecker.RansacOptions, pluecker.TriangulationOptions]


def test_the_stub_is_generated_from_the_tables():
    """``python -m pluecker._stubgen`` has been run: every generated block is what the tables say."""
    text = _stubgen.STUB.read_text(encoding="utf-8")
    assert _stubgen.render(text) == text, "run: python -m pluecker._stubgen"
    for name in _stubgen.classes_with_fields():
        assert f"# fields of {name} (generated" in text, f"{name} has no generated block in _core.pyi"


def test_no_function_writes_a_default_of_its_own():
    """A default written in a pyo3 signature drifts from Rust's (Python's ``max_iterations=200`` once also
    capped Newton, which Rust caps at 50): every default of the module's functions is None, resolved in Rust."""
    for name, obj in vars(_core).items():
        if name.startswith("_") or not callable(obj) or isinstance(obj, type):
            continue
        for p in inspect.signature(obj).parameters.values():
            assert p.default in (inspect.Parameter.empty, None), f"{name}({p.name}={p.default!r})"


@pytest.mark.parametrize("cls", OPTIONS)
def test_options_round_trip(cls):
    default = cls()
    assert cls(**default.to_dict()) == default
    assert pickle.loads(pickle.dumps(default)) == default
    assert copy.deepcopy(default) == default
    assert repr(default).startswith(f"{cls.__name__}(") and all(f"{n}=" in repr(default) for n, _, _ in cls.__fields__)
    with pytest.raises(TypeError, match=f"{cls.__name__}\\(\\) got an unexpected keyword argument 'nope'"):
        cls(nope=1)


@pytest.mark.parametrize("cls, field, value", [
    (pluecker.PoseOptions, "penalty", 7.5), (pluecker.PoseOptions, "method", "newton"),
    (pluecker.PoseOptions, "sigma_px", 0.5), (pluecker.RansacOptions, "seed", 12),
    (pluecker.RansacOptions, "time_budget", 0.25), (pluecker.TriangulationOptions, "line_bound", "relaxation"),
    (pluecker.TriangulationOptions, "outlier_threshold", 3.0),
])
def test_an_option_set_is_kept_and_compared(cls, field, value):
    options = cls(**{field: value})
    assert getattr(options, field) == value
    assert options != cls()
    again = cls()
    setattr(again, field, value)
    assert again == options and pickle.loads(pickle.dumps(options)) == options


def test_a_rejected_value_leaves_the_options_unchanged():
    options = pluecker.RansacOptions(seed=3)
    with pytest.raises(pluecker.InvalidOptionError, match="confidence"):
        options.confidence = 1.5
    assert options == pluecker.RansacOptions(seed=3)
    with pytest.raises(pluecker.InvalidOptionError):
        pluecker.RansacOptions(seed=4, confidence=2.0)


def test_no_options_means_the_default_options():
    """The functions' own default (``options=None``) is the class's default, bit for bit."""
    scene = pluecker.random_scene("general", 12, 3, seed=5)
    data = (scene["camera"], scene["points2d"] + 0.3, scene["points3d"], scene["lines2d"], scene["lines3d"])
    a = pluecker.estimate_pose(*data)
    b = pluecker.estimate_pose(*data, options=pluecker.PoseOptions())
    assert np.array_equal(a.pose.rotation, b.pose.rotation) and np.array_equal(a.pose.translation, b.pose.translation) and a.iterations == b.iterations
    robust = pluecker.estimate_pose(*data, options=pluecker.PoseOptions(ransac=pluecker.RansacOptions()))
    explicit = pluecker.estimate_pose(*data, options=pluecker.PoseOptions(ransac=pluecker.RansacOptions()))
    assert np.array_equal(robust.pose.rotation, explicit.pose.rotation)
    assert robust.details.ransac.iterations == explicit.details.ransac.iterations
    K = scene["camera"].K
    P = np.stack([K @ np.hstack([np.eye(3), [[-b], [0.0], [0.0]]]) for b in (0.0, 0.5)])
    x = np.array([[320.5, 240.2], [241.0, 240.4]])
    p = pluecker.triangulate_point(P, x)
    q = pluecker.triangulate_point(P, x, options=pluecker.TriangulationOptions())
    assert np.array_equal(p.point, q.point) and p.method == q.method == pluecker.TriangulationOptions().method


def test_the_method_is_set_in_the_options_only():
    scene = pluecker.random_scene("general", 12, 0, seed=6)
    r = pluecker.estimate_pose(scene["camera"], scene["points2d"], scene["points3d"],
                               options=pluecker.PoseOptions(method="levenberg-marquardt"))
    assert r.method == "levenberg-marquardt"
    for keyword in ({"method": "newton"}, {"ransac": pluecker.RansacOptions()}):
        with pytest.raises(TypeError):
            pluecker.estimate_pose(scene["camera"], scene["points2d"], scene["points3d"], **keyword)


def test_camera_P_bridges_pose_and_triangulation():
    """``Camera.P(R, t)`` of two estimated poses triangulates the points the poses were estimated from."""
    scene = pluecker.random_scene("general", 20, 0, seed=8)
    cam = scene["camera"]
    P = cam.P(scene["R"], scene["t"])
    X = scene["points3d"][0]
    h = P @ np.append(X, 1.0)
    np.testing.assert_allclose(h[:2] / h[2], scene["points2d"][0], atol=1e-9)
    with pytest.raises(pluecker.InvalidOptionError, match="R: expected a rotation matrix"):
        cam.P(2 * np.eye(3), scene["t"])
