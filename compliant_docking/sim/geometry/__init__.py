"""The docking interfaces as MuJoCo fragments: the round pair, plug (:mod:`.plug`) and
socket (:mod:`.socket`); the keyed pair (:mod:`.keyed`); the collision bits they share
(:mod:`.collision`) and what a fragment declares about its key (:mod:`.fragment`). A
user's interface from CAD (:mod:`.cad`, ``python -m compliant_docking.interface``): mesh
files (:mod:`.mesh`) → convex pieces (:mod:`.convex`, CoACD) → a clearance check
(:mod:`.clearance`) → fragments.

Their parameters (:class:`~compliant_docking.config.geometry.PlugGeometry`,
``SocketGeometry``, ``ContactParams``, :mod:`compliant_docking.config.keyed`) live in the
config layer, since they are the typed schemas of ``tool.geometry``, ``target.geometry``
and ``target.contact``. docs/interfaces.md describes fragments and their frames.
"""

from compliant_docking.sim.geometry.plug import (
    build_plug,
    plug_hull_vertices,
    plug_inertia,
)
from compliant_docking.sim.geometry.socket import Piece, build_socket, socket_pieces

__all__ = ["Piece", "build_plug", "build_socket", "plug_hull_vertices", "plug_inertia", "socket_pieces"]
