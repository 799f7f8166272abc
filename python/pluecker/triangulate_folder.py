"""``pluecker triangulate``: triangulate a multi-view folder in the Oxford VGG format and write the result.

:func:`run` reads the folder with :func:`pluecker.datasets.load_vgg`, keeps the chosen views, and
triangulates every point seen in at least two of them with :func:`pluecker.triangulate_points` (and, with
``lines=True``, every line seen in at least two of them with :func:`pluecker.triangulate_lines`, whose
covariances come from the segment endpoints with pixel noise ``sigma``); both batches run in parallel, and
a feature the triangulation rejects gets its ``status`` and a ``message`` instead of stopping the run.
:func:`write` stores the features as JSON (every feature, with its certificate) and PLY (the finite ones),
:func:`summary_lines` says what happened. Formats: ``docs/cli.md``.

Conventions: cameras map world points to pixels (the folder's ``*.P``, in the right-handed frame
``load_vgg`` returns); a 3-D line is given by a point on it, a unit direction, its Plücker coordinates
(Josephson & Kahl eq. 3) and the segment spanned by its observed image segments.
"""

from __future__ import annotations

import math
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

import pluecker
from pluecker._paths import folder_problem, staged
from pluecker.datasets import VggSequence, load_vgg
from pluecker.jsonio import dumps  # one key per line, every vector on one line

__all__ = ["FolderError", "Features", "Run", "run", "write", "summary_lines"]

#: Report fields of every result, copied per feature into the JSON.
REPORT_FIELDS = ("status", "certified", "certificate", "cost", "cost_kind", "lower_bound", "relative_gap", "nodes",
                 "iterations", "time_seconds")


class FolderError(Exception):
    """The folder cannot be read or the views do not exist; the message is one line."""


@dataclass
class Features:
    """The triangulated features of one kind (``"points"`` or ``"lines"``).

    ``records`` are the per-feature JSON objects (``index``: the track's row in ``nview-corners`` /
    ``nview-lines``; ``views``: the original numbers of the views it was seen in), ``geometry`` the PLY
    content (``(k, 3)`` points or ``(k, 2, 3)`` segments of the finite features) with ``certified``
    flags, and ``total`` the number of tracks in the folder (rows of its track file). Every count comes
    from the tracks, the features that are triangulated: the folder's own ``p3d`` / ``l3d`` may have
    another number of rows (or none), since triangulation does not read them.
    """

    kind: str
    total: int
    records: list[dict[str, Any]] = field(default_factory=list)
    geometry: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))
    certified: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=bool))

    @property
    def count(self) -> int:
        return len(self.records)


@dataclass
class Run:
    """Everything :func:`write` and :func:`summary_lines` need."""

    name: str
    folder: Path
    views: list[int]
    method: str  # ``options.method`` of the run
    sigma: float
    points: Features
    lines: Features | None
    seconds: float


#: Why a file of the folder is needed, by the end of its name (the list: ``pluecker triangulate --help``).
_REQUIRED = {".corners": "every camera file <prefix>NNN.P needs <prefix>NNN.corners and <prefix>NNN.lines",
             ".lines": "every camera file <prefix>NNN.P needs <prefix>NNN.corners and <prefix>NNN.lines, also "
                       "without --lines",
             "p3d": "the folder needs its 3-D points file, p3d or <prefix>p3d, which may be empty",
             "l3d": "the folder needs its 3-D segments file, l3d or <prefix>l3d, which may be empty"}
#: The track file of each kind of feature.
TRACK_FILES = {"points": "nview-corners", "lines": "nview-lines"}


def _load(folder: Path) -> VggSequence:
    if (problem := folder_problem(folder)) is not None:
        raise FolderError(f"{folder}: {problem}")
    try:
        return load_vgg(folder)
    except OSError as exc:
        if exc.filename is None:  # no camera files: load_vgg's own one-line message
            raise FolderError(str(exc).replace("\n", " ")) from None
        if isinstance(exc, FileNotFoundError):
            why = next((text for end, text in _REQUIRED.items() if str(exc.filename).endswith(end)), None)
            raise FolderError(f"{exc.filename}: no such file" + (f"; {why}" if why else "")) from None
        raise FolderError(f"cannot read {exc.filename}: {exc.strerror or exc}") from None
    except ValueError as exc:
        raise FolderError(str(exc).replace("\n", " ")) from None


