"""``trajectory=twophase``: approach to a pre-dock point, then a slow docking segment.

The pre-dock point lies ``standoff`` before the goal along the docking axis, with the
goal's orientation. Each segment is a rest-to-rest quintic of its length L lasting

    T = max(1.875·L/v_max, √(5.7735·L/a_max))

so that the peak speed 1.875·L/T and the peak acceleration 5.7735·L/T² of the quintic
stay within the segment's limits (docs/control_laws.md §4). Position moves on the straight
line; orientation (the same at both ends in the standard task) follows the SO(3)
geodesic with the same time scaling. The timing law sees only the length, so a segment
that rotates without translating is refused (use ``trajectory=se3topp``).

Start within the standoff: when the start is already at most ``standoff`` before the
goal along the axis, no approach is planned (backing away from the socket to reach the
pre-dock point would be a detour): the docking segment goes from the start to the goal
under the docking limits, and :attr:`notes` says so.
"""

from __future__ import annotations

import logging
import math

import numpy as np
import pinocchio as pin

from compliant_docking.config.ranges import require
from compliant_docking.config.schemas import TwoPhaseConfig
from compliant_docking.planning.base import (
    Planner,
    ReferenceTable,
    Waypoints,
    quintic_scaling,
)

log = logging.getLogger(__name__)

#: peak of s'(u) and of |s''(u)| of the quintic scaling s(u) = 10u³ − 15u⁴ + 6u⁵
QUINTIC_PEAK_SPEED = 1.875
QUINTIC_PEAK_ACCEL = 10.0 / math.sqrt(3.0)  # 5.7735…
#: segments shorter than this are dropped [m]; rotations below this are ignored [rad]
MIN_LENGTH = 1e-9


def quintic_segment_time(length: float, v_max: float, a_max: float) -> float:
    """Shortest duration [s] of a rest-to-rest quintic over ``length`` [m] within v_max [m/s]
    and a_max [m/s²]: max(1.875·L/v_max, √(5.7735·L/a_max))."""
    if not (v_max > 0.0 and a_max > 0.0):
        raise ValueError(f"speed and acceleration limits must be > 0, got v_max={v_max}, a_max={a_max}")
    length = float(length)
    return max(QUINTIC_PEAK_SPEED * length / v_max, math.sqrt(QUINTIC_PEAK_ACCEL * length / a_max))


def docking_waypoints(
    waypoints: Waypoints, standoff: float, planner: str
) -> tuple[list[tuple[str, pin.SE3, pin.SE3]], list[str]]:
    """The segments ``(name, from, to)`` start → pre-dock → goal, and notes about them.

    The pre-dock pose is the goal moved ``standoff`` back along the docking axis. When
    the start is already within ``standoff`` of the goal (axially), the approach is
    dropped and one "docking" segment goes from the start to the goal.
    """
    if waypoints.goal is None:
        raise ValueError(
            f"trajectory={planner} needs a goal (a target); with target=none "
            "use trajectory=tracking or trajectory=hold"
        )
    axis = np.asarray(waypoints.axis, dtype=float)
    axis = axis / np.linalg.norm(axis)
    start, goal = waypoints.start, waypoints.goal
    pre_dock = pin.SE3(goal.rotation.copy(), goal.translation - standoff * axis)
    ahead = float((goal.translation - start.translation) @ axis)  # start's distance before the goal
    notes: list[str] = []
    if ahead <= standoff:
        notes.append(
            f"trajectory={planner}: the start is {ahead * 1e3:.1f} mm before the goal, "
            f"within the standoff ({standoff * 1e3:.1f} mm): no approach segment, "
            "the docking limits apply from the start"
        )
        return [("docking", start, goal)], notes
    return [("approach", start, pre_dock), ("docking", pre_dock, goal)], notes


def rotation_path(rot_a: np.ndarray, axis: np.ndarray, angle: np.ndarray) -> np.ndarray:
    """R_a·Exp3(angle·axis) for every angle [rad] of an array (unit ``axis``): (N, 3, 3)."""
    angle = np.asarray(angle, dtype=float)
    K = pin.skew(axis)
    K2 = K @ K
    sin, omc = np.sin(angle), 2.0 * np.sin(0.5 * angle) ** 2
    local = np.eye(3) + sin[:, None, None] * K + omc[:, None, None] * K2
    return np.einsum("ij,njk->nik", rot_a, local)


