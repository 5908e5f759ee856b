"""``hydra/sweeper=optuna``: :class:`OptunaSweeper` (conf/hydra/sweeper/optuna.yaml, docs/tuning.md).

Imported by Hydra's plugin scan in every process that starts Hydra: keep it light (the
implementation imports Optuna only when a sweep runs).
"""

from compliant_docking.tune import sweeper as _impl


class OptunaSweeper(_impl.TuningSweeper):
    """Gain tuning with Optuna: see :class:`compliant_docking.tune.sweeper.TuningSweeper`."""
