"""Input that made a call crash or run away: sizes taken from an argument instead of the rows given,
thread counts, options that certify without a bound, covariances that lose their meaning, and the
fold of a lens distortion. Each gets a named error (a ``ValueError`` subclass naming the argument) or
an honest value.

Calls that used to abort the process or start a million threads run in a child process with a memory
cap and a timeout (:func:`guarded`), so that the old behaviour fails the test instead of the machine.
"""

from __future__ import annotations

import math
import re
import subprocess
import sys
import textwrap

import numpy as np
import pytest

import pluecker
from pluecker import DegenerateConfigurationError, InvalidOptionError, PlueckerError

#: Address space of a guarded child, bytes: numpy and the extension need a few hundred MB; an allocation
#: of 2**40 track slots or a million thread stacks does not fit.
CHILD_MEMORY = 2 * 1024**3
#: Seconds a guarded child may run (each does milliseconds of work when the input is refused).
CHILD_TIMEOUT = 120


def guarded(code: str) -> subprocess.CompletedProcess:
    """Runs ``code`` in a child Python with :data:`CHILD_MEMORY` of address space and
    :data:`CHILD_TIMEOUT` seconds; a crash shows as its exit status, never in this process."""
    def limit() -> None:
        import resource

        resource.setrlimit(resource.RLIMIT_AS, (CHILD_MEMORY, CHILD_MEMORY))

    return subprocess.run([sys.executable, "-c", textwrap.dedent(code)], capture_output=True, text=True,
                          timeout=CHILD_TIMEOUT, preexec_fn=limit)


def stereo():
    """Three cameras K [I | (-b, 0, 0)] and the exact pixels of one point in them."""
    K = np.array([[800.0, 0, 320], [0, 800.0, 240], [0, 0, 1]])
    P = np.stack([K @ np.hstack([np.eye(3), [[-b], [0.0], [0.0]]]) for b in (0.0, 0.5, 1.0)])
    h = P @ np.array([0.2, -0.1, 5.0, 1.0])
    return P, h[:, :2] / h[:, 2:]


# --- sizes come from the rows given ------------------------------------------------------------------------

SPARSE_CALLS = {
    "point": "pluecker.triangulate_points(P, x, track=track, image=image{extra})",
    "line": "pluecker.triangulate_lines(P, segments, track=track, image=image{extra})",
    "quadric": "pluecker.triangulate_quadrics(P, conics, track=track, image=image{extra})",
}


@pytest.mark.parametrize("kind", sorted(SPARSE_CALLS))
@pytest.mark.parametrize("track, extra, name", [
    ("[2**40] * 3", "", "track"),
    ("[2**52] * 3", "", "track"),
    ("[0] * 3", ", n_tracks=2**40", "n_tracks"),
    ("[0] * 3", ", n_tracks=2**63", "n_tracks"),
    ("[0] * 3", ", n_tracks=2**64", "n_tracks"),
], ids=["id-2**40", "id-2**52", "n-2**40", "n-2**63", "n-2**64"])
def test_a_huge_track_id_or_count_is_a_named_error_not_an_abort(kind, track, extra, name):
    """A track id of 2**40 or ``n_tracks=2**40`` aborted the process (exit 134, allocation failure);
    ``n_tracks=2**63`` raised a PanicException (capacity overflow)."""
    code = f"""
        import numpy as np, pluecker
        K = np.array([[800.0, 0, 320], [0, 800.0, 240], [0, 0, 1]])
        P = np.stack([K @ np.hstack([np.eye(3), [[-b], [0.0], [0.0]]]) for b in (0.0, 0.5, 1.0)])
        track, image = {track}, [0, 1, 2]
        x = np.full((3, 2), 300.0)
        segments = np.tile([[[300.0, 200.0], [340.0, 260.0]]], (3, 1, 1))
        conics = np.tile(np.diag([1.0, 1.0, -100.0]), (3, 1, 1))
        try:
            {SPARSE_CALLS[kind].format(extra=extra)}
        except pluecker.InvalidOptionError as exc:
            print("refused:", exc)
    """
    run = guarded(code)
    assert run.returncode == 0, (run.returncode, run.stderr[-2000:])
    assert run.stdout.startswith(f"refused: {name}: "), run.stdout + run.stderr[-2000:]
    assert "3 rows" in run.stdout, run.stdout  # the bound is the rows given


