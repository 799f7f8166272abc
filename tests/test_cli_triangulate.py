"""``pluecker triangulate`` on the real Model House data (first four views), run in-process."""

from __future__ import annotations

import json

import numpy as np
import pytest

from pluecker.cli import main
from pluecker.datasets import load_vgg, vgg_root

HOUSE = vgg_root() / "model_house"
VIEWS = [0, 1, 2, 3]


def read_ply(path):
    """(header lines, vertex rows, edge rows) of an ASCII PLY file."""
    lines = path.read_text().splitlines()
    end = lines.index("end_header")
    header = lines[:end]
    counts = {ln.split()[1]: int(ln.split()[2]) for ln in header if ln.startswith("element")}
    body = [ln.split() for ln in lines[end + 1:]]
    vertices = np.array(body[: counts["vertex"]], dtype=float)
    edges = np.array(body[counts["vertex"]:], dtype=float)
    assert len(edges) == counts.get("edge", 0)
    return header, vertices, edges


def cost_eq19(cameras, X, x):
    h = cameras @ np.append(X, 1.0)
    return float(np.sum((h[:, :2] / h[:, 2:] - x) ** 2))


@pytest.fixture(scope="module")
def house_run(tmp_path_factory):
    """One ``triangulate`` run on Model House, views 0-3, points and lines: (status, out dir, stdout)."""
    import contextlib
    import io

    out = tmp_path_factory.mktemp("house")
    stdout = io.StringIO()
    with contextlib.redirect_stdout(stdout):
        status = main(["triangulate", str(HOUSE), "--views", "0,1,2,3", "--lines", "--out", str(out)])
    return status, out, stdout.getvalue()


def test_points_are_certified_and_no_worse_than_the_shipped_reconstruction(house_run):
    status, out, printed = house_run
    assert status == 0
    doc = json.loads((out / "points.json").read_text())
    assert doc["sequence"] == "model_house" and doc["views"] == VIEWS and doc["method"] == "optimal"
    points = doc["points"]
    # The paper's count: 460 House points are seen in at least two of the first four frames.
    assert len(points) == 460 and doc["summary"]["skipped"] == 672 - 460
    seq = load_vgg(HOUSE)
    x, visible = seq.point_observations(VIEWS)
    for p in points:
        i, seen = p["index"], np.array([v in p["views"] for v in VIEWS])
        assert len(p["views"]) >= 2 and np.array_equal(seen, visible[i])
        if not p["certified"]:
            continue
        # A certified optimum within gap g costs at most (1 + g') times any other point, in particular the
        # shipped 3-D point (reconstructed from all ten views) evaluated on these views.
        shipped = cost_eq19(seq.cameras[VIEWS][seen], seq.points3d[i], x[i][seen])
        assert p["cost"] <= shipped / (1 - 1e-3) + 1e-12, p["index"]
        assert p["cost"] == pytest.approx(cost_eq19(seq.cameras[VIEWS][seen], np.array(p["point"]), x[i][seen]), rel=1e-9)
        assert p["lower_bound"] <= p["cost"] * (1 + 1e-12)
    certified = sum(p["certified"] for p in points)
    assert certified / len(points) >= 0.99
    assert doc["summary"]["certified"] == certified


def test_ply_holds_the_finite_points(house_run):
    _, out, _ = house_run
    header, vertices, _ = read_ply(out / "points.ply")
    points = json.loads((out / "points.json").read_text())["points"]
    finite = [p["point"] for p in points if all(v is not None for v in p["point"])]
    assert "format ascii 1.0" in header and vertices.shape == (len(finite), 6)
    np.testing.assert_allclose(vertices[:, :3], finite, rtol=1e-15)
    green = vertices[:, 4] > vertices[:, 3]
    assert green.sum() == sum(p["certified"] for p in points if all(v is not None for v in p["point"]))


def test_the_json_carries_covariances(house_run):
    _, out, _ = house_run
    for p in json.loads((out / "points.json").read_text())["points"]:
        C = np.array(p["covariance"])
        assert C.shape == (3, 3) and np.allclose(C, C.T) and np.linalg.eigvalsh(C).min() > 0
    for line in json.loads((out / "lines.json").read_text())["lines"]:
        assert np.array(line["chart_axes"]).shape == (2, 3)
        if line["covariance"] is not None:
            C = np.array(line["covariance"])
            assert C.shape == (4, 4) and np.linalg.eigvalsh(C).min() > 0


