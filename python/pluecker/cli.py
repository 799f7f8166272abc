"""The ``pluecker`` command line.

``pluecker pose INPUT.json [options]``
    Estimates a camera pose from the correspondences in a JSON file (``-`` reads standard input) and
    prints the result as JSON, as the core writes it (``PoseResult.to_json()``: the keys and values of
    ``PoseResult.to_dict()``, with the inlier masks and the covariance). The schema and
    every flag are documented in ``docs/cli.md`` (``tests/test_cli_docs.py`` keeps them in step).
``pluecker reproduce phong-horaud-1995``
    Re-runs the experiments of Phong, Horaud, Yassine & Tao 1995 (section 5) in simulation and writes
    tables, figures and a JSON summary.

``pluecker triangulate FOLDER``
    Triangulates every point (and with ``--lines`` every line) of a multi-view folder in the Oxford VGG
    format from the chosen views, and writes the 3-D features with their certificates as JSON and PLY.
``pluecker localize QUERIES POINTS --out DIR``
    Localises many query images from Parquet tables of 2D-3D matches (pinhole or COLMAP camera models,
    or a COLMAP model's cameras and point3D_ids with ``--colmap``), here or on a Dask cluster.
``pluecker reproduce josephson-kahl-2008``
    Re-runs the experiments of Josephson & Kahl 2008 (section 5) on the VGG data and synthetic conics.

Exit status: 0 on success, 2 on a usage or input error (one line on standard error, no traceback).
"""

from __future__ import annotations

import argparse
import json
import math
import os
import sys
import time
from pathlib import Path
from typing import Any, NoReturn, Sequence

import numpy as np

import pluecker
from pluecker import _ctrl_c, _paths
from pluecker._arguments import number
from pluecker.datasets import DataNotFoundError
from pluecker.jsonio import dumps

__all__ = ["main", "run"]

METHODS = tuple(pluecker.METHODS)
TRIANGULATION_METHODS = pluecker.TRIANGULATION_METHODS

#: ``pluecker triangulate --help``: the files ``pluecker.datasets.load_vgg`` reads, as it reads them.
TRIANGULATE_DESCRIPTION = """\
Triangulate every point seen in at least two of the chosen views (and with --lines every line) of a
folder in the Oxford VGG multi-view format (pluecker.datasets.load_vgg); write points.json / points.ply
(lines.json / lines.ply) with per-feature certificates to --out and print a summary. Formats: docs/cli.md.

Files of FOLDER (<prefix> is empty or a name ending in a dot, such as "house."; NNN are digits; the
views are the .P files in name order, numbered from 0):
  <prefix>NNN.P          required, one per view: the 3x4 camera matrix, world to pixels
  <prefix>NNN.corners    required for every view: its corners, one "x y" row each
  <prefix>NNN.lines      required for every view, also without --lines: its segments, "x0 y0 x1 y1" rows
  p3d or <prefix>p3d     required, may be empty: the folder's own 3-D points, "X Y Z" rows (read only to
                         detect a mirrored world frame, which is then made right-handed)
  l3d or <prefix>l3d     required, may be empty: the folder's own 3-D segments, "X1 Y1 Z1 X2 Y2 Z2" rows
  nview-corners or <prefix>nview-corners
                         optional (without it no point is triangulated): the point tracks, one row per
                         3-D point, one column per view holding a 0-based row of that view's .corners, or *
  nview-lines or <prefix>nview-lines
                         optional (without it no line is triangulated): the line tracks, likewise into
                         the .lines files
A missing required file, a malformed row or a track pointing past the end of a view's file is an
error: one line naming the file, exit status 2.
The summary counts tracks: "460 of 672 triangulated" means 460 of the 672 rows of nview-corners were
seen in at least two of the chosen views (the folder's p3d may have another number of rows)."""

#: ``pluecker localize --help``: the tables, as ``pluecker.distributed.localize_tables`` reads them.
LOCALIZE_DESCRIPTION = """\
One robust pose per query image (RANSAC with the minimal solvers, then the refinement on the inliers;
x_cam = R X_world + t) from Parquet tables (a file or a folder of files each). Writes --out/poses and
--out/matches as Parquet (pluecker.distributed.localize). Needs pyarrow; with --scheduler also Dask:
pip install 'pluecker[dask]'. Formats: docs/cli.md.

QUERIES: query (int64 id) and the camera, by one of these sets of columns:
  fx, fy, cx, cy         a pinhole camera, pixels u = K x_cam / z
  model, params          a COLMAP camera model (e.g. OPENCV) and its parameters in COLMAP's order (a list
                         of numbers); the pixels are the image's own, distorted ones
  camera_id              with --colmap: a camera of the model
  rig_id                 with --colmap: a frame of one of the model's rigs (the images of its cameras at
                         one instant, localised together: x_rig = R X_world + t)
POINTS: query, pixel x, y, and the world point X, Y, Z, or with --colmap its point3D_id in the model;
  for frames (rig_id) also camera_id, the camera of the rig whose image holds the keypoint.
LINES: query, segment x1, y1, x2, y2 (pixels), world segment X1, Y1, Z1, X2, Y2, Z2 (and camera_id for
  frames).
A query with a bad camera (unknown model, wrong params, a camera_id or point3D_id not in the model) or
bad matches gets status invalid_input and a message naming the query, the table and the column; the
other queries are solved as if it were not there."""

INPUT_KEYS = {"camera", "points2d", "points3d", "lines2d", "lines3d", "point_covariances", "line_covariances",
              "method", "options", "ransac"}
