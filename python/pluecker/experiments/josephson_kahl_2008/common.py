"""What the parts of the Josephson & Kahl 2008 reproduction share: the data, the methods, table and
JSON helpers."""

from __future__ import annotations

from typing import Any, Sequence

import numpy as np

SEQUENCES = ("model_house", "corridor")
LABELS = {"model_house": "House", "corridor": "Corridor"}
FRAMES = (0, 1, 2, 3)
METHODS = ("optimal", "local", "linear")
METHOD_LABELS = {"optimal": "Optimal", "local": "Bundle (local)", "linear": "Linear"}
# A cost above another by more than this fraction counts as "higher" (the optimal method's gap is 1e-3).
COST_TOLERANCE = 1e-6


def markdown_table(headers: Sequence[str], rows: Sequence[Sequence[str]]) -> str:
    """A Markdown table, the first column left-aligned and the others right-aligned."""
    rule = "|" + "|".join("---:" if i else "---" for i in range(len(headers))) + "|"
    return "\n".join(["| " + " | ".join(headers) + " |", rule, *("| " + " | ".join(r) + " |" for r in rows)])


def counts(values: np.ndarray) -> dict[str, int]:
    """How many times each value occurs, as a plain dict."""
    keys, n = np.unique(np.asarray(values), return_counts=True)
    return {str(k): int(c) for k, c in zip(keys, n)}


def clean(value: Any) -> Any:
    """Strict JSON: NaN/inf as null, numpy scalars as numbers, tuples as lists."""
    if isinstance(value, dict):
        return {str(k): clean(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [clean(v) for v in value]
    if isinstance(value, np.ndarray):
        return clean(value.tolist())
    if isinstance(value, np.generic):
        value = value.item()
    if isinstance(value, float) and not np.isfinite(value):
        return None
    return value


def triangulation_options(method: str, gap: float | None = None) -> Any:
    """``TriangulationOptions`` of ``method``, with the certificate's ``max_relative_gap`` when ``gap`` is
    given (``None``: pluecker's default)."""
    import pluecker

    options = pluecker.TriangulationOptions(method=method)
    if gap is not None:
        options.certify.max_relative_gap = gap
    return options
