"""Localisation from COLMAP data: camera models per query in the localisation tables and in
``pluecker localize``, the RANSAC flags, ``--colmap`` (matches by ``point3D_id``, cameras by
``camera_id``), per-query statuses for bad queries, and the runnable example of docs/cli.md.

The oracle of every pose is pycolmap's own projection (``Camera.img_from_cam`` / ``cam_from_img``),
never pluecker's: the scenes are made with it, and the residuals that decide inliers and costs are
recomputed with it."""

from __future__ import annotations

import re
import shlex
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

pa = pytest.importorskip("pyarrow")
pq = pytest.importorskip("pyarrow.parquet")
pc = pytest.importorskip("pyarrow.compute")
pycolmap = pytest.importorskip("pycolmap")

import pluecker  # noqa: E402
from camera_models import PARAMS  # noqa: E402
from pluecker import colmap  # noqa: E402
from pluecker import distributed as dist  # noqa: E402
from pluecker.cli import main  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
CLI_MD = (ROOT / "docs" / "cli.md").read_text(encoding="utf-8")
WIDTH, HEIGHT = 640, 480
LENSES = ("OPENCV", "OPENCV_FISHEYE", "SIMPLE_RADIAL")
SIGMA = 0.5  # pixel noise of the inliers
#: χ²₆ quantile at 1 - 5e-7 (P(χ²₆ > 40) = e^-20 (1 + 20 + 200) = 4.6e-7): the squared Mahalanobis
#: distance of a maximum-likelihood pose from the truth, 6 parameters, under the Fisher information.
CHI2_6 = 40.0


def rotation(a: np.ndarray) -> np.ndarray:
    theta = np.linalg.norm(a)
    k = np.array([[0, -a[2], a[1]], [a[2], 0, -a[0]], [-a[1], a[0], 0]]) / theta
    return np.eye(3) + np.sin(theta) * k + (1 - np.cos(theta)) * k @ k


def log_rotation(R: np.ndarray) -> np.ndarray:
    angle = np.arccos(np.clip((np.trace(R) - 1) / 2, -1, 1))
    w = np.array([R[2, 1] - R[1, 2], R[0, 2] - R[2, 0], R[1, 0] - R[0, 1]]) / 2
    return w if angle < 1e-12 else w * angle / np.sin(angle)


def scene(model: str, seed: int, n: int = 120, outlier_ratio: float = 0.3, sigma: float = SIGMA):
    """A query seen by a ``model`` camera (tests/camera_models.py) of 640 x 480 px: ``n`` matches, pixels
    spread over the whole image (where the distortion is strongest), depths 4-8, ``sigma`` px of noise,
    ``outlier_ratio`` of them replaced by random pixels. Made with pycolmap's projection. Returns the
    pycolmap camera, the true pose, the world points, the pixels and the outlier mask."""
    rng = np.random.default_rng(seed)
    camera = pycolmap.Camera(model=model, width=WIDTH, height=HEIGHT, params=PARAMS[model])
    R, t = rotation(rng.uniform(-0.5, 0.5, 3)), rng.uniform(-1, 1, 3)
    pixels = rng.uniform([0, 0], [WIDTH, HEIGHT], (n, 2))
    x_cam = np.c_[camera.cam_from_img(pixels), np.ones(n)] * rng.uniform(4, 8, n)[:, None]
    X = (x_cam - t) @ R
    u = camera.img_from_cam(x_cam) + rng.normal(0, sigma, (n, 2))
    outliers = rng.random(n) < outlier_ratio
    u[outliers] = rng.uniform([0, 0], [WIDTH, HEIGHT], (int(outliers.sum()), 2))
    return camera, R, t, X, u, outliers


def residuals(camera, R: np.ndarray, t: np.ndarray, X: np.ndarray, u: np.ndarray) -> np.ndarray:
    """Pixel distances of ``u`` from the projections of ``X`` at ``(R, t)``, by pycolmap."""
    return np.linalg.norm(camera.img_from_cam(X @ R.T + t) - u, axis=1)


def fisher(camera, R: np.ndarray, t: np.ndarray, X: np.ndarray) -> np.ndarray:
    """JᵀJ (6, 6) of pycolmap's projection of ``X`` with respect to the pose perturbation
    ``(exp(ω) R, t + δ)`` at ``(R, t)``, by central differences (step 1e-6: truncation 1e-12, rounding
    1e-10 relative, far below the 1e-2 relative accuracy a Mahalanobis bound needs)."""
    h, J = 1e-6, np.zeros((2 * len(X), 6))
    for k in range(6):
        d = np.zeros(6)
        d[k] = h
        plus = camera.img_from_cam(X @ (rotation(d[:3]) @ R).T + t + d[3:]) if k < 3 else \
            camera.img_from_cam(X @ R.T + t + d[3:])
        d[k] = -h
        minus = camera.img_from_cam(X @ (rotation(d[:3]) @ R).T + t + d[3:]) if k < 3 else \
            camera.img_from_cam(X @ R.T + t + d[3:])
        J[:, k] = ((plus - minus) / (2 * h)).reshape(-1)
    return J.T @ J


