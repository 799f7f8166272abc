"""``docs/cli.md`` and the ``--help`` texts say what the command line really does (issue 11 §6): the
documented flags are the parser's flags, the documented output keys are ``PoseResult.to_dict()``'s keys,
the example output is a real run, and the help of ``reproduce`` gives each experiment's defaults."""

from __future__ import annotations

import argparse
import contextlib
import io
import json
import re
from pathlib import Path

import numpy as np
import pytest

import pluecker
from pluecker.cli import build_parser, main

ROOT = Path(__file__).resolve().parents[1]
CLI_MD = (ROOT / "docs" / "cli.md").read_text(encoding="utf-8")
README = (ROOT / "README.md").read_text(encoding="utf-8")


def section(text: str, heading: str) -> str:
    """The text under ``heading`` (a whole Markdown heading line) up to the next heading of the same or a
    higher level."""
    level = len(heading) - len(heading.lstrip("#"))
    start = text.index(heading + "\n") + len(heading) + 1
    following = re.compile(r"^#{1,%d} " % level, re.M).search(text, start)
    return text[start: following.start() if following else len(text)]


def table_column(text: str, header: str) -> list[str]:
    """The first cells of the rows of the Markdown table whose header row starts with ``header``."""
    lines = text.splitlines()
    start = next(i for i, line in enumerate(lines) if line.startswith(header))
    cells = []
    for line in lines[start + 2:]:
        if not line.startswith("|"):
            break
        cells.append(line.split("|")[1].strip())
    return cells


def documented_flags(cells: list[str]) -> set[str]:
    return {flag for cell in cells for flag in re.findall(r"(?<![\w-])(--?[a-z][a-z-]*)", cell)}


def subparser(name: str) -> argparse.ArgumentParser:
    parser = build_parser()
    commands = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    return commands.choices[name]


def parser_flags(name: str) -> set[str]:
    return {flag for action in subparser(name)._actions for flag in action.option_strings} - {"-h", "--help"}


def help_text(name: str, monkeypatch) -> str:
    monkeypatch.setenv("COLUMNS", "1000")  # no wrapping: a phrase is on one line
    return subparser(name).format_help()


def pose_scene() -> Path:
    """The worked example's ``scene.json``, as written in docs/cli.md."""
    return json.loads(re.search(r"`scene.json`:\n\n```json\n(.*?)```", CLI_MD, re.S).group(1))


def run_pose(tmp_path, document, *flags) -> dict:
    path = tmp_path / "scene.json"
    path.write_text(json.dumps(document))
    stdout = io.StringIO()
    with contextlib.redirect_stdout(stdout):
        assert main(["pose", str(path), *flags]) == 0
    return json.loads(stdout.getvalue())


# --- flags --------------------------------------------------------------------------------------------


@pytest.mark.parametrize("command, heading, header", [
    ("pose", "## `pluecker pose`", "| flag |"),
    ("triangulate", "## `pluecker triangulate`", "| flag |"),
    ("reproduce", "## `pluecker reproduce phong-horaud-1995`", "| flag |"),
    ("reproduce", "## `pluecker reproduce josephson-kahl-2008`", "| flag |"),
])
def test_the_flag_tables_list_every_flag_of_the_parser(command, heading, header):
    documented = documented_flags(table_column(section(CLI_MD, heading), header))
    assert documented == parser_flags(command)


def test_the_command_table_lists_every_flag():
    rows = table_column(CLI_MD, "| command |")
    for command in ("pose", "triangulate", "reproduce phong-horaud-1995", "reproduce josephson-kahl-2008"):
        row = next(r for r in rows if r.startswith(f"`pluecker {command} "))
        shown = documented_flags([row])
        assert shown <= parser_flags(command.split()[0]), command
        for action in subparser(command.split()[0])._actions:  # each flag once, in one of its spellings
            assert not action.option_strings or action.dest == "help" or shown & set(action.option_strings), \
                (command, action.option_strings)


# --- pose output ----------------------------------------------------------------------------------------


def test_the_output_table_lists_every_key_of_to_dict():
    output = section(CLI_MD, "### Output")
    cells = table_column(output, "| key |")
    documented = {name for cell in cells for name in re.findall(r"`([a-z_A-Z0-9]+)`", cell)}
    details = output[output.index("`details`:"):]
    documented_details = {name for cell in table_column(details, "| key |")
                          for name in re.findall(r"`([a-z_A-Z0-9]+)`", cell)}
    scene = pluecker.random_scene("general", 8, 2, seed=3)
    for options in (None, pluecker.PoseOptions(ransac=pluecker.RansacOptions()),
                    pluecker.PoseOptions(certify=pluecker.CertifyOptions(), sigma_px=1.0)):
        result = pluecker.estimate_pose(scene["camera"], scene["points2d"], scene["points3d"],
                                        lines2d=scene["lines2d"], lines3d=scene["lines3d"], options=options)
        assert documented == set(result.to_dict()), options
        assert documented_details == set(result.to_dict()["details"]), options


