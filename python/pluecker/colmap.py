"""COLMAP and pluecker conventions side by side, in one place (issue 12 §2).

pycolmap is an optional extra (``pip install pluecker[colmap]``); the functions that take or return
pycolmap objects import it when called and say how to install it when it is missing.

- **Poses.** COLMAP's ``cam_from_world`` (a ``pycolmap.Rigid3d``) maps world points to the camera
  frame, ``x_cam = R X_world + t``: exactly pluecker's ``(R, t)``. No inversion is involved.
- **Quaternions.** pycolmap's ``Rotation3d.quat`` is ``(x, y, z, w)``. COLMAP's text files
  (``images.txt``: ``QW QX QY QZ``) and pluecker's dual quaternions are ``(w, x, y, z)``.
- **Cameras.** ``pycolmap.Camera(model, width, height, params)`` is ``pluecker.LensCamera(model,
  params)``: the same model names and parameter order. The image size is not part of the model.
- **Camera matrices.** Triangulation takes ``P = K [R | t]`` of an undistorted camera
  (``Camera.P(R, t)``). With a distorting model, the pixels are unprojected first
  (``LensCamera.unproject``) and ``K`` is the identity.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from . import _core


def _pycolmap() -> Any:
    try:
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


def lens_camera(camera: Any) -> _core.LensCamera:
    """The ``pluecker.LensCamera`` of a ``pycolmap.Camera``: same model, same parameters."""
    return _core.LensCamera(camera.model.name, list(camera.params))


def colmap_camera(camera: _core.LensCamera, width: int, height: int) -> Any:
    """The ``pycolmap.Camera`` of a ``pluecker.LensCamera``, for an image of ``width`` x ``height`` pixels."""
    pycolmap = _pycolmap()
    return pycolmap.Camera(model=camera.model, width=width, height=height, params=list(camera.params))


def retriangulate(reconstruction: Any, sigma_px: float = 1.0, method: str | None = None,
                  options: Any = None) -> tuple[np.ndarray, Any]:
    """Re-triangulates every 3-D point of a ``pycolmap.Reconstruction`` from its track, with the
    cameras (models, distortion) and poses held fixed: ``(point3D_ids, PointTriangulations)``, row ``i``
    the point ``point3D_ids[i]``.

    Each observation is unprojected exactly through its camera model (``LensCamera.unproject``), and its
    pixel noise (``sigma_px`` pixels, isotropic) is carried to the normalised coordinates to first order
    (``LensCamera.normalized_covariances``). The cost of eq. 19 is therefore in pixels² as COLMAP's bundle
    adjustment counts it, and a certificate proves the global minimum of that first-order cost. Use
    :func:`update_points` to write the points back. ``method`` and ``options`` are those of
    :func:`pluecker.triangulate_point_observations`.
    """
    images = [image for image in reconstruction.images.values() if image.has_pose]
    index = {image.image_id: j for j, image in enumerate(images)}
    # Normalised cameras [R | t]: the pixels are unprojected through each camera's model below.
    P = np.stack([np.hstack([R, t[:, None]]) for R, t in (pose_from_rigid(image.cam_from_world()) for image in images)])
    lens = {image.image_id: lens_camera(reconstruction.cameras[image.camera_id]) for image in images}
    ids, track, image_of, pixels = [], [], [], []
    for t, (point_id, point) in enumerate(sorted(reconstruction.points3D.items())):
        ids.append(point_id)
        for element in point.track.elements:
            if element.image_id not in index:
                continue
            track.append(t)
            image_of.append(element.image_id)
            pixels.append(reconstruction.images[element.image_id].points2D[element.point2D_idx].xy)
    track_a = np.asarray(track, dtype=np.int64)
    pixels_a = np.asarray(pixels, dtype=float).reshape(-1, 2)
    normalized = np.empty_like(pixels_a)
    covariances = np.empty((len(pixels_a), 2, 2))
    image_a = np.asarray(image_of, dtype=np.int64)
    for image_id in np.unique(image_a):
        rows = np.flatnonzero(image_a == image_id)
        camera = lens[int(image_id)]
        normalized[rows] = camera.unproject(pixels_a[rows])
        covariances[rows] = camera.normalized_covariances(pixels_a[rows], np.tile(sigma_px**2 * np.eye(2), (len(rows), 1, 1)))
    cameras_index = np.array([index[int(i)] for i in image_a], dtype=np.int64)
    result = _core.triangulate_point_observations(P, track_a, cameras_index, normalized, covariances,
                                                  method=method, options=options)
    return np.asarray(ids), result


def update_points(reconstruction: Any, point3D_ids: Any, result: Any) -> int:
    """Writes the successfully re-triangulated points of :func:`retriangulate` into ``reconstruction``
    (their ``xyz``); the others are left as they were. Returns how many were written."""
    written = 0
    for point_id, X, status in zip(point3D_ids, result.X, result.status):
        if status == "success":
            reconstruction.points3D[int(point_id)].xyz = X
            written += 1
    return written
