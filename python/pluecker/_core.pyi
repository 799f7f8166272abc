"""Typed stubs of ``pluecker._core`` (Rust, PyO3). Conventions: the README's "Conventions" section.

Arrays: any real array-like in (float64), fresh row-major arrays out; ``None`` is zero rows. Each
property is declared once in Rust; its block here is generated (``python -m pluecker._stubgen``,
checked by tests/test_stubs.py). Results are immutable, ``to_dict()`` is strict JSON, pickles are
exact within one version. Options are mutable, ``==``, picklable, checked as set; their defaults are
the Rust ``Default``. A bool is not a number; counts and seeds take integers up to ``2**64 - 1``.
"""

from typing import Any, Callable, ClassVar, Dict, Iterator, List, Optional, Sequence, Tuple, TypedDict, Union, final

import numpy as np
from numpy.typing import ArrayLike, NDArray

__version__: str
"""The package version (the Rust crates' version)."""

METHODS: Tuple[str, ...]
"""Every ``method`` of :func:`estimate_pose`, the default first."""

TRIANGULATION_METHODS: Tuple[str, ...]
"""Every ``method`` of the triangulation functions: ``("linear", "local", "optimal")``."""

STATUSES: Tuple[str, ...]
"""Every ``status`` of a result, ``"success"`` first (the members of :class:`pluecker.Status`)."""

# --- Exceptions (all ValueError) ------------------------------------------------------------------

class PlueckerError(ValueError):
    """Base of every error for bad input or a failed computation (a Rust panic too: never a crash)."""

class ShapeError(PlueckerError):
    """Wrong shape, or row counts that must agree and do not: ``"points2d: expected shape (N, 2), got (5, 3)"``."""

class NonFiniteError(PlueckerError):
    """NaN or inf in an input: ``"points3d: non-finite value (NaN or inf) in row 4"``."""

class TooFewCorrespondencesError(PlueckerError):
    """Fewer correspondences or views than the method needs."""

class DegenerateConfigurationError(PlueckerError):
    """Data that cannot determine the answer (collinear points, a zero-length segment, ...)."""

class SingularCameraError(PlueckerError):
    """Intrinsics or a camera matrix that cannot be inverted (zero focal length, NaN/inf, ...)."""

class InvalidOptionError(PlueckerError):
    """An option or argument outside its domain (unknown method, ``penalty <= 0``, a bool, ...)."""

class _ResidualTest(TypedDict):
    """A χ² test of residuals against their stated noise (level 1e-3)."""

    chi2: float
    dof: int
    p_value: float
    consistent: bool

# --- Camera ---------------------------------------------------------------------------------------

@final
class Camera:
    """A camera: one of the models in :attr:`MODELS` (COLMAP's, with ``PINHOLE`` one of them, and
    ``SKEWED_PINHOLE``) with its parameters in COLMAP's order. Its pixels are the observed ones: through
    a lens with distortion ``u = K D(x_cam / z)``, for the pinholes ``u = K x_cam / z``. Immutable,
    hashable, ``==``, picklable. ``fx``, ``fy`` may be negative (a mirrored axis), never zero.
    Unprojection inverts the projection to 1e-10 px."""

    MODELS: List[str]
    def __new__(cls, model: Any, params: Optional[Sequence[float]] = None) -> "Camera":
        """``Camera(model, params)``: ``model`` a name of :attr:`MODELS`, ``params`` in COLMAP's order;
        ``Camera(pycolmap_camera)``: the same model and parameters as a ``pycolmap.Camera`` (its errors
        name its ``camera_id``)."""
    @staticmethod
    def pinhole(fx: float, fy: float, cx: float, cy: float, skew: Optional[float] = None) -> "Camera":
        """``K = [[fx, skew, cx], [0, fy, cy], [0, 0, 1]]``: ``PINHOLE``, or ``SKEWED_PINHOLE`` with a
        skew (``skew=None``: 0, orthogonal pixel axes)."""
    @staticmethod
    def from_matrix(K: ArrayLike) -> "Camera":
        """The pinhole camera of a (3, 3) calibration matrix, divided by ``K[2, 2]`` first."""
    # fields of Camera (generated: python -m pluecker._stubgen)
    __fields__: ClassVar[List[Tuple[str, str, str]]]
    model: str
    """The model's name, e.g. `'PINHOLE'`, `'OPENCV'` (COLMAP's names; `'SKEWED_PINHOLE'` is pluecker's)."""
    params: NDArray[np.float64]
    """The parameters in COLMAP's order (see `parameter_names`)."""
    parameter_names: List[str]
    """The names of `params`, e.g. `['fx', 'fy', 'cx', 'cy', 'k1', 'k2', 'p1', 'p2']`."""
    fx: float
    """Focal length along u, pixels (negative for a mirrored axis)."""
    fy: float
    """Focal length along v, pixels (negative for a mirrored axis)."""
    cx: float
    """Principal point u, pixels."""
    cy: float
    """Principal point v, pixels."""
    skew: float
    """Skew, pixels (0 but for SKEWED_PINHOLE)."""
    K: NDArray[np.float64]
    """The pinhole part `K = [[fx, skew, cx], [0, fy, cy], [0, 0, 1]]` (3, 3)."""
    # end of fields
    @property
    def distorts(self) -> bool:
        """Whether the model distorts (``False`` for the pinholes and all-zero distortion parameters)."""
    @property
    def pinhole_part(self) -> "Camera":
        """The pinhole camera of this camera's ``K``: the camera of its undistorted pixels."""
    def P(self, R: ArrayLike, t: ArrayLike) -> NDArray[np.float64]:
        """The (3, 4) camera matrix ``K [R | t]`` of the pinhole part at the pose ``x_cam = R X_world + t``."""
    def project(self, points_cam: ArrayLike) -> NDArray[np.float64]:
        """Pixels (N, 2) of camera-frame points (N, 3) in front of the camera, through the lens."""
    def unproject(self, pixels: ArrayLike) -> NDArray[np.float64]:
        """Undistorted normalised coordinates (N, 2), ``(x/z, y/z)`` of the ray, of pixels (N, 2); an
        error names a pixel beyond the fold."""
    def bearings(self, pixels: ArrayLike) -> NDArray[np.float64]:
        """Unit rays (N, 3), camera frame, of pixels (N, 2) (minimal solvers)."""
    def plane_normals(self, segments: ArrayLike) -> NDArray[np.float64]:
        """Unit normals (M, 3), camera frame, of the interpretation planes of segments (M, 2, 2), pixels."""
    def undistort(self, pixels: ArrayLike, covariances: Optional[ArrayLike] = None) -> Tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Undistorted pixels (N, 2) (exact to 1e-10 px) and their covariances (N, 2, 2) for pixel
        covariances ``covariances`` (N, 2, 2) (``None``: 1 px²), first order: observations of
        :attr:`pinhole_part`; segments go through :func:`lines_from_endpoints`."""
    def normalized_covariances(self, pixels: ArrayLike, covariances: Optional[ArrayLike] = None) -> NDArray[np.float64]:
        """First-order (N, 2, 2) covariances of the normalised coordinates for pixel covariances ``covariances`` (N, 2, 2) (``None``: 1 px)."""
    def to_dict(self) -> Dict[str, Any]: ...

@final
class View:
    """A known camera of the triangulation functions: a :class:`Camera` (any model) at the pose
    ``x_cam = R X_world + t``; its pixels are the camera's observed ones. Immutable, ``==``, picklable."""

    def __new__(cls, camera: Camera, R: ArrayLike, t: ArrayLike) -> "View": ...
    @staticmethod
    def from_projection(P: ArrayLike) -> "View":
        """The pinhole view of a finite 3x4 ``P = s K [R | t]`` (any positive scale): ``K`` with
        ``K[2, 2] = 1`` and ``fy > 0`` (``det M < 0`` gives ``fx < 0``), ``R`` a rotation."""
    # fields of View (generated: python -m pluecker._stubgen)
    __fields__: ClassVar[List[Tuple[str, str, str]]]
    camera: Camera
    """The camera."""
    pose: Tuple[NDArray[np.float64], NDArray[np.float64]]
    """The pose `x_cam = R X_world + t`; `R, t = view.pose`."""
    P: NDArray[np.float64]
    """`P = K [R | t]` (3, 4) of the camera's pinhole part at the pose."""
    # end of fields
    def to_dict(self) -> Dict[str, Any]: ...

