"""``pluecker.Camera``: COLMAP's camera models (issue 12 §1). The projection is recomputed here with
numpy from the models' formulas (COLMAP's ``sensor/models.h``); unprojection inverts it to 1e-10 px; the
first-order covariance of the normalised coordinates matches a Monte Carlo estimate."""

from __future__ import annotations

import pickle

import numpy as np
import pytest

import pluecker

from camera_models import PARAMS as CAMERAS  # noqa: E402

ONE_FOCAL_LENGTH = ("SIMPLE_PINHOLE", "SIMPLE_RADIAL", "RADIAL", "SIMPLE_RADIAL_FISHEYE", "RADIAL_FISHEYE",
                    "SIMPLE_DIVISION", "SIMPLE_FISHEYE")


def tangential(u, v, p1, p2):
    r2 = u * u + v * v
    return 2 * p1 * u * v + p2 * (r2 + 2 * u * u), p1 * (r2 + 2 * v * v) + 2 * p2 * u * v


def reference_project(model: str, p: list[float], X: np.ndarray) -> np.ndarray:
    """COLMAP's projection, written out with numpy."""
    u, v = X[:, 0] / X[:, 2], X[:, 1] / X[:, 2]
    r2 = u * u + v * v
    if model in ONE_FOCAL_LENGTH:
        f, cx, cy = p[:3]
        fx = fy = f
    else:
        fx, fy, cx, cy = p[:4]
    if model in ("SIMPLE_PINHOLE", "PINHOLE"):
        du, dv = u, v
    elif model == "SIMPLE_RADIAL":
        du, dv = u * (1 + p[3] * r2), v * (1 + p[3] * r2)
    elif model == "RADIAL":
        g = 1 + p[3] * r2 + p[4] * r2**2
        du, dv = u * g, v * g
    elif model in ("OPENCV", "FULL_OPENCV"):
        k1, k2, p1, p2 = p[4:8]
        if model == "OPENCV":
            g = 1 + k1 * r2 + k2 * r2**2
        else:
            k3, k4, k5, k6 = p[8:12]
            g = (1 + k1 * r2 + k2 * r2**2 + k3 * r2**3) / (1 + k4 * r2 + k5 * r2**2 + k6 * r2**3)
        tu, tv = tangential(u, v, p1, p2)
        du, dv = u * g + tu, v * g + tv
    elif model == "FOV":
        w = p[4]
        t = np.tan(w / 2)
        with np.errstate(divide="ignore", invalid="ignore"):
            g = np.where(r2 < 1e-4, 2 * t / w * (1 - 4 * t * t * r2 / 3), np.arctan(2 * np.sqrt(r2) * t) / (np.sqrt(r2) * w))
        if w * w < 1e-4:  # COLMAP's series in omega (that of its undistortion)
            g = 1 + w * w * r2 / 3 - w * w / 12
        du, dv = u * g, v * g
    elif model in ("SIMPLE_DIVISION", "DIVISION"):
        g = 2 / (1 + np.sqrt(1 - 4 * p[-1] * r2))
        du, dv = u * g, v * g
    elif model == "EUCM":
        alpha, beta = p[4:6]
        g = 1 / (alpha * np.sqrt(1 + beta * r2) + 1 - alpha)
        du, dv = u * g, v * g
    else:  # the fisheyes: the polynomials act on m = n theta / r, |m| = theta
        r = np.sqrt(r2)
        theta = np.arctan(r)
        mu, mv = u * theta / r, v * theta / r
        t2 = theta**2
        if model in ("SIMPLE_FISHEYE", "FISHEYE"):
            du, dv = mu, mv
        elif model == "RAD_TAN_THIN_PRISM_FISHEYE":
            g = 1 + sum(k * t2 ** (i + 1) for i, k in enumerate(p[4:10]))
            x, y = mu * g, mv * g
            p0, p1, s0, s1, s2, s3 = p[10:16]
            q = x * x + y * y
            du = x + 2 * p1 * x * y + p0 * (q + 2 * x * x) + s0 * q + s1 * q * q
            dv = y + 2 * p0 * x * y + p1 * (q + 2 * y * y) + s2 * q + s3 * q * q
        else:
            k = {"SIMPLE_RADIAL_FISHEYE": p[3:4], "RADIAL_FISHEYE": p[3:5], "OPENCV_FISHEYE": p[4:8],
                 "THIN_PRISM_FISHEYE": p[4:6] + p[8:10]}[model]
            g = 1 + sum(c * t2 ** (i + 1) for i, c in enumerate(k))
            du, dv = mu * g, mv * g
            if model == "THIN_PRISM_FISHEYE":
                tu, tv = tangential(mu, mv, p[6], p[7])
                du, dv = du + tu + p[10] * t2, dv + tv + p[11] * t2
    return np.c_[fx * du + cx, fy * dv + cy]


