"""The tool and target fragments the CAD converter writes (:mod:`.cad`): the plug's and the
socket's convex pieces as mesh geoms, their own meshes drawn (or, for the SDF route,
colliding), the plug's mass properties and the sites of the scene's convention."""

from __future__ import annotations

from typing import Protocol

import mujoco
import numpy as np

from compliant_docking.config.geometry import ContactParams
from compliant_docking.sim.geometry.collision import (
    PLUG_COLLISION_GROUP,
    PLUG_RGBA,
    SOCKET_RGBA,
    VISUAL_GROUP,
    make_plug_collider,
    make_socket_collider,
)
from compliant_docking.sim.geometry.convex import Hull
from compliant_docking.sim.geometry.fragment import MATED, Key, declare_key
from compliant_docking.sim.geometry.mesh import Mesh


class FragmentOptions(Protocol):
    """What the fragments take from the converter's options (:class:`.cad.ConvertOptions`)."""

    @property
    def contact(self) -> ContactParams | None: ...

    @property
    def collision(self) -> str: ...

    @property
    def density(self) -> float: ...

    @property
    def plug_mass(self) -> float | None: ...


def _mass_properties(plug: Mesh, options: FragmentOptions) -> tuple[float, np.ndarray, np.ndarray]:
    """Mass [kg], centre of mass and inertia about it (CAD axes) of the uniform plug."""
    import trimesh

    mesh = trimesh.Trimesh(*plug, process=False)
    volume = float(mesh.volume)
    density = options.density if options.plug_mass is None else options.plug_mass / volume
    mesh.density = density
    return float(mesh.mass), np.asarray(mesh.center_mass), np.asarray(mesh.moment_inertia)


def tool_fragment(
    plug: Mesh, hulls: list[Hull], z_tip: float, z_top: float, options: FragmentOptions, key: Key
) -> tuple[mujoco.MjSpec, dict]:
    """The tool fragment of a plug (CAD frame, mated) and its pieces, and the mass record."""
    top = np.array([0.0, 0.0, z_top])

    def to_dock(points: np.ndarray) -> np.ndarray:  # CAD → dock frame: MATED · (p − top)
        return (np.asarray(points) - top) @ MATED.T

    mass, com, inertia = _mass_properties(plug, options)
    com_dock, inertia_dock = to_dock(com[None])[0], MATED @ inertia @ MATED.T
    spec = mujoco.MjSpec()
    spec.modelname = "cad_plug"
    body = spec.worldbody.add_body(name="dock")
    body.explicitinertial = True
    body.mass = mass
    body.ipos = com_dock.tolist()
    i = inertia_dock
    body.fullinertia = [i[0, 0], i[1, 1], i[2, 2], i[0, 1], i[0, 2], i[1, 2]]
    for g in _add_pieces(spec, body, "plug_piece", [to_dock(h.vertices) for h in hulls], PLUG_RGBA):
        make_plug_collider(g, options.contact)
    visual = _add_visual(spec, body, "plug_visual", to_dock(plug[0]), plug[1], VISUAL_GROUP, PLUG_RGBA)
    if options.collision == "sdf":
        visual.type = mujoco.mjtGeom.mjGEOM_SDF
        make_plug_collider(visual, options.contact)
    body.add_site(name="sensor_site", pos=[0.0, 0.0, 0.0], quat=[1.0, 0.0, 0.0, 0.0])
    body.add_site(name="tcp", pos=[0.0, 0.0, z_top - z_tip])
    declare_key(spec, key)
    record = {
        "mass_kg": mass,
        "com_in_tool_dock_m": com_dock.tolist(),
        "inertia_in_tool_dock_kg_m2": i.tolist(),
    }
    return spec, record


def target_fragment(
    socket: Mesh, hulls: list[Hull], z_tip: float, options: FragmentOptions, key: Key
) -> mujoco.MjSpec:
    """The target fragment of a socket (CAD frame, mated; the seat at z_tip) and its pieces."""
    seat = np.array([0.0, 0.0, z_tip])
    spec = mujoco.MjSpec()
    spec.modelname = "cad_socket"
    body = spec.worldbody.add_body(name="dock")
    for g in _add_pieces(spec, body, "socket_piece", [h.vertices - seat for h in hulls], SOCKET_RGBA):
        make_socket_collider(g, options.contact)
    visual = _add_visual(spec, body, "socket_visual", socket[0] - seat, socket[1], 0, SOCKET_RGBA)
    if options.collision == "sdf":
        visual.type = mujoco.mjtGeom.mjGEOM_SDF
        make_socket_collider(visual, options.contact)
    body.add_site(name="seat", pos=[0.0, 0.0, 0.0])
    body.add_site(name="mouth", pos=[0.0, 0.0, float(socket[0][:, 2].max()) - z_tip])
    declare_key(spec, key)
    return spec


def _add_pieces(
    spec: mujoco.MjSpec, body: mujoco.MjsBody, prefix: str, pieces: list[np.ndarray], rgba
) -> list[mujoco.MjsGeom]:
    """One convex mesh geom ``<prefix>_<k>`` per piece (its vertices in the body frame)."""
    geoms = []
    for k, vertices in enumerate(pieces):
        spec.add_mesh(name=f"{prefix}_{k}", uservert=np.ravel(vertices).tolist())
        geoms.append(
            body.add_geom(
                name=f"{prefix}_{k}",
                type=mujoco.mjtGeom.mjGEOM_MESH,
                meshname=f"{prefix}_{k}",
                group=PLUG_COLLISION_GROUP,
                rgba=list(rgba),
            )
        )
    return geoms


def _add_visual(
    spec, body, name: str, vertices: np.ndarray, faces: np.ndarray, group: int, rgba
) -> mujoco.MjsGeom:
    """The part's own mesh, drawn, colliding with nothing (the SDF route makes it collide)."""
    spec.add_mesh(name=name, uservert=np.ravel(vertices).tolist(), userface=np.ravel(faces).tolist())
    return body.add_geom(
        name=name,
        type=mujoco.mjtGeom.mjGEOM_MESH,
        meshname=name,
        contype=0,
        conaffinity=0,
        density=0.0,
        group=group,
        rgba=list(rgba),
    )
