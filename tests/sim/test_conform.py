"""Convex pieces rebuilt to collide like the solid (compliant_docking.sim.geometry.conform),
on an L-shaped block: its inside test, its exact split, and the contact normals MuJoCo
finds when a pyramid tip is pressed a few micrometres into the pieces near their cuts."""

from __future__ import annotations

import math

import mujoco
import numpy as np
import pytest

from compliant_docking.sim.geometry.audit import angle_to_cone_deg
from compliant_docking.sim.geometry.conform import ConformSettings, clip_to_solid, conform, inside
from compliant_docking.sim.geometry.convex import Hull, mesh_volume
from compliant_docking.sim.geometry.solid import Solid

MM = 1e-3
#: the L in the x-z plane [mm]: a bar 40 × 10 on the floor and a bar 10 × 30 on its left end
OUTLINE = [(0.0, 0.0), (40.0, 0.0), (40.0, 10.0), (10.0, 10.0), (10.0, 40.0), (0.0, 40.0)]
HALF_WIDTH = 20.0  # the block runs from y = -20 to 20 mm
#: the decomposition a decomposer would give: the two bars, cut along z = 10 mm. The cut
#: meets the reflex edge (x = 10, z = 10) and crosses the left face x = 0 (a seam in a face)
BARS = ([(0, 0), (40, 0), (40, 10), (0, 10)], [(0, 10), (10, 10), (10, 40), (0, 40)])


def _prism(outline: list[tuple[float, float]]) -> np.ndarray:
    """The corners [m] of the outline (x, z) extruded over y in ±HALF_WIDTH."""
    return np.array([(x, y, z) for x, z in outline for y in (-HALF_WIDTH, HALF_WIDTH)]) * MM


def _l_block():
    """The L block as a closed, outward-wound mesh [m] (the outline fanned from its reflex
    corner, which sees every other corner)."""
    n = len(OUTLINE)
    vertices = _prism(OUTLINE)  # corner k at y = -w is 2k, at y = +w is 2k + 1
    faces = []
    for k in range(n):  # the sides, outward
        a, b = k, (k + 1) % n
        faces += [(2 * a, 2 * b + 1, 2 * b), (2 * a, 2 * a + 1, 2 * b + 1)]
    fan = [(3, k, (k + 1) % n) for k in (4, 5, 0, 1)]  # from the reflex corner (10, 10)
    faces += [(2 * a, 2 * b, 2 * c) for a, b, c in fan]  # y = -w, outward -y
    faces += [(2 * a + 1, 2 * c + 1, 2 * b + 1) for a, b, c in fan]  # y = +w
    return vertices, np.array(faces)


@pytest.fixture(scope="module")
def block():
    vertices, faces = _l_block()
    assert mesh_volume(vertices, faces) == pytest.approx((40 * 10 + 10 * 30) * 2 * HALF_WIDTH * MM**3)
    return vertices, faces


def test_the_solid_knows_its_inside_exactly(block):
    solid = Solid(block)
    assert np.isclose(solid.winding(np.array([[5.0, 0.0, 5.0], [30.0, 0.0, 30.0]]) * MM), [1.0, 0.0]).all()
    bar = _prism(BARS[0][:4])
    assert inside(Hull.of(bar), solid)
    # 0.5 µm past the top face of the long bar: found, and it is that face's plane
    poking = bar + np.where(bar[:, [2]] > 0.0099, [0.0, 0.0, 0.5e-6], 0.0)
    crossed = solid.crossing(Hull.of(poking), 1e-7)
    assert not inside(Hull.of(poking), solid)
    np.testing.assert_allclose(solid.planes[crossed[0]], [0.0, 0.0, 1.0, -0.010], atol=1e-12)
    # 0.05 µm past it is within the tolerance (0.1 µm)
    assert inside(Hull.of(bar + np.where(bar[:, [2]] > 0.0099, [0.0, 0.0, 0.05e-6], 0.0)), solid)


def test_a_piece_bridging_the_reflex_edge_is_split_exactly(block):
    """The L's hull (one piece filling the notch) split by the L's own faces: the parts
    lie inside and fill exactly the L's volume."""
    solid = Solid(block)
    parts = clip_to_solid(Hull.of(block[0]), solid)
    assert len(parts) >= 2 and all(inside(p, solid) for p in parts)
    volume = (40 * 10 + 10 * 30) * 2 * HALF_WIDTH * MM**3
    assert sum(p.volume for p in parts) == pytest.approx(volume, rel=1e-9)


