"""What each docking interface's collision geometry costs per step in contact, and whether
it seats: the round cone pair, the keyed pair (boxes), the keyed pair converted from CAD
(convex pieces: the committed example, and CoACD's own and rebuilt pieces at several
thresholds), and the same CAD pair through MuJoCo's mesh SDF collision.

Run from the repository root (needs the `cad` extra for the conversions)::

    python benchmarks/interface_geometry.py                       # about 2 minutes
    python benchmarks/interface_geometry.py --thresholds 0.05,0.025,0.0125   # + CoACD runs
    python benchmarks/interface_geometry.py --round --thresholds 0.05,0.02   # the round pair
    python benchmarks/interface_geometry.py --fragments OLD_DIR   # + another conversion

`--fragments DIR` (repeatable) adds a directory holding a conversion's tool.xml and
target.xml, e.g. an older copy of the example, so that old and new are timed in one
process.

The rig is benchmarks/contact_geometry.py's (the package's compliance rig: a compliant
carrier pushes the plug with 5 N; zero gravity, 1 ms, implicitfast, elliptic cones). The CAD pair is the keyed
interface exported as STL (compliant_docking/interface.py --export-keyed) and converted
with compliant_docking.sim.geometry.cad; `--thresholds` converts at each CoACD threshold
without refining (so the piece counts differ), each in two rows: CoACD's own pieces and the pieces rebuilt as the
converter does (compliant_docking.sim.geometry.conform). The committed example is
assets/interfaces/keyed_cad/. `--round` converts the round cone pair instead, exported
with 64-gon sections (the plug's inscribed in its circle, the bore's faces tangent to
its cylinder, so the nominal clearance is at least the cone socket's), which CoACD must
approximate with flat pieces: the case the SDF route is for.
"""

from __future__ import annotations

import argparse
import math
import sys
import tempfile
import time
from pathlib import Path

import mujoco

if __package__ in (None, ""):
    sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
    sys.path.insert(0, str(Path(__file__).resolve().parent))

from contact_geometry import CONTACT, PLUG, SOCKET, Case, rig_from_fragments  # noqa: E402

from compliant_docking.config.store import default_keyed  # noqa: E402
from compliant_docking.sim.compliance_rig import push_insertion  # noqa: E402
from compliant_docking.sim.geometry import build_plug, build_socket  # noqa: E402
from compliant_docking.sim.geometry.keyed import build_keyed_plug, build_keyed_socket  # noqa: E402

REPO_ROOT = Path(__file__).resolve().parents[1]  # the checkout
EXAMPLE = REPO_ROOT / "assets" / "interfaces" / "keyed_cad"
#: (case, yaw of the socket about its axis [deg]): 1.5° is inside the keyed pair's 2.34° play
CASES = (
    (Case("centred"), 0.0),
    (Case("offset 3 mm", offset=0.003), 0.0),
    (Case("offset 3 mm, socket yawed 1.5 deg", offset=0.003), 1.5),
)


def export_round(directory: Path, segments: int = 64) -> tuple[Path, Path]:
    """The default cone plug and socket as a mated CAD pair in mm (``segments``-gon
    sections), seat at z = floor thickness."""
    from compliant_docking.sim.geometry.mesh import polygon_loft, write_stl

    plug, socket = PLUG, SOCKET
    inscribed = math.cos(math.pi / segments)
    z0 = socket.floor_thickness
    outer = socket.mouth_radius + socket.wall_thickness
    top = z0 + socket.mouth_height
    plug_mesh = polygon_loft(
        [
            (0.0, z0),
            (plug.tip_radius * inscribed, z0),
            (plug.radius * inscribed, z0 + plug.chamfer_length),
            (plug.radius * inscribed, z0 + plug.length),
            (0.0, z0 + plug.length),
        ],
        segments,
    )
    socket_mesh = polygon_loft(
        [
            (0.0, 0.0),
            (outer, 0.0),
            (outer, top),
            (socket.mouth_radius, top),
            (socket.bore_radius, z0 + socket.insertion_depth),
            (socket.bore_radius, z0),
            (0.0, z0),
        ],
        segments,
    )
    directory.mkdir(parents=True, exist_ok=True)
    paths = directory / "plug.stl", directory / "socket.stl"
    write_stl(paths[0], plug_mesh, scale=1000.0)
    write_stl(paths[1], socket_mesh, scale=1000.0)
    return paths


def _fragments_from_dir(directory: Path):
    def make():
        return (
            mujoco.MjSpec.from_file(str(directory / "tool.xml")),
            mujoco.MjSpec.from_file(str(directory / "target.xml")),
        )

    return make


def _pieces(directory: Path) -> int:
    return sum(1 for g in mujoco.MjSpec.from_file(str(directory / "target.xml")).geoms if "piece" in g.name)


def _cone():
    return build_plug(PLUG, CONTACT), build_socket(SOCKET, CONTACT)


def _keyed():
    plug, socket, contact = default_keyed()
    return build_keyed_plug(plug, contact), build_keyed_socket(socket, contact)


def _site_z(spec: mujoco.MjSpec, name: str) -> float:
    return float(spec.compile().site(name).pos[2])


def measure(make, case: Case, yaw_deg: float, repeats: int = 3):
    """Insert with the fragments of ``make()`` (socket yawed about its axis); the fastest
    per-step timings of ``repeats`` runs (the physics is deterministic)."""
    plug, socket = make()
    length, mouth = _site_z(plug, "tcp"), _site_z(socket, "mouth")
    plug, socket = make()
    half = 0.5 * math.radians(yaw_deg)
    socket.body("dock").quat = [math.cos(half), 0.0, 0.0, math.sin(half)]
    rig = rig_from_fragments(plug, socket, length, mouth, case)
    best = push_insertion(rig, dwell=0.5)
    for _ in range(repeats - 1):
        again = push_insertion(rig, dwell=0.5)
        best.us_per_step = min(best.us_per_step, again.us_per_step)
        best.collision_us_per_step = min(best.collision_us_per_step, again.collision_us_per_step)
    return best, rig.model.ngeom


