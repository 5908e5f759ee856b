"""Convex pieces that collide like the solid they stand for.

MuJoCo collides the plug with each convex piece on its own and pushes it out of that piece
along the piece's direction of least penetration. A piece therefore answers with the
normal of whichever of its faces is nearest, whether or not that face is on the part's
surface. CoACD's pieces (:mod:`.convex`) break this in five ways, all measured on the
keyed example (docs/interfaces.md):

1. **bridging**: a piece is the hull of a part of the solid, so across a reflex (concave)
   edge it fills some free space (up to 0.33 mm at the keyed funnel's corners, where no
   clearance ray looks); the plug meets a face the solid does not have;
2. **cuts at reflex edges**: where two pieces meet at a reflex edge, the cut face between
   them reaches the surface with no depth: a plug pressed a few micrometres into one
   piece near the edge is pushed out through the cut face (56° off at the funnel's
   corners);
3. **cuts at convex edges**: a cut through a convex edge exposes a buried face, a ledge;
4. **seams in a face**: where a cut crosses a flat face, a plug corner pressed within a
   few micrometres of the seam is pushed sideways out of one piece (a pyramid tip on two
   boxes meeting in their top face: 64° off);
5. **slivers**: a piece thinner than the penetration is pushed through, normal reversed.

The pieces are rebuilt so that none of this can happen (the parametric sockets follow
the same rules by construction, :mod:`.socket`):

- **exact**: each piece is split by the plane of a triangle of the solid that passes
  through it, and again, until none does; the parts inside the solid are kept
  (:func:`clip_to_solid`). No piece reaches into the free space (1); the parts still
  cover the solid as CoACD's pieces did;
- **merged**: two pieces are replaced by their hull while it stays inside the solid,
  the pair whose hull adds least volume first (:func:`merge`): slivers (5) and most
  cuts go, and far fewer pieces collide (the keyed socket: 37 CoACD pieces, 75 exact
  parts, 8 merged, like the generator's four walls and floor). Facets within 1 µm of a
  plane of the solid are then moved into it (:func:`snapped`);
- **grown**: every cut face (a facet not in a plane of the solid) moves out by
  ``margin`` into the neighbour's material (:func:`grow`), so at a reflex edge each
  piece's surface face continues past the edge and its cut face is buried by
  ``margin · sin(edge angle)`` (2); a growth that would leave the solid past a convex
  edge is cut back by that edge's other face, so the edge lies inside the piece (3);
  where it would still leave the solid, the margin is halved;
- **bevelled**: where a piece's edge lies on a face of the solid that goes on beyond it
  (a seam in a face, 4), the other pieces cover the face over the overlap the growth
  made; the piece is cut by a plane through the middle of that overlap turned
  ``bevel_deg`` from the face (:func:`seam_bevels`), and its neighbour by the same line
  the other way. Each piece then ends in a wedge under its neighbour whose face is
  within ``bevel_deg`` of the surface, so a plug pressed at the seam is pushed within
  ``bevel_deg`` of the true normal; the wedge's thin end is buried
  ``overlap / 2 · tan(bevel_deg)`` deep (0.16 mm at the defaults where both pieces grew
  3 mm, 0.08 mm where one could not), deeper than a contact's penetration. A bevel whose
  wedge the other pieces would not cover is dropped (the seam stays sharp; the report
  counts them, and the contact audit judges what is left).

The cost: overlapping pieces may each report a contact near a seam (two contacts with
nearly the same normal over a strip of about penetration / tan(bevel_deg) around it),
and a piece has more faces. Every step keeps every piece inside the solid (checked
exactly, :class:`~.solid.Solid`); :func:`conform` then checks that the pieces still
cover the surface.
"""

from __future__ import annotations

import heapq
import math
import time
from dataclasses import dataclass

import numpy as np

from compliant_docking.sim.geometry.clearance import sample_surface
from compliant_docking.sim.geometry.convex import Hull, union_depth
from compliant_docking.sim.geometry.mesh import Mesh
from compliant_docking.sim.geometry.solid import Solid, clip_polygon

#: a piece may overlap the free space by this much (the triangles' crossing test) [m]
TOLERANCE = 1e-7
#: the coverage check probes this far below the surface [m]
PROBE = 1e-6
#: a piece's facet this close to a plane of the solid (and parallel) is moved into it [m]
SNAP = 1e-6
#: a seam is where a face of the solid goes on this far beyond a piece's edge [m]
SEAM_PROBE = 1e-5
#: two facets of a piece whose normals are closer than this (sine) meet at no edge
SIN_COPLANAR = 1e-3
#: at most this many splits per CoACD piece
MAX_SPLITS = 5000


