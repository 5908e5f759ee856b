"""Scene assembly: robot MJCF + tool fragment + target fragment + glue → MjModel.

The recipe follows the research code's ``Scene.build_mjmodel``:

1. the arm spec is loaded from the robot's MJCF;
2. the tool's root body ``dock`` is posed relative to the flange site
   (``tool.mount_pos``/``mount_quat``) and attached there with ``tool.prefix``;
3. the target's root body ``dock`` is attached to a world frame at the socket's TRUE
   pose (the planner may believe another one, see :class:`SocketPose`);
4. floor, light, tracking camera and sensors (force and torque at the tool's
   ``sensor_site``) are added after the attaches;
5. the physics options are set on the final spec (attach may carry the fragments'
   options along), then the spec is compiled.

Fragments: a root body named ``dock``; the tool must also carry a site ``sensor_site``
and may carry a site ``tcp`` (the controlled point, default the ``dock`` origin). The
tool must be rigid (no joints): its inertia is appended to Pinocchio's flange body.
Either fragment may declare a key (custom numerics, :mod:`compliant_docking.sim.geometry.
fragment`); the scene's :attr:`Scene.key` combines both. docs/interfaces.md has the rest.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import mujoco
import numpy as np
import pinocchio as pin

from compliant_docking import looked_in, resolve_path
from compliant_docking.config.geometry import ContactParams, PlugGeometry, SocketGeometry, check_fit
from compliant_docking.config.keyed import KeyedPlugGeometry, KeyedSocketGeometry, check_keyed_fit
from compliant_docking.config.schemas import PhysicsConfig, TargetConfig, ToolConfig
from compliant_docking.config.validate import misalignment_problems
from compliant_docking.sim.dynamics import draw as contact_draw
from compliant_docking.sim.geometry import build_plug, build_socket
from compliant_docking.sim.geometry.fragment import Key, read_key
from compliant_docking.sim.geometry.keyed import build_keyed_plug, build_keyed_socket
from compliant_docking.sim.misalignment import Misalignment, draw
from compliant_docking.sim.models import ArmModel, RigidTool, mount_placement
from compliant_docking.sim.settings import SimSettings

CAMERA = "track_cam"


@dataclass(frozen=True)
class SocketPose:
    """Where the socket's seat frame is (physics) and where the planner believes it is."""

    true: pin.SE3
    believed: pin.SE3
    misalignment: Misalignment = Misalignment()  # true = believed · misalignment.apply


@dataclass
class Scene:
    """The compiled simulation and the matching Pinocchio arm."""

    model: mujoco.MjModel
    arm: ArmModel
    socket: SocketPose | None
    force_adr: int  # sensordata address of the force sensor; the torque sensor follows
    tool_body: int  # MuJoCo id of the tool's root body
    sensor_site: int  # MuJoCo id of the tool's sensor site
    tcp_site: int  # MuJoCo id of the TCP site
    gravity: np.ndarray
    key: Key = Key()  # the interface's key (symmetry 0: round, any roll mates)


def _fragment_error(kind: str, source: str, problem: str) -> ValueError:
    return ValueError(
        f"{kind} fragment {source}: {problem}. A {kind} fragment must contain a root body "
        f"named 'dock'"
        + (
            " and a site named 'sensor_site' (the force/torque sensor anchor); a site 'tcp' is optional"
            if kind == "tool"
            else ""
        )
        + "."
    )


#: the parametric parts: geometry schema → (option name, builder)
_PARAMETRIC_TOOLS: dict[type, tuple[str, Callable[..., mujoco.MjSpec]]] = {
    PlugGeometry: ("cone_plug", build_plug),
    KeyedPlugGeometry: ("keyed_plug", build_keyed_plug),
}
_PARAMETRIC_TARGETS: dict[type, tuple[str, Callable[..., mujoco.MjSpec]]] = {
    SocketGeometry: ("cone_socket", build_socket),
    KeyedSocketGeometry: ("keyed_socket", build_keyed_socket),
}
#: parametric pairs that fit each other, with their fit check
_PAIRS: dict[tuple[type, type], Callable[[Any, Any], None]] = {
    (PlugGeometry, SocketGeometry): check_fit,
    (KeyedPlugGeometry, KeyedSocketGeometry): check_keyed_fit,
}


