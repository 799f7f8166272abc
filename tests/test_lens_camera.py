"""``pluecker.LensCamera``: COLMAP's camera models (issue 12 §1). The projection is recomputed here with
numpy from the models' formulas (COLMAP's ``sensor/models.h``); unprojection inverts it to 1e-10 px; the
first-order covariance of the normalised coordinates matches a Monte Carlo estimate."""

from __future__ import annotations

import pickle

import numpy as np
import pytest

import pluecker

CAMERAS = {
    "SIMPLE_PINHOLE": [800.0, 320.0, 240.0],
    "PINHOLE": [800.0, 790.0, 320.0, 240.0],
    "SIMPLE_RADIAL": [800.0, 320.0, 240.0, -0.1],
    "RADIAL": [800.0, 320.0, 240.0, -0.1, 0.02],
    "OPENCV": [800.0, 790.0, 320.0, 240.0, -0.2, 0.05, 1e-3, -5e-4],
    "FULL_OPENCV": [800.0, 790.0, 320.0, 240.0, -0.2, 0.05, 1e-3, -5e-4, 0.01, 0.02, -0.01, 0.005],
    "OPENCV_FISHEYE": [400.0, 395.0, 320.0, 240.0, 0.05, -0.01, 0.002, -3e-4],
}


def reference_project(model: str, p: list[float], X: np.ndarray) -> np.ndarray:
    """COLMAP's projection, written out with numpy."""
    u, v = X[:, 0] / X[:, 2], X[:, 1] / X[:, 2]
    r2 = u * u + v * v
    if model in ("SIMPLE_PINHOLE", "SIMPLE_RADIAL", "RADIAL"):
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
        du = u * g + 2 * p1 * u * v + p2 * (r2 + 2 * u * u)
        dv = v * g + p1 * (r2 + 2 * v * v) + 2 * p2 * u * v
    else:  # OPENCV_FISHEYE
        k1, k2, k3, k4 = p[4:8]
        r = np.sqrt(r2)
        theta = np.arctan(r)
        theta_d = theta * (1 + k1 * theta**2 + k2 * theta**4 + k3 * theta**6 + k4 * theta**8)
        du, dv = u * theta_d / r, v * theta_d / r
    return np.c_[fx * du + cx, fy * dv + cy]


def points_in_front(seed: int, n: int = 200) -> np.ndarray:
    rng = np.random.default_rng(seed)
    return np.c_[rng.uniform(-0.6, 0.6, n), rng.uniform(-0.45, 0.45, n), rng.uniform(1.0, 1.5, n)]


@pytest.mark.parametrize("model", list(CAMERAS))
def test_projection_is_colmaps(model):
    X = points_in_front(1)
    cam = pluecker.LensCamera(model, CAMERAS[model])
    np.testing.assert_allclose(cam.project(X), reference_project(model, CAMERAS[model], X), rtol=0, atol=1e-9)


@pytest.mark.parametrize("model", list(CAMERAS))
def test_unprojection_inverts_the_projection_to_1e_10_px(model):
    X = points_in_front(2)
    cam = pluecker.LensCamera(model, CAMERAS[model])
    u = cam.project(X)
    n = cam.unproject(u)
    back = cam.project(np.c_[n, np.ones(len(n))])
    assert np.abs(back - u).max() <= 1.5e-10
    np.testing.assert_allclose(n, X[:, :2] / X[:, 2:], atol=1e-12)
    rays = cam.bearings(u)
    np.testing.assert_allclose(rays, X / np.linalg.norm(X, axis=1, keepdims=True), atol=1e-12)


def test_a_pixel_beyond_the_fold_is_named():
    cam = pluecker.LensCamera("SIMPLE_RADIAL", [500.0, 0.0, 0.0, -0.5])
    peak = np.sqrt(1 / 1.5) * (1 - 0.5 / 1.5) * 500.0  # the largest radius the distortion reaches
    cam.unproject([[0.9 * peak, 0.0]])
    with pytest.raises(pluecker.DegenerateConfigurationError, match=r"pixel 1 .*outside the invertible region"):
        cam.unproject([[0.9 * peak, 0.0], [1.05 * peak, 0.0]])


def test_normalized_covariances_match_monte_carlo():
    """1 px isotropic noise on one pixel of a strongly distorted camera: the spread of the unprojected
    points over 4000 draws matches J⁻¹ Σ J⁻ᵀ within the sampling error of a covariance (4 √(2/N))."""
    cam = pluecker.LensCamera("OPENCV", CAMERAS["OPENCV"])
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
        pluecker.LensCamera("KANNALA", [1.0])
    with pytest.raises(pluecker.ShapeError, match="OPENCV parameters: expected 8 values"):
        pluecker.LensCamera("OPENCV", [1.0, 2.0])
    with pytest.raises(pluecker.SingularCameraError):
        pluecker.LensCamera("PINHOLE", [0.0, 1.0, 0.0, 0.0])
    with pytest.raises(pluecker.NonFiniteError):
        pluecker.LensCamera("PINHOLE", [1.0, float("nan"), 0.0, 0.0])


def test_models_round_trip():
    assert pluecker.LensCamera.MODELS == ["SIMPLE_PINHOLE", "PINHOLE", "SIMPLE_RADIAL", "RADIAL", "OPENCV",
                                          "OPENCV_FISHEYE", "FULL_OPENCV"]
    cam = pluecker.LensCamera("OPENCV_FISHEYE", CAMERAS["OPENCV_FISHEYE"])
    assert pickle.loads(pickle.dumps(cam)) == cam
    assert cam.to_dict()["parameter_names"] == ["fx", "fy", "cx", "cy", "k1", "k2", "k3", "k4"]
