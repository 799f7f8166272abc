"""The Python API of pluecker: recovery on noise-free scenes, result fields, helpers, stubs."""

from __future__ import annotations

import ast
import inspect
import json
import pickle
import threading
from pathlib import Path

import numpy as np
import pytest
from conftest import assert_pose_close, correspondences, project, rotation_error

import pluecker
import pluecker._core as core

# Noise-free data: the estimate is exact up to round-off, so 1e-8 leaves a wide margin over the
# ~1e-13 the solvers reach and would still catch any modelling error (which shows at >= 1e-4).
EXACT = 1e-8
ALGEBRAIC_METHODS = [m for m in pluecker.METHODS if m != "linear"]
TERMINATIONS = {
    "gradient_tolerance",
    "radius_tolerance",
    "cost_tolerance",
    "step_tolerance",
    "max_iterations",
    "singular_hessian",
    "non_finite_cost",
    "closed_form",
}
STATUSES = {"success", "not_converged", "numerical_failure", "behind_camera"}


def log_so3(r: np.ndarray) -> np.ndarray:
    """The rotation vector w with r = exp([w]x), for angles < pi."""
    angle = np.arccos(np.clip((np.trace(r) - 1.0) / 2.0, -1.0, 1.0))
    w = np.array([r[2, 1] - r[1, 2], r[0, 2] - r[2, 0], r[1, 0] - r[0, 1]])
    return w * (0.5 if angle < 1e-12 else angle / (2.0 * np.sin(angle)))


