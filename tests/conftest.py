"""Shared fixtures and helpers for the Python tests.

Seeds derive from the test's name (so each test has its own stream, stable across runs and
orderings), and every assertion helper puts the seed in its failure message.
"""

from __future__ import annotations

import os
import zlib

import numpy as np
import pytest
from hypothesis import HealthCheck, settings

import pluecker

# Property tests (hypothesis). "ci", the default, is deterministic and small enough for every
# `make test`; PLUECKER_HYPOTHESIS=nightly explores 40x more examples from a fresh random seed each run
# (a failure prints the example and how to reproduce it).
settings.register_profile("ci", max_examples=60, deadline=None, derandomize=True, print_blob=True,
                          suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])
settings.register_profile("nightly", max_examples=2500, deadline=None, print_blob=True,
                          suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])
settings.load_profile(os.environ.get("PLUECKER_HYPOTHESIS", "ci"))


def seed_for(name: str) -> int:
    """A stable 32-bit seed from a test name."""
    return zlib.crc32(name.encode())


@pytest.fixture
def seed(request: pytest.FixtureRequest) -> int:
    """The seed of this test (its node name hashed); printed by the helpers on failure."""
    return seed_for(request.node.name)


def rotation_error(r_est: np.ndarray, r_true: np.ndarray) -> float:
    """Geodesic distance between two rotations, radians."""
    c = (np.trace(r_est.T @ r_true) - 1.0) / 2.0
    return float(np.arccos(np.clip(c, -1.0, 1.0)))


def assert_pose_close(result, r_true, t_true, tol: float, seed=None) -> None:
    """``result.R``/``result.t`` within ``tol`` (max abs entry) of the truth."""
    dr = float(np.max(np.abs(result.R - r_true)))
    dt = float(np.max(np.abs(result.t - t_true)))
    assert dr < tol and dt < tol, (
        f"seed={seed} method={result.method} status={result.status}: |dR|={dr:.3e} |dt|={dt:.3e} (tol {tol:.0e})"
    )


def project(camera: pluecker.Camera, r: np.ndarray, t: np.ndarray, x_world: np.ndarray) -> np.ndarray:
    """Pixels of world points by the documented convention, computed independently of the library."""
    x_cam = x_world @ r.T + t
    uvw = x_cam @ camera.K.T
    return uvw[:, :2] / uvw[:, 2:3]


def correspondences(scene: dict) -> dict:
    """The keyword arguments of estimate_pose for a scene dict."""
    return {k: scene[k] for k in ("points2d", "points3d", "lines2d", "lines3d") if k in scene}
