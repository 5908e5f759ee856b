"""The CAD route: the keyed pair exported as STL, the clearance check of convex pieces,
the converter (CoACD, the pieces rebuilt, cache, refinement, refusal), its fragments in a
scene, docking runs. The session's conversion (``converted``) is tests/sim/conftest.py's."""

from __future__ import annotations

import json
import math
import re
import shutil

import mujoco
import numpy as np
import pytest

from compliant_docking.config.store import default_keyed
from compliant_docking.interface import export_keyed, main
from compliant_docking.run.runner import execute
from compliant_docking.sim.geometry import cad
from compliant_docking.sim.geometry.clearance import check_clearance, yaw_play_deg
from compliant_docking.sim.geometry.conform import inside
from compliant_docking.sim.geometry.convex import Hull, is_convex, mesh_volume
from compliant_docking.sim.geometry.fragment import Key, read_key
from compliant_docking.sim.geometry.keyed import keyed_plug_inertia, keyed_socket_pieces
from compliant_docking.sim.geometry.mesh import keyed_cad_pair
from compliant_docking.sim.geometry.solid import Solid
from compliant_docking.sim.scene import build_scene
from compliant_docking.sim.settings import sim_settings
from tests.helpers import REPO_ROOT, make_cfg
from tests.sim.conftest import QUICK

pytest.importorskip("coacd", reason="the CAD converter needs the 'cad' extra (pip install -e '.[cad]')")
pytest.importorskip("trimesh", reason="the CAD converter needs the 'cad' extra (pip install -e '.[cad]')")

EXAMPLE = REPO_ROOT / "assets" / "interfaces" / "keyed_cad"
PLUG, SOCKET, _ = default_keyed()


@pytest.fixture(scope="module")
def pair():
    """The keyed pair as the CAD meshes (metres, mated, seat at z = floor thickness) and
    exact convex pieces: the plug's hull, the generator's socket pieces moved to the seat."""
    plug, socket = keyed_cad_pair(PLUG, SOCKET)
    seat = np.array([0.0, 0.0, SOCKET.floor_thickness])
    pieces = [Hull.of(np.array(p.vertices) + seat) for p in keyed_socket_pieces(SOCKET)]
    return plug, socket, [Hull.of(plug[0])], pieces


# ---------------------------------------------------------------------- the CAD pair
def test_exported_pair_is_the_generator_shape(pair):
    plug, socket, *_ = pair
    assert is_convex(*plug) and not is_convex(*socket)
    # the square prism and the frustum of the chamfer
    assert mesh_volume(*plug) == pytest.approx(
        4.0 * PLUG.inradius**2 * PLUG.chamfer_start + _frustum(), rel=1e-12
    )
    assert plug[0][:, 2].min() == pytest.approx(SOCKET.floor_thickness)  # tip on the seat


def _frustum() -> float:
    a, b, h = 2 * PLUG.inradius, 2 * PLUG.tip_inradius, PLUG.chamfer_length
    return h * (a * a + a * b + b * b) / 3.0


# ------------------------------------------------------------------- clearance check
def test_exact_pieces_keep_the_clearance_and_the_yaw_play(pair):
    """The generator's pieces are exact: the nominal 0.4 mm is measured (rays along the
    plug's face normals), every gap is kept, and the yaw play is the formula's."""
    plug, socket, plug_hulls, pieces = pair
    report = check_clearance(plug, plug_hulls, socket, pieces, samples=5000)
    assert report.passed, report.summary()
    assert report.nominal_m == pytest.approx(SOCKET.clearance, abs=1e-7)
    assert report.pieces_m == pytest.approx(SOCKET.clearance, abs=1e-7)
    assert report.plug.inside_fraction == 0.0
    # sampled points (4000) find the first contact within a few thousandths of a degree
    assert yaw_play_deg(plug, pieces, 4) == pytest.approx(SOCKET.yaw_play_deg, abs=0.02)