@pytest.mark.parametrize("argument, value, k", [
    ("track", [-1, 0, 0], 0), ("track", [0, 2**64, 0], 1), ("track", [0, 0, 2**200], 2),
    ("track", [0, 0.5, 0], 1), ("image", [0, -1, 2], 1), ("image", [0, 2**64, 2], 1), ("image", [0, 1, -(2**70)], 2),
])
def test_sparse_ids_out_of_range_are_named(argument, value, k):
    """A track or image id of -1 or 2**64 is an ``InvalidOptionError`` naming the argument and the entry
    (2**64 was a TypeError about dtype object)."""
    P, x = stereo()
    args = {"track": [0, 0, 0], "image": [0, 1, 2], argument: value}
    with pytest.raises(InvalidOptionError, match=rf"^{argument}: entry {k} is "):
        pluecker.triangulate_points(P, x, track=args["track"], image=args["image"])


@pytest.mark.parametrize("n_tracks", [-1, 2**63, 2**64, 10**400, True, 4])
def test_n_tracks_out_of_range_names_n_tracks(n_tracks):
    P, x = stereo()
    with pytest.raises(InvalidOptionError, match=r"^n_tracks: "):
        pluecker.triangulate_points(P, x, track=[0, 0, 0], image=[0, 1, 2], n_tracks=n_tracks)


def test_tracks_up_to_the_rows_given_are_solved_and_empty_ones_reported():
    """The bound leaves every sensible call alone: ``n_tracks`` up to the rows, ids 0..m-1, numpy ints."""
    P, x = stereo()
    r = pluecker.triangulate_points(P, x, track=np.zeros(3, np.uint64), image=np.arange(3), n_tracks=np.int64(3))
    assert list(r.status) == ["success", "too_few_views", "too_few_views"]
    np.testing.assert_allclose(r.point[0], [0.2, -0.1, 5.0], atol=1e-9)
    r = pluecker.triangulate_points(P, x, track=[2, 2, 2], image=[0, 1, 2])  # id 2 < 3 rows
    assert len(r) == 3 and r.status[2] == "success"
    with pytest.raises(InvalidOptionError, match=r"^track: entry 0 is 3, not a track id below the 3 rows"):
        pluecker.triangulate_points(P, x, track=[3, 3, 3], image=[0, 1, 2])


# --- threads ---------------------------------------------------------------------------------------------------


def test_a_million_threads_is_refused_before_any_starts():
    """``set_num_threads(10**6)`` tried to start a million threads (load above 1800). Guarded: a
    regression runs out of the child's address space or time, not the machine's."""
    run = guarded("""
        import pluecker, threading
        try:
            pluecker.set_num_threads(10**6)
        except pluecker.InvalidOptionError as exc:
            print("refused:", exc)
        print("threads:", threading.active_count(), pluecker.get_num_threads())
    """)
    assert run.returncode == 0, run.stderr[-2000:]
    first, second = run.stdout.splitlines()[:2]
    assert first.startswith("refused: set_num_threads: n: must be an integer from 1 to "), first
    assert "per core" in first, first


def test_the_thread_cap_is_documented_and_reachable():
    """The cap is ``max(64, 4 × cores)``: the cap itself starts, one more is refused."""
    run = guarded("""
        import re, pluecker
        try:
            pluecker.set_num_threads(10**6)
        except pluecker.InvalidOptionError as exc:
            cap = int(re.search(r"from 1 to (\\d+)", str(exc)).group(1))
        pluecker.set_num_threads(cap)
        print(cap, pluecker.get_num_threads())
        try:
            pluecker.set_num_threads(cap + 1)
            print("accepted")
        except pluecker.InvalidOptionError:
            print("refused")
    """)
    assert run.returncode == 0, run.stderr[-2000:]
    cap, threads, verdict = run.stdout.split()
    assert int(cap) == int(threads) and verdict == "refused"
    assert int(cap) >= 64 and (int(cap) == 64 or int(cap) % 4 == 0), cap
    assert "4 × the cores" in pluecker.set_num_threads.__doc__


@pytest.mark.parametrize("n", [-1, 0, 2**64, 10**400, True, False, np.True_])
def test_set_num_threads_names_n(n):
    """-1 and 2**64 were OverflowErrors, 0 a bare ValueError, True silently one thread."""
    before = pluecker.get_num_threads()
    with pytest.raises(InvalidOptionError, match=r"^set_num_threads: n: "):
        pluecker.set_num_threads(n)
    assert pluecker.get_num_threads() == before


