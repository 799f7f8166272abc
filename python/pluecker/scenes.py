"""Synthetic scenes with known answers, for tests and benchmarks (every one takes a seed or a
``numpy.random.Generator`` and is reproducible).

- :func:`random_rotation` and :func:`lens_scene`: points in a camera's frame spread over its field of view
  (out to a normalised radius, or an angle off axis for a fisheye), with a random pose.
- :func:`colmap_reconstruction`: a ``pycolmap.Reconstruction`` with one camera model, noisy observations
  through that camera's exact projection, and optionally tracks that observe one image twice (needs the
  ``colmap`` extra).
- :func:`colmap_rig_reconstruction`: a ``pycolmap.Reconstruction`` of one rig of 2-6 cameras with mixed
  models, looking different ways, its observations through each camera's exact projection.

Conventions as everywhere in pluecker: ``x_cam = R X_world + t``, pixels through the camera model.
"""

from __future__ import annotations

from typing import Any, Callable

import numpy as np


def random_rotation(rng: np.random.Generator) -> np.ndarray:
    """A rotation matrix drawn uniformly (QR of a Gaussian matrix, signs fixed, det +1)."""
    q, r = np.linalg.qr(rng.normal(size=(3, 3)))
    q = q * np.sign(np.diag(r))
    return q * np.linalg.det(q)


def lens_scene(rng: np.random.Generator, r_max: float, n: int, *, fisheye: bool = False,
               depths: tuple[float, float] = (4.0, 8.0)) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """``(R, t, x_cam, X_world)``: ``n`` camera-frame points uniform over the disc of normalised radius
    ``r_max`` (with ``fisheye``, uniform in angle over the cap out to ``atan(r_max)`` off axis) at depths
    (distances) uniform in ``depths``, and a random pose; ``X_world = Rᵀ (x_cam − t)``."""
    phi = rng.uniform(0, 2 * np.pi, n)
    if fisheye:
        r = np.tan(np.sqrt(rng.uniform(0, 1, n)) * np.arctan(r_max))
    else:
        r = np.sqrt(rng.uniform(0, 1, n)) * r_max
    d = np.column_stack([r * np.cos(phi), r * np.sin(phi), np.ones(n)])
    x_cam = d / np.linalg.norm(d, axis=1, keepdims=True) * rng.uniform(*depths, (n, 1))
    R, t = random_rotation(rng), rng.normal(size=3)
    return R, t, x_cam, (x_cam - t) @ R


def within_degrees(degrees: float) -> Callable[[np.ndarray], np.ndarray]:
    """The visibility test of rays at most ``degrees`` off axis, for camera-frame points ``(k, 3)``."""
    return lambda x: np.degrees(np.arctan2(np.hypot(x[:, 0], x[:, 1]), x[:, 2])) <= degrees


def inside_fold(k: float) -> Callable[[np.ndarray], np.ndarray]:
    """The visibility test of SIMPLE_RADIAL ``r_d = r (1 + k r²)``, ``k < 0``: normalised radius inside
    the fold ``r_fold² = −1 / (3k)`` (beyond it the model folds back into the image)."""
    r_fold = np.sqrt(-1.0 / (3.0 * k))
    return lambda x: np.hypot(x[:, 0] / x[:, 2], x[:, 1] / x[:, 2]) < r_fold


def colmap_reconstruction(model: str, params: list[float], width: int, height: int, *, spread: float = 1.0,
                          seed: int = 0, points: int = 500, visible: Callable[[np.ndarray], np.ndarray] | None = None,
                          noise_px: float = 1.0, repeated_fraction: float = 0.0) -> Any:
    """``pycolmap.synthesize_dataset`` (2 rigs x 6 frames, ``points`` 3-D points) with one camera model
    (COLMAP's name and parameter order), the structure enlarged ``spread`` times about its centre, and
    every observation re-projected through the camera (``Camera.img_from_cam``) plus Gaussian noise of
    ``noise_px`` pixels (``numpy`` seed ``seed``).

    An observation is kept when its noise-free pixel is inside the image, the point is more than 0.5
    units in front of the camera, and ``visible(x_cam)`` (the camera's valid domain, e.g.
    :func:`within_degrees`) holds; points left with fewer than two observations are deleted. Then
    ``repeated_fraction`` of the tracks get a second keypoint in one of their images (the noise-free pixel
    plus its own noise), as COLMAP's track merging leaves them."""
    import pycolmap

    options = pycolmap.SyntheticDatasetOptions()
    options.num_rigs, options.num_frames_per_rig, options.num_points3D = 2, 6, points
    options.camera_model_id = getattr(pycolmap.CameraModelId, model)
    options.camera_params = [float(v) for v in params]
    options.camera_width, options.camera_height = width, height
    options.num_points2D_without_point3D = 0
    pycolmap.set_random_seed(seed)
    rec = pycolmap.synthesize_dataset(options)
    centre = np.mean([p.xyz for p in rec.points3D.values()], axis=0)
    for p in rec.points3D.values():
        p.xyz = centre + spread * (p.xyz - centre)
    rng = np.random.default_rng(seed)
    _observe(rec, rng, visible, noise_px)
    if repeated_fraction > 0:
        ids = sorted(rec.points3D)
        for point_id in rng.choice(ids, size=int(repeated_fraction * len(ids)), replace=False):
            point = rec.points3D[int(point_id)]
            image = rec.images[point.track.elements[rng.integers(point.track.length())].image_id]
            u = rec.cameras[image.camera_id].img_from_cam(np.atleast_2d(image.cam_from_world() * point.xyz))[0]
            image.points2D.append(pycolmap.Point2D(u + noise_px * rng.normal(size=2)))
            rec.add_observation(int(point_id), pycolmap.TrackElement(image.image_id, len(image.points2D) - 1))
    return rec


