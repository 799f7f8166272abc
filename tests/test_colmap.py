"""``pluecker.colmap``: COLMAP's conventions against pycolmap itself (issue 12 §2). pycolmap is part of
the test environment (``make test`` installs it; ``pip install 'pluecker[colmap,test]'``)."""

from __future__ import annotations

import numpy as np
import pycolmap
import pytest

import pluecker
from pluecker import colmap

from camera_models import PARAMS  # noqa: E402  (tests/ is on the path, as for triangulation_scenes)
# The models that see 80° off axis (fisheyes, FOV, EUCM, the barrel division model); the polynomial
# models fold before that.
WIDE = {"OPENCV_FISHEYE", "FOV", "SIMPLE_RADIAL_FISHEYE", "RADIAL_FISHEYE", "THIN_PRISM_FISHEYE",
        "RAD_TAN_THIN_PRISM_FISHEYE", "SIMPLE_DIVISION", "DIVISION", "SIMPLE_FISHEYE", "FISHEYE", "EUCM"}


def test_the_model_lists_agree():
    """Every perspective model of pycolmap, with its name, id (the order of MODELS) and parameter names;
    EQUIRECTANGULAR, the one spherical model, is refused (test below)."""
    colmap_models = {m.name: int(m) for m in pycolmap.CameraModelId.__members__.values() if int(m) >= 0}
    assert set(colmap_models) - set(PARAMS) == {"EQUIRECTANGULAR"}
    # COLMAP's, in the order of their ids, then pluecker's SKEWED_PINHOLE (a K with skew).
    assert pluecker.Camera.MODELS[:-1] == sorted(PARAMS, key=colmap_models.__getitem__)
    assert [colmap_models[m] for m in pluecker.Camera.MODELS[:-1]] == list(range(len(PARAMS)))
    assert pluecker.Camera.MODELS[-1] == "SKEWED_PINHOLE" and "SKEWED_PINHOLE" not in colmap_models
    for model, params in PARAMS.items():
        info = pycolmap.Camera(model=model, width=640, height=480, params=params).params_info
        assert pluecker.Camera(model, params).parameter_names == [s.strip() for s in info.split(",")]


def points_off_axis(rng, n, widest_degrees):
    """n camera-frame points at angles up to widest_degrees off the optical axis, depth 1 to 1.5."""
    theta = np.deg2rad(rng.uniform(0.0, widest_degrees, n))
    phi = rng.uniform(0.0, 2 * np.pi, n)
    z = rng.uniform(1.0, 1.5, n)
    return np.c_[np.tan(theta) * np.cos(phi) * z, np.tan(theta) * np.sin(phi) * z, z]


@pytest.mark.parametrize("model", list(PARAMS))
def test_projection_and_unprojection_agree_with_colmap(model):
    rng = np.random.default_rng(7)
    X = np.c_[rng.uniform(-0.6, 0.6, 100), rng.uniform(-0.45, 0.45, 100), rng.uniform(1.0, 1.5, 100)]
    # Near the axis (FOV's series in r holds below r = 0.01) and, for the wide models, up to 80° off it.
    X = np.r_[X, [[0.0, 0.0, 1.0], [1e-7, -2e-7, 1.0], [3e-3, 4e-3, 1.0], [6e-3, -8e-3, 2.0]]]
    if model in WIDE:
        X = np.r_[X, points_off_axis(rng, 200, 80.0), [[np.tan(np.deg2rad(80.0)), 0.0, 1.0]]]
    ours = pluecker.Camera(model, PARAMS[model])
    theirs = colmap.colmap_camera(ours, 640, 480)
    assert pluecker.Camera(theirs) == ours
    np.testing.assert_allclose(ours.project(X), theirs.img_from_cam(X), rtol=0, atol=1e-9)
    u = ours.project(X)
    # COLMAP's own unprojection (cam_from_img) is iterative for the polynomial models, stopping when its
    # Newton step is below 1e-5 (the error is then about its square), or closed form; ours is exact to
    # 1e-10 px. They agree to COLMAP's accuracy, and ours reprojects to the pixels.
    np.testing.assert_allclose(ours.unproject(u), theirs.cam_from_img(u), atol=1e-6)
    np.testing.assert_allclose(ours.project(np.c_[ours.unproject(u), np.ones(len(u))]), u, atol=2e-10)


