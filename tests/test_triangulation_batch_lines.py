"""``pluecker.triangulate_lines`` and ``pluecker.triangulate_quadrics``: every track equals the single call
on its visible views (the same core function on the same numbers: equal, not close), cameras shared or
per track, per-track errors that never lose the other tracks, whole-call errors, progress reports."""

from __future__ import annotations

import threading
import time

import numpy as np
import pytest
from test_triangulation import cameras
from test_triangulation_line import project_point
from test_triangulation_quadric import ellipsoid, outlines

import pluecker
from pluecker.experiments.josephson_kahl_2008.conics import disc_scene

METHODS = pluecker.TRIANGULATION_METHODS
#: Branch and bound is capped so that the optimal runs stay short; the equality holds at any cap.
NODES = 30
REPORT = ("cost", "lower_bound", "relative_gap", "certified", "certificate", "status", "nodes", "iterations")


def line_tracks(seed: int, n: int = 10, views: int = 4, sigma: float = 1.0):
    """Cameras (v, 3, 4) and noisy segments (n, v, 2, 2) of n random 3-D segments."""
    rng = np.random.default_rng(seed)
    P = cameras(views, 30.0, rng)
    ends = rng.uniform(-1.0, 1.0, (n, 2, 3))
    segments = np.stack([np.stack([project_point(P, A), project_point(P, B)], axis=1) for A, B in ends])
    return P, segments + rng.normal(0.0, sigma, segments.shape)


def random_visibility(rng, n: int, views: int, least: int) -> np.ndarray:
    visible = rng.uniform(size=(n, views)) < 0.7
    for i in range(n):
        visible[i, rng.choice(views, least, replace=False)] = True
    return visible


def assert_same_report(batch, i: int, single) -> None:
    for field in REPORT:
        assert getattr(batch, field)[i] == getattr(single, field), (i, field)


def assert_same_line(batch, i: int, single) -> None:
    for field in ("plucker", "point", "direction"):
        np.testing.assert_array_equal(getattr(batch, field)[i], getattr(single, field), err_msg=f"{i} {field}")
    assert_same_report(batch, i, single)


@pytest.mark.parametrize("method", METHODS)
def test_line_batch_equals_single_calls(method, seed):
    P, segments = line_tracks(seed)
    rng = np.random.default_rng(seed)
    visible = random_visibility(rng, len(segments), 4, 2)
    masked = np.where(visible[..., None, None], segments, np.nan)  # unseen entries may hold anything
    batch = pluecker.triangulate_lines(P, masked, visible, method=method, sigma=1.5, options=pluecker.TriangulationOptions(max_nodes=NODES))
    assert len(batch) == 10 and batch.method == method and isinstance(batch, pluecker.BatchReport)
    assert batch.plucker.shape == (10, 6) and batch.point.shape == (10, 3) and batch.direction.shape == (10, 3)
    assert batch.status.shape == (10,) and batch.time_seconds.shape == (10,)
    for i, seen in enumerate(visible):
        single = pluecker.triangulate_line(P[seen], segments[i][seen], sigma=1.5, method=method, options=pluecker.TriangulationOptions(max_nodes=NODES))
        assert_same_line(batch, i, single)
    assert all(m == "" for m in batch.messages)
    assert "LineTriangulations(method=" in repr(batch)


def test_homogeneous_lines_with_covariances_and_cameras_per_track(seed):
    rng = np.random.default_rng(seed)
    n, views = 6, 3
    P = np.stack([cameras(views, 20.0 + 5 * i, rng) for i in range(n)])  # each track its own cameras
    ends = rng.uniform(-1.0, 1.0, (n, 2, 3))
    lines = np.stack([np.cross(P[i] @ np.append(A, 1.0), P[i] @ np.append(B, 1.0)) for i, (A, B) in enumerate(ends)])
    lines += rng.normal(0.0, 1e-3, lines.shape) * np.abs(lines)
    A = rng.normal(size=(n, views, 2, 2))
    cov = A @ A.transpose(0, 1, 3, 2) + 0.5 * np.eye(2)
    batch = pluecker.triangulate_lines(P, lines, cov=cov, method="local")
    for i in range(n):
        assert_same_line(batch, i, pluecker.triangulate_line(P[i], lines[i], cov[i], method="local"))
    # Segments whose covariances are given: the segments give only the lines.
    P1, segments = line_tracks(seed, n=4, views=3)
    cov = np.tile(np.diag([4.0, 0.25]), (4, 3, 1, 1))
    batch = pluecker.triangulate_lines(P1, segments, cov=cov, method="local")
    for i in range(4):
        assert_same_line(batch, i, pluecker.triangulate_line(P1, segments[i], cov[i], method="local"))


