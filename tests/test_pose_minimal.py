"""The minimal solvers and the reprojection refinement called one by one (issue 11 §1), checked with
numpy: every returned pose is a rotation that explains its sample exactly, the true pose is among them,
and the refinement lands where the data put it."""

from __future__ import annotations

import numpy as np
import pytest

import pluecker

K = np.array([[800.0, 0.0, 320.0], [0.0, 780.0, 240.0], [0.0, 0.0, 1.0]])
CAMERA = pluecker.Camera.from_matrix(K)


def random_pose(rng):
    q = rng.normal(size=4)
    q /= np.linalg.norm(q)
    w, x, y, z = q
    R = np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                  [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                  [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])
    return R, rng.uniform(-0.5, 0.5, 3) + [0.0, 0.0, 6.0]


def world_points(rng, R, t, n):
    """``n`` world points whose camera-frame points lie in a box in front of the camera."""
    x_cam = rng.uniform([-1.5, -1.5, 4.0], [1.5, 1.5, 8.0], (n, 3))
    return (x_cam - t) @ R


def bearing(R, t, X):
    v = R @ X + t
    return v / np.linalg.norm(v)


def plane_normal(R, t, A, B):
    n = np.cross(R @ A + t, R @ B + t)
    return n / np.linalg.norm(n)


def assert_explains(poses, points=(), lines=()):
    """Every pose is a rotation, puts each point on its ray in front, and each line in its plane."""
    for R, t in poses:
        assert np.allclose(R @ R.T, np.eye(3), atol=1e-9) and np.linalg.det(R) > 0
        for y, X in points:
            v = R @ X + t
            assert v @ y > 0 and np.linalg.norm(np.cross(v, y)) < 1e-8 * np.linalg.norm(v)
        for n, (A, B) in lines:
            for E in (A, B):
                assert abs(n @ (R @ E + t)) < 1e-8 * np.linalg.norm(R @ E + t)


def contains(poses, R, t):
    return any(np.abs(P - R).max() < 1e-8 and np.linalg.norm(u - t) < 1e-8 * np.linalg.norm(t) for P, u in poses)


@pytest.mark.parametrize("trial", range(20))
def test_each_solver_returns_the_true_pose_among_exact_solutions(trial):
    rng = np.random.default_rng(1000 + trial)
    R, t = random_pose(rng)
    X = world_points(rng, R, t, 3)
    L = world_points(rng, R, t, 6).reshape(3, 2, 3)
    y = np.array([bearing(R, t, x) for x in X])
    n = np.array([plane_normal(R, t, A, B) for A, B in L])
    cases = {
        "p3p": (pluecker.p3p(y, X), list(zip(y, X)), []),
        "p2p1l": (pluecker.p2p1l(y[:2], X[:2], n[0], L[0]), list(zip(y[:2], X[:2])), [(n[0], L[0])]),
        "p1p2l": (pluecker.p1p2l(y[0], X[0], n[:2], L[:2]), [(y[0], X[0])], list(zip(n[:2], L[:2]))),
        "p3l": (pluecker.p3l(n, L), [], list(zip(n, L))),
    }
    for name, (poses, points, lines) in cases.items():
        assert len(poses) <= (8 if name == "p3l" else 4), name
        assert contains(poses, R, t), f"{name}, trial {trial}: {len(poses)} poses, none the truth"
        assert_explains(poses, points, lines)


def test_degenerate_samples_give_no_pose_or_exact_ones():
    """Collinear points leave P3P a one-parameter family; the solver returns only poses that still
    explain the sample (possibly none), never garbage or an error."""
    rng = np.random.default_rng(5)
    R, t = random_pose(rng)
    X = np.array([[0.0, 0.0, 0.0], [1.0, 1.0, 1.0], [2.0, 2.0, 2.0]]) * 0.3
    y = np.array([bearing(R, t, x) for x in X])
    poses = pluecker.p3p(y, X)
    assert_explains(poses, list(zip(y, X)))
    assert pluecker.p3l(np.zeros((3, 3)), rng.normal(size=(3, 2, 3))) == []


def test_bearings_and_plane_normals_from_pixels():
    rng = np.random.default_rng(7)
    pixels = rng.uniform([0, 0], [640, 480], (5, 2))
    rays = np.linalg.solve(K, np.c_[pixels, np.ones(5)].T).T
    np.testing.assert_allclose(CAMERA.bearings(pixels), rays / np.linalg.norm(rays, axis=1, keepdims=True), atol=1e-15)
    segments = rng.uniform([0, 0], [640, 480], (4, 2, 2))
    a = np.linalg.solve(K, np.c_[segments[:, 0], np.ones(4)].T).T
    b = np.linalg.solve(K, np.c_[segments[:, 1], np.ones(4)].T).T
    n = np.cross(a, b)
    n /= np.linalg.norm(n, axis=1, keepdims=True)
    got = CAMERA.plane_normals(segments)
    np.testing.assert_allclose(np.abs(np.sum(got * n, axis=1)), 1.0, atol=1e-12)
    segments[2, 1] = segments[2, 0]
    with pytest.raises(pluecker.DegenerateConfigurationError, match=r"segments\[2\]: zero-length"):
        CAMERA.plane_normals(segments)