#: Optional per-observation covariances, pixels², passed to ``estimate_pose`` as they are.
COVARIANCES = ("point_covariances", "line_covariances")
#: Command-line flag (``args`` attribute) → field of ``PoseOptions``; a flag given wins over the file.
POSE_FLAGS = {"refine": "refine", "penalty": "penalty", "sigma": "sigma_px", "certify": "certify"}
#: Command-line flag (``args`` attribute) → field of ``RansacOptions``; a flag given wins over the file
#: (and makes the estimate robust).
RANSAC_FLAGS = {"point_threshold": "point_threshold", "line_threshold": "line_threshold", "seed": "seed",
                "time_budget": "time_budget"}
#: Command-line flag (``args`` attribute) → field of ``RansacOptions`` for ``pluecker localize``.
LOCALIZE_RANSAC_FLAGS = {"point_threshold": "point_threshold", "line_threshold": "line_threshold",
                         "confidence": "confidence", "max_iterations": "max_iterations",
                         "min_inliers": "min_inliers", "time_budget": "time_budget"}
#: Array key → trailing shape of one row.
ARRAYS = {"points2d": (2,), "points3d": (3,), "lines2d": (2, 2), "lines3d": (2, 3)}


class InputError(Exception):
    """Bad input, reported as one line and exit status 2."""


class _Parser(argparse.ArgumentParser):
    """argparse with a one-line usage error (the subcommand parsers inherit it)."""

    def error(self, message: str) -> NoReturn:
        self.exit(2, f"{self.prog}: error: {message} (see '{self.prog} --help')\n")


def _positive_int(text: str) -> int:
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a positive integer, got '{text}'") from None
    if value < 1:
        raise argparse.ArgumentTypeError(f"expected a positive integer, got {value}")
    return value


def _non_negative_int(text: str) -> int:
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a non-negative integer, got '{text}'") from None
    if value < 0:
        raise argparse.ArgumentTypeError(f"expected a non-negative integer, got {value}")
    return value


