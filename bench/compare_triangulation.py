"""Point triangulation side by side: pluecker, OpenCV and pycolmap on the same seeded scenes, plus real data.

**Synthetic scenes** (``make_scene``): ``--points`` (default 20,000) points uniform in the cube [-1, 1]³, seen by ``v``
cameras on a circle of radius 10 around it, all looking at its centre (f = 800 px, 640 x 480), spread
evenly over an arc of ``parallax`` degrees as seen from the centre; i.i.d. Gaussian pixel noise of
σ = 1 px from ``numpy.random.default_rng(seed)``. Cases: 2, 5, 10, 20 views over 30°, and the low-parallax
2-view cases of 1° and 0.2° (at 0.2° a 1 px error moves a point by about 4 units in depth: linear
solutions land behind the cameras).

**Methods**, every one on every point of every case where it applies:

- OpenCV ``cv2.triangulatePoints`` (2-view linear DLT; called once on all points, its natural use);
- pycolmap ``triangulate_point`` (2-view), ``triangulate_multi_view_point`` (all views, linear on
  normalised rays) and ``estimate_triangulation`` (LO-RANSAC + refinement on the reprojection error,
  threshold 4 px), one call per point;
- pluecker ``triangulate_point`` with ``method`` = linear / local / optimal, one call per point, and
  ``triangulate_points`` (the batch, rayon on every core, GIL released), one call on all points.

**Measured** per method and case: the median time per point (single calls: each call timed with
``time.perf_counter``; batches and OpenCV: the call's time over the number of points, fastest of
``--repeats`` calls), and for pluecker also the time its Rust core measured itself; the cost reached,
eq. 19 of Josephson & Kahl with identity covariances (the sum over views of squared pixel residuals,
computed here in numpy for every method alike): median, mean, and the fraction of points whose answer is
behind a camera or costs more than the best in-front answer any method found for that point by more
than 1e-6 (relative: a different local minimum or an unconverged one) and by more than 1 %; the fraction of
certified answers, certificate kinds and branch-and-bound nodes (pluecker optimal); the points behind
a camera (``λ = (P X̃)₃ ≤ 0`` in some view; every camera here has ``det M > 0``, where this is also
Hartley & Zisserman's ``sign(det M) (P X̃)₃``). A certified lower bound that another method's
answer in front of the cameras beats is counted as a violation (there must be none).

**Real data**: Model House and Corridor (``pluecker.datasets``), every 3-D point of the data, triangulated
from all the views it is seen in (3 to 11), by the batch with ``method="optimal"``: fraction certified,
by which certificate, nodes, the median time per point measured by the core, and the batch's wall time
per point.

**Batch linear throughput**: ``triangulate_points(method="linear")`` on 100,000 points of the 2- and
5-view scenes, wall time from Python over the number of points.

Results go to ``bench/out/compare_triangulation.json``; Markdown tables and PASS/FAIL lines for the
issue's targets go to standard output. Run from the repository root with the project's venv:

    .venv/bin/python bench/compare_triangulation.py            # 20,000 points per case, 5-15 s
    .venv/bin/python bench/compare_triangulation.py --quick    # 200 points, one repeat: a smoke test
"""

from __future__ import annotations

import argparse
import datetime
import json
import math
import os
import platform
import sys
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable

import numpy as np

try:
    import cv2
    import pycolmap
except ImportError as exc:  # pragma: no cover - depends on the environment
    sys.exit(
        f"compare_triangulation.py needs OpenCV and pycolmap ({exc}).\n"
        "Install them into the project's venv:\n"
        "    .venv/bin/pip install opencv-python-headless pycolmap"
    )
try:
    import pluecker
    from pluecker.datasets import load_vgg, vgg_root
except ImportError as exc:  # pragma: no cover
    sys.exit(f"compare_triangulation.py needs the pluecker bindings ({exc}); build them with `make develop`.")

