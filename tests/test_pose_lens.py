"""``estimate_pose`` with a ``Camera`` (distorted pixels) and with per-observation covariances
(issue 12 §1, §5). The pixels are made here with numpy from the truth; the checks are statistical
(normalised estimation error squared against the returned covariance) or exact identities."""

from __future__ import annotations

import numpy as np
import pytest

import pluecker

OPENCV = pluecker.Camera("OPENCV", [600.0, 600.0, 320.0, 240.0, -0.28, 0.07, 5e-4, -3e-4])
FISHEYE = pluecker.Camera("OPENCV_FISHEYE", [600.0, 600.0, 320.0, 240.0, 0.05, -0.02, 0.01, -0.002])


def rotation(rng: np.random.Generator) -> np.ndarray:
    q, r = np.linalg.qr(rng.normal(size=(3, 3)))
    q = q * np.sign(np.diag(r))
    return q * np.linalg.det(q)


def scene(rng: np.random.Generator, n_points: int = 30, n_lines: int = 4):
    """A pose and world structure at depths 4-8 inside a 640 x 480 view of f = 600 px."""
    R, t = rotation(rng), rng.normal(size=3)
    pixels = rng.uniform([0, 0], [640, 480], size=(n_points + 2 * n_lines, 2))
    rays = np.column_stack([(pixels - [320, 240]) / 600.0, np.ones(len(pixels))])
    X_cam = rays * rng.uniform(4, 8, size=(len(pixels), 1))
    X = (X_cam - t) @ R  # R^T (x - t)
    return R, t, X[:n_points], X[n_points:].reshape(n_lines, 2, 3)


def observe(lens, R, t, X, sigma, rng):
    u = lens.project(X.reshape(-1, 3) @ R.T + t)
    return u + rng.normal(size=u.shape) * sigma


def nees(result, R, t) -> float:
    dR = R @ result.pose.rotation.T
    angle = np.arccos(np.clip((np.trace(dR) - 1) / 2, -1, 1))
    axis = np.array([dR[2, 1] - dR[1, 2], dR[0, 2] - dR[2, 0], dR[1, 0] - dR[0, 1]])
    w = axis / (2 * np.sin(angle)) * angle if angle > 1e-12 else 0.5 * axis
    e = np.concatenate([w, t - result.pose.translation])
    return float(e @ np.linalg.solve(result.covariance, e))


@pytest.mark.parametrize("lens", [OPENCV, FISHEYE], ids=["OPENCV", "OPENCV_FISHEYE"])
def test_distorted_pixels_give_the_pose_within_its_covariance(lens):
    # 40 trials: the mean NEES of an efficient estimator is 6 with standard deviation sqrt(12/40) = 0.55;
    # ignoring the distortion biases the pose by hundreds of standard deviations.
    rng = np.random.default_rng(1)
    modelled, ignored = [], []
    pinhole = pluecker.Camera.pinhole(600.0, 600.0, 320.0, 240.0)
    options = pluecker.PoseOptions(sigma_px=1.0)
    for _ in range(40):
        R, t, X, L = scene(rng)
        u = observe(lens, R, t, X, 1.0, rng)
        s = observe(lens, R, t, L, 1.0, rng).reshape(-1, 2, 2)
        result = pluecker.estimate_pose(lens, u, X, s, L, options=options)
        assert result.status == "success"
        modelled.append(nees(result, R, t))
        ignored.append(nees(pluecker.estimate_pose(pinhole, u, X, s, L, options=options), R, t))
    assert 6 - 3 * 0.55 < np.mean(modelled) < 6 + 3 * 0.55
    assert np.median(ignored) > 100


def test_reported_errors_are_distorted_pixels():
    rng = np.random.default_rng(2)
    R, t, X, _ = scene(rng, 20, 0)
    u = observe(OPENCV, R, t, X, 0.5, rng)
    result = pluecker.estimate_pose(OPENCV, u, X)
    # The errors at the returned pose, recomputed through the lens.
    predicted = OPENCV.project(X @ result.pose.rotation.T + result.pose.translation)
    # rms_error_px is the RMS over the residual coordinates (u and v).
    assert np.sqrt(np.mean((predicted - u) ** 2)) == pytest.approx(result.details.rms_error_px, rel=1e-3)


def test_robust_pose_through_a_lens():
    rng = np.random.default_rng(3)
    R, t, X, _ = scene(rng, 40, 0)
    u = observe(OPENCV, R, t, X, 1.0, rng)
    outliers = np.arange(0, 40, 3)
    u[outliers] += rng.choice([-1, 1], size=(len(outliers), 2)) * rng.uniform(40, 120, size=(len(outliers), 2))
    result = pluecker.estimate_pose(OPENCV, u, X, options=pluecker.PoseOptions(ransac=pluecker.RansacOptions(seed=4)))
    assert result.status == "success"
    assert not result.inliers_points[outliers].any()
    assert result.inliers_points.sum() >= 25
    assert nees(result, R, t) < 22.5  # chi-square(6) above 22.5 with probability 1e-3