def quat_mul(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Hamilton product of (w, x, y, z) quaternions."""
    aw, av = a[0], a[1:]
    bw, bv = b[0], b[1:]
    return np.r_[aw * bw - av @ bv, aw * bv + bw * av + np.cross(av, bv)]


# --- recovery ------------------------------------------------------------------------------------


def test_methods_constant_lists_every_method_default_first():
    assert pluecker.METHODS[0] == "trust-region"
    assert set(pluecker.METHODS) == {
        "trust-region",
        "rotation-then-translation",
        "trust-region-exact",
        "newton",
        "levenberg-marquardt",
        "linear",
    }


@pytest.mark.parametrize("method", pluecker.METHODS)
def test_noise_free_points_recover_the_pose(method, seed):
    scene = pluecker.random_scene("general", 30, 0, seed=seed)
    result = pluecker.estimate_pose(scene["camera"], scene["points2d"], scene["points3d"], options=pluecker.PoseOptions(method=method))
    assert result.method == method
    assert result.status == "success", f"seed={seed}"
    assert (result.status == "success") is True
    assert_pose_close(result, scene["R"], scene["t"], EXACT, seed)
    assert result.details.rms_error_px < 1e-6


@pytest.mark.parametrize("method", pluecker.METHODS)
def test_noise_free_points_recover_the_pose_without_refinement(method, seed):
    # The algebraic estimators alone are exact on exact data (their cost is 0 at the truth).
    scene = pluecker.random_scene("general", 30, 0, seed=seed)
    result = pluecker.estimate_pose(scene["camera"], scene["points2d"], scene["points3d"], options=pluecker.PoseOptions(refine=False, method=method))
    assert "refinement" not in [s.name for s in result.details.stages]
    assert_pose_close(result, scene["R"], scene["t"], 1e-6, seed)


def test_linear_method_estimates_the_intrinsics(seed):
    scene = pluecker.random_scene("general", 30, 0, seed=seed)
    result = pluecker.estimate_pose(scene["camera"], scene["points2d"], scene["points3d"], options=pluecker.PoseOptions(method="linear"))
    cam, est = scene["camera"], result.details.estimated_camera
    assert isinstance(est, pluecker.Camera)
    # Intrinsics in pixels (f = 800): 1e-6 px is 1e-9 relative.
    np.testing.assert_allclose(est.K, cam.K, rtol=0, atol=1e-6, err_msg=f"seed={seed}")


@pytest.mark.parametrize("method", ALGEBRAIC_METHODS)
def test_noise_free_lines_only_recover_the_pose(method, seed):
    scene = pluecker.random_scene("general", 0, 10, seed=seed)
    assert scene["points2d"].shape == (0, 2) and scene["lines2d"].shape == (10, 2, 2)
    result = pluecker.estimate_pose(scene["camera"], lines2d=scene["lines2d"], lines3d=scene["lines3d"], options=pluecker.PoseOptions(method=method))
    assert result.status == "success", f"seed={seed}"
    assert_pose_close(result, scene["R"], scene["t"], EXACT, seed)


@pytest.mark.parametrize("method", pluecker.METHODS)
def test_noise_free_points_and_lines_recover_the_pose(method, seed):
    scene = pluecker.random_scene("general", 10, 5, seed=seed)
    result = pluecker.estimate_pose(scene["camera"], **correspondences(scene), options=pluecker.PoseOptions(method=method))
    assert result.status == "success", f"seed={seed}"
    assert_pose_close(result, scene["R"], scene["t"], EXACT, seed)


@pytest.mark.parametrize("kind", ["planar", "far"])
def test_other_scene_kinds_recover_the_pose(kind, seed):
    scene = pluecker.random_scene(kind, 20, 0, seed=seed)
    result = pluecker.estimate_pose(scene["camera"], scene["points2d"], scene["points3d"])
    assert result.status == "success", f"seed={seed}"
    assert_pose_close(result, scene["R"], scene["t"], 1e-6, seed)


@pytest.mark.parametrize("method", [m for m in ALGEBRAIC_METHODS if m != "newton"])
def test_paper_scene_with_its_negative_focal_length(method):
    scene = pluecker.paper_scene()
    cam = scene["camera"]
    assert (cam.fx, cam.fy, cam.cx, cam.cy) == (-1730.3, 1220.7, 243.8, 241.2)
    assert scene["points3d"].shape == (460, 3) and scene["points2d"].shape == (460, 2)
    # The scene's observations follow the documented projection convention.
    np.testing.assert_allclose(project(cam, scene["R"], scene["t"], scene["points3d"]), scene["points2d"], atol=1e-9)
    result = pluecker.estimate_pose(cam, scene["points2d"], scene["points3d"], options=pluecker.PoseOptions(method=method))
    assert result.status == "success"
    assert_pose_close(result, scene["R"], scene["t"], EXACT)
    # The paper's ground truth, section 5: angle 2.9512 rad, t = (2.627650, -11.006138, 77.479236) cm.
    assert result.pose.axis_angle()[1] == pytest.approx(2.9512, abs=1e-9)
    np.testing.assert_allclose(result.pose.translation, [2.627650, -11.006138, 77.479236], atol=1e-9)


@pytest.mark.parametrize("method", pluecker.METHODS)
def test_success_is_never_claimed_for_a_wrong_pose(method):
    """On noise-free data, the default pipeline's 'success' must mean the true pose."""
    scenes = [pluecker.paper_scene()] + [pluecker.random_scene(k, 12, 0, seed=s) for k in ("general", "far") for s in range(5)]
    for i, scene in enumerate(scenes):
        result = pluecker.estimate_pose(scene["camera"], scene["points2d"], scene["points3d"], options=pluecker.PoseOptions(method=method))
        if (result.status == "success"):
            assert result.details.rms_error_px < 1e-6, f"scene {i}: {result}"
            assert_pose_close(result, scene["R"], scene["t"], 1e-6, seed=f"scene {i}")


def test_newton_stop_at_r_zero_is_not_reported_as_success():
    """Plain Newton (the paper's baseline, which may diverge) stops on the paper scene at the
    stationary point r = 0 of the algebraic cost, whose pose is meaningless (~1e8 px error)."""
    scene = pluecker.paper_scene()
    result = pluecker.estimate_pose(scene["camera"], scene["points2d"], scene["points3d"], options=pluecker.PoseOptions(refine=False, method="newton"))
    assert (result.status == "success") is False or np.max(np.abs(result.pose.translation - scene["t"])) < 1e-6


def test_shared_fixture_matches_rust():
    """The fixture of crates/pluecker/tests/it/shared_fixture.rs, checked from Python.

    Same seed, same pinned values, same recovery tolerance: the generator and the solver must give
    the same answers on both sides of the binding.
    """
    scene = pluecker.random_scene("general", 12, 4, seed=2024)
    np.testing.assert_allclose(scene["t"], [-2.367385325682247, -0.8276321643515955, -0.5279960563202948], rtol=0, atol=1e-12)
    np.testing.assert_allclose(scene["points3d"][0], [2.8988763928469616, -7.2052549989512205, -2.916200958344869], rtol=0, atol=1e-12)
    np.testing.assert_allclose(scene["points2d"][0], [526.0136231263537, 181.72382603279056], rtol=0, atol=1e-9)
    np.testing.assert_allclose(scene["lines3d"][3, 1], [2.7386643955329504, -4.764093786434271, -2.609206889237841], rtol=0, atol=1e-12)
    np.testing.assert_allclose(scene["R"][0], [0.45397091542994217, -0.6369359292289596, 0.6230754609202178], rtol=0, atol=1e-12)
    for method in pluecker.METHODS:
        result = pluecker.estimate_pose(scene["camera"], **correspondences(scene), options=pluecker.PoseOptions(method=method))
        assert result.status == "success", method
        assert_pose_close(result, scene["R"], scene["t"], EXACT)


def test_random_scene_is_deterministic_and_in_front_of_the_camera(seed):
    a = pluecker.random_scene("general", 15, 3, seed=seed)
    b = pluecker.random_scene("general", 15, 3, seed=seed)
    c = pluecker.random_scene("general", 15, 3, seed=seed + 1)
    for key in ("R", "t", "points2d", "points3d", "lines2d", "lines3d"):
        np.testing.assert_array_equal(a[key], b[key])
    assert not np.array_equal(a["points3d"], c["points3d"])
    x_cam = a["points3d"] @ a["R"].T + a["t"]
    assert np.all(x_cam[:, 2] > 0)
    np.testing.assert_allclose(project(a["camera"], a["R"], a["t"], a["points3d"]), a["points2d"], atol=1e-9)
    ends = a["lines3d"].reshape(-1, 3)
    np.testing.assert_allclose(project(a["camera"], a["R"], a["t"], ends), a["lines2d"].reshape(-1, 2), atol=1e-9)
    assert a["lines3d"].shape == (3, 2, 3)


# --- options ----------------------------------------------------------------------------------------


@pytest.mark.parametrize("method", ALGEBRAIC_METHODS)
def test_iteration_cap_is_reported_as_not_converged(method, seed):
    scene = pluecker.random_scene("general", 30, 0, seed=seed)
    result = pluecker.estimate_pose(scene["camera"], scene["points2d"], scene["points3d"], options=pluecker.PoseOptions(trust_region={"stopping": {"max_iterations": 1}}, levenberg_marquardt={"stopping": {"max_iterations": 1}}, newton={"max_iterations": 1}, refine=False, method=method))
    assert result.details.stages[0].termination == "max_iterations"
    assert result.status == "not_converged"
    assert (result.status == "success") is False


def test_initial_pose_is_used(seed):
    # One iteration from the default starts cannot converge; from the true pose nothing is left to do,
    # and the user's start is one of the runs the pipeline picks the best answer from.
    scene = pluecker.random_scene("general", 20, 0, seed=seed)
    args = (scene["camera"], scene["points2d"], scene["points3d"])
    capped = pluecker.estimate_pose(*args, options=pluecker.PoseOptions(trust_region={"stopping": {"max_iterations": 1}}, levenberg_marquardt={"stopping": {"max_iterations": 1}}, newton={"max_iterations": 1}, refine=False))
    assert capped.status == "not_converged"
    result = pluecker.estimate_pose(*args, options=pluecker.PoseOptions(trust_region={"stopping": {"max_iterations": 1}}, levenberg_marquardt={"stopping": {"max_iterations": 1}}, newton={"max_iterations": 1}, refine=False, initial_pose=(scene["R"], scene["t"])))
    assert result.status == "success", f"seed={seed}"
    # Zero up to the round-off of the Gram-matrix form of the algebraic cost.
    assert result.details.stages[-1].cost_kind == "algebraic" and result.details.stages[-1].final_cost < 1e-12
    assert_pose_close(result, scene["R"], scene["t"], EXACT, seed)


def test_refinement_is_the_last_stage_and_reprojection_cost():
    scene = pluecker.random_scene("general", 20, 0, seed=3)
    result = pluecker.estimate_pose(scene["camera"], scene["points2d"], scene["points3d"], options=pluecker.PoseOptions(method="rotation-then-translation"))
    assert [s.name for s in result.details.stages] == ["rotation", "translation", "refinement"]
    assert [s.cost_kind for s in result.details.stages] == ["algebraic", "algebraic", "reprojection"]
    # Both Σ r² at the returned pose, one in the conditioned frame of the refinement (rounding 1e-9).
    assert result.cost == pytest.approx(result.details.stages[-1].final_cost, rel=1e-9)
    assert result.termination == result.details.stages[-1].termination
    assert result.iterations == sum(s.iterations for s in result.details.stages)


def test_penalty_and_normalize_are_passed_through(seed):
    scene = pluecker.random_scene("general", 20, 0, seed=seed)
    args = (scene["camera"], scene["points2d"], scene["points3d"])
    for kwargs in ({"penalty": 5.0}, {"penalty": 500.0}, {"normalize": False}):
        result = pluecker.estimate_pose(*args, options=pluecker.PoseOptions(**kwargs))
        assert_pose_close(result, scene["R"], scene["t"], EXACT, seed)
    # Without normalisation the algebraic stage sees a different cost, so a different path.
    a = pluecker.estimate_pose(*args, options=pluecker.PoseOptions(refine=False, normalize=True))
    b = pluecker.estimate_pose(*args, options=pluecker.PoseOptions(refine=False, normalize=False))
    assert a.details.stages[0].initial_cost != b.details.stages[0].initial_cost


def test_array_likes_are_accepted():
    scene = pluecker.random_scene("general", 10, 0, seed=4)
    lists = pluecker.estimate_pose(scene["camera"], scene["points2d"].tolist(), scene["points3d"].tolist())
    f32 = pluecker.estimate_pose(scene["camera"], scene["points2d"].astype(np.float32), scene["points3d"])
    strided = pluecker.estimate_pose(scene["camera"], np.asfortranarray(scene["points2d"]), scene["points3d"][::1])
    assert_pose_close(lists, scene["R"], scene["t"], EXACT)
    assert_pose_close(strided, scene["R"], scene["t"], EXACT)
    # float32 pixels carry ~3e-5 px of rounding: the pose moves by about that much, not more.
    assert_pose_close(f32, scene["R"], scene["t"], 1e-4)


def test_solves_from_several_threads_agree():
    scene = pluecker.random_scene("general", 50, 10, seed=9)
    expected = pluecker.estimate_pose(scene["camera"], **correspondences(scene))
    out: list = []

    def work():
        for _ in range(20):
            out.append(pluecker.estimate_pose(scene["camera"], **correspondences(scene)).pose.translation)

    threads = [threading.Thread(target=work) for _ in range(4)]
    for th in threads:
        th.start()
    for th in threads:
        th.join()
    assert len(out) == 80
    for t in out:
        np.testing.assert_array_equal(t, expected.pose.translation)


# --- results --------------------------------------------------------------------------------------


def test_result_fields_have_documented_types_and_shapes():
    scene = pluecker.random_scene("general", 20, 4, seed=5)
    r = pluecker.estimate_pose(scene["camera"], **correspondences(scene))
    axis, angle = r.pose.axis_angle()
    for value, shape in ((r.pose.rotation, (3, 3)), (r.pose.translation, (3,)), (r.pose.dual_quaternion(), (8,)),
                         (axis, (3,)), (r.pose.rotation_vector(), (3,))):
        assert isinstance(value, np.ndarray) and value.dtype == np.float64 and value.shape == shape, shape
    for value in (angle, r.cost, r.details.rms_error_px, r.time_seconds):
        assert isinstance(value, float), value
    assert isinstance(r.pose, pluecker.Pose) and isinstance(r.details, pluecker.PoseDetails)
    assert isinstance(r.iterations, int) and r.iterations >= 1
    assert isinstance(r.method, str) and r.method == "trust-region"
    assert r.termination in TERMINATIONS and r.status in STATUSES
    assert r.time_seconds >= 0.0
    assert r.details.estimated_camera is None
    # R is a rotation; axis and angle describe it (Rodrigues); the dual quaternion is unit and rigid.
    np.testing.assert_allclose(r.pose.rotation @ r.pose.rotation.T, np.eye(3), atol=1e-12)
    assert np.linalg.det(r.pose.rotation) == pytest.approx(1.0, abs=1e-12)
    assert np.linalg.norm(axis) == pytest.approx(1.0, abs=1e-12)
    assert 0.0 <= angle <= np.pi
    np.testing.assert_allclose(r.pose.rotation_vector(), angle * axis, atol=1e-15)
    k = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    rodrigues = np.eye(3) + np.sin(angle) * k + (1 - np.cos(angle)) * k @ k
    np.testing.assert_allclose(rodrigues, r.pose.rotation, atol=1e-12)
    R, t = r.pose
    assert R is not None and np.array_equal(R, r.pose.rotation) and np.array_equal(t, r.pose.translation)
    q = r.pose.dual_quaternion()
    assert np.linalg.norm(q[:4]) == pytest.approx(1.0, abs=1e-12) and abs(q[:4] @ q[4:]) < 1e-12
    assert q[0] >= 0.0
    for stage in r.details.stages:
        assert isinstance(stage, pluecker.PoseStage)
        assert isinstance(stage.name, str) and stage.cost_kind in ("algebraic", "reprojection")
        assert stage.rotation.shape == (3, 3) and stage.translation.shape == (3,)
        assert isinstance(stage.iterations, int) and stage.termination in TERMINATIONS
        assert stage.final_cost <= stage.initial_cost
        assert stage.time_seconds >= 0.0
    np.testing.assert_array_equal(r.details.stages[-1].rotation, r.pose.rotation)
    assert "PoseResult(" in repr(r) and "status='success'" in repr(r)
    assert "PoseStage(" in repr(r.details.stages[0])


def test_a_pose_is_accepted_where_a_pair_is():
    """``result.pose`` starts another estimate as ``(R, t)`` would, and unpacks into that pair."""
    scene = pluecker.random_scene("general", 10, 0, seed=6)
    r = pluecker.estimate_pose(scene["camera"], scene["points2d"], scene["points3d"])
    options = pluecker.PoseOptions(initial_pose=r.pose)
    R, t = options.initial_pose
    np.testing.assert_array_equal(R, r.pose.rotation)
    np.testing.assert_array_equal(t, r.pose.translation)
    assert options == pluecker.PoseOptions(initial_pose=tuple(r.pose))
    np.testing.assert_allclose(r.pose.centre(), -r.pose.rotation.T @ r.pose.translation, atol=1e-15)


def test_result_arrays_are_copies():
    scene = pluecker.random_scene("general", 10, 0, seed=6)
    r = pluecker.estimate_pose(scene["camera"], scene["points2d"], scene["points3d"])
    rot = r.pose.rotation
    rot[:] = 0.0
    assert np.linalg.det(r.pose.rotation) == pytest.approx(1.0)
    with pytest.raises(AttributeError):
        r.status = "success"  # frozen


def test_to_dict_is_json_serialisable_and_matches_the_attributes():
    scene = pluecker.random_scene("general", 20, 0, seed=7)
    r = pluecker.estimate_pose(scene["camera"], scene["points2d"], scene["points3d"], options=pluecker.PoseOptions(method="linear"))
    d = json.loads(json.dumps(r.to_dict()))
    np.testing.assert_array_equal(np.array(d["pose"]["rotation"]), r.pose.rotation)
    np.testing.assert_array_equal(np.array(d["pose"]["translation"]), r.pose.translation)
    for key in ("cost", "status", "certified", "method", "iterations", "termination", "time_seconds", "cost_kind"):
        assert d[key] == getattr(r, key), key
    details = d["details"]
    assert details["rms_error_px"] == r.details.rms_error_px
    assert [s["name"] for s in details["stages"]] == [s.name for s in r.details.stages]
    assert details["stages"][0] == json.loads(json.dumps(r.details.stages[0].to_dict()))
    cam = r.details.estimated_camera
    assert {k: details["estimated_camera"][k] for k in ("fx", "fy", "cx", "cy", "skew")} == \
        {"fx": cam.fx, "fy": cam.fy, "cx": cam.cx, "cy": cam.cy, "skew": cam.skew}
    # In to_dict (and the JSON) the estimated K is its five numbers, from which the Camera is rebuilt.
    assert details["estimated_camera"].keys() == {"fx", "fy", "cx", "cy", "skew"}
    np.testing.assert_array_equal(pluecker.Camera.pinhole(**details["estimated_camera"]).K, cam.K)
    other = pluecker.estimate_pose(scene["camera"], scene["points2d"], scene["points3d"]).to_dict()
    assert other["details"]["estimated_camera"] is None


# --- camera ---------------------------------------------------------------------------------------


def test_camera_from_matrix_round_trip_and_value_semantics():
    cam = pluecker.Camera.pinhole(-1730.3, 1220.7, 243.8, 241.2, skew=2.5)
    k = cam.K
    np.testing.assert_array_equal(k, [[-1730.3, 2.5, 243.8], [0.0, 1220.7, 241.2], [0.0, 0.0, 1.0]])
    back = pluecker.Camera.from_matrix(k)
    assert back == cam and hash(back) == hash(cam)
    np.testing.assert_allclose(pluecker.Camera.from_matrix(3.0 * k).K, k, rtol=1e-15, atol=1e-13)  # K is up to scale
    assert pluecker.Camera.from_matrix(k.tolist()) == cam
    assert cam != pluecker.Camera.pinhole(-1730.3, 1220.7, 243.8, 241.2)
    assert cam != "not a camera"
    assert (cam.fx, cam.fy, cam.cx, cam.cy, cam.skew) == (-1730.3, 1220.7, 243.8, 241.2, 2.5)
    assert eval(repr(cam), {"Camera": pluecker.Camera}) == cam
    assert pickle.loads(pickle.dumps(cam)) == cam
    assert len({cam, back}) == 1
    with pytest.raises(AttributeError):
        cam.fx = 1.0  # frozen


def test_camera_projection_and_normalisation_are_inverse(seed):
    rng = np.random.default_rng(seed)
    cam = pluecker.Camera.pinhole(-900.0, 850.0, 310.0, 250.0, skew=1.5)
    x_cam = np.c_[rng.uniform(-1, 1, (25, 2)), rng.uniform(2, 5, 25)]
    u = cam.project(x_cam)
    assert u.shape == (25, 2)
    homog = x_cam @ cam.K.T
    np.testing.assert_allclose(u, homog[:, :2] / homog[:, 2:], rtol=1e-13, err_msg=f"seed={seed}")
    np.testing.assert_allclose(cam.unproject(u), x_cam[:, :2] / x_cam[:, 2:], atol=1e-13)
    n = cam.unproject(u)
    np.testing.assert_allclose(cam.project(np.c_[n, np.ones(len(n))]), u, atol=1e-9)
    assert cam.project(np.empty((0, 3))).shape == (0, 2)


# --- covariance and reprojection errors -------------------------------------------------------------


def test_pose_covariance_is_symmetric_positive_definite_and_scales_with_sigma_squared():
    scene = pluecker.random_scene("general", 20, 3, seed=8)
    args = (scene["camera"], scene["R"], scene["t"])
    c1 = pluecker.pose_covariance(*args, **correspondences(scene))
    c2 = pluecker.pose_covariance(*args, **correspondences(scene), sigma_px=2.0)
    assert c1.shape == (6, 6) and c1.dtype == np.float64
    np.testing.assert_array_equal(c1, c1.T)
    assert np.all(np.linalg.eigvalsh(c1) > 0)
    np.testing.assert_allclose(c2, 4.0 * c1, rtol=1e-12)
    # More data, less uncertainty: adding the lines can only shrink the covariance (Loewner order).
    points_only = pluecker.pose_covariance(*args, scene["points2d"], scene["points3d"])
    assert np.min(np.linalg.eigvalsh(points_only - c1)) > -1e-9 * np.max(np.linalg.eigvalsh(c1))


@pytest.mark.parametrize("n_points,n_lines", [(20, 0), (6, 4)])
def test_pose_covariance_predicts_the_spread_of_noisy_estimates(n_points, n_lines, seed):
    """Monte Carlo: the ML estimate's covariance matches the Cramér-Rao bound at small noise."""
    scene = pluecker.random_scene("general", n_points, n_lines, seed=seed)
    sigma, trials = 0.5, 1500
    bound = pluecker.pose_covariance(scene["camera"], scene["R"], scene["t"], **correspondences(scene), sigma_px=sigma)
    rng = np.random.default_rng(seed)
    errors = []
    for _ in range(trials):
        noisy = correspondences(scene)
        noisy["points2d"] = scene["points2d"] + sigma * rng.standard_normal(scene["points2d"].shape)
        noisy["lines2d"] = scene["lines2d"] + sigma * rng.standard_normal(scene["lines2d"].shape)
        r = pluecker.estimate_pose(scene["camera"], **noisy)
        errors.append(np.r_[log_so3(r.pose.rotation @ scene["R"].T), r.pose.translation - scene["t"]])
    errors = np.array(errors)
    # Each variance estimate has a relative standard deviation sqrt(2 / trials) ~ 3.7 %; allow 5 sigma.
    ratio = np.diag(np.cov(errors.T)) / np.diag(bound)
    assert np.all(np.abs(ratio - 1.0) < 0.2), f"seed={seed} ratio={ratio}"
    # Squared Mahalanobis distances average 6 (chi-square, 6 dof; std of the mean 0.09).
    d2 = np.einsum("ij,jk,ik->i", errors, np.linalg.inv(bound), errors)
    assert abs(d2.mean() - 6.0) < 0.5, f"seed={seed} mean d2={d2.mean()}"


def test_reprojection_errors_vanish_at_the_truth_and_measure_pixels():
    scene = pluecker.random_scene("general", 8, 3, seed=10)
    args = (scene["camera"], scene["R"], scene["t"])
    e = pluecker.reprojection_errors(*args, **correspondences(scene))
    assert e.shape == (11,) and e.dtype == np.float64
    assert np.all(e < 1e-9)
    moved = correspondences(scene)
    moved["points2d"] = scene["points2d"].copy()
    moved["points2d"][2] += [3.0, 4.0]
    e = pluecker.reprojection_errors(*args, **moved)
    assert e[2] == pytest.approx(5.0, abs=1e-9)
    assert np.all(np.delete(e, 2) < 1e-9)
    # Sliding an image segment's endpoints along its own line leaves the line error at 0.
    slid = correspondences(scene)
    a, b = scene["lines2d"][0]
    slid["lines2d"] = scene["lines2d"].copy()
    slid["lines2d"][0] = [a + 0.3 * (b - a), b + 0.5 * (b - a)]
    assert pluecker.reprojection_errors(*args, **slid)[8] < 1e-9
    # Errors only from lines when there are no points.
    e = pluecker.reprojection_errors(*args, lines2d=scene["lines2d"], lines3d=scene["lines3d"])
    assert e.shape == (3,)


# --- dual quaternions -------------------------------------------------------------------------------


def test_dual_quaternion_helpers_round_trip_and_follow_eq_7(seed):
    rng = np.random.default_rng(seed)
    for _ in range(50):
        scene_r = pluecker.dual_quaternion_to_pose(np.r_[rng.standard_normal(4), np.zeros(4)])[0]
        t = 5.0 * rng.standard_normal(3)
        q = pluecker.pose_to_dual_quaternion(scene_r, t)
        assert q.shape == (8,)
        r, s = q[:4], q[4:]
        assert np.linalg.norm(r) == pytest.approx(1.0, abs=1e-12) and abs(r @ s) < 1e-12
        # s = 1/2 t r (eq. 7, with t the pure quaternion (0, t)).
        np.testing.assert_allclose(s, 0.5 * quat_mul(np.r_[0.0, t], r), atol=1e-12)
        r_back, t_back = pluecker.dual_quaternion_to_pose(q)
        np.testing.assert_allclose(r_back, scene_r, atol=1e-12, err_msg=f"seed={seed}")
        np.testing.assert_allclose(t_back, t, atol=1e-12)
        r_neg, t_neg = pluecker.dual_quaternion_to_pose(-q)
        np.testing.assert_allclose(r_neg, scene_r, atol=1e-12)
        np.testing.assert_allclose(t_neg, t, atol=1e-12)
        # A non-unit dual quaternion of the same motion: r is normalised first.
        r_scaled, t_scaled = pluecker.dual_quaternion_to_pose(3.0 * q)
        np.testing.assert_allclose(t_scaled, t, atol=1e-12)


def test_pose_to_screw_describes_the_motion(seed):
    rng = np.random.default_rng(seed)
    for _ in range(50):
        rot = pluecker.dual_quaternion_to_pose(np.r_[rng.standard_normal(4), np.zeros(4)])[0]
        t = 3.0 * rng.standard_normal(3)
        screw = pluecker.pose_to_screw(rot, t)
        assert set(screw) == {"d", "angle", "direction", "point"}
        d, angle, direction, point = screw["d"], screw["angle"], screw["direction"], screw["point"]
        assert np.linalg.norm(direction) == pytest.approx(1.0, abs=1e-12)
        assert abs(point @ direction) < 1e-9
        assert angle == pytest.approx(rotation_error(rot, np.eye(3)), abs=1e-9)
        # Points on the axis slide by d along it; the rotation turns about the direction.
        on_axis = point + 0.7 * direction
        np.testing.assert_allclose(rot @ on_axis + t, on_axis + d * direction, atol=1e-9, err_msg=f"seed={seed}")
        np.testing.assert_allclose(rot @ direction, direction, atol=1e-9)


# --- the stubs ------------------------------------------------------------------------------------


def _stub_tree() -> ast.Module:
    return ast.parse((Path(pluecker.__file__).parent / "_core.pyi").read_text())


def _public(names) -> set:
    return {n for n in names if not n.startswith("_") or n == "__version__"}


def _stub_args(fn: ast.FunctionDef) -> list:
    """(name, kind, default source) of a stub function's parameters, self and cls excluded."""
    a = fn.args
    positional = a.posonlyargs + a.args
    defaults = [None] * (len(positional) - len(a.defaults)) + [ast.unparse(d) for d in a.defaults]
    out = [(p.arg, "positional", d) for p, d in zip(positional, defaults)]
    out += [(p.arg, "keyword", None if d is None else ast.unparse(d)) for p, d in zip(a.kwonlyargs, a.kw_defaults)]
    return [x for x in out if x[0] not in ("self", "cls")]


def _runtime_args(obj) -> list:
    out = []
    for p in inspect.signature(obj).parameters.values():
        kind = "keyword" if p.kind is inspect.Parameter.KEYWORD_ONLY else "positional"
        default = None if p.default is inspect.Parameter.empty else repr(p.default)
        if p.name != "self":
            out.append((p.name, kind, default))
    return out


def test_stub_names_match_the_extension_module():
    tree = _stub_tree()
    stub_names = set()
    for node in tree.body:
        if isinstance(node, (ast.FunctionDef, ast.ClassDef)):
            stub_names.add(node.name)
        elif isinstance(node, ast.AnnAssign):
            stub_names.add(node.target.id)
    assert _public(stub_names) == _public(dir(core))
    # The package re-exports exactly the public names of the extension module, and adds the one enum
    # built from them (``Status``, from ``STATUSES``).
    assert set(pluecker.__all__) == _public(dir(core)) | {"Status"}


def test_status_members_are_the_cores_statuses():
    """``pluecker.Status`` is the core's list, in its order; a member is its name as a ``str``."""
    assert [s.value for s in pluecker.Status] == list(core.STATUSES)
    assert core.STATUSES[0] == "success" and "invalid_input" in core.STATUSES and "too_few_views" in core.STATUSES
    assert pluecker.Status.SUCCESS == "success" and f"{pluecker.Status.TOO_FEW_VIEWS}" == "too_few_views"
    assert str(pluecker.Status.INVALID_INPUT) == "invalid_input"


def test_the_package_namespace_holds_only_its_api():
    """Every public name of ``pluecker`` is in ``__all__`` or is one of its own submodules: an import of the
    package (``zlib``, loaded early for pycolmap's sake) does not become part of the API."""
    import types

    public = _public(dir(pluecker))
    own = {n for n in public if isinstance(getattr(pluecker, n), types.ModuleType)
           and getattr(pluecker, n).__name__ == f"pluecker.{n}"}
    assert public - own == set(pluecker.__all__)
    assert not [n for n in dir(pluecker) if "zlib" in n]  # not even as a private name


def test_stub_signatures_and_class_members_match_the_runtime():
    for node in _stub_tree().body:
        if not isinstance(node, (ast.FunctionDef, ast.ClassDef)) or node.name.startswith("_"):
            continue
        runtime = getattr(core, node.name)
        if isinstance(node, ast.FunctionDef):
            assert _stub_args(node) == _runtime_args(runtime), node.name
        elif isinstance(node, ast.ClassDef) and not issubclass(runtime, Exception):
            members = {m.name: m for m in node.body if isinstance(m, ast.FunctionDef)}
            properties = _public(m.target.id for m in node.body if isinstance(m, ast.AnnAssign))
            # Everything the stub lists exists; everything the class adds to its base is listed.
            base = runtime.__base__
            inherited = _public(dir(base)) if base is not object else set()
            assert _public(dir(runtime)) - inherited <= _public(members) | properties <= _public(dir(runtime)), node.name
            for name, member in members.items():
                if name == "__new__" and node.name.endswith("Options"):
                    # Options take keywords only, one per field, defaults from the Rust Default.
                    defaults = runtime().to_dict()
                    # Nested options (a dict in to_dict) are written `...` in the stub.
                    expected = [
                        (f, "keyword", "..." if isinstance(defaults[f], dict) else repr(defaults[f]))
                        for f, _, _ in runtime.__fields__
                    ]
                    assert _stub_args(member) == expected, node.name
                elif name == "__new__":
                    assert _stub_args(member) == _runtime_args(runtime), node.name
                elif not name.startswith("_") and callable(getattr(runtime, name)):
                    assert _stub_args(member) == _runtime_args(getattr(runtime, name)), f"{node.name}.{name}"
        elif isinstance(node, ast.ClassDef):
            bases = [ast.unparse(b) for b in node.bases]
            assert [b.__name__ for b in runtime.__bases__] == bases, node.name


def test_version_is_the_crate_version():
    assert isinstance(pluecker.__version__, str)
    assert pluecker.__version__.count(".") == 2
    from importlib.metadata import version

    assert version("pluecker") == pluecker.__version__


def test_triangulation_methods_are_exported_and_each_is_accepted():
    assert pluecker.TRIANGULATION_METHODS == ("linear", "local", "optimal")
    P = np.array([np.hstack([np.eye(3), [[c], [0.0], [5.0]]]) for c in (-1.0, 1.0)])
    X = np.array([0.1, -0.2, 1.0, 1.0])
    x = np.array([(p @ X)[:2] / (p @ X)[2] for p in P])
    for method in pluecker.TRIANGULATION_METHODS:
        assert pluecker.triangulate_point(P, x, options=pluecker.TriangulationOptions(method=method)).method == method
    with pytest.raises(pluecker.InvalidOptionError):
        pluecker.triangulate_point(P, x, options=pluecker.TriangulationOptions(method="best"))
