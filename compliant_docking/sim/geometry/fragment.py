"""What a tool or target fragment declares about its key (docs/interfaces.md).

A fragment may carry, in its ``<custom>`` section, the numbers

- ``key_symmetry``: n ≥ 1 when the part only mates at rolls about the docking axis that
  are multiples of 360°/n (a square plug: 4; a part that mates one way only: 1);
  0 or absent: the part is round, any roll mates.
- ``key_yaw_play_deg``: how far [deg] the mated plug can turn about the axis inside the
  socket (from the clearance); absent: unknown.

The task lines the tool's key up with the socket it believes in (compliant_docking/sim/
task.py) and the docking gate checks the roll against the true socket
(compliant_docking/evaluation/docking.py). The mating convention: at the mated pose the
tool's ``tcp`` frame is the target's ``dock`` frame (the seat) turned 180° about its x
axis (tcp z = −seat z, tcp x = seat x), up to a multiple of 360°/n about the axis.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import mujoco
import numpy as np

#: the tcp frame of a mated tool in the seat frame: turned 180° about x (tcp z = −seat z)
MATED = np.diag([1.0, -1.0, -1.0])

KEY_SYMMETRY = "key_symmetry"
KEY_YAW_PLAY = "key_yaw_play_deg"


@dataclass(frozen=True)
class Key:
    """The key of an interface: its rotational symmetry about the docking axis (0: round)
    and the yaw play of the mated plug [deg] (None: unknown)."""

    symmetry: int = 0
    yaw_play_deg: float | None = None

    @property
    def keyed(self) -> bool:
        return self.symmetry > 0

    def yaw_error_deg(self, seat: np.ndarray, tcp: np.ndarray) -> np.ndarray:
        """|roll error| [deg] of tcp orientations (…, 3, 3) against the mating rolls of a
        seat orientation (3, 3), modulo the key: in [0, 180/symmetry]. The roll is read
        about the seat axis (exact for a plug along the axis; tilts of a few degrees
        change it by far less than they tilt). NaN for a round interface."""
        rel = np.einsum("ji,...jk,kl->...il", seat, tcp, MATED)  # seatᵀ · tcp · MATEDᵀ
        if not self.keyed:
            return np.full(rel.shape[:-2], np.nan)
        yaw = np.arctan2(rel[..., 1, 0], rel[..., 0, 0])
        period = 2.0 * np.pi / self.symmetry
        wrapped = np.mod(yaw + 0.5 * period, period) - 0.5 * period
        return np.degrees(np.abs(wrapped))

    def combine(self, other: Key) -> Key:
        """The key of a tool and a target together.

        The mated rolls are those allowed by either part (a roll that leaves the tool
        unchanged, or the socket): 360°·(ℤ/a + ℤ/b) = 360°/lcm(a, b)·ℤ, and a round part
        (0) allows every roll, which ``math.lcm`` gives (lcm(0, n) = 0). The play is the
        target's if it declares one, else the tool's.
        """
        play = other.yaw_play_deg if other.yaw_play_deg is not None else self.yaw_play_deg
        return Key(math.lcm(self.symmetry, other.symmetry), play)


#: the key of a round interface (no key)
ROUND = Key()


def declare_key(spec: mujoco.MjSpec, key: Key) -> None:
    """Write ``key`` into the fragment's custom numbers (nothing for a round part)."""
    if not key.keyed:
        return
    spec.add_numeric(name=KEY_SYMMETRY, data=[float(key.symmetry)])
    if key.yaw_play_deg is not None:
        spec.add_numeric(name=KEY_YAW_PLAY, data=[float(key.yaw_play_deg)])


def read_key(spec: mujoco.MjSpec, source: str) -> Key:
    """The key a fragment declares (``Key()`` when it declares none).

    Raises ValueError naming the fragment when the numbers are not what the
    convention says (a non-negative integer symmetry, a non-negative finite play).
    """
    values = {n.name: list(n.data) for n in spec.numerics}
    raw = values.get(KEY_SYMMETRY, [0.0])
    symmetry = raw[0] if raw else 0.0
    if len(raw) != 1 or symmetry < 0 or symmetry != int(symmetry):
        raise ValueError(
            f"{source}: custom numeric '{KEY_SYMMETRY}' must be one integer >= 0 "
            f"(0: round; n: mates every 360/n deg); got {raw}"
        )
    play = values.get(KEY_YAW_PLAY)
    if play is not None and (len(play) != 1 or not math.isfinite(play[0]) or play[0] < 0.0):
        raise ValueError(
            f"{source}: custom numeric '{KEY_YAW_PLAY}' must be one finite number >= 0 [deg]; got {play}"
        )
    return Key(int(symmetry), float(play[0]) if play is not None else None)
