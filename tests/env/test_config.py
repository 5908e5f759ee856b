"""The environment's spaces and settings: what make_env builds from a run's overrides and env.*."""

from __future__ import annotations

import math

import numpy as np
import pytest

from compliant_docking.config.validate import ConfigError
from compliant_docking.env import DockingEnv, make_env, observation_names
from compliant_docking.env.docking import split_overrides

SHORT = ("trajectory.duration=1", "task.settle_time=1", "task.progress=false")


def test_overrides_split_into_the_run_and_the_environment():
    run, env = split_overrides(["robot=fr3", "env.policy_step=0.02", "+env.x=1", "controller.k=100"])
    assert run == ["robot=fr3", "controller.k=100"]
    assert env == ["env.policy_step=0.02", "+env.x=1"]


def test_the_spaces_follow_the_action_kind_and_the_arm():
    names = observation_names(7)
    assert len(names) == 2 * 7 + 7 * 3 + 1 and names[14:17] == ["x", "y", "z"] and names[-1] == "phase"
    for overrides, size in (
        ((), 9),  # pose offset (6) + stiffness scales (3)
        (("env.action.gains=false",), 6),
        (("env.action.kind=torque",), 7),
    ):
        env = make_env(*SHORT, *overrides)
        assert env.action_space.shape == (size,)
        assert np.all(env.action_space.low == -1.0) and np.all(env.action_space.high == 1.0)
        assert env.observation_space.shape == (len(names),) and env.observation_space.dtype == np.float32


def test_the_environment_settings_come_from_their_overrides():
    env = make_env(*SHORT, "env.policy_step=0.02", "env.reward.success=3", "robot=fr3")
    assert env.policy_steps == 20 and env.weights.success == 3.0
    assert env.cfg.robot.name == "fr3" and "env" not in env.cfg  # a run's config has no env node


@pytest.mark.parametrize(
    ("overrides", "named"),
    [
        (("env.policy_step=0.0105",), "env.policy_step must be a whole multiple of physics.timestep"),
        (("env.policy_step=nan",), "env.policy_step"),
        (("env.reward.force=-1",), "env.reward.force must be a finite number >= 0; got -1.0"),
        (("env.action.max_stiffness_scale=0.5",), "env.action.max_stiffness_scale"),
        (("env.polcy_step=0.01",), "env.polcy_step"),
        (("env.action.kind=residual",), "env.action.kind"),
        (("controller=hqp",), "env.action.gains = true needs a controller whose stiffness"),
        (("target=none", "trajectory=hold", "task.init_pos=[0.55,0,0.35]"), "target=none has none"),
        (("controller.k=-1",), "controller.k"),
    ],
)
def test_bad_settings_are_refused_by_key(overrides, named):
    with pytest.raises((ConfigError, ValueError)) as err:
        make_env(*SHORT, *overrides)
    assert named in str(err.value)


def test_controllers_without_scalable_gains_take_pose_offsets_or_torques():
    assert make_env(*SHORT, "controller=hqp", "env.action.gains=false").action_space.shape == (6,)
    assert make_env(*SHORT, "controller=se3_lie", "env.action.kind=torque").action_space.shape == (7,)


def test_a_run_config_and_settings_composed_elsewhere_are_taken_as_given():
    env = make_env(*SHORT)
    again = DockingEnv(cfg=env.cfg, settings=env.settings)
    assert again.policy_steps == env.policy_steps == round(0.01 / 0.001)
    assert math.isclose(again.dt, 0.001)


def test_the_settings_file_sets_every_field_of_its_schema():
    from omegaconf import OmegaConf

    from compliant_docking.config.store import load_env_config

    assert not OmegaConf.missing_keys(load_env_config().env)
