"""Is the certificate of a rig's pose sound, and how often and how fast does it certify? A benchmark of
``pluecker.estimate_pose(rig, ..., options=PoseOptions(certify=CertifyOptions()))`` on rigs of several
pinhole cameras, with an independent attack on every certified bound.

**Scenes** (``compare_rig_pose.Scene``, imported, not copied): rigs of 2, 4 and 6 pinhole cameras on a ring
of radius 0.3 looking outwards (f = 500-1000 px across the ring, 640 x 480), the body at a uniform random
pose; points 3-9 units in front of the camera that sees them, spread evenly over the cameras (observation
``i`` in camera ``i mod k``, segments likewise); each segment's two object endpoints drawn the same way in
one camera; i.i.d. Gaussian noise of 1 px on every pixel and segment endpoint. Scene ``i`` of every row is
``Scene(..., seed=--seed + i)``. Rows per rig: 10 points, 100 points, 50 points + 50 segments, 5 points +
5 segments; and for 2 cameras, 100 points with every focal length 250 px (a 104° x 88° field of view on the
same 640 x 480 image) and 15000 px (2.4° x 1.8°: the narrow field of view), the same pixel draws as the
ring's scenes (``FocalScene``). Two control rows of a one-camera rig (10 points; 5 points + 5 segments),
which the library certifies through its single-camera certificate, exercise the attack on live
certificates; they are left out of the rate and time targets.

**Measured** per scene: one ``estimate_pose`` call with ``certify=CertifyOptions()`` (its defaults:
``max_relative_gap`` 1e-3, ``max_nodes`` None), timed from Python (``time.perf_counter``, one cold call);
``certified``, ``status``, ``cost``, the certificate's ``lower_bound``, ``raw_lower_bound``,
``relative_gap`` and ``nodes`` (all in Σ r², the unit of ``result.cost``), and
``details.uncertified_reason`` (up to its first ``;``, numbers shown as ``#``, for the histogram). Per row:
the certified fraction, median / p99 / max time in ms, the median and max nodes, the statuses and the
most frequent uncertified reasons.

**The attack** (this script's own numpy code, never the library's residuals): the cost of a body pose
``rig_from_world = (R, t)`` is Σ over the cameras of the squared reprojection errors in that camera's
pixels at ``sensor_from_world = sensor_from_rig[k] ∘ (R, t)`` (``x = R_k (R X + t) + t_k``,
``u = K_k x / z``): two squared pixel residuals per point, and per segment the squared distances of its two
observed endpoints to the image line through the projections of its two object endpoints (the projected
3-D line: a straight line through a pinhole), the definition of ``result.cost`` in docs/pose.md. A pose
counts only when every point and every segment's two object endpoints are in front of the camera that saw
them (``z > 0``), the certificate's domain. The local search is Levenberg-Marquardt on
``(exp(ω) R, t + δ)`` with analytic Jacobians (checked against central differences by the self-test); once
in the domain it takes no step out of it, and the least valid cost met on any path is the attack's result.
Starts: the true pose; the library's answer; ``--starts`` uniform random rotations (``random_rotation``),
each with the translation solved by linear least squares at that rotation (each observed ray through its
point, each observed segment's interpretation plane through its object endpoints), which first descend a
cost on each camera's unit sphere (``ray_residuals``: chordal ray errors, large behind the camera, so that
a start outside the domain walks into it) and then the pixel cost; and ``--perturbations`` perturbations
of the answer (rotation 0.02 / 0.1 / 0.3 rad about a random axis, translation re-solved or moved by up to
30 % of the mean depth). Every certified scene is attacked, and the first ``--attack-uncertified``
uncertified scenes of each row (there the attack checks the own cost and the proved bound, if any).

A **violation** is a valid pose of a certified scene whose own cost is below
``raw_lower_bound · (1 − 1e-9)``, the bound as proved. ``lower_bound`` is that bound capped at the
answer's cost, so a pose below ``lower_bound`` is below ``raw_lower_bound`` too; the converse differs only
where ``raw_lower_bound`` exceeds the answer's own cost, itself a valid pose: then the answer is the
violation, which the check against ``lower_bound`` alone would miss. Those below ``lower_bound ·
(1 − 1e-9)`` as well are counted apart (``violations_below_lower_bound`` in the JSON). The proved bound
of an uncertified answer (a certificate that did not close its gap) is checked the same way and reported
apart. **Own-cost check**:
``own cost of the library's pose / result.cost − 1`` on every scene whose answer is in the domain: ~1e-12
means this script reads the library's cost convention as the library does. The self-test (first scene of
each row) checks the vectorised residuals against a plain loop over ``compare_rig_pose.Scene._pixel``
and the Jacobians against central differences.

**Columns** of the Markdown table: ``certified`` fraction; ``med / p99 / max ms`` of the certify call;
``nodes med / max`` of the certificates that exist; ``attacked cert / uncert``: scenes attacked;
``reach``: the fraction of random starts that ended at the answer's own cost (within 1e-6 relative: the
attack's basin reaches the library's minimum; low reach means a rugged cost, not a fault);
``violations``; ``least margin``: the least ``attack best / raw_lower_bound − 1`` over the certified
scenes (≥ −1e-9 is sound; the certified gap is at most ``max_relative_gap`` = 1e-3, so margins are
about 0-1e-3); ``own/cost−1 cert`` and ``all``: the largest ``|own cost / result.cost − 1|`` over the
certified scenes and over all; ``attack < answer``: attacked scenes where the attack found a valid pose
cheaper than the answer by more than 1e-9 relative (with the largest relative drop; on a certified
scene it cannot exceed the gap without a violation); ``status``: histogram. After the table: the three
most frequent uncertified reasons per row.

**Targets** (PASS/FAIL lines; rows of 2-6 cameras): (1) certified ≥ 99 % on the rows with 100
correspondences; (2) ≥ 95 % on the rows with 10; (3) median time of the certify call (certified or
not) ≤ 2 ms on the rows with 100 correspondences; (4) no violation
(every row, controls included); (5) own cost = ``result.cost`` to 1e-10 relative on every scene with a
valid answer.

Results go to ``--out`` (default ``bench/out/certify_rig_pose.json``: every row and every scene's
numbers); the Markdown table and the PASS/FAIL lines to standard output, progress to standard error. Run
from the repository root with the venv (numpy only: the local search is this script's own, no scipy):

    .venv/bin/python bench/certify_rig_pose.py --quick    # 15 scenes per row, 12 + 6 starts
    .venv/bin/python bench/certify_rig_pose.py            # 100 scenes per row, 40 + 12 starts
    .venv/bin/python bench/certify_rig_pose.py --rows 2cam --scenes 50 --seed 1000
    .venv/bin/python bench/certify_rig_pose.py --list-rows

A start costs 10-25 ms (2 cores, shared); every certified scene is attacked: about 1 minute with
``--quick`` and about an hour for the full run on a loaded machine (0.6-1.3 s of attack a scene with
40 + 12 starts).
"""

