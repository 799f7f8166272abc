"""pluecker against pycolmap and PoseLib on COLMAP models.

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
5. **Re-triangulation against a tight points-only BA** (``retriangulation_section``): on a real model
   (``--model PATH``) and on four seeded synthetic ones (PINHOLE, the cost-convention control; SIMPLE_RADIAL
   f = 5000 px, k = -14, every pixel inside the fold; OPENCV_FISHEYE out to 80 degrees off axis; 20 % of
   the tracks observing one image twice), 1 px noise, ``sigma_px = 1``. Every cost is recomputed by this
   script with pycolmap's ``Camera.img_from_cam`` in raw pixels (Σ r² / σ², pluecker's eq. 19; never
   pluecker's residuals), and each point's optimum is its cost at pycolmap's points-only BA with Ceres
   tolerances 1e-16 (cameras fixed, the points are independent). Reported: tracks solved (of those seen
   from two or more distinct images), certified, solved points above the optimum by more than 1e-6
   relative (or below it), certified ``lower_bound`` / ``raw_lower_bound`` above the optimum, and the time
   of ``colmap.retriangulate`` (gather / solve / ``colmap.write``) against the points-only BA at pycolmap's
   default tolerances and ``estimate_triangulation``. The real model of the recorded runs (docs/benchmarks.md): folder
   ``distorted/sparse/0`` of the GitHub repository ``mamechun/gs_data`` (128 SIMPLE_RADIAL cameras, 5751
   points, 26268 observations; not part of this repository).

6. **Localisation with lens cameras through the command line** (:func:`localize_section`):
   ``pluecker localize --colmap`` on a strong radial lens, a wide OPENCV and a fisheye to 80 degrees, and on
   a real model (``--localize-model DIR``), with 0 and 50 % outliers, against pycolmap and PoseLib:
   accuracy of the command line's poses, its end-to-end time, and each library's per-image solve time.

Run: ``.venv/bin/python bench/compare_colmap.py [--quick] [--model PATH] [--localize-model DIR]``; prints
Markdown tables. ``--retriangulation --model PATH`` runs section 5 alone (about 40 s on 2 cores),
``--localize-only`` section 6 alone.
"""

from __future__ import annotations

import argparse
import inspect
import os
import re
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any, Callable, NamedTuple

import numpy as np
import poselib
import pycolmap

import pluecker
from pluecker import colmap
from pluecker.scenes import colmap_reconstruction, inside_fold, within_degrees

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
        ours = {int(i): X for i, X, s in zip(run.point3D_ids, run.result.point, run.result.status) if s == "success"}
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
                for i, X, c, s in zip(run.point3D_ids, run.result.point, run.result.cost, run.result.status) if s == "success"]
        first_order = f"first-order cost vs pixel cost: median {np.median(gaps):.1e}, max {np.max(gaps):.1e}"
        if with_outliers:
            # The 3-D error of the tracks with an outlier against the same tracks without it (same noise),
            # and against an oracle that deletes exactly the outlier observations.
            oracle_rec = pycolmap.Reconstruction(rec)
            for image_id, idx in outliers:
                oracle_rec.delete_observation(image_id, idx)
            oracle_run = colmap.retriangulate(oracle_rec)
            oracle = {int(i): X for i, X in zip(oracle_run.point3D_ids, oracle_run.result.point)}
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
            lens, back = pluecker.Camera(model_name, params), np.full(len(n), False)
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
    # The command line, end to end: a fresh process reads the model and the tables and writes the poses
    # (beside the model: the command refuses an output inside an input).
    (folder / "model").mkdir(parents=True, exist_ok=True)
    rec.write(str(folder / "model"))
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
                          "--colmap", str(folder / "model"), "--out", str(folder / "out"), "--point-threshold", str(THRESHOLD_PX)],
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
        lens = pluecker.Camera(camera)
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


# --------------------------------------------------------------------------------------------------
# Re-triangulation against a tight points-only bundle adjustment (soundness of `solved` and `certified`).

