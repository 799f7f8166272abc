"""The pose of a camera rig, side by side: pluecker ``estimate_pose(rig, ..., point_cameras=...)``, PoseLib's
``estimate_generalized_absolute_pose`` and pycolmap's ``estimate_and_refine_generalized_absolute_pose``, on the
same seeded scenes; and the minimal solvers ``pluecker.gp3p`` against ``poselib.gp3p``.

Scenes: rigs of 2, 4 and 6 pinhole cameras (f = 500-1000 px, 640 x 480) on a ring of radius 0.3 looking
outwards (fields of view that overlap for 2 cameras and not at all for 4 and 6), at a random pose; points
3-9 units in front of the camera that sees them, spread evenly over the cameras; i.i.d. Gaussian noise of
1 px on every pixel and segment endpoint. Rows: 10 and 100 points, and 10 points + 10 segments (pluecker
only: the peers take no lines). Robust rows: 100 points of which a fraction (0 and 50 %) are outliers (a pixel
drawn uniformly in the image of the camera that "saw" it).

- accuracy rows: RMS rotation and translation errors of the non-robust estimate over the scenes, divided by
  the root of the mean Cramér-Rao bound (trace of the rotation or translation block of ``(JᵀJ)⁻¹`` at the
  true pose, σ = 1 px; ``J`` by central differences of the projections computed here in numpy, not by the
  library). Target ≤ 1.01.
- robust rows: success (rotation error < 1° and translation error < 1 % of the mean depth), median time
  per call from Python. pluecker: ``RansacOptions()`` defaults (4 px); PoseLib: its defaults as documented
  (``RansacOptions()``: ``max_reproj_error`` 12 px, ``min_iterations`` 1000) but ``max_reproj_error`` = 4 px,
  the same threshold, and again with ``min_iterations`` = 0 (as early as its adaptive rule allows); pycolmap: ``RANSACOptions(max_error=4)``. Targets: success ≥ the peers', time ≤ 0.5 x
  PoseLib's.
- minimal solvers: 10⁵ random gP3P instances (three cameras 0.3 apart, points 2-20 units away), the
  rotation error of the best returned pose (log10 histogram) and the time per call from Python.

Results go to ``--out`` (default ``bench/out/compare_rig_pose.json``); a Markdown table to standard output.

    .venv/bin/python bench/compare_rig_pose.py           # 500 scenes per row, 10^5 minimal instances
    .venv/bin/python bench/compare_rig_pose.py --quick   # 40 scenes per row, 10^4 minimal instances
"""

from __future__ import annotations

import argparse
import json
import math
import time
from pathlib import Path
from typing import Any

import numpy as np
import pluecker

OUT = Path(__file__).resolve().parent / "out" / "compare_rig_pose.json"
WIDTH, HEIGHT = 640, 480
SIGMA_PX = 1.0
THRESHOLD_PX = 4.0


def exp_so3(w: np.ndarray) -> np.ndarray:
    theta = np.linalg.norm(w)
    K = np.array([[0, -w[2], w[1]], [w[2], 0, -w[0]], [-w[1], w[0], 0]])
    if theta < 1e-12:
        return np.eye(3) + K
    return np.eye(3) + math.sin(theta) / theta * K + (1 - math.cos(theta)) / theta**2 * K @ K


def random_rotation(rng: np.random.Generator) -> np.ndarray:
    q = rng.standard_normal(4)
    q /= np.linalg.norm(q)
    w, x, y, z = q
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                     [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                     [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])


def rotation_error(Ra: np.ndarray, Rb: np.ndarray) -> float:
    """The angle of ``Ra Rbᵀ``, as ``atan2(‖axis part‖, cos part)``: accurate at 1e-16 rad too (the
    ``arccos`` of the trace is not below about 1e-8)."""
    d = Ra @ Rb.T
    axis = 0.5 * np.array([d[2, 1] - d[1, 2], d[0, 2] - d[2, 0], d[1, 0] - d[0, 1]])
    return float(math.atan2(np.linalg.norm(axis), 0.5 * (np.trace(d) - 1)))


