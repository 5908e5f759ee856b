"""Hydra plugin: the tuning sweeper of compliant-docking (``hydra/sweeper=optuna``).

Hydra finds plugins by scanning the ``hydra_plugins`` namespace package, and instantiates
only classes defined there; the implementation is :mod:`compliant_docking.tune`.
"""
