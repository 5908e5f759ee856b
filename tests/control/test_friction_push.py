"""The push test of the friction feed-forward on the FR3 (docs/controllers/friction.md): a
constant sideways push at the TCP of the arm held in free space, the TCP's travel after
0.25 s with and without the feed-forward. The feed-forward must not add to the joints'
own friction against a motion the push (a contact) drives."""

import numpy as np

from compliant_docking.sim.simulate import prepare
from tests.helpers import FREE_SPACE_HOLD, make_cfg, push_at_tcp

PUSH = np.array([0.0, 6.0, 0.0])  # [N], sideways (world y)
STEPS = 250  # 0.25 s at 1 kHz


def travel(friction_comp: str, feed_forward: bool) -> float:
    """The TCP's travel along the push after STEPS steps [m]."""
    sim = prepare(
        make_cfg(
            *FREE_SPACE_HOLD,
            "robot=fr3",
            "controller=impedance",
            "controller.integral_gain=0",
            f"controller.friction_comp={friction_comp}",
            "trajectory.duration=0.25",
            "task.progress=false",
        )
    )
    sim.controller.friction.active = feed_forward
    start = sim.scene.arm.tcp_placement(sim.q0).translation
    push_at_tcp(sim, force=PUSH)
    sim.start()
    sim.advance(STEPS)
    end = sim.scene.arm.tcp_placement(sim.data.qpos).translation
    return float((end - start) @ PUSH / np.linalg.norm(PUSH))


def test_yielding_feed_forward_does_not_resist_a_pushed_motion():
    """Measured: the joints' friction alone lets the TCP travel 6.5 mm; torque_unbiased, which
    takes its sign from the command (here the stiffness pulling back), cuts that to 4.1 mm
    (the feed-forward adds its f to the friction); yielding travels 6.2 mm."""
    without = travel("yielding", feed_forward=False)
    assert without > 0.005
    assert travel("torque_unbiased", feed_forward=True) < 0.75 * without
    assert travel("yielding", feed_forward=True) > 0.9 * without
