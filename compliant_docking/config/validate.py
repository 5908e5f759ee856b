"""Checking a composed config before anything runs: every key known, every number allowed.

:func:`validate` raises :class:`ConfigError` listing every problem of a composed config,
each one sentence naming the config key (``target.geometry.radial_clearance``, never a
class name), what is allowed and the value given:

- **unknown keys**: a key that no schema declares, added with ``+`` or ``++``
  (``+physcs.timestep=0.002``, ``++physics.timstep=0.002``, ``+controller.kk=1``), with
  the nearest valid keys (``difflib``). Plain overrides of unknown keys are already
  refused by Hydra at composition. Nodes of config groups without a schema (a folder
  under ``conf/``) and Hydra's own node are not checked here;
- **numbers**: every numeric leaf (list items included) must be finite and inside the
  range its schema field declares (:mod:`compliant_docking.config.ranges`);
- **relations** between settings: one value per joint in every per-joint list, unit
  quaternions, a non-zero stroke, the press within the settle time, the misalignment's
  fixed value or range, a plug that fits its socket (geometry checks of
  :mod:`compliant_docking.config.geometry`, named by their config keys), a start
  position without a target, HQP's torque margin (``robot.max_torque`` > 4 ·
  ``controller.eps_abs``);
- **files**: ``robot.mjcf`` and a ``tool.mjcf`` / ``target.mjcf`` fragment exist;
- **memory**: a run whose logs would not fit in the available memory
  (:func:`compliant_docking.config.memory.memory_problem`; the simulation repeats the
  check with its exact step count before it allocates anything).

The command line runs :func:`validate` before Hydra writes a run or sweep directory
(compliant_docking/run/guard.py, sweep/guard.py), and :func:`compliant_docking.run.runner.execute`
runs it first for runs started from Python. What needs the robot's model or the planner
(per-joint lists against the robot's joints, the planner's own refusals, the memory of a
run whose length follows from the planner) is checked by
:mod:`compliant_docking.run.preflight`, also before anything is written.
"""

from __future__ import annotations

import dataclasses
import difflib
import math
from collections.abc import Callable
from typing import Any

from omegaconf import DictConfig, ListConfig, OmegaConf

from compliant_docking import CONF_DIR
from compliant_docking.config import geometry, keyed, robustness
from compliant_docking.config.memory import memory_problem
from compliant_docking.config.ranges import field_range, problems, show
from compliant_docking.config.schemas import Config

#: lists with one value per joint (their length must agree)
PER_JOINT = ("robot.velocity_limits", "robot.torque_limits", "robot.max_torque", "robot.ik_guess")
#: quaternion settings, wxyz
QUATERNIONS = ("tool.mount_quat", "target.quat", "task.init_quat")
#: how far from 1 a quaternion's norm may be
UNIT_TOLERANCE = 1e-6


class ConfigError(ValueError):
    """A composed config that must not run; ``problems``: one sentence each."""

    def __init__(self, problems: list[str]) -> None:
        self.problems = list(problems)
        super().__init__(" ".join(self.problems))

    def report(self) -> str:
        """The problems as the command line prints them: a header, one paragraph each."""
        lines = ["compliant-docking: the configuration is refused; nothing was run or written."]
        lines += [f"  {p}" for p in self.problems]
        return "\n".join(lines)


def validate(cfg: DictConfig) -> None:
    """Raise :class:`ConfigError` when ``cfg`` (a composed config) must not run."""
    found = check(cfg)
    if found:
        raise ConfigError(found)


def check(cfg: DictConfig) -> list[str]:
    """Every problem of the composed config ``cfg`` (see the module docstring), [] if none."""
    found: list[str] = []
    groups = _group_names()
    top = {f.name for f in dataclasses.fields(Config)}
    for key in cfg:
        key = str(key)
        if key == "hydra" or (key not in top and key in groups):
            continue
        if key not in top:
            found += _unknown(cfg, key, sorted(top), where="")
            continue
        found += _walk(cfg, key, _choice(cfg, key))
    pair = _pair_problem(cfg)
    if pair:
        found.insert(0, pair)
    if found:
        return found
    found += _relations(cfg)
    if not found:
        problem = memory_problem(cfg)
        if problem:
            found.append(problem)
    return found


