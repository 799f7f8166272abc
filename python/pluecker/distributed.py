"""Triangulation beyond one machine, on Dask distributed (``pip install pluecker[dask]``).

The batches of pluecker already use every core of one machine. This module spreads a job over the
workers of a Dask cluster, for observation tables larger than one machine's memory. Dask is never
needed for the main job: without a client everything here runs in this process.

**Tables (Parquet, read and written with pyarrow).** Observations, one row per observation:

========== ======= ================================================================
column     type    meaning
========== ======= ================================================================
track      int64   the 3-D point the observation belongs to (any id)
image      int64   the image (camera) id, a key of ``cameras``
x, y       float64 pixel, ``u = K x_cam / z`` (``x_cam = R X_world + t``)
cov_xx,    float64 optional: the pixel covariance (px²); absent: ``sigma_px²`` I
cov_xy,
cov_yy
========== ======= ================================================================

Cameras are a :class:`Cameras` (image ids and their 3x4 matrices ``P = K [R | t]``), sent to every
worker once. The result is two Parquet datasets under ``out``: ``points/`` with one row per track
(``track``, ``X``, ``Y``, ``Z``, ``cost``, ``lower_bound``, ``relative_gap``, ``certified``, ``status``,
``certificate``, ``message``, ``covariance`` — the 3x3 covariance row-major as 9 values) and
``observations/`` with one row per observation (``track``, ``image``, ``inlier``, and ``point2D_idx``
when the input has it).

**How a job runs.** 1. *Split*: each row group of the input is read by one task, which sends every row
to one of ``buckets`` buckets by a hash of its track and writes one Parquet file per bucket to
``out/_buckets`` (a shuffle through storage: every track ends up in exactly one bucket). 2. *Solve*:
one task per bucket reads its files, sorts the rows by (track, image, x, y) and solves them with
:func:`triangulate_table`, the single-machine kernel, writing ``points/part-<bucket>.parquet`` and
``observations/part-<bucket>.parquet``. Every task is a pure function of its input files and writes
files named after its input, so a retried task (a worker killed mid-job) rewrites the same files and
the output holds every track once; a track's answer depends on its own rows only, so results are bit
for bit those of :func:`triangulate_table` on the whole table, whatever the buckets and workers.
Memory per task is bounded by a row group or a bucket, never by the job. An input whose files each hold
whole tracks (``partitioned=True``) skips the split: one solve per file. ``out`` must be storage every
worker sees (a shared file system, or an object store URI pyarrow can write).

**Bad rows.** A non-finite pixel or covariance, or an image id that is not among the cameras, gives
its track a status (``non_finite``, ``invalid_input``) and a message in ``points``; it never fails
the job or loses other tracks. A bad *table* fails before the job starts, with an
``InvalidOptionError`` naming the file, the column and the row: a column of the wrong type (bools or
text where numbers are expected are never converted), an id that is not a whole number, or (for
:func:`localize`) a query listed twice.

**Output.** A job writes into a temporary folder beside ``out`` (inside it when it exists) and then
moves its tables into ``out``, replacing those of an earlier job whole (:func:`pluecker._paths.staged`):
a job that fails or is interrupted leaves ``out`` as it was.

**Threads.** Before the job each worker sets its pluecker threads (:func:`pluecker.set_num_threads`)
to its share of its machine's cores: the cores divided by the task slots of all workers on that
machine, so that nothing is oversubscribed.
"""

from __future__ import annotations

import copy
import os
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Iterable, Optional, Union

import numpy as np

from . import _core
from ._arguments import check_sigma, number, shown
from ._cameras import Cameras
from ._paths import require_folder, staged
from ._sorting import stable_order
from ._status import Status
from .colmap import ColmapModel, ModelError, as_model

__all__ = ["Cameras", "JobSummary", "triangulate", "triangulate_table", "read_points",
           "read_observations", "localize", "localize_tables", "localize_bag", "queries_to_tables", "read_poses",
           "read_matches", "share_threads"]

OBSERVATION_COLUMNS = ("track", "image", "x", "y")
COVARIANCE_COLUMNS = ("cov_xx", "cov_xy", "cov_yy")
#: Optional observation columns copied to the ``observations`` result (COLMAP's ``point2D_idx``).
PASSTHROUGH_COLUMNS = ("point2D_idx",)
#: Rows per bucket the default bucket count aims at (about 60 MB of observations).
ROWS_PER_BUCKET = 2_000_000


def _pyarrow() -> Any:
    try:
        import pyarrow
        import pyarrow.parquet  # noqa: F401
    except ImportError as exc:  # pragma: no cover - the extra is installed in the test environment
        raise ImportError("pluecker.distributed needs pyarrow: pip install 'pluecker[dask]'") from exc
    return pyarrow


def _canonical_order(track_rank: np.ndarray, image_rank: np.ndarray, images: int, track: np.ndarray,
                     image: np.ndarray, x: np.ndarray) -> np.ndarray:
    """The rows in increasing (track id, image id, x, y): a total order that does not depend on how the
    rows arrived. One stable sort of the integer key (track rank, image rank among ``images`` ids, the
    unknown ones last); the full four-key sort only when a track has two rows of one image rank."""
    key = track_rank.astype(np.int64) * (images + 1) + image_rank
    order = stable_order(key)
    ordered = key[order]
    if np.any(ordered[1:] == ordered[:-1]):
        order = np.lexsort((x[:, 1], x[:, 0], image, track))
    return order


def triangulate_table(table: Any, cameras: Cameras, *,
                      options: Optional[_core.TriangulationOptions] = None, sigma_px: float = 1.0) -> tuple[Any, Any]:
    """The single-machine kernel: every track of an observation ``table`` (a ``pyarrow.Table`` with the
    columns of the module docs) by :func:`pluecker.triangulate_points` (rows form). Returns the
    ``points`` and ``observations`` tables of the module docs, rows in increasing track id and, per
    track, observations in increasing (image, x, y). Without covariance columns every pixel has
    covariance ``sigma_px²`` I."""
    pa = _pyarrow()
    check_sigma(sigma_px)
    _require_columns(table.column_names, OBSERVATION_COLUMNS, "observations")
    has_cov = all(name in table.column_names for name in COVARIANCE_COLUMNS)
    _check_column_types(table.schema, OBSERVATION_COLUMNS + (COVARIANCE_COLUMNS if has_cov else ()), "observations",
                        table.column)
    track = _check_ids([("observations", table.column("track"))], "track", unique=False)
    image = _check_ids([("observations", table.column("image"))], "image", unique=False)
    x = np.stack([np.asarray(table.column(n).to_numpy(), dtype=float) for n in ("x", "y")], axis=1)
    if has_cov:
        cxx, cxy, cyy = (np.asarray(table.column(n).to_numpy(), dtype=float) for n in COVARIANCE_COLUMNS)
        cov = np.stack([np.stack([cxx, cxy], -1), np.stack([cxy, cyy], -1)], axis=1)
    else:
        cov = np.broadcast_to(sigma_px**2 * np.eye(2), (len(track), 2, 2))
    ids, track_index = np.unique(track, return_inverse=True)
    image_rank, known, camera_index = cameras.lookup(image)
    order = _canonical_order(track_index, image_rank, len(cameras.ids), track, image, x)
    track_index, camera_index, known = track_index[order], camera_index[order], known[order]
    image, x, cov = image[order], x[order], np.ascontiguousarray(cov[order])
    passthrough = {name: table.column(name).take(pa.array(order)) for name in PASSTHROUGH_COLUMNS
                   if name in table.column_names}
    result = _core.triangulate_points(cameras.known(), x, covariances=cov, track=track_index, image=camera_index, options=options, n_tracks=len(ids))
    status = np.asarray(result.status).astype(object)
    messages = np.asarray(result.messages, dtype=object)
    for row in np.flatnonzero(~known):
        t = track_index[row]
        status[t] = Status.INVALID_INPUT.value
        messages[t] = f"track {ids[t]}: image id {image[row]} is not among the cameras"
    X = np.asarray(result.point)
    points = pa.table({
        "track": ids,
        "X": X[:, 0], "Y": X[:, 1], "Z": X[:, 2],
        "cost": np.asarray(result.cost),
        "lower_bound": np.asarray(result.lower_bound),
        "relative_gap": np.asarray(result.relative_gap),
        "certified": np.asarray(result.certified, dtype=bool),
        "status": status.astype(str),
        "certificate": np.asarray(result.certificate).astype(str),
        "message": messages.astype(str),
        "covariance": pa.FixedSizeListArray.from_arrays(np.asarray(result.covariance).reshape(-1), 9),
    })
    inliers = np.ones(len(image), bool) if result.inliers is None else np.asarray(result.inliers, dtype=bool)
    observations = pa.table({"track": ids[track_index], "image": image, "inlier": inliers, **passthrough})
    return points, observations


