"""Typed stubs of the extension module ``pluecker._core`` (Rust, PyO3).

Conventions: ``x_cam = R @ X_world + t``; pixels ``u = K x_cam / z`` with
``K = [[fx, skew, cx], [0, fy, cy], [0, 0, 1]]``; radians; lengths in the unit of the 3-D data.
Array arguments accept any real array-like and are converted to float64; returned arrays are fresh
float64 row-major ndarrays owned by the caller. ``tests/test_api.py`` checks that the names here and
the names of the module agree.
"""

from typing import Any, Optional, Tuple, TypedDict

import numpy as np
from numpy.typing import ArrayLike, NDArray

__version__: str
"""The package version (the Rust crates' version)."""

METHODS: Tuple[str, ...]
"""Every name ``estimate_pose`` accepts for ``method``, the default first."""

# --- Exceptions -----------------------------------------------------------------------------------

class PlueckerError(ValueError):
    """Base class of every error pluecker raises for bad input or a failed computation.

    A Rust panic (a bug) also arrives as ``PlueckerError("internal error: ...")``, never as a crash.
    """

class ShapeError(PlueckerError):
    """An array has the wrong shape, or two arrays that must have the same number of rows do not.

    Example message: ``"points2d: expected shape (N, 2), got (5, 3)"``.
    """

class NonFiniteError(PlueckerError):
    """An input holds NaN or inf: ``"points3d: non-finite value (NaN or inf) in row 4"``."""

class TooFewCorrespondencesError(PlueckerError):
    """Fewer correspondences than the method needs (3 points/lines; 6 points for ``linear``)."""

class DegenerateConfigurationError(PlueckerError):
    """The data cannot determine the answer: collinear points, all lines parallel or through one
    point, a zero-length segment, coplanar points for ``linear``, a singular information matrix."""

class SingularCameraError(PlueckerError):
    """Intrinsics that cannot be inverted: a zero focal length, a NaN/inf entry, or a ``K`` that is
    not upper triangular with last row ``(0, 0, 1)``."""

class InvalidOptionError(PlueckerError):
    """An option or argument value outside its domain: unknown method or scene kind, ``penalty <= 0``,
    an iteration cap below 1, ``sigma_px <= 0``, an ``R`` that is not a rotation matrix."""

# --- Camera ---------------------------------------------------------------------------------------

class Camera:
    """Pinhole intrinsics in pixels, ``K = [[fx, skew, cx], [0, fy, cy], [0, 0, 1]]``. Immutable,
    hashable, comparable with ``==``, picklable.

    ``fx`` and ``fy`` may be negative (a mirrored image axis, as in Phong & Horaud's camera);
    zero or non-finite values raise :class:`SingularCameraError`.
    """

    def __init__(self, fx: float, fy: float, cx: float, cy: float, skew: float = 0.0) -> None: ...
    @staticmethod
    def from_matrix(K: ArrayLike) -> "Camera":
        """From a (3, 3) calibration matrix, divided by ``K[2, 2]`` first. Raises
        :class:`ShapeError` for another shape and :class:`SingularCameraError` when ``K`` has a
        NaN/inf, is not upper triangular with last row ``(0, 0, 1)``, or has a zero focal length."""
    @property
    def fx(self) -> float:
        """Focal length along u, pixels (the paper's alpha_u)."""
    @property
    def fy(self) -> float:
        """Focal length along v, pixels (alpha_v)."""
    @property
    def cx(self) -> float:
        """Principal point u, pixels (u_0)."""
    @property
    def cy(self) -> float:
        """Principal point v, pixels (v_0)."""
    @property
    def skew(self) -> float:
        """Skew, pixels."""
    @property
    def K(self) -> NDArray[np.float64]:
        """The (3, 3) calibration matrix."""
    def project(self, points_cam: ArrayLike) -> NDArray[np.float64]:
        """Pixels (N, 2) ``u = K x_cam / z`` of camera-frame points (N, 3). Points with ``z <= 0``
        are not rejected: ``z = 0`` gives inf, ``z < 0`` the mirrored projection."""
    def pixel_to_normalized(self, pixels: ArrayLike) -> NDArray[np.float64]:
        """Normalised image coordinates (N, 2), ``(x, y, 1) ∝ K^-1 (u, v, 1)``, of pixels (N, 2)."""
    def normalized_to_pixel(self, normalized: ArrayLike) -> NDArray[np.float64]:
        """Pixels (N, 2) of normalised image coordinates (N, 2); the inverse of
        :meth:`pixel_to_normalized`."""
    def __eq__(self, other: object) -> bool: ...
    def __hash__(self) -> int: ...
    def __repr__(self) -> str: ...
    def __reduce__(self) -> Tuple[Any, Tuple[float, float, float, float, float]]: ...

