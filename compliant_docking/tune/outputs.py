"""What a tuning run leaves in its sweep directory, besides the jobs and the study.

- ``trials.csv`` / ``trials.parquet``: one row per trial (:func:`trials_frame`);
- ``best_params.yaml``: the best trial (or the Pareto-optimal trials), its values and
  parameters, the objective and the draws (:func:`write_best`);
- ``<robot>_<controller>.yaml``: the best gains as a ready file for
  ``conf/robot_controller/`` (copy it there to make them the defaults); with two
  objectives one per Pareto-optimal trial, under ``pareto/trial<N>/``;
- ``tuning/``: the figures (:mod:`compliant_docking.tune.figures`).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pandas as pd

from compliant_docking.run.files import atomic_write, atomic_write_text
from compliant_docking.tune.objectives import Objective

TRIALS_CSV, TRIALS_PARQUET, BEST_FILE = "trials.csv", "trials.parquet", "best_params.yaml"
PARETO_DIR = "pareto"
PREFIX = "controller."


def trials_frame(study, objective: Objective) -> pd.DataFrame:
    """One row per trial: ``number``, ``state``, the objective's values under their names
    (``force_N``, ``time_s``), ``feasible``, the parameters under their config keys
    (``controller.k``), the recorded attributes (``docked``, ``draws``, ``problems``, …) and
    the start, end and duration."""
    rows = []
    for t in study.get_trials(deepcopy=False):
        row: dict[str, Any] = {"number": t.number, "state": t.state.name}
        values = t.values or [None] * len(objective.value_names)
        row.update(dict(zip(objective.value_names, values)))
        row["feasible"] = bool(t.user_attrs.get("feasible", False)) if t.values else False
        row.update(t.params)
        for key, value in t.user_attrs.items():
            if key != "feasible":
                row[key] = "; ".join(map(str, value)) if isinstance(value, list) else value
        row["datetime_start"], row["datetime_complete"] = t.datetime_start, t.datetime_complete
        row["duration_s"] = (
            (t.datetime_complete - t.datetime_start).total_seconds()
            if t.datetime_start and t.datetime_complete
            else None
        )
        rows.append(row)
    return pd.DataFrame(rows)


def write_trials(frame: pd.DataFrame, sweep_dir: Path) -> list[Path]:
    """trials.csv and trials.parquet in the sweep directory (each atomically)."""
    csv, parquet = Path(sweep_dir) / TRIALS_CSV, Path(sweep_dir) / TRIALS_PARQUET
    atomic_write(csv, lambda tmp: frame.to_csv(tmp, index=False))
    table = frame.copy()
    for column in table.columns:  # mixed-type columns (categorical params, attrs) as text
        if table[column].dtype == object:
            table[column] = table[column].map(lambda v: None if v is None else str(v))
    atomic_write(parquet, lambda tmp: table.to_parquet(tmp, index=False))
    return [csv, parquet]


def best_trials(study, objective: Objective) -> list:
    """The best feasible trial (one objective) or the Pareto-optimal feasible trials."""
    from compliant_docking.tune.study import completed

    feasible = [t for t in completed(study) if t.user_attrs.get("feasible")]
    if not feasible:
        return []
    if len(objective.value_names) == 1:
        return [min(feasible, key=lambda t: (t.values[0], t.number))]
    return sorted(pareto_front(feasible), key=lambda t: (t.values, t.number))


def pareto_front(trials: list) -> list:
    """The trials no other trial dominates (all values minimised)."""

    def dominates(a, b) -> bool:
        return all(x <= y for x, y in zip(a.values, b.values)) and any(
            x < y for x, y in zip(a.values, b.values)
        )

    return [t for t in trials if not any(dominates(o, t) for o in trials if o is not t)]


def describe(trial, objective: Objective) -> str:
    """``trial 17 · controller.k=512.3 controller.d=70.12 · force_N 12.3``."""
    params = " ".join(f"{k}={_short(v)}" for k, v in trial.params.items())
    values = " · ".join(f"{n} {_short(v)}" for n, v in zip(objective.value_names, trial.values or []))
    return f"trial {trial.number} · {params} · {values}"


def _short(value) -> str:
    return f"{value:.4g}" if isinstance(value, float) else str(value)


def ready_yaml(trial, robot: str, controller: str, controller_cfg: dict, header: list[str]) -> str:
    """A ``conf/robot_controller/<robot>_<controller>.yaml`` with the trial's gains.

    It keeps every key of the current file there (values as the study composed them)
    and any other controller key the trial tuned, so copying it over the current file
    changes the tuned gains only. Tuned keys outside ``controller.`` cannot live in that
    file: they are listed in a comment.
    """
    import yaml

    from compliant_docking import CONF_DIR

    current = CONF_DIR / "robot_controller" / f"{robot}_{controller}.yaml"
    existing = yaml.safe_load(current.read_text(encoding="utf-8")) if current.is_file() else None
    keys = [k for k in (existing or {}) if k != "defaults"]
    tuned = {k[len(PREFIX) :]: v for k, v in trial.params.items() if k.startswith(PREFIX)}
    values = {k: controller_cfg.get(k) for k in keys}
    values.update(tuned)
    others = {k: v for k, v in trial.params.items() if not k.startswith(PREFIX)}
    lines = ["# @package controller", *(f"# {line}" for line in header)]
    lines.append(f"# Tuned: {', '.join(tuned) or 'no controller key'}; the other keys are those of")
    lines.append(f"# conf/robot_controller/{robot}_{controller}.yaml when the study ran.")
    if others:
        lines.append("# Tuned outside the controller (set them where they belong): ")
        lines += [f"#   {k}={_plain(v)}" for k, v in others.items()]
    body = yaml.safe_dump(
        {k: _plain(v) for k, v in values.items()}, sort_keys=False, default_flow_style=False
    )
    return "\n".join(lines) + "\n" + body


def _plain(value):
    if hasattr(value, "item"):  # numpy scalars
        value = value.item()
    if isinstance(value, float):
        return float(f"{value:.6g}")  # gains to 6 significant digits
    return value


def write_best(
    study,
    objective: Objective,
    sweep_dir: Path,
    *,
    robot: str,
    controller: str,
    controller_cfg: dict,
    definition: dict,
) -> list[Path]:
    """best_params.yaml and the ready robot_controller file(s); the paths written.

    Without a feasible trial only best_params.yaml is written (``best: []``), so no
    file can be mistaken for gains that dock.
    """
    import yaml

    sweep_dir = Path(sweep_dir)
    best = best_trials(study, objective)
    record = {
        "study": study.study_name,
        "objective": definition.get("objective"),
        "values": list(objective.value_names),
        "metrics": definition.get("metrics"),
        "draws": definition.get("draws"),
        "trials": len(study.trials),
        "best": [
            {
                "trial": t.number,
                **{n: _plain(v) for n, v in zip(objective.value_names, t.values)},
                "params": {k: _plain(v) for k, v in t.params.items()},
            }
            for t in best
        ],
    }
    written = [sweep_dir / BEST_FILE]
    atomic_write_text(written[0], yaml.safe_dump(record, sort_keys=False))
    name = f"{robot}_{controller}.yaml"
    for t in best:
        values = ", ".join(f"{n} {_short(v)}" for n, v in zip(objective.value_names, t.values))
        header = [
            f"{robot} + {controller} gains tuned with Optuna (compliant_docking/tune, docs/tuning.md):",
            f"study {study.study_name}, trial {t.number} of {len(study.trials)}, objective "
            f"{definition.get('objective')} over {len(definition.get('draws') or [[]])} draws: {values}.",
            f"Copy to conf/robot_controller/{name} to make these the defaults.",
        ]
        path = sweep_dir / name if len(best) == 1 and len(objective.value_names) == 1 else None
        if path is None:
            path = sweep_dir / PARETO_DIR / f"trial{t.number:03d}" / name
            path.parent.mkdir(parents=True, exist_ok=True)
        atomic_write_text(path, ready_yaml(t, robot, controller, controller_cfg, header))
        written.append(path)
    return written
