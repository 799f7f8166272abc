"""Pose through a lens: the exact cost in the distorted pixels against the first-order cost it replaced,
and against pycolmap, on strong distortion.

Lenses (as in tests/test_pose_lens_exact.py): OPENCV (k1 = -0.28, normalised radius to 0.55),
OPENCV_FISHEYE out to 80 degrees off axis, SIMPLE_RADIAL with f = 5000 px and k = -14 (points inside its
fold, normalised radius to 0.12). Per scene: N points at depths 4-8 in the camera frame, a random pose,
1 px Gaussian noise in the distorted pixels, no outliers.

Methods, all timed per call from Python (fastest of --repeats calls):
- ``exact``: ``pluecker.estimate_pose(lens, u, X)`` (this version: the refinement minimises the exact
  reprojection error through the lens);
- ``first-order``: the path that ``estimate_pose`` ran before it, reproduced: ``lens.undistort(u)`` then the
  pinhole ``estimate_pose`` on the undistorted pixels weighted by ``J^-1 J^-T`` (the same cost it minimised:
  the distorted-pixel error linearised at each observation);
- ``pycolmap``: ``pycolmap.estimate_and_refine_absolute_pose`` with its defaults (LO-RANSAC, then a refinement
  with a Cauchy loss of scale 1 px: it minimises a robust cost, not the squared error, hence its gap);
- ``pycolmap-lsq``: the same with plain least squares in the refinement (Cauchy scale 1e6 px) and its
  default tolerances;
- the reference minimum: pycolmap's ``refine_absolute_pose`` from the exact answer and from the first-order
  one with plain least squares (Cauchy scale 1e6 px) and tight tolerances (gradient 1e-16, 1000
  iterations); the lower of the two costs.

The cost of every answer is recomputed with pycolmap's projection (``Camera.img_from_cam``): half the sum
of squared pixel errors. Reported: median time, and the gap (cost - reference) / reference, median and
maximum over the scenes. Run from the repository root:

    .venv/bin/python bench/pose_exact_lens.py            # 200 scenes per lens, 3 repeats
    .venv/bin/python bench/pose_exact_lens.py --quick    # 20 scenes, 1 repeat
"""

from __future__ import annotations

import argparse
import time

import numpy as np
import pycolmap

import pluecker
from pluecker.scenes import lens_scene

LENSES = {
    "OPENCV": ("OPENCV", [600.0, 600.0, 320.0, 240.0, -0.28, 0.07, 5e-4, -3e-4], 0.55),
    "OPENCV_FISHEYE 80deg": ("OPENCV_FISHEYE", [600.0, 600.0, 320.0, 240.0, 0.05, -0.02, 0.01, -0.002], np.tan(np.radians(80))),
    "SIMPLE_RADIAL k=-14": ("SIMPLE_RADIAL", [5000.0, 2000.0, 1500.0, -14.0], 0.12),
}


def cost(camera, R, t, X, u):
    r = camera.img_from_cam(X @ R.T + t, check_cheirality=False) - u
    return 0.5 * float(np.sum(r * r))


def timed(f, repeats):
    best, out = np.inf, None
    for _ in range(repeats):
        t0 = time.perf_counter()
        out = f()
        best = min(best, time.perf_counter() - t0)
    return out, best


def tight(camera, R0, t0, u, X):
    options = pycolmap.AbsolutePoseRefinementOptions()
    options.loss_function_scale = 1e6
    options.gradient_tolerance = 1e-16
    options.max_num_iterations = 1000
    start = pycolmap.Rigid3d(pycolmap.Rotation3d(R0), t0)
    pose = pycolmap.refine_absolute_pose(start, u, X, np.ones(len(u), bool), camera, options)["cam_from_world"]
    return pose.rotation.matrix(), pose.translation


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--quick", action="store_true")
    parser.add_argument("--scenes", type=int, default=200)
    parser.add_argument("--points", type=int, default=100)
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args()
    scenes, repeats = (20, 1) if args.quick else (args.scenes, args.repeats)
    print(f"pluecker {pluecker.__version__}, pycolmap {pycolmap.__version__}; {scenes} scenes of {args.points} points, 1 px noise, best of {repeats}")
    print()
    print("| lens | method | median time (ms) | median gap | max gap |")
    print("|---|---|---:|---:|---:|")
    for name, (model, params, r_max) in LENSES.items():
        lens = pluecker.Camera(model, params)
        pinhole = lens.pinhole_part
        camera = pycolmap.Camera(model=model, width=4000, height=3000, params=params)
        rng = np.random.default_rng(2026)
        times = {k: [] for k in ("exact", "first-order", "pycolmap", "pycolmap-lsq")}
        lsq = pycolmap.AbsolutePoseRefinementOptions()
        lsq.loss_function_scale = 1e6
        gaps = {k: [] for k in times}
        for _ in range(scenes):
            _, _, x_cam, X = lens_scene(rng, r_max, args.points, fisheye=model == "OPENCV_FISHEYE")
            u = camera.img_from_cam(x_cam) + rng.normal(size=(args.points, 2))
            exact, t_exact = timed(lambda: pluecker.estimate_pose(lens, u, X), repeats)

            def first_order():
                ubar, cov = lens.undistort(u)
                return pluecker.estimate_pose(pinhole, ubar, X, point_covariances=cov)

            old, t_old = timed(first_order, repeats)
            colmap, t_colmap = timed(lambda: pycolmap.estimate_and_refine_absolute_pose(u, X, camera), repeats)
            colmap_lsq, t_lsq = timed(
                lambda: pycolmap.estimate_and_refine_absolute_pose(u, X, camera, refinement_options=lsq), repeats
            )
            assert exact.status == "success" and old.status == "success" and colmap is not None and colmap_lsq is not None
            pc, pl = colmap["cam_from_world"], colmap_lsq["cam_from_world"]
            answers = {
                "exact": (exact.pose.rotation, exact.pose.translation),
                "first-order": tuple(old.pose),
                "pycolmap": (pc.rotation.matrix(), pc.translation),
                "pycolmap-lsq": (pl.rotation.matrix(), pl.translation),
            }
            costs = {k: cost(camera, *v, X, u) for k, v in answers.items()}
            reference = min(cost(camera, *tight(camera, *answers[k], u, X), X, u) for k in ("exact", "first-order"))
            for k, tk in zip(times, (t_exact, t_old, t_colmap, t_lsq)):
                times[k].append(tk)
                gaps[k].append((costs[k] - reference) / reference)
        for k in times:
            g = np.array(gaps[k])
            print(f"| {name} | {k} | {1e3 * np.median(times[k]):.3f} | {np.median(g):.2e} | {g.max():.2e} |")


if __name__ == "__main__":
    main()
