"""Does ``pluecker.estimate_pose`` find the GLOBAL minimum of the reprojection error? A benchmark (not a
test) of the default, non-robust pipeline against the best minimum known, with OpenCV, PoseLib and
cvxpnpl on the same seeded scenes.

**Cost.** The cost of a pose ``(R, t)`` (``x_cam = R X + t``) is the maximum-likelihood cost under
Gaussian pixel noise, ``½ (Σ_points e² + Σ_endpoints d²)``: ``e`` of a point is its pixel distance,
``d`` of a segment endpoint its pixel distance to the projected 3-D line. On the ``cov-`` rows
(per-observation covariances) it is the whitened cost ``½ Σ r²`` that ``estimate_pose`` minimises with
``point_covariances`` / ``line_covariances``: a point's ``r·r = eᵀ Σ⁻¹ e``, ``e = π(R X + t) − u``; an
endpoint's ``r = d / √(n̂ᵀ Σ n̂)``, ``d`` its signed pixel distance to the projected line and ``n̂``
that line's unit normal. On the ``lens-`` rows (a distorting camera) the pixels are the observed,
distorted ones, as ``estimate_pose`` measures them through a ``Camera``: a point's ``e`` is to the
lens projection ``K D(x/z, y/z)`` of ``R X + t`` (``D`` the COLMAP model's distortion, the script's own
``Lens``); an endpoint's ``d`` is its distance to the *curved* image ``K D(ℓ)`` of the projected line
``ℓ`` (the line through the normalised projections of the 3-D endpoints), ``min_q |K D(q) − e|`` over
the points ``q`` of ``ℓ`` inside the lens's fold radius (the branch through the observation; the whole
line for the lenses here). ``curve_distance2`` finds it by 256 viewing angles along ``ℓ`` (they cover
the whole line), then 6 Newton steps from the best one; the answer is the least value met, never below
the true minimum, and agrees with the library's search (1-D Gauss-Newton from the foot of the
undistorted observation, ``crates/pluecker/src/curved_line.rs``) to ~1e-12 relative where the branch has
one minimum, as on these scenes (target (8)). All of these are computed here in numpy, not by the
library, so that the certified bounds are checked against a cost of the script's own. A pose with a
non-finite entry, a matrix that is not a rotation (``max |R Rᵀ − I| > 1e-6`` or ``det R ≤ 0``, the
library's own tolerance for a rotation argument), or a 3-D point or segment endpoint at depth ``<= 0``
is not valid: its cost is taken as +inf.

**Best known minimum** of a scene: the lowest valid cost among

- (a) ``estimate_pose(..., options=PoseOptions(initial_pose=(R_true, t_true)))``: pluecker started at the truth;
- (b) ``estimate_pose(..., options=PoseOptions(ransac=RansacOptions(point_threshold=1e6, line_threshold=1e6, min_inliers=3,
  seed=scene_seed)))``: LO-RANSAC over every minimal sample mix, scoring with the plain squared error,
  then refined (an exception counts as no candidate);
- (c) ``S`` random starts ``estimate_pose(..., options=PoseOptions(initial_pose=(R_rand, t_rand)))``, ``R_rand`` uniform on
  SO(3), ``t_rand`` putting the object's centroid at its true depth on the optical axis. ``S`` is
  ``--starts`` (default 100) on the rows with ≤ 10 correspondences and ``--starts-large`` (default 20)
  on the rows with more (70 or 100), whose cost has far fewer local minima: the random starts are the
  largest part of the run, and scale with pluecker's time per call;
- (d) pluecker's own default answer, and its ``certify=True`` answer when that keyword exists;
- (e) every peer's raw answer: a peer answer cheaper than all of pluecker's candidates lowers the
  best known minimum (``peer_lowered_best`` in the JSON counts those scenes per peer; ``reached_best``
  counts, per source, the scenes where it reached the best known minimum).

**Miss**: a method's answer whose cost is above ``best_known × (1 + 1e-6) + 1e-9``; an invalid or
failed answer (cost +inf) is a miss too. The validity rule is pluecker's ``behind_camera``: a
pose that puts a segment endpoint behind the camera is invalid even though only the infinite 3-D line
enters the cost (PoseLib does not check that for lines, hence most of its failures on line rows).

**Scenes.** Camera 640 x 480, ``fx = fy = f``, ``cx = 320``, ``cy = 240``; every scene draws
everything from ``numpy.random.default_rng(seed + i)`` (scene ``i`` of every row, ``--seed`` default
0): a uniform random rotation ``R``; each point (and each segment endpoint) as a pixel uniform in the
image and a depth uniform in 4.2 .. 7.8 (6 ± 30 %), back-projected to ``x_cam``; segments shorter than
20 px in the image are drawn again; the world frame is ``X = Rᵀ (x_cam − c) + o``, ``c`` the
camera-frame centroid of all 3-D points and endpoints and ``o`` uniform in [-5, 5]³, so
``t = c − R o``. Planar objects: every point and endpoint on one plane through (0, 0, 6) (camera
frame) whose normal is tilted 30-60° from the optical axis (uniform azimuth), the pixel's ray cut with
the plane, drawn again when the depth falls outside 2 .. 20. Then i.i.d. Gaussian noise, σ = 1 px, on
every image point and endpoint. Mixed data of ``n`` correspondences are ``ceil(n/2)`` points and
``floor(n/2)`` segments. Rows:

- ``f{250,800,4000,15000}-n{4,6,10,100}-{points,lines,mixed}``: general objects;
- ``planar-f{800,4000}-n{4,6,10,100}-{points,mixed}``: planar objects;
- ``rs-{general,planar,far}-{100p,50p20l}``: the scenes of ``bench/compare_pose.py``,
  ``pluecker.random_scene(kind, n_points, n_lines, seed)`` (f = 800) with the noise added as there;
- ``cov-f{800,4000,15000}-n{10,100}-{points,mixed}``: per-observation covariances. The general object
  of the row without ``cov-`` (the same draws, so the same geometry), then, instead of the 1 px
  noise, every image point and segment endpoint its own covariance ``Σ = R(φ) diag(σ₁², σ₂²) R(φ)ᵀ``,
  ``σ₁, σ₂`` uniform in 0.5 .. 2.0 px and ``φ`` uniform in [0, π) (all drawn after the geometry, points
  then endpoints), and noise ``R(φ) diag(σ₁, σ₂) z``, ``z ~ N(0, I)``, drawn from it. Every pluecker
  call on these rows passes ``point_covariances`` (N, 2, 2) and ``line_covariances`` (M, 2, 2, 2); the
  peers take no covariances and do not run on them; targets (3) and (4) leave them out;
- ``lens-{mild,strong}-f{250,800,4000,15000}-{n100-points,n10-points,n10-mixed,n100-mixed,n10-lines}``
  and ``lens-fisheye-f{250,800}-n100-{points,mixed}``: a distorting camera (``LENSES``), COLMAP's
  ``OPENCV`` with ``fx = fy = f``, ``cx = 320``, ``cy = 240`` and ``k1, k2, p1, p2`` = -0.05, 0.01, 1e-4,
  -1e-4 (mild) or -0.3, 0.1, 1e-3, -5e-4 (strong: 11 % barrel at the corner of the f = 250 image), or
  ``OPENCV_FISHEYE`` with ``k1..k4`` = 0.05, -0.01, 0.002, -0.0005. The general object of the row
  without ``lens-<lens>-`` (its *pinhole pair*, same f and composition), each pixel drawn in the image
  of the lens's pinhole part as there, then distorted by the script's own projection (``Lens.pixels``):
  a point whose distorted pixel leaves the image, or whose normalised radius is beyond the lens's fold
  radius (where the distortion stops increasing: infinite for these three lenses), is drawn again, as
  is a segment shorter than 20 px once distorted. These lenses move pixels inwards: a scene's geometry
  is its pinhole pair's but where a segment was drawn again (6 and 8 of the first 50 scenes of
  ``lens-strong-f250-n100-mixed`` and ``lens-fisheye-f250-n100-mixed``, none at f ≥ 800). Then the
  1 px noise on the distorted pixels. Every pluecker call gets ``pluecker.Camera``; the peers do
  not run on them; targets (3) and (4) leave them out, target (7) compares them with their pinhole
  pairs, and target (6) covers them (the certificate through a lens, kind ``lens_sublevel_set``).

``--rows`` selects by substring: ``--rows f800-n10`` also selects ``cov-f800-n10-points``,
``cov-f800-n10-mixed`` and the ``lens-*-f800-n10-*`` rows; ``--rows lens`` selects the 44 lens rows.

**Columns** of the Markdown table (one line per row; the JSON holds more):

- ``n``: scenes; ``misses``: pluecker default misses; ``succ``: of those, how many say
  ``status == "success"``; ``amb``: of those, how many say ``ambiguous`` (``res.ambiguous`` true, or
  status ``"ambiguous"``; ``n/a`` when the result has no such attribute);
- ``cert``: fraction of default answers with ``res.certified`` true (``n/a`` without the attribute);
- ``med µs`` / ``p95 µs``: median and 95th percentile over scenes of the time of one default call
  (``time.perf_counter`` around the Python call; the fastest of ``--repeats`` calls, by default one:
  the first call of that method on a new scene, with no warm-up, as for every method here. On a scene
  the timed calls come in the order pluecker default, SQPnP, PoseLib, ITERATIVE, SQPnP+LM,
  PoseLib-1, ``certify=True``, cvxpnpl, then the untimed candidates, so that no timed call directly
  follows one of the same code on the same data, which would be warmer, and none follows cvxpnpl,
  after which a call is up to 4 times slower; ``--repeats 3`` gives warm timings as in
  ``bench/compare_pose.py``);
- ``certify=True``: fraction certified, median and p95 µs of ``estimate_pose(..., options=PoseOptions(certify=pluecker.CertifyOptions()))``, or
  ``n/a`` when the keyword is not accepted;
- ``status``: histogram of the default answers' statuses;
- per peer: ``misses`` (``k/m`` when it ran on a subset of the scenes; ``[g]``, shown when it differs:
  of them, the gross misses, more than 10 % above the best known or invalid, i.e. in another basin
  rather than an unrefined answer or a refinement stopped a little early; ``(j fail)``: of them, failures, i.e. an
  exception, the library's failure flag or an invalid pose) and median µs of one call (Python
  boundary included, as for pluecker); ``—`` where the peer does not apply. The JSON also has the
  gross misses of pluecker (``gross_misses``).

**Peers**, each on the same scenes and pixels:

- ``sqpnp``: OpenCV ``solvePnP(..., flags=SOLVEPNP_SQPNP)``, points-only rows. SQPnP minimises an
  object-space error, not the reprojection error, and its answer is not refined: it misses nearly
  always by construction (by about 0.2 % of the cost with 100 points, often by more than 10 % with 4
  points); it is here for its time;
- ``sqpnp+lm``: the same followed by ``solvePnPRefineLM`` (reprojection error), OpenCV's ML pipeline;
- ``iter``: ``SOLVEPNP_ITERATIVE`` (DLT or homography start, then Levenberg-Marquardt); it needs ≥ 6
  points for non-planar objects (≥ 4 planar): an exception or ``retval`` false counts as a failure;
- ``poselib``: ``estimate_absolute_pose`` (points) or ``estimate_absolute_pose_pnpl`` (lines, mixed)
  with ``max_reproj_error = max_epipolar_error = 1e6`` so that every correspondence is an inlier (the
  RANSAC score is then the plain squared error), PoseLib's default ``min_iterations`` of 1000 minimal
  samples scored, and least-squares refinement (``loss_type: TRIVIAL``, the cost used here; PoseLib's
  default Cauchy loss would minimise another cost). Failure flag: fewer than 3 inliers;
- ``poselib-1``: the same with ``min_iterations: 0``: with all inliers, one minimal sample then the
  refinement, i.e. PoseLib as a local method started from P3P / P2P1L / P1P2L / P3L;
- ``cvxpnpl`` (pure Python + SCS): ``pnp`` / ``pnl`` / ``pnpl``, the SDP (Shor) relaxation of an
  algebraic cost; on the rows with ≤ 10 correspondences only (3-35 ms per call, under 100 ms: on every
  scene unless ``--cvx-scenes`` says fewer). Of the candidates it returns the cheapest valid one is
  taken (the choice not timed). Its answer is not refined on the reprojection error, so it misses
  nearly always; the JSON's ``reached_best`` and the misses of the other peers are the informative
  numbers.

**Targets** (PASS/FAIL lines): (1) no pluecker miss in any row with ≥ 6 correspondences; (2) in rows
with 4-5 correspondences every miss is flagged ambiguous or has a non-success status; (3) certified
≥ 99 % on the 100-correspondence rows and ≥ 95 % on the 10-correspondence rows (the ``certify=True``
answers when that keyword exists, else the default's ``certified``; n/a without either); (4) median
time of a certified answer (``certify=True``, else the default) ≤ 1 ms on the 100-point rows; (5) on
``f800-n100-points`` the default's median time ≤ OpenCV SQPnP's in the same run; (6) soundness: no
certified answer's ``raw_lower_bound`` above the least cost any candidate reached (every cost here is
this script's own code, not the library's residuals; n/a when nothing was certified); (7) lens cameras at
the pinhole rates: each ``lens-`` row's certified fraction at most 0.06 below its pinhole pair's (one
scene of 50 is 0.02; n/a for a lens row whose pair is not in the run, e.g. with ``--rows lens``); (8)
when lens rows run, the script's lens code against the library's (``lens_self_test``, before the rows):
``Lens.pixels`` = ``Camera.project`` and ``Camera.unproject`` of the drawn pixels back to their
points, both to 1e-9 px, on 500 points drawn as the scenes draw them per lens and f; the own cost
(``2 pose_cost``) = ``result.cost`` at the default answer to 1e-8 relative, on the first 2 scenes of each
lens row. Targets (3) and (4) are on the rows without covariances or lens (the ``cov-`` and ``lens-``
rows' certified fraction and times are in the table and the JSON). After the table the script lists,
per row, why ``certify=True`` answers were not certified (``details.uncertified_reason`` up to its first
``;``, numbers shown as ``#``).

Results go to ``bench/out/compare_global_pose.json`` (every number of the table, the misses' seeds and
relative excess cost, ``reached_best`` per source, the peers' failure reasons, the uncertified reasons,
the lens self-test's numbers, the wall time per part of the work, machine, versions and arguments). At
the end the script prints, to stderr, its wall time and an extrapolation of the same rows to the default
settings. Run from the repository root with the
venv (``.venv/bin/pip install opencv-python-headless poselib cvxpnpl``; a peer that is missing is
reported as not available and skipped):

    .venv/bin/python bench/compare_global_pose.py          # 126 rows x 1000 scenes (times below)
    .venv/bin/python bench/compare_global_pose.py --quick  # 20 scenes per row, 10 starts
    .venv/bin/python bench/compare_global_pose.py --rows cov- --quick   # the 12 rows with covariances
    .venv/bin/python bench/compare_global_pose.py --rows lens --quick   # the 44 rows through a lens
    .venv/bin/python bench/compare_global_pose.py --rows f800-n4 rs- --scenes 200   # rows by substring
    .venv/bin/python bench/compare_global_pose.py --list-rows

The full-run time is the extrapolation of a ``--quick`` run of 2026-11-23 (15.9 s; the extension as
built around commit ``4529260``, 20-200 µs per default call): random starts about 8 min, cvxpnpl
about 8 min, PoseLib (1000 samples a call) about 3.5 min. A slower pluecker lengthens the random starts in
proportion. Those times are of the 70 rows without covariances. The 12 ``cov-`` rows took 108 s with
``--quick`` on 2026-11-27 (the extension as built after commit ``a81504d``), extrapolated to about
90 min with the defaults, nearly all of it the robust candidate (b) (0.15 s a call on the points rows,
0.75 s on the mixed ones: it runs to its iteration cap, as on the rows without covariances with that
build). The 44 ``lens-`` rows took 80 s with ``--scenes 4 --starts 3 --starts-large 2`` on 2026-11-27,
extrapolated to about 6.3 h with the defaults: 5.3 h the robust candidate (b) (0.2-1 s a call on most
rows), 1 h the random starts (the script's curved-line cost takes 1-3 ms a call with 10-50 segments).
The machine is shared and noisy: compare times taken in the same run only.
"""

