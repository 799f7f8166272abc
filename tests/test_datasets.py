"""The VGG reader: counts from the data README, consistency of the shipped reconstruction, the mirror fix."""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import pytest

from pluecker.datasets import VGG_SEQUENCES, load_vgg, vgg_root

# (views, 3-D points, 3-D lines, point observations, line observations) from the data README.
EXPECTED = {
    "model_house": (10, 672, 30, 2846, 223),
    "corridor": (11, 737, 69, 4035, 632),
    "merton_college_1": (3, 717, 295, 1675, 885),
    "merton_college_2": (3, 475, 302, 1117, 906),
    "merton_college_3": (3, 575, 177, 1277, 531),
}


@pytest.mark.parametrize("name", VGG_SEQUENCES)
def test_counts_match_the_data_readme(name):
    seq = load_vgg(vgg_root() / name)
    _, visible = seq.point_observations()
    _, line_visible = seq.line_observations()
    got = (seq.n_views, len(seq.points3d), len(seq.lines3d), int(visible.sum()), int(line_visible.sum()))
    assert got == EXPECTED[name]


@pytest.mark.parametrize("name", VGG_SEQUENCES)
def test_right_handed_frame_with_points_in_front_and_small_reprojection_error(name):
    seq = load_vgg(vgg_root() / name)
    assert seq.mirrored == (name in ("model_house", "corridor")), "the README names the two mirrored sets"
    x, visible = seq.point_observations()
    homogeneous = np.hstack([seq.points3d, np.ones((len(seq.points3d), 1))])
    errors = []
    for j, camera in enumerate(seq.cameras):
        assert np.linalg.det(camera[:, :3]) > 0
        projected = homogeneous @ camera.T
        seen = visible[:, j]
        assert np.all(projected[seen, 2] > 0), f"{name}: a point behind view {j}"
        pixels = projected[seen, :2] / projected[seen, 2:]
        errors.append(np.linalg.norm(pixels - x[seen, j], axis=1))
    # The README's consistency figures: mean 0.37 (House), 0.39 (Corridor), 0.14-0.18 px (Merton).
    assert np.mean(np.concatenate(errors)) < 0.4


def test_missing_folder_is_a_clear_error(tmp_path):
    with pytest.raises(FileNotFoundError, match="no camera files"):
        load_vgg(tmp_path)


def test_a_missing_data_folder_names_the_environment_variable(tmp_path):
    from pluecker.datasets import DataNotFoundError

    with pytest.raises(DataNotFoundError, match="PLUECKER_VGG_DATA"):
        load_vgg(tmp_path / "nowhere")


def test_reproduce_without_data_fails_with_one_clear_line(tmp_path, monkeypatch, capsys):
    from pluecker.cli import main

    monkeypatch.setenv("PLUECKER_VGG_DATA", str(tmp_path / "nowhere"))
    status = main(["reproduce", "josephson-kahl-2008", "--quick", "--quiet", "--out", str(tmp_path / "out")])
    assert status == 2
    assert "VGG data folder not found" in capsys.readouterr().err


def test_the_sequences_ship_with_the_package_and_their_attribution():
    """A clone or an installed wheel has the data with nothing beside it (issue 11 §5)."""
    import pluecker.datasets as datasets

    root = vgg_root()
    package = Path(datasets.__file__).resolve().parent
    if "PLUECKER_VGG_DATA" not in os.environ:
        assert root == package / "data" / "vgg"
    attribution = (package / "data" / "vgg" / "README-VGG.txt").read_text()
    assert "VGG Multiview Dataset" in attribution and "robots.ox.ac.uk" in attribution
    for name in VGG_SEQUENCES:
        by_name = load_vgg(name)
        by_path = load_vgg(root / name)
        assert by_name.name == by_path.name == name
        np.testing.assert_array_equal(by_name.cameras, by_path.cameras)
