"""Which OpenGL backend MuJoCo uses, decided once, before ``import mujoco``.

MuJoCo reads the environment variable ``MUJOCO_GL`` when it is first imported and binds
its offscreen GL context to that backend for the life of the process: ``glfw`` (the
default: a hidden window, needs a display), ``egl`` (headless, libEGL with Mesa or a GPU
driver) or ``osmesa`` (headless software rendering). ``compliant_docking/__init__.py``
calls :func:`configure` on import, which sets ``MUJOCO_GL`` when the user has not:

=====================================================  ==============================
situation (first match wins)                           MUJOCO_GL
=====================================================  ==============================
the user set ``MUJOCO_GL``                             kept as it is
``PYOPENGL_PLATFORM`` is ``egl`` or ``osmesa``         the same (they must agree)
not Linux (macOS, Windows)                             left unset (MuJoCo's default)
a display is reachable (X11 or Wayland)                left unset: GLFW, which the
                                                       interactive viewer needs too
no display, libEGL loads and an EGL vendor is listed   ``egl``
no display, libOSMesa loads                            ``osmesa``
no display, neither                                    left unset (a video is refused
                                                       with :func:`no_backend_message`)
=====================================================  ==============================

The decision does not look at the run's config: it is made before Hydra composes it,
and a display always means GLFW, so ``viewer=true`` works however it was set (command
line, preset, notebook). Child processes (sweep workers) inherit the variable; the
marker ``COMPLIANT_DOCKING_GL`` records that the value was ours, not the user's.

This module must stay cheap: it is imported by the package's ``__init__``. It probes the
libraries with ``ctypes`` only when it has to choose (no display, no user setting).
"""

from __future__ import annotations

import ctypes
import logging
import os
import sys
from collections.abc import Callable, Mapping, MutableMapping
from dataclasses import dataclass
from pathlib import Path

#: environment variable MuJoCo reads at import
MUJOCO_GL = "MUJOCO_GL"
#: set next to MUJOCO_GL when this module chose it (child processes then know it was ours)
MARKER = "COMPLIANT_DOCKING_GL"
#: Debian packages providing each headless backend
DEBIAN_PACKAGES = {"egl": "libegl1 libegl-mesa0 libgl1-mesa-dri libopengl0", "osmesa": "libosmesa6"}
#: where libglvnd looks for EGL vendor files when the environment does not say
EGL_VENDOR_DIRS = ("/etc/glvnd/egl_vendor.d", "/usr/share/glvnd/egl_vendor.d")


@dataclass(frozen=True)
class Decision:
    """The backend chosen and why.

    backend: the value MUJOCO_GL has (or gets); None when left unset (MuJoCo's default,
             GLFW on Linux).
    source:  "user" (the user's MUJOCO_GL), "auto" (chosen here), "default" (left unset).
    reason:  one line for messages.
    """

    backend: str | None
    source: str
    reason: str


def has_display(
    env: Mapping[str, str], platform: str = sys.platform, exists: Callable[[str], bool] = os.path.exists
) -> bool:
    """Whether a desktop display is reachable (never true on Linux without DISPLAY/WAYLAND_DISPLAY).

    A local X display ``:N`` counts only when its socket ``/tmp/.X11-unix/XN`` exists (a
    stale DISPLAY in a container or CI is common); a remote one (``host:N``, e.g. SSH
    forwarding) is taken at its word. Wayland: the socket under ``XDG_RUNTIME_DIR``.
    """
    if not platform.startswith("linux"):
        return True
    wayland = env.get("WAYLAND_DISPLAY", "")
    if wayland:
        path = wayland if wayland.startswith("/") else os.path.join(env.get("XDG_RUNTIME_DIR", ""), wayland)
        if exists(path):
            return True
    display = env.get("DISPLAY", "")
    if not display:
        return False
    host, _, rest = display.rpartition(":")
    if host not in ("", "unix"):
        return True  # remote X (e.g. ssh -X): cannot be checked cheaply
    number = rest.split(".")[0]
    return number.isdigit() and exists(f"/tmp/.X11-unix/X{number}")


def choose(
    env: Mapping[str, str],
    *,
    platform: str = sys.platform,
    display: bool | None = None,
    egl_loads: Callable[[], bool] | None = None,
    osmesa_loads: Callable[[], bool] | None = None,
) -> Decision:
    """The backend for this environment (a pure function of its arguments; see the table above).

    ``display``: whether a display is reachable (default: :func:`has_display`).
    ``egl_loads``/``osmesa_loads``: probes, called only when needed (default: ctypes).
    """
    user = env.get(MUJOCO_GL, "").strip().lower()
    if user:
        ours = env.get(MARKER, "").strip().lower() == user
        return Decision(
            user,
            "auto" if ours else "user",
            f"MUJOCO_GL={user}" + (" (chosen by compliant_docking)" if ours else " (set in the environment)"),
        )
    pyopengl = env.get("PYOPENGL_PLATFORM", "").strip().lower()
    if pyopengl in ("egl", "osmesa"):
        return Decision(pyopengl, "auto", f"MUJOCO_GL={pyopengl}, as PYOPENGL_PLATFORM={pyopengl}")
    if not platform.startswith("linux"):
        return Decision(None, "default", f"MUJOCO_GL unset: MuJoCo's default on {platform}")
    if has_display(env, platform) if display is None else display:
        return Decision(None, "default", "MUJOCO_GL unset: a display is present, MuJoCo uses GLFW")
    if (egl_loads or egl_available)():
        return Decision("egl", "auto", "MUJOCO_GL=egl: no display, libEGL loads")
    if (osmesa_loads or osmesa_available)():
        return Decision("osmesa", "auto", "MUJOCO_GL=osmesa: no display and no EGL, libOSMesa loads")
    return Decision(
        None,
        "default",
        "MUJOCO_GL unset: no display, and neither libEGL (with an EGL vendor) nor libOSMesa loads",
    )


