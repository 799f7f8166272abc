"""COLMAP models and arguments that cannot be used as they stand: a camera or image that cannot be used
is left out and named by its COLMAP id (one message per reason, every id of it), and the rest is solved;
a σ whose square does not fit a double is an ``InvalidOptionError`` naming ``sigma_px``; a folder that
holds no model, or a broken model file, is one line naming what is missing or broken; numbers in
messages have at most 6 significant digits. pycolmap is part of the test environment."""

from __future__ import annotations

import re

import numpy as np
import pytest

pycolmap = pytest.importorskip("pycolmap")

import pluecker  # noqa: E402
from pluecker import colmap  # noqa: E402
from pluecker.cli import main  # noqa: E402


def model(seed: int = 15, cameras: int = 2, frames: int = 4, points: int = 40):
    """A synthetic model of ``cameras`` rigs of one OPENCV camera each, ``frames`` frames per rig."""
    options = pycolmap.SyntheticDatasetOptions()
    options.num_rigs, options.num_cameras_per_rig, options.num_frames_per_rig = cameras, 1, frames
    options.num_points3D = points
    options.camera_model_id = pycolmap.CameraModelId.OPENCV
    options.camera_params = [300.0, 300.0, 512.0, 384.0, 0.01, -0.002, 1e-4, -1e-4]
    pycolmap.set_random_seed(seed)
    return pycolmap.synthesize_dataset(options)


def short(message: str) -> None:
    """A message as the issue asks: no number printed with more than 6 significant digits (no run of 7
    digits), and not thousands of characters."""
    assert re.search(r"\d{7,}", message) is None, message
    assert len(message) < 400, message


def assert_rest_solved(rec, run, unusable_images: set[int]) -> None:
    """The observations of the images left out are not used; every point seen by two used images is
    solved."""
    used = set(run.observation_image.tolist())
    assert used and not used & unusable_images
    seen_twice = np.bincount(run.observation_point, minlength=len(run.point3D_ids)) >= 2
    assert seen_twice.sum() >= 10 and (run.result.status[seen_twice] == "success").all()


def replace_camera(rec, camera_id: int, params) -> None:
    rec.cameras[camera_id] = pycolmap.Camera(camera_id=camera_id, model="PINHOLE", width=1024, height=768,
                                             params=params)


@pytest.mark.parametrize("focal, words", [
    (1e-300, "focal lengths must be non-zero (at least 1e-9 px), got fx=1e-300, fy=1e-300"),
    (0.0, "focal lengths must be non-zero (at least 1e-9 px), got fx=0, fy=0"),
    (1e300, "focal lengths too large: det K = fx fy overflows double precision, got fx=1e+300, fy=1e+300"),
])
def test_a_camera_with_an_unusable_focal_length_is_left_out_by_camera_id(focal, words):
    """fx = fy = 1e-300 aborted the run with a 665-character message without the camera_id; 1e300 with
    ``projections: row 4 is not K [R | t] of the pinhole part of cameras[4]`` (internal indices)."""
    rec = model()
    odd = sorted(rec.cameras)[1]
    replace_camera(rec, odd, [focal, focal, 512.0, 384.0])
    run = colmap.retriangulate(rec)
    assert len(run.skipped) == 1, run.skipped
    assert run.skipped[0].startswith(f"camera_id {odd} (PINHOLE): singular camera: "), run.skipped
    assert words in run.skipped[0]
    short(run.skipped[0])
    assert_rest_solved(rec, run, {i for i, image in rec.images.items() if image.camera_id == odd})


def test_the_core_refuses_such_focal_lengths_with_short_numbers():
    """The core's camera messages print numbers as C's %g does (``1e-300``, not 300 zeros)."""
    for make in (lambda f: pluecker.Camera.pinhole(f, f, 320.0, 240.0), lambda f: pluecker.Camera("PINHOLE", [f, f, 1, 1])):
        for focal in (1e-300, 1e300, 123456789.123e150):
            with pytest.raises(pluecker.SingularCameraError) as error:
                make(focal)
            short(str(error.value))
    assert pluecker.Camera.pinhole(1e150, 1e150, 0.0, 0.0).fx == 1e150  # det K = 1e300 fits