def _load_fragment(
    kind: str, node: ToolConfig | TargetConfig, contact: ContactParams | None
) -> tuple[mujoco.MjSpec, str, Key]:
    """The fragment's spec, a description of its source and its key: from ``node.mjcf``
    if set, else generated from its geometry.

    ``contact``: the contact parameters of the scene's plug/socket pair (the target's;
    None in free space, where the plug's geoms keep MuJoCo's defaults).
    """
    if node.mjcf:
        return _fragment_file(kind, node.mjcf)
    if isinstance(node, TargetConfig):
        spec = _PARAMETRIC_TARGETS[type(node.geometry)][1](node.geometry, node.contact)
    else:
        spec = _PARAMETRIC_TOOLS[type(node.geometry)][1](node.geometry, contact)
    return _checked(kind, spec, f"{kind}={node.name} (parametric)")


def _fragment_file(kind: str, mjcf: str) -> tuple[mujoco.MjSpec, str, Key]:
    """The spec, source and key of the fragment file ``mjcf``."""
    path = resolve_path(mjcf)
    if not path.is_file():
        raise ValueError(f"{kind}.mjcf: no such file {mjcf!r} (looked for {looked_in(mjcf)})")
    try:
        spec = mujoco.MjSpec.from_file(str(path))
    except Exception as exc:  # MuJoCo parse errors
        raise _fragment_error(kind, str(path), f"MuJoCo cannot parse it ({exc})") from None
    return _checked(kind, spec, str(path))


def _checked(kind: str, spec: mujoco.MjSpec, source: str) -> tuple[mujoco.MjSpec, str, Key]:
    """The fragment's spec, source and key, once it has what a ``kind`` fragment must have."""
    if spec.body("dock") is None:
        raise _fragment_error(kind, source, "no body named 'dock'")
    if kind == "tool" and spec.site("sensor_site") is None:
        raise _fragment_error(kind, source, "no site named 'sensor_site'")
    return spec, source, read_key(spec, source)


def fragment_file_problem(kind: str, mjcf: str) -> str | None:
    """Why the fragment file ``mjcf`` cannot be the ``kind`` ("tool", "target") of a scene,
    or None: the checks :func:`build_scene` makes when it loads it, for the checks before a
    run (compliant_docking/run/preflight.py)."""
    try:
        _fragment_file(kind, mjcf)
    except ValueError as exc:
        return str(exc)
    return None


def _check_pair(tool: ToolConfig, target: TargetConfig) -> None:
    """Two parametric parts must be a pair that fits (a fragment file is the user's call)."""
    if tool.mjcf or target.mjcf:
        return
    check = _PAIRS.get((type(tool.geometry), type(target.geometry)))
    if check is None:
        pairs = ", ".join(
            f"tool={_PARAMETRIC_TOOLS[a][0]} target={_PARAMETRIC_TARGETS[b][0]}" for a, b in _PAIRS
        )
        raise ValueError(
            f"tool={tool.name} and target={target.name} are not a mating pair: use "
            f"{pairs}, or a fragment file via tool.mjcf / target.mjcf (docs/interfaces.md)"
        )
    check(tool.geometry, target.geometry)


def rigid_tool(spec: mujoco.MjSpec, source: str) -> RigidTool:
    """Mass properties and frames of a tool fragment, expressed in its ``dock`` frame."""
    root = spec.body("dock")
    root.pos, root.quat = [0.0, 0.0, 0.0], [1.0, 0.0, 0.0, 0.0]
    model = spec.compile()
    if model.njnt:
        raise _fragment_error("tool", source, "it has joints; the tool must be rigid")
    data = mujoco.MjData(model)
    mujoco.mj_kinematics(model, data)
    mujoco.mj_comPos(model, data)
    bodies = range(1, model.nbody)
    mass = float(sum(model.body_mass[b] for b in bodies))
    if mass <= 0.0:
        raise _fragment_error("tool", source, "it has no mass")
    com = sum(model.body_mass[b] * data.xipos[b] for b in bodies) / mass
    inertia = np.zeros((3, 3))
    for b in bodies:
        rot = data.ximat[b].reshape(3, 3)
        offset = data.xipos[b] - com
        inertia += rot @ np.diag(model.body_inertia[b]) @ rot.T
        inertia += model.body_mass[b] * (offset @ offset * np.eye(3) - np.outer(offset, offset))

    def site_se3(name: str) -> pin.SE3:
        sid = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_SITE, name)
        if sid < 0:
            return pin.SE3.Identity()
        return pin.SE3(data.site_xmat[sid].reshape(3, 3).copy(), data.site_xpos[sid].copy())

    return RigidTool(mass=mass, com=com, inertia=inertia, tcp=site_se3("tcp"), sensor=site_se3("sensor_site"))


