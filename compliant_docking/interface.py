"""``python -m compliant_docking.interface PLUG SOCKET --out DIR``: a docking interface from
CAD, as tool and target fragments of convex pieces rebuilt to collide like the solid
parts, with their clearance checked and their contacts audited
(:mod:`compliant_docking.sim.geometry.cad`; docs/interfaces.md).

Needs the optional ``cad`` extra (coacd, trimesh): ``pip install -e '.[cad]'``.
Exit status: 0 fragments written (or already up to date), 1 unusable input,
2 refused (the convex pieces lose the clearance, leave holes, or their contacts fail the
audit: the message says which and where; nothing is written).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from compliant_docking import exit_codes
from compliant_docking.sim.geometry.cad import COLLISIONS, UNITS, ConvertOptions, Refused, convert
from compliant_docking.sim.geometry.conform import ConformSettings
from compliant_docking.sim.geometry.convex import CoacdSettings

EXAMPLE_DIR = "assets/interfaces/keyed_cad"
#: --quick: CoACD's sampling and tree search cut down
QUICK = {"resolution": 500, "mcts_nodes": 10, "mcts_iterations": 30}
#: the command-line option of each field of ConvertOptions (for the refusals)
FLAGS = {
    "lift": "--lift-mm",
    "plug_mass": "--plug-mass",
    "min_threshold": "--min-threshold",
    "max_pieces": "--max-pieces",
    "margin": "--margin-mm",
    "bevel_deg": "--bevel-deg",
    "audit_tolerance_deg": "--audit-tolerance-deg",
}


def _parser() -> argparse.ArgumentParser:
    d, c, g = ConvertOptions(), CoacdSettings(), ConformSettings()  # the defaults' one home
    p = argparse.ArgumentParser(
        prog="python -m compliant_docking.interface",
        description=(
            "A docking interface from CAD: tool and target fragments of convex pieces that collide "
            "like the solid parts, their clearance checked and their contacts audited "
            "(docs/interfaces.md)."
        ),
        epilog=(
            "The two files hold the parts mated, in one frame, docking axis along z out of the "
            "socket through x = y = 0 (docs/interfaces.md). Example: python -m "
            f"compliant_docking.interface {EXAMPLE_DIR}/cad/plug.stl {EXAMPLE_DIR}/cad/socket.stl "
            f"--out {EXAMPLE_DIR} --symmetry 4"
        ),
    )
    p.add_argument("plug", nargs="?", help="the plug (tool): STL, OBJ, PLY, … (closed mesh)")
    p.add_argument("socket", nargs="?", help="the socket (target), same frame, mated")
    p.add_argument("--out", help="output directory: tool.xml, target.xml, interface.json")
    p.add_argument(
        "--unit", default=d.unit, choices=sorted(UNITS), help=f"length unit of the files ({d.unit})"
    )
    p.add_argument(
        "--symmetry",
        type=int,
        default=d.symmetry,
        help=f"the key: mates every 360/N deg about the axis (1: one way only; 0: round; default {d.symmetry})",
    )
    p.add_argument("--plug-mass", type=float, help="plug mass [kg] (default: density × volume)")
    p.add_argument(
        "--density", type=float, default=d.density, help=f"plug density [kg/m³] ({d.density:g}, aluminium)"
    )
    p.add_argument(
        "--threshold",
        type=float,
        default=c.threshold,
        help=f"CoACD concavity threshold to start with ({c.threshold})",
    )
    p.add_argument(
        "--min-threshold",
        type=float,
        default=d.min_threshold,
        help=f"lowest threshold refinement tries ({d.min_threshold})",
    )
    p.add_argument(
        "--max-pieces", type=int, default=d.max_pieces, help="CoACD's cap on pieces per part (-1: none)"
    )
    p.add_argument(
        "--margin-mm",
        type=float,
        default=1e3 * g.margin,
        help=f"how far the pieces' cut faces grow into their neighbours [mm] ({1e3 * g.margin:g})",
    )
    p.add_argument(
        "--bevel-deg",
        type=float,
        default=g.bevel_deg,
        help=f"the bevel of the pieces' seams in a face, from the face [deg] ({g.bevel_deg:g})",
    )
    p.add_argument(
        "--audit-tolerance-deg",
        type=float,
        default=d.audit_tolerance_deg,
        help=f"largest angle of a contact normal from the socket's surface ({d.audit_tolerance_deg:g})",
    )
    p.add_argument(
        "--keep", type=float, default=d.keep, help=f"share of every gap the pieces must keep ({d.keep})"
    )
    p.add_argument(
        "--lift-mm",
        type=float,
        default=1e3 * d.lift,
        help=f"plug lifted off the seat for the check [mm] ({1e3 * d.lift:g})",
    )
    p.add_argument("--seed", type=int, default=c.seed, help=f"CoACD's random seed ({c.seed})")
    p.add_argument(
        "--quick",
        action="store_true",
        help="cut CoACD's search down (resolution 500, 10 nodes × 30 iterations): about 4× faster, coarser cuts",
    )
    p.add_argument(
        "--collision",
        default=d.collision,
        choices=list(COLLISIONS),
        help="convex pieces (default) or each part's mesh as a MuJoCo SDF (exact shape, far slower contact)",
    )
    p.add_argument(
        "--export-keyed", metavar="DIR", help="write the keyed interface as plug.stl and socket.stl (mm)"
    )
    p.add_argument(
        "--sides",
        type=int,
        help="with --export-keyed: the polygon's sides (default: conf/tool/keyed_plug.yaml's)",
    )
    return p


def export_keyed(directory: str | Path, *overrides: str) -> tuple[Path, Path]:
    """Write the keyed plug and socket of conf/tool/keyed_plug.yaml and
    conf/target/keyed_socket.yaml (with ``overrides``, e.g. ``"tool.geometry.sides=6"``)
    as a mated CAD pair in mm: ``plug.stl`` and ``socket.stl`` in ``directory``."""
    from compliant_docking.config.store import default_keyed
    from compliant_docking.sim.geometry.mesh import keyed_cad_pair, write_stl

    plug_geometry, socket_geometry, _ = default_keyed(*overrides)  # checked before anything is written
    directory = Path(directory)
    directory.mkdir(parents=True, exist_ok=True)
    plug, socket = keyed_cad_pair(plug_geometry, socket_geometry)
    paths = directory / "plug.stl", directory / "socket.stl"
    write_stl(paths[0], plug, scale=1000.0, name="keyed plug, mm")
    write_stl(paths[1], socket, scale=1000.0, name="keyed socket, mm")
    return paths


def main(argv: list[str] | None = None) -> int:
    """``python -m compliant_docking.interface``; the exit status (a signal: 128 + its number)."""
    from compliant_docking.run import interrupt

    return interrupt.handled("interface", lambda: _main(argv))


def _main(argv: list[str] | None) -> int:
    parser = _parser()
    args = parser.parse_args(argv)
    if args.export_keyed:
        sides = () if args.sides is None else (f"tool.geometry.sides={args.sides}",)
        try:
            paths = export_keyed(args.export_keyed, *sides)
        except ValueError as exc:  # e.g. --sides outside the keyed plug's range
            print(f"error: --sides: {exc}", file=sys.stderr)
            return exit_codes.REFUSED
        for path in paths:
            print(f"wrote {path}")
        return 0
    if not (args.plug and args.socket and args.out):
        parser.error("give PLUG SOCKET --out DIR (or --export-keyed DIR)")
    options = ConvertOptions(
        unit=args.unit,
        symmetry=args.symmetry,
        plug_mass=args.plug_mass,
        density=args.density,
        coacd=CoacdSettings(threshold=args.threshold, seed=args.seed, **(QUICK if args.quick else {})),
        min_threshold=args.min_threshold,
        max_pieces=args.max_pieces,
        conform=ConformSettings(margin=args.margin_mm * 1e-3, bevel_deg=args.bevel_deg),
        audit_tolerance_deg=args.audit_tolerance_deg,
        keep=args.keep,
        lift=args.lift_mm * 1e-3,
        collision=args.collision,
    )
    refused = options.problems()  # before anything is read or written
    for name, text in refused:
        print(f"error: {FLAGS.get(name, '--' + name)}: {text}", file=sys.stderr)
    if refused:
        return exit_codes.REFUSED
    try:
        result = convert(args.plug, args.socket, args.out, options)
    except Refused as exc:
        print(f"refused: {exc}", file=sys.stderr)
        return exit_codes.REFUSED
    except (ValueError, ImportError) as exc:  # a file that cannot be read, a missing extra
        print(f"error: {exc}", file=sys.stderr)
        return exit_codes.REFUSED
    m, out = result.manifest, Path(args.out)
    clearance, play, audit = m["clearance"], m["key_yaw_play_deg"], m["contact_audit"]
    collision = (
        "SDF collision"
        if clearance is None
        else f"{m['pieces']['plug']} plug + {m['pieces']['socket']} socket pieces (CoACD threshold "
        f"{m['thresholds']}); clearance {1e3 * clearance['nominal_clearance_m']:.4f} mm nominal, "
        f"{1e3 * clearance['pieces_clearance_m']:.4f} mm with the pieces; contact audit: "
        f"{audit['contacts']} contacts, worst normal {audit['worst_deg']:.2f} deg off the socket's surface"
    )
    print(
        f"{out}: {collision}; key symmetry {m['key_symmetry']}, yaw play "
        f"{'n/a' if play is None else f'{play:.3f} deg'}; plug {m['mass_kg']:.4g} kg"
        + (" (from the cache)" if result.cached else "")
    )
    print(
        f"dock it: python -m compliant_docking tool.mjcf={out / 'tool.xml'} target.mjcf={out / 'target.xml'}"
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
