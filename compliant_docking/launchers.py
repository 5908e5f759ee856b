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
progress lines itself: :class:`ProgressWatcher` polls the sweep directory for
``metrics.json`` files that are new or rewritten.

This module is imported by the launching process and every job: keep it light.
"""

from __future__ import annotations

import threading
from pathlib import Path
from typing import Any

#: our presets → the plugin's dataclass (module ``hydra_plugins.hydra_submitit_launcher.config``)
SUBMITIT_PRESETS = {"submitit_local": "LocalQueueConf", "submitit_slurm": "SlurmQueueConf"}
#: how often :class:`ProgressWatcher` looks for finished jobs [s]
POLL_INTERVAL_S = 2.0


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
    plugin_group = cs.repo.get("hydra", {}).get("launcher", {})
    for name, schema in SUBMITIT_PRESETS.items():
        cs.store(group="schema/launcher", name=name, node=getattr(submitit_config, schema))
        plugin_group.pop(f"{name}.yaml", None)  # conf/hydra/launcher/<name>.yaml replaces it


def _target(launcher_cfg: Any) -> str:
    try:
        return str(launcher_cfg.get("_target_", "") or "")
    except Exception:
        return ""


def is_submitit(launcher_cfg: Any) -> bool:
    """True for Hydra's submitit launchers (local or Slurm): every job is a process of its
    own, which goes on running when the launching process stops waiting for it."""
    return ".hydra_submitit_launcher." in _target(launcher_cfg)


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


class ProgressWatcher:
    """Prints the progress line of every job that finishes while the sweep runs.

    A daemon thread of the launching process polls ``<sweep>/*/metrics.json`` (the
    depth of the sweep's job directories) every ``interval_s``; a file that is new, or
    rewritten since the sweep started (a rerun job of a resumed sweep), gets its line
    from :func:`compliant_docking.sweep.job_line`. :meth:`stop` polls a last time.
    """

    def __init__(self, sweep_dir: Path, total: int | None, interval_s: float = POLL_INTERVAL_S,
                 depth: int = 1) -> None:
        self.sweep_dir = Path(sweep_dir)
        self.total = total
        self.interval_s = float(interval_s)
        self.pattern = "*/" * depth + "metrics.json"
        self._seen = self._snapshot()
        self._stop = threading.Event()
        self._lock = threading.Lock()
        self._thread = threading.Thread(target=self._run, name="sweep-progress", daemon=True)

    def _snapshot(self) -> dict[Path, int]:
        found = {}
        for path in self.sweep_dir.glob(self.pattern):
            try:
                found[path] = path.stat().st_mtime_ns
            except OSError:  # replaced while we looked
                pass
        return found

    def start(self) -> "ProgressWatcher":
        self._thread.start()
        return self

    def _run(self) -> None:
        while not self._stop.wait(self.interval_s):
            self.poll()

    def poll(self) -> None:
        """Print the lines of the jobs finished since the last poll."""
        from compliant_docking.sweep import _print, job_line

        with self._lock:
            now = self._snapshot()
            new = sorted((p for p, mtime in now.items() if self._seen.get(p) != mtime),
                         key=lambda p: now[p])
            self._seen = now
            for i, path in enumerate(new):  # oldest first, with a running count
                try:
                    done = len(now) - (len(new) - 1 - i)
                    _print(job_line(path.parent, self.sweep_dir.resolve(), self.total, done))
                except Exception as exc:  # progress must never stop a sweep
                    _print(f"(progress line failed: {exc})")

    def stop(self) -> None:
        self._stop.set()
        if self._thread.is_alive():
            self._thread.join(timeout=10)
        self.poll()