def _pieces_rows(pair: str, plug_stl: Path, socket_stl: Path, threshold: float, symmetry: int):
    """Decompose the socket at ``threshold`` (no refinement) and rebuild the pieces as the
    converter does; print both clearance checks; return two rows (CoACD's pieces, the
    rebuilt ones) whose fragments hold those pieces even if a check fails."""
    from compliant_docking.sim.geometry import cad
    from compliant_docking.sim.geometry.clearance import check_clearance
    from compliant_docking.sim.geometry.conform import ConformSettings, conform
    from compliant_docking.sim.geometry.convex import CoacdSettings, decompose
    from compliant_docking.sim.geometry.fragment import Key

    plug = cad.load_mesh(plug_stl, plug_stl.read_bytes(), 1e-3, "plug")
    socket = cad.load_mesh(socket_stl, socket_stl.read_bytes(), 1e-3, "socket")
    t0 = time.perf_counter()
    settings = CoacdSettings(threshold)
    plug_hulls, raw = decompose(*plug, settings), decompose(*socket, settings)
    seconds = time.perf_counter() - t0
    rebuilt, report = conform(raw, socket, ConformSettings())
    z_tip, z_top = float(plug[0][:, 2].min()), float(plug[0][:, 2].max())
    options = cad.ConvertOptions(symmetry=symmetry, plug_mass=0.3).resolved()
    rows = []
    for kind, hulls in (("CoACD's pieces", raw), ("rebuilt", rebuilt)):
        check = check_clearance(plug, plug_hulls, socket, hulls)
        print(
            f"{pair}, CoACD {threshold:g} ({seconds:.1f} s), {kind}: {len(hulls)} socket pieces; "
            f"{check.summary()}; {'passes' if check.passed else 'FAILS'} at keep {check.keep}",
            flush=True,
        )

        def make(hulls=hulls):
            tool, _ = cad.tool_fragment(plug, plug_hulls, z_tip, z_top, options, Key(symmetry))
            return tool, cad.target_fragment(socket, hulls, z_tip, options, Key(symmetry))

        rows.append((f"{pair}, CoACD {threshold:g}, {kind}: {len(hulls)} socket pieces", make))
    print(f"  rebuilding: {report.summary()} in {report.seconds:.1f} s", flush=True)
    return rows


def _outcome(r) -> str:
    if r.seated:
        return f"yes, {r.seat_time:.2f} s"
    return "JAMMED" if r.jammed else "no"


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--thresholds", default="", help="comma-separated CoACD thresholds to convert at")
    parser.add_argument(
        "--round", action="store_true", help="convert the round cone pair instead of the keyed one"
    )
    parser.add_argument(
        "--fragments",
        action="append",
        default=[],
        metavar="DIR",
        help="also time the conversion in DIR (tool.xml, target.xml)",
    )
    args = parser.parse_args(argv)
    started = time.perf_counter()
    rows = [
        ("cone: 16+16 boxes / cylinder + chamfer mesh", _cone),
        ("keyed: 4+4 boxes / prism + chamfer meshes", _keyed),
    ]
    with tempfile.TemporaryDirectory() as tmp:
        from compliant_docking.interface import export_keyed
        from compliant_docking.sim.geometry.cad import ConvertOptions, convert

        pair = "round CAD" if args.round else "keyed CAD"
        symmetry = 0 if args.round else 4
        if args.round:
            plug_stl, socket_stl = export_round(Path(tmp) / "cad")
        else:
            plug_stl, socket_stl = export_keyed(Path(tmp) / "cad")
        if (EXAMPLE / "tool.xml").is_file() and not args.round:
            rows.append(
                (f"keyed CAD example, {_pieces(EXAMPLE)} socket pieces", _fragments_from_dir(EXAMPLE))
            )
        for directory in map(Path, args.fragments):
            rows.append((f"{directory}, {_pieces(directory)} socket pieces", _fragments_from_dir(directory)))
        for text in filter(None, args.thresholds.split(",")):
            rows += _pieces_rows(pair, plug_stl, socket_stl, float(text), symmetry)
        sdf = Path(tmp) / "sdf"
        convert(
            plug_stl,
            socket_stl,
            sdf,
            ConvertOptions(symmetry=symmetry, plug_mass=0.3, collision="sdf"),
            log=lambda _: None,
        )
        rows.append((f"{pair}, mesh SDF (plug and socket)", _fragments_from_dir(sdf)))

        print(f"MuJoCo {mujoco.__version__}; push 5 N; sdf_iterations / initpoints at MuJoCo's defaults\n")
        print(
            "| geometry | case | geoms | µs/step in contact | collision µs/step | seated "
            "| max penetration [µm] | most contacts |"
        )
        print("|---|---|---|---|---|---|---|---|")
        for name, make in rows:
            for case, yaw in CASES:
                r, ngeom = measure(make, case, yaw)
                print(
                    f"| {name} | {case.name} | {ngeom} | {r.us_per_step:.1f} | {r.collision_us_per_step:.1f} | "
                    f"{_outcome(r)} | {-1e6 * r.min_contact_dist:.1f} | {r.max_contacts} |",
                    flush=True,
                )
    print(f"\nwall time {time.perf_counter() - started:.1f} s")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