from __future__ import annotations

import argparse
import datetime
import json
import math
import os
import platform
import re
import sys
import time
import warnings
from pathlib import Path
from typing import Any, Callable

import numpy as np

try:
    import pluecker
except ImportError as exc:  # pragma: no cover
    sys.exit(f"compare_global_pose.py needs the pluecker bindings ({exc}); build them first (see bench/README.md).")

from compare_pose import _finite_or_none  # noqa: E402  (bench/ is the script's folder, first on sys.path)
from global_pose_scenes import (  # noqa: E402  (bench/ is the script's folder, first on sys.path)
    COV_SIGMA_PX,
    CURVE_NEWTON_STEPS,
    CURVE_SAMPLES,
    HEIGHT,
    LENS_COST_TOL,
    LENS_PROJECTION_TOL_PX,
    LENS_SELF_TEST_SCENES,
    LENSES,
    SIGMA_PX,
    WIDTH,
    Lens,
    Row,
    Scene,
    _draw_point,
    all_rows,
    make_scene,
    pose_cost,
    random_rotation,
)

PEER_STATE: dict[str, str] = {}  # peer -> "ok" or "not available: <reason>"
try:
    import cv2

    PEER_STATE["opencv"] = "ok"
except ImportError as exc:  # pragma: no cover - depends on the environment
    cv2 = None
    PEER_STATE["opencv"] = f"not available: {exc}"