def pose_results() -> dict[str, pluecker.PoseResult]:
    """Pose results whose JSON fills every branch: robust, certified with a χ² test, the linear method's
    estimated camera, a lens, a runner-up minimum (a planar square's twin), a robust loop that finds no
    model, a numerical failure."""
    general = pluecker.random_scene("general", 8, 2, seed=3)
    lines = {"lines2d": general["lines2d"], "lines3d": general["lines3d"]}
    planar = pluecker.random_scene("planar", 4, 0, seed=0)
    lens = pluecker.Camera("OPENCV", [800.0, 790.0, 320.0, 240.0, -0.2, 0.05, 1e-3, -1e-3])
    noise = np.random.default_rng(0).uniform(0, 640, (8, 2))

    def pose(scene, points2d=None, camera=None, **options):
        points2d = scene["points2d"] if points2d is None else points2d
        extra = lines if scene is general and points2d is scene["points2d"] else {}
        return pluecker.estimate_pose(camera or scene["camera"], points2d, scene["points3d"], **extra,
                                      options=pluecker.PoseOptions(**options))

    return {
        "default": pose(general),
        "robust": pose(general, ransac=pluecker.RansacOptions()),
        "certified": pose(general, certify=pluecker.CertifyOptions(), sigma_px=1.0),
        "linear": pose(general, points2d=general["points2d"].copy(), method="linear"),
        "lens": pose(general, points2d=lens.project(general["points3d"] @ general["R"].T + general["t"]), camera=lens,
                     certify=pluecker.CertifyOptions()),
        "runner_up": pose(planar),
        "no_model": pose(general, points2d=noise, ransac=pluecker.RansacOptions()),
        "numerical_failure": pose(general, points2d=general["points2d"] * 1e12),
    }


def test_the_json_is_the_cores_with_the_keys_and_values_of_to_dict():
    """One shape: the command line writes the core's JSON of the result (serde), and ``to_dict()`` has the
    same keys, in the same order, with the same values (a matrix as its rows, NaN as null)."""
    results = pose_results()
    shown = {name: json.loads(r.to_json()) for name, r in results.items()}
    assert shown["robust"]["details"]["ransac"] is not None and shown["no_model"]["status"] == "too_few_inliers"
    assert shown["certified"]["certificate"]["kind"] == "sublevel_set"
    assert shown["certified"]["details"]["residual_test"] is not None
    assert shown["linear"]["details"]["estimated_camera"].keys() == {"fx", "fy", "cx", "cy", "skew"}
    assert shown["lens"]["certificate"] is not None and shown["runner_up"]["details"]["second_best"] is not None
    assert shown["numerical_failure"]["status"] == "numerical_failure"

    def same(a, b, where):
        if isinstance(a, dict):
            assert isinstance(b, dict) and list(a) == list(b), (where, list(a), list(b))
            for key in a:
                same(a[key], b[key], f"{where}.{key}")
        else:
            assert a == b, (where, a, b)

    for name, result in results.items():
        # to_dict() holds tuples where JSON has lists: compared as JSON reads them back.
        same(shown[name], json.loads(json.dumps(result.to_dict(), allow_nan=False)), name)
        R = np.asarray(shown[name]["pose"]["rotation"])
        np.testing.assert_array_equal(R, result.pose.rotation)  # rows, as numpy's (3, 3) array


@pytest.mark.parametrize("heading, cls", [("`options` holds fields of", pluecker.PoseOptions),
                                          ("`ransac` holds fields of", pluecker.RansacOptions)])
def test_the_input_tables_are_the_options_classes(heading, cls):
    """One vocabulary: the JSON keys are the fields of the Python (and Rust) options, with their defaults."""
    text = CLI_MD[CLI_MD.index(heading):]
    lines = text.splitlines()
    start = next(i for i, line in enumerate(lines) if line.startswith("| key |"))
    rows = [line.split("|")[1:5] for line in lines[start + 2:] if line.startswith("|")][:len(cls.__fields__)]
    keys = [cell[0].strip().strip("`") for cell in rows]
    assert keys == [name for name, _, _ in cls.__fields__]
    defaults = cls().to_dict()
    for key, (_, _, shown, meaning) in zip(keys, rows):
        value = defaults[key]
        if isinstance(value, dict):  # a nested options object: the row names its class (its fields are its own)
            assert f"`pluecker.{type(getattr(cls(), key)).__name__}`" in meaning, key
            continue
        shown = shown.strip().split(":")[0].strip("` ")
        expected = {None: "null", True: "true", False: "false"}.get(value, value) if not isinstance(value, (int, float)) \
            or isinstance(value, bool) else value
        if isinstance(expected, (int, float)):
            assert float(shown) == expected, key
        else:
            assert shown == str(expected), key


