"""Shared fixtures and helpers for the Python tests.

Seeds derive from the test's name (so each test has its own stream, stable across runs and
orderings), and every assertion helper puts the seed in its failure message.
"""

from __future__ import annotations

import datetime
import os
import random
import zlib

import hypothesis
import numpy as np
import pytest
from hypothesis import HealthCheck, settings

import pluecker

# Property tests (hypothesis). "ci", the default, is small enough for every `make test`;
# PLUECKER_HYPOTHESIS=nightly explores 40x more examples. Both draw their examples from one seed per
# run (HYPOTHESIS_SEED below): the UTC date by default, so that the examples change every day and
# every run of one day sees the same ones; PLUECKER_HYPOTHESIS_SEED=<integer> replays a run, and
# PLUECKER_HYPOTHESIS_SEED=random draws a fresh seed. The seed is printed in pytest's header (with
# -q, which prints no header: at the end of the run) and beside every failure (with hypothesis's own
# @reproduce_failure blob). No example database: a run depends on its seed alone.
settings.register_profile("ci", max_examples=60, deadline=None, database=None, print_blob=True,
                          suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])
settings.register_profile("nightly", max_examples=2500, deadline=None, database=None, print_blob=True,
                          suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])
settings.load_profile(os.environ.get("PLUECKER_HYPOTHESIS", "ci"))


def hypothesis_seed(value: str | None, today: datetime.date) -> tuple[int, str]:
    """The seed of this run's property tests and where it came from: ``value`` (the environment's
    ``PLUECKER_HYPOTHESIS_SEED``) as an integer, a fresh random one for ``"random"``, else ``today``
    as YYYYMMDD."""
    if value is None or value.strip() == "":
        return int(today.strftime("%Y%m%d")), "the UTC date"
    if value.strip() == "random":
        return random.SystemRandom().randrange(2**32), "drawn at random"
    try:
        return int(value), "from the environment"
    except ValueError:
        raise pytest.UsageError(
            f"PLUECKER_HYPOTHESIS_SEED: expected an integer or 'random', got {value!r}") from None


#: This run's seed and where it came from (set when pytest starts).
HYPOTHESIS_SEED, SEED_SOURCE = 0, ""


def pytest_configure(config):
    global HYPOTHESIS_SEED, SEED_SOURCE
    HYPOTHESIS_SEED, SEED_SOURCE = hypothesis_seed(os.environ.get("PLUECKER_HYPOTHESIS_SEED"),
                                                   datetime.datetime.now(datetime.timezone.utc).date())


def _seed_line() -> str:
    return (f"property tests: hypothesis profile {settings.get_current_profile_name()!r}, seed {HYPOTHESIS_SEED} "
            f"({SEED_SOURCE}; PLUECKER_HYPOTHESIS_SEED={HYPOTHESIS_SEED} replays it)")


def pytest_report_header(config):
    return _seed_line()


def pytest_terminal_summary(terminalreporter, exitstatus, config):
    """The seed again at the end of the run: ``pytest -q`` (``make test``) prints no header."""
    if config.get_verbosity() < 0:
        terminalreporter.write_line(_seed_line())


def _property_test(item):
    """The hypothesis test function behind a collected ``item`` (a method's underlying function), or
    ``None`` when it is not a property test."""
    obj = getattr(item, "obj", None)
    test = getattr(obj, "__func__", obj)
    return test if hypothesis.is_hypothesis_test(test) else None


def pytest_collection_modifyitems(config, items):
    """Every property test draws from this run's seed (``hypothesis.seed``; a ``--hypothesis-seed``
    given to pytest wins)."""
    if config.getoption("--hypothesis-seed", default=None) is not None:
        return
    for item in items:
        if (test := _property_test(item)) is not None:
            hypothesis.seed(HYPOTHESIS_SEED)(test)


@pytest.hookimpl(hookwrapper=True)
def pytest_runtest_makereport(item, call):
    """Puts the seed beside the failure of a property test."""
    outcome = yield
    report = outcome.get_result()
    if report.failed and _property_test(item) is not None:
        report.sections.append(("hypothesis seed", f"PLUECKER_HYPOTHESIS_SEED={HYPOTHESIS_SEED} ({SEED_SOURCE}) "
                                                    f"reruns this test with the same examples"))


#: The test hooks of the extension: ``cargo`` feature ``test-hooks`` of crates/pluecker-py, which the
#: development build (``make develop``) turns on and the wheel (``pip install .``, ``maturin build``) leaves out.
TEST_HOOKS = ("_panic_for_tests", "_on_poll_for_tests", "_setup_polls_for_tests", "_pose_rotation_search",
              *(("_hold_gil_for_tests",) if os.name == "posix" else ()))


def missing_hook_message(name: str) -> str:
    return (f"pluecker._core has no test hook {name}: this extension ({pluecker._core.__file__}) was built without "
            f"the cargo feature `test-hooks` (as the wheel is); build the development one with `make develop` "
            f"(maturin develop --release --features test-hooks)")


class _Hooks:
    """The extension's test hooks as attributes (``hooks._on_poll_for_tests(1, "interrupt")``). In a build
    without them the test that needs one fails, with a message that says how to build them in: nothing is
    skipped."""

    def __getattr__(self, name: str):
        if name not in TEST_HOOKS:
            raise AttributeError(name)
        hook = getattr(pluecker._core, name, None)
        if hook is None:
            pytest.fail(missing_hook_message(name), pytrace=False)
        return hook


hooks = _Hooks()


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
    """``result.pose.rotation``/``result.pose.translation`` within ``tol`` (max abs entry) of the truth."""
    dr = float(np.max(np.abs(result.pose.rotation - r_true)))
    dt = float(np.max(np.abs(result.pose.translation - t_true)))
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
