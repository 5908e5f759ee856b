"""Cost and behaviour of the plug/socket contact geometry in a small insertion rig.

Run from the repository root::

    python benchmarks/contact_geometry.py          # full tables (well under a minute)
    python benchmarks/contact_geometry.py --quick  # default geometry, two cases

The rig (:func:`build_rig`): the socket is fixed in the world with its axis vertical
(socket frame = world frame, seat at the origin).  The plug hangs tip down from a
light carrier whose six joints (slides along world x, y, z, then hinges about world
x, y, z, all through the plug's mounting face) act like a compliant wrist: weak
lateral and rotational springs pull towards the starting pose, the axial slide has no
spring, and a constant push force drives the plug along -z against an axial damper
that limits the free approach speed.  Zero gravity, 1 ms timestep, implicitfast,
elliptic friction cones, every other option at MuJoCo's default.

For every case the script reports the wall time of ``mj_step`` per step while in
contact (timed around each call), MuJoCo's collision timer over the same steps,
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
from compliant_docking.sim.geometry import build_plug, build_socket  # noqa: E402

#: the default interface of conf/ (tool=cone_plug, target=cone_socket)
PLUG, SOCKET, CONTACT = default_interface()
TIMESTEP = 0.001  # [s]
SEAT_TOLERANCE = 0.0005  # tip within 0.5 mm (axially) of the seat counts as seated [m]
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


@dataclass
class InsertionResult:
    """What happened in one rig run (lengths in m, times in s)."""

    seated: bool
    jammed: bool
    seat_time: float | None  # sim time at which the tip first seated
    final_tip_height: float  # tip height above the seat at the end
    min_contact_dist: float  # most negative contact distance seen
    steady_contact_dist: float  # mean per-step minimum distance after seating
    contact_steps: int
    us_per_step: float  # wall time of mj_step per contact step [us]
    collision_us_per_step: float  # MuJoCo's collision timer per contact step [us]
    max_contacts: int


@dataclass
class Rig:
    """A compiled rig and the indices a run needs."""

    model: mujoco.MjModel
    data: mujoco.MjData
    tcp_site: int
    seat_site: int
    push_dof: int


def _plug_orientation(tilt_deg: float) -> np.ndarray:
    """World quaternion of the plug frame: +z pointing down, tilted about world y."""
    half = 0.5 * math.radians(tilt_deg)
    tilt = np.array([math.cos(half), 0.0, math.sin(half), 0.0])
    flip = np.array([0.0, 1.0, 0.0, 0.0])  # 180 deg about x: plug +z -> world -z
    quat = np.zeros(4)
    mujoco.mju_mulQuat(quat, tilt, flip)
    return quat


def build_rig(
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
    """Compile the insertion rig for ``case`` from a tool and a target fragment.

    World frame = socket frame.  The plug tip starts ``START_GAP`` above the mouth and
    ``case.offset`` along +x from the axis, the plug axis tilted by ``case.tilt_deg``
    about world y; that pose is also the rest pose of the carrier's springs.  The
    fragments are attached exactly as the scene assembler does (site / frame attach).
    """
    spec = mujoco.MjSpec()
    spec.modelname = "contact_rig"
    spec.option.timestep = TIMESTEP
    spec.option.integrator = mujoco.mjtIntegrator.mjINT_IMPLICITFAST
    spec.option.cone = mujoco.mjtCone.mjCONE_ELLIPTIC
    spec.option.gravity = [0.0, 0.0, 0.0]
    spec.worldbody.add_frame().attach_body(socket.body("dock"), prefix="target_")

    quat = _plug_orientation(case.tilt_deg)
    rot = np.zeros(9)
    mujoco.mju_quat2Mat(rot, quat)
    plug_axis = rot.reshape(3, 3)[:, 2]
    tip = np.array([case.offset, 0.0, mouth_height + START_GAP])
    carrier = spec.worldbody.add_body(name="carrier", pos=(tip - plug_length * plug_axis).tolist())
    carrier.explicitinertial = True
    carrier.mass = 1e-3
    carrier.inertia = [1e-8, 1e-8, 1e-8]
    c = compliance
    for i, axis_name in enumerate("xyz"):
        axis = [0.0, 0.0, 0.0]
        axis[i] = 1.0
        axial = axis_name == "z"
        carrier.add_joint(
            name=f"slide_{axis_name}",
            type=mujoco.mjtJoint.mjJNT_SLIDE,
            axis=axis,
            stiffness=[0.0 if axial else c.lateral_stiffness, 0.0, 0.0],
            damping=[case.push / c.approach_speed if axial else c.lateral_damping, 0.0, 0.0],
        )
    for i, axis_name in enumerate("xyz"):
        axis = [0.0, 0.0, 0.0]
        axis[i] = 1.0
        carrier.add_joint(
            name=f"hinge_{axis_name}",
            type=mujoco.mjtJoint.mjJNT_HINGE,
            axis=axis,
            stiffness=[c.rotational_stiffness, 0.0, 0.0],
            damping=[c.rotational_damping, 0.0, 0.0],
        )
    mount = carrier.add_site(name="attachment_site", quat=quat.tolist())
    mount.attach_body(plug.body("dock"), prefix="tool_")

    model = spec.compile()
    data = mujoco.MjData(model)
    return Rig(
        model=model,
        data=data,
        tcp_site=model.site("tool_tcp").id,
        seat_site=model.site("target_seat").id,
        push_dof=int(model.joint("slide_z").dofadr[0]),
    )


def run_insertion(
    rig: Rig, push: float, *, duration: float = 3.0, dwell: float = 0.2, stall_time: float = 0.3, monitor=None
) -> InsertionResult:
    """Push the plug with ``push`` newtons along -z until it seats, jams or time runs out.

    Seated: tip height above the seat <= SEAT_TOLERANCE; the run then goes on for
    ``dwell`` seconds to measure the steady penetration under the push.  Jammed: above
    the seat while the axial speed stays below 0.1 mm/s for ``stall_time``.
    ``monitor(model, data)``, if given, is called after every step, outside the timing.
    """
    model, data = rig.model, rig.data
    mujoco.mj_resetData(model, data)
    data.qfrc_applied[rig.push_dof] = -push
    mujoco.mj_forward(model, data)
    timer = data.timer[mujoco.mjtTimer.mjTIMER_POS_COLLISION]
    n_steps = int(round(duration / model.opt.timestep))
    stall_steps = int(round(stall_time / model.opt.timestep))
    seat_time, stalled, jammed = None, 0, False
    step_ns, collision_s, contact_steps, max_contacts = 0, 0.0, 0, 0
    min_dist, steady = math.inf, []
    perf = time.thread_time_ns  # CPU time of this thread: a step the VM preempts costs nothing extra
    for _ in range(n_steps):
        collision_before = timer.duration
        t0 = perf()
        mujoco.mj_step(model, data)
        t1 = perf()
        if monitor is not None:
            monitor(model, data)
        ncon = data.ncon
        if ncon:
            contact_steps += 1
            step_ns += t1 - t0
            collision_s += timer.duration - collision_before
            max_contacts = max(max_contacts, ncon)
            step_min = float(data.contact.dist[:ncon].min())
            min_dist = min(min_dist, step_min)
            if seat_time is not None:
                steady.append(step_min)
        if seat_time is None:
            height = data.site_xpos[rig.tcp_site][2] - data.site_xpos[rig.seat_site][2]
            if height <= SEAT_TOLERANCE:
                seat_time = data.time
            else:
                stalled = stalled + 1 if abs(data.qvel[rig.push_dof]) < 1e-4 else 0
                if stalled >= stall_steps:
                    jammed = True
                    break
        elif data.time - seat_time >= dwell:
            break
    height = float(data.site_xpos[rig.tcp_site][2] - data.site_xpos[rig.seat_site][2])
    return InsertionResult(
        seated=seat_time is not None,
        jammed=jammed,
        seat_time=seat_time,
        final_tip_height=height,
        min_contact_dist=min_dist if contact_steps else math.nan,
        steady_contact_dist=float(np.mean(steady)) if steady else math.nan,
        contact_steps=contact_steps,
        us_per_step=1e-3 * step_ns / contact_steps if contact_steps else math.nan,
        collision_us_per_step=1e6 * collision_s / contact_steps if contact_steps else math.nan,
        max_contacts=max_contacts,
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
    rig = build_rig(plug, socket, contact, case)
    if disable_midphase:
        rig.model.opt.disableflags |= mujoco.mjtDisableBit.mjDSBL_MIDPHASE
    best = run_insertion(rig, case.push, **run_kwargs)
    for _ in range(repeats - 1):
        again = run_insertion(rig, case.push, **run_kwargs)
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


def measured_free_radius(socket: SocketGeometry, z: float, rays: int = 960) -> tuple[float, float]:
    """(min, max) over azimuth of the distance from the socket axis to the walls at height z.

    Casts ``rays`` evenly spaced horizontal rays from the axis against the compiled
    socket's geoms (MuJoCo's ray casting).  The minimum is the effective free radius;
    960 rays hit the polygon corners exactly for 12, 16, 20, 24, 30 or 32 sectors.
    """
    model = build_socket(socket, replace(CONTACT)).compile()
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    geomid = np.zeros(1, dtype=np.int32)
    origin = np.array([0.0, 0.0, z])
    hits = []
    for azimuth in np.linspace(0.0, 2.0 * math.pi, rays, endpoint=False):
        direction = np.array([math.cos(azimuth), math.sin(azimuth), 0.0])
        hits.append(mujoco.mj_ray(model, data, origin, direction, None, 1, -1, geomid))
    hits = np.array(hits)
    if np.any(hits < 0.0):
        raise RuntimeError(f"a ray from the axis at z={z} escaped the socket walls")
    return float(hits.min()), float(hits.max())


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
        lo, hi = measured_free_radius(socket, 0.5 * socket.insertion_depth)
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
