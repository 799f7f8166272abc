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


def synthetic_model(model_id, params, seed):
    options = pycolmap.SyntheticDatasetOptions()
    options.num_frames_per_rig = 6
    options.num_points3D = 60
    options.camera_model_id = model_id
    options.camera_params = params
    pycolmap.set_random_seed(seed)
    return pycolmap.synthesize_dataset(options)


@pytest.mark.parametrize("model_id, params", [
    (pycolmap.CameraModelId.OPENCV, [300.0, 300.0, 512.0, 384.0, 0.01, -0.002, 1e-4, -1e-4]),
    (pycolmap.CameraModelId.OPENCV_FISHEYE, [300.0, 300.0, 512.0, 384.0, 0.01, -0.002, 1e-3, -1e-4]),
])
def test_retriangulating_a_model_recovers_its_points_certified(model_id, params):
    """A pycolmap synthetic model's observations are exact: every track comes back to its point, with a
    certified cost of (almost) 0, through the camera model's distortion."""
    rec = synthetic_model(model_id, params, 3)
    truth = {i: p.xyz.copy() for i, p in rec.points3D.items()}
    ids, result = colmap.retriangulate(rec)
    assert len(ids) == len(truth) == len(result)
    assert (result.status == "success").all() and result.certified.all()
    assert result.cost.max() < 1e-12
    for i, X in zip(ids, result.X):
        np.testing.assert_allclose(X, truth[int(i)], atol=1e-7 * (1 + np.linalg.norm(truth[int(i)])))
    for p in rec.points3D.values():
        p.xyz = p.xyz + 0.1
    assert colmap.update_points(rec, ids, result) == len(ids)
    for i, p in rec.points3D.items():
        np.testing.assert_allclose(p.xyz, truth[i], atol=1e-6)


def test_with_noise_the_cost_is_the_pixel_reprojection_cost():
    """With 1 px noise on every observation of a distorting camera, the reported cost (normalised
    residuals whitened by the propagated covariances) equals the true squared pixel reprojection error
    at the returned point, computed by pycolmap, to first order: the propagation linearises the
    distortion over about 1 px of a 300 px focal length, a relative error of order 1/300 of the
    distortion's curvature; 1e-3 bounds it. Every point is certified."""
    rec = synthetic_model(pycolmap.CameraModelId.OPENCV, [300.0, 300.0, 512.0, 384.0, 0.05, -0.01, 1e-3, -1e-3], 4)
    rng = np.random.default_rng(1)
    for image in rec.images.values():
        for point2D in image.points2D:
            point2D.xy = point2D.xy + rng.normal(size=2)
    ids, result = colmap.retriangulate(rec)
    assert result.certified.all()
    for i, X, cost in zip(ids, result.X, result.cost):
        pixel_cost = 0.0
        for element in rec.points3D[int(i)].track.elements:
            image = rec.images[element.image_id]
            camera = rec.cameras[image.camera_id]
            u = camera.img_from_cam(np.atleast_2d(image.cam_from_world() * X))[0]
            pixel_cost += np.sum((u - image.points2D[element.point2D_idx].xy) ** 2)
        assert abs(cost / pixel_cost - 1) < 1e-3, (i, cost, pixel_cost)