@pytest.mark.parametrize("omega", [0.005, 0.9, 3.0])
def test_fov_follows_colmaps_projection_with_its_series(omega):
    """COLMAP's FOV projection replaces the closed form by a series for omega² < 1e-4 (the series of the
    undistortion, so COLMAP's cam_from_img does not invert it there) and for r² < 1e-4; pluecker's
    projection is COLMAP's in every branch, and its unprojection inverts it."""
    rng = np.random.default_rng(11)
    r = np.r_[rng.uniform(0.0, 0.0099, 50), rng.uniform(0.0101, 2.0, 50), 0.0, 1e-9]
    phi = rng.uniform(0.0, 2 * np.pi, len(r))
    X = np.c_[r * np.cos(phi), r * np.sin(phi), np.ones(len(r))]
    params = [400.0, 395.0, 320.0, 240.0, omega]
    ours = pluecker.Camera("FOV", params)
    theirs = pycolmap.Camera(model="FOV", width=640, height=480, params=params)
    u = ours.project(X)
    np.testing.assert_allclose(u, theirs.img_from_cam(X), rtol=0, atol=1e-9)
    # COLMAP's series in r jumps up to the closed form at r = 0.01, by 8e-9 px (omega = 0.9) to 0.045 px
    # (omega = 3; 400 (2 r tan(omega/2))^5 / (5 omega)): a pixel in that gap has no preimage (an error
    # naming it); the points here keep 1e-4 away from r = 0.01.
    np.testing.assert_allclose(ours.project(np.c_[ours.unproject(u), np.ones(len(u))]), u, atol=2e-10)


def test_an_equirectangular_camera_is_refused_by_name():
    """COLMAP's spherical EQUIRECTANGULAR model sees behind the camera, where no (x/z, y/z) exists: such a
    camera is a named error, naming the camera, not a crash or a wrong answer; a model with no other
    camera is a ModelError naming it (with others, their points are solved: the test below)."""
    options = pycolmap.SyntheticDatasetOptions()
    options.num_frames_per_rig, options.num_points3D = 4, 20
    options.camera_model_id = pycolmap.CameraModelId.EQUIRECTANGULAR
    options.camera_params = [1024.0, 512.0]
    pycolmap.set_random_seed(3)
    rec = pycolmap.synthesize_dataset(options)
    camera_id = min(rec.cameras)
    message = rf"camera_id {camera_id}: .*'EQUIRECTANGULAR' is not supported: it is a spherical"
    with pytest.raises(pluecker.InvalidOptionError, match=message):
        pluecker.Camera(rec.cameras[camera_id])
    # Every camera of the model is refused for the same reason: one message names them all.
    ids = ", ".join(map(str, sorted(rec.cameras)))
    with pytest.raises(colmap.ModelError, match=rf"camera_id {ids} \(EQUIRECTANGULAR\): [^;]*is not supported"):
        colmap.retriangulate(rec)
    with pytest.raises(pluecker.InvalidOptionError, match="'EQUIRECTANGULAR' is not supported"):
        pluecker.Camera("EQUIRECTANGULAR", [1024.0, 512.0])


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


# An OPENCV lens without tangential terms: radially symmetric, so the certificate through it applies.
RADIAL_OPENCV = [300.0, 300.0, 512.0, 384.0, 0.05, -0.01, 0.0, 0.0]


def test_a_lens_the_certificate_does_not_cover_gives_exact_costs_and_no_false_certificate():
    """The certificate through a lens does not cover FOV: with noisy observations the points are refined
    on the exact pixel cost and left uncertified (``gap_not_closed``), never certified on an
    approximation."""
    rec = synthetic_model(pycolmap.CameraModelId.FOV, _synthetic_params("FOV"), 4)
    rng = np.random.default_rng(1)
    for image in rec.images.values():
        for point2D in image.points2D:
            point2D.xy = point2D.xy + rng.normal(size=2)
    ids, result = colmap.retriangulate(rec)
    assert not result.certified.any() and (result.status == "gap_not_closed").all()
    i, X = int(ids[0]), result.point[0]
    pixel_cost = sum(np.sum((rec.cameras[rec.images[e.image_id].camera_id].img_from_cam(
        np.atleast_2d(rec.images[e.image_id].cam_from_world() * X))[0]
        - rec.images[e.image_id].points2D[e.point2D_idx].xy) ** 2) for e in rec.points3D[i].track.elements)
    assert abs(result.cost[0] / pixel_cost - 1) < 1e-9


def synthetic_model(model_id, params, seed):
    options = pycolmap.SyntheticDatasetOptions()
    options.num_frames_per_rig = 6
    options.num_points3D = 60
    options.camera_model_id = model_id
    options.camera_params = params
    pycolmap.set_random_seed(seed)
    return pycolmap.synthesize_dataset(options)


