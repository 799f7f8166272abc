"""One stable sort of integer keys for the table code of :mod:`pluecker.colmap` and
:mod:`pluecker.distributed` (observations by track, rows by bucket, queries and points by id)."""

from __future__ import annotations

import numpy as np


def stable_order(values: np.ndarray) -> np.ndarray:
    """``np.argsort(values, kind="stable")`` of integers: for non-negative ones, the default sort of the
    unique keys ``value * len + row`` gives the same order 3-4 times faster (144,000 rows: 4 ms against
    14 ms) where the keys fit in 62 bits; the stable sort itself otherwise."""
    values = np.asarray(values)
    n = len(values)
    if n == 0 or values.dtype.kind not in "iu" or values.min() < 0 or int(values.max()) >= (1 << 62) // n:
        return np.argsort(values, kind="stable")
    keys = values.astype(np.int64) * n + np.arange(n, dtype=np.int64)
    return np.argsort(keys)