def test_pixels_to_solver_to_pose_end_to_end():
    scene = pluecker.random_scene("general", 3, 3, seed=11)
    cam = scene["camera"]
    y = cam.bearings(scene["points2d"])
    n = cam.plane_normals(scene["lines2d"])
    assert contains(pluecker.p3p(y, scene["points3d"]), scene["R"], scene["t"])
    assert contains(pluecker.p3l(n, scene["lines3d"]), scene["R"], scene["t"])


@pytest.mark.parametrize("call, name", [
    (lambda: pluecker.p3p(np.ones((2, 3)), np.ones((3, 3))), "bearings"),
    (lambda: pluecker.p3p(np.ones((3, 3)), np.ones((3, 2))), "points"),
    (lambda: pluecker.p2p1l(np.ones((2, 3)), np.ones((2, 3)), np.ones(2), np.ones((2, 3))), "normal"),
    (lambda: pluecker.p1p2l(np.ones(3), np.ones(3), np.ones((2, 3)), np.ones((3, 2, 3))), "endpoints"),
    (lambda: pluecker.p3l(np.ones((3, 3)), np.ones((3, 3, 3))), "endpoints"),
])
def test_wrong_shapes_name_the_argument(call, name):
    with pytest.raises(pluecker.ShapeError, match=f"^{name}: expected shape"):
        call()


def test_non_finite_input_names_the_argument_and_row():
    y = np.eye(3)
    y[1, 0] = np.nan
    with pytest.raises(pluecker.NonFiniteError, match=r"^bearings: non-finite value \(NaN or inf\) in row 1"):
        pluecker.p3p(y, np.eye(3))


def test_refinement_reaches_the_noise_floor_from_a_perturbed_start():
    """With 1 px noise on 40 points the maximum-likelihood pose lies within a few times its standard
    deviation of the truth: the covariance at the truth (pose_covariance, σ = 1 px) gives that spread, and
    the refinement from a start 0.01 rad and 1 % off must reach a cost no larger than the refinement from
    the truth (the same minimum) and stay within 5 standard deviations of the truth."""
    rng = np.random.default_rng(3)
    scene = pluecker.random_scene("general", 40, 0, seed=3)
    cam, R, t = scene["camera"], scene["R"], scene["t"]
    x = scene["points2d"] + rng.normal(0.0, 1.0, scene["points2d"].shape)
    w = np.array([0.006, -0.005, 0.006])
    theta = np.linalg.norm(w)
    k = np.array([[0, -w[2], w[1]], [w[2], 0, -w[0]], [-w[1], w[0], 0]]) / theta
    R0 = (np.eye(3) + np.sin(theta) * k + (1 - np.cos(theta)) * k @ k) @ R
    t0 = t * 1.01
    R1, t1, stage = pluecker.refine_pose(cam, R0, t0, x, scene["points3d"])
    Rt, tt, at_truth = pluecker.refine_pose(cam, R, t, x, scene["points3d"])
    assert stage.name == "refinement" and stage.cost_kind == "reprojection"
    assert stage.final_cost <= at_truth.final_cost * (1 + 1e-9) + 1e-12
    cov = pluecker.pose_covariance(cam, R, t, x, scene["points3d"], sigma_px=1.0)
    sd = np.sqrt(np.diag(cov))
    dR = R1 @ R.T
    angle_error = np.array([dR[2, 1] - dR[1, 2], dR[0, 2] - dR[2, 0], dR[1, 0] - dR[0, 1]]) / 2
    assert np.all(np.abs(angle_error) < 5 * sd[:3]), (angle_error, sd[:3])
    assert np.all(np.abs(t1 - t) < 5 * sd[3:] + 5 * np.abs(R1 - R).max() * np.linalg.norm(t)), (t1 - t, sd[3:])
    R2, t2, again = pluecker.refine_pose(cam, R1, t1, x, scene["points3d"])
    assert np.abs(R2 - R1).max() < 1e-6 and np.linalg.norm(t2 - t1) < 1e-6 * np.linalg.norm(t1)
    with pytest.raises(pluecker.InvalidOptionError, match="R: expected a rotation matrix"):
        pluecker.refine_pose(cam, 2 * R, t, x, scene["points3d"])


def test_refinement_refuses_a_camera_that_distorts_by_name():
    """``refine_pose`` takes pinhole pixels: through a lens its cost would be the wrong one, so a camera
    that distorts is refused, naming the argument; the pinhole part of the same camera is accepted."""
    scene = pluecker.random_scene("general", 10, 0, seed=4)
    lens = pluecker.Camera("OPENCV", [800.0, 800.0, 320.0, 240.0, -0.1, 0.0, 0.0, 0.0])
    args = (scene["R"], scene["t"], scene["points2d"], scene["points3d"])
    with pytest.raises(pluecker.InvalidOptionError, match="'camera': a OPENCV camera distorts"):
        pluecker.refine_pose(lens, *args)
    R, t, stage = pluecker.refine_pose(lens.pinhole_part, *args)
    assert stage.name == "refinement" and np.all(np.isfinite(R)) and np.all(np.isfinite(t))
