"""Every triangulation entry point names a bad row by the keyword the caller passed.

The core's errors reach Python unchanged (no layer rewrites their text), so the Rust argument names and
the Python keywords must be the same words: `cameras`, `observations` / `lines` / `conics`,
`covariances`. For each entry point and each array argument, a row that is bad in a way the *core*
detects (a singular projection, a non-finite pixel, a zero-length segment, a conic that is not an
ellipse, a covariance that is not positive definite) must be reported as `<keyword>[...]` or
`<keyword>: ... row ...`, and `<keyword>` must be a parameter of the function: renaming an argument in
one layer only fails here.
"""

from __future__ import annotations

import inspect
import re
from typing import Any, Callable, Dict

import numpy as np
import pluecker
import pytest

K = np.array([[800.0, 0.0, 320.0], [0.0, 800.0, 240.0], [0.0, 0.0, 1.0]])
VIEWS = 4
TRACKS = 3
LOCAL = pluecker.TriangulationOptions(method="local")


def projections() -> np.ndarray:
    """Four views on an arc of radius 5 around the origin of the scene, 0.15 rad apart."""
    out = []
    for j in range(VIEWS):
        a = 0.15 * j
        R = np.array([[np.cos(a), 0.0, -np.sin(a)], [0.0, 1.0, 0.0], [np.sin(a), 0.0, np.cos(a)]])
        C = np.array([5.0 * np.sin(a), 0.0, 5.0 - 5.0 * np.cos(a)])
        out.append(K @ np.c_[R, -R @ C])
    return np.array(out)


def pixel(P: np.ndarray, X: np.ndarray) -> np.ndarray:
    h = P @ np.append(X, 1.0)
    return h[:2] / h[2]


P = projections()
POINT = np.array([[pixel(p, np.array([0.2, -0.1, 5.0])) for p in P]])
SEGMENT = np.array([[[pixel(p, np.array([-0.5, 0.3, 5.0])), pixel(p, np.array([0.6, -0.2, 6.0]))] for p in P]])
_T = np.eye(4)
_T[:3, 3] = [0.1, 0.0, 5.0]
_DUAL = _T @ np.linalg.inv(np.diag([1.0, 0.5, 0.8, -1.0])) @ _T.T
CONIC = np.array([[np.linalg.inv(p @ _DUAL @ p.T) for p in P]])

# One good track of each kind, its entries per view, and the identity covariance of one entry.
DATA = {"observations": (POINT, np.eye(2)), "lines": (SEGMENT, np.eye(2)), "conics": (CONIC, np.eye(5))}


def bad_entry(argument: str, value: np.ndarray) -> np.ndarray:
    """`value`, one entry of `argument`, made bad in a way the core itself rejects."""
    value = value.copy()
    if argument == "observations":
        value[:] = np.nan
    elif argument == "lines":
        value[1] = value[0]  # a zero-length segment
    elif argument == "conics":
        value[:] = np.diag([1.0, 1.0, 1.0])  # u² + v² + 1 = 0: no real point
    elif argument == "covariances":
        value[:] = -np.eye(len(value))  # not positive definite
    return value


def singular(p: np.ndarray) -> np.ndarray:
    """A projection whose left 3x3 block is singular (a camera at infinity)."""
    p = p.copy()
    p[:, :3] = 0.0
    p[2, 2] = 1.0
    return p


# (function, primitive argument, layout): "single" (n, ...), "dense" (tracks, views, ...) or "rows" (m, ...).
ENTRY_POINTS = [
    (pluecker.triangulate_point, "observations", "single"),
    (pluecker.triangulate_points, "observations", "dense"),
    (pluecker.triangulate_points, "observations", "rows"),
    (pluecker.triangulate_line, "lines", "single"),
    (pluecker.triangulate_lines, "lines", "dense"),
    (pluecker.triangulate_lines, "lines", "rows"),
    (pluecker.triangulate_quadric, "conics", "single"),
    (pluecker.triangulate_quadrics, "conics", "dense"),
    (pluecker.triangulate_quadrics, "conics", "rows"),
]

BAD_TRACK, BAD_VIEW = 1, 2  # the bad entry: track 1 (batches), view 2