def _positive_float(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a positive number, got '{text}'") from None
    if not (math.isfinite(value) and value > 0):
        raise argparse.ArgumentTypeError(f"expected a positive number, got {text}")
    return value


def _probability(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number in (0, 1), got '{text}'") from None
    if not 0 < value < 1:
        raise argparse.ArgumentTypeError(f"expected a number in (0, 1), got {text}")
    return value


def _view_list(text: str) -> list[int]:
    try:
        views = [int(v) for v in text.split(",")]
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected comma-separated view numbers such as 0,1,2,3, got '{text}'") from None
    if any(v < 0 for v in views):
        raise argparse.ArgumentTypeError(f"view numbers are 0-based and non-negative, got '{text}'")
    if len(set(views)) != len(views):
        raise argparse.ArgumentTypeError(f"a view is listed twice in '{text}'")
    if len(views) < 2:
        raise argparse.ArgumentTypeError(f"triangulation needs at least 2 views, got '{text}'")
    return views


def build_parser() -> argparse.ArgumentParser:
    from pluecker.experiments import EXPERIMENTS

    parser = _Parser(prog="pluecker", description="Camera pose from 2-D/3-D point and line correspondences "
                     "(Phong, Horaud, Yassine & Tao 1995) and triangulation of points, lines and conics "
                     "(Josephson & Kahl 2008).")
    parser.add_argument("--version", action="version",
                        version=f"pluecker {getattr(pluecker, '__version__', 'unknown')}")
    commands = parser.add_subparsers(dest="command", metavar="COMMAND")

    pose = commands.add_parser("pose", help="estimate a pose from a JSON file of correspondences",
                               description="Estimate a camera pose; prints PoseResult.to_dict() as JSON. "
                               "Input schema: docs/cli.md.")
    pose.add_argument("input", metavar="INPUT", help="JSON file of correspondences, or '-' for standard input")
    pose.add_argument("-o", "--output", metavar="OUT", help="write the result here instead of standard output")
    pose.add_argument("--method", choices=METHODS, help="estimator (overrides the file's \"method\"; "
                      "default trust-region)")
    pose.add_argument("--no-refine", dest="refine", action="store_false", default=None,
                      help="skip the reprojection refinement: the paper's estimator alone")
    pose.add_argument("--penalty", type=_positive_float, metavar="L",
                      help="penalty λ on the unit and orthogonality constraints (default 50)")
    pose.add_argument("--robust", action="store_true", default=None,
                      help="robust to outliers: LO-RANSAC over points and lines, then the refinement on the "
                      "inliers (reported by the output's inliers_points, inliers_lines and details.ransac keys)")
    pose.add_argument("--point-threshold", type=_positive_float, metavar="PX",
                      help="inlier threshold of a point, reprojection distance in pixels (default 4)")
    pose.add_argument("--line-threshold", type=_positive_float, metavar="PX",
                      help="inlier threshold of a line, RMS distance of its endpoints to the projected line in "
                      "pixels (default 4)")
    pose.add_argument("--seed", type=_non_negative_int, metavar="N", help="seed of the RANSAC sampler (default 0)")
    pose.add_argument("--time-budget", type=_positive_float, metavar="S",
                      help="wall-time budget of the RANSAC loop, seconds (default none: the iteration cap bounds it)")
    pose.add_argument("--sigma", type=_positive_float, metavar="PX",
                      help="pixel noise σ for the covariance and the χ² residual test (default: σ estimated "
                      "from the residuals, no test)")
    pose.add_argument("--certify", action="store_true", default=None,
                      help="prove the answer is the global minimum of the reprojection error (the output's "
                      "certificate; status gap_not_closed when it does not hold; costs extra time, see "
                      "bench/README.md)")
    pose.set_defaults(handler=_pose)

    tri = commands.add_parser(
        "triangulate", help="triangulate the points (and lines) of a multi-view folder in the VGG format",
        formatter_class=argparse.RawDescriptionHelpFormatter, description=TRIANGULATE_DESCRIPTION)
    tri.add_argument("folder", metavar="FOLDER", type=Path, nargs="?",
                     help="a folder in the Oxford VGG multi-view format (its files: see above)")
    tri.add_argument("--colmap", metavar="DIR", type=Path,
                     help="instead of FOLDER: a COLMAP model (cameras, images, points3D; text or binary, rigs "
                     "included; needs pycolmap: pip install 'pluecker[colmap]'). Every track is re-triangulated "
                     "with the cameras fixed, through their models; --out gets the COLMAP model, points3D.ply and "
                     "points3D_triangulation.npz (covariances, certificates, inlier flags)")
    tri.add_argument("--outlier-threshold", type=_positive_float, metavar="PX", dest="outlier_threshold",
                     help="with --colmap: reject observations farther than PX pixels from their track's consensus "
                     "(default: keep every observation)")
    tri.add_argument("--text", action="store_true", help="with --colmap: write the model as text (default binary)")
    tri.add_argument("--views", type=_view_list, metavar="I,J,...", help="0-based views to use, comma-separated "
                     "(default: all)")
    tri.add_argument("--method", choices=TRIANGULATION_METHODS, default="optimal",
                     help="estimator (default optimal: certified global minimum of eq. 19)")
    tri.add_argument("--lines", action="store_true", help="also triangulate the lines (from the segments)")
    tri.add_argument("--sigma", type=_positive_float, default=1.0, metavar="PX",
                     help="pixel noise of the segment endpoints, for the line covariances, and with --colmap of "
                     "every observation (default 1)")
    tri.add_argument("--out", metavar="DIR", type=Path, help="output directory (default "
                     "results/triangulate/NAME)")
    tri.add_argument("--scheduler", metavar="ADDRESS",
                     help="with --colmap: run on the Dask cluster of this scheduler (e.g. tcp://host:8786; needs "
                     "pip install 'pluecker[dask]'); --out must be storage every worker sees. Without it the job "
                     "runs here, without Dask")
    tri.set_defaults(handler=_triangulate)

    loc = commands.add_parser(
        "localize", help="localise many query images from their 2D-3D matches (Parquet tables)",
        formatter_class=argparse.RawDescriptionHelpFormatter, description=LOCALIZE_DESCRIPTION)
    loc.add_argument("queries", metavar="QUERIES", type=Path, help="Parquet file or folder of the queries")
    loc.add_argument("points", metavar="POINTS", type=Path, help="Parquet file or folder of the point matches")
    loc.add_argument("--lines", metavar="LINES", type=Path, help="Parquet file or folder of the line matches")
    loc.add_argument("--colmap", metavar="DIR", type=Path,
                     help="a COLMAP model (text or binary; needs pycolmap: pip install 'pluecker[colmap]'): POINTS "
                     "give point3D_id instead of X, Y, Z and QUERIES may give a camera_id of the model")
    loc.add_argument("--out", metavar="DIR", type=Path, required=True, help="output directory")
    loc.add_argument("--scheduler", metavar="ADDRESS", help="run on the Dask cluster of this scheduler")
    loc.add_argument("--seed", type=_non_negative_int, default=0, metavar="N",
                     help="RANSAC seed (query q uses N + q; default 0)")
    loc.add_argument("--point-threshold", type=_positive_float, metavar="PX",
                     help="inlier threshold of a point, reprojection distance in the image's own (distorted) "
                     "pixels (default 4)")
    loc.add_argument("--line-threshold", type=_positive_float, metavar="PX",
                     help="inlier threshold of a line, RMS distance of its endpoints to the projected line in "
                     "pixels (default 4)")
    loc.add_argument("--confidence", type=_probability, metavar="P",
                     help="probability of having drawn an all-inlier sample when sampling stops (default 0.9999)")
    loc.add_argument("--max-iterations", type=_positive_int, metavar="N",
                     help="cap on the RANSAC samples per query (default 100000)")
    loc.add_argument("--min-inliers", type=_positive_int, metavar="N",
                     help="fewest inliers of a usable pose, at least 3 (default 6)")
    loc.add_argument("--time-budget", type=_positive_float, metavar="S",
                     help="wall-time budget of each query's RANSAC loop, seconds (default none: the iteration cap "
                     "bounds it)")
    loc.set_defaults(handler=_localize)

    rep = commands.add_parser(
        "reproduce", help="re-run a paper's experiments",
        description="Re-run the experiments of section 5 of a paper: phong-horaud-1995 in simulation, "
        "josephson-kahl-2008 on the shipped VGG data and synthetic conics. Writes tables.md, summary.json and "
        "PNG figures to --out. The figures need matplotlib (pip install pluecker[plots]); without it the "
        "tables and summary.json are still written, with a warning. Details: docs/cli.md.")
    rep.add_argument("name", choices=sorted(EXPERIMENTS), help="experiment")
    rep.add_argument("--out", metavar="DIR", type=Path, help="output directory (default results/NAME)")
    rep.add_argument("--trials", type=_positive_int, metavar="N",
                     help="phong-horaud-1995: random draws averaged in every table cell (default 100, 10 with "
                     "--quick); josephson-kahl-2008: synthetic disc scenes of Table 3 (default 30, 3 with --quick; "
                     "the real-data tables have no random draws)")
    rep.add_argument("--seed", type=_non_negative_int, default=0, metavar="S",
                     help="random seed (default 0): phong-horaud-1995: of every draw; josephson-kahl-2008: of the "
                     "synthetic discs and the fitting draws of Figures 1-2")
    rep.add_argument("--quick", action="store_true",
                     help="a reduced run: phong-horaud-1995: 3 values per sweep and 10 trials; josephson-kahl-2008: "
                     "3 discs, 2,000 fitting draws instead of 100,000 and the first 6 lines of each sequence")
    rep.add_argument("--quiet", action="store_true", help="no progress bar (the final lines are still printed)")
    rep.set_defaults(handler=_reproduce)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Runs the command line with ``argv`` (default ``sys.argv[1:]``); returns the exit status."""
    parser = build_parser()
    try:
        args = parser.parse_args(argv)
    except SystemExit as exit_:  # usage errors (2) and --help / --version (0)
        return exit_.code if isinstance(exit_.code, int) else 2
    if args.command is None:
        parser.print_help(sys.stderr)
        return 2
    deadline = _ctrl_c.arm(args.command) if _ARM_EXIT_DEADLINE else None
    try:
        return args.handler(args)
    except BaseException as exc:  # Ctrl-C: one line and the shell's convention, 128 + SIGINT
        if not _ctrl_c.caused_by_ctrl_c(exc):
            raise
        if deadline is not None:
            deadline.stand_down()  # the line is printed here, not by the deadline
        print(f"pluecker {args.command}: interrupted", file=sys.stderr)
        return 130
    finally:
        if deadline is not None:
            deadline.close()


#: Set by :func:`run`: :func:`main` arms the Ctrl-C deadline of :mod:`pluecker._ctrl_c`.
_ARM_EXIT_DEADLINE = False


def run() -> NoReturn:
    """The ``pluecker`` program: :func:`main` on ``sys.argv``, with Ctrl-C answered within 0.05 s even
    while a library call holds the interpreter (:mod:`pluecker._ctrl_c`), and the process ended
    at once after the ``interrupted`` line, without the interpreter's teardown."""
    global _ARM_EXIT_DEADLINE
    _ARM_EXIT_DEADLINE = True
    status = main()
    if status == 130:
        sys.stdout.flush()
        sys.stderr.flush()
        os._exit(130)
    sys.exit(status)


def _fail(command: str, message: str) -> int:
    print(f"pluecker {command}: error: {message}", file=sys.stderr)
    return 2


def _check_output(flag: str, out: str | Path, inputs: dict[str, Any], replaced: Sequence[str] = (),
                  folder: bool = True) -> None:
    """An ``InputError`` before any work when the output ``out`` (given as ``flag``) would overwrite,
    replace or write into an input (:func:`pluecker._paths.output_conflict`: symlinks, ``.`` and ``..``
    resolved), or cannot be written (:func:`pluecker._paths.output_problem`); nothing is made."""
    if (conflict := _paths.output_conflict(out, inputs, replaced)) is not None:
        raise InputError(f"{flag} {conflict}: give another {'folder' if folder else 'file'} (the inputs are never "
                         "overwritten)")
    if (problem := _paths.output_problem(out, folder=folder)) is not None:
        raise InputError(f"cannot write {flag} {out}: {problem}")


# --------------------------------------------------------------------------------------------------
# pose


def _read_document(source: str) -> dict[str, Any]:
    name = "standard input" if source == "-" else source
    try:
        text = sys.stdin.read() if source == "-" else Path(source).read_text(encoding="utf-8")
    except FileNotFoundError:
        raise InputError(f"{name}: no such file") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise InputError(f"cannot read {name}: {exc}") from None
    try:
        doc = json.loads(text)
    except RecursionError:
        raise InputError(f"{name}: the JSON is nested too deeply to parse") from None
    except ValueError as exc:  # JSONDecodeError, or an integer beyond Python's digit limit
        raise InputError(f"{name} is not valid JSON: {exc}") from None
    if not isinstance(doc, dict):
        raise InputError(f"{name}: expected a JSON object at the top level, got {type(doc).__name__}")
    unknown = sorted(set(doc) - INPUT_KEYS)
    if unknown:
        raise InputError(f"{name}: unknown key(s) {', '.join(map(repr, unknown))}; "
                         f"expected {', '.join(sorted(INPUT_KEYS))}")
    return doc


def _first_non_number(value: Any, what: str) -> tuple[str, Any] | None:
    """The path (``points2d[0][1]``) and value of the first leaf of the nested lists ``value`` that is
    not a JSON number: ``true`` / ``false`` and numeric strings are refused, never coerced to 1.0 / 0.0
    or parsed."""
    stack: list[tuple[Any, str]] = [(value, what)]
    while stack:
        item, path = stack.pop()
        if isinstance(item, list):
            stack.extend((item[i], f"{path}[{i}]") for i in reversed(range(len(item))))
        elif isinstance(item, bool) or not isinstance(item, (int, float)):
            return path, item
    return None


def _number_array(value: Any, what: str) -> np.ndarray:
    """A (nested) list of JSON numbers as a float array; an ``InputError`` naming the first entry that
    is not a number (a bool, a string, null, an object)."""
    if (bad := _first_non_number(value, what)) is not None:
        path, item = bad
        try:
            shown = json.dumps(item)[:80]
        except RecursionError:
            shown = "a deeply nested value"
        raise InputError(f"'{path}' must be a number, got {shown}")
    try:
        array = np.asarray(value, dtype=float)
    except (TypeError, ValueError, RecursionError):
        raise InputError(f"'{what}' must be a (nested) list of numbers of equal lengths") from None
    except OverflowError:
        raise InputError(f"'{what}' holds an integer too large for a float (beyond 1.8e308)") from None
    return array


def _number(value: Any, what: str) -> float:
    """A JSON number as a float; bools and numbers beyond the float range are input errors."""
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise InputError(f"'{what}' must be a number, got {json.dumps(value)[:80]}")
    try:
        return float(value)
    except OverflowError:
        raise InputError(f"'{what}' is an integer too large for a float (beyond 1.8e308)") from None


def _model_camera(spec: dict[str, Any]) -> pluecker.Camera:
    """``{"model": COLMAP name, "params": [...]}``: a camera with distortion (``pluecker.Camera``)."""
    if set(spec) != {"model", "params"}:
        raise InputError("'camera' with 'model' takes exactly {\"model\": name, \"params\": [...]}, got keys "
                         + ", ".join(sorted(spec)))
    model, params = spec["model"], spec["params"]
    if model not in pluecker.Camera.MODELS:
        raise InputError(f"'camera.model' {json.dumps(model)[:40]} is not one of {', '.join(pluecker.Camera.MODELS)}")
    if not isinstance(params, list):
        raise InputError("'camera.params' must be a list of numbers in COLMAP's order")
    values = [_number(v, f"camera.params[{i}]") for i, v in enumerate(params)]
    return pluecker.Camera(model, values)


def _camera(doc: dict[str, Any]) -> pluecker.Camera:
    spec = doc.get("camera")
    if not isinstance(spec, dict):
        raise InputError("'camera' is required: {\"fx\", \"fy\", \"cx\", \"cy\", \"skew\"?}, {\"K\": 3x3} or "
                         "{\"model\": COLMAP model, \"params\": [...]}")
    if "model" in spec:
        return _model_camera(spec)
    if "K" in spec:
        if set(spec) != {"K"}:
            raise InputError("'camera' has 'K' and other keys; give either K or fx, fy, cx, cy, skew")
        K = _number_array(spec["K"], "camera.K")
        if K.shape != (3, 3):
            raise InputError(f"'camera.K' must be 3x3, got shape {K.shape}")
        return pluecker.Camera.from_matrix(K)
    required, allowed = {"fx", "fy", "cx", "cy"}, {"fx", "fy", "cx", "cy", "skew"}
    if missing := sorted(required - set(spec)):
        raise InputError(f"'camera' lacks {', '.join(missing)} (or give \"K\", or \"model\" and \"params\")")
    if unknown := sorted(set(spec) - allowed):
        raise InputError(f"'camera' has unknown key(s) {', '.join(unknown)}")
    values = {key: _number(value, f"camera.{key}") for key, value in spec.items()}
    return pluecker.Camera.pinhole(values["fx"], values["fy"], values["cx"], values["cy"], skew=values.get("skew", 0.0))


def _correspondences(doc: dict[str, Any]) -> dict[str, np.ndarray]:
    arrays = {}
    for key, row_shape in ARRAYS.items():
        value = doc.get(key)
        if value is None or (isinstance(value, list) and not value):
            continue
        array = _number_array(value, key)
        if array.ndim != 1 + len(row_shape) or array.shape[1:] != row_shape:
            expected = "(N, " + ", ".join(map(str, row_shape)) + ")"
            raise InputError(f"'{key}' must have shape {expected}, got {array.shape}")
        arrays[key] = array
    if not arrays:
        raise InputError("no correspondences: give points2d + points3d and/or lines2d + lines3d")
    for key in COVARIANCES:
        if doc.get(key) is not None:
            arrays[key] = _number_array(doc[key], key)
    return arrays


def _initial_pose(value: dict[str, Any]) -> tuple[np.ndarray, np.ndarray]:
    if not isinstance(value, dict) or set(value) != {"R", "t"}:
        raise InputError("option 'initial_pose' must be {\"R\": 3x3, \"t\": [x, y, z]}")
    R, t = _number_array(value["R"], "initial_pose.R"), _number_array(value["t"], "initial_pose.t")
    if R.shape != (3, 3) or t.shape != (3,):
        raise InputError(f"option 'initial_pose': R must be 3x3 and t of length 3, got {R.shape} and {t.shape}")
    return R, t


def _object(doc: dict[str, Any], key: str) -> dict[str, Any]:
    value = doc.get(key) or {}
    if not isinstance(value, dict):
        raise InputError(f"'{key}' must be a JSON object")
    return dict(value)


def _options_class(cls: type, key: str, fields: dict[str, Any]) -> Any:
    """``cls(**fields)`` with its TypeError (unknown key, wrong type) as an ``InputError`` naming ``key``."""
    try:
        return cls(**fields)
    except TypeError as exc:
        raise InputError(f"'{key}': {exc}") from None


def _options(doc: dict[str, Any], args: argparse.Namespace) -> dict[str, Any]:
    """The keywords of ``estimate_pose``: ``options``, the ``PoseOptions`` from the file's ``"options"``
    object, its top-level ``"method"`` and ``"ransac"`` (``true`` or an object of ``RansacOptions``
    fields), and the flags. ``"certify"`` in ``"options"`` is ``true``/``false`` or an object of
    ``CertifyOptions`` fields. The file's options are checked first, as they are: a flag then overrides
    a valid setting but never hides an invalid one (``--certify`` turns the certificate on and keeps the
    file's ``certify`` settings, such as its ``max_nodes``)."""
    fields = _object(doc, "options")
    if "initial_pose" in fields:
        fields["initial_pose"] = _initial_pose(fields["initial_pose"])
    certify = fields.get("certify")
    if not isinstance(certify, (bool, dict, type(None))):
        raise InputError(f"'options.certify' must be true, false or a JSON object, got {json.dumps(certify)[:80]}")
    if isinstance(certify, bool):
        fields["certify"] = {} if certify else None
    if isinstance(fields.get("certify"), dict):
        fields["certify"] = _options_class(pluecker.CertifyOptions, "options.certify", fields["certify"])
    robust = doc.get("ransac", fields.pop("ransac", None))
    if not isinstance(robust, (bool, dict, type(None))):
        raise InputError(f"'ransac' must be true, false or a JSON object, got {json.dumps(robust)[:80]}")
    ransac_fields = dict(robust) if isinstance(robust, dict) else {}
    if robust:
        fields["ransac"] = _options_class(pluecker.RansacOptions, "ransac", ransac_fields)
    method = doc.get("method") or fields.get("method")
    for given in (method, args.method):
        if given is not None and given not in METHODS:
            raise InputError(f"unknown method {json.dumps(given)}; expected one of {', '.join(METHODS)}")
    if method is not None:
        fields["method"] = method
    options = _options_class(pluecker.PoseOptions, "options", fields)
    # The flags, over the file's checked options.
    for flag, field in POSE_FLAGS.items():
        if getattr(args, flag) is not None and field != "certify":
            setattr(options, field, getattr(args, flag))
    if args.certify and options.certify is None:
        options.certify = pluecker.CertifyOptions()
    flagged = {field: getattr(args, flag) for flag, field in RANSAC_FLAGS.items() if getattr(args, flag) is not None}
    if flagged or args.robust:
        options.ransac = _options_class(pluecker.RansacOptions, "ransac", {**ransac_fields, **flagged})
    if args.method is not None:
        options.method = args.method
    return {"options": options}


def _pose(args: argparse.Namespace) -> int:
    try:
        if args.output:
            _check_output("-o", args.output, {"INPUT": None if args.input == "-" else args.input}, folder=False)
        doc = _read_document(args.input)
        camera = _camera(doc)
        arrays = _correspondences(doc)
        kwargs = _options(doc, args)
        result = pluecker.estimate_pose(camera, **arrays, **kwargs)
    except (InputError, pluecker.PlueckerError) as exc:
        return _fail("pose", str(exc))
    # The core's JSON of the result (serde), laid out one key per line with every array on one line.
    text = dumps(json.loads(result.to_json())) + "\n"
    if args.output:
        try:
            _paths.write_text(args.output, text)
        except OSError as exc:
            return _fail("pose", f"cannot write {args.output}: {exc.strerror or exc}")
    else:
        sys.stdout.write(text)
    if result.status != "success":
        print(f"pluecker pose: warning: status {result.status} (termination {result.termination}); "
              "the pose may be unusable", file=sys.stderr)
    return 0


# --------------------------------------------------------------------------------------------------
# triangulate


def _client(command: str, address: str) -> Any:
    """A Dask client of the scheduler at ``address`` (an error line when Dask is missing or unreachable). It
    waits for the scheduler as Dask's configuration says (``distributed.comm.timeouts.connect``, 30 s unless
    set, e.g. ``DASK_DISTRIBUTED__COMM__TIMEOUTS__CONNECT=5s``)."""
    try:
        from distributed import Client
    except ImportError:
        raise InputError("--scheduler needs Dask: pip install 'pluecker[dask]'") from None
    try:
        return Client(address)
    except (OSError, TimeoutError) as exc:
        raise InputError(f"cannot reach the Dask scheduler at {address}: {exc}") from None


def _triangulate_colmap_on_dask(args: argparse.Namespace, reconstruction: Any) -> Any:
    """``--colmap --scheduler``: the observations to Parquet in a scratch folder beside --out, the job on
    the cluster (pluecker.distributed.triangulate), the tables back as a ``Retriangulation`` (written as
    without Dask). Returns it and the summary line."""
    import pyarrow.parquet as pq

    from pluecker import colmap, distributed

    client = _client("triangulate", args.scheduler)
    # Scratch space on the storage of --out (the workers see it), removed whatever happens.
    with client, _paths.staged(args.out, publish=False) as scratch:
        job = scratch.path
        skipped: list = []
        cameras, table = colmap.observation_table(reconstruction, args.sigma, skipped=skipped)
        (job / "input").mkdir()
        pq.write_table(table, job / "input" / "observations.parquet", row_group_size=1_000_000)
        options = pluecker.TriangulationOptions(method=args.method)
        if args.outlier_threshold is not None:
            options.outlier_threshold = args.outlier_threshold / args.sigma
        summary = distributed.triangulate(job / "input" / "observations.parquet", cameras, job / "output",
                                          client=client, options=options, progress=sys.stderr.isatty())
        run = colmap.retriangulation_of_job(distributed.read_points(job / "output"),
                                            distributed.read_observations(job / "output"), skipped)
    line = (f"{args.colmap}: {summary.tracks} points on {summary.workers} Dask workers in {summary.seconds:.1f} s, "
            f"{summary.statuses.get('success', 0)} triangulated, {summary.certified} certified ({args.method})")
    return run, line


def _read_model(flag: str, path: Path) -> Any:
    """The COLMAP model of ``flag`` (``--colmap``) as a ``pycolmap.Reconstruction``: an ``InputError``
    naming what is missing or broken (:func:`pluecker.colmap.read`), or that pycolmap is missing."""
    from pluecker import colmap

    try:
        return colmap.read(path)
    except ImportError as exc:
        raise InputError(str(exc)) from None
    except OSError as exc:
        raise InputError(f"{flag} {exc}") from None
    except colmap.ModelError as exc:
        raise InputError(f"{flag} {exc}") from None


def _localize(args: argparse.Namespace) -> int:
    """``pluecker localize QUERIES POINTS --out DIR [--colmap DIR] [--lines L] [--scheduler ADDRESS]
    [RANSAC flags]``."""
    try:
        from pluecker import colmap, distributed

        distributed._pyarrow()
    except ImportError as exc:
        return _fail("localize", str(exc))
    for flag, path in (("QUERIES", args.queries), ("POINTS", args.points), ("--lines", args.lines)):
        if path is not None and not path.exists():
            return _fail("localize", f"{flag} {path}: no such file or directory")
    if args.colmap is not None and (problem := _paths.folder_problem(args.colmap)) is not None:
        return _fail("localize", f"--colmap {args.colmap}: {problem}")
    fields = {field: getattr(args, flag) for flag, field in LOCALIZE_RANSAC_FLAGS.items()
              if getattr(args, flag) is not None}
    try:
        _check_output("--out", args.out, {"QUERIES": args.queries, "POINTS": args.points, "--lines": args.lines,
                                          "--colmap": args.colmap}, replaced=("poses", "matches"))
        ransac = pluecker.RansacOptions(**fields)
        model = None
        if args.colmap is not None:
            model = colmap.ColmapModel.from_reconstruction(_read_model("--colmap", args.colmap))
    except (InputError, pluecker.PlueckerError) as exc:
        return _fail("localize", str(exc))
    client = None
    if args.scheduler is not None:
        try:
            client = _client("localize", args.scheduler)
        except InputError as exc:
            return _fail("localize", str(exc))
    try:
        summary = distributed.localize(args.queries, args.points, args.out, line_matches=args.lines, client=client,
                                       seed=args.seed, ransac=ransac, reconstruction=model,
                                       progress=client is not None and sys.stderr.isatty())
    except pluecker.PlueckerError as exc:  # a table without its columns, of the wrong types, a query twice
        return _fail("localize", str(exc))
    except (KeyError, ValueError, OSError) as exc:
        return _fail("localize", f"cannot read the tables: {exc}")
    finally:
        if client is not None:
            client.close()
    where = f"{summary.workers} Dask workers" if client is not None else "this machine"
    lines = [f"{summary.tracks} queries on {where} in {summary.seconds:.1f} s: "
             + ", ".join(f"{n} {s}" for s, n in sorted(summary.statuses.items()))]
    if any(s != "success" for s in summary.statuses):
        poses = distributed.read_poses(args.out)
        failed = [(q, s, m) for q, s, m in zip(poses.column("query").to_pylist(), poses.column("status").to_pylist(),
                                               poses.column("message").to_pylist()) if s != "success"]
        lines.append("not localised: " + "; ".join(f"{s}: {m or f'query {q}'}" for q, s, m in failed[:3])
                     + ("; …" if len(failed) > 3 else ""))
    lines.append(f"wrote {args.out}/poses and {args.out}/matches")
    print("\n".join(lines))
    return 0


#: The files ``pluecker triangulate --colmap`` writes into --out (either format of the model).
COLMAP_OUTPUT_FILES = tuple(f"{name}.{ext}" for name in ("rigs", "cameras", "frames", "images", "points3D")
                            for ext in ("bin", "txt")) + ("points3D.ply", "points3D_triangulation.npz")
#: The files ``pluecker triangulate FOLDER`` writes into --out.
VGG_OUTPUT_FILES = ("points.json", "points.ply", "lines.json", "lines.ply")


def _triangulate_colmap(args: argparse.Namespace) -> int:
    """``pluecker triangulate --colmap DIR --out DIR``: re-triangulate every track of a COLMAP model."""
    from tqdm import tqdm

    from pluecker import colmap

    if args.out is None:
        return _fail("triangulate", "--colmap needs --out DIR (the model is written there, never over the input)")
    if args.lines or args.views:
        return _fail("triangulate", "--lines and --views apply to VGG folders, not to --colmap")
    try:
        colmap._pycolmap()
    except ImportError as exc:
        return _fail("triangulate", str(exc))
    if (problem := _paths.folder_problem(args.colmap)) is not None:
        return _fail("triangulate", f"--colmap {args.colmap}: {problem}")
    try:
        _check_output("--out", args.out, {"--colmap": args.colmap}, replaced=COLMAP_OUTPUT_FILES)
        reconstruction = _read_model("--colmap", args.colmap)
    except InputError as exc:
        return _fail("triangulate", str(exc))
    if reconstruction.num_points3D() == 0:
        return _fail("triangulate", f"{args.colmap}: the model has no 3-D points to re-triangulate")
    started = time.perf_counter()
    try:
        if args.scheduler is not None:
            run, first = _triangulate_colmap_on_dask(args, reconstruction)
        else:
            # A bar on a terminal only (tqdm's disable=None); the summary line below goes to logs too.
            with tqdm(total=reconstruction.num_points3D(), desc="points", unit="pt", disable=None,
                      leave=False) as bar:
                report = (lambda done: bar.update(done - bar.n)) if not bar.disable else None
                run = colmap.retriangulate(reconstruction, sigma_px=args.sigma,
                                           options=pluecker.TriangulationOptions(method=args.method),
                                           outlier_threshold_px=args.outlier_threshold, progress=report)
            print(f"points: {len(run.point3D_ids)} in {time.perf_counter() - started:.1f} s", file=sys.stderr)
            status = np.asarray(run.result.status)
            first = (f"{args.colmap}: {len(status)} points, {int((status == 'success').sum())} triangulated, "
                     f"{int(np.sum(run.result.certified))} certified ({args.method})")
    except (InputError, pluecker.PlueckerError) as exc:
        return _fail("triangulate", str(exc))
    stale = colmap.stale_model_files(args.out, args.text)
    try:
        files = colmap.write(reconstruction, run, args.out, text=args.text)
    except OSError as exc:
        return _fail("triangulate", f"cannot write to {args.out}: {exc.strerror or exc}")
    result = run.result
    status = np.asarray(result.status)
    lines = [first]
    if run.skipped:
        lines.append(f"left out: {len(run.skipped)} (" + "; ".join(run.skipped[:3])
                     + ("; …" if len(run.skipped) > 3 else "") + ")")
    if result.inliers is not None:
        lines.append(f"observations: {int(colmap.removed_observations(run).sum())} of {len(result.inliers)} "
                     f"removed as outliers (threshold {number(args.outlier_threshold)} px)")
    others = {s: run.point3D_ids[status == s] for s in sorted(set(status)) if s != "success"}
    if others:
        lines.append("not updated: " + "; ".join(
            f"{len(ids)} {s} (point3D_id {', '.join(map(str, ids[:5]))}{', …' if len(ids) > 5 else ''})"
            for s, ids in others.items()))
    lines.append(f"wrote {len(files)} files to {args.out}: " + ", ".join(f.name for f in files))
    if stale:
        lines.append(f"removed the {'binary' if args.text else 'text'} model of an earlier run from {args.out}: "
                     + ", ".join(f.name for f in stale))
    print("\n".join(lines))
    return 0


def _triangulate(args: argparse.Namespace) -> int:
    from pluecker import triangulate_folder

    if args.scheduler is not None and args.colmap is None:
        return _fail("triangulate", "--scheduler applies to --colmap models (VGG folders run here)")
    if args.colmap is not None:
        if args.folder is not None:
            return _fail("triangulate", "give either FOLDER or --colmap DIR, not both")
        return _triangulate_colmap(args)
    if args.folder is None:
        return _fail("triangulate", "give a VGG FOLDER or --colmap DIR")
    for given, flag in ((args.outlier_threshold is not None, "--outlier-threshold"), (args.text, "--text")):
        if given:
            return _fail("triangulate", f"{flag} applies to --colmap models, not to VGG folders")

    try:
        if args.out is not None and _paths.folder_problem(args.folder) is None:
            _check_output("--out", args.out, {"FOLDER": args.folder}, replaced=VGG_OUTPUT_FILES)
        options = pluecker.TriangulationOptions(method=args.method)
        run = triangulate_folder.run(args.folder, views=args.views, options=options, lines=args.lines,
                                     sigma=args.sigma)
        out = args.out if args.out is not None else Path("results") / "triangulate" / run.name
        if args.out is None:  # the default, named after the sequence once it is read
            _check_output("--out", out, {"FOLDER": args.folder}, replaced=VGG_OUTPUT_FILES)
    except (InputError, pluecker.PlueckerError, triangulate_folder.FolderError) as exc:
        return _fail("triangulate", str(exc))
    try:
        files = triangulate_folder.write(run, out)
    except OSError as exc:
        return _fail("triangulate", f"cannot write to {out}: {exc.strerror or exc}")
    print("\n".join(triangulate_folder.summary_lines(run, files)))
    return 0


# --------------------------------------------------------------------------------------------------
# reproduce


def _reproduce(args: argparse.Namespace) -> int:
    from pluecker import experiments

    module = experiments.load(args.name)
    out = args.out if args.out is not None else module.DEFAULT_OUT
    try:
        _check_output("--out", out, {})
    except InputError as exc:
        return _fail("reproduce", str(exc))
    try:
        import matplotlib  # noqa: F401
        plots = True
    except ImportError:
        plots = False
        print("pluecker reproduce: warning: matplotlib is not installed; writing tables without figures "
              "(pip install pluecker[plots] provides it)", file=sys.stderr)
    try:
        report = module.reproduce(out, trials=args.trials, seed=args.seed, quick=args.quick,
                                  show_progress=False if args.quiet else None, plots=plots)
    except DataNotFoundError as exc:
        return _fail("reproduce", str(exc))
    except OSError as exc:
        return _fail("reproduce", f"cannot write to {out}: {exc.strerror or exc}")
    print("\n".join(report.lines))
    return 0


if __name__ == "__main__":  # pragma: no cover
    run()