try:
    import poselib

    PEER_STATE["poselib"] = "ok"
except ImportError as exc:  # pragma: no cover
    poselib = None
    PEER_STATE["poselib"] = f"not available: {exc}"
try:
    import cvxpnpl

    PEER_STATE["cvxpnpl"] = "ok"
except Exception as exc:  # pragma: no cover - ImportError or an error of its SCS backend
    cvxpnpl = None
    PEER_STATE["cvxpnpl"] = f"not available: {type(exc).__name__}: {exc}"

MISS_REL, MISS_ABS = 1e-6, 1e-9
GROSS_REL = 0.1  # a "gross" miss: more than 10 % above the best known (another basin), or invalid
HUGE_THRESHOLD = 1e6
DEFAULT_SCENES = 1000
QUICK_SCENES = 20
DEFAULT_STARTS = 100
DEFAULT_STARTS_LARGE = 20
QUICK_STARTS = 10
DEFAULT_CVX_SCENES: int | None = None  # None: every scene of the row (a call takes 3-50 ms, under 100 ms)
CVX_MAX_CORRESPONDENCES = 10
LARGE_ROW = 10  # rows with more correspondences than this use --starts-large
CERT_TARGET = {100: 0.99, 10: 0.95}
CERT_TIME_TARGET_US = 1000.0
LENS_RATE_SLACK = 0.06  # target (7): a lens row's certified fraction at most this below its pinhole row's
OUT = Path(__file__).resolve().parent / "out" / "compare_global_pose.json"

PEERS = ("sqpnp", "sqpnp+lm", "iter", "poselib", "poselib-1", "cvxpnpl")  # the table's order
# The order of the calls on a scene: no peer right after one that runs the same code on the same data;
# cvxpnpl (SCS, megabytes of memory) runs after pluecker's certify=True and before the untimed calls,
# because a call right after it is up to 4 times slower.
RUN_ORDER = ("sqpnp", "poselib", "iter", "sqpnp+lm", "poselib-1")
LAST_PEERS = ("cvxpnpl",)


# --------------------------------------------------------------------------------------------------
# Rows and scenes
























# --------------------------------------------------------------------------------------------------
# Cost










# --------------------------------------------------------------------------------------------------
# Methods. A peer maps a scene to (R, t, ok) and may raise; ok False is the library's failure flag.


