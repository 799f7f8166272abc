"""How fast Ctrl-C stops the long calls of issue 10 §3: SIGINT is sent to this process while the call runs,
and the time from the signal to the ``KeyboardInterrupt`` reaching Python is measured.

    .venv/bin/python bench/interrupt_latency.py [--repeats 5] [--points 2000000]

Workloads (each would run for seconds to minutes if nothing stopped it):
- ``triangulate_points``: 2M tracks in 3 views, ``optimal``;
- ``triangulate_lines``: 40 noisy segments in 4 views, branch and bound to a 1e-9 gap;
- ``estimate_pose(ransac=RansacOptions(...))``: 20k all-outlier points, no inlier-ratio cap.
Prints the median and largest latency per workload, and how many tracks had finished.
"""

from __future__ import annotations

import argparse
import os
import signal
import statistics
import sys
import threading
import time
from pathlib import Path

import numpy as np

import pluecker

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
from test_triangulation_batch_lines import line_tracks  # noqa: E402


def points_workload(n: int):
    rng = np.random.default_rng(0)
    K = np.array([[800.0, 0, 320], [0, 800, 240], [0, 0, 1]])
    P = np.array([K @ np.hstack([np.eye(3), [[c], [0], [5]]]) for c in (-1.0, 0.0, 1.0)])
    X = rng.normal(size=(n, 3))
    x = np.stack([(p @ np.c_[X, np.ones(n)].T).T for p in P], axis=1)
    x = x[..., :2] / x[..., 2:] + rng.normal(0, 1, (n, 3, 2))
    return lambda: pluecker.triangulate_points(P, x, method="optimal")


def lines_workload():
    P, segments = line_tracks(0, n=40, views=4, sigma=2.0)
    return lambda: pluecker.triangulate_lines(P, segments, method="optimal", options=pluecker.TriangulationOptions(max_relative_gap=1e-9, max_nodes=10**7))


def pose_workload():
    rng = np.random.default_rng(0)
    n = 20_000
    camera = pluecker.Camera(800, 800, 320, 240)
    X = rng.uniform(-1, 1, (n, 3)) + [0, 0, 6]
    u = rng.uniform(0, 640, (n, 2))
    return lambda: pluecker.estimate_pose(camera, u, X, ransac=pluecker.RansacOptions(min_inlier_ratio=0.0, max_iterations=10**12, confidence=1 - 1e-12))


def latency(call, delay: float) -> tuple[float, str]:
    sent: dict[str, float] = {}

    def fire() -> None:
        sent["at"] = time.perf_counter()
        os.kill(os.getpid(), signal.SIGINT)

    timer = threading.Timer(delay, fire)
    timer.start()
    try:
        call()
    except KeyboardInterrupt as stopped:
        arrived = time.perf_counter()
        timer.join()
        partial = getattr(stopped, "partial", None)
        if partial is None:
            return arrived - sent["at"], "no partial result"
        if hasattr(partial, "status") and not isinstance(partial.status, str):
            done = int((partial.status != "interrupted").sum())
            return arrived - sent["at"], f"{done} of {len(partial)} tracks finished"
        return arrived - sent["at"], f"ransac_stop={partial.ransac.stop}, {partial.ransac.iterations} samples"
    timer.cancel()
    raise RuntimeError("the call ended before the signal: make the workload longer")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--points", type=int, default=2_000_000)
    parser.add_argument("--delay", type=float, default=0.5, help="seconds from the call's start to SIGINT")
    args = parser.parse_args()
    workloads = {
        f"triangulate_points ({args.points} tracks, optimal)": points_workload(args.points),
        "triangulate_lines (40 lines, gap 1e-9)": lines_workload(),
        "estimate_pose robust (20k all-outlier points)": pose_workload(),
    }
    print(f"SIGINT {args.delay} s after the start; {args.repeats} runs each")
    for name, call in workloads.items():
        runs = [latency(call, args.delay) for _ in range(args.repeats)]
        seconds = [r[0] for r in runs]
        print(f"{name}: median {1e3 * statistics.median(seconds):.1f} ms, max {1e3 * max(seconds):.1f} ms "
              f"({runs[-1][1]})")


if __name__ == "__main__":
    main()
