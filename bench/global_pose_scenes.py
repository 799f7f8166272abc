"""The scenes of the global-minimum pose benchmark (``compare_global_pose.py``), also used by
``profile_pose.py``: the rows (correspondence mix, focal length, noise model, lens), the seeded scene
generators, the cameras with lens distortion, and the cost oracles computed here with numpy, never
taken from the library (the whitened reprojection cost, the curved endpoint distance through a lens,
and the self-test that checks them against the library on a few scenes)."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from functools import cached_property
from typing import Any

import numpy as np
import pluecker

WIDTH, HEIGHT = 640, 480
CX, CY = 320.0, 240.0
SIGMA_PX = 1.0


COV_SIGMA_PX = (0.5, 2.0)  # cov- rows: range of each axis's standard deviation, px


DEPTH_RANGE = (4.2, 7.8)


PLANE_DEPTH = 6.0


PLANE_TILT_DEG = (30.0, 60.0)


PLANE_DEPTH_RANGE = (2.0, 20.0)


MIN_SEGMENT_PX = 20.0


WORLD_OFFSET = 5.0


ROTATION_TOLERANCE = 1e-6  # max |R Rᵀ − I| of a valid rotation (the library's for a rotation argument)


# Distorting cameras of the lens- rows: COLMAP model and its distortion parameters (the camera's are f, f,
# CX, CY before them). mild and strong: OPENCV k1, k2, p1, p2; fisheye: OPENCV_FISHEYE k1..k4.
LENSES: dict[str, tuple[str, tuple[float, ...]]] = {
    "mild": ("OPENCV", (-0.05, 0.01, 1e-4, -1e-4)),
    "strong": ("OPENCV", (-0.3, 0.1, 1e-3, -5e-4)),
    "fisheye": ("OPENCV_FISHEYE", (0.05, -0.01, 0.002, -0.0005)),
}


CURVE_SAMPLES = 256  # viewing angles sampled along a projected line for the curved endpoint distance


CURVE_NEWTON_STEPS = 6  # Newton steps along the line from the best sample


CURVE_DIFF_STEP = 1e-5  # radians: the central differences of the Newton steps


LENS_SELF_TEST_SCENES = 2  # scenes per selected lens row on which the own cost is checked against the library's


LENS_PROJECTION_TOL_PX = 1e-9  # own projection against Camera.project


LENS_COST_TOL = 1e-8  # own lens cost against the library's result.cost, relative


@dataclass(frozen=True)
class Row:
    name: str
    source: str  # "synthetic" or "random_scene"
    n_points: int
    n_lines: int
    f: float = 800.0
    planar: bool = False
    kind: str = ""  # random_scene kind
    covariances: bool = False  # per-observation covariances (the cov- rows)
    lens: str = ""  # a key of LENSES: the camera distorts (the lens- rows); "": pinhole

    @property
    def n(self) -> int:
        return self.n_points + self.n_lines

    @property
    def data(self) -> str:
        if self.n_lines == 0:
            return "points"
        return "lines" if self.n_points == 0 else "mixed"

    @property
    def pinhole_pair(self) -> str | None:
        """A lens row's pinhole row, same f and composition (its name without ``lens-<lens>-``)."""
        return self.name.removeprefix(f"lens-{self.lens}-") if self.lens else None


