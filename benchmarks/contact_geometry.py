"""Cost and behaviour of the plug/socket contact geometry in a small insertion rig.

Run from the repository root::

    python benchmarks/contact_geometry.py          # full tables (well under a minute)
    python benchmarks/contact_geometry.py --quick  # default geometry, two cases

The rig is the package's compliance rig (compliant_docking.sim.compliance_rig; built
here by :func:`rig_from_fragments`): the socket is fixed in the world with its axis
vertical (socket frame = world frame, seat at the origin).  The plug hangs tip down from a
light carrier whose six joints (slides along world x, y, z, then hinges about world
x, y, z, all through the plug's mounting face) act like a compliant wrist: weak
lateral and rotational springs pull towards the starting pose, the axial slide has no
spring, and a constant push force drives the plug along -z against an axial damper
that limits the free approach speed.  Zero gravity, 1 ms timestep, implicitfast,
elliptic friction cones, every other option at MuJoCo's default.

For every case the script reports the wall time of ``mj_step`` per step while in
contact (timed around each call with the thread's CPU time), MuJoCo's collision timer over the same steps,
whether and when the plug seats (tip within ``SEAT_TOLERANCE`` of the seat), whether
it jams (stalls above the seat), the deepest penetration seen (most negative contact
distance) and the most contacts at once.  It also measures the free radius of the
socket with rays and the steady penetration on the seat under 5 N and 30 N.
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from dataclasses import dataclass, replace
from pathlib import Path

import mujoco
import numpy as np

if __package__ in (None, ""):
    sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from compliant_docking.config.geometry import ContactParams, PlugGeometry, SocketGeometry  # noqa: E402
from compliant_docking.config.store import default_interface  # noqa: E402
from compliant_docking.sim.compliance_rig import (  # noqa: E402
    InsertionResult,
    Push,
    Rig,
    Support,
    build_rig,
    measured_free_radius,
    push_insertion,
)
from compliant_docking.sim.geometry import build_plug, build_socket  # noqa: E402

#: the default interface of conf/ (tool=cone_plug, target=cone_socket)
PLUG, SOCKET, CONTACT = default_interface()
TIMESTEP = 0.001  # [s]
START_GAP = 0.002  # the tip starts this far above the mouth [m]


@dataclass(frozen=True)
class Compliance:
    """Springs and dampers of the rig's carrier joints, per joint (SI units)."""

    lateral_stiffness: float = 100.0  # N/m, slides x and y
    lateral_damping: float = 10.0  # N s/m
    approach_speed: float = 0.05  # m/s; axial damping = push / approach_speed
    rotational_stiffness: float = 0.5  # N m/rad, hinges x, y, z
    rotational_damping: float = 0.02  # N m s/rad


@dataclass(frozen=True)
class Case:
    """Starting pose: lateral tip offset along world x [m], tilt about world y [deg],
    and the constant push along -z [N]."""

    name: str
    offset: float = 0.0
    tilt_deg: float = 0.0
    push: float = 5.0


def case_rig(
    plug: PlugGeometry,
    socket: SocketGeometry,
    contact: ContactParams,
    case: Case,
    *,
    compliance: Compliance = Compliance(),
) -> Rig:
    """Compile the insertion rig for ``case`` with the parametric plug and socket
    (:func:`rig_from_fragments`)."""
    return rig_from_fragments(
        build_plug(plug, contact),
        build_socket(socket, contact),
        plug.length,
        socket.mouth_height,
        case,
        compliance=compliance,
    )


def rig_from_fragments(
    plug: mujoco.MjSpec,
    socket: mujoco.MjSpec,
    plug_length: float,
    mouth_height: float,
    case: Case,
    *,
    compliance: Compliance = Compliance(),
) -> Rig:
    """The package's compliance rig (compliant_docking.sim.compliance_rig) for ``case``:
    the tip ``START_GAP`` above the mouth, the hinges (x, y, z) through the plug's
    mounting face, a constant push ``case.push``."""
    c = compliance
    support = Support(
        lateral_stiffness=c.lateral_stiffness,
        lateral_damping=c.lateral_damping,
        angular_stiffness=c.rotational_stiffness,
        angular_damping=c.rotational_damping,
        compliance_height=plug_length,
        twist=True,
    )
    return build_rig(
        plug,
        socket,
        plug_length,
        mouth_height + START_GAP,
        support=support,
        drive=Push(case.push, c.approach_speed),
        offset=case.offset,
        tilt_deg=case.tilt_deg,
        timestep=TIMESTEP,
    )


def insert(
    plug: PlugGeometry,
    socket: SocketGeometry,
    contact: ContactParams,
    case: Case,
    *,
    disable_midphase: bool = False,
    repeats: int = 1,
    **run_kwargs,
) -> InsertionResult:
    """Build the rig for ``case`` and run one insertion (``repeats`` times, keeping the
    fastest per-step timings: the physics is deterministic, only the clock is noisy).

    ``disable_midphase`` sets MuJoCo's midphase disable flag.
    """
    rig = case_rig(plug, socket, contact, case)
    if disable_midphase:
        rig.model.opt.disableflags |= mujoco.mjtDisableBit.mjDSBL_MIDPHASE
    best = push_insertion(rig, **run_kwargs)
    for _ in range(repeats - 1):
        again = push_insertion(rig, **run_kwargs)
        best.us_per_step = min(best.us_per_step, again.us_per_step)
        best.collision_us_per_step = min(best.collision_us_per_step, again.collision_us_per_step)
    return best


def axial_contact_force(model: mujoco.MjModel, data: mujoco.MjData) -> float:
    """Sum over contacts of the normal force's component along world z [N]."""
    total = 0.0
    force = np.zeros(6)
    for i in range(data.ncon):
        mujoco.mj_contactForce(model, data, i, force)
        total += force[0] * abs(data.contact.frame[i][2])
    return total