def settings_problems(cfg: DictConfig, key: str) -> list[str]:
    """Every problem of the node ``cfg[key]`` with its schema's ranges (unknown keys, NaN/inf,
    out of range), for settings composed outside a run's config (``env``)."""
    return _walk(cfg, key, _choice(cfg, key))


# --------------------------------------------------------------------------- keys and ranges
def _walk(parent: DictConfig, key: str, choice: str | None, prefix: str = "") -> list[str]:
    """The problems of the node ``parent[key]`` (full key ``prefix + key``)."""
    full = f"{prefix}{key}"
    try:
        node = parent._get_node(key)
        value = parent[key]
    except Exception as exc:  # an interpolation that does not resolve
        return [f"{full} cannot be resolved: {_first_line(exc)}."]
    schema = OmegaConf.get_type(node) if isinstance(node, DictConfig) else None
    if not (isinstance(value, DictConfig) and dataclasses.is_dataclass(schema)):
        return []
    fields = {f.name: f for f in dataclasses.fields(schema)}
    where = f" of {choice}" if choice else ""
    found: list[str] = []
    for sub in value:
        sub = str(sub)
        if sub not in fields:
            found += _unknown(value, sub, sorted(fields), where=where, prefix=f"{full}.")
            continue
        child = value._get_node(sub)
        if isinstance(child, DictConfig):
            found += _walk(value, sub, choice, prefix=f"{full}.")
            continue
        try:
            leaf = value[sub]
        except Exception as exc:
            found.append(f"{full}.{sub} cannot be resolved: {_first_line(exc)}.")
            continue
        if isinstance(leaf, ListConfig):
            leaf = OmegaConf.to_container(leaf, resolve=True)
        rng = field_range(fields[sub])
        if rng is not None:
            found += problems(f"{full}.{sub}", leaf, rng)
        elif isinstance(leaf, float) and not math.isfinite(leaf):
            found.append(f"{full}.{sub} must be a finite number; got {show(leaf)}.")
    return found


def _unknown(node: DictConfig, key: str, valid: list[str], *, where: str, prefix: str = "") -> list[str]:
    """``<prefix><key>`` is not a setting: name every leaf given under it and the nearest keys."""
    leaves = [f"{prefix}{leaf}" for leaf in _leaf_keys(node, key)]
    return [unknown_key(f"{prefix}{key}", valid, where=where, given=leaves, added=True)]


def unknown_key(
    key: str, valid: list[str], *, where: str = "", given: list[str] | None = None, added: bool = False
) -> str:
    """``controller.kk is not a setting of controller=impedance; did you mean controller.k?``

    ``valid``: the names allowed beside the last part of ``key``; ``given``: the leaf keys
    given under it (``physcs.timestep`` for the unknown ``physcs``); ``added``: it came
    with ``+``/``++`` (Hydra refuses plain overrides of unknown keys itself).
    """
    parent, _, name = key.rpartition(".")
    prefix = f"{parent}." if parent else ""
    leaves = given or [key]
    close = difflib.get_close_matches(name, valid, n=3, cutoff=0.6)
    if close:
        tail = leaves[0][len(key) :]
        hint = f"did you mean {' or '.join(f'{prefix}{c}{tail}' for c in close)}?"
    else:
        hint = f"the settings here are: {', '.join(f'{prefix}{v}' for v in valid)}."
    kind = "is not a setting" if len(leaves) == 1 else "are not settings"
    how = " (added with + or ++?)" if added else ""
    return f"{', '.join(leaves)} {kind}{where}{how}; {hint}"