def lens_self_test(rows: list[Row], seed: int) -> dict[str, Any]:
    """This script's lens code against the library's, for the selected lens rows: ``Lens.pixels``
    against ``Camera.project`` at 500 points per lens and focal length drawn as the scenes draw them
    (``_draw_point``), ``Camera.unproject`` of their pixels against their normalised coordinates (px:
    the pixels are inside the lens's invertible region), and the cost, ``2 pose_cost``, against
    ``result.cost`` at the default answer on the first ``LENS_SELF_TEST_SCENES`` scenes of each row.
    Raises AssertionError when the projections differ by more than ``LENS_PROJECTION_TOL_PX``: the
    scenes and costs would then not be those of the library's lens."""
    projection = unprojection = cost_relative = 0.0
    for lens in {Lens(*LENSES[r.lens], r.f) for r in rows if r.lens}:
        rng = np.random.default_rng([seed, 2])
        x = np.array([_draw_point(rng, lens.f, None, lens)[0] for _ in range(500)])
        n = x[:, :2] / x[:, 2:]
        camera = lens.camera()
        projection = max(projection, float(np.max(np.abs(lens.pixels(n) - camera.project(x)))))
        unprojection = max(unprojection, lens.f * float(np.max(np.abs(camera.unproject(lens.pixels(n)) - n))))
    assert projection <= LENS_PROJECTION_TOL_PX, f"own lens projection off Camera.project by {projection:.2e} px"
    worst_at, scenes = None, 0
    for row in rows:
        for i in range(LENS_SELF_TEST_SCENES if row.lens else 0):
            s = make_scene(row, seed + i)
            res, _, err = call_pluecker(s, 1)
            rel = math.nan if res is None else abs(2.0 * pose_cost(s, *res.pose) - res.cost) / max(res.cost, 1e-12)
            scenes += 1
            if not rel <= cost_relative:  # NaN (an exception or a non-finite cost) counts as the worst
                cost_relative, worst_at = rel, f"{row.name} seed {seed + i}" + (f" ({err})" if err else "")
    return {
        "projection_px": projection,
        "unprojection_px": unprojection,
        "cost_relative": cost_relative,
        "cost_worst_at": worst_at,
        "scenes": scenes,
    }


def timed(fn: Callable[[], Any], repeats: int) -> tuple[Any, float]:
    """The first call's result and the fastest of ``repeats`` calls, seconds."""
    best, out = math.inf, None
    for i in range(repeats):
        start = time.perf_counter()
        r = fn()
        elapsed = time.perf_counter() - start
        best = min(best, elapsed)
        if i == 0:
            out = r
    return out, best


def _opencv(flag: int, refine: bool = False) -> Callable[[Scene], tuple[np.ndarray, np.ndarray, bool]]:
    def run(s: Scene) -> tuple[np.ndarray, np.ndarray, bool]:
        ok, rvec, tvec = cv2.solvePnP(s.points3d, s.points2d, s.K, None, flags=flag)
        if ok and refine:
            rvec, tvec = cv2.solvePnPRefineLM(s.points3d, s.points2d, s.K, None, rvec, tvec)
        return cv2.Rodrigues(rvec)[0], np.asarray(tvec).reshape(3), bool(ok)

    return run


def _poselib(min_iterations: int | None) -> Callable[[Scene], tuple[np.ndarray, np.ndarray, bool]]:
    ransac: dict[str, Any] = {"max_reproj_error": HUGE_THRESHOLD, "max_epipolar_error": HUGE_THRESHOLD}
    if min_iterations is not None:
        ransac["min_iterations"] = min_iterations
    bundle = {"loss_type": "TRIVIAL"}

    def run(s: Scene) -> tuple[np.ndarray, np.ndarray, bool]:
        params = [s.camera.fx, s.camera.fy, s.camera.cx, s.camera.cy]
        cam = {"model": "PINHOLE", "width": WIDTH, "height": HEIGHT, "params": params}
        if len(s.lines3d):
            pose, info = poselib.estimate_absolute_pose_pnpl(
                s.points2d,
                s.points3d,
                s.lines2d[:, 0],
                s.lines2d[:, 1],
                s.lines3d[:, 0],
                s.lines3d[:, 1],
                cam,
                ransac,
                bundle,
            )
        else:
            pose, info = poselib.estimate_absolute_pose(s.points2d, s.points3d, cam, ransac, bundle)
        return np.asarray(pose.R), np.asarray(pose.t), info["num_inliers"] >= 3

    return run


def _cvxpnpl(s: Scene) -> list[tuple[np.ndarray, np.ndarray]]:
    """Every candidate pose cvxpnpl returns (chosen from outside the timed call)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # "The solution is not certifiably optimal." and SCS notes
        if len(s.lines3d) == 0:
            return cvxpnpl.pnp(s.points2d, s.points3d, s.K)
        if len(s.points3d) == 0:
            return cvxpnpl.pnl(s.lines2d, s.lines3d, s.K)
        return cvxpnpl.pnpl(s.points2d, s.lines2d, s.points3d, s.lines3d, s.K)


def call_pluecker(s: Scene, repeats: int, **extra: Any) -> tuple[Any, float, str | None]:
    """``estimate_pose`` on the scene, with its covariances when it has them: (result or None, fastest
    of ``repeats`` calls in seconds, the exception's class name or None). A PlueckerError (e.g.
    TooFewCorrespondencesError) is reported, not raised."""
    try:
        res, sec = timed(lambda: pluecker.estimate_pose(s.camera, **s.kwargs, **s.noise_kwargs, **extra), repeats)
        return res, sec, None
    except pluecker.PlueckerError as e:
        return None, math.nan, type(e).__name__


def peer_applies(peer: str, row: Row) -> bool:
    if row.covariances or row.lens:  # no peer here takes per-observation covariances or distortion
        return False
    if peer in ("sqpnp", "sqpnp+lm", "iter"):
        return cv2 is not None and row.data == "points"
    if peer in ("poselib", "poselib-1"):
        return poselib is not None
    if peer == "cvxpnpl":
        return cvxpnpl is not None and row.n <= CVX_MAX_CORRESPONDENCES
    raise KeyError(peer)


def run_peer(peer: str, s: Scene, repeats: int) -> tuple[float, float, str | None]:
    """(cost, seconds, failure reason or None)."""
    try:
        if peer == "cvxpnpl":
            cands, seconds = timed(lambda: _cvxpnpl(s), repeats)
            costs = [pose_cost(s, R, t) for R, t in cands]
            cost = min(costs) if costs else math.inf
            return cost, seconds, (None if math.isfinite(cost) else "no valid candidate")
        fn = {
            "sqpnp": _opencv(cv2.SOLVEPNP_SQPNP) if cv2 else None,
            "sqpnp+lm": _opencv(cv2.SOLVEPNP_SQPNP, refine=True) if cv2 else None,
            "iter": _opencv(cv2.SOLVEPNP_ITERATIVE) if cv2 else None,
            "poselib": _poselib(None),
            "poselib-1": _poselib(0),
        }[peer]
        (R, t, ok), seconds = timed(lambda: fn(s), repeats)
    except Exception as e:  # noqa: BLE001 - any error of a library is a failure to report
        return math.inf, math.nan, f"exception: {type(e).__name__}"
    cost = pose_cost(s, R, t)
    if not ok:
        return cost, seconds, "failure flag"
    if not math.isfinite(cost):
        return cost, seconds, "invalid pose"
    return cost, seconds, None


# --------------------------------------------------------------------------------------------------
# One row


def _quantiles(us: list[float]) -> tuple[float, float]:
    a = np.array([x for x in us if math.isfinite(x)])
    if len(a) == 0:
        return math.nan, math.nan
    return float(np.median(a)), float(np.percentile(a, 95))


def _reason(res: Any, err: str | None) -> str:
    """Why a certify=True answer is not certified: ``details.uncertified_reason`` up to its first ``;``,
    numbers replaced by ``#`` so that the reasons make a histogram."""
    if res is None:
        return f"exception: {err}"
    why = getattr(getattr(res, "details", None), "uncertified_reason", None) or "no reason given"
    return re.sub(r"[-+]?\d+(\.\d*)?([eE][-+]?\d+)?", "#", why.split(";")[0])


