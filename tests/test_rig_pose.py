"""``estimate_pose`` with a ``Rig``: the pose ``x_rig = R X_world + t`` from points and segments seen by
any of the rig's cameras. Poses are checked against the truth the data were projected from (numpy's
composition of the rig's and the cameras' poses), the one-camera case against ``estimate_pose`` with
the camera itself, and bad camera indices by the errors' names."""

from __future__ import annotations

import numpy as np
import pluecker
import pytest
from test_rig import CAMERAS, POSES, rotation


TRUTH = (rotation(0.3, -0.2, 1.1), np.array([0.4, -1.0, 0.7]))


def observe(rig: pluecker.Rig, points: list[int], segments: list[int], noise_px: float, seed: int):
    """``points[k]`` points and ``segments[k]`` segments in front of camera ``k`` (3-9 units deep, in
    its field of view), projected through it at ``TRUTH`` plus Gaussian noise: the arrays of
    ``estimate_pose`` and the camera of each row."""
    rng = np.random.default_rng(seed)
    R, t = TRUTH
    p2, p3, pc, l2, l3, lc = [], [], [], [], [], []

    def in_view(n: int) -> np.ndarray:
        x = np.column_stack([rng.uniform(-0.3, 0.3, n), rng.uniform(-0.25, 0.25, n), np.ones(n)])
        return x * rng.uniform(3.0, 9.0, (n, 1))

    for k, (camera, (Rk, tk)) in enumerate(zip(rig.cameras, rig.sensor_from_rig)):
        # x_cam = Rk (R X + t) + tk, so X = Rᵀ (Rkᵀ (x_cam − tk) − t).
        def world(x: np.ndarray, Rk: np.ndarray = Rk, tk: np.ndarray = tk) -> np.ndarray:
            return ((x - tk) @ Rk - t) @ R  # rows: Rᵀ (Rkᵀ (x − tk) − t)

        x = in_view(points[k])
        p2.append(camera.project(x) + noise_px * rng.standard_normal((points[k], 2)))
        p3.append(world(x))
        pc += [k] * points[k]
        a, b = in_view(segments[k]), in_view(segments[k])
        ends = np.stack([camera.project(a), camera.project(b)], axis=1)
        l2.append(ends + noise_px * rng.standard_normal(ends.shape))
        l3.append(np.stack([world(a + 0.3 * (b - a)), world(b + 0.2 * (b - a))], axis=1))
        lc += [k] * segments[k]
    return (np.concatenate(p2), np.concatenate(p3), np.array(pc), np.concatenate(l2).reshape(-1, 2, 2),
            np.concatenate(l3).reshape(-1, 2, 3), np.array(lc))


def rotation_error(Ra: np.ndarray, Rb: np.ndarray) -> float:
    return float(np.arccos(np.clip((np.trace(Ra.T @ Rb) - 1) / 2, -1, 1)))


def test_points_and_segments_through_three_lenses_give_the_rigs_pose():
    rig = pluecker.Rig(CAMERAS, POSES)
    p2, p3, pc, l2, l3, lc = observe(rig, [8, 8, 8], [3, 2, 3], 0.0, seed=1)
    r = pluecker.estimate_pose(rig, p2, p3, l2, l3, point_cameras=pc, line_cameras=lc)
    assert r.status == "success" and r.success
    R, t = r.pose
    assert rotation_error(R, TRUTH[0]) < 1e-8
    np.testing.assert_allclose(t, TRUTH[1], atol=1e-7)
    assert r.cost < 1e-10 and r.inliers_points.all() and r.inliers_lines.all()
    # With 1 px of noise: the covariance's predicted spread bounds the error (chi-square, 6 d.o.f.,
    # 99.9 %: 22.5), and the per-camera residuals average the noise.
    p2, p3, pc, l2, l3, lc = observe(rig, [20, 20, 20], [3, 3, 3], 1.0, seed=2)
    r = pluecker.estimate_pose(rig, p2, p3, l2, l3, point_cameras=pc, line_cameras=lc,
                               options=pluecker.PoseOptions(sigma_px=1.0))
    R, t = r.pose
    dR = R @ TRUTH[0].T
    omega = 0.5 * np.array([dR[2, 1] - dR[1, 2], dR[0, 2] - dR[2, 0], dR[1, 0] - dR[0, 1]])
    error = np.concatenate([omega, t - TRUTH[1]])
    assert r.covariance.shape == (6, 6)
    assert error @ np.linalg.solve(r.covariance, error) < 22.5
    assert 0.7 < r.details.rms_error_px < 1.3