def composition_problem(exc: BaseException) -> str:
    """A Hydra composition error as one paragraph naming the config key, never a class:
    an unknown key with the nearest valid ones, a value of the wrong type, a missing
    option with the available ones (Hydra's config search path left out)."""
    cause = exc.__cause__ if exc.__cause__ is not None else exc
    key = getattr(cause, "full_key", None)
    schema = getattr(cause, "object_type", None)
    if (
        key
        and type(cause).__name__ in ("ConfigAttributeError", "ConfigKeyError")
        and dataclasses.is_dataclass(schema)
    ):
        return unknown_key(key, [f.name for f in dataclasses.fields(schema)])
    if key:
        return f"{key}: {_first_line(cause).rstrip('.')}."
    if "Could not find 'schema/launcher/submitit_" in str(exc):  # registered only with the plugin
        from compliant_docking.extras import hint

        return hint("cluster", "Hydra's submitit launcher (hydra-submitit-launcher, submitit)")
    return one_paragraph(exc)


def one_paragraph(exc: BaseException) -> str:
    """An error's text as one paragraph: ``Could not find 'robot/ur5'; available options in
    'robot': fr3, iiwa14`` (without Hydra's config search path)."""
    text = str(exc).split("Config search path:")[0]
    parts: list[str] = []
    for line in (line.strip() for line in text.splitlines()):
        if not line:
            continue
        if parts and parts[-1].endswith(":"):
            parts[-1] += f" {line}"
        elif parts and ":" in parts[-1] and line.isidentifier():  # the next listed option
            parts[-1] += f", {line}"
        else:
            parts.append(line)
    return "; ".join(parts) or type(exc).__name__


def _leaf_keys(node: DictConfig, key: str) -> list[str]:
    """The dotted keys of the leaves under ``node[key]`` (``physcs.timestep``)."""
    child = node._get_node(key)
    if not isinstance(child, DictConfig):
        return [key]
    return [f"{key}.{leaf}" for sub in child for leaf in _leaf_keys(child, str(sub))]


def _choice(cfg: DictConfig, group: str) -> str | None:
    """``controller=impedance``: the option of ``group`` (for messages)."""
    node = cfg.get(group) if isinstance(cfg.get(group, None), DictConfig) else None
    name = node.get("name") if node is not None else None
    return f"{group}={name}" if isinstance(name, str) else None


def _group_names() -> set[str]:
    """The config groups (folders under conf/, not ``__pycache__``): their nodes are not
    schema settings."""
    if not CONF_DIR.is_dir():
        return set()
    return {p.name for p in CONF_DIR.iterdir() if p.is_dir() and not p.name.startswith(("_", "."))}


def _first_line(exc: BaseException) -> str:
    return (str(exc).strip().splitlines() or [type(exc).__name__])[0]


# --------------------------------------------------------------------------- relations
def _get(cfg: DictConfig, key: str) -> Any:
    value = OmegaConf.select(cfg, key, default=None)
    if isinstance(value, (DictConfig, ListConfig)):
        return OmegaConf.to_container(value, resolve=True)
    return value


def _relations(cfg: DictConfig) -> list[str]:
    """Checks that involve several settings (ranges are fine when this runs)."""
    found = per_joint_problems(cfg)
    for key in QUATERNIONS:
        quat = _get(cfg, key)
        if isinstance(quat, list) and len(quat) == 4 and (problem := quaternion_problem(key, quat)):
            found.append(problem)
    has_target = _get(cfg, "target.name") not in (None, "none")
    found += start_problems(_get(cfg, "task.stroke"), _get(cfg, "task.init_pos"), has_target)
    overshoot, pressing, settle = (
        _get(cfg, f"task.{k}") for k in ("insertion_overshoot", "press_duration", "settle_time")
    )
    press = press_problem(overshoot, pressing, settle, has_target)
    found += [press] if press else []
    found += misalignment_problems(_get(cfg, "task.misalignment"), has_target)
    found += robustness.problems(cfg)  # sensor, model_error, dynamics
    found += _interface(cfg, has_target)
    found += _files(cfg, has_target)
    eps_abs, max_torque = _get(cfg, "controller.eps_abs"), _get(cfg, "robot.max_torque")
    hqp = isinstance(eps_abs, (int, float)) and isinstance(max_torque, list)
    margin = torque_margin_problem(max_torque, eps_abs) if hqp else None
    return found + [margin] if margin else found


