"""What the commands write: never over an input or into an input model's folder (same path, ``./``,
``..``, symlinks), no stale files of the other model format, and nothing new, empty or half-written
after a failed or interrupted run (everything is written into a temporary folder and renamed)."""

from __future__ import annotations

import json
import os
import shutil

import numpy as np
import pytest

import pluecker
from pluecker.cli import main
from pluecker.datasets import vgg_root

pa = pytest.importorskip("pyarrow")
pq = pytest.importorskip("pyarrow.parquet")
pycolmap = pytest.importorskip("pycolmap")

from pluecker import colmap  # noqa: E402
from pluecker import distributed as dist  # noqa: E402

HOUSE = vgg_root() / "model_house"


def snapshot(*folders) -> dict[str, bytes]:
    """Every file under ``folders`` (and the files themselves) by path, with its bytes."""
    out = {}
    for folder in folders:
        paths = [folder] if folder.is_file() else sorted(p for p in folder.rglob("*") if p.is_file())
        out.update({str(p): p.read_bytes() for p in paths})
    return out


def one_line_exit_2(argv, capsys, *words) -> str:
    assert main([str(a) for a in argv]) == 2
    captured = capsys.readouterr()
    assert captured.out == "" and captured.err.count("\n") == 1 and "Traceback" not in captured.err, captured
    for word in words:
        assert word in captured.err, captured.err
    return captured.err


@pytest.fixture
def inputs(tmp_path):
    """A pose document, a VGG folder (3 views of Model House), a COLMAP model and localisation tables."""
    scene = pluecker.random_scene("general", 8, 2, seed=3)
    cam = scene["camera"]
    (tmp_path / "scene.json").write_text(json.dumps({
        "camera": {"fx": cam.fx, "fy": cam.fy, "cx": cam.cx, "cy": cam.cy},
        "points2d": scene["points2d"].tolist(), "points3d": scene["points3d"].tolist()}))
    vgg = tmp_path / "house"
    vgg.mkdir()
    for name in ["house.p3d", "house.l3d", "house.nview-corners", "house.nview-lines",
                 *[f"house.00{k}.{ext}" for k in range(3) for ext in ("P", "corners", "lines")]]:
        shutil.copy(HOUSE / name, vgg)
    rows = [r.split()[:3] for r in (HOUSE / "house.nview-corners").read_text().splitlines() if r.strip()]
    (vgg / "house.nview-corners").write_text("\n".join(" ".join(r) for r in rows) + "\n")
    (vgg / "house.nview-lines").write_text("")
    options = pycolmap.SyntheticDatasetOptions()
    options.num_frames_per_rig, options.num_points3D = 4, 30
    pycolmap.set_random_seed(2)
    rec = pycolmap.synthesize_dataset(options)
    (tmp_path / "model").mkdir()
    rec.write(str(tmp_path / "model"))
    queries = {"query": [], "camera_id": []}
    matches = {"query": [], "x": [], "y": [], "point3D_id": []}
    for image in rec.images.values():
        queries["query"].append(image.image_id)
        queries["camera_id"].append(image.camera_id)
        for keypoint in image.points2D:
            if keypoint.has_point3D():
                matches["query"].append(image.image_id)
                matches["x"].append(keypoint.xy[0])
                matches["y"].append(keypoint.xy[1])
                matches["point3D_id"].append(keypoint.point3D_id)
    (tmp_path / "tables").mkdir()
    pq.write_table(pa.table(queries), tmp_path / "tables" / "queries.parquet")
    pq.write_table(pa.table(matches), tmp_path / "tables" / "matches.parquet")
    os.symlink(tmp_path / "scene.json", tmp_path / "scene-link.json")
    os.symlink(tmp_path / "model", tmp_path / "model-link")
    os.symlink(vgg, tmp_path / "house-link")
    return tmp_path


