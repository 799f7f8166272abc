"""pluecker against pycolmap and PoseLib on COLMAP models (issue 12 §6).

Models come from ``pycolmap.synthesize_dataset`` (2 rigs x 6 frames = 12 images, 500 points) with three
cameras of 1024 x 768 pixels: a narrow OPENCV (f = 2000 px, about 28 degrees across), a wide OPENCV
(f = 400 px, about 104 degrees) and an OPENCV_FISHEYE (f = 300 px). The structure is enlarged about its
centre (``SPREAD``) until it fills each image out to the corners (the synthetic one covers only 0.2 focal
lengths around the centre, where no distortion shows). Every observation gets 1 px of Gaussian noise.

1. **Re-triangulation** of every track with the cameras fixed:
   - ``pluecker``: ``pluecker.colmap.retriangulate`` (certified optimum through the camera model);
   - ``pycolmap BA``: ``pycolmap.bundle_adjustment`` refining only the points (intrinsics, rigs and
     poses constant), started from pycolmap's RANSAC triangulation, as COLMAP does;
   - ``pycolmap RANSAC``: ``pycolmap.estimate_triangulation`` per track (reprojection error, 4 px).
   Cost: the squared pixel reprojection error summed over all observations, computed for every method by
   pycolmap's own projection (``Camera.img_from_cam``). Then with one 40 px outlier in each of 100
   tracks of at least 6 views: outliers rejected, inliers dropped, RMS 3-D error on those tracks.
2. **Localisation** of every image from its 2D-3D matches, with 0, 30 and 60 % of them replaced by
   random pixels, each library with its own camera models: ``pluecker.colmap.localize``,
   ``pycolmap.estimate_and_refine_absolute_pose`` and ``poselib.estimate_absolute_pose`` (threshold 4 px for
   all). Median rotation error (degrees), median camera-centre error (scene units), failures, median
   time per image.
3. **Glue code**: the lines a user writes for each job beyond loading the model, counted from the
   functions ``job_*`` below.
4. **Sparse batch**: ``bench/sparse_tracks.py`` (1000 images x 200k tracks) is run as a subprocess for its
   time and peak memory.

5. **Localisation with lens cameras through the command line** (:func:`localize_section`):
   ``pluecker localize --colmap`` on a strong radial lens, a wide OPENCV and a fisheye to 80 degrees, and on
   a real model (``--localize-model DIR``), with 0 and 50 % outliers, against pycolmap and PoseLib:
   accuracy of the command line's poses, its end-to-end time, and each library's per-image solve time.

Run: ``.venv/bin/python bench/compare_colmap.py [--quick] [--localize-model DIR] [--localize-only]``; prints
Markdown tables.
"""

from __future__ import annotations

import argparse
import inspect
import re
import subprocess
import sys
import time
from pathlib import Path
from typing import Any, Callable

import numpy as np
import poselib
import pycolmap

import pluecker
from pluecker import colmap

CAMERAS = {
    "OPENCV narrow": (pycolmap.CameraModelId.OPENCV, [2000.0, 2000.0, 512.0, 384.0, -0.1, 0.02, 1e-4, -1e-4]),
    "OPENCV wide": (pycolmap.CameraModelId.OPENCV, [400.0, 400.0, 512.0, 384.0, -0.25, 0.06, 5e-4, -5e-4]),
    "OPENCV_FISHEYE": (pycolmap.CameraModelId.OPENCV_FISHEYE, [300.0, 300.0, 512.0, 384.0, 0.05, -0.01, 0.002, -3e-4]),
}
#: How much the synthetic structure (about 2 units across, seen from 5 units) is enlarged about its centre
#: so that it fills each camera's image; observations then outside the image or within 0.5 units of a
#: camera's principal plane are dropped.
SPREAD = {"OPENCV narrow": 1.0, "OPENCV wide": 5.0, "OPENCV_FISHEYE": 6.0}
THRESHOLD_PX = 4.0


# --------------------------------------------------------------------------------------------------
# The jobs as a user writes them (section 3 counts their lines).


def job_pluecker_triangulate(rec: Any, out: Path) -> Any:
    run = colmap.retriangulate(rec)
    colmap.write(rec, run, out)
    return run


