"""``pluecker.distributed`` (issue 14) on a ``LocalCluster`` of 2 worker processes, on generated tracks:
the same tables as the single-machine kernel bit for bit whatever the buckets and workers, bad rows as
statuses, Parquet round trips, and a worker killed mid-job losing nothing."""

from __future__ import annotations

import os
import signal

import numpy as np
import pytest

import pluecker

pa = pytest.importorskip("pyarrow")
pq = pytest.importorskip("pyarrow.parquet")
distributed = pytest.importorskip("distributed")

from pluecker import distributed as dist  # noqa: E402

VIEWS = 8
# An address where no scheduler listens. The connection is refused at once, but Dask retries until its
# connect timeout (30 s by default): the tests that expect the refusal shorten that wait.
UNREACHABLE = "tcp://127.0.0.1:1"


def no_scheduler_at(command: list[str]) -> int:
    """The exit status of the command line ``command`` run against ``UNREACHABLE``, waiting 1 s for it."""
    import dask

    from pluecker.cli import main

    with dask.config.set({"distributed.comm.timeouts.connect": "1s"}):
        return main([*command, "--scheduler", UNREACHABLE])


def generated(n_tracks: int, seed: int, covariances: bool = False):
    """Cameras (ids 3, 13, ..., 73) on a 36° arc 10 units from the origin, f = 800 px; ``n_tracks``
    points near the origin seen by 2-8 cameras each with 1 px noise; track ids 1, 8, 15, ...; rows in
    random order."""
    rng = np.random.default_rng(seed)
    ids = np.arange(VIEWS) * 10 + 3
    K = np.array([[800.0, 0.0, 320.0], [0.0, 800.0, 240.0], [0.0, 0.0, 1.0]])
    P = []
    for i in range(VIEWS):
        a = 0.2 * 2 * np.pi * i / VIEWS
        R = np.array([[np.cos(a), 0, np.sin(a)], [0, 1, 0], [-np.sin(a), 0, np.cos(a)]])
        c = np.array([10 * np.sin(a), 0.0, -10 * np.cos(a)])
        P.append(K @ np.hstack([R, (-R @ c)[:, None]]))
    P = np.array(P)
    X = rng.normal(0, 1, (n_tracks, 3))
    counts = rng.integers(2, VIEWS + 1, n_tracks)
    track = np.repeat(np.arange(n_tracks), counts)
    views = np.concatenate([rng.choice(VIEWS, k, replace=False) for k in counts])
    h = np.einsum("kij,kj->ki", P[views], np.c_[X[track], np.ones(len(track))])
    xy = h[:, :2] / h[:, 2:] + rng.normal(0, 1, (len(track), 2))
    order = rng.permutation(len(track))
    columns = {"track": track[order] * 7 + 1, "image": ids[views][order], "x": xy[order, 0], "y": xy[order, 1]}
    if covariances:
        s = rng.uniform(0.5, 2.0, (len(track), 2))
        columns.update(cov_xx=s[:, 0] ** 2, cov_xy=0.1 * s[:, 0] * s[:, 1], cov_yy=s[:, 1] ** 2)
    return dist.Cameras(ids, P), pa.table(columns)


@pytest.fixture(scope="module")
def client():
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=":0",
                                  silence_logs=40) as cluster, distributed.Client(cluster) as c:
        yield c


def assert_same_table(a, b):
    """Equal column names and values, bit for bit, NaN equal to NaN (``Table.equals`` says NaN ≠ NaN)."""
    assert a.column_names == b.column_names and a.num_rows == b.num_rows
    for name in a.column_names:
        x, y = a.column(name).combine_chunks(), b.column(name).combine_chunks()
        if pa.types.is_fixed_size_list(x.type):
            x, y = x.flatten(), y.flatten()
        np.testing.assert_array_equal(x.to_numpy(zero_copy_only=False), y.to_numpy(zero_copy_only=False), err_msg=name)


def write(table, folder, row_group_size: int):
    folder.mkdir(parents=True, exist_ok=True)
    pq.write_table(table, folder / "observations.parquet", row_group_size=row_group_size)
    return folder / "observations.parquet"