SIGMA_PX = 1.0
FOCAL_PX = 800.0
IMAGE_SIZE = (640, 480)
RADIUS = 10.0
COLMAP_THRESHOLD_PX = 4.0
COST_TOLERANCE = 1e-6  # relative excess over the best cost found that counts as "worse"
COST_MARGIN = 1e-2  # ... and as "worse by more than 1 %"
THROUGHPUT_POINTS = 100_000
OUT = Path(__file__).resolve().parent / "out" / "compare_triangulation.json"

# Targets (certified fraction and time).
TARGET_CERTIFIED = 0.999
TARGET_US = {5: 20.0, 20: 100.0}
TARGET_BNB_US = 1000.0
TARGET_BATCH_LINEAR_US = 1.0


@dataclass(frozen=True)
class Case:
    """A family of synthetic scenes: the number of views and the arc they span, degrees."""

    views: int
    parallax_deg: float

    @property
    def name(self) -> str:
        return f"{self.views} views, {self.parallax_deg:g}°"


CASES = (Case(2, 30.0), Case(5, 30.0), Case(10, 30.0), Case(20, 30.0), Case(2, 1.0), Case(2, 0.2))


@dataclass
class Scene:
    """Cameras ``P = K [R | t]`` (v, 3, 4), their parts, the true points (n, 3) and noisy pixels (n, v, 2)."""

    K: np.ndarray
    R: np.ndarray  # (v, 3, 3)
    t: np.ndarray  # (v, 3)
    P: np.ndarray
    X: np.ndarray
    x: np.ndarray


def look_at(centre: np.ndarray, roll: float) -> np.ndarray:
    """The rotation (world → camera) of a camera at ``centre`` looking at the origin, rolled by ``roll``."""
    z = -centre / np.linalg.norm(centre)
    x = np.cross([0.0, 1.0, 0.0], z)
    x /= np.linalg.norm(x)
    y = np.cross(z, x)
    c, s = math.cos(roll), math.sin(roll)
    R = np.stack([x, y, z])
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]]) @ R


def make_scene(case: Case, n_points: int, seed: int) -> Scene:
    rng = np.random.default_rng(seed)
    K = np.array([[FOCAL_PX, 0.0, IMAGE_SIZE[0] / 2], [0.0, FOCAL_PX, IMAGE_SIZE[1] / 2], [0.0, 0.0, 1.0]])
    angles = np.radians(np.linspace(-case.parallax_deg / 2, case.parallax_deg / 2, case.views))
    Rs, ts = [], []
    for a in angles:
        centre = RADIUS * np.array([math.sin(a), 0.0, -math.cos(a)])
        R = look_at(centre, rng.uniform(-0.2, 0.2))
        Rs.append(R)
        ts.append(-R @ centre)
    R, t = np.array(Rs), np.array(ts)
    P = np.einsum("ij,vjk->vik", K, np.concatenate([R, t[:, :, None]], axis=2))
    X = rng.uniform(-1.0, 1.0, (n_points, 3))
    x = project(P, X) + rng.normal(0.0, SIGMA_PX, (n_points, case.views, 2))
    return Scene(K, R, t, P, X, x)


def project(P: np.ndarray, X: np.ndarray) -> np.ndarray:
    """Pixels (n, v, 2) of points (n, 3) in cameras (v, 3, 4)."""
    h = np.einsum("vij,nj->nvi", P, np.hstack([X, np.ones((len(X), 1))]))
    return h[..., :2] / h[..., 2:]


def cost_eq19(P: np.ndarray, X: np.ndarray, x: np.ndarray, visible: np.ndarray | None = None) -> np.ndarray:
    """Eq. 19 with identity covariances: per point, the sum over its views of squared pixel residuals."""
    r2 = np.sum((project(P, X) - x) ** 2, axis=2)
    if visible is not None:
        r2 = np.where(visible, r2, 0.0)
    return r2.sum(axis=1)


def behind(P: np.ndarray, X: np.ndarray, visible: np.ndarray | None = None) -> np.ndarray:
    """Per point: at or behind some camera (``λ = (P X̃)₃ ≤ 0``, pluecker's convention), or not finite."""
    depth = np.einsum("vj,nj->nv", P[:, 2, :], np.hstack([X, np.ones((len(X), 1))]))
    bad = depth <= 0
    if visible is not None:
        bad &= visible
    return bad.any(axis=1) | ~np.all(np.isfinite(X), axis=1)


