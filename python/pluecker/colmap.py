"""COLMAP and pluecker conventions side by side, in one place.

pycolmap is an optional extra (``pip install pluecker[colmap]``); the functions that take or return
pycolmap objects import it when called and say how to install it when it is missing.

- **Poses.** COLMAP's ``cam_from_world`` (a ``pycolmap.Rigid3d``) maps world points to the camera
  frame, ``x_cam = R X_world + t``: exactly pluecker's ``(R, t)``. No inversion is involved.
- **Quaternions.** pycolmap's ``Rotation3d.quat`` is ``(x, y, z, w)``. COLMAP's text files
  (``images.txt``: ``QW QX QY QZ``) and pluecker's dual quaternions are ``(w, x, y, z)``.
- **Cameras.** ``pycolmap.Camera(model, width, height, params)`` is ``pluecker.Camera(model,
  params)``: the same model names and parameter order. The image size is not part of the model.
- **Rigs.** A COLMAP rig's ``sensor_from_rig`` is pluecker's (``x_sensor = R x_rig + t``); its reference
  camera is at the identity. :func:`rig` gives the ``pluecker.Rig`` of a reconstruction's rig.
- **Known cameras.** Triangulation takes each image's ``View(camera, R, t)`` (its camera at its pose)
  with the observed, distorted pixels: the cost is then the reprojection error through the exact model;
  ``view.P`` is ``K [R | t]`` of the camera's pinhole part. Quadrics take pixels undistorted first
  (``Camera.undistort``): an outline seen through a lens is not a conic.
"""

from __future__ import annotations

import copy
import re
import struct
from dataclasses import dataclass, field
from typing import Any, NamedTuple

import numpy as np

from . import _core, _ctrl_c
from ._arguments import check_sigma, number, shown
from ._cameras import Cameras
from ._paths import require_folder, staged
from ._sorting import stable_order


class ModelError(_core.PlueckerError):
    """A COLMAP model that cannot be read or re-triangulated as it stands: a folder without a model or
    with a broken file (:func:`read`, naming the file), no 3-D points, no camera or image that can be
    used, or an observation whose ``point3D_id`` names no point of the model. The message names COLMAP's
    ids."""


def _pycolmap() -> Any:
    try:
        import zlib  # noqa: F401  (loaded before pycolmap, whose own zlib otherwise aborts Python's; see __init__)

        import pycolmap
    except ImportError as exc:  # pragma: no cover - depends on the environment
        raise ImportError("pluecker.colmap needs pycolmap: pip install 'pluecker[colmap]'") from exc
    return pycolmap


def quaternion_wxyz(q_xyzw: Any) -> np.ndarray:
    """A quaternion in ``(w, x, y, z)`` order (COLMAP's files, pluecker) from pycolmap's ``(x, y, z, w)``."""
    q = np.asarray(q_xyzw, dtype=float)
    return np.r_[q[3], q[:3]]


def quaternion_xyzw(q_wxyz: Any) -> np.ndarray:
    """A quaternion in pycolmap's ``(x, y, z, w)`` order from ``(w, x, y, z)``."""
    q = np.asarray(q_wxyz, dtype=float)
    return np.r_[q[1:], q[0]]


def rotation_from_quaternion(q_wxyz: Any) -> np.ndarray:
    """The rotation matrix (3, 3) of a quaternion ``(w, x, y, z)`` (any non-zero norm), as COLMAP's
    ``images.txt`` writes it."""
    w, x, y, z = np.asarray(q_wxyz, dtype=float) / np.linalg.norm(q_wxyz)
    return np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
        [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
        [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
    ])


def pose_from_rigid(cam_from_world: Any) -> tuple[np.ndarray, np.ndarray]:
    """``(R, t)`` with ``x_cam = R X_world + t`` of a ``pycolmap.Rigid3d`` ``cam_from_world``."""
    return np.array(cam_from_world.rotation.matrix()), np.array(cam_from_world.translation)


def rigid_from_pose(R: Any, t: Any) -> Any:
    """The ``pycolmap.Rigid3d`` ``cam_from_world`` of the pose ``x_cam = R X_world + t``; ``R`` must be a
    rotation (checked as every pluecker pose argument is)."""
    pycolmap = _pycolmap()
    q = _core.pose_to_dual_quaternion(R, t)[:4]  # (w, x, y, z), checks R and t
    return pycolmap.Rigid3d(pycolmap.Rotation3d(quaternion_xyzw(q)), np.asarray(t, dtype=float))


def _rig_sensors(colmap_rig: Any) -> list[Any]:
    """A pycolmap rig's sensors in the order of :func:`rig`'s cameras: the reference sensor first, then
    the others by type and id."""
    others = sorted(colmap_rig.non_ref_sensors, key=lambda s: (int(s.type.value), s.id))
    return [colmap_rig.ref_sensor_id, *others]


def rig(reconstruction: Any, rig_id: int) -> _core.Rig:
    """The rig ``rig_id`` of a pycolmap reconstruction as a ``pluecker.Rig``: its reference camera first
    (at the identity, as COLMAP fixes it), then its other cameras by sensor id, each with its camera and
    ``sensor_from_rig``. ``ModelError`` naming ``rig_id`` (and the sensor) for a rig the reconstruction
    does not have, a sensor that is not a camera, a camera sensor whose ``camera_id`` has no camera, or a
    sensor without ``sensor_from_rig``."""
    pycolmap = _pycolmap()
    rig_id = int(rig_id)
    if rig_id not in reconstruction.rigs:
        known = ", ".join(map(str, sorted(reconstruction.rigs))) or "none"
        raise ModelError(f"rig_id {rig_id}: no such rig in the reconstruction (its rig_ids: {known})")
    colmap_rig = reconstruction.rig(rig_id)
    cameras, poses = [], []
    for sensor in _rig_sensors(colmap_rig):
        where = f"rig_id {rig_id}, sensor {sensor.type.name} id {sensor.id}"
        if sensor.type != pycolmap.SensorType.CAMERA:
            raise ModelError(f"{where}: not a camera (a pluecker.Rig holds cameras only)")
        if sensor.id not in reconstruction.cameras:
            raise ModelError(f"{where}: no camera with camera_id {sensor.id} in the reconstruction")
        if colmap_rig.is_ref_sensor(sensor):
            poses.append((np.eye(3), np.zeros(3)))
        elif not colmap_rig.has_sensor_from_rig(sensor):
            raise ModelError(f"{where}: no sensor_from_rig (the rig's calibration is missing)")
        else:
            poses.append(pose_from_rigid(colmap_rig.sensor_from_rig(sensor)))
        cameras.append(_core.Camera(reconstruction.cameras[sensor.id]))
    return _core.Rig(cameras, poses)


