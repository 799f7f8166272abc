"""An independent oracle of the pose cost for the tests of the pose certificate and ambiguity: the
reprojection cost ``½ Σ r²`` written again in numpy from its definition (Phong & Horaud 1995; the
residuals that ``pluecker``'s README and ``pose::reprojection`` describe), a plain Levenberg-Marquardt
with numeric Jacobians, many-start search, and scenes. Nothing here calls ``pluecker``.

Residuals, in pixels: a point ``X`` seen at ``u``: ``π(R X + t) − u``; a segment ``(A, B)`` seen with
endpoints ``e₁, e₂``: the signed distances of ``e₁`` and ``e₂`` to the image line through the pixels
of ``R A + t`` and ``R B + t``.

With per-observation covariances (``point_covariances`` (N, 2, 2), ``line_covariances`` (M, 2, 2) for
both endpoints or (M, 2, 2, 2) per endpoint, px²) the residuals are whitened as ``pose::noise`` defines
them: a point's ``W (π(R X + t) − u)`` with ``Wᵀ W = Σ⁻¹``, an endpoint's signed distance divided by
``√(n̂ᵀ C n̂)``, ``n̂`` the projected line's unit normal and ``C`` the endpoint's covariance. The
Levenberg-Marquardt and the many-start search take them as entries 5 and 6 of their ``data`` tuple
``(p2, p3, l2, l3, point_covariances, line_covariances)``."""

from __future__ import annotations

import numpy as np


def K_of(camera) -> np.ndarray:
    """The 3x3 intrinsics of a ``pluecker.Camera`` (or a tuple ``(fx, fy, cx, cy, skew)``)."""
    if isinstance(camera, tuple):
        fx, fy, cx, cy, s = camera
    else:
        fx, fy, cx, cy, s = camera.fx, camera.fy, camera.cx, camera.cy, camera.skew
    return np.array([[fx, s, cx], [0.0, fy, cy], [0.0, 0.0, 1.0]])


def exp_so3(w) -> np.ndarray:
    """Rodrigues' formula."""
    w = np.asarray(w, dtype=float)
    th = np.linalg.norm(w)
    W = np.array([[0.0, -w[2], w[1]], [w[2], 0.0, -w[0]], [-w[1], w[0], 0.0]])
    if th < 1e-12:
        return np.eye(3) + W + 0.5 * W @ W
    return np.eye(3) + np.sin(th) / th * W + (1 - np.cos(th)) / th**2 * W @ W


def log_so3(R) -> np.ndarray:
    """The rotation vector of ``R`` (angle below π - 1e-6 assumed)."""
    c = np.clip((np.trace(R) - 1.0) / 2.0, -1.0, 1.0)
    th = np.arccos(c)
    v = np.array([R[2, 1] - R[1, 2], R[0, 2] - R[2, 0], R[1, 0] - R[0, 1]])
    if th < 1e-7:
        return 0.5 * v
    return th / (2.0 * np.sin(th)) * v


def step(R, t, d):
    """The chart step ``(ω, τ)``: ``(exp(ω) R, t + τ)``."""
    return exp_so3(d[:3]) @ R, t + d[3:]


def pixels(K, X):
    x = X @ K.T
    return x[:, :2] / x[:, 2:3]


def whitening(covariances) -> np.ndarray:
    """Per 2x2 covariance ``Σ = L Lᵀ`` (Cholesky), ``W = L⁻¹``: ``Wᵀ W = Σ⁻¹``."""
    return np.linalg.inv(np.linalg.cholesky(np.asarray(covariances, dtype=float)))


def residuals(K, R, t, p2, p3, l2=None, l3=None, point_covariances=None, line_covariances=None) -> np.ndarray:
    """The residuals in pixels, or in standard deviations where covariances are given."""
    e = pixels(K, p3 @ R.T + t) - p2
    if point_covariances is not None:
        e = np.einsum("nij,nj->ni", whitening(point_covariances), e)
    out = [e.ravel()]
    if l3 is not None and len(l3):
        ends = pixels(K, l3.reshape(-1, 3) @ R.T + t).reshape(-1, 2, 2)
        a, b = ends[:, 0], ends[:, 1]
        d = b - a
        n = np.column_stack([-d[:, 1], d[:, 0]]) / np.linalg.norm(d, axis=1)[:, None]
        dist = np.einsum("mkj,mj->mk", l2 - a[:, None, :], n)
        if line_covariances is not None:
            C = np.asarray(line_covariances, dtype=float)
            C = C if C.ndim == 4 else np.repeat(C[:, None], 2, axis=1)  # (M, 2, 2): both endpoints
            dist = dist / np.sqrt(np.einsum("mi,mkij,mj->mk", n, C, n))
        out.append(dist.ravel())
    return np.concatenate(out)