def test_covariances_weight_the_pose_and_are_absolute():
    rng = np.random.default_rng(5)
    camera = pluecker.Camera.pinhole(600.0, 600.0, 320.0, 240.0)
    pinhole = pluecker.Camera("PINHOLE", [600.0, 600.0, 320.0, 240.0])
    weighted, plain = [], []
    for _ in range(40):
        R, t, X, _ = scene(rng, 30, 0)
        sigma = np.where(np.arange(30) % 2 == 0, 0.3, 3.0)
        cov = sigma[:, None, None] ** 2 * np.eye(2)
        u = observe(pinhole, R, t, X, sigma[:, None], rng)
        result = pluecker.estimate_pose(camera, u, X, point_covariances=cov)
        assert result.details.sigma_px == 1.0 and result.certified is False
        weighted.append(np.linalg.norm(result.pose.translation - t))
        plain.append(np.linalg.norm(pluecker.estimate_pose(camera, u, X).pose.translation - t))
    assert np.sqrt(np.mean(np.square(weighted))) < 0.6 * np.sqrt(np.mean(np.square(plain)))


def test_line_covariances_per_segment_equal_per_endpoint():
    rng = np.random.default_rng(6)
    camera = pluecker.Camera.pinhole(600.0, 600.0, 320.0, 240.0)
    R, t, X, L = scene(rng, 6, 4)
    u = observe(pluecker.Camera("PINHOLE", [600.0, 600.0, 320.0, 240.0]), R, t, X, 1.0, rng)
    s = observe(pluecker.Camera("PINHOLE", [600.0, 600.0, 320.0, 240.0]), R, t, L, 1.0, rng).reshape(-1, 2, 2)
    per_segment = np.array([[[2.0, 0.3], [0.3, 1.0]]] * 4)
    per_endpoint = np.repeat(per_segment[:, None], 2, axis=1)
    a = pluecker.estimate_pose(camera, u, X, s, L, line_covariances=per_segment)
    b = pluecker.estimate_pose(camera, u, X, s, L, line_covariances=per_endpoint)
    np.testing.assert_array_equal(a.pose.rotation, b.pose.rotation)
    # Unit covariances: the same pose as without, now in standard deviations (sigma_px = 1).
    unit = pluecker.estimate_pose(camera, u, X, s, L, point_covariances=np.tile(np.eye(2), (6, 1, 1)))
    plain = pluecker.estimate_pose(camera, u, X, s, L)
    np.testing.assert_allclose(unit.pose.rotation, plain.pose.rotation, atol=1e-9)
    assert unit.details.sigma_px == 1.0 and plain.details.sigma_px != 1.0


def test_bad_covariances_and_cameras_are_named_errors():
    rng = np.random.default_rng(7)
    camera = pluecker.Camera.pinhole(600.0, 600.0, 320.0, 240.0)
    R, t, X, _ = scene(rng, 8, 0)
    u = observe(OPENCV, R, t, X, 1.0, rng)
    with pytest.raises(pluecker.ShapeError, match="point_covariances"):
        pluecker.estimate_pose(camera, u, X, point_covariances=np.tile(np.eye(2), (7, 1, 1)))
    with pytest.raises(pluecker.ShapeError, match="line_covariances"):
        pluecker.estimate_pose(camera, u, X, line_covariances=np.zeros((2, 3)))
    bad = np.tile(np.eye(2), (8, 1, 1))
    bad[5] = [[1.0, 0.0], [0.0, -1.0]]
    with pytest.raises(pluecker.DegenerateConfigurationError, match=r"point_covariances\[5\]"):
        pluecker.estimate_pose(camera, u, X, point_covariances=bad)
    bad[5] = np.nan
    with pytest.raises(pluecker.NonFiniteError, match="point_covariances"):
        pluecker.estimate_pose(camera, u, X, point_covariances=bad)
    with pytest.raises(TypeError, match="camera: expected a pluecker.Camera or a pycolmap.Camera, got str"):
        pluecker.estimate_pose("OPENCV", u, X)
    radial = pluecker.Camera("SIMPLE_RADIAL", [600.0, 320.0, 240.0, -0.28])
    far = observe(radial, R, t, X, 0.0, rng)
    far[3] = [320 + 0.8 * 600, 240]  # beyond the fold of the distortion
    with pytest.raises(pluecker.DegenerateConfigurationError, match=r"points2d.*pixel 3"):
        pluecker.estimate_pose(radial, far, X)


