"""Every long call can be stopped: Ctrl-C (a real SIGINT sent to this process), an exception raised by a
batch's ``progress`` callback, and a batch's ``time_budget``. Stopped batches keep their finished tracks
(bit-exact with an uninterrupted run) and say ``interrupted`` / ``time_budget`` for the others.

No test waits a fixed delay: a hook of the extension (``_on_poll_for_tests``) simulates Ctrl-C (what
Python's SIGINT handler does) at a given poll of the call's stop, that is once a given track,
branch-and-bound node or interior-point iteration of a conic solve has been reached, or at a given
poll of the call's set-up (reading its arrays, sorting its rows, allocating its results), or holds a
poll until the time budget has run out; the call then has to notice it by itself. The workloads run for minutes if nothing stops them (branch and
bound with a 1e-9 gap), and a batch has one track more than the extension has threads, so that
whatever the number of cores some tracks have started and some cannot have. A ``time_budget`` (or a
node cap) far beyond what a working build needs keeps a broken one from hanging the suite."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys

import numpy as np
import pytest
from conftest import hooks
from triangulation_scenes import NODES, line_tracks

import pluecker
from pluecker.experiments.josephson_kahl_2008.conics import disc_scene

#: The safety budget of an interrupted batch (seconds), and the time budget of the budget test.
SAFETY, BUDGET = 60.0, 0.3
#: The node cap of an interrupted single call: seconds of branch and bound that a build which does not
#: stop single calls runs to the end (and fails), where a working one stops within a few nodes.
SAFETY_NODES = 2_000

pytestmark = pytest.mark.skipif(not hasattr(signal, "SIGINT") or os.name == "nt", reason="POSIX signals")


@pytest.fixture(autouse=True)
def sigint_raises_keyboard_interrupt():
    """Python's own SIGINT handler for the test. A process started in the background by a
    non-interactive shell (``make test &``) inherits SIGINT ignored, and Python then installs no
    handler: the signal would be dropped and no call could be stopped."""
    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    yield
    signal.signal(signal.SIGINT, previous)


def ctrl_c_at_poll(poll: int) -> None:
    """Ctrl-C (as Python's SIGINT handler records it) at the ``poll``-th poll of the next call's stop."""
    hooks._on_poll_for_tests(poll, "interrupt")


def endless_lines(n: int | None = None, max_nodes: int = 10**7):
    """A line batch that branch and bound cannot finish in minutes: noisy lines, a 1e-9 gap, the paper's
    relaxation (the default Taylor bound closes even this gap in milliseconds). By default one line more
    than the batch has threads: at most one per thread can be started before a stop, none finishes."""
    n = pluecker.get_num_threads() + 1 if n is None else n
    P, segments = line_tracks(0, n=n, views=4, sigma=2.0)
    options = pluecker.TriangulationOptions(certify=pluecker.CertifyOptions(max_relative_gap=1e-9, max_nodes=max_nodes), line_bound="relaxation")
    return P, segments, dict(options=options)


def assert_stopped_batch(batch, n: int, status: str) -> None:
    """Every track of a batch stopped before any finished: the ones being solved keep a finite estimate
    and a lower bound at most their cost, uncertified; the others are NaN with the message."""
    assert len(batch) == n and set(batch.status) == {status}
    assert not batch.certified.any()
    started = np.array([m == "" for m in batch.messages])
    assert started.any() and not started.all()
    assert started.sum() <= pluecker.get_num_threads()
    assert np.isfinite(batch.plucker[started]).all()
    assert (batch.lower_bound[started] <= batch.cost[started]).all()
    assert np.isnan(batch.plucker[~started]).all()
    reason = "interrupted" if status == "interrupted" else "the time budget ran out"
    assert all(m.endswith(f"not solved: {reason}") for m in np.asarray(batch.messages)[~started])


def test_ctrl_c_stops_a_line_batch_and_keeps_what_it_had():
    P, segments, options = endless_lines()
    # The first poll comes before the first track, which then starts.
    ctrl_c_at_poll(1)
    with pytest.raises(KeyboardInterrupt) as caught:
        pluecker.triangulate_lines(P, segments, time_budget=SAFETY, **options)
    partial = caught.value.partial
    assert isinstance(partial, pluecker.LineTriangulations)
    assert_stopped_batch(partial, len(segments), "interrupted")


def test_time_budget_ends_a_batch_without_an_exception():
    P, segments, options = endless_lines()
    # The first track starts, its poll held until the budget has run out.
    hooks._on_poll_for_tests(1, "await_deadline")
    batch = pluecker.triangulate_lines(P, segments, time_budget=BUDGET, **options)
    assert_stopped_batch(batch, len(segments), "time_budget")
    # A zero budget solves nothing, in every batch, and the linear fast path says so too.
    for method in ("linear", "optimal"):
        lines = pluecker.triangulate_lines(P, segments, options=pluecker.TriangulationOptions(method=method), time_budget=0)
        assert set(lines.status) == {"time_budget"} and np.isnan(lines.plucker).all()
    x = np.stack([segments[:, :, 0], segments[:, :, 1]]).reshape(-1, 4, 2)
    for method in ("linear", "local", "optimal"):
        points = pluecker.triangulate_points(P, x, options=pluecker.TriangulationOptions(method=method), time_budget=0.0)
        assert set(points.status) == {"time_budget"} and np.isnan(points.point).all()


def test_a_failing_progress_callback_stops_the_batch_and_keeps_finished_tracks():
    P, segments = line_tracks(3, n=60, views=4, sigma=1.0)
    plain = pluecker.triangulate_lines(P, segments, options=pluecker.TriangulationOptions(method="optimal", certify=pluecker.CertifyOptions(max_nodes=NODES)))
    seen: list[int] = []

    def stop_after_some(done: int) -> None:
        seen.append(done)
        if done > 0:
            raise RuntimeError("enough")

    with pytest.raises(RuntimeError, match="enough") as caught:
        pluecker.triangulate_lines(P, segments, progress=stop_after_some, options=pluecker.TriangulationOptions(method="optimal", certify=pluecker.CertifyOptions(max_nodes=NODES)))
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
    camera = pluecker.Camera.pinhole(800, 800, 320, 240)
    X = rng.uniform(-1, 1, (n, 3)) + [0, 0, 6]
    u = rng.uniform(0, 640, (n, 2))  # all outliers, and no inlier-ratio cap: it would sample for hours
    # RANSAC polls before each sample and between the rounds of a local optimisation: the third poll
    # comes after the first sample at the earliest.
    ctrl_c_at_poll(3)
    with pytest.raises(KeyboardInterrupt) as caught:
        pluecker.estimate_pose(camera, u, X, options=pluecker.PoseOptions(ransac=pluecker.RansacOptions(min_inlier_ratio=0.0, max_iterations=10**12, confidence=1 - 1e-12, time_budget=SAFETY)))
    partial = caught.value.partial
    assert isinstance(partial, pluecker.PoseResult)
    assert partial.details.ransac.stop == "interrupted" and partial.status != "success"
    assert partial.details.ransac.iterations >= 1


def assert_stopped_single(partial, most_iterations: int) -> None:
    """A single triangulation stopped while bounding its root: the estimate reached, uncertified, with a
    bound at most its cost; no node split and at most ``most_iterations`` interior-point iterations."""
    assert partial.status == "interrupted" and not partial.certified
    assert np.isfinite(partial.cost) and partial.certificate.lower_bound <= partial.cost
    assert partial.certificate.nodes == 1
    assert partial.certificate.solver_iterations <= most_iterations


def test_ctrl_c_stops_a_single_line_inside_a_conic_solve():
    P, segments, options = endless_lines(n=1, max_nodes=SAFETY_NODES)
    # A conic solve polls before it starts and at every iteration: the third poll is inside the
    # first solve of the root's bound tightening, at most two iterations in; no solve runs after it.
    ctrl_c_at_poll(3)
    with pytest.raises(KeyboardInterrupt) as caught:
        pluecker.triangulate_line(P, segments[0], **options)
    assert isinstance(caught.value.partial, pluecker.LineTriangulation)
    assert_stopped_single(caught.value.partial, 2)


def test_ctrl_c_stops_the_root_of_a_line_seen_in_30_views():
    """The root of a line in 30 views (its bound tightening solves about 70 programs of 30 cones, most
    of a second) stops at the first poll: no conic solve runs after Ctrl-C."""
    P, segments = line_tracks(0, n=1, views=30, sigma=2.0)
    options = pluecker.TriangulationOptions(certify=pluecker.CertifyOptions(max_relative_gap=1e-9, max_nodes=SAFETY_NODES),
                                            line_bound="relaxation")
    ctrl_c_at_poll(1)
    with pytest.raises(KeyboardInterrupt) as caught:
        pluecker.triangulate_line(P, segments[0], options=options)
    assert isinstance(caught.value.partial, pluecker.LineTriangulation)
    assert_stopped_single(caught.value.partial, 0)


def test_ctrl_c_stops_a_single_quadric_inside_a_conic_solve():
    """The third poll is inside the first solve of the root's denominator ranges: without those
    ranges there is no box to search and no bound; the stop must say so, not that the domain was
    proved empty (``infeasible``)."""
    scene = disc_scene(3)
    options = pluecker.TriangulationOptions(certify=pluecker.CertifyOptions(max_relative_gap=1e-9, max_nodes=SAFETY_NODES), quadric_bound="relaxation")
    ctrl_c_at_poll(3)
    with pytest.raises(KeyboardInterrupt) as caught:
        pluecker.triangulate_quadric(scene.cameras, scene.conics, scene.covariances, options=options)
    partial = caught.value.partial
    assert isinstance(partial, pluecker.QuadricTriangulation)
    assert partial.status == "interrupted" and not partial.certified
    assert partial.certificate is None and np.isfinite(partial.cost)


#: Values a call's set-up handles between two polls (``SETUP_CHUNK`` of crates/pluecker-py/src/interrupt.rs).
SETUP_CHUNK = 2**20


def setup_polls(call) -> int:
    """The polls of ``call``'s set-up, counted (by a set-up hook that never acts); Ctrl-C at the first,
    the middle and the last of them stops the call with ``KeyboardInterrupt`` and ``partial = None``,
    nothing solved, and a hook armed one poll beyond them never acts (the call runs)."""
    hooks._on_poll_for_tests(2**62, "interrupt_setup")
    call()
    polls = hooks._setup_polls_for_tests()
    for poll in sorted({1, (polls + 1) // 2, polls}):
        hooks._on_poll_for_tests(poll, "interrupt_setup")
        with pytest.raises(KeyboardInterrupt) as stopped:
            call()
        assert stopped.value.partial is None
    hooks._on_poll_for_tests(polls + 1, "interrupt_setup")
    call()
    assert hooks._setup_polls_for_tests() == polls
    return polls


def test_ctrl_c_stops_the_set_up_of_a_point_batch():
    """A batch of 600,000 tracks reads 2.4 M pixel values and allocates 13.8 M result entries before it
    solves anything: a poll at least every ``SETUP_CHUNK`` values, each able to stop it."""
    rng = np.random.default_rng(0)
    P, _ = line_tracks(0, n=1, views=2)
    n = 600_000
    x = rng.uniform(0, 640, (n, 2, 2))
    # A zero budget ends the batch as soon as its solving starts: only the set-up runs. The linear fast
    # path writes into the same preallocated columns, so that a stop never waits for their assembly.
    for method in ("optimal", "linear"):
        options = pluecker.TriangulationOptions(method=method)
        polls = setup_polls(lambda: pluecker.triangulate_points(P, x, options=options, time_budget=0))
        assert polls >= (x.size + n * (11 + 3 + 9)) / SETUP_CHUNK, method
        batch = pluecker.triangulate_points(P, x, options=options, time_budget=0)
        assert set(batch.status) == {"time_budget"} and np.isnan(batch.point).all()


def test_ctrl_c_stops_the_set_up_of_line_and_quadric_batches():
    """Line and quadric batches allocate their result columns before they solve, as point batches do
    (so that a stopped batch hands them back without a pass over millions of tracks): their set-up
    polls at least every ``SETUP_CHUNK`` values read or allocated."""
    rng = np.random.default_rng(0)
    P, _ = line_tracks(0, n=1, views=3)
    n = 300_000
    segments = rng.uniform(0, 640, (n, 2, 2, 2))
    polls = setup_polls(lambda: pluecker.triangulate_lines(P[:2], segments, time_budget=0))
    # Report columns (11 per track), Plücker coordinates 6, point 3, direction 3, chart axes 6,
    # covariance 16.
    assert polls >= (segments.size + n * (11 + 6 + 3 + 3 + 6 + 16)) / SETUP_CHUNK
    n = 100_000
    conics = np.broadcast_to(np.diag([1.0, 1.0, -1.0]), (n, 3, 3, 3))
    polls = setup_polls(lambda: pluecker.triangulate_quadrics(P, conics, time_budget=0))
    # Report columns 11, dual and primal quadrics 16 each, centre 3, semi-axes 3, axes 9, covariance 81.
    assert polls >= (conics.size + n * (11 + 16 + 16 + 3 + 3 + 9 + 81)) / SETUP_CHUNK
    batch = pluecker.triangulate_quadrics(P, conics, time_budget=0)
    assert set(batch.status) == {"time_budget"} and np.isnan(batch.Q).all()


def test_ctrl_c_stops_the_set_up_of_an_observation_batch():
    """One observation per row (1.5 M rows, 500,000 tracks): the conversions of ``track`` and ``image``
    (int64) and of the broadcast covariances, the sort by track and the gathering of the rows all
    poll, at least every ``SETUP_CHUNK`` values."""
    rng = np.random.default_rng(0)
    P, _ = line_tracks(0, n=1, views=3)
    m, n = 1_500_000, 500_000
    track = np.repeat(np.arange(n), 3)
    rng.shuffle(track)
    image = rng.integers(0, 3, m)
    x = rng.uniform(0, 640, (m, 2))
    covariances = np.broadcast_to(np.eye(2), (m, 2, 2))
    polls = setup_polls(lambda: pluecker.triangulate_points(P, x, covariances=covariances, track=track, image=image, time_budget=0))
    # Read: track, image (m each), x (2m), covariances (4m); sorted: three passes over the rows and
    # the gathering of the rows of x and of the covariances; allocated: 23 result entries per track.
    assert polls >= (8 * m + 3 * m + 2 * m + 23 * n) / SETUP_CHUNK


def test_ctrl_c_stops_the_certificate_of_a_single_pose():
    scene = pluecker.random_scene("general", 30, 0, 5)
    options = pluecker.PoseOptions(certify=pluecker.CertifyOptions(max_nodes=10**9))
    plain = pluecker.estimate_pose(scene["camera"], scene["points2d"], scene["points3d"], options=options)
    assert plain.certified
    # The rotation search polls before each cell: Ctrl-C at its first.
    ctrl_c_at_poll(1)
    with pytest.raises(KeyboardInterrupt) as caught:
        pluecker.estimate_pose(scene["camera"], scene["points2d"], scene["points3d"], options=options)
    partial = caught.value.partial
    assert isinstance(partial, pluecker.PoseResult) and not partial.certified
    assert partial.status == "interrupted" and partial.certificate is None
    assert "interrupted" in partial.details.uncertified_reason
    # The pose itself does not depend on the stop.
    np.testing.assert_array_equal(partial.pose.rotation, plain.pose.rotation)


def test_the_test_hook_checks_its_arguments():
    with pytest.raises(pluecker.InvalidOptionError, match="action"):
        hooks._on_poll_for_tests(1, "explode")
    with pytest.raises(pluecker.InvalidOptionError, match="poll"):
        hooks._on_poll_for_tests(0, "interrupt")


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


#: A ``pluecker pose`` process whose command runs ``BODY`` instead of the pose (``fd``: a file
#: descriptor for ``_hold_gil_for_tests``); a ``finally`` around the command prints ``clean-up ran``.
COMMAND = """
import signal, sys
signal.signal(signal.SIGINT, signal.default_int_handler)  # as in an interactive shell
from pluecker import cli, _core
fd = int(sys.argv[1])
def command(args):
    try:
        BODY
    finally:
        print("clean-up ran", flush=True)
    return 0
cli._pose = command
sys.argv = ["pluecker", "pose", "unused.json"]
cli.run()
"""


def run_command(body: str):
    """Starts the ``COMMAND`` process with ``body``; returns it and the read end of its descriptor."""
    hooks._hold_gil_for_tests  # noqa: B018 (the child calls it: a build without it fails here, saying so)
    read, write = os.pipe()
    child = subprocess.Popen([sys.executable, "-c", COMMAND.replace("BODY", body), str(write)], pass_fds=(write,),
                             stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    os.close(write)
    return child, read


def test_the_command_ends_after_ctrl_c_while_a_call_holds_the_interpreter():
    """A library call that holds the GIL for ten minutes (as pycolmap holds it while it reads a model):
    Python cannot raise KeyboardInterrupt before it returns, so the command's deadline ends the process
    itself, status 130 and the one line, without its clean-up."""
    child, ready = run_command("_core._hold_gil_for_tests(fd, 600.0)")
    try:
        # The byte is written inside the call: from here the main thread holds the GIL.
        assert os.read(ready, 1) == b"x"
        child.send_signal(signal.SIGINT)
        out, err = child.communicate(timeout=SAFETY)
    finally:
        os.close(ready)
        child.kill()
    assert (child.returncode, err, out) == (130, "pluecker pose: interrupted\n", "")


def test_a_forced_exit_leaves_no_output_behind(tmp_path):
    """The deadline's exit runs no ``finally``, but what the command was writing goes with it: Ctrl-C
    while a call holds the GIL inside an output being staged (in parent folders made for it) leaves
    neither the output, nor its temporary folder, nor those parents. Files the user had stay."""
    kept = tmp_path / "kept.txt"
    kept.write_text("mine")
    out = tmp_path / "new" / "deeper" / "out"
    body = (f"from pluecker import _paths\n"
            f"        with _paths.staged({str(out)!r}) as stage:\n"
            f"            (stage.path / 'points.json').write_text('half')\n"
            f"            _core._hold_gil_for_tests(fd, 600.0)")
    child, ready = run_command(body)
    try:
        assert os.read(ready, 1) == b"x"
        assert len(list((tmp_path / "new" / "deeper").iterdir())) == 1  # the temporary folder
        child.send_signal(signal.SIGINT)
        out_text, err = child.communicate(timeout=SAFETY)
    finally:
        os.close(ready)
        child.kill()
    assert (child.returncode, err, out_text) == (130, "pluecker pose: interrupted\n", "")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["kept.txt"]
    assert kept.read_text() == "mine"


def command_run_to_its_end(code: str) -> tuple[int, str, str]:
    """The exit status, standard output and standard error of ``run_command(code)`` left to finish."""
    child, ready = run_command(code)
    try:
        out, err = child.communicate(timeout=SAFETY)
    finally:
        os.close(ready)
        child.kill()
    return child.returncode, out, err


def test_the_command_answers_ctrl_c_itself_when_python_can():
    """Ctrl-C that Python turns into KeyboardInterrupt: the command's own clean-up runs, and the line is
    printed once (the deadline stands down, or, had Python been slower than it, printed it instead)."""
    status, _, err = command_run_to_its_end("signal.raise_signal(signal.SIGINT)")
    assert (status, err) == (130, "pluecker pose: interrupted\n")
    # A library that turns the KeyboardInterrupt into an error of its own (pycolmap interrupted while it
    # loads its C++ module raises RuntimeError): still Ctrl-C, not a traceback.
    status, _, err = command_run_to_its_end("raise RuntimeError('cannot import the backend') from KeyboardInterrupt()")
    assert (status, err) == (130, "pluecker pose: interrupted\n")
    # And a command that ends normally gives the wakeup descriptor back and exits with its status.
    assert command_run_to_its_end("import signal as s; assert s.set_wakeup_fd(-1) != -1") == (0, "clean-up ran\n", "")
