"""pluecker: camera pose from 2-D/3-D point and line correspondences.

The estimators of Phong, Horaud, Yassine & Tao, *Object pose from 2-D to 3-D point and line
correspondences* (IJCV 1995) and their baselines, implemented in Rust (the ``pluecker`` crate) and
exposed here through the extension module ``pluecker._core``.

Conventions (everywhere in the package):

- A world point maps to the camera frame by ``x_cam = R @ X_world + t``; the camera looks down
  ``+z`` and a point is in front of it when ``z > 0``.
- Pixels are ``u = K x_cam / z`` with ``K = [[fx, skew, cx], [0, fy, cy], [0, 0, 1]]``. ``fx`` and
  ``fy`` may be negative (a mirrored axis, as in the paper's camera), never zero.
- Angles are in radians; lengths in the unit of the 3-D data; image quantities in pixels.
- Arrays are numpy float64, row-major, one correspondence per row: image points ``(N, 2)``,
  object points ``(N, 3)``, image segments ``(M, 2, 2)`` (two pixel endpoints), object segments
  ``(M, 2, 3)`` (two world endpoints). ``None`` stands for zero rows. Any real array-like is
  accepted and converted.
- Bad input raises a subclass of :class:`PlueckerError`, itself a :class:`ValueError`, whose message
  names the argument and, for NaN/inf, the row. A solver that runs but fails returns a
  :class:`PoseResult` whose ``status`` says why.

Example::

    import pluecker
    scene = pluecker.random_scene("general", n_points=20, seed=1)
    result = pluecker.estimate_pose(scene["camera"], scene["points2d"], scene["points3d"])
    assert result.success
"""

from ._core import (
    METHODS,
    Camera,
    DegenerateConfigurationError,
    FittedConic,
    FittedLine,
    InvalidOptionError,
    LineTriangulation,
    NonFiniteError,
    PlueckerError,
    PoseResult,
    PointTriangulation,
    PointTriangulations,
    PoseStage,
    QuadricTriangulation,
    ShapeError,
    SingularCameraError,
    TooFewCorrespondencesError,
    TriangulationReport,
    __version__,
    dual_quaternion_to_pose,
    estimate_pose,
    fit_conic,
    fit_line,
    fitting_residual_samples,
    paper_scene,
    pose_covariance,
    pose_to_dual_quaternion,
    pose_to_screw,
    random_scene,
    reprojection_errors,
    triangulate_line,
    triangulate_point,
    triangulate_points,
    triangulate_quadric,
)

__all__ = [
    "METHODS",
    "Camera",
    "DegenerateConfigurationError",
    "FittedConic",
    "FittedLine",
    "InvalidOptionError",
    "LineTriangulation",
    "NonFiniteError",
    "PlueckerError",
    "PoseResult",
    "PointTriangulation",
    "PointTriangulations",
    "PoseStage",
    "QuadricTriangulation",
    "ShapeError",
    "SingularCameraError",
    "TooFewCorrespondencesError",
    "TriangulationReport",
    "__version__",
    "dual_quaternion_to_pose",
    "estimate_pose",
    "fit_conic",
    "fit_line",
    "fitting_residual_samples",
    "paper_scene",
    "pose_covariance",
    "pose_to_dual_quaternion",
    "pose_to_screw",
    "random_scene",
    "reprojection_errors",
    "triangulate_line",
    "triangulate_point",
    "triangulate_points",
    "triangulate_quadric",
]
