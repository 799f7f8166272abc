"""Pose accuracy and speed side by side: pluecker, OpenCV and PoseLib on the same seeded scenes.

Two problems, each on the scene kinds "general", "planar" and "far" of ``pluecker.random_scene``:

- ``points``: 100 points (``random_scene(kind, 100, 0, seed)``) for pluecker, OpenCV ``solvePnP``
  (ITERATIVE, SQPNP, SQPNP followed by ``solvePnPRefineLM``, EPNP) and PoseLib ``estimate_absolute_pose``;
- ``points+lines``: 50 points + 20 segments (``random_scene(kind, 50, 20, seed)``) for pluecker and
  PoseLib ``estimate_absolute_pose_pnpl``.

The scenes come noise-free; i.i.d. Gaussian noise of ``SIGMA_PX`` is added here to every image point and
segment endpoint with ``numpy.random.default_rng(seed)``, so every method sees the same pixels.

Per problem, scene kind and method the script reports:

- the median over scenes of the time of one call (each call is repeated ``--repeats`` times and the
  fastest taken, to shed the noise of a shared machine); the time includes each library's Python
  boundary, as a user would see it;
- the failures: an exception, the library's own failure flag (pluecker: status other than "success";
  OpenCV: ``retval`` false; PoseLib: fewer than 4 inliers, i.e. no refined model), a non-finite pose, a
  rotation error above ``FAIL_ROTATION_RAD``, or a rotation or translation error above ``FAIL_SIGMAS``
  times its Cramér-Rao bound (for an estimator at the bound that has probability below 1e-20);
- ``sqrt(mean err²) / sqrt(mean bound²)`` over the scenes where it did not fail, for the rotation
  error ``‖log(R_est R_trueᵀ)‖`` and the translation error ``‖t_est − t_true‖``, with its Monte-Carlo
  standard error (delta method for a ratio of means). The bound of one scene is the trace of the
  rotation (resp. translation) block of ``pluecker.pose_covariance`` at the true pose: ``σ² (JᵀJ)⁻¹``
  of the reprojection residuals (point distances, endpoint-to-line distances), ``(ω, t)`` with
  ``R ← exp(ω) R``. For points it is checked once per kind against an independent numpy computation.

Results go to ``bench/out/compare_pose.json``; a Markdown table and PASS/FAIL lines for the project's
targets go to standard output. Run from the repository root with the project's venv:

    .venv/bin/python bench/compare_pose.py            # 3500 scenes per kind, about 4 minutes on 2 cores
    .venv/bin/python bench/compare_pose.py --quick    # 200 scenes, one repeat: a smoke test
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
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable

import numpy as np

try:
    import cv2
    import poselib
except ImportError as exc:  # pragma: no cover - depends on the environment
    sys.exit(
        f"compare_pose.py needs OpenCV and PoseLib ({exc}).\n"
        "Install them into the project's venv:\n"
        "    .venv/bin/pip install opencv-python-headless poselib"
    )
try:
    import pluecker
except ImportError as exc:  # pragma: no cover
    sys.exit(f"compare_pose.py needs the pluecker bindings ({exc}); build them first (see bench/README.md).")

SIGMA_PX = 1.0
KINDS = ("general", "planar", "far")
IMAGE_SIZE = (640, 480)
RANSAC_THRESHOLD_PX = 4.0
FAIL_ROTATION_RAD = 0.1
FAIL_SIGMAS = 10.0
TARGET_RATIO = 1.02
# Scenes per problem and kind: the Monte-Carlo standard error of a ratio is about 1/sqrt(6 n) for
# scenes alike (0.7 % here) and larger where the bound varies from scene to scene; 3500 keeps the
# planar kind, the most varied, near 1 %.
DEFAULT_SCENES = 3500
OUT = Path(__file__).resolve().parent / "out" / "compare_pose.json"


# --------------------------------------------------------------------------------------------------
# Scenes and the Cramér-Rao bound


@dataclass
class Scene:
    """One noisy problem instance with its truth (``x_cam = R X + t``) and its bound."""

    camera: Any
    K: np.ndarray
    R: np.ndarray
    t: np.ndarray
    points2d: np.ndarray  # (N, 2) noisy pixels
    points3d: np.ndarray  # (N, 3)
    lines2d: np.ndarray  # (M, 2, 2) noisy segment endpoints
    lines3d: np.ndarray  # (M, 2, 3)
    bound_rot2: float  # trace of the rotation block of the CRB, rad²
    bound_trans2: float  # trace of the translation block, world units²
    covariance: np.ndarray = field(repr=False)
    clean_points2d: np.ndarray = field(repr=False)


def make_scene(kind: str, n_points: int, n_lines: int, seed: int) -> Scene:
    raw = pluecker.random_scene(kind, n_points, n_lines, seed)
    camera = raw["camera"]
    R = np.asarray(raw["R"], dtype=float)
    t = np.asarray(raw["t"], dtype=float)
    p2 = np.asarray(raw["points2d"], dtype=float).reshape(-1, 2)
    p3 = np.asarray(raw["points3d"], dtype=float).reshape(-1, 3)
    l2 = np.asarray(raw["lines2d"], dtype=float).reshape(-1, 2, 2)
    l3 = np.asarray(raw["lines3d"], dtype=float).reshape(-1, 2, 3)
    kwargs: dict[str, np.ndarray] = {}
    if n_points:
        kwargs.update(points2d=p2, points3d=p3)
    if n_lines:
        kwargs.update(lines2d=l2, lines3d=l3)
    cov = np.asarray(pluecker.pose_covariance(camera, R, t, sigma_px=SIGMA_PX, **kwargs), dtype=float)
    rng = np.random.default_rng(seed)
    noisy_p2 = p2 + rng.normal(0.0, SIGMA_PX, p2.shape)
    noisy_l2 = l2 + rng.normal(0.0, SIGMA_PX, l2.shape)
    return Scene(
        camera=camera,
        K=np.asarray(camera.K, dtype=float),
        R=R,
        t=t,
        points2d=noisy_p2,
        points3d=p3,
        lines2d=noisy_l2,
        lines3d=l3,
        bound_rot2=float(np.trace(cov[:3, :3])),
        bound_trans2=float(np.trace(cov[3:, 3:])),
        covariance=cov,
        clean_points2d=p2,
    )


def points_covariance_numpy(K: np.ndarray, R: np.ndarray, t: np.ndarray, points3d: np.ndarray) -> np.ndarray:
    """``σ² (JᵀJ)⁻¹`` for point reprojection residuals, ``(ω, t)`` with ``R ← exp(ω) R``, written out
    independently of pluecker to check its bound."""
    info = np.zeros((6, 6))
    A = K[:2, :2]
    for X in points3d:
        x = R @ X + t
        dproj = np.array([[1.0 / x[2], 0.0, -x[0] / x[2] ** 2], [0.0, 1.0 / x[2], -x[1] / x[2] ** 2]])
        RX = R @ X
        skew = np.array([[0.0, -RX[2], RX[1]], [RX[2], 0.0, -RX[0]], [-RX[1], RX[0], 0.0]])
        J = A @ dproj @ np.hstack([-skew, np.eye(3)])
        info += J.T @ J
    return SIGMA_PX**2 * np.linalg.inv(info)


def rotation_error(R_est: np.ndarray, R_true: np.ndarray) -> float:
    """``‖log(R_est R_trueᵀ)‖`` in radians (stable near 0 and π through the quaternion)."""
    D = R_est @ R_true.T
    w = math.sqrt(max(0.0, 1.0 + np.trace(D))) / 2.0
    v = np.array([D[2, 1] - D[1, 2], D[0, 2] - D[2, 0], D[1, 0] - D[0, 1]]) / 4.0
    return 2.0 * math.atan2(float(np.linalg.norm(v)), w)


# --------------------------------------------------------------------------------------------------
# The methods: each maps a scene to (R, t, ok, core_seconds) and raises on error. core_seconds is the
# time the library measured itself, without the Python boundary (pluecker only; None elsewhere).


Outcome = tuple[np.ndarray, np.ndarray, bool, "float | None"]


def _pluecker(s: Scene) -> Outcome:
    kwargs: dict[str, np.ndarray] = {}
    if len(s.points3d):
        kwargs.update(points2d=s.points2d, points3d=s.points3d)
    if len(s.lines3d):
        kwargs.update(lines2d=s.lines2d, lines3d=s.lines3d)
    r = pluecker.estimate_pose(s.camera, **kwargs)
    return np.asarray(r.pose.rotation), np.asarray(r.pose.translation), r.status == "success", r.time_seconds


def _opencv(flag: int, refine: bool = False) -> Callable[[Scene], Outcome]:
    def run(s: Scene) -> Outcome:
        ok, rvec, tvec = cv2.solvePnP(s.points3d, s.points2d, s.K, None, flags=flag)
        if ok and refine:
            rvec, tvec = cv2.solvePnPRefineLM(s.points3d, s.points2d, s.K, None, rvec, tvec)
        return cv2.Rodrigues(rvec)[0], tvec.reshape(3), bool(ok), None

    return run


def _poselib_camera(s: Scene) -> dict[str, Any]:
    fx, fy, cx, cy = s.camera.fx, s.camera.fy, s.camera.cx, s.camera.cy
    return {"model": "PINHOLE", "width": IMAGE_SIZE[0], "height": IMAGE_SIZE[1], "params": [fx, fy, cx, cy]}


# PoseLib as shipped (LO-RANSAC with at least 1000 iterations, Cauchy loss of scale 1 px), and tuned
# for outlier-free data (no minimum iteration count, plain least squares): the latter is its best
# maximum-likelihood configuration here.
POSELIB_CONFIGS = {
    "poselib": ({}, {}),
    "poselib-ls": ({"min_iterations": 0}, {"loss_type": "TRIVIAL"}),
}


def _poselib(config: str) -> Callable[[Scene], Outcome]:
    ransac_extra, bundle = POSELIB_CONFIGS[config]
    ransac = {"max_reproj_error": RANSAC_THRESHOLD_PX, "max_epipolar_error": RANSAC_THRESHOLD_PX, **ransac_extra}

    def run(s: Scene) -> Outcome:
        camera = _poselib_camera(s)
        if len(s.lines3d):
            pose, info = poselib.estimate_absolute_pose_pnpl(
                s.points2d,
                s.points3d,
                s.lines2d[:, 0],
                s.lines2d[:, 1],
                s.lines3d[:, 0],
                s.lines3d[:, 1],
                camera,
                ransac,
                bundle,
            )
        else:
            pose, info = poselib.estimate_absolute_pose(s.points2d, s.points3d, camera, ransac, bundle)
        return np.asarray(pose.R), np.asarray(pose.t), info["num_inliers"] >= 4, None

    return run


PROBLEMS: dict[str, dict[str, Any]] = {
    "points": {
        "counts": (100, 0),
        "methods": {
            "pluecker": _pluecker,
            "opencv-iterative": _opencv(cv2.SOLVEPNP_ITERATIVE),
            "opencv-sqpnp": _opencv(cv2.SOLVEPNP_SQPNP),
            "opencv-sqpnp+lm": _opencv(cv2.SOLVEPNP_SQPNP, refine=True),
            "opencv-epnp": _opencv(cv2.SOLVEPNP_EPNP),
            "poselib": _poselib("poselib"),
            "poselib-ls": _poselib("poselib-ls"),
        },
    },
    "points+lines": {
        "counts": (50, 20),
        "methods": {
            "pluecker": _pluecker,
            "poselib": _poselib("poselib"),
            "poselib-ls": _poselib("poselib-ls"),
        },
    },
}


# --------------------------------------------------------------------------------------------------
# Measurement and statistics


def time_call(fn: Callable[[Scene], Outcome], scene: Scene, repeats: int) -> tuple[Outcome, float, float]:
    """The result of the first call, and the fastest of ``repeats`` calls as timed here and as timed by
    the library itself (NaN when it does not say), seconds."""
    best, best_core = math.inf, math.inf
    result = None
    for i in range(repeats):
        start = time.perf_counter()
        out = fn(scene)
        elapsed = time.perf_counter() - start
        best = min(best, elapsed)
        best_core = min(best_core, out[3] if out[3] is not None else math.nan)
        if i == 0:
            result = out
    return result, best, best_core


def ratio_of_rms(err2: np.ndarray, bound2: np.ndarray) -> tuple[float, float]:
    """``sqrt(mean err²) / sqrt(mean bound²)`` and its standard error (delta method)."""
    n = len(err2)
    if n < 2:
        return math.nan, math.nan
    r2 = err2.mean() / bound2.mean()
    se_r2 = np.std(err2 - r2 * bound2, ddof=1) / math.sqrt(n) / bound2.mean()
    r = math.sqrt(r2)
    return r, se_r2 / (2.0 * r)


def classify(scene: Scene, out: Any, exc: Exception | None) -> tuple[str | None, float, float]:
    """Failure reason (None if fine), rotation error, translation error."""
    if exc is not None:
        return f"exception: {type(exc).__name__}", math.nan, math.nan
    R, t, ok, _ = out
    if not (np.all(np.isfinite(R)) and np.all(np.isfinite(t))):
        return "non-finite pose", math.nan, math.nan
    er = rotation_error(R, scene.R)
    et = float(np.linalg.norm(t - scene.t))
    if not ok:
        return "status", er, et
    if er > FAIL_ROTATION_RAD:
        return f"rotation error > {FAIL_ROTATION_RAD} rad", er, et
    if er > FAIL_SIGMAS * math.sqrt(scene.bound_rot2) or et > FAIL_SIGMAS * math.sqrt(scene.bound_trans2):
        return f"error > {FAIL_SIGMAS:g} x bound", er, et
    return None, er, et


def run_problem(problem: str, kind: str, n_scenes: int, seed: int, repeats: int) -> list[dict[str, Any]]:
    n_points, n_lines = PROBLEMS[problem]["counts"]
    methods: dict[str, Callable] = PROBLEMS[problem]["methods"]
    times: dict[str, list[float]] = {m: [] for m in methods}
    core_times: dict[str, list[float]] = {m: [] for m in methods}
    errors: dict[str, list[tuple[float, float, float, float]]] = {m: [] for m in methods}
    failures: dict[str, dict[str, int]] = {m: {} for m in methods}
    first_failures: dict[str, list[int]] = {m: [] for m in methods}
    bounds_r, bounds_t = [], []
    crb_check = math.nan
    for i in range(n_scenes):
        scene_seed = seed + i
        scene = make_scene(kind, n_points, n_lines, scene_seed)
        bounds_r.append(scene.bound_rot2)
        bounds_t.append(scene.bound_trans2)
        if i == 0 and n_lines == 0:
            reference = points_covariance_numpy(scene.K, scene.R, scene.t, scene.points3d)
            crb_check = float(np.abs(scene.covariance - reference).max() / np.abs(reference).max())
        for name, fn in methods.items():
            try:
                out, seconds, core_seconds = time_call(fn, scene, repeats)
                exc = None
            except Exception as e:  # noqa: BLE001 - any error of a library is a failure to report
                out, seconds, core_seconds, exc = None, math.nan, math.nan, e
            times[name].append(seconds)
            core_times[name].append(core_seconds)
            reason, er, et = classify(scene, out, exc)
            if reason is None:
                errors[name].append((er * er, scene.bound_rot2, et * et, scene.bound_trans2))
            else:
                failures[name][reason] = failures[name].get(reason, 0) + 1
                if len(first_failures[name]) < 5:
                    first_failures[name].append(scene_seed)
    rows = []
    for name in methods:
        e = np.array(errors[name]).reshape(-1, 4)
        rot, rot_se = ratio_of_rms(e[:, 0], e[:, 1])
        trans, trans_se = ratio_of_rms(e[:, 2], e[:, 3])
        t_us = np.array(times[name]) * 1e6
        core_us = np.array(core_times[name]) * 1e6
        rows.append(
            {
                "problem": problem,
                "kind": kind,
                "method": name,
                "n_points": n_points,
                "n_lines": n_lines,
                "scenes": n_scenes,
                "median_us": float(np.nanmedian(t_us)) if np.isfinite(t_us).any() else math.nan,
                "median_core_us": float(np.nanmedian(core_us)) if np.isfinite(core_us).any() else math.nan,
                "failures": int(sum(failures[name].values())),
                "failure_reasons": failures[name],
                "first_failure_seeds": first_failures[name],
                "rotation_ratio": rot,
                "rotation_ratio_se": rot_se,
                "translation_ratio": trans,
                "translation_ratio_se": trans_se,
                "rms_rotation_error_rad": float(math.sqrt(e[:, 0].mean())) if len(e) else math.nan,
                "rms_translation_error": float(math.sqrt(e[:, 2].mean())) if len(e) else math.nan,
                "rms_rotation_bound_rad": float(math.sqrt(np.mean(bounds_r))),
                "rms_translation_bound": float(math.sqrt(np.mean(bounds_t))),
                "crb_check_max_rel_diff": crb_check,
            }
        )
    return rows


# --------------------------------------------------------------------------------------------------
# Report


def _fmt_ratio(r: float, se: float) -> str:
    return "—" if not math.isfinite(r) else f"{r:.3f} ± {se:.3f}"


def _fmt_time(r: dict[str, Any]) -> str:
    core = r["median_core_us"]
    return f"{r['median_us']:.1f}" + (f" ({core:.1f} in Rust)" if math.isfinite(core) else "")


def markdown(rows: list[dict[str, Any]]) -> str:
    lines = [
        "| problem | kind | method | median µs | failures | rot. err / CRB | transl. err / CRB |",
        "|---|---|---|---:|---:|---:|---:|",
    ]
    for r in rows:
        lines.append(
            f"| {r['problem']} | {r['kind']} | {r['method']} | {_fmt_time(r)} | "
            f"{r['failures']}/{r['scenes']} | {_fmt_ratio(r['rotation_ratio'], r['rotation_ratio_se'])} | "
            f"{_fmt_ratio(r['translation_ratio'], r['translation_ratio_se'])} |"
        )
    return "\n".join(lines)


def targets(rows: list[dict[str, Any]]) -> list[tuple[str, bool]]:
    checks = []
    by = {(r["problem"], r["kind"], r["method"]): r for r in rows}
    for problem in PROBLEMS:
        for kind in KINDS:
            r = by.get((problem, kind, "pluecker"))
            if r is None:
                continue
            ok = r["failures"] == 0 and r["rotation_ratio"] <= TARGET_RATIO and r["translation_ratio"] <= TARGET_RATIO
            text = (
                f"accuracy {problem}/{kind}: pluecker error ≤ {TARGET_RATIO} × CRB with no failures "
                f"(failures {r['failures']}, rotation {r['rotation_ratio']:.3f}, "
                f"translation {r['translation_ratio']:.3f})"
            )
            checks.append((text, ok))
    for kind in KINDS:
        p, s = by.get(("points", kind, "pluecker")), by.get(("points", kind, "opencv-sqpnp"))
        if p is None or s is None:
            continue
        text = (
            f"speed points/{kind}: pluecker median {p['median_us']:.1f} µs < OpenCV SQPnP "
            f"{s['median_us']:.1f} µs (ratio {p['median_us'] / s['median_us']:.2f})"
        )
        checks.append((text, p["median_us"] < s["median_us"]))
    return checks


def _finite_or_none(value: Any) -> Any:
    """NaN and infinities become ``null`` so the JSON stays strict; numpy scalars become Python's."""
    if isinstance(value, float):
        return value if math.isfinite(value) else None
    if isinstance(value, dict):
        return {k: _finite_or_none(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_finite_or_none(v) for v in value]
    if isinstance(value, (np.floating, np.integer, np.bool_)):
        return _finite_or_none(value.item())
    return value


def versions() -> dict[str, str]:
    return {
        "python": platform.python_version(),
        "numpy": np.__version__,
        "opencv": cv2.__version__,
        "poselib": getattr(poselib, "__version__", "unknown"),
        "pluecker": getattr(pluecker, "__version__", "unknown"),
    }


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument(
        "--scenes", type=int, default=None, help=f"scenes per problem and kind (default {DEFAULT_SCENES})"
    )
    parser.add_argument("--seed", type=int, default=0, help="seed of the first scene; scene i uses seed + i")
    parser.add_argument("--repeats", type=int, default=None, help="timed calls per scene, fastest kept (default 3)")
    parser.add_argument("--quick", action="store_true", help="200 scenes, 1 repeat: a smoke test")
    parser.add_argument("--problems", nargs="+", choices=list(PROBLEMS), default=list(PROBLEMS))
    parser.add_argument("--out", type=Path, default=OUT, help=f"JSON output (default {OUT})")
    args = parser.parse_args(argv)
    n_scenes = args.scenes or (200 if args.quick else DEFAULT_SCENES)
    repeats = args.repeats or (1 if args.quick else 3)

    started = time.perf_counter()
    rows: list[dict[str, Any]] = []
    for problem in args.problems:
        for kind in KINDS:
            t0 = time.perf_counter()
            rows += run_problem(problem, kind, n_scenes, args.seed, repeats)
            print(f"{problem}/{kind}: {n_scenes} scenes in {time.perf_counter() - t0:.1f} s", file=sys.stderr)
    checks = targets(rows)

    print(markdown(rows))
    print()
    print("RMS Cramér-Rao bound per scene kind (rotation mrad, translation in world units):")
    seen = set()
    for r in rows:
        key = (r["problem"], r["kind"])
        if key not in seen:
            seen.add(key)
            check = (
                "" if math.isnan(r["crb_check_max_rel_diff"]) else f" (numpy check: {r['crb_check_max_rel_diff']:.1e})"
            )
            print(
                f"  {r['problem']}/{r['kind']}: {1e3 * r['rms_rotation_bound_rad']:.3f} mrad, "
                f"{r['rms_translation_bound']:.4f}{check}"
            )
    failing = [r for r in rows if r["failures"]]
    if failing:
        print("\nFailures (reason: count; first seeds):")
        for r in failing:
            print(
                f"  {r['problem']}/{r['kind']}/{r['method']}: {r['failure_reasons']}; seeds {r['first_failure_seeds']}"
            )
    print()
    for text, ok in checks:
        print(f"{'PASS' if ok else 'FAIL'} {text}")

    args.out.parent.mkdir(parents=True, exist_ok=True)
    doc = {
        "date": datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds"),
        "machine": {"platform": platform.platform(), "cpus": os.cpu_count(), "processor": platform.processor()},
        "versions": versions(),
        "settings": {
            "scenes": n_scenes,
            "seed": args.seed,
            "repeats": repeats,
            "sigma_px": SIGMA_PX,
            "ransac_threshold_px": RANSAC_THRESHOLD_PX,
            "fail_rotation_rad": FAIL_ROTATION_RAD,
            "fail_sigmas": FAIL_SIGMAS,
            "poselib_configs": {k: {"ransac": v[0], "bundle": v[1]} for k, v in POSELIB_CONFIGS.items()},
            "wall_seconds": time.perf_counter() - started,
        },
        "results": rows,
        "targets": [{"check": text, "pass": ok} for text, ok in checks],
    }
    args.out.write_text(json.dumps(_finite_or_none(doc), indent=2, allow_nan=False) + "\n")
    print(f"\nwrote {args.out}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
