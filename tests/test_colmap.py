"""``pluecker.colmap``: COLMAP's conventions against pycolmap itself (issue 12 §2). pycolmap is part of
the test environment (``make test`` installs it; ``pip install 'pluecker[colmap,test]'``)."""

from __future__ import annotations

import numpy as np
import pycolmap
import pytest

import pluecker
from pluecker import colmap

PARAMS = {
    "SIMPLE_PINHOLE": [800.0, 320.0, 240.0],
    "PINHOLE": [800.0, 790.0, 320.0, 240.0],
    "SIMPLE_RADIAL": [800.0, 320.0, 240.0, -0.1],
    "RADIAL": [800.0, 320.0, 240.0, -0.1, 0.02],
    "OPENCV": [800.0, 790.0, 320.0, 240.0, -0.2, 0.05, 1e-3, -5e-4],
    "FULL_OPENCV": [800.0, 790.0, 320.0, 240.0, -0.2, 0.05, 1e-3, -5e-4, 0.01, 0.02, -0.01, 0.005],
    "OPENCV_FISHEYE": [400.0, 395.0, 320.0, 240.0, 0.05, -0.01, 0.002, -3e-4],
}


def test_the_model_lists_agree():
    assert set(PARAMS) <= {m.name for m in pycolmap.CameraModelId.__members__.values()}
    assert set(pluecker.LensCamera.MODELS) == set(PARAMS)


@pytest.mark.parametrize("model", list(PARAMS))
def test_projection_and_unprojection_agree_with_colmap(model):
    rng = np.random.default_rng(7)
    X = np.c_[rng.uniform(-0.6, 0.6, 100), rng.uniform(-0.45, 0.45, 100), rng.uniform(1.0, 1.5, 100)]
    ours = pluecker.LensCamera(model, PARAMS[model])
    theirs = colmap.colmap_camera(ours, 640, 480)
    assert colmap.lens_camera(theirs) == ours
    np.testing.assert_allclose(ours.project(X), theirs.img_from_cam(X), rtol=0, atol=1e-9)
    u = ours.project(X)
    # COLMAP's own unprojection (cam_from_img) is iterative with its own tolerance; ours is exact to
    # 1e-10 px. They agree to COLMAP's accuracy, and ours reprojects to the pixels.
    np.testing.assert_allclose(ours.unproject(u), theirs.cam_from_img(u), atol=1e-6)
    np.testing.assert_allclose(ours.project(np.c_[ours.unproject(u), np.ones(len(u))]), u, atol=2e-10)


def test_poses_round_trip_through_rigid3d():
    scene = pluecker.random_scene("general", 4, 0, seed=3)
    R, t = scene["R"], scene["t"]
    rigid = colmap.rigid_from_pose(R, t)
    X = scene["points3d"]
    np.testing.assert_allclose((rigid.matrix() @ np.c_[X, np.ones(len(X))].T).T, X @ R.T + t, atol=1e-12)
    R2, t2 = colmap.pose_from_rigid(rigid)
    np.testing.assert_allclose(R2, R, atol=1e-12)
    np.testing.assert_allclose(t2, t, atol=1e-15)
    with pytest.raises(pluecker.InvalidOptionError, match="R: expected a rotation matrix"):
        colmap.rigid_from_pose(2 * R, t)


def test_quaternion_orders():
    rng = np.random.default_rng(2)
    q = rng.normal(size=4)
    q /= np.linalg.norm(q)
    rotation = pycolmap.Rotation3d(q)  # pycolmap: (x, y, z, w)
    wxyz = colmap.quaternion_wxyz(q)
    np.testing.assert_allclose(colmap.rotation_from_quaternion(wxyz), rotation.matrix(), atol=1e-12)
    np.testing.assert_allclose(colmap.quaternion_xyzw(wxyz), q)
    # pluecker's dual quaternion holds the same rotation quaternion first, up to sign.
    r = pluecker.pose_to_dual_quaternion(rotation.matrix(), np.zeros(3))[:4]
    assert min(np.abs(r - wxyz).max(), np.abs(r + wxyz).max()) < 1e-12