def test_one_hull_socket_fills_the_bore_and_fails(pair):
    """The coarsest decomposition (the socket's hull) fills the cavity: every plug point
    inside it, the check fails and names the socket as the part to refine."""
    plug, socket, plug_hulls, _ = pair
    report = check_clearance(plug, plug_hulls, socket, [Hull.of(socket[0])], samples=5000)
    assert not report.passed and report.refine() == ["socket"]
    assert report.plug.inside_fraction > 0.9
    assert report.pieces_m < -0.005  # the bore is filled: points sit millimetres deep


def test_a_piece_narrowing_one_face_by_a_third_fails_at_keep_075(pair):
    """Only the gap counts, not intrusion: bore box 0 moved 0.14 mm towards the plug
    leaves 0.26 mm (65 %) there: fails at keep 0.75, passes at 0.5."""
    plug, socket, plug_hulls, pieces = pair
    moved = list(pieces)
    moved[0] = Hull.of(pieces[0].vertices - [0.00014, 0.0, 0.0])
    strict = check_clearance(plug, plug_hulls, socket, moved, keep=0.75, samples=5000)
    assert not strict.passed and strict.pieces_m == pytest.approx(0.00026, abs=1e-7)
    assert check_clearance(plug, plug_hulls, socket, moved, keep=0.5, samples=5000).passed


# ------------------------------------------------------------------------ converter
def test_converter_writes_fragments_the_scene_loads(converted):
    *_, result = converted
    m = result.manifest
    assert not result.cached and m["clearance"]["passed"]
    assert m["pieces"]["plug"] == 1  # the plug is convex: its hull, no CoACD
    assert m["pieces"]["socket"] > 4
    assert m["clearance"]["nominal_clearance_m"] == pytest.approx(SOCKET.clearance, abs=1e-6)
    assert m["clearance"]["pieces_clearance_m"] >= 0.5 * SOCKET.clearance
    out = result.out_dir
    scene = build_scene(
        sim_settings(make_cfg(f"tool.mjcf={out / 'tool.xml'}", f"target.mjcf={out / 'target.xml'}"))
    )
    assert scene.key.symmetry == 4
    assert 0.0 < scene.key.yaw_play_deg <= SOCKET.yaw_play_deg + 0.01  # pieces can only take play away
    # the mating frame: tcp 60 mm from the mounting face, the seat at the tip
    tool = mujoco.MjSpec.from_file(str(out / "tool.xml")).compile()
    np.testing.assert_allclose(tool.site("tcp").pos, [0, 0, PLUG.length], atol=1e-9)
    np.testing.assert_allclose(tool.site("sensor_site").pos, 0.0, atol=1e-12)


def test_converted_mass_properties_are_the_generators(converted):
    """The mesh's mass properties (trimesh) equal the generator's exact integrals, to the
    6 significant digits MuJoCo's XML writer keeps."""
    *_, result = converted
    tool = mujoco.MjSpec.from_file(str(result.out_dir / "tool.xml")).compile()
    mass, com, inertia = keyed_plug_inertia(PLUG)
    assert tool.body("dock").mass[0] == pytest.approx(mass)
    np.testing.assert_allclose(tool.body("dock").ipos, com, rtol=5e-6, atol=1e-12)
    np.testing.assert_allclose(np.sort(tool.body("dock").inertia), np.sort(inertia), rtol=5e-6)
    np.testing.assert_allclose(result.manifest["com_in_tool_dock_m"], com, rtol=1e-9)