# --- Pose estimation ------------------------------------------------------------------------------

class PoseStage:
    """One stage of the pose pipeline: the algebraic estimator (``"trust-region"``, ``"rotation"``
    and ``"translation"``, ...), the linear solve (``"linear"``), or the reprojection refinement
    (``"refinement"``). Immutable; array properties return fresh copies."""

    @property
    def name(self) -> str:
        """Stage name."""
    @property
    def cost_kind(self) -> str:
        """``"algebraic"`` (the paper's eqs. 13-15, 22 as ½ΣΦ², in normalised units) or
        ``"reprojection"`` (½Σ squared pixel residuals)."""
    @property
    def R(self) -> NDArray[np.float64]:
        """Rotation (3, 3) at the end of the stage, world → camera."""
    @property
    def t(self) -> NDArray[np.float64]:
        """Translation (3,) at the end of the stage, world units."""
    @property
    def iterations(self) -> int:
        """Accepted iterations (0 for a closed-form stage)."""
    @property
    def initial_cost(self) -> float:
        """Cost at the start of the stage."""
    @property
    def final_cost(self) -> float:
        """Cost at the end of the stage."""
    @property
    def termination(self) -> str:
        """Why it stopped: ``"gradient_tolerance"``, ``"radius_tolerance"``, ``"cost_tolerance"``,
        ``"step_tolerance"``, ``"max_iterations"``, ``"singular_hessian"``, ``"non_finite_cost"``
        or ``"closed_form"``."""
    @property
    def time_seconds(self) -> float:
        """Wall time of the stage, seconds."""
    def to_dict(self) -> "_PoseStageDict":
        """Plain-Python form (lists, floats, strings), JSON-serialisable."""
    def __repr__(self) -> str: ...

class PoseResult:
    """The answer of :func:`estimate_pose`. Immutable; array properties return fresh copies."""

    @property
    def R(self) -> NDArray[np.float64]:
        """Rotation (3, 3) with ``x_cam = R @ X_world + t`` (NaN if the solver failed numerically)."""
    @property
    def t(self) -> NDArray[np.float64]:
        """Translation (3,), in the unit of the 3-D data."""
    @property
    def dual_quaternion(self) -> NDArray[np.float64]:
        """The same motion as a unit dual quaternion (8,) ``(r0, rx, ry, rz, s0, sx, sy, sz)``,
        ``r`` the rotation quaternion (``r0 >= 0``) and ``s = ½ t r`` (paper eqs. 6-7)."""
    @property
    def axis(self) -> NDArray[np.float64]:
        """Unit rotation axis (3,), camera frame."""
    @property
    def angle(self) -> float:
        """Rotation angle about :attr:`axis`, radians in [0, π]."""
    @property
    def method(self) -> str:
        """The estimator that ran (one of :data:`METHODS`)."""
    @property
    def iterations(self) -> int:
        """Iterations summed over the stages."""
    @property
    def final_cost(self) -> float:
        """Cost of the last stage at the returned pose (see :attr:`PoseStage.cost_kind`)."""
    @property
    def termination(self) -> str:
        """Why the last stage stopped (see :attr:`PoseStage.termination`)."""
    @property
    def status(self) -> str:
        """``"success"``, ``"not_converged"`` (a stage hit its iteration cap),
        ``"numerical_failure"`` (singular Hessian, non-finite cost) or ``"points_behind_camera"``
        (some 3-D points or segment endpoints have ``z <= 0`` at the returned pose)."""
    @property
    def success(self) -> bool:
        """``status == "success"``."""
    @property
    def rms_error_px(self) -> float:
        """Root-mean-square reprojection error over all residuals (two per point, two per line),
        pixels."""
    @property
    def time_seconds(self) -> float:
        """Total wall time, seconds."""
    @property
    def stages(self) -> list[PoseStage]:
        """Every stage in order; the last one gave the returned pose."""
    @property
    def estimated_camera(self) -> Optional[Camera]:
        """The intrinsics estimated by ``method="linear"`` (None for the other methods)."""
    def to_dict(self) -> "_PoseResultDict":
        """Plain-Python form (nested lists, floats, strings, None), JSON-serialisable."""
    def __repr__(self) -> str: ...

