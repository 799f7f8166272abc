"""Table 2 of Josephson & Kahl 2008: lines of Model House and Corridor, frames 0-3, three methods.

The data hold image segments, not the edge points the paper fitted its lines to, so each view's line is
the line through the segment's endpoints and its covariance is that of endpoints with i.i.d. Gaussian
noise of ``SIGMA_PX`` = 1 px per coordinate (``pluecker.fit_line`` on the two endpoints; the
``segments`` form of ``pluecker.triangulate_lines``). Every line seen in at least two of frames 0-3 is
triangulated by each method, all lines of a sequence in one parallel batch. Two errors per observation: the whitened residual norm ``‖L r‖`` of eq. 18
(what eq. 19 sums, squared; the quantity closest to the paper's) and the pixel distances of the observed
segment's endpoints from the reprojected line.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from typing import Any

import numpy as np

import pluecker
from pluecker.datasets import load_vgg, vgg_root

from .common import FRAMES, LABELS, METHOD_LABELS, METHODS, counts, markdown_table, triangulation_options

SIGMA_PX = 1.0
#: The distance of an observed line from its frame origin, pixels (pluecker's section 3.1 normalisation).
FRAME_DISTANCE = 1000.0
#: The paper's branch-and-bound stopping gap for lines ("less than 10 %"); pluecker's default is 1e-3.
PAPER_GAP = 0.10
#: Lines per sequence with ``--quick`` (the paper itself reports node counts on 12 lines per sequence).
QUICK_LINES = 6

#: The paper's Table 2: (mean, std) of its line reprojection errors.
PAPER_TABLE2 = {
    "model_house": {"optimal": (1.40, 0.92), "local": (1.41, 0.93), "linear": (1.62, 1.03)},
    "corridor": {"optimal": (3.42, 4.29), "local": (3.30, 4.34), "linear": (4.02, 5.45)},
}


def residual(observed: np.ndarray, candidate: np.ndarray) -> np.ndarray:
    """The 2-entry residual (pixels) of a candidate image line in the frame of an observed one: the
    observed line gets the unit normal ``n`` and offset ``c0 <= 0``, the frame origin
    ``o = (D - c0) n``, and ``r = D (D (a, b) / c' - n)`` with ``c' = c + (a, b)·o``."""
    scale = np.hypot(observed[0], observed[1])
    n, c0 = observed[:2] / scale, observed[2] / scale
    if c0 > 0:
        n, c0 = -n, -c0
    shifted = candidate[2] + candidate[:2] @ ((FRAME_DISTANCE - c0) * n)
    return FRAME_DISTANCE * (FRAME_DISTANCE * candidate[:2] / shifted - n)


def image_line(P: np.ndarray, point: np.ndarray, direction: np.ndarray) -> np.ndarray:
    """The homogeneous image line of the 3-D line ``point + s direction`` in camera ``P``."""
    return np.cross(P @ np.append(point, 1.0), P @ np.append(point + direction, 1.0))


@dataclass
class LineRun:
    """One method on one sequence."""

    whitened: np.ndarray  # (observations,) ‖L r‖
    endpoint_px: np.ndarray  # (2 × observations,) pixel distances of the observed endpoints
    cost: np.ndarray  # (lines,) eq. 19 as reported
    recomputed_cost: np.ndarray  # (lines,) Σ ‖L r‖² computed here
    certified: np.ndarray
    certificate: np.ndarray
    nodes: np.ndarray
    status: np.ndarray
    core_seconds: np.ndarray
    wall_seconds: float

    def stats(self) -> dict[str, Any]:
        return {
            "lines": int(len(self.cost)),
            "observations": int(len(self.whitened)),
            "whitened_mean": float(np.mean(self.whitened)),
            "whitened_std": float(np.std(self.whitened)),
            "endpoint_mean_px": float(np.mean(self.endpoint_px)),
            "endpoint_std_px": float(np.std(self.endpoint_px)),
            "total_cost": float(np.sum(self.cost)),
            "max_cost_mismatch": float(np.max(np.abs(self.cost - self.recomputed_cost) / np.maximum(self.cost, 1e-300))),
            "certified": int(np.sum(self.certified)),
            "certificates": counts(self.certificate),
            "statuses": counts(self.status),
            "mean_nodes": float(np.mean(self.nodes)),
            "max_nodes": int(np.max(self.nodes)),
            "median_core_ms": float(np.median(self.core_seconds) * 1e3),
            "max_core_ms": float(np.max(self.core_seconds) * 1e3),
            "wall_seconds": self.wall_seconds,
        }


def line_data(sequence: str, limit: int | None = None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Cameras (4, 3, 4) of frames 0-3, and the segments (m, 4, 2, 2) and visibility (m, 4) of every line
    seen in at least two of them (the first ``limit`` of them)."""
    seq = load_vgg(vgg_root() / sequence)
    segments, visible = seq.line_observations(list(FRAMES))
    keep = np.flatnonzero(visible.sum(axis=1) >= 2)[:limit]
    return seq.cameras[list(FRAMES)], segments[keep], visible[keep]


def run_lines(sequence: str, method: str, limit: int | None = None, gap: float | None = None) -> LineRun:
    """``method`` on the lines of ``sequence``, all in one parallel batch (``pluecker.triangulate_lines``:
    each line as ``triangulate_line`` on its visible views); ``gap`` is the optimal method's
    ``max_relative_gap`` (None: pluecker's default). ``wall_seconds`` is the batch's wall time."""
    cameras, segments, visible = line_data(sequence, limit)
    whitened, endpoints, recomputed = [], [], []
    start = time.perf_counter()
    batch = pluecker.triangulate_lines(cameras, segments, visible, sigma=SIGMA_PX, options=triangulation_options(method, gap))
    wall = time.perf_counter() - start
    rejected = [m for m in batch.messages if m]
    if rejected:
        raise RuntimeError(f"{sequence}: {len(rejected)} line(s) rejected, first: {rejected[0]}")
    for point, direction, seg, seen in zip(batch.point, batch.direction, segments, visible):
        total = 0.0
        for P, s in zip(cameras[seen], seg[seen]):
            fit = pluecker.fit_line(s, sigma=SIGMA_PX)
            reprojected = image_line(P, point, direction)
            res = residual(np.asarray(fit.line), reprojected)
            w = float(res @ np.linalg.solve(np.asarray(fit.covariance), res))
            total += w
            whitened.append(np.sqrt(w))
            endpoints += list(np.abs(np.c_[s, np.ones(2)] @ reprojected) / np.hypot(*reprojected[:2]))
        recomputed.append(total)
    return LineRun(np.array(whitened), np.array(endpoints), batch.cost, np.array(recomputed), batch.certified,
                   batch.certificate, batch.nodes, batch.status, batch.time_seconds, wall)


def table2(lines: dict[str, dict[str, LineRun]]) -> str:
    headers = ["data set", "lines", *(f"{METHOD_LABELS[m]} {s}" for m in METHODS for s in ("mean", "std"))]
    rows = []
    for sequence, runs in lines.items():
        n = str(runs["optimal"].stats()["lines"])
        whitened = [f"{v:.3f}" for m in METHODS for v in (runs[m].stats()["whitened_mean"], runs[m].stats()["whitened_std"])]
        endpoint = [f"{v:.3f}" for m in METHODS
                    for v in (runs[m].stats()["endpoint_mean_px"], runs[m].stats()["endpoint_std_px"])]
        paper = [f"{v:.2f}" for m in METHODS for v in PAPER_TABLE2[sequence][m]]
        rows += [[f"{LABELS[sequence]}, ‖L r‖ (pluecker)", n, *whitened],
                 [f"{LABELS[sequence]}, endpoint distance px (pluecker)", n, *endpoint],
                 [f"{LABELS[sequence]} (paper)", "12 tested", *paper]]
    return markdown_table(headers, rows)


def certificate_table(lines: dict[str, dict[str, LineRun]]) -> str:
    headers = ["data set", "gap", "lines", "certified", "by Taylor / relaxation B&B", "gap not closed", "mean nodes",
               "max nodes", "median ms/line", "max ms/line"]
    rows = []
    for sequence, runs in lines.items():
        for key, gap in (("optimal", "1e-3"), ("optimal_paper_gap", f"{PAPER_GAP:g} (paper)")):
            s = runs[key].stats()
            rows.append([LABELS[sequence], gap, str(s["lines"]), f"{s['certified']} ({100 * s['certified'] / s['lines']:.0f} %)",
                         f'{s["certificates"].get("taylor_branch_and_bound", 0)} / {s["certificates"].get("branch_and_bound", 0)}',
                         str(s["statuses"].get("gap_not_closed", 0)),
                         f"{s['mean_nodes']:.1f}", str(s["max_nodes"]), f"{s['median_core_ms']:.2f}",
                         f"{s['max_core_ms']:.1f}"])
    return markdown_table(headers, rows)


def summary(lines: dict[str, dict[str, LineRun]]) -> dict[str, Any]:
    return {sequence: {**{m: runs[m].stats() for m in (*METHODS, "optimal_paper_gap")}, "paper": PAPER_TABLE2[sequence]}
            for sequence, runs in lines.items()}