def test_lines_are_written_with_their_extent(house_run):
    _, out, printed = house_run
    doc = json.loads((out / "lines.json").read_text())
    lines = doc["lines"]
    assert len(lines) == 30 and doc["sigma_px"] == 1.0
    for line in lines:
        L = np.array(line["plucker"])
        # Eq. 4, relative to the size of the coordinates.
        assert abs(L[0] * L[5] + L[1] * L[4] + L[2] * L[3]) <= 1e-9 * np.dot(L, L)
        d, p = np.array(line["direction"]), np.array(line["point"])
        assert np.linalg.norm(d) == pytest.approx(1.0)
        a, b = np.array(line["segment"])
        # Both ends of the drawn segment lie on the line.
        for end in (a, b):
            off = (end - p) - np.dot(end - p, d) * d
            assert np.linalg.norm(off) < 1e-9 * (1 + np.linalg.norm(end))
    _, vertices, edges = read_ply(out / "lines.ply")
    assert edges.shape[0] * 2 == vertices.shape[0] <= 60
    assert "lines: 30 of 30 triangulated" in printed


def test_summary_is_printed(house_run):
    _, out, printed = house_run
    lines = printed.strip().splitlines()
    assert lines[0].startswith("triangulate model_house (views 0,1,2,3, method optimal)")
    assert "points: 460 of 672 triangulated (212 seen in fewer than 2 of the views)" in lines[1]
    assert "certified" in lines[1] and "µs per point" in lines[1]
    assert lines[-1].startswith("wrote ") and "points.ply" in lines[-1]


@pytest.mark.parametrize("method", ["linear", "local"])
def test_other_methods_are_not_certified(method, tmp_path, capsys):
    assert main(["triangulate", str(HOUSE), "--views", "0,2", "--method", method, "--out", str(tmp_path)]) == 0
    doc = json.loads((tmp_path / "points.json").read_text())
    assert doc["method"] == method and doc["points"]
    assert all(p["certificate"] == "none" and not p["certified"] for p in doc["points"])
    assert not (tmp_path / "lines.json").exists()
    assert "certified 0 (0.0 %: none)" in capsys.readouterr().out


@pytest.mark.parametrize(
    "argv, message",
    [
        (["triangulate", "/no/such/folder"], "no such directory"),
        (["triangulate", str(HOUSE / "house.000.P")], "not a directory"),
        (["triangulate", str(HOUSE), "--views", "0,12"], "view 12 does not exist: model_house has 10 views (0-9)"),
    ],
    ids=["missing", "file", "view-out-of-range"],
)
def test_bad_folder_or_views_exit_2_with_one_line(argv, message, capsys, tmp_path):
    assert main(argv + ["--out", str(tmp_path / "out")]) == 2
    captured = capsys.readouterr()
    assert captured.out == ""
    assert captured.err.startswith("pluecker triangulate: error: ")
    assert captured.err.count("\n") == 1 and "Traceback" not in captured.err
    assert message in captured.err


def test_empty_folder_exits_2(tmp_path, capsys):
    (tmp_path / "empty").mkdir()
    assert main(["triangulate", str(tmp_path / "empty")]) == 2
    assert "no camera files" in capsys.readouterr().err


@pytest.mark.parametrize("views", ["0", "0,0,1", "a,b", "-1,2", ""])
def test_malformed_views_are_usage_errors(views, capsys):
    assert main(["triangulate", str(HOUSE), "--views", views]) == 2
    err = capsys.readouterr().err
    assert "--views" in err and "Traceback" not in err and err.count("\n") == 1


def test_unwritable_output_exits_2(tmp_path, capsys):
    blocker = tmp_path / "file"
    blocker.write_text("")
    assert main(["triangulate", str(HOUSE), "--views", "0,1", "--out", str(blocker)]) == 2
    assert capsys.readouterr().err.startswith("pluecker triangulate: error: cannot write")


def test_each_feature_says_what_its_cost_measures(house_run):
    _, out, _ = house_run
    points = json.loads((out / "points.json").read_text())["points"]
    lines = json.loads((out / "lines.json").read_text())["lines"]
    assert {p["cost_kind"] for p in points} == {"reprojection"}
    assert {line["cost_kind"] for line in lines} == {"line_residual"}