@dataclass(frozen=True)
class ConformSettings:
    """How the pieces are rebuilt (module doc). margin [m]: how far cut faces move into
    the neighbour's material; bevel_deg: the seams' bevel from the surface [deg]."""

    margin: float = 0.003
    bevel_deg: float = 3.0

    def record(self) -> dict:
        return dict(self.__dict__)

    def check(self) -> None:
        if not (math.isfinite(self.margin) and self.margin > 0.0):
            raise ValueError(f"margin must be a length > 0 [m]; got {self.margin!r}")
        if not (math.isfinite(self.bevel_deg) and 0.0 < self.bevel_deg < 45.0):
            raise ValueError(f"bevel_deg must be in (0, 45) [deg]; got {self.bevel_deg!r}")


@dataclass(frozen=True)
class ConformReport:
    """What :func:`conform` did to one part's pieces and what it measured."""

    coacd: int  # pieces in
    exact: int  # after splitting by the solid's planes
    pieces: int  # after merging (out)
    cut_faces: int
    full_margin: int  # cut faces grown by the whole margin
    least_margin_m: float  # the smallest margin a cut face got (0: one could not grow)
    bevels: int
    sharp_seams: int  # seams left without a bevel (no other piece covers the face beyond)
    uncovered: float  # share of surface points (PROBE below it) in no piece
    seconds: float

    @property
    def covered(self) -> bool:
        return self.uncovered == 0.0

    def summary(self) -> str:
        return (
            f"{self.coacd} CoACD pieces → {self.exact} exact → {self.pieces} merged; "
            f"{self.full_margin} of {self.cut_faces} cut faces grown by the full margin "
            f"(least {1e3 * self.least_margin_m:.3g} mm), {self.bevels} seams bevelled, {self.sharp_seams} left sharp; "
            f"surface {'covered' if self.covered else f'NOT covered ({100 * self.uncovered:.3f} % of points)'}"
        )

    def record(self) -> dict:
        return dict(self.__dict__)


def conform(
    hulls: list[Hull], mesh: Mesh, settings: ConformSettings, *, samples: int = 20_000, seed: int = 0
) -> tuple[list[Hull], ConformReport]:
    """The pieces of a part rebuilt by the module doc's rules, and the report."""
    started = time.perf_counter()
    solid = Solid(mesh)
    exact = [part for hull in hulls for part in clip_to_solid(hull, solid)]
    merged = merge(exact, solid, reach=settings.margin)
    merged = [snapped(piece, solid) for piece in merged]
    grown = [grow(piece, solid, settings.margin) for piece in merged]
    out, bevel_count, sharp = bevel([hull for hull, _, _ in grown], solid, settings)
    margins = [
        margin[: len(piece.normals)][~on_surface(piece, solid)]
        for piece, (_, _, margin) in zip(merged, grown)
    ]
    cut_margins = np.concatenate(margins) if margins else np.zeros(0)
    surface = sample_surface(mesh, samples, seed)
    uncovered = union_depth(out, surface.points - PROBE * surface.normals) <= 0.0
    report = ConformReport(
        coacd=len(hulls),
        exact=len(exact),
        pieces=len(out),
        cut_faces=len(cut_margins),
        full_margin=int(np.sum(cut_margins >= settings.margin)),
        least_margin_m=float(cut_margins.min()) if len(cut_margins) else settings.margin,
        bevels=bevel_count,
        sharp_seams=sharp,
        uncovered=float(uncovered.mean()),
        seconds=time.perf_counter() - started,
    )
    return out, report


