"""What every planner receives and gives.

A planner is built once per run from its config and the :class:`Waypoints` of the
task. :meth:`Planner.sample` gives the reference at one time; the simulation asks
once for the :meth:`Planner.table` of every control step (planners vectorise it
where they can; the default loops over ``sample``) and hands the controller row ``k``.
"""

from __future__ import annotations

from abc import ABC
from dataclasses import dataclass

import numpy as np
import pinocchio as pin


@dataclass(frozen=True)
class Waypoints:
    """Task geometry in the world, as the planner believes it.

    ``start``: TCP pose at t = 0. ``goal``: TCP pose at the end of the docking motion
    (None in free space). ``axis``: unit docking axis, the direction of insertion.
    """

    start: pin.SE3
    goal: pin.SE3 | None
    axis: np.ndarray


class Reference:
    """The reference at one instant, at the TCP, in world axes.

    ``twist = [vel; omega]`` and ``accel = [acc; alpha]`` are 6-vectors whose halves are
    exposed as views for planners writing them in :meth:`Planner.sample`. Controllers
    read only ``pos``, ``rot``, ``twist`` and ``accel`` (see :meth:`ReferenceTable.row`).
    """

    __slots__ = ("pos", "rot", "twist", "accel", "vel", "omega", "acc", "alpha")

    def __init__(self) -> None:
        self.pos = np.zeros(3)
        self.rot = np.eye(3)
        self.twist = np.zeros(6)
        self.accel = np.zeros(6)
        self.vel, self.omega = self.twist[:3], self.twist[3:]
        self.acc, self.alpha = self.accel[:3], self.accel[3:]


@dataclass(frozen=True)
class ReferenceTable:
    """The reference at a sequence of times: one row per time."""

    t: np.ndarray  # (N,)
    pos: np.ndarray  # (N, 3)
    rot: np.ndarray  # (N, 3, 3)
    twist: np.ndarray  # (N, 6) [vel; omega]
    accel: np.ndarray  # (N, 6) [acc; alpha]

    @classmethod
    def zeros(cls, t) -> ReferenceTable:
        """A table for the times ``t`` with every reference quantity zero (to be filled)."""
        t = np.asarray(t, dtype=float)
        n = len(t)
        return cls(
            t=t, pos=np.zeros((n, 3)), rot=np.zeros((n, 3, 3)), twist=np.zeros((n, 6)), accel=np.zeros((n, 6))
        )

    def row(self, k: int, ref: Reference) -> Reference:
        """Point ``ref`` at row k (views, no copies); only pos, rot, twist, accel are set."""
        ref.pos, ref.rot, ref.twist, ref.accel = self.pos[k], self.rot[k], self.twist[k], self.accel[k]
        return ref


class Planner(ABC):
    """A reference defined for every t ≥ 0 (held at its end after ``duration``).

    Subclasses implement :meth:`sample` (one time) or :meth:`table` (many times,
    vectorised), or both; each default is written in terms of the other.
    """

    def __init_subclass__(cls, **kwargs):
        super().__init_subclass__(**kwargs)
        if cls.sample is Planner.sample and cls.table is Planner.table:
            raise TypeError(f"{cls.__name__} must implement sample() or table()")

    #: time at which the planned motion ends [s]
    duration: float
    #: the bound on the reference's lead over the plug along the insertion axis [m]
    #: (planning/lead.py; None: the open-loop reference)
    lead_limit: float | None = None

    def intended_lead(self, t: np.ndarray) -> np.ndarray:
        """The part of the reference at the times ``t`` meant to lead the plug (N×3, world):
        none by default; the press home's offset for :class:`PressHome`."""
        return np.zeros((len(t), 3))

    @property
    def segments(self) -> list[tuple[str, float, float]]:
        """Named phases ``(name, t_start, t_end)``; the whole motion by default."""
        return [("motion", 0.0, self.duration)]

    def sample(self, t: float, ref: Reference) -> None:
        """Write the reference at time ``t`` into ``ref``."""
        row = self.table(np.array([float(t)]))
        ref.pos[:], ref.rot[:], ref.twist[:], ref.accel[:] = (
            row.pos[0],
            row.rot[0],
            row.twist[0],
            row.accel[0],
        )

    def table(self, t: np.ndarray) -> ReferenceTable:
        """The reference at every time of ``t`` (override to vectorise)."""
        out = ReferenceTable.zeros(t)
        ref = Reference()
        for k, tk in enumerate(out.t):
            self.sample(float(tk), ref)
            out.pos[k], out.rot[k], out.twist[k], out.accel[k] = ref.pos, ref.rot, ref.twist, ref.accel
        return out


class PressHome(Planner):
    """A docking planner followed by a press: the planned motion ends at the seat at rest;
    then the reference moves ``offset`` further (rest to rest, quintic scaling) during the
    first ``press_duration`` seconds after it, so a compliant controller presses the plug
    home with a force of about its stiffness times |offset| instead of striking the seat.

    ``duration`` stays the planner's: the press happens during the run's settle time.
    ``press_duration`` > 0 and at most the settle time: checked where the press is made
    (``sim.simulate.plan``, with the config check's rules).
    """

    def __init__(self, inner: Planner, offset: np.ndarray, press_duration: float):
        self.inner = inner
        self.duration = inner.duration
        self.lead_limit = inner.lead_limit
        self.offset = np.asarray(offset, dtype=float)
        self.press_duration = float(press_duration)

    @property
    def segments(self) -> list[tuple[str, float, float]]:
        end = self.duration
        return [*self.inner.segments, ("press", end, end + self.press_duration)]

    def intended_lead(self, t: np.ndarray) -> np.ndarray:
        s, _, _ = quintic_scaling((np.asarray(t, dtype=float) - self.duration) / self.press_duration)
        return np.outer(s, self.offset)

    def table(self, t: np.ndarray) -> ReferenceTable:
        out = self.inner.table(t)
        T = self.press_duration
        s, ds, dds = quintic_scaling((out.t - self.duration) / T)
        out.pos[:] += np.outer(s, self.offset)
        out.twist[:, :3] += np.outer(ds / T, self.offset)
        out.accel[:, :3] += np.outer(dds / T**2, self.offset)
        return out


def quintic_scaling(u):
    """s(u) = 10u³ − 15u⁴ + 6u⁵ on [0, 1] (clamped outside) and its first two derivatives.

    Works on scalars and arrays. Rest-to-rest: s, s', s'' are 0, 0, 0 at u = 0 and 1, 0, 0
    at u = 1; the peak of s' is 1.875 at u = 1/2, the peak of |s''| is 10/√3 ≈ 5.7735 at
    u = 1/2 ∓ √3/6.
    """
    u = np.clip(u, 0.0, 1.0)
    return (
        u**3 * (10.0 + u * (-15.0 + 6.0 * u)),
        30.0 * u**2 * (1.0 - u) ** 2,
        60.0 * u * (1.0 - u) * (1.0 - 2.0 * u),
    )
