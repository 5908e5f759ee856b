"""One home per default: the YAML options under conf/ (they carry units and reasons).

The typed schemas carry no values (every field MISSING: they give types and allowed
values only), every option of every group sets every field of its schema, and the
classes the options name with ``_target_`` take every config parameter without a
keyword default. A value written in two places can then not drift apart.
"""

from __future__ import annotations

import dataclasses
import inspect

import pytest
from hydra.utils import get_class
from omegaconf import MISSING, OmegaConf

from compliant_docking import CONF_DIR
from compliant_docking.config import env, geometry, keyed, schemas, tuning
from compliant_docking.config.store import _SCHEMAS
from tests.helpers import make_cfg, per_option

#: parameters a class may default: not config values (programmatic use only)
PROGRAMMATIC = {"SE3LieController": {"A", "D", "K"}}


def _dataclasses(module) -> list[type]:
    return [
        obj
        for obj in vars(module).values()
        if dataclasses.is_dataclass(obj) and obj.__module__ == module.__name__
    ]


@pytest.mark.parametrize(
    "cls",
    _dataclasses(schemas)
    + _dataclasses(geometry)
    + _dataclasses(keyed)
    + _dataclasses(tuning)
    + _dataclasses(env),
    ids=lambda c: c.__name__,
)
def test_schemas_carry_no_values(cls):
    valued = [
        f.name
        for f in dataclasses.fields(cls)
        if f.default is not MISSING or f.default_factory is not dataclasses.MISSING
    ]
    assert not valued, f"{cls.__name__} has defaults for {valued}: put them in the YAML under conf/"


def _options() -> list[tuple[str, str]]:
    return [(group, path.stem) for group in _SCHEMAS for path in sorted((CONF_DIR / group).glob("*.yaml"))]


#: options whose values interpolate another group's option (the keyed socket follows the
#: keyed plug's sides and inradius): composed with it
PAIRED = {("target", "keyed_socket"): ("tool=keyed_plug",)}


@pytest.mark.parametrize(("group", "option"), per_option(_options()))
def test_every_option_sets_every_field_of_its_schema(group, option):
    cfg = make_cfg(f"{group}={option}", *PAIRED.get((group, option), ()))
    missing = sorted(OmegaConf.missing_keys(cfg[group]))
    assert not missing, f"conf/{group}/{option}.yaml leaves {missing} unset"


@pytest.mark.parametrize(
    ("group", "option"), per_option([o for o in _options() if o[0] in ("controller", "trajectory")])
)
def test_targets_take_every_parameter_from_the_config(group, option):
    node = make_cfg(f"{group}={option}")[group]
    cls = get_class(node._target_)
    allowed = PROGRAMMATIC.get(cls.__name__, set())
    defaulted = []
    for klass in cls.__mro__:
        init = vars(klass).get("__init__")
        if init is None:
            continue
        defaulted += [
            name
            for name, p in inspect.signature(init).parameters.items()
            if p.default is not inspect.Parameter.empty and name not in allowed and name in node
        ]
    assert not defaulted, (
        f"{cls.__name__} defaults {defaulted}: the value belongs to conf/{group}/{option}.yaml"
    )


def test_the_check_sees_a_schema_default():
    """The first check can fail: a dataclass with a default is flagged."""

    @dataclasses.dataclass
    class WithDefault:
        k: float = 50.0

    assert [f.name for f in dataclasses.fields(WithDefault) if f.default is not MISSING] == ["k"]
