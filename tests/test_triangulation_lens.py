"""Points through lens cameras from Python: the exact pixel cost (judged with pycolmap's projection),
its certificate, and the errors of a camera list that does not match ``P``."""

import numpy as np
import pycolmap
import pytest

import pluecker


def _look_at(centre, target, up=(0.0, 1.0, 0.0)):
    z = np.asarray(target, float) - centre
    z /= np.linalg.norm(z)
    x = np.cross(up, z)
    x /= np.linalg.norm(x)
    R = np.stack([x, np.cross(z, x), z])
    return R, -R @ centre


def _views(params, model="SIMPLE_RADIAL", n=4, seed=0):
    rng = np.random.default_rng(seed)
    X = rng.normal(size=3) * 0.2
    lens = pluecker.Camera(model, params)
    theirs = pycolmap.Camera(model=model, width=1200, height=1000, params=params)
    poses, pixels = [], []
    for k in range(n):
        angle = 2 * np.pi * k / n
        R, t = _look_at(np.array([5 * np.cos(angle), 0.5, 5 * np.sin(angle)]), X + rng.normal(size=3) * 0.05)
        poses.append((R, t))
        pixels.append(theirs.img_from_cam(np.atleast_2d(R @ X + t))[0] + rng.normal(size=2))
    P = np.stack([lens.P(R, t) for R, t in poses])
    return P, np.array(pixels), [lens] * n, theirs, poses, X


def _pixel_cost(theirs, poses, pixels, X):
    return sum(np.sum((theirs.img_from_cam(np.atleast_2d(R @ X + t))[0] - u) ** 2) for (R, t), u in zip(poses, pixels))


def test_a_point_through_a_strong_radial_lens_is_the_certified_minimum_of_the_pixel_cost():
    """f = 5000 px, k = -14: the reported cost is pycolmap's pixel cost at the point (to rounding), no
    nearby point costs less, and the certificate is the lens one, over its stated domain."""
    P, x, cameras, theirs, poses, _ = _views([5000.0, 600.0, 500.0, -14.0])
    r = pluecker.triangulate_point(P, x, cameras=cameras)
    assert r.status == "success" and r.certified and r.certificate.kind == "lens_convexity_test"
    assert "one-to-one" in r.certificate.domain
    cost = _pixel_cost(theirs, poses, x, r.point)
    assert abs(r.cost / cost - 1) < 1e-9
    # A stationary minimum: steps of 1e-4 of the point's spread cost more (first-order term ~0).
    rng = np.random.default_rng(1)
    for _ in range(20):
        assert _pixel_cost(theirs, poses, x, r.point + rng.normal(size=3) * 1e-4) >= cost
    assert r.certificate.lower_bound <= cost


def test_the_first_order_answer_costs_more_than_the_exact_one():
    """Without ``cameras`` the pixels would have to be undistorted by hand; with them the exact cost
    is minimised: never above what the undistorted (first-order) triangulation reaches."""
    P, x, cameras, theirs, poses, _ = _views([5000.0, 600.0, 500.0, -14.0], seed=3)
    lens = cameras[0]
    undistorted, cov = lens.undistort(x, np.broadcast_to(np.eye(2), (len(x), 2, 2)))
    first = pluecker.triangulate_point(P, undistorted, cov)
    exact = pluecker.triangulate_point(P, x, cameras=cameras)
    assert _pixel_cost(theirs, poses, x, exact.point) <= _pixel_cost(theirs, poses, x, first.point) * (1 + 1e-12)


def test_a_camera_list_that_does_not_match_P_is_named():
    P, x, cameras, *_ = _views([5000.0, 600.0, 500.0, -14.0])
    with pytest.raises(pluecker.InvalidOptionError, match=r"projections: row 1 is not K \[R \| t\]"):
        pluecker.triangulate_point(P, x, cameras=[cameras[0], pluecker.Camera("SIMPLE_RADIAL", [800.0, 600.0, 500.0, 0.0]), *cameras[2:]])
    with pytest.raises(pluecker.ShapeError, match="cameras"):
        pluecker.triangulate_point(P, x, cameras=cameras[:2])
    with pytest.raises(TypeError, match=r"cameras\[0\]: expected a pluecker.Camera or a pycolmap.Camera"):
        pluecker.triangulate_point(P, x, cameras=["SIMPLE_RADIAL"] * len(P))


def test_the_covariance_through_a_lens_is_that_of_the_exact_residuals():
    """``covariance`` is ``(JᵀJ)⁻¹`` of the whitened pixel residuals through the lens, with ``J`` here by
    central differences of pycolmap's projection (step 1e-6 of the scene: error ~1e-8 relative)."""
    P, x, cameras, theirs, poses, _ = _views([5000.0, 600.0, 500.0, -14.0], seed=5)
    r = pluecker.triangulate_point(P, x, cameras=cameras)

    def residuals(X):
        return np.concatenate([theirs.img_from_cam(np.atleast_2d(R @ X + t))[0] - u for (R, t), u in zip(poses, x)])

    h = 1e-6
    J = np.stack([(residuals(r.point + h * e) - residuals(r.point - h * e)) / (2 * h) for e in np.eye(3)], axis=1)
    expected = np.linalg.inv(J.T @ J)
    np.testing.assert_allclose(r.covariance, expected, rtol=1e-5)
