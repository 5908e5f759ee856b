"""Whether a run's logs fit in memory: the estimate from the config (its length and time
step), checked before anything runs (:func:`compliant_docking.config.validate.check`),
with the exact step count when the planner gives the length
(:mod:`compliant_docking.run.preflight`, and the simulation itself)."""

from __future__ import annotations

import math
import os
from typing import Any

from omegaconf import DictConfig, OmegaConf

#: memory a run needs per simulated step [bytes]: measured 1.2 kB (peak RSS of the default
#: docking with impedance and with hqp, figures included, 20 000 → 80 000 steps:
#: 320 → 393 MB), with room for controllers that log more per-step columns
BYTES_PER_STEP = 2000


def _get(cfg: DictConfig, key: str) -> Any:
    return OmegaConf.select(cfg, key, default=None)  # a number (or None) at every key read here


def run_length(cfg: DictConfig) -> tuple[float, str] | None:
    """The run's simulated time and where it comes from, when the config alone gives it:
    ``task.duration``, or the planner's ``trajectory.duration`` + ``task.settle_time``
    (other planners' durations follow from the scene: the simulation checks them), + the
    longest a held reference may extend it (``task.max_hold``, with ``trajectory.lead_limit``)."""
    duration = _get(cfg, "task.duration")
    if duration is not None:
        return float(duration), f"task.duration = {duration:g} s"
    planned, settle = _get(cfg, "trajectory.duration"), _get(cfg, "task.settle_time")
    if isinstance(planned, (int, float)) and isinstance(settle, (int, float)):
        hold = _get(cfg, "task.max_hold") if _get(cfg, "trajectory.lead_limit") is not None else None
        if isinstance(hold, (int, float)) and hold > 0:
            return float(planned + settle + hold), (
                f"trajectory.duration + task.settle_time + task.max_hold = {planned:g} + {settle:g} + {hold:g} s"
            )
        return float(planned + settle), (
            f"trajectory.duration + task.settle_time = {planned:g} + {settle:g} s"
        )
    return None


def memory_problem(cfg: DictConfig, n_steps: int | None = None, available: int | None = None) -> str | None:
    """Why the run of ``cfg`` cannot keep its logs in memory, or None.

    ``n_steps``: the exact step count (the simulation knows it); by default the one
    :func:`run_length` gives, if any. ``available``: bytes of memory (default:
    :func:`available_memory`).
    """
    timestep = _get(cfg, "physics.timestep")
    length = run_length(cfg)
    steps: float
    if n_steps is not None:
        steps = float(n_steps)
    elif length is None or not isinstance(timestep, (int, float)) or not timestep > 0:
        return None
    else:
        steps = length[0] / timestep
    needed = steps * BYTES_PER_STEP
    available = available_memory() if available is None else available
    if available is None or needed <= available:
        return None
    source = length[1] if length is not None else "the planned trajectory + task.settle_time"
    return (
        f"the run would simulate {steps:.3g} steps ({source} at physics.timestep = "
        f"{timestep:g} s) and its logs would need about {_bytes(needed)} of memory, more than "
        f"the {_bytes(available)} available: shorten the run (task.duration, or the trajectory "
        "and task.settle_time) or raise physics.timestep."
    )


def available_memory() -> int | None:
    """Bytes of memory available to a new allocation (Linux: MemAvailable), or None."""
    try:
        with open("/proc/meminfo", encoding="ascii") as meminfo:
            for line in meminfo:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * 1024
    except (OSError, ValueError, IndexError):
        pass
    try:
        return os.sysconf("SC_AVPHYS_PAGES") * os.sysconf("SC_PAGE_SIZE")
    except (ValueError, OSError, AttributeError):
        return None


def _bytes(n: float) -> str:
    """``1.5e12`` → ``"1.5 TB"``."""
    units = ("B", "kB", "MB", "GB", "TB", "PB", "EB")
    power = min(int(math.log10(n) // 3), len(units) - 1) if n >= 1 and math.isfinite(n) else 0
    return f"{n / 1000**power:.3g} {units[power]}" if math.isfinite(n) else "unbounded"