def ring(k: int, radius: float = 0.3) -> tuple[list[np.ndarray], list[tuple[np.ndarray, np.ndarray]]]:
    """``k`` intrinsics matrices and ``sensor_from_rig`` poses on a ring looking outwards."""
    Ks, poses = [], []
    for i in range(k):
        f = 500.0 + 500.0 * i / max(k - 1, 1)
        Ks.append(np.array([[f, 0, WIDTH / 2], [0, f, HEIGHT / 2], [0, 0, 1.0]]))
        a = 2 * math.pi * i / k
        R = np.array([[math.cos(a), 0, math.sin(a)], [0, 1, 0], [-math.sin(a), 0, math.cos(a)]])
        c = R.T @ np.array([0.0, 0.0, radius])
        poses.append((R, -R @ c))
    return Ks, poses


class Scene:
    """One rig problem: the truth ``rig_from_world``, the data, and the Cramér-Rao bound."""

    def __init__(self, cameras: int, points: int, segments: int, outliers: float, seed: int) -> None:
        rng = np.random.default_rng(seed)
        self.Ks, self.sensor = ring(cameras)
        self.R, self.t = random_rotation(rng), rng.standard_normal(3)
        self.point_cameras = np.arange(points) % cameras
        self.line_cameras = np.arange(segments) % cameras
        self.X = np.array([self._world(k, self._in_view(rng, k)) for k in self.point_cameras]).reshape(-1, 3)
        ends = [(self._in_view(rng, k), self._in_view(rng, k)) for k in self.line_cameras]
        self.L = np.array([[self._world(k, a), self._world(k, b)] for k, (a, b) in zip(self.line_cameras, ends)])
        self.L = self.L.reshape(-1, 2, 3)
        self.exact = self.project(self.R, self.t)
        self.x = self.exact + SIGMA_PX * rng.standard_normal(self.exact.shape)
        self.l2 = np.array([[self._pixel(k, self.R, self.t, e) for e in s] for k, s in zip(self.line_cameras, self.L)])
        self.l2 = self.l2.reshape(-1, 2, 2) + SIGMA_PX * rng.standard_normal((segments, 2, 2))
        self.outlier = np.zeros(points, dtype=bool)
        if outliers > 0:
            self.outlier[rng.permutation(points)[: int(round(outliers * points))]] = True
            self.x[self.outlier] = rng.uniform([0, 0], [WIDTH, HEIGHT], (int(self.outlier.sum()), 2))
        depths = [(self.sensor[k][0] @ (self.R @ X + self.t) + self.sensor[k][1])[2]
                  for k, X in zip(self.point_cameras, self.X)]
        self.depth = float(np.mean(depths))

    def _in_view(self, rng: np.random.Generator, k: int) -> np.ndarray:
        u = rng.uniform([20, 20], [WIDTH - 20, HEIGHT - 20])
        return np.linalg.solve(self.Ks[k], np.array([u[0], u[1], 1.0])) * rng.uniform(3.0, 9.0)

    def _world(self, k: int, x_cam: np.ndarray) -> np.ndarray:
        Rk, tk = self.sensor[k]
        return self.R.T @ (Rk.T @ (x_cam - tk) - self.t)

    def _pixel(self, k: int, R: np.ndarray, t: np.ndarray, X: np.ndarray) -> np.ndarray:
        Rk, tk = self.sensor[k]
        x = self.Ks[k] @ (Rk @ (R @ X + t) + tk)
        return x[:2] / x[2]

    def project(self, R: np.ndarray, t: np.ndarray) -> np.ndarray:
        return np.array([self._pixel(k, R, t, X) for k, X in zip(self.point_cameras, self.X)]).reshape(-1, 2)

    def residuals(self, R: np.ndarray, t: np.ndarray) -> np.ndarray:
        """The inliers' residuals at ``(R, t)`` against the exact pixels: points, then each segment
        endpoint's distance to the projected line (pinhole: a straight line)."""
        r = [(self.project(R, t) - self.exact)[~self.outlier].ravel()]
        for k, s, ends in zip(self.line_cameras, self.L, self._exact_ends()):
            a, b = self._pixel(k, R, t, s[0]), self._pixel(k, R, t, s[1])
            n = np.array([a[1] - b[1], b[0] - a[0]])
            n /= np.linalg.norm(n)
            r.append(np.array([(e - a) @ n for e in ends]))
        return np.concatenate(r)

    def _exact_ends(self) -> np.ndarray:
        ends = [[self._pixel(k, self.R, self.t, e) for e in s] for k, s in zip(self.line_cameras, self.L)]
        return np.array(ends).reshape(-1, 2, 2)

    def bound(self) -> tuple[float, float]:
        """Traces of the rotation and translation blocks of ``σ² (JᵀJ)⁻¹`` at the truth (central differences
        in the tangent ``exp(ω) R``, ``t + δt``)."""
        h = 1e-6
        columns = []
        for j in range(6):
            d = np.zeros(6)
            d[j] = h
            plus = self.residuals(exp_so3(d[:3]) @ self.R, self.t + d[3:])
            minus = self.residuals(exp_so3(-d[:3]) @ self.R, self.t - d[3:])
            columns.append((plus - minus) / (2 * h))
        J = np.column_stack(columns)
        C = SIGMA_PX**2 * np.linalg.inv(J.T @ J)
        return float(np.trace(C[:3, :3])), float(np.trace(C[3:, 3:]))

    def rig(self) -> pluecker.Rig:
        cameras = [pluecker.Camera("PINHOLE", [K[0, 0], K[1, 1], K[0, 2], K[1, 2]]) for K in self.Ks]
        return pluecker.Rig(cameras, self.sensor)


