"""Profile of the certified re-triangulation of a COLMAP model with the cameras fixed
(``pluecker.colmap.retriangulate(rec, sigma_px=1.0)``, i.e. ``pluecker._core.triangulate_points`` in the rows form
with the images' ``View``s): where the time goes, per stage and per track.

**What runs.**

1. ``retriangulate``: one call of ``pluecker.colmap.retriangulate(rec, sigma_px=1.0)`` after a warm-up on a
   tiny model, timed by ``time.perf_counter`` (wall; the first column of the summary). ``gather`` is one
   separate call of ``pluecker.colmap._observations`` (reading the model's observations into arrays, the
   Python part of ``retriangulate``); ``solve`` = wall − gather.
2. **Stage runs**: the gathered observations are solved again by ``triangulate_points`` (rows form) with
   ``TriangulationOptions(method=...)`` ``linear``, ``local`` and ``optimal`` (the default, what
   ``retriangulate`` runs), ``--repeats`` times each, in the order linear, local, optimal, linear, ...
   Per track the fastest of the repeats of each method is kept (its ``time_seconds``, measured by the Rust
   core around the track alone). Through a lens (``crates/pluecker/src/triangulation/point/lens.rs``):
   ``linear`` is the DLT on the undistorted pixels plus the exact cost at it; ``local`` adds the
   first-order local minimisation and the refinement on the exact cost; ``optimal`` adds the certificate
   (``lens_convexity_test``, no search) at the local answer, and only where it fails, the first-order
   global search (branch and bound, ``nodes``), a second refinement and a second certificate. So the stage
   columns of a track are **differences of separate runs**:

   - ``linear``: t(linear);
   - ``minimise``: t(local) − t(linear), the local minimisation on both costs;
   - ``certify``: t(optimal) − t(local), the certificate, plus the fallback search where it ran;
   - ``total``: t(optimal).

   A stage of a few µs is at the level of the timer and the scheduling noise: a per-track difference can
   be negative. The sums over all tracks are reliable to a few %; the per-track columns of the slowest-10
   table come from a further run of that track **alone** (``n_tracks=1``, its own rows only; fastest of
   ``ALONE_REPEATS`` per method), so that they are not a difference of two noisy batch entries.
3. pycolmap's bundle adjustment of the points only (poses, rigs, intrinsics constant, default Ceres
   tolerances, started from the model's points, on a copy; ``_points_only_ba`` of
   ``bench/compare_colmap.py``), in the same process, and the ratio retriangulate / BA. pycolmap's BA
   uses its own thread count (not ``--threads``).

**Counts** carried by the batch result and reported: ``status``, ``certified``, ``certificate`` (kind),
``nodes`` (of the branch and bound, 0 for a convexity test), ``iterations`` (of the local minimisation),
``relative_gap``.

**Printed**: total wall, the summed per-track time (with ``--threads 1`` the two differ by the gather and the
batch overhead), µs per observation, certified count, the per-stage sums and shares, a log-spaced histogram
of the per-track ``optimal`` time, p50 / p90 / p99 / max and the share of the summed time spent by the
slowest 1 % of the tracks, the slowest ``--top`` tracks (point3D id, observations, distinct images, status,
certified, certificate, nodes, iterations, alone: total and stage ms), and the BA comparison.

**Models** (``--model``):

- ``opencv``: ``pluecker.scenes.colmap_reconstruction("OPENCV", [385, 430, 150, 300, -0.008, 0.0015, 0.005,
  -0.003], 300, 600, points=N, seed=S)`` (``pycolmap.synthesize_dataset``, 2 rigs x 6 frames, 1 px noise);
- ``simple_radial_strong``, ``fisheye80``: ``strong_radial_model`` / ``fisheye_model`` of
  ``bench/compare_colmap.py`` (SIMPLE_RADIAL f = 5000 px, k = -14, inside the fold; OPENCV_FISHEYE out to 80°);
- ``gs_data``: ``distorted/sparse/0`` of the GitHub repository ``mamechun/gs_data`` (128 SIMPLE_RADIAL
  cameras, 5751 points), read from ``$PLUECKER_GS_DATA`` or ``bench/out/gs_data/`` if there, else its three
  ``.bin`` files (2.4 MB) are downloaded there from raw.githubusercontent.com; never committed;
- any other value: a COLMAP model folder, ``pycolmap.Reconstruction(path)``.

``--points`` and ``--seed`` apply to the synthetic models; ``--threads`` sets ``RAYON_NUM_THREADS`` before
pluecker is imported (default 1: per-observation time without sharing the 2 cores).

Run from the repository root::

    .venv/bin/python bench/profile_colmap.py --quick               # a smoke run, a few seconds
    .venv/bin/python bench/profile_colmap.py --model opencv --points 12000
    .venv/bin/python bench/profile_colmap.py --model gs_data
"""