def colmap_camera(camera: _core.Camera, width: int, height: int) -> Any:
    """The ``pycolmap.Camera`` of a ``pluecker.Camera``, for an image of ``width`` x ``height`` pixels."""
    pycolmap = _pycolmap()
    return pycolmap.Camera(model=camera.model, width=width, height=height, params=list(camera.params))


#: The files of a COLMAP model, in the order COLMAP reads them; ``rigs`` and ``frames`` are optional
#: (a model written before COLMAP 3.12 has neither), each in binary (``.bin``) or text (``.txt``).
MODEL_FILES = ("rigs", "cameras", "frames", "images", "points3D")
REQUIRED_MODEL_FILES = ("cameras", "images", "points3D")


def model_format(folder: Any) -> str | None:
    """``"bin"`` or ``"txt"``: the format COLMAP reads the model in ``folder`` in (binary when its three
    required ``.bin`` files are there, as COLMAP decides), or ``None`` when neither is complete."""
    from pathlib import Path

    for ext in ("bin", "txt"):
        if all((Path(folder) / f"{name}.{ext}").is_file() for name in REQUIRED_MODEL_FILES):
            return ext
    return None


def read(path: Any) -> Any:
    """The COLMAP model (binary or text, rigs and frames optional) in the folder ``path``, as a
    ``pycolmap.Reconstruction``. ``FileNotFoundError`` / ``NotADirectoryError`` when ``path`` is not a
    folder; :class:`ModelError` saying what is missing (the model's files by name) or broken (the file,
    and where a binary one ends or goes wrong), never pycolmap's own words for it."""
    pycolmap = _pycolmap()
    folder = require_folder(path)
    ext = model_format(folder)
    if ext is None:
        present = sorted(p.name for p in folder.iterdir() if p.stem in MODEL_FILES and p.suffix in (".bin", ".txt"))
        if not present:
            raise ModelError(f"{path}: not a COLMAP model: no cameras, images and points3D files (.bin or .txt) "
                             "in the folder")
        missing = [f"{name}.{e}" for e in ("bin", "txt") for name in REQUIRED_MODEL_FILES
                   if any(p.endswith(f".{e}") for p in present) and not (folder / f"{name}.{e}").is_file()]
        raise ModelError(f"{path}: not a complete COLMAP model: {', '.join(missing)} missing (found "
                         f"{', '.join(present)}; a model needs cameras, images and points3D, rigs and frames are "
                         "optional)")
    # A binary model is checked first: pycolmap reads past the end of a truncated file, and then gives
    # std::bad_alloc, loops without end or reads the zeros as a model. A text model cut short may read
    # as a smaller model, or fail with pycolmap's words for the line it stopped at.
    problem = _binary_model_problem(folder) if ext == "bin" else _text_model_problem(folder)
    if problem is not None:
        raise ModelError(problem)
    try:
        return pycolmap.Reconstruction(str(folder))
    except Exception as exc:  # pycolmap raises its own types (RuntimeError, ValueError, MemoryError, ...)
        words = " ".join(str(exc).split()) or type(exc).__name__
        raise ModelError(f"{path}: cannot read the COLMAP {'binary' if ext == 'bin' else 'text'} model: "
                         f"{words[:300]}") from None


class _Truncated(Exception):
    """A binary model file ends inside a record."""


class _Bytes:
    """A little-endian reader over ``data`` that raises :class:`_Truncated` instead of reading past it."""

    def __init__(self, data: bytes) -> None:
        self.data, self.at = data, 0

    def skip(self, size: int) -> None:
        if size < 0 or self.at + size > len(self.data):
            raise _Truncated
        self.at += size

    def read(self, fmt: struct.Struct) -> tuple:
        if self.at + fmt.size > len(self.data):
            raise _Truncated
        values = fmt.unpack_from(self.data, self.at)
        self.at += fmt.size
        return values

    def name(self) -> None:
        end = self.data.find(b"\0", self.at)
        if end < 0:
            raise _Truncated
        self.at = end + 1


_U8, _U32, _U64 = struct.Struct("<B"), struct.Struct("<I"), struct.Struct("<Q")
_I32_U32, _U32_I32, _U32_U32 = struct.Struct("<iI"), struct.Struct("<Ii"), struct.Struct("<II")
#: COLMAP's sensor types (``SensorType``: invalid, camera, IMU).
_SENSOR_TYPES = (-1, 0, 1)


def _camera_parameter_counts() -> dict[int, int]:
    """COLMAP's camera model ids and their number of parameters."""
    pycolmap = _pycolmap()
    return {int(m): len(pycolmap.Camera.create_from_model_id(0, m, 1.0, 1, 1).params)
            for m in pycolmap.CameraModelId.__members__.values() if int(m) >= 0}


def _record(kind: str, f: _Bytes, counts: dict[int, int]) -> tuple[int, str | None]:
    """Reads one record of a binary model file of ``kind`` (COLMAP's ``Write*Binary``); returns its id
    and what is wrong with it beyond its length (an unknown camera model or sensor type), else ``None``."""
    if kind == "rigs":
        rig_id, sensors = f.read(_U32_U32)
        for k in range(sensors):
            sensor_type, _ = f.read(_I32_U32)
            if sensor_type not in _SENSOR_TYPES:
                return rig_id, f"an unknown sensor type {sensor_type}"
            if k > 0:  # a sensor other than the reference one: whether it has a pose, and the pose
                (has_pose,) = f.read(_U8)
                f.skip(7 * 8 if has_pose else 0)
        return rig_id, None
    if kind == "cameras":
        camera_id, model = f.read(_U32_I32)
        if model not in counts:
            return camera_id, f"an unknown camera model id {model}"
        f.skip(16 + 8 * counts[model])
        return camera_id, None
    if kind == "frames":
        (frame_id,) = f.read(_U32)
        f.skip(4 + 7 * 8)
        f.skip(16 * f.read(_U32)[0])
        return frame_id, None
    if kind == "images":
        (image_id,) = f.read(_U32)
        f.skip(7 * 8 + 4)
        f.name()
        f.skip(24 * f.read(_U64)[0])
        return image_id, None
    (point_id,) = f.read(_U64)  # points3D
    f.skip(3 * 8 + 3 + 8)
    f.skip(8 * f.read(_U64)[0])
    return point_id, None