def job_pycolmap_triangulate_and_ba(rec: Any) -> None:
    for point_id, point in rec.points3D.items():
        elements = point.track.elements
        images = [rec.images[e.image_id] for e in elements]
        xy = np.array([im.points2D[e.point2D_idx].xy for im, e in zip(images, elements)])
        options = pycolmap.EstimateTriangulationOptions()
        options.residual_type = pycolmap.TriangulationResidualType.REPROJECTION_ERROR
        options.ransac.max_error = THRESHOLD_PX
        found = pycolmap.estimate_triangulation(
            xy, [im.cam_from_world() for im in images], [rec.cameras[im.camera_id] for im in images], options)
        if found is not None:
            point.xyz = found["xyz"]
    options = pycolmap.BundleAdjustmentOptions(
        refine_focal_length=False, refine_extra_params=False, refine_principal_point=False,
        refine_rig_from_world=False, refine_sensor_from_rig=False, print_summary=False)
    pycolmap.bundle_adjustment(rec, options)


def job_pluecker_localize(camera: Any, u: np.ndarray, X: np.ndarray) -> Any:
    rigid, result = colmap.localize(camera, u, X)
    return rigid


def job_pycolmap_localize(camera: Any, u: np.ndarray, X: np.ndarray) -> Any:
    options = pycolmap.AbsolutePoseEstimationOptions()
    options.ransac.max_error = THRESHOLD_PX
    found = pycolmap.estimate_and_refine_absolute_pose(u, X, camera, options)
    return None if found is None else found["cam_from_world"]


def job_poselib_localize(camera: Any, u: np.ndarray, X: np.ndarray) -> Any:
    cam = {"model": camera.model.name, "width": camera.width, "height": camera.height, "params": list(camera.params)}
    pose, info = poselib.estimate_absolute_pose(u, X, cam, {"max_reproj_error": THRESHOLD_PX}, {})
    return pose


def glue_lines(job: Callable[..., Any]) -> int:
    """Statements in the body of ``job``, its ``return`` line excluded (what a user types)."""
    body = inspect.getsource(job).splitlines()[1:]
    lines = [l.strip() for l in body if l.strip() and not l.strip().startswith("#")]
    statements = [l for l in lines if not l.startswith("return")]
    # Continuation lines of one call count once: those that start inside an open bracket.
    depth, count = 0, 0
    for line in statements:
        if depth == 0:
            count += 1
        depth += line.count("(") + line.count("[") + line.count("{") - line.count(")") - line.count("]") - line.count("}")
    return count


# --------------------------------------------------------------------------------------------------


def model(camera: str, seed: int, points: int = 500) -> tuple[Any, dict[int, np.ndarray]]:
    """A synthetic model with 1 px noise on every observation, and the true points."""
    model_id, params = CAMERAS[camera]
    options = pycolmap.SyntheticDatasetOptions()
    options.num_rigs, options.num_frames_per_rig, options.num_points3D = 2, 6, points
    options.camera_model_id, options.camera_params = model_id, params
    pycolmap.set_random_seed(seed)
    rec = pycolmap.synthesize_dataset(options)
    centre = np.mean([p.xyz for p in rec.points3D.values()], axis=0)
    for p in rec.points3D.values():
        p.xyz = centre + SPREAD[camera] * (p.xyz - centre)
    rng = np.random.default_rng(seed)
    for image in rec.images.values():
        camera_model = rec.cameras[image.camera_id]
        for idx, point2D in enumerate(image.points2D):
            if not point2D.has_point3D():
                continue
            x_cam = image.cam_from_world() * rec.points3D[point2D.point3D_id].xyz
            u = camera_model.img_from_cam(np.atleast_2d(x_cam))[0] if x_cam[2] > 0.5 else np.full(2, -1.0)
            if not (0 <= u[0] < camera_model.width and 0 <= u[1] < camera_model.height):
                rec.delete_observation(image.image_id, idx)
                continue
            point2D.xy = u + rng.normal(size=2)
    truth = {i: np.array(p.xyz) for i, p in rec.points3D.items()}
    return rec, truth