def test_the_kernel_is_the_batch_and_independent_of_row_order():
    cameras, table = generated(300, 1)
    points, observations = dist.triangulate_table(table, cameras)
    assert points.num_rows == 300 and observations.num_rows == table.num_rows
    assert np.all(np.diff(points.column("track").to_numpy()) > 0)
    # The same tracks through the batch directly (rows grouped by track).
    track, image = table.column("track").to_numpy(), table.column("image").to_numpy()
    x = np.c_[table.column("x").to_numpy(), table.column("y").to_numpy()]
    order = np.lexsort((x[:, 1], x[:, 0], image, track))
    ids, index = np.unique(track[order], return_inverse=True)
    batch = pluecker.triangulate_points(cameras.projections, x[order], track=index, image=(image[order] - 3) // 10)
    np.testing.assert_array_equal(np.c_[points.column("X"), points.column("Y"), points.column("Z")], batch.point)
    np.testing.assert_array_equal(points.column("cost").to_numpy(), batch.cost)
    assert points.column("certified").to_numpy().all()
    # Shuffled rows give the same tables, bit for bit.
    shuffled = table.take(pa.array(np.random.default_rng(2).permutation(table.num_rows)))
    again = dist.triangulate_table(shuffled, cameras)
    assert again[0].equals(points) and again[1].equals(observations)


def test_covariance_columns_weight_the_pixels():
    cameras, table = generated(50, 3, covariances=True)
    points, _ = dist.triangulate_table(table, cameras)
    plain, _ = dist.triangulate_table(table.drop(["cov_xx", "cov_xy", "cov_yy"]), cameras)
    assert not np.allclose(points.column("cost").to_numpy(), plain.column("cost").to_numpy())
    # The covariance column: 9 values per track, a symmetric positive definite 3x3.
    cov = np.asarray(points.column("covariance").to_pylist()).reshape(-1, 3, 3)
    np.testing.assert_allclose(cov, np.swapaxes(cov, 1, 2))
    assert np.all(np.linalg.eigvalsh(cov) > 0)


@pytest.mark.parametrize("buckets", [1, 3, 8])
def test_dask_equals_the_single_machine_kernel_whatever_the_buckets(client, tmp_path, buckets):
    cameras, table = generated(1500, 4, covariances=buckets == 3)
    source = write(table, tmp_path / "in", row_group_size=1000)
    reference = dist.triangulate_table(table, cameras)
    summary = dist.triangulate(source, cameras, tmp_path / "out", client=client, buckets=buckets)
    assert summary.tracks == 1500 and summary.workers == 2 and summary.buckets == buckets
    assert dist.read_points(tmp_path / "out").equals(reference[0])
    assert dist.read_observations(tmp_path / "out").equals(reference[1])
    assert not (tmp_path / "out" / "_buckets").exists()
    # Without a client the same job runs here, with the same tables.
    dist.triangulate(source, cameras, tmp_path / "local", buckets=buckets + 1)
    assert dist.read_points(tmp_path / "local").equals(reference[0])


def test_each_worker_gets_its_share_of_the_cores(client):
    shares = dist.share_threads(client)
    cores = os.cpu_count() or 1
    assert set(shares.values()) == {max(1, cores // 2)}
    assert set(client.run(pluecker.get_num_threads).values()) == {max(1, cores // 2)}


def test_bad_rows_get_a_status_and_never_lose_other_tracks(client, tmp_path):
    cameras, table = generated(400, 5)
    x = table.column("x").to_numpy().copy()
    image = table.column("image").to_numpy().copy()
    track = table.column("track").to_numpy()
    nan_track, unknown_track = track[0], track[1]
    x[np.flatnonzero(track == nan_track)[0]] = np.nan
    image[np.flatnonzero(track == unknown_track)[0]] = 999
    bad = table.set_column(2, "x", pa.array(x)).set_column(1, "image", pa.array(image))
    summary = dist.triangulate(write(bad, tmp_path / "in", 500), cameras, tmp_path / "out", client=client, buckets=4)
    points = dist.read_points(tmp_path / "out")
    assert summary.tracks == 400 and points.num_rows == 400
    rows = {t: i for i, t in enumerate(points.column("track").to_pylist())}
    status, message = points.column("status").to_pylist(), points.column("message").to_pylist()
    assert status[rows[nan_track]] == "non_finite" and "non-finite" in message[rows[nan_track]]
    assert status[rows[unknown_track]] == "invalid_input"
    assert "image id 999 is not among the cameras" in message[rows[unknown_track]]
    # Every other track is as it would be without the bad ones.
    clean = table.filter(pa.compute.invert(pa.compute.is_in(table.column("track"), pa.array([nan_track, unknown_track]))))
    reference = dist.triangulate_table(clean, cameras)[0]
    others = points.filter(pa.compute.invert(pa.compute.is_in(points.column("track"), pa.array([nan_track, unknown_track]))))
    assert others.equals(reference)


def test_parquet_round_trip_of_the_tables(tmp_path):
    cameras, table = generated(200, 6)
    points, observations = dist.triangulate_table(table, cameras)
    pq.write_table(points, tmp_path / "p.parquet")
    pq.write_table(observations, tmp_path / "o.parquet")
    assert pq.read_table(tmp_path / "p.parquet").equals(points)
    assert pq.read_table(tmp_path / "o.parquet").equals(observations)
    assert points.schema.field("covariance").type == pa.list_(pa.float64(), 9)


def test_a_worker_killed_mid_job_loses_nothing(tmp_path):
    # Its own cluster: the nanny restarts the killed worker; Dask reruns its tasks. The worker that starts
    # the job's first solve task kills itself as that task begins (a plugin on every worker; the first
    # to create the marker file is the one), so the kill always falls inside the job.
    from distributed.diagnostics.plugin import WorkerPlugin

    marker = tmp_path / "killed"

    class KillAtTheFirstSolve(WorkerPlugin):
        def transition(self, key, start, finish, **kwargs):
            if finish != "executing" or not str(key).startswith("_after"):
                return
            try:
                fd = os.open(marker, os.O_CREAT | os.O_EXCL | os.O_WRONLY)
            except FileExistsError:
                return  # a worker was killed already (also the restarted one gets this plugin)
            os.write(fd, str(os.getpid()).encode())
            os.close(fd)
            os.kill(os.getpid(), signal.SIGKILL)

    cameras, table = generated(6000, 7)
    source = write(table, tmp_path / "in", row_group_size=2000)
    reference = dist.triangulate_table(table, cameras)
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=":0",
                                  silence_logs=50) as cluster, distributed.Client(cluster) as c:
        c.register_plugin(KillAtTheFirstSolve())
        summary = dist.triangulate(source, cameras, tmp_path / "out", client=c, buckets=40)
        victim = int(marker.read_text())
        assert victim not in c.run(os.getpid).values()
    assert summary.tracks == 6000
    points = dist.read_points(tmp_path / "out")
    assert points.num_rows == 6000 and len(np.unique(points.column("track").to_numpy())) == 6000
    assert points.equals(reference[0])
    assert dist.read_observations(tmp_path / "out").equals(reference[1])


def generated_queries(n_queries: int, seed: int):
    """``n_queries`` pinhole cameras (f = 800 px) looking at a cloud of 3-D points from 5-8 units, each
    with 30 point matches (1 px noise, 20 % outliers) and 4 line matches; the true poses."""
    rng = np.random.default_rng(seed)
    queries, points, lines, truth = [], [], [], {}
    for q in rng.permutation(n_queries) * 3 + 2:
        a = rng.uniform(-0.5, 0.5, 3)
        theta = np.linalg.norm(a)
        k = np.array([[0, -a[2], a[1]], [a[2], 0, -a[0]], [-a[1], a[0], 0]]) / theta
        R = np.eye(3) + np.sin(theta) * k + (1 - np.cos(theta)) * k @ k
        t = np.array([*rng.uniform(-0.5, 0.5, 2), rng.uniform(5, 8)])
        truth[int(q)] = (R, t)
        X = (np.c_[rng.uniform(-1.5, 1.5, (30, 2)), rng.uniform(-1, 1, 30) + t[2]] - t) @ R
        cam = X @ R.T + t
        uv = 800 * cam[:, :2] / cam[:, 2:] + [320, 240] + rng.normal(0, 1, (30, 2))
        outliers = rng.random(30) < 0.2
        uv[outliers] = rng.uniform(0, 640, (outliers.sum(), 2))
        queries.append((q, 800.0, 800.0, 320.0, 240.0))
        points += [(q, *u, *x) for u, x in zip(uv, X)]
        ends = X[:8].reshape(4, 2, 3)
        cam_ends = ends @ R.T + t
        seg = 800 * cam_ends[..., :2] / cam_ends[..., 2:] + [320, 240]
        lines += [(q, *s.reshape(-1), *e.reshape(-1)) for s, e in zip(seg, ends)]
    table = lambda rows, names: pa.table({n: np.array([r[i] for r in rows]) for i, n in enumerate(names)})  # noqa: E731
    return (table(queries, dist.QUERY_COLUMNS), table(points, dist.POINT_MATCH_COLUMNS),
            table(lines, dist.LINE_MATCH_COLUMNS), truth)


def test_batch_localisation_on_dask_equals_the_kernel_and_finds_the_poses(client, tmp_path):
    queries, points, lines, truth = generated_queries(40, 8)
    # A bad query: a NaN pixel. It gets a status and message; the others are unaffected.
    x = points.column("x").to_numpy().copy()
    bad = int(points.column("query")[0].as_py())
    x[0] = np.nan
    points = points.set_column(1, "x", pa.array(x))
    paths = {}
    for name, t in (("queries", queries), ("points", points), ("lines", lines)):
        paths[name] = write(t, tmp_path / name, row_group_size=300)
    reference = dist.localize_tables(queries, points, lines, seed=5)
    summary = dist.localize(paths["queries"], paths["points"], tmp_path / "out", line_matches=paths["lines"],
                            client=client, buckets=6, seed=5)
    assert summary.tracks == 40
    poses = dist.read_poses(tmp_path / "out")
    assert_same_table(poses, reference[0])
    assert_same_table(dist.read_matches(tmp_path / "out"), reference[1])
    status = dict(zip(poses.column("query").to_pylist(), poses.column("status").to_pylist()))
    message = dict(zip(poses.column("query").to_pylist(), poses.column("message").to_pylist()))
    assert status[bad] == "invalid_input" and "non-finite" in message[bad].lower()
    R = np.asarray(poses.column("R").to_pylist()).reshape(-1, 3, 3)
    t = np.asarray(poses.column("t").to_pylist())
    for q, r, tt, s in zip(poses.column("query").to_pylist(), R, t, poses.column("status").to_pylist()):
        if q == bad:
            continue
        assert s == "success", (q, s)
        # 1 px noise on ~24 inliers of a cloud 3 units wide seen from 5-8 units at f = 800 px: a few
        # tenths of a degree (rotation and translation trade off at this depth-to-width ratio); a wrong
        # pose (a RANSAC failure, a flipped solution) is off by many degrees.
        angle = np.arccos(np.clip((np.trace(r.T @ truth[q][0]) - 1) / 2, -1, 1))
        assert angle < np.radians(2.0) and np.linalg.norm(tt - truth[q][1]) < 0.2, (q, np.degrees(angle))


def test_command_line_on_a_scheduler_writes_the_same_colmap_model(client, tmp_path, capsys):
    pycolmap = pytest.importorskip("pycolmap")
    from test_colmap import noisy_model_with_outliers

    from pluecker.cli import main

    rec, _ = noisy_model_with_outliers(7)
    (tmp_path / "in").mkdir()
    rec.write(str(tmp_path / "in"))
    common = ["triangulate", "--colmap", str(tmp_path / "in"), "--outlier-threshold", "4"]
    assert main([*common, "--out", str(tmp_path / "here")]) == 0
    assert main([*common, "--out", str(tmp_path / "dask"), "--scheduler", client.scheduler.address]) == 0
    out = capsys.readouterr().out
    assert "on 2 Dask workers" in out and "60 certified" in out
    here, there = (np.load(tmp_path / d / "points3D_triangulation.npz") for d in ("here", "dask"))
    np.testing.assert_array_equal(here["point3D_id"], there["point3D_id"])
    np.testing.assert_array_equal(here["X"], there["X"])
    np.testing.assert_array_equal(here["certified"], there["certified"])
    # The same observations rejected, whatever their order in the two files.
    rejected = lambda s: {(int(i), int(k)) for i, k, ok in zip(s["observation_image_id"], s["observation_point2D_idx"],  # noqa: E731
                                                               s["observation_inlier"]) if not ok}
    assert rejected(here) == rejected(there) and rejected(here)
    back = pycolmap.Reconstruction(str(tmp_path / "dask"))
    assert back.num_points3D() == 60 and not (tmp_path / "dask" / "_job").exists()
    # --scheduler only with --colmap, and an unreachable scheduler is an error line.
    assert no_scheduler_at(["triangulate", str(tmp_path)]) == 2
    assert no_scheduler_at([*common, "--out", str(tmp_path / "x")]) == 2
    assert "cannot reach the Dask scheduler" in capsys.readouterr().err


def test_command_line_localize_with_and_without_a_scheduler(client, tmp_path, capsys):
    from pluecker.cli import main

    queries, points, lines, _ = generated_queries(12, 9)
    paths = {name: write(t, tmp_path / name, 100) for name, t in
             (("queries", queries), ("points", points), ("lines", lines))}
    base = ["localize", str(paths["queries"]), str(paths["points"]), "--lines", str(paths["lines"])]
    assert main([*base, "--out", str(tmp_path / "here")]) == 0
    assert "12 queries on this machine" in capsys.readouterr().out
    assert main([*base, "--out", str(tmp_path / "dask"), "--scheduler", client.scheduler.address]) == 0
    assert "12 success" in capsys.readouterr().out
    assert_same_table(dist.read_poses(tmp_path / "here"), dist.read_poses(tmp_path / "dask"))
    assert main(["localize", str(tmp_path / "missing"), str(paths["points"]), "--out", str(tmp_path / "x")]) == 2
    assert "no such file" in capsys.readouterr().err


def test_an_input_partitioned_by_track_is_solved_file_by_file(client, tmp_path):
    cameras, table = generated(900, 10)
    track = table.column("track").to_numpy()
    (tmp_path / "in").mkdir()
    for k, part in enumerate(np.array_split(np.unique(track), 3)):
        pq.write_table(table.filter(pa.compute.is_in(table.column("track"), pa.array(part))),
                       tmp_path / "in" / f"chunk-{k}.parquet")
    summary = dist.triangulate(tmp_path / "in", cameras, tmp_path / "out", client=client, partitioned=True,
                               threads_per_worker=1)
    assert summary.buckets == 3 and summary.tracks == 900
    reference = dist.triangulate_table(table, cameras)
    assert dist.read_points(tmp_path / "out").equals(reference[0])
    assert dist.read_observations(tmp_path / "out").equals(reference[1])
    assert set(client.run(pluecker.get_num_threads).values()) == {1}


def test_localisation_of_a_dask_bag_of_query_records(client, tmp_path):
    import dask
    import dask.bag as db

    queries, points, lines, _ = generated_queries(10, 11)
    reference = dist.localize_tables(queries, points, lines, seed=2)
    q = queries.column("query").to_numpy()
    P, L = points.to_pydict(), lines.to_pydict()
    pq_, lq = np.asarray(P["query"]), np.asarray(L["query"])
    records = [{"query": int(i), "camera": (800.0, 800.0, 320.0, 240.0),
                "points2d": np.c_[np.asarray(P["x"])[pq_ == i], np.asarray(P["y"])[pq_ == i]],
                "points3d": np.c_[[np.asarray(P[c])[pq_ == i] for c in "XYZ"]].T,
                "lines2d": np.c_[[np.asarray(L[c])[lq == i] for c in ("x1", "y1", "x2", "y2")]].T.reshape(-1, 2, 2),
                "lines3d": np.c_[[np.asarray(L[c])[lq == i] for c in ("X1", "Y1", "Z1", "X2", "Y2", "Z2")]].T.reshape(-1, 2, 3)}
               for i in q]
    counts = dask.compute(*dist.localize_bag(db.from_sequence(records, npartitions=3), tmp_path / "out", seed=2))
    assert sum(counts) == 10
    assert_same_table(dist.read_poses(tmp_path / "out"), reference[0])


def test_command_line_on_a_scheduler_names_what_it_left_out(client, tmp_path, capsys):
    """The Dask path of ``triangulate --colmap`` dropped the names of the cameras it left out (the local
    path printed them); its scratch folder and an unreachable scheduler leave nothing behind."""
    pycolmap = pytest.importorskip("pycolmap")
    from test_colmap_bad_input import model

    from pluecker.cli import main

    rec = model()
    odd = sorted(rec.cameras)[1]
    rec.cameras[odd] = pycolmap.Camera(camera_id=odd, model="PINHOLE", width=1024, height=768,
                                       params=[0.0, 0.0, 512.0, 384.0])
    (tmp_path / "in").mkdir()
    rec.write(str(tmp_path / "in"))
    common = ["triangulate", "--colmap", str(tmp_path / "in")]
    for out, flags in (("here", []), ("dask", ["--scheduler", client.scheduler.address])):
        assert main([*common, "--out", str(tmp_path / out), *flags]) == 0
        printed = capsys.readouterr().out
        assert f"left out: 1 (camera_id {odd} (PINHOLE): singular camera: " in printed, printed
    assert sorted(p.name for p in tmp_path.iterdir()) == ["dask", "here", "in"]
    assert not [p for p in (tmp_path / "dask").iterdir() if p.name.startswith(".")]
    assert no_scheduler_at([*common, "--out", str(tmp_path / "x")]) == 2
    assert not (tmp_path / "x").exists()


def test_ctrl_c_in_localize_tables_returns_without_waiting_for_the_running_queries(monkeypatch):
    """A KeyboardInterrupt while queries are solved on the thread pool ends the call at once: the
    queries not started are dropped, and the call does not wait for the one still running (a long
    robust pose) before it raises."""
    import threading

    from test_bad_input_tables import query_scene

    queries, matches = query_scene()
    n = 40
    many_queries = {k: v * n for k, v in queries.items()}
    many_queries["query"] = list(range(n))
    many_matches = {k: np.tile(v, n) for k, v in matches.items()}
    many_matches["query"] = np.repeat(np.arange(n), len(matches["x"]))
    # Two workers. Query 0 (RANSAC seed 0: the seeds are 0 + query) runs until released; the first other
    # query raises KeyboardInterrupt once query 0 is running. So the interrupt comes from a query after
    # one still in flight, in either order of the workers' calls (no timing assumed): the call must not
    # wait for query 0 to raise it.
    state = {"calls": 0, "running": 0, "raised": False}
    changed = threading.Condition()
    interrupted = threading.Event()
    released = []

    def estimate_pose(*args, **kwargs):
        with changed:
            state["calls"] += 1
            if kwargs["options"].ransac.seed != 0 and not state["raised"]:
                state["raised"] = True
                assert changed.wait_for(lambda: state["running"] >= 1, timeout=30)
                raise KeyboardInterrupt
            state["running"] += 1
            changed.notify_all()
        # Runs until the test releases it, which it does once the call has raised (the timeout is a
        # safety bound: a call that waits for this query gets it back False).
        released.append(interrupted.wait(timeout=30))
        with changed:
            state["running"] -= 1
            changed.notify_all()
        raise pluecker.PlueckerError("not solved in this test")

    monkeypatch.setattr(dist._core, "estimate_pose", estimate_pose)
    with pytest.raises(KeyboardInterrupt):
        dist.localize_tables(pa.table(many_queries), pa.table(many_matches), threads=2)
    interrupted.set()
    with changed:
        assert changed.wait_for(lambda: state["running"] == 0, timeout=30)
    # Every query still running when the call raised was still blocked then; at most one more query
    # (taken by the freed worker before the cancel) started after the interrupt, of the 40.
    assert released and all(released)
    assert state["calls"] <= 3