@dataclass
class JobSummary:
    """What a job did: tracks, certified tracks, statuses, seconds and where the tables are."""

    tracks: int
    certified: int
    statuses: dict[str, int]
    seconds: float
    points: Path
    observations: Path
    buckets: int = 0
    workers: int = 0


def _bucket_of(track: np.ndarray, buckets: int) -> np.ndarray:
    """A hash of the track id (splitmix64's finaliser) modulo ``buckets``: tracks with neighbouring ids
    spread over every bucket."""
    z = track.astype(np.uint64) + np.uint64(0x9E3779B97F4A7C15)
    with np.errstate(over="ignore"):
        z = (z ^ (z >> np.uint64(30))) * np.uint64(0xBF58476D1CE4E5B9)
        z = (z ^ (z >> np.uint64(27))) * np.uint64(0x94D049BB133111EB)
        z = z ^ (z >> np.uint64(31))
    return (z % np.uint64(buckets)).astype(np.int64)


def _split(source: str, fragment: int, row_group: int, buckets: int, scratch: str, key: str = "track",
           name: str = "part") -> int:
    """Task 1: one row group of the input, sent to the buckets by a hash of its ``key`` column (module
    docs), written as ``scratch/bucket=<b>/<name>-<fragment>-<row group>.parquet``. Returns its rows."""
    pa = _pyarrow()
    import pyarrow.parquet as pq

    path = _input_files(source)[fragment]
    part = pq.ParquetFile(path).read_row_group(row_group)
    bucket = _bucket_of(np.asarray(part.column(key).to_numpy(), dtype=np.int64), buckets)
    order = stable_order(bucket)
    edges = np.searchsorted(bucket[order], np.arange(buckets + 1))
    for b in range(buckets):
        rows = part.take(pa.array(order[edges[b]:edges[b + 1]]))
        folder = Path(scratch) / f"bucket={b}"
        folder.mkdir(parents=True, exist_ok=True)
        pq.write_table(rows, folder / f"{name}-{fragment}-{row_group}.parquet")
    return part.num_rows


def _bucket_table(scratch: str, bucket: int, name: str = "part") -> Any:
    """Every row of one bucket of one input (``None`` when it has none)."""
    pa = _pyarrow()
    import pyarrow.parquet as pq

    files = sorted((Path(scratch) / f"bucket={bucket}").glob(f"{name}-*.parquet"))
    table = pa.concat_tables([pq.read_table(f) for f in files]) if files else None
    return table if table is not None and table.num_rows else None


def _solve(bucket: int, scratch: str, out: str, cameras: Cameras,
           options: Optional[dict[str, Any]], sigma_px: float) -> dict[str, Any]:
    """Task 2: one bucket solved (module docs). Returns its counts."""
    return _solve_table(_bucket_table(scratch, bucket), bucket, out, cameras, options, sigma_px)


def _solve_file(index: int, source: str, out: str, cameras: Cameras,
                options: Optional[dict[str, Any]], sigma_px: float) -> dict[str, Any]:
    """Task of a ``partitioned`` job: one input file of whole tracks solved and written."""
    import pyarrow.parquet as pq

    return _solve_table(pq.read_table(_input_files(source)[index]), index, out, cameras, options, sigma_px)


def _solve_table(table: Any, bucket: int, out: str, cameras: Cameras,
                 options: Optional[dict[str, Any]], sigma_px: float) -> dict[str, Any]:
    """Solves one bucket's table and writes ``points`` and ``observations`` part ``bucket``."""
    opts = _core.TriangulationOptions(**options) if options is not None else None
    if table is None or table.num_rows == 0:
        return {"tracks": 0, "certified": 0, "statuses": {}}
    points, observations = triangulate_table(table, cameras, options=opts, sigma_px=sigma_px)
    _write_part(out, bucket, points=points, observations=observations)
    return {"tracks": points.num_rows, "certified": int(np.sum(points.column("certified").to_numpy())),
            "statuses": _status_counts(points)}


def _write_part(out: str, part: int, **tables: Any) -> None:
    """Writes each table as ``out/<its name>/part-<part>.parquet`` (a retried task rewrites the same file)."""
    import pyarrow.parquet as pq

    for name, table in tables.items():
        target = Path(out) / name
        target.mkdir(parents=True, exist_ok=True)
        pq.write_table(table, target / f"part-{part:05d}.parquet")


def _status_counts(table: Any) -> dict[str, int]:
    """How many rows of a result table have each status."""
    values, counts = np.unique(np.asarray(table.column("status").to_pylist(), dtype=str), return_counts=True)
    return {str(v): int(c) for v, c in zip(values, counts)}


def _input_files(source: str) -> list[str]:
    path = Path(source)
    if path.is_dir():
        return [str(p) for p in sorted(path.rglob("*.parquet"))]
    return [str(path)]


def _require_columns(names: Iterable[str], required: Iterable[str], what: str) -> None:
    """A ``pluecker.ShapeError`` naming ``what`` and the missing columns unless ``names`` holds every
    one of ``required``."""
    required, present = tuple(required), set(names)
    missing = [c for c in required if c not in present]
    if missing:
        raise _core.ShapeError(f"{what}: missing column(s) {', '.join(missing)}; expected the columns "
                               f"{', '.join(required)}")


#: What a column holds when it is not a number (pixels, coordinates, intrinsics, covariances): ids
#: (an integer type, or floats that are whole numbers), text, or lists of numbers.
ID_COLUMNS = ("query", "track", "image", "camera_id", "point3D_id", "point2D_idx")
TEXT_COLUMNS = ("model",)
LIST_COLUMNS = ("params",)


def _type_fits(name: str, t: Any) -> bool:
    """Whether a column ``name`` of Arrow type ``t`` holds what it should (:data:`ID_COLUMNS` ...);
    bools and text are never numbers, and numbers are never converted from text. An all-null column
    fits (its rows are then bad one by one)."""
    import pyarrow.types as pat

    number = lambda t: pat.is_integer(t) or pat.is_floating(t) or pat.is_null(t)  # noqa: E731
    if name in TEXT_COLUMNS:
        return pat.is_string(t) or pat.is_large_string(t) or pat.is_null(t)
    if name in LIST_COLUMNS:
        return pat.is_null(t) or ((pat.is_list(t) or pat.is_large_list(t) or pat.is_fixed_size_list(t))
                                  and number(t.value_type))
    return number(t)


