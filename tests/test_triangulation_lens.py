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
    return P, np.array(pixels), [pluecker.View(lens, R, t) for R, t in poses], theirs, poses, X


def _pixel_cost(theirs, poses, pixels, X):
    return sum(np.sum((theirs.img_from_cam(np.atleast_2d(R @ X + t))[0] - u) ** 2) for (R, t), u in zip(poses, pixels))


def test_a_point_through_a_strong_radial_lens_is_the_certified_minimum_of_the_pixel_cost():
    """f = 5000 px, k = -14: the reported cost is pycolmap's pixel cost at the point (to rounding), no
    nearby point costs less, and the certificate is the lens one, over its stated domain."""
    P, x, cameras, theirs, poses, _ = _views([5000.0, 600.0, 500.0, -14.0])
    r = pluecker.triangulate_point(cameras, x)
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
    """Through the pinhole part the pixels have to be undistorted by hand; through the views the exact cost
    is minimised: never above what the undistorted (first-order) triangulation reaches."""
    P, x, cameras, theirs, poses, _ = _views([5000.0, 600.0, 500.0, -14.0], seed=3)
    lens = cameras[0].camera
    undistorted, cov = lens.undistort(x, np.broadcast_to(np.eye(2), (len(x), 2, 2)))
    first = pluecker.triangulate_point(P, undistorted, cov)
    exact = pluecker.triangulate_point(cameras, x)
    assert _pixel_cost(theirs, poses, x, exact.point) <= _pixel_cost(theirs, poses, x, first.point) * (1 + 1e-12)


def test_views_that_do_not_fit_the_observations_are_named():
    P, x, cameras, *_ = _views([5000.0, 600.0, 500.0, -14.0])
    with pytest.raises(TypeError, match=r"cameras\[1\]: expected a pluecker.View"):
        pluecker.triangulate_point([cameras[0], P[1], *cameras[2:]], x)
    with pytest.raises(pluecker.ShapeError, match="observations"):
        pluecker.triangulate_point(cameras[:2], x)
    with pytest.raises(TypeError, match=r"camera: expected a pluecker.Camera or a pycolmap.Camera"):
        pluecker.View("SIMPLE_RADIAL", np.eye(3), np.zeros(3))
    # A view from its 3x4 matrix: the pinhole camera of K at the pose, the same P.
    view = pluecker.View.from_projection(P[1])
    np.testing.assert_allclose(view.P, P[1], rtol=0, atol=1e-9 * np.abs(P[1]).max())
    assert view.camera.model in ("PINHOLE", "SKEWED_PINHOLE") and view.camera.fx == pytest.approx(5000.0)
    # Views are values: equal when their cameras and poses are, and pickled whole.
    import pickle
    assert pickle.loads(pickle.dumps(cameras[1])) == cameras[1] != cameras[2]
    assert cameras[1].to_dict()["camera"]["model"] == "SIMPLE_RADIAL"


def test_the_covariance_through_a_lens_is_that_of_the_exact_residuals():
    """``covariance`` is ``(JᵀJ)⁻¹`` of the whitened pixel residuals through the lens, with ``J`` here by
    central differences of pycolmap's projection (step 1e-6 of the scene: error ~1e-8 relative)."""
    P, x, cameras, theirs, poses, _ = _views([5000.0, 600.0, 500.0, -14.0], seed=5)
    r = pluecker.triangulate_point(cameras, x)

    def residuals(X):
        return np.concatenate([theirs.img_from_cam(np.atleast_2d(R @ X + t))[0] - u for (R, t), u in zip(poses, x)])

    h = 1e-6
    J = np.stack([(residuals(r.point + h * e) - residuals(r.point - h * e)) / (2 * h) for e in np.eye(3)], axis=1)
    expected = np.linalg.inv(J.T @ J)
    np.testing.assert_allclose(r.covariance, expected, rtol=1e-5)