def bevel(shapes: list[Hull], solid: Solid, settings: ConformSettings) -> tuple[list[Hull], int, int]:
    """The grown pieces cut by their seams' bevels (:func:`seam_bevels`), a bevel kept only
    where the other pieces, bevelled, cover what it cuts off; and the numbers of seams
    bevelled and left sharp."""
    cuts, sharp = [], 0
    for i, hull in enumerate(shapes):
        planes, left = seam_bevels(
            hull, shapes[:i] + shapes[i + 1 :], solid, settings.margin, settings.bevel_deg
        )
        cuts.append(planes)
        sharp += len(left)
    kept = [np.ones(len(c), dtype=bool) for c in cuts]
    out = [_bevelled(hull, c) for hull, c in zip(shapes, cuts)]
    for i, hull in enumerate(shapes):  # dropping a bevel only adds cover for the others
        others = out[:i] + out[i + 1 :]
        for k, plane in enumerate(cuts[i]):
            removed = hull.clipped(-plane[:3], -plane[3])
            if removed is not None:
                kept[i][k] = union_depth(others, _surface_probes(removed, solid)).min() > 0.0
        out[i] = _bevelled(hull, cuts[i][kept[i]])
    return out, int(sum(k.sum() for k in kept)), sharp + int(sum((~k).sum() for k in kept))


def _surface_probes(hull: Hull, solid: Solid, per_facet: int = 400, seed: int = 0) -> np.ndarray:
    """Points :data:`PROBE` below the solid's surface, drawn uniformly over the hull's
    facets that lie on it (``per_facet`` each), and the hull's centre."""
    rng = np.random.default_rng(seed)
    out = [hull.centre[None]]
    surface = on_surface(hull, solid)
    for n, o in zip(hull.normals[surface], hull.offsets[surface]):
        corners = hull.vertices[np.abs(hull.vertices @ n + o) < 1e-10]
        if len(corners) < 3:
            continue
        centre = corners.mean(axis=0)
        # the facet as a fan of triangles around its centre, corners in order
        u = corners[0] - centre
        u /= np.linalg.norm(u)
        angle = np.arctan2((corners - centre) @ np.cross(n, u), (corners - centre) @ u)
        ring = corners[np.argsort(angle)]
        a, b = ring, np.roll(ring, -1, axis=0)
        area = 0.5 * np.linalg.norm(np.cross(a - centre, b - centre), axis=1)
        pick = rng.choice(len(ring), size=per_facet, p=area / area.sum())
        r1, r2 = rng.random(per_facet), rng.random(per_facet)
        flip = r1 + r2 > 1.0
        r1[flip], r2[flip] = 1.0 - r1[flip], 1.0 - r2[flip]
        points = centre + r1[:, None] * (a[pick] - centre) + r2[:, None] * (b[pick] - centre)
        out.append(points - PROBE * n)
    return np.vstack(out)


def _bevelled(hull: Hull, planes: np.ndarray) -> Hull:
    for plane in planes:
        hull = hull.clipped(plane[:3], plane[3]) or hull
    return hull


def inside(hull: Hull, solid: Solid, tolerance: float = TOLERANCE) -> bool:
    """Whether the hull lies inside the solid (it overlaps no triangle by more than
    ``tolerance`` and its centre is inside)."""
    return not solid.enters(hull, tolerance) and solid.holds(hull)


def clip_to_solid(hull: Hull, solid: Solid, tolerance: float = TOLERANCE) -> list[Hull]:
    """The parts of a convex hull inside the solid, each convex: the hull split by the
    plane of a triangle that passes through it, then each side again, until no triangle
    passes through a part (then it is wholly inside or wholly outside)."""
    out, stack, splits = [], [hull], 0
    while stack:
        part = stack.pop()
        planes = solid.crossing(part, tolerance)
        if not len(planes):
            if solid.holds(part):
                out.append(part)
            continue
        splits += 1
        if splits > MAX_SPLITS:
            raise ValueError(
                f"a convex piece needs more than {MAX_SPLITS} splits to fit the part's surface: "
                "decompose more finely (lower --threshold) or use --collision sdf"
            )
        normal, offset = solid.planes[planes[0], :3], solid.planes[planes[0], 3]
        for sign in (1.0, -1.0):
            side = part.clipped(sign * normal, sign * offset)
            if side is not None:
                stack.append(side)
    return out


def touching(a: Hull, b: Hull, slack: float) -> bool:
    """Whether two hulls come within ``slack`` of each other, as far as their facet
    planes tell (no facet plane of either leaves the other wholly outside by more)."""
    return not (
        np.any((b.vertices @ a.normals.T).min(axis=0) > -a.offsets + slack)
        or np.any((a.vertices @ b.normals.T).min(axis=0) > -b.offsets + slack)
    )


