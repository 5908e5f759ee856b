"""``python -m compliant_docking [overrides]``: see :mod:`compliant_docking.cli`."""

import sys

from compliant_docking.cli import main

if __name__ == "__main__":
    sys.exit(main())
