"""The simulation: build everything for a config, then the loop

    read state → reference → measured wrench → torque → clip → mj_step → record.

:func:`prepare` builds the scene, the Pinocchio arm, the start posture, the planner and
the controller (heavy objects are made here, inside the job, never at import time).
:meth:`Simulation.run` runs the loop and returns the :class:`Telemetry`; it stops early,
raising :class:`Diverged`, if the physics blows up. The loop is one implementation:
``run`` is :meth:`Simulation.start` then :meth:`Simulation.advance` to the end; the
Gymnasium environment (compliant_docking/env/) advances it a policy step at a time.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, field

import mujoco
import numpy as np
import pinocchio as pin
from hydra.utils import instantiate
from omegaconf import DictConfig

from compliant_docking.config.memory import memory_problem
from compliant_docking.config.ranges import require
from compliant_docking.config.schemas import RobotConfig, TaskConfig
from compliant_docking.config.validate import per_joint_problems, press_problem
from compliant_docking.planning.base import (
    Planner,
    PressHome,
    Reference,
    ReferenceTable,
    Waypoints,
)
from compliant_docking.planning.lead import LeadLimit, bounded
from compliant_docking.sim import model_error
from compliant_docking.sim.context import ControlContext, StepController
from compliant_docking.sim.models import ArmModel
from compliant_docking.sim.progress import RunProgress
from compliant_docking.sim.scene import Scene, build_scene
from compliant_docking.sim.sensor import Sensing, sensing, wrench_reader
from compliant_docking.sim.settings import SimSettings, sim_settings
from compliant_docking.sim.task import hold_extension, run_duration, task_waypoints
from compliant_docking.sim.telemetry import Telemetry

#: joint speed regarded as an exploding state [rad/s]
EXPLODING_SPEED = 100.0
#: steps between divergence checks
CHECK_EVERY = 50
#: what the log copies from MuJoCo each step, in this order
STATE_LOGGED = int(mujoco.mjtState.mjSTATE_QPOS | mujoco.mjtState.mjSTATE_QVEL | mujoco.mjtState.mjSTATE_CTRL)


class Diverged(RuntimeError):
    """The physics became non-finite or exploded; the message says when and why."""


@dataclass
class Simulation:
    cfg: DictConfig  # the run's composed config (its records and metrics read it)
    settings: SimSettings  # what the simulation reads of it, typed
    scene: Scene
    data: mujoco.MjData
    q0: np.ndarray
    waypoints: Waypoints
    planner: Planner
    controller: StepController
    duration: float
    n_steps: int
    telemetry: Telemetry
    loop_wall_time: float = 0.0
    notes: list[str] = field(default_factory=list)
    reference: ReferenceTable | None = None  # the planner's table, made by start()
    # the controller's own arm model (model_error); None: the plant's, scene.arm
    arm: ArmModel | None = None
    # what the controller reads (sensor, a believed payload); None: the exact wrench and state
    sensing: Sensing | None = None
    # the bounded reference (planning/lead.py) choosing reference's rows; None: open loop
    lead: LeadLimit | None = None
    steps_done: int = 0  # steps simulated so far: the index of the next one
    # steps allocated past the planned run for a held reference (task.max_hold): the run
    # lasts n_steps − extra_steps + the held steps, at most n_steps
    extra_steps: int = 0
    # the wrench handed to the controller at the last step (start() makes it)
    wrench: np.ndarray = field(default_factory=lambda: np.zeros(6), init=False)
    _loop: tuple | None = field(default=None, init=False, repr=False)  # the loop's bindings
    _elapsed: float = field(default=0.0, init=False, repr=False)

    @property
    def complete(self) -> bool:
        """Whether the run covers the whole planned trajectory."""
        return self.telemetry.count * self.scene.model.opt.timestep >= self.planner.duration - 1e-9

    @property
    def planned_steps(self) -> int:
        """The run's steps without a held reference: the planner's duration + settle time."""
        return self.n_steps - self.extra_steps

    @property
    def end(self) -> int:
        """The run's last step + 1: the planned steps extended by every step the bounded
        reference held the planner (so the settle time after the planner's end is whole),
        at most ``n_steps``."""
        if self.lead is None or not self.extra_steps:
            return self.n_steps
        return min(self.planned_steps + self.lead.held_steps, self.n_steps)

    @property
    def extension_capped(self) -> bool:
        """Whether the reference was held longer than ``task.max_hold`` extends the run (a
        fixed ``task.duration`` is never extended, so never capped)."""
        if self.lead is None or self.settings.task.duration is not None:
            return False
        return self.planned_steps + self.lead.held_steps > self.n_steps

    @property
    def finished(self) -> bool:
        """Whether all the run's steps (:attr:`end`) are simulated."""
        return self.steps_done >= self.end

    def run(self, progress: bool = False, on_step: Callable[[int], None] | None = None) -> Telemetry:
        """Simulate the run's steps (:attr:`end`); raises :class:`Diverged` when the physics blows up.

        The same loop as :meth:`start` then :meth:`advance` until the end (the Gymnasium
        environment advances it a policy step at a time). ``on_step(k)``, if given, is
        called after step k's ``mj_step`` (``data`` then holds the state at
        t = (k + 1)·dt), e.g. to pace an interactive viewer; None (the default) costs one
        ``is not None`` test per step.
        """
        self.start(progress=progress, on_step=on_step)
        self.advance(self.n_steps)
        return self.telemetry

    def start(self, progress: bool = False, on_step: Callable[[int], None] | None = None) -> None:
        """Make the planner's table of every step (:attr:`reference`) and the loop's
        bindings; no step is simulated. The table's time counts in ``loop_wall_time``.

        Between calls of :meth:`advance` the rows of :attr:`reference` not yet simulated
        may be rewritten (a new setpoint), and ``controller`` replaced by one that wraps it.
        """
        model, data = self.scene.model, self.data
        dt = model.opt.timestep
        arm = self.scene.arm if self.arm is None else self.arm
        measured = np.zeros(6)  # the exact wrench (logged: the metrics judge it)
        update: Callable[[np.ndarray, np.ndarray], None]
        if self.sensing is None:  # the ideal sensors: the controller reads the exact wrench
            wrench, update = measured, arm.update
            read_wrench = wrench_reader(self.scene, data, wrench)
        else:
            wrench = np.zeros(6)
            read_wrench = self.sensing.reader(self.scene, data, measured, wrench)
            update = self.sensing.updater(arm)
        reporter = RunProgress(self.planned_steps, dt, enabled=progress)
        start = time.perf_counter()
        # The planner's work is part of the loop's time: its table of every step first.
        self.reference = self.planner.table(np.arange(self.n_steps) * dt)
        self.lead = bounded(self.planner, self.reference, self.waypoints.axis)
        row = self.reference.row
        if self.lead is not None:  # the row chosen for the TCP position of the step
            # as the controller knows it: its own model, updated from what it reads
            lead_row, believed = self.lead.row, arm

            def row(k: int, ref: Reference) -> Reference:
                return lead_row(k, ref, believed.pos)

        self.wrench = wrench
        log = self.telemetry
        # bound once: MuJoCo's arrays are views made at each attribute access
        self._loop = (
            (read_wrench, reporter, on_step, Reference(), row, wrench, measured),
            (model, data, arm, update, log, dt),
            (data.qpos, data.qvel, data.ctrl, log.state, log.wrench, log.contacts),
            data.warning[mujoco.mjtWarning.mjWARN_BADQACC],
        )
        self.steps_done = 0
        self._elapsed = time.perf_counter() - start

    def sense_wrench(self) -> np.ndarray:
        """The F/T reading the controller will get at the next step (:attr:`wrench`, updated:
        the loop reads it again at the step, so reading it here changes nothing)."""
        if self._loop is None:
            raise RuntimeError("Simulation.sense_wrench needs Simulation.start() first")
        self._loop[0][0](self.steps_done)
        return self.wrench

    def advance(self, n: int) -> int:
        """Simulate the next ``n`` steps (fewer at the end of the run, :attr:`end`, which a
        held reference moves on while they run); returns how many.

        Raises :class:`Diverged` when the physics blows up. The torque clip is MuJoCo's
        actuator ``ctrlrange`` (set to ±robot.max_torque by the scene), so the loop writes
        the command and the log keeps it; the applied torque and the saturation flag
        follow from it after the loop. ``loop_wall_time`` is the time of the table and of
        every advance that returned.
        """
        if self._loop is None:
            raise RuntimeError("Simulation.advance needs Simulation.start() first")
        first = self.steps_done
        goal = first + max(int(n), 0)
        last = min(goal, self.end)
        (
            (read_wrench, reporter, on_step, ref, row, wrench, measured),
            (model, data, arm, update, log, dt),
            arrays,
            bad_qacc,
        ) = self._loop
        qpos, qvel, ctrl, log_state, log_w, log_contacts = arrays
        get_state, state_spec = mujoco.mj_getState, STATE_LOGGED
        mj_step, compute = mujoco.mj_step, self.controller.compute
        start = time.perf_counter()
        k0 = first
        while True:  # one pass without a held reference; a held one moves the end on
            for k in range(k0, last):
                t = k * dt
                update(qpos, qvel)
                row(k, ref)
                read_wrench(k)
                tau = compute(t, arm, ref, wrench)
                ctrl[:] = tau
                get_state(model, data, log_state[k], state_spec)  # [q, v, command]
                log_w[k] = measured
                log_contacts[k] = data.ncon
                mj_step(model, data)
                if on_step is not None:
                    on_step(k)
                if k % CHECK_EVERY == 0:
                    log.count = self.steps_done = k + 1
                    if (
                        bad_qacc.number
                        or not np.isfinite(qvel).all()
                        or np.abs(qvel).max() > EXPLODING_SPEED
                        or not np.isfinite(tau).all()
                    ):
                        raise Diverged(_divergence_reason(t, qvel, tau, bad_qacc.number))
                    reporter.update(k)
            log.count = self.steps_done = last
            k0, last = last, min(goal, self.end)
            if last <= k0:
                break
        self._elapsed += time.perf_counter() - start
        self.loop_wall_time = self._elapsed
        if self.steps_done >= self.end:
            reporter.done()
        return self.steps_done - first


def _divergence_reason(t: float, qvel: np.ndarray, tau: np.ndarray, bad_qacc: int) -> str:
    if not np.isfinite(tau).all():
        what = "the controller returned a non-finite torque"
    elif bad_qacc:
        what = "MuJoCo reported a non-finite or huge joint acceleration"
    elif not np.isfinite(qvel).all():
        what = "joint velocities became non-finite"
    else:
        what = f"a joint speed reached {np.abs(qvel).max():.3g} rad/s (limit {EXPLODING_SPEED:g})"
    return f"simulation diverged at t = {t:.3f} s: {what}"


def plan(trajectory: DictConfig, task: TaskConfig, waypoints: Waypoints) -> Planner:
    """The planner of ``trajectory`` (the `trajectory` config group's node) for ``waypoints``,
    followed by the press home when the ``task`` presses (:class:`PressHome`); raises
    ValueError for a planner that cannot serve the task."""
    # _partial_: the config's parameters are bound first, the run-time objects passed
    # directly (instantiate would otherwise turn dataclass arguments into dicts)
    planner = instantiate(trajectory, _partial_=True, _convert_="all")(waypoints=waypoints)
    overshoot = float(task.insertion_overshoot)
    if waypoints.goal is not None and overshoot != 0.0:
        require(TaskConfig, "task", press_duration=task.press_duration)  # the config check's rules
        too_long = press_problem(overshoot, task.press_duration, task.settle_time, has_target=True)
        if too_long:
            raise ValueError(too_long)
        planner = PressHome(planner, overshoot * waypoints.axis, task.press_duration)
    return planner


def prepare(cfg: DictConfig, settings: SimSettings | None = None) -> Simulation:
    """Build scene, arm, start posture, planner and controller for ``cfg`` (a composed config).

    The boundary of the simulation layer: the settings it reads are made typed here, once
    (:func:`compliant_docking.sim.settings.sim_settings`; ``settings``: those of ``cfg`` when
    the caller made them already), and the planner and the controller get theirs by
    instantiation; the config's own checks that need the built objects (the robot's
    joints, the exact step count) are asked with the config here too.
    """
    if settings is None:
        settings = sim_settings(cfg)
    robot, task = settings.robot, settings.task
    scene = build_scene(settings)
    model, arm = scene.model, scene.arm
    nv = model.nv
    wrong = per_joint_problems(cfg, nv)  # the config check's rules, for a run built from Python
    if wrong:
        raise ValueError(wrong[0])
    require(RobotConfig, "robot", max_torque=robot.max_torque)  # the motors' clip below

    waypoints = task_waypoints(settings, scene)
    planner = plan(cfg.trajectory, task, waypoints)
    duration, notes = run_duration(task, planner)
    ref = Reference()
    planner.sample(0.0, ref)
    q0 = arm.solve_ik(pin.SE3(ref.rot.copy(), ref.pos.copy()), np.asarray(robot.ik_guess, dtype=float))

    limits = np.asarray(robot.max_torque, dtype=float)
    model.actuator_ctrlrange[:] = np.column_stack([-limits, limits])  # the software clip
    data = mujoco.MjData(model)
    start_held(model, data, q0)
    planned_steps = int(round(duration / model.opt.timestep))
    extra_steps = int(round(hold_extension(task, planner) / model.opt.timestep))
    n_steps = planned_steps + extra_steps  # allocated; the run ends at Simulation.end
    too_large = memory_problem(cfg, n_steps=n_steps)  # before the logs are allocated
    if too_large:
        raise ValueError(too_large)
    # what the controller does not know: its own model (model_error) and its sensors (sensor)
    error = model_error.draw(settings.model_error)
    believed = model_error.believed_arm(settings, scene, error)
    sensors = sensing(
        settings.sensor, float(model.opt.timestep), n_steps, nv, believed.tool if error.tool_changed else None
    )
    context = ControlContext(
        arm=arm if believed is None else believed,
        dt=float(model.opt.timestep),
        n_steps=n_steps,
        q_home=q0.copy(),
        velocity_limits=np.asarray(robot.velocity_limits, dtype=float),
        torque_limits=np.asarray(robot.max_torque, dtype=float),
        joint_friction=model.dof_frictionloss * error.friction_scale,
        joint_damping=model.dof_damping * error.damping_scale,
        axis=waypoints.axis,
    )
    controller = instantiate(cfg.controller, _partial_=True, _convert_="all")(context=context)
    return Simulation(
        cfg=cfg,
        settings=settings,
        scene=scene,
        data=data,
        q0=q0,
        waypoints=waypoints,
        planner=planner,
        controller=controller,
        duration=duration,
        n_steps=n_steps,
        extra_steps=extra_steps,
        telemetry=Telemetry(n_steps, nv, model.opt.timestep),
        notes=notes,
        arm=believed,
        sensing=sensors,
    )


def start_held(model: mujoco.MjModel, data: mujoco.MjData, q0: np.ndarray) -> None:
    """The state before the first step: the arm at rest at ``q0``, held there against gravity.

    The run starts with the arm at rest, held as a real arm is held before its run starts
    (by its controller or brakes). So the motors carry the static gravity-holding torque
    (MuJoCo's own bias force at v = 0, within the software clip) in the forward pass that
    gives the first sensor reading: the F/T sensor then reads what it reads on a held arm,
    the tool's weight, which the payload compensation removes (≈ 1e-14 N). Without it the
    arm would be in free fall for that pass, and the first wrench, the one the controller
    gets at t = 0 and the time series' row 0, would be minus the tool's weight (3.6 N on
    the iiwa14 under Earth gravity): a force that is no contact. In zero gravity the
    holding torque is zero and nothing changes. The first step overwrites the command.
    """
    data.qpos[:] = q0
    data.qvel[:] = 0.0
    data.ctrl[:] = 0.0
    mujoco.mj_forward(model, data)
    if np.any(data.qfrc_bias):  # gravity: hold the arm (one actuator per joint, in order)
        data.ctrl[:] = data.qfrc_bias / model.actuator_gear[:, 0]
        mujoco.mj_forward(model, data)


def replay_physics(sim: Simulation) -> float:
    """Re-simulate the recorded torques with physics only; returns the loop's wall time [s].

    Same start state, same torque sequence, hence the same contacts: the denominator of
    the benchmark's loop/physics ratio.
    """
    model = sim.scene.model
    data = mujoco.MjData(model)
    start_held(model, data, sim.q0)
    torques = sim.telemetry.tau_cmd[: sim.telemetry.count]
    ctrl, mj_step = data.ctrl, mujoco.mj_step
    start = time.perf_counter()
    for tau in torques:
        ctrl[:] = tau
        mj_step(model, data)
    return time.perf_counter() - start