def test_second_call_uses_the_cache(converted, monkeypatch, tmp_path, audit_passed):
    plug_stl, socket_stl, options, result = converted

    def no_coacd(*args, **kwargs):
        raise AssertionError("CoACD ran although the result was cached")

    monkeypatch.setattr(cad, "decompose", no_coacd)
    again = cad.convert(plug_stl, socket_stl, result.out_dir, options, log=lambda _: None)
    assert again.cached and again.manifest == result.manifest
    # another option (the check's keep) is another result, but the pieces come from the cache
    shutil.copytree(result.out_dir, tmp_path / "copy")
    other = cad.convert(
        plug_stl,
        socket_stl,
        tmp_path / "copy",
        cad.ConvertOptions(**{**options.__dict__, "keep": 0.4}),
        log=lambda _: None,
    )
    assert not other.cached and other.manifest["pieces"] == result.manifest["pieces"]
    assert other.manifest["input_hash"] != result.manifest["input_hash"]


def test_pieces_are_inside_the_parts_and_keep_every_gap(converted):
    """The margin never costs clearance: every rebuilt piece, as written (6 significant
    digits), lies inside its part to 0.2 µm, so every gap keeps 100 % of its nominal
    width and no point of either surface is inside a piece of the other part."""
    plug_stl, socket_stl, options, result = converted
    clearance = result.manifest["clearance"]
    assert clearance["pieces_clearance_m"] == pytest.approx(clearance["nominal_clearance_m"], abs=2e-7)
    assert clearance["worst_kept"] > 0.999
    assert clearance["plug_inside_socket_pieces_fraction"] == 0.0
    socket = Solid(cad.load_mesh(socket_stl, socket_stl.read_bytes(), 1e-3, "socket"))
    model = mujoco.MjSpec.from_file(str(result.out_dir / "target.xml")).compile()
    seat = np.array(result.manifest["seat_in_cad_m"])
    pieces = [
        _piece(model, g) + seat for g in range(model.ngeom) if model.geom(g).name.startswith("socket_piece")
    ]
    assert len(pieces) == result.manifest["pieces"]["socket"]
    assert all(inside(Hull.of(p), socket, tolerance=2e-7) for p in pieces)
    # every cut grew into its neighbours (by at least half the margin), seams are bevelled
    report = result.manifest["conform"]["socket"]
    assert report["cut_faces"] > 0 and report["least_margin_m"] >= 0.5 * options.conform.margin
    assert report["bevels"] > 0 and report["uncovered"] == 0.0


def _piece(model: mujoco.MjModel, geom: int) -> np.ndarray:
    """A mesh geom's vertices in its body frame (MuJoCo moves a mesh to its centroid)."""
    mesh = model.geom_dataid[geom]
    start, count = model.mesh_vertadr[mesh], model.mesh_vertnum[mesh]
    rotation = np.zeros(9)
    mujoco.mju_quat2Mat(rotation, model.geom_quat[geom])
    vertices = model.mesh_vert[start : start + count].astype(float)
    return vertices @ rotation.reshape(3, 3).T + model.geom_pos[geom]


@pytest.mark.slow
def test_a_coarse_decomposition_is_made_exact(converted, tmp_path):
    """CoACD capped at 2 pieces per part fills the bore (the converter used to refuse
    it): split by the socket's own faces and merged, its pieces keep every gap and pass
    the contact audit. The rule in the fast suite, on an L block whose hull fills its notch:
    tests/sim/test_conform.py (split exactly, pressed like the solid at the cuts)."""
    plug_stl, socket_stl, *_ = converted
    options = cad.ConvertOptions(symmetry=4, coacd=QUICK, max_pieces=2, min_threshold=QUICK.threshold)
    m = cad.convert(plug_stl, socket_stl, tmp_path, options, log=lambda _: None).manifest
    assert m["conform"]["socket"]["coacd"] == 2 and m["thresholds"]["socket"] == QUICK.threshold
    assert m["clearance"]["worst_kept"] > 0.999 and m["contact_audit"]["passed"]


def _as_coacd_made_them(hulls, mesh, settings):
    """conform() that keeps CoACD's pieces as they are."""
    return hulls, cad.ConformReport(len(hulls), len(hulls), len(hulls), 0, 0, 0.0, 0, 0, 0.0, 0.0)


