"""Every bad value is refused before anything runs, naming its config key.

The cases are generated from the schemas: every numeric leaf of the composed config of
every option of every group (list items included) is set to NaN, to inf and to a value
just outside the range its schema field declares (compliant_docking/config/ranges.py), and
:func:`compliant_docking.config.validate.check` must refuse each, in a message that names
the key. A new numeric key is covered as soon as it exists: it must declare a range
(:func:`test_every_numeric_field_declares_a_range`) and then gets its three cases.
That the command line runs this check before Hydra writes a run or sweep directory is
tested end to end in tests/sweep/test_guard.py.
"""

from __future__ import annotations

import dataclasses
import math
import typing

import pytest
from omegaconf import DictConfig, ListConfig, OmegaConf
from omegaconf.errors import OmegaConfBaseException

from compliant_docking import CONF_DIR
from compliant_docking.config import env, geometry, schemas
from compliant_docking.config.memory import BYTES_PER_STEP, memory_problem
from compliant_docking.config.ranges import Range, field_range, show
from compliant_docking.config.store import _SCHEMAS, load_env_config
from compliant_docking.config.validate import ConfigError, check, settings_problems, validate
from tests.helpers import make_cfg, per_option

#: what an option needs beside it to make a config that runs (free-space options)
COMPANIONS = {
    ("tool", "keyed_plug"): ("target=keyed_socket",),
    ("target", "keyed_socket"): ("tool=keyed_plug",),
    ("target", "none"): ("trajectory=hold", "task.init_pos=[0.55,0,0.35]"),
    ("trajectory", "tracking"): ("target=none", "task=tracking"),
    ("task", "tracking"): ("target=none", "trajectory=tracking"),
}


def _options() -> list[tuple[str, str]]:
    groups = [(group, path.stem) for group in _SCHEMAS for path in sorted((CONF_DIR / group).glob("*.yaml"))]
    return [*groups, ("env", "docking")]  # the Gymnasium environment's settings, composed on their own


def _baseline(group: str, option: str) -> DictConfig:
    if group == "env":
        return load_env_config()
    return make_cfg(f"{group}={option}", *COMPANIONS.get((group, option), ()))


def _check(cfg: DictConfig, group: str) -> list[str]:
    return settings_problems(cfg, "env") if group == "env" else check(cfg)


# --------------------------------------------------------------------------- the declarations
def _is_numeric(annotation) -> bool:
    """float, int, List[float], Optional[...], tuple[float, ...] (bool is not a number here)."""
    if annotation in (float, int):
        return True
    return any(_is_numeric(arg) for arg in typing.get_args(annotation) if arg is not type(None))


def _schema_classes() -> list[type]:
    return [
        obj
        for module in (schemas, geometry, env)
        for obj in vars(module).values()
        if dataclasses.is_dataclass(obj) and obj.__module__ == module.__name__
    ]


@pytest.mark.parametrize("cls", _schema_classes(), ids=lambda c: c.__name__)
def test_every_numeric_field_declares_a_range(cls):
    hints = typing.get_type_hints(cls)
    undeclared = [
        f.name for f in dataclasses.fields(cls) if _is_numeric(hints[f.name]) and field_range(f) is None
    ]
    assert not undeclared, (
        f"{cls.__name__}: {undeclared} are numbers without a declared range; declare one "
        "(compliant_docking/config/ranges.py: positive(), within(...), …)"
    )


def test_the_range_check_sees_an_undeclared_number():
    """The declaration check can fail: a plain MISSING number is flagged."""

    @dataclasses.dataclass
    class Plain:
        k: float = dataclasses.field(default=None)  # type: ignore[assignment]

    assert (
        _is_numeric(typing.get_type_hints(Plain)["k"]) and field_range(dataclasses.fields(Plain)[0]) is None
    )