def pixel_cost(rec: Any, point_id: int, X: np.ndarray, skip: set | None = None) -> float:
    """Squared pixel reprojection error of ``X`` over the track of ``point_id`` (pycolmap's projection)."""
    total = 0.0
    for e in rec.points3D[point_id].track.elements:
        if skip and (e.image_id, e.point2D_idx) in skip:
            continue
        image = rec.images[e.image_id]
        u = rec.cameras[image.camera_id].img_from_cam(np.atleast_2d(image.cam_from_world() * X))[0]
        total += float(np.sum((u - image.points2D[e.point2D_idx].xy) ** 2))
    return total


def add_outliers(rec: Any, count: int, rng: np.random.Generator) -> tuple[set, set[int]]:
    """One 40 px outlier in each of ``count`` tracks of at least 6 views: the observations and tracks."""
    long = [i for i, p in sorted(rec.points3D.items()) if p.track.length() >= 6]
    chosen = rng.choice(long, size=min(count, len(long)), replace=False)
    observations = set()
    for point_id in chosen:
        elements = rec.points3D[int(point_id)].track.elements
        e = elements[rng.integers(len(elements))]
        angle = rng.uniform(0, 2 * np.pi)
        p2d = rec.images[e.image_id].points2D[e.point2D_idx]
        p2d.xy = p2d.xy + 40.0 * np.array([np.cos(angle), np.sin(angle)])
        observations.add((e.image_id, e.point2D_idx))
    return observations, {int(i) for i in chosen}


def pycolmap_ransac(rec: Any) -> tuple[dict[int, np.ndarray], dict[int, set], float]:
    """pycolmap's RANSAC triangulation of every track: points, rejected observations, seconds."""
    options = pycolmap.EstimateTriangulationOptions()
    options.residual_type = pycolmap.TriangulationResidualType.REPROJECTION_ERROR
    options.ransac.max_error = THRESHOLD_PX
    options.ransac.random_seed = 0
    points, rejected = {}, {}
    started = time.perf_counter()
    for point_id, point in rec.points3D.items():
        elements = point.track.elements
        images = [rec.images[e.image_id] for e in elements]
        xy = np.array([im.points2D[e.point2D_idx].xy for im, e in zip(images, elements)])
        found = pycolmap.estimate_triangulation(
            xy, [im.cam_from_world() for im in images], [rec.cameras[im.camera_id] for im in images], options)
        if found is not None:
            points[point_id] = np.asarray(found["xyz"])
            rejected[point_id] = {(e.image_id, e.point2D_idx) for e, ok in zip(elements, found["inliers"]) if not ok}
    return points, rejected, time.perf_counter() - started


def pycolmap_ba(rec: Any, start: dict[int, np.ndarray]) -> tuple[dict[int, np.ndarray], float]:
    """pycolmap's bundle adjustment of the points only, from ``start``: points and seconds."""
    copy = pycolmap.Reconstruction(rec)
    for point_id, X in start.items():
        copy.points3D[point_id].xyz = X
    options = pycolmap.BundleAdjustmentOptions(
        refine_focal_length=False, refine_extra_params=False, refine_principal_point=False,
        refine_rig_from_world=False, refine_sensor_from_rig=False, print_summary=False)
    started = time.perf_counter()
    pycolmap.bundle_adjustment(copy, options)
    seconds = time.perf_counter() - started
    return {i: np.array(p.xyz) for i, p in copy.points3D.items()}, seconds


