"""Figures of the experiments (matplotlib, Agg backend; import this module only when plotting).

The functions take plain numbers — series of ``(x, y)`` with a line style — so that they know nothing
about estimators or sweeps. Errors span several decades (the linear method against the non-linear
ones), so the y axes are logarithmic.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Sequence

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402  (after choosing the backend)

__all__ = ["Series", "Panel", "YLABELS", "two_panel_figure", "stacked_figure"]

YLABELS = {
    "axis": "axis error ‖r − r0‖",
    "angle": "angle error |φ − φ0| (rad)",
    "translation": "translation error ‖t − t0‖ (cm)",
}

# The paper's convention: dashed for Faugeras-Toscani, full for the non-linear method.
_LINESTYLES = {"full": "-", "dashed": "--", "dotted": ":", "dashdot": "-."}
_COLORS = {"full": "black", "dashed": "tab:red", "dotted": "tab:blue", "dashdot": "tab:green"}


@dataclass(frozen=True)
class Series:
    """One curve; ``style`` is "full", "dashed", "dotted" or "dashdot"."""

    label: str
    x: Sequence[float]
    y: Sequence[float]
    style: str = "full"


@dataclass(frozen=True)
class Panel:
    """One set of axes."""

    xlabel: str
    series: Sequence[Series]
    ylabel: str | None = None


# Noise-free cells have errors near 1e-12; showing them would squash every other decade. The y axis
# spans at most this many decades below the largest value; smaller values sit on the bottom edge.
_DECADES = 6


def _draw(ax, panel: Panel, ylabel: str | None, xlabel: bool = True, legend: bool = True) -> None:
    top = max((y for s in panel.series for y in s.y if y == y and y > 0), default=None)
    floor = top * 10.0**-_DECADES if top else None
    for s in panel.series:
        pairs = [(x, y) for x, y in zip(s.x, s.y) if y == y]  # drop NaN cells
        xs = [x for x, _ in pairs]
        ys = [max(y, floor) if floor else y for _, y in pairs]
        ax.plot(xs, ys, _LINESTYLES[s.style], color=_COLORS[s.style], marker="o", markersize=3, label=s.label)
    if floor:
        ax.set_yscale("log")
        if any(0 <= y < floor for s in panel.series for y in s.y):
            ax.set_ylim(bottom=floor / 2)
    if xlabel:
        ax.set_xlabel(panel.xlabel)
    if panel.ylabel or ylabel:
        ax.set_ylabel(panel.ylabel or ylabel)
    ax.grid(True, which="major", alpha=0.3)
    if legend:
        ax.legend(fontsize="small")


def two_panel_figure(path: Path | str, title: str, ylabel: str, left: Panel, right: Panel) -> Path:
    """Error vs number of correspondences (left) and vs noise (right), as in Figures 5-7."""
    fig, axes = plt.subplots(1, 2, figsize=(10, 4), constrained_layout=True)
    for ax, panel in zip(axes, (left, right)):
        _draw(ax, panel, ylabel)
    fig.suptitle(title)
    return _save(fig, path)


def stacked_figure(path: Path | str, title: str, panels: Sequence[Panel]) -> Path:
    """Panels stacked vertically, sharing the x axis, as in Figure 9; one legend below them (inside a
    panel it would cover curves that span the whole axes)."""
    fig, axes = plt.subplots(len(panels), 1, figsize=(6, 3 * len(panels) + 0.8), sharex=True,
                             constrained_layout=True)
    for i, (ax, panel) in enumerate(zip(axes, panels)):
        _draw(ax, panel, None, xlabel=i == len(panels) - 1, legend=False)
    handles, labels = axes[0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="outside lower center", ncols=2, fontsize="small")
    fig.suptitle(title)
    return _save(fig, path)


def _save(fig, path: Path | str) -> Path:
    path = Path(path)
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path
