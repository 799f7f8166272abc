"""Which side of a camera is in front (issue 10): ``λ = (P X̃)₃ > 0`` for the matrix as given.

Cameras with a negative focal length (the pose paper's ``α_u = −1730.3``) and the raw VGG ``.P`` files
(a left-handed world: ``det P[:, :3] < 0`` with every point at ``λ > 0``) used to make every method call the
right point ``behind_camera`` and ``optimal`` certify a point 1e10 away. The same data are checked from
Rust in ``crates/pluecker/tests/it/triangulation_cheirality.rs``.
"""

from __future__ import annotations

import re

import numpy as np
import pytest

import pluecker
from pluecker.datasets import load_vgg, vgg_root

METHODS = pluecker.TRIANGULATION_METHODS


def project(P: np.ndarray, X: np.ndarray) -> np.ndarray:
    h = P @ np.append(X, 1.0)
    return h[..., :2] / h[..., 2:]


def raw_cameras(name: str) -> np.ndarray:
    """The ``.P`` files of a VGG sequence read as they are, without the frame flip of ``load_vgg``."""
    folder = vgg_root() / name
    files = sorted(p for p in folder.iterdir() if re.fullmatch(r"(.*\.)?\d+\.P", p.name))
    return np.stack([np.loadtxt(p).reshape(3, 4) for p in files])


def test_negative_focal_length_cameras_see_the_point_in_front():
    """The issue's example: three cameras ``K [R | t + d]`` from ``paper_scene()`` and a point 78 cm deep."""
    scene = pluecker.paper_scene()
    K, R, t = scene["camera"].K, scene["R"], scene["t"]
    assert K[0, 0] < 0
    X = scene["points3d"][0]
    P = np.stack([K @ np.hstack([R, (t + d)[:, None]]) for d in ([0, 0, 0], [5.0, 0, 0], [0, 5.0, 0])])
    assert np.all(P[:, 2] @ np.append(X, 1.0) > 70)
    x = np.array([project(p, X) for p in P])
    for method in METHODS:
        r = pluecker.triangulate_point(P, x, options=pluecker.TriangulationOptions(method=method))
        assert r.status == "success", (method, r)
        # Exact pixels, 78 cm deep over a 5 cm baseline: exact to ~1e-12 relative.
        np.testing.assert_allclose(r.point, X, atol=1e-8 * 78)
    assert pluecker.triangulate_point(P, x).certified


@pytest.mark.parametrize("name", ["model_house", "corridor"])
def test_raw_vgg_cameras_give_the_mirrored_points_with_the_same_costs(name):
    """Every point of the sequence from the raw cameras: the same statuses, costs and certificates as
    from the flipped ones of ``load_vgg``, at the mirrored positions."""
    seq = load_vgg(vgg_root() / name)
    assert seq.mirrored
    raw = raw_cameras(name)
    assert np.all(np.linalg.det(raw[:, :, :3]) < 0)
    np.testing.assert_allclose(raw, seq.cameras @ np.diag([-1.0, -1.0, -1.0, 1.0]))
    x, visible = seq.point_observations()
    for method in METHODS:
        flipped = pluecker.triangulate_points(seq.cameras, x, visible, options=pluecker.TriangulationOptions(method=method))
        as_read = pluecker.triangulate_points(raw, x, visible, options=pluecker.TriangulationOptions(method=method))
        assert np.all(as_read.status == flipped.status), method
        if method != "local":  # one Corridor point needs more than the 100 local iterations either way
            assert np.all(as_read.status == "success"), (method, np.unique(as_read.status, return_counts=True))
        np.testing.assert_array_equal(as_read.certified, flipped.certified)
        np.testing.assert_allclose(as_read.cost, flipped.cost, rtol=1e-8, atol=1e-12)
        # Point scale: the scene is ~10 units across; rounding differs between the two frames only.
        np.testing.assert_allclose(as_read.point, -flipped.point, atol=1e-8 * 10)
    assert as_read.certified.all()


