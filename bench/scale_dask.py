"""Triangulation and localisation at scale on Dask: throughput, speed-up, memory, overhead.

- **Tracks:** synthetic tracks of 2-20 observations each (20 cameras 10 units around a unit cloud,
  f = 800 px, 1 px noise), generated *on the workers*, chunk by chunk (`CHUNK` tracks per Parquet file of
  whole tracks), so that the client never holds them; then `pluecker.distributed.triangulate(...,
  partitioned=True)` on a `LocalCluster` of 1 worker and of 2 workers, each worker one task slot and one
  pluecker thread (one core each). Reported: tracks per second, per core, the speed-up, the certified
  count, the peak resident memory of each worker process (`ru_maxrss`) and of the client process.
- **Overhead:** the same job on `--overhead-tracks` tracks with 2 workers against the single-machine
  batch (`triangulate_table` on each chunk, in this process, 2 pluecker threads), both reading the same
  files and writing the same tables.
- **Localisation:** `--queries` queries (30 point matches with 20 % outliers and 4 line matches each),
  generated on the workers, `pluecker.distributed.localize` with 1 and 2 workers.

Run: `.venv/bin/python bench/scale_dask.py [--tracks 10000000] [--overhead-tracks 1000000] [--queries
100000] [--quick]`; prints Markdown. Data go to `--scratch` (default a temporary folder, removed).
"""

from __future__ import annotations

import argparse
import resource
import shutil
import tempfile
import time
from pathlib import Path

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq
from distributed import Client, LocalCluster

import pluecker
from pluecker import distributed as dist

CHUNK = 100_000
VIEWS = 20
QUERY_CHUNK = 5_000


def rig() -> dist.Cameras:
    """20 cameras on a 90° arc and 10 units from the origin, f = 800 px, looking at it."""
    K = np.array([[800.0, 0.0, 320.0], [0.0, 800.0, 240.0], [0.0, 0.0, 1.0]])
    P = []
    for i in range(VIEWS):
        a = np.radians(90.0) * (i / (VIEWS - 1) - 0.5)
        R = np.array([[np.cos(a), 0, np.sin(a)], [0, 1, 0], [-np.sin(a), 0, np.cos(a)]])
        c = np.array([10 * np.sin(a), 0.5 * np.sin(7 * a), -10 * np.cos(a)])
        P.append(K @ np.hstack([R, (-R @ c)[:, None]]))
    return dist.Cameras(np.arange(VIEWS) * 10 + 3, np.array(P))


def generate_tracks(chunk: int, n: int, folder: str) -> int:
    """Worker task: chunk ``chunk`` of ``n`` tracks (ids chunk * CHUNK + i), written as one Parquet file
    of whole tracks. Returns its observations."""
    rng = np.random.default_rng([chunk, 14])
    cameras = rig()
    X = rng.uniform(-1, 1, (n, 3))
    counts = rng.integers(2, 21, n)
    track = np.repeat(np.arange(n), counts)
    # Distinct views per track: the first counts[t] of a random permutation of the 20.
    ranks = np.argsort(rng.random((n, VIEWS)), axis=1)
    starts = np.r_[0, np.cumsum(counts)[:-1]]
    views = ranks[track, np.arange(len(track)) - starts[track]]
    h = np.einsum("kij,kj->ki", cameras.projections[views], np.c_[X[track], np.ones(len(track))])
    xy = h[:, :2] / h[:, 2:] + rng.normal(0, 1, (len(track), 2))
    table = pa.table({"track": track.astype(np.int64) + chunk * CHUNK, "image": cameras.ids[views],
                      "x": xy[:, 0], "y": xy[:, 1]})
    Path(folder).mkdir(parents=True, exist_ok=True)
    pq.write_table(table, Path(folder) / f"chunk-{chunk:06d}.parquet")
    return len(track)


