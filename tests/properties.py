"""Strategies and checks shared by the property tests (hypothesis): wild scalars and arrays, and the
"documented error or a consistent result" property every public entry point must have."""

from __future__ import annotations

import json
import pickle

import numpy as np
from hypothesis import strategies as st
from hypothesis.extra import numpy as hnp

import pluecker

POSE_STATUSES = {"success", "ambiguous", "not_converged", "numerical_failure", "behind_camera",
                 "too_few_inliers", "no_hypothesis", "gap_not_closed"}
TRIANGULATION_STATUSES = {"success", "gap_not_closed", "not_converged", "behind_camera", "at_infinity",
                          "numerical_failure", "too_few_inliers"}  # the last: a point with an outlier threshold
#: Statuses of a batch track the core rejected (``BatchReport.status``).
REJECTED = {"too_few_views", "non_finite", "degenerate", "singular_camera", "invalid_input", "invalid_option"}

SPECIAL = [0.0, -0.0, 5e-324, -5e-324, 1e-300, 1e300, 1.7e308, -1.7e308, np.nan, np.inf, -np.inf]


def reals(allow_special: bool = True) -> st.SearchStrategy[float]:
    """Floats of every magnitude: a mantissa in [-1, 1] times 10^k for k from -300 to 300, often
    moderate, sometimes NaN, inf, subnormal or huge."""
    scaled = st.builds(lambda m, e: m * 10.0**e, st.floats(-1.0, 1.0),
                       st.sampled_from([-300, -150, -20, -6, -1, 0, 0, 0, 1, 1, 2, 3, 6, 12, 150, 300]))
    options = [scaled, st.floats(-1e3, 1e3)]
    if allow_special:
        options.append(st.sampled_from(SPECIAL))
    return st.one_of(*options)


def float_arrays(shape, allow_special: bool = True) -> st.SearchStrategy[np.ndarray]:
    """float64 arrays of ``shape`` whose entries share a random scale; with ``allow_special`` a few
    entries may be NaN, inf, subnormal or huge."""
    def build(values, scale, specials):
        a = np.asarray(values, dtype=float) * scale
        for index, value in specials:
            if a.size:
                a.flat[index % a.size] = value
        return a

    n = int(np.prod(shape))
    specials = st.lists(st.tuples(st.integers(0, 10**6), st.sampled_from(SPECIAL)), max_size=2) if allow_special \
        else st.just([])
    return st.builds(build, hnp.arrays(np.float64, n, elements=st.floats(-1e3, 1e3)).map(lambda a: a.reshape(shape)),
                     st.sampled_from([1e-300, 1e-6, 1.0, 1.0, 1.0, 1e3, 1e12, 1e150, 1e300]), specials)


def array_likes(shape) -> st.SearchStrategy:
    """Mostly a float array of ``shape``; sometimes the wrong shape, an integer, float32, bool or
    complex array, a nested list, or not an array at all."""
    wrong_shape = hnp.array_shapes(min_dims=0, max_dims=4, min_side=0, max_side=4).flatmap(float_arrays)
    return st.one_of(
        float_arrays(shape), float_arrays(shape), float_arrays(shape), float_arrays(shape),
        wrong_shape,
        float_arrays(shape).map(lambda a: np.nan_to_num(a).clip(-1e6, 1e6).astype(np.int64)),
        float_arrays(shape).map(lambda a: a.astype(np.float32)),
        float_arrays(shape).map(lambda a: a.tolist()),
        st.just(np.zeros(shape, dtype=bool)),
        st.just(np.zeros(shape, dtype=complex)),
        st.sampled_from(["text", None, 3.5, [[1.0, 2.0], [3.0]], {"a": 1}]),
    )


def integers() -> st.SearchStrategy[int]:
    """Python integers around the interesting limits, and bools."""
    return st.one_of(st.integers(-5, 300), st.sampled_from([2**31, 2**63 - 1, 2**63, 2**64 - 1, 2**64, -(2**63) - 1,
                                                            10**40, -(10**40), True, False]))


def check_error(error: Exception) -> None:
    """A documented error: a PlueckerError that is not an internal error (a Rust panic), with a
    message that says what is wrong."""
    assert isinstance(error, pluecker.PlueckerError) and isinstance(error, ValueError), repr(error)
    assert "internal error" not in str(error), error
    assert str(error).strip(), repr(error)


def outcome(call, type_error_ok: bool = True):
    """``call()``'s result, or the documented error it raised (checked). A TypeError is accepted only
    when the input had a wrong type; any other exception (OverflowError, PanicException, ...) fails."""
    try:
        return call()
    except pluecker.PlueckerError as error:
        check_error(error)
        return error
    except TypeError as error:
        assert type_error_ok, f"TypeError for well-typed input: {error}"
        return error


def check_strict_json_and_pickle(result) -> None:
    d = result.to_dict()
    assert json.loads(json.dumps(d, allow_nan=False)) == d
    again = pickle.loads(pickle.dumps(result))
    assert again.to_dict() == d


def check_pose(result) -> None:
    assert isinstance(result, pluecker.PoseResult)
    assert result.status in POSE_STATUSES, result.status
    R, t = result.pose.rotation, result.pose.translation
    if (result.status == "success"):
        assert np.all(np.isfinite(R)) and np.all(np.isfinite(t)) and np.isfinite(result.details.rms_error_px), result
        assert np.allclose(R @ R.T, np.eye(3), atol=1e-6) and np.linalg.det(R) > 0, result
    if result.certified:
        # A certificate is computed only for a pose that succeeded (rule: status precedence).
        assert result.status == "success", result
        assert result.certificate.lower_bound <= result.cost * (1 + 1e-9) + 1e-12, result
    if result.certificate is not None and not result.certificate.certified:
        assert result.status != "success", result
    check_strict_json_and_pickle(result)


def check_report(r, max_relative_gap: float = 1e-3) -> None:
    """A single triangulation result (point, line or quadric)."""
    assert r.status in TRIANGULATION_STATUSES, r.status
    assert r.success == (r.status == "success")
    if r.certified:
        assert r.success, r
        assert r.certificate.lower_bound <= r.cost * (1 + 1e-9) + 1e-12, r
        assert r.certificate.relative_gap <= max_relative_gap * (1 + 1e-9), r
    if r.success:
        assert np.isfinite(r.cost) and r.cost >= 0, r
    check_strict_json_and_pickle(r)


def check_batch(batch, n: int, max_relative_gap: float = 1e-3) -> None:
    assert len(batch) == n
    status = np.asarray(batch.status)
    assert set(status.tolist()) <= TRIANGULATION_STATUSES | REJECTED, set(status.tolist())
    messages = batch.messages
    for k in range(n):
        assert (status[k] in REJECTED) == bool(messages[k]), (k, status[k], messages[k])
        assert "internal error" not in messages[k], messages[k]
    certified = np.asarray(batch.certified)
    assert np.all(status[certified] == "success")
    lb, cost = np.asarray(batch.lower_bound), np.asarray(batch.cost)
    assert np.all(lb[certified] <= cost[certified] * (1 + 1e-9) + 1e-12)
    assert np.all(np.asarray(batch.relative_gap)[certified] <= max_relative_gap * (1 + 1e-9))
    check_strict_json_and_pickle(batch)