def _expected(name: str) -> str:
    return ("text" if name in TEXT_COLUMNS else "a list of numbers" if name in LIST_COLUMNS
            else "an integer id" if name in ID_COLUMNS else "a number")


def _check_column_types(schema: Any, names: Iterable[str], what: str, read: Any) -> None:
    """``InvalidOptionError`` naming ``what`` (the table), the column and its first row unless each
    column of ``names`` has a type that holds what it should (:func:`_type_fits`): a bool or text column
    of pixels is refused, never read as numbers. ``read(name)`` gives the column, read only to name the
    row."""
    for name in names:
        t = schema.field(name).type
        if _type_fits(name, t):
            continue
        cells = read(name).to_pylist()
        row = next((k for k, v in enumerate(cells) if v is not None), 0)
        value = shown(cells[row]) if cells else "nothing"
        raise _core.InvalidOptionError(f"{what} column {name}, row {row}: {value} is {_described(t)}, expected "
                                       f"{_expected(name)} (column type {t})")


def _described(t: Any) -> str:
    import pyarrow.types as pat

    if pat.is_boolean(t):
        return "a bool"
    if pat.is_string(t) or pat.is_large_string(t):
        return "text"
    if pat.is_list(t) or pat.is_large_list(t) or pat.is_fixed_size_list(t):
        return f"a list of {_described(t.value_type).removeprefix('a ')}"
    return f"of type {t}"


def _check_ids(parts: list[tuple[str, Any]], name: str, *, unique: bool) -> np.ndarray:
    """The id column ``name`` of one table given as ``parts`` (``(what, column)`` per file, rows
    counted in each) as int64; ``InvalidOptionError`` naming the table, the column and the row of the
    first cell that is not a whole number (a fraction, NaN, null), and with ``unique`` the two rows of
    the first id listed twice."""
    import pyarrow.types as pat

    values, where = [], []
    for what, column in parts:
        if pat.is_integer(column.type) and column.null_count == 0:
            ids = np.asarray(column.to_numpy(), dtype=np.int64)
        else:
            cells = np.asarray(column.to_numpy(zero_copy_only=False), dtype=float)
            whole = np.isfinite(cells) & (cells == np.round(cells)) & (np.abs(cells) < 2.0**63)
            if not whole.all():
                row = int(np.flatnonzero(~whole)[0])
                shown = "null" if column[row].as_py() is None else number(cells[row])
                raise _core.InvalidOptionError(f"{what} column {name}, row {row}: {shown} is not an integer id")
            ids = cells.astype(np.int64)
        values.append(ids)
        where += [(what, k) for k in range(len(ids))] if unique else []
    ids = np.concatenate(values) if values else np.zeros(0, dtype=np.int64)
    if unique and len(ids) > 1:
        order = stable_order(ids)
        twice = np.flatnonzero(ids[order][1:] == ids[order][:-1])
        if len(twice):
            (what_a, a), (what_b, b) = where[order[twice[0]]], where[order[twice[0] + 1]]
            rows = f"rows {a} and {b}" if what_a == what_b else f"row {a}, and {what_b} row {b}"
            raise _core.InvalidOptionError(
                f"{what_a} column {name}, {rows}: {name} {ids[order[twice[0]]]} is listed twice; the {name} ids "
                "must be unique (one row, one camera per query)")
    return ids


def _check_inputs(source: str, required: Iterable[str], what: str) -> None:
    """Before a job: ``source`` must hold Parquet files, each with the ``required`` columns (a
    ``ShapeError`` naming the file otherwise) of the types they need (:func:`_check_column_types`), so
    that a bad input fails here, not in every task."""
    import pyarrow.parquet as pq

    files = _input_files(source)
    if not files:
        raise _core.ShapeError(f"{what} {source}: no Parquet files (*.parquet) in the folder")
    import pyarrow.types as pat

    for f in files:
        schema = pq.read_schema(f)
        _require_columns(schema.names, required, f"{what} {f}")
        read = lambda name, f=f: pq.read_table(f, columns=[name]).column(name)  # noqa: E731
        _check_column_types(schema, required, f"{what} {f}", read)
        # Ids given as floats must be whole numbers (the split would truncate 0.5 to 0).
        for name in required:
            if name in ID_COLUMNS and name != "point3D_id" and not pat.is_integer(schema.field(name).type):
                _check_ids([(f"{what} {f}", read(name))], name, unique=False)


def _row_groups(source: str) -> list[tuple[int, int]]:
    import pyarrow.parquet as pq

    out = []
    for i, f in enumerate(_input_files(source)):
        out += [(i, g) for g in range(pq.ParquetFile(f).num_row_groups)]
    return out