def generate_queries(chunk: int, n: int, folder: str) -> int:
    """Worker task: ``n`` localisation queries as three Parquet files of chunk ``chunk``."""
    rng = np.random.default_rng([chunk, 41])
    q = np.arange(n, dtype=np.int64) + chunk * QUERY_CHUNK
    a = rng.uniform(-0.5, 0.5, (n, 3))
    theta = np.linalg.norm(a, axis=1)[:, None, None]
    k = np.zeros((n, 3, 3))
    k[:, 0, 1], k[:, 0, 2], k[:, 1, 2] = -a[:, 2], a[:, 1], -a[:, 0]
    k = (k - np.swapaxes(k, 1, 2)) / theta
    R = np.eye(3) + np.sin(theta) * k + (1 - np.cos(theta)) * k @ k
    t = np.c_[rng.uniform(-0.5, 0.5, (n, 2)), rng.uniform(5, 8, n)]
    cam = np.c_[rng.uniform(-1.5, 1.5, (n * 30, 2)), rng.uniform(-1, 1, n * 30)].reshape(n, 30, 3)
    cam[..., 2] += t[:, None, 2]
    X = np.einsum("nji,nkj->nki", R, cam - t[:, None, :])  # R^T (x_cam - t)
    uv = 800 * cam[..., :2] / cam[..., 2:] + [320, 240] + rng.normal(0, 1, (n, 30, 2))
    outliers = rng.random((n, 30)) < 0.2
    uv[outliers] = rng.uniform(0, 640, (int(outliers.sum()), 2))
    queries = pa.table({"query": q, "fx": np.full(n, 800.0), "fy": np.full(n, 800.0), "cx": np.full(n, 320.0),
                        "cy": np.full(n, 240.0)})
    qq = np.repeat(q, 30)
    points = pa.table({"query": qq, "x": uv[..., 0].ravel(), "y": uv[..., 1].ravel(), "X": X[..., 0].ravel(),
                       "Y": X[..., 1].ravel(), "Z": X[..., 2].ravel()})
    ends = X[:, :8].reshape(n, 4, 2, 3)
    seg = (800 * cam[:, :8, :2] / cam[:, :8, 2:] + [320, 240]).reshape(n, 4, 4)
    ql = np.repeat(q, 4)
    lines = pa.table({"query": ql, **{c: seg[..., i].ravel() for i, c in enumerate(("x1", "y1", "x2", "y2"))},
                      **{c: ends.reshape(n, 4, 6)[..., i].ravel()
                         for i, c in enumerate(("X1", "Y1", "Z1", "X2", "Y2", "Z2"))}})
    for name, table in (("queries", queries), ("points", points), ("lines", lines)):
        (Path(folder) / name).mkdir(parents=True, exist_ok=True)
        pq.write_table(table, Path(folder) / name / f"chunk-{chunk:06d}.parquet")
    return n


def peak_rss_mb() -> float:
    """This process's peak resident memory (VmHWM), MB."""
    for line in Path("/proc/self/status").read_text().splitlines():
        if line.startswith("VmHWM:"):
            return int(line.split()[1]) / 1024.0
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0


class RssSampler:
    """The largest resident memory of this process while the block runs (sampled every 20 ms), MB."""

    def __enter__(self) -> "RssSampler":
        import threading

        import psutil

        self.peak, self._stop = 0.0, threading.Event()
        process = psutil.Process()
        self.before = process.memory_info().rss / 2**20

        def sample() -> None:
            while not self._stop.is_set():
                self.peak = max(self.peak, process.memory_info().rss / 2**20)
                self._stop.wait(0.02)

        self._thread = threading.Thread(target=sample, daemon=True)
        self._thread.start()
        return self

    def __exit__(self, *exc) -> None:
        self._stop.set()
        self._thread.join()


def cluster(workers: int) -> tuple[LocalCluster, Client]:
    c = LocalCluster(n_workers=workers, threads_per_worker=1, processes=True, dashboard_address=":0",
                     silence_logs=40, memory_limit="8GiB")
    return c, Client(c)


