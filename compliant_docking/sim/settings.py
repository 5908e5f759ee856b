"""The simulation's settings, typed: the one place where the composed config enters sim/.

:func:`sim_settings` turns the composed config (Hydra's DictConfig) into
:class:`SimSettings`, a frozen record of the schema's own dataclasses
(:mod:`compliant_docking.config.schemas`, :mod:`compliant_docking.config.robustness`),
made by ``OmegaConf.to_object`` once per run: ``settings.physics.timestep`` is a float,
``settings.physics.integrator`` an :class:`~compliant_docking.config.enums.Integrator`,
``settings.target.geometry`` a ``SocketGeometry``. The scene, the task, the sensor, the model
error, the contact draw and the misalignment draw take these objects; below this module
no code of sim/ reads a DictConfig by its keys. The controller and the planner get their
typed arguments the other way Hydra offers (``_target_`` + instantiate, in
:func:`compliant_docking.sim.simulate.prepare`).

The values are the composed config's: the schema's types are checked by Hydra at
composition, the ranges by the config check (:mod:`compliant_docking.config.validate`) and
by the constructors that call ``config.ranges.require``; nothing here checks them again.
The record is frozen; the schema's classes themselves are not (a frozen dataclass makes
OmegaConf mark the composed config read-only), but each run gets its own copies, so
nothing a run does to them reaches the config.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from omegaconf import DictConfig, OmegaConf
from omegaconf.errors import OmegaConfBaseException

from compliant_docking.config.robustness import DynamicsConfig, ModelErrorConfig, SensorConfig
from compliant_docking.config.schemas import (
    NoTargetConfig,
    PhysicsConfig,
    RobotConfig,
    TargetConfig,
    TaskConfig,
    ToolConfig,
)


@dataclass(frozen=True)
class SimSettings:
    """What the simulation reads of a run's config, as the schema's dataclasses."""

    robot: RobotConfig
    tool: ToolConfig  # or KeyedToolConfig
    target: TargetConfig | NoTargetConfig  # TargetConfig, KeyedTargetConfig, or none
    physics: PhysicsConfig
    task: TaskConfig
    sensor: SensorConfig | None = None  # None: the ideal sensors
    model_error: ModelErrorConfig | None = None  # None: the controller's model is exact
    dynamics: DynamicsConfig | None = None  # None: the target's contact as configured

    @property
    def socket(self) -> TargetConfig | None:
        """The target when it is a socket; None in free space (``target=none``)."""
        return self.target if isinstance(self.target, TargetConfig) else None


#: the nodes of the composed config the simulation reads, with their schemas; the last
#: three may be absent (a config built without them: ideal, exact, nominal)
_NODES: dict[str, tuple[type, ...]] = {
    "robot": (RobotConfig,),
    "tool": (ToolConfig,),
    "target": (TargetConfig, NoTargetConfig),
    "physics": (PhysicsConfig,),
    "task": (TaskConfig,),
    "sensor": (SensorConfig,),
    "model_error": (ModelErrorConfig,),
    "dynamics": (DynamicsConfig,),
}
_OPTIONAL = ("sensor", "model_error", "dynamics")


def sim_settings(cfg: DictConfig) -> SimSettings:
    """The typed settings of the composed config ``cfg`` (:func:`compliant_docking.config.load_config`,
    or the command line's). Raises ValueError, one paragraph naming the setting, for a node
    that is not its schema's (a config composed without the schemas) or a value left
    missing (``???``)."""
    from compliant_docking.config.validate import composition_problem

    nodes: dict[str, Any] = {}
    for name, schemas in _NODES.items():
        node = cfg.get(name)
        if node is None and name in _OPTIONAL:
            continue
        try:
            value = OmegaConf.to_object(node) if isinstance(node, DictConfig) else node
        except OmegaConfBaseException as exc:
            raise ValueError(composition_problem(exc)) from None
        if not isinstance(value, schemas):
            allowed = " or ".join(s.__name__ for s in schemas)
            raise ValueError(
                f"{name} must be a node of the composed config with the schema {allowed} "
                "(compose it with compliant_docking.config.load_config or the command line); "
                f"got {type(value).__name__}."
            )
        nodes[name] = value
    return SimSettings(**nodes)
