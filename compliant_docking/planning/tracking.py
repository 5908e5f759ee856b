"""``trajectory=tracking``: the free-space tracking test (circle, then figure-8).

Refused when a target is configured: the test must not touch the docking interface.
With p0 the start position and ẑ, ŷ, x̂ the world axes, the phases are

1. ``transition_1`` (``transition_duration``): straight line p0 → top of the circle;
2. ``circle`` (``circle_duration``): vertical circle in the y-z plane, centre
   c = p0 + ``circle_center_offset``·ẑ, radius r, p = c + r(sin θ ŷ + cos θ ẑ), starting
   at its top (the circle point nearest the start for the default offset) and running
   towards +y; θ sweeps 2π·``circle_frequency``·``circle_duration`` (one turn by default);
3. ``transition_2`` (``transition_duration``): straight line from the end of the circle
   to p0;
4. ``figure8`` (``figure8_duration``): horizontal figure-8 centred on p0 (its crossing
   point), p = p0 + A_x sin θ x̂ + A_y sin 2θ ŷ, θ sweeping 2π·``figure8_frequency``·
   ``figure8_duration``;

then the reference holds its last pose (the run's settle time). The orientation is held
at the start orientation throughout. Every phase is driven by the quintic time scaling
s(u) = 10u³ − 15u⁴ + 6u⁵ (θ = Θ·s(u) on the curves), so every phase starts and ends at
rest with zero acceleration and the path is C² across the joints. The frequencies are
therefore mean values; the peak phase rate is 1.875 times the mean.
"""

from __future__ import annotations

import math

import numpy as np

from compliant_docking.config.ranges import require
from compliant_docking.config.schemas import TrackingConfig
from compliant_docking.planning.base import (
    Planner,
    ReferenceTable,
    Waypoints,
    quintic_scaling,
)
from compliant_docking.planning.twophase import segment_index

_Y, _Z = np.array([0.0, 1.0, 0.0]), np.array([0.0, 0.0, 1.0])


SEGMENT_NAMES = ("transition_1", "circle", "transition_2", "figure8")


def segment_times(
    transition_duration: float, circle_duration: float, figure8_duration: float
) -> list[tuple[str, float, float]]:
    """``(name, t_start, t_end)`` [s] of the four phases, back to back from t = 0 (also what
    a run's figures mark, from its config alone)."""
    bounds = np.cumsum([0.0, transition_duration, circle_duration, transition_duration, figure8_duration])
    return [(name, float(bounds[i]), float(bounds[i + 1])) for i, name in enumerate(SEGMENT_NAMES)]