def _binary_model_problem(folder: Any) -> str | None:
    """What is wrong with the first binary model file of ``folder`` that does not read as COLMAP writes
    it (one line naming the file: where it ends inside a record, bytes after its last one, an unknown
    camera model or sensor type, an id listed twice), or ``None``. Checked before pycolmap reads the
    files, which reads past the end of a truncated one (and may then loop or allocate without end)."""
    counts = _camera_parameter_counts()
    for kind in MODEL_FILES:
        path = folder / f"{kind}.bin"
        if not path.is_file():
            continue
        f = _Bytes(path.read_bytes())
        n, k, seen = 0, 0, set()
        try:
            (n,) = f.read(_U64)
            for k in range(n):
                key, wrong = _record(kind, f, counts)
                if wrong is not None:
                    return f"{path}: record {k + 1} of {n} has {wrong}: not a COLMAP model file"
                if key in seen:
                    return f"{path}: record {k + 1} of {n}: its id {key} is listed twice"
                seen.add(key)
        except _Truncated:
            where = f"record {k + 1} of {n}" if f.at >= 8 else "its record count"
            return f"{path}: truncated: the file ({len(f.data)} bytes) ends inside {where}"
        if f.at != len(f.data):
            return f"{path}: {len(f.data) - f.at} bytes after its {n} records: not a COLMAP model file"
    return None


#: The header line in which COLMAP states a text model file's number of records.
_TEXT_COUNT = re.compile(rb"# Number of (?:rigs|cameras|frames|images|points): (\d+)")


def _text_model_problem(folder: Any) -> str | None:
    """What is wrong with the first text model file of ``folder`` that COLMAP wrote (its header states
    the number of records; COLMAP ends every line) but that is cut short: it ends inside its header or
    a line, or holds fewer records than its header says (one line naming the file); else ``None``. A file without
    that header line (written by hand) is left to pycolmap, as are records beyond the stated number."""
    for kind in MODEL_FILES:
        path = folder / f"{kind}.txt"
        if not path.is_file():
            continue
        data = path.read_bytes()
        lines = data.split(b"\n")
        header = 0
        while header < len(lines) and lines[header].startswith(b"#"):
            header += 1
        stated = [m for m in map(_TEXT_COUNT.match, lines[:header]) if m]
        if header == len(lines) and data and not data.endswith(b"\n"):
            return f"{path}: truncated: the file ({len(data)} bytes) ends inside its header"
        if not stated:
            continue
        n = int(stated[0].group(1))
        per_record = 2 if kind == "images" else 1  # an image's pose line, then its points line
        complete = (len(lines) - 1 - header) // per_record  # the part after the last "\n" is no line
        if not data.endswith(b"\n"):
            return (f"{path}: truncated: the file ({len(data)} bytes) ends inside record {complete + 1} of {n} "
                    "(COLMAP ends every line)")
        if complete < n:
            return (f"{path}: truncated: the file ({len(data)} bytes) ends after record {complete} of the {n} "
                    "its header states")
    return None


@dataclass(frozen=True)
class ColmapModel:
    """What localisation reads of a COLMAP model: its 3-D points by ``point3D_id`` (``point3D_ids`` (n,)
    sorted, ``xyz`` (n, 3)) and its cameras by ``camera_id`` (``cameras``: ``{camera_id: (model name,
    params)}``). Plain data, sent to every Dask worker once; :meth:`from_reconstruction` reads a
    ``pycolmap.Reconstruction``."""

    point3D_ids: np.ndarray
    xyz: np.ndarray
    cameras: dict
    #: ``{rig_id: (camera_ids, sensor_from_rig)}``: each rig's cameras in :func:`rig`'s order and their
    #: poses as ``(R, t)`` nested tuples, or ``{rig_id: message}`` for a rig :func:`rig` refuses.
    rigs: dict = field(default_factory=dict)

    def __post_init__(self) -> None:
        ids = np.asarray(self.point3D_ids, dtype=np.int64).reshape(-1)
        xyz = np.asarray(self.xyz, dtype=float).reshape(-1, 3) if len(ids) else np.zeros((0, 3))
        if xyz.shape != (len(ids), 3):
            raise _core.ShapeError(f"ColmapModel: xyz must have shape ({len(ids)}, 3), got {xyz.shape}")
        order = stable_order(ids)
        ids, xyz = ids[order], xyz[order]
        if np.any(ids[1:] == ids[:-1]):
            raise _core.ShapeError(f"ColmapModel: point3D_id {int(ids[1:][ids[1:] == ids[:-1]][0])} is listed twice")
        cameras = {int(k): (str(m), tuple(float(p) for p in params)) for k, (m, params) in dict(self.cameras).items()}
        object.__setattr__(self, "point3D_ids", ids)
        object.__setattr__(self, "xyz", xyz)
        object.__setattr__(self, "cameras", cameras)

    @classmethod
    def from_reconstruction(cls, reconstruction: Any) -> "ColmapModel":
        """The points and cameras of a ``pycolmap.Reconstruction``."""
        points = reconstruction.points3D
        ids = np.fromiter((int(i) for i in points), dtype=np.int64, count=len(points))
        xyz = np.array([points[int(i)].xyz for i in ids], dtype=float).reshape(-1, 3)
        cameras = {int(i): (c.model.name, tuple(c.params)) for i, c in reconstruction.cameras.items()}
        rigs: dict = {}
        for rig_id in getattr(reconstruction, "rigs", {}):
            try:
                held = rig(reconstruction, rig_id)
            except (ModelError, _core.PlueckerError) as exc:
                rigs[int(rig_id)] = str(exc)
                continue
            camera_ids = tuple(int(sensor.id) for sensor in _rig_sensors(reconstruction.rig(rig_id)))
            poses = tuple((tuple(map(tuple, p.rotation)), tuple(p.translation)) for p in held.sensor_from_rig)
            rigs[int(rig_id)] = (camera_ids, poses)
        return cls(ids, xyz, cameras, rigs)

    def rig(self, rig_id: int) -> tuple[_core.Rig, tuple[int, ...]]:
        """The rig ``rig_id`` and the ``camera_id`` of each of its cameras; ``ModelError`` naming the
        rig_id when the model has no such rig (or one :func:`rig` refused, with its reason)."""
        held = self.rigs.get(int(rig_id))
        if held is None:
            known = ", ".join(map(str, sorted(self.rigs))) or "none"
            raise ModelError(f"rig_id {rig_id}: no such rig in the model (its rig_ids: {known})")
        if isinstance(held, str):
            raise ModelError(held)
        camera_ids, poses = held
        cameras = [_core.Camera(self.cameras[i][0], list(self.cameras[i][1])) for i in camera_ids]
        return _core.Rig(cameras, [(np.array(R), np.array(t)) for R, t in poses]), camera_ids

    def lookup(self, ids: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The points (len(ids), 3) of ``point3D_ids`` ``ids`` (NaN for an id not in the model) and the
        mask of the known ones."""
        ids = np.asarray(ids, dtype=np.int64)
        rows = np.minimum(np.searchsorted(self.point3D_ids, ids), max(len(self.point3D_ids) - 1, 0))
        known = self.point3D_ids[rows] == ids if len(self.point3D_ids) else np.zeros(len(ids), dtype=bool)
        xyz = np.full((len(ids), 3), np.nan)
        xyz[known] = self.xyz[rows[known]]
        return xyz, known


def as_model(model: Any) -> ColmapModel | None:
    """``model`` as a :class:`ColmapModel` (a ``pycolmap.Reconstruction`` is read), or ``None``."""
    if model is None or isinstance(model, ColmapModel):
        return model
    return ColmapModel.from_reconstruction(model)


class Retriangulation:
    """What :func:`retriangulate` found: one row per 3-D point of the model and one per observation.

    Attributes: ``point3D_ids`` (n,), ``result`` (a ``pluecker.PointTriangulations``, row ``i`` the point
    ``point3D_ids[i]``), and the observations as ``observation_point`` (m,) (a row of
    ``point3D_ids``), ``observation_image`` (m,) and ``observation_point2D`` (m,) (COLMAP's image id and
    ``point2D_idx``); with an outlier threshold, ``result.inliers`` (m,) flags them. ``skipped`` lists,
    with COLMAP's ids, what was left out: the cameras that cannot be used (a model that is not handled,
    a zero focal length; one message per reason, naming every camera_id) and the images whose pose
    cannot be used (likewise), with their observations; a pixel that is not finite or lies outside the
    invertible region of its camera's distortion (one message each).
    """

    def __init__(self, point3D_ids: np.ndarray, result: Any, observation_point: np.ndarray,
                 observation_image: np.ndarray, observation_point2D: np.ndarray, skipped: list | None = None) -> None:
        self.skipped = list(skipped or [])
        self.point3D_ids = point3D_ids
        self.result = result
        self.observation_point = observation_point
        self.observation_image = observation_image
        self.observation_point2D = observation_point2D

    def __iter__(self):  # ``ids, result = retriangulate(...)``
        return iter((self.point3D_ids, self.result))


class _Observations(NamedTuple):
    """A model's observations as the triangulation takes them (:func:`_observations`)."""

    P: np.ndarray               # (v, 3, 4) pinhole cameras of the posed images whose camera is handled
    P_image_ids: np.ndarray     # (v,) their COLMAP image ids
    ids: np.ndarray             # (n,) sorted point3D ids
    track: np.ndarray           # (m,) row of ids per observation
    camera: np.ndarray          # (m,) row of P
    image_id: np.ndarray        # (m,) COLMAP image id
    point2D_idx: np.ndarray     # (m,)
    skipped: list               # messages naming the cameras and observations left out, with COLMAP's ids
    pixels: np.ndarray          # (m, 2) the observed (distorted) pixels
    views: list                 # (v,) the View (camera and pose) of each row of P