def lens_tables(seeds=(0, 1, 2), **kwargs):
    """Queries ``10 * model index + seed`` of :func:`scene` for each lens of :data:`LENSES`, as the
    tables of ``localize_tables`` with ``model`` and ``params`` columns; and each query's scene."""
    queries, points, scenes = {"query": [], "model": [], "params": []}, [], {}
    for m, model in enumerate(LENSES):
        for seed in seeds:
            q = 10 * m + seed
            scenes[q] = scene(model, 1000 * m + seed, **kwargs)
            camera, _, _, X, u, _ = scenes[q]
            queries["query"].append(q)
            queries["model"].append(model)
            queries["params"].append(list(camera.params))
            points.append(np.c_[np.full(len(u), q), u, X])
    rows = np.concatenate(points)
    matches = pa.table({name: rows[:, i].astype(np.int64) if name == "query" else rows[:, i]
                        for i, name in enumerate(dist.POINT_MATCH_COLUMNS)})
    return pa.table({"query": pa.array(queries["query"], pa.int64()), "model": queries["model"],
                     "params": pa.array(queries["params"], pa.list_(pa.float64()))}), matches, scenes


def write_tables(folder: Path, **tables) -> dict[str, str]:
    folder.mkdir(parents=True, exist_ok=True)
    paths = {}
    for name, table in tables.items():
        pq.write_table(table, folder / f"{name}.parquet")
        paths[name] = str(folder / f"{name}.parquet")
    return paths


def same(a, b) -> bool:
    """Equal column names and values, bit for bit, NaN equal to NaN (``Table.equals`` says NaN ≠ NaN)."""
    if a.column_names != b.column_names or a.num_rows != b.num_rows:
        return False
    for name in a.column_names:
        x, y = a.column(name).combine_chunks(), b.column(name).combine_chunks()
        if pa.types.is_fixed_size_list(x.type):
            x, y = x.flatten(), y.flatten()
        x, y = x.to_numpy(zero_copy_only=False), y.to_numpy(zero_copy_only=False)
        if not np.array_equal(x, y, equal_nan=x.dtype.kind == "f"):
            return False
    return True


def poses_by_query(poses) -> dict[int, tuple[np.ndarray, np.ndarray, str]]:
    R = np.asarray(poses.column("R").to_pylist(), dtype=float).reshape(-1, 3, 3)
    t = np.asarray(poses.column("t").to_pylist(), dtype=float).reshape(-1, 3)
    return {q: (r, tt, s) for q, r, tt, s in zip(poses.column("query").to_pylist(), R, t,
                                                   poses.column("status").to_pylist())}


def inliers_by_query(matches) -> dict[int, np.ndarray]:
    q = matches.column("query").to_numpy()
    flags = matches.column("inlier").to_numpy(zero_copy_only=False)
    return {int(i): flags[q == i] for i in np.unique(q)}


def sorted_points(point_matches, q: int) -> tuple[np.ndarray, np.ndarray]:
    """Query ``q``'s pixels and world points in the order of the ``matches`` table (sorted by x, y, X, Y, Z)."""
    rows = point_matches.filter(pc.equal(point_matches.column("query"), q))
    values = np.c_[[rows.column(c).to_numpy() for c in dist.POINT_MATCH_COLUMNS[1:]]].T
    values = values[np.lexsort(values.T[::-1])]
    return values[:, :2], values[:, 2:]


# --- lens cameras: accuracy and thresholds ----------------------------------------------------------------


@pytest.fixture(scope="module")
def lens_run(tmp_path_factory):
    """``pluecker localize`` on the nine lens queries, at the default threshold (4 px) and at 1 px."""
    queries, points, scenes = lens_tables()
    folder = tmp_path_factory.mktemp("lens")
    paths = write_tables(folder, queries=queries, points=points)
    runs = {}
    for threshold in (None, 1.0):
        out = folder / f"out-{threshold}"
        flags = [] if threshold is None else ["--point-threshold", str(threshold)]
        assert main(["localize", paths["queries"], paths["points"], "--out", str(out), *flags]) == 0
        runs[threshold] = (dist.read_poses(out), dist.read_matches(out))
    return queries, points, scenes, runs


