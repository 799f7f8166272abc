"""Profile of the certified pose (``pluecker.estimate_pose`` with ``PoseOptions(certify=CertifyOptions())``),
pinhole and through a ``Camera``: where the time goes, per stage and per scene.

**Scenes**: those of ``bench/compare_global_pose.py`` (``bench/global_pose_scenes.py``), by import (``all_rows`` / ``make_synthetic``):
640 x 480, ``fx = fy = f``, a random pose, object 4.2-7.8 units deep, 1 px Gaussian noise; scene ``i`` of a
row is ``make_synthetic(row, --seed + i)``. Rows (``--rows`` selects by substring):

- ``f{250,800,4000,15000}-n100-points`` (100 points) and ``-n100-mixed`` (50 points + 50 segments): pinhole;
- ``lens-strong-f{250,800,4000,15000}-n100-{points,mixed}``: OPENCV, k1, k2, p1, p2 = -0.3, 0.1, 1e-3, -5e-4;
- ``lens-fisheye-f{250,800}-n100-{points,mixed}``: OPENCV_FISHEYE, k1..k4 = 0.05, -0.01, 0.002, -0.0005.

**Runs per scene**, alternating, ``--repeats`` times each, the fastest kept (by the library's own
``time_seconds``): ``default`` = ``estimate_pose(camera, ...)`` (no certificate), and ``certified`` =
the same with ``options=PoseOptions(certify=CertifyOptions())`` (default gap 1e-3, each search's own node
cap). The scene's time is the certified call's ``time_seconds``.

**Stage columns** of a scene (ms):

- ``algebraic``, ``refine``: ``details.stages`` of the certified call (the estimator, e.g. ``trust-region``,
  and ``refinement``), each timed by the library inside that one call;
- ``other``: default call's ``time_seconds`` minus its stages: the starts, the runner-up search
  (``ambiguity``), the covariance, the checks;
- ``certify``: certified ``time_seconds`` − default ``time_seconds``: the certificate (the
  sublevel-set test, ``sublevel_set`` / ``lens_sublevel_set``, with its search over ``nodes`` rotation
  cells). A **difference of separate runs**: noisy when it is small; can be negative by noise;
- ``boundary``: Python wall of the certified call − its ``time_seconds`` (argument conversion,
  result objects).

**Counts** printed: status, certified, certificate kind, ``nodes`` and ``solver_iterations`` of the
certificate, iterations per stage, ``details.uncertified_reason`` of the uncertified scenes. A search that
reached its node cap returns no certificate (``certificate is None``); its kind is shown as ``none: node
cap`` and its nodes as the cap, read from the reason's text (``max_nodes = N``).

**Printed**: per row (scenes, certified, statuses, p50 / p90 / max of the certified time, the summed stage
shares, mean / max nodes), a log-spaced histogram of the per-scene certified time over all rows, p50 / p90
/ p99 / max and the share of the summed time spent by the slowest 1 % of the scenes, and the slowest ``--top``
scenes with their stage breakdown.

Run from the repository root::

    .venv/bin/python bench/profile_pose.py --quick              # 3 scenes of the f800 rows, a few seconds
    .venv/bin/python bench/profile_pose.py --scenes 20          # the 20 rows, 20 scenes each
"""

from __future__ import annotations

import argparse
import os
import re
import sys
import time
from collections import Counter
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from profile_stats import fmt_ms, histogram, table, tail_line

sys.path.insert(0, str(Path(__file__).resolve().parent))
import global_pose_scenes as cgp  # noqa: E402  (the scene generator of the global-minimum benchmark)
import pluecker  # noqa: E402

ROW_NAMES = ([f"f{f}-n100-{d}" for f in (250, 800, 4000, 15000) for d in ("points", "mixed")]
             + [f"lens-strong-f{f}-n100-{d}" for f in (250, 800, 4000, 15000) for d in ("points", "mixed")]
             + [f"lens-fisheye-f{f}-n100-{d}" for f in (250, 800) for d in ("points", "mixed")])


@dataclass
class Profile:
    """One scene's profile (seconds)."""

    row: str
    seed: int
    status: str
    certified: bool
    kind: str
    nodes: int
    solver_iterations: int
    iterations: str  # per stage, e.g. "5+2"
    total: float  # certified time_seconds
    algebraic: float
    refine: float
    other: float
    certify: float
    boundary: float
    reason: str


def fastest(call: Any, repeats: int) -> tuple[Any, float]:
    """The result of the fastest of ``repeats`` calls (by its ``time_seconds``) and its wall time."""
    best: tuple[Any, float] | None = None
    for _ in range(repeats):
        started = time.perf_counter()
        result = call()
        wall = time.perf_counter() - started
        if best is None or result.time_seconds < best[0].time_seconds:
            best = (result, wall)
    assert best is not None
    return best