class Features:
    """What the installed pluecker offers, found on the first call."""

    certify_kw: bool | None = None  # estimate_pose(..., certify=True) accepted
    ambiguous_attr: bool | None = None
    certified_attr: bool | None = None


def run_row(row: Row, args: argparse.Namespace) -> dict[str, Any]:
    n_scenes = args.scenes
    starts = args.starts if row.n <= LARGE_ROW else args.starts_large
    peers = [p for p in RUN_ORDER + LAST_PEERS if peer_applies(p, row)]
    cvx_limit = args.cvx_scenes
    t_default: list[float] = []
    t_cert: list[float] = []
    statuses: dict[str, int] = {}
    cert_statuses: dict[str, int] = {}
    uncertified_reasons: dict[str, int] = {}  # certify=True answers not certified, by reason (numbers elided)
    misses = misses_gross = miss_success = miss_ambiguous = ambiguous_flags = status_ambiguous = 0
    certified = cert_certified = cert_misses = 0
    # Certified lower bounds against the best cost found (this script's own cost code): how many were
    # checked, how many lie above it (a wrong certificate), and the least relative margin.
    bounds_checked = bound_violations = 0
    bound_margin = math.inf
    small_miss_unflagged = 0  # misses that are neither flagged ambiguous nor non-success
    reached_best: dict[str, int] = {}  # per source: scenes where it reached the best known minimum
    peer_lowered_best: dict[str, int] = {}  # per peer: scenes where it was below every pluecker candidate
    phase: dict[str, float] = {}  # wall seconds per part of the work, for the extrapolation of run time
    miss_seeds: list[int] = []
    miss_excess: list[float] = []  # cost / best − 1 of the misses with a valid pose
    miss_invalid = 0  # misses with no valid pose (exception, NaN, a point behind the camera)
    robust_errors: dict[str, int] = {}
    peer_stats: dict[str, dict[str, Any]] = {
        p: {"scenes": 0, "misses": 0, "gross": 0, "failures": 0, "failure_reasons": {}, "times_us": [], "excess": []}
        for p in peers
    }
    for i in range(n_scenes):
        seed = args.seed + i
        clock = time.perf_counter()

        def lap(name: str) -> None:
            nonlocal clock
            now = time.perf_counter()
            phase[name] = phase.get(name, 0.0) + now - clock
            clock = now

        s = make_scene(row, seed)
        kw = s.kwargs
        lap("scene")

        res, sec, err = call_pluecker(s, args.repeats)
        t_default.append(sec * 1e6)
        if Features.ambiguous_attr is None and res is not None:
            Features.ambiguous_attr = hasattr(res, "ambiguous") or hasattr(res, "details")  # status "ambiguous"
            Features.certified_attr = hasattr(res, "certified")
        status = str(res.status) if res is not None else f"exception: {err}"
        statuses[status] = statuses.get(status, 0) + 1
        flagged = bool(getattr(res, "ambiguous", None)) or status == "ambiguous"
        ambiguous_flags += flagged
        status_ambiguous += status == "ambiguous"
        certified += getattr(res, "certified", None) is True
        cost_default = pose_cost(s, res.pose.rotation, res.pose.translation) if res is not None else math.inf
        candidates = {"default": cost_default}
        lap("default")

        # the peers and certify=True before the candidates, so that no timed call comes right after
        # another of the same code on the same data (the first call on a scene is cache-cold)
        peer_costs: dict[str, float] = {}

        # (this scene's i, s and peer_costs bound as defaults: the function is called in this iteration only)
        def run_peers(
            names: tuple[str, ...], i: int = i, s: Scene = s, peer_costs: dict[str, float] = peer_costs
        ) -> None:
            for p in names:
                if p not in peers or (p == "cvxpnpl" and i >= cvx_limit):
                    continue
                cost, psec, reason = run_peer(p, s, args.repeats)
                st = peer_stats[p]
                st["scenes"] += 1
                st["times_us"].append(psec * 1e6)
                if reason is not None:
                    st["failures"] += 1
                    st["failure_reasons"][reason] = st["failure_reasons"].get(reason, 0) + 1
                peer_costs[p] = cost
                lap(p)

        run_peers(RUN_ORDER)

        if Features.certify_kw is None:
            try:
                pluecker.estimate_pose(
                    s.camera, **kw, **s.noise_kwargs, options=pluecker.PoseOptions(certify=pluecker.CertifyOptions())
                )
                Features.certify_kw = True
            except TypeError:
                Features.certify_kw = False
            except pluecker.PlueckerError:
                Features.certify_kw = True
        cost_cert = math.nan
        cert_bound = None
        if Features.certify_kw:
            cres, csec, cerr = call_pluecker(
                s, args.repeats, options=pluecker.PoseOptions(certify=pluecker.CertifyOptions())
            )
            t_cert.append(csec * 1e6)
            cstatus = str(cres.status) if cres is not None else f"exception: {cerr}"
            cert_statuses[cstatus] = cert_statuses.get(cstatus, 0) + 1
            cert_certified += getattr(cres, "certified", None) is True
            if getattr(cres, "certified", None) is not True:
                why = _reason(cres, cerr)
                uncertified_reasons[why] = uncertified_reasons.get(why, 0) + 1
            cost_cert = pose_cost(s, cres.pose.rotation, cres.pose.translation) if cres is not None else math.inf
            candidates["certify"] = cost_cert
            cert_bound = cres.certificate.raw_lower_bound if getattr(cres, "certified", None) is True else None
        lap("certify")

        run_peers(LAST_PEERS)

        # (a) the truth as a start, (b) robust with huge thresholds, (c) random starts
        r, _, _ = call_pluecker(s, 1, options=pluecker.PoseOptions(initial_pose=(s.R, s.t)))
        candidates["true-start"] = pose_cost(s, r.pose.rotation, r.pose.translation) if r is not None else math.inf
        lap("true-start")
        if not args.skip_robust:
            r, _, err = call_pluecker(
                s,
                1,
                options=pluecker.PoseOptions(
                    ransac=pluecker.RansacOptions(
                        point_threshold=HUGE_THRESHOLD, line_threshold=HUGE_THRESHOLD, min_inliers=3, seed=seed
                    )
                ),
            )
            if r is None:
                robust_errors[err] = robust_errors.get(err, 0) + 1
            candidates["robust"] = pose_cost(s, r.pose.rotation, r.pose.translation) if r is not None else math.inf
        lap("robust")
        srng = np.random.default_rng([seed, 1])
        best_start = math.inf
        for _ in range(starts):
            R0 = random_rotation(srng)
            t0 = np.array([0.0, 0.0, s.depth]) - R0 @ s.centroid
            r, _, _ = call_pluecker(s, 1, options=pluecker.PoseOptions(initial_pose=(R0, t0)))
            if r is not None:
                best_start = min(best_start, pose_cost(s, r.pose.rotation, r.pose.translation))
        candidates["random-start"] = best_start
        lap("random-starts")

        best_pluecker = min(candidates.values())
        best = min([best_pluecker, *peer_costs.values()])
        limit = best * (1 + MISS_REL) + MISS_ABS
        for src, c in {**candidates, **peer_costs}.items():
            if c <= limit:
                reached_best[src] = reached_best.get(src, 0) + 1
        for p, c in peer_costs.items():
            if c < best_pluecker * (1 - MISS_REL) - MISS_ABS:
                peer_lowered_best[p] = peer_lowered_best.get(p, 0) + 1
        if not cost_default <= limit:
            misses += 1
            misses_gross += not cost_default <= best * (1 + GROSS_REL) + MISS_ABS
            miss_success += status == "success"
            miss_ambiguous += flagged
            small_miss_unflagged += not flagged and status == "success"
            if len(miss_seeds) < 10:
                miss_seeds.append(seed)
            if math.isfinite(cost_default):
                miss_excess.append(cost_default / best - 1 if best > 0 else math.inf)
            else:
                miss_invalid += 1
        if Features.certify_kw and not cost_cert <= limit:
            cert_misses += 1
        if Features.certify_kw and cert_bound is not None:
            # raw_lower_bound is in Σ r², the costs here ½ Σ r²; 1e-9 of rounding between the two codes.
            bounds_checked += 1
            bound_violations += cert_bound > 2.0 * best * (1 + 1e-9) + 1e-12
            if best > 0:
                bound_margin = min(bound_margin, 1.0 - cert_bound / (2.0 * best))
        for p, c in peer_costs.items():
            peer_stats[p]["misses"] += not c <= limit
            peer_stats[p]["gross"] += not c <= best * (1 + GROSS_REL) + MISS_ABS
            if not c <= limit and math.isfinite(c) and best > 0:
                peer_stats[p]["excess"].append(c / best - 1)

    med, p95 = _quantiles(t_default)
    cmed, cp95 = _quantiles(t_cert)
    out_peers = {}
    for p, st in peer_stats.items():
        pm, pp = _quantiles(st["times_us"])
        out_peers[p] = {
            "scenes": st["scenes"],
            "misses": st["misses"],
            "gross_misses": st["gross"],
            "failures": st["failures"],
            "failure_reasons": st["failure_reasons"],
            "median_us": pm,
            "p95_us": pp,
            "miss_excess_median": float(np.median(st["excess"])) if st["excess"] else None,
        }
    return {
        "row": row.name,
        "source": row.source,
        "kind": row.kind or ("planar" if row.planar else "general"),
        "f": row.f,
        "n_points": row.n_points,
        "n_lines": row.n_lines,
        "correspondences": row.n,
        "data": row.data,
        "covariances": row.covariances,
        "lens": dict(zip(("name", "model", "distortion"), (row.lens, *LENSES[row.lens]))) if row.lens else None,
        "pinhole_pair": row.pinhole_pair,
        "scenes": n_scenes,
        "random_starts": starts,
        "misses": misses,
        "gross_misses": misses_gross,
        "misses_success": miss_success,
        "misses_flagged_ambiguous": miss_ambiguous if Features.ambiguous_attr or status_ambiguous else None,
        "misses_unflagged_success": small_miss_unflagged,
        "flagged_ambiguous": ambiguous_flags,
        "status_ambiguous": status_ambiguous,
        "miss_seeds": miss_seeds,
        "misses_invalid_pose": miss_invalid,
        "miss_excess_median": float(np.median(miss_excess)) if miss_excess else None,
        "miss_excess_max": float(np.max(miss_excess)) if miss_excess else None,
        "certified_fraction": certified / n_scenes if Features.certified_attr else None,
        "status_histogram": statuses,
        "median_us": med,
        "p95_us": p95,
        "certify": (
            {
                "certified_fraction": cert_certified / n_scenes,
                "misses": cert_misses,
                "bounds_checked": bounds_checked,
                "bound_violations": bound_violations,
                "least_bound_margin": bound_margin if math.isfinite(bound_margin) else None,
                "median_us": cmed,
                "p95_us": cp95,
                "status_histogram": cert_statuses,
                "uncertified_reasons": uncertified_reasons,
            }
            if Features.certify_kw
            else None
        ),
        "reached_best": reached_best,
        "peer_lowered_best": peer_lowered_best,
        "phase_seconds": phase,
        "robust_candidate_errors": robust_errors,
        "peers": out_peers,
    }