def triangulation_rows(camera: str, seed: int) -> list[str]:
    rows = []
    clean: dict[int, np.ndarray] = {}  # pluecker's points without outliers (same noise), for the ratio
    for with_outliers in (False, True):
        rec, truth = model(camera, seed)
        outliers, dirty_tracks = add_outliers(rec, 100, np.random.default_rng(seed)) if with_outliers else (set(), set())
        started = time.perf_counter()
        run = colmap.retriangulate(rec, outlier_threshold_px=THRESHOLD_PX if with_outliers else None)
        seconds = time.perf_counter() - started
        ours = {int(i): X for i, X, s in zip(run.point3D_ids, run.result.X, run.result.status) if s == "success"}
        ours_rejected: dict[int, set] = {}
        if run.result.inliers is not None:
            for k in np.flatnonzero(~run.result.inliers):
                key = int(run.point3D_ids[run.observation_point[k]])
                ours_rejected.setdefault(key, set()).add((int(run.observation_image[k]), int(run.observation_point2D[k])))
        ransac, ransac_rejected, ransac_seconds = pycolmap_ransac(rec)
        ba, ba_seconds = pycolmap_ba(rec, ransac)
        certified = int(np.sum(run.result.certified))
        if not with_outliers:
            clean = dict(ours)
        # The first-order cost pluecker minimises against the exact pixel cost at its answer, per point.
        gaps = [abs(c / pixel_cost(rec, int(i), X, ours_rejected.get(int(i))) - 1)
                for i, X, c, s in zip(run.point3D_ids, run.result.X, run.result.cost, run.result.status) if s == "success"]
        first_order = f"first-order cost vs pixel cost: median {np.median(gaps):.1e}, max {np.max(gaps):.1e}"
        if with_outliers:
            # The 3-D error of the tracks with an outlier against the same tracks without it (same noise),
            # and against an oracle that deletes exactly the outlier observations.
            oracle_rec = pycolmap.Reconstruction(rec)
            for image_id, idx in outliers:
                oracle_rec.delete_observation(image_id, idx)
            oracle_run = colmap.retriangulate(oracle_rec)
            oracle = {int(i): X for i, X in zip(oracle_run.point3D_ids, oracle_run.result.X)}
            rms = lambda points: np.sqrt(np.mean([np.sum((points[i] - truth[i]) ** 2) for i in dirty_tracks]))
            first_order += (f"; 3-D error on those tracks {rms(ours) / rms(clean):.3f}x the same tracks without "
                            f"outliers (an oracle deleting the outliers: {rms(oracle) / rms(clean):.3f}x)")
        for name, points, rejected, secs, note in (
            ("pluecker", ours, ours_rejected, seconds, f"{certified}/{len(run.point3D_ids)} certified; {first_order}"),
            ("pycolmap BA (points only)", ba, None, ba_seconds, "from pycolmap RANSAC; keeps outliers"),
            ("pycolmap RANSAC", ransac, ransac_rejected, ransac_seconds, "per-track Python loop"),
        ):
            ids = sorted(points)
            # The cost over each method's own inliers (all observations where it rejects none).
            cost = sum(pixel_cost(rec, i, points[i], (rejected or {}).get(i)) for i in ids)
            tracks = dirty_tracks if with_outliers else set(ids)
            err = np.sqrt(np.mean([np.sum((points[i] - truth[i]) ** 2) for i in tracks if i in points]))
            if with_outliers and rejected is not None:
                flagged = set().union(*rejected.values()) if rejected else set()
                caught = len(outliers & flagged)
                rejection = f"{caught}/{len(outliers)} rejected, {len(flagged - outliers)} inliers dropped"
            elif with_outliers:
                rejection = "none rejected"
            else:
                rejection = "-"
            rows.append(f"| {camera} | {'100 x 40 px' if with_outliers else 'none'} | {name} | {len(ids)} | "
                        f"{cost:.1f} | {err:.2e} | {1e3 * secs:.1f} | {rejection} | {note} |")
    return rows


def rotation_error_deg(Ra: np.ndarray, Rb: np.ndarray) -> float:
    return float(np.degrees(np.arccos(np.clip((np.trace(Ra @ Rb.T) - 1) / 2, -1, 1))))