class _PoseStageDict(TypedDict):
    name: str
    cost_kind: str
    R: list[list[float]]
    t: list[float]
    iterations: int
    initial_cost: float
    final_cost: float
    termination: str
    time_seconds: float

class _CameraDict(TypedDict):
    fx: float
    fy: float
    cx: float
    cy: float
    skew: float

class _PoseResultDict(TypedDict):
    R: list[list[float]]
    t: list[float]
    dual_quaternion: list[float]
    axis: list[float]
    angle: float
    method: str
    iterations: int
    final_cost: float
    termination: str
    status: str
    success: bool
    rms_error_px: float
    time_seconds: float
    stages: list[_PoseStageDict]
    estimated_camera: Optional[_CameraDict]

def estimate_pose(
    camera: Camera,
    points2d: Optional[ArrayLike] = None,
    points3d: Optional[ArrayLike] = None,
    lines2d: Optional[ArrayLike] = None,
    lines3d: Optional[ArrayLike] = None,
    method: str = "trust-region",
    *,
    penalty: float = 50.0,
    normalize: bool = True,
    refine: bool = True,
    initial_pose: Optional[Tuple[ArrayLike, ArrayLike]] = None,
    max_iterations: int = 200,
    refine_max_iterations: int = 50,
) -> PoseResult:
    """Estimate the pose ``x_cam = R @ X_world + t`` of a calibrated camera (Phong & Horaud 1995).

    Args:
        camera: the intrinsics.
        points2d: observed image points (N, 2), pixels.
        points3d: object points (N, 3), world frame, row i matching ``points2d[i]``.
        lines2d: observed image segments (M, 2, 2), two pixel endpoints each.
        lines3d: object segments (M, 2, 3), two world endpoints each; only the 3-D line through
            them is used (the endpoints need not correspond to the image ones).
        method: one of :data:`METHODS`: ``"trust-region"`` (rotation and translation together,
            eqs. 13 + 22, trust region with Hebden's step, section 4.1), ``"rotation-then-translation"``
            (eq. 14 then eq. 15), ``"trust-region-exact"`` (exact Hessian, Moré-Sorensen step,
            section 4.2), ``"newton"``, ``"levenberg-marquardt"`` (the paper's baselines), or
            ``"linear"`` (Faugeras-Toscani calibration from >= 6 non-coplanar points, which also
            estimates the intrinsics, see :attr:`PoseResult.estimated_camera`; lines are ignored).
        penalty: the paper's λ weighting the constraints ``r·r = 1`` and ``r·s = 0``; > 0.
        normalize: solve the algebraic stage in a centred, unit-scale object frame.
        refine: follow the estimator with a minimisation of the reprojection error (the
            maximum-likelihood pose under Gaussian pixel noise).
        initial_pose: an extra starting pose ``(R (3, 3), t (3,))`` for the iterative methods,
            world frame. It is tried first and the default starts too; the cheapest valid answer
            wins. Not needed: the default starts do not depend on a guess.
        max_iterations: iteration cap of the algebraic stage (trust region, Levenberg-Marquardt,
            Newton); >= 1.
        refine_max_iterations: iteration cap of the refinement; >= 1.

    Returns:
        A :class:`PoseResult`. A solver that ran but failed is not an exception: check
        :attr:`PoseResult.status`.

    Raises:
        ShapeError, NonFiniteError, TooFewCorrespondencesError (fewer than 3 points and lines
        together; 6 points for ``linear``), DegenerateConfigurationError (collinear points, all
        lines parallel or concurrent, a zero-length segment, coplanar points for ``linear``),
        InvalidOptionError, all subclasses of PlueckerError (a ValueError); TypeError for an
        argument that is not an array of real numbers.

    The GIL is released while the solver runs.
    """

