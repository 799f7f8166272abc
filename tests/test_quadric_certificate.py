"""The quadric certificate (issue 13 §2): on the discs of the reproduction's Table 3 (and on discs with
3 views, anisotropic covariances, focal lengths of 250 and 15000 px and mirrored cameras), a certified lower
bound is never above the cost of any ellipsoid of its domain — every ellipsoid, flat ones included,
that no camera's principal plane cuts, in front of the cameras or behind them — found by dense
sampling across the whole domain, near every camera, by many-start descent and near the answer.

The cost of eq. 19 is recomputed here in numpy from the paper's definitions (eq. 10 for the dual
quadric, eqs. 12-13 for its image, the residual of section 3.1 in the frame of the observed ellipse,
eq. 18 for the covariance), vectorised over candidates; it agrees with the library's reported cost.
"""

from __future__ import annotations

import numpy as np
import pytest

import pluecker
from pluecker.experiments.josephson_kahl_2008.conics import _look_at, disc_scene, ellipse_points

GAP = 1e-3


def dual_quadrics(x: np.ndarray) -> np.ndarray:
    """(K, 9) rows (centre, rotation vector, signed semi-axes) → (K, 4, 4) dual quadrics
    ``H diag(s², −1) Hᵀ`` (eq. 10), ``H = [R c; 0 1]``."""
    c, w, s = x[:, :3], x[:, 3:6], x[:, 6:9]
    theta = np.linalg.norm(w, axis=1)[:, None, None]
    k = np.zeros((len(x), 3, 3))
    k[:, 0, 1], k[:, 0, 2], k[:, 1, 2] = -w[:, 2], w[:, 1], -w[:, 0]
    k = k - np.swapaxes(k, 1, 2)
    safe = np.where(theta > 1e-12, theta, 1.0)
    R = np.eye(3) + np.sin(safe) / safe * k + (1 - np.cos(safe)) / safe**2 * (k @ k)
    H = np.zeros((len(x), 4, 4))
    H[:, :3, :3], H[:, :3, 3], H[:, 3, 3] = R, c, 1.0
    D = np.zeros((len(x), 4, 4))
    D[:, 0, 0], D[:, 1, 1], D[:, 2, 2], D[:, 3, 3] = s[:, 0] ** 2, s[:, 1] ** 2, s[:, 2] ** 2, -1.0
    return H @ D @ np.swapaxes(H, 1, 2)


def costs(P: np.ndarray, conics: np.ndarray, cov: np.ndarray, Q: np.ndarray) -> np.ndarray:
    """Eq. 19 for each dual quadric of ``Q`` (K, 4, 4): per view the image dual conic ``P Q Pᵀ`` and the
    observed one, both in the frame centred on the observed ellipse, ``v(e) = (e₁₁, e₁₂, e₂₂, e₁₃, e₂₃)/e₃₃``,
    and the Mahalanobis norm of their difference."""
    total = np.zeros(len(Q))
    for p, c, s in zip(P, conics, cov):
        observed = np.linalg.inv(c)
        x0 = observed[:2, 2] / observed[2, 2]
        T = np.array([[1.0, 0.0, -x0[0]], [0.0, 1.0, -x0[1]], [0.0, 0.0, 1.0]])
        v = lambda e: np.stack([e[..., 0, 0], e[..., 0, 1], e[..., 1, 1], e[..., 0, 2], e[..., 1, 2]], -1) / e[..., 2:3, 2]  # noqa: E731
        r = v(T @ p @ Q @ p.T @ T.T) - v(T @ observed @ T.T)
        total += np.einsum("ki,ij,kj->k", r, np.linalg.inv(s), r)
    return total


def in_domain(P: np.ndarray, Q: np.ndarray) -> np.ndarray:
    """No principal plane ``πᵢ = Pᵢ[2]`` cuts the ellipsoid: ``πᵀ Q π < 0`` (``Q₄₄ = −1``)."""
    return np.all(np.einsum("vi,kij,vj->kv", P[:, 2], Q, P[:, 2]) < 0, axis=1)


def domain_costs(P, conics, cov, x: np.ndarray) -> np.ndarray:
    """Eq. 19 at ellipsoids (K, 9), ``inf`` outside the domain."""
    Q = dual_quadrics(x)
    return np.where(in_domain(P, Q), costs(P, conics, cov, Q), np.inf)


def random_ellipsoids(rng, n: int, centre: np.ndarray, reach: float, largest: float) -> np.ndarray:
    """Centres uniform within ``reach`` of ``centre``, uniform rotation vectors, semi-axes log-uniform in
    [largest/100, largest], a third of them flat."""
    x = np.empty((n, 9))
    x[:, :3] = centre + rng.uniform(-reach, reach, (n, 3))
    x[:, 3:6] = rng.uniform(-np.pi, np.pi, (n, 3))
    x[:, 6:9] = largest * 10 ** rng.uniform(-2, 0, (n, 3))
    x[rng.random(n) < 1 / 3, 8] = 0.0
    return x


