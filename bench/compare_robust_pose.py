"""Robust pose with outliers, side by side: pluecker ``estimate_pose(..., options=PoseOptions(ransac=RansacOptions()))`` and PoseLib's
LO-RANSAC ``estimate_absolute_pose`` (points) / ``estimate_absolute_pose_pnpl`` (points + lines), on the same
seeded scenes.

Scenes: ``pluecker.random_scene("general", 100, 30, seed)`` (f = 800 px, 640 x 480 image, points 4-8 units
in front of the camera), i.i.d. Gaussian noise of ``SIGMA_PX`` = 1 px on every image point and segment
endpoint, then a fraction ``ratio`` of the points and the same fraction of the lines replaced by outliers:
an image point drawn uniformly in the image, an image segment with both endpoints drawn uniformly in the
image (at least 20 px long). Ratios 0, 25, 50 and 75 %. Two problems on the same scenes:

- ``points``: the 100 points only (PoseLib ``estimate_absolute_pose``);
- ``points+lines``: 100 points and 30 lines (PoseLib ``estimate_absolute_pose_pnpl``).

Thresholds are matched: points 4 px reprojection distance for both. For lines pluecker thresholds the
RMS of the two endpoint-to-projected-line distances at 4 px; PoseLib thresholds the *sum* of the two
distances (its ``compute_msac_score`` for ``Line2D``), so it gets ``max_epipolar_error`` = 8 px, the same
cut when the two distances are equal. PoseLib runs twice: as shipped (``min_iterations`` = 1000, Cauchy
loss of scale 1 px in the final refinement), and with ``min_iterations`` = 0, which stops as early as the
adaptive rule allows (the fastest honest configuration). Both use the scene's seed.

Per problem, ratio and method:

- success rate: rotation error ``‖log(R_est R_trueᵀ)‖`` < 1° and translation error ``‖t_est − t_true‖`` <
  1 % of the scene depth (the mean camera-frame depth of the object points);
- ``sqrt(mean err²) / sqrt(mean bound²)`` on the successes, for rotation and translation, with its standard
  error: the bound of a scene is the trace of the rotation (translation) block of the Cramér-Rao bound at the
  true pose computed on the inliers only (``pluecker.pose_covariance`` with σ = 1 px), i.e. what an oracle
  that knew the outliers could reach;
- median and 95th-percentile time per call from Python (fastest of ``--repeats`` calls per scene).

Targets: pluecker's success rate ≥ PoseLib's at every ratio, RMS ≤ 1.02 × the bound, median time
≤ PoseLib's. Results go to ``bench/out/compare_robust_pose.json``; a Markdown table and PASS/FAIL lines to
standard output. Run from the repository root:

    .venv/bin/python bench/compare_robust_pose.py           # 4000 scenes per ratio (standard error of the RMS ratios about 0.7 %)
    .venv/bin/python bench/compare_robust_pose.py --quick   # 50 scenes, one repeat
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

from compare_pose import IMAGE_SIZE, _finite_or_none, ratio_of_rms, rotation_error, versions

import pluecker
import poselib

SIGMA_PX = 1.0
N_POINTS, N_LINES = 100, 30
RATIOS = (0.0, 0.25, 0.5, 0.75)
POINT_THRESHOLD_PX = 4.0
LINE_THRESHOLD_PX = 4.0
MIN_OUTLIER_SEGMENT_PX = 20.0
SUCCESS_ROTATION_RAD = math.radians(1.0)
SUCCESS_TRANSLATION_FRACTION = 0.01
TARGET_RATIO = 1.02
DEFAULT_SCENES = 4000
OUT = Path(__file__).resolve().parent / "out" / "compare_robust_pose.json"


@dataclass
class Scene:
    """One problem instance: noisy data with outliers, the truth (``x_cam = R X + t``) and the bounds."""

    camera: Any
    R: np.ndarray
    t: np.ndarray
    depth: float
    seed: int
    points2d: np.ndarray
    points3d: np.ndarray
    lines2d: np.ndarray
    lines3d: np.ndarray
    point_inliers: np.ndarray  # (N,) bool: not replaced by an outlier
    line_inliers: np.ndarray  # (M,) bool
    bounds: dict[str, tuple[float, float]]  # problem -> (rotation rad², translation units²)


def _random_segments(rng: np.random.Generator, count: int) -> np.ndarray:
    size = np.array(IMAGE_SIZE, dtype=float)
    out = np.empty((count, 2, 2))
    for k in range(count):
        while True:
            seg = rng.uniform(0.0, 1.0, (2, 2)) * size
            if np.linalg.norm(seg[1] - seg[0]) >= MIN_OUTLIER_SEGMENT_PX:
                out[k] = seg
                break
    return out


def _bound(camera: Any, R: np.ndarray, t: np.ndarray, **arrays: np.ndarray) -> tuple[float, float]:
    cov = np.asarray(pluecker.pose_covariance(camera, R, t, sigma_px=SIGMA_PX, **arrays))
    return float(np.trace(cov[:3, :3])), float(np.trace(cov[3:, 3:]))


def make_scene(ratio: float, seed: int) -> Scene:
    raw = pluecker.random_scene("general", N_POINTS, N_LINES, seed)
    camera = raw["camera"]
    R, t = np.asarray(raw["R"], dtype=float), np.asarray(raw["t"], dtype=float)
    p2 = np.asarray(raw["points2d"], dtype=float)
    p3 = np.asarray(raw["points3d"], dtype=float)
    l2 = np.asarray(raw["lines2d"], dtype=float)
    l3 = np.asarray(raw["lines3d"], dtype=float)
    rng = np.random.default_rng([seed, round(ratio * 100)])
    noisy_p2 = p2 + rng.normal(0.0, SIGMA_PX, p2.shape)
    noisy_l2 = l2 + rng.normal(0.0, SIGMA_PX, l2.shape)
    point_inliers = np.ones(N_POINTS, dtype=bool)
    line_inliers = np.ones(N_LINES, dtype=bool)
    bad_points = rng.choice(N_POINTS, size=round(ratio * N_POINTS), replace=False)
    bad_lines = rng.choice(N_LINES, size=round(ratio * N_LINES), replace=False)
    point_inliers[bad_points] = False
    line_inliers[bad_lines] = False
    noisy_p2[bad_points] = rng.uniform(0.0, 1.0, (len(bad_points), 2)) * np.array(IMAGE_SIZE, dtype=float)
    noisy_l2[bad_lines] = _random_segments(rng, len(bad_lines))
    pin, lin = point_inliers, line_inliers
    bounds = {
        "points": _bound(camera, R, t, points2d=p2[pin], points3d=p3[pin]),
        "points+lines": _bound(camera, R, t, points2d=p2[pin], points3d=p3[pin], lines2d=l2[lin], lines3d=l3[lin]),
    }
    return Scene(
        camera=camera,
        R=R,
        t=t,
        depth=float(np.mean(p3 @ R[2] + t[2])),
        seed=seed,
        points2d=noisy_p2,
        points3d=p3,
        lines2d=noisy_l2,
        lines3d=l3,
        point_inliers=point_inliers,
        line_inliers=line_inliers,
        bounds=bounds,
    )


# --------------------------------------------------------------------------------------------------
# Methods: scene, with_lines -> (R, t, reported inlier masks or None)

Outcome = tuple[np.ndarray, np.ndarray, "np.ndarray | None"]


def _pluecker(s: Scene, with_lines: bool) -> Outcome:
    lines = {"lines2d": s.lines2d, "lines3d": s.lines3d} if with_lines else {}
    r = pluecker.estimate_pose(s.camera, s.points2d, s.points3d, **lines, options=pluecker.PoseOptions(ransac=pluecker.RansacOptions(point_threshold=POINT_THRESHOLD_PX, line_threshold=LINE_THRESHOLD_PX, seed=s.seed)))
    mask = np.concatenate([np.asarray(r.inliers_points), np.asarray(r.inliers_lines)]) if with_lines else np.asarray(r.inliers_points)
    return np.asarray(r.pose.rotation), np.asarray(r.pose.translation), mask


def _poselib(min_iterations: int | None) -> Callable[[Scene, bool], Outcome]:
    extra = {} if min_iterations is None else {"min_iterations": min_iterations}

    def run(s: Scene, with_lines: bool) -> Outcome:
        K = np.asarray(s.camera.K)
        camera = {"model": "PINHOLE", "width": IMAGE_SIZE[0], "height": IMAGE_SIZE[1],
                  "params": [K[0, 0], K[1, 1], K[0, 2], K[1, 2]]}
        ransac = {"max_reproj_error": POINT_THRESHOLD_PX, "max_epipolar_error": 2.0 * LINE_THRESHOLD_PX,
                  "seed": s.seed, **extra}
        if with_lines:
            pose, info = poselib.estimate_absolute_pose_pnpl(
                s.points2d, s.points3d, s.lines2d[:, 0], s.lines2d[:, 1], s.lines3d[:, 0], s.lines3d[:, 1],
                camera, ransac, {})
            mask = np.concatenate([np.asarray(info["inliers"], dtype=bool), np.asarray(info["inliers_lines"], dtype=bool)]) \
                if "inliers_lines" in info else None
        else:
            pose, info = poselib.estimate_absolute_pose(s.points2d, s.points3d, camera, ransac, {})
            mask = np.asarray(info["inliers"], dtype=bool)
        return np.asarray(pose.R), np.asarray(pose.t), mask

    return run


METHODS: dict[str, Callable[[Scene, bool], Outcome]] = {
    "pluecker": _pluecker,
    "poselib": _poselib(None),
    "poselib-min0": _poselib(0),
}
PROBLEMS = {"points": False, "points+lines": True}


# --------------------------------------------------------------------------------------------------


def run_ratio(ratio: float, n_scenes: int, seed: int, repeats: int) -> list[dict[str, Any]]:
    cells: dict[tuple[str, str], dict[str, list]] = {
        (p, m): {"times": [], "errors": [], "fail": [], "exc": [], "mask_errors": []} for p in PROBLEMS for m in METHODS
    }
    for i in range(n_scenes):
        scene = make_scene(ratio, seed + i)
        truth = {"points": scene.point_inliers, "points+lines": np.concatenate([scene.point_inliers, scene.line_inliers])}
        for problem, with_lines in PROBLEMS.items():
            rot_b2, trans_b2 = scene.bounds[problem]
            for name, fn in METHODS.items():
                cell = cells[(problem, name)]
                best = math.inf
                try:
                    for k in range(repeats):
                        start = time.perf_counter()
                        out = fn(scene, with_lines)
                        best = min(best, time.perf_counter() - start)
                        if k == 0:
                            first = out
                except Exception as exc:  # noqa: BLE001 - any library error is a failure to report
                    cell["exc"].append(f"{type(exc).__name__}: {exc}"[:200])
                    cell["fail"].append(scene.seed)
                    continue
                cell["times"].append(best)
                R, t, mask = first
                finite = np.all(np.isfinite(R)) and np.all(np.isfinite(t))
                er = rotation_error(R, scene.R) if finite else math.inf
                et = float(np.linalg.norm(t - scene.t)) if finite else math.inf
                if er < SUCCESS_ROTATION_RAD and et < SUCCESS_TRANSLATION_FRACTION * scene.depth:
                    cell["errors"].append((er * er, rot_b2, et * et, trans_b2))
                    if mask is not None and len(mask) == len(truth[problem]):
                        cell["mask_errors"].append(int(np.sum(mask != truth[problem])))
                else:
                    cell["fail"].append(scene.seed)
    rows = []
    for (problem, name), cell in cells.items():
        e = np.array(cell["errors"]).reshape(-1, 4)
        rot, rot_se = ratio_of_rms(e[:, 0], e[:, 1])
        trans, trans_se = ratio_of_rms(e[:, 2], e[:, 3])
        t_us = np.array(cell["times"]) * 1e6
        rows.append({
            "problem": problem,
            "ratio": ratio,
            "method": name,
            "scenes": n_scenes,
            "successes": len(e),
            "success_rate": len(e) / n_scenes,
            "first_failure_seeds": cell["fail"][:5],
            "exceptions": cell["exc"][:3],
            "rotation_ratio": rot,
            "rotation_ratio_se": rot_se,
            "translation_ratio": trans,
            "translation_ratio_se": trans_se,
            "median_us": float(np.median(t_us)) if len(t_us) else math.nan,
            "p95_us": float(np.percentile(t_us, 95)) if len(t_us) else math.nan,
            "mean_mask_errors": float(np.mean(cell["mask_errors"])) if cell["mask_errors"] else math.nan,
        })
    return rows


def markdown(rows: list[dict[str, Any]]) -> str:
    out = ["| problem | outliers | method | success | rot. RMS / CRB | transl. RMS / CRB | median µs | p95 µs | mask errors |",
           "|---|---:|---|---:|---:|---:|---:|---:|---:|"]
    for r in rows:
        out.append(
            f"| {r['problem']} | {100 * r['ratio']:.0f} % | {r['method']} | {r['successes']}/{r['scenes']} | "
            f"{r['rotation_ratio']:.3f} ± {r['rotation_ratio_se']:.3f} | "
            f"{r['translation_ratio']:.3f} ± {r['translation_ratio_se']:.3f} | {r['median_us']:.0f} | "
            f"{r['p95_us']:.0f} | {r['mean_mask_errors']:.2f} |")
    return "\n".join(out)


def targets(rows: list[dict[str, Any]]) -> list[tuple[str, bool]]:
    by = {(r["problem"], r["ratio"], r["method"]): r for r in rows}
    checks = []
    for problem in PROBLEMS:
        for ratio in sorted({r["ratio"] for r in rows}):
            p = by[(problem, ratio, "pluecker")]
            tag = f"{problem} at {100 * ratio:.0f} %"
            for peer in ("poselib", "poselib-min0"):
                q = by[(problem, ratio, peer)]
                checks.append((f"success {tag}: pluecker {p['successes']} ≥ {peer} {q['successes']} of {p['scenes']}",
                               p["successes"] >= q["successes"]))
                checks.append((f"speed {tag}: pluecker median {p['median_us']:.0f} µs ≤ {peer} {q['median_us']:.0f} µs",
                               p["median_us"] <= q["median_us"]))
            checks.append((f"accuracy {tag}: rotation {p['rotation_ratio']:.3f}, translation "
                           f"{p['translation_ratio']:.3f} ≤ {TARGET_RATIO} × CRB",
                           max(p["rotation_ratio"], p["translation_ratio"]) <= TARGET_RATIO))
    return checks


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--scenes", type=int, default=None, help=f"scenes per ratio (default {DEFAULT_SCENES})")
    parser.add_argument("--seed", type=int, default=0, help="seed of the first scene; scene i uses seed + i")
    parser.add_argument("--repeats", type=int, default=None, help="timed calls per scene, fastest kept (default 3)")
    parser.add_argument("--ratios", type=float, nargs="+", default=list(RATIOS), help="outlier fractions")
    parser.add_argument("--quick", action="store_true", help="50 scenes, one repeat: a smoke test")
    parser.add_argument("--out", type=Path, default=OUT)
    args = parser.parse_args(argv)
    n_scenes = args.scenes or (50 if args.quick else DEFAULT_SCENES)
    repeats = args.repeats or (1 if args.quick else 3)

    started = time.perf_counter()
    rows: list[dict[str, Any]] = []
    for ratio in args.ratios:
        t0 = time.perf_counter()
        rows += run_ratio(ratio, n_scenes, args.seed, repeats)
        print(f"outliers {100 * ratio:.0f} %: {n_scenes} scenes in {time.perf_counter() - t0:.1f} s", file=sys.stderr)
    rows.sort(key=lambda r: (list(PROBLEMS).index(r["problem"]), r["ratio"], list(METHODS).index(r["method"])))
    checks = targets(rows)
    print(markdown(rows))
    print()
    for r in rows:
        if r["exceptions"] or r["successes"] < r["scenes"]:
            print(f"  {r['problem']} {100 * r['ratio']:.0f} % {r['method']}: failed seeds {r['first_failure_seeds']}"
                  + (f"; exceptions {r['exceptions']}" if r["exceptions"] else ""))
    print()
    for text, ok in checks:
        print(f"{'PASS' if ok else 'FAIL'} {text}")
    args.out.parent.mkdir(parents=True, exist_ok=True)
    doc = {
        "date": datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds"),
        "machine": {"platform": platform.platform(), "cpus": os.cpu_count()},
        "versions": versions(),
        "settings": {"scenes": n_scenes, "seed": args.seed, "repeats": repeats, "sigma_px": SIGMA_PX,
                     "point_threshold_px": POINT_THRESHOLD_PX, "line_threshold_px": LINE_THRESHOLD_PX,
                     "poselib_line_threshold_px": 2.0 * LINE_THRESHOLD_PX,
                     "wall_seconds": time.perf_counter() - started},
        "results": rows,
        "targets": [{"check": text, "pass": ok} for text, ok in checks],
    }
    args.out.write_text(json.dumps(_finite_or_none(doc), indent=2, allow_nan=False) + "\n")
    print(f"\nwrote {args.out}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
