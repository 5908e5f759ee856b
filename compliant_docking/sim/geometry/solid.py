"""A part as a closed triangle mesh: its planes, which points it holds, and which of its
faces enter a convex region.

The converter (:mod:`.conform`) uses it to keep convex pieces inside the part: a convex
piece lies inside the solid exactly when none of the solid's triangles passes through the
piece's interior and one interior point of the piece is inside the solid (the surface
is what separates inside from outside). Both tests are exact up to the tolerance they
are given (no sampling): the triangle test is a separating-axis test against the piece
shrunk by that tolerance, the point test the generalised winding number.
"""

from __future__ import annotations

import math

import numpy as np

from compliant_docking.sim.geometry.convex import Hull
from compliant_docking.sim.geometry.mesh import Mesh

#: triangles whose unit normals agree to 1e-7 and whose planes' offsets agree to 1e-9 m
#: lie in one plane of the solid (float32 STL coordinates are good to ~1e-9 m at 0.1 m)
NORMAL_DIGITS, OFFSET_DIGITS = 7, 9


class Solid:
    """The closed, outward-wound triangle mesh of a part [m], its triangles grouped by plane.

    ``planes`` (p, 4): unit outward normal and offset of each plane (``n @ x + o = 0``,
    the solid on the side ``n @ x + o <= 0`` near its triangles); ``plane_of`` (t,): each
    triangle's plane.
    """

    def __init__(self, mesh: Mesh):
        vertices, faces = mesh
        triangles = np.asarray(vertices, dtype=float)[np.asarray(faces)]
        cross = np.cross(triangles[:, 1] - triangles[:, 0], triangles[:, 2] - triangles[:, 0])
        area = np.linalg.norm(cross, axis=1)
        keep = area > 1e-18
        self.triangles = triangles[keep]
        normals = cross[keep] / area[keep, None]
        offsets = -np.einsum("ij,ij->i", normals, self.triangles[:, 0])
        key = np.column_stack([np.round(normals, NORMAL_DIGITS), np.round(offsets, OFFSET_DIGITS)])
        unique, self.plane_of = np.unique(key, axis=0, return_inverse=True)
        self.plane_of = self.plane_of.ravel()
        planes = np.zeros((len(unique), 4))
        np.add.at(planes, self.plane_of, np.column_stack([normals, offsets]))
        planes[:, :3] /= np.linalg.norm(planes[:, :3], axis=1, keepdims=True)
        counts = np.bincount(self.plane_of, minlength=len(unique))
        planes[:, 3] = np.bincount(self.plane_of, weights=offsets, minlength=len(unique)) / counts
        self.planes = planes
        self.lower, self.upper = self.triangles.min(axis=1), self.triangles.max(axis=1)
        # points on the surface for a quick first look (corners, edge middles, centres)
        t = self.triangles
        self.samples = np.unique(
            np.vstack([t.reshape(-1, 3), 0.5 * (t + t[:, [1, 2, 0]]).reshape(-1, 3), t.mean(axis=1)]), axis=0
        )
        self.size = float(np.linalg.norm(self.upper.max(axis=0) - self.lower.min(axis=0)))

    def plane_index(self, normal: np.ndarray, offset: float) -> int:
        """The solid's plane nearest to ``normal @ x + offset = 0``."""
        return int(np.argmin(np.abs(self.planes[:, :3] @ normal - 1.0) + np.abs(self.planes[:, 3] - offset)))

    def on_face(self, points: np.ndarray, plane: int, tolerance: float) -> bool:
        """Whether any of ``points`` lies within ``tolerance`` of a triangle in ``plane``."""
        triangles = self.triangles[self.plane_of == plane]
        return any(
            _point_triangle_distance(p, triangles).min() <= tolerance
            for p in np.atleast_2d(np.asarray(points, float))
        )

    def winding(self, points: np.ndarray) -> np.ndarray:
        """Generalised winding number of each point: 1 inside, 0 outside (exact for a
        closed mesh; ½ on its surface)."""
        points = np.atleast_2d(np.asarray(points, dtype=float))
        out = np.empty(len(points))
        for i, p in enumerate(points):
            a, b, c = (self.triangles[:, k] - p for k in range(3))
            la, lb, lc = (np.linalg.norm(v, axis=1) for v in (a, b, c))
            numerator = np.einsum("ij,ij->i", a, np.cross(b, c))
            denominator = (
                la * lb * lc
                + np.einsum("ij,ij->i", a, b) * lc
                + np.einsum("ij,ij->i", a, c) * lb
                + np.einsum("ij,ij->i", b, c) * la
            )
            out[i] = np.arctan2(numerator, denominator).sum() / (2.0 * math.pi)
        return out

    def holds(self, hull: Hull) -> bool:
        """Whether the hull's centre is inside the solid (with :meth:`crossing` empty: the
        whole hull is)."""
        return bool(self.winding(hull.centre)[0] > 0.5)

    def enters(self, hull: Hull, tolerance: float) -> bool:
        """Whether any triangle overlaps the hull by more than ``tolerance`` (as
        :meth:`crossing`, answered early when a point of the surface lies that deep in it)."""
        low, high = hull.vertices.min(axis=0), hull.vertices.max(axis=0)
        near = self.samples[np.all((self.samples > low) & (self.samples < high), axis=1)]
        if len(near) and hull.depth(near).max() > tolerance:
            return True
        return bool(len(self.crossing(hull, tolerance)))

    def crossing(self, hull: Hull, tolerance: float) -> np.ndarray:
        """The planes (indices into ``planes``) of the triangles that the hull overlaps by
        more than ``tolerance`` (the translation that would separate them), sorted by how
        many of their triangles do."""
        low, high = hull.vertices.min(axis=0) + tolerance, hull.vertices.max(axis=0) - tolerance
        near = np.flatnonzero(np.all((self.lower < high) & (self.upper > low), axis=1))
        if not len(near):
            return np.zeros(0, dtype=int)
        hit = near[_overlaps(self.triangles[near], hull, tolerance)]
        planes, counts = np.unique(self.plane_of[hit], return_counts=True)
        return planes[np.argsort(-counts, kind="stable")]


