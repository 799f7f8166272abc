"""How fast Ctrl-C stops the long calls: SIGINT is sent at random moments while a call runs, and the time
from the signal to the ``KeyboardInterrupt`` reaching Python (for the command line: to the process's exit)
is measured; for the point batch also the memory the call takes per track.

    .venv/bin/python bench/interrupt_latency.py [--signals 20] [--seed 0] [--only points line30 cli ...]

Each workload gets ``--signals`` signals, each at a moment drawn uniformly (numpy seed ``--seed``) from the
workload's window, measured from the call's start (the command line: from the start of ``cli.run``), so
that the set-up stages (argument conversion, allocation, sorting, reading a model) are hit as often as
their share of the window. Workloads (each would run for seconds to hours if nothing stopped it):

- ``points``: ``triangulate_points(P, x)``, 2M tracks (``--points``) in two pinhole views, default options
  (``optimal``), window 0-1 s (the set-up takes about half of it); each signal in a fresh process, which
  also reports the peak resident memory the call added (``ru_maxrss``) per track; one more fresh process
  runs the call uninterrupted;
- ``line30``: one ``triangulate_line`` seen in 30 views, the paper's relaxation (``line_bound='relaxation'``)
  to a 1e-9 gap, window 0-1.5 s: the root's bound tightening (about 70 conic solves) and the first nodes;
- ``cli-triangulate``: ``pluecker triangulate --colmap MODEL --out DIR`` on a synthetic COLMAP model
  (``--model-points`` 3-D points in 12 images, SIMPLE_RADIAL, :func:`pluecker.scenes.colmap_reconstruction`,
  written once to ``--model-dir``), window: its set-up (reading the model and gathering its observations,
  up to the batch's first poll), measured by a first run; latency to the process's exit;
- ``cli-localize``: ``pluecker localize QUERIES POINTS --colmap MODEL --out DIR``, the model's 12 images as
  queries matched to its points by ``point3D_id``; window: its set-up (up to the first pose);
- ``line-batch``: ``triangulate_lines``, 500,000 noisy segments in 2 views, ``local``, window 0-1 s (set-up and
  the first tracks; what a stop costs a batch of that many tracks);
- ``lines``: ``triangulate_lines``, 40 noisy segments in 4 views, branch and bound to a 1e-9 gap, window 0-1 s;
- ``pose``: ``estimate_pose`` with RANSAC, 20k all-outlier points, no inlier-ratio cap, window 0-1 s;
- ``ransac200k``: the robust pose on 200k points, half of them true, sampling without end (``min_iterations``
  10¹²), window 0-0.5 s: the set-up (the data's checks and preparation) and the first local optimisations;
- ``line``: one ``triangulate_line`` in 4 views, the relaxation to a 1e-9 gap with ``--single-nodes`` nodes,
  window 0-0.5 s (a build that does not stop single calls runs on to the node cap);
- ``quadric``: one ``triangulate_quadric`` of a disc seen in 5 views, the relaxation bound, likewise.
Prints the median and largest latency per workload (``--verbose``: every signal), and what the ``partial``
result says.
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
import tempfile
import threading
import time
from pathlib import Path

import numpy as np

import pluecker

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
from triangulation_scenes import line_tracks  # noqa: E402

from pluecker.experiments.josephson_kahl_2008.conics import disc_scene  # noqa: E402


def points_input(n: int):
    """Two pinhole views 2 units apart and ``n`` noisy tracks (1 px)."""
    rng = np.random.default_rng(0)
    K = np.array([[800.0, 0, 320], [0, 800, 240], [0, 0, 1]])
    P = np.array([K @ np.hstack([np.eye(3), [[c], [0], [5]]]) for c in (-1.0, 1.0)])
    X = rng.normal(size=(n, 3))
    x = np.stack([(p @ np.c_[X, np.ones(n)].T).T for p in P], axis=1)
    x = x[..., :2] / x[..., 2:] + rng.normal(0, 1, (n, 2, 2))
    return P, x


def relaxation(nodes: int = 10**7, **fields):
    return pluecker.TriangulationOptions(certify=pluecker.CertifyOptions(max_relative_gap=1e-9, max_nodes=nodes),
                                         **fields)


def lines_workload():
    P, segments = line_tracks(0, n=40, views=4, sigma=2.0)
    options = relaxation(line_bound="relaxation")
    return lambda: pluecker.triangulate_lines(P, segments, options=options)


def line_batch_workload():
    P, segments = line_tracks(0, n=20_000, views=2, sigma=1.0)
    segments = np.tile(segments, (25, 1, 1, 1))
    options = pluecker.TriangulationOptions(method="local")
    return lambda: pluecker.triangulate_lines(P, segments, options=options)


def pose_workload():
    rng = np.random.default_rng(0)
    n = 20_000
    camera = pluecker.Camera.pinhole(800, 800, 320, 240)
    X = rng.uniform(-1, 1, (n, 3)) + [0, 0, 6]
    u = rng.uniform(0, 640, (n, 2))
    ransac = pluecker.RansacOptions(min_inlier_ratio=0.0, max_iterations=10**12, confidence=1 - 1e-12)
    return lambda: pluecker.estimate_pose(camera, u, X, options=pluecker.PoseOptions(ransac=ransac))


def pose_200k_workload(inliers: float):
    """The robust pose on 200k points, a fraction ``inliers`` of them true (1 px noise), the others random
    pixels; ``min_iterations`` = ``max_iterations`` = 10¹², so that only a stop ends the sampling."""
    rng = np.random.default_rng(0)
    n = 200_000
    camera = pluecker.Camera.pinhole(800, 800, 320, 240)
    X = rng.uniform(-1, 1, (n, 3)) + [0, 0, 6]
    u = X[:, :2] / X[:, 2:] * 800 + [320, 240] + rng.normal(0, 1, (n, 2))
    wrong = rng.random(n) >= inliers
    u[wrong] = rng.uniform(0, [640, 480], (int(wrong.sum()), 2))
    ransac = pluecker.RansacOptions(min_inlier_ratio=0.0, max_iterations=10**12, min_iterations=10**12)
    return lambda: pluecker.estimate_pose(camera, u, X, options=pluecker.PoseOptions(ransac=ransac))


def single_line_workload(nodes: int, views: int = 4):
    P, segments = line_tracks(0, n=1, views=views, sigma=2.0)
    options = relaxation(nodes, line_bound="relaxation")
    return lambda: pluecker.triangulate_line(P, segments[0], options=options)


def single_quadric_workload(nodes: int):
    scene = disc_scene(3)  # conics fitted to 1 px noisy points of a disc in 5 views
    options = relaxation(nodes, quadric_bound="relaxation")
    return lambda: pluecker.triangulate_quadric(scene.cameras, scene.conics, scene.covariances, options=options)


def describe(partial) -> str:
    if partial is None:
        return "no partial result"
    if hasattr(partial, "details") and partial.details.ransac is not None:
        return f"ransac_stop={partial.details.ransac.stop}, {partial.details.ransac.iterations} samples"
    if hasattr(partial, "status") and not isinstance(partial.status, str):
        done = int((partial.status != "interrupted").sum())
        return f"{done} of {len(partial)} tracks finished"
    nodes = partial.certificate.nodes if partial.certificate is not None else 0
    return f"status={partial.status}, {nodes} nodes"


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
    # The call ended before the signal, or a build that does not check signals during the call raises
    # after it returned.
    try:
        timer.join()
        while True:
            time.sleep(0.001)
    except KeyboardInterrupt:
        return time.perf_counter() - sent["at"], "the call was not stopped: it ran to its end"


def moments(rng: np.random.Generator, signals: int, window: float) -> list[float]:
    return sorted(rng.uniform(0.0, window, signals).tolist())


def summary(name: str, delays: list[float], seconds: list[float], what: str, verbose: bool) -> None:
    print(f"{name}: {len(seconds)} signals at random moments in 0-{max(delays):.2f} s: Ctrl-C latency median "
          f"{1e3 * statistics.median(seconds):.0f} ms, max {1e3 * max(seconds):.0f} ms ({what})", flush=True)
    if verbose:
        print("  " + ", ".join(f"{d:.3f}s→{1e3 * s:.0f}ms" for d, s in zip(delays, seconds)), flush=True)


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
    call = lambda: pluecker.triangulate_points(P, x)  # noqa: E731
    if delay is None:
        started = time.perf_counter()
        result = call()
        out = {"seconds": time.perf_counter() - started, "finished": int((result.status != "interrupted").sum())}
    else:
        seconds, what = latency(call, delay)
        out = {"latency": seconds, "what": what}
    out["bytes_per_track"] = (peak_rss() - before) / n
    print(json.dumps(out))


def run_points(n: int, delays: list[float], verbose: bool) -> None:
    def child(*extra: str) -> dict:
        command = [sys.executable, __file__, "--child-points", str(n), *extra]
        line = subprocess.run(command, check=True, capture_output=True, text=True).stdout.strip().splitlines()[-1]
        return json.loads(line)

    runs = [child("--delay", repr(d)) for d in delays]
    summary(f"triangulate_points ({n} tracks, 2 views, optimal)", delays, [r["latency"] for r in runs],
            runs[-1]["what"], verbose)
    print(f"  peak memory of the interrupted call {statistics.median(r['bytes_per_track'] for r in runs):.0f} "
          "B/track", flush=True)
    full = child()
    print(f"triangulate_points ({n} tracks, 2 views, optimal), not interrupted: {full['seconds']:.2f} s, "
          f"peak memory of the call {full['bytes_per_track']:.0f} B/track", flush=True)


# --------------------------------------------------------------------------------------------------
# The command line on a synthetic COLMAP model

#: Runs the ``pluecker`` program (``cli.run``) in a fresh process after printing ``ready`` (imports done);
#: with ``--probe``, the batch entry point prints ``batch`` and ends the process instead of running (the
#: set-up's length).
CLI_CHILD = """\
import os, signal, sys, time
signal.signal(signal.SIGINT, signal.default_int_handler)  # as in an interactive shell
from pluecker import cli, _core
probe = sys.argv[1] == "--probe"
argv = sys.argv[2:] if probe else sys.argv[1:]
if probe:
    def reached(*args, **kwargs):  # also from several threads at once (localize's queries): one line each
        os.write(1, f"batch {time.monotonic()}\\n".encode())
        os._exit(0)
    _core.triangulate_points = _core.estimate_pose = reached
