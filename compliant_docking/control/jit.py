"""Compiled step kernels: the one place that configures numba.

A controller's per-step algebra on 6×n matrices costs far more in Python and numpy call
overhead than in arithmetic (benchmarks/step_profile.py). The laws whose step is long
(se3_lie, hqp) therefore evaluate it in a kernel compiled by numba: one call per step.

Every kernel is compiled with the same options:

* ``cache=True``: the machine code is written next to the module (``__pycache__``, or
  numba's per-user cache when that is not writable) on first use and loaded by later
  processes, so a run or a sweep worker pays the compilation once per source change;
* IEEE arithmetic (no ``fastmath``): results differ from the numpy evaluation of the same
  formula only by the order of summation (round-off);
* Python's error model: a float division by zero raises ZeroDivisionError, as the
  Python code it replaces did.

numba is imported with the controller module that uses it, never by a run that does not
(the default impedance run does not).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TypeVar

import numba

F = TypeVar("F", bound=Callable)


def kernel(fn: F) -> F:
    """``fn`` compiled for the hot loop (nopython, cached, IEEE arithmetic)."""
    return numba.njit(cache=True, nogil=True)(fn)  # type: ignore[return-value]