def _observe(rec: Any, rng: np.random.Generator, visible: Callable[[np.ndarray], np.ndarray] | None,
             noise_px: float) -> None:
    """Re-projects every observation of ``rec`` through its image's camera, plus Gaussian noise of
    ``noise_px`` pixels; drops it when its noise-free pixel is outside the image, the point is 0.5 units
    or less in front of the camera, or ``visible(x_cam)`` fails; then deletes the points left with fewer
    than two observations."""
    for image_id in sorted(rec.images):
        image = rec.images[image_id]
        camera = rec.cameras[image.camera_id]
        for idx, point2D in enumerate(image.points2D):
            if not point2D.has_point3D():
                continue
            x_cam = image.cam_from_world() * rec.points3D[point2D.point3D_id].xyz
            seen = x_cam[2] > 0.5 and (visible is None or bool(visible(np.atleast_2d(x_cam))[0]))
            u = camera.img_from_cam(np.atleast_2d(x_cam))[0] if seen else np.full(2, -1.0)
            if not (0 <= u[0] < camera.width and 0 <= u[1] < camera.height):
                rec.delete_observation(image_id, idx)
            else:
                point2D.xy = u + noise_px * rng.normal(size=2)
    for point_id in [i for i, p in rec.points3D.items() if p.track.length() < 2]:
        rec.delete_point3D(point_id)


def colmap_rig_reconstruction(cameras: list[tuple[str, list[float]]], width: int, height: int, *,
                              frames: int = 6, points: int = 500, rotation_stddev_deg: float = 30.0,
                              translation_stddev: float = 0.2, noise_px: float = 1.0, seed: int = 0,
                              visible: Callable[[np.ndarray], np.ndarray] | None = None) -> Any:
    """``pycolmap.synthesize_dataset`` with one rig of ``len(cameras)`` cameras (2-6: COLMAP's names and
    parameter orders, mixed models welcome), ``frames`` frames and ``points`` 3-D points; each camera's
    ``sensor_from_rig`` drawn by COLMAP with rotations of ``rotation_stddev_deg`` degrees (tens of degrees:
    fields of view that barely overlap or not at all) and translations of ``translation_stddev`` units.
    The rig's reference camera gets ``cameras[0]``, the others ``cameras[1:]`` by sensor id (the order of
    :func:`pluecker.colmap.rig`). Every observation is re-projected through its camera plus Gaussian noise
    of ``noise_px`` pixels (``numpy`` seed ``seed``), and dropped as :func:`colmap_reconstruction` drops
    them."""
    import pycolmap

    if not 2 <= len(cameras) <= 6:
        raise ValueError(f"cameras: a rig of 2 to 6 cameras, got {len(cameras)}")
    options = pycolmap.SyntheticDatasetOptions()
    options.num_rigs, options.num_cameras_per_rig, options.num_frames_per_rig = 1, len(cameras), frames
    options.num_points3D, options.num_points2D_without_point3D = points, 0
    options.sensor_from_rig_rotation_stddev = rotation_stddev_deg
    options.sensor_from_rig_translation_stddev = translation_stddev
    options.camera_width, options.camera_height = width, height
    pycolmap.set_random_seed(seed)
    rec = pycolmap.synthesize_dataset(options)
    rig = rec.rig(next(iter(rec.rigs)))
    order = [rig.ref_sensor_id.id, *sorted(s.id for s in rig.non_ref_sensors)]
    for camera_id, (model, params) in zip(order, cameras):
        rec.cameras[camera_id] = pycolmap.Camera(camera_id=camera_id, model=model, width=width, height=height,
                                                 params=[float(v) for v in params])
    _observe(rec, np.random.default_rng(seed), visible, noise_px)
    return rec
