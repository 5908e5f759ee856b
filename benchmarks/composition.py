"""What composing a config costs, with the composition memos (config/hydra_adapter.py)
and with Hydra's own composition, in one process (ratios, not absolute times: the
machine's load moves both alike).

Three kinds of composition, each timed through Hydra's compose API as ``load_config``
calls it (what tests, scripts and the notebook call; the command line composes the same
way):

- **new choices**: config-group choices not composed before in this process (a robot,
  controller and trajectory), so neither the defaults-list nor the merged-config memo
  has them; the parsed config files are reused after the first;
- **new values**: the same choices with a value override not seen before (a gain), as
  the jobs of a sweep differ;
- **repeat**: a composition made before.

Usage: ``python benchmarks/composition.py [--rounds N]``; prints best and median in ms.
"""

from __future__ import annotations

import argparse
import itertools
import os
import statistics
import time

from hydra import compose, initialize_config_dir
from hydra.core.global_hydra import GlobalHydra

from compliant_docking import CONF_DIR
from compliant_docking.config import hydra_adapter, register_schemas

#: 18 distinct choices of config groups
CHOICES = [
    (f"robot={robot}", f"controller={controller}", f"trajectory={trajectory}")
    for robot, controller, trajectory in itertools.product(
        ("iiwa14", "fr3"), ("impedance", "hqp", "se3_lie"), ("quintic", "se3topp", "twophase")
    )
]


def _time(overrides: tuple[str, ...]) -> float:
    # load_config's steps, not load_config itself: it would install the memos again
    start = time.perf_counter()
    register_schemas()
    GlobalHydra.instance().clear()
    with initialize_config_dir(config_dir=str(CONF_DIR), version_base="1.3"):
        compose(config_name="config", overrides=list(overrides))
    return time.perf_counter() - start


def measure(memos: bool, rounds: int) -> dict[str, list[float]]:
    """Seconds per composition of each kind, ``rounds`` times each (at most 18)."""
    hydra_adapter.uninstall()
    if memos:
        hydra_adapter.install()
    _time(())  # imports and Hydra's plugin scan, once
    times: dict[str, list[float]] = {"new choices": [], "new values": [], "repeat": []}
    for choices, seed in zip(CHOICES[:rounds], itertools.count(1)):
        times["new choices"].append(_time(choices))
        times["new values"].append(_time((*choices, f"task.misalignment.seed={seed}")))
        times["repeat"].append(_time(choices))
    hydra_adapter.install()
    return times


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--rounds", type=int, default=len(CHOICES))
    args = parser.parse_args()
    load = os.getloadavg()
    hydra = measure(memos=False, rounds=args.rounds)
    memo = measure(memos=True, rounds=args.rounds)
    print(f"load average {load[0]:.2f} {load[1]:.2f} {load[2]:.2f}; {args.rounds} rounds; ms")
    print(
        f"{'composition':<12} {'Hydra best':>10} {'median':>7} {'memos best':>10} {'median':>7} {'ratio':>6}"
    )
    for kind in hydra:
        h, m = hydra[kind], memo[kind]
        ratio = statistics.median(m) / statistics.median(h)
        print(
            f"{kind:<12} {min(h) * 1e3:10.0f} {statistics.median(h) * 1e3:7.0f} "
            f"{min(m) * 1e3:10.0f} {statistics.median(m) * 1e3:7.0f} {ratio:6.2f}"
        )


if __name__ == "__main__":
    main()
