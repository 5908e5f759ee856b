"""The docking task as a Gymnasium environment: ``CompliantDocking-v0`` (docs/env.md).

    from compliant_docking.env import make_env
    env = make_env("robot=fr3", "controller=impedance", "env.policy_step=0.02")

or, once this package is imported, ``gymnasium.make("CompliantDocking-v0", overrides=[...])``
(``gymnasium.make("compliant_docking.env:CompliantDocking-v0", ...)`` imports it first).
Needs gymnasium: the ``env`` extra.
"""

from __future__ import annotations

from compliant_docking.extras import require

require("env", "gymnasium")

import gymnasium  # noqa: E402

from compliant_docking.env.docking import ENV_ID, DockingEnv, compose  # noqa: E402
from compliant_docking.env.observation import observation_names  # noqa: E402


def make_env(*overrides: str) -> DockingEnv:
    """The environment for these overrides: a run's (``robot=fr3``, ``task.misalignment.x_range=[…]``)
    and the environment's (``env.policy_step=0.02``), as on the command line."""
    return DockingEnv(overrides)


if ENV_ID not in gymnasium.registry:
    gymnasium.register(id=ENV_ID, entry_point="compliant_docking.env.docking:DockingEnv")

__all__ = ["ENV_ID", "DockingEnv", "compose", "make_env", "observation_names"]
