"""Time-domain experiments on the held contact (steady window, last 2 s).

Each line: the overrides / wrench-path change, calm or CHATTER (the calm-hold
criterion of the docking gate:
≤ 5 make/break events/s and |F| std ≤ max(0.5 N, 20 % of the mean)), events per second,
|F| mean ± std and max over the last 2 s, the peak axial force over the run, the tip's
final depth and lateral error against the true seat, and whether the docking gate's seat
and force items hold.

Every configuration starts from the laws without the held-contact fixes (no
apparent-inertia floor, torque-mode friction feed-forward, no integral action, HQP's
euclidean null-space metric: spec()), then changes what its label says.

    python analysis/held_contact/experiments.py [group ...]     # all groups: ~5 min on 2 cores
"""
from __future__ import annotations

import sys
from concurrent.futures import ProcessPoolExecutor

sys.path.insert(0, __file__.rsplit("/", 1)[0])
from probe import fmt, run  # noqa: E402


def spec(controller="impedance"):
    """Overrides giving a controller the law and defaults without the held-contact fixes."""
    common = ("controller.friction_comp=torque", "controller.integral_gain=0")
    if controller == "hqp":
        return ("controller=hqp", *common, "controller.null_space_metric=euclidean")
    return (f"controller={controller}", *common, "controller.apparent_inertia_floor=null")


def fr3(controller="impedance", *extra):
    return ("robot=fr3", *spec(controller), *extra)


def iiwa(controller="impedance", *extra):
    return ("robot=iiwa14", *spec(controller), *extra)


def mass(m):
    return (f"controller.m={m}", f"controller.m_rot={m / 10:g}")


GROUPS = {
    # is it the force feedback? (with it off the law is pure motion control)
    "feedback": [(fr3(), {}), (fr3("impedance", "controller.use_force_feedback=false"), {}),
                 (fr3("se3_lie"), {}), (fr3("se3_lie", "controller.use_force_feedback=false"), {}),
                 (fr3("hqp"), {})],
    # the apparent mass against the task inertia (FR3 Λ_u ≈ 5.1 kg, iiwa14 6.8 kg)
    "mass": [(fr3("impedance", *mass(m)), {}) for m in (2, 2.6, 3, 4, 5, 6, 8, 10)]
            + [(iiwa("impedance", *mass(m)), {}) for m in (2, 3, 4, 10)],
    "mass_split": [(fr3("impedance", "controller.m=2", "controller.m_rot=1"), {}),
                   (fr3("impedance", "controller.m=10", "controller.m_rot=0.2"), {})],
    # the friction feed-forward: other modes, none, or no joint friction at all
    "friction": [(fr3("impedance", *mass(m), *extra), kw)
                 for m in (2, 2.6, 3, 3.5)
                 for extra, kw in ((("controller.friction_comp=velocity",), {}), ((), {"no_ff": True}),
                                   ((), {"no_joint_friction": True}))],
    # the contact: stiffer / softer time constant, a soft impedance
    "solref": [(fr3("impedance", f"target.contact.solref=[{tc},1.0]"), {}) for tc in (0.002, 0.01, 0.02, 0.05)]
              + [(fr3("impedance", "target.contact.solimp=[0.5,0.6,0.0005,0.5,2.0]"), {})],
    # one more step of measurement delay
    "delay": [(fr3(), {"extra_delay": 1}), (fr3("impedance", *mass(5)), {"extra_delay": 1}),
              (iiwa(), {"extra_delay": 1}), (iiwa(), {"extra_delay": 3})],
    # a first-order F/T low-pass (a sensor of finite bandwidth)
    "filter": [(fr3(), {"cutoff_hz": fc}) for fc in (300, 200, 100, 50, 30, 20, 10)]
              + [(fr3("se3_lie"), {"cutoff_hz": fc}) for fc in (100, 50, 30)]
              + [(iiwa(c), {"cutoff_hz": fc}) for c in ("impedance", "se3_lie") for fc in (100, 30)],
    # the fix: the apparent-inertia floor, with each friction mode, zero-g and earth
    "floor": [(fr3(c, f"controller.apparent_inertia_floor={r}", f"controller.friction_comp={fc}",
                   f"physics={ph}"), {})
              for c in ("impedance", "se3_lie") for ph in ("space", "earth")
              for fc in ("torque", "velocity", "torque_unbiased") for r in (0.5, 0.6, 0.75, 1.0)],
    # under gravity, before the floor: feedback off, friction modes; HQP
    "earth": [(fr3("impedance", "physics=earth", *extra), {}) for extra in (
        (), ("controller.use_force_feedback=false",), ("controller.friction_comp=velocity",))]
             + [(fr3("hqp", "physics=earth", f"controller.friction_comp={fc}"), {})
                for fc in ("torque", "velocity", "torque_unbiased")],
    # the floor on the iiwa14 at its default gains: 0.6 never acts, 0.75 does
    "iiwa_floor": [(iiwa(c, f"trajectory={tr}", *fl), {})
                   for c in ("impedance", "se3_lie") for tr in ("quintic", "se3topp")
                   for fl in ((), ("controller.apparent_inertia_floor=0.6",),
                              ("controller.apparent_inertia_floor=0.75",))],
}


def job(args):
    overrides, kw = args
    s, _ = run(*overrides, **kw)
    shown = [o for o in overrides if o not in spec("impedance") + spec("se3_lie") + spec("hqp")
             or o.startswith("controller=")]
    label = " ".join(shown) + ("  " + " ".join(f"{k}={v}" for k, v in kw.items()) if kw else "")
    return f"{label:<95} {fmt(s)}"


if __name__ == "__main__":
    groups = sys.argv[1:] or list(GROUPS)
    with ProcessPoolExecutor(2) as pool:
        for g in groups:
            print(f"## {g}", flush=True)
            for line in pool.map(job, GROUPS[g]):
                print(line, flush=True)