def test_pose_never_writes_over_its_input(inputs, capsys, monkeypatch):
    """``pluecker pose scene.json -o scene.json`` exited 0 and replaced the correspondences with the result."""
    before = snapshot(inputs)
    monkeypatch.chdir(inputs / "house")
    for out in ("../scene.json", inputs / "scene.json", "./../scene.json", inputs / "model" / ".." / "scene.json",
                inputs / "scene-link.json"):
        one_line_exit_2(["pose", inputs / "scene.json", "-o", out], capsys, "is the input INPUT")
    one_line_exit_2(["pose", inputs / "scene-link.json", "-o", inputs / "scene.json"], capsys, "is the input INPUT")
    assert snapshot(inputs) == before
    assert main(["pose", str(inputs / "scene.json"), "-o", str(inputs / "result.json")]) == 0
    assert json.loads((inputs / "result.json").read_text())["status"] == "success"


def test_triangulate_never_writes_into_its_input_folder(inputs, capsys):
    before = snapshot(inputs)
    for out in (inputs / "house", inputs / "house" / "sub", inputs / "house-link" / "sub", inputs / "house" / "."):
        one_line_exit_2(["triangulate", inputs / "house", "--out", out, "--method", "linear"], capsys,
                        "input FOLDER")
    # ``triangulate --colmap --out model/sub`` was accepted and wrote into the input model's folder.
    for out in (inputs / "model", inputs / "model" / "sub", inputs / "model-link" / "sub", inputs / "model" / ".."
                / "model"):
        one_line_exit_2(["triangulate", "--colmap", inputs / "model", "--out", out], capsys, "input --colmap")
    one_line_exit_2(["triangulate", "--colmap", inputs / "model-link", "--out", inputs / "model" / "x"], capsys,
                    "input --colmap")
    assert snapshot(inputs) == before


def test_localize_never_writes_into_its_inputs(inputs, capsys):
    """``pluecker localize Q M --colmap model --out model`` exited 0 and wrote poses/ and matches/ into the
    model folder."""
    tables = [inputs / "tables" / "queries.parquet", inputs / "tables" / "matches.parquet"]
    before = snapshot(inputs)
    for out in (inputs / "model", inputs / "model" / "located", inputs / "model-link"):
        one_line_exit_2(["localize", *tables, "--colmap", inputs / "model", "--out", out], capsys, "input --colmap")
    # An --out whose poses/ or matches/ would replace an input, or that lies in an input folder.
    (inputs / "job" / "poses").mkdir(parents=True)
    shutil.copy(tables[0], inputs / "job" / "poses" / "queries.parquet")
    one_line_exit_2(["localize", inputs / "job" / "poses", tables[1], "--colmap", inputs / "model", "--out",
                     inputs / "job"], capsys, "would replace the input QUERIES")
    one_line_exit_2(["localize", inputs / "tables", tables[1], "--colmap", inputs / "model", "--out",
                     inputs / "tables" / "out"], capsys, "inside the input QUERIES")
    assert {k: v for k, v in snapshot(inputs).items() if "/job/" not in k} == before
    assert main(["localize", *map(str, tables), "--colmap", str(inputs / "model"), "--out", str(inputs / "out")]) == 0
    assert dist.read_poses(inputs / "out").num_rows == pq.read_table(tables[0]).num_rows > 0


@pytest.mark.parametrize("first, second", [(True, False), (False, True)])
def test_a_run_in_the_other_format_removes_the_earlier_model(inputs, capsys, first, second):
    """A binary run into an --out holding an earlier --text run left the old .txt files beside the new
    .bin files (and a text run over a binary one would be read back as the old binary model)."""
    out = inputs / "out"
    (out).mkdir()
    (out / "notes.md").write_text("a user's file")
    for text in (first, second):
        argv = ["triangulate", "--colmap", str(inputs / "model"), "--out", str(out)] + (["--text"] if text else [])
        assert main(argv) == 0
    printed = capsys.readouterr().out
    new, old = ("txt", "bin") if second else ("bin", "txt")
    assert not any(out.glob(f"*.{old}")), sorted(p.name for p in out.iterdir())
    assert {p.stem for p in out.glob(f"*.{new}")} == {"cameras", "images", "points3D", "rigs", "frames"}
    assert (out / "notes.md").read_text() == "a user's file"
    assert f"removed the {'binary' if old == 'bin' else 'text'} model of an earlier run from {out}: " in printed
    assert colmap.read(out).num_points3D() == 30