def test_an_image_whose_pose_is_not_finite_is_left_out_by_image_id():
    """A NaN pose aborted the run with ``t: non-finite value (NaN or inf) in row 0``."""
    rec = model()
    image_id = sorted(rec.images)[2]
    image = rec.images[image_id]
    rec.frames[image.frame_id].rig_from_world = pycolmap.Rigid3d(pycolmap.Rotation3d(np.array([0, 0, 0, 1.0])),
                                                                 np.array([np.nan, 0.0, 0.0]))
    run = colmap.retriangulate(rec)
    assert run.skipped == [f"image_id {image_id}: its pose cam_from_world is not finite; its "
                           f"{image.num_points3D} observations not used"]
    assert_rest_solved(rec, run, {image_id})


def test_a_nan_keypoint_is_said_to_be_not_finite():
    """A NaN keypoint was left out as "outside the invertible region of the camera's distortion"."""
    rec = model()
    image = rec.images[sorted(rec.images)[2]]
    k = next(i for i, p in enumerate(image.points2D) if p.has_point3D())
    point_id = image.points2D[k].point3D_id
    image.points2D[k].xy = np.array([np.nan, 1.0])
    run = colmap.retriangulate(rec)
    assert run.skipped == [f"image_id {image.image_id}, point2D_idx {k} (point3D_id {point_id}): pixel (nan, 1) "
                           "is not finite; not used"]