#: The known cameras of a triangulation: (v, 3, 4) matrices ``P = K [R | t]`` or a sequence of views.
_KnownCameras = Union[ArrayLike, Sequence[View]]

@final
class Rig:
    """Cameras fixed to one body: camera ``k`` at ``sensor_from_rig[k]``, ``x_sensor = R x_rig + t``. The
    pose of the body, ``rig_from_world``, places every camera: ``sensor_from_rig[k] ∘ rig_from_world``.
    Immutable, ``==``, picklable; :func:`pluecker.colmap.rig` reads a pycolmap reconstruction's rig."""

    def __new__(
        cls, cameras: Sequence[Camera], sensor_from_rig: Sequence[Union[Pose, Tuple[ArrayLike, ArrayLike]]]
    ) -> "Rig": ...
    @property
    def cameras(self) -> List[Camera]:
        """The cameras, in order."""
    @property
    def sensor_from_rig(self) -> List[Pose]:
        """Each camera's pose in the body's frame, ``x_sensor = R x_rig + t``."""
    @property
    def centres(self) -> NDArray[np.float64]:
        """(n, 3) the cameras' optical centres in the body's frame."""
    @property
    def is_central(self) -> bool:
        """Whether every camera has its optical centre at one point (a central camera)."""
    def __len__(self) -> int: ...
    def views(self, R: ArrayLike, t: ArrayLike) -> List[View]:
        """Every camera's :class:`View` when the body is at ``rig_from_world = (R, t)``."""
    def to_dict(self) -> Dict[str, Any]:
        """``{"cameras": [{"model", "params"}, ...], "sensor_from_rig": [{"rotation", "translation"}, ...]}``."""

# --- Pose estimation (Phong & Horaud 1995) --------------------------------------------------------

@final
class PoseOptions:
    """Options of :func:`estimate_pose` (the core's ``PoseOptions``, same fields and nesting). ``ransac``
    and ``certify`` are held by reference: ``options.certify.max_nodes = 10`` takes effect."""

    # fields of PoseOptions (generated: python -m pluecker._stubgen)
    def __new__(cls, *, method: str = 'trust-region', penalty: float = 50.0, normalize: bool = True, refine: bool = True, initial_pose: Optional[Tuple[NDArray[np.float64], NDArray[np.float64]]] = None, trust_region: TrustRegionOptions = ..., levenberg_marquardt: LevenbergMarquardtOptions = ..., newton: StoppingCriteria = ..., refinement: TrustRegionOptions = ..., sigma_px: Optional[float] = None, ambiguity_threshold: float = 9.0, ransac: Optional[RansacOptions] = None, certify: Optional[CertifyOptions] = None) -> "PoseOptions": ...
    __fields__: ClassVar[List[Tuple[str, str, str]]]
    method: str
    """Estimator, one of `METHODS`."""
    penalty: float
    """Penalty λ on the dual-quaternion constraints `r·r = 1`, `r·s = 0` (Phong & Horaud 1995, eqs. 13-15, 22)."""
    normalize: bool
    """Solve the algebraic stage in a centred, unit-scale object frame."""
    refine: bool
    """Follow the estimator with a minimisation of the reprojection error in pixels."""
    initial_pose: Optional[Tuple[NDArray[np.float64], NDArray[np.float64]]]
    """An extra starting pose `(R, t)`, tried first besides the default starts; `None`: no guess needed."""
    trust_region: TrustRegionOptions
    """The trust-region solver of the algebraic stage (methods `trust-region`, `trust-region-exact`). Held by reference."""
    levenberg_marquardt: LevenbergMarquardtOptions
    """The solver of method `'levenberg-marquardt'`. Held by reference."""
    newton: StoppingCriteria
    """The stopping tests of method `'newton'`. Held by reference."""
    refinement: TrustRegionOptions
    """The trust-region minimisation of the reprojection error (`refine`). Held by reference."""
    sigma_px: Optional[float]
    """Pixel noise σ of every image point and endpoint, for the covariance; `None`: estimated from the residuals."""
    ambiguity_threshold: float
    """Status `ambiguous` when another minimum is within `ambiguity_threshold · σ²` of the answer's cost."""
    ransac: Optional[RansacOptions]
    """Robust estimation (LO-RANSAC over points and lines) with these options instead of `method`'s estimator;
    `None`: every correspondence is an inlier. Held by reference.
    """
    certify: Optional[CertifyOptions]
    """The global-optimality certificate (the sublevel-set test) with these options; `None`: not requested.
    Held by reference. A requested certificate that does not hold gives status `gap_not_closed`.
    """
    # end of fields
    def to_dict(self) -> Dict[str, Any]: ...

@final
class CertifyOptions:
    """Options of every certificate of global optimality, pose and triangulation alike (the core's
    ``CertifyOptions``)."""

    # fields of CertifyOptions (generated: python -m pluecker._stubgen)
    def __new__(cls, *, max_relative_gap: float = 0.001, max_nodes: Optional[int] = None) -> "CertifyOptions": ...
    __fields__: ClassVar[List[Tuple[str, str, str]]]
    max_relative_gap: float
    """Certified when `(cost − lower_bound) / max(cost, 1e-12)` is at most this, in (0, 1)."""
    max_nodes: Optional[int]
    """Cap on the nodes (rotation cells, boxes) a search examines; `None`: each search's own cap (see the docs)."""
    # end of fields
    def to_dict(self) -> Dict[str, Any]: ...

@final
class Certificate:
    """A proved lower bound on the cost (``Σ r²``, squared whitened pixels) over a stated ``domain``
    (the core's ``Certificate``)."""

    # fields of Certificate (generated: python -m pluecker._stubgen)
    __fields__: ClassVar[List[Tuple[str, str, str]]]
    certified: bool
    """Whether the estimate is proved globally optimal within `max_relative_gap` over `domain`."""
    lower_bound: float
    """Proved lower bound on the cost over `domain`, capped at the cost."""
    raw_lower_bound: float
    """The bound as proved, before the cap at the cost (inf when the search set was proved empty)."""
    relative_gap: float
    """`(cost − lower_bound) / max(cost, 1e-12)`."""
    kind: str
    """How the bound was proved: `convexity_test`, `branch_and_bound`, `taylor_branch_and_bound`, `lens_convexity_test` (triangulation); `sublevel_set`, `lens_sublevel_set` (pose)"""
    primitive: str
    """What was estimated: `pose`, `point`, `line` or `quadric`."""
    domain: str
    """The set of estimates over which `lower_bound` holds, in words (set by `kind` and `primitive`)."""
    nodes: int
    """Nodes of the search (0 for a convexity test)."""
    solver_iterations: int
    """Conic-solver iterations summed over the nodes."""
    # end of fields
    def to_dict(self) -> Dict[str, Any]: ...

