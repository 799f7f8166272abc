"""Reproductions of published experiments, run by ``pluecker reproduce NAME``.

Each experiment is a module with a ``reproduce(out, *, trials, seed, quick, show_progress, plots)``
function returning a report (``files``, ``summary``, the ``lines`` to print). Modules are imported
only when run, so ``import pluecker`` stays light.
"""

from __future__ import annotations

import importlib
from dataclasses import dataclass
from pathlib import Path
from types import ModuleType

__all__ = ["EXPERIMENTS", "Report", "load"]

#: Experiment name → module (relative to this package).
EXPERIMENTS = {
    "phong-horaud-1995": "phong_horaud_1995",
    "josephson-kahl-2008": "josephson_kahl_2008",
}


@dataclass
class Report:
    """What ``reproduce`` returns: the output folder, the files written, the summary (as in
    ``summary.json``), the lines to print and the wall time in seconds."""

    out: Path
    files: list[Path]
    summary: dict
    lines: list[str]
    seconds: float


def load(name: str) -> ModuleType:
    """The module of experiment ``name``; ``KeyError`` for an unknown name."""
    return importlib.import_module(f"{__name__}.{EXPERIMENTS[name]}")
