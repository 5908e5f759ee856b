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

from dataclasses import dataclass
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
from compliant_docking.config.keyed import KeyedPlugGeometry, KeyedSocketGeometry


# --------------------------------------------------------------------------- robot
@dataclass
class RobotConfig:
    """An arm: its MJCF and what MJCF cannot carry (velocity limits, software torque clip)."""

    name: str = MISSING
    mjcf: str = MISSING  # arm-only MJCF, relative to the repository root
    ee_site: str = MISSING  # flange site where the tool is mounted
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
    mjcf: Optional[str] = MISSING
    prefix: str = MISSING
    mount_pos: List[float] = MISSING  # in the ee_site frame
    mount_quat: List[float] = MISSING  # wxyz
    geometry: PlugGeometry = MISSING


@dataclass
class TargetConfig:
    """The socket, fixed in the world. Its frame origin is the seat; +z points out of it.

    ``contact`` holds the contact parameters of every plug/socket contact (the socket's
    geoms have the higher priority, so MuJoCo uses their values unmixed).
    """

    name: str = MISSING
    mjcf: Optional[str] = MISSING
    prefix: str = MISSING
    pos: List[float] = MISSING  # world position of the seat [m]
    quat: List[float] = MISSING  # wxyz
    geometry: SocketGeometry = MISSING
    contact: ContactParams = MISSING


@dataclass
class KeyedToolConfig(ToolConfig):
    """``tool=keyed_plug``: the polygonal plug (compliant_docking/sim/geometry/keyed.py)."""

    geometry: KeyedPlugGeometry = MISSING  # type: ignore[assignment]


@dataclass
class KeyedTargetConfig(TargetConfig):
    """``target=keyed_socket``: the polygonal socket (compliant_docking/sim/geometry/keyed.py)."""

    geometry: KeyedSocketGeometry = MISSING  # type: ignore[assignment]


@dataclass
class NoTargetConfig:
    """``target=none``: free space (tracking runs)."""

    name: str = MISSING


# --------------------------------------------------------------------------- physics
@dataclass
class PhysicsConfig:
    """MuJoCo options, set on the final assembled spec. Pinocchio uses the same gravity."""

    name: str = MISSING
    timestep: float = MISSING
    gravity: List[float] = MISSING
    integrator: Integrator = MISSING
    cone: Cone = MISSING
    iterations: int = MISSING
    tolerance: float = MISSING
    sdf_iterations: int = MISSING
    sdf_initpoints: int = MISSING
    # MuJoCo's bounding-volume midphase pays off for large meshes; for the handful of
    # convex pieces of a docking interface it only costs time (results are identical).
    midphase: bool = MISSING


# --------------------------------------------------------------------------- controllers
@dataclass
class ControllerConfig:
    """Fields every controller accepts."""

    _target_: str = MISSING
    name: str = MISSING
    friction_comp: FrictionComp = MISSING
    use_force_feedback: bool = MISSING  # feed the measured wrench to the law (off: pure motion control)


@dataclass
class ImpedanceConfig(ControllerConfig):
    """Task-space impedance (CONTROL_LAWS.md §1; seed ``ImpedanceConfig``)."""

    m: float = MISSING
    d: float = MISSING
    k: float = MISSING
    m_rot: float = MISSING
    d_rot: float = MISSING
    k_rot: float = MISSING
    null_damping: float = MISSING
    condition_threshold: float = MISSING  # cond(J M⁻¹ Jᵀ) above which Λ uses a damped pseudo-inverse


@dataclass
class HQPConfig(ControllerConfig):
    """HQP-AC: hierarchical QP with adaptive compliance (CONTROL_LAWS.md §2; seed ``HQPConfig``).

    The stiffness law K_r = clip((1 − α)·K0, K_min_ratio·K0, K0), α = 1/(1 + exp(−k_alpha·F)),
    already gives 0.5·K0 at F = 0. K0 is this config's, never the impedance gains.
    The torque constraint uses the robot's software clip (robot.max_torque).

    The keys are the seed's (HQPConfig) names, kept for the command line; in the code they
    are spelled out: K0 the maximum task stiffness, K_min_ratio the minimum stiffness
    ratio, k_alpha the sigmoid gain, omega_th the manipulability threshold, k_sa the
    singularity-avoidance weight, K_ji / D_ji the joint-posture stiffness / damping and
    k_ji the posture weight.
    """

    K0: List[float] = MISSING  # maximum task stiffness [N/m ×3, N·m/rad ×3]
    K_min_ratio: float = MISSING  # minimum stiffness, as a share of K0
    k_alpha: float = MISSING  # sigmoid gain of the adaptive stiffness [1/N]
    omega_th: float = MISSING  # manipulability threshold of singularity avoidance
    k_sa: float = MISSING  # weight of singularity avoidance [rad/s²]
    K_ji: List[float] = MISSING  # diagonal of the seed's 5·I [1/s²]
    D_ji: List[float] = MISSING  # diagonal of the seed's 10·I [1/s]
    k_ji: float = MISSING
    dt_p: float = MISSING  # zero-order-hold prediction horizon of the constraints [s]
    eps_abs: float = MISSING  # ProxQP absolute accuracy
    force_source: ForceSource = MISSING
    observer_kp: float = MISSING  # [1/s]
    observer_ki: float = MISSING  # [1/s²]
    preload_force: float = MISSING  # [N] along the docking axis; 0: off
    preload_ramp_s: float = MISSING  # [s]
    contact_deadband: float = MISSING  # [N] subtracted from the wrench norm
    condition_threshold: float = MISSING  # cond(J M⁻¹ Jᵀ) above which Λ's eigenvalues are floored
    null_space_metric: NullSpaceMetric = MISSING
    solve_every_step: bool = MISSING  # call ProxQP even when the closed-form optimum meets every row


