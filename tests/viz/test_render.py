"""render=video (compliant_docking/viz/render.py) and the OpenGL backend choice (gl.py)."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from compliant_docking import gl
from compliant_docking.run.runner import execute
from compliant_docking.viz.render import VIDEO_FILE, frame_count, frame_rows
from tests.helpers import REPO_ROOT, make_cfg

#: a short run at a low resolution: 1.5 s at 10 frames per second → 15 frames
SHORT = (
    "task.duration=1.5",
    "task.progress=false",
    "render=video",
    "render.fps=10",
    "render.width=320",
    "render.height=240",
)


def _need_offscreen_gl() -> None:
    """Skip where no offscreen OpenGL exists (a developer's machine); CI must have it."""
    if not gl.offscreen_possible() and not os.environ.get("CI"):
        pytest.skip(gl.no_backend_message())


def _decode(path: Path) -> list[np.ndarray]:
    import av

    with av.open(str(path)) as container:
        return [frame.to_ndarray(format="rgb24") for frame in container.decode(video=0)]


def _orange(image: np.ndarray) -> float:
    """Share of pixels in the iiwa14's orange (lit or shaded): red high, green mid, blue low."""
    r, g, b = (image[..., i].astype(int) for i in range(3))
    return float(np.mean((r > 120) & (g > 25) & (g < 0.75 * r) & (b < 0.35 * r)))


# --------------------------------------------------------------------------- the video
def test_short_run_video_decodes_with_the_expected_frames_and_shows_the_arm(tmp_path):
    _need_offscreen_gl()
    record = execute(make_cfg(*SHORT), tmp_path, figures=False, echo=False)
    assert record["video_error"] is None, record["video_error"]
    assert record["status"] == "incomplete"  # 1.5 s of a 15 s trajectory: the simulation's verdict
    video = tmp_path / VIDEO_FILE
    assert record["video"] == VIDEO_FILE and video.is_file()
    assert not list(tmp_path.glob(".*.tmp")), "temporary files left behind"
    assert video.stat().st_mtime <= (tmp_path / "metrics.json").stat().st_mtime

    frames = _decode(video)
    # frames = max(1, ⌊duration · fps / speed + ½⌋) = ⌊1.5 · 10 + ½⌋ = 15
    assert len(frames) == record["video_frames"] == 15
    assert frames[0].shape == (240, 320, 3)
    strip = max(48, round(0.2 * 240))
    main_view = frames[-1][: 240 - strip, :160]
    assert main_view.std() > 20  # not a blank image
    assert _orange(main_view) > 0.01  # the arm is in the picture
    closeup = frames[-1][: 240 - strip, 160:]
    assert closeup.std() > 10
    metrics = json.loads((tmp_path / "metrics.json").read_text())
    assert metrics["video"] == VIDEO_FILE and metrics["video_frames"] == 15
    assert "video: docking.mp4 (15 frames" in (tmp_path / "summary.txt").read_text()


def test_frame_count_and_rows():
    assert frame_count(1.5, 10) == 15
    assert frame_count(18.0, 30) == 540
    assert frame_count(2.0, 30, speed=4.0) == 15  # 15 frames = 0.5 s of video
    assert frame_count(0.05, 30) == 2  # 1.5 frames: halves round up
    assert frame_count(0.001, 30) == 1  # never empty
    rows = frame_rows(1500, 0.001, 10)
    assert rows.tolist() == list(range(0, 1500, 100))
    rows = frame_rows(100, 0.001, 30)  # 3 frames at t = 0, 33.3, 66.7 ms: the nearest steps
    assert rows.tolist() == [0, 33, 67]


def test_render_failure_is_recorded_and_the_results_are_kept(tmp_path):
    record = execute(make_cfg(*SHORT, "render.camera=no_such_camera"), tmp_path, figures=False, echo=False)
    assert record["status"] == "incomplete" and record["error"] is None
    assert record["peak_axial_force_N"] is not None  # the simulation's metrics are there
    assert "render.camera" in record["video_error"] and "track_cam" in record["video_error"]
    assert record["video"] is None
    assert (tmp_path / "timeseries.parquet").is_file()
    assert not (tmp_path / VIDEO_FILE).exists() and not list(tmp_path.glob(".*.tmp"))
    assert "video: NOT WRITTEN" in (tmp_path / "summary.txt").read_text()
    assert json.loads((tmp_path / "metrics.json").read_text())["video_error"] == record["video_error"]


def test_no_gl_backend_gives_the_one_paragraph_message(tmp_path, monkeypatch):
    monkeypatch.setattr(gl, "offscreen_possible", lambda env=None: False)
    record = execute(make_cfg(*SHORT), tmp_path, figures=False, echo=False)
    message = record["video_error"]
    for needle in (
        "MUJOCO_GL",
        "egl",
        "osmesa",
        "libegl1 libegl-mesa0 libgl1-mesa-dri",
        "libosmesa6",
        "results were kept",
    ):
        assert needle in message
    assert "\n" not in message
    assert record["status"] == "incomplete"  # a video failure does not fail the run


def test_render_none_imports_no_rendering_library_and_writes_no_video(tmp_path):
    code = f"""
import json, sys
from pathlib import Path
from compliant_docking.config import load_config
from compliant_docking.run.runner import execute
record = execute(load_config("task.duration=0.2", "task.progress=false"), Path({str(tmp_path)!r}),
                 figures=False, echo=False)
loaded = [m for m in ("av", "PIL", "compliant_docking.viz.render", "compliant_docking.viz.viewer",
                      "mujoco.viewer") if m in sys.modules]
print(json.dumps({{"loaded": loaded, "keys": [k for k in record if k.startswith("video")]}}))
"""
    out = subprocess.run(
        [sys.executable, "-c", code], cwd=REPO_ROOT, capture_output=True, text=True, timeout=120, check=True
    )
    result = json.loads(out.stdout.strip().splitlines()[-1])
    assert result == {"loaded": [], "keys": []}
    assert (tmp_path / "metrics.json").is_file()
    assert not (tmp_path / VIDEO_FILE).exists()


def test_render_options_are_typed():
    cfg = make_cfg("render=video", "render.fps=12")
    assert cfg.render.fps == 12 and cfg.render.name == "video"
    default = make_cfg()
    assert default.render.name == "none" and default.viewer is False
    with pytest.raises(Exception, match="fps"):
        make_cfg("render.fps=12")  # render=none has no options
    with pytest.raises(Exception, match="fps"):
        make_cfg("render=video", "render.fps=fast")


# --------------------------------------------------------------------------- backend choice
def _never() -> bool:
    raise AssertionError("probe called although the answer was already known")


@pytest.mark.parametrize(
    "env, platform, display, egl, osmesa, expected",
    [
        # the user's setting wins, display or not
        ({"MUJOCO_GL": "osmesa"}, "linux", True, _never, _never, ("osmesa", "user")),
        ({"MUJOCO_GL": "EGL "}, "linux", False, _never, _never, ("egl", "user")),
        # set by compliant_docking in a parent process (sweep workers inherit it)
        (
            {"MUJOCO_GL": "egl", "COMPLIANT_DOCKING_GL": "egl"},
            "linux",
            False,
            _never,
            _never,
            ("egl", "auto"),
        ),
        # PyOpenGL's platform already chosen: MuJoCo must agree with it
        ({"PYOPENGL_PLATFORM": "osmesa"}, "linux", False, _never, _never, ("osmesa", "auto")),
        # not Linux: MuJoCo's default (CGL/GLFW on macOS, WGL/GLFW on Windows)
        ({}, "darwin", False, _never, _never, (None, "default")),
        # a display: GLFW (the viewer needs it), whatever libraries exist
        ({}, "linux", True, _never, _never, (None, "default")),
        # headless
        ({}, "linux", False, lambda: True, _never, ("egl", "auto")),
        ({}, "linux", False, lambda: False, lambda: True, ("osmesa", "auto")),
        ({}, "linux", False, lambda: False, lambda: False, (None, "default")),
    ],
)
def test_backend_choice(env, platform, display, egl, osmesa, expected):
    d = gl.choose(env, platform=platform, display=display, egl_loads=egl, osmesa_loads=osmesa)
    assert (d.backend, d.source) == expected
    assert d.reason


@pytest.mark.parametrize(
    "env, sockets, expected",
    [
        ({}, set(), False),
        ({"DISPLAY": ":0"}, {"/tmp/.X11-unix/X0"}, True),
        ({"DISPLAY": ":1"}, {"/tmp/.X11-unix/X0"}, False),  # stale DISPLAY: no server socket
        ({"DISPLAY": "unix:0.0"}, {"/tmp/.X11-unix/X0"}, True),
        ({"DISPLAY": "localhost:10.0"}, set(), True),  # remote (ssh -X): taken at its word
        (
            {"WAYLAND_DISPLAY": "wayland-0", "XDG_RUNTIME_DIR": "/run/user/1000"},
            {"/run/user/1000/wayland-0"},
            True,
        ),
        ({"WAYLAND_DISPLAY": "wayland-0", "XDG_RUNTIME_DIR": "/run/user/1000"}, set(), False),
    ],
)
def test_display_detection(env, sockets, expected):
    assert gl.has_display(env, "linux", exists=sockets.__contains__) is expected


def test_display_detection_off_linux():
    assert gl.has_display({}, "darwin") and gl.has_display({}, "win32")


def _in_subprocess(env: dict, code: str) -> dict:
    """Run ``code`` in a fresh interpreter; the JSON it prints last."""
    out = subprocess.run(
        [sys.executable, "-c", code],
        cwd=REPO_ROOT,
        env=env,
        capture_output=True,
        text=True,
        timeout=180,
        check=True,
    )
    return json.loads(out.stdout.strip().splitlines()[-1])


def _clean_env() -> dict:
    return {
        k: v
        for k, v in os.environ.items()
        if k not in ("MUJOCO_GL", "COMPLIANT_DOCKING_GL", "PYOPENGL_PLATFORM", "DISPLAY", "WAYLAND_DISPLAY")
    }


_CHOICE = (
    "import json, os, sys\n{first}\nimport compliant_docking, compliant_docking.cli, compliant_docking.gl as g\n"
    "at_import = os.environ.get('MUJOCO_GL')\n"
    "d = g.configure()\n"
    "print(json.dumps({{'at_import': at_import, 'MUJOCO_GL': os.environ.get('MUJOCO_GL'), "
    "'source': d.source, 'backend': d.backend, 'context': {context}}}))"
)
_CONTEXT = "g.context_class().__module__"


def test_import_has_no_side_effect_and_the_backend_is_chosen_when_rendering_starts():
    env = _clean_env()
    expected = gl.choose(env, display=False)  # the real probes of this machine
    module = {"egl": "mujoco.egl", "osmesa": "mujoco.osmesa", None: "mujoco.glfw"}[expected.backend]
    # importing the package (and the command line) leaves the environment alone; the
    # choice, made when rendering starts, is exported while mujoco is not imported yet
    assert _in_subprocess(env, _CHOICE.format(first="", context=_CONTEXT)) == {
        "at_import": None,
        "MUJOCO_GL": expected.backend,
        "source": expected.source,
        "backend": expected.backend,
        "context": module,
    }
    # the user's choice is kept (not imported here: its libraries may be missing)
    user = _in_subprocess({**env, "MUJOCO_GL": "osmesa"}, _CHOICE.format(first="", context="None"))
    assert (user["MUJOCO_GL"], user["source"], user["backend"]) == ("osmesa", "user", "osmesa")
    # mujoco imported first (as the loop does before a video): MUJOCO_GL is not exported
    # (too late for mujoco's own binding), but the renderer's context is the chosen backend's
    late = _in_subprocess(env, _CHOICE.format(first="import mujoco", context=_CONTEXT))
    assert late["MUJOCO_GL"] is None and late["backend"] == expected.backend and late["context"] == module


def test_a_video_renders_when_mujoco_was_imported_before_the_choice(tmp_path):
    """MuJoCo 4.0 binds mujoco.Renderer's backend at its import: with MUJOCO_GL unset and no
    display that is GLFW, which cannot make a context; the video's own context is the
    chosen backend's, so the video is made all the same (0.3 s: 3 frames)."""
    _need_offscreen_gl()
    code = f"""
import json, mujoco
from pathlib import Path
from compliant_docking.config import load_config
from compliant_docking.run.runner import execute
record = execute(load_config(*{SHORT!r}, "task.duration=0.3"), Path({str(tmp_path)!r}), figures=False, echo=False)
print(json.dumps({{"error": record["video_error"], "frames": record["video_frames"]}}))
"""
    assert _in_subprocess(_clean_env(), code) == {"error": None, "frames": 3}


def test_a_diverged_log_renders_up_to_the_last_finite_pose(tmp_path):
    """Rows that went non-finite hold the last finite pose (the overlay off: views only)."""
    _need_offscreen_gl()
    from omegaconf import OmegaConf

    from compliant_docking.sim.simulate import prepare
    from compliant_docking.viz.render import write_video

    sim = prepare(make_cfg("task.progress=false"))
    q = np.vstack([np.tile(sim.q0, (60, 1)), np.full((40, len(sim.q0)), np.nan)])
    options = OmegaConf.merge(
        make_cfg("render=video").render, {"fps": 50, "width": 128, "height": 96, "overlay": False}
    )
    zeros = np.zeros(len(q))
    result = write_video(
        sim.scene.model,
        q,
        0.001,
        tmp_path / VIDEO_FILE,
        options,
        axial_force=zeros,
        force_norm=zeros,
        contacts=zeros.astype(int),
        focus=None,
        tool_body=int(sim.scene.tool_body),
    )
    frames = _decode(result.path)
    assert len(frames) == result.frames == 5  # 0.1 s at 50 fps
    assert frames[0].shape == (96, 128, 3)
    assert np.abs(frames[-1].astype(int) - frames[0].astype(int)).mean() < 3  # the same pose
