"""Table 3 and the condition numbers of section 5.1 of Josephson & Kahl 2008, on synthetic planar conics.

The paper's conic data (three planar conics photographed in several images, Figure 6) are not available,
so the experiment is re-run on synthetic ones of the same kind (:func:`disc_scene`): a flat ellipse (a
disc: its dual quadric has rank 3 and "the condition number of the corresponding 4x4 matrix should be
zero") seen by ``VIEWS`` = 5 cameras (f = 800 px, 1000 x 1000 images) from 6-10 units away, each within
60° of the disc's normal; in every image 63 points of the outline, with i.i.d. Gaussian noise of 1 px,
are fitted by ``pluecker.fit_conic``, which gives the conic and its 5x5 residual covariance (as the paper
did). The quadric is triangulated with ``method`` = optimal, local ("bundle", from the linear solution)
and linear, all scenes of a method in one parallel batch (``pluecker.triangulate_quadrics``, each scene
with its own cameras). Reported: the norm of the whitened residual, ``sqrt(cost)`` (Table 3), the ratio
of the least to the largest singular value of the dual quadric ``Q`` (the paper's condition numbers: 0 for
a disc), certificates, branch-and-bound nodes and times. Scene ``k`` depends only on ``seed`` and ``k``; the
first three are tabulated like the paper's three conics, and all ``trials`` summarised.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass
from typing import Any

import numpy as np

import pluecker

from .common import METHOD_LABELS, METHODS, markdown_table, triangulation_options

VIEWS = 5
POINTS_PER_CONIC = 63
SIGMA_PX = 1.0
FOCAL_PX = 800.0
IMAGE_SIZE = 1000.0
#: The paper's stopping gap for conics ("a gap less then 5 %"); pluecker's default is 1e-3.
PAPER_GAP = 0.05
TRIALS = 30
TRIALS_QUICK = 3

#: The paper's Table 3 (norm of the residuals; optimal, bundle, linear), its condition numbers and
#: branch-and-bound iterations (gap 5 %) for its three conics.
PAPER_TABLE3 = ((39.5, 39.5, 1190.0), (5.00, 5.00, 160.0), (15.3, 15.3, 2660.0))
PAPER_CONDITION = {"optimal": (1.2e-3, 3.7e-7, 8.8e-6), "linear": (3.7e-4, 4.1e-5, 1.1e-4)}
PAPER_ITERATIONS = (3, 6, 14)


@dataclass
class DiscScene:
    """Cameras (v, 3, 4), the true dual quadric (4, 4) of a disc, the noisy outline points (v, 63, 2),
    the image conics fitted to them (v, 3, 3) and their residual covariances (v, 5, 5)."""

    cameras: np.ndarray
    dual: np.ndarray
    points: np.ndarray
    conics: np.ndarray
    covariances: np.ndarray


def _look_at(centre: np.ndarray, target: np.ndarray, roll: float) -> np.ndarray:
    z = (target - centre) / np.linalg.norm(target - centre)
    x = np.cross([0.0, 1.0, 0.0], z)
    x /= np.linalg.norm(x)
    c, s = math.cos(roll), math.sin(roll)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]]) @ np.stack([x, np.cross(z, x), z])


def ellipse_points(conic: np.ndarray, n: int, phase: float = 0.0) -> np.ndarray:
    """``n`` points (n, 2) evenly spaced in angle on the real ellipse ``x^T conic x = 0`` (pixels)."""
    M, b, f = conic[:2, :2], conic[:2, 2], conic[2, 2]
    centre = -np.linalg.solve(M, b)
    w, V = np.linalg.eigh(M / -(f + b @ centre))
    t = phase + np.linspace(0.0, 2.0 * np.pi, n, endpoint=False)
    return centre + (V @ np.stack([np.cos(t) / np.sqrt(w[0]), np.sin(t) / np.sqrt(w[1])])).T


def disc_scene(seed: int, views: int = VIEWS, sigma: float = SIGMA_PX) -> DiscScene:
    """A seeded disc and its fitted image conics (module docs)."""
    rng = np.random.default_rng([seed, 2008])
    K = np.array([[FOCAL_PX, 0.0, IMAGE_SIZE / 2], [0.0, FOCAL_PX, IMAGE_SIZE / 2], [0.0, 0.0, 1.0]])
    centre = rng.uniform(-0.5, 0.5, 3)
    axes, _ = np.linalg.qr(rng.normal(size=(3, 3)))
    semi = np.array([rng.uniform(0.8, 1.5), rng.uniform(0.4, 0.8), 0.0])
    H = np.eye(4)
    H[:3, :3], H[:3, 3] = axes, centre
    dual = H @ np.diag([*(semi**2), -1.0]) @ H.T
    cameras, noisy, conics, covariances = [], [], [], []
    while len(cameras) < views:
        direction = rng.normal(size=3)
        direction /= np.linalg.norm(direction)
        if abs(direction @ axes[:, 2]) < 0.5:  # more than 60° from the normal: too oblique
            continue
        eye = centre + rng.uniform(6.0, 10.0) * direction
        R = _look_at(eye, centre + rng.normal(0.0, 0.2, 3), rng.uniform(-0.3, 0.3))
        P = K @ np.hstack([R, (-R @ eye)[:, None]])
        points = ellipse_points(np.linalg.inv(P @ dual @ P.T), POINTS_PER_CONIC, rng.uniform(0, 2 * np.pi))
        points = points + rng.normal(0.0, sigma, points.shape)
        fit = pluecker.fit_conic(points, sigma=sigma)
        cameras.append(P)
        noisy.append(points)
        conics.append(np.asarray(fit.conic))
        covariances.append(np.asarray(fit.covariance))
    return DiscScene(np.array(cameras), dual, np.array(noisy), np.array(conics), np.array(covariances))


def condition(Q: np.ndarray) -> float:
    """Least over largest singular value of a 4x4 matrix (0 for the rank-3 dual of a disc)."""
    s = np.linalg.svd(Q, compute_uv=False)
    return float(s[-1] / s[0])


def run_conics(trials: int, seed: int) -> list[dict[str, Any]]:
    """Every method on ``trials`` disc scenes: per scene and method, the residual norm, condition number,
    status, certificate, nodes and core time. Each method solves all scenes in one parallel batch
    (``pluecker.triangulate_quadrics`` with each scene's own cameras: each scene as
    ``triangulate_quadric``); ``wall_seconds`` is the batch's wall time over the number of scenes."""
    scenes = [disc_scene(seed * 100_003 + k) for k in range(trials)]
    P = np.array([s.cameras for s in scenes]).reshape(trials, VIEWS, 3, 4)
    conics = np.array([s.conics for s in scenes]).reshape(trials, VIEWS, 3, 3)
    covariances = np.array([s.covariances for s in scenes]).reshape(trials, VIEWS, 5, 5)
    runs: list[dict[str, Any]] = [{} for _ in scenes]
    for key, method, gap in (*((m, m, None) for m in METHODS), ("optimal_paper_gap", "optimal", PAPER_GAP)):
        start = time.perf_counter()
        batch = pluecker.triangulate_quadrics(P, conics, covariances=covariances, options=triangulation_options(method, gap))
        wall = (time.perf_counter() - start) / max(trials, 1)
        rejected = [m for m in batch.messages if m]
        if rejected:
            raise RuntimeError(f"{len(rejected)} disc scene(s) rejected, first: {rejected[0]}")
        for k, row in enumerate(runs):
            cost = float(batch.cost[k])
            row[key] = {"cost": cost, "residual_norm": math.sqrt(cost), "condition": condition(batch.Q[k]),
                        "status": str(batch.status[k]), "certified": bool(batch.certified[k]),
                        "certificate": str(batch.certificate[k]), "nodes": int(batch.nodes[k]),
                        "seconds": float(batch.time_seconds[k]), "wall_seconds": wall,
                        "lower_bound": float(batch.lower_bound[k])}
    return runs


