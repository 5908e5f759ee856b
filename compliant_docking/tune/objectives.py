"""What a tuning trial scores: the objectives, and the judgement of a trial's draws.

A trial runs the same job once per draw (``hydra.sweeper.draws``: e.g. four seeded
misalignments of the socket). :func:`evaluate` reads the draws' ``metrics.json`` records
and gives the trial its values:

- a draw **counts** when its job finished (status not ``failed``), docked (its gate
  passed; unless ``objective.require_docking`` is false) and reported every metric the
  objective reads;
- when every draw counts, the objective's ``score`` turns the draws' metrics into the
  trial's values (e.g. the mean first-strike force);
- otherwise the trial is **penalised**: each value is ``penalty × (1 + share of draws
  that do not count)``, worse than any trial that counts and graded so that the sampler
  still learns which region is less bad. Penalised trials are told to Optuna as complete
  trials (a failed state would hide them from the sampler) and recorded with the reasons.

Adding an objective is one :class:`Objective` in :data:`OBJECTIVES` (docs/tuning.md).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from statistics import fmean
from typing import Any

#: roles of the metrics an objective reads → the objective config key naming the metric
METRIC_ROLES = {"force": "metric", "time": "time_metric"}


@dataclass(frozen=True)
class Objective:
    """One objective: what it reads from each draw and how it scores a trial.

    ``reads``: the metric roles it needs per draw (keys of :data:`METRIC_ROLES`).
    ``score``: the trial's values from the counted draws, each ``{role: value}``; all
    values are minimised. ``value_names``: the names of the values (trials table, figures).
    """

    name: str
    description: str
    value_names: tuple[str, ...]
    reads: tuple[str, ...]
    score: Callable[[list[dict[str, float]]], tuple[float, ...]]

    @property
    def directions(self) -> list[str]:
        return ["minimize"] * len(self.value_names)


OBJECTIVES: dict[str, Objective] = {
    o.name: o
    for o in (
        Objective(
            "mean_force",
            "minimise the mean {force} over {draws} draws, every draw docking",
            ("force_N",),
            ("force",),
            lambda rows: (fmean(r["force"] for r in rows),),
        ),
        Objective(
            "worst_force",
            "minimise the largest {force} over {draws} draws, every draw docking",
            ("force_N",),
            ("force",),
            lambda rows: (max(r["force"] for r in rows),),
        ),
        Objective(
            "force_time",
            "minimise the mean {force} and the mean {time} over {draws} draws (a Pareto front), every draw docking",
            ("force_N", "time_s"),
            ("force", "time"),
            lambda rows: (fmean(r["force"] for r in rows), fmean(r["time"] for r in rows)),
        ),
    )
}


def get(name: str) -> Objective:
    """The objective called ``name``; ValueError naming the allowed ones."""
    try:
        return OBJECTIVES[name]
    except KeyError:
        raise ValueError(
            f"hydra.sweeper.objective.name={name!r} is not an objective; allowed: "
            f"{', '.join(OBJECTIVES)} (compliant_docking/tune/objectives.py, docs/tuning.md)"
        ) from None


def resolve_metrics(objective: Objective, cfg: Any) -> tuple[dict[str, str], list[str]]:
    """The metrics.json key of each role the objective reads, and notes to print.

    ``objective.metric`` falls back to ``objective.fallback_metric`` when it is not a
    metric of this version (compliant_docking/evaluation/registry.py); ValueError when
    neither is, naming the metrics there are.
    """
    from compliant_docking.evaluation.registry import BY_KEY

    keys, notes = {}, []
    for role in objective.reads:
        option = METRIC_ROLES[role]
        wanted = str(cfg[option])
        fallback = cfg.get("fallback_metric") if option == "metric" else None
        if wanted in BY_KEY:
            keys[role] = wanted
        elif fallback and fallback in BY_KEY:
            keys[role] = str(fallback)
            notes.append(
                f"objective: {wanted} is not a metric of this version (evaluation/registry.py); "
                f"using hydra.sweeper.objective.fallback_metric={fallback}"
            )
        else:
            raise ValueError(
                f"hydra.sweeper.objective.{option}={wanted!r} is not a metric "
                f"(fallback: {fallback!r}); the metrics are: {', '.join(BY_KEY)}"
            )
    return keys, notes


@dataclass(frozen=True)
class Draw:
    """One job of a trial, as its directory left it."""

    job: str  # the job directory's name
    record: dict | None  # its metrics.json, None when there is none
    problem: str | None = None  # why there is no record

    @classmethod
    def read(cls, job_dir: Path) -> Draw:
        from compliant_docking.run.rundir import read_metrics

        record, problem = read_metrics(job_dir)
        return cls(Path(job_dir).name, record, problem)

    def why_not(self, keys: dict[str, str], require_docking: bool) -> str | None:
        """None when the draw counts, else the reason (one line)."""
        record = self.record
        if record is None:
            return self.problem or "no metrics.json"
        if record.get("status") == "failed":
            return f"failed: {record.get('error') or 'no reason recorded'}"
        if require_docking and record.get("success") is not True:
            # the docking gate's verdict says what failed ("seated; …" or "not docked: …")
            verdict = record.get("gate_verdict")
            return (
                verdict or f"not docked: {record.get('gate_failures') or 'no docking gate (success is null)'}"
            )
        for key in keys.values():
            value = record.get(key)
            if not isinstance(value, (int, float)) or isinstance(value, bool) or not math.isfinite(value):
                return f"no {key} in metrics.json"
        return None


@dataclass
class Evaluation:
    """A trial's values, whether it counts (feasible), and what to record with it."""

    values: tuple[float, ...]
    feasible: bool
    attrs: dict[str, Any] = field(default_factory=dict)


def evaluate(objective: Objective, draws: Sequence[Draw], keys: dict[str, str], cfg: Any) -> Evaluation:
    """Score one trial from its draws (see the module docstring); never raises for what
    the draws hold. ``keys``: :func:`resolve_metrics`; ``cfg``: ``hydra.sweeper.objective``."""
    require = bool(cfg.require_docking)
    reasons = [d.why_not(keys, require) for d in draws]
    bad = [f"{d.job}: {why}"[:300] for d, why in zip(draws, reasons) if why is not None]
    counted = [d for d, why in zip(draws, reasons) if why is None]
    attrs: dict[str, Any] = {
        "feasible": not bad,
        "draws": len(draws),
        "docked": sum(1 for d in draws if d.record is not None and d.record.get("success") is True),
        "jobs": [d.job for d in draws],
        "problems": bad,
    }
    for role, key in keys.items():
        attrs[f"{role}_metric"] = key
        attrs[f"{role}_per_draw"] = [_number(d.record.get(key)) if d.record else None for d in draws]
    if bad or not draws:
        share = len(bad) / len(draws) if draws else 1.0
        penalty = float(cfg.penalty) * (1.0 + share)
        return Evaluation(tuple(penalty for _ in objective.value_names), False, attrs)
    rows = [{role: float(d.record[key]) for role, key in keys.items()} for d in counted if d.record]
    return Evaluation(tuple(float(v) for v in objective.score(rows)), True, attrs)


def _number(value) -> float | None:
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        return None
    return float(value)