def test_the_example_output_is_a_real_run_with_every_key(tmp_path):
    shown = json.loads(re.search(r"`pluecker pose scene.json` prints \(a real run\):\n\n```json\n(.*?)```",
                                 CLI_MD, re.S).group(1))
    real = run_pose(tmp_path, pose_scene())
    assert list(shown) == list(real) and list(shown["details"]) == list(real["details"])
    for key in ("rotation", "translation"):
        np.testing.assert_allclose(shown["pose"][key], real["pose"][key], rtol=1e-6, atol=1e-9, err_msg=key)
    np.testing.assert_allclose(shown["cost"], real["cost"], rtol=1e-6)
    np.testing.assert_allclose(shown["details"]["rms_error_px"], real["details"]["rms_error_px"], rtol=1e-6)
    assert shown["status"] == real["status"] == "success"
    assert [s["name"] for s in shown["details"]["stages"]] == [s["name"] for s in real["details"]["stages"]]


def test_the_certify_sigma_excerpt_is_a_real_run(tmp_path):
    real = run_pose(tmp_path, pose_scene(), "--certify", "--sigma", "0.005")
    excerpt = re.search(r"--certify --sigma 0.005` the same pose comes back with \(excerpt\):\n\n```json\n(.*?)```",
                        CLI_MD, re.S).group(1)
    assert real["certified"] and real["certificate"]["kind"] == "sublevel_set"
    assert f'"nodes": {real["certificate"]["nodes"]}' in excerpt
    test = real["details"]["residual_test"]
    assert test["consistent"] and f'"dof": {test["dof"]}' in excerpt


# --- reproduce ------------------------------------------------------------------------------------------


def test_reproduce_help_gives_each_experiments_defaults(monkeypatch):
    from pluecker.experiments import load
    from pluecker.experiments.josephson_kahl_2008 import conics, fitting, lines

    phong, jk = load("phong-horaud-1995"), load("josephson-kahl-2008")

    text = help_text("reproduce", monkeypatch)
    full, quick = phong.Settings.create(), phong.Settings.create(quick=True)
    assert (f"phong-horaud-1995: random draws averaged in every table cell (default {full.trials}, "
            f"{quick.trials} with --quick)") in text
    assert f"josephson-kahl-2008: synthetic disc scenes of Table 3 (default {conics.TRIALS}, " \
           f"{conics.TRIALS_QUICK} with --quick" in text
    assert "random seed (default 0)" in text
    assert (f"phong-horaud-1995: {len(quick.point_counts)} values per sweep and {quick.trials} trials") in text
    assert all(len(v) == len(quick.point_counts) for v in (quick.noise_levels, quick.mismatch_counts,
                                                            quick.outlier_fractions))
    assert (f"josephson-kahl-2008: {conics.TRIALS_QUICK} discs, {fitting.DRAWS_QUICK:,} fitting draws instead "
            f"of {fitting.DRAWS:,} and the first {lines.QUICK_LINES} lines of each sequence") in text
    assert jk.DEFAULT_OUT == Path("results") / "josephson-kahl-2008" and "default results/NAME" in text


def test_where_figures_need_matplotlib_is_said(monkeypatch):
    text = help_text("reproduce", monkeypatch)
    assert "matplotlib (pip install pluecker[plots])" in text
    for where in (CLI_MD.split("\n## ")[0], section(README, "## Reproducing the papers")):
        assert "matplotlib" in where and "pip install pluecker[plots]" in where
    figures = [row for row in CLI_MD.splitlines() if row.startswith("| `") and ".png`" in row]
    assert len(figures) == 5 and all("(needs matplotlib)" in row for row in figures)


def test_the_phong_horaud_run_size_is_the_documented_one():
    from pluecker.experiments import load

    phong = load("phong-horaud-1995")
    count = phong.count_estimates(phong.Settings.create())
    text = section(CLI_MD, "## `pluecker reproduce phong-horaud-1995`")
    assert f"({count:,} estimates)" in text and f"phong-horaud-1995: {count} estimates (100 trials" in text