# --------------------------------------------------------------------------------------------------
# Methods. Each takes a scene and returns a dict with "X" (n, 3) and "seconds" (n,) per point, and for
# pluecker the core's own "core_seconds" and certificate fields.


def _best_of(repeats: int, call: Callable[[], Any]) -> tuple[Any, float]:
    best, result = math.inf, None
    for _ in range(repeats):
        start = time.perf_counter()
        out = call()
        best = min(best, time.perf_counter() - start)
        result = out if result is None else result
    return result, best


def opencv_linear(s: Scene, repeats: int) -> dict[str, Any]:
    x1, x2 = s.x[:, 0].T.copy(), s.x[:, 1].T.copy()
    h, seconds = _best_of(repeats, lambda: cv2.triangulatePoints(s.P[0], s.P[1], x1, x2))
    X = (h[:3] / h[3]).T
    return {"X": X, "seconds": np.full(len(X), seconds / len(X)), "batch": True}


def _rays(s: Scene) -> np.ndarray:
    """Normalised image coordinates ``K⁻¹ (u, v, 1)`` (n, v, 3)."""
    h = np.concatenate([s.x, np.ones(s.x.shape[:2] + (1,))], axis=2)
    return h @ np.linalg.inv(s.K).T


def _per_point(n: int, call: Callable[[int], Any]) -> tuple[np.ndarray, np.ndarray]:
    X, seconds = np.full((n, 3), np.nan), np.zeros(n)
    for i in range(n):
        start = time.perf_counter()
        out = call(i)
        seconds[i] = time.perf_counter() - start
        if out is not None:
            X[i] = np.asarray(out, dtype=float).reshape(3)
    return X, seconds


def colmap_two_view(s: Scene, repeats: int) -> dict[str, Any]:
    rays = _rays(s)
    Rt = [np.hstack([s.R[j], s.t[j][:, None]]) for j in range(2)]
    X, seconds = _per_point(len(s.x), lambda i: pycolmap.triangulate_point(Rt[0], Rt[1], rays[i, 0, :2], rays[i, 1, :2]))
    return {"X": X, "seconds": seconds}


def colmap_multi_view(s: Scene, repeats: int) -> dict[str, Any]:
    rays = _rays(s)
    rays /= np.linalg.norm(rays, axis=2, keepdims=True)
    Rt = [np.hstack([s.R[j], s.t[j][:, None]]) for j in range(len(s.R))]
    X, seconds = _per_point(len(s.x), lambda i: pycolmap.triangulate_multi_view_point(Rt, rays[i]))
    return {"X": X, "seconds": seconds}


def colmap_ransac(s: Scene, repeats: int) -> dict[str, Any]:
    cams = [pycolmap.Camera(model="PINHOLE", width=IMAGE_SIZE[0], height=IMAGE_SIZE[1],
                            params=[s.K[0, 0], s.K[1, 1], s.K[0, 2], s.K[1, 2]]) for _ in s.R]
    poses = [pycolmap.Rigid3d(pycolmap.Rotation3d(R), t) for R, t in zip(s.R, s.t)]
    opts = pycolmap.EstimateTriangulationOptions()
    opts.residual_type = pycolmap.TriangulationResidualType.REPROJECTION_ERROR
    opts.ransac.max_error = COLMAP_THRESHOLD_PX
    opts.ransac.random_seed = 0

    def call(i: int) -> Any:
        out = pycolmap.estimate_triangulation(s.x[i], poses, cams, opts)
        return None if out is None else out["xyz"]

    X, seconds = _per_point(len(s.x), call)
    return {"X": X, "seconds": seconds}