def merge(hulls: list[Hull], solid: Solid, *, reach: float, tolerance: float = TOLERANCE) -> list[Hull]:
    """Greedily replace two pieces within ``reach`` of each other by their hull while it
    stays inside the solid, the pair whose hull adds the least volume first."""
    pieces = dict(enumerate(hulls))
    heap: list[tuple[float, int, int, int]] = []
    hull_of: dict[int, Hull] = {}
    counter = iter(range(1 << 62))

    def consider(i: int, j: int) -> None:
        a, b = pieces[i], pieces[j]
        if not touching(a, b, reach):
            return
        both = Hull.of(np.vstack([a.vertices, b.vertices]))
        if inside(both, solid, tolerance):
            k = next(counter)
            hull_of[k] = both
            heapq.heappush(heap, (both.volume - a.volume - b.volume, i, j, k))

    keys = sorted(pieces)
    for x, i in enumerate(keys):
        for j in keys[x + 1 :]:
            consider(i, j)
    fresh = len(hulls)
    while heap:
        _, i, j, k = heapq.heappop(heap)
        both = hull_of.pop(k)
        if i not in pieces or j not in pieces:
            continue
        del pieces[i], pieces[j]
        pieces[fresh] = both
        for x in list(pieces):
            if x != fresh:
                consider(x, fresh)
        fresh += 1
    return list(pieces.values())


def on_surface(hull: Hull, solid: Solid, tolerance: float = 1e-9) -> np.ndarray:
    """Per facet of the hull: does it lie in a plane of the solid, facing the same way?"""
    same = (1.0 - hull.normals @ solid.planes[:, :3].T < 1e-9) & (
        np.abs(hull.offsets[:, None] - solid.planes[None, :, 3]) < tolerance
    )
    return np.asarray(same.any(axis=1))


def snapped(hull: Hull, solid: Solid, tolerance: float = TOLERANCE) -> Hull:
    """The hull with every facet that lies within :data:`SNAP` of a plane of the solid,
    facing the same way, moved into that plane (CoACD's faces and Qhull's merged facets
    stray from the surface by micrometres), if it then still lies inside the solid."""
    near = (1.0 - hull.normals @ solid.planes[:, :3].T < 1e-9) & (
        np.abs(hull.offsets[:, None] - solid.planes[None, :, 3]) < SNAP
    )
    if not near.any():
        return hull
    planes = np.column_stack([hull.normals, hull.offsets])
    rows = np.flatnonzero(near.any(axis=1))
    planes[rows] = solid.planes[np.argmax(near[rows], axis=1)]
    moved = Hull.bounded_by(planes[:, :3], planes[:, 3], inside=hull.centre)
    return moved if moved is not None and inside(moved, solid, tolerance) else hull


def _behind(hull: Hull, plane: np.ndarray, tolerance: float) -> bool:
    return bool(np.all(hull.vertices @ plane[:3] + plane[3] <= tolerance))


def grow(
    hull: Hull, solid: Solid, margin: float, *, tolerance: float = TOLERANCE, halvings: int = 4
) -> tuple[Hull, np.ndarray, np.ndarray]:
    """The hull with every cut face moved out by up to ``margin`` (module doc).

    A grown hull that crosses a plane of the solid which the hull lies behind (the other
    face of a convex edge beyond the cut) is cut back by it; one that would still leave
    the solid has the margins of the cut faces whose growth reaches the crossing halved
    (``halvings`` times, then 0). Returns the grown hull; its planes (k, 4): the hull's
    facets with their grown offsets, then the solid's planes that cut it back; and the
    margin of each (k,)."""
    planes = np.column_stack([hull.normals, hull.offsets])
    margins = np.where(on_surface(hull, solid), 0.0, margin)
    for _ in range(halvings + 2):
        trial = planes.copy()
        trial[:, 3] -= margins
        grown = Hull.bounded_by(trial[:, :3], trial[:, 3], inside=hull.centre)
        box = grown
        added: list[np.ndarray] = []
        blocking: list[int] = []
        while grown is not None:
            crossed = solid.crossing(grown, tolerance)
            if not len(crossed):
                break
            for p in crossed:
                if not _behind(hull, solid.planes[p], tolerance):
                    blocking.append(int(p))
                elif grown is not None:
                    added.append(solid.planes[p])
                    grown = grown.clipped(solid.planes[p, :3], solid.planes[p, 3])
            if blocking:
                break
        if grown is not None and not blocking and solid.holds(grown):
            return grown, np.vstack([trial, *added]), np.r_[margins, np.zeros(len(added))]
        # halve the margins of the cut faces whose growth reaches the blocking triangles
        reach = np.zeros(len(planes), dtype=bool)
        for triangle in solid.triangles[np.isin(solid.plane_of, blocking)]:
            polygon = triangle if box is None else clip_polygon(triangle, box.normals, box.offsets)
            if len(polygon):
                reach |= np.any(polygon @ planes[:, :3].T + planes[:, 3] > -tolerance, axis=0)
        reach &= margins > 0.0
        if not reach.any():
            reach = margins > 0.0
        margins[reach] = np.where(margins[reach] > margin / 2**halvings, margins[reach] / 2.0, 0.0)
    return hull, planes, np.zeros(len(planes))


