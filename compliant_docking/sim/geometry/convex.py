"""Convex pieces of a triangle mesh: CoACD's decomposition, and the half-spaces of a hull.

CoACD (approximate convex decomposition by collision-aware concavity, PyPI ``coacd``) and
trimesh are the optional ``cad`` extra (``pip install -e '.[cad]'``); they are imported
when a decomposition is asked for, never at import time.
"""

from __future__ import annotations

import importlib.metadata
from dataclasses import dataclass, field

import numpy as np
from scipy.spatial import ConvexHull

#: a part is taken as convex (one piece, its hull, no decomposition) when its volume is
#: within this fraction of its hull's volume
CONVEX_VOLUME_RATIO = 1e-6


@dataclass(frozen=True)
class Hull:
    """A convex piece: its vertices and the half-spaces ``normals @ x + offsets <= 0``
    bounding it (outward unit normals, one row per hull facet)."""

    vertices: np.ndarray  # (n, 3)
    normals: np.ndarray = field(repr=False)  # (f, 3)
    offsets: np.ndarray = field(repr=False)  # (f,)

    @staticmethod
    def of(points: np.ndarray) -> Hull:
        hull = ConvexHull(np.asarray(points, dtype=float))
        return Hull(hull.points[hull.vertices], hull.equations[:, :3].copy(), hull.equations[:, 3].copy())

    @property
    def volume(self) -> float:
        return float(ConvexHull(self.vertices).volume)

    def depth(self, points: np.ndarray) -> np.ndarray:
        """Signed depth of each point inside the hull [m]: the distance to its boundary
        for points inside (> 0), a lower bound of minus the distance outside (<= 0)."""
        return -np.max(points @ self.normals.T + self.offsets, axis=1)


def union_depth(hulls: list[Hull], points: np.ndarray, chunk: int = 4096) -> np.ndarray:
    """Largest depth of each point inside any of ``hulls`` (> 0: inside one) [m]."""
    out = np.full(len(points), -np.inf)
    for start in range(0, len(points), chunk):
        block = points[start : start + chunk]
        for hull in hulls:
            np.maximum(out[start : start + chunk], hull.depth(block), out=out[start : start + chunk])
    return out


def mesh_volume(vertices: np.ndarray, faces: np.ndarray) -> float:
    """Volume enclosed by a closed, outward-wound triangle mesh (divergence theorem)."""
    tri = vertices[faces]
    return float(np.einsum("ij,ij->i", tri[:, 0], np.cross(tri[:, 1], tri[:, 2])).sum() / 6.0)


def is_convex(vertices: np.ndarray, faces: np.ndarray) -> bool:
    """Whether the closed mesh fills its convex hull (to :data:`CONVEX_VOLUME_RATIO`)."""
    hull = ConvexHull(vertices).volume
    return abs(hull - mesh_volume(vertices, faces)) <= CONVEX_VOLUME_RATIO * hull


@dataclass(frozen=True)
class CoacdSettings:
    """CoACD's parameters that the decomposition depends on (the cache key holds them).

    threshold: concavity threshold (0.01-1, smaller: more, tighter pieces).
    resolution, mcts_*: CoACD's sampling resolution and tree search (its defaults).
    seed: CoACD's random seed (same seed, same pieces).
    """

    threshold: float = 0.05
    resolution: int = 2000
    mcts_nodes: int = 20
    mcts_iterations: int = 150
    mcts_max_depth: int = 3
    seed: int = 0

    def record(self) -> dict:
        return dict(self.__dict__)


def coacd_version() -> str | None:
    try:
        return importlib.metadata.version("coacd")
    except importlib.metadata.PackageNotFoundError:
        return None


def require_cad_extra() -> None:
    """Raise ImportError (:class:`~compliant_docking.extras.MissingExtra`) naming the ``cad``
    extra when coacd or trimesh is missing."""
    from compliant_docking.extras import require

    require("cad", "coacd", "trimesh")


def decompose(
    vertices: np.ndarray, faces: np.ndarray, settings: CoacdSettings, *, max_pieces: int = -1
) -> list[Hull]:
    """Convex pieces of a closed mesh (metres): its hull if it is convex, else CoACD's
    (at most ``max_pieces`` of them; -1: no cap)."""
    if is_convex(vertices, faces):
        return [Hull.of(vertices)]
    require_cad_extra()
    import coacd

    coacd.set_log_level("error")
    parts = coacd.run_coacd(
        coacd.Mesh(np.asarray(vertices, dtype=float), np.asarray(faces, dtype=np.int32)),
        threshold=settings.threshold,
        max_convex_hull=max_pieces,
        resolution=settings.resolution,
        mcts_nodes=settings.mcts_nodes,
        mcts_iterations=settings.mcts_iterations,
        mcts_max_depth=settings.mcts_max_depth,
        seed=settings.seed,
    )
    return [Hull.of(part_vertices) for part_vertices, _ in parts]
