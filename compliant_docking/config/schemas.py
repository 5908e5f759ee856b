"""Typed schemas of the configuration tree, registered in Hydra's ConfigStore.

Every YAML option under ``conf/<group>/`` starts its defaults list with the schema of
its group (``- /schema/<group>@_here_: <schema>``), so a misspelled key, a wrong type or
an enum value outside the allowed set fails at composition with a message that names
the key. This module holds dataclasses only and is imported by the launcher process of
every sweep; the geometry dataclasses it reuses bring in mujoco's module (~0.16 s), no
model or other heavy object is built.

Units are SI (m, rad, N, N·m, s) unless a field name says otherwise (``_deg``).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, List, Optional

from omegaconf import MISSING

from compliant_docking.config.enums import (
    Cone,
    ForceSource,
    FrictionComp,
    Integrator,
    NullSpaceMetric,
    SE3Formulation,
)
from compliant_docking.config.geometry import (
    ContactParams,
    PlugGeometry,
    SocketGeometry,
)


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


@dataclass
class HQPConfig(ControllerConfig):
    """HQP-AC: hierarchical QP with adaptive compliance (CONTROL_LAWS.md §2; seed ``HQPConfig``).

    The stiffness law K_r = clip((1 − α)·K0, K_min_ratio·K0, K0), α = 1/(1 + exp(−k_alpha·F)),
    already gives 0.5·K0 at F = 0. K0 is this config's, never the impedance gains.
    The torque constraint uses the robot's software clip (robot.max_torque).
    """

    K0: List[float] = field(default_factory=lambda: [300.0, 300.0, 300.0, 50.0, 50.0, 50.0])
    K_min_ratio: float = 0.3
    k_alpha: float = 0.5  # [1/N]
    omega_th: float = 0.08  # manipulability threshold of singularity avoidance
    k_sa: float = 500.0
    K_ji: List[float] = field(default_factory=lambda: [5.0] * 7)  # diagonal of the seed's 5·I [1/s²]
    D_ji: List[float] = field(default_factory=lambda: [10.0] * 7)  # diagonal of the seed's 10·I [1/s]
    k_ji: float = 1.0
    dt_p: float = 0.05  # zero-order-hold prediction horizon of the constraints [s]
    eps_abs: float = 1e-5  # ProxQP absolute accuracy
    force_source: ForceSource = ForceSource.sensor
    observer_kp: float = 20.0  # [1/s]
    observer_ki: float = 40.0  # [1/s²]
    preload_force: float = 0.0  # [N] along the docking axis; 0: off
    preload_ramp_s: float = 1.5  # [s]
    contact_deadband: float = 0.0  # [N] subtracted from the wrench norm
    condition_threshold: float = 1e8  # cond(J M⁻¹ Jᵀ) above which Λ's eigenvalues are floored
    null_space_metric: NullSpaceMetric = NullSpaceMetric.euclidean
    solve_every_step: bool = False  # call ProxQP even when the closed-form optimum meets every row


@dataclass
class SE3LieConfig(ControllerConfig):
    """SE(3) impedance in exponential coordinates (CONTROL_LAWS.md §3; seed
    ``SE3ImpedanceConfig``). Diagonals of the 6×6 A, D, K, translation first."""

    A_diag: List[float] = field(default_factory=lambda: [10.0, 10.0, 10.0, 1.0, 1.0, 1.0])  # [kg | kg·m²]
    D_diag: List[float] = field(
        default_factory=lambda: [80.0, 80.0, 80.0, 10.0, 10.0, 10.0]
    )  # [N·s/m | N·m·s/rad]
    K_diag: List[float] = field(
        default_factory=lambda: [50.0, 50.0, 50.0, 25.0, 25.0, 25.0]
    )  # [N/m | N·m/rad]
    null_damping: float = 10.0  # null-space joint acceleration damping q̈ = −b·v [1/s]
    condition_threshold: float = 1e8  # cond(J_b M⁻¹ J_bᵀ) above which Λ uses a damped pseudo-inverse
    desired_wrench: List[float] = field(
        default_factory=lambda: [0.0] * 6
    )  # F_d in the desired TCP frame [N, N·m]
    formulation: SE3Formulation = SE3Formulation.twist  # twist | lambda_space (same law)


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


@dataclass
class TwoPhaseConfig(TrajectoryConfig):
    """Approach to a pre-dock point ``standoff`` before the goal, then a slow docking segment.

    Each segment is a rest-to-rest quintic of length L lasting
    T = max(1.875·L/v_max, √(5.7735·L/a_max)) (CONTROL_LAWS.md §4; seed ``TrajectorySpec``).
    """

    standoff: float = 0.10  # pre-dock point this far before the goal along the docking axis [m]
    v_max_approach: float = 0.10  # [m/s]
    a_max_approach: float = 0.20  # [m/s²]
    v_max_docking: float = 0.02  # [m/s]
    a_max_docking: float = 0.05  # [m/s²]


@dataclass
class SE3ToppConfig(TwoPhaseConfig):
    """The twophase waypoints and linear limits, each segment a constant-screw geodesic with
    a time-optimal bang-bang profile, also under angular speed/acceleration limits
    (paper Table 8)."""

    omega_max_approach: float = 0.20  # angular speed [rad/s]
    alpha_max_approach: float = 0.20  # angular acceleration [rad/s²]
    omega_max_docking: float = 0.05  # [rad/s]
    alpha_max_docking: float = 0.05  # [rad/s²]


@dataclass
class TrackingConfig(TrajectoryConfig):
    """Free-space tracking test: transition, vertical circle, transition, horizontal figure-8.

    Needs ``target=none``. Each phase is driven by the quintic time scaling (rest to rest).
    """

    transition_duration: float = 1.5  # each of the two transitions [s]
    circle_duration: float = 5.0  # [s]
    circle_radius: float = 0.10  # [m]
    circle_frequency: float = 0.2  # mean revolutions per second [Hz]
    circle_center_offset: float = -0.06  # circle centre relative to the start, world z [m]
    figure8_duration: float = 5.0  # [s]
    figure8_radius_x: float = 0.10  # x amplitude [m]
    figure8_radius_y: float = 0.07  # y amplitude [m]
    figure8_frequency: float = 0.2  # mean cycles per second [Hz]


# --------------------------------------------------------------------------- task
@dataclass
class DockingGateConfig:
    """When a docking run counts as a success (evaluated on the true socket pose)."""

    depth_tolerance_m: float = 0.001  # tip within this of the seat, along the socket axis
    lateral_tolerance_m: float = 0.001  # tip within this of the socket axis
    tilt_tolerance_deg: float = 2.0  # plug axis within this of the socket axis
    peak_force_budget_N: float = 50.0  # peak axial contact force allowed over the run


@dataclass
class TrackingThresholds:
    """When a free-space tracking run (``trajectory=tracking``) passes its gate (seed defaults).

    RMS and peaks are taken over the planned motion (the segments), contacts over the
    whole run; see compliant_docking/tracking_gate.py.
    """

    circle_position_rms_m: float = 0.005  # position RMS over the circle segment [m]
    figure8_position_rms_m: float = 0.005  # position RMS over the figure-8 segment [m]
    position_peak_m: float = 0.015  # peak position error over the motion [m]
    orientation_rms_rad: float = 0.008726646259971648  # orientation RMS over the motion (0.5°) [rad]
    torque_saturation_ratio: float = 0.01  # share of steps with a clipped torque command
    max_contacts: int = 0  # largest number of MuJoCo contacts allowed at any step


@dataclass
class MisalignmentConfig:
    """Error between the socket's TRUE pose (physics, gate) and the pose the planner BELIEVES.

    The believed pose is the nominal ``target.pos``/``target.quat``; the true pose is
    believed · Trans(x, y, 0) · Rz(yaw) · Rx(tilt), offsets in the believed socket frame
    (origin at the seat, +z out of the opening; rotations about the seat point, tilt
    about the yawed x axis). Each component is fixed, or drawn uniformly from its
    ``*_range`` [low, high] with ``seed`` (then the fixed value must stay 0). See
    compliant_docking/misalignment.py and docs/sweeps.md.
    """

    x: float = 0.0  # lateral offset along the socket x axis [m]
    y: float = 0.0  # lateral offset along the socket y axis [m]
    yaw_deg: float = 0.0  # rotation about the socket axis [deg]
    tilt_deg: float = 0.0  # rotation about the (yawed) socket x axis [deg]
    x_range: Optional[List[float]] = None  # [low, high]: draw x uniformly [m]
    y_range: Optional[List[float]] = None  # [low, high]: draw y uniformly [m]
    yaw_deg_range: Optional[List[float]] = None  # [low, high]: draw yaw uniformly [deg]
    tilt_deg_range: Optional[List[float]] = None  # [low, high]: draw tilt uniformly [deg]
    seed: int = 0  # seed of the draws (same seed, same draw)


@dataclass
class TaskConfig:
    """Initial conditions, run length and success criteria of the experiment.

    ``init_pos``/``init_quat`` left null: the start pose is derived from the socket pose
    the planner believes, ``stroke`` before the seat. The planner ends at start + stroke
    (the seat) at rest; then the reference is pressed ``insertion_overshoot`` further
    along the axis over ``press_duration`` (rest to rest), during the settle time.
    """

    name: str = MISSING
    init_pos: Optional[List[float]] = None  # TCP start position in the world [m]
    init_quat: Optional[List[float]] = None  # TCP start orientation, wxyz
    stroke: List[float] = field(default_factory=lambda: [0.0, 0.0, -0.18])  # start → seat [m]
    insertion_overshoot: float = 0.005  # after the motion, press the reference this far past the seat [m]
    press_duration: float = 1.0  # how long that press takes (within settle_time) [s]
    duration: Optional[float] = None  # run length [s]; null: planner duration + settle_time
    settle_time: float = 3.0  # run time after the trajectory ends [s]
    steady_window: float = 2.0  # window at the end for the steady-state metrics [s]
    gate: DockingGateConfig = field(default_factory=DockingGateConfig)
    tracking_gate: TrackingThresholds = field(default_factory=TrackingThresholds)  # trajectory=tracking
    misalignment: MisalignmentConfig = field(
        default_factory=MisalignmentConfig
    )  # true vs believed socket pose
    progress: bool = True  # print a progress line while simulating


# --------------------------------------------------------------------------- render
@dataclass
class NoRenderConfig:
    """``render=none`` (the default): no video, and nothing of the renderer is imported."""

    name: str = "none"


@dataclass
class RenderConfig:
    """``render=video``: ``docking.mp4`` in the run directory (docs/rendering.md).

    Rendered after the simulation by replaying the logged joint positions, so the loop
    pays nothing. The video has round(simulated time × fps / speed) frames (at least
    one); frame i shows the logged step nearest to t = i · speed / fps.
    """

    name: str = "video"
    fps: int = 30  # frames per second of video [1/s]
    speed: float = 1.0  # simulated seconds per second of video (0.25: 4× slow motion)
    width: int = 960  # frame width [px], rounded down to even (H.264 4:2:0)
    height: int = 540  # frame height [px], force strip included, rounded down to even
    camera: str = "track_cam"  # model camera of the main view (the scene's, aimed at the tool)
    closeup: bool = True  # a second view beside it, close to the socket mouth (or the tool)
    closeup_distance: float = 0.2  # close-up camera distance from what it looks at [m]
    overlay: bool = True  # time and contact force: text and a force-over-time strip
    shadows: bool = False  # shadows: about 3× slower with software OpenGL
    antialias: bool = False  # 4× multisampling: about 3× slower with software OpenGL
    crf: int = 23  # H.264 constant rate factor: 0 lossless … 51 worst


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
    render: Any = MISSING  # NoRenderConfig or RenderConfig
    viewer: bool = False  # MuJoCo's interactive viewer, paced to real time (one run, a display)
