"""The one-step force-feedback loop, linearised at a seated state.

For a robot and controller, take the seated state at the end of a calm run (force
feedback off), then:

1. the analytic gain: with the contact along the axis u, MuJoCo's soft constraint gives
   f_k = d·Λ_u·(a0_k − a_ref) (d = solimp impedance, Λ_u = 1/(uᵀΛ⁻¹u)), and the impedance
   law puts (Λ W⁻¹ − I) w_{k−1} into the command, so f_k = −d(Λ_u/m − 1)·f_{k−1} + (slow
   terms): period-2 (500 Hz) divergence when d·|Λ_u/m − 1| > 1;
2. the measured gain: the 6×6 Jacobian ∂w_k/∂w_{k−1} of one MuJoCo step through the real
   controller (finite differences of the wrench handed to compute()), and its spectral
   radius: > 1 means the measured wrench, fed back one step late, grows from step to step.

    python analysis/held_contact/loop_gain.py                      # the table (results/loop_gain.md)
    python analysis/held_contact/loop_gain.py robot=fr3 controller.m=5 ...   # one configuration

Configurations start from the laws without the held-contact fixes (experiments.spec()),
then the overrides.
"""
from __future__ import annotations

import copy
import sys

import mujoco
import numpy as np

from compliant_docking.config import load_config
from compliant_docking.sim.sensor import wrench_reader
from compliant_docking.sim.simulate import prepare


def seated_state(overrides):
    cfg = load_config(*overrides, "controller.use_force_feedback=false", "task.progress=false")
    sim = prepare(cfg)
    sim.run()
    return sim.data.qpos.copy(), sim.data.qvel.copy(), sim.data.act.copy(), cfg


def loop_jacobian(overrides, eps=1e-3):
    q, v, act, _ = seated_state(overrides)
    cfg = load_config(*overrides, "task.progress=false")
    sim = prepare(cfg)
    model, data, arm = sim.scene.model, sim.data, sim.scene.arm
    data.qpos[:], data.qvel[:] = q, v
    # settle one step with the feedback controller to get a consistent sensor reading
    ref_table = sim.planner.table(np.arange(sim.n_steps) * model.opt.timestep)
    from compliant_docking.planning.base import Reference
    ref = Reference()
    k_end = sim.n_steps - 1
    ref_table.row(k_end, ref)
    mujoco.mj_forward(model, data)
    w0 = np.zeros(6)
    wrench_reader(sim.scene, data, w0)()
    t = k_end * model.opt.timestep

    def step(w_in):
        d = copy.copy(data)
        arm.update(d.qpos, d.qvel)
        tau = sim.controller.compute(t, arm, ref, w_in)
        d.ctrl[:] = tau
        mujoco.mj_step(model, d)
        out = np.zeros(6)
        wrench_reader(sim.scene, d, out)()
        return out, d.ncon

    base, ncon = step(w0)
    Jw = np.zeros((6, 6))
    for i in range(6):
        dw = np.zeros(6)
        dw[i] = eps
        Jw[:, i] = (step(w0 + dw)[0] - step(w0 - dw)[0]) / (2 * eps)
    # analytic: task inertia along the axis
    arm.update(data.qpos, data.qvel)
    lam_inv = arm.J.dot(arm.Minv).dot(arm.J.T)
    u = np.concatenate([sim.waypoints.axis, np.zeros(3)])
    lam_u = 1.0 / (u @ lam_inv @ u)
    return dict(w0=w0, ncon=ncon, J=Jw, rho=max(abs(np.linalg.eigvals(Jw))),
                eig=np.linalg.eigvals(Jw), lam_u=lam_u, lam=np.linalg.inv(lam_inv),
                cfg=cfg)


TABLE = [
    ("robot=fr3",), ("robot=fr3", "controller.friction_comp=velocity"),
    ("robot=fr3", "controller.m=5", "controller.m_rot=0.5"),
    ("robot=fr3", "controller.m=10", "controller.m_rot=1"),
    ("robot=iiwa14",), ("robot=iiwa14", "controller.m=2", "controller.m_rot=0.2"),
    ("robot=fr3", "controller.apparent_inertia_floor=0.6", "controller.friction_comp=velocity"),
    ("robot=fr3", "controller.apparent_inertia_floor=0.6", "controller.friction_comp=torque_unbiased"),
    ("robot=fr3", "controller.apparent_inertia_floor=0.75", "controller.friction_comp=velocity"),
    ("robot=fr3", "controller.apparent_inertia_floor=0.75", "controller.friction_comp=torque_unbiased"),
    ("robot=fr3", "controller=hqp"),
]


def report(overrides):
    from experiments import spec

    controller = next((o.split("=")[1] for o in overrides if o.startswith("controller=")), "impedance")
    full = [*spec(controller), *[o for o in overrides if not o.startswith("controller=")]]
    full = [o for i, o in enumerate(full) if not any(p.split("=")[0] == o.split("=")[0]
                                                     for p in full[i + 1:])]  # last wins
    r = loop_jacobian(["robot=fr3", *full] if not any(o.startswith("robot=") for o in full) else full)
    c = r["cfg"].controller
    m = c.get("m")
    d = r["cfg"].target.contact.solimp[1]
    floor = c.get("apparent_inertia_floor")
    ratio = r["lam_u"] / m if m else None
    if ratio is not None and floor:
        ratio = min(ratio, 1.0 / floor)  # what the floor leaves of Λ_u/m
    analytic = f"{d * abs(ratio - 1):.2f}" if m else "n/a"
    negative = min(e.real for e in r["eig"])
    print(f"| {' '.join(overrides)} | {r['lam_u']:.2f} | {m if m else 'Λ (no shaping)'} | {analytic} | "
          f"{negative:.2f} | {r['rho']:.2f} |", flush=True)


if __name__ == "__main__":
    sys.path.insert(0, __file__.rsplit("/", 1)[0])
    print("| configuration (laws without the fixes + …) | Λ_u [kg] | m [kg] | d·|min(Λ_u/m, 1/floor) − 1| | most negative eigenvalue | spectral radius |")
    print("|---|---|---|---|---|---|")
    for overrides in ([sys.argv[1:]] if len(sys.argv) > 1 else TABLE):
        report(list(overrides))