class TrackingPlanner(Planner):
    """Transition, circle, transition, figure-8 (see the module doc). Lengths in m, times in s,
    frequencies in Hz."""

    def __init__(
        self,
        waypoints: Waypoints,
        *,
        transition_duration: float,
        circle_duration: float,
        circle_radius: float,
        circle_frequency: float,
        circle_center_offset: float,
        figure8_duration: float,
        figure8_radius_x: float,
        figure8_radius_y: float,
        figure8_frequency: float,
        name: str,
    ):
        if waypoints.goal is not None:
            raise ValueError(
                "trajectory=tracking is a free-space test and must not touch the "
                "docking interface: it needs target=none (a target is configured). "
                "Use `+experiment=tracking_gate`, or add target=none."
            )
        require(  # the schema's ranges
            TrackingConfig, "trajectory", transition_duration=transition_duration,
            circle_duration=circle_duration, circle_radius=circle_radius, circle_frequency=circle_frequency,
            circle_center_offset=circle_center_offset, figure8_duration=figure8_duration,
            figure8_radius_x=figure8_radius_x, figure8_radius_y=figure8_radius_y,
            figure8_frequency=figure8_frequency,
        )  # fmt: skip
        self._p0 = np.asarray(waypoints.start.translation, dtype=float).copy()
        self._rot = np.asarray(waypoints.start.rotation, dtype=float).copy()
        self._centre = self._p0 + float(circle_center_offset) * _Z
        self._r = float(circle_radius)
        self._circle_turn = 2.0 * math.pi * float(circle_frequency) * float(circle_duration)
        self._ax, self._ay = float(figure8_radius_x), float(figure8_radius_y)
        self._eight_turn = 2.0 * math.pi * float(figure8_frequency) * float(figure8_duration)
        Tt, Tc, T8 = float(transition_duration), float(circle_duration), float(figure8_duration)
        circle_start = self._circle(np.zeros(1), np.zeros(1), np.zeros(1))[0][0]
        circle_end = self._circle(np.array([self._circle_turn]), np.zeros(1), np.zeros(1))[0][0]
        self._lines = {
            "transition_1": (self._p0, circle_start - self._p0),
            "transition_2": (circle_end, self._p0 - circle_end),
        }
        self._segments = segment_times(Tt, Tc, T8)
        self._starts = np.array([t0 for _, t0, _ in self._segments])
        self.duration = self._segments[-1][2]

    @property
    def segments(self) -> list[tuple[str, float, float]]:
        """``(name, t_start, t_end)`` [s] of transition_1, circle, transition_2, figure8."""
        return list(self._segments)

    def _circle(self, th, dth, ddth):
        """Position, velocity, acceleration on the circle for phase θ and its derivatives."""
        r, sin, cos = self._r, np.sin(th), np.cos(th)
        radial = np.outer(sin, _Y) + np.outer(cos, _Z)  # from the centre
        tangent = np.outer(cos, _Y) - np.outer(sin, _Z)  # d radial / dθ
        pos = self._centre + r * radial
        vel = r * dth[:, None] * tangent
        acc = r * (ddth[:, None] * tangent - (dth * dth)[:, None] * radial)
        return pos, vel, acc

    def _figure8(self, th, dth, ddth):
        ax, ay = self._ax, self._ay
        s1, c1, s2, c2 = np.sin(th), np.cos(th), np.sin(2 * th), np.cos(2 * th)
        n = len(th)
        pos = np.tile(self._p0, (n, 1))
        vel, acc = np.zeros((n, 3)), np.zeros((n, 3))
        pos[:, 0] += ax * s1
        pos[:, 1] += ay * s2
        vel[:, 0] = ax * c1 * dth
        vel[:, 1] = 2 * ay * c2 * dth
        acc[:, 0] = ax * (c1 * ddth - s1 * dth * dth)
        acc[:, 1] = 2 * ay * (c2 * ddth - 2 * s2 * dth * dth)
        return pos, vel, acc

    def table(self, t: np.ndarray) -> ReferenceTable:
        t = np.asarray(t, dtype=float)
        n = len(t)
        pos, vel, acc = np.zeros((n, 3)), np.zeros((n, 3)), np.zeros((n, 3))
        which = segment_index(t, self._starts)
        for i, (name, t0, t1) in enumerate(self._segments):
            k = which == i
            if not k.any():
                continue
            T = t1 - t0
            s, ds, dds = quintic_scaling((t[k] - t0) / T)
            ds, dds = ds / T, dds / T**2
            if name in self._lines:
                p_a, delta = self._lines[name]
                pos[k] = p_a + np.outer(s, delta)
                vel[k] = np.outer(ds, delta)
                acc[k] = np.outer(dds, delta)
            else:
                turn, curve = (
                    (self._circle_turn, self._circle)
                    if name == "circle"
                    else (self._eight_turn, self._figure8)
                )
                pos[k], vel[k], acc[k] = curve(turn * s, turn * ds, turn * dds)
        twist, accel = np.zeros((n, 6)), np.zeros((n, 6))
        twist[:, :3], accel[:, :3] = vel, acc
        return ReferenceTable(
            t=t, pos=pos, rot=np.broadcast_to(self._rot, (n, 3, 3)).copy(), twist=twist, accel=accel
        )