@final
class StoppingCriteria:
    """Stopping tests and iteration cap of a solver (the core's ``StoppingCriteria``), nested in
    :class:`TrustRegionOptions`, :class:`LevenbergMarquardtOptions` and ``PoseOptions.newton``."""

    # fields of StoppingCriteria (generated: python -m pluecker._stubgen)
    __fields__: ClassVar[List[Tuple[str, str, str]]]
    gradient_tolerance: float
    """Stop when the gradient's largest entry is at most this."""
    cost_tolerance: float
    """Stop when the cost is at most this."""
    step_tolerance: float
    """Stop when an accepted step is this small relative to the tangent step size."""
    max_iterations: int
    """Iteration cap."""
    # end of fields
    def to_dict(self) -> Dict[str, Any]: ...

@final
class TrustRegionOptions:
    """Options of the trust-region solver (Phong & Horaud 1995, section 4.1; the core's
    ``TrustRegionOptions``): ``PoseOptions.trust_region`` and ``PoseOptions.refinement``."""

    # fields of TrustRegionOptions (generated: python -m pluecker._stubgen)
    def __new__(cls, *, subproblem: str = 'hebden', hessian_shift: float = 0.001, initial_radius: float = 1.0, accept_ratio: float = 0.25, expand_ratio: float = 0.75, radius_tolerance: float = 1e-12, stopping: StoppingCriteria = ...) -> "TrustRegionOptions": ...
    __fields__: ClassVar[List[Tuple[str, str, str]]]
    subproblem: str
    """Subproblem solver: `hebden` (Gauss-Newton Hessian shifted by `hessian_shift`, the paper's
    step, Appendix A) or `more_sorensen` (exact Hessian, section 4.2).
    """
    hessian_shift: float
    """α in `H' = JᵀJ + αI` (step k.3)."""
    initial_radius: float
    """Initial trust radius δ₀."""
    accept_ratio: float
    """Acceptance threshold r on the ratio of eq. 28 (paper: r ∈ [0.1, 0.3])."""
    expand_ratio: float
    """Expansion threshold s (paper: s ∈ [0.5, 0.8])."""
    radius_tolerance: float
    """Stop when the trust radius δ is at most this (the ε_δ of step k.2)."""
    stopping: StoppingCriteria
    """The other stopping tests of step k.2 and the iteration cap. Held by reference."""
    # end of fields
    def to_dict(self) -> Dict[str, Any]: ...

@final
class LevenbergMarquardtOptions:
    """Options of the Levenberg-Marquardt solver (Phong & Horaud 1995, section 4.2; the core's
    ``LevenbergMarquardtOptions``): ``PoseOptions.levenberg_marquardt``."""

    # fields of LevenbergMarquardtOptions (generated: python -m pluecker._stubgen)
    def __new__(cls, *, initial_damping: float = 0.001, max_rejections: int = 40, stopping: StoppingCriteria = ...) -> "LevenbergMarquardtOptions": ...
    __fields__: ClassVar[List[Tuple[str, str, str]]]
    initial_damping: float
    """Initial damping, relative to the largest diagonal entry of `JᵀJ`."""
    max_rejections: int
    """Failed steps in a row after which the method gives up."""
    stopping: StoppingCriteria
    """Stopping tests and iteration cap. Held by reference."""
    # end of fields
    def to_dict(self) -> Dict[str, Any]: ...

@final
class RansacOptions:
    """Options of the robust estimator (LO-RANSAC over points and lines; the core's
    ``RansacOptions``): ``estimate_pose(..., ransac=RansacOptions(...))``."""

    # fields of RansacOptions (generated: python -m pluecker._stubgen)
    def __new__(cls, *, point_threshold: float = 4.0, line_threshold: float = 4.0, confidence: float = 0.9999, max_iterations: int = 100000, min_iterations: int = 0, min_inlier_ratio: float = 0.1, sprt: bool = True, time_budget: Optional[float] = None, seed: int = 0, local_iterations: int = 10, min_inliers: int = 6) -> "RansacOptions": ...
    __fields__: ClassVar[List[Tuple[str, str, str]]]
    point_threshold: float
    """Inlier threshold of a point: reprojection distance, pixels."""
    line_threshold: float
    """Inlier threshold of a segment: RMS distance of its endpoints to the projected line, pixels."""
    confidence: float
    """Probability of having drawn an all-inlier sample when sampling stops, in (0, 1)."""
    max_iterations: int
    """Cap on the samples drawn."""
    min_iterations: int
    """Samples drawn at least, whatever the confidence."""
    min_inlier_ratio: float
    """Lowest inlier ratio sampling plans for (caps the samples drawn), in [0, 1)."""
    sprt: bool
    """Sequential probability ratio test: stop scoring a hypothesis once it cannot beat the best."""
    time_budget: Optional[float]
    """Wall-time budget of the sampling loop, seconds; `None`: no budget."""
    seed: int
    """Seed of the sampler: the same seed and data give the same result."""
    local_iterations: int
    """Iteration cap of each local optimisation run; 0 disables local optimisation."""
    min_inliers: int
    """Fewest inliers of a usable model (at least 3); fewer correspondences in all is an error."""
    # end of fields
    def to_dict(self) -> Dict[str, Any]: ...

@final
class PoseStage:
    """One stage of the pose pipeline: the algebraic estimator, the linear solve, the sampling loop
    (``"ransac"``) or the reprojection refinement (``"refinement"``)."""

    # fields of PoseStage (generated: python -m pluecker._stubgen)
    __fields__: ClassVar[List[Tuple[str, str, str]]]
    name: str
    """Name of the stage."""
    cost_kind: str
    """What `initial_cost` and `final_cost` measure: `algebraic` (eqs. 13-15, 22 as ½ΣΦ²),
    `reprojection` (Σ squared pixel residuals, px²) or `msac` (stage `ransac`: Σ min(e², τ²), px²).
    """
    rotation: NDArray[np.float64]
    """Rotation `R` at the end of the stage, `x_cam = R X_world + t`."""
    translation: NDArray[np.float64]
    """Translation `t` at the end of the stage, world units."""
    iterations: int
    """Iterations of the stage."""
    initial_cost: float
    """Cost at the stage's start."""
    final_cost: float
    """Cost at the stage's end."""
    termination: str
    """Why the stage stopped: `gradient_tolerance`, `radius_tolerance`, `cost_tolerance`, `step_tolerance`,
    `max_iterations`, `singular_hessian`, `non_finite_cost` or `closed_form`.
    """
    time_seconds: float
    """Wall time of the stage, seconds."""
    # end of fields
    def to_dict(self) -> Dict[str, Any]: ...

@final
class RansacReport:
    """What the robust loop did (:attr:`PoseDetails.ransac` of a robust estimate)."""

    # fields of RansacReport (generated: python -m pluecker._stubgen)
    __fields__: ClassVar[List[Tuple[str, str, str]]]
    iterations: int
    """Samples drawn."""
    degenerate_samples: int
    """Samples without a pose in front of the camera (collinear points, parallel lines, ...)."""
    models_scored: int
    """Poses scored (a sample may give several), fully or until an early exit."""
    sprt_rejections: int
    """Poses rejected by the sequential probability ratio test."""
    errors_evaluated: int
    """Reprojection errors evaluated while scoring: the work of the scoring."""
    local_optimizations: int
    """Local optimisations run (one per sample whose pose beat every sample's before it)."""
    inliers: int
    """Inliers (points + lines) of the best model before the final refinement."""
    required_inliers: int
    """Fewest inliers the best model needed, else status `too_few_inliers`: `max(min_inliers, min(c + 1,
    ⌈min_inlier_ratio · n⌉))`, `c` the most inliers a wrong pose plausibly gets by chance among `n`.
    """
    score: float
    """MSAC score `Σ min(e², τ²)` of the best model, px²."""
    stop: str
    """Why sampling stopped: `confidence`, `min_inlier_ratio` (enough samples to find a model with that
    inlier fraction, and none was), `iteration_cap`, `time_budget`, `interrupted` or `no_solvable_sample`.
    """
    time_seconds: float
    """Wall time of the loop including local optimisation, seconds."""
    # end of fields
    def to_dict(self) -> Dict[str, Any]: ...