def test_an_interrupted_or_failed_run_leaves_no_new_output(inputs, capsys, monkeypatch):
    """``pluecker reproduce`` interrupted left an empty --out folder; every command now writes into a
    temporary folder and renames it: an interruption leaves neither the folder nor the temporary one."""
    from pluecker.experiments import phong_horaud_1995 as phong

    def interrupt(*args, **kwargs):
        raise KeyboardInterrupt

    out = inputs / "new" / "out"
    with monkeypatch.context() as patch:
        patch.setattr(phong, "run_sweeps", interrupt)
        assert main(["reproduce", "phong-horaud-1995", "--quick", "--quiet", "--out", str(out)]) == 130
    with monkeypatch.context() as patch:
        patch.setattr(phong, "render_tables", interrupt)  # while writing
        assert main(["reproduce", "phong-horaud-1995", "--quick", "--quiet", "--out", str(out)]) == 130
    with monkeypatch.context() as patch:
        patch.setattr(colmap, "write_ply", interrupt)
        assert main(["triangulate", "--colmap", str(inputs / "model"), "--out", str(out)]) == 130
    from pluecker import triangulate_folder
    with monkeypatch.context() as patch:
        patch.setattr(triangulate_folder, "_ply", interrupt)
        assert main(["triangulate", str(inputs / "house"), "--method", "linear", "--out", str(out)]) == 130
    with monkeypatch.context() as patch:
        patch.setattr(dist, "_localize_part", interrupt)
        assert main(["localize", str(inputs / "tables" / "queries.parquet"), str(inputs / "tables" / "matches.parquet"),
                     "--colmap", str(inputs / "model"), "--out", str(out)]) == 130
    # A run that fails on its input makes nothing either (localize made --out before reading the tables).
    (inputs / "bad.parquet").write_bytes(b"not parquet")
    assert main(["localize", str(inputs / "bad.parquet"), str(inputs / "bad.parquet"), "--out", str(out)]) == 2
    capsys.readouterr()
    assert not (inputs / "new").exists()
    # An earlier run's output is kept whole when a new run into it is interrupted.
    assert main(["triangulate", "--colmap", str(inputs / "model"), "--out", str(out)]) == 0
    before = snapshot(out)
    with monkeypatch.context() as patch:
        patch.setattr(colmap, "write_ply", interrupt)
        assert main(["triangulate", "--colmap", str(inputs / "model"), "--out", str(out), "--text"]) == 130
    assert snapshot(out) == before and sorted(os.listdir(out)) == sorted(os.path.basename(p) for p in before)


def test_a_missing_or_wrong_input_folder_reads_the_same_in_every_command(inputs, capsys):
    """The VGG ``triangulate`` said ``no such directory`` where ``--colmap`` said ``not a directory``."""
    missing, file = inputs / "nowhere", inputs / "scene.json"
    tables = [str(inputs / "tables" / "queries.parquet"), str(inputs / "tables" / "matches.parquet")]
    for path, words in ((missing, "no such directory"), (file, "not a directory")):
        for argv in (["triangulate", path], ["triangulate", "--colmap", path, "--out", inputs / "o"],
                     ["localize", *tables, "--colmap", path, "--out", inputs / "o"]):
            err = one_line_exit_2(argv, capsys, f"{path}: {words}")
            assert "not a directory" not in err or words == "not a directory"
    with pytest.raises(FileNotFoundError, match="no such directory"):
        colmap.read(missing)
    with pytest.raises(NotADirectoryError, match="not a directory"):
        colmap.read(file)
    assert not (inputs / "o").exists()


def test_the_written_files_are_listed_under_out(inputs, capsys):
    """The files a run lists are those of --out (not of the temporary folder they were written in)."""
    out = inputs / "out"
    files = colmap.write(colmap.read(inputs / "model"), colmap.retriangulate(colmap.read(inputs / "model")), out)
    assert files and all(f.parent == out and f.is_file() for f in files)
    assert not [p for p in inputs.iterdir() if p.name.endswith(".partial")]
    assert main(["triangulate", str(inputs / "house"), "--method", "linear", "--out", str(out / "vgg")]) == 0
    assert f"wrote {out / 'vgg' / 'points.json'}, {out / 'vgg' / 'points.ply'}" in capsys.readouterr().out
    assert np.all([(out / "vgg" / name).is_file() for name in ("points.json", "points.ply")])