from __future__ import annotations

import argparse
import datetime
import json
import math
import platform
import re
import sys
import time
import zlib
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

import pluecker  # noqa: E402
from compare_pose import _finite_or_none  # noqa: E402
from compare_rig_pose import SIGMA_PX, Scene, exp_so3, random_rotation, rotation_error  # noqa: E402

OUT = Path(__file__).resolve().parent / "out" / "certify_rig_pose.json"
QUICK_SCENES, FULL_SCENES = 15, 100
QUICK_STARTS, FULL_STARTS = 12, 40
QUICK_PERTURBATIONS, FULL_PERTURBATIONS = 6, 12
QUICK_ATTACK_UNCERTIFIED, FULL_ATTACK_UNCERTIFIED = 3, 10
VIOLATION_REL = 1e-9
COST_CHECK_TOL = 1e-10
CERT_TARGET = {100: 0.99, 10: 0.95}
TIME_TARGET_MS = 2.0
PERTURBATION_ANGLES = (0.02, 0.1, 0.3)  # rad, cycled over the perturbation starts
LM_MAX_ITERATIONS = 100


@dataclass(frozen=True)
class Row:
    name: str
    cameras: int
    points: int
    segments: int
    focal: float | None = None  # None: the ring's 500-1000 px
    control: bool = False

    @property
    def correspondences(self) -> int:
        return self.points + self.segments


def all_rows() -> list[Row]:
    rows = [Row("control-1cam-10p", 1, 10, 0, control=True), Row("control-1cam-5p5l", 1, 5, 5, control=True)]
    for k in (2, 4, 6):
        rows += [Row(f"{k}cam-10p", k, 10, 0), Row(f"{k}cam-100p", k, 100, 0)]
        rows += [Row(f"{k}cam-50p50l", k, 50, 50), Row(f"{k}cam-5p5l", k, 5, 5)]
    rows += [Row("2cam-f250-100p", 2, 100, 0, focal=250.0), Row("2cam-f15000-100p", 2, 100, 0, focal=15000.0)]
    return rows


class FocalScene(Scene):
    """``compare_rig_pose.Scene`` with every camera's focal length ``focal`` px (principal point and image
    as there; ``None``: the ring's own). ``Scene.__init__`` sets ``self.Ks`` from ``ring()`` before it draws
    anything; the property below rewrites the focal lengths at that assignment, so every draw (the same
    random numbers, pixels and depths as the ring's scene of that seed) sees the new intrinsics."""

    def __init__(self, cameras: int, points: int, segments: int, seed: int, focal: float | None) -> None:
        self.focal = focal
        super().__init__(cameras, points, segments, 0.0, seed)

    @property
    def Ks(self) -> list[np.ndarray]:  # noqa: N802 - the base class's attribute name
        return self._Ks

    @Ks.setter
    def Ks(self, value: list[np.ndarray]) -> None:  # noqa: N802
        value = [np.array(K, dtype=float) for K in value]
        if self.focal is not None:
            for K in value:
                K[0, 0] = K[1, 1] = self.focal
        self._Ks = value


# --------------------------------------------------------------------------------------------------
# This script's own cost