def torque_margin_problem(max_torque: list[float], eps_abs: float) -> str | None:
    """controller=hqp keeps 2·eps_abs inside the torque clip (control/hqp/controller.py):
    why ``robot.max_torque`` leaves no room for it, or None (the config check and the
    controller's constructor both ask this)."""
    if min(max_torque) > 4 * eps_abs:
        return None
    return (
        f"robot.max_torque must exceed 4·controller.eps_abs = {4 * eps_abs:g} N·m for every joint (the "
        f"QP keeps twice its accuracy inside the clip); got {show(max_torque)}."
    )


def start_problems(stroke: Any, init_pos: Any, has_target: bool) -> list[str]:
    """Why the task's start and goal cannot be placed: a zero ``task.stroke`` with a socket,
    no ``task.init_pos`` without one (the config check and sim/task.py ask)."""
    if has_target and isinstance(stroke, list) and not any(stroke):
        return [f"task.stroke must be a non-zero vector (start → seat) [m]; got {show(stroke)}."]
    if not has_target and init_pos is None:
        return [
            "task.init_pos must be set when there is no target (target=none): the start pose "
            "cannot be derived from a socket; got null."
        ]
    return []


def quaternion_problem(key: str, quat: list[float]) -> str | None:
    """Why the setting ``key`` is not a unit quaternion [w, x, y, z], or None (the config
    check and the scene's and task's constructions ask)."""
    if len(quat) == 4 and all(map(math.isfinite, quat)) and abs(math.hypot(*quat) - 1.0) <= UNIT_TOLERANCE:
        return None
    norm = f" (norm {math.hypot(*quat):.6g})" if len(quat) == 4 else ""
    return f"{key} must be a unit quaternion [w, x, y, z] (norm 1 within {UNIT_TOLERANCE:g}); got {show(quat)}{norm}."


def press_problem(overshoot: Any, press: Any, settle: Any, has_target: bool) -> str | None:
    """Why the press of ``task.insertion_overshoot`` over ``task.press_duration`` does not fit
    in ``task.settle_time``, or None (the config check and the planner's construction,
    compliant_docking/sim/simulate.py, both ask)."""
    if has_target and overshoot and press is not None and settle is not None and press > settle:
        return (
            f"task.press_duration must be at most task.settle_time = {settle:g} s (the press of "
            f"task.insertion_overshoot happens while the run settles); got {press:g}."
        )
    return None


def per_joint_problems(cfg: DictConfig, joints: int | None = None) -> list[str]:
    """The per-joint lists (the robot's, and controller=hqp's posture gains) without one value
    per joint: against the robot's ``joints`` when its model is known (run.preflight, the
    simulation), else against the other lists (the config alone)."""
    per_joint = PER_JOINT + ("controller.K_ji", "controller.D_ji")  # the last two: controller=hqp
    lengths = {key: len(v) for key in per_joint if isinstance(v := _get(cfg, key), list)}
    if joints is not None:
        return [
            f"{key} has {n} values; robot {_get(cfg, 'robot.name')} has {joints} joints: give one value per joint."
            for key, n in lengths.items()
            if n != joints
        ]
    if len(set(lengths.values())) < 2:
        return []
    counts = list(lengths.values())  # name the odd ones against the most common length
    joints = max(set(counts), key=counts.count)
    agree = ", ".join(k for k, n in lengths.items() if n == joints)
    return [
        f"{key} has {n} values; the other per-joint settings ({agree}) have {joints}: give one value per joint."
        for key, n in lengths.items()
        if n != joints
    ]


def _files(cfg: DictConfig, has_target: bool) -> list[str]:
    """The MJCF files the run loads (the robot's, a fragment given as ``tool.mjcf`` or
    ``target.mjcf``) exist: a missing file is refused before anything runs."""
    from compliant_docking import looked_in, resolve_path

    found = []
    for kind in ("robot", "tool", "target") if has_target else ("robot", "tool"):
        given = _get(cfg, f"{kind}.mjcf")
        if isinstance(given, str) and given and not resolve_path(given).is_file():
            found.append(
                f"{kind}.mjcf must name an MJCF file; there is no such file (looked for {looked_in(given)}; "
                f"got {given!r})."
            )
    return found


