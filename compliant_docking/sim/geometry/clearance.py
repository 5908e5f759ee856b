"""Does a convex decomposition keep the clearance of a mated plug and socket?

Both parts are given in one frame at the mated pose (the CAD assembly pose), the
docking axis along z. The plug is lifted off the seat along z by ``lift`` (so the
seat, where the parts touch by design, does not count as zero clearance; lateral gaps
do not change when the plug rises in a straight bore). Points are then sampled on each
part's surface (area-weighted, seeded); from each point a ray is cast along the outward
normal, and the distance at which it meets the OTHER part is that point's gap:

- against the other part's own surface (its triangles, by MuJoCo's ray casting): the
  nominal gap;
- against the other part's convex pieces: the gap the simulation will see; a point
  inside a piece has a negative gap, minus its depth (distance to the piece's boundary).

The decomposition keeps the clearance when every point keeps at least ``keep`` of its
nominal gap, from both sides (the plug's surface against the socket's pieces, which
fill the socket's concavities; and the socket's surface against the plug's pieces). The
reported clearances are the smallest gaps. Rays measure a gap along the normal: for
walls facing each other (a peg in a bore) that is the clearance itself.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import mujoco
import numpy as np

from compliant_docking.sim.geometry.convex import Hull, union_depth
from compliant_docking.sim.geometry.mesh import Mesh

#: default number of surface samples per part
SAMPLES = 20_000
#: gaps are compared within this (float32 STL coordinates, CoACD's cuts) [m]
TOLERANCE = 1e-6
#: the plug is lifted this far off the seat for the check [m]
LIFT = 0.001
#: rays start this far inside their own part, so contact at zero gap is seen [m]
RAY_BACKOFF = 1e-6


@dataclass(frozen=True)
class Surface:
    """Points on a part's surface and the outward unit normals there."""

    points: np.ndarray
    normals: np.ndarray


def sample_surface(mesh: Mesh, count: int = SAMPLES, seed: int = 0) -> Surface:
    """``count`` points drawn uniformly over the area of a closed, outward-wound mesh."""
    vertices, faces = mesh
    tri = np.asarray(vertices, dtype=float)[faces]
    cross = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    area = np.linalg.norm(cross, axis=1)
    rng = np.random.default_rng(seed)
    face = rng.choice(len(faces), size=count, p=area / area.sum())
    u, v = rng.random(count), rng.random(count)
    flip = u + v > 1.0
    u[flip], v[flip] = 1.0 - u[flip], 1.0 - v[flip]
    t = tri[face]
    points = t[:, 0] + u[:, None] * (t[:, 1] - t[:, 0]) + v[:, None] * (t[:, 2] - t[:, 0])
    return Surface(points, cross[face] / area[face, None])


class _RayScene:
    """A static MuJoCo model of one part's surface (group 0) and its pieces (group 1)."""

    def __init__(self, mesh: Mesh, hulls: list[Hull]):
        spec = mujoco.MjSpec()
        vertices, faces = mesh
        spec.add_mesh(name="surface", uservert=np.ravel(vertices).tolist(), userface=np.ravel(faces).tolist())
        spec.worldbody.add_geom(type=mujoco.mjtGeom.mjGEOM_MESH, meshname="surface", group=0, density=0.0)
        for i, hull in enumerate(hulls):
            spec.add_mesh(name=f"piece_{i}", uservert=hull.vertices.ravel().tolist())
            spec.worldbody.add_geom(
                type=mujoco.mjtGeom.mjGEOM_MESH, meshname=f"piece_{i}", group=1, density=0.0
            )
        self.model = spec.compile()
        self.data = mujoco.MjData(self.model)
        mujoco.mj_forward(self.model, self.data)

    def gaps(self, surface: Surface, group: int) -> np.ndarray:
        """Distance along each normal to the geoms of ``group`` (inf: no hit)."""
        mask = np.zeros(6, dtype=np.uint8)
        mask[group] = 1
        geomid = np.zeros(1, dtype=np.int32)
        starts = surface.points - RAY_BACKOFF * surface.normals
        out = np.empty(len(starts))
        ray, model, data = mujoco.mj_ray, self.model, self.data
        for i, (start, normal) in enumerate(zip(starts, surface.normals)):
            hit = ray(model, data, start, normal, mask, 1, -1, geomid)
            out[i] = hit - RAY_BACKOFF if hit >= 0.0 else np.inf
        return out


@dataclass(frozen=True)
class SideReport:
    """One part's surface against the other part (its surface and its pieces)."""

    nominal_m: float  # smallest nominal gap (inf: no point faces the other part)
    pieces_m: float  # smallest gap to the pieces (negative: depth inside one)
    kept: float  # smallest ratio of a point's gap to the pieces over its nominal gap
    inside_fraction: float  # share of the points facing the other part that lie inside a piece


def _side(surface: Surface, other: _RayScene, other_hulls: list[Hull], tolerance: float) -> SideReport:
    nominal = other.gaps(surface, 0)
    depth = union_depth(other_hulls, surface.points)
    inside = depth > tolerance
    pieces = np.where(inside, -depth, other.gaps(surface, 1))
    facing = np.isfinite(nominal)
    if not facing.any():
        return SideReport(math.inf, math.inf, 1.0, 0.0)
    ratio = (pieces[facing] + tolerance) / np.maximum(nominal[facing], tolerance)
    return SideReport(
        nominal_m=float(nominal[facing].min()),
        pieces_m=float(pieces[facing].min()),
        kept=float(min(ratio.min(), 1.0)),
        inside_fraction=float(np.mean(inside[facing])),
    )