def pluecker_single(method: str) -> Callable[[Scene, int], dict[str, Any]]:
    options = pluecker.TriangulationOptions(method=method)

    def run(s: Scene, repeats: int) -> dict[str, Any]:
        results = []

        def call(i: int) -> Any:
            r = pluecker.triangulate_point(s.P, s.x[i], options=options)
            results.append(r)
            return r.point

        X, seconds = _per_point(len(s.x), call)
        return {
            "X": X,
            "seconds": seconds,
            "core_seconds": np.array([r.time_seconds for r in results]),
            "certified": np.array([r.certified for r in results]),
            # The batch's columns: "none", a NaN bound and 0 nodes without a certificate.
            "certificate": np.array([r.certificate.kind if r.certificate else "none" for r in results]),
            "lower_bound": np.array([r.certificate.lower_bound if r.certificate else np.nan for r in results]),
            "nodes": np.array([r.certificate.nodes if r.certificate else 0 for r in results]),
            "status": np.array([r.status for r in results]),
        }

    return run


def pluecker_batch(method: str) -> Callable[[Scene, int], dict[str, Any]]:
    def run(s: Scene, repeats: int) -> dict[str, Any]:
        options = pluecker.TriangulationOptions(method=method)
        r, seconds = _best_of(repeats, lambda: pluecker.triangulate_points(s.P, s.x, options=options))
        return {
            "X": np.asarray(r.point),
            "seconds": np.full(len(s.x), seconds / len(s.x)),
            "batch": True,
            "core_seconds": np.asarray(r.time_seconds),
            "certified": np.asarray(r.certified),
            "certificate": np.asarray(r.certificate),
            "lower_bound": np.asarray(r.lower_bound),
            "nodes": np.asarray(r.nodes),
            "status": np.asarray(r.status),
        }

    return run


#: name → (method, applies to a case).
METHODS: dict[str, tuple[Callable[[Scene, int], dict[str, Any]], Callable[[Case], bool]]] = {
    "opencv triangulatePoints (batch)": (opencv_linear, lambda c: c.views == 2),
    "pycolmap triangulate_point": (colmap_two_view, lambda c: c.views == 2),
    "pycolmap triangulate_multi_view_point": (colmap_multi_view, lambda c: True),
    "pycolmap estimate_triangulation": (colmap_ransac, lambda c: True),
    "pluecker linear": (pluecker_single("linear"), lambda c: True),
    "pluecker local": (pluecker_single("local"), lambda c: True),
    "pluecker optimal": (pluecker_single("optimal"), lambda c: True),
    "pluecker linear (batch)": (pluecker_batch("linear"), lambda c: True),
    "pluecker local (batch)": (pluecker_batch("local"), lambda c: True),
    "pluecker optimal (batch)": (pluecker_batch("optimal"), lambda c: True),
}


# --------------------------------------------------------------------------------------------------
# Measurement


def _median(values: np.ndarray) -> float:
    values = np.asarray(values, dtype=float)
    values = values[np.isfinite(values)]
    return float(np.median(values)) if values.size else math.nan