# --------------------------------------------------------------------------------------------------
# Report


def _na(x: Any, fmt: str) -> str:
    if x is None or (isinstance(x, float) and not math.isfinite(x)):
        return "n/a"
    return format(x, fmt)


def _hist(h: dict[str, int]) -> str:
    return ", ".join(f"{k} {v}" for k, v in sorted(h.items(), key=lambda kv: -kv[1]))


def markdown(rows: list[dict[str, Any]]) -> str:
    head = "| row | n | misses | succ | amb | cert | med µs | p95 µs | certify=True cert / med / p95 | status |"
    sep = "|---|---:|---:|---:|---:|---:|---:|---:|---:|---|"
    for p in PEERS:
        head += f" {p} misses | {p} µs |"
        sep += "---:|---:|"
    lines = [head, sep]
    for r in rows:
        c = r["certify"]
        cert_cols = (
            f"{_na(c['certified_fraction'], '.3f')} / {_na(c['median_us'], '.0f')} / {_na(c['p95_us'], '.0f')}"
            if c
            else "n/a"
        )
        line = (
            f"| {r['row']} | {r['scenes']} | {r['misses']} | {r['misses_success']} | "
            f"{_na(r['misses_flagged_ambiguous'], 'd')} | {_na(r['certified_fraction'], '.3f')} | "
            f"{_na(r['median_us'], '.1f')} | {_na(r['p95_us'], '.1f')} | {cert_cols} | {_hist(r['status_histogram'])} |"
        )
        for p in PEERS:
            st = r["peers"].get(p)
            if st is None:
                line += " — | — |"
            else:
                m = f"{st['misses']}" if st["scenes"] == r["scenes"] else f"{st['misses']}/{st['scenes']}"
                if st["gross_misses"] != st["misses"]:
                    m += f" [{st['gross_misses']}]"
                if st["failures"]:
                    m += f" ({st['failures']} fail)"
                line += f" {m} | {_na(st['median_us'], '.0f')} |"
        lines.append(line)
    return "\n".join(lines)


def _cert_fraction(r: dict[str, Any]) -> float | None:
    """A row's certified fraction: of the certify=True answers, else of the default answers (None: n/a)."""
    return r["certify"]["certified_fraction"] if r["certify"] else r["certified_fraction"]


