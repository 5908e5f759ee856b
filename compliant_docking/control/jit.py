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

An unusable cache entry is compiled again, and said: a data file that cannot be read
(truncated, corrupt: numba would raise at every run until ``__pycache__`` is deleted), an
index that cannot be read, or a data file that holds another function's machine code or
another signature (numba would run it) is reported on stderr in one line, the entry is
dropped (numba's ``Cache.flush``) and the kernel compiles as on first use; a cache that
cannot be written is reported and the run goes on with the compiled code.

numba offers no public API for any of this: :func:`_checked_cache` is the one place that
uses its private cache objects, and raises a clear error when they change
(tests/control/test_jit.py fails first; numba is pinned below 0.70 in pyproject.toml).

Every run imports numba: every controller calls compiled laws (the friction feed-forward
and the integral action of control/base.py, the apparent-inertia floor's refresh, and the
HQP and SE(3) steps), each loaded or compiled when its controller is built.
"""

from __future__ import annotations

import hashlib
import sys
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
    _checked_cache(dispatcher)
    return dispatcher


def _checked_cache(dispatcher: Any) -> None:
    """Stamp the kernel's cache with :data:`SOURCES_DIGEST` and check every entry it loads
    (the module doc). The only code that touches numba's private cache objects."""
    try:
        cache = dispatcher._cache
        cache_file = cache._cache_file
        stamp = cache_file._source_stamp
        load, save, flush = cache.load_overload, cache.save_overload, cache.flush
    except AttributeError as exc:
        raise RuntimeError(
            f"numba {numba.__version__} changed the private cache objects compliant_docking/control/"
            f"jit.py relies on ({exc}); install numba < 0.70 (pyproject.toml) or update jit.py"
        ) from None
    # numba's index keeps (source stamp, overloads) and discards the overloads when the stored
    # stamp differs from this one: the digest joins the defining file's (mtime, size)
    cache_file._source_stamp = (stamp, SOURCES_DIGEST)
    name = f"{dispatcher.py_func.__module__}.{dispatcher.py_func.__qualname__}"

    def load_overload(sig, target_context):
        try:
            found = load(sig, target_context)
        except Exception as exc:  # a truncated or corrupt data or index file
            why = f"{type(exc).__name__}: {str(exc).strip() or 'unreadable'}"
        else:
            why = _foreign(found, dispatcher.py_func, sig)
            if why is None:
                return found  # a usable entry, or none (numba compiles)
        _say(f"the cached machine code of {name} is unusable ({why}); compiling it again")
        try:
            flush()  # an empty index: the entry compiled now replaces the bad one
        except Exception:
            pass  # an unwritable cache: reported when the new entry cannot be saved
        return None

    def save_overload(sig, data):
        try:
            save(sig, data)
        except Exception as exc:  # the run goes on with the code compiled in memory
            _say(f"could not cache the machine code of {name} ({type(exc).__name__}: {exc})")

    cache.load_overload = load_overload
    cache.save_overload = save_overload


def _foreign(found: Any, py_func: Callable, sig: Any) -> str | None:
    """Why a loaded compile result is not ``py_func``'s for ``sig`` (another function's data
    file, or another signature's), or None when it is (or nothing was loaded)."""
    if found is None:
        return None
    qualname = getattr(getattr(found, "fndesc", None), "qualname", None)
    if qualname != py_func.__qualname__:
        return f"it holds the code of {qualname}"
    args = tuple(getattr(getattr(found, "signature", None), "args", ()))
    if args != tuple(getattr(sig, "args", sig)):
        return f"it was compiled for the argument types {args}"
    return None


def _say(message: str) -> None:
    print(f"numba: {message}", file=sys.stderr, flush=True)