def run_case(case: Case, n_points: int, seed: int, repeats: int) -> list[dict[str, Any]]:
    scene = make_scene(case, n_points, seed)
    outcomes: dict[str, dict[str, Any]] = {}
    for name, (fn, applies) in METHODS.items():
        if not applies(case):
            continue
        try:
            outcomes[name] = fn(scene, repeats)
        except Exception as exc:  # noqa: BLE001 - a library's error is a result to report
            outcomes[name] = {"error": f"{type(exc).__name__}: {exc}"}
    costs = {name: cost_eq19(scene.P, o["X"], scene.x) for name, o in outcomes.items() if "X" in o}
    # The best cost any method reached with a point in front of every camera (eq. 19 is minimised over
    # those; a point behind a camera can cost less and is still wrong).
    in_front = {name: np.where(behind(scene.P, outcomes[name]["X"]), np.inf, c) for name, c in costs.items()}
    best = np.min(np.stack(list(in_front.values())), axis=0)
    rows = []
    for name, o in outcomes.items():
        row: dict[str, Any] = {"case": case.name, "views": case.views, "parallax_deg": case.parallax_deg,
                               "method": name, "points": n_points}
        if "error" in o:
            rows.append({**row, "error": o["error"]})
            continue
        cost = costs[name]
        finite = np.isfinite(cost)
        worse = ~finite | (in_front[name] > best * (1 + COST_TOLERANCE) + 1e-12)
        much_worse = ~finite | (in_front[name] > best * (1 + COST_MARGIN) + 1e-12)
        row.update(
            median_us=_median(o["seconds"]) * 1e6,
            batch=bool(o.get("batch", False)),
            median_cost=_median(cost),
            mean_cost=float(np.mean(cost[finite])) if finite.any() else math.nan,
            worse_than_best=float(np.mean(worse)),
            worse_by_1pct=float(np.mean(much_worse)),
            failures=int(np.sum(~np.all(np.isfinite(o["X"]), axis=1))),
            behind_camera=int(np.sum(behind(scene.P, o["X"]))),
            rms_error_3d=float(np.sqrt(np.nanmean(np.sum((o["X"] - scene.X) ** 2, axis=1)))),
        )
        if "certified" in o:
            nodes = np.asarray(o["nodes"])
            kinds, counts = np.unique(o["certificate"], return_counts=True)
            statuses, status_counts = np.unique(o["status"], return_counts=True)
            lower = np.asarray(o["lower_bound"])
            violations = np.asarray(o["certified"]) & (best < lower * (1 - 1e-9) - 1e-12)
            row.update(
                median_core_us=_median(o["core_seconds"]) * 1e6,
                certified=float(np.mean(o["certified"])),
                certificates={str(k): int(c) for k, c in zip(kinds, counts)},
                statuses={str(k): int(c) for k, c in zip(statuses, status_counts)},
                mean_nodes=float(np.mean(nodes)),
                max_nodes=int(np.max(nodes)) if nodes.size else 0,
                bound_violations=int(np.sum(violations)),
            )
            bnb = np.asarray(o["certificate"]) == "branch_and_bound"
            if bnb.any() and not o.get("batch", False):
                row["bnb_points"] = int(bnb.sum())
                row["bnb_median_us"] = _median(o["seconds"][bnb]) * 1e6
                row["bnb_median_core_us"] = _median(o["core_seconds"][bnb]) * 1e6
        rows.append(row)
    return rows


def run_real(name: str, repeats: int) -> dict[str, Any]:
    seq = load_vgg(vgg_root() / name)
    x, visible = seq.point_observations()
    result, seconds = _best_of(repeats, lambda: pluecker.triangulate_points(seq.cameras, x, visible))
    kinds, counts = np.unique(np.asarray(result.certificate), return_counts=True)
    statuses, status_counts = np.unique(np.asarray(result.status), return_counts=True)
    certified = np.asarray(result.certified)
    X = np.asarray(result.point)
    views = visible.sum(axis=1)
    nodes = np.asarray(result.nodes)
    return {
        "sequence": name,
        "points": int(len(X)),
        "views_per_point": {str(k): int(c) for k, c in zip(*np.unique(views, return_counts=True))},
        "certified": float(np.mean(certified)),
        "certificates": {str(k): int(c) for k, c in zip(kinds, counts)},
        "statuses": {str(k): int(c) for k, c in zip(statuses, status_counts)},
        "mean_nodes": float(np.mean(nodes)),
        "max_nodes": int(np.max(nodes)),
        "median_core_us": _median(np.asarray(result.time_seconds)) * 1e6,
        "median_core_us_bnb": _median(np.asarray(result.time_seconds)[np.asarray(result.certificate)
                                                                       == "branch_and_bound"]) * 1e6,
        "batch_wall_us_per_point": seconds / len(X) * 1e6,
        "behind_camera": int(np.sum(behind(seq.cameras, np.nan_to_num(X, nan=np.nan), visible))),
        "rms_reprojection_px": float(np.sqrt(np.sum(cost_eq19(seq.cameras, X, np.nan_to_num(x), visible))
                                             / visible.sum())),
    }


def batch_linear_throughput(views: int, n_points: int, seed: int, repeats: int) -> dict[str, Any]:
    scene = make_scene(Case(views, 30.0), n_points, seed)
    linear = pluecker.TriangulationOptions(method="linear")
    _, seconds = _best_of(max(repeats, 3), lambda: pluecker.triangulate_points(scene.P, scene.x, options=linear))
    return {"views": views, "points": n_points, "us_per_point": seconds / n_points * 1e6}


