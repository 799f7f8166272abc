"""The ``pluecker`` command line, run in-process through ``main(argv)``."""

from __future__ import annotations

import io
import json

import numpy as np
import pytest

import pluecker
from pluecker.cli import main


def scene_document(seed: int, n_points: int = 12, n_lines: int = 4) -> tuple[dict, dict]:
    """A random scene and its ``pluecker pose`` input document."""
    scene = pluecker.random_scene("general", n_points, n_lines, seed=seed)
    cam = scene["camera"]
    doc = {
        "camera": {"fx": cam.fx, "fy": cam.fy, "cx": cam.cx, "cy": cam.cy, "skew": cam.skew},
        "points2d": scene["points2d"].tolist(),
        "points3d": scene["points3d"].tolist(),
        "lines2d": scene["lines2d"].tolist(),
        "lines3d": scene["lines3d"].tolist(),
    }
    return scene, doc


def write(tmp_path, doc, name: str = "input.json") -> str:
    path = tmp_path / name
    path.write_text(json.dumps(doc) if not isinstance(doc, str) else doc)
    return str(path)


def assert_recovers(out: dict, scene: dict, seed: int, tol: float = 1e-6) -> None:
    np.testing.assert_allclose(np.array(out["pose"]["rotation"]), scene["R"], atol=tol, err_msg=f"seed={seed}")
    np.testing.assert_allclose(np.array(out["pose"]["translation"]), scene["t"], atol=tol * 10, err_msg=f"seed={seed}")
    assert out["status"] == "success", f"seed={seed}"


def test_pose_recovers_the_pose_of_a_random_scene(tmp_path, capsys, seed):
    scene, doc = scene_document(seed)
    assert main(["pose", write(tmp_path, doc)]) == 0
    out = json.loads(capsys.readouterr().out)
    assert_recovers(out, scene, seed)
    assert out["method"] == "trust-region"
    assert [s["name"] for s in out["details"]["stages"]][-1] == "refinement"


def test_pose_writes_output_file_and_reads_stdin(tmp_path, capsys, monkeypatch, seed):
    scene, doc = scene_document(seed)
    monkeypatch.setattr("sys.stdin", io.StringIO(json.dumps(doc)))
    out_path = tmp_path / "out.json"
    assert main(["pose", "-", "-o", str(out_path)]) == 0
    assert capsys.readouterr().out == ""
    assert_recovers(json.loads(out_path.read_text()), scene, seed)