def test_set_num_threads_of_a_float_is_a_type_error():
    with pytest.raises(TypeError):
        pluecker.set_num_threads(2.0)


# --- options: gaps and resets -------------------------------------------------------------------------------


@pytest.mark.parametrize("gap", [1.0, 1.5, 1e300, math.inf, 0.0, -0.5, math.nan])
def test_a_gap_outside_0_1_is_refused_for_triangulation_as_for_the_pose(gap):
    """``max_relative_gap=1e300`` was accepted and certified a ``gap_not_closed`` quadric at gap 0.98; a
    relative gap is at most 1 for any lower bound ≥ 0, so a threshold ≥ 1 certifies without a bound."""
    with pytest.raises(InvalidOptionError, match=r"certify.max_relative_gap.*must be in \(0, 1\)"):
        pluecker.TriangulationOptions(certify=pluecker.CertifyOptions(max_relative_gap=gap))
    with pytest.raises(InvalidOptionError, match=r"certify.max_relative_gap.*must be in \(0, 1\)"):
        pluecker.CertifyOptions(max_relative_gap=gap)


@pytest.mark.parametrize("gap", [1e-12, 0.5, 0.999])
def test_a_gap_inside_0_1_is_accepted_by_both(gap):
    assert pluecker.TriangulationOptions(certify=pluecker.CertifyOptions(max_relative_gap=gap)).certify.max_relative_gap == gap
    assert pluecker.PoseOptions(certify=pluecker.CertifyOptions(max_relative_gap=gap)).certify.max_relative_gap == gap


#: A value of every optional option (``Optional[...]`` in ``__fields__``), to set before resetting it.
OPTIONAL_VALUES = {
    (pluecker.PoseOptions, "sigma_px"): 2.0,
    (pluecker.PoseOptions, "initial_pose"): (np.eye(3), np.zeros(3)),
    (pluecker.PoseOptions, "ransac"): pluecker.RansacOptions(),
    (pluecker.PoseOptions, "certify"): pluecker.CertifyOptions(),
    (pluecker.RansacOptions, "time_budget"): 1.5,
    (pluecker.TriangulationOptions, "outlier_threshold"): 3.0,
}


def test_every_optional_option_is_listed():
    """The table below covers every ``Optional`` field, so a new one is tested too."""
    optional = {(cls, name) for cls in (pluecker.PoseOptions, pluecker.RansacOptions, pluecker.TriangulationOptions)
                for name, kind, _ in cls.__fields__ if kind.startswith("Optional[")}
    assert optional == set(OPTIONAL_VALUES)


@pytest.mark.parametrize("option", sorted(OPTIONAL_VALUES, key=lambda o: (o[0].__name__, o[1])), ids=lambda o: o[1])
def test_an_optional_option_can_be_reset_to_none(option):
    """``PoseOptions(sigma_px=2.0).sigma_px = None`` raised ``AttributeError: cannot delete``."""
    cls, name = option
    options = cls(**{name: OPTIONAL_VALUES[option]})
    assert getattr(options, name) is not None and options != cls()
    setattr(options, name, None)
    assert getattr(options, name) is None
    assert options == cls()
    assert cls(**{name: None}) == cls()
    with pytest.raises(AttributeError):
        delattr(options, name)


def test_none_for_a_required_option_is_a_type_error_naming_it():
    options = pluecker.TriangulationOptions()
    with pytest.raises(TypeError, match="^certify: "):
        options.certify = None
    with pytest.raises(TypeError, match="^max_relative_gap: "):
        options.certify.max_relative_gap = None
    assert options == pluecker.TriangulationOptions()


# --- zero instead of an error ------------------------------------------------------------------------------------


def test_a_pose_covariance_that_underflows_is_an_error_like_one_that_overflows():
    """``pose_covariance(sigma_px=1e-200)`` returned all zeros (a pose known exactly) where 1e200 raised."""
    scene = pluecker.random_scene("general", 8, 2, seed=1)
    args = (scene["camera"], scene["R"], scene["t"], scene["points2d"], scene["points3d"])
    unit = pluecker.pose_covariance(*args, sigma_px=1.0)
    for sigma, word in ((1e-200, "underflows"), (1e200, "overflows")):
        with pytest.raises(InvalidOptionError, match=rf"^sigma_px: .* {word} double precision at σ = 1e[-+]200 px"):
            pluecker.pose_covariance(*args, sigma_px=sigma)
    # Where it fits, the covariance is σ² times the unit one (to rounding).
    np.testing.assert_allclose(pluecker.pose_covariance(*args, sigma_px=1e-3), 1e-6 * unit, rtol=1e-12)


