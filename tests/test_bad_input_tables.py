"""Tables and files that were reported with the wrong error, or none naming what is wrong:
``pluecker.distributed`` tables without their columns (a bare ``KeyError`` from pyarrow), an
unwritable ``localize --out`` (reported as "cannot read the tables"), and ``colmap.retriangulate``
with a σ that is not a positive number (``sigma_px=-1`` certified every track)."""

from __future__ import annotations

import math
import re

import numpy as np
import pytest

import pluecker
from pluecker import InvalidOptionError, ShapeError

pa = pytest.importorskip("pyarrow")
pq = pytest.importorskip("pyarrow.parquet")

from pluecker import distributed as dist  # noqa: E402
from pluecker.cli import main  # noqa: E402

CAMERAS = dist.Cameras(np.array([3, 13]), np.stack([np.hstack([np.eye(3), [[-b], [0.0], [0.0]]]) for b in (0, 0.5)]))


def observations(**drop):
    """Two rows of one track, without the columns named in ``drop``."""
    columns = {"track": [7, 7], "image": [3, 13], "x": [0.1, 0.0], "y": [0.0, 0.0]}
    return pa.table({k: v for k, v in columns.items() if k not in drop})


@pytest.mark.parametrize("table, missing", [
    (pa.table({}), "track, image, x, y"),
    (observations(x=1), "x"),
    (observations(track=1, image=1), "track, image"),
], ids=["no-columns", "no-x", "no-ids"])
def test_an_observation_table_without_its_columns_names_them(table, missing):
    with pytest.raises(ShapeError, match=rf"^observations: missing column\(s\) {missing}; expected the columns "
                                         r"track, image, x, y"):
        dist.triangulate_table(table, CAMERAS)


def test_an_empty_observation_table_with_its_columns_is_an_empty_answer():
    points, obs = dist.triangulate_table(observations().slice(0, 0), CAMERAS)
    assert points.num_rows == 0 and obs.num_rows == 0


def test_a_job_on_files_without_the_columns_fails_before_it_starts(tmp_path):
    """The split tasks raised ``KeyError: Field "x" does not exist in schema`` from inside the job."""
    (tmp_path / "in").mkdir()
    pq.write_table(observations(x=1), tmp_path / "in" / "a.parquet")
    with pytest.raises(ShapeError, match=r"^observations .*a\.parquet: missing column\(s\) x"):
        dist.triangulate(tmp_path / "in", CAMERAS, tmp_path / "out")
    assert not (tmp_path / "out").exists()
    (tmp_path / "empty").mkdir()
    with pytest.raises(ShapeError, match=r"no Parquet files"):
        dist.triangulate(tmp_path / "empty", CAMERAS, tmp_path / "out")


QUERIES = {"query": [1], "fx": [800.0], "fy": [800.0], "cx": [320.0], "cy": [240.0]}
POINTS = {"query": [1], "x": [0.0], "y": [0.0], "X": [0.0], "Y": [0.0], "Z": [1.0]}


@pytest.mark.parametrize("which, missing", [("queries", "fx"), ("point_matches", "Z"), ("queries", "query")])
def test_localisation_tables_without_their_columns_name_them(which, missing):
    tables = {"queries": dict(QUERIES), "point_matches": dict(POINTS)}
    del tables[which][missing]
    with pytest.raises(ShapeError, match=rf"^{which}: missing column\(s\) {missing}"):
        dist.localize_tables(pa.table(tables["queries"]), pa.table(tables["point_matches"]))
    with pytest.raises(ShapeError, match=r"^queries: missing column\(s\) query, fx, fy, cx, cy"):
        dist.localize_tables(pa.table({}), pa.table({}))


def localisation_files(tmp_path, queries=QUERIES):
    paths = []
    for name, columns in (("queries", queries), ("points", POINTS)):
        (tmp_path / name).mkdir()
        pq.write_table(pa.table(columns), tmp_path / name / "t.parquet")
        paths.append(str(tmp_path / name / "t.parquet"))
    return paths


