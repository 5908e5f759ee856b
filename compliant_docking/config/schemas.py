"""Typed schemas of the configuration tree, registered in Hydra's ConfigStore.

Every YAML option under ``conf/<group>/`` starts its defaults list with the schema of
its group (``- /schema/<group>@_here_: <schema>``), so a misspelled key, a wrong type or
an enum value outside the allowed set fails at composition with a message that names
the key. This module holds dataclasses only and is imported by the launcher process of
every sweep; the geometry dataclasses it reuses bring in mujoco's module (~0.16 s), no
model or other heavy object is built.

Units are SI (m, rad, N, N·m, s) unless a field name says otherwise (``_deg``).
Every numeric field declares its allowed values (``positive()``, ``within(0, 0.01, …)``:
:mod:`compliant_docking.config.ranges`); a composed config is checked against them before
anything runs (:mod:`compliant_docking.config.validate`). A range is not a default: the
values are in the YAML under ``conf/``.
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
    Precision,
    SE3Formulation,
)
from compliant_docking.config.geometry import (
    ContactParams,
    PlugGeometry,
    SocketGeometry,
)
from compliant_docking.config.keyed import KeyedPlugGeometry, KeyedSocketGeometry
from compliant_docking.config.ranges import (
    Range,
    at_least,
    declared,
    finite,
    inside,
    integers,
    positive,
    within,
)
from compliant_docking.config.robustness import DynamicsConfig, ModelErrorConfig, SensorConfig


# --------------------------------------------------------------------------- robot
@dataclass
class RobotConfig:
    """An arm: its MJCF and what MJCF cannot carry (velocity limits, software torque clip)."""

    name: str = MISSING
    mjcf: str = MISSING  # arm-only MJCF; relative: the working directory's, else under assets/ the package's
    ee_site: str = MISSING  # flange site where the tool is mounted
    velocity_limits: List[float] = positive(at_most=100.0, unit="rad/s")  # datasheet joint speed limits
    torque_limits: List[float] = positive(unit="N·m")  # hardware joint torque limits [N·m] (MJCF ctrlrange)
    max_torque: List[float] = positive(unit="N·m")  # software clip of the command per joint [N·m]
    ik_guess: List[float] = finite(unit="rad")  # joint-space seed of the start-pose inverse kinematics


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
    mount_pos: List[float] = within(-1.0, 1.0, unit="m", size=3)  # in the ee_site frame
    mount_quat: List[float] = within(-1.0, 1.0, size=4)  # wxyz
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
    pos: List[float] = within(-10.0, 10.0, unit="m", size=3)  # world position of the seat [m]
    quat: List[float] = within(-1.0, 1.0, size=4)  # wxyz
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
    timestep: float = positive(at_most=0.01, unit="s")
    gravity: List[float] = within(-100.0, 100.0, unit="m/s²", size=3)
    integrator: Integrator = MISSING
    cone: Cone = MISSING
    iterations: int = integers(1, 10_000)
    tolerance: float = within(0.0, 1.0, high_open=True)
    sdf_iterations: int = integers(1, 1000)
    sdf_initpoints: int = integers(1, 1000)
    # the midphase pays off for big meshes; for an interface's few convex pieces it costs time (same results)
    midphase: bool = MISSING


# --------------------------------------------------------------------------- controllers
CONDITION = Range(low=1.0, low_open=True)  # every controller's condition_threshold (Λ's fallback)


@dataclass
class ControllerConfig:
    """Fields every controller accepts (``integral_*``: docs/controllers/integral.md)."""

    _target_: str = MISSING
    name: str = MISSING
    friction_comp: FrictionComp = MISSING
    use_force_feedback: bool = MISSING  # feed the measured wrench to the law (off: pure motion control)
    integral_gain: float = at_least(0.0, unit="N/(m·s)")  # 0: off
    integral_limit: float = positive(unit="N")  # clamp of the integral force's norm
    integral_lateral_only: bool = MISSING  # only the error perpendicular to the docking axis
    integral_freeze_force: float = at_least(0.0, unit="N")  # frozen while the measured ‖f‖ exceeds this
    integral_latch: bool = MISSING  # true: frozen from the first such step to the end of the run
    integral_rot_gain: float = at_least(0.0, unit="N·m/(rad·s)")  # on the orientation error; 0: off
    integral_rot_limit: float = positive(unit="N·m")  # clamp of the integral moment's norm


@dataclass
class ImpedanceConfig(ControllerConfig):
    """Task-space impedance (docs/control_laws.md §1; seed ``ImpedanceConfig``)."""

    m: float = positive(unit="kg")
    d: float = at_least(0.0, unit="N·s/m")
    k: float = at_least(0.0, unit="N/m")
    m_rot: float = positive(unit="kg·m²")
    d_rot: float = at_least(0.0, unit="N·m·s/rad")
    k_rot: float = at_least(0.0, unit="N·m/rad")
    null_damping: float = at_least(0.0)
    condition_threshold: float = declared(CONDITION)  # cond(J M⁻¹ Jᵀ) past which Λ is a damped pseudo-inverse
    # keep the apparent inertia W ⪰ ratio·Λ (docs/controllers/impedance.md); null: the law of §1
    apparent_inertia_floor: Optional[float] = positive()


@dataclass
class HQPConfig(ControllerConfig):
    """HQP-AC: hierarchical QP with adaptive compliance (docs/control_laws.md §2; seed ``HQPConfig``).

    The stiffness law K_r = clip((1 − α)·K0, K_min_ratio·K0, K0), α = 1/(1 + exp(−k_alpha·F)),
    already gives 0.5·K0 at F = 0. K0 is this config's, never the impedance gains.
    The torque constraint uses the robot's software clip (robot.max_torque).

    The keys are the research code's (HQPConfig) names, kept for the command line; in the code they
    are spelled out: K0 the maximum task stiffness, K_min_ratio the minimum stiffness
    ratio, k_alpha the sigmoid gain, omega_th the manipulability threshold, k_sa the
    singularity-avoidance weight, K_ji / D_ji the joint-posture stiffness / damping and
    k_ji the posture weight.
    """

    K0: List[float] = positive(size=6)  # maximum task stiffness [N/m ×3, N·m/rad ×3]
    K_min_ratio: float = positive(at_most=1.0)  # minimum stiffness, as a share of K0
    k_alpha: float = at_least(0.0, unit="1/N")  # sigmoid gain of the adaptive stiffness [1/N]
    omega_th: float = at_least(0.0)  # manipulability threshold of singularity avoidance
    k_sa: float = at_least(0.0, unit="rad/s²")  # weight of singularity avoidance [rad/s²]
    K_ji: List[float] = at_least(0.0, unit="1/s²")  # diagonal of the research code's 5·I [1/s²]
    D_ji: List[float] = at_least(0.0, unit="1/s")  # diagonal of the research code's 10·I [1/s]
    k_ji: float = at_least(0.0)
    dt_p: float = positive(at_most=1.0, unit="s")  # zero-order-hold prediction horizon of the constraints
    eps_abs: float = positive()  # ProxQP absolute accuracy
    force_source: ForceSource = MISSING
    observer_kp: float = positive(unit="1/s")  # [1/s]
    observer_ki: float = at_least(0.0, unit="1/s²")  # [1/s²]
    preload_force: float = at_least(0.0, unit="N")  # [N] along the docking axis; 0: off
    preload_ramp_s: float = positive(unit="s")  # [s]
    contact_deadband: float = at_least(0.0, unit="N")  # [N] subtracted from the wrench norm
    condition_threshold: float = declared(CONDITION)  # cond(J M⁻¹ Jᵀ) above which Λ's eigenvalues are floored
    null_space_metric: NullSpaceMetric = MISSING
    solve_every_step: bool = MISSING  # call ProxQP even when the closed-form optimum meets every row


@dataclass
class SE3LieConfig(ControllerConfig):
    """SE(3) impedance in exponential coordinates (docs/control_laws.md §3; seed
    ``SE3ImpedanceConfig``). Diagonals of the 6×6 A, D, K, translation first."""

    A_diag: List[float] = positive(size=6)  # [kg | kg·m²]
    D_diag: List[float] = at_least(0.0, size=6)  # [N·s/m | N·m·s/rad]
    K_diag: List[float] = at_least(0.0, size=6)  # [N/m | N·m/rad]
    null_damping: float = at_least(0.0, unit="1/s")  # null-space joint acceleration damping q̈ = −b·v [1/s]
    condition_threshold: float = declared(CONDITION)  # cond(J_b M⁻¹ J_bᵀ) past which Λ is damped
    desired_wrench: List[float] = finite(size=6)  # F_d in the desired TCP frame [N, N·m]
    formulation: SE3Formulation = MISSING  # twist | lambda_space (same law)
    # keep the apparent inertia A ⪰ ratio·Λ_b (docs/controllers/se3_lie.md); null: the law of §3
    apparent_inertia_floor: Optional[float] = positive()


# --------------------------------------------------------------------------- trajectories
@dataclass
class TrajectoryConfig:
    """Fields every planner accepts."""

    _target_: str = MISSING
    name: str = MISSING


@dataclass
class QuinticConfig(TrajectoryConfig):
    """Rest-to-rest quintic along the stroke, orientation held (docs/control_laws.md §4)."""

    duration: float = positive(unit="s")  # the research code's DockingConfig.traj_duration [s]
    # the reference leads the plug by at most this along the insertion axis (null: open loop)
    lead_limit: Optional[float] = positive(unit="m")


@dataclass
class HoldConfig(TrajectoryConfig):
    """Hold the start pose (push tests, compliance identification)."""

    duration: float = positive(unit="s")


@dataclass
class TwoPhaseConfig(TrajectoryConfig):
    """Approach to a pre-dock point ``standoff`` before the goal, then a slow docking segment.

    Each segment is a rest-to-rest quintic of length L lasting
    T = max(1.875·L/v_max, √(5.7735·L/a_max)) (docs/control_laws.md §4; seed ``TrajectorySpec``).
    """

    standoff: float = at_least(0.0, unit="m")  # pre-dock point this far before the goal, along the axis
    v_max_approach: float = positive(unit="m/s")  # [m/s]
    a_max_approach: float = positive(unit="m/s²")  # [m/s²]
    v_max_docking: float = positive(unit="m/s")  # [m/s]
    a_max_docking: float = positive(unit="m/s²")  # [m/s²]
    # the reference leads the plug by at most this along the insertion axis (null: open loop)
    lead_limit: Optional[float] = positive(unit="m")


@dataclass
class SE3ToppConfig(TwoPhaseConfig):
    """The twophase waypoints and linear limits, each segment a constant-screw geodesic with
    a time-optimal bang-bang profile, also under angular speed/acceleration limits
    (paper Table 8)."""

    omega_max_approach: float = positive(unit="rad/s")  # angular speed [rad/s]
    alpha_max_approach: float = positive(unit="rad/s²")  # angular acceleration [rad/s²]
    omega_max_docking: float = positive(unit="rad/s")  # [rad/s]
    alpha_max_docking: float = positive(unit="rad/s²")  # [rad/s²]


@dataclass
class TrackingConfig(TrajectoryConfig):
    """Free-space tracking test: transition, vertical circle, transition, horizontal figure-8.

    Needs ``target=none``. Each phase is driven by the quintic time scaling (rest to rest).
    """

    transition_duration: float = positive(unit="s")  # each of the two transitions [s]
    circle_duration: float = positive(unit="s")  # [s]
    circle_radius: float = within(0.0, 1.0, unit="m")  # [m]
    circle_frequency: float = at_least(0.0, unit="Hz")  # mean revolutions per second [Hz]
    circle_center_offset: float = within(-1.0, 1.0, unit="m")  # circle centre relative to the start, world z
    figure8_duration: float = positive(unit="s")  # [s]
    figure8_radius_x: float = within(0.0, 1.0, unit="m")  # x amplitude [m]
    figure8_radius_y: float = within(0.0, 1.0, unit="m")  # y amplitude [m]
    figure8_frequency: float = at_least(0.0, unit="Hz")  # mean cycles per second [Hz]


# --------------------------------------------------------------------------- task
@dataclass
class DockingGateConfig:
    """When a docking run counts as a success (evaluated on the true socket pose)."""

    depth_tolerance_m: float = positive(unit="m")  # tip within this of the seat, along the socket axis
    lateral_tolerance_m: float = positive(unit="m")  # tip within this of the socket axis
    tilt_tolerance_deg: float = positive(at_most=180.0, unit="deg")  # plug axis this close to the socket axis
    peak_force_budget_N: float = positive(unit="N")  # peak axial contact force allowed over the run
    # keyed interfaces: the plug's roll within this of the socket's key; null: the key's
    # yaw play + 0.1 deg (a seated plug cannot turn further), unchecked if it declares none
    key_yaw_tolerance_deg: Optional[float] = positive(at_most=180.0, unit="deg")
    # a calm hold over the steady window (evaluation/contact.py; docs/run_directory.md)
    max_contact_events_per_s: float = at_least(0.0, unit="1/s")  # contact make/break events per second
    # std of |f| allowed: max(max_force_std_N, ratio × mean |f|)
    max_force_std_N: float = at_least(0.0, unit="N")
    max_force_std_ratio: float = at_least(0.0)


@dataclass
class TrackingThresholds:
    """When a free-space tracking run (``trajectory=tracking``) passes its gate (seed defaults).

    RMS and peaks are taken over the planned motion (the segments), contacts over the
    whole run; see compliant_docking/evaluation/tracking_gate.py.
    """

    circle_position_rms_m: float = positive(unit="m")  # position RMS over the circle segment [m]
    figure8_position_rms_m: float = positive(unit="m")  # position RMS over the figure-8 segment [m]
    position_peak_m: float = positive(unit="m")  # peak position error over the motion [m]
    orientation_rms_rad: float = positive(unit="rad")  # orientation RMS over the motion (0.5°) [rad]
    torque_saturation_ratio: float = within(0.0, 1.0)  # share of steps with a clipped torque command
    max_contacts: int = integers(0)  # largest number of MuJoCo contacts allowed at any step


@dataclass
class MisalignmentConfig:
    """Error between the socket's TRUE pose (physics, gate) and the pose the planner BELIEVES.

    The believed pose is the nominal ``target.pos``/``target.quat``; the true pose is
    believed · Trans(x, y, 0) · Rz(yaw) · Rx(tilt), offsets in the believed socket frame
    (origin at the seat, +z out of the opening; rotations about the seat point, tilt
    about the yawed x axis). Each component is fixed, or drawn uniformly from its
    ``*_range`` [low, high] with ``seed`` (then the fixed value must stay 0). See
    compliant_docking/sim/misalignment.py and docs/sweeps.md.
    """

    x: float = within(-1.0, 1.0, unit="m")  # lateral offset along the socket x axis [m]
    y: float = within(-1.0, 1.0, unit="m")  # lateral offset along the socket y axis [m]
    yaw_deg: float = within(-360.0, 360.0, unit="deg")  # rotation about the socket axis [deg]
    tilt_deg: float = inside(-60, 60, unit="deg")  # rotation about the (yawed) socket x axis [deg]
    x_range: Optional[List[float]] = within(-1.0, 1.0, unit="m", size=2)  # [low, high]: draw x uniformly [m]
    y_range: Optional[List[float]] = within(-1.0, 1.0, unit="m", size=2)  # [low, high]: draw y uniformly [m]
    yaw_deg_range: Optional[List[float]] = within(-360, 360, unit="deg", size=2)  # draw yaw in [low, high]
    tilt_deg_range: Optional[List[float]] = inside(-60, 60, unit="deg", size=2)  # draw tilt in [low, high]
    seed: int = integers(0, 2**63 - 1)  # seed of the draws (same seed, same draw)


@dataclass
class TaskConfig:
    """Initial conditions, run length and success criteria of the experiment.

    ``init_pos``/``init_quat`` left null: the start pose is derived from the socket pose
    the planner believes, ``stroke`` before the seat. The planner ends at start + stroke
    (the seat) at rest; then the reference is pressed ``insertion_overshoot`` further
    along the axis over ``press_duration`` (rest to rest), during the settle time.
    """

    name: str = MISSING
    init_pos: Optional[List[float]] = within(-10, 10, unit="m", size=3)  # TCP start position in the world
    init_quat: Optional[List[float]] = within(-1.0, 1.0, size=4)  # TCP start orientation, wxyz
    stroke: List[float] = within(-10.0, 10.0, unit="m", size=3)  # start → seat [m]
    insertion_overshoot: float = within(0.0, 0.1, unit="m")  # then press the reference this far past the seat
    press_duration: float = positive(unit="s")  # how long that press takes (within settle_time) [s]
    duration: Optional[float] = positive(unit="s")  # run length [s]; null: planner duration + settle_time
    settle_time: float = at_least(0.0, unit="s")  # run time after the trajectory ends [s]
    # the longest a held (bounded) reference extends the run, so the settle time stays whole [s]
    max_hold: float = at_least(0.0, unit="s")
    steady_window: float = positive(unit="s")  # window at the end for the steady-state metrics [s]
    # cap of the first strike after first contact (evaluation/contact.py)
    strike_window: float = positive(unit="s")
    # the filtered peak force: the peak of the axial force's mean over this window [s]
    force_window: float = positive(at_most=1.0, unit="s")
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
    fps: int = integers(1, 1000)  # frames per second of video [1/s]
    speed: float = positive()  # simulated seconds per second of video (0.25: 4× slow motion)
    width: int = integers(16, 8192)  # frame width [px], rounded down to even (H.264 4:2:0)
    height: int = integers(16, 8192)  # frame height [px], force strip included, rounded down to even
    camera: str = MISSING  # model camera of the main view (the scene's, aimed at the tool)
    closeup: bool = MISSING  # a second view beside it, close to the socket mouth (or the tool)
    closeup_distance: float = positive(unit="m")  # close-up camera distance from what it looks at [m]
    overlay: bool = MISSING  # time and contact force: text and a force-over-time strip
    shadows: bool = MISSING  # shadows: about 3× slower with software OpenGL
    antialias: bool = MISSING  # 4× multisampling: about 3× slower with software OpenGL
    crf: int = integers(0, 51)  # H.264 constant rate factor: 0 lossless … 51 worst


# --------------------------------------------------------------------------- output
@dataclass
class OutputConfig:
    """What a run writes beside its metrics (docs/run_directory.md, "Output size"): the
    metrics, gate and figures are computed from the full-precision series in memory,
    whatever is saved."""

    timeseries: bool = MISSING  # false: metrics only, no timeseries.parquet
    precision: Precision = MISSING  # float32: the saved series' floats in single precision
    every: int = integers(1, 1_000_000)  # save every N-th control step (1: every step)


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
    sensor: SensorConfig = MISSING  # what the controller's F/T sensor and encoders read
    model_error: ModelErrorConfig = MISSING  # the controller's model against the plant
    dynamics: DynamicsConfig = MISSING  # the plant's contact drawn per seed
    viewer: bool = MISSING  # MuJoCo's interactive viewer, paced to real time (one run, a display)
    # per-run figures (figures/): null = a single run draws them, a sweep job does not;
    # true / false: always / never (`python -m compliant_docking.report PATH --runs` draws them later)
    figures: Optional[bool] = MISSING
    output: OutputConfig = MISSING  # what the run saves beside its metrics
