"""Typed schemas of the robustness groups: what the controller does not know.

- ``sensor`` (compliant_docking/sim/sensor.py): the wrist force/torque sensor and the joint
  encoders as the controller reads them: noise, bias, a first-order low-pass filter, a
  sample rate and a transport delay. ``sensor=ideal`` (the default) is MuJoCo's exact
  wrench, one step old, and exact joint states.
- ``model_error`` (compliant_docking/sim/model_error.py): the controller's Pinocchio model
  and its friction assumption differ from the plant (tool mass, centre of mass and
  inertia, link masses, joint friction, damping, armature). ``model_error=none``: exact.
- ``dynamics`` (compliant_docking/sim/dynamics.py): the plant's plug–socket contact
  (friction, solref, solimp) drawn per seed. ``dynamics=nominal``: the target's contact.

Each drawn quantity has a ``<name>_range`` [low, high] (uniform); a range and a value
other than the neutral one may not both be set. Every group's ``seed`` is by default
``task.misalignment.seed``, so one seed gives one draw of everything, the same for every
controller (common random numbers); each quantity has its own random stream.

:func:`problems` holds the relations a range cannot express (low ≤ high, a sample period
that is a whole number of time steps); :mod:`compliant_docking.config.validate` calls it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, List, Optional

from omegaconf import MISSING

from compliant_docking.config.ranges import at_least, inside, integers, positive, show, within


@dataclass
class SensorConfig:
    """The controller's sensors (compliant_docking/sim/sensor.py). Zero noise and bias, no
    filter, ``rate_hz`` null and no delay: the ideal sensor (bit for bit the exact wrench)."""

    name: str = MISSING
    rate_hz: Optional[float] = positive(
        unit="Hz"
    )  # F/T samples per second, held between samples; null: every step
    cutoff_hz: Optional[float] = positive(unit="Hz")  # first-order low-pass corner; null: no filter
    delay_s: float = within(0.0, 1.0, unit="s")  # transport delay beyond the one-step-old reading [s]
    force_noise_N: List[float] = at_least(0.0, unit="N", size=3)  # white noise std per axis, per sample [N]
    moment_noise_Nm: List[float] = at_least(0.0, unit="N·m", size=3)  # [N·m]
    force_bias_N: List[float] = within(
        -1000.0, 1000.0, unit="N", size=3
    )  # fixed offset, world axes at the TCP [N]
    moment_bias_Nm: List[float] = within(-100.0, 100.0, unit="N·m", size=3)  # fixed offset [N·m]
    force_bias_std_N: float = at_least(0.0, unit="N")  # per-seed offset per axis ~ N(0, std) [N]
    moment_bias_std_Nm: float = at_least(0.0, unit="N·m")  # [N·m]
    joint_position_noise_rad: float = at_least(0.0, unit="rad")  # encoder noise std [rad]
    joint_velocity_noise_rad_s: float = at_least(0.0, unit="rad/s")  # velocity noise std [rad/s]
    seed: int = integers(0, 2**63 - 1)  # noise and bias draws (default: task.misalignment.seed)


#: the scalar model errors and their neutral (exact) values
MODEL_ERROR_SCALARS = (
    ("tool_mass_scale", 1.0),
    ("tool_inertia_scale", 1.0),
    ("link_mass_scale", 1.0),
    ("friction_scale", 1.0),
    ("damping_scale", 1.0),
    ("armature_scale", 1.0),
)


@dataclass
class ModelErrorConfig:
    """The controller's model against the plant (compliant_docking/sim/model_error.py):
    believed = scale × true (offset: believed = true + offset). Neutral values: exact."""

    name: str = MISSING
    tool_mass_scale: float = inside(0.0, 10.0)  # believed / true tool mass
    tool_mass_scale_range: Optional[List[float]] = inside(0.0, 10.0, size=2)
    tool_inertia_scale: float = inside(0.0, 10.0)  # believed / true tool rotational inertia (about its CoM)
    tool_inertia_scale_range: Optional[List[float]] = inside(0.0, 10.0, size=2)
    tool_com_offset_m: List[float] = within(
        -0.5, 0.5, unit="m", size=3
    )  # believed − true CoM, tool (dock) axes [m]
    tool_com_offset_m_range: Optional[List[float]] = within(
        -0.5, 0.5, unit="m", size=2
    )  # each axis drawn [m]
    link_mass_scale: float = inside(0.0, 10.0)  # believed / true mass and inertia of every arm link
    link_mass_scale_range: Optional[List[float]] = inside(0.0, 10.0, size=2)
    friction_scale: float = within(0.0, 10.0)  # assumed / plant joint friction (frictionloss)
    friction_scale_range: Optional[List[float]] = within(0.0, 10.0, size=2)
    damping_scale: float = within(0.0, 10.0)  # assumed / plant joint damping
    damping_scale_range: Optional[List[float]] = within(0.0, 10.0, size=2)
    armature_scale: float = within(0.0, 10.0)  # believed / true rotor inertia (armature)
    armature_scale_range: Optional[List[float]] = within(0.0, 10.0, size=2)
    seed: int = integers(0, 2**63 - 1)  # the draws (default: task.misalignment.seed)


@dataclass
class DynamicsConfig:
    """The plant's plug–socket contact drawn per seed (compliant_docking/sim/dynamics.py);
    every range null: the target's ``contact`` as configured."""

    name: str = MISSING
    friction_range: Optional[List[float]] = within(0.0, 5.0, size=2)  # sliding friction coefficient
    timeconst_range: Optional[List[float]] = positive(at_most=1.0, unit="s", size=2)  # solref[0] [s]
    dampratio_range: Optional[List[float]] = positive(at_most=10.0, size=2)  # solref[1]
    width_range: Optional[List[float]] = positive(at_most=0.1, unit="m", size=2)  # solimp[2] [m]
    seed: int = integers(0, 2**63 - 1)  # the draws (default: task.misalignment.seed)


