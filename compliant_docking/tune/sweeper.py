"""The tuning sweeper: Optuna's ask-and-tell loop behind ``hydra/sweeper=optuna``.

Hydra instantiates :class:`hydra_plugins.compliant_docking_optuna.sweeper.OptunaSweeper`
(a subclass of :class:`TuningSweeper`: plugins must live in the ``hydra_plugins``
namespace package) with the keys of ``hydra.sweeper`` (compliant_docking/config/tuning.py),
then calls :meth:`TuningSweeper.sweep` with the command line's task overrides:

1. the search space (:mod:`.space`), the draws, the objective (:mod:`.objectives`) and
   the study in ``<sweep dir>/study.db`` are set up (:mod:`.study`); a rerun of the same
   command resumes the study;
2. while fewer than ``n_trials`` trials are told: ask ``parallel_trials`` trials, launch
   one job per (trial, draw) through the configured launcher (joblib workers here,
   submitit on a cluster) into ``<sweep dir>/trial<N>_draw<M>/``, read the jobs'
   ``metrics.json`` and tell each trial its value — penalised when a draw failed or did
   not dock; a launcher that raises penalises its batch, never stops the study;
3. the trials table, best parameters, ready robot_controller YAML and figures are
   written (:mod:`.outputs`, :mod:`.figures`) and the best trial printed.

The jobs are ordinary runs (the sweep callback prints a line per job and summarises the
directory at the end). A set-up that cannot be used (a search space, objective or stored
study; a search space reaching values a setting does not allow) is refused by the guard
through :meth:`TuningSweeper.problems` before the sweep directory is created: one
paragraph each, exit status 2, like every refusal of the command line.
"""

from __future__ import annotations

import time
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from hydra.plugins.sweeper import Sweeper
from omegaconf import DictConfig, OmegaConf

from compliant_docking.sweep.progress import display, emit
from compliant_docking.tune import objectives, space
from compliant_docking.tune import study as studies

#: search-space corners composed and checked before anything runs; above it, each
#: parameter's extremes alone (with the others at their lowest)
MAX_CORNERS = 32
#: config groups whose overrides do not change what a trial computes (a study resumed
#: with or without them is the same study)
NOT_DEFINING = ("logger", "tracking")


def job_name(trial_number: int, draw: int) -> str:
    """The job directory of one draw of one trial: ``trial007_draw2``."""
    return f"trial{trial_number:03d}_draw{draw}"