def _synthetic_params(model):
    """PARAMS' distortion with this image's focal length 300 and centre (512, 384)."""
    one_focal = pycolmap.Camera(model=model, width=1024, height=768, params=PARAMS[model]).params_info.startswith("f,")
    return ([300.0, 512.0, 384.0] if one_focal else [300.0, 300.0, 512.0, 384.0]) + PARAMS[model][3 if one_focal else 4:]


@pytest.mark.parametrize("model_id, params", [
    (pycolmap.CameraModelId.OPENCV, [300.0, 300.0, 512.0, 384.0, 0.01, -0.002, 1e-4, -1e-4]),
    (pycolmap.CameraModelId.OPENCV_FISHEYE, [300.0, 300.0, 512.0, 384.0, 0.01, -0.002, 1e-3, -1e-4]),
    *[(getattr(pycolmap.CameraModelId, model), _synthetic_params(model))
      for model in ["FOV", "SIMPLE_RADIAL_FISHEYE", "RADIAL_FISHEYE", "THIN_PRISM_FISHEYE", "RAD_TAN_THIN_PRISM_FISHEYE",
                    "SIMPLE_DIVISION", "DIVISION", "SIMPLE_FISHEYE", "FISHEYE", "EUCM"]],
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
    for i, X in zip(ids, result.point):
        np.testing.assert_allclose(X, truth[int(i)], atol=1e-7 * (1 + np.linalg.norm(truth[int(i)])))
    for p in rec.points3D.values():
        p.xyz = p.xyz + 0.1
    assert colmap.update_points(rec, ids, result) == len(ids)
    for i, p in rec.points3D.items():
        np.testing.assert_allclose(p.xyz, truth[i], atol=1e-6)


def test_with_noise_the_cost_is_the_pixel_reprojection_cost():
    """With 1 px noise on every observation of a distorting camera, the reported cost is the squared
    pixel reprojection error at the returned point through the exact projection, computed by pycolmap
    (to rounding), and every point is certified on it (a radially symmetric OPENCV lens)."""
    rec = synthetic_model(pycolmap.CameraModelId.OPENCV, RADIAL_OPENCV, 4)
    rng = np.random.default_rng(1)
    for image in rec.images.values():
        for point2D in image.points2D:
            point2D.xy = point2D.xy + rng.normal(size=2)
    ids, result = colmap.retriangulate(rec)
    assert result.certified.all()
    for i, X, cost in zip(ids, result.point, result.cost):
        pixel_cost = 0.0
        for element in rec.points3D[int(i)].track.elements:
            image = rec.images[element.image_id]
            camera = rec.cameras[image.camera_id]
            u = camera.img_from_cam(np.atleast_2d(image.cam_from_world() * X))[0]
            pixel_cost += np.sum((u - image.points2D[element.point2D_idx].xy) ** 2)
        assert abs(cost / pixel_cost - 1) < 1e-9, (i, cost, pixel_cost)


def test_rigs_of_several_cameras_compose_into_each_image_pose():
    """Images of a rig get their pose from the frame (rig_from_world) and the sensor (cam_from_rig):
    with two cameras per rig the exact observations still give back every point."""
    options = pycolmap.SyntheticDatasetOptions()
    options.num_rigs, options.num_cameras_per_rig, options.num_frames_per_rig = 1, 2, 4
    options.num_points3D = 40
    options.camera_model_id = pycolmap.CameraModelId.OPENCV
    options.camera_params = [300.0, 300.0, 512.0, 384.0, 0.01, -0.002, 1e-4, -1e-4]
    pycolmap.set_random_seed(5)
    rec = pycolmap.synthesize_dataset(options)
    assert rec.num_rigs() == 1 and any(not r.sensor_from_rig(s).rotation.matrix().trace() == 3
                                       for r in rec.rigs.values() for s in r.non_ref_sensors)
    ids, result = colmap.retriangulate(rec)
    for i, X in zip(ids, result.point):
        np.testing.assert_allclose(X, rec.points3D[int(i)].xyz, atol=1e-7 * (1 + np.linalg.norm(X)))


def noisy_model_with_outliers(seed: int):
    """A 12-image OPENCV model (radially symmetric) with 1 px noise and one 40 px outlier in every other
    track."""
    rec = synthetic_model(pycolmap.CameraModelId.OPENCV, RADIAL_OPENCV, seed)
    rng = np.random.default_rng(seed)
    for image in rec.images.values():
        for point2D in image.points2D:
            point2D.xy = point2D.xy + rng.normal(size=2)
    outliers = set()
    for k, (point_id, point) in enumerate(sorted(rec.points3D.items())):
        if k % 2 == 0:
            element = point.track.elements[rng.integers(len(point.track.elements))]
            image = rec.images[element.image_id]
            angle = rng.uniform(0, 2 * np.pi)
            image.points2D[element.point2D_idx].xy = image.points2D[element.point2D_idx].xy + 40 * np.array(
                [np.cos(angle), np.sin(angle)])
            outliers.add((element.image_id, element.point2D_idx))
    return rec, outliers


def test_outlier_observations_are_rejected_and_removed_from_the_written_model(tmp_path):
    rec, outliers = noisy_model_with_outliers(6)
    run = colmap.retriangulate(rec, outlier_threshold_px=4.0)
    rejected = {(int(i), int(k)) for i, k, ok in zip(run.observation_image, run.observation_point2D,
                                                     run.result.inliers) if not ok}
    assert outliers <= rejected  # every outlier, and inliers only at the 4 σ rate (e^-8 of them)
    assert len(rejected - outliers) <= 2
    assert (run.result.status == "success").all() and run.result.certified.all()
    files = {p.name for p in colmap.write(rec, run, tmp_path / "out")}
    assert {"points3D.bin", "images.bin", "points3D.ply", "points3D_triangulation.npz"} <= files
    back = pycolmap.Reconstruction(str(tmp_path / "out"))
    kept = {(e.image_id, e.point2D_idx) for p in back.points3D.values() for e in p.track.elements}
    assert not kept & rejected
    saved = np.load(tmp_path / "out" / "points3D_triangulation.npz")
    np.testing.assert_array_equal(saved["observation_inlier"], run.result.inliers)
    assert saved["covariance"].shape == (len(run.point3D_ids), 3, 3) and saved["certified"].all()
    for i, X in zip(saved["point3D_id"], saved["X"]):
        np.testing.assert_allclose(back.points3D[int(i)].xyz, X)
    ply = (tmp_path / "out" / "points3D.ply").read_text().splitlines()
    assert f"element vertex {len(run.point3D_ids)}" in ply


def test_command_line_retriangulates_a_colmap_model(tmp_path, capsys):
    from pluecker.cli import main

    rec, _ = noisy_model_with_outliers(7)
    (tmp_path / "in").mkdir()
    rec.write(str(tmp_path / "in"))
    code = main(["triangulate", "--colmap", str(tmp_path / "in"), "--out", str(tmp_path / "out"),
                 "--outlier-threshold", "4", "--text"])
    out = capsys.readouterr().out
    assert code == 0 and "60 certified" in out and "removed as outliers" in out
    assert (tmp_path / "out" / "points3D.txt").exists()
    assert main(["triangulate", "--colmap", str(tmp_path / "in")]) == 2
    assert "--out" in capsys.readouterr().err
    assert main(["triangulate", "--colmap", str(tmp_path / "missing"), "--out", str(tmp_path / "o2")]) == 2
    assert "missing: no such directory" in capsys.readouterr().err
    assert main(["triangulate", str(tmp_path), "--colmap", str(tmp_path / "in"), "--out", str(tmp_path / "o3")]) == 2


def test_localize_an_image_of_the_model_with_its_camera_model():
    rec, _ = noisy_model_with_outliers(8)
    image = next(iter(rec.images.values()))
    matched = [p for p in image.points2D if p.has_point3D()]
    u = np.array([p.xy for p in matched])
    X = np.array([rec.points3D[p.point3D_id].xyz for p in matched])
    rng = np.random.default_rng(9)
    wrong = rng.choice(len(u), size=len(u) * 3 // 10, replace=False)  # 30 % outliers
    u[wrong] = rng.uniform([0, 0], [1024, 768], size=(len(wrong), 2))
    rigid, result = colmap.localize(rec.cameras[image.camera_id], u, X)
    assert result.status == "success" and rigid is not None
    R, t = colmap.pose_from_rigid(image.cam_from_world())
    centre = -R.T @ t
    assert np.linalg.norm(-result.pose.rotation.T @ result.pose.translation - centre) < 0.05 * np.linalg.norm(centre)
    np.testing.assert_allclose(np.array(rigid.rotation.matrix()), result.pose.rotation, atol=1e-12)


def test_an_observation_of_a_missing_point_is_a_named_error_never_another_point():
    """A point2D whose point3D_id names no point (a model edited in memory) is refused with its COLMAP
    ids: before, it was attached to the next point by id, whose cost jumped and stayed certified."""
    rec = synthetic_model(pycolmap.CameraModelId.OPENCV, [300.0, 300.0, 512.0, 384.0, 0.01, -0.002, 1e-4, -1e-4], 3)
    image = rec.images[sorted(rec.images)[1]]
    k = next(i for i, p in enumerate(image.points2D) if p.has_point3D())
    missing = max(rec.point3D_ids()) + 7 if k % 2 else min(rec.point3D_ids()) - 1 if min(rec.point3D_ids()) > 1 \
        else max(rec.point3D_ids()) + 7
    image.points2D[k].point3D_id = missing
    with pytest.raises(colmap.ModelError, match=rf"image_id {image.image_id}, point2D_idx {k} .*point3D_id "
                                                rf"{missing}") as info:
        colmap.retriangulate(rec)
    assert isinstance(info.value, pluecker.PlueckerError) and isinstance(info.value, ValueError)
    # A gap inside the ids is refused the same way (the case that attached it to the next point).
    ids = sorted(rec.point3D_ids())
    rec.delete_point3D(ids[5])
    image.points2D[k].point3D_id = ids[5]
    with pytest.raises(colmap.ModelError, match=rf"point3D_id {ids[5]}, which is not in the model"):
        colmap.retriangulate(rec)


@pytest.mark.parametrize("ids", [[1, 2, 5, 9], [7, 10**9, 3 * 10**9, 2**62]], ids=["dense ids: a table", "sparse ids: a search"])
def test_observations_find_the_rows_of_their_points_and_name_a_missing_one(ids):
    """Both ways of finding an observation's point (a lookup table for COLMAP's dense ids, a search
    otherwise) give the same rows, and both name an id that is not in the model: below, between and above
    the model's ids, and negative."""
    ids = np.array(ids, dtype=np.int64)
    wanted = np.array([3, 0, 0, 2, 1, 3])
    rows = colmap._point_rows(ids, ids[wanted], np.arange(6) + 100, np.arange(6))
    np.testing.assert_array_equal(rows, wanted)
    for missing in (ids[0] - 1, ids[1] + 1, ids[-1] + 1, -5):
        point_ids = ids[wanted].copy()
        point_ids[4] = missing
        with pytest.raises(colmap.ModelError, match=rf"image_id 104, point2D_idx 4 observes point3D_id {missing}, "):
            colmap._point_rows(ids, point_ids, np.arange(6) + 100, np.arange(6))


@pytest.mark.parametrize("low, high", [(0, 50), (0, 2**61), (-20, 30)],
                         ids=["unique keys", "keys too large: the stable sort", "negative: the stable sort"])
def test_the_observations_order_is_numpys_stable_sort(low, high):
    """The sort of the table code (the gather's observations by track, Dask's rows and ids) is numpy's
    stable argsort, ties in row order, for small ids (the fast unique-key sort), for ids whose keys would
    overflow and for negative ids (the stable sort itself)."""
    from pluecker._sorting import stable_order

    track = np.random.default_rng(3).integers(low, high, size=2000, dtype=np.int64)
    track[::7] = track[0]  # many ties
    np.testing.assert_array_equal(stable_order(track), np.argsort(track, kind="stable"))
    assert len(stable_order(np.zeros(0, dtype=np.int64))) == 0


def test_an_empty_model_is_a_named_error_and_one_line_on_the_command_line(tmp_path, capsys):
    from pluecker.cli import main

    with pytest.raises(colmap.ModelError, match="no 3-D points"):
        colmap.retriangulate(pycolmap.Reconstruction())
    (tmp_path / "empty").mkdir()
    pycolmap.Reconstruction().write(str(tmp_path / "empty"))
    assert main(["triangulate", "--colmap", str(tmp_path / "empty"), "--out", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "no 3-D points" in err and "Traceback" not in err


def test_the_command_line_never_writes_into_the_input_model(tmp_path, capsys):
    """``--out`` resolving to the input folder (same path, a trailing ``/.``, a symlink) is one line and
    exit 2, and the input's files are untouched."""
    from pluecker.cli import main

    rec, _ = noisy_model_with_outliers(11)
    model = tmp_path / "in"
    model.mkdir()
    rec.write(str(model))
    (tmp_path / "link").symlink_to(model)
    before = {p.name: p.read_bytes() for p in model.iterdir()}
    for out in (model, model / ".", tmp_path / "link"):
        assert main(["triangulate", "--colmap", str(model), "--out", str(out)]) == 2
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and "is the input --colmap" in err
    assert {p.name: p.read_bytes() for p in model.iterdir()} == before


def test_the_written_model_is_complete_and_honest(tmp_path):
    """What write() puts out: ERROR recomputed for the moved points as COLMAP defines it (the mean pixel
    reprojection error, computed here through pycolmap's own projection), every point in the PLY
    coloured by state with a legend, the npz saying what ``certified`` proves, and only the files
    written listed."""
    rec, _ = noisy_model_with_outliers(12)
    out = tmp_path / "out"
    out.mkdir()
    (out / "notes.txt").write_text("a user's file")
    run = colmap.retriangulate(rec, outlier_threshold_px=4.0)
    files = colmap.write(rec, run, out)
    assert out / "notes.txt" not in files and {"points3D.bin", "points3D.ply"} <= {f.name for f in files}
    back = pycolmap.Reconstruction(str(out))
    for point in back.points3D.values():
        errors = []
        for element in point.track.elements:
            image = back.images[element.image_id]
            u = back.cameras[image.camera_id].img_from_cam(np.atleast_2d(image.cam_from_world() * point.xyz))[0]
            errors.append(np.linalg.norm(u - image.points2D[element.point2D_idx].xy))
        assert abs(point.error - np.mean(errors)) < 1e-9 * (1 + np.mean(errors))
    ply = (out / "points3D.ply").read_text().splitlines()
    assert f"element vertex {back.num_points3D()}" in ply
    assert any(line.startswith("comment pluecker: certified = rgb") for line in ply)
    assert any(line.startswith("comment pluecker: unsolved = rgb") for line in ply)
    saved = np.load(out / "points3D_triangulation.npz")
    assert "lower bound on the global minimum" in str(saved["certified_meaning"])
    # Writing again reports the files rewritten, and still not the user's file.
    assert out / "notes.txt" not in colmap.write(rec, run, out)


def test_unsolved_points_stay_in_the_ply_in_their_colour(tmp_path):
    """A track that cannot be solved (a two-view track whose second view is 100 px off, so that no pair
    of views fits within the 4 px threshold) keeps its model position and is in the PLY as unsolved."""
    rec = synthetic_model(pycolmap.CameraModelId.OPENCV, [300.0, 300.0, 512.0, 384.0, 0.01, -0.002, 1e-4, -1e-4], 13)
    point_id, point = next((i, p) for i, p in sorted(rec.points3D.items()) if p.track.length() >= 2)
    elements = [(e.image_id, e.point2D_idx) for e in point.track.elements]  # copies: deleting moves the rest
    for image_id, point2D_idx in elements[2:]:
        rec.delete_observation(image_id, point2D_idx)
    moved = rec.images[elements[1][0]].points2D[elements[1][1]]
    moved.xy = moved.xy + np.array([100.0, 0.0])
    xyz = rec.points3D[point_id].xyz.copy()
    run = colmap.retriangulate(rec, outlier_threshold_px=4.0)
    row = int(np.flatnonzero(run.point3D_ids == point_id)[0])
    assert run.result.status[row] != "success"
    colmap.write(rec, run, tmp_path / "out")
    ply = (tmp_path / "out" / "points3D.ply").read_text().splitlines()
    assert f"element vertex {rec.num_points3D()}" in ply
    red = " ".join(map(str, colmap.PLY_COLOURS["unsolved"]))
    rows = [line for line in ply if line.endswith(red) and not line.startswith("comment")]
    assert len(rows) == 1 and np.allclose([float(v) for v in rows[0].split()[:3]], xyz, rtol=1e-8)


def test_summaries_count_only_removed_observations_and_unsolved_flags_are_unknown(tmp_path, capsys):
    """The observations of a point that was not re-triangulated are neither removed nor called outliers:
    the command line counts the observations it deleted from the model, and the npz marks the unsolved
    point's observations ``unknown``; its status line names the point3D_id."""
    from pluecker.cli import main

    rec, _ = noisy_model_with_outliers(14)
    point_id, point = next((i, p) for i, p in sorted(rec.points3D.items()) if p.track.length() >= 3)
    elements = [(e.image_id, e.point2D_idx) for e in point.track.elements]
    for image_id, point2D_idx in elements[2:]:
        rec.delete_observation(image_id, point2D_idx)
    moved = rec.images[elements[1][0]].points2D[elements[1][1]]
    moved.xy = moved.xy + np.array([100.0, 0.0])
    (tmp_path / "in").mkdir()
    rec.write(str(tmp_path / "in"))
    observations = sum(p.track.length() for p in rec.points3D.values())
    assert main(["triangulate", "--colmap", str(tmp_path / "in"), "--out", str(tmp_path / "out"),
                 "--outlier-threshold", "4"]) == 0
    out = capsys.readouterr().out
    back = pycolmap.Reconstruction(str(tmp_path / "out"))
    removed = observations - sum(p.track.length() for p in back.points3D.values())
    assert f"observations: {removed} of {observations} removed as outliers" in out
    assert f"point3D_id {point_id}" in out
    saved = np.load(tmp_path / "out" / "points3D_triangulation.npz")
    mine = saved["observation_point3D_id"] == point_id
    assert mine.sum() == 2 and (saved["observation_state"][mine] == "unknown").all()
    assert (saved["observation_state"] == "outlier").sum() == removed


def test_a_camera_that_cannot_be_handled_is_named_and_the_others_solved(tmp_path, capsys):
    """One camera of a model that pluecker cannot handle (here a zero focal length; equally a model it
    does not know) does not refuse the model: the other cameras' observations are solved, and the camera
    is named with COLMAP's id."""
    from pluecker.cli import main

    options = pycolmap.SyntheticDatasetOptions()
    options.num_rigs, options.num_cameras_per_rig, options.num_frames_per_rig = 2, 1, 4
    options.num_points3D = 40
    options.camera_model_id = pycolmap.CameraModelId.OPENCV
    options.camera_params = [300.0, 300.0, 512.0, 384.0, 0.01, -0.002, 1e-4, -1e-4]
    pycolmap.set_random_seed(15)
    rec = pycolmap.synthesize_dataset(options)
    odd = sorted(rec.cameras)[1]
    rec.cameras[odd] = pycolmap.Camera(camera_id=odd, model="SIMPLE_PINHOLE", width=1024, height=768,
                                       params=[0.0, 512.0, 384.0])  # a zero focal length: no camera
    run = colmap.retriangulate(rec)
    named = [m for m in run.skipped if m.startswith(f"camera_id {odd} (SIMPLE_PINHOLE)") and "focal" in m]
    assert len(named) == 1 and len(run.skipped) == 1
    used = set(run.observation_image.tolist())
    assert used and not used & {i for i, image in rec.images.items() if image.camera_id == odd}
    seen_twice = np.bincount(run.observation_point, minlength=len(run.point3D_ids)) >= 2
    assert (run.result.status[seen_twice] == "success").all() and seen_twice.sum() >= 10
    (tmp_path / "in").mkdir()
    rec.write(str(tmp_path / "in"))
    assert main(["triangulate", "--colmap", str(tmp_path / "in"), "--out", str(tmp_path / "out")]) == 0
    out = capsys.readouterr().out
    assert f"camera_id {odd} (SIMPLE_PINHOLE)" in out


def test_a_pixel_beyond_the_fold_is_left_out_by_name():
    """A pixel with no preimage through its camera's distortion (past the fold of a strong barrel) is left
    out, named, and its point solved from its other views."""
    rec = synthetic_model(pycolmap.CameraModelId.SIMPLE_RADIAL, [300.0, 512.0, 384.0, -0.05], 16)
    point_id, point = next((i, p) for i, p in sorted(rec.points3D.items()) if p.track.length() >= 4)
    element = point.track.elements[0]
    image_id, point2D_idx = element.image_id, element.point2D_idx
    fold = pluecker.Camera("SIMPLE_RADIAL", [300.0, 512.0, 384.0, -0.05])
    rec.images[image_id].points2D[point2D_idx].xy = np.array([512.0 + 300.0 * 3.0, 384.0])  # r = 3 > fold at 2.58
    with pytest.raises(pluecker.PlueckerError):
        fold.undistort([[512.0 + 300.0 * 3.0, 384.0]])
    run = colmap.retriangulate(rec)
    assert len(run.skipped) == 1 and run.skipped[0].startswith(
        f"image_id {image_id}, point2D_idx {point2D_idx} (point3D_id {point_id})")
    row = int(np.flatnonzero(run.point3D_ids == point_id)[0])
    assert run.result.status[row] == "success"


def with_a_second_keypoint(rec, image_id: int, point_id: int, xy, folder):
    """``rec`` with one more keypoint ``xy`` in image ``image_id`` on the track of ``point_id``, edited in
    COLMAP's text files as track merging leaves such tracks (pycolmap cannot append to an image's
    keypoints in memory)."""
    folder.mkdir()
    rec.write_text(str(folder))
    images = (folder / "images.txt").read_text().splitlines()
    at = next(k for k, line in enumerate(images) if line and not line.startswith("#")
              and int(line.split()[0]) == image_id)
    index = len(images[at + 1].split()) // 3
    images[at + 1] = f"{images[at + 1]} {xy[0]:.17g} {xy[1]:.17g} {point_id}".strip()
    (folder / "images.txt").write_text("\n".join(images) + "\n")
    points = (folder / "points3D.txt").read_text().splitlines()
    at = next(k for k, line in enumerate(points) if line and not line.startswith("#")
              and int(line.split()[0]) == point_id)
    points[at] = f"{points[at]} {image_id} {index}"
    (folder / "points3D.txt").write_text("\n".join(points) + "\n")
    return pycolmap.Reconstruction(str(folder))


def test_a_track_that_sees_one_image_twice_uses_both_keypoints(tmp_path):
    """COLMAP's track merging can leave two keypoints of one image on one track: both are used (the
    cost counts every observation, as pycolmap's bundle adjustment does)."""
    rec = synthetic_model(pycolmap.CameraModelId.OPENCV, RADIAL_OPENCV, 17)
    point_id, point = next((i, p) for i, p in sorted(rec.points3D.items()) if p.track.length() >= 3)
    image_id = point.track.elements[0].image_id
    image = rec.images[image_id]
    u = rec.cameras[image.camera_id].img_from_cam(np.atleast_2d(image.cam_from_world() * point.xyz))[0]
    rec = with_a_second_keypoint(rec, image_id, point_id, u + np.array([0.7, -0.4]), tmp_path / "merged")
    run = colmap.retriangulate(rec)
    row = int(np.flatnonzero(run.point3D_ids == point_id)[0])
    mine = run.observation_point == row
    assert mine.sum() == rec.points3D[point_id].track.length() and (run.observation_image[mine] == image_id).sum() == 2
    assert run.result.status[row] == "success" and run.result.certified[row]
    # The cost is the squared pixel error over every observation (noise-free but the moved keypoint).
    X = run.result.point[row]
    pixel_cost = 0.0
    for element in rec.points3D[point_id].track.elements:
        im = rec.images[element.image_id]
        proj = rec.cameras[im.camera_id].img_from_cam(np.atleast_2d(im.cam_from_world() * X))[0]
        pixel_cost += np.sum((proj - im.points2D[element.point2D_idx].xy) ** 2)
    assert pixel_cost > 0.1 and abs(run.result.cost[row] - pixel_cost) <= 1e-3 * pixel_cost


def test_the_distributed_tables_solve_as_retriangulate_does_through_the_lens():
    """``observation_table`` hands the observed pixels and each image's Camera to the distributed
    kernel: the same exact-cost points, costs and certificates as :func:`colmap.retriangulate`."""
    from pluecker import distributed

    rec = synthetic_model(pycolmap.CameraModelId.OPENCV, [300.0, 300.0, 512.0, 384.0, 0.05, -0.01, 1e-3, -1e-3], 4)
    rng = np.random.default_rng(2)
    for image in rec.images.values():
        for point2D in image.points2D:
            point2D.xy = point2D.xy + rng.normal(size=2)
    run = colmap.retriangulate(rec)
    cameras, table = colmap.observation_table(rec)
    points, _ = distributed.triangulate_table(table, cameras)
    np.testing.assert_array_equal(points.column("track").to_numpy(), run.point3D_ids)
    np.testing.assert_array_equal(np.c_[points.column("X"), points.column("Y"), points.column("Z")], run.result.point)
    np.testing.assert_array_equal(points.column("cost").to_numpy(), run.result.cost)
    np.testing.assert_array_equal(points.column("certified").to_numpy(), run.result.certified)
    assert run.result.certified.all()


def test_the_binary_read_of_the_keypoints_equals_pycolmaps_objects(tmp_path):
    """``_keypoints`` (one pass over a temporary images.bin) gives every image's observed pixels, point3D
    ids and point2D indices exactly as pycolmap's per-keypoint objects do, also after observations are
    deleted and a second keypoint of one image joins a track."""
    rec = synthetic_model(pycolmap.CameraModelId.OPENCV, RADIAL_OPENCV, 21)
    image = next(iter(rec.images.values()))
    rec.delete_observation(image.image_id, int(image.get_observation_point2D_idxs()[0]))
    point_id, point = next((i, p) for i, p in sorted(rec.points3D.items()) if p.track.length() >= 3)
    other = rec.images[point.track.elements[0].image_id]
    u = rec.cameras[other.camera_id].img_from_cam(np.atleast_2d(other.cam_from_world() * point.xyz))[0] + 0.5
    rec = with_a_second_keypoint(rec, other.image_id, point_id, u, tmp_path / "model")
    keypoints = colmap._keypoints(rec)
    assert keypoints is not None and sorted(keypoints) == sorted(rec.images)
    for image in rec.images.values():
        for ours, theirs in zip(keypoints[image.image_id], colmap._observed(image)):
            np.testing.assert_array_equal(ours, theirs)