def test_when_no_camera_can_be_used_one_reason_names_every_camera_id(tmp_path, capsys):
    """14 unusable cameras gave one line repeating the same explanation 14 times (5,000 characters)."""
    rec = model(cameras=14, frames=2)
    for camera_id in rec.cameras:
        rec.cameras[camera_id] = pycolmap.Camera(camera_id=camera_id, model="SIMPLE_PINHOLE", width=1024,
                                                 height=768, params=[0.0, 512.0, 384.0])
    with pytest.raises(colmap.ModelError) as error:
        colmap.retriangulate(rec)
    message = str(error.value)
    ids = ", ".join(map(str, sorted(rec.cameras)))
    assert message.count("focal lengths must be non-zero") == 1
    assert f"camera_id {ids} (SIMPLE_PINHOLE): " in message
    short(message)
    (tmp_path / "in").mkdir()
    rec.write(str(tmp_path / "in"))
    assert main(["triangulate", "--colmap", str(tmp_path / "in"), "--out", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.count("focal lengths") == 1 and len(err) < 400, err
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize("sigma, flow", [(1e300, "overflows"), (1e-200, "underflows"), (1e-155, "underflows")])
def test_a_sigma_whose_square_does_not_fit_names_sigma_px(tmp_path, capsys, sigma, flow):
    """``--sigma 1e300`` exited with an OverflowError traceback; ``--sigma 1e-200`` exited 0 with every
    point ``degenerate``. σ² I must be a normal double (its inverse finite)."""
    rec = model(points=10)
    for call in (lambda: colmap.retriangulate(rec, sigma_px=sigma), lambda: colmap.observation_table(rec, sigma)):
        with pytest.raises(pluecker.InvalidOptionError, match=rf"^sigma_px: σ = {re.escape(f'{sigma:g}')} px: the "
                                                             rf"covariance σ² I {flow} double precision$"):
            call()
    (tmp_path / "in").mkdir()
    rec.write(str(tmp_path / "in"))
    assert main(["triangulate", "--colmap", str(tmp_path / "in"), "--out", str(tmp_path / "out"),
                 "--sigma", repr(sigma)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "sigma_px" in err and "Traceback" not in err
    assert not (tmp_path / "out").exists()
    # The extremes that fit still run: σ = 1e-150 (σ² = 1e-300) and 1e150.
    for fits in (1e-150, 1e150):
        assert len(colmap.retriangulate(rec, sigma_px=fits).point3D_ids) == 10


def test_localize_in_model_names_a_negative_id_and_refuses_a_bool_camera():
    """A negative point3D_id leaked pycolmap's TypeError, ``camera=True`` an AttributeError."""
    rec = model()
    image = next(iter(rec.images.values()))
    keypoints = [p for p in image.points2D if p.has_point3D()]
    xy, ids = np.array([p.xy for p in keypoints]), np.array([p.point3D_id for p in keypoints])
    bad = ids.copy()
    bad[3] = -7
    with pytest.raises(colmap.MatchError, match=r"^point3D_ids: point3D_id -7 \(match 3\) is not a point of the model"):
        colmap.localize_in_model(rec, image.camera_id, xy, bad)
    from pluecker.colmap import ColmapModel
    with pytest.raises(colmap.MatchError, match=r"point3D_id -7 \(match 3\)"):
        colmap.localize_in_model(ColmapModel.from_reconstruction(rec), image.camera_id, xy, bad)
    for camera in (-1, 2**40):
        with pytest.raises(colmap.MatchError, match=rf"^camera: camera_id {camera} is not a camera of the model$"):
            colmap.localize_in_model(rec, camera, xy, ids)
    for camera in (True, "1", None, 1.0):
        with pytest.raises(pluecker.InvalidOptionError, match=r"^camera: expected a camera_id"):
            colmap.localize_in_model(rec, camera, xy, ids)
        with pytest.raises(TypeError, match=r"^camera: expected a pluecker.Camera or a pycolmap.Camera"):
            colmap.localize(camera, xy, np.zeros((len(xy), 3)))
    assert colmap.localize_in_model(rec, image.camera_id, xy, ids)[1].status == "success"


# --- reading a model folder ---------------------------------------------------------------------------


def test_a_folder_without_a_model_says_what_is_missing(tmp_path, capsys):
    """pycolmap said ``rigs, cameras, frames, images, points3D files do not exist`` (rigs and frames are
    optional)."""
    (tmp_path / "empty").mkdir()
    rec = model(points=10)
    (tmp_path / "partial").mkdir()
    rec.write(str(tmp_path / "partial"))
    (tmp_path / "partial" / "points3D.bin").unlink()
    (tmp_path / "q.parquet").touch()
    (tmp_path / "m.parquet").touch()
    for argv, words in (
            (["triangulate", "--colmap", tmp_path / "empty", "--out", tmp_path / "o"],
             "empty: not a COLMAP model: no cameras, images and points3D files (.bin or .txt) in the folder"),
            (["localize", tmp_path / "q.parquet", tmp_path / "m.parquet", "--colmap", tmp_path / "partial", "--out",
              tmp_path / "o"], "partial: not a complete COLMAP model: points3D.bin missing")):
        assert main([str(a) for a in argv]) == 2
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and words in err and "do not exist" not in err, err
        assert not (tmp_path / "o").exists()
    with pytest.raises(colmap.ModelError, match=r"not a COLMAP model: no cameras, images and points3D files"):
        colmap.read(tmp_path / "empty")
    with pytest.raises(colmap.ModelError, match=r"not a complete COLMAP model: points3D.bin missing .*rigs and "
                                                r"frames are optional"):
        colmap.read(tmp_path / "partial")
    # Without rigs and frames (a model of COLMAP before 3.12) it reads.
    (tmp_path / "old").mkdir()
    rec.write(str(tmp_path / "old"))
    for name in ("rigs.bin", "frames.bin"):
        (tmp_path / "old" / name).unlink()
    assert colmap.read(tmp_path / "old").num_points3D() == 10


@pytest.mark.parametrize("name", ["rigs", "cameras", "frames", "images", "points3D"])
def test_a_truncated_model_file_is_named(tmp_path, name):
    """A truncated points3D.bin gave ``std::bad_alloc``; a truncated cameras.bin could make pycolmap loop
    without end or read the missing bytes as zeros. Each cut is named before pycolmap reads the model."""
    rec = model(cameras=2, points=30)
    rec.write(str(tmp_path))
    path = tmp_path / f"{name}.bin"
    data = path.read_bytes()
    rng = np.random.default_rng(len(name))
    for cut in sorted({*rng.integers(0, len(data), 8).tolist(), 3, len(data) - 1}):
        path.write_bytes(data[:cut])
        with pytest.raises(colmap.ModelError, match=rf"^{re.escape(str(path))}: truncated: the file \({cut} bytes\) "
                                                    r"ends inside (its record count|record \d+ of \d+)$"):
            colmap.read(tmp_path)
    path.write_bytes(data + b"\0")
    with pytest.raises(colmap.ModelError, match=r"1 bytes after its \d+ records"):
        colmap.read(tmp_path)
    path.write_bytes(data)
    assert colmap.read(tmp_path).num_points3D() == 30


@pytest.mark.parametrize("name", ["rigs", "cameras", "frames", "images", "points3D"])
def test_a_truncated_text_model_file_is_named(tmp_path, name):
    """A text model cut short read as a smaller model (points3D.txt cut inside its last line gave 30
    points, the last one's track short) or failed in pycolmap's words without the file. Cut anywhere
    (inside the header, inside a line, or after a whole record), each file is named; a file written
    by hand (no stated count, no final line end) still reads."""
    rec = model(cameras=2, points=30)
    rec.write_text(str(tmp_path))
    path = tmp_path / f"{name}.txt"
    data = path.read_bytes()
    lines = data.split(b"\n")
    header = sum(1 for line in lines if line.startswith(b"#"))
    per_record = 2 if name == "images" else 1
    n = (len(lines) - 1 - header) // per_record
    rng = np.random.default_rng(len(name))
    inside = sorted({*rng.integers(1, len(data) - 1, 8).tolist(), len(data) - 2, 3})
    for cut in inside:
        path.write_bytes(data[:cut])
        if data[cut - 1:cut] == b"\n":  # a cut after a whole line is the other case below
            continue
        with pytest.raises(colmap.ModelError, match=rf"^{re.escape(str(path))}: truncated: the file \({cut} bytes\) "
                                                    r"ends inside (its header|record \d+ of \d+ \(COLMAP ends every "
                                                    r"line\))$"):
            colmap.read(tmp_path)
    kept = max(n - 1, 0)
    path.write_bytes(b"\n".join(lines[:header + kept * per_record]) + b"\n")
    with pytest.raises(colmap.ModelError, match=rf"^{re.escape(str(path))}: truncated: the file \(\d+ bytes\) ends "
                                                rf"after record {kept} of the {n} its header states$"):
        colmap.read(tmp_path)
    # Without the stated count and the final line end (as a person may write it), pycolmap decides.
    body = [line for line in lines if not line.startswith(b"#")]
    path.write_bytes(b"\n".join(body).rstrip(b"\n"))
    assert colmap.read(tmp_path).num_points3D() == 30
    path.write_bytes(data)
    assert colmap.read(tmp_path).num_points3D() == 30


def test_the_command_line_names_a_truncated_file(tmp_path, capsys):
    rec = model(points=30)
    (tmp_path / "in").mkdir()
    rec.write(str(tmp_path / "in"))
    points = tmp_path / "in" / "points3D.bin"
    points.write_bytes(points.read_bytes()[:100])
    assert main(["triangulate", "--colmap", str(tmp_path / "in"), "--out", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err
    assert err == f"pluecker triangulate: error: --colmap {points}: truncated: the file (100 bytes) ends inside " \
                  "record 1 of 30\n"


def test_an_id_listed_twice_in_a_model_file_is_named(tmp_path):
    """pycolmap said ``[reconstruction.cc:424] Check failed: cameras_.emplace(camera_id, ...)``."""
    rec = model(cameras=2, points=10)
    rec.write(str(tmp_path))
    path = tmp_path / "cameras.bin"
    data = bytearray(path.read_bytes())
    first = int.from_bytes(data[8:12], "little")
    record = 4 + 4 + 8 + 8 + 8 * 8  # camera_id, model id, width, height, the 8 OPENCV parameters
    data[8 + record:8 + record + 4] = data[8:12]
    path.write_bytes(bytes(data))
    with pytest.raises(colmap.ModelError, match=rf"^{re.escape(str(path))}: record 2 of 2: its id {first} is listed "
                                                r"twice$"):
        colmap.read(tmp_path)
