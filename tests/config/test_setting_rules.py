"""One rule per parameter: a controller's or planner's constructor refuses a setting with
the range its schema field declares, in the config check's own words
(``config.ranges.require``); a relation the run checks again (the press within the settle
time, a unit quaternion, the per-joint lengths) is one function of the config check.

Each case is a value the config check refuses; the constructor, given the same value
(built from Python without the check), must refuse it with the same sentence. The first
group of each list are the rules that used to differ: the constructor took what the
schema refuses.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from hydra.utils import instantiate

from compliant_docking.config.validate import check, per_joint_problems
from compliant_docking.sim import simulate
from compliant_docking.sim.models import mount_placement
from compliant_docking.sim.settings import sim_settings
from compliant_docking.sim.task import nominal_waypoints
from tests.helpers import make_cfg

FREE_SPACE = ("target=none", "trajectory=hold", "task.init_pos=[0.55,0.0,0.35]", "task.settle_time=0.0")

#: (controller, the key refused, the override giving it a value outside its range)
CASES = [
    # the constructor used to accept these: K0 ≥ 0, any dt_p > 0, limits ≥ 0, NaN gains
    ("hqp", "controller.K0", "controller.K0=[300,300,0,50,50,50]"),
    ("hqp", "controller.dt_p", "controller.dt_p=2.0"),
    ("hqp", "robot.velocity_limits", "robot.velocity_limits=[1.4,1.4,1.7,1.3,2.2,2.3,0]"),
    ("hqp", "robot.max_torque", "robot.max_torque=[10,10,10,10,10,10,0]"),
    ("impedance", "controller.d", "controller.d=nan"),
    ("impedance", "controller.k_rot", "controller.k_rot=-inf"),
    # condition_threshold > 1: one rule (config.schemas.CONDITION), was in five places
    ("impedance", "controller.condition_threshold", "controller.condition_threshold=1.0"),
    ("hqp", "controller.condition_threshold", "controller.condition_threshold=0.5"),
    ("se3_lie", "controller.condition_threshold", "controller.condition_threshold=1.0"),
    # the same rule as before, now in the schema's words (the QP level, the preload ramp,
    # the observer and the inertia floor held their own copies)
    ("hqp", "controller.K_min_ratio", "controller.K_min_ratio=1.5"),
    ("hqp", "controller.eps_abs", "controller.eps_abs=0"),
    ("hqp", "controller.preload_ramp_s", "controller.preload_ramp_s=0"),
    ("hqp", "controller.observer_kp", "controller.observer_kp=0"),
    ("hqp", "controller.K_ji", "controller.K_ji=[5,5,5,5,5,5,-1]"),
    ("impedance", "controller.m_rot", "controller.m_rot=0"),
    ("impedance", "controller.apparent_inertia_floor", "controller.apparent_inertia_floor=0"),
    ("se3_lie", "controller.null_damping", "controller.null_damping=nan"),
    ("se3_lie", "controller.A_diag", "controller.A_diag=[10,10,10,1,1,0]"),
    ("se3_lie", "controller.K_diag", "controller.K_diag=[50,50,-1,25,25,25]"),
    ("se3_lie", "controller.desired_wrench", "controller.desired_wrench=[0,0,0,0,0]"),
    ("se3_lie", "controller.apparent_inertia_floor", "controller.apparent_inertia_floor=0"),
    # a relation: the torque clip leaves room for the QP's accuracy (one function for both)
    ("hqp", "robot.max_torque", "controller.eps_abs=5"),
]


@pytest.fixture(scope="module")
def context():
    """A controller's context (the iiwa14 holding a pose in free space)."""
    return simulate.prepare(make_cfg(*FREE_SPACE, "task.progress=false")).controller.ctx


def _about(key: str, problem: str) -> bool:
    return problem.startswith((f"{key} ", f"{key}[", f"{key}: "))


@pytest.mark.parametrize("controller, key, override", CASES, ids=[f"{c}-{o}" for c, _, o in CASES])
def test_the_constructor_refuses_in_the_config_checks_words(context, controller, key, override):
    cfg = make_cfg(*FREE_SPACE, f"controller={controller}", override)
    refused = [p for p in check(cfg) if _about(key, p)]
    assert refused, f"the config check accepts {override}"
    given = dataclasses.replace(
        context,
        velocity_limits=np.asarray(cfg.robot.velocity_limits, dtype=float),
        torque_limits=np.asarray(cfg.robot.max_torque, dtype=float),
    )
    build = instantiate(cfg.controller, _partial_=True, _convert_="all")
    with pytest.raises(ValueError) as refusal:
        build(context=given)
    assert str(refusal.value) == " ".join(refused)


