"""Which OpenGL backend MuJoCo's offscreen rendering uses, chosen when rendering starts.

MuJoCo reads the environment variable ``MUJOCO_GL`` when it is first imported and binds
``mujoco.GLContext`` (and so ``mujoco.Renderer``) to that backend for the life of the
process: ``glfw`` (the default: a hidden window, needs a display), ``egl`` (headless,
libEGL with Mesa or a GPU driver) or ``osmesa`` (headless software rendering). A run has
imported mujoco long before its video is rendered, and with ``MUJOCO_GL`` unset on a
headless machine MuJoCo 4.0's ``Renderer`` then fails (``mjr_makeContext``: no OpenGL
platform library loaded) and leaves the process unable to make any context.

So nothing is decided at import. :func:`configure`, called by the video renderer
(``viz/render.py``) and the viewer when they start, chooses the backend:

=====================================================  ==============================
situation (first match wins)                           backend
=====================================================  ==============================
the user set ``MUJOCO_GL``                             kept as it is
``PYOPENGL_PLATFORM`` is ``egl`` or ``osmesa``         the same (they must agree)
not Linux (macOS, Windows)                             MuJoCo's default
a display is reachable (X11 or Wayland)                GLFW, which the interactive
                                                       viewer needs too
no display, libEGL loads and an EGL vendor is listed   ``egl``
no display, libOSMesa loads                            ``osmesa``
no display, neither                                    none (a video is refused
                                                       with :func:`no_backend_message`)
=====================================================  ==============================

and :func:`context_class` gives that backend's context class from MuJoCo's own backend
modules (``mujoco.egl``, ``mujoco.osmesa``, ``mujoco.glfw``), whether or not mujoco was
imported before: the video renderer makes its context from it. When mujoco is not imported
yet, :func:`configure` also exports ``MUJOCO_GL`` (MUJOCO_GL must be set before
``import mujoco`` to take effect there), so ``mujoco.Renderer`` in the same process, and
child processes, agree; the marker ``COMPLIANT_DOCKING_GL`` records that the value was
ours, not the user's.

The decision does not look at the run's config, and a display always means GLFW, so
``viewer=true`` and ``render=video`` work together. It probes the libraries with
``ctypes`` only when it has to choose (no display, no user setting).
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


def configure(environ: MutableMapping[str, str] = os.environ) -> Decision:
    """Choose the backend (once per process) and, while mujoco is not imported yet, export
    it as MUJOCO_GL. Called where rendering starts (video, viewer), never at import."""
    global _decision
    if _decision is not None:
        return _decision
    decision = choose(environ)
    if "mujoco" not in sys.modules and decision.source == "auto" and decision.backend:
        environ[MUJOCO_GL] = decision.backend
        environ[MARKER] = decision.backend
    if decision.source == "user" and decision.backend:
        probe = {"egl": egl_available, "osmesa": osmesa_available}.get(decision.backend)
        if probe is not None and not probe():  # no context can be made
            sys.stderr.write(
                f"warning: MUJOCO_GL={decision.backend} is set but its libraries do not load; "
                f"install them (Debian: apt-get install -y {DEBIAN_PACKAGES[decision.backend]}) "
                f"or unset MUJOCO_GL\n"
            )
    _decision = decision
    # PyOpenGL (imported by mujoco's EGL/OSMesa backends) logs at INFO that its optional C
    # accelerator is missing; a run's console is no place for that
    logging.getLogger("OpenGL.acceleratesupport").setLevel(logging.WARNING)
    return decision


def decision() -> Decision:
    """The decision of this process (made now if :func:`configure` has not run)."""
    return _decision or configure()


def context_class() -> type:
    """The GL context class of the chosen backend (``mujoco.egl.GLContext``, …): what a
    renderer makes its context with, whatever MuJoCo bound at its own import."""
    backend = decision().backend
    if backend == "egl":
        from mujoco.egl import GLContext
    elif backend == "osmesa":
        from mujoco.osmesa import GLContext
    elif backend in (None, "glfw") and sys.platform.startswith("linux"):
        from mujoco.glfw import GLContext
    else:  # another platform's backend (cgl, wgl, …): MuJoCo's own choice
        from mujoco import GLContext
    return GLContext


def offscreen_possible(env: Mapping[str, str] = os.environ) -> bool:
    """Whether an offscreen context can be hoped for (a backend is set, or a display for GLFW)."""
    d = decision()
    return d.backend is not None or has_display(env)


def no_backend_message(detail: str = "") -> str:
    """The one-paragraph explanation when offscreen rendering is impossible or failed."""
    d = decision()
    what = f" ({detail})" if detail else ""
    return (
        f"render=video needs an OpenGL context for offscreen rendering and none could be "
        f"created here{what}; backend: {d.reason}. Without a display the backend is 'egl' or "
        f"'osmesa' when their libraries load, or the one the environment variable MUJOCO_GL "
        f"names: 'egl' (headless; Debian "
        f"packages {DEBIAN_PACKAGES['egl']}), 'osmesa' (headless software rendering; Debian "
        f"package {DEBIAN_PACKAGES['osmesa']}) or 'glfw' (needs a display). Install one "
        f"(`make gl` does it on Debian, as root: apt-get install -y "
        f"{DEBIAN_PACKAGES['egl']}), or set MUJOCO_GL=egl or MUJOCO_GL=osmesa. The "
        f"simulation's results were kept."
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
