"""The typed schema of the tuning sweeper: ``hydra/sweeper=optuna`` (conf/hydra/sweeper/optuna.yaml).

Stored as ``schema/sweeper/optuna`` by :func:`compliant_docking.config.store.register_schemas`;
the sweeper itself is :mod:`compliant_docking.tune` (docs/tuning.md). A misspelled key
or a wrong type under ``hydra.sweeper`` is refused when the config is composed.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Dict, Optional

#: the class Hydra instantiates (it must live in the hydra_plugins namespace package)
SWEEPER_TARGET = "hydra_plugins.compliant_docking_optuna.sweeper.OptunaSweeper"


@dataclass
class TuningObjectiveConfig:
    """What a trial scores (compliant_docking/tune/objectives.py)."""

    name: str = "mean_force"  # mean_force | worst_force | force_time (two objectives: a Pareto front)
    metric: str = "first_strike_force_N"  # the force read from each draw's metrics.json
    fallback_metric: Optional[str] = (
        "peak_axial_force_N"  # used when `metric` is not a metric of this version
    )
    time_metric: str = "seated_time_s"  # force_time: the docking time
    require_docking: bool = True  # a trial counts only when every draw docked (its gate passed)
    penalty: float = 1000.0  # a penalised trial scores penalty × (1 + share of bad draws)


@dataclass
class TuningSamplerConfig:
    """Optuna's sampler (compliant_docking/tune/study.py)."""

    name: str = "tpe"  # tpe | random | qmc | nsga2 | grid
    seed: int = 0  # a resumed study reseeds with seed + trials so far (no repeated draws)
    n_startup_trials: int = 8  # tpe: random trials before its model takes over


@dataclass
class TuningSweeperConfig:
    """``hydra.sweeper`` of a tuning run (docs/tuning.md)."""

    _target_: str = SWEEPER_TARGET
    study_name: str = "tune"  # the Optuna study (its trials, in `storage`)
    storage: Optional[str] = None  # null: sqlite:///<sweep dir>/study.db (a rerun resumes it)
    n_trials: int = 24  # the budget: trials in the study when the command ends
    parallel_trials: int = 2  # trials asked and launched together (all their draws at once)
    # the search space: config key → Hydra sweep, e.g. "tag(log, interval(100, 1000))",
    # "int(interval(1, 8))", "range(0.5, 2.0, 0.25)", "choice(torque, velocity)"
    params: Dict[str, Any] = field(default_factory=dict)
    # the fixed draws every trial runs: config key → values (a comma list or range()),
    # their combinations are the draws, e.g. {task.misalignment.seed: "range(4)"}
    draws: Dict[str, Any] = field(default_factory=dict)
    objective: TuningObjectiveConfig = field(default_factory=TuningObjectiveConfig)
    sampler: TuningSamplerConfig = field(default_factory=TuningSamplerConfig)