def test_one_bad_line_track_never_loses_the_others(seed):
    P, segments = line_tracks(seed, n=8)
    visible = np.ones((8, 4), dtype=bool)
    segments = segments.copy()
    segments[1, 2, 0, 1] = np.nan  # NaN in a visible view
    segments[2, 3] = np.nan  # NaN where the track is not seen: fine
    visible[2, 3] = False
    visible[3] = [False, True, False, False]  # one view
    segments[4, 1, 1] = segments[4, 1, 0]  # a zero-length segment
    batch = pluecker.triangulate_lines(P, segments, visible, method="local")
    expected = {1: ("non_finite", "lines[1]: non-finite value (NaN or inf) in row 2"),
                3: ("too_few_views", "needs 2 visible views per track, got 1 view(s)"),
                4: ("degenerate", "lines[4][1] has zero length")}
    for i, (status, message) in expected.items():
        assert batch.status[i] == status, (i, batch.messages[i])
        assert batch.messages[i].startswith(f"track {i}: ") and message in batch.messages[i], batch.messages[i]
        assert np.all(np.isnan(batch.plucker[i])) and np.isnan(batch.cost[i]) and not batch.certified[i]
    good = np.setdiff1d(np.arange(8), list(expected))
    assert np.all(batch.status[good] == "success")
    # A covariance that is not positive definite, in homogeneous form.
    homogeneous = np.concatenate([segments, np.ones((8, 4, 2, 1))], axis=-1)
    lines = np.cross(homogeneous[..., 0, :], homogeneous[..., 1, :])
    cov = np.tile(np.eye(2), (8, 4, 1, 1))
    cov[6, 0] = [[1.0, 2.0], [2.0, 1.0]]
    batch = pluecker.triangulate_lines(P, lines, visible, cov, method="linear")
    assert batch.status[6] == "degenerate" and "cov[6][0] is not positive definite" in batch.messages[6]
    assert batch.status[0] == "success" and batch.status[5] == "success"


def test_quadric_batch_equals_single_calls_with_cameras_per_track(seed):
    # The reproduction's discs: each scene has its own cameras, solved together.
    scenes = [disc_scene(seed % 1000 + k) for k in range(3)]
    P = np.stack([s.cameras for s in scenes])
    conics = np.stack([s.conics for s in scenes])
    cov = np.stack([s.covariances for s in scenes])
    for method in METHODS:
        batch = pluecker.triangulate_quadrics(P, conics, cov=cov, method=method, options=pluecker.TriangulationOptions(max_nodes=NODES))
        assert batch.Q.shape == (3, 4, 4) and batch.primal.shape == (3, 4, 4) and batch.axes.shape == (3, 3, 3)
        assert batch.centre.shape == (3, 3) and batch.semi_axes.shape == (3, 3)
        for i, s in enumerate(scenes):
            single = pluecker.triangulate_quadric(s.cameras, s.conics, s.covariances, method=method, options=pluecker.TriangulationOptions(max_nodes=NODES))
            for field in ("Q", "centre", "semi_axes", "axes"):
                np.testing.assert_array_equal(getattr(batch, field)[i], getattr(single, field), err_msg=field)
            if single.primal is None:
                assert np.all(np.isnan(batch.primal[i]))
            else:
                np.testing.assert_array_equal(batch.primal[i], single.primal)
            assert_same_report(batch, i, single)