@dataclass
class SE3LieConfig(ControllerConfig):
    """SE(3) impedance in exponential coordinates (CONTROL_LAWS.md §3; seed
    ``SE3ImpedanceConfig``). Diagonals of the 6×6 A, D, K, translation first."""

    A_diag: List[float] = MISSING  # [kg | kg·m²]
    D_diag: List[float] = MISSING  # [N·s/m | N·m·s/rad]
    K_diag: List[float] = MISSING  # [N/m | N·m/rad]
    null_damping: float = MISSING  # null-space joint acceleration damping q̈ = −b·v [1/s]
    condition_threshold: float = MISSING  # cond(J_b M⁻¹ J_bᵀ) above which Λ uses a damped pseudo-inverse
    desired_wrench: List[float] = MISSING  # F_d in the desired TCP frame [N, N·m]
    formulation: SE3Formulation = MISSING  # twist | lambda_space (same law)


# --------------------------------------------------------------------------- trajectories
@dataclass
class TrajectoryConfig:
    """Fields every planner accepts."""

    _target_: str = MISSING
    name: str = MISSING


@dataclass
class QuinticConfig(TrajectoryConfig):
    """Rest-to-rest quintic along the stroke, orientation held (CONTROL_LAWS.md §4)."""

    duration: float = MISSING  # the seed's DockingConfig.traj_duration [s]


@dataclass
class HoldConfig(TrajectoryConfig):
    """Hold the start pose (push tests, compliance identification)."""

    duration: float = MISSING


@dataclass
class TwoPhaseConfig(TrajectoryConfig):
    """Approach to a pre-dock point ``standoff`` before the goal, then a slow docking segment.

    Each segment is a rest-to-rest quintic of length L lasting
    T = max(1.875·L/v_max, √(5.7735·L/a_max)) (CONTROL_LAWS.md §4; seed ``TrajectorySpec``).
    """

    standoff: float = MISSING  # pre-dock point this far before the goal along the docking axis [m]
    v_max_approach: float = MISSING  # [m/s]
    a_max_approach: float = MISSING  # [m/s²]
    v_max_docking: float = MISSING  # [m/s]
    a_max_docking: float = MISSING  # [m/s²]


@dataclass
class SE3ToppConfig(TwoPhaseConfig):
    """The twophase waypoints and linear limits, each segment a constant-screw geodesic with
    a time-optimal bang-bang profile, also under angular speed/acceleration limits
    (paper Table 8)."""

    omega_max_approach: float = MISSING  # angular speed [rad/s]
    alpha_max_approach: float = MISSING  # angular acceleration [rad/s²]
    omega_max_docking: float = MISSING  # [rad/s]
    alpha_max_docking: float = MISSING  # [rad/s²]


@dataclass
class TrackingConfig(TrajectoryConfig):
    """Free-space tracking test: transition, vertical circle, transition, horizontal figure-8.

    Needs ``target=none``. Each phase is driven by the quintic time scaling (rest to rest).
    """

    transition_duration: float = MISSING  # each of the two transitions [s]
    circle_duration: float = MISSING  # [s]
    circle_radius: float = MISSING  # [m]
    circle_frequency: float = MISSING  # mean revolutions per second [Hz]
    circle_center_offset: float = MISSING  # circle centre relative to the start, world z [m]
    figure8_duration: float = MISSING  # [s]
    figure8_radius_x: float = MISSING  # x amplitude [m]
    figure8_radius_y: float = MISSING  # y amplitude [m]
    figure8_frequency: float = MISSING  # mean cycles per second [Hz]


# --------------------------------------------------------------------------- task
@dataclass
class DockingGateConfig:
    """When a docking run counts as a success (evaluated on the true socket pose)."""

    depth_tolerance_m: float = MISSING  # tip within this of the seat, along the socket axis
    lateral_tolerance_m: float = MISSING  # tip within this of the socket axis
    tilt_tolerance_deg: float = MISSING  # plug axis within this of the socket axis
    peak_force_budget_N: float = MISSING  # peak axial contact force allowed over the run
    # keyed interfaces: the plug's roll within this of the socket's key; null: the key's
    # yaw play + 0.1 deg (a seated plug cannot turn further), unchecked if it declares none
    key_yaw_tolerance_deg: Optional[float] = MISSING