@final
class Pose:
    """A camera pose ``x_cam = R @ X_world + t`` (the core's ``Pose``): ``rotation`` and ``translation``,
    the rotation's other forms as methods. Unpacks as ``R, t = pose``; accepted wherever a pose ``(R, t)``
    is (``PoseOptions.initial_pose``)."""

    # fields of Pose (generated: python -m pluecker._stubgen)
    __fields__: ClassVar[List[Tuple[str, str, str]]]
    rotation: NDArray[np.float64]
    """`R`, world to camera (3x3 rotation matrix)."""
    translation: NDArray[np.float64]
    """`t`, world units: the world origin in the camera frame."""
    # end of fields
    def to_dict(self) -> Dict[str, Any]: ...
    def dual_quaternion(self) -> NDArray[np.float64]:
        """(8,) unit dual quaternion ``(r0, rx, ry, rz, s0, sx, sy, sz)`` (eqs. 6-7), ``r0 >= 0``."""
    def axis_angle(self) -> Tuple[NDArray[np.float64], float]:
        """``(axis, angle)``: unit axis (3,) and angle in [0, π], radians."""
    def rotation_vector(self) -> NDArray[np.float64]:
        """(3,) rotation vector ``angle * axis``, radians."""
    def centre(self) -> NDArray[np.float64]:
        """(3,) optical centre in the world frame, ``-R.T @ t``."""
    def __iter__(self) -> Iterator[NDArray[np.float64]]: ...
    def __len__(self) -> int: ...

@final
class PoseDetails:
    """How a :class:`PoseResult` was found (the core's ``PoseDetails``); costs are ``Σ r²``, px²."""

    # fields of PoseDetails (generated: python -m pluecker._stubgen)
    __fields__: ClassVar[List[Tuple[str, str, str]]]
    stages: List[PoseStage]
    """Every stage in order; the last one gave the returned pose."""
    rms_error_px: float
    """Root-mean-square reprojection error over the used correspondences, pixels: `√(cost / m)`."""
    estimated_camera: Optional[Camera]
    """Intrinsics estimated by method `'linear'` (`None` for the others)."""
    ransac: Optional[RansacReport]
    """What the robust loop did; `None` unless `options.ransac` is set."""
    covariance_source: Optional[str]
    """Where the σ of the covariance came from: `given` or `estimated`."""
    sigma_px: Optional[float]
    """The σ of `covariance`: `options.sigma_px`, or `σ̂ = √(Σ r² / (m − 6))` over the m used residuals."""
    second_best: Optional[Tuple[Pose, float]]
    """The cheapest other local minimum with every point in front and its cost `Σ r²` (px²); `None` if none was
    found. Within `ambiguity_threshold · σ²` of `cost`, the status is `ambiguous`.
    """
    behind_camera_cost: Optional[float]
    """Cost `Σ r²` of a pose with every point behind the camera that fits far better (status `behind_camera`)."""
    residual_test: Optional[_ResidualTest]
    """χ² test of the residuals against `sigma_px`; `None` without `options.sigma_px`."""
    uncertified_reason: Optional[str]
    """Why the pose is not certified, in words; `None` when it is."""
    # end of fields
    def to_dict(self) -> Dict[str, Any]: ...

@final
class PoseResult:
    """The answer of :func:`estimate_pose` (the core's ``PoseResult``): the pose, whether it can be used,
    its cost ``Σ r²``, the correspondences used, its covariance and certificate; how it was found is in
    :attr:`details`."""

    # fields of PoseResult (generated: python -m pluecker._stubgen)
    __fields__: ClassVar[List[Tuple[str, str, str]]]
    pose: Pose
    """The pose `x_cam = R X_world + t` (NaN if the solver failed); `R, t = result.pose`."""
    method: str
    """The estimator that ran."""
    status: str
    """`success`, or why not: `gap_not_closed` (a requested certificate does not hold), `not_converged` (a
    stage hit its cap), `numerical_failure`, `behind_camera` (points behind at the pose, or the data fit far
    better behind: `details.behind_camera_cost`), `ambiguous` (another minimum nearly as good:
    `details.second_best`); robust: `too_few_inliers`, `no_hypothesis`; `interrupted`, `time_budget`.
    """
    success: bool
    """`status == 'success'`."""
    cost: float
    """Reprojection cost `Σ r²` (px²) of the used correspondences at the pose, in the observed pixels."""
    cost_kind: str
    """What `cost` measures: `reprojection`."""
    certificate: Optional[Certificate]
    """Proved lower bound on `cost` over every pose keeping the points and segment endpoints in front
    (`options.certify`); `None` when no bound was computed (`details.uncertified_reason` says why).
    """
    certified: bool
    """`certificate is not None and certificate.certified`."""
    iterations: int
    """Iterations summed over the stages."""
    termination: str
    """Why the last iterative stage stopped."""
    time_seconds: float
    """Wall time, seconds."""
    residual_dof: int
    """Degrees of freedom of `cost`: the residuals used minus the 6 of the pose (0 when not known)."""
    inliers_points: NDArray[np.bool_]
    """(N,) points used for the pose: when robust the final inliers (error ≤ `point_threshold` px), else all true."""
    inliers_lines: NDArray[np.bool_]
    """(M,) lines used: when robust those within RMS `line_threshold` px of the projected line, else all true."""
    covariance: Optional[NDArray[np.float64]]
    """6x6 covariance `σ² (JᵀJ)⁻¹` of `(ω, t)` at the pose (`ω` the tangent of `exp(ω) R`, radians, camera
    frame; then `t`, world units), from the used correspondences; `None` when `JᵀJ` is singular or σ unknown.
    """
    details: PoseDetails
    """How the pose was found: stages, noise, runner-up."""
    # end of fields
    def to_dict(self) -> Dict[str, Any]: ...
    def to_json(self) -> str:
        """The result as JSON, written by the core (``serde``): the keys and values of ``to_dict()``, NaN
        and inf as ``null``; what ``pluecker pose`` prints."""

