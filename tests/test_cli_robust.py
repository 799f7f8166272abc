"""``pluecker pose --robust``: flags, the same keys in the JSON ``ransac`` object (the fields of
``RansacOptions``), and the output."""

from __future__ import annotations

import json

import numpy as np
import pytest

from pluecker.cli import main
from test_cli import write
from test_robust_pose import check_masks, noisy_scene


def document(scene: dict, data: dict, ransac: dict | bool | None = None, options: dict | None = None) -> dict:
    cam = scene["camera"]
    doc = {"camera": {"fx": cam.fx, "fy": cam.fy, "cx": cam.cx, "cy": cam.cy},
           **{k: np.asarray(v).tolist() for k, v in data.items()}}
    if ransac is not None:
        doc["ransac"] = ransac
    if options is not None:
        doc["options"] = options
    return doc


def test_robust_flag_finds_the_inliers_and_prints_masks_and_covariance(tmp_path, capsys, seed):
    scene, data = noisy_scene(60, 10, 0.5, seed % 1000)
    argv = ["pose", write(tmp_path, document(scene, data)), "--robust", "--point-threshold", "4",
            "--line-threshold", "4", "--seed", "3", "--sigma", "1"]
    assert main(argv) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["status"] == "success", out["status"]
    assert out["details"]["ransac"]["stop"] == "confidence" and out["details"]["ransac"]["iterations"] >= 1
    assert out["details"]["covariance_source"] == "given" and out["details"]["sigma_px"] == 1.0
    assert np.array(out["covariance"]).shape == (6, 6)

    class Result:  # the masks as check_masks reads them
        inliers_points = np.array(out["inliers_points"])
        inliers_lines = np.array(out["inliers_lines"])

    check_masks(Result, scene, data, f"seed={seed % 1000}")


def test_options_in_the_file_equal_the_flags_and_flags_win(tmp_path, capsys, seed):
    scene, data = noisy_scene(40, 10, 0.3, seed % 1000)
    ransac = {"point_threshold": 3.0, "line_threshold": 5, "seed": 11, "confidence": 0.999, "max_iterations": 5000,
              "time_budget": None, "min_inliers": 8, "min_inlier_ratio": 0.1, "sprt": True}
    options = {"sigma_px": 2.0}
    assert main(["pose", write(tmp_path, document(scene, data, ransac, options))]) == 0
    from_file = json.loads(capsys.readouterr().out)
    assert main(["pose", write(tmp_path, document(scene, data, {"confidence": 0.999, "max_iterations": 5000,
                                                                 "min_inliers": 8}), "b.json"),
                 "--robust", "--point-threshold", "3", "--line-threshold", "5", "--seed", "11", "--sigma", "2"]) == 0
    from_flags = json.loads(capsys.readouterr().out)
    assert from_file["details"]["ransac"]["iterations"] == from_flags["details"]["ransac"]["iterations"]
    for key in ("pose", "inliers_points", "inliers_lines", "covariance"):
        assert from_file[key] == from_flags[key], key
    # A flag overrides the file: another sigma scales the covariance by (σ'/σ)².
    assert main(["pose", write(tmp_path, document(scene, data, ransac, options), "c.json"), "--sigma", "1"]) == 0
    scaled = json.loads(capsys.readouterr().out)
    np.testing.assert_allclose(np.array(scaled["covariance"]) * 4.0, np.array(from_file["covariance"]), rtol=1e-12)


def test_all_outlier_input_warns_with_the_status(tmp_path, capsys, seed):
    rng = np.random.default_rng(seed)
    scene, data = noisy_scene(30, 0, 0.0, seed % 1000)
    data = dict(points2d=rng.uniform([0, 0], [640, 480], size=(30, 2)), points3d=data["points3d"])
    doc = document(scene, data, {"max_iterations": 500})
    assert main(["pose", write(tmp_path, doc), "--robust"]) == 0
    captured = capsys.readouterr()
    out = json.loads(captured.out)
    assert out["status"] == "too_few_inliers" and out["details"]["ransac"]["stop"] == "iteration_cap"
    assert "too_few_inliers" in captured.err


@pytest.mark.parametrize("argv,message", [
    (["--point-threshold", "0"], "positive number"),
    (["--line-threshold", "-1"], "positive number"),
    (["--sigma", "nan"], "positive number"),
    (["--seed", "-2"], "non-negative integer"),
])
def test_bad_flags_are_usage_errors(tmp_path, capsys, argv, message, seed):
    scene, data = noisy_scene(10, 0, 0.0, seed % 1000)
    assert main(["pose", write(tmp_path, document(scene, data)), "--robust", *argv]) == 2
    assert message in capsys.readouterr().err


@pytest.mark.parametrize("ransac,message", [
    ({"point_threshold": 0}, "point_threshold"),
    ({"line_threshold": -3.0}, "line_threshold"),
    ({"confidence": 1}, "confidence"),
    ("yes", "'ransac' must be true, false or a JSON object"),
    ({"seed": 1.5}, "'ransac': seed: "),
    ({"robust": True}, "'ransac': RansacOptions() got an unexpected keyword argument 'robust'"),
])
def test_bad_options_in_the_file_are_errors(tmp_path, capsys, ransac, message, seed):
    scene, data = noisy_scene(10, 0, 0.0, seed % 1000)
    assert main(["pose", write(tmp_path, document(scene, data, ransac))]) == 2
    err = capsys.readouterr().err
    assert message in err and err.count("\n") == 1