@pytest.mark.parametrize("model", LENSES)
def test_lens_queries_are_localised_to_the_accuracy_the_noise_allows(lens_run, model):
    queries, points, scenes, runs = lens_run
    poses, matches = runs[None]
    found, flags = poses_by_query(poses), inliers_by_query(matches)
    for q in [10 * LENSES.index(model) + s for s in (0, 1, 2)]:
        camera, R, t, X, u, outliers = scenes[q]
        R_hat, t_hat, status = found[q]
        assert status == "success", (model, q, status)
        u_sorted, X_sorted = sorted_points(points, q)
        inlier = flags[q]
        truth_inlier = ~outliers[np.lexsort(np.c_[u, X].T[::-1])]
        # Every true inlier kept (σ = 0.5 px: none is beyond 4 px, P = e^-32), no random pixel accepted.
        np.testing.assert_array_equal(inlier, truth_inlier, err_msg=f"{model} query {q}")
        # The maximum-likelihood pose lies within the noise's ellipsoid about the truth: squared
        # Mahalanobis distance under the Fisher information σ⁻² JᵀJ (pycolmap's projection) below the
        # χ²₆ quantile. A pose that ignores the distortion is off by tens of pixels: a distance of 1e4+.
        e = np.r_[log_rotation(R_hat @ R.T), t_hat - t]  # (ω, δ) with R̂ = exp(ω) R, t̂ = t + δ
        m2 = e @ fisher(camera, R, t, X_sorted[inlier]) @ e / SIGMA**2
        assert m2 < CHI2_6, (model, q, m2)
        # And it minimises the pixel cost over its inliers: not above the truth's cost there (the
        # truth's exceeds the minimum by σ² χ²₆ ≈ 1.5 px² on average; pluecker's first-order pixel cost
        # moves its minimiser by O(σ³/f), a 1e-6 px² effect).
        cost = lambda Rp, tp: np.sum(residuals(camera, Rp, tp, X_sorted[inlier], u_sorted[inlier]) ** 2)  # noqa: E731
        assert cost(R_hat, t_hat) <= cost(R, t), (model, q, cost(R_hat, t_hat), cost(R, t))


@pytest.mark.parametrize("threshold", [None, 1.0])
def test_the_threshold_decides_the_inliers_in_the_images_own_pixels(lens_run, threshold):
    """A match is an inlier exactly when its distance in the image's own (distorted) pixels at the
    returned pose is within the threshold (default 4 px). The decision is made on the first-order
    pixel error, which differs from the exact one by O(r² |∇²u|) — below 0.02 px at r ≤ 4 px on these
    lenses — so matches within 0.05 px of the threshold are not judged."""
    queries, points, scenes, runs = lens_run
    poses, matches = runs[threshold]
    tau = 4.0 if threshold is None else threshold
    found, flags = poses_by_query(poses), inliers_by_query(matches)
    judged = 0
    for q, (camera, *_rest) in scenes.items():
        R_hat, t_hat, status = found[q]
        assert status == "success"
        u, X = sorted_points(points, q)
        r = residuals(camera, R_hat, t_hat, X, u)
        clear = np.abs(r - tau) > 0.05
        np.testing.assert_array_equal(flags[q][clear], r[clear] <= tau, err_msg=f"query {q}, threshold {tau}")
        judged += int(clear.sum())
    assert judged > 0.95 * sum(len(s[3]) for s in scenes.values())


def test_a_tighter_threshold_keeps_fewer_inliers(lens_run):
    """At 1 px, σ = 0.5 px keeps 1 - e^-2 = 86 % of the true inliers; at 4 px all of them: the 1 px set
    is strictly smaller, and (being the matches within 1 px of nearly the same pose) inside the 4 px set."""
    _, _, scenes, runs = lens_run
    wide, tight = inliers_by_query(runs[None][1]), inliers_by_query(runs[1.0][1])
    for q in scenes:
        assert tight[q].sum() < wide[q].sum(), q
        assert not np.any(tight[q] & ~wide[q]), q
        assert 0.6 < tight[q].sum() / wide[q].sum() < 0.98, (q, tight[q].sum(), wide[q].sum())


def test_the_command_line_equals_the_python_kernel(lens_run):
    queries, points, _, runs = lens_run
    for threshold, ransac in ((None, None), (1.0, pluecker.RansacOptions(point_threshold=1.0))):
        poses, matches = dist.localize_tables(queries, points, ransac=ransac)
        assert same(poses, runs[threshold][0]) and same(matches, runs[threshold][1])


