"""Scenes and costs of the triangulation tests, built with numpy independently of the library.

``v`` cameras ``K [R | t]`` (f = 800 px) on a circle of radius 10 around the origin, looking at it,
spread over ``parallax`` degrees; primitives near the origin. The costs of eq. 19 are recomputed
here from the returned estimates (Josephson & Kahl 2008, eqs. 17-19 and section 3.1).
"""

from __future__ import annotations

import math

import numpy as np

import pluecker

METHODS = pluecker.TRIANGULATION_METHODS
#: Branch and bound is capped so that the optimal runs of the batch tests stay short; the equality of a
#: batch with single calls holds at any cap.
NODES = 30
REPORT = ("cost", "cost_kind", "certified", "status", "iterations")
#: The batch columns of a single result's `certificate` (NaN bounds, "none" and 0 nodes without one).
CERTIFICATE_COLUMNS = ("lower_bound", "raw_lower_bound", "relative_gap", "nodes")


def look_at(centre: np.ndarray, roll: float) -> np.ndarray:
    z = -centre / np.linalg.norm(centre)
    x = np.cross([0.0, 1.0, 0.0], z)
    x /= np.linalg.norm(x)
    c, s = math.cos(roll), math.sin(roll)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]]) @ np.stack([x, np.cross(z, x), z])


def cameras(views: int, parallax_deg: float, rng: np.random.Generator, radius: float = 10.0) -> np.ndarray:
    """(views, 3, 4) cameras ``K [R | t]`` spread over ``parallax_deg`` degrees, looking at the origin."""
    K = np.array([[800.0, 0.0, 320.0], [0.0, 800.0, 240.0], [0.0, 0.0, 1.0]])
    out = []
    for a in np.radians(np.linspace(-parallax_deg / 2, parallax_deg / 2, views)):
        centre = radius * np.array([math.sin(a), 0.1 * rng.uniform(-1, 1), -math.cos(a)])
        R = look_at(centre, rng.uniform(-0.3, 0.3))
        out.append(K @ np.hstack([R, (-R @ centre)[:, None]]))
    return np.array(out)


def project(P: np.ndarray, X: np.ndarray) -> np.ndarray:
    """Pixels (v, 2) of one point (3,) in cameras (v, 3, 4)."""
    h = P @ np.append(X, 1.0)
    return h[:, :2] / h[:, 2:]


def cost_eq19(P: np.ndarray, X: np.ndarray, x: np.ndarray, cov: np.ndarray | None = None) -> float:
    r = project(P, X) - x
    if cov is None:
        return float(np.sum(r * r))
    return float(sum(ri @ np.linalg.solve(c, ri) for ri, c in zip(r, cov)))


def depths(P: np.ndarray, X: np.ndarray) -> np.ndarray:
    """λ = (P X̃)₃ per view: positive in front (the sign of P counts, its positive scale does not)."""
    return P[:, 2] @ np.append(X, 1.0)


def refine_point(P: np.ndarray, x: np.ndarray, X0: np.ndarray, cov: np.ndarray | None = None,
                 iterations: int = 200) -> tuple[np.ndarray, float]:
    """Levenberg-Marquardt on ``cost_eq19`` from ``X0`` (numpy only, not the library), kept in front of
    every camera: the point and its cost, an upper bound of the minimum over the points in front."""
    W = np.broadcast_to(np.eye(2), (len(P), 2, 2)) if cov is None else np.linalg.inv(cov)
    X, f, damping = np.asarray(X0, float), cost_eq19(P, X0, x, cov), 1e-3
    for _ in range(iterations):
        h = P @ np.append(X, 1.0)
        proj = h[:, :2] / h[:, 2:]
        # ∂π/∂X = (rows 1-2 of M − π · row 3 of M) / λ per view.
        J = (P[:, :2, :3] - proj[:, :, None] * P[:, 2:3, :3]) / h[:, 2, None, None]
        e = proj - x
        H = np.einsum("vai,vab,vbj->ij", J, W, J)
        g = np.einsum("vai,vab,vb->i", J, W, e)
        while damping < 1e12:
            try:
                trial = X - np.linalg.solve(H + damping * np.diag(np.diag(H)) + 1e-300 * np.eye(3), g)
            except np.linalg.LinAlgError:
                damping *= 10
                continue
            ft = cost_eq19(P, trial, x, cov)
            if np.all(depths(P, trial) > 0) and ft < f:
                done = f - ft <= 1e-15 * f
                X, f, damping = trial, ft, max(damping * 0.3, 1e-12)
                break
            damping *= 10
        else:
            break
        if done:
            break
    return X, f