def estimate_pose(
    camera: Union[Camera, Rig],
    points2d: Optional[ArrayLike] = None,
    points3d: Optional[ArrayLike] = None,
    lines2d: Optional[ArrayLike] = None,
    lines3d: Optional[ArrayLike] = None,
    *,
    options: Optional[PoseOptions] = None,
    point_covariances: Optional[ArrayLike] = None,
    line_covariances: Optional[ArrayLike] = None,
    point_cameras: Optional[ArrayLike] = None,
    line_cameras: Optional[ArrayLike] = None,
) -> PoseResult:
    """Estimate the pose ``x_cam = R @ X_world + t`` of a calibrated camera from points (N, 2) ↔ (N, 3)
    and/or segments (M, 2, 2) ↔ (M, 2, 3) (only the 3-D line through a 3-D segment is used).

    ``camera`` may be a :class:`Rig` instead: the pose is then ``rig_from_world`` (``x_rig = R @ X_world + t``)
    and ``point_cameras`` (N,) / ``line_cameras`` (M,) give the index (in ``rig.cameras``) of the camera whose
    pixels each observation holds; the cost is in each camera's own pixels through its lens. Observations of
    one camera alone are that camera's problem (certificate included, pose moved into the rig's frame); over
    several pinhole cameras a requested certificate is the same proof with each observation in its own camera
    (with lenses among several cameras it is not available: status ``gap_not_closed``, the reason names the
    camera).

    ``camera``: :class:`Camera` (any model) whose observed (distorted, through a lens) pixels are given: the
    minimal solvers, RANSAC and the algebraic methods run on exactly undistorted pixels weighted by the
    distortion's Jacobian (RANSAC's thresholds are distorted pixels to first order); the refinement and
    all reported pixels use the exact error in the distorted pixels (segments: each endpoint's distance to
    the curved image of the line); a requested certificate bounds that exact cost (kind ``lens_sublevel_set``, over
    the poses whose projections stay inside the disc where the lens is proved one-to-one); with RANSAC a
    pixel beyond the lens is an outlier. ``point_covariances`` (N, 2, 2), ``line_covariances`` (M, 2, 2) or
    (M, 2, 2, 2), px²: per-observation noise (unit when left out); residuals and ``sigma_px`` are then
    in standard deviations (``sigma_px`` defaults to 1), and a requested certificate bounds that
    whitened cost.

    ``options``: :class:`PoseOptions` (``None``: the defaults). ``options.method``, one of :data:`METHODS`:
    ``"trust-region"`` (eqs. 13 + 22, Hebden's step, section 4.1), ``"rotation-then-translation"``
    (eq. 14 then 15), ``"trust-region-exact"`` (section 4.2), ``"newton"``, ``"levenberg-marquardt"``, or
    ``"linear"`` (Faugeras-Toscani from >= 6 non-coplanar points, which also estimates the intrinsics).
    ``options.ransac``, a :class:`RansacOptions`, estimates robustly (minimal solvers P3P/P2P1L/P1P2L/P3L,
    MSAC, local optimisation, then the refinement on the inliers; ``method`` is then not used).
    ``options.certify``, a :class:`CertifyOptions`, asks for the certificate of global optimality.

    With ``options.refine`` (the default) the answer is the cheapest local minimum of the reprojection
    error reached from the algebraic answer and from minimal-solver poses. A solver that runs but fails
    is not an exception: see :attr:`PoseResult.status`. The GIL is released; from 1000 correspondences
    on, Ctrl-C stops the call within about 0.1 s and the ``KeyboardInterrupt`` carries the pose so far
    as ``partial``.

    Raises ShapeError, NonFiniteError, TooFewCorrespondencesError, DegenerateConfigurationError,
    InvalidOptionError (all ValueError); TypeError for an argument of the wrong kind.
    """

# Minimal solvers (camera-frame data from Camera.bearings / Camera.plane_normals): every real pose that
# explains the sample exactly, as a list of (R, t); empty for a degenerate sample.

_Poses = List[Tuple[NDArray[np.float64], NDArray[np.float64]]]

def gp3p(origins: ArrayLike, directions: ArrayLike, points: ArrayLike) -> _Poses:
    """A rig's three rays (origins (3, 3), directions (3, 3), rig frame) and world points (3, 3): the
    generalised P3P, poses ``x_rig = R @ X + t`` with every point on its ray at positive depth; at most 8."""

def p3p(bearings: ArrayLike, points: ArrayLike) -> _Poses:
    """Three rays (3, 3) and world points (3, 3): Lambda Twist (Persson & Nordberg 2018), at most 4."""

def p2p1l(bearings: ArrayLike, points: ArrayLike, normal: ArrayLike, endpoints: ArrayLike) -> _Poses:
    """Two rays (2, 3) and points (2, 3), one plane normal (3,) and two world points of its line (2, 3)."""

def p1p2l(bearing: ArrayLike, point: ArrayLike, normals: ArrayLike, endpoints: ArrayLike) -> _Poses:
    """One ray (3,) and point (3,), two plane normals (2, 3) and their lines' world points (2, 2, 3)."""

def p3l(normals: ArrayLike, endpoints: ArrayLike) -> _Poses:
    """Three plane normals (3, 3) and their lines' world points (3, 2, 3); at most 8 poses."""

def refine_pose(
    camera: Camera,
    R: ArrayLike,
    t: ArrayLike,
    points2d: Optional[ArrayLike] = None,
    points3d: Optional[ArrayLike] = None,
    lines2d: Optional[ArrayLike] = None,
    lines3d: Optional[ArrayLike] = None,
    *,
    options: Optional[PoseOptions] = None,
) -> Tuple[NDArray[np.float64], NDArray[np.float64], PoseStage]:
    """The reprojection refinement of :func:`estimate_pose` alone, from ``(R, t)``: ``(R, t, stage)``."""

def pose_covariance(
    camera: Camera,
    R: ArrayLike,
    t: ArrayLike,
    points2d: Optional[ArrayLike] = None,
    points3d: Optional[ArrayLike] = None,
    lines2d: Optional[ArrayLike] = None,
    lines3d: Optional[ArrayLike] = None,
    sigma_px: Optional[float] = None,
) -> NDArray[np.float64]:
    """The (6, 6) covariance ``σ² (JᵀJ)⁻¹`` of ``(ω, t)`` at ``(R, t)`` for pixel noise ``sigma_px``
    (``None``: 1 px): ``ω`` the rotation tangent of ``exp(ω) R`` (radians, camera frame), then the
    translation (world units); the Cramér-Rao bound at the true pose. DegenerateConfigurationError when
    ``JᵀJ`` is singular or not finite."""

def reprojection_errors(
    camera: Camera,
    R: ArrayLike,
    t: ArrayLike,
    points2d: Optional[ArrayLike] = None,
    points3d: Optional[ArrayLike] = None,
    lines2d: Optional[ArrayLike] = None,
    lines3d: Optional[ArrayLike] = None,
) -> NDArray[np.float64]:
    """Reprojection errors (N + M,) in pixels at ``(R, t)``: points first (distance to the projected
    point), then segments (RMS distance of the two endpoints to the projected line)."""

def pose_to_dual_quaternion(R: ArrayLike, t: ArrayLike) -> NDArray[np.float64]:
    """The unit dual quaternion (8,) ``(r0, rx, ry, rz, s0, sx, sy, sz)`` of ``(R, t)``, ``s = ½ t r``
    (eqs. 6-7)."""

def dual_quaternion_to_pose(q: ArrayLike) -> Tuple[NDArray[np.float64], NDArray[np.float64]]:
    """``(R, t)`` of a dual quaternion (8,); ``r`` is normalised first (a zero ``r`` is a
    DegenerateConfigurationError)."""

class _Screw(TypedDict):
    d: float
    angle: float
    direction: NDArray[np.float64]
    point: NDArray[np.float64]

def pose_to_screw(R: ArrayLike, t: ArrayLike) -> _Screw:
    """Chasles' screw of ``(R, t)``: rotation ``angle`` about the axis through ``point`` along
    ``direction``, and translation ``d`` along it."""

class _Scene(TypedDict, total=False):
    camera: Camera
    R: NDArray[np.float64]
    t: NDArray[np.float64]
    points2d: NDArray[np.float64]
    points3d: NDArray[np.float64]
    lines2d: NDArray[np.float64]
    lines3d: NDArray[np.float64]

def paper_scene() -> _Scene:
    """The calibration object of Phong & Horaud 1995, section 5 (460 points, centimetres) at the
    paper's pose and camera, noise-free."""

def random_scene(kind: str, n_points: int, n_lines: Optional[int] = None, seed: Optional[int] = None) -> _Scene:
    """A seeded random scene, noise-free, every point in front and inside a 640 x 480 image (fx = fy =
    800): ``kind`` ``"general"``, ``"planar"`` or ``"far"``; ``n_lines`` (``None``: 0) segments;
    ``seed`` (``None``: 0) gives the same scene on every platform. At most 10,000,000 points and
    segments together."""

