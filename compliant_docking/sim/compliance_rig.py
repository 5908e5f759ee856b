"""An arm-free compliance rig: the plug on a compliant support, driven into the socket.

The socket is fixed with its axis vertical (socket frame = world frame, seat at the
origin).  The plug hangs tip down from a light carrier body (1 g) whose joints are the
support: slides along world x and y (the lateral springs K_x), a slide along world z (the
drive), hinges about world x and y (the angular springs K_θ) and, optionally, about world
z.  The hinges pass through the COMPLIANCE CENTRE, on the plug's axis ``compliance_height``
above the tip (the plug's length puts it at the mounting face), so a force through that
point only translates the plug and a moment only turns it about that point, as in
Whitney's model.  The carrier's rest pose (every spring relaxed) is the starting pose:
the tip ``offset`` along +x from the socket's axis and ``start_height`` above the seat, the
plug's axis tilted by ``tilt_deg`` about world y (positive leans the tip towards -x, back
towards the axis for a positive offset).  Zero gravity, implicitfast, elliptic friction
cones, every other option at MuJoCo's default; the fragments are attached as the scene
assembler attaches them (site / frame attach).

Two drives along the axis:

- :class:`Push`: a constant force along -z against an axial damper that limits the free
  approach speed (:func:`push_insertion`: does the plug seat or jam, and what does a step
  in contact cost);
- :class:`Ramp`: a stiff position servo on the z slide following a constant-speed ramp,
  slow enough to be quasi-static (:func:`ramp_insertion` records the contact force,
  depth, tilt and every contact along the way).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import mujoco
import numpy as np

from compliant_docking.config.geometry import ContactParams, PlugGeometry, SocketGeometry
from compliant_docking.sim.geometry import build_plug, build_socket

#: the carrier's mass [kg] and inertia [kg m²]: light next to the plug
CARRIER_MASS, CARRIER_INERTIA = 1e-3, 1e-8
#: a tip within this height [m] (axially) of the seat counts as seated
SEAT_TOLERANCE = 0.0005


@dataclass(frozen=True)
class Support:
    """Springs and dampers of the carrier's joints, per joint (SI units).

    compliance_height: L_g, the compliance centre's height above the tip along the plug's
                       axis [m] (the hinges pass through it).
    twist:             a hinge about world z too (same stiffness and damping).
    """

    lateral_stiffness: float  # N/m, slides x and y
    lateral_damping: float  # N s/m
    angular_stiffness: float  # N m/rad, hinges
    angular_damping: float  # N m s/rad
    compliance_height: float  # m
    twist: bool = True


@dataclass(frozen=True)
class Push:
    """A constant push ``force`` [N] along -z; the axial damping is force / approach_speed."""

    force: float
    approach_speed: float  # m/s


@dataclass(frozen=True)
class Ramp:
    """A position servo on the z slide (stiffness [N/m], critically damped for the plug's
    mass) whose target descends at ``speed`` [m/s] from the starting pose."""

    speed: float
    stiffness: float = 1e5


@dataclass
class Rig:
    """A compiled rig and the indices a run needs."""

    model: mujoco.MjModel
    data: mujoco.MjData
    tcp_site: int
    mount_site: int
    seat_site: int
    drive_dof: int
    lateral_dofs: tuple[int, int]
    angular_dofs: tuple[int, ...]
    plug_geoms: frozenset[int]
    drive: Push | Ramp


def plug_orientation(tilt_deg: float) -> np.ndarray:
    """World quaternion of the plug frame: +z pointing down, tilted about world y."""
    half = 0.5 * math.radians(tilt_deg)
    tilt = np.array([math.cos(half), 0.0, math.sin(half), 0.0])
    flip = np.array([0.0, 1.0, 0.0, 0.0])  # 180 deg about x: plug +z -> world -z
    quat = np.zeros(4)
    mujoco.mju_mulQuat(quat, tilt, flip)
    return quat


def build_rig(
    plug: mujoco.MjSpec,
    socket: mujoco.MjSpec,
    plug_length: float,
    start_height: float,
    *,
    support: Support,
    drive: Push | Ramp,
    offset: float = 0.0,
    tilt_deg: float = 0.0,
    timestep: float = 0.001,
) -> Rig:
    """Compile the rig from a tool and a target fragment (see the module doc); the tip
    starts ``start_height`` [m] above the seat."""
    spec = mujoco.MjSpec()
    spec.modelname = "contact_rig"
    spec.option.timestep = timestep
    spec.option.integrator = mujoco.mjtIntegrator.mjINT_IMPLICITFAST
    spec.option.cone = mujoco.mjtCone.mjCONE_ELLIPTIC
    spec.option.gravity = [0.0, 0.0, 0.0]
    spec.worldbody.add_frame().attach_body(socket.body("dock"), prefix="target_")

    quat = plug_orientation(tilt_deg)
    rot = np.zeros(9)
    mujoco.mju_quat2Mat(rot, quat)
    plug_axis = rot.reshape(3, 3)[:, 2]  # mounting face -> tip
    tip = np.array([offset, 0.0, start_height])
    carrier = spec.worldbody.add_body(name="carrier", pos=(tip - plug_length * plug_axis).tolist())
    carrier.explicitinertial = True
    carrier.mass = CARRIER_MASS
    carrier.inertia = [CARRIER_INERTIA] * 3
    centre = (plug_length - support.compliance_height) * plug_axis  # in the carrier's frame
    s = support
    axial_damping = drive.force / drive.approach_speed if isinstance(drive, Push) else 0.0
    for i, name in enumerate("xyz"):
        axial = name == "z"
        carrier.add_joint(
            name=f"slide_{name}",
            type=mujoco.mjtJoint.mjJNT_SLIDE,
            axis=np.eye(3)[i].tolist(),
            stiffness=[0.0 if axial else s.lateral_stiffness, 0.0, 0.0],
            damping=[axial_damping if axial else s.lateral_damping, 0.0, 0.0],
        )
    for i, name in enumerate("xyz" if s.twist else "xy"):
        carrier.add_joint(
            name=f"hinge_{name}",
            type=mujoco.mjtJoint.mjJNT_HINGE,
            axis=np.eye(3)[i].tolist(),
            pos=centre.tolist(),
            stiffness=[s.angular_stiffness, 0.0, 0.0],
            damping=[s.angular_damping, 0.0, 0.0],
        )
    mount = carrier.add_site(name="attachment_site", quat=quat.tolist())
    mount.attach_body(plug.body("dock"), prefix="tool_")
    if isinstance(drive, Ramp):
        servo = spec.add_actuator(name="drive", target="slide_z", trntype=mujoco.mjtTrn.mjTRN_JOINT)
        servo.set_to_position(kp=drive.stiffness)

    model = spec.compile()
    if isinstance(drive, Ramp):  # critically damped for everything the slide carries
        data = mujoco.MjData(model)
        mujoco.mj_forward(model, data)
        axial_dof = int(model.joint("slide_z").dofadr[0])
        full = np.zeros((model.nv, model.nv))
        mujoco.mj_fullM(model, data, full)
        model.actuator_biasprm[0, 2] = -2.0 * math.sqrt(drive.stiffness * full[axial_dof, axial_dof])
        model.actuator_gainprm[0, 0] = drive.stiffness
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)

    def dof(name: str) -> int:
        return int(model.joint(name).dofadr[0])

    plug_body = model.body("tool_dock").id
    return Rig(
        model=model,
        data=data,
        tcp_site=model.site("tool_tcp").id,
        mount_site=model.site("tool_sensor_site").id,
        seat_site=model.site("target_seat").id,
        drive_dof=dof("slide_z"),
        lateral_dofs=(dof("slide_x"), dof("slide_y")),
        angular_dofs=tuple(dof(f"hinge_{n}") for n in ("xyz" if s.twist else "xy")),
        plug_geoms=frozenset(int(g) for g in np.flatnonzero(model.geom_bodyid == plug_body)),
        drive=drive,
    )


def interface_rig(
    plug: PlugGeometry,
    socket: SocketGeometry,
    contact: ContactParams,
    *,
    start_gap: float = 0.002,
    **kwargs,
) -> Rig:
    """:func:`build_rig` with the parametric plug and socket, the tip ``start_gap`` above
    the mouth; ``kwargs`` as for :func:`build_rig`."""
    return build_rig(
        build_plug(plug, contact),
        build_socket(socket, contact),
        plug.length,
        socket.mouth_height + start_gap,
        **kwargs,
    )


def critically_damp(rig: Rig, ratio: float = 1.0) -> None:
    """Set the lateral and angular dampers to ``ratio`` times critical damping of each joint
    alone (2 ζ √(k M_ii), M at the starting pose)."""
    model, data = rig.model, rig.data
    mujoco.mj_forward(model, data)
    full = np.zeros((model.nv, model.nv))
    mujoco.mj_fullM(model, data, full)
    for dof in (*rig.lateral_dofs, *rig.angular_dofs):
        joint = model.dof_jntid[dof]
        model.dof_damping[dof] = 2.0 * ratio * math.sqrt(model.jnt_stiffness[joint] * full[dof, dof])


@dataclass
class InsertionResult:
    """What happened in one push run (lengths in m, times in s)."""

    seated: bool
    jammed: bool
    seat_time: float | None  # sim time at which the tip first seated
    final_tip_height: float  # tip height above the seat at the end
    min_contact_dist: float  # most negative contact distance seen
    steady_contact_dist: float  # mean per-step minimum distance after seating
    contact_steps: int
    us_per_step: float  # thread CPU time of mj_step per contact step [us]
    collision_us_per_step: float  # MuJoCo's collision timer per contact step [us]
    max_contacts: int


def push_insertion(
    rig: Rig, *, duration: float = 3.0, dwell: float = 0.2, stall_time: float = 0.3, monitor=None
) -> InsertionResult:
    """Push the plug with the rig's :class:`Push` until it seats, jams or time runs out.

    Seated: tip height above the seat <= SEAT_TOLERANCE; the run then goes on for
    ``dwell`` seconds to measure the steady penetration under the push.  Jammed: above
    the seat while the axial speed stays below 0.1 mm/s for ``stall_time``.
    ``monitor(model, data)``, if given, is called after every step, outside the timing.
    Each ``mj_step`` is timed with the thread's CPU time (a step the VM preempts costs
    nothing extra).
    """
    model, data = rig.model, rig.data
    if not isinstance(rig.drive, Push):
        raise ValueError(f"push_insertion needs a rig built with drive=Push(...); got {rig.drive!r}.")
    mujoco.mj_resetData(model, data)
    data.qfrc_applied[rig.drive_dof] = -rig.drive.force
    mujoco.mj_forward(model, data)
    timer = data.timer[mujoco.mjtTimer.mjTIMER_POS_COLLISION]
    n_steps = int(round(duration / model.opt.timestep))
    stall_steps = int(round(stall_time / model.opt.timestep))
    seat_time, stalled, jammed = None, 0, False
    step_ns, collision_s, contact_steps, max_contacts = 0, 0.0, 0, 0
    min_dist, steady = math.inf, []
    perf = time.thread_time_ns
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
            if tip_height(rig) <= SEAT_TOLERANCE:
                seat_time = data.time
            else:
                stalled = stalled + 1 if abs(data.qvel[rig.drive_dof]) < 1e-4 else 0
                if stalled >= stall_steps:
                    jammed = True
                    break
        elif data.time - seat_time >= dwell:
            break
    return InsertionResult(
        seated=seat_time is not None,
        jammed=jammed,
        seat_time=seat_time,
        final_tip_height=tip_height(rig),
        min_contact_dist=min_dist if contact_steps else math.nan,
        steady_contact_dist=float(np.mean(steady)) if steady else math.nan,
        contact_steps=contact_steps,
        us_per_step=1e-3 * step_ns / contact_steps if contact_steps else math.nan,
        collision_us_per_step=1e6 * collision_s / contact_steps if contact_steps else math.nan,
        max_contacts=max_contacts,
    )


def tip_height(rig: Rig) -> float:
    """The tip's height above the seat [m]."""
    return float(rig.data.site_xpos[rig.tcp_site][2] - rig.data.site_xpos[rig.seat_site][2])


