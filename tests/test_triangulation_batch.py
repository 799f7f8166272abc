"""What every batch shares (``triangulate_lines`` and ``triangulate_quadrics`` here; the point batch in
test_triangulation_point.py): whole-call errors, the visibility mask, empty batches, progress, the GIL,
and the folder command keeping the other tracks when one is rejected."""

from __future__ import annotations

import threading
import time

import numpy as np
import pytest
from triangulation_scenes import NODES, line_tracks

import pluecker


@pytest.mark.parametrize(
    "call, error, message",
    [
        (lambda P, s: pluecker.triangulate_lines(P[:1], s[:, :1]), pluecker.TooFewCorrespondencesError, "2 cameras"),
        (lambda P, s: pluecker.triangulate_lines(P, s[:, :3]), pluecker.ShapeError, "lines: expected shape (n, 4, 2, 2)"),
        (lambda P, s: pluecker.triangulate_lines(P, s[..., 0]), pluecker.ShapeError, "(n, v, 3) (homogeneous lines)"),
        (lambda P, s: pluecker.triangulate_lines(P[:, :2], s), pluecker.ShapeError, "cameras: expected shape (v, 3, 4)"),
        (lambda P, s: pluecker.triangulate_lines(np.stack([P, P]), s), pluecker.ShapeError, "lines: expected shape (2, 4"),
        (lambda P, s: pluecker.triangulate_lines(P, s, np.ones((5, 4), bool)), pluecker.ShapeError, "visible"),
        (lambda P, s: pluecker.triangulate_lines(P, s, covariances=np.ones((10, 4, 3, 3))), pluecker.ShapeError, "covariances"),
        (lambda P, s: pluecker.triangulate_lines(P, s, sigma=-1.0), pluecker.InvalidOptionError, "sigma"),
        (lambda P, s: pluecker.triangulate_lines(P, s, covariances=np.tile(np.eye(2), (10, 4, 1, 1)), sigma=1.0),
         pluecker.InvalidOptionError, "not both"),
        (lambda P, s: pluecker.triangulate_lines(P, np.ones((10, 4, 3)), sigma=1.0), pluecker.InvalidOptionError,
         "segments"),
        (lambda P, s: pluecker.triangulate_lines(P, s, options=pluecker.TriangulationOptions(method="best")), pluecker.InvalidOptionError, "method"),
        (lambda P, s: pluecker.triangulate_lines(P * np.array([1.0, np.nan, 1.0, 1.0])[:, None, None], s),
         pluecker.NonFiniteError, "cameras: non-finite value (NaN or inf) in row 1"),
        (lambda P, s: pluecker.triangulate_quadrics(P[:2], np.ones((1, 2, 3, 3))), pluecker.TooFewCorrespondencesError,
         "3 cameras"),
        (lambda P, s: pluecker.triangulate_quadrics(P, np.ones((1, 4, 3, 3)), covariances=np.ones((1, 4, 2, 2))),
         pluecker.ShapeError, "covariances"),
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
    batch = pluecker.triangulate_lines(P, segments, progress=counts.append, options=pluecker.TriangulationOptions(method="optimal", certify=pluecker.CertifyOptions(max_nodes=NODES)))
    plain = pluecker.triangulate_lines(P, segments, options=pluecker.TriangulationOptions(method="optimal", certify=pluecker.CertifyOptions(max_nodes=NODES)))
    assert counts and counts == sorted(counts) and counts[-1] == 12 and len(set(counts)) == len(counts)
    np.testing.assert_array_equal(batch.plucker, plain.plucker)

    # An exception raised by the callback stops the batch and comes out of the call, with the results
    # (test_interrupt.py checks them).
    def stop(done: int) -> None:
        raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt) as caught:
        pluecker.triangulate_lines(P, segments, options=pluecker.TriangulationOptions(method="local"), progress=stop)
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
        # The paper's relaxation: long enough to tell (the default bound finishes in milliseconds).
        options = pluecker.TriangulationOptions(certify=pluecker.CertifyOptions(max_nodes=NODES), line_bound="relaxation")
        pluecker.triangulate_lines(P, segments, options=options)
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
    options = pluecker.TriangulationOptions(method="linear")
    run = triangulate_folder.run(folder, views=[0, 1, 2, 3], options=options, lines=True, show_progress=False)
    records = {r["index"]: r for r in run.lines.records}
    assert records[bad]["status"] == "degenerate" and "has zero length" in records[bad]["message"]
    assert np.all(np.isnan(records[bad]["point"])) and np.all(np.isnan(records[bad]["segment"]))
    others = [r for i, r in records.items() if i != bad]
    assert others and all(r["status"] == "success" and "message" not in r for r in others)
    assert len(run.lines.geometry) == len(others)