def set_num_threads(n: Optional[int], /) -> None:
    """Sets the number of threads the batches of this process use: ``n`` from 1 to
    ``max(64, 4 × the cores available)`` (more only oversubscribes the cores), or ``None`` for the
    default, one per core or ``RAYON_NUM_THREADS``. Any other value (0, a negative or larger count, a
    bool) raises ``InvalidOptionError`` naming ``n``. For several processes sharing one machine, e.g.
    Dask workers (``pluecker.distributed``). Takes effect for the next call."""

def get_num_threads() -> int:
    """The number of threads the batches of this process use (see :func:`set_num_threads`)."""

# --- Triangulation (Josephson & Kahl 2008) --------------------------------------------------------
# Projections P = K [R | t] (n, 3, 4) map world points to pixels, λ (u, v, 1) = P (X, 1), λ > 0 in front
# (eq. 1). Every method minimises eq. 19 (residuals of eq. 17 whitened by ``covariances``; identity when None): ``"linear"``,
# ``"local"``, or ``"optimal"`` (default: certified by a convexity test or branch and bound, eqs. 21-22).
# Batches run in parallel without the GIL; ``progress(done)``; ``time_budget`` (s) ends with status
# ``"time_budget"``; Ctrl-C raises with the finished tracks as ``partial`` (``None`` if it came while the
# batch read its arrays or allocated its results). A bad track never stops others.

@final
class TriangulationOptions:
    """Options of every triangulation function (the core's ``TriangulationOptions``). A ``method=``
    given to the function wins over :attr:`method`."""

    # fields of TriangulationOptions (generated: python -m pluecker._stubgen)
    def __new__(cls, *, method: str = 'optimal', certify: CertifyOptions = ..., outlier_threshold: Optional[float] = None, line_bound: str = 'taylor', quadric_bound: str = 'convexity', local_max_iterations: int = 100) -> "TriangulationOptions": ...
    __fields__: ClassVar[List[Tuple[str, str, str]]]
    method: str
    """Estimator, one of `TRIANGULATION_METHODS`: `linear`, `local` or `optimal` (certified)."""
    certify: CertifyOptions
    """Method `optimal`: the certificate's gap and node cap (`max_nodes=None`: 2000 nodes of the conic branch and bounds, points, quadrics and `line_bound="relaxation"`; 50000 of the Taylor bound of lines), the object itself (`options.certify.max_nodes = 10` takes effect)."""
    outlier_threshold: Optional[float]
    """Points and lines: reject observations whose whitened error (pixels without `covariances`) exceeds this, by a consensus over view pairs, and solve on the rest (`inliers` of the result); `None`: use every observation."""
    line_bound: str
    """Lines, method `optimal`: the lower bound, `taylor` (interval Taylor bounds over the two-view chart; certificate `taylor_branch_and_bound` over every line) or `relaxation` (the paper's SOCP relaxation, eqs. 21-27; certificate `branch_and_bound` over the eq. 27 strips)."""
    quadric_bound: str
    """Quadrics, method `optimal`: the lower bound, `convexity` (the convexity test, certificate `convexity_test` over every ellipsoid no principal plane cuts; the relaxation when it cannot decide) or `relaxation` (the paper's SOCP relaxation only; certificate `branch_and_bound` over an a-priori box)."""
    local_max_iterations: int
    """Iteration cap of the local minimisation (method `local`, and the upper bounds of `optimal`)."""
    # end of fields
    def to_dict(self) -> Dict[str, Any]: ...

class TriangulationReport:
    """What one triangulation did: the base class of the point, line and quadric results."""

    # fields of TriangulationReport (generated: python -m pluecker._stubgen)
    __fields__: ClassVar[List[Tuple[str, str, str]]]
    method: str
    """The method that ran: `linear`, `local` or `optimal`."""
    status: str
    """`success`, or why not: `gap_not_closed` (the certificate's search hit `certify.max_nodes`), `not_converged`, `behind_camera`,
    `at_infinity` (no finite estimate: NaN), `numerical_failure`; in batches also `interrupted`, `time_budget` and the rejection statuses.
    """
    success: bool
    """`status == 'success'`."""
    cost: float
    """The cost at the estimate, of kind `cost_kind`: eq. 19 (sum of squared whitened residuals; for points the
    reprojection errors), or for segments seen through a lens that distorts their reprojection cost.
    """
    cost_kind: str
    """What `cost` measures, and what the certificate bounds: `reprojection` (points; segments
    through a lens that distorts: Σ squared distances of the endpoints to the curved images), `line_residual`
    (other lines: eq. 19 on the image lines' residuals) or `conic_residual` (quadrics).
    """
    certificate: Optional[Certificate]
    """The proof of global optimality (`Certificate`: `certified`, `lower_bound`, `raw_lower_bound`, `relative_gap`,
    `kind`, `domain`, `nodes`); `None` when no bound was computed (methods `linear` and `local`, input refused
    before the search). A search that did not close the gap gives `certified == False` and status `gap_not_closed`.
    """
    certified: bool
    """`certificate is not None and certificate.certified`."""
    iterations: int
    """Iterations of the local minimisation."""
    termination: str
    """Why the local minimisation stopped."""
    time_seconds: float
    """Wall time, seconds."""
    residual_dof: int
    """Degrees of freedom of `cost`: whitened residuals minus fitted parameters (0 when not known)."""
    residual_test: Optional[_ResidualTest]
    """χ² test of `cost` against the given covariances (identity: 1 px), `dof` = residuals − parameters;
    `consistent == False` flags an outlier, a wrong camera or noise beyond the stated one. `None` when `dof` is 0.
    """
    # end of fields
    def to_dict(self) -> Dict[str, Any]: ...

@final
class PointTriangulation(TriangulationReport):
    """A triangulated point and its report."""

    # fields of PointTriangulation (generated: python -m pluecker._stubgen)
    __fields__: ClassVar[List[Tuple[str, str, str]]]
    point: NDArray[np.float64]
    """The point, world frame."""
    covariance: Optional[NDArray[np.float64]]
    """Its 3x3 covariance (first order, from the observation covariances); `None` when singular."""
    inliers: Optional[NDArray[np.bool_]]
    """With `options.outlier_threshold`: (v,) the views the point was solved from; else `None`."""
    # end of fields

@final
class LineTriangulation(TriangulationReport):
    """A triangulated 3-D line and its report."""

    # fields of LineTriangulation (generated: python -m pluecker._stubgen)
    __fields__: ClassVar[List[Tuple[str, str, str]]]
    plucker: NDArray[np.float64]
    """Plücker coordinates `(l12, l13, l14, l23, l42, l34)` of the line, unit norm (eq. 4 holds)."""
    point: NDArray[np.float64]
    """The point of the line closest to the world origin."""
    direction: NDArray[np.float64]
    """Unit direction of the line."""
    chart_axes: NDArray[np.float64]
    """Rows `e1`, `e2`: the axes of the 4-parameter chart in which `covariance` is expressed."""
    covariance: Optional[NDArray[np.float64]]
    """4x4 covariance of the line in its chart (first order); `None` when singular."""
    inliers: Optional[NDArray[np.bool_]]
    """With `options.outlier_threshold`: (v,) the views the line was solved from; else `None`."""
    # end of fields
    def plucker_covariance(self) -> Optional[NDArray[np.float64]]:
        """The (6, 6) covariance of the unit Plücker coordinates."""
    def point_direction_covariance(self) -> Optional[NDArray[np.float64]]:
        """The (6, 6) covariance of ``(point, direction)``."""

