"""``CompliantDocking-v0``: the docking task as a Gymnasium environment (docs/env.md).

An episode is one run of the composed config: the same scene, planner, controller and
physics loop (:meth:`Simulation.advance`, the loop :meth:`Simulation.run` runs to the end),
advanced one policy step (``env.policy_step``, a multiple of the physics timestep) per
action. ``reset(seed=s)`` draws the misalignment exactly as a run with
``task.misalignment.seed=s`` does (common random numbers with sweeps); ``reset()`` draws
the next seed from the generator the last ``reset(seed=…)`` seeded (``info["seed"]``). The episode ends (``terminated``) when the run's duration is
simulated, the docking gate then judging it as a run is judged, or when the physics
diverges; nothing truncates it (a ``TimeLimit`` wrapper may). ``info`` holds the reward's
terms every step and, at the end, the run's metrics (``metrics``, ``is_success``).
"""

from __future__ import annotations

import contextlib
import copy
import math
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np
from omegaconf import DictConfig

import compliant_docking.env.reward as R
from compliant_docking.env.actions import make_action
from compliant_docking.env.observation import Observer, observation_names
from compliant_docking.sim import mjlog
from compliant_docking.sim.simulate import Diverged, Simulation, prepare

#: the id it is registered under (compliant_docking.env)
ENV_ID = "CompliantDocking-v0"
#: the largest misalignment seed (task.misalignment.seed's range)
MAX_SEED = 2**63 - 1


def split_overrides(overrides: Sequence[str]) -> tuple[list[str], list[str]]:
    """(the run's overrides, the ``env.*`` ones): ``env.policy_step=0.02``, ``+env.x=…``."""
    run: list[str] = []
    env: list[str] = []
    for text in overrides:
        key = str(text).lstrip("+~").split("=", 1)[0]
        (env if key == "env" or key.startswith("env.") else run).append(str(text))
    return run, env


def compose(overrides: Sequence[str]) -> tuple[DictConfig, DictConfig]:
    """The run's config and the environment's settings (``env``) for these overrides, checked:
    raises ValueError with one paragraph per problem, naming the key."""
    from compliant_docking.config.store import load_config, load_env_config
    from compliant_docking.config.validate import (
        ConfigError,
        check,
        composition_problem,
        settings_problems,
    )

    run, env = split_overrides(overrides)
    problems: list[str] = []
    cfg = settings = None
    for what, load, given in (("run", load_config, run), ("env", load_env_config, env)):
        try:
            node = load(*given)
        except Exception as exc:  # Hydra's composition errors: unknown keys, wrong types
            problems.append(composition_problem(exc))
            continue
        if what == "run":
            cfg = node
            problems += check(node)
        else:
            settings = node.env
            problems += settings_problems(node, "env")
    if cfg is not None and cfg.target.name == "none":
        problems.append("the environment docks into a socket: target=none has none (use a socket target)")
    if problems:
        raise ConfigError(problems)
    assert cfg is not None and settings is not None
    return cfg, settings


