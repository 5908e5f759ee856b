"""``python -m compliant_docking [overrides]``: one run (or a sweep with ``-m``).

Exit status: 0 the run succeeded (docked / tracking gate PASS), 1 the run failed
(error or divergence), 3 the run finished but its gate did not pass.
"""

from __future__ import annotations

import sys
from pathlib import Path

import hydra
from hydra.core.hydra_config import HydraConfig
from omegaconf import DictConfig

from compliant_docking import CONF_DIR
from compliant_docking.config import register_schemas

register_schemas()
_records: list[dict] = []


@hydra.main(version_base="1.3", config_path=str(CONF_DIR), config_name="config")
def _main(cfg: DictConfig) -> None:
    from compliant_docking.runner import execute, job_identity

    out_dir = Path(HydraConfig.get().runtime.output_dir)
    _records.append(execute(cfg, out_dir, identity=job_identity(cfg)))


def main() -> int:
    if any(arg in ("--help", "-h") for arg in sys.argv[1:]):
        from compliant_docking.help import print_help

        print_help(sys.argv[1:])
        return 0
    _main()
    from compliant_docking.runner import exit_status

    return max((exit_status(r) for r in _records), default=0)


if __name__ == "__main__":
    sys.exit(main())
