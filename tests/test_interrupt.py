"""Every long call can be stopped: Ctrl-C (a real SIGINT sent to this process), an exception raised by a
batch's ``progress`` callback, and a batch's ``time_budget``. Stopped batches keep their finished tracks
(bit-exact with an uninterrupted run) and say ``interrupted`` / ``time_budget`` for the others.

The workloads are chosen to run for minutes if nothing stops them (branch and bound with a 1e-9 gap), so
that the signal always arrives during the call; a ``time_budget`` far beyond the signal's delay is the
safety net that keeps a broken build from hanging the suite (it would then fail, not hang: the pending
signal would surface after the call, without ``partial``)."""

from __future__ import annotations

import json
import os
import signal
import threading

import numpy as np
import pytest
from triangulation_scenes import NODES, line_tracks

import pluecker

#: Seconds after which the test's SIGINT is sent, and the safety budget of the interrupted call.
DELAY, SAFETY = 0.3, 60.0

pytestmark = pytest.mark.skipif(not hasattr(signal, "SIGINT") or os.name == "nt", reason="POSIX signals")


@pytest.fixture(autouse=True)
def sigint_raises_keyboard_interrupt():
    """Python's own SIGINT handler for the test. A process started in the background by a
    non-interactive shell (``make test &``) inherits SIGINT ignored, and Python then installs no
    handler: the signal would be dropped and no call could be stopped."""
    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    yield
    signal.signal(signal.SIGINT, previous)


def sigint_after(seconds: float) -> threading.Timer:
    """Sends SIGINT to this process after ``seconds`` (Python raises KeyboardInterrupt in the main thread)."""
    timer = threading.Timer(seconds, os.kill, (os.getpid(), signal.SIGINT))
    timer.start()
    return timer


def endless_lines(n: int = 8):
    """A line batch that branch and bound cannot finish in minutes: noisy lines, a 1e-9 gap, the paper's
    relaxation (the default Taylor bound closes even this gap in milliseconds)."""
    P, segments = line_tracks(0, n=n, views=4, sigma=2.0)
    options = pluecker.TriangulationOptions(max_relative_gap=1e-9, max_nodes=10**7, line_bound="relaxation")
    return P, segments, dict(method="optimal", options=options)


def assert_stopped_batch(batch, n: int, status: str) -> None:
    """Every track of a batch stopped before any finished: the ones being solved keep a finite estimate
    and a lower bound at most their cost, uncertified; the others are NaN with the message."""
    assert len(batch) == n and set(batch.status) == {status}
    assert not batch.certified.any()
    started = np.array([m == "" for m in batch.messages])
    assert started.any() and not started.all()
    assert np.isfinite(batch.plucker[started]).all()
    assert (batch.lower_bound[started] <= batch.cost[started]).all()
    assert np.isnan(batch.plucker[~started]).all()
    reason = "interrupted" if status == "interrupted" else "the time budget ran out"
    assert all(m.endswith(f"not solved: {reason}") for m in np.asarray(batch.messages)[~started])


def test_ctrl_c_stops_a_line_batch_and_keeps_what_it_had():
    P, segments, options = endless_lines()
    timer = sigint_after(DELAY)
    with pytest.raises(KeyboardInterrupt) as caught:
        pluecker.triangulate_lines(P, segments, time_budget=SAFETY, **options)
    timer.join()
    partial = caught.value.partial
    assert isinstance(partial, pluecker.LineTriangulations)
    assert_stopped_batch(partial, len(segments), "interrupted")


def test_time_budget_ends_a_batch_without_an_exception():
    P, segments, options = endless_lines()
    batch = pluecker.triangulate_lines(P, segments, time_budget=DELAY, **options)
    assert_stopped_batch(batch, len(segments), "time_budget")
    # A zero budget solves nothing, in every batch, and the linear fast path says so too.
    for method in ("linear", "optimal"):
        lines = pluecker.triangulate_lines(P, segments, method=method, time_budget=0)
        assert set(lines.status) == {"time_budget"} and np.isnan(lines.plucker).all()
    x = np.stack([segments[:, :, 0], segments[:, :, 1]]).reshape(-1, 4, 2)
    for method in ("linear", "local", "optimal"):
        points = pluecker.triangulate_points(P, x, method=method, time_budget=0.0)
        assert set(points.status) == {"time_budget"} and np.isnan(points.X).all()