def targets(rows: list[dict[str, Any]], self_test: dict[str, Any] | None = None) -> list[tuple[str, bool | None]]:
    """(text, True/False, or None for n/a). ``self_test``: ``lens_self_test``'s numbers, when it ran."""
    checks: list[tuple[str, bool | None]] = []
    big = [r for r in rows if r["correspondences"] >= 6]
    if big:
        bad = [f"{r['row']} {r['misses']}" for r in big if r["misses"]]
        text = f"(1) no miss in the {len(big)} rows with ≥ 6 correspondences"
        checks.append((text + (f"; misses: {', '.join(bad)}" if bad else ""), not bad))
    small = [r for r in rows if r["correspondences"] < 6]
    if small:
        bad = [f"{r['row']} {r['misses_unflagged_success']}" for r in small if r["misses_unflagged_success"]]
        note = "" if Features.ambiguous_attr else " (no `ambiguous` attribute: only non-success statuses count)"
        text = f"(2) every miss flagged ambiguous or non-success in the {len(small)} rows with 4-5 correspondences"
        checks.append((text + note + (f"; unflagged success misses: {', '.join(bad)}" if bad else ""), not bad))
    for n, goal in CERT_TARGET.items():
        sel = [r for r in rows if r["correspondences"] == n and not r["covariances"] and not r["lens"]]
        if not sel:
            continue
        fracs = [(r["row"], _cert_fraction(r)) for r in sel]
        known = [(name, f) for name, f in fracs if f is not None]
        text = f"(3) certified ≥ {goal:.0%} on the {len(sel)} {n}-correspondence rows"
        if len(known) < len(fracs):
            checks.append((f"{text}: n/a (no certification)", None))
            continue
        worst = min(known, key=lambda x: x[1])
        checks.append((f"{text} (lowest {worst[1]:.3f}, {worst[0]})", worst[1] >= goal))
    sel = [r for r in rows if r["n_points"] == 100 and r["n_lines"] == 0 and not r["covariances"] and not r["lens"]]
    if sel:
        times: list[tuple[str, float]] = []
        if Features.certify_kw:
            times = [(r["row"], r["certify"]["median_us"]) for r in sel]
            what = "certify=True"
        elif Features.certified_attr:
            times = [(r["row"], r["median_us"]) for r in sel]
            what = "default, which certifies"
        text = f"(4) certified answer median ≤ {CERT_TIME_TARGET_US:.0f} µs on the {len(sel)} 100-point rows"
        if not times:
            checks.append((f"{text}: n/a (no certification)", None))
        else:
            worst = max(times, key=lambda x: x[1])
            checks.append((f"{text} ({what}; slowest {worst[1]:.1f} µs, {worst[0]})", worst[1] <= CERT_TIME_TARGET_US))
    r = next((r for r in rows if r["row"] == "f800-n100-points"), None)
    if r is not None:
        sq = r["peers"].get("sqpnp")
        if sq is None:
            checks.append(("(5) f800-n100-points: pluecker median ≤ SQPnP's: n/a (OpenCV not available)", None))
        else:
            text = (
                f"(5) f800-n100-points: pluecker median {r['median_us']:.1f} µs ≤ OpenCV SQPnP "
                f"{sq['median_us']:.1f} µs (ratio {r['median_us'] / sq['median_us']:.2f})"
            )
            checks.append((text, r["median_us"] <= sq["median_us"]))
    checked = [r for r in rows if r["certify"] and r["certify"].get("bounds_checked")]
    if checked:
        bad = [f"{r['row']} {r['certify']['bound_violations']}" for r in checked if r["certify"]["bound_violations"]]
        total = sum(r["certify"]["bounds_checked"] for r in checked)
        margins = [
            r["certify"]["least_bound_margin"] for r in checked if r["certify"]["least_bound_margin"] is not None
        ]
        text = (
            f"(6) no certified lower bound above the best cost found (this script's cost code) in {total} "
            f"certified answers over {len(checked)} rows (least margin {min(margins):.2e})"
        )
        checks.append((text + (f"; violations: {', '.join(bad)}" if bad else ""), not bad))
    elif Features.certify_kw:
        checks.append(("(6) no certified lower bound above the best cost found: n/a (no certified answer)", None))
    lens_rows = [r for r in rows if r["lens"]]
    if lens_rows:
        by_name = {r["row"]: r for r in rows}
        pairs = [(r, by_name.get(r["pinhole_pair"])) for r in lens_rows]
        absent = [r["pinhole_pair"] for r, q in pairs if q is None]
        text = f"(7) lens cameras at the pinhole rates: certified fraction ≥ the pinhole row's − {LENS_RATE_SLACK:.2f}"
        note = f"; pinhole rows not in this run: {', '.join(absent)}" if absent else ""
        fractions = [(r, q, _cert_fraction(r), _cert_fraction(q)) for r, q in pairs if q is not None]
        compared = [(r, q, a, b) for r, q, a, b in fractions if a is not None and b is not None]
        if not compared or len(compared) < len(fractions):
            why = "no certification" if fractions else "no pinhole row of the same f and composition in this run"
            checks.append((f"{text}: n/a ({why}){note}", None))
        else:
            below = [
                f"{r['row']} {a:.3f} vs {q['row']} {b:.3f}"
                for r, q, a, b in compared
                if a < b - LENS_RATE_SLACK - 1e-12
            ]
            text += f" on {len(compared)} pairs"
            checks.append((text + (f"; below: {', '.join(below)}" if below else "") + note, not below))
    if self_test:
        text = (
            f"(8) own lens code = the library's: projection ≤ {LENS_PROJECTION_TOL_PX:.0e} px (max "
            f"{self_test['projection_px']:.1e}), unprojection of the drawn pixels ≤ {LENS_PROJECTION_TOL_PX:.0e} px "
            f"(max {self_test['unprojection_px']:.1e}), cost = result.cost to {LENS_COST_TOL:.0e} relative "
            f"(max {self_test['cost_relative']:.1e}, {self_test['cost_worst_at']}; {self_test['scenes']} scenes)"
        )
        ok = (
            self_test["projection_px"] <= LENS_PROJECTION_TOL_PX
            and self_test["unprojection_px"] <= LENS_PROJECTION_TOL_PX
            and self_test["cost_relative"] <= LENS_COST_TOL
        )
        checks.append((text, ok))
    return checks


def extrapolate_seconds(rows: list[dict[str, Any]]) -> float:
    """Wall time the same rows would take with the default settings (scenes, starts, cvxpnpl scenes),
    scaled part by part from this run's ``phase_seconds``."""
    total = 0.0
    for r in rows:
        scale = DEFAULT_SCENES / r["scenes"]
        full_starts = DEFAULT_STARTS if r["correspondences"] <= LARGE_ROW else DEFAULT_STARTS_LARGE
        for name, sec in r["phase_seconds"].items():
            if name == "random-starts":
                total += sec * scale * (full_starts / r["random_starts"] if r["random_starts"] else 0.0)
            elif name == "cvxpnpl":
                ran = r["peers"]["cvxpnpl"]["scenes"]
                total += sec * ((DEFAULT_CVX_SCENES or DEFAULT_SCENES) / ran if ran else 0.0)
            else:
                total += sec * scale
    return total