def plug_tilt(rig: Rig) -> float:
    """The plug's tilt about world y [rad], positive with the tip towards -x (as ``tilt_deg``)."""
    axis = rig.data.site_xpos[rig.tcp_site] - rig.data.site_xpos[rig.mount_site]
    return math.atan2(-axis[0], -axis[2])


def plug_contacts(rig: Rig) -> list[tuple[int, int, np.ndarray, np.ndarray, float, np.ndarray]]:
    """The plug/socket contacts now: (plug geom, socket geom, point [m], normal into the
    plug, distance [m], force on the plug [N]), world frame."""
    model, data = rig.model, rig.data
    found = []
    local = np.zeros(6)
    for i in range(data.ncon):
        c = data.contact[i]
        if c.geom1 in rig.plug_geoms:  # MuJoCo's force acts on geom2 along the normal (geom1 -> geom2)
            plug, other, sign = int(c.geom1), int(c.geom2), -1.0
        elif c.geom2 in rig.plug_geoms:
            plug, other, sign = int(c.geom2), int(c.geom1), 1.0
        else:
            continue
        mujoco.mj_contactForce(model, data, i, local)
        frame = c.frame.reshape(3, 3)
        force = sign * (frame.T @ local[:3])
        found.append((plug, other, c.pos.copy(), sign * frame[0].copy(), float(c.dist), force))
    return found