CASES = (
    Case("centred"),
    Case("offset 3 mm", offset=0.003),
    Case("offset 3 mm + tilt 2 deg", offset=0.003, tilt_deg=2.0),
    Case("offset 3 mm + tilt -2 deg", offset=0.003, tilt_deg=-2.0),
    Case("offset 6 mm", offset=0.006),
)
"""Tilt is about world y; +2 deg leans the tip back towards the socket axis."""

CONTACT_CANDIDATES = (
    ("DEFAULT", replace(CONTACT)),
    ("stiffer solimp 0.99/0.999", replace(CONTACT, solimp=(0.99, 0.999, 0.0005, 0.5, 2.0))),
    ("dampratio 0.7", replace(CONTACT, solref=(0.005, 0.7))),
    ("timeconst 0.002", replace(CONTACT, solref=(0.002, 1.0))),
    ("MuJoCo defaults", replace(CONTACT, solref=(0.02, 1.0), solimp=(0.9, 0.95, 0.001, 0.5, 2.0))),
)


@dataclass(frozen=True)
class Candidate:
    name: str
    socket: SocketGeometry
    plug: PlugGeometry
    disable_midphase: bool = False


CANDIDATES = (
    Candidate(
        f"DEFAULT {SOCKET.sectors} wall pieces / {PLUG.segments}-gon hull", replace(SOCKET), replace(PLUG)
    ),
    Candidate("12 wall pieces", replace(SOCKET, sectors=12), replace(PLUG)),
    Candidate("32 wall pieces", replace(SOCKET, sectors=32), replace(PLUG)),
    Candidate("32-gon hull", replace(SOCKET), replace(PLUG, segments=32)),
    Candidate("64-gon hull", replace(SOCKET), replace(PLUG, segments=64)),
    Candidate("default, midphase disabled", replace(SOCKET), replace(PLUG), disable_midphase=True),
)


def _outcome(r: InsertionResult) -> str:
    if r.seated:
        return f"yes, {r.seat_time:.2f} s"
    return "JAMMED" if r.jammed else "no"


def _print_insertion_table(contact: ContactParams, candidates, cases) -> None:
    print(
        "| geometry | case | us/step in contact | collision us/step | seated | "
        "max penetration [um] | max contacts |"
    )
    print("|---|---|---|---|---|---|---|")
    for cand in candidates:
        for case in cases:
            r = insert(
                cand.plug,
                cand.socket,
                contact,
                case,
                disable_midphase=cand.disable_midphase,
                repeats=5,
                dwell=0.5,
            )
            print(
                f"| {cand.name} | {case.name} | {r.us_per_step:.1f} | "
                f"{r.collision_us_per_step:.1f} | {_outcome(r)} | "
                f"{-1e6 * r.min_contact_dist:.1f} | {r.max_contacts} |",
                flush=True,
            )


def _print_clearance_table(plug: PlugGeometry) -> None:
    print(
        "| sectors | nominal clearance [mm] | measured min clearance [mm] | "
        "max (corner) [mm] | chord polygon would give [mm] |"
    )
    print("|---|---|---|---|---|")
    for sectors in (12, 16):
        socket = replace(SOCKET, sectors=sectors)
        lo, hi = measured_free_radius(socket, replace(CONTACT), 0.5 * socket.insertion_depth)
        chord = socket.bore_radius * math.cos(math.pi / sectors) - plug.radius
        print(
            f"| {sectors} | {1e3 * socket.radial_clearance:.3f} | "
            f"{1e3 * (lo - plug.radius):.3f} | {1e3 * (hi - plug.radius):.3f} | "
            f"{1e3 * chord:.3f} |"
        )


def _print_contact_table(plug: PlugGeometry, candidates, case: Case) -> None:
    print(
        f"Contact parameters, case '{case.name}': penetration on the seat (mean over the "
        "last 0.2 s), deepest penetration (impact at the approach speed), ripple of the "
        "axial contact force on the seat (std)."
    )
    print(
        "| contact | solref | solimp | push [N] | seated | steady pen. [um] | "
        "max pen. [um] | force on seat [N] |"
    )
    print("|---|---|---|---|---|---|---|---|")
    for name, contact in candidates:
        for push in (5.0, 30.0):
            forces = []
            r = insert(
                plug,
                replace(SOCKET),
                contact,
                replace(case, push=push),
                monitor=lambda m, d: forces.append(axial_contact_force(m, d)),
            )
            tail = np.array(forces[-150:])
            print(
                f"| {name} | {contact.solref} | {contact.solimp} | {push:.0f} | "
                f"{'yes' if r.seated else 'no'} | {-1e6 * r.steady_contact_dist:.1f} | "
                f"{-1e6 * r.min_contact_dist:.1f} | {tail.mean():.1f} +- {tail.std():.2f} |"
            )


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="default geometry, two cases")
    args = parser.parse_args(argv)
    plug, contact = replace(PLUG), replace(CONTACT)
    started = time.perf_counter()
    print(f"MuJoCo {mujoco.__version__}; {contact}; approach speed {Compliance().approach_speed} m/s\n")
    candidates = CANDIDATES[:1] if args.quick else CANDIDATES
    cases = CASES[:2] if args.quick else CASES
    _print_insertion_table(contact, candidates, cases)
    print()
    _print_clearance_table(plug)
    print()
    _print_contact_table(plug, CONTACT_CANDIDATES[:1] if args.quick else CONTACT_CANDIDATES, CASES[1])
    print(f"\nwall time {time.perf_counter() - started:.1f} s")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