@final
class QuadricTriangulation(TriangulationReport):
    """A triangulated ellipsoid (dual quadric) and its report."""

    # fields of QuadricTriangulation (generated: python -m pluecker._stubgen)
    __fields__: ClassVar[List[Tuple[str, str, str]]]
    Q: NDArray[np.float64]
    """The dual quadric `Q` (4x4, symmetric), the estimate of eq. 19."""
    primal: Optional[NDArray[np.float64]]
    """The primal quadric `Q⁻¹` (4x4); `None` when `Q` is singular."""
    centre: NDArray[np.float64]
    """Centre of the ellipsoid, world frame."""
    axes: NDArray[np.float64]
    """Principal axes of the ellipsoid, one per column."""
    semi_axes: NDArray[np.float64]
    """Semi-axis lengths along `axes`, world units."""
    covariance: Optional[NDArray[np.float64]]
    """9x9 covariance of the quadric's parameters (first order); `None` when singular."""
    # end of fields

class BatchReport:
    """The per-track report columns of a batch (one entry per track in every array): the base class
    of :class:`PointTriangulations`, :class:`LineTriangulations`, :class:`QuadricTriangulations`."""

    # fields of BatchReport (generated: python -m pluecker._stubgen)
    __fields__: ClassVar[List[Tuple[str, str, str]]]
    method: str
    """The method that ran: `linear`, `local` or `optimal`."""
    status: NDArray[np.str_]
    """Per track: `success`, or why not (the statuses of `TriangulationReport`, and `too_few_views`, `non_finite`, `degenerate`, ... for a rejected track)."""
    cost: NDArray[np.float64]
    """Per track: the cost at the estimate, of kind `cost_kind` (NaN for a rejected track)."""
    cost_kind: NDArray[np.str_]
    """Per track: what `cost` measures, as `TriangulationReport.cost_kind`: `reprojection` (points; lines from
    segments through a lens that distorts), `line_residual` (other lines) or `conic_residual` (quadrics); for a
    rejected track the primitive's own (`line_residual` for lines).
    """
    lower_bound: NDArray[np.float64]
    """Per track: the proved lower bound on the cost (the single result's `certificate.lower_bound`; NaN: no bound was computed, as for `linear`, `local` or a rejected track)."""
    raw_lower_bound: NDArray[np.float64]
    """Per track: the proved bound before the cap at the cost (NaN without a bound)."""
    relative_gap: NDArray[np.float64]
    """Per track: `(cost − lower_bound) / max(cost, 1e-12)` (NaN without a bound)."""
    certified: NDArray[np.bool_]
    """Per track: whether the estimate is certified globally optimal."""
    certificate: NDArray[np.str_]
    """Per track: the certificate's `kind` (`convexity_test`, `branch_and_bound`, `taylor_branch_and_bound`, `lens_convexity_test`), `none` without one."""
    nodes: NDArray[np.int64]
    """Per track: nodes of the certificate's search (0 without one)."""
    iterations: NDArray[np.int64]
    """Per track: iterations of the local minimisation."""
    time_seconds: NDArray[np.float64]
    """Per track: wall time, seconds."""
    p_value: NDArray[np.float64]
    """Per track: p-value of the χ² test of the cost (NaN without spare degrees of freedom)."""
    messages: List[str]
    """Per track: why it was rejected or not started; empty otherwise."""
    # end of fields
    def to_dict(self) -> Dict[str, Any]: ...
    def __len__(self) -> int: ...

@final
class PointTriangulations(BatchReport):
    """The points of :func:`triangulate_points` beside the report columns."""

    # fields of PointTriangulations (generated: python -m pluecker._stubgen)
    __fields__: ClassVar[List[Tuple[str, str, str]]]
    point: NDArray[np.float64]
    """Per track: the point, world frame, shape (n, 3) (NaN for a rejected track)."""
    covariance: NDArray[np.float64]
    """Per track: its 3x3 covariance, shape (n, 3, 3) (NaN where there is none)."""
    inliers: Optional[NDArray[np.bool_]]
    """With `options.outlier_threshold`: which observations each point was solved from, shaped as
    the observations were given ((n, v) dense, (m,) in the rows form with `track=`, `image=`; false
    where not visible or rejected); else `None`.
    """
    # end of fields

@final
class LineTriangulations(BatchReport):
    """The lines of :func:`triangulate_lines` beside the report columns."""

    # fields of LineTriangulations (generated: python -m pluecker._stubgen)
    __fields__: ClassVar[List[Tuple[str, str, str]]]
    plucker: NDArray[np.float64]
    """Per track: Plücker coordinates, shape (n, 6) (NaN for a rejected track)."""
    point: NDArray[np.float64]
    """Per track: the point of the line closest to the origin, shape (n, 3)."""
    direction: NDArray[np.float64]
    """Per track: unit direction, shape (n, 3)."""
    chart_axes: NDArray[np.float64]
    """Per track: the chart axes of `covariance`, shape (n, 2, 3)."""
    covariance: NDArray[np.float64]
    """Per track: 4x4 covariance in the chart, shape (n, 4, 4) (NaN where there is none)."""
    inliers: Optional[NDArray[np.bool_]]
    """With `options.outlier_threshold`: which observations each line was solved from, shaped as the
    observations were given ((n, v) dense, (m,) in the rows form with `track=`, `image=`; false
    where not visible or rejected); else `None`.
    """
    # end of fields

@final
class QuadricTriangulations(BatchReport):
    """The ellipsoids of :func:`triangulate_quadrics` beside the report columns."""

    # fields of QuadricTriangulations (generated: python -m pluecker._stubgen)
    __fields__: ClassVar[List[Tuple[str, str, str]]]
    Q: NDArray[np.float64]
    """Per track: the dual quadric, shape (n, 4, 4) (NaN for a rejected track)."""
    primal: NDArray[np.float64]
    """Per track: the primal quadric, shape (n, 4, 4) (NaN where `Q` is singular)."""
    centre: NDArray[np.float64]
    """Per track: centre, shape (n, 3)."""
    axes: NDArray[np.float64]
    """Per track: principal axes (columns), shape (n, 3, 3)."""
    semi_axes: NDArray[np.float64]
    """Per track: semi-axis lengths, shape (n, 3)."""
    covariance: NDArray[np.float64]
    """Per track: 9x9 covariance, shape (n, 9, 9) (NaN where there is none)."""
    # end of fields

def triangulate_point(
    cameras: _KnownCameras,
    observations: ArrayLike,
    covariances: Optional[ArrayLike] = None,
    *,
    options: Optional[TriangulationOptions] = None,
) -> PointTriangulation:
    """One point from its pixels ``observations`` (n, 2) in the known ``cameras``, n >= 2, with pixel
    covariances ``covariances`` (n, 2, 2) (sections 2.1, 3-4). ``cameras``: (n, 3, 4) matrices
    ``P = K [R | t]``, or n :class:`View` s, whose ``observations`` are the observed (distorted, through
    the lens) pixels: the cost is then the reprojection error through the exact projection."""

def triangulate_points(
    cameras: _KnownCameras,
    observations: ArrayLike,
    visible: Optional[ArrayLike] = None,
    covariances: Optional[ArrayLike] = None,
    *,
    options: Optional[TriangulationOptions] = None,
    progress: Optional[Callable[[int], Any]] = None,
    time_budget: Optional[float] = None,
    track: Optional[ArrayLike] = None,
    image: Optional[ArrayLike] = None,
    n_tracks: Optional[int] = None,
) -> PointTriangulations:
    """Many points seen by the known ``cameras`` ((v, 3, 4) matrices ``P``, or v :class:`View` s in the
    rows form), in one of two forms.

    Dense: pixels ``observations`` (n, v, 2), ``visible`` (n, v) booleans (``None``: every view; NaN is
    fine where not visible), ``covariances`` (n, v, 2, 2).

    Rows (memory in the observations, as COLMAP lists them): with ``track`` and ``image`` (m,), pixel
    ``observations[k]`` (m, 2) of track ``track[k]`` in view ``image[k]``, ``covariances[k]`` (m, 2, 2);
    result row t is track t. Track ids and ``n_tracks`` (default ``max(track) + 1``) are at most the m
    rows given (number sparse ids densely: ``numpy.unique(track, return_inverse=True)``); beyond, or a
        negative id, is an ``InvalidOptionError`` naming the argument. Through views, ``observations`` are
    the observed (distorted) pixels: the cost is the reprojection error through the exact projection."""