@pytest.mark.slow
def test_raw_coacd_pieces_are_refused_by_the_contact_audit(converted, tmp_path, monkeypatch):
    """Without the rebuilding, CoACD's own pieces (which keep half of every gap, so the
    clearance check passes) fail the contact audit: refused, naming where, and nothing
    written. In the fast suite the same refusal comes through the command line from the
    cached pieces (test_command_line_exports_converts_from_the_cache_and_exits_by_outcome)."""
    plug_stl, socket_stl, *_ = converted

    monkeypatch.setattr(cad, "conform", _as_coacd_made_them)
    options = cad.ConvertOptions(symmetry=4, coacd=QUICK, keep=0.5)
    with pytest.raises(cad.ContactsUnsound, match=r"deg off on socket_piece_\d+ at \(") as caught:
        cad.convert(plug_stl, socket_stl, tmp_path, options, log=lambda _: None)
    assert caught.value.audit.worst_deg > 20.0 and caught.value.audit.unsound
    assert not (tmp_path / "tool.xml").exists() and not (tmp_path / "interface.json").exists()


def test_refinement_halves_the_threshold_of_the_part_with_holes(
    pair, converted, tmp_path, monkeypatch, audit_passed
):
    """A socket decomposition that leaves a wall out at 0.05 (a hole the growth cannot
    close) and is exact below: the converter refines the socket only (0.05 → 0.025);
    with nothing finer allowed it refuses, naming the hole."""
    _, _, _, pieces = pair
    plug_stl, socket_stl, *_ = converted
    calls = []

    def fake(vertices, faces, settings, max_pieces=-1):
        calls.append(settings.threshold)
        if is_convex(vertices, faces):
            return [Hull.of(vertices)]
        return pieces[1:] if settings.threshold >= 0.05 else pieces

    monkeypatch.setattr(cad, "decompose", fake)
    result = cad.convert(plug_stl, socket_stl, tmp_path, cad.ConvertOptions(symmetry=4), log=lambda _: None)
    assert result.manifest["thresholds"] == {"plug": 0.05, "socket": 0.025}
    assert calls == [0.05, 0.05, 0.025]  # plug once (then cached), socket twice
    with pytest.raises(cad.ClearanceLost, match=r"pieces leave holes \(\d+\.\d+ % of the socket's surface"):
        options = cad.ConvertOptions(symmetry=4, min_threshold=0.05)
        cad.convert(plug_stl, socket_stl, tmp_path / "refused", options, log=lambda _: None)


def test_sdf_route_writes_sdf_geoms(converted, tmp_path):
    plug_stl, socket_stl, *_ = converted
    result = cad.convert(
        plug_stl, socket_stl, tmp_path, cad.ConvertOptions(symmetry=4, collision="sdf"), log=lambda _: None
    )
    assert result.manifest["clearance"] is None and result.manifest["key_yaw_play_deg"] is None
    target = mujoco.MjSpec.from_file(str(tmp_path / "target.xml")).compile()
    assert [target.geom(i).type[0] for i in range(target.ngeom)] == [mujoco.mjtGeom.mjGEOM_SDF]
    assert read_key(mujoco.MjSpec.from_file(str(tmp_path / "tool.xml")), "tool") == Key(4, None)


@pytest.mark.parametrize(
    "problem, message",
    [("open", "watertight"), ("apart", "not within the socket's height"), ("missing", "no such file")],
)
def test_unusable_inputs_are_refused_naming_why(tmp_path, problem, message):
    from compliant_docking.sim.geometry.mesh import write_stl

    plug, socket = keyed_cad_pair(PLUG, SOCKET)
    if problem == "open":
        plug = (plug[0], plug[1][:-2])  # two triangles of the top face missing
    if problem == "apart":
        plug = (plug[0] + [0.0, 0.0, 0.2], plug[1])  # exported unmated
    write_stl(tmp_path / "plug.stl", plug, scale=1000.0)
    write_stl(tmp_path / "socket.stl", socket, scale=1000.0)
    plug_path = tmp_path / ("nothing.stl" if problem == "missing" else "plug.stl")
    with pytest.raises(ValueError, match=message):
        cad.convert(plug_path, tmp_path / "socket.stl", tmp_path / "out", cad.ConvertOptions(coacd=QUICK))


