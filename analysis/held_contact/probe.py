"""Run one configuration in-process, optionally with a modified wrench path (extra delay,
a first-order low-pass), and report the steady-window contact statistics: make/break events
per second and the mean, spread and maximum of |f| over the last 2 s (README.md).

    python analysis/held_contact/probe.py [overrides ...]
"""
from __future__ import annotations

import sys
import numpy as np

from compliant_docking.config import load_config
from compliant_docking.sim.simulate import prepare


def steady_stats(t, wrench, contacts, window=2.0):
    m = t > t.max() - window
    f = np.linalg.norm(wrench[m, :3], axis=1)
    c = (contacts[m] > 0).astype(int)
    events = int(np.abs(np.diff(c)).sum())
    return dict(rate=events / window, mean=float(f.mean()), std=float(f.std(ddof=1)),
                max=float(f.max()))


def wrap_wrench(controller, *, extra_delay=0, cutoff_hz=None, dt=1e-3, gain=1.0):
    """Replace controller.compute by one seeing a modified wrench."""
    inner = controller.compute
    buf = [np.zeros(6) for _ in range(extra_delay + 1)]
    filtered = np.zeros(6)
    alpha = 1.0 - np.exp(-2 * np.pi * cutoff_hz * dt) if cutoff_hz else 1.0

    def compute(t, state, ref, wrench):
        buf.append(wrench.copy())
        w = buf.pop(0)
        filtered[:] += alpha * (w - filtered)
        return inner(t, state, ref, gain * filtered)

    controller.compute = compute


def run(*overrides, extra_delay=0, cutoff_hz=None, gain=1.0, no_ff=False, no_joint_friction=False):
    cfg = load_config(*overrides, "task.progress=false")
    sim = prepare(cfg)
    if no_ff:  # no friction feed-forward (MuJoCo's joint friction stays)
        sim.controller.friction.active = False
    if no_joint_friction:  # neither MuJoCo's joint friction/damping nor the feed-forward
        sim.scene.model.dof_frictionloss[:] = 0.0
        sim.scene.model.dof_damping[:] = 0.0
        sim.controller.friction.active = False
    if extra_delay or cutoff_hz or gain != 1.0:
        wrap_wrench(sim.controller, extra_delay=extra_delay, cutoff_hz=cutoff_hz,
                    dt=sim.scene.model.opt.timestep, gain=gain)
    try:
        log = sim.run()
    except Exception as exc:  # diverged
        return dict(rate=np.nan, mean=np.nan, std=np.nan, max=np.nan, error=str(exc)[:60]), sim
    n = log.count
    t = np.arange(n) * sim.scene.model.opt.timestep
    out = steady_stats(t, log.wrench[:n], log.contacts[:n])
    out.update(docking_stats(sim))
    return out, sim


def docking_stats(sim):
    """Peak axial force, and the tip's depth / lateral error to the TRUE seat at the end."""
    log, arm = sim.telemetry, sim.scene.arm
    n = log.count
    axis = sim.waypoints.axis
    axial = -(log.wrench[:n, :3] @ axis)
    seat = sim.scene.socket.true if sim.scene.socket is not None else None
    out = dict(peak=float(np.abs(axial).max()))
    diag = sim.controller.diagnostics()
    if "inertia_floor_active_steps" in diag:
        out["floor_steps"] = diag["inertia_floor_active_steps"]
    if seat is not None:
        arm.update(log.q[n - 1], log.v[n - 1])
        rel = (arm.pos - seat.translation) @ seat.rotation
        out.update(depth_mm=abs(rel[2]) * 1e3, lateral_mm=float(np.hypot(*rel[:2])) * 1e3)
        out["docked"] = out["depth_mm"] <= 1.0 and out["lateral_mm"] <= 1.0 and out["peak"] <= 50.0
    return out


def fmt(s):
    calm = s['rate'] <= 5 and s['std'] <= max(0.5, 0.2 * s['mean'])
    dock = (f" peak {s['peak']:5.1f} depth {s['depth_mm']:5.2f} lat {s['lateral_mm']:4.2f} mm "
            f"{'DOCKED' if s['docked'] else 'not docked'}") if 'depth_mm' in s else ""
    if 'floor_steps' in s:
        dock += f" floor active {s['floor_steps']} steps"
    return (f"{'calm' if calm else 'CHATTER'} {s['rate']:6.1f} ev/s |F| {s['mean']:6.2f} ± {s['std']:5.2f} max {s['max']:6.1f}" + dock
            + (f"  {s['error']}" if 'error' in s else ""))


if __name__ == "__main__":
    s, _ = run(*sys.argv[1:])
    print(fmt(s))