from __future__ import annotations

import argparse
import os
import sys
import time
import urllib.request
from pathlib import Path
from typing import Any

import numpy as np
from profile_stats import fmt_ms, histogram, table, tail_line, tail_stats

HERE = Path(__file__).resolve().parent
OPENCV_PARAMS = [385.0, 430.0, 150.0, 300.0, -0.008, 0.0015, 0.005, -0.003]
OPENCV_SIZE = (300, 600)
SIGMA_PX = 1.0
METHODS = ("linear", "local", "optimal")
ALONE_REPEATS = 5
GS_DATA_FILES = ("cameras.bin", "images.bin", "points3D.bin")
GS_DATA_URL = "https://raw.githubusercontent.com/mamechun/gs_data/main/distorted/sparse/0/"
GS_DATA_CACHE = HERE / "out" / "gs_data" / "distorted" / "sparse" / "0"


def gs_data_folder() -> Path:
    """The gs_data model's folder: ``$PLUECKER_GS_DATA``, else the cache under bench/out (downloaded once)."""
    if os.environ.get("PLUECKER_GS_DATA"):
        return Path(os.environ["PLUECKER_GS_DATA"])
    if not all((GS_DATA_CACHE / name).exists() for name in GS_DATA_FILES):
        GS_DATA_CACHE.mkdir(parents=True, exist_ok=True)
        for name in GS_DATA_FILES:
            print(f"downloading {GS_DATA_URL}{name} -> {GS_DATA_CACHE}", file=sys.stderr)
            try:
                urllib.request.urlretrieve(GS_DATA_URL + name, GS_DATA_CACHE / name)
            except OSError as exc:
                (GS_DATA_CACHE / name).unlink(missing_ok=True)
                sys.exit(f"could not download {GS_DATA_URL}{name} ({exc}); put cameras.bin, images.bin and "
                         f"points3D.bin of mamechun/gs_data's distorted/sparse/0 in {GS_DATA_CACHE} or set "
                         "PLUECKER_GS_DATA to their folder")
    return GS_DATA_CACHE


def load_model(name: str, points: int, seed: int) -> Any:
    import pycolmap
    from pluecker.scenes import colmap_reconstruction

    if name == "opencv":
        return colmap_reconstruction("OPENCV", OPENCV_PARAMS, *OPENCV_SIZE, points=points, seed=seed)
    if name in ("simple_radial_strong", "fisheye80"):
        sys.path.insert(0, str(HERE))
        import compare_colmap  # its models, by import (it needs PoseLib too)

        build = compare_colmap.strong_radial_model if name == "simple_radial_strong" else compare_colmap.fisheye_model
        return build(seed, points)
    if name == "gs_data":
        return pycolmap.Reconstruction(str(gs_data_folder()))
    return pycolmap.Reconstruction(name)