def _edges(hull: Hull) -> list[tuple[int, int, np.ndarray]]:
    """The hull's edges: (facet, facet, the edge's two end points (2, 3))."""
    on = np.abs(hull.vertices @ hull.normals.T + hull.offsets) < 1e-10  # (vertices, facets)
    out = []
    for a in range(len(hull.normals)):
        for b in range(a + 1, len(hull.normals)):
            shared = hull.vertices[on[:, a] & on[:, b]]
            if len(shared) >= 2:
                axis = np.cross(hull.normals[a], hull.normals[b])
                order = np.argsort(shared @ axis)
                out.append((a, b, shared[[order[0], order[-1]]]))
    return out


def seam_bevels(
    grown: Hull, others: list[Hull], solid: Solid, margin: float, angle_deg: float
) -> tuple[np.ndarray, np.ndarray]:
    """The bevel planes (k, 4) of a grown piece's seams (module doc), and the number of
    seams left sharp (no other piece covers the face back from them), the middle of each.

    A seam is an edge of the piece that lies on a face of the solid, in the plane of one
    of the piece's two facets there, while the face goes on beyond it. The other pieces
    cover the face over some width ``w`` on the piece's side of the seam (the overlap the
    growth made; at most ``2 * margin`` is looked for); the bevel passes through the line
    ``w / 2`` back from the seam, the middle of the overlap, turned by ``angle_deg`` from
    the face so that it dips below it towards the seam. The neighbour, bevelled through
    the same line the other way, owns the face beyond it."""
    turn = math.radians(angle_deg)
    surface = on_surface(grown, solid)
    steps = np.linspace(0.0, 2.0 * margin, 65)
    out, sharp = [], []
    for a, b, ends in _edges(grown):
        for f, c in ((a, b), (b, a)):
            if not surface[f]:
                continue
            n_f, n_c = grown.normals[f], grown.normals[c]
            across = n_c - (n_c @ n_f) * n_f
            if np.linalg.norm(across) < SIN_COPLANAR:  # the two facets are (nearly) one plane
                continue
            across /= np.linalg.norm(across)
            face = solid.plane_index(n_f, grown.offsets[f])
            probes = ends[0] + np.array([[0.5], [0.25], [0.75]]) * (ends[1] - ends[0])
            middle = probes[0]
            if not (
                solid.on_face(middle, face, 1e-9) and solid.on_face(middle + SEAM_PROBE * across, face, 1e-9)
            ):
                continue  # not on the surface, or the face ends here (an edge of the solid)
            # how far back from the seam the pieces that own the face beyond it cover it
            beyond = probes + SEAM_PROBE * across - PROBE * n_f
            owners = [o for o in others if np.any(o.depth(beyond) > 0.0)]
            points = probes[:, None, :] - steps[None, :, None] * across - PROBE * n_f
            covered = np.all((union_depth(owners, points.reshape(-1, 3)) > 0.0).reshape(3, -1), axis=0)
            width = steps[len(steps) - 1 if covered.all() else max(int(np.argmin(covered)) - 1, 0)]
            if not covered[0] or width < 2.0 * SEAM_PROBE:
                sharp.append(middle)
                continue
            point = middle - 0.5 * width * across
            normal = math.cos(turn) * n_f + math.sin(turn) * across
            out.append(np.r_[normal, -normal @ point])
    planes = np.array(out).reshape(-1, 4)
    # seams along one line (pieces of one cut) share a bevel: the one cutting off least
    keep = [
        k
        for k, plane in enumerate(planes)
        if not np.any((1.0 - planes[:, :3] @ plane[:3] < 1e-12) & (planes[:, 3] < plane[3] - 1e-12))
    ]
    return planes[keep], np.array(sharp).reshape(-1, 3)