def points_in_front(seed: int, n: int = 200) -> np.ndarray:
    rng = np.random.default_rng(seed)
    return np.c_[rng.uniform(-0.6, 0.6, n), rng.uniform(-0.45, 0.45, n), rng.uniform(1.0, 1.5, n)]


@pytest.mark.parametrize("model", list(CAMERAS))
def test_projection_is_colmaps(model):
    X = points_in_front(1)
    cam = pluecker.Camera(model, CAMERAS[model])
    np.testing.assert_allclose(cam.project(X), reference_project(model, CAMERAS[model], X), rtol=0, atol=1e-9)


@pytest.mark.parametrize("model", list(CAMERAS))
def test_unprojection_inverts_the_projection_to_1e_10_px(model):
    X = points_in_front(2)
    cam = pluecker.Camera(model, CAMERAS[model])
    u = cam.project(X)
    n = cam.unproject(u)
    back = cam.project(np.c_[n, np.ones(len(n))])
    assert np.abs(back - u).max() <= 1.5e-10
    np.testing.assert_allclose(n, X[:, :2] / X[:, 2:], atol=1e-12)
    rays = cam.bearings(u)
    np.testing.assert_allclose(rays, X / np.linalg.norm(X, axis=1, keepdims=True), atol=1e-12)


def test_a_pixel_beyond_the_fold_is_named():
    cam = pluecker.Camera("SIMPLE_RADIAL", [500.0, 0.0, 0.0, -0.5])
    peak = np.sqrt(1 / 1.5) * (1 - 0.5 / 1.5) * 500.0  # the largest radius the distortion reaches
    cam.unproject([[0.9 * peak, 0.0]])
    with pytest.raises(pluecker.DegenerateConfigurationError, match=r"pixel 1 .*outside the invertible region"):
        cam.unproject([[0.9 * peak, 0.0], [1.05 * peak, 0.0]])


def test_normalized_covariances_match_monte_carlo():
    """1 px isotropic noise on one pixel of a strongly distorted camera: the spread of the unprojected
    points over 4000 draws matches J⁻¹ Σ J⁻ᵀ within the sampling error of a covariance (4 √(2/N))."""
    cam = pluecker.Camera("OPENCV", CAMERAS["OPENCV"])
    u0 = cam.project([[0.5, -0.35, 1.0]])
    predicted = cam.normalized_covariances(u0)[0]
    rng = np.random.default_rng(3)
    draws = 4000
    n = cam.unproject(u0 + rng.normal(size=(draws, 2)))
    sample = np.cov(n.T)
    assert np.all(np.abs(np.diag(sample) / np.diag(predicted) - 1) < 4 * np.sqrt(2 / draws))
    assert predicted[0, 0] > 1.2 / CAMERAS["OPENCV"][0] ** 2, "the distortion must show in the covariance"


def test_bad_cameras_are_named_errors():
    with pytest.raises(pluecker.InvalidOptionError, match="unknown camera model 'KANNALA'"):
        pluecker.Camera("KANNALA", [1.0])
    with pytest.raises(pluecker.ShapeError, match="OPENCV parameters: expected 8 values"):
        pluecker.Camera("OPENCV", [1.0, 2.0])
    with pytest.raises(pluecker.SingularCameraError):
        pluecker.Camera("PINHOLE", [0.0, 1.0, 0.0, 0.0])
    with pytest.raises(pluecker.NonFiniteError):
        pluecker.Camera("PINHOLE", [1.0, float("nan"), 0.0, 0.0])


def test_models_round_trip():
    # COLMAP's model ids 0-16 (colmap/sensor/models.h, CameraModelId; 17, EQUIRECTANGULAR, is refused).
    assert pluecker.Camera.MODELS == ["SIMPLE_PINHOLE", "PINHOLE", "SIMPLE_RADIAL", "RADIAL", "OPENCV",
                                          "OPENCV_FISHEYE", "FULL_OPENCV", "FOV", "SIMPLE_RADIAL_FISHEYE",
                                          "RADIAL_FISHEYE", "THIN_PRISM_FISHEYE", "RAD_TAN_THIN_PRISM_FISHEYE",
                                          "SIMPLE_DIVISION", "DIVISION", "SIMPLE_FISHEYE", "FISHEYE", "EUCM",
                                          "SKEWED_PINHOLE"]
    cam = pluecker.Camera("OPENCV_FISHEYE", CAMERAS["OPENCV_FISHEYE"])
    assert pickle.loads(pickle.dumps(cam)) == cam
    assert cam.to_dict()["parameter_names"] == ["fx", "fy", "cx", "cy", "k1", "k2", "k3", "k4"]