def segment_index(t: np.ndarray, starts: np.ndarray) -> np.ndarray:
    """Index of the segment each time falls in (before the first: 0; after the last: last)."""
    return np.clip(np.searchsorted(starts, t, side="right") - 1, 0, len(starts) - 1)


class TwoPhasePlanner(Planner):
    """Approach (fast) then docking (slow), each a rest-to-rest quintic; see the module doc.

    ``standoff`` [m]; ``v_max_*`` [m/s] and ``a_max_*`` [m/s²] per segment.
    """

    def __init__(
        self,
        waypoints: Waypoints,
        *,
        standoff: float,
        v_max_approach: float,
        a_max_approach: float,
        v_max_docking: float,
        a_max_docking: float,
        name: str,
        lead_limit: float | None,
    ):
        require(  # the schema's ranges
            TwoPhaseConfig, "trajectory", standoff=standoff, v_max_approach=v_max_approach,
            a_max_approach=a_max_approach, v_max_docking=v_max_docking, a_max_docking=a_max_docking,
            lead_limit=lead_limit,
        )  # fmt: skip
        limits = {
            "approach": (float(v_max_approach), float(a_max_approach)),
            "docking": (float(v_max_docking), float(a_max_docking)),
        }
        pieces, self.notes = docking_waypoints(waypoints, float(standoff), "twophase")
        self.lead_limit = None if lead_limit is None else float(lead_limit)
        for note in self.notes:
            log.info(note)
        self._segments: list[tuple[str, float, float]] = []
        rows = []  # per segment: t0, T, p_a, Δp, R_a, rotation axis (world), angle
        t0 = 0.0
        for seg, a, b in pieces:
            delta = b.translation - a.translation
            length = float(np.linalg.norm(delta))
            rotvec = pin.log3(a.rotation.T @ b.rotation)  # in a's axes
            angle = float(np.linalg.norm(rotvec))
            if length < MIN_LENGTH:
                if angle > MIN_LENGTH:
                    raise ValueError(
                        f"trajectory=twophase: the {seg} segment rotates by "
                        f"{math.degrees(angle):.3g}° without translating; its timing "
                        "law only knows lengths (use trajectory=se3topp)"
                    )
                continue
            T = quintic_segment_time(length, *limits[seg])
            axis = rotvec / angle if angle > MIN_LENGTH else np.array([0.0, 0.0, 1.0])
            rows.append(
                (
                    t0,
                    T,
                    a.translation.copy(),
                    delta,
                    a.rotation.copy(),
                    axis,
                    angle if angle > MIN_LENGTH else 0.0,
                )
            )
            self._segments.append((seg, t0, t0 + T))
            t0 += T
        if not rows:  # start == goal: nothing to do; hold there
            rows.append(
                (
                    0.0,
                    1.0,
                    waypoints.start.translation.copy(),
                    np.zeros(3),
                    waypoints.start.rotation.copy(),
                    np.array([0.0, 0.0, 1.0]),
                    0.0,
                )
            )
            t0 = 0.0
        self._rows = rows
        self._starts = np.array([r[0] for r in rows])
        self.duration = t0

    @property
    def segments(self) -> list[tuple[str, float, float]]:
        """``(name, t_start, t_end)`` of "approach" (if any) and "docking" [s]."""
        return list(self._segments)

    def table(self, t: np.ndarray) -> ReferenceTable:
        out = ReferenceTable.zeros(t)
        t, pos, rot, twist, accel = out.t, out.pos, out.rot, out.twist, out.accel
        which = segment_index(t, self._starts)
        for i, (t0, T, p_a, delta, rot_a, axis, angle) in enumerate(self._rows):
            k = which == i
            if not k.any():
                continue
            s, ds, dds = quintic_scaling((t[k] - t0) / T)
            ds, dds = ds / T, dds / T**2  # ṡ [1/s], s̈ [1/s²]
            pos[k] = p_a + np.outer(s, delta)
            twist[k, :3] = np.outer(ds, delta)
            accel[k, :3] = np.outer(dds, delta)
            rot[k] = rotation_path(rot_a, axis, angle * s)
            w_world = rot_a @ axis * angle  # ω = R_a φ ṡ, constant direction
            twist[k, 3:] = np.outer(ds, w_world)
            accel[k, 3:] = np.outer(dds, w_world)
        return out
