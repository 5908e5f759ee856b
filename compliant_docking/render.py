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

Encoding: H.264 (yuv420p, ``render.crf``) through PyAV, which ships its own FFmpeg; the
file is written under a temporary name and renamed. Offscreen OpenGL comes from the
backend chosen by compliant_docking/gl.py before mujoco was imported.
"""

from __future__ import annotations

import math
import os
import time
from dataclasses import dataclass
from pathlib import Path

import mujoco
import numpy as np

from compliant_docking import gl
from compliant_docking.telemetry import axial_force

VIDEO_FILE = "docking.mp4"
#: elevation of the close-up camera (below the horizon: looking down) [deg]
CLOSEUP_ELEVATION_DEG = -12.0
#: colours (RGB) of the overlay
STRIP_BG, TEXT, MUTED = (28, 30, 36), (235, 235, 240), (150, 152, 160)
PAST, FUTURE, CURSOR, BUDGET = (90, 170, 255), (85, 88, 98), (255, 210, 80), (230, 90, 80)


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
    record = {"video": None, "video_frames": None, "video_render_time_s": None, "video_error": None}
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
            sim.scene.model, tel.q[:n], float(tel.dt), Path(out_dir) / VIDEO_FILE, cfg.render,
            axial_force=axial_force(force, sim.waypoints.axis), force_norm=np.linalg.norm(force, axis=1),
            contacts=tel.contacts[:n], focus=_closeup_focus(sim, cfg),
            tool_body=int(sim.scene.tool_body), force_budget=budget, title=title)
        record.update(video=result.path.name, video_frames=result.frames,
                      video_render_time_s=result.render_time_s)
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
    return (f"\n  video: {record['video']} ({record['video_frames']} frames, "
            f"rendered in {record['video_render_time_s']:.1f} s)")


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
def write_video(model: mujoco.MjModel, q: np.ndarray, dt: float, path: Path, options, *,
                axial_force: np.ndarray, force_norm: np.ndarray, contacts: np.ndarray,
                focus: np.ndarray | None, tool_body: int, force_budget: float | None = None,
                title: str = "") -> VideoResult:
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
        raise RenderError(f"render.width × render.height = {options.width} × {options.height} "
                          f"is too small (at least 64 × {48 + strip_h} px)")
    if not gl.offscreen_possible():
        raise RenderError(gl.no_backend_message("no display and no headless backend"))

    started = time.perf_counter()
    steps = len(q)
    rows = frame_rows(steps, dt, fps, speed)
    strip = (_Strip(width, strip_h, np.arange(steps) * dt, axial_force, force_budget)
             if overlay else None)
    path = Path(path)
    tmp = path.with_name(f".{path.name}.tmp")
    views = None
    try:
        views = _Views(model, width, height - strip_h, options, focus=focus, tool_body=tool_body)
        labels = _Labels(width, height - strip_h, title, views.labels) if overlay else None
        with _Encoder(tmp, width, height, fps, int(options.crf)) as encoder:
            qpos = q[0].copy()
            for k in rows:
                if np.isfinite(q[k]).all():  # a diverged run: hold the last finite pose
                    qpos = q[k]
                image = views.render(qpos)
                if strip is not None:
                    labels.paint(image)
                    image = np.vstack([image, strip.draw(k * dt, float(axial_force[k]),
                                                         float(force_norm[k]), int(contacts[k]))])
                encoder.add(image)
        os.replace(tmp, path)
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise
    finally:
        if views is not None:
            views.close()
    return VideoResult(path=path, frames=len(rows), width=width, height=height, fps=fps,
                       render_time_s=time.perf_counter() - started)


class _Views:
    """One offscreen renderer, drawing the main view and (optionally) the close-up."""

    def __init__(self, model: mujoco.MjModel, width: int, height: int, options, *,
                 focus: np.ndarray | None, tool_body: int):
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
            raise RenderError(f"render.camera: the scene has no camera {camera!r} "
                              f"(cameras: {', '.join(names) or 'none'})")
        self.option = mujoco.MjvOption()
        self.option.sitegroup[:] = 0  # no site markers (seat, mouth, TCP) in the video
        self.labels = [camera]
        self.free = None
        if self.closeup:
            self.free = self._closeup_camera(focus, tool_body, float(options.closeup_distance))
            self.labels.append("close-up: socket mouth" if focus is not None else "close-up: tool")
        try:  # last: nothing after it may fail and leave the GL context open
            self.renderer = mujoco.Renderer(self.model, height, view_w)
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


def _font(size: int):
    from PIL import ImageFont

    try:
        return ImageFont.load_default(size=size)  # Pillow ≥ 10.1 with FreeType
    except TypeError:
        return ImageFont.load_default()


class _Labels:
    """The run's title and each view's name, drawn once and blended into every frame."""

    def __init__(self, width: int, height: int, title: str, labels: list[str]):
        from PIL import Image, ImageDraw

        size = max(10, height // 32)
        font = _font(size)
        layer = Image.new("RGBA", (width, min(height, int(3.2 * size) + 8)), (0, 0, 0, 0))
        draw = ImageDraw.Draw(layer)
        if title:
            draw.text((8, 6), title, fill=TEXT, font=font, stroke_width=2, stroke_fill=(0, 0, 0))
        view_w = width // len(labels)
        for i, label in enumerate(labels):
            draw.text((i * view_w + 8, 6 + 1.5 * size if i == 0 and title else 6), label,
                      fill=MUTED, font=font, stroke_width=2, stroke_fill=(0, 0, 0))
        rgba = np.asarray(layer).astype(np.float32)
        self.alpha = rgba[..., 3:] / 255.0
        self.premultiplied = rgba[..., :3] * self.alpha

    def paint(self, image: np.ndarray) -> None:
        """Blend the labels into the top rows of ``image`` (in place)."""
        top = image[: self.alpha.shape[0]]
        top[:] = (top * (1.0 - self.alpha) + self.premultiplied).astype(np.uint8)


class _Strip:
    """The overlay below the views: text on the left, the axial force over time on the right."""

    def __init__(self, width: int, height: int, t: np.ndarray, axial: np.ndarray,
                 budget: float | None):
        from PIL import Image, ImageDraw

        self.width, self.height = width, height
        self.size = max(10, height // 5)
        self.font, self.big = _font(self.size), _font(int(self.size * 1.35))
        self.text_w = min(width // 2, int(self.size * 11.5))
        x0, x1 = self.text_w + 6, width - 8
        y0, y1 = 6, height - self.size - 8
        self.x0, self.x1 = x0, x1
        self.t0, self.t1 = float(t[0]), float(t[-1]) if len(t) > 1 else float(t[0]) + 1.0
        finite = np.where(np.isfinite(axial), axial, 0.0)
        # the scale follows the data; the gate's budget is drawn when it is within 1.5× of it
        top = max(float(finite.max(initial=0.0)), 1.0)
        show_budget = budget is not None and 0.0 < budget <= 1.5 * top
        if show_budget:
            top = max(top, budget)
        top *= 1.1
        bottom = min(float(finite.min(initial=0.0)), 0.0) * 1.1
        span = top - bottom

        def y_of(value):
            return y1 - (np.asarray(value) - bottom) / span * (y1 - y0)

        base = Image.new("RGB", (width, height), STRIP_BG)
        draw = ImageDraw.Draw(base)
        draw.line([(x0, y_of(0.0)), (x1, y_of(0.0))], fill=(70, 72, 80))
        if show_budget:
            yb = float(y_of(budget))
            for xa in range(x0, x1, 10):
                draw.line([(xa, yb), (min(xa + 5, x1), yb)], fill=BUDGET)
            draw.text((x1 - 4, yb + 3), f"gate budget {budget:g} N", fill=BUDGET, font=self.font,
                      anchor="rt")
        draw.text((x0, height - 4), f"{self.t0:g} s", fill=MUTED, font=self.font, anchor="ld")
        draw.text((x1, height - 4), f"{self.t1:.3g} s", fill=MUTED, font=self.font, anchor="rd")
        draw.text(((x0 + x1) / 2, height - 4), "axial contact force [N] over time",
                  fill=MUTED, font=self.font, anchor="md")
        scale = f"{top / 1.1:.3g} N"
        draw.text((x0 + 2, y0), scale, fill=MUTED, font=self.font, anchor="lt")
        if budget is not None and not show_budget:  # on the left: the curve rises at the end
            left = x0 + 2 + draw.textlength(scale + "   ", font=self.font)
            draw.text((left, y0), f"gate budget {budget:g} N: off the scale", fill=BUDGET,
                      font=self.font, anchor="lt")
        past, future = base.copy(), base.copy()
        # one column per pixel: the range of the force over that column's time span
        columns = np.arange(x0, x1 + 1)
        edges = self.t0 + (columns - x0 + np.array([[-0.5], [0.5]])) / max(x1 - x0, 1) * (self.t1 - self.t0)
        idx = np.clip(np.searchsorted(t, edges), 0, len(t) - 1)
        for img, colour in ((past, PAST), (future, FUTURE)):
            d = ImageDraw.Draw(img)
            for c, lo, hi in zip(columns, idx[0], np.maximum(idx[1], idx[0] + 1)):
                seg = finite[lo:hi]
                d.line([(c, float(y_of(seg.min()))), (c, float(y_of(seg.max())))], fill=colour, width=2)
        self.past, self.future = np.asarray(past), np.asarray(future)

    def x_of(self, t: float) -> int:
        frac = (t - self.t0) / max(self.t1 - self.t0, 1e-12)
        return int(round(self.x0 + min(max(frac, 0.0), 1.0) * (self.x1 - self.x0)))

    def draw(self, t: float, axial: float, norm: float, contacts: int) -> np.ndarray:
        """The strip at time ``t`` [s] with the current axial force and ‖f‖ [N]."""
        from PIL import Image, ImageDraw

        xc = self.x_of(t)
        out = self.future.copy()
        out[:, :xc] = self.past[:, :xc]
        out[: self.height - self.size - 6, max(xc - 1, 0):xc + 1] = CURSOR
        img = Image.fromarray(out[:, : self.text_w])
        draw = ImageDraw.Draw(img)
        s = self.size
        draw.text((8, 4), f"t = {t:6.2f} s", fill=TEXT, font=self.big)
        axial_text = "n/a" if not math.isfinite(axial) else f"{axial:7.2f} N"
        norm_text = "n/a" if not math.isfinite(norm) else f"{norm:.2f} N"
        draw.text((8, 4 + 1.6 * s), f"axial force {axial_text}", fill=PAST, font=self.font)
        draw.text((8, 4 + 2.8 * s), f"|f| {norm_text} · contacts {contacts}", fill=MUTED, font=self.font)
        out[:, : self.text_w] = np.asarray(img)
        return out


class _Encoder:
    """H.264 (libx264, else MPEG-4 part 2) into an MP4 container, through PyAV."""

    def __init__(self, path: Path, width: int, height: int, fps: int, crf: int):
        import av

        self._av = av
        self.container = av.open(str(path), mode="w", format="mp4")
        if "libx264" in av.codecs_available:
            self.stream = self.container.add_stream(
                "libx264", rate=fps, options={"crf": str(int(crf)), "preset": "veryfast"})
        else:  # a PyAV build without x264
            self.stream = self.container.add_stream("mpeg4", rate=fps)
            self.stream.bit_rate = 4_000_000
        self.stream.width, self.stream.height = width, height
        self.stream.pix_fmt = "yuv420p"

    def add(self, rgb: np.ndarray) -> None:
        frame = self._av.VideoFrame.from_ndarray(np.ascontiguousarray(rgb), format="rgb24")
        for packet in self.stream.encode(frame):
            self.container.mux(packet)

    def __enter__(self) -> "_Encoder":
        return self

    def __exit__(self, exc_type, exc, tb) -> None:
        try:
            if exc_type is None:
                for packet in self.stream.encode():  # flush
                    self.container.mux(packet)
        finally:
            self.container.close()
