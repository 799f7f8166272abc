"""Certified line and quadric triangulation : certified fraction, median and p99 time, and
mean branch-and-bound nodes.

- **Real lines:** every line of every VGG sequence with lines (Model House, Corridor, Merton I-III), all
  views, from the segments with endpoint noise σ = 1 px, at the default gap 1e-3 (and the paper's 10 %).
- **Synthetic lines** at 2, 3, 5 and 20 views and 30°, 1° and 0.2° parallax (1 px endpoint noise).
- **Discs** of the reproduction's Table 3 (5 views, conics fitted to 63 noisy points).

Lines run with both lower bounds in one run: ``taylor`` (the default: interval Taylor bounds over the
two-view chart) and ``relaxation`` (the paper's SOCP relaxation, eqs. 21-27); nodes are the bound's own
(microseconds for Taylor, an SOCP each for the relaxation). Discs run with both quadric bounds:
``convexity`` (the default: the convexity test, the relaxation where it cannot decide) and
``relaxation`` (the paper's SOCP relaxation, eqs. 21-22 and 26, only).

Times are the per-track ``time_seconds`` of one batch (the batch runs on every core; a track's time is
its own solve). Run: ``.venv/bin/python bench/compare_line_triangulation.py [--quick]``; prints Markdown.
"""

from __future__ import annotations

import argparse
import math
import time

import numpy as np

import pluecker
from pluecker.datasets import load_vgg, vgg_root
from pluecker.experiments.josephson_kahl_2008.conics import disc_scene

SEQUENCES = ["model_house", "corridor", "merton_college_1", "merton_college_2", "merton_college_3"]


def summary(batch) -> tuple[str, ...]:
    """Certified count, median and p99 time (ms), mean nodes of a batch result."""
    certified = np.asarray(batch.certified)
    times = 1e3 * np.asarray(batch.time_seconds)
    nodes = np.asarray(batch.nodes)
    n = len(certified)
    return (f"{int(certified.sum())}/{n} ({100 * certified.mean():.1f} %)", f"{np.median(times):.2f}",
            f"{np.percentile(times, 99):.1f}", f"{nodes.mean():.0f}")


BOUNDS = ["taylor", "relaxation"]


def vgg_rows(gaps: list[float], quick: bool) -> list[str]:
    rows = []
    for name in SEQUENCES:
        seq = load_vgg(vgg_root() / name)
        segments, visible = seq.line_observations()
        tracks = np.flatnonzero(visible.sum(axis=1) >= 2)
        if quick:
            tracks = tracks[:10]
        for gap in gaps:
            for bound in BOUNDS:
                options = pluecker.TriangulationOptions(certify=pluecker.CertifyOptions(max_relative_gap=gap),
                                                        line_bound=bound)
                started = time.perf_counter()
                batch = pluecker.triangulate_lines(seq.cameras, segments[tracks], visible[tracks], sigma=1.0,
                                                   options=options)
                wall = time.perf_counter() - started
                rows.append(f"| {name} | {len(tracks)} | {gap:g} | {bound} | " + " | ".join(summary(batch))
                            + f" | {wall:.1f} |")
    return rows


def look_at(eye: np.ndarray, target: np.ndarray) -> np.ndarray:
    z = (target - eye) / np.linalg.norm(target - eye)
    x = np.cross([0.0, 1.0, 0.0] if abs(z[1]) < 0.9 else [1.0, 0.0, 0.0], z)
    x /= np.linalg.norm(x)
    return np.stack([x, np.cross(z, x), z])


def synthetic_lines(views: int, parallax_deg: float, n: int, seed: int):
    """``n`` segments about 1 unit long near the origin, seen from 10 units by ``views`` cameras (f = 800 px)
    spread over ``parallax_deg`` degrees, with 1 px endpoint noise: (P, segments (n, v, 2, 2))."""
    rng = np.random.default_rng(seed)
    K = np.array([[800.0, 0, 320], [0, 800.0, 240], [0, 0, 1]])
    P = []
    for a in np.radians(np.linspace(-parallax_deg / 2, parallax_deg / 2, views)):
        eye = 10.0 * np.array([math.sin(a), 0.05 * rng.uniform(-1, 1), -math.cos(a)])
        R = look_at(eye, rng.normal(0, 0.05, 3))
        P.append(K @ np.hstack([R, (-R @ eye)[:, None]]))
    P = np.array(P)
    segments = np.empty((n, views, 2, 2))
    for k in range(n):
        centre, d = rng.normal(0, 0.3, 3), rng.normal(size=3)
        ends = [centre - 0.5 * d / np.linalg.norm(d), centre + 0.5 * d / np.linalg.norm(d)]
        for j, p in enumerate(P):
            h = np.array([p @ np.append(e, 1.0) for e in ends])
            segments[k, j] = h[:, :2] / h[:, 2:] + rng.normal(size=(2, 2))
    return P, segments


def synthetic_rows(quick: bool) -> list[str]:
    rows = []
    n = 5 if quick else 30
    for views in (2, 3, 5, 20):
        for parallax in (30.0, 1.0, 0.2):
            P, segments = synthetic_lines(views, parallax, n, seed=views * 1000 + int(10 * parallax))
            for bound in BOUNDS:
                options = pluecker.TriangulationOptions(line_bound=bound)
                batch = pluecker.triangulate_lines(P, segments, sigma=1.0, options=options)
                rows.append(f"| {views} | {parallax:g}° | {n} | {bound} | " + " | ".join(summary(batch)) + " |")
    return rows


def disc_rows(quick: bool) -> list[str]:
    scenes = [disc_scene(seed) for seed in range(3 if quick else 30)]
    P = np.stack([s.cameras for s in scenes])
    conics = np.stack([s.conics for s in scenes])
    cov = np.stack([s.covariances for s in scenes])
    rows = []
    for bound in ("convexity", "relaxation"):
        for gap in (1e-3, 0.1):
            options = pluecker.TriangulationOptions(certify=pluecker.CertifyOptions(max_relative_gap=gap),
                                                    quadric_bound=bound)
            batch = pluecker.triangulate_quadrics(P, conics, covariances=cov, options=options)
            rows.append(f"| {len(scenes)} discs | {gap:g} | {bound} | " + " | ".join(summary(batch)) + " |")
    return rows


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="10 lines per sequence, fewer synthetic cases")
    args = parser.parse_args()
    print(f"pluecker {pluecker.__version__}\n")
    print("## Real lines (VGG, all views, σ = 1 px)\n")
    print("| sequence | lines | gap | bound | certified | median ms | p99 ms | mean nodes | batch wall s |")
    print("| --- | --- | --- | --- | --- | --- | --- | --- | --- |")
    for row in vgg_rows([1e-3, 0.1], args.quick):
        print(row, flush=True)
    print("\n## Synthetic lines (gap 1e-3)\n")
    print("| views | parallax | lines | bound | certified | median ms | p99 ms | mean nodes |")
    print("| --- | --- | --- | --- | --- | --- | --- | --- |")
    for row in synthetic_rows(args.quick):
        print(row, flush=True)
    print("\n## Discs (Table 3)\n")
    print("| scenes | gap | bound | certified | median ms | p99 ms | mean nodes |")
    print("| --- | --- | --- | --- | --- | --- | --- |")
    for row in disc_rows(args.quick):
        print(row, flush=True)


if __name__ == "__main__":
    main()