def test_quadric_batch_with_shared_cameras_and_visibility(seed):
    rng = np.random.default_rng(seed)
    n, views = 5, 5
    P = cameras(views, 60.0, rng)
    conics = np.stack([outlines(P, ellipsoid(rng)[3]) for _ in range(n)])
    conics += rng.normal(0.0, 1e-9, conics.shape) * np.abs(conics)
    visible = random_visibility(rng, n, views, 3)
    visible[4] = [True, True, False, False, False]  # two views: too few for a quadric
    conics[0, 1] = np.diag([1.0, -1.0, -100.0])  # a hyperbola, in a view the track is seen in
    visible[0, 1] = True
    batch = pluecker.triangulate_quadrics(P, conics, visible, method="local")
    assert batch.status[4] == "too_few_views" and "3 visible views" in batch.messages[4]
    assert batch.status[0] == "degenerate" and "conics[0][1] is not a real ellipse" in batch.messages[0]
    for i in range(1, 4):
        seen = visible[i]
        single = pluecker.triangulate_quadric(P[seen], conics[i][seen], method="local")
        np.testing.assert_array_equal(batch.Q[i], single.Q)
        assert_same_report(batch, i, single)
    assert "QuadricTriangulations(method='local', tracks=5" in repr(batch)


@pytest.mark.parametrize(
    "call, error, message",
    [
        (lambda P, s: pluecker.triangulate_lines(P[:1], s[:, :1]), pluecker.TooFewCorrespondencesError, "2 cameras"),
        (lambda P, s: pluecker.triangulate_lines(P, s[:, :3]), pluecker.ShapeError, "lines: expected shape (n, 4, 2, 2)"),
        (lambda P, s: pluecker.triangulate_lines(P, s[..., 0]), pluecker.ShapeError, "(n, v, 3) (homogeneous lines)"),
        (lambda P, s: pluecker.triangulate_lines(P[:, :2], s), pluecker.ShapeError, "P: expected shape (v, 3, 4)"),
        (lambda P, s: pluecker.triangulate_lines(np.stack([P, P]), s), pluecker.ShapeError, "lines: expected shape (2, 4"),
        (lambda P, s: pluecker.triangulate_lines(P, s, np.ones((5, 4), bool)), pluecker.ShapeError, "visible"),
        (lambda P, s: pluecker.triangulate_lines(P, s, cov=np.ones((10, 4, 3, 3))), pluecker.ShapeError, "cov"),
        (lambda P, s: pluecker.triangulate_lines(P, s, sigma=-1.0), pluecker.InvalidOptionError, "sigma"),
        (lambda P, s: pluecker.triangulate_lines(P, s, cov=np.tile(np.eye(2), (10, 4, 1, 1)), sigma=1.0),
         pluecker.InvalidOptionError, "not both"),
        (lambda P, s: pluecker.triangulate_lines(P, np.ones((10, 4, 3)), sigma=1.0), pluecker.InvalidOptionError,
         "segments"),
        (lambda P, s: pluecker.triangulate_lines(P, s, method="best"), pluecker.InvalidOptionError, "method"),
        (lambda P, s: pluecker.triangulate_lines(P * np.array([1.0, np.nan, 1.0, 1.0])[:, None, None], s),
         pluecker.NonFiniteError, "P: non-finite value (NaN or inf) in row 1"),
        (lambda P, s: pluecker.triangulate_quadrics(P[:2], np.ones((1, 2, 3, 3))), pluecker.TooFewCorrespondencesError,
         "3 cameras"),
        (lambda P, s: pluecker.triangulate_quadrics(P, np.ones((1, 4, 3, 3)), cov=np.ones((1, 4, 2, 2))),
         pluecker.ShapeError, "cov"),
    ],
)
def test_whole_call_errors(call, error, message, seed):
    P, segments = line_tracks(seed)
    with pytest.raises(error, match=message.replace("(", r"\(").replace(")", r"\)")):
        call(P, segments)


def test_visible_must_be_boolean_and_keywords_known(seed):
    P, segments = line_tracks(seed)
    with pytest.raises(TypeError, match="visible"):
        pluecker.triangulate_lines(P, segments, np.ones((10, 4)) * 0.5)
    with pytest.raises(TypeError):
        pluecker.triangulate_lines(P, segments, max_iterations=3)