def table3(runs: list[dict[str, Any]]) -> str:
    headers = ["conic #", *(METHOD_LABELS[m] for m in METHODS), "paper: Optimal", "paper: Bundle", "paper: Linear"]
    rows = [[str(k + 1), *(f"{run[m]['residual_norm']:.3g}" for m in METHODS), *(f"{v:g}" for v in paper)]
            for k, (run, paper) in enumerate(zip(runs[:3], PAPER_TABLE3))]
    return markdown_table(headers, rows)


def condition_table(runs: list[dict[str, Any]]) -> str:
    headers = ["conic #", *(f"{METHOD_LABELS[m]}" for m in METHODS), "paper: Optimal", "paper: Linear",
               "nodes (gap 1e-3)", f"nodes (gap {PAPER_GAP:g})", "paper: iterations (gap 5 %)"]
    rows = [[str(k + 1), *(f"{run[m]['condition']:.2g}" for m in METHODS), f"{PAPER_CONDITION['optimal'][k]:.2g}",
             f"{PAPER_CONDITION['linear'][k]:.2g}", _nodes(run["optimal"]), _nodes(run["optimal_paper_gap"]),
             str(PAPER_ITERATIONS[k])] for k, run in enumerate(runs[:3])]
    return markdown_table(headers, rows)


