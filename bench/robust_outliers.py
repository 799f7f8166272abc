"""Robust pose on all-outlier data and on data with inliers: time, status and accuracy, for this build and,
optionally, another build of pluecker side by side (the SPRT and the ``min_inlier_ratio``
cap of ``estimate_pose(..., options=PoseOptions(ransac=RansacOptions()))``).

Scenes: ``pluecker.random_scene("general", n_points, n_lines, seed)`` (f = 800 px, 640 x 480), i.i.d.
Gaussian noise of 1 px on every image point and segment endpoint, then a fraction ``ratio`` of the points
and of the lines replaced by outliers (a pixel uniform in the image; a segment with both endpoints uniform
in the image, at least 20 px long). All-outlier rows replace every point. Default options (4 px
thresholds, ``seed`` = the scene's seed).

Per row and build: median and 95th-percentile wall time per call (fastest of ``--repeats`` calls per
scene, Python boundary included), the statuses, the median samples drawn and errors evaluated, and on the
data with inliers the median rotation error (degrees), translation error (% of the scene depth), and the
mean recall / precision of the returned inlier mask against the correspondences that were not replaced.

Each build runs in its own process (``--before DIR`` puts ``DIR`` first on ``PYTHONPATH``, e.g. a copy of
``python/`` from an older commit with its built ``_core*.so``); the machine is shared, so compare builds
from the same run only. Run from the repository root:

    .venv/bin/python bench/robust_outliers.py                           # this build
    .venv/bin/python bench/robust_outliers.py --before /tmp/old/python  # side by side
    .venv/bin/python bench/robust_outliers.py --quick                   # fewer scenes, no 20,000-point inlier rows

Results go to ``bench/out/robust_outliers.json`` and a Markdown table to standard output.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np

OUT = Path(__file__).resolve().parent / "out" / "robust_outliers.json"
IMAGE = np.array([640.0, 480.0])

#: (name, n_points, n_lines, outlier ratio, scenes, repeats); ratio 1.0: every point an outlier.
ROWS = [
    ("all-outlier", 2000, 0, 1.0, 3, 1),
    ("all-outlier", 20000, 0, 1.0, 3, 1),
    ("points", 100, 0, 0.1, 40, 3),
    ("points", 100, 0, 0.3, 40, 3),
    ("points", 100, 0, 0.5, 40, 3),
    ("points", 1000, 0, 0.1, 20, 3),
    ("points", 1000, 0, 0.3, 20, 3),
    ("points", 1000, 0, 0.5, 20, 3),
    ("points", 20000, 0, 0.1, 5, 1),
    ("points", 20000, 0, 0.3, 5, 1),
    ("points", 20000, 0, 0.5, 5, 1),
    ("points+lines", 100, 30, 0.1, 40, 3),
    ("points+lines", 100, 30, 0.3, 40, 3),
    ("points+lines", 100, 30, 0.5, 40, 3),
    ("points+lines", 1000, 300, 0.3, 20, 3),
    ("points+lines", 1000, 300, 0.5, 20, 3),
]
LARGE = [("all-outlier", 200000, 0, 1.0, 1, 1)]


def _segments(rng: np.random.Generator, n: int) -> np.ndarray:
    out = np.empty((n, 2, 2))
    for i in range(n):
        while True:
            s = rng.uniform(0.0, 1.0, (2, 2)) * IMAGE
            if np.linalg.norm(s[1] - s[0]) >= 20.0:
                out[i] = s
                break
    return out


def make_scene(pluecker: Any, n_points: int, n_lines: int, ratio: float, seed: int) -> dict[str, Any]:
    raw = pluecker.random_scene("general", n_points, n_lines, seed)
    rng = np.random.default_rng([seed, round(100 * ratio)])
    p2 = np.asarray(raw["points2d"], float) + rng.normal(0.0, 1.0, (n_points, 2))
    l2 = np.asarray(raw["lines2d"], float) + rng.normal(0.0, 1.0, (n_lines, 2, 2))
    bad_p = rng.choice(n_points, round(ratio * n_points), replace=False)
    bad_l = rng.choice(n_lines, round(ratio * n_lines), replace=False) if n_lines else np.array([], int)
    p2[bad_p] = rng.uniform(0.0, 1.0, (len(bad_p), 2)) * IMAGE
    if len(bad_l):
        l2[bad_l] = _segments(rng, len(bad_l))
    good = np.ones(n_points + n_lines, bool)
    good[bad_p] = False
    good[n_points + bad_l] = False
    R, t = np.asarray(raw["R"]), np.asarray(raw["t"])
    p3 = np.asarray(raw["points3d"], float)
    data = dict(points2d=p2, points3d=p3)
    if n_lines:
        data.update(lines2d=l2, lines3d=np.asarray(raw["lines3d"], float))
    return dict(camera=raw["camera"], R=R, t=t, depth=float(np.mean(p3 @ R[2] + t[2])), data=data, good=good)


def worker(rows: list[tuple], out: Path) -> None:
    import pluecker

    results = []
    for name, n_points, n_lines, ratio, scenes, repeats in rows:
        cell: dict[str, Any] = {"times": [], "status": {}, "samples": [], "errors_evaluated": [], "rot_deg": [],
                                "trans_pct": [], "recall": [], "precision": []}
        for seed in range(scenes):
            s = make_scene(pluecker, n_points, n_lines, ratio, seed)
            best = float("inf")
            for _ in range(repeats):
                start = time.perf_counter()
                r = pluecker.estimate_pose(s["camera"], **s["data"], options=pluecker.PoseOptions(ransac=pluecker.RansacOptions(seed=seed)))
                best = min(best, time.perf_counter() - start)
            cell["times"].append(best)
            cell["status"][r.status] = cell["status"].get(r.status, 0) + 1
            cell["samples"].append(r.details.ransac.iterations)
            cell["errors_evaluated"].append((r.details.ransac.errors_evaluated if r.details.ransac else None))
            if ratio < 1.0:
                dR = r.pose.rotation @ s["R"].T
                cell["rot_deg"].append(float(np.degrees(np.arccos(np.clip((np.trace(dR) - 1) / 2, -1, 1)))))
                cell["trans_pct"].append(float(100 * np.linalg.norm(r.pose.translation - s["t"]) / s["depth"]))
                mask = np.concatenate([r.inliers_points, r.inliers_lines])
                tp = int(np.sum(mask & s["good"]))
                cell["recall"].append(tp / max(1, int(s["good"].sum())))
                cell["precision"].append(tp / max(1, int(mask.sum())))
        t_ms = np.array(cell["times"]) * 1e3
        med = lambda v: float(np.median(v)) if v else None  # noqa: E731
        evaluated = [e for e in cell["errors_evaluated"] if e is not None]
        results.append({
            "problem": name, "points": n_points, "lines": n_lines, "outliers": ratio, "scenes": scenes,
            "median_ms": float(np.median(t_ms)), "p95_ms": float(np.percentile(t_ms, 95)),
            "status": cell["status"], "median_samples": med(cell["samples"]),
            "median_errors_evaluated": med(evaluated),
            "median_rotation_deg": med(cell["rot_deg"]), "median_translation_pct": med(cell["trans_pct"]),
            "mean_recall": float(np.mean(cell["recall"])) if cell["recall"] else None,
            "mean_precision": float(np.mean(cell["precision"])) if cell["precision"] else None,
        })
        print(f"  {name} {n_points}+{n_lines} {100 * ratio:.0f} %: {results[-1]['median_ms']:.2f} ms "
              f"{cell['status']}", file=sys.stderr, flush=True)
    out.write_text(json.dumps(results))


def run_build(label: str, path: str | None, rows: list[tuple]) -> list[dict[str, Any]]:
    env = dict(os.environ)
    if path:
        env["PYTHONPATH"] = path + os.pathsep + env.get("PYTHONPATH", "")
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "rows.json"
        print(f"{label}:", file=sys.stderr, flush=True)
        subprocess.run([sys.executable, __file__, "--worker", str(out), "--rows", json.dumps(rows)], env=env,
                       check=True)
        return json.loads(out.read_text())


def markdown(builds: dict[str, list[dict[str, Any]]]) -> str:
    fmt = lambda v, f: "–" if v is None else format(v, f)  # noqa: E731
    lines = ["| data | outliers | build | median ms | p95 ms | status | samples | errors evaluated | rot. ° | transl. % | recall | precision |",
             "|---|---:|---|---:|---:|---|---:|---:|---:|---:|---:|---:|"]
    labels = list(builds)
    for i in range(len(builds[labels[0]])):
        for label in labels:
            r = builds[label][i]
            data = f"{r['points']} points" + (f" + {r['lines']} lines" if r["lines"] else "")
            status = ", ".join(f"{k} {v}" for k, v in sorted(r["status"].items()))
            lines.append(
                f"| {data} | {100 * r['outliers']:.0f} % | {label} | {r['median_ms']:.2f} | {r['p95_ms']:.2f} | {status} | "
                f"{fmt(r['median_samples'], '.0f')} | {fmt(r['median_errors_evaluated'], '.3g')} | "
                f"{fmt(r['median_rotation_deg'], '.4f')} | {fmt(r['median_translation_pct'], '.4f')} | "
                f"{fmt(r['mean_recall'], '.4f')} | {fmt(r['mean_precision'], '.4f')} |")
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--before", help="a directory holding another build's `pluecker` package")
    parser.add_argument("--quick", action="store_true", help="fewer scenes, no 20,000-point inlier rows")
    parser.add_argument("--large", action="store_true", help="also 200,000 all-outlier points (this build only)")
    parser.add_argument("--out", type=Path, default=OUT)
    parser.add_argument("--worker", type=Path, help=argparse.SUPPRESS)
    parser.add_argument("--rows", help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    if args.worker:
        worker([tuple(r) for r in json.loads(args.rows)], args.worker)
        return 0
    rows = [r for r in ROWS if not (args.quick and r[1] >= 20000 and r[3] < 1.0)]
    if args.quick:
        rows = [(n, p, l, q, max(1, s // 4), 1) for n, p, l, q, s, _ in rows]
    builds = {}
    if args.before:
        builds["before"] = run_build("before", args.before, rows)
    builds["this build"] = run_build("this build", None, rows)
    print(markdown(builds))
    if args.large:
        large = run_build("this build, 200,000 points", None, LARGE)
        print(markdown({"this build": large}))
        builds["this build, large"] = large
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps({"date": time.strftime("%Y-%m-%dT%H:%M:%S"), "builds": builds}, indent=1) + "\n")
    print(f"wrote {args.out}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
