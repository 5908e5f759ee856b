"""``render=video``: an offscreen video of a run, ``docking.mp4`` in its run directory.

The video is made AFTER the simulation, by replaying the logged joint positions: for
each frame the logged step nearest to the frame's time is put into a fresh ``MjData``,
``mj_kinematics`` + ``mj_comPos`` + ``mj_camlight`` place the bodies and cameras, and
MuJoCo renders. The simulation loop pays nothing, and with ``render=none`` (the default)
this module is never imported.

Frame timing: the video has N = max(1, ⌊T·fps/speed + ½⌋) frames, T the simulated
time covered by the log (steps × dt); frame i shows the logged step nearest to
t_i = i·speed/fps, so the video lasts T/speed seconds (to the nearest frame).

Each frame (``render.width`` × ``render.height`` pixels, rounded down to even numbers):

- left: the scene's tracking camera (``render.camera``, aimed at the tool);
- right (``render.closeup``): a free camera ``render.closeup_distance`` from the socket
  mouth, seen from the same side (without a socket: a camera tracking the tool); the
  socket's own colour is semi-transparent, so the plug shows inside the bore;
- below (``render.overlay``): the time, the axial contact force (−f·axis, positive
  pressing into the socket, the convention of metrics.json), ‖f‖ and the contact
  count, beside the axial force over the whole run (grey ahead of the cursor, blue
  behind it, the gate's force budget dashed).

Encoding: H.264 (yuv420p, ``render.crf``) through PyAV, which ships its own FFmpeg (the
``video`` extra, with Pillow for the overlay); the file is written under a temporary name
and renamed. Offscreen OpenGL: the backend compliant_docking/gl.py chooses when the video
starts; the context is made from that backend's class (:func:`gl.context_class`), not by
``mujoco.Renderer``, whose backend was fixed when the run imported mujoco.
"""

from __future__ import annotations

import math
import os
import time
from dataclasses import dataclass
from pathlib import Path

import mujoco
import numpy as np

from compliant_docking import extras, gl
from compliant_docking.sim.telemetry import axial_force
from compliant_docking.viz.video_parts import Encoder, ForceStrip, Labels

VIDEO_FILE = "docking.mp4"
#: elevation of the close-up camera (below the horizon: looking down) [deg]
CLOSEUP_ELEVATION_DEG = -12.0


class RenderError(RuntimeError):
    """The video could not be made; the message is the one-paragraph reason."""


@dataclass(frozen=True)
class VideoResult:
    """What :func:`write_video` produced."""

    path: Path
    frames: int
    width: int
    height: int
    fps: int
    render_time_s: float  # wall time of replay, drawing and encoding [s]


# --------------------------------------------------------------------------- timing
def frame_count(sim_time: float, fps: float, speed: float = 1.0) -> int:
    """Frames of a video of ``sim_time`` simulated seconds: max(1, ⌊T·fps/speed + ½⌋)."""
    return max(1, int(math.floor(sim_time * fps / speed + 0.5)))


def frame_rows(steps: int, dt: float, fps: float, speed: float = 1.0) -> np.ndarray:
    """For each frame, the index of the logged step it shows (nearest to t_i = i·speed/fps)."""
    n = frame_count(steps * dt, fps, speed)
    times = np.arange(n) * (speed / fps)
    return np.minimum(np.rint(times / dt).astype(np.int64), steps - 1)


def even(n: int) -> int:
    """``n`` rounded down to an even number (H.264 4:2:0 needs even frame sizes)."""
    return int(n) - int(n) % 2


# --------------------------------------------------------------------------- entry points
def record_video(sim, cfg, out_dir: Path) -> dict:
    """Render ``docking.mp4`` for a finished (or diverged) simulation; never raises.

    Returns the metrics.json keys: ``video`` (file name, or null), ``video_frames``,
    ``video_render_time_s`` and ``video_error`` (null, or the one-paragraph reason). A
    failure here leaves the simulation's results untouched.
    """
    record: dict[str, object] = {
        "video": None,
        "video_frames": None,
        "video_render_time_s": None,
        "video_error": None,
    }
    try:
        if sim is None or sim.telemetry.count == 0:
            raise RenderError("no video: the run failed before it simulated anything")
        tel = sim.telemetry
        n = tel.count
        force = tel.wrench[:n, :3]
        budget = None
        if sim.scene.socket is not None and cfg.task.get("gate") is not None:
            budget = float(cfg.task.gate.peak_force_budget_N)
        title = " · ".join(str(cfg[g].name) for g in ("robot", "controller", "trajectory"))
        result = write_video(
            sim.scene.model,
            tel.q[:n],
            float(tel.dt),
            Path(out_dir) / VIDEO_FILE,
            cfg.render,
            axial_force=axial_force(force, sim.waypoints.axis),
            force_norm=np.linalg.norm(force, axis=1),
            contacts=tel.contacts[:n],
            focus=_closeup_focus(sim, cfg),
            tool_body=int(sim.scene.tool_body),
            force_budget=budget,
            title=title,
        )
        record.update(
            video=result.path.name, video_frames=result.frames, video_render_time_s=result.render_time_s
        )
    except RenderError as exc:
        record["video_error"] = str(exc)
    except Exception as exc:  # noqa: BLE001 - a video must never cost the run its results
        record["video_error"] = f"rendering failed: {type(exc).__name__}: {exc}".replace("\n", " ")
    return record