class TuningSweeper(Sweeper):
    """See the module docstring; the arguments are the keys of ``hydra.sweeper``."""

    def __init__(
        self,
        study_name: str,
        storage: str | None,
        n_trials: int,
        parallel_trials: int,
        params: Any,
        draws: Any,
        objective: Any,
        sampler: Any,
    ) -> None:
        self.study_name = str(study_name)
        self.storage = storage
        self.n_trials = int(n_trials)
        self.parallel_trials = int(parallel_trials)
        self.params = _plain(params) or {}
        self.draws = _plain(draws) or {}
        self.objective_cfg = OmegaConf.create(_plain(objective))
        self.sampler_cfg = OmegaConf.create(_plain(sampler))
        self.hydra_context: Any = None
        self.config: DictConfig | None = None
        self.launcher: Any = None

    def setup(self, *, hydra_context, task_function, config: DictConfig) -> None:
        from hydra.core.plugins import Plugins

        self.hydra_context, self.config = hydra_context, config
        self.launcher = Plugins.instance().instantiate_launcher(
            hydra_context=hydra_context, task_function=task_function, config=config
        )

    # ------------------------------------------------------------------ the loop
    def sweep(self, arguments: list[str]) -> Any:
        assert self.config is not None and self.launcher is not None
        sweep_dir = Path(str(self.config.hydra.sweep.dir))
        try:
            plan = self._plan(list(arguments), sweep_dir)
        except (ValueError, RuntimeError) as exc:  # search space, objective, study, composition
            return self._refuse(exc)
        study = plan["study"]
        returns: list = []
        while (todo := self.n_trials - len(studies.completed(study))) > 0:
            trials = [study.ask(plan["distributions"]) for _ in range(min(self.parallel_trials, todo))]
            returns.append(self._run_batch(trials, plan, sweep_dir))
        self._finish(plan, sweep_dir)
        return returns

    def _plan(self, arguments: list[str], sweep_dir: Path) -> dict:
        """Everything the loop needs, checked before any job runs; prints the header."""
        from compliant_docking.run.rundir import MULTIRUN_FILE

        plan = self._definition(arguments)
        objective, keys, tuned, draws = plan["objective"], plan["keys"], plan["tuned"], plan["draws"]
        url = studies.storage_url(self.storage, sweep_dir)
        sweep_dir.mkdir(parents=True, exist_ok=True)
        study = studies.open_study(self.study_name, url, None, objective.directions, plan["definition"])
        OmegaConf.save(self.config, sweep_dir / MULTIRUN_FILE)  # once the study is known to fit
        study.sampler = studies.make_sampler(self.sampler_cfg, tuned, seed_offset=len(study.trials))
        retried = studies.recover_interrupted(study)
        done = len(studies.completed(study))
        description = objective.description.format(
            force=keys.get("force"), time=keys.get("time"), draws=len(draws)
        )
        emit(f"tune: study {self.study_name} in {display(Path(url.removeprefix('sqlite:///')))}")
        emit(f"  objective {objective.name}: {description}")
        emit(f"  search space: {', '.join(f'{p.key} {_describe(p.distribution)}' for p in tuned)}")
        emit(
            f"  budget {self.n_trials} trials, {self.parallel_trials} at a time "
            f"({self.parallel_trials * len(draws)} jobs per batch); {done} told earlier"
            + (f", trials {retried} were interrupted and are asked again" if retried else "")
        )
        for note in plan["notes"]:
            emit(f"  note: {note}")
        return {**plan, "study": study, "started": time.perf_counter()}

    def _definition(self, arguments: list[str]) -> dict:
        """The study's set-up from the config and the command's overrides: objective, search
        space, draws, budget (ValueError naming what cannot be used). Writes nothing."""
        from compliant_docking.extras import MissingExtra, require

        try:
            require("tune", "optuna")
        except MissingExtra as exc:
            raise ValueError(str(exc)) from None
        if self.n_trials < 1 or self.parallel_trials < 1:
            raise ValueError(
                f"hydra.sweeper.n_trials ({self.n_trials}) and hydra.sweeper.parallel_trials "
                f"({self.parallel_trials}) must be at least 1"
            )
        objective = objectives.get(str(self.objective_cfg.name))
        keys, notes = objectives.resolve_metrics(objective, self.objective_cfg)
        tuned, fixed = space.parse_space(self.params, arguments)
        draws = space.expand_draws(self.draws, tuned)
        if str(self.sampler_cfg.name) == "grid" and self.n_trials > studies.grid_size(tuned):
            notes.append(f"sampler grid: {studies.grid_size(tuned)} points, so at most that many trials")
            self.n_trials = studies.grid_size(tuned)
        studies.make_sampler(self.sampler_cfg, tuned)  # a sampler that cannot be made is refused now
        definition = {
            "objective": objective.name,
            "metrics": keys,
            "require_docking": bool(self.objective_cfg.require_docking),
            "penalty": float(self.objective_cfg.penalty),
            "draws": draws,
            # the order on the command line does not matter, nor does the logger (+logger=mlflow)
            "fixed": sorted(f for f in fixed if f.lstrip("+").split("=", 1)[0] not in NOT_DEFINING),
        }
        return {
            "objective": objective,
            "keys": keys,
            "notes": notes,
            "tuned": tuned,
            "fixed": fixed,
            "draws": draws,
            "definition": definition,
            "distributions": {p.key: p.distribution for p in tuned},
        }

    # ------------------------------------------------------------------ checked before anything exists
    def problems(self, config: DictConfig) -> list[str]:
        """Why the study of ``config`` cannot start, one paragraph each ([] when it can): the
        guard asks before the sweep directory is created (compliant_docking/sweep/guard.py).

        The set-up (search space, draws, objective, sampler, budget); the jobs the search
        space reaches, composed at its corners and checked as a run checks them, so that a
        search space outside a setting's allowed range is refused, not 96 failed jobs; and the
        sweep directory: new, empty, or this study's own, whose stored study must be readable
        and have this definition (the same command continues it).
        """
        self.config = config
        try:
            plan = self._definition([str(o) for o in config.hydra.overrides.task])
        except (ValueError, RuntimeError) as exc:
            return [_sentence(exc)]
        return self._corner_problems(plan) or self._directory_problems(
            plan, Path(str(config.hydra.sweep.dir))
        )

    def _corner_problems(self, plan: dict) -> list[str]:
        """The problems of the jobs at the corners of the search space (every combination of
        each parameter's lowest and highest value, or each extreme alone when there are more
        than :data:`MAX_CORNERS`), with the first draw; and of every draw at the lowest corner."""
        import itertools

        from hydra.core.global_hydra import GlobalHydra

        from compliant_docking.config.validate import composition_problem
        from compliant_docking.run.guard import job_problems

        extremes = [(p.key, _extremes(p.distribution)) for p in plan["tuned"]]
        lowest = {key: values[0] for key, values in extremes}
        corners = [
            dict(zip([k for k, _ in extremes], combo))
            for combo in itertools.product(*(v for _, v in extremes))
        ]
        if len(corners) > MAX_CORNERS:
            corners = [lowest] + [{**lowest, key: v} for key, values in extremes for v in values[1:]]
        cases = [(corner, 0) for corner in corners] + [(lowest, i) for i in range(1, len(plan["draws"]))]
        loader = GlobalHydra.instance().config_loader()
        assert self.config is not None
        for corner, draw in cases:
            overrides = self._jobs(0, corner, plan)[draw]
            try:
                found = job_problems(loader.load_sweep_config(self.config, overrides))
            except Exception as exc:  # a key that does not compose
                found = [composition_problem(exc)]
            if found:
                at = " ".join(p.override(corner[p.key]) for p in plan["tuned"])
                draw_text = " ".join(plan["draws"][draw]) or "the only draw"
                return [f"{f} [the search space reaches this job: {at}, draw {draw_text}]" for f in found]
        return []

    def _directory_problems(self, plan: dict, sweep_dir: Path) -> list[str]:
        """Why ``sweep_dir`` cannot hold this study: it holds something else, or a stored
        study that cannot be read or was made with another definition."""
        from compliant_docking.run.rundir import MULTIRUN_FILE

        if sweep_dir.is_dir() and any(sweep_dir.iterdir()):
            saved = sweep_dir / MULTIRUN_FILE
            stored_name = None
            if saved.is_file():
                try:
                    stored_name = OmegaConf.select(OmegaConf.load(saved), "hydra.sweeper.study_name")
                except Exception:
                    stored_name = None
            # a study's own directory: its multirun.yaml names it, or (a command stopped just
            # after it opened the study) it holds the study alone so far
            started_here = not saved.is_file() and (sweep_dir / studies.STUDY_FILE).is_file()
            if stored_name != self.study_name and not started_here:
                return [
                    f"hydra.sweep.dir={sweep_dir} holds something other than the study "
                    f"{self.study_name!r} (its {MULTIRUN_FILE} names "
                    f"{'no study' if stored_name is None else repr(stored_name)}): a study starts in a new "
                    "or empty directory and continues in its own; choose another directory."
                ]
        url = studies.storage_url(self.storage, sweep_dir)
        try:
            studies.check_stored(self.study_name, url, plan["objective"].directions, plan["definition"])
        except (studies.StudyMismatch, studies.UnreadableStudy) as exc:
            return [_sentence(exc)]
        return []

    def _jobs(self, trial_number: int, params: dict, plan: dict) -> list[list[str]]:
        settings = [p.override(params[p.key]) for p in plan["tuned"]]
        return [
            [*plan["fixed"], *settings, *draw, f"hydra.sweep.subdir={job_name(trial_number, i)}"]
            for i, draw in enumerate(plan["draws"])
        ]

    def _run_batch(self, trials: list, plan: dict, sweep_dir: Path) -> Sequence[Any]:
        """Launch every draw of ``trials``, then tell each trial its value."""
        jobs = [job for t in trials for job in self._jobs(t.number, t.params, plan)]
        n_draws = len(plan["draws"])
        crash = None
        try:
            results = self.launcher.launch(jobs, initial_job_idx=trials[0].number * n_draws)
        except Exception as exc:  # e.g. a worker process died: penalise the batch, go on
            results, crash = [], f"{type(exc).__name__}: {str(exc).strip()[:300]}"
            emit(
                f"tune: the launcher failed for trials {[t.number for t in trials]} ({crash}); they are penalised"
            )
            self._record_orphans(trials, n_draws, sweep_dir)
        study, objective = plan["study"], plan["objective"]
        for trial in trials:
            draws = [objectives.Draw.read(sweep_dir / job_name(trial.number, i)) for i in range(n_draws)]
            result = objectives.evaluate(objective, draws, plan["keys"], self.objective_cfg)
            for key, value in result.attrs.items():
                trial.set_user_attr(key, value)
            if crash:
                trial.set_user_attr("launcher_error", crash)
            study.tell(trial, result.values[0] if len(result.values) == 1 else list(result.values))
            emit(self._trial_line(trial, result, plan))
        return results

    @staticmethod
    def _record_orphans(trials: list, n_draws: int, sweep_dir: Path) -> None:
        from compliant_docking.run.rundir import METRICS_FILE
        from compliant_docking.sweep.outcome import record_orphan

        for trial in trials:
            for i in range(n_draws):
                job_dir = sweep_dir / job_name(trial.number, i)
                if job_dir.is_dir() and not (job_dir / METRICS_FILE).exists():
                    record_orphan(job_dir)

    def _trial_line(self, trial, result: objectives.Evaluation, plan: dict) -> str:
        objective = plan["objective"]
        params = " ".join(f"{k}={_short(v)}" for k, v in trial.params.items())
        values = " · ".join(f"{n} {_short(v)}" for n, v in zip(objective.value_names, result.values))
        docked = f"{result.attrs['docked']}/{result.attrs['draws']} docked"
        if result.feasible:
            line = f"trial {trial.number} · {params} · {values} ({docked})"
        else:
            first = (result.attrs.get("problems") or ["?"])[0][:140]
            line = f"trial {trial.number} · {params} · PENALISED {values} ({docked}; {first})"
        if len(objective.value_names) == 1:
            from compliant_docking.tune.outputs import best_trials

            best = best_trials(plan["study"], objective)
            if best:
                line += f" · best: trial {best[0].number} ({_short(best[0].values[0])})"
        return line

    # ------------------------------------------------------------------ the end
    def _finish(self, plan: dict, sweep_dir: Path) -> None:
        from compliant_docking.tune import figures, outputs

        assert self.config is not None
        study, objective = plan["study"], plan["objective"]
        choices = self.config.hydra.runtime.choices
        robot, controller = str(choices.get("robot")), str(choices.get("controller"))
        controller_cfg = OmegaConf.to_container(self.config.controller, resolve=True)
        frame = outputs.trials_frame(study, objective)
        written = outputs.write_trials(frame, sweep_dir)
        written += outputs.write_best(
            study,
            objective,
            sweep_dir,
            robot=robot,
            controller=controller,
            controller_cfg=controller_cfg if isinstance(controller_cfg, dict) else {},
            definition=plan["definition"],
        )
        try:
            metric = plan["keys"].get("force", "")
            written += figures.plot_history(frame, objective, sweep_dir / "tuning", metric)
            written += figures.plot_pareto(frame, objective, sweep_dir / "tuning", metric)
        except Exception as exc:  # figures are a convenience; the tables are the record
            emit(f"tune: the figures failed ({type(exc).__name__}: {exc})")
        self._report(study, objective, written, sweep_dir, robot, controller)

    def _report(
        self, study, objective, written: list[Path], sweep_dir: Path, robot: str, controller: str
    ) -> None:
        from compliant_docking.tune.outputs import best_trials, describe

        best = best_trials(study, objective)
        told = studies.completed(study)
        feasible = sum(1 for t in told if t.user_attrs.get("feasible"))
        lines = ["=" * 64, f"tune finished: {len(told)} trials told, {feasible} docked in every draw"]
        if not best:
            lines.append(
                "  no trial docked in every draw: no gains written (widen the search space or the budget)"
            )
        elif len(objective.value_names) == 1:
            lines.append(f"  best {describe(best[0], objective)}")
        else:
            lines.append(f"  Pareto front ({len(best)} trials):")
            lines += [f"    {describe(t, objective)}" for t in best]
        ready = [p for p in written if p.name == f"{robot}_{controller}.yaml"]
        if len(ready) == 1:
            lines.append(
                f"  ready gains: {display(ready[0])}  (copy to conf/robot_controller/{ready[0].name})"
            )
        elif ready:
            lines.append(
                f"  ready gains, one per Pareto trial: {display(sweep_dir / 'pareto')}/trial<N>/{ready[0].name}"
                f"  (copy one to conf/robot_controller/)"
            )
        lines.append(
            f"  trials: {display(sweep_dir / 'trials.csv')} (+ .parquet), best: {display(sweep_dir / 'best_params.yaml')}"
        )
        lines.append(f"  figures: {display(sweep_dir / 'tuning')}/")
        lines.append("=" * 64)
        emit("\n".join(lines))

    def _refuse(self, exc: Exception) -> None:
        """Refuse the study (exit status 2, the command line's refusal); nothing ran. The
        guard asked :meth:`problems` before anything was created: this is for a sweeper used
        without it (from Python)."""
        from compliant_docking.run.guard import refuse
        from compliant_docking.sweep.session import SweepSession

        SweepSession.current().discard()
        raise refuse("the tuning study is refused", [_sentence(exc)])