@pytest.mark.parametrize("controller", ["impedance", "hqp", "se3_lie"])
@pytest.mark.parametrize(
    "key, value",
    [
        ("integral_limit", "0"),
        ("integral_rot_limit", "0"),
        ("integral_freeze_force", "-1"),
        ("integral_rot_gain", "-1"),
    ],
)
def test_the_integral_refuses_in_the_config_checks_words(context, controller, key, value):
    """The integral action (built when a gain is on) held its own copy of these ranges."""
    cfg = make_cfg(
        *FREE_SPACE, f"controller={controller}", "controller.integral_gain=100", f"controller.{key}={value}"
    )
    refused = [p for p in check(cfg) if _about(f"controller.{key}", p)]
    assert refused, f"the config check accepts controller.{key}={value}"
    with pytest.raises(ValueError) as refusal:
        instantiate(cfg.controller, _partial_=True, _convert_="all")(context=context)
    assert str(refusal.value) == " ".join(refused)


def test_the_defaults_pass_both(context):
    """The check is not stricter than the config: every controller's defaults build."""
    for controller in ("impedance", "hqp", "se3_lie"):
        cfg = make_cfg(*FREE_SPACE, f"controller={controller}")
        assert not check(cfg)
        instantiate(cfg.controller, _partial_=True, _convert_="all")(context=context)


#: (the key refused, the overrides giving it a value outside its range or relation)
PLANNER_CASES = [
    # the tracking planner took any radius ≥ 0 and never looked at the centre's offset
    ("trajectory.circle_radius", ("trajectory=tracking", "trajectory.circle_radius=2")),
    ("trajectory.circle_center_offset", ("trajectory=tracking", "trajectory.circle_center_offset=5")),
    ("trajectory.figure8_frequency", ("trajectory=tracking", "trajectory.figure8_frequency=-1")),
    ("trajectory.duration", ("trajectory=hold", "trajectory.duration=0")),
    ("trajectory.lead_limit", ("trajectory=quintic", "trajectory.lead_limit=0")),
    ("trajectory.standoff", ("trajectory=twophase", "trajectory.standoff=-0.01")),
    ("trajectory.omega_max_docking", ("trajectory=se3topp", "trajectory.omega_max_docking=0")),
]
DOCKING = ("task.progress=false",)


@pytest.mark.parametrize("key, overrides", PLANNER_CASES, ids=[o[-1] for _, o in PLANNER_CASES])
def test_the_planner_refuses_in_the_config_checks_words(key, overrides):
    free = overrides[0] in ("trajectory=tracking", "trajectory=hold")
    cfg = make_cfg(*(FREE_SPACE[:1] + FREE_SPACE[2:] if free else DOCKING), *overrides)
    refused = [p for p in check(cfg) if _about(key, p)]
    assert refused, f"the config check accepts {overrides}"
    settings = sim_settings(cfg)
    with pytest.raises(ValueError) as refusal:
        simulate.plan(cfg.trajectory, settings.task, nominal_waypoints(settings))
    assert str(refusal.value) == " ".join(refused)


def test_the_press_is_refused_in_the_config_checks_words():
    """task.press_duration at most task.settle_time: one function for the check and the run."""
    cfg = make_cfg("task.press_duration=5", "task.settle_time=1")
    refused = [p for p in check(cfg) if _about("task.press_duration", p)]
    assert len(refused) == 1
    settings = sim_settings(cfg)
    with pytest.raises(ValueError) as refusal:
        simulate.plan(cfg.trajectory, settings.task, nominal_waypoints(settings))
    assert str(refusal.value) == refused[0]


@pytest.mark.parametrize("key", ["target.quat", "tool.mount_quat"])
def test_a_quaternion_is_refused_in_the_config_checks_words(key):
    cfg = make_cfg(f"{key}=[1,0,0,0.1]")
    refused = [p for p in check(cfg) if _about(key, p)]
    assert len(refused) == 1
    with pytest.raises(ValueError) as refusal:
        mount_placement([0.0, 0.0, 0.0], [1.0, 0.0, 0.0, 0.1], key)
    assert str(refusal.value) == refused[0]


def test_per_joint_lengths_are_one_rule():
    """The same function judges the lists against each other (the config alone) and against
    the robot's joints (preflight, the simulation): both name the odd list."""
    cfg = make_cfg("controller=hqp", "controller.K_ji=[5,5,5,5,5,5]")
    assert [p for p in check(cfg) if _about("controller.K_ji", p)] == [
        "controller.K_ji has 6 values; the other per-joint settings (robot.velocity_limits, "
        "robot.torque_limits, robot.max_torque, robot.ik_guess, controller.D_ji) have 7: "
        "give one value per joint."
    ]
    assert per_joint_problems(cfg, 7) == [
        "controller.K_ji has 6 values; robot iiwa14 has 7 joints: give one value per joint."
    ]
