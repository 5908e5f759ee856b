"""Convex pieces of a triangle mesh: CoACD's decomposition, and the half-spaces of a hull.

CoACD (approximate convex decomposition by collision-aware concavity, PyPI ``coacd``) and
trimesh are the optional ``cad`` extra (``pip install -e '.[cad]'``); they are imported
when a decomposition is asked for, never at import time.
"""

from __future__ import annotations

import importlib.metadata
from dataclasses import dataclass, field

import numpy as np
from scipy.optimize import linprog
from scipy.spatial import ConvexHull, HalfspaceIntersection, QhullError

#: a part is taken as convex (one piece, its hull, no decomposition) when its volume is
#: within this fraction of its hull's volume
CONVEX_VOLUME_RATIO = 1e-6
#: a hull's triangles whose planes agree within this (unit normals' 1 - cos, offsets [m])
#: are one facet
COPLANAR = 1e-12
#: points closer than this are one corner of a hull [m]
DUPLICATE = 1e-11
#: a point this deep inside a region is a good enough start for its corners [m]
WELL_INSIDE = 1e-5
#: a region bounded by half-spaces is empty when no ball of this radius fits in it [m]
THINNEST = 1e-9


@dataclass(frozen=True)
class Hull:
    """A convex piece: its vertices and the half-spaces ``normals @ x + offsets <= 0``
    bounding it (outward unit normals, one row per hull facet)."""

    vertices: np.ndarray  # (n, 3)
    normals: np.ndarray = field(repr=False)  # (f, 3)
    offsets: np.ndarray = field(repr=False)  # (f,)
    triangles: np.ndarray = field(repr=False)  # (m, 3) vertex indices: Qhull's triangulation
    volume: float = field(repr=False)  # [m³]

    @staticmethod
    def of(points: np.ndarray) -> Hull:
        points = np.asarray(points, dtype=float)
        # corners found twice (planes meeting at one point) would trouble Qhull
        points = points[np.unique(np.round(points / DUPLICATE), axis=0, return_index=True)[1]]
        hull = _qhull(points)
        normals, offsets = _facets(hull.equations)
        index = np.full(len(points), -1)
        index[hull.vertices] = np.arange(len(hull.vertices))
        return Hull(hull.points[hull.vertices], normals, offsets, index[hull.simplices], float(hull.volume))

    @staticmethod
    def bounded_by(normals: np.ndarray, offsets: np.ndarray, inside: np.ndarray | None = None) -> Hull | None:
        """The bounded convex region ``normals @ x + offsets <= 0`` (unit normals), or None
        when no ball of radius :data:`THINNEST` fits in it. ``inside``: a point known to be
        inside it, deeper than that (else the deepest point is found by linear programming)."""
        normals, offsets = np.asarray(normals, float), np.asarray(offsets, float)
        if inside is None or -np.max(normals @ inside + offsets) < WELL_INSIDE:
            # Chebyshev centre: the deepest point, well inside for Qhull
            found = linprog(
                np.r_[0.0, 0.0, 0.0, -1.0],
                A_ub=np.column_stack([normals, np.ones(len(normals))]),
                b_ub=-offsets,
                bounds=[(None, None)] * 3 + [(0.0, None)],
                method="highs",
            )
            if found.status != 0 or found.x[3] < THINNEST:
                return None
            inside = found.x[:3]
        halfspaces = np.column_stack([normals, offsets])
        for options in ("", "Q12", "QJ"):
            try:
                corners = HalfspaceIntersection(
                    halfspaces, inside, qhull_options=f"H {options}"
                ).intersections
                break
            except QhullError:
                if options == "QJ":
                    raise
        return Hull.of(corners)

    def clipped(self, normal: np.ndarray, offset: float) -> Hull | None:
        """This hull cut by the half-space ``normal @ x + offset <= 0`` (None: less than
        :data:`THINNEST` of it is left)."""
        height = self.vertices @ normal + offset
        if height.max() <= 0.0:
            return self
        if height.min() > -THINNEST:
            return None
        edges = np.unique(np.sort(self.triangles[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2), axis=1), axis=0)
        a, b = height[edges[:, 0]], height[edges[:, 1]]
        cut = edges[(a < 0.0) != (b < 0.0)]
        t = height[cut[:, 0]] / (height[cut[:, 0]] - height[cut[:, 1]])
        crossings = self.vertices[cut[:, 0]] + t[:, None] * (
            self.vertices[cut[:, 1]] - self.vertices[cut[:, 0]]
        )
        return Hull.of(np.vstack([self.vertices[height <= 0.0], crossings]))

    def edges(self) -> np.ndarray:
        """The hull's edges as segments ``(e, 2, 3)`` (and the diagonals of its non-triangular
        facets, which a separating-axis test may use as well)."""
        pairs = np.unique(np.sort(self.triangles[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2), axis=1), axis=0)
        return self.vertices[pairs]

    @property
    def centre(self) -> np.ndarray:
        return self.vertices.mean(axis=0)

    def depth(self, points: np.ndarray) -> np.ndarray:
        """Signed depth of each point inside the hull [m]: the distance to its boundary
        for points inside (> 0), a lower bound of minus the distance outside (<= 0)."""
        return -np.max(points @ self.normals.T + self.offsets, axis=1)


def _qhull(points: np.ndarray) -> ConvexHull:
    """Qhull's hull, allowing wide facets, then joggling the input, if it must."""
    for options in (None, "Qt Q12", "QJ"):
        try:
            return ConvexHull(points, qhull_options=options)
        except QhullError:
            if options == "QJ":
                raise
    raise AssertionError("unreachable")


def _facets(equations: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Qhull's triangle planes (``n @ x + o = 0`` rows), one per facet (coplanar merged)."""
    same = (1.0 - equations[:, :3] @ equations[:, :3].T < COPLANAR) & (
        np.abs(equations[:, 3, None] - equations[None, :, 3]) < COPLANAR
    )
    first = ~np.any(np.tril(same, -1), axis=1)
    return equations[first, :3].copy(), equations[first, 3].copy()


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
