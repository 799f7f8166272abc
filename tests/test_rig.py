"""``pluecker.Rig``: cameras fixed to one body, each at ``sensor_from_rig`` (``x_sensor = R x_rig + t``);
checked against poses composed here in numpy, refused by name when it is not a rig, pickled, and read
from a pycolmap reconstruction's rig."""

from __future__ import annotations

import pickle

import numpy as np
import pluecker
import pytest


def rotation(rx: float, ry: float, rz: float) -> np.ndarray:
    """``Rz Ry Rx`` of the three angles (radians)."""
    cx, sx, cy, sy, cz, sz = np.cos(rx), np.sin(rx), np.cos(ry), np.sin(ry), np.cos(rz), np.sin(rz)
    Rx = np.array([[1, 0, 0], [0, cx, -sx], [0, sx, cx]])
    Ry = np.array([[cy, 0, sy], [0, 1, 0], [-sy, 0, cy]])
    Rz = np.array([[cz, -sz, 0], [sz, cz, 0], [0, 0, 1]])
    return Rz @ Ry @ Rx


CAMERAS = [pluecker.Camera("PINHOLE", [800.0, 790.0, 320.0, 240.0]),
           pluecker.Camera("OPENCV", [600.0, 600.0, 320.0, 240.0, -0.1, 0.01, 1e-3, -1e-3]),
           pluecker.Camera("SIMPLE_RADIAL", [500.0, 320.0, 240.0, 0.05])]
POSES = [(np.eye(3), np.zeros(3)),
         (rotation(0.0, np.pi / 2, 0.0), np.array([0.1, 0.0, -0.2])),
         (rotation(0.05, -np.pi / 3, 0.1), np.array([-0.3, 0.02, 0.1]))]


def test_each_camera_is_placed_by_the_rigs_pose():
    rig = pluecker.Rig(CAMERAS, POSES)
    assert len(rig) == 3 and [c.model for c in rig.cameras] == ["PINHOLE", "OPENCV", "SIMPLE_RADIAL"]
    for (R, t), pose in zip(POSES, rig.sensor_from_rig):
        np.testing.assert_array_equal(pose.rotation, R)
        np.testing.assert_array_equal(pose.translation, t)
    # Centres in the body's frame: the points the sensors' frames have at their origins.
    for (R, t), c in zip(POSES, rig.centres):
        np.testing.assert_allclose(R @ c + t, 0.0, atol=1e-15)
    assert not rig.is_central
    R_rig, t_rig = rotation(0.3, -0.2, 1.1), np.array([0.4, -1.0, 7.0])
    X = np.array([0.3, -0.5, 1.2])
    for (R, t), view, camera in zip(POSES, rig.views(R_rig, t_rig), CAMERAS):
        # world -> body -> sensor, composed here, against the view's one step.
        x_cam = R @ (R_rig @ X + t_rig) + t
        R_view, t_view = view.pose
        np.testing.assert_allclose(R_view @ X + t_view, x_cam, atol=1e-14)
        assert view.camera == camera


def test_one_camera_or_cameras_at_one_centre_are_central():
    assert pluecker.Rig(CAMERAS[:1], POSES[:1]).is_central
    turned = [(np.eye(3), np.zeros(3)), (rotation(0.0, 0.7, 0.0), np.zeros(3))]
    assert pluecker.Rig(CAMERAS[:2], turned).is_central


def test_a_rig_that_is_not_one_is_refused_by_name():
    with pytest.raises(pluecker.ShapeError, match="cameras: expected at least one camera"):
        pluecker.Rig([], [])
    with pytest.raises(pluecker.ShapeError, match=r"sensor_from_rig: expected one pose per camera \(3\), got 2"):
        pluecker.Rig(CAMERAS, POSES[:2])
    sheared = np.eye(3)
    sheared[0, 1] = 0.01
    with pytest.raises(pluecker.InvalidOptionError, match=r"sensor_from_rig\[1\] R: expected a rotation matrix"):
        pluecker.Rig(CAMERAS[:2], [POSES[0], (sheared, np.zeros(3))])
    mirrored = np.diag([1.0, 1.0, -1.0])
    with pytest.raises(pluecker.InvalidOptionError, match=r"sensor_from_rig\[0\] R: .*det R = -1"):
        pluecker.Rig(CAMERAS[:1], [(mirrored, np.zeros(3))])
    with pytest.raises(pluecker.NonFiniteError, match=r"sensor_from_rig\[0\] t"):
        pluecker.Rig(CAMERAS[:1], [(np.eye(3), np.array([np.nan, 0.0, 0.0]))])
    with pytest.raises(TypeError, match=r"cameras\[1\]"):
        pluecker.Rig([CAMERAS[0], "PINHOLE"], POSES[:2])
    with pytest.raises(TypeError, match=r"sensor_from_rig\[0\]"):
        pluecker.Rig(CAMERAS[:1], [np.eye(4)])