def misalignment_problems(settings: Any, has_target: bool) -> list[str]:
    """The relations of ``task.misalignment`` (a dict or DictConfig; its ranges are the
    schema's): a range [low, high], a value or its range, a socket to misalign (the config
    check, the draw and the scene ask)."""
    if settings is None or not hasattr(settings, "get"):
        return []
    found = []
    for name in ("x", "y", "yaw_deg", "tilt_deg"):
        key = f"task.misalignment.{name}"
        bounds = None if settings.get(f"{name}_range") is None else list(settings.get(f"{name}_range"))
        if bounds is not None and len(bounds) == 2 and bounds[0] > bounds[1]:
            found.append(f"{key}_range must be [low, high] with low <= high; got {show(bounds)}.")
        if bounds is not None and settings.get(name):
            found.append(
                f"{key} = {settings[name]:g} and {key}_range are both set: set one of them "
                "(the range draws the value)."
            )
        if not has_target and (settings.get(name) or bounds is not None):
            found.append(f"{key} needs a socket: target=none has none; got {show(settings.get(name))}.")
    return found


#: the parametric parts' own checks, by geometry schema
_PART_CHECKS: dict[type, Callable[[Any, str], list[str]]] = {
    geometry.PlugGeometry: geometry.plug_problems,
    geometry.SocketGeometry: geometry.socket_problems,
    keyed.KeyedPlugGeometry: keyed.keyed_plug_problems,
    keyed.KeyedSocketGeometry: keyed.keyed_socket_problems,
}
#: parametric (plug, socket) pairs that mate, with their fit check
_PAIR_CHECKS: dict[tuple[type, type], Callable[[Any, Any, str, str], list[str]]] = {
    (geometry.PlugGeometry, geometry.SocketGeometry): geometry.fit_problems,
    (keyed.KeyedPlugGeometry, keyed.KeyedSocketGeometry): keyed.keyed_fit_problems,
}


def _interface(cfg: DictConfig, has_target: bool) -> list[str]:
    """The parametric plug, socket and contact (fragment files are checked when loaded)."""
    found: list[str] = []
    parts: dict[str, type | None] = {}
    for kind in ("tool", "target"):
        node = cfg.get(kind)
        if kind == "target" and not has_target:
            continue
        if not isinstance(node, DictConfig) or node.get("mjcf") or "geometry" not in node:
            continue
        schema = OmegaConf.get_type(node, "geometry")
        parts[kind] = schema
        check_part = _PART_CHECKS.get(schema)  # type: ignore[arg-type]
        if check_part is not None:
            found += check_part(node.geometry, f"{kind}.geometry")
    if has_target and isinstance(cfg.get("target"), DictConfig) and "contact" in cfg.target:
        found += geometry.contact_problems(cfg.target.contact, "target.contact")
    if found or set(parts) != {"tool", "target"}:
        return found
    fit = _PAIR_CHECKS.get((parts["tool"], parts["target"]))  # type: ignore[arg-type]
    return fit(cfg.tool.geometry, cfg.target.geometry, "tool.geometry", "target.geometry") if fit else []


def _pair_problem(cfg: DictConfig) -> str | None:
    """Two parametric parts that do not mate (judged by their schemas alone, so it is
    said even when their values do not resolve: the cone socket's plug_radius follows
    ``tool.geometry.radius``, which a keyed plug does not have)."""
    tool, target = cfg.get("tool"), cfg.get("target")
    if not (isinstance(tool, DictConfig) and isinstance(target, DictConfig)):
        return None
    if target.get("name") == "none" or tool.get("mjcf") or target.get("mjcf"):
        return None
    if "geometry" not in tool or "geometry" not in target:
        return None
    pair = (OmegaConf.get_type(tool, "geometry"), OmegaConf.get_type(target, "geometry"))
    if pair in _PAIR_CHECKS:
        return None
    return (
        f"tool={tool.get('name')} and target={target.get('name')} are not a mating pair: use "
        "tool=cone_plug target=cone_socket or tool=keyed_plug target=keyed_socket, or a "
        "fragment file via tool.mjcf / target.mjcf."
    )