def test_the_ransac_flags_reach_the_estimator(tmp_path, monkeypatch):
    """Every RANSAC flag sets its field of ``RansacOptions``; ``ransac.seed`` adds to ``--seed``."""
    seen = []
    real = dist.localize_tables

    def spy(*args, **kwargs):
        seen.append(kwargs["ransac"].to_dict())
        return real(*args, **kwargs)

    monkeypatch.setattr(dist, "localize_tables", spy)
    queries, points, _ = lens_tables(seeds=(0,))
    paths = write_tables(tmp_path, queries=queries, points=points)
    flags = ["--point-threshold", "2.5", "--line-threshold", "3.5", "--confidence", "0.99", "--max-iterations", "77",
             "--min-inliers", "9", "--time-budget", "5"]
    assert main(["localize", paths["queries"], paths["points"], "--out", str(tmp_path / "o"), *flags]) == 0
    assert seen and all(s == {**pluecker.RansacOptions().to_dict(), "point_threshold": 2.5, "line_threshold": 3.5,
                              "confidence": 0.99, "max_iterations": 77, "min_inliers": 9, "time_budget": 5.0}
                        for s in seen)


@pytest.mark.parametrize("flag, value, message", [
    ("--confidence", "1.5", "expected a number in (0, 1)"),
    ("--point-threshold", "-1", "expected a positive number"),
    ("--max-iterations", "0", "expected a positive integer"),
    ("--min-inliers", "2", "min_inliers: must be an integer from 3"),
])
def test_a_bad_ransac_flag_is_one_line_and_exit_2(tmp_path, capsys, flag, value, message):
    queries, points, _ = lens_tables(seeds=(0,))
    paths = write_tables(tmp_path, queries=queries, points=points)
    assert main(["localize", paths["queries"], paths["points"], "--out", str(tmp_path / "o"), flag, value]) == 2
    err = capsys.readouterr().err
    assert message in err and err.count("\n") == 1, err
    assert not (tmp_path / "o" / "poses").exists()


def test_the_ransac_seed_adds_to_the_job_seed():
    """Query ``q`` is seeded ``ransac.seed + seed + q``: (3, 0) and (0, 3) give the same bits, (0, 0)
    other ones (one sample per query at 30 % outliers: the sample decides the answer)."""
    queries, points, _ = lens_tables(seeds=(0, 1))
    one = dict(max_iterations=1, min_iterations=1, local_iterations=0)
    a = dist.localize_tables(queries, points, ransac=pluecker.RansacOptions(seed=3, **one))[0]
    b = dist.localize_tables(queries, points, ransac=pluecker.RansacOptions(**one), seed=3)[0]
    c = dist.localize_tables(queries, points, ransac=pluecker.RansacOptions(**one))[0]
    assert same(a, b) and not same(a, c)


# --- bad queries ---------------------------------------------------------------------------------------------


def test_a_bad_camera_is_its_querys_status_and_the_others_are_unaffected():
    queries, points, scenes = lens_tables(seeds=(0,))
    good = dist.localize_tables(queries, points)[0]
    bad_rows = {  # query id: (model, params) cells, and what the message must say
        101: ("OPENCVX", [1.0, 2.0], r"query 101: queries column model: 'OPENCVX' is not a COLMAP camera model"),
        102: ("OPENCV", [800.0, 800.0, 320.0, 240.0], r"query 102: queries column params: .*expected 8 values"),
        103: ("OPENCV", [800.0, 800.0, 320.0, 240.0, 0.0, 0.0, 0.0, float("nan")],
              r"query 103: queries column params: .*non-finite"),
        104: ("OPENCV", None, r"query 104: queries column params: expected a list of numbers"),
        105: (None, [800.0, 320.0, 240.0], r"query 105: queries column model: None is not a COLMAP camera model"),
    }
    extra_points = points.filter(pc.equal(points.column("query"), 0))
    rows = [extra_points.set_column(0, "query", pa.array(np.full(extra_points.num_rows, q), pa.int64()))
            for q in bad_rows]
    mixed_queries = pa.concat_tables([queries, pa.table({
        "query": pa.array(list(bad_rows), pa.int64()), "model": pa.array([v[0] for v in bad_rows.values()], pa.string()),
        "params": pa.array([v[1] for v in bad_rows.values()], pa.list_(pa.float64()))})])
    poses, _ = dist.localize_tables(mixed_queries, pa.concat_tables([points, *rows]))
    status = dict(zip(poses.column("query").to_pylist(), poses.column("status").to_pylist()))
    message = dict(zip(poses.column("query").to_pylist(), poses.column("message").to_pylist()))
    for q, (_, _, pattern) in bad_rows.items():
        assert status[q] == "invalid_input" and re.match(pattern, message[q]), (q, message[q])
    kept = poses.filter(pc.is_in(poses.column("query"), good.column("query")))
    assert same(kept, good)