#: σ of the observations (the synthetic noise is 1 px) and of the whitened cost Σ ‖r‖² / σ² (eq. 19).
SIGMA_PX = 1.0
#: A point whose exact cost is above the tight BA's by more than this (relative) is not at the optimum.
ABOVE_OPTIMUM_REL = 1e-6
#: A certified lower bound above the tight BA's cost by more than this (relative) is a false bound: the
#: tight BA converged to Ceres tolerances of 1e-16, and a per-point cost of ~10 terms rounds at ~1e-15.
BOUND_ABOVE_REL = 1e-9
#: The strong radial camera: SIMPLE_RADIAL, f = 5000 px, k = -14. The distortion r_d = r (1 + k r²) folds
#: at r_fold² = -1 / (3k) (normalised), where r_d = (2/3) r_fold = 0.1029, i.e. 514.5 px from the principal
#: point; an 800 x 600 image reaches 500 px at its corners, so every pixel has exactly one preimage inside
#: the fold (checked in `strong_radial_model`).
STRONG_RADIAL = (5000.0, -14.0, 800, 600)
#: The fisheye camera: OPENCV_FISHEYE, f = 300 px, mild coefficients; the image is sized so that its
#: corners are 80 degrees off axis (`fisheye_model`).
FISHEYE = ([300.0, 300.0, 0.0, 0.0, 0.05, -0.01, 0.002, -3e-4], 80.0)
#: A small-distortion OPENCV camera like a real two-camera model's: 300 x 600 px, fx = 385, fy = 430,
#: k1 = -0.008, k2 = 0.0015, p1 = 0.005, p2 = -0.003 (`opencv_model`).
OPENCV_SMALL = ([385.0, 430.0, 150.0, 300.0, -0.008, 0.0015, 0.005, -0.003], 300, 600)
#: Repeated-image tracks: this fraction of the tracks gets a second keypoint in one of its images.
REPEATED_FRACTION = 0.2


def _synthetic(model_id: Any, params: list[float], width: int, height: int, spread: float, seed: int,
               points: int, visible: Callable[[np.ndarray], np.ndarray] | None = None,
               repeated_fraction: float = 0.0) -> Any:
    """:func:`pluecker.scenes.colmap_reconstruction` (2 rigs x 6 frames, 1 px noise) with one camera model,
    the structure enlarged ``spread`` times about its centre."""
    return colmap_reconstruction(model_id.name, params, width, height, spread=spread, seed=seed, points=points,
                                 visible=visible, repeated_fraction=repeated_fraction)


def pinhole_model(seed: int, points: int = 12000) -> Any:
    """PINHOLE, f = 1000 px, 1024 x 768: no distortion, so pluecker's cost is the pixel cost exactly (the
    cost-convention check: both must agree)."""
    return _synthetic(pycolmap.CameraModelId.PINHOLE, [1000.0, 1000.0, 512.0, 384.0], 1024, 768, 1.5, seed, points)


def opencv_model(seed: int, points: int = 12000) -> Any:
    """OPENCV with small radial and tangential terms (:data:`OPENCV_SMALL`); every image sees every point (tracks
    of 12 observations)."""
    params, width, height = OPENCV_SMALL
    return _synthetic(pycolmap.CameraModelId.OPENCV, params, width, height, 1.0, seed, points)


def strong_radial_model(seed: int, points: int = 12000) -> Any:
    """SIMPLE_RADIAL (:data:`STRONG_RADIAL`), every pixel inside the distortion's fold; a point is seen only
    when its normalised radius is inside the fold (beyond it the model folds back into the image)."""
    f, k, width, height = STRONG_RADIAL
    r_fold = np.sqrt(-1.0 / (3.0 * k))
    corner = np.hypot(width / 2, height / 2) / f
    assert corner < r_fold * (1 + k * r_fold**2), "the image corner must map inside the fold"
    return _synthetic(pycolmap.CameraModelId.SIMPLE_RADIAL, [f, width / 2, height / 2, k], width, height,
                      0.4, seed, points, inside_fold(k))


