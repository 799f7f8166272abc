"""pluecker: camera pose from 2-D/3-D point and line correspondences, and triangulation of points,
lines and quadrics from known cameras.

The pose estimators of Phong, Horaud, Yassine & Tao, *Object pose from 2-D to 3-D point and line
correspondences* (IJCV 1995) and their baselines (:func:`estimate_pose`), and the triangulation of
Josephson & Kahl, *Triangulation of points, lines and conics* (JMIV 2008) with certified global
optimality (:func:`triangulate_point`, :func:`triangulate_points`, :func:`triangulate_line`,
:func:`triangulate_quadric`, their parallel batches :func:`triangulate_lines` and
:func:`triangulate_quadrics`, and :func:`fit_line` / :func:`fit_conic` for the covariances), implemented in
Rust (the ``pluecker`` crate) and exposed here through the extension module ``pluecker._core``.

Conventions (frames, pixels, units, array shapes, when a point is in front): stated once, in the
"Conventions" section of the README. In Python, ``None`` stands for zero rows and any real array-like is
accepted and converted to float64.

Bad input raises a subclass of :class:`PlueckerError`, itself a :class:`ValueError`, whose message names
the argument and, for NaN/inf, the row. A solver that runs but fails returns a result
(:class:`PoseResult`, :class:`TriangulationReport`) whose ``status`` says why.

Example::

    import pluecker
    scene = pluecker.random_scene("general", n_points=20, seed=1)
    result = pluecker.estimate_pose(scene["camera"], scene["points2d"], scene["points3d"])
    assert (result.status == "success")

    import numpy as np
    K = scene["camera"].K
    P = np.stack([K @ np.hstack([np.eye(3), [[-b], [0.0], [0.0]]]) for b in (0.0, 0.5, 1.0)])
    X = np.array([0.2, -0.1, 5.0])
    x = np.array([(p @ np.append(X, 1.0))[:2] / (p @ np.append(X, 1.0))[2] for p in P])
    point = pluecker.triangulate_point(P, x)
    assert point.certified and np.allclose(point.point, X)
"""

# pycolmap's wheels carry their own zlib: when pycolmap is imported before Python's zlib module, the first
# compression through the module aborts the process. Loading zlib here, before pluecker.colmap can import
# pycolmap, avoids it for every import order that imports pluecker first; pluecker itself never compresses
# with zlib, so the order pycolmap-then-pluecker is safe too.
import zlib  # isort: skip  (deleted from the namespace at the end: loaded, not a name of the API)

from ._core import (
    METHODS,
    STATUSES,
    TRIANGULATION_METHODS,
    BatchReport,
    Camera,
    Certificate,
    CertifyOptions,
    DegenerateConfigurationError,
    FittedConic,
    FittedLine,
    InvalidOptionError,
    LevenbergMarquardtOptions,
    LineTriangulation,
    LineTriangulations,
    NonFiniteError,
    PlueckerError,
    PointTriangulation,
    PointTriangulations,
    Pose,
    PoseDetails,
    PoseOptions,
    PoseResult,
    PoseStage,
    QuadricTriangulation,
    QuadricTriangulations,
    RansacOptions,
    RansacReport,
    Rig,
    ShapeError,
    SingularCameraError,
    StoppingCriteria,
    TooFewCorrespondencesError,
    TriangulationOptions,
    TriangulationReport,
    TrustRegionOptions,
    View,
    __version__,
    dual_quaternion_to_pose,
    estimate_pose,
    fit_conic,
    fit_line,
    fitting_residual_samples,
    get_num_threads,
    gp3p,
    lines_from_endpoints,
    p1p2l,
    p2p1l,
    p3l,
    p3p,
    paper_scene,
    pose_covariance,
    pose_to_dual_quaternion,
    pose_to_screw,
    random_scene,
    refine_pose,
    reprojection_errors,
    set_num_threads,
    triangulate_line,
    triangulate_lines,
    triangulate_point,
    triangulate_points,
    triangulate_quadric,
    triangulate_quadrics,
)
from ._status import Status

__all__ = [
    "get_num_threads",
    "set_num_threads",
    "METHODS",
    "STATUSES",
    "Status",
    "TRIANGULATION_METHODS",
    "BatchReport",
    "Camera",
    "DegenerateConfigurationError",
    "FittedConic",
    "FittedLine",
    "InvalidOptionError",
    "LineTriangulation",
    "LineTriangulations",
    "NonFiniteError",
    "PlueckerError",
    "Pose",
    "PoseDetails",
    "PoseResult",
    "TriangulationOptions",
    "View",
    "Rig",
    "RansacReport",
    "RansacOptions",
    "LevenbergMarquardtOptions",
    "StoppingCriteria",
    "TrustRegionOptions",
    "CertifyOptions",
    "Certificate",
    "PoseOptions",
    "PointTriangulation",
    "PointTriangulations",
    "PoseStage",
    "QuadricTriangulation",
    "QuadricTriangulations",
    "ShapeError",
    "SingularCameraError",
    "TooFewCorrespondencesError",
    "TriangulationReport",
    "__version__",
    "dual_quaternion_to_pose",
    "estimate_pose",
    "refine_pose",
    "p3l",
    "p1p2l",
    "p2p1l",
    "gp3p",
    "p3p",
    "fit_conic",
    "fit_line",
    "lines_from_endpoints",
    "fitting_residual_samples",
    "paper_scene",
    "pose_covariance",
    "pose_to_dual_quaternion",
    "pose_to_screw",
    "random_scene",
    "reprojection_errors",
    "triangulate_line",
    "triangulate_lines",
    "triangulate_point",
    "triangulate_points",
    "triangulate_quadric",
    "triangulate_quadrics",
]

del zlib  # loaded above (it stays in sys.modules), not a name of the API
