"""Typed stubs of the extension module ``pluecker._core`` (Rust, PyO3).

Conventions (frames, pixels, units, array shapes): the "Conventions" section of the README.
Array arguments accept any real array-like and are converted to float64; returned arrays are fresh
float64 row-major ndarrays owned by the caller. ``tests/test_api.py`` checks that the names here and
the names of the module agree.

Results (every class below that a function returns) are immutable; ``to_dict()`` gives strict JSON
(NaN and inf as ``None``), and ``pickle`` / ``copy.deepcopy`` reproduce them exactly within one version
of pluecker (a pickle from another version raises ``PlueckerError``).

Scalar arguments: a bool is not a number (``penalty=True`` or ``max_iterations=True`` is an
``InvalidOptionError``). Counts, caps and seeds take any Python or numpy integer from their minimum to
``2**64 - 1``; beyond that range, or below the minimum, they raise ``InvalidOptionError`` naming the
argument and the range (never a bare ``OverflowError``); a float where an integer is expected is a
``TypeError``.
"""

from typing import Any, Callable, Optional, Tuple, TypedDict

import numpy as np
from numpy.typing import ArrayLike, NDArray

__version__: str
"""The package version (the Rust crates' version)."""

METHODS: Tuple[str, ...]
"""Every name ``estimate_pose`` accepts for ``method``, the default first."""

TRIANGULATION_METHODS: Tuple[str, ...]
"""Every name the triangulation functions accept for ``method``: ``("linear", "local", "optimal")``."""

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
    an iteration cap below 1 or beyond ``2**64 - 1``, a bool for a number, ``sigma_px <= 0``, an ``R``
    that is not a rotation matrix, a ``visible`` entry other than 0/1, a ``sigma`` whose covariance
    overflows or underflows, 3-D coordinates whose squares overflow double precision."""

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
    and ``"translation"``, ...), the linear solve (``"linear"``), the robust sampling loop
    (``"ransac"``), or the reprojection refinement (``"refinement"``). Immutable; array properties
    return fresh copies."""

    @property
    def name(self) -> str:
        """Stage name."""
    @property
    def cost_kind(self) -> str:
        """``"algebraic"`` (the paper's eqs. 13-15, 22 as ½ΣΦ², in normalised units),
        ``"reprojection"`` (½Σ squared pixel residuals) or ``"msac"`` (stage ``"ransac"`` of
        ``robust=True``: ½Σ min(e², τ²) over all correspondences, px²; its iterations are the samples
        drawn)."""
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
        """Plain-Python form (lists, floats, strings), strict JSON: NaN and inf are ``None``."""
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
        """``"success"``, ``"not_converged"`` (a stage hit its iteration cap; robust: the sampling
        loop stopped on ``max_ransac_iterations``, ``time_budget`` or the ``min_inlier_ratio`` cap
        before reaching ``confidence`` for the best model),
        ``"numerical_failure"`` (singular Hessian, non-finite cost), ``"points_behind_camera"``
        (some 3-D points or segment endpoints — of the inliers when robust — have ``z <= 0`` at the
        returned pose, or the data are explained better with every point behind the camera: see
        :attr:`behind_camera_cost`), ``"ambiguous"`` (another local minimum explains the data nearly as well: see
        :attr:`ambiguous` and :attr:`second_best_cost`), and with ``robust=True``: ``"too_few_inliers"`` (the best model has fewer than
        :attr:`ransac_required_inliers` inliers — ``min_inliers``, or more when chance alone gives a
        wrong pose that many among many correspondences — e.g. all-outlier data or thresholds too
        tight; the pose is that
        model's, unrefined, and should not be used) or ``"no_hypothesis"`` (no sample gave a pose in
        front of the camera: every sample degenerate, or no minimal solver for the data's mix, see
        :attr:`ransac_stop`; the pose is NaN)."""
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
    def residual_test(self) -> Optional["_ResidualTestDict"]:
        """The χ² test of the residuals against ``sigma_px``: ``{"chi2", "dof", "p_value",
        "consistent"}``, ``chi2 = Σ r² / σ²`` over the ``m`` residuals of the used correspondences
        (inliers when robust), ``dof = m - 6``, ``consistent`` is ``p_value >= 1e-3``.
        ``consistent == False`` says the residuals are not explained by that noise (lens distortion
        left in the pixels, a wrong camera, noise larger than stated). None without ``sigma_px``."""
    @property
    def behind_camera_cost(self) -> Optional[float]:
        """When the residuals exceed the noise (``sigma_px``, else 1 px), the minimal solvers also look
        for poses with every object point *behind* the camera (the same pixels as a mirrored object in
        front); ``½ Σ r²`` (px²) of the best such pose when it fits better than the returned pose by
        more than ``½ ambiguity_threshold σ²`` (σ = ``sigma_px``, else 1 px) and by a factor of at least 100.
        :attr:`status` is then ``"points_behind_camera"``: the data come from points behind the
        camera, which no pose in front explains. None otherwise."""
    @property
    def stages(self) -> list[PoseStage]:
        """Every stage in order; the last one gave the returned pose."""
    @property
    def estimated_camera(self) -> Optional[Camera]:
        """The intrinsics estimated by ``method="linear"`` (None for the other methods)."""
    @property
    def inliers_points(self) -> NDArray[np.bool_]:
        """(N,) bool: the points the returned pose was fitted to — the final inliers when robust
        (reprojection distance ``<= point_threshold`` px at the returned pose), else all True."""
    @property
    def inliers_lines(self) -> NDArray[np.bool_]:
        """(M,) bool: the lines used — when robust, those whose two observed endpoints lie at an RMS
        distance ``<= line_threshold`` px from the projected 3-D line at the returned pose; else all
        True."""
    @property
    def ransac_iterations(self) -> int:
        """Minimal samples drawn by the robust loop (0 when not robust)."""
    @property
    def ransac_models_scored(self) -> int:
        """Poses scored (a sample gives up to four; 0 when not robust)."""
    @property
    def ransac_local_optimizations(self) -> int:
        """Local optimisations run, one per new best model (0 when not robust)."""
    @property
    def ransac_sprt_rejections(self) -> int:
        """Poses rejected early by the sequential probability ratio test (``sprt=True``; 0 when not
        robust)."""
    @property
    def ransac_errors_evaluated(self) -> int:
        """Reprojection errors evaluated while scoring the poses, early exits included (the work of the
        scoring; 0 when not robust)."""
    @property
    def ransac_required_inliers(self) -> int:
        """Fewest inliers the best model needed, else ``status="too_few_inliers"``:
        ``max(min_inliers, min(c + 1, ceil(min_inlier_ratio * n)))`` with ``c`` the most inliers a wrong
        pose plausibly gets by chance among the ``n`` correspondences (observations uniform in their
        bounding box; the best of the poses tried exceeds ``c`` with probability <= 1 %). Equals
        ``min_inliers`` up to a few hundred correspondences; about 20 for 20,000 points in a 640 x 480
        image (0 when not robust)."""
    @property
    def ransac_degenerate_samples(self) -> int:
        """Samples that gave no pose in front of the camera (0 when not robust)."""
    @property
    def ransac_time_seconds(self) -> float:
        """Wall time of the sampling loop, local optimisation included (0.0 when not robust)."""
    @property
    def ransac_stop(self) -> Optional[str]:
        """Why the sampling loop stopped: ``"confidence"`` (enough samples for ``confidence`` at the
        best model's inlier fractions), ``"min_inlier_ratio"`` (enough samples to have found a model
        with that inlier fraction, while the best has fewer or there is none), ``"iteration_cap"``,
        ``"time_budget"``, ``"interrupted"`` (Ctrl-C; the result is then attached to the
        ``KeyboardInterrupt`` as ``partial``) or ``"no_solvable_sample"`` (no mix of the data has a
        minimal solver); None when not robust."""
    @property
    def covariance(self) -> Optional[NDArray[np.float64]]:
        """(6, 6) covariance ``σ² (JᵀJ)⁻¹`` of the pose at the returned pose: the rotation as the
        tangent vector ``ω`` of ``R ← exp(ω) R`` (radians, camera frame; first three), then the
        translation (world units). ``J`` is the Jacobian of the reprojection residuals of the used
        correspondences (the inliers when robust). ``σ`` is :attr:`sigma_px`. Computed for every call;
        None when ``JᵀJ`` is singular (the used data do not fix the pose) or not finite, when ``σ``
        cannot be estimated (at most 6 residuals), or when the pose is NaN. First order: the
        Cramér-Rao bound at the estimate, meaningful after the refinement."""
    @property
    def covariance_source(self) -> Optional[str]:
        """``"given"`` (``sigma_px`` was passed), ``"estimated"`` (from the residuals), or None when
        :attr:`covariance` is None."""
    @property
    def sigma_px(self) -> Optional[float]:
        """The pixel noise σ of :attr:`covariance`: the given ``sigma_px``, or
        ``σ̂ = sqrt(Σ r² / (m − 6))`` over the ``m`` residuals of the used correspondences (two per
        point, two per line); None if ``m <= 6``."""
    @property
    def certified(self) -> bool:
        """True when the pose is proved to be the global minimum of the reprojection cost
        ``½ Σ r²`` (px²), to within the relative gap ``certify_gap``, over every rotation and
        translation that keeps the object points in front of the camera (``certify=True`` only;
        the sublevel-set test of ``pluecker::pose::certificate``)."""
    @property
    def lower_bound(self) -> float:
        """The proved lower bound on ``½ Σ r²`` (px²) over that domain; NaN without a certificate."""
    @property
    def gap(self) -> float:
        """``(cost − lower_bound) / max(cost, 1e-12)``; NaN without a certificate."""
    @property
    def certificate(self) -> str:
        """How the certificate was proved, or that there is none: ``"sublevel_set"``,
        ``"not_requested"`` (``certify=False``) or ``"not_proved"``."""
    @property
    def certificate_message(self) -> str:
        """A sentence: how it was proved (``"proved by the sublevel-set test (N rotation cells)"``) or
        why not (``"not requested ..."``, ``"not proved: ..."``, ``"not attempted: ..."``)."""
    @property
    def ambiguous(self) -> bool:
        """True when :attr:`status` is ``"ambiguous"``: another local minimum with every object point
        in front (:attr:`second_best_R`, :attr:`second_best_t`) has ``Σ r²`` within
        ``ambiguity_threshold · σ²`` of this one (σ = ``sigma_px``, else max(σ̂, 1 px))."""
    @property
    def second_best_R(self) -> Optional[NDArray[np.float64]]:
        """Rotation (3, 3) of the cheapest other local minimum found with every object point in
        front; None when the search found no other."""
    @property
    def second_best_t(self) -> Optional[NDArray[np.float64]]:
        """Translation (3,) of that minimum; None when there is none."""
    @property
    def second_best_cost(self) -> Optional[float]:
        """``½ Σ r²`` (px²) of that minimum; None when there is none."""
    def to_dict(self) -> "_PoseResultDict":
        """Plain-Python form (nested lists, floats, strings, None), strict JSON: NaN and inf are ``None``."""
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
    inliers_points: list[bool]
    inliers_lines: list[bool]
    ransac_iterations: int
    ransac_models_scored: int
    ransac_local_optimizations: int
    ransac_degenerate_samples: int
    ransac_sprt_rejections: int
    ransac_errors_evaluated: int
    ransac_required_inliers: int
    ransac_time_seconds: float
    ransac_stop: Optional[str]
    covariance: Optional[list[list[float]]]
    covariance_source: Optional[str]
    sigma_px: Optional[float]
    certified: bool
    lower_bound: float
    gap: float
    certificate: str
    certificate_message: str
    ambiguous: bool
    second_best_R: Optional[list[list[float]]]
    second_best_t: Optional[list[float]]
    second_best_cost: Optional[float]
    behind_camera_cost: Optional[float]
    residual_test: Optional[_ResidualTestDict]