class DockingEnv(gym.Env):
    """The docking task; build it with :func:`compliant_docking.env.make_env` or
    ``gymnasium.make("CompliantDocking-v0", overrides=[...])``.

    ``overrides``: as on the command line (``"robot=fr3"``, ``"controller.k=100"``,
    ``"env.policy_step=0.02"``); or ``cfg`` and ``settings``, already composed.
    """

    metadata: dict[str, Any] = {"render_modes": []}

    def __init__(
        self,
        overrides: Sequence[str] = (),
        *,
        cfg: DictConfig | None = None,
        settings: DictConfig | None = None,
        render_mode: str | None = None,
    ):
        from hydra.utils import get_class

        if render_mode is not None:
            raise ValueError(
                f"render_mode must be None (render=video writes a run's video), got {render_mode!r}"
            )
        if cfg is None or settings is None:
            cfg, settings = compose(overrides)
        self.cfg, self.settings = cfg, settings
        self.run_overrides = [o for o in split_overrides(overrides)[0] if not _is_seed(o)]
        self.dt = float(cfg.physics.timestep)
        self.policy_steps = round(float(settings.policy_step) / self.dt)
        if self.policy_steps < 1 or not math.isclose(
            self.policy_steps * self.dt, settings.policy_step, rel_tol=1e-9
        ):
            raise ValueError(
                f"env.policy_step must be a whole multiple of physics.timestep ({self.dt:g} s), "
                f"got {settings.policy_step:g} s"
            )
        nv = len(cfg.robot.max_torque)
        from compliant_docking.sim.scene import socket_pose
        from compliant_docking.sim.settings import sim_settings

        believed = socket_pose(sim_settings(cfg)).believed  # type: ignore[union-attr]  # target is a socket
        self.action_mode = make_action(
            settings.action,
            nv=nv,
            believed_rotation=believed.rotation,
            controller_class=get_class(cfg.controller._target_),
        )
        self.weights = R.Weights(
            **{k: float(settings.reward[k]) for k in ("distance", "force", "success", "diverged")}
        )
        self.budget = float(cfg.task.gate.peak_force_budget_N)
        self.names = observation_names(nv)
        self.observation_space = gym.spaces.Box(-np.inf, np.inf, shape=(len(self.names),), dtype=np.float32)
        self.action_space = gym.spaces.Box(-1.0, 1.0, shape=(self.action_mode.size,), dtype=np.float32)
        self.sim: Simulation | None = None
        self.seed_used: int | None = None
        self.episode_cfg: DictConfig | None = None
        self.episodes = 0
        self._done = True
        self._last_terms: dict[str, float] = {}
        self._warnings: list[str] = []  # MuJoCo's, during the episode (never MUJOCO_LOG.TXT)
        self._capture = contextlib.ExitStack()

    # ------------------------------------------------------------------ Gymnasium API
    def reset(self, *, seed: int | None = None, options: dict | None = None) -> tuple[np.ndarray, dict]:
        super().reset(seed=seed)
        # seeded: that draw; else the next seed from the generator reset(seed=…) seeded (so
        # the environments of a vector env, seeded s, s + 1, …, never share a draw)
        draw = int(seed) if seed is not None else int(self.np_random.integers(0, MAX_SEED))
        cfg = copy.deepcopy(self.cfg)
        cfg.task.misalignment.seed = draw
        if "lead_limit" in cfg.trajectory:  # the policy moves the reference itself
            cfg.trajectory.lead_limit = None
        self._capture.close()  # an episode left unfinished
        self._warnings = self._capture.enter_context(mjlog.captured())
        sim = prepare(cfg)
        self.action_mode.bind(sim)
        sim.start()
        self.sim, self.seed_used, self.episode_cfg = sim, draw, cfg
        socket, goal = sim.scene.socket, sim.waypoints.goal
        assert socket is not None and goal is not None  # compose() refused target=none
        self.observe = Observer(sim, socket.believed, goal.rotation)
        self.true_seat = socket.true.translation.copy()
        # the axial force of a wrench row: −f·axis (sim.telemetry.axial_force), as one product
        self.axial = -np.concatenate([sim.waypoints.axis / np.linalg.norm(sim.waypoints.axis), np.zeros(3)])
        self.telemetry_wrench = sim.telemetry.wrench
        obs = self.observe()
        self.start_distance = _distance(self.observe.tcp_position, self.true_seat)
        self.potential = R.potential(self.start_distance, self.start_distance, self.weights.distance)
        self.total = 0.0
        self._obs = obs
        self._done = False
        self.episodes += 1
        info = {"seed": draw, **socket.misalignment.record()}
        return obs, info

    def step(self, action: Any) -> tuple[np.ndarray, float, bool, bool, dict]:
        if self._done or self.sim is None:
            raise RuntimeError("the episode has ended (or not begun): call reset()")
        a = _components(action, self.action_mode.size)
        sim = self.sim
        first = sim.steps_done
        last = min(first + self.policy_steps, sim.n_steps)
        self.action_mode.apply(a, first, last)
        error: Diverged | None = None
        try:
            sim.advance(last - first)
        except Diverged as exc:
            error = exc
        if error is None:
            obs = self.observe()
            distance = _distance(self.observe.tcp_position, self.true_seat)
            after = R.potential(distance, self.start_distance, self.weights.distance)
        else:
            obs, after = self._obs, self.potential  # the state is not finite: no shaping
        done = sim.steps_done
        axial = self.telemetry_wrench[first:done].dot(self.axial)

        def reward_terms(success: bool) -> dict[str, float]:
            return R.terms(
                self.weights,
                potential_before=self.potential,
                potential_after=after,
                axial_force=axial,
                budget=self.budget,
                success=success,
                diverged=error is not None,
            )

        info: dict[str, Any] = {"t": done * self.dt}
        terminated = error is not None or sim.finished
        if terminated:  # the gate decides the last step's bonus: terms and return in the record
            metrics = self._finish(error, reward_terms)
            terms = self._last_terms
            info.update(metrics=metrics, is_success=bool(metrics.get("success")))
        else:
            terms = reward_terms(False)
        reward = float(sum(terms.values()))
        self.potential, self._obs = after, obs
        self.total += reward
        info["reward_terms"] = terms
        return obs, reward, terminated, False, info

    # ------------------------------------------------------------------ the episode's end
    def _finish(self, error: Diverged | None, reward_terms: Callable[[bool], dict[str, float]]) -> dict:
        """The run's record of the episode (and its run directory with ``env.record_dir``),
        with the last step's reward terms (their success bonus is the gate's) and the return."""
        from compliant_docking.run.runner import Episode, evaluate, execute

        self._done = True
        self._capture.close()
        sim, cfg = self.sim, self.episode_cfg
        assert sim is not None and cfg is not None

        def fields(record: dict) -> dict[str, Any]:
            self._last_terms = reward_terms(record.get("status") == "ok" and bool(record.get("success")))
            return {
                "env_return": self.total + sum(self._last_terms.values()),
                "env_policy_steps": math.ceil(sim.steps_done / self.policy_steps),
                "env_policy_step_s": float(self.settings.policy_step),
                "env_action": self.settings.action.kind.value,
            }

        record_dir = self.settings.record_dir
        if record_dir:
            episode = Episode(
                simulation=sim,
                error=error,
                overrides=[*self.run_overrides, f"task.misalignment.seed={self.seed_used}"],
                fields=fields,
                mujoco_warnings=self._warnings,
            )
            out = claim_directory(Path(record_dir), f"episode_{self.episodes:05d}_seed{self.seed_used}")
            written = execute(cfg, out, figures=False, echo=False, episode=episode)
            written["run_dir"] = str(out)
            return written
        record: dict[str, Any] = {"status": "failed", "error": None, "success": False}
        record.update(sim.scene.socket.misalignment.record())  # type: ignore[union-attr]
        if error is not None:
            record["error"] = str(error)
        else:
            record.update(evaluate(sim, None, figures=False))
        record.update(steps=sim.steps_done, sim_time_s=sim.steps_done * self.dt)
        record.update(fields(record), mujoco_warnings=len(self._warnings))
        return record

    def close(self) -> None:
        self._capture.close()
        super().close()