def run_pluecker(s: Scene, robust: bool, lines: bool) -> tuple[np.ndarray, np.ndarray, float]:
    options = pluecker.PoseOptions(ransac=pluecker.RansacOptions()) if robust else pluecker.PoseOptions()
    rig = s.rig()
    extra = dict(lines2d=s.l2, lines3d=s.L, line_cameras=s.line_cameras) if lines else {}
    started = time.perf_counter()
    r = pluecker.estimate_pose(rig, s.x, s.X, point_cameras=s.point_cameras, options=options, **extra)
    elapsed = time.perf_counter() - started
    return r.pose.rotation, r.pose.translation, elapsed


def run_poselib(s: Scene, min_iterations: int | None = None) -> tuple[np.ndarray, np.ndarray, float]:
    import poselib

    cameras = [{"model": "PINHOLE", "width": WIDTH, "height": HEIGHT,
                "params": [K[0, 0], K[1, 1], K[0, 2], K[1, 2]]} for K in s.Ks]
    ext = [poselib.CameraPose() for _ in s.Ks]
    for pose, (R, t) in zip(ext, s.sensor):
        pose.R, pose.t = R, t
    x = [s.x[s.point_cameras == k] for k in range(len(s.Ks))]
    X = [s.X[s.point_cameras == k] for k in range(len(s.Ks))]
    started = time.perf_counter()
    ransac = {"max_reproj_error": THRESHOLD_PX}
    if min_iterations is not None:
        ransac["min_iterations"] = min_iterations
    pose, _ = poselib.estimate_generalized_absolute_pose(x, X, ext, cameras, ransac, {})
    elapsed = time.perf_counter() - started
    return pose.R, pose.t, elapsed