def _loads(*names: str) -> bool:
    for name in names:
        try:
            ctypes.CDLL(name)
            return True
        except OSError:
            continue
    return False


def egl_available(env: Mapping[str, str] = os.environ) -> bool:
    """libEGL and a GL library load, and libglvnd has an EGL vendor (e.g. Mesa's 50_mesa.json).

    All three are needed: with MUJOCO_GL=egl and one missing, PyOpenGL fails inside
    ``import mujoco`` itself, which would break every run, not only videos.
    """
    if not _loads("libEGL.so.1", "libEGL.so") or not _loads("libOpenGL.so.0", "libGL.so.1"):
        return False
    if env.get("__EGL_VENDOR_LIBRARY_FILENAMES"):
        return True
    dirs = (
        env.get("__EGL_VENDOR_LIBRARY_DIRS", "").split(":")
        if env.get("__EGL_VENDOR_LIBRARY_DIRS")
        else EGL_VENDOR_DIRS
    )
    return any(Path(d).is_dir() and any(Path(d).glob("*.json")) for d in dirs)


def osmesa_available() -> bool:
    """libOSMesa (Debian: libosmesa6) loads."""
    return _loads("libOSMesa.so.8", "libOSMesa.so.6", "libOSMesa.so")


#: the decision of this process (set by :func:`configure`)
_decision: Decision | None = None
#: whether mujoco was already imported when :func:`configure` ran (then the choice came too late)
_too_late = False


def configure(environ: MutableMapping[str, str] = os.environ) -> Decision:
    """Decide the backend and export it as MUJOCO_GL; idempotent. Call before ``import mujoco``.

    When mujoco is already imported, nothing is changed (it has bound its backend
    already); :func:`no_backend_message` then says so.
    """
    global _decision, _too_late
    if _decision is not None:
        return _decision
    _too_late = "mujoco" in sys.modules
    decision = choose(environ)
    if not _too_late and decision.source == "auto" and decision.backend and not environ.get(MUJOCO_GL):
        environ[MUJOCO_GL] = decision.backend
        environ[MARKER] = decision.backend
    if decision.source == "user" and decision.backend and not _too_late:
        probe = {"egl": egl_available, "osmesa": osmesa_available}.get(decision.backend)
        if probe is not None and not probe():  # `import mujoco` is about to fail
            sys.stderr.write(
                f"warning: MUJOCO_GL={decision.backend} is set but its libraries do not load, "
                f"so `import mujoco` will fail; install them (Debian: apt-get install -y "
                f"{DEBIAN_PACKAGES[decision.backend]}) or unset MUJOCO_GL\n"
            )
    _decision = decision
    # PyOpenGL (imported by mujoco for EGL/OSMesa) logs at INFO that its optional C
    # accelerator is missing; a run's console is no place for that
    logging.getLogger("OpenGL.acceleratesupport").setLevel(logging.WARNING)
    return decision


def too_late() -> bool:
    """Whether mujoco was imported before the backend could be chosen."""
    return _too_late


def decision() -> Decision:
    """The decision of this process (made now if :func:`configure` has not run)."""
    return _decision or configure()


def offscreen_possible(env: Mapping[str, str] = os.environ) -> bool:
    """Whether an offscreen context can be hoped for (a backend is set, or a display for GLFW)."""
    d = decision()
    return d.backend is not None or has_display(env)


def no_backend_message(detail: str = "") -> str:
    """The one-paragraph explanation when offscreen rendering is impossible or failed."""
    d = decision()
    late = (
        " Note: mujoco was imported before compliant_docking, so the automatic choice "
        "came too late; import compliant_docking first or set MUJOCO_GL yourself."
        if _too_late
        else ""
    )
    what = f" ({detail})" if detail else ""
    return (
        f"render=video needs an OpenGL context for offscreen rendering and none could be "
        f"created here{what}; backend: {d.reason}. MuJoCo picks its backend from the "
        f"environment variable MUJOCO_GL when it is first imported: 'egl' (headless; Debian "
        f"packages {DEBIAN_PACKAGES['egl']}), 'osmesa' (headless software rendering; Debian "
        f"package {DEBIAN_PACKAGES['osmesa']}) or 'glfw' (needs a display). Install one "
        f"(`make gl` does it on Debian, as root: apt-get install -y "
        f"{DEBIAN_PACKAGES['egl']}), or set MUJOCO_GL=egl or MUJOCO_GL=osmesa before "
        f"starting Python. The simulation's results were kept.{late}"
    )


if __name__ == "__main__":
    # `python compliant_docking/gl.py [--quiet]` (the Makefile's `gl` target): exit status 0
    # when a headless backend (EGL or OSMesa) loads, or off Linux; 1 otherwise.
    # `--packages`: the Debian packages that provide EGL.
    if "--packages" in sys.argv[1:]:
        print(DEBIAN_PACKAGES["egl"])
        sys.exit(0)
    found = [name for name, probe in (("egl", egl_available), ("osmesa", osmesa_available)) if probe()]
    ok = bool(found) or not sys.platform.startswith("linux")
    if "--quiet" not in sys.argv[1:]:
        print(f"headless OpenGL for MuJoCo: {', '.join(found) or 'none'}; here: {choose(os.environ).reason}")
    sys.exit(0 if ok else 1)