def test_command_line_takes_colmap_camera_models_and_covariances(tmp_path, capsys):
    import json

    from pluecker.cli import main

    rng = np.random.default_rng(8)
    R, t, X, L = scene(rng, 20, 3)
    u = observe(FISHEYE, R, t, X, 0.5, rng)
    s = observe(FISHEYE, R, t, L, 0.5, rng).reshape(-1, 2, 2)
    doc = {
        "camera": {"model": FISHEYE.model, "params": [float(p) for p in FISHEYE.params]},
        "points2d": u.tolist(), "points3d": X.tolist(), "lines2d": s.tolist(), "lines3d": L.tolist(),
        "point_covariances": np.tile(0.25 * np.eye(2), (20, 1, 1)).tolist(),
        "line_covariances": np.tile(0.25 * np.eye(2), (3, 1, 1)).tolist(),
    }
    path = tmp_path / "pose.json"
    path.write_text(json.dumps(doc))
    assert main(["pose", str(path)]) == 0
    out = json.loads(capsys.readouterr().out)
    direct = pluecker.estimate_pose(FISHEYE, u, X, s, L, point_covariances=doc["point_covariances"],
                                    line_covariances=doc["line_covariances"])
    np.testing.assert_allclose(out["pose"]["rotation"], direct.pose.rotation, atol=1e-12)
    assert out["status"] == "success" and out["details"]["sigma_px"] == 1.0
    assert nees(direct, R, t) < 22.5
    doc["camera"] = {"model": "OPENCV", "params": [600.0, 600.0]}
    path.write_text(json.dumps(doc))
    assert main(["pose", str(path)]) == 2
    assert "OPENCV parameters: expected 8 values" in capsys.readouterr().err


def test_lines_triangulated_through_a_lens():
    """Segments seen by 4 wide OPENCV cameras (f = 400 px, out to the image corners), 1 px noise on the
    distorted endpoints: undistorted with their covariances and turned into lines (``lines_from_endpoints``),
    the minimal cost is χ² with 2·4 − 4 = 4 degrees of freedom (mean over 60 lines 4 ± 0.37); taken as
    pinhole pixels, the distortion shows as a cost far above it."""
    import math

    from triangulation_scenes import look_at

    lens = pluecker.Camera("OPENCV", [400.0, 400.0, 512.0, 384.0, -0.25, 0.06, 5e-4, -5e-4])
    rng = np.random.default_rng(11)
    poses = []
    for a in np.radians([-25.0, -8.0, 8.0, 25.0]):
        centre = 6.0 * np.array([math.sin(a), 0.3 * rng.uniform(-1, 1), -math.cos(a)])
        R = look_at(centre, rng.uniform(-0.3, 0.3))
        poses.append((R, -R @ centre))
    P = np.array([lens.P(R, t) for R, t in poses])
    costs, ignored, errors, naive_errors = [], [], [], []
    while len(costs) < 60:
        ends = rng.uniform(-3.0, 3.0, (2, 3))
        pixels = np.array([lens.project(ends @ R.T + t) for R, t in poses])  # (4, 2, 2)
        inside = np.all((pixels >= 0) & (pixels < [1024, 768]))
        if not inside or np.min([(ends @ R.T + t)[:, 2] for R, t in poses]) < 1.0:
            continue
        observed = pixels + rng.normal(size=pixels.shape)
        ubar, C = lens.undistort(observed.reshape(-1, 2))
        lines, cov = pluecker.lines_from_endpoints(ubar.reshape(4, 2, 2), C.reshape(4, 2, 2, 2))
        r = pluecker.triangulate_line(P, lines, cov, options=pluecker.TriangulationOptions(method="local"))  # certifying lines is issue 13's
        assert r.status == "success"
        costs.append(r.cost)  # eq. 19: Σ r², the χ² statistic
        # Distance of the true endpoints to the estimated line.
        d = r.direction
        errors.append(max(np.linalg.norm(np.cross(e - r.point, d)) for e in ends))
        naive = pluecker.triangulate_line(P, observed, sigma=1.0, options=pluecker.TriangulationOptions(method="local"))
        ignored.append(naive.cost)
        naive_errors.append(max(np.linalg.norm(np.cross(e - naive.point, naive.direction)) for e in ends))
    print(f"lines through a lens: mean cost {np.mean(costs):.2f} (χ²(4): 4), ignored {np.mean(ignored):.1f}; median "
          f"3-D error {np.median(errors):.4f} vs {np.median(naive_errors):.4f}")
    assert 4 - 3 * 0.37 < np.mean(costs) < 4 + 3 * 0.37, np.mean(costs)
    # Ignoring the distortion: a cost far beyond χ²(4) (its mean's 3σ bound is 5.1) and larger 3-D errors.
    assert np.mean(ignored) > 8.0, np.mean(ignored)
    assert np.median(errors) < 0.5 * np.median(naive_errors), (np.median(errors), np.median(naive_errors))