def localisation_rows(camera: str, seed: int, ratios: tuple[float, ...]) -> list[str]:
    rec, _ = model(camera, seed)
    rows = []
    jobs = {"pluecker": job_pluecker_localize, "pycolmap": job_pycolmap_localize, "PoseLib": job_poselib_localize}
    for ratio in ratios:
        rng = np.random.default_rng(seed)
        stats = {name: {"rot": [], "centre": [], "fail": 0, "time": []} for name in jobs}
        for image in rec.images.values():
            matched = [p for p in image.points2D if p.has_point3D()]
            u = np.array([p.xy for p in matched])
            X = np.array([rec.points3D[p.point3D_id].xyz for p in matched])
            wrong = rng.choice(len(u), size=int(ratio * len(u)), replace=False)
            u[wrong] = rng.uniform([0, 0], [1024, 768], size=(len(wrong), 2))
            R_true, t_true = colmap.pose_from_rigid(image.cam_from_world())
            camera_model = rec.cameras[image.camera_id]
            for name, job in jobs.items():
                started = time.perf_counter()
                found = job(camera_model, u, X)
                stats[name]["time"].append(time.perf_counter() - started)
                if found is None:
                    stats[name]["fail"] += 1
                    continue
                R, t = (np.asarray(found.R), np.asarray(found.t)) if name == "PoseLib" else colmap.pose_from_rigid(found)
                stats[name]["rot"].append(rotation_error_deg(R, R_true))
                stats[name]["centre"].append(float(np.linalg.norm(-R.T @ t + R_true.T @ t_true)))
        for name, s in stats.items():
            rows.append(f"| {camera} | {int(100 * ratio)} % | {name} | {np.median(s['rot']):.4f} | "
                        f"{np.median(s['centre']):.2e} | {s['fail']}/{len(rec.images)} | {1e3 * np.median(s['time']):.2f} |")
    return rows


# --------------------------------------------------------------------------------------------------
# Localisation with lens cameras through ``pluecker localize --colmap`` (the command line, end to end).

#: Synthetic lens cameras of 1024 x 768 px for the localisation section: a strong radial lens (f = 5000 px,
#: k = -8: the image corner, 0.128 focal lengths from the centre, is 0.162 undistorted, 21 % barrel, near
#: the fold at 0.136 where the distortion stops being invertible), and the wide OPENCV and the fisheye of
#: :data:`CAMERAS` (65 degrees off axis at the corners).
LOCALIZE_CAMERAS = {
    "SIMPLE_RADIAL strong": ("SIMPLE_RADIAL", [5000.0, 512.0, 384.0, -8.0]),
    "OPENCV wide": ("OPENCV", CAMERAS["OPENCV wide"][1]),
    "OPENCV_FISHEYE": ("OPENCV_FISHEYE", CAMERAS["OPENCV_FISHEYE"][1]),
}
LOCALIZE_QUERIES, LOCALIZE_MATCHES = 30, 200  # synthetic queries per camera, matches per query


def _rotation(a: np.ndarray) -> np.ndarray:
    theta = np.linalg.norm(a)
    k = np.array([[0, -a[2], a[1]], [a[2], 0, -a[0]], [-a[1], a[0], 0]]) / theta
    return np.eye(3) + np.sin(theta) * k + (1 - np.cos(theta)) * k @ k


def localize_synthetic(name: str, seed: int) -> tuple[Any, list[dict[str, Any]]]:
    """A COLMAP model holding one camera of :data:`LOCALIZE_CAMERAS` and the 3-D points of
    :data:`LOCALIZE_QUERIES` queries, each with :data:`LOCALIZE_MATCHES` keypoints spread over the whole
    image (where the distortion is strongest), depths 4-8, 1 px noise, made with pycolmap's projection
    (normalised points drawn in the camera frame and projected forward: pycolmap's iterative
    undistortion does not converge near the corners of the strong radial lens). Returns the model
    and the queries (``query``, ``camera_id``, ``xy``, ``point3D_ids``, true ``R``, ``t``)."""
    model_name, params = LOCALIZE_CAMERAS[name]
    rng = np.random.default_rng(seed)
    rec = pycolmap.Reconstruction()
    camera = pycolmap.Camera(model=model_name, width=1024, height=768, params=params, camera_id=1)
    rec.add_camera(camera)
    # The normalised half-extent that covers the image (the fisheye: to 80 degrees off axis).
    extent = {"SIMPLE_RADIAL": 0.2, "OPENCV": 2.0, "OPENCV_FISHEYE": 5.7}[model_name]
    queries = []
    for q in range(LOCALIZE_QUERIES):
        R, t = _rotation(rng.uniform(-0.5, 0.5, 3)), rng.uniform(-1, 1, 3)
        xy = np.zeros((0, 2))
        x_cam = np.zeros((0, 3))
        while len(xy) < LOCALIZE_MATCHES:
            n = rng.uniform(-extent, extent, (4 * LOCALIZE_MATCHES, 2))
            n = n[np.hypot(*n.T) < extent]
            u = camera.img_from_cam(np.c_[n, np.ones(len(n))])
            inside = np.all(np.isfinite(u), axis=1) & (u[:, 0] >= 0) & (u[:, 0] < 1024) & (u[:, 1] >= 0) & (u[:, 1] < 768)
            # Keep only pixels the lens maps one to one (the fisheye polynomial folds past its range).
            lens, back = pluecker.LensCamera(model_name, params), np.full(len(n), False)
            for k in np.flatnonzero(inside):
                try:
                    back[k] = np.linalg.norm(lens.unproject(u[k:k + 1])[0] - n[k]) < 1e-9 * (1 + np.hypot(*n[k]))
                except pluecker.PlueckerError:
                    pass
            depth = rng.uniform(4, 8, back.sum())
            xy, x_cam = np.r_[xy, u[back]], np.r_[x_cam, np.c_[n[back], np.ones(back.sum())] * depth[:, None]]
        xy, x_cam = xy[:LOCALIZE_MATCHES] + rng.normal(0, 1, (LOCALIZE_MATCHES, 2)), x_cam[:LOCALIZE_MATCHES]
        X = (x_cam - t) @ R
        ids = np.array([rec.add_point3D(x, pycolmap.Track()) for x in X], dtype=np.int64)
        queries.append({"query": q, "camera_id": 1, "xy": xy, "point3D_ids": ids, "R": R, "t": t})
    return rec, queries