def share_threads(client: Any) -> dict[str, int]:
    """Sets every worker's pluecker threads to its share of its machine's cores (module docs) and
    returns them by worker address."""
    cores = client.run(os.cpu_count)
    info = client.scheduler_info()["workers"]
    slots: dict[str, int] = {}
    for w in info.values():
        slots[w["host"]] = slots.get(w["host"], 0) + int(w["nthreads"])
    # One process-wide pool per worker, shared by its task slots: per slot the machine's cores over
    # the slots of every worker on it.
    shares = {address: max(1, int(cores.get(address) or 1) // max(1, slots[w["host"]])) * int(w["nthreads"])
              for address, w in info.items()}
    for address, n in shares.items():
        client.run(_core.set_num_threads, n, workers=[address])
    return shares


def triangulate(source: Union[str, Path], cameras: Cameras, out: Union[str, Path], *, client: Any = None,
                buckets: Optional[int] = None,
                options: Optional[_core.TriangulationOptions] = None, sigma_px: float = 1.0,
                progress: bool = False, partitioned: bool = False,
                threads_per_worker: Optional[int] = None) -> JobSummary:
    """Re-triangulates every track of the observation table at ``source`` (a Parquet file or a folder
    of them, columns of the module docs) and writes ``out/points`` and ``out/observations``.

    ``client``: a ``distributed.Client`` (``None``: run here, without Dask). ``buckets``: the number of
    solve tasks (default: enough for about 2 million observations each, at least 4 per worker).
    ``options``: those of :func:`pluecker.triangulate_points` (method: ``options.method``). ``progress``:
    a progress bar on the terminal (Dask's). ``partitioned``: every input file already holds whole
    tracks (written by track, e.g. one file per chunk of tracks): one solve per file, no split.
    ``threads_per_worker``: pluecker threads of every worker (default: its share of the cores,
    :func:`share_threads`). Returns a :class:`JobSummary`.
    """
    import pyarrow.parquet as pq

    started = time.perf_counter()
    source, out = str(source), Path(out)
    check_sigma(sigma_px)
    _check_inputs(source, OBSERVATION_COLUMNS, "observations")
    workers = len(client.scheduler_info()["workers"]) if client is not None else 1
    if buckets is None and not partitioned:
        rows = sum(pq.ParquetFile(f).metadata.num_rows for f in _input_files(source))
        buckets = max(4 * workers, -(-rows // ROWS_PER_BUCKET), 1)
    option_fields = options.to_dict() if options is not None else None
    # Written into a temporary folder, then ``points`` and ``observations`` replace those of ``out``
    # whole (module docs of :mod:`pluecker._paths`).
    with staged(out) as stage:
        target = stage.path
        scratch = str(target / "_buckets")
        if partitioned:
            files = _input_files(source)
            buckets = len(files)
            results = _run_tasks(client, _solve_file, [(i, source) for i in range(len(files))],
                                 (str(target), cameras, option_fields, sigma_px), progress, threads_per_worker)
        else:
            results = _run_job(client, [(source, "track", "part")], buckets, scratch, _solve,
                               (scratch, str(target), cameras, option_fields, sigma_px), progress,
                               threads_per_worker)
        _remove_tree(Path(scratch))
        if not any(r["tracks"] for r in results):
            # No rows at all: the result tables still exist, empty, with the columns a job writes.
            empty = pq.read_schema(_input_files(source)[0]).empty_table()
            points, observations = triangulate_table(empty, cameras, options=options, sigma_px=sigma_px)
            _write_part(str(target), 0, points=points, observations=observations)
    statuses = _tally(results)
    return JobSummary(tracks=sum(r["tracks"] for r in results), certified=sum(r["certified"] for r in results),
                      statuses=statuses, seconds=time.perf_counter() - started, points=out / "points",
                      observations=out / "observations", buckets=buckets, workers=workers)


def _set_threads(client: Any, threads_per_worker: Optional[int]) -> None:
    if threads_per_worker is None:
        share_threads(client)
    else:
        client.run(_core.set_num_threads, int(threads_per_worker))


def _run_tasks(client: Any, task: Any, items: list[tuple[Any, ...]], args: tuple[Any, ...], progress: bool,
               threads_per_worker: Optional[int] = None, *, broadcast: int = 1, after: Any = None) -> list[Any]:
    """``task(*item, *args)`` for every item: here without ``client``, else on its workers, with
    ``args[broadcast]`` sent to every worker once, each task started after the future ``after`` when
    given, and 3 retries per task."""
    if client is None:
        return [task(*item, *args) for item in items]
    _set_threads(client, threads_per_worker)
    args = (*args[:broadcast], client.scatter(args[broadcast], broadcast=True), *args[broadcast + 1:])
    if after is None:
        futures = [client.submit(task, *item, *args, pure=False, retries=3) for item in items]
    else:
        futures = [client.submit(_after, after, task, *item, *args, pure=False, retries=3) for item in items]
    if progress:
        from distributed import progress as dask_progress

        dask_progress(futures)
    return client.gather(futures)


def _run_job(client: Any, inputs: list[tuple[str, str, str]], buckets: int, scratch: str, solve: Any,
             args: tuple[Any, ...], progress: bool, threads_per_worker: Optional[int] = None) -> list[Any]:
    """Splits every input ``(source, key column, name)`` into the buckets, then runs
    ``solve(bucket, *args)`` on each (module docs) by :func:`_run_tasks`, ``args[2]`` broadcast."""
    groups = [(source, key, name, f, g) for source, key, name in inputs for f, g in _row_groups(source)]
    barrier = None
    if client is None:
        for source, key, name, f, g in groups:
            _split(source, f, g, buckets, scratch, key, name)
    else:
        splits = [client.submit(_split, source, f, g, buckets, scratch, key, name, pure=False, retries=3)
                  for source, key, name, f, g in groups]
        # Every solve waits for every split (a bucket gathers rows from all of them).
        barrier = client.submit(_count, *splits, pure=False, retries=3)
    return _run_tasks(client, solve, [(b,) for b in range(buckets)], args, progress, threads_per_worker,
                      broadcast=2, after=barrier)


def _tally(results: list[dict[str, Any]]) -> dict[str, int]:
    """The tasks' status counts, summed."""
    statuses: dict[str, int] = {}
    for r in results:
        for k, v in r["statuses"].items():
            statuses[k] = statuses.get(k, 0) + v
    return statuses


def _count(*rows: int) -> int:
    return sum(rows)


def _after(_barrier: int, solve: Any, *args: Any) -> Any:
    return solve(*args)


def _remove_tree(path: Path) -> None:
    if not path.exists():
        return
    for p in sorted(path.rglob("*"), reverse=True):
        p.unlink() if p.is_file() else p.rmdir()
    path.rmdir()


#: Query tables give each query's camera by one of these column sets: pinhole intrinsics (pixels), a
#: COLMAP camera model (its name as COLMAP spells it, e.g. ``OPENCV``, and its parameters in COLMAP's
#: order, a list of numbers; pixels are then the raw, distorted ones), or, with a COLMAP model
#: (``reconstruction=``), the ``camera_id`` of one of its cameras.
QUERY_COLUMNS = ("query", "fx", "fy", "cx", "cy")
LENS_QUERY_COLUMNS = ("query", "model", "params")
MODEL_QUERY_COLUMNS = ("query", "camera_id")
#: A frame of a rig of the COLMAP model (``reconstruction=``): the images of its cameras at one instant,
#: localised together (``x_rig = R X_world + t``); every match then names its image's ``camera_id``.
RIG_QUERY_COLUMNS = ("query", "rig_id")
POINT_MATCH_COLUMNS = ("query", "x", "y", "X", "Y", "Z")
#: Point matches with a COLMAP model (``reconstruction=``): the 3-D point is the model's ``point3D_id``.
MODEL_POINT_MATCH_COLUMNS = ("query", "x", "y", "point3D_id")
#: Point matches of a rig's frame (queries by ``rig_id``): the camera of the rig that saw each one.
RIG_POINT_MATCH_COLUMNS = ("query", "camera_id", "x", "y", "point3D_id")
LINE_MATCH_COLUMNS = ("query", "x1", "y1", "x2", "y2", "X1", "Y1", "Z1", "X2", "Y2", "Z2")


#: The columns of a query table by the way it gives its cameras (:func:`_query_camera_kind`).
CAMERA_COLUMN_SETS = {"pinhole": QUERY_COLUMNS, "lens": LENS_QUERY_COLUMNS, "camera_id": MODEL_QUERY_COLUMNS,
                      "rig_id": RIG_QUERY_COLUMNS}


def _point_match_columns(kind: str, model: Optional[ColmapModel]) -> tuple[str, ...]:
    """The columns of the point matches for queries whose cameras are given by ``kind``."""
    if kind == "rig_id":
        return RIG_POINT_MATCH_COLUMNS
    return MODEL_POINT_MATCH_COLUMNS if model is not None else POINT_MATCH_COLUMNS


def _line_match_columns(kind: str) -> tuple[str, ...]:
    """The columns of the line matches for queries whose cameras are given by ``kind`` (a rig's frame
    names the camera of each)."""
    return LINE_MATCH_COLUMNS + (("camera_id",) if kind == "rig_id" else ())


def _query_camera_kind(names: Iterable[str], what: str, model: Optional[ColmapModel]) -> str:
    """Which camera columns a query table holds: ``"pinhole"``, ``"lens"``, ``"camera_id"`` or
    ``"rig_id"`` (:data:`QUERY_COLUMNS`). A ``ShapeError`` naming ``what`` when it holds none of the sets,
    or more than one (which camera would win is not guessed), or ``camera_id`` / ``rig_id`` without a
    model."""
    present = set(names)
    sets = CAMERA_COLUMN_SETS
    complete = [kind for kind, columns in sets.items() if set(columns) <= present]
    if len(complete) > 1:
        raise _core.ShapeError(f"{what}: one camera per query: give the columns of one of "
                               + " or ".join(", ".join(sets[k][1:]) for k in complete) + ", not both")
    if complete in (["camera_id"], ["rig_id"]) and model is None:
        raise _core.ShapeError(f"{what}: column {complete[0]} names {complete[0][:-3]}s of a COLMAP model: pass the "
                               "model (reconstruction=, or --colmap on the command line), or give model, params per "
                               "query")
    if complete:
        return complete[0]
    # None complete: the missing columns of the pinhole set, the documented default, with the others.
    try:
        _require_columns(present, QUERY_COLUMNS, what)
    except _core.ShapeError as error:
        others = "query, model, params (a COLMAP camera model)" + (", or query, camera_id (a camera of the "
                                                                   "model)" if model is not None else "")
        raise _core.ShapeError(f"{error}; or {others}") from None
    raise AssertionError("unreachable")  # pragma: no cover


class _BadQuery(Exception):
    """A query whose own rows are bad: its status is ``invalid_input`` with this message."""


def _query_cameras(queries: Any, kind: str, model: Optional[ColmapModel]) -> list[Any]:
    """Per row of ``queries``, a function that returns its camera (``Camera`` or ``Camera``) or
    raises :class:`_BadQuery` naming the table, the column and the query id."""
    q_ids = np.asarray(queries.column("query").to_numpy(), dtype=np.int64)
    if kind == "pinhole":
        intrinsics = _columns(queries, QUERY_COLUMNS[1:])

        def pinhole(i: int) -> Any:
            try:
                return _core.Camera.pinhole(*intrinsics[i])
            except _core.PlueckerError as exc:
                raise _BadQuery(f"query {q_ids[i]}: queries columns fx, fy, cx, cy: {exc}") from None
        return [lambda i=i: pinhole(i) for i in range(len(q_ids))]
    if kind == "lens":
        names, params = queries.column("model").to_pylist(), queries.column("params").to_pylist()
        return [lambda i=i: _lens(q_ids[i], names[i], params[i]) for i in range(len(q_ids))]
    if kind == "rig_id":
        rig_ids = queries.column("rig_id").to_pylist()
        return [lambda i=i: _model_rig(q_ids[i], rig_ids[i], model) for i in range(len(q_ids))]
    camera_ids = queries.column("camera_id").to_pylist()
    return [lambda i=i: _model_camera(q_ids[i], camera_ids[i], model) for i in range(len(q_ids))]


def _id_cell(query: int, column: str, value: Any) -> int:
    """A query's id cell (``camera_id``, ``rig_id``) as an int (a float holding an integer counts), or
    :class:`_BadQuery` naming the query and the column."""
    if isinstance(value, float) and value.is_integer():
        value = int(value)
    if not isinstance(value, int):
        raise _BadQuery(f"query {query}: queries column {column}: {shown(value)} is not an integer {column}")
    return value


def _model_rig(query: int, rig_id: Any, model: ColmapModel) -> tuple[_core.Rig, tuple[int, ...]]:
    """The rig ``rig_id`` of the model for one query, and the ``camera_id`` of each of its cameras."""
    rig_id = _id_cell(query, "rig_id", rig_id)
    try:
        return model.rig(rig_id)
    except (ModelError, _core.PlueckerError) as exc:
        raise _BadQuery(f"query {query}: queries column rig_id: {exc}") from None


def _lens(query: int, name: Any, params: Any, what: str = "queries") -> _core.Camera:
    """The ``Camera`` of one query's ``model`` and ``params`` cells."""
    if not isinstance(name, str) or name not in _core.Camera.MODELS:
        raise _BadQuery(f"query {query}: {what} column model: {name!r} is not a COLMAP camera model; expected one "
                        f"of {', '.join(_core.Camera.MODELS)}")
    if not isinstance(params, (list, tuple)) or not all(
            isinstance(p, (int, float)) and not isinstance(p, bool) for p in params):
        raise _BadQuery(f"query {query}: {what} column params: expected a list of numbers in COLMAP's order for "
                        f"{name}, got {params!r}"[:300])
    try:
        return _core.Camera(name, [float(p) for p in params])
    except _core.PlueckerError as exc:
        raise _BadQuery(f"query {query}: {what} column params: {exc}") from None


def _model_camera(query: int, camera_id: Any, model: ColmapModel) -> _core.Camera:
    """The ``Camera`` of the model's camera ``camera_id`` for one query."""
    camera_id = _id_cell(query, "camera_id", camera_id)
    if camera_id not in model.cameras:
        raise _BadQuery(f"query {query}: queries column camera_id: camera_id {camera_id} is not a camera of the "
                        "COLMAP model")
    name, params = model.cameras[int(camera_id)]
    try:
        return _core.Camera(name, list(params))
    except _core.PlueckerError as exc:
        raise _BadQuery(f"query {query}: queries column camera_id: camera_id {camera_id} of the COLMAP model: "
                        f"{exc}") from None


def _columns(table: Any, names: Iterable[str]) -> np.ndarray:
    return np.stack([np.asarray(table.column(n).to_numpy(), dtype=float) for n in names], axis=1)


def _point3D_ids(table: Any) -> tuple[np.ndarray, np.ndarray]:
    """The ``point3D_id`` column as int64 and the mask of its cells that hold an integer (not null, not
    a fraction)."""
    column = table.column("point3D_id")
    import pyarrow.types as types

    if types.is_integer(column.type) and column.null_count == 0:
        return np.asarray(column.to_numpy(), dtype=np.int64), np.ones(len(column), dtype=bool)
    values = np.asarray(column.to_numpy(zero_copy_only=False), dtype=float)
    valid = np.isfinite(values) & (values == np.round(values))
    return np.where(valid, values, -1).astype(np.int64), valid


def _grouped(table: Any, names: tuple[str, ...]) -> dict[int, np.ndarray]:
    """Per query id, the rows of ``table`` holding it, in increasing order of the columns ``names``: an
    order that does not depend on how the rows arrived (the result is the same whatever the
    partitioning)."""
    if table is None or table.num_rows == 0:
        return {}
    key = np.asarray(table.column("query").to_numpy(), dtype=np.int64)
    values = [np.asarray(table.column(n).to_numpy(zero_copy_only=False)) for n in names]
    rows = np.lexsort((*values[::-1], key))
    key = key[rows]
    starts = np.flatnonzero(np.r_[True, key[1:] != key[:-1]])
    return {int(key[a]): rows[a:b] for a, b in zip(starts, np.r_[starts[1:], len(key)])}


def _point_matches(table: Any, model: Optional[ColmapModel],
                   kind: str) -> tuple[dict[int, np.ndarray], np.ndarray, Any, Any]:
    """The point matches: rows per query (:func:`_grouped`), every row as ``(x, y, X, Y, Z)`` (the 3-D
    point read from the model with a ``model``), with a model the ``point3D_id`` per row with the
    mask of those in the model (else ``None``), and for a rig's frames the ``camera_id`` per row (else
    ``None``)."""
    if table is None or table.num_rows == 0:
        return {}, np.zeros((0, 5)), None, None
    if model is None:
        return _grouped(table, POINT_MATCH_COLUMNS[1:]), _columns(table, POINT_MATCH_COLUMNS[1:]), None, None
    ids, valid = _point3D_ids(table)
    xyz, known = model.lookup(ids)
    known &= valid
    columns = _point_match_columns(kind, model)
    groups = _grouped(table, columns[1:])
    camera_ids = table.column("camera_id").to_pylist() if "camera_id" in columns else None
    return groups, np.c_[_columns(table, ("x", "y")), xyz], (ids, known, valid), camera_ids


def localize_tables(queries: Any, point_matches: Any, line_matches: Any = None, *, ransac: Any = None,
                    options: Optional[_core.PoseOptions] = None, seed: int = 0, threads: Optional[int] = None,
                    reconstruction: Any = None) -> tuple[Any, Any]:
    """The single-machine kernel of :func:`localize`: one robust pose per row of ``queries`` from its rows
    of ``point_matches`` and ``line_matches``: ``pyarrow.Table`` or anything ``pyarrow.table`` takes (a
    dict of columns, a pandas DataFrame).

    ``queries``: ``query`` (int64 id) and the camera, by one set of columns (:data:`QUERY_COLUMNS`):
    ``fx``, ``fy``, ``cx``, ``cy`` (a pinhole camera), or ``model`` (a COLMAP camera model name, e.g.
    ``"OPENCV"``) and ``params`` (a list of numbers in COLMAP's order), or with ``reconstruction=`` the
    ``camera_id`` of one of the model's cameras. Pixels are those of the camera: raw, distorted ones for
    a model with distortion. ``point_matches``: ``query``, pixel ``x``, ``y`` and world ``X``,
    ``Y``, ``Z``, or with ``reconstruction=`` the ``point3D_id`` of one of the model's 3-D points.
    ``line_matches``: ``query``, segment ``x1 … y2`` in pixels, 3-D segment ``X1 … Z2``.
    ``reconstruction``: a COLMAP model, a ``pycolmap.Reconstruction`` or a :class:`pluecker.colmap.ColmapModel`.

    Each query runs :func:`pluecker.estimate_pose` with RANSAC (``ransac``: a
    :class:`pluecker.RansacOptions`, ``None``: its defaults, a 4 px point threshold; its thresholds
    are distorted pixels through a lens) seeded ``ransac.seed + seed + query`` (reproducible whatever
    the partitioning), matches sorted by their values. Returns the ``poses`` table (``query``, ``R`` 9
    values row-major, ``t`` 3, ``status``, ``rms_error_px``, ``point_inliers``, ``line_inliers``,
    ``message``; ``x_cam = R X_world + t``) and the ``matches`` table (``query``, ``kind`` point/line,
    ``index`` in the sorted order, ``inlier``, and with ``reconstruction=`` the ``point3D_id`` of a
    point match), rows in increasing query id. A query with bad or too few matches, or a bad camera (an unknown
    model name, wrong params, a ``camera_id`` or ``point3D_id`` not in the model), gets status
    ``invalid_input`` and a message naming the query, the table and the column; the other queries are
    solved as if it were not there."""
    pa = _pyarrow()
    from concurrent.futures import FIRST_EXCEPTION, ThreadPoolExecutor, wait

    queries, point_matches, line_matches = (t if t is None or isinstance(t, pa.Table) else pa.table(t)
                                            for t in (queries, point_matches, line_matches))
    model = as_model(reconstruction)
    kind = _query_camera_kind(queries.column_names, "queries", model)
    _check_column_types(queries.schema, CAMERA_COLUMN_SETS[kind], "queries", queries.column)
    q_ids = _check_ids([("queries", queries.column("query"))], "query", unique=True)
    line_columns = _line_match_columns(kind)
    for table, columns, what in ((point_matches, _point_match_columns(kind, model), "point_matches"),
                                 (line_matches, line_columns, "line_matches")):
        if table is not None:
            _require_columns(table.column_names, columns, what)
            _check_column_types(table.schema, columns, what, table.column)
            _check_ids([(what, table.column("query"))], "query", unique=False)
    if ransac is None:
        ransac = options.ransac if options is not None and options.ransac is not None else _core.RansacOptions()
    base = ransac.to_dict()
    cameras = _query_cameras(queries, kind, model)
    order = stable_order(q_ids)
    q_ids = q_ids[order]
    cameras = [cameras[i] for i in order]
    points, point_values, point_ids, point_camera_ids = _point_matches(point_matches, model, kind)
    lines = _grouped(line_matches, line_columns[1:])
    line_values = _columns(line_matches, LINE_MATCH_COLUMNS[1:]) if lines else np.zeros((0, 10))
    line_camera_ids = line_matches.column("camera_id").to_pylist() if lines and kind == "rig_id" else None

    def rig_cameras(q: int, rows: np.ndarray, camera_ids: Any, sensors: tuple[int, ...], what: str) -> np.ndarray:
        """The index in the rig of the camera of each match, or :class:`_BadQuery` naming the first
        camera_id the rig does not hold."""
        index = {c: k for k, c in enumerate(sensors)}
        cells = [camera_ids[int(r)] for r in rows]
        for cell in cells:
            if not (isinstance(cell, int) or (isinstance(cell, float) and cell.is_integer())) or int(cell) not in index:
                raise _BadQuery(f"query {q}: {what} column camera_id: {shown(cell)} is not a camera of the query's rig "
                                f"(its camera_ids: {', '.join(map(str, sensors))})")
        return np.array([index[int(c)] for c in cells], dtype=np.int64)
    no_rows = np.zeros(0, dtype=np.int64)

    def solve(i: int) -> dict[str, Any]:
        q = int(q_ids[i])
        p_rows, l_rows = points.get(q, no_rows), lines.get(q, no_rows)
        p, segs = point_values[p_rows], line_values[l_rows]
        out: dict[str, Any] = {"R": np.full(9, np.nan), "t": np.full(3, np.nan), "rms": np.nan, "message": "",
                               "pin": np.zeros(len(p), bool), "lin": np.zeros(len(segs), bool),
                               "ids": point_ids[0][p_rows] if point_ids is not None else None}
        try:
            if point_ids is not None and not point_ids[1][p_rows].all():
                unknown = p_rows[~point_ids[1][p_rows]]
                first = int(unknown[0])
                shown = (point_ids[0][first] if point_ids[2][first]
                         else point_matches.column("point3D_id")[first].as_py())
                raise _BadQuery(f"query {q}: point_matches column point3D_id: point3D_id {shown} is not a point of "
                                f"the COLMAP model ({len(unknown)} such match{'es' if len(unknown) > 1 else ''})")
            camera = cameras[i]()
            frame = {}
            if kind == "rig_id":
                camera, sensors = camera
                frame = {"point_cameras": rig_cameras(q, p_rows, point_camera_ids, sensors, "point_matches"),
                         "line_cameras": rig_cameras(q, l_rows, line_camera_ids, sensors, "line_matches")}
            options_q = copy.copy(options) if options is not None else _core.PoseOptions()
            options_q.ransac = _core.RansacOptions(**{**base, "seed": (base["seed"] + seed + q) % 2**63})
            r = _core.estimate_pose(camera, p[:, :2] if len(p) else None, p[:, 2:] if len(p) else None,
                                    segs[:, :4].reshape(-1, 2, 2) if len(segs) else None,
                                    segs[:, 4:].reshape(-1, 2, 3) if len(segs) else None, options=options_q,
                                    **frame)
        except _BadQuery as exc:
            out["status"], out["message"] = Status.INVALID_INPUT.value, str(exc)
            return out
        except (_core.PlueckerError, TypeError) as exc:
            out["status"], out["message"] = Status.INVALID_INPUT.value, f"query {q}: {exc}"
            return out
        out.update(status=r.status, R=np.asarray(r.pose.rotation).reshape(-1), t=np.asarray(r.pose.translation),
                   rms=r.details.rms_error_px,
                   pin=np.asarray(r.inliers_points, dtype=bool), lin=np.asarray(r.inliers_lines, dtype=bool))
        return out

    pool = ThreadPoolExecutor(max_workers=threads or _core.get_num_threads())
    try:
        futures = [pool.submit(solve, i) for i in range(len(q_ids))]
        # The first query that raises ends the call at once, whatever the queries before it are doing
        # (results taken in order would wait for each earlier query first).
        done, _ = wait(futures, return_when=FIRST_EXCEPTION)
        failed = [f for f in futures if f in done and f.exception() is not None]
        if failed:
            raise failed[0].exception()
        solved = [f.result() for f in futures]
    finally:
        # On Ctrl-C (or any error) the queries not started are dropped, not run to the end first.
        pool.shutdown(wait=False, cancel_futures=True)
    poses = pa.table({
        "query": q_ids,
        "R": pa.FixedSizeListArray.from_arrays(np.concatenate([s["R"] for s in solved]) if solved else np.zeros(0), 9),
        "t": pa.FixedSizeListArray.from_arrays(np.concatenate([s["t"] for s in solved]) if solved else np.zeros(0), 3),
        "status": pa.array([s["status"] for s in solved], pa.string()),
        "rms_error_px": np.array([s["rms"] for s in solved], float),
        "point_inliers": np.array([int(s["pin"].sum()) for s in solved], np.int64),
        "line_inliers": np.array([int(s["lin"].sum()) for s in solved], np.int64),
        "message": pa.array([s["message"] for s in solved], pa.string()),
    })
    kinds, query, index, inlier, ids = [], [], [], [], []
    for q, s in zip(q_ids, solved):
        for k, mask in (("point", s["pin"]), ("line", s["lin"])):
            kinds += [k] * len(mask)
            query.append(np.full(len(mask), q, np.int64))
            index.append(np.arange(len(mask), dtype=np.int64))
            inlier.append(mask)
            if model is not None:
                ids.append(s["ids"] if k == "point" else np.full(len(mask), -1, np.int64))
    columns = {
        "query": np.concatenate(query) if query else np.zeros(0, np.int64),
        "kind": pa.array(kinds, pa.string()),
        "index": np.concatenate(index) if index else np.zeros(0, np.int64),
        "inlier": np.concatenate(inlier) if inlier else np.zeros(0, bool),
    }
    if model is not None:
        # The point3D_id of each point match (null for a line match).
        flat = np.concatenate(ids) if ids else np.zeros(0, np.int64)
        columns["point3D_id"] = pa.array(flat, pa.int64(), mask=np.asarray(kinds, dtype=object) != "point")
    return poses, pa.table(columns)


def _localize_bucket(bucket: int, scratch: str, out: str, settings: dict[str, Any]) -> dict[str, Any]:
    """Task 2 of :func:`localize`: one bucket of queries solved and written."""
    queries = _bucket_table(scratch, bucket, "queries")
    if queries is None:
        return {"queries": 0, "statuses": {}}
    poses = _localize_part(out, bucket, settings, queries, _bucket_table(scratch, bucket, "points"),
                           _bucket_table(scratch, bucket, "lines"))
    return {"queries": poses.num_rows, "statuses": _status_counts(poses)}


def _pose_settings(ransac: Any, options: Optional[_core.PoseOptions], seed: int,
                   model: Optional[ColmapModel] = None) -> dict[str, Any]:
    """The options (and COLMAP model) of a localisation job as plain data, for the tasks."""
    return {"ransac": ransac.to_dict() if ransac is not None else None,
            "options": options.to_dict() if options is not None else None, "seed": int(seed), "model": model}


def _localize_part(out: str, part: int, settings: dict[str, Any], *tables: Any) -> Any:
    """:func:`localize_tables` on one part's tables with the job's ``settings``; writes and returns
    its ``poses`` (and ``matches``) as part ``part``."""
    ransac = _core.RansacOptions(**settings["ransac"]) if settings["ransac"] is not None else None
    options = _core.PoseOptions(**settings["options"]) if settings["options"] is not None else None
    poses, matches = localize_tables(*tables, ransac=ransac, options=options, seed=settings["seed"],
                                     reconstruction=settings.get("model"))
    _write_part(out, part, poses=poses, matches=matches)
    return poses


def _check_query_inputs(source: str, model: Optional[ColmapModel]) -> str:
    """Before a job: every query file holds the same one set of camera columns
    (:func:`_query_camera_kind`; the buckets concatenate rows of several files); returns that set's
    kind."""
    import pyarrow.parquet as pq

    _check_inputs(source, ("query",), "queries")
    kinds = {f: _query_camera_kind(pq.read_schema(f).names, f"queries {f}", model) for f in _input_files(source)}
    if len(set(kinds.values())) > 1:
        shown = "; ".join(f"{f}: {k}" for f, k in list(kinds.items())[:4])
        raise _core.ShapeError(f"queries {source}: the files give the cameras by different columns ({shown}); "
                               "use one set of columns in every file")
    for f, kind in kinds.items():
        _check_inputs(f, CAMERA_COLUMN_SETS[kind], "queries")
    # One row per query over every file (the buckets would meet the duplicates only after the split).
    _check_ids([(f"queries {f}", pq.read_table(f, columns=["query"]).column("query")) for f in kinds], "query",
               unique=True)
    return next(iter(kinds.values()), "pinhole")


def localize(queries: Union[str, Path], point_matches: Union[str, Path], out: Union[str, Path], *,
             line_matches: Union[str, Path, None] = None, client: Any = None, buckets: Optional[int] = None,
             ransac: Any = None, options: Optional[_core.PoseOptions] = None, seed: int = 0,
             progress: bool = False, threads_per_worker: Optional[int] = None,
             reconstruction: Any = None) -> JobSummary:
    """Batch localisation: one robust pose per query of the Parquet tables ``queries`` and
    ``point_matches`` (and ``line_matches``), columns of :func:`localize_tables` (cameras as pinhole
    intrinsics, COLMAP models, or a COLMAP model's ``camera_id``; 3-D points as ``X, Y, Z`` or the
    model's ``point3D_id``), written to ``out/poses`` and ``out/matches``. ``reconstruction`` (a
    ``pycolmap.Reconstruction`` or :class:`pluecker.colmap.ColmapModel`) is sent to every worker once. ``ransac``,
    ``options`` and ``seed`` as for :func:`localize_tables`. The tables are split by a hash of
    ``query`` (module docs), so a query's matches meet in one task; results equal :func:`localize_tables`
    on the whole tables. Without ``client`` and ``buckets``, tables of at most :data:`ROWS_PER_BUCKET`
    rows in all are solved as one part, without the split.
    ``client``: a ``distributed.Client`` (``None``: here, without Dask); ``threads_per_worker`` as for
    :func:`triangulate` (the poses of a task run on that many threads). Returns a :class:`JobSummary`
    (``tracks`` counts queries; ``points``/``observations`` are the poses and matches folders)."""
    import pyarrow.parquet as pq

    started = time.perf_counter()
    out = Path(out)
    model = as_model(reconstruction)
    kind = _check_query_inputs(str(queries), model)
    _check_inputs(str(point_matches), _point_match_columns(kind, model), "point_matches")
    if line_matches is not None:
        _check_inputs(str(line_matches), _line_match_columns(kind), "line_matches")
    rows = lambda source: sum(pq.ParquetFile(f).metadata.num_rows for f in _input_files(str(source)))  # noqa: E731
    n = rows(queries)
    workers = len(client.scheduler_info()["workers"]) if client is not None else 1
    inputs = [(str(queries), "query", "queries"), (str(point_matches), "query", "points")]
    if line_matches is not None:
        inputs.append((str(line_matches), "query", "lines"))
    settings = _pose_settings(ransac, options, seed, model)
    # Written into a temporary folder, then ``poses`` and ``matches`` replace those of ``out`` whole:
    # no part of an earlier job (another bucket count) is left among them, and a job that fails or is
    # interrupted leaves ``out`` as it was.
    with staged(out) as stage:
        target = stage.path
        if client is None and buckets is None and sum(rows(source) for source, _, _ in inputs) <= ROWS_PER_BUCKET:
            # Here, and small enough for one task: the whole tables in one part, without the split through
            # storage (the same bits: a query's answer depends on its own rows only).
            pa = _pyarrow()
            tables = [pa.concat_tables([pq.read_table(f) for f in _input_files(source)]) for source, _, _ in inputs]
            poses = _localize_part(str(target), 0, settings, *tables)
            results, buckets = [{"queries": poses.num_rows, "statuses": _status_counts(poses)}], 1
        else:
            buckets = buckets or max(4 * workers, -(-n // 20_000), 1)
            scratch = str(target / "_buckets")
            results = _run_job(client, inputs, buckets, scratch, _localize_bucket, (scratch, str(target), settings),
                               progress, threads_per_worker)
            _remove_tree(Path(scratch))
        if not any(r["queries"] for r in results):
            # No queries: empty ``poses`` and ``matches`` tables, as for :func:`triangulate`.
            tables = [pq.read_schema(_input_files(str(f))[0]).empty_table() for f in (queries, point_matches)]
            _localize_part(str(target), 0, settings, *tables)
    statuses = _tally(results)
    return JobSummary(tracks=sum(r["queries"] for r in results), certified=0, statuses=statuses,
                      seconds=time.perf_counter() - started, points=out / "poses", observations=out / "matches",
                      buckets=buckets, workers=workers)


def _record_camera(camera: Any) -> tuple[str, list[float]]:
    """A query record's camera as ``(COLMAP model name, params)``: ``(fx, fy, cx, cy)`` is a
    ``PINHOLE``; a ``pluecker.Camera``, a ``pycolmap.Camera`` or ``{"model": ..., "params": ...}``
    its model."""
    if isinstance(camera, dict):
        return camera["model"], list(camera["params"])
    if isinstance(camera, _core.Camera):
        return camera.model, list(camera.params)
    if hasattr(camera, "model") and hasattr(camera, "params"):  # pycolmap.Camera
        return getattr(camera.model, "name", camera.model), list(camera.params)
    return "PINHOLE", [float(v) for v in camera]


def queries_to_tables(queries: Iterable[dict[str, Any]]) -> tuple[Any, Any, Any]:
    """The three tables of :func:`localize_tables` from query records: dicts with ``query`` (int),
    ``camera`` (``(fx, fy, cx, cy)``, or a camera model: a ``pluecker.Camera``, a
    ``pycolmap.Camera`` or ``{"model": name, "params": [...]}``), ``points2d`` (n, 2), ``points3d``
    (n, 3) and optionally ``lines2d`` (m, 2, 2), ``lines3d`` (m, 2, 3). The queries table has the
    pinhole columns when every camera is a plain ``(fx, fy, cx, cy)``, else ``model`` and ``params``."""
    pa = _pyarrow()
    q_ids, q_cameras, p_parts, l_parts = [], [], [], []
    for record in queries:
        q = int(record["query"])
        q_ids.append(q)
        q_cameras.append(record["camera"])
        p2, p3 = np.asarray(record.get("points2d", np.zeros((0, 2))), float), np.asarray(
            record.get("points3d", np.zeros((0, 3))), float)
        p_parts.append(np.c_[np.full(len(p2), q), p2.reshape(-1, 2), p3.reshape(-1, 3)])
        l2, l3 = np.asarray(record.get("lines2d", np.zeros((0, 2, 2))), float), np.asarray(
            record.get("lines3d", np.zeros((0, 2, 3))), float)
        l_parts.append(np.c_[np.full(len(l2), q), l2.reshape(-1, 4), l3.reshape(-1, 6)])

    def table(rows: np.ndarray, names: tuple[str, ...]) -> Any:
        rows = rows.reshape(-1, len(names))
        return pa.table({n: rows[:, i].astype(np.int64) if n == "query" else rows[:, i] for i, n in enumerate(names)})

    plain = all(not isinstance(c, (dict, _core.Camera)) and not hasattr(c, "params") for c in q_cameras)
    if plain:
        query_table = table(np.array([(q, *map(float, c)) for q, c in zip(q_ids, q_cameras)], float), QUERY_COLUMNS)
    else:
        models = [_record_camera(c) for c in q_cameras]
        query_table = pa.table({"query": np.array(q_ids, np.int64),
                                "model": pa.array([m for m, _ in models], pa.string()),
                                "params": pa.array([p for _, p in models], pa.list_(pa.float64()))})
    return (query_table, table(np.concatenate(p_parts) if p_parts else np.zeros(0), POINT_MATCH_COLUMNS),
            table(np.concatenate(l_parts) if l_parts else np.zeros(0), LINE_MATCH_COLUMNS))


def localize_bag(bag: Any, out: Union[str, Path], *, ransac: Any = None, options: Optional[_core.PoseOptions] = None,
                 seed: int = 0) -> Any:
    """Batch localisation of a ``dask.bag.Bag`` of query records (:func:`queries_to_tables`): each
    partition solved by :func:`localize_tables` and written as ``out/poses/part-<k>.parquet`` and
    ``out/matches/part-<k>.parquet``. Returns the delayed per-partition query counts (compute them,
    e.g. ``dask.compute(*localize_bag(bag, out))``)."""
    from dask import delayed

    settings = _pose_settings(ransac, options, seed)
    return [delayed(_localize_partition)(part, k, str(out), settings) for k, part in enumerate(bag.to_delayed())]


def _localize_partition(records: list[dict[str, Any]], k: int, out: str, settings: dict[str, Any]) -> int:
    return _localize_part(out, k, settings, *queries_to_tables(records)).num_rows


def read_poses(out: Union[str, Path]) -> Any:
    """The ``poses`` table of a :func:`localize` job, rows in increasing query id."""
    return _read_sorted(Path(out) / "poses", ["query"])


def read_matches(out: Union[str, Path]) -> Any:
    """The ``matches`` table of a :func:`localize` job, rows in increasing query id (stable within)."""
    return _read_sorted(Path(out) / "matches", ["query"])


def read_points(out: Union[str, Path]) -> Any:
    """The ``points`` table of a job, rows in increasing track id (a ``pyarrow.Table``)."""
    return _read_sorted(Path(out) / "points", ["track"])


def read_observations(out: Union[str, Path]) -> Any:
    """The ``observations`` table of a job, rows in increasing track id and, per track, in the
    kernel's order (a ``pyarrow.Table``)."""
    return _read_sorted(Path(out) / "observations", ["track"])


def _read_sorted(folder: Path, keys: Iterable[str]) -> Any:
    """Every part of a job's table ``folder``; ``FileNotFoundError`` (or ``NotADirectoryError``) naming
    it when the job wrote none there."""
    pa = _pyarrow()
    import pyarrow.parquet as pq

    require_folder(folder.parent, "job output ")
    require_folder(folder, f"no {folder.name} table of a job: ")
    files = sorted(folder.glob("*.parquet"))
    if not files:
        raise FileNotFoundError(f"{folder}: no Parquet files (*.parquet): not the {folder.name} table of a job")
    table = pa.concat_tables([pq.read_table(f) for f in files])
    return table.sort_by([(k, "ascending") for k in keys])