def _check_views(seq: VggSequence, views: list[int] | None) -> list[int]:
    if views is None:
        return list(range(seq.n_views))
    bad = [v for v in views if v >= seq.n_views]
    if bad:
        raise FolderError(f"view {bad[0]} does not exist: {seq.name} has {seq.n_views} views (0-{seq.n_views - 1})")
    return list(views)


def _columns(result: Any) -> dict[str, np.ndarray]:
    """The report columns of a batch result, fetched once (every getter returns a fresh array)."""
    return {k: np.asarray(getattr(result, k)) for k in (*REPORT_FIELDS, "messages")}


def _report(columns: dict[str, np.ndarray], i: int) -> dict[str, Any]:
    """The report fields of track ``i`` of a batch result, and its ``message`` when it was rejected."""
    record = {k: columns[k][i].item() for k in REPORT_FIELDS}
    if columns["messages"][i]:
        record["message"] = str(columns["messages"][i])
    return record


def _matrix_or_none(m: np.ndarray) -> Any:
    """A covariance as nested lists, or ``None`` where the batch has none (NaN)."""
    return m.tolist() if np.all(np.isfinite(m)) else None


def _points(seq: VggSequence, views: list[int], options: pluecker.TriangulationOptions) -> Features:
    x, visible = seq.point_observations(views)
    tracks = np.flatnonzero(visible.sum(axis=1) >= 2)
    features = Features("points", total=len(seq.point_tracks))
    if len(tracks) == 0:
        return features
    cameras = seq.cameras[views]
    result = pluecker.triangulate_points(cameras, x[tracks], visible[tracks], options=options)
    columns = _columns(result)
    X = np.asarray(result.point)
    covariances = np.asarray(result.covariance)
    homogeneous = np.hstack([X, np.ones((len(X), 1))])
    projected = np.einsum("vij,nj->nvi", cameras, homogeneous)
    residuals = np.linalg.norm(projected[..., :2] / projected[..., 2:] - x[tracks], axis=2)
    for k, track in enumerate(tracks):
        seen = visible[track]
        record = {"index": int(track), "views": [views[j] for j in np.flatnonzero(seen)],
                  "point": X[k].tolist(), "covariance": _matrix_or_none(covariances[k]), **_report(columns, k),
                  "rms_reprojection_px": float(np.sqrt(np.mean(residuals[k][seen] ** 2)))}
        features.records.append(record)
    finite = np.all(np.isfinite(X), axis=1)
    features.geometry = X[finite]
    features.certified = np.asarray(result.certified)[finite]
    return features


def _segment_extent(point: np.ndarray, direction: np.ndarray, cameras: np.ndarray,
                    segments: np.ndarray) -> np.ndarray:
    """The part of the 3-D line ``point + s direction`` seen in the images: for every observed segment
    endpoint, the point of the line closest to its viewing ray; the two extreme ones (2, 3)."""
    params = []
    for P, segment in zip(cameras, segments):
        M, p4 = P[:, :3], P[:, 3]
        centre = -np.linalg.solve(M, p4)
        for pixel in segment:
            ray = np.linalg.solve(M, np.array([pixel[0], pixel[1], 1.0]))
            # Closest points of two lines: point + s d and centre + r ray.
            a, b, c = direction @ direction, direction @ ray, ray @ ray
            w = point - centre
            denominator = a * c - b * b
            if abs(denominator) > 1e-12 * a * c:
                params.append((b * (ray @ w) - c * (direction @ w)) / denominator)
    if not params:
        return np.full((2, 3), np.nan)
    return np.stack([point + min(params) * direction, point + max(params) * direction])