def test_localize_on_the_command_line_names_a_missing_column(tmp_path, capsys):
    queries = {k: v for k, v in QUERIES.items() if k != "cy"}
    assert main(["localize", *localisation_files(tmp_path, queries), "--out", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err
    assert err.startswith("pluecker localize: error: ") and "missing column(s) cy" in err, err


@pytest.mark.parametrize("out", ["file", "under-a-file"])
def test_an_unwritable_localize_out_is_reported_as_such(tmp_path, capsys, out):
    """``--out`` that cannot be written was reported as "cannot read the tables"."""
    paths = localisation_files(tmp_path)
    (tmp_path / "file").write_text("not a folder")
    target = tmp_path / "file" if out == "file" else tmp_path / "file" / "out"
    assert main(["localize", *paths, "--out", str(target)]) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"pluecker localize: error: cannot write --out {target}: "), err
    assert "cannot read" not in err and err.count("\n") == 1, err


def test_localize_still_runs_into_a_new_folder(tmp_path, capsys):
    assert main(["localize", *localisation_files(tmp_path), "--out", str(tmp_path / "new" / "out")]) == 0
    assert dist.read_poses(tmp_path / "new" / "out").num_rows == 1


@pytest.mark.parametrize("sigma", [-1.0, 0.0, -0.0, math.nan, math.inf, 10**400, True, "1"])
def test_retriangulate_refuses_a_sigma_that_is_not_a_positive_number(sigma):
    """``colmap.retriangulate(sigma_px=-1)`` squared σ into the covariance and certified every track."""
    pycolmap = pytest.importorskip("pycolmap")
    from pluecker import colmap

    options = pycolmap.SyntheticDatasetOptions()
    options.num_frames_per_rig, options.num_points3D = 3, 5
    pycolmap.set_random_seed(1)
    rec = pycolmap.synthesize_dataset(options)
    with pytest.raises(InvalidOptionError, match=r"^sigma_px: must be a positive finite number of pixels, got "):
        colmap.retriangulate(rec, sigma_px=sigma)
    with pytest.raises(InvalidOptionError, match=r"^sigma_px: "):
        colmap.observation_table(rec, sigma)
    ids, result = colmap.retriangulate(rec, sigma_px=0.5)
    assert len(ids) == len(result) == len(rec.points3D) > 0


@pytest.mark.parametrize("sigma", [-1.0, 0.0, math.nan, True])
def test_a_distributed_job_refuses_a_sigma_that_is_not_a_positive_number(tmp_path, sigma):
    """``sigma_px=-1`` squared into the covariance as in ``colmap.retriangulate``."""
    with pytest.raises(InvalidOptionError, match=r"^sigma_px: must be a positive finite number of pixels"):
        dist.triangulate_table(observations(), CAMERAS, sigma_px=sigma)
    (tmp_path / "in").mkdir()
    pq.write_table(observations(), tmp_path / "in" / "a.parquet")
    with pytest.raises(InvalidOptionError, match=r"^sigma_px: "):
        dist.triangulate(tmp_path / "in", CAMERAS, tmp_path / "out", sigma_px=sigma)


def test_a_job_on_a_table_without_rows_writes_empty_result_tables(tmp_path):
    """An input with the columns but no rows: reading the result raised pyarrow's "Must pass at least one
    table"; it is now the empty tables, with the columns of a job's result."""
    (tmp_path / "in").mkdir()
    pq.write_table(observations().slice(0, 0), tmp_path / "in" / "a.parquet")
    reference = dist.triangulate_table(observations(), CAMERAS)
    for partitioned in (False, True):
        out = tmp_path / f"out-{partitioned}"
        summary = dist.triangulate(tmp_path / "in", CAMERAS, out, partitioned=partitioned)
        assert summary.tracks == 0 and summary.statuses == {}
        points, obs = dist.read_points(out), dist.read_observations(out)
        assert points.num_rows == obs.num_rows == 0
        assert points.schema.names == reference[0].schema.names and obs.schema.names == reference[1].schema.names
    paths = localisation_files(tmp_path, {k: [] for k in QUERIES})
    summary = dist.localize(*paths, tmp_path / "poses")
    assert summary.tracks == 0
    assert dist.read_poses(tmp_path / "poses").num_rows == dist.read_matches(tmp_path / "poses").num_rows == 0


# --- column types and query ids ------------------------------------------------------------------------------


def query_scene(n: int = 30):
    """A pinhole query with ``n`` exact matches: its queries and point-match columns."""
    scene = pluecker.random_scene("general", n_points=n, n_lines=0, seed=0)
    cam, p2, p3 = scene["camera"], np.asarray(scene["points2d"]), np.asarray(scene["points3d"])
    queries = {"query": [4], "fx": [cam.fx], "fy": [cam.fy], "cx": [cam.cx], "cy": [cam.cy]}
    matches = {"query": np.full(n, 4, np.int64), "x": p2[:, 0], "y": p2[:, 1], "X": p3[:, 0], "Y": p3[:, 1],
               "Z": p3[:, 2]}
    return queries, matches


BAD_TABLES = {
    # A boolean pixel column was read as 0/1 and gave "success" with 7 of 30 inliers.
    "bool x": ("point_matches", lambda q, m: (q, {**m, "x": m["x"] > 300}),
               r"point_matches column x, row 0: (True|False) is a bool, expected a number"),
    "text x": ("point_matches", lambda q, m: (q, {**m, "x": pa.array([str(float(v)) for v in m["x"]])}),
               r"point_matches column x, row 0: '.*' is text, expected a number"),
    "text fx": ("queries", lambda q, m: ({**q, "fx": ["400"]}, m),
                r"queries column fx, row 0: '400' is text, expected a number"),
    "float query": ("queries", lambda q, m: ({**q, "query": [0.5]}, {**m, "query": np.full(len(m["x"]), 0.5)}),
                    r"queries column query, row 0: 0.5 is not an integer id"),
    "null query": ("queries", lambda q, m: ({**q, "query": pa.array([None], pa.int64())}, m),
                   r"queries column query, row 0: null is not an integer id"),
    "float match query": ("point_matches", lambda q, m: (q, {**m, "query": np.r_[4.0, np.full(len(m["x"]) - 1, 4.5)]}),
                          r"point_matches column query, row 1: 4.5 is not an integer id"),
    "duplicate query": ("queries", lambda q, m: ({k: v * 2 for k, v in q.items()}, m),
                        r"queries column query, rows 0 and 1: query 4 is listed twice"),
}


@pytest.mark.parametrize("case", list(BAD_TABLES))
def test_localisation_tables_of_the_wrong_types_or_ids_are_refused_naming_table_column_and_row(tmp_path, capsys, case):
    """Each of these was converted silently (text and bools to numbers, 0.5 to query 0) or solved twice
    (two poses for one query)."""
    _, edit, message = BAD_TABLES[case]
    queries, matches = edit(*query_scene())
    with pytest.raises(InvalidOptionError, match="^" + message):
        dist.localize_tables(pa.table(queries), pa.table(matches))
    paths = []
    for name, columns in (("queries", queries), ("points", matches)):
        pq.write_table(pa.table(columns), tmp_path / f"{name}.parquet")
        paths.append(str(tmp_path / f"{name}.parquet"))
    # The job checks before it starts, naming the file: here and split into buckets.
    for buckets in (None, 3):
        with pytest.raises(InvalidOptionError, match=r"^(queries|point_matches) .*\.parquet column "):
            dist.localize(*paths, tmp_path / "job", buckets=buckets)
    assert not (tmp_path / "job").exists()
    assert main(["localize", *paths, "--out", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err
    # The command line reads files: the message names the file after the table.
    assert err.count("\n") == 1 and re.search(message.replace(" column ", " .*column ", 1), err), err
    assert "cannot read" not in err
    assert not (tmp_path / "out").exists()


def test_well_typed_tables_still_localise_integer_valued_float_ids_included():
    queries, matches = query_scene()
    poses, _ = dist.localize_tables(pa.table({**queries, "query": [4.0]}), pa.table({**matches, "query": 4.0 + 0 * matches["x"]}))
    assert poses.column("query").to_pylist() == [4] and poses.column("status").to_pylist() == ["success"]
    assert poses.column("point_inliers").to_pylist() == [30]


def test_duplicate_queries_in_two_files_are_named_with_both_files(tmp_path):
    queries, matches = query_scene()
    (tmp_path / "q").mkdir()
    for name in ("a", "b"):
        pq.write_table(pa.table(queries), tmp_path / "q" / f"{name}.parquet")
    pq.write_table(pa.table(matches), tmp_path / "m.parquet")
    with pytest.raises(InvalidOptionError, match=r"^queries .*a\.parquet column query, row 0, and queries .*b\.parquet "
                                                 r"row 0: query 4 is listed twice"):
        dist.localize(tmp_path / "q", tmp_path / "m.parquet", tmp_path / "out")


def test_an_observation_table_of_the_wrong_types_is_refused():
    """The same for the observations of ``pluecker.distributed.triangulate``."""
    with pytest.raises(InvalidOptionError, match=r"^observations column x, row 0: True is a bool"):
        dist.triangulate_table(observations().set_column(2, "x", pa.array([True, False])), CAMERAS)
    with pytest.raises(InvalidOptionError, match=r"^observations column image, row 1: 13.5 is not an integer id"):
        dist.triangulate_table(observations().set_column(1, "image", pa.array([3.0, 13.5])), CAMERAS)


def test_reading_a_job_that_is_not_there_names_the_folder(tmp_path):
    """``read_poses("missing")`` raised pyarrow's ``ArrowInvalid: Must pass at least one table``."""
    for read in (dist.read_poses, dist.read_matches, dist.read_points, dist.read_observations):
        with pytest.raises(FileNotFoundError, match=r"missing: no such directory"):
            read(tmp_path / "missing")
        with pytest.raises(FileNotFoundError, match=r"no such directory"):
            read(tmp_path)
    (tmp_path / "poses").mkdir()
    with pytest.raises(FileNotFoundError, match=r"poses: no Parquet files"):
        dist.read_poses(tmp_path)