def run_pycolmap(s: Scene) -> tuple[np.ndarray, np.ndarray, float]:
    import pycolmap

    cameras = [pycolmap.Camera(model="PINHOLE", width=WIDTH, height=HEIGHT,
                               params=[K[0, 0], K[1, 1], K[0, 2], K[1, 2]]) for K in s.Ks]
    rigs = [pycolmap.Rigid3d(pycolmap.Rotation3d(R), t) for R, t in s.sensor]
    options = pycolmap.RANSACOptions()
    options.max_error = THRESHOLD_PX
    started = time.perf_counter()
    out = pycolmap.estimate_and_refine_generalized_absolute_pose(s.x, s.X, [int(k) for k in s.point_cameras], rigs,
                                                                 cameras, options)
    elapsed = time.perf_counter() - started
    if out is None:
        return np.full((3, 3), np.nan), np.full(3, np.nan), elapsed
    rig_from_world = out["rig_from_world"]
    return rig_from_world.rotation.matrix(), np.asarray(rig_from_world.translation), elapsed


def accuracy_row(cameras: int, points: int, segments: int, scenes: int) -> dict[str, Any]:
    errors: dict[str, list[tuple[float, float]]] = {"pluecker": []}
    bounds, times = [], []
    for seed in range(scenes):
        s = Scene(cameras, points, segments, 0.0, seed)
        bounds.append(s.bound())
        R, t, elapsed = run_pluecker(s, robust=False, lines=segments > 0)
        times.append(elapsed)
        errors["pluecker"].append((rotation_error(R, s.R) ** 2, float(np.sum((t - s.t) ** 2))))
    b = np.mean(bounds, axis=0)
    row: dict[str, Any] = {"cameras": cameras, "points": points, "segments": segments, "scenes": scenes}
    for name, e in errors.items():
        e = np.array(e)
        row[name] = {"rotation_vs_bound": float(np.sqrt(e[:, 0].mean() / b[0])),
                     "translation_vs_bound": float(np.sqrt(e[:, 1].mean() / b[1])),
                     "median_ms": 1e3 * float(np.median(times)), "p99_ms": 1e3 * float(np.percentile(times, 99))}
    return row


def robust_row(cameras: int, points: int, outliers: float, scenes: int) -> dict[str, Any]:
    methods = {"pluecker": lambda s: run_pluecker(s, robust=True, lines=False), "poselib": run_poselib,
               "poselib_min_iterations_0": lambda s: run_poselib(s, 0), "pycolmap": run_pycolmap}
    row: dict[str, Any] = {"cameras": cameras, "points": points, "outliers": outliers, "scenes": scenes}
    for name, method in methods.items():
        ok, times = 0, []
        for seed in range(scenes):
            s = Scene(cameras, points, 0, outliers, 10_000 + seed)
            R, t, elapsed = method(s)
            times.append(elapsed)
            good = np.all(np.isfinite(R)) and rotation_error(R, s.R) < math.radians(1.0) \
                and np.linalg.norm(t - s.t) < 0.01 * s.depth
            ok += bool(good)
        row[name] = {"success": ok / scenes, "median_ms": 1e3 * float(np.median(times)),
                     "p99_ms": 1e3 * float(np.percentile(times, 99))}
    row["time_vs_poselib"] = row["pluecker"]["median_ms"] / row["poselib"]["median_ms"]
    row["time_vs_poselib_min_iterations_0"] = row["pluecker"]["median_ms"] / row["poselib_min_iterations_0"]["median_ms"]
    return row