def _has_preimage(lens: _core.Camera, xy: np.ndarray) -> np.ndarray:
    """Which (finite) pixels have a preimage through ``lens`` (``lens.unproject`` succeeds). The pixels
    of an image go in one call; only when one of them is refused are they tried one by one."""
    try:
        lens.unproject(xy)
        return np.ones(len(xy), dtype=bool)
    except _core.PlueckerError:
        kept = np.ones(len(xy), dtype=bool)
        for k in range(len(xy)):
            try:
                lens.unproject(xy[k:k + 1])
            except _core.PlueckerError:
                kept[k] = False
        return kept


def _ids(name: str, ids: list[int]) -> str:
    """``camera_id 3`` or ``camera_id 3, 5, 8`` (the first 20, then how many more)."""
    shown = ", ".join(map(str, ids[:20])) + (f", … ({len(ids)} in all)" if len(ids) > 20 else "")
    return f"{name} {shown}"


def _grouped(name: str, problems: list[tuple[int, str, int]]) -> list[str]:
    """One message per reason of ``problems`` (id, reason, observations lost): the ids that share it,
    the reason once, and the observations not used. A reason may start with a label for the ids, such as
    ``(OPENCV): ``."""
    by_reason: dict[str, list[tuple[int, int]]] = {}
    for key, reason, count in problems:
        by_reason.setdefault(reason, []).append((key, count))
    return [f"{_ids(name, [k for k, _ in items])}{'' if reason.startswith(' (') else ': '}{reason}; "
            f"{'its' if len(items) == 1 else 'their'} {sum(c for _, c in items)} observations not used"
            for reason, items in by_reason.items()]


def _camera_problem(camera: Any) -> tuple[_core.Camera | None, str]:
    """The ``Camera`` of a model's camera, or ``None`` and why it cannot be used (its model and the
    error of ``Camera``: a model pluecker does not handle, a zero focal length, ...)."""
    try:
        return _core.Camera(camera.model.name, list(camera.params)), ""
    except _core.PlueckerError as exc:
        return None, f" ({camera.model.name}): {exc}"


def _image_problem(lens: _core.Camera, image: Any) -> tuple[_core.View | None, str]:
    """The view of a posed image (its camera at its pose ``cam_from_world``), or ``None`` and why it
    cannot be used (a pose that is not finite, a matrix ``K [R | t]`` that overflows)."""
    R, t = pose_from_rigid(image.cam_from_world())
    if not (np.all(np.isfinite(R)) and np.all(np.isfinite(t))):
        return None, "its pose cam_from_world is not finite"
    with np.errstate(over="ignore", invalid="ignore"):
        try:
            view = _core.View(lens, R, t)
        except _core.PlueckerError as exc:
            return None, f"its pose cam_from_world is not usable: {exc}"
    if not np.all(np.isfinite(view.P)):
        return None, f"K [R | t] overflows double precision (|t| = {number(np.linalg.norm(t))})"
    return view, ""