def test_a_rig_of_one_camera_at_the_identity_is_the_camera():
    rig = pluecker.Rig(CAMERAS[1:2], POSES[:1])
    p2, p3, _, l2, l3, _ = observe(rig, [12], [2], 1.0, seed=3)
    options = pluecker.PoseOptions(certify=pluecker.CertifyOptions())
    ours = pluecker.estimate_pose(rig, p2, p3, l2, l3, options=options).to_dict()
    single = pluecker.estimate_pose(CAMERAS[1], p2, p3, l2, l3, options=options).to_dict()

    def timeless(d):
        if isinstance(d, dict):
            return {k: timeless(v) for k, v in d.items() if k != "time_seconds"}
        if isinstance(d, list):
            return [timeless(v) for v in d]
        return d

    assert timeless(ours) == timeless(single)
    assert ours["certificate"] is not None


def test_several_pinhole_cameras_are_certified_and_lenses_say_why_not():
    options = pluecker.PoseOptions(certify=pluecker.CertifyOptions())
    pinholes = [c for c in CAMERAS if c.model in ("PINHOLE", "SIMPLE_PINHOLE")]
    assert len(pinholes) >= 1
    rig = pluecker.Rig([pinholes[0]] * len(POSES), POSES)
    p2, p3, pc, l2, l3, lc = observe(rig, [6, 6, 6], [2, 2, 2], 1.0, seed=4)
    r = pluecker.estimate_pose(rig, p2, p3, l2, l3, point_cameras=pc, line_cameras=lc, options=options)
    assert r.status == "success" and r.certified
    assert r.certificate.kind == "sublevel_set" and r.certificate.raw_lower_bound <= r.cost * (1 + 1e-12)
    assert r.certificate.relative_gap <= 1e-3
    # With a lens among several cameras: the status says it, and the reason names the camera.
    rig = pluecker.Rig(CAMERAS, POSES)
    p2, p3, pc, *_ = observe(rig, [6, 6, 6], [0, 0, 0], 1.0, seed=4)
    r = pluecker.estimate_pose(rig, p2, p3, point_cameras=pc, options=options)
    assert r.status == "gap_not_closed" and not r.certified and r.certificate is None
    lens = next(k for k, c in enumerate(CAMERAS) if c.model not in ("PINHOLE", "SIMPLE_PINHOLE"))
    assert f"pinhole cameras; camera {lens} is" in r.details.uncertified_reason


def test_half_outliers_are_found_by_the_robust_rig_pose():
    rig = pluecker.Rig(CAMERAS, POSES)
    p2, p3, pc, *_ = observe(rig, [40, 40, 40], [0, 0, 0], 0.5, seed=5)
    rng = np.random.default_rng(6)
    outlier = np.arange(len(p2)) % 2 == 1
    p2 = p2.copy()
    p2[outlier] = rng.uniform([0, 0], [640, 480], (int(outlier.sum()), 2))
    options = pluecker.PoseOptions(ransac=pluecker.RansacOptions(seed=3))
    r = pluecker.estimate_pose(rig, p2, p3, point_cameras=pc, options=options)
    assert r.status == "success"
    assert (r.inliers_points != ~outlier).sum() <= 1
    assert rotation_error(r.pose.rotation, TRUTH[0]) < 5e-3
    again = pluecker.estimate_pose(rig, p2, p3, point_cameras=pc, options=options)
    np.testing.assert_array_equal(again.pose.rotation, r.pose.rotation)


def test_camera_indices_that_do_not_fit_are_refused_by_name_and_row():
    rig = pluecker.Rig(CAMERAS, POSES)
    p2, p3, pc, l2, l3, lc = observe(rig, [3, 3, 3], [1, 1, 1], 0.0, seed=7)
    bad = pc.copy()
    bad[5] = 3
    with pytest.raises(pluecker.ShapeError, match=r"point_cameras\[5\].*below 3"):
        pluecker.estimate_pose(rig, p2, p3, l2, l3, point_cameras=bad, line_cameras=lc)
    bad = pc.astype(float)
    bad[2] = -1
    with pytest.raises(pluecker.InvalidOptionError, match="point_cameras.*entry 2 is -1"):
        pluecker.estimate_pose(rig, p2, p3, l2, l3, point_cameras=bad, line_cameras=lc)
    with pytest.raises(pluecker.ShapeError, match="line_cameras.*one camera index per observation"):
        pluecker.estimate_pose(rig, p2, p3, l2, l3, point_cameras=pc, line_cameras=lc[:2])
    with pytest.raises(pluecker.ShapeError, match="point_cameras"):
        pluecker.estimate_pose(rig, p2, p3, l2, l3, line_cameras=lc)
    with pytest.raises(pluecker.InvalidOptionError, match="point_cameras: is for a Rig"):
        pluecker.estimate_pose(CAMERAS[0], p2, p3, point_cameras=pc)
    # The input arrays are left as they were.
    assert pc.tolist() == [0, 0, 0, 1, 1, 1, 2, 2, 2]