def triangulate_line(
    cameras: _KnownCameras,
    lines: ArrayLike,
    covariances: Optional[ArrayLike] = None,
    *,
    sigma: Optional[float] = None,
    options: Optional[TriangulationOptions] = None,
) -> LineTriangulation:
    """One 3-D line (sections 2.2, 3-4) from (n, 3) homogeneous image lines or (n, 2, 2) segments.
    ``covariances`` (n, 2, 2) residual covariances, e.g. :attr:`FittedLine.covariance`; for segments
    without ``covariances``, that of endpoints with noise ``sigma`` px (``None``: 1). ``cameras``: (n, 3, 4)
    matrices ``P``, or n :class:`View` s, through which ``lines`` are (n, 2, 2) segments in the observed (distorted) pixels and ``covariances`` (n, 2, 2, 2)
    their endpoints' covariances:
    through a distorting lens the cost is the endpoints' distances to the line's curved images
    (``cost_kind`` ``'reprojection'``), never certified (``optimal`` gives ``gap_not_closed``); without
    distortion it is eq. 19 on the segments' line residuals (``'line_residual'``), certified."""

def triangulate_lines(
    cameras: _KnownCameras,
    lines: ArrayLike,
    visible: Optional[ArrayLike] = None,
    covariances: Optional[ArrayLike] = None,
    *,
    sigma: Optional[float] = None,
    options: Optional[TriangulationOptions] = None,
    progress: Optional[Callable[[int], Any]] = None,
    time_budget: Optional[float] = None,
    track: Optional[ArrayLike] = None,
    image: Optional[ArrayLike] = None,
    n_tracks: Optional[int] = None,
) -> LineTriangulations:
    """Many 3-D lines, in one of two forms. Dense: ``cameras`` (v, 3, 4) shared or (n, v, 3, 4) per
    track; ``lines`` (n, v, 3) or (n, v, 2, 2); ``visible`` (n, v); ``covariances`` (n, v, 2, 2).

    Rows: with ``track`` and ``image`` (m,), ``lines[k]`` ((m, 3) homogeneous or (m, 2, 2) segments) of
    track ``track[k]`` in image ``image[k]`` (a row of ``cameras``: (v, 3, 4) or v :class:`View` s),
    ``covariances[k]`` (m, 2, 2); track ids and ``n_tracks`` as for :func:`triangulate_points`. Through
    views, ``lines`` are (m, 2, 2) segments in the observed pixels and ``covariances`` (m, 2, 2, 2) their
    endpoints' covariances; each track is solved as :func:`triangulate_line` solves it."""

def triangulate_quadric(
    cameras: _KnownCameras,
    conics: ArrayLike,
    covariances: Optional[ArrayLike] = None,
    *,
    options: Optional[TriangulationOptions] = None,
) -> QuadricTriangulation:
    """One ellipsoid from its outline conics (n, 3, 3) in n >= 3 known ``cameras`` ((n, 3, 4) matrices or
    :class:`View` s), ``covariances`` (n, 5, 5) e.g. :attr:`FittedConic.covariance` (sections 2.3, 3-4).
    A view whose camera distorts is refused (``InvalidOptionError`` naming ``cameras``): the outline
    through a lens is not a conic."""

def triangulate_quadrics(
    cameras: _KnownCameras,
    conics: ArrayLike,
    visible: Optional[ArrayLike] = None,
    covariances: Optional[ArrayLike] = None,
    *,
    options: Optional[TriangulationOptions] = None,
    progress: Optional[Callable[[int], Any]] = None,
    time_budget: Optional[float] = None,
    track: Optional[ArrayLike] = None,
    image: Optional[ArrayLike] = None,
    n_tracks: Optional[int] = None,
) -> QuadricTriangulations:
    """Many ellipsoids, in one of two forms. Dense: ``cameras`` (v, 3, 4) or (n, v, 3, 4); ``conics``
    (n, v, 3, 3); ``covariances`` (n, v, 5, 5). Rows: with ``track`` and ``image`` (m,), ``conics[k]``
    (m, 3, 3) of track ``track[k]`` in image ``image[k]`` (a row of ``cameras``: (v, 3, 4), or v :class:`View` s without distortion),
    ``covariances[k]`` (m, 5, 5); track ids and ``n_tracks`` as for :func:`triangulate_points`."""

# --- Fitting image primitives (section 3.1) -------------------------------------------------------

@final
class FittedLine:
    """An image line fitted to points by :func:`fit_line`."""

    # fields of FittedLine (generated: python -m pluecker._stubgen)
    __fields__: ClassVar[List[Tuple[str, str, str]]]
    line: NDArray[np.float64]
    """The image line `(a, b, c)`, `a u + b v + c = 0`, with `a² + b² = 1`."""
    covariance: NDArray[np.float64]
    """2x2 covariance of the line's residual (section 3.1), px²."""
    rms_distance: float
    """RMS distance of the points to the line, pixels."""
    # end of fields
    def to_dict(self) -> Dict[str, Any]: ...

@final
class FittedConic:
    """An ellipse fitted to points by :func:`fit_conic`."""

    # fields of FittedConic (generated: python -m pluecker._stubgen)
    __fields__: ClassVar[List[Tuple[str, str, str]]]
    conic: NDArray[np.float64]
    """The conic `C` (3x3, symmetric): `(u, v, 1) C (u, v, 1)ᵀ = 0` on the ellipse."""
    centre: NDArray[np.float64]
    """Centre of the ellipse, pixels."""
    axes: NDArray[np.float64]
    """Principal axes of the ellipse, one per column."""
    semi_axes: NDArray[np.float64]
    """Semi-axis lengths along `axes`, pixels."""
    covariance: NDArray[np.float64]
    """5x5 covariance of the conic's residual (section 3.1)."""
    iterations: int
    """Iterations of the geometric fit."""
    # end of fields
    def to_dict(self) -> Dict[str, Any]: ...

def fit_line(points: ArrayLike, sigma: Optional[float] = None) -> FittedLine:
    """Total-least-squares line through points (N, 2), N >= 2, with its residual covariance for
    point noise ``sigma`` px (``None``: 1)."""

def lines_from_endpoints(segments: ArrayLike, covariances: ArrayLike) -> Tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Lines (M, 3) through segments (M, 2, 2) whose endpoints have covariances ``covariances``
    (M, 2, 2, 2), px², and the covariances (M, 2, 2) of their residuals: the ``lines`` and
    ``covariances`` of :func:`triangulate_line`."""

def fit_conic(points: ArrayLike, sigma: Optional[float] = None) -> FittedConic:
    """Ellipse through points (N, 2), N >= 5, with its residual covariance for point noise ``sigma``
    px (``None``: 1)."""

class _ResidualSamples(TypedDict):
    line: NDArray[np.float64]
    line_whitened: NDArray[np.float64]
    conic: NDArray[np.float64]
    conic_whitened: NDArray[np.float64]

def fitting_residual_samples(
    draws: int, size: Optional[float] = None, sigma: Optional[float] = None, seed: Optional[int] = None
) -> _ResidualSamples:
    """The residual samples of Figures 1-2 (section 3.1): ``draws`` images of ``size`` px (``None``:
    1000), noise ``sigma`` px (``None``: 1), seeded (``None``: 0)."""