def solve(pluecker: Any, o: Any, method: str, rows: np.ndarray | None = None) -> tuple[Any, float]:
    """``triangulate_points`` (rows form) of the gathered observations ``o`` (only the observations ``rows``
    of one track, renumbered 0, if given) with ``method``: (result, wall seconds)."""
    track, camera, pixels = o.track, o.camera, o.pixels
    n_tracks = len(o.ids)
    if rows is not None:
        track, camera, pixels, n_tracks = np.zeros(len(rows), dtype=np.int64), camera[rows], pixels[rows], 1
    covariances = np.broadcast_to(SIGMA_PX**2 * np.eye(2), (len(track), 2, 2))
    options = pluecker.TriangulationOptions(method=method)
    started = time.perf_counter()
    result = pluecker.triangulate_points(o.views, pixels, covariances=covariances, track=track, image=camera, options=options, n_tracks=n_tracks)
    return result, time.perf_counter() - started


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--model", default="opencv",
                        help="opencv, simple_radial_strong, fisheye80, gs_data, or a COLMAP model folder")
    parser.add_argument("--points", type=int, default=12000, help="3-D points of a synthetic model")
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--threads", type=int, default=1, help="RAYON_NUM_THREADS for pluecker (default 1)")
    parser.add_argument("--top", type=int, default=10, help="slowest tracks listed")
    parser.add_argument("--repeats", type=int, default=3, help="stage runs per method (fastest kept per track)")
    parser.add_argument("--no-ba", action="store_true", help="skip pycolmap's bundle adjustment")
    parser.add_argument("--quick", action="store_true", help="500 points, 1 repeat: a smoke run")
    args = parser.parse_args()
    if args.quick:
        args.points, args.repeats = min(args.points, 500), 1
    os.environ["RAYON_NUM_THREADS"] = str(args.threads)  # before pluecker is imported
    import pluecker
    import pycolmap
    from pluecker import colmap
    from pluecker.scenes import colmap_reconstruction

    pycolmap.logging.minloglevel = 2
    print(f"pluecker {pluecker.__version__} ({pluecker.get_num_threads()} threads), pycolmap {pycolmap.__version__}, "
          f"{os.cpu_count()} cores, load average {os.getloadavg()[0]:.2f}")
    rec = load_model(args.model, args.points, args.seed)
    colmap.retriangulate(colmap_reconstruction("OPENCV", OPENCV_PARAMS, *OPENCV_SIZE, points=20, seed=99))  # warm-up
    cameras = sorted({c.model.name for c in rec.cameras.values()})
    print(f"model {args.model}: {rec.num_points3D()} points, {rec.num_reg_images()} images, cameras {', '.join(cameras)}"
          + (f" (points={args.points}, seed={args.seed})" if args.model in ("opencv", "simple_radial_strong", "fisheye80")
             else ""))

    # 1. The call as a user makes it, and its gather part alone.
    started = time.perf_counter()
    run = colmap.retriangulate(rec, sigma_px=SIGMA_PX)
    wall = time.perf_counter() - started
    started = time.perf_counter()
    o = colmap._observations(rec, SIGMA_PX)
    gather = time.perf_counter() - started
    n, m = len(o.ids), len(o.track)
    assert np.array_equal(o.ids, run.point3D_ids)

    # 2. Stage runs: per track, the fastest of the repeats of each method.
    best = {method: np.full(n, np.inf) for method in METHODS}
    walls = {method: (np.inf, np.nan) for method in METHODS}  # fastest batch: (wall, its summed per-track time)
    final: Any = None
    for _ in range(args.repeats):
        for method in METHODS:
            result, seconds = solve(pluecker, o, method)
            best[method] = np.minimum(best[method], np.asarray(result.time_seconds))
            walls[method] = min(walls[method], (seconds, float(np.sum(result.time_seconds))))
            if method == "optimal":
                final = result
    t_opt = best["optimal"]
    stage = {"linear": best["linear"], "minimise": best["local"] - best["linear"], "certify": t_opt - best["local"]}
    status, certified = np.asarray(final.status), np.asarray(final.certified)
    kinds, nodes, iterations = np.asarray(final.certificate), np.asarray(final.nodes), np.asarray(final.iterations)
    observations = np.bincount(o.track, minlength=n)
    pairs = np.unique(o.track * len(o.P) + o.camera)  # distinct (track, image) pairs
    images = np.bincount(pairs // len(o.P), minlength=n)

    print(f"\n## Summary ({n} tracks, {m} observations, {m / n:.1f} per track; sigma_px = {SIGMA_PX})\n")
    first_run = np.asarray(run.result.time_seconds)
    print(f"- retriangulate wall: {fmt_ms(wall)} ms = gather {fmt_ms(gather)} ms (separate call) + solve "
          f"{fmt_ms(wall - gather)} ms; {1e6 * wall / m:.2f} µs per observation ({1e6 * (wall - gather) / m:.2f} µs "
          "solve only)")
    print(f"- summed per-track time: {fmt_ms(first_run.sum())} ms in that call; {fmt_ms(t_opt.sum())} ms as the "
          f"per-track fastest of {args.repeats} optimal runs ({1e6 * t_opt.sum() / m:.2f} µs per observation)")
    print(f"- certified {int(certified.sum())} / {n} ({100 * certified.mean():.2f} %); status "
          + ", ".join(f"{s} {c}" for s, c in zip(*np.unique(status, return_counts=True))))
    print("- certificates: " + ", ".join(f"{k} {c}" for k, c in zip(*np.unique(kinds, return_counts=True)))
          + f"; nodes: {int((nodes > 0).sum())} tracks searched, {int(nodes.sum())} in all, max {int(nodes.max())}; "
          f"local iterations mean {iterations.mean():.2f}, max {int(iterations.max())}")

    print("\n## Stages (sums over tracks of the per-track fastest runs; differences of separate runs)\n")
    rows = [[name, fmt_ms(float(v.sum())), f"{100 * v.sum() / t_opt.sum():.1f} %", f"{1e6 * v.sum() / m:.2f}",
             int((v < 0).sum())] for name, v in stage.items()]
    rows.append(["total (optimal)", fmt_ms(float(t_opt.sum())), "100 %", f"{1e6 * t_opt.sum() / m:.2f}", 0])
    print("\n".join(table(["stage", "summed ms", "share", "µs per observation", "tracks < 0"], rows)))
    print("\nBatch wall per method, fastest of the repeats (ms), and the part outside the per-track timers (wall − "
          "that run's summed time_seconds: reading the arrays, grouping the tracks, the result arrays): "
          + ", ".join(f"{k} {fmt_ms(w)} (outside {fmt_ms(w - s)})" for k, (w, s) in walls.items()))

    print("\n## Per-track time, method optimal (fastest of the repeats)\n")
    print("```\n" + "\n".join(histogram(t_opt)) + "\n```\n")
    print(tail_line(t_opt))
    searched = nodes > 0
    if searched.any():
        print(f"\nTracks with a search (nodes > 0): {int(searched.sum())}, {fmt_ms(float(t_opt[searched].sum()))} ms "
              f"({100 * t_opt[searched].sum() / t_opt.sum():.1f} % of the summed time)")
    # Where the time goes against how far off axis a track is seen: its largest |pixel − principal point| / f.
    K = np.array([np.asarray(view.camera.K, dtype=float) for view in o.views])[o.camera]
    radius = np.hypot((o.pixels[:, 0] - K[:, 0, 2]) / K[:, 0, 0], (o.pixels[:, 1] - K[:, 1, 2]) / K[:, 1, 1])
    off_axis = np.zeros(n)
    np.maximum.at(off_axis, o.track, radius)
    edges = np.quantile(off_axis, [0.0, 0.25, 0.5, 0.75, 0.9, 1.0])
    print("\nPer-track time by the track's largest distorted radius |u − c| / f over its observations (quantile bins):\n")
    radius_rows = []
    for k, (a, b) in enumerate(zip(edges[:-1], edges[1:])):
        sel = (off_axis >= a) & ((off_axis < b) if k < len(edges) - 2 else (off_axis <= b))
        if sel.any():
            radius_rows.append([f"{a:.3f} – {b:.3f}", int(sel.sum()), fmt_ms(float(np.median(t_opt[sel]))),
                                fmt_ms(float(np.median(stage["certify"][sel]))),
                                f"{100 * t_opt[sel].sum() / t_opt.sum():.1f} %"])
    print("\n".join(table(["max radius / f", "tracks", "median ms", "median certify ms", "share of time"], radius_rows)))
    failed = ~certified
    if failed.any():
        print(f"Uncertified tracks: {int(failed.sum())}, {fmt_ms(float(t_opt[failed].sum()))} ms "
              f"({100 * t_opt[failed].sum() / t_opt.sum():.1f} % of the summed time)")

    print(f"\n## The {args.top} slowest tracks (by the batch's optimal time; stage ms: the track alone, fastest of "
          f"{ALONE_REPEATS} per method; last line: the median track, the same way, for reference)\n")
    order = np.argsort(t_opt)
    slowest = order[::-1][:args.top]
    median_track = int(order[len(order) // 2])
    top_rows = []
    for t in [*slowest, median_track]:
        rows_t = np.flatnonzero(o.track == t)
        alone = {}
        for method in METHODS:
            times = []
            for _ in range(ALONE_REPEATS):
                r, _seconds = solve(pluecker, o, method, rows_t)
                times.append(float(np.asarray(r.time_seconds)[0]))
            alone[method] = min(times)
        label = f"{int(o.ids[t])}" if t != median_track else f"median track: {int(o.ids[t])}"
        top_rows.append([label, len(rows_t), int(images[t]), status[t], bool(certified[t]), kinds[t], int(nodes[t]),
                         int(iterations[t]), fmt_ms(float(t_opt[t])), fmt_ms(alone["optimal"]), fmt_ms(alone["linear"]),
                         fmt_ms(alone["local"] - alone["linear"]), fmt_ms(alone["optimal"] - alone["local"]),
                         f"{float(np.asarray(final.relative_gap)[t]):.1e}"])
    print("\n".join(table(["point3D_id", "obs", "images", "status", "certified", "certificate", "nodes", "iterations",
                           "batch ms", "alone ms", "linear", "minimise", "certify", "relative gap"], top_rows)))
    typical = tail_stats(t_opt)["p50"]
    print(f"\nSlowest track: {fmt_ms(float(t_opt[slowest[0]]))} ms, {float(t_opt[slowest[0]]) / typical:.0f}x the median "
          f"({fmt_ms(typical)} ms); observations of the slowest {len(slowest)}: "
          f"{observations[slowest].tolist()} (median over all tracks {int(np.median(observations))})")

    if not args.no_ba:
        sys.path.insert(0, str(HERE))
        from compare_colmap import _points_only_ba

        _copy, ba = _points_only_ba(rec, tight=False)
        print(f"\n## pycolmap points-only BA (default tolerances, on a copy)\n\nBA {fmt_ms(ba)} ms; retriangulate "
              f"{fmt_ms(wall)} ms; ratio pluecker / BA = {wall / ba:.2f} (solve only: {(wall - gather) / ba:.2f})")


if __name__ == "__main__":
    main()