def test_the_query_table_gives_one_set_of_camera_columns():
    queries, points, _ = lens_tables(seeds=(0,))
    both = queries.append_column("fx", pa.array(np.full(queries.num_rows, 800.0)))
    for name in ("fy", "cx", "cy"):
        both = both.append_column(name, pa.array(np.full(queries.num_rows, 1.0)))
    with pytest.raises(pluecker.ShapeError, match=r"^queries: one camera per query: give the columns of one of "
                                                  r"fx, fy, cx, cy or model, params, not both"):
        dist.localize_tables(both, points)
    ids = pa.table({"query": queries.column("query"), "camera_id": pa.array(np.ones(queries.num_rows, np.int64))})
    with pytest.raises(pluecker.ShapeError, match=r"^queries: column camera_id names cameras of a COLMAP model"):
        dist.localize_tables(ids, points)
    with pytest.raises(pluecker.ShapeError, match=r"^queries: missing column\(s\) fx, fy, cx, cy; .*or query, "
                                                  r"model, params \(a COLMAP camera model\)$"):
        dist.localize_tables(queries.select(["query"]), points)


def test_query_records_with_camera_models_make_the_model_columns():
    camera, R, t, X, u, _ = scene("OPENCV", 5)
    records = [{"query": 1, "camera": camera, "points2d": u, "points3d": X},
               {"query": 2, "camera": pluecker.Camera("OPENCV", list(camera.params)), "points2d": u, "points3d": X},
               {"query": 3, "camera": {"model": "OPENCV", "params": list(camera.params)}, "points2d": u, "points3d": X},
               {"query": 4, "camera": (800.0, 790.0, 320.0, 240.0), "points2d": u, "points3d": X}]
    queries, points, lines = dist.queries_to_tables(records)
    assert queries.column("model").to_pylist() == ["OPENCV"] * 3 + ["PINHOLE"]
    poses = dist.localize_tables(queries, points, lines)[0]
    found = poses_by_query(poses)
    for q in (1, 2, 3):
        # One camera three ways: the same inliers and optimum; the queries' RANSAC seeds differ (seed + q),
        # so the refinement starts elsewhere and stops within its tolerance of the same point.
        assert found[q][2] == "success"
        np.testing.assert_allclose(found[q][0], found[1][0], atol=1e-8)
        np.testing.assert_allclose(found[q][1], found[1][1], atol=1e-8)
        assert np.degrees(np.arccos(np.clip((np.trace(found[q][0] @ R.T) - 1) / 2, -1, 1))) < 0.5


# --- COLMAP models: point3D_id and camera_id ------------------------------------------------------------


def colmap_queries(seed: int = 0):
    """A synthetic SIMPLE_RADIAL model and its images as queries: (model, queries, matches) tables with
    ``camera_id`` and ``point3D_id``, 1 px noise on the keypoints."""
    pycolmap.set_random_seed(seed)
    rec = pycolmap.synthesize_dataset(pycolmap.SyntheticDatasetOptions(num_frames_per_rig=3, num_points3D=150))
    rng = np.random.default_rng(seed)
    queries, matches = {"query": [], "camera_id": []}, {"query": [], "x": [], "y": [], "point3D_id": []}
    for image in rec.images.values():
        queries["query"].append(image.image_id)
        queries["camera_id"].append(image.camera_id)
        for keypoint in image.points2D:
            if keypoint.has_point3D():
                xy = keypoint.xy + rng.normal(0, 1, 2)
                matches["query"].append(image.image_id)
                matches["x"].append(xy[0])
                matches["y"].append(xy[1])
                matches["point3D_id"].append(keypoint.point3D_id)
    return rec, pa.table(queries), pa.table({k: pa.array(v, pa.int64() if k in ("query", "point3D_id") else None)
                                             for k, v in matches.items()})


def test_colmap_queries_by_camera_id_and_point3D_id_find_the_models_poses(tmp_path):
    rec, queries, matches = colmap_queries()
    poses, out_matches = dist.localize_tables(queries, matches, reconstruction=rec)
    found = poses_by_query(poses)
    for image in rec.images.values():
        R, t = colmap.pose_from_rigid(image.cam_from_world())
        R_hat, t_hat, status = found[image.image_id]
        assert status == "success"
        # 1 px noise on ~50-150 keypoints spread over a fifth of the focal length, at 5 units: a few
        # hundredths of a degree; a wrong point lookup (a neighbouring point3D_id) is off by degrees.
        assert np.degrees(np.arccos(np.clip((np.trace(R_hat @ R.T) - 1) / 2, -1, 1))) < 0.5
        assert np.linalg.norm(-R_hat.T @ t_hat + R.T @ t) < 0.1
    # The matches table names each point match's point3D_id, in the kernel's order.
    assert out_matches.column("point3D_id").null_count == 0
    assert sorted(out_matches.column("point3D_id").to_pylist()) == sorted(matches.column("point3D_id").to_pylist())
    # The in-memory function, the Parquet job and the command line give the same bits.
    paths = write_tables(tmp_path, queries=queries, matches=matches)
    (tmp_path / "model").mkdir()
    rec.write(str(tmp_path / "model"))
    summary = dist.localize(paths["queries"], paths["matches"], tmp_path / "job", reconstruction=rec, buckets=3)
    assert summary.statuses == {"success": len(rec.images)}
    assert same(dist.read_poses(tmp_path / "job"), poses)
    assert same(dist.read_matches(tmp_path / "job"), out_matches)
    assert main(["localize", paths["queries"], paths["matches"], "--colmap", str(tmp_path / "model"), "--out",
                 str(tmp_path / "cli")]) == 0
    assert same(dist.read_poses(tmp_path / "cli"), poses)


