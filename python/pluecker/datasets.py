"""Readers for real multi-view data: the Oxford VGG multi-view sequences (Model House, Corridor, Merton).

A folder in the VGG format holds, per view ``k``, a camera ``<prefix>k.P`` (3x4, world to pixels),
corners ``<prefix>k.corners`` (``x y`` rows) and segments ``<prefix>k.lines`` (``x0 y0 x1 y1`` rows, extra
columns ignored), and for the whole sequence the 3-D points ``p3d``, 3-D segments ``l3d`` and the tracks
``nview-corners`` / ``nview-lines`` (row r = 3-D feature r; one column per view holding a 0-based row of that
view's file, ``*`` when not seen). The prefix (``house.``, ``bt.`` or none) is found from the file names.

Two sequences (Model House, Corridor) use a mirrored, left-handed world frame: every camera has
``det(P[:, :3]) * (P [X; 1])[2] < 0`` for the reconstructed points. :func:`load_vgg` detects this from the
data and, when it holds, negates X, Y, Z of every 3-D point and segment and right-multiplies every camera by
``diag(-1, -1, -1, 1)``: the projections and ``λ = (P X̃)₃`` are unchanged and ``det`` of the left 3x3 block
becomes positive, so the world frame is right-handed. pluecker does not need the flip: a point is in front
when ``λ > 0`` for the matrix as given (every point of every sequence, flipped or not), and the raw cameras
triangulate the mirrored points with the same costs and statuses.

Conventions: pixels with (0, 0) the top-left pixel, x right, y down; arrays row-major float64.
"""

from __future__ import annotations

import os
import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np

__all__ = ["DataNotFoundError", "VggSequence", "load_vgg", "vgg_root", "VGG_SEQUENCES"]

# The data: Oxford Visual Geometry Group, "VGG Multiview Dataset",
# http://www.robots.ox.ac.uk/~vgg/data/data-mview.html (see data/vgg/README-VGG.txt).

#: The five sequences shipped in ``pluecker/data/vgg`` (see :func:`vgg_root`).
VGG_SEQUENCES = ("model_house", "corridor", "merton_college_1", "merton_college_2", "merton_college_3")


class DataNotFoundError(FileNotFoundError):
    """A data folder is missing; the message says where it was looked for and how to point to it."""


def vgg_root() -> Path:
    """Where the VGG data live: ``$PLUECKER_VGG_DATA`` if set, else the copy shipped inside the package
    (``pluecker/data/vgg``: the geometry files of the five sequences, 1.5 MB, with the VGG's attribution in
    ``README-VGG.txt``)."""
    env = os.environ.get("PLUECKER_VGG_DATA")
    if env:
        return Path(env)
    return Path(__file__).resolve().parent / "data" / "vgg"


@dataclass(frozen=True)
class VggSequence:
    """One VGG multi-view sequence, in a right-handed world frame (see the module docs).

    Attributes:
        name: folder name.
        cameras: (v, 3, 4) camera matrices, world to pixels.
        points3d: (n, 3) reconstructed 3-D points shipped with the data.
        lines3d: (m, 2, 3) reconstructed 3-D segment endpoints shipped with the data.
        corners: per view, a (k_i, 2) array of detected corners (pixels).
        segments: per view, a (j_i, 2, 2) array of detected segment endpoints (pixels).
        point_tracks: (n, v) int, the corner row seen in each view, -1 when not seen.
        line_tracks: (m, v) int, the segment row seen in each view, -1 when not seen.
        mirrored: True when the shipped frame was left-handed and has been flipped.
    """

    name: str
    cameras: np.ndarray
    points3d: np.ndarray
    lines3d: np.ndarray
    corners: list[np.ndarray]
    segments: list[np.ndarray]
    point_tracks: np.ndarray
    line_tracks: np.ndarray
    mirrored: bool

    @property
    def n_views(self) -> int:
        """Number of views."""
        return self.cameras.shape[0]

    def point_observations(self, views: list[int] | None = None) -> tuple[np.ndarray, np.ndarray]:
        """Observations of every 3-D point in the chosen views (default: all).

        Returns ``(x, visible)``: ``x`` (n, len(views), 2) pixels (NaN where not seen) and ``visible``
        (n, len(views)) bool; the layout ``pluecker.triangulate_points`` takes.
        """
        return _observations(self.point_tracks, self.corners, views, (2,))

    def line_observations(self, views: list[int] | None = None) -> tuple[np.ndarray, np.ndarray]:
        """Observed segments of every 3-D line in the chosen views (default: all).

        Returns ``(segments, visible)``: (m, len(views), 2, 2) pixel endpoints (NaN where not seen) and
        (m, len(views)) bool.
        """
        return _observations(self.line_tracks, self.segments, views, (2, 2))