def _normals(pieces: list[Hull], tip: np.ndarray, axis: np.ndarray, depth: float) -> list[np.ndarray]:
    """Contact normals (from the block into the plug) when the tip of a square pyramid
    (90° apex) pointing along ``axis`` is at ``tip`` moved ``depth`` further along it."""
    spec = mujoco.MjSpec()
    for k, piece in enumerate(pieces):
        spec.add_mesh(name=f"piece_{k}", uservert=piece.vertices.ravel().tolist())
        geom = spec.worldbody.add_geom(
            name=f"piece_{k}", type=mujoco.mjtGeom.mjGEOM_MESH, meshname=f"piece_{k}"
        )
        geom.contype, geom.conaffinity = 1, 0
    body = spec.worldbody.add_body(name="plug")
    body.add_freejoint()
    base = [
        (3 * MM * math.cos(a), 3 * MM * math.sin(a), -3 * MM)
        for a in (0.3, 0.3 + math.pi / 2, 0.3 + math.pi, 1.5 * math.pi + 0.3)
    ]
    spec.add_mesh(name="pyramid", uservert=np.ravel([(0.0, 0.0, 0.0), *base]).tolist())
    plug = body.add_geom(type=mujoco.mjtGeom.mjGEOM_MESH, meshname="pyramid")
    plug.contype, plug.conaffinity = 0, 1
    model = spec.compile()
    data = mujoco.MjData(model)
    quat = np.zeros(4)  # the pyramid's +z (tip) along axis
    mujoco.mju_quatZ2Vec(quat, axis)
    data.qpos[:3] = tip + depth * axis
    data.qpos[3:7] = quat
    mujoco.mj_kinematics(model, data)
    mujoco.mj_collision(model, data)
    contacts = [data.contact[i] for i in range(data.ncon)]
    # MuJoCo's normal points from geom1 to geom2; the plug is the last geom
    return [np.array(c.frame[:3]) * (1.0 if c.geom2 == plug.id else -1.0) for c in contacts]


#: probes along the cut [mm]: tip, pressing direction, the block's normals there. At the
#: left face near the seam (one normal); onto the long bar's top and into the upright
#: bar's right face next to the reflex edge (the pyramid's flank touches the other face)
LEFT, UP = (-1.0, 0.0, 0.0), (0.0, 0.0, 1.0)
PROBES = [
    *[
        ((0.0, 3.0, 10.0 + s), (1.0, 0.0, 0.0), [LEFT])
        for s in (-0.06, -0.02, -0.005, 0.0, 0.005, 0.02, 0.06)
    ],
    *[((10.0 + s, 3.0, 10.0), (0.0, 0.0, -1.0), [UP, (1.0, 0.0, 0.0)]) for s in (0.005, 0.02, 0.06, 0.2)],
    *[((10.0, 3.0, 10.0 + s), (-1.0, 0.0, 0.0), [UP, (1.0, 0.0, 0.0)]) for s in (0.005, 0.02, 0.06, 0.2)],
]


def _worst_deg(pieces: list[Hull]) -> float:
    worst = 0.0
    for tip, axis, cone in PROBES:
        for depth in (20e-6, 60e-6):
            for normal in _normals(pieces, np.array(tip) * MM, np.array(axis), depth):
                worst = max(worst, angle_to_cone_deg(normal, np.array(cone)))
    return worst


def test_rebuilt_pieces_press_like_the_solid_at_their_cuts(block):
    """The two bars as a decomposer would cut them: a tip pressed 20-60 µm near the cut
    is pushed out through it, far from the block's normal (the bars' faces at the seam in
    the left face and at the reflex edge). Rebuilt (grown 2 mm into each other, bevelled
    3° at the seam), every normal is within the bevel of the block's, and the pieces
    still lie inside the block and cover its surface."""
    raw = [Hull.of(_prism(bar)) for bar in BARS]
    assert _worst_deg(raw) > 30.0
    settings = ConformSettings()
    pieces, report = conform(raw, _l_block(), settings)
    solid = Solid(block)
    assert report.covered and all(inside(p, solid) for p in pieces)
    assert report.pieces == 2 and report.bevels > 0
    assert _worst_deg(pieces) <= settings.bevel_deg + 0.01