def test_pose_accepts_K_method_and_options(tmp_path, capsys, seed):
    scene, doc = scene_document(seed, n_points=10, n_lines=0)
    doc["camera"] = {"K": scene["camera"].K.tolist()}
    del doc["lines2d"], doc["lines3d"]
    doc["method"] = "levenberg-marquardt"
    doc["options"] = {"penalty": 50.0, "normalize": True, "levenberg_marquardt": {"stopping": {"max_iterations": 100}}}
    # The command-line flags win over the file.
    assert main(["pose", write(tmp_path, doc), "--method", "rotation-then-translation", "--no-refine"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["method"] == "rotation-then-translation"
    assert [s["name"] for s in out["details"]["stages"]] == ["rotation", "translation"]
    assert_recovers(out, scene, seed, tol=1e-5)


def test_certify_flag_and_option(tmp_path, capsys, seed):
    """``--certify`` (or ``options.certify``) adds a proved lower bound; without it nothing is claimed."""
    scene, doc = scene_document(seed, n_points=30, n_lines=0)
    del doc["lines2d"], doc["lines3d"]
    rng = np.random.default_rng(seed)
    doc["points2d"] = (np.array(doc["points2d"]) + rng.normal(size=(30, 2))).tolist()
    assert main(["pose", write(tmp_path, doc)]) == 0
    plain = json.loads(capsys.readouterr().out)
    assert plain["certified"] is False and plain["certificate"] is None
    assert plain["details"]["uncertified_reason"].startswith("not requested")
    doc["options"] = {"certify": False}
    assert main(["pose", write(tmp_path, doc), "--certify"]) == 0  # the flag wins over the file
    out = json.loads(capsys.readouterr().out)
    cert = out["certificate"]
    assert cert["kind"] == "sublevel_set", cert
    assert out["certified"] is True and cert["certified"] is True and cert["relative_gap"] <= 1e-3
    assert cert["lower_bound"] <= out["cost"] <= cert["lower_bound"] / (1 - 1e-3)
    # The certificate's options from the file: one rotation cell is not enough, and the status says so.
    doc["options"] = {"certify": {"max_relative_gap": 1e-3, "max_nodes": 1}}
    assert main(["pose", write(tmp_path, doc)]) == 0
    capped = json.loads(capsys.readouterr().out)
    assert capped["status"] == "gap_not_closed" and capped["certified"] is False
    assert "max_nodes = 1" in capped["details"]["uncertified_reason"]


def test_linear_method_reports_estimated_intrinsics(tmp_path, capsys, seed):
    scene, doc = scene_document(seed, n_points=20, n_lines=0)
    assert main(["pose", write(tmp_path, doc), "--method", "linear", "--no-refine"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["details"]["estimated_camera"]["fx"] == pytest.approx(scene["camera"].fx, rel=1e-5), f"seed={seed}"


@pytest.mark.parametrize(
    "change, message",
    [
        (lambda d: "{not json", "not valid JSON"),
        (lambda d: [1, 2, 3], "JSON object"),
        (lambda d: {k: v for k, v in d.items() if k != "camera"}, "'camera' is required"),
        (lambda d: {**d, "camera": {"fx": 800, "fy": 800, "cx": 320}}, "lacks cy"),
        (lambda d: {**d, "camera": {"K": [[1, 0], [0, 1]]}}, "3x3"),
        (lambda d: {**d, "points2d": [[u, v, 1.0] for u, v in d["points2d"]]}, "shape (N, 2)"),
        (lambda d: {**d, "points2d": [[1.0, 2.0], [3.0]]}, "list of numbers"),
        (lambda d: {**d, "points2d": d["points2d"][:-1]}, "points2d"),
        (lambda d: {"camera": d["camera"], "points2d": d["points2d"][:2], "points3d": d["points3d"][:2]},
         "needs at least 3"),
        (lambda d: {"camera": d["camera"]}, "no correspondences"),
        (lambda d: {**d, "method": "gradient-descent"}, "unknown method"),
        (lambda d: {**d, "options": {"lamda": 3}}, "'options': PoseOptions() got an unexpected keyword argument 'lamda'"),
        (lambda d: {**d, "options": {"refine": "yes"}}, "'options': refine: "),
        (lambda d: {**d, "pointz2d": []}, "unknown key(s) 'pointz2d'"),
        (lambda d: {**d, "options": {"initial_pose": {"R": [[1, 0, 0], [0, 1, 0]], "t": [0, 0, 1]}}},
         "option 'initial_pose'"),
        (lambda d: {**d, "options": {"max_iterations": 0}}, "max_iterations"),
        (lambda d: {**d, "camera": {"fx": 0.0, "fy": 800, "cx": 320, "cy": 240}}, "singular camera"),
    ],
    ids=["malformed-json", "not-an-object", "no-camera", "camera-incomplete", "bad-K", "wrong-shape",
         "ragged", "count-mismatch", "too-few-points", "no-data", "bad-method", "bad-option",
         "bad-option-type", "unknown-key", "bad-initial-pose", "bad-max-iterations", "singular-camera"],
)
def test_bad_input_exits_2_with_one_line(tmp_path, capsys, change, message, seed):
    _, doc = scene_document(seed)
    bad = change(doc)
    path = write(tmp_path, bad if isinstance(bad, str) else json.dumps(bad))
    assert main(["pose", path]) == 2
    captured = capsys.readouterr()
    assert captured.out == ""
    assert captured.err.startswith("pluecker pose: error: ")
    assert captured.err.count("\n") == 1 and "Traceback" not in captured.err
    assert message in captured.err


def test_initial_pose_option_is_passed_on(tmp_path, capsys, seed):
    scene, doc = scene_document(seed)
    doc["options"] = {"initial_pose": {"R": scene["R"].tolist(), "t": scene["t"].tolist()}, "refine": False}
    assert main(["pose", write(tmp_path, doc)]) == 0
    out = json.loads(capsys.readouterr().out)
    assert_recovers(out, scene, seed)


def test_unwritable_output_exits_2(tmp_path, capsys, seed):
    _, doc = scene_document(seed)
    assert main(["pose", write(tmp_path, doc), "-o", str(tmp_path / "no" / "such" / "dir.json")]) == 2
    assert capsys.readouterr().err.startswith("pluecker pose: error: cannot write")


def test_reproduce_into_a_file_exits_2(tmp_path, capsys):
    blocker = tmp_path / "file"
    blocker.write_text("")
    assert main(["reproduce", "phong-horaud-1995", "--quick", "--quiet", "--out", str(blocker)]) == 2
    assert capsys.readouterr().err.startswith("pluecker reproduce: error: cannot write")


def test_missing_file_exits_2(tmp_path, capsys):
    assert main(["pose", str(tmp_path / "nope.json")]) == 2
    assert "no such file" in capsys.readouterr().err


def test_non_finite_input_exits_2(tmp_path, capsys, seed):
    _, doc = scene_document(seed)
    doc["points2d"][1][0] = "__NaN__"
    text = json.dumps(doc).replace('"__NaN__"', "NaN")  # Python's json reads the non-standard NaN
    assert main(["pose", write(tmp_path, text)]) == 2
    assert "non-finite" in capsys.readouterr().err


@pytest.mark.parametrize(
    "argv",
    [[], ["pose"], ["frobnicate"], ["pose", "x.json", "--method", "simplex"], ["pose", "x.json", "--penalty", "-1"],
     ["reproduce", "someone-else-2020"], ["reproduce", "phong-horaud-1995", "--trials", "0"],
     ["reproduce", "phong-horaud-1995", "--seed", "-1"]],
)
def test_usage_errors_exit_2(argv, capsys):
    assert main(argv) == 2
    assert "Traceback" not in capsys.readouterr().err


def test_help_exits_0(capsys):
    assert main(["--help"]) == 0
    assert "reproduce" in capsys.readouterr().out
