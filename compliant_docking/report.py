"""``python -m compliant_docking.report PATH``: tables and comparison figures for runs
(:mod:`compliant_docking.results.report`)."""

import sys

from compliant_docking.results.report import main

if __name__ == "__main__":
    sys.exit(main())
