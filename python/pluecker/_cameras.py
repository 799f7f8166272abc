"""The known cameras of a set of images, as the triangulation of tracks takes them: image ids and their
3x4 matrices, with each image's lens when the pixels are the observed (distorted) ones. Shared by the
COLMAP adapter (:func:`pluecker.colmap.observation_table`) and :mod:`pluecker.distributed`.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Optional

import numpy as np

from . import _core


@dataclass(frozen=True)
class Cameras:
    """Image ids (v,) and their ``projections`` (v, 3, 4) mapping world points to pixels; with ``views``
    (v,), each image's ``View`` (its camera, any model, at its pose), ``projections[j]`` is ``K [R | t]`` of
    its pinhole part and the table's pixels are the observed (distorted) ones, as
    ``triangulate_points(views, ..., track=..., image=...)`` takes them."""

    ids: np.ndarray
    projections: np.ndarray
    views: Optional[tuple] = None

    def __post_init__(self) -> None:
        ids = np.asarray(self.ids, dtype=np.int64).reshape(-1)
        P = np.asarray(self.projections, dtype=float)
        if P.shape != (len(ids), 3, 4):
            raise _core.ShapeError(
                f"Cameras: projections must have shape ({len(ids)}, 3, 4) for {len(ids)} ids, got {P.shape}")
        if len(np.unique(ids)) != len(ids):
            raise ValueError("Cameras: image ids must be unique")
        if self.views is not None and len(self.views) != len(ids):
            raise _core.ShapeError(f"Cameras: views must have one view per id ({len(ids)}), got {len(self.views)}")
        object.__setattr__(self, "ids", ids)
        object.__setattr__(self, "projections", P)
        if self.views is not None:
            object.__setattr__(self, "views", tuple(self.views))

    def known(self) -> Any:
        """The known cameras as the triangulation functions take them: the views when there are, else
        the projections."""
        return list(self.views) if self.views is not None else self.projections

    @classmethod
    def from_dict(cls, cameras: dict[int, Any]) -> "Cameras":
        """From ``{image id: P (3, 4)}``."""
        ids = np.array(sorted(cameras), dtype=np.int64)
        return cls(ids, np.stack([np.asarray(cameras[int(i)], dtype=float) for i in ids]) if len(ids) else
                   np.zeros((0, 3, 4)))

    def lookup(self, image: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """For each image id: its rank among the sorted ids, whether it is known, and its row of ``projections``
        (an unknown id gets rank and row ``v``, one past the cameras)."""
        v = len(self.ids)
        order = np.argsort(self.ids)
        rank = np.searchsorted(self.ids[order], image)
        known = rank < v
        known[known] = self.ids[order][rank[known]] == image[known]
        rank = np.where(known, rank, v)
        row = np.full(len(image), v, dtype=np.int64)
        row[known] = order[rank[known]]
        return rank.astype(np.int64), known, row