def summary_line(record: dict) -> str:
    """The summary's line about the video ('' when none was asked for)."""
    if "video_error" not in record:
        return ""
    if record["video_error"]:
        return f"\n  video: NOT WRITTEN — {record['video_error']}"
    return (
        f"\n  video: {record['video']} ({record['video_frames']} frames, "
        f"rendered in {record['video_render_time_s']:.1f} s)"
    )


def _closeup_focus(sim, cfg) -> np.ndarray | None:
    """World point the close-up looks at: the socket's ``mouth`` site, else its seat; None
    without a socket (the close-up then tracks the tool)."""
    socket = sim.scene.socket
    if socket is None:
        return None
    model = sim.scene.model
    prefix = cfg.target.get("prefix") or "target_"
    sid = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_SITE, f"{prefix}mouth")
    if sid >= 0:
        data = mujoco.MjData(model)
        mujoco.mj_kinematics(model, data)
        return data.site_xpos[sid].copy()
    return np.asarray(socket.true.translation, dtype=float).copy()


# --------------------------------------------------------------------------- the video
def write_video(
    model: mujoco.MjModel,
    q: np.ndarray,
    dt: float,
    path: Path,
    options,
    *,
    axial_force: np.ndarray,
    force_norm: np.ndarray,
    contacts: np.ndarray,
    focus: np.ndarray | None,
    tool_body: int,
    force_budget: float | None = None,
    title: str = "",
) -> VideoResult:
    """Render the logged joint positions ``q`` (one row per step of ``dt`` s) into ``path``.

    ``options``: the ``render`` config node (fps, speed, width, height, camera, closeup,
    closeup_distance, overlay, shadows, antialias, crf). ``axial_force`` [N],
    ``force_norm`` [N] and ``contacts`` are per step, for the overlay. ``focus``: the
    close-up's look-at point [m] (None: track ``tool_body``).
    """
    fps, speed = int(options.fps), float(options.speed)
    if fps <= 0 or not speed > 0.0 or not math.isfinite(speed):
        raise RenderError(f"render.fps ({options.fps}) and render.speed ({options.speed}) must be > 0")
    width, height = even(options.width), even(options.height)
    overlay = bool(options.overlay)
    strip_h = even(max(48, round(0.2 * height))) if overlay else 0
    if width < 64 or height - strip_h < 48:
        raise RenderError(
            f"render.width × render.height = {options.width} × {options.height} "
            f"is too small (at least 64 × {48 + strip_h} px)"
        )
    try:
        extras.require("video", "av", "PIL")
    except extras.MissingExtra as exc:
        raise RenderError(str(exc)) from None
    gl.configure()
    if not gl.offscreen_possible():
        raise RenderError(gl.no_backend_message("no display and no headless backend"))

    started = time.perf_counter()
    steps = len(q)
    rows = frame_rows(steps, dt, fps, speed)
    strip = ForceStrip(width, strip_h, np.arange(steps) * dt, axial_force, force_budget) if overlay else None
    path = Path(path)
    tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp")  # one per writer
    views = None
    try:
        views = _Views(model, width, height - strip_h, options, focus=focus, tool_body=tool_body)
        labels = Labels(width, height - strip_h, title, views.labels) if overlay else None
        with Encoder(tmp, width, height, fps, int(options.crf)) as encoder:
            qpos = q[0].copy()
            for k in rows:
                if np.isfinite(q[k]).all():  # a diverged run: hold the last finite pose
                    qpos = q[k]
                image = views.render(qpos)
                if labels is not None and strip is not None:
                    labels.paint(image)
                    image = np.vstack(
                        [
                            image,
                            strip.draw(k * dt, float(axial_force[k]), float(force_norm[k]), int(contacts[k])),
                        ]
                    )
                encoder.add(image)
        os.replace(tmp, path)
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise
    finally:
        if views is not None:
            views.close()
    return VideoResult(
        path=path,
        frames=len(rows),
        width=width,
        height=height,
        fps=fps,
        render_time_s=time.perf_counter() - started,
    )