def _split(n: int, data: str) -> tuple[int, int]:
    """(points, segments) of ``n`` correspondences of kind ``data``: mixed is ``ceil(n/2)`` + ``floor(n/2)``."""
    return {"points": (n, 0), "lines": (0, n), "mixed": ((n + 1) // 2, n // 2)}[data]


def all_rows() -> list[Row]:
    rows = []
    for f in (250.0, 800.0, 4000.0, 15000.0):
        for n in (4, 6, 10, 100):
            for data in ("points", "lines", "mixed"):
                rows.append(Row(f"f{f:g}-n{n}-{data}", "synthetic", *_split(n, data), f=f))
    for f in (800.0, 4000.0):
        for n in (4, 6, 10, 100):
            for data in ("points", "mixed"):
                rows.append(Row(f"planar-f{f:g}-n{n}-{data}", "synthetic", *_split(n, data), f=f, planar=True))
    for kind in ("general", "planar", "far"):
        rows.append(Row(f"rs-{kind}-100p", "random_scene", 100, 0, kind=kind))
        rows.append(Row(f"rs-{kind}-50p20l", "random_scene", 50, 20, kind=kind))
    for f in (800.0, 4000.0, 15000.0):
        for n in (10, 100):
            for data in ("points", "mixed"):
                rows.append(Row(f"cov-f{f:g}-n{n}-{data}", "synthetic", *_split(n, data), f=f, covariances=True))
    lens_mixes = ((100, "points"), (10, "points"), (10, "mixed"), (100, "mixed"), (10, "lines"))
    for lens, focals, mixes in (
        ("mild", (250.0, 800.0, 4000.0, 15000.0), lens_mixes),
        ("strong", (250.0, 800.0, 4000.0, 15000.0), lens_mixes),
        ("fisheye", (250.0, 800.0), ((100, "points"), (100, "mixed"))),
    ):
        for f in focals:
            for n, data in mixes:
                rows.append(Row(f"lens-{lens}-f{f:g}-n{n}-{data}", "synthetic", *_split(n, data), f=f, lens=lens))
    return rows


@dataclass(frozen=True)
class Lens:
    """A distorting camera of COLMAP's ``model`` (OPENCV, RADIAL or OPENCV_FISHEYE), ``fx = fy = f``,
    principal point (CX, CY), distortion ``k`` in COLMAP's order, in this script's own numpy code: the
    pixel of normalised coordinates ``n = (x/z, y/z)`` is ``K D(n)``. OPENCV:
    ``D(n) = n (1 + k1 r² + k2 r⁴) + (2 p1 x y + p2 (r² + 2 x²), p1 (r² + 2 y²) + 2 p2 x y)``, ``r = |n|``;
    RADIAL: the same without p1, p2; OPENCV_FISHEYE: ``D(n) = n θ_d / r``, ``θ = atan r``,
    ``θ_d = θ (1 + k1 θ² + k2 θ⁴ + k3 θ⁶ + k4 θ⁸)``."""

    model: str
    k: tuple[float, ...]
    f: float

    @property
    def params(self) -> list[float]:
        """The camera's parameters in COLMAP's order (RADIAL has one focal length)."""
        return [self.f, CX, CY, *self.k] if self.model == "RADIAL" else [self.f, self.f, CX, CY, *self.k]

    def camera(self) -> Any:
        return pluecker.Camera(self.model, self.params)

    def distort(self, n: np.ndarray) -> np.ndarray:
        """``D(n)`` of normalised coordinates ``n`` (..., 2)."""
        x, y = n[..., 0], n[..., 1]
        r2 = x * x + y * y
        if self.model == "OPENCV_FISHEYE":
            r = np.sqrt(r2)
            theta = np.arctan(r)
            t2 = theta * theta
            k1, k2, k3, k4 = self.k
            theta_d = theta * (1.0 + t2 * (k1 + t2 * (k2 + t2 * (k3 + t2 * k4))))
            tiny = r < 1e-12  # θ_d / r → 1 on the axis
            return n * np.where(tiny, 1.0, theta_d / np.where(tiny, 1.0, r))[..., None]
        k1, k2 = self.k[:2]
        radial = 1.0 + r2 * (k1 + k2 * r2)
        xd, yd = x * radial, y * radial
        if self.model == "OPENCV":
            p1, p2 = self.k[2:]
            xd = xd + 2.0 * p1 * x * y + p2 * (r2 + 2.0 * x * x)
            yd = yd + p1 * (r2 + 2.0 * y * y) + 2.0 * p2 * x * y
        return np.stack([xd, yd], axis=-1)

    def pixels(self, n: np.ndarray) -> np.ndarray:
        """Distorted pixels ``K D(n)`` (..., 2) of normalised coordinates ``n`` (..., 2)."""
        return self.distort(n) * self.f + np.array([CX, CY])

    @cached_property
    def fold_radius(self) -> float:
        """``|n|`` where the radial distortion stops increasing (inf when it never does; the library's
        invertible region): the first positive root ``s`` of ``1 + 3 k1 s + 5 k2 s² (+ 7 k3 s³ + 9 k4 s⁴)``,
        ``s = r²`` (fisheye: ``θ²``, the radius then ``tan θ``, inf beyond 90°)."""
        k = self.k if self.model == "OPENCV_FISHEYE" else self.k[:2]
        roots = np.roots([(2 * i + 3) * c for i, c in reversed(list(enumerate(k)))] + [1.0])
        real = [z.real for z in roots if abs(z.imag) <= 1e-12 * abs(z) and z.real > 0.0]
        if not real:
            return math.inf
        if self.model == "OPENCV_FISHEYE":
            theta = math.sqrt(min(real))
            return math.tan(theta) if theta < math.pi / 2 else math.inf
        return math.sqrt(min(real))


@dataclass
class Scene:
    """One noisy problem with its truth, ``x_cam = R X + t``."""

    seed: int
    camera: Any
    K: np.ndarray
    R: np.ndarray
    t: np.ndarray
    points2d: np.ndarray  # (N, 2) noisy pixels
    points3d: np.ndarray  # (N, 3) world
    lines2d: np.ndarray  # (M, 2, 2) noisy endpoints
    lines3d: np.ndarray  # (M, 2, 3) world endpoints
    planar: bool
    point_covariances: np.ndarray | None = None  # (N, 2, 2) px², cov- rows only (both or neither)
    line_covariances: np.ndarray | None = None  # (M, 2, 2, 2) px², per endpoint, cov- rows only
    lens: Lens | None = None  # lens- rows: the observations are distorted pixels through this lens
    all3d: np.ndarray = field(init=False, repr=False)  # every point and endpoint, (N + 2M, 3)
    centroid: np.ndarray = field(init=False, repr=False)
    depth: float = field(init=False)

    def __post_init__(self) -> None:
        self.all3d = np.vstack([self.points3d.reshape(-1, 3), self.lines3d.reshape(-1, 3)])
        self.centroid = self.all3d.mean(axis=0)
        self.depth = float((self.R @ self.centroid + self.t)[2])

    @property
    def kwargs(self) -> dict[str, Any]:
        """The data as ``estimate_pose`` keywords, None for an absent kind."""
        has_p, has_l = len(self.points3d) > 0, len(self.lines3d) > 0
        return {
            "points2d": self.points2d if has_p else None,
            "points3d": self.points3d if has_p else None,
            "lines2d": self.lines2d if has_l else None,
            "lines3d": self.lines3d if has_l else None,
        }

    @property
    def noise_kwargs(self) -> dict[str, Any]:
        """The covariances as ``estimate_pose`` keywords (empty without them)."""
        out: dict[str, Any] = {}
        if self.point_covariances is not None and len(self.points3d):
            out["point_covariances"] = self.point_covariances
        if self.line_covariances is not None and len(self.lines3d):
            out["line_covariances"] = self.line_covariances
        return out


def random_rotation(rng: np.random.Generator) -> np.ndarray:
    """Uniform on SO(3): a normalised Gaussian quaternion."""
    q = rng.normal(size=4)
    w, x, y, z = q / np.linalg.norm(q)
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
            [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
            [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
        ]
    )


def _draw_point(
    rng: np.random.Generator, f: float, plane: tuple[np.ndarray, float] | None, lens: Lens | None = None
) -> tuple[np.ndarray, np.ndarray]:
    """A camera-frame point visible in the image, and its clean pixel. Through a lens the pixel is drawn
    in the image of its pinhole part (undistorted) and distorted by ``Lens.pixels``; drawn again when the
    distorted pixel leaves the image or the point lies beyond the lens's fold radius."""
    while True:
        uv = np.array([rng.uniform(0.0, WIDTH), rng.uniform(0.0, HEIGHT)])
        ray = np.array([(uv[0] - CX) / f, (uv[1] - CY) / f, 1.0])
        if plane is None:
            z = rng.uniform(*DEPTH_RANGE)
        else:
            normal, offset = plane  # n · x = offset
            denom = float(normal @ ray)
            if abs(denom) < 1e-12:
                continue
            z = offset / denom
            if not PLANE_DEPTH_RANGE[0] <= z <= PLANE_DEPTH_RANGE[1]:
                continue
        if lens is not None:
            if not math.hypot(ray[0], ray[1]) < lens.fold_radius:
                continue
            uv = lens.pixels(ray[:2])
            if not (0.0 <= uv[0] <= WIDTH and 0.0 <= uv[1] <= HEIGHT):
                continue
        return z * ray, uv


def make_synthetic(row: Row, seed: int) -> Scene:
    rng = np.random.default_rng(seed)
    lens = Lens(*LENSES[row.lens], row.f) if row.lens else None
    R = random_rotation(rng)
    plane = None
    if row.planar:
        tilt = math.radians(rng.uniform(*PLANE_TILT_DEG))
        azimuth = rng.uniform(0.0, 2.0 * math.pi)
        normal = np.array([math.sin(tilt) * math.cos(azimuth), math.sin(tilt) * math.sin(azimuth), math.cos(tilt)])
        plane = (normal, float(normal @ np.array([0.0, 0.0, PLANE_DEPTH])))
    pts_cam, pts_px = [], []
    for _ in range(row.n_points):
        x, uv = _draw_point(rng, row.f, plane, lens)
        pts_cam.append(x)
        pts_px.append(uv)
    seg_cam, seg_px = [], []
    for _ in range(row.n_lines):
        while True:
            a, ua = _draw_point(rng, row.f, plane, lens)
            b, ub = _draw_point(rng, row.f, plane, lens)
            if np.linalg.norm(ua - ub) >= MIN_SEGMENT_PX:
                break
        seg_cam.append([a, b])
        seg_px.append([ua, ub])
    pts_cam_a = np.array(pts_cam).reshape(-1, 3)
    seg_cam_a = np.array(seg_cam).reshape(-1, 2, 3)
    c = np.vstack([pts_cam_a, seg_cam_a.reshape(-1, 3)]).mean(axis=0)
    o = rng.uniform(-WORLD_OFFSET, WORLD_OFFSET, 3)
    t = c - R @ o
    # X = Rᵀ (x_cam − c) + o, row-wise: (x_cam − c) R + o
    p3 = (pts_cam_a - c) @ R + o
    l3 = (seg_cam_a - c) @ R + o
    p2 = np.array(pts_px).reshape(-1, 2)
    l2 = np.array(seg_px).reshape(-1, 2, 2)
    pinhole = pluecker.Camera.pinhole(row.f, row.f, CX, CY)  # the lens's pinhole part too
    camera = lens.camera() if lens else pinhole
    K = np.asarray(pinhole.K, float)
    if row.covariances:
        (pn, pc), (ln, lc) = _anisotropic_noise(rng, len(p2)), _anisotropic_noise(rng, 2 * len(l2))
        p2, l2, lc = p2 + pn, l2 + ln.reshape(l2.shape), lc.reshape(-1, 2, 2, 2)
        return Scene(seed, camera, K, R, t, p2, p3, l2, l3, row.planar, pc, lc, lens)
    p2 = p2 + rng.normal(0.0, SIGMA_PX, p2.shape)
    l2 = l2 + rng.normal(0.0, SIGMA_PX, l2.shape)
    return Scene(seed, camera, K, R, t, p2, p3, l2, l3, row.planar, lens=lens)


def _anisotropic_noise(rng: np.random.Generator, k: int) -> tuple[np.ndarray, np.ndarray]:
    """``k`` covariances ``Σ = R(φ) diag(σ₁², σ₂²) R(φ)ᵀ`` (σ uniform in ``COV_SIGMA_PX``, φ uniform in
    [0, π)) and a noise vector drawn from each, ``R(φ) diag(σ₁, σ₂) z``: ``((k, 2), (k, 2, 2))``."""
    sig = rng.uniform(*COV_SIGMA_PX, size=(k, 2))
    phi = rng.uniform(0.0, math.pi, size=k)
    c, s = np.cos(phi), np.sin(phi)
    rot = np.stack([np.stack([c, -s], axis=-1), np.stack([s, c], axis=-1)], axis=-2)  # (k, 2, 2)
    half = rot * sig[:, None, :]  # R diag(σ): Σ = half halfᵀ
    noise = np.einsum("kij,kj->ki", half, rng.normal(size=(k, 2)))
    return noise, half @ np.swapaxes(half, 1, 2)


def make_random_scene(row: Row, seed: int) -> Scene:
    """As ``bench/compare_pose.py``: ``random_scene`` and noise from ``default_rng(seed)``."""
    raw = pluecker.random_scene(row.kind, row.n_points, row.n_lines, seed)
    camera = raw["camera"]
    p2 = np.asarray(raw["points2d"], dtype=float).reshape(-1, 2)
    l2 = np.asarray(raw["lines2d"], dtype=float).reshape(-1, 2, 2)
    rng = np.random.default_rng(seed)
    p2 = p2 + rng.normal(0.0, SIGMA_PX, p2.shape)
    l2 = l2 + rng.normal(0.0, SIGMA_PX, l2.shape)
    return Scene(
        seed,
        camera,
        np.asarray(camera.K, float),
        np.asarray(raw["R"], float),
        np.asarray(raw["t"], float),
        p2,
        np.asarray(raw["points3d"], float).reshape(-1, 3),
        l2,
        np.asarray(raw["lines3d"], float).reshape(-1, 2, 3),
        row.kind == "planar",
    )


def make_scene(row: Row, seed: int) -> Scene:
    return make_synthetic(row, seed) if row.source == "synthetic" else make_random_scene(row, seed)


def pose_cost(scene: Scene, R: Any, t: Any) -> float:
    """``½ (Σ_points e² + Σ_endpoints d²)`` px² at ``(R, t)`` (the whitened ``½ Σ r²`` on a scene with
    covariances); +inf for an invalid pose (non-finite, not a rotation, or a point or endpoint at depth
    <= 0)."""
    try:
        R = np.asarray(R, dtype=float).reshape(3, 3)
        t = np.asarray(t, dtype=float).reshape(3)
    except (TypeError, ValueError):
        return math.inf
    if not (np.all(np.isfinite(R)) and np.all(np.isfinite(t))):
        return math.inf
    if np.max(np.abs(R @ R.T - np.eye(3))) > ROTATION_TOLERANCE or np.linalg.det(R) <= 0.0:
        return math.inf
    if np.any(scene.all3d @ R[2] + t[2] <= 0.0):
        return math.inf
    c = _whitened_cost(scene, R, t)
    return c if math.isfinite(c) else math.inf


def _whitened_cost(scene: Scene, R: np.ndarray, t: np.ndarray) -> float:
    """``½ Σ r²`` with the scene's covariances (see the module docstring; the identity without them), at
    a valid pose: a point's ``eᵀ Σ⁻¹ e``, an endpoint's ``d² / (n̂ᵀ Σ n̂)``; through a lens a point's
    ``e`` is to ``Lens.pixels`` and an endpoint's ``r²`` its squared distance to the curved image of the
    projected line (``curve_distance2``). This script's own code, not the library's residuals: the
    certified bounds are checked against it."""

    def pixels(X: np.ndarray) -> np.ndarray:
        if scene.lens is not None:
            x = X @ R.T + t
            return scene.lens.pixels(x[:, :2] / x[:, 2:3])
        x = (X @ R.T + t) @ scene.K.T
        return x[:, :2] / x[:, 2:3]

    total = 0.0
    if len(scene.points3d):
        e = pixels(scene.points3d) - scene.points2d
        if scene.point_covariances is None:
            total += float(np.sum(e**2))
        else:
            total += float(np.einsum("ni,ni->", e, np.linalg.solve(scene.point_covariances, e[..., None])[..., 0]))
    if len(scene.lines3d) and scene.lens is not None:
        x = scene.lines3d @ R.T + t  # (M, 2, 3) camera frame
        lines = np.repeat(np.cross(x[:, 0], x[:, 1]), 2, axis=0)  # ℓ of each endpoint, normalised coordinates
        info = None if scene.line_covariances is None else np.linalg.inv(scene.line_covariances.reshape(-1, 2, 2))
        total += float(np.sum(curve_distance2(scene.lens, lines, scene.lines2d.reshape(-1, 2), info)))
    elif len(scene.lines3d):
        ends = pixels(scene.lines3d.reshape(-1, 3)).reshape(-1, 2, 2)
        d = ends[:, 1] - ends[:, 0]
        n = np.stack([-d[:, 1], d[:, 0]], axis=1) / np.linalg.norm(d, axis=1)[:, None]
        dist = np.einsum("mkj,mj->mk", scene.lines2d - ends[:, :1], n)
        if scene.line_covariances is None:
            total += float(np.sum(dist**2))
        else:
            total += float(np.sum(dist**2 / np.einsum("mi,mkij,mj->mk", n, scene.line_covariances, n)))
    return 0.5 * total


def curve_distance2(lens: Lens, lines: np.ndarray, e: np.ndarray, info: np.ndarray | None = None) -> np.ndarray:
    """Squared distance (K,), px² (``(u − e)ᵀ info (u − e)`` with ``info`` (K, 2, 2), ``C⁻¹``), of each
    observed pixel ``e`` (K, 2) to the curved image ``u(q) = K D(q)`` of its line ``ℓ`` of normalised
    coordinates, ``l·(q, 1) = 0``, ``lines`` (K, 3): the least over the points ``q`` of ``ℓ`` inside the
    lens's fold radius (the branch of the curve through the observation, the whole of ``ℓ`` for the
    lenses here). ``ℓ`` is parametrised by the viewing angle ``φ`` within its plane through the camera
    centre, ``q(φ) = q₀ + √(1 + l₂²) tan φ · d`` (``l`` scaled to ``|(l₀, l₁)| = 1``, ``q₀ = −l₂ (l₀, l₁)``
    the foot of the principal point on ``ℓ``, ``d`` its direction), which covers the whole line;
    ``CURVE_SAMPLES`` angles spread evenly over the branch, then ``CURVE_NEWTON_STEPS`` Newton steps
    (derivatives of ``u(φ)`` by central differences; Gauss-Newton where the curvature is not positive)
    from the best sample, kept within its two neighbours. The answer is the least value met, so never
    below the true minimum. NaN where ``ℓ`` does not exist or misses the fold radius."""
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        h = lines / np.linalg.norm(lines[:, :2], axis=1, keepdims=True)
        foot = -h[:, 2:3] * h[:, :2]
        direction = np.stack([-h[:, 1], h[:, 0]], axis=1)
        scale = np.sqrt(1.0 + h[:, 2] ** 2)
        reach = np.sqrt(lens.fold_radius**2 - h[:, 2] ** 2)  # |τ| inside the fold (inf without one, NaN: missed)
        phi_max = np.arctan2(reach, scale)

        def pixels(phi: np.ndarray) -> np.ndarray:  # (K, S) angles -> (K, S, 2) pixels
            return lens.pixels(foot[:, None] + (scale[:, None] * np.tan(phi))[..., None] * direction[:, None])

        def dist2(a: np.ndarray, b: np.ndarray) -> np.ndarray:  # aᵀ info b over the last axis
            return np.sum(a * b, axis=-1) if info is None else np.einsum("ksi,kij,ksj->ks", a, info, b)

        grid = phi_max[:, None] * ((2.0 * np.arange(CURVE_SAMPLES) + 1.0 - CURVE_SAMPLES) / CURVE_SAMPLES)
        r = pixels(grid) - e[:, None]
        values = dist2(r, r)
        values = np.where(np.isfinite(values), values, np.inf)
        pick = np.argmin(values, axis=1)
        rows = np.arange(len(h))
        phi, least = grid[rows, pick], values[rows, pick]
        step = 2.0 * phi_max / CURVE_SAMPLES
        lo, hi = np.maximum(phi - step, -phi_max), np.minimum(phi + step, phi_max)
        hd = CURVE_DIFF_STEP
        for _ in range(CURVE_NEWTON_STEPS):
            u = pixels(phi[:, None] + np.array([-hd, 0.0, hd]))
            r, du = u[:, 1:2] - e[:, None], (u[:, 2:] - u[:, :1]) / (2.0 * hd)
            ddu = (u[:, 2:] - 2.0 * u[:, 1:2] + u[:, :1]) / hd**2
            value, grad, gauss = dist2(r, r)[:, 0], dist2(du, r)[:, 0], dist2(du, du)[:, 0]
            least = np.minimum(least, np.where(np.isfinite(value), value, np.inf))
            curvature = gauss + dist2(ddu, r)[:, 0]
            phi = np.clip(phi - grad / np.where(curvature > 0.0, curvature, gauss), lo, hi)
        r = pixels(phi[:, None]) - e[:, None]
        value = dist2(r, r)[:, 0]
        least = np.minimum(least, np.where(np.isfinite(value), value, np.inf))
    return np.where(np.isfinite(phi_max) & np.isfinite(least), least, np.nan)
