"""The typed schema of the tuning sweeper: ``hydra/sweeper=optuna`` (conf/hydra/sweeper/optuna.yaml).

Stored as ``schema/sweeper/optuna`` by :func:`compliant_docking.config.store.register_schemas`;
the sweeper itself is :mod:`compliant_docking.tune` (docs/tuning.md). A misspelled key
or a wrong type under ``hydra.sweeper`` is refused when the config is composed. Like
every schema it carries no values: they live in the YAML (one home per default).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Dict, Optional

from omegaconf import MISSING


@dataclass
class TuningObjectiveConfig:
    """What a trial scores (compliant_docking/tune/objectives.py)."""

    name: str = MISSING  # mean_force | worst_force | force_time (two objectives: a Pareto front)
    metric: str = MISSING  # the force read from each draw's metrics.json
    fallback_metric: Optional[str] = MISSING  # used when `metric` is not a metric of this version
    time_metric: str = MISSING  # force_time: the docking time
    require_docking: bool = MISSING  # a trial counts only when every draw docked (its gate passed)
    penalty: float = MISSING  # a penalised trial scores penalty × (1 + share of bad draws)


@dataclass
class TuningSamplerConfig:
    """Optuna's sampler (compliant_docking/tune/study.py)."""

    name: str = MISSING  # tpe | random | qmc | nsga2 | grid
    seed: int = MISSING  # a resumed study reseeds with seed + trials so far (no repeated draws)
    n_startup_trials: int = MISSING  # tpe: random trials before its model takes over


@dataclass
class TuningSweeperConfig:
    """``hydra.sweeper`` of a tuning run (docs/tuning.md)."""

    _target_: str = MISSING  # the class Hydra instantiates (in the hydra_plugins namespace package)
    study_name: str = MISSING  # the Optuna study (its trials, in `storage`)
    storage: Optional[str] = MISSING  # null: sqlite:///<sweep dir>/study.db (a rerun resumes it)
    n_trials: int = MISSING  # the budget: trials in the study when the command ends
    parallel_trials: int = MISSING  # trials asked and launched together (all their draws at once)
    # the search space: config key → Hydra sweep, e.g. "tag(log, interval(100, 1000))",
    # "int(interval(1, 8))", "range(0.5, 2.0, 0.25)", "choice(torque, velocity)"
    params: Dict[str, Any] = MISSING
    # the fixed draws every trial runs: config key → values (a comma list or range()),
    # their combinations are the draws, e.g. {task.misalignment.seed: "range(4)"}
    draws: Dict[str, Any] = MISSING
    objective: TuningObjectiveConfig = MISSING
    sampler: TuningSamplerConfig = MISSING