class RigCost:
    """The rig's reprojection cost Σ r² (px²) at a body pose ``(R, t)``, its residuals and their Jacobian
    in the tangent ``(exp(ω) R, t + δ)``; numpy only. Per observation ``M = K_k R_k`` and ``c = K_k t_k``,
    so that ``y = M (R X + t) + c`` is the homogeneous pixel and ``y_z`` the depth in camera ``k``."""

    def __init__(self, s: Scene) -> None:
        K = np.array(s.Ks)
        Rk = np.array([p[0] for p in s.sensor])
        tk = np.array([p[1] for p in s.sensor])
        M = K @ Rk  # (k, 3, 3)
        c = np.einsum("kij,kj->ki", K, tk)
        pc = np.asarray(s.point_cameras, dtype=int)
        lc = np.asarray(s.line_cameras, dtype=int)
        self.X = np.asarray(s.X, dtype=float).reshape(-1, 3)
        self.u = np.asarray(s.x, dtype=float).reshape(-1, 2)
        self.Mp, self.cp = M[pc], c[pc]
        self.L = np.asarray(s.L, dtype=float).reshape(-1, 2, 3)
        ends = np.asarray(s.l2, dtype=float).reshape(-1, 2, 2)
        self.e = np.concatenate([ends, np.ones((len(ends), 2, 1))], axis=2)  # (m, 2, 3) homogeneous
        self.Ml, self.cl = M[lc], c[lc]
        # for the linear translation: unit rays / interpretation-plane normals in each camera's frame
        Kinv = np.linalg.inv(K)
        self.Rp, self.tp = Rk[pc], tk[pc]
        self.Rl, self.tl = Rk[lc], tk[lc]
        rays = np.einsum("nij,nj->ni", Kinv[pc], np.column_stack([self.u, np.ones(len(self.u))]))
        self.rays = rays / np.linalg.norm(rays, axis=1, keepdims=True)
        if len(self.L):
            m = np.einsum("mij,mkj->mki", Kinv[lc], self.e)
            n = _cross(m[:, 0], m[:, 1])
            self.normals = n / np.linalg.norm(n, axis=1, keepdims=True)
        else:
            self.normals = np.zeros((0, 3))

    def _project(self, R: np.ndarray, t: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """Rotated points ``R X`` and homogeneous pixels ``y`` of the points (n, 3) and endpoints (m, 2, 3)."""
        RX = self.X @ R.T
        y = np.einsum("nij,nj->ni", self.Mp, RX + t) + self.cp
        RL = self.L @ R.T
        yl = np.einsum("mij,mkj->mki", self.Ml, RL + t) + self.cl[:, None, :]
        return RX, y, RL, yl

    def valid(self, R: np.ndarray, t: np.ndarray) -> bool:
        _, y, _, yl = self._project(R, t)
        return bool(np.all(y[:, 2] > 0) and np.all(yl[..., 2] > 0))

    def residuals(self, R: np.ndarray, t: np.ndarray, jacobian: bool = False) -> tuple[np.ndarray, Any, bool]:
        """(residuals: points' (du, dv) then each segment's two endpoint distances, Jacobian (r, 6) or None,
        every depth > 0)."""
        RX, y, RL, yl = self._project(R, t)
        z = y[:, 2]
        rp = (y[:, :2] / z[:, None] - self.u).ravel()
        ya, yb = yl[:, 0], yl[:, 1]
        line = _cross(ya, yb)  # the projected line, homogeneous pixel coordinates
        rho = np.linalg.norm(line[:, :2], axis=1)
        dot = np.einsum("mkj,mj->mk", self.e, line)  # (m, 2)
        rl = (dot / rho[:, None]).ravel()
        ok = bool(np.all(z > 0) and np.all(yl[..., 2] > 0))
        r = np.concatenate([rp, rl])
        if not jacobian:
            return r, None, ok
        # points: du/dξ = du/dy · M · [-[RX]x, I]; the rows of du/dy · M are a = (M_i − u_i M_2) / z, and
        # a · (-[RX]x) = RX × a
        uv = y[:, :2] / z[:, None]
        A = (self.Mp[:, :2, :] - uv[:, :, None] * self.Mp[:, None, 2, :]) / z[:, None, None]  # (n, 2, 3)
        Jp = np.concatenate([_cross(RX[:, None, :], A), A], axis=2).reshape(-1, 6)
        # segments: r = ẽ·ℓ / |ℓ_xy|, ℓ = ya × yb, dy_end/dξ = M [-[R X_end]x, I]; with w = dr/dℓ,
        # w · dℓ = -(w × yb) · dya + (w × ya) · dyb
        Jl = np.zeros((0, 6))
        if len(rho):
            lxy = np.zeros_like(line)
            lxy[:, :2] = line[:, :2]
            w = self.e / rho[:, None, None] - dot[:, :, None] * lxy[:, None, :] / rho[:, None, None] ** 3  # (m, 2, 3)
            ga = np.einsum("mki,mij->mkj", -_cross(w, yb[:, None, :]), self.Ml)
            gb = np.einsum("mki,mij->mkj", _cross(w, ya[:, None, :]), self.Ml)
            rot = _cross(RL[:, None, 0, :], ga) + _cross(RL[:, None, 1, :], gb)
            Jl = np.concatenate([rot, ga + gb], axis=2).reshape(-1, 6)
        return r, np.concatenate([Jp, Jl]), ok

    def ray_residuals(self, R: np.ndarray, t: np.ndarray, jacobian: bool = False) -> tuple[np.ndarray, Any, bool]:
        """The first phase of a far start: residuals on the unit sphere of each camera, smooth everywhere and
        large behind a camera, so that a start outside the domain walks into it. Per point the chordal
        ``q/|q| − ray`` (3), per segment endpoint ``n · q/|q|`` (the sine of its angle to the observed
        interpretation plane) and the hinge ``min(0, q_z/|q|)``; ``q`` in the camera's frame. Scaled by
        1000 (about pixels at f = 1000 px). Same return as ``residuals``."""
        RX = self.X @ R.T
        q = np.einsum("nij,nj->ni", self.Rp, RX + t) + self.tp
        nq = np.linalg.norm(q, axis=1)
        qh = q / nq[:, None]
        RL = self.L @ R.T
        ql = np.einsum("mij,mkj->mki", self.Rl, RL + t) + self.tl[:, None, :]
        nql = np.linalg.norm(ql, axis=2)
        qlh = ql / nql[..., None]
        plane = np.einsum("mkj,mj->mk", qlh, self.normals)
        hinge = np.minimum(0.0, qlh[..., 2])
        r = 1e3 * np.concatenate([(qh - self.rays).ravel(), np.stack([plane, hinge], axis=2).ravel()])
        ok = bool(np.all(q[:, 2] > 0) and np.all(ql[..., 2] > 0))
        if not jacobian:
            return r, None, ok
        # d q̂ = (I − q̂ q̂ᵀ) / |q| · R_k · [-[RX]x, I] dξ; a row a of the first two factors gives RX × a
        A = (self.Rp - qh[:, :, None] * np.einsum("ni,nij->nj", qh, self.Rp)[:, None, :]) / nq[:, None, None]
        Jp = np.concatenate([_cross(RX[:, None, :], A), A], axis=2).reshape(-1, 6)
        Jl = np.zeros((0, 6))
        if len(self.L):
            proj = np.einsum("mki,mij->mkj", qlh, self.Rl)  # q̂ᵀ R_k, (m, 2, 3)
            Al = (self.Rl[:, None] - qlh[..., :, None] * proj[..., None, :]) / nql[..., None, None]  # (m, 2, 3, 3)
            dqh = np.concatenate([_cross(RL[:, :, None, :], Al), Al], axis=3)  # (m, 2, 3, 6)
            dplane = np.einsum("mj,mkjc->mkc", self.normals, dqh)
            dhinge = np.where((qlh[..., 2] < 0)[..., None], dqh[..., 2, :], 0.0)
            Jl = np.stack([dplane, dhinge], axis=2).reshape(-1, 6)
        return r, 1e3 * np.concatenate([Jp, Jl]), ok

    def cost(self, R: np.ndarray, t: np.ndarray) -> tuple[float, bool]:
        """(Σ r², every depth > 0): the cost whatever the depths, and whether the pose is in the domain."""
        r, _, ok = self.residuals(R, t)
        return float(r @ r), ok

    def translation_at(self, R: np.ndarray) -> np.ndarray:
        """The linear least-squares translation at rotation ``R``: ``ray × (R_k (R X + t) + t_k) = 0`` per
        point and ``n · (R_k (R X + t) + t_k) = 0`` per segment endpoint (``n`` the observed interpretation
        plane's unit normal in the camera's frame)."""
        S = _skew(self.rays)  # (n, 3, 3)
        A = [(S @ self.Rp).reshape(-1, 3)]
        b = [-np.einsum("nij,nj->ni", S, np.einsum("nij,nj->ni", self.Rp, self.X @ R.T) + self.tp).ravel()]
        if len(self.L):
            nR = np.einsum("mi,mij->mj", self.normals, self.Rl)  # (m, 3): nᵀ R_k
            for k in range(2):
                A.append(nR)
                b.append(
                    -(np.einsum("mj,mj->m", nR, self.L[:, k] @ R.T) + np.einsum("mi,mi->m", self.normals, self.tl))
                )
        return np.linalg.lstsq(np.concatenate(A), np.concatenate(b), rcond=None)[0]


def _cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """a × b over the last axis, broadcast (``np.cross`` without its axis handling: a third of the time)."""
    a0, a1, a2 = a[..., 0], a[..., 1], a[..., 2]
    b0, b1, b2 = b[..., 0], b[..., 1], b[..., 2]
    return np.stack([a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0], axis=-1)


def _skew(v: np.ndarray) -> np.ndarray:
    """[v]x for (…, 3) vectors: (…, 3, 3)."""
    S = np.zeros(v.shape + (3,))
    S[..., 0, 1], S[..., 0, 2] = -v[..., 2], v[..., 1]
    S[..., 1, 0], S[..., 1, 2] = v[..., 2], -v[..., 0]
    S[..., 2, 0], S[..., 2, 1] = -v[..., 1], v[..., 0]
    return S


def local_search(
    f: RigCost, R: np.ndarray, t: np.ndarray, rays_first: bool = False
) -> tuple[float, np.ndarray, np.ndarray]:
    """Levenberg-Marquardt on the pixel cost from ``(R, t)`` (first on ``ray_residuals`` when
    ``rays_first``): (least valid pixel cost met, its R, its t); +inf when no pose on the path was valid."""
    R, t = np.array(R, dtype=float), np.array(t, dtype=float)
    if rays_first:
        _, R, t = levenberg_marquardt(f.ray_residuals, R, t, keep_valid=False)
    return levenberg_marquardt(f.residuals, R, t, keep_valid=True)


def levenberg_marquardt(
    fun: Any, R: np.ndarray, t: np.ndarray, keep_valid: bool
) -> tuple[float, np.ndarray, np.ndarray]:
    """Levenberg-Marquardt on ``fun(R, t, jacobian) -> (r, J, in the domain)`` in the tangent
    ``(exp(ω) R, t + δ)``: (least Σ r² met in the domain, its R, its t), or (+inf, the last pose) when no
    pose on the path was in it. A step is taken when it lowers Σ r² and, with ``keep_valid``, does not
    leave the domain once in it (a start outside the domain may walk into it)."""
    r, J, ok = fun(R, t, jacobian=True)
    cost = float(r @ r)
    best = (cost, R, t) if ok else (math.inf, R, t)
    lam = 1e-3
    for _ in range(LM_MAX_ITERATIONS):
        if not np.all(np.isfinite(J)) or not math.isfinite(cost):
            break
        H, g = J.T @ J, J.T @ r
        improved = False
        while lam < 1e12:
            try:
                step = np.linalg.solve(H + lam * np.diag(np.diag(H) + 1e-12 * np.trace(H)), -g)
            except np.linalg.LinAlgError:
                lam *= 10
                continue
            R1, t1 = exp_so3(step[:3]) @ R, t + step[3:]
            r1, J1, ok1 = fun(R1, t1, jacobian=True)
            cost1 = float(r1 @ r1)
            if math.isfinite(cost1) and cost1 < cost and (ok1 or not ok or not keep_valid):
                improved = True
                break
            lam *= 4
        if not improved:
            break
        done = cost - cost1 <= 1e-15 * cost or np.linalg.norm(step) < 1e-14
        R, t, r, J, ok, cost = R1, t1, r1, J1, ok1, cost1
        lam = max(lam / 3, 1e-12)
        if ok and cost < best[0]:
            best = (cost, R, t)
        if done:
            break
    return best if math.isfinite(best[0]) else (math.inf, R, t)


def attack(
    f: RigCost,
    s: Scene,
    answer: tuple[np.ndarray, np.ndarray] | None,
    starts: int,
    perturbations: int,
    rng: np.random.Generator,
) -> dict[str, Any]:
    """The many-start local search: the least valid own cost found, which start reached it, and how many
    random starts ended within 1e-6 of the answer's own cost (the attack's reach)."""
    depth = max(s.depth, 1.0)
    begin: list[tuple[str, np.ndarray, np.ndarray]] = [("truth", s.R, s.t)]
    if answer is not None:
        begin.append(("answer", *answer))
    for _ in range(starts):
        R0 = random_rotation(rng)
        begin.append(("random", R0, f.translation_at(R0)))
    if answer is not None:
        for j in range(perturbations):
            angle = PERTURBATION_ANGLES[j % len(PERTURBATION_ANGLES)]
            w = rng.standard_normal(3)
            R0 = exp_so3(angle * w / np.linalg.norm(w)) @ answer[0]
            if j % 2 == 0:
                t0 = f.translation_at(R0)
            else:
                t0 = answer[1] + angle * depth * rng.standard_normal(3) / math.sqrt(3)
            begin.append(("perturbed", R0, t0))
    answer_cost = math.inf
    if answer is not None:
        c, ok = f.cost(*answer)
        answer_cost = c if ok else math.inf
    best, best_from, best_pose = math.inf, None, None
    reached = {"random": 0, "perturbed": 0}
    for name, R0, t0 in begin:
        c, R1, t1 = local_search(f, R0, t0, rays_first=name == "random" or not f.valid(R0, t0))
        if name in reached and c <= answer_cost * (1 + 1e-6):
            reached[name] += 1
        if c < best:
            best, best_from, best_pose = c, name, (R1, t1)
    out: dict[str, Any] = {
        "best": best,
        "best_from": best_from,
        "starts": len(begin),
        "random_starts": starts,
        "random_reached_answer": reached["random"],
        "perturbed_reached_answer": reached["perturbed"],
    }
    if best_pose is not None:
        out["best_rotation_error_to_truth_deg"] = math.degrees(rotation_error(best_pose[0], s.R))
    return out


def self_test(f: RigCost, s: Scene, rng: np.random.Generator) -> dict[str, float]:
    """The vectorised residuals against a plain loop over ``Scene._pixel`` (points, and segment endpoints
    to the line through the projected endpoints as ``compare_rig_pose.Scene.residuals`` measures it), and
    the analytic Jacobian against central differences, at a pose near the truth."""
    R = exp_so3(0.05 * rng.standard_normal(3)) @ s.R
    t = s.t + 0.05 * rng.standard_normal(3)
    r = f.residuals(R, t)[0]
    plain = [s._pixel(k, R, t, X) - u for k, X, u in zip(s.point_cameras, s.X, s.x)]
    loop = [np.ravel(plain)] if plain else []
    for k, seg, ends in zip(s.line_cameras, s.L, s.l2):
        a, b = s._pixel(k, R, t, seg[0]), s._pixel(k, R, t, seg[1])
        n = np.array([a[1] - b[1], b[0] - a[0]])
        n /= np.linalg.norm(n)
        loop.append(np.array([(e - a) @ n for e in ends]))
    ref = np.concatenate(loop)
    residual_err = float(np.max(np.abs(np.abs(r) - np.abs(ref))))  # a segment's sign is a convention
    jac_err = _jacobian_error(f.residuals, R, t)
    ray_err = _jacobian_error(f.ray_residuals, R, t)
    return {"residual_px": residual_err, "jacobian_relative": max(jac_err, ray_err)}


def _jacobian_error(fun: Any, R: np.ndarray, t: np.ndarray) -> float:
    """max |J − J_central differences| / max |J_cd| of ``fun`` at ``(R, t)``."""
    J = fun(R, t, jacobian=True)[1]
    h = 1e-6
    cols = []
    for j in range(6):
        d = np.zeros(6)
        d[j] = h
        plus = fun(exp_so3(d[:3]) @ R, t + d[3:])[0]
        minus = fun(exp_so3(-d[:3]) @ R, t - d[3:])[0]
        cols.append((plus - minus) / (2 * h))
    Jn = np.column_stack(cols)
    return float(np.max(np.abs(J - Jn)) / max(np.max(np.abs(Jn)), 1e-300))


# --------------------------------------------------------------------------------------------------
# One row


def reason_of(res: Any, err: str | None) -> str:
    """``details.uncertified_reason`` up to its first ``;``, numbers as ``#`` (a histogram key)."""
    if res is None:
        return f"exception: {err}"
    why = getattr(getattr(res, "details", None), "uncertified_reason", None) or "no reason given"
    return re.sub(r"[-+]?\d+(\.\d*)?([eE][-+]?\d+)?", "#", why.split(";")[0])


def call(s: Scene) -> tuple[Any, float, str | None]:
    """One timed ``estimate_pose(rig, ..., certify=CertifyOptions())``: (result or None, seconds, error)."""
    rig = s.rig()
    options = pluecker.PoseOptions(certify=pluecker.CertifyOptions())
    extra: dict[str, Any] = {}
    if len(s.L):
        extra = dict(lines2d=s.l2, lines3d=s.L, line_cameras=s.line_cameras)
    started = time.perf_counter()
    try:
        res = pluecker.estimate_pose(rig, s.x, s.X, point_cameras=s.point_cameras, options=options, **extra)
        err = None
    except pluecker.PlueckerError as e:
        res, err = None, f"{type(e).__name__}: {e}"
    return res, time.perf_counter() - started, err


def _num(x: Any) -> float | None:
    return None if x is None else float(x)


def run_row(row: Row, args: argparse.Namespace) -> dict[str, Any]:
    salt = zlib.crc32(row.name.encode())
    scenes: list[dict[str, Any]] = []
    tests: list[dict[str, float]] = []
    uncertified_attacked = 0
    for i in range(args.scenes):
        seed = args.seed + i
        s = FocalScene(row.cameras, row.points, row.segments, seed, row.focal)
        f = RigCost(s)
        if i == 0:
            tests.append(self_test(f, s, np.random.default_rng([seed, salt, 3])))
        res, sec, err = call(s)
        cert = getattr(res, "certificate", None)
        certified = bool(getattr(res, "certified", False)) if res is not None else False
        rec: dict[str, Any] = {
            "seed": seed,
            "certified": certified,
            "status": str(res.status) if res is not None else "exception",
            "cost": float(res.cost) if res is not None else None,
            "lower_bound": _num(getattr(cert, "lower_bound", None)),
            "raw_lower_bound": _num(getattr(cert, "raw_lower_bound", None)),
            "relative_gap": _num(getattr(cert, "relative_gap", None)),
            "nodes": getattr(cert, "nodes", None),
            "reason": None if certified else reason_of(res, err),
            "reason_full": None if certified else (err if res is None else res.details.uncertified_reason),
            "ms": 1e3 * sec,
        }
        answer = None
        if res is not None:
            answer = (np.asarray(res.pose.rotation, dtype=float), np.asarray(res.pose.translation, dtype=float))
            own, ok = f.cost(*answer)
            rec["answer_valid"] = ok
            rec["own_cost_relative"] = own / res.cost - 1.0 if res.cost > 0 else own - res.cost
            rec["rotation_error_deg"] = math.degrees(rotation_error(answer[0], s.R))
        attack_it = res is not None and (certified or uncertified_attacked < args.attack_uncertified)
        if attack_it:
            uncertified_attacked += not certified
            a = attack(f, s, answer, args.starts, args.perturbations, np.random.default_rng([seed, salt, 1]))
            rec["attack"] = a
            if rec["raw_lower_bound"] is not None:
                rec["violation"] = bool(a["best"] < rec["raw_lower_bound"] * (1.0 - VIOLATION_REL))
                rec["violation_lower"] = bool(a["best"] < rec["lower_bound"] * (1.0 - VIOLATION_REL))
                rec["bound_margin"] = a["best"] / rec["raw_lower_bound"] - 1.0 if rec["raw_lower_bound"] > 0 else None
            rec["attack_below_answer"] = (
                a["best"] / res.cost - 1.0 if a["best"] < res.cost * (1.0 - VIOLATION_REL) else None
            )
        scenes.append(rec)
    return summarise(row, scenes, tests)


def summarise(row: Row, scenes: list[dict[str, Any]], tests: list[dict[str, float]]) -> dict[str, Any]:
    n = len(scenes)
    ms = np.array([r["ms"] for r in scenes])
    cert = [r for r in scenes if r["certified"]]
    attacked = [r for r in scenes if "attack" in r]
    statuses: dict[str, int] = {}
    reasons: dict[str, int] = {}
    for r in scenes:
        statuses[r["status"]] = statuses.get(r["status"], 0) + 1
        if r["reason"] is not None:
            reasons[r["reason"]] = reasons.get(r["reason"], 0) + 1
    nodes = [r["nodes"] for r in scenes if r["nodes"] is not None]
    rel_all = [abs(r["own_cost_relative"]) for r in scenes if r.get("answer_valid")]
    rel_cert = [abs(r["own_cost_relative"]) for r in cert if r.get("answer_valid")]
    margins = [r["bound_margin"] for r in attacked if r["certified"] and r.get("bound_margin") is not None]
    below = [r["attack_below_answer"] for r in attacked if r.get("attack_below_answer") is not None]
    random_starts = sum(r["attack"]["random_starts"] for r in attacked)
    reach = sum(r["attack"]["random_reached_answer"] for r in attacked) / random_starts if random_starts else None
    return {
        "row": row.name,
        "cameras": row.cameras,
        "points": row.points,
        "segments": row.segments,
        "correspondences": row.correspondences,
        "focal": row.focal,
        "control": row.control,
        "scenes": n,
        "certified": len(cert),
        "certified_fraction": len(cert) / n if n else None,
        "median_ms": float(np.median(ms)),
        "p99_ms": float(np.percentile(ms, 99)),
        "max_ms": float(np.max(ms)),
        "median_ms_certified": float(np.median([r["ms"] for r in cert])) if cert else None,
        "nodes_median": float(np.median(nodes)) if nodes else None,
        "nodes_max": int(max(nodes)) if nodes else None,
        "status_histogram": statuses,
        "uncertified_reasons": reasons,
        "invalid_answers": sum(1 for r in scenes if r.get("answer_valid") is False),
        "attacked_certified": sum(1 for r in attacked if r["certified"]),
        "attacked_uncertified": sum(1 for r in attacked if not r["certified"]),
        "attack_starts": sum(r["attack"]["starts"] for r in attacked),
        "random_start_reach": reach,
        "violations": sum(1 for r in attacked if r["certified"] and r.get("violation")),
        "violations_below_lower_bound": sum(1 for r in attacked if r["certified"] and r.get("violation_lower")),
        "violation_seeds": [r["seed"] for r in attacked if r["certified"] and r.get("violation")],
        "uncertified_bound_violations": sum(1 for r in attacked if not r["certified"] and r.get("violation")),
        "least_bound_margin": min(margins) if margins else None,
        "own_cost_rel_max_certified": max(rel_cert) if rel_cert else None,
        "own_cost_rel_max_all": max(rel_all) if rel_all else None,
        "attack_below_answer": len(below),
        "attack_below_answer_max": min(below) if below else None,
        "self_test": tests[0] if tests else None,
        "per_scene": scenes,
    }


# --------------------------------------------------------------------------------------------------
# Report


def _na(x: Any, fmt: str) -> str:
    if x is None or (isinstance(x, float) and not math.isfinite(x)):
        return "n/a"
    return format(x, fmt)


def _hist(h: dict[str, int], top: int | None = None) -> str:
    items = sorted(h.items(), key=lambda kv: -kv[1])
    return ", ".join(f"{k} ({v})" for k, v in items[:top])


def markdown(rows: list[dict[str, Any]]) -> str:
    head = (
        "| row | scenes | certified | med ms | p99 ms | max ms | nodes med / max | attacked cert / uncert | "
        "reach | violations | least margin | own/cost−1 cert | own/cost−1 all | attack < answer | status |"
    )
    lines = [head, "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---|"]
    for r in rows:
        below = f"{r['attack_below_answer']}"
        if r["attack_below_answer"]:
            below += f" ({r['attack_below_answer_max']:.1e})"
        lines.append(
            f"| {r['row']} | {r['scenes']} | {r['certified_fraction']:.3f} | {r['median_ms']:.2f} | "
            f"{r['p99_ms']:.2f} | {r['max_ms']:.2f} | {_na(r['nodes_median'], '.0f')} / {_na(r['nodes_max'], 'd')} | "
            f"{r['attacked_certified']} / {r['attacked_uncertified']} | {_na(r['random_start_reach'], '.2f')} | "
            f"{r['violations']} | "
            f"{_na(r['least_bound_margin'], '.2e')} | {_na(r['own_cost_rel_max_certified'], '.1e')} | "
            f"{_na(r['own_cost_rel_max_all'], '.1e')} | {below} | {_hist(r['status_histogram'])} |"
        )
    return "\n".join(lines)


def targets(rows: list[dict[str, Any]]) -> list[tuple[str, bool | None]]:
    checks: list[tuple[str, bool | None]] = []
    rig = [r for r in rows if not r["control"]]
    for n, goal in CERT_TARGET.items():
        sel = [r for r in rig if r["correspondences"] == n]
        if sel:
            worst = min(sel, key=lambda r: r["certified_fraction"])
            checks.append(
                (
                    f"({1 if n == 100 else 2}) certified ≥ {goal:.0%} on the {len(sel)} rig rows with {n} "
                    f"correspondences (lowest {worst['certified_fraction']:.3f}, {worst['row']})",
                    worst["certified_fraction"] >= goal,
                )
            )
    sel = [r for r in rig if r["correspondences"] == 100]
    if sel:
        worst = max(sel, key=lambda r: r["median_ms"])
        text = (
            f"(3) median time of the certify call ≤ {TIME_TARGET_MS:.0f} ms on the {len(sel)} rig rows with 100 "
            f"correspondences (slowest {worst['median_ms']:.2f} ms, {worst['row']})"
        )
        if not any(r["certified"] for r in sel):
            checks.append((text + ": n/a (nothing certified: the time of a refusal)", None))
        else:
            checks.append((text, worst["median_ms"] <= TIME_TARGET_MS))
    checked = sum(r["attacked_certified"] for r in rows)
    bad = [
        f"{r['row']} {r['violations']} (below lower_bound too: {r['violations_below_lower_bound']}; seeds "
        f"{r['violation_seeds']})"
        for r in rows
        if r["violations"]
    ]
    text = f"(4) no violation: {checked} certified answers attacked over {len(rows)} rows"
    if checked:
        margins = [r["least_bound_margin"] for r in rows if r["least_bound_margin"] is not None]
        text += f" (least margin own best / raw_lower_bound − 1: {min(margins):.2e})" if margins else ""
        checks.append((text + (f"; violations: {', '.join(bad)}" if bad else ""), not bad))
    else:
        checks.append((text + ": n/a (nothing certified)", None))
    rel = [(r["own_cost_rel_max_all"], r["row"]) for r in rows if r["own_cost_rel_max_all"] is not None]
    if rel:
        worst_rel = max(rel)
        checks.append(
            (
                f"(5) own cost of the library's pose = result.cost to {COST_CHECK_TOL:.0e} relative on every valid "
                f"answer (max {worst_rel[0]:.1e}, {worst_rel[1]})",
                worst_rel[0] <= COST_CHECK_TOL,
            )
        )
    return checks


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--quick", action="store_true", help=f"{QUICK_SCENES} scenes per row, fewer starts")
    parser.add_argument("--scenes", type=int, default=None, help=f"scenes per row (default {FULL_SCENES})")
    parser.add_argument("--seed", type=int, default=0, help="scene i of every row uses seed + i")
    parser.add_argument("--starts", type=int, default=None, help=f"random-rotation starts (default {FULL_STARTS})")
    parser.add_argument(
        "--perturbations", type=int, default=None, help=f"perturbations of the answer (default {FULL_PERTURBATIONS})"
    )
    parser.add_argument(
        "--attack-uncertified",
        type=int,
        default=None,
        help=f"uncertified scenes attacked per row, the first ones (default {FULL_ATTACK_UNCERTIFIED})",
    )
    parser.add_argument("--rows", nargs="+", default=None, help="only the rows whose name contains one of these")
    parser.add_argument("--list-rows", action="store_true")
    parser.add_argument("--out", type=Path, default=OUT, help=f"JSON output (default {OUT})")
    args = parser.parse_args(argv)
    q = args.quick
    args.scenes = args.scenes or (QUICK_SCENES if q else FULL_SCENES)
    args.starts = args.starts if args.starts is not None else (QUICK_STARTS if q else FULL_STARTS)
    if args.perturbations is None:
        args.perturbations = QUICK_PERTURBATIONS if q else FULL_PERTURBATIONS
    if args.attack_uncertified is None:
        args.attack_uncertified = QUICK_ATTACK_UNCERTIFIED if q else FULL_ATTACK_UNCERTIFIED

    rows_def = all_rows()
    if args.rows:
        rows_def = [r for r in rows_def if any(s in r.name for s in args.rows)]
    if args.list_rows:
        print("\n".join(r.name for r in rows_def))
        return 0
    if not rows_def:
        sys.exit("no row matches --rows")

    started = time.perf_counter()
    rows = []
    for row in rows_def:
        t0 = time.perf_counter()
        rows.append(run_row(row, args))
        r = rows[-1]
        r["wall_seconds"] = time.perf_counter() - t0
        st = r["self_test"]
        print(
            f"{row.name}: {r['scenes']} scenes, {r['wall_seconds']:.1f} s, certified {r['certified']}, "
            f"violations {r['violations']}; self-test residuals {st['residual_px']:.1e} px, "
            f"Jacobian {st['jacobian_relative']:.1e}",
            file=sys.stderr,
        )
    wall = time.perf_counter() - started
    checks = targets(rows)

    print(markdown(rows))
    print()
    print("Not certified, by reason (details.uncertified_reason up to its first ';', numbers as #):")
    for r in rows:
        if r["uncertified_reasons"]:
            print(f"  {r['row']}: {_hist(r['uncertified_reasons'], 3)}")
    worst_test = {k: max(r["self_test"][k] for r in rows) for k in ("residual_px", "jacobian_relative")}
    print(
        f"\nSelf-test (first scene of each row): residuals against a plain loop {worst_test['residual_px']:.1e} px, "
        f"analytic Jacobian against central differences {worst_test['jacobian_relative']:.1e} relative"
    )
    bound_bad = sum(r["uncertified_bound_violations"] for r in rows)
    with_bound = sum(
        1
        for r in rows
        for s in r["per_scene"]
        if "attack" in s and not s["certified"] and s["raw_lower_bound"] is not None
    )
    if with_bound:
        print(f"Proved bounds of uncertified answers: {with_bound} attacked, {bound_bad} below the own cost found")
    print()
    for text, ok in checks:
        print(f"{'n/a ' if ok is None else ('PASS' if ok else 'FAIL')} {text}")
    print(f"\nwall time {wall:.1f} s", file=sys.stderr)

    doc = {
        "date": datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds"),
        "machine": {"platform": platform.platform(), "processor": platform.processor()},
        "versions": {
            "python": platform.python_version(),
            "numpy": np.__version__,
            "pluecker": getattr(pluecker, "__version__", "unknown"),
        },
        "settings": {
            "argv": sys.argv[1:] if argv is None else argv,
            "quick": q,
            "scenes": args.scenes,
            "seed": args.seed,
            "starts": args.starts,
            "perturbations": args.perturbations,
            "attack_uncertified": args.attack_uncertified,
            "sigma_px": SIGMA_PX,
            "violation_relative": VIOLATION_REL,
            "cost_check_tolerance": COST_CHECK_TOL,
            "wall_seconds": wall,
        },
        "results": rows,
        "targets": [{"check": text, "pass": ok} for text, ok in checks],
    }
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps(_finite_or_none(doc), indent=1, allow_nan=False) + "\n")
    print(f"wrote {args.out}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
