"""Every command-line failure prints one line on standard error and exits 2, never a traceback or a
numpy warning (docs/cli.md, issue 10 §5): hostile JSON for ``pose`` and corrupted VGG folders for
``triangulate``."""

from __future__ import annotations

import json
import shutil
import warnings

import pytest

import pluecker
from pluecker.cli import main
from pluecker.datasets import vgg_root

HOUSE = vgg_root() / "model_house"


def pose_document() -> dict:
    scene = pluecker.random_scene("general", 8, 2, seed=3)
    cam = scene["camera"]
    return {"camera": {"fx": cam.fx, "fy": cam.fy, "cx": cam.cx, "cy": cam.cy},
            "points2d": scene["points2d"].tolist(), "points3d": scene["points3d"].tolist()}


def assert_one_line_exit_2(argv, capsys, command: str, *words: str) -> str:
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # a numpy RuntimeWarning would fail the run
        status = main(argv)
    captured = capsys.readouterr()
    assert status == 2, captured
    assert captured.out == ""
    assert captured.err.startswith(f"pluecker {command}: error: "), captured.err
    assert captured.err.count("\n") == 1 and "Traceback" not in captured.err, captured.err
    for word in words:
        assert word in captured.err, captured.err
    return captured.err


# --- pose --------------------------------------------------------------------------------------------


def test_deeply_nested_json(tmp_path, capsys):
    """``[[[[...]]]]`` 100000 deep raised RecursionError with a traceback."""
    path = tmp_path / "deep.json"
    path.write_text("[" * 100_000 + "]" * 100_000)
    assert_one_line_exit_2(["pose", str(path)], capsys, "pose", "nested")
    doc = pose_document()
    doc["points2d"] = json.loads("[" * 50 + "]" * 50)
    text = json.dumps(doc).replace('[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]',
                                   "[" * 100_000 + "]" * 100_000)
    path.write_text(text)
    assert_one_line_exit_2(["pose", str(path)], capsys, "pose")


@pytest.mark.parametrize("where", ["option", "camera", "points2d", "initial_pose"])
def test_a_400_digit_integer(tmp_path, capsys, where):
    """A 400-digit integer raised OverflowError with a traceback."""
    doc = pose_document()
    big = 10**400
    if where == "option":
        doc["options"] = {"max_iterations": big}
    elif where == "camera":
        doc["camera"]["fx"] = big
    elif where == "points2d":
        doc["points2d"][0][0] = big
    else:
        doc["options"] = {"initial_pose": {"R": [[big, 0, 0], [0, 1, 0], [0, 0, 1]], "t": [0, 0, 0]}}
    path = tmp_path / "big.json"
    path.write_text(json.dumps(doc))
    assert_one_line_exit_2(["pose", str(path)], capsys, "pose")


def test_an_integer_beyond_the_json_digit_limit(tmp_path, capsys):
    """Python refuses to parse integers of more than 4300 digits (ValueError, not JSONDecodeError)."""
    doc = pose_document()
    text = json.dumps(doc).replace('"points2d": [[', '"points2d": [[' + "9" * 5000 + ", ", 1)
    path = tmp_path / "huge.json"
    path.write_text(text)
    assert_one_line_exit_2(["pose", str(path)], capsys, "pose")


# --- triangulate ---------------------------------------------------------------------------------------


@pytest.fixture
def house_copy(tmp_path):
    """Views 0-2 of Model House with their tracks, in a folder the test may corrupt."""
    folder = tmp_path / "house"
    folder.mkdir()
    for k in range(3):
        for ext in ("P", "corners", "lines"):
            shutil.copy(HOUSE / f"house.00{k}.{ext}", folder)
    for name in ("p3d", "l3d"):
        shutil.copy(HOUSE / f"house.{name}", folder)
    for name in ("nview-corners", "nview-lines"):
        rows = [r.split()[:3] for r in (HOUSE / f"house.{name}").read_text().splitlines() if r.strip()]
        (folder / f"house.{name}").write_text("\n".join(" ".join(r) for r in rows) + "\n")
    return folder


def test_the_house_copy_triangulates(house_copy, tmp_path, capsys):
    assert main(["triangulate", str(house_copy), "--out", str(tmp_path / "out")]) == 0


def test_a_track_index_beyond_the_corners(house_copy, tmp_path, capsys):
    """A track pointing past the last row of a ``.corners`` file raised IndexError."""
    n = len((house_copy / "house.001.corners").read_text().split("\n")) + 5
    tracks = house_copy / "house.nview-corners"
    tracks.write_text(tracks.read_text() + f"0 {n} *\n")
    assert_one_line_exit_2(["triangulate", str(house_copy), "--out", str(tmp_path / "o")], capsys, "triangulate",
                           "house.nview-corners", "house.001.corners", str(n))


