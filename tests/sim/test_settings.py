"""The simulation's typed settings (compliant_docking/sim/settings.py): the one place where
the composed config enters sim/, as the schema's own dataclasses."""

from __future__ import annotations

import ast
import dataclasses
from pathlib import Path

import numpy as np
import pytest
from omegaconf import MISSING, OmegaConf
from omegaconf.errors import ValidationError

import compliant_docking
from compliant_docking.config.enums import Integrator
from compliant_docking.config.geometry import ContactParams, SocketGeometry
from compliant_docking.config.robustness import ModelErrorConfig, SensorConfig
from compliant_docking.config.schemas import MisalignmentConfig, PhysicsConfig
from compliant_docking.config.validate import check, composition_problem
from compliant_docking.sim.settings import sim_settings
from compliant_docking.sim.simulate import prepare
from tests.helpers import make_cfg

#: the package, and the modules of sim/ that may hold the composed config: the boundary and prepare()
PACKAGE_DIR = Path(compliant_docking.__file__).parent
BOUNDARY = ("settings.py", "simulate.py")


def test_the_settings_are_the_schemas_dataclasses_made_once_from_the_config():
    cfg = make_cfg("physics.integrator=rk4", "sensor.delay_s=0.003")
    settings = sim_settings(cfg)
    assert isinstance(settings.physics, PhysicsConfig) and settings.physics.integrator is Integrator.rk4
    assert isinstance(settings.target.geometry, SocketGeometry)
    assert isinstance(settings.target.contact, ContactParams)
    assert isinstance(settings.task.misalignment, MisalignmentConfig)
    assert isinstance(settings.sensor, SensorConfig) and settings.sensor.delay_s == 0.003
    assert isinstance(settings.model_error, ModelErrorConfig)
    # the groups' seeds follow task.misalignment.seed (an interpolation, resolved)
    assert settings.sensor.seed == settings.task.misalignment.seed == cfg.task.misalignment.seed
    with pytest.raises(dataclasses.FrozenInstanceError):
        settings.physics = settings.physics  # type: ignore[misc]
    settings.physics.iterations = 1  # the run's own copy: the config keeps its value
    assert cfg.physics.iterations != 1


def test_a_setting_reaches_the_simulation_under_its_typed_name():
    """Each group the simulation reads, changed in the config, changes what is built."""
    sim = prepare(
        make_cfg(
            "physics.iterations=37",
            "task.misalignment.x=0.002",
            "model_error.friction_scale=1.5",
            "sensor.delay_s=0.003",
            "task.progress=false",
        )
    )
    assert sim.settings.physics.iterations == 37 and sim.scene.model.opt.iterations == 37
    assert sim.scene.socket is not None and sim.scene.socket.misalignment.x == 0.002
    friction = sim.controller.ctx.joint_friction  # type: ignore[attr-defined]
    np.testing.assert_array_equal(friction, sim.scene.model.dof_frictionloss * 1.5)
    assert sim.sensing is not None and sim.sensing.model.delay == 3  # 3 ms at 1 kHz


def test_a_value_out_of_its_range_is_refused_in_the_config_checks_words():
    """The ranges stay the schema's: the simulation refuses with the config check's sentence."""
    cfg = make_cfg("task.misalignment.tilt_deg=75")
    [refused] = [p for p in check(cfg) if p.startswith("task.misalignment.tilt_deg ")]
    with pytest.raises(ValueError) as refusal:
        prepare(cfg)
    assert str(refusal.value) == refused
    assert refused == "task.misalignment.tilt_deg must be a finite number in (-60, 60) deg; got 75.0."


def test_a_value_of_the_wrong_type_never_reaches_the_settings():
    """The schema's types are checked where the config is made: composition and assignment
    refuse a wrong type, naming the key in one paragraph."""
    with pytest.raises(Exception) as refusal:
        make_cfg("physics.iterations=many")
    message = composition_problem(refusal.value)
    assert message == "physics.iterations: Value 'many' of type 'str' could not be converted to Integer."
    cfg = make_cfg()
    with pytest.raises(ValidationError, match="physics.iterations"):
        cfg.physics.iterations = "many"


def test_a_config_without_the_schemas_or_with_a_missing_value_is_refused_naming_it():
    untyped = OmegaConf.create(OmegaConf.to_container(make_cfg(), resolve=True))
    with pytest.raises(ValueError) as refusal:
        sim_settings(untyped)
    assert str(refusal.value).startswith(
        "robot must be a node of the composed config with the schema RobotConfig"
    )
    assert str(refusal.value).endswith("; got dict.")
    cfg = make_cfg()
    cfg.physics.timestep = MISSING
    with pytest.raises(ValueError) as refusal:
        sim_settings(cfg)
    assert str(refusal.value).startswith("physics.timestep: ") and "\n" not in str(refusal.value)


def test_below_the_boundary_no_module_of_sim_reads_the_composed_config():
    """Only sim/settings.py (the conversion) and sim/simulate.py (prepare: instantiation and
    the config's own checks) import omegaconf; every other module reads typed settings."""
    readers = []
    for path in sorted((PACKAGE_DIR / "sim").rglob("*.py")):
        if path.parent.name == "sim" and path.name in BOUNDARY:
            continue
        for node in ast.walk(ast.parse(path.read_text())):
            names = []
            if isinstance(node, ast.Import):
                names = [alias.name for alias in node.names]
            elif isinstance(node, ast.ImportFrom) and node.module:
                names = [node.module]
            if any(name.split(".")[0] == "omegaconf" for name in names):
                readers.append(str(path.relative_to(PACKAGE_DIR)))
    assert readers == []