def _extremes(distribution) -> list:
    """The values at the ends of a distribution: every choice of a categorical one, else its
    lowest and highest value (the last point of a stepped grid)."""
    from optuna.distributions import CategoricalDistribution

    if isinstance(distribution, CategoricalDistribution):
        return list(distribution.choices)
    high = distribution.high
    step = getattr(distribution, "step", None)
    if step:
        high = distribution.low + step * int((distribution.high - distribution.low) // step)
    return [distribution.low] if high == distribution.low else [distribution.low, high]


def _sentence(exc: BaseException) -> str:
    text = " ".join(str(exc).split())
    return text if text.endswith(".") else f"{text}."


def _plain(node) -> Any:
    return OmegaConf.to_container(node, resolve=True) if OmegaConf.is_config(node) else node


def _short(value) -> str:
    return f"{value:.4g}" if isinstance(value, float) else str(value)


def _describe(distribution) -> str:
    from optuna.distributions import CategoricalDistribution

    if isinstance(distribution, CategoricalDistribution):
        return "{" + ", ".join(map(str, distribution.choices)) + "}"
    log = " log" if getattr(distribution, "log", False) else ""
    step = f" step {distribution.step}" if getattr(distribution, "step", None) not in (None, 1) else ""
    return f"[{distribution.low}, {distribution.high}]{log}{step}"
