"""The files of a ``pluecker triangulate`` folder (issue 11 §6): ``--help`` lists every file
``load_vgg`` reads and says truly which are optional; a missing file is one line naming it, exit 2; the
counts of the summary come from the tracks, whatever the folder's own 3-D files hold."""

from __future__ import annotations

import contextlib
import io
import json
import re
import shutil

import pytest

from pluecker.cli import main
from pluecker.datasets import vgg_root

HOUSE = vgg_root() / "model_house"
VIEWS = 3

#: A file of the folder → what ``--help`` must say of it.
FILES = {"<prefix>NNN.P": "required", "<prefix>NNN.corners": "required", "<prefix>NNN.lines": "required",
         "p3d or <prefix>p3d": "required", "l3d or <prefix>l3d": "required",
         "nview-corners or <prefix>nview-corners": "optional", "nview-lines or <prefix>nview-lines": "optional"}


@pytest.fixture
def house(tmp_path):
    """Views 0-2 of Model House: exactly the files the help lists, nothing else."""
    folder = tmp_path / "house"
    folder.mkdir()
    for k in range(VIEWS):
        for ext in ("P", "corners", "lines"):
            shutil.copy(HOUSE / f"house.00{k}.{ext}", folder)
    for name in ("p3d", "l3d"):
        shutil.copy(HOUSE / f"house.{name}", folder)
    for name in ("nview-corners", "nview-lines"):
        rows = [r.split()[:VIEWS] for r in (HOUSE / f"house.{name}").read_text().splitlines() if r.strip()]
        (folder / f"house.{name}").write_text("\n".join(" ".join(r) for r in rows) + "\n")
    return folder


def run(argv) -> tuple[int, str, str]:
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        status = main(argv)
    return status, out.getvalue(), err.getvalue()


def test_help_lists_every_file_and_whether_it_is_required(monkeypatch):
    monkeypatch.setenv("COLUMNS", "1000")
    status, text, _ = run(["triangulate", "--help"])
    assert status == 0
    for name, need in FILES.items():
        assert re.search(re.escape(name) + r"\s+" + need, text), name
    assert "also without --lines" in text


@pytest.mark.parametrize("missing", ["house.nview-corners", "house.nview-lines"])
def test_the_optional_files_are_optional(house, tmp_path, missing):
    (house / missing).unlink()
    status, out, err = run(["triangulate", str(house), "--lines", "--method", "linear", "--out", str(tmp_path / "out")])
    assert status == 0 and err == ""
    kind = "points" if missing.endswith("corners") else "lines"
    assert f"{kind}: no tracks ({missing.split('.', 1)[1]} missing or empty)" in out
    doc = json.loads((tmp_path / "out" / f"{kind}.json").read_text())
    assert doc["summary"]["tracks"] == 0 and doc["summary"]["skipped"] == 0 and doc[kind] == []


@pytest.mark.parametrize("missing, why", [
    ("house.001.corners", "needs <prefix>NNN.corners"),
    ("house.002.lines", "also without --lines"),
    ("house.p3d", "3-D points file"),
    ("house.l3d", "3-D segments file"),
])
def test_a_missing_required_file_is_one_line_naming_it(house, tmp_path, missing, why):
    (house / missing).unlink()
    status, out, err = run(["triangulate", str(house), "--out", str(tmp_path / "out")])
    assert status == 2 and out == ""
    assert err.startswith("pluecker triangulate: error: ") and err.count("\n") == 1
    assert "Errno" not in err and "Traceback" not in err
    named = missing if missing.count(".") == 2 else missing.split(".", 1)[1]  # p3d / l3d: the name looked for
    assert f"{named}: no such file" in err and why in err


def test_an_unreadable_file_is_one_line_without_errno(house, tmp_path):
    (house / "house.000.corners").unlink()
    (house / "house.000.corners").mkdir()  # a directory where a file should be: IsADirectoryError
    status, _, err = run(["triangulate", str(house), "--out", str(tmp_path / "out")])
    assert status == 2 and err.count("\n") == 1
    assert "Errno" not in err and "house.000.corners" in err


def test_counts_come_from_the_tracks_with_an_empty_p3d(house, tmp_path):
    """An empty 3-D points file printed "500 of 0 triangulated (-500 seen ...)" and wrote ``"skipped": -500``."""
    tracks = len([r for r in (house / "house.nview-corners").read_text().splitlines() if r.strip()])
    (house / "house.p3d").write_text("")
    (house / "house.l3d").write_text("")
    status, out, _ = run(["triangulate", str(house), "--lines", "--method", "linear", "--out", str(tmp_path / "out")])
    assert status == 0
    for kind, file in (("points", "house.nview-corners"), ("lines", "house.nview-lines")):
        rows = len([r for r in (house / file).read_text().splitlines() if r.strip()])
        summary = json.loads((tmp_path / "out" / f"{kind}.json").read_text())["summary"]
        assert summary["tracks"] == rows > 0
        assert summary["skipped"] == rows - summary["triangulated"] >= 0
        assert f"{kind}: {summary['triangulated']} of {rows} triangulated ({summary['skipped']} seen" in out
    assert tracks == 672


def test_counts_come_from_the_tracks_with_a_longer_p3d(house, tmp_path):
    p3d = house / "house.p3d"
    p3d.write_text(p3d.read_text() + "1 2 3\n" * 50)
    status, out, _ = run(["triangulate", str(house), "--out", str(tmp_path / "out")])
    assert status == 0
    summary = json.loads((tmp_path / "out" / "points.json").read_text())["summary"]
    assert summary["tracks"] == 672 and summary["triangulated"] + summary["skipped"] == 672