def many_start_point_minimum(P: np.ndarray, x: np.ndarray, X_ref: np.ndarray, rng: np.random.Generator,
                             starts: int = 30, cov: np.ndarray | None = None) -> float:
    """The least cost ``refine_point`` reaches from ``X_ref`` and from ``starts`` random points in front of
    every camera along camera 0's ray through ``X_ref`` (0.1 to 1000 times its depth, jittered)."""
    centre = -np.linalg.solve(P[0, :, :3], P[0, :, 3])
    best = refine_point(P, x, X_ref, cov)[1] if np.all(depths(P, X_ref) > 0) else math.inf
    for _ in range(starts):
        depth = 10 ** rng.uniform(-1, 3)
        X0 = centre + (X_ref - centre) * depth + rng.normal(0, 0.02 * depth * np.linalg.norm(X_ref - centre), 3)
        if np.all(depths(P, X0) > 0):
            best = min(best, refine_point(P, x, X0, cov)[1])
    return best


def image_line(P: np.ndarray, A: np.ndarray, B: np.ndarray) -> np.ndarray:
    """Homogeneous image lines (v, 3) of the 3-D line through A and B."""
    a, b = P @ np.append(A, 1.0), P @ np.append(B, 1.0)
    return np.cross(a, b)


def ellipsoid(rng):
    """A random ellipsoid near the origin: centre, axes (columns), semi-axes, dual quadric (L44 = -1)."""
    centre = rng.uniform(-0.3, 0.3, 3)
    axes, _ = np.linalg.qr(rng.normal(size=(3, 3)))
    semi = np.sort(rng.uniform(0.3, 1.0, 3))[::-1]
    H = np.eye(4)
    H[:3, :3], H[:3, 3] = axes, centre
    return centre, axes, semi, H @ np.diag([*(semi**2), -1.0]) @ H.T


def outlines(P, dual):
    return np.array([np.linalg.inv(p @ dual @ p.T) for p in P])


def line_tracks(seed: int, n: int = 10, views: int = 4, sigma: float = 1.0):
    """Cameras (v, 3, 4) and noisy segments (n, v, 2, 2) of n random 3-D segments."""
    rng = np.random.default_rng(seed)
    P = cameras(views, 30.0, rng)
    ends = rng.uniform(-1.0, 1.0, (n, 2, 3))
    segments = np.stack([np.stack([project(P, A), project(P, B)], axis=1) for A, B in ends])
    return P, segments + rng.normal(0.0, sigma, segments.shape)


def random_visibility(rng, n: int, views: int, least: int) -> np.ndarray:
    visible = rng.uniform(size=(n, views)) < 0.7
    for i in range(n):
        visible[i, rng.choice(views, least, replace=False)] = True
    return visible


def assert_same_report(batch, i: int, single) -> None:
    for field in REPORT:
        assert getattr(batch, field)[i] == getattr(single, field), (i, field)
    c = single.certificate
    if c is None:
        assert batch.certificate[i] == "none" and batch.nodes[i] == 0, i
        assert all(np.isnan(getattr(batch, f)[i]) for f in ("lower_bound", "raw_lower_bound", "relative_gap")), i
    else:
        assert batch.certificate[i] == c.kind, i
        for field in CERTIFICATE_COLUMNS:
            assert getattr(batch, field)[i] == getattr(c, field), (i, field)


def assert_same_line(batch, i: int, single) -> None:
    for field in ("plucker", "point", "direction"):
        np.testing.assert_array_equal(getattr(batch, field)[i], getattr(single, field), err_msg=f"{i} {field}")
    assert_same_report(batch, i, single)