def test_command_line_exports_converts_from_the_cache_and_exits_by_outcome(
    pair, converted, tmp_path, capsys, monkeypatch
):
    assert main(["--export-keyed", str(tmp_path / "cad"), "--sides", "6"]) == 0
    # binary STL: 84 bytes + 50 per triangle; two fans and four strips of 6 sides: 60 triangles
    assert (tmp_path / "cad" / "socket.stl").stat().st_size == 84 + 50 * 60
    plug_stl, socket_stl, options, result = converted
    copy = tmp_path / "copy"
    shutil.copytree(result.out_dir, copy)
    argv = [str(plug_stl), str(socket_stl), "--out", str(copy), "--symmetry", "4", "--plug-mass", "0.3"]
    assert main([*argv, "--quick", "--keep", "0.5"]) == 0  # the fixture's options: a cache hit
    out = capsys.readouterr().out
    assert "(from the cache)" in out and f"tool.mjcf={copy / 'tool.xml'}" in out
    assert main([str(tmp_path / "none.stl"), str(socket_stl), "--out", str(copy)]) == 2
    assert "no such file" in capsys.readouterr().err
    # CoACD's own pieces (cached), not rebuilt: the contact audit refuses them, saying where
    monkeypatch.setattr(cad, "conform", _as_coacd_made_them)
    assert main([*argv, "--quick", "--keep", "0.5", "--margin-mm", "2.5"]) == 2
    err = capsys.readouterr().err
    assert err.startswith("refused: the convex pieces' contacts are not those of the solid parts")
    assert re.search(r"\d+\.\d deg off on socket_piece_\d+ at \(-?\d+\.\d\d, ", err)
    assert json.loads((copy / "interface.json").read_text()) == result.manifest  # nothing written
    plug, socket, plug_hulls, _ = pair
    lost = check_clearance(plug, plug_hulls, socket, [Hull.of(socket[0])], samples=500)

    def refuse(*args, **kwargs):
        raise cad.ClearanceLost(lost, {"socket": 0.01})

    monkeypatch.setattr("compliant_docking.interface.convert", refuse)
    assert main(argv) == 2
    assert "refused" in capsys.readouterr().err


# ------------------------------------------------------------------------- docking
def test_committed_example_is_what_the_converter_wrote():
    """assets/interfaces/keyed_cad/: the README's example, converted with the defaults."""
    manifest = json.loads((EXAMPLE / "interface.json").read_text())
    assert manifest["clearance"]["passed"] and manifest["clearance"]["keep"] == 0.75
    assert manifest["key_symmetry"] == 4 and manifest["mass_kg"] == 0.3
    digest = cad.input_hash(
        (EXAMPLE / "cad" / "plug.stl").read_bytes(),
        (EXAMPLE / "cad" / "socket.stl").read_bytes(),
        cad.ConvertOptions(symmetry=4, plug_mass=0.3).resolved(),
    )
    if manifest["coacd_version"] == cad.coacd_version():
        assert digest == manifest["input_hash"]  # `make`ing it again is a cache hit


def test_converted_example_docks(tmp_path):
    record = execute(
        make_cfg(
            f"tool.mjcf={EXAMPLE / 'tool.xml'}",
            f"target.mjcf={EXAMPLE / 'target.xml'}",
            "task.progress=false",
        ),
        tmp_path,
        figures=False,
        echo=False,
    )
    assert record["success"] is True, record["gate_failures"]
    assert record["key_symmetry"] == 4 and record["seat_key_yaw_deg"] < 0.1


