"""The error between the socket's TRUE pose (physics) and the pose the planner BELIEVES.

The planner only knows the nominal socket pose (``target.pos``/``target.quat``): that
is the *believed* pose B. The socket that MuJoCo simulates, and that the docking gate
judges against, sits at the *true* pose

    T = B · Trans(x, y, 0) · Rz(yaw) · Rx(tilt)

i.e. the offsets are expressed in the **believed socket frame** (origin at the seat,
the bottom of the bore; +z out of the opening):

- ``x``, ``y`` [m]: lateral offset of the seat in the socket's x/y plane;
- ``yaw_deg`` [deg]: rotation about the socket axis (z), about the seat point;
- ``tilt_deg`` [deg]: then a rotation about the (yawed) socket x axis, about the seat
  point: the true socket axis leans by ``tilt_deg`` towards the yawed −y direction, so
  ``yaw_deg`` chooses the direction of the tilt.

Each component is either fixed (``x``, …) or drawn uniformly from ``[low, high]``
(``x_range``, …) with ``seed``. Every component has its own random stream derived from
``(seed, component)``, so the same seed gives the same draw, the draw of one component
does not depend on which other components are drawn, and scaling a range scales the
draw (common random numbers across a grid of ranges).

This module is light (numpy only; Pinocchio is imported when a pose is built).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    from compliant_docking.config.schemas import MisalignmentConfig
    from compliant_docking.sim.settings import SimSettings

#: the components, in the order of their random streams
COMPONENTS = ("x", "y", "yaw_deg", "tilt_deg")
#: flat keys recorded in metrics.json (null when there is no socket)
RECORD_KEYS = (
    "misalignment_x_m",
    "misalignment_y_m",
    "misalignment_lateral_m",
    "misalignment_yaw_deg",
    "misalignment_tilt_deg",
    "misalignment_seed",
)


@dataclass(frozen=True)
class Misalignment:
    """One realised misalignment (believed → true socket pose), believed socket frame."""

    x: float = 0.0  # [m]
    y: float = 0.0  # [m]
    yaw_deg: float = 0.0  # about the socket axis [deg]
    tilt_deg: float = 0.0  # about the yawed socket x axis [deg]
    seed: int | None = None  # the seed of the draw; None when nothing was drawn

    @property
    def lateral(self) -> float:
        """Lateral distance of the true seat from the believed one [m]."""
        return math.hypot(self.x, self.y)

    @property
    def is_zero(self) -> bool:
        return not any((self.x, self.y, self.yaw_deg, self.tilt_deg))

    def rotation(self) -> np.ndarray:
        """Rz(yaw) · Rx(tilt): the true socket axes in the believed socket frame."""
        cy, sy = math.cos(math.radians(self.yaw_deg)), math.sin(math.radians(self.yaw_deg))
        ct, st = math.cos(math.radians(self.tilt_deg)), math.sin(math.radians(self.tilt_deg))
        rz = np.array([[cy, -sy, 0.0], [sy, cy, 0.0], [0.0, 0.0, 1.0]])
        rx = np.array([[1.0, 0.0, 0.0], [0.0, ct, -st], [0.0, st, ct]])
        return rz @ rx

    def apply(self, believed):
        """The true seat pose (``pin.SE3``) for the ``believed`` one (``pin.SE3``)."""
        import pinocchio as pin

        offset = pin.SE3(self.rotation(), np.array([self.x, self.y, 0.0]))
        return believed * offset

    def record(self) -> dict:
        """The flat metrics.json keys (:data:`RECORD_KEYS`)."""
        return {
            "misalignment_x_m": self.x,
            "misalignment_y_m": self.y,
            "misalignment_lateral_m": self.lateral,
            "misalignment_yaw_deg": self.yaw_deg,
            "misalignment_tilt_deg": self.tilt_deg,
            "misalignment_seed": self.seed,
        }


def stream_rng(seed: int, stream: int) -> np.random.Generator:
    """The random stream ``SeedSequence([seed, stream])``: every drawn quantity of a run
    (misalignment, model error, sensor, contact) has its own stream."""
    return np.random.default_rng(np.random.SeedSequence([int(seed), stream]))


def uniform_draw(seed: int, stream: int, low: float, high: float) -> float:
    """One uniform draw in [low, high] from the random stream of ``seed`` and ``stream``."""
    return low + (high - low) * float(stream_rng(seed, stream).random())


def empty_record() -> dict:
    """The misalignment keys of a run without a socket (or before the scene exists)."""
    return dict.fromkeys(RECORD_KEYS)


def draw(settings: MisalignmentConfig | None) -> Misalignment:
    """The misalignment of ``settings`` (``task.misalignment``, typed: :mod:`compliant_docking.sim.settings`).

    Fixed components pass through; a component with a ``<name>_range`` is drawn
    uniformly from it with the stream ``SeedSequence([seed, index of the component])``.
    Raises ValueError naming the setting for contradictory or meaningless values: the
    config check's ranges (``MisalignmentConfig``) and relations, in its words.
    """
    if settings is None:
        return Misalignment()
    from compliant_docking.config.ranges import require
    from compliant_docking.config.schemas import MisalignmentConfig
    from compliant_docking.config.validate import misalignment_problems

    given = {k: v for k, v in vars(settings).items() if v is not None}
    require(MisalignmentConfig, "task.misalignment", **given)
    found = misalignment_problems(vars(settings), has_target=True)
    if found:
        raise ValueError(" ".join(found))
    seed = settings.seed
    values: dict[str, float] = {}
    drawn = False
    for index, name in enumerate(COMPONENTS):
        bounds = given.get(f"{name}_range")
        if bounds is None:
            values[name] = float(given.get(name, 0.0))
            continue
        if seed is None:  # a draw needs its seed
            raise ValueError(
                f"task.misalignment.seed must be an integer >= 0 to draw task.misalignment.{name}; got None."
            )
        values[name] = uniform_draw(int(seed), index, float(bounds[0]), float(bounds[1]))
        drawn = True
    return Misalignment(**values, seed=int(seed) if drawn else None)


def record_for(settings: SimSettings | None) -> dict:
    """The misalignment keys of metrics.json for the run's ``settings`` (never raises).

    Null without a socket, or when the settings are invalid (None: the config's nodes are
    not the schema's; the run then fails with the reason when its scene is built).
    """
    if settings is None or settings.socket is None:
        return empty_record()
    try:
        return draw(settings.task.misalignment).record()
    except (ValueError, TypeError):
        return empty_record()