def profile_scene(row: Any, seed: int, repeats: int) -> Profile:
    scene = cgp.make_synthetic(row, seed)
    certify = pluecker.PoseOptions(certify=pluecker.CertifyOptions())
    default, _ = fastest(lambda: pluecker.estimate_pose(scene.camera, **scene.kwargs), repeats)
    certified, wall = fastest(lambda: pluecker.estimate_pose(scene.camera, **scene.kwargs, options=certify), repeats)
    d, c = default.details, certified.details
    stage = {s.name: s.time_seconds for s in c.stages}
    refine = stage.pop("refinement", 0.0)
    cert = certified.certificate
    reason = c.uncertified_reason or ""
    # A search that hit its node cap returns no certificate: its nodes are only in the reason's text.
    capped = re.search(r"max_nodes = (\d+)", reason)
    kind = cert.kind if cert is not None else ("none: node cap" if capped else "none")
    nodes = cert.nodes if cert is not None else (int(capped.group(1)) if capped else 0)
    return Profile(
        row=row.name, seed=seed, status=certified.status, certified=bool(certified.certified),
        kind=kind, nodes=nodes,
        solver_iterations=cert.solver_iterations if cert is not None else 0,
        iterations="+".join(str(s.iterations) for s in c.stages), total=c.time_seconds,
        algebraic=sum(stage.values()), refine=refine,
        other=d.time_seconds - sum(s.time_seconds for s in d.stages), certify=c.time_seconds - d.time_seconds,
        boundary=wall - c.time_seconds, reason=reason)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rows", default="", help="comma-separated substrings of the row names (default: all 20)")
    parser.add_argument("--scenes", type=int, default=20, help="scenes per row")
    parser.add_argument("--seed", type=int, default=0, help="scene i of a row uses seed + i")
    parser.add_argument("--repeats", type=int, default=3, help="calls per scene and kind, fastest kept")
    parser.add_argument("--top", type=int, default=10, help="slowest scenes listed")
    parser.add_argument("--quick", action="store_true", help="3 scenes of the f800 rows, 1 repeat")
    args = parser.parse_args()
    if args.quick:
        args.rows, args.scenes, args.repeats = args.rows or "f800-", min(args.scenes, 3), 1
    wanted = [w for w in args.rows.split(",") if w]
    rows = [r for r in cgp.all_rows() if r.name in ROW_NAMES and (not wanted or any(w in r.name for w in wanted))]
    print(f"pluecker {pluecker.__version__}, {os.cpu_count()} cores, load average {os.getloadavg()[0]:.2f}; "
          f"{len(rows)} rows x {args.scenes} scenes (seeds {args.seed}..{args.seed + args.scenes - 1}), "
          f"fastest of {args.repeats} calls")
    warm = cgp.make_synthetic(rows[0], 10**6)
    pluecker.estimate_pose(warm.camera, **warm.kwargs, options=pluecker.PoseOptions(certify=pluecker.CertifyOptions()))

    profiles: list[Profile] = []
    table_rows = []
    for row in rows:
        ps = [profile_scene(row, args.seed + i, args.repeats) for i in range(args.scenes)]
        profiles += ps
        t = np.array([p.total for p in ps])
        shares = [sum(getattr(p, k) for p in ps) / t.sum() for k in ("algebraic", "refine", "other", "certify")]
        nodes = np.array([p.nodes for p in ps])
        statuses = Counter(p.status for p in ps)
        table_rows.append([row.name, len(ps), sum(p.certified for p in ps),
                           ", ".join(f"{k} {v}" for k, v in statuses.most_common()),
                           fmt_ms(float(np.median(t))), fmt_ms(float(np.percentile(t, 90))), fmt_ms(float(t.max())),
                           *(f"{100 * s:.0f} %" for s in shares), f"{nodes.mean():.0f}", int(nodes.max())])
        print(f"  {row.name}: done", file=sys.stderr, flush=True)

    print("\n## Per row (certified call; stage shares of the summed certified time, stages as in the docstring)\n")
    print("\n".join(table(["row", "scenes", "certified", "status", "p50 ms", "p90 ms", "max ms", "algebraic",
                           "refine", "other", "certify", "mean nodes", "max nodes"], table_rows)))

    t = np.array([p.total for p in profiles])
    print(f"\n## Per-scene certified time, all {len(profiles)} scenes\n")
    print("```\n" + "\n".join(histogram(t)) + "\n```\n")
    print(tail_line(t))
    print("\nSummed over all scenes: " + ", ".join(
        f"{k} {fmt_ms(sum(getattr(p, k) for p in profiles))} ms ({100 * sum(getattr(p, k) for p in profiles) / t.sum():.1f} %)"
        for k in ("algebraic", "refine", "other", "certify")) + f" of {fmt_ms(float(t.sum()))} ms; Python boundary "
        f"{fmt_ms(sum(p.boundary for p in profiles))} ms on top")
    reasons = Counter(re.sub(r"(lines2d|points2d)\[\d+\]", r"\1[k]", p.reason) for p in profiles if not p.certified)
    if reasons:
        print("\nUncertified scenes, by reason:")
        for reason, count in reasons.most_common():
            print(f"- {count} x {reason}")

    print(f"\n## The {args.top} slowest scenes (certified call)\n")
    top = sorted(profiles, key=lambda p: p.total, reverse=True)[:args.top]
    print("\n".join(table(["row", "seed", "status", "certified", "certificate", "nodes", "solver it.", "stage it.",
                           "total ms", "algebraic", "refine", "other", "certify", "boundary"],
                          [[p.row, p.seed, p.status, p.certified, p.kind, p.nodes, p.solver_iterations, p.iterations,
                            fmt_ms(p.total), fmt_ms(p.algebraic), fmt_ms(p.refine), fmt_ms(p.other),
                            fmt_ms(p.certify), fmt_ms(p.boundary)] for p in top])))
    print("\nCertificate time per node, by kind (summed certify / summed nodes; a fixed part per call included):\n")
    for kind in sorted({p.kind for p in profiles}):
        ps = [p for p in profiles if p.kind == kind]
        n_nodes = sum(p.nodes for p in ps)
        per_node = f"{1e6 * sum(p.certify for p in ps) / n_nodes:.2f} µs per node" if n_nodes else "no nodes"
        print(f"- {kind}: {len(ps)} scenes, {n_nodes} nodes, {fmt_ms(sum(p.certify for p in ps))} ms: {per_node}")

if __name__ == "__main__":
    main()