def _observations(reconstruction: Any, sigma_px: float) -> _Observations:
    """Every observation of a model's 3-D points with its image's camera (:func:`retriangulate`), sorted
    by point. A camera that cannot be used (a model that is not handled, a zero focal length), an image
    whose pose is not usable, and a pixel that is not finite or has no preimage through the camera's
    distortion are left out and named in ``skipped`` (cameras and images grouped by reason); a model
    without points or without a usable camera or image, or a dangling ``point3D_id``, is a
    :class:`ModelError`."""
    check_sigma(sigma_px)
    if reconstruction.num_points3D() == 0:
        raise ModelError("reconstruction: the model has no 3-D points to re-triangulate")
    ids = np.sort(np.fromiter(reconstruction.point3D_ids(), dtype=np.int64))
    posed = sorted((image for image in reconstruction.images.values() if image.has_pose),
                   key=lambda image: image.image_id)
    lenses, bad_cameras = {}, []
    for camera_id in sorted({image.camera_id for image in posed}):
        lens, reason = _camera_problem(reconstruction.cameras[camera_id])
        if lens is None:
            count = sum(image.num_points3D for image in posed if image.camera_id == camera_id)
            bad_cameras.append((camera_id, reason, count))
        else:
            lenses[camera_id] = lens
    skipped = _grouped("camera_id", bad_cameras)
    if posed and not lenses:
        raise ModelError("reconstruction: no camera of the model can be used: " + "; ".join(skipped))
    images, views, bad_images = [], [], []
    for image in posed:
        if image.camera_id not in lenses:
            continue
        view, reason = _image_problem(lenses[image.camera_id], image)
        if view is None:
            bad_images.append((image.image_id, reason, image.num_points3D))
        else:
            images.append(image)
            views.append(view)
    skipped += _grouped("image_id", bad_images)
    if bad_images and not images:
        raise ModelError("reconstruction: no image of the model can be used: " + "; ".join(skipped))
    image_ids = np.array([image.image_id for image in images], dtype=np.int64)
    P = np.array([view.P for view in views], dtype=float).reshape(-1, 3, 4)
    # The observations image by image (pycolmap hands them over per image, in increasing image id).
    keypoints = _keypoints(reconstruction)
    per_image = [keypoints[image.image_id] if keypoints else _observed(image) for image in images]
    counts = np.array([len(idx) for _, _, idx in per_image], dtype=np.int64)
    pixels = np.concatenate([xy for xy, _, _ in per_image]) if per_image else np.zeros((0, 2))
    point_ids = np.concatenate([p for _, p, _ in per_image]) if per_image else np.zeros(0, dtype=np.int64)
    point2D_idx = np.concatenate([i for _, _, i in per_image]) if per_image else np.zeros(0, dtype=np.int64)
    camera = np.repeat(np.arange(len(images), dtype=np.int64), counts)
    image_id = np.repeat(image_ids, counts)
    track = _point_rows(ids, point_ids, image_id, point2D_idx)
    finite = np.all(np.isfinite(pixels), axis=1)
    kept = finite.copy()
    for image, start, stop in zip(images, np.cumsum(counts) - counts, np.cumsum(counts)):
        rows = start + np.flatnonzero(finite[start:stop])
        if len(rows):
            kept[rows] = _has_preimage(lenses[image.camera_id], pixels[rows])
    skipped.extend(f"image_id {int(image_id[k])}, point2D_idx {int(point2D_idx[k])} (point3D_id {int(point_ids[k])}): "
                   f"pixel ({number(pixels[k, 0])}, {number(pixels[k, 1])}) "
                   + ("is not finite" if not finite[k] else "outside the invertible region of the camera's distortion")
                   + "; not used" for k in np.flatnonzero(~kept))
    if not kept.all():
        track, camera, image_id, point2D_idx, pixels = (a[kept] for a in (track, camera, image_id, point2D_idx, pixels))
    # Sorted by (track, image id, pixel), as pluecker.distributed sorts them, so that both give the same
    # bits: the observations are in increasing image id, so a stable sort by track leaves only the
    # pixels of one track seen twice in one image to order.
    order = stable_order(track)
    key = track[order] * (len(images) + 1) + camera[order]
    for start, stop in _runs(key):
        run = order[start:stop]
        order[start:stop] = run[np.lexsort((pixels[run, 1], pixels[run, 0]))]
    return _Observations(P, image_ids, ids, track[order], camera[order], image_id[order], point2D_idx[order],
                         skipped, pixels[order], views)


def _runs(key: np.ndarray) -> list[tuple[int, int]]:
    """The ``[start, stop)`` ranges of equal adjacent values of ``key`` longer than one."""
    if len(key) < 2:
        return []
    change = np.flatnonzero(key[1:] != key[:-1]) + 1
    starts = np.r_[0, change]
    stops = np.r_[change, len(key)]
    long = stops - starts > 1
    return list(zip(starts[long].tolist(), stops[long].tolist()))


def _observed(image: Any) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """An image's observations of 3-D points through pycolmap's objects: pixels (k, 2), point3D ids (k,)
    and point2D indices (k,)."""
    observed = image.get_observation_points2D()
    xy = np.array([p.xy for p in observed], dtype=float).reshape(-1, 2)
    point_ids = np.array([p.point3D_id for p in observed], dtype=np.int64)
    return xy, point_ids, np.asarray(image.get_observation_point2D_idxs(), dtype=np.int64)


# COLMAP's `kInvalidPoint3DId` in images.bin: a keypoint that observes no 3-D point.
_NO_POINT3D = np.iinfo(np.uint64).max


def _keypoints(reconstruction: Any) -> dict[int, tuple[np.ndarray, np.ndarray, np.ndarray]] | None:
    """Every image's observations as :func:`_observed` gives them, read in one pass from the model
    written by pycolmap to a temporary binary ``images.bin`` (per image: id, pose, camera id, name, the
    keypoint count and ``(x, y, point3D_id)`` records; COLMAP's ``WriteImagesBinary``): per-keypoint
    Python objects are most of the time otherwise. ``None`` (the caller takes the objects' path) when
    the file does not read back as exactly the model's images and keypoints."""
    import tempfile

    try:
        with tempfile.TemporaryDirectory() as folder, _ctrl_c.removed_on_forced_exit(folder):
            reconstruction.write_binary(folder)
            with open(f"{folder}/images.bin", "rb") as f:
                data = f.read()
        out: dict[int, tuple[np.ndarray, np.ndarray, np.ndarray]] = {}
        count = int(np.frombuffer(data, "<u8", 1, 0)[0])
        at = 8
        record = np.dtype([("x", "<f8"), ("y", "<f8"), ("id", "<u8")])
        for _ in range(count):
            image_id = int(np.frombuffer(data, "<u4", 1, at)[0])
            at += 4 + 7 * 8 + 4
            end = data.index(b"\0", at)
            at = end + 1
            n = int(np.frombuffer(data, "<u8", 1, at)[0])
            at += 8
            points = np.frombuffer(data, record, n, at)
            at += n * record.itemsize
            idx = np.flatnonzero(points["id"] != _NO_POINT3D)
            xy = np.stack([points["x"][idx], points["y"][idx]], axis=1)
            out[image_id] = (xy, points["id"][idx].astype(np.int64), idx.astype(np.int64))
        images = reconstruction.images
        if at != len(data) or sorted(out) != sorted(images) or any(
                len(out[i][2]) != images[i].num_points3D for i in out):
            return None
        return out
    except (OSError, ValueError, IndexError, TypeError):  # pragma: no cover - a format this reader does not know
        return None