def fisheye_angle_px(params: list[float], degrees: float) -> float:
    """Distance from the principal point, pixels, of a ray ``degrees`` off axis through OPENCV_FISHEYE."""
    theta = np.radians(degrees)
    k1, k2, k3, k4 = params[4:8]
    return params[0] * theta * (1 + k1 * theta**2 + k2 * theta**4 + k3 * theta**6 + k4 * theta**8)


def fisheye_model(seed: int, points: int = 12000) -> Any:
    """OPENCV_FISHEYE (:data:`FISHEYE`), the image's half-diagonal at 80 degrees off axis (4:3); rays
    beyond 80 degrees are not seen."""
    params, degrees = FISHEYE
    half_diagonal = fisheye_angle_px(params, degrees)
    width, height = int(2 * 0.8 * half_diagonal), int(2 * 0.6 * half_diagonal)
    params = [params[0], params[1], width / 2, height / 2, *params[4:]]
    return _synthetic(pycolmap.CameraModelId.OPENCV_FISHEYE, params, width, height, 6.0, seed, points,
                      within_degrees(degrees))


def repeated_model(seed: int, points: int = 12000) -> Any:
    """SIMPLE_RADIAL (f = 1280 px, k = 0.05, 1024 x 768) where :data:`REPEATED_FRACTION` of the tracks
    observe one of their images twice: a second keypoint at the noise-free pixel plus its own 1 px noise,
    as COLMAP allows after merging tracks."""
    return _synthetic(pycolmap.CameraModelId.SIMPLE_RADIAL, [1280.0, 512.0, 384.0, 0.05], 1024, 768, 1.0, seed,
                      points, repeated_fraction=REPEATED_FRACTION)


class Observations(NamedTuple):
    """A model's observations, read with pycolmap only (never through pluecker)."""

    ids: np.ndarray          # (n,) sorted point3D ids
    images: np.ndarray       # (n,) distinct images per point
    row: np.ndarray          # (m,) row of ids per observation
    xy: np.ndarray           # (m, 2) raw pixels
    per_image: list          # (camera, (3, 4) cam_from_world, slice of the observations)


def observations(rec: Any) -> Observations:
    ids = np.array(sorted(rec.points3D), dtype=np.int64)
    rows, xys, per_image, start = [], [], [], 0
    for image_id in sorted(rec.images):
        image = rec.images[image_id]
        seen = [p for p in image.points2D if p.has_point3D()]
        if not seen or not image.has_pose:
            continue
        rows.append(np.searchsorted(ids, [p.point3D_id for p in seen]))
        xys.append(np.array([p.xy for p in seen], dtype=float))
        per_image.append((rec.cameras[image.camera_id], np.array(image.cam_from_world().matrix()),
                          slice(start, start + len(seen))))
        start += len(seen)
    row = np.concatenate(rows)
    images = np.array([len({e.image_id for e in rec.points3D[int(i)].track.elements}) for i in ids])
    return Observations(ids, images, row, np.concatenate(xys), per_image)


def exact_costs(obs: Observations, X: np.ndarray, sigma_px: float = SIGMA_PX) -> np.ndarray:
    """Per point (rows of ``obs.ids``): Σ ‖img_from_cam(R X + t) − xy‖² / σ² over all its observations,
    raw pixels through pycolmap's own projection; ``inf`` where an observation does not project (behind
    the camera), NaN where ``X`` is NaN. Σ r², not Ceres' ½ Σ r²: pluecker's eq. 19."""
    squared = np.empty(len(obs.row))
    for camera, T, part in obs.per_image:
        Xi = X[obs.row[part]]
        x_cam = Xi @ T[:, :3].T + T[:, 3]
        u = camera.img_from_cam(x_cam)
        r2 = np.sum((u - obs.xy[part]) ** 2, axis=1) / sigma_px**2
        squared[part] = np.where(np.isnan(r2) & ~np.isnan(Xi).any(axis=1), np.inf, r2)
    return np.bincount(obs.row, weights=squared, minlength=len(obs.ids)) if len(obs.row) else np.zeros(len(obs.ids))