def _observations(tracks, per_view, views, shape):
    views = list(range(tracks.shape[1])) if views is None else list(views)
    out = np.full((tracks.shape[0], len(views), *shape), np.nan)
    visible = np.zeros((tracks.shape[0], len(views)), dtype=bool)
    for j, view in enumerate(views):
        rows = tracks[:, view]
        seen = rows >= 0
        out[seen, j] = per_view[view][rows[seen]]
        visible[:, j] = seen
    return out, visible


def _numbered_rows(path: Path) -> list[tuple[int, list[str]]]:
    """The non-empty lines of ``path`` as (1-based line number, whitespace-separated fields)."""
    return [(n, line.split()) for n, line in enumerate(path.read_text().splitlines(), start=1) if line.strip()]


def _read_rows(path: Path, columns: int) -> np.ndarray:
    """Whitespace-separated finite numbers, the first ``columns`` of every non-empty row; a ValueError
    naming the file and line otherwise."""
    rows = _numbered_rows(path)
    values = np.zeros((len(rows), columns))
    for k, (line, fields) in enumerate(rows):
        if len(fields) < columns:
            raise ValueError(f"{path}: line {line}: expected at least {columns} numbers, got {len(fields)}")
        try:
            values[k] = [float(v) for v in fields[:columns]]
        except ValueError:
            raise ValueError(f"{path}: line {line}: not a number in {' '.join(fields[:columns])!r}") from None
        if not np.all(np.isfinite(values[k])):
            raise ValueError(f"{path}: line {line}: non-finite value (NaN or inf)")
    return values


def _read_camera(path: Path) -> np.ndarray:
    """The 3x4 camera of a ``.P`` file: exactly three rows of (at least) four numbers, else a ValueError
    naming the file."""
    rows = _read_rows(path, 4)
    if rows.shape[0] != 3:
        raise ValueError(f"{path}: expected a 3x4 camera matrix (3 rows of 4 numbers), got {rows.shape[0]} rows")
    return rows


def _read_tracks(path: Path, n_views: int) -> np.ndarray:
    """Rows of 0-based feature indices (``*`` where a view does not see the track, stored as -1)."""
    if not path.exists():
        return np.zeros((0, n_views), dtype=np.int64)
    rows = _numbered_rows(path)
    tracks = np.full((len(rows), n_views), -1, dtype=np.int64)
    for k, (line, fields) in enumerate(rows):
        if len(fields) != n_views:
            raise ValueError(f"{path}: line {line}: expected {n_views} columns (one per view), got {len(fields)}")
        for j, v in enumerate(fields):
            if v == "*":
                continue
            if not (v.isascii() and v.isdigit()):
                raise ValueError(f"{path}: line {line}: expected a 0-based row index or '*', got {v!r}")
            tracks[k, j] = int(v) if len(v) < 19 else np.iinfo(np.int64).max
    return tracks