def test_the_issues_first_model_house_track_from_the_raw_files():
    seq = load_vgg(vgg_root() / "model_house")
    raw = raw_cameras("model_house")
    x, visible = seq.point_observations()
    seen = visible[0]
    for method in METHODS:
        r = pluecker.triangulate_point(raw[seen], x[0, seen], options=pluecker.TriangulationOptions(method=method))
        assert r.status == "success", (method, r)
        rms = np.sqrt(np.mean(np.sum((project(raw[seen], r.point) - x[0, seen]) ** 2, axis=1)))
        assert rms < 1.0, (method, rms)  # the data's own consistency: 0.37 px mean (test_datasets)
    r = pluecker.triangulate_point(raw[seen], x[0, seen])
    assert r.certified and r.certificate.kind == "convexity_test"


def test_raw_vgg_lines_agree_with_the_flipped_frame():
    seq = load_vgg(vgg_root() / "model_house")
    raw = raw_cameras("model_house")
    segments, visible = seq.line_observations()
    kept = visible.sum(axis=1) >= 3
    segments, visible = segments[kept][:4], visible[kept][:4]
    for method in METHODS:
        flipped = pluecker.triangulate_lines(seq.cameras, segments, visible, sigma=1.0, options=pluecker.TriangulationOptions(method=method, certify=pluecker.CertifyOptions(max_nodes=300)))
        as_read = pluecker.triangulate_lines(raw, segments, visible, sigma=1.0, options=pluecker.TriangulationOptions(method=method, certify=pluecker.CertifyOptions(max_nodes=300)))
        assert np.all(as_read.status == flipped.status), method
        np.testing.assert_allclose(as_read.cost, flipped.cost, rtol=1e-6)
        np.testing.assert_allclose(as_read.point, -flipped.point, atol=1e-6 * 10)
        np.testing.assert_array_equal(as_read.certified, flipped.certified)
    assert as_read.certified.sum() >= 3, as_read.status


def test_a_point_behind_every_camera_is_reported_not_certified():
    """The issue's example: f = 800, cameras ``K [I | (−c, 0, 0)]`` for c = −1, 0, 1, and the exact images
    of X = (0.1, −0.2, −5). Every point in front costs more than a point at infinity (2 · 160² = 51200)."""
    K = np.array([[800.0, 0, 320], [0, 800.0, 240], [0, 0, 1]])
    P = np.stack([K @ np.hstack([np.eye(3), [[-c], [0], [0]]]) for c in (-1.0, 0.0, 1.0)])
    X = np.array([0.1, -0.2, -5.0])
    x = np.array([project(p, X) for p in P])
    for method in METHODS:
        r = pluecker.triangulate_point(P, x, options=pluecker.TriangulationOptions(method=method))
        assert r.status == "behind_camera", (method, r)
        assert not r.certified
        np.testing.assert_allclose(r.point, X, atol=1e-9)
    batch = pluecker.triangulate_points(P, x[None])
    assert batch.status[0] == "behind_camera" and not batch.certified[0]
    # Negated cameras see the same point in front: the sign of P is part of the camera.
    r = pluecker.triangulate_point(-P, x)
    assert r.status == "success" and r.certified
    np.testing.assert_allclose(r.point, X, atol=1e-9)


def test_parallel_rays_are_at_infinity_for_every_method():
    """Two translated cameras, the same pixel in both: the point is at infinity; no method certifies a far
    point (the cost at infinity is 0, no finite point reaches it)."""
    K = np.array([[800.0, 0, 320], [0, 800.0, 240], [0, 0, 1]])
    P = np.stack([K @ np.hstack([np.eye(3), [[-c], [0], [0]]]) for c in (0.0, 1.0)])
    x = np.array([[300.0, 200.0], [300.0, 200.0]])
    for method in METHODS:
        r = pluecker.triangulate_point(P, x, options=pluecker.TriangulationOptions(method=method))
        assert r.status == "at_infinity", (method, r)
        assert not r.certified and np.all(np.isnan(r.point))