@pytest.mark.parametrize(
    ("rng", "inside", "outside", "text"),
    [
        (Range(0.0, 0.01, low_open=True, unit="s"), [1e-9, 0.01], [0.0, 0.011, -1.0], "in (0, 0.01] s"),
        (Range(0.0, math.inf, low_open=True), [1e-300, 1e300], [0.0, -1e-9], "> 0"),
        (Range(12, 128, integer=True), [12, 128], [11, 129, 12.5], "an integer in [12, 128]"),
        (Range(integer=True, choices=(1.0, 3.0, 4.0, 6.0)), [1, 6], [2, 0], "one of 1, 3, 4, 6"),
    ],
)
def test_a_range_holds_what_it_says(rng, inside, outside, text):
    assert all(rng.contains(v) for v in inside)
    assert not any(rng.contains(v) for v in outside)
    assert not rng.contains(rng.outside())
    assert text in rng.describe()


# --------------------------------------------------------------------------- generated cases
def _leaves(node: DictConfig, prefix: str):
    """(key, container, index or name, range, size of a null list) of every numeric leaf."""
    fields = {f.name: f for f in dataclasses.fields(OmegaConf.get_type(node))}
    for name in node:
        child = node._get_node(name)
        if isinstance(child, DictConfig):
            yield from _leaves(node[name], f"{prefix}.{name}")
            continue
        rng = field_range(fields[str(name)])
        if rng is None:
            continue
        value = node[name]
        if isinstance(value, ListConfig):
            for i in range(len(value)):
                yield f"{prefix}.{name}[{i}]", value, i, rng.at(i), None
        else:
            yield f"{prefix}.{name}", node, name, rng, rng.size if value is None else None


def _bad_values(rng: Range) -> list[float]:
    outside = rng.outside()
    return [math.nan, math.inf] + ([outside] if outside is not None else [])


def _set(container, index, key: str, value, failures: list[str]) -> bool:
    """Put ``value`` at ``container[index]``; an int field refuses NaN/inf/fractions at
    assignment (as at composition), which must name the key: then False."""
    try:
        container[index] = value
    except OmegaConfBaseException as exc:
        if key.split("[")[0] not in str(exc):
            failures.append(f"{key}={show(value)}: the type error does not name the key: {exc}")
        return False
    return True


def _judge(key: str, value, bad: float, problems: list[str], failures: list[str]) -> None:
    named = [p for p in problems if key.split("[")[0] in p]
    if not named:
        failures.append(f"{key}={show(value)}: not refused, or not by name: {problems}")
    elif not any(show(bad) in p for p in named):
        failures.append(f"{key}={show(value)}: the message does not show the value: {named}")


def _refusals(group: str, option: str, one_at_a_time: bool) -> tuple[int, list[str]]:
    """Set every numeric leaf of ``group`` to NaN, to inf and to a value just outside its
    range, and collect what the check does not refuse by name with the value shown.

    ``one_at_a_time``: one bad leaf per check (the rest of the config sound). Otherwise one
    check per kind of bad value with every leaf bad at once: the range check walks every
    leaf and reports each (a refusal lists every problem), so each leaf must still be named
    with its own value. Every value is restored afterwards (checked)."""
    cfg = _baseline(group, option)
    assert _check(cfg, group) == [], (
        f"conf/{group}/{option}.yaml (with {COMPANIONS.get((group, option))}) is refused"
    )
    leaves = list(_leaves(cfg[group], group))
    saved = [container._get_node(index)._value() for _, container, index, _, _ in leaves]  # raw
    failures: list[str] = []
    cases = 0
    for kind in range(3):  # NaN, inf, just outside
        placed = []
        for (key, container, index, rng, null_size), keep in zip(leaves, saved, strict=True):
            bads = _bad_values(rng)
            if kind >= len(bads):  # no value outside an unbounded range
                continue
            bad = bads[kind]
            value = [bad] * null_size if null_size else bad
            cases += 1
            if not _set(container, index, key, value, failures):
                continue
            if one_at_a_time:
                try:
                    _judge(key, value, bad, _check(cfg, group), failures)
                finally:
                    container[index] = keep
            else:
                placed.append((key, value, bad))
        if placed:
            problems = _check(cfg, group)
            for (_, container, index, _, _), keep in zip(leaves, saved, strict=True):
                container[index] = keep
            for key, value, bad in placed:
                _judge(key, value, bad, problems, failures)
    assert _check(cfg, group) == []  # every value restored
    schema = OmegaConf.get_type(cfg[group])
    assert cases > 0 or not any(
        field_range(f) for f in dataclasses.fields(schema)
    )  # target=none, render=none
    return cases, failures


