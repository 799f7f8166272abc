"""Robust triangulation and robust pose outputs, to compare two builds bit for bit (the sampling loop's
refactor must not change them).

About 2,000 robust triangulations (``TriangulationOptions(outlier_threshold=4.0)``): points and lines
with pinhole cameras (the scenes of ``tests/test_triangulation_robust.py``: 3 to 30 views, so that both
the all-pairs and the seeded-pairs consensus run, one to three outlier views per track) and points and
lines through lenses (the scenes of ``tests/test_triangulation_lens*.py`` with outlier views added); and 1,800 robust poses on
the scenes of ``bench/robust_outliers.py`` (points, points and lines, 0 to 100 % outliers, with and without
the SPRT): pose, inlier masks and every count of the loop's report (``RansacReport``, time excepted).
Each build runs in its own process; ``--before DIR`` puts ``DIR`` first on ``sys.path`` (a copy of
``python/`` from an older commit with its built ``_core*.so``). Run from the repository root:

    .venv/bin/python bench/consensus_identity.py --out /tmp/after.npz
    .venv/bin/python bench/consensus_identity.py --before /tmp/old/python --out /tmp/before.npz
    .venv/bin/python bench/consensus_identity.py --compare /tmp/before.npz /tmp/after.npz
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np


def _arrays(pluecker, triangulation_scenes, lens_lines):
    cameras, project = triangulation_scenes.cameras, triangulation_scenes.project
    robust = pluecker.TriangulationOptions(outlier_threshold=4.0)
    local = pluecker.TriangulationOptions(outlier_threshold=4.0, method="local")
    out: dict[str, np.ndarray] = {}

    def keep(name, r, fields):
        for f in fields:
            out[f"{name}.{f}"] = np.asarray(getattr(r, f))

    # Points, pinhole: 3 to 30 views (> 21 views: seeded pairs), 1-3 outliers of 40 px.
    k = 0
    for views in (3, 4, 6, 9, 14, 21, 22, 30):
        for seed in range(3):
            rng = np.random.default_rng(1000 * views + seed)
            P = cameras(views, 40.0, rng)
            n = 40
            X = rng.normal(scale=0.5, size=(n, 3))
            x = np.stack([project(P, p) for p in X]) + rng.normal(size=(n, views, 2))
            for t in range(n):
                bad = rng.choice(views, size=min(1 + t % 3, views - 2), replace=False)
                angle = rng.uniform(0, 2 * np.pi, size=len(bad))
                x[t, bad] += 40 * np.column_stack([np.cos(angle), np.sin(angle)])
            r = pluecker.triangulate_points(P, x, options=robust)
            keep(f"points{k}", r, ("point", "inliers", "cost", "status", "certified"))
            k += n
    # Lines, pinhole (local method: the consensus is the same for every method), 3 to 24 views.
    for views in (3, 4, 5, 7, 10, 16, 24):
        for seed in range(3):
            rng = np.random.default_rng(7000 + 100 * views + seed)
            P = cameras(views, 40.0, rng)
            n = 30
            ends = rng.normal(scale=0.5, size=(n, 2, 3))
            seg = np.stack([np.stack([project(P, A), project(P, B)], axis=1) for A, B in ends])
            seg = seg + rng.normal(size=seg.shape)
            for t in range(n):
                for v in rng.choice(views, size=min(1 + t % 2, views - 2), replace=False):
                    a, b = seg[t, v]
                    d = (b - a) / np.linalg.norm(b - a)
                    seg[t, v] += 40.0 * np.array([-d[1], d[0]])
            r = pluecker.triangulate_lines(P, seg, options=local)
            keep(f"lines{k}", r, ("plucker", "inliers", "cost", "status"))
            k += n
    # A few lines with the default (certified) method.
    rng = np.random.default_rng(99)
    P = cameras(6, 40.0, rng)
    ends = rng.normal(scale=0.5, size=(20, 2, 3))
    seg = np.stack([np.stack([project(P, A), project(P, B)], axis=1) for A, B in ends]) + rng.normal(size=(20, 6, 2, 2))
    seg[np.arange(20), rng.integers(0, 6, size=20)] += 40.0
    keep(f"lines{k}", pluecker.triangulate_lines(P, seg, options=robust), ("plucker", "inliers", "cost", "status"))
    k += 20
    # Points through a lens (SIMPLE_RADIAL, the lens test's strong and mild lenses), outlier views.
    for params in ([5000.0, 600.0, 500.0, -14.0], [800.0, 600.0, 500.0, -0.2], [800.0, 600.0, 500.0, 0.05]):
        lens = pluecker.Camera("SIMPLE_RADIAL", params)
        for views in (4, 6, 9):
            for seed in range(40):
                rng = np.random.default_rng(seed)
                Xt = rng.normal(size=3) * 0.2
                poses = []
                for j in range(views):
                    angle = 2 * np.pi * j / views
                    centre = np.array([5 * np.cos(angle), 0.5, 5 * np.sin(angle)])
                    z = Xt + rng.normal(size=3) * 0.05 - centre
                    z /= np.linalg.norm(z)
                    xa = np.cross([0.0, 1.0, 0.0], z)
                    xa /= np.linalg.norm(xa)
                    R = np.stack([xa, np.cross(z, xa), z])
                    poses.append((R, -R @ centre))
                known = [pluecker.View(lens, R, t) for R, t in poses]
                pix = np.array([lens_lines.pycolmap.Camera(model="SIMPLE_RADIAL", width=1200, height=1000,
                                                           params=params).img_from_cam(np.atleast_2d(R @ Xt + t))[0]
                                for R, t in poses]) + rng.normal(size=(views, 2))
                for v in rng.choice(views, size=1 + seed % 2, replace=False):
                    pix[v] += rng.uniform(30, 80) * np.array([1.0, -0.5])
                r = pluecker.triangulate_point(known, pix, options=robust)
                keep(f"lenspoint{k}", r, ("point", "inliers", "cost", "status", "certified"))
                k += 1
    # Lines through a fisheye lens (the lens-lines test's scenes), one view moved across the segment.
    for seed in range(60):
        for views in (4, 6):
            sc = lens_lines.Scene(*lens_lines.FISHEYE, n=views, off_axis=np.radians(65), max_angle=np.radians(80),
                                  noise=1.0, anisotropic=False, seed=seed)
            seg = sc.segments.copy()
            v = seed % views
            a, b = seg[v]
            d = (b - a) / np.linalg.norm(b - a)
            seg[v] += 40.0 * np.array([-d[1], d[0]])
            r = pluecker.triangulate_line(sc.views, seg, options=local)
            keep(f"lensline{k}", r, ("plucker", "inliers", "cost", "status"))
            k += 1
    out["count"] = np.array(k)
    return out


REPORT = ("iterations", "degenerate_samples", "models_scored", "sprt_rejections", "errors_evaluated",
          "local_optimizations", "inliers", "required_inliers", "score", "stop")


def _poses(pluecker, robust_outliers):
    """Robust poses (``estimate_pose(..., ransac=RansacOptions(seed=...))``) on the scenes of
    ``bench/robust_outliers.py``: the pose, the inlier masks and every count of the loop's report."""
    out: dict[str, np.ndarray] = {}
    k = 0
    for n_points, n_lines, scenes in ((30, 0, 40), (100, 0, 40), (100, 30, 40), (300, 60, 10), (20, 10, 20)):
        for ratio in (0.0, 0.3, 0.5, 0.75, 0.9, 1.0):
            for seed in range(scenes):
                s = robust_outliers.make_scene(pluecker, n_points, n_lines, ratio, seed)
                for sprt in (True, False):
                    opts = pluecker.RansacOptions(seed=seed, sprt=sprt)
                    r = pluecker.estimate_pose(s["camera"], **s["data"], ransac=opts)
                    name = f"pose{k}"
                    out[f"{name}.R"], out[f"{name}.t"] = np.asarray(r.R), np.asarray(r.t)
                    out[f"{name}.status"] = np.asarray(r.status)
                    out[f"{name}.inliers_points"] = np.asarray(r.inliers_points)
                    if n_lines:
                        out[f"{name}.inliers_lines"] = np.asarray(r.inliers_lines)
                    for f in REPORT:
                        out[f"{name}.ransac.{f}"] = np.asarray(getattr(r.ransac, f))
                    k += 1
    out["pose_count"] = np.array(k)
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--before", type=Path, help="a python/ directory to import pluecker from")
    parser.add_argument("--out", type=Path)
    parser.add_argument("--compare", type=Path, nargs=2)
    args = parser.parse_args()
    if args.compare:
        a, b = (np.load(p) for p in args.compare)
        assert sorted(a.files) == sorted(b.files), "different outputs"
        differ = [f for f in a.files if not np.array_equal(a[f], b[f], equal_nan=a[f].dtype.kind == "f")]
        print(f"{int(a['count'])} triangulations, {int(a['pose_count'])} robust poses, {len(a.files) - 2} arrays; "
              f"bit-identical: {not differ}")
        for f in differ:
            print("differs:", f, a[f], b[f])
        sys.exit(1 if differ else 0)
    if args.before:
        sys.path.insert(0, str(args.before))
    root = Path(__file__).resolve().parent.parent
    sys.path.insert(1, str(root / "tests"))
    import pluecker
    import test_triangulation_lens_lines as lens_lines
    import triangulation_scenes

    sys.path.insert(1, str(root / "bench"))
    import robust_outliers

    print("pluecker from", pluecker.__file__)
    out = _arrays(pluecker, triangulation_scenes, lens_lines)
    out.update(_poses(pluecker, robust_outliers))
    np.savez(args.out, **out)
    print(f"{int(out['count'])} triangulations and {int(out['pose_count'])} robust poses written to {args.out}")


if __name__ == "__main__":
    main()
