"""Where one control step's time goes, per robot × controller.

Runs the default docking run once (the loop as the simulation runs it), then replays the
recorded states (q, v, measured wrench) through a freshly built arm model and controller,
timing each part of the step separately: the arm's update (Pinocchio), the reference row,
the controller's compute, and the physics (a physics-only replay of the recorded
torques). The controller sees exactly the inputs it saw in the loop, so it takes the same
branches. Best of ``--repeats`` per part, in µs per step.

    python benchmarks/step_profile.py --robots iiwa14 fr3
    python benchmarks/step_profile.py --robots fr3 --controllers hqp --cprofile 25

``--cprofile N`` also prints the N most expensive functions of the controller's compute
(cumulative time; cProfile's overhead inflates small calls, read it for proportions).
"""

from __future__ import annotations

import argparse
import cProfile
import pstats
import sys
import time
from pathlib import Path

import numpy as np

from compliant_docking import CONF_DIR
from compliant_docking.config import load_config
from compliant_docking.planning.base import Reference
from compliant_docking.sim.simulate import prepare, replay_physics


def parts(overrides: list[str], repeats: int, profile: int) -> dict[str, float]:
    cfg = load_config(*overrides)
    sim = prepare(cfg)
    sim.run()
    n = sim.telemetry.count
    q, v, w = sim.telemetry.q[:n].copy(), sim.telemetry.v[:n].copy(), sim.telemetry.wrench[:n].copy()
    dt = sim.scene.model.opt.timestep
    best = {
        "loop": sim.loop_wall_time / n * 1e6,
        "update": np.inf,
        "reference": np.inf,
        "compute": np.inf,
        "physics": np.inf,
    }
    for r in range(repeats):
        fresh = prepare(cfg)
        arm, ctrl = fresh.scene.arm, fresh.controller
        table = fresh.planner.table(np.arange(fresh.n_steps) * dt)
        ref = Reference()
        t_up = t_ref = t_comp = 0
        clock = time.perf_counter_ns
        prof = cProfile.Profile() if profile and r == 0 else None
        qk, vk, wk = np.zeros_like(q[0]), np.zeros_like(v[0]), np.zeros(6)
        for k in range(n):
            qk[:] = q[k]
            vk[:] = v[k]
            wk[:] = w[k]
            a = clock()
            arm.update(qk, vk)
            b = clock()
            table.row(k, ref)
            c = clock()
            if prof is not None:
                prof.enable()
            ctrl.compute(k * dt, arm, ref, wk)
            if prof is not None:
                prof.disable()
            d = clock()
            t_up += b - a
            t_ref += c - b
            t_comp += d - c
        if prof is None:
            best["update"] = min(best["update"], t_up / n * 1e-3)
            best["reference"] = min(best["reference"], t_ref / n * 1e-3)
            best["compute"] = min(best["compute"], t_comp / n * 1e-3)
        else:
            stats = pstats.Stats(prof)
            stats.sort_stats("tottime").print_stats(profile)
        best["physics"] = min(best["physics"], replay_physics(sim) / n * 1e6)
    return best


def main() -> int:
    options = sorted(p.stem for p in (Path(CONF_DIR) / "controller").glob("*.yaml"))
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--controllers", nargs="+", default=options, choices=options)
    parser.add_argument("--robots", nargs="+", default=["iiwa14"])
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--cprofile", type=int, default=0, metavar="N")
    parser.add_argument("overrides", nargs="*", help="extra Hydra overrides for every run")
    args = parser.parse_args()
    rows = []
    for robot in args.robots:
        for controller in args.controllers:
            over = [f"robot={robot}", f"controller={controller}", "task.progress=false", *args.overrides]
            rows.append((robot, controller, parts(over, args.repeats + bool(args.cprofile), args.cprofile)))
    print(
        f"{'robot':8} {'controller':11} {'loop':>7} {'update':>7} {'ref':>6} {'compute':>8} "
        f"{'physics':>8} {'rest':>6}   (µs/step; rest = loop − the parts: logging, sensor, ctrl)"
    )
    for robot, controller, p in rows:
        rest = p["loop"] - p["update"] - p["reference"] - p["compute"] - p["physics"]
        print(
            f"{robot:8} {controller:11} {p['loop']:7.1f} {p['update']:7.1f} {p['reference']:6.1f} "
            f"{p['compute']:8.1f} {p['physics']:8.1f} {rest:6.1f}"
        )
    return 0


if __name__ == "__main__":
    sys.exit(main())
