"""Issue 10: what the new pieces cost per control step (µs, best of 5 × 20 000 calls of
controller.compute at one mid-approach state; the machine is shared, so the best is the
code's cost). Variants differ by one option each from the law as specified.

    python analysis/issue10/cost.py
"""
from __future__ import annotations

import time

import numpy as np

from compliant_docking.config import load_config
from compliant_docking.planning.base import Reference
from compliant_docking.sim.simulate import prepare

SPEC = ("controller.apparent_inertia_floor=null", "controller.friction_comp=torque",
        "controller.integral_gain=0")


def per_step(overrides, calls=20_000, repeats=5):
    sim = prepare(load_config(*overrides, "task.progress=false", "task.duration=8"))
    sim.run()  # a mid-approach state, no contact
    arm, ctrl = sim.scene.arm, sim.controller
    q, v = sim.data.qpos.copy(), sim.data.qvel.copy()
    ref = Reference()
    sim.reference.row(sim.telemetry.count - 1, ref)
    wrench = np.zeros(6)
    arm.update(q, v)
    best = np.inf
    for _ in range(repeats):
        start = time.perf_counter()
        for _ in range(calls):
            ctrl.compute(8.0, arm, ref, wrench)
        best = min(best, (time.perf_counter() - start) / calls * 1e6)
    return best, ctrl.diagnostics().get("inertia_floor_active_steps")


if __name__ == "__main__":
    for robot in ("iiwa14", "fr3"):
        for controller in ("impedance", "se3_lie", "hqp"):
            base = (f"robot={robot}", f"controller={controller}")
            spec = SPEC if controller != "hqp" else (*SPEC[1:], "controller.null_space_metric=euclidean")
            variants = [("as specified", spec)]
            if controller != "hqp":
                variants.append(("+ floor", (*spec[1:], "controller.apparent_inertia_floor=0.6")))
            else:
                variants.append(("+ inertia metric", spec[:2]))
            variants += [("+ torque_unbiased", tuple(o if "friction" not in o else
                                                     "controller.friction_comp=torque_unbiased" for o in spec)),
                         ("+ integral", tuple(o if "integral" not in o else
                                              "controller.integral_gain=2000" for o in spec)),
                         ("defaults", ())]
            for label, extra in variants:
                us, active = per_step((*base, *extra))
                note = "" if active is None else f" (floor active {active > 0})"
                print(f"{robot:6s} {controller:9s} {label:18s} {us:6.2f} µs/step{note}", flush=True)