# --------------------------------------------------------------------------------------------------
# Report


def _f(value: Any, fmt: str) -> str:
    return "—" if value is None or (isinstance(value, float) and not math.isfinite(value)) else format(value, fmt)


def markdown(rows: list[dict[str, Any]]) -> str:
    lines = ["| case | method | median µs/point | median cost | mean cost | worse than best (> 1e-6 / > 1 %) "
             "| behind camera | certified | certificates | mean / max nodes |",
             "|---|---|---:|---:|---:|---:|---:|---:|---|---:|"]
    for r in rows:
        if "error" in r:
            lines.append(f"| {r['case']} | {r['method']} | error: {r['error']} | | | | | | | |")
            continue
        t = _f(r["median_us"], ".2f")
        if "median_core_us" in r:
            t += f" ({_f(r['median_core_us'], '.2f')} in Rust)"
        cert = _f(100 * r["certified"], ".1f") + " %" if "certified" in r else "—"
        kinds = ", ".join(f"{k} {v}" for k, v in r.get("certificates", {}).items()) or "—"
        nodes = f"{r['mean_nodes']:.2f} / {r['max_nodes']}" if "mean_nodes" in r else "—"
        lines.append(f"| {r['case']} | {r['method']} | {t} | {_f(r['median_cost'], '.3f')} | "
                     f"{_f(r['mean_cost'], '.3f')} | {_f(100 * r['worse_than_best'], '.1f')} % / "
                     f"{_f(100 * r['worse_by_1pct'], '.1f')} % | "
                     f"{r['behind_camera']} | {cert} | {kinds} | {nodes} |")
    return "\n".join(lines)


def real_markdown(real: list[dict[str, Any]]) -> str:
    lines = ["| sequence | points | certified | certificates | mean / max nodes | median µs/point (Rust) "
             "| batch wall µs/point | behind camera | RMS reprojection px |",
             "|---|---:|---:|---|---:|---:|---:|---:|---:|"]
    for r in real:
        kinds = ", ".join(f"{k} {v}" for k, v in r["certificates"].items())
        lines.append(f"| {r['sequence']} | {r['points']} | {100 * r['certified']:.2f} % | {kinds} | "
                     f"{r['mean_nodes']:.2f} / {r['max_nodes']} | {r['median_core_us']:.2f} | "
                     f"{r['batch_wall_us_per_point']:.2f} | {r['behind_camera']} | {r['rms_reprojection_px']:.3f} |")
    return "\n".join(lines)


def targets(rows: list[dict[str, Any]], real: list[dict[str, Any]],
            throughput: list[dict[str, Any]]) -> list[tuple[str, bool | None]]:
    checks: list[tuple[str, bool | None]] = []
    for r in real:
        checks.append((f"certified ≥ {100 * TARGET_CERTIFIED:g} % on {r['sequence']}: {100 * r['certified']:.2f} %",
                       r["certified"] >= TARGET_CERTIFIED))
    by = {(r["case"], r["method"]): r for r in rows if "error" not in r}
    for views, limit in TARGET_US.items():
        r = by.get((Case(views, 30.0).name, "pluecker optimal"))
        if r is not None:
            checks.append((f"optimal, {views} views: median {r['median_us']:.1f} µs/point from Python "
                           f"({r['median_core_us']:.1f} in Rust) ≤ {limit:g} µs, certified {100 * r['certified']:.1f} %",
                           r["median_us"] <= limit))
    bnb = [(r["bnb_median_us"], r["bnb_points"], r["case"]) for r in rows if "bnb_median_us" in r]
    for r in real:
        if math.isfinite(r["median_core_us_bnb"]):
            bnb.append((r["median_core_us_bnb"], r["certificates"].get("branch_and_bound", 0), r["sequence"]))
    if bnb:
        worst = max(bnb)
        detail = ", ".join(f"{case} {us:.0f} µs over {n}" for us, n, case in bnb)
        checks.append((f"branch and bound ≤ {TARGET_BNB_US:g} µs per point where needed: median {detail}",
                       worst[0] <= TARGET_BNB_US))
    else:
        checks.append(("branch and bound ≤ 1 ms per point where needed: no point needed branch and bound", None))
    for t in throughput:
        checks.append((f"batch linear from Python, {t['views']} views, {t['points']} points: "
                       f"{t['us_per_point']:.3f} µs/point ≤ {TARGET_BATCH_LINEAR_US:g}",
                       t["us_per_point"] <= TARGET_BATCH_LINEAR_US))
    for case in (Case(2, 1.0), Case(2, 0.2)):
        for method in ("pluecker optimal", "pluecker optimal (batch)"):
            r = by.get((case.name, method))
            if r is not None:
                checks.append((f"{method}, {case.name}: {r['behind_camera']} points behind a camera",
                               r["behind_camera"] == 0))
    violations = sum(r.get("bound_violations", 0) for r in rows)
    checks.append((f"no certified lower bound beaten by any method: {violations} violations", violations == 0))
    return checks