def claim_directory(root: Path, name: str) -> Path:
    """A new directory ``root/name`` (``name_2``, ``name_3``, … if taken: several
    environments may record into one folder), created here."""
    root.mkdir(parents=True, exist_ok=True)
    for n in range(1, 10_000):
        path = root / (name if n == 1 else f"{name}_{n}")
        try:
            path.mkdir()
        except FileExistsError:
            continue
        return path
    raise RuntimeError(f"no free directory name for {name} under {root}")


def _components(action, size: int) -> list[float]:
    """The action's components as floats clipped to [−1, 1]; refuses a wrong size or a
    non-finite value (Python floats: a handful of numbers, between cold-cache loops)."""
    try:
        values = np.asarray(action, dtype=np.float64).ravel().tolist()
    except (TypeError, ValueError):
        values = []
    out = []
    for x in values:
        if not -math.inf < x < math.inf:  # NaN fails the comparison too
            break
        out.append(1.0 if x > 1.0 else -1.0 if x < -1.0 else x)
    if len(out) != size or len(values) != size:
        raise ValueError(
            f"an action must be {size} finite numbers in [-1, 1] (beyond ±1 they are clipped), got {action!r}"
        )
    return out


def _distance(a: np.ndarray, b: np.ndarray) -> float:
    dx, dy, dz = (a - b).tolist()
    return math.sqrt(dx * dx + dy * dy + dz * dz)


def _is_seed(override: str) -> bool:
    return override.lstrip("+~").split("=", 1)[0] == "task.misalignment.seed"