def test_a_rig_pickles_and_its_dict_rebuilds_it():
    rig = pluecker.Rig(CAMERAS, POSES)
    assert pickle.loads(pickle.dumps(rig)) == rig
    d = rig.to_dict()
    assert list(d) == ["cameras", "sensor_from_rig"]
    assert d["cameras"][1] == {"model": "OPENCV", "params": list(CAMERAS[1].params)}
    np.testing.assert_array_equal(np.array(d["sensor_from_rig"][1]["rotation"]), POSES[1][0])  # rows
    again = pluecker.Rig([pluecker.Camera(c["model"], c["params"]) for c in d["cameras"]],
                         [(np.array(p["rotation"]), np.array(p["translation"])) for p in d["sensor_from_rig"]])
    assert again == rig and again != pluecker.Rig(CAMERAS[:1], POSES[:1])


def colmap_rig_model(with_calibration: bool = True):
    """A pycolmap reconstruction with cameras 1 (PINHOLE) and 2 (OPENCV) and rig 7: camera 1 its
    reference sensor, camera 2 at ``POSES[1]``."""
    pycolmap = pytest.importorskip("pycolmap")
    from pluecker import colmap

    rec = pycolmap.Reconstruction()
    for camera_id, camera in ((1, CAMERAS[0]), (2, CAMERAS[1])):
        rec.add_camera(pycolmap.Camera(camera_id=camera_id, model=camera.model, width=640, height=480,
                                       params=list(camera.params)))
    rig = pycolmap.Rig(rig_id=7)
    rig.add_ref_sensor(pycolmap.sensor_t(type=pycolmap.SensorType.CAMERA, id=1))
    second = pycolmap.sensor_t(type=pycolmap.SensorType.CAMERA, id=2)
    if with_calibration:
        rig.add_sensor(second, colmap.rigid_from_pose(*POSES[1]))
    else:
        rig.add_sensor(second, None)
    rec.add_rig(rig)
    return rec


def test_a_colmap_rig_is_read_as_it_is():
    from pluecker import colmap

    rig = colmap.rig(colmap_rig_model(), 7)
    assert [c.model for c in rig.cameras] == ["PINHOLE", "OPENCV"]
    np.testing.assert_array_equal(rig.cameras[1].params, CAMERAS[1].params)
    np.testing.assert_allclose(rig.sensor_from_rig[0].rotation, np.eye(3), atol=0)
    np.testing.assert_allclose(rig.sensor_from_rig[1].rotation, POSES[1][0], atol=1e-12)
    np.testing.assert_allclose(rig.sensor_from_rig[1].translation, POSES[1][1], atol=1e-15)


def test_a_colmap_rig_that_cannot_be_read_names_its_rig_and_sensor():
    from pluecker import colmap

    with pytest.raises(colmap.ModelError, match=r"rig_id 8: no such rig in the reconstruction \(its rig_ids: 7\)"):
        colmap.rig(colmap_rig_model(), 8)
    with pytest.raises(colmap.ModelError, match="rig_id 7, sensor CAMERA id 2: no sensor_from_rig"):
        colmap.rig(colmap_rig_model(with_calibration=False), 7)