def test_an_unknown_camera_id_or_point3D_id_is_named_and_loses_no_other_query(tmp_path, capsys):
    rec, queries, matches = colmap_queries(1)
    good, _ = dist.localize_tables(queries, matches, reconstruction=rec)
    first = queries.column("query")[0].as_py()
    ids = matches.column("point3D_id").to_numpy().copy()
    bad_point = int(np.max(ids)) + 1000
    second = queries.column("query")[1].as_py()
    ids[np.flatnonzero(matches.column("query").to_numpy() == second)[:2]] = bad_point
    camera_ids = queries.column("camera_id").to_numpy().copy()
    camera_ids[0] = 99
    queries_bad = queries.set_column(1, "camera_id", pa.array(camera_ids))
    matches_bad = matches.set_column(3, "point3D_id", pa.array(ids))
    poses, _ = dist.localize_tables(queries_bad, matches_bad, reconstruction=rec)
    message = dict(zip(poses.column("query").to_pylist(), poses.column("message").to_pylist()))
    assert message[first] == f"query {first}: queries column camera_id: camera_id 99 is not a camera of the COLMAP model"
    assert message[second] == (f"query {second}: point_matches column point3D_id: point3D_id {bad_point} is not a "
                               "point of the COLMAP model (2 such matches)")
    others = [q for q in good.column("query").to_pylist() if q not in (first, second)]
    keep = lambda t: t.filter(pc.is_in(t.column("query"), pa.array(others)))  # noqa: E731
    assert same(keep(poses), keep(good)) and len(others) == len(rec.images) - 2
    # The command line prints the failed queries' messages and still writes every pose.
    paths = write_tables(tmp_path, queries=queries_bad, matches=matches_bad)
    (tmp_path / "model").mkdir()
    rec.write(str(tmp_path / "model"))
    assert main(["localize", paths["queries"], paths["matches"], "--colmap", str(tmp_path / "model"), "--out",
                 str(tmp_path / "o")]) == 0
    out = capsys.readouterr().out
    assert f"{len(others)} success" in out and "2 invalid_input" in out
    assert "camera_id 99 is not a camera" in out and f"point3D_id {bad_point} is not a point" in out
    assert dist.read_poses(tmp_path / "o").num_rows == len(rec.images)


def test_localize_in_model_takes_a_camera_id_and_point3D_ids():
    rec, _, _ = colmap_queries(2)
    image = next(iter(rec.images.values()))
    keypoints = [p for p in image.points2D if p.has_point3D()]
    xy, ids = np.array([p.xy for p in keypoints]), np.array([p.point3D_id for p in keypoints])
    rigid, result = colmap.localize_in_model(rec, image.camera_id, xy, ids)
    R, t = colmap.pose_from_rigid(image.cam_from_world())
    # Exact keypoints: the pose to the refinement's tolerance (the pixels are COLMAP's own projections).
    np.testing.assert_allclose(colmap.pose_from_rigid(rigid)[0], R, atol=1e-7)
    np.testing.assert_allclose(colmap.pose_from_rigid(rigid)[1], t, atol=1e-6)
    # The same from a ColmapModel, and with the pycolmap camera instead of its id.
    model = colmap.ColmapModel.from_reconstruction(rec)
    for args in ((model, image.camera_id), (rec, rec.cameras[image.camera_id])):
        other = colmap.localize_in_model(args[0], args[1], xy, ids)[1]
        np.testing.assert_array_equal(other.pose.rotation, result.pose.rotation)
    with pytest.raises(colmap.MatchError, match=r"^camera: camera_id 42 is not a camera of the model$"):
        colmap.localize_in_model(rec, 42, xy, ids)
    ids[5] = 10**9
    with pytest.raises(colmap.MatchError, match=r"^point3D_ids: point3D_id 1000000000 \(match 5\) is not a point"):
        colmap.localize_in_model(rec, image.camera_id, xy, ids)
    assert issubclass(colmap.MatchError, ValueError)