def test_empty_batches(seed):
    P, _ = line_tracks(seed)
    lines = pluecker.triangulate_lines(P, np.zeros((0, 4, 2, 2)))
    assert len(lines) == 0 and lines.plucker.shape == (0, 6) and lines.status.shape == (0,)
    quadrics = pluecker.triangulate_quadrics(P, np.zeros((0, 4, 3, 3)))
    assert len(quadrics) == 0 and quadrics.Q.shape == (0, 4, 4)


def test_progress_counts_finished_tracks(seed):
    P, segments = line_tracks(seed, n=12)
    counts: list[int] = []
    batch = pluecker.triangulate_lines(P, segments, method="optimal", progress=counts.append, options=pluecker.TriangulationOptions(max_nodes=NODES))
    plain = pluecker.triangulate_lines(P, segments, method="optimal", options=pluecker.TriangulationOptions(max_nodes=NODES))
    assert counts and counts == sorted(counts) and counts[-1] == 12 and len(set(counts)) == len(counts)
    np.testing.assert_array_equal(batch.plucker, plain.plucker)

    # An exception raised by the callback stops the batch and comes out of the call, with the results
    # (test_interrupt.py checks them).
    def stop(done: int) -> None:
        raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt) as caught:
        pluecker.triangulate_lines(P, segments, method="local", progress=stop)
    assert len(caught.value.partial) == len(segments)


def test_gil_is_released_during_the_batch(seed):
    """Python keeps running while a line batch is solved in another thread: during a call of at least
    0.1 s the main thread must do at least 10 % of the iterations it would do alone in that time (with the
    GIL held it could run at most one switch interval, 5 ms, before the call enters Rust)."""
    import sys

    P, segments = line_tracks(seed, n=40)
    state = {"inside": False, "seconds": 0.0}

    def loop(seconds: float) -> int:
        count, end = 0, time.perf_counter() + seconds
        while time.perf_counter() < end:
            count += 1
        return count

    rate = loop(0.02) / 0.02

    def work():
        state["inside"] = True
        start = time.perf_counter()
        pluecker.triangulate_lines(P, segments, method="optimal", options=pluecker.TriangulationOptions(max_nodes=NODES))
        state["seconds"] = time.perf_counter() - start
        state["inside"] = False

    worker = threading.Thread(target=work)
    counted = 0
    worker.start()
    while not state["inside"]:
        time.sleep(0)
    while state["inside"]:
        time.perf_counter()
        counted += 1
    worker.join()
    assert state["seconds"] > 20 * sys.getswitchinterval(), "the call is too short to tell"
    assert counted > 0.1 * rate * state["seconds"], (counted, rate, state["seconds"])


def test_folder_records_a_rejected_line_and_keeps_the_others(tmp_path):
    """``pluecker triangulate --lines`` runs one batch: a line whose segment has zero length in one view is
    recorded with its status and message, left out of the PLY, and every other line is triangulated."""
    import shutil

    from pluecker import triangulate_folder
    from pluecker.datasets import load_vgg, vgg_root

    folder = tmp_path / "model_house"
    shutil.copytree(vgg_root() / "model_house", folder)
    seq = load_vgg(folder)
    tracks = np.flatnonzero(((seq.line_tracks[:, :4] >= 0).sum(axis=1) >= 2) & (seq.line_tracks[:, 0] >= 0))
    bad = int(tracks[0])
    path = folder / "house.000.lines"
    rows = path.read_text().splitlines()
    fields = rows[seq.line_tracks[bad, 0]].split()
    fields[2:4] = fields[0:2]  # the second endpoint onto the first
    rows[seq.line_tracks[bad, 0]] = " ".join(fields)
    path.write_text("\n".join(rows) + "\n")
    run = triangulate_folder.run(folder, views=[0, 1, 2, 3], method="linear", lines=True, show_progress=False)
    records = {r["index"]: r for r in run.lines.records}
    assert records[bad]["status"] == "degenerate" and "has zero length" in records[bad]["message"]
    assert np.all(np.isnan(records[bad]["point"])) and np.all(np.isnan(records[bad]["segment"]))
    others = [r for i, r in records.items() if i != bad]
    assert others and all(r["status"] == "success" and "message" not in r for r in others)
    assert len(run.lines.geometry) == len(others)