def _point_rows(ids: np.ndarray, point_ids: np.ndarray, image_id: np.ndarray, point2D_idx: np.ndarray) -> np.ndarray:
    """The rows of ``point_ids`` in the model's sorted point ids ``ids``; :class:`ModelError` naming the
    first observation (``image_id``, ``point2D_idx``) whose ``point3D_id`` is not among them (a dangling
    id, as a model edited in memory can hold)."""
    if len(ids) and 0 <= ids[0] and ids[-1] < 4 * len(ids) + 4096:
        # COLMAP numbers its points densely: a lookup table is several times faster than a search.
        table = np.full(int(ids[-1]) + 2, -1, dtype=np.int64)  # the last entry: every id out of range
        table[ids] = np.arange(len(ids))
        found = table[np.where((point_ids >= 0) & (point_ids <= ids[-1]), point_ids, len(table) - 1)]
        dangling = np.flatnonzero(found < 0)
        rows = np.maximum(found, 0)
    else:
        rows = np.minimum(np.searchsorted(ids, point_ids), max(len(ids) - 1, 0))
        dangling = np.flatnonzero(ids[rows] != point_ids) if len(ids) else np.arange(len(point_ids))
    if len(dangling):
        k = dangling[0]
        same = int(np.sum(image_id[dangling] == image_id[k]))
        raise ModelError(f"reconstruction: image_id {int(image_id[k])}, point2D_idx {int(point2D_idx[k])} observes "
                         f"point3D_id {int(point_ids[k])}, which is not in the model ({same} such "
                         f"observation{'s' if same > 1 else ''} in this image)")
    return rows


def observation_table(reconstruction: Any, sigma_px: float = 1.0, *, skipped: list | None = None) -> tuple[Any, Any]:
    """A model's observations as the table of :mod:`pluecker.distributed` (``track`` = point3D id,
    ``image`` = image id, the observed pixel ``x``, ``y`` and ``cov_*`` = ``sigma_px²`` I, ``point2D_idx``)
    and its :class:`pluecker.distributed.Cameras` (each posed image's ``K [R | t]`` and ``View``):
    the same solve as :func:`retriangulate`. What is left out (cameras, images, pixels) is named as in
    ``Retriangulation.skipped``, appended to the list ``skipped`` when one is given."""
    import pyarrow as pa

    o = _observations(reconstruction, sigma_px)
    if skipped is not None:
        skipped.extend(o.skipped)
    table = pa.table({"track": o.ids[o.track], "image": o.image_id.astype(np.int64),
                      "x": o.pixels[:, 0], "y": o.pixels[:, 1], "cov_xx": np.full(len(o.track), float(sigma_px)**2),
                      "cov_xy": np.zeros(len(o.track)), "cov_yy": np.full(len(o.track), float(sigma_px)**2),
                      "point2D_idx": o.point2D_idx.astype(np.int64)})
    return Cameras(o.P_image_ids, o.P, tuple(o.views)), table


class TableResult:
    """The columns of :func:`retriangulate`'s result read from the tables of a distributed job, in the
    order of ``point3D_ids`` and of the observations (for :func:`write`)."""

    def __init__(self, points: Any, inliers: np.ndarray) -> None:
        self.point = np.c_[points.column("X").to_numpy(), points.column("Y").to_numpy(), points.column("Z").to_numpy()]
        self.status = np.asarray(points.column("status").to_pylist(), dtype=str)
        self.certified = points.column("certified").to_numpy(zero_copy_only=False).astype(bool)
        self.cost = points.column("cost").to_numpy()
        self.lower_bound = points.column("lower_bound").to_numpy()
        self.covariance = np.asarray(points.column("covariance").combine_chunks().flatten().to_numpy()).reshape(-1, 3, 3)
        self.inliers = inliers


def retriangulation_of_job(points: Any, observations: Any, skipped: Any = ()) -> Retriangulation:
    """A :class:`Retriangulation` from the ``points`` and ``observations`` tables of
    :func:`pluecker.distributed.triangulate` run on :func:`observation_table` (for :func:`write`), with
    the ``skipped`` messages of :func:`observation_table`."""
    ids = points.column("track").to_numpy()
    obs_track = observations.column("track").to_numpy()
    inliers = observations.column("inlier").to_numpy(zero_copy_only=False).astype(bool)
    return Retriangulation(ids, TableResult(points, inliers), np.searchsorted(ids, obs_track),
                           observations.column("image").to_numpy(), observations.column("point2D_idx").to_numpy(),
                           list(skipped))


def retriangulate(reconstruction: Any, sigma_px: float = 1.0,
                  options: Any = None, *, outlier_threshold_px: float | None = None,
                  progress: Any = None) -> Retriangulation:
    """Re-triangulates every 3-D point of a ``pycolmap.Reconstruction`` from its track, with the
    cameras (models, distortion, rigs) and poses held fixed. Returns a :class:`Retriangulation`, which
    also unpacks as ``(point3D_ids, PointTriangulations)``, row ``i`` the point ``point3D_ids[i]``.

    The cost is the reprojection error in each image's own (distorted) pixels through its camera model,
    exactly, in squared standard deviations (``sigma_px`` pixels, isotropic; pixels² for
    ``sigma_px = 1``), as COLMAP's bundle adjustment counts it. The first stages run on the pixels
    undistorted into each camera's pinhole part; the point is then refined on the exact cost, and a
    certificate (``lens_convexity_test`` through a lens) proves its global minimum over every point whose
    projections lie inside the disc where each lens is proved one-to-one (the fold radius for radially
    symmetric lenses). Where no proof is found (FOV, a rational FULL_OPENCV, the fisheyes' tangential and
    thin-prism terms, low parallax) the point is ``gap_not_closed``:
    uncertified, never certified on an approximation.

    ``outlier_threshold_px`` rejects observations farther than that many pixels from the consensus of
    their track (``TriangulationOptions.outlier_threshold``; ``result.inliers`` flags the observations).
    ``options`` (its ``method`` and ``certify`` too) and ``progress`` are those of
    :func:`pluecker.triangulate_points` (rows form).
    Use :func:`update_points` or :func:`write` to put the points back.
    """
    o = _observations(reconstruction, sigma_px)
    if outlier_threshold_px is not None:
        fields = options.to_dict() if options is not None else {}
        options = _core.TriangulationOptions(**{**fields, "outlier_threshold": outlier_threshold_px / sigma_px})
    covariances = np.broadcast_to(float(sigma_px)**2 * np.eye(2), (len(o.track), 2, 2))
    result = _core.triangulate_points(o.views, o.pixels, covariances=covariances, track=o.track, image=o.camera, options=options, progress=progress, n_tracks=len(o.ids))
    return Retriangulation(o.ids, result, o.track, o.image_id, o.point2D_idx, o.skipped)


def update_points(reconstruction: Any, point3D_ids: Any, result: Any) -> int:
    """Writes the successfully re-triangulated points of :func:`retriangulate` into ``reconstruction``
    (their ``xyz``); the others are left as they were. Returns how many were written."""
    written = 0
    for point_id, X, status in zip(point3D_ids, result.point, result.status):
        if status == "success":
            reconstruction.points3D[int(point_id)].xyz = X
            written += 1
    return written