def test_a_track_index_beyond_the_lines(house_copy, tmp_path, capsys):
    tracks = house_copy / "house.nview-lines"
    tracks.write_text(tracks.read_text() + "* 100000 0\n")
    assert_one_line_exit_2(["triangulate", str(house_copy), "--lines", "--out", str(tmp_path / "o")], capsys,
                           "triangulate", "house.nview-lines", "house.001.lines")


def test_an_empty_corners_file(house_copy, tmp_path, capsys):
    """An empty ``.corners`` file that the tracks refer to raised IndexError."""
    (house_copy / "house.002.corners").write_text("")
    assert_one_line_exit_2(["triangulate", str(house_copy), "--out", str(tmp_path / "o")], capsys, "triangulate",
                           "house.002.corners")


@pytest.mark.parametrize("value", ["nan", "inf", "-inf"])
def test_a_non_finite_camera_names_the_file(house_copy, tmp_path, capsys, value):
    """A NaN in a ``.P`` file printed a numpy RuntimeWarning, and the message did not name the file."""
    path = house_copy / "house.001.P"
    rows = path.read_text().split("\n")
    rows[1] = f"{value} " + " ".join(rows[1].split()[1:])
    path.write_text("\n".join(rows))
    assert_one_line_exit_2(["triangulate", str(house_copy), "--out", str(tmp_path / "o")], capsys, "triangulate",
                           "house.001.P", "line 2")


def test_a_non_numeric_entry_names_the_file(house_copy, tmp_path, capsys):
    path = house_copy / "house.000.corners"
    path.write_text("12.5 abc\n" + path.read_text())
    assert_one_line_exit_2(["triangulate", str(house_copy), "--out", str(tmp_path / "o")], capsys, "triangulate",
                           "house.000.corners")


def test_a_negative_track_index(house_copy, tmp_path, capsys):
    tracks = house_copy / "house.nview-corners"
    tracks.write_text(tracks.read_text() + "0 -3 1\n")
    assert_one_line_exit_2(["triangulate", str(house_copy), "--out", str(tmp_path / "o")], capsys, "triangulate",
                           "house.nview-corners", "-3")


# --- pose: JSON values that are not numbers ------------------------------------------------------------


def pose_document_with_everything() -> dict:
    """Points and lines with their covariances, ``camera.K`` and an ``initial_pose``: every array field."""
    scene = pluecker.random_scene("general", 8, 4, seed=3)
    K = scene["camera"].K
    return {"camera": {"K": K.tolist()},
            "points2d": scene["points2d"].tolist(), "points3d": scene["points3d"].tolist(),
            "lines2d": scene["lines2d"].tolist(), "lines3d": scene["lines3d"].tolist(),
            "point_covariances": [[[1.0, 0.0], [0.0, 1.0]] for _ in range(8)],
            "line_covariances": [[[1.0, 0.0], [0.0, 1.0]] for _ in range(4)],
            "options": {"initial_pose": {"R": scene["R"].tolist(), "t": scene["t"].tolist()}}}


#: (path of an entry in the document, how it is printed in the message).
ENTRIES = [
    (("points2d", 0, 0), "points2d[0][0]"),
    (("points3d", 3, 2), "points3d[3][2]"),
    (("lines2d", 1, 0, 1), "lines2d[1][0][1]"),
    (("lines3d", 2, 1, 0), "lines3d[2][1][0]"),
    (("camera", "K", 0, 0), "camera.K[0][0]"),
    (("point_covariances", 4, 1, 1), "point_covariances[4][1][1]"),
    (("line_covariances", 3, 0, 1), "line_covariances[3][0][1]"),
    (("options", "initial_pose", "R", 1, 1), "initial_pose.R[1][1]"),
    (("options", "initial_pose", "t", 2), "initial_pose.t[2]"),
]


@pytest.mark.parametrize("path, shown", ENTRIES, ids=[e[1] for e in ENTRIES])
@pytest.mark.parametrize("value", [True, False, "118.6", "1e3", None])
def test_a_json_bool_or_string_in_an_array_is_refused_not_coerced(tmp_path, capsys, path, shown, value):
    """``"points2d": [[true, 118.6], ...]`` ran as 1.0 and gave ``success`` at 31 px RMS; numeric
    strings were parsed. Every array field refuses them, naming the entry."""
    doc = pose_document_with_everything()
    where = doc
    for key in path[:-1]:
        where = where[key]
    where[path[-1]] = value
    (tmp_path / "in.json").write_text(json.dumps(doc))
    assert_one_line_exit_2(["pose", str(tmp_path / "in.json")], capsys, "pose",
                           f"'{shown}' must be a number, got {json.dumps(value)}")


def test_the_document_with_every_array_field_runs(tmp_path, capsys):
    """The document the test above corrupts is valid as it is."""
    (tmp_path / "in.json").write_text(json.dumps(pose_document_with_everything()))
    assert main(["pose", str(tmp_path / "in.json")]) == 0
    assert json.loads(capsys.readouterr().out)["status"] == "success"


# --- triangulate: camera files ----------------------------------------------------------------------------


