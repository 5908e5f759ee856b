"""The search space and the draws of a tuning study, written in Hydra's override grammar.

``hydra.sweeper.params`` and the sweep overrides of the command line become Optuna
distributions (the command line wins for a key given in both, as with Hydra's basic
sweeper):

=============================================  ==========================================
``interval(100, 1000)``                        float, uniform
``tag(log, interval(100, 1000))``              float, log-uniform
``int(interval(1, 8))``                        integer (``tag(log, …)``: log-uniform)
``range(0.5, 2.0, 0.25)`` / ``range(1, 9, 2)``   float / integer on a grid (stop excluded)
``choice(torque, velocity)`` or ``a,b,c``        categorical
=============================================  ==========================================

Plain values (``controller.m=2``) are fixed: every job gets them. ``hydra.sweeper.draws``
lists the draws every trial runs, as discrete sweeps whose combinations are the draws
(``task.misalignment.seed: range(4)`` → 4 draws). On the command line both are nested
(``hydra.sweeper.draws.task.misalignment.seed='range(8)'``), which means the same key.
"""

from __future__ import annotations

import re
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

from compliant_docking.run.rundir import flatten

_PLAIN = re.compile(r"[A-Za-z0-9_.\-+/]+")


class SearchSpaceError(ValueError):
    """A search space or a set of draws that cannot be used; the message names the key."""


@dataclass(frozen=True)
class Param:
    """One tuned config key: its Optuna distribution and how its override is written."""

    key: str  # the config key, e.g. controller.k (also Optuna's parameter name)
    prefix: str  # "", "+" or "++" as given
    distribution: Any  # optuna.distributions.BaseDistribution

    def override(self, value: Any) -> str:
        """``controller.k=512.3``: the override that sets this key to ``value``."""
        return f"{self.prefix}{self.key}={format_value(value)}"


def format_value(value: Any) -> str:
    """A sampled value as Hydra override text (strings quoted when they need it)."""
    if value is None:
        return "null"
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, (int, float)):
        return repr(value)
    text = str(value)
    if _PLAIN.fullmatch(text) and text.lower() not in ("null", "true", "false"):
        return text
    return "'" + text.replace("\\", "\\\\").replace("'", "\\'") + "'"


def _prefix(override) -> str:
    from hydra.core.override_parser.types import OverrideType

    return {OverrideType.ADD: "+", OverrideType.FORCE_ADD: "++"}.get(override.type, "")


def parse_space(params: Mapping[str, Any], arguments: Sequence[str]) -> tuple[list[Param], list[str]]:
    """The tuned parameters and the fixed overrides of ``hydra.sweeper.params`` and the
    command line's task overrides ``arguments`` (later wins for the same key).

    Raises :class:`SearchSpaceError` for a sweep that has no Optuna counterpart (``glob``,
    a shuffled or empty range, a choice of lists) or a search space with no parameter.
    """
    from hydra.core.override_parser.overrides_parser import OverridesParser

    lines = [f"{key}={value}" for key, value in flatten(params).items()] + list(arguments)
    tuned: dict[str, Param] = {}
    fixed: dict[str, str] = {}
    for override in OverridesParser.create().parse_overrides(lines):
        key = (
            override.key_or_group
            if override.package is None
            else f"{override.key_or_group}@{override.package}"
        )
        tuned.pop(key, None)
        fixed.pop(key, None)
        if override.is_sweep_override():
            tuned[key] = Param(key, _prefix(override), distribution(key, override))
        else:
            fixed[key] = (
                override.input_line or f"{override.get_key_element()}={override.get_value_element_as_str()}"
            )
    if not tuned:
        raise SearchSpaceError(
            "nothing to tune: give hydra.sweeper.params (a preset such as +experiment=tune) or a "
            "sweep on the command line, e.g. 'controller.k=tag(log,interval(100,1000))' (docs/tuning.md)"
        )
    return list(tuned.values()), list(fixed.values())


def distribution(key: str, override) -> Any:
    """The Optuna distribution of one sweep override (see the module docstring)."""
    from hydra.core.override_parser.types import ChoiceSweep, IntervalSweep, RangeSweep
    from optuna.distributions import CategoricalDistribution, FloatDistribution, IntDistribution

    value = override.value()
    log = "log" in getattr(value, "tags", set())
    if isinstance(value, IntervalSweep):
        low, high = value.start, value.end
        if low is None or high is None or not low < high:
            raise SearchSpaceError(f"{key}: interval({low}, {high}) needs low < high")
        if log and low <= 0:
            raise SearchSpaceError(f"{key}: tag(log, interval(...)) needs a positive lower bound, got {low}")
        if isinstance(low, int) and isinstance(high, int):
            return IntDistribution(low, high, log=log)
        return FloatDistribution(float(low), float(high), log=log)
    if isinstance(value, RangeSweep):
        grid = list(override.sweep_iterator())
        if value.shuffle or not grid or log:
            raise SearchSpaceError(f"{key}: range() must be non-empty, without shuffle() or tag(log, ...)")
        start, step = grid[0], value.step
        if all(isinstance(v, int) for v in grid) and isinstance(step, int):
            return IntDistribution(start, grid[-1], step=step)
        if len(grid) == 1:
            return FloatDistribution(float(start), float(start))
        return FloatDistribution(float(start), float(grid[-1]), step=float(step))
    if isinstance(value, ChoiceSweep):
        choices: list[Any] = list(value.list)
        if value.shuffle or not choices:
            raise SearchSpaceError(f"{key}: choice() must be non-empty and without shuffle()")
        if any(isinstance(c, (list, dict)) for c in choices):
            raise SearchSpaceError(f"{key}: choices must be plain values (numbers, strings, true/false)")
        return CategoricalDistribution(choices)
    raise SearchSpaceError(
        f"{override.input_line or key}: not a search space; use interval(), "
        "tag(log, interval()), int(interval()), range() or choice() (docs/tuning.md)"
    )


def expand_draws(draws: Mapping[str, Any], tuned: Sequence[Param]) -> list[list[str]]:
    """The overrides of each draw: the combinations of ``hydra.sweeper.draws`` (one empty
    draw when there are none). Raises :class:`SearchSpaceError` for a key that is tuned too."""
    from hydra.core.override_parser.overrides_parser import OverridesParser

    from compliant_docking.config.hydra_adapter import split_sweep

    draws = flatten(draws)
    if not draws:
        return [[]]
    lines = [f"{key}={value}" for key, value in draws.items()]
    overrides = OverridesParser.create().parse_overrides(lines)
    clash = sorted({o.key_or_group for o in overrides} & {p.key for p in tuned})
    if clash:
        raise SearchSpaceError(
            f"hydra.sweeper.draws: {', '.join(clash)} is tuned as well; a key is one or the other"
        )
    try:
        combinations = split_sweep(overrides)
    except Exception as exc:  # an interval in draws: no finite list of draws
        raise SearchSpaceError(
            f"hydra.sweeper.draws: {exc}; draws are lists (a,b,c) or range(), e.g. task.misalignment.seed: range(4)"
        ) from None
    return combinations
