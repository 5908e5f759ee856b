"""The project's default sweep launcher as a Hydra plugin.

Hydra instantiates launchers only from classes defined in the ``hydra_plugins``
namespace package; this one is :class:`compliant_docking.sweep.pool.PoolLauncher`, where
the code and its documentation live. conf/hydra/launcher/local.yaml names it.
"""

from compliant_docking.sweep import pool


class PoolLauncher(pool.PoolLauncher):
    """:class:`compliant_docking.sweep.pool.PoolLauncher` (this name is what Hydra needs)."""
