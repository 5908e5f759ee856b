"""The converter's own contact audit of the fragments it writes.

:mod:`.audit` poses the plug at the mouth, on the funnel and in the bore, presses it 20
and 60 µm past first touch and compares every contact normal with the normal cone of
the socket's own surface (its mesh) at the contact point. The sweep here is derived from
the two parts alone, since the converter knows nothing of the interface's design:

- **heights** of the plug tip for the lateral approach: wherever one of the plug's
  feature levels (the z of its vertices above its tip: the tip, the chamfer's edge)
  passes one of the socket's (the z of its vertices above the seat: the lip, the mouth),
  and 0.3 mm either side, plus six heights spread from the seat to the mouth;
- **offsets** for the vertical approach: on the axis, just inside and just outside the
  clearance (0.97 and 1.05 times it, 1.5 times it), and a tenth and a quarter of the way
  from the plug's outline to the mouth's;
- **azimuths**: eight per period of the key (360°/symmetry; 360° for a round or one-way
  part), from a face's direction;
- **tilts**: as tests/sim/test_contact_normals.py (0°, and 2-3° in three directions).

A contact is sound when its normal is within ``tolerance_deg`` (5°, the test's) of the
socket's normal cone and no more upward than the cone allows by sin(tolerance).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import mujoco
import numpy as np

from compliant_docking.sim.geometry.audit import Audit, ContactSample, Tilt, mesh_surface
from compliant_docking.sim.geometry.mesh import Mesh

#: the largest angle [deg] between a contact normal and the socket's normal cone
TOLERANCE_DEG = 5.0
TILTS = (Tilt(0.0), Tilt(2.0, 0.0), Tilt(3.0, 180.0), Tilt(2.0, 90.0))
AZIMUTHS_PER_PERIOD = 8
#: heights this far either side of where a plug level passes a socket level [m]
NEAR = 0.0003
#: at most this many heights (spread evenly over the candidates)
MAX_HEIGHTS = 24


@dataclass(frozen=True)
class Sweep:
    """The audited poses (module doc), socket frame (seat at the origin) [m, deg]."""

    heights: tuple[float, ...]
    offsets: tuple[float, ...]
    azimuths_deg: tuple[float, ...]
    top: float  # the vertical approach starts this high

    def poses(self) -> int:
        return (len(self.heights) + len(self.offsets)) * len(self.azimuths_deg) * len(TILTS)


def _levels(z: np.ndarray) -> np.ndarray:
    return np.unique(np.round(z, 6))


def sweep_for(plug: Mesh, socket: Mesh, z_tip: float, symmetry: int, clearance: float) -> Sweep:
    """The sweep for a mated CAD pair (CAD frame, seat at z = ``z_tip`` on the axis)."""
    mouth = float(socket[0][:, 2].max()) - z_tip
    socket_levels = _levels(socket[0][:, 2] - z_tip)
    plug_levels = _levels(plug[0][:, 2] - z_tip)
    candidates = [s - q + d for s in socket_levels for q in plug_levels for d in (-NEAR, 0.0, NEAR)]
    candidates += list(np.linspace(0.002, mouth, 6))
    heights = np.unique(np.round([h for h in candidates if 0.001 <= h <= mouth + 0.002], 4))
    if len(heights) > MAX_HEIGHTS:
        heights = heights[np.round(np.linspace(0, len(heights) - 1, MAX_HEIGHTS)).astype(int)]
    top_ring = socket[0][np.abs(socket[0][:, 2] - socket[0][:, 2].max()) < 1e-9]
    mouth_radius = float(np.hypot(top_ring[:, 0], top_ring[:, 1]).min())
    plug_radius = float(np.hypot(plug[0][:, 0], plug[0][:, 1]).max())
    funnel = max(mouth_radius - plug_radius, 0.0)
    offsets = (0.0, 0.97 * clearance, 1.05 * clearance, 1.5 * clearance, 0.1 * funnel, 0.25 * funnel)
    period = 360.0 / max(symmetry, 1)
    azimuths = tuple(float(k * period / AZIMUTHS_PER_PERIOD) for k in range(AZIMUTHS_PER_PERIOD))
    return Sweep(tuple(float(h) for h in heights), tuple(float(o) for o in offsets), azimuths, mouth + 0.003)


@dataclass(frozen=True)
class ContactAudit:
    """The verdict on the contacts of a conversion."""

    contacts: int
    poses: int
    worst_deg: float  # largest angle of a normal from the socket's cone
    worst_excess_up: float  # largest upward excess over the cone (> sin(tolerance): a ledge)
    tolerance_deg: float
    unsound: tuple[ContactSample, ...]

    @property
    def passed(self) -> bool:
        return self.contacts > 0 and not self.unsound

    def summary(self) -> str:
        return (
            f"contact audit: {self.contacts} contacts at {self.poses} poses, worst normal "
            f"{self.worst_deg:.2f} deg from the socket's surface (at most {self.tolerance_deg:g}), "
            f"{len(self.unsound)} unsound"
        )

    def describe(self, count: int = 5) -> str:
        """The worst unsound contacts, one line each (socket frame, mm)."""
        worst = sorted(self.unsound, key=lambda s: -s.angle_deg)[:count]
        return "; ".join(
            f"{s.angle_deg:.1f} deg off on {s.socket_geom.removeprefix('target_')} at "
            f"({', '.join(f'{1e3 * v:.2f}' for v in s.point)}) mm above the seat, normal "
            f"({', '.join(f'{v:.2f}' for v in s.normal)}), plug tilted {s.tilt_deg:g} deg"
            for s in worst
        )

    def record(self) -> dict:
        return {
            "contacts": self.contacts,
            "poses": self.poses,
            "worst_deg": self.worst_deg,
            "worst_excess_up": self.worst_excess_up,
            "tolerance_deg": self.tolerance_deg,
            "unsound": len(self.unsound),
            "passed": self.passed,
        }


def audit_fragments(
    tool: mujoco.MjSpec,
    target: mujoco.MjSpec,
    plug: Mesh,
    socket: Mesh,
    z_tip: float,
    sweep: Sweep,
    tolerance_deg: float = TOLERANCE_DEG,
) -> ContactAudit:
    """Audit the contacts of fragments converted from ``plug`` and ``socket`` (CAD frame,
    the seat at ``z_tip``) over ``sweep``; the specs are copied, not changed."""
    seat = np.array([0.0, 0.0, z_tip])
    length = float(plug[0][:, 2].max()) - z_tip
    audit = Audit(tool.copy(), target.copy(), length, mesh_surface(socket[0], socket[1], tuple(-seat)))
    samples = audit.lateral(sweep.heights, sweep.azimuths_deg, TILTS) + audit.vertical(
        sweep.offsets, sweep.azimuths_deg, TILTS, sweep.top
    )
    up = math.sin(math.radians(tolerance_deg))
    unsound = tuple(s for s in samples if s.angle_deg > tolerance_deg or s.excess_up > up)
    return ContactAudit(
        contacts=len(samples),
        poses=sweep.poses(),
        worst_deg=max((s.angle_deg for s in samples), default=math.nan),
        worst_excess_up=max((s.excess_up for s in samples), default=math.nan),
        tolerance_deg=tolerance_deg,
        unsound=unsound,
    )
