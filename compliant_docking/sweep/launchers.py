"""Sweeps on Hydra's submitit launcher: schemas of the presets, the header, console progress.

``conf/hydra/launcher/submitit_local.yaml`` and ``submitit_slurm.yaml`` are our presets
of Hydra's submitit launcher (docs/cluster.md). The plugin registers presets of the same
names in Hydra's ConfigStore; Hydra would then validate our files against them by its
deprecated "automatic schema matching" (a warning at every composition, and an error
once a file has its own defaults list). :func:`register_schemas` therefore stores the
plugin's dataclasses as ``schema/launcher/submitit_{local,slurm}`` — each of our
presets starts its defaults list with its schema, like every other option of this
project — and removes the plugin's own entries, which our files replace.

With submitit every job runs in its own process whose output goes to its log file
(``<sweep>/.submitit/<job id>/``), so the launching process prints the per-job
progress lines itself: :class:`~compliant_docking.sweep.progress.ProgressWatcher` polls the sweep directory for
``metrics.json`` files that are new or rewritten.

This module is imported by the launching process and every job: keep it light.
"""

from __future__ import annotations

from typing import Any

#: our presets → the plugin's dataclass (module ``hydra_plugins.hydra_submitit_launcher.config``)
SUBMITIT_PRESETS = {"submitit_local": "LocalQueueConf", "submitit_slurm": "SlurmQueueConf"}


def register_schemas(cs) -> None:
    """Store the submitit schemas under ``schema/launcher`` and drop the plugin's presets
    of the same names from ``cs`` (Hydra's ConfigStore); idempotent. Nothing happens
    without the plugin (``hydra/launcher=submitit_*`` then fails to compose, naming it)."""
    from hydra.core.plugins import Plugins

    # Hydra's plugin scan (once per process) executes every plugin module again, storing
    # its presets anew and creating new dataclasses: scan first, then edit the store.
    Plugins.instance()
    try:
        from hydra_plugins.hydra_submitit_launcher import config as submitit_config
    except ImportError:
        return
    from compliant_docking.config.hydra_adapter import unstore

    for name, schema in SUBMITIT_PRESETS.items():
        cs.store(group="schema/launcher", name=name, node=getattr(submitit_config, schema))
        unstore(cs, "hydra/launcher", name)  # conf/hydra/launcher/<name>.yaml replaces it


def _target(launcher_cfg: Any) -> str:
    try:
        return str(launcher_cfg.get("_target_", "") or "")
    except Exception:
        return ""


def is_submitit(launcher_cfg: Any) -> bool:
    """True for Hydra's submitit launchers (local or Slurm): every job is a process of its
    own, which goes on running when the launching process stops waiting for it."""
    return ".hydra_submitit_launcher." in _target(launcher_cfg)


def launcher_problem(launcher_cfg: Any) -> str | None:
    """Why the launcher of ``hydra.launcher`` cannot run jobs on this machine, or None:
    submitit not installed, or ``hydra/launcher=submitit_slurm`` without Slurm's ``sbatch``
    (the guard refuses the sweep before anything is created)."""
    import importlib.util
    import shutil

    target = _target(launcher_cfg)
    if not is_submitit(launcher_cfg):
        return None
    name = "submitit_slurm" if target.endswith(".SlurmLauncher") else "submitit_local"
    if importlib.util.find_spec("submitit") is None:
        return f"hydra/launcher={name} needs submitit, which is not installed: pip install hydra-submitit-launcher."
    if name == "submitit_slurm" and shutil.which("sbatch") is None:
        return (
            "hydra/launcher=submitit_slurm needs Slurm, and this machine has no sbatch on its PATH: "
            "start the sweep on the cluster's login node, or run it here with hydra/launcher=local "
            "(the default) or hydra/launcher=submitit_local."
        )
    return None


def describe(launcher_cfg: Any) -> str | None:
    """How a submitit launcher runs the jobs, for the sweep's header line (None for others)."""
    target = _target(launcher_cfg)
    if target.endswith("submitit_launcher.LocalLauncher"):
        return "as local submitit processes (one per job, all at once; logs in .submitit/)"
    if target.endswith("submitit_launcher.SlurmLauncher"):
        partition = launcher_cfg.get("partition") or "the default partition"
        at_once = launcher_cfg.get("array_parallelism")
        limit = f", at most {at_once} at a time" if at_once else ""
        return f"as a Slurm job array on {partition}{limit} (logs in .submitit/)"
    return None