@dataclass
class Trace:
    """A ramp run, one row per step: time [s], tip height above the seat and tip x [m],
    tilt [rad] (as :func:`plug_tilt`), the contact force on the plug (x, y, z) [N] and the
    servo's force [N]; ``contacts`` holds, per contact and step, (step, plug geom, socket
    geom, point (3), normal into the plug (3), distance, force on the plug (3))."""

    time: np.ndarray
    tip_height: np.ndarray
    tip_x: np.ndarray
    tilt: np.ndarray
    force: np.ndarray
    servo_force: np.ndarray
    contacts: np.ndarray = field(default_factory=lambda: np.zeros((0, 15)))
    stopped: str = ""


def ramp_insertion(rig: Rig, *, end_height: float, max_force: float = 50.0, max_time: float = 60.0) -> Trace:
    """Drive the plug down with the rig's :class:`Ramp` until the tip is ``end_height`` [m]
    above the seat, the servo pushes with more than ``max_force`` [N] (wedged or jammed),
    or ``max_time`` [s] has passed; record every step (:class:`Trace`)."""
    model, data = rig.model, rig.data
    if not isinstance(rig.drive, Ramp):
        raise ValueError(f"ramp_insertion needs a rig built with drive=Ramp(...); got {rig.drive!r}.")
    mujoco.mj_resetData(model, data)
    mujoco.mj_forward(model, data)
    speed, dt = rig.drive.speed, model.opt.timestep
    n = int(round(max_time / dt))
    rows = np.full((n, 8), math.nan)
    contacts: list[list[float]] = []
    stopped = "time"
    tcp, seat_z = rig.tcp_site, float(data.site_xpos[rig.seat_site][2])
    for k in range(n):
        data.ctrl[0] = -speed * (data.time + dt)
        mujoco.mj_step(model, data)
        total = [0.0, 0.0, 0.0]
        if data.ncon:
            for plug, other, point, normal, dist, force in plug_contacts(rig):
                total = [total[0] + force[0], total[1] + force[1], total[2] + force[2]]
                contacts.append([k, plug, other, *point, *normal, dist, *force])
        servo = -float(data.actuator_force[0])
        height = float(data.site_xpos[tcp][2]) - seat_z
        rows[k] = (data.time, height, data.site_xpos[tcp][0], plug_tilt(rig), *total, servo)
        if height <= end_height:
            stopped = "depth"
            break
        if servo > max_force:
            stopped = "force"
            break
    rows = rows[: k + 1]
    return Trace(
        time=rows[:, 0],
        tip_height=rows[:, 1],
        tip_x=rows[:, 2],
        tilt=rows[:, 3],
        force=rows[:, 4:7],
        servo_force=rows[:, 7],
        contacts=np.array(contacts) if contacts else np.zeros((0, 15)),
        stopped=stopped,
    )


def measured_free_radius(
    socket: SocketGeometry, contact: ContactParams, z: float, rays: int = 960
) -> tuple[float, float]:
    """(min, max) over azimuth of the distance from the socket axis to the walls at height z.

    Casts ``rays`` evenly spaced horizontal rays from the axis against the compiled
    socket's geoms (MuJoCo's ray casting).  The minimum is the effective free radius;
    960 rays hit the polygon corners exactly for 12, 16, 20, 24, 30 or 32 sectors.
    """
    model = build_socket(socket, contact).compile()
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    geomid = np.zeros(1, dtype=np.int32)
    origin = np.array([0.0, 0.0, z])
    hits = []
    for azimuth in np.linspace(0.0, 2.0 * math.pi, rays, endpoint=False):
        direction = np.array([math.cos(azimuth), math.sin(azimuth), 0.0])
        hits.append(mujoco.mj_ray(model, data, origin, direction, None, 1, -1, geomid))
    found = np.array(hits)
    if np.any(found < 0.0):
        raise RuntimeError(f"a ray from the axis at z={z} escaped the socket walls")
    return float(found.min()), float(found.max())