class _Views:
    """One offscreen renderer, drawing the main view and (optionally) the close-up."""

    def __init__(
        self,
        model: mujoco.MjModel,
        width: int,
        height: int,
        options,
        *,
        focus: np.ndarray | None,
        tool_body: int,
    ):
        self.closeup = bool(options.closeup)
        view_w = width // 2 if self.closeup else width
        self.model = model.__copy__()  # the run's model is left as it was
        vis = self.model.vis
        vis.global_.offwidth = max(int(vis.global_.offwidth), view_w)
        vis.global_.offheight = max(int(vis.global_.offheight), height)
        vis.quality.offsamples = 4 if options.get("antialias", False) else 0
        if options.shadows:
            vis.quality.shadowsize = min(int(vis.quality.shadowsize), 2048)
        self.data = mujoco.MjData(self.model)
        camera = str(options.camera)
        self.camera_id = mujoco.mj_name2id(self.model, mujoco.mjtObj.mjOBJ_CAMERA, camera)
        if self.camera_id < 0:
            names = [self.model.camera(i).name for i in range(self.model.ncam)]
            raise RenderError(
                f"render.camera: the scene has no camera {camera!r} (cameras: {', '.join(names) or 'none'})"
            )
        self.option = mujoco.MjvOption()
        self.option.sitegroup[:] = 0  # no site markers (seat, mouth, TCP) in the video
        self.labels = [camera]
        self.free = None
        if self.closeup:
            self.free = self._closeup_camera(focus, tool_body, float(options.closeup_distance))
            self.labels.append("close-up: socket mouth" if focus is not None else "close-up: tool")
        try:  # last: nothing after it may fail and leave the GL context open
            self.renderer = Offscreen(self.model, height, view_w)
        except Exception as exc:  # the GL backend could not make a context
            raise RenderError(gl.no_backend_message(f"{type(exc).__name__}: {exc}".strip())) from None
        self.renderer.scene.flags[mujoco.mjtRndFlag.mjRND_SHADOW] = bool(options.shadows)

    def _closeup_camera(self, focus, tool_body: int, distance: float) -> mujoco.MjvCamera:
        """A free (or tool-tracking) camera seen from the main camera's side."""
        data = self.data
        mujoco.mj_kinematics(self.model, data)
        mujoco.mj_comPos(self.model, data)
        mujoco.mj_camlight(self.model, data)
        cam = mujoco.MjvCamera()
        target = focus if focus is not None else data.xpos[tool_body]
        look = np.asarray(target, float) - data.cam_xpos[self.camera_id]
        cam.azimuth = math.degrees(math.atan2(look[1], look[0]))
        cam.elevation = CLOSEUP_ELEVATION_DEG
        cam.distance = distance
        if focus is not None:
            cam.type = mujoco.mjtCamera.mjCAMERA_FREE
            cam.lookat[:] = focus
        else:
            cam.type = mujoco.mjtCamera.mjCAMERA_TRACKING
            cam.trackbodyid = tool_body
        return cam

    def render(self, qpos: np.ndarray) -> np.ndarray:
        """The view(s) of the arm at ``qpos``, side by side: (height, width, 3) uint8."""
        model, data, renderer = self.model, self.data, self.renderer
        data.qpos[:] = qpos
        mujoco.mj_kinematics(model, data)
        mujoco.mj_comPos(model, data)
        mujoco.mj_camlight(model, data)
        renderer.update_scene(data, camera=self.camera_id, scene_option=self.option)
        main = renderer.render()  # a fresh array each call
        if self.free is None:
            return main
        renderer.update_scene(data, camera=self.free, scene_option=self.option)
        return np.hstack([main, renderer.render()])

    def close(self) -> None:
        self.renderer.close()


class Offscreen:
    """What ``mujoco.Renderer`` does for an RGB image (the same MuJoCo calls), with the GL
    context made from the backend chosen now (:func:`gl.context_class`)."""

    def __init__(self, model: mujoco.MjModel, height: int, width: int):
        self.model = model
        self.context = gl.context_class()(width, height)
        self.mjr = None
        try:
            self.context.make_current()
            self.scene = mujoco.MjvScene(model=model, maxgeom=10000)
            self.mjr = mujoco.MjrContext(model, mujoco.mjtFontScale.mjFONTSCALE_150.value)
            mujoco.mjr_setBuffer(mujoco.mjtFramebuffer.mjFB_OFFSCREEN.value, self.mjr)
            self.mjr.readDepthMap = mujoco.mjtDepthMap.mjDEPTH_ZEROFAR
        except BaseException:
            self.close()
            raise
        self.rect = mujoco.MjrRect(0, 0, width, height)
        self.shape = (height, width, 3)

    def update_scene(self, data: mujoco.MjData, camera: int | mujoco.MjvCamera, scene_option) -> None:
        """The scene seen from ``camera`` (a camera id of the model, or a free camera)."""
        if not isinstance(camera, mujoco.MjvCamera):
            camera_id, camera = int(camera), mujoco.MjvCamera()
            camera.type = mujoco.mjtCamera.mjCAMERA_FIXED
            camera.fixedcamid = camera_id
        mujoco.mjv_updateScene(
            self.model, data, scene_option, None, camera, mujoco.mjtCatBit.mjCAT_ALL.value, self.scene
        )

    def render(self) -> np.ndarray:
        """The image of the last scene: (height, width, 3) uint8, a fresh array, top row first."""
        self.context.make_current()
        image = np.empty(self.shape, dtype=np.uint8)
        mujoco.mjr_render(self.rect, self.scene, self.mjr)
        mujoco.mjr_readPixels(image, None, self.rect, self.mjr)
        image[:] = np.flipud(image)  # OpenGL's rows start at the bottom
        return image

    def close(self) -> None:
        if self.mjr is not None:
            self.context.make_current()
            self.mjr.free()
            self.mjr = None
        if self.context is not None:
            self.context.free()
            self.context = None