def _points_only_ba(rec: Any, tight: bool) -> tuple[Any, float]:
    """pycolmap's bundle adjustment of the 3-D points only (intrinsics, rigs and poses constant), started
    from the model's points, on a copy: (the copy, seconds). ``tight``: Ceres function, gradient and
    parameter tolerances 1e-16 and 10000 iterations; else pycolmap's defaults."""
    copy = pycolmap.Reconstruction(rec)
    options = pycolmap.BundleAdjustmentOptions(
        refine_focal_length=False, refine_extra_params=False, refine_principal_point=False,
        refine_rig_from_world=False, refine_sensor_from_rig=False, print_summary=False)
    if tight:
        solver = options.ceres.solver_options
        solver.function_tolerance = solver.gradient_tolerance = solver.parameter_tolerance = 1e-16
        solver.max_num_iterations = 10000
    started = time.perf_counter()
    pycolmap.bundle_adjustment(copy, options)
    return copy, time.perf_counter() - started


def _estimate_triangulation(rec: Any, obs: Observations) -> tuple[np.ndarray, float]:
    """``pycolmap.estimate_triangulation`` (reprojection error, 4 px, seed 0) of every track seen from two
    or more images: (points (n, 3), NaN where it fails; seconds)."""
    options = pycolmap.EstimateTriangulationOptions()
    options.residual_type = pycolmap.TriangulationResidualType.REPROJECTION_ERROR
    options.ransac.max_error = THRESHOLD_PX
    options.ransac.random_seed = 0
    X = np.full((len(obs.ids), 3), np.nan)
    started = time.perf_counter()
    for row, point_id in enumerate(obs.ids):
        if obs.images[row] < 2:
            continue
        elements = rec.points3D[int(point_id)].track.elements
        images = [rec.images[e.image_id] for e in elements]
        xy = np.array([im.points2D[e.point2D_idx].xy for im, e in zip(images, elements)])
        found = pycolmap.estimate_triangulation(
            xy, [im.cam_from_world() for im in images], [rec.cameras[im.camera_id] for im in images], options)
        if found is not None:
            X[row] = found["xyz"]
    return X, time.perf_counter() - started


class _CoreTimer:
    """Times the calls into ``pluecker._core``'s ``*triangulate*`` functions made inside ``with`` (the
    solve of :func:`pluecker.colmap.retriangulate`; the rest of its time is gathering the observations).
    A stopwatch around the public functions, nothing else changed; ``calls`` is 0 if none was seen."""

    def __init__(self) -> None:
        self.seconds, self.calls, self._saved = 0.0, 0, {}

    def __enter__(self) -> "_CoreTimer":
        from pluecker import _core

        def timed(function: Callable[..., Any]) -> Callable[..., Any]:
            def call(*args: Any, **kwargs: Any) -> Any:
                started = time.perf_counter()
                try:
                    return function(*args, **kwargs)
                finally:
                    self.seconds += time.perf_counter() - started
                    self.calls += 1
            return call

        self._saved = {name: getattr(_core, name) for name in dir(_core)
                       if "triangulate" in name and callable(getattr(_core, name))}
        for name, function in self._saved.items():
            setattr(_core, name, timed(function))
        return self

    def __exit__(self, *exc: Any) -> None:
        from pluecker import _core

        for name, function in self._saved.items():
            setattr(_core, name, function)