def call(function: Callable[..., Any], primitive: str, layout: str, bad: str) -> str:
    """The error text of `function` given one bad entry in argument `bad`: the message raised, or the
    message of the rejected track of a batch."""
    entries, identity = DATA[primitive]
    kwargs: Dict[str, Any] = {"cameras": P.copy(), "options": LOCAL}
    if layout == "single":
        values = entries[0].copy()
        covariances = np.broadcast_to(identity, (VIEWS, *identity.shape)).copy()
        where: tuple = (BAD_VIEW,)
    else:
        values = np.repeat(entries, TRACKS, axis=0)
        covariances = np.broadcast_to(identity, (TRACKS, VIEWS, *identity.shape)).copy()
        where = (BAD_TRACK, BAD_VIEW)
        if layout == "rows":
            values = values.reshape(TRACKS * VIEWS, *values.shape[2:])
            covariances = covariances.reshape(TRACKS * VIEWS, *identity.shape)
            where = (BAD_TRACK * VIEWS + BAD_VIEW,)
            kwargs["track"] = np.repeat(np.arange(TRACKS), VIEWS)
            kwargs["image"] = np.tile(np.arange(VIEWS), TRACKS)
    if bad == "cameras":
        kwargs["cameras"][BAD_VIEW] = singular(P[BAD_VIEW])
    elif bad == "covariances":
        covariances[where] = bad_entry(bad, covariances[where])
    else:
        values[where] = bad_entry(bad, values[where])
    kwargs[primitive] = values
    kwargs["covariances"] = covariances
    try:
        result = function(**kwargs)
    except pluecker.PlueckerError as error:
        return str(error)
    rejected = [m for m in result.messages if m]
    assert len(rejected) == 1, rejected
    return rejected[0]


def named(message: str) -> str:
    """The argument a message names first, after the error kind and the track:
    `degenerate configuration: track 1: covariances[1][2] is ...` → `covariances`."""
    kinds = "degenerate configuration: |singular camera: "
    match = re.match(rf"(?:track \d+: )?(?:{kinds})?(?:track \d+: )?([a-z_]+)(?=[\[:])", message)
    assert match, message
    return match.group(1)


@pytest.mark.parametrize("function, primitive, layout", ENTRY_POINTS, ids=[f"{e[0].__name__}-{e[2]}" for e in ENTRY_POINTS])
@pytest.mark.parametrize("bad", ["cameras", "primitive", "covariances"])
def test_a_bad_row_is_named_by_the_python_keyword(function, primitive, layout, bad):
    argument = primitive if bad == "primitive" else bad
    assert argument in inspect.signature(function).parameters
    message = call(function, primitive, layout, argument)
    assert named(message) == argument, message
    # ...and the row: the view for shared projections, else the entry as the caller indexes it.
    if argument == "cameras" or layout == "single":
        row = rf"(\[{BAD_VIEW}\]|row {BAD_VIEW}\b)"
    elif layout == "dense":
        row = rf"(\[{BAD_TRACK}\]\[{BAD_VIEW}\]|\[{BAD_TRACK}\].* row {BAD_VIEW}\b)"
    else:  # the given row, or the track and its observation (the rows of one track in their order)
        k = BAD_TRACK * VIEWS + BAD_VIEW
        row = rf"(\[{k}\]|row {k}\b|\[{BAD_TRACK}\]\[{BAD_VIEW}\]|\[{BAD_TRACK}\].* row {BAD_VIEW}\b)"
    assert re.search(row, message), message


def test_lens_camera_covariances_keyword():
    """`Camera.undistort` and `normalized_covariances` take `covariances`, as triangulation does."""
    lens = pluecker.Camera("SIMPLE_RADIAL", [800.0, 320.0, 240.0, -0.1])
    pixels = np.array([[300.0, 200.0], [330.0, 250.0]])
    bad = np.array([np.eye(2), -np.eye(2)])
    for method in (lens.undistort, lens.normalized_covariances):
        assert "covariances" in inspect.signature(method).parameters
        with pytest.raises(pluecker.DegenerateConfigurationError, match=r"covariances\[1\] is not a covariance"):
            method(pixels, covariances=bad)
