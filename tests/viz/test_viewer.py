"""viewer=true (compliant_docking/viz/viewer.py) and the loop's per-step hook."""

from __future__ import annotations

import contextlib
import json
from types import SimpleNamespace

import mujoco
import pytest

from compliant_docking.run.runner import execute
from compliant_docking.sim.simulate import prepare
from compliant_docking.viz import viewer
from tests.helpers import cli_in_process_output, make_cfg


# --------------------------------------------------------------------------- refusals
def test_refused_in_a_sweep_even_with_a_display():
    reason = viewer.refusal(multirun=True, env={"DISPLAY": "localhost:10.0"})
    assert "sweep" in reason and "-m" in reason


def test_refused_without_a_display():
    reason = viewer.refusal(multirun=False, env={}, platform="linux")
    assert "display" in reason and "DISPLAY" in reason and "render=video" in reason


def test_allowed_with_a_display():
    assert viewer.refusal(multirun=False, env={"DISPLAY": "localhost:10.0"}, platform="linux") is None


def test_single_run_without_display_is_refused_before_simulating(tmp_path, monkeypatch):
    monkeypatch.delenv("DISPLAY", raising=False)
    monkeypatch.delenv("WAYLAND_DISPLAY", raising=False)
    record = execute(make_cfg("viewer=true", "task.progress=false"), tmp_path, figures=False, echo=False)
    assert record["status"] == "failed" and "needs a desktop display" in record["error"]
    assert record.get("steps") is None  # nothing was simulated
    assert json.loads((tmp_path / "metrics.json").read_text())["error"] == record["error"]


def test_sweep_with_viewer_is_refused_before_anything_runs(tmp_path, capsys):
    """viewer=true in a sweep is refused up front (compliant_docking/sweep/guard.py), not by
    every job; the runner's own refusal (a job that sees Hydra's MULTIRUN mode) stays for
    runs started otherwise."""
    sweep = tmp_path / "sweep"
    code, out, err = cli_in_process_output(
        capsys,
        "-m",
        "viewer=true",
        "task.duration=0.2",
        "task.progress=false",
        "hydra.launcher.n_jobs=1",
        f"hydra.sweep.dir={sweep}",
        "hydra.callbacks.sweep.figures=false",
    )
    assert code == 2
    assert "viewer=true is refused in a sweep (-m)" in err
    assert "resume" not in out + err and "Traceback" not in err
    assert not sweep.exists()


# --------------------------------------------------------------------------- pacing
class _FakeHandle:
    def __init__(self, clock):
        self.clock, self.syncs, self.closed, self.running = clock, [], 0, True
        self.cam = SimpleNamespace(type=None, fixedcamid=None)

    def is_running(self):
        return self.running

    def sync(self):
        self.syncs.append(self.clock.now)

    def lock(self):
        return contextlib.nullcontext()

    def close(self):
        self.closed += 1


class _FakeClock:
    def __init__(self):
        self.now, self.slept = 100.0, 0.0

    def __call__(self):
        return self.now

    def sleep(self, seconds):
        self.slept += seconds
        self.now += seconds


def _fake_sim(n_steps: int):
    model = mujoco.MjModel.from_xml_string(
        '<mujoco><option timestep="0.001"/><worldbody><camera name="track_cam"/>'
        '<body><joint/><geom size=".1"/></body></worldbody></mujoco>'
    )
    return SimpleNamespace(
        scene=SimpleNamespace(model=model), data=mujoco.MjData(model), n_steps=n_steps, end=n_steps
    )


def test_viewer_is_paced_to_real_time_and_closes_at_the_end():
    clock = _FakeClock()
    handles = []

    def launch(model, data, **kwargs):
        handles.append(_FakeHandle(clock))
        return handles[-1]

    on_step = viewer.RealTimeViewer(_fake_sim(1000), launch=launch, clock=clock, sleep=clock.sleep)
    for k in range(1000):
        on_step(k)
        clock.now += 1e-5  # the loop's own work: 10 µs per step, far faster than real time
    handle = handles[0]
    assert handle.cam.fixedcamid == 0  # starts from the scene's tracking camera
    # about 60 Hz of simulated time (every 17 steps of 1 ms), and the last step
    assert len(handle.syncs) == len(range(0, 1000, on_step.every)) + 1
    # wall time from the first step to the end ≈ the simulated time (1 s)
    assert clock.now - (100.0 - 0.001) == pytest.approx(1.0, abs=2e-3)
    assert handle.closed == 1


def test_closing_the_window_lets_the_run_finish_at_full_speed():
    clock = _FakeClock()
    handle = _FakeHandle(clock)
    on_step = viewer.RealTimeViewer(
        _fake_sim(1000), launch=lambda *a, **k: handle, clock=clock, sleep=clock.sleep
    )
    for k in range(1000):
        if k == 100:
            handle.running = False  # the user closed the window
        on_step(k)
    assert clock.slept < 0.11 and len(handle.syncs) <= 100 // on_step.every + 1
    assert handle.closed == 0  # already gone


def test_the_loop_calls_on_step_once_per_step_after_mj_step():
    sim = prepare(make_cfg("task.duration=0.02", "task.progress=false"))
    seen = []
    sim.run(on_step=lambda k: seen.append((k, sim.data.time)))
    dt = sim.scene.model.opt.timestep
    assert [k for k, _ in seen] == list(range(sim.n_steps))
    assert all(t == pytest.approx((k + 1) * dt) for k, t in seen)
