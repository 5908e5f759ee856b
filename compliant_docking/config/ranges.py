"""Allowed values of the numeric settings, declared on the schema fields themselves.

Every numeric field of a schema (:mod:`.schemas`, :mod:`.geometry`) is declared with one
of the helpers below instead of a bare ``MISSING``::

    k: float = at_least(0.0, unit="N/m")        # translational stiffness
    timestep: float = within(0.0, 0.01, low_open=True, unit="s")
    K0: List[float] = positive(size=6)           # one range for every value of the list
    solref: tuple[float, float] = each(positive(unit="s"), positive())  # a range per value

The helpers return ``dataclasses.field(default=MISSING, metadata={RANGE: Range(...)})``:
the value itself still lives only in the YAML under ``conf/`` (a range is not a default).
:func:`compliant_docking.config.validate.validate` checks every numeric leaf of a
composed config against its field's range, and ``tests/config/test_validate.py`` derives
its NaN / inf / out-of-range cases from the same declarations, so a new numeric key
without a range fails the tests until it declares one.

This module imports nothing of the package: the geometry dataclasses read it too.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import Any

from omegaconf import MISSING

#: the key of a field's :class:`Range` in ``dataclasses.Field.metadata``
RANGE = "compliant_docking.range"


@dataclass(frozen=True)
class Range:
    """The allowed values of one number (or of every number of a list setting).

    ``low``/``high``: bounds, included unless ``low_open``/``high_open``; ``integer``: whole
    numbers only; ``choices``: the only allowed values (then the bounds are ignored);
    ``size``: a list setting's number of values (None: a scalar, or a list whose length is
    checked elsewhere, e.g. one value per joint); ``items``: one range per position of a
    fixed-length list (``each(...)``); ``unit``: shown in messages.
    """

    low: float = -math.inf
    high: float = math.inf
    low_open: bool = False
    high_open: bool = False
    integer: bool = False
    choices: tuple[float, ...] | None = None
    size: int | None = None
    items: tuple[Range, ...] | None = None
    unit: str = ""

    def contains(self, value: float) -> bool:
        """Whether the finite number ``value`` is allowed."""
        if self.integer and value != int(value):
            return False
        if self.choices is not None:
            return value in self.choices
        above = value > self.low if self.low_open else value >= self.low
        below = value < self.high if self.high_open else value <= self.high
        return above and below

    def describe(self) -> str:
        """``"in (0, 0.01] s"``, ``"> 0 N/m"``, ``"one of 1, 3, 4, 6"``, ``"any finite number"``."""
        unit = f" {self.unit}" if self.unit else ""
        kind = "an integer" if self.integer else "a finite number"
        if self.choices is not None:
            return "one of " + ", ".join(_num(c) for c in self.choices)
        low, high = math.isfinite(self.low), math.isfinite(self.high)
        if low and high:
            text = (
                f"{kind} in {'(' if self.low_open else '['}{_num(self.low)}, "
                f"{_num(self.high)}{')' if self.high_open else ']'}{unit}"
            )
        elif low:
            text = f"{kind} {'>' if self.low_open else '>='} {_num(self.low)}{unit}"
        elif high:
            text = f"{kind} {'<' if self.high_open else '<='} {_num(self.high)}{unit}"
        else:
            text = f"{kind} [{self.unit}]" if self.unit else kind
        return text

    def outside(self) -> float | None:
        """A finite value outside the range (None when every finite number is allowed);
        for the generated tests."""
        if self.choices is not None:
            return max(self.choices) + 1.0
        if math.isfinite(self.low):
            return self.low if self.low_open else self.low - max(1.0, abs(self.low))
        if math.isfinite(self.high):
            return self.high if self.high_open else self.high + max(1.0, abs(self.high))
        return None

    def at(self, index: int) -> Range:
        """The range of the value at ``index`` of a list setting."""
        return self.items[index] if self.items is not None and index < len(self.items) else self


def _num(x: float) -> str:
    return f"{x:g}"


def declared(rng: Range) -> Any:
    """A schema field with this range and no value (the value is in conf/)."""
    return dataclasses.field(default=MISSING, metadata={RANGE: rng})


def within(
    low: float,
    high: float,
    *,
    low_open: bool = False,
    high_open: bool = False,
    unit: str = "",
    size: int | None = None,
    integer: bool = False,
) -> Any:
    """``low <= value <= high`` (``low_open``/``high_open``: strict)."""
    return declared(
        Range(
            low=low, high=high, low_open=low_open, high_open=high_open, integer=integer, size=size, unit=unit
        )
    )


def inside(low: float, high: float, *, unit: str = "", size: int | None = None) -> Any:
    """``low < value < high`` (the open interval)."""
    return within(low, high, low_open=True, high_open=True, unit=unit, size=size)


def positive(*, at_most: float = math.inf, unit: str = "", size: int | None = None) -> Any:
    """``0 < value <= at_most``."""
    return within(0.0, at_most, low_open=True, unit=unit, size=size)


def at_least(low: float, *, unit: str = "", size: int | None = None, integer: bool = False) -> Any:
    """``value >= low``."""
    return within(low, math.inf, unit=unit, size=size, integer=integer)


def above(low: float, *, unit: str = "", size: int | None = None) -> Any:
    """``value > low``."""
    return within(low, math.inf, low_open=True, unit=unit, size=size)


def finite(*, unit: str = "", size: int | None = None) -> Any:
    """Any finite number (the only documented limit; NaN and inf are refused)."""
    return within(-math.inf, math.inf, unit=unit, size=size)


def integers(low: float, high: float = math.inf) -> Any:
    """A whole number in ``[low, high]``."""
    return within(low, high, integer=True)


def one_of(*choices: float) -> Any:
    """One of the listed numbers."""
    return declared(Range(integer=True, choices=tuple(choices)))


def each(*fields: Any) -> Any:
    """A fixed-length list with one range per position: ``each(positive(), at_least(1))``."""
    items = tuple(range_of(f) for f in fields)
    return declared(Range(size=len(items), items=items))


def range_of(spec: Any) -> Range:
    """The :class:`Range` of a field made by these helpers (a ``dataclasses.Field``)."""
    return spec.metadata[RANGE]


def field_range(field: dataclasses.Field) -> Range | None:
    """The declared range of a schema field, or None (not a numeric setting)."""
    return field.metadata.get(RANGE)


# --------------------------------------------------------------------------- checking
def problems(key: str, value: Any, rng: Range) -> list[str]:
    """Why ``value`` (a number, or a list of numbers for a list setting) is not allowed at
    the config key ``key``: one sentence per problem, naming the key, the allowed range and
    the value; [] when it is allowed. None (an optional setting left null) is allowed."""
    if value is None:
        return []
    if isinstance(value, (list, tuple)):
        found = []
        if rng.size is not None and len(value) != rng.size:
            found.append(f"{key} must have {rng.size} values; got {len(value)}: {show(value)}.")
        for i, item in enumerate(value):
            problem = _scalar_problem(f"{key}[{i}]", item, rng.at(i))
            if problem:
                found.append(problem)
        return found
    problem = _scalar_problem(key, value, rng)
    return [problem] if problem else []


def _scalar_problem(key: str, value: Any, rng: Range) -> str | None:
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        return f"{key} must be {rng.describe()}; got {value!r}."
    if not math.isfinite(value) or not rng.contains(value):
        return f"{key} must be {rng.describe()}; got {show(value)}."
    return None


def show(value: Any) -> str:
    """A value as the command line would write it: ``nan``, ``inf``, ``[0.0, 0.0, -0.18]``."""
    if isinstance(value, (list, tuple)):
        return "[" + ", ".join(show(v) for v in value) + "]"
    if isinstance(value, float):
        return repr(value) if math.isfinite(value) else str(value)
    return repr(value) if isinstance(value, str) else str(value)


def require(schema: type, group: str, **values: Any) -> None:
    """The check a constructor makes of its settings: each value of ``values`` against the
    range its field of the dataclass ``schema`` declares, named ``<group>.<field>``; raises
    one ValueError with :func:`problems`' sentences, word for word the config check's
    refusal of the same value (:func:`compliant_docking.config.validate.check`). The
    schema's range is the one rule; constructors never write their own copy::

        require(HQPConfig, "controller", K0=K0, dt_p=dt_p)

    numpy values are compared as the Python numbers and lists they hold."""
    declared = {f.name: field_range(f) for f in dataclasses.fields(schema)}
    found: list[str] = []
    for name, value in values.items():
        rng = declared[name]
        if rng is None:
            raise TypeError(f"{schema.__name__}.{name} declares no range")
        found += problems(f"{group}.{name}", value.tolist() if hasattr(value, "tolist") else value, rng)
    if found:
        raise ValueError(" ".join(found))


def object_problems(obj: Any, where: str) -> list[str]:
    """Every declared range of the dataclass instance ``obj``, its fields named
    ``<where>.<field>`` (a config key, or the class name for programmatic use)."""
    found: list[str] = []
    for f in dataclasses.fields(obj):
        rng = field_range(f)
        if rng is not None:
            found += problems(f"{where}.{f.name}", getattr(obj, f.name), rng)
    return found
