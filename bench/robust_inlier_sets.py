"""Inlier sets of the robust pose through a lens, against PoseLib, on queries with a high-leverage match.

Each query is seen by the wide OPENCV lens of ``bench/compare_colmap.py`` (1024 x 768, f = 400 px, k₁ = -0.25):
``--true`` (180) matches of points spread over the image at depths 4-40, one of them moved along its ray to
depth ``--near`` (0.05: a point many times nearer than the scene, whose pixel fixes the camera centre
along a direction the far points barely constrain), 1 px Gaussian noise, then ``--wrong`` (30 %) of all the
matches are wrong: a true match's pixel replaced by a random one (the near match is never replaced).
Both libraries run as a user calls them on one image, 4 px threshold: ``pluecker.colmap.localize`` with
the image's lens (``RansacOptions(seed=query)``), ``poselib.estimate_absolute_pose`` as shipped.

Per method: the images where the returned pose keeps the near match (within 4 px of its projection, the
lens's own ``img_from_cam``), the true matches kept (median), the images where each method keeps fewer
true matches than the other, the MSAC cost ``½ Σ min(e², 16)`` of the returned pose (median), the median
rotation and centre errors, and the median time per image. Run from the repository root:

    .venv/bin/python bench/robust_inlier_sets.py [--queries 60] [--near 0.05] [--seed 0]
"""

from __future__ import annotations

import argparse
import statistics
import time

import numpy as np
import pluecker
import poselib
import pycolmap
from pluecker import colmap

THRESHOLD_PX = 4.0
PARAMS = [400.0, 400.0, 512.0, 384.0, -0.25, 0.06, 5e-4, -5e-4]  # compare_colmap.CAMERAS["OPENCV wide"]


def rotation(a: np.ndarray) -> np.ndarray:
    theta = np.linalg.norm(a)
    k = np.array([[0, -a[2], a[1]], [a[2], 0, -a[0]], [-a[1], a[0], 0]]) / theta
    return np.eye(3) + np.sin(theta) * k + (1 - np.cos(theta)) * k @ k


def query(camera, rng: np.random.Generator, n_true: int, n_wrong: int, near: float):
    """Pixels, world points, the true pose and the number of true matches (the near one first)."""
    R, t = rotation(rng.uniform(-0.5, 0.5, 3)), rng.uniform(-1, 1, 3)
    n = np.zeros((0, 2))
    while len(n) < n_true:
        candidates = rng.uniform(-1.2, 1.2, (4 * n_true, 2))  # the lens is one to one out to any radius
        u = camera.img_from_cam(np.c_[candidates, np.ones(len(candidates))])
        inside = (u[:, 0] >= 0) & (u[:, 0] < 1024) & (u[:, 1] >= 0) & (u[:, 1] < 768)
        n = np.r_[n, candidates[inside]]
    n = n[:n_true]
    depth = np.r_[near, rng.uniform(4.0, 40.0, n_true - 1)]
    x_cam = np.c_[n, np.ones(n_true)] * depth[:, None]
    xy = camera.img_from_cam(x_cam) + rng.normal(0, 1, (n_true, 2))
    wrong = 1 + rng.choice(n_true - 1, size=n_wrong, replace=False)
    xy[wrong] = rng.uniform([0, 0], [1024, 768], (n_wrong, 2))
    truly = np.ones(n_true, dtype=bool)
    truly[wrong] = False
    return xy, (x_cam - t) @ R, R, t, truly


def pixel_errors(camera, R: np.ndarray, t: np.ndarray, xy: np.ndarray, X: np.ndarray) -> np.ndarray:
    x_cam = X @ R.T + t
    u = camera.img_from_cam(x_cam)
    e = np.linalg.norm(u - xy, axis=1)
    e[~(x_cam[:, 2] > 0) | ~np.all(np.isfinite(u), axis=1)] = np.inf
    return e


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--queries", type=int, default=60)
    parser.add_argument("--true", type=int, default=180)
    parser.add_argument("--wrong", type=float, default=0.3, help="fraction of all the matches that are wrong")
    parser.add_argument("--near", type=float, default=0.05, help="depth of the one near point")
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args()
    camera = pycolmap.Camera(model="OPENCV", width=1024, height=768, params=PARAMS, camera_id=1)
    lens = pluecker.Camera(camera)
    cam = {"model": "OPENCV", "width": 1024, "height": 768, "params": PARAMS}
    rng = np.random.default_rng(args.seed)
    n_wrong = int(round(args.wrong * args.true / (1 - args.wrong)))
    stats = {m: {"near": 0, "kept": [], "msac": [], "rot": [], "centre": [], "time": [], "fewer": 0}
             for m in ("pluecker", "PoseLib")}
    for q in range(args.queries):
        xy, X, R0, t0, truly = query(camera, rng, args.true + n_wrong, n_wrong, args.near)
        kept = {}
        for method in stats:
            started = time.perf_counter()
            if method == "pluecker":
                _, result = colmap.localize(lens, xy, X, ransac=pluecker.RansacOptions(seed=q))
                R, t = result.pose.rotation, result.pose.translation
            else:
                pose, _ = poselib.estimate_absolute_pose(xy, X, cam, {"max_reproj_error": THRESHOLD_PX}, {})
                R, t = np.asarray(pose.R), np.asarray(pose.t)
            s = stats[method]
            s["time"].append(time.perf_counter() - started)
            e = pixel_errors(camera, R, t, xy, X)
            kept[method] = int(np.sum(truly & (e <= THRESHOLD_PX)))
            s["near"] += bool(e[0] <= THRESHOLD_PX)
            s["kept"].append(kept[method])
            s["msac"].append(0.5 * float(np.sum(np.minimum(e**2, THRESHOLD_PX**2))))
            cos = np.clip((np.trace(R @ R0.T) - 1) / 2, -1, 1)
            s["rot"].append(float(np.degrees(np.arccos(cos))))
            s["centre"].append(float(np.linalg.norm(-R.T @ t + R0.T @ t0)))
        stats["pluecker"]["fewer"] += kept["pluecker"] < kept["PoseLib"]
        stats["PoseLib"]["fewer"] += kept["PoseLib"] < kept["pluecker"]
    print(f"{args.queries} queries, OPENCV wide, {args.true} true matches (one at depth {args.near}), "
          f"{n_wrong} wrong; threshold {THRESHOLD_PX} px")
    print("| method | near match kept | true matches kept (median) | images with fewer true matches than the other "
          "| MSAC (median) | rotation error (deg, median) | centre error (median) | time per image (ms, median) |")
    print("| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: |")
    for method, s in stats.items():
        print(f"| {method} | {s['near']}/{args.queries} | {statistics.median(s['kept']):.0f} | {s['fewer']} "
              f"| {statistics.median(s['msac']):.1f} | {statistics.median(s['rot']):.4f} "
              f"| {statistics.median(s['centre']):.2e} | {1e3 * statistics.median(s['time']):.2f} |")


if __name__ == "__main__":
    main()