def versions() -> dict[str, str]:
    return {
        "python": platform.python_version(),
        "numpy": np.__version__,
        "opencv": getattr(cv2, "__version__", "n/a") if cv2 else "n/a",
        "poselib": getattr(poselib, "__version__", "unknown") if poselib else "n/a",
        "cvxpnpl": getattr(cvxpnpl, "__version__", "unknown") if cvxpnpl else "n/a",
        "pluecker": getattr(pluecker, "__version__", "unknown"),
    }


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument(
        "--scenes", type=int, default=None, help=f"scenes per row (default {DEFAULT_SCENES}; --quick {QUICK_SCENES})"
    )
    parser.add_argument("--seed", type=int, default=0, help="seed of the first scene; scene i of a row uses seed + i")
    parser.add_argument("--repeats", type=int, default=1, help="timed calls per scene and method, fastest kept")
    parser.add_argument(
        "--starts",
        type=int,
        default=None,
        help=f"random starts per scene on rows with ≤ {LARGE_ROW} correspondences "
        f"(default {DEFAULT_STARTS}; --quick {QUICK_STARTS})",
    )
    parser.add_argument(
        "--starts-large",
        type=int,
        default=None,
        help=f"random starts per scene on the larger rows (default {DEFAULT_STARTS_LARGE}; --quick {QUICK_STARTS})",
    )
    parser.add_argument(
        "--cvx-scenes", type=int, default=None, help="cvxpnpl runs on the first this many scenes of a row (default all)"
    )
    parser.add_argument(
        "--rows", nargs="+", default=None, help="run only the rows whose name contains one of these strings"
    )
    parser.add_argument(
        "--quick",
        action="store_true",
        help=f"{QUICK_SCENES} scenes per row, {QUICK_STARTS} random starts: a smoke test",
    )
    parser.add_argument(
        "--skip-robust",
        action="store_true",
        help="leave out candidate (b), the robust run with huge thresholds (0.2-1 s a call through a lens), "
        "from the search for the best pose: the truth start and the random starts remain",
    )
    parser.add_argument("--list-rows", action="store_true", help="print the row names and exit")
    parser.add_argument("--out", type=Path, default=OUT, help=f"JSON output (default {OUT})")
    args = parser.parse_args(argv)
    args.scenes = args.scenes or (QUICK_SCENES if args.quick else DEFAULT_SCENES)
    args.starts = args.starts if args.starts is not None else (QUICK_STARTS if args.quick else DEFAULT_STARTS)
    if args.starts_large is None:
        args.starts_large = QUICK_STARTS if args.quick else DEFAULT_STARTS_LARGE
    args.cvx_scenes = args.cvx_scenes if args.cvx_scenes is not None else args.scenes

    rows_def = all_rows()
    if args.rows:
        rows_def = [r for r in rows_def if any(s in r.name for s in args.rows)]
    if args.list_rows:
        print("\n".join(r.name for r in rows_def))
        return 0
    if not rows_def:
        sys.exit("no row matches --rows")
    for peer, state in PEER_STATE.items():
        if state != "ok":
            print(f"{peer}: {state}", file=sys.stderr)

    started = time.perf_counter()
    self_test = lens_self_test(rows_def, args.seed) if any(r.lens for r in rows_def) else None
    if self_test:
        print(f"lens self-test: {self_test}", file=sys.stderr)
    rows: list[dict[str, Any]] = []
    for row in rows_def:
        t0 = time.perf_counter()
        rows.append(run_row(row, args))
        rows[-1]["wall_seconds"] = time.perf_counter() - t0
        done = rows[-1]
        progress = f"{row.name}: {args.scenes} scenes, {done['wall_seconds']:.1f} s, {done['misses']} misses"
        print(progress, file=sys.stderr)
    wall = time.perf_counter() - started
    checks = targets(rows, self_test)
    full_estimate = extrapolate_seconds(rows)

    print(markdown(rows))
    print()
    print(
        f"pluecker features: ambiguous attribute {'yes' if Features.ambiguous_attr else 'n/a'}, certified attribute "
        f"{'yes' if Features.certified_attr else 'n/a'}, certify= keyword {'yes' if Features.certify_kw else 'n/a'}"
    )
    for peer, state in PEER_STATE.items():
        if state != "ok":
            print(f"{peer}: {state}")
    missing = [r for r in rows if r["misses"]]
    if missing:
        print("\nMisses (first seeds; median / max of cost / best − 1; scenes where each source reached the best):")
        for r in missing:
            print(
                f"  {r['row']}: {r['misses']} (success {r['misses_success']}, "
                f"invalid pose {r['misses_invalid_pose']}); "
                f"seeds {r['miss_seeds']}; excess "
                f"{_na(r['miss_excess_median'], '.2e')} / {_na(r['miss_excess_max'], '.2e')}; "
                f"reached by {r['reached_best']}"
            )
    uncertified = [r for r in rows if r["certify"] and r["certify"]["uncertified_reasons"]]
    if uncertified:
        print("\nNot certified (certify=True answers, by reason; numbers shown as #):")
        for r in uncertified:
            print(f"  {r['row']}: {_hist(r['certify']['uncertified_reasons'])}")
    print()
    for text, ok in checks:
        print(f"{'n/a ' if ok is None else ('PASS' if ok else 'FAIL')} {text}")
    print(
        f"\nwall time {wall:.1f} s; these {len(rows)} rows with the default settings ({DEFAULT_SCENES} scenes, "
        f"{DEFAULT_STARTS}/{DEFAULT_STARTS_LARGE} starts, cvxpnpl on {DEFAULT_CVX_SCENES or 'all'} scenes): about "
        f"{full_estimate / 60:.1f} min",
        file=sys.stderr,
    )

    args.out.parent.mkdir(parents=True, exist_ok=True)
    doc = {
        "date": datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds"),
        "machine": {"platform": platform.platform(), "cpus": os.cpu_count(), "processor": platform.processor()},
        "versions": versions(),
        "peers": PEER_STATE,
        "pluecker_features": {
            "ambiguous_attribute": Features.ambiguous_attr,
            "certified_attribute": Features.certified_attr,
            "certify_keyword": Features.certify_kw,
        },
        "settings": {
            "argv": sys.argv[1:] if argv is None else argv,
            "scenes": args.scenes,
            "seed": args.seed,
            "repeats": args.repeats,
            "starts": args.starts,
            "starts_large": args.starts_large,
            "large_row_above": LARGE_ROW,
            "cvx_scenes": args.cvx_scenes,
            "quick": args.quick,
            "rows_filter": args.rows,
            "sigma_px": SIGMA_PX,
            "cov_sigma_px": COV_SIGMA_PX,
            "lenses": LENSES,
            "curve_samples": CURVE_SAMPLES,
            "curve_newton_steps": CURVE_NEWTON_STEPS,
            "miss_rel": MISS_REL,
            "miss_abs": MISS_ABS,
            "wall_seconds": wall,
            "extrapolated_default_seconds": full_estimate,
        },
        "lens_self_test": self_test,
        "results": rows,
        "targets": [{"check": text, "pass": ok} for text, ok in checks],
    }
    args.out.write_text(json.dumps(_finite_or_none(doc), indent=2, allow_nan=False) + "\n")
    print(f"wrote {args.out}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