@dataclass
class TrackingThresholds:
    """When a free-space tracking run (``trajectory=tracking``) passes its gate (seed defaults).

    RMS and peaks are taken over the planned motion (the segments), contacts over the
    whole run; see compliant_docking/tracking_gate.py.
    """

    circle_position_rms_m: float = MISSING  # position RMS over the circle segment [m]
    figure8_position_rms_m: float = MISSING  # position RMS over the figure-8 segment [m]
    position_peak_m: float = MISSING  # peak position error over the motion [m]
    orientation_rms_rad: float = MISSING  # orientation RMS over the motion (0.5°) [rad]
    torque_saturation_ratio: float = MISSING  # share of steps with a clipped torque command
    max_contacts: int = MISSING  # largest number of MuJoCo contacts allowed at any step


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

    x: float = MISSING  # lateral offset along the socket x axis [m]
    y: float = MISSING  # lateral offset along the socket y axis [m]
    yaw_deg: float = MISSING  # rotation about the socket axis [deg]
    tilt_deg: float = MISSING  # rotation about the (yawed) socket x axis [deg]
    x_range: Optional[List[float]] = MISSING  # [low, high]: draw x uniformly [m]
    y_range: Optional[List[float]] = MISSING  # [low, high]: draw y uniformly [m]
    yaw_deg_range: Optional[List[float]] = MISSING  # [low, high]: draw yaw uniformly [deg]
    tilt_deg_range: Optional[List[float]] = MISSING  # [low, high]: draw tilt uniformly [deg]
    seed: int = MISSING  # seed of the draws (same seed, same draw)


@dataclass
class TaskConfig:
    """Initial conditions, run length and success criteria of the experiment.

    ``init_pos``/``init_quat`` left null: the start pose is derived from the socket pose
    the planner believes, ``stroke`` before the seat. The planner ends at start + stroke
    (the seat) at rest; then the reference is pressed ``insertion_overshoot`` further
    along the axis over ``press_duration`` (rest to rest), during the settle time.
    """

    name: str = MISSING
    init_pos: Optional[List[float]] = MISSING  # TCP start position in the world [m]
    init_quat: Optional[List[float]] = MISSING  # TCP start orientation, wxyz
    stroke: List[float] = MISSING  # start → seat [m]
    insertion_overshoot: float = MISSING  # after the motion, press the reference this far past the seat [m]
    press_duration: float = MISSING  # how long that press takes (within settle_time) [s]
    duration: Optional[float] = MISSING  # run length [s]; null: planner duration + settle_time
    settle_time: float = MISSING  # run time after the trajectory ends [s]
    steady_window: float = MISSING  # window at the end for the steady-state metrics [s]
    gate: DockingGateConfig = MISSING
    tracking_gate: TrackingThresholds = MISSING  # trajectory=tracking
    misalignment: MisalignmentConfig = MISSING  # true vs believed socket pose
    progress: bool = MISSING  # print a progress line while simulating


# --------------------------------------------------------------------------- render
@dataclass
class NoRenderConfig:
    """``render=none`` (the default): no video, and nothing of the renderer is imported."""

    name: str = MISSING


@dataclass
class RenderConfig:
    """``render=video``: ``docking.mp4`` in the run directory (docs/rendering.md).

    Rendered after the simulation by replaying the logged joint positions, so the loop
    pays nothing. The video has round(simulated time × fps / speed) frames (at least
    one); frame i shows the logged step nearest to t = i · speed / fps.
    """

    name: str = MISSING
    fps: int = MISSING  # frames per second of video [1/s]
    speed: float = MISSING  # simulated seconds per second of video (0.25: 4× slow motion)
    width: int = MISSING  # frame width [px], rounded down to even (H.264 4:2:0)
    height: int = MISSING  # frame height [px], force strip included, rounded down to even
    camera: str = MISSING  # model camera of the main view (the scene's, aimed at the tool)
    closeup: bool = MISSING  # a second view beside it, close to the socket mouth (or the tool)
    closeup_distance: float = MISSING  # close-up camera distance from what it looks at [m]
    overlay: bool = MISSING  # time and contact force: text and a force-over-time strip
    shadows: bool = MISSING  # shadows: about 3× slower with software OpenGL
    antialias: bool = MISSING  # 4× multisampling: about 3× slower with software OpenGL
    crf: int = MISSING  # H.264 constant rate factor: 0 lossless … 51 worst


# --------------------------------------------------------------------------- top level
@dataclass
class Config:
    robot: RobotConfig = MISSING
    tool: Any = MISSING  # ToolConfig or KeyedToolConfig (their geometry schemas differ)
    target: Any = MISSING  # TargetConfig, KeyedTargetConfig or NoTargetConfig
    physics: PhysicsConfig = MISSING
    controller: Any = MISSING  # one of the controller schemas
    trajectory: Any = MISSING  # one of the planner schemas
    task: TaskConfig = MISSING
    render: Any = MISSING  # NoRenderConfig or RenderConfig
    viewer: bool = MISSING  # MuJoCo's interactive viewer, paced to real time (one run, a display)
    # per-run figures (figures/): null = a single run draws them, a sweep job does not;
    # true / false: always / never (`python -m compliant_docking.report PATH --runs` draws them later)
    figures: Optional[bool] = MISSING
