"""Section 5 of Phong, Horaud, Yassine & Tao 1995, "Object pose from 2-D to 3-D point and line
correspondences" (IJCV 15:225-243), re-run in simulation.

The paper calibrates a real camera on a 460-point object with the linear method of Faugeras & Toscani,
takes that solution as ground truth, and compares estimators on random subsets of the correspondences
(Tables 1-8, Figures 5-7) and under matching errors (section 5.1, Figures 8-9). Here the ground truth
is the paper's pose and intrinsics (:func:`pluecker.paper_scene`), the image points are its exact
projections, and every perturbation is drawn with ``numpy.random.default_rng``:

* **count sweep** (Tables 1, 3, 5, 7; Figures 5-7 left): ``n`` of the 460 points chosen at random, uniform
  pixel noise of maximum amplitude 0.1 px (the accuracy of the paper's measured image points);
  the line estimators get the ``n/2`` lines through consecutive pairs of those points (Figure 2).
* **noise sweep** (Tables 2, 4, 6, 8 and the solver comparison; Figures 5-7 right): 100 points
  (50 lines), uniform noise of maximum amplitude ``a`` in each pixel coordinate.
* **mismatch sweep** (Figure 9): 400 points (200 lines), 0.1 px noise, and ``k`` point mismatched
  pairs: the image points of two points on two different lines are swapped, which also makes a line
  mismatched pair (Figure 8). The robust estimator (``estimate_pose(..., options=PoseOptions(ransac=RansacOptions()))``: LO-RANSAC over
  minimal samples, then the refinement on the inliers) is the third curve of Figure 9.
* **outlier sweep** (not in the paper): 100 points, 0.1 px noise, and a fraction ``f`` (0 to 80 %) of the
  image points replaced by points drawn uniformly in the bounding box of the 460 true image points, for the
  linear method, the default pipeline and the robust estimator.

Each cell is the mean over ``trials`` independent draws. A draw depends only on the seed, the sweep,
the trial and (count sweep only) the value, so every estimator sees the same data, the noise and
mismatch sweeps vary only the noise amplitude or the number of swaps within a trial (as the paper
degrades one 100-point subset), and ``--quick`` cells equal the matching cells of a full run.
The paper's estimators run alone (``refine=False``); the default pipeline (``refine=True``: the same
estimator followed by reprojection refinement) is reported beside them. The tables of the paper's
estimators print the paper's own values (:data:`PAPER_TABLES`, Tables 1-8 transcribed) beside our means,
in the same rows, with why they differ (:data:`PAPER_DIFFERENCE`).
"""

from __future__ import annotations

import json
import sys
import time
import zlib
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Callable, Sequence

import numpy as np
from tqdm import tqdm

import pluecker
from pluecker._paths import staged
from pluecker.experiments import Report

NAME = "phong-horaud-1995"
DEFAULT_OUT = Path("results") / NAME

POINT_COUNTS = (10, 20, 40, 60, 80, 100, 200, 300, 400, 460)
NOISE_LEVELS = (0.0, 0.01, 0.05, 0.1, 0.5, 1.0, 1.5, 2.0, 3.0, 4.0, 5.0)
MISMATCH_COUNTS = tuple(range(11))
OUTLIER_FRACTIONS = (0.0, 0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8)
OUTLIER_SWEEP_POINTS = 100
COUNT_SWEEP_NOISE_PX = 0.1
NOISE_SWEEP_POINTS = 100
MISMATCH_POINTS = 400
DEFAULT_TRIALS = 100

# A trial "fails" when the estimator raises, returns a non-success status or a non-finite pose, or
# ends grossly far from the truth (the object is ~20 cm across, 77 cm away).
FAIL_TRANSLATION_CM = 5.0
FAIL_AXIS = 0.1


# --------------------------------------------------------------------------------------------------
# Settings, truth, data


@dataclass(frozen=True)
class Settings:
    """What to run: the sweep values and the number of trials per cell."""

    trials: int = DEFAULT_TRIALS
    seed: int = 0
    quick: bool = False
    point_counts: tuple[int, ...] = POINT_COUNTS
    noise_levels: tuple[float, ...] = NOISE_LEVELS
    mismatch_counts: tuple[int, ...] = MISMATCH_COUNTS
    outlier_fractions: tuple[float, ...] = OUTLIER_FRACTIONS

    @classmethod
    def create(cls, trials: int | None = None, seed: int = 0, quick: bool = False) -> Settings:
        """The full experiment, or with ``quick`` a reduced one (3 values per sweep, 10 trials)."""
        if not quick:
            return cls(trials=trials or DEFAULT_TRIALS, seed=seed)
        return cls(
            trials=trials or 10,
            seed=seed,
            quick=True,
            point_counts=(20, 100, 460),
            noise_levels=(0.0, 1.0, 3.0),
            mismatch_counts=(0, 5, 10),
            outlier_fractions=(0.0, 0.5, 0.8),
        )


@dataclass(frozen=True)
class Truth:
    """The paper's ground truth: camera, pose (axis, angle, translation) and all 460 points."""

    camera: pluecker.Camera
    R: np.ndarray
    t: np.ndarray
    axis: np.ndarray
    angle: float
    points3d: np.ndarray
    points2d: np.ndarray

    @classmethod
    def load(cls) -> Truth:
        s = pluecker.paper_scene()
        axis, angle = _axis_angle(np.asarray(s["R"]))
        return cls(s["camera"], np.asarray(s["R"]), np.asarray(s["t"]), axis, angle,
                   np.asarray(s["points3d"]), np.asarray(s["points2d"]))


@dataclass(frozen=True)
class Observation:
    """The data handed to an estimator: points, and lines through consecutive pairs of them."""

    points2d: np.ndarray
    points3d: np.ndarray

    @property
    def lines2d(self) -> np.ndarray:
        m = len(self.points2d) // 2
        return self.points2d[: 2 * m].reshape(m, 2, 2)

    @property
    def lines3d(self) -> np.ndarray:
        m = len(self.points3d) // 2
        return self.points3d[: 2 * m].reshape(m, 2, 3)