def removed_observations(run: Retriangulation) -> np.ndarray:
    """Mask (m,) of the observations that :func:`remove_outliers` deletes: rejected by the outlier
    threshold at a point that was re-triangulated. Those of unsolved points are kept (their flag in
    ``result.inliers`` says nothing: no point was found to judge them against)."""
    if run.result.inliers is None:
        return np.zeros(len(run.observation_point), dtype=bool)
    solved = np.asarray(run.result.status) == "success"
    return ~np.asarray(run.result.inliers, dtype=bool) & solved[run.observation_point]


def remove_outliers(reconstruction: Any, run: Retriangulation) -> int:
    """Deletes from ``reconstruction`` the observations that :func:`retriangulate` rejected as outliers
    (``run.result.inliers`` false) of the points it solved; COLMAP deletes a point left with fewer than
    two observations. Returns how many observations were deleted."""
    deleted = 0
    for k in np.flatnonzero(removed_observations(run)):
        point_id = int(run.point3D_ids[run.observation_point[k]])
        image_id, point2D_idx = int(run.observation_image[k]), int(run.observation_point2D[k])
        # Only if the observation is still there: a second write of the same run deletes nothing twice.
        if (reconstruction.exists_point3D(point_id)
                and reconstruction.images[image_id].points2D[point2D_idx].point3D_id == point_id):
            reconstruction.delete_observation(int(run.observation_image[k]), int(run.observation_point2D[k]))
            deleted += 1
    return deleted


#: PLY colours per point state, in the order of the legend in the file's header.
PLY_COLOURS = {
    "certified": (40, 180, 60),     # green: re-triangulated, global optimum certified
    "solved": (240, 200, 30),       # yellow: re-triangulated, not certified
    "unsolved": (220, 40, 40),      # red: not re-triangulated, the model's position kept
}

#: What ``certified`` proves, as stated in ``points3D_triangulation.npz``.
CERTIFIED_MEANING = (
    "certified: lower_bound is a proved lower bound on the global minimum of the point's cost (eq. 19: the "
    "squared reprojection residuals whitened by sigma_px, summed over the observations used), within the "
    "relative gap certify.max_relative_gap of cost; the residuals are those of the observed (distorted) pixels "
    "through the exact camera model, and the bound holds over every point whose projection in each image "
    "lies inside the disc where its camera's distortion is proved one-to-one (the fold radius for radially "
    "symmetric lenses); points of cameras the certificate does not cover are left uncertified")


def write_ply(path: Any, X: np.ndarray, states: np.ndarray) -> None:
    """An ASCII PLY of every point (n, 3), coloured by its state (``"certified"``, ``"solved"`` or
    ``"unsolved"``; :data:`PLY_COLOURS`), with the legend as comments in the header. Points with a
    non-finite coordinate (none in a COLMAP model) are left out."""
    keep = np.all(np.isfinite(X), axis=1)
    colours = np.array([PLY_COLOURS[state] for state in states], dtype=int).reshape(-1, 3)
    legend = [f"comment pluecker: {state} = rgb {r} {g} {b}" for state, (r, g, b) in PLY_COLOURS.items()]
    header = ["ply", "format ascii 1.0", *legend, f"element vertex {int(keep.sum())}", "property double x",
              "property double y", "property double z", "property uchar red", "property uchar green",
              "property uchar blue", "end_header"]
    rows = (f"{x:.9g} {y:.9g} {z:.9g} {r} {g} {b}" for (x, y, z), (r, g, b) in zip(X[keep], colours[keep]))
    with open(path, "w", encoding="utf-8") as f:
        f.write("\n".join([*header, *rows]) + "\n")


def stale_model_files(out: Any, text: bool) -> list[Any]:
    """The model files of the other format than the one :func:`write` writes (``.bin`` when ``text``,
    else ``.txt``) that ``out`` holds, sorted: a COLMAP reader would take them for the model (it reads
    the binary files when there are three, else the text ones), so :func:`write` removes them."""
    from pathlib import Path

    other = "bin" if text else "txt"
    return sorted(p for name in MODEL_FILES for p in [Path(out) / f"{name}.{other}"] if p.is_file())


def write(reconstruction: Any, run: Retriangulation, out: Any, *, text: bool = False) -> list[Any]:
    """Writes a re-triangulated model into the directory ``out``: the points back into
    ``reconstruction`` (:func:`update_points`, :func:`remove_outliers`, then every point's ERROR
    recomputed as COLMAP defines it, the mean reprojection error in pixels), the COLMAP model (binary,
    or text with ``text``), ``points3D.ply`` (every point of the model, coloured by state:
    :data:`PLY_COLOURS`) and ``points3D_triangulation.npz``: per point ``point3D_id``, ``X``,
    ``covariance`` (3, 3), ``cost``, ``lower_bound``, ``certified``, ``status``; per observation
    ``observation_point3D_id``, ``observation_image_id``, ``observation_point2D_idx``,
    ``observation_inlier`` and ``observation_state`` (``"inlier"``, ``"outlier"`` (removed from the
    model), or ``"unknown"`` for the observations of a point that was not re-triangulated); and
    ``certified_meaning``, what ``certified`` proves. Returns the paths of the files written, sorted.

    The files are written into a temporary folder and then moved into ``out`` (made when missing): an
    interrupted or failed write leaves ``out`` as it was. Other files of ``out`` are kept, except the
    model files of the other format (:func:`stale_model_files`), which a COLMAP reader would otherwise
    take for this model."""
    result = run.result
    update_points(reconstruction, run.point3D_ids, result)
    remove_outliers(reconstruction, run)
    reconstruction.update_point_3d_errors()
    certified = np.asarray(result.certified, dtype=bool)
    solved = np.asarray(result.status) == "success"
    state = dict(zip(run.point3D_ids.tolist(), np.where(certified, "certified", np.where(solved, "solved",
                                                                                             "unsolved"))))
    ply_ids = sorted(reconstruction.point3D_ids())  # points that lost their track to outliers are gone
    ply_X = np.array([reconstruction.points3D[i].xyz for i in ply_ids], dtype=float).reshape(-1, 3)
    inliers = result.inliers if result.inliers is not None else np.ones(len(run.observation_point), dtype=bool)
    observation_state = np.where(~solved[run.observation_point], "unknown", np.where(inliers, "inlier", "outlier"))
    with staged(out) as stage:
        folder = stage.path
        (reconstruction.write_text if text else reconstruction.write)(str(folder))
        write_ply(folder / "points3D.ply", ply_X, np.array([state.get(i, "unsolved") for i in ply_ids]))
        # Not savez_compressed: Python's zlib aborts the process when pycolmap was imported before it.
        np.savez(
            folder / "points3D_triangulation.npz", point3D_id=run.point3D_ids, X=result.point,
            covariance=result.covariance, cost=result.cost, lower_bound=result.lower_bound, certified=certified,
            status=np.asarray(result.status, dtype=str), observation_point3D_id=run.point3D_ids[run.observation_point],
            observation_image_id=run.observation_image, observation_point2D_idx=run.observation_point2D,
            observation_inlier=inliers, observation_state=observation_state,
            certified_meaning=np.array(CERTIFIED_MEANING))
    for stale in stale_model_files(out, text):
        stale.unlink()
    return stage.written