def cost(K, R, t, p2, p3, l2=None, l3=None, point_covariances=None, line_covariances=None) -> float:
    """``½ Σ r²`` (the library reports ``Σ r²``)."""
    r = residuals(K, R, t, p2, p3, l2, l3, point_covariances, line_covariances)
    return 0.5 * float(r @ r)


def points_in_front(R, t, p3) -> bool:
    return bool(np.all((p3 @ R.T + t)[:, 2] > 0))


def jacobian(K, R, t, data, h=1e-7) -> np.ndarray:
    cols = []
    for i in range(6):
        d = np.zeros(6)
        d[i] = h
        cols.append((residuals(K, *step(R, t, d), *data) - residuals(K, *step(R, t, -d), *data)) / (2 * h))
    return np.column_stack(cols)


def minimise(K, R, t, data, iterations=200):
    """Levenberg-Marquardt from ``(R, t)``; returns ``(R, t, cost)``."""
    f = cost(K, R, t, *data)
    lam = 1e-3
    for _ in range(iterations):
        r = residuals(K, R, t, *data)
        J = jacobian(K, R, t, data)
        A, g = J.T @ J, J.T @ r
        improved = False
        for _ in range(30):
            d = np.linalg.solve(A + lam * np.diag(1.0 + np.diag(A)), -g)
            Rn, tn = step(R, t, d)
            fn = cost(K, Rn, tn, *data)
            if np.isfinite(fn) and fn < f:
                done = f - fn <= 1e-15 * max(f, 1e-300) or np.linalg.norm(d) < 1e-14
                R, t, f, lam, improved = Rn, tn, fn, max(lam * 0.3, 1e-12), True
                if done:
                    return R, t, f
                break
            lam *= 10.0
        if not improved:
            break
    return R, t, f


def random_rotation(rng) -> np.ndarray:
    q, r = np.linalg.qr(rng.normal(size=(3, 3)))
    q = q * np.sign(np.diag(r))
    return q * np.linalg.det(q)


def many_start(K, R0, t0, data, starts, rng):
    """Distinct local minima with every object point in front, cheapest first: ``[(R, t, cost)]``,
    from ``(R0, t0)`` and ``starts`` random rotations with the object's centroid at its depth. ``data`` is
    ``(p2, p3, l2, l3)``, or with the covariances ``(p2, p3, l2, l3, pc, lc)`` (either may be None)."""
    p3 = data[1]
    allx = np.concatenate([p3, data[3].reshape(-1, 3)]) if data[3] is not None and len(data[3]) else p3
    c = allx.mean(axis=0)
    depth = (R0 @ c + t0)[2]
    found = []
    for k in range(starts + 1):
        R = R0 if k == 0 else random_rotation(rng)
        t = t0 if k == 0 else np.array([0.0, 0.0, depth]) - R @ c
        R, t, f = minimise(K, R, t, data)
        if not (np.isfinite(f) and points_in_front(R, t, p3)):
            continue
        same = [
            i
            for i, (Rm, tm, _) in enumerate(found)
            if np.linalg.norm(log_so3(R @ Rm.T)) < 1e-5 and np.linalg.norm(t - tm) < 1e-5 * np.ptp(allx)
        ]
        if same:
            i = same[0]
            if f < found[i][2]:
                found[i] = (R, t, f)
        else:
            found.append((R, t, f))
    return sorted(found, key=lambda m: m[2])


def visible_scene(rng, focal, n_points, planar=False):
    """A 640 x 480 view at ``fx = fy = focal``: pixels uniform in the image back-projected to depths
    6 ± 30 % (or to a plane through (0, 0, 6) tilted 30-60°), seen from a random pose; returns
    ``(K, R, t, points3d, exact pixels)``."""
    K = K_of((focal, focal, 320.0, 240.0, 0.0))
    u = rng.uniform([0, 0], [640, 480], size=(n_points, 2))
    rays = np.column_stack([(u - [320, 240]) / focal, np.ones(n_points)])
    if planar:
        tilt = np.radians(rng.uniform(30, 60))
        normal = exp_so3(rng.normal(size=3) * 0.0 + np.array([tilt, 0.0, 0.0])) @ np.array([0.0, 0.0, 1.0])
        depth = 6.0 * normal[2] / (rays @ normal)
        x_cam = rays * np.clip(depth, 2, 20)[:, None]
    else:
        x_cam = rays * rng.uniform(4.2, 7.8, size=(n_points, 1))
    R = random_rotation(rng)
    t = rng.normal(size=3)
    X = (x_cam - t) @ R  # Rᵀ (x − t)
    return K, R, t, X, pixels(K, x_cam)