@pytest.mark.parametrize("sigma", [1e-200, 1e200])
def test_a_given_sigma_whose_covariance_does_not_fit_gives_no_covariance(sigma):
    """``estimate_pose`` with ``sigma_px=1e-200`` reported an all-zero covariance as "given"; with 1e200
    none. Either way the covariance is not representable, and the result says so."""
    scene = pluecker.random_scene("general", 8, 2, seed=1)
    r = pluecker.estimate_pose(scene["camera"], scene["points2d"], scene["points3d"],
                               options=pluecker.PoseOptions(sigma_px=sigma))
    assert r.status == "success"
    assert r.covariance is None and r.details.covariance_source is None


def ellipse_points(n=40):
    t = np.linspace(0, 2 * np.pi, n, endpoint=False)
    rng = np.random.default_rng(5)
    return np.stack([300 + 80 * np.cos(t), 200 + 40 * np.sin(t)], 1) + rng.normal(0, 0.3, (n, 2))


@pytest.mark.parametrize("fit, points", [(pluecker.fit_conic, ellipse_points()),
                                         (pluecker.fit_line, np.stack([np.arange(10.0), 2 * np.arange(10.0)], 1))],
                         ids=["fit_conic", "fit_line"])
def test_a_fitted_covariance_that_underflows_is_an_error(fit, points):
    """``fit_conic(sigma=1e-300)`` returned an all-zero covariance where ``fit_line`` raised."""
    with pytest.raises(InvalidOptionError, match=r"sigma'?: σ = 1e-300 px: the covariance σ² Σ underflows"):
        fit(points, sigma=1e-300)
    unit = fit(points, sigma=1.0).covariance
    # The covariance is σ² Σ₁: the same fit at σ = 1e-3 (the χ² test of the conic passes at both).
    np.testing.assert_allclose(fit(points, sigma=1e-3).covariance, 1e-6 * unit, rtol=1e-9)


LENS = pluecker.Camera("OPENCV", [800.0, 790.0, 320.0, 240.0, -0.2, 0.05, 1e-3, -5e-4])


@pytest.mark.parametrize("bad", [-np.eye(2), np.diag([1.0, -1e-3]), [[1.0, 2.0], [2.0, 1.0]], [[1.0, 0.5], [0.0, 1.0]]],
                         ids=["-I", "negative-variance", "indefinite", "asymmetric"])
@pytest.mark.parametrize("method", ["undistort", "normalized_covariances"])
def test_a_pixel_covariance_that_is_not_a_covariance_is_refused(bad, method):
    """``Camera.undistort(px, covariances=-I)`` returned negative-definite covariances."""
    pixels = np.array([[300.0, 200.0], [350.0, 260.0]])
    cov = np.stack([np.eye(2), np.asarray(bad, dtype=float)])
    with pytest.raises(DegenerateConfigurationError, match=r"covariances\[1\] is not a covariance"):
        getattr(LENS, method)(pixels, cov)


def test_a_semidefinite_pixel_covariance_is_a_covariance():
    pixels = np.array([[300.0, 200.0]])
    _, cov = LENS.undistort(pixels, np.array([[[1.0, 1.0], [1.0, 1.0]]]))
    assert np.linalg.eigvalsh(cov[0]).min() > -1e-12 * np.abs(cov[0]).max()


# --- the fold of a radial distortion -----------------------------------------------------------------------------


def test_every_pixel_beyond_the_fold_of_a_radial_distortion_is_refused():
    """RADIAL [800, 320, 240, -0.5, 0.1] refused (1000, 1000) as beyond the fold but unprojected (5000, 5000).

    Independently of the library: ρ(r) = r (1 - 0.5 r² + 0.1 r⁴) has ρ' = 1 - 1.5 r² + 0.5 r⁴ = 0 at
    r = 1 (a maximum, ρ = 0.6) and r = √2, then rises for ever; only pixels closer to the principal point
    than 0.6 f = 480 px have a preimage on the branch through it."""
    cam = pluecker.Camera("RADIAL", [800.0, 320.0, 240.0, -0.5, 0.1])
    r = np.linspace(0, 3, 30001)
    rho = r * (1 - 0.5 * r**2 + 0.1 * r**4)
    peak = 800.0 * rho[: np.argmax(np.diff(rho) <= 0) + 1].max()
    assert abs(peak - 480.0) < 1e-6
    for pixel in ([1000.0, 1000.0], [5000.0, 5000.0], [320.0 + 481.0, 240.0]):
        with pytest.raises(DegenerateConfigurationError, match="beyond the fold|folds"):
            cam.unproject(np.array([pixel]))
    for radius in np.geomspace(1.0, 50 * peak, 400):
        for angle in (0.3, 2.5, 4.4):
            pixel = np.array([[320.0 + radius * np.cos(angle), 240.0 + radius * np.sin(angle)]])
            try:
                n = cam.unproject(pixel)[0]
            except DegenerateConfigurationError:
                # Newton's method may also give up just inside the peak, where ρ' → 0.
                assert radius > 0.99 * peak, radius
                continue
            assert radius < peak, f"{radius:.1f} px is past the fold at {peak:.1f} px yet unprojected to {n}"
            np.testing.assert_allclose(cam.project(np.array([[*n, 1.0]]))[0], pixel[0], atol=1e-8)


