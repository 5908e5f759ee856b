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
    paths, the options and the conversion. The converter's contact audit is replaced by a
    passing verdict (:func:`passed_audit`: it is ~45 % of the conversion); the fragments
    written are judged by the audit all the same, by their socket's STL, in
    tests/sim/test_contact_normals.py::test_fresh_cad_conversion_contacts_follow_the_solid,
    and the converter's refusal on the audit's verdict is tested through the command line
    (tests/sim/test_cad.py::test_command_line_exports_converts_from_the_cache_and_exits_by_outcome)."""
    pytest.importorskip("coacd", reason="the CAD converter needs the 'cad' extra (pip install -e '.[cad]')")
    pytest.importorskip("trimesh", reason="the CAD converter needs the 'cad' extra (pip install -e '.[cad]')")
    from compliant_docking.interface import export_keyed
    from compliant_docking.sim.geometry import cad

    root = tmp_path_factory.mktemp("cad")
    plug_stl, socket_stl = export_keyed(root / "cad")
    options = cad.ConvertOptions(symmetry=4, plug_mass=0.3, coacd=QUICK, keep=0.5)
    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(cad, "audit_fragments", passed_audit)
        result = cad.convert(plug_stl, socket_stl, root / "out", options, log=lambda _: None)
    return plug_stl, socket_stl, options, result


def passed_audit(*args, **kwargs):
    """A passing contact audit, in place of the converter's (``cad.audit_fragments``)."""
    from compliant_docking.sim.geometry.conversion_audit import ContactAudit

    return ContactAudit(
        contacts=1, poses=1, worst_deg=0.0, worst_excess_up=0.0, tolerance_deg=1.0, unsound=()
    )


@pytest.fixture
def audit_passed(monkeypatch):
    """The converter's contact audit replaced by a passing verdict, for tests whose property
    is not the audit (the threshold chosen, the cache), as in ``converted``."""
    from compliant_docking.sim.geometry import cad

    monkeypatch.setattr(cad, "audit_fragments", passed_audit)
