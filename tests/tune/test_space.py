"""The tuning study's search space, draws and objectives, without running anything."""

from __future__ import annotations

import math

import pytest
from omegaconf import OmegaConf
from optuna.distributions import CategoricalDistribution, FloatDistribution, IntDistribution

from compliant_docking.tune import objectives
from compliant_docking.tune.objectives import Draw, evaluate, resolve_metrics
from compliant_docking.tune.space import SearchSpaceError, expand_draws, format_value, parse_space

OBJECTIVE = OmegaConf.create(
    {
        "name": "mean_force",
        "metric": "first_strike_force_N",
        "fallback_metric": "peak_axial_force_N",
        "time_metric": "docking_time_s",
        "require_docking": True,
        "penalty": 1000.0,
    }
)


def test_hydra_sweeps_become_optuna_distributions():
    tuned, fixed = parse_space(
        {
            "controller.k": "tag(log, interval(100, 1000))",
            "controller.d": "interval(30, 300)",
            "controller.m": "2.0",  # plain: fixed
        },
        [
            "+experiment=tune",
            "controller.null_damping=int(interval(1, 8))",
            "controller.m_rot=range(0.5, 2.0, 0.5)",
            "controller.friction_comp=choice(torque, velocity)",
            "controller.d=40",  # the command line wins: d is fixed after all
        ],
    )
    space = {p.key: p.distribution for p in tuned}
    assert space["controller.k"] == FloatDistribution(100.0, 1000.0, log=True)
    assert space["controller.null_damping"] == IntDistribution(1, 8)
    assert space["controller.m_rot"] == FloatDistribution(0.5, 1.5, step=0.5)  # stop excluded
    assert space["controller.friction_comp"] == CategoricalDistribution(["torque", "velocity"])
    assert "controller.d" not in space
    assert fixed == ["controller.m=2.0", "+experiment=tune", "controller.d=40"]


def test_nested_keys_mean_the_same_key_and_values_format_as_overrides():
    tuned, _ = parse_space({"controller": {"k": "interval(1, 2)"}}, [])
    assert tuned[0].key == "controller.k"
    assert tuned[0].override(1.25) == "controller.k=1.25"
    assert format_value("torque") == "torque"
    assert format_value("a b") == "'a b'"
    assert format_value(True) == "true" and format_value(None) == "null"


@pytest.mark.parametrize(
    "line, message",
    [
        ("controller.k=glob(*)", "not a search space"),
        ("controller.k=tag(log, interval(0, 10))", "positive lower bound"),
        ("controller.k=interval(5, 1)", "low < high"),
    ],
)
def test_unusable_sweeps_are_refused_naming_the_key(line, message):
    with pytest.raises(SearchSpaceError, match=message):
        parse_space({}, [line])


def test_nothing_to_tune_is_refused():
    with pytest.raises(SearchSpaceError, match="nothing to tune"):
        parse_space({}, ["controller.k=300"])


def test_draws_are_the_combinations_and_may_not_be_tuned():
    tuned, _ = parse_space({"controller.k": "interval(1, 2)"}, [])
    draws = expand_draws({"task.misalignment.seed": "range(3)", "task.misalignment.x": "0,0.001"}, tuned)
    assert len(draws) == 6
    assert draws[0] == ["task.misalignment.seed=0", "task.misalignment.x=0"]
    assert expand_draws({}, tuned) == [[]]
    with pytest.raises(SearchSpaceError, match="is tuned as well"):
        expand_draws({"controller.k": "1,2"}, tuned)


# --------------------------------------------------------------------------- objectives
def record(success=True, force=10.0, time=14.0, status="ok", **extra) -> dict:
    return {
        "status": status,
        "success": success,
        "error": "simulation diverged" if status == "failed" else None,
        "gate_failures": None if success else "peak axial force 61 N > 50 N",
        "peak_axial_force_N": force,
        "docking_time_s": time,
        **extra,
    }