def test_a_failing_progress_callback_stops_the_batch_and_keeps_finished_tracks():
    P, segments = line_tracks(3, n=60, views=4, sigma=1.0)
    plain = pluecker.triangulate_lines(P, segments, method="optimal", options=pluecker.TriangulationOptions(max_nodes=NODES))
    seen: list[int] = []

    def stop_after_some(done: int) -> None:
        seen.append(done)
        if done > 0:
            raise RuntimeError("enough")

    with pytest.raises(RuntimeError, match="enough") as caught:
        pluecker.triangulate_lines(P, segments, method="optimal", progress=stop_after_some, options=pluecker.TriangulationOptions(max_nodes=NODES))
    partial = caught.value.partial
    finished = partial.status != "interrupted"
    # The callback is not called again once it raised.
    assert seen[-1] > 0 and all(d == 0 for d in seen[:-1])
    assert finished.sum() >= seen[-1]
    np.testing.assert_array_equal(partial.plucker[finished], plain.plucker[finished])
    np.testing.assert_array_equal(partial.status[finished], plain.status[finished])
    if seen[-1] < len(segments):
        assert (~finished).any()


def test_ctrl_c_stops_a_robust_pose_and_returns_the_best_so_far():
    rng = np.random.default_rng(0)
    n = 20_000
    camera = pluecker.Camera(800, 800, 320, 240)
    X = rng.uniform(-1, 1, (n, 3)) + [0, 0, 6]
    u = rng.uniform(0, 640, (n, 2))  # all outliers, and no inlier-ratio cap: it would sample for hours
    timer = sigint_after(DELAY)
    with pytest.raises(KeyboardInterrupt) as caught:
        pluecker.estimate_pose(camera, u, X, ransac=pluecker.RansacOptions(min_inlier_ratio=0.0, max_iterations=10**12, confidence=1 - 1e-12, time_budget=SAFETY))
    timer.join()
    partial = caught.value.partial
    assert isinstance(partial, pluecker.PoseResult)
    assert partial.ransac.stop == "interrupted" and partial.status != "success"
    assert partial.ransac.iterations > 0


@pytest.mark.parametrize("budget", [-1.0, float("nan"), float("inf"), 1e20])
def test_bad_time_budgets_are_option_errors(budget):
    P, segments = line_tracks(0, n=2)
    with pytest.raises(pluecker.InvalidOptionError, match="time_budget"):
        pluecker.triangulate_lines(P, segments, time_budget=budget)
    with pytest.raises(pluecker.InvalidOptionError, match="time_budget"):
        pluecker.triangulate_points(P, segments[:, :, 0], time_budget=budget)


def test_command_line_ctrl_c_is_one_line_and_exit_130(monkeypatch, capsys, tmp_path):
    from pluecker import cli

    def interrupted(*args, **kwargs):
        raise KeyboardInterrupt

    monkeypatch.setattr(pluecker, "estimate_pose", interrupted)
    scene = pluecker.random_scene("general", 10, 0, 1)
    camera = scene["camera"]
    document = {
        "camera": {"fx": camera.fx, "fy": camera.fy, "cx": camera.cx, "cy": camera.cy},
        "points2d": scene["points2d"].tolist(),
        "points3d": scene["points3d"].tolist(),
    }
    path = tmp_path / "scene.json"
    path.write_text(json.dumps(document))
    assert cli.main(["pose", str(path)]) == 130
    captured = capsys.readouterr()
    assert captured.err == "pluecker pose: interrupted\n" and captured.out == ""
