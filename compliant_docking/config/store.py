"""Registration of the typed schemas in Hydra's ConfigStore, and composing a config in Python.

Every YAML option under ``conf/<group>/`` starts its defaults list with the schema of its
group (``- /schema/<group>@_here_: <schema>``); :func:`register_schemas` stores them under
``schema/<group>``. :func:`load_config` composes a config exactly as the command line does,
for scripts, notebooks and tests.
"""

from __future__ import annotations

from hydra.core.config_store import ConfigStore
from omegaconf import DictConfig

from compliant_docking import CONF_DIR
from compliant_docking.config.env import EnvConfig
from compliant_docking.config.geometry import ContactParams, PlugGeometry, SocketGeometry
from compliant_docking.config.hydra_adapter import install as install_compose_cache
from compliant_docking.config.keyed import KeyedPlugGeometry, KeyedSocketGeometry
from compliant_docking.config.robustness import DynamicsConfig, ModelErrorConfig, SensorConfig
from compliant_docking.config.schemas import (
    Config,
    HoldConfig,
    HQPConfig,
    ImpedanceConfig,
    KeyedTargetConfig,
    KeyedToolConfig,
    NoRenderConfig,
    NoTargetConfig,
    PhysicsConfig,
    QuinticConfig,
    RenderConfig,
    RobotConfig,
    SE3LieConfig,
    SE3ToppConfig,
    TargetConfig,
    TaskConfig,
    ToolConfig,
    TrackingConfig,
    TwoPhaseConfig,
)
from compliant_docking.config.tuning import TuningSweeperConfig

_SCHEMAS: dict[str, dict[str, type]] = {
    "robot": {"robot": RobotConfig},
    "tool": {"tool": ToolConfig, "keyed": KeyedToolConfig},
    "target": {"socket": TargetConfig, "keyed": KeyedTargetConfig, "none": NoTargetConfig},
    "physics": {"physics": PhysicsConfig},
    "controller": {"impedance": ImpedanceConfig, "hqp": HQPConfig, "se3_lie": SE3LieConfig},
    "trajectory": {
        "quintic": QuinticConfig,
        "hold": HoldConfig,
        "twophase": TwoPhaseConfig,
        "se3topp": SE3ToppConfig,
        "tracking": TrackingConfig,
    },
    "task": {"task": TaskConfig},
    "render": {"none": NoRenderConfig, "video": RenderConfig},
    "sensor": {"sensor": SensorConfig},
    "model_error": {"model_error": ModelErrorConfig},
    "dynamics": {"dynamics": DynamicsConfig},
}


def _every_schema() -> list[tuple[str | None, str, type]]:
    """(group, name, dataclass) of every schema :func:`register_schemas` stores."""
    return [
        (None, "base_config", Config),
        *(
            (f"schema/{group}", name, node)
            for group, schemas in _SCHEMAS.items()
            for name, node in schemas.items()
        ),
        # conf/env/docking.yaml: the Gymnasium environment's keys (load_env_config)
        ("schema/env", "env", EnvConfig),
        # hydra/sweeper=optuna (conf/hydra/sweeper/optuna.yaml): the tuning sweeper's keys
        ("schema/sweeper", "optuna", TuningSweeperConfig),
    ]


def register_schemas() -> None:
    """Store every schema in Hydra's ConfigStore (idempotent).

    Storing converts each dataclass into a typed config (~50 ms in all), so a schema the
    store already holds under its name is not stored again: :func:`load_config` calls this
    at every composition. The schemas of the submitit launcher presets are registered by
    the command line (:func:`compliant_docking.sweep.launchers.register_schemas`): they
    belong to sweeps.
    """
    cs = ConfigStore.instance()
    held: dict[str | None, list[str]] = {}
    for group, name, node in _every_schema():
        if group not in held:
            try:
                held[group] = cs.list(group or "")
            except OSError:  # a group not stored yet
                held[group] = []
        if f"{name}.yaml" not in held[group]:
            cs.store(group=group, name=name, node=node)


def load_config(*overrides: str) -> DictConfig:
    """The composed config for these overrides, exactly as the command line builds it.

    For scripts, notebooks and tests: ``sim.simulate.prepare(load_config("robot=fr3"))``.
    """
    from hydra import compose, initialize_config_dir
    from hydra.core.global_hydra import GlobalHydra

    install_compose_cache()  # repeated compositions reuse the parsed files and merged trees
    register_schemas()
    GlobalHydra.instance().clear()
    with initialize_config_dir(config_dir=str(CONF_DIR), version_base="1.3"):
        return compose(config_name="config", overrides=list(overrides))


def load_env_config(*overrides: str) -> DictConfig:
    """The Gymnasium environment's settings (conf/env/docking.yaml) with ``overrides``
    (``"env.policy_step=0.02"``), as a config whose one node is ``env``.

    Composed on their own, not into a run's config: a run has no ``env`` node, so the run
    directory of an episode holds a run's config. :func:`compliant_docking.env.make_env`
    sends the ``env.*`` overrides here and the others to :func:`load_config`.
    """
    from hydra import compose, initialize_config_dir
    from hydra.core.global_hydra import GlobalHydra

    install_compose_cache()
    register_schemas()
    GlobalHydra.instance().clear()
    with initialize_config_dir(config_dir=str(CONF_DIR), version_base="1.3"):
        return compose(config_name="env/docking", overrides=list(overrides))


def default_interface() -> tuple[PlugGeometry, SocketGeometry, ContactParams]:
    """The default plug, socket and contact parameters, as conf/tool/cone_plug.yaml and
    conf/target/cone_socket.yaml set them (their one home), for scripts and tests that
    build the interface without a run: ``dataclasses.replace(socket, sectors=12)``."""
    from omegaconf import OmegaConf

    cfg = load_config()
    return (
        OmegaConf.to_object(cfg.tool.geometry),
        OmegaConf.to_object(cfg.target.geometry),  # type: ignore[return-value]
        OmegaConf.to_object(cfg.target.contact),
    )


def default_keyed(*overrides: str) -> tuple[KeyedPlugGeometry, KeyedSocketGeometry, ContactParams]:
    """The keyed plug, socket and contact parameters as conf/tool/keyed_plug.yaml and
    conf/target/keyed_socket.yaml set them, with ``overrides`` (e.g.
    ``"tool.geometry.sides=6"``: the socket follows the plug's sides and inradius)."""
    from omegaconf import OmegaConf

    cfg = load_config("tool=keyed_plug", "target=keyed_socket", *overrides)
    return (
        OmegaConf.to_object(cfg.tool.geometry),
        OmegaConf.to_object(cfg.target.geometry),  # type: ignore[return-value]
        OmegaConf.to_object(cfg.target.contact),
    )