def generate(client: Client, task, total: int, per_chunk: int, folder: Path) -> float:
    started = time.perf_counter()
    sizes = [min(per_chunk, total - k * per_chunk) for k in range(-(-total // per_chunk))]
    futures = client.map(task, range(len(sizes)), sizes, [str(folder)] * len(sizes), pure=False)
    client.gather(futures)
    del futures
    return time.perf_counter() - started


def tracks_row(workers: int, n: int, data: Path, out: Path) -> dict:
    c, client = cluster(workers)
    with c, client:
        shutil.rmtree(out, ignore_errors=True)
        with RssSampler() as sampler:
            s = dist.triangulate(data, rig(), out, client=client, partitioned=True, threads_per_worker=1)
        worker_rss = client.run(peak_rss_mb)
    return {"workers": workers, "tracks": s.tracks, "certified": s.certified, "seconds": s.seconds,
            "per_second": s.tracks / s.seconds, "per_core": s.tracks / s.seconds / workers,
            "worker_peak_mb": max(worker_rss.values()), "client_peak_mb": sampler.peak,
            "client_before_mb": sampler.before, "statuses": s.statuses}


def single_machine(data: Path, out: Path) -> float:
    """The batch without Dask: each chunk file read, solved by triangulate_table (2 threads) and its
    tables written, in this process."""
    pluecker.set_num_threads(2)
    started = time.perf_counter()
    (out / "points").mkdir(parents=True, exist_ok=True)
    (out / "observations").mkdir(parents=True, exist_ok=True)
    for k, f in enumerate(sorted(data.glob("*.parquet"))):
        points, observations = dist.triangulate_table(pq.read_table(f), rig())
        pq.write_table(points, out / "points" / f"part-{k:05d}.parquet")
        pq.write_table(observations, out / "observations" / f"part-{k:05d}.parquet")
    pluecker.set_num_threads(None)
    return time.perf_counter() - started


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--tracks", type=int, default=10_000_000)
    parser.add_argument("--overhead-tracks", type=int, default=1_000_000)
    parser.add_argument("--queries", type=int, default=100_000)
    parser.add_argument("--quick", action="store_true", help="10^5 tracks, 10^5 for the overhead, 2000 queries")
    parser.add_argument("--scratch", type=Path)
    args = parser.parse_args()
    if args.quick:
        args.tracks, args.overhead_tracks, args.queries = 100_000, 100_000, 2_000
    scratch = args.scratch or Path(tempfile.mkdtemp(prefix="pluecker-scale-"))
    print(f"pluecker {pluecker.__version__}; scratch {scratch}\n")
    client_rss: list[tuple[str, float, float]] = []

    # Overhead first (small), then the big job.
    c, client = cluster(2)
    with c, client:
        generate(client, generate_tracks, args.overhead_tracks, CHUNK, scratch / "small")
    single = single_machine(scratch / "small", scratch / "single")
    dask_small = tracks_row(2, args.overhead_tracks, scratch / "small", scratch / "out-small")
    same = dist.read_points(scratch / "out-small").equals(dist.read_points(scratch / "single"))
    client_rss.append((f"Dask job on {args.overhead_tracks:,} tracks (2 workers)", dask_small["client_before_mb"],
                       dask_small["client_peak_mb"]))
    print("## Overhead of Dask over the single-machine batch\n")
    print("| tracks | single machine s (2 threads) | Dask s (2 workers × 1 thread) | overhead | same tables |")
    print("| --- | --- | --- | --- | --- |")
    print(f"| {args.overhead_tracks:,} | {single:.1f} | {dask_small['seconds']:.1f} | "
          f"{100 * (dask_small['seconds'] / single - 1):+.1f} % | {same} |\n", flush=True)

    c, client = cluster(2)
    with c, client:
        gen = generate(client, generate_tracks, args.tracks, CHUNK, scratch / "big")
    rows = [tracks_row(w, args.tracks, scratch / "big", scratch / f"out-{w}") for w in (1, 2)]
    client_rss += [(f"Dask job on {args.tracks:,} tracks ({r['workers']} workers)", r["client_before_mb"],
                    r["client_peak_mb"]) for r in rows]
    print(f"## {args.tracks:,} tracks of 2-20 observations (generated on the workers in {gen:.0f} s)\n")
    print("| workers | tracks | certified | s | tracks/s | tracks/s per core | speed-up | worker peak MB |")
    print("| --- | --- | --- | --- | --- | --- | --- | --- |")
    for r in rows:
        print(f"| {r['workers']} | {r['tracks']:,} | {r['certified']:,} | {r['seconds']:.0f} | {r['per_second']:,.0f} | "
              f"{r['per_core']:,.0f} | {rows[0]['seconds'] / r['seconds']:.2f} | {r['worker_peak_mb']:.0f} |")
    print(f"\nstatuses (2 workers): {rows[1]['statuses']}\n", flush=True)

    c, client = cluster(2)
    with c, client:
        generate(client, generate_queries, args.queries, QUERY_CHUNK, scratch / "queries")
    loc = []
    for w in (1, 2):
        c, client = cluster(w)
        with c, client:
            with RssSampler() as sampler:
                s = dist.localize(scratch / "queries" / "queries", scratch / "queries" / "points",
                                  scratch / f"loc-{w}", line_matches=scratch / "queries" / "lines", client=client,
                                  threads_per_worker=1)
        loc.append((w, s))
        client_rss.append((f"Dask localisation of {args.queries:,} queries ({w} workers)", sampler.before,
                           sampler.peak))
    print(f"## Localisation of {args.queries:,} queries (30 points with 20 % outliers, 4 lines each)\n")
    print("| workers | queries | success | s | queries/s | speed-up |")
    print("| --- | --- | --- | --- | --- | --- |")
    for w, s in loc:
        print(f"| {w} | {s.tracks:,} | {s.statuses.get('success', 0):,} | {s.seconds:.1f} | {s.tracks / s.seconds:,.0f} | "
              f"{loc[0][1].seconds / s.seconds:.2f} |")
    print("\n## Client resident memory during the Dask jobs (largest sample, MB)\n")
    print("| job | before MB | largest during MB | increase MB |\n| --- | --- | --- | --- |")
    for when, before, peak in client_rss:
        print(f"| {when} | {before:.0f} | {peak:.0f} | {peak - before:+.0f} |")
    if args.scratch is None:
        shutil.rmtree(scratch, ignore_errors=True)


if __name__ == "__main__":
    main()
