"""Checks of argument values shared by the Python modules (the Rust core checks its own), and the one
way messages print a number."""

import math
from typing import Any

import numpy as np

from ._core import InvalidOptionError


def number(value: Any) -> str:
    """A number as messages print it: six significant digits, like C's ``%g`` and the core's messages
    (``1e+300``, ``0.001``, ``-2.5``, ``nan``, ``inf``), never spelled out in hundreds of digits."""
    try:
        return f"{float(value):.6g}"
    except OverflowError:  # an int beyond the float range
        return f"{'-' if value < 0 else ''}an integer beyond 1.8e+308"
    except (TypeError, ValueError):
        return repr(value)


def shown(value: Any) -> str:
    """A value as a message shows it: a float as :func:`number` prints it, else its repr, cut to 60
    characters."""
    text = number(value) if isinstance(value, float) else repr(value)
    return text if len(text) <= 60 else text[:57] + "..."


def check_sigma(sigma_px: Any) -> None:
    """``pluecker.InvalidOptionError`` naming ``sigma_px`` unless it is a positive finite number (not a
    bool) whose square is a normal double: the covariance is ``sigma_px²`` I, so a negative σ would pass
    as its absolute value, a zero or NaN one would make every cost meaningless, and a σ² that overflows
    or underflows (to zero or a subnormal, whose inverse overflows) would leave no usable cost."""
    if isinstance(sigma_px, (bool, np.bool_)) or not isinstance(sigma_px, (int, float, np.integer, np.floating)):
        raise InvalidOptionError(f"sigma_px: must be a positive finite number of pixels, got {sigma_px!r}")
    try:
        value = float(sigma_px)
    except OverflowError:
        value = math.inf
    if not (math.isfinite(value) and value > 0):
        raise InvalidOptionError(f"sigma_px: must be a positive finite number of pixels, got {number(value)}")
    variance = value * value
    if not (math.isfinite(variance) and variance >= np.finfo(float).tiny):
        flow = "overflows" if not math.isfinite(variance) else "underflows"
        raise InvalidOptionError(f"sigma_px: σ = {number(value)} px: the covariance σ² I {flow} double precision")