def _rel(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """(a − b) / b, with b floored at 1e-300 (a cost of exactly 0 is a relative excess of a/1e-300)."""
    return (a - b) / np.maximum(b, 1e-300)


def retriangulation_row(name: str, rec: Any, repeats: int = 5) -> tuple[str, str, list[str]]:
    """One model: (soundness row, timing row, notes). Everything pluecker returns is judged by costs this
    script recomputes (:func:`exact_costs`) at the tight BA's points."""
    obs = observations(rec)
    eligible = obs.images >= 2
    # pluecker: the run whose results are judged, then best-of timing with the stage breakdown,
    # alternating with the default BA so that both see the same load on a shared machine.
    run = colmap.retriangulate(rec, sigma_px=SIGMA_PX)
    total, solve, default_seconds = np.inf, np.nan, np.inf
    for _ in range(repeats):
        with _CoreTimer() as timer:
            started = time.perf_counter()
            colmap.retriangulate(rec, sigma_px=SIGMA_PX)
            seconds = time.perf_counter() - started
        if seconds < total:
            total, solve = seconds, (timer.seconds if timer.calls else np.nan)
        default, seconds = _points_only_ba(rec, False)
        default_seconds = min(default_seconds, seconds)
    with tempfile.TemporaryDirectory() as folder:
        copy = pycolmap.Reconstruction(rec)  # write() updates the model it is given: a copy, not timed
        started = time.perf_counter()
        colmap.write(copy, run, Path(folder) / "model")
        write_seconds = time.perf_counter() - started
    # pluecker's rows by point3D_id, in obs.ids order.
    rows = np.searchsorted(run.point3D_ids, obs.ids)
    assert np.array_equal(np.asarray(run.point3D_ids)[rows], obs.ids), "retriangulate lost a point3D_id"
    result = run.result
    X = np.asarray(result.point)[rows]
    status = np.asarray(result.status)[rows]
    certified = np.asarray(result.certified, dtype=bool)[rows]
    lower = np.asarray(result.lower_bound)[rows]
    raw = np.asarray(result.raw_lower_bound)[rows]
    their_cost = np.asarray(result.cost)[rows]
    solved = (status == "success") & eligible
    # The references: tight BA (the per-point optimum), default BA, estimate_triangulation.
    tight, tight_seconds = _points_only_ba(rec, True)
    X_tight = np.array([tight.points3D[int(i)].xyz for i in obs.ids])
    X_default = np.array([default.points3D[int(i)].xyz for i in obs.ids])
    X_ransac, ransac_seconds = _estimate_triangulation(rec, obs)
    optimum = exact_costs(obs, X_tight)
    ours = exact_costs(obs, X)
    excess = _rel(ours, optimum)
    above = solved & (excess > ABOVE_OPTIMUM_REL)
    below = solved & (excess < -ABOVE_OPTIMUM_REL)
    judged = certified & solved
    lb_excess, raw_excess = _rel(lower, optimum), _rel(raw, optimum)
    lb_above = judged & (lb_excess > BOUND_ABOVE_REL)
    raw_above = judged & (raw_excess > BOUND_ABOVE_REL)
    # pluecker's own cost against the exact cost at its own point (equal on pinhole cameras).
    own = np.abs(_rel(their_cost, ours))[solved]
    default_above = eligible & (_rel(exact_costs(obs, X_default), optimum) > ABOVE_OPTIMUM_REL)
    ransac_ok = eligible & np.all(np.isfinite(X_ransac), axis=1)
    ransac_above = ransac_ok & (_rel(exact_costs(obs, X_ransac), optimum) > ABOVE_OPTIMUM_REL)
    fmt_max = lambda mask, values: f" (max {np.max(values[mask]):.1e})" if mask.any() else ""
    n, s = int(eligible.sum()), int(solved.sum())
    soundness = (
        f"| {name} | {len(obs.ids)} / {len(obs.row)} | {n} | {s} ({100 * s / max(n, 1):.2f} %) | "
        f"{int(judged.sum())} ({100 * judged.sum() / max(s, 1):.2f} %) | {int(above.sum())}{fmt_max(above, excess)} | "
        f"{int(below.sum())}{fmt_max(below, -excess)} | {int(lb_above.sum())}{fmt_max(lb_above, lb_excess)} | "
        f"{int(raw_above.sum())}{fmt_max(raw_above, raw_excess)} | {np.max(own) if len(own) else np.nan:.1e} | "
        f"{int(default_above.sum())} | {int(ransac_ok.sum())} / {int(ransac_above.sum())} |")
    stage = lambda v: "n/a" if not np.isfinite(v) else f"{1e3 * v:.0f}"
    timing = (f"| {name} | {1e3 * total:.0f} | {stage(total - solve)} | {stage(solve)} | {1e3 * write_seconds:.0f} | "
              f"{1e3 * default_seconds:.0f} | {total / default_seconds:.2f} | {1e3 * tight_seconds:.0f} | "
              f"{1e3 * ransac_seconds:.0f} |")
    notes = []
    unsolved = eligible & ~solved
    if unsolved.any():
        counts = {k: int(v) for k, v in zip(*np.unique(status[unsolved], return_counts=True))}
        notes.append(f"{name}: unsolved tracks (≥ 2 images) by status: {counts}")
    if (~eligible).any():
        notes.append(f"{name}: {int((~eligible).sum())} tracks see fewer than two distinct images (not judged); "
                     f"their statuses: {dict(zip(*np.unique(status[~eligible], return_counts=True)))}")
    repeated = eligible & (np.bincount(obs.row, minlength=len(obs.ids)) > obs.images)
    if repeated.any():
        notes.append(f"{name}: {int(repeated.sum())} tracks (≥ 2 images) observe one image twice or more; "
                     f"pluecker solves {int((repeated & solved).sum())} of them")
    if len(run.observation_point) != len(obs.row):
        notes.append(f"{name}: retriangulate used {len(run.observation_point)} of the model's {len(obs.row)} "
                     "observations")
    tight_not_lowest = eligible & (_rel(optimum, exact_costs(obs, X_default)) > BOUND_ABOVE_REL)
    if tight_not_lowest.any():
        notes.append(f"{name}: the tight BA is above the default BA at {int(tight_not_lowest.sum())} points "
                     "(the reference is not converged there)")
    if run.skipped:
        notes.append(f"{name}: retriangulate skipped {len(run.skipped)} item(s), e.g. {run.skipped[0]}")
    if lb_above.any():
        worst = int(np.argmax(np.where(lb_above, lb_excess, -np.inf)))
        notes.append(f"{name}: worst certified bound: point3D_id {int(obs.ids[worst])}, lower_bound "
                     f"{lower[worst]:.10g} > tight BA optimum {optimum[worst]:.10g} (pluecker's exact cost "
                     f"{ours[worst]:.10g}, its own cost {their_cost[worst]:.10g})")
    return soundness, timing, notes


def convention_check(seed: int) -> str:
    """On a pinhole model pluecker's cost is the pixel cost: Σ r² / σ² at pluecker's own point, for σ = 1
    and σ = 0.5 (a ½ Σ r² convention or a σ instead of σ² would show here as a factor 2 or 2)."""
    rec = pinhole_model(seed, 200)
    obs = observations(rec)
    parts = []
    for sigma in (1.0, 0.5):
        run = colmap.retriangulate(rec, sigma_px=sigma)
        rows = np.searchsorted(run.point3D_ids, obs.ids)
        ok = np.asarray(run.result.status)[rows] == "success"
        X = np.asarray(run.result.point)[rows]
        mine = exact_costs(obs, X, sigma)
        parts.append(f"σ = {sigma}: max |cost − Σ r²/σ²| / Σ r²/σ² = "
                     f"{np.max(np.abs(_rel(np.asarray(run.result.cost)[rows][ok], mine[ok]))):.1e} over {int(ok.sum())} points")
    return "cost convention (PINHOLE, pluecker's cost against this script's Σ r²/σ² at pluecker's point): " + "; ".join(parts)


def retriangulation_section(seed: int, model_path: str | None) -> None:
    models: list[tuple[str, Callable[[], Any]]] = []
    if model_path:
        models.append((f"public ({Path(model_path).name})", lambda: pycolmap.Reconstruction(model_path)))
    f, k, width, height = STRONG_RADIAL
    models += [
        ("PINHOLE f=1000", lambda: pinhole_model(seed)),
        ("OPENCV small distortion", lambda: opencv_model(seed)),
        (f"SIMPLE_RADIAL f={f:.0f} k={k:.0f}", lambda: strong_radial_model(seed)),
        (f"OPENCV_FISHEYE to {FISHEYE[1]:.0f}°", lambda: fisheye_model(seed)),
        (f"repeated images ({100 * REPEATED_FRACTION:.0f} % of tracks)", lambda: repeated_model(seed)),
    ]
    print(f"## Re-triangulation against a tight points-only BA (sigma_px = {SIGMA_PX}, seed {seed})\n")
    print("Per model: points / observations; tracks seen from ≥ 2 distinct images; solved and certified by "
          "pluecker; solved points whose exact pixel cost (this script, pycolmap's img_from_cam) is above the "
          f"tight BA's by > {ABOVE_OPTIMUM_REL:g} relative, or below it (pluecker lower); certified points whose "
          f"lower_bound / raw_lower_bound is above the tight BA's cost by > {BOUND_ABOVE_REL:g} relative; "
          "pluecker's reported cost against the exact cost at its own point; default BA points above the tight "
          "BA; estimate_triangulation solved / above the tight BA.\n")
    print("| model | points / obs | tracks ≥ 2 images | solved | certified | above tight BA | below tight BA | "
          "certified LB above | raw LB above | own cost vs exact (max rel) | default BA above | "
          "estimate_triangulation solved / above |")
    print("| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |")
    timings, notes = [], []
    for name, load in models:
        rec = load()
        soundness, timing, extra = retriangulation_row(name, rec)
        print(soundness, flush=True)
        timings.append(timing)
        notes += extra
    print("\n" + convention_check(seed))
    print("\n### Time (ms; pluecker and default BA best of 5, run alternately; gather = retriangulate − solve, solve = the calls "
          "into pluecker._core's *triangulate* functions; write = colmap.write to a temporary folder)\n")
    print("| model | retriangulate | gather | solve | write | pycolmap BA default | ratio | BA tight | "
          "estimate_triangulation |")
    print("| --- | --- | --- | --- | --- | --- | --- | --- | --- |")
    print("\n".join(timings))
    if notes:
        print("\nNotes:\n" + "\n".join(f"- {note}" for note in notes))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="one camera, no sparse batch")
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--localize-model", type=Path, metavar="DIR",
                        help="a real COLMAP model for the localisation with lens cameras (e.g. mamechun/gs_data's "
                        "distorted/sparse/0)")
    parser.add_argument("--localize-only", action="store_true", help="only the localisation with lens cameras")
    parser.add_argument("--model", metavar="PATH", help="a COLMAP sparse model for the re-triangulation section, "
                        "e.g. distorted/sparse/0 of the GitHub repository mamechun/gs_data")
    parser.add_argument("--retriangulation", action="store_true",
                        help="only the re-triangulation section against a tight points-only BA")
    args = parser.parse_args()
    if args.localize_only:
        print(f"pluecker {pluecker.__version__}, pycolmap {pycolmap.__version__}, PoseLib {poselib.__version__}\n")
        print("\n".join(localize_section(args.seed, args.localize_model)))
        return
    if args.retriangulation:
        commit = subprocess.run(["git", "-C", str(Path(__file__).parent), "rev-parse", "--short", "HEAD"],
                                capture_output=True, text=True).stdout.strip() or "unknown"
        print(f"pluecker {pluecker.__version__} (commit {commit}), pycolmap {pycolmap.__version__}, "
              f"numpy {np.__version__}, {os.cpu_count()} cores, load average {os.getloadavg()[0]:.2f} at the start\n")
        pycolmap.logging.minloglevel = 2  # no glog lines from the bundle adjuster
        colmap.retriangulate(pinhole_model(99, 20))  # warm-up: one-off imports are not timed
        retriangulation_section(args.seed, args.model)
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
    print()
    retriangulation_section(args.seed, args.model)
    if not args.quick:
        print("\n## Sparse batch (bench/sparse_tracks.py)\n")
        script = Path(__file__).with_name("sparse_tracks.py")
        out = subprocess.run([sys.executable, str(script)], capture_output=True, text=True, check=True).stdout
        print("```\n" + out.strip() + "\n```")


if __name__ == "__main__":
    main()
