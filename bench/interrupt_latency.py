"""How fast Ctrl-C stops the long calls: SIGINT is sent to this process while the call runs, and the time
from the signal to the ``KeyboardInterrupt`` reaching Python is measured; for the point batch also the
memory the call takes per track.

    .venv/bin/python bench/interrupt_latency.py [--repeats 3] [--points 2000000] [--only points line ...]
    .venv/bin/python bench/interrupt_latency.py --only ransac200k [--signals 20] [--window 0.5] [--seed 0]

Workloads (each would run for seconds to hours if nothing stopped it):
- ``points``: ``triangulate_points``, 2M tracks in 3 views, ``optimal``; each run in a fresh process, which
  reports the peak resident memory the call added (``ru_maxrss``) per track, for the interrupted call
  and for one uninterrupted call;
- ``lines``: ``triangulate_lines``, 40 noisy segments in 4 views, branch and bound to a 1e-9 gap;
- ``pose``: ``estimate_pose(options=PoseOptions(ransac=RansacOptions(...)))``, 20k all-outlier points, no inlier-ratio cap;
- ``ransac200k``: the robust pose on 200k points, ``--inliers`` (0.5) of them true, sampling without end
  (``min_iterations`` 10¹²); SIGINT at ``--signals`` (20) seeded random moments in the first ``--window`` (0.5) s of
  the call: the set-up (the data's checks and preparation) and the first local optimisations;
- ``line``: one ``triangulate_line``, the paper's relaxation to a 1e-9 gap with ``max_nodes`` nodes
  (``--single-nodes``, about 1.6 ms each on the shared 2-core machine): a build that does not stop single calls runs on to
  the node cap, and the "latency" is the rest of the call;
- ``quadric``: one ``triangulate_quadric`` of a disc seen in 5 views, the relaxation bound, likewise
  (about 3 ms per node).
Prints the median and largest latency per workload, and what the ``partial`` result says.
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import signal
import statistics
import subprocess
import sys
import threading
import time
from pathlib import Path

import numpy as np

import pluecker

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
from triangulation_scenes import line_tracks  # noqa: E402

from pluecker.experiments.josephson_kahl_2008.conics import disc_scene  # noqa: E402


def points_input(n: int):
    rng = np.random.default_rng(0)
    K = np.array([[800.0, 0, 320], [0, 800, 240], [0, 0, 1]])
    P = np.array([K @ np.hstack([np.eye(3), [[c], [0], [5]]]) for c in (-1.0, 0.0, 1.0)])
    X = rng.normal(size=(n, 3))
    x = np.stack([(p @ np.c_[X, np.ones(n)].T).T for p in P], axis=1)
    x = x[..., :2] / x[..., 2:] + rng.normal(0, 1, (n, 3, 2))
    return P, x


def lines_workload():
    P, segments = line_tracks(0, n=40, views=4, sigma=2.0)
    options = pluecker.TriangulationOptions(max_relative_gap=1e-9, max_nodes=10**7, line_bound="relaxation")
    return lambda: pluecker.triangulate_lines(P, segments, method="optimal", options=options)


def pose_workload():
    rng = np.random.default_rng(0)
    n = 20_000
    camera = pluecker.Camera(800, 800, 320, 240)
    X = rng.uniform(-1, 1, (n, 3)) + [0, 0, 6]
    u = rng.uniform(0, 640, (n, 2))
    ransac = pluecker.RansacOptions(min_inlier_ratio=0.0, max_iterations=10**12, confidence=1 - 1e-12)
    return lambda: pluecker.estimate_pose(camera, u, X, options=pluecker.PoseOptions(ransac=ransac))


def pose_200k_workload(inliers: float):
    """The robust pose on 200k points, a fraction ``inliers`` of them true (1 px noise), the others random
    pixels; ``min_iterations`` = ``max_iterations`` = 10¹², so that only a stop ends the sampling."""
    rng = np.random.default_rng(0)
    n = 200_000
    camera = pluecker.Camera(800, 800, 320, 240)
    X = rng.uniform(-1, 1, (n, 3)) + [0, 0, 6]
    u = X[:, :2] / X[:, 2:] * 800 + [320, 240] + rng.normal(0, 1, (n, 2))
    wrong = rng.random(n) >= inliers
    u[wrong] = rng.uniform(0, [640, 480], (int(wrong.sum()), 2))
    ransac = pluecker.RansacOptions(min_inlier_ratio=0.0, max_iterations=10**12, min_iterations=10**12)
    return lambda: pluecker.estimate_pose(camera, u, X, options=pluecker.PoseOptions(ransac=ransac))


def run_ransac_200k(signals: int, window: float, seed: int, inliers: float) -> None:
    """Ctrl-C latency of the 200k robust pose, SIGINT at ``signals`` moments drawn uniformly in the first
    ``window`` seconds of the call (seeded): median and largest, and the moments of the three slowest."""
    call = pose_200k_workload(inliers)
    moments = np.random.default_rng(seed).uniform(0.0, window, signals)
    runs = [latency(call, float(delay)) for delay in moments]
    seconds = np.array([r[0] for r in runs])
    slowest = np.argsort(seconds)[::-1][:3]
    print(f"estimate_pose robust (200k points, {100 * inliers:.0f} % inliers), {signals} signals in the first {window} s (seed {seed}): "
          f"median {1e3 * np.median(seconds):.1f} ms, max {1e3 * seconds.max():.1f} ms; slowest at "
          + ", ".join(f"{1e3 * moments[k]:.0f} ms -> {1e3 * seconds[k]:.0f} ms" for k in slowest)
          + f" ({runs[-1][1]})", flush=True)


def single_line_workload(nodes: int):
    P, segments = line_tracks(0, n=1, views=4, sigma=2.0)
    options = pluecker.TriangulationOptions(max_relative_gap=1e-9, max_nodes=nodes, line_bound="relaxation")
    return lambda: pluecker.triangulate_line(P, segments[0], method="optimal", options=options)


def single_quadric_workload(nodes: int):
    scene = disc_scene(3)  # conics fitted to 1 px noisy points of a disc in 5 views
    options = pluecker.TriangulationOptions(max_relative_gap=1e-9, max_nodes=nodes, quadric_bound="relaxation")
    return lambda: pluecker.triangulate_quadric(scene.cameras, scene.conics, scene.covariances, method="optimal",
                                                options=options)


def describe(partial) -> str:
    if partial is None:
        return "no partial result: the call was not stopped, it ran to its end"
    if hasattr(partial, "details") and partial.details.ransac is not None:
        return f"ransac_stop={partial.details.ransac.stop}, {partial.details.ransac.iterations} samples"
    if hasattr(partial, "status") and not isinstance(partial.status, str):
        done = int((partial.status != "interrupted").sum())
        return f"{done} of {len(partial)} tracks finished"
    return f"status={partial.status}, {partial.nodes} nodes"


def latency(call, delay: float) -> tuple[float, str]:
    """Seconds from SIGINT (sent ``delay`` s after the call starts) to the KeyboardInterrupt, and what
    the partial result says."""
    sent: dict[str, float] = {}

    def fire() -> None:
        sent["at"] = time.perf_counter()
        os.kill(os.getpid(), signal.SIGINT)

    timer = threading.Timer(delay, fire)
    try:
        timer.start()  # inside the try: a SIGINT due at once may arrive while the timer starts
        call()
    except KeyboardInterrupt as stopped:
        arrived = time.perf_counter()
        timer.join()
        return arrived - sent["at"], describe(getattr(stopped, "partial", None))
    # A build that does not check signals during the call raises after it returned.
    try:
        timer.join()
        while True:
            time.sleep(0.001)
    except KeyboardInterrupt:
        return time.perf_counter() - sent["at"], describe(None)


def peak_rss() -> int:
    """Peak resident memory of this process so far, bytes (Linux reports kB)."""
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024


def current_rss() -> int:
    with open("/proc/self/statm") as f:
        return int(f.read().split()[1]) * os.sysconf("SC_PAGE_SIZE")


def points_child(n: int, delay: float | None) -> None:
    """One point-batch run in this (fresh) process; prints a JSON line."""
    P, x = points_input(n)
    before = current_rss()
    call = lambda: pluecker.triangulate_points(P, x, method="optimal")  # noqa: E731
    if delay is None:
        started = time.perf_counter()
        result = call()
        out = {"seconds": time.perf_counter() - started, "finished": int((result.status != "interrupted").sum())}
    else:
        seconds, what = latency(call, delay)
        out = {"latency": seconds, "what": what}
    out["bytes_per_track"] = (peak_rss() - before) / n
    print(json.dumps(out))


def run_points(n: int, repeats: int, delay: float) -> None:
    def child(*extra: str) -> dict:
        command = [sys.executable, __file__, "--child-points", str(n), *extra]
        line = subprocess.run(command, check=True, capture_output=True, text=True).stdout.strip().splitlines()[-1]
        return json.loads(line)

    runs = [child("--delay", str(delay)) for _ in range(repeats)]
    seconds = [r["latency"] for r in runs]
    memory = [r["bytes_per_track"] for r in runs]
    print(f"triangulate_points ({n} tracks, optimal): Ctrl-C latency median {1e3 * statistics.median(seconds):.0f} ms, "
          f"max {1e3 * max(seconds):.0f} ms; peak memory of the interrupted call {statistics.median(memory):.0f} B/track "
          f"({runs[-1]['what']})", flush=True)
    full = child()
    print(f"triangulate_points ({n} tracks, optimal), not interrupted: {full['seconds']:.2f} s, "
          f"peak memory of the call {full['bytes_per_track']:.0f} B/track", flush=True)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--points", type=int, default=2_000_000)
    parser.add_argument("--delay", type=float, default=0.5, help="seconds from the call's start to SIGINT")
    parser.add_argument("--single-nodes", type=int, default=10_000, help="node cap of the single calls")
    parser.add_argument("--signals", type=int, default=20, help="SIGINTs of the ransac200k workload")
    parser.add_argument("--window", type=float, default=0.5, help="ransac200k: seconds after the start the SIGINTs fall in")
    parser.add_argument("--seed", type=int, default=0, help="ransac200k: seed of the SIGINT moments")
    parser.add_argument("--inliers", type=float, default=0.5, help="ransac200k: fraction of true correspondences")
    parser.add_argument("--only", nargs="*", choices=["points", "lines", "pose", "line", "quadric", "ransac200k"])
    parser.add_argument("--child-points", type=int, help=argparse.SUPPRESS)
    args = parser.parse_args()
    # Python's own handler, also when started in the background (SIGINT then inherited as ignored).
    signal.signal(signal.SIGINT, signal.default_int_handler)
    if args.child_points:
        points_child(args.child_points, args.delay if "--delay" in sys.argv else None)
        return
    chosen = set(args.only or ["points", "lines", "pose", "line", "quadric", "ransac200k"])
    print(f"SIGINT {args.delay} s after the start; {args.repeats} runs each; {pluecker.get_num_threads()} threads",
          flush=True)
    if "points" in chosen:
        run_points(args.points, args.repeats, args.delay)
    if "ransac200k" in chosen:
        run_ransac_200k(args.signals, args.window, args.seed, args.inliers)
    workloads = {
        "lines": ("triangulate_lines (40 lines, gap 1e-9)", lines_workload),
        "pose": ("estimate_pose robust (20k all-outlier points)", pose_workload),
        "line": (f"triangulate_line (relaxation, gap 1e-9, max_nodes {args.single_nodes})",
                 lambda: single_line_workload(args.single_nodes)),
        "quadric": (f"triangulate_quadric (relaxation, gap 1e-9, max_nodes {args.single_nodes})",
                    lambda: single_quadric_workload(args.single_nodes)),
    }
    for key, (name, make) in workloads.items():
        if key not in chosen:
            continue
        call = make()
        runs = [latency(call, args.delay) for _ in range(args.repeats)]
        seconds = [r[0] for r in runs]
        print(f"{name}: median {1e3 * statistics.median(seconds):.1f} ms, max {1e3 * max(seconds):.1f} ms "
              f"({runs[-1][1]})", flush=True)


if __name__ == "__main__":
    main()