def _check_tracks(path: Path, tracks: np.ndarray, files: list[Path], counts: list[int]) -> None:
    """A ValueError naming both files unless every index of ``tracks`` is a row of its view's file."""
    for j, (file, count) in enumerate(zip(files, counts)):
        beyond = np.flatnonzero(tracks[:, j] >= count)
        if len(beyond):
            line = _numbered_rows(path)[beyond[0]][0]
            raise ValueError(f"{path}: line {line} refers to row {tracks[beyond[0], j]} of {file}, which has "
                             f"{count} rows")


def _find(folder: Path, suffix: str) -> Path:
    """The sequence file ``<prefix>suffix`` (e.g. ``house.p3d`` or ``p3d``)."""
    for candidate in sorted(folder.iterdir()):
        if candidate.name == suffix or candidate.name.endswith("." + suffix):
            return candidate
    return folder / suffix


def load_vgg(folder: str | Path) -> VggSequence:
    """Reads a VGG multi-view folder (see the module docs) into a right-handed :class:`VggSequence`.

    ``folder`` is a path, or the name of a shipped sequence (one of :data:`VGG_SEQUENCES`, read from
    :func:`vgg_root`): ``load_vgg("model_house")``.

    Raises:
        DataNotFoundError: the folder does not exist.
        FileNotFoundError: no camera files (``*.P``) in the folder.
        ValueError: a malformed file (the message names it).
    """
    folder = vgg_root() / folder if str(folder) in VGG_SEQUENCES else Path(folder)
    if not folder.is_dir():
        raise DataNotFoundError(
            f"VGG data folder not found: {folder} (set PLUECKER_VGG_DATA to the folder that holds "
            f"{', '.join(VGG_SEQUENCES)})"
        )
    camera_files = sorted(p for p in folder.iterdir() if re.fullmatch(r"(.*\.)?\d+\.P", p.name))
    if not camera_files:
        raise FileNotFoundError(f"{folder}: no camera files '<prefix>NNN.P'")
    cameras = np.stack([_read_camera(p) for p in camera_files])
    stems = [p.name[: -len(".P")] for p in camera_files]
    corners = [_read_rows(folder / f"{s}.corners", 2) for s in stems]
    segments = [_read_rows(folder / f"{s}.lines", 4).reshape(-1, 2, 2) for s in stems]
    points3d = _read_rows(_find(folder, "p3d"), 3)
    lines3d = _read_rows(_find(folder, "l3d"), 6).reshape(-1, 2, 3)
    n_views = len(camera_files)
    point_tracks = _read_tracks(_find(folder, "nview-corners"), n_views)
    line_tracks = _read_tracks(_find(folder, "nview-lines"), n_views)
    _check_tracks(_find(folder, "nview-corners"), point_tracks, [folder / f"{s}.corners" for s in stems],
                  [len(c) for c in corners])
    _check_tracks(_find(folder, "nview-lines"), line_tracks, [folder / f"{s}.lines" for s in stems],
                  [len(g) for g in segments])
    mirrored = _is_mirrored(cameras, points3d)
    if mirrored:
        flip = np.diag([-1.0, -1.0, -1.0, 1.0])
        cameras = cameras @ flip
        points3d = -points3d
        lines3d = -lines3d
    return VggSequence(
        name=folder.name,
        cameras=cameras,
        points3d=points3d,
        lines3d=lines3d,
        corners=corners,
        segments=segments,
        point_tracks=point_tracks,
        line_tracks=line_tracks,
        mirrored=mirrored,
    )


def _is_mirrored(cameras: np.ndarray, points3d: np.ndarray) -> bool:
    """True when most points have ``det(M) (P X̃)₃ < 0`` in most cameras: a left-handed frame (every VGG point has
    ``λ = (P X̃)₃ > 0``, so the sign is that of ``det M``)."""
    if points3d.shape[0] == 0:
        return False
    homogeneous = np.hstack([points3d, np.ones((points3d.shape[0], 1))])
    signs = [np.sign(np.linalg.det(p[:, :3])) * (homogeneous @ p[2]) for p in cameras]
    return float(np.median(np.concatenate(signs))) < 0.0
