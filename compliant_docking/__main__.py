"""``python -m compliant_docking [overrides]``: one run (or a sweep with ``-m``).

Exit status: 0 the run succeeded (docked / tracking gate PASS), 1 the run failed
(error or divergence), 3 the run finished but its gate did not pass.
A sweep (``-m``): 1 if any job failed (or its worker died), else 0 — jobs that did not
dock are results, counted in the summary (compliant_docking/sweep.py); 2 a refused
``resume=`` (compliant_docking/resume.py); 143 stopped by SIGTERM (the summary of what
finished is written, as after Ctrl-C).
"""

from __future__ import annotations

import signal
import sys
from pathlib import Path

import hydra
from hydra.core.hydra_config import HydraConfig
from hydra.types import RunMode
from omegaconf import DictConfig

from compliant_docking import CONF_DIR, resume
from compliant_docking.config import register_schemas

register_schemas()
_records: list[dict] = []


@hydra.main(version_base="1.3", config_path=str(CONF_DIR), config_name="config")
def _main(cfg: DictConfig) -> str | None:
    from compliant_docking.runner import execute

    hydra_cfg = HydraConfig.get()
    out_dir = Path(hydra_cfg.runtime.output_dir)
    if resume.resuming(hydra_cfg):  # resume=<sweep dir>: keep a finished job untouched
        kept = resume.finished_record(cfg, out_dir)
        if kept is not None:
            _records.append(kept)
            return resume.SKIPPED
        resume.prepare_rerun(cfg, out_dir)
    # in a sweep, each job prints one progress line (sweep.SweepCallback), not its summary
    _records.append(execute(cfg, out_dir, echo=hydra_cfg.mode != RunMode.MULTIRUN))


def main() -> int:
    if any(arg in ("--help", "-h") for arg in sys.argv[1:]):
        from compliant_docking.help import print_help

        print_help(sys.argv[1:])
        return 0
    from compliant_docking import sweep

    try:
        sys.argv[1:] = resume.translate_argv(sys.argv[1:])  # resume=<sweep dir> → Hydra overrides
    except resume.ResumeError as exc:
        return resume.fail(exc)
    if any(arg in ("-m", "--multirun") for arg in sys.argv[1:]):
        signal.signal(signal.SIGTERM, _terminated)  # like Ctrl-C: summarise what finished
    sweep.reset()
    try:
        _main()
    except (SystemExit, KeyboardInterrupt):
        sweep.finish_aborted()  # a sweep cut short (worker crash, Ctrl-C): summarise it
        raise
    if sweep.last_outcome() is not None:  # the jobs ran in worker processes
        return sweep.last_outcome().exit_status
    from compliant_docking.runner import exit_status

    return max((exit_status(r) for r in _records), default=0)


def _terminated(signum, frame) -> None:
    """SIGTERM in a sweep (``kill``, Slurm's ``scancel`` of the launching job): unwind
    like Ctrl-C, so the joblib workers are stopped and the summary is written."""
    raise SystemExit(128 + signum)


if __name__ == "__main__":
    sys.exit(main())
