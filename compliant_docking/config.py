"""Typed schemas of the configuration tree, registered in Hydra's ConfigStore.

Every YAML option under ``conf/<group>/`` starts its defaults list with the schema of
its group (``- /schema/<group>@_here_: <schema>``), so a misspelled key, a wrong type or
an enum value outside the allowed set fails at composition with a message that names
the key. This module stays light (dataclasses only): it is imported by the launcher
process of every sweep.

Units are SI (m, rad, N, N·m, s) unless a field name says otherwise (``_deg``).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from enum import Enum
from typing import Any, List, Optional

from hydra.core.config_store import ConfigStore
from omegaconf import MISSING

from compliant_docking.geometry import ContactParams, PlugGeometry, SocketGeometry


class Integrator(Enum):
    """MuJoCo integrators (``mjtIntegrator``)."""

    euler = 0
    rk4 = 1
    implicit = 2
    implicitfast = 3


class Cone(Enum):
    """MuJoCo friction cones (``mjtCone``)."""

    pyramidal = 0
    elliptic = 1


class FrictionComp(Enum):
    """Friction feed-forward mode (CONTROL_LAWS.md, shared conventions)."""

    torque = "torque"  # f·tanh(2·τ_pre/f) + b·v: follows the commanded torque, no dead zone at v = 0
    velocity = "velocity"  # f·tanh(v/0.01) + b·v: classic velocity-sign compensation


class ForceSource(Enum):
    """Where a force-aware controller reads the contact wrench."""

    sensor = "sensor"  # the wrist force/torque sensor
    observer = "observer"  # sensorless: the generalised-momentum observer


# --------------------------------------------------------------------------- robot
@dataclass
class RobotConfig:
    """An arm: its MJCF and what MJCF cannot carry (velocity limits, software torque clip)."""

    name: str = MISSING
    mjcf: str = MISSING  # arm-only MJCF, relative to the repository root
    ee_site: str = "attachment_site"  # flange site where the tool is mounted
    velocity_limits: List[float] = MISSING  # datasheet joint speed limits [rad/s]
    torque_limits: List[float] = MISSING  # hardware joint torque limits [N·m] (MJCF ctrlrange)
    max_torque: List[float] = MISSING  # software clip of the command per joint [N·m]
    ik_guess: List[float] = MISSING  # joint-space seed of the start-pose inverse kinematics


# --------------------------------------------------------------------------- tool / target
@dataclass
class ToolConfig:
    """The plug. Parametric by default; ``mjcf`` names a fragment file instead.

    A fragment file must contain a root body ``dock`` and a site ``sensor_site``; an
    optional site ``tcp`` marks the controlled point (default: the ``dock`` origin).
    """

    name: str = MISSING
    mjcf: Optional[str] = None
    prefix: str = "tool_"
    mount_pos: List[float] = field(default_factory=lambda: [0.0, 0.0, 0.0])  # in the ee_site frame
    mount_quat: List[float] = field(default_factory=lambda: [1.0, 0.0, 0.0, 0.0])  # wxyz
    geometry: PlugGeometry = field(default_factory=PlugGeometry)


@dataclass
class TargetConfig:
    """The socket, fixed in the world. Its frame origin is the seat; +z points out of it.

    ``contact`` holds the contact parameters of every plug/socket contact (the socket's
    geoms have the higher priority, so MuJoCo uses their values unmixed).
    """

    name: str = MISSING
    mjcf: Optional[str] = None
    prefix: str = "target_"
    pos: List[float] = MISSING  # world position of the seat [m]
    quat: List[float] = field(default_factory=lambda: [1.0, 0.0, 0.0, 0.0])  # wxyz
    geometry: SocketGeometry = field(default_factory=SocketGeometry)
    contact: ContactParams = field(default_factory=ContactParams)


@dataclass
class NoTargetConfig:
    """``target=none``: free space (tracking runs)."""

    name: str = "none"


# --------------------------------------------------------------------------- physics
@dataclass
class PhysicsConfig:
    """MuJoCo options, set on the final assembled spec. Pinocchio uses the same gravity."""

    name: str = MISSING
    timestep: float = 0.001
    gravity: List[float] = field(default_factory=lambda: [0.0, 0.0, 0.0])
    integrator: Integrator = Integrator.implicitfast
    cone: Cone = Cone.elliptic
    iterations: int = 100
    tolerance: float = 1e-8
    sdf_iterations: int = 10
    sdf_initpoints: int = 40
    # MuJoCo's bounding-volume midphase pays off for large meshes; for the handful of
    # convex pieces of a docking interface it only costs time (results are identical).
    midphase: bool = False


# --------------------------------------------------------------------------- controllers
@dataclass
class ControllerConfig:
    """Fields every controller accepts."""

    _target_: str = MISSING
    name: str = MISSING
    friction_comp: FrictionComp = FrictionComp.torque
    use_force_feedback: bool = True  # feed the measured wrench to the law (off: pure motion control)


@dataclass
class ImpedanceConfig(ControllerConfig):
    """Task-space impedance (CONTROL_LAWS.md §1; seed ``ImpedanceConfig``)."""

    m: float = 10.0
    d: float = 80.0
    k: float = 50.0
    m_rot: float = 1.0
    d_rot: float = 10.0
    k_rot: float = 25.0
    null_damping: float = 10.0
    condition_threshold: float = 1e8  # cond(J M⁻¹ Jᵀ) above which Λ uses a damped pseudo-inverse


# --------------------------------------------------------------------------- trajectories
@dataclass
class TrajectoryConfig:
    """Fields every planner accepts."""

    _target_: str = MISSING
    name: str = MISSING


@dataclass
class QuinticConfig(TrajectoryConfig):
    """Rest-to-rest quintic along the stroke, orientation held (CONTROL_LAWS.md §4)."""

    duration: float = 15.0  # the seed's DockingConfig.traj_duration [s]


@dataclass
class HoldConfig(TrajectoryConfig):
    """Hold the start pose (push tests, compliance identification)."""

    duration: float = 5.0


# --------------------------------------------------------------------------- task
@dataclass
class DockingGateConfig:
    """When a docking run counts as a success (evaluated on the true socket pose)."""

    depth_tolerance_m: float = 0.001  # tip within this of the seat, along the socket axis
    lateral_tolerance_m: float = 0.001  # tip within this of the socket axis
    tilt_tolerance_deg: float = 2.0  # plug axis within this of the socket axis
    peak_force_budget_N: float = 50.0  # peak axial contact force allowed over the run


@dataclass
class TaskConfig:
    """Initial conditions, run length and success criteria of the experiment.

    ``init_pos``/``init_quat`` left null: the start pose is derived from the socket pose
    the planner believes, ``stroke`` before the seat (plus ``insertion_overshoot``).
    """

    name: str = MISSING
    init_pos: Optional[List[float]] = None  # TCP start position in the world [m]
    init_quat: Optional[List[float]] = None  # TCP start orientation, wxyz
    stroke: List[float] = field(default_factory=lambda: [0.0, 0.0, -0.1])  # start → goal [m]
    insertion_overshoot: float = 0.005  # goal this far past the seat, so the plug is pressed home [m]
    duration: Optional[float] = None  # run length [s]; null: planner duration + settle_time
    settle_time: float = 3.0  # run time after the trajectory ends [s]
    steady_window: float = 2.0  # window at the end for the steady-state metrics [s]
    gate: DockingGateConfig = field(default_factory=DockingGateConfig)
    progress: bool = True  # print a progress line while simulating


# --------------------------------------------------------------------------- top level
@dataclass
class Config:
    robot: RobotConfig = MISSING
    tool: ToolConfig = MISSING
    target: Any = MISSING  # TargetConfig or NoTargetConfig
    physics: PhysicsConfig = MISSING
    controller: Any = MISSING  # one of the controller schemas
    trajectory: Any = MISSING  # one of the planner schemas
    task: TaskConfig = MISSING


_SCHEMAS: dict[str, dict[str, type]] = {
    "robot": {"robot": RobotConfig},
    "tool": {"tool": ToolConfig},
    "target": {"socket": TargetConfig, "none": NoTargetConfig},
    "physics": {"physics": PhysicsConfig},
    "controller": {"impedance": ImpedanceConfig},
    "trajectory": {"quintic": QuinticConfig, "hold": HoldConfig},
    "task": {"task": TaskConfig},
}


def register_schemas() -> None:
    """Store every schema in Hydra's ConfigStore (idempotent)."""
    cs = ConfigStore.instance()
    cs.store(name="base_config", node=Config)
    for group, schemas in _SCHEMAS.items():
        for name, node in schemas.items():
            cs.store(group=f"schema/{group}", name=name, node=node)