def _lines(seq: VggSequence, views: list[int], options: pluecker.TriangulationOptions, sigma: float,
           show_progress: bool | None) -> Features:
    from tqdm import tqdm

    segments, visible = seq.line_observations(views)
    features = Features("lines", total=len(seq.line_tracks))
    cameras = seq.cameras[views]
    tracks = np.flatnonzero(visible.sum(axis=1) >= 2)
    # Branch and bound over lines is far slower than over points: a bar on a terminal, nothing in a log.
    started = time.perf_counter()
    with tqdm(total=len(tracks), desc="lines", unit="line", leave=False,
              disable=None if show_progress is None else not show_progress) as bar:
        report = (lambda done: bar.update(done - bar.n)) if not bar.disable else None
        result = pluecker.triangulate_lines(cameras, segments[tracks], visible[tracks], sigma=sigma,
                                            options=options, progress=report)
        shown = not bar.disable
    columns = _columns(result)
    plucker, points, directions = (np.asarray(a) for a in (result.plucker, result.point, result.direction))
    chart_axes, covariances = np.asarray(result.chart_axes), np.asarray(result.covariance)
    geometry, certified = [], []
    for k, track in enumerate(tracks):
        seen = visible[track]
        point, direction = points[k], directions[k]
        extent = (_segment_extent(point, direction, cameras[seen], segments[track][seen])
                  if np.all(np.isfinite(point)) else np.full((2, 3), np.nan))
        features.records.append({
            "index": int(track), "views": [views[j] for j in np.flatnonzero(seen)],
            "plucker": plucker[k].tolist(), "point": point.tolist(),
            "direction": direction.tolist(), "segment": extent.tolist(),
            "chart_axes": chart_axes[k].tolist(), "covariance": _matrix_or_none(covariances[k]), **_report(columns, k)})
        if np.all(np.isfinite(extent)):
            geometry.append(extent)
            certified.append(bool(columns["certified"][k]))
    if shown:
        print(f"lines: {len(tracks)} in {time.perf_counter() - started:.1f} s", file=sys.stderr)
    features.geometry = np.array(geometry).reshape(-1, 2, 3)
    features.certified = np.array(certified, dtype=bool)
    return features


def run(folder: str | Path, views: list[int] | None = None, options: pluecker.TriangulationOptions | None = None,
        lines: bool = False, sigma: float = 1.0, show_progress: bool | None = None) -> Run:
    """Triangulates the folder's points (and lines) from ``views`` (default all) with ``options``
    (``None``: the defaults, method ``optimal``), as every triangulation call takes them. Raises
    :class:`FolderError` for an unreadable folder or a view that does not exist, and a
    :class:`pluecker.PlueckerError` for arguments the triangulation rejects as a whole (e.g. ``sigma``); a
    rejected feature is recorded with its status and message. ``show_progress`` draws a progress bar over
    the lines (None: when standard error is a terminal)."""
    options = options if options is not None else pluecker.TriangulationOptions()
    folder = Path(folder)
    seq = _load(folder)
    views = _check_views(seq, views)
    started = time.perf_counter()
    points = _points(seq, views, options)
    line_features = _lines(seq, views, options, sigma, show_progress) if lines else None
    return Run(seq.name, folder, views, options.method, sigma, points, line_features, time.perf_counter() - started)


# --------------------------------------------------------------------------------------------------
# Output


