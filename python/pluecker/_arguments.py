"""Checks of argument values shared by the Python modules (the Rust core checks its own)."""

import math
from typing import Any

import numpy as np

from ._core import InvalidOptionError


def check_sigma(sigma_px: Any) -> None:
    """``pluecker.InvalidOptionError`` unless ``sigma_px`` is a positive finite number (not a bool): the
    covariance is ``sigma_px²`` I, so a negative σ would pass as its absolute value and a zero or NaN
    one would make every cost meaningless."""
    if isinstance(sigma_px, (bool, np.bool_)) or not isinstance(sigma_px, (int, float, np.integer, np.floating)):
        raise InvalidOptionError(f"sigma_px: must be a positive finite number of pixels, got {sigma_px!r}")
    try:
        value = float(sigma_px)
    except OverflowError:
        value = math.inf
    if not (math.isfinite(value) and value > 0):
        raise InvalidOptionError(f"sigma_px: must be a positive finite number of pixels, got {value:.6g}")
