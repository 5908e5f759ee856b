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


@pytest.fixture
def audit_passed(monkeypatch):
    """The converter's contact audit replaced by a passing verdict, for tests whose property
    is not the audit (the threshold chosen, the cache): the audit is half of a conversion's
    time. The audit itself is tested with the session's conversion (``converted``, whose
    manifest it passed) and through the command line's refusal in tests/sim/test_cad.py."""
    from compliant_docking.sim.geometry import cad
    from compliant_docking.sim.geometry.conversion_audit import ContactAudit

    def passed(*args, **kwargs):
        return ContactAudit(contacts=1, poses=1, worst_deg=0.0, worst_excess_up=0.0, tolerance_deg=1.0, unsound=())

    monkeypatch.setattr(cad, "audit_fragments", passed)