@dataclass(frozen=True)
class ClearanceReport:
    """The decomposition against the nominal clearance, from both sides (module doc)."""

    plug: SideReport  # the plug's surface against the socket (its surface, its pieces)
    socket: SideReport  # the socket's surface against the plug
    keep: float  # share of each nominal gap the pieces must keep
    lift: float  # the plug was lifted this far off the seat [m]

    @property
    def nominal_m(self) -> float:
        """The parts' own clearance: the smallest nominal gap from either side [m]."""
        return min(self.plug.nominal_m, self.socket.nominal_m)

    @property
    def pieces_m(self) -> float:
        """The clearance the convex pieces leave (negative: they intrude) [m]."""
        return min(self.plug.pieces_m, self.socket.pieces_m)

    def refine(self) -> list[str]:
        """The parts whose pieces lose clearance ("socket": its pieces come too close to
        the plug's surface; "plug": the other way round). Empty: the check passes."""
        return [
            part for side, part in ((self.plug, "socket"), (self.socket, "plug")) if side.kept < self.keep
        ]

    @property
    def passed(self) -> bool:
        return math.isfinite(self.nominal_m) and not self.refine()

    def summary(self) -> str:
        return (
            f"clearance (plug lifted {1e3 * self.lift:g} mm off the seat): nominal "
            f"{1e3 * self.nominal_m:.4f} mm, convex pieces {1e3 * self.pieces_m:.4f} mm; worst "
            f"point keeps {100 * min(self.plug.kept, self.socket.kept):.1f} % of its gap "
            f"(at least {100 * self.keep:.0f} % required); plug surface inside socket pieces "
            f"{100 * self.plug.inside_fraction:.2f} %, socket surface inside plug pieces "
            f"{100 * self.socket.inside_fraction:.2f} %"
        )

    def record(self) -> dict:
        return {
            "nominal_clearance_m": self.nominal_m,
            "pieces_clearance_m": self.pieces_m,
            "worst_kept": min(self.plug.kept, self.socket.kept),
            "plug_inside_socket_pieces_fraction": self.plug.inside_fraction,
            "socket_inside_plug_pieces_fraction": self.socket.inside_fraction,
            "keep": self.keep,
            "lift_m": self.lift,
            "passed": self.passed,
        }


def _lifted(mesh: Mesh, lift: float) -> Mesh:
    return np.asarray(mesh[0], dtype=float) + [0.0, 0.0, lift], mesh[1]


def check_clearance(
    plug: Mesh,
    plug_hulls: list[Hull],
    socket: Mesh,
    socket_hulls: list[Hull],
    *,
    keep: float = 0.5,
    lift: float = LIFT,
    samples: int = SAMPLES,
    seed: int = 0,
    tolerance: float = TOLERANCE,
) -> ClearanceReport:
    """Measure the clearance the pieces keep at the mated pose, plug lifted by ``lift``
    (the module doc says how); passes when every sampled point keeps at least ``keep``
    of its nominal gap (within ``tolerance``) from both sides."""
    plug = _lifted(plug, lift)
    plug_hulls = [Hull.of(h.vertices + [0.0, 0.0, lift]) for h in plug_hulls]
    return ClearanceReport(
        plug=_side(
            sample_surface(plug, samples, seed), _RayScene(socket, socket_hulls), socket_hulls, tolerance
        ),
        socket=_side(
            sample_surface(socket, samples, seed + 1), _RayScene(plug, plug_hulls), plug_hulls, tolerance
        ),
        keep=keep,
        lift=lift,
    )


def yaw_play_deg(
    plug: Mesh,
    socket_hulls: list[Hull],
    symmetry: int,
    *,
    samples: int = 4000,
    seed: int = 0,
    lift: float = LIFT,
    tolerance: float = TOLERANCE,
    step_deg: float = 1.0,
) -> float | None:
    """How far [deg] the mated plug, lifted by ``lift``, turns about the z axis, either
    way, before its surface sinks deeper than ``tolerance`` into a socket piece (the
    smaller of the two ways).

    Scans in ``step_deg`` steps up to half the key's period (180°/symmetry), then bisects
    to 0.001°. None when nothing stops it within that range: the interface is not keyed.
    """
    points = sample_surface(_lifted(plug, lift), samples, seed).points

    def blocked(angle_deg: float) -> bool:
        a = math.radians(angle_deg)
        c, s = math.cos(a), math.sin(a)
        turned = points @ np.array([[c, s, 0.0], [-s, c, 0.0], [0.0, 0.0, 1.0]])
        return bool(union_depth(socket_hulls, turned).max() > tolerance)

    limit = 180.0 / max(symmetry, 1)
    plays = []
    for sign in (1.0, -1.0):
        clear, angle = 0.0, step_deg
        while angle <= limit and not blocked(sign * angle):
            clear, angle = angle, angle + step_deg
        if angle > limit:
            return None
        stop = angle
        while stop - clear > 1e-3:
            mid = 0.5 * (clear + stop)
            clear, stop = (clear, mid) if blocked(sign * mid) else (mid, stop)
        plays.append(clear)
    return min(plays)
