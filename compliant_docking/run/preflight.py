"""The checks of a job's config that need more than the config layer, run before anything
is created (the guard calls :func:`problems` for a run and for every job of a sweep).

:func:`compliant_docking.config.validate.check` judges the config by itself: keys, ranges,
relations, files that must exist. What it cannot judge without the robot's model or the
planner is judged here, by the same code the run uses, so that a job the run would
refuse is refused before its directory exists:

- **the fragment files** (``tool.mjcf``, ``target.mjcf``): MuJoCo loads them and they hold
  what a fragment must (a body ``dock``, the tool's ``sensor_site``, a valid key);
- **the robot's joints**: every per-joint list (``robot.velocity_limits``,
  ``robot.torque_limits``, ``robot.max_torque``, ``robot.ik_guess``) has one value per
  joint of ``robot.mjcf``, which has one motor per joint and the site ``robot.ee_site``
  (the arm's MJCF alone is compiled once per file and process: ~5 ms);
- **the planner**: built by :func:`compliant_docking.sim.simulate.plan` for the task's
  waypoints up to a rigid motion (:func:`compliant_docking.sim.task.nominal_waypoints`),
  so its own refusals (``trajectory=tracking`` with a socket, ``trajectory=twophase``
  without one, …) come now, and its duration is the run's;
- **memory**: the run's exact step count (the planned duration + ``task.settle_time``,
  or ``task.duration``) against the memory available
  (:func:`compliant_docking.config.memory.memory_problem`): a planner whose duration
  follows from the task (twophase, se3topp) is judged like a fixed one.

The simulation repeats each check when it builds the run (a run started from Python
without the guard gets the same refusals, recorded as a failed run).
"""

from __future__ import annotations

import functools
from pathlib import Path

from omegaconf import DictConfig


def problems(cfg: DictConfig) -> list[str]:
    """The problems of ``cfg`` (a composed config that passed the config layer's check),
    one sentence each; [] when the run can start."""
    from compliant_docking.config.memory import memory_problem
    from compliant_docking.config.validate import per_joint_problems

    found = _robot_problems(cfg)
    if not found:
        found = per_joint_problems(cfg, _robot(str(cfg.robot.mjcf))[0])
    for kind in ("tool", "target") if cfg.target.get("name") != "none" else ("tool",):
        mjcf = cfg[kind].get("mjcf")
        problem = _fragment(kind, str(mjcf)) if mjcf else None
        if problem:
            found.append(_sentence(problem))
    duration = _run_duration(cfg)
    if isinstance(duration, str):
        return [*found, duration]
    too_large = memory_problem(cfg, n_steps=int(round(duration / float(cfg.physics.timestep))))
    return [*found, too_large] if too_large else found


#: the run durations (or why the planner refuses) of the planner settings met so far: the
#: jobs of a sweep mostly share them (a 180-job preset has 6), and a planner costs ~10 ms
_PLANNED: dict[str, float | str] = {}


def _run_duration(cfg: DictConfig) -> float | str:
    """The run's length [s] with the planner of ``cfg``, or why the planner refuses the task;
    with a bounded reference, the longest it may be extended (``task.max_hold``) included."""
    import json

    from omegaconf import OmegaConf

    from compliant_docking.sim.settings import sim_settings
    from compliant_docking.sim.simulate import plan
    from compliant_docking.sim.task import hold_extension, nominal_waypoints, run_duration

    # what the planner and the run's length depend on (the task's waypoints up to a rigid motion)
    key = json.dumps(
        [
            OmegaConf.to_container(node, resolve=True) if OmegaConf.is_config(node) else node
            for node in (
                cfg.trajectory,
                cfg.target.get("name"),
                *(cfg.task.get(k) for k in ("stroke", "init_pos", "duration", "settle_time", "max_hold")),
                *(cfg.task.get(k) for k in ("insertion_overshoot", "press_duration")),
            )
        ],
        sort_keys=True,
        default=str,
    )
    if key not in _PLANNED:
        try:
            settings = sim_settings(cfg)
            planner = plan(cfg.trajectory, settings.task, nominal_waypoints(settings))
            _PLANNED[key] = run_duration(settings.task, planner)[0] + hold_extension(settings.task, planner)
        except ValueError as exc:
            _PLANNED[key] = _sentence(exc)
    return _PLANNED[key]


def _robot_problems(cfg: DictConfig) -> list[str]:
    try:
        nv, nu, sites = _robot(str(cfg.robot.mjcf))
    except ValueError as exc:
        return [_sentence(exc)]
    found = []
    if nu != nv:
        found.append(
            f"robot.mjcf {cfg.robot.mjcf}: expected one motor per joint, found {nu} for {nv} joints."
        )
    if cfg.robot.ee_site not in sites:
        found.append(
            f"robot.ee_site must be a site of robot.mjcf ({', '.join(sorted(sites)) or 'it has none'}); "
            f"got {cfg.robot.ee_site!r}."
        )
    return found


def _robot(mjcf: str) -> tuple[int, int, frozenset[str]]:
    """(joints, motors, site names) of the arm's MJCF file (ValueError when MuJoCo cannot
    load it); cached per file version."""
    from compliant_docking import resolve_path

    path = resolve_path(mjcf)
    try:
        stat = path.stat()
    except OSError as exc:
        raise ValueError(f"robot.mjcf: cannot read {path}: {exc.strerror or exc}") from None
    return _compiled(path, stat.st_mtime_ns, stat.st_size)


@functools.lru_cache(maxsize=8)
def _compiled(path: Path, mtime_ns: int, size: int) -> tuple[int, int, frozenset[str]]:
    import mujoco

    try:
        spec = mujoco.MjSpec.from_file(str(path))
        model = spec.compile()
    except Exception as exc:  # MuJoCo's parse and compile errors
        first = (str(exc).strip().splitlines() or [type(exc).__name__])[0]
        raise ValueError(f"robot.mjcf: MuJoCo cannot load {path}: {first}") from None
    return model.nv, model.nu, frozenset(model.site(i).name for i in range(model.nsite))


def _fragment(kind: str, mjcf: str) -> str | None:
    """Why the fragment file cannot be used (:func:`compliant_docking.sim.scene.fragment_file_problem`),
    cached per file version."""
    from compliant_docking import resolve_path

    path = resolve_path(mjcf)
    try:
        stat = path.stat()
    except OSError:
        return None  # a missing file is the config layer's refusal
    return _fragment_checked(kind, path, stat.st_mtime_ns, stat.st_size)


@functools.lru_cache(maxsize=16)
def _fragment_checked(kind: str, path: Path, mtime_ns: int, size: int) -> str | None:
    from compliant_docking.sim.scene import fragment_file_problem

    return fragment_file_problem(kind, str(path))


def _sentence(exc: BaseException | str) -> str:
    text = " ".join(str(exc).split())
    return text if text.endswith(".") else f"{text}."