def localize_public(rec: Any) -> list[dict[str, Any]]:
    """The registered images of a real model as queries: their keypoints with a point3D_id; the truth is
    the model's own pose (COLMAP's bundle adjustment with every observation)."""
    queries = []
    for image_id in sorted(rec.images):
        image = rec.images[image_id]
        keypoints = [p for p in image.points2D if p.has_point3D()]
        if image.has_pose and len(keypoints) >= 6:
            R, t = colmap.pose_from_rigid(image.cam_from_world())
            queries.append({"query": image_id, "camera_id": image.camera_id, "xy": np.array([p.xy for p in keypoints]),
                            "point3D_ids": np.array([p.point3D_id for p in keypoints], dtype=np.int64), "R": R, "t": t})
    return queries


def _pose_errors(R: np.ndarray, t: np.ndarray, query: dict[str, Any]) -> tuple[float, float]:
    return rotation_error_deg(R, query["R"]), float(np.linalg.norm(-R.T @ t + query["R"].T @ query["t"]))


def localize_rows(name: str, rec: Any, queries: list[dict[str, Any]], ratio: float, seed: int,
                  folder: Path) -> list[str]:
    """One table row per method for the queries of one model with ``ratio`` of every query's keypoints
    replaced by random pixels of its image (their point3D_id kept: a mismatch)."""
    import pyarrow as pa
    import pyarrow.parquet as pq

    rng = np.random.default_rng(seed)
    queries = [dict(q) for q in queries]
    for q in queries:
        camera = rec.cameras[q["camera_id"]]
        wrong = rng.choice(len(q["xy"]), size=int(ratio * len(q["xy"])), replace=False)
        q["xy"] = q["xy"].copy()
        q["xy"][wrong] = rng.uniform([0, 0], [camera.width, camera.height], size=(len(wrong), 2))
    # The command line, end to end: a fresh process reads the model and the tables and writes the poses.
    folder.mkdir(parents=True, exist_ok=True)
    rec.write(str(folder))
    pq.write_table(pa.table({"query": [q["query"] for q in queries], "camera_id": [q["camera_id"] for q in queries]}),
                   folder / "queries.parquet")
    pq.write_table(pa.table({
        "query": np.concatenate([np.full(len(q["xy"]), q["query"]) for q in queries]),
        "x": np.concatenate([q["xy"][:, 0] for q in queries]), "y": np.concatenate([q["xy"][:, 1] for q in queries]),
        "point3D_id": np.concatenate([q["point3D_ids"] for q in queries])}), folder / "matches.parquet")
    executable = Path(sys.executable).with_name("pluecker")
    command = [str(executable)] if executable.exists() else [sys.executable, "-m", "pluecker.cli"]
    started = time.perf_counter()
    run = subprocess.run([*command, "localize", str(folder / "queries.parquet"), str(folder / "matches.parquet"),
                          "--colmap", str(folder), "--out", str(folder / "out"), "--point-threshold", str(THRESHOLD_PX)],
                         capture_output=True, text=True, check=True)
    wall = time.perf_counter() - started
    from pluecker import distributed

    poses = distributed.read_poses(folder / "out")
    found = {q: (np.asarray(R).reshape(3, 3), np.asarray(t), s) for q, R, t, s in zip(
        poses.column("query").to_pylist(), poses.column("R").to_pylist(), poses.column("t").to_pylist(),
        poses.column("status").to_pylist())}
    stats = {m: {"rot": [], "centre": [], "fail": 0, "time": []} for m in ("pluecker", "pycolmap", "PoseLib")}
    points = {i: np.array(p.xyz) for i, p in rec.points3D.items()}
    for q in queries:
        camera = rec.cameras[q["camera_id"]]
        X = np.array([points[int(i)] for i in q["point3D_ids"]])
        R, t, status = found[q["query"]]
        if status == "success":
            rot, centre = _pose_errors(R, t, q)
            stats["pluecker"]["rot"].append(rot)
            stats["pluecker"]["centre"].append(centre)
        else:
            stats["pluecker"]["fail"] += 1
        # The per-image solve, in this process, as each library is called on one image.
        lens = colmap.lens_camera(camera)
        ransac = pluecker.RansacOptions(point_threshold=THRESHOLD_PX, seed=seed + q["query"])
        started = time.perf_counter()
        colmap.localize(lens, q["xy"], X, ransac=ransac)
        stats["pluecker"]["time"].append(time.perf_counter() - started)
        for method, job in (("pycolmap", job_pycolmap_localize), ("PoseLib", job_poselib_localize)):
            started = time.perf_counter()
            try:
                pose = job(camera, q["xy"], X)
            except Exception:  # noqa: BLE001 - a library's own failure is a failure of that image
                pose = None
            stats[method]["time"].append(time.perf_counter() - started)
            if pose is None:
                stats[method]["fail"] += 1
                continue
            R, t = (np.asarray(pose.R), np.asarray(pose.t)) if method == "PoseLib" else colmap.pose_from_rigid(pose)
            rot, centre = _pose_errors(R, t, q)
            stats[method]["rot"].append(rot)
            stats[method]["centre"].append(centre)
    job = float(re.search(r"in (\d+\.\d+) s", run.stdout).group(1))
    rows = []
    for method, s in stats.items():
        note = (f"CLI end to end {wall:.2f} s for {len(queries)} images ({1e3 * wall / len(queries):.1f} ms/image; "
                f"job {job:.1f} s)" if method == "pluecker" else "")
        median = lambda v, f: f"{np.median(v):{f}}" if v else "-"  # noqa: E731
        rows.append(f"| {name} | {int(100 * ratio)} % | {method} | {median(s['rot'], '.4f')} | "
                    f"{median(s['centre'], '.2e')} | {s['fail']}/{len(queries)} | {1e3 * np.median(s['time']):.2f} | "
                    f"{note} |")
    return rows