class _ResidualTestDict(TypedDict):
    chi2: float
    dof: int
    p_value: float
    consistent: bool

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
    robust: bool = False,
    point_threshold: float = 4.0,
    line_threshold: float = 4.0,
    confidence: float = 0.9999,
    max_ransac_iterations: int = 100000,
    time_budget: Optional[float] = None,
    seed: int = 0,
    min_inliers: int = 6,
    min_inlier_ratio: float = 0.1,
    sprt: bool = True,
    sigma_px: Optional[float] = None,
    certify: bool = False,
    certify_gap: float = 1e-3,
    ambiguity_threshold: float = 9.0,
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
        robust: estimate robustly to outliers: LO-RANSAC over points and lines together (minimal
            samples of three correspondences of any mix solved by P3P / P2P1L / P1P2L / P3L, MSAC
            scoring, local optimisation of each new best model), then the reprojection refinement
            (``refine``) on the final inliers. ``method`` is not used on this path. The options below
            are checked whether or not ``robust`` is set.
        point_threshold: inlier threshold of a point: reprojection distance, pixels; > 0.
        line_threshold: inlier threshold of a line: RMS of the distances of its two observed
            endpoints to the projected 3-D line, pixels; > 0.
        confidence: stop when the probability of having drawn an all-inlier sample reaches this, at
            the best model's inlier fractions of points and of lines (with ``sprt``, counting that
            the test may reject a good pose with probability 1/A); in (0, 1).
        max_ransac_iterations: cap on the samples drawn; >= 1.
        time_budget: wall-time budget of the sampling loop, seconds, at least 0 and below 2**64 (None: only
            the cap bounds it); anything else is an ``InvalidOptionError``.
        seed: seed of the sampler (>= 0); the same seed and data give the same result.
        min_inliers: fewest inliers a model needs (>= 3); fewer gives ``status="too_few_inliers"``,
            and fewer correspondences than this in all is a TooFewCorrespondencesError. With many
            correspondences the model must also beat chance: see
            :attr:`PoseResult.ransac_required_inliers`.
        min_inlier_ratio: the smallest inlier fraction the loop is designed to find, in [0, 1): it
            stops after ``ceil(log(1 - confidence) / log(1 - min_inlier_ratio**3))`` samples (9,206 at
            the defaults; a little more with ``sprt``) even when the best model has fewer inliers or
            there is none (``ransac_stop="min_inlier_ratio"``), so all-outlier data end quickly with
            ``"too_few_inliers"``. A model with at least this fraction of inliers always meets
            :attr:`PoseResult.ransac_required_inliers`. 0 removes the cap and the chance requirement.
        sprt: reject bad poses early by Wald's sequential probability ratio test (Matas & Chum 2005)
            on the correspondences in a random order, with the inlier fraction of the best model so
            far (at least ``min_inlier_ratio``) against the rate of chance agreements estimated from
            the rejected poses. ``False`` scores every pose until it cannot beat the best one.
        sigma_px: standard deviation of the pixel noise for :attr:`PoseResult.covariance`; None
            estimates it from the residuals (see :attr:`PoseResult.sigma_px`); > 0.

        certify: prove that the answer is the global minimum (see :attr:`PoseResult.certified`);
            off by default (0.2-2 ms for 10-100 points at f = 800 px, see the README).
        certify_gap: relative gap at or below which the answer is certified, in (0, 1).
        ambiguity_threshold: the answer's status is ``"ambiguous"`` when another local minimum has
            ``Σ r²`` within this many ``σ²`` of it; ≥ 0.

    With ``refine=True`` (the default) the answer is the cheapest local minimum of the reprojection
    error that the refinement reaches from the algebraic answer and from the minimal solvers' poses on
    a few wide samples (every triple for 4-6 correspondences).

    Returns:
        A :class:`PoseResult`. A solver that ran but failed is not an exception: check
        :attr:`PoseResult.status`.

    Raises:
        ShapeError, NonFiniteError, TooFewCorrespondencesError (fewer than 3 points and lines
        together; 6 points for ``linear``; ``min_inliers`` when robust), DegenerateConfigurationError (collinear points, all
        lines parallel or concurrent, a zero-length segment, coplanar points for ``linear``),
        InvalidOptionError, all subclasses of PlueckerError (a ValueError); TypeError for an
        argument that is not an array of real numbers.

    The GIL is released while the solver runs. From 1000 correspondences on, the solve runs on a
    worker thread and Ctrl-C stops it within about 0.1 s: the ``KeyboardInterrupt`` carries the pose
    reached so far as ``partial`` (a robust pose: ``ransac_stop == "interrupted"``). Smaller problems
    take milliseconds and see Ctrl-C when they end.
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
    on every platform (and in Rust, ``pluecker::synthetic::random_scene``). At most 10,000,000 points and
    segments together (``InvalidOptionError`` naming the count beyond, before anything is allocated).
    """

# --- Triangulation (Josephson & Kahl 2008) --------------------------------------------------------
#
# Cameras are (n, 3, 4) matrices P that map world points straight to pixels, λ (u, v, 1) = P (X, 1)
# with λ = (P X̃)₃ > 0 in front of the camera (eq. 1) for the matrix as given: any positive scale, but the
# sign counts (−P sees the other half-space); fx < 0 or a left-handed world (det P[:, :3] < 0) are
# fine. ``certified`` is True only with status "success". Every method minimises
# eq. 19, Σ_i ‖L_i r_i‖², the residuals r_i of eq. 17 (pixels) whitened by the Cholesky factor L_i of
# the inverse observation covariance (eq. 18; identity when ``cov`` is None, so that the cost of a
# point is its sum of squared pixel errors). Methods: ``"linear"`` (DLT with Hartley normalisation),
# ``"local"`` (minimisation of eq. 19 from the linear answer; the paper's "bundle") and ``"optimal"``
# (the default: the local answer certified as the global minimum by a convexity test, or by branch
# and bound over the SOCP envelopes of eqs. 21-22 when the test cannot decide).

class TriangulationReport:
    """What a triangulation did: method, status, cost, certificate of global optimality, iterations,
    time. The base class of :class:`PointTriangulation`; immutable."""

    @property
    def method(self) -> str:
        """``"linear"``, ``"local"`` or ``"optimal"``."""
    @property
    def status(self) -> str:
        """``"success"``; ``"gap_not_closed"`` (branch and bound hit ``max_nodes``; the estimate is the
        best found and ``lower_bound`` the bound reached); ``"not_converged"`` (the local minimisation hit
        its iteration cap); ``"behind_camera"`` (the estimate is at or behind a camera; for ``local`` and
        ``optimal`` also: the data are best explained behind the cameras, and ``X`` is the linear point
        there); ``"at_infinity"`` (parallel rays, or no point in front costs less than a point at
        infinity: no finite estimate, ``X`` is NaN, ``cost`` the cost at infinity); ``"infeasible"`` (no
        estimate has every reprojection error below ``max_reprojection_error``);
        ``"numerical_failure"``; in batches, ``"interrupted"`` or ``"time_budget"`` (the batch was stopped
        by Ctrl-C, a failed ``progress`` callback or its ``time_budget``: see :func:`triangulate_lines`)."""
    @property
    def success(self) -> bool:
        """``status == "success"``."""
    @property
    def cost(self) -> float:
        """Eq. 19 at the estimate: the sum of squared whitened residuals (squared pixels without
        covariances)."""
    @property
    def lower_bound(self) -> float:
        """A lower bound on eq. 19 over every estimate in front of the cameras (0 when not computed)."""
    @property
    def relative_gap(self) -> float:
        """``(cost - lower_bound) / cost`` (1 when not computed, 0 when the cost is 0)."""
    @property
    def certified(self) -> bool:
        """The estimate is the global minimum within ``max_relative_gap``, backed by ``lower_bound``.
        True only with ``status == "success"``."""
    @property
    def certificate(self) -> str:
        """How optimality was established: ``"none"`` (methods linear and local),
        ``"convexity_test"`` (a sufficient condition at the local minimum, no branching) or
        ``"branch_and_bound"``."""
    @property
    def nodes(self) -> int:
        """Branch-and-bound nodes whose bound was computed (0 for the convexity test)."""
    @property
    def solver_iterations(self) -> int:
        """Interior-point iterations of the conic solver, summed over the nodes."""
    @property
    def iterations(self) -> int:
        """Accepted iterations of the local minimisation (0 for ``linear``)."""
    @property
    def termination(self) -> str:
        """Why the local minimisation stopped (see :attr:`PoseStage.termination`; ``"closed_form"``
        for ``linear``)."""
    @property
    def time_seconds(self) -> float:
        """Wall time of the call in the core, seconds (the Python boundary excluded)."""
    @property
    def residual_test(self) -> Optional["_ResidualTestDict"]:
        """The χ² test of :attr:`cost` against the given covariances (identity: 1 px):
        ``{"chi2", "dof", "p_value", "consistent"}`` with ``dof`` = whitened residuals (2 per view for
        points and lines, 5 for conics) minus parameters (3, 4, 9); ``consistent`` is ``p_value >=
        1e-3``. ``consistent == False`` says the observations disagree beyond their stated noise (an
        outlier, a wrong camera, lens distortion, a covariance too small). None when ``dof`` is 0 or
        there is no cost."""
    def to_dict(self) -> dict[str, Any]:
        """The fields above as a plain dict (strict JSON: NaN and inf are ``None``)."""
    def __repr__(self) -> str: ...

class PointTriangulation(TriangulationReport):
    """A triangulated point: :attr:`X` and the fields of :class:`TriangulationReport`. Immutable;
    ``X`` returns a fresh array."""

    @property
    def X(self) -> NDArray[np.float64]:
        """The point (3,), world coordinates (NaN when ``status == "at_infinity"``)."""
    @property
    def covariance(self) -> Optional[NDArray[np.float64]]:
        """First-order covariance (3, 3) of :attr:`X`, world units²: ``(JᵀJ)⁻¹`` with ``J`` the Jacobian
        of the whitened residuals of eq. 18 at ``X``, so the ``cov`` given carries the scale (without
        ``cov`` every view counts as 1 px isotropic noise); not rescaled by the cost. Computed for every
        method and status whenever ``X`` is finite (for ``linear``: evaluated at the linear point). None
        when ``X`` is not finite or ``JᵀJ`` is numerically singular (``‖H‖_F ‖H⁻¹‖_F > 1e12``: a point at
        or near infinity, parallax below about 1e-6 rad). First order: at low parallax it is large and
        right while the depth error stays a small fraction of the depth."""
    @property
    def method(self) -> str:
        """See :attr:`TriangulationReport.method`."""
    @property
    def status(self) -> str:
        """See :attr:`TriangulationReport.status`."""
    @property
    def success(self) -> bool:
        """See :attr:`TriangulationReport.success`."""
    @property
    def cost(self) -> float:
        """See :attr:`TriangulationReport.cost`."""
    @property
    def lower_bound(self) -> float:
        """See :attr:`TriangulationReport.lower_bound`."""
    @property
    def relative_gap(self) -> float:
        """See :attr:`TriangulationReport.relative_gap`."""
    @property
    def certified(self) -> bool:
        """See :attr:`TriangulationReport.certified`."""
    @property
    def certificate(self) -> str:
        """See :attr:`TriangulationReport.certificate`."""
    @property
    def nodes(self) -> int:
        """See :attr:`TriangulationReport.nodes`."""
    @property
    def solver_iterations(self) -> int:
        """See :attr:`TriangulationReport.solver_iterations`."""
    @property
    def iterations(self) -> int:
        """See :attr:`TriangulationReport.iterations`."""
    @property
    def termination(self) -> str:
        """See :attr:`TriangulationReport.termination`."""
    @property
    def time_seconds(self) -> float:
        """See :attr:`TriangulationReport.time_seconds`."""
    @property
    def residual_test(self) -> Optional["_ResidualTestDict"]:
        """See :attr:`TriangulationReport.residual_test`."""
    def to_dict(self) -> dict[str, Any]:
        """The report fields, ``"X"`` and ``"covariance"`` (nested lists or None) as a plain dict
        (strict JSON: NaN and inf are ``None``)."""
    def __repr__(self) -> str: ...

def triangulate_point(
    P: ArrayLike,
    x: ArrayLike,
    cov: Optional[ArrayLike] = None,
    method: str = "optimal",
    *,
    max_relative_gap: Optional[float] = None,
    max_reprojection_error: Optional[float] = None,
    max_nodes: Optional[int] = None,
) -> PointTriangulation:
    """Triangulate one point seen in two or more views (Josephson & Kahl 2008, sections 2.1, 3-4).

    Args:
        P: cameras (n, 3, 4), world → pixels, n >= 2.
        x: the point's pixels in each view (n, 2).
        cov: pixel covariances (n, 2, 2), symmetric positive definite; None for the identity.
        method: ``"optimal"`` (default), ``"local"`` or ``"linear"`` (see the section comment).
        max_relative_gap: branch and bound stops when ``(cost - lower_bound) / cost`` is at most this;
            None for the default 1e-3 (the paper stopped at 10 %).
        max_reprojection_error: the paper's γ (section 4.3): only points whose whitened reprojection
            error is at most γ in every view are searched. None (default) takes the square root of the
            local solution's cost, which every better point satisfies: the certificate then covers every
            point in front of the cameras.
        max_nodes: branch-and-bound node budget; None for the default 2000.

    Returns:
        A :class:`PointTriangulation`; a solve that runs but fails says so in ``status``.

    Raises:
        ShapeError (shapes, or row counts that differ from P's), NonFiniteError, TooFewCorrespondencesError
        (fewer than 2 views), SingularCameraError (a camera whose left 3x3 block is singular),
        DegenerateConfigurationError (a covariance that is not positive definite, all camera centres
        equal), InvalidOptionError (unknown method, out-of-range option); TypeError for an unknown
        keyword or an argument that is not numeric.

    The GIL is released while the core runs.
    """

class BatchReport:
    """The per-track report columns of a batch of points, lines or quadrics (the base class of
    :class:`PointTriangulations`, :class:`LineTriangulations` and :class:`QuadricTriangulations`): one
    entry per track in every array (fresh copies). Tracks the core rejected have a ``status`` naming
    the problem, NaN estimates and cost, and a message in :attr:`messages`."""

    @property
    def cost(self) -> NDArray[np.float64]:
        """Eq. 19 at each estimate (n,) (NaN for a rejected track)."""
    @property
    def lower_bound(self) -> NDArray[np.float64]:
        """Lower bounds on eq. 19 (n,) (0 when not computed)."""
    @property
    def relative_gap(self) -> NDArray[np.float64]:
        """``(cost - lower_bound) / max(cost, 1e-12)`` (n,) (1 when not computed)."""
    @property
    def certified(self) -> NDArray[np.bool_]:
        """Global optimality certified within ``max_relative_gap`` (n,)."""
    @property
    def certificate(self) -> NDArray[np.str_]:
        """``"none"``, ``"convexity_test"`` or ``"branch_and_bound"`` per track (n,)."""
    @property
    def status(self) -> NDArray[np.str_]:
        """Per track (n,): a :attr:`TriangulationReport.status`, or for a track the core rejected
        ``"too_few_views"`` (fewer visible views than the primitive needs), ``"non_finite"`` (NaN/inf
        in a visible observation, covariance or per-track camera), ``"degenerate"`` (a zero-length
        segment, a line at infinity, a conic that is not an ellipse, a covariance that is not positive
        definite, all visible camera centres equal, a line in an epipolar plane of its views),
        ``"singular_camera"``, ``"invalid_input"``."""
    @property
    def nodes(self) -> NDArray[np.int64]:
        """Branch-and-bound nodes per track (n,)."""
    @property
    def iterations(self) -> NDArray[np.int64]:
        """Local-minimisation iterations per track (n,)."""
    @property
    def time_seconds(self) -> NDArray[np.float64]:
        """Core time per track (n,), seconds, on one thread (0 for a rejected track)."""
    @property
    def p_value(self) -> NDArray[np.float64]:
        """Per track (n,): the ``p_value`` of :attr:`TriangulationReport.residual_test`, NaN where
        there is none (rejected tracks included)."""
    @property
    def messages(self) -> list[str]:
        """Per track: ``""``, or why the core rejected it, naming the track and the view
        (``"track 3: degenerate configuration: lines[3][1] has zero length"``)."""
    @property
    def method(self) -> str:
        """The method that ran."""
    def __len__(self) -> int: ...
    def to_dict(self) -> dict[str, Any]:
        """Plain-Python, strict-JSON form: ``method`` and every per-track column as a list (``status``,
        ``cost``, ``lower_bound``, ``relative_gap``, ``certified``, ``certificate``, ``nodes``,
        ``iterations``, ``time_seconds``, ``messages``); NaN and inf are ``None``."""
    def __repr__(self) -> str: ...

class PointTriangulations(BatchReport):
    """The results of :func:`triangulate_points`: the columns of :class:`BatchReport` and each track's
    point, one entry per track in every array (fresh copies). Tracks the core rejected have a
    ``status`` naming the problem, NaN in ``X`` and ``cost``, and a message in :attr:`messages`."""

    @property
    def X(self) -> NDArray[np.float64]:
        """Points (n, 3), world coordinates (NaN where there is no estimate)."""
    @property
    def covariance(self) -> NDArray[np.float64]:
        """Covariances (n, 3, 3) of the points, world units² (see :attr:`PointTriangulation.covariance`);
        NaN where there is no point or no covariance."""
    @property
    def cost(self) -> NDArray[np.float64]:
        """Eq. 19 at each point (n,)."""
    @property
    def lower_bound(self) -> NDArray[np.float64]:
        """Lower bounds on eq. 19 (n,) (0 when not computed)."""
    @property
    def relative_gap(self) -> NDArray[np.float64]:
        """``(cost - lower_bound) / cost`` (n,)."""
    @property
    def certified(self) -> NDArray[np.bool_]:
        """Global optimality certified within ``max_relative_gap`` (n,)."""
    @property
    def certificate(self) -> NDArray[np.str_]:
        """``"none"``, ``"convexity_test"`` or ``"branch_and_bound"`` per track (n,)."""
    @property
    def status(self) -> NDArray[np.str_]:
        """Per track (n,): a :attr:`TriangulationReport.status`, or for a track the core rejected
        ``"too_few_views"`` (fewer than 2 visible views), ``"non_finite"`` (NaN/inf in a visible
        observation or covariance), ``"degenerate"`` (a covariance that is not positive definite, all
        visible camera centres equal), ``"singular_camera"``, ``"invalid_input"``."""
    @property
    def nodes(self) -> NDArray[np.int64]:
        """Branch-and-bound nodes per track (n,)."""
    @property
    def iterations(self) -> NDArray[np.int64]:
        """Local-minimisation iterations per track (n,)."""
    @property
    def time_seconds(self) -> NDArray[np.float64]:
        """Core time per track (n,), seconds, on one thread. Method ``linear`` runs an allocation-free
        path that does not time tracks one by one: every track gets the batch's core time over ``n``."""
    @property
    def p_value(self) -> NDArray[np.float64]:
        """See :attr:`BatchReport.p_value`."""
    @property
    def messages(self) -> list[str]:
        """Per track: ``""``, or why the core rejected it, naming the track and its view as a row
        (``"track 3: x[3]: non-finite value (NaN or inf) in row 1"``)."""
    @property
    def method(self) -> str:
        """The method that ran."""
    def __len__(self) -> int: ...
    def to_dict(self) -> dict[str, Any]:
        """Plain-Python, strict-JSON form: ``method`` and every per-track column as a list (``status``,
        ``cost``, ``lower_bound``, ``relative_gap``, ``certified``, ``certificate``, ``nodes``,
        ``iterations``, ``time_seconds``, ``messages``) and ``X``, ``covariance``; NaN and inf are ``None``."""
    def __repr__(self) -> str: ...

def triangulate_points(
    P: ArrayLike,
    x: ArrayLike,
    visible: Optional[ArrayLike] = None,
    cov: Optional[ArrayLike] = None,
    method: str = "optimal",
    *,
    max_relative_gap: Optional[float] = None,
    max_reprojection_error: Optional[float] = None,
    max_nodes: Optional[int] = None,
    progress: Optional[Callable[[int], Any]] = None,
    time_budget: Optional[float] = None,
) -> PointTriangulations:
    """Triangulate many points (tracks) seen by the same cameras, in parallel with the GIL released.

    Each track is :func:`triangulate_point` on its visible views. One bad track (NaN in a visible view,
    fewer than 2 visible views, a covariance that is not positive definite) gets a ``status`` and a
    message and never stops the others.

    Args:
        P: cameras (v, 3, 4), world → pixels, v >= 2.
        x: pixels (n, v, 2); entries of views a track is not seen in are ignored (NaN is fine there).
        visible: (n, v) booleans, True where the track is seen, or integers 0/1 (any other integer,
            e.g. -1, is an InvalidOptionError); None: every view.
        cov: pixel covariances (n, v, 2, 2); None for the identity.
        method, max_relative_gap, max_reprojection_error, max_nodes: as for :func:`triangulate_point`.
        progress, time_budget: as for :func:`triangulate_lines` (Ctrl-C too). ``linear`` and ``local``
            batches of at most 4096 observations (tracks x views) without either run on the calling
            thread and see Ctrl-C only when they end (they take milliseconds).

    Raises (for the whole call, before any track is solved): ShapeError, NonFiniteError or
    SingularCameraError for ``P``, TooFewCorrespondencesError (fewer than 2 cameras), InvalidOptionError;
    TypeError for an unknown keyword or a ``visible`` that is neither boolean nor integer.
    """

class LineTriangulation(TriangulationReport):
    """A triangulated 3-D line: Plücker coordinates, a point and a unit direction, and the fields of
    :class:`TriangulationReport` (its ``cost`` in whitened units of the line residual). Immutable; arrays
    are fresh copies."""

    @property
    def plucker(self) -> NDArray[np.float64]:
        """Plücker coordinates (6,) ``(l12, l13, l14, l23, l42, l34)`` of eq. 3, world frame, unit norm,
        satisfying eq. 4. For two points ``A``, ``B`` of the line: direction ``(l14, -l42, l34) ∝ A - B``,
        moment ``(-l23, l13, -l12) = p × d``."""
    @property
    def point(self) -> NDArray[np.float64]:
        """The point (3,) of the line closest to the world origin."""
    @property
    def direction(self) -> NDArray[np.float64]:
        """Unit direction (3,) of the line, world frame."""
    @property
    def chart_axes(self) -> NDArray[np.float64]:
        """The axes ``e1``, ``e2`` (2, 3) of the chart of :attr:`covariance`: ``e1 = d × a / ‖d × a‖``
        with ``d`` = :attr:`direction` and ``a = (1, 0, 0)`` when ``|d[0]| < 0.9``, else ``(0, 1, 0)``;
        ``e2 = d × e1`` (``(e1, e2, d)`` right-handed orthonormal)."""
    @property
    def covariance(self) -> Optional[NDArray[np.float64]]:
        """First-order covariance (4, 4) of the line in the chart ``(a1, a2, t1, t2)`` at the estimate:
        the line through ``point + t1 e1 + t2 e2`` with direction ``direction + a1 e1 + a2 e2``
        (:attr:`chart_axes`). ``t`` (world units) is where the line crosses the plane through
        :attr:`point` normal to :attr:`direction`; ``a`` (dimensionless, radians to first order) tilts
        the direction towards ``e1``, ``e2``. ``(JᵀJ)⁻¹`` with ``J`` the Jacobian of the whitened
        residuals of eq. 18, so the covariances given (``cov``, or from ``sigma`` for segments) carry
        the scale; homogeneous lines without ``cov`` count as unit residual covariance (1 px offset,
        1/1000 rad angle). Computed for every method and status; None when ``JᵀJ`` is numerically
        singular (a line nearly in an epipolar plane of every pair of views). See
        :meth:`plucker_covariance` and :meth:`point_direction_covariance`."""
    def plucker_covariance(self) -> Optional[NDArray[np.float64]]:
        """Covariance (6, 6), rank 4, of the unit Plücker coordinates :attr:`plucker` (first order, from
        :attr:`covariance`); None when :attr:`covariance` is None."""
    def point_direction_covariance(self) -> Optional[NDArray[np.float64]]:
        """Covariance (6, 6), rank 4, of ``(point, direction)`` stacked (world units, then unit
        direction; first order, from :attr:`covariance`); None when :attr:`covariance` is None."""
    @property
    def method(self) -> str:
        """See :attr:`TriangulationReport.method`."""
    @property
    def status(self) -> str:
        """See :attr:`TriangulationReport.status` (never ``"behind_camera"`` for lines)."""
    @property
    def success(self) -> bool:
        """See :attr:`TriangulationReport.success`."""
    @property
    def cost(self) -> float:
        """See :attr:`TriangulationReport.cost`."""
    @property
    def lower_bound(self) -> float:
        """See :attr:`TriangulationReport.lower_bound`."""
    @property
    def relative_gap(self) -> float:
        """See :attr:`TriangulationReport.relative_gap`."""
    @property
    def certified(self) -> bool:
        """See :attr:`TriangulationReport.certified`."""
    @property
    def certificate(self) -> str:
        """See :attr:`TriangulationReport.certificate`."""
    @property
    def nodes(self) -> int:
        """See :attr:`TriangulationReport.nodes`."""
    @property
    def solver_iterations(self) -> int:
        """See :attr:`TriangulationReport.solver_iterations`."""
    @property
    def iterations(self) -> int:
        """See :attr:`TriangulationReport.iterations`."""
    @property
    def termination(self) -> str:
        """See :attr:`TriangulationReport.termination`."""
    @property
    def time_seconds(self) -> float:
        """See :attr:`TriangulationReport.time_seconds`."""
    @property
    def residual_test(self) -> Optional["_ResidualTestDict"]:
        """See :attr:`TriangulationReport.residual_test`."""
    def to_dict(self) -> dict[str, Any]:
        """The report fields, ``"plucker"``, ``"point"``, ``"direction"``, ``"chart_axes"`` and
        ``"covariance"`` (None when there is none) as a plain dict."""
    def __repr__(self) -> str: ...

def triangulate_line(
    P: ArrayLike,
    lines: ArrayLike,
    cov: Optional[ArrayLike] = None,
    method: str = "optimal",
    *,
    sigma: Optional[float] = None,
    max_relative_gap: Optional[float] = None,
    max_reprojection_error: Optional[float] = None,
    max_nodes: Optional[int] = None,
) -> LineTriangulation:
    """Triangulate one 3-D line seen in two or more views (Josephson & Kahl 2008, sections 2.2, 3-4).

    The cost is eq. 19 over the residuals of section 3.1: each observed image line is normalised (unit
    normal, put 1000 px from a shifted origin) and the residual of a candidate line is 2 numbers in pixels;
    the 3-D line stays on the Plücker quadric (eq. 4) throughout.

    Args:
        P: cameras (n, 3, 4), world → pixels, n >= 2.
        lines: the observed lines, either (n, 3) homogeneous image lines ``l`` with ``l · (u, v, 1) = 0``
            (any scale and sign), or (n, 2, 2) image segments (two pixel endpoints each): then each view's
            line is the one through the endpoints and, unless ``cov`` is given, its covariance is that of
            endpoints with i.i.d. Gaussian noise of ``sigma`` px per coordinate (:func:`fit_line` on two points).
        cov: residual covariances (n, 2, 2), e.g. :attr:`FittedLine.covariance`; None: the identity for
            homogeneous lines, the endpoint model for segments.
        method: ``"optimal"`` (default), ``"local"`` or ``"linear"``.
        sigma: endpoint noise for segments, pixels; None means 1. An error with homogeneous lines or
            together with ``cov``.
        max_relative_gap, max_reprojection_error, max_nodes: as for :func:`triangulate_point`.

    Raises:
        ShapeError, NonFiniteError, TooFewCorrespondencesError, SingularCameraError,
        DegenerateConfigurationError (a line with zero normal, a zero-length segment, a covariance that is
        not positive definite, all camera centres equal, a 3-D line in an epipolar plane of every view pair),
        InvalidOptionError; TypeError for an unknown keyword.

    The GIL is released while the core runs.
    """

class QuadricTriangulation(TriangulationReport):
    """A triangulated ellipsoid (possibly flat: a disc): its dual and primal quadric, centre, axes and
    semi-axes, and the fields of :class:`TriangulationReport` (its ``cost`` in whitened units of the conic
    residual). Immutable; arrays are fresh copies."""

    @property
    def Q(self) -> NDArray[np.float64]:
        """The dual quadric (4, 4) ``L`` of eq. 10, world frame, ``U^T L U = 0`` for tangent planes ``U``,
        normalised so that ``L[3, 3] = -1``: ``L = H diag(s1², s2², s3², -1) H^T`` with ``H = [axes centre;
        0 1]``."""
    @property
    def primal(self) -> Optional[NDArray[np.float64]]:
        """The point quadric (4, 4) ``C = L^-1`` of eq. 9 (``X^T C X = 0``), None for a flat ellipsoid."""
    @property
    def centre(self) -> NDArray[np.float64]:
        """Centre (3,), world units."""
    @property
    def axes(self) -> NDArray[np.float64]:
        """Unit axes (3, 3) as columns, in the order of :attr:`semi_axes`."""
    @property
    def semi_axes(self) -> NDArray[np.float64]:
        """Semi-axis lengths (3,), decreasing, world units; a 0 is a flat ellipsoid."""
    @property
    def covariance(self) -> Optional[NDArray[np.float64]]:
        """First-order covariance (9, 9) of the ellipsoid in the chart ``(c1, c2, c3, S11, S12, S13, S22,
        S23, S33)``: the centre (world units) and the upper triangle of the shape matrix
        ``S = axes diag(semi_axes²) axes^T`` (world units²), so that ``Q = [S - c c^T, -c; -c^T, -1]``
        (an off-diagonal ``S_ij`` moves ``S_ij`` and ``S_ji``). A chart of the 9 dof of a real ellipsoid
        that stays regular for spheres and flat ellipsoids. ``(JᵀJ)⁻¹`` with ``J`` the Jacobian of the
        whitened residuals of eq. 18, so ``cov`` carries the scale (without it each conic residual
        entry counts as unit variance: give ``cov``, e.g. from :func:`fit_conic`). Computed for every
        method and status with a finite estimate; None when ``JᵀJ`` is numerically singular. For a
        flat estimate it ignores the constraint ``S ⪰ 0`` (the estimate is on that boundary)."""
    @property
    def method(self) -> str:
        """See :attr:`TriangulationReport.method`."""
    @property
    def status(self) -> str:
        """See :attr:`TriangulationReport.status` (``"behind_camera"`` when the ellipsoid's centre is behind
        a camera or it crosses a camera's principal plane)."""
    @property
    def success(self) -> bool:
        """See :attr:`TriangulationReport.success`."""
    @property
    def cost(self) -> float:
        """See :attr:`TriangulationReport.cost`."""
    @property
    def lower_bound(self) -> float:
        """See :attr:`TriangulationReport.lower_bound`."""
    @property
    def relative_gap(self) -> float:
        """See :attr:`TriangulationReport.relative_gap`."""
    @property
    def certified(self) -> bool:
        """See :attr:`TriangulationReport.certified`."""
    @property
    def certificate(self) -> str:
        """See :attr:`TriangulationReport.certificate`."""
    @property
    def nodes(self) -> int:
        """See :attr:`TriangulationReport.nodes`."""
    @property
    def solver_iterations(self) -> int:
        """See :attr:`TriangulationReport.solver_iterations`."""
    @property
    def iterations(self) -> int:
        """See :attr:`TriangulationReport.iterations`."""
    @property
    def termination(self) -> str:
        """See :attr:`TriangulationReport.termination`."""
    @property
    def time_seconds(self) -> float:
        """See :attr:`TriangulationReport.time_seconds`."""
    @property
    def residual_test(self) -> Optional["_ResidualTestDict"]:
        """See :attr:`TriangulationReport.residual_test`."""
    def to_dict(self) -> dict[str, Any]:
        """The report fields, ``"Q"``, ``"primal"`` (None when flat), ``"centre"``, ``"axes"``,
        ``"semi_axes"`` and ``"covariance"`` (None when there is none) as a plain dict."""
    def __repr__(self) -> str: ...

def triangulate_quadric(
    P: ArrayLike,
    conics: ArrayLike,
    cov: Optional[ArrayLike] = None,
    method: str = "optimal",
    *,
    max_relative_gap: Optional[float] = None,
    max_reprojection_error: Optional[float] = None,
    max_nodes: Optional[int] = None,
) -> QuadricTriangulation:
    """Triangulate an ellipsoid from its outline conics in three or more views (Josephson & Kahl 2008,
    sections 2.3, 3-4; the conic camera of Lemma 2.1).

    The cost is eq. 19 over the 5-entry conic residuals of section 3.1; without ``cov`` the shape entries
    (pixels²) dominate, so pass the covariances of :func:`fit_conic`. ``linear`` is made a proper
    (possibly flat) ellipsoid; ``local`` keeps every iterate one.

    Args:
        P: cameras (n, 3, 4), world → pixels, n >= 3 (two views leave a family of quadrics).
        conics: the observed point conics (n, 3, 3) of eq. 8 (``x^T c x = 0``, homogeneous pixels, any
            scale and sign), each a real ellipse, e.g. :attr:`FittedConic.conic`.
        cov: residual covariances (n, 5, 5), e.g. :attr:`FittedConic.covariance`; None for the identity.
        method: ``"optimal"`` (default), ``"local"`` or ``"linear"``.
        max_relative_gap, max_reprojection_error, max_nodes: as for :func:`triangulate_point`.

    Raises:
        ShapeError, NonFiniteError, TooFewCorrespondencesError (fewer than 3 views), SingularCameraError,
        DegenerateConfigurationError (a conic that is not a real ellipse, a covariance that is not positive
        definite, all camera centres equal), InvalidOptionError; TypeError for an unknown keyword.

    The GIL is released while the core runs.
    """

# --- Batches of lines and quadrics ---------------------------------------------------------------

class LineTriangulations(BatchReport):
    """The results of :func:`triangulate_lines`: the columns of :class:`BatchReport` and each track's
    line (NaN for a rejected track), as :class:`LineTriangulation` gives them."""

    @property
    def plucker(self) -> NDArray[np.float64]:
        """Plücker coordinates (n, 6) of eq. 3, world frame, unit norm (see :attr:`LineTriangulation.plucker`)."""
    @property
    def point(self) -> NDArray[np.float64]:
        """The point of each line closest to the world origin (n, 3)."""
    @property
    def direction(self) -> NDArray[np.float64]:
        """Unit directions (n, 3), world frame."""
    @property
    def chart_axes(self) -> NDArray[np.float64]:
        """Chart axes (n, 2, 3) of each covariance (see :attr:`LineTriangulation.chart_axes`)."""
    @property
    def covariance(self) -> NDArray[np.float64]:
        """Covariances (n, 4, 4) in each line's chart (see :attr:`LineTriangulation.covariance`); NaN
        where there is no line or no covariance."""
    @property
    def cost(self) -> NDArray[np.float64]:
        """Eq. 19 at each estimate (n,) (NaN for a rejected track)."""
    @property
    def lower_bound(self) -> NDArray[np.float64]:
        """Lower bounds on eq. 19 (n,) (0 when not computed)."""
    @property
    def relative_gap(self) -> NDArray[np.float64]:
        """``(cost - lower_bound) / max(cost, 1e-12)`` (n,) (1 when not computed)."""
    @property
    def certified(self) -> NDArray[np.bool_]:
        """Global optimality certified within ``max_relative_gap`` (n,)."""
    @property
    def certificate(self) -> NDArray[np.str_]:
        """``"none"``, ``"convexity_test"`` or ``"branch_and_bound"`` per track (n,)."""
    @property
    def status(self) -> NDArray[np.str_]:
        """Per track (n,): a :attr:`TriangulationReport.status`, or for a track the core rejected
        ``"too_few_views"`` (fewer visible views than the primitive needs), ``"non_finite"`` (NaN/inf
        in a visible observation, covariance or per-track camera), ``"degenerate"`` (a zero-length
        segment, a line at infinity, a conic that is not an ellipse, a covariance that is not positive
        definite, all visible camera centres equal, a line in an epipolar plane of its views),
        ``"singular_camera"``, ``"invalid_input"``."""
    @property
    def nodes(self) -> NDArray[np.int64]:
        """Branch-and-bound nodes per track (n,)."""
    @property
    def iterations(self) -> NDArray[np.int64]:
        """Local-minimisation iterations per track (n,)."""
    @property
    def time_seconds(self) -> NDArray[np.float64]:
        """Core time per track (n,), seconds, on one thread (0 for a rejected track)."""
    @property
    def p_value(self) -> NDArray[np.float64]:
        """See :attr:`BatchReport.p_value`."""
    @property
    def messages(self) -> list[str]:
        """Per track: ``""``, or why the core rejected it, naming the track and the view
        (``"track 3: degenerate configuration: lines[3][1] has zero length"``)."""
    @property
    def method(self) -> str:
        """The method that ran."""
    def __len__(self) -> int: ...
    def to_dict(self) -> dict[str, Any]:
        """Plain-Python, strict-JSON form: ``method`` and every per-track column as a list (``status``,
        ``cost``, ``lower_bound``, ``relative_gap``, ``certified``, ``certificate``, ``nodes``,
        ``iterations``, ``time_seconds``, ``messages``) and ``plucker``, ``point``, ``direction``, ``chart_axes``, ``covariance``; NaN and inf are ``None``."""
    def __repr__(self) -> str: ...

def triangulate_lines(
    P: ArrayLike,
    lines: ArrayLike,
    visible: Optional[ArrayLike] = None,
    cov: Optional[ArrayLike] = None,
    method: str = "optimal",
    *,
    sigma: Optional[float] = None,
    max_relative_gap: Optional[float] = None,
    max_reprojection_error: Optional[float] = None,
    max_nodes: Optional[int] = None,
    progress: Optional[Callable[[int], Any]] = None,
    time_budget: Optional[float] = None,
) -> LineTriangulations:
    """Triangulate many 3-D lines (tracks) in parallel with the GIL released (Josephson & Kahl 2008,
    sections 2.2, 3-4).

    Each track is :func:`triangulate_line` on its visible views (the same numbers, but for
    ``time_seconds``). One bad track (NaN in a visible view, fewer than 2 visible views, a zero-length
    segment, a covariance that is not positive definite, ...) gets a ``status`` and a message and never
    stops the others.

    Args:
        P: cameras (v, 3, 4) seen by every track, or (n, v, 3, 4), one set per track; world → pixels.
        lines: (n, v, 3) homogeneous image lines, or (n, v, 2, 2) image segments (two pixel endpoints),
            as for :func:`triangulate_line`; entries of views a track is not seen in are ignored (NaN is
            fine there).
        visible: (n, v) booleans, True where the track is seen, or integers 0/1 (any other integer,
            e.g. -1, is an InvalidOptionError); None: every view.
        cov: residual covariances (n, v, 2, 2); None: the identity for homogeneous lines, the endpoint
            model (``sigma``) for segments.
        method, sigma, max_relative_gap, max_reprojection_error, max_nodes: as for :func:`triangulate_line`.
        progress: called from the calling thread with the number of finished tracks, about twenty times
            a second while it changes and once at the end.
        time_budget: seconds (finite, >= 0) after which the batch stops; None (default): no limit.

    Stopping: the batch runs on a worker thread while the calling thread checks for Ctrl-C every 0.05 s.
    Ctrl-C, or an exception raised by ``progress``, stops the batch within about 0.1 s: tracks being
    solved stop at their next branch-and-bound node and keep the estimate and ``lower_bound`` reached
    (uncertified), with status ``"interrupted"``; tracks not yet started get status ``"interrupted"``,
    NaN estimates and the message ``"not solved: interrupted"``. Finished tracks keep their results.
    The exception (``KeyboardInterrupt`` or the callback's) is then raised with these results attached
    as its attribute ``partial``. A ``time_budget`` that runs out does the same with status
    ``"time_budget"``, and the call returns normally.

    Raises (for the whole call, before any track is solved): ShapeError (shapes, or counts of views
    or tracks that differ from P's), NonFiniteError or SingularCameraError for shared cameras,
    TooFewCorrespondencesError (fewer than 2 cameras per track), InvalidOptionError (options, ``sigma``
    with homogeneous lines or with ``cov``); TypeError for an unknown keyword or a ``visible`` that is
    not boolean.
    """

class QuadricTriangulations(BatchReport):
    """The results of :func:`triangulate_quadrics`: the columns of :class:`BatchReport` and each track's
    ellipsoid (NaN for a rejected track), as :class:`QuadricTriangulation` gives them."""

    @property
    def Q(self) -> NDArray[np.float64]:
        """Dual quadrics (n, 4, 4) of eq. 10, ``L[3, 3] = -1`` (see :attr:`QuadricTriangulation.Q`)."""
    @property
    def primal(self) -> NDArray[np.float64]:
        """Point quadrics (n, 4, 4) ``C = L^-1`` of eq. 9; NaN for a flat ellipsoid."""
    @property
    def centre(self) -> NDArray[np.float64]:
        """Centres (n, 3), world units."""
    @property
    def axes(self) -> NDArray[np.float64]:
        """Unit axes (n, 3, 3) as columns, in the order of :attr:`semi_axes`."""
    @property
    def semi_axes(self) -> NDArray[np.float64]:
        """Semi-axis lengths (n, 3), decreasing, world units."""
    @property
    def covariance(self) -> NDArray[np.float64]:
        """Covariances (n, 9, 9) in the centre/shape chart (see :attr:`QuadricTriangulation.covariance`);
        NaN where there is no ellipsoid or no covariance."""
    @property
    def cost(self) -> NDArray[np.float64]:
        """Eq. 19 at each estimate (n,) (NaN for a rejected track)."""
    @property
    def lower_bound(self) -> NDArray[np.float64]:
        """Lower bounds on eq. 19 (n,) (0 when not computed)."""
    @property
    def relative_gap(self) -> NDArray[np.float64]:
        """``(cost - lower_bound) / max(cost, 1e-12)`` (n,) (1 when not computed)."""
    @property
    def certified(self) -> NDArray[np.bool_]:
        """Global optimality certified within ``max_relative_gap`` (n,)."""
    @property
    def certificate(self) -> NDArray[np.str_]:
        """``"none"``, ``"convexity_test"`` or ``"branch_and_bound"`` per track (n,)."""
    @property
    def status(self) -> NDArray[np.str_]:
        """Per track (n,): a :attr:`TriangulationReport.status`, or for a track the core rejected
        ``"too_few_views"`` (fewer visible views than the primitive needs), ``"non_finite"`` (NaN/inf
        in a visible observation, covariance or per-track camera), ``"degenerate"`` (a zero-length
        segment, a line at infinity, a conic that is not an ellipse, a covariance that is not positive
        definite, all visible camera centres equal, a line in an epipolar plane of its views),
        ``"singular_camera"``, ``"invalid_input"``."""
    @property
    def nodes(self) -> NDArray[np.int64]:
        """Branch-and-bound nodes per track (n,)."""
    @property
    def iterations(self) -> NDArray[np.int64]:
        """Local-minimisation iterations per track (n,)."""
    @property
    def time_seconds(self) -> NDArray[np.float64]:
        """Core time per track (n,), seconds, on one thread (0 for a rejected track)."""
    @property
    def p_value(self) -> NDArray[np.float64]:
        """See :attr:`BatchReport.p_value`."""
    @property
    def messages(self) -> list[str]:
        """Per track: ``""``, or why the core rejected it, naming the track and the view
        (``"track 3: degenerate configuration: lines[3][1] has zero length"``)."""
    @property
    def method(self) -> str:
        """The method that ran."""
    def __len__(self) -> int: ...
    def to_dict(self) -> dict[str, Any]:
        """Plain-Python, strict-JSON form: ``method`` and every per-track column as a list (``status``,
        ``cost``, ``lower_bound``, ``relative_gap``, ``certified``, ``certificate``, ``nodes``,
        ``iterations``, ``time_seconds``, ``messages``) and ``Q``, ``primal``, ``centre``, ``axes``, ``semi_axes``, ``covariance``; NaN and inf are ``None``."""
    def __repr__(self) -> str: ...

def triangulate_quadrics(
    P: ArrayLike,
    conics: ArrayLike,
    visible: Optional[ArrayLike] = None,
    cov: Optional[ArrayLike] = None,
    method: str = "optimal",
    *,
    max_relative_gap: Optional[float] = None,
    max_reprojection_error: Optional[float] = None,
    max_nodes: Optional[int] = None,
    progress: Optional[Callable[[int], Any]] = None,
    time_budget: Optional[float] = None,
) -> QuadricTriangulations:
    """Triangulate many ellipsoids (tracks) from their outline conics in parallel with the GIL released
    (Josephson & Kahl 2008, sections 2.3, 3-4).

    Each track is :func:`triangulate_quadric` on its visible views (the same numbers, but for
    ``time_seconds``). One bad track (NaN in a visible view, fewer than 3 visible views, a conic that is
    not a real ellipse, a covariance that is not positive definite) gets a ``status`` and a message and
    never stops the others.

    Args:
        P: cameras (v, 3, 4) seen by every track, or (n, v, 3, 4), one set per track (e.g. independent
            scenes solved together); world → pixels.
        conics: point conics (n, v, 3, 3) of eq. 8; entries of views a track is not seen in are ignored.
        visible: (n, v) booleans, True where the track is seen, or integers 0/1 (any other integer,
            e.g. -1, is an InvalidOptionError); None: every view.
        cov: residual covariances (n, v, 5, 5), e.g. :attr:`FittedConic.covariance`; None for the identity.
        method, max_relative_gap, max_reprojection_error, max_nodes: as for :func:`triangulate_quadric`.
        progress, time_budget: as for :func:`triangulate_lines`, which also says how Ctrl-C stops the batch.

    Raises (for the whole call): ShapeError, NonFiniteError or SingularCameraError for shared cameras,
    TooFewCorrespondencesError (fewer than 3 cameras per track), InvalidOptionError; TypeError for an
    unknown keyword or a ``visible`` that is not boolean.
    """

# --- Fitting image primitives (section 3.1) -------------------------------------------------------

class FittedLine:
    """An image line fitted to points by :func:`fit_line`. Immutable; arrays are fresh copies."""

    @property
    def line(self) -> NDArray[np.float64]:
        """Homogeneous line (3,) ``(a, b, c)`` with ``a u + b v + c = 0`` in pixels, ``a² + b² = 1`` and
        ``c <= 0``."""
    @property
    def covariance(self) -> NDArray[np.float64]:
        """(2, 2) covariance of the line's residual (pixels², section 3.1 normalisation): the ``cov``
        row :func:`triangulate_line` takes for this view."""
    @property
    def rms_distance(self) -> float:
        """Root-mean-square distance of the points from the line, pixels."""
    def to_dict(self) -> dict[str, Any]:
        """Plain-Python (strict JSON: NaN and inf are ``None``) form."""
    def __repr__(self) -> str: ...

class FittedConic:
    """An ellipse fitted to points by :func:`fit_conic`. Immutable; arrays are fresh copies."""

    @property
    def conic(self) -> NDArray[np.float64]:
        """The point conic (3, 3) ``c`` of eq. 8, ``x^T c x = 0`` for homogeneous pixels, unit Frobenius
        norm."""
    @property
    def centre(self) -> NDArray[np.float64]:
        """Centre (2,), pixels."""
    @property
    def axes(self) -> NDArray[np.float64]:
        """Orthonormal axes (2, 2) as columns, in the order of :attr:`semi_axes`."""
    @property
    def semi_axes(self) -> NDArray[np.float64]:
        """Semi-axis lengths (2,), pixels, decreasing."""
    @property
    def covariance(self) -> NDArray[np.float64]:
        """(5, 5) covariance of the conic's 5-entry residual (section 3.1 normalisation): the ``cov``
        row :func:`triangulate_quadric` takes for this view."""
    @property
    def iterations(self) -> int:
        """Reweighting iterations of the fit."""
    def to_dict(self) -> dict[str, Any]:
        """Plain-Python (strict JSON: NaN and inf are ``None``) form."""
    def __repr__(self) -> str: ...

def fit_line(points: ArrayLike, sigma: float = 1.0) -> FittedLine:
    """Fit an image line to points (N, 2), N >= 2, by total least squares, with the first-order
    covariance of its residual for i.i.d. Gaussian pixel noise of ``sigma`` px per coordinate.

    Raises TooFewCorrespondencesError (N < 2), NonFiniteError, DegenerateConfigurationError (all
    points coincide to the rounding of their coordinates), InvalidOptionError (``sigma <= 0``, or a
    ``sigma`` for which the covariance ``σ² Σ₁`` overflows or underflows), ShapeError.
    """

def fit_conic(points: ArrayLike, sigma: float = 1.0) -> FittedConic:
    """Fit an ellipse to points (N, 2), N >= 5 (Sampson's reweighted algebraic fit, at the KCR bound),
    with the first-order covariance of its residual for i.i.d. Gaussian pixel noise of ``sigma`` px.

    Raises TooFewCorrespondencesError (N < 5), NonFiniteError, DegenerateConfigurationError (no
    ellipse is determined: the points lie on a line to within the noise — the χ² of their distances
    from the best line, ``Σ d²/σ²``, is below its 99.9 % quantile with N − 2 degrees of freedom — or no
    real ellipse fits, e.g. a hyperbola), InvalidOptionError (``sigma <= 0``), ShapeError.
    The GIL is released during the fit.
    """

class _ResidualSamples(TypedDict):
    line: NDArray[np.float64]
    line_whitened: NDArray[np.float64]
    conic: NDArray[np.float64]
    conic_whitened: NDArray[np.float64]

def fitting_residual_samples(draws: int, size: float = 1000.0, sigma: float = 1.0, seed: int = 0) -> _ResidualSamples:
    """The data of the paper's Figures 1-2 (section 3.1): ``draws`` random ``size`` x ``size`` images, each
    with a line sampled at 21 points and an ellipse sampled at 63, Gaussian noise of ``sigma`` px on every
    point, both refitted (:func:`fit_line`, :func:`fit_conic`). Returns the residuals of the true primitives
    in the frames of the fitted ones: ``line`` (draws, 2) and ``conic`` (draws, 5), and the same whitened by
    the predicted covariances (standard normal to first order). Seeded; the paper used 100,000 draws,
    size 1000, sigma 1; at most 10,000,000 draws (``InvalidOptionError`` beyond). The GIL is released.
    """