def test_the_first_strike_metric_falls_back_to_the_peak_while_it_is_not_a_metric():
    from compliant_docking.evaluation.registry import BY_KEY

    keys, notes = resolve_metrics(objectives.get("mean_force"), OBJECTIVE)
    if "first_strike_force_N" in BY_KEY:  # once the contact metrics land, no fallback
        assert keys == {"force": "first_strike_force_N"} and not notes
    else:
        assert keys == {"force": "peak_axial_force_N"}
        assert "fallback_metric=peak_axial_force_N" in notes[0]
    with pytest.raises(ValueError, match="objective.metric='nope' is not a metric"):
        resolve_metrics(
            objectives.get("mean_force"),
            OmegaConf.merge(OBJECTIVE, {"metric": "nope", "fallback_metric": None}),
        )
    with pytest.raises(ValueError, match="allowed: mean_force, worst_force, force_time"):
        objectives.get("fastest")


def test_a_trial_whose_draws_all_dock_scores_their_mean():
    keys = {"force": "peak_axial_force_N"}
    draws = [
        Draw("t_d0", record(force=10.0)),
        Draw("t_d1", record(force=20.0)),
        Draw("t_d2", record(force=33.0)),
    ]
    result = evaluate(objectives.get("mean_force"), draws, keys, OBJECTIVE)
    assert result.feasible and result.values == pytest.approx((21.0,))
    assert result.attrs["docked"] == 3 and result.attrs["force_per_draw"] == [10.0, 20.0, 33.0]
    worst = evaluate(objectives.get("worst_force"), draws, keys, OBJECTIVE)
    assert worst.values == (33.0,)
    both = evaluate(objectives.get("force_time"), draws, {**keys, "time": "docking_time_s"}, OBJECTIVE)
    assert both.values == pytest.approx((21.0, 14.0))


def test_failed_missing_and_undocked_draws_penalise_the_trial_by_their_share():
    keys = {"force": "peak_axial_force_N"}
    ok = Draw("t_d0", record(force=5.0))
    undocked = Draw("t_d1", record(success=False, force=61.0))
    failed = Draw("t_d2", record(status="failed", success=False, force=None))
    missing = Draw("t_d3", None, "no metrics.json (the job is still running, or its process died)")
    result = evaluate(objectives.get("mean_force"), [ok, undocked, failed, missing], keys, OBJECTIVE)
    assert not result.feasible
    assert result.values == pytest.approx((1000.0 * (1 + 3 / 4),))  # 3 of 4 draws do not count
    problems = result.attrs["problems"]
    assert problems[0].startswith("t_d1: not docked: peak axial force 61 N > 50 N")
    assert problems[1] == "t_d2: failed: simulation diverged"
    assert problems[2].startswith("t_d3: no metrics.json")
    # one bad draw of four is penalised less than three: the sampler sees a slope
    one_bad = evaluate(objectives.get("mean_force"), [ok, ok, ok, undocked], keys, OBJECTIVE)
    assert one_bad.values[0] == pytest.approx(1250.0)
    assert one_bad.values[0] < result.values[0]
    # every penalised trial is worse than any that counts, whatever its force
    assert (
        one_bad.values[0]
        > evaluate(objectives.get("mean_force"), [Draw("x", record(force=999.0))], keys, OBJECTIVE).values[0]
    )


def test_without_the_docking_requirement_an_undocked_draw_counts_but_a_nan_does_not():
    keys = {"force": "peak_axial_force_N"}
    relaxed = OmegaConf.merge(OBJECTIVE, {"require_docking": False})
    undocked = Draw("d1", record(success=False, force=61.0))
    result = evaluate(objectives.get("mean_force"), [Draw("d0", record(force=5.0)), undocked], keys, relaxed)
    assert result.feasible and result.values == pytest.approx((33.0,))
    nan = Draw("d2", record(force=math.nan))
    assert not evaluate(objectives.get("mean_force"), [nan], keys, relaxed).feasible
