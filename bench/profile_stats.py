"""Text summaries shared by ``bench/profile_colmap.py`` and ``bench/profile_pose.py``: a log-spaced
histogram of per-item times, tail statistics, and Markdown tables. Pure numpy, no pluecker."""

from __future__ import annotations

import math
from typing import Sequence

import numpy as np


def fmt_ms(seconds: float) -> str:
    """Milliseconds with 3 significant digits (a dash for NaN)."""
    if not math.isfinite(seconds):
        return "—"
    ms = 1e3 * seconds
    return f"{ms:.3g}" if abs(ms) >= 0.001 else f"{ms:.1e}"


def fmt_us(seconds: float) -> str:
    """Microseconds with 3 significant digits (a dash for NaN)."""
    return "—" if not math.isfinite(seconds) else f"{1e6 * seconds:.3g}"


def tail_stats(times: np.ndarray) -> dict[str, float]:
    """p50 / p90 / p99 / max of ``times`` (seconds), their sum, and the share of the sum spent by the
    slowest 1 % of the items (at least one item)."""
    t = np.sort(np.asarray(times, dtype=float))
    total = float(t.sum())
    k = max(1, math.ceil(len(t) / 100))
    return {
        "n": float(len(t)),
        "sum": total,
        "p50": float(np.percentile(t, 50)),
        "p90": float(np.percentile(t, 90)),
        "p99": float(np.percentile(t, 99)),
        "max": float(t[-1]),
        "slowest_1pct_items": float(k),
        "slowest_1pct_share": float(t[-k:].sum() / total) if total > 0 else math.nan,
    }


def tail_line(times: np.ndarray, unit: str = "ms") -> str:
    """One line of :func:`tail_stats`."""
    s = tail_stats(times)
    f = fmt_ms if unit == "ms" else fmt_us
    return (f"n = {int(s['n'])}, p50 {f(s['p50'])} {unit}, p90 {f(s['p90'])} {unit}, p99 {f(s['p99'])} {unit}, "
            f"max {f(s['max'])} {unit}; the slowest 1 % ({int(s['slowest_1pct_items'])} items) spend "
            f"{100 * s['slowest_1pct_share']:.1f} % of the summed time ({fmt_ms(s['sum'])} ms)")


def histogram(times: np.ndarray, per_decade: int = 4, width: int = 40) -> list[str]:
    """A text histogram of ``times`` (seconds) on log-spaced bins (``per_decade`` bins per factor 10),
    in µs: bin, count, share of the items, share of the summed time, and a bar (by count, log-scaled so
    that a bin of one item still shows)."""
    t = np.asarray(times, dtype=float)
    t = t[np.isfinite(t) & (t > 0)]
    if len(t) == 0:
        return ["(no positive times)"]
    us = 1e6 * t
    lo = math.floor(per_decade * math.log10(us.min())) / per_decade
    hi = (math.floor(per_decade * math.log10(us.max())) + 1) / per_decade
    edges = 10.0 ** np.arange(lo, hi + 1e-9, 1.0 / per_decade)
    counts, _ = np.histogram(us, bins=edges)
    sums, _ = np.histogram(us, bins=edges, weights=us)
    top = math.log1p(counts.max())
    lines = [f"{'µs from':>10} {'to':>10} {'items':>8} {'% items':>8} {'% time':>7}  bar (log count)"]
    for a, b, c, s in zip(edges[:-1], edges[1:], counts, sums):
        bar = "#" * (0 if c == 0 else max(1, round(width * math.log1p(c) / top)))
        lines.append(f"{a:>10.3g} {b:>10.3g} {c:>8d} {100 * c / len(us):>8.2f} {100 * s / us.sum():>7.2f}  {bar}")
    return lines


def table(header: Sequence[str], rows: Sequence[Sequence[object]]) -> list[str]:
    """A Markdown table."""
    out = ["| " + " | ".join(header) + " |", "|" + " --- |" * len(header)]
    out += ["| " + " | ".join(str(c) for c in row) + " |" for row in rows]
    return out