def test_colmaps_rigs_place_their_images_as_pluecker_rigs_do():
    """On pycolmap's synthetic model with two rigs of three cameras (sensors turned by tens of degrees and
    offset by tenths of the scene), every image's ``cam_from_world`` is its camera's view in
    ``colmap.rig(...).views(*frame.rig_from_world)``, and the model re-triangulates with every point
    certified."""
    pycolmap = pytest.importorskip("pycolmap")
    from pluecker import colmap

    options = pycolmap.SyntheticDatasetOptions(num_rigs=2, num_cameras_per_rig=3, num_frames_per_rig=4,
                                               num_points3D=60, sensor_from_rig_translation_stddev=0.3,
                                               sensor_from_rig_rotation_stddev=30.0)
    pycolmap.set_random_seed(3)
    rec = pycolmap.synthesize_dataset(options)
    rigs = {rig_id: colmap.rig(rec, rig_id) for rig_id in rec.rigs}
    assert sorted(len(r) for r in rigs.values()) == [3, 3] and not any(r.is_central for r in rigs.values())
    checked = 0
    for image in rec.images.values():
        frame = rec.frame(image.frame_id)
        rig = rigs[frame.rig_id]
        views = rig.views(*colmap.pose_from_rigid(frame.rig_from_world))
        # colmap.rig's order: the reference sensor, then the others by id (a camera sensor's id is its camera_id).
        colmap_rig = rec.rig(frame.rig_id)
        order = [colmap_rig.ref_sensor_id.id, *sorted(s.id for s in colmap_rig.non_ref_sensors)]
        view = views[order.index(image.camera_id)]
        R, t = colmap.pose_from_rigid(image.cam_from_world())
        np.testing.assert_allclose(view.pose[0], R, atol=1e-12, err_msg=str(image.image_id))
        np.testing.assert_allclose(view.pose[1], t, atol=1e-12, err_msg=str(image.image_id))
        assert view.camera == rig.cameras[order.index(image.camera_id)]
        checked += 1
    assert checked == rec.num_images() == 24
    run = colmap.retriangulate(rec)
    assert int(np.sum(run.result.certified)) == rec.num_points3D() == 60 and not run.skipped


def test_a_synthetic_rig_of_mixed_lenses_is_seen_through_each_lens():
    """``scenes.colmap_rig_reconstruction``: one rig of four cameras of four models; with no noise every
    observation is the pixel of its point through its own camera, placed by ``colmap.rig``; the same seed
    gives the same model."""
    pytest.importorskip("pycolmap")
    from pluecker import colmap, scenes

    cameras = [("PINHOLE", [500.0, 500.0, 320.0, 240.0]),
               ("OPENCV", [450.0, 455.0, 320.0, 240.0, -0.05, 0.01, 1e-3, -1e-3]),
               ("SIMPLE_RADIAL", [400.0, 320.0, 240.0, 0.02]),
               ("OPENCV_FISHEYE", [300.0, 300.0, 320.0, 240.0, 0.02, -0.01, 0.0, 0.0])]
    rec = scenes.colmap_rig_reconstruction(cameras, 640, 480, noise_px=0.0, seed=4, points=300)
    assert rec.num_rigs() == 1 and rec.num_images() == 24
    (rig_id,) = rec.rigs
    rig = colmap.rig(rec, rig_id)
    assert [c.model for c in rig.cameras] == [m for m, _ in cameras]
    colmap_rig = rec.rig(rig_id)
    order = [colmap_rig.ref_sensor_id.id, *sorted(s.id for s in colmap_rig.non_ref_sensors)]
    worst, seen = 0.0, set()
    for image in rec.images.values():
        frame = rec.frame(image.frame_id)
        k = order.index(image.camera_id)
        R, t = rig.views(*colmap.pose_from_rigid(frame.rig_from_world))[k].pose
        for point2D in image.points2D:
            if point2D.has_point3D():
                x_cam = R @ rec.points3D[point2D.point3D_id].xyz + t
                worst = max(worst, float(np.abs(rig.cameras[k].project(x_cam[None])[0] - point2D.xy).max()))
                seen.add(k)
    assert worst < 1e-8 and seen == {0, 1, 2, 3}, (worst, seen)
    again = scenes.colmap_rig_reconstruction(cameras, 640, 480, noise_px=0.0, seed=4, points=300)
    assert sorted(again.points3D) == sorted(rec.points3D)
    assert all(np.array_equal(again.points3D[i].xyz, p.xyz) and again.points3D[i].track.length() == p.track.length()
               for i, p in rec.points3D.items())
    with pytest.raises(ValueError, match="cameras: a rig of 2 to 6 cameras, got 1"):
        scenes.colmap_rig_reconstruction(cameras[:1], 640, 480)