sys.argv = ["pluecker", *argv]
print("ready", time.monotonic(), flush=True)
run = getattr(cli, "run", None)  # builds before the command's Ctrl-C deadline have main only
run() if run is not None else sys.exit(cli.main())
"""


def cli_model(folder: Path, points: int) -> Path:
    """The synthetic model (SIMPLE_RADIAL, 12 images, 1 px noise), its queries and matches, written once."""
    model = folder / "model"
    if (model / "points3D.bin").exists():
        return model
    import pyarrow as pa
    import pyarrow.parquet as pq

    from pluecker.scenes import colmap_reconstruction

    print(f"writing a synthetic COLMAP model of {points} points to {model} (once) ...", flush=True)
    rec = colmap_reconstruction("SIMPLE_RADIAL", [800.0, 640.0, 480.0, -0.05], 1280, 960, points=points, seed=0)
    rng = np.random.default_rng(0)
    queries, matches = {"query": [], "camera_id": []}, []
    for image_id in sorted(rec.images):
        image = rec.images[image_id]
        queries["query"].append(image_id)
        queries["camera_id"].append(image.camera_id)
        observed = image.get_observation_points2D()
        xy = np.array([p.xy for p in observed]).reshape(-1, 2) + rng.normal(0, 1, (len(observed), 2))
        ids = np.array([p.point3D_id for p in observed], dtype=np.int64)
        matches.append(pa.table({"query": np.full(len(ids), image_id, np.int64), "x": xy[:, 0], "y": xy[:, 1],
                                 "point3D_id": ids}))
    folder.mkdir(parents=True, exist_ok=True)
    pq.write_table(pa.table({k: pa.array(v, pa.int64()) for k, v in queries.items()}), folder / "queries.parquet")
    pq.write_table(pa.concat_tables(matches), folder / "matches.parquet")
    model.mkdir(parents=True, exist_ok=True)
    rec.write(str(model))
    return model


def cli_run(argv: list[str], delay: float | None) -> tuple[float, int, str]:
    """Runs the command line in a fresh process; with ``delay``, SIGINT that many seconds after
    ``cli.run`` starts. Returns (seconds from SIGINT to the process's exit, or with ``delay=None``
    the seconds from ``cli.main``'s start to the batch, the exit status, the last line of stderr)."""
    probe = ["--probe"] if delay is None else []
    child = subprocess.Popen([sys.executable, "-c", CLI_CHILD, *probe, *argv], stdout=subprocess.PIPE,
                             stderr=subprocess.PIPE, text=True, start_new_session=True)
    ready = child.stdout.readline().split()
    assert ready and ready[0] == "ready", (ready, child.stderr.read())
    started = float(ready[1])
    if delay is None:
        batch = child.stdout.readline().split()
        child.wait()
        assert batch and batch[0] == "batch", (batch, child.stderr.read())
        return float(batch[1]) - started, child.returncode, ""
    time.sleep(max(0.0, started + delay - time.monotonic()))
    sent = time.monotonic()
    child.send_signal(signal.SIGINT)
    _, err = child.communicate()
    exited = time.monotonic()
    lines = err.strip().splitlines()
    return exited - sent, child.returncode, lines[-1] if lines else ""


def run_cli(name: str, argv: list[str], signals: int, rng: np.random.Generator, verbose: bool) -> None:
    setup, _, _ = cli_run(argv, None)
    delays = moments(rng, signals, setup)
    runs = [cli_run(argv, d) for d in delays]
    codes = sorted({code for _, code, _ in runs})
    summary(f"{name} (set-up {setup:.2f} s)", delays, [s for s, _, _ in runs],
            f"exit status {codes}, last line {runs[-1][2]!r}", verbose)
    for d, (_, code, line) in zip(delays, runs):
        if code != 130:
            print(f"  SIGINT at {d:.3f} s: exit status {code}, last line of stderr {line!r}", flush=True)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--signals", type=int, default=20, help="signals per workload (default 20)")
    parser.add_argument("--seed", type=int, default=0, help="seed of the signals' moments (default 0)")
    parser.add_argument("--points", type=int, default=2_000_000)
    parser.add_argument("--single-nodes", type=int, default=10_000, help="node cap of the single calls")
    parser.add_argument("--model-points", type=int, default=200_000, help="3-D points of the COLMAP model")
    parser.add_argument("--model-dir", type=Path, help="where the COLMAP model is written once (default: "
                        "a folder under the temporary directory named by --model-points)")
    parser.add_argument("--verbose", action="store_true", help="print every signal's moment and latency")
    parser.add_argument("--only", nargs="*", choices=["points", "line30", "cli-triangulate", "cli-localize",
                                                      "line-batch", "lines", "pose", "ransac200k", "line", "quadric"])
    parser.add_argument("--child-points", type=int, help=argparse.SUPPRESS)
    parser.add_argument("--delay", type=float, help=argparse.SUPPRESS)
    args = parser.parse_args()
    # Python's own handler, also when started in the background (SIGINT then inherited as ignored).
    signal.signal(signal.SIGINT, signal.default_int_handler)
    if args.child_points:
        points_child(args.child_points, args.delay)
        return
    chosen = set(args.only or ["points", "line30", "cli-triangulate", "cli-localize"])
    rng = np.random.default_rng(args.seed)
    print(f"{args.signals} signals per workload, seed {args.seed}; {pluecker.get_num_threads()} threads", flush=True)
    if "points" in chosen:
        run_points(args.points, moments(rng, args.signals, 1.0), args.verbose)
    workloads = {
        "line30": ("triangulate_line (30 views, relaxation, gap 1e-9)", 1.5,
                   lambda: single_line_workload(args.single_nodes, views=30)),
        "line-batch": ("triangulate_lines (500,000 lines, 2 views, local)", 1.0, line_batch_workload),
        "lines": ("triangulate_lines (40 lines, relaxation, gap 1e-9)", 1.0, lines_workload),
        "pose": ("estimate_pose robust (20k all-outlier points)", 1.0, pose_workload),
        "ransac200k": ("estimate_pose robust (200k points, 50 % inliers)", 0.5, lambda: pose_200k_workload(0.5)),
        "line": (f"triangulate_line (4 views, relaxation, gap 1e-9, max_nodes {args.single_nodes})", 0.5,
                 lambda: single_line_workload(args.single_nodes)),
        "quadric": (f"triangulate_quadric (relaxation, gap 1e-9, max_nodes {args.single_nodes})", 0.5,
                    lambda: single_quadric_workload(args.single_nodes)),
    }
    for key, (name, window, make) in workloads.items():
        if key not in chosen:
            continue
        call = make()
        delays = moments(rng, args.signals, window)
        runs = [latency(call, d) for d in delays]
        summary(name, delays, [r[0] for r in runs], runs[-1][1], args.verbose)
    if chosen & {"cli-triangulate", "cli-localize"}:
        folder = args.model_dir or Path(tempfile.gettempdir()) / f"pluecker-interrupt-model-{args.model_points}"
        model = cli_model(folder, args.model_points)
        with tempfile.TemporaryDirectory() as out:
            if "cli-triangulate" in chosen:
                run_cli(f"pluecker triangulate --colmap ({args.model_points} points)",
                        ["triangulate", "--colmap", str(model), "--out", out], args.signals, rng, args.verbose)
            if "cli-localize" in chosen:
                run_cli(f"pluecker localize --colmap ({args.model_points} points, 12 queries)",
                        ["localize", str(folder / "queries.parquet"), str(folder / "matches.parquet"), "--colmap",
                         str(model), "--out", out], args.signals, rng, args.verbose)


if __name__ == "__main__":
    main()