def socket_pose(settings: SimSettings) -> SocketPose | None:
    """The socket's nominal (believed) and physical (true) seat pose in the world.

    believed = ``target.pos``/``target.quat``; true = believed · the misalignment of
    ``task.misalignment`` (fixed or drawn with its seed; compliant_docking/sim/misalignment.py).
    """
    misaligned = settings.task.misalignment
    offset = draw(misaligned)
    target = settings.socket
    if target is None:
        needs_socket = misalignment_problems(vars(misaligned), has_target=False)  # the config check's rule
        if needs_socket:
            raise ValueError(" ".join(needs_socket))
        return None
    nominal = mount_placement(target.pos, target.quat, "target.quat")
    return SocketPose(true=offset.apply(nominal), believed=nominal, misalignment=offset)


def _add_glue(spec: mujoco.MjSpec, tool_prefix: str, socket: SocketPose | None) -> None:
    """Floor, light, tracking camera, and a pedestal under the socket (visual only)."""
    world = spec.worldbody
    spec.add_texture(
        name="grid",
        type=mujoco.mjtTexture.mjTEXTURE_2D,
        builtin=mujoco.mjtBuiltin.mjBUILTIN_CHECKER,
        width=256,
        height=256,
        rgb1=[0.82, 0.84, 0.86],
        rgb2=[0.72, 0.74, 0.77],
    )
    floor_mat = spec.add_material(name="groundplane", texrepeat=[4, 4])
    floor_mat.textures[mujoco.mjtTextureRole.mjTEXROLE_RGB] = "grid"
    world.add_geom(
        name="floor",
        type=mujoco.mjtGeom.mjGEOM_PLANE,
        size=[2.0, 2.0, 0.05],
        material="groundplane",
        contype=0,
        conaffinity=0,
    )
    world.add_light(
        name="sun",
        pos=[0.0, 0.0, 2.5],
        dir=[0.0, 0.0, -1.0],
        type=mujoco.mjtLightType.mjLIGHT_DIRECTIONAL,
        diffuse=[0.8, 0.8, 0.8],
    )
    look_at = socket.true.translation if socket is not None else np.array([0.5, 0.0, 0.3])
    world.add_camera(
        name=CAMERA,
        pos=(look_at + np.array([0.45, 0.9, 0.35])).tolist(),
        mode=mujoco.mjtCamLight.mjCAMLIGHT_TARGETBODY,
        targetbody=f"{tool_prefix}dock",
    )
    if socket is not None and socket.true.translation[2] > 0.02:
        height = float(socket.true.translation[2]) - 0.01
        world.add_geom(
            name="pedestal",
            type=mujoco.mjtGeom.mjGEOM_CYLINDER,
            size=[0.05, height / 2, 0.0],
            pos=[*socket.true.translation[:2], height / 2],
            rgba=[0.35, 0.36, 0.4, 1],
            contype=0,
            conaffinity=0,
            group=1,
        )


def _set_physics(spec: mujoco.MjSpec, physics: PhysicsConfig) -> None:
    opt = spec.option
    opt.timestep = float(physics.timestep)
    opt.gravity = [float(g) for g in physics.gravity]
    opt.integrator = int(physics.integrator.value)
    opt.cone = int(physics.cone.value)
    opt.iterations = int(physics.iterations)
    opt.tolerance = float(physics.tolerance)
    opt.sdf_iterations = int(physics.sdf_iterations)
    opt.sdf_initpoints = int(physics.sdf_initpoints)
    if not physics.midphase:
        opt.disableflags |= int(mujoco.mjtDisableBit.mjDSBL_MIDPHASE)