def _clean(value: Any) -> Any:
    """Strict JSON: NaN/inf as null, numpy scalars as numbers."""
    if isinstance(value, dict):
        return {str(k): _clean(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_clean(v) for v in value]
    if isinstance(value, np.generic):
        value = value.item()
    if isinstance(value, float) and not math.isfinite(value):
        return None
    return value


def versions() -> dict[str, str]:
    return {"python": platform.python_version(), "numpy": np.__version__, "opencv": cv2.__version__,
            "pycolmap": getattr(pycolmap, "__version__", "unknown"),
            "pluecker": getattr(pluecker, "__version__", "unknown")}


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--points", type=int, default=None, help="points per synthetic case (default 20000)")
    parser.add_argument("--seed", type=int, default=0, help="seed of the synthetic scenes")
    parser.add_argument("--repeats", type=int, default=None, help="timed batch calls, fastest kept (default 3)")
    parser.add_argument("--quick", action="store_true", help="200 points, 1 repeat, 10,000-point throughput")
    parser.add_argument("--out", type=Path, default=OUT, help=f"JSON output (default {OUT})")
    args = parser.parse_args(argv)
    n_points = args.points or (200 if args.quick else 20_000)
    repeats = args.repeats or (1 if args.quick else 3)
    throughput_points = 10_000 if args.quick else THROUGHPUT_POINTS

    started = time.perf_counter()
    rows: list[dict[str, Any]] = []
    for i, case in enumerate(CASES):
        t0 = time.perf_counter()
        rows += run_case(case, n_points, args.seed + i, repeats)
        print(f"{case.name}: {n_points} points in {time.perf_counter() - t0:.1f} s", file=sys.stderr)
    real = [run_real(name, repeats) for name in ("model_house", "corridor")]
    throughput = [batch_linear_throughput(v, throughput_points, args.seed, repeats) for v in (2, 5)]
    checks = targets(rows, real, throughput)

    print(markdown(rows))
    print()
    print(real_markdown(real))
    print()
    for t in throughput:
        print(f"batch linear, {t['views']} views, {t['points']} points: {t['us_per_point']:.3f} µs/point")
    print()
    for text, ok in checks:
        print(f"{'N/A ' if ok is None else 'PASS' if ok else 'FAIL'} {text}")

    args.out.parent.mkdir(parents=True, exist_ok=True)
    doc = {
        "date": datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds"),
        "machine": {"platform": platform.platform(), "cpus": os.cpu_count(), "processor": platform.processor()},
        "versions": versions(),
        "settings": {"points": n_points, "seed": args.seed, "repeats": repeats, "sigma_px": SIGMA_PX,
                     "focal_px": FOCAL_PX, "radius": RADIUS, "colmap_threshold_px": COLMAP_THRESHOLD_PX,
                     "cases": [c.name for c in CASES], "throughput_points": throughput_points,
                     "wall_seconds": time.perf_counter() - started},
        "synthetic": rows,
        "real": real,
        "batch_linear": throughput,
        "targets": [{"check": text, "pass": ok} for text, ok in checks],
    }
    args.out.write_text(json.dumps(_clean(doc), indent=2, allow_nan=False) + "\n")
    print(f"\nwrote {args.out}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
