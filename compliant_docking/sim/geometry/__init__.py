"""The parametric docking interface as MuJoCo fragments: the plug (:mod:`.plug`) and the
socket (:mod:`.socket`), with the collision filtering they share (:mod:`.collision`).

Their parameters (:class:`~compliant_docking.config.geometry.PlugGeometry`,
``SocketGeometry``, ``ContactParams``) live in the config layer, since they are the
typed schemas of ``tool.geometry``, ``target.geometry`` and ``target.contact``.
"""

from compliant_docking.sim.geometry.plug import (
    build_plug,
    plug_hull_vertices,
    plug_inertia,
)
from compliant_docking.sim.geometry.socket import Box, build_socket, socket_boxes

__all__ = ["Box", "build_plug", "build_socket", "plug_hull_vertices", "plug_inertia", "socket_boxes"]
