"""``viewer=true``: watch one run live in MuJoCo's interactive viewer, paced to real time.

The viewer is MuJoCo's passive viewer (``mujoco.viewer.launch_passive``): a desktop
window in its own thread, showing the simulation's own ``MjData``. The loop calls
:class:`RealTimeViewer` after every step (``Simulation.run(on_step=…)``); about every
1/60 s of simulated time it hands the state to the window (``sync``) and sleeps until
the wall clock has caught up with the simulated time. Closing the window lets the run
finish at full speed; the window closes by itself when the run ends.

Refused (:func:`check_allowed`, a ``ValueError`` naming the reason, recorded like any
bad value) in a sweep (Hydra's runtime mode is MULTIRUN: jobs run in worker processes,
in parallel) and without a display. Mouse perturbations in the window (double-click a
body, Ctrl + drag) push the arm for real: they are part of the physics and of the
results.

The window needs GLFW; compliant_docking/gl.py, whose choice the viewer makes when it
opens, keeps GLFW whenever a display is present, so the offscreen video
(``render=video``) and the viewer can be used together.
"""

from __future__ import annotations

import os
import sys
import time
from collections.abc import Callable, Mapping

from compliant_docking import gl

#: simulated time between two hand-overs of the state to the window [s]
FRAME_PERIOD = 1.0 / 60.0


def refusal(
    *, multirun: bool, env: Mapping[str, str] = os.environ, platform: str = sys.platform
) -> str | None:
    """Why ``viewer=true`` cannot be honoured here, or None when it can (a pure function)."""
    if multirun:
        return (
            "viewer=true is refused in a sweep (-m): the jobs run in parallel worker "
            "processes and a window per job cannot be paced to real time; run the one "
            "configuration you want to watch without -m"
        )
    if not gl.has_display(env, platform):
        return (
            "viewer=true needs a desktop display and none is reachable here (DISPLAY and "
            "WAYLAND_DISPLAY are unset or point to no running server); use render=video "
            "for an offscreen video instead (docking.mp4 in the run directory)"
        )
    return None


def hydra_multirun() -> bool:
    """Whether this job runs under Hydra in MULTIRUN mode (False outside Hydra)."""
    try:
        from hydra.core.hydra_config import HydraConfig
        from hydra.types import RunMode

        return HydraConfig.get().mode == RunMode.MULTIRUN
    except ValueError:  # HydraConfig not set: a script, a notebook, a test
        return False


def check_allowed() -> None:
    """Raise ``ValueError`` with the reason when the viewer cannot be opened here."""
    reason = refusal(multirun=hydra_multirun())
    if reason:
        raise ValueError(reason)


class RealTimeViewer:
    """A per-step callback showing ``sim`` in MuJoCo's passive viewer at real time.

    ``launch``, ``clock`` and ``sleep`` are injectable for tests (defaults: the passive
    viewer, ``time.perf_counter`` [s], ``time.sleep`` [s]).
    """

    def __init__(
        self,
        sim,
        *,
        launch: Callable | None = None,
        clock: Callable[[], float] = time.perf_counter,
        sleep: Callable[[float], None] = time.sleep,
    ):
        gl.configure()  # before mujoco.viewer, in case nothing imported mujoco yet
        if launch is None:
            import mujoco.viewer

            launch = mujoco.viewer.launch_passive
        self.model, self.data = sim.scene.model, sim.data
        self.dt = float(self.model.opt.timestep)
        self.sim = sim  # its last step (Simulation.end − 1) moves on while a reference is held
        self.every = max(1, round(FRAME_PERIOD / self.dt))
        self.clock, self.sleep = clock, sleep
        self.handle = launch(self.model, self.data, show_left_ui=False, show_right_ui=False)
        self._point_camera()
        self.start: float | None = None  # wall time of t = 0, set at the first step
        self.open = True

    def _point_camera(self) -> None:
        """Start from the scene's tracking camera, if the viewer exposes its camera."""
        try:
            import mujoco

            cam_id = mujoco.mj_name2id(self.model, mujoco.mjtObj.mjOBJ_CAMERA, "track_cam")
            if cam_id >= 0:
                with self.handle.lock():
                    self.handle.cam.type = mujoco.mjtCamera.mjCAMERA_FIXED
                    self.handle.cam.fixedcamid = cam_id
        except Exception:  # noqa: BLE001 - a camera preference is not worth failing a run
            pass

    def __call__(self, k: int) -> None:
        """After step k: every ``every`` steps (and at the last), sync and wait for the clock."""
        last = k == self.sim.end - 1
        if not self.open or (k % self.every and not last):
            return
        if self.start is None:  # wall time at which the simulated time was 0
            self.start = self.clock() - (k + 1) * self.dt
        if not self.handle.is_running():  # the user closed the window: finish at full speed
            self.open = False
            return
        self.handle.sync()
        ahead = self.start + (k + 1) * self.dt - self.clock()
        if ahead > 0.0:
            self.sleep(ahead)
        if last:
            self.close()

    def close(self) -> None:
        if self.open:
            self.open = False
            self.handle.close()
