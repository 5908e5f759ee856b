"""``controller=hqp``: HQP-AC, the hierarchical QP with adaptive compliance.

:mod:`.controller` (the per-step law and the constraint rows), :mod:`.compliance`
(adaptive stiffness, damping, preload), :mod:`.manipulability` (the singularity-avoidance
gradient), :mod:`.qp_level` (one ProxQP level).
"""

from compliant_docking.control.hqp.controller import HQPController

__all__ = ["HQPController"]