def least_cost_found(P, conics, cov, answer: np.ndarray, rng) -> np.ndarray:
    """Every cost evaluated: 20000 ellipsoids across the domain (a box 24 units wide around the disc and
    its cameras, 6-10 units away), 1000 small ones within 2 units of each camera centre, a random
    descent of 500 steps from the 20 cheapest (many starts; flat ones reachable), and the answer moved
    by 1e-1 to 1e-5 (half of them flattened)."""
    centres = np.array([-np.linalg.solve(p[:, :3], p[:, 3]) for p in P])
    samples = [random_ellipsoids(rng, 20000, answer[:3], 12.0, 3.0)]
    samples += [random_ellipsoids(rng, 1000, c, 2.0, 0.5) for c in centres]
    x = np.concatenate(samples)
    found = [domain_costs(P, conics, cov, x)]
    order = np.argsort(found[0])[:20]
    best, at = found[0][order], x[order]
    step = np.full(len(at), 0.3)
    for _ in range(500):
        trial = at + step[:, None] * rng.normal(size=at.shape)
        c = domain_costs(P, conics, cov, trial)
        better = c < best
        best, at = np.where(better, c, best), np.where(better[:, None], trial, at)
        step = np.where(better, step, step * 0.99)
    found.append(best)
    scales = 10.0 ** -(1 + np.arange(1000) % 5)
    near = answer + scales[:, None] * rng.normal(size=(1000, 9))
    near[::2, 8] = 0.0
    found.append(domain_costs(P, conics, cov, near))
    return np.concatenate(found)


def answer_parameters(r) -> np.ndarray:
    """(centre, rotation vector, semi-axes) of a result."""
    R = r.axes if np.linalg.det(r.axes) > 0 else r.axes @ np.diag([1.0, 1.0, -1.0])
    angle = np.arccos(np.clip((np.trace(R) - 1) / 2, -1, 1))
    axis = np.array([R[2, 1] - R[1, 2], R[0, 2] - R[2, 0], R[1, 0] - R[0, 1]])
    w = axis / (2 * np.sin(angle)) * angle if angle > 1e-9 else np.zeros(3)
    return np.concatenate([r.centre, w, r.semi_axes])


def disc_with(seed: int, focal: float, views: int, mirrored: bool):
    """A Table 3 disc (``disc_scene``'s geometry) seen with focal length ``focal`` from ``focal / 100``
    units (the disc keeps its size in pixels: a narrow field of view at 15000 px); ``mirrored`` flips
    the x axis of every other camera's calibration (``det M < 0``, still in front). Conics fitted to 63
    points with 1 px noise: (P, conics, covariances)."""
    rng = np.random.default_rng([seed, 77])
    K = np.array([[focal, 0.0, 500.0], [0.0, focal, 500.0], [0.0, 0.0, 1.0]])
    centre, (axes, _) = rng.uniform(-0.5, 0.5, 3), np.linalg.qr(rng.normal(size=(3, 3)))
    H = np.eye(4)
    H[:3, :3], H[:3, 3] = axes, centre
    dual = H @ np.diag([rng.uniform(0.8, 1.5) ** 2, rng.uniform(0.4, 0.8) ** 2, 0.0, -1.0]) @ H.T
    P, conics, cov = [], [], []
    while len(P) < views:
        d = rng.normal(size=3)
        d /= np.linalg.norm(d)
        if abs(d @ axes[:, 2]) < 0.5:
            continue
        eye = centre + rng.uniform(0.75, 1.25) * focal / 100 * d
        R = _look_at(eye, centre + rng.normal(0, 0.2, 3), rng.uniform(-0.3, 0.3))
        flip = np.diag([-1.0, 1.0, 1.0]) if mirrored and len(P) % 2 == 0 else np.eye(3)
        p = K @ flip @ np.hstack([R, (-R @ eye)[:, None]])
        points = ellipse_points(np.linalg.inv(p @ dual @ p.T), 63, rng.uniform(0, 2 * np.pi))
        fit = pluecker.fit_conic(points + rng.normal(0, 1.0, points.shape), sigma=1.0)
        P.append(p)
        conics.append(np.asarray(fit.conic))
        cov.append(np.asarray(fit.covariance))
    return np.array(P), np.array(conics), np.array(cov)


def regime_problem(regime: str, k: int):
    """(P, conics, covariances) of a regime of the test below."""
    if regime in ("table 3 disc", "3 views", "anisotropic covariances"):
        scene = disc_scene(k * 100_003, views=3 if regime == "3 views" else 5)
        cov = scene.covariances
        if regime == "anisotropic covariances":
            scale = np.diag([3.0, 1.0, 0.3, 2.0, 0.5])
            cov = scale @ cov @ scale
        return scene.cameras, scene.conics, cov
    focal = {"f = 250 px": 250.0, "f = 15000 px": 15000.0}.get(regime, 800.0)
    return disc_with(k, focal, 3 if k % 2 else 5, mirrored=regime == "mirrored cameras")