def _clean(value: Any) -> Any:
    """Strict JSON: NaN/inf as null, numpy scalars as numbers."""
    if isinstance(value, dict):
        return {k: _clean(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_clean(v) for v in value]
    if isinstance(value, np.generic):
        value = value.item()
    if isinstance(value, float) and not math.isfinite(value):
        return None
    return value


def summary(features: Features) -> dict[str, Any]:
    """Counts, certificate kinds, median time and error of one kind of feature."""
    records = features.records
    statuses: dict[str, int] = {}
    kinds: dict[str, int] = {}
    for r in records:
        statuses[r["status"]] = statuses.get(r["status"], 0) + 1
        if r["certified"]:
            kinds[r["certificate"]] = kinds.get(r["certificate"], 0) + 1
    certified = sum(kinds.values())
    times = [r["time_seconds"] for r in records]
    out = {"tracks": features.total, "triangulated": len(records), "skipped": features.total - len(records),
           "statuses": statuses, "certified": certified,
           "certified_fraction": certified / len(records) if records else None, "certificates": kinds,
           "median_time_seconds": float(np.median(times)) if times else None}
    if features.kind == "points" and records:
        out["median_rms_reprojection_px"] = float(np.median([r["rms_reprojection_px"] for r in records]))
    return out


def _header(run: Run, features: Features) -> dict[str, Any]:
    return {"sequence": run.name, "folder": str(run.folder), "views": run.views, "method": run.method,
            **({"sigma_px": run.sigma} if features.kind == "lines" else {}),
            "summary": summary(features), features.kind: features.records}


def _ply(path: Path, run: Run, features: Features) -> Path:
    colours = np.where(features.certified[:, None], [[40, 180, 60]], [[220, 60, 40]])
    comment = f"comment pluecker triangulate {run.name}, views {','.join(map(str, run.views))}, method {run.method}"
    if features.kind == "points":
        vertices = features.geometry
        header = ["ply", "format ascii 1.0", comment, "comment green: certified global optimum, red: not",
                  f"element vertex {len(vertices)}", "property double x", "property double y", "property double z",
                  "property uchar red", "property uchar green", "property uchar blue", "end_header"]
        body = [f"{x!r} {y!r} {z!r} {r} {g} {b}" for (x, y, z), (r, g, b) in zip(vertices.tolist(), colours.tolist())]
    else:
        vertices = features.geometry.reshape(-1, 3)
        header = ["ply", "format ascii 1.0", comment, "comment one edge per line: the part seen in the images; "
                  "green: certified global optimum, red: not",
                  f"element vertex {len(vertices)}", "property double x", "property double y", "property double z",
                  f"element edge {len(features.geometry)}", "property int vertex1", "property int vertex2",
                  "property uchar red", "property uchar green", "property uchar blue", "end_header"]
        body = [f"{x!r} {y!r} {z!r}" for x, y, z in vertices.tolist()]
        body += [f"{2 * i} {2 * i + 1} {r} {g} {b}" for i, (r, g, b) in enumerate(colours.tolist())]
    path.write_text("\n".join(header + body) + "\n", encoding="ascii")
    return path


def write(run: Run, out: str | Path) -> list[Path]:
    """Writes ``points.json`` and ``points.ply`` (and ``lines.json``, ``lines.ply``) into ``out`` (made
    when missing), through a temporary folder: an interrupted or failed write leaves ``out`` as it was."""
    out = Path(out)
    names = []
    with staged(out) as stage:
        for features in (run.points, run.lines):
            if features is None:
                continue
            (stage.path / f"{features.kind}.json").write_text(dumps(_clean(_header(run, features))) + "\n",
                                                               encoding="utf-8")
            _ply(stage.path / f"{features.kind}.ply", run, features)
            names += [f"{features.kind}.json", f"{features.kind}.ply"]
    return [out / name for name in names]


def _summary_line(features: Features) -> str:
    s = summary(features)
    if not s["tracks"]:
        return f"{features.kind}: no tracks ({TRACK_FILES[features.kind]} missing or empty)"
    line = (f"{features.kind}: {s['triangulated']} of {s['tracks']} triangulated ({s['skipped']} seen in fewer "
            f"than 2 of the views)")
    if not s["triangulated"]:
        return line
    statuses = ", ".join(f"{k} {v}" for k, v in sorted(s["statuses"].items()))
    kinds = ", ".join(f"{k} {v}" for k, v in sorted(s["certificates"].items())) or "none"
    median = s["median_time_seconds"]
    median_text = f"{1e6 * median:.1f} µs" if median < 1e-3 else f"{1e3 * median:.1f} ms"
    line += (f"; status {statuses}; certified {s['certified']} ({100 * s['certified_fraction']:.1f} %: {kinds}); "
             f"median {median_text} per {features.kind[:-1]}")
    if "median_rms_reprojection_px" in s:
        line += f"; median RMS reprojection error {s['median_rms_reprojection_px']:.3f} px"
    return line


def summary_lines(run: Run, files: list[Path]) -> list[str]:
    """What was done, one line per feature kind, then the files."""
    lines = [f"triangulate {run.name} (views {','.join(map(str, run.views))}, method {run.method}) in "
             f"{run.seconds:.2f} s", _summary_line(run.points)]
    if run.lines is not None:
        lines.append(_summary_line(run.lines) + (f" (segment endpoints σ = {run.sigma:g} px)" if run.lines.total
                                                 else ""))
    lines.append("wrote " + ", ".join(str(f) for f in files))
    return lines