def build_scene(settings: SimSettings) -> Scene:
    """Assemble and compile the scene of ``settings`` and build the matching Pinocchio arm."""
    robot, plug, target, physics = settings.robot, settings.tool, settings.socket, settings.physics
    robot_path = resolve_path(robot.mjcf)
    if not robot_path.is_file():
        raise ValueError(f"robot.mjcf: no such file {robot.mjcf!r} (looked for {looked_in(robot.mjcf)})")
    arm_spec = mujoco.MjSpec.from_file(str(robot_path))
    ee_site = arm_spec.site(robot.ee_site)
    if ee_site is None:
        raise ValueError(f"robot.ee_site {robot.ee_site!r} is not a site of {robot_path}")

    # Tool: its mass properties first (from a standalone copy), then attach it posed
    # relative to the flange site: attach interprets the body pose in the site frame.
    contact = None if target is None else target.contact  # the pair's contact parameters
    tool_spec, source, key = _load_fragment("tool", plug, contact)
    tool = rigid_tool(tool_spec, source)
    tool_spec, _, _ = _load_fragment("tool", plug, contact)
    mount = mount_placement(plug.mount_pos, plug.mount_quat, "tool.mount_quat")
    tool_root = tool_spec.body("dock")
    tool_root.pos = mount.translation.tolist()
    tool_root.quat = pin.Quaternion(mount.rotation).coeffs()[[3, 0, 1, 2]].tolist()
    ee_site.attach_body(tool_root, prefix=plug.prefix)
    tcp_name = f"{plug.prefix}tcp"
    if arm_spec.site(tcp_name) is None:  # fragment without a tcp site: the dock origin
        arm_spec.body(f"{plug.prefix}dock").add_site(name=tcp_name)

    socket = socket_pose(settings)
    if socket is not None and target is not None:
        _check_pair(plug, target)
        target_spec, _, target_key = _load_fragment("target", target, contact)
        key = key.combine(target_key)
        quat = pin.Quaternion(socket.true.rotation).coeffs()[[3, 0, 1, 2]]
        frame = arm_spec.worldbody.add_frame(
            name="target_frame", pos=socket.true.translation.tolist(), quat=quat.tolist()
        )
        frame.attach_body(target_spec.body("dock"), prefix=target.prefix)

    _add_glue(arm_spec, plug.prefix, socket)
    sensor_site = f"{plug.prefix}sensor_site"
    arm_spec.add_sensor(
        name="force_sensor",
        type=mujoco.mjtSensor.mjSENS_FORCE,
        objtype=mujoco.mjtObj.mjOBJ_SITE,
        objname=sensor_site,
    )
    arm_spec.add_sensor(
        name="torque_sensor",
        type=mujoco.mjtSensor.mjSENS_TORQUE,
        objtype=mujoco.mjtObj.mjOBJ_SITE,
        objname=sensor_site,
    )
    _set_physics(arm_spec, physics)
    model = arm_spec.compile()
    if target is not None:  # the plant's contact drawn per seed (dynamics=randomised)
        contact_draw(settings.dynamics).apply(
            model, [model.body(f"{plug.prefix}dock").id, model.body(f"{target.prefix}dock").id]
        )

    if model.sensor("torque_sensor").adr[0] != model.sensor("force_sensor").adr[0] + 3:
        raise RuntimeError("force and torque sensors must be adjacent in sensordata")
    if model.nu != model.nv:
        raise ValueError(
            f"robot.mjcf {robot_path}: expected one motor per joint, found "
            f"{model.nu} actuators for {model.nv} joints"
        )
    gravity = np.asarray(physics.gravity, dtype=float)
    arm = ArmModel(robot_path, robot.ee_site, mount, tool, gravity)
    return Scene(
        model=model,
        arm=arm,
        socket=socket,
        force_adr=int(model.sensor("force_sensor").adr[0]),
        tool_body=model.body(f"{plug.prefix}dock").id,
        sensor_site=model.site(sensor_site).id,
        tcp_site=model.site(tcp_name).id,
        gravity=gravity,
        key=key if socket is not None else Key(),
    )
