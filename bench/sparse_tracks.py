"""Sparse point tracks at scale: ``triangulate_points(track=, image=)`` on 1000 images and
200,000 tracks of 2-20 observations each (one observation per row, as COLMAP lists them), against the
dense ``(n, v, 2)`` form it replaces, which would need ``n · v · 2`` floats (3.2 GB here).

Run: ``.venv/bin/python bench/sparse_tracks.py [--tracks N] [--images V] [--method M]``. Prints the
number of observations, the wall time of the call, tracks per second, and the peak resident memory of
the process (``ru_maxrss``) before and after the call; writes nothing.
"""

from __future__ import annotations

import argparse
import resource
import time

import numpy as np

import pluecker


def peak_mb() -> float:
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0


def scene(images: int, tracks: int, seed: int):
    """Cameras on a sphere of radius 10 looking at the origin (f = 800 px), points in a 4 m cube, each
    seen by 2-20 random cameras with 1 px noise: (P, track, image, x)."""
    rng = np.random.default_rng(seed)
    K = np.array([[800.0, 0, 320], [0, 800.0, 240], [0, 0, 1]])
    P = np.empty((images, 3, 4))
    centres = rng.normal(size=(images, 3))
    centres *= 10.0 / np.linalg.norm(centres, axis=1, keepdims=True)
    for i, c in enumerate(centres):
        z = -c / np.linalg.norm(c)
        x = np.cross([0.0, 0.0, 1.0] if abs(z[2]) < 0.9 else [1.0, 0.0, 0.0], z)
        x /= np.linalg.norm(x)
        R = np.stack([x, np.cross(z, x), z])
        P[i] = K @ np.hstack([R, (-R @ c)[:, None]])
    counts = rng.integers(2, 21, tracks)
    track = np.repeat(np.arange(tracks), counts)
    image = np.concatenate([rng.choice(images, k, replace=False) for k in counts])
    X = rng.uniform(-2.0, 2.0, (tracks, 3))
    h = np.einsum("mij,mj->mi", P[image], np.c_[X[track], np.ones(len(track))])
    x = h[:, :2] / h[:, 2:] + rng.normal(size=(len(track), 2))
    return P, track, image, x


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--tracks", type=int, default=200_000)
    parser.add_argument("--images", type=int, default=1000)
    parser.add_argument("--method", default="optimal", choices=pluecker.TRIANGULATION_METHODS)
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args()
    P, track, image, x = scene(args.images, args.tracks, args.seed)
    before = peak_mb()
    started = time.perf_counter()
    result = pluecker.triangulate_points(P, x, track=track, image=image, options=pluecker.TriangulationOptions(method=args.method))
    seconds = time.perf_counter() - started
    print(f"{args.tracks} tracks, {len(track)} observations, {args.images} images, method {args.method}")
    print(f"time {seconds:.2f} s ({args.tracks / seconds:,.0f} tracks/s); "
          f"certified {int(result.certified.sum())}, success {int((result.status == 'success').sum())}")
    print(f"peak RSS {before:.0f} MB before the call (inputs made), {peak_mb():.0f} MB after; "
          f"the dense form would hold {args.tracks * args.images * 2 * 8 / 1e9:.1f} GB of pixels alone")


if __name__ == "__main__":
    main()