def test_colmap_flag_errors_are_one_line(tmp_path, capsys):
    rec, queries, matches = colmap_queries(3)
    paths = write_tables(tmp_path, queries=queries, matches=matches)
    assert main(["localize", paths["queries"], paths["matches"], "--colmap", str(tmp_path / "none"), "--out",
                 str(tmp_path / "o")]) == 2
    assert "--colmap " in capsys.readouterr().err
    # Without --colmap the tables lack X, Y, Z (and camera_id needs a model): named, exit 2.
    assert main(["localize", paths["queries"], paths["matches"], "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err
    assert "column camera_id names cameras of a COLMAP model" in err and err.count("\n") == 1


def test_a_rerun_into_the_same_folder_leaves_no_stale_parts(tmp_path):
    rec, queries, matches = colmap_queries(4)
    paths = write_tables(tmp_path, queries=queries, matches=matches)
    dist.localize(paths["queries"], paths["matches"], tmp_path / "o", reconstruction=rec, buckets=7)
    dist.localize(paths["queries"], paths["matches"], tmp_path / "o", reconstruction=rec, buckets=2)
    assert dist.read_poses(tmp_path / "o").num_rows == len(rec.images)


# --- docs ----------------------------------------------------------------------------------------------------


def test_the_docs_colmap_example_runs_as_written(tmp_path):
    """The script and the command of docs/cli.md, run in an empty folder in fresh processes; the output
    is the one shown (but the time), and the poses are the model's."""
    section = CLI_MD[CLI_MD.index("### Localising images in a COLMAP model"):]
    script = re.search(r"```python\n(.*?)```", section, re.S).group(1)
    commands = re.search(r"```\n(python make_example.py\n.*?)```", section, re.S).group(1).splitlines()
    shown = re.search(r"prints \(a real run; the time varies\)\n\n```\n(.*?)```", section, re.S).group(1)
    (tmp_path / "make_example.py").write_text(script, encoding="utf-8")
    assert commands[0] == "python make_example.py"
    subprocess.run([sys.executable, "make_example.py"], cwd=tmp_path, check=True, capture_output=True)
    words = shlex.split(commands[1])
    assert words[0] == "pluecker"
    executable = Path(sys.executable).with_name("pluecker")  # the installed command, as a user runs it
    command = [str(executable)] if executable.exists() else [sys.executable, "-m", "pluecker.cli"]
    run = subprocess.run([*command, *words[1:]], cwd=tmp_path, capture_output=True, text=True)
    assert run.returncode == 0, run.stderr
    mask = lambda text: re.sub(r"in \d+\.\d s", "in T s", text)  # noqa: E731
    assert mask(run.stdout) == mask(shown)
    rec = pycolmap.Reconstruction(str(tmp_path / "model"))
    found = poses_by_query(dist.read_poses(tmp_path / "located"))
    assert len(found) == len(rec.images)
    for image in rec.images.values():
        R, t = colmap.pose_from_rigid(image.cam_from_world())
        # Exact keypoints (COLMAP's projections): equal to the refinement's tolerance.
        np.testing.assert_allclose(found[image.image_id][0], R, atol=1e-7)
        np.testing.assert_allclose(found[image.image_id][1], t, atol=1e-6)


def test_the_localize_flag_table_lists_every_flag():
    from test_cli_docs import documented_flags, parser_flags, section, table_column

    documented = documented_flags(table_column(section(CLI_MD, "## `pluecker localize`"), "| flag |"))
    assert documented == parser_flags("localize")
    row = next(r for r in table_column(CLI_MD, "| command |") if r.startswith("`pluecker localize "))
    assert documented_flags([row]) == parser_flags("localize")


def test_a_colmap_job_on_a_dask_cluster_equals_the_kernel(tmp_path, capsys):
    """The model goes to the workers once (pickled); the poses are those of the in-process kernel."""
    distributed = pytest.importorskip("distributed")
    rec, queries, matches = colmap_queries(5)
    paths = write_tables(tmp_path, queries=queries, matches=matches)
    (tmp_path / "model").mkdir()
    rec.write(str(tmp_path / "model"))
    reference = dist.localize_tables(queries, matches, reconstruction=rec)
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=":0",
                                  silence_logs=40) as cluster, distributed.Client(cluster) as client:
        summary = dist.localize(paths["queries"], paths["matches"], tmp_path / "dask", client=client, buckets=4,
                                reconstruction=rec)
        assert main(["localize", paths["queries"], paths["matches"], "--colmap", str(tmp_path / "model"), "--out",
                     str(tmp_path / "cli"), "--scheduler", cluster.scheduler_address]) == 0
    assert summary.workers == 2 and summary.statuses == {"success": len(rec.images)}
    assert f"{len(rec.images)} queries on 2 Dask workers" in capsys.readouterr().out
    for folder in ("dask", "cli"):
        assert same(dist.read_poses(tmp_path / folder), reference[0])
        assert same(dist.read_matches(tmp_path / folder), reference[1])


def test_the_documented_ransac_defaults_are_the_options_defaults(monkeypatch):
    """The defaults in ``--help`` and in docs/cli.md's flag table are ``RansacOptions()``'s."""
    from pluecker.cli import LOCALIZE_RANSAC_FLAGS
    from test_cli_docs import help_text, section

    defaults = pluecker.RansacOptions().to_dict()
    text = help_text("localize", monkeypatch)
    rows = {line.split("|")[1].strip().split()[0].strip("`"): line.split("|")[2].strip()
            for line in section(CLI_MD, "## `pluecker localize`").splitlines() if line.startswith("| `--")}
    for attribute, field in LOCALIZE_RANSAC_FLAGS.items():
        flag = "--" + attribute.replace("_", "-")
        shown = re.search(re.escape(flag) + r" \S+ .*?\(default ([^):]+)", text).group(1)
        value = defaults[field]
        if value is None:
            assert shown.startswith("none") and rows[flag] == "none", flag
        else:
            assert float(shown) == value and float(rows[flag]) == value, (flag, shown, rows[flag], value)


def rig_frame_tables(noise_px: float = 1.0):
    """A synthetic COLMAP model with one rig of three lens models, and its frames as queries
    (``query``, ``rig_id``) with the keypoints of all their images as point matches (``query``,
    ``camera_id``, ``x``, ``y``, ``point3D_id``)."""
    from pluecker import scenes

    cameras = [("PINHOLE", [500.0, 500.0, 320.0, 240.0]),
               ("OPENCV", [450.0, 455.0, 320.0, 240.0, -0.05, 0.01, 1e-3, -1e-3]),
               ("SIMPLE_RADIAL", [400.0, 320.0, 240.0, 0.02])]
    rec = scenes.colmap_rig_reconstruction(cameras, 640, 480, noise_px=noise_px, seed=12, points=300, frames=4)
    (rig_id,) = rec.rigs
    queries = {"query": [], "rig_id": []}
    matches = {"query": [], "camera_id": [], "x": [], "y": [], "point3D_id": []}
    for image in rec.images.values():
        if image.frame_id not in queries["query"]:
            queries["query"].append(image.frame_id)
            queries["rig_id"].append(rig_id)
        for point2D in image.points2D:
            if point2D.has_point3D():
                for key, value in zip(matches, (image.frame_id, image.camera_id, *point2D.xy, point2D.point3D_id)):
                    matches[key].append(value)
    return rec, pa.table(queries), pa.table(matches)


def test_frames_of_a_colmap_rig_are_localised_by_rig_id(tmp_path, capsys):
    """Queries by ``rig_id``, matches by ``camera_id`` and ``point3D_id``: each frame's
    ``rig_from_world``, equal through the kernel, the Parquet job and the command line; a camera_id the
    rig does not hold is named, and the other frames are solved."""
    rec, queries, matches = rig_frame_tables()
    poses, _ = dist.localize_tables(queries, matches, reconstruction=rec)
    found = poses_by_query(poses)
    assert len(found) == 4
    for frame_id, (R_hat, t_hat, status) in found.items():
        R, t = colmap.pose_from_rigid(rec.frame(frame_id).rig_from_world)
        assert status == "success"
        # 1 px of noise on ~100-300 keypoints over three cameras, 5 units away: hundredths of a degree.
        assert np.degrees(np.arccos(np.clip((np.trace(R_hat @ R.T) - 1) / 2, -1, 1))) < 0.5
        assert np.linalg.norm(t_hat - t) < 0.1
    paths = write_tables(tmp_path, queries=queries, matches=matches)
    (tmp_path / "model").mkdir()
    rec.write(str(tmp_path / "model"))
    assert main(["localize", paths["queries"], paths["matches"], "--colmap", str(tmp_path / "model"), "--out",
                 str(tmp_path / "cli")]) == 0
    assert same(dist.read_poses(tmp_path / "cli"), poses)
    # A camera_id that is not one of the rig's: that frame is invalid_input, named; the others are solved.
    camera_ids = matches.column("camera_id").to_numpy().copy()
    first = matches.column("query")[0].as_py()
    camera_ids[0] = 77
    bad = matches.set_column(1, "camera_id", pa.array(camera_ids))
    poses_bad, _ = dist.localize_tables(queries, bad, reconstruction=rec)
    message = dict(zip(poses_bad.column("query").to_pylist(), poses_bad.column("message").to_pylist()))
    assert message[first].startswith(f"query {first}: point_matches column camera_id: 77 is not a camera of the "
                                     "query's rig")
    assert sorted(poses_bad.column("status").to_pylist()).count("success") == 3
    # Without the camera_id column the tables are refused by name.
    with pytest.raises(pluecker.ShapeError, match="point_matches.*camera_id"):
        dist.localize_tables(queries, matches.drop_columns(["camera_id"]), reconstruction=rec)