@pytest.mark.slow
@pytest.mark.parametrize("robot", ["iiwa14", "fr3"])
@pytest.mark.parametrize("controller", ["impedance", "hqp", "se3_lie"])
def test_converted_example_docks_with_every_controller(tmp_path, robot, controller):
    record = execute(
        make_cfg(
            f"tool.mjcf={EXAMPLE / 'tool.xml'}",
            f"target.mjcf={EXAMPLE / 'target.xml'}",
            f"robot={robot}",
            f"controller={controller}",
            "task.progress=false",
        ),
        tmp_path,
        figures=False,
        echo=False,
    )
    assert record["success"] is True, record["gate_failures"]


@pytest.mark.slow
def test_example_converts_from_scratch_with_the_defaults(tmp_path):
    """The README's `make` step without its cache: CoACD once at 0.05, the pieces rebuilt
    (they keep every gap), the contact audit passed (about 40 s), and the result docks."""
    plug_stl, socket_stl = export_keyed(tmp_path / "cad")
    result = cad.convert(
        plug_stl, socket_stl, tmp_path / "out", cad.ConvertOptions(symmetry=4, plug_mass=0.3)
    )
    assert result.manifest["clearance"]["worst_kept"] > 0.999 and result.manifest["contact_audit"]["passed"]
    record = execute(
        make_cfg(
            f"tool.mjcf={tmp_path / 'out' / 'tool.xml'}",
            f"target.mjcf={tmp_path / 'out' / 'target.xml'}",
            "task.progress=false",
        ),
        tmp_path / "run",
        figures=False,
        echo=False,
    )
    assert record["success"] is True, record["gate_failures"]
    assert math.isfinite(record["seat_key_yaw_deg"])


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (("--plug-mass", "nan"), "error: --plug-mass: plug_mass must be a finite number > 0 kg; got nan."),
        (("--plug-mass", "-0.3"), "error: --plug-mass: plug_mass must be a finite number > 0 kg; got -0.3."),
        (("--density", "inf"), "error: --density: density must be a finite number > 0 kg/m³; got inf."),
        (("--threshold", "nan"), "error: --threshold: threshold must be a finite number in (0, 1]; got nan."),
        (("--lift-mm", "inf"), "error: --lift-mm: lift must be a finite number >= 0 m; got inf."),
        (("--keep", "0"), "error: --keep: keep must be a finite number in (0, 1]; got 0.0."),
        (("--max-pieces", "0"), "error: --max-pieces: max_pieces must be -1 (no cap) or at least 1; got 0."),
        (("--symmetry", "-1"), "error: --symmetry: symmetry must be an integer >= 0; got -1."),
        (("--margin-mm", "nan"), "error: --margin-mm: margin must be a length > 0 [m]; got nan."),
        (("--bevel-deg", "45"), "error: --bevel-deg: bevel_deg must be in (0, 45) [deg]; got 45.0."),
        (
            ("--audit-tolerance-deg", "inf"),
            "error: --audit-tolerance-deg: audit_tolerance_deg must be a finite number in (0, 90) deg; got inf.",
        ),
    ],
)
def test_command_line_refuses_an_unusable_option_before_writing(tmp_path, capsys, args, message):
    """Every numeric option is checked (finite, in its range) before any file is read or
    written: the fragments of a NaN plug mass would not load in MuJoCo."""
    argv = [
        str(EXAMPLE / "cad" / "plug.stl"),
        str(EXAMPLE / "cad" / "socket.stl"),
        "--out",
        str(tmp_path / "out"),
    ]
    assert main([*argv, "--symmetry", "4", *args]) == 2
    err = capsys.readouterr().err
    assert message in err and "Traceback" not in err
    assert not (tmp_path / "out").exists()


def test_export_refuses_a_keyed_plug_outside_its_range(tmp_path, capsys):
    assert main(["--export-keyed", str(tmp_path / "cad"), "--sides", "2"]) == 2
    err = capsys.readouterr().err
    assert err.startswith("error: --sides: ") and "sides must be an integer in [3, 12]; got 2" in err
    assert not (tmp_path / "cad").exists()