@pytest.mark.parametrize(("group", "option"), per_option(_options()))
def test_every_numeric_leaf_refuses_nan_inf_and_out_of_range(group, option):
    cases, failures = _refusals(group, option, one_at_a_time=False)
    assert not failures, f"{len(failures)} of {cases} cases:\n" + "\n".join(failures)


@pytest.mark.parametrize(("group", "option"), [("task", "docking"), ("controller", "hqp")])
def test_a_single_bad_leaf_is_refused_alone(group, option):
    """The same cases, one bad leaf per check, on the options with the most leaves (nested
    nodes, lists, per-joint lists, null lists): nothing in the check needs a second bad
    value to see the first."""
    cases, failures = _refusals(group, option, one_at_a_time=True)
    assert not failures, f"{len(failures)} of {cases} cases:\n" + "\n".join(failures)


def test_the_batch_judge_sees_a_leaf_the_check_misses(monkeypatch):
    """The batch form can fail: a check that drops one key's problem is caught."""
    from tests.config import test_validate as this

    real = this._check

    def blind(cfg, group):
        return [p for p in real(cfg, group) if "controller.null_damping" not in p]

    monkeypatch.setattr(this, "_check", blind)
    _, failures = _refusals("controller", "impedance", one_at_a_time=False)
    assert failures and all("controller.null_damping" in f for f in failures)


# --------------------------------------------------------------------------- keys
@pytest.mark.parametrize(
    ("override", "named", "suggested"),
    [
        ("+physcs.timestep=0.002", "physcs.timestep", "physics.timestep"),
        ("++physics.timstep=0.002", "physics.timstep", "physics.timestep"),
        ("+controller.kk=1", "controller.kk", "controller.k"),
        ("++task.gate.depth_tolerance=0.1", "task.gate.depth_tolerance", "task.gate.depth_tolerance_m"),
        ("+target.geometry.radial_clearence=1e-3", "radial_clearence", "target.geometry.radial_clearance"),
        ("+tool.geometry.extra.depth=1", "tool.geometry.extra.depth", "tool.geometry.radius"),
    ],
)
def test_misspelled_keys_added_with_plus_are_refused_with_the_nearest_keys(override, named, suggested):
    problems = check(make_cfg(override))
    assert len(problems) == 1, problems
    assert named in problems[0] and suggested in problems[0]
    assert "Config" not in problems[0] and "Geometry" not in problems[0]  # keys, not class names


@pytest.mark.parametrize(
    "overrides",
    [
        ("+experiment=controller_comparison",),
        ("+experiment=clearance",),
        ("+experiment=misalignment",),
        ("+experiment=misalignment_keyed",),
        ("+experiment=jamming_map",),
        ("+experiment=tracking_gate", "robot=fr3"),
        ("physics=earth", "controller=hqp", "robot=fr3"),
        ("render=video",),
    ],
)
def test_legitimate_appends_and_presets_pass(overrides):
    assert check(make_cfg(*overrides)) == []


