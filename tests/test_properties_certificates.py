"""Certificate soundness, property-tested (hypothesis, issue 10 §6).

Triangulation (points, lines, quadrics): a certified answer's raw bound (``raw_lower_bound``, before the
library caps it at its cost) is at most the numpy cost of the answer, of the truth and of ``local``
whenever those lie in front of every camera (``λ = (P X̃)₃ > 0`` for P as given), and for points at most
the least cost of a numpy many-start search; the gap recomputed from the numpy cost and the raw bound is
within the tolerance; and no admissible candidate we know of is cheaper than the gap allows.
Cameras have focal lengths of either sign and are scaled by factors of either sign; points lie in
front of, near, or behind the cameras. Pose: a certified answer's raw (unclamped) bound closes the gap
against its cost and is at most the cost of the truth and of the oracle's minimum reached from it.

Costs are recomputed here in numpy, never with the library's residuals: triangulation from the paper's
definitions (eq. 17-19), the pose by ``tests/pose_oracle.py``: they agree with the library's reported cost at its own estimate, which each test
checks.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import assume, event, given, note
from hypothesis import strategies as st

import pluecker
import pose_oracle
from triangulation_scenes import many_start_point_minimum

pytestmark = pytest.mark.filterwarnings("ignore::RuntimeWarning")

GAP = 1e-3  # the default CertifyOptions.max_relative_gap
D = 1000.0  # LINE_FRAME_DISTANCE: an observed line sits D px from the origin of its frame


def rotation(q) -> np.ndarray:
    w, x, y, z = np.asarray(q, float) / np.linalg.norm(q)
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                     [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                     [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])


def look_at(centre: np.ndarray, target: np.ndarray, rng) -> np.ndarray:
    """A rotation whose camera at ``centre`` looks at ``target`` (optical axis +z), rolled at random."""
    z = (target - centre) / np.linalg.norm(target - centre)
    x = np.cross(rng.normal(size=3), z)
    x /= np.linalg.norm(x)
    return np.stack([x, np.cross(z, x), z])


@st.composite
def rigs(draw, min_views: int):
    """Cameras ``s K [R | −R c]`` around the origin looking near it: focal lengths of either sign
    (a mirrored axis), and an overall factor ``s`` that may be negative (then the origin is behind
    that camera, since ``λ = (P X̃)₃`` changes sign)."""
    views = draw(st.integers(min_views, 4))
    rng = np.random.default_rng(draw(st.integers(0, 2**32 - 1)))
    flip_probability = draw(st.sampled_from([0.0, 0.0, 0.3, 1.0]))
    P = []
    for _ in range(views):
        centre = rng.normal(size=3)
        centre *= draw(st.sampled_from([3.0, 6.0, 30.0])) / np.linalg.norm(centre)
        R = look_at(centre, rng.normal(0, 0.3, 3), rng)
        f = rng.choice([-1.0, 1.0], 2) * rng.uniform(400, 2000, 2)
        K = np.array([[f[0], rng.uniform(-2, 2), 320], [0, f[1], 240], [0, 0, 1]])
        s = rng.uniform(0.1, 10) * (-1.0 if rng.random() < flip_probability else 1.0)
        P.append(s * K @ np.hstack([R, -(R @ centre)[:, None]]))
    note(f"{views} views, flip probability {flip_probability}")
    return np.array(P), rng


def depths(P, X) -> np.ndarray:
    """``λᵢ = (Pᵢ X̃)₃`` of a point in every camera."""
    return P[:, 2, :3] @ X + P[:, 2, 3]


def project(P, X) -> np.ndarray:
    h = P @ np.append(X, 1.0)
    return h[:, :2] / h[:, 2:]


def assert_sound(opt, own_cost: float, local, truth_cost: float | None, local_cost: float | None,
                 searched: float | None = None) -> None:
    """The certificate's claims against numpy's costs: ``own_cost`` of the answer, ``truth_cost`` of the truth,
    ``local_cost`` of the local answer (None when not admissible) and ``searched``, a many-start minimum.
    The raw bound may exceed none of them, and the gap recomputed from ``own_cost`` and the raw bound must
    be within the tolerance. numpy's cost agrees with the library's to 1e-6 relative (checked by the
    callers), hence that slack; ``eps`` absorbs exact data (costs at the rounding level)."""
    event(f"certified={opt.certified}, truth in front={truth_cost is not None}, local={local.status}")
    if not opt.certified:
        return
    eps = 1e-8
    assert opt.success, opt
    raw = opt.certificate.raw_lower_bound
    assert np.isfinite(raw) and opt.certificate.lower_bound == min(raw, opt.cost), opt
    assert raw <= own_cost * (1 + 1e-6) + eps, (opt, own_cost)
    gap = (own_cost - min(raw, own_cost)) / max(own_cost, 1e-12)
    assert gap <= GAP * (1 + 1e-3) or own_cost <= eps, (opt, own_cost, gap)
    for other in (truth_cost, local_cost, searched):
        if other is not None:
            assert raw <= other * (1 + 1e-6) + eps, (opt, other)
            assert opt.cost * (1 - GAP) <= other * (1 + 1e-9) + eps, (opt, other)


# --- points ---------------------------------------------------------------------------------------------


def point_cost(P, x, X) -> float:
    """Eq. 19 without covariances: Σ ‖π(Pᵢ X̃) − xᵢ‖²."""
    return float(np.sum((project(P, X) - x) ** 2))


@given(rigs(2), st.sampled_from(["front", "front", "near", "behind", "far"]), st.sampled_from([0.0, 0.3, 2.0, 30.0]))
def test_point_certificates_are_sound(rig, where, sigma):
    P, rng = rig
    X = rng.normal(0, 0.5, 3)
    if where == "near":  # just in front of (or just behind) camera 0
        c0 = -np.linalg.solve(P[0, :, :3], P[0, :, 3])
        X = c0 + rng.choice([-1.0, 1.0]) * rng.uniform(1e-4, 0.05) * (X - c0) / np.linalg.norm(X - c0)
    elif where == "behind":  # behind camera 0 (in front of it if P₀ was flipped)
        c0 = -np.linalg.solve(P[0, :, :3], P[0, :, 3])
        X = c0 + rng.uniform(0.5, 5) * (c0 - X) / np.linalg.norm(c0 - X)
    elif where == "far":
        X = X * 1e3
    lam = depths(P, X)
    assume(np.all(np.abs(lam) > 1e-9 * np.abs(P[:, 2]).max()))
    x = project(P, X) + rng.normal(0, sigma, (len(P), 2))
    note(f"X={X}, λ={lam}, σ={sigma}")
    opt = pluecker.triangulate_point(P, x, options=pluecker.TriangulationOptions(method="optimal"))
    local = pluecker.triangulate_point(P, x, options=pluecker.TriangulationOptions(method="local"))
    if opt.success:
        assert np.all(depths(P, opt.point) > 0), opt
        assert np.isclose(point_cost(P, x, opt.point), opt.cost, rtol=1e-6, atol=1e-9), opt
    local_in_front = local.success and bool(np.all(depths(P, local.point) > 0))
    truth_cost = point_cost(P, x, X) if np.all(lam > 0) else None
    searched = None
    if opt.certified:
        searched = many_start_point_minimum(P, x, opt.point, rng, starts=8)
    assert_sound(opt, point_cost(P, x, opt.point), local, truth_cost,
                 point_cost(P, x, local.point) if local_in_front else None, searched)


# --- lines ------------------------------------------------------------------------------------------------


def line_residual(observed, image) -> np.ndarray:
    """Eq. 17 in pluecker's frame (see ``line_residual.rs``): the candidate image line in the frame of the
    observed one, ``D (D (a, b)/c − n)``."""
    h = np.linalg.norm(observed[:2])
    n, c0 = observed[:2] / h, observed[2] / h
    if c0 > 0:
        n, c0 = -n, -c0
    origin = n * (D - c0)
    c = image[0] * origin[0] + image[1] * origin[1] + image[2]
    return D * (D * image[:2] / c - n)


def line_cost(P, lines, point, direction) -> float:
    A, B = np.append(point, 1.0), np.append(point + direction, 1.0)
    return float(sum(np.sum(line_residual(l, np.cross(p @ A, p @ B)) ** 2) for p, l in zip(P, lines)))


@given(rigs(2), st.sampled_from([0.0, 0.3, 2.0]))
def test_line_certificates_are_sound(rig, sigma):
    P, rng = rig
    A, B = rng.normal(0, 0.5, 3), rng.normal(0, 0.5, 3)
    assume(np.linalg.norm(B - A) > 0.2)
    ends = np.stack([project(P, A), project(P, B)], axis=1) + rng.normal(0, sigma, (len(P), 2, 2))
    lines = np.cross(np.c_[ends[:, 0], np.ones(len(P))], np.c_[ends[:, 1], np.ones(len(P))])
    note(f"A={A}, B={B}, σ={sigma}")
    try:
        opt = pluecker.triangulate_line(P, lines, options=pluecker.TriangulationOptions(method="optimal", certify=pluecker.CertifyOptions(max_nodes=300)))
        local = pluecker.triangulate_line(P, lines, options=pluecker.TriangulationOptions(method="local"))
    except pluecker.DegenerateConfigurationError:
        return  # e.g. the line lies in an epipolar plane of every pair of views
    if np.all(np.isfinite(opt.point)):
        assert np.isclose(line_cost(P, lines, opt.point, opt.direction), opt.cost, rtol=1e-6, atol=1e-9), opt
    in_front = lambda *points: all(np.all(depths(P, Y) > 0) for Y in points)  # noqa: E731
    truth_cost = line_cost(P, lines, A, B - A) if in_front(A, B, (A + B) / 2) else None
    own = line_cost(P, lines, opt.point, opt.direction) if np.all(np.isfinite(opt.point)) else np.inf
    local_cost = line_cost(P, lines, local.point, local.direction) if np.all(np.isfinite(local.point)) else None
    assert_sound(opt, own, local, truth_cost, local_cost)


# --- quadrics ---------------------------------------------------------------------------------------------


def normalized_dual(e, centre) -> np.ndarray:
    """``v(T e Tᵀ)`` of ``quadric_residual.rs``: the dual conic in the frame centred on the observed
    ellipse, five entries over the last."""
    T = np.array([[1, 0, -centre[0]], [0, 1, -centre[1]], [0, 0, 1.0]])
    e = T @ e @ T.T
    return np.array([e[0, 0], e[0, 1], e[1, 1], e[0, 2], e[1, 2]]) / e[2, 2]


def quadric_cost(P, conics, dual_quadric) -> float:
    total = 0.0
    for p, c in zip(P, conics):
        observed = np.linalg.inv(c)
        centre = observed[:2, 2] / observed[2, 2]
        total += np.sum((normalized_dual(p @ dual_quadric @ p.T, centre) - normalized_dual(observed, centre)) ** 2)
    return float(total)


def entirely_in_front(P, dual_quadric, centre) -> bool:
    """Every principal plane ``πᵢ = Pᵢ[2]`` misses the ellipsoid (``πᵀ Q* π < 0``) and the centre has
    ``λ > 0``: the whole ellipsoid is in front of every camera."""
    return all(p[2] @ dual_quadric @ p[2] < 0 for p in P) and bool(np.all(depths(P, centre) > 0))


@given(rigs(3), st.sampled_from([0.0, 1e-4, 1e-3, 1e-2]))
def test_quadric_certificates_are_sound(rig, noise):
    P, rng = rig
    T = np.eye(4)
    T[:3, :3] = rotation(rng.normal(size=4)) @ np.diag(rng.uniform(0.1, 0.8, 3))
    T[:3, 3] = rng.normal(0, 0.3, 3)
    dual = T @ np.diag([1.0, 1.0, 1.0, -1.0]) @ T.T
    duals = np.stack([p @ dual @ p.T for p in P])
    e = rng.normal(0, noise, duals.shape) * np.abs(duals)
    duals = duals + (e + np.swapaxes(e, 1, 2)) / 2
    conics = np.linalg.inv(duals)
    note(f"centre={T[:3, 3]}, noise={noise}")
    try:
        opt = pluecker.triangulate_quadric(P, conics, options=pluecker.TriangulationOptions(method="optimal", certify=pluecker.CertifyOptions(max_nodes=200)))
        local = pluecker.triangulate_quadric(P, conics, options=pluecker.TriangulationOptions(method="local"))
    except pluecker.DegenerateConfigurationError:
        return  # an outline that is no real ellipse (the ellipsoid crosses a principal plane)
    if np.all(np.isfinite(opt.Q)):
        assert np.isclose(quadric_cost(P, conics, opt.Q), opt.cost, rtol=1e-6, atol=1e-9), opt
    truth_cost = quadric_cost(P, conics, dual) if entirely_in_front(P, dual, T[:3, 3]) else None
    own = quadric_cost(P, conics, opt.Q) if np.all(np.isfinite(opt.Q)) else np.inf
    local_cost = quadric_cost(P, conics, local.Q) if local.success and np.all(np.isfinite(local.Q)) else None
    assert_sound(opt, own, local, truth_cost, local_cost)


# --- pose -------------------------------------------------------------------------------------------------


@given(st.integers(0, 2**32 - 1), st.integers(3, 14), st.integers(0, 5), st.sampled_from([0.0, 0.5, 3.0]),
       st.sampled_from([(800.0, 800.0), (-1730.3, 1220.7), (600.0, -600.0)]))
def test_pose_certificates_are_sound(seed, n_points, n_lines, sigma, focal):
    scene = pluecker.random_scene("general", n_points, n_lines, seed=seed)
    camera = pluecker.Camera.pinhole(focal[0], focal[1], 320.0, 240.0)
    R, t = scene["R"], scene["t"]
    rng = np.random.default_rng(seed)
    points2d = camera.project(scene["points3d"] @ R.T + t) + rng.normal(0, sigma, (n_points, 2))
    lines3d = scene["lines3d"]
    lines2d = camera.project(lines3d.reshape(-1, 3) @ R.T + t).reshape(-1, 2, 2) + rng.normal(0, sigma, (n_lines, 2, 2))
    data = dict(points2d=points2d, points3d=scene["points3d"], lines2d=lines2d, lines3d=lines3d)
    result = pluecker.estimate_pose(camera, **data, options=pluecker.PoseOptions(certify=pluecker.CertifyOptions()))
    event(f"certified={result.certified}")
    assume(result.certified)
    # ½ Σ r² recomputed in numpy (``pose_oracle``: the residuals written again, not the library's),
    # checked against the reported cost (Σ r², halved); the bound is the raw, unclamped one (halved)
    # and the gap is recomputed.
    K = pose_oracle.K_of(camera)
    args = (points2d, scene["points3d"], lines2d, lines3d)
    cost = pose_oracle.cost(K, result.pose.rotation, result.pose.translation, *args)
    assert np.isclose(cost, result.cost / 2, rtol=1e-6, atol=1e-12), result
    assert result.status == "success" and result.certificate.kind == "sublevel_set"
    eps = 1e-9
    raw = result.certificate.raw_lower_bound / 2
    assert (cost - raw) / max(cost, 1e-12) <= GAP + 1e-12, result
    # The oracle's own local minimum from the truth (Levenberg-Marquardt), when every point is in front.
    R1, t1, refined = pose_oracle.minimise(K, R, t, args)
    if pose_oracle.points_in_front(R1, t1, scene["points3d"]):
        assert raw <= refined * (1 + 1e-9) + eps, (result, refined)
        assert cost * (1 - GAP) <= refined * (1 + 1e-9) + eps, (result, refined)
    assert raw <= pose_oracle.cost(K, R, t, *args) * (1 + 1e-9) + eps, result  # the truth keeps every point in front
