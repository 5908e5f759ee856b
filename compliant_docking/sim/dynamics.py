"""The plant's plug–socket contact drawn per seed: the ``dynamics`` config group.

``dynamics=nominal`` leaves the contact as the target configures it. A ``*_range``
[low, high] draws, uniformly with ``seed`` (default ``task.misalignment.seed``) from its own
stream ``SeedSequence([seed, 300 + index])``, one value per run, written on every collision
geom of the plug and of the socket of the compiled model (the socket's priority makes its
values govern every plug–socket contact; both are written so a fragment without that
priority gets the same contact):

- ``friction_range``: the sliding friction coefficient (``friction[0]``);
- ``timeconst_range``: solref's time constant [s], the contact's stiffness;
- ``dampratio_range``: solref's damping ratio;
- ``width_range``: solimp's width [m], the penetration over which the impedance rises.

The ranges of conf/dynamics/randomised.yaml and why they are physically meaningful are in
that file and docs/robustness.md.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import mujoco
import numpy as np

from compliant_docking.config.robustness import DynamicsConfig
from compliant_docking.sim.misalignment import uniform_draw

if TYPE_CHECKING:
    from compliant_docking.sim.settings import SimSettings

#: the drawn quantities, in the order of their random streams (300 + index)
QUANTITIES = ("friction", "timeconst", "dampratio", "width")
#: flat keys recorded in metrics.json (null when nothing is drawn)
RECORD_KEYS = (*(f"contact_{name}" for name in QUANTITIES), "contact_seed")


@dataclass(frozen=True)
class ContactDraw:
    """The drawn contact values; None: as configured."""

    friction: float | None = None
    timeconst: float | None = None
    dampratio: float | None = None
    width: float | None = None
    seed: int | None = None

    @property
    def is_nominal(self) -> bool:
        return all(getattr(self, name) is None for name in QUANTITIES)

    def record(self) -> dict:
        return {**{f"contact_{name}": getattr(self, name) for name in QUANTITIES}, "contact_seed": self.seed}

    def apply(self, model: mujoco.MjModel, bodies: list[int]) -> int:
        """Write the drawn values on the collision geoms of ``bodies`` and their subtrees;
        returns how many geoms were written."""
        if self.is_nominal:
            return 0
        inside = np.zeros(model.nbody, dtype=bool)
        for b in range(model.nbody):  # a body is inside when one of its ancestors is listed
            a = b
            while a > 0 and a not in bodies:
                a = model.body_parentid[a]
            inside[b] = a in bodies
        geoms = np.flatnonzero(
            inside[model.geom_bodyid] & ((model.geom_contype != 0) | (model.geom_conaffinity != 0))
        )
        if self.friction is not None:
            model.geom_friction[geoms, 0] = self.friction
        if self.timeconst is not None:
            model.geom_solref[geoms, 0] = self.timeconst
        if self.dampratio is not None:
            model.geom_solref[geoms, 1] = self.dampratio
        if self.width is not None:
            model.geom_solimp[geoms, 2] = self.width
        return len(geoms)


def draw(settings: DynamicsConfig | None) -> ContactDraw:
    """The contact draw of ``settings`` (the ``dynamics`` group, typed; None: nominal)."""
    if settings is None:
        return ContactDraw()
    seed = int(settings.seed or 0)
    values: dict = {}
    for index, name in enumerate(QUANTITIES):
        bounds = getattr(settings, f"{name}_range")
        if bounds is not None:
            values[name] = uniform_draw(seed, 300 + index, float(bounds[0]), float(bounds[1]))
    return ContactDraw(**values, seed=seed if values else None)


def record_for(settings: SimSettings | None) -> dict:
    """The contact keys of metrics.json for the run's ``settings`` (never raises: null when
    invalid; None: the config's nodes are not the schema's)."""
    if settings is None:
        return dict.fromkeys(RECORD_KEYS)
    try:
        return draw(settings.dynamics).record()
    except Exception:
        return dict.fromkeys(RECORD_KEYS)
