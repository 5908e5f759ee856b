"""The Optuna study of a tuning run: its sampler, its storage, and resuming it.

The study lives in SQLite in the sweep directory (``<sweep dir>/study.db``, or
``hydra.sweeper.storage``), written only by the launching process. Rerunning the same
command opens it again (``load_if_exists``): the trials told so far stay, a trial that
was running when the command stopped is marked failed and its parameters are asked
again first, and the sampler is reseeded with ``seed + trials so far`` so that a
resumed study does not repeat its first samples. The definition of the study (objective,
metrics, draws, fixed overrides) is stored with it; a rerun whose definition differs is
refused, since its values would not be comparable (a changed search space is allowed).
"""

from __future__ import annotations

import warnings
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from compliant_docking.tune.space import Param

SAMPLERS = ("tpe", "random", "qmc", "nsga2", "grid")
#: the study's file in the sweep directory when hydra.sweeper.storage is null
STUDY_FILE = "study.db"


class StudyMismatch(ValueError):
    """The stored study was made with another definition; the message says what differs."""


def storage_url(storage: str | None, sweep_dir: Path) -> str:
    """``hydra.sweeper.storage``, or SQLite in the sweep directory when it is null."""
    if storage:
        return str(storage)
    return f"sqlite:///{(Path(sweep_dir) / STUDY_FILE).resolve()}"


def make_sampler(cfg: Any, space: Sequence[Param], seed_offset: int = 0):
    """Optuna's sampler for ``hydra.sweeper.sampler`` (ValueError naming the allowed ones)."""
    import optuna

    name, seed = str(cfg.name), int(cfg.seed) + int(seed_offset)
    with warnings.catch_warnings():  # multivariate TPE is "experimental" in some versions
        warnings.simplefilter("ignore", optuna.exceptions.ExperimentalWarning)
        if name == "tpe":
            return optuna.samplers.TPESampler(
                seed=seed, n_startup_trials=int(cfg.n_startup_trials), multivariate=True, constant_liar=True
            )
        if name == "random":
            return optuna.samplers.RandomSampler(seed=seed)
        if name == "qmc":
            return optuna.samplers.QMCSampler(seed=int(cfg.seed), scramble=True)  # a sequence: not reseeded
        if name == "nsga2":
            return optuna.samplers.NSGAIISampler(seed=seed)
        if name == "grid":
            return optuna.samplers.GridSampler({p.key: grid_values(p) for p in space}, seed=int(cfg.seed))
    raise ValueError(f"hydra.sweeper.sampler.name={name!r} is not a sampler; allowed: {', '.join(SAMPLERS)}")


def grid_values(param: Param) -> list:
    """Every value of a finite distribution (the grid sampler); ValueError for an interval."""
    from optuna.distributions import CategoricalDistribution, FloatDistribution, IntDistribution

    d = param.distribution
    if isinstance(d, CategoricalDistribution):
        return list(d.choices)
    if isinstance(d, IntDistribution) and not d.log:
        return list(range(d.low, d.high + 1, d.step))
    if isinstance(d, FloatDistribution) and d.step is not None:
        n = int(round((d.high - d.low) / d.step))
        return [d.low + i * d.step for i in range(n + 1)]
    raise ValueError(
        f"sampler grid: {param.key} has no finite set of values; use choice() or range() (or another sampler)"
    )


def grid_size(space: Sequence[Param]) -> int:
    size = 1
    for param in space:
        size *= len(grid_values(param))
    return size


def open_study(name: str, url: str, sampler, directions: Sequence[Any], definition: dict):
    """Create the study, or load it when it exists (then check its definition)."""
    import optuna

    optuna.logging.set_verbosity(optuna.logging.WARNING)  # the sweeper prints its own lines
    study = optuna.create_study(
        study_name=name, storage=url, sampler=sampler, directions=directions, load_if_exists=True
    )
    _check(study, name, url, directions, definition)
    if study.user_attrs.get("definition") is None:
        study.set_user_attr("definition", definition)
    return study


class UnreadableStudy(ValueError):
    """The stored study cannot be read (a corrupt or foreign file); the message says what to do."""


def check_stored(name: str, url: str, directions: Sequence[Any], definition: dict) -> None:
    """Check the study ``name`` stored at ``url``, if there is one, without changing it:
    :class:`UnreadableStudy` when the storage cannot be read, :class:`StudyMismatch` when it
    was made with other objective values or another definition. Nothing is created: a
    SQLite file that does not exist yet is a new study."""
    import optuna

    path = Path(url.removeprefix("sqlite:///")) if url.startswith("sqlite:///") else None
    if path is not None and not path.exists():
        return
    optuna.logging.set_verbosity(optuna.logging.WARNING)
    try:
        storage = optuna.storages.RDBStorage(url, skip_table_creation=True)
        names = {s.study_name for s in storage.get_all_studies()}
    except Exception as exc:  # SQLAlchemy's DatabaseError, a newer schema, …
        first = (str(exc).strip().splitlines() or [type(exc).__name__])[0]
        where = path if path is not None else url
        raise UnreadableStudy(
            f"the study storage {where} cannot be read ({type(exc).__name__}: {first[:200]}): move it "
            "away to start the study afresh, or give another hydra.sweeper.study_name or hydra.sweep.dir"
        ) from None
    if name in names:
        _check(optuna.load_study(study_name=name, storage=storage), name, url, directions, definition)


def _check(study, name: str, url: str, directions: Sequence[Any], definition: dict) -> None:
    stored_dirs = [d.name.lower() for d in study.directions]
    if stored_dirs != [d.lower() for d in directions]:
        raise StudyMismatch(
            f"study {name!r} in {url} has {len(stored_dirs)} objective value(s) and this command asks for "
            f"{len(directions)}: give another hydra.sweeper.study_name (or another sweep directory)"
        )
    stored = study.user_attrs.get("definition")
    if stored is not None and stored != definition:
        changed = sorted(k for k in set(stored) | set(definition) if stored.get(k) != definition.get(k))
        details = "; ".join(f"{k}: {stored.get(k)!r} → {definition.get(k)!r}" for k in changed)
        raise StudyMismatch(
            f"study {name!r} in {url} was started with another definition ({details}). A resumed study "
            "must keep its objective, metrics, draws and fixed overrides (its values would not be "
            "comparable); give another hydra.sweeper.study_name for a new study"
        )


def recover_interrupted(study) -> list[int]:
    """Mark the trials left running by a stopped command as failed and enqueue their
    parameters again (they are asked first); the numbers of those trials."""
    from optuna.trial import TrialState

    stale = study.get_trials(deepcopy=False, states=(TrialState.RUNNING,))
    for trial in stale:
        study.tell(trial.number, state=TrialState.FAIL)
        if trial.params:
            study.enqueue_trial(dict(trial.params), user_attrs={"retry_of": trial.number})
    return [t.number for t in stale]


def completed(study) -> list:
    """The trials told a value (penalised ones included), in order."""
    from optuna.trial import TrialState

    return study.get_trials(deepcopy=False, states=(TrialState.COMPLETE,))