def sample_period(rate_hz: float, dt: float) -> int | None:
    """The steps between two F/T samples at ``rate_hz`` in a loop of time step ``dt`` [s];
    None unless that is a whole number of steps (at least one)."""
    period = 1.0 / (rate_hz * dt)
    if period < 1.0 - 1e-9 or abs(period - round(period)) > 1e-6 * period:
        return None
    return int(round(period))


def _ranges(node: Any, group: str) -> list[str]:
    found = []
    for key in node:
        bounds = node.get(key)
        if not str(key).endswith("_range") or bounds is None or len(bounds) != 2:
            continue
        if not all(isinstance(b, (int, float)) and math.isfinite(b) for b in bounds):
            continue  # the range check names it
        if bounds[0] > bounds[1]:
            found.append(f"{group}.{key} must be [low, high] with low <= high; got {show(list(bounds))}.")
    return found


def problems(cfg: Any) -> list[str]:
    """The relations of the robustness groups that their ranges cannot express."""
    found: list[str] = []
    error = cfg.get("model_error")
    if error is not None:
        found += _ranges(error, "model_error")
        for key, neutral in MODEL_ERROR_SCALARS:
            if error.get(f"{key}_range") is not None and error.get(key) != neutral:
                found.append(
                    f"model_error.{key} = {show(error.get(key))} and model_error.{key}_range are both set: "
                    f"set one of them (the range draws the value; {key} stays {neutral:g})."
                )
        com = error.get("tool_com_offset_m")
        if error.get("tool_com_offset_m_range") is not None and com is not None and any(com):
            found.append(
                f"model_error.tool_com_offset_m = {show(list(com))} and model_error.tool_com_offset_m_range are "
                "both set: set one of them (the range draws each axis; the offset stays [0, 0, 0])."
            )
    dynamics = cfg.get("dynamics")
    if dynamics is not None:
        found += _ranges(dynamics, "dynamics")
        drawn = [
            f"dynamics.{k}" for k in dynamics if str(k).endswith("_range") and dynamics.get(k) is not None
        ]
        target = cfg.get("target")
        if drawn and (target is None or target.get("name") == "none"):
            found.append(
                f"{', '.join(drawn)} draw the plug–socket contact and need a socket; target=none has "
                "none (use dynamics=nominal)."
            )
    sensor, physics = cfg.get("sensor"), cfg.get("physics")
    if sensor is None or physics is None:
        return found
    dt = physics.get("timestep")
    if not isinstance(dt, (int, float)) or dt <= 0:
        return found
    rate, cutoff, delay = sensor.get("rate_hz"), sensor.get("cutoff_hz"), sensor.get("delay_s")
    if isinstance(rate, (int, float)) and rate > 0:
        if sample_period(rate, dt) is None:
            found.append(
                f"sensor.rate_hz must make the sample period a whole number of physics.timestep = {dt:g} s "
                f"(at most {1.0 / dt:g} Hz, e.g. {1.0 / dt:g}, {0.5 / dt:g}, {0.25 / dt:g}); got {show(rate)}."
            )
    if isinstance(cutoff, (int, float)) and cutoff > 0.5 / dt:
        found.append(
            f"sensor.cutoff_hz must be at most the Nyquist frequency of the loop, 0.5 / physics.timestep = "
            f"{0.5 / dt:g} Hz; got {show(cutoff)}."
        )
    if isinstance(delay, (int, float)) and delay > 0:
        steps = delay / dt
        if abs(steps - round(steps)) > 1e-6 * max(steps, 1.0):
            found.append(
                f"sensor.delay_s must be a whole number of physics.timestep = {dt:g} s; got {show(delay)} "
                f"({steps:.4g} steps)."
            )
    return found