def pose_covariance(
    camera: Camera,
    R: ArrayLike,
    t: ArrayLike,
    points2d: Optional[ArrayLike] = None,
    points3d: Optional[ArrayLike] = None,
    lines2d: Optional[ArrayLike] = None,
    lines3d: Optional[ArrayLike] = None,
    sigma_px: float = 1.0,
) -> NDArray[np.float64]:
    """The (6, 6) covariance ``σ² (JᵀJ)⁻¹`` of the pose ``(ω, t)`` for isotropic Gaussian pixel
    noise of standard deviation ``sigma_px`` (pixels) on every image point and segment endpoint.

    ``ω`` (first three, radians) is the rotation tangent vector with ``R ← exp(ω) R`` (camera
    frame); the last three are the translation, world units. ``J`` is the Jacobian of the
    reprojection residuals at ``(R, t)``; at the true pose this is the Cramér-Rao bound.
    Raises DegenerateConfigurationError when ``JᵀJ`` is singular (the data do not determine the
    pose) or not finite, InvalidOptionError when ``R`` is not a rotation or ``sigma_px <= 0``.
    """

def reprojection_errors(
    camera: Camera,
    R: ArrayLike,
    t: ArrayLike,
    points2d: Optional[ArrayLike] = None,
    points3d: Optional[ArrayLike] = None,
    lines2d: Optional[ArrayLike] = None,
    lines3d: Optional[ArrayLike] = None,
) -> NDArray[np.float64]:
    """Per-correspondence reprojection errors (N + M,) in pixels at ``(R, t)``: points first (the
    distance between the observed and projected point), then lines (the RMS of the distances of the
    two observed endpoints to the projected 3-D line). A zero-length segment gives NaN."""

# --- Dual quaternions -----------------------------------------------------------------------------

def pose_to_dual_quaternion(R: ArrayLike, t: ArrayLike) -> NDArray[np.float64]:
    """The unit dual quaternion (8,) ``(r0, rx, ry, rz, s0, sx, sy, sz)`` of ``(R, t)``:
    ``r`` the rotation quaternion and ``s = ½ t r`` (paper eqs. 6-7)."""

def dual_quaternion_to_pose(q: ArrayLike) -> Tuple[NDArray[np.float64], NDArray[np.float64]]:
    """``(R (3, 3), t (3,))`` of a dual quaternion (8,). ``r`` is normalised first; the component
    of ``s`` along ``r`` is ignored. ``q`` and ``-q`` give the same pose. Raises
    DegenerateConfigurationError when the real part is zero."""

class _Screw(TypedDict):
    d: float
    angle: float
    direction: NDArray[np.float64]
    point: NDArray[np.float64]

def pose_to_screw(R: ArrayLike, t: ArrayLike) -> _Screw:
    """Chasles' screw of ``(R, t)`` (section 2.1): a rotation by ``angle`` (radians, [0, π]) about
    the line through ``point`` (3,) with unit ``direction`` (3,), then a slide ``d`` along it.
    ``point`` is the point of the axis nearest the origin. For a pure translation the axis is the
    translation direction through the origin."""

# --- Synthetic scenes -----------------------------------------------------------------------------

class _PaperScene(TypedDict):
    camera: Camera
    R: NDArray[np.float64]
    t: NDArray[np.float64]
    points3d: NDArray[np.float64]
    points2d: NDArray[np.float64]

class _RandomScene(TypedDict):
    camera: Camera
    R: NDArray[np.float64]
    t: NDArray[np.float64]
    points3d: NDArray[np.float64]
    points2d: NDArray[np.float64]
    lines3d: NDArray[np.float64]
    lines2d: NDArray[np.float64]

def paper_scene() -> _PaperScene:
    """The calibration object of Phong & Horaud 1995, section 5: 460 points (two faces of a
    dihedral corner, centimetres) at the paper's pose, seen by the paper's camera
    (fx = -1730.3, fy = 1220.7, cx = 243.8, cy = 241.2), noise-free: ``points3d`` (460, 3),
    ``points2d`` (460, 2), ``R`` (3, 3), ``t`` (3,)."""

def random_scene(kind: str, n_points: int, n_lines: int = 0, seed: int = 0) -> _RandomScene:
    """A seeded random scene, noise-free, every point and endpoint in front of the camera and inside
    a 640 x 480 image (fx = fy = 800, cx = 320, cy = 240).

    ``kind``: ``"general"`` (points in a box 4-8 units in front of the camera), ``"planar"`` (one
    plane tilted 30-60°) or ``"far"`` (1 unit across at depth ~100, weak perspective). Returns
    ``points2d`` (n_points, 2), ``points3d`` (n_points, 3), ``lines2d`` (n_lines, 2, 2),
    ``lines3d`` (n_lines, 2, 3), ``R``, ``t`` and ``camera``. The same seed gives the same scene
    on every platform (and in Rust, ``pluecker::synthetic::random_scene``).
    """