def _nodes(cell: dict[str, Any]) -> str:
    return f"{cell['nodes']}" + ("" if cell["certified"] else " (not closed)")


def summary(runs: list[dict[str, Any]]) -> dict[str, Any]:
    out: dict[str, Any] = {"scenes": len(runs)}
    for m in (*METHODS, "optimal_paper_gap"):
        cells = [run[m] for run in runs]
        out[m] = {
            "median_residual_norm": float(np.median([c["residual_norm"] for c in cells])),
            "median_condition": float(np.median([c["condition"] for c in cells])),
            "statuses": {s: sum(c["status"] == s for c in cells) for s in sorted({c["status"] for c in cells})},
            "certified": int(sum(c["certified"] for c in cells)),
            "by_convexity_test": int(sum(c["certified"] and c["certificate"] == "convexity_test" for c in cells)),
            "mean_nodes": float(np.mean([c["nodes"] for c in cells])),
            "max_nodes": int(max(c["nodes"] for c in cells)),
            "median_core_ms": float(np.median([c["seconds"] for c in cells]) * 1e3),
            "max_core_ms": float(max(c["seconds"] for c in cells) * 1e3),
        }
    optimal = np.array([run["optimal"]["cost"] for run in runs])
    local = np.array([run["local"]["cost"] for run in runs])
    linear = np.array([run["linear"]["cost"] for run in runs])
    out["local_above_optimal"] = int(np.sum(local > optimal * (1 + 1e-6) + 1e-12))
    out["median_linear_over_optimal"] = float(np.median(linear / optimal))
    out["first_three"] = runs[:3]
    return out


def statistics_table(s: dict[str, Any]) -> str:
    headers = ["method", "median ‖L r‖", "median condition", "statuses", "certified", "by convexity test / B&B",
               "mean / max nodes", "median / max ms"]
    labels = {**METHOD_LABELS, "optimal_paper_gap": f"Optimal, gap {PAPER_GAP:g} (paper)"}
    rows = [[labels[m], f"{s[m]['median_residual_norm']:.3g}", f"{s[m]['median_condition']:.2g}",
             ", ".join(f"{k} {v}" for k, v in s[m]["statuses"].items()), f"{s[m]['certified']}/{s['scenes']}",
             f"{s[m]['by_convexity_test']} / {s[m]['certified'] - s[m]['by_convexity_test']}" if m.startswith("optimal") else "",
             f"{s[m]['mean_nodes']:.1f} / {s[m]['max_nodes']}", f"{s[m]['median_core_ms']:.2f} / {s[m]['max_core_ms']:.1f}"]
            for m in (*METHODS, "optimal_paper_gap")]
    return markdown_table(headers, rows)


def figure7(seed: int, out) -> Any:
    """The paper's Figure 7 for the first scene: in its first view, the noisy outline points, the true
    conic and the reprojections of the optimal and linear quadrics."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    scene = disc_scene(seed * 100_003)
    P = scene.cameras[0]
    # The figure takes the outline's aspect (equal axes): a square one leaves half of it blank.
    extent = np.ptp(scene.points[0], axis=0)
    fig, ax = plt.subplots(figsize=(7, min(7.0, max(2.5, 7 * extent[1] / extent[0])) + 1.2), constrained_layout=True)
    ax.plot(*scene.points[0].T, ".", color="0.5", markersize=3, label=f"{POINTS_PER_CONIC} noisy points ({SIGMA_PX:g} px)")
    styles = {"truth": ("black", "-"), "optimal": ("tab:green", "--"), "linear": ("tab:red", ":")}
    for name, (colour, style) in styles.items():
        Q = scene.dual if name == "truth" else np.asarray(
            pluecker.triangulate_quadric(scene.cameras, scene.conics, scene.covariances,
                                         options=pluecker.TriangulationOptions(method=name)).Q)
        curve = ellipse_points(np.linalg.inv(P @ Q @ P.T), 400)
        ax.plot(*np.vstack([curve, curve[:1]]).T, style, color=colour, lw=1.2, label=name if name == "truth" else
                f"{name} quadric, reprojected")
    ax.set_aspect("equal")
    ax.invert_yaxis()
    ax.set_xlabel("u (px)")
    ax.set_ylabel("v (px)")
    ax.legend(fontsize="small", loc="center")
    ax.set_title(f"Figure 7 (synthetic): conic #1, view 1 of {VIEWS}", fontsize="small")
    path = out / "figure7_conic_reprojection.png"
    fig.savefig(path, dpi=100)
    plt.close(fig)
    return path