def _axis_angle(R: np.ndarray) -> tuple[np.ndarray, float]:
    """Unit axis and angle in [0, π] of a rotation matrix (the convention of ``PoseResult``)."""
    angle = float(np.arccos(np.clip((np.trace(R) - 1.0) / 2.0, -1.0, 1.0)))
    w, v = np.linalg.eigh(R + R.T)  # the axis is the eigenvector of eigenvalue 2
    axis = v[:, np.argmax(w)]
    skew = np.array([R[2, 1] - R[1, 2], R[0, 2] - R[2, 0], R[1, 0] - R[0, 1]])
    if axis @ skew < 0:
        axis = -axis
    return axis, angle


def rng_for(seed: int, sweep: str, value: float, trial: int) -> np.random.Generator:
    """The generator of one draw; it depends only on the seed, the sweep, the value and the trial."""
    return np.random.default_rng([seed, zlib.crc32(sweep.encode()), int(round(value * 1000)), trial])


def draw_observation(
    truth: Truth, rng: np.random.Generator, n_points: int, noise_px: float, mismatched_pairs: int = 0,
    outlier_fraction: float = 0.0,
) -> Observation:
    """``n_points`` of the truth's points in random order, uniform pixel noise of maximum amplitude
    ``noise_px`` per coordinate, ``mismatched_pairs`` swaps of image points between two points
    that lie on two different lines (lines join points ``2i`` and ``2i+1``), and
    ``round(outlier_fraction * n_points)`` image points replaced by points drawn uniformly in the
    bounding box of all the truth's image points."""
    index = rng.permutation(len(truth.points3d))[:n_points]
    points2d = truth.points2d[index] + rng.uniform(-noise_px, noise_px, size=(n_points, 2))
    n_outliers = int(round(outlier_fraction * n_points))
    if n_outliers:
        low, high = truth.points2d.min(axis=0), truth.points2d.max(axis=0)
        points2d[rng.permutation(n_points)[:n_outliers]] = rng.uniform(low, high, size=(n_outliers, 2))
    if mismatched_pairs:
        while True:
            chosen = rng.choice(n_points - n_points % 2, size=2 * mismatched_pairs, replace=False)
            a, b = chosen[0::2], chosen[1::2]
            if np.all(a // 2 != b // 2):
                break
        points2d[a], points2d[b] = points2d[b].copy(), points2d[a].copy()
    return Observation(points2d, truth.points3d[index].copy())


# --------------------------------------------------------------------------------------------------
# Estimators and scores


@dataclass(frozen=True)
class Estimator:
    """One way of estimating the pose: a method, the data it is given, and whether to refine."""

    method: str
    data: str  # "points" or "lines"
    refine: bool = False
    robust: bool = False  # LO-RANSAC first (the refinement then runs on its inliers)

    @property
    def key(self) -> str:
        return f"{self.method}/{self.data}" + ("/robust" if self.robust else "/refined" if self.refine else "")

    @property
    def label(self) -> str:
        if self.robust:
            return f"robust (LO-RANSAC + {self.method} refinement), {self.data}"
        name = "linear (Faugeras-Toscani)" if self.method == "linear" else self.method
        return f"{name}, {self.data}" + (" + refinement" if self.refine else "")

    def refined(self) -> Estimator:
        return replace(self, refine=True)


LINEAR = Estimator("linear", "points")
RTT_LINES = Estimator("rotation-then-translation", "lines")
TR_LINES = Estimator("trust-region", "lines")
TR_POINTS = Estimator("trust-region", "points")
ROBUST_POINTS = Estimator("trust-region", "points", refine=True, robust=True)
SOLVER_COMPARISON = (
    TR_POINTS,
    Estimator("trust-region-exact", "points"),
    Estimator("levenberg-marquardt", "points"),
    Estimator("newton", "points"),
)

METRICS = ("axis", "angle", "translation", "img_max", "img_min", "img_mean",
           "iterations", "time_ms", "u0", "v0", "alpha_u", "alpha_v")


@dataclass
class Score:
    """The errors of one estimate (NaN where there is no estimate) and whether it failed."""

    values: dict[str, float]
    failed: bool
    error: str = ""


def run_and_score(truth: Truth, obs: Observation, est: Estimator) -> Score:
    """Runs ``est`` on ``obs`` and measures it as the paper does: axis ``‖r − r0‖``, angle ``|φ − φ0|``,
    translation ``‖t − t0‖`` (cm), and the pixel distances between the true projections of all 460
    points and their projections by the estimate (largest, smallest, average). The linear method is
    scored with the intrinsics it estimates, as in the paper; the others with the known camera."""
    nan = dict.fromkeys(METRICS, float("nan"))
    data = ({"points2d": obs.points2d, "points3d": obs.points3d} if est.data == "points"
            else {"lines2d": obs.lines2d, "lines3d": obs.lines3d})
    try:
        ransac = pluecker.RansacOptions(seed=0) if est.robust else None
        res = pluecker.estimate_pose(truth.camera, **data, options=pluecker.PoseOptions(refine=est.refine, method=est.method, ransac=ransac))
    except pluecker.PlueckerError as exc:
        return Score(nan, failed=True, error=f"{type(exc).__name__}: {exc}")
    R, t = np.asarray(res.pose.rotation), np.asarray(res.pose.translation)
    values = dict(nan, iterations=float(res.iterations), time_ms=1000.0 * res.time_seconds)
    if not (np.all(np.isfinite(R)) and np.all(np.isfinite(t))):
        return Score(values, failed=True, error=f"non-finite pose ({res.status})")
    camera = res.details.estimated_camera or truth.camera
    if res.details.estimated_camera is not None:
        values.update(u0=camera.cx, v0=camera.cy, alpha_u=camera.fx, alpha_v=camera.fy)
    projected = camera.project(truth.points3d @ R.T + t)
    distances = np.linalg.norm(projected - truth.points2d, axis=1)
    values.update(
        axis=float(np.linalg.norm(res.pose.axis_angle()[0] - truth.axis)),
        angle=abs(res.pose.axis_angle()[1] - truth.angle),
        translation=float(np.linalg.norm(t - truth.t)),
        img_max=float(distances.max()),
        img_min=float(distances.min()),
        img_mean=float(distances.mean()),
    )
    failed = (res.status != "success" or values["translation"] > FAIL_TRANSLATION_CM
              or values["axis"] > FAIL_AXIS)
    return Score(values, failed=failed, error="" if res.status == "success" else res.status)


@dataclass
class Cell:
    """The scores of one estimator at one sweep value, over all trials."""

    scores: list[Score] = field(default_factory=list)

    def mean(self, metric: str) -> float:
        v = np.array([s.values[metric] for s in self.scores])
        v = v[np.isfinite(v)]
        return float(v.mean()) if v.size else float("nan")

    def median(self, metric: str) -> float:
        v = np.array([s.values[metric] for s in self.scores])
        v = v[np.isfinite(v)]
        return float(np.median(v)) if v.size else float("nan")

    @property
    def failures(self) -> int:
        return sum(s.failed for s in self.scores)

    def to_dict(self) -> dict:
        return {
            "trials": len(self.scores),
            "failures": self.failures,
            "mean": {m: _json_number(self.mean(m)) for m in METRICS},
            "median": {m: _json_number(self.median(m)) for m in METRICS},
            "errors": sorted({s.error for s in self.scores if s.error}),
        }


def _json_number(x: float) -> float | None:
    return x if np.isfinite(x) else None


def _json_clean(value):
    """NaN and inf as ``null``, numpy scalars as numbers, tuples as lists (strict JSON)."""
    if isinstance(value, dict):
        return {str(k): _json_clean(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_json_clean(v) for v in value]
    if isinstance(value, (float, np.floating)):
        return _json_number(float(value))
    if isinstance(value, np.bool_):
        return bool(value)
    return value


# --------------------------------------------------------------------------------------------------
# Sweeps


@dataclass(frozen=True)
class Sweep:
    """A family of draws indexed by one value, and the estimators run on every draw.

    ``paired``: trial ``i`` uses the same random numbers at every value (common random numbers), so
    the values differ only by what the sweep varies: the same 100 points and noise pattern scaled to
    each amplitude (as the paper's single 100-point subset), or the same 400 points with more swaps.
    """

    key: str
    values: tuple[float, ...]
    draw: Callable[[Truth, np.random.Generator, float], Observation]
    estimators: tuple[Estimator, ...]
    paired: bool = False

    def observation(self, truth: Truth, seed: int, value: float, trial: int) -> Observation:
        return self.draw(truth, rng_for(seed, self.key, 0 if self.paired else value, trial), value)


def _sweeps(settings: Settings) -> list[Sweep]:
    paper = (LINEAR, RTT_LINES, TR_LINES, TR_POINTS)
    refined = tuple(e.refined() for e in paper[1:])
    return [
        Sweep("count", settings.point_counts,
              lambda truth, rng, n: draw_observation(truth, rng, int(n), COUNT_SWEEP_NOISE_PX),
              paper + refined),
        Sweep("noise", settings.noise_levels,
              lambda truth, rng, a: draw_observation(truth, rng, NOISE_SWEEP_POINTS, a),
              paper + refined + SOLVER_COMPARISON[1:], paired=True),
        Sweep("mismatch", settings.mismatch_counts,
              lambda truth, rng, k: draw_observation(truth, rng, MISMATCH_POINTS, COUNT_SWEEP_NOISE_PX, int(k)),
              (LINEAR, RTT_LINES, TR_POINTS, ROBUST_POINTS), paired=True),
        Sweep("outliers", settings.outlier_fractions,
              lambda truth, rng, f: draw_observation(truth, rng, OUTLIER_SWEEP_POINTS, COUNT_SWEEP_NOISE_PX,
                                                     outlier_fraction=f),
              (LINEAR, TR_POINTS.refined(), ROBUST_POINTS), paired=True),
    ]


Results = dict[str, dict[str, dict[float, Cell]]]  # sweep key -> estimator key -> value -> cell


def run_sweeps(truth: Truth, settings: Settings, progress: tqdm | None = None) -> Results:
    """Every estimator of every sweep on every draw."""
    results: Results = {}
    for sweep in _sweeps(settings):
        cells = results[sweep.key] = {e.key: {v: Cell() for v in sweep.values} for e in sweep.estimators}
        for value in sweep.values:
            if progress is not None:
                progress.set_postfix_str(f"{sweep.key} {value:g}")
            for trial in range(settings.trials):
                obs = sweep.observation(truth, settings.seed, value, trial)
                for est in sweep.estimators:
                    cells[est.key][value].scores.append(run_and_score(truth, obs, est))
                if progress is not None:
                    progress.update(len(sweep.estimators))
    return results


def count_estimates(settings: Settings) -> int:
    return sum(len(s.values) * len(s.estimators) for s in _sweeps(settings)) * settings.trials


# --------------------------------------------------------------------------------------------------
# Tables

@dataclass(frozen=True)
class Column:
    """A table column: a metric, its statistic over the trials ("mean" or "median"), its format."""

    header: str
    metric: str
    fmt: str = ".3g"
    stat: str = "mean"
    paper_header: str = ""  # the header when a cell reads "ours / paper", if it differs

    @property
    def header_beside_paper(self) -> str:
        return self.paper_header or self.header

    def cell(self, cell: Cell) -> str:
        value = cell.mean(self.metric) if self.stat == "mean" else cell.median(self.metric)
        return "–" if not np.isfinite(value) else format(value, self.fmt)


TRANSFORMATION = (Column("axis", "axis"), Column("angle (rad)", "angle"), Column("translation (cm)", "translation"))
IMAGE = (Column("largest (px)", "img_max"), Column("smallest (px)", "img_min"), Column("average (px)", "img_mean"))
MEDIAN_TRANSLATION = Column("median translation (cm)", "translation", stat="median")
INTRINSICS = (Column("u0", "u0", ".1f"), Column("v0", "v0", ".1f"), Column("αu", "alpha_u", ".1f"),
              Column("αv", "alpha_v", ".1f"))
PERFORMANCE = (Column("iterations", "iterations", ".1f"),
               Column("time (ms)", "time_ms", ".2g", paper_header="time (ours ms / paper s)"))


# --------------------------------------------------------------------------------------------------
# The paper's own values

# Columns of the paper's tables, named as ours (``time_ms`` holds the paper's "CPU time", in seconds
# on a Sun/Sparc10: Table 3's caption).
_LINEAR_COLUMNS = ("axis", "angle", "translation", "img_max", "img_min", "img_mean", "u0", "v0", "alpha_u", "alpha_v")
_NONLINEAR_COLUMNS = ("axis", "angle", "translation", "img_max", "img_min", "img_mean", "iterations", "time_ms")


def _paper_rows(columns: Sequence[str], text: str) -> dict[str, dict[str, str]]:
    """A table as printed in the paper (one row a line, first column then ``columns``), keyed by its first
    column; the numbers stay text so they print exactly as the paper does."""
    rows = {}
    for line in text.strip().splitlines():
        first, *cells = line.split()
        if len(cells) != len(columns):
            raise ValueError(f"paper table row {first!r}: {len(cells)} values for {len(columns)} columns")
        rows[first] = dict(zip(columns, cells))
    return rows


#: Tables 1-8 of the paper, transcribed from its text. Each row is one run of the estimator on one
#: random subset of the measured points; the errors are against the paper's ground truth, the linear
#: solution with all 460 points. Rows are keyed as our tables label them (points, lines, or noise in px).
PAPER_TABLES: dict[str, dict[str, dict[str, str]]] = {
    # Table 1: the linear method of Faugeras & Toscani vs the number of points (460: the truth itself).
    "1": _paper_rows(_LINEAR_COLUMNS, """
    10 0.0170 0.0032 2.4277 0.9754 0.0008 0.2150 243.1 224.3 -1677.8 1183.2
    20 0.0064 0.0143 3.2806 1.0983 0.0002 0.1912 269.0 233.2 -1663.5 1173.5
    40 0.0016 0.0047 0.8157 1.0935 0.0018 0.1577 235.2 238.3 -1715.7 1209.6
    60 0.0009 0.0015 0.2563 0.7255 0.0007 0.1508 239.9 242.9 -1734.2 1223.2
    80 0.0024 0.0038 0.6620 0.9277 0.0001 0.1500 235.9 245.5 -1741.8 1229.0
    100 0.0020 0.0003 0.1727 0.6431 0.0006 0.1500 245.6 238.8 -1730.3 1221.0
    200 0.0011 0.0001 0.2249 0.7806 0.0001 0.1444 243.6 243.5 -1734.6 1223.8
    300 0.0015 0.0016 0.3334 0.7471 0.0010 0.1425 246.0 244.1 -1736.8 1225.1
    400 0.0002 0.0001 0.0147 0.6979 0.0000 0.1444 244.1 241.2 -1730.1 1220.5
    460 0.0000 0.0000 0.0000 0.6987 0.0006 0.1446 243.8 241.2 -1730.3 1220.7
    """),
    # Table 2: the linear method, 100 points, vs the maximum noise amplitude (px).
    "2": _paper_rows(_LINEAR_COLUMNS, """
    0.00 0.0023 0.0006 0.3333 0.5997 0.0008 0.1461 244.0 236.5 -1726.2 1217.6
    0.01 0.0042 0.0035 0.6013 1.1291 0.0002 0.1574 235.2 246.8 -1738.3 1225.9
    0.05 0.0014 0.0006 0.0970 0.7807 0.0011 0.1460 245.2 242.1 -1731.9 1221.9
    0.10 0.0018 0.0029 0.4556 0.8290 0.0009 0.1463 239.4 238.7 -1721.9 1214.7
    0.50 0.0103 0.0046 0.9617 0.7590 0.0016 0.1589 241.8 230.2 -1714.2 1208.9
    1.00 0.0198 0.0177 11.4770 2.2091 0.0022 0.3827 222.0 198.4 -1478.2 1042.3
    1.50 0.0414 0.0306 17.8853 3.3508 0.0028 0.6589 226.5 159.7 -1336.2 938.9
    2.00 0.0460 0.0578 23.1873 4.3128 0.0022 1.0022 197.4 152.6 -1218.2 856.5
    3.00 0.1774 0.0583 44.3465 13.9919 0.0368 2.6464 194.2 156.3 -734.1 510.7
    4.00 1.2958 0.0339 55.6320 32.0500 0.0171 5.6593 160.2 141.1 -441.4 303.9
    5.00 0.7169 0.0753 61.1560 45.8325 0.0312 7.9906 201.9 185.8 -336.3 231.2
    """),
    # Table 3: rotation then translation, lines, vs the number of lines; CPU time in seconds on a Sun/Sparc10.
    "3": _paper_rows(_NONLINEAR_COLUMNS, """
    5 0.0034 0.0005 0.0056 0.9421 0.0106 0.2870 10 0.12
    10 0.0047 0.0008 0.0156 0.9049 0.0098 0.2127 7 0.03
    20 0.0042 0.0012 0.0037 0.6071 0.0020 0.1804 6 0.02
    30 0.0038 0.0004 0.0038 0.7150 0.0117 0.1775 6 0.03
    40 0.0036 0.0001 0.0025 0.6534 0.0060 0.1856 7 0.05
    50 0.0036 0.0005 0.0042 0.7525 0.0105 0.1872 6 0.07
    100 0.0037 0.0001 0.0013 0.6784 0.0022 0.1702 6 0.12
    150 0.0036 0.0003 0.0001 0.6067 0.0078 0.1667 6 0.17
    200 0.0037 0.0004 0.0000 0.5468 0.0098 0.1658 6 0.22
    230 0.0035 0.0004 0.0004 0.6010 0.0086 0.1669 6 0.25
    """),
    # Table 4: rotation then translation, 50 lines, vs the maximum noise amplitude (px).
    "4": _paper_rows(_NONLINEAR_COLUMNS, """
    0.00 0.0034 0.0005 0.0001 0.5653 0.0121 0.1675 6 0.07
    0.01 0.0039 0.0005 0.0007 0.6794 0.0105 0.1729 6 0.07
    0.05 0.0038 0.0010 0.0010 0.5823 0.0126 0.1696 6 0.07
    0.10 0.0039 0.0003 0.0016 0.7211 0.0025 0.1732 6 0.07
    0.50 0.0034 0.0005 0.0028 0.7690 0.0129 0.2016 7 0.07
    1.00 0.0034 0.0004 0.0024 0.6709 0.0038 0.2620 6 0.05
    1.50 0.0040 0.0008 0.1024 1.7369 0.0470 0.5088 6 0.05
    2.00 0.0038 0.0001 0.1326 1.6247 0.0276 0.5777 6 0.07
    3.00 0.0042 0.0014 0.4713 2.9518 0.0805 1.1266 6 0.07
    4.00 0.0033 0.0013 0.1499 2.0029 0.0162 0.7612 6 0.07
    5.00 0.0034 0.0015 0.1055 2.2339 0.3024 1.1693 6 0.05
    """),
    # Table 5: rotation and translation (trust region), lines, vs the number of lines.
    "5": _paper_rows(_NONLINEAR_COLUMNS, """
    5 0.0151 0.0316 1.7323 6.3106 0.1415 2.9870 3 0.05
    10 0.0036 0.0018 0.0014 0.6187 0.0063 0.1948 18 0.13
    20 0.0040 0.0021 0.0023 0.5790 0.0055 0.1830 30 0.33
    30 0.0035 0.0021 0.0032 0.7203 0.0134 0.1933 23 0.35
    40 0.0034 0.0007 0.0018 0.6408 0.0132 0.1881 23 0.45
    50 0.0034 0.0004 0.0026 0.7202 0.0049 0.1890 24 0.53
    100 0.0037 0.0002 0.0017 0.6992 0.0052 0.1726 14 0.65
    150 0.0037 0.0002 0.0004 0.6320 0.0094 0.1686 19 1.28
    200 0.0035 0.0003 0.0004 0.5415 0.0054 0.1666 8 0.57
    230 0.0036 0.0003 0.0009 0.6380 0.0078 0.1680 8 0.67
    """),
    # Table 6: rotation and translation, 50 lines, vs the maximum noise amplitude (px).
    "6": _paper_rows(_NONLINEAR_COLUMNS, """
    0.00 0.0033 0.0008 0.0003 0.4916 0.0096 0.1706 11 0.27
    0.01 0.0038 0.0000 0.0004 0.6495 0.0045 0.1720 21 0.48
    0.05 0.0041 0.0008 0.0028 0.6654 0.0031 0.1768 22 0.55
    0.10 0.0037 0.0007 0.0009 0.6408 0.0086 0.1690 21 0.53
    0.50 0.0040 0.0030 0.0050 1.0173 0.0128 0.2381 10 0.20
    1.00 0.0057 0.0028 0.0421 1.3253 0.0055 0.3742 34 0.87
    1.50 0.0033 0.0010 0.0553 1.4390 0.0206 0.4949 22 0.52
    2.00 0.0039 0.0081 0.0798 1.6826 0.0354 0.6471 21 0.52
    3.00 0.0032 0.0083 0.3092 2.9927 0.0842 1.0871 25 0.67
    4.00 0.0048 0.0213 0.6658 3.3989 0.0473 1.1541 22 0.57
    5.00 0.0065 0.0222 0.5787 4.0622 0.0557 1.3912 22 0.52
    """),
    # Table 7: rotation and translation (trust region), points, vs the number of points.
    "7": _paper_rows(_NONLINEAR_COLUMNS, """
    10 0.0032 0.0010 0.0171 0.6706 0.0015 0.2186 24 0.32
    20 0.0033 0.0012 0.0001 0.5503 0.0051 0.1780 10 0.18
    40 0.0035 0.0000 0.0000 0.5747 0.0189 0.1709 9 0.37
    60 0.0035 0.0002 0.0002 0.5220 0.0115 0.1665 9 0.45
    80 0.0035 0.0000 0.0002 0.5201 0.0163 0.1657 9 0.55
    100 0.0035 0.0003 0.0001 0.5747 0.0112 0.1675 9 0.70
    200 0.0036 0.0003 0.0000 0.5385 0.0109 0.1652 9 1.62
    300 0.0035 0.0003 0.0004 0.5168 0.0054 0.1666 10 2.88
    400 0.0035 0.0002 0.0002 0.5385 0.0158 0.1657 10 4.00
    460 0.0035 0.0001 0.0001 0.5427 0.0228 0.1654 10 4.83
    """),
    # Table 8: rotation and translation, 100 points, vs the maximum noise amplitude (px).
    "8": _paper_rows(_NONLINEAR_COLUMNS, """
    0.00 0.0034 0.0004 0.0012 0.4761 0.0121 0.1708 9 0.77
    0.01 0.0035 0.0003 0.0008 0.5356 0.0091 0.1678 9 0.72
    0.05 0.0035 0.0000 0.0001 0.5414 0.0096 0.1656 9 0.80
    0.10 0.0038 0.0004 0.0004 0.5877 0.0105 0.1664 9 0.72
    0.50 0.0034 0.0002 0.0001 0.5635 0.0069 0.1823 9 0.80
    1.00 0.0039 0.0005 0.0002 0.6765 0.0108 0.2026 9 0.78
    1.50 0.0036 0.0023 0.0024 0.7637 0.0062 0.2046 9 0.80
    2.00 0.0047 0.0114 0.0014 1.3642 0.0173 0.4545 9 0.70
    3.00 0.0059 0.0020 0.0482 1.0298 0.0289 0.3472 9 0.80
    4.00 0.0043 0.0004 0.0001 1.0785 0.0214 0.3643 10 0.93
    5.00 0.0070 0.0078 0.3820 2.3401 0.0551 0.8375 10 0.83
    """),
}

PAPER_DIFFERENCE = (
    "The paper's values are single trials, one random subset of its measured image points (accurate to 0.1 px) "
    "per row, scored against its own linear 460-point solution taken as the truth and, for the image errors, "
    "against the measured points themselves; ours are means over {n} simulated trials scored against the exact "
    "pose and the exact projections, on a synthetic object with the paper's pose and intrinsics, so the trends "
    "compare, the digits do not."
)
PAPER_TIMES = ("The paper's CPU times are seconds on a Sun/Sparc10 (Table 3's caption; Tables 4-8 have the same "
               "column); ours are milliseconds of wall-clock time on this machine.")


@dataclass(frozen=True)
class TableSpec:
    number: str
    sweep: str
    estimator: Estimator
    caption: str

    @property
    def columns(self) -> tuple[Column, ...]:
        last = INTRINSICS if self.estimator.method == "linear" else PERFORMANCE
        return TRANSFORMATION + IMAGE + last


TABLES = (
    TableSpec("1", "count", LINEAR, "Linear method of Faugeras & Toscani vs number of points."),
    TableSpec("2", "noise", LINEAR, "Linear method, 100 points, vs image noise."),
    TableSpec("3", "count", RTT_LINES, "Rotation-then-translation with line correspondences vs number of lines."),
    TableSpec("4", "noise", RTT_LINES, "Rotation-then-translation, 50 lines, vs image noise."),
    TableSpec("5", "count", TR_LINES, "Rotation-and-translation (trust region) with lines vs number of lines."),
    TableSpec("6", "noise", TR_LINES, "Rotation-and-translation with lines, 50 lines, vs image noise."),
    TableSpec("7", "count", TR_POINTS, "Rotation-and-translation (trust region) with points vs number of points."),
    TableSpec("8", "noise", TR_POINTS, "Rotation-and-translation with points, 100 points, vs image noise."),
)


def _row_label(sweep: str, est: Estimator, value: float) -> str:
    if sweep == "count" and est.data == "lines":
        return str(int(value) // 2)
    if sweep == "outliers":
        return f"{100 * value:.0f}"
    return f"{value:g}" if sweep != "noise" else f"{value:.2f}"


def _first_header(sweep: str, est: Estimator) -> str:
    if sweep == "count":
        return "lines" if est.data == "lines" else "points"
    return {"noise": "noise (px)", "mismatch": "mismatched pairs", "outliers": "outliers (%)"}[sweep]


def markdown_table(headers: Sequence[str], rows: Sequence[Sequence[str]]) -> str:
    lines = ["| " + " | ".join(headers) + " |", "|" + "|".join("---:" for _ in headers) + "|"]
    lines += ["| " + " | ".join(r) + " |" for r in rows]
    return "\n".join(lines)


def estimator_table(cells: dict[float, Cell], sweep: str, est: Estimator, columns: Sequence[Column]) -> str:
    headers = [_first_header(sweep, est), *(c.header for c in columns), "failures"]
    rows = [[_row_label(sweep, est, v), *(c.cell(cell) for c in columns),
             f"{cell.failures}/{len(cell.scores)}"] for v, cell in cells.items()]
    return markdown_table(headers, rows)


def table_beside_paper(cells: dict[float, Cell], sweep: str, est: Estimator, columns: Sequence[Column],
                       paper: dict[str, dict[str, str]]) -> str:
    """Our means and the paper's values in the same rows, each cell reading "ours / paper"; the rows are
    those of both (a quick run has fewer than the paper), "–" where one side has no value."""
    ours = {_row_label(sweep, est, v): cell for v, cell in cells.items()}
    headers = [_first_header(sweep, est), *(c.header_beside_paper for c in columns), "failures (ours)"]
    rows = []
    for label in sorted(ours.keys() | paper.keys(), key=float):
        cell, printed = ours.get(label), paper.get(label, {})
        rows.append([label, *(f"{c.cell(cell) if cell else '–'} / {printed.get(c.metric, '–')}" for c in columns),
                     f"{cell.failures}/{len(cell.scores)}" if cell else "–"])
    return markdown_table(headers, rows)


def comparison_table(results: Results, sweep: str, estimators: Sequence[Estimator],
                     columns: Sequence[Column]) -> str:
    """One row per (estimator, value): the solver comparison and the Figure 9 data."""
    headers = ["method", _first_header(sweep, estimators[0]), *(c.header for c in columns), "failures"]
    rows = []
    for est in estimators:
        for value, cell in results[sweep][est.key].items():
            rows.append([est.label, _row_label(sweep, est, value),
                         *(c.cell(cell) for c in columns),
                         f"{cell.failures}/{len(cell.scores)}"])
    return markdown_table(headers, rows)


def render_tables(results: Results, settings: Settings) -> str:
    n = settings.trials
    failures = (f"'failures' counts the trials that raised, returned a non-success status, or ended more than "
                f"{FAIL_TRANSLATION_CM:g} cm or {FAIL_AXIS:g} (axis error) from the truth.")
    mean_note = f"Each cell is the **mean over {n} trials**; 'failures' as defined at the top."
    out = [
        "# Phong, Horaud, Yassine & Tao 1995, section 5, in simulation",
        "",
        f"Seed {settings.seed}, {n} trials per cell{', quick run' if settings.quick else ''}. Ground truth: the "
        "paper's pose and intrinsics and a 460-point object (`pluecker.paper_scene()`); image points are exact "
        "projections plus uniform noise of the given maximum amplitude in each coordinate (0.1 px for the "
        "count tables, like the paper's measured points). Lines join consecutive pairs of the chosen points "
        "(Figure 2). Errors: axis ‖r − r0‖, angle |φ − φ0| (rad), translation ‖t − t0‖ (cm); image errors are "
        "pixel distances between the true projections of all 460 points and their projections by the "
        "estimate (the linear method with its own estimated intrinsics, the others with the known ones). "
        "Iterations are `PoseResult.iterations`: summed over the stages of an estimate and over the starts "
        "of the library's default initialisation. Times are wall-clock on this machine.",
        "",
        f"Each cell is the **mean over {n} trials**, each with its own random subset and noise. {failures}",
    ]
    for spec in TABLES:
        est = spec.estimator
        times = f" {PAPER_TIMES}" if est.method != "linear" else ""
        out += ["", f"## Table {spec.number}: {spec.caption}", "",
                f"Paper's estimator alone (`method=\"{est.method}\", refine=False`), {est.data}. Each cell reads "
                f"**ours / paper**: our mean over {n} trials ('failures' as defined at the top), then the value of "
                f"the paper's Table {spec.number} as printed ('–' where a side has no such row). "
                f"{PAPER_DIFFERENCE.format(n=n)}{times}", "",
                table_beside_paper(results[spec.sweep][est.key], spec.sweep, est, spec.columns,
                                   PAPER_TABLES[spec.number])]
        if est.method != "linear":
            out += ["", f"Default pipeline: the same estimator followed by reprojection refinement "
                        f"(`refine=True`); iterations include the refinement's. The paper has no such stage. "
                        f"{mean_note}", "",
                    estimator_table(results[spec.sweep][est.refined().key], spec.sweep, est.refined(),
                                    spec.columns)]
    out += ["", "## Extra table: solvers of section 4 on points, 100 points, vs image noise", "",
            "The rotation-and-translation cost with points (eqs. 13 + 22) minimised by the trust region with "
            "Hebden's step (the paper's choice), the trust region with the exact Hessian and the Moré-Sorensen "
            f"step, Levenberg-Marquardt, and plain Newton; all from the library's default start (no user guess), "
            f"`refine=False`. {mean_note}"
            " Plain Newton can diverge, so its means are dominated by a few runaway trials: the median "
            "translation error is given too. The paper compares these solvers in words (section 4.2) and prints no "
            "table of them, so no paper values stand beside these.", "",
            comparison_table(results, "noise", SOLVER_COMPARISON,
                             TRANSFORMATION + (MEDIAN_TRANSLATION, IMAGE[2]) + PERFORMANCE)]
    out += ["", "## Figure 9 data: point mismatched pairs (section 5.1)", "",
            f"{MISMATCH_POINTS} points ({MISMATCH_POINTS // 2} lines through consecutive pairs), "
            f"{COUNT_SWEEP_NOISE_PX:g} px noise; k pairs of points on different lines have their image points "
            f"swapped (Figure 8). `refine=False`. {mean_note} The paper gives Figure 9 as curves only, without "
            "numbers, so no paper values stand beside these.", "",
            comparison_table(results, "mismatch", (LINEAR, RTT_LINES, TR_POINTS, ROBUST_POINTS),
                             TRANSFORMATION + (IMAGE[2],))]
    out += ["", "## Extra table: random outliers (not in the paper)", "",
            f"{OUTLIER_SWEEP_POINTS} points, {COUNT_SWEEP_NOISE_PX:g} px noise, and the given percentage of the image "
            "points replaced by points drawn uniformly in the bounding box of the 460 true image points. The robust "
            "estimator uses its defaults (4 px point threshold, seed 0). The median translation error shows where "
            f"each method breaks down. {mean_note}", "",
            comparison_table(results, "outliers", (LINEAR, TR_POINTS.refined(), ROBUST_POINTS),
                             TRANSFORMATION + (MEDIAN_TRANSLATION, IMAGE[2]) + PERFORMANCE)]
    return "\n".join(out) + "\n"


# --------------------------------------------------------------------------------------------------
# Figures, summary, entry point


def _series(results: Results, sweep: str, est: Estimator, metric: str,
            stat: str = "mean") -> tuple[list[float], list[float]]:
    cells = results[sweep][est.key]
    return list(cells), [c.mean(metric) if stat == "mean" else c.median(metric) for c in cells.values()]


def render_figures(results: Results, out: Path) -> list[Path]:
    from pluecker import plots

    files = []
    curves = ((LINEAR, "Faugeras-Toscani (linear)", "dashed"),
              (RTT_LINES, "rotation-then-translation (lines)", "full"))
    for number, metric, what in (("5", "axis", "axis"), ("6", "angle", "angle"), ("7", "translation", "translation")):
        panels = []
        for sweep, xlabel in (("count", "number of points (lines: half as many)"),
                              ("noise", "noise max. amplitude (px)")):
            series = [plots.Series(label, *_series(results, sweep, est, metric), style)
                      for est, label, style in curves]
            panels.append(plots.Panel(xlabel, series))
        files.append(plots.two_panel_figure(
            out / f"figure{number}_{what}.png",
            f"Figure {number}: {plots.YLABELS[metric]} (mean over trials)", plots.YLABELS[metric], *panels))
    robust_curve = (ROBUST_POINTS, "robust: LO-RANSAC + refinement (points)", "dashdot")
    mismatch_curves = curves + ((TR_POINTS, "trust region (points)", "dotted"), robust_curve)
    panels = [plots.Panel("point mismatched pairs",
                          [plots.Series(label, *_series(results, "mismatch", est, metric), style)
                           for est, label, style in mismatch_curves], ylabel=plots.YLABELS[metric])
              for metric in ("axis", "angle", "translation")]
    files.append(plots.stacked_figure(out / "figure9_mismatches.png",
                                      "Figure 9: matching errors, 400 points (mean over trials)", panels))
    outlier_curves = ((LINEAR, "Faugeras-Toscani (linear)", "dashed"),
                      (TR_POINTS.refined(), "trust region + refinement (points)", "full"), robust_curve)
    panels = [plots.Panel("outliers (fraction of the points)",
                          [plots.Series(label, *_series(results, "outliers", est, metric, "median"), style)
                           for est, label, style in outlier_curves], ylabel=plots.YLABELS[metric])
              for metric in ("axis", "angle", "translation")]
    files.append(plots.stacked_figure(out / "outliers.png",
                                      f"Random outliers, {OUTLIER_SWEEP_POINTS} points (median over trials)", panels))
    return files


def summarize(results: Results, settings: Settings) -> dict:
    """Medians at 1 px noise and the paper's two claims checked on this run."""
    noise = 1.0 if 1.0 in settings.noise_levels else max(settings.noise_levels)
    medians = {est.label: {m: results["noise"][est.key][noise].median(m) for m in ("axis", "angle", "translation")}
               for est in (LINEAR, RTT_LINES, TR_LINES, TR_POINTS)}
    linear_t = medians[LINEAR.label]["translation"]
    claim_noise = all(medians[e.label]["translation"] < linear_t for e in (RTT_LINES, TR_POINTS))
    k = max(settings.mismatch_counts)
    mismatch = {est.label: results["mismatch"][est.key][k].median("translation")
                for est in (LINEAR, RTT_LINES, ROBUST_POINTS)}
    outliers = {f"{v:g}": {"robust_failures": cells.failures, "robust_median_translation": cells.median("translation"),
                           "default_failures": results["outliers"][TR_POINTS.refined().key][v].failures}
                for v, cells in results["outliers"][ROBUST_POINTS.key].items()}
    smallest = min(settings.point_counts)
    failures = {est.key: results["count"][est.key][smallest].failures
                for est in (LINEAR, RTT_LINES, TR_LINES, TR_POINTS)}
    return {
        "smallest_count": smallest,
        "failures_at_smallest_count": failures,
        "noise_px": noise,
        "median_errors_at_noise": medians,
        "nonlinear_beats_linear_translation": claim_noise,
        "mismatched_pairs": k,
        "median_translation_with_mismatches": mismatch,
        "nonlinear_beats_linear_with_mismatches": bool(mismatch[RTT_LINES.label] < mismatch[LINEAR.label]),
        "robust_beats_nonlinear_with_mismatches": bool(mismatch[ROBUST_POINTS.label] < mismatch[RTT_LINES.label]),
        "outliers": outliers,
    }


def summary_lines(summary: dict, settings: Settings, n_estimates: int, seconds: float, out: Path) -> list[str]:
    a = summary["noise_px"]
    lines = [f"{NAME}: {n_estimates} estimates ({settings.trials} trials per cell, seed {settings.seed}"
             f"{', quick' if settings.quick else ''}) in {seconds:.1f} s -> {out}",
             f"median errors at {a:g} px noise (100 points / 50 lines, paper's estimators alone):",
             f"  {'method':<40} {'axis':>9} {'angle':>9} {'transl. cm':>10}"]
    for label, m in summary["median_errors_at_noise"].items():
        lines.append(f"  {label:<40} {m['axis']:9.2e} {m['angle']:9.2e} {m['translation']:10.3g}")
    verdict = "holds" if summary["nonlinear_beats_linear_translation"] else "DOES NOT hold"
    lines.append(f"paper (Tables 2 vs 4, 8): nonlinear translation error below the linear one at {a:g} px: {verdict}")
    n = summary["smallest_count"]
    fails = ", ".join(f"{key} {k}" for key, k in summary["failures_at_smallest_count"].items())
    lines.append(f"failures with {n} points / {n // 2} lines, of {settings.trials} trials: {fails}")
    mm = summary["median_translation_with_mismatches"]
    verdict = "holds" if summary["nonlinear_beats_linear_with_mismatches"] else "DOES NOT hold"
    lines.append(f"paper (Figure 9): with {summary['mismatched_pairs']} mismatched pairs the nonlinear method stays "
                 f"closer (median translation error {mm[RTT_LINES.label]:.3g} cm vs linear {mm[LINEAR.label]:.3g} cm):"
                 f" {verdict}")
    lines.append(f"robust estimator with {summary['mismatched_pairs']} mismatched pairs: median translation error "
                 f"{mm[ROBUST_POINTS.label]:.3g} cm")
    trials = settings.trials
    lines.append("random outliers, failures of " + str(trials) + " trials (robust / default pipeline): " + ", ".join(
        f"{100 * float(v):.0f}% {o['robust_failures']}/{o['default_failures']}" for v, o in summary["outliers"].items()))
    return lines


def reproduce(out: Path | str = DEFAULT_OUT, *, trials: int | None = None, seed: int = 0, quick: bool = False,
              show_progress: bool | None = None, plots: bool = True) -> Report:
    """Runs every sweep and writes ``tables.md``, ``summary.json`` and the figures into ``out``.

    ``show_progress=None`` draws a progress bar when standard error is a terminal; ``False`` never.
    ``plots=False`` skips the figures (they need matplotlib)."""
    settings = Settings.create(trials=trials, seed=seed, quick=quick)
    out = Path(out)
    truth = Truth.load()
    started = time.perf_counter()
    n_estimates = count_estimates(settings)
    progress = tqdm(total=n_estimates, desc=NAME, unit="estimate", leave=False,
                    disable=None if show_progress is None else not show_progress)
    results = run_sweeps(truth, settings, progress)
    # Every file into a temporary folder, moved into ``out`` at the end: an interrupted or failed run
    # leaves ``out`` as it was (no new empty or half-written folder).
    with staged(out) as stage:
        folder = stage.path
        files = [folder / "tables.md"]
        files[0].write_text(render_tables(results, settings), encoding="utf-8")
        if plots:
            files += render_figures(results, folder)
        seconds = time.perf_counter() - started
        progress.close()
        print(f"{NAME}: {n_estimates} estimates in {seconds:.1f} s", file=sys.stderr)
        summary = summarize(results, settings)
        document = {
            "experiment": NAME,
            "settings": {"trials": settings.trials, "seed": settings.seed, "quick": settings.quick,
                         "point_counts": settings.point_counts, "noise_levels": settings.noise_levels,
                         "mismatch_counts": settings.mismatch_counts, "outlier_fractions": settings.outlier_fractions,
                         "outlier_sweep_points": OUTLIER_SWEEP_POINTS, "count_sweep_noise_px": COUNT_SWEEP_NOISE_PX,
                         "noise_sweep_points": NOISE_SWEEP_POINTS, "mismatch_points": MISMATCH_POINTS},
            "truth": {"axis": truth.axis.tolist(), "angle": truth.angle, "t": truth.t.tolist()},
            "seconds": seconds,
            "summary": summary,
            "sweeps": {sweep: {key: {f"{v:g}": cell.to_dict() for v, cell in cells.items()}
                               for key, cells in by_est.items()} for sweep, by_est in results.items()},
        }
        files.append(folder / "summary.json")
        files[-1].write_text(json.dumps(_json_clean(document), indent=1, allow_nan=False) + "\n", encoding="utf-8")
    files = [out / f.name for f in files]
    return Report(out, files, summary, summary_lines(summary, settings, n_estimates, seconds, out), seconds)
