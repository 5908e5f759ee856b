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

A stale cache is refused: numba checks only the modification time and size of the file
that defines a kernel, not of the files whose compiled functions the kernel calls (lie's
log3, :mod:`~.kernel_blocks`, …). Each kernel's cache entry is therefore stamped with
:data:`SOURCES_DIGEST` as well, a hash of every module of this package
(``compliant_docking/control``): an edit to any of them recompiles every kernel at its next
use. A kernel may call compiled functions of this package only.

numba is imported with the controller module that uses it, never by a run that does not
(the default impedance run does not).
"""

from __future__ import annotations

import hashlib
from collections.abc import Callable
from pathlib import Path
from typing import Any, TypeVar

import numba

F = TypeVar("F", bound=Callable)

CONTROL_DIR = Path(__file__).resolve().parent


def sources_digest(root: Path = CONTROL_DIR) -> str:
    """A hash of the names and contents of every ``*.py`` below ``root``."""
    digest = hashlib.sha256()
    for path in sorted(root.rglob("*.py")):
        digest.update(path.relative_to(root).as_posix().encode())
        digest.update(path.read_bytes())
    return digest.hexdigest()[:16]


#: the stamp every kernel's cache entry carries besides numba's own (see the module doc)
SOURCES_DIGEST = sources_digest()


def kernel(fn: F) -> F:
    """``fn`` compiled for the hot loop (nopython, cached, IEEE arithmetic)."""
    dispatcher: Any = numba.njit(cache=True, nogil=True)(fn)
    # numba's index keeps (source stamp, overloads) and discards the overloads when the stored
    # stamp differs from this one: the digest joins the defining file's (mtime, size)
    cache_file = dispatcher._cache._cache_file
    cache_file._source_stamp = (cache_file._source_stamp, SOURCES_DIGEST)
    return dispatcher