def _separated(a: np.ndarray, b: np.ndarray, slack: float) -> np.ndarray:
    """Per axis: do the projections ``a`` (..., m) and ``b`` (..., k) overlap by less than
    ``slack``?"""
    return (a.min(axis=-1) >= b.max(axis=-1) - slack) | (a.max(axis=-1) <= b.min(axis=-1) + slack)


def _overlaps(triangles: np.ndarray, hull: Hull, slack: float, chunk: int = 256) -> np.ndarray:
    """Separating-axis test of each triangle (t, 3, 3) against a convex hull: True where
    they overlap by more than ``slack`` along every axis (the hull's facet normals, the
    triangle's normal, the cross products of their edges), i.e. where the smallest
    translation that separates them is longer than ``slack``."""
    vertices = hull.vertices
    # the hull's facet normals first (cheap): the triangle lies (almost) outside one of its half-spaces
    out = ~np.any((triangles @ hull.normals.T).min(axis=1) >= -hull.offsets - slack, axis=1)
    if not out.any():
        return out
    edges = hull.edges()
    hull_dirs = edges[:, 1] - edges[:, 0]
    hull_dirs /= np.linalg.norm(hull_dirs, axis=1, keepdims=True)
    for index in np.array_split(np.flatnonzero(out), max(1, int(out.sum()) // chunk)):
        tri = triangles[index]
        normal = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
        normal /= np.linalg.norm(normal, axis=1, keepdims=True)
        apart = _separated(np.einsum("tj,tkj->tk", normal, tri), normal @ vertices.T, slack)
        tri_dirs = tri[:, [1, 2, 0]] - tri
        tri_dirs /= np.linalg.norm(tri_dirs, axis=-1, keepdims=True)
        axes = np.cross(tri_dirs[:, :, None, :], hull_dirs[None, None, :, :])  # (t, 3, e, 3)
        length = np.linalg.norm(axes, axis=-1, keepdims=True)
        usable = length[..., 0] > 1e-6  # edges not parallel
        axes = axes / np.maximum(length, 1e-300)
        tri_proj = np.einsum("tiej,tkj->tiek", axes, tri)
        hull_proj = np.einsum("tiej,kj->tiek", axes, vertices)
        apart |= np.any(usable & _separated(tri_proj, hull_proj, slack), axis=(1, 2))
        out[index] = ~apart
    return out


def _point_triangle_distance(p: np.ndarray, triangles: np.ndarray) -> np.ndarray:
    """Distance from ``p`` to each triangle (t, 3, 3)."""
    a, b, c = triangles[:, 0], triangles[:, 1], triangles[:, 2]
    normal = np.cross(b - a, c - a)
    n2 = np.einsum("ij,ij->i", normal, normal)
    ap = p - a
    v = np.einsum("ij,ij->i", np.cross(ap, c - a), normal) / n2
    w = np.einsum("ij,ij->i", np.cross(b - a, ap), normal) / n2
    inside = (v >= 0) & (w >= 0) & (v + w <= 1)
    plane = np.abs(np.einsum("ij,ij->i", ap, normal)) / np.sqrt(n2)

    def segment(s: np.ndarray, e: np.ndarray) -> np.ndarray:
        d = e - s
        t = np.clip(np.einsum("ij,ij->i", p - s, d) / np.einsum("ij,ij->i", d, d), 0.0, 1.0)
        return np.linalg.norm(p - (s + t[:, None] * d), axis=1)

    edges = np.minimum(np.minimum(segment(a, b), segment(b, c)), segment(c, a))
    return np.where(inside, plane, edges)


def clip_polygon(polygon: np.ndarray, normals: np.ndarray, offsets: np.ndarray) -> np.ndarray:
    """The part of a convex polygon (k, 3) inside ``normals @ x + offsets <= 0``."""
    for n, o in zip(normals, offsets):
        if not len(polygon):
            break
        h = polygon @ n + o
        out = []
        for k in range(len(polygon)):
            a, b, ha, hb = polygon[k], polygon[(k + 1) % len(polygon)], h[k], h[(k + 1) % len(polygon)]
            if ha <= 0.0:
                out.append(a)
            if (ha < 0.0) != (hb < 0.0) and ha != hb:
                out.append(a + ha / (ha - hb) * (b - a))
        polygon = np.array(out).reshape(-1, 3)
    return polygon