# --- messages -----------------------------------------------------------------------------------------------------


@pytest.mark.parametrize("call", [
    lambda: pluecker.TriangulationOptions(certify=pluecker.CertifyOptions(max_relative_gap=1e300)),
    lambda: pluecker.CertifyOptions(max_relative_gap=-1e300),
    lambda: pluecker.RansacOptions(confidence=1e300),
    lambda: pluecker.RansacOptions(point_threshold=-1e300),
    lambda: pluecker.fit_line(np.eye(2), sigma=-1e300),
    lambda: pluecker.RansacOptions(time_budget=-1e300),
    lambda: pluecker.triangulate_points(stereo()[0], stereo()[1], track=[1e300, 0, 0], image=[0, 1, 2]),
    lambda: LENS.unproject(np.array([[1e300, 0.0]])),
    lambda: LENS.undistort(np.array([[300.0, 200.0]]), np.array([[[-1e300, 0.0], [0.0, 1.0]]])),
], ids=["max_relative_gap", "certify_max_relative_gap", "confidence", "point_threshold", "sigma", "time_budget", "track",
        "pixel", "covariances"])
def test_floats_in_messages_have_six_significant_digits(call):
    """``1e300`` was printed in full, 301 digits."""
    with pytest.raises(PlueckerError) as info:
        call()
    message = str(info.value)
    assert re.search(r"e\+300|e-300|1e\+300", message), message
    assert not re.search(r"\d{12}", message), message


def test_the_thread_cap_message_states_this_machines_limit():
    """The message said "at most 4 threads per core, and 64 on any machine" on every machine; it states
    the limit here, with the cores it was computed from."""
    import os

    with pytest.raises(InvalidOptionError) as error:
        pluecker.set_num_threads(10**6)
    message = str(error.value)
    cap = int(re.search(r"from 1 to (\d+),", message).group(1))
    cores = int(re.search(r"the limit on this machine, with (\d+) cores?: the larger of 64 and 4 per core\)",
                          message).group(1))
    assert cap == max(64, 4 * cores) and 1 <= cores <= len(os.sched_getaffinity(0)), message


@pytest.mark.parametrize("sigma, flow", [(1e300, "overflows"), (1e-300, "underflows")])
def test_a_segment_sigma_through_a_lens_blames_sigma_not_covariances(sigma, flow):
    """``triangulate_line(views, ..., sigma=1e300)`` raised ``NonFiniteError: covariances: ...``
    although no covariances were given."""
    R = np.eye(3)
    views = [pluecker.View(LENS, R, np.array([-b, 0.0, 0.0])) for b in (0.0, 0.5, 1.0)]
    ends = np.array([[-0.5, 0.2, 5.0], [0.6, -0.1, 6.0]])
    segments = np.stack([LENS.project(ends - [b, 0.0, 0.0]) for b in (0.0, 0.5, 1.0)])
    message = rf"^sigma: σ = {re.escape(f'{sigma:g}')} px: the covariance σ² I {flow} double precision"
    with pytest.raises(InvalidOptionError, match=message):
        pluecker.triangulate_line(views, segments, sigma=sigma)
    with pytest.raises(InvalidOptionError, match=message):
        pluecker.triangulate_lines(views, segments, track=[0, 0, 0], image=[0, 1, 2], sigma=sigma)
    # Through a distorting lens a line is never certified: gap_not_closed, at the exact line (cost ~ 0).
    assert pluecker.triangulate_line(views, segments, sigma=1e-3).cost < 1e-12
