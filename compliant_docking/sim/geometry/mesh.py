"""Triangle meshes of the keyed interface as a CAD pair, and binary STL files, in numpy.

The CAD example (docs/interfaces.md) is the keyed plug and socket exported as STL files
in a common CAD frame, mated: what a user's CAD tool would export from an assembly. The
meshes are lofts of regular polygons (:func:`polygon_loft`): every quad between two
rings is planar, so the triangles describe the generator's flat faces exactly.
"""

from __future__ import annotations

import math
import struct
from pathlib import Path

import numpy as np

from compliant_docking.config.keyed import KeyedPlugGeometry, KeyedSocketGeometry

Mesh = tuple[np.ndarray, np.ndarray]  # (vertices (n, 3) float, faces (m, 3) int)


def polygon_loft(profile: list[tuple[float, float]], sides: int) -> Mesh:
    """Closed triangle mesh of a "lathe" with regular ``sides``-gon sections.

    ``profile``: (inradius, z) points of the section's half-outline, from the axis back to
    the axis (the first and last inradius 0), going counter-clockwise in the (r, z) plane
    (up the outside first for a solid): each point becomes a ring of corners at azimuths
    (2k + 1)π/sides, so face k of every ring faces azimuth 2πk/sides (as the keyed parts).
    Faces are wound counter-clockwise seen from outside (outward normals).
    """
    if profile[0][0] != 0.0 or profile[-1][0] != 0.0:
        raise ValueError("polygon_loft: the profile must start and end on the axis (inradius 0)")
    angle = (2.0 * np.arange(sides) + 1.0) * np.pi / sides
    scale = 1.0 / math.cos(math.pi / sides)
    vertices: list[np.ndarray] = []
    index: list[list[int] | int] = []
    for r, z in profile:
        if r == 0.0:
            index.append(len(vertices))
            vertices.append(np.array([0.0, 0.0, z]))
        else:
            start = len(vertices)
            ring = np.column_stack([r * scale * np.cos(angle), r * scale * np.sin(angle), np.full(sides, z)])
            vertices.extend(ring)
            index.append(list(range(start, start + sides)))
    faces: list[tuple[int, int, int]] = []
    for a, b in zip(index[:-1], index[1:]):
        for k in range(sides):
            k1 = (k + 1) % sides
            if isinstance(a, int) and isinstance(b, list):
                faces.append((a, b[k1], b[k]))
            elif isinstance(a, list) and isinstance(b, int):
                faces.append((a[k], a[k1], b))
            elif isinstance(a, list) and isinstance(b, list):
                faces.append((a[k], b[k1], b[k]))
                faces.append((a[k], a[k1], b[k1]))
    return np.array(vertices), np.array(faces, dtype=np.int64)


def keyed_cad_pair(
    plug: KeyedPlugGeometry, socket: KeyedSocketGeometry, *, outer_inradius: float | None = None
) -> tuple[Mesh, Mesh]:
    """The keyed plug and socket as solids in one CAD frame, mated (plug tip on the seat).

    CAD frame: z is the socket axis, out of the opening; the socket block's bottom face
    is z = 0, so the seat is at z = floor_thickness (the converter must find it). The
    socket's outside is a ``sides``-gon prism of ``outer_inradius`` (default: the mouth
    plus the wall thickness). Lengths in metres.
    """
    seat = socket.floor_thickness
    outer = socket.mouth_inradius + socket.wall_thickness if outer_inradius is None else outer_inradius
    top = seat + socket.mouth_height
    socket_profile = [
        (0.0, 0.0),
        (outer, 0.0),
        (outer, top),
        (socket.mouth_inradius, top),
        (socket.bore_inradius, seat + socket.insertion_depth),
        (socket.bore_inradius, seat),
        (0.0, seat),
    ]
    plug_profile = [
        (0.0, seat),
        (plug.tip_inradius, seat),
        (plug.inradius, seat + plug.chamfer_length),
        (plug.inradius, seat + plug.length),
        (0.0, seat + plug.length),
    ]
    return polygon_loft(plug_profile, plug.sides), polygon_loft(socket_profile, socket.sides)


def write_stl(path: str | Path, mesh: Mesh, *, scale: float = 1.0, name: str = "part") -> None:
    """Write ``mesh`` (vertices × ``scale``) as a binary STL file with facet normals."""
    vertices, faces = mesh
    tri = np.asarray(vertices, dtype=float)[np.asarray(faces)] * scale
    normals = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    normals /= np.maximum(np.linalg.norm(normals, axis=1, keepdims=True), 1e-300)
    record = np.zeros(len(tri), dtype=[("n", "<f4", 3), ("v", "<f4", (3, 3)), ("attr", "<u2")])
    record["n"], record["v"] = normals, tri
    header = f"compliant-docking {name}".encode()[:80].ljust(80, b" ")
    with open(path, "wb") as f:
        f.write(header + struct.pack("<I", len(tri)) + record.tobytes())