def minimal_rows(instances: int) -> dict[str, Any]:
    """gP3P on random instances: log10 of the best rotation error, and the time per call from Python
    (the fastest of three passes over all the instances), with each library's P3P on the same rays as the
    baseline of its call overhead: ``gp3p − p3p`` is the difference of the solvers' own times."""
    import poselib

    rng = np.random.default_rng(1)
    data = []
    for _ in range(instances):
        R, t = random_rotation(rng), rng.standard_normal(3)
        origins = 0.3 * rng.standard_normal((3, 3))
        y = rng.standard_normal((3, 3))
        y = y / np.linalg.norm(y, axis=1, keepdims=True) * rng.uniform(2, 20, (3, 1)) + origins
        directions = y - origins
        directions /= np.linalg.norm(directions, axis=1, keepdims=True)
        data.append((R, origins, directions, (y - t) @ R))  # x_rig = R X + t
    calls = {"pluecker": (lambda o, d, X: pluecker.gp3p(o, d, X), lambda o, d, X: pluecker.p3p(d, X)),
             "poselib": (lambda o, d, X: poselib.gp3p(o, d, X), lambda o, d, X: poselib.p3p(d, X))}

    def per_call(f: Any) -> float:
        best = math.inf
        for _ in range(3):
            started = time.perf_counter()
            for _, o, d, X in data:
                f(o, d, X)
            best = min(best, (time.perf_counter() - started) / len(data))
        return 1e6 * best

    out: dict[str, Any] = {"instances": instances}
    for name, (solver, baseline) in calls.items():
        errors = []
        for R, o, d, X in data:
            poses = solver(o, d, X)
            rotations = [p[0] for p in poses] if name == "pluecker" else [p.R for p in poses]
            errors.append(min((rotation_error(P, R) for P in rotations), default=math.inf))
        e = np.array(errors)
        gp3p_us, p3p_us = per_call(solver), per_call(baseline)
        out[name] = {"us_per_call": gp3p_us, "p3p_us_per_call": p3p_us, "gp3p_minus_p3p_us": gp3p_us - p3p_us,
                     "no_solution": float(np.mean(~np.isfinite(e))),
                     "below_1e-12": float(np.mean(e < 1e-12)), "below_1e-8": float(np.mean(e < 1e-8)),
                     "below_1e-4": float(np.mean(e < 1e-4)),
                     "histogram_log10": np.histogram(np.log10(np.maximum(e[np.isfinite(e)], 1e-17)),
                                                     bins=np.arange(-17, 1))[0].tolist()}
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--quick", action="store_true")
    parser.add_argument("--out", type=Path, default=OUT)
    args = parser.parse_args()
    scenes = 40 if args.quick else 500
    result: dict[str, Any] = {"accuracy": [], "robust": []}
    for cameras in (2, 4, 6):
        for points, segments in ((10, 0), (100, 0), (10, 10)):
            row = accuracy_row(cameras, points, segments, scenes)
            result["accuracy"].append(row)
            p = row["pluecker"]
            print(f"accuracy | {cameras} cameras | {points} points | {segments} segments | "
                  f"rotation {p['rotation_vs_bound']:.3f} x bound | translation {p['translation_vs_bound']:.3f} x bound | "
                  f"{p['median_ms']:.2f} ms (p99 {p['p99_ms']:.2f})")
    for cameras in (2, 4, 6):
        for outliers in (0.0, 0.5):
            row = robust_row(cameras, 100, outliers, scenes)
            result["robust"].append(row)
            print(f"robust | {cameras} cameras | {outliers:.0%} outliers | " + " | ".join(
                f"{m} {row[m]['success']:.3f} in {row[m]['median_ms']:.2f} ms (p99 {row[m]['p99_ms']:.2f})"
                for m in ("pluecker", "poselib", "poselib_min_iterations_0", "pycolmap"))
                + f" | time / PoseLib {row['time_vs_poselib']:.2f}, / PoseLib min_iterations 0 "
                  f"{row['time_vs_poselib_min_iterations_0']:.2f}")
    result["minimal"] = minimal_rows(10_000 if args.quick else 100_000)
    for m in ("pluecker", "poselib"):
        r = result["minimal"][m]
        print(f"gp3p | {m} | {r['us_per_call']:.2f} us/call (p3p {r['p3p_us_per_call']:.2f}, difference "
              f"{r['gp3p_minus_p3p_us']:.2f}) | < 1e-12: {r['below_1e-12']:.4f} | < 1e-8: "
              f"{r['below_1e-8']:.4f} | < 1e-4: {r['below_1e-4']:.4f} | no solution: {r['no_solution']:.5f}")
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps(result, indent=1))


if __name__ == "__main__":
    main()