SCENES = [("table 3 disc", k) for k in range(6)] + [
    ("3 views", 7), ("anisotropic covariances", 8), ("f = 250 px", 1), ("f = 250 px", 2), ("f = 15000 px", 1),
    ("f = 15000 px", 2), ("mirrored cameras", 1), ("mirrored cameras", 2)]


@pytest.mark.parametrize(("regime", "k"), SCENES, ids=[f"{s[0]}-{s[1]}" for s in SCENES])
def test_no_ellipsoid_of_the_domain_costs_less_than_the_certified_bound(regime, k):
    P, conics, cov = regime_problem(regime, k)
    r = pluecker.triangulate_quadric(P, conics, cov, options=pluecker.TriangulationOptions(method="optimal"))
    # Every disc of these kinds is certified by the convexity test (30 of 30 in the reproduction, 29 of
    # 29 in the Rust regimes, 96 of 96 at 250-15000 px and mirrored): a failure means certification broke.
    assert r.certified and r.certificate.kind == "convexity_test" and r.status == "success", r
    assert "principal plane" in r.certificate.domain
    x = answer_parameters(r)
    reported = costs(P, conics, cov, dual_quadrics(x[None]))[0]
    assert reported == pytest.approx(r.cost, rel=1e-7), "the independent cost disagrees with the library's"
    found = least_cost_found(P, conics, cov, x, np.random.default_rng(k))
    slack = 1e-9 * (1 + r.cost)
    # The raw bound (before the library's cap at its cost) against numpy's costs: of the answer, of
    # everything the search found; the gap recomputed from the answer's cost and the raw bound.
    raw = r.certificate.raw_lower_bound
    assert raw <= reported * (1 + 1e-7), (raw, reported)
    assert (reported - min(raw, reported)) / reported <= GAP * (1 + 1e-4), (raw, reported)
    violations = int(np.sum(found < raw - slack))
    assert violations == 0, f"{violations} ellipsoids below the bound {raw} (least {found.min()})"
    assert found.min() >= r.cost * (1 - GAP) - slack


def quadric_of(q: np.ndarray) -> np.ndarray:
    """The symmetric 4x4 with ``Q₄₄ = −1`` and the other 9 upper-triangle entries ``q`` (any quadric)."""
    Q = np.zeros((4, 4))
    Q[np.triu_indices(4)] = np.append(q, -1.0)
    return Q + np.triu(Q, 1).T


def test_the_best_quadric_is_often_no_ellipsoid_which_the_certificate_excludes():
    """Over every quadric (the domain of a relaxation that does not impose ``S ⪰ 0``) the best fit to a
    disc's outlines is often slightly hyperbolic: the smallest eigenvalue of the shape ``S`` estimated
    below 0. Then no bound over all quadrics can certify the disc, and the certificate's bound, which is
    over ellipsoids, lies above that quadric's cost. Measured on the 30 discs of the reproduction: 19
    beaten by more than the gap. Gauss-Newton on the 9 free entries, numerical Jacobian."""
    beaten = 0
    for k in (0, 2, 4):
        scene = disc_scene(k * 100_003)
        P, conics, cov = scene.cameras, scene.conics, scene.covariances
        r = pluecker.triangulate_quadric(P, conics, cov, options=pluecker.TriangulationOptions(method="optimal"))
        whiten = [np.linalg.cholesky(np.linalg.inv(s)) for s in cov]
        cost = lambda q: costs(P, conics, cov, quadric_of(q)[None])[0]  # noqa: E731

        def residuals(q):
            Q = quadric_of(q)
            out = []
            for p, c, w in zip(P, conics, whiten):
                observed = np.linalg.inv(c)
                x0 = observed[:2, 2] / observed[2, 2]
                T = np.array([[1.0, 0.0, -x0[0]], [0.0, 1.0, -x0[1]], [0.0, 0.0, 1.0]])
                v = lambda e: np.array([e[0, 0], e[0, 1], e[1, 1], e[0, 2], e[1, 2]]) / e[2, 2]  # noqa: E731
                out.append(w.T @ (v(T @ p @ Q @ p.T @ T.T) - v(T @ observed @ T.T)))
            return np.concatenate(out)

        q = r.Q[np.triu_indices(4)][:9]
        for _ in range(30):
            f = residuals(q)
            J = np.stack([(residuals(q + e) - residuals(q - e)) / (2 * e.max()) for e in np.eye(9) * 1e-7], axis=1)
            trial = q + np.linalg.lstsq(J, -f, rcond=None)[0]
            if not cost(trial) < cost(q):
                break
            q = trial
        Q = quadric_of(q)
        shape = Q[:3, :3] + np.outer(Q[:3, 3], Q[:3, 3])
        assert cost(q) == pytest.approx(np.sum(residuals(q) ** 2), rel=1e-9)
        if cost(q) < r.cost * (1 - GAP):
            beaten += 1
            assert np.linalg.eigvalsh(shape)[0] < 0, "a cheaper quadric that is an ellipsoid: the disc was not optimal"
            assert r.certificate.raw_lower_bound > cost(q), "the bound should be over ellipsoids only"
    assert beaten >= 2, beaten  # measured: all three