def localize_section(seed: int, public: Path | None, ratios: tuple[float, ...] = (0.0, 0.5),
                     cameras: list[str] | None = None) -> list[str]:
    """Localisation with lens cameras: ``pluecker localize --colmap`` (accuracy from the command line's
    poses, its end-to-end time, and the per-image solve time in this process) against
    ``pycolmap.estimate_and_refine_absolute_pose`` and ``poselib.estimate_absolute_pose`` (4 px for
    all), on the synthetic lenses of :data:`LOCALIZE_CAMERAS` and on the public model at ``public``.
    Returns the Markdown lines."""
    import tempfile

    lines = [f"## Localisation with lens cameras (threshold {THRESHOLD_PX:g} px; {LOCALIZE_QUERIES} synthetic queries "
             f"of {LOCALIZE_MATCHES} keypoints with 1 px noise per camera; outliers: keypoints replaced by random "
             "pixels; truth: the synthetic pose, or the public model's own)\n",
             "| model | outliers | method | median rotation error (deg) | median centre error | failures | "
             "median time per image (ms) | note |", "| --- | --- | --- | --- | --- | --- | --- | --- |"]
    models = [(name, *localize_synthetic(name, seed)) for name in (cameras or list(LOCALIZE_CAMERAS))]
    if public is not None:
        rec = pycolmap.Reconstruction(str(public))
        kinds = sorted({c.model.name for c in rec.cameras.values()})
        models.append((f"public model ({len(rec.images)} images, {'/'.join(kinds)})", rec,
                       localize_public(rec)))
    with tempfile.TemporaryDirectory() as scratch:
        for k, (name, rec, queries) in enumerate(models):
            for ratio in ratios:
                lines += localize_rows(name, rec, queries, ratio, seed, Path(scratch) / f"{k}-{ratio}")
                print(lines[-3], lines[-2], lines[-1], sep="\n", file=sys.stderr, flush=True)
    return lines


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="one camera, no sparse batch")
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--localize-model", type=Path, metavar="DIR",
                        help="a real COLMAP model for the localisation with lens cameras (e.g. mamechun/gs_data's "
                        "distorted/sparse/0)")
    parser.add_argument("--localize-only", action="store_true", help="only the localisation with lens cameras")
    args = parser.parse_args()
    if args.localize_only:
        print(f"pluecker {pluecker.__version__}, pycolmap {pycolmap.__version__}, PoseLib {poselib.__version__}\n")
        print("\n".join(localize_section(args.seed, args.localize_model)))
        return
    cameras = list(CAMERAS)[:1] if args.quick else list(CAMERAS)
    print(f"pluecker {pluecker.__version__}, pycolmap {pycolmap.__version__}, PoseLib {poselib.__version__}\n")
    pycolmap.logging.minloglevel = 2  # no glog lines from the bundle adjuster
    colmap.retriangulate(model(cameras[0], 99, 20)[0])  # warm-up: one-off imports are not timed
    print("## Re-triangulation (cameras fixed, 1 px noise; cost: Σ squared pixel reprojection error over each "
          "method's inliers; 3-D error: RMS over all tracks, or over the 100 tracks with an outlier)\n")
    print("| camera | outliers | method | points | cost (px²) | RMS 3-D error | time (ms) | outlier rejection | note |")
    print("| --- | --- | --- | --- | --- | --- | --- | --- | --- |")
    for camera in cameras:
        print("\n".join(triangulation_rows(camera, args.seed)), flush=True)
    print("\n## Localisation (12 images per camera; threshold 4 px)\n")
    print("| camera | outliers | method | median rotation error (deg) | median centre error | failures | median time (ms) |")
    print("| --- | --- | --- | --- | --- | --- | --- |")
    for camera in cameras:
        print("\n".join(localisation_rows(camera, args.seed, (0.0, 0.3, 0.6))), flush=True)
    print("\n" + "\n".join(localize_section(args.seed, args.localize_model,
                                             cameras=list(LOCALIZE_CAMERAS)[:1] if args.quick else None)))
    print("\n## Glue code beyond loading the model (statements a user writes)\n")
    print("| job | pluecker | pycolmap | PoseLib |")
    print("| --- | --- | --- | --- |")
    print(f"| re-triangulate and write a model | {glue_lines(job_pluecker_triangulate)} (command line: 0, "
          f"`pluecker triangulate --colmap DIR --out DIR`) | {glue_lines(job_pycolmap_triangulate_and_ba)} "
          "(RANSAC per track, then BA with cameras fixed; no covariances, no certificates) | - |")
    print(f"| localise an image | {glue_lines(job_pluecker_localize)} | {glue_lines(job_pycolmap_localize)} | "
          f"{glue_lines(job_poselib_localize)} |")
    if not args.quick:
        print("\n## Sparse batch (bench/sparse_tracks.py)\n")
        script = Path(__file__).with_name("sparse_tracks.py")
        out = subprocess.run([sys.executable, str(script)], capture_output=True, text=True, check=True).stdout
        print("```\n" + out.strip() + "\n```")


if __name__ == "__main__":
    main()
