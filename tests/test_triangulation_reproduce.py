"""``pluecker reproduce josephson-kahl-2008 --quick``: the files it writes and the paper's claims on them."""

from __future__ import annotations

import contextlib
import io
import json

import pytest

from pluecker.cli import main
from pluecker.experiments import josephson_kahl_2008 as jk

FIGURES = ("figure1_line_residuals.png", "figure2_conic_residuals.png")


@pytest.fixture(scope="module")
def quick_run(tmp_path_factory):
    out = tmp_path_factory.mktemp("josephson-kahl-2008")
    stdout = io.StringIO()
    with contextlib.redirect_stdout(stdout):
        status = main(["reproduce", "josephson-kahl-2008", "--quick", "--quiet", "--out", str(out)])
    return status, out, stdout.getvalue(), json.loads((out / "summary.json").read_text())


def test_writes_tables_figures_and_summary(quick_run):
    status, out, printed, doc = quick_run
    assert status == 0
    for name in ("tables.md", "summary.json", *FIGURES):
        assert (out / name).is_file() and (out / name).stat().st_size > 0, name
    assert (out / FIGURES[0]).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    md = (out / "tables.md").read_text()
    for heading in ("## Table 1", "## Table 2", "## Figures 1-2", "## Certificates, branch-and-bound nodes"):
        assert heading in md
    assert doc["settings"]["quick"] is True and doc["settings"]["fitting_draws"] == jk.fitting.DRAWS_QUICK
    lines = printed.strip().splitlines()
    assert lines[0].startswith("josephson-kahl-2008 (quick)") and 6 <= len(lines) <= 14


def test_points_have_the_papers_counts_and_are_certified(quick_run):
    _, _, _, doc = quick_run
    points = doc["summary"]["points"]
    for sequence, count in (("model_house", 460), ("corridor", 490)):
        opt = points[sequence]["optimal"]
        assert opt["points"] == count
        assert opt["certified"] >= 0.99 * count
        # The optimal answer is never above the local one beyond the certificate's gap; the local one
        # is sometimes stuck above it (the paper's point).
        assert points[sequence]["local_minima"]["optimal_above_local"] == 0
        assert points[sequence]["local"]["total_cost"] >= opt["total_cost"] * (1 - 1e-3)
        # The linear answer can cost less only by lying behind a camera (the optimum is over points in
        # front): Corridor has such a point.
        linear = points[sequence]["linear"]
        if linear["total_cost"] < opt["total_cost"] * (1 - 1e-3):
            assert linear["statuses"].get("behind_camera", 0) > 0
        # Sub-pixel errors, as in the paper (0.13-0.16 px): the data's own consistency is 0.37-0.39 px
        # over all ten views.
        assert 0.05 < opt["mean_px"] < 0.4


def test_line_errors_are_eq19(quick_run):
    _, _, _, doc = quick_run
    for sequence, by_method in doc["summary"]["lines"].items():
        for m in jk.METHODS:
            s = by_method[m]
            assert s["lines"] == jk.lines.QUICK_LINES
            # The whitened residuals recomputed by the experiment sum to the cost the core reports.
            assert s["max_cost_mismatch"] < 1e-6, (sequence, m)
        assert by_method["optimal"]["total_cost"] <= by_method["linear"]["total_cost"] * (1 + 1e-3)


def test_fitted_residuals_whiten_to_unit_variance(quick_run):
    _, _, _, doc = quick_run
    fit = doc["summary"]["fitting"]
    assert fit["draws"] == jk.fitting.DRAWS_QUICK
    # 2000 draws: a standard deviation is estimated to ±1.6 %; 8 % is 5 standard errors.
    for kind in ("line", "conic"):
        for entry in fit[kind]:
            assert abs(entry["whitened"]["std"] - 1.0) < 0.08, (kind, entry)


def test_residual_statistics_of_a_gaussian_sample():
    import numpy as np

    stats = jk.fitting.residual_statistics(np.random.default_rng(0).normal(2.0, 3.0, 20000))
    assert stats["mean"] == pytest.approx(2.0, abs=0.1) and stats["std"] == pytest.approx(3.0, rel=0.03)
    # Sampling error of the KS distance at n = 20000 is ~0.006; of skewness/kurtosis ~0.02/0.04.
    assert stats["ks_distance"] < 0.015 and abs(stats["skewness"]) < 0.08 and abs(stats["excess_kurtosis"]) < 0.15