# --------------------------------------------------------------------------- relations, memory
@pytest.mark.parametrize(
    ("overrides", "message"),
    [
        (("robot.max_torque=[1,1]",), "robot.max_torque has 2 values"),
        (("controller=hqp", "controller.K_ji=[1,1,1]"), "controller.K_ji has 3 values"),
        (("target.quat=[1,0,0,0.1]",), "target.quat must be a unit quaternion"),
        (("task.stroke=[0,0,0]",), "task.stroke must be a non-zero vector"),
        (("task.press_duration=5",), "task.press_duration must be at most task.settle_time"),
        (("task.misalignment.x=0.001", "task.misalignment.x_range=[0,0.002]"), "are both set"),
        (("task.misalignment.x_range=[0.002,0.001]",), "low <= high"),
        (
            ("sensor=wrist_ft", "sensor.rate_hz=300"),
            "sensor.rate_hz must make the sample period a whole number",
        ),
        (
            ("sensor=wrist_ft", "sensor.cutoff_hz=600"),
            "sensor.cutoff_hz must be at most the Nyquist frequency",
        ),
        (
            ("sensor=wrist_ft", "sensor.delay_s=0.0015"),
            "sensor.delay_s must be a whole number of physics.timestep",
        ),
        (("model_error=drawn", "model_error.link_mass_scale_range=[1.02,0.98]"), "low <= high"),
        (("model_error=drawn", "model_error.link_mass_scale=1.1"), "are both set"),
        (("dynamics=randomised", "target=none", "trajectory=hold"), "need a socket"),
        (("target.geometry.radial_clearance=0.02",), "target.geometry.radial_clearance must be > 0 and <"),
        (("tool.geometry.chamfer_length=0.02",), "tool.geometry.chamfer_length must be at most"),
        (("tool.geometry.length=0.02",), "tool.geometry.length must be longer than target.geometry"),
        (("target.contact.solimp=[0.99,0.95,0.001,0.5,2]",), "target.contact.solimp must have dmin <= dmax"),
        (("target=none", "trajectory=hold"), "task.init_pos must be set"),
        (("tool=keyed_plug",), "tool=keyed_plug and target=cone_socket are not a mating pair"),
        (
            ("tool=keyed_plug", "target.geometry.plug_radius=0.01"),
            "tool=keyed_plug and target=cone_socket are not a mating pair",
        ),
        (
            ("tool=keyed_plug", "target=keyed_socket", "target.geometry.sides=6"),
            "target.geometry.sides must equal",
        ),
        (
            ("tool=keyed_plug", "target=keyed_socket", "target.geometry.clearance=0.02"),
            "target.geometry.clearance must be",
        ),
    ],
)
def test_relations_between_settings_are_checked_by_key(overrides, message):
    problems = check(make_cfg(*overrides))
    assert any(message in p for p in problems), problems


def test_a_run_whose_logs_do_not_fit_in_memory_is_refused_with_the_estimate():
    cfg = make_cfg("task.duration=1e9")
    problem = memory_problem(cfg, available=8 * 10**9)
    assert "1e+12 steps" in problem and "task.duration = 1e+09 s" in problem
    assert "2 PB" in problem and "8 GB available" in problem  # BYTES_PER_STEP = 2 kB
    assert BYTES_PER_STEP == 2000
    # the default run (18 000 steps, 36 MB) fits; the trajectory's duration counts when
    # task.duration is null
    assert memory_problem(make_cfg(), available=8 * 10**9) is None
    long = memory_problem(make_cfg("trajectory.duration=1e7"), available=8 * 10**9)
    assert "trajectory.duration + task.settle_time" in long
    with pytest.raises(ConfigError, match="logs would need about"):
        validate(make_cfg("task.duration=1e9"))


def test_a_refusal_is_one_paragraph_per_problem():
    with pytest.raises(ConfigError) as caught:
        validate(make_cfg("physics.timestep=0", "controller.k=nan"))
    error = caught.value
    assert len(error.problems) == 2 and all("\n" not in p for p in error.problems)
    assert error.report().splitlines()[0].endswith("nothing was run or written.")
    assert "physics.timestep must be a finite number in (0, 0.01] s; got 0.0." in error.problems
    assert "n/a" not in error.report()