def robust_options(options: Any = None, ransac: Any = True) -> Any:
    """A copy of ``options`` (a :class:`pluecker.PoseOptions`, default ``PoseOptions()``) with its
    ``ransac`` set from ``ransac``: ``True`` keeps ``options.ransac`` or takes the
    :class:`pluecker.RansacOptions` defaults, a ``RansacOptions`` is used as it is, ``False`` or ``None``
    turn robust estimation off."""
    opts = copy.copy(options) if options is not None else _core.PoseOptions()
    if ransac is True:
        opts.ransac = opts.ransac if opts.ransac is not None else _core.RansacOptions()
    elif ransac is False or ransac is None:
        opts.ransac = None
    else:
        opts.ransac = ransac
    return opts


def localize(camera: Any, points2D: Any = None, points3D: Any = None, lines2D: Any = None, lines3D: Any = None,
             *, ransac: Any = True, options: Any = None, point_covariances: Any = None,
             line_covariances: Any = None, point_cameras: Any = None, line_cameras: Any = None) -> tuple[Any, Any]:
    """Localises one image, or one frame of a rig, from its 2D-3D matches (points and/or segments,
    distorted pixels): ``(cam_from_world, PoseResult)``, the first a ``pycolmap.Rigid3d`` (``None``
    unless the status is ``success``). ``camera``: a ``pycolmap.Camera`` or ``pluecker.Camera``; or a
    :class:`pluecker.Rig` (from a model: :func:`rig`) with ``point_cameras`` / ``line_cameras``, the
    index of the rig's camera that saw each match, and then the pose is the frame's ``rig_from_world``.
    Robust by default: ``ransac`` sets ``options.ransac`` as :func:`robust_options` says (``True``:
    ``options.ransac`` or the :class:`pluecker.RansacOptions` defaults); the rest as
    :func:`pluecker.estimate_pose`."""
    result = _core.estimate_pose(camera, points2D, points3D, lines2D, lines3D, options=robust_options(options, ransac),
                                 point_covariances=point_covariances, line_covariances=line_covariances,
                                 point_cameras=point_cameras, line_cameras=line_cameras)
    rigid = rigid_from_pose(result.pose.rotation, result.pose.translation) if result.status == "success" else None
    return rigid, result


class MatchError(_core.PlueckerError):
    """Localisation input that names what the COLMAP model does not hold: a ``camera_id`` or a
    ``point3D_id``. The message names the argument and the id."""


def localize_in_model(reconstruction: Any, camera: Any, points2D: Any, point3D_ids: Any, *, ransac: Any = True,
                      options: Any = None, point_covariances: Any = None,
                      point_cameras: Any = None) -> tuple[Any, Any]:
    """Localises one image, or one frame of a rig, in a COLMAP model from its keypoints matched to the
    model's 3-D points: ``points2D`` (n, 2), the image's own (distorted) pixels, and ``point3D_ids``
    (n,). ``camera``: the ``camera_id`` of one of the model's cameras, a ``pycolmap.Camera`` or a
    ``pluecker.Camera``; or a frame: a :class:`pluecker.Rig` (``rig(reconstruction, rig_id)``) with
    ``point_cameras`` (n,), the index in ``rig.cameras`` of the camera whose pixels each match holds,
    and then the pose is the frame's ``rig_from_world``.
    ``reconstruction``: a ``pycolmap.Reconstruction`` (or a :class:`ColmapModel`).
    Returns ``(cam_from_world, PoseResult)`` as :func:`localize` does: robust by default (``ransac=True``,
    :class:`pluecker.RansacOptions` defaults: 4 px threshold in the image's pixels; pass
    ``ransac=pluecker.RansacOptions(point_threshold=..., confidence=..., max_iterations=..., seed=...)``).
    A ``camera_id`` or ``point3D_id`` the model does not hold (a negative one included) is a
    :class:`MatchError` naming it; a ``camera`` of another type (a bool, say) ``InvalidOptionError``."""
    ids = np.asarray(point3D_ids)
    if ids.ndim != 1 or not (np.issubdtype(ids.dtype, np.integer) or len(ids) == 0):
        raise _core.ShapeError(f"point3D_ids: expected a 1-D array of integer ids, got shape {ids.shape} of "
                               f"{ids.dtype}")
    # COLMAP's ids are unsigned; a negative id, or one beyond int64, names no point of a model.
    values = [int(i) for i in ids]
    in_range = np.array([0 <= v < 2**63 for v in values], dtype=bool)
    lookup = np.where(in_range, ids if ids.dtype != np.uint64 else np.minimum(ids, 2**63 - 1), 0).astype(np.int64)
    if isinstance(reconstruction, ColmapModel):
        points3D, known = reconstruction.lookup(lookup)
        cameras = reconstruction.cameras
    else:
        known = np.array([ok and reconstruction.exists_point3D(int(i)) for i, ok in zip(lookup, in_range)], dtype=bool)
        points3D = np.array([reconstruction.points3D[int(i)].xyz if ok else np.full(3, np.nan)
                             for i, ok in zip(lookup, known)], dtype=float).reshape(-1, 3)
        cameras = reconstruction.cameras
    known &= in_range
    if not known.all():
        first = int(np.flatnonzero(~known)[0])
        missing = int((~known).sum())
        raise MatchError(f"point3D_ids: point3D_id {values[first]} (match {first}) is not a point of the model "
                         f"({missing} such match{'es' if missing > 1 else ''})")
    if isinstance(camera, (int, np.integer)) and not isinstance(camera, (bool, np.bool_)):
        camera_id = int(camera)
        if not (0 <= camera_id < 2**32 and camera_id in cameras):
            raise MatchError(f"camera: camera_id {camera_id} is not a camera of the model")
        camera = cameras[camera_id]
        if isinstance(camera, tuple):  # a ColmapModel's (model name, params)
            camera = _core.Camera(camera[0], list(camera[1]))
    elif not isinstance(camera, (_core.Camera, _core.Rig)) and not hasattr(camera, "params"):
        raise _core.InvalidOptionError(f"camera: expected a camera_id (an int), a pycolmap.Camera, a "
                                       f"pluecker.Camera or a pluecker.Rig, got {shown(camera)}")
    return localize(camera, points2D, points3D, ransac=ransac, options=options,
                    point_covariances=point_covariances, point_cameras=point_cameras)
