"""The Gymnasium environment's speed against the plain simulation loop, as ratios in one process.

Alternating in one process (the same load for both), for each repeat:

  plain   prepare the run, then Simulation.run(): the loop's wall time (``loop_wall_time``)
  env     reset(seed) and step a zero action to the end (the same run, bit for bit)

and reports, best and median over ``--repeats``:

  env step rate          policy steps per second (the final step, which evaluates the
                         run's metrics, left out; reported on its own)
  overhead / loop        (Σ step time − the loop's time inside the steps) / the loop's time:
                         what the env layer adds per step (the target: ≤ 20 % at a 10 ms
                         policy step)
  env / plain loop       the steps' time over the plain loop's (the same physics and
                         controller, so the same ratio measured the other way)
  reset, final step      seconds per episode: prepare + the first observation; the run's
                         metrics and gate (the runner's evaluate)

    python benchmarks/env_speed.py                         # default run, 10 ms policy step
    python benchmarks/env_speed.py --policy-steps 0.01 0.05 --repeats 5
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time

import numpy as np

from compliant_docking.config import load_config
from compliant_docking.env import compose
from compliant_docking.env.docking import DockingEnv
from compliant_docking.sim.simulate import prepare

#: the target: the env layer's time per step at most this share of the loop's, at 10 ms
OVERHEAD_TARGET = 0.20


def plain(overrides: list[str]) -> float:
    """The loop's wall time of one run [s]."""
    sim = prepare(load_config(*overrides))
    sim.run()
    return sim.loop_wall_time


def episode(env: DockingEnv, seed: int) -> dict[str, float]:
    """One episode of zero actions: its timings [s]. The steps between the first and the
    final one are timed (the first sets the loop's clock apart from the planner's table,
    which the loop's time holds too; the final one evaluates the run)."""
    zero = np.zeros(env.action_space.shape, dtype=np.float32)
    start = time.perf_counter()
    env.reset(seed=seed)
    reset = time.perf_counter() - start
    env.step(zero)
    sim = env.sim
    assert sim is not None
    loop_start = sim.loop_wall_time
    steps, stepping, loop_end = 0, 0.0, loop_start
    while True:
        before = time.perf_counter()
        _, _, terminated, truncated, _ = env.step(zero)
        spent = time.perf_counter() - before
        if terminated or truncated:
            break
        stepping += spent
        steps += 1
        loop_end = sim.loop_wall_time
    return {
        "reset": reset,
        "steps": steps,
        "stepping": stepping,
        "loop": loop_end - loop_start,
        "final": spent,
    }


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--policy-steps", nargs="+", type=float, default=[0.01])
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("overrides", nargs="*", help="Hydra overrides of the run (and env.*)")
    args = parser.parse_args()
    with open("/proc/loadavg") as f:
        print(f"load before: {f.read().split()[:3]}")
    failures = 0
    for policy_step in args.policy_steps:
        overrides = [*args.overrides, f"env.policy_step={policy_step}", "task.progress=false"]
        cfg, settings = compose(overrides)
        env = DockingEnv(cfg=cfg, settings=settings)
        env.run_overrides = []
        rows = []
        for _ in range(args.repeats):
            loop = plain([o for o in overrides if not o.startswith("env.")])
            ep = episode(env, seed=int(cfg.task.misalignment.seed))
            rows.append((loop, ep))
        overhead = [(e["stepping"] - e["loop"]) / e["loop"] for _, e in rows]
        rate = [e["steps"] / e["stepping"] for _, e in rows]
        versus = [e["stepping"] / p for p, e in rows]
        best = min(range(len(rows)), key=lambda i: overhead[i])
        ok = overhead[best] <= OVERHEAD_TARGET
        failures += not ok and policy_step == 0.01
        print(
            f"policy step {policy_step * 1e3:g} ms ({rows[0][1]['steps']} steps timed):\n"
            f"  env step rate     best {max(rate):8.0f}/s   median {statistics.median(rate):8.0f}/s\n"
            f"  overhead / loop   best {overhead[best]:8.1%}    median {statistics.median(overhead):8.1%}"
            f"   (target ≤ {OVERHEAD_TARGET:.0%} at 10 ms: {'met' if ok else 'MISSED'})\n"
            f"  env / plain loop  best {min(versus):8.2f}     median {statistics.median(versus):8.2f}\n"
            f"  plain loop        best {min(p for p, _ in rows):8.2f} s   "
            f"median {statistics.median(p for p, _ in rows):8.2f} s\n"
            f"  reset             median {statistics.median(e['reset'] for _, e in rows):8.3f} s;   "
            f"final step (metrics, gate) median {statistics.median(e['final'] for _, e in rows):8.3f} s"
        )
    with open("/proc/loadavg") as f:
        print(f"load after: {f.read().split()[:3]}")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