def test_each_frame_of_a_colmap_rig_is_localised_in_its_model():
    """``colmap.localize_in_model`` with the model's rig: every frame of a synthetic COLMAP rig of three
    lens models, from the matches of all its images (1 px of noise), lands within the covariance's
    reach of the frame's ``rig_from_world`` in the model."""
    pytest.importorskip("pycolmap")
    from pluecker import colmap, scenes

    cameras = [("PINHOLE", [500.0, 500.0, 320.0, 240.0]),
               ("OPENCV", [450.0, 455.0, 320.0, 240.0, -0.05, 0.01, 1e-3, -1e-3]),
               ("SIMPLE_RADIAL", [400.0, 320.0, 240.0, 0.02])]
    rec = scenes.colmap_rig_reconstruction(cameras, 640, 480, noise_px=1.0, seed=8, points=300, frames=4)
    (rig_id,) = rec.rigs
    rig = colmap.rig(rec, rig_id)
    colmap_rig = rec.rig(rig_id)
    order = [colmap_rig.ref_sensor_id.id, *sorted(s.id for s in colmap_rig.non_ref_sensors)]
    frames: dict[int, list] = {}
    for image in rec.images.values():
        frames.setdefault(image.frame_id, []).append(image)
    assert len(frames) == 4
    for frame_id, images in frames.items():
        xy, ids, which = [], [], []
        for image in images:
            for point2D in image.points2D:
                if point2D.has_point3D():
                    xy.append(point2D.xy)
                    ids.append(point2D.point3D_id)
                    which.append(order.index(image.camera_id))
        rigid, r = colmap.localize_in_model(rec, rig, np.array(xy), np.array(ids), point_cameras=np.array(which),
                                            options=pluecker.PoseOptions(sigma_px=1.0))
        assert r.status == "success" and rigid is not None, (frame_id, r.status)
        R_true, t_true = colmap.pose_from_rigid(rec.frame(frame_id).rig_from_world)
        R, t = r.pose
        dR = R @ R_true.T
        omega = 0.5 * np.array([dR[2, 1] - dR[1, 2], dR[0, 2] - dR[2, 0], dR[1, 0] - dR[0, 1]])
        error = np.concatenate([omega, t - t_true])
        # The model's points are exact and the pixels carry 1 px: chi-square, 6 d.o.f., 99.9 %.
        assert error @ np.linalg.solve(r.covariance, error) < 22.5, (frame_id, error)


def test_per_observation_covariances_weight_each_cameras_pixels():
    """Covariances through a rig: residuals in standard deviations (``sigma_px`` 1), and an observation
    with a huge variance stops mattering: the pose moves by less than with the same pixel wrong at unit
    variance."""
    rig = pluecker.Rig(CAMERAS, POSES)
    p2, p3, pc, *_ = observe(rig, [6, 6, 6], [0, 0, 0], 0.0, seed=9)
    p2 = p2.copy()
    p2[7] += [15.0, -10.0]  # one pixel off, in camera 1
    covariances = np.tile(np.eye(2), (len(p2), 1, 1))
    unweighted = pluecker.estimate_pose(rig, p2, p3, point_cameras=pc, point_covariances=covariances)
    covariances[7] *= 1e6
    weighted = pluecker.estimate_pose(rig, p2, p3, point_cameras=pc, point_covariances=covariances)
    assert weighted.details.sigma_px == 1.0 and unweighted.details.sigma_px == 1.0
    assert rotation_error(weighted.pose.rotation, TRUTH[0]) < 0.01 * rotation_error(unweighted.pose.rotation, TRUTH[0])
    with pytest.raises(pluecker.ShapeError, match="point_covariances"):
        pluecker.estimate_pose(rig, p2, p3, point_cameras=pc, point_covariances=covariances[:-1])
