"""The keyed pair converted from CAD once per session, CoACD's search cut down (shared by
tests/sim/test_cad.py and tests/sim/test_contact_normals.py)."""

from __future__ import annotations

import pytest

from compliant_docking.interface import QUICK as QUICK_SEARCH
from compliant_docking.sim.geometry.convex import CoacdSettings

#: CoACD's search cut down (about 5 s instead of 20 s on the example socket); same threshold
QUICK = CoacdSettings(threshold=0.05, **QUICK_SEARCH)


@pytest.fixture(scope="session")
def converted(tmp_path_factory):
    """The exported keyed pair through the converter (QUICK CoACD, keep 0.5): the STL
    paths, the options and the conversion."""
    pytest.importorskip("coacd", reason="the CAD converter needs the 'cad' extra (pip install -e '.[cad]')")
    pytest.importorskip("trimesh", reason="the CAD converter needs the 'cad' extra (pip install -e '.[cad]')")
    from compliant_docking.interface import export_keyed
    from compliant_docking.sim.geometry import cad

    root = tmp_path_factory.mktemp("cad")
    plug_stl, socket_stl = export_keyed(root / "cad")
    options = cad.ConvertOptions(symmetry=4, plug_mass=0.3, coacd=QUICK, keep=0.5)
    result = cad.convert(plug_stl, socket_stl, root / "out", options, log=lambda _: None)
    return plug_stl, socket_stl, options, result