@pytest.mark.parametrize("rows", [2, 4])
def test_a_camera_file_without_three_rows_names_the_file(house_copy, tmp_path, capsys, rows):
    """A 2-row ``.P`` file raised numpy's "cannot reshape array of size 8 into shape (3,4)"."""
    path = house_copy / "house.002.P"
    lines = [line for line in path.read_text().splitlines() if line.strip()]
    path.write_text("\n".join((lines * 2)[:rows]) + "\n")
    assert_one_line_exit_2(["triangulate", str(house_copy), "--out", str(tmp_path / "o")], capsys, "triangulate",
                           "house.002.P", f"3x4 camera matrix (3 rows of 4 numbers), got {rows} rows")


@pytest.mark.parametrize("flags", [["--text"], ["--outlier-threshold", "3"]])
def test_colmap_only_flags_with_a_vgg_folder_are_refused_by_name(tmp_path, capsys, flags):
    """``--text`` and ``--outlier-threshold`` act on COLMAP models only: with a VGG folder they are an
    error naming the flag (they used to be ignored without a word), and nothing is written."""
    out = tmp_path / "out"
    assert main(["triangulate", str(vgg_root() / "corridor"), *flags, "--out", str(out)]) == 2
    assert f"{flags[0]} applies to --colmap models" in capsys.readouterr().err
    assert not out.exists()


# --- the file's options are checked before the flags override them -------------------------------------------


@pytest.mark.parametrize("certify, words", [
    ({"max_relative_gap": float("nan")}, "max_relative_gap"),
    ("yes", "'options.certify' must be true, false or a JSON object"),
    ({"max_nodes": -5}, "max_nodes"),
    ({"max_nodes": 2**70}, "max_nodes"),
    ({"max_gap": 0.1}, "options.certify"),
])
def test_an_invalid_certify_object_is_refused_with_and_without_the_flag(tmp_path, capsys, certify, words):
    """``--certify`` replaced an invalid ``options.certify`` object by the defaults and reported
    ``success``; without the flag the same file was refused."""
    doc = pose_document()
    doc["options"] = {"certify": certify}
    path = tmp_path / "in.json"
    path.write_text(json.dumps(doc))
    for flags in ([], ["--certify"]):
        assert_one_line_exit_2(["pose", str(path), *flags], capsys, "pose", words)


@pytest.mark.parametrize("options, flag", [
    ({"options": {"sigma_px": -1.0}}, ["--sigma", "2"]),
    ({"options": {"penalty": 0}}, ["--penalty", "10"]),
    ({"ransac": {"point_threshold": -1.0}}, ["--point-threshold", "2"]),
    ({"ransac": {"seed": -1}}, ["--seed", "3"]),
])
def test_a_flag_does_not_hide_an_invalid_setting_of_the_file(tmp_path, capsys, options, flag):
    doc = {**pose_document(), **options}
    path = tmp_path / "in.json"
    path.write_text(json.dumps(doc))
    for flags in ([], flag):
        assert_one_line_exit_2(["pose", str(path), *flags], capsys, "pose")


def test_the_certify_flag_keeps_the_files_certify_settings(tmp_path, capsys):
    """``--certify`` replaced ``{"max_nodes": 100}`` of the file by the defaults (1201 nodes, certified);
    it turns the certificate on and keeps the file's settings: the same result as without the flag."""
    # The six points of docs/cli.md's example (rounded to 0.01 px): the certificate needs about 1200 nodes.
    doc = {"camera": {"fx": 800.0, "fy": 800.0, "cx": 320.0, "cy": 240.0},
           "points2d": [[167.79, 118.6], [485.55, 226.3], [349.02, 322.91], [88.87, 99.2], [277.86, 202.3],
                        [394.4, 282.73]],
           "points3d": [[2.5124, 1.7405, -6.4687], [5.0523, 0.8626, -5.4563], [4.8769, -0.0934, -7.5085],
                        [2.0987, 2.07, -7.5823], [3.8452, 1.1438, -7.1353], [4.2382, 0.3731, -5.6591]],
           "options": {"certify": {"max_nodes": 100, "max_relative_gap": 1e-3}}}
    path = tmp_path / "in.json"
    path.write_text(json.dumps(doc))
    results = []
    for flags in ([], ["--certify"]):
        assert main(["pose", str(path), *flags]) == 0
        result = json.loads(capsys.readouterr().out)
        results.append((result["status"], result["certified"], result["details"]["uncertified_reason"],
                        (result["certificate"] or {}).get("nodes")))
    assert results[0] == results[1]
    assert results[0][0] == "gap_not_closed" and results[0][1] is False, results
    # With certify off in the file, the flag turns it on with the defaults.
    doc["options"] = {"certify": False}
    path.write_text(json.dumps(doc))
    assert main(["pose", str(path), "--certify"]) == 0
    assert json.loads(capsys.readouterr().out)["certificate"] is not None
